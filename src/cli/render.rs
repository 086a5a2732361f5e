//! `fluidymation render`: the whole pipeline, as motion designers run it.

use super::Ctx;
use super::params::{SynthFlags, parse_frames, set_threads};
use anyhow::{Context, Result, bail};
use fluidymation::anim::{self, LoadOptions};
use fluidymation::composite::{Recolor, StrokeMode};
use fluidymation::render::{self, RenderOptions};
use fluidymation::{Error, Progress};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::collections::HashMap;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

/// Arguments of `render`.
#[derive(clap::Args, Debug)]
// `--target-scale` is `synth`'s; `render` has `--scale`.
#[command(mut_arg("target_scale", |a| a.hide(true)))]
pub struct Args {
    /// A Lottie .json file, a directory or glob of SVG frames, or a directory of PNG masks.
    pub input: PathBuf,
    /// Output directory for the frames (NNNN.png, 0001 = the first frame).
    #[arg(long, short = 'o', value_name = "OUT_DIR")]
    pub output: PathBuf,
    /// Also write an animated GIF.
    #[arg(long, value_name = "FILE")]
    pub gif: Option<PathBuf>,
    /// Style of one layer: LAYER=EXEMPLAR, LAYER a name or 1-based index, EXEMPLAR a name,
    /// a folder, or "none" to leave the layer flat. Repeat for more layers.
    #[arg(long, value_name = "LAYER=EXEMPLAR")]
    pub style: Vec<String>,
    /// Exemplar of every layer not given a --style [default: the bundled blue-bloom].
    #[arg(long, short = 'e', value_name = "NAME|DIR")]
    pub exemplar: Option<String>,
    /// A TOML file of styles: `default = "NAME"` and a `[layers]` table of LAYER = "EXEMPLAR".
    #[arg(long, value_name = "FILE.toml")]
    pub styles: Option<PathBuf>,
    /// Background: a color (#rrggbb or a name), "none" (transparent), or an image file
    /// [default: the animation's own background, else white].
    #[arg(long, value_name = "COLOR|none|IMAGE")]
    pub background: Option<String>,
    /// How stylized layers take their colors [default: glaze; none for a PNG mask sequence,
    /// which has no colors of its own].
    #[arg(long, value_enum)]
    pub recolor: Option<Recolor>,
    /// What happens to strokes.
    #[arg(long, value_enum, default_value_t = StrokeMode::Keep)]
    pub strokes: StrokeMode,
    /// Scale the canvas (0.5 = quick half-size preview; the paint texture scales along).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f32,
    /// Frames to render, 1-based inclusive: A..B, A.., ..B or N [default: all].
    #[arg(long, value_name = "A..B")]
    pub frames: Option<String>,
    /// Worker threads [default: all cores]. The output does not depend on it.
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Also write every layer alone (RGBA) under OUT_DIR/layers/NN_name/.
    #[arg(long)]
    pub keep_layers: bool,
    /// Continue an interrupted (Ctrl-C, killed) render into the same OUT_DIR; give the same
    /// options as the interrupted run.
    #[arg(long)]
    pub resume: bool,
    /// Measure each stylized layer against its exemplar afterwards and print the numbers.
    #[arg(long)]
    pub eval: bool,
    /// Make each layer inside a precomp a region of its own.
    #[arg(long)]
    pub split_precomps: bool,
    /// Extra directories to look for exemplars by name.
    #[arg(long, value_name = "DIR")]
    pub exemplar_dir: Vec<PathBuf>,
    #[command(flatten, next_help_heading = "Synthesis (seed and engine parameters)")]
    pub flags: SynthFlags,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct StylesFile {
    default: Option<String>,
    #[serde(default)]
    layers: toml::Table,
}

/// A styles file's default exemplar and per-layer `(LAYER, EXEMPLAR)` pairs.
type Styles = (Option<String>, Vec<(String, String)>);

fn read_styles(path: &Path) -> Result<Styles> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("could not read the styles file '{}'", path.display()))?;
    let file: StylesFile =
        toml::from_str(&text).with_context(|| format!("'{}' is not a valid styles file", path.display()))?;
    let mut out = Vec::new();
    for (k, v) in file.layers {
        let Some(s) = v.as_str() else {
            bail!(
                "'{}': layer '{}' must be given an exemplar name as a string, e.g. {} = \"blue-bloom\"",
                path.display(),
                k,
                k
            );
        };
        out.push((k, s.to_string()));
    }
    Ok((file.default, out))
}

/// Progress bars: one per layer and a total with ETA, on a terminal only.
struct Bars {
    multi: Option<MultiProgress>,
    bars: Mutex<HashMap<String, ProgressBar>>,
    interrupted: &'static AtomicBool,
}

impl Bars {
    /// Removes every bar from the terminal. Bars that are only dropped draw themselves once
    /// more (indicatif's default), which left a stale bar above the summary or the error.
    fn clear(&self) {
        if let Ok(bars) = self.bars.lock() {
            for bar in bars.values() {
                bar.finish_and_clear();
            }
        }
        if let Some(m) = &self.multi {
            let _ = m.clear();
        }
    }
}

impl Progress for Bars {
    fn update(&self, stage: &str, done: usize, total: usize) -> bool {
        if let Some(multi) = &self.multi
            && let Ok(mut bars) = self.bars.lock()
        {
            let bar = bars.entry(stage.to_string()).or_insert_with(|| {
                let (template, bar) = if stage == "frames" {
                    (
                        "{prefix:>16.bold} {bar:30.green/blue} {pos}/{len} frames  {elapsed_precise} < {eta_precise}",
                        ProgressBar::new(total as u64),
                    )
                } else {
                    ("{prefix:>16} {bar:30.cyan/blue} {pos}/{len}", ProgressBar::new(total as u64))
                };
                let bar = multi.add(bar);
                bar.set_style(ProgressStyle::with_template(template).unwrap_or_else(|_| ProgressStyle::default_bar()));
                let name: String = stage.chars().take(16).collect();
                bar.set_prefix(if stage == "frames" { "total".to_string() } else { name });
                bar
            });
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        }
        !self.interrupted.load(Ordering::SeqCst)
    }
}

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Runs `render`.
pub fn run(args: Args, ctx: &Ctx) -> Result<()> {
    set_threads(args.threads)?;
    if args.flags.target_scale.is_some() {
        bail!("--target-scale is for `synth`; use --scale with `render`");
    }
    let params = args.flags.params()?;
    let load = LoadOptions { scale: args.scale, split_precomps: args.split_precomps };
    let anim = anim::load(&args.input, &load).with_context(|| format!("could not load '{}'", args.input.display()))?;
    for w in &anim.warnings {
        log::warn!("{}: {}", args.input.display(), w);
    }
    for r in &anim.regions {
        for w in &r.warnings {
            log::warn!("layer '{}': {}", r.name, w);
        }
    }
    let frames = parse_frames(args.frames.as_deref(), anim.frames)?;
    if let Some(end) =
        args.frames.as_deref().and_then(|f| f.split_once("..")).and_then(|(_, b)| b.trim().parse::<usize>().ok())
        && end > anim.frames
    {
        log::warn!(
            "--frames '{}': the input has only {} frames; rendering {}..{}",
            args.frames.as_deref().unwrap_or_default(),
            anim.frames,
            frames.start + 1,
            frames.end
        );
    }
    let mut opts = RenderOptions::new(args.output.clone(), frames.clone());
    if let Some(path) = &args.styles {
        let (default, layers) = read_styles(path)?;
        for (layer, _) in &layers {
            anim.find_region(layer).with_context(|| format!("in the styles file '{}'", path.display()))?;
        }
        opts.default_style = default;
        opts.styles = layers;
    }
    if let Some(e) = &args.exemplar {
        opts.default_style = Some(e.clone());
    }
    for s in &args.style {
        let Some((layer, ex)) = s.split_once('=') else {
            bail!("--style '{}': expected LAYER=EXEMPLAR, e.g. --style body=ink-rims", s);
        };
        opts.styles.push((layer.trim().to_string(), ex.trim().to_string()));
    }
    opts.gif = args.gif.clone();
    opts.exemplar_dirs = args.exemplar_dir.clone();
    opts.background = args.background.clone();
    // Mask sequences are white on nothing: glazed in their own color they would not show.
    let masks_only = anim.regions.iter().all(|r| r.kind == anim::RegionKind::MaskSequence);
    opts.recolor = args.recolor.unwrap_or(if masks_only { Recolor::None } else { Recolor::Glaze });
    if opts.recolor == Recolor::Glaze {
        let paper = match args.background.as_deref() {
            None => Some(anim.background.as_ref().map(|b| b.color).unwrap_or([1.0; 4])),
            Some(spec) => fluidymation::composite::parse_color(spec),
        };
        for (i, r) in anim.regions.iter().enumerate() {
            // The last --style naming the layer wins, else the default.
            let style = opts.styles.iter().rev().find(|(k, _)| anim.find_region(k).ok() == Some(i)).map(|(_, e)| e);
            let flat = style.or(opts.default_style.as_ref()).is_some_and(|e| e == render::NO_STYLE);
            if let Some(p) = paper
                && !flat
                && (0..3).all(|i| (r.color[i] - p[i]).abs() < 0.02)
            {
                log::warn!(
                    "layer '{}' has the background's color: a glaze of it does not show; \
                     try --recolor none (the exemplar's colors) or another --background",
                    r.name
                );
            }
        }
    }
    opts.strokes = args.strokes;
    opts.params = params;
    opts.scale = args.scale;
    opts.keep_layers = args.keep_layers;
    opts.resume = args.resume;
    opts.eval = args.eval;

    // The first Ctrl-C stops after the frame in progress (resumable); a second one quits at once.
    let _ = ctrlc::set_handler(|| {
        if INTERRUPTED.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
    });
    let show = !ctx.quiet && std::io::stderr().is_terminal();
    let bars = Bars {
        multi: show.then(|| MultiProgress::with_draw_target(ProgressDrawTarget::stderr())),
        bars: Mutex::new(HashMap::new()),
        interrupted: &INTERRUPTED,
    };
    let result = render::render(&anim, &opts, &bars);
    bars.clear();
    let summary = match result {
        Ok(s) => s,
        Err(Error::Cancelled) => {
            bail!(anyhow::Error::new(Error::Cancelled).context(format!(
                "interrupted; the finished frames are in '{}' — continue with the same command and --resume",
                args.output.display()
            )))
        }
        Err(e) => return Err(anyhow::Error::new(e).context(format!("could not render '{}'", args.input.display()))),
    };
    if !ctx.quiet {
        eprintln!(
            "{} frames{} in {:.1} s ({:.2} s/frame) -> {}{}",
            summary.frames,
            if summary.resumed > 0 { format!(" (after {} resumed)", summary.resumed) } else { String::new() },
            summary.seconds,
            summary.seconds_per_frame(),
            summary.frame_dir.display(),
            summary.gif.as_ref().map(|g| format!(", {}", g.display())).unwrap_or_default()
        );
        for l in &summary.layers {
            eprintln!(
                "  {:02} {:<20} {:<18} {:.1} s",
                l.index,
                l.name,
                l.exemplar.as_deref().unwrap_or("(flat)"),
                l.seconds
            );
        }
        if args.keep_layers {
            eprintln!("layers -> {}", args.output.join("layers").display());
        }
    }
    for l in &summary.layers {
        if let Some(r) = &l.eval {
            println!("== layer {:02} {} ({})", l.index, l.name, l.exemplar.as_deref().unwrap_or(""));
            println!("{}", r);
        }
    }
    Ok(())
}
