//! The quality suite (`fluidymation quality`): every exemplar painted onto generated targets
//! with exactly the pipeline `synth` and `render` use, measured with [`crate::eval`], in one
//! table.
//!
//! For each exemplar the suite runs
//!
//! * the **identity**: the target is the exemplar's own masks at its full size (after its
//!   recommended or given step and scale). The output should be the exemplar itself; besides
//!   the usual measures the row reports the PSNR inside the mask per frame (median and worst);
//! * the generated targets of [`TargetKind`] — still, growing, shrinking, translating,
//!   rotating, a thin limb (48 frames by default) and a long one (300 frames), on a 512 × 512
//!   canvas like the layers users paint ([`SuiteOptions::scale`] reduces it, scaling the
//!   exemplar along as `render --scale` does). The long target is also reported per window
//!   of [`SuiteOptions::window`] frames, with each window's contrast and edge darkening
//!   relative to the first window's.
//!
//! **Pipeline.** Per run, as `synth` and `render` paint a layer: σ and b fitted to the target's
//! thickness ([`Params::fit_to_thickness`], unless switched off), [`Source::prepare`] and the
//! [`GuideStream`](crate::guide::GuideStream) by [`crate::synth::start`], and
//! [`Synthesizer::step`](crate::synth::Synthesizer::step) per frame, with [`SuiteOptions::params`]
//! (defaults and `--seed 1` unless given).
//!
//! **Measures.** The output (the engine's RGB with alpha = its mask) is flattened over the
//! exemplar's paper and measured with an [`Evaluator`] as it is produced (memory does not grow
//! with the length). Coverage is measured **by color**: a pixel is painted where the flattened
//! output differs from the paper by more than [`EvalOptions::paint_threshold`] — what a
//! viewer sees; the engine's alpha is a pre-processed (blurred and re-thresholded) mask that
//! includes a little paper, so its IoU ([`Row::coverage_alpha`]) is reported beside it.
//! Motion agreement on a generated target is measured against its known motion
//! ([`Target::motion`], [`Evaluator::with_motion`]): its masks show only the normal part, which
//! rewarded paint that turned at two thirds of a turning ellipse's speed (the flow guide before
//! 2026-12-06; 0.84–0.86 against the normal part, 0.56–0.59 against the whole, 0.94–0.97 with
//! today's flow); the identity, whose motion is not known, keeps the masks' normal motion.
//!
//! **Parallelism.** Runs go through [`SuiteOptions::jobs`] lanes at once (each run's frames
//! in order, its stages parallel inside); every number depends only on the inputs and the
//! seed, not on the thread or lane count.
//!
//! ```no_run
//! use fluidymation::quality::{self, SuiteOptions, TargetKind};
//! # fn main() -> fluidymation::Result<()> {
//! // A quick look: one exemplar, two targets at half size, 16 frames.
//! let opts = SuiteOptions::default()
//!     .exemplars(["ink-rims"])
//!     .targets([TargetKind::Growing, TargetKind::Limb])
//!     .scale(0.5)
//!     .frames(16);
//! let report = quality::run(&opts, &fluidymation::NoProgress)?;
//! println!("{report}");
//! # Ok(()) }
//! ```

mod sheet;
mod table;
pub mod targets;

pub use targets::{Target, TargetKind};

use crate::error::{Error, Result};
use crate::eval::{
    self, EvalOptions, Evaluator, ExemplarSummary, Painted, Reference, RimParams, Summary, intersection_union,
};
use crate::exemplar::{self, Exemplar, SearchPath};
use crate::img::{Mask, Plane, Rgb, Rgba};
use crate::progress::Progress;
use crate::synth::{Params, Source, resample_exemplar, sequence_thickness};
use serde::{Deserialize, Serialize};
use sheet::SheetRow;
use std::path::PathBuf;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

/// Side of the generated targets at scale 1, pixels.
pub const DEFAULT_SIDE: usize = 512;

/// The name of the identity run (the exemplar's own masks as the target).
pub const IDENTITY: &str = "identity";

/// The least edge-darkening ratio (to the exemplar's) of the long target's first window for
/// the other windows' rims to be compared with it.
pub const MIN_RIM_TO_KEEP: f32 = 0.1;

/// PSNR reported for a frame identical to the exemplar's, dB.
pub const PSNR_CAP: f32 = 100.0;

/// What the suite runs: `SuiteOptions::default().exemplars(["ink-rims"]).scale(0.5)`.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct SuiteOptions {
    /// Exemplars by name or folder (names are looked up like `synth --exemplar`); empty = every
    /// bundled exemplar.
    pub exemplars: Vec<String>,
    /// Extra folders to look up exemplars by name.
    pub exemplar_dirs: Vec<PathBuf>,
    /// Generated targets to run. Default: all of [`TargetKind::ALL`].
    pub targets: Vec<TargetKind>,
    /// Also run the identity (the exemplar's own masks as the target). Default: true.
    pub identity: bool,
    /// Size of the generated targets relative to [`DEFAULT_SIDE`]; the exemplar, the blur σ,
    /// the border width and the temporal bounds are scaled alike, as `render --scale` does, and
    /// so are the distances of the edge-darkening measure ([`RimParams`]), so that a reduced
    /// run measures the same parts of the picture (the identity stays at full size). Default: 1.
    pub scale: f32,
    /// Frames of every generated target but the long one. Default: 48.
    pub frames: usize,
    /// Frames of the long target. Default: 300.
    pub long_frames: usize,
    /// Window of the long target's per-window rows, frames. Default: 50.
    pub window: usize,
    /// Engine parameters (every flag of `synth`; the seed among them). Default: the defaults,
    /// seed 1.
    pub params: Params,
    /// Measuring options (the exemplar's step and scale are taken from the engine's).
    /// Default: [`EvalOptions::default`].
    pub eval: EvalOptions,
    /// Write a contact sheet per run into this folder (`EXEMPLAR-TARGET.png`). Default: none.
    pub sheets: Option<PathBuf>,
    /// Runs painted at the same time. Default: 2.
    pub jobs: usize,
}

impl Default for SuiteOptions {
    fn default() -> Self {
        SuiteOptions {
            exemplars: Vec::new(),
            exemplar_dirs: Vec::new(),
            targets: TargetKind::ALL.to_vec(),
            identity: true,
            scale: 1.0,
            frames: 48,
            long_frames: 300,
            window: 50,
            params: Params::default(),
            eval: EvalOptions::default(),
            sheets: None,
            jobs: 2,
        }
    }
}

impl SuiteOptions {
    /// Sets [`SuiteOptions::exemplars`], names or folders. Default: every bundled exemplar.
    pub fn exemplars<S: Into<String>>(mut self, exemplars: impl IntoIterator<Item = S>) -> Self {
        self.exemplars = exemplars.into_iter().map(Into::into).collect();
        self
    }

    /// Sets [`SuiteOptions::exemplar_dirs`]. Default: none.
    pub fn exemplar_dirs<P: Into<PathBuf>>(mut self, dirs: impl IntoIterator<Item = P>) -> Self {
        self.exemplar_dirs = dirs.into_iter().map(Into::into).collect();
        self
    }

    /// Sets [`SuiteOptions::targets`]. Default: all of [`TargetKind::ALL`].
    pub fn targets(mut self, targets: impl IntoIterator<Item = TargetKind>) -> Self {
        self.targets = targets.into_iter().collect();
        self
    }

    /// Sets [`SuiteOptions::identity`]. Default: true.
    pub fn identity(mut self, yes: bool) -> Self {
        self.identity = yes;
        self
    }

    /// Sets [`SuiteOptions::scale`], in `(0, 4]`. Default: 1.
    pub fn scale(mut self, scale: f32) -> Self {
        self.scale = scale;
        self
    }

    /// Sets [`SuiteOptions::frames`], in `2..=10000`. Default: 48.
    pub fn frames(mut self, frames: usize) -> Self {
        self.frames = frames;
        self
    }

    /// Sets [`SuiteOptions::long_frames`], in `2..=10000`. Default: 300.
    pub fn long_frames(mut self, frames: usize) -> Self {
        self.long_frames = frames;
        self
    }

    /// Sets [`SuiteOptions::window`], frames. Default: 50.
    pub fn window(mut self, frames: usize) -> Self {
        self.window = frames;
        self
    }

    /// Sets [`SuiteOptions::params`]. Default: the defaults, seed 1.
    pub fn params(mut self, params: Params) -> Self {
        self.params = params;
        self
    }

    /// Sets [`SuiteOptions::eval`]. Default: [`EvalOptions::default`].
    pub fn eval(mut self, eval: EvalOptions) -> Self {
        self.eval = eval;
        self
    }

    /// Sets [`SuiteOptions::sheets`], the folder of the contact sheets. Default: none.
    pub fn sheets(mut self, dir: impl Into<PathBuf>) -> Self {
        self.sheets = Some(dir.into());
        self
    }

    /// Sets [`SuiteOptions::jobs`], in `1..=64`. Default: 2.
    pub fn jobs(mut self, jobs: usize) -> Self {
        self.jobs = jobs;
        self
    }

    /// Checks the settings; the error names the command-line flag.
    pub fn validate(&self) -> Result<()> {
        if !(self.scale.is_finite() && self.scale > 0.0 && self.scale <= 4.0) {
            return Err(Error::param("--scale", self.scale, "a factor in (0, 4]"));
        }
        let side = self.side();
        if side < 64 {
            return Err(Error::param(
                "--scale",
                self.scale,
                format!("a factor giving targets of at least 64 px (got {side})"),
            ));
        }
        for (name, v) in [("--frames", self.frames), ("--long-frames", self.long_frames)] {
            if !(2..=10_000).contains(&v) {
                return Err(Error::param(name, v, "2..=10000 frames"));
            }
        }
        if self.window == 0 {
            return Err(Error::param("--window", self.window, "at least 1 frame"));
        }
        if !(1..=64).contains(&self.jobs) {
            return Err(Error::param("--jobs", self.jobs, "1..=64"));
        }
        if !self.identity && self.targets.is_empty() {
            return Err(Error::param("targets", "none", "at least one target or the identity"));
        }
        self.eval.validate()
    }

    /// Side of the generated targets, pixels.
    pub fn side(&self) -> usize {
        (DEFAULT_SIDE as f32 * self.scale).round() as usize
    }

    fn frames_of(&self, kind: TargetKind) -> usize {
        if kind == TargetKind::Long { self.long_frames } else { self.frames }
    }
}

/// The identity's own numbers.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Identity {
    /// Median over the frames of the PSNR inside the exemplar's mask (RGB, flattened output
    /// against the exemplar frame), dB; [`PSNR_CAP`] for identical frames.
    pub psnr_median: f32,
    /// The worst frame's PSNR, dB.
    pub psnr_min: f32,
    /// The worst frame (1-based).
    pub psnr_min_frame: usize,
    /// Every frame's PSNR, dB.
    pub psnr: Vec<f32>,
}

/// One window of the long target.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Window {
    /// First frame (1-based).
    pub first: usize,
    /// Last frame (1-based, inclusive).
    pub last: usize,
    /// The measures over these frames (pairs count at their second frame).
    pub summary: Summary,
    /// This window's local contrast ÷ the first window's.
    pub contrast_vs_first: Option<f32>,
    /// This window's edge darkening ÷ the first window's; `None` when the first window has
    /// less than [`MIN_RIM_TO_KEEP`] of the exemplar's (a ratio to a rim that is not there
    /// says nothing).
    pub rim_vs_first: Option<f32>,
}

/// One exemplar on one target.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// The exemplar's name.
    pub exemplar: String,
    /// The target: a [`TargetKind`] name or `identity`.
    pub target: String,
    /// Frames painted.
    pub frames: usize,
    /// Frame width, pixels.
    pub width: usize,
    /// Frame height, pixels.
    pub height: usize,
    /// Blur σ the engine used (after the thickness fit), pixels.
    pub blur_sigma: f32,
    /// Border width b the engine used (after the thickness fit), exemplar pixels.
    pub border_width: f32,
    /// Whether σ or b were lowered to fit the target's thickness.
    pub fitted: bool,
    /// The most pyramid levels the fit allowed (`None`: the frame size alone decides).
    pub max_levels: Option<usize>,
    /// Every measure over the whole run (coverage by color, see the module documentation).
    pub summary: Summary,
    /// IoU of the engine's alpha with the target (pooled over frames).
    pub coverage_alpha: Option<f32>,
    /// The exemplar's own values.
    pub exemplar_summary: ExemplarSummary,
    /// The long target's windows (empty for the others).
    pub windows: Vec<Window>,
    /// The identity's PSNR (only on the identity row).
    pub identity: Option<Identity>,
    /// Wall-clock seconds of painting and measuring this run.
    pub seconds: f64,
    /// Of which measuring (the rest is mostly painting).
    pub measure_seconds: f64,
}

/// Everything the suite measured; its [`Display`](std::fmt::Display) is the table.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SuiteReport {
    /// Side of the generated targets, pixels.
    pub side: usize,
    /// Their scale relative to [`DEFAULT_SIDE`].
    pub scale: f32,
    /// Frames of the short targets.
    pub frames: usize,
    /// Frames of the long target.
    pub long_frames: usize,
    /// Window of the long target, frames.
    pub window: usize,
    /// The engine's seed.
    pub seed: u64,
    /// How coverage is measured.
    pub coverage: String,
    /// One row per exemplar and target, exemplars in the order given, the identity first.
    pub rows: Vec<Row>,
    /// Contact sheets written.
    pub sheets: Vec<PathBuf>,
    /// Wall-clock seconds of the whole suite.
    pub seconds: f64,
}

/// What a run paints and against what.
pub struct RunSpec<'a> {
    /// The exemplar.
    pub exemplar: &'a Exemplar,
    /// Its position among the suite's exemplars.
    pub exemplar_index: usize,
    /// The target's name.
    pub target: &'a str,
    /// Number of frames.
    pub frames: usize,
    /// Target coverage of frame k.
    pub coverage: &'a (dyn Fn(usize) -> Plane<f32> + Sync),
    /// The engine parameters for this run (fitted to the target's thickness).
    pub params: &'a Params,
    /// The exemplar as measured.
    pub reference: &'a Reference,
}

/// One painted frame: RGB in the exemplar's colors and the painted mask (the output's alpha).
pub struct PaintedFrame {
    /// Colors (outside the mask they are replaced by the paper).
    pub rgb: Plane<Rgb>,
    /// Where paint is.
    pub mask: Mask,
}

/// Paints a run's frames in order. [`Engine`] is the suite's; tests substitute stand-ins to
/// check the measuring on outputs with known answers.
pub trait Painter: Sync {
    /// Paints the frames of `run` in order, handing each to `emit`.
    fn paint(&self, run: &RunSpec<'_>, emit: &mut dyn FnMut(PaintedFrame) -> Result<()>) -> Result<()>;
}

/// The synthesis engine, as `synth` and `render` run it per layer (prepared exemplars are
/// shared between runs with the same parameters).
#[derive(Default)]
pub struct Engine {
    sources: Mutex<Vec<((usize, Params), Source)>>,
}

impl Engine {
    fn source(&self, run: &RunSpec<'_>) -> Result<Source> {
        let key = (run.exemplar_index, run.params.clone());
        let mut cache = self.sources.lock().map_err(|_| Error::param("engine", "poisoned", "a usable cache"))?;
        if let Some((_, s)) = cache.iter().find(|(k, _)| *k == key) {
            return Ok(s.clone());
        }
        let source = Source::prepare(run.exemplar, run.params)?;
        cache.push((key, source.clone()));
        Ok(source)
    }
}

impl Painter for Engine {
    fn paint(&self, run: &RunSpec<'_>, emit: &mut dyn FnMut(PaintedFrame) -> Result<()>) -> Result<()> {
        let (mut synth, stream) =
            crate::synth::start(|| self.source(run), run.params, run.frames, |k| Ok((run.coverage)(k)))?;
        for g in stream {
            let out = synth.step(&g?)?;
            emit(PaintedFrame { rgb: out.rgb, mask: out.mask })?;
        }
        Ok(())
    }
}

/// Parameters for targets at `scale` (as `render --scale`): the exemplar, the blur σ, the
/// border width and the temporal bounds scaled along.
fn scaled_params(base: &Params, ex: &Exemplar, scale: f32) -> Result<Params> {
    if (scale - 1.0).abs() < 1e-6 {
        return Ok(base.clone());
    }
    let (m_l, m_u) = base.prev_bounds();
    let mut b = base
        .to_builder()
        .src_scale(base.src_scale().unwrap_or(ex.meta.scale) * scale)
        .blur_sigma(base.guide().blur_sigma * scale)
        .prev_bounds(m_l * scale, m_u * scale);
    if let Some(w) = base.border_width() {
        b = b.border_width(w * scale);
    }
    b.build()
}

/// `scale` of the exemplar and step the engine uses with `params`.
fn exemplar_view(params: &Params, ex: &Exemplar) -> (f32, usize) {
    (params.src_scale().unwrap_or(ex.meta.scale), params.src_speed().unwrap_or(ex.meta.speed).max(1))
}

/// PSNR of `out` against `reference` over `mask` (coverage ≥ [`eval::MASK_THRESHOLD`]), dB
/// (capped at [`PSNR_CAP`]); `None` for an empty mask.
pub fn psnr(out: &Plane<Rgb>, reference: &Plane<Rgb>, mask: &Plane<f32>) -> Option<f32> {
    let (mut se, mut n) = (0f64, 0u64);
    for ((o, r), &m) in out.data().iter().zip(reference.data()).zip(mask.data()) {
        if m >= eval::MASK_THRESHOLD {
            se += (0..3).map(|k| ((o[k] - r[k]) as f64).powi(2)).sum::<f64>();
            n += 3;
        }
    }
    (n > 0).then(|| {
        let mse = se / n as f64;
        if mse <= 0.0 { PSNR_CAP } else { ((10.0 * (1.0 / mse).log10()) as f32).min(PSNR_CAP) }
    })
}

/// One run to do.
struct Job {
    exemplar: usize,
    fitted: bool,
    /// `None` = the identity.
    target: Option<TargetKind>,
    frames: usize,
    params: Params,
    /// How it is measured.
    eval: EvalOptions,
    reference: usize,
}

fn name_of(target: Option<TargetKind>) -> &'static str {
    target.map_or(IDENTITY, TargetKind::name)
}

/// Indices of `count` frames spread evenly over `frames` (first and last included).
fn spread(frames: usize, count: usize) -> Vec<usize> {
    let count = count.min(frames).max(1);
    if count == 1 {
        return vec![0];
    }
    (0..count).map(|i| i * (frames - 1) / (count - 1)).collect()
}

/// Runs the suite with the engine; see the [module documentation](self).
pub fn run(options: &SuiteOptions, progress: &dyn Progress) -> Result<SuiteReport> {
    run_with(options, &Engine::default(), progress)
}

/// Runs the suite with `painter` in place of the engine.
pub fn run_with(options: &SuiteOptions, painter: &dyn Painter, progress: &dyn Progress) -> Result<SuiteReport> {
    let start = Instant::now();
    options.validate()?;
    let exemplars: Vec<Exemplar> = if options.exemplars.is_empty() {
        let bundled = SearchPath::new().with_bundled(true);
        exemplar::list(&bundled).iter().map(|info| exemplar::find(&info.name, &bundled)).collect::<Result<_>>()?
    } else {
        let search = SearchPath::standard(&options.exemplar_dirs);
        options.exemplars.iter().map(|e| exemplar::find(e, &search)).collect::<Result<_>>()?
    };
    let side = options.side();

    // The runs, each with its parameters fitted to its target's thickness.
    let mut plan: Vec<(usize, Option<TargetKind>)> = Vec::new();
    for e in 0..exemplars.len() {
        if options.identity {
            plan.push((e, None));
        }
        plan.extend(options.targets.iter().map(|&t| (e, Some(t))));
    }
    let identity_masks: Vec<Vec<Plane<f32>>> = exemplars
        .iter()
        .map(|ex| {
            let (scale, step) = exemplar_view(&options.params, ex);
            if options.identity { resample_exemplar(ex, scale, step).1 } else { Vec::new() }
        })
        .collect();
    let mut references: Vec<((usize, EvalOptions), Reference)> = Vec::new();
    let mut jobs: Vec<Job> = Vec::new();
    for &(e, target) in &plan {
        let ex = &exemplars[e];
        let base = match target {
            None => options.params.clone(),
            Some(_) => scaled_params(&options.params, ex, options.scale)?,
        };
        let (frames, thickness) = match target {
            None => {
                let masks = &identity_masks[e];
                (masks.len(), sequence_thickness(masks.len(), |k| Ok(masks[k].clone()))?)
            }
            Some(kind) => {
                let t = Target::new(kind, side, options.frames_of(kind));
                (t.frames(), sequence_thickness(t.frames(), |k| Ok(t.coverage(k)))?)
            }
        };
        let params = match thickness {
            Some(t) if base.fit_thin() => base.fit_to_thickness(t, base.exemplar_border_width(ex)),
            _ => base.clone(),
        };
        let fitted = params != base;
        // The exemplar as the engine sees it; the rim's distances scale with the picture.
        let scale = if target.is_some() { options.scale } else { 1.0 };
        let eval = EvalOptions {
            exemplar_scale: params.src_scale(),
            exemplar_step: params.src_speed(),
            rim: RimParams {
                band: options.eval.rim.band * scale,
                interior: options.eval.rim.interior * scale,
                ..options.eval.rim
            },
            ..options.eval.clone()
        };
        let key = (e, eval.clone());
        let reference = match references.iter().position(|(k, _)| *k == key) {
            Some(i) => i,
            None => {
                references.push((key, Reference::new(ex, &eval)?));
                references.len() - 1
            }
        };
        jobs.push(Job { exemplar: e, fitted, target, frames, params, eval, reference });
    }
    if let Some(dir) = &options.sheets {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }

    // Paint and measure, `jobs` runs at a time.
    let total: usize = jobs.iter().map(|j| j.frames).sum();
    let done = AtomicUsize::new(0);
    let next = AtomicUsize::new(0);
    let cancelled = AtomicBool::new(false);
    let results: Vec<Mutex<Option<Result<RunResult>>>> = jobs.iter().map(|_| Mutex::new(None)).collect();
    let lanes = options.jobs.min(jobs.len()).max(1);
    std::thread::scope(|scope| {
        for _ in 0..lanes {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    if i >= jobs.len() || cancelled.load(Ordering::SeqCst) {
                        break;
                    }
                    let job = &jobs[i];
                    let stage = format!("{} {}", exemplars[job.exemplar].meta.name, name_of(job.target));
                    let tick = || {
                        let d = done.fetch_add(1, Ordering::SeqCst) + 1;
                        if !progress.update(&stage, d, total) {
                            cancelled.store(true, Ordering::SeqCst);
                            return false;
                        }
                        true
                    };
                    let r = run_job(
                        options,
                        painter,
                        job,
                        &exemplars,
                        &identity_masks,
                        &references[job.reference].1,
                        &tick,
                    );
                    if r.is_err() {
                        cancelled.store(true, Ordering::SeqCst);
                    }
                    if let Ok(mut slot) = results[i].lock() {
                        *slot = Some(r);
                    }
                }
            });
        }
    });
    let mut rows = Vec::with_capacity(jobs.len());
    let mut sheets = Vec::new();
    let mut first_error = None;
    for slot in results {
        match slot.into_inner().ok().flatten() {
            Some(Ok((row, sheet))) => {
                rows.push(row);
                sheets.extend(sheet);
            }
            // A cancellation is reported only when nothing else went wrong.
            Some(Err(e)) if first_error.as_ref().is_none_or(|f| matches!(f, Error::Cancelled)) => {
                first_error = Some(e);
            }
            Some(Err(_)) => {}
            None => {}
        }
    }
    if let Some(e) = first_error {
        return Err(e);
    }
    if rows.len() < jobs.len() {
        return Err(Error::Cancelled);
    }
    Ok(SuiteReport {
        side,
        scale: options.scale,
        frames: options.frames,
        long_frames: options.long_frames,
        window: options.window,
        seed: options.params.seed(),
        coverage: format!(
            "by color: painted where the output flattened over the paper differs from the paper by more than {}",
            options.eval.paint_threshold
        ),
        rows,
        sheets,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// A run's row and the contact sheet it wrote.
type RunResult = (Row, Option<PathBuf>);

/// Frames measured at once.
const BATCH: usize = 8;

fn run_job(
    options: &SuiteOptions,
    painter: &dyn Painter,
    job: &Job,
    exemplars: &[Exemplar],
    identity_masks: &[Vec<Plane<f32>>],
    reference: &Reference,
    tick: &dyn Fn() -> bool,
) -> Result<RunResult> {
    let start = Instant::now();
    let ex = &exemplars[job.exemplar];
    let target_name = name_of(job.target);
    let generated = job.target.map(|kind| Target::new(kind, options.side(), job.frames));
    let coverage = |k: usize| match &generated {
        Some(t) => t.coverage(k),
        None => identity_masks[job.exemplar][k].clone(),
    };
    let paper = reference.paper();
    let painted = Painted::Color { background: paper, threshold: job.eval.paint_threshold };
    let mut evaluator = Evaluator::new(reference, &job.eval, job.frames, painted)?;
    if let Some(t) = generated {
        evaluator = evaluator.with_motion(Box::new(move |k, x, y| t.motion(k, x, y)));
    }
    let sheet_frames = spread(job.frames, if job.frames >= 200 { 6 } else { 4 });
    let mut kept: Vec<(usize, Plane<Rgb>)> = Vec::new();
    let mut batch: Vec<(Plane<Rgba>, Plane<f32>)> = Vec::with_capacity(BATCH);
    let (mut inter, mut union) = (0u64, 0u64);
    let mut psnrs: Vec<f32> = Vec::new();
    let mut k = 0usize;
    let mut measuring = 0f64;
    let flush = |batch: &mut Vec<(Plane<Rgba>, Plane<f32>)>, evaluator: &mut Evaluator<'_>, measuring: &mut f64| {
        let t = Instant::now();
        let (frames, masks): (Vec<_>, Vec<_>) = batch.drain(..).unzip();
        let r = evaluator.push(&frames, &masks);
        *measuring += t.elapsed().as_secs_f64();
        r
    };
    let run = RunSpec {
        exemplar: ex,
        exemplar_index: job.exemplar,
        target: target_name,
        frames: job.frames,
        coverage: &coverage,
        params: &job.params,
        reference,
    };
    painter.paint(&run, &mut |frame: PaintedFrame| {
        if k >= job.frames {
            return Err(Error::param("painter", format!("frame {}", k + 1), format!("at most {} frames", job.frames)));
        }
        let target = coverage(k);
        let flat = Plane::from_fn(frame.rgb.width(), frame.rgb.height(), |x, y| {
            if frame.mask.get(x, y) { frame.rgb.get(x, y) } else { paper }
        });
        let (i, u) = intersection_union(&frame.mask, &target.threshold(eval::MASK_THRESHOLD));
        inter += i;
        union += u;
        if job.target.is_none()
            && let (Some(r), Some(m)) = (reference.frames().get(k), reference.masks().get(k))
            && r.size() == flat.size()
        {
            psnrs.push(psnr(&flat, r, m).unwrap_or(f32::NAN));
        }
        if sheet_frames.contains(&k) {
            kept.push((k + 1, flat.clone()));
        }
        batch.push((flat.map(|c| [c[0], c[1], c[2], 1.0]), target));
        if batch.len() == BATCH {
            flush(&mut batch, &mut evaluator, &mut measuring)?;
        }
        k += 1;
        if tick() { Ok(()) } else { Err(Error::Cancelled) }
    })?;
    flush(&mut batch, &mut evaluator, &mut measuring)?;
    if k != job.frames {
        return Err(Error::param("painter", format!("{k} frames"), format!("{} frames", job.frames)));
    }
    let report = evaluator.report();
    let windows = if job.target == Some(TargetKind::Long) {
        let mut out: Vec<Window> = Vec::new();
        let mut s = 0;
        while s < job.frames {
            let e = (s + options.window).min(job.frames);
            let (summary, _) = evaluator.summary(s..e);
            let first = out.first().map_or(&summary, |w| &w.summary);
            let (c0, r0) = (first.local_contrast, first.edge_darkening);
            // Without a rim in the first window there is nothing to keep.
            let r0 = r0.filter(|_| first.edge_darkening_ratio.is_some_and(|r| r >= MIN_RIM_TO_KEEP));
            out.push(Window {
                first: s + 1,
                last: e,
                contrast_vs_first: eval::ratio(summary.local_contrast, c0),
                rim_vs_first: eval::ratio(summary.edge_darkening, r0),
                summary,
            });
            s = e;
        }
        out
    } else {
        Vec::new()
    };
    let identity = (!psnrs.is_empty()).then(|| {
        let mut sorted: Vec<f32> = psnrs.iter().copied().filter(|v| v.is_finite()).collect();
        sorted.sort_by(f32::total_cmp);
        let (min_frame, min) = psnrs
            .iter()
            .enumerate()
            .filter(|(_, v)| v.is_finite())
            .fold((0, f32::INFINITY), |a, (i, &v)| if v < a.1 { (i, v) } else { a });
        Identity {
            psnr_median: sorted.get(sorted.len() / 2).copied().unwrap_or(f32::NAN),
            psnr_min: min,
            psnr_min_frame: min_frame + 1,
            psnr: psnrs,
        }
    });
    let sheet = match &options.sheets {
        Some(dir) => {
            let path = dir.join(format!("{}-{}.png", ex.meta.name, target_name));
            let ex_frames: Vec<usize> = if job.target.is_none() {
                sheet_frames.iter().copied().filter(|&i| i < reference.frames().len()).collect()
            } else {
                spread(reference.frames().len(), 4)
            };
            let rows = [
                SheetRow {
                    label: format!(
                        "output: {} on {} ({}x{}, seed {})",
                        ex.meta.name,
                        target_name,
                        report.width,
                        report.height,
                        job.params.seed()
                    ),
                    frames: kept.iter().map(|(n, f)| (*n, f)).collect(),
                },
                SheetRow {
                    label: format!("exemplar {} at the same scale", ex.meta.name),
                    frames: ex_frames.iter().map(|&i| (i + 1, &reference.frames()[i])).collect(),
                },
            ];
            let title = format!("fluidymation quality: {} x {}", ex.meta.name, target_name);
            sheet::save_sheet(&path, &title, &rows)?;
            Some(path)
        }
        None => None,
    };
    let seconds = start.elapsed().as_secs_f64();
    log::info!(
        "{} on {}: {} frames in {:.1} s, of which {:.1} s measuring",
        ex.meta.name,
        target_name,
        job.frames,
        seconds,
        measuring
    );
    let blur_sigma = job.params.guide().blur_sigma;
    let border_width = job.params.border_width().unwrap_or(job.params.exemplar_border_width(ex));
    Ok((
        Row {
            exemplar: ex.meta.name.clone(),
            target: target_name.to_string(),
            frames: report.frames,
            width: report.width,
            height: report.height,
            blur_sigma,
            border_width,
            fitted: job.fitted,
            max_levels: job.params.max_levels(),
            summary: report.summary,
            coverage_alpha: (union > 0).then(|| (inter as f64 / union as f64) as f32),
            exemplar_summary: report.exemplar,
            windows,
            identity,
            seconds,
            measure_seconds: measuring,
        },
        sheet,
    ))
}
