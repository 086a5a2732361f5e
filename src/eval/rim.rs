//! Edge darkening: how much darker the paint is just inside its edge than in its interior —
//! the dark rim of watercolor, the first thing a painter looks for.

use super::{Measure, Shape, luma};
use crate::img::{Plane, Rgb};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Default outer band of [`RimParams::band`]: pixels at most this far inside the edge.
pub const RIM_BAND: f32 = 4.0;
/// Default [`RimParams::interior`]: pixels farther than this inside the edge.
pub const RIM_INTERIOR: f32 = 12.0;
/// Default [`RimParams::min_pixels`].
pub const RIM_MIN_PIXELS: usize = 20;

/// Where [`edge_darkening`] compares the paint.
///
/// Distances are `d = sdf + ½` ([`Shape::sdf`] plus half a pixel): the Euclidean distance
/// from a pixel's center to the center of the nearest pixel outside the mask, so the pixels
/// touching the outside have `d = 1` (the convention of OpenCV's distance transform).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RimParams {
    /// The band: pixels with `0 < d <= band`. Default: [`RIM_BAND`] (4 px).
    pub band: f32,
    /// The interior: pixels with `d > interior`. Default: [`RIM_INTERIOR`] (12 px).
    pub interior: f32,
    /// A frame with fewer pixels than this in the band or in the interior has no value.
    /// Default: [`RIM_MIN_PIXELS`] (20).
    pub min_pixels: usize,
}

impl Default for RimParams {
    fn default() -> Self {
        RimParams { band: RIM_BAND, interior: RIM_INTERIOR, min_pixels: RIM_MIN_PIXELS }
    }
}

/// Edge darkening of one frame: `mean luma(interior) − mean luma(band)` over the regions of
/// [`RimParams`] of `shape` (luma = [`luma`]) — positive when the edge is darker than the
/// interior, negative when it is lighter, 0 for a flat fill. `None` when the band or the
/// interior has fewer than `params.min_pixels` pixels (a shape thinner than about
/// `2 · interior`).
pub fn edge_darkening(img: &Plane<Rgb>, shape: &Shape, params: &RimParams) -> Option<f32> {
    let (mut band, mut nb, mut inner, mut ni) = (0f64, 0usize, 0f64, 0usize);
    for (&c, &s) in img.data().iter().zip(shape.sdf.data()) {
        let d = s + 0.5;
        if d <= 0.0 {
            continue;
        }
        if d <= params.band {
            band += luma(c) as f64;
            nb += 1;
        } else if d > params.interior {
            inner += luma(c) as f64;
            ni += 1;
        }
    }
    let min = params.min_pixels.max(1);
    (nb >= min && ni >= min).then(|| (inner / ni as f64 - band / nb as f64) as f32)
}

/// [`edge_darkening`] of every frame (`shapes[i]` belongs to `frames[i]`); the sequence's
/// value is the **mean of the per-frame values** (frames without one are left out), so that
/// every frame weighs the same whatever its size; `samples` counts the frames with a value.
pub fn edge_darkening_seq(frames: &[Plane<Rgb>], shapes: &[Shape], params: &RimParams) -> Measure {
    let per_frame: Vec<Option<f32>> =
        frames.par_iter().zip(shapes).map(|(f, s)| edge_darkening(f, s, params)).collect();
    Measure::from_frame_values(per_frame)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dark_rim_light_rim_and_flat() {
        let disc = Shape::from_coverage(&Plane::from_fn(80, 80, |x, y| {
            let (dx, dy) = (x as f32 - 40.0, y as f32 - 40.0);
            if dx * dx + dy * dy < 900.0 { 1.0 } else { 0.0 }
        }));
        let p = RimParams::default();
        // Paint 0.3 darker within 4 px of the edge.
        let rim = Plane::from_fn(80, 80, |x, y| if disc.sdf.get(x, y) + 0.5 <= 4.0 { [0.4f32; 3] } else { [0.7; 3] });
        assert!((edge_darkening(&rim, &disc, &p).unwrap() - 0.3).abs() < 1e-5);
        let light = rim.map(|c| [1.1 - c[0]; 3]);
        assert!((edge_darkening(&light, &disc, &p).unwrap() + 0.3).abs() < 1e-5);
        assert_eq!(edge_darkening(&Plane::filled(80, 80, [0.5f32; 3]), &disc, &p), Some(0.0));
        // A disc too small for an interior has no value.
        let small = Shape::from_coverage(&Plane::from_fn(80, 80, |x, y| {
            let (dx, dy) = (x as f32 - 40.0, y as f32 - 40.0);
            if dx * dx + dy * dy < 100.0 { 1.0 } else { 0.0 }
        }));
        assert_eq!(edge_darkening(&rim, &small, &p), None);
    }
}
