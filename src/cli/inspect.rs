//! `fluidymation inspect`: what is in an animation, and optionally its masks.

use super::Ctx;
use anyhow::Context;
use fluidymation::anim::{self, Animation, LoadOptions};
use fluidymation::guide::preview::{PreviewOptions, write_previews};
use fluidymation::guide::{GuideParams, GuideStream};
use fluidymation::img::Plane;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::io::IsTerminal;
use std::ops::Range;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Arguments of `inspect`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A Lottie .json file, an .svg file (a one-frame still), a folder or quoted glob of SVG
    /// frames, or a folder or glob of PNG masks. Globs: `*`, `?` and `[...]` classes (`[0-9]`,
    /// `[!0-9]`) in the file name.
    pub input: PathBuf,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Write each region's mask per frame to DIR/<NN>_<slug>/<frame:04>.png (255 inside,
    /// antialiased edges; frame 0001 is the animation's first frame).
    #[arg(long, value_name = "DIR")]
    pub masks: Option<PathBuf>,
    /// Write what the engine is guided by, per region and frame, to DIR/<NN>_<slug>/: the flow
    /// as hue (direction) and brightness (speed) `flow_NNNN.png`, the motion extents
    /// `ext_pos_NNNN.png` and `ext_neg_NNNN.png` as grayscale, and the border channel
    /// `border_NNNN.png` (brightness scales are per frame and printed with -v).
    #[arg(long, value_name = "DIR")]
    pub guides: Option<PathBuf>,
    /// Only these frames, 1-based and inclusive: `A..B`, `A..`, `..B` or `N`.
    #[arg(long, value_name = "A..B", allow_hyphen_values = true)]
    pub frames: Option<String>,
    /// Scale the canvas (0.5 = half size).
    #[arg(long, default_value_t = 1.0, value_parser = super::params::factor(0.0, 16.0))]
    pub scale: f32,
    /// Make each layer inside a top-level precomp a region of its own (`outer/inner`).
    #[arg(long)]
    pub split_precomps: bool,
}

/// Coverage is measured on at most this many frames spread over the range (all of them
/// when masks are written): an `op` of 100 000 must not make `inspect` render every frame.
pub const MAX_MEASURED_FRAMES: usize = 240;

/// The frames of `range` whose coverage is measured: all when `all`, else at most
/// [`MAX_MEASURED_FRAMES`] spread evenly (the first and the last included).
fn sampled(range: &Range<usize>, all: bool) -> Vec<usize> {
    let n = range.len();
    if all || n <= MAX_MEASURED_FRAMES {
        return range.clone().collect();
    }
    let m = MAX_MEASURED_FRAMES;
    (0..m).map(|k| range.start + k * (n - 1) / (m - 1)).collect()
}

fn hex(c: [f32; 4]) -> String {
    let b = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    format!("#{:02x}{:02x}{:02x}", b(c[0]), b(c[1]), b(c[2]))
}

fn frames_label(r: &Range<usize>) -> String {
    if r.is_empty() { "none".to_string() } else { format!("{}..{}", r.start + 1, r.end) }
}

struct Stats {
    mean_coverage: f64,
}

/// Renders every region over `range` (writing masks when asked) and measures coverage.
fn measure(a: &Animation, frames: &[usize], masks: Option<&PathBuf>, ctx: &Ctx) -> anyhow::Result<Vec<Stats>> {
    let jobs: Vec<(usize, usize)> = (0..a.regions.len()).flat_map(|r| frames.iter().map(move |&f| (r, f))).collect();
    if let Some(dir) = masks {
        for r in &a.regions {
            let d = dir.join(r.dir_name());
            std::fs::create_dir_all(&d).with_context(|| format!("could not create '{}'", d.display()))?;
        }
    }
    let show = !ctx.quiet && std::io::stderr().is_terminal() && jobs.len() > 8;
    let bar = if show {
        let pb = indicatif::ProgressBar::new(jobs.len() as u64);
        let what = if masks.is_some() { "masks" } else { "frames measured" };
        if let Ok(style) =
            indicatif::ProgressStyle::with_template(&format!("{{bar:40}} {{pos}}/{{len}} {what} {{eta}}"))
        {
            pb.set_style(style);
        }
        Some(pb)
    } else {
        None
    };
    let done = AtomicUsize::new(0);
    let pixels = (a.width as f64) * (a.height as f64);
    let results: Vec<anyhow::Result<(usize, f64)>> = jobs
        .par_iter()
        .map(|&(r, f)| {
            let frame =
                a.render(r, f).with_context(|| format!("could not render '{}' frame {}", a.regions[r].name, f + 1))?;
            let cov: Plane<f32> = frame.coverage();
            let sum: f64 = cov.data().iter().map(|&v| v as f64).sum();
            if let Some(dir) = masks {
                let path = dir.join(a.regions[r].dir_name()).join(format!("{:04}.png", f + 1));
                fluidymation::img::save_gray(&path, &cov)
                    .with_context(|| format!("could not write '{}'", path.display()))?;
            }
            let n = done.fetch_add(1, Ordering::Relaxed);
            if let Some(pb) = &bar {
                pb.set_position(n as u64 + 1);
            }
            Ok((r, sum / pixels))
        })
        .collect();
    if let Some(pb) = bar {
        pb.finish_and_clear();
    }
    let mut sums = vec![(0.0f64, 0usize); a.regions.len()];
    for res in results {
        let (r, c) = res?;
        sums[r].0 += c;
        sums[r].1 += 1;
    }
    Ok(sums.into_iter().map(|(s, n)| Stats { mean_coverage: if n > 0 { s / n as f64 } else { 0.0 } }).collect())
}

/// Writes the guide previews of every region over `range` into `dir` (regions in parallel,
/// frames of a region streamed in order: ext− needs the backward pass over the range).
fn write_guides(a: &Animation, range: &Range<usize>, dir: &std::path::Path, ctx: &Ctx) -> anyhow::Result<()> {
    let params = GuideParams::default();
    let opts = PreviewOptions::default();
    let bar = (!ctx.quiet && std::io::stderr().is_terminal()).then(|| {
        let pb = indicatif::ProgressBar::new((a.regions.len() * range.len()) as u64);
        if let Ok(style) = indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} guide frames {eta}") {
            pb.set_style(style);
        }
        pb
    });
    let results: Vec<anyhow::Result<()>> = (0..a.regions.len())
        .into_par_iter()
        .map(|r| {
            let region = &a.regions[r];
            let d = dir.join(region.dir_name());
            std::fs::create_dir_all(&d).with_context(|| format!("could not create '{}'", d.display()))?;
            let masks = |k: usize| -> fluidymation::Result<Plane<f32>> { Ok(a.render(r, range.start + k)?.coverage()) };
            let stream = GuideStream::new(range.len(), masks, &params)
                .with_context(|| format!("could not compute the guides of '{}'", region.name))?;
            for (k, g) in stream.enumerate() {
                let f = range.start + k + 1;
                let g = g.with_context(|| format!("could not compute the guides of '{}' frame {f}", region.name))?;
                let s = write_previews(&g, &d, f, &opts)
                    .with_context(|| format!("could not write the guide previews into '{}'", d.display()))?;
                if ctx.verbose > 0 {
                    eprintln!(
                        "{} frame {f}: flow {:.3} px/frame and extent {:.1} px at full brightness",
                        region.name, s.flow, s.ext
                    );
                }
                if let Some(pb) = &bar {
                    pb.inc(1);
                }
            }
            Ok(())
        })
        .collect();
    if let Some(pb) = bar {
        pb.finish_and_clear();
    }
    results.into_iter().collect()
}

/// Runs `inspect`.
pub fn run(args: Args, ctx: &Ctx) -> anyhow::Result<()> {
    let opts = LoadOptions::default().scale(args.scale).split_precomps(args.split_precomps);
    let a = anim::load(&args.input, &opts).with_context(|| format!("could not load '{}'", args.input.display()))?;
    let range = super::params::parse_frames(args.frames.as_deref(), a.frames)?;
    super::params::warn_if_clipped(args.frames.as_deref(), &range, a.frames, "the input");
    if args.masks.is_some() || args.guides.is_some() {
        fluidymation::limits::check_preview_memory(&args.input, a.width, a.height)?;
    }
    let measured = sampled(&range, args.masks.is_some());
    let stats = measure(&a, &measured, args.masks.as_ref(), ctx)?;
    if let Some(dir) = &args.guides {
        write_guides(&a, &range, dir, ctx)?;
    }
    let mut out = String::new();
    if args.json {
        let regions: Vec<serde_json::Value> = a
            .regions
            .iter()
            .zip(&stats)
            .map(|(r, s)| {
                serde_json::json!({
                    "index": r.index,
                    "name": r.name,
                    "kind": r.kind.as_str(),
                    "color": hex(r.color),
                    "visible": {"first": r.visible.start + 1, "last": r.visible.end, "count": r.visible.len()},
                    "has_strokes": r.has_strokes,
                    "mean_coverage": s.mean_coverage,
                    "warnings": r.warnings,
                })
            })
            .collect();
        let doc = serde_json::json!({
            "input": a.path.display().to_string(),
            "width": a.width,
            "height": a.height,
            "fps": a.fps,
            "frames": a.frames,
            "duration": a.duration(),
            "measured_frames": {"first": range.start + 1, "last": range.end, "count": measured.len()},
            "background": a.background.as_ref().map(|b| serde_json::json!({"name": b.name, "color": hex(b.color)})),
            "regions": regions,
            "warnings": a.warnings,
        });
        writeln!(out, "{}", serde_json::to_string_pretty(&doc)?)?;
        return emit(&out);
    }
    writeln!(out, "{}", a.path.display())?;
    writeln!(
        out,
        "  {}x{} px, {} fps, {} ({:.2} s)",
        a.width,
        a.height,
        (a.fps * 1000.0).round() / 1000.0,
        fluidymation::seq::plural(a.frames, "frame"),
        a.duration()
    )?;
    match &a.background {
        Some(b) => writeln!(out, "  background: {} {}", hex(b.color), b.name)?,
        None => writeln!(out, "  background: none")?,
    }
    if range != (0..a.frames) || measured.len() < range.len() {
        let sample = if measured.len() < range.len() {
            format!(" (coverage from {} of them, evenly spread; --masks measures all)", measured.len())
        } else {
            String::new()
        };
        writeln!(out, "  measured frames {}{sample}", frames_label(&range))?;
    }
    for w in &a.warnings {
        writeln!(out, "  warning: {w}")?;
    }
    writeln!(out, "  {:>2}  {:<24} {:<13} {:<7} {:<11} {:>8}", "#", "name", "kind", "color", "visible", "coverage")?;
    for (r, s) in a.regions.iter().zip(&stats) {
        writeln!(
            out,
            "  {:02}  {:<24} {:<13} {:<7} {:<11} {:>7.2}%{}",
            r.index,
            r.name,
            r.kind.as_str(),
            hex(r.color),
            frames_label(&r.visible),
            s.mean_coverage * 100.0,
            match (r.has_strokes, s.mean_coverage > 0.0) {
                (true, true) => "  +strokes",
                // Regions are the fills: a layer of strokes alone has nothing to paint into.
                (true, false) => "  strokes only: no fill to stylize (--strokes keep|stylize|drop)",
                _ => "",
            }
        )?;
        for w in &r.warnings {
            writeln!(out, "        warning: {w}")?;
        }
    }
    if let Some(dir) = &args.masks {
        writeln!(out, "  masks written to {}", dir.display())?;
    }
    if let Some(dir) = &args.guides {
        writeln!(out, "  guide previews written to {}", dir.display())?;
    }
    emit(&out)
}

/// Writes the report; a closed pipe (`| head`) is not an error.
fn emit(out: &str) -> anyhow::Result<()> {
    use std::io::Write;
    match std::io::stdout().lock().write_all(out.as_bytes()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        r => r.context("could not write to stdout"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_ranges_are_sampled() {
        assert_eq!(sampled(&(0..10), false), (0..10).collect::<Vec<_>>());
        let s = sampled(&(5..100_005), false);
        assert_eq!(s.len(), MAX_MEASURED_FRAMES);
        assert_eq!((s[0], s[s.len() - 1]), (5, 100_004));
        assert!(s.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(sampled(&(0..1000), true).len(), 1000);
    }
}
