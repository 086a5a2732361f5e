//! A painted layer frame: the engine's output for one layer and frame, in the exemplar's
//! colors, quantized to 16 bits per channel.
//!
//! This is what a [`render_layer`](super::render_layer) job writes to
//! `layers/NN_name/paint/NNNN.png` (16-bit RGBA PNG, alpha = the synthesized mask, color 0
//! outside it) and what [`composite`](super::composite()) reads back. [`render`](super::render)
//! keeps it in memory but passes it through the same quantization, so the three ways of
//! rendering recolor exactly the same numbers and write the same bytes. 16 bits keep the
//! quantization far below what an 8-bit frame can show (steps of 1/65535 against 1/255).

use crate::error::{Error, Result};
use crate::img::{self, Mask, Plane, Rgb};
use std::path::Path;

/// One painted frame of a layer, RGBA with 16 bits per channel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Paint {
    width: usize,
    height: usize,
    /// Row-major RGBA; alpha is 65535 inside the mask and 0 outside, where the color is 0.
    data: Vec<u16>,
}

fn to_u16(v: f32) -> u16 {
    // NaN becomes 0.
    (v.clamp(0.0, 1.0) * 65535.0 + 0.5) as u16
}

fn from_u16(v: u16) -> f32 {
    v as f32 / 65535.0
}

impl Paint {
    /// Quantizes the engine's output: its colors inside `mask` (`rgb` and `mask` must have the
    /// same size; a smaller `rgb` reads as black).
    pub fn from_frame(rgb: &Plane<Rgb>, mask: &Mask) -> Paint {
        let (width, height) = mask.size();
        let mut data = vec![0u16; width * height * 4];
        for ((px, &on), c) in data.chunks_exact_mut(4).zip(mask.data()).zip(rgb.data()) {
            if on {
                px.copy_from_slice(&[to_u16(c[0]), to_u16(c[1]), to_u16(c[2]), u16::MAX]);
            }
        }
        Paint { width, height, data }
    }

    /// `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The colors and the mask, as [`composite::recolor_layer`](crate::composite::recolor_layer)
    /// takes them. A pixel is inside the mask when its alpha is at least half.
    pub fn rgb_mask(&self) -> (Plane<Rgb>, Mask) {
        let px = self.data.chunks_exact(4);
        let rgb = px.clone().map(|p| [from_u16(p[0]), from_u16(p[1]), from_u16(p[2])]).collect();
        let mask = px.map(|p| p[3] >= 0x8000).collect();
        let rgb = Plane::from_vec(self.width, self.height, rgb).expect("one color per pixel");
        (rgb, Plane::from_vec(self.width, self.height, mask).expect("one mask value per pixel"))
    }

    /// Writes a 16-bit RGBA PNG, atomically (a temporary file renamed into place).
    pub fn save(&self, path: &Path) -> Result<()> {
        use image::ImageEncoder;
        use image::codecs::png::{CompressionType, FilterType, PngEncoder};
        // PNG stores 16-bit samples big-endian; `write_image` takes them in native order.
        let bytes: Vec<u8> = self.data.iter().flat_map(|v| v.to_ne_bytes()).collect();
        img::atomic_write(path, |out| {
            PngEncoder::new_with_quality(out, CompressionType::Fast, FilterType::Adaptive)
                .write_image(&bytes, self.width as u32, self.height as u32, image::ExtendedColorType::Rgba16)
                .map_err(std::io::Error::other)
        })
    }

    /// Reads a PNG written by [`Paint::save`]; any PNG reads, converted to 16-bit RGBA.
    pub fn load(path: &Path) -> Result<Paint> {
        let reader = image::ImageReader::open(path).map_err(|e| Error::io(path, e))?;
        let decoded = reader.with_guessed_format().map_err(|e| Error::io(path, e))?.decode();
        let img = decoded.map_err(|e| Error::image_codec(path, e))?.into_rgba16();
        let (w, h) = img.dimensions();
        Ok(Paint { width: w as usize, height: h as usize, data: img.into_raw() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantization_survives_a_png_round_trip_exactly() {
        let rgb = Plane::from_fn(7, 5, |x, y| [x as f32 / 6.0, y as f32 / 4.0 + 1e-5, 0.123_456_7]);
        let mask = Plane::from_fn(7, 5, |x, y| (x + y) % 3 != 0);
        let paint = Paint::from_frame(&rgb, &mask);
        let dir = std::env::temp_dir().join(format!("fm-paint-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("0001.png");
        paint.save(&path).unwrap();
        let back = Paint::load(&path).unwrap();
        assert_eq!(back, paint);
        let (r, m) = back.rgb_mask();
        assert_eq!(m, mask);
        for (i, (&on, (a, b))) in mask.data().iter().zip(r.data().iter().zip(rgb.data())).enumerate() {
            if on {
                for c in 0..3 {
                    let want = b[c].clamp(0.0, 1.0);
                    assert!((a[c] - want).abs() <= 0.5 / 65535.0 + 1e-7, "pixel {i} channel {c}: {a:?} vs {b:?}");
                }
            } else {
                assert_eq!(*a, [0.0; 3], "outside the mask");
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
