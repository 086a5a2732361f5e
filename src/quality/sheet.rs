//! Contact sheets: a few output frames beside exemplar frames, at full pixel size, labeled.

use crate::error::{Error, Result};
use crate::eval::plot::{escape, rasterize_svg};
use crate::img::{self, Plane, Rgb};
use std::fmt::Write as _;
use std::path::Path;

const GAP: usize = 8;
const LABEL: usize = 22;
const TITLE: usize = 26;

/// A labeled row of frames.
pub(crate) struct SheetRow<'a> {
    pub label: String,
    /// (1-based frame number, frame).
    pub frames: Vec<(usize, &'a Plane<Rgb>)>,
}

/// Lays out `rows` under `title` on a light gray ground: each frame at its own pixel size
/// with its frame number above it; labels need system fonts (left out without them).
pub(crate) fn contact_sheet(title: &str, rows: &[SheetRow<'_>]) -> Plane<Rgb> {
    let row_h = |r: &SheetRow<'_>| r.frames.iter().map(|(_, f)| f.height()).max().unwrap_or(0);
    let row_w = |r: &SheetRow<'_>| r.frames.iter().map(|(_, f)| f.width() + GAP).sum::<usize>() + GAP;
    let width = rows.iter().map(row_w).max().unwrap_or(0).max(320);
    let height = TITLE + rows.iter().map(|r| LABEL * 2 + row_h(r) + GAP).sum::<usize>() + GAP;
    let mut sheet = Plane::filled(width, height, [0.86f32, 0.86, 0.86]);
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}">"#
    );
    let text = |svg: &mut String, x: usize, y: usize, size: u32, s: &str| {
        let _ = writeln!(
            svg,
            r##"<text x="{x}" y="{y}" font-size="{size}" font-family="DejaVu Sans, sans-serif" fill="#222">{}</text>"##,
            escape(s)
        );
    };
    text(&mut svg, GAP, TITLE - 8, 16, title);
    let mut y = TITLE;
    for r in rows {
        text(&mut svg, GAP, y + LABEL - 6, 14, &r.label);
        y += LABEL;
        let mut x = GAP;
        for (n, f) in &r.frames {
            text(&mut svg, x, y + LABEL - 6, 12, &format!("frame {n}"));
            for fy in 0..f.height() {
                let dst = &mut sheet.row_mut(y + LABEL + fy)[x..x + f.width()];
                dst.copy_from_slice(f.row(fy));
            }
            x += f.width() + GAP;
        }
        y += LABEL + row_h(r) + GAP;
    }
    svg.push_str("</svg>\n");
    // The labels, drawn over the frames.
    if let Ok(pixmap) = rasterize_svg(&svg) {
        for (dst, p) in sheet.data_mut().iter_mut().zip(pixmap.pixels()) {
            let c = p.demultiply();
            let a = c.alpha() as f32 / 255.0;
            if a > 0.0 {
                let src = [c.red(), c.green(), c.blue()].map(|v| v as f32 / 255.0);
                *dst = [0, 1, 2].map(|i| src[i] * a + dst[i] * (1.0 - a));
            }
        }
    }
    sheet
}

/// Writes a contact sheet as a PNG (atomically).
pub(crate) fn save_sheet(path: &Path, title: &str, rows: &[SheetRow<'_>]) -> Result<()> {
    let sheet = contact_sheet(title, rows);
    if sheet.is_empty() {
        return Err(Error::image(path, "nothing to draw"));
    }
    img::save_rgb(path, &sheet)
}
