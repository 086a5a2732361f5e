//! Texture fidelity: how far output patches are from their nearest exemplar patches.
//!
//! The search is a branch-and-bound nearest-neighbour search in a kd-tree built over the
//! exemplar patches projected onto their first [`PCA_DIMS`] principal components. A
//! projection onto orthonormal axes never lengthens a difference, so the distance in the
//! projected space is a lower bound of the full 75-value distance: subtrees and points whose
//! bound is not below the best full distance found so far can be skipped without missing the
//! nearest neighbour. Only the budget of [`PatchParams::checks`] makes the search approximate.

use super::{Mean, Measure};
use crate::img::{Mask, Plane, Rgb};
use crate::rng::SplitMix64;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Side of the compared patches (the synthesis's n = 5).
pub const PATCH_SIZE: usize = 5;
/// Dimensions of the projected space the kd-tree is built in.
pub const PCA_DIMS: usize = 12;
const HALF: usize = PATCH_SIZE / 2;
/// Values per patch: 5 × 5 pixels × RGB.
const DIM: usize = PATCH_SIZE * PATCH_SIZE * 3;
const ROW: usize = PATCH_SIZE * 3;
const LEAF: usize = 8;

/// Sampling and search budget of [`patch_nn_distance`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PatchParams {
    /// Output patches sampled over the whole sequence (spread evenly over the frames).
    /// Default: 2048.
    pub samples: usize,
    /// Most exemplar patches indexed; with more interior patches than this, every k-th one
    /// (in raster order per frame) is kept. Default: 400 000.
    pub pool: usize,
    /// Most exemplar patches examined per query before the search settles for the best so
    /// far. Default: 4096.
    pub checks: usize,
    /// Seed of the sampling of output patches. Default: 1.
    pub seed: u64,
}

impl Default for PatchParams {
    fn default() -> Self {
        PatchParams { samples: 2048, pool: 400_000, checks: 4096, seed: 1 }
    }
}

/// Centers whose whole patch lies inside the image and whose center is in `region`.
fn centers(region: &Mask) -> Vec<u32> {
    let (w, h) = region.size();
    let mut out = Vec::new();
    if w < PATCH_SIZE || h < PATCH_SIZE {
        return out;
    }
    for y in HALF..h - HALF {
        for x in HALF..w - HALF {
            if region.get(x, y) {
                out.push((y * w + x) as u32);
            }
        }
    }
    out
}

#[inline]
fn extract(img: &Plane<Rgb>, x: usize, y: usize, out: &mut [f32; DIM]) {
    for r in 0..PATCH_SIZE {
        let row = &img.row(y + r - HALF)[x - HALF..x + HALF + 1];
        for (i, c) in row.iter().enumerate() {
            out[r * ROW + 3 * i..r * ROW + 3 * i + 3].copy_from_slice(c);
        }
    }
}

/// Sum of squared differences, giving up (returning a value `>= limit`) once a full patch row
/// has pushed the running sum to `limit`.
#[inline]
fn ssd(a: &[f32; DIM], b: &[f32; DIM], limit: f32) -> f32 {
    let mut acc = 0.0;
    for (ra, rb) in a.chunks_exact(ROW).zip(b.chunks_exact(ROW)) {
        acc += ra.iter().zip(rb).map(|(p, q)| (p - q) * (p - q)).sum::<f32>();
        if acc >= limit {
            return acc;
        }
    }
    acc
}

/// Mean and orthonormal principal axes of a set of patches (power iteration with
/// Gram–Schmidt deflation; any orthonormal axes keep the lower bound valid, good ones make it
/// tight).
struct Projection {
    mean: [f32; DIM],
    axes: [[f32; DIM]; PCA_DIMS],
}

impl Projection {
    fn fit(patches: &[[f32; DIM]]) -> Projection {
        let n = patches.len().max(1) as f64;
        let mut mean = [0f64; DIM];
        for p in patches {
            for (m, &v) in mean.iter_mut().zip(p) {
                *m += v as f64;
            }
        }
        mean.iter_mut().for_each(|m| *m /= n);
        // Covariance by accumulating outer products patch by patch (each patch stays in
        // cache), upper triangle only, in parallel chunks.
        let upper: Vec<f64> = patches
            .par_chunks(512)
            .map(|chunk| {
                let mut acc = vec![0f64; DIM * DIM];
                let mut c = [0f64; DIM];
                for p in chunk {
                    for (ci, (&v, m)) in c.iter_mut().zip(p.iter().zip(&mean)) {
                        *ci = v as f64 - m;
                    }
                    for i in 0..DIM {
                        let ci = c[i];
                        for (a, &cj) in acc[i * DIM + i..(i + 1) * DIM].iter_mut().zip(&c[i..]) {
                            *a += ci * cj;
                        }
                    }
                }
                acc
            })
            .collect::<Vec<_>>()
            // Summed in chunk order: the same result whatever the thread count.
            .into_iter()
            .fold(vec![0f64; DIM * DIM], |a, b| a.iter().zip(&b).map(|(x, y)| x + y).collect());
        let mut cov = vec![0f64; DIM * DIM];
        for i in 0..DIM {
            for j in i..DIM {
                cov[i * DIM + j] = upper[i * DIM + j] / n;
                cov[j * DIM + i] = upper[i * DIM + j] / n;
            }
        }
        let mut axes = [[0f32; DIM]; PCA_DIMS];
        let mut found: Vec<[f64; DIM]> = Vec::with_capacity(PCA_DIMS);
        for (k, axis) in axes.iter_mut().enumerate() {
            let mut v = [0f64; DIM];
            for (i, x) in v.iter_mut().enumerate() {
                // A deterministic start that is not orthogonal to much.
                *x = 1.0 + ((i * 7 + k * 13) % 11) as f64 * 0.1;
            }
            for _ in 0..60 {
                let mut next = [0f64; DIM];
                for (i, o) in next.iter_mut().enumerate() {
                    *o = cov[i * DIM..(i + 1) * DIM].iter().zip(&v).map(|(c, x)| c * x).sum();
                }
                orthonormalize(&mut next, &found);
                v = next;
            }
            orthonormalize(&mut v, &found);
            found.push(v);
            *axis = v.map(|x| x as f32);
        }
        Projection { mean: mean.map(|m| m as f32), axes }
    }

    #[inline]
    fn apply(&self, p: &[f32; DIM]) -> [f32; PCA_DIMS] {
        let mut out = [0f32; PCA_DIMS];
        for (o, axis) in out.iter_mut().zip(&self.axes) {
            *o = p.iter().zip(&self.mean).zip(axis).map(|((v, m), a)| (v - m) * a).sum();
        }
        out
    }
}

/// Removes the components along `basis` and normalizes; falls back to a unit vector
/// orthogonal to `basis` when nothing is left (a degenerate, e.g. flat, exemplar).
fn orthonormalize(v: &mut [f64; DIM], basis: &[[f64; DIM]]) {
    for _ in 0..2 {
        for b in basis {
            let d: f64 = v.iter().zip(b).map(|(x, y)| x * y).sum();
            v.iter_mut().zip(b).for_each(|(x, y)| *x -= d * y);
        }
    }
    let len = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    if len > 1e-12 {
        v.iter_mut().for_each(|x| *x /= len);
        return;
    }
    for e in 0..DIM {
        let mut u = [0f64; DIM];
        u[e] = 1.0;
        for b in basis {
            let d = b[e];
            u.iter_mut().zip(b).for_each(|(x, y)| *x -= d * y);
        }
        let len = u.iter().map(|x| x * x).sum::<f64>().sqrt();
        if len > 1e-3 {
            *v = u.map(|x| x / len);
            return;
        }
    }
}

enum Node {
    Leaf { start: u32, end: u32 },
    Split { dim: u8, value: f32, left: u32, right: u32 },
}

/// The exemplar side of the search: its interior patches, projected and organized in a
/// kd-tree. Build it once with [`PatchIndex::build`] and query it with
/// [`PatchIndex::nearest`].
pub struct PatchIndex<'a> {
    frames: &'a [Plane<Rgb>],
    /// `(frame, x, y)` of each indexed patch, in tree order.
    positions: Vec<(u32, u32, u32)>,
    /// Projected coordinates, in tree order.
    points: Vec<[f32; PCA_DIMS]>,
    nodes: Vec<Node>,
    projection: Projection,
    checks: usize,
}

impl<'a> PatchIndex<'a> {
    /// Indexes the exemplar patches whose centers lie in `regions` (`regions[i]` belongs to
    /// `frames[i]`), at most `params.pool` of them. Deterministic.
    pub fn build(frames: &'a [Plane<Rgb>], regions: &'a [Mask], params: &PatchParams) -> Self {
        let per_frame: Vec<Vec<u32>> = regions.par_iter().map(centers).collect();
        let total: usize = per_frame.iter().map(Vec::len).sum();
        let keep_every = total.div_ceil(params.pool.max(1)).max(1);
        let mut positions: Vec<(u32, u32, u32)> = Vec::with_capacity(total / keep_every + per_frame.len());
        for (f, list) in per_frame.iter().enumerate() {
            let w = frames[f].width() as u32;
            positions.extend(list.iter().step_by(keep_every).map(|&p| (f as u32, p % w, p / w)));
        }
        let patch_at = |&(f, x, y): &(u32, u32, u32)| {
            let mut buf = [0f32; DIM];
            extract(&frames[f as usize], x as usize, y as usize, &mut buf);
            buf
        };
        // Principal axes from an evenly spread sample of at most 20 000 patches.
        let sample_every = positions.len().div_ceil(20_000).max(1);
        let sample: Vec<[f32; DIM]> = positions.iter().step_by(sample_every).map(patch_at).collect();
        let projection = Projection::fit(&sample);
        let points: Vec<[f32; PCA_DIMS]> = positions.par_iter().map(|p| projection.apply(&patch_at(p))).collect();
        let mut order: Vec<u32> = (0..positions.len() as u32).collect();
        let mut nodes = Vec::new();
        if !order.is_empty() {
            build_tree(&points, &mut order, 0, &mut nodes);
        }
        let positions = order.iter().map(|&i| positions[i as usize]).collect();
        let points = order.iter().map(|&i| points[i as usize]).collect();
        PatchIndex { frames, positions, points, nodes, projection, checks: params.checks.max(1) }
    }

    /// Number of indexed exemplar patches.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True without indexed patches (the exemplar has no interior patch).
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Distance from `patch` (5 × 5 pixels of RGB, row by row: 75 values) to its nearest
    /// indexed exemplar patch, as the RMS difference per value `sqrt(SSD / 75)`; `None`
    /// without indexed patches. Exact unless the search exhausts its budget of checks.
    pub fn nearest(&self, patch: &[f32; DIM]) -> Option<f32> {
        if self.nodes.is_empty() {
            return None;
        }
        let q = self.projection.apply(patch);
        let mut search = Search { best: f32::INFINITY, checked: 0, buf: [0f32; DIM] };
        self.visit(0, patch, &q, &mut search);
        Some((search.best.max(0.0) / DIM as f32).sqrt())
    }

    fn visit(&self, node: usize, patch: &[f32; DIM], q: &[f32; PCA_DIMS], s: &mut Search) {
        match self.nodes[node] {
            Node::Leaf { start, end } => {
                for i in start as usize..end as usize {
                    let p = &self.points[i];
                    let bound: f32 = q.iter().zip(p).map(|(a, b)| (a - b) * (a - b)).sum();
                    if bound < s.best {
                        let (f, x, y) = self.positions[i];
                        extract(&self.frames[f as usize], x as usize, y as usize, &mut s.buf);
                        s.best = s.best.min(ssd(patch, &s.buf, s.best));
                    }
                }
                s.checked += (end - start) as usize;
            }
            Node::Split { dim, value, left, right } => {
                let diff = q[dim as usize] - value;
                let (near, far) = if diff < 0.0 { (left, right) } else { (right, left) };
                self.visit(near as usize, patch, q, s);
                if diff * diff < s.best && s.checked < self.checks {
                    self.visit(far as usize, patch, q, s);
                }
            }
        }
    }
}

struct Search {
    best: f32,
    checked: usize,
    buf: [f32; DIM],
}

/// Builds the subtree over `order` (indices into `points`), splitting at the median of the
/// dimension of largest spread; returns the node's index.
fn build_tree(points: &[[f32; PCA_DIMS]], order: &mut [u32], offset: usize, nodes: &mut Vec<Node>) -> u32 {
    let id = nodes.len() as u32;
    if order.len() <= LEAF {
        nodes.push(Node::Leaf { start: offset as u32, end: (offset + order.len()) as u32 });
        return id;
    }
    let mut lo = [f32::INFINITY; PCA_DIMS];
    let mut hi = [f32::NEG_INFINITY; PCA_DIMS];
    for &i in order.iter() {
        for d in 0..PCA_DIMS {
            lo[d] = lo[d].min(points[i as usize][d]);
            hi[d] = hi[d].max(points[i as usize][d]);
        }
    }
    let dim = (0..PCA_DIMS).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])).then(b.cmp(&a))).unwrap_or(0);
    let mid = order.len() / 2;
    order.select_nth_unstable_by(mid, |&a, &b| {
        points[a as usize][dim].total_cmp(&points[b as usize][dim]).then(a.cmp(&b))
    });
    let value = points[order[mid] as usize][dim];
    nodes.push(Node::Split { dim: dim as u8, value, left: 0, right: 0 });
    let (left_part, right_part) = order.split_at_mut(mid);
    let left = build_tree(points, left_part, offset, nodes);
    let right = build_tree(points, right_part, offset + mid, nodes);
    nodes[id as usize] = Node::Split { dim: dim as u8, value, left, right };
    id
}

/// Texture fidelity of a sequence: the mean distance of output patches to their nearest
/// exemplar patches.
///
/// Exactly, it estimates `mean over output interior patches P of min over exemplar interior
/// patches Q of sqrt(‖P − Q‖² / 75)` (5×5 RGB patches, sRGB `0..=1`, centers in
/// `out_regions` / `ex_regions`, windows inside the image) — the RMS color difference to the
/// best-matching exemplar patch, without rotations (a rotated copy of an exemplar patch scores
/// above 0). Approximations: `params.samples` output patches drawn at random (evenly per
/// frame) stand in for all of them; when the exemplar has more than `params.pool` interior
/// patches only every k-th is searched; the search itself is exact over those but stops after
/// `params.checks` candidates per query (then the value is an upper bound). A copy of the
/// exemplar scores 0. Deterministic for a given seed; independent of the thread count.
///
/// Per frame: the mean over that frame's samples. `None` where there is no sample.
pub fn patch_nn_distance(
    output: &[Plane<Rgb>],
    out_regions: &[Mask],
    exemplar: &[Plane<Rgb>],
    ex_regions: &[Mask],
    params: &PatchParams,
) -> Measure {
    let index = PatchIndex::build(exemplar, ex_regions, params);
    patch_nn_distance_with(&index, output, out_regions, params)
}

/// [`patch_nn_distance`] against a prebuilt [`PatchIndex`].
pub fn patch_nn_distance_with(
    index: &PatchIndex<'_>,
    output: &[Plane<Rgb>],
    out_regions: &[Mask],
    params: &PatchParams,
) -> Measure {
    let n = output.len().min(out_regions.len());
    if n == 0 {
        return Measure::default();
    }
    let per_frame_samples = params.samples.div_ceil(n).max(1);
    let means: Vec<Mean> = (0..n)
        .map(|f| frame_patch_mean(index, &output[f], &out_regions[f], f, per_frame_samples, params.seed))
        .collect();
    Measure::from_means(&means)
}

/// The patch statistic of frame `f` of a sequence: `samples` query centers drawn in `region`
/// (seeded by `seed` and `f`, so a frame's queries do not depend on the other frames) and the
/// mean of their nearest-patch distances.
pub(crate) fn frame_patch_mean(
    index: &PatchIndex<'_>,
    img: &Plane<Rgb>,
    region: &Mask,
    f: usize,
    samples: usize,
    seed: u64,
) -> Mean {
    let list = centers(region);
    if list.is_empty() {
        return Mean::default();
    }
    let mut rng = SplitMix64::new(seed.wrapping_add(0x9E37_79B9).wrapping_mul(f as u64 + 1));
    let w = img.width();
    let queries: Vec<(usize, usize)> = (0..samples.min(list.len()))
        .map(|_| {
            let p = list[rng.below(list.len())] as usize;
            (p % w, p / w)
        })
        .collect();
    let dists: Vec<Option<f32>> = queries
        .par_iter()
        .map(|&(x, y)| {
            let mut buf = [0f32; DIM];
            extract(img, x, y, &mut buf);
            index.nearest(&buf)
        })
        .collect();
    // Summed in query order: the same result whatever the thread count.
    let mut mean = Mean::default();
    dists.into_iter().flatten().for_each(|d| mean.add(d as f64));
    mean
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tree_search_equals_brute_force_with_enough_checks() {
        let mut rng = SplitMix64::new(5);
        let mut rnd = move || (rng.next_u64() >> 40) as f32 / (1u64 << 24) as f32;
        let frames: Vec<Plane<Rgb>> = (0..2)
            .map(|_| {
                let base = Plane::from_fn(40, 30, |_, _| [rnd(), rnd(), rnd()]);
                crate::img::gaussian_blur(&base, 1.0)
            })
            .collect();
        let regions = vec![Plane::filled(40, 30, true); 2];
        let p = PatchParams { checks: usize::MAX, ..Default::default() };
        let index = PatchIndex::build(&frames, &regions, &p);
        assert_eq!(index.len(), 2 * 36 * 26);
        let query_img = crate::img::gaussian_blur(&Plane::from_fn(20, 20, |_, _| [rnd(), rnd(), rnd()]), 1.0);
        for (x, y) in [(2, 2), (10, 7), (17, 17), (5, 12)] {
            let mut q = [0f32; DIM];
            extract(&query_img, x, y, &mut q);
            let mut best = f32::INFINITY;
            let mut buf = [0f32; DIM];
            for (f, img) in frames.iter().enumerate() {
                let _ = f;
                for cy in 2..28 {
                    for cx in 2..38 {
                        extract(img, cx, cy, &mut buf);
                        best = best.min(ssd(&q, &buf, f32::INFINITY));
                    }
                }
            }
            let brute = (best / DIM as f32).sqrt();
            let tree = index.nearest(&q).unwrap();
            assert!((brute - tree).abs() < 1e-6, "{brute} vs {tree}");
        }
        // A patch of the exemplar itself is found exactly.
        let mut q = [0f32; DIM];
        extract(&frames[1], 20, 15, &mut q);
        assert_eq!(index.nearest(&q), Some(0.0));
    }
}
