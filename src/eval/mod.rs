//! Measuring a stylized sequence against its exemplar and target masks, so that users and
//! tests can judge quality with numbers (issue #7).
//!
//! [`evaluate`] runs every metric and returns a [`Report`] (serde-serializable, with a
//! human-readable [`Display`](std::fmt::Display)); [`plot::render_plot`] draws its per-frame
//! series. Each metric is also a pure function usable on its own:
//!
//! | metric | function | reading |
//! |---|---|---|
//! | coverage | [`coverage_iou`] | IoU of the painted area with the target masks; 1 = exact |
//! | texture fidelity | [`patch_nn_distance`] | RMS distance of output 5×5 patches to their nearest exemplar patches; 0 = made of exemplar patches |
//! | wash-out | [`local_contrast`] | mean 7×7 luma standard deviation of the interior; output / exemplar ≈ 1, a flat fill scores 0 |
//! | palette | [`palette_distance`] | per-channel Wasserstein distance of interior colors; 0 = same distribution |
//! | temporal behaviour | [`temporal_change`] | mean change between consecutive frames in the stationary interior; output / exemplar ≈ 1 is exemplar-like, ≫ 1 flicker, ≈ 0 paint glued still |
//! | motion | [`motion_agreement`] | mean cosine between the paint's block-matching flow and the target's motion near moving boundaries; +1 with it, −1 against it |
//!
//! Conventions: colors are sRGB in `0..=1`; masks are coverage thresholded at 0.5 ([`Shape`]);
//! the **interior** of a mask is the set of pixels at least
//! [`EvalOptions::interior_margin`] (default 5) pixels inside its boundary, so that 7×7
//! windows and 5×5 patches around interior pixels lie entirely inside the paint. Output
//! frames with a real alpha channel (alpha = the target mask, as `synth` writes them) are
//! composited over the exemplar's paper color before colors are measured; opaque outputs are
//! measured as they are. Everything is deterministic (seeded sampling, fixed tie-breaking)
//! and independent of the number of threads.
//!
//! ```
//! use fluidymation::eval::{local_contrast, Shape};
//! use fluidymation::img::Plane;
//!
//! let disc = Plane::from_fn(32, 32, |x, y| {
//!     let (dx, dy) = (x as f32 - 16.0, y as f32 - 16.0);
//!     if dx * dx + dy * dy < 144.0 { 1.0 } else { 0.0 }
//! });
//! let interior = Shape::from_coverage(&disc).interior(5.0);
//! let flat = Plane::filled(32, 32, [0.2f32, 0.4, 0.8]);
//! assert!(local_contrast(&flat, &interior).unwrap() < 1e-6); // a flat fill has no texture
//! ```

mod contrast;
mod coverage;
mod farneback;
mod flow;
mod palette;
mod patches;
pub mod plot;
mod report;
mod shape;
mod temporal;

pub use contrast::{CONTRAST_WINDOW, local_contrast, local_contrast_seq};
pub use coverage::{
    OPAQUE_ALPHA, Painted, coverage_iou, detect_painted, estimate_background, has_alpha, intersection_union, iou,
    painted_mask,
};
pub use farneback::{FarnebackParams, MIN_LEVEL_SIDE, REGULARIZATION, farneback_flow, warp_bilinear};
pub use flow::{
    BlockMatchParams, MotionParams, block_matching_flow, match_block, motion_agreement, target_motion,
    target_motion_field,
};
pub use palette::{ColorHistogram, HISTOGRAM_BINS, palette_distance};
pub use patches::{PATCH_SIZE, PCA_DIMS, PatchIndex, PatchParams, patch_nn_distance, patch_nn_distance_with};
pub use report::{ExemplarSummary, FrameStats, Report, Summary};
pub use shape::{MASK_THRESHOLD, Shape, signed_distance};
pub use temporal::{TemporalParams, frame_change, stationary_interior, temporal_change};

use crate::error::{Error, Result};
use crate::exemplar::Exemplar;
use crate::img::{self, Plane, Rgb, Rgba};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Rec. 709 luma of a (gamma-encoded) sRGB color: `0.2126 R + 0.7152 G + 0.0722 B`.
#[inline]
pub fn luma(c: Rgb) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// The [`luma`] of every pixel.
pub fn luma_plane(img: &Plane<Rgb>) -> Plane<f32> {
    img.map(luma)
}

/// `a / b`, or `None` when either is missing or `b` is (nearly) zero.
pub fn ratio(a: Option<f32>, b: Option<f32>) -> Option<f32> {
    match (a, b) {
        (Some(a), Some(b)) if b.abs() > 1e-9 => Some(a / b),
        _ => None,
    }
}

/// One metric over a sequence: the pooled value and the per-frame series.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Measure {
    /// The value over the whole sequence (pooled over every sample of every frame, not the
    /// mean of the per-frame values); `None` without samples.
    pub value: Option<f32>,
    /// The value per frame (index = frame); `None` for frames without samples.
    pub per_frame: Vec<Option<f32>>,
    /// Number of samples (pixels, patches, points) behind `value`.
    pub samples: u64,
}

impl Measure {
    pub(crate) fn from_means(means: &[Mean]) -> Measure {
        let total = means.iter().fold(Mean::default(), |a, &b| a.merged(b));
        Measure { value: total.value(), per_frame: means.iter().map(Mean::value).collect(), samples: total.count }
    }
}

/// A running mean, for pooling over frames.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Mean {
    sum: f64,
    count: u64,
}

impl Mean {
    #[inline]
    pub(crate) fn add(&mut self, v: f64) {
        self.sum += v;
        self.count += 1;
    }

    pub(crate) fn merged(self, other: Mean) -> Mean {
        Mean { sum: self.sum + other.sum, count: self.count + other.count }
    }

    pub(crate) fn value(&self) -> Option<f32> {
        (self.count > 0).then(|| (self.sum / self.count as f64) as f32)
    }
}

/// SplitMix64: a tiny, fast, seedable generator; good enough for sampling positions.
pub(crate) struct Rng(u64);

impl Rng {
    pub(crate) fn new(seed: u64) -> Self {
        Rng(seed)
    }

    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n` (`n > 0`).
    pub(crate) fn below(&mut self, n: usize) -> usize {
        ((self.next_u64() as u128 * n as u128) >> 64) as usize
    }
}

/// Settings of [`evaluate`]. The defaults suit sequences of a few hundred pixels a side.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct EvalOptions {
    /// Interior margin, pixels: contrast, palette and patch statistics use pixels at least this
    /// far inside the mask (target masks for the output, exemplar masks for the exemplar).
    /// Default: 5 (7×7 windows and 5×5 patches then lie inside the mask).
    pub interior_margin: f32,
    /// The stationary interior of [`temporal_change`]. Default: [`TemporalParams::default`].
    pub temporal: TemporalParams,
    /// [`motion_agreement`]'s points and block matcher. Default: [`MotionParams::default`].
    pub motion: MotionParams,
    /// [`patch_nn_distance`]'s sampling (its seed is the seed of the whole evaluation).
    /// Default: [`PatchParams::default`].
    pub patches: PatchParams,
    /// Background color of opaque outputs; `None` estimates it ([`estimate_background`]).
    /// Default: `None`.
    pub background: Option<Rgb>,
    /// Color distance from the background above which an opaque output pixel counts as
    /// painted ([`Painted::Color`]). Default: 0.1.
    pub paint_threshold: f32,
    /// Use every `step`-th exemplar frame, as the synthesis does with `--src-speed`; `None`
    /// takes the exemplar's recommended `speed`. Default: `None`.
    pub exemplar_step: Option<usize>,
    /// Resize the exemplar by this factor first, as the synthesis does with `--src-scale`;
    /// `None` takes the exemplar's recommended `scale`. Default: `None`.
    pub exemplar_scale: Option<f32>,
}

impl Default for EvalOptions {
    fn default() -> Self {
        EvalOptions {
            interior_margin: 5.0,
            temporal: TemporalParams::default(),
            motion: MotionParams::default(),
            patches: PatchParams::default(),
            background: None,
            paint_threshold: 0.1,
            exemplar_step: None,
            exemplar_scale: None,
        }
    }
}

fn check(ok: bool, name: &str, value: impl std::fmt::Display, allowed: &str) -> Result<()> {
    if ok { Ok(()) } else { Err(Error::param(name, value, allowed)) }
}

impl EvalOptions {
    /// Checks every setting's range; the error names the command-line flag.
    pub fn validate(&self) -> Result<()> {
        let finite_nonneg = |v: f32| v.is_finite() && v >= 0.0;
        check(finite_nonneg(self.interior_margin), "--interior-margin", self.interior_margin, "a number >= 0")?;
        check(finite_nonneg(self.temporal.margin), "temporal.margin", self.temporal.margin, "a number >= 0")?;
        check(finite_nonneg(self.temporal.horizon), "temporal.horizon", self.temporal.horizon, "a number >= 0")?;
        let m = &self.motion;
        check(m.band.is_finite() && m.band > 0.0, "motion.band", m.band, "a number > 0")?;
        check(finite_nonneg(m.min_speed), "motion.min_speed", m.min_speed, "a number >= 0")?;
        check(finite_nonneg(m.min_flow), "motion.min_flow", m.min_flow, "a number >= 0")?;
        check(m.stride >= 1, "motion.stride", m.stride, "at least 1")?;
        check(finite_nonneg(m.edge_margin), "motion.edge_margin", m.edge_margin, "a number >= 0")?;
        let b = &m.block;
        check(
            b.block % 2 == 1 && (3..=31).contains(&b.block),
            "motion.block.block",
            b.block,
            "an odd number in 3..=31",
        )?;
        check((1..=32).contains(&b.radius), "--flow-radius", b.radius, "1..=32 pixels")?;
        check(b.min_valid > 0.0 && b.min_valid <= 1.0, "motion.block.min_valid", b.min_valid, "a fraction in (0, 1]")?;
        check(finite_nonneg(b.min_texture), "motion.block.min_texture", b.min_texture, "a number >= 0")?;
        let p = &self.patches;
        check(p.samples >= 1, "--patch-samples", p.samples, "at least 1")?;
        check(p.pool >= 1, "patches.pool", p.pool, "at least 1")?;
        check(p.checks >= 1, "patches.checks", p.checks, "at least 1")?;
        check(
            self.paint_threshold > 0.0 && self.paint_threshold < 3f32.sqrt(),
            "--paint-threshold",
            self.paint_threshold,
            "a color distance in (0, 1.732)",
        )?;
        if let Some(bg) = self.background {
            check(bg.iter().all(|v| (0.0..=1.0).contains(v)), "--background", format!("{bg:?}"), "colors in 0..=1")?;
        }
        if let Some(s) = self.exemplar_step {
            check(s >= 1, "--src-speed", s, "at least 1")?;
        }
        if let Some(s) = self.exemplar_scale {
            check(s.is_finite() && s > 0.0 && s <= 8.0, "--src-scale", s, "a factor in (0, 8]")?;
        }
        Ok(())
    }
}

/// Output colors as measured: straight RGBA composited over `paper` when `painted` is
/// [`Painted::Alpha`], the RGB as it is otherwise.
pub fn composite_output(output: &[Plane<Rgba>], painted: &Painted, paper: Rgb) -> Vec<Plane<Rgb>> {
    output
        .par_iter()
        .map(|f| match painted {
            Painted::Alpha => f.map(|c| {
                let a = c[3].clamp(0.0, 1.0);
                [0, 1, 2].map(|i| c[i] * a + paper[i] * (1.0 - a))
            }),
            Painted::Color { .. } => f.map(|c| [c[0], c[1], c[2]]),
        })
        .collect()
}

/// Runs `f`, logging how long it took at debug level (`-vv` on the command line).
fn timed<T>(stage: &str, f: impl FnOnce() -> T) -> T {
    let start = std::time::Instant::now();
    let out = f();
    log::debug!("eval: {} took {:.3} s", stage, start.elapsed().as_secs_f64());
    out
}

/// The exemplar as the synthesis sees it: every `step`-th frame, resized by `scale`.
fn prepare_exemplar(exemplar: &Exemplar, step: usize, scale: f32) -> (Vec<Plane<Rgb>>, Vec<Plane<f32>>) {
    let resize = |w: usize, h: usize| {
        (((w as f32 * scale).round() as usize).max(1), ((h as f32 * scale).round() as usize).max(1))
    };
    let frames: Vec<Plane<Rgb>> = exemplar
        .frames
        .par_iter()
        .step_by(step)
        .map(|f| {
            let (w, h) = resize(f.width(), f.height());
            img::resize_bilinear(f, w, h)
        })
        .collect();
    let masks: Vec<Plane<f32>> = exemplar
        .masks
        .par_iter()
        .step_by(step)
        .map(|m| {
            let (w, h) = resize(m.width(), m.height());
            img::resize_bilinear(m, w, h)
        })
        .collect();
    (frames, masks)
}

/// Measures a stylized sequence.
///
/// `output` holds the stylized frames (straight RGBA: in the exemplar's colors with alpha =
/// the target mask, or opaque, composited over a background), `target_masks` the target mask
/// of each frame as coverage (`0..=1`, thresholded at 0.5), all of one size. Returns every
/// metric of the [module documentation](self), pooled over the sequence and per frame, with
/// the exemplar's own values where a ratio needs them.
///
/// Errors: [`Error::InvalidParam`] for an empty output, a mask count different from the frame
/// count, frames or masks of different sizes, an empty exemplar, or an invalid option.
pub fn evaluate(
    output: &[Plane<Rgba>],
    exemplar: &Exemplar,
    target_masks: &[Plane<f32>],
    options: &EvalOptions,
) -> Result<Report> {
    options.validate()?;
    let first = output.first().ok_or_else(|| Error::param("output", "0 frames", "at least one frame"))?;
    let (w, h) = first.size();
    check(
        target_masks.len() == output.len(),
        "target_masks",
        format!("{} masks", target_masks.len()),
        &format!("one mask per output frame ({})", output.len()),
    )?;
    for (i, (f, m)) in output.iter().zip(target_masks).enumerate() {
        for (what, size) in [("output frame", f.size()), ("target mask", m.size())] {
            check(
                size == (w, h),
                &format!("{} {}", what, i + 1),
                format!("{}x{}", size.0, size.1),
                &format!("{}x{} like output frame 1", w, h),
            )?;
        }
    }
    check(
        !exemplar.is_empty() && exemplar.frames.len() == exemplar.masks.len(),
        "exemplar",
        format!("{} frames, {} masks", exemplar.frames.len(), exemplar.masks.len()),
        "at least one frame, each with a mask",
    )?;
    let step = options.exemplar_step.unwrap_or(exemplar.meta.speed).max(1);
    let scale = options.exemplar_scale.unwrap_or(exemplar.meta.scale);
    let scale = if scale.is_finite() && scale > 0.0 { scale } else { 1.0 };
    let margin = options.interior_margin;

    // Exemplar side.
    let (ex_frames, ex_masks) = prepare_exemplar(exemplar, step, scale);
    let ex_shapes = timed("exemplar distance fields", || Shape::sequence(&ex_masks));
    let ex_regions: Vec<_> = ex_shapes.par_iter().map(|s| s.interior(margin)).collect();
    let ex_luma: Vec<_> = ex_frames.par_iter().map(luma_plane).collect();
    let ex_contrast = timed("exemplar contrast", || local_contrast_seq(&ex_frames, &ex_regions));
    let ex_temporal = timed("exemplar temporal change", || temporal_change(&ex_frames, &ex_shapes, &options.temporal));
    let ex_motion = timed("exemplar motion", || motion_agreement(&ex_luma, &ex_shapes, &options.motion));
    let mut ex_hist = ColorHistogram::new();
    for (f, r) in ex_frames.iter().zip(&ex_regions) {
        ex_hist.add_masked(f, r);
    }

    // Output side.
    let painted = detect_painted(output, options.background, options.paint_threshold);
    let out_rgb = composite_output(output, &painted, exemplar.paper());
    let shapes = timed("target distance fields", || Shape::sequence(target_masks));
    let regions: Vec<_> = shapes.par_iter().map(|s| s.interior(margin)).collect();
    let out_luma: Vec<_> = out_rgb.par_iter().map(luma_plane).collect();

    let coverage = timed("coverage", || coverage_iou(output, &shapes, &painted));
    let contrast = timed("contrast", || local_contrast_seq(&out_rgb, &regions));
    let hists: Vec<ColorHistogram> =
        out_rgb.par_iter().zip(&regions).map(|(f, r)| ColorHistogram::of_region(f, r)).collect();
    let mut out_hist = ColorHistogram::new();
    for hgram in &hists {
        out_hist.merge(hgram);
    }
    let palette_frames: Vec<Option<[f32; 3]>> = hists.par_iter().map(|hg| hg.wasserstein(&ex_hist)).collect();
    let palette = out_hist.wasserstein(&ex_hist);
    let index = timed("patch index", || PatchIndex::build(&ex_frames, &ex_regions, &options.patches));
    let patches = timed("patch search", || patch_nn_distance_with(&index, &out_rgb, &regions, &options.patches));
    let temporal = timed("temporal change", || temporal_change(&out_rgb, &shapes, &options.temporal));
    let motion = timed("motion", || motion_agreement(&out_luma, &shapes, &options.motion));

    let n = output.len();
    let at = |m: &Measure, i: usize| m.per_frame.get(i).copied().flatten();
    let per_frame = (0..n)
        .map(|i| FrameStats {
            frame: i + 1,
            coverage_iou: at(&coverage, i),
            local_contrast: at(&contrast, i),
            contrast_ratio: ratio(at(&contrast, i), ex_contrast.value),
            palette_distance: palette_frames[i],
            patch_nn_distance: at(&patches, i),
            temporal_change: at(&temporal, i),
            temporal_change_ratio: ratio(at(&temporal, i), ex_temporal.value),
            motion_agreement: at(&motion, i),
        })
        .collect();
    let summary = Summary {
        coverage_iou: coverage.value,
        local_contrast: contrast.value,
        contrast_ratio: ratio(contrast.value, ex_contrast.value),
        palette_distance: palette,
        palette_distance_mean: palette.map(|p| (p[0] + p[1] + p[2]) / 3.0),
        patch_nn_distance: patches.value,
        temporal_change: temporal.value,
        temporal_change_ratio: ratio(temporal.value, ex_temporal.value),
        motion_agreement: motion.value,
        interior_pixels: out_hist.len(),
        patch_samples: patches.samples,
        temporal_pixels: temporal.samples,
        motion_points: motion.samples,
    };
    let exemplar_summary = ExemplarSummary {
        name: exemplar.meta.name.clone(),
        frames: ex_frames.len(),
        width: ex_frames[0].width(),
        height: ex_frames[0].height(),
        step,
        scale,
        local_contrast: ex_contrast.value,
        temporal_change: ex_temporal.value,
        motion_agreement: ex_motion.value,
        interior_pixels: ex_hist.len(),
        patch_pool: index.len() as u64,
        temporal_pixels: ex_temporal.samples,
        motion_points: ex_motion.samples,
    };
    Ok(Report {
        frames: n,
        width: w,
        height: h,
        exemplar: exemplar_summary,
        painted,
        summary,
        per_frame,
        options: options.clone(),
    })
}
