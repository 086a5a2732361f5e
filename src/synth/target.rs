//! The target frame T_j at one pyramid level, laid out like the exemplar (8-lane padded
//! pixels) for the patch error: the current estimate `T^rgb`, the temporal guide `T^prev`,
//! the guide channels, and per-pixel info.

use super::params::HALF;
use super::source::{
    IN_MASK, INTERIOR, LANES, PixInfo, Quant, RESTING, VALID, dilate, extent_falloff, flow_dir, outward_unit,
};
use crate::guide::FrameGuides;
use crate::img::Rgb;
use glam::Vec2;
use rayon::prelude::*;

/// Padding of the target arrays: ⌊n/2⌋, so every window of a pixel in the frame is inside.
pub(crate) const TPAD: usize = HALF;

/// One level of one target frame.
pub(crate) struct TargetLevel {
    pub w: usize,
    /// Row stride of the padded arrays.
    pub stride: usize,
    /// `[T^rgb, T^df, T^ext+, T^ext−, 0, 0]` in the source's quantization units, padded.
    pub cur: Vec<[f32; LANES]>,
    /// `[T^prev, 0…]` in quantization units, padded.
    pub prev: Vec<[f32; LANES]>,
    /// Per-pixel info, unpadded (`VALID` = active: inside the mask dilated by ⌊n/2⌋).
    pub info: Vec<PixInfo>,
    /// `m(q) · w_prev` per pixel, unpadded.
    pub mw: Vec<f32>,
    /// Active pixels (unpadded indices), row-major.
    pub active: Vec<u32>,
    /// |T_seg|: mask pixels per segment (0 = border, 1 = interior).
    pub seg_count: [usize; 2],
    /// A still's rotation M per pixel (cos, sin): that of the carried match, where the field
    /// was carried; empty = θ = 0 wherever the exemplar has no flow direction.
    pub spin: Vec<(f32, f32)>,
}

/// The direction of target pixel (x, y) for the direction rule, and whether it is the resting
/// normal ([`resting_normal`], with `resting_normal` set) rather than its flow's.
fn direction(g: &FrameGuides, x: usize, y: usize, resting_normal: bool) -> (Vec2, bool) {
    match if resting_normal { self::resting_normal(g, x, y) } else { None } {
        Some(normal) => (normal, true),
        None => (flow_dir(g.flow.get(x, y)), false),
    }
}

/// The outward normal of target pixel (x, y) where it rests, its direction for the direction
/// rule with [`ParamsBuilder::resting_normal`](super::ParamsBuilder::resting_normal) (a
/// moving pixel's is its flow's): inside the mask where it moves less than
/// [`super::source::FLOW_EPS`]; outside it (the ring of patch centres around it, where the
/// flow is zero by convention) where the mask pixel it faces, one pixel inside along the
/// normal, does not move either. `None` where the pixel or the one it faces moves (the ring of
/// a moving shape keeps θ = 0, as without the rule), and on a ridge of the distance field.
pub(crate) fn resting_normal(g: &FrameGuides, x: usize, y: usize) -> Option<Vec2> {
    if flow_dir(g.flow.get(x, y)) != Vec2::ZERO {
        return None;
    }
    let (normal, grad) = outward_normal(&g.dist, x, y)?;
    let d = g.dist.get(x, y);
    if d >= 0.0 {
        return Some(normal);
    }
    // The distances of a coarser pyramid level keep the finest level's units: `grad` pixels of
    // distance per pixel of the level.
    let (w, h) = g.dist.size();
    let inside = Vec2::new(x as f32, y as f32) - normal * (1.0 - d / grad);
    let (xi, yi) =
        (inside.x.round().clamp(0.0, (w - 1) as f32) as usize, inside.y.round().clamp(0.0, (h - 1) as f32) as usize);
    (g.flow.get(xi, yi) == Vec2::ZERO).then_some(normal)
}

/// The outward unit normal of the shape at (x, y) and the gradient's length
/// ([`outward_unit`]), ∇dist by central differences (one-sided at the frame's edge).
fn outward_normal(dist: &crate::img::Plane<f32>, x: usize, y: usize) -> Option<(Vec2, f32)> {
    let (w, h) = dist.size();
    let (x0, x1, y0, y1) = (x.saturating_sub(1), (x + 1).min(w - 1), y.saturating_sub(1), (y + 1).min(h - 1));
    let gx = (dist.get(x1, y) - dist.get(x0, y)) / (x1 - x0).max(1) as f32;
    let gy = (dist.get(x, y1) - dist.get(x, y0)) / (y1 - y0).max(1) as f32;
    outward_unit(Vec2::new(gx, gy))
}

impl TargetLevel {
    /// Builds the level from its guides. `ext_cap` clamps the extents (None = no clamp);
    /// `falloff` fades them out in the interior as the source level does
    /// ([`super::source::extent_falloff`]).
    pub fn new(
        g: &FrameGuides,
        quant: &Quant,
        border_width: f32,
        ext_cap: Option<f32>,
        falloff: bool,
        fill: Rgb,
        resting_normal: bool,
    ) -> TargetLevel {
        let (w, h) = g.mask.size();
        let stride = w + 2 * TPAD;
        let cap = ext_cap.unwrap_or(f32::INFINITY);
        let roi = dilate(&g.mask, HALF);
        let mut cur = vec![[0.0f32; LANES]; stride * (h + 2 * TPAD)];
        cur.par_chunks_mut(stride).enumerate().for_each(|(py, row)| {
            let y = (py as isize - TPAD as isize).clamp(0, h as isize - 1) as usize;
            for (px, out) in row.iter_mut().enumerate() {
                let x = (px as isize - TPAD as isize).clamp(0, w as isize - 1) as usize;
                let dist = g.dist.get(x, y);
                let df = (dist / border_width).min(1.0);
                let fade = extent_falloff(falloff, dist / border_width);
                let ep = g.ext_pos.get(x, y).min(cap) * fade;
                let en = g.ext_neg.get(x, y).min(cap) * fade;
                let v = [fill[0], fill[1], fill[2], df, ep, en, 0.0, 0.0];
                // Guide lanes on the source's 8-bit grid (identical guides compare exactly equal).
                *out = std::array::from_fn(|k| {
                    if k < 3 {
                        quant.units(k, v[k])
                    } else if k < 6 {
                        quant.quantize(k, v[k]) as f32
                    } else {
                        0.0
                    }
                });
            }
        });
        let mut info = vec![PixInfo::default(); w * h];
        info.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, out) in row.iter_mut().enumerate() {
                let dist = g.dist.get(x, y);
                let interior = dist >= border_width;
                let mut flags = 0;
                if interior {
                    flags |= INTERIOR;
                }
                if g.mask.get(x, y) {
                    flags |= IN_MASK;
                }
                if roi.get(x, y) {
                    flags |= VALID;
                }
                let (dir, rests) = direction(g, x, y, resting_normal);
                if rests {
                    flags |= RESTING;
                }
                *out = PixInfo {
                    dir,
                    dist,
                    ext_pos: g.ext_pos.get(x, y),
                    ext_neg: g.ext_neg.get(x, y),
                    flags,
                    speed: 0.0,
                };
            }
        });
        let mut active = Vec::new();
        let mut seg_count = [0usize; 2];
        for (q, p) in info.iter().enumerate() {
            if p.flags & IN_MASK != 0 {
                seg_count[(p.flags & INTERIOR != 0) as usize] += 1;
            }
            if p.flags & VALID != 0 {
                active.push(q as u32);
            }
        }
        let prev = vec![[0.0f32; LANES]; cur.len()];
        TargetLevel { w, stride, cur, prev, info, mw: vec![0.0; w * h], active, seg_count, spin: Vec::new() }
    }

    /// Padded index of pixel (x, y).
    #[inline]
    pub fn pindex(&self, x: usize, y: usize) -> usize {
        (y + TPAD) * self.stride + x + TPAD
    }

    /// Segment of pixel `idx` (unpadded): 0 = border, 1 = interior.
    #[inline]
    pub fn segment(&self, idx: usize) -> usize {
        (self.info[idx].flags & INTERIOR != 0) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::img::Plane;

    /// A disc of radius 10 centred at (20, 20) in a 40 × 40 frame, with `flow` inside it.
    fn disc(flow: Vec2) -> FrameGuides {
        let c = Vec2::new(20.0, 20.0);
        let dist = Plane::from_fn(40, 40, |x, y| 10.0 - (Vec2::new(x as f32, y as f32) - c).length());
        let mask = dist.map(|d| d >= 0.0);
        let flow = Plane::from_fn(40, 40, |x, y| if mask.get(x, y) { flow } else { Vec2::ZERO });
        let zero = Plane::filled(40, 40, 0.0f32);
        FrameGuides { mask, dist, flow, ext_pos: zero.clone(), ext_neg: zero }
    }

    /// Where the shape rests its direction is the outward normal, inside and in the ring just
    /// outside; where it moves, the flow's, and the ring has none (as without the rule); the
    /// middle (a ridge of the distance field) has none; without the rule a resting shape has
    /// none anywhere.
    #[test]
    fn the_direction_is_the_flow_or_where_the_shape_rests_its_normal() {
        let close = |a: Vec2, b: Vec2| (a - b).length() < 0.05;
        let rest = disc(Vec2::ZERO);
        assert!(close(direction(&rest, 26, 20, true).0, Vec2::X), "inside, right of the middle");
        assert!(close(direction(&rest, 20, 13, true).0, -Vec2::Y), "inside, above the middle");
        assert!(close(direction(&rest, 20, 31, true).0, Vec2::Y), "outside, below");
        assert_eq!(direction(&rest, 20, 20, true).0, Vec2::ZERO, "the middle");
        assert_eq!(direction(&rest, 26, 20, false).0, Vec2::ZERO, "without the rule");
        let moving = disc(Vec2::new(0.0, 2.0));
        assert!(close(direction(&moving, 26, 20, true).0, Vec2::Y), "inside: the flow");
        assert_eq!(direction(&moving, 31, 20, true).0, Vec2::ZERO, "the ring of a moving shape");
        assert_eq!(direction(&moving, 31, 20, false).0, Vec2::ZERO, "the ring without the rule");
    }
}
