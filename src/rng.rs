//! The crate's one pseudo-random generator, SplitMix64 (Steele, Lea, Flood 2014), and the
//! hashes built from its finalizer.
//!
//! Every random stream is either drawn in a fixed order on one thread (the exemplar
//! generator) or keyed by what it is for — seed, frame, level, iteration, pixel
//! ([`SplitMix64::keyed`]) — so results do not depend on the thread count or scheduling.

/// SplitMix64: 64 bits of state, passes BigCrush, trivially seedable. Good enough for
/// textures, random thresholds, PatchMatch's random search and sampling; not for
/// cryptography.
#[derive(Clone, Debug)]
pub(crate) struct SplitMix64(u64);

/// The golden-ratio increment of the state.
const GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

impl SplitMix64 {
    /// A generator started from `seed`.
    pub(crate) fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }

    /// A stream keyed by several values (seed, frame, level, …): the same keys give the same
    /// stream, different keys independent-looking ones.
    pub(crate) fn keyed(keys: &[u64]) -> Self {
        SplitMix64(keys.iter().fold(GAMMA, |h, &k| mix(h ^ k.wrapping_mul(GAMMA))))
    }

    /// The next 64 random bits.
    #[inline]
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(GAMMA);
        mix(self.0)
    }

    /// Uniform in `[0, 1)`, 24 bits of precision.
    #[inline]
    pub(crate) fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// Uniform in `[lo, hi)` (`lo` when the range is empty).
    #[inline]
    pub(crate) fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }

    /// Uniform integer in `0..n` (`n > 0`, at most 2³²), from the upper 32 bits.
    #[inline]
    pub(crate) fn below(&mut self, n: usize) -> usize {
        (((self.next_u64() >> 32) * n as u64) >> 32) as usize
    }

    /// A new independent generator for a sub-task, derived from this one.
    pub(crate) fn fork(&mut self) -> SplitMix64 {
        SplitMix64::new(self.next_u64() ^ 0xD1B5_4A32_D192_ED03)
    }
}

/// The SplitMix64 finalizer: a bijective 64-bit mix.
#[inline]
pub(crate) fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A uniform value in `[0, 1)` for the lattice point `(x, y)` of noise layer `seed`.
#[inline]
pub(crate) fn lattice(seed: u64, x: i64, y: i64) -> f32 {
    let h = mix(seed ^ mix((x as u64).wrapping_mul(GAMMA) ^ (y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)));
    (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deterministic_and_uniform() {
        let mut a = SplitMix64::new(7);
        let mut b = SplitMix64::new(7);
        let xs: Vec<f32> = (0..10_000).map(|_| a.next_f32()).collect();
        assert!(xs.iter().all(|&x| (0.0..1.0).contains(&x)));
        assert!(xs.iter().zip((0..10_000).map(|_| b.next_f32())).all(|(x, y)| *x == y));
        let mean = xs.iter().sum::<f32>() / xs.len() as f32;
        assert!((mean - 0.5).abs() < 0.02, "mean {mean}");
        assert!((0..1000).all(|_| a.below(7) < 7));
    }

    #[test]
    fn known_values() {
        // SplitMix64's reference output for seed 0 (the first two values).
        let mut r = SplitMix64::new(0);
        assert_eq!(r.next_u64(), 0xE220_A839_7B1D_CDAF);
        assert_eq!(r.next_u64(), 0x6E78_9E6A_A1B9_65F4);
    }

    #[test]
    fn keyed_streams_are_reproducible_and_distinct() {
        let a: Vec<u64> = (0..4).map(|_| SplitMix64::keyed(&[1, 2, 3]).next_u64()).collect();
        assert!(a.windows(2).all(|w| w[0] == w[1]));
        assert_ne!(SplitMix64::keyed(&[1, 2, 3]).next_u64(), SplitMix64::keyed(&[1, 2, 4]).next_u64());
    }
}
