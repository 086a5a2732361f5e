//! The flow field `I^flow` estimated from the masks (paper Appendix A, thesis §3.8, §4.1).
//!
//! **Frame convention.** `flow(i)` is the motion from frame `i` to frame `i+1`, defined on the
//! mask of frame `i`. With it the paper's recurrences (§3.3) read exactly as written:
//! `acc+(i) = acc+(i−1) + flow(i−1)` sums the motion `0 → i` that brought the material to frame
//! `i`, and `acc−(i) = acc−(i+1) + flow(i)` sums the motion `i → last` still to come. (Appendix A
//! writes the estimate at frame `i` from `dist_i − dist_{i−1}`, the motion `i−1 → i`; used in those
//! recurrences it would lag one frame behind.) The last frame's flow carries on the motion that
//! brought it (its velocity is measured backwards, step 2): nothing follows it, but what arrived
//! at it moved. The raw
//! field `F_i` of step 2–4 is a velocity *at* frame `i` (a central difference); the flow of
//! frame `i` is the mean of the velocities at `i` and `i + 1` (step 5), the trapezoid rule for
//! the motion between them.
//!
//! **Construction, per frame `i` with a non-degenerate mask** (neither empty nor full):
//!
//! 1. Temporal smoothing of the distance fields (thesis §4.1): `D̃_i = Σ_k g_k · dist_{i+k}`, a
//!    Gaussian of σ_t = `time_blur_sigma` frames (radius ⌈3σ_t⌉). Frames beyond the sequence, or
//!    beyond a run of frames whose masks are non-degenerate, are replaced by the nearest frame of
//!    the run (edges replicated): an empty or full mask has no meaningful distance field, so a
//!    layer that appears or vanishes does not get a burst of fake motion. **The averages and
//!    differences below read only real frames of the run** (an addition): a replicated end is a
//!    frame in which nothing moved, and averaging it in under-reported the motion of the first
//!    and last frames of every moving shape — the first three and last three flows of the quality
//!    suite's 24-frame targets (512²) had a mean error of 0.82 px (translating, 3.1 px a frame),
//!    0.65 (growing), 0.52 (shrinking), 1.26 (turning ellipse), 1.12 (limb); with real frames
//!    only, 0.19, 0.11, 0.09, 0.52, 0.85 (the middle frames 0.06, 0.03, 0.03, 0.45, 0.26).
//!
//!    **Per boundary pixel, the window is cut to the frames that fit** (an addition). The
//!    average and the difference below assume that the edge a boundary pixel `b` lies on moves
//!    like a straight front: in frame `i + k`, `b` is outside the mask, or inside with its
//!    distance counted from that same edge. A part that moves farther than its half thickness
//!    within the window — a thin arm or leg swinging fast — breaks it: past the part's middle
//!    `dist_{i+k}(b)` is counted from the part's *other* edge (the gradient of `dist_{i+k}`
//!    points outward along `b`'s normal), and averaging such frames, or differencing them,
//!    under-reports the motion (a 14-px limb swinging at up to 11 px a frame got 32–64 % of its
//!    true motion; a 12-px bar moving 8 px a frame, 28 %). So `b` averages over `k = −r ..= r + 1`
//!    with the largest `r ≤ ⌈3σ_t⌉` whose frames all fit, the kernel cut and normalized again;
//!    where frame `i + 1` itself does not fit, `b`'s speed is not measured at all and the part's
//!    fitted motion (step 3) stands in for it. A shape that moves less than its half thickness
//!    over the window keeps the whole window. For the central difference of step 2 the window
//!    is `k = −1−r ..= 1+r` and takes a frame only where its nearest edge to `b` also lies
//!    within 45° of `b`'s normal: a small round part that has moved farther than its radius is
//!    nearest to `b` at its side, and its distance there grows with the distance travelled in
//!    any direction (the quality suite's 14-px limb, with the flows of step 5 smoothed at the
//!    pixel: mean flow error 0.29 px with the angle test, 0.64 px without, 0.73 px with the
//!    forward difference; `Task::estimate_at`).
//! 2. Boundary pixels `B_i`: mask pixels with a 4-neighbour, inside the image, that is not in the
//!    mask (the image edge is not a material boundary). At `b ∈ B_i` the outward normal is
//!    `n = −∇D̃_i / |∇D̃_i|` (central differences, one-sided at the image edge) and the normal speed
//!    is the central difference `s = (D̃_{i+1}(b) − D̃_{i−1}(b)) / 2g` (an addition), `g` the
//!    mean of `|∇D̃_{i−1}(b)|` and `|∇D̃_{i+1}(b)|` clamped to `[0.9, 1]` (an addition: a field
//!    moving at speed v changes by `|∇D̃|·(n·v)`, and an average of distance fields whose
//!    normals differ a little has a gradient a little shorter than 1; see `MIN_SLOPE`). A
//!    curved front of radius `R` that moves by `v` changes its distance at `b` by about
//!    `n·v − (|v|² − (n·v)²)/2R`: the paper's forward difference `D̃_{i+1} − D̃_i` reads a small
//!    round part moving along itself as slower than it is (the 12-px bar's round ends, the tip
//!    of a limb), while in the central difference the second-order term cancels. Over a
//!    temporal window in which the part moves past its own radius the distance is no longer
//!    near that expansion, hence the angle test of step 1 (flows smoothed at the pixel in step 5:
//!    a 7-px disc at 3.7 px a frame gets
//!    0.865 of its speed with the forward difference, 0.870 with the central one, 0.907 with
//!    the angle test too; the rest is of third order and beyond). Where frame
//!    `i − 1` does not fit, or is a replicated end of the run, the forward difference stands in
//!    for it; at the last frame of the run, where frame `i + 1` is the replicated end, the
//!    backward difference `dist_i − dist_{i−1}`. The boundary flow is `s · n`. This is Appendix A's
//!    `(dist_i − dist_{i−1}) ∇dist_i / |∇dist_i|` with one sign flipped: for a distance that is
//!    *positive inside*, a growing mask has a rising distance and a gradient pointing inwards, so
//!    the paper's expression as printed points inwards; `−∇` is the outward direction.
//! 3. Tangential component (an addition, [`super::GuideParams::tangential_fit`]): the boundary
//!    only reveals the normal part of the motion (the aperture problem), so a shape that
//!    translates would get only half of its velocity in the middle (the harmonic extension of
//!    `(n·u) n` on a circle is `u/2` at the centre). For each 4-connected part of the mask an
//!    affine motion `v(p) = A p + c` is fitted to the normal speeds by least squares,
//!    `min Σ_b (n_b · v(b) − s_b)²` (with a small ridge term), where the normal speeds determine
//!    it; along the modes they do not observe (an ellipse turning about its centre looks like one
//!    shearing along its outline; the rotation of a disc shows nothing at all) the motion is
//!    taken as rigid as possible — the least strain, a disc's rotation zero (see `Affine::fit`,
//!    an addition). The boundary value becomes
//!    `s n + (v − (v·n) n)`: measured normal part, fitted tangential part. Pure growth keeps
//!    `s n`; a translation gets its full velocity. The fit uses the boundary pixels whose speed
//!    was measured (all of them if fewer than three were), and those whose speed was not get
//!    the fitted motion `v` whole.
//! 4. Interior values: Laplace's equation with the boundary values fixed, solved by multigrid
//!    ([`super::laplace`]) inside the mask's bounding box, starting from the fitted affine field,
//!    to the tolerance [`super::GuideParams::laplace_tolerance`].
//! 5. Temporal smoothing of the flow sequence (Appendix A, radius `flow_time_radius`, σ =
//!    radius/3), along the motion and normalized over the frames whose mask holds the point:
//!    `flow(i, p) = Σ_k g_k [q_k ∈ mask_{i+k}] F_{i+k}(q_k) / Σ_k g_k [q_k ∈ mask_{i+k}]` with
//!    `q_k = p + k·F_i(p)` (an addition; the paper averages at `p`, bilinear here over the
//!    pixels of `mask_{i+k}`). Averaging in the zeros of frames where the pixel was still paper
//!    would shrink the flow at every moving front; averaging at `p` mixes in the velocity of
//!    whatever part of the shape lies there in the other frames — on a growing shape a
//!    slower one, since the field at a fixed pixel slows as the shape grows (growing ellipse:
//!    mean error 0.075 px at `p`, 0.051 along the motion; limb 0.289 and 0.244; turning
//!    ellipse 0.465 and 0.462; shrinking ellipse 0.040 and 0.049). The Gaussian is centred
//!    half a frame ahead, `g_k ∝ exp(−(k − ½)²/2σ²)` over
//!    `k = 1 − radius ..= radius` (an addition; radius 0 is taken as 1, the plain mean of
//!    `F_i` and `F_{i+1}`): the velocities at frames `i` and `i + 1` weigh alike, so the flows
//!    sum to the motion — a disc that moves 24 px and back ends with its accumulated extent at
//!    0.22 px (median) instead of 1.40 px with the centred kernel.
//!
//! Outside the mask the flow is zero. Everything is deterministic and independent of the number
//! of threads and of the order frames are visited in (forward for [`super::compute_sequence`],
//! backward in segments for [`super::GuideStream`]).

use super::GuideParams;
use super::crop::{Crop, FrameMask, Rect};
use super::laplace::{self, Cell};
use crate::error::{Error, Result};
use crate::img::{Mask, Plane, gaussian_kernel};
use glam::{DVec2, Vec2};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::sync::Arc;

/// The final flow fields of a sequence of pre-processed masks (as [`super::preprocess_mask`]
/// returns them), one per frame, following the construction in the module docs.
pub fn estimate_sequence(masks: &[Mask], params: &GuideParams) -> Result<Vec<Plane<Vec2>>> {
    params.validate()?;
    let Some(first) = masks.first() else { return Ok(Vec::new()) };
    let (w, h) = first.size();
    let frames: Vec<Arc<FrameMask>> = masks
        .iter()
        .enumerate()
        .map(|(i, m)| {
            check_size(m.size(), (w, h), "mask", i)?;
            Ok(Arc::new(FrameMask::from_full(m)))
        })
        .collect::<Result<_>>()?;
    let mut provider = SliceProvider { masks: &frames };
    let mut machine = FlowMachine::new(frames.len(), true, 0, frames.len() - 1, params);
    let mut out = Vec::with_capacity(frames.len());
    while let Some((_, _, f)) = machine.next_output(&mut provider)? {
        out.push(f.to_full(w, h));
    }
    Ok(out)
}

pub(crate) fn check_size(found: (usize, usize), expected: (usize, usize), what: &str, frame: usize) -> Result<()> {
    if found == expected {
        Ok(())
    } else {
        Err(Error::param(
            what,
            format!("{}x{} at frame {}", found.0, found.1, frame),
            format!("every frame of the sequence to be {}x{}", expected.0, expected.1),
        ))
    }
}

/// Hands frame masks to the [`FlowMachine`].
pub(crate) trait MaskProvider {
    fn mask(&mut self, i: usize) -> Result<Arc<FrameMask>>;
}

/// All masks in memory.
pub(crate) struct SliceProvider<'a> {
    pub masks: &'a [Arc<FrameMask>],
}

impl MaskProvider for SliceProvider<'_> {
    fn mask(&mut self, i: usize) -> Result<Arc<FrameMask>> {
        Ok(self.masks[i].clone())
    }
}

/// Kernels and switches derived from [`GuideParams`].
#[derive(Clone, Debug)]
pub(crate) struct FlowConfig {
    /// Temporal kernel of the distance fields, `2·rt + 1` taps.
    kt: Vec<f32>,
    rt: usize,
    /// Temporal kernel of the flow over `k = −rf_lo ..= rf_hi`, centred on `k = ½` (step 5).
    kf: Vec<f32>,
    rf_lo: usize,
    rf_hi: usize,
    tangential: bool,
    tolerance: f32,
}

impl FlowConfig {
    pub fn new(p: &GuideParams) -> Self {
        let kt = gaussian_kernel(p.time_blur_sigma);
        let rt = kt.len() / 2;
        // Centred on k = ½: the raw fields are velocities at their frames (step 2), the flow the
        // motion from frame i to i + 1 (the trapezoid rule for radius 0).
        let rf = p.flow_time_radius.max(1);
        let (rf_lo, rf_hi) = (rf - 1, rf);
        let sigma = rf as f32 / 3.0;
        let mut kf: Vec<f32> = (0..=rf_lo + rf_hi)
            .map(|i| {
                let k = i as f32 - rf_lo as f32 - 0.5;
                (-(k * k) / (2.0 * sigma * sigma)).exp()
            })
            .collect();
        let s: f32 = kf.iter().sum();
        kf.iter_mut().for_each(|v| *v /= s);
        FlowConfig { kt, rt, kf, rf_lo, rf_hi, tangential: p.tangential_fit, tolerance: p.laplace_tolerance }
    }
}

/// The pending estimate of the raw flow `F_j` of one frame: samples of the distance fields of
/// its temporal window at the boundary pixels and their neighbours.
struct Task {
    mask: Arc<FrameMask>,
    /// `B_j` and its 4-neighbours, linear image indices, sorted.
    stencil: Vec<u32>,
    srect: Rect,
    /// Per boundary pixel: stencil index of itself and of its left, right, upper, lower neighbour
    /// (`u32::MAX` off the image).
    nbr: Vec<[u32; 5]>,
    /// The distinct frames of the window, ascending, and their samples once known.
    frames: Vec<usize>,
    rows: Vec<Option<Vec<f32>>>,
    /// The slot of frame `j + k` for `k = −rt ..= rt + 1` (frames beyond the run of
    /// non-degenerate masks clamped to its ends, module docs, step 1).
    kslots: Vec<usize>,
}

const NO: u32 = u32::MAX;

/// How a boundary pixel's normal speed is measured ([`Task::estimate_at`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Estimate {
    /// `(D̃_{j+1} − D̃_{j−1}) / 2`, each averaged over `k = −r ..= r` around its frame.
    Central(usize),
    /// `D̃_{j+1} − D̃_j`, each averaged over `k = −r ..= r` around its frame.
    Forward(usize),
    /// `dist_j − dist_{j−1}`: frame `j` is the last of its run, and its velocity is the motion
    /// that brought it.
    Backward,
    /// The frame the difference needs (`j + 1`, or `j − 1` at the last frame) does not fit:
    /// the part's fitted motion stands in.
    Unmeasured,
}

impl Task {
    fn complete(&self) -> bool {
        self.rows.iter().all(Option::is_some)
    }

    fn slot_of(&self, m: usize) -> Option<usize> {
        self.frames.binary_search(&m).ok().filter(|&s| self.rows[s].is_none())
    }

    /// Stores the samples of distance field `d` (a crop holding the stencil) of frame `m`.
    fn fill(&mut self, m: usize, d: &Crop<f32>) {
        if let Some(s) = self.slot_of(m) {
            let w = self.mask.w;
            self.rows[s] = Some(self.stencil.iter().map(|&i| d.get(i as usize % w, i as usize / w)).collect());
        }
    }

    /// The distance sample of slot `slot` at stencil index `idx`.
    fn sample(&self, slot: usize, idx: usize) -> f32 {
        self.rows[slot].as_ref().map_or(0.0, |r| r[idx])
    }

    /// `Σ g · sample(slot, idx)` over a kernel's (slot, weight) pairs.
    fn smoothed(&self, weights: impl Iterator<Item = (usize, f32)>, idx: usize) -> f32 {
        let mut acc = 0f32;
        for (s, g) in weights {
            acc += g * self.sample(s, idx);
        }
        acc
    }

    /// The distance sample of frame `j + k` at stencil index `idx`.
    fn raw(&self, k: isize, rt: usize, idx: usize) -> f32 {
        self.sample(self.kslots[(k + rt as isize) as usize], idx)
    }

    /// How a boundary pixel's speed is measured (module docs, steps 1–2), from the frames of
    /// its temporal window that fit the straight-front model behind the estimate.
    ///
    /// A frame `j + k` fits when the pixel lies outside it, or inside with its distance still
    /// counted from the edge the pixel belongs to: the gradient of `D_{j+k}` does not point
    /// outward along this frame's normal. A part that moved by more than its half thickness (a
    /// thin limb swinging fast) breaks this: past its middle the distance is counted from the
    /// part's other edge, so the averaged field (and, at `k = ±1`, the speed itself)
    /// under-reports the motion — on a 14-px limb swinging at up to 11 px a frame the flow had
    /// 32–64 % of the true motion.
    ///
    /// Every window holds real frames only, never the replicated ends of the run (module
    /// docs, step 1). The central difference needs frames `j ± 1` to fit; its window widens to
    /// `k = −1−r ..= 1+r` while the frames added are real, fit and their nearest edge still lies
    /// along the pixel's normal (within 45°, [`MIN_ALONG`]): a small curved part that has moved
    /// past its own radius is nearest to the pixel at its side, and its distance there grows
    /// with the distance travelled in any direction. Without the central difference the forward
    /// one over `k = −r ..= r + 1`, the window cut before the first frame that is not real or
    /// does not fit on either side; when that is frame `j + 1` itself the speed is not measured.
    /// At the ends of the run the window is the two frames there: at the first frame the
    /// forward difference, at the last the backward one ([`Estimate::Backward`]), each where
    /// the other frame fits and lies along the normal (else not measured).
    fn estimate_at(&self, nb: &[u32; 5], rt: usize) -> Estimate {
        let at = |k: isize| {
            let here = self.raw(k, rt, nb[0] as usize);
            (here, gradient(nb, here, |i| self.raw(k, rt, i)))
        };
        let g0 = at(0).1;
        if g0.length() <= 1e-6 {
            return Estimate::Forward(rt);
        }
        let outward = -g0.normalize();
        let fits = |k: isize| {
            let (d, g) = at(k);
            d <= 1.0 || g.dot(outward) <= 0.5 * g.length()
        };
        let along = |k: isize| {
            let (d, g) = at(k);
            d.abs() <= 1.0 || -g.dot(outward) >= MIN_ALONG * g.length()
        };
        // Frame j + k is real unless it is a replicated end: the same slot as its neighbour
        // nearer to j.
        let real = |k: isize| {
            let slot = |k: isize| self.kslots[(rt as isize + k) as usize];
            k == 0 || slot(k) != slot(k - k.signum())
        };
        if rt > 0 && !real(1) {
            let before = real(-1) && fits(-1) && along(-1);
            return if before { Estimate::Backward } else { Estimate::Unmeasured };
        }
        if rt > 0 && !real(-1) {
            return if fits(1) && along(1) { Estimate::Forward(0) } else { Estimate::Unmeasured };
        }
        if !fits(1) {
            return Estimate::Unmeasured;
        }
        let fits_real = |k: isize| real(k) && fits(k);
        if rt > 0 && fits(-1) {
            let widens = |k: isize| fits_real(k) && along(k);
            let mut r = 0;
            while r + 1 < rt && widens(-(r as isize) - 2) && widens(r as isize + 2) {
                r += 1;
            }
            return Estimate::Central(r);
        }
        let mut r = 0;
        while r < rt && fits_real(-(r as isize) - 1) && fits_real(r as isize + 2) {
            r += 1;
        }
        Estimate::Forward(r)
    }

    /// The kernel of `D̃_{j+s}` over `k = −r ..= r` around frame `j + s` (`s ∈ {−1, 0, 1}`),
    /// as (slot, weight): the whole temporal Gaussian for `r = rt`, else cut and normalized
    /// again.
    fn kernel<'a>(
        &'a self,
        cfg: &'a FlowConfig,
        r: usize,
        s: isize,
    ) -> impl Iterator<Item = (usize, f32)> + Clone + 'a {
        let rt = cfg.rt;
        let taps = rt - r..=rt + r;
        let sum: f32 = if r == rt { 1.0 } else { cfg.kt[taps.clone()].iter().sum() };
        taps.map(move |t| (self.kslots[(t as isize + s) as usize], cfg.kt[t] / sum))
    }

    /// The normal speed and the outward normal at a boundary pixel, and whether the speed was
    /// measured (module docs, step 2).
    fn speed_at(&self, cfg: &FlowConfig, nb: &[u32; 5]) -> (f32, Vec2, bool) {
        let (r, before, after, steps, measured) = match self.estimate_at(nb, cfg.rt) {
            Estimate::Central(r) => (r, -1, 1, 2.0, true),
            Estimate::Forward(r) => (r, 0, 1, 1.0, true),
            Estimate::Backward => (0, -1, 0, 1.0, true),
            Estimate::Unmeasured => (0, 0, 1, 1.0, false),
        };
        let field = |s: isize| {
            let w = self.kernel(cfg, r, s);
            let v = self.smoothed(w.clone(), nb[0] as usize);
            (v, gradient(nb, v, |i| self.smoothed(w.clone(), i)))
        };
        let here = field(0);
        let len = here.1.length();
        let n = if len > 1e-6 { -here.1 / len } else { Vec2::ZERO };
        let (d0, g0) = if before == 0 { here } else { field(before) };
        let (d1, g1) = if after == 0 { here } else { field(after) };
        // A field that moves by v changes by |∇D̃|·(n·v): a temporal average of distance fields
        // whose normals disagree has |∇D̃| < 1, so its change is divided by it.
        let slope = (0.5 * (g0.length() + g1.length())).clamp(MIN_SLOPE, 1.0);
        ((d1 - d0) / (steps * slope), n, measured)
    }

    /// The raw flow `F_j` over the mask's bounding box (steps 2–4 of the module docs).
    fn solve(&self, cfg: &FlowConfig) -> Crop<Vec2> {
        let mask = &self.mask;
        let w = mask.w;
        // Step 2: normal speed and outward normal at each boundary pixel, and whether the
        // distance fields could measure it (see `estimate_at`).
        let normals: Vec<(f32, Vec2, bool)> = self.nbr.iter().map(|nb| self.speed_at(cfg, nb)).collect();
        // Components of the mask (4-connected) inside its bounding box.
        let rect = mask.rect();
        let (labels, ncomp) = label_components(mask);
        let label_of = |x: usize, y: usize| labels[(y - rect.y0) * rect.width() + (x - rect.x0)];
        // Step 3: an affine motion per component.
        let fits: Vec<Affine> = if cfg.tangential {
            // Each part's fit uses the boundary pixels whose normal speed was measured, or all
            // of them if fewer than three were (then nothing is replaced by the fit below).
            let mut members: Vec<Vec<usize>> = vec![Vec::new(); ncomp];
            let mut all: Vec<Vec<usize>> = vec![Vec::new(); ncomp];
            for (bi, &b) in mask.boundary.iter().enumerate() {
                let (x, y) = (b as usize % w, b as usize / w);
                let c = label_of(x, y) as usize;
                all[c].push(bi);
                if normals[bi].2 {
                    members[c].push(bi);
                }
            }
            for (m, a) in members.iter_mut().zip(all) {
                if m.len() < 3 {
                    *m = a;
                }
            }
            members
                .iter()
                .map(|m| {
                    let pts: Vec<(DVec2, DVec2, f64)> = m
                        .iter()
                        .map(|&bi| {
                            let b = mask.boundary[bi] as usize;
                            let (s, n, _) = normals[bi];
                            (DVec2::new((b % w) as f64, (b / w) as f64), n.as_dvec2(), s as f64)
                        })
                        .collect();
                    Affine::fit(&pts)
                })
                .collect()
        } else {
            vec![Affine::ZERO; ncomp]
        };
        // Step 4: Laplace with the boundary values fixed.
        // The mask's crop covers exactly its bounding box.
        let mut cells = mask.crop.plane.map(|inside| if inside { Cell::Free } else { Cell::Outside });
        let mut values = Plane::from_fn(rect.width(), rect.height(), |x, y| {
            let (gx, gy) = (x + rect.x0, y + rect.y0);
            if cells.get(x, y) == Cell::Free { fits[label_of(gx, gy) as usize].at(gx, gy) } else { Vec2::ZERO }
        });
        for (bi, &b) in mask.boundary.iter().enumerate() {
            let (x, y) = (b as usize % w, b as usize / w);
            let (s, n, reliable) = normals[bi];
            let v = fits[label_of(x, y) as usize].at(x, y);
            // Where the distance fields could not measure the boundary's speed, the part's
            // fitted motion stands in for it.
            let g = if reliable || !cfg.tangential { s * n + (v - v.dot(n) * n) } else { v };
            cells.set(x - rect.x0, y - rect.y0, Cell::Fixed);
            values.set(x - rect.x0, y - rect.y0, g);
        }
        let report = laplace::solve(&cells, &mut values, cfg.tolerance);
        if !report.converged {
            log::warn!(
                "flow: the Laplace solve stopped after {} V-cycles at residual {} (tolerance {})",
                report.cycles,
                report.residual,
                report.threshold
            );
        }
        Crop { rect, plane: values }
    }
}

/// The smallest gradient magnitude of the smoothed distance fields that the change of a
/// boundary pixel's distance is divided by (step 2). The frames of a front that moves as one
/// agree to within a few percent (translating, growing and shrinking ellipses: the mean flow
/// error fell from 0.187, 0.120, 0.088 px to 0.114, 0.081, 0.054 px with the division, figures
/// measured while building it with an earlier version of `tests/guide_motion.rs`); where
/// they disagree more — the tip of a swinging limb, whose neighbouring frames' nearest edge is
/// its side, not its end — the change is not a front's speed, and dividing by a small slope
/// only enlarges its error (limb: 0.76 px undivided, 0.91 px divided down to slope 0.5,
/// 0.72 px clamped at 0.9).
const MIN_SLOPE: f32 = 0.9;

/// The central difference's window takes a frame only where the gradient of its distance field
/// at the boundary pixel lies within 45° of the pixel's inward normal ([`Task::estimate_at`]).
const MIN_ALONG: f32 = std::f32::consts::FRAC_1_SQRT_2;

/// Central differences (one-sided at the image edge) of a field sampled at a boundary pixel's
/// stencil `nb` (itself, left, right, upper, lower neighbour), `here` being its own value.
fn gradient(nb: &[u32; 5], here: f32, value: impl Fn(usize) -> f32) -> Vec2 {
    let d = |k: usize| (nb[k] != NO).then(|| value(nb[k] as usize));
    let diff = |lo: Option<f32>, hi: Option<f32>| match (lo, hi) {
        (Some(a), Some(b)) => 0.5 * (b - a),
        (None, Some(b)) => b - here,
        (Some(a), None) => here - a,
        (None, None) => 0.0,
    };
    Vec2::new(diff(d(1), d(2)), diff(d(3), d(4)))
}

/// 4-connected components of a frame mask over its bounding box; returns the labels (row-major
/// over the box, `u32::MAX` outside the mask) and their number.
fn label_components(mask: &FrameMask) -> (Vec<u32>, usize) {
    let r = mask.rect();
    let (rw, rh) = (r.width(), r.height());
    let inside = |i: usize| mask.crop.plane.data()[i];
    let mut labels = vec![u32::MAX; rw * rh];
    let mut n = 0u32;
    let mut stack = Vec::new();
    for start in 0..rw * rh {
        if !inside(start) || labels[start] != u32::MAX {
            continue;
        }
        labels[start] = n;
        stack.push(start);
        while let Some(i) = stack.pop() {
            crate::img::for_each_neighbour4(i, rw, rh, |j| {
                if inside(j) && labels[j] == u32::MAX {
                    labels[j] = n;
                    stack.push(j);
                }
            });
        }
        n += 1;
    }
    (labels, n as usize)
}

/// An affine motion `v(p) = A (p − c)/ρ + t`, fitted in centred, scaled coordinates.
#[derive(Clone, Copy, Debug)]
struct Affine {
    c: DVec2,
    inv_rho: f64,
    /// `[a11, a12, a21, a22, t1, t2]`.
    theta: [f64; 6],
}

impl Affine {
    const ZERO: Affine = Affine { c: DVec2::ZERO, inv_rho: 0.0, theta: [0.0; 6] };

    /// Relative weight of the ridge term on the observed modes (those at or above
    /// [`Self::UNOBSERVED`] of the average information): each is shrunk by at most
    /// `RIDGE / (UNOBSERVED + RIDGE)` ≈ 1/6 of its least-squares value.
    const RIDGE: f64 = 0.01;

    /// Modes of the motion whose information (eigenvalue of the normal matrix) is below this
    /// fraction of the average are not observed by the boundary ([`Affine::fit`]).
    const UNOBSERVED: f64 = 0.05;

    /// How much a mode that the boundary does not observe may move for each unit of strain it
    /// takes away ([`Affine::fit`]): the weight of `|θ|²` against `|strain|²` there.
    const STILLNESS: f64 = 0.1;

    /// Least squares `min Σ (n·v(p) − s)² + λ|θ|²` over `(p, n, s)`, on the modes of the motion
    /// the boundary observes; on those it does not, the motion as rigid as possible.
    ///
    /// Normal speeds alone do not determine an affine motion everywhere: an ellipse that turns
    /// about its centre shows the same normal speeds as one that shears along its own outline
    /// (`L·J·L⁻¹` for the ellipse `L`·disc and `J` the turn), and a thin limb shows little of
    /// how it moves along itself. The plain ridge solution takes the smallest motion that fits,
    /// which turns such an ellipse at about two thirds of its speed and makes up the rest with
    /// a shear (measured while building it on a 190 × 70 ellipse turning 2.5°/frame, before the
    /// slope division: mean flow error 1.80 px of 3.99). So the normal matrix is diagonalized, and along its eigen-directions whose
    /// information is below [`Self::UNOBSERVED`] of the average the combination with the least
    /// strain (the symmetric part of `A`: growth, stretch, shear) is taken, held back by
    /// [`Self::STILLNESS`]·`|θ|²` (a part that is nearly a disc does not start turning on a
    /// speck of noise): what the boundary cannot tell is taken to move rigidly (error 0.48 px
    /// on the turning ellipse; growing, shrinking and translating ellipses unchanged within
    /// 0.003 px). Observed modes are the ridge solution, as before.
    fn fit(pts: &[(DVec2, DVec2, f64)]) -> Affine {
        if pts.len() < 3 {
            return Affine::ZERO;
        }
        let c = pts.iter().map(|p| p.0).sum::<DVec2>() / pts.len() as f64;
        let rho = (pts.iter().map(|p| (p.0 - c).length_squared()).sum::<f64>() / pts.len() as f64).sqrt().max(1.0);
        let inv_rho = 1.0 / rho;
        let mut m = [[0f64; 6]; 6];
        let mut rhs = [0f64; 6];
        for &(p, n, s) in pts {
            let q = (p - c) * inv_rho;
            let j = [n.x * q.x, n.x * q.y, n.y * q.x, n.y * q.y, n.x, n.y];
            for a in 0..6 {
                rhs[a] += j[a] * s;
                for b in 0..6 {
                    m[a][b] += j[a] * j[b];
                }
            }
        }
        let mean_info = (0..6).map(|a| m[a][a]).sum::<f64>() / 6.0;
        if !(mean_info > 0.0 && mean_info.is_finite()) {
            return Affine::ZERO;
        }
        let (values, vectors) = eigen6(&m);
        let ridge = Self::RIDGE * mean_info;
        let mut theta = [0f64; 6];
        let mut unobserved = Vec::new();
        for (k, &value) in values.iter().enumerate() {
            let v: [f64; 6] = std::array::from_fn(|i| vectors[i][k]);
            if value >= Self::UNOBSERVED * mean_info {
                let coef = dot6(&v, &rhs) / (value + ridge);
                (0..6).for_each(|i| theta[i] += coef * v[i]);
            } else {
                unobserved.push(v);
            }
        }
        if let Some(coefs) = least_strain(&theta, &unobserved, Self::STILLNESS) {
            for (v, coef) in unobserved.iter().zip(coefs) {
                (0..6).for_each(|i| theta[i] += coef * v[i]);
            }
        }
        if theta.iter().all(|t| t.is_finite()) { Affine { c, inv_rho, theta } } else { Affine::ZERO }
    }

    #[inline]
    fn at(&self, x: usize, y: usize) -> Vec2 {
        let q = (DVec2::new(x as f64, y as f64) - self.c) * self.inv_rho;
        let t = &self.theta;
        Vec2::new((t[0] * q.x + t[1] * q.y + t[4]) as f32, (t[2] * q.x + t[3] * q.y + t[5]) as f32)
    }
}

fn dot6(a: &[f64; 6], b: &[f64; 6]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Eigenvalues and eigenvectors (the columns of the matrix returned) of a symmetric 6 × 6
/// matrix, by cyclic Jacobi rotations in a fixed order (deterministic).
fn eigen6(m: &[[f64; 6]; 6]) -> ([f64; 6], [[f64; 6]; 6]) {
    let mut a = *m;
    let mut v = [[0f64; 6]; 6];
    (0..6).for_each(|i| v[i][i] = 1.0);
    let scale: f64 = a.iter().flatten().map(|x| x * x).sum();
    for _ in 0..64 {
        let off: f64 = (0..6)
            .flat_map(|i| (0..6).map(move |j| (i, j)))
            .filter(|(i, j)| i != j)
            .map(|(i, j)| a[i][j] * a[i][j])
            .sum();
        if off <= 1e-30 * scale {
            break;
        }
        for p in 0..5 {
            for q in p + 1..6 {
                if a[p][q] == 0.0 {
                    continue;
                }
                // The rotation that zeroes a[p][q] (Golub & Van Loan, §8.5.2).
                let tau = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = if tau >= 0.0 {
                    1.0 / (tau + (1.0 + tau * tau).sqrt())
                } else {
                    -1.0 / (-tau + (1.0 + tau * tau).sqrt())
                };
                let c = 1.0 / (1.0 + t * t).sqrt();
                let s = t * c;
                for row in a.iter_mut() {
                    let (x, y) = (row[p], row[q]);
                    row[p] = c * x - s * y;
                    row[q] = s * x + c * y;
                }
                let (rp, rq) = (a[p], a[q]);
                for (k, (x, y)) in rp.into_iter().zip(rq).enumerate() {
                    a[p][k] = c * x - s * y;
                    a[q][k] = s * x + c * y;
                }
                for row in v.iter_mut() {
                    let (x, y) = (row[p], row[q]);
                    row[p] = c * x - s * y;
                    row[q] = s * x + c * y;
                }
            }
        }
    }
    (std::array::from_fn(|i| a[i][i]), v)
}

/// The strain of the motion `θ` (the symmetric part of `A`): `(a11, a22, (a12 + a21)/√2)`.
fn strain(t: &[f64; 6]) -> [f64; 3] {
    [t[0], t[3], (t[1] + t[2]) * std::f64::consts::FRAC_1_SQRT_2]
}

/// The coefficients `c` of the directions `dirs` that minimize
/// `|strain(θ + Σ c_k d_k)|² + stillness·|θ + Σ c_k d_k|²`; `None` without directions or when
/// the system is singular.
fn least_strain(theta: &[f64; 6], dirs: &[[f64; 6]], stillness: f64) -> Option<Vec<f64>> {
    let n = dirs.len();
    if n == 0 {
        return None;
    }
    let s0 = strain(theta);
    let sd: Vec<[f64; 3]> = dirs.iter().map(strain).collect();
    let dot3 = |a: &[f64; 3], b: &[f64; 3]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let mut g: Vec<Vec<f64>> =
        (0..n).map(|i| (0..n).map(|j| dot3(&sd[i], &sd[j]) + stillness * dot6(&dirs[i], &dirs[j])).collect()).collect();
    let mut b: Vec<f64> = (0..n).map(|i| -(dot3(&sd[i], &s0) + stillness * dot6(&dirs[i], theta))).collect();
    // Gauss-Jordan with partial pivoting (n ≤ 6).
    for col in 0..n {
        let piv = (col..n).max_by(|&x, &y| g[x][col].abs().total_cmp(&g[y][col].abs()))?;
        g.swap(col, piv);
        b.swap(col, piv);
        if g[col][col].abs() < 1e-12 {
            return None;
        }
        let (pivot_row, bc) = (g[col].clone(), b[col]);
        for r in 0..n {
            if r != col {
                let f = g[r][col] / pivot_row[col];
                g[r].iter_mut().zip(&pivot_row).for_each(|(x, p)| *x -= f * p);
                b[r] -= f * bc;
            }
        }
    }
    Some((0..n).map(|i| b[i] / g[i][i]).collect())
}

/// Step 5: the normalized temporal Gaussian of the raw flows around frame `i`.
fn smooth_in_time(
    i: usize,
    cfg: &FlowConfig,
    mask: &FrameMask,
    flows: &BTreeMap<usize, (Arc<FrameMask>, Arc<Crop<Vec2>>)>,
) -> Crop<Vec2> {
    let rect = mask.rect();
    let (lo, hi) = (cfg.rf_lo as isize, cfg.rf_hi as isize);
    let neighbours: Vec<(f32, f32, &FrameMask, &Crop<Vec2>)> = (-lo..=hi)
        .filter_map(|k| {
            let j = i as isize + k;
            let g = cfg.kf[(k + lo) as usize];
            (j >= 0).then(|| flows.get(&(j as usize))).flatten().map(|(m, f)| (g, k as f32, &**m, &**f))
        })
        .collect();
    let own = &flows[&i].1;
    let mut out = Crop::new(rect);
    out.plane.data_mut().par_chunks_mut(rect.width().max(1)).enumerate().for_each(|(yy, row)| {
        let y = rect.y0 + yy;
        for (xx, o) in row.iter_mut().enumerate() {
            let x = rect.x0 + xx;
            if !mask.contains(x, y) {
                continue;
            }
            let (mut num, mut den) = (Vec2::ZERO, 0f32);
            // Frame i + k is read where this frame's velocity carries the pixel in k frames.
            let p = Vec2::new(x as f32, y as f32);
            let v = own.get(x, y);
            for &(g, k, m, f) in &neighbours {
                let sample = if k == 0.0 { Some(v) } else { sample_inside(m, f, p + k * v) };
                if let Some(s) = sample {
                    num += s * g;
                    den += g;
                }
            }
            *o = if den > 0.0 { num / den } else { Vec2::ZERO };
        }
    });
    out
}

/// The flow `f` at the image position `q`, interpolated bilinearly over the pixels of the four
/// around it that lie in `m`; `None` when none does (or `q` is off the image or not finite).
fn sample_inside(m: &FrameMask, f: &Crop<Vec2>, q: Vec2) -> Option<Vec2> {
    if !(q.x >= 0.0 && q.y >= 0.0 && q.x < m.w as f32 && q.y < m.h as f32) {
        return None;
    }
    let (x0, y0) = (q.x.floor() as usize, q.y.floor() as usize);
    let (fx, fy) = (q.x - x0 as f32, q.y - y0 as f32);
    let (mut num, mut den) = (Vec2::ZERO, 0f32);
    for (dx, dy, w) in
        [(0, 0, (1.0 - fx) * (1.0 - fy)), (1, 0, fx * (1.0 - fy)), (0, 1, (1.0 - fx) * fy), (1, 1, fx * fy)]
    {
        let (x, y) = (x0 + dx, y0 + dy);
        if w > 0.0 && m.contains(x, y) {
            num += f.get(x, y) * w;
            den += w;
        }
    }
    (den > 1e-6).then(|| num / den)
}

/// A frame index, its mask and its final flow (over the mask's bounding box).
pub(crate) type FlowOutput = (usize, Arc<FrameMask>, Crop<Vec2>);

/// Produces the final flows of a range of frames, visited forward or backward, keeping only a
/// sliding window of masks, distance samples and raw flows in memory. The flow of a frame does
/// not depend on where the machine started or which way it runs.
pub(crate) struct FlowMachine {
    n: usize,
    forward: bool,
    cfg: FlowConfig,
    /// Next frame to output, and the last one.
    next: Option<usize>,
    last: usize,
    /// Frames whose raw flow may be needed.
    f_lo: usize,
    f_hi: usize,
    /// Frames whose distance field may be needed.
    d_lo: usize,
    d_hi: usize,
    /// Next distance field to compute.
    frontier: Option<usize>,
    masks: BTreeMap<usize, Arc<FrameMask>>,
    tasks: BTreeMap<usize, Task>,
    flows: BTreeMap<usize, (Arc<FrameMask>, Arc<Crop<Vec2>>)>,
}

impl FlowMachine {
    /// Outputs frames `first, first ± 1, …, last` (forward: `first ≤ last`) of an `n`-frame sequence.
    pub fn new(n: usize, forward: bool, first: usize, last: usize, params: &GuideParams) -> Self {
        let cfg = FlowConfig::new(params);
        let (lo, hi) = (first.min(last), first.max(last));
        let f_lo = lo.saturating_sub(cfg.rf_lo);
        let f_hi = (hi + cfg.rf_hi).min(n.saturating_sub(1));
        let d_lo = f_lo.saturating_sub(cfg.rt);
        let d_hi = (f_hi + cfg.rt + 1).min(n.saturating_sub(1));
        FlowMachine {
            n,
            forward,
            next: (n > 0).then_some(first),
            last,
            f_lo,
            f_hi,
            d_lo,
            d_hi,
            frontier: Some(if forward { d_lo } else { d_hi }),
            cfg,
            masks: BTreeMap::new(),
            tasks: BTreeMap::new(),
            flows: BTreeMap::new(),
        }
    }

    /// Number of frames `a` lies after `b` in the direction of travel (negative: before).
    fn ahead(&self, a: usize, b: usize) -> isize {
        if self.forward { a as isize - b as isize } else { b as isize - a as isize }
    }

    fn mask(&mut self, i: usize, p: &mut dyn MaskProvider) -> Result<Arc<FrameMask>> {
        if let Some(m) = self.masks.get(&i) {
            return Ok(m.clone());
        }
        let m = p.mask(i)?;
        self.masks.insert(i, m.clone());
        Ok(m)
    }

    /// The next frame's index, mask and final flow (over the mask's bounding box).
    pub fn next_output(&mut self, p: &mut dyn MaskProvider) -> Result<Option<FlowOutput>> {
        let Some(i) = self.next else { return Ok(None) };
        let rf = self.cfg.rf_hi;
        let (lo, hi) = (i.saturating_sub(self.cfg.rf_lo), (i + rf).min(self.n - 1));
        let order: Vec<usize> = if self.forward { (lo..=hi).collect() } else { (lo..=hi).rev().collect() };
        for j in order {
            self.ensure_flow(j, p)?;
        }
        let mask = self.flows[&i].0.clone();
        let out = smooth_in_time(i, &self.cfg, &mask, &self.flows);
        // Forget what no later output needs.
        let keep_from = i;
        let rf = rf as isize;
        let stale: Vec<usize> = self.flows.keys().copied().filter(|&j| self.ahead(j, keep_from) < 1 - rf).collect();
        for j in stale {
            self.flows.remove(&j);
        }
        // Masks still needed: those of later outputs' windows (from i − rf + 1 on) and those
        // that tasks created at the frontier look at (from frontier − 2·rt − 1 on).
        let rt = self.cfg.rt as isize;
        let frontier = self.frontier;
        let stale: Vec<usize> = self
            .masks
            .keys()
            .copied()
            .filter(|&k| self.ahead(k, i) < 1 - rf && frontier.is_none_or(|f| self.ahead(k, f) < -2 * rt - 1))
            .collect();
        for k in stale {
            self.masks.remove(&k);
        }
        self.next = if i == self.last {
            None
        } else if self.forward {
            Some(i + 1)
        } else {
            Some(i - 1)
        };
        Ok(Some((i, mask, out)))
    }

    fn ensure_flow(&mut self, j: usize, p: &mut dyn MaskProvider) -> Result<()> {
        if self.flows.contains_key(&j) {
            return Ok(());
        }
        let mask = self.mask(j, p)?;
        if mask.is_degenerate() {
            let zero = Crop::new(mask.rect());
            self.flows.insert(j, (mask, Arc::new(zero)));
            return Ok(());
        }
        if !self.tasks.contains_key(&j) {
            self.create_task(j, p)?;
        }
        while !self.tasks[&j].complete() {
            if self.frontier.is_none() {
                // Cannot happen: every task's window lies inside [d_lo, d_hi].
                return Err(Error::param("flow window", j, "a frame whose temporal window was visited"));
            }
            self.advance(p)?;
        }
        if let Some(task) = self.tasks.remove(&j) {
            let f = task.solve(&self.cfg);
            self.flows.insert(j, (task.mask, Arc::new(f)));
        }
        Ok(())
    }

    fn create_task(&mut self, j: usize, p: &mut dyn MaskProvider) -> Result<()> {
        let rt = self.cfg.rt;
        let mask = self.mask(j, p)?;
        // The run of non-degenerate masks around j, within the window.
        let mut lo = j;
        while lo > j.saturating_sub(rt) && !self.mask(lo - 1, p)?.is_degenerate() {
            lo -= 1;
        }
        let mut hi = j;
        while hi < (j + rt + 1).min(self.n - 1) && !self.mask(hi + 1, p)?.is_degenerate() {
            hi += 1;
        }
        let clamp = |k: isize| (j as isize + k).clamp(lo as isize, hi as isize) as usize;
        let mut frames: Vec<usize> = (-(rt as isize)..=rt as isize + 1).map(clamp).collect();
        frames.sort_unstable();
        frames.dedup();
        let slot = |f: usize| frames.binary_search(&f).unwrap_or(0);
        let rti = rt as isize;
        let kslots = (-rti..=rti + 1).map(|k| slot(clamp(k))).collect();
        // The stencil: boundary pixels and their neighbours.
        let (w, h) = (mask.w, mask.h);
        let mut stencil = Vec::with_capacity(mask.boundary.len() * 3);
        for &b in &mask.boundary {
            let (x, y) = (b as usize % w, b as usize / w);
            stencil.push(b);
            if x > 0 {
                stencil.push(b - 1);
            }
            if x + 1 < w {
                stencil.push(b + 1);
            }
            if y > 0 {
                stencil.push(b - w as u32);
            }
            if y + 1 < h {
                stencil.push(b + w as u32);
            }
        }
        stencil.sort_unstable();
        stencil.dedup();
        let find = |i: u32| stencil.binary_search(&i).map_or(NO, |k| k as u32);
        let nbr = mask
            .boundary
            .iter()
            .map(|&b| {
                let (x, y) = (b as usize % w, b as usize / w);
                [
                    find(b),
                    if x > 0 { find(b - 1) } else { NO },
                    if x + 1 < w { find(b + 1) } else { NO },
                    if y > 0 { find(b - w as u32) } else { NO },
                    if y + 1 < h { find(b + w as u32) } else { NO },
                ]
            })
            .collect();
        let srect = mask.rect().expand(1, w, h);
        let rows = vec![None; frames.len()];
        self.tasks.insert(j, Task { mask, stencil, srect, nbr, frames, rows, kslots });
        Ok(())
    }

    /// Computes the distance field of the frontier frame for every task that needs it.
    fn advance(&mut self, p: &mut dyn MaskProvider) -> Result<()> {
        let Some(m) = self.frontier else { return Ok(()) };
        let rt = self.cfg.rt;
        // Create every task whose (unclamped) window starts here or has started.
        for j in m.saturating_sub(rt + 1)..=(m + rt).min(self.n - 1) {
            if j < self.f_lo || j > self.f_hi || self.flows.contains_key(&j) || self.tasks.contains_key(&j) {
                continue;
            }
            if !self.mask(j, p)?.is_degenerate() {
                self.create_task(j, p)?;
            }
        }
        let needing: Vec<usize> = self.tasks.iter().filter(|(_, t)| t.slot_of(m).is_some()).map(|(&j, _)| j).collect();
        if !needing.is_empty() {
            let mask = self.mask(m, p)?;
            let mut rect = mask.rect().expand(1, mask.w, mask.h);
            for j in &needing {
                rect = rect.union(self.tasks[j].srect);
            }
            let d = Crop { rect, plane: super::sdf::sdf(&mask.crop_to(rect)) };
            for j in needing {
                if let Some(t) = self.tasks.get_mut(&j) {
                    t.fill(m, &d);
                }
            }
        }
        let (lo, hi) = (self.d_lo, self.d_hi);
        self.frontier = if self.forward { (m < hi).then_some(m + 1) } else { (m > lo).then(|| m - 1) };
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_along_the_motion_only_inside_the_mask() {
        // A 10 × 8 image whose mask holds columns 2..6 of rows 1..5; the flow's x is the column.
        let (w, h) = (10, 8);
        let mut full = Crop::new(Rect::full(w, h));
        let mut flow = Crop::new(Rect::full(w, h));
        for y in 1..5 {
            for x in 2..6 {
                full.plane.set(x, y, true);
                flow.plane.set(x, y, Vec2::new(x as f32, 1.0));
            }
        }
        let m = FrameMask::from_crop(w, h, &full);
        // Between four inside pixels: bilinear.
        let v = sample_inside(&m, &flow, Vec2::new(3.25, 2.5)).unwrap();
        assert!((v - Vec2::new(3.25, 1.0)).length() < 1e-5, "{v:?}");
        // Half outside: only the inside pixels count (column 5 weighs alone past the edge).
        let v = sample_inside(&m, &flow, Vec2::new(5.5, 2.0)).unwrap();
        assert!((v - Vec2::new(5.0, 1.0)).length() < 1e-5, "{v:?}");
        // Wholly outside, off the image, or not a number: nothing.
        for q in [Vec2::new(7.5, 2.0), Vec2::new(-0.5, 2.0), Vec2::new(1e30, 2.0), Vec2::new(f32::NAN, 2.0)] {
            assert!(sample_inside(&m, &flow, q).is_none(), "{q:?}");
        }
    }

    #[test]
    fn affine_fit_recovers_translation_and_growth() {
        // Points on a circle with exact normal speeds of a known motion.
        let pts = |v: &dyn Fn(DVec2) -> DVec2| -> Vec<(DVec2, DVec2, f64)> {
            (0..200)
                .map(|k| {
                    let a = k as f64 * std::f64::consts::TAU / 200.0;
                    let n = DVec2::new(a.cos(), a.sin());
                    let p = DVec2::new(50.0, 40.0) + 20.0 * n;
                    (p, n, n.dot(v(p)))
                })
                .collect()
        };
        let t = Affine::fit(&pts(&|_| DVec2::new(1.5, -0.5)));
        let v = t.at(50, 40);
        assert!((v - Vec2::new(1.5, -0.5)).length() < 0.03, "{v:?}");
        let g = Affine::fit(&pts(&|p| (p - DVec2::new(50.0, 40.0)) * 0.1));
        let v = g.at(70, 40);
        assert!((v - Vec2::new(2.0, 0.0)).length() < 0.05, "{v:?}");
        // A rotation of a disc is invisible at its boundary: the fit stays at zero.
        let r = Affine::fit(&pts(&|p| {
            let q = p - DVec2::new(50.0, 40.0);
            DVec2::new(-q.y, q.x) * 0.1
        }));
        assert!(r.at(70, 40).length() < 1e-6);
        assert!(Affine::fit(&[]).at(3, 3) == Vec2::ZERO);
    }

    #[test]
    fn affine_fit_turns_an_ellipse_rather_than_shearing_it() {
        // Points on a 3:1 ellipse turning about its centre at 0.05 rad/frame, with the exact
        // normal speeds of the turn. A shear along the outline gives the same speeds; the fit
        // must pick the turn. Relative errors at the three points: the ridge solution alone
        // 0.13, 1.10, 0.37; with the least strain 0.03, 0.23, 0.08 (held back a little by
        // `STILLNESS`).
        let (c, omega) = (DVec2::new(100.0, 80.0), 0.05);
        let pts: Vec<(DVec2, DVec2, f64)> = (0..400)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 400.0;
                let p = c + DVec2::new(60.0 * a.cos(), 20.0 * a.sin());
                let n = DVec2::new(a.cos() / 60.0, a.sin() / 20.0).normalize();
                let q = p - c;
                (p, n, n.dot(DVec2::new(-q.y, q.x) * omega))
            })
            .collect();
        let fit = Affine::fit(&pts);
        for (x, y) in [(160, 80), (100, 100), (130, 90)] {
            let q = DVec2::new(x as f64, y as f64) - c;
            let want = (DVec2::new(-q.y, q.x) * omega).as_vec2();
            let got = fit.at(x, y);
            assert!((got - want).length() < 0.3 * want.length(), "at ({x}, {y}): {got:?} vs {want:?}");
        }
    }

    #[test]
    fn eigen6_diagonalizes() {
        let m: [[f64; 6]; 6] =
            std::array::from_fn(|i| std::array::from_fn(|j| 1.0 / (1 + i + j) as f64 + if i == j { 0.5 } else { 0.0 }));
        let (values, v) = eigen6(&m);
        for k in 0..6 {
            for i in 0..6 {
                let mv: f64 = (0..6).map(|j| m[i][j] * v[j][k]).sum();
                assert!((mv - values[k] * v[i][k]).abs() < 1e-9, "column {k}, row {i}");
            }
            for l in 0..6 {
                let d: f64 = (0..6).map(|i| v[i][k] * v[i][l]).sum();
                assert!((d - if k == l { 1.0 } else { 0.0 }).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn components_are_labelled_separately() {
        let m = Plane::from_fn(10, 5, |x, y| !(3..=6).contains(&x) && y > 0);
        let fm = FrameMask::from_full(&m);
        let (labels, n) = label_components(&fm);
        assert_eq!(n, 2);
        assert_ne!(labels[0], labels[9]);
    }
}
