//! A small single-threaded separable Gaussian blur on flat `f32` buffers, with separate σ
//! along x and y (edges clamped). Single-threaded on purpose: the generator must give the
//! same bytes whatever the thread count, and its grids are small.

use crate::img::gaussian_kernel;

/// Blurs the row-major `w × h` buffer `src` with standard deviations `sx`, `sy`.
pub(crate) fn blur_xy(src: &[f32], w: usize, h: usize, sx: f32, sy: f32) -> Vec<f32> {
    let kx = gaussian_kernel(sx);
    let ky = gaussian_kernel(sy);
    let (rx, ry) = ((kx.len() / 2) as isize, (ky.len() / 2) as isize);
    let mut tmp = vec![0.0f32; w * h];
    for y in 0..h {
        let row = &src[y * w..(y + 1) * w];
        for x in 0..w {
            let mut acc = 0.0;
            for (i, &k) in kx.iter().enumerate() {
                let sx = (x as isize + i as isize - rx).clamp(0, w as isize - 1) as usize;
                acc += k * row[sx];
            }
            tmp[y * w + x] = acc;
        }
    }
    let mut out = vec![0.0f32; w * h];
    for y in 0..h {
        for (i, &k) in ky.iter().enumerate() {
            let sy = (y as isize + i as isize - ry).clamp(0, h as isize - 1) as usize;
            let (o, r) = (&mut out[y * w..(y + 1) * w], &tmp[sy * w..(sy + 1) * w]);
            for (o, &v) in o.iter_mut().zip(r) {
                *o += k * v;
            }
        }
    }
    out
}
