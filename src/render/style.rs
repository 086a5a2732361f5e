//! What a layer is painted with ([`Style`]) and what the layers are composited over
//! ([`Background`]), as values; the command line's spellings parse into them ([`FromStr`]).

use crate::composite::{self, parse_color};
use crate::error::{Error, Result};
use crate::exemplar::{self, Exemplar, SearchPath};
use crate::img::Rgba;
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::Arc;

/// The style name that leaves a layer flat ([`Style::None`] on the command line).
pub const NO_STYLE: &str = "none";

/// What a layer is painted with.
///
/// ```
/// use fluidymation::render::Style;
/// assert_eq!("ink-rims".parse::<Style>().unwrap(), Style::named("ink-rims"));
/// assert_eq!("none".parse::<Style>().unwrap(), Style::None);
/// ```
///
/// Two styles are equal when they name the same exemplar the same way; two
/// [`Style::Exemplar`]s when they share the same exemplar in memory.
#[derive(Clone)]
#[non_exhaustive]
pub enum Style {
    /// An exemplar found as [`exemplar::find`] finds it: by name among the bundled exemplars and
    /// the search folders ([`RenderOptions::exemplar_dirs`](super::RenderOptions::exemplar_dirs),
    /// `FLUIDYMATION_EXEMPLARS`, the user's folder), or by the path of an exemplar folder or of
    /// a still image.
    Named(String),
    /// An exemplar in memory: loaded, generated ([`exemplar::generate`]) or imported
    /// ([`exemplar::import`]) by the caller. A still painted in memory is one frame keyed out
    /// into its mask by [`exemplar::import::from_frames`]:
    ///
    /// ```
    /// use fluidymation::exemplar::import::{ImportOptions, from_frames};
    /// use fluidymation::img::Plane;
    /// use fluidymation::render::Style;
    /// // A blue blot on cream paper.
    /// let image = Plane::from_fn(96, 96, |x, y| {
    ///     let d = ((x as f32 - 48.0).powi(2) + (y as f32 - 48.0).powi(2)).sqrt();
    ///     if d < 30.0 { [0.2, 0.3, 0.8 - d / 200.0] } else { [0.95, 0.93, 0.88] }
    /// });
    /// let still = from_frames(vec![image], &[], &ImportOptions::default().name("blot"))?;
    /// assert_eq!(still.frames.len(), 1);
    /// let style = Style::exemplar(still);
    /// # Ok::<(), fluidymation::Error>(())
    /// ```
    Exemplar(Arc<Exemplar>),
    /// A still image (PNG or JPEG) of paint on paper, keyed out into its mask as
    /// `fluidymation exemplar import` does ([`exemplar::import::still`]).
    Still(PathBuf),
    /// No style: the layer is left flat, in its own colors.
    None,
}

impl Style {
    /// [`Style::Named`]: an exemplar by name (bundled or in a search folder) or path.
    pub fn named(name: impl Into<String>) -> Style {
        Style::Named(name.into())
    }

    /// [`Style::Exemplar`]: an exemplar in memory.
    pub fn exemplar(exemplar: Exemplar) -> Style {
        Style::Exemplar(Arc::new(exemplar))
    }

    /// [`Style::Still`]: a still image of paint.
    pub fn still(image: impl Into<PathBuf>) -> Style {
        Style::Still(image.into())
    }

    /// How the render refers to this style (in its summaries, checkpoints and caches): the name
    /// or path as given; for an exemplar in memory, its name and a digest of its contents (so
    /// that a resumed render checks it is the same). `None` for [`Style::None`].
    pub(crate) fn key(&self) -> Option<String> {
        match self {
            Style::Named(name) if name == NO_STYLE => None,
            Style::Named(name) => Some(name.clone()),
            Style::Still(path) => Some(path.to_string_lossy().into_owned()),
            Style::Exemplar(ex) => Some(format!("{}#{:016x}", ex.meta.name, digest(ex))),
            Style::None => None,
        }
    }

    /// Loads the exemplar (`dirs`: extra folders to search by name); `None` for [`Style::None`].
    pub(crate) fn load(&self, dirs: &[PathBuf]) -> Result<Option<Exemplar>> {
        Ok(match self {
            Style::Named(name) if name == NO_STYLE => None,
            Style::Named(name) => Some(exemplar::find(name, &SearchPath::standard(dirs))?),
            Style::Still(path) => Some(exemplar::import::still(path)?),
            Style::Exemplar(ex) => Some(Exemplar::clone(ex)),
            Style::None => None,
        })
    }
}

/// The contents of an exemplar as one number: its metadata, frames and masks.
fn digest(ex: &Exemplar) -> u64 {
    let mut frames = crc32fast::Hasher::new();
    let mut rest = crc32fast::Hasher::new();
    rest.update(format!("{:?}", ex.meta).as_bytes());
    for f in &ex.frames {
        rest.update(&(f.width() as u64 * 100_000 + f.height() as u64).to_le_bytes());
        for c in f.data() {
            for v in c {
                frames.update(&v.to_bits().to_le_bytes());
            }
        }
    }
    for m in &ex.masks {
        rest.update(&(m.width() as u64 * 100_000 + m.height() as u64).to_le_bytes());
        for v in m.data() {
            rest.update(&v.to_bits().to_le_bytes());
        }
    }
    (frames.finalize() as u64) << 32 | rest.finalize() as u64
}

impl PartialEq for Style {
    fn eq(&self, other: &Style) -> bool {
        match (self, other) {
            (Style::Named(a), Style::Named(b)) => a == b,
            (Style::Exemplar(a), Style::Exemplar(b)) => Arc::ptr_eq(a, b),
            (Style::Still(a), Style::Still(b)) => a == b,
            (Style::None, Style::None) => true,
            _ => false,
        }
    }
}

impl fmt::Debug for Style {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Style::Named(name) => f.debug_tuple("Named").field(name).finish(),
            // Not the frames: only which exemplar it is.
            Style::Exemplar(ex) => f.debug_tuple("Exemplar").field(&ex.meta.name).finish(),
            Style::Still(path) => f.debug_tuple("Still").field(path).finish(),
            Style::None => f.write_str("None"),
        }
    }
}

impl FromStr for Style {
    type Err = std::convert::Infallible;

    /// `none` ([`NO_STYLE`]) is [`Style::None`]; anything else is [`Style::Named`] (a name, an
    /// exemplar folder or a still image, found when the render starts).
    fn from_str(s: &str) -> std::result::Result<Style, Self::Err> {
        Ok(if s == NO_STYLE { Style::None } else { Style::Named(s.to_string()) })
    }
}

impl From<Exemplar> for Style {
    fn from(exemplar: Exemplar) -> Style {
        Style::exemplar(exemplar)
    }
}

/// What the layers are composited over.
///
/// ```
/// use fluidymation::render::Background;
/// assert_eq!("none".parse::<Background>().unwrap(), Background::Transparent);
/// assert_eq!("#ff0000".parse::<Background>().unwrap(), Background::Color([1.0, 0.0, 0.0, 1.0]));
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
#[non_exhaustive]
pub enum Background {
    /// The animation's own background (its bottom full-canvas solid), white paper when it has
    /// none.
    #[default]
    Animation,
    /// Nothing: the frames' alpha comes from the layers' coverage.
    Transparent,
    /// A uniform color, straight sRGB RGBA in `0..=1`.
    Color(Rgba),
    /// An image file (PNG or JPEG, a paper texture say), scaled to cover the canvas (aspect
    /// ratio kept, centered, the excess cropped).
    Image(PathBuf),
}

impl Background {
    /// The color under the layers, when it is one color: the animation's own (or white), or
    /// [`Background::Color`].
    pub fn color(&self, anim: &crate::anim::Animation) -> Option<Rgba> {
        match self {
            Background::Animation => Some(anim.background.as_ref().map_or(composite::WHITE, |b| b.color)),
            Background::Color(c) => Some(*c),
            Background::Transparent | Background::Image(_) => None,
        }
    }

    /// The background as the resume fingerprint has always spelled it (the command line's
    /// `Option<String>`): `None` for the animation's own, else a `--background` value — so
    /// that a render interrupted by an earlier version resumes with this one.
    pub(crate) fn fingerprint_spec(&self) -> Option<String> {
        let hex = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
        match self {
            Background::Animation => None,
            Background::Transparent => Some("none".into()),
            Background::Color([r, g, b, a]) if *a >= 1.0 => {
                Some(format!("#{:02x}{:02x}{:02x}", hex(*r), hex(*g), hex(*b)))
            }
            Background::Color([r, g, b, a]) => {
                Some(format!("#{:02x}{:02x}{:02x}{:02x}", hex(*r), hex(*g), hex(*b), hex(*a)))
            }
            Background::Image(path) => Some(path.to_string_lossy().into_owned()),
        }
    }

    /// The background of the composite for `anim`; an image is loaded and fitted to its canvas.
    pub(crate) fn resolve(&self, anim: &crate::anim::Animation) -> Result<composite::Background> {
        Ok(match self {
            Background::Animation => composite::Background::from_animation(anim.background.as_ref()),
            Background::Transparent => composite::Background::Transparent,
            Background::Color(c) => composite::Background::Color(*c),
            Background::Image(path) => {
                if !path.exists() {
                    return Err(not_a_background(&path.to_string_lossy()));
                }
                composite::Background::load_image(path, anim.width as usize, anim.height as usize)?
            }
        })
    }
}

fn not_a_background(spec: &str) -> Error {
    Error::param(
        "background",
        spec,
        "a color (#rrggbb, #rgb, #rrggbbaa, white, black, …), 'none', or an existing image file (no file of that \
         name was found)",
    )
}

impl FromStr for Background {
    type Err = Error;

    /// `none` or `transparent`, a color (`#rrggbb`, `#rgb`, `#rrggbbaa`, `white`, …), or else the
    /// path of an image file (checked when the render starts).
    fn from_str(spec: &str) -> Result<Background> {
        let trimmed = spec.trim();
        if trimmed.eq_ignore_ascii_case("none") || trimmed.eq_ignore_ascii_case("transparent") {
            return Ok(Background::Transparent);
        }
        if let Some(c) = parse_color(trimmed) {
            return Ok(Background::Color(c));
        }
        if trimmed.is_empty() {
            return Err(not_a_background(spec));
        }
        Ok(Background::Image(Path::new(spec).to_path_buf()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn styles_parse_and_key() {
        assert_eq!("none".parse::<Style>().unwrap(), Style::None);
        assert_eq!(Style::from("blue-bloom"), Style::named("blue-bloom"));
        assert_eq!(Style::named(NO_STYLE).key(), None);
        assert_eq!(Style::still("a/swatch.png").key().as_deref(), Some("a/swatch.png"));
        let ex = exemplar::find("blue-swatch", &SearchPath::new().with_bundled(true)).unwrap();
        let key = Style::exemplar(ex.clone()).key().unwrap();
        assert!(key.starts_with("blue-swatch#"), "{key}");
        assert_eq!(Style::exemplar(ex.clone()).key().unwrap(), key, "the same contents, the same key");
        let mut other = ex;
        other.frames[0].data_mut()[0][0] += 0.5;
        assert_ne!(Style::exemplar(other).key().unwrap(), key, "other contents, another key");
    }

    #[test]
    fn backgrounds_spell_as_the_command_line_did() {
        let spec = |s: &str| s.parse::<Background>().unwrap().fingerprint_spec();
        assert_eq!(Background::default().fingerprint_spec(), None);
        assert_eq!(spec("none").as_deref(), Some("none"));
        assert_eq!(spec("#f3ede2").as_deref(), Some("#f3ede2"));
        assert_eq!(spec("#11223380").as_deref(), Some("#11223380"));
        assert_eq!(spec("paper.png").as_deref(), Some("paper.png"));
        assert!("  ".parse::<Background>().is_err());
    }
}
