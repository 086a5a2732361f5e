//! Interrupted renders to tamper with (`tests/resume_state.rs`, the resume-state fuzzer): a
//! small animation, its uninterrupted render, and readers and writers of the state files'
//! format (the frame of [`fluidymation::resume`] around the synthesizer's checkpoint).
#![allow(dead_code)]

use crc32fast::hash as crc32;
use fluidymation::anim::{self, Animation, LoadOptions};
use fluidymation::render::{self, RenderOptions, RenderSummary};
use fluidymation::synth::Params;
use fluidymation::{Error, NoProgress};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Frames of the test animation.
pub const FRAMES: usize = 6;

/// A 96×64 canvas with one ellipse (wider than tall) moving right and growing.
pub fn animation_json() -> String {
    serde_json::json!({
        "v": "5.7.1", "fr": 12, "ip": 0, "op": FRAMES, "w": 96, "h": 64,
        "layers": [{
            "ty": 4, "nm": "blob", "ind": 1, "ip": 0, "op": FRAMES, "st": 0,
            "ks": {"p": {"a": 1, "k": [{"t": 0, "s": [36, 32]}, {"t": FRAMES - 1, "s": [56, 32]}]}},
            "shapes": [
                {"ty": "el", "p": {"a": 0, "k": [0, 0]},
                 "s": {"a": 1, "k": [{"t": 0, "s": [40, 22]}, {"t": FRAMES - 1, "s": [48, 26]}]}},
                {"ty": "fl", "c": {"a": 0, "k": [0.8, 0.2, 0.1, 1]}, "o": {"a": 0, "k": 100}}
            ]
        }]
    })
    .to_string()
}

/// Every file in `dir` (recursively, relative names), except the resume state.
pub fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(base: &Path, dir: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        let Ok(rd) = std::fs::read_dir(dir) else { return };
        for e in rd.flatten() {
            let p = e.path();
            if p.file_name().is_some_and(|n| n == render::STATE_DIR) {
                continue;
            }
            if p.is_dir() {
                walk(base, &p, out);
            } else {
                let name = p.strip_prefix(base).unwrap().to_string_lossy().into_owned();
                out.insert(name, std::fs::read(&p).unwrap());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// One tampering experiment: an input file and an output folder of its own.
pub struct Case {
    pub dir: PathBuf,
    pub input: PathBuf,
    pub out: PathBuf,
    /// The folder of a case of its own, removed with the case (panics included).
    _scratch: Option<tempfile::TempDir>,
}

impl Case {
    /// A case in a folder prepared elsewhere (`blob.json` and `out/`), left in place.
    pub fn at(dir: &Path) -> Case {
        Case { dir: dir.to_path_buf(), input: dir.join("blob.json"), out: dir.join("out"), _scratch: None }
    }

    pub fn new(name: &str) -> Case {
        let scratch = tempfile::Builder::new().prefix(&format!("fm-resume-{name}-")).tempdir().unwrap();
        let dir = scratch.path().to_path_buf();
        let input = dir.join("blob.json");
        std::fs::write(&input, animation_json()).unwrap();
        Case { out: dir.join("out"), input, dir, _scratch: Some(scratch) }
    }

    pub fn anim(&self) -> Animation {
        anim::load(&self.input, &LoadOptions::default()).unwrap()
    }

    pub fn options(&self, resume: bool) -> RenderOptions {
        let mut o = RenderOptions::new(self.out.clone(), 0..FRAMES);
        o.gif = Some(self.out.join("blob.gif"));
        o.keep_layers = true;
        o.params = Params::builder().seed(5).build().unwrap();
        o.resume = resume;
        o
    }

    /// The files of the uninterrupted render (made once per test process).
    pub fn reference(&self) -> BTreeMap<String, Vec<u8>> {
        static REF: OnceLock<BTreeMap<String, Vec<u8>>> = OnceLock::new();
        REF.get_or_init(|| {
            let c = Case::new("reference");
            render::render(&c.anim(), &c.options(false), &NoProgress).unwrap();
            files(&c.out)
        })
        .clone()
    }

    /// Renders and cancels once `k` frames are done (with `k == FRAMES`, before the GIF).
    pub fn interrupt_after(&self, k: usize) {
        let stop = move |stage: &str, done: usize, _: usize| {
            !((k < FRAMES && stage == "frames" && done == k) || (k == FRAMES && stage == "gif"))
        };
        let e = render::render(&self.anim(), &self.options(false), &stop).unwrap_err();
        assert!(matches!(e, Error::Cancelled), "{e}");
    }

    pub fn resume(&self) -> fluidymation::Result<RenderSummary> {
        render::render(&self.anim(), &self.options(true), &NoProgress)
    }

    /// The output files (frames, layers, GIF).
    pub fn frames(&self) -> BTreeMap<String, Vec<u8>> {
        files(&self.out)
    }

    /// Resuming must fail with an error holding every needle, and change no file.
    #[track_caller]
    pub fn refused(&self, needles: &[&str]) {
        let before = self.frames();
        let e = self.resume().expect_err("a tampered state was accepted");
        let text = e.to_string();
        assert!(matches!(e, Error::Corrupt { .. }), "{text}");
        for n in needles {
            assert!(text.contains(n), "'{n}' not in: {text}");
        }
        assert!(self.frames() == before, "a refused resume changed the output");
    }

    pub fn state_dir(&self) -> PathBuf {
        self.out.join(render::STATE_DIR)
    }

    /// The layers' state files, sorted.
    pub fn state_files(&self) -> Vec<PathBuf> {
        let mut v: Vec<PathBuf> = std::fs::read_dir(self.state_dir())
            .unwrap()
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|x| x == "state"))
            .collect();
        v.sort();
        v
    }

    /// Replaces `from` by `to` in the progress file; with `fix`, the checksum is made to match.
    pub fn edit_progress(&self, from: &str, to: &str, fix: bool) {
        let p = self.state_dir().join("progress.toml");
        let text = std::fs::read_to_string(&p).unwrap();
        let text = text.replace(from, to);
        let text = if fix { with_checksum(&text) } else { text };
        std::fs::write(&p, text).unwrap();
    }

    /// Decodes a state file, lets `f` change it, and writes it back with matching checksums.
    pub fn edit_state(&self, path: &Path, f: impl FnOnce(&mut SynthState)) {
        let mut s = SynthState::decode(&unframe(&std::fs::read(path).unwrap()).unwrap()).unwrap();
        f(&mut s);
        std::fs::write(path, frame(&s.encode())).unwrap();
    }
}

/// The progress file's text with its checksum line recomputed.
pub fn with_checksum(text: &str) -> String {
    let body = text.rsplit_once("checksum = ").map_or(text, |(b, _)| b);
    format!("{body}checksum = {:08x}\n", crc32(body.as_bytes()))
}

/// The payload of a state file (magic, length, CRC-32, payload), when well framed.
pub fn unframe(data: &[u8]) -> Option<Vec<u8>> {
    (data.len() >= 20 && &data[..8] == b"FMSTATE2").then(|| data[20..].to_vec())
}

/// A state file around `payload`, with a matching checksum.
pub fn frame(payload: &[u8]) -> Vec<u8> {
    let mut v = b"FMSTATE2".to_vec();
    v.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    v.extend_from_slice(&crc32(payload).to_le_bytes());
    v.extend_from_slice(payload);
    v
}

/// One saved match of the previous frame's field.
#[derive(Clone, Debug)]
pub struct MatchRecord {
    pub x: f32,
    pub y: f32,
    pub c: f32,
    pub s: f32,
    pub err: f32,
    pub ext: f32,
    /// `T^flow` of the previous frame at this pixel.
    pub flow: (f32, f32),
    pub i: u16,
    pub flip: u8,
}

/// The synthesizer's checkpoint (`FMSYNTH4`), decoded field by field.
#[derive(Clone, Debug)]
pub struct SynthState {
    pub fingerprint: Vec<u8>,
    pub frame: u64,
    pub size: (u64, u64),
    /// The extent factor k (NaN before the first painted frame).
    pub ext_factor: f32,
    pub has_prev: u64,
    pub origin: (u64, u64),
    pub w: u64,
    pub h: u64,
    pub bits: Vec<u8>,
    pub matches: Vec<MatchRecord>,
    /// `(pixel count, packed bits)` per pyramid level.
    pub masks: Vec<(u64, Vec<u8>)>,
}

struct Rd<'a>(&'a [u8], usize);

impl Rd<'_> {
    fn take(&mut self, n: usize) -> Option<&[u8]> {
        let s = self.0.get(self.1..self.1.checked_add(n)?)?;
        self.1 += n;
        Some(s)
    }
    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
    fn f32(&mut self) -> Option<f32> {
        Some(f32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
    fn bytes(&mut self) -> Option<Vec<u8>> {
        let n = self.u64()? as usize;
        Some(self.take(n)?.to_vec())
    }
}

impl SynthState {
    pub fn decode(data: &[u8]) -> Option<SynthState> {
        let mut r = Rd(data, 0);
        if r.take(8)? != b"FMSYNTH4" {
            panic!("the checkpoint format changed: update tests/resume_support");
        }
        let fingerprint = r.bytes()?;
        let frame = r.u64()?;
        let size = (r.u64()?, r.u64()?);
        let ext_factor = r.f32()?;
        let has_prev = r.u64()?;
        let mut s = SynthState {
            fingerprint,
            frame,
            size,
            ext_factor,
            has_prev,
            origin: (0, 0),
            w: 0,
            h: 0,
            bits: Vec::new(),
            matches: Vec::new(),
            masks: Vec::new(),
        };
        if has_prev == 0 {
            return (r.1 == data.len()).then_some(s);
        }
        s.origin = (r.u64()?, r.u64()?);
        s.w = r.u64()?;
        s.h = r.u64()?;
        s.bits = r.bytes()?;
        let set: usize = s.bits.iter().map(|b| b.count_ones() as usize).sum();
        for _ in 0..set {
            let (x, y, c, sn, err, ext) = (r.f32()?, r.f32()?, r.f32()?, r.f32()?, r.f32()?, r.f32()?);
            let flow = (r.f32()?, r.f32()?);
            let rest = r.take(3)?;
            s.matches.push(MatchRecord {
                x,
                y,
                c,
                s: sn,
                err,
                ext,
                flow,
                i: u16::from_le_bytes([rest[0], rest[1]]),
                flip: rest[2],
            });
        }
        let levels = r.u64()?;
        for _ in 0..levels {
            let n = r.u64()?;
            s.masks.push((n, r.bytes()?));
        }
        (r.1 == data.len()).then_some(s)
    }

    pub fn encode(&self) -> Vec<u8> {
        let mut v = b"FMSYNTH4".to_vec();
        let u = |v: &mut Vec<u8>, x: u64| v.extend_from_slice(&x.to_le_bytes());
        u(&mut v, self.fingerprint.len() as u64);
        v.extend_from_slice(&self.fingerprint);
        for x in [self.frame, self.size.0, self.size.1] {
            u(&mut v, x);
        }
        v.extend_from_slice(&self.ext_factor.to_le_bytes());
        u(&mut v, self.has_prev);
        if self.has_prev == 0 {
            return v;
        }
        for x in [self.origin.0, self.origin.1, self.w, self.h, self.bits.len() as u64] {
            u(&mut v, x);
        }
        v.extend_from_slice(&self.bits);
        for m in &self.matches {
            for f in [m.x, m.y, m.c, m.s, m.err, m.ext, m.flow.0, m.flow.1] {
                v.extend_from_slice(&f.to_le_bytes());
            }
            v.extend_from_slice(&m.i.to_le_bytes());
            v.push(m.flip);
        }
        u(&mut v, self.masks.len() as u64);
        for (n, bits) in &self.masks {
            u(&mut v, *n);
            u(&mut v, bits.len() as u64);
            v.extend_from_slice(bits);
        }
        v
    }
}
