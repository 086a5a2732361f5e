//! Contact sheets: a few frames of an exemplar side by side, with their masks below.

use super::Exemplar;
use crate::img::{Plane, Rgb, resize_bilinear};

/// Draws a contact sheet of `ex`: up to `columns` frames spread evenly over the sequence
/// (first and last included) in the top row, their masks (white on black) in the bottom
/// row, each cell scaled down to at most `cell` pixels on its longer side, 2 px gaps.
pub fn contact_sheet(ex: &Exemplar, columns: usize, cell: usize) -> Plane<Rgb> {
    let n = ex.len();
    let cols = columns.clamp(1, n.max(1));
    let picks: Vec<usize> =
        if cols == 1 { vec![0] } else { (0..cols).map(|c| (c * (n - 1) + (cols - 1) / 2) / (cols - 1)).collect() };
    let (w, h) = (ex.width(), ex.height());
    let s = (cell.max(1) as f32 / w.max(h) as f32).min(1.0);
    let (cw, ch) = (((w as f32 * s).round() as usize).max(1), ((h as f32 * s).round() as usize).max(1));
    let gap = 2;
    let sheet_w = cols * cw + (cols - 1) * gap;
    let sheet_h = 2 * ch + gap;
    let mut sheet = Plane::filled(sheet_w, sheet_h, [0.25f32, 0.25, 0.25]);
    for (c, &i) in picks.iter().enumerate() {
        let f = resize_bilinear(&ex.frames[i], cw, ch);
        let m = resize_bilinear(&ex.masks[i], cw, ch);
        let x0 = c * (cw + gap);
        for y in 0..ch {
            for x in 0..cw {
                sheet.set(x0 + x, y, f.get(x, y));
                let v = m.get(x, y).clamp(0.0, 1.0);
                sheet.set(x0 + x, ch + gap + y, [v, v, v]);
            }
        }
    }
    sheet
}
