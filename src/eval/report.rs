//! The result of [`super::evaluate`] and its text rendering.

use super::{EvalOptions, Painted};
use serde::{Deserialize, Serialize};
use std::fmt::{self, Write as _};

/// The exemplar's side of an evaluation: what was measured and its own reference values.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExemplarSummary {
    /// The exemplar's name (from its metadata).
    pub name: String,
    /// Frames used (after taking every `step`-th).
    pub frames: usize,
    /// Width after scaling.
    pub width: usize,
    /// Height after scaling.
    pub height: usize,
    /// Frame step used.
    pub step: usize,
    /// Scale used.
    pub scale: f32,
    /// Its mean local contrast (7×7 luma std) over its interiors.
    pub local_contrast: Option<f32>,
    /// Its mean change between consecutive frames in its stationary interiors.
    pub temporal_change: Option<f32>,
    /// Its own motion agreement with its masks' motion (how its paint flows as it spreads).
    pub motion_agreement: Option<f32>,
    /// Its own edge darkening (luma of the interior minus that of the band inside the edge,
    /// mean over its frames).
    #[serde(default)]
    pub edge_darkening: Option<f32>,
    /// Its own incoherent change (flow-compensated change between consecutive frames, mean
    /// over its pairs).
    #[serde(default)]
    pub incoherent_change: Option<f32>,
    /// Interior pixels over all its frames (the palette reference).
    pub interior_pixels: u64,
    /// Exemplar patches indexed for the nearest-neighbour statistic.
    pub patch_pool: u64,
    /// Pixels behind `temporal_change`.
    pub temporal_pixels: u64,
    /// Points behind `motion_agreement`.
    pub motion_points: u64,
}

/// The metrics over the whole sequence (each pooled over all samples of all frames).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// IoU of the painted area with the target masks, `Σ|A∩B| / Σ|A∪B|`; 1 = exact.
    pub coverage_iou: Option<f32>,
    /// The IoU an output painted like the exemplar at every distance from the edge would
    /// reach on these masks (the exemplar's own painted fraction per half-pixel depth,
    /// weighted by the masks' pixels there): below 1 where the exemplar's edge fades into the
    /// paper, the more so the thinner the target. Color detection only (it is the exemplar's
    /// paint that fades, not its alpha).
    #[serde(default)]
    pub coverage_iou_exemplar: Option<f32>,
    /// Mean local contrast (7×7 luma std) of the output interiors.
    pub local_contrast: Option<f32>,
    /// `local_contrast` / the exemplar's at the same depths (distance from the edge, see the
    /// [module documentation](super)): ≈ 1 keeps the exemplar's texture, ≈ 0 is wash-out.
    pub contrast_ratio: Option<f32>,
    /// `local_contrast` / the exemplar's over its whole interior, whatever the depths (the
    /// measure before depth matching; lower than `contrast_ratio` where the output's interior
    /// is deeper than the exemplar's).
    #[serde(default)]
    pub contrast_ratio_whole: Option<f32>,
    /// Per-channel (R, G, B) Wasserstein-1 distance of interior colors, output vs exemplar at
    /// the same depths.
    pub palette_distance: Option<[f32; 3]>,
    /// Mean of the three `palette_distance` channels.
    pub palette_distance_mean: Option<f32>,
    /// The mean palette distance to the exemplar's whole interior, whatever the depths.
    #[serde(default)]
    pub palette_distance_whole: Option<f32>,
    /// Mean RMS distance of sampled output 5×5 patches to their nearest exemplar patches.
    pub patch_nn_distance: Option<f32>,
    /// Mean absolute change between consecutive frames in the stationary interior.
    pub temporal_change: Option<f32>,
    /// `temporal_change` / the exemplar's: ≈ 1 exemplar-like, ≫ 1 flicker, ≈ 0 glued still.
    pub temporal_change_ratio: Option<f32>,
    /// Mean cosine between the paint's flow and the target's motion near moving boundaries.
    pub motion_agreement: Option<f32>,
    /// Edge darkening: mean luma of the interior (> 12 px inside) minus that of the band
    /// (≤ 4 px inside the edge), mean over frames; > 0 when the edge is darker.
    #[serde(default)]
    pub edge_darkening: Option<f32>,
    /// `edge_darkening` / the exemplar's: ≈ 1 has the exemplar's rim, ≈ 0 none, < 0 a pale edge.
    #[serde(default)]
    pub edge_darkening_ratio: Option<f32>,
    /// Incoherent change: mean absolute luma residual between consecutive frames after
    /// compensating their optical flow, mean over pairs.
    #[serde(default)]
    pub incoherent_change: Option<f32>,
    /// `incoherent_change` / the exemplar's: ≈ 1 changes like the exemplar, ≫ 1 boils.
    #[serde(default)]
    pub incoherent_change_ratio: Option<f32>,
    /// `incoherent_change` / the exemplar's at the same depths: what the exemplar's paint
    /// would score with the output's mix of distances from the edge (its own residual per 2-px
    /// depth bin, weighted by the output's residual pixels per bin). The exemplar's paint
    /// changes most near its advancing edge (1.5–2.7× its mean 5–7 px inside, on the bundled
    /// exemplars) and least deep inside, so a thin part scores lower here than in
    /// `incoherent_change_ratio` and a large interior higher.
    #[serde(default)]
    pub incoherent_change_ratio_depth: Option<f32>,
    /// Interior pixels over all frames (behind contrast and palette).
    pub interior_pixels: u64,
    /// Output patches sampled for `patch_nn_distance`.
    pub patch_samples: u64,
    /// Pixels behind `temporal_change`.
    pub temporal_pixels: u64,
    /// Points behind `motion_agreement`.
    pub motion_points: u64,
    /// Frames behind `edge_darkening`.
    #[serde(default)]
    pub rim_frames: u64,
    /// Pixels behind `incoherent_change`.
    #[serde(default)]
    pub incoherent_pixels: u64,
}

/// The metrics of one frame (`None` where the frame has nothing to measure; temporal change
/// and motion compare frame `i` with frame `i − 1`, so frame 1 has neither).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameStats {
    /// 1-based frame number.
    pub frame: usize,
    /// IoU of the painted area with the target mask.
    pub coverage_iou: Option<f32>,
    /// The IoU exemplar-like paint would reach on this frame's mask (see
    /// [`Summary::coverage_iou_exemplar`]).
    #[serde(default)]
    pub coverage_iou_exemplar: Option<f32>,
    /// Mean local contrast of the interior.
    pub local_contrast: Option<f32>,
    /// `local_contrast` / the exemplar's (whole-sequence) local contrast.
    pub contrast_ratio: Option<f32>,
    /// Per-channel Wasserstein distance of this frame's interior colors to the exemplar's.
    pub palette_distance: Option<[f32; 3]>,
    /// Mean nearest-exemplar-patch distance of this frame's samples.
    pub patch_nn_distance: Option<f32>,
    /// Mean change since the previous frame in the stationary interior.
    pub temporal_change: Option<f32>,
    /// `temporal_change` / the exemplar's (whole-sequence) temporal change.
    pub temporal_change_ratio: Option<f32>,
    /// Mean cosine of the flow since the previous frame with the target's motion.
    pub motion_agreement: Option<f32>,
    /// Edge darkening of this frame.
    #[serde(default)]
    pub edge_darkening: Option<f32>,
    /// `edge_darkening` / the exemplar's (mean over its frames).
    #[serde(default)]
    pub edge_darkening_ratio: Option<f32>,
    /// Flow-compensated change since the previous frame.
    #[serde(default)]
    pub incoherent_change: Option<f32>,
    /// `incoherent_change` / the exemplar's (mean over its pairs).
    #[serde(default)]
    pub incoherent_change_ratio: Option<f32>,
    /// `incoherent_change` / the exemplar's at this frame's depths (see
    /// [`Summary::incoherent_change_ratio_depth`]).
    #[serde(default)]
    pub incoherent_change_ratio_depth: Option<f32>,
}

/// Everything [`super::evaluate`] measured.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// Number of output frames.
    pub frames: usize,
    /// Output width.
    pub width: usize,
    /// Output height.
    pub height: usize,
    /// The exemplar and its reference values.
    pub exemplar: ExemplarSummary,
    /// How painted pixels were detected.
    pub painted: Painted,
    /// Whole-sequence values.
    pub summary: Summary,
    /// Per-frame series.
    pub per_frame: Vec<FrameStats>,
    /// The options used.
    pub options: EvalOptions,
}

fn num(v: Option<f32>) -> String {
    match v {
        Some(v) if !v.is_finite() => "–".to_string(),
        Some(v) if v.abs() >= 100.0 => format!("{v:.1}"),
        Some(v) => format!("{v:.4}"),
        None => "–".to_string(),
    }
}

fn hex(c: [f32; 3]) -> String {
    let b = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    format!("#{:02x}{:02x}{:02x}", b(c[0]), b(c[1]), b(c[2]))
}

impl Report {
    /// The per-frame series as a text table, one line per frame.
    pub fn per_frame_table(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{:>5}  {:>7}  {:>8}  {:>8}  {:>8}  {:>8}  {:>8}  {:>8}  {:>8}  {:>8}  {:>8}",
            "frame",
            "IoU",
            "contrast",
            "c.ratio",
            "rim",
            "r.ratio",
            "palette",
            "patch NN",
            "t.ratio",
            "i.ratio",
            "motion"
        );
        for f in &self.per_frame {
            let _ = writeln!(
                s,
                "{:>5}  {:>7}  {:>8}  {:>8}  {:>8}  {:>8}  {:>8}  {:>8}  {:>8}  {:>8}  {:>8}",
                f.frame,
                num(f.coverage_iou),
                num(f.local_contrast),
                num(f.contrast_ratio),
                num(f.edge_darkening),
                num(f.edge_darkening_ratio),
                num(f.palette_distance.map(|p| (p[0] + p[1] + p[2]) / 3.0)),
                num(f.patch_nn_distance),
                num(f.temporal_change_ratio),
                num(f.incoherent_change_ratio),
                num(f.motion_agreement),
            );
        }
        s
    }
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let e = &self.exemplar;
        let s = &self.summary;
        writeln!(
            f,
            "{} frames of {}x{} against exemplar '{}' ({} frames of {}x{}, step {}, scale {})",
            self.frames, self.width, self.height, e.name, e.frames, e.width, e.height, e.step, e.scale
        )?;
        match self.painted {
            Painted::Alpha => writeln!(f, "painted area: alpha >= 0.5")?,
            Painted::Color { background, threshold } => {
                writeln!(f, "painted area: color farther than {} from the background {}", threshold, hex(background))?
            }
        }
        writeln!(f)?;
        let row = |f: &mut fmt::Formatter<'_>, name: &str, out: String, ex: String, r: String, note: &str| {
            writeln!(f, "{name:<38} {out:>9} {ex:>9} {r:>7}   {note}")
        };
        row(f, "metric", "output".into(), "exemplar".into(), "ratio".into(), "reading")?;
        row(
            f,
            "coverage IoU",
            num(s.coverage_iou),
            num(s.coverage_iou_exemplar),
            String::new(),
            "1 = painted area is the target; exemplar: its paint's own at these depths",
        )?;
        // The exemplar's contrast at the output's depths (what the ratio divides by); its whole
        // interior's is in the JSON (`contrast_ratio_whole`).
        let at_depths = match (s.local_contrast, s.contrast_ratio) {
            (Some(c), Some(r)) if r > 0.0 => Some(c / r),
            _ => e.local_contrast,
        };
        row(
            f,
            "local contrast (7x7 luma std)",
            num(s.local_contrast),
            num(at_depths),
            num(s.contrast_ratio),
            "ratio ~1; ~0 is wash-out (exemplar at the same depths)",
        )?;
        let channels =
            s.palette_distance.map(|p| format!(" (R {:.4}, G {:.4}, B {:.4})", p[0], p[1], p[2])).unwrap_or_default();
        row(
            f,
            "edge darkening (interior - rim band)",
            num(s.edge_darkening),
            num(e.edge_darkening),
            num(s.edge_darkening_ratio),
            "ratio ~1; ~0 no rim; <0 pale edge",
        )?;
        row(
            f,
            "palette distance (W1, mean of RGB)",
            num(s.palette_distance_mean),
            String::new(),
            String::new(),
            &format!("0 = exemplar's colors{channels}"),
        )?;
        row(
            f,
            "patch NN distance (RMS, 5x5)",
            num(s.patch_nn_distance),
            String::new(),
            String::new(),
            "0 = made of exemplar patches",
        )?;
        row(
            f,
            "temporal change (stationary interior)",
            num(s.temporal_change),
            num(e.temporal_change),
            num(s.temporal_change_ratio),
            "ratio ~1; >>1 flicker; ~0 glued still",
        )?;
        row(
            f,
            "incoherent change (flow-compensated)",
            num(s.incoherent_change),
            num(e.incoherent_change),
            num(s.incoherent_change_ratio),
            "ratio ~1; >>1 boiling",
        )?;
        row(
            f,
            "  at the output's depths",
            String::new(),
            num(s.incoherent_change.zip(s.incoherent_change_ratio_depth).filter(|&(_, r)| r > 0.0).map(|(v, r)| v / r)),
            num(s.incoherent_change_ratio_depth),
            "the exemplar's change at the same distances from the edge",
        )?;
        row(
            f,
            "motion agreement (mean cosine)",
            num(s.motion_agreement),
            num(e.motion_agreement),
            String::new(),
            "+1 flows with the target, -1 against",
        )?;
        writeln!(f)?;
        write!(
            f,
            "samples: {} interior pixels, {} patches against {} exemplar patches, {} stationary pixels, {} motion points, \
             {} frames with a rim value, {} flow-compensated pixels",
            s.interior_pixels,
            s.patch_samples,
            e.patch_pool,
            s.temporal_pixels,
            s.motion_points,
            s.rim_frames,
            s.incoherent_pixels
        )
    }
}
