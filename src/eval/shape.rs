//! Mask geometry shared by the metrics: the thresholded mask and its exact signed distance.

use crate::img::{Mask, Plane};
use rayon::prelude::*;

/// Coverage at or above this value counts as inside a mask.
pub const MASK_THRESHOLD: f32 = 0.5;

/// A binary mask together with its signed distance field.
///
/// The signed distance is in pixels, **positive inside**, with the boundary half-way between
/// an inside and an outside pixel: an inside pixel next to an outside one has `+0.5`, that
/// outside pixel `−0.5`. It is computed exactly (Euclidean, Felzenszwalb–Huttenlocher). The
/// image border is not a boundary: a mask covering the whole image has distance
/// `width + height` everywhere, an empty one `−(width + height)`.
#[derive(Clone, Debug)]
pub struct Shape {
    /// The mask (`coverage >= 0.5`).
    pub mask: Mask,
    /// Signed distance to the mask boundary, pixels, positive inside.
    pub sdf: Plane<f32>,
}

impl Shape {
    /// Thresholds a coverage plane at [`MASK_THRESHOLD`] and computes its signed distance.
    pub fn from_coverage(coverage: &Plane<f32>) -> Shape {
        Shape::from_mask(coverage.threshold(MASK_THRESHOLD))
    }

    /// Computes the signed distance of a binary mask.
    pub fn from_mask(mask: Mask) -> Shape {
        let sdf = signed_distance(&mask);
        Shape { mask, sdf }
    }

    /// The shapes of a whole coverage sequence (computed in parallel).
    pub fn sequence(masks: &[Plane<f32>]) -> Vec<Shape> {
        masks.par_iter().map(Shape::from_coverage).collect()
    }

    /// The *interior*: pixels at least `margin` pixels inside the boundary (`sdf >= margin`).
    pub fn interior(&self, margin: f32) -> Mask {
        self.sdf.map(|d| d >= margin)
    }

    /// `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        self.mask.size()
    }
}

/// A stand-in for "no feature pixel" in the squared distance transform.
const FAR: f64 = 1e20;

/// Squared Euclidean distance from every pixel to the nearest pixel where `feature` is true;
/// [`FAR`]-sized values where there is none. Felzenszwalb & Huttenlocher's lower envelope of
/// parabolas along rows, then (on the transposed result, so memory is read in order) along
/// columns.
fn squared_edt(feature: &Plane<bool>) -> Plane<f64> {
    let (w, h) = feature.size();
    if w == 0 || h == 0 {
        return Plane::filled(w, h, FAR);
    }
    // Rows of the transposed image are the columns of the original.
    let mut tr = vec![FAR; w * h];
    let mut rows = vec![0f64; w * h];
    rows.par_chunks_mut(w).enumerate().for_each_init(Scratch::default, |scratch, (y, out)| {
        scratch.f.clear();
        scratch.f.extend(feature.row(y).iter().map(|&b| if b { 0.0 } else { FAR }));
        envelope_1d(scratch, out);
    });
    transpose(&rows, w, h, &mut tr);
    let mut cols = vec![0f64; w * h];
    cols.par_chunks_mut(h).enumerate().for_each_init(Scratch::default, |scratch, (x, out)| {
        scratch.f.clear();
        scratch.f.extend_from_slice(&tr[x * h..(x + 1) * h]);
        envelope_1d(scratch, out);
    });
    transpose(&cols, h, w, &mut rows);
    Plane::from_vec(w, h, rows).unwrap_or_else(|| Plane::filled(w, h, FAR))
}

/// `dst` (h × w) = transpose of `src` (w × h, row-major), in cache-friendly tiles.
fn transpose(src: &[f64], w: usize, h: usize, dst: &mut [f64]) {
    const T: usize = 32;
    for y0 in (0..h).step_by(T) {
        for x0 in (0..w).step_by(T) {
            for y in y0..(y0 + T).min(h) {
                for x in x0..(x0 + T).min(w) {
                    dst[x * h + y] = src[y * w + x];
                }
            }
        }
    }
}

#[derive(Default)]
struct Scratch {
    f: Vec<f64>,
    v: Vec<usize>,
    z: Vec<f64>,
}

/// One-dimensional squared distance transform of the sampled function `scratch.f` into `d`:
/// `d[q] = min_p (q − p)² + f[p]`.
fn envelope_1d(scratch: &mut Scratch, d: &mut [f64]) {
    let Scratch { f, v, z } = scratch;
    let n = f.len();
    if n == 0 {
        return;
    }
    v.clear();
    v.resize(n, 0);
    z.clear();
    z.resize(n + 1, 0.0);
    let mut k = 0usize;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    let meet = |q: usize, p: usize| -> f64 {
        let (qf, pf) = (q as f64, p as f64);
        ((f[q] + qf * qf) - (f[p] + pf * pf)) / (2.0 * (qf - pf))
    };
    for q in 1..n {
        let mut s = meet(q, v[k]);
        while s <= z[k] {
            // z[0] is −∞, so this stops at k = 0 at the latest.
            k -= 1;
            s = meet(q, v[k]);
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    k = 0;
    for (q, out) in d.iter_mut().enumerate() {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let dq = q as f64 - v[k] as f64;
        *out = dq * dq + f[v[k]];
    }
}

/// Exact signed Euclidean distance of a mask, as described on [`Shape`].
pub fn signed_distance(mask: &Mask) -> Plane<f32> {
    let (w, h) = mask.size();
    let cap = (w + h) as f32;
    let to_outside = squared_edt(&mask.map(|b| !b));
    let to_inside = squared_edt(mask);
    Plane::from_fn(w, h, |x, y| {
        if mask.get(x, y) {
            let d2 = to_outside.get(x, y);
            if d2 >= FAR * 0.5 { cap } else { (d2.sqrt() as f32 - 0.5).min(cap) }
        } else {
            let d2 = to_inside.get(x, y);
            if d2 >= FAR * 0.5 { -cap } else { -(d2.sqrt() as f32 - 0.5).min(cap) }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(mask: &Mask) -> Plane<f32> {
        let (w, h) = mask.size();
        let cap = (w + h) as f32;
        Plane::from_fn(w, h, |x, y| {
            let inside = mask.get(x, y);
            let mut best = f32::INFINITY;
            for v in 0..h {
                for u in 0..w {
                    if mask.get(u, v) != inside {
                        let d = ((u as f32 - x as f32).powi(2) + (v as f32 - y as f32).powi(2)).sqrt();
                        best = best.min(d);
                    }
                }
            }
            let d = if best.is_finite() { (best - 0.5).min(cap) } else { cap };
            if inside { d } else { -d }
        })
    }

    #[test]
    fn matches_brute_force_on_pseudo_random_masks() {
        let mut state = 12345u64;
        for (w, h) in [(1, 1), (7, 3), (16, 11), (23, 23)] {
            for _ in 0..4 {
                let m = Plane::from_fn(w, h, |_, _| {
                    state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                    (state >> 33).is_multiple_of(3)
                });
                let a = signed_distance(&m);
                let b = brute(&m);
                for (p, q) in a.data().iter().zip(b.data()) {
                    assert!((p - q).abs() < 1e-4, "{} vs {} ({}x{})", p, q, w, h);
                }
            }
        }
    }

    #[test]
    fn full_and_empty_masks_are_capped() {
        let full = signed_distance(&Plane::filled(4, 3, true));
        assert!(full.data().iter().all(|&d| d == 7.0));
        let empty = signed_distance(&Plane::filled(4, 3, false));
        assert!(empty.data().iter().all(|&d| d == -7.0));
    }
}
