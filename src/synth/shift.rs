//! Temporal coherence by time shift (paper §3.4, thesis §3.7): SHIFTNNF moves each match of
//! the previous frame along the exemplar's own time axis by the Δi whose exemplar motion best
//! matches the target motion, and m(q) modulates the temporal weight.

use super::nnf::{Match, Nnf};
use super::source::{IN_MASK, SourceLevel, VALID};
use super::target::TargetLevel;
use rayon::prelude::*;

/// SHIFTNNF. `prev` is the previous frame's full-resolution field, `ext_prev` / `ext_cur` are
/// `T^ext+` of the previous and the current frame (row-major, full resolution), `active`
/// tells which pixels the current frame synthesizes.
///
/// For a match (i, x, y) with aligned flows, Δi ≥ 0 minimizes
/// `|ΔT − (S^ext+(i+Δi, x, y) − S^ext+(i, x, y))|` with `ΔT = T^ext+(j) − T^ext+(j−1)`;
/// with opposite flows ([`Match::flip`]), Δi ≤ 0 minimizes the same with `S^ext−`.
/// Δi stays inside the exemplar (when it runs out the paint lags; m(q) handles that).
pub(crate) fn shift_nnf(
    src: &SourceLevel,
    prev: &Nnf,
    ext_prev: &[f32],
    ext_cur: &[f32],
    active: &[bool],
    enabled: bool,
) -> Nnf {
    let mut out = Nnf::new(prev.w, prev.h);
    out.data.par_iter_mut().enumerate().for_each(|(q, o)| {
        let m = &prev.data[q];
        if !m.ok || !active[q] {
            return;
        }
        if !enabled {
            *o = Match { err: f32::INFINITY, ..*m };
            return;
        }
        let dt = ext_cur[q] - ext_prev[q];
        let i = m.i as usize;
        let Some((idx0, _)) = src.info_at(i, m.x, m.y) else {
            *o = *m;
            return;
        };
        let pix = idx0 - i * src.frame_len;
        let val = |k: usize| {
            let inf = &src.info[k * src.frame_len + pix];
            if m.flip { inf.ext_neg } else { inf.ext_pos }
        };
        let base = val(i);
        let mut best = (dt - 0.0).abs();
        let mut best_i = i;
        let mut consider = |k: usize| {
            let d = (dt - (val(k) - base)).abs();
            if d < best {
                best = d;
                best_i = k;
            }
        };
        if m.flip {
            (0..i).rev().for_each(&mut consider);
        } else {
            (i + 1..src.frames).for_each(&mut consider);
        }
        *o = Match { i: best_i as u16, err: f32::INFINITY, ..*m };
    });
    out
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

    #[test]
    fn modulation_falls_with_mismatch() {
        assert_eq!(modulation(0.0, 2.0, 10.0), 1.0);
        assert_eq!(modulation(2.0, 2.0, 10.0), 1.0);
        assert_eq!(modulation(10.0, 2.0, 10.0), 0.0);
        assert!((modulation(6.0, 2.0, 10.0) - 0.5).abs() < 1e-6);
        assert!(modulation(4.0, 2.0, 10.0) > modulation(8.0, 2.0, 10.0));
    }
}
