//! A PNG chart of a [`Report`]'s per-frame series.
//!
//! The chart is built as an SVG document ([`plot_svg`]) and rasterized with resvg — no
//! plotting dependency. It is a stack of panels with fixed order and colors, top to bottom:
//! coverage IoU (0..1), local-contrast ratio (reference line at 1), edge-darkening ratio
//! (reference line at 1; below 0 when the edge is paler than the interior), palette distance
//! (red, green and blue lines), patch nearest-neighbour distance, temporal-change ratio
//! (reference line at 1), incoherent-change ratio (reference line at 1) and motion agreement
//! (−1..1, reference line at 0); the x axis is the frame number. Missing values leave gaps.
//!
//! **Fonts.** Titles and tick labels are SVG text, drawn with whatever fonts the system has
//! (DejaVu Sans when installed, else the first font found). On a machine without any font
//! the labels are simply left out — a warning is logged, and the chart stays readable from
//! its fixed panel order, colors and reference lines. Nothing else depends on fonts.

use super::Report;
use crate::error::{Error, Result};
use crate::img::{self, Plane, Rgba};
use std::fmt::Write as _;
use std::path::Path;
use std::sync::{Arc, OnceLock};

/// Size of the chart.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlotOptions {
    /// Width in pixels. Default: 960.
    pub width: u32,
    /// Height of each of the eight panels, pixels. Default: 120.
    pub panel_height: u32,
}

impl Default for PlotOptions {
    fn default() -> Self {
        PlotOptions { width: 960, panel_height: 120 }
    }
}

const LEFT: f64 = 70.0;
const RIGHT: f64 = 20.0;
const TOP: f64 = 36.0;
const TITLE: f64 = 22.0;
const GAP: f64 = 10.0;
const BOTTOM: f64 = 40.0;
const PAD: f64 = 4.0;
const FONT: &str = "font-family=\"DejaVu Sans, sans-serif\"";

struct Panel {
    title: &'static str,
    /// (color, values) per line.
    lines: Vec<(&'static str, Vec<Option<f32>>)>,
    /// Fixed y range, or `None` for 0..max (at least `min_top`), extended below 0 when a value
    /// is negative.
    range: Option<(f32, f32)>,
    min_top: f32,
    reference: Option<f32>,
}

pub(crate) fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// A step of 1, 2 or 5 × 10^k giving about `target` intervals over `span`.
fn nice_step(span: f64, target: f64) -> f64 {
    let raw = (span / target).max(1e-12);
    let mag = 10f64.powf(raw.log10().floor());
    let norm = raw / mag;
    let m = if norm <= 1.0 {
        1.0
    } else if norm <= 2.0 {
        2.0
    } else if norm <= 5.0 {
        5.0
    } else {
        10.0
    };
    m * mag
}

fn label(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".to_string() } else { s.to_string() }
}

/// The chart as an SVG document (see the [module documentation](self)).
pub fn plot_svg(report: &Report, options: &PlotOptions) -> String {
    let frames = &report.per_frame;
    let series = |f: fn(&super::FrameStats) -> Option<f32>| frames.iter().map(f).collect::<Vec<_>>();
    let channel = |c: usize| frames.iter().map(|f| f.palette_distance.map(|p| p[c])).collect::<Vec<_>>();
    let panels = [
        Panel {
            title: "coverage IoU (gray: what the exemplar's own paint reaches at these depths)",
            lines: vec![("#7f7f7f", series(|f| f.coverage_iou_exemplar)), ("#1f77b4", series(|f| f.coverage_iou))],
            range: Some((0.0, 1.0)),
            min_top: 1.0,
            reference: None,
        },
        Panel {
            title: "local contrast ratio (output / exemplar; ~1 good, ~0 wash-out)",
            lines: vec![("#ff7f0e", series(|f| f.contrast_ratio))],
            range: None,
            min_top: 1.5,
            reference: Some(1.0),
        },
        Panel {
            title: "edge darkening ratio (output / exemplar; ~1 good, ~0 no rim, <0 pale edge)",
            lines: vec![("#e377c2", series(|f| f.edge_darkening_ratio))],
            range: None,
            min_top: 1.5,
            reference: Some(1.0),
        },
        Panel {
            title: "palette distance W1 (R, G, B)",
            lines: vec![("#d62728", channel(0)), ("#2ca02c", channel(1)), ("#1f3fd4", channel(2))],
            range: None,
            min_top: 0.05,
            reference: None,
        },
        Panel {
            title: "patch NN distance (RMS, 5x5)",
            lines: vec![("#9467bd", series(|f| f.patch_nn_distance))],
            range: None,
            min_top: 0.05,
            reference: None,
        },
        Panel {
            title: "temporal change ratio (output / exemplar; ~1 good, >>1 flicker, ~0 glued)",
            lines: vec![("#8c564b", series(|f| f.temporal_change_ratio))],
            range: None,
            min_top: 2.0,
            reference: Some(1.0),
        },
        Panel {
            title: "incoherent change ratio (flow-compensated, output / exemplar; ~1 good, >>1 boiling)",
            lines: vec![("#bcbd22", series(|f| f.incoherent_change_ratio))],
            range: None,
            min_top: 2.0,
            reference: Some(1.0),
        },
        Panel {
            title: "motion agreement (mean cosine; +1 with the target)",
            lines: vec![("#17becf", series(|f| f.motion_agreement))],
            range: Some((-1.0, 1.0)),
            min_top: 1.0,
            reference: Some(0.0),
        },
    ];
    let width = options.width.max(200) as f64;
    let ph = options.panel_height.max(40) as f64;
    let height = TOP + panels.len() as f64 * (TITLE + ph + GAP) + BOTTOM;
    let n = frames.len().max(1);
    let plot_w = width - LEFT - RIGHT;
    let x_of = |i: usize| LEFT + if n == 1 { plot_w / 2.0 } else { plot_w * i as f64 / (n - 1) as f64 };

    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}">"#
    );
    let _ = writeln!(s, r#"<rect width="{width}" height="{height}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{LEFT}" y="22" font-size="15" {FONT} fill="black">fluidymation eval: {} frames of {}x{}, exemplar '{}'</text>"#,
        report.frames,
        report.width,
        report.height,
        escape(&report.exemplar.name)
    );
    for (k, p) in panels.iter().enumerate() {
        let top = TOP + k as f64 * (TITLE + ph + GAP) + TITLE;
        let (lo, hi) = p.range.unwrap_or_else(|| {
            let values = || p.lines.iter().flat_map(|(_, v)| v.iter().flatten()).filter(|v| v.is_finite());
            let max = values().fold(0f32, |a, &b| a.max(b));
            let min = values().fold(0f32, |a, &b| a.min(b));
            (min * 1.1, (max * 1.1).max(p.min_top))
        });
        let (lo, hi) = (lo as f64, hi as f64);
        // Values map into the panel less a small padding, so lines at the limits stay visible.
        let y_of = |v: f64| top + PAD + (ph - 2.0 * PAD) * (1.0 - (v.clamp(lo, hi) - lo) / (hi - lo));
        let _ = writeln!(
            s,
            r#"<text x="{LEFT}" y="{:.1}" font-size="12" {FONT} fill="black">{}</text>"#,
            top - 6.0,
            escape(p.title)
        );
        let _ = writeln!(
            s,
            r##"<rect x="{LEFT}" y="{top:.1}" width="{plot_w:.1}" height="{ph:.1}" fill="#fafafa" stroke="#888" stroke-width="1"/>"##
        );
        // Horizontal grid and y labels.
        let step = nice_step(hi - lo, 4.0);
        let mut v = (lo / step).ceil() * step;
        while v <= hi + 1e-9 {
            let y = y_of(v);
            let _ = writeln!(
                s,
                r##"<line x1="{LEFT}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#ddd" stroke-width="1"/>"##,
                LEFT + plot_w
            );
            let _ = writeln!(
                s,
                r##"<text x="{:.1}" y="{:.1}" font-size="10" {FONT} fill="#333" text-anchor="end">{}</text>"##,
                LEFT - 6.0,
                y + 3.5,
                label(v)
            );
            v += step;
        }
        if let Some(r) = p.reference {
            let y = y_of(r as f64);
            let _ = writeln!(
                s,
                r##"<line x1="{LEFT}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#444" stroke-width="1" stroke-dasharray="5,4"/>"##,
                LEFT + plot_w
            );
        }
        for (color, values) in &p.lines {
            // Polylines broken at missing values; isolated points as dots.
            let mut run: Vec<(f64, f64)> = Vec::new();
            let flush = |run: &mut Vec<(f64, f64)>, s: &mut String| {
                if run.len() == 1 {
                    let _ =
                        writeln!(s, r#"<circle cx="{:.1}" cy="{:.1}" r="2.5" fill="{color}"/>"#, run[0].0, run[0].1);
                } else if run.len() > 1 {
                    let pts: Vec<String> = run.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
                    let _ = writeln!(
                        s,
                        r#"<polyline points="{}" fill="none" stroke="{color}" stroke-width="1.8" stroke-linejoin="round"/>"#,
                        pts.join(" ")
                    );
                }
                run.clear();
            };
            for (i, v) in values.iter().enumerate() {
                match v {
                    Some(v) if v.is_finite() => run.push((x_of(i), y_of(*v as f64))),
                    _ => flush(&mut run, &mut s),
                }
            }
            flush(&mut run, &mut s);
        }
    }
    // Frame numbers along the bottom.
    let bottom = TOP + panels.len() as f64 * (TITLE + ph + GAP) - GAP;
    let step = nice_step(n as f64, 10.0).max(1.0) as usize;
    let mut i = 0;
    while i < n {
        let x = x_of(i);
        let _ = writeln!(
            s,
            r##"<line x1="{x:.1}" y1="{bottom:.1}" x2="{x:.1}" y2="{:.1}" stroke="#888" stroke-width="1"/>"##,
            bottom + 4.0
        );
        let _ = writeln!(
            s,
            r##"<text x="{x:.1}" y="{:.1}" font-size="10" {FONT} fill="#333" text-anchor="middle">{}</text>"##,
            bottom + 16.0,
            i + 1
        );
        i += step;
    }
    let _ = writeln!(
        s,
        r##"<text x="{:.1}" y="{:.1}" font-size="11" {FONT} fill="#333" text-anchor="middle">frame</text>"##,
        LEFT + plot_w / 2.0,
        bottom + 32.0
    );
    s.push_str("</svg>\n");
    s
}

/// The system's fonts, loaded once; `sans-serif` is DejaVu Sans when present, else the first
/// family found.
fn font_db() -> Arc<usvg::fontdb::Database> {
    static DB: OnceLock<Arc<usvg::fontdb::Database>> = OnceLock::new();
    DB.get_or_init(|| {
        let mut db = usvg::fontdb::Database::new();
        db.load_system_fonts();
        let families: Vec<String> = db.faces().flat_map(|f| f.families.iter().map(|(name, _)| name.clone())).collect();
        if let Some(name) = families.iter().find(|n| n.as_str() == "DejaVu Sans").or(families.first()) {
            db.set_sans_serif_family(name.clone());
        }
        Arc::new(db)
    })
    .clone()
}

/// True when at least one font was found, i.e. the chart will have labels.
pub fn fonts_available() -> bool {
    !font_db().is_empty()
}

fn rasterize(report: &Report, options: &PlotOptions) -> std::result::Result<tiny_skia::Pixmap, String> {
    rasterize_with(report, options, font_db())
}

fn rasterize_with(
    report: &Report,
    options: &PlotOptions,
    db: Arc<usvg::fontdb::Database>,
) -> std::result::Result<tiny_skia::Pixmap, String> {
    svg_pixmap(&plot_svg(report, options), db)
}

/// Rasterizes an SVG document drawn with the system's fonts (labels are left out, with a
/// warning, on a machine without fonts).
pub(crate) fn rasterize_svg(svg: &str) -> std::result::Result<tiny_skia::Pixmap, String> {
    svg_pixmap(svg, font_db())
}

fn svg_pixmap(svg: &str, db: Arc<usvg::fontdb::Database>) -> std::result::Result<tiny_skia::Pixmap, String> {
    if db.is_empty() {
        log::warn!("no fonts found on this system; the picture is drawn without labels");
    }
    let opt = usvg::Options { fontdb: db, ..Default::default() };
    let tree = usvg::Tree::from_str(svg, &opt).map_err(|e| e.to_string())?;
    let size = tree.size().to_int_size();
    let mut pixmap = tiny_skia::Pixmap::new(size.width(), size.height()).ok_or("the chart has no area")?;
    resvg::render(&tree, tiny_skia::Transform::default(), &mut pixmap.as_mut());
    Ok(pixmap)
}

fn rgba8(pixmap: &tiny_skia::Pixmap) -> Vec<u8> {
    pixmap
        .pixels()
        .iter()
        .flat_map(|p| {
            let c = p.demultiply();
            [c.red(), c.green(), c.blue(), c.alpha()]
        })
        .collect()
}

/// Renders the chart (straight RGBA in `0..=1`).
pub fn render_plot(report: &Report, options: &PlotOptions) -> Result<Plane<Rgba>> {
    let pixmap = rasterize(report, options).map_err(|e| Error::image("<chart>", e))?;
    let data = rgba8(&pixmap).chunks_exact(4).map(|c| [0, 1, 2, 3].map(|i| c[i] as f32 / 255.0)).collect();
    let (w, h) = (pixmap.width() as usize, pixmap.height() as usize);
    Plane::from_vec(w, h, data).ok_or_else(|| Error::image("<chart>", "inconsistent chart size"))
}

/// Renders the chart and writes it as a PNG (atomically).
pub fn save_plot(report: &Report, path: &Path, options: &PlotOptions) -> Result<()> {
    let pixmap = rasterize(report, options).map_err(|e| Error::image(path, e))?;
    img::write_png_rgba8(path, pixmap.width() as usize, pixmap.height() as usize, &rgba8(&pixmap))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::{FrameStats, Painted, Summary};

    fn report(frames: usize) -> Report {
        let series = |i: usize| (i > 0).then_some(0.5 + 0.1 * i as f32);
        Report {
            frames,
            width: 10,
            height: 10,
            exemplar: crate::eval::ExemplarSummary {
                name: "a<b>".into(),
                frames: 2,
                width: 10,
                height: 10,
                step: 1,
                scale: 1.0,
                local_contrast: Some(0.1),
                temporal_change: Some(0.1),
                motion_agreement: None,
                edge_darkening: Some(0.05),
                incoherent_change: Some(0.02),
                interior_pixels: 1,
                patch_pool: 1,
                temporal_pixels: 1,
                motion_points: 0,
            },
            painted: Painted::Alpha,
            summary: Summary {
                coverage_iou: Some(1.0),
                coverage_iou_exemplar: Some(0.98),
                local_contrast: None,
                contrast_ratio: None,
                contrast_ratio_whole: None,
                palette_distance: None,
                palette_distance_mean: None,
                palette_distance_whole: None,
                patch_nn_distance: None,
                temporal_change: None,
                temporal_change_ratio: None,
                motion_agreement: None,
                edge_darkening: None,
                edge_darkening_ratio: None,
                incoherent_change: None,
                incoherent_change_ratio: None,
                incoherent_change_ratio_depth: None,
                interior_pixels: 0,
                patch_samples: 0,
                temporal_pixels: 0,
                motion_points: 0,
                rim_frames: 0,
                incoherent_pixels: 0,
            },
            per_frame: (0..frames)
                .map(|i| FrameStats {
                    frame: i + 1,
                    coverage_iou: Some(1.0),
                    coverage_iou_exemplar: Some(0.98),
                    local_contrast: series(i),
                    contrast_ratio: series(i),
                    palette_distance: series(i).map(|v| [v, v / 2.0, v / 3.0]),
                    patch_nn_distance: series(i),
                    temporal_change: series(i),
                    temporal_change_ratio: series(i),
                    motion_agreement: series(i),
                    edge_darkening: series(i),
                    edge_darkening_ratio: series(i).map(|v| 1.0 - v),
                    incoherent_change: series(i),
                    incoherent_change_ratio: series(i),
                    incoherent_change_ratio_depth: series(i),
                })
                .collect(),
            options: Default::default(),
        }
    }

    #[test]
    fn draws_without_any_font() {
        let empty = Arc::new(usvg::fontdb::Database::new());
        let r = report(4);
        let pixmap = rasterize_with(&r, &PlotOptions::default(), empty).unwrap();
        assert_eq!(pixmap.width(), 960);
        // The lines are there (the orange of the contrast panel), the escaped name parses.
        let orange =
            pixmap.pixels().iter().filter(|p| p.red() == 0xff && p.green() == 0x7f && p.blue() == 0x0e).count();
        assert!(orange > 50, "{orange}");
        // A single frame (a dot per series) and an empty report draw too.
        assert!(rasterize_with(&report(1), &PlotOptions::default(), Arc::new(Default::default())).is_ok());
        assert!(rasterize_with(&report(0), &PlotOptions::default(), Arc::new(Default::default())).is_ok());
    }

    #[test]
    fn nice_steps_and_labels() {
        for (span, target, step) in [(1.0, 4.0, 0.5), (2.0, 4.0, 0.5), (48.0, 10.0, 5.0), (0.3, 4.0, 0.1)] {
            assert!((nice_step(span, target) - step).abs() < 1e-12, "{span} {target}");
        }
        assert_eq!(label(0.25), "0.25");
        assert_eq!(label(1.0), "1");
        assert_eq!(label(-0.0), "0");
    }
}
