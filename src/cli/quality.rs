//! `fluidymation quality`: the quality suite — every exemplar on generated targets, one table.

use super::Ctx;
use super::params::{ExemplarDirs, SynthFlags, Threads, count, factor};
use super::progress::Bars;
use anyhow::{Context, Result, bail};
use fluidymation::img;
use fluidymation::quality::{self, IDENTITY, SuiteOptions, TargetKind};
use std::path::PathBuf;

/// Arguments of `quality`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Exemplar (name or folder); repeat for several [default: every bundled exemplar].
    #[arg(long, short = 'e', value_name = "NAME")]
    pub exemplar: Vec<String>,
    /// Target: identity (the exemplar's own masks), still, growing, shrinking, translating,
    /// rotating, limb or long; repeat for several [default: all].
    #[arg(long, value_name = "NAME")]
    pub target: Vec<String>,
    /// Size of the generated targets relative to 512x512; the exemplar, blur and border are
    /// scaled alike, as `render --scale` does (the identity stays at full size).
    #[arg(long, default_value_t = 1.0, value_parser = factor(0.0, 4.0))]
    pub scale: f32,
    /// Frames of each generated target but the long one (2 to 10000).
    #[arg(long, default_value_t = 48, value_parser = count(2, 10_000))]
    pub frames: usize,
    /// Frames of the long target (2 to 10000).
    #[arg(long, default_value_t = 300, value_parser = count(2, 10_000))]
    pub long_frames: usize,
    /// The long target is also reported per window of this many frames.
    #[arg(long, default_value_t = 50, value_parser = count(1, usize::MAX))]
    pub window: usize,
    /// Write a contact sheet per run (EXEMPLAR-TARGET.png) and the table (quality.txt) here.
    #[arg(long, short = 'o', value_name = "DIR")]
    pub output: Option<PathBuf>,
    /// Also write the report as JSON.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Measure the palette of every pixel against the exemplar's at its own distance from the
    /// edge (as `eval --own-depths`); by default a shape deeper than the exemplar's paint is
    /// measured at the exemplar's depths stretched to it.
    #[arg(long)]
    pub own_depths: bool,
    /// Runs painted at the same time, 1 to 64 (each uses every thread for its own stages).
    #[arg(long, default_value_t = 2, value_parser = count(1, 64))]
    pub jobs: usize,
    #[command(flatten)]
    pub threads: Threads,
    #[command(flatten)]
    pub exemplar_dir: ExemplarDirs,
    #[command(flatten)]
    pub flags: SynthFlags,
}

/// Runs `quality`.
pub fn run(args: Args, ctx: &Ctx) -> Result<()> {
    args.threads.apply()?;
    if args.flags.target_scale.is_some() {
        bail!("--target-scale is for `synth`; use --scale with `quality`");
    }
    let params = args.flags.params()?;
    let defaults = SuiteOptions::default();
    let (identity, targets) = if args.target.is_empty() {
        (defaults.identity, defaults.targets.clone())
    } else {
        let targets = args
            .target
            .iter()
            .filter(|t| t.as_str() != IDENTITY)
            .map(|t| {
                TargetKind::parse(t).with_context(|| {
                    let names: Vec<&str> = TargetKind::ALL.iter().map(|k| k.name()).collect();
                    format!("--target '{}': expected {} or one of {}", t, IDENTITY, names.join(", "))
                })
            })
            .collect::<Result<Vec<_>>>()?;
        (args.target.iter().any(|t| t == IDENTITY), targets)
    };
    let mut options = SuiteOptions::default()
        .exemplars(args.exemplar)
        .exemplar_dirs(args.exemplar_dir.dirs)
        .targets(targets)
        .identity(identity)
        .scale(args.scale)
        .frames(args.frames)
        .long_frames(args.long_frames)
        .window(args.window)
        .params(params)
        .eval(fluidymation::eval::EvalOptions::default().depth_stretch(!args.own_depths))
        .jobs(args.jobs);
    if let Some(dir) = &args.output {
        options = options.sheets(dir);
    }
    options.validate()?;
    // Where the results go is checked before the suite runs (it may take an hour).
    if let Some(dir) = &args.output {
        fluidymation::output::prepare_dir(dir).context("-o: cannot write the contact sheets and the table there")?;
    }
    if let Some(path) = &args.json {
        fluidymation::output::prepare_file(path).context("--json: cannot write the report there")?;
    }
    let bars = Bars::new(ctx.quiet);
    let report = quality::run(&options, &bars);
    bars.clear();
    let report = report.context("the quality suite failed")?;
    let table = report.to_string();
    println!("{table}");
    if let Some(dir) = &args.output {
        let path = dir.join("quality.txt");
        img::atomic_write(&path, |w| writeln!(w, "{table}"))?;
    }
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&report).context("could not serialize the report")?;
        img::atomic_write(path, |w| w.write_all(text.as_bytes()))
            .with_context(|| format!("could not write '{}'", path.display()))?;
        if !ctx.quiet {
            eprintln!("report written to '{}'", path.display());
        }
    }
    Ok(())
}
