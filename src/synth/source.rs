//! The exemplar S laid out for the hot loop: per pyramid level, all frames' features in one
//! padded array of 8-byte pixels, so that a tap is one 8-byte load and the exemplar stays small
//! enough for the caches (random access dominates PatchMatch).
//!
//! Lanes: `[r, g, b, S^df, S^ext+, S^ext−, flags, Ω]`, each 8 bits: the features quantized by
//! [`Quant`] (rgb exactly as in the 8-bit exemplar; `S^df` over [−1, 1]; extents over
//! [0, max ext]), the pixel's flags ([`FLAG_LANE`]), and the occurrence penalty
//! ([`OMEGA_LANE`], 0 here; a search writes it into its own copy, see
//! [`super::occurrence::Occurrence`]). Target values are kept in the same units but unrounded,
//! and the per-lane weights absorb the quantization steps (see [`super::patch`]).

use super::params::{HALF, Params};
use crate::guide::FrameGuides;
use crate::img::{self, Mask, Plane, Rgb};
use glam::Vec2;
use rayon::prelude::*;

/// Lanes per pixel.
pub(crate) const LANES: usize = 8;
/// One pixel's quantized features.
pub(crate) type Feat = [u8; LANES];

/// The 8-bit quantization of each lane: value = q · scale + offset.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Quant {
    pub scale: [f32; LANES],
    pub offset: [f32; LANES],
}

impl Quant {
    /// rgb in 0..=1, df in −1..=1, extents in 0..=`ext_max`.
    pub fn new(ext_max: f32) -> Quant {
        let e = ext_max.max(1e-3) / 255.0;
        let c = 1.0 / 255.0;
        Quant { scale: [c, c, c, 2.0 / 255.0, e, e, 1.0, 1.0], offset: [0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0] }
    }

    /// `v` of lane `k` in quantization units (not rounded).
    #[inline]
    pub fn units(&self, k: usize, v: f32) -> f32 {
        (v - self.offset[k]) / self.scale[k]
    }

    /// `v` of lane `k` quantized.
    #[inline]
    pub fn quantize(&self, k: usize, v: f32) -> u8 {
        // Rounding half away from zero, as `round()`, without its libm call: `c − ⌊c⌋` is exact.
        let c = self.units(k, v).clamp(0.0, 255.0);
        let t = c as u8;
        t + (c - t as f32 >= 0.5) as u8
    }

    /// Per-lane weights of squared differences in quantization units:
    /// `[1/v, 1/v, 1/v, w_df, w_ext, w_ext, 0, 0] · scale²`, where `v` is the exemplar's color
    /// variance unit ([`color_variance`]); the color lanes get w_col per query.
    pub fn weights(&self, w_df: f32, w_ext: f32, v: f32) -> [f32; LANES] {
        let c = 1.0 / v;
        let w = [c, c, c, w_df, w_ext, w_ext, 0.0, 0.0];
        std::array::from_fn(|k| w[k] * self.scale[k] * self.scale[k])
    }
}
/// Bilinear interpolation of the first four lanes of the 2 × 2 block whose top-left pixel is
/// `base` (rows `stride` apart), at fractions (fx, fy): one bounds check for the block, 4-lane
/// arithmetic that vectorizes.
#[inline(always)]
fn bilerp4<const N: usize>(px: &[[u8; N]], base: usize, stride: usize, fx: f32, fy: f32) -> [f32; 4] {
    let quad = &px[base..=base + stride + 1];
    let p = |k: usize| -> [f32; 4] { std::array::from_fn(|c| quad[k][c] as f32) };
    let (a, b, c, d) = (p(0), p(1), p(stride), p(stride + 1));
    let top: [f32; 4] = std::array::from_fn(|c| a[c] + (b[c] - a[c]) * fx);
    let bot: [f32; 4] = std::array::from_fn(|k| c[k] + (d[k] - c[k]) * fx);
    std::array::from_fn(|c| top[c] + (bot[c] - top[c]) * fy)
}

/// Padding around every source frame: rotated windows around a valid center (≥ `MARGIN` px
/// from the border) plus the bilinear neighbour never leave the padded frame.
pub(crate) const PAD: usize = 4;
/// Smallest distance of a valid patch center from the frame border: ⌈√2·⌊n/2⌋⌉, so the
/// rotated window lies inside the exemplar image.
pub(crate) const MARGIN: usize = 3;

/// Flow magnitude (pixels per frame) below which a flow direction is considered undefined.
pub(crate) const FLOW_EPS: f32 = 0.02;

/// Flag: a candidate patch center may sit here (inside the dilated mask, away from the border).
pub(crate) const VALID: u8 = 1;
/// Flag: interior segment (`I^df = 1`); otherwise border segment.
pub(crate) const INTERIOR: u8 = 2;
/// Flag: inside the (pre-processed) mask itself.
pub(crate) const IN_MASK: u8 = 4;
/// Flag (target pixels only): the direction is the resting shape's outward normal
/// ([`super::ParamsBuilder::resting_normal`]), to be aligned with the exemplar's own normal
/// at the source ([`SourceLevel::normal`]) rather than its flow.
pub(crate) const RESTING: u8 = 8;

/// The "segment" a target pixel inside its mask and in the border segment asks its candidates
/// to come from ([`SourceLevel::valid_table`]) at the finest level: the border segment's
/// centers inside the exemplar's mask. Coarser levels have no such table
/// ([`SourceLevel::border_in_mask`] = 0), and their pixels ask for the border segment.
///
/// Valid centers reach [`HALF`] pixels beyond the mask, so that a patch can sit on the edge
/// as the target's outermost patches do; but a pixel *inside* the shape whose final match sits
/// on the paper outside the exemplar's paint shows paper. Measured on a growing ellipse
/// (blue-bloom, 512 × 512, 24 frames): 315 paper-colored pixels 1–5 px inside the mask on the
/// first frame (94 % of them matched outside the exemplar's mask: a notched outline with
/// slivers of paint standing off it), 4–20 on the others; with the rule 16 and 2–18. Only the
/// finest level, whose field is the one voted into the output, is held to it. At coarser
/// levels the border band is a few pixels wide and the ring outside it a large share of its
/// centers: holding every level to the rule concentrated the field's use of the exemplar
/// (first frame of a still ellipse: the most-used 5 % of the exemplar took 0.42 of the use
/// instead of 0.36, against 0.44–0.46 without Ω at all), and holding the levels whose band is
/// at least twice the ring (the two finest, blue-bloom) gave paler rims (blue-bloom growing
/// 0.72 of the exemplar's edge darkening, against 0.88 with the finest alone and 0.75
/// without the rule). The cost: on a first frame, which no temporal guide holds, the pixels
/// the rule turns away take their neighbours' or random matches, and the outline there is
/// speckled rather than notched.
pub(crate) const BORDER_IN_MASK: usize = 3;

/// Feature lane holding the pixel's flags (weight 0 in the patch error); the search checks
/// candidates against [`SourceLevel::valid_bits`] instead, which stays in cache. (The flow
/// direction stays exact, in [`SourceLevel::dirs`]: quantizing it to 8 bits turns the θ = 0
/// of equal flows into ±1.4° and cost the identity test 4–6 dB.)
pub(crate) const FLAG_LANE: usize = 6;
/// Feature lane holding the occurrence penalty of the voxel, as `√(Ω penalty / w_Ω)` in 8 bits
/// ([`super::occurrence::Occurrence`]): the target's lane is 0, so the patch error's weighted
/// squared difference of this lane *is* the penalty, with no second array to read.
pub(crate) const OMEGA_LANE: usize = 7;
/// ⌊v⌋ for finite `v` in i32 range, without a libm call (saturates outside).
#[inline(always)]
pub(crate) fn floor_i32(v: f32) -> i32 {
    let t = v as i32;
    t - ((t as f32) > v) as i32
}

/// [`floor_i32`] of four values at once (four SSE2 instructions on x86_64, where a saturating
/// `as i32` costs several per value). Values outside the i32 range give unspecified results
/// (never undefined behaviour).
#[inline(always)]
pub(crate) fn floor4_i32(v: [f32; 4]) -> [i32; 4] {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        // SAFETY: SSE2 is part of the x86_64 baseline; the loads and stores are of 4 values.
        unsafe {
            let x = _mm_loadu_ps(v.as_ptr());
            let t = _mm_cvttps_epi32(x);
            // −1 where truncation went up (negative non-integers).
            let up = _mm_castps_si128(_mm_cmpgt_ps(_mm_cvtepi32_ps(t), x));
            let mut out = [0i32; 4];
            _mm_storeu_si128(out.as_mut_ptr() as *mut __m128i, _mm_add_epi32(t, up));
            out
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    v.map(floor_i32)
}

/// Per-pixel data not needed in the patch error's inner loop.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PixInfo {
    /// Unit flow direction, or zero where the flow is below [`FLOW_EPS`] (undefined).
    pub dir: Vec2,
    /// Signed distance to the mask edge, full-resolution pixels.
    pub dist: f32,
    /// ext+ in full-resolution pixels (unweighted).
    pub ext_pos: f32,
    /// ext− in full-resolution pixels (unweighted).
    pub ext_neg: f32,
    /// [`VALID`] | [`INTERIOR`] | [`IN_MASK`].
    pub flags: u8,
    /// `|S^flow|`: how far the paint here moves to the next frame, full-resolution pixels.
    pub speed: f32,
}

/// Unit direction of a flow vector, or zero where it is too small to have a direction
/// ("rotation where there is no motion", DESIGN pitfalls: the rotation then falls back to θ = 0).
#[inline]
pub(crate) fn flow_dir(f: Vec2) -> Vec2 {
    let m = f.length();
    if m >= FLOW_EPS && m.is_finite() { f / m } else { Vec2::ZERO }
}

/// The outward unit normal −∇dist / |∇dist| of a shape from the gradient `grad` of its signed
/// distance (positive inside), and the gradient's length; `None` where it is shorter than ¼ (a
/// ridge of the distance field, or a mask covering the whole frame). The distances of every
/// pyramid level keep the finest level's units, so the length is about 2^l at level l.
#[inline]
pub(crate) fn outward_unit(grad: Vec2) -> Option<(Vec2, f32)> {
    let len = grad.length();
    (len >= 0.25).then(|| (-grad / len, len))
}

/// Dilates a mask by a square of radius `r` (Chebyshev distance).
pub(crate) fn dilate(mask: &Plane<bool>, r: usize) -> Plane<bool> {
    let (w, h) = mask.size();
    let mut tmp = Plane::new(w, h);
    for y in 0..h {
        let row = mask.row(y);
        let mut last: isize = -(r as isize) - 1;
        // forward then backward scan keeps it linear
        let mut out = vec![false; w];
        for x in 0..w {
            if row[x] {
                last = x as isize;
            }
            out[x] = x as isize - last <= r as isize;
        }
        let mut next: isize = isize::MAX / 2;
        for x in (0..w).rev() {
            if row[x] {
                next = x as isize;
            }
            out[x] |= next - (x as isize) <= r as isize;
        }
        tmp.row_mut(y).copy_from_slice(&out);
    }
    let mut res = Plane::new(w, h);
    for x in 0..w {
        let mut last: isize = -(r as isize) - 1;
        for y in 0..h {
            if tmp.get(x, y) {
                last = y as isize;
            }
            if y as isize - last <= r as isize {
                res.set(x, y, true);
            }
        }
        let mut next: isize = isize::MAX / 2;
        for y in (0..h).rev() {
            if tmp.get(x, y) {
                next = y as isize;
            }
            if next - (y as isize) <= r as isize {
                res.set(x, y, true);
            }
        }
    }
    res
}

/// Whether bit `idx` of the bit set `bits` is set.
#[inline(always)]
pub(crate) fn bit_set(bits: &[u64], idx: usize) -> bool {
    bits[idx / 64] >> (idx % 64) & 1 != 0
}

/// One pyramid level of the exemplar.
pub(crate) struct SourceLevel {
    /// Frame width and height at this level (unpadded).
    pub w: usize,
    pub h: usize,
    /// Number of frames l_S.
    pub frames: usize,
    /// Row stride of the padded frames.
    pub stride: usize,
    /// Pixels per padded frame.
    pub frame_len: usize,
    /// Features, padded (clamp-to-edge), frame after frame.
    pub feat: Vec<Feat>,
    /// Per-pixel info, same padded layout (padding is invalid).
    pub info: Vec<PixInfo>,
    /// The flow directions of `info` alone (8 bytes a pixel instead of 24), for the candidate
    /// checks of the search, which read them at random places.
    pub dirs: Vec<Vec2>,
    /// Valid centers per segment (0 = border, 1 = interior), as padded indices.
    pub valid: [Vec<u32>; 2],
    /// The same as bit sets over padded indices (bit `idx % 64` of word `idx / 64`), a third
    /// of the two segments together, and a fourth of [`BORDER_IN_MASK`]'s centers (empty at
    /// the levels where the rule does not apply): 1 bit a voxel, so the search rejects a
    /// candidate outside the mask or in the wrong segment from a table that stays in cache,
    /// without reading the exemplar at a random place.
    pub valid_bits: [Vec<u64>; 4],
    /// How many centers [`BORDER_IN_MASK`] has: the border segment's valid centers inside the
    /// mask itself; 0 at a level where the rule does not apply, which turns it off there.
    pub border_in_mask: usize,
    /// |S_seg,i|: mask pixels per segment (0 border, 1 interior) of each frame i (for ω*).
    pub seg_count: Vec<[usize; 2]>,
    /// Lane weights in quantization units ([`Quant::weights`]).
    pub lane_w: [f32; LANES],
    /// Grain map (finest level only, and only with [`super::ParamsBuilder::keep_grain`]; else empty), same
    /// padded layout: the low-pass of the
    /// colors within their own segment (paint or paper), 0..=255, and in lane 3 the local
    /// standard deviation of the grain (color − low-pass), in units of 1/1020.
    pub grain: Vec<[u8; 4]>,
    /// Autocorrelation ρ(k) of the paint's grain (color − low-pass, inside the mask) at lags
    /// k = 0–3 pixels, rows and columns pooled over every frame, ρ(0) = 1 (finest level with
    /// the grain; else white grain, `[1, 0, 0, 0]`): how much of the grain a sub-pixel sample
    /// keeps ([`SourceLevel::grain_phase_gain`]).
    pub grain_rho: [f32; 4],
    /// The contrast bin of every valid center ([`NO_BIN`] elsewhere), same padded layout: the
    /// standard deviation of the luma over its n × n window, as a quantile of the in-mask valid
    /// centers of its segment and frame (bin b holds the b-th of [`CONTRAST_BINS`] equal shares),
    /// for the contrast balance of the occurrence penalty
    /// ([`super::occurrence::Occurrence::update`]).
    pub contrast: Vec<u8>,
    /// Whether the extent lanes of this level fade out in the interior
    /// ([`ParamsBuilder::extent_falloff`](super::ParamsBuilder::extent_falloff) and
    /// [`EXTENT_FALLOFF_MIN_SIDE`]); the target's level does the same.
    pub ext_falloff: bool,
}

impl SourceLevel {
    /// The exemplar's outward unit normal −∇S^dist at padded index `idx` (central differences
    /// within its frame, [`outward_unit`]), or zero on a ridge of the distance field: the
    /// direction a resting
    /// target pixel's normal is aligned with ([`RESTING`]). Unlike the flow, it does not turn
    /// or vanish as the paint at a pixel ages from frame to frame, so a match carried forward
    /// in time keeps its turn.
    #[inline]
    pub fn normal(&self, idx: usize) -> Vec2 {
        let d = |k: usize| self.info.get(k).map_or(0.0, |p| p.dist);
        let s = self.stride;
        let grad = Vec2::new(d(idx + 1) - d(idx.saturating_sub(1)), d(idx + s) - d(idx.saturating_sub(s))) * 0.5;
        outward_unit(grad).map_or(Vec2::ZERO, |(n, _)| n)
    }

    /// Padded index of pixel (x, y) of frame i.
    #[inline]
    pub fn index(&self, i: usize, x: usize, y: usize) -> usize {
        i * self.frame_len + (y + PAD) * self.stride + x + PAD
    }

    /// Inverse of [`SourceLevel::index`]: (i, x, y).
    #[inline]
    pub fn coords(&self, idx: usize) -> (usize, usize, usize) {
        let i = idx / self.frame_len;
        let r = idx % self.frame_len;
        (i, r % self.stride - PAD, r / self.stride - PAD)
    }

    /// Whether padded index `idx` is a valid center of segment `seg` (of either when `None`;
    /// [`BORDER_IN_MASK`]: of the border segment and inside the mask).
    #[inline]
    pub fn is_valid(&self, seg: Option<usize>, idx: usize) -> bool {
        bit_set(self.valid_table(seg), idx)
    }

    /// The bit set of valid centers of segment `seg` (of either when `None`;
    /// [`BORDER_IN_MASK`]: of the border segment and inside the mask), for [`bit_set`].
    #[inline]
    pub fn valid_table(&self, seg: Option<usize>) -> &[u64] {
        &self.valid_bits[seg.unwrap_or(2).min(BORDER_IN_MASK)]
    }

    /// Padded index of the pixel nearest to (x, y) in frame i, when inside the frame.
    #[inline]
    pub fn nearest(&self, i: usize, x: f32, y: f32) -> Option<usize> {
        let xi = floor_i32(x + 0.5);
        let yi = floor_i32(y + 0.5);
        if i >= self.frames || xi < 0 || yi < 0 || xi >= self.w as i32 || yi >= self.h as i32 {
            return None;
        }
        Some(self.index(i, xi as usize, yi as usize))
    }

    /// The info at the pixel nearest to (x, y) in frame i, when inside the frame.
    #[inline]
    pub fn info_at(&self, i: usize, x: f32, y: f32) -> Option<(usize, &PixInfo)> {
        self.nearest(i, x, y).map(|idx| (idx, &self.info[idx]))
    }

    /// Bilinear sample of the rgb lanes at (x, y) of frame i (clamped to the padded frame).
    #[inline(always)]
    pub fn sample_rgb(&self, i: usize, x: f32, y: f32) -> Rgb {
        let (base, fx, fy) = self.bilinear_at(i, x, y);
        let v = bilerp4(&self.feat, base, self.stride, fx, fy);
        std::array::from_fn(|c| v[c] * (1.0 / 255.0))
    }

    /// Bilinear sample of [`SourceLevel::grain`] at (x, y) of frame i: the low-pass color
    /// (0..=1) and the local grain deviation.
    #[inline(always)]
    pub fn sample_grain(&self, i: usize, x: f32, y: f32) -> ([f32; 3], f32) {
        let (base, fx, fy) = self.bilinear_at(i, x, y);
        let v = bilerp4(&self.grain, base, self.stride, fx, fy);
        ([v[0] / 255.0, v[1] / 255.0, v[2] / 255.0], v[3] / GRAIN_STD_UNIT)
    }

    /// The 2 × 2 block of [`SourceLevel::sample_rgb`]: the padded index of its top-left pixel
    /// and the fractions (fx, fy).
    #[inline(always)]
    fn bilinear_at(&self, i: usize, x: f32, y: f32) -> (usize, f32, f32) {
        // The padded frame is (w + 2·PAD) × (h + 2·PAD); 32-bit conversions (no division, no
        // unsigned fix-ups on the path of every sample).
        let px = (x + PAD as f32).clamp(0.0, (self.w + 2 * PAD - 2) as u32 as f32);
        let py = (y + PAD as f32).clamp(0.0, (self.h + 2 * PAD - 2) as u32 as f32);
        let (x0, y0) = (px as i32 as usize, py as i32 as usize);
        (i * self.frame_len + y0 * self.stride + x0, px - x0 as f32, py - y0 as f32)
    }

    /// Catmull–Rom (bicubic) sample of the rgb lanes at (x, y) of frame i, clamped to 0..=1:
    /// sharper than [`SourceLevel::sample_rgb`] where rotated patches land between pixels.
    #[inline(always)]
    pub fn sample_rgb_cubic(&self, i: usize, x: f32, y: f32) -> Rgb {
        let (base, wx, wy) = self.cubic_at(i, x, y);
        // One bounds check for the 4 × 4 block; 4-lane arithmetic that vectorizes.
        let block = &self.feat[base..base + 3 * self.stride + 4];
        let mut out = [0.0f32; 4];
        for (j, &wyj) in wy.iter().enumerate() {
            let row = &block[j * self.stride..j * self.stride + 4];
            let mut r = [0.0f32; 4];
            for (p, &wxk) in row.iter().zip(&wx) {
                for c in 0..4 {
                    r[c] += wxk * p[c] as f32;
                }
            }
            for c in 0..4 {
                out[c] += wyj * r[c];
            }
        }
        std::array::from_fn(|c| (out[c] * (1.0 / 255.0)).clamp(0.0, 1.0))
    }

    /// The 4 × 4 block of [`SourceLevel::sample_rgb_cubic`]: the padded index of its top-left
    /// pixel and the Catmull–Rom weights of its columns and rows.
    #[inline(always)]
    fn cubic_at(&self, i: usize, x: f32, y: f32) -> (usize, [f32; 4], [f32; 4]) {
        let px = (x + PAD as f32).clamp(1.0, (self.w + 2 * PAD - 3) as u32 as f32);
        let py = (y + PAD as f32).clamp(1.0, (self.h + 2 * PAD - 3) as u32 as f32);
        let (x0, y0) = (px as i32 as usize, py as i32 as usize);
        (i * self.frame_len + (y0 - 1) * self.stride + x0 - 1, catmull_rom(px - x0 as f32), catmull_rom(py - y0 as f32))
    }

    /// How much a voter's grain sampled at (x, y) ([`SourceLevel::sample_rgb_cubic`] less
    /// [`SourceLevel::sample_grain`]'s low-pass) is scaled up in the output's vote: the
    /// Catmull–Rom sample between pixels is a weighted sum of 4 × 4 of them, which keeps only
    /// the share `V(fx)·V(fy)` of the grain's variance ([`interpolated_variance`], with the
    /// grain's own autocorrelation [`SourceLevel::grain_rho`]; for white grain 0.41 half-way
    /// between pixels on both axes, 1 on a pixel). The gain is `(V(fx)·V(fy))^(−e)`,
    /// e = [`GRAIN_PHASE_EXPONENT`]: half (in log) of the lost deviation is given back.
    #[inline(always)]
    pub fn grain_phase_gain(&self, x: f32, y: f32) -> f32 {
        let v = interpolated_variance(x - x.floor(), &self.grain_rho)
            * interpolated_variance(y - y.floor(), &self.grain_rho);
        v.max(MIN_INTERPOLATED_VARIANCE).powf(-GRAIN_PHASE_EXPONENT)
    }
}

/// The samplers compiled for AVX2 with explicit 4-lane arithmetic: the same operations in the
/// same order as [`SourceLevel::sample_rgb`] and [`SourceLevel::sample_rgb_cubic`] (no fused
/// multiply-adds), so the same results, from two 16-byte loads per row of pixels instead of one
/// scalar load and conversion per byte.
#[cfg(target_arch = "x86_64")]
impl SourceLevel {
    /// [`SourceLevel::sample_rgb`] for AVX2 code.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(crate) fn sample_rgb_avx2(&self, i: usize, x: f32, y: f32) -> Rgb {
        use std::arch::x86_64::*;
        let (base, fx, fy) = self.bilinear_at(i, x, y);
        let quad = &self.feat[base..=base + self.stride + 1];
        // Pixels (0, 1) and (stride, stride + 1) are 16 contiguous bytes each.
        let pair = |k: usize| {
            // SAFETY: `quad` holds pixels k and k + 1 (8 bytes each) for k = 0 and k = stride.
            let v = unsafe { _mm_loadu_si128(quad[k..k + 2].as_ptr() as *const __m128i) };
            (_mm_cvtepi32_ps(_mm_cvtepu8_epi32(v)), _mm_cvtepi32_ps(_mm_cvtepu8_epi32(_mm_srli_si128::<8>(v))))
        };
        let ((a, b), (c, d)) = (pair(0), pair(self.stride));
        let (fx, fy) = (_mm_set1_ps(fx), _mm_set1_ps(fy));
        let top = _mm_add_ps(a, _mm_mul_ps(_mm_sub_ps(b, a), fx));
        let bot = _mm_add_ps(c, _mm_mul_ps(_mm_sub_ps(d, c), fx));
        let out = _mm_mul_ps(_mm_add_ps(top, _mm_mul_ps(_mm_sub_ps(bot, top), fy)), _mm_set1_ps(1.0 / 255.0));
        let mut o = [0.0f32; 4];
        // SAFETY: `o` holds 4 floats.
        unsafe { _mm_storeu_ps(o.as_mut_ptr(), out) };
        [o[0], o[1], o[2]]
    }

    /// [`SourceLevel::sample_rgb_cubic`] for AVX2 code.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(crate) fn sample_rgb_cubic_avx2(&self, i: usize, x: f32, y: f32) -> Rgb {
        use std::arch::x86_64::*;
        let (base, wx, wy) = self.cubic_at(i, x, y);
        let block = &self.feat[base..base + 3 * self.stride + 4];
        let wxv = wx.map(|v| _mm_set1_ps(v));
        let mut out = _mm_setzero_ps();
        for (j, &wyj) in wy.iter().enumerate() {
            let row = &block[j * self.stride..j * self.stride + 4];
            // SAFETY: `row` holds 4 pixels of 8 bytes: two 16-byte loads.
            let (v01, v23) = unsafe {
                (_mm_loadu_si128(row.as_ptr() as *const __m128i), _mm_loadu_si128(row[2..].as_ptr() as *const __m128i))
            };
            let px = [v01, _mm_srli_si128::<8>(v01), v23, _mm_srli_si128::<8>(v23)];
            let mut r = _mm_setzero_ps();
            for (p, w) in px.into_iter().zip(wxv) {
                r = _mm_add_ps(r, _mm_mul_ps(w, _mm_cvtepi32_ps(_mm_cvtepu8_epi32(p))));
            }
            out = _mm_add_ps(out, _mm_mul_ps(_mm_set1_ps(wyj), r));
        }
        let mut o = [0.0f32; 4];
        // SAFETY: `o` holds 4 floats.
        unsafe { _mm_storeu_ps(o.as_mut_ptr(), out) };
        std::array::from_fn(|c| (o[c] * (1.0 / 255.0)).clamp(0.0, 1.0))
    }
}

/// The exemplar's pyramid, shared by every layer synthesized with the same exemplar and
/// parameters.
pub struct SourcePyramid {
    pub(crate) levels: Vec<SourceLevel>,
    /// Largest |ext| over the exemplar (full-resolution pixels), for clamping target extents.
    pub(crate) ext_max: f32,
    /// The exemplar's extent scale ([`crate::guide::extent_scale`]), full-resolution pixels.
    pub(crate) ext_scale: f32,
    /// The lanes' quantization.
    pub(crate) quant: Quant,
    /// The color variance unit v ([`color_variance`]).
    pub(crate) color_unit: f32,
    /// Border width b actually used (pixels).
    pub(crate) border_width: f32,
    /// Mean color of the exemplar outside its masks (≈ the paper).
    pub(crate) paper: Rgb,
    /// Full-resolution frame size.
    pub(crate) size: (usize, usize),
    /// The exemplar's pigment density per frame and depth ([`super::tone`]).
    pub(crate) tone: super::tone::ToneProfile,
    /// The exemplar's grain amplitude per frame and depth, with the grain kept
    /// ([`super::tone::grain_gains`]).
    pub(crate) grain_tone: Option<super::tone::GrainProfile>,
}

impl SourcePyramid {
    /// Builds the pyramid of `levels` levels from the exemplar frames `S^rgb` and their guides.
    pub(crate) fn build(
        frames: &[Plane<Rgb>],
        guides: &[FrameGuides],
        params: &Params,
        border_width: f32,
        levels: usize,
    ) -> SourcePyramid {
        let mut ext_max: f32 = 0.0;
        let mut paper = [0.0f64; 3];
        let mut paper_n = 0usize;
        for (f, g) in frames.iter().zip(guides) {
            for (c, &m) in f.data().iter().zip(g.mask.data()) {
                if !m {
                    for k in 0..3 {
                        paper[k] += c[k] as f64;
                    }
                    paper_n += 1;
                }
            }
            for (&a, &b) in g.ext_pos.data().iter().zip(g.ext_neg.data()) {
                ext_max = ext_max.max(a).max(b);
            }
        }
        let paper = if paper_n > 0 {
            [(paper[0] / paper_n as f64) as f32, (paper[1] / paper_n as f64) as f32, (paper[2] / paper_n as f64) as f32]
        } else {
            [1.0, 1.0, 1.0]
        };
        let quant = Quant::new(ext_max);
        let v = color_variance(frames, guides);
        // The exemplar's low-pass (its structure without its grain), made once: the grain map
        // and the tone profile both read it.
        let low: Vec<Plane<Rgb>> = if params.parts.keep_grain {
            frames.par_iter().zip(guides).map(|(f, g)| segment_low_pass(f, &g.mask)).collect()
        } else {
            Vec::new()
        };
        let mut cur_rgb: Vec<Plane<Rgb>> = frames.to_vec();
        let mut cur_g: Vec<FrameGuides> = guides.to_vec();
        let mut out = Vec::with_capacity(levels);
        for l in 0..levels {
            if l > 0 {
                cur_rgb = cur_rgb.iter().map(img::downsample2).collect();
                cur_g = cur_g.iter().map(|g| g.downsample2()).collect();
            }
            let (lw, lh) = cur_rgb[0].size();
            let falloff = params.parts.extent_falloff && lw.min(lh) >= EXTENT_FALLOFF_MIN_SIDE;
            let weights = quant.weights(params.weights.w_df, params.weights.w_ext, v);
            // Border centers inside the mask only at the finest level (see BORDER_IN_MASK).
            let mut level = build_level(&cur_rgb, &cur_g, &quant, weights, border_width, falloff, l == 0);
            if l == 0 && params.parts.keep_grain {
                build_grain(&mut level, &cur_rgb, &cur_g, &low);
            }
            out.push(level);
        }
        let ext_scale = crate::guide::extent_scale(guides);
        SourcePyramid {
            levels: out,
            ext_max,
            ext_scale,
            quant,
            color_unit: v,
            border_width,
            paper,
            size: frames[0].size(),
            // With the grain kept, the output's low-pass is matched, before its grain is added back.
            tone: super::tone::ToneProfile::new(if params.parts.keep_grain { &low } else { frames }, guides, paper),
            grain_tone: params
                .parts
                .keep_grain
                .then(|| super::tone::GrainProfile::new(frames, &low, guides, paper, border_width)),
        }
    }
}

/// The unit in which color differences are measured: the exemplar's mean local color variance,
/// `v = E[Σ_c Var_{5×5}(S_c)]` over mask pixels (sampled), clamped to `[1e-4, 1]`.
///
/// The papers' weights (w_df, w_ext, w_prev, λ) are relative to the color term, whose size
/// depends on how contrasted the exemplar is: a faint wash has color differences a hundred
/// times smaller than an ink. Measuring colors in units of the exemplar's own texture contrast
/// makes the weights mean the same for every exemplar: a random pairing of pixels from one
/// texture costs about 2 per pixel.
pub(crate) fn color_variance(frames: &[Plane<Rgb>], guides: &[FrameGuides]) -> f32 {
    let mut sum = 0.0f64;
    let mut n = 0usize;
    let step = (frames.len() / 8).max(1);
    for (f, g) in frames.iter().zip(guides).step_by(step) {
        let (w, h) = f.size();
        for y in (2..h.saturating_sub(2)).step_by(3) {
            for x in (2..w.saturating_sub(2)).step_by(3) {
                if !g.mask.get(x, y) {
                    continue;
                }
                let mut m = [0.0f64; 3];
                let mut m2 = [0.0f64; 3];
                for dy in 0..5 {
                    for dx in 0..5 {
                        let c = f.get(x + dx - 2, y + dy - 2);
                        for k in 0..3 {
                            m[k] += c[k] as f64;
                            m2[k] += (c[k] as f64).powi(2);
                        }
                    }
                }
                sum += (0..3).map(|k| (m2[k] / 25.0 - (m[k] / 25.0).powi(2)).max(0.0)).sum::<f64>();
                n += 1;
            }
        }
    }
    if n == 0 { 1e-2 } else { ((sum / n as f64) as f32).clamp(1e-4, 1.0) }
}

/// The smallest exemplar frame side (pixels of the level) at which the extent lanes fade out in
/// the interior: 10 patch widths. At coarser levels a patch covers much of the exemplar's paint,
/// the occurrence term Ω (which counts the taps of whole windows) cannot tell the reuse of one
/// spot from uniform use, and an interior left free of the extents collapses onto one spot
/// whose pattern then repeats over the target at the level's pixel pitch (a 16-px lattice on a
/// still ellipse at the fourth level down). There the extents keep the interior's layout.
pub(crate) const EXTENT_FALLOFF_MIN_SIDE: usize = 10 * super::params::PATCH;

/// The factor of the extent lanes at depth `r = d/b` (distance from the edge over the border
/// width): 1 when they do not fade (`on` false, the level's [`SourceLevel::ext_falloff`]);
/// else 1 in the border band (r ≤ 1), falling linearly to 0 at r = 2.
///
/// The extents say how far the paint has travelled to a pixel. Near the edge that decides
/// the rim (advancing, receding, settled); deep inside, it ties the target's interior to the
/// exemplar's least-travelled paint — where its drop landed, its flat and pale core — whenever
/// the target's interior has moved less than the exemplar's paint (a still shape, the first
/// frame of any shape): the interior then copies the calmest quarter of the exemplar
/// (measured: 84 % of the matches of a still ellipse, green-wash), and its 7×7 contrast is
/// 0.6 of the exemplar's at the same depths. Without the extents there, the interior is
/// matched by texture, border channel and uniformity alone.
#[inline]
pub(crate) fn extent_falloff(on: bool, r: f32) -> f32 {
    if on { (2.0 - r).clamp(0.0, 1.0) } else { 1.0 }
}

/// One level of the exemplar pyramid; with `inside_only` it has a [`BORDER_IN_MASK`] table
/// (the border centers inside the mask).
fn build_level(
    rgb: &[Plane<Rgb>],
    guides: &[FrameGuides],
    qn: &Quant,
    lane_w: [f32; LANES],
    b: f32,
    falloff: bool,
    inside_only: bool,
) -> SourceLevel {
    let (w, h) = rgb[0].size();
    let stride = w + 2 * PAD;
    let frame_len = stride * (h + 2 * PAD);
    let frames = rgb.len();
    let mut feat = vec![[0u8; LANES]; frame_len * frames];
    let mut info = vec![PixInfo::default(); frame_len * frames];
    // Frames are independent: each fills its own slice and lists its own valid centers, which
    // are joined in frame order (the same lists as a serial pass).
    let per_frame: Vec<([Vec<u32>; 2], [usize; 2])> = feat
        .par_chunks_mut(frame_len)
        .zip(info.par_chunks_mut(frame_len))
        .zip(rgb.par_iter().zip(guides))
        .enumerate()
        .map(|(i, ((feat, info), (c, g)))| {
            let roi = dilate(&g.mask, HALF);
            let mut valid: [Vec<u32>; 2] = [Vec::new(), Vec::new()];
            let mut seg_count = [0usize; 2];
            for (offset, x, y, inside) in padded_pixels(w, h) {
                let col = c.get(x, y);
                let dist = g.dist.get(x, y);
                let df = (dist / b).min(1.0);
                let ep = g.ext_pos.get(x, y);
                let en = g.ext_neg.get(x, y);
                let fade = extent_falloff(falloff, dist / b);
                let v = [col[0], col[1], col[2], df, ep * fade, en * fade, 0.0, 0.0];
                feat[offset] = std::array::from_fn(|k| if k < 6 { qn.quantize(k, v[k]) } else { 0 });
                if !inside {
                    continue;
                }
                let interior = dist >= b;
                let in_mask = g.mask.get(x, y);
                let away = x >= MARGIN && y >= MARGIN && x + MARGIN < w && y + MARGIN < h;
                let mut flags = 0;
                if interior {
                    flags |= INTERIOR;
                }
                if in_mask {
                    flags |= IN_MASK;
                    seg_count[interior as usize] += 1;
                }
                if roi.get(x, y) && away {
                    flags |= VALID;
                    valid[interior as usize].push((i * frame_len + offset) as u32);
                }
                feat[offset][FLAG_LANE] = flags;
                let f = g.flow.get(x, y);
                info[offset] = PixInfo { dir: flow_dir(f), dist, ext_pos: ep, ext_neg: en, flags, speed: f.length() };
            }
            (valid, seg_count)
        })
        .collect();
    let mut valid: [Vec<u32>; 2] = [Vec::new(), Vec::new()];
    let mut seg_count = Vec::with_capacity(frames);
    for (v, n) in per_frame {
        valid[0].extend(v[0].iter());
        valid[1].extend(v[1].iter());
        seg_count.push(n);
    }
    let dirs = info.iter().map(|p| p.dir).collect();
    let bit_table = |list: &[u32]| {
        let mut bits = vec![0u64; feat.len().div_ceil(64)];
        for &idx in list {
            bits[idx as usize / 64] |= 1 << (idx % 64);
        }
        bits
    };
    let (border, interior) = (bit_table(&valid[0]), bit_table(&valid[1]));
    let either = border.iter().zip(&interior).map(|(a, b)| a | b).collect();
    // The border centers inside the mask; none without `inside_only` (the rule does not
    // apply, see BORDER_IN_MASK).
    let (border_in_mask, in_mask_bits) = if inside_only {
        let in_mask: Vec<u32> =
            valid[0].iter().copied().filter(|&idx| info[idx as usize].flags & IN_MASK != 0).collect();
        (in_mask.len(), bit_table(&in_mask))
    } else {
        (0, Vec::new())
    };
    let valid_bits = [border, interior, either, in_mask_bits];
    SourceLevel {
        w,
        h,
        frames,
        stride,
        frame_len,
        feat,
        info,
        dirs,
        valid,
        valid_bits,
        border_in_mask,
        seg_count,
        lane_w,
        grain: Vec::new(),
        grain_rho: [1.0, 0.0, 0.0, 0.0],
        contrast: Vec::new(),
        ext_falloff: falloff,
    }
    .with_contrast()
}

/// Bins of [`SourceLevel::contrast`].
pub(crate) const CONTRAST_BINS: usize = 8;
/// [`SourceLevel::contrast`] of a voxel that is not a valid center.
pub(crate) const NO_BIN: u8 = u8::MAX;

impl SourceLevel {
    /// Fills [`SourceLevel::contrast`]: each valid center's luma deviation over its unrotated
    /// n × n window, binned by the quantiles of the in-mask valid centers of its segment and
    /// frame.
    fn with_contrast(mut self) -> SourceLevel {
        let mut bins = vec![NO_BIN; self.feat.len()];
        let (stride, feat) = (self.stride as isize, &self.feat);
        let deviation = |idx: u32| -> f32 {
            let (mut s, mut s2) = (0.0f32, 0.0f32);
            for dy in -(HALF as isize)..=HALF as isize {
                for dx in -(HALF as isize)..=HALF as isize {
                    let f = feat[(idx as isize + dy * stride + dx) as usize];
                    let l = (f[0] as f32 + f[1] as f32 + f[2] as f32) / 3.0;
                    s += l;
                    s2 += l * l;
                }
            }
            let n = ((2 * HALF + 1) * (2 * HALF + 1)) as f32;
            (s2 / n - (s / n).powi(2)).max(0.0).sqrt()
        };
        let frame_len = self.frame_len;
        for list in &self.valid {
            let devs: Vec<f32> = list.par_iter().map(|&idx| deviation(idx)).collect();
            // Quantiles per frame: the valid lists are in frame order.
            let mut start = 0;
            while start < list.len() {
                let frame = list[start] as usize / frame_len;
                let end = start + list[start..].partition_point(|&idx| idx as usize / frame_len == frame);
                // The shares are of the centers in the mask: those are the ones in-mask pixels
                // of the target take, and the use is counted over them.
                let in_mask = |k: &usize| self.feat[list[*k] as usize][FLAG_LANE] & IN_MASK != 0;
                let mut sorted: Vec<f32> = (start..end).filter(in_mask).map(|k| devs[k]).collect();
                if sorted.is_empty() {
                    sorted = devs[start..end].to_vec();
                }
                sorted.sort_by(f32::total_cmp);
                let edges: Vec<f32> = (1..CONTRAST_BINS).map(|k| sorted[k * sorted.len() / CONTRAST_BINS]).collect();
                for (&idx, &d) in list[start..end].iter().zip(&devs[start..end]) {
                    bins[idx as usize] = edges.iter().filter(|&&e| d >= e).count() as u8;
                }
                start = end;
            }
        }
        self.contrast = bins;
        self
    }
}

/// Every pixel of a frame's padded layout (`w + 2·PAD` × `h + 2·PAD`, row-major): its offset
/// within the frame, the frame pixel it holds (the nearest one: the padding repeats the edge),
/// and whether it lies in the frame itself.
fn padded_pixels(w: usize, h: usize) -> impl Iterator<Item = (usize, usize, usize, bool)> {
    let stride = w + 2 * PAD;
    (0..h + 2 * PAD).flat_map(move |py| {
        (0..stride).map(move |px| {
            let x = (px as isize - PAD as isize).clamp(0, w as isize - 1) as usize;
            let y = (py as isize - PAD as isize).clamp(0, h as isize - 1) as usize;
            let inside = px >= PAD && py >= PAD && px < PAD + w && py < PAD + h;
            (py * stride + px, x, y, inside)
        })
    })
}

/// The Catmull–Rom weights of the 4 pixels around a sample at phase `t` ∈ [0, 1) past the
/// second of them.
#[inline(always)]
pub(crate) fn catmull_rom(t: f32) -> [f32; 4] {
    let t2 = t * t;
    let t3 = t2 * t;
    [0.5 * (-t3 + 2.0 * t2 - t), 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0), 0.5 * (-3.0 * t3 + 4.0 * t2 + t), 0.5 * (t3 - t2)]
}

/// The share of a stationary signal's variance that Catmull–Rom interpolation at phase `t`
/// keeps along one axis: `V(t) = Σ_a Σ_b w_a(t)·w_b(t)·ρ(|a − b|)`, with `w` the
/// [`catmull_rom`] weights and `ρ` the signal's autocorrelation at lags 0–3. `V(0) = 1`.
#[inline(always)]
pub(crate) fn interpolated_variance(t: f32, rho: &[f32; 4]) -> f32 {
    let w = catmull_rom(t);
    let mut v = 0.0;
    for (a, wa) in w.iter().enumerate() {
        for (b, wb) in w.iter().enumerate() {
            v += wa * wb * rho[a.abs_diff(b)];
        }
    }
    v
}

/// The exponent e of [`SourceLevel::grain_phase_gain`]: ½ would give the interpolated grain
/// all of its variance back, ¼ gives back half of the lost deviation (in log). Measured on the
/// 24-frame quality suite (five video exemplars × six targets, seeds 1 and 2; means over the
/// moving runs): ½ raised the contrast 0.90 → 0.95 and the incoherent change 0.90 → 0.99–1.00
/// (three ellipses of yellow-granules over the 1.2), ¼ 0.90 → 0.92–0.93 and
/// 0.90 → 0.94–0.95 (one over).
pub(crate) const GRAIN_PHASE_EXPONENT: f32 = 0.25;

/// The least `V(fx)·V(fy)` that [`SourceLevel::grain_phase_gain`] compensates (white grain
/// half-way between pixels on both axes keeps 0.41).
const MIN_INTERPOLATED_VARIANCE: f32 = 0.25;

/// σ of the low-pass that separates a frame's structure from its grain, pixels.
pub(crate) const GRAIN_SIGMA: f32 = 1.5;
/// Scale of the grain deviation in [`SourceLevel::grain`] lane 3.
pub(crate) const GRAIN_STD_UNIT: f32 = 1020.0;

/// The Gaussian blur (σ [`GRAIN_SIGMA`]) of `f` within each segment of `mask` — the paint and
/// the paper apart, so that the edge of the paint is structure, not grain — normalized by the
/// segment's share of the kernel.
fn segment_blur<const N: usize>(mask: &Mask, f: &dyn Fn(usize, usize) -> [f32; N]) -> Plane<[f32; N]> {
    let [paper, paint] = [false, true].map(|side| img::blur_within(mask, side, GRAIN_SIGMA, f));
    let (w, h) = mask.size();
    Plane::from_fn(w, h, |x, y| if mask.get(x, y) { paint.get(x, y) } else { paper.get(x, y) })
}

/// The low-pass of a frame that separates its structure from its grain ([`segment_blur`]).
pub(crate) fn segment_low_pass(c: &Plane<Rgb>, mask: &Mask) -> Plane<Rgb> {
    segment_blur(mask, &|x, y| c.get(x, y))
}

/// Builds [`SourceLevel::grain`] of `level` from its frames, their masks and their low-pass
/// ([`segment_low_pass`]).
fn build_grain(level: &mut SourceLevel, rgb: &[Plane<Rgb>], guides: &[FrameGuides], low: &[Plane<Rgb>]) {
    let (w, h) = (level.w, level.h);
    let mut grain = vec![[0u8; 4]; level.feat.len()];
    let frames = grain.par_chunks_mut(level.frame_len).zip(rgb.par_iter().zip(guides).zip(low));
    // Per frame: the sums of the paint's lagged grain products and their counts, lags 0–3.
    let lagged = frames.map(|(grain, ((c, g), low))| {
        let var = segment_blur(&g.mask, &|x, y| {
            let (v, l) = (c.get(x, y), low.get(x, y));
            [(v[0] - l[0]).powi(2) + (v[1] - l[1]).powi(2) + (v[2] - l[2]).powi(2)]
        });
        for (offset, x, y, _) in padded_pixels(w, h) {
            let l = low.get(x, y);
            let sd = var.get(x, y)[0].max(0.0).sqrt();
            let q = |v: f32, unit: f32| (v * unit).round().clamp(0.0, 255.0) as u8;
            grain[offset] = [q(l[0], 255.0), q(l[1], 255.0), q(l[2], 255.0), q(sd, GRAIN_STD_UNIT)];
        }
        let grain_at = |x: usize, y: usize| {
            let (v, l) = (c.get(x, y), low.get(x, y));
            [v[0] - l[0], v[1] - l[1], v[2] - l[2]]
        };
        let mut sums = [(0f64, 0u64); 4];
        for (x, y) in (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).filter(|&(x, y)| g.mask.get(x, y)) {
            let a = grain_at(x, y);
            for (k, s) in sums.iter_mut().enumerate() {
                for (nx, ny) in [(x + k, y), (x, y + k)] {
                    if nx < w && ny < h && g.mask.get(nx, ny) {
                        let b = grain_at(nx, ny);
                        s.0 += (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) as f64;
                        s.1 += 1;
                    }
                }
            }
        }
        sums
    });
    // Added in frame order: a parallel reduce groups the f64 sums by how the work was split,
    // which depends on the thread count.
    let per_frame: Vec<[(f64, u64); 4]> = lagged.collect();
    let sums = per_frame.iter().fold([(0.0, 0); 4], |a, b| std::array::from_fn(|k| (a[k].0 + b[k].0, a[k].1 + b[k].1)));
    let mean = sums.map(|(s, n)| if n > 0 { s / n as f64 } else { 0.0 });
    if mean[0] > 0.0 {
        level.grain_rho = mean.map(|m| (m / mean[0]).clamp(-1.0, 1.0) as f32);
    }
    level.grain = grain;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Catmull–Rom interpolation keeps all of a sample on the grid, all of a smooth signal,
    /// and 0.64 of a white one's variance half-way between pixels (Σ w² at t = ½ = 41/64).
    #[test]
    fn interpolated_variance_of_white_and_smooth_signals() {
        for t in [0.0, 0.25, 0.5, 0.9] {
            assert!((catmull_rom(t).iter().sum::<f32>() - 1.0).abs() < 1e-6);
            assert!((interpolated_variance(t, &[1.0; 4]) - 1.0).abs() < 1e-5, "smooth at {t}");
        }
        let white = [1.0, 0.0, 0.0, 0.0];
        assert!((interpolated_variance(0.0, &white) - 1.0).abs() < 1e-6);
        assert!((interpolated_variance(0.5, &white) - 0.640625).abs() < 1e-6);
        assert!(interpolated_variance(0.25, &white) > interpolated_variance(0.5, &white));
    }

    #[test]
    fn dilate_square() {
        let mut m = Plane::new(9, 9);
        m.set(4, 4, true);
        let d = dilate(&m, 2);
        assert_eq!(d.count(), 25);
        assert!(d.get(2, 2) && d.get(6, 6) && !d.get(1, 4) && !d.get(7, 4));
    }

    #[test]
    fn floor_without_libm() {
        for v in [-2.5f32, -1.0, -0.2, 0.0, -0.0, 0.7, 3.0, 1e6 + 0.5, -7e5 - 0.25] {
            assert_eq!(floor_i32(v), v.floor() as i32);
            assert_eq!(floor4_i32([v, -v, v + 0.5, v - 0.5]), [v, -v, v + 0.5, v - 0.5].map(|x| x.floor() as i32));
        }
    }

    /// Both samplers interpolate (a pixel's own position gives its color), and the AVX2 builds
    /// give the generic results bit for bit, inside the frame, between pixels, and clamped
    /// beyond the border.
    #[test]
    fn samplers_interpolate_and_the_avx2_build_matches() {
        use crate::synth::patch::tests::synthetic;
        let params = crate::synth::Params::builder().build().unwrap();
        let frames: Vec<_> = (0..3).map(|k| synthetic(40, 30, 9.0, k)).collect();
        let rgb: Vec<_> = frames.iter().map(|f| f.0.clone()).collect();
        let g: Vec<_> = frames.iter().map(|f| f.1.clone()).collect();
        let pyr = SourcePyramid::build(&rgb, &g, &params, 4.0, 1);
        let src = &pyr.levels[0];
        for (x, y) in [(0, 0), (7, 3), (39, 29), (20, 15)] {
            let px = src.feat[src.index(2, x, y)];
            let want: Rgb = std::array::from_fn(|c| px[c] as f32 * (1.0 / 255.0));
            assert_eq!(src.sample_rgb(2, x as f32, y as f32), want);
            assert_eq!(src.sample_rgb_cubic(2, x as f32, y as f32), want);
        }
        let mut rng = crate::rng::SplitMix64::keyed(&[11]);
        let mut between = 0;
        for _ in 0..20_000 {
            let i = rng.below(3);
            let (x, y) = (rng.range(-8.0, 48.0), rng.range(-8.0, 38.0));
            let (a, b) = (src.sample_rgb(i, x, y), src.sample_rgb_cubic(i, x, y));
            assert!(a.iter().chain(&b).all(|v| (0.0..=1.0).contains(v)), "{a:?} {b:?} at {x},{y}");
            between += (a != src.sample_rgb(i, x.round(), y.round())) as usize;
            #[cfg(target_arch = "x86_64")]
            if crate::synth::patch::has_avx2() {
                // SAFETY: the CPU supports AVX2.
                let (a2, b2) = unsafe { (src.sample_rgb_avx2(i, x, y), src.sample_rgb_cubic_avx2(i, x, y)) };
                assert_eq!(a.map(f32::to_bits), a2.map(f32::to_bits), "bilinear at {i} {x} {y}");
                assert_eq!(b.map(f32::to_bits), b2.map(f32::to_bits), "bicubic at {i} {x} {y}");
            }
        }
        assert!(between > 10_000, "sub-pixel positions interpolate ({between})");
    }

    #[test]
    fn quantize_rounds_as_round_does() {
        // Lane 6 has scale 1 and offset 0: the value is its own unit.
        let q = Quant::new(7.0);
        let mut v = -3.0f32;
        while v < 260.0 {
            for x in [v, v + 0.5, v.next_up(), (v + 0.5).next_down(), (v + 0.5).next_up()] {
                assert_eq!(q.quantize(6, x), x.round().clamp(0.0, 255.0) as u8, "{x}");
            }
            v += 0.25;
        }
        assert_eq!(q.quantize(6, 0.5f32.next_down()), 0);
        assert_eq!(q.quantize(6, f32::NAN), 0);
        assert_eq!(q.quantize(6, f32::INFINITY), 255);
        for x in [0.3f32, 0.77, 0.5] {
            assert_eq!(q.quantize(0, x), q.units(0, x).round() as u8);
        }
    }

    /// The exemplar's normal at a pixel is the outward direction of its shape (a disc: radial),
    /// at every level, and none at the disc's middle (a ridge of the distance field; at the
    /// finest level, where the disc is centred on a pixel).
    #[test]
    fn the_exemplar_normal_points_out_of_its_shape() {
        use crate::synth::patch::tests::synthetic;
        let params = crate::synth::Params::builder().build().unwrap();
        let (rgb, g) = synthetic(40, 40, 14.0, 1);
        let pyr = SourcePyramid::build(&[rgb], &[g], &params, 6.0, 2);
        for (l, src) in pyr.levels.iter().enumerate() {
            let c = (src.w / 2) as f32;
            let mut n = 0;
            for y in 0..src.h {
                for x in 0..src.w {
                    let off = Vec2::new(x as f32, y as f32) - Vec2::splat(c);
                    if off.length() < 2.0 || off.length() > c - 3.0 {
                        continue;
                    }
                    let normal = src.normal(src.index(0, x, y));
                    assert!(normal.dot(off.normalize()) > 0.95, "level {l} ({x}, {y}): {normal}");
                    n += 1;
                }
            }
            assert!(n > 20, "level {l}: {n} pixels");
        }
        let src = &pyr.levels[0];
        assert_eq!(src.normal(src.index(0, 20, 20)), Vec2::ZERO, "the middle");
    }

    #[test]
    fn flow_dir_fallback() {
        assert_eq!(flow_dir(Vec2::new(0.001, 0.0)), Vec2::ZERO);
        assert!((flow_dir(Vec2::new(0.0, -3.0)) - Vec2::new(0.0, -1.0)).length() < 1e-6);
    }
}
