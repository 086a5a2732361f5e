//! The patch error D(p, q) over a rotated 5 × 5 window (paper §3, thesis §3.7 and §4.4.1):
//!
//! ```text
//! D = Σ_{p′,q′} w_col·|S^rgb(p′) − T^rgb(q′)|² + w_df·|S^df − T^df|²
//!             + w_ext·(|S^ext+ − T^ext±|² + |S^ext− − T^ext∓|²)
//!             + m(q)·w_prev·|S^rgb(p′) − T^prev(q′)|²  +  λ·Ω*(p′)/(n²·ω*)
//! ```
//!
//! where p′ runs over the window around the sub-pixel source center rotated by θ, and ext±
//! are swapped when the rotated flows oppose. In this search metric each rotated tap reads the
//! nearest exemplar pixel (at most ½ px away); voting, which makes the output, samples the
//! rotated windows bilinearly at their exact sub-pixel positions ([`super::vote`]). The direction term
//! `w_dir·|tan(…)|` is dropped as in the thesis's implementation (§4.4.1): the θ rule already
//! aligns the flows. The sum stops early once it exceeds the best error found so far.
//!
//! Hot path: no trigonometry (the rotation is a stored matrix), no allocation, no bounds
//! checks in the inner loop (centers are validated: every tap stays inside the padded
//! frame), 8-lane pixels that vectorize, and a runtime-dispatched AVX2 build of the same code.

use super::params::HALF;
use super::source::{LANES, PAD, SourceLevel};
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
}

/// Per-level occurrence penalty `λ·Ω*(p′)/(n²·ω*_seg)`, in the padded source layout.
pub(crate) type OmegaMap = [f32];

/// D for source center (cx, cy) of frame `i` with rotation M = (c, s); returns a value
/// `> best` (possibly partial) once the running sum exceeds `best`.
///
/// The caller guarantees that the center's nearest pixel is a valid center (≥ `MARGIN` px from
/// the border), so every tap lies inside the padded frame.
#[inline]
#[allow(clippy::too_many_arguments)]
pub(crate) fn patch_error(
    src: &SourceLevel,
    omega: &OmegaMap,
    tgt: &TargetLevel,
    q: Query,
    i: usize,
    cx: f32,
    cy: f32,
    c: f32,
    s: f32,
    flip: bool,
    best: f32,
) -> f32 {
    debug_assert!(cx > -0.5 + super::source::MARGIN as f32 - 0.51 && cy > -0.5 + super::source::MARGIN as f32 - 0.51);
    debug_assert!(cx < (src.w - super::source::MARGIN) as f32 && cy < (src.h - super::source::MARGIN) as f32);
    #[cfg(target_arch = "x86_64")]
    {
        if has_avx2() {
            // SAFETY: the CPU supports AVX2 (checked above); the body is the same safe code.
            return unsafe { patch_error_avx2(src, omega, tgt, q, i, cx, cy, c, s, flip, best) };
        }
    }
    patch_error_generic(src, omega, tgt, q, i, cx, cy, c, s, flip, best)
}

#[cfg(target_arch = "x86_64")]
#[inline]
fn has_avx2() -> bool {
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

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
unsafe fn patch_error_avx2(
    src: &SourceLevel,
    omega: &OmegaMap,
    tgt: &TargetLevel,
    q: Query,
    i: usize,
    cx: f32,
    cy: f32,
    c: f32,
    s: f32,
    flip: bool,
    best: f32,
) -> f32 {
    use std::arch::x86_64::*;
    let feat = src.feat.as_ptr();
    let stride = src.stride;
    let fbase = i * src.frame_len;
    let lw = &src.lane_w;
    let wc = _mm256_setr_ps(q.w_col * lw[0], q.w_col * lw[1], q.w_col * lw[2], lw[3], lw[4], lw[5], 0.0, 0.0);
    let wp = _mm256_setr_ps(q.mw * lw[0], q.mw * lw[1], q.mw * lw[2], 0.0, 0.0, 0.0, 0.0, 0.0);
    let swap = _mm256_setr_epi32(0, 1, 2, 3, 5, 4, 6, 7);
    let use_prev = q.mw > 0.0;
    let r = HALF as f32;
    let pad = PAD as f32;
    let mut acc = _mm256_setzero_ps();
    let mut om = 0.0f32;
    let tstride = tgt.stride;
    let cur = tgt.cur.as_ptr() as *const f32;
    let prev = tgt.prev.as_ptr() as *const f32;
    let hsum = |acc: __m256| {
        let mut l = [0.0f32; LANES];
        // SAFETY: `l` holds 8 floats.
        unsafe { _mm256_storeu_ps(l.as_mut_ptr(), acc) };
        l.iter().sum::<f32>()
    };
    for b in 0..(2 * HALF + 1) {
        let bf = b as f32 - r;
        let trow = q.tq + b * tstride - HALF - HALF * tstride;
        for a in 0..(2 * HALF + 1) {
            let af = a as f32 - r;
            let sx = cx + pad + (c * af - s * bf);
            let sy = cy + pad + (s * af + c * bf);
            // SAFETY (all unchecked accesses below): the padded coordinates are positive and
            // inside frame i's padded block by the validity rule; target arrays are padded by
            // ⌊n/2⌋ around every pixel; the CPU has AVX2 (checked by the caller).
            let (x0, y0) = unsafe {
                ((sx + 0.5).to_int_unchecked::<i32>() as usize, (sy + 0.5).to_int_unchecked::<i32>() as usize)
            };
            let idx = fbase + y0 * stride + x0;
            debug_assert!(idx < src.feat.len());
            let bytes = unsafe { _mm_loadl_epi64(feat.add(idx) as *const __m128i) };
            let mut v = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(bytes));
            if flip {
                v = _mm256_permutevar8x32_ps(v, swap);
            }
            let ti = trow + a;
            debug_assert!(ti < tgt.cur.len());
            let t = unsafe { _mm256_loadu_ps(cur.add(ti * LANES)) };
            let d = _mm256_sub_ps(v, t);
            acc = _mm256_add_ps(acc, _mm256_mul_ps(_mm256_mul_ps(wc, d), d));
            if use_prev {
                let p = unsafe { _mm256_loadu_ps(prev.add(ti * LANES)) };
                let e = _mm256_sub_ps(v, p);
                acc = _mm256_add_ps(acc, _mm256_mul_ps(_mm256_mul_ps(wp, e), e));
            }
            om += unsafe { *omega.get_unchecked(idx) };
        }
        let total = hsum(acc) + om;
        if total > best {
            return total;
        }
    }
    hsum(acc) + om
}

#[allow(clippy::too_many_arguments)]
fn patch_error_generic(
    src: &SourceLevel,
    omega: &OmegaMap,
    tgt: &TargetLevel,
    q: Query,
    i: usize,
    cx: f32,
    cy: f32,
    c: f32,
    s: f32,
    flip: bool,
    best: f32,
) -> f32 {
    kernel(src, omega, tgt, q, i, cx, cy, c, s, flip, best)
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn kernel(
    src: &SourceLevel,
    omega: &OmegaMap,
    tgt: &TargetLevel,
    q: Query,
    i: usize,
    cx: f32,
    cy: f32,
    c: f32,
    s: f32,
    flip: bool,
    best: f32,
) -> f32 {
    let feat = &src.feat[..];
    let stride = src.stride;
    let fbase = i * src.frame_len;
    let lw = &src.lane_w;
    let wc = [q.w_col * lw[0], q.w_col * lw[1], q.w_col * lw[2], lw[3], lw[4], lw[5], 0.0, 0.0];
    let wp = [q.mw * lw[0], q.mw * lw[1], q.mw * lw[2], 0.0, 0.0, 0.0, 0.0, 0.0];
    let use_prev = q.mw > 0.0;
    let r = HALF as f32;
    let pad = PAD as f32;
    let mut acc = [0.0f32; LANES];
    let mut om = 0.0f32;
    let tstride = tgt.stride;
    for b in 0..(2 * HALF + 1) {
        let bf = b as f32 - r;
        let trow = q.tq + b * tstride - HALF - HALF * tstride;
        for a in 0..(2 * HALF + 1) {
            let af = a as f32 - r;
            // Tap position M·(a, b) around the center, in padded coordinates.
            let sx = cx + pad + (c * af - s * bf);
            let sy = cy + pad + (s * af + c * bf);
            // Nearest exemplar pixel of the tap; truncation is floor since padded coordinates
            // are positive by the validity rule (so no saturating conversion is needed).
            // SAFETY: sx, sy are finite and within the padded frame (validity rule).
            let (x0, y0) = unsafe {
                ((sx + 0.5).to_int_unchecked::<i32>() as usize, (sy + 0.5).to_int_unchecked::<i32>() as usize)
            };
            let idx = fbase + y0 * stride + x0;
            debug_assert!(idx < feat.len() && sx >= 0.0 && sy >= 0.0);
            // SAFETY: idx lies in frame i's padded block (validity rule above).
            let p00 = unsafe { feat.get_unchecked(idx) };
            let mut v: [f32; LANES] = p00.map(|b| b as f32);
            if flip {
                v.swap(4, 5);
            }
            let ti = trow + a;
            debug_assert!(ti < tgt.cur.len());
            // SAFETY: the target arrays are padded by ⌊n/2⌋ around every pixel.
            let t = unsafe { tgt.cur.get_unchecked(ti) };
            for k in 0..LANES {
                let d = v[k] - t[k];
                acc[k] += wc[k] * d * d;
            }
            if use_prev {
                let p = unsafe { tgt.prev.get_unchecked(ti) };
                for k in 0..LANES {
                    let d = v[k] - p[k];
                    acc[k] += wp[k] * d * d;
                }
            }
            // SAFETY: same index as above.
            om += unsafe { *omega.get_unchecked(idx) };
        }
        let total = acc.iter().sum::<f32>() + om;
        if total > best {
            return total;
        }
    }
    acc.iter().sum::<f32>() + om
}

/// A plain, obviously-correct version of [`patch_error`] (no early exit, straight loops, f64
/// sums), for tests.
#[cfg(test)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn patch_error_reference(
    src: &SourceLevel,
    omega: &OmegaMap,
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
        src.feat[i * src.frame_len + py * src.stride + px].map(|b| b as f32)
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
            for k in 3..6 {
                total += (lw[k] * (v[k] - t[k]).powi(2)) as f64;
            }
            let ox = (x + 0.5).floor() as usize;
            let oy = (y + 0.5).floor() as usize;
            total += omega[i * src.frame_len + oy * src.stride + ox] as f64;
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guide::FrameGuides;
    use crate::img::Plane;
    use crate::synth::params::Params;
    use crate::synth::rng::Rng;
    use crate::synth::source::{SourcePyramid, VALID};
    use glam::Vec2;

    /// Synthetic guides: a disc of radius `r` with noisy channels.
    pub(crate) fn synthetic(w: usize, h: usize, r: f32, seed: u64) -> (Plane<[f32; 3]>, FrameGuides) {
        let mut rng = Rng::keyed(&[seed]);
        let (cx, cy) = (w as f32 / 2.0, h as f32 / 2.0);
        let dist = Plane::from_fn(w, h, |x, y| r - ((x as f32 - cx).powi(2) + (y as f32 - cy).powi(2)).sqrt());
        let mask = dist.map(|d| d >= 0.0);
        let flow = Plane::from_fn(w, h, |x, y| Vec2::new(x as f32 - cx, y as f32 - cy) * 0.05);
        let ext_pos = Plane::from_fn(w, h, |_, _| rng.f32() * 5.0);
        let ext_neg = Plane::from_fn(w, h, |_, _| rng.f32() * 5.0);
        let rgb = Plane::from_fn(w, h, |_, _| [rng.f32(), rng.f32(), rng.f32()]);
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
        let mut tgt = TargetLevel::new(&tg, &pyr.quant, 6.0, None, [1.0, 1.0, 1.0]);
        let mut rng = Rng::keyed(&[5]);
        for (k, px) in tgt.cur.iter_mut().enumerate() {
            let c = trgb.data()[k % trgb.len()];
            px[..3].copy_from_slice(&c.map(|v| v * 255.0));
        }
        for px in tgt.prev.iter_mut() {
            px[..3].copy_from_slice(&[rng.f32() * 255.0, rng.f32() * 255.0, rng.f32() * 255.0]);
        }
        let omega: Vec<f32> = (0..src.feat.len()).map(|_| rng.f32() * 0.01).collect();
        let mut checked = 0;
        for _ in 0..400 {
            let list = &src.valid[rng.below(2)];
            if list.is_empty() {
                continue;
            }
            let (i, x, y) = src.coords(list[rng.below(list.len())] as usize);
            let (cx, cy) = (x as f32 + rng.range_f32(-0.49, 0.49), y as f32 + rng.range_f32(-0.49, 0.49));
            let th = rng.range_f32(-std::f32::consts::PI, std::f32::consts::PI);
            let (c, s) = (th.cos(), th.sin());
            let q = tgt.active[rng.below(tgt.active.len())] as usize;
            let query =
                Query { tq: tgt.pindex(q % 30, q / 30), w_col: 1.0, mw: if rng.f32() < 0.5 { 0.0 } else { 0.7 } };
            let flip = rng.f32() < 0.5;
            assert!(src.info_at(i, cx, cy).unwrap().1.flags & VALID != 0);
            let fast = patch_error(src, &omega, &tgt, query, i, cx, cy, c, s, flip, f32::INFINITY);
            let slow = patch_error_reference(src, &omega, &tgt, query, i, cx, cy, c, s, flip);
            assert!(((fast as f64) - slow).abs() <= 1e-4 * slow.max(1.0), "{fast} vs {slow}");
            let generic = patch_error_generic(src, &omega, &tgt, query, i, cx, cy, c, s, flip, f32::INFINITY);
            assert_eq!(fast.to_bits(), generic.to_bits(), "SIMD and generic builds must agree bit for bit");
            // Early termination: a bound below the true error returns something above the bound.
            let bound = fast * 0.3;
            let partial = patch_error(src, &omega, &tgt, query, i, cx, cy, c, s, flip, bound);
            assert!(partial > bound && partial <= fast + 1e-3);
            checked += 1;
        }
        assert!(checked > 200);
    }

    #[test]
    fn identity_match_has_zero_error() {
        let params = Params::builder().build().unwrap();
        let (rgb, g) = synthetic(32, 32, 12.0, 3);
        let pyr = SourcePyramid::build(&[rgb.clone(), rgb.clone()], &[g.clone(), g.clone()], &params, 5.0, 1);
        let src = &pyr.levels[0];
        let mut tgt = TargetLevel::new(&g, &pyr.quant, 5.0, None, [1.0; 3]);
        for y in 0..32 {
            for x in 0..32 {
                let k = tgt.pindex(x, y);
                tgt.cur[k][..3].copy_from_slice(&rgb.get(x, y).map(|v| (v * 255.0).round()));
            }
        }
        let omega = vec![0.0; src.feat.len()];
        let q = Query { tq: tgt.pindex(16, 16), w_col: 1.0, mw: 0.0 };
        let e = patch_error(src, &omega, &tgt, q, 1, 16.0, 16.0, 1.0, 0.0, false, f32::INFINITY);
        assert!(e < 1e-9, "{e}");
        let shifted = patch_error(src, &omega, &tgt, q, 1, 17.0, 16.0, 1.0, 0.0, false, f32::INFINITY);
        assert!(shifted > 0.1);
    }
}

#[cfg(test)]
mod speed {
    use super::tests::synthetic;
    use super::*;
    use crate::synth::params::Params;
    use crate::synth::rng::Rng;
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
        let tgt = TargetLevel::new(&tg, &pyr.quant, 10.0, None, [1.0, 1.0, 1.0]);
        let omega = vec![0.0f32; src.feat.len()];
        let mut rng = Rng::keyed(&[5]);
        let n: usize = std::env::var("FM_N").ok().and_then(|v| v.parse().ok()).unwrap_or(2_000_000);
        let cands: Vec<_> = (0..n)
            .map(|_| {
                let list = &src.valid[1];
                let (i, x, y) = src.coords(list[rng.below(list.len())] as usize);
                let th = rng.range_f32(-3.0, 3.0);
                let q = tgt.active[rng.below(tgt.active.len())] as usize;
                (i, x as f32 + 0.3, y as f32 - 0.2, th.cos(), th.sin(), tgt.pindex(q % 500, q / 500))
            })
            .collect();
        for (label, mw) in [("no prev", 0.0), ("with prev", 1.0)] {
            let t = std::time::Instant::now();
            let mut sum = 0.0;
            for &(i, x, y, c, s, tq) in &cands {
                sum +=
                    patch_error(src, &omega, &tgt, Query { tq, w_col: 1.0, mw }, i, x, y, c, s, false, f32::INFINITY);
            }
            let ns = t.elapsed().as_nanos() as f64 / n as f64;
            println!("{label}: {ns:.1} ns per full evaluation (random access) [{sum}]");
        }
        // Coherent access: neighbouring candidates
        let t = std::time::Instant::now();
        let mut sum = 0.0;
        for k in 0..n {
            let x = 20.0 + (k % 300) as f32 + 0.3;
            let y = 80.0 + ((k / 300) % 50) as f32;
            sum += patch_error(
                src,
                &omega,
                &tgt,
                Query { tq: tgt.pindex(200 + k % 100, 200), w_col: 1.0, mw: 1.0 },
                3,
                x,
                y,
                0.8,
                0.6,
                true,
                f32::INFINITY,
            );
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
            let mut tgt = TargetLevel::new(&g, &pyr.quant, 5.0, None, [1.0; 3]);
            for y in 0..40 {
                for x in 0..40 {
                    let k = tgt.pindex(x, y);
                    tgt.cur[k][..3].copy_from_slice(&rgb.get(x, y).map(|v| (v * 255.0).round()));
                    tgt.prev[k][..3].copy_from_slice(&rgb.get(x, y).map(|v| (v * 255.0).round()));
                }
            }
            edit(&mut tgt);
            let omega = vec![0.0; src.feat.len()];
            let q = Query { tq: tgt.pindex(20, 20), w_col: 1.0, mw: params.w_prev };
            patch_error(src, &omega, &tgt, q, 1, 20.0, 20.0, 1.0, 0.0, false, f32::INFINITY)
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
        for (name, lane, with, without) in [
            ("df", 3, def.clone(), Params::builder().w_df(0.0).build().unwrap()),
            ("ext+", 4, def.clone(), Params::builder().w_ext(0.0).build().unwrap()),
            ("ext-", 5, def.clone(), Params::builder().w_ext(0.0).build().unwrap()),
        ] {
            let a = run(with, &shift_lane(lane, 30.0));
            let b = run(without, &shift_lane(lane, 30.0));
            assert!(a > 0.01 && b < 1e-6, "{name}: with the term {a}, without {b}");
        }
        let a = run(def, &prev_off);
        let b = run(Params::builder().w_prev(0.0).build().unwrap(), &prev_off);
        assert!(a > 0.01 && b < 1e-6, "T^prev: with {a}, without {b}");
    }
}
