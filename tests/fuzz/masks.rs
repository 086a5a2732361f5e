//! PNG mask sequences: 1–5 images of random sizes and color types (gray, gray+alpha, RGB,
//! RGBA, 16-bit), blobs of random coverage, sometimes of different sizes, damaged bytes, a
//! header claiming another size (with a valid checksum), truncation, an empty file or a JPEG
//! behind a `.png` name, loaded at a hostile `--scale`: every sequence loads and renders
//! each frame, or is an `Err`.

use super::harness::{Files, Reader, Rng};
use fluidymation::anim::{self, LoadOptions};
use std::path::Path;

pub const READER: Reader = Reader { name: "masks", make, check };

fn encode(w: u32, h: u32, kind: usize, pixels: &dyn Fn(u32, u32) -> u8) -> Vec<u8> {
    let mut out = std::io::Cursor::new(Vec::new());
    let fmt = image::ImageFormat::Png;
    let r = match kind {
        0 => image::GrayImage::from_fn(w, h, |x, y| image::Luma([pixels(x, y)])).write_to(&mut out, fmt),
        1 => image::GrayAlphaImage::from_fn(w, h, |x, y| image::LumaA([255, pixels(x, y)])).write_to(&mut out, fmt),
        2 => image::RgbImage::from_fn(w, h, |x, y| image::Rgb([pixels(x, y), 0, 9])).write_to(&mut out, fmt),
        3 => image::RgbaImage::from_fn(w, h, |x, y| image::Rgba([9, 9, 9, pixels(x, y)])).write_to(&mut out, fmt),
        4 => image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_fn(w, h, |x, y| {
            image::Luma([pixels(x, y) as u16 * 257])
        })
        .write_to(&mut out, fmt),
        _ => image::RgbImage::from_fn(w, h, |x, y| image::Rgb([pixels(x, y); 3]))
            .write_to(&mut out, image::ImageFormat::Jpeg),
    };
    r.unwrap();
    out.into_inner()
}

/// Sets the IHDR size of a PNG and fixes the chunk's CRC.
fn claim_size(png: &mut [u8], w: u32, h: u32) {
    if png.len() < 33 {
        return;
    }
    png[16..20].copy_from_slice(&w.to_be_bytes());
    png[20..24].copy_from_slice(&h.to_be_bytes());
    let crc = crc32fast::hash(&png[12..29]);
    png[29..33].copy_from_slice(&crc.to_be_bytes());
}

fn make(rng: &mut Rng) -> Files {
    let (w, h) = (rng.range(1, 64) as u32, rng.range(1, 64) as u32);
    let kind = if rng.chance(0.9) { rng.below(5) } else { 5 };
    let mut files = Vec::new();
    for k in 0..rng.range(1, 5) {
        let (fw, fh) = if rng.chance(0.1) { (rng.range(1, 64) as u32, rng.range(1, 64) as u32) } else { (w, h) };
        let (cx, cy, r) =
            (rng.range(0, fw as i64) as f32, rng.range(0, fh as i64) as f32, rng.range(0, 40) as f32 + k as f32);
        let solid = rng.below(4);
        let mut png = encode(fw, fh, kind, &|x, y| match solid {
            0 => 0,
            1 => 255,
            _ => {
                let d = ((x as f32 - cx).powi(2) + (y as f32 - cy).powi(2)).sqrt();
                ((r - d).clamp(0.0, 1.0) * 255.0) as u8
            }
        });
        match rng.below(12) {
            0 => {
                let n = rng.below(png.len());
                png.truncate(n);
            }
            1 => {
                for _ in 0..rng.range(1, 8) {
                    let i = rng.below(png.len());
                    png[i] ^= 1 << rng.below(8);
                }
            }
            2 => {
                let side = *rng.pick(&[0u32, 1, 16384, 16385, 100_000, u32::MAX, 3]);
                claim_size(&mut png, side, if rng.chance(0.5) { side } else { fh });
            }
            3 => png.clear(),
            _ => {}
        }
        files.push((format!("masks/m{:03}.png", k + 1), png));
    }
    let scale = *rng.pick(&["1", "1", "0.5", "2", "0.001", "16", "300", "0.37"]);
    files.push(("scale.txt".into(), scale.as_bytes().to_vec()));
    files
}

fn check(dir: &Path) {
    let scale: f32 =
        std::fs::read_to_string(dir.join("scale.txt")).ok().and_then(|s| s.trim().parse().ok()).unwrap_or(1.0);
    let Ok(a) = anim::load(&dir.join("masks"), &LoadOptions::default().scale(scale)) else { return };
    assert!(a.width as usize <= anim::MAX_SIDE as usize && a.height as usize <= anim::MAX_SIDE as usize);
    for f in 0..a.frames {
        if let Ok(rf) = a.render(0, f) {
            assert_eq!(rf.fill.size(), (a.width as usize, a.height as usize));
            assert!(rf.fill.data().iter().all(|c| (0.0..=1.0).contains(&c[3])));
        }
    }
}
