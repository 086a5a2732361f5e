//! The evaluation itself: the exemplar's side prepared once ([`Reference`]), output frames
//! measured batch by batch ([`Evaluator`]), and [`evaluate`] doing both for a whole sequence.

use super::coherence::{incoherent_change_binned, pair_residual};
use super::contrast::local_contrast_binned;
use super::coverage::{COVER_BINS, PaintedProfile, coverage_from_counts, mask_bins};
use super::depth::{DEPTH_BINS, DepthProfile, depth_bin, paint_depth, region_bins};
use super::flow::{motion_pair_mean, motion_pair_mean_with};
use super::patches::frame_patch_mean;
use super::temporal::frame_change_mean;
use super::{
    ColorHistogram, EvalOptions, ExemplarSummary, FrameStats, Mean, Measure, Painted, PatchIndex, Report, Shape,
    Summary, check, composite_output, detect_painted, edge_darkening, edge_darkening_seq, intersection_union,
    luma_plane, motion_agreement, painted_mask, ratio, stationary_interior, temporal_change, timed,
};
use crate::error::{Error, Result};
use crate::exemplar::Exemplar;
use crate::img::{self, Blend, Mask, Plane, Rgb, Rgba};
use rayon::prelude::*;
use std::ops::Range;

/// Every `step`-th plane, resized by `scale`: the exemplar as the synthesis sees it.
fn resample<T: Blend>(planes: &[Plane<T>], step: usize, scale: f32) -> Vec<Plane<T>> {
    planes
        .par_iter()
        .step_by(step)
        .map(|p| {
            let size = |v: usize| ((v as f32 * scale).round() as usize).max(1);
            img::resize_bilinear(p, size(p.width()), size(p.height()))
        })
        .collect()
}

/// The exemplar's side of an evaluation, measured once: its frames and masks as the synthesis
/// sees them (every `step`-th frame, resized by `scale`, per [`EvalOptions::exemplar_step`]
/// and [`EvalOptions::exemplar_scale`]) and its own values of every measure that is compared
/// by a ratio.
pub struct Reference {
    name: String,
    /// The border width `b` and the paint's depth `R` at which a deeper target is measured
    /// ([`EvalOptions::depth_stretch`]); `None` = at its own depths.
    stretch: Option<(f32, f32)>,
    step: usize,
    scale: f32,
    paper: Rgb,
    frames: Vec<Plane<Rgb>>,
    masks: Vec<Plane<f32>>,
    regions: Vec<Mask>,
    temporal: Measure,
    motion: Measure,
    rim: Measure,
    coherence: Measure,
    /// Contrast and colors over the whole interior (from `depth`).
    contrast: Option<f32>,
    hist: ColorHistogram,
    depth: DepthProfile,
    /// How much of its masks its paint covers per depth (for the coverage an exemplar-like
    /// output can reach).
    painted: PaintedProfile,
}

impl Reference {
    /// Measures `exemplar`. Errors: [`Error::InvalidParam`] for an invalid option or an empty
    /// exemplar.
    pub fn new(exemplar: &Exemplar, options: &EvalOptions) -> Result<Reference> {
        options.validate()?;
        check(
            !exemplar.is_empty() && exemplar.frames.len() == exemplar.masks.len(),
            "exemplar",
            format!("{} frames, {} masks", exemplar.frames.len(), exemplar.masks.len()),
            "at least one frame, each with a mask",
        )?;
        let step = options.exemplar_step.unwrap_or(exemplar.meta.speed).max(1);
        let scale = options.exemplar_scale.unwrap_or(exemplar.meta.scale);
        let scale = if scale.is_finite() && scale > 0.0 { scale } else { 1.0 };
        let (frames, masks) = (resample(&exemplar.frames, step, scale), resample(&exemplar.masks, step, scale));
        let shapes = timed("exemplar distance fields", || Shape::sequence(&masks));
        let regions: Vec<Mask> = shapes.par_iter().map(|s| s.interior(options.interior_margin)).collect();
        let lumas: Vec<Plane<f32>> = frames.par_iter().map(luma_plane).collect();
        let temporal = timed("exemplar temporal change", || temporal_change(&frames, &shapes, &options.temporal));
        let motion = timed("exemplar motion", || motion_agreement(&lumas, &shapes, &options.motion));
        let rim = timed("exemplar edge darkening", || edge_darkening_seq(&frames, &shapes, &options.rim));
        let (coherence, coherence_bins) =
            timed("exemplar incoherent change", || incoherent_change_binned(&lumas, &shapes, &options.coherence));
        // Contrast and colors per depth, and over the whole interior from the same pass.
        let depth = timed("exemplar depth profile", || DepthProfile::new(&frames, &shapes, &regions, &coherence_bins));
        let (contrast, hist) = depth.whole();
        let contrast = contrast.value();
        let paper = exemplar.paper();
        let painted = PaintedProfile::new(&frames, &shapes, paper, options.paint_threshold);
        let stretch = options.depth_stretch.then(|| (exemplar.meta.border_width * scale, paint_depth(&shapes)));
        Ok(Reference {
            name: exemplar.meta.name.clone(),
            stretch,
            step,
            scale,
            paper,
            frames,
            masks,
            regions,
            contrast,
            temporal,
            motion,
            rim,
            coherence,
            hist,
            depth,
            painted,
        })
    }

    /// The exemplar's frames as measured (after its step and scale).
    pub fn frames(&self) -> &[Plane<Rgb>] {
        &self.frames
    }

    /// The exemplar's masks as measured (coverage, after its step and scale).
    pub fn masks(&self) -> &[Plane<f32>] {
        &self.masks
    }

    /// Its paper color (from its metadata): outputs with alpha are composited over it.
    pub fn paper(&self) -> Rgb {
        self.paper
    }

    /// The depths at which `shape`'s pixels are compared with the exemplar's
    /// ([`EvalOptions::depth_stretch`]): its signed distances, a part deeper than the
    /// exemplar's paint stretched onto the paint's depths.
    pub(crate) fn matched_depths<'s>(&self, shape: &'s Shape) -> std::borrow::Cow<'s, Plane<f32>> {
        match self.stretch {
            Some((band, reach)) => {
                std::borrow::Cow::Owned(crate::guide::stretched_depths(&shape.sdf, &shape.mask, band, |_| Some(reach)))
            }
            None => std::borrow::Cow::Borrowed(&shape.sdf),
        }
    }

    /// Its own edge darkening ([`super::edge_darkening`], mean over its frames).
    pub fn edge_darkening(&self) -> Option<f32> {
        self.rim.value
    }

    fn summary(&self, patch_pool: u64) -> ExemplarSummary {
        ExemplarSummary {
            name: self.name.clone(),
            frames: self.frames.len(),
            width: self.frames[0].width(),
            height: self.frames[0].height(),
            step: self.step,
            scale: self.scale,
            local_contrast: self.contrast,
            temporal_change: self.temporal.value,
            motion_agreement: self.motion.value,
            edge_darkening: self.rim.value,
            incoherent_change: self.coherence.value,
            interior_pixels: self.hist.len(),
            patch_pool,
            temporal_pixels: self.temporal.samples,
            motion_points: self.motion.samples,
        }
    }
}

/// What one output frame contributed.
#[derive(Clone)]
struct FrameTotals {
    /// Intersection and union of the painted area with the target mask.
    coverage: (u64, u64),
    /// The target mask's pixels per depth ([`mask_bins`]).
    mask_bins: Vec<u64>,
    /// The local contrast per depth bin, and the interior's pixels per depth bin.
    contrast_bins: Vec<Mean>,
    region_bins: Vec<u64>,
    hist: ColorHistogram,
    patches: Mean,
    temporal: Mean,
    motion: Mean,
    rim: Option<f32>,
    coherence: Option<f32>,
    /// The flow residual's pixels per depth bin (all zero for a frame without a pair).
    coherence_bins: Vec<u64>,
}

impl FrameTotals {
    /// The local contrast over all depths.
    fn contrast(&self) -> Mean {
        self.contrast_bins.iter().fold(Mean::default(), |a, &b| a.merged(b))
    }
}

/// The last frame of the previous batch, for the measures of consecutive pairs.
struct Previous {
    rgb: Plane<Rgb>,
    luma: Plane<f32>,
    shape: Shape,
}

/// Measures an output sequence a batch of frames at a time, so that memory does not grow
/// with its length (beyond a few numbers and one color histogram per frame): push frames in
/// order with [`Evaluator::push`], then ask for the [`Evaluator::report`] of all of them or
/// the [`Evaluator::summary`] of a range of them.
///
/// The result is exactly [`evaluate`]'s on the same frames, however they are batched.
pub struct Evaluator<'a> {
    reference: &'a Reference,
    index: PatchIndex<'a>,
    options: EvalOptions,
    painted: Painted,
    /// The sequence length the patch samples are spread over.
    expected: usize,
    size: Option<(usize, usize)>,
    frames: Vec<FrameTotals>,
    prev: Option<Previous>,
    /// The target's known motion, when it has one ([`Evaluator::with_motion`]).
    motion: Option<KnownMotion<'a>>,
}

/// The motion at pixel `(x, y)` from frame `k − 1` to frame `k`, called as `(k, x, y)`.
pub type KnownMotion<'a> = Box<dyn Fn(usize, usize, usize) -> Option<glam::Vec2> + Sync + 'a>;

impl<'a> Evaluator<'a> {
    /// An evaluator of a sequence of `frames` frames (the number over which
    /// [`super::PatchParams::samples`] are spread; more or fewer may be pushed) whose painted
    /// pixels are told by `painted` (see [`detect_painted`]). `options` should be the ones
    /// `reference` was made with.
    pub fn new(reference: &'a Reference, options: &EvalOptions, frames: usize, painted: Painted) -> Result<Self> {
        options.validate()?;
        let index = timed("patch index", || PatchIndex::build(&reference.frames, &reference.regions, &options.patches));
        Ok(Evaluator {
            reference,
            index,
            options: options.clone(),
            painted,
            expected: frames.max(1),
            size: None,
            frames: Vec::new(),
            prev: None,
            motion: None,
        })
    }

    /// Measures the motion agreement against the target's known motion `motion(k, x, y)` (a
    /// generated target's whole motion) instead of the normal motion its masks reveal
    /// ([`super::motion_agreement_with`]): masks show only the normal part, which rewards paint
    /// that lags a turning shape (the quality suite's turning ellipse on the flow guide before
    /// 2026-12-06: 0.84–0.86 against the normal part, 0.56–0.59 against the whole motion;
    /// `crate::quality`).
    pub fn with_motion(mut self, motion: KnownMotion<'a>) -> Self {
        self.motion = Some(motion);
        self
    }

    /// Frames pushed so far.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// True before the first frame.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// Measures the next frames: `output[i]` (straight RGBA, see [`evaluate`]) with its target
    /// coverage `masks[i]`, all of the size of the first frame ever pushed. Frames of a batch
    /// are measured in parallel.
    pub fn push(&mut self, output: &[Plane<Rgba>], masks: &[Plane<f32>]) -> Result<()> {
        let Some(first) = output.first() else {
            return check_batch(output, masks, (0, 0), 0);
        };
        let size = *self.size.get_or_insert(first.size());
        check_batch(output, masks, size, self.frames.len())?;
        let o = &self.options;
        let rgb = composite_output(output, &self.painted, self.reference.paper);
        let shapes = Shape::sequence(masks);
        let lumas: Vec<Plane<f32>> = rgb.par_iter().map(luma_plane).collect();
        let offset = self.frames.len();
        let per_frame_samples = o.patches.samples.div_ceil(self.expected).max(1);
        let prev = self.prev.as_ref();
        let totals: Vec<FrameTotals> = (0..output.len())
            .into_par_iter()
            .map(|i| {
                let shape = &shapes[i];
                let region = shape.interior(o.interior_margin);
                let before = if i > 0 {
                    Some((&rgb[i - 1], &lumas[i - 1], &shapes[i - 1]))
                } else {
                    prev.map(|p| (&p.rgb, &p.luma, &p.shape))
                };
                let (temporal, motion, pair) = match before {
                    Some((prgb, pluma, pshape)) => {
                        let still = stationary_interior(pshape, shape, &o.temporal);
                        (
                            frame_change_mean(prgb, &rgb[i], &still),
                            match &self.motion {
                                Some(m) => {
                                    motion_pair_mean_with((pluma, pshape), (&lumas[i], shape), &o.motion, &|x, y| {
                                        m(offset + i, x, y)
                                    })
                                }
                                None => motion_pair_mean((pluma, pshape), (&lumas[i], shape), &o.motion),
                            },
                            Some(pair_residual((pluma, pshape), (&lumas[i], shape), &o.coherence)),
                        )
                    }
                    None => (Mean::default(), Mean::default(), None),
                };
                let coherence = pair.as_ref().and_then(|p| p.value);
                let coherence_bins =
                    pair.map_or_else(|| vec![0; DEPTH_BINS], |p| p.bins.iter().map(|b| b.count()).collect());
                let contrast_bins =
                    local_contrast_binned(&rgb[i], &region, DEPTH_BINS, |x, y| depth_bin(shape.sdf.get(x, y)));
                FrameTotals {
                    coverage: intersection_union(&painted_mask(&output[i], &self.painted), &shape.mask),
                    mask_bins: mask_bins(shape),
                    // The palette's depths ([`EvalOptions::depth_stretch`]).
                    region_bins: region_bins(&self.reference.matched_depths(shape), &region),
                    contrast_bins,
                    hist: ColorHistogram::of_region(&rgb[i], &region),
                    patches: frame_patch_mean(
                        &self.index,
                        &rgb[i],
                        &region,
                        offset + i,
                        per_frame_samples,
                        o.patches.seed,
                    ),
                    temporal,
                    motion,
                    rim: edge_darkening(&rgb[i], shape, &o.rim),
                    coherence,
                    coherence_bins,
                }
            })
            .collect();
        self.frames.extend(totals);
        if let (Some(rgb), Some(luma), Some(shape)) =
            (rgb.into_iter().last(), lumas.into_iter().last(), shapes.into_iter().last())
        {
            self.prev = Some(Previous { rgb, luma, shape });
        }
        Ok(())
    }

    /// Every measure over the frames in `range` (0-based; measures of a pair count at its
    /// second frame, so the first frame of a range still compares with the frame before it),
    /// pooled or averaged as over a whole sequence, and their per-frame values.
    pub fn summary(&self, range: Range<usize>) -> (Summary, Vec<FrameStats>) {
        let range = range.start.min(self.frames.len())..range.end.min(self.frames.len());
        let frames = &self.frames[range.clone()];
        let r = self.reference;
        let pooled = |f: fn(&FrameTotals) -> Mean| Measure::from_means(&frames.iter().map(f).collect::<Vec<_>>());
        let contrast = pooled(FrameTotals::contrast);
        let patches = pooled(|t| t.patches);
        let temporal = pooled(|t| t.temporal);
        let motion = pooled(|t| t.motion);
        let rim = Measure::from_frame_values(frames.iter().map(|t| t.rim).collect());
        let coverage = coverage_from_counts(&frames.iter().map(|t| t.coverage).collect::<Vec<_>>());
        let mut hist = ColorHistogram::new();
        let mut contrast_bins = vec![Mean::default(); DEPTH_BINS];
        let mut counts = vec![0u64; DEPTH_BINS];
        let mut mask_counts = vec![0u64; COVER_BINS];
        let mut coherence_counts = vec![0u64; DEPTH_BINS];
        for t in frames {
            hist.merge(&t.hist);
            for k in 0..DEPTH_BINS {
                contrast_bins[k] = contrast_bins[k].merged(t.contrast_bins[k]);
                counts[k] += t.region_bins[k];
                coherence_counts[k] += t.coherence_bins[k];
            }
            for (a, b) in mask_counts.iter_mut().zip(&t.mask_bins) {
                *a += b;
            }
        }
        let coherence = Measure {
            samples: coherence_counts.iter().sum(),
            ..Measure::from_frame_values(frames.iter().map(|t| t.coherence).collect())
        };
        // The exemplar's incoherent change at the output's depths.
        let coherence_at = |counts: &[u64]| Some(r.coherence.value? * r.depth.coherence_factor(counts)?);
        let palette = r.depth.palette(&hist, &counts);
        let palette_whole = hist.wasserstein(&r.hist);
        let per_frame = frames
            .par_iter()
            .enumerate()
            .map(|(k, t)| FrameStats {
                frame: range.start + k + 1,
                coverage_iou: coverage.per_frame[k],
                coverage_iou_exemplar: r.painted.expected_iou(&t.mask_bins),
                local_contrast: t.contrast().value(),
                contrast_ratio: ratio(t.contrast().value(), r.depth.contrast(&t.contrast_bins)),
                palette_distance: r.depth.palette(&t.hist, &t.region_bins),
                patch_nn_distance: t.patches.value(),
                temporal_change: t.temporal.value(),
                temporal_change_ratio: ratio(t.temporal.value(), r.temporal.value),
                motion_agreement: t.motion.value(),
                edge_darkening: t.rim,
                edge_darkening_ratio: ratio(t.rim, r.rim.value),
                incoherent_change: t.coherence,
                incoherent_change_ratio: ratio(t.coherence, r.coherence.value),
                incoherent_change_ratio_depth: ratio(t.coherence, coherence_at(&t.coherence_bins)),
            })
            .collect();
        let summary = Summary {
            coverage_iou: coverage.value,
            coverage_iou_exemplar: r.painted.expected_iou(&mask_counts),
            local_contrast: contrast.value,
            contrast_ratio: ratio(contrast.value, r.depth.contrast(&contrast_bins)),
            contrast_ratio_whole: ratio(contrast.value, r.contrast),
            palette_distance: palette,
            palette_distance_mean: palette.map(|p| (p[0] + p[1] + p[2]) / 3.0),
            palette_distance_whole: palette_whole.map(|p| (p[0] + p[1] + p[2]) / 3.0),
            patch_nn_distance: patches.value,
            temporal_change: temporal.value,
            temporal_change_ratio: ratio(temporal.value, r.temporal.value),
            motion_agreement: motion.value,
            edge_darkening: rim.value,
            edge_darkening_ratio: ratio(rim.value, r.rim.value),
            incoherent_change: coherence.value,
            incoherent_change_ratio: ratio(coherence.value, r.coherence.value),
            incoherent_change_ratio_depth: ratio(coherence.value, coherence_at(&coherence_counts)),
            interior_pixels: hist.len(),
            patch_samples: patches.samples,
            temporal_pixels: temporal.samples,
            motion_points: motion.samples,
            rim_frames: rim.samples,
            incoherent_pixels: coherence.samples,
        };
        (summary, per_frame)
    }

    /// Every measure over all frames pushed.
    pub fn report(&self) -> Report {
        let (summary, per_frame) = self.summary(0..self.frames.len());
        let (width, height) = self.size.unwrap_or((0, 0));
        Report {
            frames: self.frames.len(),
            width,
            height,
            exemplar: self.reference.summary(self.index.len() as u64),
            painted: self.painted,
            summary,
            per_frame,
            options: self.options.clone(),
        }
    }
}

/// Checks that there is a mask per frame and that frames and masks are all `size`; `offset`
/// is the number of frames before these (for the frame numbers in the errors).
fn check_batch(output: &[Plane<Rgba>], masks: &[Plane<f32>], size: (usize, usize), offset: usize) -> Result<()> {
    check(
        masks.len() == output.len(),
        "target_masks",
        format!("{} masks", masks.len()),
        &format!("one mask per output frame ({})", output.len()),
    )?;
    let (w, h) = size;
    for (i, (f, m)) in output.iter().zip(masks).enumerate() {
        for (what, found) in [("output frame", f.size()), ("target mask", m.size())] {
            check(
                found == size,
                &format!("{} {}", what, offset + i + 1),
                format!("{}x{}", found.0, found.1),
                &format!("{}x{} like output frame 1", w, h),
            )?;
        }
    }
    Ok(())
}

/// Measures a stylized sequence.
///
/// `output` holds the stylized frames (straight RGBA: in the exemplar's colors with alpha =
/// the target mask, or opaque, composited over a background), `target_masks` the target mask
/// of each frame as coverage (`0..=1`, thresholded at 0.5), all of one size. Returns every
/// metric of the [module documentation](super), pooled over the sequence and per frame, with
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
    check_batch(output, target_masks, first.size(), 0)?;
    let reference = Reference::new(exemplar, options)?;
    let painted = detect_painted(output, options.background, options.paint_threshold);
    let mut evaluator = Evaluator::new(&reference, options, output.len(), painted)?;
    timed("output measures", || evaluator.push(output, target_masks))?;
    Ok(evaluator.report())
}
