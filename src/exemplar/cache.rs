//! On-disk cache of exemplar guides (issue 3): the guides of an exemplar are computed once per
//! content and guide parameters and stored next to the exemplar, in `<exemplar>/.cache/`, or —
//! for bundled and in-memory exemplars, or a read-only exemplar folder — in the user's cache
//! folder (`$XDG_CACHE_HOME/fluidymation/guides`, `~/.cache/fluidymation/guides`,
//! `~/Library/Caches/fluidymation/guides` on macOS, `%LOCALAPPDATA%\fluidymation\guides` on
//! Windows).
//!
//! The key hashes the (resampled) exemplar masks the guides are computed from — so content,
//! `--src-scale` and `--src-speed` are all in it — together with
//! [`GuideParams::fingerprint`]. A cache file that cannot be read, is truncated or has another
//! key is ignored and rewritten; a cache folder that cannot be written only costs the time of
//! computing the guides again. Files are written to a temporary name and renamed.
//!
//! The environment variable `FLUIDYMATION_CACHE` overrides the location (a folder), or turns the
//! cache off (`off`).

use crate::error::Result;
use crate::exemplar::Exemplar;
use crate::guide::{self, FrameGuides, GuideParams};
use crate::img::{self, Plane};
use glam::Vec2;
use std::io::Write;
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"FMGUIDE1";
/// Most cache files kept in the user's cache folder (the oldest are removed beyond it).
const MAX_USER_FILES: usize = 24;

/// The cache key of the guides of `masks` computed with `params`.
pub fn key(masks: &[Plane<f32>], params: &GuideParams) -> u64 {
    let mut h = Fnv::default();
    h.bytes(params.fingerprint().as_bytes());
    h.u64(masks.len() as u64);
    for m in masks {
        h.u64(m.width() as u64);
        h.u64(m.height() as u64);
        for &v in m.data() {
            h.u64(v.to_bits() as u64);
        }
    }
    h.0
}

/// Where the guides of `ex` are cached: `FLUIDYMATION_CACHE`, else the exemplar's own
/// `.cache` folder, else the user's cache folder (see the module docs). `None` = no cache.
pub fn locations(ex: &Exemplar) -> Vec<PathBuf> {
    match std::env::var_os("FLUIDYMATION_CACHE") {
        Some(v) if v == "off" || v == "0" => return Vec::new(),
        Some(v) if !v.is_empty() => return vec![PathBuf::from(v)],
        _ => {}
    }
    let mut out = Vec::new();
    if let Some(d) = &ex.dir {
        out.push(d.join(".cache"));
    }
    out.extend(user_cache_dir());
    out
}

/// The user's cache folder for guides, when the home folder is known.
pub fn user_cache_dir() -> Option<PathBuf> {
    let env = |k: &str| std::env::var_os(k).filter(|v| !v.is_empty()).map(PathBuf::from);
    let base = if cfg!(windows) {
        env("LOCALAPPDATA")
    } else if cfg!(target_os = "macos") {
        env("HOME").map(|h| h.join("Library").join("Caches"))
    } else {
        env("XDG_CACHE_HOME").filter(|p| p.is_absolute()).or_else(|| env("HOME").map(|h| h.join(".cache")))
    }?;
    Some(base.join("fluidymation").join("guides"))
}

/// The guides of the exemplar masks `masks` (already resampled), from the first cache location
/// that holds them, else computed and stored in the first location that can be written.
pub fn guides(ex: &Exemplar, masks: &[Plane<f32>], params: &GuideParams) -> Result<Vec<FrameGuides>> {
    guides_in(&locations(ex), &crate::anim::slug(&ex.meta.name), masks, params)
}

/// [`guides`] with explicit cache folders (tried in order) and a file-name stem.
pub fn guides_in(dirs: &[PathBuf], stem: &str, masks: &[Plane<f32>], params: &GuideParams) -> Result<Vec<FrameGuides>> {
    if dirs.is_empty() {
        return guide::compute_sequence(masks, params);
    }
    let k = key(masks, params);
    let name = format!("{stem}-{k:016x}.fmguides");
    for d in dirs {
        let path = d.join(&name);
        match read(&path, k) {
            Some(g) if g.len() == masks.len() && g.iter().zip(masks).all(|(g, m)| g.dist.size() == m.size()) => {
                log::debug!("exemplar guides from the cache '{}'", path.display());
                return Ok(g);
            }
            _ => {}
        }
    }
    let g = guide::compute_sequence(masks, params)?;
    for d in dirs {
        let path = d.join(&name);
        let written = std::fs::create_dir_all(d).is_ok() && img::atomic_write(&path, |w| write(w, k, &g)).is_ok();
        if written {
            log::debug!("exemplar guides cached in '{}'", path.display());
            if Some(d) == user_cache_dir().as_ref() {
                prune(d, MAX_USER_FILES);
            }
            break;
        }
        log::debug!("could not cache the exemplar guides in '{}'", d.display());
    }
    Ok(g)
}

/// Removes the least recently written cache files of `dir` beyond `keep`.
fn prune(dir: &Path, keep: usize) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut files: Vec<(std::time::SystemTime, PathBuf)> = entries
        .flatten()
        .filter(|e| e.path().extension().is_some_and(|x| x == "fmguides"))
        .filter_map(|e| Some((e.metadata().ok()?.modified().ok()?, e.path())))
        .collect();
    if files.len() <= keep {
        return;
    }
    files.sort();
    for (_, p) in &files[..files.len() - keep] {
        let _ = std::fs::remove_file(p);
    }
}

fn write(w: &mut dyn Write, key: u64, g: &[FrameGuides]) -> std::io::Result<()> {
    w.write_all(MAGIC)?;
    w.write_all(&key.to_le_bytes())?;
    let (width, height) = g.first().map(|f| f.dist.size()).unwrap_or((0, 0));
    for v in [g.len(), width, height] {
        w.write_all(&(v as u32).to_le_bytes())?;
    }
    let mut buf = Vec::with_capacity(width * height * 21);
    for f in g {
        buf.clear();
        buf.extend(f.mask.data().iter().map(|&b| b as u8));
        for p in [&f.dist, &f.ext_pos, &f.ext_neg] {
            buf.extend(p.data().iter().flat_map(|v| v.to_le_bytes()));
        }
        buf.extend(f.flow.data().iter().flat_map(|v| [v.x.to_le_bytes(), v.y.to_le_bytes()].concat()));
        w.write_all(&buf)?;
    }
    Ok(())
}

/// Reads a cache file; `None` when it is missing, damaged or of another key.
fn read(path: &Path, key: u64) -> Option<Vec<FrameGuides>> {
    let data = std::fs::read(path).ok()?;
    let mut r = Reader(&data);
    if r.take(8)? != MAGIC || r.u64()? != key {
        return None;
    }
    let (n, w, h) = (r.u32()? as usize, r.u32()? as usize, r.u32()? as usize);
    let px = w.checked_mul(h)?;
    if r.0.len() != n.checked_mul(px.checked_mul(21)?)? {
        return None;
    }
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let mask = Plane::from_vec(w, h, r.take(px)?.iter().map(|&b| b != 0).collect())?;
        let f32s = |r: &mut Reader| -> Option<Plane<f32>> {
            let b = r.take(px * 4)?;
            Plane::from_vec(w, h, b.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect())
        };
        let dist = f32s(&mut r)?;
        let ext_pos = f32s(&mut r)?;
        let ext_neg = f32s(&mut r)?;
        let b = r.take(px * 8)?;
        let flow = Plane::from_vec(
            w,
            h,
            b.chunks_exact(8)
                .map(|c| {
                    Vec2::new(
                        f32::from_le_bytes([c[0], c[1], c[2], c[3]]),
                        f32::from_le_bytes([c[4], c[5], c[6], c[7]]),
                    )
                })
                .collect(),
        )?;
        out.push(FrameGuides { mask, dist, flow, ext_pos, ext_neg });
    }
    Some(out)
}

struct Reader<'a>(&'a [u8]);

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        if self.0.len() < n {
            return None;
        }
        let (a, b) = self.0.split_at(n);
        self.0 = b;
        Some(a)
    }
    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
}

/// 64-bit FNV-1a (the crate's one; `resume` fingerprints with it too).
pub(crate) struct Fnv(pub(crate) u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    pub(crate) fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 = (self.0 ^ x as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn masks(r0: f32) -> Vec<Plane<f32>> {
        (0..4)
            .map(|k| {
                let r = r0 + 2.0 * k as f32;
                Plane::from_fn(48, 40, |x, y| {
                    let (dx, dy) = (x as f32 - 24.0, y as f32 - 20.0);
                    if dx * dx + dy * dy < r * r { 1.0 } else { 0.0 }
                })
            })
            .collect()
    }

    #[test]
    fn cached_guides_equal_computed_ones_and_damage_is_repaired() {
        let dir = std::env::temp_dir().join(format!("fm-guide-cache-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let params = GuideParams::default();
        let m = masks(8.0);
        let fresh = guide::compute_sequence(&m, &params).unwrap();
        let first = guides_in(std::slice::from_ref(&dir), "t", &m, &params).unwrap();
        assert_eq!(first, fresh);
        let files: Vec<PathBuf> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
        assert_eq!(files.len(), 1);
        let file = &files[0];
        assert_eq!(read(file, key(&m, &params)).unwrap(), fresh);
        // Another key (other content or parameters) does not read this file.
        assert!(read(file, key(&masks(9.0), &params)).is_none());
        let other = GuideParams { blur_sigma: params.blur_sigma + 1.0, ..params.clone() };
        assert_ne!(key(&m, &params), key(&m, &other));
        // A truncated file is ignored, recomputed and rewritten.
        let len = std::fs::metadata(file).unwrap().len();
        std::fs::write(file, &std::fs::read(file).unwrap()[..100]).unwrap();
        assert_eq!(guides_in(std::slice::from_ref(&dir), "t", &m, &params).unwrap(), fresh);
        assert_eq!(std::fs::metadata(file).unwrap().len(), len);
        // An unwritable first location falls through to the next.
        let blocked = dir.join("blocked");
        std::fs::write(&blocked, b"a file, not a folder").unwrap();
        let second = dir.join("second");
        let g = guides_in(&[blocked.clone(), second.clone()], "t", &masks(7.0), &params).unwrap();
        assert_eq!(g.len(), 4);
        assert_eq!(std::fs::read_dir(&second).unwrap().count(), 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn pruning_keeps_the_newest() {
        let dir = std::env::temp_dir().join(format!("fm-guide-prune-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        for k in 0..5 {
            std::fs::write(dir.join(format!("{k}.fmguides")), b"x").unwrap();
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        std::fs::write(dir.join("other.txt"), b"kept").unwrap();
        prune(&dir, 2);
        let mut left: Vec<String> =
            std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        left.sort();
        assert_eq!(left, ["3.fmguides", "4.fmguides", "other.txt"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
