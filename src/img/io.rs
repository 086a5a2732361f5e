//! PNG (and JPEG) input, PNG output. Every write goes to a temporary file in the
//! destination's directory and is renamed into place, so a failed or interrupted run never
//! leaves a half-written file behind.

use super::{Plane, Rgb, Rgba};
use crate::error::{Error, Result};
use std::fs;
use std::io::{BufWriter, Write};
use std::path::Path;

/// Writes a file atomically: `write` fills a temporary file next to `path`, which is then
/// renamed over `path`. On any error the temporary file is removed and `path` is untouched.
pub fn atomic_write(path: &Path, write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    // Unique per call, so concurrent writers of one path (threads too) never share a temporary.
    static SERIAL: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let serial = SERIAL.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = dir.join(format!(".{}.{}-{}.tmp", name, std::process::id(), serial));
    let result = (|| -> std::io::Result<()> {
        let file = fs::File::create(&tmp)?;
        let mut w = BufWriter::new(file);
        write(&mut w)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        Ok(())
    })();
    match result.and_then(|_| fs::rename(&tmp, path)) {
        Ok(()) => Ok(()),
        Err(e) => {
            let _ = fs::remove_file(&tmp);
            Err(Error::io(path, e))
        }
    }
}

/// Largest image side decoded, pixels (the largest canvas, [`crate::anim::MAX_SIDE`]).
pub const MAX_IMAGE_SIDE: u32 = crate::anim::MAX_SIDE;

/// Most bytes a decoder may allocate for one image.
const MAX_DECODE_BYTES: u64 = 1 << 30;

/// Decodes an image held in memory (`path` names it in errors). Its header is read first: a
/// side over `max_side`, or a PNG too short to hold the pixels its header claims (deflate
/// compresses at most ~1032:1), is refused before any pixel buffer is allocated.
pub fn decode(bytes: &[u8], path: &Path, max_side: u32) -> Result<image::DynamicImage> {
    let reader =
        image::ImageReader::new(std::io::Cursor::new(bytes)).with_guessed_format().map_err(|e| Error::io(path, e))?;
    let format = reader.format();
    let (w, h) = reader.into_dimensions().map_err(|e| Error::image_codec(path, e))?;
    if w.max(h) > max_side {
        return Err(Error::Limit {
            path: path.to_path_buf(),
            what: format!("image side ({w}x{h})"),
            value: w.max(h) as f64,
            limit: max_side as f64,
        });
    }
    // The smallest PNG of w × h pixels: 1 bit a pixel and a filter byte a row, at deflate's
    // best ratio.
    let least = h as u64 * (1 + (w as u64).div_ceil(8)) / 1100;
    if format == Some(image::ImageFormat::Png) && (bytes.len() as u64) < least {
        return Err(Error::image(
            path,
            format!(
                "its header claims {w}x{h} pixels but the file has only {} bytes: it is truncated or damaged",
                bytes.len()
            ),
        ));
    }
    let mut reader =
        image::ImageReader::new(std::io::Cursor::new(bytes)).with_guessed_format().map_err(|e| Error::io(path, e))?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(max_side);
    limits.max_image_height = Some(max_side);
    limits.max_alloc = Some(MAX_DECODE_BYTES);
    reader.limits(limits);
    reader.decode().map_err(|e| Error::image_codec(path, e))
}

fn open(path: &Path) -> Result<image::DynamicImage> {
    let bytes = fs::read(path).map_err(|e| Error::io(path, e))?;
    decode(&bytes, path, MAX_IMAGE_SIDE)
}

#[inline]
fn unorm(v: u8) -> f32 {
    v as f32 * (1.0 / 255.0)
}

#[inline]
fn to_u8(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

/// Loads an image as RGB in `0..=1` (alpha, if any, is ignored).
pub fn load_rgb(path: &Path) -> Result<Plane<Rgb>> {
    let img = open(path)?.to_rgb8();
    let (w, h) = img.dimensions();
    let data = img.pixels().map(|p| [unorm(p[0]), unorm(p[1]), unorm(p[2])]).collect();
    Ok(Plane::from_vec(w as usize, h as usize, data).expect("decoder returned a consistent size"))
}

/// Loads an image as straight RGBA in `0..=1`.
pub fn load_rgba(path: &Path) -> Result<Plane<Rgba>> {
    let img = open(path)?.to_rgba8();
    let (w, h) = img.dimensions();
    let data = img.pixels().map(|p| [unorm(p[0]), unorm(p[1]), unorm(p[2]), unorm(p[3])]).collect();
    Ok(Plane::from_vec(w as usize, h as usize, data).expect("decoder returned a consistent size"))
}

/// Loads a mask image as coverage in `0..=1`: the alpha channel when the image has one that
/// is not fully opaque, otherwise the luminance (white = inside).
pub fn load_gray(path: &Path) -> Result<Plane<f32>> {
    let img = open(path)?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let data: Vec<f32> = if img.color().has_alpha() {
        let rgba = img.to_rgba8();
        if rgba.pixels().any(|p| p[3] < 255) {
            rgba.pixels().map(|p| unorm(p[3])).collect()
        } else {
            img.to_luma8().pixels().map(|p| unorm(p[0])).collect()
        }
    } else {
        img.to_luma8().pixels().map(|p| unorm(p[0])).collect()
    };
    Ok(Plane::from_vec(w, h, data).expect("decoder returned a consistent size"))
}

fn encode_png(path: &Path, w: usize, h: usize, color: image::ExtendedColorType, bytes: &[u8]) -> Result<()> {
    use image::ImageEncoder;
    atomic_write(path, |out| {
        image::codecs::png::PngEncoder::new(out)
            .write_image(bytes, w as u32, h as u32, color)
            .map_err(std::io::Error::other)
    })
}

/// Writes 8-bit straight RGBA bytes (`w * h * 4`) as a PNG, atomically.
pub fn write_png_rgba8(path: &Path, w: usize, h: usize, rgba: &[u8]) -> Result<()> {
    encode_png(path, w, h, image::ExtendedColorType::Rgba8, rgba)
}

/// Saves straight RGBA in `0..=1` as an 8-bit PNG, atomically.
pub fn save_rgba(path: &Path, p: &Plane<Rgba>) -> Result<()> {
    let bytes: Vec<u8> = p.data().iter().flat_map(|c| c.map(to_u8)).collect();
    write_png_rgba8(path, p.width(), p.height(), &bytes)
}

/// Saves RGB in `0..=1` as an 8-bit PNG, atomically.
pub fn save_rgb(path: &Path, p: &Plane<Rgb>) -> Result<()> {
    let bytes: Vec<u8> = p.data().iter().flat_map(|c| c.map(to_u8)).collect();
    encode_png(path, p.width(), p.height(), image::ExtendedColorType::Rgb8, &bytes)
}

/// Saves a gray plane in `0..=1` as an 8-bit grayscale PNG, atomically.
pub fn save_gray(path: &Path, p: &Plane<f32>) -> Result<()> {
    let bytes: Vec<u8> = p.data().iter().map(|&v| to_u8(v)).collect();
    encode_png(path, p.width(), p.height(), image::ExtendedColorType::L8, &bytes)
}

/// Saves a binary mask as a grayscale PNG (255 inside, 0 outside), atomically.
pub fn save_mask(path: &Path, m: &Plane<bool>) -> Result<()> {
    let bytes: Vec<u8> = m.data().iter().map(|&b| if b { 255 } else { 0 }).collect();
    encode_png(path, m.width(), m.height(), image::ExtendedColorType::L8, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roundtrip_and_atomicity() {
        let dir = std::env::temp_dir().join(format!("fm-io-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let p = Plane::from_fn(7, 5, |x, y| [x as f32 / 6.0, y as f32 / 4.0, 0.5, 1.0]);
        let f = dir.join("a.png");
        save_rgba(&f, &p).unwrap();
        let q = load_rgba(&f).unwrap();
        assert_eq!(q.size(), (7, 5));
        assert!((q.get(6, 4)[0] - 1.0).abs() < 1e-6 && (q.get(3, 2)[2] - 128.0 / 255.0).abs() < 1e-6);
        // A failing writer leaves the previous file intact and no temporary behind.
        let err = atomic_write(&f, |_| Err(std::io::Error::other("boom")));
        assert!(err.is_err());
        assert_eq!(load_rgba(&f).unwrap(), q);
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1);
        let g = load_gray(&f).unwrap(); // opaque RGBA -> luminance
        assert!(g.get(0, 0) < 0.3);
        // A header claiming a huge image over a few bytes is refused before decoding.
        let mut png = fs::read(&f).unwrap();
        let ihdr = |png: &mut Vec<u8>, size: [u8; 8]| {
            png[16..24].copy_from_slice(&size);
            let crc = crc32fast::hash(&png[12..29]);
            png[29..33].copy_from_slice(&crc.to_be_bytes());
        };
        ihdr(&mut png, [0, 0, 0x40, 0, 0, 0, 0x40, 0]); // 16384 x 16384
        let e = decode(&png, &f, MAX_IMAGE_SIDE).unwrap_err().to_string();
        assert!(e.contains("16384x16384") && e.contains("truncated or damaged"), "{e}");
        ihdr(&mut png, [0, 0, 0x40, 1, 0, 0, 0, 5]);
        let e = decode(&png, &f, MAX_IMAGE_SIDE).unwrap_err().to_string();
        assert!(e.contains("16385x5") && e.contains("at most 16384"), "{e}");
        fs::remove_dir_all(&dir).unwrap();
    }
}
