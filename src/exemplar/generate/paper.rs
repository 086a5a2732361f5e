//! The paper: a height field `h ∈ [0, 1]` made of value-noise fBm (cloudy formation of the
//! sheet), fine white noise (tooth) and randomly oriented fibres, after the recipe in
//! `shared/notes/watercolor-generator.md` (step 1) with isotropic fibres instead of
//! horizontally blurred noise.

use super::blur::blur_xy;
use crate::rng::{SplitMix64, lattice};

/// The paper's height field and what the simulation derives from it.
pub(crate) struct Paper {
    /// Height `h`, normalized to `[0, 1]`, row-major.
    pub height: Vec<f32>,
    /// `h_s`: height blurred (σ 1.5) and normalized; drives where the wet front advances.
    pub smooth: Vec<f32>,
    /// Fluid capacity `c = 0.3 + 0.4 h` (paper-guided diffusion).
    pub capacity: Vec<f32>,
}

fn smoothstep(t: f32) -> f32 {
    t * t * (3.0 - 2.0 * t)
}

/// Value noise with cells of `cell` pixels: lattice values interpolated with a smoothstep.
fn value_noise(seed: u64, w: usize, h: usize, cell: f32, out: &mut [f32], amp: f32) {
    for y in 0..h {
        let fy = y as f32 / cell;
        let iy = fy.floor();
        let ty = smoothstep(fy - iy);
        for x in 0..w {
            let fx = x as f32 / cell;
            let ix = fx.floor();
            let tx = smoothstep(fx - ix);
            let (ix, iy) = (ix as i64, iy as i64);
            let a = lattice(seed, ix, iy);
            let b = lattice(seed, ix + 1, iy);
            let c = lattice(seed, ix, iy + 1);
            let d = lattice(seed, ix + 1, iy + 1);
            let top = a + (b - a) * tx;
            let bot = c + (d - c) * tx;
            out[y * w + x] += amp * (top + (bot - top) * ty);
        }
    }
}

fn normalize(v: &mut [f32]) {
    // Percentile-free min/max: the inputs are smooth sums, without outliers worth clipping.
    let (lo, hi) = v.iter().fold((f32::MAX, f32::MIN), |(lo, hi), &x| (lo.min(x), hi.max(x)));
    let span = (hi - lo).max(1e-6);
    v.iter_mut().for_each(|x| *x = (*x - lo) / span);
}

/// Makes a `w × h` sheet of paper. `grain` scales the fine tooth and fibres against the
/// cloudy formation (1 = the recipe's mix).
pub(crate) fn make(w: usize, h: usize, grain: f32, rng: &mut SplitMix64) -> Paper {
    let n = w * h;
    // Cloudy formation: fBm of value noise, 32 px base cell, 5 octaves, gain 0.5.
    let mut fbm = vec![0.0f32; n];
    let (mut cell, mut amp) = (32.0f32, 1.0f32);
    for _ in 0..5 {
        value_noise(rng.next_u64(), w, h, cell, &mut fbm, amp);
        cell *= 0.5;
        amp *= 0.5;
    }
    normalize(&mut fbm);
    // Tooth: white noise, blurred a little.
    let white: Vec<f32> = (0..n).map(|_| rng.next_f32()).collect();
    let mut tooth = blur_xy(&white, w, h, 0.8, 0.8);
    normalize(&mut tooth);
    // Fibres: short straight segments in random directions, drawn additively.
    let mut fibre = vec![0.0f32; n];
    let count = n / 30;
    for _ in 0..count {
        let (x0, y0) = (rng.range(0.0, w as f32), rng.range(0.0, h as f32));
        let angle = rng.range(0.0, std::f32::consts::PI);
        let len = rng.range(4.0, 18.0);
        let a = rng.range(0.3, 1.0);
        let (dx, dy) = (angle.cos(), angle.sin());
        let steps = (len * 2.0) as usize;
        for s in 0..steps {
            let t = s as f32 * 0.5 - len * 0.5;
            let (x, y) = ((x0 + dx * t) as isize, (y0 + dy * t) as isize);
            if x >= 0 && y >= 0 && (x as usize) < w && (y as usize) < h {
                fibre[y as usize * w + x as usize] += a;
            }
        }
    }
    let mut fibre = blur_xy(&fibre, w, h, 0.6, 0.6);
    normalize(&mut fibre);
    let fibre_mean = fibre.iter().sum::<f32>() / n as f32;
    let mut height: Vec<f32> =
        (0..n).map(|i| 0.6 * fbm[i] + grain * (0.4 * tooth[i] + 0.5 * (fibre[i] - fibre_mean))).collect();
    normalize(&mut height);
    let mut smooth = blur_xy(&height, w, h, 1.5, 1.5);
    normalize(&mut smooth);
    let capacity = height.iter().map(|&h| 0.3 + 0.4 * h).collect();
    Paper { height, smooth, capacity }
}
