//! `fluidymation plan`: a batch render as a graph of jobs (JSON on stdout) for a job
//! scheduler: one `render-layer` job per stylized layer of each input and one `composite`
//! job per input that depends on them. Run in any order that respects the dependencies, by
//! hand or by `scripts/fluidymation_dask.py`, the jobs give the same bytes as `render`.

use super::Ctx;
use super::render::{RenderArgs, Targets, check_args, check_layer_keys, file_options, input_stem, load_input};
use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use fluidymation::anim::Animation;
use fluidymation::exemplar::{self, SearchPath};
use fluidymation::output;
use fluidymation::render::{self, NO_STYLE, RenderOptions};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The version of the plan's JSON layout.
pub const PLAN_FORMAT: u32 = 1;

/// A composite costs about this many times less per canvas pixel than synthesis per masked
/// pixel (measured on the demo: ~3 µs per masked pixel and frame to synthesize, ~0.1 µs per
/// canvas pixel and frame to recolor, composite and write).
const COMPOSITE_COST_DIVISOR: u64 = 25;

/// Arguments of `plan`.
#[derive(clap::Args, Debug)]
#[command(mut_arg("target_scale", |a| a.hide(true)))]
pub struct Args {
    #[command(flatten)]
    pub targets: Targets,
    #[command(flatten)]
    pub render: RenderArgs,
}

#[derive(serde::Serialize)]
struct Plan {
    format: u32,
    fluidymation: &'static str,
    /// The executable that made the plan (`argv[0]` of every job).
    program: String,
    out: String,
    /// What `cost` counts.
    cost_unit: &'static str,
    files: Vec<PlanFile>,
    jobs: Vec<Job>,
}

#[derive(serde::Serialize)]
struct PlanFile {
    input: String,
    stem: String,
    out_dir: String,
    gif: Option<String>,
    frames: usize,
    width: u32,
    height: u32,
    layer_jobs: Vec<String>,
    composite_job: String,
}

#[derive(serde::Serialize)]
struct Job {
    id: String,
    kind: &'static str,
    input: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    layer: Option<String>,
    argv: Vec<String>,
    deps: Vec<String>,
    inputs: Vec<String>,
    outputs: Vec<String>,
    cost: u64,
    frames: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    masked_pixels: Option<u64>,
}

fn text(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}

/// An absolute form of `p` (canonical when it exists).
fn absolute(p: &Path) -> Result<PathBuf> {
    match std::fs::canonicalize(p) {
        Ok(c) => Ok(c),
        Err(_) => std::path::absolute(p).with_context(|| format!("could not make '{}' absolute", p.display())),
    }
}

fn value_name<T: ValueEnum>(v: &T) -> String {
    v.to_possible_value().map(|p| p.get_name().to_string()).unwrap_or_default()
}

/// A key that `--style`/`--layer` resolve to region `region` and to no other.
fn layer_key(anim: &Animation, region: usize) -> Result<String> {
    let name = &anim.regions[region].name;
    if !name.contains('=') && name.trim() == name && anim.find_region(name).ok() == Some(region) {
        return Ok(name.clone());
    }
    let index = anim.regions[region].index.to_string();
    if anim.find_region(&index).ok() == Some(region) {
        return Ok(index);
    }
    bail!("'{}': layer '{}' cannot be named unambiguously on a command line", anim.path.display(), name)
}

/// The style as the jobs are given it: bundled exemplars by name, others by absolute folder
/// (so that the jobs find them from any folder, on any machine that shares it).
fn job_style(style: &str, dirs: &[PathBuf], known: &mut HashMap<String, String>) -> Result<String> {
    if style == NO_STYLE {
        return Ok(style.to_string());
    }
    if let Some(s) = known.get(style) {
        return Ok(s.clone());
    }
    let ex = exemplar::find(style, &SearchPath::standard(dirs))
        .with_context(|| format!("could not load exemplar '{}'", style))?;
    let resolved = match &ex.dir {
        Some(d) => text(&absolute(d)?),
        None => style.to_string(),
    };
    known.insert(style.to_string(), resolved.clone());
    Ok(resolved)
}

/// Runs `plan`.
pub fn run(mut args: Args, _ctx: &Ctx) -> Result<()> {
    args.targets.expand_lottie_globs();
    let styles = check_args(&args.render)?;
    let layout = args.targets.layout()?;
    let program = std::env::current_exe().context("could not find this program's path")?;
    let program = text(&absolute(&program)?);
    let out = absolute(&args.targets.output)?;
    let anims: Vec<Animation> =
        args.targets.inputs.iter().map(|i| load_input(i, &args.render)).collect::<Result<_>>()?;
    check_layer_keys(&args.render, styles.as_ref(), &anims.iter().collect::<Vec<_>>())?;
    let mut known = HashMap::new();
    let dirs: Vec<PathBuf> = args.render.exemplar_dir.dirs.iter().map(|d| absolute(d)).collect::<Result<_>>()?;
    let mut plan = Plan {
        format: PLAN_FORMAT,
        fluidymation: env!("CARGO_PKG_VERSION"),
        program: program.clone(),
        out: text(&out),
        cost_unit: "masked pixels × frames to synthesize (a composite counts canvas pixels × frames / 25)",
        files: Vec::new(),
        jobs: Vec::new(),
    };
    for ((anim, input), (out_dir, gif)) in anims.iter().zip(&args.targets.inputs).zip(layout) {
        let out_dir = absolute(&out_dir)?;
        let gif = gif.as_deref().map(absolute).transpose()?;
        let opts = file_options(anim, input, out_dir.clone(), gif.clone(), &args.render, styles.as_ref())
            .with_context(|| format!("could not plan '{}'", input.display()))?;
        let input_abs = absolute(input)?;
        add_file(&mut plan, anim, &opts, &input_abs, input_stem(input), &args.render, &dirs, &mut known)
            .with_context(|| format!("could not plan '{}'", input.display()))?;
    }
    let json = serde_json::to_string_pretty(&plan).context("could not write the plan")?;
    println!("{json}");
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn add_file(
    plan: &mut Plan,
    anim: &Animation,
    opts: &RenderOptions,
    input: &Path,
    stem: String,
    args: &RenderArgs,
    dirs: &[PathBuf],
    known: &mut HashMap<String, String>,
) -> Result<()> {
    let costs = render::layer_costs(anim, opts)?;
    let range = opts.frames.start..opts.frames.end.min(anim.frames);
    // The options every job of this file gets, with every layer's style spelled out.
    let mut common: Vec<String> = vec![
        "--frames".into(),
        format!("{}..{}", range.start + 1, range.end),
        "--scale".into(),
        args.scale.to_string(),
        "--strokes".into(),
        value_name(&opts.strokes),
        "--recolor".into(),
        value_name(&opts.recolor),
    ];
    if args.split_precomps {
        common.push("--split-precomps".into());
    }
    let mut extra_inputs = Vec::new();
    if let Some(bg) = &args.background {
        let p = Path::new(bg);
        let spec = if p.is_file() {
            let abs = text(&absolute(p)?);
            extra_inputs.push(abs.clone());
            abs
        } else {
            bg.clone()
        };
        common.extend(["--background".into(), spec]);
    }
    for d in dirs {
        common.extend(["--exemplar-dir".into(), text(d)]);
    }
    let mut exemplar_inputs: Vec<Vec<String>> = Vec::new();
    for c in &costs {
        let style = job_style(c.style.as_deref().unwrap_or(NO_STYLE), &opts.exemplar_dirs, known)?;
        exemplar_inputs.push(if Path::new(&style).is_absolute() { vec![style.clone()] } else { Vec::new() });
        common.extend(["--style".into(), format!("{}={}", layer_key(anim, c.region)?, style)]);
    }
    common.extend(args.flags.to_args());

    let input_text = text(input);
    let out_dir = text(&opts.out_dir);
    let mut layer_jobs = Vec::new();
    for (c, exemplars) in costs.iter().zip(exemplar_inputs) {
        if c.style.is_none() {
            continue;
        }
        let region = &anim.regions[c.region];
        let id = format!("{}/{}", stem, region.dir_name());
        let mut argv = vec![
            plan.program.clone(),
            "render-layer".into(),
            input_text.clone(),
            "-o".into(),
            out_dir.clone(),
            "--layer".into(),
            layer_key(anim, c.region)?,
        ];
        argv.extend(common.iter().cloned());
        let mut inputs = vec![input_text.clone()];
        inputs.extend(exemplars);
        plan.jobs.push(Job {
            id: id.clone(),
            kind: "layer",
            input: input_text.clone(),
            layer: Some(region.name.clone()),
            argv,
            deps: Vec::new(),
            inputs,
            outputs: vec![text(&output::layer_dir(&opts.out_dir, region))],
            cost: c.masked_pixels.max(1),
            frames: c.frames,
            masked_pixels: Some(c.masked_pixels),
        });
        layer_jobs.push(id);
    }

    let composite_id = format!("{stem}/composite");
    let mut argv = vec![plan.program.clone(), "composite".into(), input_text.clone(), "-o".into(), out_dir.clone()];
    if let Some(g) = &opts.gif {
        argv.extend(["--gif".into(), text(g)]);
    }
    if opts.keep_layers {
        argv.push("--keep-layers".into());
    }
    argv.extend(common.iter().cloned());
    let mut inputs = vec![input_text.clone()];
    inputs.extend(extra_inputs);
    for c in costs.iter().filter(|c| c.style.is_some()) {
        inputs.push(text(&output::layer_dir(&opts.out_dir, &anim.regions[c.region])));
    }
    let mut outputs: Vec<String> =
        range.clone().map(|f| text(&output::frame_path(&opts.out_dir, f, anim.frames))).collect();
    if let Some(g) = &opts.gif {
        outputs.push(text(g));
    }
    if opts.keep_layers {
        for r in &anim.regions {
            outputs.extend(
                range.clone().map(|f| text(&output::frame_path(&output::layer_dir(&opts.out_dir, r), f, anim.frames))),
            );
        }
    }
    let canvas = anim.width as u64 * anim.height as u64;
    plan.jobs.push(Job {
        id: composite_id.clone(),
        kind: "composite",
        input: input_text.clone(),
        layer: None,
        argv,
        deps: layer_jobs.clone(),
        inputs,
        outputs,
        cost: (canvas * range.len() as u64 / COMPOSITE_COST_DIVISOR).max(1),
        frames: range.len(),
        masked_pixels: None,
    });
    plan.files.push(PlanFile {
        input: input_text,
        stem,
        out_dir,
        gif: opts.gif.as_deref().map(text),
        frames: range.len(),
        width: anim.width,
        height: anim.height,
        layer_jobs,
        composite_job: composite_id,
    });
    Ok(())
}
