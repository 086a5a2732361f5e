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
//! cellular noise, uniform in [0, 1), of the position `p` that the forward pass's field gives
//! the pixel in painting A — a position that moves with the paint, so each bit of paint changes
//! from A's to B's once, in blobs of about [`CELL`] pixels that grow as t rises, and the blobs
//! travel with the shape instead of swimming over it. Only across the seam between a blob of A
//! and one of B are the two cross-faded, over `SEAM` (1) pixel to each side, which softens the
//! blobs' straight edges without a visible blend.
//!
//! Simplifications (see the README): Bénard et al. select per pixel at random with the same
//! time weights and then optimize the frame once more, so that propagation can heal the
//! seams between the two passes; here the selection is final (a seam between two blobs is
//! where A's and B's paint meet). Their orientation field and ribbons are not used (the carried
//! field is the position in the painting; a patch is never turned). The backward pass of one
//! gap between keyframes is held in memory until the forward pass meets it (12 bytes a pixel a
//! frame).

use super::{Params, Source, SynthFrame, Synthesizer};
use crate::error::{Error, Result};
use crate::exemplar::{Exemplar, ExemplarMeta};
use crate::guide::GuideStream;
use crate::img::{Mask, Plane, Rgb};

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

/// Paints every frame of a `frames`-frame target from its painted keyframes `keys` (any order;
/// at least one, at most one per frame) and hands them to `emit` in order, frame index first.
/// `tick` is called after every frame synthesized, in either pass (for progress).
pub fn paint(
    params: &Params,
    frames: usize,
    coverage: Coverage<'_>,
    keys: &[Keyframe],
    emit: &mut dyn FnMut(usize, KeyedFrame) -> Result<()>,
    tick: &mut dyn FnMut(),
) -> Result<()> {
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
    let sources: Vec<Source> =
        keys.iter().map(|k| key_source(k, &coverage(k.frame)?, params)).collect::<Result<_>>()?;
    let seed = params.seed;
    // Before the first keyframe: backward from it.
    let first = keys[0].frame;
    if first > 0 {
        let seq: Vec<usize> = (0..=first).rev().collect();
        let mut held = Held::new(first);
        pass(&sources[0], params, &seq, coverage, false, &mut |j, out, _| {
            tick();
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
            return pass(&sources[a], params, &seq, coverage, false, &mut |j, out, _| {
                tick();
                emit(j, KeyedFrame { rgb: out.rgb, mask: out.mask })
            });
        };
        let (ka, kb) = (key.frame, next.frame);
        if kb == ka + 1 {
            continue;
        }
        // Backward from B, held; then forward from A, each frame merged with the held one.
        let seq_b: Vec<usize> = (ka + 1..=kb).rev().collect();
        let mut held = Held::new(kb);
        pass(&sources[a + 1], params, &seq_b, coverage, false, &mut |j, out, _| {
            tick();
            held.put(j, out);
            Ok(())
        })?;
        let seq_a: Vec<usize> = (ka..kb).collect();
        pass(&sources[a], params, &seq_a, coverage, true, &mut |j, out, field| {
            tick();
            let t = (j - ka) as f32 / (kb - ka) as f32;
            let back = held.take(j)?;
            emit(j, merge(out, field.as_ref(), back, t, seed ^ ((ka as u64) << 32) ^ kb as u64))
        })?;
    }
    Ok(())
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
        if let Some(slot) = self.0.get_mut(j) {
            *slot = Some(KeyedFrame { rgb: out.rgb, mask: out.mask });
        }
    }

    fn take(&mut self, j: usize) -> Result<KeyedFrame> {
        self.0
            .get_mut(j)
            .and_then(Option::take)
            .ok_or_else(|| Error::param("keyframe pass", format!("frame {}", j + 1), "a frame of the backward pass"))
    }
}

/// One pass from a keyframe along `seq` (target frame indices; `seq[0]` is the keyframe's),
/// handing every later frame to `emit` — with its field ([`Synthesizer::field`]) when
/// `with_field` (for [`merge`]).
fn pass(
    source: &Source,
    params: &Params,
    seq: &[usize],
    coverage: Coverage<'_>,
    with_field: bool,
    emit: &mut dyn FnMut(usize, SynthFrame, Option<Plane<[f32; 4]>>) -> Result<()>,
) -> Result<()> {
    let stream = GuideStream::new(seq.len(), |k| coverage(seq[k]), params.guide())?;
    let mut synth = Synthesizer::new(source.clone(), params.clone())?;
    synth.set_target_extent(stream.extent_scale());
    for (k, g) in stream.enumerate() {
        let g = g?;
        if k == 0 {
            synth.begin_at_source(&g)?;
        } else {
            let out = synth.step(&g)?;
            let field = if with_field { synth.field() } else { None };
            emit(seq[k], out, field)?;
        }
    }
    Ok(())
}

/// Frame j between keyframes A and B: each pixel from the forward pass `fwd` (painting A) or
/// the backward pass `back` (painting B), by the cellular noise of its position in painting A
/// (`field`, the forward pass's) against `t = (j − A)/(B − A)` (module docs).
fn merge(fwd: SynthFrame, field: Option<&Plane<[f32; 4]>>, back: KeyedFrame, t: f32, seed: u64) -> KeyedFrame {
    let (w, h) = fwd.rgb.size();
    let rgb = Plane::from_fn(w, h, |x, y| {
        let p = field.map(|f| f.get(x, y)).filter(|m| m[1].is_finite()).map_or((x as f32, y as f32), |m| (m[1], m[2]));
        let (a, b) = (fwd.rgb.get(x, y), back.rgb.get(x, y));
        let k = from_later(cell_noise(p.0 / CELL, p.1 / CELL, seed), t);
        [0, 1, 2].map(|i| a[i] + k * (b[i] - a[i]))
    });
    KeyedFrame { rgb, mask: fwd.mask }
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
