//! Guidance channels (thesis §3.4–3.8, §4.1; paper Appendix A), computed by the same code for
//! the exemplar sequence S and the target sequence T:
//!
//! * mask pre-processing: Gaussian blur (σ = `blur_sigma`) and a threshold below 0.5;
//! * the signed distance field `I^dist` (positive inside);
//! * the border channel `I^df = min(I^dist / b, 1)` ([`FrameGuides::df`]);
//! * the flow field `I^flow` (boundary values from distance-field differences, diffused into
//!   the interior by a multigrid Laplace solve, smoothed in time);
//! * motion extent `I^ext+` / `I^ext−` (norms of the 2D flow accumulated forward / backward in
//!   time, reset outside the mask);
//! * direction `I^dir = atan2(I^flow)` ([`FrameGuides::dir`]).
//!
//! All lengths (distances, flow, extents) are in pixels of the sequence the guides were
//! computed on; [`FrameGuides::downsample2`] keeps them in those full-resolution units.

use crate::img::{Mask, Plane};
use glam::Vec2;

/// Parameters of guide computation.
#[derive(Clone, Debug, PartialEq)]
pub struct GuideParams {
    /// σ of the Gaussian blur applied to masks before thresholding (`--blur-sigma`), pixels.
    /// Default: 8 (thesis).
    pub blur_sigma: f32,
    /// Threshold applied to the blurred mask; below 0.5 so the mask takes in a little paper.
    /// Default: 0.3.
    pub mask_threshold: f32,
    /// σ of the temporal Gaussian applied to distance fields before the flow is estimated
    /// (`--time-blur-sigma`), frames. Default: 2 (thesis).
    pub time_blur_sigma: f32,
    /// Radius, in frames, of the temporal Gaussian applied to the flow sequence. Default: 3
    /// (paper, Appendix A).
    pub flow_time_radius: usize,
}

impl Default for GuideParams {
    fn default() -> Self {
        GuideParams { blur_sigma: 8.0, mask_threshold: 0.3, time_blur_sigma: 2.0, flow_time_radius: 3 }
    }
}

/// The guidance channels of one frame.
#[derive(Clone, Debug)]
pub struct FrameGuides {
    /// The pre-processed binary mask `I^mask`.
    pub mask: Mask,
    /// Signed distance to the mask boundary `I^dist`, positive inside, pixels.
    pub dist: Plane<f32>,
    /// Flow field `I^flow` between this frame and the next, pixels per frame.
    pub flow: Plane<Vec2>,
    /// Forward motion extent `I^ext+`, pixels.
    pub ext_pos: Plane<f32>,
    /// Backward motion extent `I^ext−`, pixels.
    pub ext_neg: Plane<f32>,
}

// TEMPORARY stand-ins until the guide module lands (replaced at merge).
impl FrameGuides {
    /// Half-resolution guides (placeholder).
    pub fn downsample2(&self) -> FrameGuides {
        let mask = crate::img::downsample2(&self.mask.to_coverage()).threshold(0.5);
        FrameGuides {
            mask,
            dist: crate::img::downsample2(&self.dist),
            flow: crate::img::downsample2(&self.flow),
            ext_pos: crate::img::downsample2(&self.ext_pos),
            ext_neg: crate::img::downsample2(&self.ext_neg),
        }
    }
}

/// Placeholder.
pub fn compute_sequence(_masks: &[Plane<f32>], _p: &GuideParams) -> crate::error::Result<Vec<FrameGuides>> {
    Err(crate::error::Error::Cancelled)
}
