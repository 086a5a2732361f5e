//! Guidance channels (thesis §3.4–3.8, §4.1; paper Appendix A), computed by the same code for
//! the exemplar sequence S and the target sequence T:
//!
//! * mask pre-processing: Gaussian blur (σ = `blur_sigma`) and a threshold below 0.5
//!   ([`preprocess_mask`]);
//! * the signed distance field `I^dist` (positive inside; [`sdf()`]);
//! * the border channel `I^df = min(I^dist / b, 1)` ([`FrameGuides::df`]) and the
//!   border/interior segmentation ([`FrameGuides::segments`]);
//! * the flow field `I^flow` (boundary values from distance-field differences, diffused into
//!   the interior by a multigrid Laplace solve, smoothed in time; [`flow`], [`laplace`]), or
//!   user-supplied flow fields ([`compute_sequence_with_flow`], [`flo`]);
//! * motion extent `I^ext+` / `I^ext−` (norms of the 2D flow accumulated forward / backward in
//!   time, reset outside the mask; [`extent`]);
//! * direction `I^dir = atan2(I^flow)` ([`FrameGuides::dir`]);
//! * pictures of all of them ([`preview`]).
//!
//! Two entry points: [`compute_sequence`] holds a whole (short) sequence in memory, as for an
//! exemplar; [`GuideStream`] yields the guides of a long target frame by frame in bounded
//! memory. Both give bit-identical results, independent of the number of threads.
//!
//! # Conventions
//!
//! * **Distance**: pixel centres at integer coordinates; `dist = ±(distance to the nearest pixel
//!   of the other set − ½)`, so the rim pixels are at ±½ and the zero level lies on the pixel
//!   edges. An empty or full mask has `dist = ∓`/`±` the image diagonal everywhere.
//! * **Boundary pixels**: mask pixels with a 4-neighbour inside the image that is not in the
//!   mask; the image edge is not a boundary (the flow has a zero normal derivative there).
//! * **Flow**: `flow(i)` is the motion from frame `i` to `i + 1` on the mask of frame `i`, so the
//!   paper's `acc+(i) = acc+(i−1) + flow(i−1)` and `acc−(i) = acc−(i+1) + flow(i)` hold as
//!   written. Appendix A's sign is flipped for a positive-inside distance (see [`flow`]).
//! * **Laplace tolerance**: the solve stops when every interior pixel is within
//!   `laplace_tolerance · max |boundary flow|` (10⁻⁴) of its neighbours' mean ([`laplace`]).
//! * **Ends**: frames beyond the sequence, or beyond a run of non-empty masks, are replaced by
//!   the nearest frame of the run in the temporal filters; `acc+` starts at 0 on the first frame,
//!   `acc−` is 0 on the last.
//!
//! All lengths (distances, flow, extents) are in pixels of the sequence the guides were
//! computed on; [`FrameGuides::downsample2`] keeps them in those full-resolution units.

mod crop;
pub mod extent;
pub mod flo;
pub mod flow;
pub mod laplace;
mod preprocess;
pub mod preview;
pub mod sdf;
mod stream;

pub use extent::{ExtentHistogram, compute_sequence, compute_sequence_with_flow, extent_scale};
pub use preprocess::preprocess_mask;
pub use sdf::sdf;
pub(crate) use sdf::{deepest_inside, stretched_depths};
pub use stream::{GuideStream, GuideStreamBuilder};

use crate::error::{Error, Result};
use crate::img::{Mask, Plane};
use glam::Vec2;

/// Parameters of guide computation: `GuideParams::default().blur_sigma(2.0)`.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct GuideParams {
    /// σ of the Gaussian blur applied to masks before thresholding (`--blur-sigma`), pixels.
    /// Default: 0 (no blur; the thesis uses 8). The thesis blurs hand-drawn bitmap masks to
    /// smooth them; our masks are anti-aliased rasterizations, already smooth, and the blur
    /// rounds corners, fills concavities and moves the edge the distance guide measures from,
    /// so the exemplar's dark rim lands off the target's edge. Measured with `quality` (blue-bloom,
    /// ink-rims, yellow-granules × growing, translating, 24 frames, 512²): edge darkening
    /// 0.28–0.78 with σ = 8, 0.45–0.80 with σ = 1, 0.52–0.86 with σ = 0; coverage IoU of the
    /// alpha 0.92 → 0.99; incoherent change 1.12–1.63 → 1.01–1.55.
    pub blur_sigma: f32,
    /// Threshold applied to the blurred mask; below 0.5 so the mask takes in a little paper.
    /// Default: 0.3.
    pub mask_threshold: f32,
    /// σ of the temporal Gaussian applied to distance fields before the flow is estimated
    /// (`--time-blur-sigma`), frames. Default: 2 (thesis).
    pub time_blur_sigma: f32,
    /// Radius, in frames, of the temporal Gaussian applied to the flow sequence (σ = radius / 3),
    /// centred half a frame ahead (see [`flow`], step 5; 0 is taken as 1, the mean of the
    /// velocities of the frame and the next). Default: 3 (paper, Appendix A).
    pub flow_time_radius: usize,
    /// Completes the boundary flow with a tangential component from an affine motion fitted to
    /// each connected part of the mask (see [`flow`]); `false` keeps the paper's purely normal
    /// boundary flow. Default: true.
    pub tangential_fit: bool,
    /// Tolerance of the Laplace solve (scaled residual relative to the largest boundary flow, see
    /// [`laplace`]). Default: [`laplace::TOLERANCE`] (10⁻⁴).
    pub laplace_tolerance: f32,
}

impl Default for GuideParams {
    fn default() -> Self {
        GuideParams {
            blur_sigma: 0.0,
            mask_threshold: 0.3,
            time_blur_sigma: 2.0,
            flow_time_radius: 3,
            tangential_fit: true,
            laplace_tolerance: laplace::TOLERANCE,
        }
    }
}

impl GuideParams {
    /// Sets [`GuideParams::blur_sigma`], pixels, in `0..=100`. Default: 0.
    pub fn blur_sigma(mut self, sigma: f32) -> Self {
        self.blur_sigma = sigma;
        self
    }

    /// Sets [`GuideParams::mask_threshold`], in `(0, 1]`. Default: 0.3.
    pub fn mask_threshold(mut self, threshold: f32) -> Self {
        self.mask_threshold = threshold;
        self
    }

    /// Sets [`GuideParams::time_blur_sigma`], frames, in `0..=20`. Default: 2.
    pub fn time_blur_sigma(mut self, sigma: f32) -> Self {
        self.time_blur_sigma = sigma;
        self
    }

    /// Sets [`GuideParams::flow_time_radius`], frames, in `0..=60`. Default: 3.
    pub fn flow_time_radius(mut self, radius: usize) -> Self {
        self.flow_time_radius = radius;
        self
    }

    /// Sets [`GuideParams::tangential_fit`]. Default: true.
    pub fn tangential_fit(mut self, yes: bool) -> Self {
        self.tangential_fit = yes;
        self
    }

    /// Sets [`GuideParams::laplace_tolerance`], in `(0, 0.1]`. Default: 10⁻⁴.
    pub fn laplace_tolerance(mut self, tolerance: f32) -> Self {
        self.laplace_tolerance = tolerance;
        self
    }

    /// Checks every value's range.
    pub fn validate(&self) -> Result<()> {
        let check = |name: &str, v: f32, lo: f32, hi: f32, lo_open: bool, allowed: &str| {
            let ok = v.is_finite() && (if lo_open { v > lo } else { v >= lo }) && v <= hi;
            if ok { Ok(()) } else { Err(Error::param(name, v, allowed)) }
        };
        check("blur-sigma", self.blur_sigma, 0.0, 100.0, false, "a number of pixels from 0 to 100")?;
        check("mask-threshold", self.mask_threshold, 0.0, 1.0, true, "a number greater than 0 and at most 1")?;
        check("time-blur-sigma", self.time_blur_sigma, 0.0, 20.0, false, "a number of frames from 0 to 20")?;
        check("laplace-tolerance", self.laplace_tolerance, 0.0, 0.1, true, "a number greater than 0 and at most 0.1")?;
        if self.flow_time_radius > 60 {
            return Err(Error::param("flow-time-radius", self.flow_time_radius, "a number of frames from 0 to 60"));
        }
        Ok(())
    }

    /// A stable text key of every parameter, for caches of computed guides. Its version
    /// (`guides-vN`) must change whenever the guides computed from the same masks change:
    /// the cache key holds no version of the computation otherwise, and an exemplar's guides
    /// cached by an earlier release would be read beside a target's computed by this one
    /// (measured with a changed flow estimate: the identity's worst frame fell from 33.5–100 dB
    /// to 23–37 dB until the version changed). v4: the flow's speeds divided by the smoothed
    /// field's slope, its unobserved modes fitted rigid. v6: the flow's temporal windows read
    /// only real frames, the last frame's velocity measured backwards.
    pub fn fingerprint(&self) -> String {
        format!(
            "guides-v6 blur={} thr={} tblur={} frad={} tan={} tol={}",
            self.blur_sigma,
            self.mask_threshold,
            self.time_blur_sigma,
            self.flow_time_radius,
            self.tangential_fit,
            self.laplace_tolerance
        )
    }
}

/// The guidance channels of one frame `i`, as planar images of the frame's size (or of a pyramid
/// level, see [`FrameGuides::downsample2`]).
#[derive(Clone, Debug, PartialEq)]
pub struct FrameGuides {
    /// The pre-processed binary mask `I_i^mask`.
    pub mask: Mask,
    /// Signed distance to the mask boundary `I_i^dist`, positive inside, pixels (convention in
    /// [`sdf`](mod@sdf): ±½ at the rim pixels; ± the image diagonal when the mask is empty or full).
    pub dist: Plane<f32>,
    /// Flow field `I_i^flow`: the motion from this frame to the next (`i → i+1`), pixels per
    /// frame, inside the mask; zero outside. See [`flow`] for why this convention.
    pub flow: Plane<Vec2>,
    /// Forward motion extent `I_i^ext+ = ‖acc+(i)‖`, pixels: how far the material here has moved
    /// since it appeared. Zero outside the mask.
    pub ext_pos: Plane<f32>,
    /// Backward motion extent `I_i^ext− = ‖acc−(i)‖`, pixels: how far it will still move until it
    /// disappears or the sequence ends. Zero outside the mask.
    pub ext_neg: Plane<f32>,
}

/// The segment of a pixel (thesis §3.4): patches only match within the same segment.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[repr(u8)]
pub enum Segment {
    /// Not in the mask.
    #[default]
    Outside,
    /// In the mask, closer than the border width to its edge: `I^df < 1`.
    Border,
    /// In the mask, at least the border width from its edge: `I^df = 1`.
    Interior,
}

impl FrameGuides {
    /// `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        self.mask.size()
    }

    /// The border channel `I^df = min(I^dist / b, 1)` for border width `b` pixels (full-resolution
    /// units at every pyramid level). Below 0 outside the mask, in `(0, 1)` in the border
    /// segment, 1 in the interior. A `b` that is not positive is taken as the smallest positive
    /// number (every mask pixel is interior).
    pub fn df(&self, border_width: f32) -> Plane<f32> {
        let b = border_width_or_min(border_width);
        self.dist.map(|d| (d / b).min(1.0))
    }

    /// The border/interior segmentation for border width `b`: [`Segment::Border`] where the mask
    /// has `I^df < 1`, [`Segment::Interior`] where `I^df = 1`, [`Segment::Outside`] elsewhere.
    pub fn segments(&self, border_width: f32) -> Plane<Segment> {
        let b = border_width_or_min(border_width);
        let (w, h) = self.size();
        Plane::from_fn(w, h, |x, y| match (self.mask.get(x, y), self.dist.get(x, y) / b >= 1.0) {
            (false, _) => Segment::Outside,
            (true, false) => Segment::Border,
            (true, true) => Segment::Interior,
        })
    }

    /// The direction channel `I^dir = atan2(flow.y, flow.x)`, radians in `(−π, π]`, measured from
    /// the +x axis towards +y (image rows grow downwards, so positive angles turn clockwise on
    /// screen). Zero flow gives 0: where `|flow|` is tiny the angle is noise, see DESIGN.md.
    pub fn dir(&self) -> Plane<f32> {
        self.flow.map(|f| f.y.atan2(f.x))
    }

    /// One step of the synthesis pyramid: half resolution, the size rounding up, pixel `(x, y)`
    /// covering `(2x..2x+2, 2y..2y+2)` (edges clamped as in [`crate::img::downsample2`]). Values
    /// stay in full-resolution units, so source and target guides remain comparable at every
    /// level. The mask is "at least half of the four pixels in the mask"; `dist` is the plain
    /// average; `flow`, `ext+` and `ext−` are averaged over the pixels that are in the mask (they
    /// are zero outside it), and zero where none is.
    pub fn downsample2(&self) -> FrameGuides {
        let (w, h) = self.size();
        let (w2, h2) = (w.div_ceil(2), h.div_ceil(2));
        let mut mask = Plane::new(w2, h2);
        let mut flow = Plane::new(w2, h2);
        let mut ext_pos = Plane::new(w2, h2);
        let mut ext_neg = Plane::new(w2, h2);
        for y in 0..h2 {
            for x in 0..w2 {
                let (x0, y0) = (2 * x, 2 * y);
                let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
                let (mut n, mut f, mut ep, mut en) = (0u32, Vec2::ZERO, 0f32, 0f32);
                for (px, py) in [(x0, y0), (x1, y0), (x0, y1), (x1, y1)] {
                    if self.mask.get(px, py) {
                        n += 1;
                        f += self.flow.get(px, py);
                        ep += self.ext_pos.get(px, py);
                        en += self.ext_neg.get(px, py);
                    }
                }
                mask.set(x, y, n >= 2);
                if n > 0 {
                    let inv = 1.0 / n as f32;
                    flow.set(x, y, f * inv);
                    ext_pos.set(x, y, ep * inv);
                    ext_neg.set(x, y, en * inv);
                }
            }
        }
        FrameGuides { mask, dist: crate::img::downsample2(&self.dist), flow, ext_pos, ext_neg }
    }

    /// Checks that every channel has the mask's size (and that it is not empty), as every
    /// consumer of guides assumes; `what` names the guides in the error.
    pub fn check(&self, what: &str) -> Result<()> {
        let size = self.mask.size();
        let sizes = [
            ("dist", self.dist.size()),
            ("flow", self.flow.size()),
            ("ext_pos", self.ext_pos.size()),
            ("ext_neg", self.ext_neg.size()),
        ];
        match sizes.iter().find(|(_, s)| *s != size) {
            Some((name, s)) => Err(Error::param(
                what,
                format!("mask {}x{}, {name} {}x{}", size.0, size.1, s.0, s.1),
                "every channel of the size of the mask",
            )),
            None if size.0 == 0 || size.1 == 0 => Err(Error::param(what, "0 pixels", "at least 1x1 pixels")),
            None => Ok(()),
        }
    }

    /// `levels` pyramid levels, finest (this frame's resolution) first; `levels = 0` gives none.
    pub fn pyramid(&self, levels: usize) -> Vec<FrameGuides> {
        let mut out: Vec<FrameGuides> = Vec::with_capacity(levels);
        for l in 0..levels {
            let next = if l == 0 { self.clone() } else { out[l - 1].downsample2() };
            out.push(next);
        }
        out
    }
}

fn border_width_or_min(b: f32) -> f32 {
    if b > 0.0 { b } else { f32::MIN_POSITIVE }
}
