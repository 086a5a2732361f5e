//! Writing results: numbered PNG frames, stylized layers and animated GIFs.
//!
//! Every file is written to a temporary name in its destination directory and renamed into
//! place when complete, so an interrupted or failed run never leaves a half-written file.
//!
//! # GIF quality
//!
//! GIF frames hold at most 256 colors, and watercolor washes are exactly the smooth gradients
//! that band with naive palettes. [`GifWriter`] therefore
//! - gives every frame its own palette, built from the pixels that frame changes: used as they
//!   are when there are few enough; otherwise the most frequent colors (flat areas such as the
//!   background, ≥ 1 % of the pixels, at most 16) are kept exactly — so flat areas are never
//!   dithered — and the rest of the palette is learned by NeuQuant (`color_quant`) and refined
//!   by three Lloyd (k-means) iterations;
//! - maps pixels with serpentine Floyd–Steinberg error diffusion (exact nearest-color search on
//!   a 16³ grid of candidate lists; error clamped to ±48 levels per channel so that colors the
//!   palette cannot reach do not smear);
//! - for opaque animations stores only the rectangle that changed since the previous frame,
//!   pixels that did not change being transparent ("keep" disposal): still areas stay exactly
//!   still instead of re-dithering every frame, and the palette is spent on what moves;
//! - for transparent backgrounds writes whole frames cleared before the next ("background"
//!   disposal); pixels with alpha < 0.5 are transparent, the others opaque (GIF has 1-bit
//!   alpha);
//! - times frames by rounding each frame's start time `100 k / fps` to 1/100 s, so delays
//!   alternate (24 fps: 4, 4, 5, 4, 4, 4 …) and the total duration is exact ([`gif_schedule`]);
//!   identical consecutive frames are merged into one longer frame, and above 50 fps frames
//!   shorter than 2/100 s are dropped (browsers slow such frames down to 1/10 s);
//! - loops forever.
//!
//! Deliberately not used: gifski / libimagequant, whose core is GPL-3.

mod gif_writer;
mod quant;

pub use gif_writer::{GifOptions, GifSummary, GifWriter, MIN_DELAY_CS, gif_schedule};

use crate::anim::Region;
use crate::error::{Error, Result};
use crate::img::{self, Plane, Rgba};
use std::path::{Path, PathBuf};

/// Digits of frame numbers in file names: 4, or more when `frame_count` needs them, so names
/// always sort in frame order.
pub fn frame_digits(frame_count: usize) -> usize {
    frame_count.max(1).to_string().len().max(4)
}

/// `dir/NNNN.png` for the 0-based frame `frame0` of a sequence of `frame_count` frames: numbers
/// start at 1 (`0001.png` is the first frame) and have [`frame_digits`] digits.
pub fn frame_path(dir: &Path, frame0: usize, frame_count: usize) -> PathBuf {
    dir.join(format!("{:0width$}.png", frame0 + 1, width = frame_digits(frame_count)))
}

/// Writes a frame as an 8-bit RGBA PNG at [`frame_path`], atomically; returns the path.
pub fn write_frame(dir: &Path, frame0: usize, frame_count: usize, frame: &Plane<Rgba>) -> Result<PathBuf> {
    let path = frame_path(dir, frame0, frame_count);
    img::save_rgba(&path, frame)?;
    Ok(path)
}

/// `out_dir/layers/NN_slug`, where `--keep-layers` writes a region's stylized frames.
pub fn layer_dir(out_dir: &Path, region: &Region) -> PathBuf {
    out_dir.join("layers").join(region.dir_name())
}

/// Creates `dir` (and its parents) if needed and checks that files can be created in it,
/// so that an unwritable output directory fails before any work is done.
pub fn prepare_dir(dir: &Path) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        return Err(Error::io(
            dir,
            std::io::Error::new(std::io::ErrorKind::NotADirectory, "exists and is not a directory"),
        ));
    }
    if let Err(e) = std::fs::create_dir_all(dir) {
        // Name the part of the path that is in the way (a file where a folder should be).
        let blocker = dir.ancestors().skip(1).find(|a| a.exists() && !a.is_dir());
        return Err(match blocker {
            Some(b) => Error::io(
                dir,
                std::io::Error::new(
                    e.kind(),
                    format!("cannot create it: '{}' is a file, not a directory", b.display()),
                ),
            ),
            None => Error::io(dir, e),
        });
    }
    // Unique per call: a batch prepares several files' folders at once, in one process.
    static PROBES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = PROBES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let probe = dir.join(format!(".fluidymation-write-test.{}-{n}", std::process::id()));
    std::fs::write(&probe, b"").map_err(|e| Error::io(dir, e))?;
    std::fs::remove_file(&probe).map_err(|e| Error::io(dir, e))?;
    Ok(())
}

/// Checks, before any work is done, that the file `path` can be written later: it is not a
/// folder, and its folder exists or can be created and is writable ([`prepare_dir`], which
/// creates it).
pub fn prepare_file(path: &Path) -> Result<()> {
    if path.is_dir() {
        return Err(Error::io(
            path,
            std::io::Error::new(std::io::ErrorKind::IsADirectory, "is a directory, not a file"),
        ));
    }
    match path.parent().filter(|p| !p.as_os_str().is_empty()) {
        Some(dir) => prepare_dir(dir),
        None => prepare_dir(Path::new(".")),
    }
}

/// Removes the temporary files that an atomic write of a killed process left in `dir`
/// (`.NAME.PID-SERIAL.tmp` for PNG, GIF and resume-state files, see [`img::atomic_write`]; only
/// those of the file `only` when given), except those of processes still running. Returns
/// how many were removed; errors are ignored.
pub(crate) fn remove_stale_temporaries(dir: &Path, only: Option<&str>) -> usize {
    let Ok(entries) = std::fs::read_dir(dir) else { return 0 };
    let own = std::process::id().to_string();
    let proc_fs = Path::new("/proc/self").exists();
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(name) = name.to_str() else { continue };
        let Some(inner) = name.strip_prefix('.').and_then(|n| n.strip_suffix(".tmp")) else { continue };
        let Some((target, pid)) = inner.rsplit_once('.') else { continue };
        // `PID` or `PID-SERIAL` (several writers in one process).
        let pid = pid.split_once('-').map_or(pid, |(p, _)| p);
        let ours = match only {
            Some(file) => target == file,
            None => [".png", ".gif", ".state", ".toml"].iter().any(|ext| target.ends_with(ext)),
        };
        if !ours || pid.is_empty() || !pid.bytes().all(|b| b.is_ascii_digit()) || pid == own {
            continue;
        }
        if proc_fs && Path::new("/proc").join(pid).exists() {
            continue; // another render is writing it right now
        }
        if entry.file_type().map(|t| t.is_file()).unwrap_or(false) && std::fs::remove_file(entry.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_paths_are_one_based_and_sortable() {
        let d = Path::new("out");
        assert_eq!(frame_path(d, 0, 24), Path::new("out/0001.png"));
        assert_eq!(frame_path(d, 9998, 9999), Path::new("out/9999.png"));
        assert_eq!(frame_path(d, 0, 10_000), Path::new("out/00001.png"));
        assert_eq!(frame_path(d, 9999, 10_000), Path::new("out/10000.png"));
        assert_eq!(frame_path(d, 0, 0), Path::new("out/0001.png"));
    }

    #[test]
    fn stale_temporaries_of_dead_processes_are_removed() {
        let dir = std::env::temp_dir().join(format!("fm-output-stale-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        // A pid that cannot be running (above the Linux maximum 2^22).
        let dead = 4_999_999;
        let own = std::process::id();
        let names = [
            format!(".0003.png.{dead}-7.tmp"),
            format!(".demo.gif.{dead}.tmp"),
            format!(".0004.png.{own}.tmp"),
            format!(".notes.txt.{dead}.tmp"),
            "0001.png".to_string(),
            ".hidden".to_string(),
        ];
        for n in &names {
            std::fs::write(dir.join(n), b"x").unwrap();
        }
        assert_eq!(remove_stale_temporaries(&dir, Some("other.gif")), 0);
        assert_eq!(remove_stale_temporaries(&dir, None), 2);
        let mut left: Vec<String> =
            std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        left.sort();
        assert_eq!(
            left,
            [format!(".0004.png.{own}.tmp"), ".hidden".into(), format!(".notes.txt.{dead}.tmp"), "0001.png".into()]
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
