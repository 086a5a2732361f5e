//! Incoherent change: how much the paint changes between consecutive frames in ways its own
//! motion does not explain — boiling, as opposed to paint that flows.

use super::depth::{DEPTH_BINS, depth_bin};
use super::{FarnebackParams, Mean, Measure, Shape, farneback_flow, warp_bilinear};
use crate::img::{Mask, Plane};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Settings of [`incoherent_change`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CoherenceParams {
    /// The residual is averaged over pixels at least this far inside both frames' masks, as
    /// `d = sdf + ½` (see [`super::RimParams`]), pixels. Default: 5.
    pub margin: f32,
    /// The optical flow. Default: [`FarnebackParams::default`].
    pub flow: FarnebackParams,
}

impl Default for CoherenceParams {
    fn default() -> Self {
        CoherenceParams { margin: 5.0, flow: FarnebackParams::default() }
    }
}

/// The pixels of a pair where [`flow_residual`] is measured: at least `margin` inside both
/// masks (`d = sdf + ½ >= margin`).
pub fn coherence_region(prev: &Shape, next: &Shape, margin: f32) -> Mask {
    let (w, h) = prev.size();
    Plane::from_fn(w, h, |x, y| prev.sdf.get(x, y).min(next.sdf.get(x, y)) + 0.5 >= margin)
}

/// The change from `prev` to `next` (luma planes) that motion does not explain: with the
/// dense flow `f` from `next` to `prev` ([`farneback_flow`]), both frames are carried to the
/// time half-way between them — `prev` read at `x + f/2`, `next` at `x − f/2`
/// ([`warp_bilinear`]) — and the result is the mean absolute luma difference of the two over
/// `region`; `None` for an empty region. 0 for paint that only moves (a translated texture);
/// large when each frame shows unrelated paint.
///
/// Half-way rather than `prev` carried the whole way onto `next`: bilinear reading between
/// pixels blurs, and blurring only one of the two frames counted the blur as change. For a
/// translation by `f` the two readings fall at mirrored fractions of a pixel and blur alike.
/// Measured on a still paint moved rigidly (nothing in it changes; the bundled exemplars'
/// last frames, 24 frames, 0.5 and 1.3 px a frame): yellow-granules' fine grain read 0.0041
/// and 0.0049 luma carried the whole way — three quarters of the exemplar's own change, 0.0054
/// — and 0.0026 and 0.0022 half-way; ink-rims 0.0056 and 0.0067 against 0.0035 and 0.0031.
/// Whole-pixel moves read 0.0002–0.0003 either way.
pub fn flow_residual(prev: &Plane<f32>, next: &Plane<f32>, region: &Mask, params: &FarnebackParams) -> Option<f32> {
    let (sum, n) = residual_sum(prev, next, region, params);
    (n > 0).then(|| (sum / n as f64) as f32)
}

fn residual_sum(prev: &Plane<f32>, next: &Plane<f32>, region: &Mask, params: &FarnebackParams) -> (f64, u64) {
    let bins = residual_bins(prev, next, region, params, 1, |_| 0);
    bins.first().map_or((0.0, 0), |m| (m.sum(), m.count()))
}

/// [`flow_residual`]'s sums per bin: the residual of every pixel of `region` (row-major
/// index) pooled into bin `bin(index)` of `n` (indices past the last go to the last).
fn residual_bins(
    prev: &Plane<f32>,
    next: &Plane<f32>,
    region: &Mask,
    params: &FarnebackParams,
    n: usize,
    bin: impl Fn(usize) -> usize,
) -> Vec<Mean> {
    let mut bins = vec![Mean::default(); n.max(1)];
    if region.data().iter().all(|&b| !b) {
        return bins;
    }
    let flow = farneback_flow(next, prev, params);
    let (ahead, behind) = (flow.map(|f| f * 0.5), flow.map(|f| f * -0.5));
    let warped = warp_bilinear(prev, &ahead);
    let met = warp_bilinear(next, &behind);
    let last = bins.len() - 1;
    for (k, ((&a, &b), &inside)) in met.data().iter().zip(warped.data()).zip(region.data()).enumerate() {
        if inside {
            bins[bin(k).min(last)].add((a - b).abs() as f64);
        }
    }
    bins
}

/// One pair of frames' [`flow_residual`] over their [`coherence_region`]: its value, and its
/// sums per depth bin (whose counts are the pixels behind it) ([`depth_bin`] of the smaller of the two
/// frames' distances from the edge).
pub(crate) struct PairResidual {
    pub value: Option<f32>,
    pub bins: Vec<Mean>,
}

/// The [`PairResidual`] of one pair of frames.
pub(crate) fn pair_residual(
    prev: (&Plane<f32>, &Shape),
    next: (&Plane<f32>, &Shape),
    params: &CoherenceParams,
) -> PairResidual {
    let region = coherence_region(prev.1, next.1, params.margin);
    let (a, b) = (prev.1.sdf.data(), next.1.sdf.data());
    let bins = residual_bins(prev.0, next.0, &region, &params.flow, DEPTH_BINS, |k| depth_bin(a[k].min(b[k])));
    let value = bins.iter().fold(Mean::default(), |a, &b| a.merged(b)).value();
    PairResidual { value, bins }
}

/// Incoherent change of a sequence of luma planes: for each pair of consecutive frames
/// `(i − 1, i)` (reported at frame `i`; frame 0 has none) the [`flow_residual`] over their
/// [`coherence_region`]; the sequence's value is the **mean over the pairs** that have one.
/// `samples` counts the pixels behind all pairs.
///
/// Compare a stylized sequence with its exemplar by the ratio of the two: ≈ 1 changes like
/// the exemplar's paint, ≫ 1 boils; the exemplar's frames in a shuffled order score several
/// times their ordered value.
pub fn incoherent_change(lumas: &[Plane<f32>], shapes: &[Shape], params: &CoherenceParams) -> Measure {
    incoherent_change_binned(lumas, shapes, params).0
}

/// [`incoherent_change`], and its residuals pooled over all pairs per depth bin (see
/// [`PairResidual`]).
pub(crate) fn incoherent_change_binned(
    lumas: &[Plane<f32>],
    shapes: &[Shape],
    params: &CoherenceParams,
) -> (Measure, Vec<Mean>) {
    let n = lumas.len().min(shapes.len());
    let pairs: Vec<Option<PairResidual>> = (0..n)
        .into_par_iter()
        .map(|i| (i > 0).then(|| pair_residual((&lumas[i - 1], &shapes[i - 1]), (&lumas[i], &shapes[i]), params)))
        .collect();
    let mut bins = vec![Mean::default(); DEPTH_BINS];
    for p in pairs.iter().flatten() {
        for (a, &b) in bins.iter_mut().zip(&p.bins) {
            *a = a.merged(b);
        }
    }
    let samples = bins.iter().map(|b| b.count()).sum();
    let values = pairs.iter().map(|p| p.as_ref().and_then(|p| p.value)).collect();
    (Measure { samples, ..Measure::from_frame_values(values) }, bins)
}
