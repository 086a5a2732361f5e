//! Recoloring a synthesized layer: from the exemplar's colors to pigment amount (Beer–Lambert)
//! and the layer's own colors.

use super::Recolor;
use super::color::{fast_ln, ln_linear, rgb_to_linear, sanitize, srgb_to_linear};
use crate::error::{Error, Result};
use crate::exemplar::Exemplar;
use crate::img::{Mask, Plane, Rect, Rgb, Rgba, sample_bilinear};
use rayon::prelude::*;

/// Floor of linear-light intensities before taking logarithms (density ≤ ln 10⁴ ≈ 9.2).
pub const INTENSITY_FLOOR: f32 = 1e-4;
/// Floor of a tint's linear channels in [`Recolor::Glaze`] and [`Recolor::Over`] (sRGB ≈ 25/255):
/// the transmittance of the layer's color at the typical density. A channel at 0 (pure
/// colors: #ff00ff, #0000ff, black) would absorb everything at any amount of paint, `0^a = 0`,
/// and the paint's texture would not show in it at all; with the floor it shows as in any
/// other color (`0.01^a`: 0.10 at half the typical density, 0.0001 at twice), and the typical
/// density gives #ff19ff for #ff00ff — what a watercolor can reach.
pub const TINT_FLOOR: f32 = 0.01;
/// Largest pigment amount `a` kept (a multiple of the reference density).
pub const MAX_AMOUNT: f32 = 8.0;
/// Smallest mean reference density; exemplars lighter than this (no paint at all) are
/// measured against this floor so that noise on bare paper is not blown up to full color.
pub const MIN_REFERENCE_DENSITY: f32 = 0.05;
/// At most this many exemplar pixels are sampled by [`Pigment::from_exemplar`].
const MAX_SAMPLES: usize = 250_000;

/// The optics of an exemplar: its paper color and the **reference density** `k` — the
/// per-channel optical density of its typical paint (the median over painted pixels).
///
/// With linear-light intensities `I` and paper `P`, the density of a pixel is
/// `d_c = ln P_c − ln max(I_c, 10⁻⁴)` (Beer–Lambert: `I = P · e^(−d)`), and its **pigment
/// amount** is the least-squares projection of `d` on `k`:
/// `a = clamp((d · k) / (k · k), 0, 8)`, so `a = 1` at the typical density, `a < 1` in light
/// washes and blooms, `a > 1` in dark rims and granulation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pigment {
    paper: Rgb,
    paper_ln: [f32; 3],
    reference: [f32; 3],
}

impl Pigment {
    /// A pigment of the given paper color (sRGB) and reference density (per channel, linear
    /// light). The reference is clamped to non-negative values and raised to a mean of at
    /// least [`MIN_REFERENCE_DENSITY`].
    pub fn new(paper: Rgb, reference: [f32; 3]) -> Pigment {
        let paper = paper.map(sanitize);
        let paper_ln = paper.map(|v| fast_ln(srgb_to_linear(v).max(INTENSITY_FLOOR)));
        let mut k = reference.map(|v| if v.is_finite() { v.max(0.0) } else { 0.0 });
        let mean = (k[0] + k[1] + k[2]) / 3.0;
        if mean < MIN_REFERENCE_DENSITY {
            k = if mean > 1e-6 { k.map(|v| v * MIN_REFERENCE_DENSITY / mean) } else { [MIN_REFERENCE_DENSITY; 3] };
        }
        Pigment { paper, paper_ln, reference: k }
    }

    /// Measures the reference density as the per-channel median density of `paint`, colors
    /// (sRGB) of pixels where paint is present. Without any sample the reference is the floor.
    pub fn from_colors(paper: Rgb, paint: impl IntoIterator<Item = Rgb>) -> Pigment {
        let base = Pigment::new(paper, [0.0; 3]);
        let mut channels: [Vec<f32>; 3] = Default::default();
        for c in paint {
            let d = base.density(c);
            for (ch, v) in channels.iter_mut().zip(d) {
                ch.push(v);
            }
        }
        Pigment::new(paper, channels.map(|mut v| median(&mut v)))
    }

    /// Measures the reference density over a whole exemplar (all frames, inside `S^mask`,
    /// regularly subsampled to at most 250 000 pixels). Computed once per exemplar, it keeps
    /// the recolored intensity stable from frame to frame, unlike a per-frame estimate.
    pub fn from_exemplar(exemplar: &Exemplar) -> Pigment {
        let total: usize = exemplar.frames.iter().map(|f| f.len()).sum();
        let stride = total.div_ceil(MAX_SAMPLES).max(1);
        let samples = exemplar.frames.iter().zip(&exemplar.masks).flat_map(|(f, m)| {
            f.data().iter().zip(m.data()).step_by(stride).filter(|(_, m)| **m >= 0.5).map(|(c, _)| *c)
        });
        Pigment::from_colors(exemplar.paper(), samples)
    }

    /// The paper color (sRGB).
    pub fn paper(&self) -> Rgb {
        self.paper
    }

    /// The reference density `k` (per channel, linear light).
    #[cfg(test)] // used by the tests only
    pub fn reference_density(&self) -> [f32; 3] {
        self.reference
    }

    /// The optical density `d` of an sRGB color against the paper (negative where the color is
    /// lighter than the paper).
    #[inline]
    pub fn density(&self, c: Rgb) -> [f32; 3] {
        let ln = ln_linear(c);
        [self.paper_ln[0] - ln[0], self.paper_ln[1] - ln[1], self.paper_ln[2] - ln[2]]
    }

    /// The pigment amount `a` of an sRGB color (1 = the reference density).
    #[inline]
    pub fn amount(&self, c: Rgb) -> f32 {
        let d = self.density(c);
        let k = self.reference;
        let a = (d[0] * k[0] + d[1] * k[1] + d[2] * k[2]) / (k[0] * k[0] + k[1] * k[1] + k[2] * k[2]);
        if a.is_finite() { a.clamp(0.0, MAX_AMOUNT) } else { 0.0 }
    }
}

/// Median of finite values (0 for none); reorders `v`.
fn median(v: &mut Vec<f32>) -> f32 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return 0.0;
    }
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
    *m
}

/// One pixel of a recolored layer.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct LayerPixel {
    /// Inside the synthesized mask (outside, nothing of the layer is drawn).
    pub on: bool,
    /// Pigment amount `a` (1 = reference density); 1 for [`Recolor::None`].
    pub amount: f32,
    /// Linear-light color: the tint `F` (glaze, over) or the exemplar's own transmittance
    /// `I / P` (none).
    pub color: Rgb,
    /// `ln max(color, 10⁻⁴)`.
    pub ln: Rgb,
    /// The layer's opacity here ([`super::opacity`]; 1 for a painted keyframe layer).
    pub opacity: f32,
}

/// A synthesized layer ready for [`composite`](super::composite): per pixel inside the
/// synthesized mask, the pigment amount and the color it is painted in.
#[derive(Clone, Debug)]
pub struct StylizedLayer {
    pub(crate) mode: Recolor,
    pub(crate) width: usize,
    pub(crate) height: usize,
    /// `[x0, y0, x1, y1)`: bounding box of the mask (all 0 when the mask is empty).
    pub(crate) bbox: [usize; 4],
    /// The pixels of the bounding box, row-major.
    pub(crate) px: Vec<LayerPixel>,
}

impl StylizedLayer {
    /// `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The pigment amount `a` at `(x, y)` (1 = the reference density), `None` outside the
    /// mask or the image.
    #[cfg(test)] // used by the tests only
    pub fn amount(&self, x: usize, y: usize) -> Option<f32> {
        self.pixel(x, y).map(|p| p.amount)
    }

    /// The color the layer is painted in at `(x, y)`, sRGB: the tint (the flat rendering,
    /// extended past its coverage) for glaze and over, the exemplar's transmittance (its color
    /// with the paper normalized to white) for [`Recolor::None`]. `None` outside the mask.
    #[cfg(test)] // used by the tests only
    pub fn tint(&self, x: usize, y: usize) -> Option<Rgb> {
        self.pixel(x, y).map(|p| super::color::rgb_to_srgb(p.color))
    }

    #[cfg(test)] // used by the tests only
    fn pixel(&self, x: usize, y: usize) -> Option<LayerPixel> {
        let [x0, y0, x1, y1] = self.bbox;
        ((x0..x1).contains(&x) && (y0..y1).contains(&y))
            .then(|| self.px[(y - y0) * (x1 - x0) + x - x0])
            .filter(|p| p.on)
    }

    /// The layer alone over a transparent background, straight sRGB RGBA (for
    /// `--keep-layers`; see [`composite`](super::composite) for how a glaze becomes alpha).
    pub fn to_rgba(&self) -> Plane<Rgba> {
        let layer = [super::LayerFrame::stylized(self, None)];
        super::composite_unchecked(
            self.width,
            self.height,
            &super::Background::Transparent,
            &layer,
            super::StrokeMode::Drop,
        )
    }
}

fn check_size(what: &str, found: (usize, usize), expected: (usize, usize)) -> Result<()> {
    if found == expected {
        Ok(())
    } else {
        Err(Error::param(
            what,
            format!("{}x{}", found.0, found.1),
            format!("the synthesized frame's size {}x{}", expected.0, expected.1),
        ))
    }
}

/// Recolors one synthesized frame of a layer, estimating the reference density from this frame
/// alone (the per-channel median density over mask pixels where `flat` covers at least half,
/// else over the whole mask). Prefer [`recolor_with`] and a [`Pigment::from_exemplar`] computed
/// once per exemplar: it is cheaper and keeps the intensity steady over time.
///
/// `stylized` is the engine's output in the exemplar's colors, `mask` the synthesized region,
/// `flat` the layer's flat rendering (its own colors; alpha = coverage), `paper` the exemplar's
/// paper color. All three images must have the same size.
#[cfg(test)] // used by the tests only
pub fn recolor(
    stylized: &Plane<Rgb>,
    mask: &Mask,
    flat: &Plane<Rgba>,
    paper: Rgb,
    mode: Recolor,
) -> Result<StylizedLayer> {
    check_size("mask size", mask.size(), stylized.size())?;
    check_size("flat layer size", flat.size(), stylized.size())?;
    let inside = |min_alpha: f32| {
        stylized
            .data()
            .iter()
            .zip(mask.data())
            .zip(flat.data())
            .filter(move |((_, m), f)| **m && f[3] >= min_alpha)
            .map(|((c, _), _)| *c)
    };
    let pigment = if inside(0.5).next().is_some() {
        Pigment::from_colors(paper, inside(0.5))
    } else {
        Pigment::from_colors(paper, inside(0.0))
    };
    recolor_with(stylized, mask, flat, &pigment, mode)
}

/// [`recolor_layer`] of a layer whose flat alpha holds its opacity (Lottie, SVG).
#[cfg(test)] // the tests' entry; the renderer calls `recolor_layer`
pub fn recolor_with(
    stylized: &Plane<Rgb>,
    mask: &Mask,
    flat: &Plane<Rgba>,
    pigment: &Pigment,
    mode: Recolor,
) -> Result<StylizedLayer> {
    recolor_layer(stylized, mask, flat, pigment, mode, true)
}

/// Recolors one synthesized frame of a layer against a known [`Pigment`].
///
/// For every pixel inside `mask`:
/// - [`Recolor::Glaze`] and [`Recolor::Over`] keep the pigment amount `a` ([`Pigment::amount`])
///   and the tint `F`: the flat rendering's color at that pixel in linear light — where `flat`
///   covers only partly or not at all (its antialiased edge, the paper margin of the
///   synthesized mask) `F` is blended with the nearest covered colors (push–pull filling of the
///   premultiplied flat rendering), so edges keep their hue instead of turning black or white;
/// - [`Recolor::None`] keeps the exemplar's transmittance `I / P` (per channel, linear, at most
///   1) with `a = 1`;
/// - the layer's opacity ([`super::opacity`], from `flat`'s alpha) is kept; with
///   `opacity_in_alpha` false (a mask sequence, whose flat alpha is coverage alone) the layer
///   is drawn at full opacity.
///
/// How these become pixels is described at [`composite`](super::composite).
pub(crate) fn recolor_layer(
    stylized: &Plane<Rgb>,
    mask: &Mask,
    flat: &Plane<Rgba>,
    pigment: &Pigment,
    mode: Recolor,
    opacity_in_alpha: bool,
) -> Result<StylizedLayer> {
    check_size("mask size", mask.size(), stylized.size())?;
    check_size("flat layer size", flat.size(), stylized.size())?;
    let (w, h) = stylized.size();
    // The tint is computed on the box grown by a margin, so colors just outside it still
    // reach the mask's edge.
    let grown = mask.bounding_box().filter(|_| mode != Recolor::None).map(|b| b.expand(TINT_MARGIN, w, h));
    let tint = grown.map(|g| (g, extended_tint(flat, mask, g)));
    let paper_lin = rgb_to_linear(pigment.paper());
    let opacity = opacity_in_alpha.then(|| super::opacity(flat));
    Ok(layer(mask, mode, |x, y| {
        let c = stylized.get(x, y);
        let o = opacity.as_ref().map_or(1.0, |o| o.get(x, y));
        match &tint {
            Some((g, t)) => (pigment.amount(c), o, t.get(x - g.x0, y - g.y0).map(|v| v.max(TINT_FLOOR))),
            None => {
                let lin = rgb_to_linear(c);
                (1.0, o, [0, 1, 2].map(|i| (lin[i] / paper_lin[i].max(INTENSITY_FLOOR)).min(1.0)))
            }
        }
    }))
}

/// A layer in its final colors — a layer painted from keyframes, whose colors are the user's
/// painting: drawn opaque (ordinary "over") with its own colors inside `mask`, nothing recolored.
pub fn painted(rgb: &Plane<Rgb>, mask: &Mask) -> Result<StylizedLayer> {
    check_size("mask size", mask.size(), rgb.size())?;
    // Amount at the opaque threshold: fully opaque, in the color itself.
    Ok(layer(mask, Recolor::Over, |x, y| (super::OVER_OPAQUE_AMOUNT, 1.0, rgb_to_linear(rgb.get(x, y)))))
}

/// The layer of the pixels inside `mask` (over its bounding box, rows in parallel), each
/// `pixel(x, y)` = (pigment amount, opacity, linear color).
fn layer(mask: &Mask, mode: Recolor, pixel: impl Fn(usize, usize) -> (f32, f32, Rgb) + Sync) -> StylizedLayer {
    let (w, h) = mask.size();
    let bbox = mask.bounding_box().map_or([0; 4], |b| [b.x0, b.y0, b.x1, b.y1]);
    let [x0, y0, x1, y1] = bbox;
    let bw = x1 - x0;
    let mut px = vec![LayerPixel::default(); bw * (y1 - y0)];
    if bw > 0 {
        px.par_chunks_mut(bw).enumerate().for_each(|(row, out)| {
            let y = y0 + row;
            // Flat fills repeat one color: reuse its logarithm.
            let mut last: Option<(Rgb, Rgb)> = None;
            for (x, p) in (x0..x1).zip(out.iter_mut()) {
                if !mask.get(x, y) {
                    continue;
                }
                let (amount, opacity, color) = pixel(x, y);
                let color = color.map(|v| sanitize(v).max(INTENSITY_FLOOR));
                let ln = match last {
                    Some((c, ln)) if c == color => ln,
                    _ => [fast_ln(color[0]), fast_ln(color[1]), fast_ln(color[2])],
                };
                last = Some((color, ln));
                *p = LayerPixel { on: true, amount, color, ln, opacity };
            }
        });
    }
    StylizedLayer { mode, width: w, height: h, bbox, px }
}

/// Margin (pixels) around the mask's bounding box from which flat colors are gathered.
const TINT_MARGIN: usize = 16;

/// The flat rendering's color in linear light, defined everywhere: the straight color where
/// the coverage is full, blended towards the colors of the nearest covered pixels where it is
/// partial or zero (pull–push filling, Gortler et al. 1996: coarser levels take the
/// coverage-weighted mean color of their children with the weight `min(1, Σ w)`, so a coarse
/// pixel with one fully covered child is fully trusted; finer levels are then completed with
/// `c = w·c + (1 − w)·coarse`). Computed on `region` (non-empty) only;
/// only pixels inside `mask` matter.
fn extended_tint(flat: &Plane<Rgba>, mask: &Mask, region: Rect) -> Plane<Rgb> {
    let Rect { x0: rx, y0: ry, x1: rx1, y1: ry1 } = region;
    // Straight linear color and weight (the coverage).
    let level0: Plane<[f32; 4]> = Plane::from_fn(rx1 - rx, ry1 - ry, |x, y| {
        let c = flat.get(rx + x, ry + y);
        let l = rgb_to_linear([c[0], c[1], c[2]]);
        [l[0], l[1], l[2], sanitize(c[3])]
    });
    let needs_fill = level0
        .data()
        .iter()
        .enumerate()
        .any(|(i, c)| c[3] < 1.0 && mask.get(rx + i % level0.width(), ry + i / level0.width()));
    if !needs_fill {
        return level0.map(|c| [c[0], c[1], c[2]]);
    }
    let mut levels = vec![level0];
    while let Some(last) = levels.last()
        && (last.width() > 1 || last.height() > 1)
    {
        let next = pull(last);
        levels.push(next);
    }
    let top = levels.last().map(|p| p.get(0, 0)).unwrap_or([0.0; 4]);
    // Nothing covered at all: a white tint, which glazes to nothing.
    let mut filled: Plane<Rgb> = Plane::filled(1, 1, if top[3] > 0.0 { [top[0], top[1], top[2]] } else { [1.0; 3] });
    for level in levels.iter().rev().skip(1) {
        let coarse = &filled;
        filled = Plane::from_fn(level.width(), level.height(), |x, y| {
            let p = level.get(x, y);
            let w = p[3];
            if w >= 1.0 {
                return [p[0], p[1], p[2]];
            }
            let up = sample_bilinear(coarse, (x as f32 + 0.5) * 0.5 - 0.5, (y as f32 + 0.5) * 0.5 - 0.5);
            [0, 1, 2].map(|i| w * p[i] + (1.0 - w) * up[i])
        });
    }
    filled
}

/// One coarser level: the weighted mean color of each 2×2 block and the weight `min(1, Σ w)`.
fn pull(fine: &Plane<[f32; 4]>) -> Plane<[f32; 4]> {
    let (w, h) = fine.size();
    Plane::from_fn(w.div_ceil(2), h.div_ceil(2), |x, y| {
        let mut acc = [0.0f32; 4];
        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let (fx, fy) = (2 * x + dx, 2 * y + dy);
            if fx < w && fy < h {
                let p = fine.get(fx, fy);
                for i in 0..3 {
                    acc[i] += p[i] * p[3];
                }
                acc[3] += p[3];
            }
        }
        if acc[3] > 0.0 { [acc[0] / acc[3], acc[1] / acc[3], acc[2] / acc[3], acc[3].min(1.0)] } else { [0.0; 4] }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn amount_is_one_at_reference_and_scales_with_density() {
        let paper = [0.95, 0.95, 0.92];
        let pig = Pigment::new(paper, [1.2, 0.6, 0.1]);
        let paint = |a: f32| {
            let p = rgb_to_linear(paper);
            let k = pig.reference_density();
            [0, 1, 2].map(|i| super::super::color::linear_to_srgb(p[i] * (-a * k[i]).exp()))
        };
        for a in [0.0, 0.5, 1.0, 2.0] {
            assert!((pig.amount(paint(a)) - a).abs() < 2e-3, "{a}: {}", pig.amount(paint(a)));
        }
        assert_eq!(pig.amount([1.0, 1.0, 1.0]), 0.0);
        assert_eq!(Pigment::new(paper, [0.0; 3]).reference_density(), [MIN_REFERENCE_DENSITY; 3]);
    }

    #[test]
    fn extended_tint_keeps_covered_colors_and_fills_the_margin() {
        // Left half red, right half green, covered only for 8 <= y < 24; mask everything.
        let flat = Plane::from_fn(32, 32, |x, y| {
            let a = if (8..24).contains(&y) { 1.0 } else { 0.0 };
            if x < 16 { [1.0, 0.0, 0.0, a] } else { [0.0, 1.0, 0.0, a] }
        });
        let mask = Plane::filled(32, 32, true);
        let t = extended_tint(&flat, &mask, Rect::full(32, 32));
        assert_eq!(t.get(3, 10), [1.0, 0.0, 0.0]);
        // Margin rows take the color of the covered pixels below/above them.
        let m = t.get(3, 2);
        assert!(m[0] > 0.8 && m[1] < 0.2, "{m:?}");
        let m = t.get(28, 30);
        assert!(m[1] > 0.8 && m[0] < 0.2, "{m:?}");
    }
}
