//! `fluidymation inspect`: what is in an animation.

use super::Ctx;
use anyhow::Context;
use fluidymation::anim::{self, LoadOptions};
use std::path::PathBuf;

/// Arguments of `inspect`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A Lottie .json file, a directory or glob of SVG frames, or a directory of PNG masks.
    pub input: PathBuf,
    /// Scale the canvas (0.5 = half size).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f32,
}

/// Runs `inspect`.
pub fn run(args: Args, _ctx: &Ctx) -> anyhow::Result<()> {
    let opts = LoadOptions { scale: args.scale, ..Default::default() };
    let a = anim::load(&args.input, &opts).with_context(|| format!("could not load '{}'", args.input.display()))?;
    println!("{}x{} px, {} fps, {} frames ({:.2} s)", a.width, a.height, a.fps, a.frames, a.duration());
    for r in &a.regions {
        println!("{:02} {} [{}] frames {}..{}", r.index, r.name, r.kind.as_str(), r.visible.start + 1, r.visible.end);
    }
    Ok(())
}
