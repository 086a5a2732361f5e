//! Incoherent change: how much the paint changes between consecutive frames in ways its own
//! motion does not explain — boiling, as opposed to paint that flows.

use super::{FarnebackParams, Measure, Shape, farneback_flow, warp_bilinear};
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

/// The change from `prev` to `next` (luma planes) that motion does not explain: the dense
/// flow from `next` to `prev` ([`farneback_flow`]) carries `prev` onto `next`
/// ([`warp_bilinear`]), and the result is the mean absolute luma difference
/// `|next − warped prev|` over `region`; `None` for an empty region. 0 for paint that only
/// moves (a translated texture); large when each frame shows unrelated paint.
pub fn flow_residual(prev: &Plane<f32>, next: &Plane<f32>, region: &Mask, params: &FarnebackParams) -> Option<f32> {
    let (sum, n) = residual_sum(prev, next, region, params);
    (n > 0).then(|| (sum / n as f64) as f32)
}

fn residual_sum(prev: &Plane<f32>, next: &Plane<f32>, region: &Mask, params: &FarnebackParams) -> (f64, u64) {
    if region.data().iter().all(|&b| !b) {
        return (0.0, 0);
    }
    let flow = farneback_flow(next, prev, params);
    let warped = warp_bilinear(prev, &flow);
    let (mut sum, mut n) = (0f64, 0u64);
    for ((&a, &b), &inside) in next.data().iter().zip(warped.data()).zip(region.data()) {
        if inside {
            sum += (a - b).abs() as f64;
            n += 1;
        }
    }
    (sum, n)
}

/// The [`flow_residual`] of one pair of frames over their [`coherence_region`], and the
/// number of pixels behind it.
pub(crate) fn pair_residual(
    prev: (&Plane<f32>, &Shape),
    next: (&Plane<f32>, &Shape),
    params: &CoherenceParams,
) -> (Option<f32>, u64) {
    let region = coherence_region(prev.1, next.1, params.margin);
    let (sum, n) = residual_sum(prev.0, next.0, &region, &params.flow);
    ((n > 0).then(|| (sum / n as f64) as f32), n)
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
    let n = lumas.len().min(shapes.len());
    let pairs: Vec<(Option<f32>, u64)> = (0..n)
        .into_par_iter()
        .map(|i| {
            if i == 0 {
                return (None, 0);
            }
            pair_residual((&lumas[i - 1], &shapes[i - 1]), (&lumas[i], &shapes[i]), params)
        })
        .collect();
    let samples = pairs.iter().map(|p| p.1).sum();
    Measure { samples, ..Measure::from_frame_values(pairs.into_iter().map(|p| p.0).collect()) }
}
