//! Lottie (Bodymovin JSON) input, in three steps like usvg/velato: `schema` (serde mirror of
//! the JSON, shape items tagged by `ty`, tolerant of 4.x and 5.x layouts) → `model` (resolved
//! layers, transforms and shapes whose values `evaluate(frame)`, built once by [`parse`]) →
//! [`render()`] (tiny-skia, no JSON; `geom` holds the path geometry).
//!
//! Supported: shape, solid, null and precomp layers (assets, nesting, reuse, time remap,
//! `ip`/`op`/`st`/`sr`, parenting in any order, hidden layers); layer and group transforms
//! (anchor, position incl. split and spatial tangents, scale, rotation, skew, opacity);
//! keyframes with per-dimension bezier easing, hold keyframes and 4.x `e` end values;
//! shapes `gr sh rc el sr fl gf st gs tm rd rp`; masks (add, subtract, intersect, lighten,
//! darken, difference, inverted, opacity, expansion) and track mattes (alpha, luma,
//! inverted; `tt`/`td` and `tp`).
//!
//! Not supported, reported as warnings naming the feature and the layer: text and image
//! layers, expressions (the keyframed value is used), effects, layer styles, blend modes,
//! 3D, auto-orient, merge paths other than plain merging (paths are combined, no boolean
//! operation), the offset/puker-bloat/twist/zig-zag modifiers.
//!
//! Regions: every top-level layer that draws something is a region, except nulls, matte
//! sources (`td`), hidden layers and the background (the bottom-most run of solid layers that
//! cover the whole canvas). With [`LoadOptions::split_precomps`](super::LoadOptions) each
//! drawable layer inside a top-level precomp is a region of its own, named `outer/inner`.
//! A region's `visible` range comes from the layers' in and out points.

mod geom;
mod model;
mod nesting;
mod render;
mod schema;
mod value;

pub use model::Model;
pub use render::{Pass, Target, render};
pub(crate) use render::{drawable, to_ts};

use super::{
    Animation, Background, LoadOptions, MAX_FRAMES, MAX_SIDE, Region, RegionFrame, RegionKind, RegionRenderer,
};
use crate::error::{Error, Result, number};
use crate::img::{Plane, Rgba};
use model::{Composition, Content, Shape};
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// Smallest frame rate accepted (a frame every 100 s; the GIF's delays are hundredths of a
/// second, at most 655 s).
pub const MIN_FPS: f64 = 0.01;

/// Largest frame rate accepted.
pub const MAX_FPS: f64 = 1000.0;

/// Parses Lottie JSON text into the resolved model. `path` is only used in messages.
pub fn parse(path: &Path, text: &str) -> Result<Model> {
    if text.trim().is_empty() {
        return Err(Error::Empty { path: path.to_path_buf(), what: "the file is empty".into() });
    }
    // A Lottie file is one JSON object; anything else (an array, a number) would be reported in
    // the deserializer's own terms.
    let first = text.trim_start().chars().next();
    if first.is_some_and(|c| c != '{') && serde_json::from_str::<serde::de::IgnoredAny>(text).is_ok() {
        return Err(Error::animation(
            path,
            "not a Lottie file: its top level is not a JSON object; re-export it with Bodymovin",
        ));
    }
    // A field of the wrong type is named by its JSON path where the typed reading's message
    // would only give the line and column.
    let root: schema::Root = serde_json::from_str(text).map_err(|e| {
        let why = e.is_data().then(|| serde_json::from_str(text).ok().and_then(|v| schema::misshapen(&v))).flatten();
        match why {
            Some(why) => Error::animation(path, why),
            None => Error::Json {
                path: path.to_path_buf(),
                line: e.line(),
                column: e.column(),
                message: e.to_string(),
                source: Some(Box::new(e)),
            },
        }
    })?;
    let need = |v: Option<f64>, key: &str, what: &str| -> Result<f64> {
        match v {
            None => Err(Error::animation(
                path,
                format!("missing '{key}' ({what}); is this a Lottie file? Re-export it with Bodymovin"),
            )),
            Some(x) if !x.is_finite() => {
                Err(Error::animation(path, format!("'{key}' ({what}) is not a finite number")))
            }
            Some(x) => Ok(x),
        }
    };
    let w = need(root.w, "w", "canvas width")?;
    let h = need(root.h, "h", "canvas height")?;
    let fr = need(root.fr, "fr", "frame rate")?;
    let ip = root.ip.map_or(Ok(0.0), |x| need(Some(x), "ip", "first frame"))?;
    let op = need(root.op, "op", "end frame")?;
    for (v, what) in [(w, "canvas width 'w'"), (h, "canvas height 'h'")] {
        if v < 1.0 {
            return Err(Error::animation(path, format!("{what} is {v}; it must be at least 1 pixel")));
        }
        if v > MAX_SIDE as f64 {
            return Err(Error::Limit { path: path.to_path_buf(), what: what.into(), value: v, limit: MAX_SIDE as f64 });
        }
    }
    if fr < MIN_FPS {
        return Err(Error::animation(
            path,
            format!("frame rate 'fr' is {}; it must be at least {MIN_FPS}", number(fr)),
        ));
    }
    if fr > MAX_FPS {
        return Err(Error::Limit {
            path: path.to_path_buf(),
            what: "frame rate 'fr'".into(),
            value: fr,
            limit: MAX_FPS,
        });
    }
    if ip.abs() > 1e9 || op.abs() > 1e9 {
        return Err(Error::animation(
            path,
            format!("'ip' {} / 'op' {} are absurd frame numbers", number(ip), number(op)),
        ));
    }
    // The model keeps frame numbers in f32: they must differ there too (`op` = 1e-300).
    if op <= ip || op as f32 <= ip as f32 {
        return Err(Error::animation(
            path,
            format!(
                "end frame 'op' ({}) is not after the first frame 'ip' ({}); the animation has no frames",
                number(op),
                number(ip)
            ),
        ));
    }
    let frames = (op - ip).ceil();
    if frames > MAX_FRAMES as f64 {
        return Err(Error::Limit {
            path: path.to_path_buf(),
            what: "frame count ('op' - 'ip')".into(),
            value: frames,
            limit: MAX_FRAMES as f64,
        });
    }
    if root.layers.is_none() {
        return Err(Error::animation(path, "missing 'layers'; is this a Lottie file?"));
    }
    nesting::check_references(path, &root)?;
    Ok(model::build(&root, w as f32, h as f32, fr as f32, ip as f32, op as f32))
}

fn has_strokes(model: &Model, items: &[Shape]) -> bool {
    let _ = model;
    items.iter().any(|s| match s {
        Shape::Stroke { .. } => true,
        Shape::Group { items, .. } => has_strokes(model, items),
        _ => false,
    })
}

fn layer_has_strokes(model: &Model, comp: &Composition, li: usize, memo: &mut HashMap<usize, bool>) -> bool {
    match &comp.layers[li].content {
        Content::Shapes(items) => has_strokes(model, items),
        Content::Precomp { comp: c, .. } => {
            if let Some(&known) = memo.get(c) {
                return known;
            }
            memo.insert(*c, false); // cycles end here
            let inner = &model.comps[*c];
            let any = (0..inner.layers.len())
                .any(|i| !inner.layers[i].is_matte_source && layer_has_strokes(model, inner, i, memo));
            memo.insert(*c, any);
            any
        }
        _ => false,
    }
}

/// Gathers the warnings of a layer, its matte source and everything inside its precomp
/// (each composition visited once).
fn collect_warnings(model: &Model, comp: &Composition, li: usize, out: &mut Vec<String>, seen: &mut Vec<usize>) {
    let l = &comp.layers[li];
    for w in &l.warnings {
        if !out.contains(w) {
            out.push(w.clone());
        }
    }
    if let Some((_, src)) = l.matte
        && src != li
    {
        for w in &comp.layers[src].warnings {
            if !out.contains(w) {
                out.push(w.clone());
            }
        }
    }
    if let Content::Precomp { comp: c, .. } = &l.content {
        if seen.contains(c) {
            return;
        }
        seen.push(*c);
        let inner = &model.comps[*c];
        for i in 0..inner.layers.len() {
            collect_warnings(model, inner, i, out, seen);
        }
    }
}

/// True when the layer draws nothing by its nature (null, unsupported types) or is fully
/// transparent at every frame (a helper layer, often a parent).
fn draws_nothing(l: &model::Layer) -> bool {
    matches!(l.content, Content::Nothing)
        || matches!(l.transform.opacity, value::Value::Fixed(o) if o.is_nan() || o <= 0.0)
}

/// Whether a root layer is a full-canvas solid, opaque and unmasked, visible throughout.
fn is_background(model: &Model, li: usize) -> Option<[f32; 4]> {
    let l = &model.comps[0].layers[li];
    let Content::Solid { color, width, height } = l.content else { return None };
    if !l.masks.is_empty() || l.matte.is_some() || l.hidden || l.ip > model.ip || l.op < model.op {
        return None;
    }
    // Check coverage and opacity at a few times.
    let n = model.frame_count();
    for f in [0, n / 2, n.saturating_sub(1)] {
        let t = model.ip + f as f32;
        let lt = l.local_time(t);
        if l.transform.opacity(lt) < 0.999 {
            return None;
        }
        let mut m = l.transform.matrix(lt);
        let mut cur = l.parent;
        let mut guard = 0;
        while let Some(p) = cur {
            guard += 1;
            if guard > 64 {
                return None;
            }
            let pl = &model.comps[0].layers[p];
            m = pl.transform.matrix(pl.local_time(t)) * m;
            cur = pl.parent;
        }
        let inv = m.inverse();
        if !inv.is_finite() {
            return None;
        }
        for c in [(0.0, 0.0), (model.width, 0.0), (0.0, model.height), (model.width, model.height)] {
            let p = inv.transform_point2(glam::Vec2::new(c.0, c.1));
            if p.x < -0.5 || p.y < -0.5 || p.x > width + 0.5 || p.y > height + 0.5 {
                return None;
            }
        }
        if m.matrix2.x_axis.y.abs() > 1e-4 || m.matrix2.y_axis.x.abs() > 1e-4 {
            return None;
        }
    }
    Some(color)
}

/// Frame range (0-based) of composition times `[ip, op)`.
fn frame_range(model: &Model, ip: f32, op: f32) -> std::ops::Range<usize> {
    let n = model.frame_count() as f32;
    let s = (ip - model.ip).ceil().clamp(0.0, n);
    let e = (op - model.ip).ceil().clamp(0.0, n);
    let (s, e) = (s as usize, e as usize);
    if e > s { s..e } else { s..s }
}

/// The renderer behind a loaded Lottie [`Animation`].
struct LottieRenderer {
    model: Arc<Model>,
    targets: Vec<Target>,
    strokes: Vec<bool>,
    width: u32,
    height: u32,
    scale: f32,
}

/// Converts a premultiplied pixmap into straight RGBA in `0..=1` (one sequential pass; at
/// large sizes this conversion, not the rasterization, dominates the cost of a frame).
pub(crate) fn to_plane(pm: &tiny_skia::Pixmap) -> Plane<Rgba> {
    let data = pm
        .pixels()
        .iter()
        .map(|p| {
            let a = p.alpha();
            if a == 0 {
                return [0.0; 4];
            }
            let af = a as f32 / 255.0;
            let inv = 1.0 / (255.0 * af);
            let c = |v: u8| (v as f32 * inv).min(1.0);
            [c(p.red()), c(p.green()), c(p.blue()), af]
        })
        .collect();
    Plane::from_vec(pm.width() as usize, pm.height() as usize, data).unwrap_or_else(|| Plane::new(0, 0))
}

impl LottieRenderer {
    /// Renders a region at composition frame `frame` (0-based) in one pass, at the loaded size.
    fn render_pass(&self, region: usize, frame: usize, pass: Pass) -> tiny_skia::Pixmap {
        render::render(
            &self.model,
            self.targets[region],
            self.model.ip + frame as f32,
            self.width,
            self.height,
            self.scale,
            pass,
        )
    }
}

impl RegionRenderer for LottieRenderer {
    fn render(&self, region: usize, frame: usize) -> Result<RegionFrame> {
        if region >= self.targets.len() {
            return Err(Error::param("region", region, format!("0..{}", self.targets.len())));
        }
        let fill = to_plane(&self.render_pass(region, frame, Pass::Fills));
        // Strokes only when the region strokes something at this frame: most frames of most
        // layers have none, and a full-canvas plane is the dominant cost of a frame.
        let strokes = if self.strokes[region] {
            let pm = self.render_pass(region, frame, Pass::Strokes);
            pm.pixels().iter().any(|p| p.alpha() > 0).then(|| to_plane(&pm))
        } else {
            None
        };
        Ok(RegionFrame { fill, strokes, opacity_in_alpha: true })
    }

    fn fill_motion(&self, region: usize, from: usize, to: usize) -> Option<Plane<Option<glam::Vec2>>> {
        let (t, next) = (self.model.ip + from as f32, self.model.ip + to as f32);
        let target = *self.targets.get(region)?;
        render::fill_motion(&self.model, target, t, next, self.width, self.height, self.scale)
    }
}

/// The dominant color (area-weighted mode over a 5-bit-per-channel histogram) of a region,
/// from a few frames rendered small.
fn dominant_color(model: &Model, target: Target, visible: &std::ops::Range<usize>) -> Option<Rgba> {
    let side = model.width.max(model.height);
    let scale = (96.0 / side).min(1.0);
    let (w, h) = (((model.width * scale).round() as u32).max(1), ((model.height * scale).round() as u32).max(1));
    let mut hist = super::ColorHistogram::default();
    let n = visible.len();
    if n == 0 {
        return None;
    }
    let samples = 5.min(n);
    // Fills decide; a region that only strokes takes its stroke color.
    for pass in [Pass::Fills, Pass::Strokes] {
        for s in 0..samples {
            let f = visible.start + s * n / samples;
            let pm = render::render(model, target, model.ip + f as f32, w, h, scale, pass);
            hist.add(&to_plane(&pm));
        }
        if let Some(c) = hist.dominant() {
            return Some(c);
        }
    }
    None
}

/// Loads a Lottie file.
pub fn load(path: &Path, options: &LoadOptions) -> Result<Animation> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let model = parse(path, &text)?;
    from_model(path, model, options)
}

/// Builds the regions of a parsed model.
pub fn from_model(path: &Path, model: Model, options: &LoadOptions) -> Result<Animation> {
    let (width, height) = super::scaled_canvas(path, model.width, model.height, options.scale)?;
    nesting::check_work(path, &model, width, height)?;
    let frames = model.frame_count();
    let root = &model.comps[0];
    let mut warnings: Vec<String> = model.warnings.clone();
    if root.layers.is_empty() {
        return Err(Error::Empty { path: path.to_path_buf(), what: "the animation has no layers".into() });
    }
    let (background, bg_layers) = background(&model);
    let specs = region_specs(&model, &bg_layers, options.split_precomps, &mut warnings);
    if specs.is_empty() {
        return Err(Error::Empty { path: path.to_path_buf(), what: nothing_to_stylize(&model, &bg_layers) });
    }
    let mut regions = Vec::with_capacity(specs.len());
    let mut targets = Vec::with_capacity(specs.len());
    let mut strokes = Vec::with_capacity(specs.len());
    let mut names: Vec<String> = Vec::new();
    for (n, spec) in specs.into_iter().enumerate() {
        let mut unique = spec.name.clone();
        let mut k = 2;
        while names.contains(&unique) {
            unique = format!("{} ({k})", spec.name);
            k += 1;
        }
        names.push(unique.clone());
        let (w, has) = region_warnings_and_strokes(&model, spec.target);
        let color = dominant_color(&model, spec.target, &spec.visible).unwrap_or([1.0, 1.0, 1.0, 0.0]);
        regions.push(Region {
            index: n + 1,
            name: unique,
            kind: spec.kind,
            visible: spec.visible,
            color,
            has_strokes: has,
            warnings: w,
        });
        targets.push(spec.target);
        strokes.push(has);
    }
    let fps = model.fps as f64;
    let renderer = LottieRenderer { model: Arc::new(model), targets, strokes, width, height, scale: options.scale };
    let mut animation = Animation::new(
        path.to_path_buf(),
        width,
        height,
        fps,
        frames,
        regions,
        background,
        warnings,
        Box::new(renderer),
    );
    // The scale it was built at, as `anim::load` records it (a render reads it from here).
    animation.scale = options.scale;
    Ok(animation)
}

/// The background: the bottom-most run of full-canvas solids (its top-most layer names it),
/// and the root layers it is made of.
fn background(model: &Model) -> (Option<Background>, Vec<usize>) {
    let root = &model.comps[0];
    let mut background = None;
    let mut bg_layers = Vec::new();
    for li in (0..root.layers.len()).rev() {
        let l = &root.layers[li];
        if l.hidden || draws_nothing(l) {
            continue;
        }
        match is_background(model, li) {
            Some(color) => {
                bg_layers.push(li);
                background = Some(Background { name: l.name.clone(), color });
            }
            None => break,
        }
    }
    (background, bg_layers)
}

/// Most layers of a composition [`nothing_to_stylize`] names (the rest are counted).
const MAX_LISTED: usize = 8;

/// The error when no root layer is a region: each layer (the first [`MAX_LISTED`]) with why
/// it is not one, e.g. "layer 1 'title' (text): text layers are not supported".
fn nothing_to_stylize(model: &Model, bg_layers: &[usize]) -> String {
    format!("no layer draws anything that could be stylized: {}", why_no_regions(model, 0, bg_layers))
}

/// Why no layer of composition `c` is a region, layer by layer.
fn why_no_regions(model: &Model, c: usize, bg_layers: &[usize]) -> String {
    let layers = &model.comps[c].layers;
    let mut why: Vec<String> = layers
        .iter()
        .enumerate()
        .take(MAX_LISTED)
        .map(|(li, l)| {
            let kind = match l.ty {
                Some(0) => " (precomp)".to_string(),
                Some(1) => " (solid)".to_string(),
                Some(2) => " (image)".to_string(),
                Some(3) => " (null)".to_string(),
                Some(4) => " (shape)".to_string(),
                Some(5) => " (text)".to_string(),
                Some(t) => format!(" (type {t})"),
                None => String::new(),
            };
            format!("layer {} '{}'{kind}: {}", li + 1, l.name, not_a_region(model, c, li, bg_layers))
        })
        .collect();
    if layers.len() > MAX_LISTED {
        why.push(format!("and {} more layers", layers.len() - MAX_LISTED));
    }
    why.join("; ")
}

/// Why layer `li` of composition `c` is not a region (the reasons [`region_specs`] skips a
/// layer for; a root precomp is only skipped when its layers are regions of their own).
fn not_a_region(model: &Model, c: usize, li: usize, bg_layers: &[usize]) -> String {
    let comp = &model.comps[c];
    let l = &comp.layers[li];
    if c == 0 && bg_layers.contains(&li) {
        return "it is the background (an opaque solid covering the canvas), which is not stylized".into();
    }
    if l.is_matte_source {
        return match comp.layers.iter().position(|m| m.matte.is_some_and(|(_, src)| src == li)) {
            Some(m) => format!("it is the track matte of layer {} '{}', not drawn itself", m + 1, comp.layers[m].name),
            None => "it is a track matte (td), not drawn itself".into(),
        };
    }
    if l.ty == Some(3) {
        return "a null draws nothing (it only moves the layers parented to it)".into();
    }
    if l.hidden {
        return "it is hidden (hd)".into();
    }
    if let Some(why) = &l.nothing {
        return why.clone();
    }
    if matches!(l.transform.opacity, value::Value::Fixed(o) if o.is_nan() || o <= 0.0) {
        return "its opacity is 0 throughout".into();
    }
    match l.content {
        Content::Precomp { comp: inner, .. } if c == 0 => format!(
            "with --split-precomps each layer inside it is a region, and none draws anything ({})",
            why_no_regions(model, inner, &[])
        ),
        _ => "it draws nothing".into(),
    }
}

/// A region before its name is made unique.
struct Spec {
    target: Target,
    name: String,
    kind: RegionKind,
    visible: std::ops::Range<usize>,
}

/// The regions of the root layers, top-most first: every layer that draws something, except
/// the background, matte sources, nulls and hidden layers; with `split`, each drawable layer
/// inside a top-level precomp. Warnings of layers that draw nothing go to `warnings`.
fn region_specs(model: &Model, bg_layers: &[usize], split: bool, warnings: &mut Vec<String>) -> Vec<Spec> {
    let root = &model.comps[0];
    let mut specs = Vec::new();
    for (li, l) in root.layers.iter().enumerate() {
        if bg_layers.contains(&li) || l.is_matte_source || l.ty == Some(3) || l.hidden {
            continue;
        }
        if draws_nothing(l) {
            for w in &l.warnings {
                if !warnings.contains(w) {
                    warnings.push(w.clone());
                }
            }
            continue;
        }
        let visible = frame_range(model, l.ip, l.op);
        match (&l.content, split) {
            (Content::Precomp { comp, .. }, true) => {
                let inner = &model.comps[*comp];
                for (ci, c) in inner.layers.iter().enumerate() {
                    if c.is_matte_source || c.hidden || draws_nothing(c) {
                        continue;
                    }
                    // Child in/out points in outer composition time (no time remap).
                    let vis = if l.time_remap.is_some() {
                        visible.clone()
                    } else {
                        let (a, b) = (c.ip * l.sr + l.st, c.op * l.sr + l.st);
                        let (a, b) = if a <= b { (a, b) } else { (b, a) };
                        let r = frame_range(model, a.max(l.ip), b.min(l.op));
                        if r.is_empty() { r.start..r.start } else { r }
                    };
                    specs.push(Spec {
                        target: Target { layer: li, child: Some(ci) },
                        name: format!("{}/{}", l.name, c.name),
                        kind: RegionKind::PrecompChild,
                        visible: vis,
                    });
                }
            }
            (content, _) => {
                let kind = match content {
                    Content::Precomp { .. } => RegionKind::Precomp,
                    Content::Solid { .. } => RegionKind::Solid,
                    _ => RegionKind::Shape,
                };
                specs.push(Spec { target: Target { layer: li, child: None }, name: l.name.clone(), kind, visible });
            }
        }
    }
    specs
}

/// The warnings of a region's layers, and whether it strokes anything.
fn region_warnings_and_strokes(model: &Model, target: Target) -> (Vec<String>, bool) {
    let root = &model.comps[0];
    let l = &root.layers[target.layer];
    let mut w = Vec::new();
    let has = match (target.child, &l.content) {
        (Some(ci), Content::Precomp { comp, .. }) => {
            let inner = &model.comps[*comp];
            for x in &l.warnings {
                w.push(x.clone());
            }
            collect_warnings(model, inner, ci, &mut w, &mut Vec::new());
            layer_has_strokes(model, inner, ci, &mut HashMap::new())
        }
        _ => {
            collect_warnings(model, root, target.layer, &mut w, &mut Vec::new());
            layer_has_strokes(model, root, target.layer, &mut HashMap::new())
        }
    };
    (w, has)
}
