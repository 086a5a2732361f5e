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
//! `A u = b` over the free pixels. Coarse node `(X, Y)` sits on fine pixel `(2X, 2Y)` and is an
//! unknown when that pixel is free; the prolongation `P` is bilinear from the free coarse nodes
//! (a missing coarse node counts as zero, the Dirichlet condition, except beyond the grid's edge,
//! where the nearer node is used alone, the Neumann condition); the restriction is `Pᵀ`; the
//! coarse operator is the Galerkin product `Pᵀ A P`, a 9-point stencil. Because every coarse
//! operator is derived from the fine one, irregular boundaries and image edges need no special
//! geometry on coarse grids. Each V-cycle does [`PRE_SWEEPS`] Gauss–Seidel sweep before and
//! [`POST_SWEEPS`] after the coarse-grid correction; the coarsest grid is smoothed until its own
//! residual has dropped 1000-fold. Gauss–Seidel visits the pixels in four colour classes (the
//! parities of x and y, so that no two pixels of a class share a 9-point stencil), each class in
//! parallel over rows: the result does not depend on the number of threads.

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
/// Gauss–Seidel sweeps before each coarse-grid correction.
pub const PRE_SWEEPS: usize = 1;
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

/// Weights of the coarse parents of fine coordinate `i` along one axis of a grid whose coarse
/// size is `nc`: `(first parent, weight, second weight)`; the second parent is `first + 1`.
#[inline]
fn parents(i: usize, nc: usize) -> (usize, f32, f32) {
    if i & 1 == 0 {
        (i / 2, 1.0, 0.0)
    } else if i / 2 + 1 < nc {
        (i / 2, 0.5, 0.5)
    } else {
        (i / 2, 1.0, 0.0)
    }
}

/// Weight of coarse node `c` as a parent of fine coordinate `i`.
#[inline]
fn weight_of(i: usize, c: usize, nc: usize) -> f32 {
    let (p, w0, w1) = parents(i, nc);
    if c == p {
        w0
    } else if c == p + 1 {
        w1
    } else {
        0.0
    }
}

/// One grid of the hierarchy. Pixels are stored in four classes by the parities of `x` and `y`
/// (class `2·(y&1) + (x&1)`), each a padded grid of `(hh + 2) × (hw + 2)` cells with a ring of
/// zeros, so that a class can be updated in place while the others are read and every neighbour
/// access is valid without bounds checks.
struct Level {
    w: usize,
    h: usize,
    /// Cells per class row and class rows (without padding), `⌈w/2⌉`, `⌈h/2⌉`.
    hw: usize,
    hh: usize,
    free: [Vec<bool>; 4],
    a: [Vec<Stencil>; 4],
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
    fn empty(w: usize, h: usize) -> Level {
        let (hw, hh) = (w.div_ceil(2), h.div_ceil(2));
        let n = (hw + 2) * (hh + 2);
        let four = |v| [vec![v; n], vec![v; n], vec![v; n], vec![v; n]];
        Level {
            w,
            h,
            hw,
            hh,
            free: [vec![false; n], vec![false; n], vec![false; n], vec![false; n]],
            a: [vec![[0.0; 9]; n], vec![[0.0; 9]; n], vec![[0.0; 9]; n], vec![[0.0; 9]; n]],
            u: four(Vec2::ZERO),
            f: four(Vec2::ZERO),
            r: four(Vec2::ZERO),
            five_point: false,
            interior: [0.0; 9],
        }
    }

    #[inline]
    fn geom(&self) -> Geom {
        Geom { w: self.w, h: self.h, stride: self.hw + 2 }
    }

    #[inline]
    fn is_free(&self, x: usize, y: usize) -> bool {
        self.free[class(x, y)][self.geom().idx(x, y)]
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
        let five = self.five_point;
        // Take class q out so the other three can be read while it is written.
        let mut mine = std::mem::take(&mut self.u[q]);
        let u: [&[Vec2]; 4] = [&self.u[0], &self.u[1], &self.u[2], &self.u[3]];
        let (free, a, f) = (&self.free[q], &self.a[q], &self.f[q]);
        mine.par_chunks_mut(g.stride).enumerate().skip(1).take(ch).for_each(|(row, out)| {
            let rows = NeighbourRows::new(u, q, row, g.stride);
            let base = row * g.stride;
            for k in 1..=cw {
                let i = base + k;
                if !free[i] {
                    continue;
                }
                let st = &a[i];
                let s = if five { rows.sum5(st, k) } else { rows.sum9(st, k) };
                out[k] = (f[i] - s) / st[4];
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
            let (free, a, f) = (&self.free[q], &self.a[q], &self.f[q]);
            let m = self.r[q]
                .par_chunks_mut(g.stride)
                .enumerate()
                .skip(1)
                .take(ch)
                .map(|(row, out)| {
                    let rows = NeighbourRows::new(u, q, row, g.stride);
                    let base = row * g.stride;
                    let mut mx = 0f32;
                    for k in 1..=cw {
                        let i = base + k;
                        if !free[i] {
                            continue;
                        }
                        let st = &a[i];
                        let s = if five { rows.sum5(st, k) } else { rows.sum9(st, k) };
                        let r = f[i] - s - u[q][i] * st[4];
                        out[k] = r;
                        mx = mx.max(r.length() / st[4]);
                    }
                    mx
                })
                .reduce(|| 0.0, f32::max);
            worst = worst.max(m);
        }
        worst
    }

    /// The coarse level: unknowns at the free even pixels, operator `Pᵀ A P` (gathered per coarse
    /// node, in parallel over coarse rows); `None` when this grid should be the coarsest.
    fn coarsen(&self) -> Option<Level> {
        if self.w <= 3 || self.h <= 3 || self.free_count() <= 16 {
            return None;
        }
        let (wc, hc) = (self.w.div_ceil(2), self.h.div_ceil(2));
        let mut c = Level::empty(wc, hc);
        let cg = c.geom();
        for yc in 0..hc {
            for xc in 0..wc {
                c.free[class(xc, yc)][cg.idx(xc, yc)] = self.is_free(2 * xc, 2 * yc);
            }
        }
        if c.free_count() == 0 {
            return None;
        }
        let g = self.geom();
        // Away from the boundary every coarse stencil is the same: compute it once, with the same
        // arithmetic as the general case.
        let interior = self.interior;
        c.interior = galerkin_node(2, 2, 1 << 20, 1 << 20, |_, _| Some(&interior), |_, _| true);
        let standard: [Vec<bool>; 4] =
            std::array::from_fn(|q| self.free[q].iter().zip(&self.a[q]).map(|(&f, st)| f && *st == interior).collect());
        let cfree = &c.free;
        let cfree_at = |x: usize, y: usize| x < wc && y < hc && cfree[class(x, y)][cg.idx(x, y)];
        let fine_at = |x: usize, y: usize| {
            let (q, i) = (class(x, y), g.idx(x, y));
            self.free[q][i].then(|| &self.a[q][i])
        };
        let (w, h) = (self.w, self.h);
        let coarse_interior = c.interior;
        for q in 0..4 {
            let (cw, ch) = cg.class_dims(q);
            c.a[q].par_chunks_mut(cg.stride).enumerate().skip(1).take(ch).for_each(|(row, out)| {
                let yc = 2 * (row - 1) + (q >> 1);
                for k in 1..=cw {
                    let xc = 2 * (k - 1) + (q & 1);
                    if !cfree_at(xc, yc) {
                        continue;
                    }
                    let inside = xc >= 1
                        && yc >= 1
                        && 2 * xc + 2 < w
                        && 2 * yc + 2 < h
                        && (2 * yc - 2..=2 * yc + 2).all(|y| {
                            (2 * xc - 2..=2 * xc + 2).all(|x| {
                                let (qq, i) = (class(x, y), g.idx(x, y));
                                let near = x + 1 >= 2 * xc && x <= 2 * xc + 1 && y + 1 >= 2 * yc && y <= 2 * yc + 1;
                                self.free[qq][i] && (!near || standard[qq][i])
                            })
                        });
                    out[k] = if inside { coarse_interior } else { galerkin_node(xc, yc, wc, hc, fine_at, cfree_at) };
                }
            });
        }
        Some(c)
    }

    /// `coarse.f = Pᵀ r`, `coarse.u = 0`.
    fn restrict_into(&self, coarse: &mut Level) {
        let (g, cg) = (self.geom(), coarse.geom());
        let (wc, hc) = (coarse.w, coarse.h);
        let (w, h) = (self.w, self.h);
        let r = |x: usize, y: usize| self.r[class(x, y)][g.idx(x, y)];
        for q in 0..4 {
            let (cw, ch) = cg.class_dims(q);
            let free = &coarse.free[q];
            coarse.f[q].par_chunks_mut(cg.stride).enumerate().skip(1).take(ch).for_each(|(row, out)| {
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
                            let wy = weight_of(iy, yc, hc);
                            for ix in x.saturating_sub(1)..(x + 2).min(w) {
                                let wxy = weight_of(ix, xc, wc) * wy;
                                if wxy != 0.0 {
                                    s += r(ix, iy) * wxy;
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
        let (wc, hc) = (coarse.w, coarse.h);
        // The coarse values as one padded grid per class; a fine pixel of class (qx, qy) reads
        // coarse node (k, j) and, for odd coordinates, (k + 1) / (j + 1).
        let cu = |x: usize, y: usize| coarse.u[class(x, y)][cg.idx(x, y)];
        for q in 0..4 {
            let (cw, ch) = g.class_dims(q);
            let (qx, qy) = (q & 1, q >> 1);
            let free = &self.free[q];
            self.u[q].par_chunks_mut(g.stride).enumerate().skip(1).take(ch).for_each(|(row, out)| {
                let yc = row - 1;
                let y_pair = qy == 1 && yc + 1 < hc;
                let wy = if qy == 1 && y_pair { 0.5 } else { 1.0 };
                for k in 1..=cw {
                    if !free[row * g.stride + k] {
                        continue;
                    }
                    let xc = k - 1;
                    let x_pair = qx == 1 && xc + 1 < wc;
                    let wx = if x_pair { 0.5 } else { 1.0 };
                    let mut e = cu(xc, yc);
                    if x_pair {
                        e += cu(xc + 1, yc);
                    }
                    if y_pair {
                        e += cu(xc, yc + 1);
                        if x_pair {
                            e += cu(xc + 1, yc + 1);
                        }
                    }
                    out[k] += e * (wx * wy);
                }
            });
        }
    }
}

/// The Galerkin stencil `(Pᵀ A P)` of coarse node `(xc, yc)` on a coarse grid of `wc × hc`:
/// `fine(x, y)` is the fine stencil of a free fine pixel, `cfree` tells which coarse nodes are
/// unknowns.
#[inline]
fn galerkin_node<'a>(
    xc: usize,
    yc: usize,
    wc: usize,
    hc: usize,
    fine: impl Fn(usize, usize) -> Option<&'a Stencil>,
    cfree: impl Fn(usize, usize) -> bool,
) -> Stencil {
    let mut st = [0f32; 9];
    for iy in (2 * yc).saturating_sub(1)..(2 * yc + 2).min(2 * hc) {
        let wy = weight_of(iy, yc, hc);
        if wy == 0.0 {
            continue;
        }
        for ix in (2 * xc).saturating_sub(1)..(2 * xc + 2).min(2 * wc) {
            let wx = weight_of(ix, xc, wc);
            let Some(ai) = fine(ix, iy).filter(|_| wx != 0.0) else { continue };
            let pi = wx * wy;
            for (kk, aij) in ai.iter().enumerate() {
                if *aij == 0.0 {
                    continue;
                }
                let jx = ix + kk % 3 - 1;
                let jy = iy + kk / 3 - 1;
                let (px, px0, px1) = parents(jx, wc);
                let (py, py0, py1) = parents(jy, hc);
                for (jyc, wyj) in [(py, py0), (py + 1, py1)] {
                    if wyj == 0.0 {
                        continue;
                    }
                    for (jxc, wxj) in [(px, px0), (px + 1, px1)] {
                        if wxj == 0.0 || !cfree(jxc, jyc) {
                            continue;
                        }
                        st[(jyc + 1 - yc) * 3 + (jxc + 1 - xc)] += pi * aij * wxj * wyj;
                    }
                }
            }
        }
    }
    st
}

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
    for _ in 0..PRE_SWEEPS {
        fine.smooth(false);
    }
    fine.residual();
    fine.restrict_into(&mut rest[0]);
    vcycle(rest);
    fine.prolong_from(&rest[0]);
    for _ in 0..POST_SWEEPS {
        fine.smooth(true);
    }
}

/// The fine system over `rect` of the cells (5-point stencil over the free pixels, fixed
/// neighbours on the right-hand side) and its coarse levels.
fn build(cells: &Plane<Cell>, values: &Plane<Vec2>, x0: usize, y0: usize, w: usize, h: usize) -> Vec<Level> {
    let (iw, ih) = cells.size();
    let mut fine = Level::empty(w, h);
    fine.five_point = true;
    fine.interior = [0.0, -1.0, 0.0, -1.0, 4.0, -1.0, 0.0, -1.0, 0.0];
    let g = fine.geom();
    for y in 0..h {
        let (crow, vrow) = (cells.row(y0 + y), values.row(y0 + y));
        for x in 0..w {
            let gx = x0 + x;
            if crow[gx] != Cell::Free {
                continue;
            }
            let mut st = [0f32; 9];
            let mut b = Vec2::ZERO;
            for (k, (dx, dy)) in [(3, (-1, 0)), (5, (1, 0)), (1, (0, -1)), (7, (0, 1))] {
                let (xx, yy) = (gx as isize + dx, (y0 + y) as isize + dy);
                if xx < 0 || yy < 0 || xx as usize >= iw || yy as usize >= ih {
                    continue;
                }
                let (xx, yy) = (xx as usize, yy as usize);
                match cells.get(xx, yy) {
                    Cell::Outside => continue,
                    Cell::Fixed => b += values.get(xx, yy),
                    Cell::Free => st[k] = -1.0,
                }
                st[4] += 1.0;
            }
            if st[4] == 0.0 {
                continue; // isolated: keeps its value
            }
            let (q, i) = (class(x, y), g.idx(x, y));
            fine.free[q][i] = true;
            fine.a[q][i] = st;
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
pub fn solve(cells: &Plane<Cell>, values: &mut Plane<Vec2>, tolerance: f32) -> SolveReport {
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
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for y in 0..h {
        let row = cells.row(y);
        if let Some(first) = row.iter().position(|c| *c == Cell::Free) {
            let last = row.iter().rposition(|c| *c == Cell::Free).unwrap_or(first);
            (x0, x1, y0, y1) = (x0.min(first), x1.max(last + 1), y0.min(y), y + 1);
        }
    }
    if x1 <= x0 {
        return SolveReport { cycles: 0, residual: 0.0, threshold, converged: true };
    }
    let mut levels = build(cells, values, x0, y0, x1 - x0, y1 - y0);
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
