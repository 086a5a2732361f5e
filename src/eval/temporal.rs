//! Temporal behaviour: how much the paint changes between consecutive frames where the
//! target is still.

use super::{Mean, Measure, Shape};
use crate::img::{Mask, Plane, Rgb};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Which pixels of a pair of frames form the *stationary interior*.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TemporalParams {
    /// A pixel must lie at least this far inside the mask in both frames (signed distance, px).
    /// Default: 5.
    pub margin: f32,
    /// … and so far from the boundary that the boundary, moving at its current local speed
    /// `|Δsdf|` px/frame, would need at least this many frames to reach it:
    /// `min(sdf_prev, sdf_next) >= margin + horizon · |sdf_next − sdf_prev|`. 0 disables the
    /// motion criterion. Default: 4 frames.
    pub horizon: f32,
}

impl Default for TemporalParams {
    fn default() -> Self {
        TemporalParams { margin: 5.0, horizon: 4.0 }
    }
}

/// The stationary interior of two consecutive frames (see [`TemporalParams`]): pixels well
/// inside both masks where the target does not move, or moves so slowly that its boundary
/// stays far away. For a target that does not move at all this is the interior
/// `sdf >= margin`; for a growing disc it is a smaller concentric disc; the sides of a
/// translating shape (where the boundary slides along itself) stay in, the leading and
/// trailing parts drop out.
pub fn stationary_interior(prev: &Shape, next: &Shape, params: &TemporalParams) -> Mask {
    let (w, h) = prev.size();
    Plane::from_fn(w, h, |x, y| {
        let (a, b) = (prev.sdf.get(x, y), next.sdf.get(x, y));
        a.min(b) >= params.margin + params.horizon * (b - a).abs()
    })
}

/// Mean absolute change between two frames over `region`: the mean over the region of
/// `(|ΔR| + |ΔG| + |ΔB|) / 3` (sRGB, `0..=1`); `None` for an empty region.
pub fn frame_change(prev: &Plane<Rgb>, next: &Plane<Rgb>, region: &Mask) -> Option<f32> {
    frame_change_mean(prev, next, region).value()
}

pub(crate) fn frame_change_mean(prev: &Plane<Rgb>, next: &Plane<Rgb>, region: &Mask) -> Mean {
    let mut m = Mean::default();
    for ((a, b), &inside) in prev.data().iter().zip(next.data()).zip(region.data()) {
        if inside {
            m.add((((a[0] - b[0]).abs() + (a[1] - b[1]).abs() + (a[2] - b[2]).abs()) / 3.0) as f64);
        }
    }
    m
}

/// Temporal change of a sequence: for each pair of consecutive frames `(i − 1, i)`, the
/// [`frame_change`] over their [`stationary_interior`] (reported at frame `i`; frame 0 has
/// none), and the mean over all such pixels of all pairs.
///
/// `shapes[i]` is the target (or exemplar) mask of `frames[i]`. Compare a stylized sequence
/// with its exemplar through the ratio of the two pooled values: ≈ 1 is exemplar-like
/// dynamics, ≫ 1 flicker, ≈ 0 paint glued still.
pub fn temporal_change(frames: &[Plane<Rgb>], shapes: &[Shape], params: &TemporalParams) -> Measure {
    let n = frames.len().min(shapes.len());
    let means: Vec<Mean> = (0..n)
        .into_par_iter()
        .map(|i| {
            if i == 0 {
                return Mean::default();
            }
            let region = stationary_interior(&shapes[i - 1], &shapes[i], params);
            frame_change_mean(&frames[i - 1], &frames[i], &region)
        })
        .collect();
    Measure::from_means(&means)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disc(w: usize, r: f32, cx: f32) -> Shape {
        Shape::from_mask(Plane::from_fn(w, w, |x, y| {
            let (dx, dy) = (x as f32 - cx, y as f32 - w as f32 / 2.0);
            dx * dx + dy * dy <= r * r
        }))
    }

    #[test]
    fn stationary_region_of_still_growing_and_moving_targets() {
        let p = TemporalParams::default();
        let still = stationary_interior(&disc(64, 20.0, 32.0), &disc(64, 20.0, 32.0), &p);
        let interior = disc(64, 20.0, 32.0).interior(5.0);
        assert_eq!(still, interior);
        // Growing by 2 px/frame: only pixels at least 5 + 4·2 = 13 px inside stay.
        let grow = stationary_interior(&disc(64, 20.0, 32.0), &disc(64, 22.0, 32.0), &p);
        assert!(grow.get(32, 32) && !grow.get(32 + 9, 32) && grow.get(32 + 6, 32));
        // Without the motion criterion, the whole common interior counts.
        let loose = TemporalParams { horizon: 0.0, ..p };
        assert!(stationary_interior(&disc(64, 20.0, 32.0), &disc(64, 22.0, 32.0), &loose).get(32 + 14, 32));
    }
}
