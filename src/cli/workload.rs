//! Synthetic workloads for benchmarks, shaped like the paper's: `horse` is a target of
//! 1000 × 800 pixels with ≈ 111 000 masked pixels (a body and a neck that move and deform),
//! stylized with a 400 × 222 × 20 exemplar (paper Table 2).

//!
//! Part of the command line (`fluidymation bench`), not of the library; `benches/synth.rs`
//! includes this file too.

use fluidymation::exemplar::{
    Exemplar,
    generate::{GeneratorParams, generate},
};
use fluidymation::img::Plane;
use fluidymation::{NoProgress, Result};

/// Frame `k` of the horse-like target at `width × height` (scaled from 1000 × 800): an ellipse
/// body that trots right and breathes, with a neck that nods.
pub fn horse_mask(width: usize, height: usize, k: usize) -> Plane<f32> {
    let s = width as f32 / 1000.0;
    let t = k as f32;
    let (cx, cy) = ((430.0 + 6.0 * t) * s, (420.0 + 8.0 * (t / 3.0).sin()) * height as f32 / 800.0);
    let (a, b) = ((220.0 + 3.0 * (t / 2.0).sin()) * s, 140.0 * s);
    let (nx, ny) = (cx + 190.0 * s, cy - (140.0 + 10.0 * (t / 2.0).sin()) * s);
    let (na, nb) = (38.0 * s, 100.0 * s);
    Plane::from_fn(width, height, |x, y| {
        let (x, y) = (x as f32, y as f32);
        let body = ((x - cx) / a).powi(2) + ((y - cy) / b).powi(2) < 1.0;
        let neck = ((x - nx) / na).powi(2) + ((y - ny) / nb).powi(2) < 1.0;
        if body || neck { 1.0 } else { 0.0 }
    })
}

/// The workload's exemplar: a generated 400 × 222 × 20 watercolor bloom (seed 3).
pub fn horse_exemplar() -> Result<Exemplar> {
    let params = GeneratorParams::default().size(400, 222).frames(20).seed(3);
    generate(&params, "horse-bench", &NoProgress)
}

#[cfg(test)]
mod tests {
    #[test]
    fn horse_has_about_111k_pixels() {
        let n = super::horse_mask(1000, 800, 0).data().iter().filter(|&&v| v > 0.5).count();
        assert!((100_000..125_000).contains(&n), "{n}");
    }
}
