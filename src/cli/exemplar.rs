//! `fluidymation exemplar …`: list, show, generate and import style exemplars.

use super::Ctx;
use super::params::count;
use anyhow::{Context, bail};
use fluidymation::exemplar::generate::{self, GeneratorParams, Pigment};
use fluidymation::exemplar::import::{self, ImportOptions};
use fluidymation::exemplar::{self, Exemplar, Origin, SearchPath};
use fluidymation::progress::{NoProgress, Progress};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// Arguments of `exemplar`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Extra folder to look for exemplars in, before FLUIDYMATION_EXEMPLARS, the user's
    /// exemplar folder and the bundled set (repeatable).
    #[arg(long = "exemplar-dir", value_name = "DIR", global = true)]
    pub exemplar_dirs: Vec<PathBuf>,
    #[command(subcommand)]
    pub command: Command,
}

/// The `exemplar` subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// List the exemplars that can be used by name: name, size, frames, description, where.
    List,
    /// Print an exemplar's metadata; optionally write a contact sheet of frames and masks.
    Show(ShowArgs),
    /// Generate a watercolor exemplar by simulation (paint spreading on wet paper).
    Generate(GenerateArgs),
    /// Import a PNG/JPEG frame sequence of real paint, or one image (a still: a scanned swatch):
    /// paper color, masks, metadata.
    Import(ImportArgs),
}

/// Arguments of `exemplar show`.
#[derive(clap::Args, Debug)]
pub struct ShowArgs {
    /// Name of the exemplar, or path to its folder.
    pub name: String,
    /// Write a contact sheet PNG (frames on top, masks below) here.
    #[arg(short, long, value_name = "PNG")]
    pub output: Option<PathBuf>,
    /// Frames on the contact sheet (1 to 64).
    #[arg(long, default_value_t = 8, value_parser = count(1, 64))]
    pub columns: usize,
    /// Largest side of one cell of the contact sheet, pixels (8 to 1024).
    #[arg(long, default_value_t = 200, value_parser = count(8, 1024))]
    pub cell: usize,
}

/// Arguments of `exemplar generate`.
#[derive(clap::Args, Debug)]
pub struct GenerateArgs {
    /// Name of the new exemplar (its folder name).
    #[arg(long)]
    pub name: String,
    /// Folder to create the exemplar folder NAME in. Default: the user's exemplar folder.
    #[arg(short, long, value_name = "DIR")]
    pub output: Option<PathBuf>,
    /// Replace an existing exemplar of that name.
    #[arg(short, long)]
    pub force: bool,
    /// Pigment: rose, yellow, blue, ink, umber or green.
    #[arg(long, default_value = "blue", value_parser = parse_pigment)]
    pub pigment: Pigment,
    /// Seed of every random choice (same seed, same exemplar).
    #[arg(long, default_value_t = 1, value_parser = super::params::parse_seed)]
    pub seed: u64,
    /// Number of frames (2 to 1000).
    #[arg(long, default_value_t = 30, value_parser = count(2, generate::MAX_FRAMES))]
    pub frames: usize,
    /// Frame size, WIDTHxHEIGHT (16–2048 each).
    #[arg(long, default_value = "200x200", value_parser = parse_size)]
    pub size: (usize, usize),
    /// Bloom speed: 0.5 slow, 1 normal, 2 a fast burst (0.25–4).
    #[arg(long, default_value_t = 1.0)]
    pub bloom: f32,
    /// Rim strength: 0 none, 1 normal, 3 strong dark rims (0–4).
    #[arg(long, default_value_t = 1.0)]
    pub rim: f32,
    /// Directional drift of the water X,Y in pixels per step, y down (each −0.5–0.5),
    /// e.g. 0.15,0 for a wash running right.
    #[arg(long, default_value = "0,0", value_parser = parse_pair, allow_hyphen_values = true)]
    pub flow: (f32, f32),
    /// Number of drops (1–16).
    #[arg(long, default_value_t = 1, value_parser = count(1, 16))]
    pub drops: usize,
    /// Drop radius in pixels at 200 px (2–50).
    #[arg(long, default_value_t = 7.0)]
    pub drop_radius: f32,
    /// Granulation relative to the pigment's own (0–3).
    #[arg(long, default_value_t = 1.0)]
    pub granulation: f32,
    /// Paper grain (0–3).
    #[arg(long, default_value_t = 1.0)]
    pub grain: f32,
    /// Pigment load (0.1–5).
    #[arg(long, default_value_t = 1.0)]
    pub load: f32,
    /// Fraction of frames at the end where the front stops and the paint dries (0–0.8).
    #[arg(long, default_value_t = 0.0)]
    pub drying: f32,
    /// Simulation steps per frame (1–100).
    #[arg(long, default_value_t = 12, value_parser = count(1, 100))]
    pub steps_per_frame: usize,
    /// Frame rate written to the metadata.
    #[arg(long, default_value_t = 24.0)]
    pub fps: f32,
    /// Also write a contact sheet PNG here.
    #[arg(long, value_name = "PNG")]
    pub sheet: Option<PathBuf>,
}

/// Arguments of `exemplar import`.
#[derive(clap::Args, Debug)]
pub struct ImportArgs {
    /// Folder (or glob such as `shots/*.jpg`) of PNG/JPEG frames, in natural order, or one
    /// PNG/JPEG image: a still exemplar (a swatch of paint on paper, with paper around it).
    pub src: PathBuf,
    /// Name of the new exemplar (its folder name).
    #[arg(long)]
    pub name: String,
    /// Folder to create the exemplar folder NAME in. Default: the user's exemplar folder.
    #[arg(short, long, value_name = "DIR")]
    pub output: Option<PathBuf>,
    /// Replace an existing exemplar of that name.
    #[arg(short, long)]
    pub force: bool,
    /// Crop X,Y,W,H in source pixels (applied before --scale).
    #[arg(long, value_parser = parse_crop)]
    pub crop: Option<[usize; 4]>,
    /// Scale after cropping (0.02–4).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f32,
    /// Frame rate of the footage.
    #[arg(long, default_value_t = 24.0)]
    pub fps: f32,
    /// Fixed threshold on the paint measure (optical density) instead of the automatic one.
    #[arg(long)]
    pub threshold: Option<f32>,
    /// One-line description.
    #[arg(long, default_value = "")]
    pub description: String,
    /// License of the footage, e.g. CC-BY-4.0.
    #[arg(long, default_value = "unknown")]
    pub license: String,
    /// Also write a contact sheet PNG here.
    #[arg(long, value_name = "PNG")]
    pub sheet: Option<PathBuf>,
}

/// `println!` that ends quietly when stdout is closed (`exemplar list | head`).
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = writeln!(std::io::stdout().lock(), $($arg)*) {
            if e.kind() == std::io::ErrorKind::BrokenPipe {
                std::process::exit(0);
            }
            return Err(anyhow::Error::from(e).context("could not write to stdout"));
        }
    }};
}

fn parse_pigment(s: &str) -> Result<Pigment, String> {
    s.parse().map_err(|e: fluidymation::Error| e.to_string())
}

fn parse_size(s: &str) -> Result<(usize, usize), String> {
    let err = || format!("'{s}' is not WIDTHxHEIGHT (e.g. 200x200)");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(err)?;
    Ok((w.trim().parse().map_err(|_| err())?, h.trim().parse().map_err(|_| err())?))
}

fn parse_pair(s: &str) -> Result<(f32, f32), String> {
    let err = || format!("'{s}' is not X,Y (e.g. 0.15,0)");
    let (x, y) = s.split_once(',').ok_or_else(err)?;
    Ok((x.trim().parse().map_err(|_| err())?, y.trim().parse().map_err(|_| err())?))
}

fn parse_crop(s: &str) -> Result<[usize; 4], String> {
    let v: Vec<usize> = s
        .split(',')
        .map(|p| p.trim().parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("'{s}' is not X,Y,W,H in whole pixels (e.g. 100,50,400,400)"))?;
    v.try_into().map_err(|_| format!("'{s}' is not X,Y,W,H (four numbers)"))
}

/// Runs `exemplar`.
pub fn run(args: Args, ctx: &Ctx) -> anyhow::Result<()> {
    let search = SearchPath::standard(&args.exemplar_dirs);
    match args.command {
        Command::List => list(&search),
        Command::Show(a) => show(a, &search),
        Command::Generate(a) => generate(a, &search, ctx),
        Command::Import(a) => import(a, &search, ctx),
    }
}

fn list(search: &SearchPath) -> anyhow::Result<()> {
    let all = exemplar::list(search);
    if all.is_empty() {
        outln!("no exemplars found");
        return Ok(());
    }
    let width = all.iter().map(|i| i.name.chars().count()).max().unwrap_or(4).max(4);
    // The descriptions' column as wide as the longest (up to 72 characters; a longer one is
    // cut with an ellipsis), so that WHERE stays one column.
    const MAX_DESCRIPTION: usize = 72;
    let cut = |d: &str| -> String {
        if d.chars().count() <= MAX_DESCRIPTION {
            d.to_string()
        } else {
            d.chars().take(MAX_DESCRIPTION - 1).chain(std::iter::once('…')).collect()
        }
    };
    let descriptions: Vec<String> = all.iter().map(|i| cut(&i.description)).collect();
    let dwidth = descriptions.iter().map(|d| d.chars().count()).max().unwrap_or(0).max(11);
    outln!("{:width$}  {:>9}  {:>6}  {:>6}  {:dwidth$}  WHERE", "NAME", "SIZE", "FRAMES", "BORDER", "DESCRIPTION");
    for (i, description) in all.iter().zip(&descriptions) {
        let size = format!("{}x{}", i.size.0, i.size.1);
        let hidden = if i.shadowed { " [hidden by an earlier one]" } else { "" };
        outln!(
            "{:width$}  {:>9}  {:>6}  {:>6.1}  {:dwidth$}  {}{}",
            i.name,
            size,
            i.frames,
            i.border_width,
            description,
            i.location,
            hidden
        );
    }
    Ok(())
}

fn print_meta(ex: &Exemplar) -> anyhow::Result<()> {
    let m = &ex.meta;
    outln!("name:         {}", m.name);
    outln!("description:  {}", m.description);
    if let Some(d) = &ex.dir {
        outln!("folder:       {}", d.display());
    } else {
        outln!("folder:       (bundled)");
    }
    outln!("size:         {}x{} px, {} frames at {} fps", ex.width(), ex.height(), ex.len(), m.fps);
    outln!("paper:        {}", m.paper);
    outln!("pigment:      {}", m.pigment);
    outln!("border width: {} px", m.border_width);
    outln!("scale, speed: {}, {}", m.scale, m.speed);
    if let Some(seed) = m.seed {
        outln!("seed:         {seed}");
    }
    if let Some(g) = &m.generator {
        let mut keys: Vec<_> = g.iter().map(|(k, v)| format!("{k}={v}")).collect();
        keys.sort();
        outln!("generator:    {}", keys.join(" "));
    }
    outln!("license:      {}", m.license);
    outln!("origin:       {}", m.origin);
    Ok(())
}

fn show(a: ShowArgs, search: &SearchPath) -> anyhow::Result<()> {
    let ex = exemplar::find(&a.name, search).with_context(|| format!("could not load exemplar '{}'", a.name))?;
    print_meta(&ex)?;
    let est = exemplar::border::estimate_border_width(&ex);
    outln!("border width estimated from the frames: {} px", est.width);
    if let Some(out) = a.output {
        write_sheet(&ex, &out, a.columns, a.cell)?;
        outln!("contact sheet: {}", out.display());
    }
    Ok(())
}

fn write_sheet(ex: &Exemplar, out: &Path, columns: usize, cell: usize) -> anyhow::Result<()> {
    let sheet = exemplar::contact_sheet(ex, columns, cell);
    fluidymation::img::save_rgb(out, &sheet).with_context(|| format!("could not write '{}'", out.display()))
}

/// Where a new exemplar called `name` goes.
/// The folder a new exemplar NAME is written to: `output/NAME`, else in the user's exemplar
/// folder; an existing one is an error unless `force`.
fn target_dir(output: Option<PathBuf>, name: &str, force: bool, search: &SearchPath) -> anyhow::Result<PathBuf> {
    exemplar::validate_name(name)?;
    let parent = match output {
        Some(o) => o,
        None => search
            .first(Origin::User)
            .map(Path::to_path_buf)
            .context("no user exemplar folder (HOME is not set); pass -o DIR")?,
    };
    fluidymation::output::prepare_dir(&parent).context("-o: cannot create the exemplar folder there")?;
    let dir = parent.join(name);
    if dir.exists() && !force {
        bail!("'{}' already exists; pass --force to replace it or choose another --name", dir.display());
    }
    if exemplar::list(&SearchPath::new().with_bundled(true)).iter().any(|b| b.name == name) {
        log::warn!(
            "'{name}' is also the name of a bundled exemplar: wherever '{}' is searched (the user's exemplar \
             folder always is, before the bundled set), '-e {name}'{} will paint with this one; choose another \
             --name to keep both",
            parent.display(),
            if name == exemplar::DEFAULT { " and the default style" } else { "" }
        );
    }
    Ok(dir)
}

/// An indicatif bar on stderr when it is a terminal and not `--quiet`.
struct Bar(Option<indicatif::ProgressBar>);

impl Bar {
    fn new(ctx: &Ctx) -> Bar {
        if ctx.quiet || !std::io::stderr().is_terminal() {
            return Bar(None);
        }
        let bar = indicatif::ProgressBar::new(0);
        if let Ok(style) = indicatif::ProgressStyle::with_template("{msg:>12} [{bar:30}] {pos}/{len} {elapsed}") {
            bar.set_style(style.progress_chars("=> "));
        }
        Bar(Some(bar))
    }
    fn progress(&self) -> &dyn Progress {
        match &self.0 {
            Some(_) => self,
            None => &NoProgress,
        }
    }
}

impl Progress for Bar {
    fn update(&self, stage: &str, done: usize, total: usize) -> bool {
        if let Some(b) = &self.0 {
            b.set_length(total as u64);
            b.set_position(done as u64);
            b.set_message(stage.to_string());
        }
        true
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        if let Some(b) = &self.0 {
            b.finish_and_clear();
        }
    }
}

fn generate(a: GenerateArgs, search: &SearchPath, ctx: &Ctx) -> anyhow::Result<()> {
    let dir = target_dir(a.output, &a.name, a.force, search)?;
    let params = GeneratorParams::default()
        .size(a.size.0, a.size.1)
        .frames(a.frames)
        .steps_per_frame(a.steps_per_frame)
        .fps(a.fps)
        .seed(a.seed)
        .pigment(a.pigment)
        .bloom(a.bloom)
        .rim(a.rim)
        .flow([a.flow.0, a.flow.1])
        .drops(a.drops)
        .drop_radius(a.drop_radius)
        .granulation(a.granulation)
        .grain(a.grain)
        .load(a.load)
        .drying(a.drying);
    params.validate()?;
    let start = std::time::Instant::now();
    let ex = {
        let bar = Bar::new(ctx);
        generate::generate(&params, &a.name, bar.progress())?
    };
    ex.save(&dir, a.force).with_context(|| format!("could not write exemplar '{}'", dir.display()))?;
    if !ctx.quiet {
        eprintln!(
            "generated '{}' ({}x{}, {} frames, border width {} px) in {:.1} s: {}",
            a.name,
            ex.width(),
            ex.height(),
            ex.len(),
            ex.meta.border_width,
            start.elapsed().as_secs_f32(),
            dir.display()
        );
    }
    if let Some(sheet) = a.sheet {
        write_sheet(&ex, &sheet, 8, 200)?;
    }
    Ok(())
}

fn import(a: ImportArgs, search: &SearchPath, ctx: &Ctx) -> anyhow::Result<()> {
    let dir = target_dir(a.output, &a.name, a.force, search)?;
    let mut opts = ImportOptions::default()
        .name(a.name.clone())
        .scale(a.scale)
        .fps(a.fps)
        .description(a.description)
        .license(a.license);
    opts.crop = a.crop;
    opts.threshold = a.threshold;
    let ex = {
        let bar = Bar::new(ctx);
        import::import(&a.src, &opts, bar.progress())
            .with_context(|| format!("could not import '{}'", a.src.display()))?
    };
    ex.save(&dir, a.force).with_context(|| format!("could not write exemplar '{}'", dir.display()))?;
    if !ctx.quiet {
        eprintln!(
            "imported '{}' ({}x{}, {}, paper {}, border width {} px): {}",
            a.name,
            ex.width(),
            ex.height(),
            if ex.len() == 1 { "1 frame: a still".to_string() } else { format!("{} frames", ex.len()) },
            ex.meta.paper,
            ex.meta.border_width,
            dir.display()
        );
    }
    if let Some(sheet) = a.sheet {
        write_sheet(&ex, &sheet, 8, 200)?;
    }
    Ok(())
}
