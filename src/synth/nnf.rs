//! The nearest-neighbour field: for each target pixel q = (x̂, ŷ) of frame j, the source
//! patch `(i, x, y, θ)` — exemplar frame, sub-pixel center, rotation — with its error.
//!
//! The rotation is stored as the matrix `M = R_{−θ}` (cosine and sine) that maps a window
//! offset in the target to the offset in the source (paper §3.6): `src = (x, y) + M·(a, b)`.
//! [`Match::flip`] is set when the rotated source flow opposes the target flow, i.e. when the
//! θ_T − θ_S + π option was chosen: ext+ and ext− are then compared swapped (paper §3.3).

use super::params::HALF;
use super::source::floor_i32;
use glam::Vec2;
use rayon::prelude::*;

/// One entry of the field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Match {
    /// Source center, pixels of the level (sub-pixel).
    pub x: f32,
    pub y: f32,
    /// `M = R_{−θ}` as (cos θ, −sin θ): src offset = (c·a − s·b, s·a + c·b).
    pub c: f32,
    pub s: f32,
    /// Patch error D at the last evaluation.
    pub err: f32,
    /// Exemplar frame i.
    pub i: u16,
    /// Opposite flows: ext+/ext− swapped, time shifted backwards.
    pub flip: bool,
    /// False for "no match" (outside the active region, or no previous frame here).
    pub ok: bool,
}

impl Match {
    /// The "no match" value.
    pub const NONE: Match = Match { x: 0.0, y: 0.0, c: 1.0, s: 0.0, err: f32::INFINITY, i: 0, flip: false, ok: false };

    /// Applies M to a target offset.
    #[inline]
    pub fn rotate(&self, a: f32, b: f32) -> (f32, f32) {
        (self.c * a - self.s * b, self.s * a + self.c * b)
    }
}

/// The rotation M taking target direction `t` onto source direction `s` (both unit), and
/// its +π alternative.
#[inline]
pub(crate) fn aligning_rotation(t: Vec2, s: Vec2) -> (f32, f32) {
    (t.dot(s), t.perp_dot(s))
}

/// A dense field over a level's w × h pixels.
#[derive(Clone, Debug)]
pub(crate) struct Nnf {
    pub w: usize,
    pub h: usize,
    pub data: Vec<Match>,
}

impl Nnf {
    pub fn new(w: usize, h: usize) -> Nnf {
        Nnf { w, h, data: vec![Match::NONE; w * h] }
    }

    #[inline]
    pub fn get(&self, x: usize, y: usize) -> &Match {
        &self.data[y * self.w + x]
    }

    /// The index of the entry nearest to point `p` (at `⌊p⌉`), if it lies in the field.
    #[inline]
    pub fn index_near(&self, p: glam::Vec2) -> Option<usize> {
        let r = p.round();
        (r.x >= 0.0 && r.y >= 0.0 && (r.x as usize) < self.w && (r.y as usize) < self.h)
            .then(|| r.y as usize * self.w + r.x as usize)
    }

    /// UPSCALENNF (paper §3.6): each coarse entry becomes a 2 × 2 block,
    /// `(x↑, y↑) = 2·(x′, y′) + c + M·((x̂ mod 2, ŷ mod 2) − c)` with c = (½, ½).
    pub fn upscale(&self, w: usize, h: usize) -> Nnf {
        let mut out = Nnf::new(w, h);
        out.data.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let (cx, cy) = ((x / 2).min(self.w - 1), (y / 2).min(self.h - 1));
                let m = self.get(cx, cy);
                if !m.ok {
                    continue;
                }
                let (dx, dy) = m.rotate((x % 2) as f32 - 0.5, (y % 2) as f32 - 0.5);
                *o = Match { x: 2.0 * m.x + 0.5 + dx, y: 2.0 * m.y + 0.5 + dy, err: f32::INFINITY, ..*m };
            }
        });
        out
    }

    /// DOWNSCALENNF (paper §3.6) by a factor 2^`l`: for each coarse pixel, the entries of its
    /// 2^l × 2^l block are mapped back by the inverse of the up-scaling transform, rounded to
    /// integer positions, and the mode of (i, x, y) wins; its rotation comes along.
    pub fn downscale(&self, l: usize, w: usize, h: usize) -> Nnf {
        if l == 0 {
            let mut out = Nnf::new(w, h);
            for y in 0..h.min(self.h) {
                for x in 0..w.min(self.w) {
                    out.data[y * w + x] = *self.get(x, y);
                }
            }
            return out;
        }
        let k = 1usize << l;
        let kf = k as f32;
        let center = (kf - 1.0) * 0.5;
        let mut out = Nnf::new(w, h);
        out.data.par_chunks_mut(w).enumerate().for_each_init(
            || Vec::with_capacity(k * k),
            |votes: &mut Vec<((u16, i32, i32), Match)>, (y, row)| {
                for (x, o) in row.iter_mut().enumerate() {
                    votes.clear();
                    for by in 0..k {
                        for bx in 0..k {
                            let (fx, fy) = (x * k + bx, y * k + by);
                            if fx >= self.w || fy >= self.h {
                                continue;
                            }
                            let m = self.get(fx, fy);
                            if !m.ok {
                                continue;
                            }
                            let (dx, dy) = m.rotate(bx as f32 - center, by as f32 - center);
                            let cx = (m.x - dx - center) / kf;
                            let cy = (m.y - dy - center) / kf;
                            let key = (m.i, floor_i32(cx + 0.5), floor_i32(cy + 0.5));
                            votes.push((key, Match { x: key.1 as f32, y: key.2 as f32, err: f32::INFINITY, ..*m }));
                        }
                    }
                    if votes.is_empty() {
                        continue;
                    }
                    votes.sort_by_key(|v| v.0);
                    // Mode; ties go to the smallest key (deterministic).
                    let (mut best, mut best_n, mut run_start) = (0usize, 0usize, 0usize);
                    for n in 1..=votes.len() {
                        if n == votes.len() || votes[n].0 != votes[run_start].0 {
                            if n - run_start > best_n {
                                best_n = n - run_start;
                                best = run_start;
                            }
                            run_start = n;
                        }
                    }
                    *o = votes[best].1;
                }
            },
        );
        out
    }
}

/// Number of pyramid levels ⌊log2(d_min / n)⌋ (at least 1), paper §3.6.
pub(crate) fn level_count(d_min: usize) -> usize {
    let ratio = d_min as f32 / super::params::PATCH as f32;
    if ratio < 2.0 { 1 } else { ratio.log2().floor() as usize }
}

/// The window offsets of a patch, row by row.
#[inline]
pub(crate) fn offsets() -> impl Iterator<Item = (isize, isize)> {
    let r = HALF as isize;
    (-r..=r).flat_map(move |b| (-r..=r).map(move |a| (a, b)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rot(theta: f32) -> (f32, f32) {
        (theta.cos(), theta.sin())
    }

    #[test]
    fn upscale_then_downscale_is_identity_for_rotated_fields() {
        let mut coarse = Nnf::new(6, 5);
        for (k, m) in coarse.data.iter_mut().enumerate() {
            let (c, s) = rot(0.3 * k as f32);
            *m = Match {
                x: 10.0 + k as f32,
                y: 7.0 + (k % 3) as f32,
                c,
                s,
                err: 0.0,
                i: (k % 4) as u16,
                flip: k % 2 == 0,
                ok: true,
            };
        }
        let fine = coarse.upscale(12, 10);
        // A 2x2 block of an unrotated field tiles the source 2x2 block.
        let back = fine.downscale(1, 6, 5);
        for (a, b) in coarse.data.iter().zip(&back.data) {
            assert_eq!((a.i, a.x, a.y, a.flip), (b.i, b.x, b.y, b.flip));
        }
        // Two levels up and back down.
        let finer = fine.upscale(24, 20);
        let back2 = finer.downscale(2, 6, 5);
        for (a, b) in coarse.data.iter().zip(&back2.data) {
            assert_eq!((a.i, a.x, a.y), (b.i, b.x, b.y));
        }
    }

    #[test]
    fn upscale_offsets_follow_the_rotation() {
        let mut coarse = Nnf::new(1, 1);
        let (c, s) = rot(std::f32::consts::FRAC_PI_2);
        coarse.data[0] = Match { x: 5.0, y: 5.0, c, s, err: 0.0, i: 0, flip: false, ok: true };
        let fine = coarse.upscale(2, 2);
        // Target offset (+½, −½) from the block center maps to M·(½, −½) = (½, ½) (90°).
        let m = fine.get(1, 0);
        assert!((m.x - 11.0).abs() < 1e-5 && (m.y - 11.0).abs() < 1e-5, "{:?}", m);
        // Neighbouring target pixels map to neighbouring source pixels along the rotated axis.
        let a = fine.get(0, 0);
        let b = fine.get(1, 0);
        assert!(((b.x - a.x) - c).abs() < 1e-5 && ((b.y - a.y) - s).abs() < 1e-5);
    }

    #[test]
    fn downscale_takes_the_mode() {
        let mut f = Nnf::new(2, 2);
        let m = Match { x: 4.0, y: 6.0, c: 1.0, s: 0.0, err: 0.0, i: 3, flip: false, ok: true };
        f.data[0] = m; // (0,0) -> coarse (4-0.5... )
        f.data[1] = Match { x: 5.0, ..m }; // consistent with the same coarse pixel
        f.data[2] = Match { x: 40.0, y: 40.0, ..m };
        f.data[3] = Match::NONE;
        let d = f.downscale(1, 1, 1);
        assert_eq!((d.data[0].x, d.data[0].y), (2.0, 3.0));
    }

    #[test]
    fn levels() {
        assert_eq!(level_count(200), 5);
        assert_eq!(level_count(222), 5);
        assert_eq!(level_count(12), 1);
        assert_eq!(level_count(3), 1);
    }
}
