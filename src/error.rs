//! The library's one error type.
//!
//! Every variant carries what a user needs to fix the problem: the file, the layer or the
//! value, and what was expected. Messages are written for motion designers running the CLI.

use std::fmt;
use std::path::{Path, PathBuf};

/// A `Result` with the library's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in fluidymation.
#[derive(Debug)]
#[non_exhaustive]
pub enum Error {
    /// Reading or writing a file failed.
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A JSON file could not be parsed.
    Json {
        /// The file.
        path: PathBuf,
        /// 1-based line of the problem.
        line: usize,
        /// 1-based column of the problem.
        column: usize,
        /// What serde_json reported (its message ends with the position; the error's text
        /// then gives it only once).
        message: String,
        /// serde_json's own error ([`std::error::Error::source`]).
        source: Option<Box<dyn std::error::Error + Send + Sync>>,
    },
    /// A TOML file (exemplar metadata, styles file) could not be parsed.
    Toml {
        /// The file.
        path: PathBuf,
        /// What went wrong, with the location when known.
        message: String,
        /// The TOML parser's or writer's own error ([`std::error::Error::source`]).
        source: Option<Box<dyn std::error::Error + Send + Sync>>,
    },
    /// An animation file parsed but its content is not usable (missing `w`, NaN values, …).
    InvalidAnimation {
        /// The file.
        path: PathBuf,
        /// What is wrong and, where possible, what to do about it.
        message: String,
    },
    /// An image file could not be decoded or encoded.
    Image {
        /// The file.
        path: PathBuf,
        /// The decoder's message.
        message: String,
        /// The codec's own error where there is one ([`std::error::Error::source`]).
        source: Option<Box<dyn std::error::Error + Send + Sync>>,
    },
    /// Images of one sequence do not all have the same size.
    SizeMismatch {
        /// The offending file.
        path: PathBuf,
        /// Size of the first image of the sequence.
        expected: (u32, u32),
        /// Size of this file.
        found: (u32, u32),
    },
    /// An input has nothing in it (no frames, no layers, an empty mask …).
    Empty {
        /// The file or directory.
        path: PathBuf,
        /// What is missing.
        what: String,
    },
    /// A safety limit was exceeded (canvas side, frame count, element count).
    Limit {
        /// The file.
        path: PathBuf,
        /// What exceeded the limit, e.g. "canvas width".
        what: String,
        /// The value found.
        value: f64,
        /// The largest value allowed.
        limit: f64,
    },
    /// A parameter is outside its valid range.
    InvalidParam {
        /// The parameter's name (as on the command line).
        name: String,
        /// The value given.
        value: String,
        /// The allowed range or values.
        allowed: String,
    },
    /// An exemplar folder is malformed.
    Exemplar {
        /// The exemplar folder (or file inside it).
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// No exemplar of this name was found.
    UnknownExemplar {
        /// The name asked for.
        name: String,
        /// The names that exist.
        available: Vec<String>,
    },
    /// No layer of this name or index exists.
    UnknownLayer {
        /// The name or index asked for.
        name: String,
        /// The layers that exist.
        available: Vec<String>,
    },
    /// Something a command works from was never made: no interrupted render to resume, a
    /// layer that its render-layer job has not painted yet.
    Missing {
        /// Where it should be.
        path: PathBuf,
        /// What is missing and what to do.
        what: String,
    },
    /// A file the program wrote earlier was made with other options than this run's (another
    /// input, range, style or parameters): sound, but not this run's.
    Stale {
        /// The file.
        path: PathBuf,
        /// What differs and what to do.
        message: String,
    },
    /// A file the program wrote earlier (a checkpoint, a cache) is damaged or fails its checks.
    Corrupt {
        /// The file.
        path: PathBuf,
        /// What is wrong and what to do.
        message: String,
    },
    /// The work was cancelled through a progress callback.
    Cancelled,
}

impl Error {
    /// Shorthand for an [`Error::Io`] on `path`.
    pub fn io(path: impl AsRef<Path>, source: std::io::Error) -> Self {
        Error::Io { path: path.as_ref().to_path_buf(), source }
    }

    /// Shorthand for an [`Error::InvalidParam`].
    pub fn param(name: &str, value: impl fmt::Display, allowed: impl Into<String>) -> Self {
        Error::InvalidParam { name: name.to_string(), value: value.to_string(), allowed: allowed.into() }
    }

    /// Shorthand for an [`Error::InvalidAnimation`].
    pub fn animation(path: impl AsRef<Path>, message: impl Into<String>) -> Self {
        Error::InvalidAnimation { path: path.as_ref().to_path_buf(), message: message.into() }
    }

    /// Shorthand for an [`Error::Image`] without a source error.
    pub fn image(path: impl AsRef<Path>, message: impl fmt::Display) -> Self {
        Error::Image { path: path.as_ref().to_path_buf(), message: message.to_string(), source: None }
    }

    /// An [`Error::Image`] from the codec's error, kept as its source.
    pub fn image_codec(path: impl AsRef<Path>, error: impl std::error::Error + Send + Sync + 'static) -> Self {
        Error::Image { path: path.as_ref().to_path_buf(), message: error.to_string(), source: Some(Box::new(error)) }
    }

    /// An [`Error::Toml`] from the TOML parser's or writer's error, kept as its source.
    pub fn toml(path: impl AsRef<Path>, error: impl std::error::Error + Send + Sync + 'static) -> Self {
        Error::Toml { path: path.as_ref().to_path_buf(), message: error.to_string(), source: Some(Box::new(error)) }
    }

    /// Shorthand for an [`Error::Exemplar`].
    pub fn exemplar(path: impl AsRef<Path>, message: impl Into<String>) -> Self {
        Error::Exemplar { path: path.as_ref().to_path_buf(), message: message.into() }
    }
}

/// A number for a message: plain, or in scientific notation when very large or small.
pub(crate) fn number(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-3..1e9).contains(&v.abs()) { format!("{v:e}") } else { format!("{v}") }
}

fn list(names: &[String]) -> String {
    if names.is_empty() { "(none)".to_string() } else { names.join(", ") }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Io { path, source } => write!(f, "'{}': {}", path.display(), source),
            Error::Json { path, line, column, message, .. } => {
                // serde_json's message already ends with the position: say it once.
                if *line == 0 || message.ends_with(&format!(" at line {line} column {column}")) {
                    write!(f, "'{}' is not valid JSON: {}", path.display(), message)
                } else {
                    write!(f, "'{}' is not valid JSON at line {}, column {}: {}", path.display(), line, column, message)
                }
            }
            Error::Toml { path, message, .. } => write!(f, "'{}' is not valid TOML: {}", path.display(), message),
            Error::InvalidAnimation { path, message } => write!(f, "'{}': {}", path.display(), message),
            Error::Image { path, message, .. } => write!(f, "image '{}': {}", path.display(), message),
            Error::SizeMismatch { path, expected, found } => write!(
                f,
                "'{}' is {}x{} but the sequence's first image is {}x{}; all frames must have the same size",
                path.display(),
                found.0,
                found.1,
                expected.0,
                expected.1
            ),
            Error::Empty { path, what } => write!(f, "'{}': {}", path.display(), what),
            Error::Limit { path, what, value, limit } => {
                write!(
                    f,
                    "'{}': {} is {} but at most {} is supported",
                    path.display(),
                    what,
                    number(*value),
                    number(*limit)
                )
            }
            Error::InvalidParam { name, value, allowed } => {
                write!(f, "parameter '{}' - value '{}' is invalid: expected {}", name, value, allowed)
            }
            Error::Exemplar { path, message } => write!(f, "exemplar '{}': {}", path.display(), message),
            Error::UnknownExemplar { name, available } => {
                write!(f, "no exemplar named '{}'; available: {}", name, list(available))
            }
            Error::UnknownLayer { name, available } => {
                write!(f, "no layer named '{}'; layers: {}", name, list(available))
            }
            Error::Missing { path, what } => write!(f, "'{}': {}", path.display(), what),
            Error::Stale { path, message } => write!(f, "'{}': {}", path.display(), message),
            Error::Corrupt { path, message } => write!(f, "'{}': {}", path.display(), message),
            Error::Cancelled => write!(f, "cancelled"),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Io { source, .. } => Some(source),
            Error::Json { source: Some(s), .. }
            | Error::Toml { source: Some(s), .. }
            | Error::Image { source: Some(s), .. } => Some(s.as_ref()),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::error::Error as _;

    #[test]
    fn parser_and_codec_errors_keep_their_source() {
        // A PNG signature followed by garbage: the codec's error is the source.
        let e = crate::img::decode(b"\x89PNG\r\n\x1a\n garbage", Path::new("x.png"), 100).unwrap_err();
        assert!(matches!(e, Error::Image { .. }), "{e}");
        assert!(e.source().and_then(|s| s.downcast_ref::<image::ImageError>()).is_some(), "{e:?}");
        let t = toml::from_str::<toml::Value>("name = [").unwrap_err();
        let e = Error::toml("x.toml", t);
        assert!(e.to_string().starts_with("'x.toml' is not valid TOML: "), "{e}");
        assert!(e.source().and_then(|s| s.downcast_ref::<toml::de::Error>()).is_some(), "{e:?}");
        // A message of our own has no source to show.
        assert!(Error::image("x.png", "nothing to draw").source().is_none());
    }
}
