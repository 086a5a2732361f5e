//! The target frame T_j at one pyramid level, laid out like the exemplar (8-lane padded
//! pixels) for the patch error: the current estimate `T^rgb`, the temporal guide `T^prev`,
//! the guide channels, and per-pixel info.

use super::params::HALF;
use super::source::{IN_MASK, INTERIOR, LANES, PixInfo, Quant, VALID, dilate, extent_falloff, flow_dir};
use crate::guide::FrameGuides;
use crate::img::Rgb;
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
                *out = PixInfo {
                    dir: flow_dir(g.flow.get(x, y)),
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
