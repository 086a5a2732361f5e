//! The `fluidymation` command line: a thin layer over the library.

mod cli;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use std::process::ExitCode;

/// Stylize vector animations with the moving appearance of real paint.
#[derive(Parser, Debug)]
#[command(name = "fluidymation", version, about, long_about = None)]
struct Cli {
    /// Print nothing but errors (no progress, no warnings).
    #[arg(short, long, global = true)]
    quiet: bool,
    /// Print more detail (repeat for more).
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    verbose: u8,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Print an animation's size, frames and layers; optionally write mask and guide previews.
    Inspect(cli::inspect::Args),
    /// Stylize an animation: every layer painted with an exemplar, recolored, composited,
    /// written as PNG frames (and a GIF).
    Render(Box<cli::render::Args>),
    /// Print a batch render as a graph of jobs (JSON) for a job scheduler: one render-layer
    /// job per stylized layer of each input, one composite job per input.
    Plan(Box<cli::plan::Args>),
    /// Paint one layer of one input into OUT_DIR/layers/NN_name/ (a job of a plan; continues
    /// from its checkpoint when run again).
    RenderLayer(Box<cli::jobs::LayerArgs>),
    /// Recolor and composite an input's painted layers into frames and a GIF (a job of a
    /// plan, after its render-layer jobs).
    Composite(Box<cli::jobs::CompositeArgs>),
    /// Measure the engine's speed on a paper-like workload (the `horse` of Table 2).
    Bench(cli::bench::Args),
    /// Run the synthesis engine on a plain mask sequence (output in the exemplar's colors).
    Synth(cli::synth::Args),
    /// Measure a stylized sequence against its exemplar and target masks (coverage, texture,
    /// edge darkening, palette, temporal and incoherent change, motion); print a table or JSON,
    /// optionally draw a chart.
    Eval(cli::eval::Args),
    /// Run every exemplar on generated targets (still, growing, shrinking, translating,
    /// rotating, a thin limb, a long one) and the identity, and print one table of the
    /// measures; optionally contact sheets and JSON.
    Quality(Box<cli::quality::Args>),
    /// Manage style exemplars: list, show, generate and import.
    Exemplar(cli::exemplar::Args),
}

/// The command line with negative numbers taken as values everywhere (`--scale -1` is then
/// refused by the option's own check, which says what is expected, instead of by the parser
/// as an unknown flag with a hint that turns it into an input).
fn command() -> clap::Command {
    fn negatives(c: clap::Command) -> clap::Command {
        c.allow_negative_numbers(true).mut_subcommands(negatives)
    }
    negatives(Cli::command())
}

fn main() -> ExitCode {
    let cli = Cli::from_arg_matches(&command().get_matches()).unwrap_or_else(|e| e.exit());
    cli::init_logging(cli.quiet, cli.verbose);
    let ctx = cli::Ctx { quiet: cli.quiet, verbose: cli.verbose };
    cli::exit_with_parent();
    let result = match cli.command {
        Command::Inspect(args) => cli::inspect::run(args, &ctx),
        Command::Render(args) => cli::render::run(*args, &ctx),
        Command::Plan(args) => cli::plan::run(*args, &ctx),
        Command::RenderLayer(args) => cli::jobs::run_layer(*args, &ctx),
        Command::Composite(args) => cli::jobs::run_composite(*args, &ctx),
        Command::Bench(args) => cli::bench::run(args, &ctx),
        Command::Synth(args) => cli::synth::run(args, &ctx),
        Command::Eval(args) => cli::eval::run(args, &ctx),
        Command::Quality(args) => cli::quality::run(*args, &ctx),
        Command::Exemplar(args) => cli::exemplar::run(args, &ctx),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => cli::report_error(&err),
    }
}
