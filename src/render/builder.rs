//! [`Render`]: a render set up step by step, styles given as values.

use super::{Background, Recolor, RenderOptions, RenderSummary, StrokeMode, Style};
use crate::anim::Animation;
use crate::error::Result;
use crate::exemplar::Exemplar;
use crate::progress::Progress;
use crate::synth::Params;
use std::ops::Range;
use std::path::PathBuf;
use std::sync::Arc;

/// A render of one animation, set up step by step and run into a folder of PNG frames: every
/// layer painted with its [`Style`], recolored to the layer's own colors, composited over the
/// [`Background`]. The canvas scale is the animation's own ([`Animation::scale`]).
///
/// ```no_run
/// use fluidymation::anim::{self, LoadOptions};
/// use fluidymation::exemplar::{self, SearchPath};
/// use fluidymation::render::{Background, Render, Style};
/// use fluidymation::NoProgress;
/// # fn main() -> fluidymation::Result<()> {
/// let a = anim::load("fixtures/demo/waving.json".as_ref(), &LoadOptions::default().scale(0.5))?;
/// let ink = exemplar::find("ink-rims", &SearchPath::standard(&[]))?;
/// let summary = Render::new(&a)
///     .style_all(Style::named("blue-bloom"))
///     .style("dress", Style::exemplar(ink))
///     .style("hair", Style::None)
///     .background(Background::Color([0.96, 0.94, 0.9, 1.0]))
///     .frames(0..12)
///     .seed(7)
///     .gif("out/demo.gif")
///     .run("out/demo", &NoProgress)?;
/// println!("{} frames in {:.1} s", summary.frames, summary.seconds);
/// # Ok(()) }
/// ```
#[derive(Clone, Debug)]
#[must_use = "a Render does nothing until it is run"]
pub struct Render<'a> {
    anim: &'a Animation,
    opts: RenderOptions,
    seed: Option<u64>,
}

impl<'a> Render<'a> {
    /// A render of every frame of `animation`, every layer painted with the bundled default
    /// exemplar ([`crate::exemplar::DEFAULT`]) over the animation's own background.
    pub fn new(animation: &'a Animation) -> Render<'a> {
        Render { anim: animation, opts: RenderOptions::new(PathBuf::new(), 0..animation.frames), seed: None }
    }

    /// The style of one layer: `layer` a name (case-insensitive) or 1-based index
    /// ([`Animation::find_region`]; an unknown layer is an error when the render runs). A later
    /// call for the same layer wins. Default: [`Render::style_all`]'s.
    pub fn style(mut self, layer: impl Into<String>, style: impl Into<Style>) -> Self {
        self.opts.styles.push((layer.into(), style.into()));
        self
    }

    /// The style of every layer not given one with [`Render::style`]. Default: the bundled
    /// default exemplar.
    pub fn style_all(mut self, style: impl Into<Style>) -> Self {
        self.opts.default_style = Some(style.into());
        self
    }

    /// An extra folder to look up [`Style::Named`] exemplars in, before `FLUIDYMATION_EXEMPLARS`,
    /// the user's folder and the bundled set. Default: none.
    pub fn exemplar_dir(mut self, dir: impl Into<PathBuf>) -> Self {
        self.opts.exemplar_dirs.push(dir.into());
        self
    }

    /// What the layers are composited over. Default: [`Background::Animation`].
    pub fn background(mut self, background: Background) -> Self {
        self.opts.background = background;
        self
    }

    /// How stylized layers take their colors. Default: [`Recolor::Glaze`].
    pub fn recolor(mut self, recolor: Recolor) -> Self {
        self.opts.recolor = recolor;
        self
    }

    /// What happens to strokes. Default: [`StrokeMode::Keep`].
    pub fn strokes(mut self, strokes: StrokeMode) -> Self {
        self.opts.strokes = strokes;
        self
    }

    /// The frames to render, 0-based (clipped to the animation; an empty range is an error when
    /// the render runs). Guides are computed over this range only. Default: every frame.
    pub fn frames(mut self, frames: Range<usize>) -> Self {
        self.opts.frames = frames;
        self
    }

    /// The engine's parameters ([`Params::builder`]). Default: [`Params::default`].
    pub fn params(mut self, params: Params) -> Self {
        self.opts.params = params;
        self
    }

    /// The seed of the engine's random choices, over [`Render::params`]'s. The same seed
    /// gives the same frames, whatever the number of threads. Default: the parameters' seed.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = Some(seed);
        self
    }

    /// Also write an animated GIF here. Default: none.
    pub fn gif(mut self, path: impl Into<PathBuf>) -> Self {
        self.opts.gif = Some(path.into());
        self
    }

    /// Also write every layer alone (RGBA) under `OUT_DIR/layers/NN_name/`. Default: false.
    pub fn keep_layers(mut self, yes: bool) -> Self {
        self.opts.keep_layers = yes;
        self
    }

    /// Continue an interrupted render into the same folder, with the same settings; see
    /// [`RenderOptions::resume`]. Default: false.
    pub fn resume(mut self, yes: bool) -> Self {
        self.opts.resume = yes;
        self
    }

    /// Measure every stylized layer against its exemplar afterwards, into
    /// [`LayerSummary::eval`](super::LayerSummary::eval). Default: false.
    pub fn eval(mut self, yes: bool) -> Self {
        self.opts.eval = yes;
        self
    }

    /// A painted keyframe: frame `frame` (0-based) of the animation painted over, in an image
    /// file of the canvas's size; see [`RenderOptions::keyframes`]. Default: none.
    pub fn keyframe(mut self, frame: usize, painting: impl Into<PathBuf>) -> Self {
        self.opts.keyframes.push((frame, painting.into()));
        self
    }

    /// The options of this render into `out_dir`: the lower layer that [`super::render`],
    /// [`super::render_batch`] and the per-layer jobs take.
    pub fn into_options(self, out_dir: impl Into<PathBuf>) -> Result<RenderOptions> {
        let mut opts = self.opts;
        opts.out_dir = out_dir.into();
        if let Some(seed) = self.seed {
            opts.params = opts.params.to_builder().seed(seed).build()?;
        }
        Ok(opts)
    }

    /// Renders into `out_dir`: numbered PNG frames (`0001.png` = the animation's first frame),
    /// reporting to `progress` (which may cancel: [`crate::Error::Cancelled`]).
    pub fn run(self, out_dir: impl Into<PathBuf>, progress: &dyn Progress) -> Result<RenderSummary> {
        let anim = self.anim;
        super::render(anim, &self.into_options(out_dir)?, progress)
    }
}

impl From<Arc<Exemplar>> for Style {
    fn from(exemplar: Arc<Exemplar>) -> Style {
        Style::Exemplar(exemplar)
    }
}

impl From<&str> for Style {
    /// As [`str::parse`]: `"none"` is [`Style::None`], anything else [`Style::Named`].
    fn from(name: &str) -> Style {
        name.parse().unwrap_or_else(|never| match never {})
    }
}
