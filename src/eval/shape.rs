//! Mask geometry shared by the metrics: the thresholded mask and its exact signed distance.

use crate::img::{Mask, Plane};
use rayon::prelude::*;

/// Coverage at or above this value counts as inside a mask.
pub const MASK_THRESHOLD: f32 = 0.5;

/// A binary mask together with its signed distance field.
///
/// The signed distance is in pixels, **positive inside**, with the boundary half-way between
/// an inside and an outside pixel: an inside pixel next to an outside one has `+0.5`, that
/// outside pixel `−0.5`. It is computed exactly (Euclidean, by [`crate::guide::sdf()`]). The
/// image border is not a boundary: a mask covering the whole image has distance
/// `width + height` everywhere, an empty one `−(width + height)` (see [`signed_distance`]).
#[derive(Clone, Debug)]
pub struct Shape {
    /// The mask (`coverage >= 0.5`).
    pub mask: Mask,
    /// Signed distance to the mask boundary, pixels, positive inside.
    pub sdf: Plane<f32>,
}

impl Shape {
    /// Thresholds a coverage plane at [`MASK_THRESHOLD`] and computes its signed distance.
    pub fn from_coverage(coverage: &Plane<f32>) -> Shape {
        Shape::from_mask(coverage.threshold(MASK_THRESHOLD))
    }

    /// Computes the signed distance of a binary mask.
    pub fn from_mask(mask: Mask) -> Shape {
        let sdf = signed_distance(&mask);
        Shape { mask, sdf }
    }

    /// The shapes of a whole coverage sequence (computed in parallel).
    pub fn sequence(masks: &[Plane<f32>]) -> Vec<Shape> {
        masks.par_iter().map(Shape::from_coverage).collect()
    }

    /// The *interior*: pixels at least `margin` pixels inside the boundary (`sdf >= margin`).
    pub fn interior(&self, margin: f32) -> Mask {
        self.sdf.map(|d| d >= margin)
    }

    /// `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        self.mask.size()
    }
}

/// Exact signed Euclidean distance of a mask, as described on [`Shape`]: the guides' field
/// [`crate::guide::sdf()`], except for a mask without a boundary (empty, or covering the whole
/// image), where the metrics keep their own documented value `±(width + height)` instead of the
/// guides' `±`[`no_boundary_distance`](crate::guide::sdf::no_boundary_distance) (the image
/// diagonal). The metrics read that value (e.g. [`super::flow::target_motion`] takes
/// `sdf_next − sdf_prev` after an empty frame), so adapting it here keeps every report as it was.
pub fn signed_distance(mask: &Mask) -> Plane<f32> {
    let (w, h) = mask.size();
    let count = mask.count();
    if count == 0 || count == mask.len() {
        let cap = (w + h) as f32;
        return Plane::filled(w, h, if count == 0 { -cap } else { cap });
    }
    crate::guide::sdf(mask)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_and_empty_masks_are_capped() {
        let full = signed_distance(&Plane::filled(4, 3, true));
        assert!(full.data().iter().all(|&d| d == 7.0));
        let empty = signed_distance(&Plane::filled(4, 3, false));
        assert!(empty.data().iter().all(|&d| d == -7.0));
    }
}
