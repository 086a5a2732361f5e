//! Estimating the border width `b` of an exemplar (thesis `--border-width`), which the paper
//! and thesis leave to be hand-set per exemplar.
//!
//! The border channel `df = min(dist / b, 1)` separates the *border segment* (pixels closer
//! than `b` to the mask edge, where the paint looks and moves like a rim) from the *interior*
//! (where it has settled). So `b` should be the distance from the edge at which the paint's
//! look stops depending on that distance. We measure exactly that:
//!
//! 1. for every frame, the exact Euclidean distance of each painted pixel to the nearest
//!    unpainted one ([`signed_distance`], a two-pass separable transform after Felzenszwalb
//!    and Huttenlocher);
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

const INF: f32 = 1e20;

/// 1D squared distance transform of `f` (Felzenszwalb & Huttenlocher 2012), into `out`.
fn dt1d(f: &[f32], out: &mut [f32], v: &mut [usize], z: &mut [f32]) {
    let n = f.len();
    let mut k = 0usize;
    v[0] = 0;
    z[0] = -INF;
    z[1] = INF;
    for q in 1..n {
        loop {
            let p = v[k];
            let s = ((f[q] + (q * q) as f32) - (f[p] + (p * p) as f32)) / (2.0 * (q as f32 - p as f32));
            if s <= z[k] && k > 0 {
                k -= 1;
            } else if s <= z[k] {
                // k == 0 and the parabola at q hides the one at v[0] everywhere.
                v[0] = q;
                z[1] = INF;
                break;
            } else {
                k += 1;
                v[k] = q;
                z[k] = s;
                z[k + 1] = INF;
                break;
            }
        }
    }
    k = 0;
    for (q, o) in out.iter_mut().enumerate() {
        while z[k + 1] < q as f32 {
            k += 1;
        }
        let p = v[k];
        let d = q as f32 - p as f32;
        *o = d * d + f[p];
    }
}

/// Exact squared Euclidean distance from every pixel to the nearest pixel where `seed` is
/// true (`INF`-like when there is none).
fn squared_edt(seed: &[bool], w: usize, h: usize) -> Vec<f32> {
    let mut grid: Vec<f32> = seed.iter().map(|&s| if s { 0.0 } else { INF }).collect();
    let n = w.max(h);
    let (mut f, mut out, mut v, mut z) = (vec![0.0; n], vec![0.0; n], vec![0usize; n], vec![0.0; n + 1]);
    for x in 0..w {
        for y in 0..h {
            f[y] = grid[y * w + x];
        }
        dt1d(&f[..h], &mut out[..h], &mut v, &mut z);
        for y in 0..h {
            grid[y * w + x] = out[y];
        }
    }
    for y in 0..h {
        f[..w].copy_from_slice(&grid[y * w..(y + 1) * w]);
        dt1d(&f[..w], &mut out[..w], &mut v, &mut z);
        grid[y * w..(y + 1) * w].copy_from_slice(&out[..w]);
    }
    grid
}

/// Signed Euclidean distance to the edge of `mask` (`w × h`, row-major), positive inside:
/// a painted pixel gets its distance to the nearest unpainted pixel minus ½, an unpainted
/// one minus its distance to the nearest painted pixel plus ½ (so the edge sits between
/// pixel centers). Without any pixel on one side, that side's distances are `w + h`.
pub fn signed_distance(mask: &[bool], w: usize, h: usize) -> Vec<f32> {
    let outside: Vec<bool> = mask.iter().map(|&m| !m).collect();
    let to_out = squared_edt(&outside, w, h);
    let to_in = squared_edt(mask, w, h);
    let cap = (w + h) as f32;
    mask.iter()
        .enumerate()
        .map(|(i, &m)| if m { (to_out[i].sqrt() - 0.5).min(cap) } else { -(to_in[i].sqrt() - 0.5).min(cap) })
        .collect()
}

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
        let inside: Vec<bool> = mask.data().iter().map(|&m| m >= 0.5).collect();
        let dist = signed_distance(&inside, w, h);
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

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(mask: &[bool], w: usize, h: usize) -> Vec<f32> {
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                let best = (0..w * h)
                    .filter(|&j| mask[j] != mask[i])
                    .map(|j| ((j % w) as f32 - x).hypot((j / w) as f32 - y))
                    .fold(f32::MAX, f32::min);
                let best = best.min((w + h) as f32 + 0.5);
                if mask[i] { best - 0.5 } else { -(best - 0.5) }
            })
            .collect()
    }

    #[test]
    fn edt_matches_brute_force() {
        let mut s = crate::rng::SplitMix64::new(3);
        for (w, h) in [(1, 1), (7, 3), (13, 11), (20, 20)] {
            let mask: Vec<bool> = (0..w * h).map(|_| s.next_f32() < 0.4).collect();
            let fast = signed_distance(&mask, w, h);
            let slow = brute(&mask, w, h);
            for (a, b) in fast.iter().zip(&slow) {
                assert!((a - b).abs() < 1e-3 || (a.abs() >= (w + h) as f32 - 1.0), "{a} vs {b} ({w}x{h})");
            }
        }
    }

    #[test]
    fn disc_distance_is_radial() {
        let (w, h) = (41, 41);
        let mask: Vec<bool> =
            (0..w * h).map(|i| ((i % w) as f32 - 20.0).hypot((i / w) as f32 - 20.0) <= 15.0).collect();
        let d = signed_distance(&mask, w, h);
        assert!((d[20 * w + 20] - 14.53).abs() < 0.01, "{}", d[20 * w + 20]);
        assert!(d[20 * w + 40] < -3.0);
    }
}
