//! Painted keyframes (issue 15; Bénard et al. 2013, §4): the user paints over one or more frames
//! of the target, and every other frame is synthesized from those paintings.
//!
//! Each keyframe is a still exemplar ([`key_source`]): its painting, with the target's coverage
//! at its frame as the mask (the border channel comes from it, as for any exemplar). At the
//! keyframe the output *is* the painting, and the field is the identity
//! ([`Synthesizer::begin_at_source`]); the frames after it are synthesized in order, each from
//! the previous one's field carried along the target's motion (SHIFTNNF's residual advection
//! carries all of it, a still having no time axis) and held by the temporal term — the
//! *forward pass*. The frames before it are synthesized the same way in reverse order, the
//! target's motion running backwards — the *backward pass* (its guide stream is computed over
//! the reversed frames). Before the first keyframe there is only a backward pass from it, after
//! the last only a forward pass.
//!
//! **Between two keyframes A < B** both passes run — forward from A, backward from B — and
//! frame j takes each pixel from one of them, not a mix of their colors: linear blending of two
//! textures is ghosting, and it halves their contrast in the middle (Bénard et al. §2.1). The
//! choice follows the time: the pixel comes from the backward pass (painting B) when
//! `v(p) < t`, `t = (j − A)/(B − A)`, else from the forward pass (painting A). `v` is a
//! cellular noise, uniform in [0, 1), of the pixel's *material coordinates* `p` — where it was
//! at keyframe A, carried frame by frame along the target's own motion (its flow guide) — so
//! each bit of paint changes from A's to B's once, in blobs of about [`CELL`] pixels that grow
//! as t rises, and the blobs travel with the shape instead of swimming over it. Only across the
//! seam between a blob of A and one of B are the two cross-faded, over `SEAM` (1) pixel to each
//! side, which softens the blobs' straight edges without a visible blend.
//!
//! **The target's motion** is its flow guide, estimated from the masks — or, where the caller
//! knows the target's true motion for every step of a pass ([`Motion`]; for a Lottie layer or an
//! SVG sequence's, the step of its fills' transforms and of their animated outlines,
//! [`crate::anim::Animation::fill_motion_to`]), that motion: masks show only the normal part of
//! a motion (a turning disc looks still), so paint carried along them slides over a part that
//! turns. The guides' other channels are computed from it as from an estimated flow (a still
//! has no motion extents of its own, so the target's add the same cost to every candidate).
//!
//! The choice is known before either pass paints anything (it depends on the target alone), so
//! **each pass paints only the part of the frame it gives** — the forward pass where A's paint
//! is still seen, the backward pass where B's already is, each with a margin of `MARGIN` (3)
//! pixels; the guide channels stay those of the whole shape, so the rim is where the shape's rim
//! is. Between them the two passes paint about one frame and a half per frame instead of two.
//! The forward pass runs first and its frames are held until the backward pass meets them.
//!
//! Simplifications (see the README): Bénard et al. select per pixel at random with the same
//! time weights and then optimize the frame once more, so that propagation can heal the
//! seams between the two passes; here the selection is final (a seam between two blobs is
//! where A's and B's paint meet). Their orientation field and ribbons are not used (the carried
//! field is the position in the painting; a patch turns only as the shape does, by the local
//! rotation of its motion, [`super::ParamsBuilder::turn`]). The forward pass of one
//! gap between keyframes is held in memory until the backward pass meets it, with the choice
//! (17 bytes a pixel a frame), and each pass keeps the flows of its guide stream rather than
//! estimate them twice (8 bytes a masked pixel a frame, until used).

use super::params::HALF;
use super::{Params, Source, SynthFrame, Synthesizer};
use crate::error::{Error, Result};
use crate::exemplar::{Exemplar, ExemplarMeta};
use crate::guide::{FrameGuides, GuideStream};
use crate::img::{Mask, Plane, Rgb};
use crate::progress::Progress;
use glam::Vec2;

/// A painted keyframe: the painting of target frame `frame` (0-based), the size of the target's
/// frames. Only the pixels inside the target's mask at that frame are used.
#[derive(Clone, Debug)]
pub struct Keyframe {
    /// The target frame it paints (0-based).
    pub frame: usize,
    /// The painting.
    pub painting: Plane<Rgb>,
    /// Which part of the painting is this target's paint (coverage, 0–1); `None`: the target's
    /// coverage at the frame. Where something above the target hides it (another layer of
    /// the animation), the painting shows that instead, and the mask leaves it out.
    pub mask: Option<Plane<f32>>,
}

/// One frame painted from keyframes: colors (the paintings' own) and the mask (the output's
/// alpha).
#[derive(Clone, Debug)]
pub struct KeyedFrame {
    /// The colors.
    pub rgb: Plane<Rgb>,
    /// Where paint is.
    pub mask: Mask,
}

/// Side of the cells of the noise that chooses, between two keyframes, which pass each pixel
/// comes from, in painting pixels: about five patches, so that a blob holds whole patches of
/// one painting and the seams between blobs are few.
pub const CELL: f32 = 24.0;

/// The still exemplar of keyframe `key`: its painting with its mask ([`Keyframe::mask`], by
/// default `coverage`, the target's coverage at the keyframe). The border width is `params`'s, else estimated from the painting
/// as for any exemplar.
pub fn key_source(key: &Keyframe, coverage: &Plane<f32>, params: &Params) -> Result<Source> {
    if key.painting.size() != coverage.size() {
        return Err(Error::param(
            "keyframe size",
            format!("{}x{} (frame {})", key.painting.width(), key.painting.height(), key.frame + 1),
            format!("{}x{}, the size of the target's frames", coverage.width(), coverage.height()),
        ));
    }
    let masks = vec![key.mask.clone().unwrap_or_else(|| coverage.clone())];
    if masks[0].size() != coverage.size() {
        return Err(Error::param(
            "keyframe mask size",
            format!("{}x{} (frame {})", masks[0].width(), masks[0].height(), key.frame + 1),
            format!("{}x{}, the size of the target's frames", coverage.width(), coverage.height()),
        ));
    }
    let guides = crate::guide::compute_sequence(&masks, params.guide())?;
    let border = match params.border_width {
        Some(b) => b,
        None => {
            let outside: Vec<Rgb> =
                key.painting.data().iter().zip(masks[0].data()).filter(|(_, m)| **m < 0.5).map(|(c, _)| *c).collect();
            let mean = |k: usize| outside.iter().map(|c| c[k]).sum::<f32>() / outside.len().max(1) as f32;
            let ex = Exemplar {
                dir: None,
                meta: ExemplarMeta::new("keyframe", [mean(0), mean(1), mean(2)]),
                frames: vec![key.painting.clone()],
                masks,
            };
            crate::exemplar::border::estimate_border_width(&ex).width
        }
    };
    Source::from_parts(std::slice::from_ref(&key.painting), &guides, params, border)
}

/// The coverage of target frame k.
pub type Coverage<'a> = &'a (dyn Fn(usize) -> Result<Plane<f32>> + Sync);

/// The target's true motion from frame `from` to frame `to` (neighbours, either way in time),
/// pixels, where it is known — for a Lottie layer, the step of the transforms its fills are
/// drawn with ([`crate::anim::Animation::fill_motion_to`]): per pixel, `None` where it is not
/// known; `Ok(None)` when it is not known for that pair at all.
pub type Motion<'a> = &'a (dyn Fn(usize, usize) -> Result<Option<Plane<Option<Vec2>>>> + Sync);

/// Paints every frame of a `frames`-frame target from its painted keyframes `keys` (any order;
/// at least one, at most one per frame) and hands them to `emit` in order, frame index first.
/// Reports every frame synthesized, in either pass, to `progress` as one unit of `stage` (of
/// [`pass_frames`] in all); when it asks to stop, returns [`Error::Cancelled`].
#[allow(clippy::too_many_arguments)]
pub fn paint(
    params: &Params,
    frames: usize,
    coverage: Coverage<'_>,
    motion: Option<Motion<'_>>,
    keys: &[Keyframe],
    emit: &mut dyn FnMut(usize, KeyedFrame) -> Result<()>,
    stage: &str,
    progress: &dyn Progress,
) -> Result<()> {
    // The paintings' grain is carried, not re-sampled from a paint video: the phase gain
    // ([`super::ParamsBuilder::grain_phase`]) would only add change between frames here; and
    // the output at a keyframe is the painting, whose tone the matching
    // ([`super::ParamsBuilder::tone_match`]) must not move.
    let params = &params.to_builder().grain_phase(false).tone_match(false).build()?;
    let mut keys: Vec<&Keyframe> = keys.iter().collect();
    keys.sort_by_key(|k| k.frame);
    if keys.is_empty() {
        return Err(Error::param("keyframes", "none", "at least one painted keyframe"));
    }
    for (a, b) in keys.iter().zip(keys.iter().skip(1)) {
        if a.frame == b.frame {
            return Err(Error::param("keyframes", format!("two of frame {}", a.frame + 1), "one painting per frame"));
        }
    }
    if let Some(k) = keys.iter().find(|k| k.frame >= frames) {
        return Err(Error::param("keyframe", k.frame + 1, format!("a frame of the target (1–{frames})")));
    }
    let total = pass_frames(frames, keys.iter().map(|k| k.frame));
    let mut done = 0;
    let mut tick = || -> Result<()> {
        done += 1;
        if progress.update(stage, done, total) { Ok(()) } else { Err(Error::Cancelled) }
    };
    let sources: Vec<Source> = {
        use rayon::prelude::*;
        keys.par_iter().map(|k| key_source(k, &coverage(k.frame)?, params)).collect::<Result<_>>()?
    };
    let seed = params.seed;
    // Before the first keyframe: backward from it.
    let first = keys[0].frame;
    if first > 0 {
        let seq: Vec<usize> = (0..=first).rev().collect();
        let mut held = Held::new(first);
        pass(&sources[0], params, &seq, guides(&seq, coverage, motion, params)?, &mut |_, _| {}, &mut |j, out| {
            tick()?;
            held.put(j, out);
            Ok(())
        })?;
        for j in 0..first {
            emit(j, held.take(j)?)?;
        }
    }
    for (a, key) in keys.iter().enumerate() {
        emit(key.frame, painted(key, &coverage(key.frame)?))?;
        let Some(next) = keys.get(a + 1) else {
            // After the last keyframe: forward from it.
            let seq: Vec<usize> = (key.frame..frames).collect();
            return pass(
                &sources[a],
                params,
                &seq,
                guides(&seq, coverage, motion, params)?,
                &mut |_, _| {},
                &mut |j, out| {
                    tick()?;
                    emit(j, KeyedFrame { rgb: out.rgb, mask: out.mask })
                },
            );
        };
        let (ka, kb) = (key.frame, next.frame);
        if kb == ka + 1 {
            continue;
        }
        // Forward from A, held; then backward from B, each frame merged into the held one; each
        // pass paints only the part of the frame that it gives (`Split`).
        let mut split = Split::new(ka, kb, seed ^ ((ka as u64) << 32) ^ kb as u64);
        let mut held = Held::new(kb);
        let seq_a: Vec<usize> = (ka..kb).collect();
        let seq_b: Vec<usize> = (ka + 1..=kb).rev().collect();
        // The backward pass's guides are computed while the forward pass paints (it leaves a
        // core idle part of the time) — as a job of the thread pool, not a thread of its own:
        // layers are painted in the pool's threads, and one of them blocked waiting for a thread
        // that waits for the pool could leave no thread to run it.
        let mut stream_b = None;
        rayon::in_place_scope(|s| -> Result<()> {
            s.spawn(|_| stream_b = Some(guides(&seq_b, coverage, motion, params)));
            let stream_a = guides(&seq_a, coverage, motion, params)?;
            pass(&sources[a], params, &seq_a, stream_a, &mut |k, g| split.forward(k, g), &mut |j, out| {
                tick()?;
                held.put(j, out);
                Ok(())
            })
        })?;
        let stream_b = stream_b.ok_or_else(|| Error::param("keyframe pass", "no guides", "the backward pass's"))??;
        pass(&sources[a + 1], params, &seq_b, stream_b, &mut |k, g| split.backward(seq_b[k], g), &mut |j, out| {
            tick()?;
            let fwd = held.take(j)?;
            held.put_keyed(j, split.merge(j, fwd, out)?);
            Ok(())
        })?;
        for j in ka + 1..kb {
            emit(j, held.take(j)?)?;
        }
    }
    Ok(())
}

/// How many frames [`paint`] synthesizes for a `frames`-frame target with keyframes at these
/// (0-based, different) frames: one pass before the first keyframe and one after the last, two
/// between keyframes (forward and backward) — the units of its progress.
pub fn pass_frames(frames: usize, keys: impl IntoIterator<Item = usize>) -> usize {
    let mut keys: Vec<usize> = keys.into_iter().collect();
    keys.sort_unstable();
    match (keys.first(), keys.last()) {
        (Some(&first), Some(&last)) => {
            first
                + frames.saturating_sub(last + 1)
                + keys.windows(2).map(|w| 2 * w[1].saturating_sub(w[0] + 1)).sum::<usize>()
        }
        _ => 0,
    }
}

/// The keyframe's own output: its painting, with the target's mask.
fn painted(key: &Keyframe, coverage: &Plane<f32>) -> KeyedFrame {
    KeyedFrame { rgb: key.painting.clone(), mask: coverage.map(|v| v >= 0.5) }
}

/// Frames of a backward pass, held until they are merged or emitted in order.
struct Held(Vec<Option<KeyedFrame>>);

impl Held {
    fn new(len: usize) -> Held {
        Held(vec![None; len])
    }

    fn put(&mut self, j: usize, out: SynthFrame) {
        self.put_keyed(j, KeyedFrame { rgb: out.rgb, mask: out.mask });
    }

    fn put_keyed(&mut self, j: usize, f: KeyedFrame) {
        if let Some(slot) = self.0.get_mut(j) {
            *slot = Some(f);
        }
    }

    fn take(&mut self, j: usize) -> Result<KeyedFrame> {
        self.0
            .get_mut(j)
            .and_then(Option::take)
            .ok_or_else(|| Error::param("keyframe pass", format!("frame {}", j + 1), "a frame painted by a pass"))
    }
}

/// The guides of the target frames `seq`, in that order. Their flows are the target's true
/// motion where `motion` knows it for every step of `seq` ([`true_flows`]), else estimated
/// from the masks.
fn guides(seq: &[usize], coverage: Coverage<'_>, motion: Option<Motion<'_>>, params: &Params) -> Result<GuideStream> {
    // A pass's frames are held anyway: keep the flows rather than estimate them twice.
    let builder = GuideStream::builder(params.guide()).keep_flows(true);
    let builder = match motion.map(|m| true_flows(seq, m)).transpose()?.flatten() {
        Some(flows) => builder.flow_source(move |k| Ok(flows[k].plane())),
        None => builder,
    };
    builder.build(seq.len(), |k| coverage(seq[k]))
}

/// The flows of a pass along `seq` from the target's true motion: frame `seq[k]`'s motion to
/// `seq[k + 1]` (zero past the last frame, where the pass ends), `None` when a step is not
/// known (or there is none). Pixels with no motion of their own (e.g. a stroke's, when strokes
/// are painted, or an antialiased rim pixel) take the nearest known one within [`HOLE_REACH`]
/// pixels, else zero; the guide stream zeroes it outside the mask. Each is kept only over the
/// box where it is not zero ([`BoxedFlow`]).
fn true_flows(seq: &[usize], motion: Motion<'_>) -> Result<Option<Vec<BoxedFlow>>> {
    let mut out = Vec::with_capacity(seq.len());
    for w in seq.windows(2) {
        let Some(m) = motion(w[0], w[1])? else { return Ok(None) };
        out.push(BoxedFlow::new(&m));
    }
    let Some(size) = out.last().map(|f| f.size) else { return Ok(None) };
    out.push(BoxedFlow { size, origin: (0, 0), part: Plane::new(0, 0) });
    Ok(Some(out))
}

/// A flow that is zero outside a box: the box's part, kept for a pass.
struct BoxedFlow {
    size: (usize, usize),
    origin: (usize, usize),
    part: Plane<Vec2>,
}

impl BoxedFlow {
    /// The motion `m` with its holes filled ([`fill_holes`]), over the bounding box of its
    /// known pixels widened by [`HOLE_REACH`].
    fn new(m: &Plane<Option<Vec2>>) -> BoxedFlow {
        let (w, h) = m.size();
        let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
        for y in 0..h {
            for x in 0..w {
                if m.get(x, y).is_some() {
                    (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x + 1), y1.max(y + 1));
                }
            }
        }
        if x0 >= x1 {
            return BoxedFlow { size: (w, h), origin: (0, 0), part: Plane::new(0, 0) };
        }
        let (x0, y0) = (x0.saturating_sub(HOLE_REACH), y0.saturating_sub(HOLE_REACH));
        let (x1, y1) = ((x1 + HOLE_REACH).min(w), (y1 + HOLE_REACH).min(h));
        let part = Plane::par_from_fn(x1 - x0, y1 - y0, |x, y| fill_holes(m, x0 + x, y0 + y));
        BoxedFlow { size: (w, h), origin: (x0, y0), part }
    }

    /// The whole frame's flow.
    fn plane(&self) -> Plane<Vec2> {
        let ((x0, y0), (bw, bh)) = (self.origin, self.part.size());
        Plane::par_from_fn(self.size.0, self.size.1, |x, y| {
            if x >= x0 && y >= y0 && x < x0 + bw && y < y0 + bh { self.part.get(x - x0, y - y0) } else { Vec2::ZERO }
        })
    }
}

/// How far, pixels, [`fill_holes`] looks for a known motion.
const HOLE_REACH: usize = 4;

/// The motion at (x, y): `m`'s own, or else the known motion nearest to it (in rings of growing
/// Chebyshev distance, the first found in row order) within [`HOLE_REACH`] pixels, else zero.
fn fill_holes(m: &Plane<Option<Vec2>>, x: usize, y: usize) -> Vec2 {
    let (w, h) = m.size();
    if let Some(v) = m.get(x, y) {
        return v;
    }
    for r in 1..=HOLE_REACH as isize {
        for dy in -r..=r {
            for dx in -r..=r {
                if dx.abs() != r && dy.abs() != r {
                    continue;
                }
                let (qx, qy) = (x as isize + dx, y as isize + dy);
                if qx >= 0
                    && qy >= 0
                    && (qx as usize) < w
                    && (qy as usize) < h
                    && let Some(v) = m.get(qx as usize, qy as usize)
                {
                    return v;
                }
            }
        }
    }
    Vec2::ZERO
}

/// One pass from a keyframe along `seq` (target frame indices; `seq[0]` is the keyframe's),
/// guided by `stream` (their guides), handing every later frame to `emit`. `restrict(k, g)` may narrow the mask of the guides of
/// `seq[k]` to the part the pass has to paint (the guide channels stay those of the whole shape).
fn pass(
    source: &Source,
    params: &Params,
    seq: &[usize],
    stream: GuideStream,
    restrict: &mut dyn FnMut(usize, &mut FrameGuides),
    emit: &mut dyn FnMut(usize, SynthFrame) -> Result<()>,
) -> Result<()> {
    let mut synth = Synthesizer::new(source.clone(), params.clone())?;
    synth.set_target_extent(stream.extent_scale());
    for (k, g) in stream.enumerate() {
        let mut g = g?;
        restrict(k, &mut g);
        if k == 0 {
            synth.begin_at_source(&g)?;
        } else {
            emit(seq[k], synth.step(&g)?)?;
        }
    }
    Ok(())
}

/// Margin around the part of a frame that a pass between two keyframes gives, pixels: the pass
/// paints this much more, so that the pixels it gives are not at the edge of what it painted.
const MARGIN: usize = HALF + 1;

/// Between keyframes A and B: which painting each pixel of each frame comes from, `k` = the
/// share of the later painting ([`from_later`]). The cells of the noise are laid out in
/// *material coordinates* — the position a pixel had at keyframe A, carried frame by frame
/// along the target's own motion (its flow guide) — so that the blobs travel with the shape,
/// and every bit of paint passes from A's to B's once. They are known before either pass paints
/// anything, so each pass paints only what it gives: the forward pass where `k < 1`, the
/// backward pass where `k > 0`, each with a margin of [`MARGIN`] pixels.
struct Split {
    ka: usize,
    kb: usize,
    seed: u64,
    /// Material coordinates of the frame last seen by the forward pass.
    coords: Option<Plane<Vec2>>,
    /// The flow guide of that frame (its motion to the next).
    flow: Option<Plane<Vec2>>,
    /// The share of B per frame between A and B.
    shares: Vec<Option<Plane<f32>>>,
}

impl Split {
    fn new(ka: usize, kb: usize, seed: u64) -> Split {
        Split { ka, kb, seed, coords: None, flow: None, shares: vec![None; kb - ka] }
    }

    /// The forward pass's guides of frame `A + k`: the coordinates carried to it, its shares,
    /// and its mask narrowed to where A's paint is still seen.
    fn forward(&mut self, k: usize, g: &mut FrameGuides) {
        let (w, h) = g.mask.size();
        let mut coords = match (self.coords.take(), self.flow.take()) {
            (Some(c), Some(f)) => advect(&c, &f, &g.mask),
            _ => Plane::par_from_fn(w, h, |x, y| Vec2::new(x as f32, y as f32)),
        };
        let mut flow = g.flow.clone();
        extend(&mut coords, &mut flow, &g.mask);
        self.flow = Some(flow);
        if k > 0 {
            let t = k as f32 / (self.kb - self.ka) as f32;
            // Only inside the mask (NaN outside: neither pass is asked to paint there).
            let share = Plane::par_from_fn(w, h, |x, y| {
                let p = coords.get(x, y);
                if g.mask.get(x, y) { from_later(cell_noise(p.x / CELL, p.y / CELL, self.seed), t) } else { f32::NAN }
            });
            g.mask = narrow(&g.mask, &share, |s| s < 1.0);
            self.shares[k] = Some(share);
        }
        self.coords = Some(coords);
    }

    /// The backward pass's guides of frame `j`: the mask narrowed to where B's paint is seen.
    fn backward(&self, j: usize, g: &mut FrameGuides) {
        if let Some(Some(share)) = self.shares.get(j.wrapping_sub(self.ka)) {
            g.mask = narrow(&g.mask, share, |s| s > 0.0);
        }
    }

    /// Frame j from the forward pass's `fwd` (painting A) and the backward pass's `back`
    /// (painting B), pixel by pixel by the share of B; the mask is the frame's whole coverage,
    /// the union of the two passes' narrowed masks (every pixel of it has `k < 1` or `k > 0`).
    fn merge(&self, j: usize, fwd: KeyedFrame, back: SynthFrame) -> Result<KeyedFrame> {
        let Some(Some(share)) = self.shares.get(j.wrapping_sub(self.ka)) else {
            return Err(Error::param("keyframe pass", format!("frame {}", j + 1), "a frame between two keyframes"));
        };
        let (w, h) = share.size();
        let rgb = Plane::par_from_fn(w, h, |x, y| {
            let (a, b, s) = (fwd.rgb.get(x, y), back.rgb.get(x, y), share.get(x, y));
            if s.is_nan() { a } else { [0, 1, 2].map(|i| a[i] + s * (b[i] - a[i])) }
        });
        let mask = Plane::par_from_fn(w, h, |x, y| fwd.mask.get(x, y) || back.mask.get(x, y));
        Ok(KeyedFrame { rgb, mask })
    }
}

/// `mask` where `keep(share)` holds within [`MARGIN`] pixels.
fn narrow(mask: &Mask, share: &Plane<f32>, keep: impl Fn(f32) -> bool) -> Mask {
    let (w, h) = mask.size();
    let mut out = Plane::new(w, h);
    // Within the mask's bounding box (shapes often fill a small part of a wide frame).
    let Some(r) = mask.bounding_box() else { return out };
    let r = r.expand(MARGIN, w, h);
    let near = super::source::dilate(
        &Plane::from_fn(r.width(), r.height(), |x, y| keep(share.get(r.x0 + x, r.y0 + y))),
        MARGIN,
    );
    for y in r.y0..r.y1 {
        for x in r.x0..r.x1 {
            out.set(x, y, mask.get(x, y) && near.get(x - r.x0, y - r.y0));
        }
    }
    out
}

/// How far outside its mask a frame's material coordinates and flow are continued
/// ([`extend`]), pixels: more than shapes move in a frame, so that newly covered pixels find
/// them.
const BAND: usize = 16;

/// Continues a frame's material coordinates `coords` and its `flow` from the pixels of `mask`
/// outward, [`BAND`] rings of pixels, each pixel taking the mean over its neighbours already set
/// (of their flow, and of their coordinates moved by its offset from them). With the flow
/// continued, a pixel that a shape newly covers finds where it came from inside the shape
/// ([`advect`]) instead of staying put, and with the coordinates continued, it continues the
/// pattern of the paint; otherwise every frame's new rim would take coordinates from the paper
/// or from a jump, and cut the blobs into thin strips along an advancing edge.
fn extend(coords: &mut Plane<Vec2>, flow: &mut Plane<Vec2>, mask: &Mask) {
    const AROUND: [(isize, isize); 8] = [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)];
    let (w, h) = mask.size();
    let neighbours = |x: usize, y: usize| {
        AROUND.iter().filter_map(move |&(dx, dy)| {
            let (nx, ny) = (x as isize + dx, y as isize + dy);
            mask.contains(nx, ny).then_some((nx as usize, ny as usize, dx, dy))
        })
    };
    let mut set = mask.clone();
    // The first ring: the pixels outside the mask next to it.
    let mut queued = mask.clone();
    let mut ring = Vec::new();
    if let Some(r) = mask.bounding_box() {
        let r = r.expand(1, w, h);
        for y in r.y0..r.y1 {
            for x in r.x0..r.x1 {
                if !mask.get(x, y) && neighbours(x, y).any(|(nx, ny, _, _)| mask.get(nx, ny)) {
                    queued.set(x, y, true);
                    ring.push((x, y));
                }
            }
        }
    }
    let mut values = Vec::new();
    for _ in 0..BAND {
        values.clear();
        for &(x, y) in &ring {
            let (mut c, mut f, mut n) = (Vec2::ZERO, Vec2::ZERO, 0.0);
            for (nx, ny, dx, dy) in neighbours(x, y).filter(|&(nx, ny, _, _)| set.get(nx, ny)) {
                c += coords.get(nx, ny) - Vec2::new(dx as f32, dy as f32);
                f += flow.get(nx, ny);
                n += 1.0;
            }
            values.push((c / n, f / n));
        }
        for (&(x, y), &(c, f)) in ring.iter().zip(&values) {
            coords.set(x, y, c);
            flow.set(x, y, f);
            set.set(x, y, true);
        }
        let mut next = Vec::new();
        for &(x, y) in &ring {
            for (nx, ny, _, _) in neighbours(x, y) {
                if !queued.get(nx, ny) {
                    queued.set(nx, ny, true);
                    next.push((nx, ny));
                }
            }
        }
        ring = next;
    }
}

/// Material coordinates `coords` of a frame carried one frame on along its motion `flow`
/// (pixels per frame, from it to the next), at the pixels of the next frame's `mask` (elsewhere
/// they stay; [`extend`] continues them): each pixel takes the coordinates of where it came
/// from, `x − flow(x − flow(x))` (two fixed-point steps of the inverse motion).
fn advect(coords: &Plane<Vec2>, flow: &Plane<Vec2>, mask: &Mask) -> Plane<Vec2> {
    Plane::par_from_fn(coords.width(), coords.height(), |x, y| {
        if !mask.get(x, y) {
            return coords.get(x, y);
        }
        let p = Vec2::new(x as f32, y as f32);
        let back = p - crate::img::sample_bilinear(flow, p.x, p.y);
        let back = p - crate::img::sample_bilinear(flow, back.x, back.y);
        crate::img::sample_bilinear(coords, back.x, back.y)
    })
}

/// Half the width of the seam between two blobs over which their paintings are cross-faded,
/// pixels: enough to soften the blobs' straight edges, too little to show a blend.
const SEAM: f32 = 1.0;

/// How much of a pixel comes from the later painting at time `t`: 1 inside a blob whose value
/// is below t, 0 inside one whose value is not, and across the seam between two such blobs a
/// ramp [`SEAM`] pixels to each side.
fn from_later(n: CellNoise, t: f32) -> f32 {
    let own = if n.value < t { 1.0 } else { 0.0 };
    let other = if n.next < t { 1.0 } else { 0.0 };
    if own == other {
        return own;
    }
    let w = 0.5 + 0.5 * (n.edge * CELL / SEAM).min(1.0);
    own * w + other * (1.0 - w)
}

/// Cellular (Worley) noise at a point: the value, uniform in [0, 1), of the cell whose jittered
/// point is nearest, that of the next nearest, and the distance to the edge between them.
#[derive(Clone, Copy, Debug)]
struct CellNoise {
    value: f32,
    next: f32,
    /// Distance to the bisector of the two nearest points, in cells.
    edge: f32,
}

/// [`CellNoise`] at (x, y), coordinates in cells.
fn cell_noise(x: f32, y: f32, seed: u64) -> CellNoise {
    let (cx, cy) = (x.floor() as i64, y.floor() as i64);
    // (squared distance, point, value) of the nearest and the next nearest.
    let mut near = [(f32::INFINITY, (0.0, 0.0), 0.0f32); 2];
    for dy in -1..=1 {
        for dx in -1..=1 {
            let (gx, gy) = (cx + dx, cy + dy);
            let h = |k: u64| crate::rng::lattice(crate::rng::mix(seed ^ k), gx, gy);
            let (px, py) = (gx as f32 + h(0), gy as f32 + h(1));
            let d = (px - x).powi(2) + (py - y).powi(2);
            if d < near[0].0 {
                near[1] = near[0];
                near[0] = (d, (px, py), h(2));
            } else if d < near[1].0 {
                near[1] = (d, (px, py), h(2));
            }
        }
    }
    let ((d1, p1, v1), (d2, p2, v2)) = (near[0], near[1]);
    let gap = ((p2.0 - p1.0).powi(2) + (p2.1 - p1.1).powi(2)).sqrt().max(1e-6);
    CellNoise { value: v1, next: v2, edge: (d2 - d1) / (2.0 * gap) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pass_frames_counts_both_passes_between_keys() {
        assert_eq!(pass_frames(48, [0, 47]), 2 * 46);
        assert_eq!(pass_frames(48, [47, 0]), 2 * 46);
        assert_eq!(pass_frames(48, [10]), 10 + 37);
        // 2 before, none between 2 and 3, 2 × 2 between 3 and 6, 3 after.
        assert_eq!(pass_frames(10, [2, 3, 6]), 2 + 2 * 2 + 3);
        assert_eq!(pass_frames(5, std::iter::empty()), 0);
    }

    /// A true motion kept for a pass: its known pixels as they are, each unknown pixel within
    /// [`HOLE_REACH`] of a known one given the nearest (Chebyshev distance, the first in row
    /// order among the nearest), zero beyond; kept over the known pixels' box widened by the
    /// reach.
    #[test]
    fn boxed_flows_fill_holes_within_reach() {
        // Known on a block but its right column (x = 11).
        let known = |x: usize, y: usize| (5..11).contains(&x) && (4..9).contains(&y);
        let m = Plane::from_fn(20, 16, |x, y| known(x, y).then(|| Vec2::new(x as f32, y as f32)));
        let f = BoxedFlow::new(&m);
        assert_eq!((f.origin, f.part.size()), ((1, 0), (14, 13)));
        let p = f.plane();
        for y in 0..16usize {
            for x in 0..20usize {
                // The nearest known pixel, found by scanning them all in row order.
                let mut best: Option<(usize, Vec2)> = None;
                for qy in 0..16 {
                    for qx in 0..20 {
                        let d = x.abs_diff(qx).max(y.abs_diff(qy));
                        if known(qx, qy) && d <= HOLE_REACH && best.is_none_or(|(bd, _)| d < bd) {
                            best = Some((d, Vec2::new(qx as f32, qy as f32)));
                        }
                    }
                }
                assert_eq!(p.get(x, y), best.map_or(Vec2::ZERO, |b| b.1), "({x}, {y})");
            }
        }
    }

    #[test]
    fn a_cancelled_paint_stops_with_cancelled() {
        let disc = |k: usize| {
            Plane::from_fn(48, 40, move |x, y| {
                let (dx, dy) = (x as f32 - 18.0 - k as f32, y as f32 - 20.0);
                if dx * dx + dy * dy < 100.0 { 1.0 } else { 0.0 }
            })
        };
        let key = Keyframe { frame: 0, painting: Plane::filled(48, 40, [0.3, 0.5, 0.7]), mask: None };
        let params = Params::builder().seed(1).build().unwrap();
        let mut emitted = 0;
        let stop = |_: &str, done: usize, _: usize| done < 2;
        let r = paint(
            &params,
            6,
            &|k| Ok(disc(k)),
            None,
            &[key],
            &mut |_, _| {
                emitted += 1;
                Ok(())
            },
            "keys",
            &stop,
        );
        assert!(matches!(r, Err(Error::Cancelled)), "{r:?}");
        assert!(emitted <= 2, "stopped at once: {emitted} frames emitted");
    }

    #[test]
    fn cell_noise_is_uniform_and_made_of_blobs() {
        let n = 200;
        let vals: Vec<f32> =
            (0..n * n).map(|i| cell_noise((i % n) as f32 * 0.1, (i / n) as f32 * 0.1, 7).value).collect();
        // Uniform: each quarter of [0, 1) holds about a quarter of the area.
        for q in 0..4 {
            let share = vals.iter().filter(|v| (**v * 4.0) as usize == q).count() as f32 / vals.len() as f32;
            assert!((0.15..0.35).contains(&share), "quarter {q}: {share}");
        }
        // Blobs: neighbours 0.1 cell apart share their value far more often than not.
        let same = (0..n * n - 1).filter(|&i| i % n != n - 1 && vals[i] == vals[i + 1]).count();
        assert!(same as f32 > 0.8 * (n * (n - 1)) as f32, "{same}");
        // Deterministic, and another seed gives another pattern.
        assert_eq!(cell_noise(3.3, 4.4, 7).value, cell_noise(3.3, 4.4, 7).value);
        assert!((0..50).any(|i| cell_noise(i as f32 * 0.7, 1.0, 7).value != cell_noise(i as f32 * 0.7, 1.0, 8).value));
    }

    /// A disc of radius 60 moving (3, 1) px a frame, with the flow guide it would have.
    fn moving_disc(k: usize) -> FrameGuides {
        let (w, h) = (320, 200);
        let c = Vec2::new(100.0 + 3.0 * k as f32, 100.0 + k as f32);
        let mask = Plane::from_fn(w, h, |x, y| Vec2::new(x as f32, y as f32).distance(c) < 60.0);
        let flow = mask.map(|m| if m { Vec2::new(3.0, 1.0) } else { Vec2::ZERO });
        FrameGuides { dist: Plane::new(w, h), ext_pos: Plane::new(w, h), ext_neg: Plane::new(w, h), mask, flow }
    }

    #[test]
    fn material_coordinates_move_with_the_shape() {
        // Carried 20 frames along a translation, every pixel of the disc has the coordinates it
        // had at the first frame, `x − 20·(3, 1)` — also those on the leading edge that the disc
        // covered on the way, which take them from the continued flow and coordinates, not from
        // the paper they were on before.
        let mut split = Split::new(0, 40, 5);
        for k in 0..=20 {
            split.forward(k, &mut moving_disc(k));
        }
        let coords = split.coords.as_ref().unwrap();
        let g = moving_disc(20);
        let mut worst: f32 = 0.0;
        for y in 0..g.mask.height() {
            for x in 0..g.mask.width() {
                if g.mask.get(x, y) {
                    let want = Vec2::new(x as f32 - 60.0, y as f32 - 20.0);
                    worst = worst.max(coords.get(x, y).distance(want));
                }
            }
        }
        // Measured 0.0 (whole-pixel moves and a uniform flow); 63 px with the flow not continued
        // past the edge. The floor allows the rounding of sub-pixel motion.
        assert!(worst < 0.5, "coordinates off by up to {worst} px");
    }

    #[test]
    fn each_pass_paints_only_what_it_gives() {
        // Halfway between the keyframes each pass paints about half the shape (with its margin),
        // both together far less than two whole frames, and together every pixel of the shape.
        // Measured: forward 0.79, backward 0.64 of the shape (1.43 together).
        let mut split = Split::new(0, 20, 5);
        let mut painted = (0, 0, 0);
        for k in 0..20 {
            let mut g = moving_disc(k);
            let whole = g.mask.clone();
            split.forward(k, &mut g);
            if k == 10 {
                let fwd = g.mask.clone();
                let mut gb = moving_disc(k);
                split.backward(k, &mut gb);
                for ((w, f), b) in whole.data().iter().zip(fwd.data()).zip(gb.mask.data()) {
                    assert!(!*w || *f || *b, "a pixel of the shape that neither pass paints");
                    painted.0 += *w as usize;
                    painted.1 += *f as usize;
                    painted.2 += *b as usize;
                }
            }
        }
        let (whole, fwd, back) = painted;
        let share = |n: usize| n as f32 / whole as f32;
        println!("forward {:.2}, backward {:.2} of the shape", share(fwd), share(back));
        assert!((0.3..0.85).contains(&share(fwd)) && (0.3..0.85).contains(&share(back)));
        assert!(share(fwd + back) < 1.5, "{}", share(fwd + back));
    }

    #[test]
    fn seams_are_narrow_ramps() {
        // Along a line, the share of the later painting is 0 or 1 but within SEAM px of a
        // change between two blobs, and steps of a pixel change it by at most ½ there.
        let t = 0.5;
        let k: Vec<f32> = (0..4000).map(|i| from_later(cell_noise(i as f32 * 0.25 / CELL, 3.7, 11), t)).collect();
        let partial = k.iter().filter(|&&v| v > 0.0 && v < 1.0).count();
        let changes = k.windows(2).filter(|w| (w[0] < 0.5) != (w[1] < 0.5)).count();
        assert!(changes > 10, "{changes} seams");
        // The ramps are a small part of the line: seams 2·SEAM px wide (more where the line
        // crosses one obliquely) between blobs of about CELL px, half of them between A and B.
        assert!(partial < k.len() * 12 / 100, "{partial} partial samples of {}", k.len());
        // Continuous across a seam; a jump only where the second nearest cell changes (near
        // a corner where three blobs meet), rarely.
        let jumps = k.windows(2).filter(|w| (w[1] - w[0]).abs() > 0.5 * 0.25 / SEAM + 0.05).count();
        assert!(jumps * 4 <= changes, "{jumps} jumps at {changes} seams");
    }
}
