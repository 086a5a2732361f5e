//! User-supplied flow fields in the Middlebury `.flo` format (Baker et al., *A Database and
//! Evaluation Methodology for Optical Flow*): the format optical-flow tools write.
//!
//! Layout, little-endian: the tag `202021.25` as an `f32` (the bytes `PIEH`), the width and the
//! height as `i32`, then `width × height` pairs `(u, v)` of `f32`, row by row. `(u, v)` is the
//! motion of the pixel from this frame to the next, in pixels, x to the right and y downwards —
//! the convention of [`super::FrameGuides::flow`]. Values above 10⁹ in magnitude (the format's
//! "unknown") and non-finite values are read as zero.

use crate::error::{Error, Result};
use crate::img::{Plane, atomic_write};
use glam::Vec2;
use std::path::Path;

const TAG: f32 = 202021.25;
/// The largest side accepted when reading.
const MAX_SIDE: usize = 1 << 15;

/// Reads a `.flo` file.
pub fn read_flo(path: &Path) -> Result<Plane<Vec2>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let bad = |m: String| Error::image(path, m);
    if bytes.len() < 12 {
        return Err(bad(format!("{} bytes is too short for a .flo file (header is 12 bytes)", bytes.len())));
    }
    let word = |i: usize| [bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]];
    if f32::from_le_bytes(word(0)) != TAG {
        return Err(bad("not a Middlebury .flo file (the first four bytes are not 'PIEH')".into()));
    }
    let (w, h) = (i32::from_le_bytes(word(4)), i32::from_le_bytes(word(8)));
    if w <= 0 || h <= 0 || w as usize > MAX_SIDE || h as usize > MAX_SIDE {
        return Err(Error::Limit {
            path: path.to_path_buf(),
            what: format!("flow field size {w}x{h}"),
            value: w.max(h) as f64,
            limit: MAX_SIDE as f64,
        });
    }
    let (w, h) = (w as usize, h as usize);
    let need = 12 + w * h * 8;
    if bytes.len() != need {
        return Err(bad(format!("{}x{} flow needs {} bytes but the file has {}", w, h, need, bytes.len())));
    }
    let clean = |v: f32| if v.is_finite() && v.abs() <= 1e9 { v } else { 0.0 };
    let data = (0..w * h)
        .map(|i| {
            let o = 12 + i * 8;
            Vec2::new(clean(f32::from_le_bytes(word(o))), clean(f32::from_le_bytes(word(o + 4))))
        })
        .collect();
    Plane::from_vec(w, h, data).ok_or_else(|| bad("inconsistent size".into()))
}

/// Writes a `.flo` file, atomically.
pub fn write_flo(path: &Path, flow: &Plane<Vec2>) -> Result<()> {
    let mut bytes = Vec::with_capacity(12 + flow.len() * 8);
    bytes.extend_from_slice(&TAG.to_le_bytes());
    bytes.extend_from_slice(&(flow.width() as i32).to_le_bytes());
    bytes.extend_from_slice(&(flow.height() as i32).to_le_bytes());
    for v in flow.data() {
        bytes.extend_from_slice(&v.x.to_le_bytes());
        bytes.extend_from_slice(&v.y.to_le_bytes());
    }
    atomic_write(path, |w| w.write_all(&bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roundtrip_and_errors() {
        let dir = std::env::temp_dir().join(format!("fm-flo-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = Plane::from_fn(5, 3, |x, y| Vec2::new(x as f32 * 0.5, -(y as f32)));
        let p = dir.join("a.flo");
        write_flo(&p, &f).unwrap();
        assert_eq!(read_flo(&p).unwrap(), f);
        std::fs::write(&p, b"PIEH\x05\0\0\0").unwrap();
        assert!(read_flo(&p).unwrap_err().to_string().contains("too short"));
        std::fs::write(&p, b"NOPE\x01\0\0\0\x01\0\0\0\0\0\0\0\0\0\0\0").unwrap();
        assert!(read_flo(&p).unwrap_err().to_string().contains("PIEH"));
        let mut b = TAG.to_le_bytes().to_vec();
        b.extend_from_slice(&(-3i32).to_le_bytes());
        b.extend_from_slice(&3i32.to_le_bytes());
        std::fs::write(&p, &b).unwrap();
        assert!(matches!(read_flo(&p), Err(Error::Limit { .. })));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
