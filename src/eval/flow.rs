//! Motion: a simple block-matching optical flow, the target's motion derived from its masks,
//! and the agreement of the two near moving boundaries.

use super::{Mean, Measure, Shape};
use crate::img::{Mask, Plane};
use glam::Vec2;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Parameters of [`match_block`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlockMatchParams {
    /// Side of the square block compared (odd). Default: 9.
    pub block: usize,
    /// Search radius: displacements up to this many pixels in x and y are tried. Faster
    /// motion cannot be measured. Default: 6.
    pub radius: usize,
    /// A block is only matched when at least this fraction of its pixels is usable (inside
    /// the image and, when masks are given, inside both masks), and a displacement only when
    /// that many pixels stay inside the image. Default: 0.5.
    pub min_valid: f32,
    /// Blocks whose standard deviation (over their usable pixels) is below this are
    /// textureless: their flow is unknown (`None`). Default: 0.004.
    pub min_texture: f32,
}

impl Default for BlockMatchParams {
    fn default() -> Self {
        BlockMatchParams { block: 9, radius: 6, min_valid: 0.5, min_texture: 0.004 }
    }
}

/// Displacements within the search window, nearest first (ties by row, then column), so that
/// the first strict minimum found is also the smallest such motion: deterministic ties.
fn displacements(radius: usize) -> Vec<(i32, i32)> {
    let r = radius as i32;
    let mut d: Vec<(i32, i32)> = (-r..=r).flat_map(|dy| (-r..=r).map(move |dx| (dx, dy))).collect();
    d.sort_by_key(|&(dx, dy)| (dx * dx + dy * dy, dy, dx));
    d
}

/// Refines an integer minimum with a parabola through it and its two neighbours.
fn parabola(left: f32, mid: f32, right: f32) -> f32 {
    let denom = left - 2.0 * mid + right;
    if left.is_finite() && right.is_finite() && denom > 1e-12 {
        (0.5 * (left - right) / denom).clamp(-0.5, 0.5)
    } else {
        0.0
    }
}

struct Matcher {
    order: Vec<(i32, i32)>,
    params: BlockMatchParams,
}

impl Matcher {
    fn new(params: &BlockMatchParams) -> Self {
        Matcher { order: displacements(params.radius), params: *params }
    }

    fn at(
        &self,
        prev: &Plane<f32>,
        next: &Plane<f32>,
        masks: Option<(&Mask, &Mask)>,
        x: usize,
        y: usize,
    ) -> Option<Vec2> {
        let p = &self.params;
        let (w, h) = prev.size();
        let half = (p.block / 2) as isize;
        let side = (2 * half + 1) as usize;
        let need = ((p.min_valid * (side * side) as f32).ceil() as usize).max(1);
        // The block of `prev` and a weight per pixel: 1 where usable, 0 elsewhere.
        let (x0, y0) = (x as isize - half, y as isize - half);
        let mut values = vec![0f32; side * side];
        let mut weights = vec![0f32; side * side];
        let mut count = 0usize;
        let (mut sum, mut sum2) = (0f64, 0f64);
        for v in 0..side {
            for u in 0..side {
                let (px, py) = (x0 + u as isize, y0 + v as isize);
                if !prev.contains(px, py) {
                    continue;
                }
                let (px, py) = (px as usize, py as usize);
                if masks.is_some_and(|(a, b)| !(a.get(px, py) && b.get(px, py))) {
                    continue;
                }
                let a = prev.get(px, py);
                values[v * side + u] = a;
                weights[v * side + u] = 1.0;
                count += 1;
                sum += a as f64;
                sum2 += (a as f64) * (a as f64);
            }
        }
        if count < need {
            return None;
        }
        let mean = sum / count as f64;
        if (((sum2 / count as f64) - mean * mean).max(0.0).sqrt() as f32) < p.min_texture {
            return None;
        }
        let r = p.radius as i32;
        let span = (2 * r + 1) as usize;
        let mut cost = vec![f32::INFINITY; span * span];
        let (mut best, mut best_d) = (f32::INFINITY, (0i32, 0i32));
        for &(dx, dy) in &self.order {
            let (bx, by) = (x0 + dx as isize, y0 + dy as isize);
            let inside = bx >= 0 && by >= 0 && bx + side as isize <= w as isize && by + side as isize <= h as isize;
            let (total, n) = if inside {
                // The whole shifted block is in the image: plain row slices.
                let mut total = 0f32;
                for v in 0..side {
                    let row = &next.row(by as usize + v)[bx as usize..bx as usize + side];
                    let (a, wt) = (&values[v * side..(v + 1) * side], &weights[v * side..(v + 1) * side]);
                    total += row.iter().zip(a).zip(wt).map(|((b, a), wt)| wt * (a - b).abs()).sum::<f32>();
                }
                (total, count)
            } else {
                let (mut total, mut n) = (0f32, 0usize);
                for v in 0..side {
                    for u in 0..side {
                        let (qx, qy) = (bx + u as isize, by + v as isize);
                        if weights[v * side + u] == 0.0 || !next.contains(qx, qy) {
                            continue;
                        }
                        total += (values[v * side + u] - next.get(qx as usize, qy as usize)).abs();
                        n += 1;
                    }
                }
                (total, n)
            };
            if n >= need {
                let c = total / n as f32;
                cost[(dy + r) as usize * span + (dx + r) as usize] = c;
                if c < best {
                    best = c;
                    best_d = (dx, dy);
                }
            }
        }
        if !best.is_finite() {
            return None;
        }
        let (bx, by) = best_d;
        let c = |dx: i32, dy: i32| {
            if dx.abs() > r || dy.abs() > r {
                f32::INFINITY
            } else {
                cost[(dy + r) as usize * span + (dx + r) as usize]
            }
        };
        let fx = parabola(c(bx - 1, by), best, c(bx + 1, by));
        let fy = parabola(c(bx, by - 1), best, c(bx, by + 1));
        Some(Vec2::new(bx as f32 + fx, by as f32 + fy))
    }
}

/// Block-matching optical flow at one pixel: the displacement `d` (pixels, within
/// `±params.radius`) minimizing the mean absolute difference (SAD / count) between the
/// `block × block` block of `prev` centered at `(x, y)` and the same block of `next` shifted
/// by `d`, refined to sub-pixel precision by a parabola through the neighbouring costs in x
/// and in y. With `masks = Some((prev_mask, next_mask))` only the block pixels inside both
/// masks (paint present in both frames) are compared — each with `next` at its displaced
/// position, wherever that is — so the moving edge of the mask does not drag the estimate
/// along: a flat fill has no usable texture, and paint glued to the paper inside a moving mask
/// matches at zero displacement. Displacing paint out of `next`'s mask compares it with
/// whatever lies there (paper) and is penalized, as paint cannot be outside the mask. `None`
/// for a textureless block or one with too few usable pixels. Exhaustive and deterministic
/// (ties go to the smaller displacement).
pub fn match_block(
    prev: &Plane<f32>,
    next: &Plane<f32>,
    masks: Option<(&Mask, &Mask)>,
    x: usize,
    y: usize,
    params: &BlockMatchParams,
) -> Option<Vec2> {
    Matcher::new(params).at(prev, next, masks, x, y)
}

/// Dense block-matching flow from `prev` to `next` (gray planes of the same size): at every
/// pixel, [`match_block`] without masks. Costs `block² · (2·radius + 1)²` operations per
/// pixel: meant for small images and tests; [`motion_agreement`] samples points instead.
pub fn block_matching_flow(prev: &Plane<f32>, next: &Plane<f32>, params: &BlockMatchParams) -> Plane<Option<Vec2>> {
    let (w, h) = prev.size();
    let matcher = Matcher::new(params);
    let rows: Vec<Vec<Option<Vec2>>> =
        (0..h).into_par_iter().map(|y| (0..w).map(|x| matcher.at(prev, next, None, x, y)).collect()).collect();
    Plane::from_vec(w, h, rows.concat()).unwrap_or_else(|| Plane::filled(w, h, None))
}

/// The target's own motion at `(x, y)` between two frames, from its masks alone: the unit
/// normal of the level sets of the mean signed distance `s̄ = (sdf_prev + sdf_next) / 2`
/// (central differences), pointing **outward** (`−∇s̄ / |∇s̄|`, as the distance is positive
/// inside) when the distance grows (`Δsdf = sdf_next − sdf_prev > 0`, the mask advances) and
/// inward when it shrinks, scaled by `|Δsdf|` (pixels per frame): `m = −Δsdf · ∇s̄ / |∇s̄|`.
/// A translating shape gets the translation direction on its leading and trailing edges.
/// `None` where the gradient vanishes (`|∇s̄| < 0.5`, e.g. on the medial axis).
pub fn target_motion(prev: &Shape, next: &Shape, x: usize, y: usize) -> Option<Vec2> {
    let s = |x: isize, y: isize| 0.5 * (prev.sdf.get_clamped(x, y) + next.sdf.get_clamped(x, y));
    let (xi, yi) = (x as isize, y as isize);
    let (w, h) = prev.size();
    let span = |i: isize, n: usize| ((i + 1).min(n as isize - 1) - (i - 1).max(0)).max(1) as f32;
    let g = Vec2::new((s(xi + 1, yi) - s(xi - 1, yi)) / span(xi, w), (s(xi, yi + 1) - s(xi, yi - 1)) / span(yi, h));
    let len = g.length();
    if len < 0.5 {
        return None;
    }
    let change = next.sdf.get(x, y) - prev.sdf.get(x, y);
    Some(-change * g / len)
}

/// [`target_motion`] at every pixel (zero where it is undefined).
pub fn target_motion_field(prev: &Shape, next: &Shape) -> Plane<Vec2> {
    let (w, h) = prev.size();
    Plane::from_fn(w, h, |x, y| target_motion(prev, next, x, y).unwrap_or(Vec2::ZERO))
}

/// Where and how [`motion_agreement`] measures.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MotionParams {
    /// Points lie inside the previous frame's mask, at most this far from its boundary
    /// (`0 < sdf_prev <= band`, pixels). Default: 12.
    pub band: f32,
    /// … where the target moves at least this fast (`|Δsdf|`, px/frame). Default: 0.25.
    pub min_speed: f32,
    /// Measured flows shorter than this (px/frame) are "no motion" and score cosine 0.
    /// Default: 0.25.
    pub min_flow: f32,
    /// Points are taken on a grid of this step (pixels). Default: 3.
    pub stride: usize,
    /// Only pixels at least this far inside both masks (`sdf >= edge_margin`) are compared,
    /// so that the antialiased edge of a moving mask is not taken for texture. Default: 1.5.
    pub edge_margin: f32,
    /// The block matcher. Default: [`BlockMatchParams::default`].
    pub block: BlockMatchParams,
}

impl Default for MotionParams {
    fn default() -> Self {
        MotionParams {
            band: 12.0,
            min_speed: 0.25,
            min_flow: 0.25,
            stride: 3,
            edge_margin: 1.5,
            block: BlockMatchParams::default(),
        }
    }
}

/// Agreement of the paint's motion with the target's motion near moving boundaries.
///
/// For each pair of consecutive frames `(i − 1, i)` (reported at frame `i`) and each point
/// `q` on the `stride` grid with `0 < sdf_{i−1}(q) <= band` and a [`target_motion`] `m(q)`
/// of at least `min_speed`: the masked block-matching flow `f(q)` of the gray `frames`
/// ([`match_block`] with both masks eroded by `edge_margin`, so only the paint inside moves
/// it, not the mask's edge) is compared with
/// `m(q)` by their cosine `f·m / (|f| |m|)`; a flow shorter than `min_flow` (paint not
/// moving) scores 0; textureless points (no flow) are skipped. Per frame and pooled over all
/// points: the mean cosine — +1 when the paint flows with the target's motion, −1 against
/// it, ≈ 0 when it stands still or moves at random. `samples` counts the points.
///
/// Masks only reveal the *normal* component of the target's motion, so `m` is normal to the
/// boundary: on edges perpendicular to the motion a perfect flow scores 1, but on a
/// translating disc it scores the mean of `|cos φ|` between the translation and the normals,
/// about 0.7. Compare values of similar shapes, or with the exemplar's own.
pub fn motion_agreement(frames: &[Plane<f32>], shapes: &[Shape], params: &MotionParams) -> Measure {
    motion_agreement_with(frames, shapes, params, &|i, x, y| target_motion(&shapes[i - 1], &shapes[i], x, y))
}

/// [`motion_agreement`] against a known motion of the target instead of the one its masks
/// reveal: `motion(i, x, y)` is the motion at `(x, y)` from frame `i − 1` to frame `i`
/// (pixels per frame; `None` where it is unknown). Masks only show the normal part of a
/// motion, so on a translating ellipse even paint that moves exactly with it scores well
/// below 1 against them; a generated target whose motion is known can be measured against
/// the whole of it, where a perfect carry scores ≈ 1. Points, block matcher and scoring as
/// in [`motion_agreement`].
pub fn motion_agreement_with(
    frames: &[Plane<f32>],
    shapes: &[Shape],
    params: &MotionParams,
    motion: &(dyn Fn(usize, usize, usize) -> Option<Vec2> + Sync),
) -> Measure {
    let n = frames.len().min(shapes.len());
    let means: Vec<Mean> = (0..n)
        .into_par_iter()
        .map(|i| {
            if i == 0 {
                return Mean::default();
            }
            motion_pair_mean_with((&frames[i - 1], &shapes[i - 1]), (&frames[i], &shapes[i]), params, &|x, y| {
                motion(i, x, y)
            })
        })
        .collect();
    Measure::from_means(&means)
}

/// The cosines of [`motion_agreement`] for one pair of frames `(prev, next)` (gray plane and
/// shape each), summed in point order: the same result whatever the thread count.
pub(crate) fn motion_pair_mean(
    prev: (&Plane<f32>, &Shape),
    next: (&Plane<f32>, &Shape),
    params: &MotionParams,
) -> Mean {
    motion_pair_mean_with(prev, next, params, &|x, y| target_motion(prev.1, next.1, x, y))
}

/// [`motion_pair_mean`] against the target motion `motion(x, y)`.
pub(crate) fn motion_pair_mean_with(
    prev: (&Plane<f32>, &Shape),
    next: (&Plane<f32>, &Shape),
    params: &MotionParams,
    motion: &(dyn Fn(usize, usize) -> Option<Vec2> + Sync),
) -> Mean {
    let matcher = Matcher::new(&params.block);
    let stride = params.stride.max(1);
    let (sa, sb) = (prev.1, next.1);
    let (w, h) = sa.size();
    let (ma, mb) = (sa.interior(params.edge_margin), sb.interior(params.edge_margin));
    let mut points = Vec::new();
    for y in (0..h).step_by(stride) {
        for x in (0..w).step_by(stride) {
            let d = sa.sdf.get(x, y);
            if d <= 0.0 || d > params.band {
                continue;
            }
            match motion(x, y) {
                Some(m) if m.length() >= params.min_speed => points.push((x, y, m)),
                _ => {}
            }
        }
    }
    let cosines: Vec<Option<f64>> = points
        .par_iter()
        .map(|&(x, y, m)| {
            let f = matcher.at(prev.0, next.0, Some((&ma, &mb)), x, y)?;
            let fl = f.length();
            Some(if fl < params.min_flow { 0.0 } else { (f.dot(m) / (fl * m.length())) as f64 })
        })
        .collect();
    let mut mean = Mean::default();
    cosines.into_iter().flatten().for_each(|c| mean.add(c));
    mean
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parabola_finds_the_vertex() {
        // f(t) = (t − 0.3)²: samples at −1, 0, 1.
        let f = |t: f32| (t - 0.3) * (t - 0.3);
        assert!((parabola(f(-1.0), f(0.0), f(1.0)) - 0.3).abs() < 1e-5);
        assert_eq!(parabola(f32::INFINITY, 0.0, 1.0), 0.0);
    }

    #[test]
    fn displacement_order_is_nearest_first() {
        let d = displacements(2);
        assert_eq!(d.len(), 25);
        assert_eq!(d[0], (0, 0));
        assert_eq!(d[1], (0, -1));
        assert_eq!(*d.last().unwrap(), (2, 2));
    }
}
