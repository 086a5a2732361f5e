//! Rectangles, cropped planes and compact per-frame masks: the storage that lets guides be
//! computed inside a mask's bounding box and kept for many frames in little memory.

use crate::img::{Mask, Plane};
use rayon::prelude::*;

pub(crate) use crate::img::Rect;

/// A plane covering `rect` of a larger image; pixels outside `rect` hold `T::default()`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Crop<T> {
    pub rect: Rect,
    pub plane: Plane<T>,
}

impl<T: Copy + Default + Send + Sync> Crop<T> {
    /// A crop of `rect` filled with `T::default()`.
    pub fn new(rect: Rect) -> Self {
        Crop { rect, plane: Plane::new(rect.width(), rect.height()) }
    }

    /// The value at image position `(x, y)`, `T::default()` outside the rectangle.
    #[inline]
    pub fn get(&self, x: usize, y: usize) -> T {
        if self.rect.contains(x, y) { self.plane.get(x - self.rect.x0, y - self.rect.y0) } else { T::default() }
    }

    /// The crop as a full `w × h` plane.
    pub fn to_full(&self, w: usize, h: usize) -> Plane<T> {
        let mut out = Plane::new(w, h);
        let r = self.rect;
        if r.is_empty() {
            return out;
        }
        out.data_mut().par_chunks_mut(w.max(1)).enumerate().skip(r.y0).take(r.height()).for_each(|(y, row)| {
            row[r.x0..r.x1].copy_from_slice(self.plane.row(y - r.y0));
        });
        out
    }
}

/// One frame's pre-processed mask, stored in its bounding box, with its boundary pixels.
#[derive(Clone, Debug)]
pub(crate) struct FrameMask {
    /// Image size.
    pub w: usize,
    pub h: usize,
    /// The mask inside its bounding box (an empty rectangle for an empty mask).
    pub crop: Crop<bool>,
    /// Number of mask pixels.
    pub count: usize,
    /// Boundary pixels `B`: mask pixels with a 4-neighbour inside the image that is not in the mask,
    /// as linear image indices `y·w + x`, in scan order.
    pub boundary: Vec<u32>,
}

impl FrameMask {
    /// From a crop of any rectangle (values outside it are `false`); trims to the bounding box.
    pub fn from_crop(w: usize, h: usize, c: &Crop<bool>) -> Self {
        let bb = c.plane.bounding_box().map_or(Rect::default(), |b| b.offset(c.rect.x0, c.rect.y0));
        let count = c.plane.count();
        let crop = Crop::from_full_crop(c, bb);
        let mut m = FrameMask { w, h, crop, count, boundary: Vec::new() };
        m.boundary = m.find_boundary();
        m
    }

    /// From a full-size mask.
    pub fn from_full(mask: &Mask) -> Self {
        let (w, h) = mask.size();
        Self::from_crop(w, h, &Crop { rect: Rect::full(w, h), plane: mask.clone() })
    }

    /// True when the mask is empty or covers the whole image: it has no boundary and no flow.
    pub fn is_degenerate(&self) -> bool {
        self.count == 0 || self.count == self.w * self.h
    }

    #[inline]
    pub fn contains(&self, x: usize, y: usize) -> bool {
        self.crop.get(x, y)
    }

    /// The bounding box.
    pub fn rect(&self) -> Rect {
        self.crop.rect
    }

    /// The mask as a full plane.
    pub fn to_full(&self) -> Mask {
        self.crop.to_full(self.w, self.h)
    }

    /// The mask over `rect` (any rectangle of the image).
    pub fn crop_to(&self, rect: Rect) -> Plane<bool> {
        Plane::from_fn(rect.width(), rect.height(), |x, y| self.contains(x + rect.x0, y + rect.y0))
    }

    fn find_boundary(&self) -> Vec<u32> {
        let r = self.rect();
        let (w, h) = (self.w, self.h);
        let rows: Vec<Vec<u32>> = (r.y0..r.y1)
            .into_par_iter()
            .map(|y| {
                let mut v = Vec::new();
                for x in r.x0..r.x1 {
                    if !self.contains(x, y) {
                        continue;
                    }
                    let out = (x > 0 && !self.contains(x - 1, y))
                        || (x + 1 < w && !self.contains(x + 1, y))
                        || (y > 0 && !self.contains(x, y - 1))
                        || (y + 1 < h && !self.contains(x, y + 1));
                    if out {
                        v.push((y * w + x) as u32);
                    }
                }
                v
            })
            .collect();
        rows.concat()
    }

    /// Calls `f(x, y, k)` for every mask pixel in scan order, `k` counting from 0.
    pub fn for_each_pixel(&self, mut f: impl FnMut(usize, usize, usize)) {
        let r = self.rect();
        let mut k = 0;
        for y in r.y0..r.y1 {
            for (i, &b) in self.crop.plane.row(y - r.y0).iter().enumerate() {
                if b {
                    f(r.x0 + i, y, k);
                    k += 1;
                }
            }
        }
    }

    /// The values of `crop` at the mask pixels, in scan order.
    pub fn gather<T: Copy + Default + Send + Sync>(&self, crop: &Crop<T>) -> Vec<T> {
        let mut v = Vec::with_capacity(self.count);
        self.for_each_pixel(|x, y, _| v.push(crop.get(x, y)));
        v
    }

    /// The values of a full-size plane at the mask pixels, in scan order.
    pub fn gather_plane<T: Copy>(&self, p: &Plane<T>) -> Vec<T> {
        let mut v = Vec::with_capacity(self.count);
        self.for_each_pixel(|x, y, _| v.push(p.get(x, y)));
        v
    }

    /// A crop over the bounding box holding `values` (scan order) at the mask pixels.
    pub fn scatter<T: Copy + Default + Send + Sync>(&self, values: &[T]) -> Crop<T> {
        let mut c = Crop::new(self.rect());
        let r = self.rect();
        self.for_each_pixel(|x, y, k| c.plane.set(x - r.x0, y - r.y0, values[k]));
        c
    }

    /// Bit-packed copy for long-term storage.
    pub fn pack(&self) -> PackedMask {
        let r = self.rect();
        let n = r.width() * r.height();
        let mut bits = vec![0u64; n.div_ceil(64)];
        for (i, &b) in self.crop.plane.data().iter().enumerate() {
            if b {
                bits[i / 64] |= 1 << (i % 64);
            }
        }
        PackedMask { w: self.w, h: self.h, rect: r, bits }
    }
}

impl Crop<bool> {
    /// The part of crop `c` inside `rect` (`false` where `c` does not reach).
    fn from_full_crop(c: &Crop<bool>, rect: Rect) -> Self {
        Crop { rect, plane: Plane::from_fn(rect.width(), rect.height(), |x, y| c.get(x + rect.x0, y + rect.y0)) }
    }
}

/// A frame mask packed one bit per pixel of its bounding box.
#[derive(Clone, Debug)]
pub(crate) struct PackedMask {
    w: usize,
    h: usize,
    rect: Rect,
    bits: Vec<u64>,
}

impl PackedMask {
    pub fn unpack(&self) -> FrameMask {
        let r = self.rect;
        let plane = Plane::from_fn(r.width(), r.height(), |x, y| {
            let i = y * r.width() + x;
            self.bits[i / 64] >> (i % 64) & 1 == 1
        });
        let count = self.bits.iter().map(|b| b.count_ones() as usize).sum();
        let mut m = FrameMask { w: self.w, h: self.h, crop: Crop { rect: r, plane }, count, boundary: Vec::new() };
        m.boundary = m.find_boundary();
        m
    }

    /// Heap bytes held.
    pub fn bytes(&self) -> usize {
        self.bits.len() * 8
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_mask_roundtrips_and_finds_boundary() {
        let mask = Plane::from_fn(9, 7, |x, y| (2..6).contains(&x) && (1..5).contains(&y));
        let m = FrameMask::from_full(&mask);
        assert_eq!(m.rect(), Rect { x0: 2, y0: 1, x1: 6, y1: 5 });
        assert_eq!(m.count, 16);
        assert_eq!(m.boundary.len(), 12);
        assert_eq!(m.to_full(), mask);
        let p = m.pack().unpack();
        assert_eq!(p.to_full(), mask);
        assert_eq!(p.boundary, m.boundary);
        let vals: Vec<f32> = (0..m.count).map(|k| k as f32).collect();
        let c = m.scatter(&vals);
        assert_eq!(m.gather(&c), vals);
        // A mask touching the image edge has no boundary there.
        let edge = FrameMask::from_full(&Plane::from_fn(4, 4, |x, _| x < 2));
        assert_eq!(edge.boundary.len(), 4);
        assert!(!FrameMask::from_full(&Plane::filled(3, 3, true)).boundary.iter().any(|_| true));
        assert!(FrameMask::from_full(&Plane::filled(3, 3, false)).is_degenerate());
    }
}
