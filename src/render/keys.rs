//! Painted keyframes in a render (`render --keyframe N=PAINTED.png`, issue 15): which layers a
//! painting paints, and those layers' frames painted from the paintings
//! ([`crate::synth::keyframes`]).
//!
//! A painting is the user's paint over a frame of the animation, the canvas's size — typically
//! a flat rendering of that frame (`render --exemplar none`) painted over in any paint
//! program. A layer counts as painted in it when, where the layer is the top-most one, the
//! painting differs from the flat rendering by more than [`PAINTED_DIFFERENCE`] on average:
//! layers left as they were keep their other style. A painted layer's paint at the keyframe is
//! only what is visible of it there (its coverage less the coverage of the layers above). Its
//! frames are painted before the render composites its first frame (the backward passes run
//! from later keyframes), into the render's state folder, and read back frame by frame.

use super::{RenderOptions, target_fill};
use crate::anim::Animation;
use crate::composite::{self, Background, LayerFrame};
use crate::error::{Error, Result};
use crate::img::{self, Plane};
use crate::progress::Progress;
use crate::synth::keyframes::{self, KeyedFrame, Keyframe};
use rayon::prelude::*;
use std::ops::Range;

/// Mean color difference (sRGB, per channel, 0–1) between a painting and the flat rendering,
/// over the pixels where a layer is on top, above which the layer counts as painted: about
/// 8 of 255 levels — far above what saving a flat frame again changes (0–1 level), far below
/// what paint over it does (watercolor texture alone changes it by 20–40 levels).
pub const PAINTED_DIFFERENCE: f32 = 0.03;

/// Fewest visible pixels a layer needs in a painting to count as painted there.
const MIN_VISIBLE: usize = 16;

/// Per region, the keyframes that paint it (empty: none). Loads every painting of
/// [`RenderOptions::keyframes`] and checks it (size, frame inside the rendered range).
pub(crate) fn painted_regions(
    anim: &Animation,
    opts: &RenderOptions,
    range: &Range<usize>,
    background: &Background,
) -> Result<Vec<Vec<Keyframe>>> {
    let mut per_region: Vec<Vec<Keyframe>> = vec![Vec::new(); anim.regions.len()];
    let (w, h) = (anim.width as usize, anim.height as usize);
    let mut seen: Vec<usize> = Vec::new();
    for (frame, path) in &opts.keyframes {
        if !range.contains(frame) {
            return Err(Error::param(
                "keyframe",
                format!("{} ('{}')", frame + 1, path.display()),
                format!("a frame of the rendered range ({}–{})", range.start + 1, range.end),
            ));
        }
        if seen.contains(frame) {
            return Err(Error::param("keyframe", frame + 1, "one painting per frame"));
        }
        seen.push(*frame);
        let mut painting = img::load_rgb(path)?;
        // Painted at the animation's own size, rendered with --scale: scaled along.
        let full = ((w as f32 / anim.scale()).round() as usize, (h as f32 / anim.scale()).round() as usize);
        if anim.scale() != 1.0 && painting.size() == full {
            painting = img::resize_bilinear(&painting, w, h);
        }
        if painting.size() != (w, h) {
            let sizes = if anim.scale() != 1.0 {
                format!("{}x{} (the animation) or {w}x{h} (at --scale {})", full.0, full.1, anim.scale())
            } else {
                format!("{w}x{h}, the animation's size")
            };
            return Err(Error::param(
                "keyframe",
                format!("{} ('{}', {}x{})", frame + 1, path.display(), painting.width(), painting.height()),
                format!("a painting of {sizes}"),
            ));
        }
        let regions: Vec<_> = (0..anim.regions.len()).map(|r| anim.render(r, *frame)).collect::<Result<_>>()?;
        // Regions are listed top-most first; composite bottom to top.
        let flat: Vec<LayerFrame> =
            regions.iter().rev().map(|rf| LayerFrame::flat(&rf.fill, rf.strokes.as_ref())).collect();
        let flat = composite::composite(w, h, background, &flat, opts.strokes)?;
        let mut above = Plane::filled(w, h, 0.0f32);
        let mut painted = 0usize;
        let mut largest = 0.0f64;
        for (r, rf) in regions.iter().enumerate() {
            let cov = target_fill(rf, opts.strokes).map(|c| c[3]);
            let visible = Plane::from_fn(w, h, |x, y| cov.get(x, y) * (1.0 - above.get(x, y)));
            let (mut diff, mut n) = (0.0f64, 0usize);
            for ((v, p), f) in visible.data().iter().zip(painting.data()).zip(flat.data()) {
                if *v >= 0.5 {
                    diff += (0..3).map(|i| (p[i] - f[i]).abs() as f64).sum::<f64>() / 3.0;
                    n += 1;
                }
            }
            if n >= MIN_VISIBLE {
                largest = largest.max(diff / n as f64);
            }
            if n >= MIN_VISIBLE && diff / n as f64 > PAINTED_DIFFERENCE as f64 {
                painted += 1;
                log::info!(
                    "keyframe {} ('{}') paints layer '{}' (mean difference {:.3} from the flat frame)",
                    frame + 1,
                    path.display(),
                    anim.regions[r].name,
                    diff / n as f64
                );
                per_region[r].push(Keyframe {
                    frame: frame - range.start,
                    painting: painting.clone(),
                    mask: Some(visible),
                });
            }
            above = Plane::from_fn(w, h, |x, y| {
                let a = above.get(x, y);
                a + (1.0 - a) * cov.get(x, y)
            });
        }
        if painted == 0 {
            return Err(Error::Exemplar {
                path: path.clone(),
                message: format!(
                    "paints no layer of frame {}: where each layer shows, it differs from the flat frame by at most \
                     {largest:.3} on average (a painted layer: more than {PAINTED_DIFFERENCE}); paint over the flat \
                     frame (render --exemplar none --frames {0}..{0})",
                    frame + 1
                ),
            });
        }
    }
    Ok(per_region)
}

/// The frames of a layer painted from keyframes, written under `dir` (one 16-bit PNG a frame,
/// [`super::paint::Paint`]) as they are painted and read back one at a time while compositing,
/// so that a long render does not hold them in memory.
pub(crate) struct KeyedFrames {
    dir: std::path::PathBuf,
    /// Seconds spent painting them in this run (0 when reused).
    pub(crate) seconds: f64,
}

impl KeyedFrames {
    /// Frame k (0-based within the rendered range).
    pub(crate) fn frame(&self, k: usize) -> Result<super::paint::Paint> {
        super::paint::Paint::load(&self.dir.join(format!("{:04}.png", k + 1)))
    }

    /// Removes the frames.
    pub(crate) fn remove(&self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// Where a render starts, for [`paint_regions`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Resume {
    /// From the first frame: everything is painted.
    Start,
    /// From this frame (0-based within the range), continuing an interrupted render.
    From(usize),
    /// Every frame was composited already (only the GIF is left): nothing is painted.
    Nothing,
}

/// Paints every painted region's frames (over `range`) from its keyframes, into
/// `state/keyframes/NN/`; `None` for the others. Regions in parallel, each reported to
/// `progress` as stage `"keys NN name"` (the frames both passes paint).
///
/// `resume`: a render that continues (the same inputs and options, checked by its journal)
/// reuses a region's frames when they were all painted (`NN/complete` says how many) instead
/// of painting them again, and paints nothing when no frame is left to composite.
pub(crate) fn paint_regions(
    anim: &Animation,
    opts: &RenderOptions,
    range: &Range<usize>,
    keys: &[Vec<Keyframe>],
    state: &std::path::Path,
    resume: Resume,
    progress: &dyn Progress,
) -> Result<Vec<Option<KeyedFrames>>> {
    keys.par_iter()
        .enumerate()
        .map(|(region, keys)| -> Result<Option<KeyedFrames>> {
            if keys.is_empty() {
                return Ok(None);
            }
            let dir = state.join("keyframes").join(format!("{:02}", region + 1));
            let complete = dir.join("complete");
            let reusable = || std::fs::read_to_string(&complete).is_ok_and(|n| n.trim() == range.len().to_string());
            match resume {
                Resume::Nothing => return Ok(Some(KeyedFrames { dir, seconds: 0.0 })),
                Resume::From(_) if reusable() => return Ok(Some(KeyedFrames { dir, seconds: 0.0 })),
                _ => {}
            }
            std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
            if complete.exists() {
                std::fs::remove_file(&complete).map_err(|e| Error::io(&complete, e))?;
            }
            let coverage = |k: usize| Ok(super::target_coverage(&anim.render(region, range.start + k)?, opts.strokes));
            let mut emit = |j: usize, out: KeyedFrame| -> Result<()> {
                super::paint::Paint::from_frame(&out.rgb, &out.mask).save(&dir.join(format!("{:04}.png", j + 1)))
            };
            let stage = format!("keys {}", super::stage_name(anim, region));
            let t0 = std::time::Instant::now();
            // The layer's true motion from its transforms, where the file gives it.
            let motion = |a: usize, b: usize| anim.fill_motion_to(region, range.start + a, range.start + b);
            keyframes::paint(&opts.params, range.len(), &coverage, Some(&motion), keys, &mut emit, &stage, progress)?;
            let seconds = t0.elapsed().as_secs_f64();
            img::atomic_write(&complete, |w| write!(w, "{}", range.len()))?;
            Ok(Some(KeyedFrames { dir, seconds }))
        })
        .collect()
}
