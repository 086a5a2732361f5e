//! Generalized PatchMatch over (i, x, y) with θ set by the flow-alignment rule (paper §4,
//! thesis §4.3): propagation with the rotation's Jacobian, random search in windows shrinking
//! by α, matches restricted to valid centers of the target pixel's segment.
//!
//! Parallel as in thesis §4.4.2, made deterministic: the field is cut into fixed bands of
//! [`tile_rows`] rows (a function of the field's height only) processed in parallel; inside a
//! band propagation uses the values updated in this sweep, across band borders it reads the
//! values from before the sweep (propagation across tiles is delayed one iteration). Random
//! numbers are keyed per pixel and sweep, so the result does not depend on the thread count.

use super::nnf::{Match, Nnf, aligning_rotation};
use super::params::{HALF, PATCH, Params};
use super::patch::{Center, Query, Window, patch_error, patch_error_pair};
use super::source::{BORDER_IN_MASK, Feat, IN_MASK, RESTING, SourceLevel, VALID, bit_set, floor4_i32};
use super::target::TargetLevel;
use crate::rng::SplitMix64;
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
    if !params.parts.direction_rule {
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

/// Rows per parallel band (at most; see [`tile_rows`]).
pub(crate) const TILE_ROWS: usize = 16;

/// Rows per band for a field of `h` rows: [`TILE_ROWS`], or fewer on small (coarse) fields so
/// that there are about 16 bands to share among the threads (4 rows at least). It depends only
/// on `h`, so the result does not depend on the thread count.
pub(crate) fn tile_rows(h: usize) -> usize {
    h.div_ceil(16).clamp(4, TILE_ROWS)
}

/// What one PatchMatch run needs.
pub(crate) struct Ctx<'a> {
    pub src: &'a SourceLevel,
    pub tgt: &'a TargetLevel,
    /// The exemplar pixels the search reads: `src.feat`, or a copy of it whose occurrence lane
    /// holds the current Ω penalty ([`super::occurrence::Occurrence`]).
    pub feat: &'a [Feat],
    /// Weight w_Ω of the occurrence lane (0 with `src.feat`).
    pub w_om: f32,
    /// Color weight (0 for the guide-only initialization pass).
    pub w_col: f32,
    /// The parameters (α, the θ rule, the segment restriction).
    pub params: &'a Params,
    /// Keys of the random streams (seed, frame, level, EM iteration).
    pub keys: [u64; 4],
    /// The half-sizes (x, y, i) of the random-search windows, α^k·(w, h, l_S) for k = 0, 1,
    /// … while the window is at least a pixel wide ([`search_radii`]), and how many there are.
    pub radii: [(f32, f32, f32); MAX_RANDOM],
    pub draws: usize,
}

/// The random-search windows of a level: α^k·(w, h, l_S) for k from 0 until both spatial
/// half-sizes are below one pixel, at most [`MAX_RANDOM`]; and how many.
pub(crate) fn search_radii(src: &SourceLevel, alpha: f32) -> ([(f32, f32, f32); MAX_RANDOM], usize) {
    let mut radii = [(0.0, 0.0, 0.0); MAX_RANDOM];
    let (mut sx, mut sy, mut si) = (src.w as f32, src.h as f32, src.frames as f32);
    let mut n = 0;
    while (sx >= 1.0 || sy >= 1.0) && n < MAX_RANDOM {
        radii[n] = (sx, sy, si);
        (sx, sy, si) = (sx * alpha, sy * alpha, si * alpha);
        n += 1;
    }
    (radii, n)
}

/// Counts of patch-error evaluations, for profiling.
#[derive(Clone, Copy, Debug, Default)]
pub struct Stats {
    /// Full or early-terminated evaluations.
    pub evaluations: u64,
}

impl<'a> Ctx<'a> {
    /// A search context; `omega` is the features with the occurrence lane filled and its
    /// weight ([`super::occurrence::Occurrence`]), `None` to search without the occurrence term.
    pub fn new(
        src: &'a SourceLevel,
        tgt: &'a TargetLevel,
        omega: Option<(&'a [Feat], f32)>,
        w_col: f32,
        params: &'a Params,
        keys: [u64; 4],
    ) -> Self {
        let (feat, w_om) = match omega {
            Some((feat, w)) => (feat, w),
            None => (&src.feat[..], 0.0),
        };
        let (radii, draws) = search_radii(src, params.schedule.alpha);
        Ctx { src, tgt, feat, w_om, w_col, params, keys, radii, draws }
    }

    #[inline]
    /// The target window of pixel q for [`patch_error`].
    pub fn window(&self, q: usize) -> Window {
        let (x, y) = (q % self.tgt.w, q / self.tgt.w);
        let query = Query { tq: self.tgt.pindex(x, y), w_col: self.w_col, mw: self.tgt.mw[q], w_om: self.w_om };
        Window::new(self.src, self.tgt, &query)
    }

    /// Segment (0 border, 1 interior) the candidates for target pixel q must come from:
    /// the pixel's own, unless the exemplar has no pixel in it; for a border pixel inside the
    /// target's mask, [`BORDER_IN_MASK`]: the border segment's centers inside the exemplar's
    /// mask (paint inside the shape comes from inside the paint), where the level has such a
    /// table and it is not empty.
    #[inline]
    pub fn wanted_segment(&self, q: usize) -> Option<usize> {
        let seg = self.tgt.segment(q);
        if !self.params.parts.segments || self.src.valid[seg].is_empty() {
            None
        } else if seg == 0 && self.tgt.info[q].flags & IN_MASK != 0 && self.src.border_in_mask > 0 {
            Some(BORDER_IN_MASK)
        } else {
            Some(seg)
        }
    }

    /// The rotations to try for target pixel q and a source pixel with flow direction `s_dir`
    /// ([`rotations`]).
    #[inline]
    pub fn rotations(&self, q: usize, s_dir: Vec2) -> ([(f32, f32, bool); 2], usize) {
        if let Some((c, s)) = self.spin(q, s_dir) {
            return ([(c, s, false); 2], 1);
        }
        rotations(self.params, self.tgt.info[q].dir, s_dir)
    }

    /// A still's rotation at target pixel q ([`TargetLevel::spin`]), where the rule has none to
    /// give: the source pixel has no flow direction.
    #[inline]
    fn spin(&self, q: usize, s_dir: Vec2) -> Option<(f32, f32)> {
        if s_dir == Vec2::ZERO { self.tgt.spin.get(q).copied() } else { None }
    }

    /// The rotation option of the same kind (aligned or flipped) as `flip`.
    #[inline]
    pub fn rotation_like(&self, q: usize, s_dir: Vec2, flip: bool) -> (f32, f32, bool) {
        if let Some((c, s)) = self.spin(q, s_dir) {
            return (c, s, false);
        }
        rotation_like(self.params, self.tgt.info[q].dir, s_dir, flip)
    }

    /// Validates a candidate center: the nearest pixel is a valid center of the right segment;
    /// returns its padded index.
    #[inline]
    pub fn check(&self, seg: Option<usize>, i: usize, x: f32, y: f32) -> Option<usize> {
        let idx = self.src.nearest(i, x, y)?;
        self.src.is_valid(seg, idx).then_some(idx)
    }

    /// The source direction the rule aligns target pixel q's with, at the exemplar pixel with
    /// padded index `idx`: its flow direction, or where q rests and takes its shape's normal
    /// ([`RESTING`]), the exemplar's own normal there ([`SourceLevel::normal`]).
    #[inline]
    pub fn s_dir(&self, q: usize, idx: usize) -> Vec2 {
        if self.tgt.info[q].flags & RESTING != 0 { self.src.normal(idx) } else { self.src.dirs[idx] }
    }

    /// Hints the CPU to load the exemplar rows a candidate at padded index `idx` reads.
    #[inline(always)]
    fn prefetch(&self, idx: usize) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            let stride = self.src.stride;
            let lo = idx.saturating_sub(HALF * stride + HALF);
            for r in 0..PATCH {
                let k = lo + r * stride;
                // SAFETY: SSE is part of the x86_64 baseline, and a prefetch is a hint that never
                // faults, whatever the address.
                unsafe {
                    _mm_prefetch::<_MM_HINT_T0>(self.feat.as_ptr().wrapping_add(k) as *const i8);
                }
            }
            // SAFETY: as above.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(self.src.dirs.as_ptr().wrapping_add(idx) as *const i8) };
        }
    }

    /// Full error of match `m` against the target window `win` (∞ when its center is not
    /// usable).
    pub fn error_in(&self, win: &Window, m: &Match) -> f32 {
        if !m.ok || self.check(None, m.i as usize, m.x, m.y).is_none() {
            return f32::INFINITY;
        }
        let at = Center { i: m.i as usize, cx: m.x, cy: m.y, c: m.c, s: m.s };
        patch_error(self.src, self.feat, win, at, m.flip, f32::INFINITY)
    }

    /// A uniformly random valid match for target pixel q.
    pub fn random_match(&self, q: usize, rng: &mut SplitMix64) -> Match {
        let wanted = self.wanted_segment(q);
        let seg = match wanted {
            Some(BORDER_IN_MASK) => 0,
            Some(s) => s,
            None => usize::from(self.src.valid[0].is_empty()),
        };
        let list = &self.src.valid[seg];
        if list.is_empty() {
            return Match::NONE;
        }
        // A few draws for a center inside the mask where one is wanted (most of the list is).
        let mut idx = list[rng.below(list.len())] as usize;
        for _ in 0..8 {
            if wanted.is_none_or(|s| self.src.is_valid(Some(s), idx)) {
                break;
            }
            idx = list[rng.below(list.len())] as usize;
        }
        let (i, x, y) = self.src.coords(idx);
        let (c, s, flip) = self.rotation_like(q, self.s_dir(q, idx), false);
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
        seg: Option<usize>,
        win: &Window,
        best: &mut Match,
        i: usize,
        x: f32,
        y: f32,
        like: Option<bool>,
        pen: f32,
        stats: &mut Stats,
    ) {
        let Some(idx) = self.check(seg, i, x, y) else { return };
        self.try_valid(q, win, best, self.s_dir(q, idx), i, x, y, like, pen, stats);
    }

    /// [`Ctx::try_candidate`] for a center already checked, whose flow direction is `s_dir`;
    /// `pen` (the candidate's seam cost) is added to its error, and `best.err` includes the
    /// best's.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn try_valid(
        &self,
        q: usize,
        win: &Window,
        best: &mut Match,
        s_dir: Vec2,
        i: usize,
        x: f32,
        y: f32,
        like: Option<bool>,
        pen: f32,
        stats: &mut Stats,
    ) {
        let (opts, n) = match like {
            Some(f) => ([self.rotation_like(q, s_dir, f); 2], 1),
            None => self.rotations(q, s_dir),
        };
        let coh = if like.is_none() { self.params.weights.coherence } else { 1.0 };
        let keep = |best: &mut Match, (c, s, flip): (f32, f32, bool), e: f32| {
            if e * coh + pen < best.err {
                *best = Match { x, y, c, s, err: e + pen, i: i as u16, flip, ok: true };
            }
        };
        // A candidate equal to the best match has exactly its error (the error is a function of
        // the match and the window, and the best's was computed in full), so it cannot win:
        // propagation in a coherent region proposes the current match itself most of the time.
        let same = |(c, s, flip): (f32, f32, bool)| {
            best.ok
                && best.i as usize == i
                && best.x == x
                && best.y == y
                && best.c == c
                && best.s == s
                && best.flip == flip
        };
        let todo = [!same(opts[0]), n == 2 && !same(opts[1])];
        // A candidate must get below best.err / κ to win: its error stops being summed there.
        let bound = (best.err - pen) / coh;
        if todo == [true, true] {
            // Both options of the rule (M and −M flipped) read the same 25 source pixels: one
            // pass gives both errors. The aligned one wins ties, as if tried first.
            stats.evaluations += 2;
            let (c, s, _) = opts[0];
            let (ea, ef) = patch_error_pair(self.src, self.feat, win, Center { i, cx: x, cy: y, c, s }, bound);
            keep(best, opts[0], ea);
            keep(best, opts[1], ef);
            return;
        }
        for (&opt, _) in opts.iter().zip(todo).filter(|&(_, t)| t) {
            stats.evaluations += 1;
            let (c, s, flip) = opt;
            let e =
                patch_error(self.src, self.feat, win, Center { i, cx: x, cy: y, c, s }, flip, (best.err - pen) / coh);
            keep(best, opt, e);
        }
    }

    /// Improves the match of pixel q: its error recomputed, then propagation from the two
    /// already-visited neighbours (`n1`, `n2`, with the offsets `e1`, `e2` from them to q), then
    /// random search. Every candidate is judged by its patch error plus its seam cost against
    /// all four neighbours (`ahead`: the two not yet visited, at −`e1` and −`e2`, as they were
    /// before the sweep). Returns the new match (its error without the seams) and the
    /// recomputed error of `cur` (∞ when `cur` is not usable).
    #[allow(clippy::too_many_arguments)]
    fn improve(
        &self,
        q: usize,
        cur: Match,
        n1: Option<Match>,
        e1: (f32, f32),
        n2: Option<Match>,
        e2: (f32, f32),
        ahead: [Option<Match>; 2],
        rng: &mut SplitMix64,
        stats: &mut Stats,
    ) -> (Match, f32) {
        let win = self.window(q);
        let seg = self.wanted_segment(q);
        // The seam cost of a candidate (i, x, y): c per neighbour whose match it does not
        // continue (`ParamsBuilder::seam_cost`); the comparisons below are of error plus seams.
        // The center each usable neighbour's match continues to at q, (i, x + M·e, y + M·e),
        // is computed once here; a candidate counts the ones it is not within half a pixel of
        // (branch-free: the slots of missing neighbours hold NaN, which no candidate is near).
        let cost = self.params.weights.seam_cost;
        let around = [(n1, e1), (n2, e2), (ahead[0], (-e1.0, -e1.1)), (ahead[1], (-e2.0, -e2.1))];
        let conts = around.map(|(n, e)| {
            n.filter(|n| n.ok).map(|n| {
                let (dx, dy) = n.rotate(e.0, e.1);
                (n.i, n.x + dx, n.y + dy)
            })
        });
        let (ci, cx, cy) = (
            conts.map(|c| c.map_or(0, |c| c.0)),
            conts.map(|c| c.map_or(f32::NAN, |c| c.1)),
            conts.map(|c| c.map_or(f32::NAN, |c| c.2)),
        );
        let live = conts.iter().flatten().count() as u32;
        let seams = |i: u16, x: f32, y: f32| -> f32 {
            if cost == 0.0 {
                return 0.0;
            }
            let mut near = 0;
            for k in 0..4 {
                near += ((ci[k] == i) & ((cx[k] - x).abs() < 0.5) & ((cy[k] - y).abs() < 0.5)) as u32;
            }
            cost * (live - near) as f32
        };
        // The current match's error under this context (the target estimate and Ω change
        // between sweeps), from the window the search uses anyway.
        let mut best = Match { err: self.error_in(&win, &cur), ..cur };
        let refreshed = best.err;
        best.err += seams(best.i, best.x, best.y);
        stats.evaluations += refreshed.is_finite() as u64;
        // Jacobian of the rotation: one step in the target is M·e in the source (`conts`).
        for (n, cont) in [n1, n2].into_iter().zip(conts) {
            let (Some(n), Some((i, cx, cy))) = (n, cont) else { continue };
            let pen = seams(i, cx, cy);
            self.try_candidate(q, seg, &win, &mut best, i as usize, cx, cy, Some(n.flip), pen, stats);
        }
        // Random search (thesis §4.3): candidate k is drawn uniformly from α^k·(±w, ±h, ±l_S)
        // around v0, the match after propagation (as in PatchMatch), for k from 0 until the
        // window is below one pixel. (The thesis's cuboid is half as wide; on the identity
        // test the wider one found the exemplar's own patches more often, 31 vs 26 dB at seed
        // 5.) The candidates do not depend on the evaluations, so they are all drawn first,
        // those outside the frame or the segment's valid centers dropped (a bit table), and
        // the memory of candidate k + AHEAD is prefetched while candidate k is evaluated.
        let v0 = best;
        let src = self.src;
        let last = src.frames as i32 - 1;
        let valid = src.valid_table(seg);
        // (padded index, frame, x, y) of each draw, and whether it is a valid center.
        let mut drawn = [(0u32, 0u16, 0u16, 0u16, false); MAX_RANDOM];
        for (d, &(sx, sy, si)) in drawn.iter_mut().zip(&self.radii[..self.draws]) {
            let (ox, oy, oi) = (rng.range(-sx, sx), rng.range(-sy, sy), rng.range(-si, si));
            let [x, y, i, _] = floor4_i32([v0.x + ox + 0.5, v0.y + oy + 0.5, v0.i as f32 + oi + 0.5, 0.0]);
            let i = i.clamp(0, last);
            // Negative coordinates wrap to large unsigned ones.
            let inside = (x as u32) < src.w as u32 && (y as u32) < src.h as u32;
            let (x, y) = if inside { (x as usize, y as usize) } else { (0, 0) };
            let idx = src.index(i as usize, x, y);
            // Indices fit 32 bits and coordinates 16 (the exemplar's size limits).
            *d = (idx as u32, i as u16, x as u16, y as u16, inside & bit_set(valid, idx));
        }
        // The valid ones, but for a repeat of one of the last three kept (small windows repeat
        // candidates; an evaluation of the same one gains nothing). A separate pass, so that the
        // validity look-ups above (at random places of the bit table) do not wait for each
        // other through `recent`. Branch-free: whether a draw is kept is data the CPU cannot
        // predict, so every draw is written and only the kept ones advance `n`.
        let mut cands = [(0u32, 0u16, 0u16, 0u16); MAX_RANDOM];
        let mut n = 0usize;
        let mut recent = [u32::MAX; 3];
        for &(key, i, x, y, valid) in &drawn[..self.draws] {
            let keep = valid & (key != recent[0]) & (key != recent[1]) & (key != recent[2]);
            cands[n] = (key, i, x, y);
            if keep {
                recent = [key, recent[0], recent[1]];
            }
            n += keep as usize;
        }
        for c in &cands[..n.min(AHEAD)] {
            self.prefetch(c.0 as usize);
        }
        for k in 0..n {
            if k + AHEAD < n {
                self.prefetch(cands[k + AHEAD].0 as usize);
            }
            let (idx, i, x, y) = cands[k];
            let s_dir = self.s_dir(q, idx as usize);
            let pen = seams(i, x as f32, y as f32);
            self.try_valid(q, &win, &mut best, s_dir, i as usize, x as f32, y as f32, None, pen, stats);
        }
        // The field keeps the patch error alone.
        if best.ok && best.err.is_finite() {
            best.err -= seams(best.i, best.x, best.y);
        }
        (best, refreshed)
    }
}

/// Most random-search candidates per pixel and sweep (α = 0.75 on a 4096-pixel exemplar needs
/// 29; α = 0.85, 51: the search then stops at the 40th).
const MAX_RANDOM: usize = 40;
/// How many candidates ahead of the evaluation the random search prefetches.
const AHEAD: usize = 2;

/// One PatchMatch sweep (`iter` even: forward scan; odd: backward). The errors stored in the
/// field are not trusted (the target estimate or Ω may have changed): each pixel's is
/// recomputed first. Returns the statistics and the energy before the sweep, the mean of those
/// recomputed errors over the pixels with a usable match.
pub(crate) fn sweep(ctx: &Ctx, nnf: &mut Nnf, iter: usize) -> (Stats, f64) {
    let (w, h) = (nnf.w, nnf.h);
    let rows_per_band = tile_rows(h);
    let snapshot = nnf.data.clone();
    let forward = iter.is_multiple_of(2);
    let step: isize = if forward { 1 } else { -1 };
    let stats: Vec<(Stats, f64, u64)> = nnf
        .data
        .par_chunks_mut(rows_per_band * w)
        .enumerate()
        .map(|(tile, chunk)| {
            let mut stats = Stats::default();
            let (mut energy, mut scored) = (0.0f64, 0u64);
            let y0 = tile * rows_per_band;
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
                    if ctx.tgt.info[q].flags & VALID == 0 {
                        continue;
                    }
                    let (xi, yi) = (x as isize, y as isize);
                    let n1 = get(chunk, xi - step, yi);
                    let n2 = get(chunk, xi, yi - step);
                    let mut rng =
                        SplitMix64::keyed(&[ctx.keys[0], ctx.keys[1], ctx.keys[2], ctx.keys[3], iter as u64, q as u64]);
                    let cur = chunk[(y - y0) * w + x];
                    let e = step as f32;
                    let ahead = [get(chunk, xi + step, yi), get(chunk, xi, yi + step)];
                    let (new, refreshed) = ctx.improve(q, cur, n1, (e, 0.0), n2, (0.0, e), ahead, &mut rng, &mut stats);
                    if refreshed.is_finite() {
                        energy += refreshed as f64;
                        scored += 1;
                    }
                    chunk[(y - y0) * w + x] = new;
                }
            }
            (stats, energy, scored)
        })
        .collect();
    let evaluations = stats.iter().map(|s| s.0.evaluations).sum::<u64>();
    let (energy, scored) = stats.iter().fold((0.0, 0), |(e, n), s| (e + s.1, n + s.2));
    (Stats { evaluations }, if scored > 0 { energy / scored as f64 } else { 0.0 })
}
