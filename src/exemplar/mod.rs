//! Style exemplars: short sequences of paint spreading on paper, with masks of where the
//! paint is, and their metadata (`exemplar.toml`).
//!
//! An exemplar is a folder holding `frames/0001.png …` (RGB), `masks/0001.png …` (white where
//! paint is present) and `exemplar.toml` ([`ExemplarMeta`]). This module
//!
//! * loads and validates folders ([`Exemplar::load`]) and writes them atomically
//!   ([`Exemplar::save`]);
//! * finds exemplars by path or by name in a [`SearchPath`] — `--exemplar-dir` folders, the
//!   `FLUIDYMATION_EXEMPLARS` folders, the user's data folder and the set bundled into the
//!   binary ([`find`], [`list`], [`DEFAULT`]);
//! * generates watercolor exemplars by simulation ([`generate`]);
//! * imports real footage ([`import`]);
//! * estimates the border width `b` ([`border`]) and draws contact sheets ([`contact_sheet`]).
//!
//! ```no_run
//! use fluidymation::exemplar::{self, SearchPath};
//! let ex = exemplar::find(exemplar::DEFAULT, &SearchPath::standard(&[]))?;
//! println!("{}: {} frames of {}x{}", ex.meta.name, ex.len(), ex.width(), ex.height());
//! # Ok::<(), fluidymation::Error>(())
//! ```

pub mod border;
mod bundled;
pub(crate) mod cache;
pub mod generate;
pub mod import;
mod search;
mod sheet;

pub use search::{DEFAULT, ENV_VAR, ExemplarInfo, Location, Origin, SearchPath, find, list, user_dir, validate_name};
pub use sheet::contact_sheet;

use crate::error::{Error, Result};
use crate::img::{self, Plane, Rgb};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Largest exemplar side accepted when loading, pixels.
pub const MAX_SIDE: usize = 4096;
/// Largest number of exemplar frames accepted when loading.
pub const MAX_FRAMES: usize = 10_000;

/// The contents of `exemplar.toml`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ExemplarMeta {
    /// Short name, used to refer to the exemplar (`--exemplar NAME`).
    pub name: String,
    /// One line describing its character.
    #[serde(default)]
    pub description: String,
    /// Frame rate of the recording.
    #[serde(default = "default_fps")]
    pub fps: f32,
    /// Color of the bare paper, `#rrggbb`.
    pub paper: String,
    /// Dominant pigment color, `#rrggbb`.
    #[serde(default)]
    pub pigment: String,
    /// Recommended border width b in pixels (thesis `--border-width`).
    #[serde(default = "default_border")]
    pub border_width: f32,
    /// Recommended scale (thesis `--src-scale`).
    #[serde(default = "one_f32")]
    pub scale: f32,
    /// Recommended speed, the frame step (thesis `--src-speed`).
    #[serde(default = "one_usize")]
    pub speed: usize,
    /// Seed, for generated exemplars.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Generator parameters, for generated exemplars.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub generator: Option<toml::Table>,
    /// License of the frames.
    #[serde(default)]
    pub license: String,
    /// Where the frames come from.
    #[serde(default)]
    pub origin: String,
}

impl ExemplarMeta {
    /// Metadata for an exemplar made in memory (a keyframe's painting, frames a program made):
    /// `name`, the paper color `paper`, and the defaults `exemplar.toml` has for the rest (24
    /// fps, border width 10, scale and speed 1, no pigment, description, license or origin).
    pub fn new(name: &str, paper: Rgb) -> ExemplarMeta {
        ExemplarMeta {
            name: name.into(),
            description: String::new(),
            fps: default_fps(),
            paper: hex_color(paper),
            pigment: String::new(),
            border_width: default_border(),
            scale: one_f32(),
            speed: one_usize(),
            seed: None,
            generator: None,
            license: String::new(),
            origin: String::new(),
        }
    }
}

fn default_fps() -> f32 {
    24.0
}
fn default_border() -> f32 {
    10.0
}
fn one_f32() -> f32 {
    1.0
}
fn one_usize() -> usize {
    1
}

/// A loaded exemplar: `S^rgb` and `S^mask`.
#[derive(Clone, Debug)]
pub struct Exemplar {
    /// The folder it was loaded from, if any.
    pub dir: Option<PathBuf>,
    /// Its metadata.
    pub meta: ExemplarMeta,
    /// `S^rgb`, sRGB in `0..=1`.
    pub frames: Vec<Plane<Rgb>>,
    /// `S^mask` as coverage in `0..=1`.
    pub masks: Vec<Plane<f32>>,
}

/// Parses `#rrggbb` into RGB in `0..=1`.
pub fn parse_hex_color(s: &str) -> Option<Rgb> {
    let h = s.trim().strip_prefix('#')?;
    if h.len() != 6 || !h.is_ascii() {
        return None;
    }
    let c = |i: usize| u8::from_str_radix(&h[i..i + 2], 16).ok().map(|v| v as f32 / 255.0);
    Some([c(0)?, c(2)?, c(4)?])
}

/// `#rrggbb` of an sRGB color in `0..=1`.
pub fn hex_color(c: Rgb) -> String {
    let b = |v: f32| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
    format!("#{:02x}{:02x}{:02x}", b(c[0]), b(c[1]), b(c[2]))
}

/// One file of an exemplar held in memory: a name to report in errors, and its bytes.
pub(crate) struct FileBytes {
    pub path: PathBuf,
    pub bytes: std::borrow::Cow<'static, [u8]>,
}

fn decode(f: &FileBytes) -> Result<image::DynamicImage> {
    img::decode(&f.bytes, &f.path, MAX_SIDE as u32)
}

fn decode_rgb(f: &FileBytes) -> Result<Plane<Rgb>> {
    let img = decode(f)?.to_rgb8();
    let (w, h) = (img.width() as usize, img.height() as usize);
    let data = img.pixels().map(|p| p.0.map(|v| v as f32 / 255.0)).collect();
    Plane::from_vec(w, h, data).ok_or_else(|| Error::image(&f.path, "inconsistent image size"))
}

/// A mask as coverage: the alpha channel when there is a non-opaque one, else luminance.
fn decode_mask(f: &FileBytes) -> Result<Plane<f32>> {
    let img = decode(f)?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let data: Vec<f32> = if img.color().has_alpha() && img.to_rgba8().pixels().any(|p| p[3] < 255) {
        img.to_rgba8().pixels().map(|p| p[3] as f32 / 255.0).collect()
    } else {
        img.to_luma8().pixels().map(|p| p[0] as f32 / 255.0).collect()
    };
    Plane::from_vec(w, h, data).ok_or_else(|| Error::image(&f.path, "inconsistent image size"))
}

/// Checks the metadata's values (colors, positive numbers); `path` names `exemplar.toml`.
fn validate_meta(meta: &ExemplarMeta, path: &Path) -> Result<()> {
    let bad = |msg: String| Err(Error::exemplar(path, msg));
    if meta.name.trim().is_empty() {
        return bad("'name' is empty".into());
    }
    if parse_hex_color(&meta.paper).is_none() {
        return bad(format!("paper color '{}' is not #rrggbb", meta.paper));
    }
    if !meta.pigment.is_empty() && parse_hex_color(&meta.pigment).is_none() {
        return bad(format!("pigment color '{}' is not #rrggbb", meta.pigment));
    }
    for (name, v, lo, hi) in [
        ("fps", meta.fps, 0.01, 1000.0),
        ("border_width", meta.border_width, 0.5, 1000.0),
        ("scale", meta.scale, 0.01, 100.0),
    ] {
        if !(v.is_finite() && (lo..=hi).contains(&v)) {
            return bad(format!("'{name}' is {v} but must be in {lo}–{hi}"));
        }
    }
    if !(1..=100).contains(&meta.speed) {
        return bad(format!("'speed' is {} but must be in 1–100", meta.speed));
    }
    Ok(())
}

/// Parses `exemplar.toml` text; `path` names the file in errors.
pub(crate) fn parse_meta(text: &str, path: &Path) -> Result<ExemplarMeta> {
    let meta: ExemplarMeta = toml::from_str(text).map_err(|e| Error::toml(path, e))?;
    validate_meta(&meta, path)?;
    Ok(meta)
}

impl Exemplar {
    /// Loads and validates an exemplar folder: `exemplar.toml` must parse and hold valid
    /// values, there must be as many masks as frames and at least one of each (one: a still
    /// exemplar), all images must
    /// have the same size (at most [`MAX_SIDE`]) and no mask may be empty. Errors name the
    /// offending file.
    pub fn load(dir: &Path) -> Result<Exemplar> {
        let toml_path = dir.join("exemplar.toml");
        if !dir.exists() {
            return Err(Error::exemplar(dir, "no such file or folder"));
        }
        if !dir.is_dir() {
            return Err(Error::exemplar(dir, "is a file, neither an exemplar folder nor a PNG or JPEG image"));
        }
        if !toml_path.is_file() {
            return Err(Error::exemplar(
                dir,
                "has no exemplar.toml; is this an exemplar folder? (frames of paint are made into one with \
                 `fluidymation exemplar import`)",
            ));
        }
        let text = std::fs::read_to_string(&toml_path).map_err(|e| Error::io(&toml_path, e))?;
        let meta = parse_meta(&text, &toml_path)?;
        let read_all = |sub: &str, exts: &[&str]| -> Result<Vec<FileBytes>> {
            if !dir.join(sub).is_dir() {
                return Err(Error::exemplar(
                    dir,
                    format!(
                        "has no {sub}/ folder; an exemplar folder holds exemplar.toml, frames/0001.png … (the \
                         paint) and masks/0001.png … (white where there is paint, one per frame)"
                    ),
                ));
            }
            let files = crate::seq::list_sequence(&dir.join(sub), exts)?;
            if files.len() > MAX_FRAMES {
                return Err(Error::Limit {
                    path: dir.join(sub),
                    what: "frame count".into(),
                    value: files.len() as f64,
                    limit: MAX_FRAMES as f64,
                });
            }
            files
                .into_iter()
                .map(|path| {
                    let bytes = std::fs::read(&path).map_err(|e| Error::io(&path, e))?;
                    Ok(FileBytes { path, bytes: bytes.into() })
                })
                .collect()
        };
        let frames = read_all("frames", &["png", "jpg", "jpeg"])?;
        let masks = read_all("masks", &["png"])?;
        let mut ex = Exemplar::from_files(dir, meta, &frames, &masks)?;
        ex.dir = Some(dir.to_path_buf());
        Ok(ex)
    }

    /// Decodes and validates an exemplar from in-memory files (frames and masks in order).
    pub(crate) fn from_files(
        label: &Path,
        meta: ExemplarMeta,
        frame_files: &[FileBytes],
        mask_files: &[FileBytes],
    ) -> Result<Exemplar> {
        if frame_files.len() != mask_files.len() {
            return Err(Error::exemplar(
                label,
                format!("{} frames but {} masks; every frame needs a mask", frame_files.len(), mask_files.len()),
            ));
        }
        if frame_files.is_empty() {
            return Err(Error::exemplar(label, "an exemplar needs at least one frame"));
        }
        let mut frames = Vec::with_capacity(frame_files.len());
        let mut masks = Vec::with_capacity(frame_files.len());
        for (f, m) in frame_files.iter().zip(mask_files) {
            let rgb = decode_rgb(f)?;
            let mask = decode_mask(m)?;
            let expected = frames.first().map(|p: &Plane<Rgb>| p.size()).unwrap_or(rgb.size());
            if expected.0 > MAX_SIDE || expected.1 > MAX_SIDE || expected.0 == 0 || expected.1 == 0 {
                return Err(Error::Limit {
                    path: f.path.clone(),
                    what: "exemplar side".into(),
                    value: expected.0.max(expected.1) as f64,
                    limit: MAX_SIDE as f64,
                });
            }
            for (path, size) in [(&f.path, rgb.size()), (&m.path, mask.size())] {
                if size != expected {
                    return Err(Error::SizeMismatch {
                        path: path.clone(),
                        expected: (expected.0 as u32, expected.1 as u32),
                        found: (size.0 as u32, size.1 as u32),
                    });
                }
            }
            if !mask.data().iter().any(|&v| v >= 0.5) {
                return Err(Error::exemplar(&m.path, "mask is empty (no pixel is white)"));
            }
            frames.push(rgb);
            masks.push(mask);
        }
        Ok(Exemplar { dir: None, meta, frames, masks })
    }

    /// Checks an in-memory exemplar the way [`Exemplar::load`] checks a folder.
    pub fn validate(&self) -> Result<()> {
        let label = self.dir.clone().unwrap_or_else(|| PathBuf::from(&self.meta.name));
        validate_meta(&self.meta, &label.join("exemplar.toml"))?;
        if self.frames.is_empty() || self.frames.len() != self.masks.len() {
            return Err(Error::exemplar(
                &label,
                format!(
                    "needs at least one frame and one mask per frame ({} frames, {} masks)",
                    self.frames.len(),
                    self.masks.len()
                ),
            ));
        }
        let size = self.frames[0].size();
        for (i, (f, m)) in self.frames.iter().zip(&self.masks).enumerate() {
            if f.size() != size || m.size() != size {
                return Err(Error::exemplar(
                    &label,
                    format!("frame {} is not {}x{} like frame 1", i + 1, size.0, size.1),
                ));
            }
            if !m.data().iter().any(|&v| v >= 0.5) {
                return Err(Error::exemplar(&label, format!("mask {} is empty", i + 1)));
            }
        }
        Ok(())
    }

    /// Writes the exemplar to the folder `dir` (`exemplar.toml`, `frames/0001.png …`,
    /// `masks/0001.png …`). Everything is written into a hidden temporary folder next to
    /// `dir`, which is renamed into place only when complete, so an interrupted or failed
    /// write never leaves a half-written exemplar. An existing `dir` is an error unless
    /// `overwrite`; then it is replaced (also by renames).
    pub fn save(&self, dir: &Path, overwrite: bool) -> Result<()> {
        self.validate()?;
        if dir.exists() && !overwrite {
            return Err(Error::exemplar(dir, "already exists (choose another name, or overwrite it)"));
        }
        let parent = match dir.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&parent).map_err(|e| Error::io(&parent, e))?;
        let base = dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "exemplar".into());
        let unique =
            format!("{}-{}", std::process::id(), SAVE_COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed));
        let tmp = parent.join(format!(".{base}.partial-{unique}"));
        let result = self.write_into(&tmp);
        if let Err(e) = result {
            let _ = std::fs::remove_dir_all(&tmp);
            return Err(e);
        }
        if dir.exists() {
            let old = parent.join(format!(".{base}.old-{unique}"));
            std::fs::rename(dir, &old).map_err(|e| {
                let _ = std::fs::remove_dir_all(&tmp);
                Error::io(dir, e)
            })?;
            if let Err(e) = std::fs::rename(&tmp, dir) {
                let _ = std::fs::rename(&old, dir);
                let _ = std::fs::remove_dir_all(&tmp);
                return Err(Error::io(dir, e));
            }
            let _ = std::fs::remove_dir_all(&old);
        } else if let Err(e) = std::fs::rename(&tmp, dir) {
            let _ = std::fs::remove_dir_all(&tmp);
            return Err(Error::io(dir, e));
        }
        Ok(())
    }

    fn write_into(&self, tmp: &Path) -> Result<()> {
        if tmp.exists() {
            std::fs::remove_dir_all(tmp).map_err(|e| Error::io(tmp, e))?;
        }
        for sub in ["frames", "masks"] {
            let d = tmp.join(sub);
            std::fs::create_dir_all(&d).map_err(|e| Error::io(&d, e))?;
        }
        // PNG encoding dominates the time of a write: encode frames in parallel (the bytes
        // do not depend on the thread count).
        use rayon::prelude::*;
        (0..self.frames.len()).into_par_iter().try_for_each(|i| -> Result<()> {
            let (f, m) = (&self.frames[i], &self.masks[i]);
            let name = format!("{:04}.png", i + 1);
            let rgb: Vec<u8> = f.data().iter().flat_map(|c| c.map(to_u8)).collect();
            write_png(&tmp.join("frames").join(&name), f.width(), f.height(), image::ExtendedColorType::Rgb8, &rgb)?;
            let mask: Vec<u8> = m.data().iter().map(|&v| if v >= 0.5 { 255 } else { 0 }).collect();
            write_png(&tmp.join("masks").join(&name), m.width(), m.height(), image::ExtendedColorType::L8, &mask)
        })?;
        let path = tmp.join("exemplar.toml");
        let text = toml::to_string(&self.meta).map_err(|e| Error::toml(&path, e))?;
        img::atomic_write(&path, |w| w.write_all(text.as_bytes()))
    }

    /// Width of the frames.
    pub fn width(&self) -> usize {
        self.frames[0].width()
    }

    /// Height of the frames.
    pub fn height(&self) -> usize {
        self.frames[0].height()
    }

    /// Number of frames `l_S`.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// True without frames (never for a loaded exemplar).
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The paper color.
    pub fn paper(&self) -> Rgb {
        parse_hex_color(&self.meta.paper).unwrap_or([1.0, 1.0, 1.0])
    }

    /// The binary mask of frame `i` (coverage ≥ ½).
    pub fn mask(&self, i: usize) -> img::Mask {
        self.masks[i].threshold(0.5)
    }
}

static SAVE_COUNTER: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

#[inline]
fn to_u8(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

/// Writes a PNG with the strongest compression (bundled exemplars are embedded in the binary).
fn write_png(path: &Path, w: usize, h: usize, color: image::ExtendedColorType, bytes: &[u8]) -> Result<()> {
    use image::ImageEncoder;
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    img::atomic_write(path, |out| {
        PngEncoder::new_with_quality(out, CompressionType::Best, FilterType::Adaptive)
            .write_image(bytes, w as u32, h as u32, color)
            .map_err(std::io::Error::other)
    })
}
