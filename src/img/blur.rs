//! Separable Gaussian blur with clamped edges.

use super::{Blend, Mask, Plane};
use rayon::prelude::*;

/// A normalized 1D Gaussian kernel of standard deviation `sigma`, radius `⌈3σ⌉`.
/// `sigma <= 0` gives the identity kernel `[1]`.
pub fn gaussian_kernel(sigma: f32) -> Vec<f32> {
    if sigma <= 0.0 || !sigma.is_finite() {
        return vec![1.0];
    }
    let radius = (3.0 * sigma).ceil() as usize;
    let mut k: Vec<f32> =
        (0..=2 * radius).map(|i| (-((i as f32 - radius as f32).powi(2)) / (2.0 * sigma * sigma)).exp()).collect();
    let sum: f32 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= sum);
    k
}

/// Gaussian blur of standard deviation `sigma` pixels (edges clamped).
pub fn gaussian_blur<T: Blend>(src: &Plane<T>, sigma: f32) -> Plane<T> {
    let k = gaussian_kernel(sigma);
    if k.len() == 1 || src.is_empty() {
        return src.clone();
    }
    let r = (k.len() / 2) as isize;
    let (w, h) = src.size();
    // Horizontal pass.
    let mut tmp: Plane<T> = Plane::new(w, h);
    tmp.data_mut().par_chunks_mut(w).enumerate().for_each(|(y, out)| {
        let row = src.row(y);
        for (x, o) in out.iter_mut().enumerate() {
            let mut acc = T::default();
            for (i, &kv) in k.iter().enumerate() {
                let sx = (x as isize + i as isize - r).clamp(0, w as isize - 1) as usize;
                acc = acc.add_scaled(row[sx], kv);
            }
            *o = acc;
        }
    });
    // Vertical pass.
    let mut dst: Plane<T> = Plane::new(w, h);
    dst.data_mut().par_chunks_mut(w).enumerate().for_each(|(y, out)| {
        for (i, &kv) in k.iter().enumerate() {
            let sy = (y as isize + i as isize - r).clamp(0, h as isize - 1) as usize;
            let row = tmp.row(sy);
            for (o, &v) in out.iter_mut().zip(row) {
                *o = o.add_scaled(v, kv);
            }
        }
    });
    dst
}

/// The Gaussian blur (σ `sigma`) of `f` over the pixels where `mask` equals `side`, normalized
/// by their share of the kernel, so that nothing from the other side of the mask's edge is
/// mixed in (up to three lanes). Only that side's bounding box and the kernel's reach around it
/// are blurred; the result is zero on the other side.
pub fn blur_within<const N: usize>(
    mask: &Mask,
    side: bool,
    sigma: f32,
    f: &dyn Fn(usize, usize) -> [f32; N],
) -> Plane<[f32; N]> {
    const { assert!(N <= 3) };
    let (w, h) = mask.size();
    let mut out = Plane::filled(w, h, [0.0f32; N]);
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
    for y in 0..h {
        for x in (0..w).filter(|&x| mask.get(x, y) == side) {
            (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x + 1), y1.max(y + 1));
        }
    }
    if x0 >= x1 {
        return out;
    }
    let reach = gaussian_kernel(sigma).len() / 2;
    let (x0, y0) = (x0.saturating_sub(reach), y0.saturating_sub(reach));
    let (x1, y1) = ((x1 + reach).min(w), (y1 + reach).min(h));
    let lanes = Plane::from_fn(x1 - x0, y1 - y0, |x, y| {
        let (x, y) = (x + x0, y + y0);
        if mask.get(x, y) == side {
            let v = f(x, y);
            std::array::from_fn::<f32, 4, _>(|k| {
                if k < N {
                    v[k]
                } else if k == 3 {
                    1.0
                } else {
                    0.0
                }
            })
        } else {
            [0.0; 4]
        }
    });
    let blurred = gaussian_blur(&lanes, sigma);
    for y in y0..y1 {
        for x in (x0..x1).filter(|&x| mask.get(x, y) == side) {
            let v = blurred.get(x - x0, y - y0);
            let n = v[3].max(1e-6);
            out.set(x, y, std::array::from_fn(|k| v[k] / n));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernel_is_normalized_and_symmetric() {
        let k = gaussian_kernel(2.0);
        assert_eq!(k.len(), 13);
        assert!((k.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        assert!((k[0] - k[12]).abs() < 1e-7);
    }

    #[test]
    fn blur_preserves_constant_and_mass() {
        let p = Plane::filled(20, 10, 0.5f32);
        let b = gaussian_blur(&p, 3.0);
        assert!(b.data().iter().all(|&v| (v - 0.5).abs() < 1e-5));
        let mut d = Plane::new(41, 41);
        d.set(20, 20, 1.0f32);
        let b = gaussian_blur(&d, 2.0);
        let sum: f32 = b.data().iter().sum();
        assert!((sum - 1.0).abs() < 1e-4);
        assert!(b.get(20, 20) > b.get(22, 20));
    }
}
