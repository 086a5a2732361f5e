//! The 3D occurrence map Ω* (paper §3.5, thesis §3.3): how many rotated n × n × (2r+1) boxes
//! of the current field cover each exemplar voxel (i, x, y), and the uniformity penalty
//! `Ω(p′) = Ω*(p′)/(n²·ω*)` with `ω* = n²(2r+1)·|T_seg|/|S_seg|` per segment.
//!
//! Boxes are accumulated with +1/−1 markers along time and one prefix sum, so each target
//! pixel costs n² updates whatever r is. Each thread counts a part of the target into its own
//! array and the arrays are added: integer sums do not depend on the order (deterministic for
//! any thread count).

use super::nnf::{Nnf, offsets};
use super::params::PATCH;
use super::source::{FLAG_LANE, Feat, IN_MASK, INTERIOR, OMEGA_LANE, PAD, SourceLevel, floor_i32};
use super::target::TargetLevel;
use rayon::prelude::*;

/// Raw counts Ω*(i, x, y) in the padded source layout.
pub(crate) fn counts(src: &SourceLevel, nnf: &Nnf, tgt: &TargetLevel, r: usize) -> Vec<i32> {
    let len = src.feat.len();
    let frames = src.frames;
    let rows = (src.frame_len / src.stride) as i32;
    // One plain (non-atomic) array of +1/−1 markers per part of the target, summed after:
    // integer sums do not depend on the order, so the counts are the same for any split.
    let parts = rayon::current_num_threads().clamp(1, 8);
    let per = tgt.active.len().div_ceil(parts).max(1);
    let marks: Vec<Vec<i32>> = tgt
        .active
        .par_chunks(per)
        .map(|chunk| {
            let mut delta = vec![0i32; len];
            for &q in chunk {
                let q = q as usize;
                if tgt.info[q].flags & IN_MASK == 0 {
                    continue;
                }
                let m = &nnf.data[q];
                if !m.ok {
                    continue;
                }
                let i = m.i as usize;
                let lo = i.saturating_sub(r) * src.frame_len;
                let hi = (i + r + 1 < frames).then_some((i + r + 1) * src.frame_len);
                for (a, b) in offsets() {
                    let (dx, dy) = m.rotate(a as f32, b as f32);
                    let px = floor_i32(m.x + dx + PAD as f32 + 0.5);
                    let py = floor_i32(m.y + dy + PAD as f32 + 0.5);
                    if px < 0 || py < 0 || px >= src.stride as i32 || py >= rows {
                        continue;
                    }
                    let pix = py as usize * src.stride + px as usize;
                    delta[lo + pix] += 1;
                    if let Some(hi) = hi {
                        delta[hi + pix] -= 1;
                    }
                }
            }
            delta
        })
        .collect();
    let mut parts = marks.into_iter();
    let mut out = parts.next().unwrap_or_else(|| vec![0; len]);
    for other in parts {
        out.par_chunks_mut(1 << 16).zip(other.par_chunks(1 << 16)).for_each(|(o, p)| {
            for (o, p) in o.iter_mut().zip(p) {
                *o += *p;
            }
        });
    }
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

/// Penalties above this many times λ/n² (the per-tap penalty of a voxel used exactly as often
/// as uniform use would, Ω* = ω*) are clamped when stored in the features' occurrence lane.
pub(crate) const OMEGA_CAP: f32 = 32.0;

/// The exemplar features of this level with the penalty `λ·Ω*(p′)/(n²·ω*_seg)` of each source
/// voxel written into the occurrence lane ([`OMEGA_LANE`]), where the segment is the voxel's own
/// (matches never cross segments), and the lane's weight `w_Ω`. `None` when λ = 0.
///
/// The lane holds `q = round(√(penalty / w_Ω))` with `w_Ω = OMEGA_CAP·λ/n² / 255²`, so that the
/// patch error's `w_Ω·(q − 0)²` is the penalty: uniform use (Ω* = ω*) gives q ≈ 45, a step of
/// ≈ 4 % there and finer below; penalties above [`OMEGA_CAP`] times that are clamped.
/// Keeping Ω in the 8-byte pixel the error reads anyway halves the cache lines a random
/// candidate touches.
pub(crate) fn penalty(
    src: &SourceLevel,
    nnf: &Nnf,
    tgt: &TargetLevel,
    r: usize,
    lambda: f32,
) -> Option<(Vec<Feat>, f32)> {
    if lambda == 0.0 {
        return None;
    }
    let counts = counts(src, nnf, tgt, r);
    let n2 = (PATCH * PATCH) as f32;
    let w_omega = OMEGA_CAP * lambda / n2 / (255.0 * 255.0);
    // (q/255)² = penalty/(OMEGA_CAP·λ/n²) = Ω*/(OMEGA_CAP·ω*), so q = 255·√(Ω* · k_seg).
    let k: [f32; 2] = std::array::from_fn(|seg| {
        let t = tgt.seg_count[seg] as f32;
        let s = src.seg_count[seg] as f32;
        if t > 0.0 && s > 0.0 {
            // 1/(OMEGA_CAP·ω*) with ω* = n²(2r+1)|T|/|S|
            s / (OMEGA_CAP * n2 * (2 * r + 1) as f32 * t)
        } else {
            0.0
        }
    });
    let mut feat = src.feat.clone();
    feat.par_chunks_mut(src.frame_len).zip(counts.par_chunks(src.frame_len)).for_each(|(fr, cr)| {
        for (f, &c) in fr.iter_mut().zip(cr) {
            f[OMEGA_LANE] = if c <= 0 {
                0
            } else {
                let seg = (f[FLAG_LANE] & INTERIOR != 0) as usize;
                ((255.0 * (c as f32 * k[seg]).sqrt() + 0.5) as u32).min(255) as u8
            };
        }
    });
    Some((feat, w_omega))
}
