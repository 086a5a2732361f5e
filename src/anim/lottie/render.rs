//! The rasterizer: draws the resolved [`Model`] with tiny-skia. Knows nothing of JSON.
//!
//! One entry point, [`render`]: a layer (or one layer inside a top-level precomp) at a
//! composition time, at a given scale, in one [`Pass`] (fills, strokes, or both).

use super::super::motion::Fill;
use super::geom::{self, Bez, Star};
use super::model::{
    Composition, Content, Gradient, Layer, MAX_DEPTH, MaskMode, MatteMode, Model, Paint, Shape, StrokeStyle,
};
use super::value::Color;
use glam::{Affine2, Vec2};
use tiny_skia::{FillRule, Mask, MaskType, Pixmap, PixmapPaint};

/// What to draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    /// Fills only (`fl`, `gf`, solids).
    Fills,
    /// Strokes only (`st`, `gs`).
    Strokes,
    /// Everything, as the file would be displayed.
    All,
}

impl Pass {
    fn fills(self) -> bool {
        self != Pass::Strokes
    }
    fn strokes(self) -> bool {
        self != Pass::Fills
    }
}

/// Which layer to draw: a top-level layer, or one layer inside a top-level precomp.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Target {
    /// Position in the root composition.
    pub layer: usize,
    /// Position inside the layer's precomp, for split precomps.
    pub child: Option<usize>,
}

/// `m` as a tiny-skia transform; `None` when a coefficient is not finite.
pub(crate) fn to_ts(m: &Affine2) -> Option<tiny_skia::Transform> {
    let c = m.to_cols_array();
    if !c.iter().all(|x| x.is_finite()) {
        return None;
    }
    Some(tiny_skia::Transform::from_row(c[0], c[1], c[2], c[3], c[4], c[5]))
}

/// Largest device-space coordinate drawn. tiny-skia works in fixed point and can fail on
/// paths far outside the canvas (found by fuzzing); such paths are skipped.
const MAX_DEVICE_COORD: f32 = 1_000_000.0;

/// True when `path` under `ts`, widened by `pad` local units, stays within safe coordinates.
/// A path with a point that is not a number is not drawable either: its bounds leave the
/// point out, and tiny-skia panics on it (found by fuzzing: regression lottie/20261202-66841).
pub(crate) fn drawable(path: &tiny_skia::Path, ts: tiny_skia::Transform, pad: f32) -> bool {
    if !path.points().iter().all(|p| p.is_finite()) {
        return false;
    }
    let b = path.bounds();
    let pad = if pad.is_finite() { pad.max(0.0) } else { return false };
    let corners = [
        (b.left() - pad, b.top() - pad),
        (b.right() + pad, b.top() - pad),
        (b.left() - pad, b.bottom() + pad),
        (b.right() + pad, b.bottom() + pad),
    ];
    corners.iter().all(|&(x, y)| {
        let dx = ts.sx * x + ts.kx * y + ts.tx;
        let dy = ts.ky * x + ts.sy * y + ts.ty;
        dx.is_finite() && dy.is_finite() && dx.abs() < MAX_DEVICE_COORD && dy.abs() < MAX_DEVICE_COORD
    })
}

/// Most layer and repeater-copy draws in one rendering: reused precomps nested deeply, or
/// nested repeaters, multiply; past this budget the rest is skipped (with a warning).
pub const MAX_DRAWS: usize = 10_000;

/// What one rendering shares: the model, the canvas size and the draw budget.
struct Ctx<'a> {
    model: &'a Model,
    width: u32,
    height: u32,
    draws: std::cell::Cell<usize>,
    /// When set, fills are recorded here instead of drawn ([`fill_motion`]).
    record: Option<std::cell::RefCell<Vec<Fill>>>,
}

/// How a layer or a list of shape items is drawn: the state passed down from the enclosing
/// layers, precomps, groups and repeater copies.
#[derive(Clone, Copy)]
struct Draw<'a> {
    /// Time: of the containing composition for a layer, the layer's local time for its shapes.
    t: f32,
    /// The transform to the canvas.
    m: Affine2,
    /// Opacity in `0..=1` accumulated from the enclosing layers, groups and copies.
    alpha: f32,
    /// Coverage of the enclosing precomps' bounds.
    clip: Option<&'a Mask>,
    /// Fills, strokes or both.
    pass: Pass,
    /// Precomp nesting depth.
    depth: usize,
    /// Drawn as a track matte (not part of the region's own paint).
    matte: bool,
}

/// Why a layer is drawn.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Role {
    /// It is the region (drawn even when hidden); for a split precomp, only this child.
    Region(Option<usize>),
    /// It is the track matte of another layer (drawn even when hidden).
    Matte,
    /// It is inside a precomp being drawn.
    Nested,
}

impl Ctx<'_> {
    /// Counts one draw; false once the budget is spent.
    fn spend(&self) -> bool {
        let n = self.draws.get() + 1;
        self.draws.set(n);
        if n == MAX_DRAWS {
            log::warn!("more than {MAX_DRAWS} layer or repeater draws in one frame; the rest is skipped");
        }
        n <= MAX_DRAWS
    }
}

/// Renders `target` at composition time `time` (absolute frame number, `ip` based) into a
/// premultiplied pixmap of `width × height`, scaling the canvas by `scale`.
pub fn render(model: &Model, target: Target, time: f32, width: u32, height: u32, scale: f32, pass: Pass) -> Pixmap {
    let Some(mut pm) = Pixmap::new(width.max(1), height.max(1)) else {
        // Sizes are validated at load; a 1×1 pixmap always exists.
        return Pixmap::new(1, 1).unwrap_or_else(|| unreachable!());
    };
    let ctx = Ctx { model, width: pm.width(), height: pm.height(), draws: std::cell::Cell::new(0), record: None };
    ctx.draw_region(target, time, scale, pass, &mut pm);
    pm
}

/// The motion of the fills of `target` from composition time `time` to `next`, per
/// pixel of a `width × height` canvas scaled by `scale` (pixels; `None` where no fill is).
///
/// Each fill is drawn in its own coordinates under a transform to the canvas — the layer's,
/// its parents', the enclosing precomps', groups' and repeater copies' — so a point of the
/// fill at canvas position p at `time` is at `M′·M⁻¹·p` at `next`, M and M′ the fill's
/// transforms at the two times. Where fills overlap, the top-most one's motion is given.
/// A fill whose outline changes in its own coordinates but keeps its structure (path
/// keyframes, which interpolate vertex by vertex; an ellipse's or a rectangle's keyed size)
/// moves its outline point by point: sampled along each segment at the same curve parameters
/// at both times, the best affine map of the samples (least squares) plus each sample's
/// remaining motion, spread inside by inverse squared distance (`anim::motion`'s `PointMap`) — exact for an
/// outline that only scales or shears, an estimate inside one that bends. `None` when a
/// fill's outline changes its structure (a trim, a path of another vertex count), when the
/// two times do not draw the same number of fills (one appears, disappears or fades out
/// entirely), or when there is none.
pub(crate) fn fill_motion(
    model: &Model,
    target: Target,
    time: f32,
    next: f32,
    width: u32,
    height: u32,
    scale: f32,
) -> Option<crate::img::Plane<Option<Vec2>>> {
    let record = |t: f32| -> Option<Vec<Fill>> {
        let mut pm = Pixmap::new(width.max(1), height.max(1))?;
        let ctx = Ctx {
            model,
            width: pm.width(),
            height: pm.height(),
            draws: std::cell::Cell::new(0),
            record: Some(std::cell::RefCell::new(Vec::new())),
        };
        ctx.draw_region(target, t, scale, Pass::Fills, &mut pm);
        ctx.record.map(|r| r.into_inner())
    };
    let (from, to) = (record(time)?, record(next)?);
    super::super::motion::fills_motion(&from, &to, width, height)
}

impl Ctx<'_> {
    /// Draws `target` at composition time `time`, the canvas scaled by `scale`.
    fn draw_region(&self, target: Target, time: f32, scale: f32, pass: Pass, pm: &mut Pixmap) {
        let d = Draw {
            t: time,
            m: Affine2::from_scale(Vec2::splat(scale)),
            alpha: 1.0,
            clip: None,
            pass,
            depth: 0,
            matte: false,
        };
        if target.layer < self.model.comps[0].layers.len() {
            self.draw_layer(0, target.layer, Role::Region(target.child), d, pm);
        }
    }

    fn comp(&self, c: usize) -> &Composition {
        &self.model.comps[c]
    }

    fn world(&self, comp: &Composition, li: usize, t: f32) -> Affine2 {
        let l = &comp.layers[li];
        let mut m = l.transform.matrix(l.local_time(t));
        let mut cur = l.parent;
        let mut guard = 0;
        while let Some(p) = cur {
            guard += 1;
            if guard > comp.layers.len() {
                break;
            }
            let pl = &comp.layers[p];
            m = pl.transform.matrix(pl.local_time(t)) * m;
            cur = pl.parent;
        }
        m
    }

    fn new_pixmap(&self) -> Option<Pixmap> {
        Pixmap::new(self.width, self.height)
    }

    /// Draws layer `li` of composition `c`: its content, then its masks and track matte.
    fn draw_layer(&self, c: usize, li: usize, role: Role, d: Draw, target: &mut Pixmap) {
        let comp = self.comp(c);
        let layer = &comp.layers[li];
        if (layer.hidden && role == Role::Nested) || !layer.active(d.t) || d.depth > MAX_DEPTH || !self.spend() {
            return;
        }
        let lt = layer.local_time(d.t);
        let content =
            Draw { t: lt, m: d.m * self.world(comp, li, d.t), alpha: d.alpha * layer.transform.opacity(lt), ..d };
        if content.alpha <= 0.0 {
            return;
        }
        let only = match role {
            Role::Region(child) => child,
            Role::Matte | Role::Nested => None,
        };
        let has_masks = layer.masks.iter().any(|m| m.mode != MaskMode::None);
        if !has_masks && layer.matte.is_none() {
            self.draw_content(layer, only, content, target);
            return;
        }
        let Some(mut pm) = self.new_pixmap() else { return };
        self.draw_content(layer, only, content, &mut pm);
        if has_masks {
            match self.layer_mask(layer, lt, content.m) {
                Some(mask) => pm.apply_mask(&mask),
                None => return,
            }
        }
        if let Some((mode, src)) = layer.matte {
            let Some(mut mp) = self.new_pixmap() else { return };
            // The matte source is drawn whole (fills and strokes), with the same outer transform.
            let matte = Draw { alpha: 1.0, pass: Pass::All, depth: d.depth + 1, matte: true, ..d };
            self.draw_layer(c, src, Role::Matte, matte, &mut mp);
            let mut mask = Mask::from_pixmap(
                mp.as_ref(),
                match mode {
                    MatteMode::Alpha | MatteMode::AlphaInverted => MaskType::Alpha,
                    MatteMode::Luma | MatteMode::LumaInverted => MaskType::Luminance,
                },
            );
            if matches!(mode, MatteMode::AlphaInverted | MatteMode::LumaInverted) {
                mask.invert();
            }
            pm.apply_mask(&mask);
        }
        target.draw_pixmap(0, 0, pm.as_ref(), &PixmapPaint::default(), tiny_skia::Transform::identity(), None);
    }

    /// Draws what a layer contains (`only` one child of a precomp, for split precomps).
    fn draw_content(&self, layer: &Layer, only: Option<usize>, d: Draw, target: &mut Pixmap) {
        match &layer.content {
            Content::Shapes(items) => self.draw_items(items, d, target),
            Content::Solid { color, width, height } => {
                if !d.pass.fills() {
                    return;
                }
                let Some(rect) = tiny_skia::Rect::from_xywh(0.0, 0.0, *width, *height) else { return };
                let Some(ts) = to_ts(&d.m) else { return };
                let mut paint = tiny_skia::Paint { anti_alias: true, ..Default::default() };
                paint.set_color(rgba(color, d.alpha));
                let path = tiny_skia::PathBuilder::from_rect(rect);
                if !drawable(&path, ts, 0.0) {
                    return;
                }
                if let Some(record) = &self.record {
                    if !d.matte {
                        record.borrow_mut().push(Fill { path, m: d.m, rule: FillRule::Winding });
                    }
                    return;
                }
                target.fill_path(&path, &paint, FillRule::Winding, ts, d.clip);
            }
            Content::Precomp { comp, width, height } => {
                let inner_t = match &layer.time_remap {
                    Some(tm) => tm.evaluate(d.t) * self.model.fps,
                    None => layer.inner_time(d.t),
                };
                if !inner_t.is_finite() {
                    return;
                }
                let own_clip = self.precomp_clip(d.m, *width, *height, d.clip);
                let clip = match &own_clip {
                    Some(Some(mask)) => Some(mask),
                    Some(None) => return, // clipped away entirely
                    None => d.clip,
                };
                let inner = self.comp(*comp);
                let d = Draw { t: inner_t, clip, depth: d.depth + 1, ..d };
                for ci in (0..inner.layers.len()).rev() {
                    if inner.layers[ci].is_matte_source || only.is_some_and(|o| o != ci) {
                        continue;
                    }
                    self.draw_layer(*comp, ci, Role::Nested, d, target);
                }
            }
            Content::Nothing => {}
        }
    }

    /// The clip of a precomp's bounds: `None` when it clips nothing visible, `Some(None)`
    /// when it hides everything, else the combined clip mask.
    fn precomp_clip(&self, m: Affine2, w: f32, h: f32, clip: Option<&Mask>) -> Option<Option<Mask>> {
        if !(w.is_finite() && h.is_finite()) {
            return None;
        }
        let corners =
            [Vec2::ZERO, Vec2::new(w, 0.0), Vec2::new(w, h), Vec2::new(0.0, h)].map(|p| m.transform_point2(p));
        let axis_aligned = m.matrix2.x_axis.y.abs() < 1e-6 && m.matrix2.y_axis.x.abs() < 1e-6;
        if axis_aligned {
            let (minx, maxx) = corners.iter().fold((f32::MAX, f32::MIN), |a, p| (a.0.min(p.x), a.1.max(p.x)));
            let (miny, maxy) = corners.iter().fold((f32::MAX, f32::MIN), |a, p| (a.0.min(p.y), a.1.max(p.y)));
            if minx <= 0.0 && miny <= 0.0 && maxx >= self.width as f32 && maxy >= self.height as f32 {
                return None;
            }
        }
        let mut pb = tiny_skia::PathBuilder::new();
        pb.move_to(corners[0].x, corners[0].y);
        for p in &corners[1..] {
            pb.line_to(p.x, p.y);
        }
        pb.close();
        let Some(path) = pb.finish() else { return Some(None) };
        if !drawable(&path, tiny_skia::Transform::identity(), 0.0) {
            return None;
        }
        let mut mask = Mask::new(self.width, self.height)?;
        mask.fill_path(&path, FillRule::Winding, true, tiny_skia::Transform::identity());
        if let Some(c) = clip {
            for (a, b) in mask.data_mut().iter_mut().zip(c.data()) {
                *a = ((*a as u16 * *b as u16 + 127) / 255) as u8;
            }
        }
        Some(Some(mask))
    }

    /// The combined coverage of a layer's masks, or `None` when nothing is visible.
    fn layer_mask(&self, layer: &Layer, lt: f32, m: Affine2) -> Option<Mask> {
        let masks: Vec<_> = layer.masks.iter().filter(|k| k.mode != MaskMode::None).collect();
        let n = (self.width * self.height) as usize;
        let first_full =
            matches!(masks.first().map(|k| k.mode), Some(MaskMode::Subtract | MaskMode::Intersect | MaskMode::Darken));
        let mut acc = vec![if first_full { 1.0f32 } else { 0.0 }; n];
        let ts = to_ts(&m)?;
        for mk in masks {
            let bez = mk.path.evaluate(lt);
            let opacity = (mk.opacity.evaluate(lt) / 100.0).clamp(0.0, 1.0);
            let opacity = if opacity.is_finite() { opacity } else { 0.0 };
            let x = mk.expansion.evaluate(lt);
            let mut pm = self.new_pixmap()?;
            if let Some(path) = geom::to_skia_path(std::slice::from_ref(&bez))
                && drawable(&path, ts, x.abs())
            {
                let mut paint = tiny_skia::Paint { anti_alias: true, ..Default::default() };
                paint.set_color(tiny_skia::Color::WHITE);
                pm.fill_path(&path, &paint, FillRule::Winding, ts, None);
                if x.is_finite() && x.abs() > 0.0 {
                    let stroke = tiny_skia::Stroke {
                        width: 2.0 * x.abs(),
                        line_join: tiny_skia::LineJoin::Round,
                        ..Default::default()
                    };
                    if x < 0.0 {
                        paint.blend_mode = tiny_skia::BlendMode::Clear;
                    }
                    pm.stroke_path(&path, &paint, &stroke, ts, None);
                }
            }
            for (a, p) in acc.iter_mut().zip(pm.pixels()) {
                let mut v = p.alpha() as f32 / 255.0;
                if mk.inverted {
                    v = 1.0 - v;
                }
                v *= opacity;
                *a = match mk.mode {
                    MaskMode::Add => *a + v - *a * v,
                    MaskMode::Subtract => *a * (1.0 - v),
                    MaskMode::Intersect => *a * v,
                    MaskMode::Lighten => a.max(v),
                    MaskMode::Darken => a.min(v),
                    MaskMode::Difference => (*a - v).abs(),
                    MaskMode::None => *a,
                };
            }
        }
        let data = acc.iter().map(|&a| (a.clamp(0.0, 1.0) * 255.0 + 0.5) as u8).collect();
        Mask::from_vec(data, tiny_skia::IntSize::from_wh(self.width, self.height)?)
    }

    fn draw_items(&self, items: &[Shape], d: Draw, target: &mut Pixmap) {
        let mut tree = evaluate(items, d.t, 0);
        apply_modifiers(&mut tree);
        self.draw_tree(&tree, d, target);
    }

    /// Draws evaluated items, bottom-most first: each style paints the paths above it.
    fn draw_tree(&self, items: &[Item], d: Draw, target: &mut Pixmap) {
        for k in (0..items.len()).rev() {
            match &items[k] {
                Item::Group { items: inner, matrix, opacity } if *opacity > 0.0 => {
                    self.draw_tree(inner, Draw { m: d.m * *matrix, alpha: d.alpha * opacity, ..d }, target);
                }
                Item::Other(Shape::Fill { paint, opacity, even_odd }) if d.pass.fills() => {
                    let paths = collect(&items[..k]);
                    let alpha = d.alpha * (opacity.evaluate(d.t) / 100.0).clamp(0.0, 1.0);
                    let rule = if *even_odd { FillRule::EvenOdd } else { FillRule::Winding };
                    self.fill(&paths, paint, rule, Draw { alpha, ..d }, target);
                }
                Item::Other(Shape::Stroke { paint, opacity, style }) if d.pass.strokes() => {
                    let paths = collect(&items[..k]);
                    let alpha = d.alpha * (opacity.evaluate(d.t) / 100.0).clamp(0.0, 1.0);
                    self.stroke(&paths, paint, style, Draw { alpha, ..d }, target);
                }
                Item::Repeater { copies, start_opacity, end_opacity, above } => {
                    let n = copies.len();
                    let order: Vec<usize> = if *above { (0..n).collect() } else { (0..n).rev().collect() };
                    for c in order {
                        if !self.spend() {
                            return;
                        }
                        // Copy c fades by (c + 1) / n, as ThorVG draws it.
                        let f = (c + 1) as f32 / n as f32;
                        let o = (start_opacity + (end_opacity - start_opacity) * f).clamp(0.0, 1.0);
                        self.draw_tree(&items[..k], Draw { m: d.m * copies[c], alpha: d.alpha * o, ..d }, target);
                    }
                    return;
                }
                _ => {}
            }
        }
    }

    /// Fills `paths` with `paint` at opacity `d.alpha`.
    fn fill(&self, paths: &[Bez], paint: &Paint, rule: FillRule, d: Draw, target: &mut Pixmap) {
        if d.alpha <= 0.0 || !d.alpha.is_finite() {
            return;
        }
        let (Some(path), Some(ts)) = (geom::to_skia_path(paths), to_ts(&d.m)) else { return };
        if !drawable(&path, ts, 0.0) {
            return;
        }
        if let Some(record) = &self.record {
            if !d.matte {
                record.borrow_mut().push(Fill { path, m: d.m, rule });
            }
            return;
        }
        let Some(p) = make_paint(paint, d.alpha, d.t) else { return };
        target.fill_path(&path, &p, rule, ts, d.clip);
    }

    /// Strokes `paths` with `paint` at opacity `d.alpha`.
    fn stroke(&self, paths: &[Bez], paint: &Paint, style: &StrokeStyle, d: Draw, target: &mut Pixmap) {
        let (t, opacity) = (d.t, d.alpha);
        let width = style.width.evaluate(t);
        if opacity <= 0.0 || !opacity.is_finite() || !width.is_finite() || width <= 0.0 {
            return;
        }
        let Some(ts) = to_ts(&d.m) else { return };
        let Some(p) = make_paint(paint, opacity, t) else { return };
        let Some(path) = geom::to_skia_path(paths) else { return };
        if !drawable(&path, ts, width * style.miter.max(1.0)) {
            return;
        }
        if path.bounds().width() <= 0.0 && path.bounds().height() <= 0.0 {
            return; // zero-length: ThorVG draws no cap dot either
        }
        let mut stroke = tiny_skia::Stroke {
            width,
            miter_limit: style.miter,
            line_cap: style.cap,
            line_join: style.join,
            dash: None,
        };
        if !style.dashes.is_empty() {
            let mut arr: Vec<f32> = style.dashes.iter().map(|(_, v)| v.evaluate(t).max(0.0)).collect();
            if arr.len() % 2 == 1 {
                arr.extend(arr.clone());
            }
            let off = style.dash_offset.as_ref().map_or(0.0, |o| o.evaluate(t));
            if arr.iter().all(|x| x.is_finite()) && arr.iter().sum::<f32>() > 0.0 {
                stroke.dash = tiny_skia::StrokeDash::new(arr, if off.is_finite() { off } else { 0.0 });
            }
        }
        target.stroke_path(&path, &p, &stroke, ts, d.clip);
    }
}

fn rgba(c: &[f32; 4], opacity: f32) -> tiny_skia::Color {
    tiny_skia::Color::from_rgba(
        c[0].clamp(0.0, 1.0),
        c[1].clamp(0.0, 1.0),
        c[2].clamp(0.0, 1.0),
        (c[3] * opacity).clamp(0.0, 1.0),
    )
    .unwrap_or(tiny_skia::Color::TRANSPARENT)
}

/// The color and alpha stops of a gradient at `t`, merged into one list.
pub fn gradient_stops(g: &Gradient, t: f32) -> Vec<(f32, [f32; 4])> {
    let raw = g.stops.evaluate(t);
    let n = g.count.min(raw.len() / 4);
    let colors: Vec<(f32, [f32; 3])> =
        (0..n).map(|k| (raw[4 * k], [raw[4 * k + 1], raw[4 * k + 2], raw[4 * k + 3]])).collect();
    let alphas: Vec<(f32, f32)> = raw[4 * n..].chunks_exact(2).map(|c| (c[0], c[1])).collect();
    let interp = |list: &[(f32, f32)], x: f32| -> f32 {
        match list.iter().position(|s| s.0 >= x) {
            Some(0) => list[0].1,
            Some(i) => {
                let (a, b) = (list[i - 1], list[i]);
                let f = if b.0 > a.0 { (x - a.0) / (b.0 - a.0) } else { 0.0 };
                a.1 + (b.1 - a.1) * f
            }
            None => list.last().map_or(1.0, |s| s.1),
        }
    };
    let color_at = |x: f32| -> [f32; 3] {
        std::array::from_fn(|ch| {
            let l: Vec<(f32, f32)> = colors.iter().map(|c| (c.0, c.1[ch])).collect();
            interp(&l, x)
        })
    };
    let mut offsets: Vec<f32> = colors.iter().map(|c| c.0).chain(alphas.iter().map(|a| a.0)).collect();
    offsets.retain(|x| x.is_finite());
    offsets.sort_by(|a, b| a.total_cmp(b));
    offsets.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
    offsets
        .into_iter()
        .map(|x| {
            let c = color_at(x);
            let a = if alphas.is_empty() { 1.0 } else { interp(&alphas, x) };
            (x.clamp(0.0, 1.0), [c[0], c[1], c[2], a])
        })
        .collect()
}

fn make_paint(paint: &Paint, opacity: f32, t: f32) -> Option<tiny_skia::Paint<'static>> {
    let mut p = tiny_skia::Paint { anti_alias: true, ..Default::default() };
    match paint {
        Paint::Color(c) => {
            let Color(c) = c.evaluate(t);
            p.set_color(rgba(&c, opacity));
        }
        Paint::Gradient(g) => {
            let stops: Vec<tiny_skia::GradientStop> = gradient_stops(g, t)
                .into_iter()
                .map(|(x, c)| tiny_skia::GradientStop::new(x, rgba(&c, opacity)))
                .collect();
            if stops.is_empty() {
                return None;
            }
            let (s, e) = (g.start.evaluate(t), g.end.evaluate(t));
            let (s, e) = (tiny_skia::Point::from_xy(s.x, s.y), tiny_skia::Point::from_xy(e.x, e.y));
            let id = tiny_skia::Transform::identity();
            let shader = if g.radial {
                let r = ((e.x - s.x).powi(2) + (e.y - s.y).powi(2)).sqrt();
                let hl = (g.highlight_length.evaluate(t) / 100.0).clamp(-0.99, 0.99);
                let ha = g.highlight_angle.evaluate(t).to_radians() + (e.y - s.y).atan2(e.x - s.x);
                let f = tiny_skia::Point::from_xy(s.x + hl * r * ha.cos(), s.y + hl * r * ha.sin());
                tiny_skia::RadialGradient::new(f, 0.0, s, r, stops, tiny_skia::SpreadMode::Pad, id)
            } else {
                tiny_skia::LinearGradient::new(s, e, stops, tiny_skia::SpreadMode::Pad, id)
            };
            // A degenerate gradient paints its last color (what browsers do).
            p.shader = match shader {
                Some(sh) => sh,
                None => {
                    let last = gradient_stops(g, t).last().map(|s| s.1)?;
                    tiny_skia::Shader::SolidColor(rgba(&last, opacity))
                }
            };
        }
    }
    Some(p)
}

fn repeater_matrix(tr: &super::model::Transform, t: f32, i: f32) -> Affine2 {
    let a = tr.anchor.evaluate(t);
    let p = tr.position.evaluate(t);
    let s = tr.scale.evaluate(t) / 100.0;
    let r = tr.rotation.evaluate(t).to_radians();
    let sp = Vec2::new(s.x.abs().powf(i) * s.x.signum(), s.y.abs().powf(i) * s.y.signum());
    Affine2::from_translation(p * i + a)
        * Affine2::from_angle(r * i)
        * Affine2::from_scale(sp)
        * Affine2::from_translation(-a)
}

/// A shape item evaluated at one time: geometry as paths, groups with their matrix.
pub enum Item<'a> {
    /// A geometry item's paths (after the modifiers that apply to it).
    Geometry(Vec<Bez>),
    /// A group.
    Group {
        /// Its items.
        items: Vec<Item<'a>>,
        /// Its transform.
        matrix: Affine2,
        /// Its opacity in `0..=1`.
        opacity: f32,
    },
    /// A repeater: per-copy matrices and the opacity fade.
    Repeater {
        /// One matrix per copy.
        copies: Vec<Affine2>,
        /// Opacity of the first copy.
        start_opacity: f32,
        /// Opacity of the last copy.
        end_opacity: f32,
        /// Copies stacked above the original.
        above: bool,
    },
    /// Trim paths: start, end (fractions), offset (turns), sequential.
    Trim(f32, f32, f32, bool),
    /// Rounded corners with this radius.
    Round(f32),
    /// Styles and anything else, evaluated when drawn.
    Other(&'a Shape),
}

/// Evaluates the shape items at `t`.
pub fn evaluate(items: &[Shape], t: f32, depth: usize) -> Vec<Item<'_>> {
    let mut out = Vec::with_capacity(items.len());
    for item in items {
        out.push(match item {
            Shape::Path(v) => Item::Geometry(vec![v.evaluate(t)]),
            Shape::Rect { position, size, roundness, reverse } => Item::Geometry(vec![geom::rect(
                position.evaluate(t),
                size.evaluate(t),
                roundness.evaluate(t),
                *reverse,
            )]),
            Shape::Ellipse { position, size, reverse } => {
                Item::Geometry(vec![geom::ellipse(position.evaluate(t), size.evaluate(t), *reverse)])
            }
            Shape::Star {
                star,
                position,
                points,
                rotation,
                outer_radius,
                outer_roundness,
                inner_radius,
                inner_roundness,
                reverse,
            } => Item::Geometry(vec![geom::polystar(&Star {
                center: position.evaluate(t),
                points: points.evaluate(t),
                rotation: rotation.evaluate(t),
                outer_radius: outer_radius.evaluate(t),
                outer_roundness: outer_roundness.evaluate(t),
                inner_radius: inner_radius.evaluate(t),
                inner_roundness: inner_roundness.evaluate(t),
                star: *star,
                reverse: *reverse,
            })]),
            Shape::Group { items, transform } => {
                if depth > 64 {
                    continue;
                }
                Item::Group {
                    items: evaluate(items, t, depth + 1),
                    matrix: transform.matrix(t),
                    opacity: transform.opacity(t),
                }
            }
            Shape::Trim { start, end, offset, sequential } => {
                let (s, e, o) = (start.evaluate(t) / 100.0, end.evaluate(t) / 100.0, offset.evaluate(t) / 360.0);
                if !(s.is_finite() && e.is_finite()) {
                    continue;
                }
                Item::Trim(s, e, if o.is_finite() { o } else { 0.0 }, *sequential)
            }
            Shape::Round(r) => Item::Round(r.evaluate(t)),
            Shape::Repeater { copies, offset, transform, start_opacity, end_opacity, above } => {
                let n = copies.evaluate(t).clamp(0.0, super::model::MAX_COPIES);
                let n = if n.is_finite() { n.ceil() as usize } else { 0 };
                let off = offset.evaluate(t);
                Item::Repeater {
                    copies: (0..n).map(|c| repeater_matrix(transform, t, c as f32 + off)).collect(),
                    start_opacity: start_opacity.evaluate(t) / 100.0,
                    end_opacity: end_opacity.evaluate(t) / 100.0,
                    above: *above,
                }
            }
            other => Item::Other(other),
        });
    }
    out
}

fn geometry_mut<'a, 'b>(items: &'a mut [Item<'b>], out: &mut Vec<&'a mut Vec<Bez>>) {
    for item in items {
        match item {
            Item::Geometry(g) => out.push(g),
            Item::Group { items, .. } => geometry_mut(items, out),
            _ => {}
        }
    }
}

/// Applies every modifier (trim, rounded corners) to the geometry above it in its group,
/// nested groups included, in list order.
pub fn apply_modifiers(items: &mut [Item]) {
    for k in 0..items.len() {
        if let Item::Group { items: inner, .. } = &mut items[k] {
            apply_modifiers(inner);
        }
        let (before, rest) = items.split_at_mut(k);
        match &rest[0] {
            Item::Trim(s, e, o, sequential) => {
                let (s, e, o, sequential) = (*s, *e, *o, *sequential);
                let mut geo = Vec::new();
                geometry_mut(before, &mut geo);
                if sequential {
                    let all: Vec<Bez> = geo.iter().flat_map(|g| g.iter().cloned()).collect();
                    let counts: Vec<usize> = geo.iter().map(|g| g.len()).collect();
                    let trimmed = geom::trim_sequential_per_path(&all, s, e, o);
                    let mut it = trimmed.into_iter();
                    for (g, n) in geo.iter_mut().zip(counts) {
                        **g = it.by_ref().take(n).flatten().collect();
                    }
                } else {
                    for g in geo {
                        *g = geom::trim(g, s, e, o, false);
                    }
                }
            }
            Item::Round(r) => {
                let r = *r;
                let mut geo = Vec::new();
                geometry_mut(before, &mut geo);
                for g in geo {
                    *g = g.iter().map(|b| geom::round_corners(b, r)).collect();
                }
            }
            _ => {}
        }
    }
}

/// The paths of the items (geometry and nested groups, transformed into the items' space),
/// repeated by any repeater among them.
pub fn collect(items: &[Item]) -> Vec<Bez> {
    let mut out: Vec<Bez> = Vec::new();
    for item in items {
        match item {
            Item::Geometry(g) => out.extend(g.iter().cloned()),
            Item::Group { items, matrix, .. } => out.extend(collect(items).iter().map(|b| b.transformed(matrix))),
            Item::Repeater { copies, .. } => {
                let base = std::mem::take(&mut out);
                for m in copies {
                    out.extend(base.iter().map(|b| b.transformed(m)));
                }
            }
            _ => {}
        }
    }
    out
}
