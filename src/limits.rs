//! The memory a render will need, estimated before any work, against a documented limit.
//!
//! Measured on the bundled demo (400×400 to 1200×1200, peak resident memory): a render needs
//! about [`BASE_BYTES`] plus, per pixel of the canvas, [`STYLIZED_BYTES`] for every stylized
//! layer (its target guides, the engine's pyramid and state, its flat rendering) and
//! [`FLAT_BYTES`] for every layer left flat; `--eval` keeps 5 bytes a pixel per frame and
//! stylized layer on top. The limit is [`DEFAULT_MEMORY_LIMIT`] or the machine's memory if
//! smaller; the environment variable `FLUIDYMATION_MEMORY_LIMIT` sets another (`24G`,
//! `8000M`, or `off`).

use crate::error::{Error, Result};
use std::path::Path;

/// Memory of a render that does not grow with the canvas (exemplars, buffers), bytes.
pub const BASE_BYTES: u64 = 128 << 20;
/// Memory per canvas pixel of a stylized layer, bytes.
pub const STYLIZED_BYTES: u64 = 500;
/// Memory per canvas pixel of a layer left flat, bytes.
pub const FLAT_BYTES: u64 = 110;
/// Memory per canvas pixel and frame that `--eval` keeps of a stylized layer, bytes.
pub const EVAL_BYTES: u64 = 5;
/// Memory per canvas pixel of `inspect`'s mask and guide previews, bytes (one region at a
/// time). Measured on the demo's canvas set to 3000×3000, six frames, peak resident memory:
/// 584 MB writing masks, 734 MB writing guides (65 and 82 bytes a pixel with everything else).
pub const PREVIEW_BYTES: u64 = 90;
/// The limit when the machine's memory is not smaller and no other is set: 16 GiB.
pub const DEFAULT_MEMORY_LIMIT: u64 = 16 << 30;
/// The environment variable that sets the limit.
pub const MEMORY_LIMIT_VAR: &str = "FLUIDYMATION_MEMORY_LIMIT";

/// What a render holds in memory at once.
#[derive(Clone, Copy, Debug)]
pub struct RenderShape {
    /// Canvas width and height, pixels.
    pub width: u32,
    /// Canvas height, pixels.
    pub height: u32,
    /// Layers painted with an exemplar.
    pub stylized: usize,
    /// Layers left flat.
    pub flat: usize,
    /// Frames whose layers are kept for `--eval` (0 without it).
    pub kept_frames: usize,
}

impl RenderShape {
    /// The estimated peak memory, bytes.
    pub fn memory(&self) -> u64 {
        let px = self.width as u64 * self.height as u64;
        let per_stylized = STYLIZED_BYTES.saturating_add(EVAL_BYTES.saturating_mul(self.kept_frames as u64));
        BASE_BYTES
            .saturating_add(px.saturating_mul(per_stylized).saturating_mul(self.stylized as u64))
            .saturating_add(px.saturating_mul(FLAT_BYTES).saturating_mul(self.flat as u64))
    }
}

/// Parses `24G`, `8000M`, `512K` or a plain byte count.
fn parse_size(s: &str) -> Option<u64> {
    let s = s.trim();
    let (num, unit) = match s.char_indices().find(|(_, c)| c.is_ascii_alphabetic()) {
        Some((i, _)) => (&s[..i], s[i..].trim_end_matches(['b', 'B', 'i'])),
        None => (s, ""),
    };
    let v: f64 = num.trim().parse().ok()?;
    let mul = match unit.to_ascii_uppercase().as_str() {
        "" => 1u64,
        "K" => 1 << 10,
        "M" => 1 << 20,
        "G" => 1 << 30,
        "T" => 1 << 40,
        _ => return None,
    };
    (v.is_finite() && v > 0.0).then_some((v * mul as f64) as u64)
}

/// The machine's memory, where it can be read (Linux).
fn physical_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// The memory limit in force: `FLUIDYMATION_MEMORY_LIMIT`, else the smaller of
/// [`DEFAULT_MEMORY_LIMIT`] and the machine's memory; `None` when turned off.
pub fn memory_limit() -> Result<Option<u64>> {
    match std::env::var(MEMORY_LIMIT_VAR) {
        Ok(v) if v.trim().eq_ignore_ascii_case("off") => Ok(None),
        Ok(v) => parse_size(&v)
            .map(Some)
            .ok_or_else(|| Error::param(MEMORY_LIMIT_VAR, v, "a size such as 24G or 8000M, or off")),
        Err(_) => Ok(Some(physical_memory().map_or(DEFAULT_MEMORY_LIMIT, |m| m.min(DEFAULT_MEMORY_LIMIT)))),
    }
}

/// Refuses a render of `input` whose estimated memory is over [`memory_limit`].
pub fn check_render_memory(input: &Path, shape: &RenderShape) -> Result<()> {
    let what = format!(
        "the memory this render needs, estimated in MiB ({} stylized and {} flat layers of {}x{} px{}; \
         use --scale, stylize fewer layers at a time with --style LAYER=none, or set {MEMORY_LIMIT_VAR})",
        shape.stylized,
        shape.flat,
        shape.width,
        shape.height,
        if shape.kept_frames > 0 { format!(", {} frames kept for --eval", shape.kept_frames) } else { String::new() }
    );
    check(input, shape.memory(), what)
}

/// The estimated peak memory of `inspect`'s mask or guide previews of a `width × height`
/// canvas, bytes ([`PREVIEW_BYTES`]).
pub fn preview_memory(width: u32, height: u32) -> u64 {
    BASE_BYTES.saturating_add((width as u64 * height as u64).saturating_mul(PREVIEW_BYTES))
}

/// Refuses `inspect`'s mask or guide previews of `input` (a `width × height` canvas) whose
/// estimated memory is over [`memory_limit`].
pub fn check_preview_memory(input: &Path, width: u32, height: u32) -> Result<()> {
    let what = format!(
        "the memory the mask and guide previews need, estimated in MiB (one layer of {width}x{height} px at a time; \
         use --scale, or set {MEMORY_LIMIT_VAR})"
    );
    check(input, preview_memory(width, height), what)
}

/// [`Error::Limit`] when `need` bytes are over the limit in force.
fn check(input: &Path, need: u64, what: String) -> Result<()> {
    let Some(limit) = memory_limit()? else { return Ok(()) };
    if need <= limit {
        return Ok(());
    }
    let mib = |b: u64| (b >> 20) as f64;
    Err(Error::Limit { path: input.to_path_buf(), what, value: mib(need), limit: mib(limit) })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimates_follow_the_measurements() {
        // The demo at 1x, 2x and 3x (5 stylized layers): measured 508, 1670 and 3556 MB.
        for (side, measured) in [(400u32, 508e6), (800, 1670e6), (1200, 3556e6)] {
            let s = RenderShape { width: side, height: side, stylized: 5, flat: 0, kept_frames: 0 };
            let ratio = s.memory() as f64 / measured;
            assert!((0.85..1.25).contains(&ratio), "{side}: {} vs {measured}", s.memory());
        }
        // One stylized and four flat layers at 2x: measured 705 MB.
        let s = RenderShape { width: 800, height: 800, stylized: 1, flat: 4, kept_frames: 0 };
        assert!((0.85..1.25).contains(&(s.memory() as f64 / 705e6)), "{}", s.memory());
    }

    #[test]
    fn preview_estimates_cover_the_measurements() {
        // Masks and guides of the demo's canvas at 3000x3000: measured 584 and 734 MB.
        let e = preview_memory(3000, 3000) as f64;
        for measured in [584e6, 734e6] {
            assert!((1.0..1.7).contains(&(e / measured)), "{e} vs {measured}");
        }
    }

    #[test]
    fn sizes_parse() {
        assert_eq!(parse_size("24G"), Some(24 << 30));
        assert_eq!(parse_size("8000M"), Some(8000 << 20));
        assert_eq!(parse_size("1.5GiB"), Some(3 << 29));
        assert_eq!(parse_size("4096"), Some(4096));
        assert_eq!(parse_size("lots"), None);
        assert_eq!(parse_size("-3G"), None);
    }
}
