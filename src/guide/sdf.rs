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

use crate::img::{Mask, Plane};
use rayon::prelude::*;

/// The magnitude of `dist` when the mask has no boundary (empty or full): the image diagonal
/// `√(w² + h²)`, larger than any distance between two pixels of the image.
pub fn no_boundary_distance(w: usize, h: usize) -> f32 {
    ((w * w + h * h) as f64).sqrt() as f32
}

/// Width of the column strips of phase 1.
const STRIP: usize = 64;

/// The exact signed Euclidean distance field of `mask`, positive inside (see the module docs for
/// the ½-pixel convention and the value for masks without a boundary).
pub fn sdf(mask: &Mask) -> Plane<f32> {
    let (w, h) = mask.size();
    if w == 0 || h == 0 {
        return Plane::new(w, h);
    }
    let count = mask.count();
    if count == 0 || count == w * h {
        let d = no_boundary_distance(w, h);
        return Plane::filled(w, h, if count == 0 { -d } else { d });
    }
    // "No feature in this column" is a vertical distance larger than any real one.
    let inf = (w + h) as u32;
    // Phase 1: per column, the vertical distance to the nearest inside pixel (`g_in`) and to
    // the nearest outside pixel (`g_out`), in strips of columns.
    let strips: Vec<(Vec<u32>, Vec<u32>)> = (0..w.div_ceil(STRIP))
        .into_par_iter()
        .map(|s| {
            let x0 = s * STRIP;
            let sw = STRIP.min(w - x0);
            let mut gi = vec![0u32; sw * h];
            let mut go = vec![0u32; sw * h];
            for y in 0..h {
                let m = &mask.row(y)[x0..x0 + sw];
                for i in 0..sw {
                    let (pi, po) = if y == 0 { (inf, inf) } else { (gi[(y - 1) * sw + i], go[(y - 1) * sw + i]) };
                    gi[y * sw + i] = if m[i] { 0 } else { (pi + 1).min(inf) };
                    go[y * sw + i] = if m[i] { (po + 1).min(inf) } else { 0 };
                }
            }
            for y in (0..h - 1).rev() {
                for i in 0..sw {
                    let (ni, no) = (gi[(y + 1) * sw + i] + 1, go[(y + 1) * sw + i] + 1);
                    gi[y * sw + i] = gi[y * sw + i].min(ni);
                    go[y * sw + i] = go[y * sw + i].min(no);
                }
            }
            (gi, go)
        })
        .collect();
    // Phase 2: per row, the lower envelope of parabolas.
    let mut out = Plane::new(w, h);
    out.data_mut().par_chunks_mut(w).enumerate().for_each_init(
        || RowScratch::new(w),
        |sc, (y, row)| {
            for (s, (gi, go)) in strips.iter().enumerate() {
                let x0 = s * STRIP;
                let sw = STRIP.min(w - x0);
                sc.g_in[x0..x0 + sw].copy_from_slice(&gi[y * sw..(y + 1) * sw]);
                sc.g_out[x0..x0 + sw].copy_from_slice(&go[y * sw..(y + 1) * sw]);
            }
            let RowScratch { g_in, g_out, s, t, d_in, d_out } = sc;
            edt_row(g_out, s, t, d_out);
            edt_row(g_in, s, t, d_in);
            let m = mask.row(y);
            for x in 0..w {
                row[x] =
                    if m[x] { (d_out[x] as f64).sqrt() as f32 - 0.5 } else { 0.5 - (d_in[x] as f64).sqrt() as f32 };
            }
        },
    );
    out
}

struct RowScratch {
    g_in: Vec<u32>,
    g_out: Vec<u32>,
    s: Vec<usize>,
    t: Vec<usize>,
    d_in: Vec<i64>,
    d_out: Vec<i64>,
}

impl RowScratch {
    fn new(w: usize) -> Self {
        RowScratch {
            g_in: vec![0; w],
            g_out: vec![0; w],
            s: vec![0; w],
            t: vec![0; w],
            d_in: vec![0; w],
            d_out: vec![0; w],
        }
    }
}

/// Meijster's second phase on one row: `out[x] = min_i (x − i)² + g[i]²`, exact in integers.
fn edt_row(g: &[u32], s: &mut [usize], t: &mut [usize], out: &mut [i64]) {
    let n = g.len();
    let gg = |i: usize| (g[i] as i64) * (g[i] as i64);
    let f = |x: usize, i: usize| {
        let d = x as i64 - i as i64;
        d * d + gg(i)
    };
    // The first x at which the parabola of `u` lies below that of `i` (i < u).
    let sep = |i: usize, u: usize| {
        let (ii, uu) = (i as i64, u as i64);
        (uu * uu - ii * ii + gg(u) - gg(i)).div_euclid(2 * (uu - ii))
    };
    let mut q: isize = 0;
    s[0] = 0;
    t[0] = 0;
    for u in 1..n {
        while q >= 0 && f(t[q as usize], s[q as usize]) > f(t[q as usize], u) {
            q -= 1;
        }
        if q < 0 {
            q = 0;
            s[0] = u;
        } else {
            let wv = 1 + sep(s[q as usize], u);
            if wv < n as i64 {
                q += 1;
                s[q as usize] = u;
                t[q as usize] = wv as usize;
            }
        }
    }
    for u in (0..n).rev() {
        out[u] = f(u, s[q as usize]);
        if u == t[q as usize] {
            q -= 1;
        }
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
    fn large_mask_matches_brute_force_on_a_sample() {
        // Wider than one phase-1 strip, with a single inside pixel.
        let mut mask = Plane::filled(150, 20, false);
        mask.set(140, 3, true);
        let d = sdf(&mask);
        assert!((d.get(0, 19) - (0.5 - ((140.0f64 * 140.0 + 16.0 * 16.0).sqrt() as f32))).abs() < 1e-4);
        assert_eq!(d.get(140, 3), 0.5);
    }
}
