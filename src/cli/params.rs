//! Synthesis flags shared by `synth` and `render` (the thesis's parameter names).

use anyhow::{Context, Result, bail};
use fluidymation::synth::{Params, ParamsBuilder};

/// Parses "6,4" into [6, 4].
fn parse_list(name: &str, s: &str) -> Result<Vec<usize>> {
    s.split(',')
        .map(|t| {
            t.trim().parse::<usize>().with_context(|| format!("--{}: '{}' is not a list of counts like 6,4", name, s))
        })
        .collect()
}

/// The engine's parameters as command-line flags. Unset flags keep the defaults (and, for
/// border width, scale and speed, the exemplar's recommendations).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct SynthFlags {
    /// Seed of every random choice (same seed + input = same output).
    #[arg(long, default_value_t = 1, value_parser = parse_seed)]
    pub seed: u64,
    /// Weight of the border channel w_df (w^bound) [default: 5].
    #[arg(long, value_name = "W")]
    pub dist_weight: Option<f32>,
    /// Weight of the motion-extent channels w_ext [default: 0.005].
    #[arg(long, value_name = "W")]
    pub flow_weight: Option<f32>,
    /// Weight of the temporal guide w_prev (w^temp) [default: 4].
    #[arg(long, value_name = "W")]
    pub prev_weight: Option<f32>,
    /// Uniformity weight λ [default: 4].
    #[arg(long, value_name = "L")]
    pub lambda: Option<f32>,
    /// Contrast balance μ: exemplar paint of a contrast that the output uses more than the
    /// exemplar holds it costs μ·λ more per patch; 0 = off, as in the paper [default: 4].
    #[arg(long, value_name = "MU")]
    pub contrast_balance: Option<f32>,
    /// Coherence factor κ: a random PatchMatch candidate must be κ times better than the
    /// current match (1 = plain PatchMatch, the paper; 2 keeps more texture) [default: 2].
    #[arg(long, value_name = "K")]
    pub coherence: Option<f32>,
    /// Seam cost c: each neighbour whose match a match does not continue adds c to its error in
    /// the search, so the field keeps larger pieces (0 = off, the paper) [default: 5].
    #[arg(long, value_name = "C")]
    pub seam_cost: Option<f32>,
    /// Temporal radius r of the occurrence boxes, frames [default: 5].
    #[arg(long, value_name = "R")]
    pub occ_radius: Option<usize>,
    /// Border width b, exemplar pixels [default: the exemplar's recommendation].
    #[arg(long, value_name = "PX")]
    pub border_width: Option<f32>,
    /// σ of the spatial mask blur, pixels (the thesis uses 8) [default: 0].
    #[arg(long, value_name = "PX")]
    pub blur_sigma: Option<f32>,
    /// σ of the temporal distance-field blur, frames [default: 2].
    #[arg(long, value_name = "FRAMES")]
    pub time_blur_sigma: Option<f32>,
    /// PatchMatch iterations per level, coarsest first; the last repeats [default: 6,4].
    #[arg(long, value_name = "LIST")]
    pub patchmatch_iterations: Option<String>,
    /// EM iterations per level, coarsest first; the last repeats [default: 4,2,1].
    #[arg(long, value_name = "LIST")]
    pub opt_iterations: Option<String>,
    /// PatchMatch random-search shrink factor α: the search window shrinks by α at each
    /// draw, in (0, 1) [default: 0.75].
    #[arg(long, value_name = "A")]
    pub patchmatch_alpha: Option<f32>,
    /// Exemplar frame step, 1 to 1000 [default: the exemplar's recommendation].
    #[arg(long, value_name = "N", value_parser = count(1, 1000))]
    pub src_speed: Option<usize>,
    /// Exemplar scale [default: the exemplar's recommendation].
    #[arg(long, value_name = "F")]
    pub src_scale: Option<f32>,
    /// Target scale; the output has the scaled size, in (0.01, 16] [default: 1].
    #[arg(long, value_name = "F", value_parser = factor(0.01, 16.0))]
    pub target_scale: Option<f32>,
    /// Temporal modulation bounds "m_u,m_l" in pixels, as in the thesis [default: 10,2].
    #[arg(long, value_name = "MU,ML")]
    pub prev_modulation_bounds: Option<String>,
    /// σ of the center weighting in voting the output, pixels; 0 = uniform [default: 0.7].
    #[arg(long, value_name = "PX")]
    pub vote_sigma: Option<f32>,
    /// σ of the center weighting of the estimates the search matches against (EM estimate,
    /// the merge's estimate), pixels; ≤ 0.35 = each pixel's own match, 0 = uniform [default: 0.5].
    #[arg(long, value_name = "PX")]
    pub estimate_sigma: Option<f32>,
    /// σ of the center weighting of the temporal guide voted from the previous frame's
    /// field, pixels; ≤ 0.35 = each pixel's own match, 0 = uniform [default: 0.3].
    #[arg(long, value_name = "PX")]
    pub prev_sigma: Option<f32>,
    /// Also optimize the finest pyramid level (slower; the thesis only votes it).
    #[arg(long)]
    pub optimize_finest: bool,
    /// Turn the patches of a shape where it does not move by its outward normal, so the
    /// exemplar's lobes and veins run out to its edge instead of repeating in rows (a large
    /// still shape's middle); its paint then changes more from frame to frame (README,
    /// *A resting shape turned by its normal*).
    #[arg(long)]
    pub resting_normal: bool,
    /// Give the output back the exemplar's fine grain that voting averages away (the default;
    /// the flag is kept so that scripts which give it keep working).
    #[arg(long, conflicts_with = "no_grain")]
    pub keep_grain: bool,
    /// Vote the output as the plain average of the patches, as in the paper: calmer paint on
    /// moving shapes (less grain that changes from frame to frame), less texture.
    #[arg(long)]
    pub no_grain: bool,
    /// Keep σ and b as given for thin layers too (by default they are lowered to fit layers
    /// only a few pixels thick; giving --blur-sigma or --border-width also turns this off).
    #[arg(long)]
    pub no_thin_fit: bool,
    /// Switch one part of the method off, to see what it does (repeatable): direction-rule
    /// (patches unrotated), time-shift (no SHIFTNNF), segments (interior and border patches
    /// mixed), segment-snap (an inherited match that lands just outside its pixel's segment
    /// is dropped, as in the paper, instead of moved the least distance into it), advection
    /// (no residual advection or rim re-anchoring), extent-normalization
    /// (raw target extents, as in the paper), extent-falloff (the extents weigh as much deep
    /// inside a shape as at its edge, as in the paper), carried-rim (in the border band the
    /// merge of the carried and the up-scaled field picks the match with the smaller error, as
    /// in the paper, instead of keeping the carried one unless the other is four times
    /// better), carried-estimate (the merge of the
    /// carried and the up-scaled field judges both against an estimate voted from the
    /// up-scaled field instead of the carried one), finest-uniformity (the finest level's
    /// merge compares patch errors alone, without the uniformity penalty and the contrast
    /// balance: over hundreds of frames the interior settles on the exemplar's calmest
    /// paint), settle (the shifted field is not
    /// settled onto its pieces: each carried match keeps the position its own warp gave it),
    /// receding-hold (receding paint runs its exemplar time backwards deep inside the shape
    /// too, as in the paper, instead of only within the border band), aging (paint steps
    /// through the exemplar's frames only as far as the target's extents ask, as in the paper:
    /// where the shape does not spread, young paint stays young — a still shape's rim keeps
    /// the frame it was first painted with, a receding one runs back to the bloom's wet first
    /// frames — and over a long animation the interior drifts back to the bloom's pale early
    /// frames),
    /// pace (a moving shape's
    /// paint runs through as many exemplar frames per frame as its motion asks, as in the
    /// paper: a fast limb ages its paint several frames at a time and boils), full-carry (a
    /// moving shape's exemplar time steps supply part of its motion, as in the paper: its
    /// paint's texture lags behind the shape and boils), travel-hold (the border paint of a
    /// travelling shape steps through the exemplar's frames like the rest: a swinging limb's
    /// paint changes in place as it swings, and boils), contrast-balance (the
    /// occurrence penalty spreads the use over the exemplar's positions only, as in the paper,
    /// and the search drifts to the exemplar's flattest paint; same as --contrast-balance 0),
    /// grain-phase (the grain of a patch that lands between exemplar pixels keeps only what
    /// the interpolation leaves of it: softer paint on moving shapes), grain-match (the grain
    /// keeps the amplitude the vote left it: carried paint's grain fades as the field is
    /// stretched, a growing shape's interior grows calmer), tone-match (the output
    /// keeps the density of the paint its patches were stitched from: paler than the
    /// exemplar at the same distance from the edge on shapes larger than its paint),
    /// depth-stretch (a shape deeper than the exemplar's paint takes the tones of the
    /// exemplar's calm, pale middle everywhere deeper than the paint reaches, as before
    /// 2026-12-07), repaint-first (the first frame is painted once, from a random field: its rim band is
    /// rough and the paint jumps between frames 1 and 2), turn (a still's patches are never
    /// turned: on a turning shape the carried paint's pieces turn while the patches they
    /// sample do not, and the paint blurs over a long animation).
    #[arg(long, value_name = "PART", value_enum)]
    pub without: Vec<Part>,
}

/// The parts of the method `--without` switches off.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    DirectionRule,
    TimeShift,
    Segments,
    SegmentSnap,
    Advection,
    ExtentNormalization,
    ExtentFalloff,
    CarriedRim,
    CarriedEstimate,
    FinestUniformity,
    Settle,
    RecedingHold,
    Aging,
    Pace,
    FullCarry,
    TravelHold,
    ContrastBalance,
    GrainPhase,
    GrainMatch,
    ToneMatch,
    DepthStretch,
    RepaintFirst,
    Turn,
}

impl SynthFlags {
    /// `--target-scale` (thesis; its parser keeps it in (0.01, 16]): how `synth` scales the
    /// masks it reads (not an engine parameter, so not in [`Params`]; `render` and `quality`
    /// scale with `--scale`).
    pub fn target_scale(&self) -> f32 {
        self.target_scale.unwrap_or(1.0)
    }

    /// The validated parameters.
    pub fn params(&self) -> Result<Params> {
        let fit = !self.no_thin_fit && self.blur_sigma.is_none() && self.border_width.is_none();
        let mut b: ParamsBuilder = Params::builder()
            .seed(self.seed)
            .optimize_finest(self.optimize_finest)
            .resting_normal(self.resting_normal)
            .keep_grain(!self.no_grain)
            .fit_thin_layers(fit);
        if let Some(v) = self.dist_weight {
            b = b.w_df(v);
        }
        if let Some(v) = self.flow_weight {
            b = b.w_ext(v);
        }
        if let Some(v) = self.prev_weight {
            b = b.w_prev(v);
        }
        if let Some(v) = self.vote_sigma {
            b = b.vote_sigma(v);
        }
        if let Some(v) = self.estimate_sigma {
            b = b.estimate_sigma(v);
        }
        if let Some(v) = self.lambda {
            b = b.lambda(v);
        }
        if let Some(v) = self.contrast_balance {
            b = b.contrast_balance(v);
        }
        if let Some(v) = self.prev_sigma {
            b = b.prev_sigma(v);
        }
        if let Some(v) = self.coherence {
            b = b.coherence(v);
        }
        if let Some(v) = self.seam_cost {
            b = b.seam_cost(v);
        }
        if let Some(v) = self.occ_radius {
            b = b.occ_radius(v);
        }
        if let Some(v) = self.border_width {
            b = b.border_width(v);
        }
        if let Some(v) = self.blur_sigma {
            b = b.blur_sigma(v);
        }
        if let Some(v) = self.time_blur_sigma {
            b = b.time_blur_sigma(v);
        }
        if let Some(s) = &self.patchmatch_iterations {
            b = b.pm_iters(parse_list("patchmatch-iterations", s)?);
        }
        if let Some(s) = &self.opt_iterations {
            b = b.opt_iters(parse_list("opt-iterations", s)?);
        }
        if let Some(v) = self.patchmatch_alpha {
            b = b.alpha(v);
        }
        if let Some(v) = self.src_speed {
            b = b.src_speed(v);
        }
        if let Some(v) = self.src_scale {
            b = b.src_scale(v);
        }
        if let Some(s) = &self.prev_modulation_bounds {
            let v: Vec<f32> = s.split(',').filter_map(|t| t.trim().parse().ok()).collect();
            if v.len() != 2 {
                bail!("--prev-modulation-bounds: '{}' must be two numbers m_u,m_l (e.g. 10,2)", s);
            }
            b = b.prev_bounds(v[1], v[0]);
        }
        for part in &self.without {
            b = match part {
                Part::DirectionRule => b.direction_rule(false),
                Part::TimeShift => b.time_shift(false),
                Part::Segments => b.segments(false),
                Part::SegmentSnap => b.segment_snap(false),
                Part::Advection => b.advect(false),
                Part::ExtentNormalization => b.ext_normalize(false),
                Part::ExtentFalloff => b.extent_falloff(false),
                Part::CarriedRim => b.carried_rim(false),
                Part::CarriedEstimate => b.carried_estimate(false),
                Part::FinestUniformity => b.finest_uniformity(false),
                Part::Settle => b.settle(false),
                Part::RecedingHold => b.receding_hold(false),
                Part::Aging => b.aging(false),
                Part::Pace => b.pace(false),
                Part::FullCarry => b.full_carry(false),
                Part::TravelHold => b.travel_hold(false),
                Part::ContrastBalance => b.contrast_balance(0.0),
                Part::GrainPhase => b.grain_phase(false),
                Part::GrainMatch => b.grain_match(false),
                Part::ToneMatch => b.tone_match(false),
                Part::DepthStretch => b.depth_stretch(false),
                Part::RepaintFirst => b.repaint_first(false),
                Part::Turn => b.turn(false),
            };
        }
        Ok(b.build()?)
    }
}

impl SynthFlags {
    /// The flags as command-line arguments that parse back to the same values (numbers are
    /// written in their shortest exact form), for the jobs of a plan.
    pub fn to_args(&self) -> Vec<String> {
        let mut out = vec!["--seed".to_string(), self.seed.to_string()];
        let mut push = |flag: &str, value: Option<String>| {
            if let Some(v) = value {
                out.push(format!("--{flag}"));
                out.push(v);
            }
        };
        push("dist-weight", self.dist_weight.map(|v| v.to_string()));
        push("flow-weight", self.flow_weight.map(|v| v.to_string()));
        push("prev-weight", self.prev_weight.map(|v| v.to_string()));
        push("lambda", self.lambda.map(|v| v.to_string()));
        push("contrast-balance", self.contrast_balance.map(|v| v.to_string()));
        push("coherence", self.coherence.map(|v| v.to_string()));
        push("seam-cost", self.seam_cost.map(|v| v.to_string()));
        push("occ-radius", self.occ_radius.map(|v| v.to_string()));
        push("border-width", self.border_width.map(|v| v.to_string()));
        push("blur-sigma", self.blur_sigma.map(|v| v.to_string()));
        push("time-blur-sigma", self.time_blur_sigma.map(|v| v.to_string()));
        push("patchmatch-iterations", self.patchmatch_iterations.clone());
        push("opt-iterations", self.opt_iterations.clone());
        push("patchmatch-alpha", self.patchmatch_alpha.map(|v| v.to_string()));
        push("src-speed", self.src_speed.map(|v| v.to_string()));
        push("src-scale", self.src_scale.map(|v| v.to_string()));
        push("target-scale", self.target_scale.map(|v| v.to_string()));
        push("prev-modulation-bounds", self.prev_modulation_bounds.clone());
        push("vote-sigma", self.vote_sigma.map(|v| v.to_string()));
        push("estimate-sigma", self.estimate_sigma.map(|v| v.to_string()));
        push("prev-sigma", self.prev_sigma.map(|v| v.to_string()));
        if self.optimize_finest {
            out.push("--optimize-finest".into());
        }
        if self.resting_normal {
            out.push("--resting-normal".into());
        }
        if self.keep_grain {
            out.push("--keep-grain".into());
        }
        if self.no_grain {
            out.push("--no-grain".into());
        }
        if self.no_thin_fit {
            out.push("--no-thin-fit".into());
        }
        for part in &self.without {
            out.push("--without".into());
            out.push(clap::ValueEnum::to_possible_value(part).map(|v| v.get_name().to_string()).unwrap_or_default());
        }
        out
    }
}

/// A value parser for a count option: a whole number from `min` to `max` (`usize::MAX`: no
/// upper bound). Anything else — `0` where 1 is the least, `-1`, `2.5`, a word — is refused by
/// clap as a malformed command line (exit code 2), with the option's name and this range:
/// `invalid value '0' for '--jobs <JOBS>': expected a whole number from 1 to 64`.
pub fn count(min: usize, max: usize) -> impl Fn(&str) -> std::result::Result<usize, String> + Clone + Send + Sync {
    move |v| {
        v.trim().parse::<usize>().ok().filter(|n| (min..=max).contains(n)).ok_or_else(|| {
            if max == usize::MAX {
                format!("expected a whole number of at least {min}")
            } else {
                format!("expected a whole number from {min} to {max}")
            }
        })
    }
}

/// A value parser for a scale factor: a number greater than `min` and at most `max`; anything
/// else is refused by clap like [`count`] (exit code 2, the option and the range named).
pub fn factor(min: f32, max: f32) -> impl Fn(&str) -> std::result::Result<f32, String> + Clone + Send + Sync {
    move |v| {
        v.trim()
            .parse::<f32>()
            .ok()
            .filter(|f| f.is_finite() && *f > min && *f <= max)
            .ok_or_else(|| format!("expected a number in ({min}, {max}] (greater than {min}, at most {max})"))
    }
}

/// Parses a `--seed`: a whole number from 0 to 2⁶⁴ − 1, with a message that says so (the
/// parser's own reads "invalid digit found in string" for `-1`).
pub fn parse_seed(v: &str) -> std::result::Result<u64, String> {
    v.trim().parse().map_err(|_| format!("expected a whole number from 0 to {}", u64::MAX))
}

/// Parses a 1-based inclusive frame range "A..B", "A..", "..B" or "N" into a 0-based range
/// clipped to `0..total`.
pub fn parse_frames(spec: Option<&str>, total: usize) -> Result<std::ops::Range<usize>> {
    let Some(spec) = spec else { return Ok(0..total) };
    let bad = || anyhow::anyhow!("--frames '{}': expected A..B (1-based, inclusive), e.g. 1..24", spec);
    let (a, b) = match spec.split_once("..") {
        Some((a, b)) => (a.trim(), b.trim().trim_start_matches('=').trim()),
        None => (spec.trim(), spec.trim()),
    };
    // A frame number: a negative one is told it counts from 1, one too large to hold is
    // named as such (both are numbers, so "expected A..B" would not say what is wrong).
    let number = |v: &str| -> Result<usize> {
        let digits = |t: &str| !t.is_empty() && t.bytes().all(|c| c.is_ascii_digit());
        match v.parse() {
            Ok(n) => Ok(n),
            Err(_) if v.strip_prefix('-').is_some_and(digits) => {
                bail!("--frames '{}': frames are numbered from 1 (1-based, inclusive), e.g. 1..24", spec)
            }
            Err(_) if digits(v) => bail!("--frames '{}': frame number {} is too large", spec, v),
            Err(_) => Err(bad()),
        }
    };
    let a: usize = if a.is_empty() { 1 } else { number(a)? };
    let b: usize = if b.is_empty() { total.max(a) } else { number(b)? };
    if a == 0 {
        bail!("--frames '{}': frames are numbered from 1 (1-based, inclusive), e.g. 1..24", spec);
    }
    if a > total {
        bail!("--frames '{}': the input has only {} frames", spec, total);
    }
    if b < a {
        bail!("--frames '{}': the first frame must not come after the last (A..B with A ≤ B), e.g. {b}..{a}", spec);
    }
    Ok(a - 1..b.min(total))
}

/// Warns when `--frames` asked for frames past the input's last (`range` is what is used);
/// `input` names the input in the warning ("the input", or a file of a batch).
pub fn warn_if_clipped(spec: Option<&str>, range: &std::ops::Range<usize>, total: usize, input: &str) {
    let end =
        spec.and_then(|f| f.split_once("..")).and_then(|(_, b)| b.trim().trim_start_matches('=').parse::<usize>().ok());
    if end.is_some_and(|end| end > total) {
        log::warn!(
            "--frames '{}': {} has only {} frames; using {}..{}",
            spec.unwrap_or_default(),
            input,
            total,
            range.start + 1,
            range.end
        );
    }
}

/// `--threads`, the same on every command that computes.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct Threads {
    /// Worker threads, 1 to 1024 [default: all cores]. The results do not depend on it
    /// (timings do).
    #[arg(long = "threads", value_name = "N", value_parser = count(1, 1024))]
    pub n: Option<usize>,
}

impl Threads {
    /// Sizes the global thread pool (all cores when not given).
    pub fn apply(&self) -> Result<()> {
        if let Some(n) = self.n {
            rayon::ThreadPoolBuilder::new().num_threads(n).build_global().context("could not start the thread pool")?;
        }
        Ok(())
    }
}

/// `--exemplar-dir`, the same on every command that looks exemplars up by name.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct ExemplarDirs {
    /// Extra folder to look for exemplars in, before FLUIDYMATION_EXEMPLARS, the user's
    /// exemplar folder and the bundled set (repeatable).
    #[arg(long = "exemplar-dir", value_name = "DIR")]
    pub dirs: Vec<std::path::PathBuf>,
}

/// One `--keyframe N=PAINTED.png` value of an animation of `frames` frames: the 0-based frame
/// and the painting's file (which must exist; it is read and checked by whoever uses it).
pub fn parse_keyframe(v: &str, frames: usize) -> anyhow::Result<(usize, std::path::PathBuf)> {
    use anyhow::Context;
    let (n, file) =
        v.split_once('=').with_context(|| format!("--keyframe '{v}': expected N=PAINTED.png (N the 1-based frame)"))?;
    let n: usize = n
        .trim()
        .parse()
        .ok()
        .filter(|n| (1..=frames).contains(n))
        .with_context(|| format!("--keyframe '{v}': the frame must be a number from 1 to {frames}"))?;
    if !std::path::Path::new(file).is_file() {
        anyhow::bail!("--keyframe '{v}': no file '{file}'");
    }
    Ok((n - 1, std::path::PathBuf::from(file)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_ranges() {
        assert_eq!(parse_frames(Some("2..4"), 10).unwrap(), 1..4);
        assert_eq!(parse_frames(Some("3"), 10).unwrap(), 2..3);
        assert_eq!(parse_frames(Some("5.."), 10).unwrap(), 4..10);
        assert_eq!(parse_frames(Some("..100"), 10).unwrap(), 0..10);
        assert!(parse_frames(Some("0..3"), 10).is_err());
        assert!(parse_frames(Some("11..12"), 10).is_err());
        assert_eq!(parse_frames(Some("2..=4"), 10).unwrap(), 1..4);
        assert!(parse_frames(Some("x"), 10).is_err());
        assert!(parse_frames(Some("9..3"), 10).is_err());
        assert!(parse_frames(Some("x"), 10).is_err());
    }

    #[test]
    fn flags_survive_the_round_trip_through_arguments() {
        use clap::Parser;
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            flags: SynthFlags,
        }
        let flags = SynthFlags {
            seed: 42,
            dist_weight: Some(0.1 + 0.2),
            lambda: Some(1.0 / 3.0),
            occ_radius: Some(3),
            patchmatch_iterations: Some("6,4".into()),
            patchmatch_alpha: Some(0.6),
            prev_modulation_bounds: Some("10,2".into()),
            vote_sigma: Some(0.0),
            estimate_sigma: Some(0.5),
            prev_sigma: Some(0.25),
            contrast_balance: Some(2.5),
            optimize_finest: true,
            resting_normal: true,
            keep_grain: true,
            without: <Part as clap::ValueEnum>::value_variants().to_vec(),
            ..Default::default()
        };
        let args = flags.to_args();
        let back = Cli::try_parse_from(std::iter::once("x".to_string()).chain(args.clone())).unwrap().flags;
        assert_eq!(back.to_args(), args);
        let p = back.params().unwrap();
        assert_eq!(p, flags.params().unwrap());
        // Every part named by `--without` is switched off.
        let all_on = SynthFlags { without: Vec::new(), ..flags }.params().unwrap().to_builder();
        let off = all_on.direction_rule(false).time_shift(false).segments(false).segment_snap(false).advect(false);
        let off = off.ext_normalize(false).extent_falloff(false).carried_rim(false).carried_estimate(false);
        let off = off.finest_uniformity(false);
        let off =
            off.settle(false).receding_hold(false).aging(false).pace(false).full_carry(false).contrast_balance(0.0);
        let off = off.travel_hold(false).grain_phase(false).grain_match(false);
        let off = off.tone_match(false).depth_stretch(false).repaint_first(false).turn(false).build().unwrap();
        assert_eq!(p, off);
    }

    #[test]
    fn thesis_order_of_bounds() {
        let f = SynthFlags { prev_modulation_bounds: Some("10,2".into()), ..Default::default() };
        assert_eq!(f.params().unwrap().prev_bounds(), (2.0, 10.0));
        let f = SynthFlags { patchmatch_iterations: Some("6,x".into()), ..Default::default() };
        assert!(f.params().is_err());
        let f = SynthFlags { patchmatch_alpha: Some(0.6), ..Default::default() };
        let want = SynthFlags::default().params().unwrap().to_builder().alpha(0.6).build().unwrap();
        assert_eq!(f.params().unwrap(), want);
        let f = SynthFlags { patchmatch_alpha: Some(1.0), ..Default::default() };
        assert!(f.params().unwrap_err().to_string().contains("patchmatch-alpha"));
    }
}
