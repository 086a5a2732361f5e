//! The render cut into independent jobs: one per stylized layer ([`render_layer`]) and one per
//! file ([`composite`]), which waits for the file's layers. A job scheduler (see
//! `fluidymation plan` and `scripts/fluidymation_dask.py`) runs them on many machines that
//! share the output folder; run in any order that respects that dependency, they give the
//! same bytes as [`render`](super::render).
//!
//! A layer job writes into `OUT_DIR/layers/NN_name/`:
//! - `paint/NNNN.png`: every frame of the layer painted in the exemplar's colors
//!   ([`Paint`], 16-bit RGBA, alpha = the synthesized mask);
//! - `.fluidymation/`: its checkpoints while it runs ([`crate::resume`], checked like a
//!   render's) — a job that is run again (after its machine died, say) continues from the last
//!   frame it completed, and starts over when they fail their checks;
//! - [`LAYER_MANIFEST`], written last: the job is complete, with which options, and the size
//!   and CRC-32 of every painted frame, which the composite and a second run check;
//! - `.lock`: held while the job runs, so that two runs of one job never write at once (the
//!   second waits for the first and finds its work done).

use super::paint::Paint;
use super::{
    Layer, Prepared, RenderOptions, RenderSummary, STATE_DIR, StyleCache, background, frame_range, layer_states,
    next_frame, prepare, prepare_outputs, recolor_paint, resolve_styles, restore, stage_name, start_layer, target_fill,
    verified, write_composite, write_gif,
};
use crate::anim::{Animation, RegionFrame};
use crate::composite::{Pigment, StylizedLayer};
use crate::error::{Error, Result};
use crate::img;
use crate::output;
use crate::progress::Progress;
use crate::resume::{self, FileRecord, Journal, Remedy};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// The file a complete layer job leaves in its folder (JSON: input, layer, exemplar, frames
/// and a fingerprint of the options).
pub const LAYER_MANIFEST: &str = "layer.json";

/// The folder of a layer's painted frames, inside its layer folder.
pub const PAINT_DIR: &str = "paint";

const MANIFEST_FORMAT: u32 = 2;

#[derive(serde::Serialize, serde::Deserialize)]
struct Manifest {
    format: u32,
    input: PathBuf,
    index: usize,
    layer: String,
    exemplar: String,
    /// First and last frame, 1-based.
    frames: [usize; 2],
    fingerprint: String,
    /// Every painted frame, as written.
    files: Vec<PaintedFile>,
}

/// One painted frame in the manifest: its place in the range (0-based), its path in the
/// layer folder, its size and CRC-32 (hex).
#[derive(serde::Serialize, serde::Deserialize)]
struct PaintedFile {
    frame: usize,
    path: String,
    size: u64,
    crc: String,
}

impl Manifest {
    /// The painted frames as records; an error when one is malformed.
    fn records(&self, path: &Path) -> Result<Vec<FileRecord>> {
        self.files
            .iter()
            .map(|f| {
                let crc = u32::from_str_radix(&f.crc, 16).ok();
                let line = format!("{} {} {:08x} {}", f.frame, f.size, crc.unwrap_or_default(), f.path);
                crc.and_then(|_| FileRecord::parse(&line)).ok_or_else(|| Error::Corrupt {
                    path: path.to_path_buf(),
                    message: format!("the record of the painted frame '{}' is malformed", f.path),
                })
            })
            .collect()
    }
}

/// What a layer job did.
#[derive(Clone, Debug)]
pub struct LayerJobSummary {
    /// The layer's 1-based index from the top.
    pub index: usize,
    /// The layer's name.
    pub name: String,
    /// The exemplar it is painted with.
    pub exemplar: String,
    /// The layer's folder.
    pub dir: PathBuf,
    /// Frames painted by this run.
    pub painted: usize,
    /// Frames found done (by an earlier, interrupted run or a complete one).
    pub resumed: usize,
    /// Wall-clock seconds of this run.
    pub seconds: f64,
}

/// Everything that decides a layer's painted frames, as one number: the composite checks
/// that the layers it reads were painted with its own options. `input` is the
/// [`resume::input_digest`] of the animation: the same content gives the same fingerprint
/// wherever it lies (on another machine of a farm, say).
fn layer_fingerprint(anim: &Animation, opts: &RenderOptions, input: u64, region: usize, style: &str) -> String {
    let r = &anim.regions[region];
    format!(
        "{:016x}",
        resume::fingerprint(&format!(
            "layer|{:016x}|{:?}|{}|{}|{}|{:?}|{:?}|{:?}|{}|{}x{}x{}",
            input,
            opts.frames.start.min(anim.frames)..opts.frames.end.min(anim.frames),
            r.index,
            r.name,
            style,
            opts.exemplar_dirs,
            opts.strokes,
            opts.params,
            anim.scale(),
            anim.width,
            anim.height,
            anim.frames,
        ))
    )
}

fn read_manifest(path: &Path) -> Result<Manifest> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let m: Manifest = serde_json::from_str(&text)
        .map_err(|e| Error::Corrupt { path: path.to_path_buf(), message: format!("not a layer manifest: {e}") })?;
    if m.format != MANIFEST_FORMAT {
        return Err(Error::Corrupt {
            path: path.to_path_buf(),
            message: format!("layer manifest format {} (this version reads {})", m.format, MANIFEST_FORMAT),
        });
    }
    Ok(m)
}

/// Takes the layer folder's lock, waiting while another run of the same job holds it.
fn lock(dir: &Path) -> Result<std::fs::File> {
    let path = dir.join(".lock");
    let file = std::fs::File::options()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .map_err(|e| Error::io(&path, e))?;
    match file.try_lock() {
        Ok(()) => {}
        Err(std::fs::TryLockError::WouldBlock) => {
            log::info!("'{}': another run of this layer job is in progress; waiting for it", dir.display());
            file.lock().map_err(|e| Error::io(&path, e))?;
        }
        Err(std::fs::TryLockError::Error(e)) => return Err(Error::io(&path, e)),
    }
    Ok(file)
}

/// Paints region `region` of `anim` (its position in [`Animation::regions`]) as `opts` says,
/// into `opts.out_dir/layers/NN_name/`: `paint/NNNN.png` (16-bit RGBA in the exemplar's colors), checkpoints in
/// `.fluidymation/` while it runs, [`LAYER_MANIFEST`] when complete, and a `.lock` held while
/// it runs (a second run of the same job waits for the first). A complete job with the same
/// options whose painted frames are as it wrote them is not done again; an interrupted one
/// continues from its last checkpoint when the checkpoint and the frames painted so far pass
/// their checks; any other is started over (with a warning when something was damaged).
///
/// Only the options that decide the painting are used: input, frames, scale, styles, strokes,
/// exemplar folders and engine parameters ([`RenderOptions::gif`], `background`, `recolor`
/// and `keep_layers` are the composite's).
pub fn render_layer(
    anim: &Animation,
    opts: &RenderOptions,
    region: usize,
    progress: &dyn Progress,
) -> Result<LayerJobSummary> {
    let start = Instant::now();
    no_keyframes(opts)?;
    let range = frame_range(anim, opts)?;
    let Some(r) = anim.regions.get(region) else {
        return Err(Error::param("layer", region + 1, format!("a layer number in 1..={}", anim.regions.len())));
    };
    let styles_of = resolve_styles(anim, opts)?;
    let Some(style) = styles_of[region].clone() else {
        return Err(Error::param(
            "layer",
            &r.name,
            "a stylized layer: this one is left flat (style none), so it has no render-layer job; the composite \
             job draws it as it is",
        ));
    };
    let n = range.len();
    let dir = output::layer_dir(&opts.out_dir, r);
    let mut summary = LayerJobSummary {
        index: r.index,
        name: r.name.clone(),
        exemplar: style.clone(),
        dir: dir.clone(),
        painted: 0,
        resumed: 0,
        seconds: 0.0,
    };
    output::prepare_dir(&dir)?;
    let _lock = lock(&dir)?;
    let fingerprint = layer_fingerprint(anim, opts, resume::input_digest(&anim.path)?, region, &style);
    let paint_dir = dir.join(PAINT_DIR);
    let frame_file = |k: usize| output::frame_path(&paint_dir, range.start + k, anim.frames);
    let manifest_path = dir.join(LAYER_MANIFEST);
    if let Ok(m) = read_manifest(&manifest_path)
        && m.fingerprint == fingerprint
    {
        let records = m.records(&manifest_path).unwrap_or_default();
        let damage: Vec<_> = records.iter().filter_map(|r| r.check(&dir)).collect();
        if damage.is_empty() && (0..n).all(|k| records.iter().any(|f| f.frame == k)) {
            summary.resumed = n;
            summary.seconds = start.elapsed().as_secs_f64();
            return Ok(summary);
        }
        for d in &damage {
            log::warn!("'{}' {}", d.path.display(), d.what);
        }
        log::warn!("layer {:02} '{}': painted frames were changed or removed; painting it again", r.index, r.name);
    }
    let Prepared { region_style, styles, .. } = prepare(anim, opts, &range, Some(region), &StyleCache::new())?;
    let st = &styles[region_style[region].expect("a stylized region is prepared")];

    // The checkpoints: continue when they were made with the same options and they and the
    // frames painted so far pass their checks, else start over.
    let state_fingerprint = u64::from_str_radix(&fingerprint, 16).unwrap_or_default();
    let resumed = match Journal::open(&dir, state_fingerprint, n, Remedy::StartOver) {
        Ok((journal, done)) => {
            verified(&journal, "painting the layer again from its first frame").then_some((journal, done))
        }
        Err(Error::Missing { .. }) => None,
        Err(e @ (Error::Corrupt { .. } | Error::Stale { .. })) => {
            log::warn!("layer {:02} '{}': {e}", r.index, r.name);
            None
        }
        Err(e) => return Err(e),
    };
    if manifest_path.exists() {
        std::fs::remove_file(&manifest_path).map_err(|e| Error::io(&manifest_path, e))?;
    }
    let stages = [stage_name(anim, region)];
    let start_over = || -> Result<(Journal, Vec<Layer>)> {
        if paint_dir.exists() {
            std::fs::remove_dir_all(&paint_dir).map_err(|e| Error::io(&paint_dir, e))?;
        }
        let journal = Journal::create(&dir, state_fingerprint, n, Remedy::StartOver)?;
        Ok((journal, vec![new_layer(anim, opts, region, &range, st, region_style[region])?]))
    };
    let (mut journal, mut layers, done) = match resumed {
        Some((journal, done)) => {
            let mut layers = vec![new_layer(anim, opts, region, &range, st, region_style[region])?];
            match restore(&journal, done, &mut layers, &stages) {
                Ok(()) => (journal, layers, done),
                Err(e @ Error::Corrupt { .. }) => {
                    log::warn!("layer {:02} '{}': {e}", r.index, r.name);
                    let (journal, layers) = start_over()?;
                    (journal, layers, 0)
                }
                Err(e) => return Err(e),
            }
        }
        None => {
            let (journal, layers) = start_over()?;
            (journal, layers, 0)
        }
    };
    output::prepare_dir(&paint_dir)?;
    output::remove_stale_temporaries(&paint_dir, None);
    output::remove_stale_temporaries(&dir, None);
    output::remove_stale_temporaries(&dir.join(STATE_DIR), None);

    if !progress.update(&stages[0], done, n) {
        return Err(Error::Cancelled);
    }
    for k in done..n {
        let frame = range.start + k;
        let l = &mut layers[0];
        let (Some(synth), Some(guides)) = (l.synth.as_mut(), l.guides.as_mut()) else { unreachable!() };
        let out = next_frame(anim, synth, guides, frame)?;
        let path = frame_file(k);
        Paint::from_frame(&out.rgb, &out.mask).save(&path)?;
        journal.record(k, &path)?;
        journal.commit(k + 1, &layer_states(&layers, &stages))?;
        if !progress.update(&stages[0], k + 1, n) {
            return Err(Error::Cancelled);
        }
    }
    let files = journal
        .records()
        .iter()
        .map(|f| PaintedFile { frame: f.frame, path: f.path.clone(), size: f.size, crc: format!("{:08x}", f.crc) })
        .collect();
    let manifest = Manifest {
        format: MANIFEST_FORMAT,
        input: std::fs::canonicalize(&anim.path).unwrap_or_else(|_| anim.path.clone()),
        index: r.index,
        layer: r.name.clone(),
        exemplar: style,
        frames: [range.start + 1, range.end],
        fingerprint,
        files,
    };
    let text = serde_json::to_string_pretty(&manifest).expect("a manifest serializes");
    img::atomic_write(&manifest_path, |w| w.write_all(format!("{text}\n").as_bytes()))?;
    // The manifest holds the records now.
    journal.remove()?;
    summary.painted = n - done;
    summary.resumed = done;
    summary.seconds = start.elapsed().as_secs_f64();
    Ok(summary)
}

/// A new layer of a render-layer job: its synthesizer and guide stream.
fn new_layer(
    anim: &Animation,
    opts: &RenderOptions,
    region: usize,
    range: &std::ops::Range<usize>,
    st: &super::Prepped,
    style: Option<usize>,
) -> Result<Layer> {
    let (synth, guides) = start_layer(anim, opts, region, range, st)?;
    Ok(Layer { region, style, synth: Some(synth), guides: Some(guides), seconds: 0.0, kept: Vec::new() })
}

/// Recolors and composites the layers that [`render_layer`] painted into
/// `opts.out_dir/layers/` (flat layers are drawn from the animation), writes the frames and
/// the GIF as [`render`](super::render) does, with `--keep-layers` every layer alone too.
/// Fails, before writing anything, when a stylized layer is not painted completely or was
/// painted with other options.
pub fn composite(anim: &Animation, opts: &RenderOptions, progress: &dyn Progress) -> Result<RenderSummary> {
    let start = Instant::now();
    no_keyframes(opts)?;
    let range = frame_range(anim, opts)?;
    let background = background(anim, opts)?;
    let styles_of = resolve_styles(anim, opts)?;
    let cache = StyleCache::new();
    let n = range.len();
    let input = resume::input_digest(&anim.path)?;
    let pigments: Vec<Option<Pigment>> = styles_of
        .iter()
        .enumerate()
        .map(|(region, style)| -> Result<Option<Pigment>> {
            let Some(style) = style else { return Ok(None) };
            let r = &anim.regions[region];
            let dir = output::layer_dir(&opts.out_dir, r);
            let path = dir.join(LAYER_MANIFEST);
            let manifest = read_manifest(&path).map_err(|e| match e {
                Error::Io { .. } => Error::Missing {
                    path: dir.clone(),
                    what: format!(
                        "layer {:02} '{}' is not painted (completely): run its render-layer job first",
                        r.index, r.name
                    ),
                },
                other => other,
            })?;
            if manifest.fingerprint != layer_fingerprint(anim, opts, input, region, style) {
                return Err(Error::Stale {
                    path,
                    message: format!(
                        "layer {:02} '{}' was painted with other options than this composite's (input, frames, \
                         style, scale, strokes or engine parameters); run its render-layer job again with the same \
                         options",
                        r.index, r.name
                    ),
                });
            }
            // Every painted frame must be as the job wrote it.
            let records = manifest.records(&path)?;
            for k in 0..n {
                let file = output::frame_path(&dir.join(PAINT_DIR), range.start + k, anim.frames);
                let rel = format!("{PAINT_DIR}/{}", file.file_name().unwrap_or_default().to_string_lossy());
                let what = match records.iter().find(|f| f.frame == k && f.path == rel) {
                    None => Some("was never recorded by the job".to_string()),
                    Some(record) => record.check(&dir).map(|d| d.what),
                };
                if let Some(what) = what {
                    return Err(Error::Corrupt {
                        path: file,
                        message: format!(
                            "layer {:02} '{}': this painted frame {what}; run its render-layer job again",
                            r.index, r.name
                        ),
                    });
                }
            }
            Ok(Some(Pigment::from_exemplar(&cache.exemplar(style, opts)?)))
        })
        .collect::<Result<_>>()?;
    let layer_dirs = prepare_outputs(anim, opts)?;
    let (w, h) = (anim.width as usize, anim.height as usize);
    let finished = AtomicUsize::new(0);
    if !progress.update("frames", 0, n) {
        return Err(Error::Cancelled);
    }
    range.clone().into_par_iter().try_for_each(|frame| -> Result<()> {
        let results: Vec<(Option<StylizedLayer>, RegionFrame)> = (0..anim.regions.len())
            .into_par_iter()
            .map(|region| -> Result<(Option<StylizedLayer>, RegionFrame)> {
                let rf = anim.render(region, frame)?;
                let Some(pigment) = &pigments[region] else { return Ok((None, rf)) };
                let dir = output::layer_dir(&opts.out_dir, &anim.regions[region]).join(PAINT_DIR);
                let path = output::frame_path(&dir, frame, anim.frames);
                let paint = Paint::load(&path)?;
                if paint.size() != (w, h) {
                    return Err(Error::SizeMismatch {
                        path,
                        expected: (w as u32, h as u32),
                        found: (paint.size().0 as u32, paint.size().1 as u32),
                    });
                }
                Ok((Some(recolor_paint(&paint, &rf, pigment, opts)?), rf))
            })
            .collect::<Result<_>>()?;
        write_composite(anim, opts, &background, frame, &results, &layer_dirs)?;
        let k = finished.fetch_add(1, Ordering::SeqCst) + 1;
        if !progress.update("frames", k, n) {
            return Err(Error::Cancelled);
        }
        Ok(())
    })?;
    write_gif(anim, opts, &range, &background, progress)?;
    Ok(RenderSummary {
        frames: n,
        resumed: 0,
        seconds: start.elapsed().as_secs_f64(),
        frame_dir: opts.out_dir.clone(),
        gif: opts.gif.clone(),
        layers: anim
            .regions
            .iter()
            .zip(&styles_of)
            .map(|(r, s)| super::LayerSummary {
                index: r.index,
                name: r.name.clone(),
                exemplar: s.clone(),
                seconds: 0.0,
                eval: None,
            })
            .collect(),
    })
}

/// The estimated cost of one layer's job.
#[derive(Clone, Debug, PartialEq)]
pub struct LayerCost {
    /// The region (position in [`Animation::regions`]).
    pub region: usize,
    /// Its style (`None`: left flat, no job).
    pub style: Option<String>,
    /// Frames to paint.
    pub frames: usize,
    /// Pixels inside the layer's mask (coverage ≥ ½), summed over the frames: what the
    /// synthesis time grows with. 0 for flat layers.
    pub masked_pixels: u64,
}

/// The cost of every region's layer job as `opts` would render it: frames × masked pixels,
/// from the region's flat renderings (no synthesis).
pub fn layer_costs(anim: &Animation, opts: &RenderOptions) -> Result<Vec<LayerCost>> {
    let range = frame_range(anim, opts)?;
    let styles_of = resolve_styles(anim, opts)?;
    (0..anim.regions.len())
        .into_par_iter()
        .map(|region| -> Result<LayerCost> {
            let style = styles_of[region].clone();
            let mut masked = 0u64;
            if style.is_some() {
                for frame in range.clone() {
                    let fill = target_fill(&anim.render(region, frame)?, opts.strokes);
                    masked += fill.data().iter().filter(|c| c[3] >= 0.5).count() as u64;
                }
            }
            Ok(LayerCost { region, style, frames: range.len(), masked_pixels: masked })
        })
        .collect()
}

/// Painted keyframes need every frame of a layer painted before the first is composited (the
/// backward passes), which the per-layer jobs do not do: they are [`super::render_with`]'s only.
fn no_keyframes(opts: &RenderOptions) -> Result<()> {
    if opts.keyframes.is_empty() {
        Ok(())
    } else {
        Err(Error::param("keyframes", opts.keyframes.len(), "none in layer and composite jobs (render the file whole)"))
    }
}
