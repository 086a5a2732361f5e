//! Reading animations: Lottie JSON, SVG frame sequences and plain PNG mask sequences.
//!
//! [`load`] parses an input into an [`Animation`]: its size, frame rate, frame count and the
//! **regions** to stylize (by default the top-level layers), plus the background. A region is
//! rendered on demand, frame by frame, into its *flat rendering* ([`RegionFrame`]): the fills
//! in their own colors as straight RGBA, whose alpha is the region's antialiased coverage mask,
//! with strokes kept apart so later stages can draw them crisp on top.
//!
//! Inputs:
//! - a Lottie `.json` file ([`lottie`]): regions are the top-level layers (a precomp is one
//!   region unless [`LoadOptions::split_precomps`]); nulls, matte sources, hidden and fully
//!   transparent helper layers are not regions; the bottom full-canvas solids are the
//!   [`Background`]. Frame 0 is the composition's `ip`.
//! - a directory or `dir/*.svg` glob of SVG frames, or a single `.svg` file (a one-frame
//!   still): regions are the top-level groups, identified across frames by name; shapes
//!   outside groups form one `root` region. Played at 24 fps.
//! - a directory or glob of PNG masks: one region, 24 fps.
//!
//! [`source`] tells which an input path is.
//!
//! ```no_run
//! use fluidymation::anim::{self, LoadOptions};
//! let a = anim::load("fixtures/demo/waving.json".as_ref(), &LoadOptions::default())?;
//! for (i, r) in a.regions.iter().enumerate() {
//!     let frame = a.render(i, r.visible.start)?;
//!     println!("{} covers {} px", r.name, frame.coverage().threshold(0.5).count());
//! }
//! # Ok::<(), fluidymation::Error>(())
//! ```

pub mod lottie;
mod masks;
mod motion;
pub(crate) mod svg;

use crate::error::{Error, Result};
use crate::img::{Plane, Rgba};
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Largest canvas side accepted, in pixels.
pub const MAX_SIDE: u32 = 16384;
/// Largest frame count accepted.
pub const MAX_FRAMES: usize = 100_000;

/// Options for [`load`]: `LoadOptions::default().scale(0.5)`.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct LoadOptions {
    /// Uniform scale applied to the canvas (0.5 = half size previews). Default: 1.
    pub scale: f32,
    /// Make each layer inside a top-level precomp a region of its own (`outer/inner`).
    /// Default: false.
    pub split_precomps: bool,
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions { scale: 1.0, split_precomps: false }
    }
}

impl LoadOptions {
    /// Sets [`LoadOptions::scale`], in `(0, 16]` (checked by [`load`]). Default: 1.
    pub fn scale(mut self, scale: f32) -> Self {
        self.scale = scale;
        self
    }

    /// Sets [`LoadOptions::split_precomps`]. Default: false.
    pub fn split_precomps(mut self, yes: bool) -> Self {
        self.split_precomps = yes;
        self
    }
}

/// What a region is made from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RegionKind {
    /// A Lottie shape layer (ty 4).
    Shape,
    /// A Lottie solid layer (ty 1) that is not the background.
    Solid,
    /// A Lottie precomp layer (ty 0), all of its content as one region.
    Precomp,
    /// A layer inside a precomp (with `--split-precomps`).
    PrecompChild,
    /// A top-level group of an SVG frame sequence.
    SvgGroup,
    /// Top-level SVG shapes outside any group, gathered into one region.
    SvgRoot,
    /// A plain PNG mask sequence.
    MaskSequence,
}

impl RegionKind {
    /// A short lower-case name for listings.
    pub fn as_str(self) -> &'static str {
        match self {
            RegionKind::Shape => "shape",
            RegionKind::Solid => "solid",
            RegionKind::Precomp => "precomp",
            RegionKind::PrecompChild => "precomp-child",
            RegionKind::SvgGroup => "svg-group",
            RegionKind::SvgRoot => "svg-root",
            RegionKind::MaskSequence => "masks",
        }
    }
}

/// A region to stylize.
#[derive(Clone, Debug)]
pub struct Region {
    /// Position in the stack, 1 = top-most (drawn last).
    pub index: usize,
    /// The layer's name (unique within the animation; duplicates get ` (2)` … appended).
    pub name: String,
    /// What the region is made from.
    pub kind: RegionKind,
    /// Frames (0-based, 0 = the composition's first frame) in which the region is visible.
    pub visible: Range<usize>,
    /// Dominant fill color (area-weighted), straight RGBA in `0..=1`, for display; transparent
    /// white when the region draws nothing where it was sampled (hidden, empty, text).
    pub color: Rgba,
    /// True when the region draws strokes (reported separately in [`RegionFrame::strokes`]).
    pub has_strokes: bool,
    /// Non-fatal problems (unsupported features) found in this region, each naming its layer
    /// (`layer 'arm': …`; in a Lottie region, possibly a layer nested inside it).
    pub warnings: Vec<String>,
}

impl Region {
    /// `NN_slug` as used for output folders (`01_body`).
    pub fn dir_name(&self) -> String {
        format!("{:02}_{}", self.index, slug(&self.name))
    }
}

/// The lower-cased name with every run of non-alphanumeric characters replaced by `-`.
pub fn slug(name: &str) -> String {
    let mut s = String::new();
    for c in name.chars() {
        if c.is_alphanumeric() {
            s.extend(c.to_lowercase());
        } else if !s.ends_with('-') {
            s.push('-');
        }
    }
    let s = s.trim_matches('-').to_string();
    if s.is_empty() { "layer".to_string() } else { s }
}

/// The bottom full-canvas solid color that serves as background.
#[derive(Clone, Debug)]
pub struct Background {
    /// The layer's name.
    pub name: String,
    /// Its color, straight RGBA in `0..=1`.
    pub color: Rgba,
}

/// One frame of one region.
#[derive(Clone, Debug)]
pub struct RegionFrame {
    /// The fills in their own colors, straight RGBA; alpha is the coverage mask.
    pub fill: Plane<Rgba>,
    /// The strokes, straight RGBA, when the region strokes anything at this frame (`None`
    /// when it has no strokes at all, see [`Region::has_strokes`], or none at this frame).
    pub strokes: Option<Plane<Rgba>>,
    /// Whether the fill's alpha includes the layer's opacity (Lottie, SVG), which is then
    /// separated from its coverage ([`RegionFrame::coverage`]); false when the alpha is coverage
    /// alone (a mask sequence's gray values, soft edges included).
    pub opacity_in_alpha: bool,
}

impl RegionFrame {
    /// The coverage of the fills by their shapes, whatever their opacity: the alpha divided by
    /// the layer's opacity there (the largest alpha within 2 px); the alpha itself when it is
    /// coverage alone ([`RegionFrame::opacity_in_alpha`]).
    pub fn coverage(&self) -> Plane<f32> {
        coverage_of(&self.fill, self.opacity_in_alpha)
    }
}

/// The coverage of a fill (see [`RegionFrame::coverage`]).
pub(crate) fn coverage_of(fill: &Plane<Rgba>, opacity_in_alpha: bool) -> Plane<f32> {
    if opacity_in_alpha { crate::composite::coverage(fill) } else { fill.map(|c| c[3]) }
}

/// Renders the regions of a loaded animation. Implemented by each input format.
pub(crate) trait RegionRenderer: Send + Sync {
    /// Renders region number `region` (position in [`Animation::regions`]) at frame `frame`
    /// at the animation's (scaled) size.
    fn render(&self, region: usize, frame: usize) -> Result<RegionFrame>;

    /// The motion of region `region` from frame `from` to frame `to`, where the format knows
    /// it ([`Animation::fill_motion_to`]); `None` by default.
    fn fill_motion(&self, _region: usize, _from: usize, _to: usize) -> Option<Plane<Option<glam::Vec2>>> {
        None
    }
}

/// A loaded animation.
pub struct Animation {
    /// The input file or directory.
    pub path: PathBuf,
    /// Canvas width in pixels (after [`LoadOptions::scale`]).
    pub width: u32,
    /// Canvas height in pixels (after [`LoadOptions::scale`]).
    pub height: u32,
    /// Frames per second.
    pub fps: f64,
    /// Number of frames.
    pub frames: usize,
    /// The regions to stylize, top-most first.
    pub regions: Vec<Region>,
    /// The background, when the animation has one.
    pub background: Option<Background>,
    /// Problems that concern the whole file.
    pub warnings: Vec<String>,
    /// The [`LoadOptions::scale`] it was loaded with ([`Animation::scale`]).
    scale: f32,
    renderer: Box<dyn RegionRenderer>,
}

impl std::fmt::Debug for Animation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Animation")
            .field("path", &self.path)
            .field("width", &self.width)
            .field("height", &self.height)
            .field("fps", &self.fps)
            .field("frames", &self.frames)
            .field("scale", &self.scale)
            .field("regions", &self.regions)
            .field("background", &self.background)
            .finish_non_exhaustive()
    }
}

impl Animation {
    /// Assembles an animation from its parts (used by the format readers), at scale 1 until
    /// [`load`] sets the scale it was loaded with.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        path: PathBuf,
        width: u32,
        height: u32,
        fps: f64,
        frames: usize,
        regions: Vec<Region>,
        background: Option<Background>,
        warnings: Vec<String>,
        renderer: Box<dyn RegionRenderer>,
    ) -> Self {
        Animation { path, width, height, fps, frames, regions, background, warnings, scale: 1.0, renderer }
    }

    /// The scale the canvas was loaded at ([`LoadOptions::scale`]; 0.5 = a half-size preview).
    /// A render reads it from here to scale the paint texture along with the canvas, so that a
    /// preview looks like the full render.
    pub fn scale(&self) -> f32 {
        self.scale
    }

    /// Renders region number `region` (position in [`Animation::regions`]) at `frame`.
    pub fn render(&self, region: usize, frame: usize) -> Result<RegionFrame> {
        self.check(region, frame)?;
        self.renderer.render(region, frame)
    }

    /// The true motion of region `region` from frame `frame` to `frame + 1`, pixels per frame,
    /// per pixel of the canvas (`None` where none of its fills is), where the file gives it.
    ///
    /// A Lottie file draws each fill in its own coordinates under a chain of transforms
    /// (layer, parents, precomps, groups, repeater copies), so a point of a fill moves by
    /// `M′·M⁻¹`, M and M′ the chain at the two frames: the whole motion, where a mask shows
    /// only its normal part (a turning disc looks still). A fill whose outline is animated in
    /// its own coordinates but keeps its vertices (path keyframes, an ellipse's or rectangle's
    /// keyed size) moves with its outline point by point: the best affine map of the
    /// outline's samples, plus their remaining motion spread inside (exact where the outline
    /// only scales or shears, an estimate inside one that bends). An SVG sequence gives the
    /// same from the region's elements drawn again in both frames (paired in document order).
    /// `Ok(None)` where an outline changes its structure (a trim, another vertex count), for
    /// mask sequences, at the last frame, and when the two frames do not draw the same fills
    /// (one appears or fades out entirely).
    pub fn fill_motion(&self, region: usize, frame: usize) -> Result<Option<Plane<Option<glam::Vec2>>>> {
        self.check(region, frame)?;
        if frame + 1 == self.frames {
            return Ok(None);
        }
        self.fill_motion_to(region, frame, frame + 1)
    }

    /// [`Animation::fill_motion`] from frame `from` to frame `to`, either way in time (the
    /// backward passes of painted keyframes carry paint from a frame to the one before it).
    pub fn fill_motion_to(&self, region: usize, from: usize, to: usize) -> Result<Option<Plane<Option<glam::Vec2>>>> {
        self.check(region, from)?;
        self.check(region, to)?;
        Ok(self.renderer.fill_motion(region, from, to))
    }

    /// An error unless `region` and `frame` are one of the animation's.
    fn check(&self, region: usize, frame: usize) -> Result<()> {
        if region >= self.regions.len() {
            return Err(Error::UnknownLayer {
                name: region.to_string(),
                available: self.regions.iter().map(|r| r.name.clone()).collect(),
            });
        }
        if frame >= self.frames {
            return Err(Error::param("frame", frame, format!("0..{}", self.frames)));
        }
        Ok(())
    }

    /// Duration in seconds.
    pub fn duration(&self) -> f64 {
        self.frames as f64 / self.fps
    }

    /// Finds a region by name (case-insensitive) or by 1-based index; returns its position
    /// in [`Animation::regions`].
    pub fn find_region(&self, key: &str) -> Result<usize> {
        if let Some(i) = self.regions.iter().position(|r| r.name == key) {
            return Ok(i);
        }
        if let Some(i) = self.regions.iter().position(|r| r.name.eq_ignore_ascii_case(key) || slug(&r.name) == key) {
            return Ok(i);
        }
        if let Ok(n) = key.parse::<usize>()
            && let Some(i) = self.regions.iter().position(|r| r.index == n)
        {
            return Ok(i);
        }
        Err(Error::UnknownLayer {
            name: key.to_string(),
            available: self.regions.iter().map(|r| format!("{} ({})", r.name, r.index)).collect(),
        })
    }
}

/// Area-weighted color histogram (5 bits per channel) for a region's dominant color.
#[derive(Clone, Debug, Default)]
pub(crate) struct ColorHistogram {
    bins: std::collections::HashMap<u16, (f64, [f64; 3])>,
}

impl ColorHistogram {
    /// Adds every pixel of a flat rendering, weighted by its alpha.
    pub fn add(&mut self, fill: &Plane<Rgba>) {
        for c in fill.data() {
            if c[3].is_nan() || c[3] <= 0.0 {
                continue;
            }
            let q = |v: f32| ((v.clamp(0.0, 1.0) * 31.0).round() as u16) & 31;
            let e = self.bins.entry(q(c[0]) << 10 | q(c[1]) << 5 | q(c[2])).or_insert((0.0, [0.0; 3]));
            let a = c[3] as f64;
            e.0 += a;
            for (acc, &v) in e.1.iter_mut().zip(c) {
                *acc += v as f64 * a;
            }
        }
    }

    /// The mean color of the heaviest bin (ties broken by the lower bin), opaque; `None` when
    /// nothing was covered.
    pub fn dominant(&self) -> Option<Rgba> {
        let (_, (w, sum)) = self.bins.iter().max_by(|a, b| a.1.0.total_cmp(&b.1.0).then(b.0.cmp(a.0)))?;
        Some([(sum[0] / w) as f32, (sum[1] / w) as f32, (sum[2] / w) as f32, 1.0])
    }
}

/// The canvas size of a `width × height` input at `scale`: each side rounded, at least 1 px.
/// A side over [`MAX_SIDE`] is an error (never clamped, which would crop the output).
pub(crate) fn scaled_canvas(path: &Path, width: f32, height: f32, scale: f32) -> Result<(u32, u32)> {
    let side = |v: f32, what: &str| -> Result<u32> {
        let s = (v as f64 * scale as f64).round();
        if s.is_nan() || s > MAX_SIDE as f64 {
            let at = if scale == 1.0 { String::new() } else { format!(" at --scale {scale}") };
            return Err(Error::Limit {
                path: path.to_path_buf(),
                what: format!("canvas {what}{at}"),
                value: s,
                limit: MAX_SIDE as f64,
            });
        }
        Ok((s as u32).max(1))
    };
    Ok((side(width, "width")?, side(height, "height")?))
}

/// Loads an animation: a `.json` Lottie file, an `.svg` file (a one-frame still), a directory
/// or glob of SVG files, or a directory or glob of PNG masks (one region); see [`source`].
pub fn load(path: &Path, options: &LoadOptions) -> Result<Animation> {
    if !(options.scale > 0.0 && options.scale <= 16.0) {
        return Err(Error::param("scale", options.scale, "a number in (0, 16]"));
    }
    let mut animation = read(path, options)?;
    animation.scale = options.scale;
    Ok(animation)
}

/// What an input path is, as [`source`] decides it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Source {
    /// A Lottie `.json` file.
    Lottie(PathBuf),
    /// SVG frames in order: a folder's `.svg` files, a glob's `.svg` matches, or one `.svg`
    /// file (a still).
    Svg(Vec<PathBuf>),
    /// PNG masks in order: a folder's `.png` files, a glob's `.png` matches, or one `.png`
    /// file (a one-frame mask sequence).
    Masks(Vec<PathBuf>),
    /// A glob matching several Lottie `.json` files (and no SVG frames or PNG masks): each is
    /// an animation of its own, to be loaded one at a time.
    LottieFiles(Vec<PathBuf>),
}

/// What inputs are accepted, for messages.
const ACCEPTED: &str = "a Lottie .json file, an .svg file (a one-frame still), a .png mask (one frame), a folder or glob \
                        of SVG frames (.svg), or a folder or glob of PNG masks (.png)";

/// At most three file names of `files`, for a message: "a.json, b.json, c.json and 2 more".
fn some_names(files: &[&PathBuf]) -> String {
    let names: Vec<String> =
        files.iter().take(3).map(|f| f.file_name().unwrap_or_default().to_string_lossy().into_owned()).collect();
    match files.len() {
        n if n > 3 => format!("{} and {} more", names.join(", "), n - 3),
        _ => names.join(", "),
    }
}

/// The files of one kind among `files`: `.svg` frames if there are any, else `.png` masks,
/// else `.json` Lottie files (`None` when there are none of these).
fn pick(files: &[PathBuf]) -> Option<Source> {
    let of = |ext: &str| -> Vec<PathBuf> {
        files.iter().filter(|f| crate::seq::extension(f).as_deref() == Some(ext)).cloned().collect()
    };
    let (svg, png, json) = (of("svg"), of("png"), of("json"));
    if !svg.is_empty() {
        Some(Source::Svg(svg))
    } else if !png.is_empty() {
        Some(Source::Masks(png))
    } else if json.len() == 1 {
        Some(Source::Lottie(json[0].clone()))
    } else if !json.is_empty() {
        Some(Source::LottieFiles(json))
    } else {
        None
    }
}

/// Decides what the input `path` is:
/// - a file: by its extension, `.json` a Lottie file, `.svg` a one-frame SVG sequence (a still),
///   `.png` a one-frame mask sequence (as a glob matching that one file);
/// - a folder: its `.svg` files if it has any (other files are ignored), else its `.png`
///   files; a folder of neither is an error that says what it holds (Lottie files are given as
///   files, not as their folder);
/// - a glob (`dir/f*.svg`, `dir/f0[1-3].svg`; see [`crate::seq::GLOB_SYNTAX`]): its matches,
///   picked by the same rule, or its `.json` matches ([`Source::LottieFiles`] when several).
pub fn source(path: &Path) -> Result<Source> {
    if path.is_file() {
        return match crate::seq::extension(path).as_deref() {
            Some("json") => Ok(Source::Lottie(path.to_path_buf())),
            Some("svg") => Ok(Source::Svg(vec![path.to_path_buf()])),
            Some("png") => Ok(Source::Masks(vec![path.to_path_buf()])),
            _ => Err(Error::animation(path, format!("unknown input: expected {ACCEPTED}"))),
        };
    }
    if path.is_dir() {
        let contents = crate::seq::Contents::read(path)?;
        return match pick(&contents.files) {
            Some(s @ (Source::Svg(_) | Source::Masks(_))) => Ok(s),
            _ => Err(Error::Empty { path: path.to_path_buf(), what: folder_without_frames(path, &contents) }),
        };
    }
    if crate::seq::is_glob(path) {
        let files = crate::seq::glob_files(path)?;
        return pick(&files).ok_or_else(|| Error::Empty {
            path: path.to_path_buf(),
            what: format!(
                "matches {} but no SVG frames (.svg), PNG masks (.png) or Lottie files (.json); expected {ACCEPTED}",
                crate::seq::Contents { files, folders: 0 }.describe()
            ),
        });
    }
    Err(Error::io(path, std::io::Error::new(std::io::ErrorKind::NotFound, "no such file or directory")))
}

/// Why the folder `dir` is not an input: it holds no SVG frames or PNG masks (but maybe
/// Lottie files, which are given as files).
fn folder_without_frames(dir: &Path, contents: &crate::seq::Contents) -> String {
    let holds = contents.describe();
    let json: Vec<&PathBuf> =
        contents.files.iter().filter(|f| crate::seq::extension(f).as_deref() == Some("json")).collect();
    let example = match json.as_slice() {
        [] => {
            return format!(
                "no SVG frames (.svg) or PNG masks (.png) found: it holds {holds}. A folder is read as one \
                 animation, a sequence of SVG frames or of PNG masks; a Lottie .json or a single .svg is given as \
                 the file itself"
            );
        }
        [one] => format!("`render '{}' -o OUT_DIR`", one.display()),
        [a, b, rest @ ..] => format!(
            "`render '{}' '{}'{} -o OUT_DIR` or `render '{}' -o OUT_DIR`",
            a.display(),
            b.display(),
            if rest.is_empty() { "" } else { " …" },
            dir.join("*.json").display()
        ),
    };
    format!(
        "holds {holds} but no SVG frames (.svg) or PNG masks (.png), which is what a folder is read as. Lottie \
         animations ({}) are given as files, not as their folder: {example} (several inputs are rendered as a \
         batch, each to OUT_DIR/<name>/; `inspect` takes one file)",
        some_names(&json)
    )
}

/// [`load`] by the input's format.
fn read(path: &Path, options: &LoadOptions) -> Result<Animation> {
    match source(path)? {
        Source::Lottie(file) => lottie::load(&file, options),
        Source::Svg(files) => svg::load(path, files, options),
        Source::Masks(files) => masks::load(path, files, options),
        Source::LottieFiles(files) => {
            let refs: Vec<&PathBuf> = files.iter().collect();
            Err(Error::animation(
                path,
                format!(
                    "matches {} Lottie .json files ({}); each is an animation of its own: give one file, or \
                     several inputs to `render`, which renders them as a batch (and expands such a glob itself)",
                    files.len(),
                    some_names(&refs)
                ),
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slugs() {
        assert_eq!(slug("Left Arm #2"), "left-arm-2");
        assert_eq!(slug("  "), "layer");
        assert_eq!(slug("Ärm"), "ärm");
    }
}
