//! The bundled exemplars, embedded into the binary by `build.rs` (`include_bytes!` of every
//! file under `exemplars/<name>/`), so they work from an installed binary. They are decoded
//! on demand, only when asked for.

use super::{Exemplar, FileBytes};
use crate::error::Result;
use std::borrow::Cow;
use std::path::{Path, PathBuf};

/// One embedded exemplar: its folder name and its files.
pub(crate) struct BundledExemplar {
    pub name: &'static str,
    pub toml: &'static str,
    pub frames: &'static [&'static [u8]],
    pub masks: &'static [&'static [u8]],
}

include!(concat!(env!("OUT_DIR"), "/bundled_exemplars.rs"));

/// The embedded exemplar called `name`.
pub(crate) fn get(name: &str) -> Option<&'static BundledExemplar> {
    BUNDLED.iter().find(|b| b.name == name)
}

impl BundledExemplar {
    /// The label used in error messages: `<bundled>/NAME`.
    pub fn label(&self) -> PathBuf {
        Path::new("<bundled>").join(self.name)
    }

    /// Decodes and validates it.
    pub fn load(&self) -> Result<Exemplar> {
        let label = self.label();
        let meta = super::parse_meta(self.toml, &label.join("exemplar.toml"))?;
        let files = |sub: &str, all: &'static [&'static [u8]]| -> Vec<FileBytes> {
            all.iter()
                .enumerate()
                .map(|(i, b)| FileBytes {
                    path: label.join(sub).join(format!("{:04}.png", i + 1)),
                    bytes: Cow::Borrowed(*b),
                })
                .collect()
        };
        Exemplar::from_files(&label, meta, &files("frames", self.frames), &files("masks", self.masks))
    }

    /// Width and height of its frames, read from the first PNG header (no decoding).
    pub fn size(&self) -> Option<(usize, usize)> {
        let first = self.frames.first()?;
        let reader = image::ImageReader::new(std::io::Cursor::new(*first)).with_guessed_format().ok()?;
        reader.into_dimensions().ok().map(|(w, h)| (w as usize, h as usize))
    }
}
