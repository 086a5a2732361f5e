//! The 3D occurrence map Ω* (paper §3.5, thesis §3.3): how many rotated n × n × (2r+1) boxes
//! of the current field cover each exemplar voxel (i, x, y), and the uniformity penalty
//! `Ω(p′) = Ω*(p′)/(n²·ω*)` with `ω* = n²(2r+1)·|T_seg|/|S_seg|` per segment.
//!
//! Boxes are accumulated with +1/−1 markers along time and one prefix sum, so each target
//! pixel costs n² updates whatever r is. Counting uses atomic integer adds, whose result does
//! not depend on the order (deterministic for any thread count).

use super::nnf::{Nnf, offsets};
use super::params::PATCH;
use super::source::{IN_MASK, INTERIOR, PAD, SourceLevel, floor_i32};
use super::target::TargetLevel;
use rayon::prelude::*;
use std::sync::atomic::{AtomicI32, Ordering};

/// Raw counts Ω*(i, x, y) in the padded source layout.
pub(crate) fn counts(src: &SourceLevel, nnf: &Nnf, tgt: &TargetLevel, r: usize) -> Vec<i32> {
    let len = src.feat.len();
    let delta: Vec<AtomicI32> = (0..len).map(|_| AtomicI32::new(0)).collect();
    let frames = src.frames;
    tgt.active.par_iter().for_each(|&q| {
        let q = q as usize;
        if tgt.info[q].flags & IN_MASK == 0 {
            return;
        }
        let m = &nnf.data[q];
        if !m.ok {
            return;
        }
        let i = m.i as usize;
        let lo = i.saturating_sub(r);
        let hi = (i + r + 1).min(frames);
        for (a, b) in offsets() {
            let (dx, dy) = m.rotate(a as f32, b as f32);
            let px = floor_i32(m.x + dx + PAD as f32 + 0.5);
            let py = floor_i32(m.y + dy + PAD as f32 + 0.5);
            if px < 0 || py < 0 || px >= src.stride as i32 || py >= (src.frame_len / src.stride) as i32 {
                continue;
            }
            let pix = py as usize * src.stride + px as usize;
            delta[lo * src.frame_len + pix].fetch_add(1, Ordering::Relaxed);
            if hi < frames {
                delta[hi * src.frame_len + pix].fetch_sub(1, Ordering::Relaxed);
            }
        }
    });
    let mut out: Vec<i32> = delta.into_iter().map(|a| a.into_inner()).collect();
    // Prefix sum along time, per pixel.
    let fl = src.frame_len;
    for i in 1..frames {
        let (done, rest) = out.split_at_mut(i * fl);
        let prev = &done[(i - 1) * fl..];
        for (o, p) in rest[..fl].iter_mut().zip(prev) {
            *o += *p;
        }
    }
    out
}

/// The penalty `λ·Ω*(p′)/(n²·ω*_seg)` per source voxel (padded layout), where the segment is
/// the voxel's own (matches never cross segments).
pub(crate) fn penalty(src: &SourceLevel, nnf: &Nnf, tgt: &TargetLevel, r: usize, lambda: f32) -> Vec<f32> {
    if lambda == 0.0 {
        return vec![0.0; src.feat.len()];
    }
    let counts = counts(src, nnf, tgt, r);
    let n2 = (PATCH * PATCH) as f32;
    let scale: [f32; 2] = std::array::from_fn(|seg| {
        let t = tgt.seg_count[seg] as f32;
        let s = src.seg_count[seg] as f32;
        if t > 0.0 && s > 0.0 {
            // Ω*/(n²ω*) with ω* = n²(2r+1)|T|/|S|
            lambda * s / (n2 * n2 * (2 * r + 1) as f32 * t)
        } else {
            0.0
        }
    });
    counts
        .par_iter()
        .zip(src.info.par_iter())
        .map(|(&c, info)| if c == 0 { 0.0 } else { c as f32 * scale[(info.flags & INTERIOR != 0) as usize] })
        .collect()
}
