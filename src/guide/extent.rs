//! Motion extent `I^ext+` and `I^ext−` (paper §3.3, thesis §3.5) and the in-memory entry point
//! [`compute_sequence`].
//!
//! With `flow(i)` the motion `i → i+1` (see [`super::flow`]), frames counted from 0 to `n − 1`:
//!
//! * `acc+(0) = 0`, `acc+(i) = [p ∈ mask_i] · (acc+(i−1) + flow(i−1))`, `ext+(i) = ‖acc+(i)‖`;
//! * `acc−(n−1) = 0`, `acc−(i) = [p ∈ mask_i] · (acc−(i+1) + flow(i))`, `ext−(i) = ‖acc−(i)‖`.
//!
//! The accumulators are 2D vectors, so motion that is undone (forward then back) returns
//! `ext+` to zero, as the thesis requires; they restart wherever the material disappears.
//! `flow(i−1)` is zero outside `mask_{i−1}`, so a pixel the paint has just reached starts at 0.

use super::crop::{Crop, FrameMask};
use super::flow::{FlowMachine, SliceProvider, check_size};
use super::preprocess::preprocess_frame;
use super::{FrameGuides, GuideParams};
use crate::error::Result;
use crate::img::Plane;
use glam::Vec2;
use rayon::prelude::*;
use std::sync::Arc;

/// One step of either recurrence: `acc ← [p ∈ mask] · (acc + flow)`, with `flow` zero outside its
/// rectangle. The same function serves both entry points, so they agree to the bit.
pub(crate) fn accumulate(acc: &mut Plane<Vec2>, mask: &FrameMask, flow: &Crop<Vec2>) {
    let w = acc.width();
    acc.data_mut().par_chunks_mut(w.max(1)).enumerate().for_each(|(y, row)| {
        for (x, a) in row.iter_mut().enumerate() {
            *a = if mask.contains(x, y) { *a + flow.get(x, y) } else { Vec2::ZERO };
        }
    });
}

/// A histogram of motion extents (pixels, in steps of 1/4 up to 16 384) for their quantiles:
/// how far the material of a whole sequence moves, in the bounded memory of a stream.
#[derive(Clone, Debug)]
pub struct ExtentHistogram {
    bins: Vec<u64>,
    count: u64,
}

impl Default for ExtentHistogram {
    fn default() -> Self {
        ExtentHistogram { bins: vec![0; Self::BINS], count: 0 }
    }
}

impl ExtentHistogram {
    const STEP: f32 = 0.25;
    const BINS: usize = 65_536;

    /// Counts one extent.
    pub fn add(&mut self, v: f32) {
        if v.is_finite() {
            let k = ((v.max(0.0) / Self::STEP) as usize).min(Self::BINS - 1);
            self.bins[k] += 1;
            self.count += 1;
        }
    }

    /// The q-quantile (`0..=1`), to the bin's upper edge; 0 without values.
    pub fn quantile(&self, q: f32) -> f32 {
        if self.count == 0 {
            return 0.0;
        }
        let want = ((q.clamp(0.0, 1.0) as f64 * self.count as f64).ceil() as u64).max(1);
        let mut seen = 0;
        for (k, &n) in self.bins.iter().enumerate() {
            seen += n;
            if seen >= want {
                return if k == 0 && self.bins[0] == seen { 0.0 } else { (k + 1) as f32 * Self::STEP };
            }
        }
        Self::BINS as f32 * Self::STEP
    }
}

/// The extent scale of a sequence: the 95th percentile of `ext−` over the mask pixels of all its
/// frames — how far most of its material moves (0 for a sequence that does not move). The
/// synthesis compares the target's extents with the exemplar's after bringing this scale of
/// the target down to the exemplar's ([`crate::synth::Synthesizer::set_target_extent`]).
pub fn extent_scale(guides: &[FrameGuides]) -> f32 {
    let mut h = ExtentHistogram::default();
    for g in guides {
        for (&v, &m) in g.ext_neg.data().iter().zip(g.mask.data()) {
            if m {
                h.add(v);
            }
        }
    }
    h.quantile(EXTENT_QUANTILE)
}

/// The quantile of [`extent_scale`].
pub const EXTENT_QUANTILE: f32 = 0.95;

/// `‖acc‖` per pixel.
pub(crate) fn norms(acc: &Plane<Vec2>) -> Plane<f32> {
    let (w, h) = acc.size();
    let mut out = Plane::new(w, h);
    out.data_mut().par_iter_mut().zip(acc.data().par_iter()).for_each(|(o, a)| *o = a.length());
    out
}

/// The full [`FrameGuides`] of a frame from its mask, final flow and extents.
pub(crate) fn assemble(mask: &FrameMask, flow: &Crop<Vec2>, ext_pos: Plane<f32>, ext_neg: Plane<f32>) -> FrameGuides {
    let full = mask.to_full();
    let dist = super::sdf::sdf(&full);
    FrameGuides { mask: full, dist, flow: flow.to_full(mask.w, mask.h), ext_pos, ext_neg }
}

/// All guides of a sequence held in memory (an exemplar): `coverages` are the raw masks
/// (coverage in `0..=1`, e.g. the alpha of a rendered layer), all of one size. The result is
/// identical to what [`super::GuideStream`] yields for the same frames.
pub fn compute_sequence(coverages: &[Plane<f32>], params: &GuideParams) -> Result<Vec<FrameGuides>> {
    compute(coverages, None, params)
}

/// [`compute_sequence`] with user-supplied flow fields instead of the estimate: `flows[i]` is the
/// motion from frame `i` to frame `i+1` in pixels per frame (the Middlebury convention, see
/// [`super::flo`]), used as given inside the mask and set to zero outside it.
pub fn compute_sequence_with_flow(
    coverages: &[Plane<f32>],
    flows: &[Plane<Vec2>],
    params: &GuideParams,
) -> Result<Vec<FrameGuides>> {
    if flows.len() != coverages.len() {
        return Err(crate::Error::param(
            "flow",
            format!("{} flow fields", flows.len()),
            format!("one flow field per mask frame ({})", coverages.len()),
        ));
    }
    compute(coverages, Some(flows), params)
}

/// A user flow field restricted to the mask (zero elsewhere), over the mask's bounding box.
pub(crate) fn masked_user_flow(mask: &FrameMask, flow: &Plane<Vec2>) -> Crop<Vec2> {
    let r = mask.rect();
    let inside = &mask.crop.plane;
    Crop {
        rect: r,
        plane: Plane::from_fn(r.width(), r.height(), |x, y| {
            if inside.get(x, y) { flow.get(x + r.x0, y + r.y0) } else { Vec2::ZERO }
        }),
    }
}

fn compute(coverages: &[Plane<f32>], user: Option<&[Plane<Vec2>]>, params: &GuideParams) -> Result<Vec<FrameGuides>> {
    params.validate()?;
    let Some(first) = coverages.first() else { return Ok(Vec::new()) };
    let (w, h) = first.size();
    super::stream::check_image_size(w, h)?;
    for (i, c) in coverages.iter().enumerate() {
        check_size(c.size(), (w, h), "mask", i)?;
        if let Some(f) = user {
            check_size(f[i].size(), (w, h), "flow", i)?;
        }
    }
    let n = coverages.len();
    let masks: Vec<Arc<FrameMask>> = coverages.par_iter().map(|c| Arc::new(preprocess_frame(c, params))).collect();
    let flows: Vec<Crop<Vec2>> = match user {
        Some(f) => masks.iter().zip(f).map(|(m, f)| masked_user_flow(m, f)).collect(),
        None => {
            let mut provider = SliceProvider { masks: &masks };
            let mut machine = FlowMachine::new(n, true, 0, n - 1, params);
            let mut out = Vec::with_capacity(n);
            while let Some((_, _, f)) = machine.next_output(&mut provider)? {
                out.push(f);
            }
            out
        }
    };
    let mut ext_neg = vec![Plane::new(0, 0); n];
    let mut acc = Plane::new(w, h);
    for i in (0..n).rev() {
        if i + 1 < n {
            accumulate(&mut acc, &masks[i], &flows[i]);
        }
        ext_neg[i] = norms(&acc);
    }
    let mut acc = Plane::new(w, h);
    let mut out = Vec::with_capacity(n);
    for (i, en) in ext_neg.into_iter().enumerate() {
        if i > 0 {
            accumulate(&mut acc, &masks[i], &flows[i - 1]);
        }
        out.push(assemble(&masks[i], &flows[i], norms(&acc), en));
    }
    Ok(out)
}
