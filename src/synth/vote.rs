//! VOTE: every target pixel becomes the average of the colors that the overlapping rotated
//! source patches of its n × n neighbours put on it (Kwatra et al. 2005; thesis §2.1.2).
//! Gathered per pixel, so it runs in parallel without write conflicts.

use super::nnf::{Nnf, offsets};
use super::source::SourceLevel;
use crate::img::Rgb;
use rayon::prelude::*;

/// Votes the colors of the `w × h` field; pixels without any voter get `fill`.
///
/// Each patch's vote is weighted by `exp(−|o|²/2σ²)` of the pixel's offset o from the patch
/// center (σ = `sigma`; 0 = uniform weights as in Kwatra et al.). Watercolor is a fine-grained
/// stochastic texture: uniform averaging of 25 slightly misaligned patches washes its grain out,
/// center weighting keeps it (measured in the engine's notes).
pub(crate) fn vote(src: &SourceLevel, nnf: &Nnf, fill: Rgb, sigma: f32) -> Vec<Rgb> {
    vote_with(src, nnf, fill, sigma, false)
}

/// [`vote`] with bicubic sampling when `cubic` (for the final output).
pub(crate) fn vote_with(src: &SourceLevel, nnf: &Nnf, fill: Rgb, sigma: f32, cubic: bool) -> Vec<Rgb> {
    let (w, h) = (nnf.w, nnf.h);
    // Offsets whose weight is below 2 % of the center's are skipped (with σ = 0.7 the 3 × 3
    // core: the outer ring would add under 2 % each and cost two thirds of the work).
    let taps: Vec<((isize, isize), f32)> = offsets()
        .map(|(a, b)| {
            ((a, b), if sigma > 0.0 { (-((a * a + b * b) as f32) / (2.0 * sigma * sigma)).exp() } else { 1.0 })
        })
        .filter(|&(_, w)| w >= 0.02)
        .collect();
    let mut out = vec![fill; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        #[cfg(target_arch = "x86_64")]
        {
            if super::patch::has_avx2() {
                // SAFETY: the CPU supports AVX2 (checked above).
                return unsafe { vote_row_avx2(src, nnf, &taps, y, row, cubic) };
            }
        }
        if cubic {
            vote_row(nnf, &taps, y, row, |i, x, y| src.sample_rgb_cubic(i, x, y))
        } else {
            vote_row(nnf, &taps, y, row, |i, x, y| src.sample_rgb(i, x, y))
        }
    });
    out
}

/// [`vote_row`] compiled for AVX2, with the AVX2 samplers (the same results).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn vote_row_avx2(
    src: &SourceLevel,
    nnf: &Nnf,
    taps: &[((isize, isize), f32)],
    y: usize,
    row: &mut [Rgb],
    cubic: bool,
) {
    if cubic {
        vote_row(nnf, taps, y, row, |i, x, y| src.sample_rgb_cubic_avx2(i, x, y))
    } else {
        vote_row(nnf, taps, y, row, |i, x, y| src.sample_rgb_avx2(i, x, y))
    }
}

/// Votes row `y` of the field into `row`, sampling the source with `sample(i, x, y)`.
#[inline(always)]
fn vote_row(
    nnf: &Nnf,
    taps: &[((isize, isize), f32)],
    y: usize,
    row: &mut [Rgb],
    sample: impl Fn(usize, f32, f32) -> Rgb,
) {
    let (w, h) = (nnf.w, nnf.h);
    for (x, o) in row.iter_mut().enumerate() {
        if !nnf.data[y * w + x].ok {
            continue;
        }
        let mut acc = [0.0f32; 3];
        let mut n = 0.0f32;
        for &((a, b), wt) in taps {
            // The neighbour centered at (x − a, y − b) covers this pixel at its offset (a, b).
            let (nx, ny) = (x as isize - a, y as isize - b);
            if nx < 0 || ny < 0 || nx >= w as isize || ny >= h as isize {
                continue;
            }
            let m = &nnf.data[ny as usize * w + nx as usize];
            if !m.ok {
                continue;
            }
            let (dx, dy) = m.rotate(a as f32, b as f32);
            let c = sample(m.i as usize, m.x + dx, m.y + dy);
            acc[0] += wt * c[0];
            acc[1] += wt * c[1];
            acc[2] += wt * c[2];
            n += wt;
        }
        if n > 0.0 {
            *o = [acc[0] / n, acc[1] / n, acc[2] / n];
        }
    }
}
