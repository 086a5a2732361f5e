//! Style exemplars: short sequences of paint spreading on paper, with masks of where the
//! paint is, and their metadata (`exemplar.toml`).
//!
//! An exemplar is a folder holding `frames/0001.png …` (RGB), `masks/0001.png …` (white where
//! paint is present) and `exemplar.toml`.

use crate::error::{Error, Result};
use crate::img::{self, Plane, Rgb};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

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

impl Exemplar {
    /// Loads and validates an exemplar folder.
    pub fn load(dir: &Path) -> Result<Exemplar> {
        let toml_path = dir.join("exemplar.toml");
        let text = std::fs::read_to_string(&toml_path).map_err(|e| Error::io(&toml_path, e))?;
        let meta: ExemplarMeta =
            toml::from_str(&text).map_err(|e| Error::Toml { path: toml_path.clone(), message: e.to_string() })?;
        if parse_hex_color(&meta.paper).is_none() {
            return Err(Error::exemplar(&toml_path, format!("paper color '{}' is not #rrggbb", meta.paper)));
        }
        let frame_files = crate::seq::list_sequence(&dir.join("frames"), &["png", "jpg", "jpeg"])?;
        let mask_files = crate::seq::list_sequence(&dir.join("masks"), &["png"])?;
        if frame_files.len() != mask_files.len() {
            return Err(Error::exemplar(
                dir,
                format!("{} frames but {} masks; every frame needs a mask", frame_files.len(), mask_files.len()),
            ));
        }
        if frame_files.len() < 2 {
            return Err(Error::exemplar(dir, "an exemplar needs at least 2 frames"));
        }
        let mut frames = Vec::with_capacity(frame_files.len());
        let mut masks = Vec::with_capacity(frame_files.len());
        for (f, m) in frame_files.iter().zip(&mask_files) {
            let rgb = img::load_rgb(f)?;
            let mask = img::load_gray(m)?;
            let expected = frames.first().map(|p: &Plane<Rgb>| p.size()).unwrap_or(rgb.size());
            for (path, size) in [(f, rgb.size()), (m, mask.size())] {
                if size != expected {
                    return Err(Error::SizeMismatch {
                        path: path.clone(),
                        expected: (expected.0 as u32, expected.1 as u32),
                        found: (size.0 as u32, size.1 as u32),
                    });
                }
            }
            if !mask.data().iter().any(|&v| v >= 0.5) {
                return Err(Error::exemplar(m, "mask is empty (no pixel is white)"));
            }
            frames.push(rgb);
            masks.push(mask);
        }
        Ok(Exemplar { dir: Some(dir.to_path_buf()), meta, frames, masks })
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
}
