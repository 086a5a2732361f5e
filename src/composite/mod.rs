//! Recoloring synthesized layers to their own colors and compositing them over the background.
//!
//! The engine paints every layer in the exemplar's colors (say blue pigment on white paper).
//! This module treats the exemplar as **paper × pigment transmittance** (Beer–Lambert), turns
//! each synthesized pixel into a pigment amount, re-tints it pixel by pixel with the layer's
//! flat rendering (so gradients and multi-colored layers keep their colors) and lays the layers
//! over the background in z-order.
//!
//! All arithmetic is in linear light; images in and out are straight-alpha sRGB.
//!
//! # Pipeline
//!
//! (Crate-private, so not a doc test; `render` does this for every frame.)
//!
//! ```ignore
//! use crate::composite::{self, Background, LayerFrame, Pigment, Recolor, StrokeMode};
//! # fn frames() -> (crate::img::Plane<[f32; 3]>, crate::img::Mask,
//! #     crate::anim::RegionFrame, crate::exemplar::Exemplar) { unimplemented!() }
//! let (rgb, mask, region_frame, exemplar) = frames();
//! let pigment = Pigment::from_exemplar(&exemplar); // once per exemplar
//! let layer = composite::recolor_layer(&rgb, &mask, &region_frame.fill, &pigment, Recolor::Glaze, true)?;
//! let layers = [LayerFrame::stylized(&layer, region_frame.strokes.as_ref())]; // bottom to top
//! let (w, h) = rgb.size();
//! let frame = composite::composite(w, h, &Background::default(), &layers, StrokeMode::Keep)?;
//! # Ok::<(), crate::Error>(())
//! ```
//!
//! # The glaze, exactly
//!
//! Notation: `I` the synthesized pixel, `P` the exemplar's paper, both linear light; `k` the
//! exemplar's reference density ([`Pigment`], the per-channel median density of its paint).
//!
//! 1. Density: `d_c = ln P_c − ln max(I_c, 10⁻⁴)`.
//! 2. Pigment amount (scalar): `a = clamp((d·k)/(k·k), 0, 8)` — the least-squares fit of
//!    `d = a·k`. For one pigment Beer–Lambert gives `d = amount × absorption spectrum`, so `a`
//!    is the amount relative to the typical paint. A scalar is used, not the per-channel
//!    density, because the exemplar's hue is exactly what is to be replaced; projecting on `k`
//!    (rather than taking, say, the luminance density) weighs the channels by how much the
//!    pigment absorbs in them, so a yellow pigment (absorbing only blue, nearly invisible in
//!    luminance) is measured as well as a blue one, with the best signal-to-noise ratio.
//! 3. Tint `F` (linear): the flat rendering at that pixel, extended past its coverage, each
//!    channel at least [`recolor::TINT_FLOOR`] (0.01): a channel at 0 would hide the paint's
//!    texture in it entirely (`0^a = 0`), which leaves pure colors flat.
//! 4. Base `B` (linear): the background at that pixel (white for a transparent background).
//!    Lift `β = max_c (F_c − B_c)/(1 − B_c)` over channels with `F_c > B_c`, clamped to
//!    `0..=1` (0 whenever `F ≤ B`, e.g. always on white paper); lifted base
//!    `B' = B + β(1 − B)`.
//! 5. Transmittance at the reference: `T_ref = F / B'` (≤ 1); at this pixel:
//!    `T = T_ref^a = exp(a · (ln F − ln B'))`; lift amount `λ = β · min(a, 1)`.
//! 6. Compositing onto the premultiplied linear result so far `(C, A)`:
//!    first the lift, white paint of opacity λ: `C ← λ + (1 − λ)C`, `A ← λ + (1 − λ)A`; then the
//!    glaze: `C ← C·T + (1 − A)(T − m)`, `A ← A + (1 − A)(1 − m)` with `m = min_c T_c`.
//!
//! 7. Opacity: a layer whose flat rendering is partly transparent (its fill's or its own
//!    opacity `o`, [`opacity`]) is laid over what is below with alpha `o`, as the flat layer is:
//!    `T ← 1 − o + o·T` and `λ ← o·λ` (with [`Recolor::Over`] its opacity is multiplied by `o`).
//!    The engine paints the shape itself ([`coverage`]), whatever `o`.
//!
//! On an opaque background (`A = 1`) step 6 is plain glazing, `out = below × T`, so stacked
//! glazes multiply their transmittances (`out = bg × Π T_k`) and overlaps get darker. Where the
//! paint has its typical density (`a = 1`) over the bare background, the result is exactly the
//! flat color `F`; the exemplar's texture (`a` ≠ 1: blooms, dark rims, granulation) modulates
//! it as more or less of the same pigment. The lift is the watercolorist's *reserved paper*:
//! a glaze can only darken, so a layer lighter than the background (a white cloud on a blue
//! sky) first lifts the background towards white where its paint is — nothing changes on white
//! paper. On a transparent background a glaze becomes the least-opaque film that looks the same
//! over white: alpha `1 − min_c T_c`, color `(T − m)/(1 − m)`.
//!
//! [`Recolor::Over`] composites like opaque paint: opacity `min(a / 0.5, 1)`
//! ([`OVER_OPAQUE_AMOUNT`]: paint of half the typical density already hides what is below), color
//! `F^max(a, 1) = exp(max(a, 1) · ln F)` (the flat color at the typical density, darker where
//! paint accumulates), with ordinary "over". [`Recolor::None`] glazes with the exemplar's own
//! transmittance `T = I / P`: over a background of the exemplar's paper color it reproduces the
//! exemplar's colors. Layers left flat draw their flat rendering with ordinary alpha, and
//! strokes are drawn the same way on top of their layer. Outside a layer's synthesized mask
//! nothing of it is drawn; pixels no layer touches are the background's exact values.

mod background;
mod color;
mod recolor;

pub use background::{Background, WHITE};
pub use color::parse_color;
pub(crate) use recolor::recolor_layer;
#[cfg(test)]
pub use recolor::recolor_with;
pub use recolor::{INTENSITY_FLOOR, Pigment, StylizedLayer, painted};

use crate::error::{Error, Result};
use crate::img::{Plane, Rgb, Rgba};
use color::{fast_exp, fast_ln, rgb_to_linear, sanitize};
use rayon::prelude::*;

/// With [`Recolor::Over`], paint of at least this amount (a fraction of the typical density)
/// hides what is below it; thinner paint (light blooms, the fading edge) lets it show through.
pub const OVER_OPAQUE_AMOUNT: f32 = 0.5;

/// How a stylized layer is recolored (`--recolor`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Recolor {
    /// Transparent watercolor: pigment density re-tinted to the layer's colors, layers
    /// multiply (glazing).
    #[default]
    Glaze,
    /// Opaque paint: the layer's colors, opacity from the pigment density, ordinary "over".
    Over,
    /// The exemplar's own colors, glazed.
    None,
}

/// What happens to a layer's strokes (`--strokes`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum StrokeMode {
    /// Drawn crisp (antialiased vector rendering) on top of their layer.
    #[default]
    Keep,
    /// Painted like the fill: merged into the layer's region before synthesis; nothing is
    /// drawn on top.
    Stylize,
    /// Not drawn.
    Drop,
}

/// What one layer contributes to a frame.
#[derive(Clone, Copy, Debug)]
pub enum LayerPaint<'a> {
    /// A synthesized, recolored layer.
    Stylized(&'a StylizedLayer),
    /// A layer left flat (no style): its flat rendering, straight sRGB RGBA, drawn with
    /// ordinary alpha.
    Flat(&'a Plane<Rgba>),
}

/// One layer of one frame, as given to [`composite`].
#[derive(Clone, Copy, Debug)]
pub struct LayerFrame<'a> {
    /// The layer's paint.
    pub paint: LayerPaint<'a>,
    /// The layer's strokes (straight sRGB RGBA), drawn over it with [`StrokeMode::Keep`] (and
    /// over a flat layer with [`StrokeMode::Stylize`]).
    pub strokes: Option<&'a Plane<Rgba>>,
}

impl<'a> LayerFrame<'a> {
    /// A stylized layer with its strokes.
    pub fn stylized(layer: &'a StylizedLayer, strokes: Option<&'a Plane<Rgba>>) -> Self {
        LayerFrame { paint: LayerPaint::Stylized(layer), strokes }
    }

    /// A flat layer with its strokes.
    pub fn flat(fill: &'a Plane<Rgba>, strokes: Option<&'a Plane<Rgba>>) -> Self {
        LayerFrame { paint: LayerPaint::Flat(fill), strokes }
    }

    fn size(&self) -> (usize, usize) {
        match self.paint {
            LayerPaint::Stylized(l) => l.size(),
            LayerPaint::Flat(p) => p.size(),
        }
    }
}

/// The fill with the strokes drawn over it (ordinary "over", straight sRGB RGBA): the region
/// to synthesize under [`StrokeMode::Stylize`].
pub fn merge_strokes(fill: &Plane<Rgba>, strokes: Option<&Plane<Rgba>>) -> Plane<Rgba> {
    let Some(strokes) = strokes.filter(|s| s.size() == fill.size()) else {
        return fill.clone();
    };
    let mut out = fill.clone();
    for (o, s) in out.data_mut().iter_mut().zip(strokes.data()) {
        let mut acc = premultiply(*o);
        over(&mut acc, *s);
        *o = unpremultiply(acc);
    }
    out
}

/// Radius (pixels) of the neighbourhood whose largest alpha is a layer's opacity ([`opacity`]):
/// wider than an antialiased edge.
pub(crate) const OPACITY_RADIUS: usize = 2;

/// A layer's opacity at every pixel, from its flat rendering `flat` (straight RGBA; alpha =
/// coverage × opacity — the layer's and the fill's, animated or not): the largest alpha within
/// [`OPACITY_RADIUS`], so that an antialiased edge has the opacity of the paint beside it;
/// where nothing of the layer is that close, the layer's largest alpha in the frame. A layer
/// at 40 % opacity is painted whole and laid over what is below with 40 % alpha (see
/// [`recolor_layer`]), not left out because its alpha is under ½, nor painted at full strength.
pub(crate) fn opacity(flat: &Plane<Rgba>) -> Plane<f32> {
    let (w, h) = flat.size();
    let r = OPACITY_RADIUS;
    let alpha = |x: usize, y: usize| sanitize(flat.get(x, y)[3]);
    // Only within `r` of the layer's paint is there an opacity to read: the windows are
    // computed there alone (a layer covers a small part of most frames).
    let Some(b) = flat.map(|c| sanitize(c[3]) > 0.0).bounding_box() else { return Plane::new(w, h) };
    let b = b.expand(r, w, h);
    let rows: Plane<f32> = Plane::par_from_fn(b.x1 - b.x0, b.y1 - b.y0, |x, y| {
        let (x, y) = (b.x0 + x, b.y0 + y);
        (x.saturating_sub(r)..(x + r + 1).min(w)).map(|i| alpha(i, y)).fold(0.0, f32::max)
    });
    let most = rows.data().iter().copied().fold(0.0, f32::max);
    Plane::par_from_fn(w, h, |x, y| {
        if !b.contains(x, y) {
            return most;
        }
        let (x, y) = (x - b.x0, y - b.y0);
        let o = (y.saturating_sub(r)..(y + r + 1).min(rows.height())).map(|j| rows.get(x, j)).fold(0.0, f32::max);
        if o > 0.0 { o } else { most }
    })
}

/// A layer's coverage by its shapes, whatever its opacity: the flat rendering's alpha divided
/// by its [`opacity`] (0–1). The engine's masks are this at ½, so a layer that fades in is
/// painted from its first visible frame, with the shape it has.
pub(crate) fn coverage(flat: &Plane<Rgba>) -> Plane<f32> {
    let o = opacity(flat);
    Plane::par_from_fn(flat.width(), flat.height(), |x, y| {
        let (a, o) = (sanitize(flat.get(x, y)[3]), o.get(x, y));
        if o > 0.0 { (a / o).min(1.0) } else { 0.0 }
    })
}

/// Composites `layers` (bottom to top) over `background` into a `width × height` frame of
/// straight sRGB RGBA. The formulas are in the [module documentation](self).
///
/// Every layer, its strokes and an image background must be `width × height`
/// ([`Error::InvalidParam`] otherwise). Rows are processed in parallel; the result does not
/// depend on the number of threads.
pub fn composite(
    width: usize,
    height: usize,
    background: &Background,
    layers: &[LayerFrame<'_>],
    strokes: StrokeMode,
) -> Result<Plane<Rgba>> {
    let expect = |what: &str, size: (usize, usize)| -> Result<()> {
        if size == (width, height) {
            Ok(())
        } else {
            Err(Error::param(what, format!("{}x{}", size.0, size.1), format!("the canvas size {width}x{height}")))
        }
    };
    if let Some(size) = background.size() {
        expect("background image size", size)?;
    }
    for layer in layers {
        expect("layer size", layer.size())?;
        if let Some(s) = layer.strokes {
            expect("stroke layer size", s.size())?;
        }
    }
    Ok(composite_unchecked(width, height, background, layers, strokes))
}

/// [`composite`] without the size checks.
pub(crate) fn composite_unchecked(
    width: usize,
    height: usize,
    background: &Background,
    layers: &[LayerFrame<'_>],
    strokes: StrokeMode,
) -> Plane<Rgba> {
    let mut out: Plane<Rgba> = Plane::new(width, height);
    if width == 0 {
        return out;
    }
    // Background constants (per-pixel for images).
    let uniform = match background {
        Background::Color(c) => Some(BasePixel::new(*c)),
        Background::Transparent => Some(BasePixel::new([0.0; 4])),
        Background::Image(_) => None,
    };
    out.data_mut().par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        let mut acc: Vec<[f32; 4]> = Vec::with_capacity(width);
        let mut base: Vec<BasePixel> = Vec::with_capacity(width);
        for x in 0..width {
            let b = uniform.unwrap_or_else(|| BasePixel::new(background.pixel(x, y)));
            acc.push(b.premultiplied);
            base.push(b);
        }
        let mut touched = vec![false; width];
        for layer in layers {
            match layer.paint {
                LayerPaint::Stylized(l) => draw_stylized(l, y, &mut acc, &base, &mut touched),
                LayerPaint::Flat(p) => draw_flat(p.row(y), &mut acc, &mut touched),
            }
            // A flat layer with `Stylize` is its fill and strokes merged, which is the same as
            // the strokes drawn over the fill.
            let flat = matches!(layer.paint, LayerPaint::Flat(_));
            if (strokes == StrokeMode::Keep || (flat && strokes == StrokeMode::Stylize))
                && let Some(s) = layer.strokes
            {
                draw_flat(s.row(y), &mut acc, &mut touched);
            }
        }
        for (x, o) in row.iter_mut().enumerate() {
            *o = if touched[x] { encode(acc[x]) } else { background.pixel(x, y) };
        }
    });
    out
}

/// The background at one pixel: its premultiplied linear value and the base `B` of the lift
/// (the background over white, linear) with its logarithm.
#[derive(Clone, Copy, Debug)]
struct BasePixel {
    premultiplied: [f32; 4],
    base: Rgb,
    ln_base: Rgb,
}

impl BasePixel {
    fn new(c: Rgba) -> BasePixel {
        let premultiplied = premultiply(c);
        let a = premultiplied[3];
        let base = [0, 1, 2].map(|i| (premultiplied[i] + 1.0 - a).clamp(recolor::INTENSITY_FLOOR, 1.0));
        BasePixel { premultiplied, base, ln_base: base.map(fast_ln) }
    }
}

/// Straight sRGB RGBA → premultiplied linear.
#[inline]
fn premultiply(c: Rgba) -> [f32; 4] {
    let a = color::sanitize(c[3]);
    let l = rgb_to_linear([c[0], c[1], c[2]]);
    [l[0] * a, l[1] * a, l[2] * a, a]
}

/// Premultiplied linear → straight sRGB RGBA.
#[inline]
fn unpremultiply(p: [f32; 4]) -> Rgba {
    let a = p[3].clamp(0.0, 1.0);
    if a <= 1e-7 {
        return [0.0; 4];
    }
    let inv = 1.0 / a;
    let c = color::rgb_to_srgb([p[0] * inv, p[1] * inv, p[2] * inv]);
    [c[0], c[1], c[2], a]
}

#[inline]
fn encode(p: [f32; 4]) -> Rgba {
    unpremultiply(p)
}

/// Ordinary "over" of a straight sRGB RGBA pixel onto a premultiplied linear accumulator.
#[inline]
fn over(acc: &mut [f32; 4], s: Rgba) {
    let a = color::sanitize(s[3]);
    let k = 1.0 - a;
    let l = rgb_to_linear([s[0], s[1], s[2]]);
    *acc = [l[0] * a + acc[0] * k, l[1] * a + acc[1] * k, l[2] * a + acc[2] * k, a + acc[3] * k];
}

fn draw_flat(row: &[Rgba], acc: &mut [[f32; 4]], touched: &mut [bool]) {
    for ((s, a), t) in row.iter().zip(acc.iter_mut()).zip(touched.iter_mut()) {
        if s[3] > 0.0 {
            over(a, *s);
            *t = true;
        }
    }
}

/// Multiplies the accumulator by the transmittance `t` (see the module documentation).
#[inline]
fn glaze(acc: &mut [f32; 4], t: Rgb) {
    let m = t[0].min(t[1]).min(t[2]);
    let open = 1.0 - acc[3];
    for i in 0..3 {
        acc[i] = acc[i] * t[i] + open * (t[i] - m);
    }
    acc[3] += open * (1.0 - m);
}

fn draw_stylized(layer: &StylizedLayer, y: usize, acc: &mut [[f32; 4]], base: &[BasePixel], touched: &mut [bool]) {
    let [x0, y0, x1, y1] = layer.bbox;
    if y < y0 || y >= y1 {
        return;
    }
    let bw = x1 - x0;
    let row = &layer.px[(y - y0) * bw..(y - y0 + 1) * bw];
    for (x, &p) in (x0..x1).zip(row) {
        if !p.on {
            continue;
        }
        touched[x] = true;
        let a = &mut acc[x];
        match layer.mode {
            Recolor::Glaze => {
                if p.amount <= 0.0 || p.opacity <= 0.0 {
                    continue;
                }
                let b = &base[x];
                let mut beta: f32 = 0.0;
                for i in 0..3 {
                    let room = 1.0 - b.base[i];
                    if p.color[i] > b.base[i] && room > 1e-6 {
                        beta = beta.max((p.color[i] - b.base[i]) / room);
                    }
                }
                let beta = beta.min(1.0);
                let ln_base = if beta > 0.0 {
                    let lifted = |i: usize| fast_ln(b.base[i] + beta * (1.0 - b.base[i]));
                    [lifted(0), lifted(1), lifted(2)]
                } else {
                    b.ln_base
                };
                // At partial opacity o the glazed layer is laid over what is below with alpha o,
                // as a flat layer is: T → 1 − o + o·T.
                let o = p.opacity;
                let t_at = |i: usize| 1.0 - o + o * fast_exp(p.amount * (p.ln[i] - ln_base[i]).min(0.0));
                let t = [t_at(0), t_at(1), t_at(2)];
                let lift = o * beta * p.amount.min(1.0);
                if lift > 0.0 {
                    let k = 1.0 - lift;
                    *a = [lift + k * a[0], lift + k * a[1], lift + k * a[2], lift + k * a[3]];
                }
                glaze(a, t);
            }
            Recolor::Over => {
                let o = (p.amount * (1.0 / OVER_OPAQUE_AMOUNT)).min(1.0) * p.opacity;
                if o <= 0.0 {
                    continue;
                }
                let s = p.amount.max(1.0);
                let c = if s == 1.0 {
                    p.color
                } else {
                    [fast_exp(s * p.ln[0]), fast_exp(s * p.ln[1]), fast_exp(s * p.ln[2])]
                };
                let k = 1.0 - o;
                *a = [o * c[0] + k * a[0], o * c[1] + k * a[1], o * c[2] + k * a[2], o + k * a[3]];
            }
            Recolor::None if p.opacity < 1.0 => glaze(a, p.color.map(|t| 1.0 - p.opacity + p.opacity * t)),
            Recolor::None => glaze(a, p.color),
        }
    }
}

#[cfg(test)]
mod tests;
