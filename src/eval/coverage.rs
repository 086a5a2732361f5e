//! Coverage: how well the painted area of the output matches the target masks.

use super::{Measure, Shape};
use crate::img::{Mask, Plane, Rgb, Rgba};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// An alpha below this value anywhere in a sequence makes it a sequence "with alpha".
pub const OPAQUE_ALPHA: f32 = 0.999;

/// How painted pixels are told from unpainted ones.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Painted {
    /// The output has a real alpha channel: painted where `alpha >= 0.5` (the threshold of
    /// the target masks, [`super::MASK_THRESHOLD`]).
    Alpha,
    /// The output is opaque (composited): painted where the RGB color is farther than
    /// `threshold` (Euclidean distance of sRGB values in `0..=1`) from `background`.
    Color {
        /// The background (paper) color.
        background: Rgb,
        /// Distance above which a pixel counts as painted.
        threshold: f32,
    },
}

/// True when some pixel of some frame is not opaque (`alpha < 0.999`).
pub fn has_alpha(frames: &[Plane<Rgba>]) -> bool {
    frames.par_iter().any(|f| f.data().iter().any(|c| c[3] < OPAQUE_ALPHA))
}

/// Estimates the background color of a sequence as its dominant border color: the pixels of
/// the 1-pixel frame border of every frame are put into 16×16×16 color bins, and the mean
/// color of the fullest bin (the first one on ties) is returned. `None` without pixels.
pub fn estimate_background(frames: &[Plane<Rgba>]) -> Option<Rgb> {
    const LEVELS: usize = 16;
    let mut count = vec![0u64; LEVELS * LEVELS * LEVELS];
    let mut sum = vec![[0f64; 3]; LEVELS * LEVELS * LEVELS];
    let q = |v: f32| ((v.clamp(0.0, 1.0) * LEVELS as f32) as usize).min(LEVELS - 1);
    let mut visit = |c: Rgba| {
        let k = (q(c[0]) * LEVELS + q(c[1])) * LEVELS + q(c[2]);
        count[k] += 1;
        for ch in 0..3 {
            sum[k][ch] += c[ch] as f64;
        }
    };
    for f in frames {
        let (w, h) = f.size();
        if w == 0 || h == 0 {
            continue;
        }
        for x in 0..w {
            visit(f.get(x, 0));
            if h > 1 {
                visit(f.get(x, h - 1));
            }
        }
        for y in 1..h.saturating_sub(1) {
            visit(f.get(0, y));
            if w > 1 {
                visit(f.get(w - 1, y));
            }
        }
    }
    let (best, &n) = count.iter().enumerate().max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(&a.0)))?;
    (n > 0).then(|| sum[best].map(|s| (s / n as f64) as f32))
}

/// Decides how to detect paint in `frames`: [`Painted::Alpha`] when the sequence has a
/// non-opaque alpha channel, otherwise [`Painted::Color`] against `background` or, when that
/// is `None`, the [`estimate_background`] (white if there is nothing to estimate from).
pub fn detect_painted(frames: &[Plane<Rgba>], background: Option<Rgb>, threshold: f32) -> Painted {
    if has_alpha(frames) {
        Painted::Alpha
    } else {
        let background = background.or_else(|| estimate_background(frames)).unwrap_or([1.0; 3]);
        Painted::Color { background, threshold }
    }
}

/// The painted area of one frame.
pub fn painted_mask(frame: &Plane<Rgba>, painted: &Painted) -> Mask {
    match *painted {
        Painted::Alpha => frame.map(|c| c[3] >= super::MASK_THRESHOLD),
        Painted::Color { background: b, threshold } => frame.map(|c| {
            let d2 = (c[0] - b[0]).powi(2) + (c[1] - b[1]).powi(2) + (c[2] - b[2]).powi(2);
            d2 > threshold * threshold
        }),
    }
}

/// Intersection and union pixel counts of two masks of the same size.
pub fn intersection_union(a: &Mask, b: &Mask) -> (u64, u64) {
    let (mut i, mut u) = (0u64, 0u64);
    for (&p, &q) in a.data().iter().zip(b.data()) {
        i += (p && q) as u64;
        u += (p || q) as u64;
    }
    (i, u)
}

/// Intersection over union `|A ∩ B| / |A ∪ B|` of two masks; 1 when both are empty.
pub fn iou(a: &Mask, b: &Mask) -> f32 {
    let (i, u) = intersection_union(a, b);
    if u == 0 { 1.0 } else { (i as f64 / u as f64) as f32 }
}

/// Coverage of a sequence: per frame the [`iou`] of the [`painted_mask`] with the target mask,
/// and over the whole sequence the pooled `Σ|A ∩ B| / Σ|A ∪ B|`.
pub fn coverage_iou(output: &[Plane<Rgba>], targets: &[Shape], painted: &Painted) -> Measure {
    let counts: Vec<(u64, u64)> =
        output.par_iter().zip(targets).map(|(f, t)| intersection_union(&painted_mask(f, painted), &t.mask)).collect();
    coverage_from_counts(&counts)
}

/// The coverage measure from each frame's intersection and union counts: per frame their
/// ratio (1 when both masks are empty), pooled `Σ|A ∩ B| / Σ|A ∪ B|`; `samples` = `Σ|A ∪ B|`.
pub(crate) fn coverage_from_counts(counts: &[(u64, u64)]) -> Measure {
    let ratio = |i: u64, u: u64| if u == 0 { 1.0 } else { (i as f64 / u as f64) as f32 };
    let per_frame = counts.iter().map(|&(i, u)| Some(ratio(i, u))).collect();
    let (si, su) = counts.iter().fold((0u64, 0u64), |(a, b), &(i, u)| (a + i, b + u));
    Measure { value: (!counts.is_empty()).then(|| ratio(si, su)), per_frame, samples: su }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn background_is_the_dominant_border_color() {
        let f = Plane::from_fn(10, 8, |x, _| if x == 9 { [0.1, 0.2, 0.9, 1.0] } else { [0.95, 0.93, 0.9, 1.0] });
        let bg = estimate_background(&[f]).unwrap();
        assert!((bg[0] - 0.95).abs() < 1e-6 && (bg[2] - 0.9).abs() < 1e-6);
    }
}
