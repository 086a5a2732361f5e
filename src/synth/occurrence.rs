//! The 3D occurrence map Ω* (paper §3.5, thesis §3.3): how many rotated n × n × (2r+1) boxes
//! of the current field cover each exemplar voxel (i, x, y), and the uniformity penalty
//! `Ω(p′) = Ω*(p′)/(n²·ω*)` with `ω* = n²(2r+1)·|T_seg|/|S_seg|` per segment.
//!
//! Each matched pixel splats its rotated n × n window into its own frame i only (n² updates
//! whatever r is); the box along time is a running sum over 2r + 1 frames. Each thread splats
//! a part of the target into its own array and the arrays are added: integer sums do not depend
//! on the order (deterministic for any thread count). The splat arrays and the features
//! carrying the penalty are kept for the whole level ([`Occurrence`]); one parallel pass over
//! the exemplar's pixels adds the parts, runs the sum along time, writes the penalty and clears
//! the arrays for the next update.
//!
//! The same lane carries the contrast balance ([`contrast_excess`], not in the papers): every
//! voxel of a contrast bin that the field uses more than the exemplar holds it pays a charge,
//! so that the search cannot drift to the exemplar's flattest paint, which Ω* (counting
//! positions) does not see.

use super::nnf::Nnf;
use super::params::PATCH;
use super::patch::{Center, OFFS, tap_offsets};
use super::source::{CONTRAST_BINS, FLAG_LANE, Feat, IN_MASK, INTERIOR, NO_BIN, OMEGA_LANE, SourceLevel};
use super::target::TargetLevel;
use rayon::prelude::*;

/// Adds the rotated n × n window of every matched in-mask pixel of `nnf`, in its own frame,
/// into `marks` (one zeroed array of the level's padded size per part of the target). The
/// voxels of a window are the pixels the patch error reads for it ([`tap_offsets`]).
fn mark(src: &SourceLevel, nnf: &Nnf, tgt: &TargetLevel, marks: &mut [Vec<i32>]) {
    let per = tgt.active.len().div_ceil(marks.len()).max(1);
    marks.par_iter_mut().zip(tgt.active.par_chunks(per)).for_each(|(hits, chunk)| {
        #[cfg(target_arch = "x86_64")]
        {
            if super::patch::has_avx2() {
                // SAFETY: the CPU supports AVX2 (checked above).
                return unsafe { mark_part_avx2(src, nnf, tgt, chunk, hits) };
            }
        }
        mark_part(src, nnf, tgt, chunk, hits, tap_offsets)
    });
}

/// [`mark_part`] compiled for AVX2, with the AVX2 tap offsets (the same values).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn mark_part_avx2(src: &SourceLevel, nnf: &Nnf, tgt: &TargetLevel, chunk: &[u32], hits: &mut [i32]) {
    mark_part(src, nnf, tgt, chunk, hits, |stride, at| super::patch::tap_offsets_avx2(stride, at))
}

/// The windows of the target pixels `chunk` added into `hits`.
#[inline(always)]
fn mark_part(
    src: &SourceLevel,
    nnf: &Nnf,
    tgt: &TargetLevel,
    chunk: &[u32],
    hits: &mut [i32],
    offsets: impl Fn(usize, Center) -> [i32; OFFS],
) {
    for &q in chunk {
        let q = q as usize;
        if tgt.info[q].flags & IN_MASK == 0 {
            continue;
        }
        let m = &nnf.data[q];
        if !m.ok {
            continue;
        }
        let frame = &mut hits[m.i as usize * src.frame_len..(m.i as usize + 1) * src.frame_len];
        let offs = offsets(src.stride, Center { i: m.i as usize, cx: m.x, cy: m.y, c: m.c, s: m.s });
        for &o in &offs[..PATCH * PATCH] {
            // Matches have valid centers, so every tap is inside the padded frame; one that
            // were not would be skipped (a negative offset wraps to a large index).
            if let Some(h) = frame.get_mut(o as usize) {
                *h += 1;
            }
        }
    }
}

/// Turns the splats of one column of pixels (`parts[p][i]`: part p, frame i, the same pixels
/// in every frame) into counts Ω* = the sum over frames i − r ..= i + r, handing each frame's
/// counts to `out(i, counts)`, and clears the splats.
fn box_sum(parts: &mut [Vec<&mut [i32]>], r: usize, mut out: impl FnMut(usize, &[i32])) {
    // No parts: no frames to hand out.
    let Some((first, rest)) = parts.split_first_mut() else { return };
    let frames = first.len();
    let len = first.first().map_or(0, |f| f.len());
    // Frame j's splats summed over the parts into the first part (the others cleared), and
    // added to the running sum.
    fn add(first: &mut [&mut [i32]], rest: &mut [Vec<&mut [i32]>], j: usize, run: &mut [i32]) {
        for part in rest.iter_mut() {
            for (a, b) in first[j].iter_mut().zip(part[j].iter_mut()) {
                *a += std::mem::take(b);
            }
        }
        for (s, &v) in run.iter_mut().zip(first[j].iter()) {
            *s += v;
        }
    }
    let mut run = vec![0i32; len];
    for j in 0..r.min(frames) {
        add(first, rest, j, &mut run);
    }
    for i in 0..frames {
        if i + r < frames {
            add(first, rest, i + r, &mut run);
        }
        out(i, &run);
        if i >= r {
            for (s, v) in run.iter_mut().zip(first[i - r].iter_mut()) {
                *s -= std::mem::take(v);
            }
        }
    }
    for f in first.iter_mut().skip(frames.saturating_sub(r)) {
        f.fill(0);
    }
}

/// Splits `arrays` (each `frames` frames of `frame_len`) into columns of `per` pixels:
/// `columns[c][a][i]` is array a's frame i, pixels `c·per ..`.
fn columns<'a, T>(
    arrays: impl IntoIterator<Item = &'a mut [T]>,
    frame_len: usize,
    per: usize,
) -> Vec<Vec<Vec<&'a mut [T]>>> {
    let mut cols: Vec<Vec<Vec<&mut [T]>>> = (0..frame_len.div_ceil(per)).map(|_| Vec::new()).collect();
    for (a, array) in arrays.into_iter().enumerate() {
        for col in cols.iter_mut() {
            col.push(Vec::new());
        }
        for frame in array.chunks_mut(frame_len) {
            for (c, piece) in frame.chunks_mut(per).enumerate() {
                cols[c][a].push(piece);
            }
        }
    }
    cols
}

/// How many parts the target is marked in (one marker array each).
fn parts() -> usize {
    rayon::current_num_threads().clamp(1, 8)
}

/// Raw counts Ω*(i, x, y) in the padded source layout (for the debug view).
pub(crate) fn counts(src: &SourceLevel, nnf: &Nnf, tgt: &TargetLevel, r: usize) -> Vec<i32> {
    let len = src.feat.len();
    let mut marks = vec![vec![0i32; len]; parts()];
    mark(src, nnf, tgt, &mut marks);
    let mut out = vec![0i32; len];
    let fl = src.frame_len;
    for mut parts in columns(marks.iter_mut().map(|m| &mut m[..]), fl, fl) {
        box_sum(&mut parts, r, |i, run| out[i * fl..][..run.len()].copy_from_slice(run));
    }
    out
}

/// `1/ω*` of every exemplar frame i and segment (0 where the target or the frame has no pixel
/// of the segment), with the count a voxel of frame i has when the field's matches are spread
/// uniformly over the pixels of the 2r+1 frames of its box:
///
/// ```text
/// ω*_seg,i = n² · |T_seg| / |S_seg,i|
/// ```
///
/// The papers divide by the exemplar's pixels over *all* frames (`n²(2r+1)|T|/|S|`), as if the
/// field of one target frame spread over the whole sequence; but it draws from the few exemplar
/// frames its motion calls for (the extents and the time shift choose them), and each voxel's
/// count Ω* sums only the 2r+1 frames of its box. With the papers' ω* a one-to-one use of a
/// frame — the exemplar itself, on its own masks — scores `|S|/((2r+1)|S_i|)` times "uniform"
/// (≈ 2.7 mid-sequence, ≈ 48 on a small first frame) and the penalty pushes the search away
/// from the perfect match. Per frame, one-to-one use scores 1 whether the field takes one
/// frame or spreads over the box, and only spatial over-use stands out. (ω* does not depend
/// on the current field: normalizing by the use the field makes of each frame would make
/// frames cheaper the more they are used.)
pub(crate) fn omega_inv(src: &SourceLevel, tgt: &TargetLevel) -> Vec<[f32; 2]> {
    let n2 = (PATCH * PATCH) as f32;
    (0..src.frames)
        .map(|i| {
            std::array::from_fn(|seg| {
                let t = tgt.seg_count[seg] as f32;
                let s = src.seg_count[i][seg] as f32;
                if t > 0.0 && s > 0.0 { s / (n2 * t) } else { 0.0 }
            })
        })
        .collect()
}

/// Penalties above this many times λ/n² (the per-tap penalty of a voxel used exactly as often
/// as uniform use would, Ω* = ω*) are clamped when stored in the features' occurrence lane.
pub(crate) const OMEGA_CAP: f32 = 32.0;

/// The occurrence map of one pyramid level, kept across its PatchMatch iterations: the
/// level's exemplar features with the penalty `λ·Ω*(p′)/(n²·ω*_seg)` of each source voxel in
/// the occurrence lane ([`OMEGA_LANE`]), where the segment is the voxel's own (matches never
/// cross segments), and the lane's weight `w_Ω`.
///
/// The lane holds `q = round(√(penalty / w_Ω))` with `w_Ω = OMEGA_CAP·λ/n² / 255²`, so that the
/// patch error's `w_Ω·(q − 0)²` is the penalty: uniform use (Ω* = ω*) gives q ≈ 45, a step of
/// ≈ 4 % there and finer below; penalties above [`OMEGA_CAP`] times that are clamped.
/// Keeping Ω in the 8-byte pixel the error reads anyway halves the cache lines a random
/// candidate touches.
pub(crate) struct Occurrence {
    /// The level's features with the occurrence lane (empty until the first update).
    feat: Vec<Feat>,
    /// Zeroed marker arrays, one per part of the target.
    marks: Vec<Vec<i32>>,
}

/// The contrast balance of the field `nnf` (μ = `balance`): per segment and contrast bin of
/// the exemplar ([`SourceLevel::contrast`]), `μ·max(0, B·u_b − 1)/OMEGA_CAP` — `u_b` the share
/// of the segment's matched in-mask pixels whose center lies in bin b, B the bins, each of
/// which holds 1/B of the exemplar's centers — in the units of `Ω*·k` of the occurrence lane.
/// Every voxel of a bin the field uses more than the exemplar holds pays it, whether or not
/// that voxel is used.
fn contrast_excess(src: &SourceLevel, nnf: &Nnf, tgt: &TargetLevel, balance: f32) -> [[f32; CONTRAST_BINS]; 2] {
    type Counts = [[usize; CONTRAST_BINS]; 2];
    let mut count: Counts = [[0; CONTRAST_BINS]; 2];
    if balance > 0.0 {
        // Integer counts per row, added: the same for any thread count.
        let add = |mut a: Counts, b: Counts| {
            for (ra, rb) in a.iter_mut().zip(b) {
                for (x, y) in ra.iter_mut().zip(rb) {
                    *x += y;
                }
            }
            a
        };
        count = nnf
            .data
            .par_chunks(nnf.w.max(1))
            .enumerate()
            .map(|(y, row)| {
                let mut c: Counts = [[0; CONTRAST_BINS]; 2];
                for (x, m) in row.iter().enumerate() {
                    if !m.ok || tgt.info[y * nnf.w + x].flags & IN_MASK == 0 {
                        continue;
                    }
                    if let Some(idx) = src.nearest(m.i as usize, m.x, m.y)
                        && src.contrast[idx] != NO_BIN
                    {
                        let seg = (src.feat[idx][FLAG_LANE] & INTERIOR != 0) as usize;
                        c[seg][src.contrast[idx] as usize] += 1;
                    }
                }
                c
            })
            .reduce(|| [[0; CONTRAST_BINS]; 2], add);
    }
    count.map(|c| {
        let total = c.iter().sum::<usize>().max(1) as f32;
        c.map(|n| balance * (CONTRAST_BINS as f32 * n as f32 / total - 1.0).max(0.0) / OMEGA_CAP)
    })
}

impl Occurrence {
    /// Buffers for one level (allocated at the first update).
    pub fn new() -> Occurrence {
        Occurrence { feat: Vec::new(), marks: Vec::new() }
    }

    /// Recomputes the penalty of level `src` for the field `nnf` (r = `r`, λ = `lambda`, the
    /// contrast balance μ = `balance`, [`contrast_excess`]); returns the features with the
    /// occurrence lane and `w_Ω`, `None` when λ = 0.
    pub fn update(
        &mut self,
        src: &SourceLevel,
        nnf: &Nnf,
        tgt: &TargetLevel,
        r: usize,
        lambda: f32,
        balance: f32,
    ) -> Option<(&[Feat], f32)> {
        if lambda == 0.0 {
            return None;
        }
        let len = src.feat.len();
        if self.feat.len() != len {
            self.feat = src.feat.clone();
        }
        let excess = contrast_excess(src, nnf, tgt, balance);
        // The lane's value for `v` = Ω*·k plus the bin's charge, and the value of an unused voxel
        // of each segment and bin.
        let lane = |v: f32| if v <= 0.0 { 0 } else { ((255.0 * v.sqrt() + 0.5) as u32).min(255) as u8 };
        let idle = excess.map(|row| row.map(lane));
        if self.marks.len() != parts() || self.marks.iter().any(|m| m.len() != len) {
            self.marks = vec![vec![0i32; len]; parts()];
        }
        mark(src, nnf, tgt, &mut self.marks);
        let n2 = (PATCH * PATCH) as f32;
        let w_omega = OMEGA_CAP * lambda / n2 / (255.0 * 255.0);
        // (q/255)² = penalty/(OMEGA_CAP·λ/n²) = Ω*/(OMEGA_CAP·ω*), so q = 255·√(Ω* · k), with
        // k = 1/(OMEGA_CAP·ω*_seg,i) per frame i and segment.
        let k: Vec<[f32; 2]> = omega_inv(src, tgt).into_iter().map(|v| v.map(|x| x / OMEGA_CAP)).collect();
        // One pass per column of pixels (the same pixel range of every frame): add the parts,
        // sum along time, write the lane, clear the splats.
        let fl = src.frame_len;
        let per = fl.div_ceil(64).max(1);
        let feat = columns(std::iter::once(&mut self.feat[..]), fl, per);
        let marks = columns(self.marks.iter_mut().map(|m| &mut m[..]), fl, per);
        feat.into_par_iter().zip(marks).enumerate().for_each(|(col, (mut feat, mut parts))| {
            let feat = &mut feat[0];
            box_sum(&mut parts, r, |i, run| {
                // The column's pixels of frame i, read from the level (same layout as `feat`).
                let start = i * fl + col * per;
                let bins = &src.contrast[start..start + run.len()];
                for ((f, &b), &c) in feat[i].iter_mut().zip(bins).zip(run) {
                    let seg = (f[FLAG_LANE] & INTERIOR != 0) as usize;
                    f[OMEGA_LANE] = if c <= 0 {
                        // Unused: the bin's charge alone (the same for every such voxel).
                        if b == NO_BIN { 0 } else { idle[seg][b as usize] }
                    } else {
                        let e = if b == NO_BIN { 0.0 } else { excess[seg][b as usize] };
                        lane(c as f32 * k[i][seg] + e)
                    };
                }
            });
        });
        Some((&self.feat, w_omega))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;
    use crate::synth::nnf::{Match, offsets};
    use crate::synth::params::Params;
    use crate::synth::source::PAD;
    use crate::synth::source::{MARGIN, SourcePyramid};
    use crate::synth::tests::{disc_exemplar, disc_guides};

    /// A field of random matches (random rotations and sub-pixel centers, some frames near
    /// the ends of the sequence) over every active pixel.
    fn random_field(src: &SourceLevel, tgt: &TargetLevel, seed: u64) -> Nnf {
        let mut rng = SplitMix64::keyed(&[seed]);
        let mut nnf = Nnf::new(tgt.w, tgt.info.len() / tgt.w);
        for &q in &tgt.active {
            let th = rng.range(-3.1, 3.1);
            nnf.data[q as usize] = Match {
                x: rng.range(MARGIN as f32, (src.w - 1 - MARGIN) as f32),
                y: rng.range(MARGIN as f32, (src.h - 1 - MARGIN) as f32),
                c: th.cos(),
                s: th.sin(),
                err: 0.0,
                i: rng.below(src.frames) as u16,
                flip: false,
                ok: rng.next_f32() < 0.9,
            };
        }
        nnf
    }

    /// Ω* counted the obvious way: every tap of every box, frame by frame, each tap at the
    /// pixel nearest to its rotated position (as the patch error reads it).
    fn brute_counts(src: &SourceLevel, nnf: &Nnf, tgt: &TargetLevel, r: usize) -> Vec<i32> {
        let mut out = vec![0; src.feat.len()];
        for &q in &tgt.active {
            let m = nnf.data[q as usize];
            if !m.ok || tgt.info[q as usize].flags & IN_MASK == 0 {
                continue;
            }
            for (a, b) in offsets() {
                let (dx, dy) = m.rotate(a as f32, b as f32);
                let px = (m.x + PAD as f32 + dx + 0.5).floor() as usize;
                let py = (m.y + PAD as f32 + dy + 0.5).floor() as usize;
                let (lo, hi) = ((m.i as usize).saturating_sub(r), (m.i as usize + r).min(src.frames - 1));
                for i in lo..=hi {
                    out[i * src.frame_len + py * src.stride + px] += 1;
                }
            }
        }
        out
    }

    /// A one-level pyramid of a 9-frame disc exemplar and a growing disc's first target level.
    fn disc_level() -> (SourcePyramid, TargetLevel) {
        let params = Params::builder().build().unwrap();
        let (rgb, g) = disc_exemplar(48, 40, 9, 2);
        let pyr = SourcePyramid::build(&rgb, &g, &params, 4.0, 1);
        let tg = disc_guides(36, 30, glam::Vec2::new(18.0, 15.0), 11.0, 0.5, 2, 5);
        let tgt = TargetLevel::new(&tg, &pyr.quant, 4.0, None, pyr.levels[0].ext_falloff, [1.0; 3], false);
        (pyr, tgt)
    }

    #[test]
    fn counts_and_penalty_lane_match_a_direct_count() {
        let (pyr, tgt) = disc_level();
        let src = &pyr.levels[0];
        let lambda = 0.7;
        let mut occ = Occurrence::new();
        let fields: Vec<Nnf> = (0..3).map(|k| random_field(src, &tgt, k)).collect();
        // Updating again with other fields, then with the first: the buffers carry nothing over.
        // (A radius beyond the sequence covers all of it.)
        for (nnf, r) in [(&fields[0], 2), (&fields[1], 2), (&fields[2], 12), (&fields[0], 2)] {
            let want = brute_counts(src, nnf, &tgt, r);
            assert!(want.iter().filter(|&&c| c > 0).count() > 500);
            assert_eq!(counts(src, nnf, &tgt, r), want);
            let (feat, w) = occ.update(src, nnf, &tgt, r, lambda, 0.0).unwrap();
            let n2 = (PATCH * PATCH) as f32;
            assert!((w - OMEGA_CAP * lambda / n2 / (255.0 * 255.0)).abs() < 1e-12);
            let mut nonzero = 0;
            for (k, (f, &c)) in feat.iter().zip(&want).enumerate() {
                // Every other lane is the level's own.
                assert_eq!(f[..OMEGA_LANE], src.feat[k][..OMEGA_LANE]);
                let seg = (f[FLAG_LANE] & INTERIOR != 0) as usize;
                let frame = k / src.frame_len;
                let omega_star = n2 * tgt.seg_count[seg] as f32 / src.seg_count[frame][seg] as f32;
                // w_Ω·q² ≈ λ·Ω*/(n²·ω*), capped at OMEGA_CAP·λ/n².
                let penalty = (lambda * c as f32 / (n2 * omega_star)).min(OMEGA_CAP * lambda / n2);
                let stored = w * (f[OMEGA_LANE] as f32).powi(2);
                let step = w * (2.0 * f[OMEGA_LANE] as f32 + 1.0);
                assert!((stored - penalty).abs() <= step, "voxel {k}: count {c}, {stored} vs {penalty}");
                nonzero += (f[OMEGA_LANE] > 0) as usize;
            }
            assert_eq!(nonzero, want.iter().filter(|&&c| c > 0).count());
        }
        assert!(occ.update(src, &fields[0], &tgt, 2, 0.0, 0.0).is_none());
    }

    /// The contrast balance: a field that takes only the exemplar's flattest paint makes every
    /// voxel of that bin pay `μ·λ·(B − 1)` per patch, used or not, and leaves the other bins'
    /// unused voxels free; without the balance every unused voxel is free.
    #[test]
    fn contrast_balance_charges_the_overused_bin() {
        let (pyr, tgt) = disc_level();
        let src = &pyr.levels[0];
        // Every frame's in-mask centers of a segment are split into equal shares.
        for i in 0..src.frames {
            for seg in 0..2 {
                let mut per_bin = [0usize; CONTRAST_BINS];
                for &idx in &src.valid[seg] {
                    let (idx, f) = (idx as usize, src.feat[idx as usize]);
                    if idx / src.frame_len == i && f[FLAG_LANE] & IN_MASK != 0 {
                        per_bin[src.contrast[idx] as usize] += 1;
                    }
                }
                let n: usize = per_bin.iter().sum();
                if n >= 8 * CONTRAST_BINS {
                    assert!(
                        per_bin.iter().all(|&c| c * CONTRAST_BINS * 2 >= n),
                        "frame {i}, segment {seg}: {per_bin:?}"
                    );
                }
            }
        }
        let (lambda, mu) = (0.7, 2.0);
        let n2 = (PATCH * PATCH) as f32;
        // Every matched pixel moved onto one flattest-bin center of its own segment.
        let mut flat = random_field(src, &tgt, 0);
        for (q, m) in flat.data.iter_mut().enumerate() {
            if !m.ok {
                continue;
            }
            let seg = (tgt.info[q].flags & INTERIOR != 0) as usize;
            let idx = *src.valid[seg].iter().find(|&&idx| src.contrast[idx as usize] == 0).unwrap() as usize;
            let (i, x, y) = src.coords(idx);
            (m.i, m.x, m.y) = (i as u16, x as f32, y as f32);
        }
        let used = counts(src, &flat, &tgt, 2);
        let mut occ = Occurrence::new();
        let (feat, w) = occ.update(src, &flat, &tgt, 2, lambda, mu).unwrap();
        let full = (CONTRAST_BINS - 1) as f32 * mu * lambda / n2;
        let (mut charged, mut free) = (0, 0);
        for (k, f) in feat.iter().enumerate() {
            let stored = w * (f[OMEGA_LANE] as f32).powi(2);
            if used[k] > 0 || src.contrast[k] == NO_BIN {
                continue;
            }
            if src.contrast[k] == 0 {
                assert!(
                    (stored - full).abs() <= w * (2.0 * f[OMEGA_LANE] as f32 + 1.0),
                    "voxel {k}: {stored} vs {full}"
                );
                charged += 1;
            } else {
                assert_eq!(f[OMEGA_LANE], 0, "voxel {k} of bin {}", src.contrast[k]);
                free += 1;
            }
        }
        assert!(charged > 50 && free > 300, "{charged} charged, {free} free");
        // Without the balance the unused voxels are free.
        let (feat, _) = occ.update(src, &flat, &tgt, 2, lambda, 0.0).unwrap();
        assert!(feat.iter().zip(&used).all(|(f, &c)| c > 0 || f[OMEGA_LANE] == 0));
    }
}
