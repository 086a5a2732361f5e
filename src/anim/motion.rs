//! The true motion of a region's fills from one frame to another, from the shapes themselves:
//! each fill is a path drawn under a transform to the canvas, and the same fill at two frames
//! tells where its points go ([`fills_motion`]). Shared by the Lottie reader (whose fills are
//! drawn under chains of keyed transforms) and SVG sequences (whose frames draw the same
//! elements again, moved by their transforms or by their coordinates).

use super::lottie::{drawable, to_ts};
use crate::img::Plane;
use glam::{Affine2, Vec2};
use tiny_skia::{FillRule, Mask};

/// One fill as the rasterizer draws it: its path in its own coordinates, the transform to the
/// canvas and its fill rule.
pub(crate) struct Fill {
    pub path: tiny_skia::Path,
    pub m: Affine2,
    pub rule: FillRule,
}

/// The motion of the fills `from` (at one frame, bottom-most first) to the same fills `to` (at
/// another), per pixel of a `width × height` canvas (pixels; `None` where no fill is). Where
/// fills overlap, the top-most one's motion is given. Each fill moves by its [`PointMap`]: the
/// step of its transforms while it keeps its shape in its own coordinates, else its outline's
/// own motion point by point while the outline keeps its structure (verbs and point count).
/// `None` when an outline changes its structure, when the two frames do not draw the same
/// number of fills, or when there is none. A fill with a singular transform, or one the
/// renderer would not draw (reaching farther than tiny-skia can, see [`drawable`]), is skipped.
pub(crate) fn fills_motion(from: &[Fill], to: &[Fill], width: u32, height: u32) -> Option<Plane<Option<Vec2>>> {
    if from.is_empty() || from.len() != to.len() {
        return None;
    }
    // Each fill's transform to draw it with, where it is drawn.
    let drawn = |a: &Fill| {
        let det = a.m.matrix2.determinant();
        to_ts(&a.m).filter(|&ts| det.is_finite() && det.abs() >= 1e-12 && drawable(&a.path, ts, 0.0))
    };
    let maps: Vec<Option<(tiny_skia::Transform, PointMap)>> = from
        .iter()
        .zip(to)
        .map(|(a, b)| match drawn(a) {
            None => Ok(None),
            Some(ts) => PointMap::new(a, b).map(|m| Some((ts, m))).ok_or(()),
        })
        .collect::<Result<_, ()>>()
        .ok()?;
    let (w, h) = (width.max(1) as usize, height.max(1) as usize);
    let mut out = Plane::new(w, h);
    let mut cover = Mask::new(w as u32, h as u32)?;
    // Bottom-most first: a fill drawn later covers the ones before it.
    for (a, map) in from.iter().zip(&maps) {
        let Some((ts, map)) = map else { continue };
        let ts = *ts;
        cover.clear();
        cover.fill_path(&a.path, a.rule, false, ts);
        for (k, &c) in cover.data().iter().enumerate() {
            if c > 127 {
                let p = Vec2::new((k % w) as f32 + 0.5, (k / w) as f32 + 0.5);
                let v = map.apply(p) - p;
                if v.is_finite() {
                    out.data_mut()[k] = Some(v);
                }
            }
        }
    }
    Some(out)
}

/// Where a fill's points go from one time to another, on the canvas.
enum PointMap {
    /// The fill keeps its shape: the step of its transforms, `M′·M⁻¹`.
    Rigid(Affine2),
    /// Its outline changes but keeps its vertices (path keyframes interpolate vertex by
    /// vertex; an ellipse's or a rectangle's size moves the same points): the affine map
    /// that best carries the outline's samples to theirs (least squares), plus what is left of
    /// each sample's motion, spread inside by inverse squared distance.
    Deformed { affine: Affine2, samples: Vec<(Vec2, Vec2)> },
}

/// Samples per outline segment of [`PointMap::Deformed`].
const OUTLINE_SAMPLES: usize = 8;

/// Most outline samples whose remaining motion is spread inside ([`PointMap::Deformed`]).
const SPREAD_SAMPLES: usize = 64;

impl PointMap {
    /// The map of fill `a` to fill `b` (the same fill at two times; `a`'s transform
    /// invertible); `None` when they do not share their outline's structure (verbs and point
    /// count).
    fn new(a: &Fill, b: &Fill) -> Option<PointMap> {
        if a.path.verbs() != b.path.verbs() || a.path.points().len() != b.path.points().len() {
            return None;
        }
        // The same shape: the same points within 1e-3 units.
        let (pa, pb) = (a.path.points(), b.path.points());
        if pa.iter().zip(pb).all(|(p, q)| (p.x - q.x).abs() <= 1e-3 && (p.y - q.y).abs() <= 1e-3) {
            return Some(PointMap::Rigid(b.m * a.m.inverse()));
        }
        let pairs = outline_samples(&a.path, &b.path)
            .into_iter()
            .map(|(p, q)| (a.m.transform_point2(p), b.m.transform_point2(q)))
            .collect::<Vec<_>>();
        let affine = fit_affine(&pairs)?;
        // The remaining motion is smooth along the outline; spreading it from at most
        // SPREAD_SAMPLES samples bounds the work per pixel whatever the outline's length.
        let stride = pairs.len().div_ceil(SPREAD_SAMPLES).max(1);
        let samples = pairs.iter().step_by(stride).map(|&(p, q)| (p, q - affine.transform_point2(p))).collect();
        Some(PointMap::Deformed { affine, samples })
    }

    /// Where canvas point `p` goes.
    fn apply(&self, p: Vec2) -> Vec2 {
        match self {
            PointMap::Rigid(m) => m.transform_point2(p),
            PointMap::Deformed { affine, samples } => {
                let (mut sum, mut wsum) = (Vec2::ZERO, 0.0f32);
                for &(s, r) in samples {
                    let w = 1.0 / (s.distance_squared(p) + 1.0);
                    sum += r * w;
                    wsum += w;
                }
                affine.transform_point2(p) + if wsum > 0.0 { sum / wsum } else { Vec2::ZERO }
            }
        }
    }
}

/// Corresponding points of two outlines of the same structure, in their own coordinates:
/// [`OUTLINE_SAMPLES`] per segment, evenly in the curve parameter.
fn outline_samples(a: &tiny_skia::Path, b: &tiny_skia::Path) -> Vec<(Vec2, Vec2)> {
    use tiny_skia::PathSegment as S;
    let v = |p: tiny_skia::Point| Vec2::new(p.x, p.y);
    let mut out = Vec::new();
    let (mut last_a, mut last_b) = (Vec2::ZERO, Vec2::ZERO);
    for (sa, sb) in a.segments().zip(b.segments()) {
        let curve: Option<(Vec<Vec2>, Vec<Vec2>)> = match (sa, sb) {
            (S::MoveTo(p), S::MoveTo(q)) => {
                (last_a, last_b) = (v(p), v(q));
                out.push((last_a, last_b));
                None
            }
            (S::LineTo(p), S::LineTo(q)) => Some((vec![last_a, v(p)], vec![last_b, v(q)])),
            (S::QuadTo(p1, p), S::QuadTo(q1, q)) => Some((vec![last_a, v(p1), v(p)], vec![last_b, v(q1), v(q)])),
            (S::CubicTo(p1, p2, p), S::CubicTo(q1, q2, q)) => {
                Some((vec![last_a, v(p1), v(p2), v(p)], vec![last_b, v(q1), v(q2), v(q)]))
            }
            _ => None,
        };
        if let Some((ca, cb)) = curve {
            for k in 1..=OUTLINE_SAMPLES {
                let t = k as f32 / OUTLINE_SAMPLES as f32;
                out.push((bezier(&ca, t), bezier(&cb, t)));
            }
            (last_a, last_b) = (ca[ca.len() - 1], cb[cb.len() - 1]);
        }
    }
    out
}

/// The Bézier curve of control points `c` at parameter `t` (de Casteljau).
fn bezier(c: &[Vec2], t: f32) -> Vec2 {
    let mut c = c.to_vec();
    while c.len() > 1 {
        c = c.windows(2).map(|w| w[0].lerp(w[1], t)).collect();
    }
    c[0]
}

/// The affine map that carries the points `p` of `pairs` closest to their `q` (least
/// squares); the mean translation when the points do not span the plane.
fn fit_affine(pairs: &[(Vec2, Vec2)]) -> Option<Affine2> {
    let n = pairs.len() as f64;
    if n == 0.0 {
        return None;
    }
    let mean = |f: &dyn Fn(&(Vec2, Vec2)) -> Vec2| {
        let s = pairs.iter().fold(glam::DVec2::ZERO, |s, x| s + f(x).as_dvec2());
        s / n
    };
    let (mp, mq) = (mean(&|x| x.0), mean(&|x| x.1));
    // Centered normal equations: C = Σ p̃ p̃ᵀ, D = Σ q̃ p̃ᵀ, A = D C⁻¹.
    let (mut c, mut d) = (glam::DMat2::ZERO, glam::DMat2::ZERO);
    for &(p, q) in pairs {
        let (p, q) = (p.as_dvec2() - mp, q.as_dvec2() - mq);
        c += glam::DMat2::from_cols(p * p.x, p * p.y);
        d += glam::DMat2::from_cols(q * p.x, q * p.y);
    }
    let scale = c.x_axis.x + c.y_axis.y;
    let linear = if scale > 0.0 && c.determinant().abs() > 1e-9 * scale * scale {
        d * c.inverse()
    } else {
        glam::DMat2::IDENTITY
    };
    let t = mq - linear * mp;
    let m = Affine2::from_mat2_translation(linear.as_mat2(), t.as_vec2());
    m.is_finite().then_some(m)
}
