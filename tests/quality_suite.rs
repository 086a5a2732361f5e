//! The quality suite's structure and measures, at a reduced size: stand-in painters with
//! known answers (a flat fill, the exemplar fed back on the identity) and one small run of
//! the engine itself. Floors on the engine's numbers belong to the engine's own tests.

use fluidymation::NoProgress;
use fluidymation::img::Plane;
use fluidymation::quality::{self, PaintedFrame, Painter, RunSpec, SuiteOptions, TargetKind};
use fluidymation::{Result, eval};
use std::path::PathBuf;

/// Paints every target with one flat color inside the target mask.
struct Flat;

impl Painter for Flat {
    fn paint(&self, run: &RunSpec<'_>, emit: &mut dyn FnMut(PaintedFrame) -> Result<()>) -> Result<()> {
        for k in 0..run.frames {
            let cov = (run.coverage)(k);
            emit(PaintedFrame {
                rgb: Plane::filled(cov.width(), cov.height(), [0.3, 0.5, 0.7]),
                mask: cov.threshold(0.5),
            })?;
        }
        Ok(())
    }
}

/// Paints every target flat with a darker rim: the pixels touching the outside (the rim band
/// of the suite at a quarter of the size) darker by 0.2.
struct Rimmed;

impl Painter for Rimmed {
    fn paint(&self, run: &RunSpec<'_>, emit: &mut dyn FnMut(PaintedFrame) -> Result<()>) -> Result<()> {
        for k in 0..run.frames {
            let shape = eval::Shape::from_coverage(&(run.coverage)(k));
            let rgb = shape.sdf.map(|d| if d + 0.5 <= 1.0 { [0.4, 0.4, 0.4] } else { [0.6, 0.6, 0.6] });
            emit(PaintedFrame { rgb, mask: shape.mask })?;
        }
        Ok(())
    }
}

/// Paints the identity with the exemplar's own frames (and other targets flat).
struct Echo;

impl Painter for Echo {
    fn paint(&self, run: &RunSpec<'_>, emit: &mut dyn FnMut(PaintedFrame) -> Result<()>) -> Result<()> {
        if run.target != quality::IDENTITY {
            return Flat.paint(run, emit);
        }
        for k in 0..run.frames {
            let (f, m) = (&run.reference.frames()[k], &run.reference.masks()[k]);
            emit(PaintedFrame { rgb: f.clone(), mask: m.threshold(0.5) })?;
        }
        Ok(())
    }
}

fn small(targets: Vec<TargetKind>) -> SuiteOptions {
    SuiteOptions::default().exemplars(["ink-rims"]).targets(targets).scale(0.25).frames(6).long_frames(12).window(5)
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("fm-quality-{}-{}", name, std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn stand_ins_score_what_they_are() {
    let sheets = scratch("sheets");
    let opts = small(TargetKind::ALL.to_vec()).sheets(&sheets);
    let report = quality::run_with(&opts, &Echo, &NoProgress).unwrap();
    println!("{report}");
    // One row per target and the identity first; 128 px targets.
    let names: Vec<&str> = report.rows.iter().map(|r| r.target.as_str()).collect();
    assert_eq!(names, ["identity", "still", "growing", "shrinking", "translating", "rotating", "limb", "long"]);
    assert_eq!(report.side, 128);
    assert!(report.rows[1..].iter().all(|r| r.width == 128 && r.exemplar == "ink-rims"));
    assert_eq!(report.rows[7].frames, 12);
    assert_eq!(report.rows[1].frames, 6);

    // The exemplar fed back: identical, its own rim, its own coverage (by color, the exemplar's
    // own pale fringe below the threshold aside).
    let id = &report.rows[0];
    let psnr = id.identity.as_ref().unwrap();
    assert_eq!((psnr.psnr_median, psnr.psnr_min), (quality::PSNR_CAP, quality::PSNR_CAP));
    assert_eq!(psnr.psnr.len(), id.frames);
    assert_eq!(id.summary.edge_darkening_ratio, Some(1.0));
    assert_eq!(id.summary.contrast_ratio, Some(1.0));
    // (The flow also reads the paper around the paint, which the flattening makes uniform.)
    assert!(
        (id.summary.incoherent_change_ratio.unwrap() - 1.0).abs() < 1e-3,
        "{:?}",
        id.summary.incoherent_change_ratio
    );
    let at_depths = id.summary.incoherent_change_ratio_depth.unwrap();
    assert!((at_depths - 1.0).abs() < 1e-3, "its own depths: {at_depths}");
    assert_eq!(id.coverage_alpha, Some(1.0));
    assert!(id.summary.coverage_iou.unwrap() > 0.95, "{:?}", id.summary.coverage_iou);
    // What exemplar-like paint reaches on these masks is what the exemplar itself reaches.
    let (got, reachable) = (id.summary.coverage_iou.unwrap(), id.summary.coverage_iou_exemplar.unwrap());
    assert!((got - reachable).abs() < 0.005, "{got} vs {reachable}");
    assert!(id.exemplar_summary.edge_darkening.unwrap() > 0.05, "ink-rims has dark rims");

    // A flat fill: no texture, no rim, no change; exact coverage.
    for r in &report.rows[1..] {
        let s = &r.summary;
        assert!(s.coverage_iou.unwrap() > 0.97 && r.coverage_alpha == Some(1.0), "{}", r.target);
        if r.target == "limb" {
            // 14 px wide, a quarter of it here: no pixel 5 px inside, nor 3 px (the rim's 12
            // px scaled): nothing to measure texture, rim or change on.
            assert_eq!((s.local_contrast, s.edge_darkening, s.incoherent_change), (None, None, None));
            continue;
        }
        assert!(s.contrast_ratio.unwrap() < 1e-3, "{}: {:?}", r.target, s.contrast_ratio);
        assert!(s.edge_darkening_ratio.unwrap().abs() < 1e-3, "{}: {:?}", r.target, s.edge_darkening_ratio);
        assert!(s.incoherent_change.unwrap() < 1e-4, "{}: {:?}", r.target, s.incoherent_change);
        assert!(s.palette_distance_mean.unwrap() > 0.05);
    }

    // The long target per window: 12 frames in windows of 5, 5 and 2.
    let long = &report.rows[7];
    let w: Vec<(usize, usize)> = long.windows.iter().map(|w| (w.first, w.last)).collect();
    assert_eq!(w, [(1, 5), (6, 10), (11, 12)]);
    assert_eq!(long.windows[0].contrast_vs_first, None, "0 / 0 has no ratio");
    assert!(long.windows.iter().all(|w| w.rim_vs_first.is_none()), "no rim in the first window to keep");
    assert!(report.rows.iter().filter(|r| r.target != "long").all(|r| r.windows.is_empty()));

    // A contact sheet per run, and the table names every row.
    assert_eq!(report.sheets.len(), 8);
    let sheet = fluidymation::img::load_rgb(&sheets.join("ink-rims-limb.png")).unwrap();
    assert!(sheet.width() >= 4 * 128 && sheet.height() > 2 * 128, "{:?}", sheet.size());
    let table = report.to_string();
    for name in names {
        assert!(table.contains(name), "{name} missing from\n{table}");
    }
    assert!(table.contains("  6-10") && table.contains("PSNR median 100.0 dB"), "{table}");
    // The JSON round-trips (timings aside: serde_json may move an f64 by an ulp).
    let back: quality::SuiteReport = serde_json::from_str(&serde_json::to_string(&report).unwrap()).unwrap();
    let untimed = |r: &quality::SuiteReport| {
        r.rows.iter().map(|r| quality::Row { seconds: 0.0, measure_seconds: 0.0, ..r.clone() }).collect::<Vec<_>>()
    };
    assert_eq!(untimed(&back), untimed(&report));
    let _ = std::fs::remove_dir_all(&sheets);
}

#[test]
fn a_rim_kept_over_the_long_target_scores_one_per_window() {
    let opts = small(vec![TargetKind::Long]).identity(false).long_frames(15);
    let report = quality::run_with(&opts, &Rimmed, &NoProgress).unwrap();
    let long = &report.rows[0];
    // The luma of 0.6 inside and 0.4 on the edge: a rim of 0.2 in every frame and window.
    assert!((long.summary.edge_darkening.unwrap() - 0.2).abs() < 1e-5, "{:?}", long.summary.edge_darkening);
    assert_eq!(long.windows.len(), 3);
    for w in &long.windows {
        assert!((w.rim_vs_first.unwrap() - 1.0).abs() < 1e-5, "{:?}", w.rim_vs_first);
        assert_eq!(w.summary.rim_frames, 5);
    }
}

#[test]
fn engine_runs_the_user_pipeline_deterministically() {
    // Two small targets painted by the engine: the lanes do not change a number.
    let opts = small(vec![TargetKind::Growing, TargetKind::Limb]).identity(false).frames(5);
    let a = quality::run(&opts, &NoProgress).unwrap();
    let b = quality::run(&opts.clone().jobs(1), &NoProgress).unwrap();
    println!("{a}");
    let strip =
        |r: &quality::SuiteReport| r.rows.iter().map(|r| (r.summary.clone(), r.coverage_alpha)).collect::<Vec<_>>();
    assert_eq!(strip(&a), strip(&b));
    // Paint where the target is, with the exemplar's texture and colors (the limb, 3.5 px wide
    // at this scale, has no interior to measure texture in).
    for r in &a.rows {
        assert!(r.summary.coverage_iou.unwrap() > 0.6, "{}: {:?}", r.target, r.summary.coverage_iou);
    }
    let s = &a.rows[0].summary;
    assert!(s.contrast_ratio.unwrap() > 0.3, "{:?}", s.contrast_ratio);
    assert!(s.palette_distance_mean.unwrap() < 0.1, "{:?}", s.palette_distance_mean);
    assert!(s.edge_darkening.is_some() && s.incoherent_change.is_some() && s.motion_agreement.is_some());
    // At a quarter of the size there is nothing to fit: no blur (σ 0), and the exemplar's
    // border (10 px, 2.5 here) is already below the fit's 4-px minimum.
    for r in &a.rows {
        assert!(
            !r.fitted && r.blur_sigma == 0.0 && r.border_width == 2.5,
            "{}: fitted {} σ {} b {}",
            r.target,
            r.fitted,
            r.blur_sigma,
            r.border_width
        );
    }
}

#[test]
fn bad_options_are_named() {
    let e = quality::run(&small(vec![]).scale(0.05), &NoProgress).unwrap_err().to_string();
    assert!(e.contains("--scale"), "{e}");
    let e = quality::run(&small(vec![]).frames(1), &NoProgress).unwrap_err().to_string();
    assert!(e.contains("--frames"), "{e}");
    let e = quality::run(&small(vec![]).exemplars(["no-such-exemplar"]), &NoProgress).unwrap_err().to_string();
    assert!(e.contains("no-such-exemplar"), "{e}");
    let bad_eval = eval::EvalOptions::default().paint_threshold(5.0);
    let e = quality::run(&small(vec![]).eval(bad_eval), &NoProgress).unwrap_err().to_string();
    assert!(e.contains("--paint-threshold"), "{e}");
}

#[test]
fn command_line_prints_the_table_and_writes_sheets_and_json() {
    let dir = scratch("cli");
    let json = dir.join("report.json");
    let run = |extra: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_fluidymation"))
            .args(["quality", "-e", "ink-rims", "--scale", "0.25", "--frames", "4"])
            .args(extra)
            .output()
            .unwrap()
    };
    let o = run(&["--target", "still", "-o", dir.to_str().unwrap(), "--json", json.to_str().unwrap(), "--seed", "3"]);
    let (out, err) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{err}");
    assert!(out.contains("engine seed 3") && out.contains("ink-rims") && out.contains("still"), "{out}");
    assert!(!out.contains("identity"), "only the target asked for: {out}");
    assert!(dir.join("ink-rims-still.png").is_file() && dir.join("quality.txt").is_file());
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["rows"].as_array().unwrap().len(), 1);
    assert_eq!(v["rows"][0]["frames"], 4);
    assert!(v["rows"][0]["summary"]["coverage_iou"].as_f64().unwrap() > 0.6);
    // Mistakes are named: exit 1 for a value read after parsing, 2 for a count outside the
    // range its parser allows (a malformed command line, README *Robustness*).
    for (args, needle, code) in [
        (&["--target", "nope"][..], "--target 'nope': expected identity or one of still, growing", 1),
        (&["--target", "still", "--target-scale", "2"][..], "use --scale with `quality`", 1),
        (
            &["--target", "still", "--long-frames", "1"][..],
            "'--long-frames <LONG_FRAMES>': expected a whole number from 2",
            2,
        ),
        (&["--target", "still", "--lambda=-1"][..], "lambda", 1),
    ] {
        let o = run(args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "{args:?}: {err}");
        assert!(err.contains(needle) && !err.contains("panicked"), "{args:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
