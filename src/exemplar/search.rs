//! Finding exemplars by path or by name.
//!
//! Wherever an exemplar is asked for, a path to a folder works, and so does a name. A name is
//! looked up, first match wins, in
//! 1. the `--exemplar-dir` folders, in the order given;
//! 2. the folders listed in `FLUIDYMATION_EXEMPLARS` (separated like `PATH`: `:` on Unix,
//!    `;` on Windows);
//! 3. the user's exemplar folder ([`user_dir`]);
//! 4. the bundled set, embedded in the binary.
//!
//! In each folder, the exemplar `NAME` is the sub-folder `NAME` holding an `exemplar.toml`.

use super::{Exemplar, bundled};
use crate::error::{Error, Result};
use std::fmt;
use std::path::{Path, PathBuf};

/// The exemplar `render` uses when none is given: a steady, medium-rimmed blue bloom.
pub const DEFAULT: &str = "blue-bloom";

/// The environment variable listing extra exemplar folders.
pub const ENV_VAR: &str = "FLUIDYMATION_EXEMPLARS";

/// Why a folder is in the search path (where it came from).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origin {
    /// Given on the command line (`--exemplar-dir`).
    Argument,
    /// Listed in `FLUIDYMATION_EXEMPLARS`.
    Environment,
    /// The user's data folder.
    User,
}

impl Origin {
    fn label(self) -> &'static str {
        match self {
            Origin::Argument => "--exemplar-dir",
            Origin::Environment => ENV_VAR,
            Origin::User => "user folder",
        }
    }
}

/// Where an exemplar was found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Location {
    /// A folder on disk (the exemplar's own folder), and why it was searched.
    Folder(PathBuf, Option<Origin>),
    /// Embedded in the binary.
    Bundled,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Folder(p, Some(s)) => write!(f, "{} ({})", p.display(), s.label()),
            Location::Folder(p, None) => write!(f, "{}", p.display()),
            Location::Bundled => f.write_str("bundled"),
        }
    }
}

/// Where to look for exemplars by name. [`SearchPath::standard`] gives the usual order;
/// [`SearchPath::new`] an empty one to build up (useful in tests).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SearchPath {
    /// Folders searched in order, each with the reason it is searched.
    pub dirs: Vec<(PathBuf, Origin)>,
    /// Whether the bundled set is searched last.
    pub bundled: bool,
}

impl SearchPath {
    /// An empty search path: no folders, no bundled set.
    pub fn new() -> Self {
        SearchPath::default()
    }

    /// The standard search path: `extra` (`--exemplar-dir`), then `FLUIDYMATION_EXEMPLARS`,
    /// then [`user_dir`], then the bundled set.
    pub fn standard(extra: &[PathBuf]) -> Self {
        let mut sp = SearchPath::new();
        for d in extra {
            sp = sp.dir(d.clone(), Origin::Argument);
        }
        if let Some(v) = std::env::var_os(ENV_VAR) {
            for d in std::env::split_paths(&v).filter(|d| !d.as_os_str().is_empty()) {
                sp = sp.dir(d, Origin::Environment);
            }
        }
        if let Some(d) = user_dir() {
            sp = sp.dir(d, Origin::User);
        }
        sp.with_bundled(true)
    }

    /// Appends a folder.
    pub fn dir(mut self, dir: impl Into<PathBuf>, source: Origin) -> Self {
        self.dirs.push((dir.into(), source));
        self
    }

    /// Includes (or not) the bundled set.
    pub fn with_bundled(mut self, yes: bool) -> Self {
        self.bundled = yes;
        self
    }

    /// The first folder of the given kind, e.g. where `exemplar generate` writes by default.
    pub fn first(&self, source: Origin) -> Option<&Path> {
        self.dirs.iter().find(|(_, s)| *s == source).map(|(d, _)| d.as_path())
    }
}

/// The user's exemplar folder:
/// * Linux and other Unix: `$XDG_DATA_HOME/fluidymation/exemplars`, or
///   `~/.local/share/fluidymation/exemplars` when `XDG_DATA_HOME` is unset or relative;
/// * macOS: `~/Library/Application Support/fluidymation/exemplars`;
/// * Windows: `%APPDATA%\fluidymation\exemplars`.
///
/// `None` when the home folder is unknown.
pub fn user_dir() -> Option<PathBuf> {
    let home = || std::env::var_os("HOME").filter(|h| !h.is_empty()).map(PathBuf::from);
    let base = if cfg!(windows) {
        std::env::var_os("APPDATA").filter(|h| !h.is_empty()).map(PathBuf::from)
    } else if cfg!(target_os = "macos") {
        home().map(|h| h.join("Library").join("Application Support"))
    } else {
        std::env::var_os("XDG_DATA_HOME")
            .map(PathBuf::from)
            .filter(|p| p.is_absolute())
            .or_else(|| home().map(|h| h.join(".local").join("share")))
    }?;
    Some(base.join("fluidymation").join("exemplars"))
}

/// True when `s` should be read as a path rather than a name.
fn looks_like_path(s: &str) -> bool {
    s.contains('/') || s.contains(std::path::MAIN_SEPARATOR) || s.starts_with('.') || s.starts_with('~')
}

/// Loads the exemplar `name_or_path`: a still exemplar imported on the fly when it is a PNG or
/// JPEG file ([`super::import::still`]), a folder when it is a path to one (or contains a path
/// separator), else the first exemplar of that name in `search`. An unknown name gives
/// [`Error::UnknownExemplar`] with the names that are available.
pub fn find(name_or_path: &str, search: &SearchPath) -> Result<Exemplar> {
    let p = Path::new(name_or_path);
    if super::import::is_still_image(p) {
        return super::import::still(p);
    }
    if p.join("exemplar.toml").is_file() || looks_like_path(name_or_path) {
        return Exemplar::load(p);
    }
    for (dir, _) in &search.dirs {
        let cand = dir.join(name_or_path);
        if cand.join("exemplar.toml").is_file() {
            return Exemplar::load(&cand);
        }
    }
    if search.bundled
        && let Some(b) = bundled::get(name_or_path)
    {
        return b.load();
    }
    // A folder of that name here that is not an exemplar (say, raw video frames): say so.
    if p.is_dir() {
        return Exemplar::load(p);
    }
    let mut available: Vec<String> = list(search).into_iter().filter(|i| !i.shadowed).map(|i| i.name).collect();
    available.sort();
    Err(Error::UnknownExemplar { name: name_or_path.to_string(), available })
}

/// What [`list`] tells about an exemplar (without decoding its frames).
#[derive(Clone, Debug, PartialEq)]
pub struct ExemplarInfo {
    /// The name to ask for it by (its folder name).
    pub name: String,
    /// Its one-line description.
    pub description: String,
    /// Frame width and height, pixels (0 × 0 when unreadable).
    pub size: (usize, usize),
    /// Number of frames.
    pub frames: usize,
    /// Recommended border width from its metadata, pixels.
    pub border_width: f32,
    /// Where it is.
    pub location: Location,
    /// True when an exemplar of the same name earlier in the search path hides this one.
    pub shadowed: bool,
}

/// Every exemplar in `search`, in search order. Folders whose `exemplar.toml` does not parse
/// are skipped with a warning.
pub fn list(search: &SearchPath) -> Vec<ExemplarInfo> {
    let mut out: Vec<ExemplarInfo> = Vec::new();
    let mut push = |mut info: ExemplarInfo| {
        info.shadowed = out.iter().any(|o| o.name == info.name);
        out.push(info);
    };
    for (dir, source) in &search.dirs {
        let Ok(rd) = std::fs::read_dir(dir) else { continue };
        let mut subs: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
        subs.sort();
        for sub in subs {
            let toml_path = sub.join("exemplar.toml");
            if !toml_path.is_file() {
                continue;
            }
            let name = sub.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
            let meta = match std::fs::read_to_string(&toml_path)
                .map_err(|e| Error::io(&toml_path, e))
                .and_then(|t| super::parse_meta(&t, &toml_path))
            {
                Ok(m) => m,
                Err(e) => {
                    log::warn!("skipping exemplar '{}': {}", name, e);
                    continue;
                }
            };
            let frames = crate::seq::list_sequence(&sub.join("frames"), &["png", "jpg", "jpeg"]).unwrap_or_default();
            let size = frames
                .first()
                .and_then(|f| image::image_dimensions(f).ok())
                .map(|(w, h)| (w as usize, h as usize))
                .unwrap_or((0, 0));
            push(ExemplarInfo {
                name,
                description: meta.description,
                size,
                frames: frames.len(),
                border_width: meta.border_width,
                location: Location::Folder(sub.clone(), Some(*source)),
                shadowed: false,
            });
        }
    }
    if search.bundled {
        for b in bundled::BUNDLED {
            let meta = super::parse_meta(b.toml, &b.label().join("exemplar.toml"));
            let (description, border_width) = meta.map(|m| (m.description, m.border_width)).unwrap_or_default();
            push(ExemplarInfo {
                name: b.name.to_string(),
                description,
                size: b.size().unwrap_or((0, 0)),
                frames: b.frames.len(),
                border_width,
                location: Location::Bundled,
                shadowed: false,
            });
        }
    }
    out
}

/// Checks that `name` can name an exemplar folder: 1–64 characters of letters, digits,
/// `-`, `_` and `.`, not starting with `.` or `-`.
pub fn validate_name(name: &str) -> Result<()> {
    let ok = !name.is_empty()
        && name.len() <= 64
        && !name.starts_with(['.', '-'])
        && name.chars().all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'));
    if ok {
        Ok(())
    } else {
        Err(Error::param("name", name, "1–64 letters, digits, '-', '_' or '.', not starting with '.' or '-'"))
    }
}
