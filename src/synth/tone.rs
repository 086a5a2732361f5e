//! Tone matching by depth (not in the papers): the output's pigment density at each distance
//! from the edge is brought to the exemplar's at that distance, in the frames its matches
//! come from ([`ParamsBuilder::tone_match`](super::ParamsBuilder::tone_match)).
//!
//! A target larger than the exemplar's paint is assembled from many pieces of it, and the
//! search stitches them more easily from the flat, pale parts of the rim band than from its
//! blotchy dark ones: the matches sit on exemplar pixels paler than the exemplar's mean at the
//! same depth of the same frame, and the output is paler than the exemplar at every depth of
//! its rim band (the measurements are in the builder's documentation). The density
//! `D = −ln(c / paper)` of each channel is what pigment adds (Beer–Lambert: a layer twice as
//! thick doubles it), so the correction scales it: the mean density of the output's pixels at
//! depth d is brought to the mean, over the same pixels, of the exemplar's density at depth d
//! in the frame each pixel is matched to. Paper stays paper, a blotch darkens with the band it
//! lies in, and an output that is the exemplar (the identity) is left as it is. The grain is
//! added after (module `vote`), at its own amplitude.

use super::nnf::Nnf;
use super::vote::with_grain;
use crate::guide::FrameGuides;
use crate::img::{Mask, Plane, Rgb};

/// Depth bins of the profile, 1 px each; deeper pixels share the last.
const DEPTHS: usize = 64;
/// Pixels a bin of an exemplar frame needs to stand on its own; a bin with fewer takes the
/// value of the nearest shallower bin that has them.
const MIN_EXEMPLAR: usize = 24;
/// Output pixels a depth bin needs for its density to be corrected.
const MIN_OUTPUT: usize = 24;
/// Bounds of the correction factor.
const RATIO: (f32, f32) = (0.5, 2.0);

/// Pigment density `−ln(c / paper)` per channel (0 for paper or lighter).
#[inline]
fn density(c: Rgb, paper: Rgb) -> [f32; 3] {
    std::array::from_fn(|k| -(c[k] / paper[k].max(1e-3)).clamp(1e-3, 1.0).ln())
}

/// The exemplar's mean pigment density per frame and depth bin.
pub(crate) struct ToneProfile {
    per_frame: Vec<[[f32; 3]; DEPTHS]>,
}

impl ToneProfile {
    /// The profile of the exemplar frames `frames` with their guides, over the paper color `paper`.
    pub(crate) fn new(frames: &[Plane<Rgb>], guides: &[FrameGuides], paper: Rgb) -> ToneProfile {
        let per_frame = frames
            .iter()
            .zip(guides)
            .map(|(f, g)| {
                let mut sum = [[0.0f64; 3]; DEPTHS];
                let mut n = [0usize; DEPTHS];
                for ((c, &m), &d) in f.data().iter().zip(g.mask.data()).zip(g.dist.data()) {
                    if m {
                        let b = bin(d);
                        let dn = density(*c, paper);
                        for k in 0..3 {
                            sum[b][k] += dn[k] as f64;
                        }
                        n[b] += 1;
                    }
                }
                let mut out = [[0.0f32; 3]; DEPTHS];
                let mut last = [0.0f32; 3];
                for b in 0..DEPTHS {
                    if n[b] >= MIN_EXEMPLAR {
                        last = std::array::from_fn(|k| (sum[b][k] / n[b] as f64) as f32);
                    }
                    out[b] = last;
                }
                out
            })
            .collect();
        ToneProfile { per_frame }
    }
}

/// The depth bin of a signed distance (positive inside).
#[inline]
fn bin(d: f32) -> usize {
    (d.max(0.0) as usize).min(DEPTHS - 1)
}

/// Brings the output to the exemplar's density per depth: per depth bin of the target (`dist`,
/// inside `mask`), the mean density of the exemplar at that depth in the frames the bin's
/// matches use, over the output's mean density there; each channel's density of the low-pass
/// `rgb` (the field's window, row-major) is scaled by that ratio (bounded, linear between bin
/// centers). The output is `rgb` with `grain` added ([`with_grain`]; none when `grain` is
/// empty): its density is what is compared, so that where the output is the exemplar the ratio
/// is 1 (the mean density of a low-pass is not that of the colors with their grain).
pub(crate) fn match_tone(
    rgb: &mut [Rgb],
    grain: &[Rgb],
    field: &Nnf,
    mask: &Mask,
    dist: &Plane<f32>,
    prof: &ToneProfile,
    paper: Rgb,
) {
    let mut want = [[0.0f64; 3]; DEPTHS];
    let mut have = [[0.0f64; 3]; DEPTHS];
    let mut n = [0usize; DEPTHS];
    let frames = prof.per_frame.len();
    for (q, m) in field.data.iter().enumerate() {
        let (x, y) = (q % field.w, q / field.w);
        if !m.ok || !mask.get(x, y) || (m.i as usize) >= frames {
            continue;
        }
        let b = bin(dist.get(x, y));
        let r = prof.per_frame[m.i as usize][b];
        let d = density(grain.get(q).map_or(rgb[q], |&g| with_grain(rgb[q], g)), paper);
        for k in 0..3 {
            want[b][k] += r[k] as f64;
            have[b][k] += d[k] as f64;
        }
        n[b] += 1;
    }
    let ratio: Vec<[f32; 3]> = (0..DEPTHS)
        .map(|b| {
            std::array::from_fn(|k| {
                if n[b] < MIN_OUTPUT || have[b][k] <= 1e-6 {
                    1.0
                } else {
                    ((want[b][k] / have[b][k]) as f32).clamp(RATIO.0, RATIO.1)
                }
            })
        })
        .collect();
    for (q, c) in rgb.iter_mut().enumerate() {
        let (x, y) = (q % field.w, q / field.w);
        if !mask.get(x, y) {
            continue;
        }
        // Linear between the bin centers (b + 0.5).
        let t = (dist.get(x, y).max(0.0) - 0.5).clamp(0.0, (DEPTHS - 1) as f32);
        let (b0, f) = (t as usize, t.fract());
        let b1 = (b0 + 1).min(DEPTHS - 1);
        let d = density(*c, paper);
        *c = std::array::from_fn(|k| {
            if d[k] <= 0.0 {
                return c[k];
            }
            let r = ratio[b0][k] * (1.0 - f) + ratio[b1][k] * f;
            paper[k] * (-d[k] * r).exp()
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::nnf::Match;
    use crate::synth::tests::disc_exemplar;

    /// The field that matches every pixel of frame `i` to itself.
    fn identity(w: usize, h: usize, i: u16) -> Nnf {
        let mut f = Nnf::new(w, h);
        for (q, m) in f.data.iter_mut().enumerate() {
            *m = Match { x: (q % w) as f32, y: (q / w) as f32, i, ok: true, ..Match::NONE };
        }
        f
    }

    /// The largest difference of any channel between `a` and `b`.
    fn largest_difference(a: impl Iterator<Item = Rgb>, b: &[Rgb]) -> f32 {
        a.zip(b).flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs())).fold(0.0, f32::max)
    }

    /// Mean density of channel `k` of `rgb` over the pixels of `mask` at depth bin `b`.
    fn mean_density(rgb: &[Rgb], mask: &Mask, dist: &Plane<f32>, k: usize, b: usize) -> f32 {
        let (mut s, mut n) = (0.0, 0);
        for (q, c) in rgb.iter().enumerate() {
            let (x, y) = (q % mask.width(), q / mask.width());
            if mask.get(x, y) && bin(dist.get(x, y)) == b {
                s += density(*c, [1.0; 3])[k];
                n += 1;
            }
        }
        s / n.max(1) as f32
    }

    #[test]
    fn the_exemplar_itself_is_left_as_it_is() {
        let (frames, guides) = disc_exemplar(64, 64, 4, 3);
        let prof = ToneProfile::new(&frames, &guides, [1.0; 3]);
        let (g, full) = (&guides[2], &frames[2]);
        let mut rgb = full.data().to_vec();
        match_tone(&mut rgb, &[], &identity(64, 64, 2), &g.mask, &g.dist, &prof, [1.0; 3]);
        let worst = largest_difference(rgb.iter().copied(), full.data());
        assert!(worst < 1e-4, "the identity changed by {worst}");
        // Split into a low-pass and its grain, as the output's vote is corrected before the
        // grain is added back: the low-pass is paler in density than the colors with their
        // grain, and that must not read as pale.
        let mut low = crate::img::gaussian_blur(full, 1.5).data().to_vec();
        let grain: Vec<Rgb> = full.data().iter().zip(&low).map(|(c, l)| std::array::from_fn(|k| c[k] - l[k])).collect();
        match_tone(&mut low, &grain, &identity(64, 64, 2), &g.mask, &g.dist, &prof, [1.0; 3]);
        let out = low.iter().zip(&grain).map(|(l, gr)| with_grain(*l, *gr));
        let worst = largest_difference(out, full.data());
        assert!(worst < 1e-4, "the identity split into low-pass and grain changed by {worst}");
    }

    #[test]
    fn a_pale_output_gets_the_exemplars_density_at_each_depth() {
        let (frames, guides) = disc_exemplar(64, 64, 4, 5);
        let prof = ToneProfile::new(&frames, &guides, [1.0; 3]);
        let g = &guides[3];
        // The exemplar's own frame with half its pigment: paler at every depth.
        let pale: Vec<Rgb> = frames[3].data().iter().map(|c| c.map(|v| v.sqrt())).collect();
        let mut rgb = pale.clone();
        match_tone(&mut rgb, &[], &identity(64, 64, 3), &g.mask, &g.dist, &prof, [1.0; 3]);
        for b in [0, 2, 5, 9] {
            for k in 0..3 {
                let want = mean_density(frames[3].data(), &g.mask, &g.dist, k, b);
                let was = mean_density(&pale, &g.mask, &g.dist, k, b);
                let got = mean_density(&rgb, &g.mask, &g.dist, k, b);
                assert!((was - want / 2.0).abs() < 1e-3 * want.max(1e-3), "the test's output is half as dense");
                // Between bin centers the ratio is interpolated: within a few percent.
                assert!((got - want).abs() < 0.05 * want, "bin {b} channel {k}: {got} against the exemplar's {want}");
            }
        }
        // Paper (here: outside the mask) is not touched.
        for (q, (a, b)) in rgb.iter().zip(&pale).enumerate() {
            if !g.mask.get(q % 64, q / 64) {
                assert_eq!(a, b);
            }
        }
    }

    #[test]
    fn paper_colored_paint_and_unmatched_pixels_stay() {
        let (frames, guides) = disc_exemplar(48, 48, 3, 7);
        let prof = ToneProfile::new(&frames, &guides, [1.0; 3]);
        let g = &guides[1];
        // Every other pixel unmatched; the matched ones paler than the exemplar.
        let mut field = identity(48, 48, 1);
        for (q, m) in field.data.iter_mut().enumerate() {
            if q % 2 == 1 {
                *m = Match::NONE;
            }
        }
        let mut rgb: Vec<Rgb> = frames[1].data().iter().map(|c| c.map(|v| v.sqrt())).collect();
        rgb[24 * 48 + 24] = [1.0; 3]; // a paper-colored pixel in the middle of the disc
        let before = rgb.clone();
        match_tone(&mut rgb, &[], &field, &g.mask, &g.dist, &prof, [1.0; 3]);
        assert_eq!(rgb[24 * 48 + 24], [1.0; 3], "paper has no pigment to scale");
        let darker = rgb.iter().zip(&before).filter(|(a, b)| a[0] < b[0] - 1e-3).count();
        assert!(darker > 200, "the pale paint darkened ({darker} pixels)");
    }
}
