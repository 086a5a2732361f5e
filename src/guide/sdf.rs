//! The signed distance field `I^dist` (thesis §3.4): exact Euclidean distances by Meijster's
//! linear-time algorithm (Meijster, Roerdink, Hesselink 2000), columns then rows, both phases
//! parallel.
//!
//! **Convention.** Pixel centres sit at integer coordinates. For a pixel `p` inside the mask,
//! `dist(p) = min_{q ∉ mask} ‖p − q‖ − ½`; for `p` outside, `dist(p) = −(min_{q ∈ mask} ‖p − q‖ − ½)`.
//! The thesis's `D_I` minus ½ in magnitude: the zero level set then lies on the pixel edges
//! between the mask and the paper, so the rim pixels are at `+½` inside and `−½` outside,
//! `|dist| ≥ ½` everywhere, and the field is (up to pixelization) the continuous signed distance
//! to the mask's outline. A pixel at the image edge is not "next to" anything outside the image:
//! only image pixels count.
//!
//! **No boundary.** When the other set is empty (an empty mask, or a mask covering the whole
//! image) every pixel gets `±`[`no_boundary_distance`]`(w, h)` (the image diagonal, larger than
//! any real distance): positive for a full mask, negative for an empty one. No infinities.
//!
//! This is the crate's one exact distance transform: the metrics ([`crate::eval::Shape`], which
//! keeps its own `±(w + h)` for masks without a boundary) and the border-width estimate
//! ([`crate::exemplar::border`]) use it too.

use crate::img::{Mask, Plane, Rect};
use rayon::prelude::*;

/// The magnitude of `dist` when the mask has no boundary (empty or full): the image diagonal
/// `√(w² + h²)`, larger than any distance between two pixels of the image.
pub fn no_boundary_distance(w: usize, h: usize) -> f32 {
    ((w * w + h * h) as f64).sqrt() as f32
}

/// The largest of the distances `dist` over the pixels of `mask`: how deep its paint reaches
/// (0 for an empty mask).
pub(crate) fn deepest_inside(dist: &Plane<f32>, mask: &Mask) -> f32 {
    dist.data().iter().zip(mask.data()).filter(|(_, m)| **m).map(|(&d, _)| d).fold(0.0, f32::max)
}

/// The depths at which a shape reads a paint whose own depth is `reach` (not in the papers):
/// the signed distances `dist` of `mask` with each 4-connected part deeper than its paint
/// stretched onto the paint's depths.
///
/// Paint keeps its edge as it spreads, so the band within `band` pixels of the edge keeps its
/// depths. Deeper than that, a part whose deepest pixel lies at `D` greater than `R =
/// reach(part)` (the part's pixels as indices into `dist`; `None` leaves the part as it is)
/// reads `d' = b + (d − b)·(R − b)/(D − b)`: its middle is the paint's middle and the depths
/// between are the paint's depths between, as the same paint laid over a larger area would
/// be. Parts no deeper than their paint, and paint no deeper than the band, keep their
/// depths; so does everything outside `mask`.
pub(crate) fn stretched_depths(
    dist: &Plane<f32>,
    mask: &Mask,
    band: f32,
    mut reach: impl FnMut(&[usize]) -> Option<f32>,
) -> Plane<f32> {
    let (w, h) = mask.size();
    let mut out = dist.clone();
    for (part, _) in crate::img::components(mask.data(), w, h, true) {
        let deepest = part.iter().map(|&q| dist.data()[q]).fold(0.0, f32::max);
        let Some(r) = reach(&part) else { continue };
        if deepest <= r || r <= band {
            continue;
        }
        let k = (r - band) / (deepest - band);
        let data = out.data_mut();
        for &q in &part {
            if data[q] > band {
                data[q] = band + (data[q] - band) * k;
            }
        }
    }
    out
}

/// Width of the column strips of phase 1.
const STRIP: usize = 64;

/// The exact signed Euclidean distance field of `mask`, positive inside (see the module docs for
/// the ½-pixel convention and the value for masks without a boundary).
///
/// Only what can matter is computed: the distance to the nearest inside pixel (needed by every
/// outside pixel) from parabolas whose apexes lie in the columns of the mask's bounding box, and
/// the distance to the nearest outside pixel (needed by the inside pixels) inside that box grown
/// by one pixel, where that nearest outside pixel always is.
pub fn sdf(mask: &Mask) -> Plane<f32> {
    let (w, h) = mask.size();
    if w == 0 || h == 0 {
        return Plane::new(w, h);
    }
    // Bounding box of the inside pixels.
    let Some(Rect { x0, y0, x1, y1 }) = mask.bounding_box() else {
        return Plane::filled(w, h, -no_boundary_distance(w, h));
    };
    if (x1 - x0, y1 - y0) == (w, h) && mask.data().iter().all(|&b| b) {
        return Plane::filled(w, h, no_boundary_distance(w, h));
    }
    // "No feature in this column" is a vertical distance larger than any real one.
    let inf = (w + h) as u32;
    // Phase 1: per column, the vertical distance to the nearest inside pixel over the whole
    // height (columns x0..x1), and to the nearest outside pixel inside the grown box.
    let (ox0, ox1, oy0, oy1) = (x0.saturating_sub(1), (x1 + 1).min(w), y0.saturating_sub(1), (y1 + 1).min(h));
    let g_in = column_distances(mask, x0, x1, 0, h, true, inf);
    let g_out = column_distances(mask, ox0, ox1, oy0, oy1, false, inf);
    // Phase 2: per row, the lower envelope of parabolas.
    let mut out = Plane::new(w, h);
    out.data_mut().par_chunks_mut(w).enumerate().for_each_init(
        || RowScratch::new(w),
        |sc, (y, row)| {
            g_in.row(y, &mut sc.g[..x1 - x0]);
            envelope(&sc.g[..x1 - x0], x0, 0, w, &mut sc.s, &mut sc.t, &mut sc.d);
            let m = mask.row(y);
            for (o, &d) in row.iter_mut().zip(&sc.d) {
                *o = 0.5 - (d as f64).sqrt() as f32;
            }
            if (y0..y1).contains(&y) {
                g_out.row(y - oy0, &mut sc.g[..ox1 - ox0]);
                envelope(&sc.g[..ox1 - ox0], ox0, x0, x1, &mut sc.s, &mut sc.t, &mut sc.d);
                for x in x0..x1 {
                    if m[x] {
                        row[x] = (sc.d[x] as f64).sqrt() as f32 - 0.5;
                    }
                }
            }
        },
    );
    out
}

/// Vertical distances of phase 1 for columns `cx0..cx1` and rows `ry0..ry1`, to the nearest
/// pixel whose mask value is `target`, stored in strips of [`STRIP`] columns.
struct ColumnDistances {
    cx0: usize,
    cx1: usize,
    strips: Vec<Vec<u32>>,
}

impl ColumnDistances {
    /// Row `r` (relative to `ry0`) into `out` (`cx1 − cx0` values).
    fn row(&self, r: usize, out: &mut [u32]) {
        for (k, strip) in self.strips.iter().enumerate() {
            let sx = k * STRIP;
            let sw = STRIP.min(self.cx1 - self.cx0 - sx);
            out[sx..sx + sw].copy_from_slice(&strip[r * sw..(r + 1) * sw]);
        }
    }
}

fn column_distances(
    mask: &Mask,
    cx0: usize,
    cx1: usize,
    ry0: usize,
    ry1: usize,
    target: bool,
    inf: u32,
) -> ColumnDistances {
    let n = ry1 - ry0;
    let strips = (0..(cx1 - cx0).div_ceil(STRIP))
        .into_par_iter()
        .map(|k| {
            let x0 = cx0 + k * STRIP;
            let sw = STRIP.min(cx1 - x0);
            let mut g = vec![0u32; sw * n];
            for r in 0..n {
                let m = &mask.row(ry0 + r)[x0..x0 + sw];
                for i in 0..sw {
                    let prev = if r == 0 { inf } else { g[(r - 1) * sw + i] };
                    g[r * sw + i] = if m[i] == target { 0 } else { (prev + 1).min(inf) };
                }
            }
            for r in (0..n.saturating_sub(1)).rev() {
                for i in 0..sw {
                    let below = g[(r + 1) * sw + i] + 1;
                    g[r * sw + i] = g[r * sw + i].min(below);
                }
            }
            g
        })
        .collect();
    ColumnDistances { cx0, cx1, strips }
}

struct RowScratch {
    g: Vec<u32>,
    s: Vec<usize>,
    t: Vec<f64>,
    d: Vec<i64>,
}

impl RowScratch {
    fn new(w: usize) -> Self {
        RowScratch { g: vec![0; w], s: vec![0; w], t: vec![0.0; w], d: vec![0; w] }
    }
}

/// Meijster's second phase on one row: `out[x] = min_i (x − i)² + g_i²` for `x` in `e0..e1`,
/// over apex columns `i = c0 + k` with vertical distances `g[k]`. The squared distances are
/// exact integers; the separation points are computed in `f64`, which decides every comparison
/// exactly (numerators and denominators are integers far below 2⁵³, and a quotient that is not
/// an integer is at least 1/denominator away from one).
fn envelope(g: &[u32], c0: usize, e0: usize, e1: usize, s: &mut [usize], t: &mut [f64], out: &mut [i64]) {
    let gg = |i: usize| {
        let v = g[i - c0] as i64;
        v * v
    };
    // Where the parabola of `u` starts to lie below that of `i` (i < u).
    let sep = |i: usize, u: usize| {
        let (ii, uu) = (i as i64, u as i64);
        (uu * uu - ii * ii + gg(u) - gg(i)) as f64 / (2 * (uu - ii)) as f64
    };
    let mut q = 0;
    s[0] = c0;
    t[0] = f64::NEG_INFINITY;
    for u in c0 + 1..c0 + g.len() {
        let mut x = sep(s[q], u);
        while x <= t[q] {
            // The new parabola is below parabola q everywhere q was lowest: drop q.
            if q == 0 {
                break;
            }
            q -= 1;
            x = sep(s[q], u);
        }
        if q == 0 && x <= t[0] {
            s[0] = u;
            continue;
        }
        if x < e1 as f64 {
            q += 1;
            s[q] = u;
            t[q] = x;
        }
    }
    let mut k = 0;
    for (x, o) in out.iter_mut().enumerate().take(e1).skip(e0) {
        while k < q && t[k + 1] <= x as f64 {
            k += 1;
        }
        let d = x as i64 - s[k] as i64;
        *o = d * d + gg(s[k]);
    }
}

/// The same field by brute force, `O(n²)`: the reference the fast version is tested against.
#[cfg(test)]
pub(crate) fn sdf_brute_force(mask: &Mask) -> Plane<f32> {
    let (w, h) = mask.size();
    let count = mask.count();
    if count == 0 || count == w * h {
        let d = no_boundary_distance(w, h);
        return Plane::filled(w, h, if count == 0 { -d } else { d });
    }
    Plane::from_fn(w, h, |x, y| {
        let inside = mask.get(x, y);
        let mut best = i64::MAX;
        for qy in 0..h {
            for qx in 0..w {
                if mask.get(qx, qy) != inside {
                    let (dx, dy) = (qx as i64 - x as i64, qy as i64 - y as i64);
                    best = best.min(dx * dx + dy * dy);
                }
            }
        }
        let d = (best as f64).sqrt() as f32 - 0.5;
        if inside { d } else { -d }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn mask_strategy() -> impl Strategy<Value = Mask> {
        (1usize..24, 1usize..24, 0.0f64..1.0, any::<u64>()).prop_map(|(w, h, density, seed)| {
            // A tiny deterministic generator, so shrinking keeps the same masks.
            let mut s = seed | 1;
            Plane::from_fn(w, h, |_, _| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                ((s >> 11) as f64 / (1u64 << 53) as f64) < density
            })
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]
        #[test]
        fn matches_brute_force(mask in mask_strategy()) {
            let fast = sdf(&mask);
            let slow = sdf_brute_force(&mask);
            for (a, b) in fast.data().iter().zip(slow.data()) {
                prop_assert!((a - b).abs() <= 1e-5, "{} vs {}", a, b);
            }
        }
    }

    #[test]
    fn convention_and_degenerate_masks() {
        let mask = Plane::from_fn(7, 1, |x, _| (2..5).contains(&x));
        let d = sdf(&mask);
        assert_eq!(d.row(0), &[-1.5, -0.5, 0.5, 1.5, 0.5, -0.5, -1.5]);
        let full = sdf(&Plane::filled(3, 4, true));
        assert!(full.data().iter().all(|&v| v == 5.0));
        let empty = sdf(&Plane::filled(3, 4, false));
        assert!(empty.data().iter().all(|&v| v == -5.0));
        assert!(sdf(&Plane::new(0, 3)).is_empty());
    }

    #[test]
    fn crop_and_edge_cases_match_brute_force() {
        // Touching every image edge, two components, a one-column gap, thin lines.
        let cases = [
            Plane::from_fn(30, 20, |x, y| x < 4 || y == 19 || (10..12).contains(&x) && y > 5),
            Plane::from_fn(25, 25, |x, y| (x + y) % 7 == 0),
            Plane::from_fn(40, 9, |x, y| (5..9).contains(&x) && y > 2 || (11..30).contains(&x) && y < 3),
            Plane::from_fn(1, 12, |_, y| y == 4),
            Plane::from_fn(12, 1, |x, _| x != 4),
        ];
        for m in cases {
            assert_eq!(sdf(&m), sdf_brute_force(&m));
        }
    }

    #[test]
    fn large_mask_matches_brute_force_on_a_sample() {
        // Wider than one phase-1 strip, with a single inside pixel.
        let mut mask = Plane::filled(150, 20, false);
        mask.set(140, 3, true);
        let d = sdf(&mask);
        assert!((d.get(0, 19) - (0.5 - ((140.0f64 * 140.0 + 16.0 * 16.0).sqrt() as f32))).abs() < 1e-4);
        assert_eq!(d.get(140, 3), 0.5);
    }

    #[test]
    fn a_part_deeper_than_its_paint_is_stretched_onto_it() {
        // A disc 40 px deep and one 10 px deep; the paint reaches 20 px, its band is 5 px.
        let mask = Plane::from_fn(140, 90, |x, y| {
            let d = |cx: f32, cy: f32| ((x as f32 - cx).powi(2) + (y as f32 - cy).powi(2)).sqrt();
            d(45.0, 45.0) < 40.0 || d(115.0, 45.0) < 10.0
        });
        let dist = sdf(&mask);
        let out = stretched_depths(&dist, &mask, 5.0, |_| Some(20.0));
        // The deep disc's middle reads the paint's deepest, its band its own depths, and the
        // depths between keep their order.
        assert!((out.get(45, 45) - 20.0).abs() < 1e-3, "{}", out.get(45, 45));
        for (x, y) in [(45, 45), (25, 45), (12, 45), (8, 45), (6, 45), (45, 80)] {
            let (d, o) = (dist.get(x, y), out.get(x, y));
            let want = if d <= 5.0 { d } else { 5.0 + (d - 5.0) * 15.0 / (dist.get(45, 45) - 5.0) };
            assert!((o - want).abs() < 1e-4, "({x}, {y}): {d} -> {o}, expected {want}");
        }
        // The shallow disc, no deeper than the paint, and the paper keep theirs.
        for (x, y) in [(115, 45), (110, 45), (0, 0), (100, 10)] {
            assert_eq!(out.get(x, y), dist.get(x, y));
        }
        // No paint depth, or one within the band: nothing moves.
        assert_eq!(stretched_depths(&dist, &mask, 5.0, |_| None), dist);
        assert_eq!(stretched_depths(&dist, &mask, 5.0, |_| Some(4.0)), dist);
    }
}
