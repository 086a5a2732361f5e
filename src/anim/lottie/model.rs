//! The resolved Lottie model: layers, transforms and shapes with [`Value`]s, built from the
//! [`schema`] once at load time. Nothing here knows JSON keys any more; every
//! unsupported or malformed thing became a warning naming the feature and the layer.

use super::geom::Bez;
use super::schema;
use super::value::{Animatable, Color, Value};
use crate::error::number;
use glam::{Affine2, Vec2};
use std::collections::HashMap;

/// Deepest precomp nesting followed (protects against reference cycles).
pub const MAX_DEPTH: usize = 16;
/// Largest repeater copy count drawn.
pub const MAX_COPIES: f32 = 1000.0;

/// Collects warnings for one layer, each naming the feature and the layer.
pub struct Warn<'a> {
    layer: &'a str,
    out: &'a mut Vec<String>,
}

impl Warn<'_> {
    fn add(&mut self, what: impl AsRef<str>) {
        let msg = format!("layer '{}': {}", self.layer, what.as_ref());
        if !self.out.contains(&msg) {
            self.out.push(msg);
        }
    }
}

/// Resolves a property with a default, warning about expressions and malformed values.
fn prop<T: Animatable>(p: Option<&schema::Prop<T>>, default: T, what: &str, w: &mut Warn) -> Value<T> {
    let Some(p) = p else { return Value::Fixed(default) };
    if p.x {
        w.add(format!("expressions are not supported ({what}); using its keyframed value"));
    }
    keyed(p.k.as_ref(), default, what, w)
}

/// Resolves the `k` of a property (absent: the default).
fn keyed<T: Animatable>(k: Option<&schema::Value<T>>, default: T, what: &str, w: &mut Warn) -> Value<T> {
    let Some(k) = k else { return Value::Fixed(default) };
    Value::from_schema(k).unwrap_or_else(|_| {
        w.add(format!("malformed value of '{what}'; using the default"));
        Value::Fixed(default)
    })
}

/// A position: one 2D value (with spatial tangents) or split X/Y.
#[derive(Clone, Debug)]
pub enum Position {
    /// `p` as one value.
    Combined(Value<Vec2>),
    /// `p` split into `x` and `y`.
    Split(Value<f32>, Value<f32>),
}

impl Position {
    /// The position at `t`.
    pub fn evaluate(&self, t: f32) -> Vec2 {
        match self {
            Position::Combined(v) => v.evaluate_spatial(t),
            Position::Split(x, y) => Vec2::new(x.evaluate(t), y.evaluate(t)),
        }
    }
}

/// A layer, group or repeater transform.
#[derive(Clone, Debug)]
pub struct Transform {
    /// Anchor point.
    pub anchor: Value<Vec2>,
    /// Position.
    pub position: Position,
    /// Scale in percent.
    pub scale: Value<Vec2>,
    /// Rotation in degrees, clockwise.
    pub rotation: Value<f32>,
    /// Skew in degrees.
    pub skew: Value<f32>,
    /// Skew axis in degrees.
    pub skew_axis: Value<f32>,
    /// Opacity in percent.
    pub opacity: Value<f32>,
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            anchor: Value::Fixed(Vec2::ZERO),
            position: Position::Combined(Value::Fixed(Vec2::ZERO)),
            scale: Value::Fixed(Vec2::splat(100.0)),
            rotation: Value::Fixed(0.0),
            skew: Value::Fixed(0.0),
            skew_axis: Value::Fixed(0.0),
            opacity: Value::Fixed(100.0),
        }
    }
}

impl Transform {
    fn from_schema(t: Option<&schema::Transform>, w: &mut Warn) -> Transform {
        let Some(t) = t else { return Transform::default() };
        let position = match &t.p {
            Some(p) if p.s => Position::Split(
                prop(p.x.component.as_ref(), 0.0, "position x", w),
                prop(p.y.as_ref(), 0.0, "position y", w),
            ),
            Some(p) => {
                if p.x.expression {
                    w.add("expressions are not supported (position); using its keyframed value");
                }
                Position::Combined(keyed(p.k.as_ref(), Vec2::ZERO, "position", w))
            }
            None => Position::Combined(Value::Fixed(Vec2::ZERO)),
        };
        if t.rx.is_some() || t.ry.is_some() || t.or.is_some() {
            w.add("3D rotation (rx/ry/or) is not supported; only the Z rotation is used");
        }
        Transform {
            anchor: prop(t.a.as_ref(), Vec2::ZERO, "anchor", w),
            position,
            scale: prop(t.s.as_ref(), Vec2::splat(100.0), "scale", w),
            rotation: prop(t.r.as_ref().or(t.rz.as_ref()), 0.0, "rotation", w),
            skew: prop(t.sk.as_ref(), 0.0, "skew", w),
            skew_axis: prop(t.sa.as_ref(), 0.0, "skew axis", w),
            opacity: prop(t.o.as_ref(), 100.0, "opacity", w),
        }
    }

    /// The matrix at `t`: translate(p) · rotate(r) · skew · scale(s) · translate(−a).
    pub fn matrix(&self, t: f32) -> Affine2 {
        let a = self.anchor.evaluate(t);
        let p = self.position.evaluate(t);
        let s = self.scale.evaluate(t) / 100.0;
        let r = self.rotation.evaluate(t).to_radians();
        let sk = self.skew.evaluate(t);
        let mut m = Affine2::from_translation(p) * Affine2::from_angle(r);
        if sk != 0.0 {
            let sa = self.skew_axis.evaluate(t).to_radians();
            let shear = Affine2::from_cols(Vec2::new(1.0, 0.0), Vec2::new((-sk.to_radians()).tan(), 1.0), Vec2::ZERO);
            m = m * Affine2::from_angle(-sa) * shear * Affine2::from_angle(sa);
        }
        m * Affine2::from_scale(s) * Affine2::from_translation(-a)
    }

    /// Opacity at `t` in `0..=1`.
    pub fn opacity(&self, t: f32) -> f32 {
        let o = self.opacity.evaluate(t) / 100.0;
        if o.is_finite() { o.clamp(0.0, 1.0) } else { 0.0 }
    }
}

/// Gradient definition shared by `gf` and `gs`.
#[derive(Clone, Debug)]
pub struct Gradient {
    /// Start point.
    pub start: Value<Vec2>,
    /// End point.
    pub end: Value<Vec2>,
    /// Radial (else linear).
    pub radial: bool,
    /// Highlight length in percent (radial).
    pub highlight_length: Value<f32>,
    /// Highlight angle in degrees (radial).
    pub highlight_angle: Value<f32>,
    /// Number of color stops.
    pub count: usize,
    /// The flat stop list.
    pub stops: Value<Vec<f32>>,
}

/// Stroke geometry settings.
#[derive(Clone, Debug)]
pub struct StrokeStyle {
    /// Width.
    pub width: Value<f32>,
    /// Cap.
    pub cap: tiny_skia::LineCap,
    /// Join.
    pub join: tiny_skia::LineJoin,
    /// Miter limit.
    pub miter: f32,
    /// Dashes: (is gap, length); offset.
    pub dashes: Vec<(bool, Value<f32>)>,
    /// Dash offset.
    pub dash_offset: Option<Value<f32>>,
}

/// What paints the paths: a flat color or a gradient.
#[derive(Clone, Debug)]
pub enum Paint {
    /// Flat color.
    Color(Value<Color>),
    /// Gradient.
    Gradient(Gradient),
}

/// An item of a shape list.
#[derive(Clone, Debug)]
pub enum Shape {
    /// A group with its own items and transform.
    Group {
        /// Items, top-most first.
        items: Vec<Shape>,
        /// The group transform.
        transform: Transform,
    },
    /// A free path.
    Path(Value<Bez>),
    /// A rectangle.
    Rect {
        /// Center.
        position: Value<Vec2>,
        /// Size.
        size: Value<Vec2>,
        /// Corner radius.
        roundness: Value<f32>,
        /// Counter-clockwise.
        reverse: bool,
    },
    /// An ellipse.
    Ellipse {
        /// Center.
        position: Value<Vec2>,
        /// Size.
        size: Value<Vec2>,
        /// Counter-clockwise.
        reverse: bool,
    },
    /// A star or polygon.
    Star {
        /// Star (else polygon).
        star: bool,
        /// Center.
        position: Value<Vec2>,
        /// Points.
        points: Value<f32>,
        /// Rotation.
        rotation: Value<f32>,
        /// Outer radius.
        outer_radius: Value<f32>,
        /// Outer roundness.
        outer_roundness: Value<f32>,
        /// Inner radius.
        inner_radius: Value<f32>,
        /// Inner roundness.
        inner_roundness: Value<f32>,
        /// Counter-clockwise.
        reverse: bool,
    },
    /// A fill (`fl`, `gf`).
    Fill {
        /// Color or gradient.
        paint: Paint,
        /// Opacity in percent.
        opacity: Value<f32>,
        /// Even-odd (else nonzero).
        even_odd: bool,
    },
    /// A stroke (`st`, `gs`).
    Stroke {
        /// Color or gradient.
        paint: Paint,
        /// Opacity in percent.
        opacity: Value<f32>,
        /// Width, joins, dashes.
        style: StrokeStyle,
    },
    /// Trim paths.
    Trim {
        /// Start in percent.
        start: Value<f32>,
        /// End in percent.
        end: Value<f32>,
        /// Offset in degrees.
        offset: Value<f32>,
        /// Sequential (`m` 2) rather than parallel.
        sequential: bool,
    },
    /// Rounded corners.
    Round(Value<f32>),
    /// Merge paths: the paths above are combined without a boolean operation (modes other
    /// than plain merging were warned about at load).
    Merge,
    /// Repeater.
    Repeater {
        /// Copies.
        copies: Value<f32>,
        /// Offset (in copies).
        offset: Value<f32>,
        /// Per-copy transform.
        transform: Transform,
        /// Start opacity of the per-copy fade, percent.
        start_opacity: Value<f32>,
        /// End opacity, percent.
        end_opacity: Value<f32>,
        /// Copies stacked above (1) or below (2) the original.
        above: bool,
    },
}

/// Resolves a shape list (hidden items skipped, unsupported ones warned about).
fn shapes<'a>(entries: impl IntoIterator<Item = &'a schema::ShapeEntry>, w: &mut Warn, depth: usize) -> Vec<Shape> {
    if depth > 64 {
        w.add("shape groups nested more than 64 deep; deeper content ignored");
        return Vec::new();
    }
    entries.into_iter().filter(|e| !e.hidden).filter_map(|e| shape(e, w, depth)).collect()
}

/// Resolves one shape item; `None` for transforms (taken by their group) and for what is
/// not supported.
fn shape(entry: &schema::ShapeEntry, w: &mut Warn, depth: usize) -> Option<Shape> {
    use schema::Shape as S;
    let reverse = |d: Option<f64>| d == Some(3.0);
    let unsupported = match &entry.shape {
        S::Transform(_) => return None,
        S::PuckerBloat => Some("puker/bloat modifier (pb)"),
        S::Twist => Some("twist modifier (tw)"),
        S::OffsetPath => Some("offset path modifier (op)"),
        S::ZigZag => Some("zig-zag modifier (zz)"),
        S::Unknown => {
            w.add(format!("shape item type '{}' is not supported; ignored", entry.ty));
            return None;
        }
        _ => None,
    };
    if let Some(what) = unsupported {
        w.add(format!("{what} is not supported; ignored"));
        return None;
    }
    if let Some(e) = &entry.error {
        w.add(format!("malformed shape item '{}' ({e}); using defaults", entry.ty));
    }
    Some(match &entry.shape {
        S::Group(g) => group(g, w, depth),
        S::Path(p) => Shape::Path(prop(p.ks.as_ref(), Bez::default(), "path", w)),
        S::Rect(r) => Shape::Rect {
            position: prop(r.p.as_ref(), Vec2::ZERO, "rect position", w),
            size: prop(r.s.as_ref(), Vec2::ZERO, "rect size", w),
            roundness: prop(r.r.as_ref(), 0.0, "rect roundness", w),
            reverse: reverse(r.d),
        },
        S::Ellipse(e) => Shape::Ellipse {
            position: prop(e.p.as_ref(), Vec2::ZERO, "ellipse position", w),
            size: prop(e.s.as_ref(), Vec2::ZERO, "ellipse size", w),
            reverse: reverse(e.d),
        },
        S::Star(s) => star(s, w),
        S::Fill(f) => {
            let opacity = prop(f.o.as_ref(), 100.0, "opacity", w);
            Shape::Fill { paint: color(f.c.as_ref(), w), opacity, even_odd: f.r == Some(2.0) }
        }
        S::GradientFill(f) => {
            let opacity = prop(f.o.as_ref(), 100.0, "opacity", w);
            Shape::Fill { paint: gradient(&f.gradient, w), opacity, even_odd: f.r == Some(2.0) }
        }
        S::Stroke(s) => {
            let opacity = prop(s.o.as_ref(), 100.0, "opacity", w);
            Shape::Stroke { paint: color(s.c.as_ref(), w), opacity, style: stroke_style(&s.line, w) }
        }
        S::GradientStroke(s) => {
            let opacity = prop(s.o.as_ref(), 100.0, "opacity", w);
            Shape::Stroke { paint: gradient(&s.gradient, w), opacity, style: stroke_style(&s.line, w) }
        }
        S::Trim(t) => Shape::Trim {
            start: prop(t.s.as_ref(), 0.0, "trim start", w),
            end: prop(t.e.as_ref(), 100.0, "trim end", w),
            offset: prop(t.o.as_ref(), 0.0, "trim offset", w),
            sequential: t.m == Some(2.0),
        },
        S::RoundCorners(r) => Shape::Round(prop(r.r.as_ref(), 0.0, "corner radius", w)),
        S::Merge(m) => merge(m, w),
        S::Repeater(r) => repeater(r, w),
        S::Transform(_) | S::PuckerBloat | S::Twist | S::OffsetPath | S::ZigZag | S::Unknown => return None,
    })
}

/// A group: its items and the transform of its (first) `tr` item.
fn group(g: &schema::Group, w: &mut Warn, depth: usize) -> Shape {
    let tr = g.it.iter().find(|e| e.ty == "tr");
    let transform = match tr {
        Some(schema::ShapeEntry { shape: schema::Shape::Transform(t), error, .. }) => {
            if let Some(e) = error {
                w.add(format!("malformed shape item 'tr' ({e}); using defaults"));
            }
            Transform::from_schema(Some(t), w)
        }
        _ => Transform::default(),
    };
    Shape::Group { items: shapes(g.it.iter().filter(|e| e.ty != "tr"), w, depth + 1), transform }
}

fn star(s: &schema::Star, w: &mut Warn) -> Shape {
    Shape::Star {
        star: s.sy != Some(2.0),
        position: prop(s.p.as_ref(), Vec2::ZERO, "star position", w),
        points: prop(s.pt.as_ref(), 5.0, "star points", w),
        rotation: prop(s.r.as_ref(), 0.0, "star rotation", w),
        outer_radius: prop(s.or.as_ref(), 0.0, "star outer radius", w),
        outer_roundness: prop(s.os.as_ref(), 0.0, "star outer roundness", w),
        inner_radius: prop(s.ir.as_ref(), 0.0, "star inner radius", w),
        inner_roundness: prop(s.is.as_ref(), 0.0, "star inner roundness", w),
        reverse: s.d == Some(3.0),
    }
}

fn color(c: Option<&schema::Prop<Color>>, w: &mut Warn) -> Paint {
    Paint::Color(prop(c, Color([0.0, 0.0, 0.0, 1.0]), "color", w))
}

fn gradient(g: &schema::Gradient, w: &mut Warn) -> Paint {
    let colors = g.g.clone().unwrap_or_default();
    let count = colors.p.filter(|p| p.is_finite() && *p >= 0.0).unwrap_or(0.0).min(1000.0) as usize;
    Paint::Gradient(Gradient {
        start: prop(g.s.as_ref(), Vec2::ZERO, "gradient start", w),
        end: prop(g.e.as_ref(), Vec2::ZERO, "gradient end", w),
        radial: g.t == Some(2.0),
        highlight_length: prop(g.h.as_ref(), 0.0, "highlight length", w),
        highlight_angle: prop(g.a.as_ref(), 0.0, "highlight angle", w),
        count,
        stops: prop(colors.k.as_ref(), Vec::new(), "gradient colors", w),
    })
}

fn stroke_style(l: &schema::Line, w: &mut Warn) -> StrokeStyle {
    let mut dashes = Vec::new();
    let mut dash_offset = None;
    for d in l.d.iter().flatten() {
        let v = prop(d.v.as_ref(), 0.0, "dash", w);
        match d.n.as_deref() {
            Some("o") => dash_offset = Some(v),
            Some("g") => dashes.push((true, v)),
            _ => dashes.push((false, v)),
        }
    }
    StrokeStyle {
        width: prop(l.w.as_ref(), 1.0, "stroke width", w),
        cap: match l.lc {
            Some(2.0) => tiny_skia::LineCap::Round,
            Some(3.0) => tiny_skia::LineCap::Square,
            _ => tiny_skia::LineCap::Butt,
        },
        join: match l.lj {
            Some(2.0) => tiny_skia::LineJoin::Round,
            Some(3.0) => tiny_skia::LineJoin::Bevel,
            _ => tiny_skia::LineJoin::Miter,
        },
        miter: l.ml.filter(|m| m.is_finite() && *m >= 1.0).unwrap_or(4.0) as f32,
        dashes,
        dash_offset,
    }
}

fn merge(m: &schema::Merge, w: &mut Warn) -> Shape {
    let mode = m.m.filter(|x| (1.0..=5.0).contains(x)).unwrap_or(1.0) as u8;
    if mode != 1 {
        let name = ["", "merge", "add", "subtract", "intersect", "exclude"][mode as usize];
        w.add(format!(
            "merge paths mode '{name}' is not supported; the paths are combined without a boolean operation"
        ));
    }
    Shape::Merge
}

fn repeater(r: &schema::Repeater, w: &mut Warn) -> Shape {
    let tr = r.tr.clone().unwrap_or_default();
    Shape::Repeater {
        copies: prop(r.c.as_ref(), 1.0, "repeater copies", w),
        offset: prop(r.o.as_ref(), 0.0, "repeater offset", w),
        transform: Transform::from_schema(Some(&tr), w),
        start_opacity: prop(tr.so.as_ref(), 100.0, "repeater start opacity", w),
        end_opacity: prop(tr.eo.as_ref(), 100.0, "repeater end opacity", w),
        above: r.m != Some(2.0),
    }
}

/// Mask combination mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaskMode {
    /// Union.
    Add,
    /// Subtract from what is there.
    Subtract,
    /// Intersect.
    Intersect,
    /// Maximum.
    Lighten,
    /// Minimum.
    Darken,
    /// Absolute difference.
    Difference,
    /// Disabled.
    None,
}

/// A layer mask.
#[derive(Clone, Debug)]
pub struct Mask {
    /// Mode.
    pub mode: MaskMode,
    /// Inverted.
    pub inverted: bool,
    /// The path (layer space).
    pub path: Value<Bez>,
    /// Opacity in percent.
    pub opacity: Value<f32>,
    /// Expansion in pixels.
    pub expansion: Value<f32>,
}

/// Resolves a mask of `masksProperties`.
fn mask(m: &schema::Mask, w: &mut Warn) -> Mask {
    let mode = match m.mode.as_deref() {
        Some("a") | None => MaskMode::Add,
        Some("s") => MaskMode::Subtract,
        Some("i") => MaskMode::Intersect,
        Some("l") => MaskMode::Lighten,
        Some("d") => MaskMode::Darken,
        Some("f") => MaskMode::Difference,
        Some("n") => MaskMode::None,
        Some(other) => {
            w.add(format!("mask mode '{other}' is not supported; treated as add"));
            MaskMode::Add
        }
    };
    Mask {
        mode,
        inverted: m.inv,
        path: prop(m.pt.as_ref(), Bez::default(), "mask path", w),
        opacity: prop(m.o.as_ref(), 100.0, "mask opacity", w),
        expansion: prop(m.x.as_ref(), 0.0, "mask expansion", w),
    }
}

/// Track matte mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MatteMode {
    /// Visible where the matte is opaque.
    Alpha,
    /// Visible where the matte is transparent.
    AlphaInverted,
    /// Visible by the matte's luminance.
    Luma,
    /// Visible by the inverse of the matte's luminance.
    LumaInverted,
}

/// What a layer draws.
#[derive(Clone, Debug)]
pub enum Content {
    /// Shapes (ty 4).
    Shapes(Vec<Shape>),
    /// A solid rectangle (ty 1).
    Solid {
        /// Color.
        color: [f32; 4],
        /// Width.
        width: f32,
        /// Height.
        height: f32,
    },
    /// A precomposition (ty 0).
    Precomp {
        /// Index into [`Model::comps`].
        comp: usize,
        /// Clip width.
        width: f32,
        /// Clip height.
        height: f32,
    },
    /// Null (ty 3) and everything that draws nothing.
    Nothing,
}

/// A layer.
#[derive(Clone, Debug)]
pub struct Layer {
    /// Name.
    pub name: String,
    /// Lottie type number (`None` when `ty` is missing or not a whole number).
    pub ty: Option<i64>,
    /// `ind`.
    pub ind: Option<i64>,
    /// Position of the parent layer in the same composition.
    pub parent: Option<usize>,
    /// In point.
    pub ip: f32,
    /// Out point.
    pub op: f32,
    /// Start time.
    pub st: f32,
    /// Time stretch.
    pub sr: f32,
    /// Hidden.
    pub hidden: bool,
    /// Transform.
    pub transform: Transform,
    /// Masks.
    pub masks: Vec<Mask>,
    /// Track matte: mode and position of the source layer in the same composition.
    pub matte: Option<(MatteMode, usize)>,
    /// True when this layer is a matte source (`td`), not drawn itself.
    pub is_matte_source: bool,
    /// Time remap in seconds (precomps).
    pub time_remap: Option<Value<f32>>,
    /// What it draws.
    pub content: Content,
    /// Why its type draws nothing (text, image, a missing precomp asset, an unreadable `ty`),
    /// without the layer's name: the error when no layer can be stylized quotes it.
    pub nothing: Option<String>,
    /// Problems found in this layer.
    pub warnings: Vec<String>,
}

impl Layer {
    /// The time at which the layer's own properties are evaluated for composition time `t`.
    /// Keyframe times are stored in the time of the containing composition (Bodymovin, and
    /// lottie-web / ThorVG, do not shift them by `st`), so this is `t` itself.
    pub fn local_time(&self, t: f32) -> f32 {
        t
    }

    /// The time inside a precomp layer's content for composition time `t`: `(t − st) / sr`.
    pub fn inner_time(&self, t: f32) -> f32 {
        (t - self.st) / self.sr
    }

    /// True when the layer is drawn at composition time `t`.
    pub fn active(&self, t: f32) -> bool {
        t >= self.ip && t < self.op
    }
}

/// A composition: the root or a precomp asset.
#[derive(Clone, Debug, Default)]
pub struct Composition {
    /// The layers, top-most first.
    pub layers: Vec<Layer>,
}

/// A parsed Lottie animation, resolved: compositions of layers whose transforms and shapes
/// evaluate at any frame. Made by [`parse`](super::parse), drawn by [`render`](super::render()).
#[derive(Clone, Debug)]
pub struct Model {
    /// Canvas width.
    pub(crate) width: f32,
    /// Canvas height.
    pub(crate) height: f32,
    /// Frame rate.
    pub(crate) fps: f32,
    /// First frame.
    pub(crate) ip: f32,
    /// Frame after the last.
    pub(crate) op: f32,
    /// `comps[0]` is the root; the rest are precomp assets.
    pub(crate) comps: Vec<Composition>,
    /// File-level warnings.
    pub(crate) warnings: Vec<String>,
}

impl Model {
    /// Canvas width in pixels (`w`).
    pub fn width(&self) -> f32 {
        self.width
    }

    /// Canvas height in pixels (`h`).
    pub fn height(&self) -> f32 {
        self.height
    }

    /// Frames per second (`fr`).
    pub fn fps(&self) -> f32 {
        self.fps
    }

    /// The first frame (`ip`): frame 0 of the animation is this composition time.
    pub fn first_frame(&self) -> f32 {
        self.ip
    }

    /// Number of frames, `op − ip` rounded up.
    pub fn frame_count(&self) -> usize {
        (self.op - self.ip).ceil().max(0.0) as usize
    }

    /// Number of top-level layers; a [`Target`](super::Target)'s `layer` is below it.
    pub fn layer_count(&self) -> usize {
        self.comps[0].layers.len()
    }

    /// Problems of the file as a whole (unsupported features), each a sentence.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }
}

fn solid_color(sc: Option<&str>) -> Option<[f32; 4]> {
    let s = sc?.trim().trim_start_matches('#');
    if s.len() < 6 || !s.is_ascii() {
        return None;
    }
    let c = |i: usize| u8::from_str_radix(&s[i..i + 2], 16).ok().map(|v| v as f32 / 255.0);
    Some([c(0)?, c(2)?, c(4)?, 1.0])
}

/// The type of the layer at JSON path `at`, or why it cannot be read.
fn layer_type(ty: Option<&Result<f64, String>>, at: &str) -> Result<i64, String> {
    match ty {
        None => Err(format!("{at}.ty is missing, expected a number (the layer type)")),
        Some(Err(written)) => Err(format!("{at}.ty is {written}, expected a number (the layer type)")),
        Some(Ok(t)) if t.fract() != 0.0 || t.abs() > 1e9 => {
            Err(format!("{at}.ty is {}, expected a whole number (the layer type)", number(*t)))
        }
        Some(Ok(t)) => Ok(*t as i64),
    }
}

struct Builder<'a> {
    asset_ids: HashMap<String, usize>,
    assets: &'a [schema::Asset],
    comps: Vec<Option<Composition>>,
    warnings: Vec<String>,
}

impl Builder<'_> {
    /// The layers of a composition; `at` is the JSON path of the list (`layers`,
    /// `assets[2].layers`), for messages.
    fn comp(&mut self, layers: &[schema::Layer], at: &str, depth: usize) -> Composition {
        let mut out: Vec<Layer> =
            layers.iter().enumerate().map(|(i, l)| self.layer(l, &format!("{at}[{i}]"), depth)).collect();
        // Parents by `ind`, in any order.
        let by_ind: HashMap<i64, usize> = out.iter().enumerate().filter_map(|(i, l)| l.ind.map(|x| (x, i))).collect();
        for (i, src) in layers.iter().enumerate() {
            if let Some(p) = src.parent {
                match by_ind.get(&(p as i64)) {
                    Some(&pi) if pi != i => out[i].parent = Some(pi),
                    found => {
                        let what = if found.is_some() { "is the layer itself" } else { "does not exist" };
                        let msg = format!("layer '{}': parent {} {what}; ignored", out[i].name, p);
                        out[i].warnings.push(msg);
                    }
                }
            }
        }
        // Break parent cycles.
        for i in 0..out.len() {
            let mut seen = 0;
            let mut cur = out[i].parent;
            while let Some(c) = cur {
                seen += 1;
                if seen > out.len() {
                    let msg = format!("layer '{}': parenting cycle; parent ignored", out[i].name);
                    out[i].warnings.push(msg);
                    out[i].parent = None;
                    break;
                }
                cur = out[c].parent;
            }
        }
        // Track mattes: `tp` names the source by `ind`; otherwise the layer right above.
        for (i, src) in layers.iter().enumerate() {
            let Some(tt) = src.tt.filter(|t| *t != 0.0) else { continue };
            let mode = match tt as i64 {
                1 => MatteMode::Alpha,
                2 => MatteMode::AlphaInverted,
                3 => MatteMode::Luma,
                4 => MatteMode::LumaInverted,
                other => {
                    let msg = format!("layer '{}': track matte mode {} is not supported; ignored", out[i].name, other);
                    out[i].warnings.push(msg);
                    continue;
                }
            };
            let source = match src.tp {
                Some(tp) => by_ind.get(&(tp as i64)).copied(),
                None => (i > 0).then(|| i - 1),
            };
            match source {
                Some(s) if s != i => {
                    out[i].matte = Some((mode, s));
                    out[s].is_matte_source = true;
                }
                _ => {
                    let msg = format!("layer '{}': its track matte layer does not exist; matte ignored", out[i].name);
                    out[i].warnings.push(msg);
                }
            }
        }
        for (i, src) in layers.iter().enumerate() {
            if src.td.is_some_and(|t| t != 0.0) {
                out[i].is_matte_source = true;
            }
        }
        Composition { layers: out }
    }

    /// The composition of precomp asset `id`; `Err` says why there is none.
    fn asset(&mut self, id: &str, depth: usize) -> Result<usize, String> {
        let Some(&idx) = self.asset_ids.get(id) else {
            return Err(format!("precomp asset '{id}' does not exist"));
        };
        let comp_index = idx + 1;
        if self.comps[comp_index].is_some() {
            return Ok(comp_index);
        }
        if depth >= MAX_DEPTH {
            return Err(format!("precomps nested deeper than {MAX_DEPTH} (or a reference cycle) at '{id}'"));
        }
        let Some(layers) = self.assets[idx].layers.as_ref() else {
            return Err(format!("asset '{id}' is an image (image layers are not supported)"));
        };
        // Mark as in progress (empty) so that a cycle terminates.
        self.comps[comp_index] = Some(Composition::default());
        let comp = self.comp(layers, &format!("assets[{idx}].layers"), depth + 1);
        self.comps[comp_index] = Some(comp);
        Ok(comp_index)
    }

    /// What a layer of type `ty` draws (`Content::Nothing` for a null); `Err` says why a layer
    /// that should draw something draws nothing.
    fn content(&mut self, l: &schema::Layer, ty: i64, depth: usize, w: &mut Warn) -> Result<Content, String> {
        Ok(match ty {
            0 => {
                let id = l.refId.as_deref().ok_or("precomp layer without refId")?;
                Content::Precomp {
                    comp: self.asset(id, depth)?,
                    width: l.w.unwrap_or(f64::INFINITY) as f32,
                    height: l.h.unwrap_or(f64::INFINITY) as f32,
                }
            }
            1 => {
                let color = solid_color(l.sc.as_deref()).unwrap_or_else(|| {
                    w.add("solid color missing or malformed; using black");
                    [0.0, 0.0, 0.0, 1.0]
                });
                Content::Solid { color, width: l.sw.unwrap_or(0.0) as f32, height: l.sh.unwrap_or(0.0) as f32 }
            }
            2 => return Err("image layers are not supported".into()),
            3 => Content::Nothing,
            4 => Content::Shapes(shapes(l.shapes.iter().flatten(), w, 0)),
            5 => return Err("text layers are not supported".into()),
            other => return Err(format!("layer type {other} is not supported")),
        })
    }

    /// A layer; `at` is its JSON path (`layers[0]`), for messages.
    fn layer(&mut self, l: &schema::Layer, at: &str, depth: usize) -> Layer {
        let ty = layer_type(l.ty.as_ref(), at);
        let name = l.nm.clone().unwrap_or_else(|| format!("layer {}", l.ind.map(|i| i as i64).unwrap_or(0)));
        let mut warnings = Vec::new();
        let mut w = Warn { layer: &name, out: &mut warnings };
        if l.ddd.is_some_and(|d| d != 0.0) {
            w.add("3D layers are not supported; drawn flat");
        }
        if l.ao.is_some_and(|a| a != 0.0) {
            w.add("auto-orient is not supported; ignored");
        }
        if l.bm.is_some_and(|b| b != 0.0) {
            w.add("blend modes are not supported; drawn as normal");
        }
        if l.ef {
            w.add("effects are not supported; ignored");
        }
        if l.sy {
            w.add("layer styles are not supported; ignored");
        }
        let transform = Transform::from_schema(l.ks.as_ref(), &mut w);
        let masks = l.masksProperties.iter().flatten().map(|m| mask(m, &mut w)).collect();
        let content = ty.clone().and_then(|ty| self.content(l, ty, depth, &mut w));
        let (content, nothing) = match content {
            Ok(content) => (content, None),
            Err(why) => {
                w.add(format!("{why}; nothing drawn"));
                (Content::Nothing, Some(why))
            }
        };
        let time_remap = (ty == Ok(0) && l.tm.is_some()).then(|| prop(l.tm.as_ref(), 0.0, "time remap", &mut w));
        let finite = |v: Option<f64>, d: f32| v.map(|x| x as f32).filter(|x| x.is_finite()).unwrap_or(d);
        let sr = finite(l.sr, 1.0);
        Layer {
            ind: l.ind.filter(|x| x.is_finite()).map(|x| x as i64),
            parent: None,
            ip: finite(l.ip, f32::NEG_INFINITY),
            op: finite(l.op, f32::INFINITY),
            st: finite(l.st, 0.0),
            sr: if sr == 0.0 { 1.0 } else { sr },
            hidden: l.hd,
            transform,
            masks,
            matte: None,
            is_matte_source: false,
            time_remap,
            content,
            nothing,
            ty: ty.ok(),
            name,
            warnings,
        }
    }
}

/// Builds the model from the parsed schema. `w`, `h`, `fr`, `ip`, `op` must be validated by
/// the caller.
pub fn build(root: &schema::Root, width: f32, height: f32, fps: f32, ip: f32, op: f32) -> Model {
    let mut asset_ids = HashMap::new();
    for (i, a) in root.assets.iter().enumerate() {
        if let Some(id) = &a.id {
            asset_ids.entry(id.clone()).or_insert(i);
        }
    }
    let mut b = Builder {
        asset_ids,
        assets: &root.assets,
        comps: (0..=root.assets.len()).map(|_| None).collect(),
        warnings: Vec::new(),
    };
    let rootc = b.comp(root.layers.as_deref().unwrap_or(&[]), "layers", 0);
    if root.chars {
        b.warnings.push("the file embeds glyphs (chars) for text; text is not supported".into());
    }
    if root.ddd.is_some_and(|d| d != 0.0) {
        b.warnings.push("3D composition (ddd) is not supported; drawn flat".into());
    }
    let mut comps: Vec<Composition> = b.comps.into_iter().map(Option::unwrap_or_default).collect();
    comps[0] = rootc;
    Model { width, height, fps, ip, op, comps, warnings: b.warnings }
}

#[cfg(test)]
mod tests {
    use serde_json::json;
    use std::path::Path;

    #[test]
    fn keyframes_of_both_layouts_evaluate_through_the_model() {
        // Position: linear 0 → 30 over frames 0..6 (4.x `e` style), held, then 5.x `s` style.
        let doc = json!({"v": "5.7.1", "fr": 10, "ip": 0, "op": 10, "w": 40, "h": 40, "layers": [
            {"ty": 4, "nm": "moving", "ind": 1, "ip": 0, "op": 10, "st": 0, "shapes": [],
             "ks": {"p": {"k": [
                {"t": 0, "s": [0, 0], "e": [30, 0], "i": {"x": 1, "y": 1}, "o": {"x": 0, "y": 0}},
                {"t": 6, "s": [30, 0], "h": 1}, {"t": 8, "s": [0, 20]}]}}}]});
        let m = super::super::parse(Path::new("t.json"), &doc.to_string()).unwrap();
        let tr = &m.comps[0].layers[0].transform;
        assert!((tr.position.evaluate(3.0).x - 15.0).abs() < 1e-3);
        assert_eq!(tr.position.evaluate(7.0), glam::Vec2::new(30.0, 0.0));
        assert_eq!(tr.position.evaluate(9.0), glam::Vec2::new(0.0, 20.0));
    }
}
