//! The procedural watercolor generator: a drop of paint spreading on wet paper, simulated
//! after Curtis et al. 1997 (*Computer-Generated Watercolor*) and rendered with
//! Kubelka–Munk, following the project's recipe (`shared/notes/watercolor-generator.md`).
//!
//! Pipeline per exemplar:
//! 1. **paper** (`paper`): a height field of cloudy fBm, fine tooth and random fibres;
//! 2. **simulation** (`sim`): staggered-grid shallow-water velocities pushed downhill and by
//!    pressure, divergence relaxation with the drop as a water source, edge darkening (lower
//!    pressure near the rim), upwind pigment transport, paper-guided diffusion, Curtis's
//!    adsorption/desorption (granulation), and a wet front that advances where neighbouring
//!    pressure beats a paper- and noise-dependent threshold; an optional drying phase at the
//!    end freezes the front and lets pigment pile up at the rim;
//! 3. **rendering** (`km`): one Kubelka–Munk layer of suspended + deposited pigment over
//!    the paper's reflectance, converted to sRGB; the mask is where pigment is visible.
//!
//! Everything is single-threaded and driven by one SplitMix64 generator
//! stream, so a seed gives byte-identical frames on any machine and thread count.
//!
//! ```no_run
//! use fluidymation::exemplar::generate::{GeneratorParams, Pigment, generate};
//! let params = GeneratorParams::default().pigment(Pigment::Rose).seed(7).frames(24).bloom(1.5);
//! let ex = generate(&params, "rose-burst", &fluidymation::NoProgress)?;
//! ex.save(std::path::Path::new("rose-burst"), false)?;
//! # Ok::<(), fluidymation::Error>(())
//! ```

mod blur;
mod km;
mod paper;
mod sim;

use super::{Exemplar, ExemplarMeta};
use crate::error::{Error, Result};
use crate::img::{Plane, Rgb};
use crate::progress::Progress;
use crate::rng::SplitMix64;
use paper::Paper;
use serde::{Deserialize, Serialize};
use sim::{Drop, Sim, SimParams};
use std::fmt;
use std::str::FromStr;

/// Largest generated side, pixels.
pub const MAX_SIDE: usize = 2048;
/// Smallest generated side, pixels.
pub const MIN_SIDE: usize = 16;
/// Largest number of generated frames.
pub const MAX_FRAMES: usize = 1000;

/// A watercolor pigment: Kubelka–Munk absorption `K` and scattering `S` per RGB channel
/// (per unit thickness), and how it behaves on paper.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Pigment {
    /// Quinacridone Rose (Curtis 97): a transparent, staining magenta.
    Rose,
    /// Hansa Yellow (Curtis 97), made to granulate strongly here.
    Yellow,
    /// Cerulean Blue (Curtis 97): a soft, slightly granulating blue.
    Blue,
    /// A dark blue-black ink: high absorption, little scattering, strongly staining.
    Ink,
    /// A burnt-umber-like brown.
    Umber,
    /// A phthalo-like green.
    Green,
}

/// The physical constants of a [`Pigment`].
#[derive(Clone, Copy, Debug)]
pub struct PigmentProps {
    /// Absorption `K` per channel.
    pub k: [f32; 3],
    /// Scattering `S` per channel.
    pub s: [f32; 3],
    /// Pigment density ρ (deposition rate per step).
    pub density: f32,
    /// Staining power ω (≥ 1: deposited pigment lifts 1/ω as easily as it settles).
    pub staining: f32,
    /// Granulation γ in `0..=1`: how much paper valleys collect pigment.
    pub granulation: f32,
    /// Optical thickness per unit of pigment, for rendering.
    pub strength: f32,
}

impl Pigment {
    /// All pigments, in the order they are listed in help texts.
    pub const ALL: [Pigment; 6] =
        [Pigment::Rose, Pigment::Yellow, Pigment::Blue, Pigment::Ink, Pigment::Umber, Pigment::Green];

    /// The pigment's name (`rose`, `yellow`, …).
    pub fn name(self) -> &'static str {
        match self {
            Pigment::Rose => "rose",
            Pigment::Yellow => "yellow",
            Pigment::Blue => "blue",
            Pigment::Ink => "ink",
            Pigment::Umber => "umber",
            Pigment::Green => "green",
        }
    }

    /// Its physical constants.
    pub fn props(self) -> PigmentProps {
        let p = |k, s, density, staining, granulation, strength| PigmentProps {
            k,
            s,
            density,
            staining,
            granulation,
            strength,
        };
        match self {
            Pigment::Rose => p([0.22, 1.47, 0.57], [0.05, 0.003, 0.03], 0.02, 1.5, 0.6, 1.0),
            Pigment::Yellow => p([0.06, 0.21, 1.78], [0.5, 0.88, 0.009], 0.035, 1.2, 0.95, 1.2),
            Pigment::Blue => p([1.52, 0.32, 0.25], [0.06, 0.26, 0.40], 0.02, 1.5, 0.8, 1.0),
            Pigment::Ink => p([1.45, 1.25, 0.95], [0.02, 0.02, 0.03], 0.015, 3.0, 0.4, 1.0),
            Pigment::Umber => p([0.45, 0.75, 1.05], [0.12, 0.08, 0.06], 0.025, 1.5, 0.85, 1.0),
            Pigment::Green => p([1.55, 0.28, 1.15], [0.03, 0.08, 0.03], 0.02, 2.0, 0.5, 1.0),
        }
    }
}

impl fmt::Display for Pigment {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Pigment {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Pigment::ALL.into_iter().find(|p| p.name().eq_ignore_ascii_case(s.trim())).ok_or_else(|| {
            Error::param("pigment", s, Pigment::ALL.iter().map(|p| p.name()).collect::<Vec<_>>().join(", "))
        })
    }
}

/// Settings of the generator, as a validated builder: start from
/// [`GeneratorParams::default`], chain setters, and [`generate`] validates the ranges (or
/// call [`GeneratorParams::validate`]). Stored in `exemplar.toml` under `[generator]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
#[non_exhaustive]
pub struct GeneratorParams {
    /// Frame width, pixels. Default: 200. Range: 16–2048.
    pub width: usize,
    /// Frame height, pixels. Default: 200. Range: 16–2048.
    pub height: usize,
    /// Number of frames `l_S`. Default: 30. Range: 2–1000.
    pub frames: usize,
    /// Simulation steps per frame. Default: 12. Range: 1–100.
    pub steps_per_frame: usize,
    /// Frame rate written to the metadata. Default: 24.
    pub fps: f32,
    /// Seed of every random choice. Default: 1.
    pub seed: u64,
    /// The pigment. Default: blue.
    pub pigment: Pigment,
    /// Bloom speed: how fast the wet front runs (1 = normal, 2 = a fast burst, 0.5 = a slow
    /// bloom). Default: 1. Range: 0.25–4.
    pub bloom: f32,
    /// Rim strength: scales edge darkening η (0.2 × rim) and raises the wet-front threshold
    /// so pigment catches up with the front (0 = no dark rim, 1 = normal, 3 = strong).
    /// Default: 1. Range: 0–4.
    pub rim: f32,
    /// Directional drift of the water (a tilted sheet), pixels per step, `[x, y]` with y
    /// pointing down. Default: `[0, 0]`. Each component in −0.5–0.5.
    pub flow: [f32; 2],
    /// Number of drops. Default: 1. Range: 1–16.
    pub drops: usize,
    /// Radius of a drop, pixels (multiplied by size/200). Default: 7. Range: 2–50.
    pub drop_radius: f32,
    /// Granulation relative to the pigment's own (0 = smooth, 1 = the pigment's, 2 =
    /// double). Default: 1. Range: 0–3.
    pub granulation: f32,
    /// Paper grain (tooth and fibres) relative to the recipe. Default: 1. Range: 0–3.
    pub grain: f32,
    /// Pigment load: how much pigment each unit of water carries. Default: 1. Range: 0.1–5.
    pub load: f32,
    /// Fraction of the frames at the end in which the front stops and the paint dries
    /// (rims darken). Default: 0. Range: 0–0.8.
    pub drying: f32,
}

impl Default for GeneratorParams {
    fn default() -> Self {
        GeneratorParams {
            width: 200,
            height: 200,
            frames: 30,
            steps_per_frame: 12,
            fps: 24.0,
            seed: 1,
            pigment: Pigment::Blue,
            bloom: 1.0,
            rim: 1.0,
            flow: [0.0, 0.0],
            drops: 1,
            drop_radius: 7.0,
            granulation: 1.0,
            grain: 1.0,
            load: 1.0,
            drying: 0.0,
        }
    }
}

macro_rules! setter {
    ($(#[$doc:meta])* $name:ident: $t:ty) => {
        $(#[$doc])*
        pub fn $name(mut self, value: $t) -> Self {
            self.$name = value;
            self
        }
    };
}

impl GeneratorParams {
    /// Sets the frame size. Default: 200 × 200.
    pub fn size(mut self, width: usize, height: usize) -> Self {
        self.width = width;
        self.height = height;
        self
    }
    setter!(/// Sets the number of frames. Default: 30.
        frames: usize);
    setter!(/// Sets the simulation steps per frame. Default: 12.
        steps_per_frame: usize);
    setter!(/// Sets the frame rate. Default: 24.
        fps: f32);
    setter!(/// Sets the seed. Default: 1.
        seed: u64);
    setter!(/// Sets the pigment. Default: blue.
        pigment: Pigment);
    setter!(/// Sets the bloom speed. Default: 1.
        bloom: f32);
    setter!(/// Sets the rim strength. Default: 1.
        rim: f32);
    setter!(/// Sets the directional drift `[x, y]`, px/step. Default: `[0, 0]`.
        flow: [f32; 2]);
    setter!(/// Sets the number of drops. Default: 1.
        drops: usize);
    setter!(/// Sets the drop radius. Default: 7.
        drop_radius: f32);
    setter!(/// Sets the relative granulation. Default: 1.
        granulation: f32);
    setter!(/// Sets the paper grain. Default: 1.
        grain: f32);
    setter!(/// Sets the pigment load. Default: 1.
        load: f32);
    setter!(/// Sets the drying fraction. Default: 0.
        drying: f32);

    /// Checks every setting against its range; the error names the parameter, its value and
    /// the allowed range.
    pub fn validate(&self) -> Result<()> {
        fn range(name: &str, v: f32, lo: f32, hi: f32) -> Result<()> {
            if v.is_finite() && (lo..=hi).contains(&v) {
                Ok(())
            } else {
                Err(Error::param(name, v, format!("a number in {lo}–{hi}")))
            }
        }
        for (name, v) in [("width", self.width), ("height", self.height)] {
            if !(MIN_SIDE..=MAX_SIDE).contains(&v) {
                return Err(Error::param(
                    "size",
                    format!("{}x{}", self.width, self.height),
                    format!("{name} in {MIN_SIDE}–{MAX_SIDE} pixels"),
                ));
            }
        }
        if !(2..=MAX_FRAMES).contains(&self.frames) {
            return Err(Error::param("frames", self.frames, format!("2–{MAX_FRAMES}")));
        }
        if !(1..=100).contains(&self.steps_per_frame) {
            return Err(Error::param("steps-per-frame", self.steps_per_frame, "1–100"));
        }
        range("fps", self.fps, 0.1, 1000.0)?;
        range("bloom", self.bloom, 0.25, 4.0)?;
        range("rim", self.rim, 0.0, 4.0)?;
        range("flow x", self.flow[0], -0.5, 0.5)?;
        range("flow y", self.flow[1], -0.5, 0.5)?;
        if !(1..=16).contains(&self.drops) {
            return Err(Error::param("drops", self.drops, "1–16"));
        }
        range("drop-radius", self.drop_radius, 2.0, 50.0)?;
        range("granulation", self.granulation, 0.0, 3.0)?;
        range("grain", self.grain, 0.0, 3.0)?;
        range("load", self.load, 0.1, 5.0)?;
        range("drying", self.drying, 0.0, 0.8)?;
        Ok(())
    }

    /// The parameters as a TOML table (for `exemplar.toml`).
    pub fn to_table(&self) -> toml::Table {
        toml::Table::try_from(self).unwrap_or_default()
    }

    /// Number of frames (at the start) in which the front still grows.
    fn growing_frames(&self) -> usize {
        let dry = (self.drying * self.frames as f32).round() as usize;
        self.frames.saturating_sub(dry).max(1)
    }

    fn sim_params(&self) -> SimParams {
        let pig = self.pigment.props();
        let drag = 0.01;
        SimParams {
            viscosity: 0.1,
            drag,
            slope: 1.0,
            tilt: [self.flow[0] * drag, self.flow[1] * drag],
            edge_darkening: 0.2 * self.rim,
            edge_sigma: 10.0 / 3.0,
            diffusion: 0.03,
            density: pig.density,
            staining: pig.staining,
            granulation: (pig.granulation * self.granulation).min(1.0),
            front_threshold: 3.5 * (1.0 + 0.25 * self.rim) / self.bloom,
            front_noise: 0.6,
            source: 0.8,
            source_decay: 200.0,
            load: 2.0 * self.load,
            load_decay: 60.0,
            flow_suspend: 10.0,
        }
    }

    fn drop_list(&self, rng: &mut SplitMix64) -> Vec<Drop> {
        let (w, h) = (self.width as f32, self.height as f32);
        let scale = w.min(h) / 200.0;
        let r = self.drop_radius * scale;
        // Start upstream of the drift so the paint has room to travel.
        let fl = (self.flow[0].hypot(self.flow[1])).max(1e-6);
        let shift = self.flow[0].hypot(self.flow[1]).min(0.2);
        let (cx, cy) = (w * (0.5 - shift * self.flow[0] / fl), h * (0.5 - shift * self.flow[1] / fl));
        if self.drops == 1 {
            return vec![Drop { x: cx, y: cy, r }];
        }
        (0..self.drops)
            .map(|_| Drop {
                x: cx + rng.range(-0.15, 0.15) * w,
                y: cy + rng.range(-0.15, 0.15) * h,
                r: r * rng.range(0.6, 1.1),
            })
            .collect()
    }
}

/// Renders the simulation state: one Kubelka–Munk layer over the paper, and the mask
/// `(g + d > 0.05) ∧ M`.
fn render(sim: &Sim, props: &PigmentProps, granulation: f32, paper_tint: Rgb) -> (Plane<Rgb>, Plane<f32>) {
    let (w, h) = (sim.w, sim.h);
    let rgb = Plane::from_fn(w, h, |x, y| {
        let i = y * w + x;
        let hgt = sim.paper.height[i];
        let (g, d) = (sim.g[i], sim.d[i]);
        let x = props.strength * (0.5 * g + d * (1.0 + 1.6 * granulation * (0.5 - hgt)).max(0.0));
        let (r, t) = km::layer(props.k, props.s, x);
        km::over(r, t, paper_reflectance(hgt, paper_tint)).map(km::to_srgb)
    });
    let mut inside: Vec<bool> = (0..w * h).map(|i| sim.wet[i] && sim.g[i] + sim.d[i] > 0.05).collect();
    fill_holes(&mut inside, w, h);
    let mask = Plane::from_fn(w, h, |x, y| if inside[y * w + x] { 1.0 } else { 0.0 });
    (rgb, mask)
}

/// Fills the holes of a mask: unpainted pixels not connected (4-neighbourhood) to the frame
/// edge through unpainted pixels. A bloom whose paint was pushed out of its center still
/// covers that center.
fn fill_holes(mask: &mut [bool], w: usize, h: usize) {
    let mut outside = vec![false; w * h];
    let mut stack: Vec<usize> =
        (0..w * h).filter(|&i| !mask[i] && (i % w == 0 || i % w == w - 1 || i / w == 0 || i / w == h - 1)).collect();
    for &i in &stack {
        outside[i] = true;
    }
    while let Some(i) = stack.pop() {
        crate::img::for_each_neighbour4(i, w, h, |j| {
            if !mask[j] && !outside[j] {
                outside[j] = true;
                stack.push(j);
            }
        });
    }
    for (m, o) in mask.iter_mut().zip(&outside) {
        *m = !o;
    }
}

#[inline]
fn paper_reflectance(hgt: f32, tint: Rgb) -> Rgb {
    let b = 0.90 + 0.10 * (hgt - 0.5);
    [b * tint[0], b * tint[1], b * tint[2]]
}

/// The color of `thickness` units of `pigment` over white paper, as `#rrggbb`.
fn swatch(props: &PigmentProps, thickness: f32, paper: Rgb) -> String {
    let (r, t) = km::layer(props.k, props.s, thickness);
    super::hex_color(km::over(r, t, paper).map(km::to_srgb))
}

/// Runs the simulation and renders an exemplar named `name`. Reports one progress unit per
/// frame (stage `"simulating"`); returns [`Error::Cancelled`] when `progress` asks to stop.
/// The border width in the metadata is estimated with [`super::border::estimate_border_width`].
pub fn generate(params: &GeneratorParams, name: &str, progress: &dyn Progress) -> Result<Exemplar> {
    params.validate()?;
    let mut rng = SplitMix64::new(params.seed);
    let (w, h) = (params.width, params.height);
    let paper: Paper = paper::make(w, h, params.grain, &mut rng.fork());
    let drops = params.drop_list(&mut rng.fork());
    let props = params.pigment.props();
    let granulation = (props.granulation * params.granulation).min(1.5);
    let tint = [1.0, 0.98, 0.95];
    let mut sim = Sim::new(w, h, paper, params.sim_params(), &drops, rng.fork());
    let growing = params.growing_frames();
    let mut frames = Vec::with_capacity(params.frames);
    let mut masks = Vec::with_capacity(params.frames);
    for f in 0..params.frames {
        for _ in 0..params.steps_per_frame {
            sim.step(f < growing);
        }
        log::debug!("frame {}: {}", f + 1, sim.stats());
        let (rgb, mask) = render(&sim, &props, granulation, tint);
        frames.push(rgb);
        masks.push(mask);
        if !progress.update("simulating", f + 1, params.frames) {
            return Err(Error::Cancelled);
        }
    }
    // Paper color: the average rendered paper (no pigment).
    let paper_mean = {
        let mut acc = [0.0f64; 3];
        for &hgt in &sim.paper.height {
            let c = paper_reflectance(hgt, tint).map(km::to_srgb);
            (0..3).for_each(|i| acc[i] += c[i] as f64);
        }
        acc.map(|v| (v / (w * h) as f64) as f32)
    };
    let paper_lin = paper_reflectance(0.5, tint);
    let mut meta = ExemplarMeta {
        name: name.to_string(),
        description: describe(params),
        fps: params.fps,
        paper: super::hex_color(paper_mean),
        pigment: swatch(&props, 1.5, paper_lin),
        border_width: 0.0,
        scale: 1.0,
        speed: 1,
        seed: Some(params.seed),
        generator: Some(params.to_table()),
        license: "CC0-1.0 (procedurally generated by fluidymation)".into(),
        origin: format!("fluidymation {} watercolor generator", env!("CARGO_PKG_VERSION")),
    };
    let mut ex = Exemplar { dir: None, meta: meta.clone(), frames, masks };
    meta.border_width = super::border::estimate_border_width(&ex).width;
    ex.meta = meta;
    Ok(ex)
}

/// A one-line description of what the parameters make.
pub fn describe(p: &GeneratorParams) -> String {
    let speed = if p.bloom >= 1.3 {
        "fast"
    } else if p.bloom <= 0.8 {
        "slow"
    } else {
        "steady"
    };
    let mut extras = Vec::new();
    if p.granulation * p.pigment.props().granulation >= 1.2 || p.grain >= 1.5 {
        extras.push("granulating");
    }
    if p.rim >= 2.0 {
        extras.push("strong dark rims");
    } else if p.rim <= 0.6 {
        extras.push("soft feathered edges");
    }
    if p.flow[0] != 0.0 || p.flow[1] != 0.0 {
        extras.push("drifting with the flow");
    }
    if p.drying > 0.0 {
        extras.push("dries at the end");
    }
    let drops = if p.drops > 1 { format!(" of {} drops", p.drops) } else { String::new() };
    let extras = if extras.is_empty() { String::new() } else { format!(", {}", extras.join(", ")) };
    format!("generated {speed} {} bloom{drops}{extras}", p.pigment)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pigment_names_roundtrip() {
        for p in Pigment::ALL {
            assert_eq!(p.name().parse::<Pigment>().unwrap(), p);
        }
        assert!("mauve".parse::<Pigment>().is_err());
    }

    #[test]
    fn validation_names_the_parameter() {
        let e = GeneratorParams::default().size(0, 0).validate().unwrap_err().to_string();
        assert!(e.contains("0x0") && e.contains("16–2048"), "{e}");
        let e = GeneratorParams::default().size(100_000, 100_000).validate().unwrap_err().to_string();
        assert!(e.contains("100000x100000"), "{e}");
        let e = GeneratorParams::default().bloom(f32::NAN).validate().unwrap_err().to_string();
        assert!(e.contains("bloom"), "{e}");
        assert!(GeneratorParams::default().validate().is_ok());
    }

    #[test]
    fn params_roundtrip_through_toml() {
        let p = GeneratorParams::default().pigment(Pigment::Ink).flow([0.1, -0.05]).drops(3);
        let t = p.to_table();
        let q: GeneratorParams = t.try_into().unwrap();
        assert_eq!(p, q);
    }
}
