//! `fluidymation bench`: the end-to-end speed of the engine on a paper-like workload.

use super::Ctx;
use super::params::{ExemplarDirs, SynthFlags, Threads};
use super::workload;
use anyhow::{Context, Result};
use fluidymation::guide::GuideStream;
use fluidymation::synth::{Source, StageTimes, Synthesizer};
use std::time::{Duration, Instant};

/// Arguments of `bench`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Frames to synthesize (at least 1).
    #[arg(long, default_value_t = 10, value_parser = super::params::count(1, usize::MAX))]
    pub frames: usize,
    /// Target size WxH (the horse-like shape is scaled to it).
    #[arg(long, default_value = "1000x800")]
    pub size: String,
    /// Exemplar (name or folder) [default: a generated 400x222x20 bloom, as in the paper's horse].
    #[arg(long, short = 'e')]
    pub exemplar: Option<String>,
    #[command(flatten)]
    pub exemplar_dir: ExemplarDirs,
    #[command(flatten)]
    pub threads: Threads,
    /// Write the workload instead of timing it: DIR/masks/0001.png … (the target's masks) and
    /// DIR/exemplar (the exemplar), to time `synth` or `render` on it end to end.
    #[arg(long, value_name = "DIR")]
    pub save_workload: Option<std::path::PathBuf>,
    #[command(flatten)]
    pub flags: SynthFlags,
}

fn peak_memory_mib() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

/// Runs `bench`.
pub fn run(args: Args, ctx: &Ctx) -> Result<()> {
    args.threads.apply()?;
    let params = args.flags.params()?;
    let (w, h) = args
        .size
        .split_once('x')
        .and_then(|(a, b)| Some((a.parse::<usize>().ok()?, b.parse::<usize>().ok()?)))
        .filter(|&(a, b)| (64..=8192).contains(&a) && (64..=8192).contains(&b))
        .with_context(|| format!("--size '{}': expected WxH between 64 and 8192, e.g. 1000x800", args.size))?;
    let exemplar = match &args.exemplar {
        Some(e) => super::find_exemplar(e, &args.exemplar_dir.dirs)?,
        None => workload::horse_exemplar()?,
    };
    if let Some(dir) = &args.save_workload {
        return save_workload(dir, &exemplar, args.frames, (w, h), ctx);
    }
    let t = Instant::now();
    let source = Source::prepare(&exemplar, &params)?;
    let prepare = t.elapsed();
    let masked = workload::horse_mask(w, h, 0).data().iter().filter(|&&v| v > 0.5).count();
    let t = Instant::now();
    let stream = GuideStream::new(args.frames, |k| Ok(workload::horse_mask(w, h, k)), params.guide())?;
    let backward = t.elapsed();
    let mut synth = Synthesizer::new(source, params)?;
    synth.set_target_extent(stream.extent_scale());
    let (mut guides_t, mut synth_t) = (Duration::ZERO, Duration::ZERO);
    let mut levels: Vec<Duration> = Vec::new();
    let mut st = StageTimes::default();
    let mut evals = 0u64;
    let mut t = Instant::now();
    for (k, g) in stream.enumerate() {
        let g = g?;
        guides_t += t.elapsed();
        let t1 = Instant::now();
        let out = synth.step(&g)?;
        synth_t += t1.elapsed();
        if levels.len() < out.level_times.len() {
            levels.resize(out.level_times.len(), Duration::ZERO);
        }
        for (a, b) in levels.iter_mut().zip(&out.level_times) {
            *a += *b;
        }
        let s = out.stages;
        for (a, b) in [
            (&mut st.target, s.target),
            (&mut st.shift, s.shift),
            (&mut st.vote, s.vote),
            (&mut st.occurrence, s.occurrence),
            (&mut st.patchmatch, s.patchmatch),
            (&mut st.init, s.init),
        ] {
            *a += b;
        }
        evals += out.evaluations;
        if !ctx.quiet {
            eprintln!("frame {:>3}: {:.3} s", k + 1, t1.elapsed().as_secs_f64());
        }
        t = Instant::now();
    }
    let n = args.frames.max(1) as f64;
    let per = |d: Duration| d.as_secs_f64() / n;
    println!(
        "workload: target {}x{} ({} masked px), exemplar '{}' {}x{}x{}, {} threads",
        w,
        h,
        masked,
        exemplar.meta.name,
        exemplar.width(),
        exemplar.height(),
        exemplar.len(),
        rayon::current_num_threads()
    );
    println!("exemplar preparation (guides + pyramid): {:.2} s", prepare.as_secs_f64());
    println!(
        "target guides: backward pass {:.3} s/frame, forward {:.3} s/frame",
        backward.as_secs_f64() / n,
        per(guides_t)
    );
    println!("synthesis: {:.3} s/frame ({:.2} M patch evaluations/frame)", per(synth_t), evals as f64 / n / 1e6);
    println!("total: {:.3} s/frame", (backward.as_secs_f64() + guides_t.as_secs_f64() + synth_t.as_secs_f64()) / n);
    let lv: Vec<String> = levels.iter().rev().enumerate().map(|(l, d)| format!("L{} {:.3}", l, per(*d))).collect();
    println!("per level (finest = L0), s/frame: {}", lv.join(", "));
    println!(
        "per stage, s/frame: patchmatch {:.3}, occurrence {:.3}, vote {:.3}, init/merge {:.3}, shift {:.3}, target layout {:.3}",
        per(st.patchmatch),
        per(st.occurrence),
        per(st.vote),
        per(st.init),
        per(st.shift),
        per(st.target)
    );
    if let Some(m) = peak_memory_mib() {
        println!("peak memory: {:.0} MiB", m);
    }
    Ok(())
}

/// Writes the workload's masks and exemplar under `dir` (see [`Args::save_workload`]).
fn save_workload(
    dir: &std::path::Path,
    exemplar: &fluidymation::exemplar::Exemplar,
    frames: usize,
    (w, h): (usize, usize),
    ctx: &Ctx,
) -> Result<()> {
    let masks = dir.join("masks");
    std::fs::create_dir_all(&masks).with_context(|| format!("could not create '{}'", masks.display()))?;
    for k in 0..frames {
        fluidymation::img::save_gray(&masks.join(format!("{:04}.png", k + 1)), &workload::horse_mask(w, h, k))?;
    }
    let ex = dir.join("exemplar");
    exemplar.save(&ex, true)?;
    if !ctx.quiet {
        println!("{} masks of {w}x{h} in {}, the exemplar in {}", frames, masks.display(), ex.display());
        println!(
            "time it end to end: fluidymation synth --exemplar {} --masks {} -o OUT",
            ex.display(),
            masks.display()
        );
    }
    Ok(())
}
