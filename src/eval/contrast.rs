//! Local contrast: the mean standard deviation of luma in 7×7 windows (wash-out detector).

use super::{Mean, Measure, luma};
use crate::img::{Mask, Plane, Rgb};
use rayon::prelude::*;

/// Side of the square window of [`local_contrast`].
pub const CONTRAST_WINDOW: usize = 7;

/// Mean local contrast of `img` over the pixels of `region`.
///
/// For every pixel `p` of `region` whose 7×7 window lies inside the image, the population
/// standard deviation of the luma ([`luma`]) of the 49 window pixels; the result is the mean
/// of these over `region`. Luma rather than per-channel values because the texture a viewer
/// sees is mostly a variation of lightness, and a single-pigment exemplar varies along one
/// color axis anyway. Pass an interior mask (e.g. [`super::Shape::interior`] with a margin of
/// at least 4.3 px) so that windows do not straddle the boundary of the paint.
///
/// A flat fill scores 0; values are in luma units (`0..=0.5`). `None` when no pixel of
/// `region` qualifies.
pub fn local_contrast(img: &Plane<Rgb>, region: &Mask) -> Option<f32> {
    local_contrast_mean(img, region).value()
}

/// [`local_contrast`] of a sequence: per frame, and pooled over all qualifying pixels of all
/// frames (`regions[i]` belongs to `frames[i]`).
pub fn local_contrast_seq(frames: &[Plane<Rgb>], regions: &[Mask]) -> Measure {
    let means: Vec<Mean> = frames.par_iter().zip(regions).map(|(f, r)| local_contrast_mean(f, r)).collect();
    Measure::from_means(&means)
}

/// Sum and count behind [`local_contrast`], for pooling over frames.
pub(crate) fn local_contrast_mean(img: &Plane<Rgb>, region: &Mask) -> Mean {
    local_contrast_binned(img, region, 1, |_, _| 0).into_iter().fold(Mean::default(), Mean::merged)
}

/// [`local_contrast_mean`] split by `bin(x, y)` (`0..bins`) of each qualifying pixel.
pub(crate) fn local_contrast_binned(
    img: &Plane<Rgb>,
    region: &Mask,
    bins: usize,
    bin: impl Fn(usize, usize) -> usize + Sync,
) -> Vec<Mean> {
    let (w, h) = img.size();
    let r = CONTRAST_WINDOW / 2;
    if w < CONTRAST_WINDOW || h < CONTRAST_WINDOW || region.size() != img.size() {
        return vec![Mean::default(); bins];
    }
    // Summed-area tables of luma and luma² (f64: no cancellation trouble in var = E[y²] − E[y]²).
    let stride = w + 1;
    let mut s1 = vec![0f64; stride * (h + 1)];
    let mut s2 = vec![0f64; stride * (h + 1)];
    for y in 0..h {
        let (mut row1, mut row2) = (0f64, 0f64);
        for (x, &c) in img.row(y).iter().enumerate() {
            let v = luma(c) as f64;
            row1 += v;
            row2 += v * v;
            s1[(y + 1) * stride + x + 1] = s1[y * stride + x + 1] + row1;
            s2[(y + 1) * stride + x + 1] = s2[y * stride + x + 1] + row2;
        }
    }
    let n = (CONTRAST_WINDOW * CONTRAST_WINDOW) as f64;
    let box_sum = |s: &[f64], x0: usize, y0: usize| {
        let (x1, y1) = (x0 + CONTRAST_WINDOW, y0 + CONTRAST_WINDOW);
        s[y1 * stride + x1] - s[y0 * stride + x1] - s[y1 * stride + x0] + s[y0 * stride + x0]
    };
    (r..h - r)
        .into_par_iter()
        .map(|y| {
            let mut m = vec![Mean::default(); bins];
            for x in r..w - r {
                if region.get(x, y) {
                    let mean = box_sum(&s1, x - r, y - r) / n;
                    let var = (box_sum(&s2, x - r, y - r) / n - mean * mean).max(0.0);
                    m[bin(x, y).min(bins - 1)].add(var.sqrt());
                }
            }
            m
        })
        .collect::<Vec<_>>()
        // Summed in row order: the same result whatever the thread count.
        .into_iter()
        .fold(vec![Mean::default(); bins], |acc, m| acc.into_iter().zip(m).map(|(a, b)| a.merged(b)).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_is_zero_and_checkerboard_is_half() {
        let region = Plane::filled(20, 20, true);
        let flat = Plane::filled(20, 20, [0.3f32, 0.6, 0.1]);
        assert!(local_contrast(&flat, &region).unwrap() < 1e-6);
        // Alternating black/white: a 7×7 window holds 24 or 25 of one kind → std ≈ 0.4996.
        let checker = Plane::from_fn(20, 20, |x, y| if (x + y) % 2 == 0 { [1.0f32; 3] } else { [0.0; 3] });
        let c = local_contrast(&checker, &region).unwrap();
        let expected = ((24.0f64 * 25.0) / (49.0 * 49.0)).sqrt() as f32;
        assert!((c - expected).abs() < 1e-5, "{c} vs {expected}");
        // Windows leaving the image do not count; an empty region gives None.
        assert!(local_contrast(&checker, &Plane::filled(20, 20, false)).is_none());
        let edge_only = Plane::from_fn(20, 20, |x, _| x < 3);
        assert!(local_contrast(&checker, &edge_only).is_none());
    }
}
