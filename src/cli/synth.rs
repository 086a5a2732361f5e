//! `fluidymation synth`: the engine on a plain mask sequence, as the thesis's program ran.

use super::Ctx;
use super::params::{ExemplarDirs, SynthFlags, Threads, parse_frames, warn_if_clipped};
use super::progress::Bars;
use anyhow::{Context, Result, bail};
use fluidymation::Progress;
use fluidymation::anim::{self, LoadOptions};
use fluidymation::img::{self, Plane};
use fluidymation::synth::Source;
use fluidymation::synth::keyframes::{self, KeyedFrame, Keyframe};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Arguments of `synth`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Style exemplar: a name (see `fluidymation exemplar list`), a folder, or one image (a
    /// still). Not needed with --keyframe.
    #[arg(long, short = 'e', required_unless_present = "keyframe")]
    pub exemplar: Option<String>,
    /// A painted keyframe, N=PAINTING.png: frame N (1-based) painted over, the size of the
    /// output frames. Every other frame is synthesized from the painting(s) instead of an
    /// exemplar: carried forward and backward along the masks' motion, and between two
    /// keyframes taken from both in blobs that pass from the earlier painting to the later one.
    /// Repeatable.
    #[arg(long, value_name = "N=PNG")]
    pub keyframe: Vec<String>,
    /// Directory (or glob) of target mask PNGs, white = paint.
    #[arg(long)]
    pub masks: PathBuf,
    /// Output directory for RGBA frames (exemplar colors, alpha = the target mask).
    #[arg(long, short = 'o')]
    pub output: PathBuf,
    /// Frames to synthesize, 1-based inclusive (e.g. 1..24). Guides still use every frame.
    #[arg(long, allow_hyphen_values = true)]
    pub frames: Option<String>,
    #[command(flatten)]
    pub threads: Threads,
    /// Also write the field (frame index and position as colors) and Ω per frame here.
    #[arg(long, value_name = "DIR")]
    pub debug: Option<PathBuf>,
    #[command(flatten)]
    pub exemplar_dir: ExemplarDirs,
    #[command(flatten)]
    pub flags: SynthFlags,
}

/// Runs `synth`.
pub fn run(args: Args, ctx: &Ctx) -> Result<()> {
    args.threads.apply()?;
    let t0 = Instant::now();
    let params = args.flags.params()?;
    super::render::check_not_input(&args.masks, &args.output)?;
    let anim = anim::load(&args.masks, &LoadOptions::default().scale(args.flags.target_scale()))
        .with_context(|| format!("could not read the masks in '{}'", args.masks.display()))?;
    super::render::print_warnings(&args.masks, &anim);
    if !args.keyframe.is_empty() {
        if let Some(e) = &args.exemplar {
            log::warn!("--exemplar '{e}' is not used: with --keyframe every frame is painted from the keyframes");
        }
        return run_keyframes(&args, &anim, params, ctx);
    }
    let Some(name) = args.exemplar.as_deref() else { bail!("give --exemplar or --keyframe") };
    let exemplar = super::find_exemplar(name, &args.exemplar_dir.dirs)?;
    let range = parse_frames(args.frames.as_deref(), anim.frames)?;
    warn_if_clipped(args.frames.as_deref(), &range, anim.frames, "the input");
    for dir in std::iter::once(&args.output).chain(args.debug.as_ref()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("could not create the output directory '{}'", dir.display()))?;
    }
    let bars = Bars::new(ctx.quiet);
    // σ and b fitted to the target's thickness.
    let params = if params.fit_thin() {
        let b = params.exemplar_border_width(&exemplar);
        match fluidymation::synth::sequence_thickness(anim.frames, |k| Ok(anim.render(0, k)?.coverage()))? {
            Some(t) => params.fit_to_thickness(t, b),
            None => params,
        }
    } else {
        params
    };
    let read = t0.elapsed();
    let t = Instant::now();
    let (mut synth, stream) = fluidymation::synth::start(
        || Source::prepare(&exemplar, &params),
        &params,
        anim.frames,
        |i| Ok(anim.render(0, i)?.coverage()),
    )
    .with_context(|| format!("could not prepare exemplar '{}' and the target's guides", exemplar.meta.name))?;
    synth.set_debug(args.debug.is_some());
    let mut time = Phases { read, prepare: t.elapsed(), ..Phases::default() };
    let start = Instant::now();
    let mut written = 0;
    let mut stream = stream.enumerate();
    loop {
        let t = Instant::now();
        let Some((k, g)) = stream.next() else { break };
        if k >= range.end {
            break;
        }
        let g = g.with_context(|| format!("could not compute the guides of frame {}", k + 1))?;
        time.guides += t.elapsed();
        let t = Instant::now();
        let out = synth.step(&g).with_context(|| format!("synthesis failed at frame {}", k + 1))?;
        time.synthesis += t.elapsed();
        bars.update("frames", k + 1, range.end);
        if k < range.start {
            continue;
        }
        let t = Instant::now();
        save_frame(&args.output, k, &out.rgb, &out.mask)?;
        if let (Some(dir), Some(d)) = (&args.debug, &out.debug) {
            img::save_rgb(&dir.join(format!("nnf_{:04}.png", k + 1)), &d.nnf)?;
            let max = d.omega.data().iter().cloned().fold(1e-6f32, f32::max);
            img::save_gray(&dir.join(format!("omega_{:04}.png", k + 1)), &d.omega.map(|v| v / max))?;
        }
        written += 1;
        time.writing += t.elapsed();
    }
    bars.clear();
    if written == 0 {
        bail!("no frame was synthesized");
    }
    if !ctx.quiet {
        // The whole command; per frame, the frames after the preparation.
        let secs = start.elapsed().as_secs_f64();
        eprintln!(
            "{} in {:.1} s ({:.2} s/frame after {:.1} s of preparation) -> {}",
            fluidymation::seq::plural(written, "frame"),
            t0.elapsed().as_secs_f64(),
            secs / written as f64,
            (time.read + time.prepare).as_secs_f64(),
            args.output.display()
        );
        let s = |d: Duration| d.as_secs_f64();
        eprintln!(
            "  reading the masks and the exemplar {:.2} s, preparing the exemplar and the guides' backward pass {:.2} s, target \
             guides {:.2} s, synthesis {:.2} s, writing {:.2} s",
            s(time.read),
            s(time.prepare),
            s(time.guides),
            s(time.synthesis),
            s(time.writing)
        );
    }
    Ok(())
}

/// Parses `--keyframe N=PAINTING.png` values into keyframes of a `frames`-frame target whose
/// frames are `size`.
pub fn parse_keyframes(values: &[String], frames: usize, size: (usize, usize)) -> Result<Vec<Keyframe>> {
    values
        .iter()
        .map(|v| {
            let (frame, path) = super::params::parse_keyframe(v, frames)?;
            let painting =
                img::load_rgb(&path).with_context(|| format!("could not read the keyframe '{}'", path.display()))?;
            if painting.size() != size {
                bail!(
                    "the keyframe '{}' is {}x{}, but the frames are {}x{}: paint over a frame of the output at its size",
                    path.display(),
                    painting.width(),
                    painting.height(),
                    size.0,
                    size.1
                );
            }
            Ok(Keyframe { frame, painting, mask: None })
        })
        .collect()
}

/// `synth --keyframe`: every frame painted from the painted keyframes (no exemplar).
fn run_keyframes(args: &Args, anim: &anim::Animation, params: fluidymation::synth::Params, ctx: &Ctx) -> Result<()> {
    let range = parse_frames(args.frames.as_deref(), anim.frames)?;
    let size = (anim.width as usize, anim.height as usize);
    let keys = parse_keyframes(&args.keyframe, anim.frames, size)?;
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("could not create the output directory '{}'", args.output.display()))?;
    let bars = Bars::new(ctx.quiet);
    let start = Instant::now();
    let mut written = 0usize;
    let coverage = |k: usize| Ok(anim.render(0, k)?.coverage());
    let mut emit = |j: usize, out: KeyedFrame| -> fluidymation::Result<()> {
        if range.contains(&j) {
            save_frame(&args.output, j, &out.rgb, &out.mask)?;
            written += 1;
        }
        Ok(())
    };
    // The bar counts the frames both passes paint (two per frame between keyframes).
    keyframes::paint(&params, anim.frames, &coverage, None, &keys, &mut emit, "frames", &bars)
        .context("painting from the keyframes")?;
    let synthesized = anim.frames - keys.len();
    bars.clear();
    if !ctx.quiet {
        let secs = start.elapsed().as_secs_f64();
        eprintln!(
            "{written} frames from {} keyframe(s) in {secs:.1} s ({:.2} s/frame synthesized) -> {}",
            keys.len(),
            secs / synthesized.max(1) as f64,
            args.output.display()
        );
    }
    Ok(())
}

/// Writes frame `k` (0-based) as `dir/NNNN.png`: RGBA, the colors with alpha = the mask.
fn save_frame(dir: &std::path::Path, k: usize, rgb: &Plane<img::Rgb>, mask: &img::Mask) -> fluidymation::Result<()> {
    let rgba = Plane::from_fn(rgb.width(), rgb.height(), |x, y| {
        let c = rgb.get(x, y);
        [c[0], c[1], c[2], if mask.get(x, y) { 1.0 } else { 0.0 }]
    });
    img::save_rgba(&dir.join(format!("{:04}.png", k + 1)), &rgba)
}

/// Where the time of a run goes (reported after it).
#[derive(Default)]
struct Phases {
    read: Duration,
    prepare: Duration,
    guides: Duration,
    synthesis: Duration,
    writing: Duration,
}
