//! The whole pipeline behind `fluidymation render`: every region of an animation is
//! synthesized with its exemplar (layers in parallel, frames in order), recolored to the
//! region's own colors, composited in z-order over the background and written as numbered PNG
//! frames, optionally as stylized layers and a GIF.
//!
//! [`Render`] sets a render up step by step, with styles as values ([`Style`]: an exemplar by
//! name, one in memory, a still image, or none) and the background as one ([`Background`]):
//!
//! ```no_run
//! use fluidymation::{anim, render::{Background, Render, Style}, NoProgress};
//! # fn main() -> fluidymation::Result<()> {
//! let a = anim::load("fixtures/demo/waving.json".as_ref(), &Default::default())?;
//! let summary = Render::new(&a)
//!     .style("dress", Style::named("ink-rims"))
//!     .background(Background::Transparent)
//!     .gif("out/demo.gif")
//!     .run("out", &NoProgress)?;
//! println!("{} frames, {:.2} s per frame", summary.frames, summary.seconds_per_frame());
//! # Ok(()) }
//! ```
//!
//! Under it, [`RenderOptions`] is the same set of choices as one value, which [`render()`],
//! [`render_batch`] and the jobs below take ([`Render::into_options`] gives it).
//!
//! An interrupted render keeps, after every completed frame, the state each layer's
//! synthesizer carries to the next frame in `OUT_DIR/.fluidymation/` ([`STATE_DIR`]);
//! [`RenderOptions::resume`] continues from there and gives the same frames as an
//! uninterrupted run. Every piece of that state is checked before it is used: a damaged or
//! foreign state is an error, and frames changed since they were written are rendered again.
//! After a complete render only the progress file and the record of the files written stay
//! there, so that resuming it (in a batch, say) knows it is done and checks its frames.
//!
//! # Batches and plans
//!
//! [`render_batch`] renders many files, several at once, sharing the prepared exemplars; a
//! file that fails does not stop the others. The same render can also be cut into
//! independent jobs — one per stylized layer ([`render_layer`]: the layer's frames painted
//! in the exemplar's colors, with its own checkpoints) and one per file ([`composite()`]:
//! recoloring and compositing the painted layers into frames and a GIF) — which a job
//! scheduler can run on many machines. All three give the same bytes: the painted layer
//! passes through the same 16-bit quantization (to 16-bit PNG) whether it stays in memory or is
//! written to disk in between.

use crate::anim::{Animation, RegionFrame};
use crate::composite::{self, LayerFrame, Pigment, StylizedLayer};
use crate::error::{Error, Result};
use crate::eval;
use crate::exemplar::{self, Exemplar};
use crate::guide::GuideStream;
use crate::img::{self, Plane, Rgba};
use crate::output::{self, GifOptions, GifWriter};
use crate::progress::Progress;
use crate::resume::{self, Journal, Remedy};
use crate::synth::{Params, Source, Synthesizer};
use rayon::prelude::*;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::Instant;

mod batch;
mod builder;
mod jobs;
pub(crate) mod keys;
pub(crate) mod paint;
mod style;

pub use crate::composite::{Recolor, StrokeMode};
pub(crate) use batch::StyleCache;
pub use batch::render_batch;
pub use builder::Render;
pub use jobs::{LAYER_MANIFEST, LayerCost, LayerJobSummary, composite, layer_costs, render_layer};
pub use style::{Background, NO_STYLE, Style};

/// The style a layer painted from keyframes is reported with.
pub const KEYFRAMES_STYLE: &str = "keyframes";

/// What to render and how: the lower layer under [`Render`], which the command line uses.
/// Start from [`RenderOptions::new`] and set the fields.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct RenderOptions {
    /// Directory of the PNG frames (`NNNN.png`, numbered by animation frame, 0001 = the first).
    pub out_dir: PathBuf,
    /// Also write an animated GIF here.
    pub gif: Option<PathBuf>,
    /// Per-layer styles: a layer name or 1-based index ([`Animation::find_region`]), and its
    /// style. The last one naming a layer wins.
    pub styles: Vec<(String, Style)>,
    /// The style of every other layer. Default (`None`): the bundled default exemplar
    /// ([`exemplar::DEFAULT`]).
    pub default_style: Option<Style>,
    /// Extra folders to look up exemplars by name.
    pub exemplar_dirs: Vec<PathBuf>,
    /// What the layers are composited over. Default: the animation's own background (white
    /// when it has none).
    pub background: Background,
    /// How stylized layers are recolored.
    pub recolor: Recolor,
    /// What happens to strokes.
    pub strokes: StrokeMode,
    /// Frames to render (0-based); guides are computed over this range only.
    pub frames: Range<usize>,
    /// Engine parameters. At an animation's [`Animation::scale`] other than 1, the exemplar's
    /// scale, the blur and the modulation bounds are scaled alike, so that a preview looks like
    /// the full render.
    pub params: Params,
    /// Also write each layer under `OUT_DIR/layers/NN_slug/`.
    pub keep_layers: bool,
    /// Continue an interrupted render in `out_dir`.
    pub resume: bool,
    /// Measure every stylized layer against its exemplar afterwards ([`eval`]).
    pub eval: bool,
    /// Painted keyframes: (animation frame, 0-based; the painting's file), each painting the
    /// canvas's size (or the animation's unscaled size, resized along with
    /// [`Animation::scale`]).
    /// The layers a painting paints are painted from the paintings in every frame, the others
    /// keep their style.
    pub keyframes: Vec<(usize, PathBuf)>,
}

impl RenderOptions {
    /// Defaults for rendering `frames` into `out_dir`.
    pub fn new(out_dir: PathBuf, frames: Range<usize>) -> RenderOptions {
        RenderOptions {
            out_dir,
            gif: None,
            styles: Vec::new(),
            default_style: None,
            exemplar_dirs: Vec::new(),
            background: Background::Animation,
            recolor: Recolor::Glaze,
            strokes: StrokeMode::Keep,
            frames,
            params: Params::default(),
            keep_layers: false,
            resume: false,
            eval: false,
            keyframes: Vec::new(),
        }
    }
}

/// What one layer got.
#[derive(Clone, Debug)]
pub struct LayerSummary {
    /// 1-based index from the top.
    pub index: usize,
    /// The layer's name.
    pub name: String,
    /// The exemplar it was stylized with (`None` = left flat).
    pub exemplar: Option<String>,
    /// Seconds spent synthesizing it (summed over frames).
    pub seconds: f64,
    /// The quality report, with [`RenderOptions::eval`].
    pub eval: Option<eval::Report>,
}

/// What a render did.
#[derive(Clone, Debug)]
pub struct RenderSummary {
    /// Frames written by this run.
    pub frames: usize,
    /// Frames that were already done when resuming.
    pub resumed: usize,
    /// Wall-clock seconds of this run.
    pub seconds: f64,
    /// The frames' directory.
    pub frame_dir: PathBuf,
    /// The GIF, when written.
    pub gif: Option<PathBuf>,
    /// Per layer, top-most first.
    pub layers: Vec<LayerSummary>,
}

impl RenderSummary {
    /// Wall-clock seconds per frame written.
    pub fn seconds_per_frame(&self) -> f64 {
        if self.frames == 0 { 0.0 } else { self.seconds / self.frames as f64 }
    }
}

/// One exemplar prepared for this render.
struct Prepped {
    name: String,
    exemplar: Exemplar,
    source: Source,
    pigment: Pigment,
    params: Params,
}

/// The per-layer state of a render.
struct Layer {
    region: usize,
    style: Option<usize>,
    synth: Option<Synthesizer>,
    guides: Option<GuideStream>,
    seconds: f64,
    /// Exemplar-colored frames and target coverages, for `eval` (8-bit to save memory).
    kept: Vec<(Vec<u8>, Vec<u8>)>,
}

pub use crate::resume::STATE_DIR;

/// The region to synthesize for one frame: the fill, with the strokes merged under
/// [`StrokeMode::Stylize`].
fn target_fill(rf: &RegionFrame, strokes: StrokeMode) -> Plane<Rgba> {
    if strokes == StrokeMode::Stylize {
        composite::merge_strokes(&rf.fill, rf.strokes.as_ref())
    } else {
        rf.fill.clone()
    }
}

/// What the engine paints of a region frame: the coverage of [`target_fill`]
/// ([`RegionFrame::coverage`]).
fn target_coverage(rf: &RegionFrame, strokes: StrokeMode) -> Plane<f32> {
    crate::anim::coverage_of(&target_fill(rf, strokes), rf.opacity_in_alpha)
}

/// The style of layers without one of their own.
fn default_style(opts: &RenderOptions) -> Style {
    opts.default_style.clone().unwrap_or_else(|| Style::named(exemplar::DEFAULT))
}

/// Resolves every region's style, as its key ([`Style::key`], `None`: left flat): explicit
/// `styles` first, then the default.
fn resolve_styles(anim: &Animation, opts: &RenderOptions) -> Result<Vec<Option<String>>> {
    let mut out: Vec<Option<String>> = vec![default_style(opts).key(); anim.regions.len()];
    for (key, style) in &opts.styles {
        let i = anim.find_region(key)?;
        out[i] = style.key();
    }
    Ok(out)
}

/// The style of `opts` whose key is `key`.
fn style_of_key(opts: &RenderOptions, key: &str) -> Style {
    opts.styles
        .iter()
        .rev()
        .map(|(_, s)| s.clone())
        .chain([default_style(opts)])
        .find(|s| s.key().as_deref() == Some(key))
        .unwrap_or_else(|| Style::named(key))
}

/// Parameters for one exemplar at the render's scale.
fn style_params(base: &Params, ex: &Exemplar, scale: f32) -> Result<Params> {
    if (scale - 1.0).abs() < 1e-6 {
        return Ok(base.clone());
    }
    let g = base.guide();
    let (ml, mu) = base.prev_bounds();
    let mut b = base
        .to_builder()
        .src_scale(base.src_scale().unwrap_or(ex.meta.scale) * scale)
        .blur_sigma(g.blur_sigma * scale)
        .prev_bounds(ml * scale, mu * scale);
    if let Some(bw) = base.border_width() {
        b = b.border_width(bw * scale);
    }
    b.build().map_err(|e| match e {
        Error::InvalidParam { name, value, allowed } => Error::param(
            "scale",
            scale,
            format!("a larger scale: the exemplar's {name} scaled along would be {value}, but it must be {allowed}"),
        ),
        other => other,
    })
}

/// Renders `anim` as `opts` says; see the [module documentation](self).
pub fn render(anim: &Animation, opts: &RenderOptions, progress: &dyn Progress) -> Result<RenderSummary> {
    render_with(anim, opts, &StyleCache::new(), progress)
}

/// The frame range of `opts` inside the animation; an error when it is empty or the
/// animation has nothing to stylize.
fn frame_range(anim: &Animation, opts: &RenderOptions) -> Result<Range<usize>> {
    if anim.regions.is_empty() {
        return Err(Error::Empty {
            path: anim.path.clone(),
            what: "there are no layers to stylize (only a background, hidden or empty layers)".into(),
        });
    }
    let range = opts.frames.start.min(anim.frames)..opts.frames.end.min(anim.frames);
    if range.is_empty() {
        return Err(Error::param(
            "frames",
            format!("{}..{}", opts.frames.start + 1, opts.frames.end),
            format!("a range inside 1..{} (1-based, inclusive)", anim.frames),
        ));
    }
    Ok(range)
}

fn background(anim: &Animation, opts: &RenderOptions) -> Result<composite::Background> {
    opts.background.resolve(anim)
}

/// The styles of one file's regions, resolved and prepared.
struct Prepared {
    /// Per region, the style's name (`None`: left flat).
    styles_of: Vec<Option<String>>,
    /// Per region, its entry in `styles` (`None`: flat, or not prepared).
    region_style: Vec<Option<usize>>,
    styles: Vec<Prepped>,
}

/// Resolves the style of every region and prepares the exemplars of the stylized ones (only
/// of region `only` when given): each exemplar is loaded once, parameters are fitted to thin
/// layers, and layers with the same exemplar and parameters share one prepared source.
/// Before any of that, the memory the work will need is checked against the limit
/// ([`crate::limits`]): every layer of the file, or only region `only` (a layer job).
fn prepare(
    anim: &Animation,
    opts: &RenderOptions,
    range: &Range<usize>,
    only: Option<usize>,
    cache: &StyleCache,
) -> Result<Prepared> {
    let styles_of = resolve_styles(anim, opts)?;
    let shape = match only {
        Some(_) => {
            crate::limits::RenderShape { width: anim.width, height: anim.height, stylized: 1, flat: 0, kept_frames: 0 }
        }
        None => {
            let stylized = styles_of.iter().filter(|s| s.is_some()).count();
            crate::limits::RenderShape {
                width: anim.width,
                height: anim.height,
                stylized,
                flat: anim.regions.len() - stylized,
                kept_frames: if opts.eval { range.len() } else { 0 },
            }
        }
    };
    crate::limits::check_render_memory(&anim.path, &shape)?;
    let wanted = |region: usize| only.is_none_or(|o| o == region);
    let mut names: Vec<String> =
        styles_of.iter().enumerate().filter(|(r, _)| wanted(*r)).filter_map(|(_, s)| s.clone()).collect();
    names.sort();
    names.dedup();
    let exemplars: Vec<Exemplar> = names.iter().map(|n| cache.exemplar(n, opts)).collect::<Result<_>>()?;
    let base: Vec<Params> =
        exemplars.iter().map(|ex| style_params(&opts.params, ex, anim.scale())).collect::<Result<_>>()?;
    // Per layer: its exemplar and the parameters fitted to its thickness (thin layers get a
    // smaller blur σ and border width b, see `Params::fit_to_thickness`).
    let fitted: Vec<Option<(usize, Params)>> = (0..anim.regions.len())
        .into_par_iter()
        .map(|region| -> Result<Option<(usize, Params)>> {
            if !wanted(region) {
                return Ok(None);
            }
            let Some(e) = styles_of[region].as_ref().and_then(|n| names.iter().position(|m| m == n)) else {
                return Ok(None);
            };
            let p = &base[e];
            if !p.fit_thin() {
                return Ok(Some((e, p.clone())));
            }
            let ex = &exemplars[e];
            let exemplar_border = p.exemplar_border_width(ex);
            let thickness = crate::synth::sequence_thickness(range.len(), |k| {
                Ok(target_coverage(&anim.render(region, range.start + k)?, opts.strokes))
            })?;
            Ok(Some((e, thickness.map_or_else(|| p.clone(), |t| p.fit_to_thickness(t, exemplar_border)))))
        })
        .collect::<Result<_>>()?;
    let mut keys: Vec<(usize, Params)> = Vec::new();
    let region_style: Vec<Option<usize>> = fitted
        .into_iter()
        .map(|f| {
            f.map(|(e, p)| {
                keys.iter().position(|(ke, kp)| *ke == e && *kp == p).unwrap_or_else(|| {
                    keys.push((e, p));
                    keys.len() - 1
                })
            })
        })
        .collect();
    let styles: Vec<Prepped> = keys
        .into_iter()
        .map(|(e, params)| {
            let ex = exemplars[e].clone();
            let source = cache.source(&names[e], &ex, &params, &opts.exemplar_dirs)?;
            let pigment = Pigment::from_exemplar(&ex);
            let name = match style_of_key(opts, &names[e]) {
                Style::Exemplar(ex) => ex.meta.name.clone(),
                _ => names[e].clone(),
            };
            Ok(Prepped { name, exemplar: ex, source, pigment, params })
        })
        .collect::<Result<_>>()?;
    Ok(Prepared { styles_of, region_style, styles })
}

/// Recolors one painted frame of a region ([`paint::Paint`], the engine's output after the
/// 16-bit quantization every path shares) against its flat rendering.
fn recolor_paint(
    paint: &paint::Paint,
    rf: &RegionFrame,
    pigment: &Pigment,
    opts: &RenderOptions,
) -> Result<StylizedLayer> {
    let (rgb, mask) = paint.rgb_mask();
    // A mask sequence's gray is coverage, not opacity: such a layer is opaque.
    composite::recolor_layer(&rgb, &mask, &target_fill(rf, opts.strokes), pigment, opts.recolor, rf.opacity_in_alpha)
}

/// Composites one frame from its regions (top-most first: a recolored layer or `None` for a
/// flat one, with the region's flat rendering) and writes it, and with
/// [`RenderOptions::keep_layers`] every layer alone into `layer_dirs`. Returns the files
/// written.
fn write_composite(
    anim: &Animation,
    opts: &RenderOptions,
    background: &composite::Background,
    frame: usize,
    results: &[(Option<StylizedLayer>, RegionFrame)],
    layer_dirs: &[PathBuf],
) -> Result<Vec<PathBuf>> {
    // Bottom to top: regions are listed top-most first.
    let frames: Vec<LayerFrame> = results
        .iter()
        .rev()
        .map(|(st, rf)| match st {
            Some(l) => LayerFrame::stylized(l, rf.strokes.as_ref()),
            None => LayerFrame::flat(&rf.fill, rf.strokes.as_ref()),
        })
        .collect();
    let image = composite::composite(anim.width as usize, anim.height as usize, background, &frames, opts.strokes)?;
    let mut written = Vec::with_capacity(results.len() + 1);
    if opts.keep_layers {
        for ((st, rf), dir) in results.iter().zip(layer_dirs) {
            let layer = match st {
                Some(l) => l.to_rgba(),
                None => rf.fill.clone(),
            };
            written.push(output::write_frame(dir, frame, anim.frames, &layer)?);
        }
    }
    written.push(output::write_frame(&opts.out_dir, frame, anim.frames, &image)?);
    Ok(written)
}

/// Checks where the frames, the layers and the GIF go, creates the folders and removes the
/// temporary files of a run that was killed while writing.
fn prepare_outputs(anim: &Animation, opts: &RenderOptions) -> Result<Vec<PathBuf>> {
    if let Some(gif) = &opts.gif {
        if gif.is_dir() {
            return Err(Error::io(
                gif,
                std::io::Error::new(std::io::ErrorKind::IsADirectory, "is a directory; --gif needs a file name"),
            ));
        }
        if let Some(dir) = gif.parent().filter(|d| !d.as_os_str().is_empty()) {
            output::prepare_dir(dir)?;
        }
    }
    output::prepare_dir(&opts.out_dir)?;
    let layer_dirs: Vec<PathBuf> = anim.regions.iter().map(|r| output::layer_dir(&opts.out_dir, r)).collect();
    if opts.keep_layers {
        for d in &layer_dirs {
            output::prepare_dir(d)?;
        }
    }
    output::remove_stale_temporaries(&opts.out_dir, None);
    for d in layer_dirs.iter().filter(|d| d.is_dir()) {
        output::remove_stale_temporaries(d, None);
    }
    if let Some(gif) = &opts.gif {
        // The GIF may be written anywhere: only its own temporary files.
        let dir = gif.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        output::remove_stale_temporaries(dir, gif.file_name().and_then(|n| n.to_str()));
    }
    Ok(layer_dirs)
}

/// Writes the GIF of `opts` from the frames written in `out_dir` (which also covers resumed
/// renders and composites).
fn write_gif(
    anim: &Animation,
    opts: &RenderOptions,
    range: &Range<usize>,
    background: &composite::Background,
    progress: &dyn Progress,
) -> Result<()> {
    let Some(gif) = &opts.gif else { return Ok(()) };
    let transparent = matches!(background, composite::Background::Transparent);
    let options = GifOptions { transparent, ..GifOptions::new(anim.fps) };
    let mut writer = GifWriter::create(gif, anim.width as usize, anim.height as usize, options)?;
    for frame in range.clone() {
        let path = output::frame_path(&opts.out_dir, frame, anim.frames);
        writer.add_frame(&img::load_rgba(&path)?)?;
        if !progress.update("gif", frame - range.start + 1, range.len()) {
            return Err(Error::Cancelled);
        }
    }
    writer.finish()?;
    Ok(())
}

/// The progress stage of region `r`: `"NN name"`.
fn stage_name(anim: &Animation, region: usize) -> String {
    let r = &anim.regions[region];
    format!("{:02} {}", r.index, r.name)
}

/// [`render`] with exemplars and prepared sources shared through `cache` (as in a batch).
pub(crate) fn render_with(
    anim: &Animation,
    opts: &RenderOptions,
    cache: &StyleCache,
    progress: &dyn Progress,
) -> Result<RenderSummary> {
    let start = Instant::now();
    let range = frame_range(anim, opts)?;
    let background = background(anim, opts)?;
    let prepared = prepare(anim, opts, &range, None, cache)?;
    let n = range.len();
    let painted = keys::painted_regions(anim, opts, &range, &background)?;
    // Resume: check that there is something to continue, made with the same options, before
    // anything is created or computed; then the output locations, checked before the work.
    let fingerprint = render_fingerprint(anim, opts, &range, &prepared)?;
    let (resumed, done) = open_journal(opts, fingerprint, n)?;
    let resume = match &resumed {
        _ if done >= n => keys::Resume::Nothing,
        Some(_) => keys::Resume::From(done),
        None => keys::Resume::Start,
    };
    let layer_dirs = prepare_outputs(anim, opts)?;
    output::remove_stale_temporaries(&opts.out_dir.join(STATE_DIR), None);
    let mut journal = match resumed {
        Some(journal) => journal,
        // Resumable from the start: an interruption before the first frame resumes too.
        None => Journal::create(&opts.out_dir, fingerprint, n, Remedy::RenderAgain)?,
    };
    // Layers painted from keyframes: every frame painted first (the backward passes), to the
    // state folder.
    let keyed = keys::paint_regions(anim, opts, &range, &painted, &opts.out_dir.join(STATE_DIR), resume, progress)?;

    let stages: Vec<String> = (0..anim.regions.len()).map(|r| stage_name(anim, r)).collect();
    let mut layers = start_layers(anim, opts, &range, &prepared, done, &keyed)?;
    if done > 0 {
        restore(&journal, done, &mut layers, &stages)?;
    }
    for (l, s) in layers.iter().zip(&stages) {
        if l.synth.is_some() && !progress.update(s, done, n) {
            return Err(Error::Cancelled);
        }
    }
    if !progress.update(TOTAL_STAGE, done, n) {
        return Err(Error::Cancelled);
    }
    let mut written = 0usize;
    for k in done..n {
        let frame = range.start + k;
        let results: Vec<(Option<StylizedLayer>, RegionFrame)> = layers
            .par_iter_mut()
            .zip(&stages)
            .map(|(l, stage)| {
                let rf = anim.render(l.region, frame)?;
                let layer = match &keyed[l.region] {
                    Some(frames) => {
                        let (rgb, mask) = frames.frame(k)?.rgb_mask();
                        Some(composite::painted(&rgb, &mask)?)
                    }
                    None => paint_layer(anim, opts, &prepared.styles, l, &rf, frame)?,
                };
                // This layer's bar moves as soon as its frame is done; the frame is only
                // written (and the state saved) once every layer has it.
                if layer.is_some() && !progress.update(stage, k + 1, n) {
                    return Err(Error::Cancelled);
                }
                Ok((layer, rf))
            })
            .collect::<Result<_>>()?;
        for path in write_composite(anim, opts, &background, frame, &results, &layer_dirs)? {
            journal.record(k, &path)?;
        }
        journal.commit(k + 1, &layer_states(&layers, &stages))?;
        written += 1;
        if !progress.update(TOTAL_STAGE, k + 1, n) {
            return Err(Error::Cancelled);
        }
    }

    keyed.iter().flatten().for_each(keys::KeyedFrames::remove);
    let _ = std::fs::remove_dir(opts.out_dir.join(STATE_DIR).join("keyframes"));
    write_gif(anim, opts, &range, &background, progress)?;
    // The progress file and the frames log stay (they say the render is complete and what it
    // wrote, for a later --resume).
    journal.finish();
    Ok(RenderSummary {
        frames: written,
        resumed: done,
        seconds: start.elapsed().as_secs_f64(),
        frame_dir: opts.out_dir.clone(),
        gif: opts.gif.clone(),
        layers: summarize(anim, opts, &prepared.styles, &layers, &keyed)?,
    })
}

/// The progress stage of the whole render (one step per frame written).
const TOTAL_STAGE: &str = "frames";

/// What a render's state must match to be resumed: the input's content and every option that
/// changes the output.
fn render_fingerprint(anim: &Animation, opts: &RenderOptions, range: &Range<usize>, p: &Prepared) -> Result<u64> {
    let input = resume::input_digest(&anim.path)?;
    let keys: Vec<(usize, u64)> =
        opts.keyframes.iter().map(|(f, path)| Ok((*f, resume::input_digest(path)?))).collect::<Result<_>>()?;
    let (w, h) = (anim.width as usize, anim.height as usize);
    Ok(resume::fingerprint(&format!(
        "{}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{}|{}|{:?}|{}|{:?}",
        input,
        range,
        p.styles_of,
        opts.recolor,
        opts.strokes,
        opts.background.fingerprint_spec(),
        opts.params,
        anim.scale(),
        w * 100_000 + h,
        p.styles.iter().map(|s| s.source.frames()).collect::<Vec<_>>(),
        opts.keep_layers,
        keys,
    )))
}

/// With `--resume`, the journal of the render to continue (made with the same `fingerprint`)
/// and how many frames it has done. The frames already written must be the ones recorded; the
/// engine's state before the first damaged one is gone, so a damaged frame means rendering
/// again from the start (`None`).
fn open_journal(opts: &RenderOptions, fingerprint: u64, frames: usize) -> Result<(Option<Journal>, usize)> {
    if !opts.resume {
        return Ok((None, 0));
    }
    let (journal, done) = Journal::open(&opts.out_dir, fingerprint, frames, Remedy::RenderAgain)?;
    Ok(if verified(&journal, "rendering again from the start") { (Some(journal), done) } else { (None, 0) })
}

/// Per-layer synthesizers and guide streams (the guides' backward pass runs here), in
/// parallel over the layers; none where a layer is flat or every frame was done already (only
/// the GIF was missing).
fn start_layers(
    anim: &Animation,
    opts: &RenderOptions,
    range: &Range<usize>,
    p: &Prepared,
    done: usize,
    keyed: &[Option<keys::KeyedFrames>],
) -> Result<Vec<Layer>> {
    (0..anim.regions.len())
        .into_par_iter()
        .map(|region| -> Result<Layer> {
            // Layers painted from keyframes are not synthesized from an exemplar.
            let style = p.region_style[region].filter(|_| keyed[region].is_none());
            let (synth, guides) = match style {
                Some(s) if done < range.len() => {
                    let (synth, stream) = start_layer(anim, opts, region, range, &p.styles[s])?;
                    (Some(synth), Some(stream))
                }
                _ => (None, None),
            };
            Ok(Layer { region, style, synth, guides, seconds: 0.0, kept: Vec::new() })
        })
        .collect()
}

/// Synthesizes and recolors layer `l`'s frame `frame` (`rf`, the region's frame); `None` for
/// a flat layer. With `eval`, keeps the exemplar-colored frame and the target's coverage.
fn paint_layer(
    anim: &Animation,
    opts: &RenderOptions,
    styles: &[Prepped],
    l: &mut Layer,
    rf: &RegionFrame,
    frame: usize,
) -> Result<Option<StylizedLayer>> {
    let (Some(synth), Some(guides), Some(s)) = (l.synth.as_mut(), l.guides.as_mut(), l.style) else {
        return Ok(None);
    };
    let t0 = Instant::now();
    let out = next_frame(anim, synth, guides, frame)?;
    let layer = recolor_paint(&paint::Paint::from_frame(&out.rgb, &out.mask), rf, &styles[s].pigment, opts)?;
    l.seconds += t0.elapsed().as_secs_f64();
    if opts.eval {
        let q = |v: f32| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
        let rgba: Vec<u8> = out
            .rgb
            .data()
            .iter()
            .zip(out.mask.data())
            .flat_map(|(c, &m)| [q(c[0]), q(c[1]), q(c[2]), if m { 255 } else { 0 }])
            .collect();
        let cov: Vec<u8> = target_coverage(rf, opts.strokes).data().iter().map(|&c| q(c)).collect();
        l.kept.push((rgba, cov));
    }
    Ok(Some(layer))
}

/// Each layer's summary: its style, time, and with `eval` its measures.
fn summarize(
    anim: &Animation,
    opts: &RenderOptions,
    styles: &[Prepped],
    layers: &[Layer],
    keyed: &[Option<keys::KeyedFrames>],
) -> Result<Vec<LayerSummary>> {
    let (w, h) = (anim.width as usize, anim.height as usize);
    layers
        .iter()
        .map(|l| {
            let r = &anim.regions[l.region];
            let eval = match (opts.eval, l.style) {
                (true, Some(s)) if !l.kept.is_empty() => Some(evaluate_layer(l, &styles[s], w, h)?),
                _ => None,
            };
            Ok(LayerSummary {
                index: r.index,
                name: r.name.clone(),
                exemplar: match &keyed[l.region] {
                    Some(_) => Some(KEYFRAMES_STYLE.to_string()),
                    None => l.style.map(|s| styles[s].name.clone()),
                },
                seconds: l.seconds + keyed[l.region].as_ref().map_or(0.0, |k| k.seconds),
                eval,
            })
        })
        .collect()
}

/// The synthesizer and guide stream of one stylized region over `range`.
fn start_layer(
    anim: &Animation,
    opts: &RenderOptions,
    region: usize,
    range: &Range<usize>,
    style: &Prepped,
) -> Result<(Synthesizer, GuideStream)> {
    let (first, strokes) = (range.start, opts.strokes);
    crate::synth::start(
        || Ok(style.source.clone()),
        &style.params,
        range.len(),
        |k| Ok(target_coverage(&anim.render(region, first + k)?, strokes)),
    )
}

/// Synthesizes the next frame (animation frame `frame`) of a layer.
fn next_frame(
    anim: &Animation,
    synth: &mut Synthesizer,
    guides: &mut GuideStream,
    frame: usize,
) -> Result<crate::synth::SynthFrame> {
    let g = guides.next().ok_or_else(|| Error::Empty {
        path: anim.path.clone(),
        what: format!("the guides ended before frame {}", frame + 1),
    })??;
    synth.step(&g)
}

fn evaluate_layer(l: &Layer, style: &Prepped, w: usize, h: usize) -> Result<eval::Report> {
    let unorm = |v: u8| v as f32 / 255.0;
    let frames: Vec<Plane<Rgba>> = l
        .kept
        .iter()
        .map(|(rgba, _)| {
            Plane::from_vec(
                w,
                h,
                rgba.chunks(4).map(|c| [unorm(c[0]), unorm(c[1]), unorm(c[2]), unorm(c[3])]).collect(),
            )
            .unwrap_or_else(|| Plane::new(w, h))
        })
        .collect();
    let masks: Vec<Plane<f32>> = l
        .kept
        .iter()
        .map(|(_, cov)| {
            Plane::from_vec(w, h, cov.iter().map(|&v| unorm(v)).collect()).unwrap_or_else(|| Plane::new(w, h))
        })
        .collect();
    let options = eval::EvalOptions {
        exemplar_scale: style.params.src_scale(),
        exemplar_step: style.params.src_speed(),
        ..Default::default()
    };
    eval::evaluate(&frames, &style.exemplar, &masks, &options)
}

/// The state of every stylized layer, by its stage name, to commit after a frame.
fn layer_states<'a>(layers: &[Layer], stages: &'a [String]) -> Vec<(&'a str, Vec<u8>)> {
    layers
        .iter()
        .zip(stages)
        .filter_map(|(l, stage)| l.synth.as_ref().map(|s| (stage.as_str(), s.save_state())))
        .collect()
}

/// Whether every file that `journal` recorded is as it was written; warns of each that is
/// not, and then that the work is done again (`then`).
fn verified(journal: &Journal, then: &str) -> bool {
    let damage = journal.verify();
    for d in &damage {
        log::warn!("'{}' {}", d.path.display(), d.what);
    }
    if !damage.is_empty() {
        log::warn!("files written by the interrupted render were changed or removed; {then}");
    }
    damage.is_empty()
}

/// Restores every layer's state after `done` frames from `journal`, moves its guides past
/// those frames and checks the state against the guides of the last one.
fn restore(journal: &Journal, done: usize, layers: &mut [Layer], stages: &[String]) -> Result<()> {
    for (l, stage) in layers.iter_mut().zip(stages) {
        let (Some(s), Some(guides)) = (l.synth.as_mut(), l.guides.as_mut()) else { continue };
        let (bytes, file) = journal.load_state(stage, done)?;
        s.load_state(&bytes, &file).map_err(|e| journal.advise(e))?;
        if s.frame() != done {
            return Err(journal.advise(Error::Corrupt {
                path: file,
                message: format!("holds frame {} but the render stopped after {}", s.frame(), done),
            }));
        }
        let mut last = None;
        for _ in 0..done {
            last = guides.next().transpose()?;
        }
        s.check_resumed(last.as_ref(), &file).map_err(|e| journal.advise(e))?;
    }
    Ok(())
}
