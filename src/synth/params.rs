//! Synthesis parameters as a validated builder.
//!
//! Where the paper (Table 1) and the thesis (§4.5, CLI table) disagree, each setter says which
//! one the default follows and why.

use crate::error::{Error, Result};
use crate::guide::GuideParams;

/// Patch size n (fixed at compile time, as in the thesis §4.4.1: 5 × 5).
pub const PATCH: usize = 5;
/// ⌊n/2⌋.
pub const HALF: usize = PATCH / 2;

/// All tunable parameters of the synthesis. Build with [`Params::builder`].
#[derive(Clone, Debug, PartialEq)]
pub struct Params {
    pub(crate) border_width: Option<f32>,
    pub(crate) src_scale: Option<f32>,
    pub(crate) src_speed: Option<usize>,
    pub(crate) weights: Weights,
    pub(crate) schedule: Schedule,
    pub(crate) parts: Parts,
    pub(crate) seed: u64,
    pub(crate) guide: GuideParams,
    pub(crate) fit_thin: bool,
}

/// The weights of the patch error and of the search (Table 1 and the thesis; each has its
/// setter on [`ParamsBuilder`], where its default is explained).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Weights {
    pub w_df: f32,
    pub w_ext: f32,
    pub w_prev: f32,
    pub w_color: f32,
    pub lambda: f32,
    pub coherence: f32,
    pub contrast_balance: f32,
    pub seam_cost: f32,
}

impl Default for Weights {
    fn default() -> Weights {
        Weights {
            w_df: 5.0,
            w_ext: 0.005,
            w_prev: 4.0,
            w_color: 1.0,
            lambda: 4.0,
            coherence: 2.0,
            contrast_balance: 4.0,
            seam_cost: 5.0,
        }
    }
}

/// The schedule of the search and of the voting: iterations per level, search radius decay,
/// the occurrence window, the temporal bounds and the vote kernels (setters on [`ParamsBuilder`]).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Schedule {
    pub vote_sigma: f32,
    pub estimate_sigma: f32,
    pub prev_sigma: f32,
    pub occ_radius: usize,
    pub prev_bounds: (f32, f32),
    pub alpha: f32,
    pub pm_iters: Vec<usize>,
    pub opt_iters: Vec<usize>,
    pub optimize_finest: bool,
    pub levels: Option<usize>,
    /// At most this many levels, whatever the frame size ([`Params::fit_to_thickness`]).
    pub max_levels: Option<usize>,
}

impl Default for Schedule {
    fn default() -> Schedule {
        Schedule {
            vote_sigma: 0.7,
            estimate_sigma: 0.5,
            prev_sigma: 0.3,
            occ_radius: 5,
            prev_bounds: (2.0, 10.0),
            alpha: 0.75,
            pm_iters: vec![6, 4],
            opt_iters: vec![4, 2, 1],
            optimize_finest: false,
            levels: None,
            max_levels: None,
        }
    }
}

/// The parts of the method that can be switched off, to see what each does (ablations), and
/// the engine's departures from the paper; every one is on by default. Each has its setter on
/// [`ParamsBuilder`], where it is documented.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Parts {
    pub direction_rule: bool,
    pub time_shift: bool,
    pub advect: bool,
    pub segments: bool,
    pub segment_snap: bool,
    pub ext_clamp: bool,
    pub ext_normalize: bool,
    pub extent_falloff: bool,
    pub carried_rim: bool,
    pub carried_estimate: bool,
    pub finest_uniformity: bool,
    pub settle: bool,
    pub receding_hold: bool,
    pub aging: bool,
    pub pace: bool,
    pub full_carry: bool,
    pub travel_hold: bool,
    pub keep_grain: bool,
    pub grain_phase: bool,
    pub grain_match: bool,
    pub tone_match: bool,
    pub depth_stretch: bool,
    pub resting_normal: bool,
    pub repaint_first: bool,
    pub turn: bool,
}

impl Default for Parts {
    fn default() -> Parts {
        Parts {
            direction_rule: true,
            time_shift: true,
            advect: true,
            segments: true,
            segment_snap: true,
            ext_clamp: true,
            ext_normalize: true,
            extent_falloff: true,
            carried_rim: true,
            carried_estimate: true,
            finest_uniformity: true,
            settle: true,
            receding_hold: true,
            aging: true,
            pace: true,
            full_carry: true,
            travel_hold: true,
            keep_grain: true,
            grain_phase: true,
            grain_match: true,
            tone_match: true,
            depth_stretch: true,
            resting_normal: false,
            repaint_first: true,
            turn: true,
        }
    }
}

impl Default for Params {
    fn default() -> Self {
        Params {
            border_width: None,
            src_scale: None,
            src_speed: None,
            weights: Weights::default(),
            schedule: Schedule::default(),
            parts: Parts::default(),
            seed: 1,
            guide: GuideParams::default(),
            fit_thin: true,
        }
    }
}

impl Params {
    /// A builder starting from the defaults.
    pub fn builder() -> ParamsBuilder {
        ParamsBuilder { p: Params::default() }
    }

    /// A builder starting from these parameters.
    pub fn to_builder(&self) -> ParamsBuilder {
        ParamsBuilder { p: self.clone() }
    }

    /// Border width b in pixels, when set explicitly (else the exemplar's recommendation).
    pub fn border_width(&self) -> Option<f32> {
        self.border_width
    }
    /// Weight of the border channel w_df (w^bound).
    pub fn w_df(&self) -> f32 {
        self.weights.w_df
    }
    /// Weight of the motion-extent channels w_ext.
    pub fn w_ext(&self) -> f32 {
        self.weights.w_ext
    }
    /// Weight of the temporal guide w_prev (w^temp).
    pub fn w_prev(&self) -> f32 {
        self.weights.w_prev
    }
    /// Uniformity weight λ (w^uni).
    pub fn lambda(&self) -> f32 {
        self.weights.lambda
    }
    /// Coherence factor κ of the random search (a random candidate must be κ× better).
    pub fn coherence(&self) -> f32 {
        self.weights.coherence
    }
    /// Seam cost: what each neighbour whose match a match does not continue adds to its error.
    pub fn seam_cost(&self) -> f32 {
        self.weights.seam_cost
    }
    /// Temporal radius r of the occurrence boxes.
    pub fn occ_radius(&self) -> usize {
        self.schedule.occ_radius
    }
    /// Bounds (m_l, m_u) of the temporal modulation, pixels.
    pub fn prev_bounds(&self) -> (f32, f32) {
        self.schedule.prev_bounds
    }
    /// Whether the patches of an exemplar of `frames` frames turn with the shape: a still's,
    /// with [`ParamsBuilder::turn`] on.
    pub(crate) fn turns(&self, frames: usize) -> bool {
        self.parts.turn && frames == 1
    }
    /// The seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }
    /// Whether σ and b are lowered for layers thinner than they suit ([`Params::fit_to_thickness`]).
    pub fn fit_thin(&self) -> bool {
        self.fit_thin
    }

    /// The exemplar's recommended border width at the exemplar scale in use (`--src-scale`, else
    /// its own), pixels: what b is when [`Params::border_width`] is not set.
    pub fn exemplar_border_width(&self, ex: &crate::exemplar::Exemplar) -> f32 {
        ex.meta.border_width * self.src_scale.unwrap_or(ex.meta.scale)
    }

    /// These parameters fitted to a target whose parts are `thickness` pixels thick (the
    /// inscribed radius, see [`mask_thickness`](super::mask_thickness)), for an exemplar whose
    /// border width is `exemplar_border` pixels (at the exemplar's scale in use).
    ///
    /// The thesis's σ = 8 and b ≈ 10–30 px suit shapes tens of pixels thick (the `horse`, 1000 ×
    /// 800). A part only ~15 px wide is closed up and merged with its neighbours by that blur, so
    /// thin limbs, scarves and strokes all but vanish: here σ ≤ thickness / 2.5. And b is
    /// lowered to the part's thickness (not below 4 px), so the border channel grades the
    /// whole part, edge to middle, as it grades the exemplar's paint over the same depths;
    /// thick targets are unchanged. A part thinner than 1.5 b also gets no more pyramid
    /// levels than keep it one patch across ([`Params::max_levels`]). Off when
    /// [`ParamsBuilder::fit_thin_layers`] is false.
    ///
    /// Until the sixth session of 2026-12-06 b was lowered to thickness / 1.5, to give the part
    /// an interior of its own. But the interior segment matches any exemplar pixel deeper than
    /// b alike, and most of them lie far inside the bloom: the middle of the quality suite's
    /// limb (14 px across, 6.5 px thick, b = 4 px then, 6.5 now) took its paint from a median
    /// 10–25 px deep in green-wash (`synth --debug`, seed 1, frames 1–24), where the paint's
    /// pigment density is 0.25–0.37, while the exemplar's at the limb's own depths, 4–6 px, is
    /// 0.77 — so pale that the tone match, bounded to 2×, could not bring it back, and calm
    /// where the exemplar's paint there is blotchy. Graded to its middle, the limb takes the
    /// exemplar's paint at its own depths: on that limb (24 frames, seeds 1–6, the four video
    /// exemplars whose limbs boiled) the palette distance falls 0.047 → 0.031 and the runs
    /// meeting the palette floor 3 → 10 of 24; incoherent change 1.24 → 1.33 (blue-bloom 1.20
    /// → 1.16, ink-rims 1.39 → 1.14, green-wash 1.05 → 1.28, yellow-granules 1.33 → 1.73: its
    /// granules are fine and change more where they are carried), runs meeting that floor
    /// 9 → 11.
    pub fn fit_to_thickness(&self, thickness: f32, exemplar_border: f32) -> Params {
        let mut p = self.clone();
        if !(self.fit_thin && thickness.is_finite() && thickness > 0.0) {
            return p;
        }
        // Rounded to half pixels, so layers of similar thickness share one prepared exemplar.
        let half = |v: f32| ((v * 2.0).floor() / 2.0).max(0.5);
        let sigma = half(thickness / 2.5);
        if sigma < p.guide.blur_sigma {
            p.guide.blur_sigma = sigma;
        }
        // Not below 4 px: the rims of paint are ~2–4 px wide, and a border band narrower than
        // the rim would count rim pixels as interior (darker interiors).
        let b = half(thickness).max(4.0);
        let current = p.border_width.unwrap_or(exemplar_border);
        if b < current {
            p.border_width = Some(b);
        }
        if half(thickness / 1.5).max(4.0) < current {
            // A part this thin also loses the pyramid levels too coarse to hold it.
            p.schedule.max_levels = Some(levels_for_thickness(thickness));
        }
        p
    }

    /// The most pyramid levels a thin target is synthesized with ([`Params::fit_to_thickness`]);
    /// `None` = the paper's rule from the frame size alone.
    pub fn max_levels(&self) -> Option<usize> {
        self.schedule.max_levels
    }

    /// Exemplar scale, when set explicitly (else the exemplar's recommendation).
    pub fn src_scale(&self) -> Option<f32> {
        self.src_scale
    }
    /// Exemplar speed (frame step), when set explicitly (else the exemplar's recommendation).
    pub fn src_speed(&self) -> Option<usize> {
        self.src_speed
    }
    /// Guide computation parameters.
    pub fn guide(&self) -> &GuideParams {
        &self.guide
    }

    /// PatchMatch iterations at pyramid level `l` counted from the coarsest (0 = coarsest).
    pub(crate) fn pm_iters_at(&self, from_coarsest: usize) -> usize {
        *self.schedule.pm_iters.get(from_coarsest).or(self.schedule.pm_iters.last()).unwrap_or(&4)
    }

    /// EM (optimize) iterations at pyramid level `l` counted from the coarsest.
    pub(crate) fn opt_iters_at(&self, from_coarsest: usize) -> usize {
        *self.schedule.opt_iters.get(from_coarsest).or(self.schedule.opt_iters.last()).unwrap_or(&1)
    }
}

/// Builds [`Params`]; [`ParamsBuilder::build`] validates every value.
#[derive(Clone, Debug)]
pub struct ParamsBuilder {
    p: Params,
}

impl ParamsBuilder {
    /// Border width b (thesis `--border-width`), pixels of the (scaled) exemplar: the band along
    /// the mask edge where edge effects live; `I^df = min(I^dist / b, 1)`; patches only match
    /// within the same segment (border `I^df < 1` or interior `I^df = 1`).
    /// Default: the exemplar's recommendation from `exemplar.toml` (thesis default 10).
    pub fn border_width(mut self, b: f32) -> Self {
        self.p.border_width = Some(b);
        self
    }

    /// Weight w_df of the border channel (thesis `--dist-weight`, paper w^bound).
    /// Default: 5 (thesis; the paper's 4 is with b = 30 px).
    pub fn w_df(mut self, w: f32) -> Self {
        self.p.weights.w_df = w;
        self
    }

    /// Weight w_ext of the motion-extent channels ext+ and ext− (thesis `--flow-weight`), per
    /// squared pixel of extent difference. Colors are measured in units of the exemplar's own
    /// texture variance (a random pairing of texture pixels costs ≈ 2), so with 0.03 an extent
    /// mismatch of 12 px costs as much as unrelated texture.
    /// Default: 0.005 (our calibration; the thesis's 0.1 and the paper's 0.25 are relative to
    /// colors on an unknown scale — with our normalized colors they let the extents override
    /// the texture: on a still target the temporal-change ratio was 2.2 with 0.1, and the
    /// contrast ratio of moving targets 0.70/0.61 with 0.03 against 0.84/0.74 with 0.015).
    /// Since the target's extents are brought to the exemplar's scale
    /// ([`ParamsBuilder::ext_normalize`]) they match more closely and need less weight: 0.005
    /// against 0.015 raised edge darkening on the quality suite's moving targets (blue-bloom
    /// translating 0.70 → 0.81, yellow-granules growing 0.54 → 0.61) at equal contrast.
    /// The term applies only where no paint is carried from the previous frame (the first
    /// frame, newly covered pixels; see `synth::patch`): carried paint keeps the age it was
    /// given, and the time shift advances it.
    pub fn w_ext(mut self, w: f32) -> Self {
        self.p.weights.w_ext = w;
        self
    }

    /// Weight w_prev of the temporal guide (thesis `--prev-weight`, paper w^temp).
    /// Default: 4 (paper Table 1; the thesis's 1 measured a temporal-change ratio of 1.4–1.5 on
    /// a still target against 0.8–0.9 with 4).
    pub fn w_prev(mut self, w: f32) -> Self {
        self.p.weights.w_prev = w;
        self
    }

    /// Weight of the color term D^tex; only for ablations (0 disables it). Default: 1.
    pub fn w_color(mut self, w: f32) -> Self {
        self.p.weights.w_color = w;
        self
    }

    /// σ (pixels) of the center weighting in voting the output (the search's estimates use
    /// [`Self::estimate_sigma`]): each overlapping patch votes with weight
    /// `exp(−|o|²/2σ²)` of the offset o from its center; 0 = uniform (Kwatra et al. 2005).
    /// Default: 0.7 (keeps the fine grain of watercolor that uniform averaging washes out:
    /// contrast ratio 0.84 vs 0.62 on the growing test target, 0.73 vs 0.54 on the sliding one;
    /// smaller σ approaches copying patch centers and starts to flicker).
    pub fn vote_sigma(mut self, s: f32) -> Self {
        self.p.schedule.vote_sigma = s;
        self
    }

    /// σ (pixels) of the center weighting of the estimates the search matches against: the
    /// EM estimate `T^rgb` of every level and the estimate MERGENNF compares with (the
    /// temporal guide has its own, [`Self::prev_sigma`]). Same weights as [`Self::vote_sigma`]:
    /// with σ = 0.5 a pixel's own match votes with weight 1, its four edge neighbours' with
    /// 0.14 (the diagonals fall below the 2 % cut-off); with σ ≤ 0.35 only the own match votes.
    ///
    /// Not in the paper, whose estimate is the plain average of the overlapping patches
    /// (Kwatra et al. 2005). That average is a blur, and a flat, pale exemplar patch fits a
    /// blur better than texture does: the search drifts to the exemplar's flattest paint, and
    /// on long animations the paint pales and loses its rim. On the quality suite
    /// (docs/quality.md), 0.5 instead of 0.7 raised contrast on 23 of 25 moving runs (mean 0.669 →
    /// 0.694) and lowered incoherent change on 24 (0.798 → 0.753); on the long target
    /// green-wash's lowest window keeps 0.60 of the first window's contrast instead of 0.52.
    /// Lower is sharper still but lets a mistake hold itself in place (the estimate is then
    /// the field's own mosaic): at 0.35 the identity of green-wash fell to 26.6 dB. The output
    /// is voted with [`Self::vote_sigma`], and the first frame uses it here too: it starts
    /// from a random field, whose own mosaic would hold the search in place (at 0.35 the
    /// identity of ink-rims fell to 7 dB on its first frame). Default: 0.5.
    pub fn estimate_sigma(mut self, s: f32) -> Self {
        self.p.schedule.estimate_sigma = s;
        self
    }

    /// σ (pixels) of the center weighting of the temporal guide `T^prev`, voted from the
    /// shifted field (same weights as [`Self::vote_sigma`]; ≤ 0.35: each pixel's own match).
    ///
    /// Not in the paper, which votes `T^prev` like any estimate (a plain average). The
    /// temporal term judges every candidate against it, and a blurred `T^prev` is fitted
    /// better by a flat, pale exemplar patch than by the carried texture it was voted from:
    /// the coarse levels then replace carried paint with flatter paint every frame. Voted
    /// from each pixel's own carried match, `T^prev` is the carried paint itself. On the
    /// quality suite (24 frames, seed 1, with the other defaults of the time) 0.3 instead of
    /// 0.5 raised contrast on all 30 runs (mean 0.85 → 0.86) with the incoherent change
    /// unchanged (mean 0.82); it also made the contrast balance ([`Self::contrast_balance`])
    /// cost less coherence (incoherent change 0.86 → 0.85 with it). Unlike the EM estimate it
    /// cannot hold a mistake in place: it guides the search towards the previous frame's
    /// paint, which is what it is for. Default: 0.3.
    pub fn prev_sigma(mut self, s: f32) -> Self {
        self.p.schedule.prev_sigma = s;
        self
    }

    /// Contrast balance μ of the occurrence penalty (not in the papers): every exemplar voxel
    /// of a contrast bin that the field uses more than the exemplar holds it pays
    /// `μ·λ·(B·u_b − 1)` per patch (u_b the field's share of bin b, B = 8 bins of equal
    /// share of each exemplar frame's centers, by the luma deviation over the patch window).
    ///
    /// Ω* spreads the use over the exemplar's *positions*; it cannot stop the search from
    /// preferring its flattest paint, because the exemplar has plenty of unused flat
    /// positions. It does prefer it: EM's estimate is a vote, a blur where the field is not
    /// coherent, and flat patches fit a blur best. Measured on yellow-granules (translating
    /// ellipse, 24 frames, interior pixels): the flattest fifth of the exemplar's paint gave
    /// 32 % of the output's matches on the first frame and 54 % on the last, the most textured
    /// fifth 7 % and 4 %; the output's local contrast followed the matches' exactly (0.041 →
    /// 0.036 against the exemplar's 0.050), and the paint paled (mean luma 0.775 → 0.790
    /// against 0.756). With the balance: 27 % → 41 % and 12 % → 8 %, contrast 0.044 → 0.042.
    /// A balance over contrast bins is a histogram constraint on the feature that fades (Kopf
    /// et al. 2007 match histograms in the vote; here it is in the search, so the choice of
    /// patches changes, not their colors). Per frame, so it does not favour late
    /// frames over early ones. On the quality suite (24 frames, 512², with
    /// [`Self::prev_sigma`]): contrast ≥ 0.85 of the exemplar's on 21 of 30 runs instead of 17
    /// (seed 2: 22 instead of 14), mean 0.85 → 0.90, palette mean 0.035 → 0.029, at the cost of
    /// some coherence (incoherent change of the moving runs 0.82 → 0.88); μ = 2 and 8 kept less
    /// of the rim. docs/quality.md has the whole table. 0 switches it off.
    /// Default: 4.
    pub fn contrast_balance(mut self, mu: f32) -> Self {
        self.p.weights.contrast_balance = mu;
        self
    }

    /// Uniformity weight λ (thesis `--lambda`, paper w^uni) of Ω(p') = Ω*(p')/(n²ω*).
    /// Default: 4 (the thesis uses 2, the paper 1). With ω* counted per frame and segment
    /// (what a one-to-one use of the frames the occurrence box spans gives), λ = 4 keeps the
    /// identity exact; the ablation `--lambda 0` changes the quality suite's moving targets
    /// little (edge darkening 0.50–0.86 against 0.57–0.86, incoherent change 0.98–1.13
    /// against 0.94–1.04).
    pub fn lambda(mut self, l: f32) -> Self {
        self.p.weights.lambda = l;
        self
    }

    /// Temporal radius r of the n × n × (2r+1) occurrence boxes (thesis `--occ-radius`).
    /// Default: 5 (paper Table 1; the thesis's 10 covers most of a 20–30 frame exemplar, which
    /// makes the penalty nearly frame-blind).
    pub fn occ_radius(mut self, r: usize) -> Self {
        self.p.schedule.occ_radius = r;
        self
    }

    /// Bounds (m_l, m_u) in pixels of the temporal modulation m(q): full temporal weight where
    /// the edge distances of target and source differ by at most m_l, none beyond m_u (thesis
    /// `--prev-modulation-bounds 10,2`, given there as (m_u, m_l)). Distances are compared after
    /// clamping both to b, as the thesis compares `I^df`. Default: (2, 10).
    pub fn prev_bounds(mut self, m_l: f32, m_u: f32) -> Self {
        self.p.schedule.prev_bounds = (m_l, m_u);
        self
    }

    /// Coherence factor κ ≥ 1 of the random search: a randomly drawn candidate replaces the
    /// current match only when its error is below 1/κ of the current one; propagated
    /// candidates (a neighbour's match shifted by one pixel) compete at face value.
    ///
    /// Not in the paper. The EM objective prefers smooth exemplar patches — a flat patch is the
    /// cheapest compromise with a blurred target estimate — and the field falls apart into
    /// pieces of one or two pixels whose vote is a blur. Favouring coherent copies keeps larger
    /// pieces of real texture: on the quality suite (every bundled exemplar; still, growing,
    /// shrinking, translating, rotating and limb targets, 24 frames at 512²) κ = 2 raised the
    /// contrast ratio on 29 of 30 runs, by 0.02–0.14 (0.36–0.80 → 0.38–0.85), at a price in
    /// coherence (incoherent change +0.0–0.1, the limbs up to +0.3). The first frame is
    /// searched with κ = 1 whatever this says: it starts from a random field, and κ would keep
    /// random matches against the exact ones (the identity of blue-bloom fell to 18.5 dB
    /// median with κ = 2 on every frame; it is
    /// exact again with a plain first frame).
    ///
    /// The same κ decides at the vote-only finest level between the carried (shifted) match and
    /// the up-scaled one (MERGENNF): the up-scaled match replaces carried paint only when its
    /// error is below 1/κ of the carried one's (see `merge` in the engine).
    ///
    /// Default: 2; 1 = plain PatchMatch and the paper's merge.
    pub fn coherence(mut self, k: f32) -> Self {
        self.p.weights.coherence = k;
        self
    }

    /// Seam cost c ≥ 0: in the search, a match pays c for each of its four neighbours whose
    /// match it does not continue (another exemplar frame, or a source point more than ½ px
    /// from the neighbour's moved one rotated step `M·e` on), on top of its patch error — a
    /// smoothness term over the field, as graph-cut texture synthesis charges its seams. The
    /// field keeps the patch errors alone; only the search's comparisons see the cost.
    ///
    /// Not in the paper. On a shape larger than the exemplar's paint the color term's optimum is
    /// a field in pieces of one or two pixels, whatever the other weights: at the half-size
    /// level of green-wash's still 512² ellipse 0.56 of the neighbouring matches continue each
    /// other (0.99–1.00 on the exemplar's own masks), and each sweep lowers error and coherence
    /// together. Up-scaled, every piece becomes a 2 × 2 block of the vote-only finest level, and
    /// the paint shows a stipple of period 2 px — a darker pixel per block, power at that
    /// period 5–9 times the mean where the exemplar's is at most 3.7 — over a mush without the
    /// exemplar's mid-sized lobes (the 4–16 px bands 0.66–0.92 of the exemplar's contrast).
    /// With c = 5 the half-size field is 0.75 coherent, the stipple is gone (green-wash still:
    /// period-2 power 8.2, 5.2, 8.9 → 0.5, 0.6, 5.5 along x, y and the diagonal, the exemplar's
    /// 0.5, 0.8, 3.7). c = 20 (0.85 coherent) copies pieces so large that they repeat visibly
    /// around a still shape's rim. In units of the color term (a random pairing of pixels costs
    /// about 2 per pixel, 50 per 5 × 5 patch).
    ///
    /// Default: 5; 0 = off, as in the paper.
    pub fn seam_cost(mut self, c: f32) -> Self {
        self.p.weights.seam_cost = c;
        self
    }

    /// PatchMatch random-search shrink factor α (thesis `--patchmatch-alpha`). Default: 0.75.
    pub fn alpha(mut self, a: f32) -> Self {
        self.p.schedule.alpha = a;
        self
    }

    /// PatchMatch iterations per level, coarsest first; the last repeats
    /// (thesis `--patchmatch-iterations`). Default: [6, 4] (thesis §4.4.3).
    pub fn pm_iters(mut self, v: Vec<usize>) -> Self {
        self.p.schedule.pm_iters = v;
        self
    }

    /// EM iterations per level, coarsest first; the last repeats (thesis `--opt-iterations`).
    /// Default: [4, 2, 1] (thesis §4.4.3 table).
    pub fn opt_iters(mut self, v: Vec<usize>) -> Self {
        self.p.schedule.opt_iters = v;
        self
    }

    /// Also optimize the finest pyramid level instead of only voting the up-scaled field
    /// (thesis §4.4.3 skips it). Default: false.
    pub fn optimize_finest(mut self, on: bool) -> Self {
        self.p.schedule.optimize_finest = on;
        self
    }

    /// Number of pyramid levels. Default: ⌊log2(d_min / n)⌋ (paper §3.6).
    pub fn levels(mut self, l: usize) -> Self {
        self.p.schedule.levels = Some(l);
        self
    }

    /// Exemplar scale (thesis `--src-scale`). Default: the exemplar's recommendation (1).
    pub fn src_scale(mut self, s: f32) -> Self {
        self.p.src_scale = Some(s);
        self
    }

    /// Exemplar speed: step between used exemplar frames (thesis `--src-speed`).
    /// Default: the exemplar's recommendation (1).
    pub fn src_speed(mut self, s: usize) -> Self {
        self.p.src_speed = Some(s);
        self
    }

    /// The flow-alignment rule for θ (paper §3.2, thesis §4.3): rotations that align source
    /// and target flow. Off = θ = 0 everywhere (the "no direction term" ablation).
    /// Default: on.
    pub fn direction_rule(mut self, on: bool) -> Self {
        self.p.parts.direction_rule = on;
        self
    }

    /// SHIFTNNF (paper §3.4): move the previous frame's matches along the exemplar's time axis
    /// by the Δi that matches the target's motion. Off = Δi = 0 (the "no time shift" ablation:
    /// the previous frame's matches are reused as they are). Default: on.
    pub fn time_shift(mut self, on: bool) -> Self {
        self.p.parts.time_shift = on;
        self
    }

    /// Residual advection in SHIFTNNF: the part of the target's motion over one frame that
    /// the exemplar's own evolution (the time shift Δi) does not supply — because the target
    /// moves faster than the paint, or the exemplar has run out of frames — is carried by
    /// warping the field along the target flow (a pixel takes the match of the pixel that far
    /// upstream), and matches in the border band are re-anchored to the target's distance from
    /// the edge. Off = the paper's SHIFTNNF alone. Default: on.
    pub fn advect(mut self, on: bool) -> Self {
        self.p.parts.advect = on;
        self
    }

    /// Settle the shifted field (SHIFTNNF, module `shift`, `settle`): after the time shift and
    /// the advection, each carried match's position becomes the median of what its 3 × 3
    /// neighbours of the same piece of the field (same exemplar frame, within 1.5 px) predict
    /// for it, twice. Every match is warped on its own, so neighbours that continued each other
    /// drift apart by fractions of a pixel every frame; over a long animation the field comes
    /// apart into slivers and the vote averages the paint flat (green-wash on the 300-frame
    /// target: 64 % of the interior's neighbours continued each other within ½ px at frame 1,
    /// 21 % at frame 70). Not in the paper, whose field is not advected. Off = the warped field
    /// as it is. Default: on.
    pub fn settle(mut self, on: bool) -> Self {
        self.p.parts.settle = on;
        self
    }

    /// Hold the time of receding paint deeper than the border band (SHIFTNNF, module `shift`,
    /// `hold_receding`): where the target moves against the exemplar's flow (a match with the
    /// flipped rotation: the shape recedes there), the paper runs the exemplar's time
    /// backwards, so that the edge retreats the way the bloom spread. That is right at the
    /// edge, but deeper inside than the border width b the exemplar's paint does not move;
    /// running its time backwards there only turns it back towards the wet, concentrated paint
    /// of the bloom's first frames — un-spreading it — and, as neighbouring matches step by
    /// different amounts, makes it boil. With this on, a receding match deeper than b keeps
    /// its exemplar frame (Δi = 0) and the advection carries all of its motion. Measured on the
    /// 24-frame quality suite (five exemplars × six targets): incoherent change lower on every
    /// moving run (mean 0.90 → 0.82; the thin limbs 1.68 → 1.56, 1.04 → 0.88), edge darkening
    /// ≥ 0.8 of the exemplar's on 21 of 25 runs instead of 18, palette ≤ 0.03 on 23 of 30
    /// instead of 22, contrast unchanged on average. With [`ParamsBuilder::aging`] on (the
    /// default) a receding match steps forward instead, and this changes nothing; it acts
    /// with the aging off. Off = the paper's rule everywhere. Default: on.
    pub fn receding_hold(mut self, on: bool) -> Self {
        self.p.parts.receding_hold = on;
        self
    }

    /// Paint ages (SHIFTNNF, module `shift`, `aged`): every carried match steps at least one
    /// exemplar frame forward per target frame, until the exemplar's last frame, whatever the
    /// target's extents ask. The paper's Δi follows the extents alone, and the engine's
    /// nominal step wins only near-ties, so where the target's extent does not change (a still
    /// interior, the middle of a shape that only moves) paint whose exemplar extent changes
    /// fast — young paint near the bloom's spreading front — stayed young; the search put
    /// young paint there (without Ω, λ = 0, even more of it), and nothing aged it again. The
    /// same rule held the rim of a still shape in the frame it was first painted with, and ran
    /// a receding rim back towards the bloom's first, wet frames. Real paint dries on whether
    /// or not its shape moves: it does not stay wet, nor un-spread. Measured on the 300-frame
    /// target (yellow-granules, 512², seed 1): the interior's mean exemplar frame fell from
    /// 21.5 (of 29) at frame 1 to 15.3 at frame 150 without it; aged, 28.4–28.8 from frame 30
    /// on, and the lowest 50-frame window keeps 0.94 of the first window's contrast instead of
    /// 0.87. Aging the rim band too (it was first applied deeper than the border width b
    /// only) gave rose-burst's feathered late rim to its still and shrinking ellipses (edge
    /// darkening 0.48–0.61 → 0.75–0.77 of the exemplar's on the 24-frame suite) and lowered the
    /// incoherent change of green-wash's moving runs (docs/quality.md). Not in the
    /// paper. Off = Δi as the extents and the nominal step choose it everywhere. Default: on.
    pub fn aging(mut self, on: bool) -> Self {
        self.p.parts.aging = on;
        self
    }

    /// A moving shape's paint keeps the exemplar's pace (SHIFTNNF, module `shift`): where the
    /// shape moves rather than grows from one frame to the next — it gives up at least a third
    /// as much area as it newly covers: a swinging limb, a translating or turning shape — each
    /// carried match steps at most one exemplar frame per target frame (either way), and the
    /// advection carries the rest of the motion. The paper's SHIFTNNF steps through as many
    /// frames as match the target's extent change: a part moving faster than the exemplar's
    /// paint ever spreads runs through several exemplar frames per frame, ageing its paint
    /// that much faster, and the border band's matches land deep inside the exemplar's later,
    /// larger bloom, where the segment check drops them and new paint replaces them. Nothing
    /// spreads onto new paper where a shape only moves, so its paint ages at the exemplar's own
    /// pace; a growing shape keeps the paper's rule (its front is new paint). Measured on a
    /// 14-px limb swinging at up to 11 px a frame (ink-rims, 24 frames, 512²): carried matches
    /// stepped 2–6 exemplar frames in a frame at its tip, and their distance from the exemplar's
    /// edge after re-anchoring was 6–12 px where the target's was 2. With the pace, on the
    /// 24-frame quality suite (seeds 1 and 2): incoherent change of the five video exemplars'
    /// limbs 1.86 → 1.65 and 1.81 → 1.58 on average, of the whole suite 0.849 → 0.800 and
    /// 0.842 → 0.790; contrast 0.961 → 0.959 and 0.958 → 0.954; growing shapes and the
    /// identity unchanged. Not in the paper. Off = the paper's unbounded step everywhere.
    /// Default: on.
    pub fn pace(mut self, on: bool) -> Self {
        self.p.parts.pace = on;
        self
    }

    /// A moving shape's paint is carried with all of its motion (SHIFTNNF, module `shift`):
    /// where the shape moves rather than grows from one frame to the next (a translating,
    /// turning or swinging part; [`Self::pace`]), the exemplar's time step only ages the paint,
    /// and the advection carries the whole target motion. The paper lets the time step supply
    /// the motion: a match that steps from frame i to i + Δi shows what the exemplar's flow
    /// brought to its position, and only the rest is carried (with [`Self::advect`]). But the
    /// exemplar's flow is its outline's spread, diffused inwards; its paint's texture — the
    /// grain, the pigment's blotches — does not travel with it. Supplied by the time step, the
    /// motion let the texture lag behind the shape by the exemplar's speed at each match,
    /// unevenly from match to match: on the swinging limb (ink-rims, 24 frames, 512², `synth
    /// --debug`) the shifted field lagged the exact motion by 0.7–1.0 px a frame at its fastest
    /// and only 0.37 of its pixels continued the previous frame's match within ½ px (0.46
    /// with this). Where the shape grows, its front is new paint and the paper's rule holds.
    /// A carried part keeps the paint it was first given: on a thin part that made plain
    /// that its middle was painted from the bloom's deep, pale middle, which the border width
    /// fitted to the part now prevents ([`Params::fit_to_thickness`]). Not in the paper. Off = the time step supplies the motion it stands for. Default: on.
    pub fn full_carry(mut self, on: bool) -> Self {
        self.p.parts.full_carry = on;
        self
    }

    /// Travelling border paint holds its exemplar frame (SHIFTNNF, module `shift`): where the
    /// shape travels — it newly covers and gives up about as much area from one frame to the
    /// next (within a factor of three either way: a swinging limb, a translating or turning
    /// shape; not a growing, shrinking or still one) — a carried match that lands within the
    /// border width b of the edge keeps its exemplar frame when the match moves at least half
    /// a pixel a frame or, on a thin part (no deeper than 2 b: a limb, a stroke), when the
    /// part moves noticeably (the 90th percentile of its pixels' speeds at least half a pixel
    /// a frame): neither the extents' time step nor the aging
    /// ([`Self::aging`]) steps it, and the advection carries it whole. Interior paint, and
    /// the paint of a shape at rest, age as before.
    ///
    /// An exemplar frame step changes the paint at a fixed point of the exemplar by the
    /// exemplar's own change there, and its border band, where a bloom's front deposits its
    /// pigment, changes fastest (2.4 times as much as its interior, flow compensated, on
    /// yellow-granules). On a shape that only travels nothing spreads: the carried texture is
    /// expected to move with the part, and the band's change, in place, reads as boiling — a
    /// thin part (a limb) is all band. Measured (instrumented, yellow-granules, the suite's
    /// swinging limb, seed 1): 60–73 % of the limb's carried matches stepped one frame per
    /// frame over its first ten frames and 10–28 % two or backwards; the flow-compensated
    /// residual of the pixels whose match continued the previous frame's rigidly (same frame,
    /// within 1 px) was 0.0081, of those that stepped 0.0107–0.0204, and the 72 % that
    /// stepped carried 81 % of the residual. Holding every carried match on the limb (a scratch build) took its
    /// incoherent change from 1.64 to 1.03 of the exemplar's, and stepping them by exactly one
    /// frame with nothing else changed left it at 1.69: the step itself is what boils. Held in
    /// the interior too, the paint of travelling ellipses lost the streaks its aging gives it
    /// (contrast of the turning ellipse 0.94–0.99 → 0.87–0.90 with green-wash and
    /// yellow-granules); so only the band holds. Whether a thin part moves is the part's:
    /// judged per pixel alone, a limb's paint near its shoulder, and all of it at the turn of
    /// each swing, aged in place and boiled (yellow-granules' limb, seed 1: incoherent change
    /// 1.62 and 1.66 in frames 13–14, held 0.94 and 0.95). A large shape's rim is judged per
    /// pixel: held as a whole while the shape drifts slowly, it stopped aging and lost its
    /// texture over hundreds of frames (green-wash, the suite's 300-frame target at half size,
    /// without the tone match: lowest window 0.84 of the first's contrast, against 0.89).
    /// Not in the paper. Off = every carried match
    /// takes its time step and ages. Default: on.
    pub fn travel_hold(mut self, on: bool) -> Self {
        self.p.parts.travel_hold = on;
        self
    }

    /// Paint the first frame twice (`Synthesizer::step`): once from a random field, as the
    /// paper does, and again from that result carried over as if it were the previous frame
    /// with no motion — SHIFTNNF with the exemplar's time held (Δi = 0), its rim re-anchored to
    /// the target's distance from the edge and the field settled onto its pieces, then the
    /// search with the temporal term and the coherence factor κ of every later frame.
    ///
    /// The random start leaves the border band rough — specks and a rim too wide where the
    /// matches landed a little off their depth — and the second frame, the first with a
    /// carried field, cleans it up at once: the paint jumps between frames 1 and 2 and is
    /// steady after (a still ellipse at 512², mean change per channel inside it: ink-rims
    /// 0.0133 from frame 1 to 2, 0.0031 from 2 to 3; blue-bloom 0.0089, 0.0025). Painted
    /// twice, frame 1 already looks like frame 2 (0.0035, 0.0024; 0.0026, 0.0019:
    /// `tests/first_frame.rs`). The exemplar's own masks still give back the exemplar at frame
    /// 1 (its time is held). Costs one frame's synthesis per sequence. Not in the paper.
    /// Off = the first frame painted once.
    /// Default: on.
    pub fn repaint_first(mut self, on: bool) -> Self {
        self.p.parts.repaint_first = on;
        self
    }

    /// A still's patches turn with the shape (`synth::shift`): a still exemplar has no flow, so
    /// the flow-alignment rule gives no rotation and every patch was sampled unturned (θ = 0).
    /// On a turning shape the carried field's pieces turn with the paint — the warp carries
    /// positions — while the patches they sample did not: neighbouring pixels no longer
    /// continued each other's patches (on a lobed blob turning 0.9°/frame, the field's pieces
    /// were turned 7–14° against their patches), the vote averaged patches that disagree, and
    /// the texture washed out over a long animation. With this, each carried match turns by the
    /// target's local rotation (½ curl of its flow) as it is carried, and the search samples
    /// every candidate at the rotation of the carried match at its pixel (the pixels with no
    /// carried match take their neighbours'), so the paint's pieces and the patches they
    /// sample turn together. Video exemplars are unchanged: their rotation is the rule's.
    /// Not in the paper (whose exemplars all have flow). Off = θ = 0 for a still.
    /// Default: on.
    pub fn turn(mut self, on: bool) -> Self {
        self.p.parts.turn = on;
        self
    }

    /// Restrict matches to the target pixel's segment (border `I^df < 1` / interior, thesis
    /// §3.4). Off = any segment (ablation). Default: on.
    pub fn segments(mut self, on: bool) -> Self {
        self.p.parts.segments = on;
        self
    }

    /// An inherited match (up-scaled, or carried from the previous frame by SHIFTNNF) whose
    /// center has landed just outside its target pixel's segment — in the other segment, or,
    /// for a border pixel inside the target's mask, on the paper just outside the exemplar's
    /// paint — moves the least distance that puts it on a valid center of that segment, into
    /// one of the eight pixels around its own (the rotation and exemplar frame kept), and is
    /// dropped only where none of them is valid. The paper drops it.
    ///
    /// A match carried by a motion of a fraction of a pixel lands a fraction of a pixel from
    /// where it was, and where its target pixel lies at the border width b (the segments'
    /// divide) or at the edge, the segments' rasterized boundaries step by a whole pixel where
    /// the paint moved by less: 1–15 % of a thin bar's carried matches a frame were dropped for
    /// it and replaced by the up-scaled match, 30–39 px away in the exemplar on average
    /// (measured in docs/quality.md, *Where the carrying boils*). Moved by a fraction of a pixel,
    /// the paint stays the paint that was there. Measured on the 24-frame quality suite (seeds
    /// 1 and 2): the moving ellipses' incoherent change lower on 36 of 40 runs (mean 0.631 →
    /// 0.605 and 0.630 → 0.607), the limbs' palette closer (ink-rims 0.086 → 0.077 and 0.085 →
    /// 0.071), their coherence unchanged (over six seeds, 1.628 → 1.614 on average). Moving
    /// each match by a whole pixel instead (the first pixel of the eight that was valid) gave
    /// the same on the suite, but drifted matches up and to the left, the order it tried the
    /// pixels in, and a slowly moving bar's band changed more as the frames went on
    /// (`tests/rim_band.rs`: blue-swatch 0.0124 → 0.0155, 1.25×). Off = such matches are
    /// dropped, as in the paper. Default: on.
    pub fn segment_snap(mut self, on: bool) -> Self {
        self.p.parts.segment_snap = on;
        self
    }

    /// Clamp target motion extents to the exemplar's largest (so long target motions do not
    /// all collapse onto the exemplar's few most-moved pixels). Default: on.
    pub fn ext_clamp(mut self, on: bool) -> Self {
        self.p.parts.ext_clamp = on;
        self
    }

    /// Bring the target's extents to the exemplar's scale before comparing them
    /// ([`super::Synthesizer::set_target_extent`]). Off = raw extents, as in the paper.
    /// Default: on.
    pub fn ext_normalize(mut self, on: bool) -> Self {
        self.p.parts.ext_normalize = on;
        self
    }

    /// Fade the extent channels out in the interior (module `source`, `extent_falloff`): full
    /// weight w_ext in the border band (`I^df < 1`), falling linearly to none at twice the
    /// border width from the edge, on both the exemplar's and the target's side — at the
    /// pyramid levels where the exemplar's frames are at least 10 patch widths across (at the
    /// coarser ones the extents still lay the interior out). Off = the extents weigh the same
    /// everywhere, as in the paper.
    ///
    /// The extents say how far the paint has travelled; near the edge that decides the rim,
    /// deep inside it ties the target's interior to the exemplar's least-travelled paint — the
    /// flat, pale core where its drop landed — whenever the interior has moved less than the
    /// exemplar's paint: on a still shape and on the first frame of any shape. A still ellipse
    /// on green-wash took 84 % of its interior matches from the calmest quarter of the
    /// exemplar's interior, with 0.6 of the exemplar's local contrast at the same depths.
    /// With the falloff (the quality suite, 24 frames at 512², every bundled exemplar):
    /// contrast ≥ 0.85 of the exemplar's on 13 of the 30 still and moving runs instead of 8
    /// (the stills: green-wash 0.68 → 0.80, ink-rims 0.71 → 0.86, yellow-granules 0.79 → 0.93),
    /// the palette within 0.03 on 20 runs instead of 17, edge darkening 0.896 → 0.908 and
    /// incoherent change 0.898 → 0.890 on average over the 25 moving runs; the identity
    /// unchanged. At the coarsest levels the interior would collapse onto one exemplar spot
    /// and repeat it as a lattice at the level's pixel pitch (see
    /// `source::EXTENT_FALLOFF_MIN_SIDE`), so the falloff starts where the exemplar's frames
    /// are at least 10 patch widths across.
    ///
    /// Default: on.
    pub fn extent_falloff(mut self, on: bool) -> Self {
        self.p.parts.extent_falloff = on;
        self
    }

    /// Keep the carried rim (MERGENNF, module `pyramid`, `merge`): in the border band
    /// (`I^df < 1`, the target's border segment) the match carried from the previous frame —
    /// shifted in time, advected, and re-anchored to the target's distance from the edge by
    /// SHIFTNNF — is kept at every level unless the up-scaled match's error is below a quarter
    /// of its own (only a carried match that has gone wrong is replaced); the up-scaled match
    /// competes for the rest of the shape as before. Off = the merge compares the two
    /// everywhere, as in the paper.
    ///
    /// The up-scaled match comes from a level where the band is a pixel or two wide: placed
    /// within a few pixels of the edge, it lands on the exemplar's paler paint behind the rim
    /// more often than on the rim, and compared against an estimate voted from the up-scaled
    /// field itself it still wins often enough. A few rim pixels a frame, and over a long
    /// sequence the rim is gone (green-wash on the 300-frame target: the lowest 50-frame
    /// window's rim 0.42 of the first window's). The carried match was re-anchored to the
    /// edge, so keeping it keeps the rim: on that target green-wash's lowest window keeps 1.00
    /// of the first window's rim, every bundled exemplar at least 0.86, and the contrast holds
    /// better too (blue-bloom's lowest window 0.74 → 0.90; docs/quality.md). Newly
    /// covered pixels (a growing edge) have no carried match and are matched afresh as before.
    ///
    /// Kept without any comparison (the rule until 2026-12-05), a carried match that had gone
    /// wrong was never replaced, and the band of a slowly moving shape gathered dark specks and
    /// streaks over the frames; the factor of four replaces those and keeps the rest (measured
    /// in `pyramid::merge`'s documentation and docs/quality.md).
    ///
    /// Default: on.
    pub fn carried_rim(mut self, on: bool) -> Self {
        self.p.parts.carried_rim = on;
        self
    }

    /// MERGENNF judges the carried and the up-scaled match against an estimate of the frame
    /// voted from the *carried* field (completed by the up-scaled matches where nothing is
    /// carried, i.e. newly covered pixels), instead of from the up-scaled field.
    ///
    /// The merge keeps the carried match for most pixels (about 90 % at the finest level on a
    /// moving ellipse), so the frame it makes looks like the carried field's vote, not like
    /// the up-scaled field's. An estimate voted from the up-scaled field is the challenger's
    /// own picture: measured against it, an up-scaled match always fits well, and about a tenth
    /// of the carried matches were replaced every frame — texture renewed for no better fit,
    /// which the vote then averages with its carried neighbours. Judged against the carried
    /// picture, the up-scaled match wins only where the carried one really fits worse. On the
    /// suite's moving ellipses (24 frames, 512²) contrast rose with the same incoherent
    /// change (docs/quality.md). Not in the paper, which does not say what the merge's
    /// estimate is voted from. Off = the up-scaled field's estimate. Default: on.
    pub fn carried_estimate(mut self, on: bool) -> Self {
        self.p.parts.carried_estimate = on;
        self
    }

    /// The finest level's MERGENNF weighs its two candidates with the uniformity penalty Ω
    /// (and the contrast balance, [`Self::contrast_balance`]) as every coarser level's merge
    /// does, counted over the up-scaled field as there. Off = the finest level's merge
    /// compares the patch errors alone.
    ///
    /// The finest level is only voted, so its merge is the one choice made there: every frame
    /// it replaces a few per cent of the carried matches by up-scaled ones. Judged by the
    /// patch error alone, a calm piece of the exemplar's paint fits the estimate as well as a
    /// textured one, and the replacements were calmer than what they replaced (the exemplar's
    /// contrast at the matched positions 9–16 % lower; yellow-granules on the 300-frame
    /// target), so over hundreds of frames the interior settled on the exemplar's calmest
    /// paint. The contrast balance charges a candidate from a contrast bin the field already
    /// uses more than the exemplar holds, and Ω one from a spot it already reuses. On the
    /// 300-frame target (512², seed 1) the contrast of every 50-frame window rose
    /// (yellow-granules 0.70–0.85 → 0.76–0.87 of the exemplar's, green-wash 0.69–0.80 →
    /// 0.74–0.85, blue-bloom 0.75–0.88 → 0.83–0.92, ink-rims 0.85–0.95 → 0.95–1.04), the lowest
    /// window's rim ÷ the first's 0.91–1.01 → 0.95–1.01 (ink-rims 0.97 → 0.96, the others up),
    /// and the paint changes a little more from frame to frame (incoherent change 0.40–0.80 → 0.45–0.89);
    /// docs/quality.md. Not in the paper, which does not optimize the finest level and does not say what its
    /// merge weighs. Default: on.
    pub fn finest_uniformity(mut self, on: bool) -> Self {
        self.p.parts.finest_uniformity = on;
        self
    }

    /// Keep the grain's variance in the output's vote (module `vote`, `vote_grain`): the
    /// average of patches that do not agree washes the exemplar's fine grain out, so the
    /// deviation of the voted grain is scaled back by what the votes' disagreement took from
    /// it. Off = the plain average of Kwatra et al., as in the paper.
    ///
    /// Default: on (CLI `--no-grain` switches it off). It gives the output the exemplar's grain:
    /// on the quality suite (κ = 2 in the search and the finest merge, the search's estimates
    /// voted with σ = 0.5; 24 frames at 512², every bundled exemplar) contrast rose on all 25
    /// moving runs (mean 0.694 → 0.766; ≥ 0.85 of the exemplar's on 8 of 30 still and moving
    /// runs instead of none), the palette stayed (within 0.03 on 17 of 30 runs instead of 16),
    /// and the grain it gives back changes from frame to frame with the field: incoherent
    /// change 0.753 → 0.898 on average, the ellipses at most 1.11 (yellow-granules), within
    /// the 1.2 of the exemplar's own change that the issue allows; the limbs 1.15–2.01. With
    /// the blurred estimate and the merge at face value of earlier versions the same flag made
    /// the ellipses boil (up to 1.78), and it was off by default.
    pub fn keep_grain(mut self, on: bool) -> Self {
        self.p.parts.keep_grain = on;
        self
    }

    /// Give the grain of a patch that lands between exemplar pixels part of the variance the
    /// interpolation takes from it (module `vote`, `vote_grain`, with [`Self::keep_grain`]).
    /// A moving shape's patches are turned by the direction rule and carried by sub-pixel
    /// amounts, so the output samples the exemplar between its pixels, and the Catmull–Rom
    /// sample of a fine grain keeps only part of its variance (0.41 of a white grain's half-way
    /// between pixels on both axes): the paint of a moving shape is softer than that of a
    /// still one. Each voter's grain is scaled by `(V(fx)·V(fy))^(−1/4)`, V the variance that
    /// the interpolation at its sub-pixel phase keeps of a grain with the exemplar's own
    /// autocorrelation — half of the lost deviation (in log) is given back; giving all of it
    /// back bought contrast with as much boiling. Not in the paper. On the 24-frame quality
    /// suite (five video exemplars × six targets): local contrast ≥ 0.85 of the exemplar's on
    /// 25 of 30 runs instead of 21 with seed 1 (27 instead of 23 with seed 2), mean over the
    /// moving runs 0.90 → 0.93 (0.90 → 0.92), incoherent change 0.90 → 0.95 (0.90 → 0.94; within the
    /// issue's 1.2 on 25 runs instead of 26 with both seeds), edge darkening and palette within
    /// 0.01. Off = the grain as the interpolation leaves it. Default: on; always off for
    /// painted keyframes ([`super::keyframes::paint`]), where the carried painting already
    /// keeps 0.95–0.98 of the keyframe's contrast on every frame and the gain only adds change
    /// between frames (`tests/keyframes.rs`, two keyframes: the demo's dress 0.27 of the
    /// incoherent change of painting each frame alone with the gain, 0.26 without it; the ball
    /// 0.28 and 0.27).
    pub fn grain_phase(mut self, on: bool) -> Self {
        self.p.parts.grain_phase = on;
        self
    }

    /// Give the output's grain back the exemplar's amplitude at each distance from the edge
    /// deeper than the border band, in the frames its matches come from (module `tone`,
    /// `grain_gains`; with [`Self::keep_grain`] and [`Self::tone_match`]): the tone match gives
    /// the low-pass the exemplar's tones and detail, and the grain, voted apart and added back
    /// after, kept what the vote left of it. Carried paint sits between the exemplar's pixels
    /// and its voters agree less as the field is stretched, so its grain faded from frame to
    /// frame (the still swatch on the quality suite's growing ellipse, seed 1: the finest grain
    /// 16–64 px inside 0.036–0.038 on the first frame, 0.025–0.026 by frame 24, the swatch's
    /// 0.036–0.045; with the gain 0.033–0.036; contrast 0.782 → 0.870 of the swatch's). The gain
    /// only raises the grain, at most 2×: lowering it where the vote left more than the exemplar
    /// has took ink-rims' ellipses' contrast from 1.04 to 0.92. The border band, matched again
    /// every frame against the rim's own paint, did not fade, and raising a thin part's grain
    /// only made it change more (yellow-granules' limb 1.134 → 1.216 of the exemplar's
    /// incoherent change); it keeps its grain. Not in the paper. Off = the grain as voted.
    /// Default: on.
    pub fn grain_match(mut self, on: bool) -> Self {
        self.p.parts.grain_match = on;
        self
    }

    /// Bring the output's pigment density at each distance from the edge to the exemplar's at
    /// that distance, in the frames its matches come from (module `tone`). Not in the papers.
    ///
    /// Patch-based synthesis assembles a target larger than the exemplar's paint from many
    /// pieces, and it stitches them more easily from the flat, pale parts of a band than from
    /// the blotchy dark ones: the matches of the quality suite's targets sit on exemplar pixels
    /// paler than the exemplar's mean at the same depth in the same frame — ink-rims, a still
    /// ellipse's first frame, +0.05 to +0.08 luma 0–7 px inside; the exemplar's own outline
    /// scaled 1.6× +0.07 to +0.12, and only +0.01 to +0.06 at its own size; 49–60 % of the
    /// border band's matches in the palest third of the exemplar's paint at their depth, 14–21 %
    /// in the darkest. No search setting removed it (the scaled outline's first frame with λ 0
    /// and 16, r 0, w_df 1 and 20, w_ext 0, the vote's σ 0–1.5, two to five pyramid levels,
    /// more EM iterations: +0.06 to +0.12 at 3–7 px; κ = 1 only deeper than 5 px, on the
    /// limb), nor a balance over the tone like the contrast balance (module `occurrence`).
    ///
    /// So the output is corrected where it is voted: per 1-px depth bin of the target, each
    /// channel's density `−ln(c/paper)` of the output's low-pass is mapped onto the exemplar's
    /// low-pass at that depth, pooled over the frames its matches use, quantile to quantile
    /// (monotone, so every blotch keeps its place in the band's order; linear between bins);
    /// the grain is then given back as a density ([`Self::keep_grain`]), a factor of the
    /// low-pass, so that it darkens with it and cannot take a dark pixel below black. Density
    /// rather than color: paper stays paper. Where the output is the exemplar (the identity)
    /// the map is the identity.
    ///
    /// The first form of the correction scaled each bin's density by the ratio of the means
    /// (bounded to 0.5–2): it brought the mean back but stretched the band's whole spread with
    /// it, and the dark tail went past anything the exemplar has — on the suite's swinging
    /// limb 9–18 % of the pixels 15 % darker than the exemplar's 99.5th percentile in some
    /// channel (green-wash 17.8 %, ink-rims 14.1 %, blue-swatch 13.1 %, yellow-granules 8.6 %;
    /// 1.1 % without the correction), near-black spots a painter's paint never makes.
    /// Matching the distribution: 4.8 %, 6.7 %, 2.4 % and 2.1 % (the rest is the grain), the
    /// palette of the 24-frame suite 0.0164 → 0.0127 (seed 1) and 0.0163 → 0.0125 (seed 2),
    /// the limbs' 0.022–0.049 → 0.009–0.026 (rose-burst's 0.069, its feathered rim, aside);
    /// the paint's changes from frame to frame grow with its contrast (incoherent change
    /// 0.602 → 0.660 and 0.606 → 0.663; the limbs 1.08–1.82 → 1.27–2.03).
    ///
    /// One such map gives each depth the exemplar's spread of tones, but puts it wherever the
    /// output varies — at the scale of the patches it was stitched from: the limbs' local
    /// contrast came out 1.13–1.19 of the exemplar's. So the match runs in two passes
    /// (module `synth::tone`): the coarse band (a blur of σ 2 px within the mask)
    /// quantile to quantile with the detail scaled to the exemplar's amplitude, then the whole
    /// density quantile to quantile; and the exemplar's distribution for a bin is the
    /// Wasserstein barycenter of its frames' rather than their mixture. The four boiling limbs
    /// over seeds 1–6: incoherent change 1.554 → 1.353, palette 0.0135 → 0.0126, contrast
    /// 1.186 → 1.032; the 24-frame suite's incoherent change 0.660 → 0.618 and 0.663 → 0.626.
    ///
    /// Default: on; off for painted keyframes ([`super::keyframes::paint`]), whose output is
    /// the painting itself.
    pub fn tone_match(mut self, on: bool) -> Self {
        self.p.parts.tone_match = on;
        self
    }

    /// With the tone match ([`Self::tone_match`]), read a shape deeper than the exemplar's
    /// paint at the exemplar's depths stretched to it (not in the papers): within the border
    /// width of the edge every pixel keeps its depth; deeper, a connected part whose deepest
    /// pixel lies at `D`, more than the paint's own depth `R` (the deepest pixel of the
    /// exemplar frames its matches come from, averaged over the part), reads the paint at
    /// `d' = b + (d − b)·(R − b)/(D − b)` (`guide::stretched_depths`). A part no
    /// deeper than the paint keeps its depths, and the identity is left as it is.
    ///
    /// Read at their own depths, every depth beyond the exemplar's deepest took the tones of
    /// its few central pixels, the calmest and palest of a bloom: a shape two or three times
    /// the exemplar's size had most of its interior in one pale, flat tone, its middle a mush
    /// that looked like no part of the exemplar, and over the whole interior it was paler and
    /// flatter than the exemplar (the 24-frame suite, seed 1: contrast over the whole interior
    /// 0.86 of the exemplar's on average, 0.58 for ink-rims' still ellipse; the palette
    /// against the exemplar's whole interior 0.062). Stretched, the shape's middle takes the
    /// exemplar's middle and the depths between take the tones between: the figures and the
    /// reasons are in the README (*Decisions and simplifications*).
    ///
    /// Default: on.
    pub fn depth_stretch(mut self, on: bool) -> Self {
        self.p.parts.depth_stretch = on;
        self
    }

    /// Where the target does not move, turn the patches by the shape's outward normal (not in
    /// the papers): the direction rule M (thesis §3.3) aligns the exemplar's flow direction at
    /// the source with the target's flow direction, and a target pixel with no flow (below
    /// 0.02 px a frame) has none, so its patches were never turned (θ = 0). A resting shape is
    /// paint that has spread to its outline, as the exemplar's paint spread to its own; with
    /// this rule its direction is its outward normal −∇I^dist, the direction a growing shape's
    /// flow has, aligned with the exemplar's own outward normal −∇S^dist at the source (a
    /// bloom's direction of spread; unlike its flow, which fades out and turns where the paint
    /// slows down, the normal at a pixel stays put from one exemplar frame to the next, so a
    /// match keeps its turn as its paint ages). The exemplar's radial structure — lobes and
    /// fingers that run out from the bloom's middle, the dark rim's inner edge — then keeps its
    /// orientation toward the shape's edge, and a rim piece can come from anywhere along the
    /// exemplar's rim, turned to fit.
    /// The ring of patch centres just outside the mask, where the flow is zero by convention,
    /// takes the normal where the mask pixel it faces rests too, and stays unturned where that
    /// pixel moves. A ridge of the distance field (the middle of a shape) has no normal and
    /// stays unturned.
    ///
    /// Without it, the middle of a resting shape several times the exemplar's size is a
    /// mosaic of unturned pieces: each piece's lobes run the way they ran wherever the piece
    /// was cut from the bloom, and pieces next to each other along an edge are cut from the
    /// same side of it, so the same motif repeats in rows parallel to the edge (ink-rims: rows
    /// of pale cells and rectangular dark blotches; rose-burst: a lattice of its paper's light
    /// fibres; yellow-granules: wavy bands). The figures are in the README (*Decisions and
    /// simplifications*).
    ///
    /// Default: off (`--resting-normal` on the command line). It costs a resting shape's paint
    /// some steadiness: turned pieces are smaller than the unturned mosaic's, and their seams
    /// settle anew as the paint ages, so a still target changes more from frame to frame —
    /// 0.80 → 1.01 of the exemplar's own change in `tests/engine_quality.rs` (a 130 × 110 still
    /// ellipse, whose floor is the exemplar's 1.0; 1.10 when the rule aligned with the
    /// exemplar's flow instead of its normal), 0.32–0.99 → 0.43–1.00 on the 24-frame suite's
    /// still ellipses (seed 1). Until that is resolved the look it gives is a choice, not the
    /// default.
    pub fn resting_normal(mut self, on: bool) -> Self {
        self.p.parts.resting_normal = on;
        self
    }

    /// Seed of every random choice. Default: 1.
    pub fn seed(mut self, s: u64) -> Self {
        self.p.seed = s;
        self
    }

    /// Lower σ and b for thin layers ([`Params::fit_to_thickness`]). Default: true.
    pub fn fit_thin_layers(mut self, on: bool) -> Self {
        self.p.fit_thin = on;
        self
    }

    /// σ of the spatial mask blur (thesis `--blur-sigma`), pixels. Default: 0 (see
    /// [`GuideParams::blur_sigma`]).
    pub fn blur_sigma(mut self, s: f32) -> Self {
        self.p.guide.blur_sigma = s;
        self
    }

    /// σ of the temporal distance-field blur (thesis `--time-blur-sigma`), frames. Default: 2.
    pub fn time_blur_sigma(mut self, s: f32) -> Self {
        self.p.guide.time_blur_sigma = s;
        self
    }

    /// Replaces all guide parameters.
    pub fn guide(mut self, g: GuideParams) -> Self {
        self.p.guide = g;
        self
    }

    /// Validates and returns the parameters.
    pub fn build(self) -> Result<Params> {
        let p = self.p;
        let finite_nonneg = |name: &str, v: f32| {
            if v.is_finite() && v >= 0.0 { Ok(()) } else { Err(Error::param(name, v, "a finite number >= 0")) }
        };
        finite_nonneg("dist-weight", p.weights.w_df)?;
        finite_nonneg("flow-weight", p.weights.w_ext)?;
        finite_nonneg("prev-weight", p.weights.w_prev)?;
        finite_nonneg("color-weight", p.weights.w_color)?;
        // The σ of a vote's center weighting.
        let vote_sigma = |name: &str, v: f32| {
            if v.is_finite() && (0.0..=10.0).contains(&v) {
                Ok(())
            } else {
                Err(Error::param(name, v, "0..=10 pixels"))
            }
        };
        vote_sigma("vote-sigma", p.schedule.vote_sigma)?;
        vote_sigma("estimate-sigma", p.schedule.estimate_sigma)?;
        vote_sigma("prev-sigma", p.schedule.prev_sigma)?;
        finite_nonneg("lambda", p.weights.lambda)?;
        finite_nonneg("contrast-balance", p.weights.contrast_balance)?;
        finite_nonneg("seam-cost", p.weights.seam_cost)?;
        if !(p.weights.coherence.is_finite() && (1.0..=100.0).contains(&p.weights.coherence)) {
            return Err(Error::param("coherence", p.weights.coherence, "a number in 1..=100 (1 = plain PatchMatch)"));
        }
        if let Some(b) = p.border_width
            && !(b.is_finite() && b > 0.0 && b <= 10_000.0)
        {
            return Err(Error::param("border-width", b, "a number of pixels in (0, 10000]"));
        }
        if p.schedule.occ_radius > 1000 {
            return Err(Error::param("occ-radius", p.schedule.occ_radius, "0..=1000 frames"));
        }
        let (ml, mu) = p.schedule.prev_bounds;
        if !(ml.is_finite() && mu.is_finite() && ml >= 0.0 && mu > ml) {
            // Shown as the command line takes it: m_u,m_l.
            return Err(Error::param(
                "prev-modulation-bounds",
                format!("{},{}", mu, ml),
                "m_u,m_l with 0 <= m_l < m_u (pixels)",
            ));
        }
        if !(p.schedule.alpha > 0.0 && p.schedule.alpha < 1.0) {
            return Err(Error::param("patchmatch-alpha", p.schedule.alpha, "a number in (0, 1)"));
        }
        for (name, v) in [("patchmatch-iterations", &p.schedule.pm_iters), ("opt-iterations", &p.schedule.opt_iters)] {
            if v.is_empty() || v.iter().any(|&n| n > 1000) {
                return Err(Error::param(
                    name,
                    format!("{:?}", v),
                    "a non-empty comma-separated list of counts (each <= 1000)",
                ));
            }
        }
        if let Some(l) = p.schedule.levels
            && !(1..=16).contains(&l)
        {
            return Err(Error::param("levels", l, "1..=16"));
        }
        if let Some(s) = p.src_scale
            && !(s.is_finite() && s > 0.01 && s <= 16.0)
        {
            return Err(Error::param("src-scale", s, "a number in (0.01, 16]"));
        }
        if let Some(s) = p.src_speed
            && !(1..=1000).contains(&s)
        {
            return Err(Error::param("src-speed", s, "1..=1000"));
        }
        let g = &p.guide;
        if !(g.blur_sigma.is_finite() && (0.0..=200.0).contains(&g.blur_sigma)) {
            return Err(Error::param("blur-sigma", g.blur_sigma, "0..=200 pixels"));
        }
        if !(g.time_blur_sigma.is_finite() && (0.0..=100.0).contains(&g.time_blur_sigma)) {
            return Err(Error::param("time-blur-sigma", g.time_blur_sigma, "0..=100 frames"));
        }
        if !(g.mask_threshold > 0.0 && g.mask_threshold < 1.0) {
            return Err(Error::param("mask-threshold", g.mask_threshold, "a number in (0, 1)"));
        }
        Ok(p)
    }
}

/// The most pyramid levels that a target `thickness` pixels thick (its inscribed radius) is
/// synthesized with: the paper's rule ⌊log2(d_min / n)⌋ (§3.6) keeps the frame at least two
/// patches across at the coarsest level; a part of the target must stay at least one patch
/// across there, `2·thickness / 2^(L−1) ≥ n`. A coarser level would see the whole part, both
/// of its edges at once, in one patch, and match it to the exemplar's thinnest features only —
/// the pale wet lobes of its advancing front — which the finer levels then inherit.
pub(crate) fn levels_for_thickness(thickness: f32) -> usize {
    let across = 2.0 * thickness / PATCH as f32;
    if across.is_finite() && across >= 1.0 { 1 + across.log2().floor() as usize } else { 1 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thin_targets_get_a_smaller_blur_and_border() {
        let p = Params::default();
        // Thick targets keep the thesis's values.
        assert_eq!(p.fit_to_thickness(60.0, 12.0), p);
        let thin = p.fit_to_thickness(7.5, 12.0);
        assert_eq!(thin.guide().blur_sigma, 0.0, "no blur stays no blur");
        let blurred = Params::builder().blur_sigma(8.0).build().unwrap().fit_to_thickness(7.5, 12.0);
        assert_eq!(blurred.guide().blur_sigma, 3.0);
        assert_eq!(thin.border_width(), Some(7.5));
        assert!(thin.fit_to_thickness(7.5, 12.0) == thin);
        // 15 px across, three patches: at the third level it would be under one.
        assert_eq!(thin.max_levels(), Some(2));
        assert_eq!(p.fit_to_thickness(60.0, 12.0).max_levels(), None, "thick: the frame decides");
        assert_eq!((levels_for_thickness(2.4), levels_for_thickness(2.5), levels_for_thickness(5.0)), (1, 1, 2));
        assert_eq!(levels_for_thickness(f32::NAN), 1);
        // Switched off, or a target of unknown thickness: unchanged.
        let off = Params::builder().fit_thin_layers(false).build().unwrap();
        assert_eq!(off.fit_to_thickness(7.5, 12.0), off);
        assert_eq!(p.fit_to_thickness(f32::NAN, 12.0), p);
        // A bar 15 px wide is 7.5 px thick; empty frames do not count.
        let bar = crate::img::Plane::from_fn(64, 64, |x, _| if (20..35).contains(&x) { 1.0 } else { 0.0 });
        let empty = crate::img::Plane::filled(64, 64, 0.0f32);
        let t = super::super::mask_thickness([bar.clone(), empty.clone(), bar]).unwrap();
        assert!((t - 7.5).abs() <= 1.0, "{t}");
        assert_eq!(super::super::mask_thickness([empty]), None);
    }

    #[test]
    fn defaults_validate_and_bad_values_are_named() {
        let p = Params::builder().build().unwrap();
        assert_eq!(p.pm_iters_at(0), 6);
        assert_eq!(p.pm_iters_at(7), 4);
        assert_eq!(p.opt_iters_at(1), 2);
        let e = Params::builder().lambda(f32::NAN).build().unwrap_err().to_string();
        assert!(e.contains("lambda"), "{e}");
        let e = Params::builder().prev_bounds(10.0, 2.0).build().unwrap_err().to_string();
        assert!(e.contains("prev-modulation-bounds"), "{e}");
        assert!(Params::builder().alpha(1.0).build().is_err());
        assert!(Params::builder().pm_iters(vec![]).build().is_err());
    }
}
