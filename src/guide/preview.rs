//! Pictures of the guides, so a user can see what the synthesis will be guided by.
//!
//! * **flow**: hue = direction (paper Fig. 4b): red → +x (right), yellow-green → +y (down),
//!   cyan → −x (left), blue-violet → −y (up), i.e. hue = `dir` measured clockwise on screen;
//!   brightness = `|flow| / flow_scale`, clamped to 1; black where there is no motion.
//! * **ext+ / ext−**: grayscale `ext / ext_scale`, clamped to 1; both use the same scale so they
//!   can be compared.
//! * **border**: the border channel `df = min(dist / b, 1)` clamped to `0..=1`: black outside the
//!   mask, a ramp across the border segment, white in the interior.
//!
//! A scale left as `None` in [`PreviewOptions`] is the frame's own maximum (so every frame uses
//! the full range; pass fixed scales to compare frames). The scales used are returned.

use super::FrameGuides;
use crate::error::Result;
use crate::img::{Plane, Rgb, save_gray, save_rgb};
use glam::Vec2;
use std::path::Path;

/// How the previews are drawn: `PreviewOptions::default().border_width(5.0)`.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct PreviewOptions {
    /// Border width `b` of the border channel, pixels. Default: 10 (thesis `--border-width`).
    pub border_width: f32,
    /// Flow magnitude drawn at full brightness, pixels per frame. Default: `None` (the frame's
    /// largest).
    pub flow_scale: Option<f32>,
    /// Extent drawn white, pixels. Default: `None` (the frame's largest `ext+` or `ext−`).
    pub ext_scale: Option<f32>,
}

impl Default for PreviewOptions {
    fn default() -> Self {
        PreviewOptions { border_width: 10.0, flow_scale: None, ext_scale: None }
    }
}

impl PreviewOptions {
    /// Sets [`PreviewOptions::border_width`]. Default: 10.
    pub fn border_width(mut self, b: f32) -> Self {
        self.border_width = b;
        self
    }

    /// Sets [`PreviewOptions::flow_scale`]. Default: the frame's largest flow.
    pub fn flow_scale(mut self, scale: f32) -> Self {
        self.flow_scale = Some(scale);
        self
    }

    /// Sets [`PreviewOptions::ext_scale`]. Default: the frame's largest extent.
    pub fn ext_scale(mut self, scale: f32) -> Self {
        self.ext_scale = Some(scale);
        self
    }
}

/// The scales a preview was drawn with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreviewScales {
    /// Flow magnitude at full brightness, pixels per frame.
    pub flow: f32,
    /// Extent drawn white, pixels.
    pub ext: f32,
}

/// The scales `opts` asks for, with `None` replaced by the frame's maxima (1 when those are 0).
pub fn scales(g: &FrameGuides, opts: &PreviewOptions) -> PreviewScales {
    let positive = |v: f32| if v > 0.0 && v.is_finite() { v } else { 1.0 };
    let flow = opts.flow_scale.unwrap_or_else(|| g.flow.data().iter().map(|f| f.length()).fold(0.0, f32::max));
    let ext =
        opts.ext_scale.unwrap_or_else(|| g.ext_pos.data().iter().chain(g.ext_neg.data()).copied().fold(0.0, f32::max));
    PreviewScales { flow: positive(flow), ext: positive(ext) }
}

/// The flow as color: hue = angle, value = magnitude / `scale`.
pub fn flow_image(flow: &Plane<Vec2>, scale: f32) -> Plane<Rgb> {
    flow.map(|f| {
        let v = (f.length() / scale).clamp(0.0, 1.0);
        let hue = (f.y.atan2(f.x) / std::f32::consts::TAU).rem_euclid(1.0) * 6.0;
        let x = 1.0 - (hue % 2.0 - 1.0).abs();
        let (r, g, b) = match hue as u32 {
            0 => (1.0, x, 0.0),
            1 => (x, 1.0, 0.0),
            2 => (0.0, 1.0, x),
            3 => (0.0, x, 1.0),
            4 => (x, 0.0, 1.0),
            _ => (1.0, 0.0, x),
        };
        [r * v, g * v, b * v]
    })
}

/// A channel as gray: `value / scale`, clamped to `0..=1`.
pub fn gray_image(values: &Plane<f32>, scale: f32) -> Plane<f32> {
    values.map(|v| (v / scale).clamp(0.0, 1.0))
}

/// The border channel for border width `b`, clamped to `0..=1`.
pub fn border_image(g: &FrameGuides, border_width: f32) -> Plane<f32> {
    g.df(border_width).map(|v| v.clamp(0.0, 1.0))
}

/// Writes `flow_NNNN.png`, `ext_pos_NNNN.png`, `ext_neg_NNNN.png` and `border_NNNN.png`
/// (`NNNN` = `frame`, 4 digits) into `dir`, which must exist; returns the scales used.
pub fn write_previews(g: &FrameGuides, dir: &Path, frame: usize, opts: &PreviewOptions) -> Result<PreviewScales> {
    let s = scales(g, opts);
    save_rgb(&dir.join(format!("flow_{frame:04}.png")), &flow_image(&g.flow, s.flow))?;
    save_gray(&dir.join(format!("ext_pos_{frame:04}.png")), &gray_image(&g.ext_pos, s.ext))?;
    save_gray(&dir.join(format!("ext_neg_{frame:04}.png")), &gray_image(&g.ext_neg, s.ext))?;
    save_gray(&dir.join(format!("border_{frame:04}.png")), &border_image(g, opts.border_width))?;
    Ok(s)
}

/// The four previews side by side (flow | ext+ | ext− | border) with 2-pixel gaps, as one RGB
/// image: handy for documentation.
pub fn montage(g: &FrameGuides, opts: &PreviewOptions) -> (Plane<Rgb>, PreviewScales) {
    let s = scales(g, opts);
    let (w, h) = g.size();
    let gap = 2;
    let gray = |p: Plane<f32>| p.map(|v| [v, v, v]);
    let panels = [
        flow_image(&g.flow, s.flow),
        gray(gray_image(&g.ext_pos, s.ext)),
        gray(gray_image(&g.ext_neg, s.ext)),
        gray(border_image(g, opts.border_width)),
    ];
    let mut out = Plane::filled(4 * w + 3 * gap, h, [0.5, 0.5, 0.5]);
    for (k, p) in panels.iter().enumerate() {
        for y in 0..h {
            for x in 0..w {
                out.set(k * (w + gap) + x, y, p.get(x, y));
            }
        }
    }
    (out, s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hue_and_brightness() {
        let f = Plane::from_vec(4, 1, vec![Vec2::new(2.0, 0.0), Vec2::new(0.0, 1.0), Vec2::new(-1.0, 0.0), Vec2::ZERO])
            .unwrap();
        let img = flow_image(&f, 2.0);
        assert_eq!(img.get(0, 0), [1.0, 0.0, 0.0]);
        let down = img.get(1, 0);
        assert!(down[1] > 0.49 && down[2] < 0.01, "{down:?}");
        let left = img.get(2, 0);
        assert!(left[0] < 0.01 && (left[1] - 0.5).abs() < 0.01 && (left[2] - 0.5).abs() < 0.01, "{left:?}");
        assert_eq!(img.get(3, 0), [0.0, 0.0, 0.0]);
    }
}
