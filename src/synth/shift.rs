//! Temporal coherence by time shift (paper §3.4, thesis §3.7): SHIFTNNF moves each match of
//! the previous frame along the exemplar's own time axis by the Δi whose exemplar motion best
//! matches the target motion, and m(q) modulates the temporal weight.

use super::nnf::{Match, Nnf};
use super::source::{FLOW_EPS, IN_MASK, SourceLevel, VALID};
use super::target::TargetLevel;
use glam::Vec2;
use rayon::prelude::*;

/// What SHIFTNNF needs besides the previous field, over the current working window at full
/// resolution (row-major).
pub(crate) struct ShiftInputs<'a> {
    pub src: &'a SourceLevel,
    /// `T^ext+` of the previous and of the current frame (scaled like every target extent).
    pub ext_prev: &'a [f32],
    pub ext_cur: &'a [f32],
    /// `T^flow` of the previous frame: the motion from it to the current one.
    pub flow_prev: &'a [Vec2],
    /// `T^flow` of the current frame (the motion from it to the next): where the previous
    /// frame had no paint, the motion that brought it ([`carried_in`]).
    pub flow_cur: &'a [Vec2],
    /// `T^dist` of the current frame.
    pub dist_cur: &'a [f32],
    /// The border width b: matches within it of an edge are re-anchored.
    pub band: f32,
    /// What one frame of time travel beyond the nominal step costs, in pixels of motion
    /// ([`step_cost`]).
    pub step_cost: f32,
    /// Pixels the current frame synthesizes.
    pub active: &'a [bool],
    /// Pixels the previous frame did not paint take the match their motion came from
    /// ([`carried_in`]; where the shape moves rather than grows, [`AreaChange::moves_rather_than_grows`]).
    pub carry_new: bool,
    /// The time shift ([`super::ParamsBuilder::time_shift`]).
    pub time_shift: bool,
    /// Residual advection and re-anchoring ([`super::ParamsBuilder::advect`]).
    pub advect: bool,
    /// Settle the shifted field ([`super::ParamsBuilder::settle`], [`settle`]).
    pub settle: bool,
    /// Hold receding paint deeper than the border band ([`super::ParamsBuilder::receding_hold`],
    /// [`hold_receding`]).
    pub receding_hold: bool,
    /// Paint ages: every carried match steps at least one exemplar frame forward
    /// ([`super::ParamsBuilder::aging`], [`aged`]).
    pub age: bool,
    /// Every match keeps its exemplar frame (Δi = 0): the first frame carried onto itself
    /// ([`super::ParamsBuilder::repaint_first`]).
    pub hold_time: bool,
    /// The most exemplar frames a match steps through in one target frame, either way:
    /// unbounded (`usize::MAX`) is the paper's rule; 1 where the shape moves rather than grows
    /// ([`super::ParamsBuilder::pace`]).
    pub max_step: usize,
    /// The time step supplies none of the motion: the advection carries all of it (where the
    /// shape moves rather than grows; [`super::ParamsBuilder::full_carry`]).
    pub full_carry: bool,
    /// The shape travels ([`AreaChange::travels`]): its border paint holds its exemplar frame
    /// where it moves ([`holds`]; [`super::ParamsBuilder::travel_hold`]).
    pub travel_hold: bool,
    /// The shape is a thin part ([`all_rim`]) that moves noticeably ([`moves_noticeably`] of
    /// `flow_prev`): where it travels, all of its border paint holds, however slowly it moves
    /// itself.
    pub moving: bool,
    /// The exemplar is a still: every carried match turns with the target's local rotation
    /// ([`flow_turn`]) — where the field is carried along the motion (with the time shift and
    /// the advection; without them nothing is carried, and nothing turns).
    pub turn: bool,
    /// The pixels that rest and take their shape's normal as their direction
    /// ([`super::target::resting_normal`]; empty without
    /// [`super::ParamsBuilder::resting_normal`]): their matches turn with the exemplar's normal
    /// rather than its flow when they move ([`moved`]).
    pub resting: &'a [bool],
}

/// Pixels of motion that one frame of deviation from the nominal step costs in the paper's
/// rule alone (no advection): a tie-breaker, far below any real difference of motion.
const TIE_BREAK: f32 = 0.02;

/// The speed, pixels per frame, from which a travelling shape's border paint holds its
/// exemplar frame ([`holds`], [`moves_noticeably`]): half a pixel, below which a carried
/// texture barely moves and the shape's paint reads as resting.
const HOLD_SPEED: f32 = 0.5;

/// The share of a shape's moving pixels below the speed that [`moves_noticeably`] reads.
const HOLD_QUANTILE: f32 = 0.9;

/// Whether the shape moves noticeably from the previous frame: the 90th percentile of the
/// speed of its pixels (`flow_prev`, zero where it had no paint) reaches [`HOLD_SPEED`].
///
/// Decided for a thin part ([`all_rim`]) as well as per pixel ([`holds`]): a swinging limb's
/// paint near its shoulder, and all of it for the few frames at the turn of each swing, moves less than half
/// a pixel a frame while the limb travels on. Read per pixel only, that paint aged there — one
/// exemplar frame a frame, in place — and boiled (measured on the suite's limb with
/// yellow-granules, seed 1, `synth` and `eval`: incoherent change 1.62 and 1.66 of the
/// exemplar's in frames 13–14, the turn, against 1.13–1.16 in frames 11–12 and 15–16, and
/// 1.37–1.47 in frames 3, 5 and 7; held, 0.94 and 0.95, and 1.09–1.25).
pub(crate) fn moves_noticeably(flow_prev: &[Vec2]) -> bool {
    let mut speeds: Vec<f32> = flow_prev.iter().map(|f| f.length()).filter(|&v| v >= FLOW_EPS).collect();
    if speeds.is_empty() {
        return false;
    }
    let k = ((speeds.len() - 1) as f32 * HOLD_QUANTILE).round() as usize;
    *speeds.select_nth_unstable_by(k, f32::total_cmp).1 >= HOLD_SPEED
}

/// How many border widths deep a shape may reach and still count as all rim ([`all_rim`]).
const RIM_DEPTHS: f32 = 2.0;

/// Whether a shape is all rim: no pixel of it lies deeper than [`RIM_DEPTHS`] border widths
/// `band` (`dist`: the signed distance to its edge, positive inside) — a thin part, a limb or a
/// stroke, whose paint is its border paint and moves with it as one piece.
///
/// Only such a shape's border paint holds as a whole when the shape moves noticeably
/// ([`ShiftInputs::moving`]). A large shape's rim holds only where it moves itself: held as a
/// whole while the shape drifts slowly, a blob's rim stopped aging and lost its texture over a
/// long animation (green-wash on the quality suite's 300-frame target at half size, without
/// the tone match: the lowest 50-frame window kept 0.84 of the first's contrast, against 0.89
/// with the rim held only where it moves).
pub(crate) fn all_rim(dist: &[f32], band: f32) -> bool {
    let deepest = dist.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    deepest > 0.0 && deepest <= RIM_DEPTHS * band
}

/// Fixed-point steps of [`carried_in`]'s inversion of the warp.
const INVERSION_STEPS: usize = 3;

/// The cost of one frame of time travel beyond the nominal step when the rest of the motion
/// is carried by advection: a quarter of the exemplar's mean speed (its extent scale over its
/// frames). A step of the exemplar's time is worth taking only where it supplies at least
/// that much motion; where the paint at a match hardly moves (a bloom's still center, its
/// settled last frames), running through many frames would only change the paint's look for
/// nothing (or, backwards, un-spread it), and the motion is carried instead.
pub(crate) fn step_cost(ext_scale: f32, frames: usize) -> f32 {
    (0.25 * ext_scale / frames.max(1) as f32).max(TIE_BREAK)
}

/// The time step of match m under the target's extent change `dt` (see [`shift_nnf`]): the
/// new frame index i + Δi and the motion the exemplar supplies by it — the path its paint at
/// the match travels over the frames stepped, `Σ_k |S^flow(k, x, y)|` for k from i to
/// i + Δi (exclusive); `c` is the cost of one frame off the nominal step, and |Δi| is at most
/// `max_step`. `None` where the match is outside the exemplar.
///
/// The supplied motion is the flow's path, not the change of the extent at the match
/// `|S^ext(i+Δi) − S^ext(i)|` that chooses Δi: at a fixed point the extent changes by
/// `|f| − f·∇S^ext` per frame, not by `|f|`, so the extent's change under-reports the
/// motion wherever the extent varies along the flow (measured on the identity: +0.06 px per
/// frame of motion left over for the warp where there is none, which drifted the interior's
/// matches 1–2 px off their own within 30 frames; worst frame 28.1 dB on green-wash, 34 dB
/// with the path).
fn time_step(src: &SourceLevel, m: &Match, dt: f32, c: f32, max_step: usize) -> Option<(usize, f32)> {
    let i = m.i as usize;
    let (idx0, _) = src.info_at(i, m.x, m.y)?;
    let pix = idx0 - i * src.frame_len;
    let val = |k: usize| {
        let inf = &src.info[k * src.frame_len + pix];
        if m.flip { inf.ext_neg } else { inf.ext_pos }
    };
    let base = val(i);
    let nominal_step = if m.flip { 0 } else { 1 };
    let cost = |k: usize| (dt - (val(k) - base)).abs() + c * k.abs_diff(i).abs_diff(nominal_step) as f32;
    let mut best_i = if m.flip || i + 1 >= src.frames { i } else { i + 1 };
    let mut best = cost(best_i);
    let mut consider = |k: usize| {
        let d = cost(k);
        if d < best {
            best = d;
            best_i = k;
        }
    };
    consider(i);
    if m.flip {
        (i.saturating_sub(max_step)..i).rev().for_each(&mut consider);
    } else {
        (i + 1..src.frames.min(i.saturating_add(max_step).saturating_add(1))).for_each(&mut consider);
    }
    let speed = |k: usize| src.info[k * src.frame_len + pix].speed;
    let path = if best_i >= i { (i..best_i).map(speed).sum() } else { (best_i..i).map(speed).sum() };
    Some((best_i, path))
}

/// Whether the carried match `m` at target pixel `q` keeps its exemplar frame (Δi = 0) instead of
/// taking its time step ([`super::ParamsBuilder::receding_hold`]): a receding match
/// ([`Match::flip`]: the target moves against the exemplar's flow) deeper inside the target
/// than the border width b. The paper runs the exemplar's time backwards there, which at the
/// edge lets the rim retreat the way the bloom spread, but deeper inside only turns the
/// still interior back towards the bloom's first, wet frames (un-spreading it) and makes it
/// boil; held, its motion is all carried by the advection.
fn hold_receding(inp: &ShiftInputs, m: &Match, q: usize) -> bool {
    inp.receding_hold && inp.advect && m.flip && inp.dist_cur[q] > inp.band
}

/// The time step of q's own carried match `m`: [`time_step`] (at most
/// [`ShiftInputs::max_step`] frames), or, for a held match ([`ShiftInputs::hold_time`],
/// [`hold_receding`]), its own frame, supplying no motion — like a time step, it needs its
/// center inside the exemplar. (The match the advection takes from the pixel behind q,
/// [`warped_from`], takes its plain time step: the hold is judged at the match's own pixel.)
/// Then aged ([`aged`], which leaves [`ShiftInputs::hold_time`]'s matches alone): a held
/// receding match steps one frame forward too.
fn step_of(inp: &ShiftInputs, m: &Match, q: usize, dt: f32, c: f32) -> Option<(usize, f32)> {
    if holds(inp, q, q) {
        return held(inp, m);
    }
    let step = if inp.hold_time || hold_receding(inp, m, q) {
        held(inp, m)
    } else {
        time_step(inp.src, m, dt, c, inp.max_step)
    }?;
    Some(aged(inp, m, step))
}

/// Whether the paint carried to target pixel `q` from pixel `from` of the previous frame holds
/// its exemplar frame ([`super::ParamsBuilder::travel_hold`]): the shape travels
/// ([`ShiftInputs::travel_hold`]), the paint lands in the border band (within b of the edge),
/// and either the shape is a thin part that moves noticeably ([`ShiftInputs::moving`]) or the
/// paint itself moves at least [`HOLD_SPEED`] (the previous frame's flow where it was: a fast part of a shape
/// that mostly rests).
fn holds(inp: &ShiftInputs, from: usize, q: usize) -> bool {
    inp.travel_hold && inp.dist_cur[q] <= inp.band && (inp.moving || inp.flow_prev[from].length() >= HOLD_SPEED)
}

/// A match that keeps its exemplar frame and supplies no motion: `(i, 0)`, where its center
/// lies inside the exemplar (as a time step needs).
fn held(inp: &ShiftInputs, m: &Match) -> Option<(usize, f32)> {
    inp.src.info_at(m.i as usize, m.x, m.y).map(|_| (m.i as usize, 0.0))
}

/// The time step `(i + Δi, supplied motion)` of the carried match `m`, aged
/// ([`super::ParamsBuilder::aging`]): Δi is at least +1 until the exemplar's last frame, at
/// the rim as deep inside. A step the rule chose is kept where it is already forward;
/// otherwise the match steps to the next frame and supplies no motion — the paint dries where
/// it lies, and the advection carries all of the target's motion, as for a held match. At a
/// still or receding edge the paper's rule holds the rim in its frame or runs it back towards
/// the bloom's wet first frames; aged, it settles as the exemplar's own rim does. (Counting
/// the path its paint travels in that frame instead, as a chosen step does, measured worse:
/// the swinging limb's incoherent change 0.12–0.18 higher with three of four exemplars, 0.05
/// lower with ink-rims; 24 frames, seed 1, aging deeper than b only.)
fn aged(inp: &ShiftInputs, m: &Match, (best_i, supplied): (usize, f32)) -> (usize, f32) {
    let next = (m.i as usize + 1).min(inp.src.frames - 1);
    if !inp.age || inp.hold_time || best_i >= next {
        return (best_i, supplied);
    }
    (next, 0.0)
}

/// How a shape's mask changed from the previous frame to the current one (both over the same
/// window): the pixels it newly covers and the pixels it gives up, counted in one pass.
#[derive(Clone, Copy, Debug)]
pub(crate) struct AreaChange {
    new: usize,
    lost: usize,
}

impl AreaChange {
    /// The change from `prev` to `cur`.
    pub(crate) fn of(cur: &[bool], prev: &[bool]) -> AreaChange {
        let (new, lost) = cur
            .iter()
            .zip(prev)
            .fold((0, 0), |(new, lost), (&c, &p)| (new + (c && !p) as usize, lost + (p && !c) as usize));
        AreaChange { new, lost }
    }

    /// Whether the shape moves rather than grows: it gave up at least a third as much area as
    /// it newly covers, so what it newly covers is mostly the same paint moved along — a part
    /// that translates, turns or swings — and not paint spreading onto new paper, which grows
    /// without giving anything up (an exemplar's own bloom; a growing shape), whose front the
    /// search paints as new paint (the extent term).
    pub(crate) fn moves_rather_than_grows(self) -> bool {
        self.new <= 3 * self.lost
    }

    /// Whether the shape travels: it moves rather than grows
    /// ([`AreaChange::moves_rather_than_grows`]) and also newly covers at least a third as
    /// much area as it gives up — a part that translates, turns or swings, not one that
    /// shrinks (which only gives up area: its edge recedes, as paint drying back does) nor one
    /// that stands still.
    pub(crate) fn travels(self) -> bool {
        // `new > 0` with `moves_rather_than_grows` (new ≤ 3·lost) also gives `lost > 0`.
        self.new > 0 && self.moves_rather_than_grows() && self.lost <= 3 * self.new
    }
}

/// The match a pixel `q` the previous frame did not paint takes from the pixel its motion came
/// from: `p = q − f` with `f` the previous frame's flow at `p` (found by fixed-point
/// iteration from the current frame's flow at `q`: the previous frame's flow is zero where it
/// had no mask), the previous match at `⌊p⌉` time-shifted like any carried match
/// and offset by `M·(p − ⌊p⌉)`, then re-anchored within the border band (where that move is
/// refused, it stays at `⌊p⌉`'s match). `None` where `⌊p⌉` had no match either: the pixel is
/// new paint, found by the search. Without it, only pixels within the active margin of the
/// previous mask (2 px) were carried, and a part that moves farther in a frame — a thin limb
/// swinging at up to 11 px a frame — was painted anew over most of its width every frame
/// (measured on a 14-px limb: 15–28 % of its pixels had no carried match at its fastest).
fn carried_in(inp: &ShiftInputs, prev: &Nnf, q: usize, c: f32) -> Option<Match> {
    if !inp.carry_new || !inp.advect || !inp.time_shift {
        return None;
    }
    let f = inp.flow_cur[q];
    if f.length() < FLOW_EPS {
        return None;
    }
    let here = Vec2::new((q % prev.w) as f32, (q / prev.w) as f32);
    // The previous frame's flow at the source is the motion that brought it here: refine the
    // estimate with it (a fixed-point inversion of the warp).
    let mut p = here - f;
    for _ in 0..INVERSION_STEPS {
        match prev.index_near(p).map(|k| inp.flow_prev[k]) {
            Some(f) if f.length() >= FLOW_EPS => p = here - f,
            _ => break,
        }
    }
    let dt = inp.ext_cur[q] - inp.ext_prev[q];
    let (m, i, x, y) = warped_from(inp, prev, p, q, dt, c)?;
    Some(placed(inp, q, m, i, x, y))
}

/// The previous frame's match nearest to `p` (at `⌊p⌉`), carried to target pixel `q` and
/// time-shifted under the extent change `dt` ([`time_step`], at most [`ShiftInputs::max_step`]
/// frames; [`aged`]) or held in its frame ([`holds`]), and the point it stands for at `p`: its
/// position offset by `M·(p − ⌊p⌉)`. `None` where `⌊p⌉` is off the field or had no match.
fn warped_from(inp: &ShiftInputs, prev: &Nnf, p: Vec2, q: usize, dt: f32, c: f32) -> Option<(Match, usize, f32, f32)> {
    let from = prev.index_near(p)?;
    let m = prev.data[from];
    if !m.ok {
        return None;
    }
    let (i, _) =
        if holds(inp, from, q) { held(inp, &m)? } else { aged(inp, &m, time_step(inp.src, &m, dt, c, inp.max_step)?) };
    let r = p.round();
    let (dx, dy) = m.rotate(p.x - r.x, p.y - r.y);
    Some((m, i, m.x + dx, m.y + dy))
}

/// Match `m` at target pixel `q`, time-shifted to exemplar frame `i` and carried to `(x, y)`:
/// near the edge re-anchored to the target's distance from the edge — the rim of paint
/// travels with the edge (flow magnitudes only approximate how far an edge moves, and the
/// small errors of every frame would add up to a lagging, pale rim) — and [`moved`] there;
/// where the move is refused, the time-shifted match where it was.
fn placed(inp: &ShiftInputs, q: usize, m: Match, i: usize, x: f32, y: f32) -> Match {
    let shifted = Match { i: i as u16, err: f32::INFINITY, ..m };
    let (x, y) = reanchor(inp.src, i, x, y, inp.dist_cur[q], inp.band).unwrap_or((x, y));
    let normal = inp.resting.get(q).copied().unwrap_or(false);
    moved(inp.src, &shifted, x, y, normal).unwrap_or(shifted)
}

/// Match `m` moved to `(x, y)` in its exemplar frame; `m` itself if that is where it is; `None`
/// where the move is refused. The move must stay valid and on the same side of any divide of
/// the exemplar's flow (its source, where the paint started). The rotation M turns with the
/// exemplar's flow direction between the two points, so it still maps the target's flow onto
/// the exemplar's where the match now is (the θ rule holds after the move); with `normal` (a
/// resting target pixel, [`super::ParamsBuilder::resting_normal`]) with the exemplar's normal.
fn moved(src: &SourceLevel, m: &Match, x: f32, y: f32, normal: bool) -> Option<Match> {
    if (x, y) == (m.x, m.y) {
        return Some(*m);
    }
    let at = |x: f32, y: f32| src.nearest(m.i as usize, x, y);
    let to = at(x, y).filter(|&k| src.info[k].flags & VALID != 0)?;
    let dir = |k: usize| if normal { src.normal(k) } else { src.info[k].dir };
    let (mut c, mut s) = (m.c, m.s);
    if let Some(from) = at(m.x, m.y).map(dir)
        && from != Vec2::ZERO
        && dir(to) != Vec2::ZERO
    {
        let to = dir(to);
        let (cos_p, sin_p) = (from.dot(to), from.perp_dot(to));
        if cos_p < 0.0 {
            return None;
        }
        let n = (cos_p * cos_p + sin_p * sin_p).sqrt();
        let (cos_p, sin_p) = (cos_p / n, sin_p / n);
        (c, s) = m.rotate(cos_p, sin_p);
    }
    Some(Match { x, y, c, s, ..*m })
}

/// SHIFTNNF (paper §3.4), extended.
///
/// For a match (i, x, y) with aligned flows, Δi ≥ 0 minimizes
/// `|ΔT − (S^ext+(i+Δi, x, y) − S^ext+(i, x, y))| + c·|Δi − 1|` with
/// `ΔT = T^ext+(j) − T^ext+(j−1)`; with opposite flows ([`Match::flip`]), Δi ≤ 0 minimizes
/// the same with `S^ext−` and `c·|Δi|`: near-ties go to the nominal step — one exemplar frame
/// per target frame for aligned flows (stationary paint keeps its own pace instead of stopping),
/// none for opposite flows (time runs backwards only as far as the motion asks). The paper's
/// rule is `c → 0`; with advection `c` = [`step_cost`]. |Δi| is at most
/// [`ShiftInputs::max_step`]: one frame where the shape moves rather than grows (see
/// [`super::ParamsBuilder::pace`]). A held match keeps its frame ([`step_of`]); with
/// [`ShiftInputs::age`] every match steps at least one frame forward ([`aged`]: paint dries
/// on, whether or not its shape moves) — but where the shape travels, border paint that moves
/// keeps its frame ([`holds`], [`ShiftInputs::travel_hold`]).
///
/// Then, with [`ShiftInputs::advect`]: the motion the time shift did not supply is carried by
/// warping the field — the target pixel q takes the shifted match of the previous frame's
/// pixel `p = q − rest·f̂` (f the target flow, `rest` the motion beyond what the exemplar's
/// evolution supplied at q's match), offset by `M·(p − ⌊p⌉)` for the sub-pixel part: q shows
/// what was that far behind it (the exemplar's evolution carries as much of the motion as it
/// can, the warp the rest; when the exemplar runs out of frames, all of it; where the shape
/// moves rather than grows, with [`ShiftInputs::full_carry`], all of it too: the time step
/// only ages the paint). Where `⌊p⌉` had
/// no match (paint that was not there), q's own match is moved upstream in the exemplar by
/// `M·rest·f̂` instead. Within a coherent piece of the field the two are the same; across
/// pieces the warp keeps each piece whole — moving every match in the exemplar by its own
/// rest cuts the pieces (measured: 0.56–0.61 of neighbouring pixels continue each other's
/// match after a translating frame, 0.36–0.45 after the shift) and leaves matches travelling
/// across the exemplar for as long as the shape moves. Within the border band the match is
/// re-anchored to the target's distance from the edge. Last, with [`ShiftInputs::settle`],
/// the field is settled onto its pieces ([`settle`]).
pub(crate) fn shift_nnf(inp: &ShiftInputs, prev: &Nnf) -> Nnf {
    let c = if inp.advect { inp.step_cost } else { TIE_BREAK };
    let mut out = Nnf::new(prev.w, prev.h);
    out.data.par_iter_mut().enumerate().for_each(|(q, o)| {
        if !inp.active[q] {
            return;
        }
        let m = &prev.data[q];
        if !m.ok {
            if let Some(carried) = carried_in(inp, prev, q, c) {
                *o = carried;
            }
            return;
        }
        if !inp.time_shift {
            *o = Match { err: f32::INFINITY, ..*m };
            return;
        }
        let dt = inp.ext_cur[q] - inp.ext_prev[q];
        let Some((best_i, supplied)) = step_of(inp, m, q, dt, c) else {
            *o = *m;
            return;
        };
        let supplied = if inp.full_carry { 0.0 } else { supplied };
        if !inp.advect {
            *o = Match { i: best_i as u16, err: f32::INFINITY, ..*m };
            return;
        }
        // The rest of the motion: the match of the pixel `rest` behind q (the warp), or q's
        // own match moved upstream by it.
        let (mut m, mut best_i, (mut x, mut y)) = (*m, best_i, (m.x, m.y));
        let f = inp.flow_prev[q];
        let speed = f.length();
        if speed >= FLOW_EPS {
            let rest = (speed - supplied).clamp(-speed, speed);
            let back = f / speed * rest;
            let p = Vec2::new((q % prev.w) as f32, (q / prev.w) as f32) - back;
            if let Some(from) = warped_from(inp, prev, p, q, dt, c) {
                (m, best_i, x, y) = from;
            } else {
                let (dx, dy) = m.rotate(back.x, back.y);
                (x, y) = (x - dx, y - dy);
            }
        }
        *o = placed(inp, q, m, best_i, x, y);
    });
    if inp.turn && inp.advect && inp.time_shift {
        let w = prev.w;
        out.data.par_iter_mut().enumerate().for_each(|(q, o)| {
            if o.ok {
                let a = flow_turn(inp.flow_prev, inp.dist_cur, w, q);
                if a != 0.0 {
                    // M turned by −a: M·R(−a), whose columns are M applied to R(−a)'s.
                    let (sn, cs) = a.sin_cos();
                    (o.c, o.s) = o.rotate(cs, -sn);
                }
            }
        });
    }
    if inp.settle {
        for _ in 0..SETTLE_PASSES {
            out = settle(&out, inp.active);
        }
    }
    out
}

/// The local rotation of the flow `f` at pixel q, radians per frame: ½ curl, from central
/// differences 2 px apart; 0 where one of them lies outside the mask (`dist` ≤ 0).
fn flow_turn(f: &[Vec2], dist: &[f32], w: usize, q: usize) -> f32 {
    const D: usize = 2;
    let (x, y, h) = (q % w, q / w, f.len() / w);
    if x < D || y < D || x + D >= w || y + D >= h {
        return 0.0;
    }
    let n = [q - D, q + D, q - D * w, q + D * w];
    if n.iter().any(|&k| dist[k] <= 0.0) {
        return 0.0;
    }
    let (l, r, u, d) = (f[n[0]], f[n[1]], f[n[2]], f[n[3]]);
    ((r.y - l.y) - (d.x - u.x)) / (4 * D) as f32
}

/// How far (full-resolution pixels, per axis) a neighbour's prediction of a match may lie from
/// it and still count as the same piece of the field in [`settle`].
const SETTLE_TOLERANCE: f32 = 1.5;

/// Passes of [`settle`] per frame.
const SETTLE_PASSES: usize = 2;

/// Settles the shifted field: each match's position becomes the per-axis median of what its
/// 3 × 3 neighbours predict for it — a neighbour n at offset o from q predicts
/// `m_n + M_n·(−o)` — counting only neighbours of the same exemplar frame and time direction
/// whose prediction is within [`SETTLE_TOLERANCE`] of the match's own (the same piece of
/// the field), and only where there are at least three.
///
/// Every match of the shifted field is warped on its own (its own time step, its own rest of
/// the motion, its own sub-pixel offset), so neighbours that continued each other drift apart
/// by fractions of a pixel, a little more every frame: a random walk. The vote then averages
/// patches that no longer agree, and the paint washes out over a long animation (measured on
/// the 300-frame target, green-wash: 64 % of the interior's neighbours continued each other
/// within ½ px at frame 1, 21 % at frame 70; the contrast of the last windows 0.54 of the
/// exemplar's). The median pulls each match back onto the piece it belongs to and leaves the
/// boundaries between pieces where they are (a neighbour of another piece is out of
/// tolerance); a piece that moves as a whole moves the same.
fn settle(f: &Nnf, active: &[bool]) -> Nnf {
    let mut out = Nnf::new(f.w, f.h);
    out.data.par_iter_mut().enumerate().for_each(|(q, o)| {
        let m = f.data[q];
        *o = m;
        if !m.ok || !active[q] {
            return;
        }
        let (qx, qy) = ((q % f.w) as isize, (q / f.w) as isize);
        let (mut xs, mut ys, mut n) = ([0f32; 9], [0f32; 9], 0);
        for b in -1..=1isize {
            for a in -1..=1isize {
                let (nx, ny) = (qx + a, qy + b);
                if nx < 0 || ny < 0 || nx >= f.w as isize || ny >= f.h as isize {
                    continue;
                }
                let mn = &f.data[ny as usize * f.w + nx as usize];
                if !mn.ok || mn.i != m.i || mn.flip != m.flip {
                    continue;
                }
                let (dx, dy) = mn.rotate(-a as f32, -b as f32);
                let (px, py) = (mn.x + dx, mn.y + dy);
                if (px - m.x).abs() > SETTLE_TOLERANCE || (py - m.y).abs() > SETTLE_TOLERANCE {
                    continue;
                }
                (xs[n], ys[n]) = (px, py);
                n += 1;
            }
        }
        if n >= 3 {
            (o.x, o.y) = (median(&xs[..n]), median(&ys[..n]));
        }
    });
    out
}

/// The element of rank `len / 2` of at most 9 values in the order of [`f32::total_cmp`]: the one
/// with at most `len / 2` keys below its own and more than `len / 2` at or below it, the keys
/// being the integers `total_cmp` compares (counted without branches: on so few values, faster
/// than a selection's data-dependent branches).
#[inline]
fn median(v: &[f32]) -> f32 {
    // The key is its own inverse: flipping the magnitude bits of the negative values.
    let key = |bits: i32| bits ^ (((bits >> 31) as u32) >> 1) as i32;
    let mut keys = [0i32; 9];
    for (k, x) in keys.iter_mut().zip(v) {
        *k = key(x.to_bits() as i32);
    }
    let (keys, mid) = (&keys[..v.len()], v.len() / 2);
    for &kj in keys {
        let (mut below, mut at_or_below) = (0, 0);
        for &k in keys {
            below += (k < kj) as usize;
            at_or_below += (k <= kj) as usize;
        }
        if below <= mid && mid < at_or_below {
            return f32::from_bits(key(kj) as u32);
        }
    }
    unreachable!("some key has the middle rank")
}

/// The source distance field of frame i at (x, y), bilinear, and its gradient (central
/// differences of the samples); `None` outside the frame.
fn dist_and_gradient(src: &SourceLevel, i: usize, x: f32, y: f32) -> Option<(f32, Vec2)> {
    let d = |x: f32, y: f32| -> Option<f32> {
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (xi, yi) = (x0 as isize, y0 as isize);
        if xi < 0 || yi < 0 || xi + 1 >= src.w as isize || yi + 1 >= src.h as isize {
            return None;
        }
        let at = |a: usize, b: usize| src.info[src.index(i, a, b)].dist;
        let (xi, yi) = (xi as usize, yi as usize);
        let top = at(xi, yi) * (1.0 - fx) + at(xi + 1, yi) * fx;
        let bot = at(xi, yi + 1) * (1.0 - fx) + at(xi + 1, yi + 1) * fx;
        Some(top * (1.0 - fy) + bot * fy)
    };
    let c = d(x, y)?;
    let g = Vec2::new(d(x + 1.0, y)? - d(x - 1.0, y)?, d(x, y + 1.0)? - d(x, y - 1.0)?) * 0.5;
    Some((c, g))
}

/// Most pixels a match moves in one re-anchoring step.
const REANCHOR_MAX: f32 = 3.0;

/// Moves the source point (x, y) of frame i along the gradient of its distance field until its
/// distance from the exemplar's edge equals the target's, `t_dist`, when either lies within
/// `band` pixels of its edge (two Newton steps of at most [`REANCHOR_MAX`] pixels). `None`
/// where nothing moves or there is no gradient.
fn reanchor(src: &SourceLevel, i: usize, x: f32, y: f32, t_dist: f32, band: f32) -> Option<(f32, f32)> {
    let (mut x, mut y) = (x, y);
    let mut moved = false;
    for _ in 0..2 {
        let (sd, g) = dist_and_gradient(src, i, x, y)?;
        if sd.min(band) == t_dist.min(band) {
            break;
        }
        let e = (t_dist.min(band.max(sd)) - sd).clamp(-REANCHOR_MAX, REANCHOR_MAX);
        let gl = g.length();
        if gl < 0.5 || e.abs() < 0.05 {
            break;
        }
        let step = g / gl * e / gl.min(1.0);
        x += step.x;
        y += step.y;
        moved = true;
    }
    moved.then_some((x, y))
}

/// `1 − smoothstep(v; m_l, m_u)`: 1 for v ≤ m_l, 0 for v ≥ m_u (the thesis's
/// `smoothstep(v, m_u, m_l)` with its reversed bounds — the weight falls as the mismatch grows).
#[inline]
pub(crate) fn modulation(v: f32, m_l: f32, m_u: f32) -> f32 {
    let t = ((v - m_l) / (m_u - m_l)).clamp(0.0, 1.0);
    1.0 - t * t * (3.0 - 2.0 * t)
}

/// Fills `tgt.mw` with m(q)·w_prev: 0 where the previous frame's mask (`prev_mask`, this
/// level) did not cover q or there is no shifted match; else the modulation of
/// `|min(T^dist(q), b) − min(S^dist(i+Δi, x, y), b)|` (distances compared after clamping to
/// the border width b, as the thesis compares `I^df`).
pub(crate) fn fill_modulation(
    tgt: &mut TargetLevel,
    src: &SourceLevel,
    shifted: &Nnf,
    prev_mask: &[bool],
    b: f32,
    bounds: (f32, f32),
    w_prev: f32,
) {
    let info = &tgt.info;
    tgt.mw.par_iter_mut().enumerate().for_each(|(q, mw)| {
        *mw = 0.0;
        let m = &shifted.data[q];
        if info[q].flags & VALID == 0 || !m.ok || !prev_mask[q] {
            return;
        }
        let Some((_, s)) = src.info_at(m.i as usize, m.x, m.y) else { return };
        let v = (info[q].dist.min(b) - s.dist.min(b)).abs();
        *mw = w_prev * modulation(v, bounds.0, bounds.1);
    });
}

/// True when the previous frame's pixel was inside its mask.
pub(crate) fn mask_flags(tgt: &TargetLevel) -> Vec<bool> {
    tgt.info.iter().map(|i| i.flags & IN_MASK != 0).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The median is the element `select_nth_unstable_by(len / 2, f32::total_cmp)` picks, bit
    /// for bit: signed zeros, negative values, repeats.
    #[test]
    fn median_is_the_total_order_median() {
        let mut rng = crate::rng::SplitMix64::keyed(&[11]);
        let pool = [0.0, -0.0, 1.5, -1.5, 2.25, -3.0, 1e-30, -1e-30, 7.0, 100.0];
        for _ in 0..5000 {
            let n = 3 + rng.below(7);
            let v: Vec<f32> = (0..n)
                .map(|_| if rng.next_f32() < 0.5 { pool[rng.below(pool.len())] } else { rng.range(-50.0, 50.0) })
                .collect();
            let mut sel = v.clone();
            let want = *sel.select_nth_unstable_by(n / 2, f32::total_cmp).1;
            assert_eq!(median(&v).to_bits(), want.to_bits(), "{v:?}");
        }
    }

    #[test]
    fn modulation_falls_with_mismatch() {
        assert_eq!(modulation(0.0, 2.0, 10.0), 1.0);
        assert_eq!(modulation(2.0, 2.0, 10.0), 1.0);
        assert_eq!(modulation(10.0, 2.0, 10.0), 0.0);
        assert!((modulation(6.0, 2.0, 10.0) - 0.5).abs() < 1e-6);
        assert!(modulation(4.0, 2.0, 10.0) > modulation(8.0, 2.0, 10.0));
    }

    #[test]
    fn flow_turn_is_the_local_rotation() {
        let (w, h) = (21, 21);
        let center = Vec2::new(10.0, 7.0);
        let rigid = |turn: f32, shift: Vec2| -> Vec<Vec2> {
            (0..w * h)
                .map(|q| {
                    let p = Vec2::new((q % w) as f32, (q / w) as f32) - center;
                    Vec2::from_angle(turn).rotate(p) - p + shift
                })
                .collect()
        };
        let inside = vec![5.0f32; w * h];
        // A rigid turn by a gives sin a everywhere, whatever the centre and an added translation.
        for (a, q) in [(0.02f32, 10 * w + 10), (-0.05, 3 * w + 15), (0.01, 17 * w + 2)] {
            let t = flow_turn(&rigid(a, Vec2::new(1.5, -0.7)), &inside, w, q);
            assert!((t - a.sin()).abs() < 1e-5, "turn {a}: {t}");
        }
        // A translation, or a uniform growth, turns nothing.
        assert_eq!(flow_turn(&vec![Vec2::new(2.0, 1.0); w * h], &inside, w, 10 * w + 10), 0.0);
        let grow: Vec<Vec2> = (0..w * h).map(|q| (Vec2::new((q % w) as f32, (q / w) as f32) - center) * 0.1).collect();
        assert!(flow_turn(&grow, &inside, w, 10 * w + 10).abs() < 1e-6);
        // Next to the frame's edge or the mask's, nothing is known.
        assert_eq!(flow_turn(&rigid(0.02, Vec2::ZERO), &inside, w, w + 1), 0.0);
        let mut edge = inside.clone();
        edge[10 * w + 12] = -1.0;
        assert_eq!(flow_turn(&rigid(0.02, Vec2::ZERO), &edge, w, 10 * w + 10), 0.0);
    }
}
