//! Laplace's equation `∇²u = 0` on an irregular domain with fixed (Dirichlet) values, solved by
//! geometric multigrid: V-cycles with red–black Gauss–Seidel smoothing, iterated until the
//! residual is below a stated tolerance (thesis §3.8, paper Appendix A: the interior of the flow
//! field is the diffusion of its boundary values).
//!
//! **Discretization.** Every [`Cell::Free`] pixel `c` satisfies the 5-point equation
//! `Σ_{n ∈ N(c)} (u_n − u_c) = 0`, where `N(c)` are its 4-neighbours that lie in the grid and are
//! not [`Cell::Outside`]. Neighbours left out (off the grid or outside) give a zero normal
//! derivative (Neumann), which is what the image border means for a mask that touches it.
//! [`Cell::Fixed`] pixels keep their values.
//!
//! **Tolerance.** The scaled residual of a free cell is `ρ_c = |mean_{n∈N(c)} u_n − u_c|` (the
//! Euclidean length for 2D values): how far `u_c` is from the average of its neighbours. The
//! solve stops when `max_c ρ_c ≤ tolerance · max_{fixed} |u|` ([`TOLERANCE`] = 10⁻⁴ by default),
//! or after [`MAX_CYCLES`] V-cycles (reported as not converged).
//!
//! **Multigrid.** The fixed values move to the right-hand side, leaving a symmetric system
//! `A u = b` over the free pixels. Coarse node `(X, Y)` sits on fine pixel `(2X, 2Y)` (the coarse
//! grid has `w/2 + 1` columns, so every fine pixel has its parents on it) and takes its role:
//! free, fixed, or outside — except that an outside node next to a fixed pixel becomes fixed, so
//! Dirichlet walls stay closed on every level and never turn into Neumann sides. The
//! prolongation `P` is bilinear from the free coarse nodes; a fixed parent holds zero (the
//! Dirichlet condition) and an outside parent, which only happens beyond an image edge, hands its
//! weight to its mirror image (the Neumann condition). The restriction is `Pᵀ` and the coarse
//! operator the Galerkin product `Pᵀ A P`, a 9-point stencil, so irregular boundaries need no
//! special geometry on coarse grids. As in the thesis, a V-cycle has no pre-smoothing: the
//! residual is restricted level by level, the coarsest grid is smoothed until its residual has
//! dropped 1000-fold, and on the way up each level gets [`POST_SWEEPS`] Gauss–Seidel sweeps after
//! its coarse-grid correction (the sweeps visit the colour classes in reverse order). Gauss–Seidel visits the pixels in four colour classes (the
//! parities of x and y, so that no two pixels of a class share a 9-point stencil), each class in
//! parallel over rows: the result does not depend on the number of threads. On the shapes of the
//! tests and of the benchmark one V-cycle reduces the residual 9- to 20-fold (ratios 0.05–0.11
//! measured), down to the rounding floor of `f32`.

use crate::img::Plane;
use glam::Vec2;
use rayon::prelude::*;

/// The role of a pixel in a Laplace problem.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Cell {
    /// Not part of the domain; its value is neither read nor written.
    #[default]
    Outside,
    /// A boundary pixel whose value is given (Dirichlet condition).
    Fixed,
    /// An unknown.
    Free,
}

/// Default tolerance of the scaled residual, relative to the largest fixed value.
pub const TOLERANCE: f32 = 1e-4;
/// At most this many V-cycles are run.
pub const MAX_CYCLES: usize = 100;
/// Gauss–Seidel sweeps after each coarse-grid correction.
pub const POST_SWEEPS: usize = 2;

/// What a solve did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolveReport {
    /// V-cycles run.
    pub cycles: usize,
    /// Final `max ρ_c` (see the module docs), in the units of the values.
    pub residual: f32,
    /// The tolerance in those units (`tolerance · max_fixed |u|`).
    pub threshold: f32,
    /// True when `residual ≤ threshold`.
    pub converged: bool,
}

/// A 9-point stencil, row-major over offsets `(dx, dy) ∈ {−1, 0, 1}²`; index 4 is the centre.
type Stencil = [f32; 9];

const NONE: u8 = 0;
const FIXED: u8 = 1;
const FREE: u8 = 2;

/// The prolongation weights of fine pixel `(x, y)`: bilinear from coarse nodes `(x/2, y/2)` and,
/// for odd coordinates, `x/2 + 1` / `y/2 + 1`. A parent that is outside the domain (only
/// possible beyond an image edge, a Neumann boundary) hands its weight to its mirror image,
/// the parent on the same row or column nearer to the pixel; fixed parents keep their weight
/// but hold zero. Returns `(coarse x, coarse y, weight)` of the free parents.
#[inline]
fn pweights(x: usize, y: usize, ckind: impl Fn(usize, usize) -> u8) -> ([(usize, usize, f32); 4], usize) {
    let (xa, ya) = (x / 2, y / 2);
    let nx = 1 + (x & 1);
    let ny = 1 + (y & 1);
    let base = if nx * ny == 4 {
        0.25
    } else if nx * ny == 2 {
        0.5
    } else {
        1.0
    };
    let mut w = [[0f32; 2]; 2];
    let mut k = [[NONE; 2]; 2];
    for b in 0..ny {
        for a in 0..nx {
            w[b][a] = base;
            k[b][a] = ckind(xa + a, ya + b);
        }
    }
    // Fold outside parents, farthest first.
    for (b, a) in [(1, 1), (0, 1), (1, 0)] {
        if b >= ny || a >= nx || k[b][a] != NONE || w[b][a] == 0.0 {
            continue;
        }
        let wt = std::mem::take(&mut w[b][a]);
        if a == 1 && k[b][0] != NONE {
            w[b][0] += wt;
        } else if b == 1 && k[0][a] != NONE {
            w[0][a] += wt;
        } else if k[0][0] != NONE {
            w[0][0] += wt;
        }
    }
    let mut out = [(0, 0, 0f32); 4];
    let mut n = 0;
    for b in 0..ny {
        for a in 0..nx {
            if k[b][a] == FREE && w[b][a] != 0.0 {
                out[n] = (xa + a, ya + b, w[b][a]);
                n += 1;
            }
        }
    }
    (out, n)
}

/// One grid of the hierarchy. Pixels are stored in four classes by the parities of `x` and `y`
/// (class `2·(y&1) + (x&1)`), each a padded grid of `(hh + 2) × (hw + 2)` cells with a ring of
/// zeros, so that a class can be updated in place while the others are read and every neighbour
/// access is valid without bounds checks.
struct Level {
    w: usize,
    h: usize,
    /// Cells per class row (without padding), `⌈w/2⌉`.
    hw: usize,
    /// [`NONE`], [`FIXED`] or [`FREE`] per pixel.
    kind: [Vec<u8>; 4],
    free: [Vec<bool>; 4],
    a: [Vec<Stencil>; 4],
    /// `1 / a_centre` at free pixels, 0 elsewhere (so updates need no branch). On the finest
    /// level (`five_point`) the off-diagonal entries are all −1 and non-free pixels hold 0, so a
    /// pixel's update is `(f + Σ u_n) / deg` without reading the stencil.
    inv_deg: [Vec<f32>; 4],
    /// `a_centre` (0 at non-free pixels).
    diag: [Vec<f32>; 4],
    u: [Vec<Vec2>; 4],
    f: [Vec<Vec2>; 4],
    r: [Vec<Vec2>; 4],
    /// True when every stencil has zero corners (the finest level).
    five_point: bool,
    /// The stencil of a pixel far from the boundary.
    interior: Stencil,
}

#[inline]
fn class(x: usize, y: usize) -> usize {
    ((y & 1) << 1) | (x & 1)
}

/// Geometry of a level, copyable into parallel closures.
#[derive(Clone, Copy)]
struct Geom {
    w: usize,
    h: usize,
    stride: usize,
}

impl Geom {
    /// Padded index of pixel `(x, y)` inside its class.
    #[inline]
    fn idx(&self, x: usize, y: usize) -> usize {
        ((y >> 1) + 1) * self.stride + (x >> 1) + 1
    }

    /// Number of pixels of class `q` in a class row, and number of class rows.
    #[inline]
    fn class_dims(&self, q: usize) -> (usize, usize) {
        ((self.w + 1 - (q & 1)) / 2, (self.h + 1 - (q >> 1)) / 2)
    }
}

/// The rows of the other three classes around class-`q` row `row`: a pixel at class column `k`
/// finds its left / right neighbours at `k + qx − 1` / `k + qx` of `h`, its upper / lower ones at
/// `k` of `up` / `down`, and the diagonal ones at `k + qx − 1`, `k + qx` of `dup` / `ddown`.
struct NeighbourRows<'a> {
    qx: usize,
    h: &'a [Vec2],
    up: &'a [Vec2],
    down: &'a [Vec2],
    dup: &'a [Vec2],
    ddown: &'a [Vec2],
}

impl<'a> NeighbourRows<'a> {
    #[inline]
    fn new(u: [&'a [Vec2]; 4], q: usize, row: usize, stride: usize) -> Self {
        let qy = q >> 1;
        let r = |c: usize, rr: usize| &u[c][rr * stride..(rr + 1) * stride];
        let (ru, rd) = (row + qy - 1, row + qy);
        NeighbourRows {
            qx: q & 1,
            h: r(q ^ 1, row),
            up: r(q ^ 2, ru),
            down: r(q ^ 2, rd),
            dup: r(q ^ 3, ru),
            ddown: r(q ^ 3, rd),
        }
    }

    /// `Σ u_n` over the four direct neighbours.
    #[inline(always)]
    fn sum4(&self, k: usize) -> Vec2 {
        let (l, r) = (k + self.qx - 1, k + self.qx);
        self.up[k] + self.h[l] + self.h[r] + self.down[k]
    }

    /// `Σ_{d ≠ centre} a_d u(x + d)` for a 5-point stencil (corners zero).
    #[inline(always)]
    fn sum5(&self, st: &Stencil, k: usize) -> Vec2 {
        let (l, r) = (k + self.qx - 1, k + self.qx);
        self.up[k] * st[1] + self.h[l] * st[3] + self.h[r] * st[5] + self.down[k] * st[7]
    }

    /// The same for a full 9-point stencil.
    #[inline(always)]
    fn sum9(&self, st: &Stencil, k: usize) -> Vec2 {
        let (l, r) = (k + self.qx - 1, k + self.qx);
        self.sum5(st, k) + self.dup[l] * st[0] + self.dup[r] * st[2] + self.ddown[l] * st[6] + self.ddown[r] * st[8]
    }
}

impl Level {
    /// A zeroed level of `w × h`. Five-point levels get `inv_deg` and `diag` but no stencils;
    /// nine-point levels get all three.
    fn new(w: usize, h: usize, five_point: bool) -> Level {
        let (hw, hh) = (w.div_ceil(2), h.div_ceil(2));
        let n = (hw + 2) * (hh + 2);
        fn four<T: Clone>(n: usize, v: T) -> [Vec<T>; 4] {
            [vec![v.clone(); n], vec![v.clone(); n], vec![v.clone(); n], vec![v; n]]
        }
        Level {
            w,
            h,
            hw,
            kind: four(n, NONE),
            free: four(n, false),
            a: four(if five_point { 0 } else { n }, [0.0; 9]),
            inv_deg: four(n, 0.0),
            diag: four(n, 0.0),
            u: four(n, Vec2::ZERO),
            f: four(n, Vec2::ZERO),
            r: four(n, Vec2::ZERO),
            five_point,
            interior: [0.0; 9],
        }
    }

    #[inline]
    fn geom(&self) -> Geom {
        Geom { w: self.w, h: self.h, stride: self.hw + 2 }
    }

    /// The kind of `(x, y)`, [`NONE`] off the grid.
    #[inline]
    fn kind_at(&self, x: usize, y: usize) -> u8 {
        if x < self.w && y < self.h { self.kind[class(x, y)][self.geom().idx(x, y)] } else { NONE }
    }

    fn set_kind(&mut self, x: usize, y: usize, k: u8) {
        let (q, i) = (class(x, y), self.geom().idx(x, y));
        self.kind[q][i] = k;
        self.free[q][i] = k == FREE;
    }

    /// The stencil of free pixel `(x, y)` (`None` if it is not free).
    #[inline]
    fn stencil(&self, x: usize, y: usize) -> Option<Stencil> {
        if x >= self.w || y >= self.h {
            return None;
        }
        let (q, i) = (class(x, y), self.geom().idx(x, y));
        if !self.free[q][i] {
            return None;
        }
        if !self.five_point {
            return Some(self.a[q][i]);
        }
        let nb = |dx: isize, dy: isize| {
            let (xx, yy) = (x as isize + dx, y as isize + dy);
            if xx >= 0 && yy >= 0 && self.kind_at(xx as usize, yy as usize) == FREE { -1.0 } else { 0.0 }
        };
        Some([0.0, nb(0, -1), 0.0, nb(-1, 0), 1.0 / self.inv_deg[q][i], nb(1, 0), 0.0, nb(0, 1), 0.0])
    }

    /// Row-major `w × h` map of the free pixels.
    fn free_grid(&self) -> Vec<bool> {
        let g = self.geom();
        let mut out = vec![false; self.w * self.h];
        out.par_chunks_mut(self.w).enumerate().for_each(|(y, row)| {
            for (x, v) in row.iter_mut().enumerate() {
                *v = self.free[class(x, y)][g.idx(x, y)];
            }
        });
        out
    }

    fn free_count(&self) -> usize {
        self.free.iter().map(|v| v.iter().filter(|&&b| b).count()).sum()
    }

    /// One Gauss–Seidel sweep, class by class; `reverse` visits the classes backwards (so that
    /// pre- and post-smoothing mirror each other).
    fn smooth(&mut self, reverse: bool) {
        for step in 0..4 {
            self.smooth_class(if reverse { 3 - step } else { step });
        }
    }

    fn smooth_class(&mut self, q: usize) {
        let g = self.geom();
        let (cw, ch) = g.class_dims(q);
        // Take class q out so the other three can be read while it is written.
        let mut mine = std::mem::take(&mut self.u[q]);
        let u: [&[Vec2]; 4] = [&self.u[0], &self.u[1], &self.u[2], &self.u[3]];
        let (f, inv, a, five) = (&self.f[q], &self.inv_deg[q], &self.a[q], self.five_point);
        for_rows(&mut mine, g.stride, ch, |row, out| {
            let rows = NeighbourRows::new(u, q, row, g.stride);
            let base = row * g.stride;
            let (f, inv) = (&f[base..base + g.stride], &inv[base..base + g.stride]);
            if five {
                for k in 1..=cw {
                    out[k] = (f[k] + rows.sum4(k)) * inv[k];
                }
            } else {
                let a = &a[base..base + g.stride];
                for k in 1..=cw {
                    out[k] = (f[k] - rows.sum9(&a[k], k)) * inv[k];
                }
            }
        });
        self.u[q] = mine;
    }

    /// `r = f − A u` on free pixels; returns `max |r| / a_centre`.
    fn residual(&mut self) -> f32 {
        let g = self.geom();
        let five = self.five_point;
        let u: [&[Vec2]; 4] = [&self.u[0], &self.u[1], &self.u[2], &self.u[3]];
        let mut worst = 0f32;
        for q in 0..4 {
            let (cw, ch) = g.class_dims(q);
            let (a, f, inv, diag) = (&self.a[q], &self.f[q], &self.inv_deg[q], &self.diag[q]);
            let m = max_over_rows(&mut self.r[q], g.stride, ch, |row, out| {
                let rows = NeighbourRows::new(u, q, row, g.stride);
                let base = row * g.stride;
                let mut mx = 0f32;
                for (k, o) in out.iter_mut().enumerate().take(cw + 1).skip(1) {
                    let i = base + k;
                    let inv = inv[i];
                    if inv == 0.0 {
                        continue;
                    }
                    let r = if five {
                        // Off-diagonals −1, diagonal 1 / inv.
                        f[i] + rows.sum4(k) - u[q][i] * diag[i]
                    } else {
                        f[i] - rows.sum9(&a[i], k) - u[q][i] * diag[i]
                    };
                    *o = r;
                    mx = mx.max(r.length_squared() * (inv * inv));
                }
                mx
            });
            worst = worst.max(m);
        }
        worst.sqrt()
    }

    /// The coarse level: unknowns at the free even pixels, operator `Pᵀ A P` (gathered per coarse
    /// node, in parallel over coarse rows); `None` when this grid should be the coarsest.
    fn coarsen(&self) -> Option<Level> {
        if self.w <= 3 || self.h <= 3 || self.free_count() <= 16 {
            return None;
        }
        // Coarse node (X, Y) sits on fine pixel (2X, 2Y); one node more than half, so that every
        // fine pixel has its parents on the grid.
        let (wc, hc) = (self.w / 2 + 1, self.h / 2 + 1);
        let mut c = Level::new(wc, hc, false);
        for yc in 0..hc {
            for xc in 0..wc {
                let (x, y) = (2 * xc, 2 * yc);
                let k = match self.kind_at(x, y) {
                    NONE => {
                        // Next to a fixed pixel: a (zero) wall, so Dirichlet boundaries stay closed.
                        let near = (x.saturating_sub(1)..=x + 1)
                            .any(|xx| (y.saturating_sub(1)..=y + 1).any(|yy| self.kind_at(xx, yy) == FIXED));
                        if near { FIXED } else { NONE }
                    }
                    k => k,
                };
                c.set_kind(xc, yc, k);
            }
        }
        if c.free_count() == 0 {
            return None;
        }
        // Away from the boundary every coarse stencil is the same: compute it once, with the same
        // arithmetic as the general case.
        let interior = self.interior;
        c.interior = galerkin_node(2, 2, |_, _| Some(interior), |_, _| FREE);
        // Fine pixels with the interior stencil whose 8 neighbours are all free.
        let (w, h) = (self.w, self.h);
        let free = self.free_grid();
        let mut standard = vec![false; w * h];
        standard.par_chunks_mut(w).enumerate().skip(1).take(h.saturating_sub(2)).for_each(|(y, row)| {
            let (up, mid, down) =
                (&free[(y - 1) * w..y * w], &free[y * w..(y + 1) * w], &free[(y + 1) * w..(y + 2) * w]);
            for x in 1..w.saturating_sub(1) {
                let all = up[x - 1..=x + 1].iter().chain(&mid[x - 1..=x + 1]).chain(&down[x - 1..=x + 1]).all(|&b| b);
                // On the finest level a pixel with four free neighbours has the interior stencil.
                row[x] = all && (self.five_point || self.stencil(x, y) == Some(interior));
            }
        });
        let cg = c.geom();
        let ckind = &c.kind;
        let ckind_at = |x: usize, y: usize| if x < wc && y < hc { ckind[class(x, y)][cg.idx(x, y)] } else { NONE };
        let coarse_interior = c.interior;
        for q in 0..4 {
            let (cw, ch) = cg.class_dims(q);
            c.a[q].par_chunks_mut(cg.stride).enumerate().skip(1).take(ch).for_each(|(row, out)| {
                let yc = 2 * (row - 1) + (q >> 1);
                for (k, o) in out.iter_mut().enumerate().take(cw + 1).skip(1) {
                    let xc = 2 * (k - 1) + (q & 1);
                    if ckind_at(xc, yc) != FREE {
                        continue;
                    }
                    // Interior: the nine fine pixels under the node are standard (so their
                    // neighbours are free) and so are the coarse neighbours (the fine corners).
                    let (x, y) = (2 * xc, 2 * yc);
                    let inside = xc >= 1
                        && yc >= 1
                        && x + 2 < w
                        && y + 2 < h
                        && (y - 1..=y + 1).all(|yy| standard[yy * w + x - 1..=yy * w + x + 1].iter().all(|&b| b))
                        && [(x - 2, y - 2), (x + 2, y - 2), (x - 2, y + 2), (x + 2, y + 2)]
                            .iter()
                            .all(|&(xx, yy)| free[yy * w + xx]);
                    *o = if inside {
                        coarse_interior
                    } else {
                        galerkin_node(xc, yc, |x, y| self.stencil(x, y), ckind_at)
                    };
                }
            });
        }
        c.inv_deg = std::array::from_fn(|q| {
            c.a[q].iter().zip(&c.free[q]).map(|(st, &f)| if f && st[4] > 0.0 { 1.0 / st[4] } else { 0.0 }).collect()
        });
        c.diag = std::array::from_fn(|q| {
            c.a[q].iter().zip(&c.free[q]).map(|(st, &f)| if f { st[4] } else { 0.0 }).collect()
        });
        Some(c)
    }

    /// `coarse.f = Pᵀ r`, `coarse.u = 0`.
    fn restrict_into(&self, coarse: &mut Level) {
        let (g, cg) = (self.geom(), coarse.geom());
        let (wc, hc) = (coarse.w, coarse.h);
        let (w, h) = (self.w, self.h);
        let ck = &coarse.kind;
        let ckind_at = |x: usize, y: usize| if x < wc && y < hc { ck[class(x, y)][cg.idx(x, y)] } else { NONE };
        let r = |x: usize, y: usize| self.r[class(x, y)][g.idx(x, y)];
        for q in 0..4 {
            let (cw, ch) = cg.class_dims(q);
            let free = &coarse.free[q];
            let fq = &mut coarse.f[q];
            for_rows(fq, cg.stride, ch, |row, out| {
                let yc = 2 * (row - 1) + (q >> 1);
                for k in 1..=cw {
                    if !free[row * cg.stride + k] {
                        out[k] = Vec2::ZERO;
                        continue;
                    }
                    let xc = 2 * (k - 1) + (q & 1);
                    let (x, y) = (2 * xc, 2 * yc);
                    out[k] = if x >= 1 && y >= 1 && x + 2 < w && y + 2 < h {
                        // Interior: weights ½ 1 ½ along both axes.
                        (r(x - 1, y - 1) + r(x + 1, y - 1) + r(x - 1, y + 1) + r(x + 1, y + 1)) * 0.25
                            + (r(x, y - 1) + r(x, y + 1) + r(x - 1, y) + r(x + 1, y)) * 0.5
                            + r(x, y)
                    } else {
                        let mut s = Vec2::ZERO;
                        for iy in y.saturating_sub(1)..(y + 2).min(h) {
                            for ix in x.saturating_sub(1)..(x + 2).min(w) {
                                if !self.free[class(ix, iy)][g.idx(ix, iy)] {
                                    continue;
                                }
                                let (p, n) = pweights(ix, iy, ckind_at);
                                if let Some(&(_, _, wt)) = p[..n].iter().find(|p| p.0 == xc && p.1 == yc) {
                                    s += r(ix, iy) * wt;
                                }
                            }
                        }
                        s
                    };
                }
            });
            coarse.u[q].iter_mut().for_each(|v| *v = Vec2::ZERO);
        }
    }

    /// `u += P e` on the free pixels, `e = coarse.u` (zero at coarse non-unknowns).
    fn prolong_from(&mut self, coarse: &Level) {
        let (g, cg) = (self.geom(), coarse.geom());
        let (w, h) = (self.w, self.h);
        let (wc, hc) = (coarse.w, coarse.h);
        let ckind_at =
            |x: usize, y: usize| if x < wc && y < hc { coarse.kind[class(x, y)][cg.idx(x, y)] } else { NONE };
        // The coarse values de-interleaved into one row-major grid, with one zero column and row
        // of margin so that odd pixels can read their second parents without checks.
        let cw1 = wc + 1;
        let mut e = vec![Vec2::ZERO; cw1 * (hc + 1)];
        e.par_chunks_mut(cw1).take(hc).enumerate().for_each(|(y, row)| {
            for (x, v) in row.iter_mut().take(wc).enumerate() {
                *v = coarse.u[class(x, y)][cg.idx(x, y)];
            }
        });
        for q in 0..4 {
            let (cw, ch) = g.class_dims(q);
            let (qx, qy) = (q & 1, q >> 1);
            let free = &self.free[q];
            let e = &e;
            for_rows(&mut self.u[q], g.stride, ch, |row, out| {
                let yc = row - 1;
                let y = 2 * yc + qy;
                let r0 = &e[yc * cw1..(yc + 1) * cw1];
                let r1 = &e[(yc + 1) * cw1..(yc + 2) * cw1];
                // Parents beyond the fine grid's far edge may be outside (Neumann): general path.
                let y_edge = qy == 1 && y + 1 >= h;
                let free = &free[row * g.stride..(row + 1) * g.stride];
                for (k, o) in out.iter_mut().enumerate().take(cw + 1).skip(1) {
                    if !free[k] {
                        continue;
                    }
                    let xc = k - 1;
                    let x = 2 * xc + qx;
                    if y_edge || (qx == 1 && x + 1 >= w) {
                        let (p, n) = pweights(x, y, ckind_at);
                        for &(px, py, wt) in &p[..n] {
                            *o += e[py * cw1 + px] * wt;
                        }
                        continue;
                    }
                    *o += match (qx, qy) {
                        (0, 0) => r0[xc],
                        (1, 0) => (r0[xc] + r0[xc + 1]) * 0.5,
                        (0, _) => (r0[xc] + r1[xc]) * 0.5,
                        _ => (r0[xc] + r0[xc + 1] + r1[xc] + r1[xc + 1]) * 0.25,
                    };
                }
            });
        }
    }
}

/// The Galerkin stencil `(Pᵀ A P)` of coarse node `(xc, yc)`: `fine(x, y)` is the stencil of a
/// free fine pixel, `ckind` the kind of a coarse node.
#[inline]
fn galerkin_node(
    xc: usize,
    yc: usize,
    fine: impl Fn(usize, usize) -> Option<Stencil>,
    ckind: impl Fn(usize, usize) -> u8 + Copy,
) -> Stencil {
    let mut st = [0f32; 9];
    for iy in (2 * yc).saturating_sub(1)..=2 * yc + 1 {
        for ix in (2 * xc).saturating_sub(1)..=2 * xc + 1 {
            let Some(ai) = fine(ix, iy) else { continue };
            let (pi, n) = pweights(ix, iy, ckind);
            let Some(&(_, _, wi)) = pi[..n].iter().find(|p| p.0 == xc && p.1 == yc) else { continue };
            for (kk, aij) in ai.iter().enumerate() {
                if *aij == 0.0 {
                    continue;
                }
                let (jx, jy) = (ix + kk % 3 - 1, iy + kk / 3 - 1);
                let (pj, m) = pweights(jx, jy, ckind);
                for &(jxc, jyc, wj) in &pj[..m] {
                    st[(jyc + 1 - yc) * 3 + (jxc + 1 - xc)] += wi * aij * wj;
                }
            }
        }
    }
    st
}

/// Below this many cells a level is processed on one thread: spreading it out costs more than
/// the work.
const PARALLEL_MIN: usize = 16 * 1024;

/// Calls `f(row, chunk)` for rows `1..=rows` of `data` (rows of `stride` cells), in parallel when
/// `data` is large.
fn for_rows<T: Send>(data: &mut [T], stride: usize, rows: usize, f: impl Fn(usize, &mut [T]) + Sync + Send) {
    if data.len() < PARALLEL_MIN {
        data.chunks_mut(stride).enumerate().skip(1).take(rows).for_each(|(r, c)| f(r, c));
    } else {
        data.par_chunks_mut(stride).enumerate().skip(1).take(rows).for_each(|(r, c)| f(r, c));
    }
}

/// Like [`for_rows`], returning the maximum of `f`.
fn max_over_rows<T: Send>(
    data: &mut [T],
    stride: usize,
    rows: usize,
    f: impl Fn(usize, &mut [T]) -> f32 + Sync + Send,
) -> f32 {
    if data.len() < PARALLEL_MIN {
        data.chunks_mut(stride).enumerate().skip(1).take(rows).map(|(r, c)| f(r, c)).fold(0.0, f32::max)
    } else {
        data.par_chunks_mut(stride).enumerate().skip(1).take(rows).map(|(r, c)| f(r, c)).reduce(|| 0.0, f32::max)
    }
}

/// One V-cycle. On entry `levels[0].r` holds the current residual (the thesis's cycle has no
/// pre-smoothing, so the residual of the convergence test is the one restricted); coarser levels
/// start from zero, so their residual is their right-hand side.
fn vcycle(levels: &mut [Level]) {
    let Some((fine, rest)) = levels.split_first_mut() else { return };
    if rest.is_empty() {
        // Coarsest grid: smooth until its residual has dropped 1000-fold.
        let r0 = fine.residual();
        for _ in 0..1000 {
            fine.smooth(false);
            if fine.residual() <= 1e-3 * r0 {
                break;
            }
        }
        return;
    }
    fine.restrict_into(&mut rest[0]);
    if rest.len() > 1 {
        // u = 0 on the coarse level: its residual is its right-hand side.
        let c = &mut rest[0];
        for q in 0..4 {
            c.r[q].copy_from_slice(&c.f[q]);
        }
    }
    vcycle(rest);
    fine.prolong_from(&rest[0]);
    for _ in 0..POST_SWEEPS {
        fine.smooth(true);
    }
}

/// The fine system over `rect` of the cells (5-point stencil over the free pixels, fixed
/// neighbours on the right-hand side) and its coarse levels.
fn build(cells: &Plane<Cell>, values: &Plane<Vec2>, (x0, y0, w, h): (usize, usize, usize, usize)) -> Vec<Level> {
    let (iw, ih) = cells.size();
    let mut fine = Level::new(w, h, true);
    fine.interior = [0.0, -1.0, 0.0, -1.0, 4.0, -1.0, 0.0, -1.0, 0.0];
    let g = fine.geom();
    let none_row = vec![Cell::Outside; iw];
    for y in 0..h {
        let gy = y0 + y;
        let (crow, vrow) = (cells.row(gy), values.row(gy));
        let up = if gy > 0 { cells.row(gy - 1) } else { &none_row };
        let down = if gy + 1 < ih { cells.row(gy + 1) } else { &none_row };
        let (vup, vdown) =
            (if gy > 0 { values.row(gy - 1) } else { vrow }, if gy + 1 < ih { values.row(gy + 1) } else { vrow });
        for x in 0..w {
            let gx = x0 + x;
            let (q, i) = (class(x, y), g.idx(x, y));
            match crow[gx] {
                Cell::Outside => continue,
                Cell::Fixed => {
                    fine.kind[q][i] = FIXED;
                    continue;
                }
                Cell::Free => {}
            }
            let mut deg = 0f32;
            let mut b = Vec2::ZERO;
            let left = if gx > 0 { Some((crow[gx - 1], vrow[gx - 1])) } else { None };
            let right = if gx + 1 < iw { Some((crow[gx + 1], vrow[gx + 1])) } else { None };
            for (c, v) in [left, right, Some((up[gx], vup[gx])), Some((down[gx], vdown[gx]))].into_iter().flatten() {
                match c {
                    Cell::Outside => {}
                    Cell::Fixed => {
                        deg += 1.0;
                        b += v;
                    }
                    Cell::Free => deg += 1.0,
                }
            }
            if deg == 0.0 {
                continue; // isolated: keeps its value
            }
            fine.kind[q][i] = FREE;
            fine.free[q][i] = true;
            fine.inv_deg[q][i] = 1.0 / deg;
            fine.diag[q][i] = deg;
            fine.f[q][i] = b;
            fine.u[q][i] = vrow[gx];
        }
    }
    let mut levels = vec![fine];
    while let Some(c) = levels.last().and_then(Level::coarsen) {
        levels.push(c);
    }
    levels
}

/// Solves Laplace's equation on the free cells of `cells`, with the values of `values` at fixed
/// cells as boundary conditions; the free values of `values` are the initial guess and receive
/// the solution. Outside cells are not touched. A free region that touches no fixed cell keeps
/// an arbitrary constant (Neumann everywhere); with no fixed value at all, or only zero ones, free
/// cells are set to zero. `tolerance` as in the module docs. Only the bounding box of the free
/// cells (and their neighbours) is worked on.
///
/// # Panics
///
/// If `cells` and `values` differ in size (a programming error: both describe the same grid).
pub fn solve(cells: &Plane<Cell>, values: &mut Plane<Vec2>, tolerance: f32) -> SolveReport {
    {
        let (w, h) = cells.size();
        assert_eq!(values.size(), (w, h), "cells and values must have the same size");
        let scale = cells
            .data()
            .iter()
            .zip(values.data())
            .filter(|(c, _)| **c == Cell::Fixed)
            .map(|(_, v)| v.length())
            .fold(0f32, f32::max);
        let threshold = tolerance.max(0.0) * scale;
        if scale == 0.0 || !scale.is_finite() {
            for (c, v) in cells.data().iter().zip(values.data_mut()) {
                if *c == Cell::Free {
                    *v = Vec2::ZERO;
                }
            }
            return SolveReport { cycles: 0, residual: 0.0, threshold, converged: scale == 0.0 };
        }
        // Bounding box of the free cells.
        let Some(free) = cells.bounds(|c| *c == Cell::Free) else {
            return SolveReport { cycles: 0, residual: 0.0, threshold, converged: true };
        };
        // Grown by one pixel so the fixed cells around the free ones are on the grid: only the image
        // edge may stay off it (a Neumann side).
        let crate::img::Rect { x0, y0, x1, y1 } = free.expand(1, w, h);
        let mut levels = build(cells, values, (x0, y0, x1 - x0, y1 - y0));
        let mut residual = levels[0].residual();
        let mut cycles = 0;
        while residual > threshold && cycles < MAX_CYCLES {
            if levels.len() == 1 {
                levels[0].smooth(false);
            } else {
                vcycle(&mut levels);
            }
            residual = levels[0].residual();
            cycles += 1;
        }
        let fine = &levels[0];
        let g = fine.geom();
        for y in 0..fine.h {
            let row = values.row_mut(y0 + y);
            for x in 0..fine.w {
                let (q, i) = (class(x, y), g.idx(x, y));
                if fine.free[q][i] {
                    row[x0 + x] = fine.u[q][i];
                }
            }
        }
        SolveReport { cycles, residual, threshold, converged: residual <= threshold }
    }
}

/// The slow reference: lexicographic Gauss–Seidel in `f64` until `max ρ_c ≤ 10⁻¹²·max|u_fixed|`.
#[cfg(test)]
pub(crate) fn solve_reference(cells: &Plane<Cell>, values: &Plane<Vec2>) -> Plane<glam::DVec2> {
    let (w, h) = cells.size();
    let mut u = Plane::from_fn(w, h, |x, y| {
        if cells.get(x, y) == Cell::Fixed { values.get(x, y).as_dvec2() } else { glam::DVec2::ZERO }
    });
    let scale = u.data().iter().map(|v| v.length()).fold(0f64, f64::max);
    let nbrs = |x: usize, y: usize| {
        let mut v = Vec::new();
        if x > 0 {
            v.push((x - 1, y));
        }
        if x + 1 < w {
            v.push((x + 1, y));
        }
        if y > 0 {
            v.push((x, y - 1));
        }
        if y + 1 < h {
            v.push((x, y + 1));
        }
        v.retain(|&(a, b)| cells.get(a, b) != Cell::Outside);
        v
    };
    for _ in 0..2_000_000 {
        let mut worst = 0f64;
        for y in 0..h {
            for x in 0..w {
                if cells.get(x, y) != Cell::Free {
                    continue;
                }
                let n = nbrs(x, y);
                if n.is_empty() {
                    continue;
                }
                let mean = n.iter().map(|&(a, b)| u.get(a, b)).sum::<glam::DVec2>() / n.len() as f64;
                worst = worst.max((mean - u.get(x, y)).length());
                u.set(x, y, mean);
            }
        }
        if worst <= 1e-12 * scale {
            break;
        }
    }
    u
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An irregular domain: a blob with a hole and a thin arm, touching the image's left edge.
    fn problem(w: usize, h: usize) -> (Plane<Cell>, Plane<Vec2>) {
        let inside = |x: usize, y: usize| {
            let (fx, fy) = (x as f32 - w as f32 * 0.5, y as f32 - h as f32 * 0.5);
            let r = (fx * fx + fy * fy).sqrt();
            let blob = r < w as f32 * 0.4 * (1.0 + 0.25 * (3.0 * fy.atan2(fx)).sin());
            let hole = ((fx - 4.0).powi(2) + (fy + 3.0).powi(2)).sqrt() < w as f32 * 0.08;
            let arm = y == h / 2 || y == h / 2 + 1;
            (blob && !hole) || arm
        };
        let cells = Plane::from_fn(w, h, |x, y| {
            if !inside(x, y) {
                return Cell::Outside;
            }
            let out = |a: isize, b: isize| {
                a >= 0 && b >= 0 && (a as usize) < w && (b as usize) < h && !inside(a as usize, b as usize)
            };
            let (xi, yi) = (x as isize, y as isize);
            if out(xi - 1, yi) || out(xi + 1, yi) || out(xi, yi - 1) || out(xi, yi + 1) {
                Cell::Fixed
            } else {
                Cell::Free
            }
        });
        let values = Plane::from_fn(w, h, |x, y| {
            if cells.get(x, y) == Cell::Fixed {
                Vec2::new((x as f32 * 0.3).sin() * 2.0, (y as f32 * 0.2).cos() + 0.5)
            } else {
                Vec2::ZERO
            }
        });
        (cells, values)
    }

    #[test]
    fn converges_below_tolerance_and_matches_reference() {
        let (cells, values) = problem(48, 40);
        let mut u = values.clone();
        let rep = solve(&cells, &mut u, TOLERANCE);
        assert!(rep.converged && rep.residual <= rep.threshold, "{rep:?}");
        assert!(rep.cycles >= 1 && rep.cycles < 30, "{rep:?}");
        let reference = solve_reference(&cells, &values);
        let scale = 2.5f64;
        let mut worst = 0f64;
        for y in 0..40 {
            for x in 0..48 {
                if cells.get(x, y) == Cell::Free {
                    worst = worst.max((u.get(x, y).as_dvec2() - reference.get(x, y)).length());
                } else if cells.get(x, y) == Cell::Fixed {
                    assert_eq!(u.get(x, y), values.get(x, y));
                }
            }
        }
        assert!(worst < 2e-3 * scale, "max difference to the reference {worst}");
    }

    #[test]
    fn each_v_cycle_reduces_the_residual_several_fold() {
        // The test domain touches the image's left and bottom edges (Neumann sides).
        for (w, h) in [(200, 160), (201, 161), (96, 150)] {
            let (cells, values) = problem(w, h);
            let mut levels = build(&cells, &values, (0, 0, w, h));
            assert!(levels.len() >= 4);
            let mut r = levels[0].residual();
            for cycle in 0..4 {
                vcycle(&mut levels);
                let next = levels[0].residual();
                eprintln!("{w}x{h}, cycle {cycle}: residual ratio {:.3}", next / r);
                assert!(next < 0.15 * r, "{w}x{h}, cycle {cycle}: {r} -> {next}");
                r = next;
            }
        }
    }

    #[test]
    fn default_tolerance_is_close_to_a_tight_solve() {
        let (cells, values) = problem(160, 140);
        let mut tight = values.clone();
        assert!(solve(&cells, &mut tight, 1e-6).converged);
        let mut u = values.clone();
        let rep = solve(&cells, &mut u, TOLERANCE);
        let scale = rep.threshold / TOLERANCE;
        let err = u.data().iter().zip(tight.data()).map(|(a, b)| (*a - *b).length()).fold(0f32, f32::max);
        eprintln!(
            "tolerance {TOLERANCE}: {} cycles, max |u − u(10⁻⁶)| = {err:.2e} ({:.3} % of max |g|)",
            rep.cycles,
            100.0 * err / scale
        );
        assert!(err < 0.01 * scale, "{err} vs {scale}");
    }

    #[test]
    fn tighter_tolerance_gets_closer_and_stays_fast() {
        let (cells, values) = problem(200, 160);
        let mut u = values.clone();
        let rep = solve(&cells, &mut u, 1e-6);
        assert!(rep.converged, "{rep:?}");
        // Multigrid: the number of cycles barely depends on the grid size.
        let (c2, v2) = problem(50, 40);
        let mut u2 = v2.clone();
        let rep2 = solve(&c2, &mut u2, 1e-6);
        assert!(rep.cycles <= rep2.cycles + 6, "{rep:?} vs {rep2:?}");
    }

    #[test]
    fn reproduces_a_linear_field_and_handles_degenerate_input() {
        // A linear field is harmonic: the solution must be it, wherever the boundary is.
        let (cells, _) = problem(64, 64);
        let lin = |x: usize, y: usize| Vec2::new(0.5 * x as f32 - 3.0, 0.25 * y as f32 + 1.0);
        let mut u = Plane::from_fn(64, 64, |x, y| if cells.get(x, y) == Cell::Fixed { lin(x, y) } else { Vec2::ZERO });
        let rep = solve(&cells, &mut u, 1e-6);
        assert!(rep.converged);
        for y in 0..64 {
            for x in 0..64 {
                if cells.get(x, y) == Cell::Free {
                    assert!((u.get(x, y) - lin(x, y)).length() < 1e-2, "{:?} vs {:?}", u.get(x, y), lin(x, y));
                }
            }
        }
        // No fixed values: zeros, immediately.
        let cells = Plane::filled(5, 5, Cell::Free);
        let mut u = Plane::filled(5, 5, Vec2::ONE);
        let rep = solve(&cells, &mut u, TOLERANCE);
        assert_eq!(rep.cycles, 0);
        assert!(u.data().iter().all(|v| *v == Vec2::ZERO));
    }
}
