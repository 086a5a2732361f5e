//! Depth matching: the exemplar's texture and colors taken at the distances from the edge at
//! which the output has its pixels.
//!
//! Paint is not the same all the way in: a watercolor's band just inside the rim is darker
//! and far more varied than its calm middle (the bundled exemplars' 7×7 contrast is 1.1–3.0×
//! higher 4–12 px inside the edge than beyond 25 px). A target larger than the exemplar's
//! blobs has most of its interior deeper than any of the exemplar's, so comparing it with the
//! exemplar's interior as a whole asks its calm middle for the rim band's variation: an output
//! that copied the exemplar exactly at every depth would score well below 1. The reference
//! values of contrast and palette are therefore the exemplar's at the output's own depths:
//! per 2-px bin of distance from the edge, weighted by how many output pixels fall in it;
//! depths the exemplar never reaches take its deepest bin with at least [`MIN_BIN_PIXELS`].
//! For the palette, a part deeper than the exemplar's paint counts its pixels at the
//! exemplar's depths stretched to it ([`super::EvalOptions::depth_stretch`], [`paint_depth`]).

use super::{ColorHistogram, Mean, Shape};
use crate::img::{Mask, Plane, Rgb};

/// Width of a depth bin, pixels.
pub(crate) const DEPTH_BIN: f32 = 2.0;
/// Number of depth bins; the last holds every depth beyond.
pub(crate) const DEPTH_BINS: usize = 48;
/// Exemplar pixels a bin needs to stand for the depths beyond the exemplar's deepest.
pub(crate) const MIN_BIN_PIXELS: u64 = 200;

/// The depth bin of a signed distance (positive inside).
#[inline]
pub(crate) fn depth_bin(d: f32) -> usize {
    ((d.max(0.0) / DEPTH_BIN) as usize).min(DEPTH_BINS - 1)
}

/// Pixels of `region` per depth bin of `depth` (a shape's matched depths).
pub(crate) fn region_bins(depth: &Plane<f32>, region: &Mask) -> Vec<u64> {
    let mut n = vec![0u64; DEPTH_BINS];
    for (&d, &inside) in depth.data().iter().zip(region.data()) {
        if inside {
            n[depth_bin(d)] += 1;
        }
    }
    n
}

/// The depth of a paint: the deepest pixel of any of its frames (0 for no paint). A frame of
/// the exemplar is never deeper, so the exemplar measured against itself is measured at its
/// own depths.
pub(crate) fn paint_depth(shapes: &[Shape]) -> f32 {
    shapes.iter().map(|s| crate::guide::deepest_inside(&s.sdf, &s.mask)).fold(0.0, f32::max)
}

/// The exemplar's contrast and colors per depth bin.
#[derive(Clone, Debug)]
pub(crate) struct DepthProfile {
    contrast: Vec<Mean>,
    hist: Vec<ColorHistogram>,
    /// The bin that stands for each bin (itself when it has enough pixels).
    stand_in: Vec<Option<usize>>,
    /// The exemplar's flow residual ([`super::incoherent_change`]) pooled per depth bin, and
    /// the bin that stands for each bin.
    coherence: Vec<Mean>,
    coherence_stand_in: Vec<Option<usize>>,
}

/// The bin that stands for each bin: itself where it has samples (`has`); beyond the deepest
/// bin with samples, the deepest with at least [`MIN_BIN_PIXELS`] (`enough`, or else the
/// deepest); a gap within, the nearest shallower bin with samples (or deeper).
fn stand_ins(has: impl Fn(usize) -> bool, enough: impl Fn(usize) -> bool) -> Vec<Option<usize>> {
    let deepest = (0..DEPTH_BINS).rev().find(|&j| has(j));
    let tail = (0..DEPTH_BINS).rev().find(|&j| enough(j)).or(deepest);
    (0..DEPTH_BINS)
        .map(|k| match deepest {
            Some(d) if k > d => tail,
            _ if has(k) => Some(k),
            _ => (0..k).rev().find(|&j| has(j)).or_else(|| (k..DEPTH_BINS).find(|&j| has(j))),
        })
        .collect()
}

impl DepthProfile {
    /// Profiles the exemplar's `frames` over `regions` (interiors of `shapes`); `coherence`
    /// is its flow residual per depth bin ([`super::coherence::incoherent_change_binned`]).
    pub(crate) fn new(frames: &[Plane<Rgb>], shapes: &[Shape], regions: &[Mask], coherence: &[Mean]) -> DepthProfile {
        let mut contrast = vec![Mean::default(); DEPTH_BINS];
        let mut hist = vec![ColorHistogram::new(); DEPTH_BINS];
        for ((f, s), r) in frames.iter().zip(shapes).zip(regions) {
            let bins = super::contrast::local_contrast_binned(f, r, DEPTH_BINS, |x, y| depth_bin(s.sdf.get(x, y)));
            for (a, b) in contrast.iter_mut().zip(bins) {
                *a = a.merged(b);
            }
            for ((&c, &d), &inside) in f.data().iter().zip(s.sdf.data()).zip(r.data()) {
                if inside {
                    hist[depth_bin(d)].add(c);
                }
            }
        }
        let has = |k: usize| contrast[k].count() > 0 && !hist[k].is_empty();
        let enough = |k: usize| contrast[k].count() >= MIN_BIN_PIXELS && hist[k].len() >= MIN_BIN_PIXELS;
        // Beyond the exemplar's deepest pixels: its deepest well-sampled bin (or, if none
        // is, its deepest bin); within its depths each bin stands for itself (an output of the
        // exemplar's own shapes is then measured against exactly the exemplar).
        let stand_in = stand_ins(has, enough);
        let coherence = coherence.to_vec();
        let coherence_stand_in = stand_ins(|k| coherence[k].count() > 0, |k| coherence[k].count() >= MIN_BIN_PIXELS);
        DepthProfile { contrast, hist, stand_in, coherence, coherence_stand_in }
    }

    /// The exemplar's contrast and colors over its whole interior, whatever the depths (the
    /// bins merged).
    pub(crate) fn whole(&self) -> (Mean, ColorHistogram) {
        let mut hist = ColorHistogram::new();
        for h in &self.hist {
            hist.merge(h);
        }
        (self.contrast.iter().fold(Mean::default(), |a, &b| a.merged(b)), hist)
    }

    /// The exemplar's contrast at the depths of `bins` (the output's contrast samples per bin).
    pub(crate) fn contrast(&self, bins: &[Mean]) -> Option<f32> {
        let (mut sum, mut n) = (0f64, 0f64);
        for (k, b) in bins.iter().enumerate() {
            let Some(j) = self.stand_in[k] else { continue };
            if let Some(c) = self.contrast[j].value() {
                sum += b.count() as f64 * c as f64;
                n += b.count() as f64;
            }
        }
        (n > 0.0).then(|| (sum / n) as f32)
    }

    /// How much more the exemplar's paint changes at the depths of `counts` (the output's
    /// flow-residual pixels per bin) than over its own: the exemplar's pooled residual at
    /// those depths ÷ over all of its own pixels. The exemplar's incoherent change times this
    /// is what an output that changed like the exemplar at each of its depths would score;
    /// exactly 1 for the exemplar's own depths.
    pub(crate) fn coherence_factor(&self, counts: &[u64]) -> Option<f32> {
        let own = self.coherence.iter().fold(Mean::default(), |a, &b| a.merged(b)).value()?;
        let (mut sum, mut n) = (0f64, 0f64);
        for (k, &c) in counts.iter().enumerate() {
            let Some(j) = self.coherence_stand_in[k] else { continue };
            if let (Some(v), true) = (self.coherence[j].value(), c > 0) {
                sum += c as f64 * v as f64;
                n += c as f64;
            }
        }
        (n > 0.0 && own > 0.0).then(|| (sum / n / own as f64) as f32)
    }

    /// Per-channel Wasserstein distance of `out` to the exemplar's colors mixed at the depths
    /// of `counts` (the output's pixels per bin).
    pub(crate) fn palette(&self, out: &ColorHistogram, counts: &[u64]) -> Option<[f32; 3]> {
        let mut parts: Vec<(&ColorHistogram, f64)> = Vec::new();
        for (k, &c) in counts.iter().enumerate() {
            if let (Some(j), true) = (self.stand_in[k], c > 0) {
                match parts.iter_mut().find(|(h, _)| std::ptr::eq(*h, &self.hist[j])) {
                    Some(p) => p.1 += c as f64,
                    None => parts.push((&self.hist[j], c as f64)),
                }
            }
        }
        out.wasserstein_mixture(&parts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mean(v: f64, n: u64) -> Mean {
        let mut m = Mean::default();
        for _ in 0..n {
            m.add(v);
        }
        m
    }

    /// The exemplar's residual at the output's depths over its own: a paint that changes
    /// three times as fast 4–6 px inside as 20–22 px inside.
    #[test]
    fn coherence_factor_weighs_the_exemplar_by_the_output_depths() {
        let mut coherence = vec![Mean::default(); DEPTH_BINS];
        coherence[2] = mean(0.03, 1000);
        coherence[10] = mean(0.01, 3000);
        let has = |k: usize| coherence[k].count() > 0;
        let p = DepthProfile {
            contrast: vec![Mean::default(); DEPTH_BINS],
            hist: vec![ColorHistogram::new(); DEPTH_BINS],
            stand_in: vec![None; DEPTH_BINS],
            coherence_stand_in: stand_ins(has, |k| coherence[k].count() >= MIN_BIN_PIXELS),
            coherence: coherence.clone(),
        };
        let own = (30.0 + 30.0) / 4000.0;
        let at = |pairs: &[(usize, u64)]| {
            let mut counts = vec![0u64; DEPTH_BINS];
            for &(k, n) in pairs {
                counts[k] = n;
            }
            p.coherence_factor(&counts).unwrap()
        };
        let close = |a: f32, b: f64| (a as f64 - b).abs() < 1e-5;
        // The exemplar's own depths: 1, whatever the scale of the counts.
        assert!(close(at(&[(2, 10), (10, 30)]), 1.0), "{}", at(&[(2, 10), (10, 30)]));
        // All near the edge (a thin part), and all deeper than the exemplar reaches (its
        // deepest bin stands in), and a gap between them (the nearest shallower bin).
        assert!(close(at(&[(2, 5)]), 0.03 / own));
        assert!(close(at(&[(30, 5)]), 0.01 / own));
        assert!(close(at(&[(6, 1), (10, 1)]), 0.03 / own / 2.0 + 0.01 / own / 2.0));
        // Nothing measured: no factor.
        assert_eq!(p.coherence_factor(&[0; DEPTH_BINS]), None);
    }
}
