//! Estimating the border width `b` of an exemplar (thesis `--border-width`), which the paper
//! and thesis leave to be hand-set per exemplar.
//!
//! The border channel `df = min(dist / b, 1)` separates the *border segment* (pixels closer
//! than `b` to the mask edge, where the paint looks and moves like a rim) from the *interior*
//! (where it has settled). So `b` should be the distance from the edge at which the paint's
//! look stops depending on that distance. We measure exactly that:
//!
//! 1. for every frame, the exact Euclidean distance of each painted pixel to the nearest
//!    unpainted one (the guides' signed distance field, [`crate::guide::sdf()`]; a frame
//!    painted everywhere has no edge to measure from and is skipped);
//! 2. two texture statistics per pixel: **darkness**, the optical density
//!    `−ln(I / paper)` averaged over RGB, and **contrast**, the absolute difference between
//!    that density and its 3×3 mean (granulation, fine structure);
//! 3. their means as a function of the distance (1-pixel bins, all frames pooled, bins with
//!    fewer than 30 pixels dropped), smoothed with a `[1 2 1]` filter;
//! 4. for each profile, the distance `k₀` where it stops changing: from `k₀` on its slope
//!    stays below 20 % of its steepest slope near the edge for at least 3 px (a slow
//!    large-scale gradient towards a bloom's light center does not count as border);
//! 5. `b` is the larger of the two `k₀`, at least 2 px and at most half the deepest valid
//!    distance (near-edge = that first half).
//!
//! The distances are measured on the raw masks, as the engine's guides are by default (no
//! blur; with `--blur-sigma 8`, the thesis's value, the edge moves outwards by a pixel or two,
//! well within the estimate's precision).

use super::Exemplar;

/// The result of [`estimate_border_width`], with the profiles it was derived from.
#[derive(Clone, Debug, PartialEq)]
pub struct BorderEstimate {
    /// The estimated border width `b`, pixels (rounded to 0.5 px).
    pub width: f32,
    /// Mean optical density by distance from the edge (index = whole pixels).
    pub darkness: Vec<f32>,
    /// Mean local contrast of the optical density by distance from the edge.
    pub contrast: Vec<f32>,
    /// Number of pixels in each distance bin.
    pub counts: Vec<usize>,
}

/// Fallback when an exemplar's masks are too small to measure anything (pixels).
pub const FALLBACK_WIDTH: f32 = 10.0;

fn smooth121(v: &[f32]) -> Vec<f32> {
    (0..v.len())
        .map(|i| {
            let a = v[i.saturating_sub(1)];
            let c = v[(i + 1).min(v.len() - 1)];
            0.25 * a + 0.5 * v[i] + 0.25 * c
        })
        .collect()
}

/// Where a profile stops changing: the smallest distance `k₀` from which on its slope
/// (central differences) stays below 20 % of the steepest slope near the edge (over
/// `0..=end`) for at least 3 px.
fn settle_distance(profile: &[f32], end: usize) -> usize {
    let n = profile.len();
    let slope = |k: usize| -> f32 {
        let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
        (profile[b] - profile[a]) / (b - a).max(1) as f32
    };
    let slopes: Vec<f32> = (0..n).map(|k| slope(k).abs()).collect();
    let peak = slopes[..=end].iter().fold(0.0f32, |m, &d| m.max(d));
    if peak <= 1e-9 {
        return 0;
    }
    (0..=end).find(|&k| slopes[k..(k + 3).min(n)].iter().all(|&d| d < 0.2 * peak)).unwrap_or(end)
}

/// Estimates the border width of `ex` from how its texture changes with the distance from
/// the mask edge (see the module documentation for the method).
pub fn estimate_border_width(ex: &Exemplar) -> BorderEstimate {
    let paper = ex.paper();
    let mut dark_sum: Vec<f64> = Vec::new();
    let mut con_sum: Vec<f64> = Vec::new();
    let mut counts: Vec<usize> = Vec::new();
    for (frame, mask) in ex.frames.iter().zip(&ex.masks) {
        let (w, h) = frame.size();
        let painted = mask.threshold(0.5);
        if painted.count() == painted.len() {
            // No edge to measure from. (Before one SDF served the crate, such a frame's pixels
            // went to bin `w + h`, which never reached the estimate: every real distance in a
            // `w × h` frame is at most `√((w−1)² + (h−1)²) − ½ < w + h − 2`, so bin `w + h − 1`
            // stayed empty and cut the valid bins off before it; the frames of an exemplar
            // share one size.)
            continue;
        }
        let dist = crate::guide::sdf(&painted);
        let (inside, dist) = (painted.data(), dist.data());
        let od: Vec<f32> = frame
            .data()
            .iter()
            .map(|c| (0..3).map(|i| (-(c[i].max(1e-3) / paper[i].max(1e-3)).ln()).max(0.0)).sum::<f32>() / 3.0)
            .collect();
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                if !inside[i] {
                    continue;
                }
                let mut local = 0.0;
                let mut n = 0.0;
                for yy in y.saturating_sub(1)..(y + 2).min(h) {
                    for xx in x.saturating_sub(1)..(x + 2).min(w) {
                        local += od[yy * w + xx];
                        n += 1.0;
                    }
                }
                let k = dist[i].max(0.0) as usize;
                if k >= counts.len() {
                    counts.resize(k + 1, 0);
                    dark_sum.resize(k + 1, 0.0);
                    con_sum.resize(k + 1, 0.0);
                }
                counts[k] += 1;
                dark_sum[k] += od[i] as f64;
                con_sum[k] += (od[i] - local / n).abs() as f64;
            }
        }
    }
    // Keep the bins with enough pixels, up to the first one without.
    let valid = counts.iter().take_while(|&&c| c >= 30).count();
    let darkness: Vec<f32> = (0..valid).map(|k| (dark_sum[k] / counts[k] as f64) as f32).collect();
    let contrast: Vec<f32> = (0..valid).map(|k| (con_sum[k] / counts[k] as f64) as f32).collect();
    counts.truncate(valid);
    if valid < 8 {
        let width = FALLBACK_WIDTH.min((valid as f32 / 2.0).max(2.0));
        return BorderEstimate { width, darkness, contrast, counts };
    }
    let end = (valid - 1) / 2;
    let (sd, sc) = (smooth121(&darkness), smooth121(&contrast));
    let (kd, kc) = (settle_distance(&sd, end), settle_distance(&sc, end));
    log::debug!("border: darkness settles at {kd} px, contrast at {kc} px (of {valid} valid distances)");
    log::debug!("border: darkness profile {:?}", sd.iter().map(|v| (v * 1000.0).round() / 1000.0).collect::<Vec<_>>());
    log::debug!("border: contrast profile {:?}", sc.iter().map(|v| (v * 1000.0).round() / 1000.0).collect::<Vec<_>>());
    let k0 = kd.max(kc);
    let width = (k0 as f32).clamp(2.0, end as f32);
    BorderEstimate { width: (width * 2.0).round() / 2.0, darkness, contrast, counts }
}
