//! [`GuideStream`]: the guides of a long target sequence, frame by frame, in bounded memory.
//!
//! `ext−` needs the whole future of every pixel, so a backward pass must come first. Holding the
//! guides of every frame would take ~17 MB per 1000×800 frame (7 GB for 400 frames); instead:
//!
//! 1. **Backward pass** ([`GuideStreamBuilder::build`]): every mask is read once, pre-processed
//!    and kept bit-packed inside its bounding box (≤ 100 kB per 1000×800 frame). The flows are
//!    estimated from the last frame to the first with a sliding window ([`super::flow`]), the
//!    accumulator `acc−` is updated, and at the first frame of every segment of `K` frames
//!    (`K ≈ √n`) it is saved as a checkpoint, only at that frame's mask pixels.
//! 2. **Forward iteration**: a second sliding window estimates the flows again, from the first
//!    frame on. When a segment starts, its `K` flows are taken from it and kept at the mask
//!    pixels; `acc−` is run backwards over them from the checkpoint after the segment, keeping
//!    the segment's `ext−`; the frames are then handed out in order, with `ext+` accumulated on
//!    the way and the distance field computed for each.
//!
//! Peak memory is then a few full-frame planes, the two windows (one at a time), `n/K`
//! checkpoints and one segment — `O(√n)` frames' worth of mask pixels — for twice the flow
//! computations of the in-memory path. What grows with the sequence: one bit per pixel of each
//! mask's bounding box, 8 bytes per mask pixel per checkpoint and 12 bytes per mask pixel per
//! segment frame. Measured (`tests/guide_memory.rs`): 400 frames of 1000×800 with a moving blob
//! covering ~18 % of the frame peak at 142 MB resident for the whole test process (79 MB after
//! the backward pass; 29.5 MB of masks and checkpoints). The results are identical to
//! [`super::compute_sequence`]'s.

use super::crop::{Crop, FrameMask, PackedMask};
use super::extent::{EXTENT_QUANTILE, ExtentHistogram, accumulate, assemble, masked_user_flow, norms};
use super::flow::{FlowMachine, MaskProvider, check_size};
use super::preprocess::preprocess_frame;
use super::{FrameGuides, GuideParams};
use crate::error::{Error, Result};
use crate::img::Plane;
use crate::progress::Progress;
use glam::Vec2;
use std::sync::Arc;

/// A source of user-supplied flow fields: frame index → motion from that frame to the next,
/// pixels per frame.
pub type FlowSource = Box<dyn FnMut(usize) -> Result<Plane<Vec2>> + Send>;

/// The largest image (in pixels) guides are computed for.
const MAX_PIXELS: usize = 1 << 28;

pub(crate) fn check_image_size(w: usize, h: usize) -> Result<()> {
    if w.checked_mul(h).is_none_or(|n| n > MAX_PIXELS) {
        return Err(Error::param("mask size", format!("{w}x{h}"), format!("at most {MAX_PIXELS} pixels")));
    }
    Ok(())
}

/// Options of a [`GuideStream`]; see [`GuideStream::builder`].
pub struct GuideStreamBuilder<'p> {
    params: GuideParams,
    segment_len: Option<usize>,
    flow: Option<FlowSource>,
    progress: Option<&'p dyn Progress>,
    keep_flows: bool,
}

impl<'p> GuideStreamBuilder<'p> {
    /// Frames per segment of the forward iteration, `K`: `n/K` checkpoints of `acc−` and one
    /// segment of `K` frames' flows and `ext−` are kept (both at the mask pixels), so `K ≈ √n`
    /// keeps the sum small. Default: `⌈√n⌉`.
    pub fn segment_len(mut self, k: usize) -> Self {
        self.segment_len = Some(k.max(1));
        self
    }

    /// Uses these flow fields instead of estimating them: `source(i)` is the motion from frame `i`
    /// to `i+1` in pixels per frame (e.g. read with [`super::flo::read_flo`]); it is called twice
    /// per frame (backward pass, then in order). Inside the mask it is used as given, outside it is set to zero.
    /// Default: estimated from the masks.
    pub fn flow_source(mut self, source: impl FnMut(usize) -> Result<Plane<Vec2>> + Send + 'static) -> Self {
        self.flow = Some(Box::new(source));
        self
    }

    /// Keeps the flows the backward pass estimates (8 bytes per mask pixel per frame, released as
    /// the frames are handed out) instead of estimating them a second time in the forward
    /// iteration: memory then grows with the sequence, so this is for short sequences whose
    /// frames are held anyway (the passes between painted keyframes). Same results. Default: off.
    pub fn keep_flows(mut self, keep: bool) -> Self {
        self.keep_flows = keep;
        self
    }

    /// Reports the backward pass (stage `"guides: backward pass"`, one unit per frame) and
    /// lets it be cancelled. Default: none.
    pub fn progress(mut self, progress: &'p dyn Progress) -> Self {
        self.progress = Some(progress);
        self
    }

    /// Runs the backward pass over `frame_count` frames: `mask_source(i)` returns the raw mask
    /// (coverage in `0..=1`) of frame `i`; it is called exactly once per frame, here. Errors from
    /// the source are returned as they are; frames of different sizes are an
    /// [`Error::InvalidParam`].
    pub fn build(
        self,
        frame_count: usize,
        mut mask_source: impl FnMut(usize) -> Result<Plane<f32>>,
    ) -> Result<GuideStream> {
        self.params.validate()?;
        let n = frame_count;
        let seg_len = self.segment_len.unwrap_or_else(|| ((n as f64).sqrt().ceil() as usize).max(1));
        let mut s = GuideStream {
            n,
            size: (0, 0),
            params: self.params,
            masks: Vec::new(),
            checkpoints: vec![None; n.div_ceil(seg_len)],
            seg_len,
            flow: self.flow,
            machine: None,
            next: 0,
            seg: None,
            acc_pos: Plane::new(0, 0),
            prev_flow: None,
            failed: false,
            extent_scale: 0.0,
            kept: Vec::new(),
        };
        if n == 0 {
            return Ok(s);
        }
        let mut provider =
            SourceProvider { source: &mut mask_source, params: &s.params, packed: vec![None; n], size: None };
        let progress = self.progress;
        let mut done = 0;
        let mut acc = Plane::new(0, 0);
        let mut extents = ExtentHistogram::default();
        let seg_len = s.seg_len;
        let checkpoints = &mut s.checkpoints;
        let flow = &mut s.flow;
        let mut kept: Vec<Option<Vec<Vec2>>> = if self.keep_flows { vec![None; n] } else { Vec::new() };
        backward_flows(n, n - 1, 0, &s.params, flow, &mut provider, |j, mask, f| {
            if let Some(slot) = kept.get_mut(j) {
                *slot = Some(mask.gather(f));
            }
            if acc.is_empty() {
                acc = Plane::new(mask.w, mask.h);
            }
            if j + 1 < n {
                accumulate(&mut acc, mask, f);
            }
            let gathered = mask.gather_plane(&acc);
            for a in &gathered {
                extents.add(a.length());
            }
            if j % seg_len == 0 && j > 0 {
                checkpoints[j / seg_len - 1] = Some(gathered);
            }
            done += 1;
            match progress {
                Some(p) if !p.update("guides: backward pass", done, n) => Err(Error::Cancelled),
                _ => Ok(()),
            }
        })?;
        s.size = provider.size.unwrap_or((0, 0));
        s.masks = provider
            .packed
            .into_iter()
            .enumerate()
            .map(|(i, m)| m.ok_or_else(|| Error::param("frame", i, "a frame read by the backward pass")))
            .collect::<Result<_>>()?;
        s.acc_pos = Plane::new(s.size.0, s.size.1);
        s.kept = kept;
        s.extent_scale = extents.quantile(EXTENT_QUANTILE);
        Ok(s)
    }
}

/// The guides of a sequence, frame by frame in order, computed in bounded memory (see the module
/// docs of `guide::stream` for how). Iterating yields `Result<FrameGuides>`; after an error the
/// stream ends.
///
/// ```
/// # use fluidymation::{guide::{GuideParams, GuideStream}, img::Plane};
/// let disc = |i: usize| Plane::from_fn(48, 40, move |x, y| {
///     let (dx, dy) = (x as f32 - 20.0 - i as f32, y as f32 - 20.0);
///     if dx * dx + dy * dy < 100.0 { 1.0 } else { 0.0 }
/// });
/// let params = GuideParams::default().blur_sigma(1.0);
/// let stream = GuideStream::new(6, |i| Ok(disc(i)), &params)?;
/// for g in stream {
///     let g = g?;
///     assert_eq!(g.mask.size(), (48, 40));
/// }
/// # Ok::<(), fluidymation::Error>(())
/// ```
pub struct GuideStream {
    n: usize,
    size: (usize, usize),
    params: GuideParams,
    masks: Vec<PackedMask>,
    /// `acc−` at the first frame after segment `k`, at that frame's mask pixels.
    checkpoints: Vec<Option<Vec<Vec2>>>,
    seg_len: usize,
    flow: Option<FlowSource>,
    /// The forward window of the second pass (created at the first frame).
    machine: Option<FlowMachine>,
    next: usize,
    seg: Option<SegmentBuf>,
    acc_pos: Plane<Vec2>,
    prev_flow: Option<Crop<Vec2>>,
    failed: bool,
    extent_scale: f32,
    /// The backward pass's flows at the mask pixels, if kept ([`GuideStreamBuilder::keep_flows`]).
    kept: Vec<Option<Vec<Vec2>>>,
}

/// One segment's final flows and `ext−` at the mask pixels of each frame.
struct SegmentBuf {
    start: usize,
    flows: Vec<Vec<Vec2>>,
    ext_neg: Vec<Vec<f32>>,
}

impl GuideStream {
    /// Runs the backward pass with default options; see [`GuideStreamBuilder::build`].
    pub fn new(
        frame_count: usize,
        mask_source: impl FnMut(usize) -> Result<Plane<f32>>,
        params: &GuideParams,
    ) -> Result<GuideStream> {
        Self::builder(params).build(frame_count, mask_source)
    }

    /// A builder with the default options.
    pub fn builder(params: &GuideParams) -> GuideStreamBuilder<'static> {
        GuideStreamBuilder { params: params.clone(), segment_len: None, flow: None, progress: None, keep_flows: false }
    }

    /// Number of frames.
    pub fn frame_count(&self) -> usize {
        self.n
    }

    /// Frame size `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        self.size
    }

    /// The sequence's extent scale, [`super::extent_scale`] of all its frames (from the
    /// backward pass), for [`crate::synth::Synthesizer::set_target_extent`].
    pub fn extent_scale(&self) -> f32 {
        self.extent_scale
    }

    /// Bytes held between frames by the stored masks and the checkpoints not used yet (not
    /// counting the current segment and the working planes).
    pub fn stored_bytes(&self) -> usize {
        self.masks.iter().map(PackedMask::bytes).sum::<usize>()
            + self.checkpoints.iter().chain(&self.kept).flatten().map(|c| c.len() * size_of::<Vec2>()).sum::<usize>()
    }

    fn mask(&self, i: usize) -> Arc<FrameMask> {
        Arc::new(self.masks[i].unpack())
    }

    /// The flow of frame `i` from the forward pass (frames are asked for in order).
    fn forward_flow(&mut self, i: usize, mask: &FrameMask) -> Result<Crop<Vec2>> {
        if let Some(src) = &mut self.flow {
            let flow = src(i)?;
            check_size(flow.size(), (mask.w, mask.h), "flow", i)?;
            return Ok(masked_user_flow(mask, &flow));
        }
        let n = self.n;
        let machine = self.machine.get_or_insert_with(|| FlowMachine::new(n, true, 0, n - 1, &self.params));
        let mut provider = PackedProvider { masks: &self.masks };
        match machine.next_output(&mut provider)? {
            Some((j, _, f)) if j == i => Ok(f),
            _ => Err(Error::param("frame", i, "frames in order")),
        }
    }

    /// Takes segment `k`'s flows from the forward pass and runs `acc−` backwards over them from
    /// the checkpoint after the segment.
    fn load_segment(&mut self, k: usize) -> Result<SegmentBuf> {
        let (w, h) = self.size;
        let start = k * self.seg_len;
        let end = (start + self.seg_len).min(self.n);
        let mut masks = Vec::with_capacity(end - start);
        let mut flows = Vec::with_capacity(end - start);
        for i in start..end {
            let mask = self.mask(i);
            match self.kept.get_mut(i).and_then(Option::take) {
                Some(f) => flows.push(f),
                None => {
                    let f = self.forward_flow(i, &mask)?;
                    flows.push(mask.gather(&f));
                }
            }
            masks.push(mask);
        }
        // The checkpoint is used once: free it.
        let mut acc = match (end < self.n, self.checkpoints[k].take()) {
            (true, Some(c)) => self.mask(end).scatter(&c).to_full(w, h),
            _ => Plane::new(w, h),
        };
        let mut ext_neg = vec![Vec::new(); end - start];
        for i in (start..end).rev() {
            let mask = &masks[i - start];
            if i + 1 < self.n {
                accumulate(&mut acc, mask, &mask.scatter(&flows[i - start]));
            }
            ext_neg[i - start] = mask.gather_plane(&acc).iter().map(|a| a.length()).collect();
        }
        Ok(SegmentBuf { start, flows, ext_neg })
    }

    fn emit(&mut self) -> Result<FrameGuides> {
        let i = self.next;
        let k = i / self.seg_len;
        let seg = match self.seg.take() {
            Some(seg) if seg.start == k * self.seg_len => seg,
            old => {
                drop(old); // before the next segment is built
                self.load_segment(k)?
            }
        };
        let mask = self.mask(i);
        let (flow, ext_neg) = (mask.scatter(&seg.flows[i - seg.start]), mask.scatter(&seg.ext_neg[i - seg.start]));
        self.seg = Some(seg);
        if let Some(prev) = &self.prev_flow {
            accumulate(&mut self.acc_pos, &mask, prev);
        }
        let (w, h) = self.size;
        let g = assemble(&mask, &flow, norms(&self.acc_pos), ext_neg.to_full(w, h));
        self.prev_flow = Some(flow);
        Ok(g)
    }
}

impl Iterator for GuideStream {
    type Item = Result<FrameGuides>;

    fn next(&mut self) -> Option<Result<FrameGuides>> {
        if self.failed || self.next >= self.n {
            return None;
        }
        let r = self.emit();
        match r {
            Ok(_) => self.next += 1,
            Err(_) => self.failed = true,
        }
        if self.next == self.n {
            self.seg = None;
            self.machine = None;
        }
        Some(r)
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let left = if self.failed { 0 } else { self.n - self.next };
        (0, Some(left))
    }
}

/// Calls `f(j, mask_j, flow_j)` for `j = first, first − 1, …, last` (`first ≥ last`): the final
/// flows, estimated or user-supplied.
fn backward_flows(
    n: usize,
    first: usize,
    last: usize,
    params: &GuideParams,
    user: &mut Option<FlowSource>,
    provider: &mut dyn MaskProvider,
    mut f: impl FnMut(usize, &FrameMask, &Crop<Vec2>) -> Result<()>,
) -> Result<()> {
    match user {
        Some(src) => {
            for j in (last..=first).rev() {
                let mask = provider.mask(j)?;
                let flow = src(j)?;
                check_size(flow.size(), (mask.w, mask.h), "flow", j)?;
                f(j, &mask, &masked_user_flow(&mask, &flow))?;
            }
        }
        None => {
            let mut machine = FlowMachine::new(n, false, first, last, params);
            while let Some((j, mask, flow)) = machine.next_output(provider)? {
                f(j, &mask, &flow)?;
            }
        }
    }
    Ok(())
}

/// Reads masks from the user's source once each, keeping them packed.
struct SourceProvider<'a, S: FnMut(usize) -> Result<Plane<f32>>> {
    source: &'a mut S,
    params: &'a GuideParams,
    packed: Vec<Option<PackedMask>>,
    size: Option<(usize, usize)>,
}

impl<S: FnMut(usize) -> Result<Plane<f32>>> MaskProvider for SourceProvider<'_, S> {
    fn mask(&mut self, i: usize) -> Result<Arc<FrameMask>> {
        if let Some(p) = &self.packed[i] {
            return Ok(Arc::new(p.unpack()));
        }
        let cov = (self.source)(i)?;
        match self.size {
            Some(s) => check_size(cov.size(), s, "mask", i)?,
            None => {
                check_image_size(cov.width(), cov.height())?;
                self.size = Some(cov.size());
            }
        }
        let m = preprocess_frame(&cov, self.params);
        self.packed[i] = Some(m.pack());
        Ok(Arc::new(m))
    }
}

/// Masks already packed by the backward pass.
struct PackedProvider<'a> {
    masks: &'a [PackedMask],
}

impl MaskProvider for PackedProvider<'_> {
    fn mask(&mut self, i: usize) -> Result<Arc<FrameMask>> {
        Ok(Arc::new(self.masks[i].unpack()))
    }
}
