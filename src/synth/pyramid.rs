//! The multi-scale driver of one frame (paper Appendix B, Algorithm 1; thesis §4.2): from the
//! coarsest pyramid level to the finest, [`level`] builds the target's level, votes the
//! temporal guide `T^prev` from the down-scaled shifted field ([`temporal_guide`]), initializes
//! the field ([`initial_field`]: a random field and a guide-only pass on the first frame,
//! UPSCALENNF and MERGENNF after) and runs the EM iterations ([`optimize`]: occurrence map,
//! PatchMatch, vote). The finest level is only voted unless
//! [`ParamsBuilder::optimize_finest`](super::ParamsBuilder::optimize_finest) is set; its vote
//! is the output.

use super::nnf::{Match, Nnf};
use super::params::{PATCH, Params};
use super::patchmatch::{self, Ctx};
use super::source::{self, MARGIN, SourceLevel, SourcePyramid};
use super::target::{self, TargetLevel};
use super::{StageTimes, occurrence, shift, timed, tone, vote};
use crate::guide::FrameGuides;
use crate::img::{Plane, Rgb};
use crate::rng::SplitMix64;
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// What one frame's pyramid works from.
pub(crate) struct FrameInputs<'a> {
    /// The exemplar's pyramid.
    pub src: &'a SourcePyramid,
    /// The target's guides per level, finest first (cropped to the working window).
    pub pyr: &'a [FrameGuides],
    /// The parameters of this frame (the first frame's differ, see `Synthesizer::step`).
    pub params: &'a Params,
    /// The frame's index (a key of its random streams).
    pub frame: usize,
    /// The previous frame's field shifted in time (SHIFTNNF) at full resolution, and the
    /// previous frame's masks per level; `None` on the first frame or when nothing is carried.
    pub prev: Option<(&'a Nnf, &'a [Vec<bool>])>,
    /// Also compute the occurrence view of the debug output.
    pub debug: bool,
}

/// What one frame's pyramid produced.
pub(crate) struct FrameOutcome {
    /// The final field at the finest level.
    pub field: Nnf,
    /// The output's colors over the working window (row-major).
    pub rgb: Vec<Rgb>,
    /// The target's masks per level (carried to the next frame for m(q)).
    pub masks: Vec<Vec<bool>>,
    /// Time per level, coarsest first.
    pub level_times: Vec<Duration>,
    /// Patch-error evaluations.
    pub evaluations: u64,
    /// The energy at every PatchMatch sweep, `(level, E)`.
    pub energy: Vec<(usize, f64)>,
    /// Ω* of the finest optimized level, summed over frames (debug only).
    pub omega: Option<Plane<f32>>,
}

/// Runs the pyramid of one frame, coarsest level first.
pub(crate) fn run(f: &FrameInputs, st: &mut StageTimes) -> FrameOutcome {
    let levels = f.pyr.len();
    let mut out = FrameOutcome {
        field: Nnf::new(0, 0),
        rgb: Vec::new(),
        masks: vec![Vec::new(); levels],
        level_times: Vec::with_capacity(levels),
        evaluations: 0,
        energy: Vec::new(),
        omega: None,
    };
    let mut coarse: Option<Nnf> = None;
    for l in (0..levels).rev() {
        let t0 = Instant::now();
        coarse = Some(level(f, l, coarse.take(), st, &mut out));
        out.level_times.push(t0.elapsed());
    }
    let (w, h) = f.pyr[0].mask.size();
    out.field = coarse.unwrap_or_else(|| Nnf::new(w, h));
    out
}

/// One pyramid level `l`: the target level, the temporal guide, the initial field (from the
/// coarser level's field `coarse`, or none at the coarsest), the EM iterations, and at the
/// finest level the output's vote. Returns the level's field.
fn level(f: &FrameInputs, l: usize, coarse: Option<Nnf>, st: &mut StageTimes, out: &mut FrameOutcome) -> Nnf {
    let (src, p) = (f.src, f.params);
    let levels = f.pyr.len();
    let sl = &src.levels[l];
    let gl = &f.pyr[l];
    let ext_cap = p.parts.ext_clamp.then_some(src.ext_max);
    let mut tgt = timed(&mut st.target, || {
        TargetLevel::new(gl, &src.quant, src.border_width, ext_cap, sl.ext_falloff, src.paper, p.parts.resting_normal)
    });
    out.masks[l] = shift::mask_flags(&tgt);
    let prev_down = temporal_guide(f, l, &mut tgt, st);
    let lv = Level {
        src: sl,
        params: p,
        frame: f.frame,
        level: l,
        from_coarsest: levels - 1 - l,
        finest_vote_only: l == 0 && levels > 1 && !p.schedule.optimize_finest,
        paper: src.paper,
        size: gl.mask.size(),
    };
    // The occurrence map's buffers, kept through the level's iterations.
    let mut occ = occurrence::Occurrence::new();
    let mut field = initial_field(&lv, &mut tgt, coarse, prev_down, &mut occ, st, out);
    if !lv.finest_vote_only {
        optimize(&lv, &mut tgt, &mut field, &mut occ, st, out);
        if f.debug {
            let counts = occurrence::counts(sl, &field, &tgt, p.schedule.occ_radius);
            let norm = ((PATCH * PATCH) * (2 * p.schedule.occ_radius + 1)) as f32;
            out.omega = Some(Plane::from_fn(sl.w, sl.h, |x, y| {
                (0..sl.frames).map(|i| counts[sl.index(i, x, y)] as f32).sum::<f32>() / norm
            }));
        }
    }
    if l == 0 {
        // The output: bicubic sampling keeps rotated patches sharper than bilinear; its tone
        // matched to the exemplar's by depth before the grain is added back (`tone`).
        out.rgb = timed(&mut st.vote, || {
            let (mut low, grain): (Vec<Rgb>, Vec<Rgb>) = if p.parts.keep_grain {
                vote::vote_grain_parts(sl, &field, src.paper, p.schedule.vote_sigma, p.parts.grain_phase)
                    .into_iter()
                    .unzip()
            } else {
                (vote::vote_with(sl, &field, src.paper, p.schedule.vote_sigma, true), Vec::new())
            };
            // The depths at which the exemplar is read (`ParamsBuilder::depth_stretch`).
            let depth = if p.parts.depth_stretch && p.parts.tone_match {
                std::borrow::Cow::Owned(tone::tone_depths(&gl.dist, &gl.mask, &field, &src.tone, src.border_width))
            } else {
                std::borrow::Cow::Borrowed(&gl.dist)
            };
            if grain.is_empty() {
                if p.parts.tone_match {
                    tone::match_tone(&mut low, &field, &gl.mask, &depth, &src.tone, src.paper);
                }
                return low;
            }
            let full: Vec<Rgb> = low.iter().zip(&grain).map(|(&l, &g)| vote::with_grain(l, g)).collect();
            if !p.parts.tone_match {
                return full;
            }
            // The grain is kept as a density (a factor of the low-pass): where the tone match
            // darkens the low-pass, its grain darkens in proportion, and a dark pixel's grain
            // cannot take it below black.
            // Its amplitude is then brought to the exemplar's at each depth (`tone::grain_gains`):
            // a density scaled by g is the factor raised to the power g.
            let before = low.clone();
            tone::match_tone(&mut low, &field, &gl.mask, &depth, &src.tone, src.paper);
            let gains = (src.grain_tone.as_ref())
                .filter(|_| p.parts.grain_match)
                .map(|prof| tone::grain_gains(&before, &full, &field, &gl.mask, &depth, prof));
            low.iter()
                .zip(&before)
                .zip(full)
                .enumerate()
                .map(|(q, ((l, b), f))| {
                    let g = gains.as_ref().map_or([1.0; 3], |gains| tone::grain_gain_at(gains, depth.data()[q]));
                    std::array::from_fn(|k| {
                        if b[k] > 1e-4 { (l[k] * (f[k] / b[k]).powf(g[k])).clamp(0.0, 1.0) } else { f[k] }
                    })
                })
                .collect()
        });
    }
    field
}

/// The settings of one level's search.
struct Level<'a> {
    src: &'a SourceLevel,
    params: &'a Params,
    /// The frame's index.
    frame: usize,
    /// The level's index (0 = finest).
    level: usize,
    /// The level's index counted from the coarsest (for the per-level iteration lists).
    from_coarsest: usize,
    /// The finest level, only voted (and merged).
    finest_vote_only: bool,
    paper: Rgb,
    /// The level's size, pixels.
    size: (usize, usize),
}

impl Level<'_> {
    /// The random-stream keys of iteration `it`.
    fn keys(&self, it: u64) -> [u64; 4] {
        [self.params.seed, self.frame as u64, self.level as u64, it]
    }

    /// The estimate the search matches against, voted from `field`.
    fn estimate(&self, field: &Nnf, st: &mut StageTimes) -> Vec<Rgb> {
        timed(&mut st.vote, || vote::vote(self.src, field, self.paper, self.params.schedule.estimate_sigma))
    }
}

/// The temporal guide `T^prev` and m(q) of level `l`, voted from the shifted field down-scaled
/// to the level (DOWNSCALENNF); returns that field (it also initializes the search), `None`
/// when nothing is carried.
fn temporal_guide(f: &FrameInputs, l: usize, tgt: &mut TargetLevel, st: &mut StageTimes) -> Option<Nnf> {
    let (shifted, prev_masks) = f.prev?;
    let (src, p) = (f.src, f.params);
    let sl = &src.levels[l];
    let (lw, lh) = f.pyr[l].mask.size();
    let sd = timed(&mut st.shift, || shifted.downscale(l, lw, lh));
    let voted = timed(&mut st.vote, || vote::vote(sl, &sd, src.paper, p.schedule.prev_sigma));
    write_lanes(tgt, &voted, false);
    if p.turns(sl.frames) {
        tgt.spin = spin_of(&sd);
    }
    timed(&mut st.shift, || {
        shift::fill_modulation(tgt, sl, &sd, &prev_masks[l], src.border_width, p.schedule.prev_bounds, p.weights.w_prev)
    });
    Some(sd)
}

/// The rotation of a still's carried field `f` per pixel, spread to the pixels with no
/// carried match from their neighbours (a few passes; the rest θ = 0).
fn spin_of(f: &Nnf) -> Vec<(f32, f32)> {
    let (w, h) = (f.w, f.h);
    let mut spin: Vec<Option<(f32, f32)>> = f.data.iter().map(|m| m.ok.then_some((m.c, m.s))).collect();
    for _ in 0..4 {
        let prev = spin.clone();
        for (q, o) in spin.iter_mut().enumerate() {
            if o.is_some() {
                continue;
            }
            let (mut c, mut s) = (0.0f32, 0.0f32);
            for (n, _) in neighbours4(q % w, q / w, w, h) {
                if let Some((nc, ns)) = prev[n] {
                    (c, s) = (c + nc, s + ns);
                }
            }
            let n = (c * c + s * s).sqrt();
            if n > 1e-3 {
                *o = Some((c / n, s / n));
            }
        }
    }
    spin.into_iter().map(|o| o.unwrap_or((1.0, 0.0))).collect()
}

/// The 4-neighbours of pixel (x, y) that lie inside a `w × h` grid, left, right, up, down:
/// each as its row-major index and its offset from (x, y).
fn neighbours4(x: usize, y: usize, w: usize, h: usize) -> impl Iterator<Item = (usize, (isize, isize))> {
    [(-1isize, 0isize), (1, 0), (0, -1), (0, 1)].into_iter().filter_map(move |(dx, dy)| {
        let (nx, ny) = (x as isize + dx, y as isize + dy);
        (nx >= 0 && ny >= 0 && (nx as usize) < w && (ny as usize) < h)
            .then(|| (ny as usize * w + nx as usize, (dx, dy)))
    })
}

/// The field a level starts from. At the coarsest level: the shifted field (or a random one
/// on the first frame, followed by one guide-only PatchMatch pass, thesis §4.2). Below it: the
/// coarser field up-scaled (UPSCALENNF), merged with the shifted one (MERGENNF) where there
/// is one. Inherited matches are sanitized and holes repaired.
fn initial_field(
    lv: &Level,
    tgt: &mut TargetLevel,
    coarse: Option<Nnf>,
    prev_down: Option<Nnf>,
    occ: &mut occurrence::Occurrence,
    st: &mut StageTimes,
    out: &mut FrameOutcome,
) -> Nnf {
    let (sl, p) = (lv.src, lv.params);
    let (lw, lh) = lv.size;
    let Some(coarse) = coarse else {
        let had_prev = prev_down.is_some();
        let mut f = prev_down.unwrap_or_else(|| Nnf::new(lw, lh));
        let ctx = Ctx::new(sl, tgt, None, 1.0, p, lv.keys(u64::MAX));
        sanitize(&ctx, &mut f);
        repair(&ctx, &mut f);
        if !had_prev {
            // First frame: random field, then one guide-only PatchMatch pass (thesis §4.2).
            let ctx = Ctx { w_col: 0.0, ..ctx };
            out.evaluations += timed(&mut st.patchmatch, || patchmatch::sweep(&ctx, &mut f, 0)).0.evaluations;
        }
        return f;
    };
    let mut up = coarse.upscale(lw, lh);
    let init = Ctx::new(sl, tgt, None, 1.0, p, lv.keys(u64::MAX));
    sanitize(&init, &mut up);
    repair(&init, &mut up);
    if let Some(mut pd) = prev_down {
        sanitize(&init, &mut pd);
        // MERGENNF: per pixel, the field with the smaller error, against an estimate voted
        // from the carried field where there is one (`ParamsBuilder::carried_estimate`), else
        // from the up-scaled field.
        let voted = if p.parts.carried_estimate { lv.estimate(&completed(&pd, &up), st) } else { lv.estimate(&up, st) };
        write_lanes(tgt, &voted, true);
        let omega = if lv.finest_vote_only && !p.parts.finest_uniformity {
            None
        } else {
            timed(&mut st.occurrence, || {
                occ.update(sl, &up, tgt, p.schedule.occ_radius, p.weights.lambda, p.weights.contrast_balance)
            })
        };
        let ctx = Ctx::new(sl, tgt, omega, p.weights.w_color, p, lv.keys(0));
        let kappa = if lv.finest_vote_only { p.weights.coherence } else { 1.0 };
        timed(&mut st.init, || merge(&ctx, &mut up, &pd, kappa, p.parts.carried_rim));
        out.evaluations += 2 * tgt.active.len() as u64;
    }
    up
}

/// How many times smaller the up-scaled match's error must be than the carried match's for it
/// to replace the carried one in the border band (MERGENNF with
/// [`ParamsBuilder::carried_rim`](super::ParamsBuilder::carried_rim)): only a carried match that
/// has gone wrong is replaced there.
const RIM_COHERENCE: f32 = 4.0;

/// The carried field `carried`, with the matches of `up` where nothing is carried (newly
/// covered pixels): the basis of MERGENNF's estimate.
fn completed(carried: &Nnf, up: &Nnf) -> Nnf {
    let mut basis = carried.clone();
    for (b, u) in basis.data.iter_mut().zip(&up.data) {
        if !b.ok {
            *b = *u;
        }
    }
    basis
}

/// The EM iterations of a level: per iteration, PatchMatch sweeps against the current
/// estimate (the occurrence map updated before each) and a new estimate voted from the field.
fn optimize(
    lv: &Level,
    tgt: &mut TargetLevel,
    field: &mut Nnf,
    occ: &mut occurrence::Occurrence,
    st: &mut StageTimes,
    out: &mut FrameOutcome,
) {
    let l = lv.level;
    let (sl, p) = (lv.src, lv.params);
    let voted = lv.estimate(field, st);
    write_lanes(tgt, &voted, true);
    for opt in 0..p.opt_iters_at(lv.from_coarsest) {
        for it in 0..p.pm_iters_at(lv.from_coarsest) {
            let omega = timed(&mut st.occurrence, || {
                occ.update(sl, field, tgt, p.schedule.occ_radius, p.weights.lambda, p.weights.contrast_balance)
            });
            let ctx = Ctx::new(sl, tgt, omega, p.weights.w_color, p, lv.keys(opt as u64));
            let (stats, e) = timed(&mut st.patchmatch, || patchmatch::sweep(&ctx, field, it));
            out.energy.push((l, e));
            out.evaluations += stats.evaluations;
        }
        out.energy.push((l, mean_err(field)));
        let voted = lv.estimate(field, st);
        write_lanes(tgt, &voted, true);
    }
}

/// Mean patch error of the matched pixels of `nnf`.
fn mean_err(nnf: &Nnf) -> f64 {
    let (mut s, mut n) = (0.0f64, 0usize);
    for m in &nnf.data {
        if m.ok && m.err.is_finite() {
            s += m.err as f64;
            n += 1;
        }
    }
    if n > 0 { s / n as f64 } else { 0.0 }
}

/// Writes voted colors into the rgb lanes of `T^rgb` (`cur`) or `T^prev` (`!cur`), and into
/// their padding the colors mirrored at the window's edge.
fn write_lanes(tgt: &mut TargetLevel, rgb: &[Rgb], cur: bool) {
    let (w, stride) = (tgt.w, tgt.stride);
    let h = rgb.len() / w.max(1);
    if h == 0 {
        return;
    }
    let pad = target::TPAD;
    let arr = if cur { &mut tgt.cur } else { &mut tgt.prev };
    arr.par_chunks_mut(stride).enumerate().for_each(|(py, row)| {
        let y = mirror(py as isize - pad as isize, h);
        for (px, lanes) in row.iter_mut().enumerate() {
            let c = rgb[y * w + mirror(px as isize - pad as isize, w)];
            // Quantization units of the color lanes: 0..=255.
            lanes[0] = c[0] * 255.0;
            lanes[1] = c[1] * 255.0;
            lanes[2] = c[2] * 255.0;
        }
    });
}

/// Index `i` reflected into `0..n` about the edge pixels (…, 2, 1, 0, 1, 2, …), clamped
/// when `n` is too small to reflect.
fn mirror(i: isize, n: usize) -> usize {
    let (last, r) = (n as isize - 1, i.abs());
    r.min(2 * last - r).clamp(0, last.max(0)) as usize
}

/// Makes every inherited match (up-scaled, shifted in time, carried over) usable: frame
/// indices and centers clamped into the valid margin (centers may have drifted out through
/// up-scaling or the time shift; θ is kept, as the paper keeps it through UPSCALENNF and
/// SHIFTNNF), and a match whose center is not a valid center of its target pixel's segment
/// (border or interior) is moved the least distance onto one, within the eight pixels around
/// its own ([`ParamsBuilder::segment_snap`](super::ParamsBuilder::segment_snap)), or dropped
/// where none of them is one (or the snap is off), as the search would never have chosen it.
/// Matches of
/// inactive pixels are dropped too.
fn sanitize(ctx: &Ctx, nnf: &mut Nnf) {
    let src = ctx.src;
    let (xmax, ymax) = ((src.w - 1 - MARGIN) as f32, (src.h - 1 - MARGIN) as f32);
    let last = (src.frames - 1) as u16;
    let snap = ctx.params.parts.segment_snap;
    nnf.data.par_iter_mut().enumerate().for_each(|(q, m)| {
        if ctx.tgt.info[q].flags & source::VALID == 0 {
            *m = Match::NONE;
            return;
        }
        if m.ok {
            m.x = m.x.clamp(MARGIN as f32, xmax);
            m.y = m.y.clamp(MARGIN as f32, ymax);
            m.i = m.i.min(last);
            m.err = f32::INFINITY;
            let seg = ctx.wanted_segment(q);
            if ctx.check(seg, m.i as usize, m.x, m.y).is_some() {
                return;
            }
            match snap.then(|| nearest_valid(ctx, seg, m, (xmax, ymax))).flatten() {
                Some((x, y)) => (m.x, m.y) = (x, y),
                None => *m = Match::NONE,
            }
        }
    });
}

/// The point nearest to match `m`'s center that lies in one of the eight pixels around its own
/// and is a valid center of segment `seg` (inside the valid margin, whose far corner is
/// `max`): the least move that makes the match usable ([`sanitize`]). Ties go to the first
/// pixel in a fixed order, so the result does not depend on the threads.
fn nearest_valid(ctx: &Ctx, seg: Option<usize>, m: &Match, max: (f32, f32)) -> Option<(f32, f32)> {
    // A pixel's cell is [n − ½, n + ½) (`SourceLevel::nearest`); a point moved into it stays
    // this far inside, clear of rounding.
    const INSET: f32 = 1.0 / 64.0;
    let (rx, ry) = ((m.x + 0.5).floor(), (m.y + 0.5).floor());
    let mut best: Option<(f32, (f32, f32))> = None;
    for (dx, dy) in
        [(0.0, -1.0), (-1.0, 0.0), (1.0, 0.0), (0.0, 1.0), (-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)]
    {
        let (nx, ny) = (rx + dx, ry + dy);
        let x = m.x.clamp(nx - 0.5 + INSET, nx + 0.5 - INSET);
        let y = m.y.clamp(ny - 0.5 + INSET, ny + 0.5 - INSET);
        let inside = (MARGIN as f32..=max.0).contains(&x) && (MARGIN as f32..=max.1).contains(&y);
        let d = (x - m.x).powi(2) + (y - m.y).powi(2);
        if inside && best.is_none_or(|(b, _)| d < b) && ctx.check(seg, m.i as usize, x, y).is_some() {
            best = Some((d, (x, y)));
        }
    }
    best.map(|(_, p)| p)
}

/// Gives every active pixel without a match one: the first of its four neighbours' matches,
/// moved by the one-pixel offset (rotated), that is a valid center of its segment — the
/// propagation step of PatchMatch, which keeps the field coherent where a few inherited
/// matches were dropped — or else a random one. Reads the field as it was before (the result
/// does not depend on the order of the pixels).
fn repair(ctx: &Ctx, nnf: &mut Nnf) {
    let (w, h) = (nnf.w, nnf.h);
    if !nnf.data.iter().enumerate().any(|(q, m)| !m.ok && ctx.tgt.info[q].flags & source::VALID != 0) {
        return;
    }
    let before = nnf.data.clone();
    nnf.data.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, m) in row.iter_mut().enumerate() {
            let q = y * w + x;
            if m.ok || ctx.tgt.info[q].flags & source::VALID == 0 {
                continue;
            }
            let seg = ctx.wanted_segment(q);
            let propagated = neighbours4(x, y, w, h).find_map(|(k, (dx, dy))| {
                let n = before[k];
                if !n.ok {
                    return None;
                }
                // One step from the neighbour to q is M·(−dx, −dy) in the source.
                let (ox, oy) = n.rotate(-dx as f32, -dy as f32);
                let (cx, cy) = (n.x + ox, n.y + oy);
                ctx.check(seg, n.i as usize, cx, cy).map(|_| Match { x: cx, y: cy, err: f32::INFINITY, ..n })
            });
            *m = propagated.unwrap_or_else(|| {
                let mut rng = SplitMix64::keyed(&[ctx.keys[0], ctx.keys[1], ctx.keys[2], 0x5eed, q as u64]);
                ctx.random_match(q, &mut rng)
            });
        }
    });
}

/// MERGENNF: keeps, per pixel, whichever of `up` and `prev` has the smaller patch error —
/// the up-scaled match `up` only when its error is below 1/κ of the carried match's
/// (`kappa` = κ, 1 = the paper's comparison at face value). The errors are measured against
/// the estimate in `ctx`'s target, by default voted from the carried field
/// ([`ParamsBuilder::carried_estimate`](super::ParamsBuilder::carried_estimate)). With `keep_rim`
/// ([`ParamsBuilder::carried_rim`](super::ParamsBuilder::carried_rim)) the carried match is
/// kept in the target's border segment (`I^df < 1`) unless the up-scaled one's error is below
/// 1/[`RIM_COHERENCE`] of its own: SHIFTNNF re-anchored it to the target's distance from the
/// edge, while the up-scaled match is placed only as precisely as the coarser level's pixels,
/// which near the edge is often the paler paint behind the exemplar's rim.
///
/// The finest level merges with the coherence factor κ of the random search
/// ([`super::ParamsBuilder::coherence`]): it is only voted, so the merge is the one choice made
/// there, and the up-scaled challenger gets the same handicap as a random candidate. Its
/// errors include Ω and the contrast balance in `ctx`, as every level's do
/// ([`ParamsBuilder::finest_uniformity`](super::ParamsBuilder::finest_uniformity)). The
/// coarse levels' estimate is a blur, which a flat, pale exemplar patch fits better than
/// carried texture; compared at face value, a fifth of the carried matches were replaced
/// every frame, each by a paler one (measured on green-wash, long target: mean exemplar
/// luminance of the replacement +0.01), and over 150 frames the paint paled and lost its rim.
///
/// Kept without any comparison (as before 2026-12-05), a carried rim match that had gone wrong
/// stayed wrong: the border band of a slowly moving shape gathered dark specks and streaks
/// frame after frame (a 40-px bar moving 0.5 px a frame, 48 frames: the band's change that its
/// motion does not explain rose from 0.021–0.025 luma a frame in frames 2–8 to 0.025–0.031 in
/// the last 20 with the still swatch, while the interior stayed at the measure's floor). A
/// match the up-scaled one beats four times over is such a one; the rim's good matches are
/// kept (band change in the last 20 frames 0.018–0.024 with the swatch, 0.017–0.027 with
/// green-wash where it was 0.024–0.032, 0.025–0.027 with ink-rims where it was 0.030–0.035).
fn merge(ctx: &Ctx, up: &mut Nnf, prev: &Nnf, kappa: f32, keep_rim: bool) {
    let w = up.w;
    up.data.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, m) in row.iter_mut().enumerate() {
            let q = y * w + x;
            let pm = &prev.data[q];
            if !pm.ok {
                continue;
            }
            let win = ctx.window(q);
            let ep = ctx.error_in(&win, pm);
            let eu = ctx.error_in(&win, m);
            let k = if keep_rim && ctx.tgt.segment(q) == 0 { RIM_COHERENCE } else { kappa };
            if ep < k * eu {
                *m = Match { err: ep, ..*pm };
            } else {
                m.err = eu;
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::mirror;

    #[test]
    fn the_padding_mirrors_about_the_edge_pixels() {
        let row: Vec<usize> = (-2..7).map(|i| mirror(i, 5)).collect();
        assert_eq!(row, [2, 1, 0, 1, 2, 3, 4, 3, 2]);
        // Too small to reflect: the one pixel there is.
        assert_eq!((-2..3).map(|i| mirror(i, 1)).collect::<Vec<_>>(), [0; 5]);
        assert_eq!((-2..4).map(|i| mirror(i, 2)).collect::<Vec<_>>(), [0, 1, 0, 1, 0, 0]);
    }
}
