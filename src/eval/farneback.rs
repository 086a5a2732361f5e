//! Dense optical flow by polynomial expansion: G. Farnebäck, *Two-Frame Motion Estimation
//! Based on Polynomial Expansion* (SCIA 2003).
//!
//! **Polynomial expansion.** Around every pixel the image is approximated by a quadratic
//! polynomial in local coordinates `u = (x, y)`:
//!
//! ```text
//! f(u) ≈ uᵀ A u + bᵀ u + c,    A symmetric 2 × 2
//! ```
//!
//! fitted by weighted least squares with a Gaussian *applicability* `a(u)` of standard
//! deviation [`FarnebackParams::poly_sigma`] over a `(2n + 1)²` neighbourhood
//! ([`FarnebackParams::poly_n`] = n). With full certainty (image borders are replicated) the
//! fit is a fixed linear filter: the correlations of the image with the six basis functions
//! `{1, x, y, x², y², xy}` weighted by `a` — separable, so one vertical pass (weights `a`,
//! `y·a`, `y²·a`) and one horizontal pass give all six — multiplied by the inverse of the
//! 6 × 6 Gram matrix `Bᵀ W B` of the basis. By symmetry of `a` that matrix falls apart into
//! `x` and `y` (each `m₀m₂`), `xy` (`m₂²`) and a 3 × 3 block for `{1, x², y²}`, where
//! `m_k = Σ t^k a(t)` are the moments of the 1-D applicability.
//!
//! **Displacement.** If the second image is the first one moved by `d`,
//! `f₂(u) = f₁(u − d)`, then `A₂ = A₁` and `b₂ = b₁ − 2 A₁ d`, so `d = −½ A₁⁻¹ (b₂ − b₁)`.
//! With an a-priori displacement `d̃(x)` (from a coarser level or the previous iteration) the
//! second expansion is read at `x̃ = x + d̃(x)` (bilinear), and with
//!
//! ```text
//! A(x)  = (A₁(x) + A₂(x̃)) / 2
//! Δb(x) = −½ (b₂(x̃) − b₁(x)) + A(x) d̃(x)
//! ```
//!
//! the displacement satisfies `A(x) d(x) = Δb(x)`. One pixel's equation does not determine
//! `d` well, so `d` is assumed constant over a [`FarnebackParams::window`]² neighbourhood and
//! solved in the least-squares sense: `d = (Σ AᵀA + μI)⁻¹ Σ AᵀΔb`, the sums being means over
//! the window (a box filter, as in the paper's simplest variant). `μ` (Tikhonov,
//! [`REGULARIZATION`]) only matters where there is no texture: there `d` tends to 0, and along
//! a straight edge (the aperture problem) `d` is the displacement normal to it. Pixels whose
//! `x̃` falls outside the image carry no information and get weight 0.
//!
//! **Iterations and scales.** The estimate is refined [`FarnebackParams::iterations`] times
//! (each time the second expansion is read at the new `x̃`), coarse to fine over a pyramid of
//! [`FarnebackParams::levels`] levels besides the full resolution, each
//! [`FarnebackParams::pyr_scale`] times the size of the next finer one: level `k` is the image
//! smoothed with a Gaussian of σ = `(1/s − 1) / 2` full-resolution pixels (`s` = its scale;
//! each level is blurred from the one before by the σ that remains) and resampled bilinearly;
//! the flow of a level, resized and scaled, is the a-priori displacement of the next. Levels whose smaller side would fall below [`MIN_LEVEL_SIDE`] pixels are skipped.
//!
//! The defaults are the classic ones (pyramid 0.5 over 3 levels, window 9, 3 iterations,
//! expansion n = 5, σ = 1.1). Everything runs in `f32` except the constant matrices; rows are
//! processed in parallel without reductions, so the result does not depend on the thread
//! count.
//!
//! ```
//! use fluidymation::eval::{farneback_flow, warp_bilinear, FarnebackParams};
//! use fluidymation::img::Plane;
//!
//! let tex = |dx: f32| Plane::from_fn(64, 64, |x, y| ((x as f32 - dx) * 0.4).sin() * ((y as f32) * 0.3).cos());
//! let (a, b) = (tex(0.0), tex(1.5)); // b is a moved 1.5 px to the right
//! let flow = farneback_flow(&a, &b, &FarnebackParams::default());
//! assert!((flow.get(32, 32).x - 1.5).abs() < 0.1);
//! // Reading b along the flow gives back a.
//! let back = warp_bilinear(&b, &flow);
//! assert!((back.get(32, 32) - a.get(32, 32)).abs() < 0.02);
//! ```

use crate::img::{Plane, gaussian_blur, resize_bilinear, sample_bilinear};
use glam::Vec2;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Smallest side of a pyramid level, pixels; coarser levels are skipped.
pub const MIN_LEVEL_SIDE: usize = 32;

/// Tikhonov term `μ` added to the window's `Σ AᵀA` before solving, for intensities in `0..=1`
/// (negligible against any visible texture, whose `AᵀA` is ~10⁻⁴ or more).
pub const REGULARIZATION: f32 = 1e-7;

/// Settings of [`farneback_flow`] (see the [module documentation](self)).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FarnebackParams {
    /// Pyramid levels coarser than the full resolution. Default: 3.
    pub levels: usize,
    /// Size of a level relative to the next finer one, in `(0, 1)`. Default: 0.5.
    pub pyr_scale: f32,
    /// Side of the square window over which the displacement is assumed constant (pixels,
    /// odd). Default: 9.
    pub window: usize,
    /// Refinements per level. Default: 3.
    pub iterations: usize,
    /// Radius n of the polynomial expansion's neighbourhood (`(2n + 1)²` pixels). Default: 5.
    pub poly_n: usize,
    /// Standard deviation of the expansion's Gaussian applicability, pixels. Default: 1.1.
    pub poly_sigma: f32,
}

impl Default for FarnebackParams {
    fn default() -> Self {
        FarnebackParams { levels: 3, pyr_scale: 0.5, window: 9, iterations: 3, poly_n: 5, poly_sigma: 1.1 }
    }
}

impl FarnebackParams {
    /// `None` when every setting is in range, else the offending setting's name and the range
    /// it must be in.
    pub fn invalid(&self) -> Option<(&'static str, String, &'static str)> {
        if self.levels > 16 {
            return Some(("levels", self.levels.to_string(), "0..=16"));
        }
        if !(self.pyr_scale > 0.0 && self.pyr_scale < 1.0) {
            return Some(("pyr_scale", self.pyr_scale.to_string(), "a factor in (0, 1)"));
        }
        if self.window.is_multiple_of(2) || !(1..=63).contains(&self.window) {
            return Some(("window", self.window.to_string(), "an odd number in 1..=63"));
        }
        if !(1..=100).contains(&self.iterations) {
            return Some(("iterations", self.iterations.to_string(), "1..=100"));
        }
        if !(1..=15).contains(&self.poly_n) {
            return Some(("poly_n", self.poly_n.to_string(), "1..=15"));
        }
        if !(self.poly_sigma.is_finite() && self.poly_sigma > 0.1) {
            return Some(("poly_sigma", self.poly_sigma.to_string(), "a number > 0.1"));
        }
        None
    }
}

/// The expansion coefficients of one pixel: `[b_x, b_y, A_xx, A_yy, A_xy]` (`A_xy` is the
/// off-diagonal element, half the coefficient of `xy`).
type Coeffs = [f32; 5];

/// The constant part of the least-squares fit: the applicability and the inverse Gram matrix.
struct Expansion {
    /// Applicability `a(t)` for `t = −n..=n`.
    weights: Vec<f32>,
    /// `1 / (m₀ m₂)`: from the `x` (or `y`) correlation to `b_x` (`b_y`).
    to_linear: f32,
    /// `1 / m₂²`: from the `xy` correlation to its coefficient.
    to_cross: f32,
    /// Rows 2 and 3 of the inverse of the `{1, x², y²}` block: `A_xx` and `A_yy` from the
    /// correlations with `1`, `x²`, `y²`.
    to_quadratic: [[f32; 3]; 2],
}

impl Expansion {
    fn new(n: usize, sigma: f32) -> Expansion {
        let n = n as i32;
        let s2 = 2.0 * (sigma as f64) * (sigma as f64);
        let weights: Vec<f64> = (-n..=n).map(|t| (-((t * t) as f64) / s2).exp()).collect();
        let moment = |k: i32| -> f64 { (-n..=n).zip(&weights).map(|(t, w)| (t as f64).powi(k) * w).sum() };
        let (m0, m2, m4) = (moment(0), moment(2), moment(4));
        let g = [[m0 * m0, m0 * m2, m0 * m2], [m0 * m2, m0 * m4, m2 * m2], [m0 * m2, m2 * m2, m0 * m4]];
        let inv = invert3(g);
        let row = |r: [f64; 3]| r.map(|v| v as f32);
        Expansion {
            weights: weights.iter().map(|&w| w as f32).collect(),
            to_linear: (1.0 / (m0 * m2)) as f32,
            to_cross: (1.0 / (m2 * m2)) as f32,
            to_quadratic: [row(inv[1]), row(inv[2])],
        }
    }

    /// The coefficients of every pixel of `img` (borders replicated).
    fn apply(&self, img: &Plane<f32>) -> Plane<Coeffs> {
        let (w, h) = img.size();
        let n = self.weights.len() / 2;
        let taps: Vec<(f32, f32, f32)> = self
            .weights
            .iter()
            .enumerate()
            .map(|(k, &a)| {
                let t = k as f32 - n as f32;
                (a, t * a, t * t * a)
            })
            .collect();
        let [qx, qy] = self.to_quadratic;
        let mut out: Plane<Coeffs> = Plane::new(w, h);
        out.data_mut().par_chunks_mut(w).enumerate().for_each(|(y, row_out)| {
            // Vertical pass: Σ a(t) f, Σ t a(t) f, Σ t² a(t) f over the column, per x, into
            // rows padded by n replicated values on each side (one array per sum, so that the
            // loops run over contiguous values).
            let mut v = [vec![0f32; w + 2 * n], vec![0f32; w + 2 * n], vec![0f32; w + 2 * n]];
            for (k, &(a, ta, tta)) in taps.iter().enumerate() {
                let sy = (y as isize + k as isize - n as isize).clamp(0, h as isize - 1) as usize;
                let src = img.row(sy);
                for (vc, weight) in v.iter_mut().zip([a, ta, tta]) {
                    for (acc, &f) in vc[n..n + w].iter_mut().zip(src) {
                        *acc += weight * f;
                    }
                }
            }
            for vc in &mut v {
                let (first, last) = (vc[n], vc[n + w - 1]);
                vc[..n].fill(first);
                vc[n + w..].fill(last);
            }
            // Horizontal pass: the six correlations.
            let mut sums = [(); 6].map(|_| vec![0f32; w]);
            let [s00, s10, s20, s01, s11, s02] = &mut sums;
            for (k, &(a, ta, tta)) in taps.iter().enumerate() {
                let (v0, v1, v2) = (&v[0][k..k + w], &v[1][k..k + w], &v[2][k..k + w]);
                for x in 0..w {
                    s00[x] += a * v0[x];
                    s10[x] += ta * v0[x];
                    s20[x] += tta * v0[x];
                    s01[x] += a * v1[x];
                    s11[x] += ta * v1[x];
                    s02[x] += a * v2[x];
                }
            }
            for (x, o) in row_out.iter_mut().enumerate() {
                *o = [
                    s10[x] * self.to_linear,
                    s01[x] * self.to_linear,
                    qx[0] * s00[x] + qx[1] * s20[x] + qx[2] * s02[x],
                    qy[0] * s00[x] + qy[1] * s20[x] + qy[2] * s02[x],
                    0.5 * s11[x] * self.to_cross,
                ];
            }
        });
        out
    }
}

/// Inverse of a symmetric positive definite 3 × 3 matrix (cofactors).
fn invert3(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let c = |r0: usize, r1: usize, c0: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
    let cof = [
        [c(1, 2, 1, 2), -c(1, 2, 0, 2), c(1, 2, 0, 1)],
        [-c(0, 2, 1, 2), c(0, 2, 0, 2), -c(0, 2, 0, 1)],
        [c(0, 1, 1, 2), -c(0, 1, 0, 2), c(0, 1, 0, 1)],
    ];
    let det = m[0][0] * cof[0][0] + m[0][1] * cof[0][1] + m[0][2] * cof[0][2];
    // The inverse is the transposed cofactor matrix over the determinant (symmetric here).
    let mut inv = [[0.0; 3]; 3];
    for (r, row) in inv.iter_mut().enumerate() {
        for (col, v) in row.iter_mut().enumerate() {
            *v = cof[col][r] / det;
        }
    }
    inv
}

/// Bilinear sample of the expansion at `(x, y)`, which must lie inside the plane.
#[inline]
fn sample_coeffs(p: &Plane<Coeffs>, x: f32, y: f32) -> Coeffs {
    let (w, h) = p.size();
    let (x0, y0) = ((x as usize).min(w - 1), (y as usize).min(h - 1));
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let (top, bottom) = (p.row(y0), p.row(y1));
    let (a, b, c, d) = (top[x0], top[x1], bottom[x0], bottom[x1]);
    let mut out = [0f32; 5];
    for k in 0..5 {
        let upper = a[k] + fx * (b[k] - a[k]);
        let lower = c[k] + fx * (d[k] - c[k]);
        out[k] = upper + fy * (lower - upper);
    }
    out
}

/// Per pixel, the terms of the least-squares system `AᵀA d = AᵀΔb` for the a-priori
/// displacement `flow`: `[G₁₁, G₁₂, G₂₂, h₁, h₂]` (zero where `x̃` leaves the image).
fn equations(first: &Plane<Coeffs>, second: &Plane<Coeffs>, flow: &Plane<Vec2>) -> Plane<[f32; 5]> {
    let (w, h) = first.size();
    let (xmax, ymax) = ((w - 1) as f32, (h - 1) as f32);
    let mut out: Plane<[f32; 5]> = Plane::new(w, h);
    out.data_mut().par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, ((o, r1), d)) in row.iter_mut().zip(first.row(y)).zip(flow.row(y)).enumerate() {
            let (tx, ty) = (x as f32 + d.x, y as f32 + d.y);
            if !(tx >= 0.0 && ty >= 0.0 && tx <= xmax && ty <= ymax) {
                *o = [0.0; 5];
                continue;
            }
            let r2 = sample_coeffs(second, tx, ty);
            let (a11, a22, a12) = (0.5 * (r1[2] + r2[2]), 0.5 * (r1[3] + r2[3]), 0.5 * (r1[4] + r2[4]));
            let db1 = -0.5 * (r2[0] - r1[0]) + a11 * d.x + a12 * d.y;
            let db2 = -0.5 * (r2[1] - r1[1]) + a12 * d.x + a22 * d.y;
            *o = [
                a11 * a11 + a12 * a12,
                a12 * (a11 + a22),
                a12 * a12 + a22 * a22,
                a11 * db1 + a12 * db2,
                a12 * db1 + a22 * db2,
            ];
        }
    });
    out
}

/// Rows per parallel task of [`box_mean`].
const BAND: usize = 16;

/// Mean over a `side × side` window (borders replicated), separable: per band of rows, the
/// column sums over the window slide down the band, and a running sum slides along each row
/// (both in `f64`, so that sliding does not accumulate rounding).
fn box_mean(p: &Plane<[f32; 5]>, side: usize) -> Plane<[f32; 5]> {
    let (w, h) = p.size();
    let r = side / 2;
    let norm = 1.0 / (side * side) as f64;
    let row_at = |y: isize| p.row(y.clamp(0, h as isize - 1) as usize);
    let mut out: Plane<[f32; 5]> = Plane::new(w, h);
    out.data_mut().par_chunks_mut(w * BAND).enumerate().for_each(|(band, rows)| {
        let y0 = band * BAND;
        // Column sums, padded by r replicated values on each side.
        let mut cols = vec![[0f64; 5]; w + 2 * r];
        for t in 0..side {
            for (c, s) in cols[r..r + w].iter_mut().zip(row_at(y0 as isize + t as isize - r as isize)) {
                for k in 0..5 {
                    c[k] += s[k] as f64;
                }
            }
        }
        for (i, row) in rows.chunks_mut(w).enumerate() {
            let y = (y0 + i) as isize;
            if i > 0 {
                let (add, sub) = (row_at(y + r as isize), row_at(y - r as isize - 1));
                for ((c, a), s) in cols[r..r + w].iter_mut().zip(add).zip(sub) {
                    for k in 0..5 {
                        c[k] += a[k] as f64 - s[k] as f64;
                    }
                }
            }
            let (first, last) = (cols[r], cols[r + w - 1]);
            cols[..r].fill(first);
            cols[r + w..].fill(last);
            let mut acc = [0f64; 5];
            for c in &cols[..side] {
                for k in 0..5 {
                    acc[k] += c[k];
                }
            }
            for (x, o) in row.iter_mut().enumerate() {
                *o = acc.map(|v| (v * norm) as f32);
                if x + 1 < w {
                    let (add, sub) = (cols[x + side], cols[x]);
                    for k in 0..5 {
                        acc[k] += add[k] - sub[k];
                    }
                }
            }
        }
    });
    out
}

/// Solves each pixel's regularized 2 × 2 system.
fn solve(m: &Plane<[f32; 5]>) -> Plane<Vec2> {
    m.map(|[g11, g12, g22, h1, h2]| {
        let (g11, g22) = (g11 + REGULARIZATION, g22 + REGULARIZATION);
        let det = g11 * g22 - g12 * g12;
        if det > 0.0 { Vec2::new(g22 * h1 - g12 * h2, g11 * h2 - g12 * h1) / det } else { Vec2::ZERO }
    })
}

/// Level sizes and scales, finest (the full resolution) first.
fn level_sizes(w: usize, h: usize, params: &FarnebackParams) -> Vec<(usize, usize, f32)> {
    let mut sizes = vec![(w, h, 1.0f32)];
    for k in 1..=params.levels {
        let s = params.pyr_scale.powi(k as i32);
        let (lw, lh) = ((w as f32 * s).round() as usize, (h as f32 * s).round() as usize);
        if lw.min(lh) < MIN_LEVEL_SIDE {
            break;
        }
        sizes.push((lw, lh, s));
    }
    sizes
}

/// The pyramid of `img` at `sizes` (finest first): level `k` carries the smoothing of a
/// Gaussian of σ_k = `(1/s_k − 1) / 2` full-resolution pixels (`s_k` its scale), reached from
/// the level before by the blur that remains (σ's add in quadrature), then resampled
/// bilinearly.
fn pyramid(img: &Plane<f32>, sizes: &[(usize, usize, f32)]) -> Vec<Plane<f32>> {
    let mut levels = vec![img.clone()];
    for pair in sizes.windows(2) {
        let ((_, _, s0), (w, h, s)) = (pair[0], pair[1]);
        let (sigma0, sigma) = ((1.0 / s0 - 1.0) * 0.5, (1.0 / s - 1.0) * 0.5);
        let Some(prev) = levels.last() else { break };
        // The remaining blur, in the previous level's pixels.
        let blurred = gaussian_blur(prev, (sigma * sigma - sigma0 * sigma0).max(0.0).sqrt() * s0);
        let (sx, sy) = (prev.width() as f32 / w as f32, prev.height() as f32 / h as f32);
        let level = Plane::from_fn(w, h, |x, y| {
            sample_bilinear(&blurred, (x as f32 + 0.5) * sx - 0.5, (y as f32 + 0.5) * sy - 0.5)
        });
        levels.push(level);
    }
    levels
}

/// Dense flow from `from` to `to` (gray planes of one size): at every pixel `x` the
/// displacement `d` with `to(x + d) ≈ from(x)`, pixels (see the [module
/// documentation](self)). [`warp_bilinear`]`(to, flow)` then resembles `from`.
///
/// Panics when the planes differ in size; returns a zero field for an empty plane.
pub fn farneback_flow(from: &Plane<f32>, to: &Plane<f32>, params: &FarnebackParams) -> Plane<Vec2> {
    assert_eq!(from.size(), to.size(), "farneback_flow: images of different sizes");
    let (w, h) = from.size();
    if w == 0 || h == 0 {
        return Plane::new(w, h);
    }
    let expansion = Expansion::new(params.poly_n, params.poly_sigma);
    let sizes = level_sizes(w, h, params);
    let (from_levels, to_levels) = (pyramid(from, &sizes), pyramid(to, &sizes));
    let mut flow: Option<Plane<Vec2>> = None;
    for (k, &(lw, lh, _)) in sizes.iter().enumerate().rev() {
        let prior = match flow.take() {
            None => Plane::filled(lw, lh, Vec2::ZERO),
            Some(f) => {
                let (fx, fy) = (lw as f32 / f.width() as f32, lh as f32 / f.height() as f32);
                resize_bilinear(&f, lw, lh).map(|v| Vec2::new(v.x * fx, v.y * fy))
            }
        };
        let first = expansion.apply(&from_levels[k]);
        let second = expansion.apply(&to_levels[k]);
        let mut current = prior;
        for _ in 0..params.iterations.max(1) {
            current = solve(&box_mean(&equations(&first, &second, &current), params.window));
        }
        flow = Some(current);
    }
    flow.unwrap_or_else(|| Plane::new(w, h))
}

/// `img` read along `flow`: `out(x) = img(x + flow(x))`, bilinear, positions outside clamped
/// to the border.
pub fn warp_bilinear(img: &Plane<f32>, flow: &Plane<Vec2>) -> Plane<f32> {
    let (w, h) = flow.size();
    let mut out: Plane<f32> = Plane::new(w, h);
    out.data_mut().par_chunks_mut(w.max(1)).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            let d = flow.get(x, y);
            *o = sample_bilinear(img, x as f32 + d.x, y as f32 + d.y);
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expansion_recovers_a_quadratic_exactly() {
        // f = 0.3 + 0.02x − 0.01y + 0.004x² − 0.002y² + 0.003xy around (20, 15).
        let f = |x: f32, y: f32| {
            let (u, v) = (x - 20.0, y - 15.0);
            0.3 + 0.02 * u - 0.01 * v + 0.004 * u * u - 0.002 * v * v + 0.003 * u * v
        };
        let img = Plane::from_fn(40, 30, |x, y| f(x as f32, y as f32));
        let c = Expansion::new(5, 1.1).apply(&img).get(20, 15);
        let want = [0.02, -0.01, 0.004, -0.002, 0.0015];
        for (a, b) in c.iter().zip(want) {
            assert!((a - b).abs() < 1e-5, "{c:?} vs {want:?}");
        }
    }

    #[test]
    fn inverse_of_a_symmetric_matrix() {
        let m = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]];
        let inv = invert3(m);
        for (i, row) in m.iter().enumerate() {
            for j in 0..3 {
                let v: f64 = row.iter().zip(&inv).map(|(a, r)| a * r[j]).sum();
                assert!((v - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12);
            }
        }
    }
}
