//! What the layers are composited over.

use crate::error::{Error, Result};
use crate::img::{self, Plane, Rgba};
use std::path::Path;

/// The background of the composite.
#[derive(Clone, Debug, PartialEq)]
pub enum Background {
    /// A uniform color, straight sRGB RGBA in `0..=1` (usually opaque).
    Color(Rgba),
    /// Nothing: the output's alpha comes from the layers' coverage.
    Transparent,
    /// An image of exactly the canvas size, straight sRGB RGBA (e.g. a paper texture); see
    /// [`Background::load_image`].
    Image(Plane<Rgba>),
}

/// White paper, the background when the animation has none of its own.
pub const WHITE: Rgba = [1.0, 1.0, 1.0, 1.0];

impl Default for Background {
    fn default() -> Self {
        Background::Color(WHITE)
    }
}

impl Background {
    /// The animation's own background (its bottom full-canvas solid) or, when it has none,
    /// white paper.
    pub fn from_animation(background: Option<&crate::anim::Background>) -> Background {
        Background::Color(background.map(|b| b.color).unwrap_or(WHITE))
    }

    /// Loads an image file (PNG or JPEG) as background, scaled to *cover* the
    /// `width × height` canvas (aspect ratio kept, centered, the excess cropped; scaling is
    /// bilinear on premultiplied colors). Fails with an [`Error::Image`] naming the file.
    pub fn load_image(path: &Path, width: usize, height: usize) -> Result<Background> {
        let fail = |message: String| Error::image(path, format!("cannot use it as background: {message}"));
        if width == 0 || height == 0 {
            return Err(fail(format!("the canvas is {width}x{height}")));
        }
        let src = img::load_rgba(path).map_err(|e| match e {
            Error::Io { source, .. } => fail(source.to_string()),
            Error::Image { message, .. } => fail(message),
            other => other,
        })?;
        if src.is_empty() {
            return Err(fail("the image has no pixels".to_string()));
        }
        let enlarged = (width as f32 / src.width() as f32).max(height as f32 / src.height() as f32);
        if enlarged > 2.0 {
            log::warn!(
                "'{}': the background image ({}x{}) is enlarged {enlarged:.1}x to cover the {width}x{height} canvas; \
                 it will look blurred",
                path.display(),
                src.width(),
                src.height()
            );
        }
        Ok(Background::Image(cover(&src, width, height)))
    }

    /// The straight sRGB RGBA background at `(x, y)`.
    #[inline]
    pub fn pixel(&self, x: usize, y: usize) -> Rgba {
        match self {
            Background::Color(c) => *c,
            Background::Transparent => [0.0; 4],
            Background::Image(p) => p.get(x, y),
        }
    }

    /// The size this background needs, if it has one (images).
    pub fn size(&self) -> Option<(usize, usize)> {
        match self {
            Background::Image(p) => Some(p.size()),
            _ => None,
        }
    }
}

/// Scales `src` to cover `width × height`, cropping the excess symmetrically.
fn cover(src: &Plane<Rgba>, width: usize, height: usize) -> Plane<Rgba> {
    let (sw, sh) = src.size();
    // Largest centered crop of the canvas's aspect ratio.
    let (cw, ch) = if sw as f64 * height as f64 > sh as f64 * width as f64 {
        (((sh as f64 * width as f64 / height as f64).round() as usize).clamp(1, sw), sh)
    } else {
        (sw, ((sw as f64 * height as f64 / width as f64).round() as usize).clamp(1, sh))
    };
    let (ox, oy) = ((sw - cw) / 2, (sh - ch) / 2);
    let premultiplied = Plane::from_fn(cw, ch, |x, y| {
        let c = src.get(x + ox, y + oy);
        [c[0] * c[3], c[1] * c[3], c[2] * c[3], c[3]]
    });
    img::resize_bilinear(&premultiplied, width, height).map(|c| {
        if c[3] > 1e-6 {
            [(c[0] / c[3]).min(1.0), (c[1] / c[3]).min(1.0), (c[2] / c[3]).min(1.0), c[3].min(1.0)]
        } else {
            [0.0; 4]
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cover_crops_to_aspect() {
        // 4x2 source, left half black, right half white; a 2x2 canvas sees the middle.
        let src = Plane::from_fn(4, 2, |x, _| if x < 2 { [0.0, 0.0, 0.0, 1.0] } else { [1.0; 4] });
        let out = cover(&src, 2, 2);
        assert_eq!(out.size(), (2, 2));
        assert_eq!(out.get(0, 0), [0.0, 0.0, 0.0, 1.0]);
        assert_eq!(out.get(1, 1), [1.0; 4]);
        let tall = cover(&src, 1, 4);
        assert_eq!(tall.size(), (1, 4));
    }
}
