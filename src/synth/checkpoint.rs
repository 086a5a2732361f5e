//! Saving and restoring the state a synthesizer carries between frames (the previous frame's
//! field, its `T^ext+`, `T^flow` and masks, and the extent factor k), so an interrupted render can resume and give the same
//! result as an uninterrupted one. Ω needs no saving: it is recomputed for every frame.

use super::nnf::{Match, Nnf};
use super::{PrevState, Synthesizer};
use crate::error::{Error, Result};
use crate::guide::FrameGuides;
use std::path::Path;

const MAGIC: &[u8; 8] = b"FMSYNTH4";

struct Writer(Vec<u8>);

impl Writer {
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f32(&mut self, v: f32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn bytes(&mut self, b: &[u8]) {
        self.u64(b.len() as u64);
        self.0.extend_from_slice(b);
    }
}

struct Reader<'a> {
    data: &'a [u8],
    pos: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Option<&[u8]> {
        let end = self.pos.checked_add(n)?;
        let s = self.data.get(self.pos..end)?;
        self.pos = end;
        Some(s)
    }
    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
    fn f32(&mut self) -> Option<f32> {
        Some(f32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
    fn len(&mut self, limit: usize) -> Option<usize> {
        let n = self.u64()? as usize;
        (n <= limit).then_some(n)
    }
}

impl Synthesizer {
    /// A string that changes whenever the parameters or the exemplar preparation change;
    /// a checkpoint only restores into a synthesizer with the same fingerprint.
    pub fn fingerprint(&self) -> String {
        let src = &self.source.pyramid;
        format!(
            "{:?}|{}x{}x{}|b={}|v={}|paper={:?}",
            self.params, src.size.0, src.size.1, src.levels[0].frames, src.border_width, src.color_unit, src.paper
        )
    }

    /// Serializes the inter-frame state.
    pub fn save_state(&self) -> Vec<u8> {
        let mut w = Writer(Vec::new());
        w.0.extend_from_slice(MAGIC);
        w.bytes(self.fingerprint().as_bytes());
        w.u64(self.frame as u64);
        let (sw, sh) = self.size.unwrap_or((0, 0));
        w.u64(sw as u64);
        w.u64(sh as u64);
        // k of the extent normalization, fixed at the first frame with paint (NaN: not yet).
        w.f32(self.ext_factor.unwrap_or(f32::NAN));
        match &self.prev {
            None => w.u64(0),
            Some(p) => {
                w.u64(1);
                w.u64(p.origin.0 as u64);
                w.u64(p.origin.1 as u64);
                w.u64(p.nnf0.w as u64);
                w.u64(p.nnf0.h as u64);
                // Sparse: a bit per pixel, then the matches (and T^ext+, T^flow) of the set bits only.
                let ok: Vec<bool> = p.nnf0.data.iter().map(|m| m.ok).collect();
                w.bytes(&pack_bits(&ok));
                for ((m, &e), f) in p.nnf0.data.iter().zip(&p.ext_pos).zip(&p.flow) {
                    if !m.ok {
                        continue;
                    }
                    for v in [m.x, m.y, m.c, m.s, m.err, e, f.x, f.y] {
                        w.f32(v);
                    }
                    w.0.extend_from_slice(&m.i.to_le_bytes());
                    w.0.push(m.flip as u8);
                }
                w.u64(p.masks.len() as u64);
                for m in &p.masks {
                    w.u64(m.len() as u64);
                    w.bytes(&pack_bits(m));
                }
            }
        }
        w.0
    }

    /// Restores state saved by [`Synthesizer::save_state`] into a synthesizer built with the
    /// same source and parameters. `path` only names the file in errors.
    pub fn load_state(&mut self, data: &[u8], path: &Path) -> Result<()> {
        let bad = |what: &str| Error::Corrupt {
            path: path.to_path_buf(),
            message: format!("checkpoint is unusable: {}", what),
        };
        let mut r = Reader { data, pos: 0 };
        if r.take(8) != Some(MAGIC.as_slice()) {
            return Err(bad("not a fluidymation checkpoint"));
        }
        let n = r.len(1 << 20).ok_or_else(|| bad("truncated"))?;
        let fp = r.take(n).ok_or_else(|| bad("truncated"))?;
        if fp != self.fingerprint().as_bytes() {
            return Err(bad("it was made with other parameters or another exemplar; start again without --resume"));
        }
        let limit = 1 << 28;
        let trunc = || bad("truncated");
        let frame = r.u64().ok_or_else(trunc)? as usize;
        let sw = r.u64().ok_or_else(trunc)? as usize;
        let sh = r.u64().ok_or_else(trunc)? as usize;
        if sw.max(sh) > crate::anim::MAX_SIDE as usize {
            return Err(bad(&format!("the target size {sw}x{sh} is impossible")));
        }
        let ext_factor = r.f32().ok_or_else(trunc)?;
        if !(ext_factor.is_nan() || (ext_factor > 0.0 && ext_factor <= 1.0)) {
            return Err(bad("the extent factor is not in (0, 1]"));
        }
        // Known from the whole target (Synthesizer::set_target_extent): it must agree.
        if let Some(e_t) = self.target_extent
            && !ext_factor.is_nan()
            && ext_factor != self.extent_factor_for(e_t)
        {
            return Err(bad("the extent factor does not match the target's motion"));
        }
        let prev = match r.u64().ok_or_else(trunc)? {
            0 => None,
            _ => {
                let ox = r.len(1 << 16).ok_or_else(trunc)?;
                let oy = r.len(1 << 16).ok_or_else(trunc)?;
                let w = r.len(1 << 16).ok_or_else(trunc)?;
                let h = r.len(1 << 16).ok_or_else(trunc)?;
                // Before anything of that size is allocated.
                if w == 0 || h == 0 || ox.saturating_add(w) > sw || oy.saturating_add(h) > sh {
                    return Err(bad(&format!(
                        "the previous frame's window {w}x{h} at ({ox}, {oy}) does not fit the {sw}x{sh} frame"
                    )));
                }
                let n = r.len(limit).ok_or_else(trunc)?;
                let ok = unpack_bits(r.take(n).ok_or_else(trunc)?, w * h).ok_or_else(|| bad("inconsistent sizes"))?;
                let mut nnf = Nnf::new(w, h);
                let mut ext_pos = vec![0.0f32; w * h];
                let mut flow = vec![glam::Vec2::ZERO; w * h];
                for (((m, e), f), &ok) in nnf.data.iter_mut().zip(ext_pos.iter_mut()).zip(flow.iter_mut()).zip(&ok) {
                    if !ok {
                        continue;
                    }
                    let mut v = [0.0f32; 8];
                    for x in v.iter_mut() {
                        *x = r.f32().ok_or_else(trunc)?;
                    }
                    let rest = r.take(3).ok_or_else(trunc)?;
                    *m = Match {
                        x: v[0],
                        y: v[1],
                        c: v[2],
                        s: v[3],
                        err: v[4],
                        i: u16::from_le_bytes([rest[0], rest[1]]),
                        flip: rest[2] != 0,
                        ok: true,
                    };
                    *e = v[5];
                    *f = glam::Vec2::new(v[6], v[7]);
                    if !(f.is_finite() && f.length() <= crate::anim::MAX_SIDE as f32) {
                        return Err(bad(&format!("a flow value ({}, {}) is impossible", f.x, f.y)));
                    }
                    if rest[2] > 1 {
                        return Err(bad("a match's flip flag is neither 0 nor 1"));
                    }
                    self.check_match(m, *e).map_err(|what| bad(&what))?;
                }
                let levels = r.len(32).ok_or_else(trunc)?;
                let mut masks = Vec::with_capacity(levels);
                for _ in 0..levels {
                    let len = r.len(limit).ok_or_else(trunc)?;
                    let n = r.len(limit).ok_or_else(trunc)?;
                    masks
                        .push(unpack_bits(r.take(n).ok_or_else(trunc)?, len).ok_or_else(|| bad("inconsistent sizes"))?);
                }
                Some(PrevState { origin: (ox, oy), nnf0: nnf, ext_pos, flow, masks })
            }
        };
        if r.pos != data.len() {
            return Err(bad("trailing data"));
        }
        self.check_sizes(frame, (sw, sh), prev.as_ref()).map_err(|what| bad(&what))?;
        self.frame = frame;
        self.size = (sw > 0).then_some((sw, sh));
        self.prev = prev;
        self.ext_factor = (!ext_factor.is_nan()).then_some(ext_factor);
        Ok(())
    }
}

/// Largest |c² + s² − 1| of a loaded rotation (saved rotations are unit up to rounding).
const ROTATION_TOLERANCE: f32 = 1e-3;

impl Synthesizer {
    /// The size of the target frames seen so far (`None` before the first frame).
    pub fn target_size(&self) -> Option<(usize, usize)> {
        self.size
    }

    /// A loaded match must address the exemplar: frame `i` among its frames, the center
    /// inside the finest level (where the time shift and the kernels read it; the margin is
    /// restored by `sanitize` before a search), a rotation `(c, s)` with c² + s² ≈ 1, and a
    /// finite, non-negative `T^ext+`. The error is recomputed before any use, so it is not checked.
    fn check_match(&self, m: &Match, ext: f32) -> std::result::Result<(), String> {
        let src = &self.source.pyramid.levels[0];
        if m.i as usize >= src.frames {
            return Err(format!("a match points to exemplar frame {} of {}", m.i as usize + 1, src.frames));
        }
        let inside = |v: f32, n: usize| v.is_finite() && v >= 0.0 && v <= (n - 1) as f32;
        if !(inside(m.x, src.w) && inside(m.y, src.h)) {
            return Err(format!("a match points to ({}, {}), outside the {}x{} exemplar", m.x, m.y, src.w, src.h));
        }
        let off = (m.c * m.c + m.s * m.s - 1.0).abs();
        if off.is_nan() || off > ROTATION_TOLERANCE {
            return Err(format!("a match's rotation ({}, {}) is not a rotation", m.c, m.s));
        }
        if !(ext.is_finite() && ext >= 0.0) {
            return Err(format!("a motion extent is {ext}"));
        }
        Ok(())
    }

    /// The sizes of a loaded state must fit each other: the previous frame's window inside
    /// the frame, its corner aligned like the windows [`Synthesizer::step`] makes, and one
    /// mask per pyramid level of the window's size.
    fn check_sizes(
        &self,
        frame: usize,
        (sw, sh): (usize, usize),
        prev: Option<&PrevState>,
    ) -> std::result::Result<(), String> {
        let max = crate::anim::MAX_SIDE as usize;
        if sw > max || sh > max || (sw == 0) != (sh == 0) {
            return Err(format!("the target size {sw}x{sh} is impossible"));
        }
        if frame == 0 && (sw > 0 || prev.is_some()) {
            return Err("it holds a previous frame but no frame was done".into());
        }
        let Some(p) = prev else { return Ok(()) };
        if sw == 0 {
            return Err("it holds a previous frame but no target size".into());
        }
        let (w, h) = (p.nnf0.w, p.nnf0.h);
        let levels = self.level_count(sw, sh);
        let align = 1 << (levels - 1);
        if w == 0 || h == 0 || p.origin.0 + w > sw || p.origin.1 + h > sh {
            return Err(format!(
                "the previous frame's window {}x{} at ({}, {}) does not fit the {sw}x{sh} frame",
                w, h, p.origin.0, p.origin.1
            ));
        }
        if p.origin.0 % align != 0 || p.origin.1 % align != 0 {
            return Err(format!("the previous frame's window corner is not a multiple of {align}"));
        }
        if p.masks.len() != levels {
            return Err(format!("{} mask levels where the frame has {levels}", p.masks.len()));
        }
        for (l, m) in p.masks.iter().enumerate() {
            let (lw, lh) = (w.div_ceil(1 << l), h.div_ceil(1 << l));
            if m.len() != lw * lh {
                return Err(format!("mask level {l} holds {} pixels, not {lw}x{lh}", m.len()));
            }
        }
        Ok(())
    }

    /// Checks a restored state against the guides of the frame it was saved after (the
    /// previous frame of the next [`Synthesizer::step`]): the saved window must be the one
    /// that frame's mask gives, the frames must have the same size, and the `T^ext+` and
    /// `T^flow` saved with each match must be that frame's. `None` when no frame was done.
    /// `path` names the state in errors.
    pub fn check_resumed(&self, previous: Option<&FrameGuides>, path: &Path) -> Result<()> {
        let bad = |what: String| Error::Corrupt {
            path: path.to_path_buf(),
            message: format!("checkpoint does not belong to this render: {what}"),
        };
        let Some(g) = previous else {
            return match self.frame {
                0 => Ok(()),
                n => Err(bad(format!("it was saved after frame {n}, but this render has done none"))),
            };
        };
        let size = g.mask.size();
        if self.size != Some(size) {
            let (w, h) = self.size.unwrap_or((0, 0));
            return Err(bad(format!("it was saved for {w}x{h} frames, this render's are {}x{}", size.0, size.1)));
        }
        let levels = self.level_count(size.0, size.1);
        let expected = super::window(&g.mask, 1 << (levels - 1));
        let saved = self.prev.as_ref().map(|p| (p.origin.0, p.origin.1, p.nnf0.w, p.nnf0.h));
        if expected != saved {
            return Err(bad(format!(
                "its working window {saved:?} is not the one of the previous frame's mask {expected:?}"
            )));
        }
        // The previous frame's `T^ext+` and `T^flow` saved with each match must be that frame's
        // own (`T^ext+` scaled by k, as the target's pyramid scales it): a forged value that
        // passes the checksums would carry that match differently, and the output would differ
        // from an uninterrupted render's.
        if let Some(p) = &self.prev {
            let k = self.ext_factor.unwrap_or(1.0);
            let (ox, oy) = p.origin;
            for (q, m) in p.nnf0.data.iter().enumerate() {
                if !m.ok {
                    continue;
                }
                let (x, y) = (ox + q % p.nnf0.w, oy + q / p.nnf0.w);
                // (x·1 = x exactly: the pyramid's unscaled extents compare alike.)
                let e = g.ext_pos.get(x, y) * k;
                if p.ext_pos[q].to_bits() != e.to_bits() || p.flow[q] != g.flow.get(x, y) {
                    return Err(bad(format!("its motion guides at ({x}, {y}) are not the previous frame's")));
                }
            }
        }
        Ok(())
    }
}

fn pack_bits(bits: &[bool]) -> Vec<u8> {
    bits.chunks(8).map(|c| c.iter().enumerate().fold(0u8, |acc, (k, &b)| acc | ((b as u8) << k))).collect()
}

fn unpack_bits(bytes: &[u8], n: usize) -> Option<Vec<bool>> {
    (bytes.len() == n.div_ceil(8)).then(|| (0..n).map(|k| bytes[k / 8] >> (k % 8) & 1 != 0).collect())
}
