//! `fluidymation eval`: measure a stylized sequence against its exemplar and target masks.

use super::Ctx;
use anyhow::{Context, bail};
use fluidymation::eval::{self, EvalOptions, plot};
use fluidymation::exemplar::Exemplar;
use fluidymation::img::{self, Plane};
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// A coverage IoU below this warns that the masks may not be the output's ([`run`]): on the
/// quality suite every output covers its masks at 0.82 or more (rose-burst's feathered limb),
/// the others 0.94–1.0.
const LOW_COVERAGE: f32 = 0.5;

/// Arguments of `eval`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Directory (or glob) of the stylized frames, 0001.png …: RGBA in the exemplar's colors
    /// with alpha = the mask, or opaque frames composited over a background.
    pub out_dir: PathBuf,
    /// The exemplar the frames were stylized with: its folder (holding exemplar.toml, frames/,
    /// masks/).
    #[arg(long, short = 'e', value_name = "DIR")]
    pub exemplar: String,
    /// Directory (or glob) of the target masks, one PNG per frame (white or alpha = inside).
    #[arg(long, value_name = "DIR")]
    pub masks: PathBuf,
    /// Print the report as JSON (with the per-frame series) instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Also draw the per-frame series as a PNG chart.
    #[arg(long, value_name = "FILE.png")]
    pub plot: Option<PathBuf>,
    /// Print the per-frame table after the summary.
    #[arg(long)]
    pub per_frame: bool,
    /// Background color of opaque frames, #rrggbb or a name as `render --background` takes
    /// [default: the dominant color of the frame borders].
    #[arg(long, value_name = "COLOR")]
    pub background: Option<String>,
    /// Color distance (sRGB, 0..1.73) from the background above which a pixel of an opaque
    /// frame counts as painted.
    #[arg(long, default_value_t = 0.1)]
    pub paint_threshold: f32,
    /// Pixels at least this far inside a mask form its interior, where texture, colors and
    /// changes are measured.
    #[arg(long, default_value_t = 5.0)]
    pub interior_margin: f32,
    /// Use every n-th exemplar frame, as `synth --src-speed` [default: the exemplar's speed].
    #[arg(long, value_name = "N", value_parser = super::params::count(1, usize::MAX))]
    pub src_speed: Option<usize>,
    /// Resize the exemplar first, as `synth --src-scale` [default: the exemplar's scale].
    #[arg(long, value_name = "FACTOR")]
    pub src_scale: Option<f32>,
    /// Compare the palette of every pixel with the exemplar's at its own distance from the
    /// edge; by default a shape deeper than the exemplar's paint is compared at the exemplar's
    /// depths stretched to it, as the synthesis paints it (see `--without depth-stretch`).
    #[arg(long)]
    pub own_depths: bool,
    /// Output patches sampled for the nearest-neighbour distance.
    #[arg(long, default_value_t = 2048, value_parser = super::params::count(1, usize::MAX))]
    pub patch_samples: usize,
    /// Edge darkening compares the band of pixels at most this far inside the edge…
    #[arg(long, value_name = "PX", default_value_t = eval::RIM_BAND)]
    pub rim_band: f32,
    /// …with the interior of pixels farther inside than this.
    #[arg(long, value_name = "PX", default_value_t = eval::RIM_INTERIOR)]
    pub rim_interior: f32,
    /// Search radius of the block-matching flow, pixels per frame.
    #[arg(long, default_value_t = 6, value_parser = super::params::count(1, 32))]
    pub flow_radius: usize,
    /// Seed of the random sampling (results are deterministic for a seed).
    #[arg(long, default_value_t = 1, value_parser = super::params::parse_seed)]
    pub seed: u64,
}

/// Finds the exemplar given on the command line: a name or a folder.
fn load_exemplar(arg: &str) -> anyhow::Result<Exemplar> {
    super::find_exemplar(arg, &[])
}

/// Loads every file with `load`, in parallel, reporting the first failure in sequence order.
fn load_all<T: Send>(
    files: &[PathBuf],
    load: impl Fn(&Path) -> fluidymation::Result<T> + Sync,
) -> fluidymation::Result<Vec<T>> {
    let loaded: Vec<fluidymation::Result<T>> = files.par_iter().map(|f| load(f)).collect();
    loaded.into_iter().collect()
}

fn name(p: &Path) -> String {
    p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| p.display().to_string())
}

/// Runs `eval`.
pub fn run(args: Args, ctx: &Ctx) -> anyhow::Result<()> {
    let background = match &args.background {
        Some(s) => Some(
            match s.parse::<fluidymation::render::Background>() {
                Ok(fluidymation::render::Background::Color(c)) if c[3] >= 1.0 => Some([c[0], c[1], c[2]]),
                _ => None,
            }
            .with_context(|| {
                format!(
                    "--background '{s}': expected an opaque color, #rrggbb, #rgb or a name (white, black, gray, red, \
                         green, blue, yellow)"
                )
            })?,
        ),
        None => None,
    };
    let defaults = EvalOptions::default();
    let mut options = EvalOptions::default()
        .interior_margin(args.interior_margin)
        .paint_threshold(args.paint_threshold)
        .depth_stretch(!args.own_depths)
        .rim(eval::RimParams { band: args.rim_band, interior: args.rim_interior, ..defaults.rim })
        .patches(eval::PatchParams { samples: args.patch_samples, seed: args.seed, ..defaults.patches })
        .motion(eval::MotionParams {
            block: eval::BlockMatchParams { radius: args.flow_radius, ..defaults.motion.block },
            ..defaults.motion
        });
    // Unset on the command line: the defaults (an estimated background, the exemplar's own step
    // and scale).
    if let Some(color) = background {
        options = options.background(color);
    }
    if let Some(step) = args.src_speed {
        options = options.exemplar_step(step);
    }
    if let Some(scale) = args.src_scale {
        options = options.exemplar_scale(scale);
    }
    options.validate()?;

    let frame_files = fluidymation::seq::list_sequence(&args.out_dir, &["png"])
        .with_context(|| format!("could not read the stylized frames in '{}'", args.out_dir.display()))?;
    let mask_files = fluidymation::seq::list_sequence(&args.masks, &["png"])
        .with_context(|| format!("could not read the target masks in '{}'", args.masks.display()))?;
    if frame_files.len() != mask_files.len() {
        let n = frame_files.len().min(mask_files.len());
        let extra = if frame_files.len() > n {
            format!("frame '{}' has no mask", frame_files[n].display())
        } else {
            format!("mask '{}' has no frame", mask_files[n].display())
        };
        bail!(
            "'{}' holds {} frames but '{}' holds {} masks ({}); give one mask per frame",
            args.out_dir.display(),
            frame_files.len(),
            args.masks.display(),
            mask_files.len(),
            extra
        );
    }
    let exemplar = load_exemplar(&args.exemplar)?;

    let frames = load_all(&frame_files, img::load_rgba)?;
    let masks: Vec<Plane<f32>> = load_all(&mask_files, img::load_gray)?;
    let size = frames[0].size();
    for (files, sizes, what) in [
        (&frame_files, frames.iter().map(Plane::size).collect::<Vec<_>>(), "frame"),
        (&mask_files, masks.iter().map(Plane::size).collect::<Vec<_>>(), "mask"),
    ] {
        if let Some(i) = sizes.iter().position(|&s| s != size) {
            bail!(
                "{} '{}' is {}x{} but frame '{}' is {}x{}; frames and masks must all have one size",
                what,
                files[i].display(),
                sizes[i].0,
                sizes[i].1,
                frame_files[0].display(),
                size.0,
                size.1
            );
        }
    }
    log::info!(
        "evaluating {} frames ({} … {}) against '{}'",
        frames.len(),
        name(&frame_files[0]),
        name(&frame_files[frames.len() - 1]),
        exemplar.meta.name
    );

    if let Some(path) = &args.plot {
        fluidymation::output::prepare_file(path).context("--plot: cannot write the chart there")?;
    }
    let report = eval::evaluate(&frames, &exemplar, &masks, &options).context("evaluation failed")?;
    // Every other measure reads the output inside the masks: masks of another layer or
    // animation give numbers that mean nothing, so say so.
    if let Some(iou) = report.summary.coverage_iou.filter(|&v| v < LOW_COVERAGE) {
        log::warn!(
            "coverage IoU {iou:.3}: the paint of '{}' hardly lies inside the masks of '{}'; are these the masks of \
             this output? (every other measure reads the output inside them)",
            args.out_dir.display(),
            args.masks.display()
        );
    }

    if args.json {
        let text = serde_json::to_string_pretty(&report).context("could not serialize the report")?;
        println!("{}", text);
    } else {
        println!("{}", report);
        if args.per_frame {
            println!();
            print!("{}", report.per_frame_table());
        }
    }
    if let Some(path) = &args.plot {
        plot::save_plot(&report, path, &plot::PlotOptions::default())
            .with_context(|| format!("could not write the chart '{}'", path.display()))?;
        if !ctx.quiet {
            eprintln!("chart written to '{}'", path.display());
        }
    }
    Ok(())
}
