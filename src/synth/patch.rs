//! The patch error D(p, q) over a rotated 5 × 5 window (paper §3, thesis §3.7 and §4.4.1):
//!
//! ```text
//! D = Σ_{p′,q′} w_col·|S^rgb(p′) − T^rgb(q′)|² + w_df·|S^df − T^df|²
//!             + [m(q) = 0]·w_ext·(|S^ext+ − T^ext±|² + |S^ext− − T^ext∓|²)
//!             + m(q)·w_prev·|S^rgb(p′) − T^prev(q′)|²  +  λ·Ω*(p′)/(n²·ω*)
//! ```
//!
//! where p′ runs over the window around the sub-pixel source center rotated by θ, and ext±
//! are swapped when the rotated flows oppose. The extent term applies only where no paint is
//! carried from the previous frame (m(q)·w_prev = 0: the first frame, newly covered pixels):
//! a deviation from the paper, whose extent term applies everywhere — measured on the quality
//! suite's 25 moving runs it raised edge darkening from 0.84 to 0.89 on average and lowered
//! incoherent change from 0.92 to 0.82, with the palette within 0.03 on 20 of 30 runs instead of
//! 15 (docs/quality.md). The occurrence penalty rides in the pixel's
//! eighth lane as `√(penalty/w_Ω)` against a target lane of 0, so it is one more weighted
//! squared difference ([`super::occurrence::Occurrence`]). In this search metric each rotated tap
//! reads the nearest exemplar pixel (at most ½ px away); voting samples the rotated windows at
//! their exact sub-pixel positions, bilinearly, and bicubically for the output
//! ([`super::vote`]). The direction term `w_dir·|tan(…)|` is dropped as in the thesis's
//! implementation (§4.4.1): the θ rule already aligns the flows. The sum stops early once it
//! exceeds the best error found so far.
//!
//! Hot path: no trigonometry (the rotation is a stored matrix), no allocation, no bounds
//! checks in the inner loop (centers are validated: every tap stays inside the padded
//! frame), 8-lane pixels that vectorize, and a runtime-dispatched AVX2 build of the same code.

use super::params::{HALF, PATCH};
use super::source::{Feat, LANES, OMEGA_LANE, PAD, SourceLevel};
use super::target::TargetLevel;

/// Everything about one evaluation except the candidate itself.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Query {
    /// Padded index of the target center in [`TargetLevel::cur`].
    pub tq: usize,
    /// Weight of the color lanes (1, or 0 for the guide-only initialization pass).
    pub w_col: f32,
    /// m(q)·w_prev.
    pub mw: f32,
    /// Weight w_Ω of the occurrence lane (0 where the features carry no Ω).
    pub w_om: f32,
}

/// The target side of D for one target pixel q, gathered once and reused by every candidate
/// tried for q: the two color terms against `T^rgb` and `T^prev` folded into one,
///
/// ```text
/// a·(v − t)² + b·(v − p)² = (a + b)·(v − m)² + a·b/(a + b)·(t − p)²,   m = t + b/(a + b)·(p − t),
/// ```
///
/// whose second part does not depend on the candidate (`base`), so a tap costs one weighted
/// squared difference of 8 lanes read from this small block instead of two from the strided
/// target (a = w_col·w_rgb, b = m(q)·w_prev·w_rgb; b/(a + b) is the same for the three color
/// lanes).
///
/// The window also holds its point reflection with ext± swapped (`flip`): the flipped rotation
/// −M of a candidate reads exactly the source pixels of M, tap (a, b) of −M being tap
/// (−a, −b) of M, so the flipped error is the aligned one against the reflected window, and
/// both come from one pass over the source pixels ([`patch_error_pair`]).
#[derive(Clone, Debug)]
pub(crate) struct Window {
    /// m(q′) per tap (row-major over the n × n window), in quantization units.
    taps: [[f32; LANES]; PATCH * PATCH],
    /// `taps` point-reflected (`flip[k] = taps[n² − 1 − k]`) with lanes ext+ and ext− swapped.
    flip: [[f32; LANES]; PATCH * PATCH],
    /// Per-lane weights: `(w_col + m(q)·w_prev)·w_rgb` for the three color lanes, then `w_df`,
    /// `w_ext`, `w_ext`, 0 (flags) and `w_Ω`.
    w: [f32; LANES],
    /// The candidate-independent part of the temporal term, Σ a·b/(a + b)·(t − p)².
    base: f32,
}

impl Window {
    /// Gathers the window of target pixel `q.tq`.
    pub fn new(src: &SourceLevel, tgt: &TargetLevel, q: &Query) -> Window {
        let lw = &src.lane_w;
        let mw = q.mw.max(0.0);
        let sum = q.w_col + mw;
        // b/(a + b) and a·b/(a + b) per lane (zero but for the color lanes).
        let (beta, gamma) = if mw > 0.0 && sum > 0.0 { (mw / sum, q.w_col * mw / sum) } else { (0.0, 0.0) };
        let beta = [beta, beta, beta, 0.0, 0.0, 0.0, 0.0, 0.0];
        let gamma: [f32; LANES] = std::array::from_fn(|k| if k < 3 { gamma * lw[k] } else { 0.0 });
        let mut w = [sum * lw[0], sum * lw[1], sum * lw[2], lw[3], lw[4], lw[5], 0.0, 0.0];
        w[OMEGA_LANE] = q.w_om;
        // Where the previous frame's paint is carried (m(q)·w_prev > 0), the extents no longer
        // choose the paint: its age was chosen where it first appeared, and the time shift
        // advances it. Comparing the carried match's extents again would pull it off the field
        // the temporal term holds (the target's extents keep changing with its motion).
        if mw > 0.0 {
            w[4] = 0.0;
            w[5] = 0.0;
        }
        // The reflected window swaps ext± on the target side, which needs equal weights.
        debug_assert_eq!(w[4], w[5]);
        let top = q.tq - HALF - HALF * tgt.stride;
        let (cur, prev) = (&tgt.cur[top..], &tgt.prev[top..]);
        assert!(cur.len() > (PATCH - 1) * tgt.stride + PATCH - 1 && prev.len() == cur.len());
        let mut win = Window { taps: [[0.0; LANES]; PATCH * PATCH], flip: [[0.0; LANES]; PATCH * PATCH], w, base: 0.0 };
        #[cfg(target_arch = "x86_64")]
        {
            if has_avx2() {
                // SAFETY: the CPU supports AVX2 (checked above); the body is the same safe code.
                unsafe { gather_avx2(&mut win, cur, prev, tgt.stride, beta, gamma) };
                return win;
            }
        }
        gather(&mut win, cur, prev, tgt.stride, beta, gamma);
        win
    }
}

/// Fills the taps of `win` from the n × n block of `cur` / `prev` (rows `stride` apart)
/// starting at index 0, and the temporal base.
#[inline(always)]
fn gather(
    win: &mut Window,
    cur: &[[f32; LANES]],
    prev: &[[f32; LANES]],
    stride: usize,
    beta: [f32; LANES],
    gamma: [f32; LANES],
) {
    let mut base = [0.0f32; LANES];
    for row in 0..PATCH {
        let at = row * stride;
        let (cur, prev) = (&cur[at..at + PATCH], &prev[at..at + PATCH]);
        for a in 0..PATCH {
            let (t, p) = (&cur[a], &prev[a]);
            let d: [f32; LANES] = std::array::from_fn(|k| p[k] - t[k]);
            let m: [f32; LANES] = std::array::from_fn(|k| t[k] + beta[k] * d[k]);
            for k in 0..LANES {
                base[k] += gamma[k] * d[k] * d[k];
            }
            let j = row * PATCH + a;
            win.taps[j] = m;
            win.flip[PATCH * PATCH - 1 - j] = [m[0], m[1], m[2], m[3], m[5], m[4], m[6], m[7]];
        }
    }
    win.base = base.iter().sum();
}

/// [`gather`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn gather_avx2(
    win: &mut Window,
    cur: &[[f32; LANES]],
    prev: &[[f32; LANES]],
    stride: usize,
    beta: [f32; LANES],
    gamma: [f32; LANES],
) {
    gather(win, cur, prev, stride, beta, gamma)
}

/// D for the source center `at` (frame i, (cx, cy), rotation M = (c, s)) against target window
/// `win`, reading the exemplar pixels from `feat` (the level's features, or a copy with the
/// occurrence lane filled); returns a value `> best` (possibly partial) once the running sum
/// exceeds `best`. `flip` compares ext± swapped (the candidate of the +π option, M = (c, s)
/// being that option's matrix).
///
/// The caller guarantees that the center's nearest pixel is a valid center (≥ `MARGIN` px from
/// the border), so every tap lies inside the padded frame, and that `feat` has the level's
/// layout.
#[inline]
pub(crate) fn patch_error(src: &SourceLevel, feat: &[Feat], win: &Window, at: Center, flip: bool, best: f32) -> f32 {
    // The flipped option with M reads the taps of −M against the reflected window.
    let (at, taps) = if flip { (Center { c: -at.c, s: -at.s, ..at }, &win.flip) } else { (at, &win.taps) };
    kernel::<false>(src, feat, win, [taps, taps], at, best).0
}

/// Both options of the flow-alignment rule at once: D with rotation M = (c, s) and D with −M
/// and ext± swapped, from one pass over the 25 source pixels they share. Returns
/// `(D(M), D(−M, flipped))`; the pass stops early once both running sums exceed `best`, and
/// each value is bit-identical to [`patch_error`]'s when neither stops early. Same contract
/// as [`patch_error`].
#[inline]
pub(crate) fn patch_error_pair(src: &SourceLevel, feat: &[Feat], win: &Window, at: Center, best: f32) -> (f32, f32) {
    kernel::<true>(src, feat, win, [&win.taps, &win.flip], at, best)
}

/// Target taps of one evaluation.
type Taps = [[f32; LANES]; PATCH * PATCH];

/// A candidate of the kernel: frame i, sub-pixel center (cx, cy), rotation M = (c, s).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Center {
    pub i: usize,
    pub cx: f32,
    pub cy: f32,
    pub c: f32,
    pub s: f32,
}

/// The kernel: with `PAIR`, the errors against `taps[0]` and `taps[1]`, else only the first.
#[inline(always)]
fn kernel<const PAIR: bool>(
    src: &SourceLevel,
    feat: &[Feat],
    win: &Window,
    taps: [&Taps; 2],
    at: Center,
    best: f32,
) -> (f32, f32) {
    let Center { cx, cy, .. } = at;
    debug_assert!(cx > -0.5 + super::source::MARGIN as f32 - 0.51 && cy > -0.5 + super::source::MARGIN as f32 - 0.51);
    debug_assert!(cx < (src.w - super::source::MARGIN) as f32 && cy < (src.h - super::source::MARGIN) as f32);
    debug_assert_eq!(feat.len(), src.feat.len());
    #[cfg(target_arch = "x86_64")]
    {
        if has_avx2() {
            // SAFETY: the CPU supports AVX2 (checked above); the body is the same safe code.
            return unsafe { kernel_avx2::<PAIR>(src, feat, win, taps, at, best) };
        }
    }
    kernel_generic::<PAIR>(src, feat, win, taps, at, best)
}

/// Whether the AVX2 builds of the hot loops may run (the CPU has AVX2, and
/// `FLUIDYMATION_NO_SIMD` is not set).
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn has_avx2() -> bool {
    use std::sync::atomic::{AtomicU8, Ordering};
    static STATE: AtomicU8 = AtomicU8::new(0);
    match STATE.load(Ordering::Relaxed) {
        1 => false,
        2 => true,
        _ => {
            let yes = std::is_x86_feature_detected!("avx2") && std::env::var_os("FLUIDYMATION_NO_SIMD").is_none();
            STATE.store(if yes { 2 } else { 1 }, Ordering::Relaxed);
            yes
        }
    }
}

/// Tap offsets (a − r, b − r) of the n × n window in row-major order, padded with zeros to a
/// multiple of 8 for the AVX2 index computation.
pub(crate) const OFFS: usize = (PATCH * PATCH).div_ceil(8) * 8;
const TAP_A: [f32; OFFS] = window_offsets(true);
const TAP_B: [f32; OFFS] = window_offsets(false);

const fn window_offsets(column: bool) -> [f32; OFFS] {
    let mut out = [0.0f32; OFFS];
    let mut k = 0;
    while k < PATCH * PATCH {
        let v = if column { k % PATCH } else { k / PATCH };
        out[k] = v as f32 - HALF as f32;
        k += 1;
    }
    out
}

/// The horizontal sum of 8 lanes in a fixed tree order, `((a0+a4)+(a2+a6)) + ((a1+a5)+(a3+a7))`,
/// which the AVX2 build computes the same way.
#[inline(always)]
fn tree_sum(a: &[f32; LANES]) -> f32 {
    let s: [f32; 4] = std::array::from_fn(|k| a[k] + a[k + 4]);
    (s[0] + s[2]) + (s[1] + s[3])
}

/// The offsets from frame i's first padded pixel of the n² taps of the rotated window around
/// `at` (row-major; zeros after the n²-th): the pixel nearest to `(cx, cy) + M·(a − r, b − r)`
/// in padded coordinates, `⌊x + ½⌋` by truncation (padded coordinates are positive). Same
/// contract as [`patch_error`] (a valid center).
#[inline(always)]
pub(crate) fn tap_offsets(stride: usize, at: Center) -> [i32; OFFS] {
    let Center { cx, cy, c, s, .. } = at;
    let (px, py) = (cx + PAD as f32, cy + PAD as f32);
    let mut offs = [0i32; OFFS];
    for (k, o) in offs.iter_mut().enumerate().take(PATCH * PATCH) {
        let (af, bf) = (TAP_A[k], TAP_B[k]);
        let sx = px + (c * af - s * bf);
        let sy = py + (s * af + c * bf);
        *o = (sy + 0.5) as i32 * stride as i32 + (sx + 0.5) as i32;
    }
    offs
}

/// [`tap_offsets`] 8 at a time (the same operations in the same order).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(crate) fn tap_offsets_avx2(stride: usize, at: Center) -> [i32; OFFS] {
    use std::arch::x86_64::*;
    let Center { cx, cy, c, s, .. } = at;
    let (px, py) = (cx + PAD as f32, cy + PAD as f32);
    let mut offs = [0i32; OFFS];
    let (cv, sv) = (_mm256_set1_ps(c), _mm256_set1_ps(s));
    let (pxv, pyv, half) = (_mm256_set1_ps(px), _mm256_set1_ps(py), _mm256_set1_ps(0.5));
    let stride_v = _mm256_set1_epi32(stride as i32);
    for v in 0..OFFS / 8 {
        // SAFETY: TAP_A, TAP_B and `offs` hold OFFS values.
        let (af, bf) = unsafe { (_mm256_loadu_ps(TAP_A[v * 8..].as_ptr()), _mm256_loadu_ps(TAP_B[v * 8..].as_ptr())) };
        let sx = _mm256_add_ps(pxv, _mm256_sub_ps(_mm256_mul_ps(cv, af), _mm256_mul_ps(sv, bf)));
        let sy = _mm256_add_ps(pyv, _mm256_add_ps(_mm256_mul_ps(sv, af), _mm256_mul_ps(cv, bf)));
        let ix = _mm256_cvttps_epi32(_mm256_add_ps(sx, half));
        let iy = _mm256_cvttps_epi32(_mm256_add_ps(sy, half));
        let o = _mm256_add_epi32(_mm256_mullo_epi32(iy, stride_v), ix);
        // SAFETY: as above.
        unsafe { _mm256_storeu_si256(offs[v * 8..].as_mut_ptr() as *mut __m256i, o) };
    }
    // The padding lanes (offset 0 from TAP_A = TAP_B = 0) are not taps.
    offs[PATCH * PATCH..].fill(0);
    offs
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn kernel_avx2<const PAIR: bool>(
    src: &SourceLevel,
    feat: &[Feat],
    win: &Window,
    taps: [&Taps; 2],
    at: Center,
    best: f32,
) -> (f32, f32) {
    use std::arch::x86_64::*;
    let fp = feat.as_ptr();
    let fbase = at.i * src.frame_len;
    let (ta, tb) = (taps[0].as_ptr() as *const f32, taps[1].as_ptr() as *const f32);
    // SAFETY: `w` holds 8 floats.
    let w = unsafe { _mm256_loadu_ps(win.w.as_ptr()) };
    // Two accumulators per error (even and odd columns) halve the chain of dependent additions.
    let mut acc = [_mm256_setzero_ps(); 4];
    // The tree order of `tree_sum`.
    let hsum = |x: __m256| -> f32 {
        let s4 = _mm_add_ps(_mm256_castps256_ps128(x), _mm256_extractf128_ps::<1>(x));
        let s2 = _mm_add_ps(s4, _mm_movehl_ps(s4, s4));
        _mm_cvtss_f32(_mm_add_ss(s2, _mm_shuffle_ps::<1>(s2, s2))) + win.base
    };
    let totals = |acc: &[__m256; 4]| {
        let a = hsum(_mm256_add_ps(acc[0], acc[1]));
        (a, if PAIR { hsum(_mm256_add_ps(acc[2], acc[3])) } else { a })
    };
    let offs = tap_offsets_avx2(src.stride, at);
    for b in 0..PATCH {
        for a in 0..PATCH {
            // SAFETY (all unchecked accesses below): the padded coordinates are positive and
            // inside frame i's padded block by the validity rule; the windows have n² taps;
            // the CPU has AVX2 (checked by the caller).
            let idx = fbase + offs[b * PATCH + a] as usize;
            debug_assert!(idx < feat.len());
            let bytes = unsafe { _mm_loadl_epi64(fp.add(idx) as *const __m128i) };
            let v = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(bytes));
            let k = (b * PATCH + a) * LANES;
            let d = _mm256_sub_ps(v, unsafe { _mm256_loadu_ps(ta.add(k)) });
            acc[a & 1] = _mm256_add_ps(acc[a & 1], _mm256_mul_ps(_mm256_mul_ps(w, d), d));
            if PAIR {
                let e = _mm256_sub_ps(v, unsafe { _mm256_loadu_ps(tb.add(k)) });
                acc[2 + (a & 1)] = _mm256_add_ps(acc[2 + (a & 1)], _mm256_mul_ps(_mm256_mul_ps(w, e), e));
            }
        }
        let (x, y) = totals(&acc);
        if x > best && y > best {
            return (x, y);
        }
    }
    totals(&acc)
}

fn kernel_generic<const PAIR: bool>(
    src: &SourceLevel,
    feat: &[Feat],
    win: &Window,
    taps: [&Taps; 2],
    at: Center,
    best: f32,
) -> (f32, f32) {
    let fbase = at.i * src.frame_len;
    let offs = tap_offsets(src.stride, at);
    let w = &win.w;
    let mut acc = [[0.0f32; LANES]; 4];
    let sum = |p: &[f32; LANES], q: &[f32; LANES]| tree_sum(&std::array::from_fn(|k| p[k] + q[k])) + win.base;
    let totals = |acc: &[[f32; LANES]; 4]| {
        let a = sum(&acc[0], &acc[1]);
        (a, if PAIR { sum(&acc[2], &acc[3]) } else { a })
    };
    for b in 0..PATCH {
        for a in 0..PATCH {
            let idx = fbase + offs[b * PATCH + a] as usize;
            debug_assert!(idx < feat.len());
            // SAFETY: idx lies in frame i's padded block (validity rule above).
            let v = unsafe { feat.get_unchecked(idx) }.map(f32::from);
            let k = b * PATCH + a;
            for (e, t) in taps.iter().take(if PAIR { 2 } else { 1 }).enumerate() {
                let acc = &mut acc[2 * e + (a & 1)];
                for l in 0..LANES {
                    let d = v[l] - t[k][l];
                    acc[l] += w[l] * d * d;
                }
            }
        }
        let (x, y) = totals(&acc);
        if x > best && y > best {
            return (x, y);
        }
    }
    totals(&acc)
}

/// A plain, obviously-correct version of [`patch_error`] (no early exit, straight loops, f64
/// sums), for tests.
#[cfg(test)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn patch_error_reference(
    src: &SourceLevel,
    feat: &[Feat],
    tgt: &TargetLevel,
    q: Query,
    i: usize,
    cx: f32,
    cy: f32,
    c: f32,
    s: f32,
    flip: bool,
) -> f64 {
    let mut total = 0.0f64;
    let sample = |x: f32, y: f32| -> [f32; LANES] {
        let px = (x + 0.5).floor() as usize;
        let py = (y + 0.5).floor() as usize;
        feat[i * src.frame_len + py * src.stride + px].map(|b| b as f32)
    };
    for b in -(HALF as isize)..=HALF as isize {
        for a in -(HALF as isize)..=HALF as isize {
            let (a, b) = (a as f32, b as f32);
            let x = cx + PAD as f32 + (c * a - s * b);
            let y = cy + PAD as f32 + (s * a + c * b);
            let mut v = sample(x, y);
            if flip {
                v.swap(4, 5);
            }
            let ti = (q.tq as isize + b as isize * tgt.stride as isize + a as isize) as usize;
            let t = tgt.cur[ti];
            let p = tgt.prev[ti];
            let lw = &src.lane_w;
            for k in 0..3 {
                total += (q.w_col * lw[k] * (v[k] - t[k]).powi(2)) as f64;
                total += (q.mw * lw[k] * (v[k] - p[k]).powi(2)) as f64;
            }
            // The boundary term always; the extent terms only where nothing is carried.
            let ext_on = q.mw <= 0.0;
            for k in 3..6 {
                if k == 3 || ext_on {
                    total += (lw[k] * (v[k] - t[k]).powi(2)) as f64;
                }
            }
            // The occurrence penalty w_Ω·q².
            total += (q.w_om * v[OMEGA_LANE] * v[OMEGA_LANE]) as f64;
        }
    }
    total
}

/// A kernel candidate from its parts (tests).
#[cfg(test)]
pub(crate) fn at(i: usize, cx: f32, cy: f32, c: f32, s: f32) -> Center {
    Center { i, cx, cy, c, s }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::guide::FrameGuides;
    use crate::img::Plane;
    use crate::rng::SplitMix64;
    use crate::synth::params::Params;
    use crate::synth::source::{SourcePyramid, VALID};
    use glam::Vec2;

    /// Synthetic guides: a disc of radius `r` with noisy channels.
    pub(crate) fn synthetic(w: usize, h: usize, r: f32, seed: u64) -> (Plane<[f32; 3]>, FrameGuides) {
        let mut rng = SplitMix64::keyed(&[seed]);
        let (cx, cy) = (w as f32 / 2.0, h as f32 / 2.0);
        let dist = Plane::from_fn(w, h, |x, y| r - ((x as f32 - cx).powi(2) + (y as f32 - cy).powi(2)).sqrt());
        let mask = dist.map(|d| d >= 0.0);
        let flow = Plane::from_fn(w, h, |x, y| Vec2::new(x as f32 - cx, y as f32 - cy) * 0.05);
        let ext_pos = Plane::from_fn(w, h, |_, _| rng.next_f32() * 5.0);
        let ext_neg = Plane::from_fn(w, h, |_, _| rng.next_f32() * 5.0);
        let rgb = Plane::from_fn(w, h, |_, _| [rng.next_f32(), rng.next_f32(), rng.next_f32()]);
        (rgb, FrameGuides { mask, dist, flow, ext_pos, ext_neg })
    }

    #[test]
    fn kernel_matches_reference_and_terminates_early() {
        let params = Params::builder().build().unwrap();
        let frames: Vec<_> = (0..3).map(|k| synthetic(40, 36, 14.0, k)).collect();
        let rgb: Vec<_> = frames.iter().map(|f| f.0.clone()).collect();
        let g: Vec<_> = frames.iter().map(|f| f.1.clone()).collect();
        let pyr = SourcePyramid::build(&rgb, &g, &params, 6.0, 1);
        let src = &pyr.levels[0];
        let (trgb, tg) = synthetic(30, 30, 12.0, 99);
        let mut tgt = TargetLevel::new(&tg, &pyr.quant, 6.0, None, src.ext_falloff, [1.0, 1.0, 1.0], false);
        let mut rng = SplitMix64::keyed(&[5]);
        for (k, px) in tgt.cur.iter_mut().enumerate() {
            let c = trgb.data()[k % trgb.len()];
            px[..3].copy_from_slice(&c.map(|v| v * 255.0));
        }
        for px in tgt.prev.iter_mut() {
            px[..3].copy_from_slice(&[rng.next_f32() * 255.0, rng.next_f32() * 255.0, rng.next_f32() * 255.0]);
        }
        let mut feat = src.feat.clone();
        for f in feat.iter_mut() {
            f[OMEGA_LANE] = rng.below(256) as u8;
        }
        let mut checked = 0;
        for _ in 0..400 {
            let list = &src.valid[rng.below(2)];
            if list.is_empty() {
                continue;
            }
            let (i, x, y) = src.coords(list[rng.below(list.len())] as usize);
            let (cx, cy) = (x as f32 + rng.range(-0.49, 0.49), y as f32 + rng.range(-0.49, 0.49));
            let th = rng.range(-std::f32::consts::PI, std::f32::consts::PI);
            let (c, s) = (th.cos(), th.sin());
            let q = tgt.active[rng.below(tgt.active.len())] as usize;
            let query = Query {
                tq: tgt.pindex(q % 30, q / 30),
                w_col: 1.0,
                mw: if rng.next_f32() < 0.5 { 0.0 } else { 0.7 },
                w_om: if rng.next_f32() < 0.3 { 0.0 } else { 1e-4 },
            };
            let flip = rng.next_f32() < 0.5;
            assert!(src.info_at(i, cx, cy).unwrap().1.flags & VALID != 0);
            let win = Window::new(src, &tgt, &query);
            let fast = patch_error(src, &feat, &win, at(i, cx, cy, c, s), flip, f32::INFINITY);
            let slow = patch_error_reference(src, &feat, &tgt, query, i, cx, cy, c, s, flip);
            assert!(((fast as f64) - slow).abs() <= 1e-4 * slow.max(1.0), "{fast} vs {slow}");
            let taps = if flip { &win.flip } else { &win.taps };
            let (gc, gs) = if flip { (-c, -s) } else { (c, s) };
            let generic =
                kernel_generic::<false>(src, &feat, &win, [taps, taps], at(i, cx, cy, gc, gs), f32::INFINITY).0;
            assert_eq!(fast.to_bits(), generic.to_bits(), "SIMD and generic builds must agree bit for bit");
            // The pair of options (M, −M flipped) from one pass equals the two evaluations.
            let (ca, sa) = if flip { (-c, -s) } else { (c, s) };
            let (ea, ef) = patch_error_pair(src, &feat, &win, at(i, cx, cy, ca, sa), f32::INFINITY);
            let one = patch_error(src, &feat, &win, at(i, cx, cy, ca, sa), false, f32::INFINITY);
            let other = patch_error(src, &feat, &win, at(i, cx, cy, -ca, -sa), true, f32::INFINITY);
            assert_eq!((ea.to_bits(), ef.to_bits()), (one.to_bits(), other.to_bits()));
            let generic_pair =
                kernel_generic::<true>(src, &feat, &win, [&win.taps, &win.flip], at(i, cx, cy, ca, sa), f32::INFINITY);
            assert_eq!((generic_pair.0.to_bits(), generic_pair.1.to_bits()), (ea.to_bits(), ef.to_bits()));
            let slow_flip = patch_error_reference(src, &feat, &tgt, query, i, cx, cy, -ca, -sa, true);
            assert!(((ef as f64) - slow_flip).abs() <= 1e-4 * slow_flip.max(1.0), "{ef} vs {slow_flip}");
            // The pair stops only once both sums are above the bound.
            let bound = ea.min(ef) * 0.5;
            let (pa, pf) = patch_error_pair(src, &feat, &win, at(i, cx, cy, ca, sa), bound);
            assert!(pa > bound && pf > bound && pa <= ea + 1e-3 && pf <= ef + 1e-3);
            // Early termination: a bound below the true error returns something above the bound.
            let bound = fast * 0.3;
            let partial = patch_error(src, &feat, &win, at(i, cx, cy, c, s), flip, bound);
            assert!(partial > bound && partial <= fast + 1e-3);
            checked += 1;
        }
        assert!(checked > 200);
    }

    /// The tap pixels are the nearest to the rotated offsets, and the AVX2 computation gives
    /// the same offsets.
    #[test]
    fn tap_offsets_are_the_nearest_pixels() {
        let stride = 57;
        let mut rng = SplitMix64::keyed(&[21]);
        for _ in 0..5000 {
            let th = rng.range(-3.2, 3.2);
            let c = Center { i: 0, cx: rng.range(3.0, 40.0), cy: rng.range(3.0, 40.0), c: th.cos(), s: th.sin() };
            let offs = tap_offsets(stride, c);
            for (k, (a, b)) in crate::synth::nnf::offsets().enumerate() {
                let (a, b) = (a as f32, b as f32);
                let x = (c.cx + PAD as f32 + (c.c * a - c.s * b) + 0.5).floor() as i32;
                let y = (c.cy + PAD as f32 + (c.s * a + c.c * b) + 0.5).floor() as i32;
                assert_eq!(offs[k], y * stride as i32 + x, "tap {k} of {c:?}");
            }
            assert!(offs[PATCH * PATCH..].iter().all(|&o| o == 0));
            #[cfg(target_arch = "x86_64")]
            if has_avx2() {
                // SAFETY: the CPU supports AVX2.
                assert_eq!(unsafe { tap_offsets_avx2(stride, c) }, offs);
            }
        }
    }

    #[test]
    fn identity_match_has_zero_error() {
        let params = Params::builder().build().unwrap();
        let (rgb, g) = synthetic(32, 32, 12.0, 3);
        let pyr = SourcePyramid::build(&[rgb.clone(), rgb.clone()], &[g.clone(), g.clone()], &params, 5.0, 1);
        let src = &pyr.levels[0];
        let mut tgt = TargetLevel::new(&g, &pyr.quant, 5.0, None, src.ext_falloff, [1.0; 3], false);
        for y in 0..32 {
            for x in 0..32 {
                let k = tgt.pindex(x, y);
                tgt.cur[k][..3].copy_from_slice(&rgb.get(x, y).map(|v| (v * 255.0).round()));
            }
        }
        let feat = src.feat.clone();
        let q = Query { tq: tgt.pindex(16, 16), w_col: 1.0, mw: 0.0, w_om: 0.0 };
        let win = Window::new(src, &tgt, &q);
        let e = patch_error(src, &feat, &win, at(1, 16.0, 16.0, 1.0, 0.0), false, f32::INFINITY);
        assert!(e < 1e-9, "{e}");
        let shifted = patch_error(src, &feat, &win, at(1, 17.0, 16.0, 1.0, 0.0), false, f32::INFINITY);
        assert!(shifted > 0.1);
    }
}

#[cfg(test)]
mod speed {
    use super::tests::synthetic;
    use super::*;
    use crate::rng::SplitMix64;
    use crate::synth::params::Params;
    use crate::synth::source::SourcePyramid;

    /// Development measurement (not a test of speed): `cargo test --release kernel_speed -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn kernel_speed() {
        let params = Params::builder().build().unwrap();
        let frames: Vec<_> = (0..20).map(|k| synthetic(400, 222, 100.0, k)).collect();
        let rgb: Vec<_> = frames.iter().map(|f| f.0.clone()).collect();
        let g: Vec<_> = frames.iter().map(|f| f.1.clone()).collect();
        let pyr = SourcePyramid::build(&rgb, &g, &params, 10.0, 1);
        let src = &pyr.levels[0];
        let (_, tg) = synthetic(500, 400, 150.0, 99);
        let tgt = TargetLevel::new(&tg, &pyr.quant, 10.0, None, src.ext_falloff, [1.0, 1.0, 1.0], false);
        let feat = src.feat.clone();
        let mut rng = SplitMix64::keyed(&[5]);
        let n: usize = std::env::var("FM_N").ok().and_then(|v| v.parse().ok()).unwrap_or(2_000_000);
        let windows = |mw: f32| -> Vec<Window> {
            (0..256)
                .map(|k| {
                    let q = tgt.active[(k * 7919) % tgt.active.len()] as usize;
                    Window::new(src, &tgt, &Query { tq: tgt.pindex(q % 500, q / 500), w_col: 1.0, mw, w_om: 0.0 })
                })
                .collect()
        };
        let cands: Vec<_> = (0..n)
            .map(|_| {
                let list = &src.valid[1];
                let (i, x, y) = src.coords(list[rng.below(list.len())] as usize);
                let th = rng.range(-3.0, 3.0);
                (i, x as f32 + 0.3, y as f32 - 0.2, th.cos(), th.sin(), rng.below(256))
            })
            .collect();
        for (label, mw) in [("no prev", 0.0), ("with prev", 1.0)] {
            let wins = windows(mw);
            let t = std::time::Instant::now();
            let mut sum = 0.0;
            for &(i, x, y, c, s, k) in &cands {
                sum += patch_error(src, &feat, &wins[k], at(i, x, y, c, s), false, f32::INFINITY);
            }
            let ns = t.elapsed().as_nanos() as f64 / n as f64;
            println!("{label}: {ns:.1} ns per full evaluation (random access) [{sum}]");
        }
        // Coherent access: neighbouring candidates
        let wins = windows(1.0);
        let t = std::time::Instant::now();
        let mut sum = 0.0;
        for k in 0..n {
            let x = 20.0 + (k % 300) as f32 + 0.3;
            let y = 80.0 + ((k / 300) % 50) as f32;
            sum += patch_error(src, &feat, &wins[k % 100], at(3, x, y, 0.8, 0.6), true, f32::INFINITY);
        }
        println!("coherent: {:.1} ns [{sum}]", t.elapsed().as_nanos() as f64 / n as f64);
    }
}

#[cfg(test)]
mod terms {
    use super::tests::synthetic;
    use super::*;
    use crate::synth::params::Params;
    use crate::synth::source::SourcePyramid;

    /// Every guide term of D is used: a candidate whose df / ext± / T^prev differ costs more,
    /// and the difference scales with the term's weight (0 = no effect).
    #[test]
    fn every_term_counts_with_its_weight() {
        let (rgb, g) = synthetic(40, 40, 15.0, 1);
        let run = |params: Params, edit: &dyn Fn(&mut TargetLevel)| {
            let pyr = SourcePyramid::build(&[rgb.clone(), rgb.clone()], &[g.clone(), g.clone()], &params, 5.0, 1);
            let src = &pyr.levels[0];
            let mut tgt = TargetLevel::new(&g, &pyr.quant, 5.0, None, src.ext_falloff, [1.0; 3], false);
            for y in 0..40 {
                for x in 0..40 {
                    let k = tgt.pindex(x, y);
                    tgt.cur[k][..3].copy_from_slice(&rgb.get(x, y).map(|v| (v * 255.0).round()));
                    tgt.prev[k][..3].copy_from_slice(&rgb.get(x, y).map(|v| (v * 255.0).round()));
                }
            }
            edit(&mut tgt);
            let feat = src.feat.clone();
            let q = Query { tq: tgt.pindex(20, 20), w_col: 1.0, mw: params.weights.w_prev, w_om: 0.0 };
            patch_error(src, &feat, &Window::new(src, &tgt, &q), at(1, 20.0, 20.0, 1.0, 0.0), false, f32::INFINITY)
        };
        let shift_lane = |lane: usize, by: f32| {
            move |t: &mut TargetLevel| {
                for px in t.cur.iter_mut() {
                    px[lane] += by;
                }
            }
        };
        let prev_off = |t: &mut TargetLevel| {
            for px in t.prev.iter_mut() {
                px[0] += 40.0;
            }
        };
        let def = Params::builder().build().unwrap();
        assert!(run(def.clone(), &|_| {}) < 1e-6);
        // The extent terms count where no paint is carried (w_prev = 0 here: m(q)·w_prev = 0).
        let fresh = || Params::builder().w_prev(0.0);
        for (name, lane, with, without) in [
            ("df", 3, def.clone(), Params::builder().w_df(0.0).build().unwrap()),
            ("ext+", 4, fresh().build().unwrap(), fresh().w_ext(0.0).build().unwrap()),
            ("ext-", 5, fresh().build().unwrap(), fresh().w_ext(0.0).build().unwrap()),
        ] {
            let a = run(with, &shift_lane(lane, 30.0));
            let b = run(without, &shift_lane(lane, 30.0));
            assert!(a > 0.01 && b < 1e-6, "{name}: with the term {a}, without {b}");
        }
        // Where paint is carried (m(q)·w_prev > 0) they do not: its age was chosen before.
        for lane in [4, 5] {
            let carried = run(def.clone(), &shift_lane(lane, 30.0));
            assert!(carried < 1e-6, "ext lane {lane} counted on carried paint: {carried}");
        }
        let a = run(def, &prev_off);
        let b = run(Params::builder().w_prev(0.0).build().unwrap(), &prev_off);
        assert!(a > 0.01 && b < 1e-6, "T^prev: with {a}, without {b}");
    }
}
