//! Generalized PatchMatch over (i, x, y) with θ set by the flow-alignment rule (paper §4,
//! thesis §4.3): propagation with the rotation's Jacobian, random search in windows shrinking
//! by α, matches restricted to valid centers of the target pixel's segment.
//!
//! Parallel as in thesis §4.4.2, made deterministic: the field is cut into fixed bands of
//! [`TILE_ROWS`] rows processed in parallel; inside a band propagation uses the values updated
//! in this sweep, across band borders it reads the values from before the sweep (propagation
//! across tiles is delayed one iteration). Random numbers are keyed per pixel and sweep, so the
//! result does not depend on the thread count.

use super::nnf::{Match, Nnf, aligning_rotation};
use super::params::{HALF, PATCH, Params};
use super::patch::{OmegaMap, Query, patch_error};
use super::rng::Rng;
use super::source::{INTERIOR, SourceLevel, VALID, floor_i32};
use super::target::TargetLevel;
use glam::Vec2;
use rayon::prelude::*;

/// The rotations to try for a target pixel with flow direction `t_dir` and a source pixel with
/// `s_dir` (paper §4, thesis §4.3): M aligning the flows (θ_T − θ_S) and its +π alternative,
/// which compares ext± swapped. Where either flow is too small to have a direction, only θ = 0.
/// Returns the options and how many are valid.
#[inline]
pub(crate) fn rotations(params: &Params, t_dir: Vec2, s_dir: Vec2) -> ([(f32, f32, bool); 2], usize) {
    if t_dir == Vec2::ZERO || s_dir == Vec2::ZERO {
        return ([(1.0, 0.0, false); 2], 1);
    }
    if !params.direction_rule {
        // Ablation: θ = 0; the ext swap still follows the flows' relative direction.
        return ([(1.0, 0.0, t_dir.dot(s_dir) < 0.0); 2], 1);
    }
    let (c, s) = aligning_rotation(t_dir, s_dir);
    ([(c, s, false), (-c, -s, true)], 2)
}

/// The option of [`rotations`] of the same kind (aligned or flipped) as `flip`.
#[inline]
pub(crate) fn rotation_like(params: &Params, t_dir: Vec2, s_dir: Vec2, flip: bool) -> (f32, f32, bool) {
    let (opts, n) = rotations(params, t_dir, s_dir);
    if n == 2 && flip { opts[1] } else { opts[0] }
}

/// Rows per parallel band.
pub(crate) const TILE_ROWS: usize = 16;

/// What one PatchMatch run needs.
pub(crate) struct Ctx<'a> {
    pub src: &'a SourceLevel,
    pub tgt: &'a TargetLevel,
    pub omega: &'a OmegaMap,
    /// Color weight (0 for the guide-only initialization pass).
    pub w_col: f32,
    /// The parameters (α, the θ rule, the segment restriction).
    pub params: &'a Params,
    /// Keys of the random streams (seed, frame, level, EM iteration).
    pub keys: [u64; 4],
}

/// Counts of patch-error evaluations, for profiling.
#[derive(Clone, Copy, Debug, Default)]
pub struct Stats {
    /// Full or early-terminated evaluations.
    pub evaluations: u64,
}

impl Ctx<'_> {
    #[inline]
    fn query(&self, q: usize) -> Query {
        let (x, y) = (q % self.tgt.w, q / self.tgt.w);
        Query { tq: self.tgt.pindex(x, y), w_col: self.w_col, mw: self.tgt.mw[q] }
    }

    /// Segment (0 border, 1 interior) the candidates for target pixel q must come from:
    /// the pixel's own, unless the exemplar has no pixel in it.
    #[inline]
    pub fn wanted_segment(&self, q: usize) -> Option<usize> {
        let seg = self.tgt.segment(q);
        if !self.params.segments || self.src.valid[seg].is_empty() { None } else { Some(seg) }
    }

    /// The rotations to try for target pixel q and a source pixel with flow direction `s_dir`
    /// ([`rotations`]).
    #[inline]
    pub fn rotations(&self, q: usize, s_dir: Vec2) -> ([(f32, f32, bool); 2], usize) {
        rotations(self.params, self.tgt.info[q].dir, s_dir)
    }

    /// The rotation option of the same kind (aligned or flipped) as `flip`.
    #[inline]
    pub fn rotation_like(&self, q: usize, s_dir: Vec2, flip: bool) -> (f32, f32, bool) {
        rotation_like(self.params, self.tgt.info[q].dir, s_dir, flip)
    }

    /// Validates a candidate center: the nearest pixel is a valid center of the right segment.
    #[inline]
    pub fn check(&self, seg: Option<usize>, i: usize, x: f32, y: f32) -> Option<Vec2> {
        let (flags, dir) = self.src.hot_at(i, x, y)?;
        if flags & VALID == 0 {
            return None;
        }
        if let Some(seg) = seg
            && ((flags & INTERIOR != 0) as usize) != seg
        {
            return None;
        }
        Some(dir)
    }

    /// Hints the CPU to load the exemplar features and Ω rows a candidate at (i, x, y) reads.
    #[inline(always)]
    fn prefetch(&self, i: usize, x: f32, y: f32) {
        #[cfg(target_arch = "x86_64")]
        if let Some(idx) = self.src.nearest(i, x, y) {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            let stride = self.src.stride;
            let lo = idx.saturating_sub(HALF * stride + HALF);
            for r in 0..PATCH {
                let k = lo + r * stride;
                // SAFETY: SSE is part of the x86_64 baseline, and a prefetch is a hint that never
                // faults, whatever the address.
                unsafe {
                    _mm_prefetch::<_MM_HINT_T0>(self.src.feat.as_ptr().wrapping_add(k) as *const i8);
                    _mm_prefetch::<_MM_HINT_T0>(self.omega.as_ptr().wrapping_add(k) as *const i8);
                }
            }
        }
    }

    /// Full error of match `m` at target pixel q (∞ when its center is not usable).
    pub fn error_of(&self, q: usize, m: &Match) -> f32 {
        if !m.ok || self.src.info_at(m.i as usize, m.x, m.y).is_none_or(|(_, inf)| inf.flags & VALID == 0) {
            return f32::INFINITY;
        }
        patch_error(
            self.src,
            self.omega,
            self.tgt,
            self.query(q),
            m.i as usize,
            m.x,
            m.y,
            m.c,
            m.s,
            m.flip,
            f32::INFINITY,
        )
    }

    /// A uniformly random valid match for target pixel q.
    pub fn random_match(&self, q: usize, rng: &mut Rng) -> Match {
        let seg = self.wanted_segment(q).unwrap_or(if self.src.valid[0].is_empty() { 1 } else { 0 });
        let list = &self.src.valid[seg];
        if list.is_empty() {
            return Match::NONE;
        }
        let idx = list[rng.below(list.len())] as usize;
        let (i, x, y) = self.src.coords(idx);
        let (c, s, flip) = self.rotation_like(q, self.src.info[idx].dir, false);
        Match { x: x as f32, y: y as f32, c, s, err: f32::INFINITY, i: i as u16, flip, ok: true }
    }

    /// Tries candidate center (i, x, y) against `best` with θ set by the flow-alignment rule
    /// (paper §4): for propagation only the option of the neighbour's kind (aligned or flipped,
    /// `like`), for random search both.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn try_candidate(
        &self,
        q: usize,
        query: Query,
        best: &mut Match,
        i: usize,
        x: f32,
        y: f32,
        like: Option<bool>,
        stats: &mut Stats,
    ) {
        let Some(s_dir) = self.check(self.wanted_segment(q), i, x, y) else { return };
        let (opts, n) = match like {
            Some(f) => ([self.rotation_like(q, s_dir, f); 2], 1),
            None => self.rotations(q, s_dir),
        };
        for &(c, s, flip) in &opts[..n] {
            stats.evaluations += 1;
            let e = patch_error(self.src, self.omega, self.tgt, query, i, x, y, c, s, flip, best.err);
            if e < best.err {
                *best = Match { x, y, c, s, err: e, i: i as u16, flip, ok: true };
            }
        }
    }

    /// Improves the match of pixel q: propagation from the two already-visited neighbours
    /// (`n1`, `n2`, with the offsets `e1`, `e2` from them to q), then random search.
    #[allow(clippy::too_many_arguments)]
    fn improve(
        &self,
        q: usize,
        cur: Match,
        n1: Option<Match>,
        e1: (f32, f32),
        n2: Option<Match>,
        e2: (f32, f32),
        rng: &mut Rng,
        stats: &mut Stats,
    ) -> Match {
        let query = self.query(q);
        let mut best = cur;
        for (n, e) in [(n1, e1), (n2, e2)] {
            let Some(n) = n else { continue };
            if !n.ok {
                continue;
            }
            // Jacobian of the rotation: one step in the target is M·e in the source.
            let (dx, dy) = n.rotate(e.0, e.1);
            self.try_candidate(q, query, &mut best, n.i as usize, n.x + dx, n.y + dy, Some(n.flip), stats);
        }
        // Random search in windows of size α^k·(w, h, l_S) around the current best. The offsets
        // do not depend on the evaluations, so each is drawn one step ahead and the next
        // candidate's memory is prefetched while the current one is evaluated (the search is
        // bound by the latency of reading the exemplar at random places, not by arithmetic).
        let (mut rx, mut ry, mut ri) = (self.src.w as f32, self.src.h as f32, self.src.frames as f32);
        let alpha = self.params.alpha;
        let mut draw = |rng: &mut Rng| {
            if rx < 1.0 && ry < 1.0 {
                return None;
            }
            let o = (rng.range_f32(-rx, rx), rng.range_f32(-ry, ry), rng.range_f32(-ri, ri));
            (rx, ry, ri) = (rx * alpha, ry * alpha, ri * alpha);
            Some(o)
        };
        let last = (self.src.frames - 1) as f32;
        let at = |best: &Match, (ox, oy, oi): (f32, f32, f32)| {
            let x = floor_i32(best.x + ox + 0.5) as f32;
            let y = floor_i32(best.y + oy + 0.5) as f32;
            let i = (floor_i32(best.i as f32 + oi + 0.5) as f32).clamp(0.0, last);
            (i as usize, x, y)
        };
        let mut next = draw(rng);
        if let Some(o) = next {
            let (i, x, y) = at(&best, o);
            self.prefetch(i, x, y);
        }
        while let Some(o) = next {
            next = draw(rng);
            let (i, x, y) = at(&best, o);
            if let Some(o) = next {
                let (i, x, y) = at(&best, o);
                self.prefetch(i, x, y);
            }
            self.try_candidate(q, query, &mut best, i, x, y, None, stats);
        }
        best
    }
}

/// Recomputes the error of every match (after the target estimate or Ω changed).
pub(crate) fn refresh_errors(ctx: &Ctx, nnf: &mut Nnf) {
    let w = nnf.w;
    nnf.data.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, m) in row.iter_mut().enumerate() {
            if m.ok {
                m.err = ctx.error_of(y * w + x, m);
            }
        }
    });
}

/// One PatchMatch sweep (`iter` even: forward scan; odd: backward).
pub(crate) fn sweep(ctx: &Ctx, nnf: &mut Nnf, iter: usize) -> Stats {
    let (w, h) = (nnf.w, nnf.h);
    let snapshot = nnf.data.clone();
    let forward = iter.is_multiple_of(2);
    let step: isize = if forward { 1 } else { -1 };
    let active: Vec<bool> = ctx.tgt.info.iter().map(|i| i.flags & VALID != 0).collect();
    let stats: Vec<Stats> = nnf
        .data
        .par_chunks_mut(TILE_ROWS * w)
        .enumerate()
        .map(|(tile, chunk)| {
            let mut stats = Stats::default();
            let y0 = tile * TILE_ROWS;
            let rows = chunk.len() / w;
            let get = |chunk: &[Match], x: isize, y: isize| -> Option<Match> {
                if x < 0 || y < 0 || x >= w as isize || y >= h as isize {
                    return None;
                }
                let (x, y) = (x as usize, y as usize);
                if y >= y0 && y < y0 + rows { Some(chunk[(y - y0) * w + x]) } else { Some(snapshot[y * w + x]) }
            };
            for r in 0..rows {
                let y = if forward { y0 + r } else { y0 + rows - 1 - r };
                for c in 0..w {
                    let x = if forward { c } else { w - 1 - c };
                    let q = y * w + x;
                    if !active[q] {
                        continue;
                    }
                    let (xi, yi) = (x as isize, y as isize);
                    let n1 = get(chunk, xi - step, yi);
                    let n2 = get(chunk, xi, yi - step);
                    let mut rng =
                        Rng::keyed(&[ctx.keys[0], ctx.keys[1], ctx.keys[2], ctx.keys[3], iter as u64, q as u64]);
                    let cur = chunk[(y - y0) * w + x];
                    let e = step as f32;
                    let new = ctx.improve(q, cur, n1, (e, 0.0), n2, (0.0, e), &mut rng, &mut stats);
                    chunk[(y - y0) * w + x] = new;
                }
            }
            stats
        })
        .collect();
    Stats { evaluations: stats.iter().map(|s| s.evaluations).sum() }
}
