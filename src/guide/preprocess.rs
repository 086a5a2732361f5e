//! Mask pre-processing (thesis §4.1, Fig. 4.1): a Gaussian blur of the coverage with
//! σ = `blur_sigma`, then a threshold below 0.5, so masks have smooth edges and take in a little
//! of the unpainted paper around the paint. The covered pixels themselves (coverage ≥ ½) always
//! stay in the mask: the blur alone erases parts narrower than about σ (a dot, the tip of a
//! limb, the first drop of an exemplar), and what the animation covers must be painted.
//!
//! The blur only runs inside the bounding box of the non-zero coverage grown by the kernel
//! radius; the result is bit-for-bit the same as [`crate::img::gaussian_blur`] on the whole
//! image followed by [`Plane::threshold`].

use super::GuideParams;
use super::crop::{Crop, FrameMask, Rect};
use crate::img::{Mask, Plane, gaussian_kernel};
use rayon::prelude::*;

/// Blurs `coverage` (σ = `params.blur_sigma`, edges clamped) and keeps the pixels whose blurred
/// value is at least `params.mask_threshold`, and the covered pixels (coverage ≥ ½): the
/// pre-processed mask `I^mask`.
pub fn preprocess_mask(coverage: &Plane<f32>, params: &GuideParams) -> Mask {
    let (w, h) = coverage.size();
    blurred_threshold(coverage, params.blur_sigma, params.mask_threshold).to_full(w, h)
}

/// [`preprocess_mask`] as a [`FrameMask`].
pub(crate) fn preprocess_frame(coverage: &Plane<f32>, params: &GuideParams) -> FrameMask {
    let (w, h) = coverage.size();
    FrameMask::from_crop(w, h, &blurred_threshold(coverage, params.blur_sigma, params.mask_threshold))
}

/// The thresholded blur over the only rectangle where it can be non-zero.
fn blurred_threshold(cov: &Plane<f32>, sigma: f32, threshold: f32) -> Crop<bool> {
    let (w, h) = cov.size();
    let k = gaussian_kernel(sigma);
    let r = k.len() / 2;
    // Bounding box of the non-zero coverage.
    let bb = cov.bounds(|&v| v != 0.0).unwrap_or_default();
    if bb.is_empty() || threshold <= 0.0 {
        // Nothing covered (or a threshold every pixel passes): no blur needed.
        let rect = Rect::full(w, h);
        return Crop { rect, plane: Plane::filled(w, h, threshold <= 0.0) };
    }
    let out = bb.expand(r, w, h);
    let (ow, oh) = (out.width(), out.height());
    // Horizontal pass over the rows the vertical pass reads: taps in order, like img::gaussian_blur.
    let ty0 = out.y0.saturating_sub(r);
    let ty1 = (out.y1 + r).min(h);
    let mut tmp = vec![0f32; ow * (ty1 - ty0)];
    tmp.par_chunks_mut(ow).enumerate().for_each_init(
        || vec![0f32; ow + 2 * r],
        |pad, (i, trow)| {
            let src = cov.row(ty0 + i);
            for (j, p) in pad.iter_mut().enumerate() {
                let sx = (out.x0 + j) as isize - r as isize;
                *p = src[sx.clamp(0, w as isize - 1) as usize];
            }
            for (t, &kv) in k.iter().enumerate() {
                for (o, &v) in trow.iter_mut().zip(&pad[t..t + ow]) {
                    *o += v * kv;
                }
            }
        },
    );
    // Vertical pass, then the threshold.
    let mut mask = Plane::new(ow, oh);
    mask.data_mut().par_chunks_mut(ow).enumerate().for_each_init(
        || vec![0f32; ow],
        |acc, (i, mrow)| {
            acc.iter_mut().for_each(|v| *v = 0.0);
            let y = out.y0 + i;
            for (t, &kv) in k.iter().enumerate() {
                let sy = (y as isize + t as isize - r as isize).clamp(0, h as isize - 1) as usize - ty0;
                for (o, &v) in acc.iter_mut().zip(&tmp[sy * ow..(sy + 1) * ow]) {
                    *o += v * kv;
                }
            }
            let raw = &cov.row(y)[out.x0..out.x1];
            for ((m, &v), &c) in mrow.iter_mut().zip(acc.iter()).zip(raw) {
                *m = v >= threshold || c >= 0.5;
            }
        },
    );
    Crop { rect: out, plane: mask }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::img::gaussian_blur;

    #[test]
    fn same_as_full_blur_then_threshold() {
        let cov = Plane::from_fn(90, 70, |x, y| {
            let (dx, dy) = (x as f32 - 60.0, y as f32 - 20.0);
            if dx * dx + 2.0 * dy * dy < 150.0 || (x == 3 && y == 66) { 1.0 } else { 0.0 }
        });
        for (sigma, thr) in [(8.0, 0.3), (2.5, 0.5), (0.0, 0.3), (3.0, 0.05)] {
            let p = GuideParams { blur_sigma: sigma, mask_threshold: thr, ..Default::default() };
            let blurred = gaussian_blur(&cov, sigma).threshold(thr);
            let expected = Plane::from_fn(90, 70, |x, y| blurred.get(x, y) || cov.get(x, y) >= 0.5);
            assert_eq!(preprocess_mask(&cov, &p), expected, "sigma {sigma} threshold {thr}");
        }
        let empty = Plane::new(10, 10);
        assert_eq!(preprocess_mask(&empty, &GuideParams::default()).count(), 0);
    }

    #[test]
    fn small_parts_survive_the_blur() {
        // A 3-pixel dot vanishes in a σ = 8 blur (its peak is far below 0.3), but stays painted.
        let cov = Plane::from_fn(40, 40, |x, y| if (19..22).contains(&x) && (19..22).contains(&y) { 1.0 } else { 0.0 });
        let p = GuideParams { blur_sigma: 8.0, ..GuideParams::default() };
        assert!(gaussian_blur(&cov, p.blur_sigma).threshold(p.mask_threshold).count() == 0);
        assert_eq!(preprocess_mask(&cov, &p).count(), 9);
    }

    #[test]
    fn threshold_below_half_grows_the_mask() {
        let cov = Plane::from_fn(60, 60, |x, y| if (20..40).contains(&x) && (20..40).contains(&y) { 1.0 } else { 0.0 });
        let m = preprocess_mask(&cov, &GuideParams { blur_sigma: 8.0, ..GuideParams::default() });
        assert!(m.count() > 400);
        assert!(m.get(19, 30) && !m.get(30, 30 - 20));
    }
}
