//! The suite's table.

use super::{Row, SuiteReport};
use crate::eval::Summary;
use std::fmt;

fn num(v: Option<f32>, digits: usize) -> String {
    match v {
        Some(v) if v.is_finite() => format!("{v:.digits$}"),
        _ => "–".to_string(),
    }
}

const HEADER: [&str; 13] = [
    "exemplar", "target", "frames", "IoU", "IoU ex", "IoU α", "contrast", "rim", "palette", "t.change", "incoh.",
    "incoh.d", "motion",
];

fn line(f: &mut fmt::Formatter<'_>, cells: &[String], notes: &str) -> fmt::Result {
    write!(f, "{:<16} {:<13} {:>6}", cells[0], cells[1], cells[2])?;
    for c in &cells[3..] {
        write!(f, " {c:>8}")?;
    }
    writeln!(f, "  {notes}")
}

fn cells(exemplar: &str, target: &str, frames: usize, s: &Summary, alpha: Option<f32>) -> Vec<String> {
    vec![
        exemplar.to_string(),
        target.to_string(),
        frames.to_string(),
        num(s.coverage_iou, 3),
        num(s.coverage_iou_exemplar, 3),
        num(alpha, 3),
        num(s.contrast_ratio, 2),
        num(s.edge_darkening_ratio, 2),
        num(s.palette_distance_mean, 4),
        num(s.temporal_change_ratio, 2),
        num(s.incoherent_change_ratio, 2),
        num(s.incoherent_change_ratio_depth, 2),
        num(s.motion_agreement, 2),
    ]
}

fn notes(r: &Row) -> String {
    let mut n = Vec::new();
    let still = r.exemplar_summary.frames == 1;
    if let Some(id) = &r.identity {
        n.push(format!("PSNR median {:.1} dB, min {:.1} (frame {})", id.psnr_median, id.psnr_min, id.psnr_min_frame));
        if still {
            n.push("a still's interior is free texture (no guide pins it), so PSNR does not measure it".into());
        }
    }
    if still && let Some(v) = r.summary.incoherent_change {
        n.push(format!("a still: incoherent change {v:.4} (no exemplar motion to compare with)"));
    }
    if !still && r.summary.contrast_ratio.is_none() {
        n.push("too thin at this size to measure its paint: no pixel lies deep enough inside for contrast, palette, rim or change".into());
    }
    if r.fitted {
        let levels = r.max_levels.map(|l| format!(", at most {l} levels")).unwrap_or_default();
        n.push(format!("fitted to its thickness: σ {}, b {}{levels}", r.blur_sigma, r.border_width));
    }
    n.join("; ")
}

impl fmt::Display for SuiteReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let long = if self.rows.iter().any(|r| r.target == "long") {
            format!(", long {} in windows of {}", self.long_frames, self.window)
        } else {
            String::new()
        };
        writeln!(
            f,
            "quality suite: targets {0}x{0} ({1} frames{long}), engine seed {2}, {3:.1} s",
            self.side, self.frames, self.seed, self.seconds
        )?;
        writeln!(
            f,
            "coverage (IoU) {}; IoU ex: what paint like the exemplar's at each distance from the edge would reach (below 1 \
             where its edge fades into the paper); IoU α: of the engine's alpha",
            self.coverage
        )?;
        writeln!(
            f,
            "contrast, rim (edge darkening), t.change (temporal change), incoh. (incoherent change): output / exemplar, \
             1 = like the exemplar; palette: W1 distance, 0 = the exemplar's colors (contrast and palette against the exemplar \
             at the same distances from the edge, the palette of a shape deeper than the exemplar's paint at the \
             exemplar's depths stretched to it); incoh.d: incoherent change against the exemplar's at the same distances from \
             the edge (its paint changes most near its advancing edge); motion: mean cosine with the target's motion \
             (a generated target's whole motion; on the exemplar's own masks the normal motion they show)"
        )?;
        writeln!(f)?;
        line(f, &HEADER.map(String::from), "notes")?;
        for r in &self.rows {
            line(f, &cells(&r.exemplar, &r.target, r.frames, &r.summary, r.coverage_alpha), &notes(r))?;
            for w in &r.windows {
                let label = format!("  {}-{}", w.first, w.last);
                let note = format!(
                    "contrast {}, rim {} of the first window",
                    num(w.contrast_vs_first, 2),
                    num(w.rim_vs_first, 2)
                );
                line(f, &cells("", &label, w.last + 1 - w.first, &w.summary, None), &note)?;
            }
        }
        if !self.sheets.is_empty() {
            writeln!(f)?;
            let dir = self.sheets[0].parent().map(|p| p.display().to_string()).unwrap_or_default();
            write!(f, "{} contact sheets in {}", self.sheets.len(), dir)?;
        }
        Ok(())
    }
}
