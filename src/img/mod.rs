//! Small, boring image types: planar images of any pixel type, masks, Gaussian blur,
//! bilinear sampling, resampling, and PNG input/output with atomic writes.
//!
//! Colors are stored as `[f32; 3]` / `[f32; 4]` in non-linear sRGB scaled to `0..=1`
//! (what PNG files hold); alpha is straight (not premultiplied) unless a function says
//! otherwise.

mod blur;
mod io;
mod resample;

pub use blur::{blur_within, gaussian_blur, gaussian_kernel};
pub use io::{
    MAX_IMAGE_SIDE, atomic_write, decode, load_gray, load_rgb, load_rgba, save_gray, save_mask, save_rgb, save_rgba,
    write_png_rgba8,
};
pub use resample::{downsample2, resize_bilinear, sample_bilinear};

/// An RGB color, sRGB components in `0..=1`.
pub type Rgb = [f32; 3];
/// An RGBA color, sRGB components and straight alpha in `0..=1`.
pub type Rgba = [f32; 4];

/// A rectangular image with one value of type `T` per pixel, stored row by row.
#[derive(Clone, Debug, PartialEq)]
pub struct Plane<T> {
    width: usize,
    height: usize,
    data: Vec<T>,
}

/// A binary mask: `true` where the medium (paint) is present.
pub type Mask = Plane<bool>;

/// A pixel rectangle `[x0, x1) × [y0, y1)`; empty when either side is empty.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Rect {
    /// First column.
    pub x0: usize,
    /// First row.
    pub y0: usize,
    /// One past the last column.
    pub x1: usize,
    /// One past the last row.
    pub y1: usize,
}

impl Rect {
    /// The whole `w × h` image.
    pub fn full(w: usize, h: usize) -> Self {
        Rect { x0: 0, y0: 0, x1: w, y1: h }
    }

    /// True when the rectangle holds no pixel.
    pub fn is_empty(&self) -> bool {
        self.x1 <= self.x0 || self.y1 <= self.y0
    }

    /// Number of columns.
    pub fn width(&self) -> usize {
        self.x1.saturating_sub(self.x0)
    }

    /// Number of rows.
    pub fn height(&self) -> usize {
        self.y1.saturating_sub(self.y0)
    }

    /// The smallest rectangle holding both.
    pub fn union(self, o: Rect) -> Rect {
        if self.is_empty() {
            o
        } else if o.is_empty() {
            self
        } else {
            Rect { x0: self.x0.min(o.x0), y0: self.y0.min(o.y0), x1: self.x1.max(o.x1), y1: self.y1.max(o.y1) }
        }
    }

    /// Grown by `m` pixels on every side, clipped to a `w × h` image.
    pub fn expand(self, m: usize, w: usize, h: usize) -> Rect {
        if self.is_empty() {
            return self;
        }
        Rect {
            x0: self.x0.saturating_sub(m),
            y0: self.y0.saturating_sub(m),
            x1: (self.x1 + m).min(w),
            y1: (self.y1 + m).min(h),
        }
    }

    /// Moved by `(dx, dy)`.
    pub fn offset(self, dx: usize, dy: usize) -> Rect {
        Rect { x0: self.x0 + dx, y0: self.y0 + dy, x1: self.x1 + dx, y1: self.y1 + dy }
    }

    /// True when pixel `(x, y)` lies inside.
    #[inline]
    pub fn contains(&self, x: usize, y: usize) -> bool {
        x >= self.x0 && x < self.x1 && y >= self.y0 && y < self.y1
    }
}

/// Calls `f` with the row-major index of each 4-connected neighbour of pixel `i` in a
/// `w`-wide, `h`-high image: left, right, up, down (those inside the image).
#[inline]
pub(crate) fn for_each_neighbour4(i: usize, w: usize, h: usize, mut f: impl FnMut(usize)) {
    let (x, y) = (i % w, i / w);
    if x > 0 {
        f(i - 1);
    }
    if x + 1 < w {
        f(i + 1);
    }
    if y > 0 {
        f(i - w);
    }
    if y + 1 < h {
        f(i + w);
    }
}

/// The 4-connected components of the pixels of `m` equal to `value`, each with whether it
/// touches the frame edge.
pub(crate) fn components(m: &[bool], w: usize, h: usize, value: bool) -> impl Iterator<Item = (Vec<usize>, bool)> + '_ {
    let mut seen = vec![false; w * h];
    (0..w * h).filter_map(move |start| {
        if seen[start] || m[start] != value {
            return None;
        }
        let mut comp = vec![start];
        seen[start] = true;
        let mut head = 0;
        let mut touches_edge = false;
        while head < comp.len() {
            let i = comp[head];
            head += 1;
            let (x, y) = (i % w, i / w);
            touches_edge |= x == 0 || y == 0 || x == w - 1 || y == h - 1;
            for_each_neighbour4(i, w, h, |j| {
                if !seen[j] && m[j] == value {
                    seen[j] = true;
                    comp.push(j);
                }
            });
        }
        Some((comp, touches_edge))
    })
}

impl<T: Copy + Default> Plane<T> {
    /// A `width × height` plane filled with `T::default()`.
    pub fn new(width: usize, height: usize) -> Self {
        Self::filled(width, height, T::default())
    }
}

impl<T: Copy> Plane<T> {
    /// A `width × height` plane filled with `value`.
    pub fn filled(width: usize, height: usize, value: T) -> Self {
        Plane { width, height, data: vec![value; width * height] }
    }

    /// Builds a plane from a function of the pixel coordinates.
    pub fn from_fn(width: usize, height: usize, mut f: impl FnMut(usize, usize) -> T) -> Self {
        let mut data = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                data.push(f(x, y));
            }
        }
        Plane { width, height, data }
    }

    /// [`Plane::from_fn`] with the rows computed in parallel (`f` must not depend on the order).
    pub fn par_from_fn(width: usize, height: usize, f: impl Fn(usize, usize) -> T + Sync) -> Self
    where
        T: Send + Sync + Default,
    {
        use rayon::prelude::*;
        let mut data = vec![T::default(); width * height];
        data.par_chunks_mut(width.max(1)).enumerate().for_each(|(y, row)| {
            for (x, v) in row.iter_mut().enumerate() {
                *v = f(x, y);
            }
        });
        Plane { width, height, data }
    }

    /// Wraps row-major `data`; `None` if its length is not `width * height`.
    pub fn from_vec(width: usize, height: usize, data: Vec<T>) -> Option<Self> {
        (data.len() == width * height).then_some(Plane { width, height, data })
    }

    /// Width in pixels.
    #[inline]
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    #[inline]
    pub fn height(&self) -> usize {
        self.height
    }

    /// `(width, height)`.
    #[inline]
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// Number of pixels.
    #[inline]
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// True for a plane without pixels.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// The value at `(x, y)`; panics when out of bounds.
    #[inline]
    pub fn get(&self, x: usize, y: usize) -> T {
        self.data[y * self.width + x]
    }

    /// The value at `(x, y)` with coordinates clamped into the plane.
    #[inline]
    pub fn get_clamped(&self, x: isize, y: isize) -> T {
        let x = x.clamp(0, self.width as isize - 1) as usize;
        let y = y.clamp(0, self.height as isize - 1) as usize;
        self.data[y * self.width + x]
    }

    /// Sets the value at `(x, y)`.
    #[inline]
    pub fn set(&mut self, x: usize, y: usize, value: T) {
        self.data[y * self.width + x] = value;
    }

    /// Mutable access to the value at `(x, y)`.
    #[inline]
    pub fn at_mut(&mut self, x: usize, y: usize) -> &mut T {
        &mut self.data[y * self.width + x]
    }

    /// Row `y`.
    #[inline]
    pub fn row(&self, y: usize) -> &[T] {
        &self.data[y * self.width..(y + 1) * self.width]
    }

    /// Row `y`, mutable.
    #[inline]
    pub fn row_mut(&mut self, y: usize) -> &mut [T] {
        &mut self.data[y * self.width..(y + 1) * self.width]
    }

    /// All pixels, row-major.
    #[inline]
    pub fn data(&self) -> &[T] {
        &self.data
    }

    /// All pixels, row-major, mutable.
    #[inline]
    pub fn data_mut(&mut self) -> &mut [T] {
        &mut self.data
    }

    /// Consumes the plane, returning its pixels.
    pub fn into_vec(self) -> Vec<T> {
        self.data
    }

    /// A new plane with `f` applied to every pixel.
    pub fn map<U: Copy>(&self, f: impl FnMut(T) -> U) -> Plane<U> {
        Plane { width: self.width, height: self.height, data: self.data.iter().copied().map(f).collect() }
    }

    /// The `w × h` window whose top-left pixel is `(x0, y0)`; parts outside the plane are
    /// `fill`.
    pub fn crop(&self, x0: usize, y0: usize, w: usize, h: usize, fill: T) -> Plane<T> {
        Plane::from_fn(w, h, |x, y| {
            let (sx, sy) = (x0 + x, y0 + y);
            if sx < self.width && sy < self.height { self.data[sy * self.width + sx] } else { fill }
        })
    }

    /// The bounding box of the pixels where `inside` holds; `None` when there are none.
    pub fn bounds(&self, mut inside: impl FnMut(&T) -> bool) -> Option<Rect> {
        let mut b: Option<Rect> = None;
        for y in 0..self.height {
            let row = self.row(y);
            if let Some(first) = row.iter().position(&mut inside) {
                let last = row.iter().rposition(&mut inside).unwrap_or(first);
                let r = Rect { x0: first, y0: y, x1: last + 1, y1: y + 1 };
                b = Some(b.map_or(r, |b| b.union(r)));
            }
        }
        b
    }

    /// True when `(x, y)` (signed) lies inside the plane.
    #[inline]
    pub fn contains(&self, x: isize, y: isize) -> bool {
        x >= 0 && y >= 0 && (x as usize) < self.width && (y as usize) < self.height
    }
}

impl Plane<bool> {
    /// Number of `true` pixels (`|I|` in the papers).
    pub fn count(&self) -> usize {
        self.data.iter().filter(|&&b| b).count()
    }

    /// The bounding box of the `true` pixels; `None` for an empty mask.
    pub fn bounding_box(&self) -> Option<Rect> {
        self.bounds(|&b| b)
    }

    /// The mask as a coverage plane (1 inside, 0 outside).
    pub fn to_coverage(&self) -> Plane<f32> {
        self.map(|b| if b { 1.0 } else { 0.0 })
    }
}

impl Plane<f32> {
    /// Pixels with value `>= threshold` become `true`.
    pub fn threshold(&self, threshold: f32) -> Mask {
        self.map(|v| v >= threshold)
    }
}

/// Pixel types that can be blended linearly (blur, bilinear sampling, voting).
pub trait Blend: Copy + Default + Send + Sync {
    /// `self + other * w`.
    fn add_scaled(self, other: Self, w: f32) -> Self;
    /// `self * w`.
    fn scale(self, w: f32) -> Self;
}

impl Blend for f32 {
    #[inline]
    fn add_scaled(self, other: Self, w: f32) -> Self {
        self + other * w
    }
    #[inline]
    fn scale(self, w: f32) -> Self {
        self * w
    }
}

impl<const N: usize> Blend for [f32; N]
where
    [f32; N]: Default,
{
    #[inline]
    fn add_scaled(mut self, other: Self, w: f32) -> Self {
        for i in 0..N {
            self[i] += other[i] * w;
        }
        self
    }
    #[inline]
    fn scale(mut self, w: f32) -> Self {
        for v in &mut self {
            *v *= w;
        }
        self
    }
}

impl Blend for glam::Vec2 {
    #[inline]
    fn add_scaled(self, other: Self, w: f32) -> Self {
        self + other * w
    }
    #[inline]
    fn scale(self, w: f32) -> Self {
        self * w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_basics() {
        let p = Plane::from_fn(3, 2, |x, y| (x + 10 * y) as f32);
        assert_eq!(p.get(2, 1), 12.0);
        assert_eq!(p.row(1), &[10.0, 11.0, 12.0]);
        assert_eq!(p.get_clamped(-5, 9), 10.0);
        assert!(Plane::from_vec(2, 2, vec![0u8; 3]).is_none());
        let m = p.threshold(11.0);
        assert_eq!(m.count(), 2);
    }

    #[test]
    fn bounding_boxes() {
        let m = Plane::from_fn(8, 9, |x, y| (2..5).contains(&x) && (3..7).contains(&y) && (x + y) % 2 == 0);
        assert_eq!(m.bounding_box(), Some(Rect { x0: 2, y0: 3, x1: 5, y1: 7 }));
        assert_eq!(Plane::filled(4, 4, false).bounding_box(), None);
        assert_eq!(Plane::filled(3, 2, true).bounding_box(), Some(Rect::full(3, 2)));
        assert_eq!(Plane::<bool>::new(0, 3).bounding_box(), None);
        let mut one = Plane::filled(5, 1, false);
        one.set(4, 0, true);
        assert_eq!(one.bounding_box(), Some(Rect { x0: 4, y0: 0, x1: 5, y1: 1 }));
        let p = Plane::from_fn(6, 4, |x, y| if x == 1 && y == 2 || x == 4 && y == 0 { 0.5f32 } else { 0.0 });
        assert_eq!(p.bounds(|&v| v != 0.0), Some(Rect { x0: 1, y0: 0, x1: 5, y1: 3 }));
    }
}
