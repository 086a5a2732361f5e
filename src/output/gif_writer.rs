//! Animated GIF output: timing, palettes, inter-frame updates, atomic writing.

use super::quant::{Palette, build_palette, map_pixels};
use crate::error::{Error, Result};
use crate::img::{Plane, Rgb, Rgba};
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// Shortest frame delay written, in 1/100 s: browsers show frames of 0 or 1 centisecond for
/// 1/10 s, so faster animations drop frames instead (see [`gif_schedule`]).
pub const MIN_DELAY_CS: u64 = 2;

/// Options of a [`GifWriter`]: `GifOptions::new(fps).transparent(true)`.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct GifOptions {
    /// Frames per second of the animation. Default: 24.
    pub fps: f64,
    /// Floyd–Steinberg error diffusion (otherwise nearest color). Default: true.
    pub dither: bool,
    /// Keep transparency (pixels with alpha < 0.5 become transparent; every frame is then
    /// written whole and cleared before the next). Without it frames are flattened over
    /// [`GifOptions::matte`]. Default: false.
    pub transparent: bool,
    /// Color that frames with partial alpha are flattened over when not
    /// [`transparent`](GifOptions::transparent), sRGB. Default: white.
    pub matte: Rgb,
}

impl Default for GifOptions {
    fn default() -> Self {
        GifOptions { fps: 24.0, dither: true, transparent: false, matte: [1.0; 3] }
    }
}

impl GifOptions {
    /// Default options at `fps` frames per second.
    pub fn new(fps: f64) -> Self {
        GifOptions { fps, ..Default::default() }
    }

    /// Sets [`GifOptions::dither`]. Default: true.
    pub fn dither(mut self, yes: bool) -> Self {
        self.dither = yes;
        self
    }

    /// Sets [`GifOptions::transparent`]. Default: false.
    pub fn transparent(mut self, yes: bool) -> Self {
        self.transparent = yes;
        self
    }

    /// Sets [`GifOptions::matte`]. Default: white.
    pub fn matte(mut self, color: Rgb) -> Self {
        self.matte = color;
        self
    }
}

/// What [`GifWriter::finish`] wrote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GifSummary {
    /// The GIF file.
    pub path: PathBuf,
    /// Frames given to [`GifWriter::add_frame`].
    pub frames_added: usize,
    /// Frames in the file (fewer when consecutive identical frames were merged, or frames
    /// dropped above 50 fps).
    pub frames_written: usize,
    /// Total duration in 1/100 s.
    pub duration_cs: u64,
}

/// Start time of frame `k` in 1/100 s: `round(100 k / fps)`. Delays are differences of these
/// rounded times, so rounding errors never accumulate (24 fps: 4, 4, 5, 4, 4, 4, … — 25 cs
/// per 6 frames, exactly 100 cs per 24 frames).
fn start_cs(k: usize, fps: f64) -> u64 {
    (k as f64 * 100.0 / fps).round() as u64
}

/// The frames a GIF of `frames` frames at `fps` shows and their delays in 1/100 s, as
/// `(frame index, delay)`. Each frame lasts from its rounded start time to the next shown
/// frame's, so the total is `round(100 · frames / fps)`. A frame that would last less than
/// [`MIN_DELAY_CS`] is dropped and the next one starts in its place (only above 50 fps).
/// [`GifWriter`] follows this schedule, merging identical consecutive frames on top.
pub fn gif_schedule(fps: f64, frames: usize) -> Vec<(usize, u16)> {
    let mut out = Vec::new();
    let mut pending: Option<(usize, u64)> = None;
    for k in 0..frames {
        let t = start_cs(k, fps);
        pending = match pending {
            Some((p, start)) if t - start >= MIN_DELAY_CS => {
                out.push((p, clamp_delay(t - start)));
                Some((k, t))
            }
            Some((_, start)) => Some((k, start)),
            None => Some((k, t)),
        };
    }
    if let Some((p, start)) = pending {
        out.push((p, clamp_delay(start_cs(frames, fps).saturating_sub(start).max(MIN_DELAY_CS))));
    }
    out
}

fn clamp_delay(cs: u64) -> u16 {
    cs.min(u16::MAX as u64) as u16
}

struct Pending {
    /// RGBA8, straight, fully transparent pixels zeroed.
    rgba: Vec<u8>,
    start: u64,
}

/// Writes an animated GIF frame by frame (infinite loop), to a temporary file next to the
/// destination that [`finish`](GifWriter::finish) renames into place: a failed or interrupted
/// run leaves no half-written GIF, and dropping the writer without finishing removes the
/// temporary file.
///
/// Every frame gets its own palette, built from the pixels it changes (see the `quant`
/// notes in the [module documentation](super)). Opaque animations only store what changed
/// since the previous frame (a cropped frame, unchanged pixels transparent), which keeps
/// still areas perfectly still and spends the palette on what moves.
pub struct GifWriter {
    path: PathBuf,
    tmp: PathBuf,
    encoder: Option<gif::Encoder<BufWriter<File>>>,
    width: usize,
    height: usize,
    options: GifOptions,
    added: usize,
    written: usize,
    pending: Option<Pending>,
    /// Source of the last written frame (opaque mode): the base of the next frame's changes.
    last: Option<Vec<u8>>,
}

impl std::fmt::Debug for GifWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GifWriter")
            .field("path", &self.path)
            .field("width", &self.width)
            .field("height", &self.height)
            .field("options", &self.options)
            .field("added", &self.added)
            .finish_non_exhaustive()
    }
}

impl GifWriter {
    /// Starts a `width × height` GIF at `path` (its directory must exist).
    pub fn create(path: &Path, width: usize, height: usize, options: GifOptions) -> Result<GifWriter> {
        if !(options.fps.is_finite() && options.fps > 0.0) {
            return Err(Error::param("fps", options.fps, "a positive number of frames per second"));
        }
        for (name, v) in [("GIF width", width), ("GIF height", height)] {
            if v == 0 || v > u16::MAX as usize {
                return Err(Error::param(name, v, "1..=65535 pixels"));
            }
        }
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "animation.gif".into());
        let tmp = dir.join(format!(".{}.{}.tmp", name, std::process::id()));
        let file = File::create(&tmp).map_err(|e| Error::io(path, e))?;
        let mut writer = GifWriter {
            path: path.to_path_buf(),
            tmp,
            encoder: None,
            width,
            height,
            options,
            added: 0,
            written: 0,
            pending: None,
            last: None,
        };
        let mut encoder = gif::Encoder::new(BufWriter::new(file), width as u16, height as u16, &[])
            .map_err(|e| writer.encoding_error(e))?;
        encoder.set_repeat(gif::Repeat::Infinite).map_err(|e| writer.encoding_error(e))?;
        writer.encoder = Some(encoder);
        Ok(writer)
    }

    /// The destination path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Frames added so far.
    pub fn frames_added(&self) -> usize {
        self.added
    }

    /// Adds the next frame (straight sRGB RGBA, the writer's size). The frame is encoded when
    /// its duration is known, i.e. when the next frame arrives or at [`finish`](Self::finish).
    pub fn add_frame(&mut self, frame: &Plane<Rgba>) -> Result<()> {
        if frame.size() != (self.width, self.height) {
            return Err(Error::param(
                "GIF frame size",
                format!("{}x{}", frame.width(), frame.height()),
                format!("the GIF's size {}x{}", self.width, self.height),
            ));
        }
        let rgba = self.to_rgba8(frame);
        let t = start_cs(self.added, self.options.fps);
        self.added += 1;
        match self.pending.take() {
            None => self.pending = Some(Pending { rgba, start: t }),
            // Identical to the frame on hold: it simply lasts longer.
            Some(p) if p.rgba == rgba => self.pending = Some(p),
            // Too short to show (above 50 fps): the new frame replaces it.
            Some(p) if t - p.start < MIN_DELAY_CS => self.pending = Some(Pending { rgba, start: p.start }),
            Some(p) => {
                self.write(&p.rgba, t - p.start)?;
                self.pending = Some(Pending { rgba, start: t });
            }
        }
        Ok(())
    }

    /// Writes the last frame, completes the file and renames it into place.
    pub fn finish(mut self) -> Result<GifSummary> {
        let Some(p) = self.pending.take() else {
            return Err(Error::Empty { path: self.path.clone(), what: "no frames were given for the GIF".into() });
        };
        let end = start_cs(self.added, self.options.fps);
        self.write(&p.rgba, end.saturating_sub(p.start).max(MIN_DELAY_CS))?;
        let duration_cs = end.max(p.start + MIN_DELAY_CS);
        let Some(encoder) = self.encoder.take() else {
            return Err(Error::io(&self.tmp, std::io::Error::other("GIF encoder gone")));
        };
        // From here on `Drop` no longer cleans up: remove the temporary file on any error.
        let completed = (|| -> Result<()> {
            let buffered = encoder.into_inner().map_err(|e| self.encoding_error(e))?;
            let file = buffered.into_inner().map_err(|e| Error::io(&self.path, e.into_error()))?;
            file.sync_all().map_err(|e| Error::io(&self.path, e))?;
            drop(file);
            std::fs::rename(&self.tmp, &self.path).map_err(|e| Error::io(&self.path, e))
        })();
        if let Err(e) = completed {
            let _ = std::fs::remove_file(&self.tmp);
            return Err(e);
        }
        Ok(GifSummary { path: self.path.clone(), frames_added: self.added, frames_written: self.written, duration_cs })
    }

    fn encoding_error(&self, e: gif::EncodingError) -> Error {
        match e {
            gif::EncodingError::Io(io) => Error::io(&self.path, io),
            other => Error::image_codec(&self.path, other),
        }
    }

    /// RGBA8 of a frame: straight color, alpha kept or flattened over the matte.
    fn to_rgba8(&self, frame: &Plane<Rgba>) -> Vec<u8> {
        let q = |v: f32| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
        let mut out = Vec::with_capacity(frame.len() * 4);
        for c in frame.data() {
            let a = if c[3].is_nan() { 0.0 } else { c[3].clamp(0.0, 1.0) };
            if self.options.transparent {
                if a < 0.5 {
                    out.extend_from_slice(&[0, 0, 0, 0]);
                } else {
                    out.extend_from_slice(&[q(c[0]), q(c[1]), q(c[2]), 255]);
                }
            } else {
                let m = self.options.matte;
                out.extend_from_slice(&[
                    q(c[0] * a + m[0] * (1.0 - a)),
                    q(c[1] * a + m[1] * (1.0 - a)),
                    q(c[2] * a + m[2] * (1.0 - a)),
                    255,
                ]);
            }
        }
        out
    }

    /// Encodes one frame lasting `delay` centiseconds.
    fn write(&mut self, rgba: &[u8], delay: u64) -> Result<()> {
        let (w, h) = (self.width, self.height);
        let px = |i: usize| [rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]];
        // Region to store and the pixels inside it left as they are (transparent index).
        let (rect, skip): ([usize; 4], Vec<bool>) = if self.options.transparent {
            ([0, 0, w, h], (0..w * h).map(|i| rgba[4 * i + 3] == 0).collect())
        } else if let Some(last) = &self.last {
            let changed = |i: usize| rgba[4 * i..4 * i + 3] != last[4 * i..4 * i + 3];
            let mut r = [w, h, 0, 0];
            for y in 0..h {
                for x in 0..w {
                    if changed(y * w + x) {
                        r = [r[0].min(x), r[1].min(y), r[2].max(x + 1), r[3].max(y + 1)];
                    }
                }
            }
            if r[0] >= r[2] {
                r = [0, 0, 1, 1]; // nothing changed: one transparent pixel carries the delay
            }
            let skip = (r[1]..r[3]).flat_map(|y| (r[0]..r[2]).map(move |x| y * w + x)).map(|i| !changed(i)).collect();
            (r, skip)
        } else {
            ([0, 0, w, h], vec![false; w * h])
        };
        let (rw, rh) = (rect[2] - rect[0], rect[3] - rect[1]);
        let pixels: Vec<[u8; 3]> =
            (rect[1]..rect[3]).flat_map(|y| (rect[0]..rect[2]).map(move |x| y * w + x)).map(px).collect();
        let needs_transparency = skip.iter().any(|&s| s);
        let max_colors = if needs_transparency { 255 } else { 256 };
        let shown: Vec<[u8; 3]> = pixels.iter().zip(&skip).filter(|(_, s)| !**s).map(|(p, _)| *p).collect();
        let colors = if shown.is_empty() { vec![[0, 0, 0]] } else { build_palette(&shown, max_colors) };
        let mut palette = Palette::new(colors);
        let transparent_index = palette.colors().len() as u8; // == 255 at most
        let indices = map_pixels(&pixels, &skip, rw, rh, &mut palette, self.options.dither, transparent_index);
        let mut table: Vec<u8> = palette.colors().iter().flatten().copied().collect();
        if needs_transparency {
            table.extend_from_slice(&[0, 0, 0]);
        }
        let frame = gif::Frame {
            delay: clamp_delay(delay),
            dispose: if self.options.transparent { gif::DisposalMethod::Background } else { gif::DisposalMethod::Keep },
            transparent: needs_transparency.then_some(transparent_index),
            left: rect[0] as u16,
            top: rect[1] as u16,
            width: rw as u16,
            height: rh as u16,
            palette: Some(table),
            buffer: std::borrow::Cow::Owned(indices),
            ..gif::Frame::default()
        };
        let result = match self.encoder.as_mut() {
            Some(encoder) => encoder.write_frame(&frame),
            None => Err(gif::EncodingError::Io(std::io::Error::other("GIF encoder gone"))),
        };
        result.map_err(|e| self.encoding_error(e))?;
        self.written += 1;
        if !self.options.transparent {
            self.last = Some(rgba.to_vec());
        }
        Ok(())
    }
}

impl Drop for GifWriter {
    fn drop(&mut self) {
        if let Some(encoder) = self.encoder.take() {
            // Not finished: close the file and remove it (errors ignored; nothing to report to).
            drop(encoder);
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}
