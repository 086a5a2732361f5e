//! Exemplar folders: `exemplar.toml` from a valid one with fields removed, retyped, made
//! hostile or unknown (or the TOML damaged), 0–5 frames (PNG or JPEG) and 0–5 masks of random
//! sizes, masks empty, full, touching the border or thin, damaged or truncated files. Loaded
//! and, when that succeeds, prepared for synthesis at a small scale: every folder loads and
//! prepares, or is an `Err`.

use super::harness::{Files, Reader, Rng};
use fluidymation::exemplar::Exemplar;
use fluidymation::synth::{Params, Source};
use std::path::Path;

pub const READER: Reader = Reader { name: "exemplar", make, check };

const FIELDS: &[(&str, &str)] = &[
    ("name", "\"fuzz\""),
    ("description", "\"made by the fuzzer\""),
    ("fps", "24.0"),
    ("paper", "\"#f8f4ec\""),
    ("pigment", "\"#2050a0\""),
    ("border_width", "6.0"),
    ("scale", "1.0"),
    ("speed", "1"),
    ("license", "\"CC0\""),
];

fn toml(rng: &mut Rng) -> String {
    let mut out = String::new();
    for (k, v) in FIELDS {
        if rng.chance(0.95) {
            out.push_str(&format!("{k} = {v}\n"));
            continue;
        }
        let v = match rng.below(8) {
            0 => continue,
            1 => "\"text\"".to_string(),
            2 => format!("{}", rng.hostile_f64(3.0)).replace("NaN", "nan"),
            3 => "[1, 2]".to_string(),
            4 => "-7".to_string(),
            5 => "\"#12345\"".to_string(),
            6 => "0".to_string(),
            _ => v.to_string(),
        };
        out.push_str(&format!("{k} = {v}\n"));
    }
    if rng.chance(0.05) {
        out.push_str("unknown = 1\n");
    }
    if rng.chance(0.05) {
        out.push_str("[generator\n");
    }
    out
}

fn png(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3], jpeg: bool) -> Vec<u8> {
    let img = image::RgbImage::from_fn(w, h, |x, y| image::Rgb(f(x, y)));
    let mut out = std::io::Cursor::new(Vec::new());
    let fmt = if jpeg { image::ImageFormat::Jpeg } else { image::ImageFormat::Png };
    img.write_to(&mut out, fmt).unwrap();
    out.into_inner()
}

fn damage(bytes: &mut Vec<u8>, rng: &mut Rng) {
    match rng.below(20) {
        0 => {
            let n = rng.below(bytes.len().max(1));
            bytes.truncate(n);
        }
        1 if !bytes.is_empty() => {
            let i = rng.below(bytes.len());
            bytes[i] ^= 0x55;
        }
        2 => bytes.clear(),
        _ => {}
    }
}

fn make(rng: &mut Rng) -> Files {
    let mut files = vec![("ex/exemplar.toml".to_string(), toml(rng).into_bytes())];
    let (w, h) = (rng.range(4, 48) as u32, rng.range(4, 48) as u32);
    let n = if rng.chance(0.9) { rng.range(2, 5) } else { rng.range(0, 5) } as usize;
    let m = if rng.chance(0.9) { n } else { rng.range(0, 5) as usize };
    let jpeg = rng.chance(0.1);
    for k in 0..n.max(m) {
        let size =
            |rng: &mut Rng| if rng.chance(0.05) { (rng.range(1, 48) as u32, rng.range(1, 48) as u32) } else { (w, h) };
        let r = rng.range(0, 30) as f32 + 2.0 * k as f32;
        let (cx, cy) = if rng.chance(0.2) { (0.0, 0.0) } else { (w as f32 / 2.0, h as f32 / 2.0) };
        let inside = move |x: u32, y: u32| ((x as f32 - cx).powi(2) + (y as f32 - cy).powi(2)).sqrt() < r;
        if k < n {
            let (fw, fh) = size(rng);
            let mut b = png(fw, fh, |x, y| if inside(x, y) { [40, 80, 160] } else { [248, 244, 236] }, jpeg);
            damage(&mut b, rng);
            files.push((format!("ex/frames/{:04}.{}", k + 1, if jpeg { "jpg" } else { "png" }), b));
        }
        if k < m {
            let (mw, mh) = size(rng);
            let full = rng.chance(0.05);
            let mut b = png(mw, mh, |x, y| if full || inside(x, y) { [255; 3] } else { [0; 3] }, false);
            damage(&mut b, rng);
            files.push((format!("ex/masks/{:04}.png", k + 1), b));
        }
    }
    files
}

fn check(dir: &Path) {
    let Ok(ex) = Exemplar::load(&dir.join("ex")) else { return };
    // One frame is a still exemplar.
    assert!(!ex.is_empty() && ex.frames.len() == ex.masks.len());
    let params = Params::builder().src_scale(0.5).build().unwrap();
    if let Ok(source) = Source::prepare(&ex, &params) {
        assert!(source.frames() >= 1 && source.frames() <= ex.len());
    }
}
