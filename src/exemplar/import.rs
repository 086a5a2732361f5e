//! Importing real footage: a PNG/JPEG frame sequence of paint spreading on paper becomes an
//! exemplar (frames, masks, metadata).
//!
//! 1. **crop and rescale** every frame (optional);
//! 2. **paper color**: the pixels of a thin ring along the frame edges (all frames), of which
//!    the brightest 40 % by luminance are taken as bare paper; their per-channel median is
//!    the paper color (robust to paint reaching the edge and to dark vignetting);
//! 3. **paint measure** per pixel: the optical density relative to paper,
//!    `max_c max(0, −ln(I_c / paper_c))` (the channel the pigment absorbs most), blurred with
//!    σ = 1 px to calm the paper grain;
//! 4. **threshold**, chosen automatically: Otsu's threshold over the measure of all frames
//!    gives confident paint; it is then grown (hysteresis) into connected pixels whose
//!    unblurred measure is above a low threshold, the paper's own noise level (median + 4 ×
//!    MAD of the edge ring's unblurred measure), so faint, feathered fronts stay attached to
//!    the paint while the blur does not widen dark rims;
//! 5. **clean-up**: a 3×3-majority-like smoothing (blur σ = 1, threshold ½), then specks
//!    (components smaller than `min_area`) removed and equally small holes filled;
//! 6. **painted holes**: a hole enclosed by paint that was mostly paint in the previous frame
//!    is filled, whatever its size: paint does not withdraw from paper it has covered, and a
//!    pale wash inside it is paint, though on filmed footage noise, JPEG and uneven light push
//!    a bloom's pale middle below the paper's noise level. A hole that was paper in the
//!    previous frame too (a ring of paint, a dry island) stays.
//!
//! A frame in which no paint is found is an error naming the file.

use super::{Exemplar, ExemplarMeta};
use crate::error::{Error, Result};
use crate::img::{self, Plane, Rgb};
use crate::progress::Progress;
use std::path::{Path, PathBuf};

/// Options of [`import`]: `ImportOptions::default().name("swatch").scale(0.5)`.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct ImportOptions {
    /// The exemplar's name. Default: `imported`.
    pub name: String,
    /// Crop rectangle `[x, y, width, height]` in source pixels, applied first. Default: none.
    pub crop: Option<[usize; 4]>,
    /// Scale applied after cropping (0.5 = half size). Default: 1. Range: 0.02–4.
    pub scale: f32,
    /// Frame rate of the footage. Default: 24.
    pub fps: f32,
    /// A fixed threshold on the paint measure instead of the automatic one. Default: none.
    pub threshold: Option<f32>,
    /// Components (and holes) smaller than this many pixels are removed (filled). Default:
    /// none, meaning 0.05 % of the frame area but at least 12 px.
    pub min_area: Option<usize>,
    /// Description for the metadata. Default: empty (one is made up).
    pub description: String,
    /// License of the footage. Default: `unknown`.
    pub license: String,
}

impl Default for ImportOptions {
    fn default() -> Self {
        ImportOptions {
            name: "imported".into(),
            crop: None,
            scale: 1.0,
            fps: 24.0,
            threshold: None,
            min_area: None,
            description: String::new(),
            license: "unknown".into(),
        }
    }
}

impl ImportOptions {
    /// Sets [`ImportOptions::name`]. Default: `imported`.
    pub fn name(mut self, name: impl Into<String>) -> Self {
        self.name = name.into();
        self
    }

    /// Sets [`ImportOptions::crop`], `[x, y, width, height]`. Default: none.
    pub fn crop(mut self, rect: [usize; 4]) -> Self {
        self.crop = Some(rect);
        self
    }

    /// Sets [`ImportOptions::scale`]. Default: 1.
    pub fn scale(mut self, scale: f32) -> Self {
        self.scale = scale;
        self
    }

    /// Sets [`ImportOptions::fps`]. Default: 24.
    pub fn fps(mut self, fps: f32) -> Self {
        self.fps = fps;
        self
    }

    /// Sets [`ImportOptions::threshold`]. Default: automatic.
    pub fn threshold(mut self, threshold: f32) -> Self {
        self.threshold = Some(threshold);
        self
    }

    /// Sets [`ImportOptions::min_area`]. Default: 0.05 % of the frame area, at least 12 px.
    pub fn min_area(mut self, pixels: usize) -> Self {
        self.min_area = Some(pixels);
        self
    }

    /// Sets [`ImportOptions::description`]. Default: one is made up.
    pub fn description(mut self, text: impl Into<String>) -> Self {
        self.description = text.into();
        self
    }

    /// Sets [`ImportOptions::license`]. Default: `unknown`.
    pub fn license(mut self, license: impl Into<String>) -> Self {
        self.license = license.into();
        self
    }
}

/// What the mask extraction decided, for reporting.
#[derive(Clone, Debug, PartialEq)]
pub struct MaskReport {
    /// The estimated paper color.
    pub paper: Rgb,
    /// The high (Otsu) threshold on the paint measure.
    pub high: f32,
    /// The low (paper noise) threshold the masks were grown into.
    pub low: f32,
}

/// Imports the frame sequence `src` (a folder or a glob of PNG/JPEG files, natural order), or
/// one image: a still exemplar ([`is_still_image`]). Reports progress per frame read (stage
/// `"reading"`).
pub fn import(src: &Path, opts: &ImportOptions, progress: &dyn Progress) -> Result<Exemplar> {
    super::validate_name(&opts.name)?;
    let files =
        if is_still_image(src) { vec![src.to_path_buf()] } else { crate::seq::list_sequence(src, &IMAGE_EXTENSIONS)? };
    if files.is_empty() {
        return Err(Error::exemplar(src, "found no PNG or JPEG frame"));
    }
    if files.len() > super::MAX_FRAMES {
        return Err(Error::Limit {
            path: src.to_path_buf(),
            what: "frame count".into(),
            value: files.len() as f64,
            limit: super::MAX_FRAMES as f64,
        });
    }
    let mut frames = Vec::with_capacity(files.len());
    for (i, f) in files.iter().enumerate() {
        let frame = prepare(img::load_rgb(f)?, f, opts)?;
        if let Some(first) = frames.first().map(|p: &Plane<Rgb>| p.size())
            && first != frame.size()
        {
            return Err(Error::SizeMismatch {
                path: f.clone(),
                expected: (first.0 as u32, first.1 as u32),
                found: (frame.width() as u32, frame.height() as u32),
            });
        }
        frames.push(frame);
        if !progress.update("reading", i + 1, files.len()) {
            return Err(Error::Cancelled);
        }
    }
    let mut ex = from_frames(frames, &files, opts)?;
    ex.meta.origin = format!("imported from '{}'", src.display());
    Ok(ex)
}

/// The image files an exemplar can be imported from.
const IMAGE_EXTENSIONS: [&str; 3] = ["png", "jpg", "jpeg"];

/// True when `path` is one image file (PNG or JPEG): a still exemplar — one painted image, a
/// scanned swatch of paint on paper — rather than a frame sequence.
pub fn is_still_image(path: &Path) -> bool {
    path.is_file() && path.extension().is_some_and(|e| IMAGE_EXTENSIONS.iter().any(|x| e.eq_ignore_ascii_case(x)))
}

/// Imports one image as a still exemplar with the default options, named after the file (its
/// stem, with characters a name cannot hold replaced by `-`): what `--exemplar swatch.png` and
/// `--style LAYER=swatch.png` load. Its paper color is keyed out into its mask as for footage.
pub fn still(path: &Path) -> Result<Exemplar> {
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let mut name: String = stem
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') { c } else { '-' })
        .take(64)
        .collect();
    if name.is_empty() || name.starts_with(['.', '-']) {
        name.insert_str(0, "still");
        name.truncate(64);
    }
    let opts = ImportOptions { name, description: "a still image of paint".into(), ..ImportOptions::default() };
    import(path, &opts, &crate::progress::NoProgress)
}

/// Crops and rescales one frame; `path` names it in errors.
fn prepare(mut rgb: Plane<Rgb>, path: &Path, opts: &ImportOptions) -> Result<Plane<Rgb>> {
    if let Some([x, y, w, h]) = opts.crop {
        let (iw, ih) = rgb.size();
        if w == 0 || h == 0 || x.saturating_add(w) > iw || y.saturating_add(h) > ih {
            return Err(Error::param(
                "crop",
                format!("{x},{y},{w},{h}"),
                format!("a non-empty rectangle inside the {iw}x{ih} frame '{}'", path.display()),
            ));
        }
        rgb = Plane::from_fn(w, h, |cx, cy| rgb.get(x + cx, y + cy));
    }
    if !(opts.scale.is_finite() && (0.02..=4.0).contains(&opts.scale)) {
        return Err(Error::param("scale", opts.scale, "0.02–4"));
    }
    if opts.scale != 1.0 {
        let nw = (rgb.width() as f32 * opts.scale).round() as usize;
        let nh = (rgb.height() as f32 * opts.scale).round() as usize;
        if nw < 8 || nh < 8 || nw > super::MAX_SIDE || nh > super::MAX_SIDE {
            return Err(Error::param(
                "scale",
                opts.scale,
                format!("a scale giving 8–{} px per side (it gives {nw}x{nh})", super::MAX_SIDE),
            ));
        }
        rgb = img::resize_bilinear(&rgb, nw, nh);
    }
    if rgb.width() > super::MAX_SIDE || rgb.height() > super::MAX_SIDE {
        return Err(Error::Limit {
            path: path.to_path_buf(),
            what: "frame side (use --crop or --scale)".into(),
            value: rgb.width().max(rgb.height()) as f64,
            limit: super::MAX_SIDE as f64,
        });
    }
    Ok(rgb)
}

/// Builds an exemplar from already prepared frames (`files` name them in errors; may be
/// empty for in-memory frames): paper color, masks, metadata, border width.
pub fn from_frames(frames: Vec<Plane<Rgb>>, files: &[PathBuf], opts: &ImportOptions) -> Result<Exemplar> {
    if !(opts.fps.is_finite() && (0.01..=1000.0).contains(&opts.fps)) {
        return Err(Error::param("fps", opts.fps, "0.01–1000"));
    }
    let label = |i: usize| files.get(i).cloned().unwrap_or_else(|| PathBuf::from(format!("frame {}", i + 1)));
    let (masks, report) = extract_masks(&frames, opts).map_err(|e| match e {
        // Named by the first frame: the paper is estimated from all of them.
        Error::InvalidParam { name, value, allowed } if name == "paper" => {
            Error::Exemplar { path: label(0), message: format!("no bare paper found: {value}; expected {allowed}") }
        }
        other => other,
    })?;
    for (i, m) in masks.iter().enumerate() {
        if !m.data().iter().any(|&v| v >= 0.5) {
            return Err(Error::Exemplar {
                path: label(i),
                message: format!(
                    "no paint found (paper {}, threshold {:.3}); try --threshold or --crop",
                    super::hex_color(report.paper),
                    report.low
                ),
            });
        }
    }
    let edges: Vec<[bool; 4]> = masks.iter().map(cut_edges).collect();
    if let Some(first) = edges.iter().position(|e| e.contains(&true)) {
        let cut = side_names(edges.iter().copied());
        let frames = if masks.len() > 1 { " (in this frame first)" } else { "" };
        log::warn!(
            "'{}': the paint reaches the image's {} edge{frames}: paint cut by the image's edge is missing \
             that part of its outline and rim, and paint within 3 px of the image's edge is never matched (at \
             the coarse levels, within 3 px of theirs); crop with a margin of bare paper around the paint",
            label(first).display(),
            cut.join(" and ")
        );
    }
    let pigment = pigment_color(frames.last(), masks.last(), report.paper);
    let mut ex = Exemplar {
        dir: None,
        meta: ExemplarMeta {
            name: opts.name.clone(),
            description: if opts.description.is_empty() { "imported footage".into() } else { opts.description.clone() },
            fps: opts.fps,
            paper: super::hex_color(report.paper),
            pigment,
            border_width: super::border::FALLBACK_WIDTH,
            scale: 1.0,
            speed: 1,
            seed: None,
            generator: None,
            license: opts.license.clone(),
            origin: "imported".into(),
        },
        frames,
        masks,
    };
    ex.meta.border_width = super::border::estimate_border_width(&ex).width;
    Ok(ex)
}

/// The sides of the image (`left`, `top`, `right`, `bottom`) that the paint of some frame
/// reaches (coverage ≥ ½ in the outermost column or row): where the paint was cut by the edge
/// of the scan or the crop.
pub fn cut_sides(masks: &[Plane<f32>]) -> Vec<&'static str> {
    side_names(masks.iter().map(cut_edges))
}

/// The names of the sides that any of `edges` ([`cut_edges`] of a mask each) reaches.
fn side_names(edges: impl Iterator<Item = [bool; 4]>) -> Vec<&'static str> {
    let cut = edges.fold([false; 4], |a, b| std::array::from_fn(|k| a[k] | b[k]));
    ["left", "top", "right", "bottom"].into_iter().zip(cut).filter(|&(_, c)| c).map(|(s, _)| s).collect()
}

/// Whether the paint of mask `m` reaches its left, top, right and bottom edge.
fn cut_edges(m: &Plane<f32>) -> [bool; 4] {
    let (w, h) = m.size();
    if w == 0 || h == 0 {
        return [false; 4];
    }
    let painted = |x: usize, y: usize| m.get(x, y) >= 0.5;
    [
        (0..h).any(|y| painted(0, y)),
        (0..w).any(|x| painted(x, 0)),
        (0..h).any(|y| painted(w - 1, y)),
        (0..w).any(|x| painted(x, h - 1)),
    ]
}

/// The typical color of the paint: the mean of the darker half of the painted pixels.
fn pigment_color(frame: Option<&Plane<Rgb>>, mask: Option<&Plane<f32>>, paper: Rgb) -> String {
    let (Some(f), Some(m)) = (frame, mask) else { return String::new() };
    let mut px: Vec<(f32, Rgb)> =
        f.data().iter().zip(m.data()).filter(|(_, m)| **m >= 0.5).map(|(c, _)| (measure(*c, paper), *c)).collect();
    if px.is_empty() {
        return String::new();
    }
    px.sort_by(|a, b| b.0.total_cmp(&a.0));
    let half = &px[..px.len().div_ceil(2)];
    let mut acc = [0.0f32; 3];
    for (_, c) in half {
        (0..3).for_each(|i| acc[i] += c[i]);
    }
    super::hex_color(acc.map(|v| v / half.len() as f32))
}

/// The paint measure of one pixel: the largest optical density relative to paper.
#[inline]
fn measure(c: Rgb, paper: Rgb) -> f32 {
    (0..3).map(|i| (-(c[i].max(1e-3) / paper[i].max(1e-3)).ln()).max(0.0)).fold(0.0, f32::max)
}

/// Pixels of the edge ring (width 3 % of the shorter side, at least 2 px), row-major indices.
fn ring(w: usize, h: usize) -> Vec<usize> {
    let r = ((w.min(h) as f32 * 0.03) as usize).max(2).min(w.min(h) / 2).max(1);
    (0..w * h).filter(|&i| (i % w) < r || (i % w) >= w - r || (i / w) < r || (i / w) >= h - r).collect()
}

/// Estimates the paper color from the edge rings of `frames` (see the module docs).
pub fn estimate_paper(frames: &[Plane<Rgb>]) -> Rgb {
    let Some(first) = frames.first() else { return [1.0; 3] };
    let idx = ring(first.width(), first.height());
    let step = frames.len().div_ceil(64).max(1);
    let mut px: Vec<Rgb> = frames.iter().step_by(step).flat_map(|f| idx.iter().map(|&i| f.data()[i])).collect();
    let lum = |c: &Rgb| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    px.sort_by(|a, b| lum(b).total_cmp(&lum(a)));
    px.truncate((px.len() * 2 / 5).max(1));
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let mut v: Vec<f32> = px.iter().map(|p| p[c]).collect();
        v.sort_by(|a, b| a.total_cmp(b));
        *o = v[v.len() / 2];
    }
    out
}

/// Otsu's threshold of `values` over a 256-bin histogram of `[0, hi]`.
pub fn otsu(values: &[f32], hi: f32) -> f32 {
    const BINS: usize = 256;
    let hi = hi.max(1e-6);
    let mut hist = [0u64; BINS];
    for &v in values {
        hist[((v / hi * BINS as f32) as usize).min(BINS - 1)] += 1;
    }
    let total: u64 = hist.iter().sum();
    let sum_all: f64 = hist.iter().enumerate().map(|(i, &c)| i as f64 * c as f64).sum();
    let (mut w0, mut sum0, mut best, mut best_t) = (0u64, 0.0f64, -1.0f64, 0usize);
    for (t, &c) in hist.iter().enumerate() {
        w0 += c;
        sum0 += t as f64 * c as f64;
        let w1 = total - w0;
        if w0 == 0 || w1 == 0 {
            continue;
        }
        let (m0, m1) = (sum0 / w0 as f64, (sum_all - sum0) / w1 as f64);
        let between = w0 as f64 * w1 as f64 * (m0 - m1) * (m0 - m1);
        if between > best {
            best = between;
            best_t = t;
        }
    }
    (best_t as f32 + 1.0) / BINS as f32 * hi
}

/// Darkest paper accepted (sRGB luminance of the estimated paper color).
pub const MIN_PAPER_LUMA: f32 = 0.35;

/// Extracts the masks of prepared frames (steps 2–6 of the module docs).
pub fn extract_masks(frames: &[Plane<Rgb>], opts: &ImportOptions) -> Result<(Vec<Plane<f32>>, MaskReport)> {
    let Some(first) = frames.first() else {
        return Err(Error::param("frames", 0, "at least one frame"));
    };
    let (w, h) = first.size();
    let paper = estimate_paper(frames);
    // Paint darkens paper (Beer–Lambert): the brightest of the frames' edges must be paper, and
    // paper is light. A frame filled with paint to its edges has none to key out.
    let light = 0.2126 * paper[0] + 0.7152 * paper[1] + 0.0722 * paper[2];
    if light < MIN_PAPER_LUMA {
        return Err(Error::param(
            "paper",
            format!("{} (luminance {light:.2}, the brightest pixels along the frames' edges)", super::hex_color(paper)),
            format!(
                "bare, light paper (luminance ≥ {MIN_PAPER_LUMA}) along the edges of the frames: the paint must not \
                 fill them; crop to a part with paper around the paint (--crop)"
            ),
        ));
    }
    let raw: Vec<Plane<f32>> = frames.iter().map(|f| f.map(|c| measure(c, paper))).collect();
    let measures: Vec<Plane<f32>> = raw.iter().map(|m| img::gaussian_blur(m, 1.0)).collect();
    // Paper noise level from the edge rings, on the unblurred measure (the low threshold is
    // applied to it, so the blur cannot spread dark rims outwards).
    let idx = ring(w, h);
    let mut noise: Vec<f32> = raw.iter().flat_map(|m| idx.iter().map(|&i| m.data()[i])).collect();
    noise.sort_by(|a, b| a.total_cmp(b));
    let med = noise[noise.len() / 2];
    let mut dev: Vec<f32> = noise.iter().map(|v| (v - med).abs()).collect();
    dev.sort_by(|a, b| a.total_cmp(b));
    let mad = dev[dev.len() / 2];
    let (high, low) = match opts.threshold {
        Some(t) if t.is_finite() && t > 0.0 => (t, t),
        Some(t) => return Err(Error::param("threshold", t, "a positive number")),
        None => {
            let step = (frames.len() * w * h).div_ceil(2_000_000).max(1);
            let all: Vec<f32> = measures.iter().flat_map(|m| m.data().iter().copied()).step_by(step).collect();
            let mut sorted = all.clone();
            sorted.sort_by(|a, b| a.total_cmp(b));
            let hi = sorted[(sorted.len() - 1) * 999 / 1000].max(1e-3);
            let high = otsu(&all, hi);
            let low = (med + 4.0 * 1.4826 * mad).max(0.01).min(high);
            (high, low)
        }
    };
    let min_area = opts.min_area.unwrap_or(((w * h) as f32 * 0.0005) as usize).max(12);
    let mut masks: Vec<Plane<f32>> =
        measures.iter().zip(&raw).map(|(m, r)| clean(&hysteresis(m, r, high, low), w, h, min_area)).collect();
    fill_painted_holes(&mut masks);
    Ok((masks, MaskReport { paper, high, low }))
}

/// Pixels whose raw measure `r` is above `low`, connected (8-neighbourhood) to a pixel
/// whose smoothed measure `m` is above `high`.
fn hysteresis(m: &Plane<f32>, r: &Plane<f32>, high: f32, low: f32) -> Vec<bool> {
    let (w, h) = m.size();
    let d = r.data();
    let m = m.data();
    let mut out = vec![false; w * h];
    let mut stack: Vec<usize> = (0..w * h).filter(|&i| m[i] >= high).collect();
    for &i in &stack {
        out[i] = true;
    }
    while let Some(i) = stack.pop() {
        let (x, y) = ((i % w) as isize, (i / w) as isize);
        for (dx, dy) in [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)] {
            let (nx, ny) = (x + dx, y + dy);
            if nx < 0 || ny < 0 || nx >= w as isize || ny >= h as isize {
                continue;
            }
            let j = ny as usize * w + nx as usize;
            if !out[j] && d[j] >= low {
                out[j] = true;
                stack.push(j);
            }
        }
    }
    out
}

/// Smooths a binary mask, removes components smaller than `min_area` and fills holes of
/// that size; returns it as coverage (0 or 1).
fn clean(mask: &[bool], w: usize, h: usize, min_area: usize) -> Plane<f32> {
    let cov = Plane::from_vec(w, h, mask.iter().map(|&b| if b { 1.0f32 } else { 0.0 }).collect())
        .unwrap_or_else(|| Plane::new(w, h));
    let smooth = img::gaussian_blur(&cov, 1.0);
    let mut m: Vec<bool> = smooth.data().iter().map(|&v| v >= 0.5).collect();
    remove_small(&mut m, w, h, min_area, true);
    remove_small(&mut m, w, h, min_area, false);
    Plane::from_vec(w, h, m.into_iter().map(|b| if b { 1.0 } else { 0.0 }).collect())
        .unwrap_or_else(|| Plane::new(w, h))
}

/// Flips components of value `value` (4-connected) smaller than `min_area` pixels. Holes
/// (`value == false`) touching the frame edge are background and kept.
fn remove_small(m: &mut [bool], w: usize, h: usize, min_area: usize, value: bool) {
    let flip: Vec<Vec<usize>> = crate::img::components(m, w, h, value)
        .filter(|(comp, touches_edge)| comp.len() < min_area && (value || !touches_edge))
        .map(|(comp, _)| comp)
        .collect();
    for i in flip.into_iter().flatten() {
        m[i] = !value;
    }
}

/// Fills, frame by frame, the holes enclosed by paint (components of paper that do not touch
/// the frame edge) of which at least half was paint in the previous frame's mask (as filled):
/// paint spreading on wet paper does not withdraw from paper it has covered, and a pale wash
/// inside it is paint, however close to the paper's color. On filmed footage the pale middle
/// of a bloom falls below the paper's noise level — sensor noise, JPEG and uneven light raise
/// it — and the masks of the last frames opened holes of hundreds of pixels (blue-bloom
/// re-filmed at 480 × 480 with paper fibres, a vignette, noise and JPEG at quality 82: 554 and
/// 1057 px in frames 25 and 28), inside which the border channel saw an edge that is not
/// there. A hole that was already paper in the previous frame (a ring of paint, a dry island)
/// stays.
fn fill_painted_holes(masks: &mut [Plane<f32>]) {
    for k in 1..masks.len() {
        let (before, after) = masks.split_at_mut(k);
        let (prev, cur) = (&before[k - 1], &mut after[0]);
        let (w, h) = cur.size();
        let m: Vec<bool> = cur.data().iter().map(|&v| v >= 0.5).collect();
        let fill: Vec<usize> = crate::img::components(&m, w, h, false)
            .filter(|(comp, touches_edge)| {
                !touches_edge && 2 * comp.iter().filter(|&&i| prev.data()[i] >= 0.5).count() >= comp.len()
            })
            .flat_map(|(comp, _)| comp)
            .collect();
        for i in fill {
            cur.data_mut()[i] = 1.0;
        }
    }
}

/// Intersection over union of two masks (coverage ≥ ½); 1 when both are empty.
pub fn iou(a: &Plane<f32>, b: &Plane<f32>) -> f32 {
    let (mut inter, mut union) = (0usize, 0usize);
    for (&x, &y) in a.data().iter().zip(b.data()) {
        let (x, y) = (x >= 0.5, y >= 0.5);
        inter += (x && y) as usize;
        union += (x || y) as usize;
    }
    if union == 0 { 1.0 } else { inter as f32 / union as f32 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn otsu_splits_two_modes() {
        let v: Vec<f32> = (0..1000).map(|i| if i % 3 == 0 { 0.8 + (i % 7) as f32 * 0.01 } else { 0.1 }).collect();
        let t = otsu(&v, 1.0);
        assert!(t > 0.1 && t <= 0.8, "{t}");
    }

    /// A disc of paint on paper, centered at (cx, cy) with radius r, 64 × 48.
    fn disc(cx: f32, cy: f32, r: f32) -> Plane<Rgb> {
        Plane::from_fn(64, 48, |x, y| {
            let d = ((x as f32 - cx).powi(2) + (y as f32 - cy).powi(2)).sqrt();
            if d <= r { [0.2, 0.35, 0.6] } else { [0.95, 0.94, 0.92] }
        })
    }

    #[test]
    fn paint_cut_by_the_image_edge_is_reported_by_side() {
        let opts = ImportOptions::default();
        let framed = from_frames(vec![disc(32.0, 24.0, 12.0)], &[], &opts).unwrap();
        assert!(cut_sides(&framed.masks).is_empty());
        // Reaching over the top and the right of the image.
        let cut = from_frames(vec![disc(56.0, 6.0, 12.0)], &[], &opts).unwrap();
        assert_eq!(cut_sides(&cut.masks), ["top", "right"]);
        // Over several frames: any frame counts.
        let seq = from_frames(vec![disc(32.0, 24.0, 8.0), disc(6.0, 40.0, 12.0)], &[], &opts).unwrap();
        assert_eq!(cut_sides(&seq.masks), ["left", "bottom"]);
    }

    #[test]
    fn a_pale_middle_that_was_paint_stays_paint_and_a_ring_keeps_its_hole() {
        // 96 × 96 frames: a disc that grows (radius 20, 30, 40) and whose last frame has a
        // paper-colored middle of radius 12 (452 px, far above the speck size of 12 px); and,
        // as another exemplar, a ring of paint whose hole (radius 10) is paper from the start.
        let paper = [0.95, 0.94, 0.92];
        let frame = |r: f32, pale: f32, ring: f32| {
            Plane::from_fn(96, 96, |x, y| {
                let d = ((x as f32 - 47.5).powi(2) + (y as f32 - 47.5).powi(2)).sqrt();
                if d <= r && d > pale.max(ring) { [0.2, 0.35, 0.6] } else { paper }
            })
        };
        let opts = ImportOptions::default();
        let bloom = from_frames(vec![frame(20.0, 0.0, 0.0), frame(30.0, 0.0, 0.0), frame(40.0, 12.0, 0.0)], &[], &opts)
            .unwrap();
        let centre = |m: &Plane<f32>| m.get(47, 47);
        assert_eq!(centre(&bloom.masks[2]), 1.0, "the pale middle was paint a frame before");
        assert!(bloom.masks[2].data().iter().filter(|&&v| v >= 0.5).count() > 4900);
        // One frame alone has no history: the middle is a hole. A ring is a hole throughout.
        let alone = from_frames(vec![frame(40.0, 12.0, 0.0)], &[], &opts).unwrap();
        assert_eq!(centre(&alone.masks[0]), 0.0);
        let ring = from_frames(vec![frame(20.0, 0.0, 10.0), frame(30.0, 0.0, 10.0)], &[], &opts).unwrap();
        assert!(ring.masks.iter().all(|m| centre(m) == 0.0 && m.get(47 + 15, 47) == 1.0));
    }

    #[test]
    fn specks_removed_holes_filled() {
        let (w, h) = (20, 20);
        let mut m = vec![false; w * h];
        for y in 5..15 {
            for x in 5..15 {
                m[y * w + x] = true;
            }
        }
        m[9 * w + 9] = false; // a one-pixel hole
        m[w + 1] = true; // a one-pixel speck
        remove_small(&mut m, w, h, 4, true);
        remove_small(&mut m, w, h, 4, false);
        assert!(m[9 * w + 9] && !m[w + 1]);
        assert_eq!(m.iter().filter(|&&b| b).count(), 100);
    }
}
