//! The Fluidymation synthesis engine (paper §3 and Appendix B, thesis ch. 3–4).
//!
//! For every target frame j, in order, a coarse-to-fine pyramid of EM iterations finds a
//! nearest-neighbour field into the whole exemplar sequence — frame i, sub-pixel position,
//! rotation θ — that minimizes the guided patch error D ([`patch`]), and votes the frame's
//! colors from it ([`vote`]). Temporal coherence comes from the previous frame's field,
//! shifted along the exemplar's own time axis ([`shift`]), which both initializes the search
//! and votes the temporal guide `T^prev`. A 3D occurrence map keeps the use of exemplar
//! patches uniform ([`occurrence`]).
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
mod nnf;
mod occurrence;
mod params;
mod patch;
mod patchmatch;
mod rng;
mod shift;
mod source;
mod target;
mod vote;

pub use params::{HALF, PATCH, Params, ParamsBuilder};
pub use patchmatch::Stats;
pub use source::SourcePyramid;

use crate::error::{Error, Result};
use crate::exemplar::Exemplar;
use crate::guide::{self, FrameGuides};
use crate::img::{self, Mask, Plane, Rgb};
use nnf::{Match, Nnf, level_count};
use patchmatch::Ctx;
use rayon::prelude::*;
use rng::Rng;
use source::{MARGIN, SourceLevel};
use std::sync::Arc;
use std::time::{Duration, Instant};
use target::TargetLevel;

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
    pub fn prepare(ex: &Exemplar, params: &Params) -> Result<Source> {
        let scale = params.src_scale.unwrap_or(ex.meta.scale);
        let speed = params.src_speed.unwrap_or(ex.meta.speed).max(1);
        let (frames, masks) = resample_exemplar(ex, scale, speed);
        if frames.len() < 2 {
            return Err(Error::param(
                "src-speed",
                speed,
                format!("a step that leaves at least 2 of the exemplar's {} frames", ex.len()),
            ));
        }
        let guides = guide::compute_sequence(&masks, &params.guide)?;
        Self::from_parts(&frames, &guides, params, params.border_width.unwrap_or(ex.meta.border_width * scale))
    }

    /// Prepares a source from frames and precomputed guides.
    pub fn from_parts(
        frames: &[Plane<Rgb>],
        guides: &[FrameGuides],
        params: &Params,
        border_width: f32,
    ) -> Result<Source> {
        if frames.len() < 2 || frames.len() != guides.len() {
            return Err(Error::param("exemplar frames", frames.len(), "at least 2 frames, each with guides"));
        }
        if frames.len() > u16::MAX as usize {
            return Err(Error::param("exemplar frames", frames.len(), "at most 65535"));
        }
        let (w, h) = frames[0].size();
        if w < 2 * MARGIN + 2 || h < 2 * MARGIN + 2 {
            return Err(Error::param("exemplar size", format!("{}x{}", w, h), "at least 8x8 pixels"));
        }
        if !(border_width.is_finite() && border_width > 0.0) {
            return Err(Error::param("border-width", border_width, "a positive number of pixels"));
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
    /// Patch-error evaluations in this frame.
    pub evaluations: u64,
    /// The energy E = Σ_q D(NNF(q), q) (mean per active pixel) at the start of every
    /// PatchMatch sweep and after the last one, per level: `(level, E)`, coarsest first.
    pub energy: Vec<(usize, f64)>,
    /// Debug views, when enabled with [`Synthesizer::set_debug`].
    pub debug: Option<DebugViews>,
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
}

fn mean_err(nnf: &Nnf) -> f64 {
    let (mut s, mut n) = (0.0f64, 0usize);
    for m in &nnf.data {
        if m.ok && m.err.is_finite() {
            s += m.err as f64;
            n += 1;
        }
    }
    if n > 0 { s / n as f64 } else { 0.0 }
}

/// What is carried from one frame to the next.
struct PrevState {
    /// Final full-resolution field of the previous frame.
    nnf0: Nnf,
    /// `T^ext+` of the previous frame.
    ext_pos: Vec<f32>,
    /// The previous frame's masks per level.
    masks: Vec<Vec<bool>>,
}

/// Synthesizes a target sequence frame by frame ([`Synthesizer::step`]).
pub struct Synthesizer {
    params: Params,
    source: Source,
    frame: usize,
    prev: Option<PrevState>,
    size: Option<(usize, usize)>,
    debug: bool,
}

impl Synthesizer {
    /// A synthesizer for one target sequence (one layer).
    pub fn new(source: Source, params: Params) -> Result<Synthesizer> {
        Ok(Synthesizer { params, source, frame: 0, prev: None, size: None, debug: false })
    }

    /// Also produce [`DebugViews`] with every frame.
    pub fn set_debug(&mut self, on: bool) {
        self.debug = on;
    }

    /// Index of the next frame.
    pub fn frame(&self) -> usize {
        self.frame
    }

    fn level_count(&self, w: usize, h: usize) -> usize {
        let src = &self.source.pyramid;
        let auto = level_count(w.min(h).min(src.size.0).min(src.size.1)).min(src.levels.len());
        self.params.levels.map(|l| l.min(src.levels.len())).unwrap_or(auto).max(1)
    }

    /// Synthesizes the next frame from its guides (frames must come in order and all have
    /// the same size).
    pub fn step(&mut self, g: &FrameGuides) -> Result<SynthFrame> {
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
        let mut pyr: Vec<FrameGuides> = Vec::with_capacity(levels);
        pyr.push(g.clone());
        for l in 1..levels {
            let next = pyr[l - 1].downsample2();
            pyr.push(next);
        }
        let src = self.source.pyramid.clone();
        let p = &self.params;
        let b = src.border_width;
        let ext_cap = p.ext_clamp.then_some(src.ext_max);
        let paper = src.paper;

        // SHIFTNNF of the previous frame's field, at full resolution.
        let active0: Vec<bool> = source::dilate(&g.mask, HALF).into_vec();
        let shifted0 = self.prev.as_ref().map(|prev| {
            shift::shift_nnf(&src.levels[0], &prev.nnf0, &prev.ext_pos, g.ext_pos.data(), &active0, p.time_shift)
        });
        let has_prev = shifted0.as_ref().is_some_and(|n| n.data.iter().any(|m| m.ok));

        let mut level_times = Vec::with_capacity(levels);
        let mut evaluations = 0u64;
        let mut nnf: Option<Nnf> = None;
        let mut masks = vec![Vec::new(); levels];
        let mut final_rgb = Vec::new();
        let mut energy = Vec::new();
        let mut omega_view: Option<Plane<f32>> = None;
        for l in (0..levels).rev() {
            let t0 = Instant::now();
            let from_coarsest = levels - 1 - l;
            let sl = &src.levels[l];
            let gl = &pyr[l];
            let (lw, lh) = gl.mask.size();
            let mut tgt = TargetLevel::new(gl, &src.quant, b, ext_cap, paper);
            masks[l] = shift::mask_flags(&tgt);
            let keys = |it: u64| [p.seed, self.frame as u64, l as u64, it];
            // Temporal guide T^prev and m(q) from the down-scaled shifted field.
            let prev_down = if has_prev {
                let shifted = shifted0.as_ref().map(|s| s.downscale(l, lw, lh));
                if let (Some(sd), Some(prev)) = (&shifted, &self.prev) {
                    let voted = vote::vote(sl, sd, paper, p.vote_sigma);
                    write_lanes(&mut tgt, &voted, false);
                    shift::fill_modulation(&mut tgt, sl, sd, &prev.masks[l], b, p.prev_bounds, p.w_prev);
                }
                shifted
            } else {
                None
            };
            let no_omega = vec![0.0f32; sl.feat.len()];
            let finest_vote_only = l == 0 && levels > 1 && !p.optimize_finest;
            // Initialization.
            let mut field = match nnf.take() {
                None => {
                    let mut f = prev_down.clone().unwrap_or_else(|| Nnf::new(lw, lh));
                    let had_prev = prev_down.is_some();
                    sanitize(&mut f, sl, &tgt);
                    let ctx = Ctx { src: sl, tgt: &tgt, omega: &no_omega, w_col: 1.0, params: p, keys: keys(u64::MAX) };
                    fill_holes(&ctx, &mut f);
                    if !had_prev {
                        // First frame: random field, then one guide-only PatchMatch pass (thesis §4.2).
                        let ctx = Ctx { w_col: 0.0, ..ctx };
                        patchmatch::refresh_errors(&ctx, &mut f);
                        evaluations += patchmatch::sweep(&ctx, &mut f, 0).evaluations;
                    }
                    f
                }
                Some(coarse) => {
                    let mut up = coarse.upscale(lw, lh);
                    sanitize(&mut up, sl, &tgt);
                    if !finest_vote_only {
                        let ctx =
                            Ctx { src: sl, tgt: &tgt, omega: &no_omega, w_col: 1.0, params: p, keys: keys(u64::MAX) };
                        fill_holes(&ctx, &mut up);
                    }
                    if let Some(mut pd) = prev_down.clone() {
                        if !finest_vote_only {
                            sanitize(&mut pd, sl, &tgt);
                        }
                        // MERGENNF: per pixel, the field with the smaller error (against the
                        // estimate voted from the up-scaled field).
                        let voted = vote::vote(sl, &up, paper, p.vote_sigma);
                        write_lanes(&mut tgt, &voted, true);
                        let omega = if finest_vote_only {
                            no_omega.clone()
                        } else {
                            occurrence::penalty(sl, &up, &tgt, p.occ_radius, p.lambda)
                        };
                        let ctx = Ctx { src: sl, tgt: &tgt, omega: &omega, w_col: p.w_color, params: p, keys: keys(0) };
                        merge(&ctx, &mut up, &pd);
                        evaluations += 2 * tgt.active.len() as u64;
                    }
                    up
                }
            };
            if !finest_vote_only {
                let voted = vote::vote(sl, &field, paper, p.vote_sigma);
                write_lanes(&mut tgt, &voted, true);
                for opt in 0..p.opt_iters_at(from_coarsest) {
                    for it in 0..p.pm_iters_at(from_coarsest) {
                        let omega = occurrence::penalty(sl, &field, &tgt, p.occ_radius, p.lambda);
                        let ctx = Ctx {
                            src: sl,
                            tgt: &tgt,
                            omega: &omega,
                            w_col: p.w_color,
                            params: p,
                            keys: keys(opt as u64),
                        };
                        patchmatch::refresh_errors(&ctx, &mut field);
                        energy.push((l, mean_err(&field)));
                        evaluations += tgt.active.len() as u64;
                        evaluations += patchmatch::sweep(&ctx, &mut field, it).evaluations;
                    }
                    energy.push((l, mean_err(&field)));
                    let voted = vote::vote(sl, &field, paper, p.vote_sigma);
                    write_lanes(&mut tgt, &voted, true);
                }
            }
            if !finest_vote_only && self.debug {
                let counts = occurrence::counts(sl, &field, &tgt, p.occ_radius);
                let norm = ((PATCH * PATCH) * (2 * p.occ_radius + 1)) as f32;
                omega_view = Some(Plane::from_fn(sl.w, sl.h, |x, y| {
                    (0..sl.frames).map(|i| counts[sl.index(i, x, y)] as f32).sum::<f32>() / norm
                }));
            }
            if l == 0 {
                // The output: bicubic sampling keeps rotated patches sharper than bilinear.
                final_rgb = vote::vote_with(sl, &field, paper, p.vote_sigma, true);
            }
            nnf = Some(field);
            level_times.push(t0.elapsed());
        }
        let field = nnf.unwrap_or_else(|| Nnf::new(w, h));
        let rgb = Plane::from_vec(w, h, final_rgb).unwrap_or_else(|| Plane::filled(w, h, paper));
        let debug = self.debug.then(|| {
            let s0 = &src.levels[0];
            let nnf = Plane::from_fn(w, h, |x, y| {
                let m = field.get(x, y);
                if !m.ok {
                    return [0.0; 3];
                }
                [m.x / s0.w as f32, m.y / s0.h as f32, m.i as f32 / (s0.frames - 1).max(1) as f32]
            });
            DebugViews { nnf, omega: omega_view.unwrap_or_else(|| Plane::new(1, 1)) }
        });
        self.prev = Some(PrevState { nnf0: field, ext_pos: g.ext_pos.data().to_vec(), masks });
        self.frame += 1;
        Ok(SynthFrame { rgb, mask: g.mask.clone(), level_times, evaluations, energy, debug })
    }
}

/// Writes voted colors into the rgb lanes of `T^rgb` (`cur`) or `T^prev` (`!cur`).
fn write_lanes(tgt: &mut TargetLevel, rgb: &[Rgb], cur: bool) {
    let (w, stride) = (tgt.w, tgt.stride);
    let pad = target::TPAD;
    let arr = if cur { &mut tgt.cur } else { &mut tgt.prev };
    arr.par_chunks_mut(stride).enumerate().for_each(|(py, row)| {
        if py < pad || py >= pad + rgb.len() / w {
            return;
        }
        let y = py - pad;
        for x in 0..w {
            let c = rgb[y * w + x];
            let px = &mut row[x + pad];
            // Quantization units of the color lanes: 0..=255.
            px[0] = c[0] * 255.0;
            px[1] = c[1] * 255.0;
            px[2] = c[2] * 255.0;
        }
    });
}

/// Makes every match usable by the kernel: drops matches of inactive pixels, clamps frame
/// indices and centers into the valid margin (centers may have drifted out through
/// up-scaling or the time shift). θ is kept, as the paper keeps it through UPSCALENNF and
/// SHIFTNNF.
fn sanitize(nnf: &mut Nnf, src: &SourceLevel, tgt: &TargetLevel) {
    let (xmax, ymax) = ((src.w - 1 - MARGIN) as f32, (src.h - 1 - MARGIN) as f32);
    let last = (src.frames - 1) as u16;
    nnf.data.par_iter_mut().zip(tgt.info.par_iter()).for_each(|(m, inf)| {
        if inf.flags & source::VALID == 0 {
            *m = Match::NONE;
            return;
        }
        if m.ok {
            m.x = m.x.clamp(MARGIN as f32, xmax);
            m.y = m.y.clamp(MARGIN as f32, ymax);
            m.i = m.i.min(last);
            m.err = f32::INFINITY;
        }
    });
}

/// Gives every active pixel without a match a random one.
fn fill_holes(ctx: &Ctx, nnf: &mut Nnf) {
    let w = nnf.w;
    nnf.data.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, m) in row.iter_mut().enumerate() {
            let q = y * w + x;
            if !m.ok && ctx.tgt.info[q].flags & source::VALID != 0 {
                let mut rng = Rng::keyed(&[ctx.keys[0], ctx.keys[1], ctx.keys[2], 0x5eed, q as u64]);
                *m = ctx.random_match(q, &mut rng);
            }
        }
    });
}

/// MERGENNF: keeps, per pixel, whichever of `up` and `prev` has the smaller patch error.
fn merge(ctx: &Ctx, up: &mut Nnf, prev: &Nnf) {
    let w = up.w;
    up.data.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, m) in row.iter_mut().enumerate() {
            let q = y * w + x;
            let pm = &prev.data[q];
            if !pm.ok {
                continue;
            }
            let eu = ctx.error_of(q, m);
            let ep = ctx.error_of(q, pm);
            if ep < eu {
                *m = Match { err: ep, ..*pm };
            } else {
                m.err = eu;
            }
        }
    });
}

#[cfg(test)]
mod tests;
