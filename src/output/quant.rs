//! Palette selection and dithering for GIF frames.
//!
//! A frame's palette (at most 256 colors) is built from the pixels that frame actually
//! changes: when they hold few enough distinct colors they are used exactly; otherwise the
//! most frequent colors (large flat areas such as the background) are kept exactly, NeuQuant
//! (`color_quant`) trains the rest of the palette on the remaining pixels, and a few Lloyd
//! (k-means) iterations refine it against the pixels. Pixels are then mapped with serpentine
//! Floyd–Steinberg error diffusion, which turns the steps between palette entries of a smooth
//! watercolor gradient into fine noise instead of bands.

use std::collections::HashMap;

/// Cell side of the nearest-color search grid (16 → 16³ cells).
const CELL: i32 = 16;
/// Colors covering at least this fraction of the pixels are kept exactly.
const DOMINANT_FRACTION: usize = 100;
/// At most this many exact dominant colors.
const MAX_DOMINANT: usize = 16;
/// Lloyd iterations refining the NeuQuant palette.
const LLOYD_ITERATIONS: usize = 3;
/// Pixels used by the Lloyd iterations (regular subsample).
const LLOYD_SAMPLES: usize = 60_000;
/// NeuQuant is trained on about this many samples.
const NEUQUANT_SAMPLES: usize = 60_000;
/// Largest error (per channel, in levels) carried by error diffusion, so that colors the
/// palette cannot reach do not smear far ("error bleeding").
const MAX_ERROR: f32 = 48.0;

/// A palette with a fast exact nearest-color search.
pub(crate) struct Palette {
    colors: Vec<[u8; 3]>,
    /// Per grid cell, lazily: the palette entries that can be nearest to a point of the cell,
    /// with their smallest squared distance to the cell, sorted by it.
    cells: Vec<Option<Candidates>>,
}

/// `(smallest squared distance to the cell, palette index)`, sorted.
type Candidates = Box<[(u32, u8)]>;

#[inline]
fn dist2(a: [i32; 3], b: [u8; 3]) -> u32 {
    let d = [a[0] - b[0] as i32, a[1] - b[1] as i32, a[2] - b[2] as i32];
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) as u32
}

impl Palette {
    /// A palette of 1 to 256 colors.
    pub fn new(colors: Vec<[u8; 3]>) -> Palette {
        debug_assert!(!colors.is_empty() && colors.len() <= 256);
        let n = (256 / CELL) as usize;
        Palette { colors, cells: vec![None; n * n * n] }
    }

    pub fn colors(&self) -> &[[u8; 3]] {
        &self.colors
    }

    /// Index of the palette color nearest (Euclidean, sRGB levels) to `c` (each in `0..=255`).
    #[inline]
    pub fn nearest(&mut self, c: [i32; 3]) -> u8 {
        let n = 256 / CELL;
        let cell = ((c[0] / CELL) * n + c[1] / CELL) * n + c[2] / CELL;
        let colors = &self.colors;
        let candidates = self.cells[cell as usize].get_or_insert_with(|| {
            let lo = [c[0] / CELL * CELL, c[1] / CELL * CELL, c[2] / CELL * CELL];
            let hi = lo.map(|v| v + CELL - 1);
            let bounds: Vec<(u32, u32)> = colors
                .iter()
                .map(|p| {
                    let (mut dmin, mut dmax) = (0u32, 0u32);
                    for i in 0..3 {
                        let v = p[i] as i32;
                        let below = (lo[i] - v).max(0);
                        let above = (v - hi[i]).max(0);
                        let near = below.max(above);
                        let far = (v - lo[i]).abs().max((v - hi[i]).abs());
                        dmin += (near * near) as u32;
                        dmax += (far * far) as u32;
                    }
                    (dmin, dmax)
                })
                .collect();
            let limit = bounds.iter().map(|b| b.1).min().unwrap_or(0);
            let mut list: Vec<(u32, u8)> =
                bounds.iter().enumerate().filter(|(_, b)| b.0 <= limit).map(|(i, b)| (b.0, i as u8)).collect();
            list.sort_unstable();
            list.into_boxed_slice()
        });
        let mut best = (u32::MAX, 0u8);
        for &(dmin, i) in candidates.iter() {
            if dmin > best.0 {
                break;
            }
            let d = dist2(c, colors[i as usize]);
            if d < best.0 {
                best = (d, i);
            }
        }
        best.1
    }
}

#[inline]
fn key(c: [u8; 3]) -> u32 {
    (c[0] as u32) << 16 | (c[1] as u32) << 8 | c[2] as u32
}

#[inline]
fn unkey(k: u32) -> [u8; 3] {
    [(k >> 16) as u8, (k >> 8) as u8, k as u8]
}

/// Chooses at most `max_colors` (≥ 64) colors for `pixels` (at least one pixel).
pub(crate) fn build_palette(pixels: &[[u8; 3]], max_colors: usize) -> Vec<[u8; 3]> {
    let mut histogram: HashMap<u32, u32> = HashMap::new();
    for &p in pixels {
        *histogram.entry(key(p)).or_insert(0) += 1;
    }
    if histogram.len() <= max_colors {
        let mut keys: Vec<u32> = histogram.into_keys().collect();
        keys.sort_unstable();
        return keys.into_iter().map(unkey).collect();
    }
    // Exact dominant colors.
    let mut by_count: Vec<(u32, u32)> = histogram.iter().map(|(&k, &n)| (n, k)).collect();
    by_count.sort_unstable_by(|a, b| b.cmp(a));
    let min_count = (pixels.len() / DOMINANT_FRACTION).max(4) as u32;
    let dominant: Vec<[u8; 3]> =
        by_count.iter().take_while(|(n, _)| *n >= min_count).take(MAX_DOMINANT).map(|&(_, k)| unkey(k)).collect();
    let is_dominant = |p: [u8; 3]| dominant.contains(&p);

    // NeuQuant on the other pixels.
    let rest: Vec<u8> = pixels.iter().filter(|p| !is_dominant(**p)).flat_map(|p| [p[0], p[1], p[2], 255]).collect();
    let trained = max_colors - dominant.len();
    let samplefac = (rest.len() / 4).div_ceil(NEUQUANT_SAMPLES).clamp(1, 30) as i32;
    let nq = color_quant::NeuQuant::new(samplefac, trained, &rest);
    let mut learned: Vec<[u8; 3]> = nq.color_map_rgb().chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();

    // Lloyd refinement of the learned colors, the dominant ones staying fixed.
    let stride = pixels.len().div_ceil(LLOYD_SAMPLES).max(1);
    for _ in 0..LLOYD_ITERATIONS {
        let mut palette = Palette::new(dominant.iter().chain(&learned).copied().collect());
        let mut sums = vec![[0u64; 4]; learned.len()];
        for p in pixels.iter().step_by(stride) {
            let i = palette.nearest([p[0] as i32, p[1] as i32, p[2] as i32]) as usize;
            if i >= dominant.len() {
                let s = &mut sums[i - dominant.len()];
                for c in 0..3 {
                    s[c] += p[c] as u64;
                }
                s[3] += 1;
            }
        }
        for (color, s) in learned.iter_mut().zip(&sums) {
            if s[3] > 0 {
                *color = [0, 1, 2].map(|c| ((s[c] + s[3] / 2) / s[3]) as u8);
            }
        }
    }
    let mut out = dominant;
    for c in learned {
        if !out.contains(&c) {
            out.push(c);
        }
    }
    out
}

/// Maps `pixels` (`width × height`, row-major) to palette indices. Pixels with `skip[i]` set
/// get `skip_index` and neither receive nor pass on diffusion error. With `dither`, serpentine
/// Floyd–Steinberg error diffusion (error clamped to ±48 levels per channel).
pub(crate) fn map_pixels(
    pixels: &[[u8; 3]],
    skip: &[bool],
    width: usize,
    height: usize,
    palette: &mut Palette,
    dither: bool,
    skip_index: u8,
) -> Vec<u8> {
    let mut out = vec![skip_index; width * height];
    if !dither {
        for (i, (p, &s)) in pixels.iter().zip(skip).enumerate() {
            if !s {
                out[i] = palette.nearest([p[0] as i32, p[1] as i32, p[2] as i32]);
            }
        }
        return out;
    }
    // Error rows with one pixel of padding on each side.
    let mut current = vec![[0f32; 3]; width + 2];
    let mut next = vec![[0f32; 3]; width + 2];
    for y in 0..height {
        let forward = y % 2 == 0;
        for step in 0..width {
            let x = if forward { step } else { width - 1 - step };
            let i = y * width + x;
            if skip[i] {
                continue;
            }
            let e = current[x + 1];
            let p = pixels[i];
            let want = [0, 1, 2].map(|c| (p[c] as f32 + e[c]).clamp(0.0, 255.0));
            let idx = palette.nearest(want.map(|v| (v + 0.5) as i32));
            out[i] = idx;
            let got = palette.colors[idx as usize];
            let err = [0, 1, 2].map(|c| (want[c] - got[c] as f32).clamp(-MAX_ERROR, MAX_ERROR));
            // Forward neighbor, then the three below (backward, straight, forward).
            let (ahead, behind) = if forward { (x + 2, x) } else { (x, x + 2) };
            for c in 0..3 {
                current[ahead][c] += err[c] * (7.0 / 16.0);
                next[behind][c] += err[c] * (3.0 / 16.0);
                next[x + 1][c] += err[c] * (5.0 / 16.0);
                next[ahead][c] += err[c] * (1.0 / 16.0);
            }
        }
        std::mem::swap(&mut current, &mut next);
        next.iter_mut().for_each(|e| *e = [0.0; 3]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_matches_brute_force() {
        let mut state = 12345u32;
        let mut rnd = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state
        };
        let colors: Vec<[u8; 3]> = (0..200).map(|_| [rnd() as u8, rnd() as u8, rnd() as u8]).collect();
        let mut pal = Palette::new(colors.clone());
        for _ in 0..20_000 {
            let c = [(rnd() % 256) as i32, (rnd() % 256) as i32, (rnd() % 256) as i32];
            let best = colors.iter().map(|&p| dist2(c, p)).min().unwrap();
            let got = pal.nearest(c);
            assert_eq!(dist2(c, colors[got as usize]), best);
        }
    }

    #[test]
    fn few_colors_are_kept_exactly() {
        let px: Vec<[u8; 3]> = (0..1000).map(|i| [(i % 7) as u8 * 30, 5, 9]).collect();
        let pal = build_palette(&px, 255);
        assert_eq!(pal.len(), 7);
        assert!(px.iter().all(|p| pal.contains(p)));
    }

    #[test]
    fn dominant_colors_survive_quantization() {
        // A big flat background plus a many-colored gradient.
        let mut px = vec![[250u8, 245, 235]; 20_000];
        px.extend((0..20_000).map(|i| [(i % 256) as u8, (i / 256 % 256) as u8, 128]));
        let pal = build_palette(&px, 255);
        assert!(pal.len() <= 255);
        assert!(pal.contains(&[250, 245, 235]));
    }
}
