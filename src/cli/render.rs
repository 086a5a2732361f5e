//! `fluidymation render`: the whole pipeline, as motion designers run it, for one file or a
//! batch; and the options it shares with `plan`, `render-layer` and `composite`.

use super::params::{ExemplarDirs, SynthFlags, Threads, count, factor, parse_frames, parse_keyframe, warn_if_clipped};
use super::progress::{Bars, handle_interrupts};
use super::{Ctx, one_line};
use anyhow::{Context, Result, bail};
use fluidymation::anim::{self, Animation, LoadOptions};
use fluidymation::render::{self, Recolor, RenderOptions, RenderSummary, StrokeMode, Style};
use fluidymation::{Error, Progress};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// What to render and how: the options `render`, `plan`, `render-layer` and `composite`
/// share.
#[derive(clap::Args, Debug, Clone)]
pub struct RenderArgs {
    /// Style of one layer: LAYER=EXEMPLAR, LAYER a name or 1-based index, EXEMPLAR a name,
    /// a folder, or "none" to leave the layer flat. Repeat for more layers.
    #[arg(long, value_name = "LAYER=EXEMPLAR")]
    pub style: Vec<String>,
    /// Exemplar of every layer not given a --style [default: the bundled blue-bloom].
    #[arg(long, short = 'e', value_name = "NAME|DIR")]
    pub exemplar: Option<String>,
    /// A TOML file of styles: `default = "NAME"`, a `[layers]` table of LAYER = "EXEMPLAR",
    /// and per input file `[files."walk.json"]` with its own `default` and `layers`.
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
    #[arg(long, default_value_t = 1.0, value_parser = factor(0.0, 16.0))]
    pub scale: f32,
    /// Frames to render, 1-based inclusive: A..B, A.., ..B or N [default: all].
    #[arg(long, value_name = "A..B", allow_hyphen_values = true)]
    pub frames: Option<String>,
    /// Also write every layer alone (RGBA) under OUT_DIR/layers/NN_name/.
    #[arg(long)]
    pub keep_layers: bool,
    /// Make each layer inside a precomp a region of its own.
    #[arg(long)]
    pub split_precomps: bool,
    #[command(flatten)]
    pub exemplar_dir: ExemplarDirs,
    #[command(flatten, next_help_heading = "Synthesis (seed and engine parameters)")]
    pub flags: SynthFlags,
}

/// The inputs and where they go, as `render` and `plan` take them.
#[derive(clap::Args, Debug)]
pub struct Targets {
    /// Lottie .json files (a quoted glob of them, 'shots/*.json', stands for its files), an
    /// .svg file (a one-frame still), folders or quoted globs of SVG frames, or folders or
    /// globs of PNG masks. Globs: `*`, `?` and `[...]` classes (`[0-9]`, `[!0-9]`) in the file
    /// name. With several inputs, each is written to OUT_DIR/<name>/.
    #[arg(required = true, value_name = "INPUT")]
    pub inputs: Vec<PathBuf>,
    /// Output directory for the frames (NNNN.png, 0001 = the first frame); with several
    /// inputs, the folder of one sub-folder per input. On a render farm, a folder every
    /// machine shares.
    #[arg(long, short = 'o', value_name = "OUT_DIR")]
    pub output: PathBuf,
    /// Also write an animated GIF: to FILE (one input only), or without a value to
    /// OUT_DIR/<name>.gif for every input.
    #[arg(long, value_name = "FILE")]
    pub gif: Option<Option<PathBuf>>,
}

impl Targets {
    /// Replaces every glob that matches Lottie files (`'shots/*.json'`, quoted so the shell
    /// did not expand it) by those files in natural order, as the shell would have: each is
    /// an input of its own. Other globs stay one input (a sequence of frames).
    pub fn expand_lottie_globs(&mut self) {
        self.inputs = std::mem::take(&mut self.inputs)
            .into_iter()
            .flat_map(|input| {
                if !input.exists() && fluidymation::seq::is_glob(&input) {
                    match anim::source(&input) {
                        Ok(anim::Source::Lottie(file)) => return vec![file],
                        Ok(anim::Source::LottieFiles(files)) => return files,
                        _ => {}
                    }
                }
                vec![input]
            })
            .collect();
    }

    /// Where each input goes (see [`output_layout`]).
    pub fn layout(&self) -> Result<Vec<(PathBuf, Option<PathBuf>)>> {
        output_layout(&self.inputs, &self.output, self.gif.as_ref().map(|g| g.as_deref()))
    }
}

/// Arguments of `render`.
#[derive(clap::Args, Debug)]
// `--target-scale` is `synth`'s; `render` has `--scale`.
#[command(mut_arg("target_scale", |a| a.hide(true)))]
pub struct Args {
    #[command(flatten)]
    pub targets: Targets,
    #[command(flatten)]
    pub threads: Threads,
    /// Continue an interrupted (Ctrl-C, killed) render into the same OUT_DIR; give the same
    /// options as the interrupted run. In a batch, finished files are skipped and files not
    /// yet started are rendered.
    #[arg(long)]
    pub resume: bool,
    /// Measure each stylized layer against its exemplar afterwards and print the numbers.
    #[arg(long)]
    pub eval: bool,
    /// A painted keyframe, N=PAINTED.png (repeatable, one input only): frame N (1-based) of
    /// the animation painted over, at the canvas size — render it flat with `--exemplar none
    /// --frames N..N`, paint over it in any paint program. The layers it paints are painted
    /// from the painting(s) in every frame (carried along their motion, forward and backward;
    /// between two keyframes passing from one painting to the next); the layers left as they
    /// were keep their style.
    #[arg(long, value_name = "N=PNG")]
    pub keyframe: Vec<String>,
    /// Files rendered at the same time in a batch (they share the cores; each holds its
    /// layers in memory).
    #[arg(long, value_name = "N", default_value_t = 2, value_parser = count(1, usize::MAX))]
    pub parallel_files: usize,
    #[command(flatten)]
    pub render: RenderArgs,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct StylesFile {
    default: Option<String>,
    #[serde(default)]
    layers: toml::Table,
    #[serde(default)]
    files: BTreeMap<String, FileStylesEntry>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FileStylesEntry {
    default: Option<String>,
    #[serde(default)]
    layers: toml::Table,
}

/// A styles file: a default exemplar and per-layer styles for every input, and the same per
/// input file.
pub struct Styles {
    path: PathBuf,
    default: Option<String>,
    layers: Vec<(String, String)>,
    files: Vec<FileStyles>,
}

/// A styles file's `[files."KEY"]` table.
struct FileStyles {
    key: String,
    default: Option<String>,
    layers: Vec<(String, String)>,
}

fn layer_table(path: &Path, table: toml::Table, within: &str) -> Result<Vec<(String, String)>> {
    let mut out = Vec::new();
    for (k, v) in table {
        let Some(s) = v.as_str() else {
            bail!(
                "'{}': layer '{}'{} must be given an exemplar name as a string, e.g. {} = \"blue-bloom\"",
                path.display(),
                k,
                within,
                k
            );
        };
        out.push((k, s.to_string()));
    }
    Ok(out)
}

impl Styles {
    /// Reads a styles file.
    pub fn read(path: &Path) -> Result<Styles> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("could not read the styles file '{}'", path.display()))?;
        let file: StylesFile =
            toml::from_str(&text).with_context(|| format!("'{}' is not a valid styles file", path.display()))?;
        let layers = layer_table(path, file.layers, "")?;
        let mut files = Vec::new();
        for (key, entry) in file.files {
            let within = format!(" in [files.\"{key}\".layers]");
            let layers = layer_table(path, entry.layers, &within)?;
            files.push(FileStyles { key, default: entry.default, layers });
        }
        Ok(Styles { path: path.to_path_buf(), default: file.default, layers, files })
    }

    /// Whether the `[files."KEY"]` key names `input`: its file name, the path as given, or
    /// the path relative to the styles file.
    fn matches(&self, key: &str, input: &Path) -> bool {
        if input.file_name().is_some_and(|n| n == key) || input == Path::new(key) {
            return true;
        }
        let beside = self.path.parent().unwrap_or(Path::new(".")).join(key);
        matches!((std::fs::canonicalize(beside), std::fs::canonicalize(input)), (Ok(a), Ok(b)) if a == b)
    }

    /// The `[files]` entry of `input`, if any.
    fn file(&self, input: &Path) -> Option<&FileStyles> {
        self.files.iter().find(|f| self.matches(&f.key, input))
    }
}

/// The name of an input's output folder and GIF in a batch: the file's stem, a folder's
/// name, a glob's folder.
pub fn input_stem(input: &Path) -> String {
    let p = if fluidymation::seq::is_glob(input) { input.parent().unwrap_or(input) } else { input };
    let name = if p.is_dir() { p.file_name() } else { p.file_stem() };
    name.map(|n| n.to_string_lossy().into_owned()).filter(|n| !n.is_empty()).unwrap_or_else(|| "input".into())
}

/// Where each input goes: `(folder of its frames, its GIF)`. One input is written to
/// `out` itself (and `--gif FILE` is allowed); several to `out/<stem>/` and
/// `out/<stem>.gif`. Two inputs with the same stem are an error. `gif` is `--gif`: absent,
/// without a value, or with a file name.
pub fn output_layout(
    inputs: &[PathBuf],
    out: &Path,
    gif: Option<Option<&Path>>,
) -> Result<Vec<(PathBuf, Option<PathBuf>)>> {
    let stems: Vec<String> = inputs.iter().map(|i| input_stem(i)).collect();
    let named_gif = gif.flatten();
    if let Some(g) = named_gif {
        check_gif_name(g, inputs)?;
    }
    if inputs.len() == 1 {
        check_not_input(&inputs[0], out)?;
        let gif = gif.map(|_| named_gif.map_or_else(|| out.join(format!("{}.gif", stems[0])), Path::to_path_buf));
        return Ok(vec![(out.to_path_buf(), gif)]);
    }
    for (input, s) in inputs.iter().zip(&stems) {
        check_not_input(input, &out.join(s))?;
    }
    if let Some(g) = named_gif {
        bail!(
            "--gif '{}': with several inputs each GIF is written to OUT_DIR/<name>.gif; give --gif without a file \
             name (after the inputs)",
            g.display()
        );
    }
    for (i, s) in stems.iter().enumerate() {
        if let Some(j) = stems[..i].iter().position(|t| t == s) {
            bail!(
                "'{}' and '{}' would both be written to '{}': rename one, or render them in separate runs",
                inputs[j].display(),
                inputs[i].display(),
                out.join(s).display()
            );
        }
    }
    Ok(stems.iter().map(|s| (out.join(s), gif.map(|_| out.join(format!("{s}.gif"))))).collect())
}

/// A GIF file name given with `--gif FILE` must end in `.gif`, must not be an input, and must
/// not be an existing file that is not a GIF: `--gif` takes an optional value, so `--gif
/// walk.json intro.json` reads `walk.json` as the GIF's name, and writing it would destroy the
/// animation.
fn check_gif_name(gif: &Path, inputs: &[PathBuf]) -> Result<()> {
    let is_gif = gif.extension().is_some_and(|e| e.eq_ignore_ascii_case("gif"));
    // A folder is reported where the GIF is created.
    if !is_gif && !gif.is_dir() {
        bail!(
            "--gif '{}': not a .gif file name. To write OUT_DIR/<name>.gif, give --gif without a file name after \
             the inputs (or as the last option); to name the GIF, write --gif=FILE.gif",
            gif.display()
        );
    }
    if let Some(i) = inputs.iter().find(|i| *i == gif || same_file(i, gif)) {
        bail!("--gif '{}' is the input '{}': it would be overwritten", gif.display(), i.display());
    }
    if gif.is_file() {
        let mut magic = [0u8; 4];
        let is_gif = std::fs::File::open(gif).and_then(|mut f| std::io::Read::read_exact(&mut f, &mut magic)).is_ok()
            && &magic == b"GIF8";
        if !is_gif {
            bail!("--gif '{}' exists and is not a GIF: not overwriting it", gif.display());
        }
    }
    Ok(())
}

/// The frames of an input that is a folder (of masks or SVG frames) must not be written into
/// that folder: they would overwrite its frames.
pub fn check_not_input(input: &Path, out: &Path) -> Result<()> {
    // A glob of frames names their folder.
    let folder = if input.to_string_lossy().contains(['*', '?', '[']) { input.parent() } else { Some(input) };
    if let Some(folder) = folder.filter(|f| f.is_dir())
        && (folder == out || same_file(folder, out))
    {
        bail!(
            "the output folder '{}' is the input folder '{}': its frames would be overwritten; choose another -o",
            out.display(),
            folder.display()
        );
    }
    Ok(())
}

/// Whether two existing paths name the same file.
fn same_file(a: &Path, b: &Path) -> bool {
    matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
}

/// Loads one input with the scale and precomp options, printing its warnings.
pub fn load_input(input: &Path, args: &RenderArgs) -> Result<Animation> {
    let load = LoadOptions::default().scale(args.scale).split_precomps(args.split_precomps);
    let anim = anim::load(input, &load).with_context(|| format!("could not load '{}'", input.display()))?;
    print_warnings(input, &anim);
    Ok(anim)
}

/// Prints what the loader found wrong with `input` (unsupported features and the like), once
/// each, naming the file and the layer.
pub fn print_warnings(input: &Path, anim: &Animation) {
    for w in &anim.warnings {
        log::warn!("{}: {}", input.display(), w);
    }
    // A region's warnings name their layer (a Lottie region's may be about a layer inside it).
    for w in anim.regions.iter().flat_map(|r| &r.warnings) {
        log::warn!("{}: {}", input.display(), w);
    }
}

/// Parses `--style LAYER=EXEMPLAR` values.
fn style_flags(args: &RenderArgs) -> Result<Vec<(String, String)>> {
    args.style
        .iter()
        .map(|s| {
            let Some((layer, ex)) = s.split_once('=') else {
                bail!("--style '{}': expected LAYER=EXEMPLAR, e.g. --style body=ink-rims", s);
            };
            Ok((layer.trim().to_string(), ex.trim().to_string()))
        })
        .collect()
}

/// Checks the layers that `--style` and the styles file's `[layers]` name for every input:
/// each must be a layer of at least one of `anims`.
pub fn check_layer_keys(args: &RenderArgs, styles: Option<&Styles>, anims: &[&Animation]) -> Result<()> {
    let Some(first) = anims.first() else { return Ok(()) };
    let has = |key: &str| anims.iter().any(|a| a.find_region(key).is_ok());
    if let Some(s) = styles {
        for (layer, _) in &s.layers {
            if !has(layer) {
                let err = first.find_region(layer).err().map(anyhow::Error::new).unwrap_or_else(|| anyhow::anyhow!(""));
                return Err(err.context(format!("in the styles file '{}'", s.path.display())));
            }
        }
    }
    for (layer, _) in style_flags(args)? {
        if !has(&layer) {
            let err = first.find_region(&layer).err().map(anyhow::Error::new).unwrap_or_else(|| anyhow::anyhow!(""));
            return Err(err.context(format!("--style {layer}=…")));
        }
    }
    Ok(())
}

/// The options of one input: its output folder and GIF, and the styles that apply to it
/// (from the most to the least specific: `--style`, the styles file's `[files."NAME".layers]`,
/// its `[layers]`, `--exemplar`, `[files."NAME"].default`, `default`, the bundled default).
pub fn file_options(
    anim: &Animation,
    input: &Path,
    out_dir: PathBuf,
    gif: Option<PathBuf>,
    args: &RenderArgs,
    styles: Option<&Styles>,
) -> Result<RenderOptions> {
    let frames = parse_frames(args.frames.as_deref(), anim.frames)?;
    warn_if_clipped(args.frames.as_deref(), &frames, anim.frames, &format!("'{}'", input.display()));
    let mut opts = RenderOptions::new(out_dir, frames);
    let style = |name: &str| -> Style { name.parse().unwrap_or_else(|never| match never {}) };
    if let Some(s) = styles {
        opts.default_style = s.default.as_deref().map(style);
        opts.styles.extend(
            s.layers.iter().filter(|(layer, _)| anim.find_region(layer).is_ok()).map(|(l, ex)| (l.clone(), style(ex))),
        );
        if let Some(file) = s.file(input) {
            if let Some(d) = &file.default {
                opts.default_style = Some(style(d));
            }
            for (layer, ex) in &file.layers {
                anim.find_region(layer).with_context(|| {
                    format!("in the styles file '{}', [files.\"{}\".layers]", s.path.display(), file.key)
                })?;
                opts.styles.push((layer.clone(), style(ex)));
            }
        }
    }
    if let Some(e) = &args.exemplar {
        opts.default_style = Some(style(e));
    }
    for (layer, ex) in style_flags(args)? {
        if anim.find_region(&layer).is_ok() {
            opts.styles.push((layer, style(&ex)));
        }
    }
    opts.gif = gif;
    opts.exemplar_dirs = args.exemplar_dir.dirs.clone();
    if let Some(spec) = &args.background {
        opts.background = spec.parse()?;
    }
    // Mask sequences are white on nothing: glazed in their own color they would not show.
    let masks_only = anim.regions.iter().all(|r| r.kind == anim::RegionKind::MaskSequence);
    opts.recolor = args.recolor.unwrap_or(if masks_only { Recolor::None } else { Recolor::Glaze });
    if opts.recolor == Recolor::Glaze {
        let paper = opts.background.color(anim);
        for (i, r) in anim.regions.iter().enumerate() {
            // The last --style naming the layer wins, else the default.
            let style = opts.styles.iter().rev().find(|(k, _)| anim.find_region(k).ok() == Some(i)).map(|(_, e)| e);
            let flat = style.or(opts.default_style.as_ref()).is_some_and(|e| *e == Style::None);
            if let Some(p) = paper
                && !flat
                && r.color[3] > 0.0
                && (0..3).all(|i| (r.color[i] - p[i]).abs() < 0.02)
                && (args.strokes == StrokeMode::Stylize || !strokes_only(anim, i))
            {
                log::warn!(
                    "{}: layer '{}' has the background's color: a glaze of it does not show; \
                     try --recolor none (the exemplar's colors) or another --background",
                    input.display(),
                    r.name
                );
            }
        }
    }
    opts.strokes = args.strokes;
    opts.params = args.flags.params()?;
    opts.keep_layers = args.keep_layers;
    Ok(opts)
}

/// Whether region `i` draws strokes and no fill at the start, middle and end of its range: its
/// color is then its stroke's ([`anim::Region::color`]), and unless strokes are stylized the
/// glaze never shows that color (the strokes are drawn as they are, or dropped).
fn strokes_only(anim: &Animation, i: usize) -> bool {
    let r = &anim.regions[i];
    if !r.has_strokes || r.visible.is_empty() {
        return false;
    }
    let (a, b) = (r.visible.start, r.visible.end - 1);
    [a, a + (b - a) / 2, b]
        .iter()
        .all(|&f| anim.render(i, f).is_ok_and(|rf| rf.coverage().data().iter().all(|&c| c <= 0.0)))
}

/// Warns when `dir` holds frames (`NNNN.png`) outside the range just rendered: left by an
/// earlier render of other frames, they would be mistaken for part of this one (they are not
/// removed: they may be wanted).
fn warn_stale_frames(dir: &Path, range: &std::ops::Range<usize>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut stale: Vec<usize> = entries
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().into_string().ok()?;
            let n = name.strip_suffix(".png")?;
            (n.len() >= 4 && n.bytes().all(|b| b.is_ascii_digit())).then(|| n.parse::<usize>().ok()).flatten()
        })
        .filter(|&n| n == 0 || !range.contains(&(n - 1)))
        .collect();
    stale.sort_unstable();
    if let (Some(first), Some(last)) = (stale.first(), stale.last()) {
        log::warn!(
            "'{}' also holds {} frame(s) from an earlier render ({first:04}.png–{last:04}.png), outside the frames \
             rendered now ({}–{}); remove them if they are not wanted",
            dir.display(),
            stale.len(),
            range.start + 1,
            range.end
        );
    }
}

/// Checks the options every command that renders shares, before any input is read.
pub fn check_args(args: &RenderArgs) -> Result<Option<Styles>> {
    if args.flags.target_scale.is_some() {
        bail!("--target-scale is for `synth`; use --scale with `render`");
    }
    args.flags.params()?;
    let styles = style_flags(args)?;
    for (i, (layer, ex)) in styles.iter().enumerate() {
        if let Some((_, later)) = styles[i + 1..].iter().find(|(l, _)| l == layer) {
            log::warn!("--style {layer}={ex} is overridden by a later --style {layer}={later}");
        }
    }
    args.styles.as_deref().map(Styles::read).transpose()
}

/// Several SVG files given as inputs are most likely the frames of one sequence, expanded by
/// the shell.
fn check_svg_frames(inputs: &[PathBuf]) -> Result<()> {
    let svg = |p: &PathBuf| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("svg")) && p.is_file();
    if inputs.len() > 1 && inputs.iter().all(svg) {
        bail!(
            "{} SVG files were given as {} inputs; an SVG animation is a folder of frames: give the folder, or \
             quote the glob ('{}/*.svg') so the shell does not expand it (one .svg file alone is a still)",
            inputs.len(),
            inputs.len(),
            inputs[0].parent().unwrap_or(Path::new(".")).display()
        );
    }
    Ok(())
}

/// The progress of one file of a batch: its frames as one bar named after the file, and
/// the sum over the files as the total.
struct FileProgress<'a> {
    bars: &'a Bars,
    name: String,
    file: usize,
    counts: &'a Mutex<Vec<(usize, usize)>>,
}

impl Progress for FileProgress<'_> {
    fn update(&self, stage: &str, done: usize, total: usize) -> bool {
        if stage != "frames" {
            return !self.bars.interrupted();
        }
        self.bars.update(&self.name, done, total);
        let (sum, all) = {
            let mut counts = self.counts.lock().unwrap_or_else(|e| e.into_inner());
            counts[self.file] = (done, total);
            counts.iter().fold((0, 0), |(a, b), (d, t)| (a + d, b + t))
        };
        self.bars.update("frames", sum, all)
    }
}

/// Runs `render`.
pub fn run(mut args: Args, ctx: &Ctx) -> Result<()> {
    args.threads.apply()?;
    args.targets.expand_lottie_globs();
    let styles = check_args(&args.render)?;
    check_svg_frames(&args.targets.inputs)?;
    let layout = args.targets.layout()?;
    handle_interrupts();
    if args.targets.inputs.len() == 1 {
        let (out_dir, gif) = layout.into_iter().next().expect("one input");
        return run_one(&args, ctx, &args.targets.inputs[0], out_dir, gif, styles.as_ref());
    }
    run_batch(&args, ctx, layout, styles.as_ref())
}

fn run_one(
    args: &Args,
    ctx: &Ctx,
    input: &Path,
    out_dir: PathBuf,
    gif: Option<PathBuf>,
    styles: Option<&Styles>,
) -> Result<()> {
    let anim = load_input(input, &args.render)?;
    check_layer_keys(&args.render, styles, &[&anim])?;
    let mut opts = file_options(&anim, input, out_dir, gif, &args.render, styles)?;
    opts.resume = args.resume;
    opts.eval = args.eval;
    opts.keyframes = args.keyframe.iter().map(|v| parse_keyframe(v, anim.frames)).collect::<Result<_>>()?;
    let bars = Bars::new(ctx.quiet);
    let result = render::render(&anim, &opts, &bars);
    bars.clear();
    let summary = match result {
        Ok(s) => s,
        Err(Error::Cancelled) => {
            bail!(anyhow::Error::new(Error::Cancelled).context(format!(
                "interrupted; the finished frames are in '{}' — continue with the same command and --resume",
                args.targets.output.display()
            )))
        }
        Err(e) => return Err(anyhow::Error::new(e).context(format!("could not render '{}'", input.display()))),
    };
    warn_stale_frames(&opts.out_dir, &opts.frames);
    if !ctx.quiet {
        eprintln!("{}", summary_line(&summary));
        for l in &summary.layers {
            eprintln!(
                "  {:02} {:<20} {:<18} {:.1} s",
                l.index,
                l.name,
                l.exemplar.as_deref().unwrap_or("(flat)"),
                l.seconds
            );
        }
        if args.render.keep_layers {
            eprintln!("layers -> {}", opts.out_dir.join("layers").display());
        }
    }
    print_eval(&summary, None);
    Ok(())
}

/// "48 frames in 12.1 s (0.25 s/frame) -> out, out/demo.gif".
fn summary_line(summary: &RenderSummary) -> String {
    let resumed = match (summary.frames, summary.resumed) {
        (0, r) if r > 0 => " (already complete)".to_string(),
        (_, 0) => String::new(),
        (_, r) => format!(" (after {r} resumed)"),
    };
    format!(
        "{}{} in {:.1} s ({:.2} s/frame) -> {}{}",
        fluidymation::seq::plural(summary.frames, "frame"),
        resumed,
        summary.seconds,
        summary.seconds_per_frame(),
        summary.frame_dir.display(),
        summary.gif.as_ref().map(|g| format!(", {}", g.display())).unwrap_or_default()
    )
}

fn print_eval(summary: &RenderSummary, file: Option<&Path>) {
    for l in &summary.layers {
        if let Some(r) = &l.eval {
            let of = file.map(|f| format!("{}: ", f.display())).unwrap_or_default();
            println!("== {}layer {:02} {} ({})", of, l.index, l.name, l.exemplar.as_deref().unwrap_or(""));
            println!("{}", r);
        }
    }
}

fn run_batch(args: &Args, ctx: &Ctx, layout: Vec<(PathBuf, Option<PathBuf>)>, styles: Option<&Styles>) -> Result<()> {
    if !args.keyframe.is_empty() {
        bail!("--keyframe paints frames of one animation: give one input");
    }
    let start = std::time::Instant::now();
    // Load every input; one that fails is reported at the end, the others are rendered.
    let loaded: Vec<Result<Animation>> = args.targets.inputs.iter().map(|i| load_input(i, &args.render)).collect();
    let anims: Vec<&Animation> = loaded.iter().filter_map(|a| a.as_ref().ok()).collect();
    check_layer_keys(&args.render, styles, &anims)?;
    let mut options: Vec<Result<RenderOptions>> = loaded
        .iter()
        .zip(&args.targets.inputs)
        .zip(layout)
        .map(|((anim, input), (out_dir, gif))| {
            let anim = anim.as_ref().map_err(|e| anyhow::anyhow!("{}", one_line(e)))?;
            let mut opts = file_options(anim, input, out_dir, gif, &args.render, styles)?;
            opts.eval = args.eval;
            Ok(opts)
        })
        .collect();
    if args.resume {
        // Per file: continue what was started, skip what is complete, start the rest.
        let mut any = false;
        for opts in options.iter_mut().flatten() {
            opts.resume = opts.out_dir.join(render::STATE_DIR).join("progress.toml").is_file();
            any |= opts.resume;
        }
        if !any {
            bail!(
                "'{}': there is no interrupted render to resume here (none of the {} inputs has one); render \
                 without --resume",
                args.targets.output.display(),
                args.targets.inputs.len()
            );
        }
    }

    let bars = Bars::new(ctx.quiet);
    let counts = Mutex::new(vec![(0, 0); args.targets.inputs.len()]);
    let progress: Vec<FileProgress> = args
        .targets
        .inputs
        .iter()
        .enumerate()
        .map(|(file, input)| FileProgress {
            bars: &bars,
            name: input.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default(),
            file,
            counts: &counts,
        })
        .collect();
    let mut jobs = Vec::new();
    let mut slots = Vec::new();
    for (i, (anim, opts)) in loaded.iter().zip(&options).enumerate() {
        if let (Ok(anim), Ok(opts)) = (anim, opts) {
            slots.push(i);
            jobs.push((anim, opts, &progress[i] as &dyn Progress));
        }
    }
    let rendered = render::render_batch(&jobs, args.parallel_files);
    bars.clear();
    let mut results: Vec<Result<RenderSummary>> = options
        .iter_mut()
        .map(|o| match o {
            Ok(_) => Err(anyhow::anyhow!("not rendered")),
            Err(e) => Err(anyhow::anyhow!("{}", one_line(e))),
        })
        .collect();
    for (slot, r) in slots.into_iter().zip(rendered) {
        results[slot] = r.map_err(anyhow::Error::new);
    }
    for (opts, r) in options.iter().zip(&results) {
        if let (Ok(opts), Ok(_)) = (opts, r) {
            warn_stale_frames(&opts.out_dir, &opts.frames);
        }
    }

    // The summary: one line per file, in the order given.
    let cancelled = results
        .iter()
        .any(|r| r.as_ref().err().is_some_and(|e| matches!(e.downcast_ref::<Error>(), Some(Error::Cancelled))));
    let failed: Vec<&PathBuf> =
        args.targets.inputs.iter().zip(&results).filter(|(_, r)| r.is_err()).map(|(i, _)| i).collect();
    if !ctx.quiet || !failed.is_empty() {
        eprintln!(
            "{} files in {:.1} s: {} rendered, {} failed",
            args.targets.inputs.len(),
            start.elapsed().as_secs_f64(),
            args.targets.inputs.len() - failed.len(),
            failed.len()
        );
        for (input, r) in args.targets.inputs.iter().zip(&results) {
            match r {
                Ok(s) if !ctx.quiet => eprintln!("  ok      {}: {}", input.display(), summary_line(s)),
                Ok(_) => {}
                Err(e) => eprintln!("  FAILED  {}: {}", input.display(), one_line(e)),
            }
        }
    }
    for (input, r) in args.targets.inputs.iter().zip(&results) {
        if let Ok(s) = r {
            print_eval(s, Some(input));
        }
    }
    if cancelled {
        bail!(anyhow::Error::new(Error::Cancelled).context(format!(
            "interrupted; the finished frames are in '{}' — continue with the same command and --resume",
            args.targets.output.display()
        )));
    }
    if !failed.is_empty() {
        let names: Vec<String> = failed.iter().map(|p| format!("'{}'", p.display())).collect();
        bail!("{} of {} files failed: {}", failed.len(), args.targets.inputs.len(), names.join(", "));
    }
    Ok(())
}
