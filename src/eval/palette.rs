//! Palette: per-channel 1D Wasserstein (earth mover's) distance between color distributions.

use crate::img::{Mask, Plane, Rgb};
use rayon::prelude::*;

/// Number of bins per channel of a [`ColorHistogram`]; a value `v` falls into bin
/// `round(v · (BINS − 1))`, so binning moves a value by at most `1 / (2 (BINS − 1))`.
pub const HISTOGRAM_BINS: usize = 4096;

/// Per-channel histograms of colors in `0..=1` (values outside are clamped), for streaming
/// Wasserstein distances over many frames without keeping every pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct ColorHistogram {
    bins: Vec<[u64; 3]>,
    count: u64,
}

impl Default for ColorHistogram {
    fn default() -> Self {
        ColorHistogram { bins: vec![[0; 3]; HISTOGRAM_BINS], count: 0 }
    }
}

#[inline]
fn bin(v: f32) -> usize {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    (v * (HISTOGRAM_BINS - 1) as f32 + 0.5) as usize
}

impl ColorHistogram {
    /// An empty histogram.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds one color.
    pub fn add(&mut self, c: Rgb) {
        for (ch, &v) in c.iter().enumerate() {
            self.bins[bin(v)][ch] += 1;
        }
        self.count += 1;
    }

    /// Adds the colors of `img` at the pixels of `region`.
    pub fn add_masked(&mut self, img: &Plane<Rgb>, region: &Mask) {
        for (&c, &inside) in img.data().iter().zip(region.data()) {
            if inside {
                self.add(c);
            }
        }
    }

    /// The histogram of `img` over `region`.
    pub fn of_region(img: &Plane<Rgb>, region: &Mask) -> Self {
        let mut h = Self::new();
        h.add_masked(img, region);
        h
    }

    /// Adds all counts of `other`.
    pub fn merge(&mut self, other: &ColorHistogram) {
        for (a, b) in self.bins.iter_mut().zip(&other.bins) {
            for ch in 0..3 {
                a[ch] += b[ch];
            }
        }
        self.count += other.count;
    }

    /// Number of colors added.
    pub fn len(&self) -> u64 {
        self.count
    }

    /// True when no color was added.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Per-channel Wasserstein-1 distance `∫ |F_a(x) − F_b(x)| dx` between the two binned
    /// distributions (in `0..=1` color units); `None` if either is empty.
    pub fn wasserstein(&self, other: &ColorHistogram) -> Option<[f32; 3]> {
        self.wasserstein_mixture(&[(other, 1.0)])
    }

    /// [`ColorHistogram::wasserstein`] to the mixture of `parts`, each histogram normalized
    /// and weighted by its weight; `None` if this one is empty or no part has both colors and
    /// weight.
    pub fn wasserstein_mixture(&self, parts: &[(&ColorHistogram, f64)]) -> Option<[f32; 3]> {
        let parts: Vec<(&ColorHistogram, f64)> =
            parts.iter().copied().filter(|(h, w)| !h.is_empty() && *w > 0.0).collect();
        let total: f64 = parts.iter().map(|p| p.1).sum();
        if self.is_empty() || parts.is_empty() {
            return None;
        }
        let na = self.count as f64;
        let mut out = [0f32; 3];
        for (ch, o) in out.iter_mut().enumerate() {
            let mut ca = 0u64;
            let mut cb = vec![0u64; parts.len()];
            let mut acc = 0f64;
            for k in 0..HISTOGRAM_BINS - 1 {
                ca += self.bins[k][ch];
                let mut fb = 0f64;
                for ((h, w), c) in parts.iter().zip(cb.iter_mut()) {
                    *c += h.bins[k][ch];
                    fb += w / total * (*c as f64 / h.count as f64);
                }
                // Differences below 1e-12 are the rounding of the weighted sum (a part's share
                // of one pixel in a trillion): the exemplar's own colors score exactly 0.
                let d = (ca as f64 / na - fb).abs();
                if d > 1e-12 {
                    acc += d;
                }
            }
            *o = (acc / (HISTOGRAM_BINS - 1) as f64) as f32;
        }
        Some(out)
    }
}

/// Exact per-channel Wasserstein-1 (earth mover's) distance between the empirical
/// distributions of two color samples, `∫ |F_a(x) − F_b(x)| dx` per channel (the mean
/// absolute difference of matched quantiles); `None` if either sample is empty. The samples
/// may differ in size. Identical distributions score 0; shifting every value by `δ` scores `δ`.
///
/// This sorts the samples; [`ColorHistogram::wasserstein`] is the binned, streaming
/// equivalent [`super::evaluate`] uses (they agree to within `1 / (2 (HISTOGRAM_BINS − 1))`).
pub fn palette_distance(a: &[Rgb], b: &[Rgb]) -> Option<[f32; 3]> {
    if a.is_empty() || b.is_empty() {
        return None;
    }
    let mut out = [0f32; 3];
    out.par_iter_mut().enumerate().for_each(|(ch, o)| {
        let mut xa: Vec<f32> = a.iter().map(|c| c[ch]).collect();
        let mut xb: Vec<f32> = b.iter().map(|c| c[ch]).collect();
        xa.sort_by(f32::total_cmp);
        xb.sort_by(f32::total_cmp);
        *o = wasserstein_sorted(&xa, &xb) as f32;
    });
    Some(out)
}

/// `∫ |F_a − F_b|` for two sorted, non-empty samples: walk the merged order and integrate the
/// CDF gap between consecutive distinct values.
fn wasserstein_sorted(a: &[f32], b: &[f32]) -> f64 {
    let (na, nb) = (a.len() as f64, b.len() as f64);
    let (mut i, mut j) = (0usize, 0usize);
    let mut acc = 0f64;
    let mut prev: Option<f64> = None;
    while i < a.len() || j < b.len() {
        let x = match (a.get(i), b.get(j)) {
            (Some(&u), Some(&v)) => u.min(v),
            (Some(&u), None) => u,
            (None, Some(&v)) => v,
            (None, None) => break,
        } as f64;
        if let Some(p) = prev {
            acc += (i as f64 / na - j as f64 / nb).abs() * (x - p);
        }
        while i < a.len() && a[i] as f64 == x {
            i += 1;
        }
        while j < b.len() && b[j] as f64 == x {
            j += 1;
        }
        prev = Some(x);
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_distance_of_known_samples() {
        let a: Vec<Rgb> = (0..100).map(|i| [i as f32 / 100.0, 0.5, 0.2]).collect();
        let b: Vec<Rgb> = a.iter().map(|c| [c[0] + 0.1, 0.5, 0.3]).collect();
        let d = palette_distance(&a, &b).unwrap();
        assert!((d[0] - 0.1).abs() < 1e-5 && d[1] == 0.0 && (d[2] - 0.1).abs() < 1e-6, "{d:?}");
        // Different sizes: {0} vs {0, 1} → half the mass moves by 1.
        let d = palette_distance(&[[0.0; 3]], &[[0.0; 3], [1.0; 3]]).unwrap();
        assert!((d[0] - 0.5).abs() < 1e-6);
        assert!(palette_distance(&[], &a).is_none());
    }

    #[test]
    fn histogram_agrees_with_exact() {
        let mut s = 7u32;
        let mut next = || {
            s = s.wrapping_mul(1664525).wrapping_add(1013904223);
            (s >> 8) as f32 / (1u32 << 24) as f32
        };
        let a: Vec<Rgb> = (0..3000).map(|_| [next(), next() * next(), 0.5 + 0.5 * next()]).collect();
        let b: Vec<Rgb> = (0..1700).map(|_| [next() * 0.8, next(), next()]).collect();
        let exact = palette_distance(&a, &b).unwrap();
        let mut ha = ColorHistogram::new();
        a.iter().for_each(|&c| ha.add(c));
        let mut hb = ColorHistogram::new();
        b.iter().for_each(|&c| hb.add(c));
        let binned = ha.wasserstein(&hb).unwrap();
        for ch in 0..3 {
            assert!((exact[ch] - binned[ch]).abs() <= 0.5 / (HISTOGRAM_BINS - 1) as f32 + 1e-6, "{exact:?} {binned:?}");
        }
        assert_eq!(ha.wasserstein(&ha).unwrap(), [0.0; 3]);
    }
}
