//! The Fluidymation synthesis engine (paper §3 and Appendix B, thesis ch. 3–4).
//!
//! For every target frame j, in order, a coarse-to-fine pyramid of EM iterations finds a
//! nearest-neighbour field into the whole exemplar sequence — frame i, sub-pixel position,
//! rotation θ — that minimizes the guided patch error D (module `patch`), and votes the frame's
//! colors from it (module `vote`). Temporal coherence comes from the previous frame's field,
//! shifted along the exemplar's own time axis (module `shift`), which both initializes the search
//! and votes the temporal guide `T^prev`. A 3D occurrence map keeps the use of exemplar
//! patches uniform (module `occurrence`). [`Synthesizer::step`] crops the frame to its working
//! window, builds the target's pyramid and shifts the previous field; module `pyramid` runs
//! the coarse-to-fine EM of the frame (Appendix B, Algorithm 1).
//!
//! ```no_run
//! use fluidymation::{exemplar::Exemplar, guide, synth::{Params, Source, Synthesizer}};
//! # fn main() -> fluidymation::Result<()> {
//! let ex = Exemplar::load("exemplars/blue-bloom".as_ref())?;
//! let params = Params::builder().seed(7).build()?;
//! let source = Source::prepare(&ex, &params)?;
//! # let target_masks: Vec<fluidymation::img::Plane<f32>> = vec![];
//! let target = guide::compute_sequence(&target_masks, params.guide())?;
//! let mut synth = Synthesizer::new(source, params)?;
//! for g in &target {
//!     let frame = synth.step(g)?; // T^rgb in the exemplar's colors, alpha = frame.mask
//!     # let _ = frame;
//! }
//! # Ok(()) }
//! ```

mod checkpoint;
pub mod keyframes;
mod nnf;
mod occurrence;
mod params;
mod patch;
mod patchmatch;
mod pyramid;
mod shift;
mod source;
mod target;
mod tone;
mod vote;

pub use params::{HALF, PATCH, Params, ParamsBuilder};
use source::SourcePyramid;

use crate::error::{Error, Result};
use crate::exemplar::Exemplar;
use crate::guide::FrameGuides;
use crate::img::{self, Mask, Plane, Rgb};
use nnf::{Nnf, level_count};
use source::MARGIN;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// An exemplar prepared for synthesis: resampled (scale, speed), with its guides and its
/// pyramid. Cheap to clone (shared).
#[derive(Clone)]
pub struct Source {
    pyramid: Arc<SourcePyramid>,
}

impl std::fmt::Debug for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Source")
            .field("size", &self.pyramid.size)
            .field("frames", &self.pyramid.levels[0].frames)
            .field("levels", &self.pyramid.levels.len())
            .field("border_width", &self.pyramid.border_width)
            .finish()
    }
}

/// The thickness of a target, for [`Params::fit_to_thickness`]: the median over the given
/// coverage frames of the mask's largest inscribed radius (the largest distance from the
/// outside among the pixels of coverage ≥ ½), pixels. Empty frames are skipped; `None` when all
/// are empty.
pub fn mask_thickness(coverages: impl IntoIterator<Item = Plane<f32>>) -> Option<f32> {
    let mut radii: Vec<f32> = coverages
        .into_iter()
        .filter_map(|c| {
            let m = c.map(|v| v >= 0.5);
            if m.data().iter().all(|&b| !b) {
                return None;
            }
            Some(crate::guide::sdf(&m).data().iter().copied().fold(0.0, f32::max))
        })
        .collect();
    if radii.is_empty() {
        return None;
    }
    radii.sort_by(f32::total_cmp);
    Some(radii[radii.len() / 2])
}

/// [`mask_thickness`] of a sequence of `frames` frames from up to 9 of them spread evenly
/// over it (the first and the last included); `coverage(k)` gives frame k's coverage.
pub fn sequence_thickness(frames: usize, mut coverage: impl FnMut(usize) -> Result<Plane<f32>>) -> Result<Option<f32>> {
    let samples = frames.min(9);
    let picked = (0..samples).map(|k| if samples > 1 { k * (frames - 1) / (samples - 1) } else { 0 });
    Ok(mask_thickness(picked.map(&mut coverage).collect::<Result<Vec<_>>>()?))
}

/// The synthesizer and the target's guide stream of one layer, ready for its first frame —
/// the pipeline that `synth`, `render`'s layers and the quality suite share: the exemplar
/// prepared (`prepare`, e.g. [`Source::prepare`] or a cached source), the stream's backward
/// pass over the target's `frames` coverages, and the synthesizer given the target's extent
/// scale.
///
/// The two are run one after the other. Run side by side (measured on the horse-like
/// workload, 12 frames of 1000×800, 2 threads) they saved 2 % of the wall time and raised the
/// peak memory by 86 MiB (both peaks at once): not worth it.
pub fn start(
    prepare: impl FnOnce() -> Result<Source>,
    params: &Params,
    frames: usize,
    coverage: impl FnMut(usize) -> Result<Plane<f32>>,
) -> Result<(Synthesizer, crate::guide::GuideStream)> {
    let source = prepare()?;
    let stream = crate::guide::GuideStream::new(frames, coverage, params.guide())?;
    let mut synth = Synthesizer::new(source, params.clone())?;
    synth.set_target_extent(stream.extent_scale());
    Ok((synth, stream))
}

/// Resamples exemplar frames: every `speed`-th frame, scaled by `scale`.
pub fn resample_exemplar(ex: &Exemplar, scale: f32, speed: usize) -> (Vec<Plane<Rgb>>, Vec<Plane<f32>>) {
    let (w, h) = (ex.width(), ex.height());
    let (sw, sh) = (((w as f32 * scale).round() as usize).max(1), ((h as f32 * scale).round() as usize).max(1));
    let pick: Vec<usize> = (0..ex.len()).step_by(speed.max(1)).collect();
    let frames = pick.iter().map(|&k| img::resize_bilinear(&ex.frames[k], sw, sh)).collect();
    let masks = pick.iter().map(|&k| img::resize_bilinear(&ex.masks[k], sw, sh)).collect();
    (frames, masks)
}

impl Source {
    /// Prepares an exemplar with `params` (its scale, speed and border width default to the
    /// exemplar's recommendations). Guides are computed after resampling.
    ///
    /// An exemplar of one frame is a still (a painted swatch): its paint has no motion, so its
    /// extents are zero (the target's are scaled to zero with them, `k = E_S/E_T = 0`), the
    /// flow-alignment rule gives no rotation (a flow has no direction), and SHIFTNNF has no
    /// frame to step to — the residual advection carries all of the target's motion, which
    /// warps the previous frame's field along the target's flow (Frigo et al. 2017 advect the
    /// previous stylized frame the same way, Bénard et al. 2013 the previous offsets). The
    /// patches start unturned (θ = 0) and turn with the shape's local rotation as the field is
    /// carried ([`ParamsBuilder::turn`]).
    pub fn prepare(ex: &Exemplar, params: &Params) -> Result<Source> {
        ex.validate()?;
        let scale = params.src_scale.unwrap_or(ex.meta.scale);
        let speed = params.src_speed.unwrap_or(ex.meta.speed).max(1);
        let (frames, masks) = resample_exemplar(ex, scale, speed);
        if frames.len() < 2 && ex.len() >= 2 {
            return Err(Error::param(
                "src-speed",
                speed,
                format!("a step that leaves at least 2 of the exemplar's {} frames", ex.len()),
            ));
        }
        let guides = crate::exemplar::cache::guides(ex, &masks, &params.guide)?;
        Self::from_parts(&frames, &guides, params, params.border_width.unwrap_or(params.exemplar_border_width(ex)))
    }

    /// Prepares a source from frames and precomputed guides (one frame or more; one is a
    /// still, see [`Source::prepare`]).
    pub fn from_parts(
        frames: &[Plane<Rgb>],
        guides: &[FrameGuides],
        params: &Params,
        border_width: f32,
    ) -> Result<Source> {
        if frames.is_empty() || frames.len() != guides.len() {
            return Err(Error::param("exemplar frames", frames.len(), "at least one frame, each with guides"));
        }
        if frames.len() > u16::MAX as usize {
            return Err(Error::param("exemplar frames", frames.len(), "at most 65535"));
        }
        let (w, h) = frames[0].size();
        for (k, (f, g)) in frames.iter().zip(guides).enumerate() {
            g.check("exemplar guides")?;
            if f.size() != (w, h) || g.size() != (w, h) {
                return Err(Error::param(
                    "exemplar frames",
                    format!("frame {} {}x{} with guides {}x{}", k + 1, f.width(), f.height(), g.size().0, g.size().1),
                    format!("{w}x{h} like frame 1, and guides of the same size"),
                ));
            }
        }
        if w < 2 * MARGIN + 2 || h < 2 * MARGIN + 2 {
            return Err(Error::param("exemplar size", format!("{}x{}", w, h), "at least 8x8 pixels"));
        }
        if !(border_width.is_finite() && border_width > 0.0) {
            return Err(Error::param("border-width", border_width, "a positive number of pixels"));
        }
        // The search addresses exemplar voxels with 32-bit indices (and w, h with 16 bits).
        let voxels = (w + 2 * source::PAD) as u64 * (h + 2 * source::PAD) as u64 * frames.len() as u64;
        if voxels >= u32::MAX as u64 || w > u16::MAX as usize || h > u16::MAX as usize {
            return Err(Error::param(
                "exemplar size",
                format!("{w}x{h}x{}", frames.len()),
                "fewer than 2^32 padded pixels over all frames (use --src-scale or --src-speed)",
            ));
        }
        let mut levels = level_count(w.min(h));
        // Every level must offer candidate centers.
        let pyr = loop {
            let pyr = SourcePyramid::build(frames, guides, params, border_width, levels);
            if levels == 1 || pyr.levels.iter().all(|l| l.valid.iter().any(|v| !v.is_empty())) {
                break pyr;
            }
            levels -= 1;
        };
        if pyr.levels[0].valid.iter().all(|v| v.is_empty()) {
            return Err(Error::param(
                "exemplar masks",
                "empty",
                "paint at least a few pixels away from the frame border",
            ));
        }
        Ok(Source { pyramid: Arc::new(pyr) })
    }

    /// The border width b in use, pixels.
    pub fn border_width(&self) -> f32 {
        self.pyramid.border_width
    }

    /// The mean color outside the exemplar's masks (≈ its paper).
    pub fn paper(&self) -> Rgb {
        self.pyramid.paper
    }

    /// Number of (resampled) exemplar frames l_S.
    pub fn frames(&self) -> usize {
        self.pyramid.levels[0].frames
    }
}

/// One synthesized frame.
#[derive(Clone, Debug)]
pub struct SynthFrame {
    /// `T^rgb` in the exemplar's colors; outside the mask, the paper color.
    pub rgb: Plane<Rgb>,
    /// The (pre-processed) target mask: the output's alpha.
    pub mask: Mask,
    /// Time spent per pyramid level, coarsest first.
    pub level_times: Vec<Duration>,
    /// Time spent per stage.
    pub stages: StageTimes,
    /// Patch-error evaluations in this frame.
    pub evaluations: u64,
    /// The energy E = Σ_q D(NNF(q), q) (mean per active pixel) at the start of every
    /// PatchMatch sweep and after the last one, per level: `(level, E)`, coarsest first.
    pub energy: Vec<(usize, f64)>,
    /// Debug views, when enabled with [`Synthesizer::set_debug`].
    pub debug: Option<DebugViews>,
}

/// Where the time of one frame went, per stage (summed over levels).
#[derive(Clone, Copy, Debug, Default)]
pub struct StageTimes {
    /// Building the target pyramid and per-level layouts.
    pub target: Duration,
    /// SHIFTNNF, DOWNSCALENNF and m(q).
    pub shift: Duration,
    /// Voting (T^rgb, T^prev and the output).
    pub vote: Duration,
    /// The occurrence map Ω.
    pub occurrence: Duration,
    /// PatchMatch sweeps (the errors of the current field recomputed, propagation and random
    /// search).
    pub patchmatch: Duration,
    /// UPSCALENNF, MERGENNF and initialization.
    pub init: Duration,
}

#[inline]
fn timed<T>(acc: &mut Duration, f: impl FnOnce() -> T) -> T {
    let t = Instant::now();
    let r = f();
    *acc += t.elapsed();
    r
}

/// What a user can look at to see what the engine did in one frame.
#[derive(Clone, Debug)]
pub struct DebugViews {
    /// The final field as colors: red = x / w_S, green = y / h_S, blue = i / (l_S − 1);
    /// black where there is no match.
    pub nnf: Plane<Rgb>,
    /// Ω* of the finest optimized level summed over the exemplar frames, divided by
    /// n²(2r+1) (≈ how many times each exemplar pixel was used).
    pub omega: Plane<f32>,
    /// The final field itself, per target pixel: (i, x, y, θ) — exemplar frame, sub-pixel
    /// center in full-resolution exemplar pixels, rotation in radians; NaN where there is no
    /// match.
    pub field: Plane<[f32; 4]>,
    /// The previous frame's field shifted in time (SHIFTNNF), in the same form as `field`.
    pub shifted: Plane<[f32; 4]>,
}

/// What is carried from one frame to the next.
struct PrevState {
    /// Top-left corner of the previous frame's working window (full resolution).
    origin: (usize, usize),
    /// Final full-resolution field of the previous frame, over its window.
    nnf0: Nnf,
    /// `T^ext+` of the previous frame.
    ext_pos: Vec<f32>,
    /// `T^flow` of the previous frame: the motion from it to this one.
    flow: Vec<glam::Vec2>,
    /// The previous frame's masks per level.
    masks: Vec<Vec<bool>>,
}

impl PrevState {
    /// The state a frame leaves: its working window `win`, its final field, its finest guides
    /// `g0` (for `T^ext+` and `T^flow`) and its masks per level.
    fn new(win: (usize, usize, usize, usize), field: Nnf, g0: &FrameGuides, masks: Vec<Vec<bool>>) -> PrevState {
        PrevState {
            origin: (win.0, win.1),
            nnf0: field,
            ext_pos: g0.ext_pos.data().to_vec(),
            flow: g0.flow.data().to_vec(),
            masks,
        }
    }
}

/// Synthesizes a target sequence frame by frame ([`Synthesizer::step`]).
pub struct Synthesizer {
    params: Params,
    source: Source,
    frame: usize,
    prev: Option<PrevState>,
    size: Option<(usize, usize)>,
    debug: bool,
    /// The target's extent scale, when the caller knows it ([`Synthesizer::set_target_extent`]).
    target_extent: Option<f32>,
    /// The factor applied to the target's extents, fixed at the first non-empty frame.
    ext_factor: Option<f32>,
}

impl Synthesizer {
    /// A synthesizer for one target sequence (one layer).
    pub fn new(source: Source, params: Params) -> Result<Synthesizer> {
        Ok(Synthesizer {
            params,
            source,
            frame: 0,
            prev: None,
            size: None,
            debug: false,
            target_extent: None,
            ext_factor: None,
        })
    }

    /// Tells the synthesizer how far the target's material moves over the whole sequence: its
    /// extent scale `E_T` ([`crate::guide::extent_scale`], or
    /// [`crate::guide::GuideStream::extent_scale`] of the stream the frames come from). Call
    /// it before the first frame.
    ///
    /// The target's extents are compared with the exemplar's after scaling them by
    /// `k = min(1, E_S / E_T)`, `E_S` being the exemplar's scale: an animation whose material
    /// travels four times as far as the paint in the exemplar then asks for the exemplar's
    /// patches in the same proportions of little-moved and much-moved paint, instead of
    /// asking all its interior for the few most-moved pixels of the exemplar (whose extents
    /// are the only ones near its own, and whose overuse washes the texture out). The time
    /// shift follows the scaled extents too, so the exemplar's life — wet bloom to settled
    /// paint — is spread over the animation's motion; the motion it does not supply is
    /// carried ([`ParamsBuilder::advect`]). Without this call, `E_T` is taken from the first
    /// frame with paint: the extent scale of its `ext−` (how far that material will move).
    pub fn set_target_extent(&mut self, extent_scale: f32) {
        if extent_scale.is_finite() && extent_scale >= 0.0 {
            self.target_extent = Some(extent_scale);
        }
    }

    /// The factor `k` the target's extents are scaled by (fixed at the first frame with paint).
    pub fn extent_factor(&self) -> Option<f32> {
        self.ext_factor
    }

    /// `k = min(1, E_S / E_T)` for a target extent scale `E_T` (1 when normalization is off).
    pub(crate) fn extent_factor_for(&self, e_t: f32) -> f32 {
        let e_s = self.source.pyramid.ext_scale;
        if self.params.parts.ext_normalize && e_t > e_s && e_t > 0.0 { e_s / e_t } else { 1.0 }
    }

    /// Also produce [`DebugViews`] with every frame.
    pub fn set_debug(&mut self, on: bool) {
        self.debug = on;
    }

    /// The last frame's final field per target pixel, in the form of [`DebugViews::field`]:
    /// (i, x, y, θ), NaN where there is no match. `None` before the first frame and after a
    /// frame with nothing to paint.
    pub fn field(&self) -> Option<Plane<[f32; 4]>> {
        let (prev, full) = (self.prev.as_ref()?, self.size?);
        let place = Placement { full, win: (prev.origin.0, prev.origin.1, prev.nnf0.w, prev.nnf0.h) };
        Some(place.raw(&prev.nnf0))
    }

    /// Index of the next frame.
    pub fn frame(&self) -> usize {
        self.frame
    }

    fn level_count(&self, w: usize, h: usize) -> usize {
        let src = &self.source.pyramid;
        let auto = level_count(w.min(h).min(src.size.0).min(src.size.1))
            .min(src.levels.len())
            .min(self.params.schedule.max_levels.unwrap_or(usize::MAX));
        self.params.schedule.levels.map(|l| l.min(src.levels.len())).unwrap_or(auto).max(1)
    }

    /// Synthesizes the next frame from its guides (frames must come in order and all have
    /// the same size).
    pub fn step(&mut self, g: &FrameGuides) -> Result<SynthFrame> {
        g.check("target guides")?;
        let (w, h) = g.mask.size();
        if let Some(size) = self.size
            && size != (w, h)
        {
            return Err(Error::param(
                "target frame size",
                format!("{}x{}", w, h),
                format!("{}x{} like the first frame", size.0, size.1),
            ));
        }
        self.size = Some((w, h));
        let levels = self.level_count(w, h);
        let mut st = StageTimes::default();
        // Work only in the mask's bounding box (grown by the patch radius and a margin),
        // aligned so that every pyramid level keeps whole pixels.
        let Some(win) = window(&g.mask, 1 << (levels - 1)) else {
            self.prev = None;
            self.frame += 1;
            return Ok(SynthFrame {
                rgb: Plane::filled(w, h, self.source.pyramid.paper),
                mask: g.mask.clone(),
                level_times: Vec::new(),
                stages: st,
                evaluations: 0,
                energy: Vec::new(),
                debug: None,
            });
        };
        let pyr = timed(&mut st.target, || self.target_pyramid(g, win, levels));
        let src = self.source.pyramid.clone();
        let plain;
        let p = if self.frame == 0 {
            plain = self.first_frame_params();
            &plain
        } else {
            &self.params
        };
        // The previous frame's state, moved into this frame's window, and its field shifted in
        // time (SHIFTNNF) at full resolution.
        let (prev_here, shifted) = timed(&mut st.shift, || {
            let prev_here: Option<PrevState> = self.prev.as_ref().map(|prev| rewindow(prev, (win.0, win.1), &pyr));
            let shifted = prev_here.as_ref().map(|prev| shift_previous(&src, p, &pyr[0], prev, false));
            (prev_here, shifted)
        });
        let has_prev = shifted.as_ref().is_some_and(|n| n.data.iter().any(|m| m.ok));
        let inputs = pyramid::FrameInputs {
            src: &src,
            pyr: &pyr,
            params: p,
            frame: self.frame,
            prev: match (&shifted, &prev_here) {
                (Some(shifted), Some(prev)) if has_prev => Some((shifted, &prev.masks[..])),
                _ => None,
            },
            debug: self.debug,
        };
        let mut out = pyramid::run(&inputs, &mut st);
        if self.frame == 0 && self.params.parts.repaint_first {
            out = self.repaint_first(out, &src, &pyr, win, &mut st);
        }
        let place = Placement { full: (w, h), win };
        let rgb = place.uncrop(&out.rgb, src.paper);
        let debug = self.debug.then(|| DebugViews {
            nnf: place.nnf_colors(&out.field, &src.levels[0]),
            omega: out.omega.unwrap_or_else(|| Plane::new(1, 1)),
            field: place.raw(&out.field),
            shifted: shifted.as_ref().map(|f| place.raw(f)).unwrap_or_else(|| Plane::filled(w, h, [f32::NAN; 4])),
        });
        let g0 = &pyr[0];
        self.prev = Some(PrevState::new(win, out.field, g0, out.masks));
        self.frame += 1;
        Ok(SynthFrame {
            rgb,
            mask: g.mask.clone(),
            level_times: out.level_times,
            stages: st,
            evaluations: out.evaluations,
            energy: out.energy,
            debug,
        })
    }

    /// The first frame painted again from its first painting `first` carried onto itself
    /// ([`ParamsBuilder::repaint_first`]): SHIFTNNF with no motion and the exemplar's time
    /// held, then the search with the parameters of every later frame.
    fn repaint_first(
        &self,
        first: pyramid::FrameOutcome,
        src: &SourcePyramid,
        pyr: &[FrameGuides],
        win: (usize, usize, usize, usize),
        st: &mut StageTimes,
    ) -> pyramid::FrameOutcome {
        let mut state = PrevState::new(win, first.field, &pyr[0], first.masks);
        state.flow.fill(glam::Vec2::ZERO);
        let carried = timed(&mut st.shift, || shift_previous(src, &self.params, &pyr[0], &state, true));
        let inputs = pyramid::FrameInputs {
            src,
            pyr,
            params: &self.params,
            frame: self.frame,
            prev: Some((&carried, &state.masks[..])),
            debug: self.debug,
        };
        let mut out = pyramid::run(&inputs, st);
        out.evaluations += first.evaluations;
        for (t, t0) in out.level_times.iter_mut().zip(&first.level_times) {
            *t += *t0;
        }
        out
    }

    /// Starts the sequence at a frame whose picture is the source itself: a painted keyframe
    /// ([`keyframes`]), whose source is the painting of this very frame `g` (same size). Nothing
    /// is synthesized; the frame's field becomes the identity — every target pixel inside the
    /// mask matches its own position in the source, where that is a valid center — and the
    /// next [`Synthesizer::step`] carries it along the target's motion like any previous field.
    /// Counts as a frame.
    pub fn begin_at_source(&mut self, g: &FrameGuides) -> Result<()> {
        g.check("target guides")?;
        let (w, h) = g.mask.size();
        let s0 = &self.source.pyramid.levels[0];
        if (s0.w, s0.h) != (w, h) {
            return Err(Error::param(
                "keyframe size",
                format!("{}x{}", s0.w, s0.h),
                format!("{w}x{h}, the size of the target's frames"),
            ));
        }
        self.size = Some((w, h));
        self.frame += 1;
        let levels = self.level_count(w, h);
        let Some(win) = window(&g.mask, 1 << (levels - 1)) else {
            self.prev = None;
            return Ok(());
        };
        let pyr = self.target_pyramid(g, win, levels);
        let s0 = &self.source.pyramid.levels[0];
        let mut field = Nnf::new(win.2, win.3);
        for y in 0..win.3 {
            for x in 0..win.2 {
                let (gx, gy) = ((win.0 + x) as f32, (win.1 + y) as f32);
                let valid = s0.nearest(0, gx, gy).is_some_and(|idx| s0.is_valid(None, idx));
                if pyr[0].mask.get(x, y) && valid {
                    field.data[y * win.2 + x] =
                        nnf::Match { x: gx, y: gy, c: 1.0, s: 0.0, err: 0.0, i: 0, flip: false, ok: true };
                }
            }
        }
        let masks = pyr.iter().map(|l| l.mask.data().to_vec()).collect();
        self.prev = Some(PrevState::new(win, field, &pyr[0], masks));
        Ok(())
    }

    /// The target's guides cropped to the working window `win`, their extents brought to the
    /// exemplar's scale ([`ParamsBuilder::ext_normalize`]), and their pyramid of `levels`
    /// levels, finest first.
    fn target_pyramid(
        &mut self,
        g: &FrameGuides,
        win: (usize, usize, usize, usize),
        levels: usize,
    ) -> Vec<FrameGuides> {
        let mut cropped = crop_guides(g, win);
        let k = match self.ext_factor {
            Some(k) => k,
            None => {
                let e_t = self.target_extent.unwrap_or_else(|| crate::guide::extent_scale(std::slice::from_ref(g)));
                *self.ext_factor.insert(self.extent_factor_for(e_t))
            }
        };
        if k != 1.0 {
            cropped.ext_pos = cropped.ext_pos.map(|v| v * k);
            cropped.ext_neg = cropped.ext_neg.map(|v| v * k);
        }
        let mut pyr: Vec<FrameGuides> = Vec::with_capacity(levels);
        pyr.push(cropped);
        for l in 1..levels {
            let next = pyr[l - 1].downsample2();
            pyr.push(next);
        }
        pyr
    }

    /// The parameters of the first frame. It starts from a random field: its search runs
    /// without the coherence factor κ, which would keep random matches against better ones
    /// (Params::coherence), and against the averaged estimate of the output's vote: the
    /// estimate of each pixel's own match (Params::estimate_sigma) would hold the random
    /// field's mosaic in place.
    fn first_frame_params(&self) -> Params {
        let mut p = self.params.clone();
        p.weights.coherence = 1.0;
        p.schedule.estimate_sigma = p.schedule.vote_sigma;
        p
    }
}

/// SHIFTNNF of the previous frame's field `prev` into the current frame `g` (the finest level
/// of its pyramid), at full resolution; with `hold_time`, every match keeps its exemplar frame.
fn shift_previous(src: &SourcePyramid, p: &Params, g: &FrameGuides, prev: &PrevState, hold_time: bool) -> Nnf {
    let active: Vec<bool> = source::dilate(&g.mask, HALF).into_vec();
    let change = shift::AreaChange::of(g.mask.data(), &prev.masks[0]);
    let moves = change.moves_rather_than_grows();
    let travel_hold = p.parts.travel_hold && p.parts.full_carry && p.parts.advect && change.travels();
    let (w, h) = g.mask.size();
    let resting: Vec<bool> = if p.parts.resting_normal {
        (0..w * h).map(|q| target::resting_normal(g, q % w, q / w).is_some()).collect()
    } else {
        Vec::new()
    };
    let inputs = shift::ShiftInputs {
        carry_new: moves,
        src: &src.levels[0],
        ext_prev: &prev.ext_pos,
        ext_cur: g.ext_pos.data(),
        flow_prev: &prev.flow,
        flow_cur: g.flow.data(),
        dist_cur: g.dist.data(),
        band: src.border_width,
        step_cost: shift::step_cost(src.ext_scale, src.levels[0].frames),
        active: &active,
        time_shift: p.parts.time_shift,
        advect: p.parts.advect,
        settle: p.parts.settle,
        receding_hold: p.parts.receding_hold,
        age: p.parts.aging,
        hold_time,
        max_step: if moves && p.parts.pace && p.parts.advect { 1 } else { usize::MAX },
        full_carry: moves && p.parts.full_carry,
        travel_hold,
        // Read only where the shape travels.
        moving: travel_hold && shift::all_rim(g.dist.data(), src.border_width) && shift::moves_noticeably(&prev.flow),
        turn: p.turns(src.levels[0].frames),
        resting: &resting,
    };
    shift::shift_nnf(&inputs, &prev.nnf0)
}

/// Where the working window lies in the full frame: for putting its results back.
struct Placement {
    /// The full frame's size.
    full: (usize, usize),
    /// The window `(x0, y0, w, h)`.
    win: (usize, usize, usize, usize),
}

impl Placement {
    /// The window coordinates of full-frame pixel (x, y), if it lies in the window.
    fn inside(&self, x: usize, y: usize) -> Option<(usize, usize)> {
        let (x0, y0, w, h) = self.win;
        (x >= x0 && y >= y0 && x < x0 + w && y < y0 + h).then(|| (x - x0, y - y0))
    }

    /// The window's colors `rgb` placed in a full frame of `paper`.
    fn uncrop(&self, rgb: &[Rgb], paper: Rgb) -> Plane<Rgb> {
        let w = self.win.2;
        Plane::from_fn(self.full.0, self.full.1, |x, y| match self.inside(x, y) {
            Some((cx, cy)) => rgb.get(cy * w + cx).copied().unwrap_or(paper),
            None => paper,
        })
    }

    /// `f(match)` of every full-frame pixel whose field `field` has a match there, else `none`.
    fn map_field<T: Copy>(&self, field: &Nnf, none: T, f: impl Fn(&nnf::Match) -> T) -> Plane<T> {
        Plane::from_fn(self.full.0, self.full.1, |x, y| match self.inside(x, y).map(|(x, y)| field.get(x, y)) {
            Some(m) if m.ok => f(m),
            _ => none,
        })
    }

    /// The field as colors ([`DebugViews::nnf`]).
    fn nnf_colors(&self, field: &Nnf, s0: &source::SourceLevel) -> Plane<Rgb> {
        self.map_field(field, [0.0; 3], |m| {
            [m.x / s0.w as f32, m.y / s0.h as f32, m.i as f32 / (s0.frames - 1).max(1) as f32]
        })
    }

    /// The field itself per full-frame pixel ([`DebugViews::field`]).
    fn raw(&self, field: &Nnf) -> Plane<[f32; 4]> {
        self.map_field(field, [f32::NAN; 4], |m| [m.i as f32, m.x, m.y, m.s.atan2(m.c)])
    }
}

/// The working window `(x0, y0, w, h)` of a frame: the mask's bounding box grown by a margin of
/// `(⌊n/2⌋ + 1)·align + 4` pixels, its corner aligned to multiples of `align` (2^(levels−1), so
/// every pyramid level of the window starts on a whole pixel). The margin is what a patch of
/// the coarsest level reaches beyond the mask: with less, coarse target patches near the edge
/// read the arrays' clamp-to-edge padding where the exemplar's read real surroundings, and
/// even a target equal to an exemplar frame would not match it exactly. `None` for an empty
/// mask.
fn window(mask: &Mask, align: usize) -> Option<(usize, usize, usize, usize)> {
    let (w, h) = mask.size();
    let crate::img::Rect { x0, y0, x1, y1 } = mask.bounding_box()?;
    let m = (HALF + 1) * align + 4;
    let (x0, y0) = (x0.saturating_sub(m) / align * align, y0.saturating_sub(m) / align * align);
    let (x1, y1) = ((x1 + m).min(w), (y1 + m).min(h));
    Some((x0, y0, x1 - x0, y1 - y0))
}

/// The guides inside a window.
fn crop_guides(g: &FrameGuides, (x0, y0, w, h): (usize, usize, usize, usize)) -> FrameGuides {
    FrameGuides {
        mask: g.mask.crop(x0, y0, w, h, false),
        dist: g.dist.crop(x0, y0, w, h, -1.0),
        flow: g.flow.crop(x0, y0, w, h, glam::Vec2::ZERO),
        ext_pos: g.ext_pos.crop(x0, y0, w, h, 0.0),
        ext_neg: g.ext_neg.crop(x0, y0, w, h, 0.0),
    }
}

/// The previous frame's state re-indexed into the current window (origin `to`, full
/// resolution) whose pyramid is `pyr`; what lies outside the previous window is empty.
fn rewindow(prev: &PrevState, to: (usize, usize), pyr: &[FrameGuides]) -> PrevState {
    let (fx, fy) = prev.origin;
    let (w, h) = pyr[0].mask.size();
    let map = |x: usize, y: usize, scale: usize, pw: usize, ph: usize| -> Option<usize> {
        let (gx, gy) = (to.0 / scale + x, to.1 / scale + y);
        let (px, py) = (gx.checked_sub(fx / scale)?, gy.checked_sub(fy / scale)?);
        (px < pw && py < ph).then_some(py * pw + px)
    };
    let mut nnf0 = Nnf::new(w, h);
    let mut ext_pos = vec![0.0; w * h];
    let mut flow = vec![glam::Vec2::ZERO; w * h];
    for y in 0..h {
        for x in 0..w {
            if let Some(k) = map(x, y, 1, prev.nnf0.w, prev.nnf0.h) {
                nnf0.data[y * w + x] = prev.nnf0.data[k];
                ext_pos[y * w + x] = prev.ext_pos[k];
                flow[y * w + x] = prev.flow[k];
            }
        }
    }
    let (pw0, ph0) = (prev.nnf0.w, prev.nnf0.h);
    let masks = pyr
        .iter()
        .enumerate()
        .map(|(l, g)| {
            let (lw, lh) = g.mask.size();
            let scale = 1 << l;
            let (pw, ph) = (pw0.div_ceil(scale), ph0.div_ceil(scale));
            let old = prev.masks.get(l);
            (0..lh)
                .flat_map(|y| (0..lw).map(move |x| (x, y)))
                .map(|(x, y)| match (old, map(x, y, scale, pw, ph)) {
                    (Some(m), Some(k)) => m.get(k).copied().unwrap_or(false),
                    _ => false,
                })
                .collect()
        })
        .collect();
    PrevState { origin: to, nnf0, ext_pos, flow, masks }
}

#[cfg(test)]
mod tests;
