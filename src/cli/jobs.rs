//! `fluidymation render-layer` and `fluidymation composite`: the two kinds of job a render is
//! cut into (`fluidymation plan` lists them for a whole batch). Run by hand or by a job
//! scheduler, they give the same bytes as `render`.

use super::Ctx;
use super::params::Threads;
use super::progress::{Bars, handle_interrupts};
use super::render::{RenderArgs, check_args, check_layer_keys, file_options, load_input};
use anyhow::{Context, Result, bail};
use fluidymation::Error;
use fluidymation::render;
use std::path::PathBuf;

/// Arguments of `render-layer`.
#[derive(clap::Args, Debug)]
#[command(mut_arg("target_scale", |a| a.hide(true)))]
pub struct LayerArgs {
    /// The input (as for `render`; one file).
    pub input: PathBuf,
    /// The input's output directory (as `render -o` for this one input); the layer is painted
    /// into OUT_DIR/layers/NN_name/.
    #[arg(long, short = 'o', value_name = "OUT_DIR")]
    pub output: PathBuf,
    /// The layer to paint: its name or 1-based index.
    #[arg(long, value_name = "LAYER")]
    pub layer: String,
    #[command(flatten)]
    pub threads: Threads,
    #[command(flatten)]
    pub render: RenderArgs,
}

/// Arguments of `composite`.
#[derive(clap::Args, Debug)]
#[command(mut_arg("target_scale", |a| a.hide(true)))]
pub struct CompositeArgs {
    /// The input (as for `render`; one file).
    pub input: PathBuf,
    /// The input's output directory, where its layers were painted; the frames are written
    /// here.
    #[arg(long, short = 'o', value_name = "OUT_DIR")]
    pub output: PathBuf,
    /// Also write an animated GIF.
    #[arg(long, value_name = "FILE")]
    pub gif: Option<PathBuf>,
    #[command(flatten)]
    pub threads: Threads,
    #[command(flatten)]
    pub render: RenderArgs,
}

/// Runs `render-layer`.
pub fn run_layer(args: LayerArgs, ctx: &Ctx) -> Result<()> {
    args.threads.apply()?;
    let styles = check_args(&args.render)?;
    let anim = load_input(&args.input, &args.render)?;
    check_layer_keys(&args.render, styles.as_ref(), &[&anim])?;
    let opts = file_options(&anim, &args.input, args.output.clone(), None, &args.render, styles.as_ref())?;
    let region = anim.find_region(&args.layer).context("--layer")?;
    handle_interrupts();
    let bars = Bars::new(ctx.quiet);
    let result = render::render_layer(&anim, &opts, region, &bars);
    bars.clear();
    let s = match result {
        Ok(s) => s,
        Err(Error::Cancelled) => bail!(anyhow::Error::new(Error::Cancelled).context(
            "interrupted; the painted frames and a checkpoint are kept: run the same command again to continue"
        )),
        Err(e) => {
            return Err(anyhow::Error::new(e).context(format!(
                "could not paint layer '{}' of '{}'",
                args.layer,
                args.input.display()
            )));
        }
    };
    if !ctx.quiet {
        let how = match (s.painted, s.resumed) {
            (0, r) => format!("already complete ({r} frames)"),
            (p, 0) => format!("{p} frames painted"),
            (p, r) => format!("{p} frames painted after {r} resumed"),
        };
        eprintln!(
            "layer {:02} {} ({}): {} in {:.1} s -> {}",
            s.index,
            s.name,
            s.exemplar,
            how,
            s.seconds,
            s.dir.display()
        );
    }
    Ok(())
}

/// Runs `composite`.
pub fn run_composite(args: CompositeArgs, ctx: &Ctx) -> Result<()> {
    args.threads.apply()?;
    let styles = check_args(&args.render)?;
    let anim = load_input(&args.input, &args.render)?;
    check_layer_keys(&args.render, styles.as_ref(), &[&anim])?;
    let opts = file_options(&anim, &args.input, args.output.clone(), args.gif.clone(), &args.render, styles.as_ref())?;
    handle_interrupts();
    let bars = Bars::new(ctx.quiet);
    let result = render::composite(&anim, &opts, &bars);
    bars.clear();
    let s = match result {
        Ok(s) => s,
        Err(Error::Cancelled) => {
            bail!(anyhow::Error::new(Error::Cancelled).context("interrupted; run the same command again"))
        }
        Err(e) => {
            return Err(anyhow::Error::new(e).context(format!("could not composite '{}'", args.input.display())));
        }
    };
    if !ctx.quiet {
        eprintln!(
            "{} frames composited in {:.1} s -> {}{}",
            s.frames,
            s.seconds,
            s.frame_dir.display(),
            s.gif.as_ref().map(|g| format!(", {}", g.display())).unwrap_or_default()
        );
    }
    Ok(())
}
