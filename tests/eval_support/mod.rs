//! Synthetic sequences for the `eval` tests: procedural "paint" (value-noise pigment density,
//! Beer–Lambert colors over paper) inside growing or moving discs.
#![allow(dead_code)]

use fluidymation::exemplar::{Exemplar, ExemplarMeta};
use fluidymation::img::{Plane, Rgb, Rgba};

/// The paper color, exactly the exemplar metadata's `#f5f0e6`.
pub const PAPER: Rgb = [245.0 / 255.0, 240.0 / 255.0, 230.0 / 255.0];
/// Optical density per unit pigment, per channel (a blue pigment).
pub const ABSORB: Rgb = [1.6, 0.9, 0.35];

fn hash(x: i64, y: i64, seed: u64) -> f32 {
    let mut h = (x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ seed.wrapping_mul(0x1656_67B1_9E37_79F9);
    h ^= h >> 29;
    h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h ^= h >> 32;
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// Smooth value noise in `0..1` with lattice cells of `cell` pixels.
pub fn value_noise(x: f32, y: f32, cell: f32, seed: u64) -> f32 {
    let (u, v) = (x / cell, y / cell);
    let (x0, y0) = (u.floor(), v.floor());
    let (fx, fy) = (u - x0, v - y0);
    let s = |t: f32| t * t * (3.0 - 2.0 * t);
    let (sx, sy) = (s(fx), s(fy));
    let (xi, yi) = (x0 as i64, y0 as i64);
    let a = hash(xi, yi, seed) * (1.0 - sx) + hash(xi + 1, yi, seed) * sx;
    let b = hash(xi, yi + 1, seed) * (1.0 - sx) + hash(xi + 1, yi + 1, seed) * sx;
    a * (1.0 - sy) + b * sy
}

/// Pigment density texture: two octaves of noise.
pub fn texture(x: f32, y: f32, seed: u64) -> f32 {
    0.65 * value_noise(x, y, 6.0, seed) + 0.35 * value_noise(x, y, 2.5, seed + 17)
}

/// Paint color for a pigment density.
pub fn paint(density: f32) -> Rgb {
    [0, 1, 2].map(|i| PAPER[i] * (-ABSORB[i] * density).exp())
}

/// Antialiased disc coverage.
pub fn disc(w: usize, h: usize, cx: f32, cy: f32, r: f32) -> Plane<f32> {
    Plane::from_fn(w, h, |x, y| {
        let d = ((x as f32 - cx).powi(2) + (y as f32 - cy).powi(2)).sqrt();
        (r - d + 0.5).clamp(0.0, 1.0)
    })
}

/// A procedural exemplar: a blue bloom growing from radius 14 by 2.5 px per frame in a
/// `size × size` frame. Its density is a static grain (fixed to the paper) plus a texture that
/// expands with the bloom (paint flowing outward) and slowly changes.
pub struct Bloom {
    pub size: usize,
    pub frames: usize,
}

impl Bloom {
    pub fn radius(&self, t: usize) -> f32 {
        14.0 + 2.5 * t as f32
    }

    pub fn center(&self) -> f32 {
        self.size as f32 / 2.0
    }

    /// The paint field of frame `t` over the whole frame (as if the paint were everywhere).
    pub fn field(&self, t: usize) -> Plane<Rgb> {
        let c = self.center();
        let k = self.radius(0) / self.radius(t);
        Plane::from_fn(self.size, self.size, |x, y| {
            let (dx, dy) = (x as f32 - c, y as f32 - c);
            let grain = texture(x as f32, y as f32, 3);
            let flowing = texture(c + dx * k, c + dy * k, 11);
            let slow = value_noise(x as f32 + 0.7 * t as f32, y as f32, 9.0, 23);
            paint(0.25 + 0.35 * grain + 0.5 * flowing + 0.15 * slow)
        })
    }

    pub fn mask(&self, t: usize) -> Plane<f32> {
        let c = self.center();
        disc(self.size, self.size, c, c, self.radius(t))
    }

    /// Frame `t` as the exemplar shows it: paint inside the mask over paper.
    pub fn frame(&self, t: usize) -> Plane<Rgb> {
        over_paper(&self.field(t), &self.mask(t))
    }

    pub fn exemplar(&self) -> Exemplar {
        let meta = ExemplarMeta {
            name: "test-bloom".into(),
            description: String::new(),
            fps: 24.0,
            paper: "#f5f0e6".into(),
            pigment: String::new(),
            border_width: 10.0,
            scale: 1.0,
            speed: 1,
            seed: None,
            generator: None,
            license: String::new(),
            origin: String::new(),
        };
        Exemplar {
            dir: None,
            meta,
            frames: (0..self.frames).map(|t| self.frame(t)).collect(),
            masks: (0..self.frames).map(|t| self.mask(t)).collect(),
        }
    }
}

/// `rgb` where `mask` is 1, paper where 0, blended in between.
pub fn over_paper(rgb: &Plane<Rgb>, mask: &Plane<f32>) -> Plane<Rgb> {
    Plane::from_fn(rgb.width(), rgb.height(), |x, y| {
        let (c, a) = (rgb.get(x, y), mask.get(x, y));
        [0, 1, 2].map(|i| c[i] * a + PAPER[i] * (1.0 - a))
    })
}

/// Straight RGBA with alpha = `mask` (what `synth` writes).
pub fn with_alpha(rgb: &Plane<Rgb>, mask: &Plane<f32>) -> Plane<Rgba> {
    Plane::from_fn(rgb.width(), rgb.height(), |x, y| {
        let c = rgb.get(x, y);
        [c[0], c[1], c[2], mask.get(x, y)]
    })
}

/// Opaque RGBA composited over `background`.
pub fn composited(rgb: &Plane<Rgb>, mask: &Plane<f32>, background: Rgb) -> Plane<Rgba> {
    Plane::from_fn(rgb.width(), rgb.height(), |x, y| {
        let (c, a) = (rgb.get(x, y), mask.get(x, y));
        let m = [0, 1, 2].map(|i| c[i] * a + background[i] * (1.0 - a));
        [m[0], m[1], m[2], 1.0]
    })
}
