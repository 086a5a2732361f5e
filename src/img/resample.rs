//! Bilinear sampling and resizing.

use super::{Blend, Plane};

/// Samples `p` at the continuous position `(x, y)`, where pixel centers sit at integer
/// coordinates; positions outside are clamped to the border.
#[inline]
pub fn sample_bilinear<T: Blend>(p: &Plane<T>, x: f32, y: f32) -> T {
    let (w, h) = p.size();
    let x = x.clamp(0.0, (w - 1) as f32);
    let y = y.clamp(0.0, (h - 1) as f32);
    let x0 = x.floor() as usize;
    let y0 = y.floor() as usize;
    let x1 = (x0 + 1).min(w - 1);
    let y1 = (y0 + 1).min(h - 1);
    let fx = x - x0 as f32;
    let fy = y - y0 as f32;
    let top = p.get(x0, y0).scale(1.0 - fx).add_scaled(p.get(x1, y0), fx);
    let bot = p.get(x0, y1).scale(1.0 - fx).add_scaled(p.get(x1, y1), fx);
    top.scale(1.0 - fy).add_scaled(bot, fy)
}

/// Resizes `p` to `width × height`. Shrinking by more than 2× pre-blurs to avoid aliasing.
pub fn resize_bilinear<T: Blend>(p: &Plane<T>, width: usize, height: usize) -> Plane<T> {
    if p.size() == (width, height) {
        return p.clone();
    }
    let sx = p.width() as f32 / width as f32;
    let sy = p.height() as f32 / height as f32;
    let shrink = sx.max(sy);
    let blurred;
    let src = if shrink > 2.0 {
        blurred = super::gaussian_blur(p, 0.5 * (shrink * shrink - 1.0).sqrt());
        &blurred
    } else {
        p
    };
    Plane::from_fn(width, height, |x, y| sample_bilinear(src, (x as f32 + 0.5) * sx - 0.5, (y as f32 + 0.5) * sy - 0.5))
}

/// Halves a plane by averaging 2×2 blocks (the size rounds up; odd edges are clamped).
/// This is one step of the synthesis pyramid: pixel `(x, y)` of the result covers pixels
/// `(2x..2x+2, 2y..2y+2)` of the input.
pub fn downsample2<T: Blend>(p: &Plane<T>) -> Plane<T> {
    let (w, h) = p.size();
    let (w2, h2) = (w.div_ceil(2), h.div_ceil(2));
    Plane::from_fn(w2, h2, |x, y| {
        let x0 = 2 * x;
        let y0 = 2 * y;
        let x1 = (x0 + 1).min(w - 1);
        let y1 = (y0 + 1).min(h - 1);
        p.get(x0, y0)
            .add_scaled(p.get(x1, y0), 1.0)
            .add_scaled(p.get(x0, y1), 1.0)
            .add_scaled(p.get(x1, y1), 1.0)
            .scale(0.25)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_interpolates_linear_ramps_exactly() {
        let p = Plane::from_fn(8, 8, |x, y| x as f32 * 2.0 + y as f32);
        let v = sample_bilinear(&p, 2.25, 3.5);
        assert!((v - (4.5 + 3.5)).abs() < 1e-5);
    }

    #[test]
    fn downsample_halves_and_averages() {
        let p = Plane::from_fn(5, 4, |x, _| x as f32);
        let d = downsample2(&p);
        assert_eq!(d.size(), (3, 2));
        assert!((d.get(0, 0) - 0.5).abs() < 1e-6);
        assert!((d.get(2, 1) - 4.0).abs() < 1e-6);
    }

    #[test]
    fn resize_keeps_constant() {
        let p = Plane::filled(10, 6, [0.2f32, 0.4, 0.6]);
        let r = resize_bilinear(&p, 33, 2);
        assert!(r.data().iter().all(|c| (c[1] - 0.4).abs() < 1e-5));
    }
}
