//! The self-checking state of an interrupted render (`OUT_DIR/.fluidymation/`), which
//! [`render`](crate::render::render) keeps so that `--resume` continues where it stopped and
//! gives the same bytes as an uninterrupted run — or refuses.
//!
//! Three kinds of files, all written to a temporary name and renamed:
//!
//! * `progress.toml`, the commit point: the options' fingerprint, the frames in the range,
//!   how many are done, the length and CRC-32 of the committed part of `frames.log`, and a
//!   CRC-32 of all of it;
//! * `frames.log`, one line per file written (`frame size crc32 path`), appended when the
//!   file is complete, so the frames already written can be verified before they are trusted;
//! * per layer `NN-name.DONE.state`: the synthesizer's state after `DONE` frames, framed by a
//!   magic, its length and its CRC-32.
//!
//! A state that fails a check is never used: a damaged or edited progress or state file is an
//! error that says what to do ([`Error::Corrupt`], with the journal's [`Remedy`]); a frame
//! that was changed or removed after it was written is rendered again ([`Journal::verify`]).
//!
//! When the render is complete, the layers' states are removed and the progress file and the
//! frames log stay ([`Journal::finish`]): a later `--resume` knows the render is done and
//! still checks its frames.

use crate::error::{Error, Result};
use crate::img;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Folder of the resume state inside the output directory.
pub const STATE_DIR: &str = ".fluidymation";

const VERSION: u32 = 2;
const STATE_MAGIC: &[u8; 8] = b"FMSTATE2";

/// CRC-32 (IEEE) of `bytes`.
pub fn crc32(bytes: &[u8]) -> u32 {
    crc32fast::hash(bytes)
}

/// The FNV-1a hash of a text, for fingerprints of render options.
pub fn fingerprint(text: &str) -> u64 {
    let mut h = crate::exemplar::cache::Fnv::default();
    h.bytes(text.as_bytes());
    h.0
}

/// A digest of an input's content: the bytes of a file, or the names and bytes of the files of
/// a sequence folder or glob (SVG, else PNG, as [`crate::anim::source`] picks them). Renders of the same content resume wherever it
/// lies; an input changed since the interrupted run does not.
pub fn input_digest(path: &Path) -> Result<u64> {
    let mut h = crc32fast::Hasher::new();
    let mut len = 0u64;
    let mut add = |bytes: &[u8]| {
        h.update(bytes);
        len = len.wrapping_add(bytes.len() as u64);
    };
    if path.is_file() {
        add(&std::fs::read(path).map_err(|e| Error::io(path, e))?);
    } else {
        let files = match crate::anim::source(path)? {
            crate::anim::Source::Svg(files) | crate::anim::Source::Masks(files) => files,
            crate::anim::Source::Lottie(file) => vec![file],
            crate::anim::Source::LottieFiles(files) => files,
        };
        for f in files {
            add(f.file_name().unwrap_or_default().to_string_lossy().as_bytes());
            add(&std::fs::read(&f).map_err(|e| Error::io(&f, e))?);
        }
    }
    Ok((len << 32) ^ h.finalize() as u64)
}

/// What a user is told to do about a state that cannot be used; it also decides the words of
/// the journal's errors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Remedy {
    /// `render --resume`: delete the state and render again without `--resume`.
    RenderAgain,
    /// A job that runs again by itself (`render-layer`): it starts over from its first frame.
    StartOver,
}

/// One file written by a render, as recorded in `frames.log`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FileRecord {
    /// The 0-based position of its frame in the rendered range.
    pub frame: usize,
    /// The path relative to the output directory (`/`-separated).
    pub path: String,
    /// Its size in bytes.
    pub size: u64,
    /// Its CRC-32.
    pub crc: u32,
}

impl FileRecord {
    /// Checks the file under `dir`: it must exist with the recorded size and CRC-32.
    pub fn check(&self, dir: &Path) -> Option<Damage> {
        let path = dir.join(&self.path);
        let what = match std::fs::read(&path) {
            Err(e) => format!("cannot be read ({e})"),
            Ok(b) => self.check_bytes(&b)?,
        };
        Some(Damage { path, what })
    }

    /// What is wrong with `bytes` as the content of this file (`None`: nothing).
    pub fn check_bytes(&self, bytes: &[u8]) -> Option<String> {
        if bytes.len() as u64 != self.size {
            Some(format!("has {} bytes, {} were written", bytes.len(), self.size))
        } else if crc32(bytes) != self.crc {
            Some("was changed after it was written".to_string())
        } else {
            None
        }
    }

    /// The line of `frames.log` for this record (with its newline).
    pub fn line(&self) -> String {
        format!("{} {} {:08x} {}\n", self.frame, self.size, self.crc, self.path)
    }

    /// Parses a line of `frames.log` (without its newline); `None` when it is malformed or
    /// its path leaves the output directory.
    pub fn parse(line: &str) -> Option<FileRecord> {
        let mut it = line.splitn(4, ' ');
        let frame = it.next()?.parse().ok()?;
        let size = it.next()?.parse().ok()?;
        let crc = u32::from_str_radix(it.next()?, 16).ok()?;
        let path = it.next()?.to_string();
        // Only plain relative paths below the output directory.
        let safe = !path.is_empty()
            && !path.starts_with('/')
            && path.split('/').all(|c| !c.is_empty() && c != "." && c != "..")
            && !path.contains('\\');
        safe.then_some(FileRecord { frame, path, size, crc })
    }
}

/// What is wrong with a frame that was already written.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Damage {
    /// The file, in the output directory.
    pub path: PathBuf,
    /// What changed: missing, size or content.
    pub what: String,
}

/// The resume state of one render in its output directory.
#[derive(Debug)]
pub struct Journal {
    out_dir: PathBuf,
    dir: PathBuf,
    fingerprint: u64,
    total: usize,
    remedy: Remedy,
    /// The committed prefix of `frames.log`: its bytes (to extend the checksum) and records.
    log: Vec<u8>,
    records: Vec<FileRecord>,
    /// Records of the frame in progress, not yet committed.
    pending: Vec<FileRecord>,
}

fn corrupt(path: &Path, out_dir: &Path, remedy: Remedy, what: impl std::fmt::Display) -> Error {
    let message = match remedy {
        Remedy::RenderAgain => format!(
            "the state of the interrupted render is unusable ({what}); delete '{}' and render again without --resume",
            out_dir.join(STATE_DIR).display()
        ),
        Remedy::StartOver => format!("the checkpoint is unusable ({what}); the job starts again from its first frame"),
    };
    Error::Corrupt { path: path.to_path_buf(), message }
}

impl Journal {
    /// Starts the state of a new render of `total` frames in `out_dir`, replacing any older
    /// state there.
    pub fn create(out_dir: &Path, fingerprint: u64, total: usize, remedy: Remedy) -> Result<Journal> {
        let dir = out_dir.join(STATE_DIR);
        if dir.exists() {
            std::fs::remove_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
        }
        std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
        let j = Journal {
            out_dir: out_dir.to_path_buf(),
            dir,
            fingerprint,
            total,
            remedy,
            log: Vec::new(),
            records: Vec::new(),
            pending: Vec::new(),
        };
        img::atomic_write(&j.log_path(), |_| Ok(()))?;
        j.write_progress(0)?;
        Ok(j)
    }

    /// Opens the state of an interrupted render in `out_dir` made with the same options
    /// (`fingerprint`) over `total` frames, and returns it with the number of frames done.
    /// Fails when there is none ([`Error::Missing`]), when it was made with other options
    /// ([`Error::Stale`]), or when any of it fails its checks ([`Error::Corrupt`]); the last two
    /// say what to do as `remedy` says.
    pub fn open(out_dir: &Path, fingerprint: u64, total: usize, remedy: Remedy) -> Result<(Journal, usize)> {
        let dir = out_dir.join(STATE_DIR);
        let path = dir.join("progress.toml");
        let text = std::fs::read(&path).map_err(|e| Error::Missing {
            path: out_dir.to_path_buf(),
            what: format!(
                "there is no interrupted render to resume here ({}: {}); render without --resume",
                path.display(),
                e
            ),
        })?;
        let bad = |what: &str| corrupt(&path, out_dir, remedy, what);
        let text = String::from_utf8(text).map_err(|_| bad("the progress file is not text"))?;
        let Some((body, sum)) = text.rsplit_once("checksum = ") else {
            return Err(bad("the progress file has no checksum"));
        };
        let sum = u32::from_str_radix(sum.trim().trim_start_matches("0x"), 16)
            .map_err(|_| bad("the progress file's checksum is malformed"))?;
        if crc32(body.as_bytes()) != sum {
            return Err(bad("the progress file was damaged or edited: its checksum does not match"));
        }
        let fields: BTreeMap<&str, &str> =
            body.lines().filter_map(|l| l.split_once('=')).map(|(k, v)| (k.trim(), v.trim())).collect();
        let num = |key: &str| -> Result<u64> {
            let v = fields.get(key).ok_or_else(|| bad(&format!("the progress file has no '{key}'")))?;
            let v = v.trim_start_matches("0x");
            let radix = if key.ends_with("crc") { 16 } else { 10 };
            u64::from_str_radix(v, radix).map_err(|_| bad(&format!("'{key}' is not a number")))
        };
        if num("version")? != VERSION as u64 {
            return Err(bad("it was written by another version of fluidymation"));
        }
        if num("fingerprint")? != fingerprint || num("frames")? != total as u64 {
            let message = match remedy {
                Remedy::RenderAgain => {
                    "the interrupted render used another input, frame range, style, --keep-layers \
                                        or parameters; resume with the same options, or render without --resume"
                }
                Remedy::StartOver => {
                    "the checkpoint was made with other options; the job starts again from its first \
                                      frame"
                }
            };
            return Err(Error::Stale { path: path.clone(), message: message.into() });
        }
        let done = num("done")?;
        if done > total as u64 {
            return Err(bad(&format!("it says {done} frames are done, but the range has {total}")));
        }
        let done = done as usize;
        // The committed part of the log.
        let log_path = dir.join("frames.log");
        let (log_len, log_crc) = (num("log_bytes")?, num("log_crc")?);
        let mut log = std::fs::read(&log_path).map_err(|e| corrupt(&log_path, out_dir, remedy, e))?;
        if (log.len() as u64) < log_len {
            return Err(corrupt(&log_path, out_dir, remedy, "the frames log is shorter than committed"));
        }
        log.truncate(log_len as usize);
        if crc32(&log) != log_crc as u32 {
            return Err(corrupt(&log_path, out_dir, remedy, "the frames log was damaged: its checksum does not match"));
        }
        let text =
            std::str::from_utf8(&log).map_err(|_| corrupt(&log_path, out_dir, remedy, "the frames log is not text"))?;
        let records: Vec<FileRecord> = text
            .lines()
            .map(|l| {
                FileRecord::parse(l)
                    .ok_or_else(|| corrupt(&log_path, out_dir, remedy, "a line of the frames log is malformed"))
            })
            .collect::<Result<_>>()?;
        for k in 0..done {
            if !records.iter().any(|r| r.frame == k) {
                return Err(corrupt(
                    &log_path,
                    out_dir,
                    remedy,
                    format!("frame {} is done but was never recorded", k + 1),
                ));
            }
        }
        if let Some(r) = records.iter().find(|r| r.frame >= done) {
            return Err(corrupt(
                &log_path,
                out_dir,
                remedy,
                format!("'{}' is recorded but its frame is not done", r.path),
            ));
        }
        // Drop what an interrupted frame appended after the commit.
        let file = std::fs::OpenOptions::new().write(true).open(&log_path).map_err(|e| Error::io(&log_path, e))?;
        file.set_len(log_len).map_err(|e| Error::io(&log_path, e))?;
        let j = Journal {
            out_dir: out_dir.to_path_buf(),
            dir,
            fingerprint,
            total,
            remedy,
            log,
            records,
            pending: Vec::new(),
        };
        Ok((j, done))
    }

    fn log_path(&self) -> PathBuf {
        self.dir.join("frames.log")
    }

    /// The state file of layer `stage` after `done` frames. Every frame has its own files, so
    /// that the progress file (the commit point) never refers to states that a later,
    /// interrupted save has already overwritten.
    fn state_path(&self, stage: &str, done: usize) -> PathBuf {
        self.dir.join(format!("{}.{}.state", crate::anim::slug(stage), done))
    }

    fn write_progress(&self, done: usize) -> Result<()> {
        let body = format!(
            "# the state of an interrupted render: `fluidymation render … --resume` continues it\n\
             version = {VERSION}\nfingerprint = {}\nframes = {}\ndone = {done}\nlog_bytes = {}\nlog_crc = {:08x}\n",
            self.fingerprint,
            self.total,
            self.log.len(),
            crc32(&self.log),
        );
        let text = format!("{body}checksum = {:08x}\n", crc32(body.as_bytes()));
        img::atomic_write(&self.dir.join("progress.toml"), |w| w.write_all(text.as_bytes()))
    }

    /// Checks every file of the frames done: it must exist with the size and CRC-32 recorded
    /// when it was written. Returns what failed (nothing when all is well).
    pub fn verify(&self) -> Vec<Damage> {
        self.records.iter().filter_map(|r| r.check(&self.out_dir)).collect()
    }

    /// The files of the frames committed so far, in the order they were written.
    pub fn records(&self) -> &[FileRecord] {
        &self.records
    }

    /// `e` with this journal's remedy added when it is an [`Error::Corrupt`] about the state
    /// (a checkpoint that fails the synthesizer's checks, say).
    pub fn advise(&self, e: Error) -> Error {
        match e {
            Error::Corrupt { path, message } => {
                let message = match self.remedy {
                    Remedy::RenderAgain => {
                        format!("{message}; delete '{}' and render again without --resume", self.dir.display())
                    }
                    Remedy::StartOver => format!("{message}; the job starts again from its first frame"),
                };
                Error::Corrupt { path, message }
            }
            other => other,
        }
    }

    /// Records a file of frame `frame` (0-based in the range) that was just written.
    pub fn record(&mut self, frame: usize, path: &Path) -> Result<()> {
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        let rel = path.strip_prefix(&self.out_dir).unwrap_or(path);
        let rel: Vec<String> = rel.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
        self.pending.push(FileRecord { frame, path: rel.join("/"), size: bytes.len() as u64, crc: crc32(&bytes) });
        Ok(())
    }

    /// Commits `done` frames: writes each layer's state (`(stage, bytes)`), appends the
    /// frame's records to the log, writes the progress file, then removes the states of the
    /// frame before.
    pub fn commit(&mut self, done: usize, states: &[(&str, Vec<u8>)]) -> Result<()> {
        for (stage, bytes) in states {
            let mut framed = Vec::with_capacity(bytes.len() + 20);
            framed.extend_from_slice(STATE_MAGIC);
            framed.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
            framed.extend_from_slice(&crc32(bytes).to_le_bytes());
            framed.extend_from_slice(bytes);
            img::atomic_write(&self.state_path(stage, done), |w| w.write_all(&framed))?;
        }
        let lines: String = self.pending.iter().map(FileRecord::line).collect();
        let log_path = self.log_path();
        let mut file = std::fs::OpenOptions::new().append(true).open(&log_path).map_err(|e| Error::io(&log_path, e))?;
        file.write_all(lines.as_bytes()).and_then(|_| file.sync_data()).map_err(|e| Error::io(&log_path, e))?;
        self.log.extend_from_slice(lines.as_bytes());
        self.records.append(&mut self.pending);
        self.write_progress(done)?;
        if done > 0 {
            for (stage, _) in states {
                let _ = std::fs::remove_file(self.state_path(stage, done - 1));
            }
        }
        Ok(())
    }

    /// The state of layer `stage` after `done` frames, checked against its checksum.
    pub fn load_state(&self, stage: &str, done: usize) -> Result<(Vec<u8>, PathBuf)> {
        let path = self.state_path(stage, done);
        let data = std::fs::read(&path).map_err(|e| corrupt(&path, &self.out_dir, self.remedy, e))?;
        let bad = |what: &str| corrupt(&path, &self.out_dir, self.remedy, what);
        if data.len() < 20 || &data[..8] != STATE_MAGIC {
            return Err(bad("not a fluidymation state file"));
        }
        let len = u64::from_le_bytes(data[8..16].try_into().unwrap_or_default());
        let crc = u32::from_le_bytes(data[16..20].try_into().unwrap_or_default());
        let payload = &data[20..];
        if payload.len() as u64 != len {
            return Err(bad("the state file is truncated"));
        }
        if crc32(payload) != crc {
            return Err(bad("the state file was damaged: its checksum does not match"));
        }
        Ok((payload.to_vec(), path))
    }

    /// The render is complete: removes the layers' states and keeps the progress file and
    /// the frames log, which say so and what was written.
    pub fn finish(self) {
        let Ok(rd) = std::fs::read_dir(&self.dir) else { return };
        for e in rd.flatten() {
            if e.path().extension().is_some_and(|x| x == "state") {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }

    /// Removes the whole state (the caller keeps the records elsewhere).
    pub fn remove(self) -> Result<()> {
        std::fs::remove_dir_all(&self.dir).map_err(|e| Error::io(&self.dir, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fingerprints are FNV-1a 64 (the published test vectors), so saved states stay valid
    /// across versions that only move the code.
    #[test]
    fn fingerprint_is_fnv1a() {
        assert_eq!(fingerprint(""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fingerprint("a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fingerprint("foobar"), 0x8594_4171_f739_67e8);
    }

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("fm-journal-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// A journal with two committed frames, each with a file.
    fn two_frames(out: &Path) -> Journal {
        let mut j = Journal::create(out, 42, 5, Remedy::RenderAgain).unwrap();
        for k in 0..2 {
            let f = out.join(format!("{:04}.png", k + 1));
            std::fs::write(&f, format!("frame {k}")).unwrap();
            j.record(k, &f).unwrap();
            j.commit(k + 1, &[("01 arm", vec![k as u8; 10])]).unwrap();
        }
        j
    }

    #[test]
    fn committed_frames_resume() {
        let out = scratch("ok");
        two_frames(&out);
        let (j, done) = Journal::open(&out, 42, 5, Remedy::RenderAgain).unwrap();
        assert_eq!(done, 2);
        assert!(j.verify().is_empty());
        assert_eq!(j.load_state("01 arm", 2).unwrap().0, vec![1u8; 10]);
        // The state of the frame before was removed.
        assert!(j.load_state("01 arm", 1).is_err());
        // Other options.
        let e = Journal::open(&out, 43, 5, Remedy::RenderAgain).unwrap_err().to_string();
        assert!(e.contains("resume with the same options"), "{e}");
        assert!(Journal::open(&out, 42, 6, Remedy::RenderAgain).is_err());
        let _ = std::fs::remove_dir_all(&out);
    }

    #[test]
    fn an_edited_progress_file_is_refused() {
        let out = scratch("edit");
        two_frames(&out);
        let p = out.join(STATE_DIR).join("progress.toml");
        let text = std::fs::read_to_string(&p).unwrap();
        std::fs::write(&p, text.replace("done = 2", "done = 99999")).unwrap();
        let e = Journal::open(&out, 42, 5, Remedy::RenderAgain).unwrap_err().to_string();
        assert!(e.contains("checksum") && e.contains("delete") && e.contains(STATE_DIR), "{e}");
        // Even with a matching checksum, more frames than the range are refused.
        let body = text.replace("done = 2", "done = 99999");
        let body = body.rsplit_once("checksum = ").unwrap().0;
        std::fs::write(&p, format!("{body}checksum = {:08x}\n", crc32(body.as_bytes()))).unwrap();
        let e = Journal::open(&out, 42, 5, Remedy::RenderAgain).unwrap_err().to_string();
        assert!(e.contains("99999"), "{e}");
        // Done frames without records.
        let body = text.replace("done = 2", "done = 3");
        let body = body.rsplit_once("checksum = ").unwrap().0;
        std::fs::write(&p, format!("{body}checksum = {:08x}\n", crc32(body.as_bytes()))).unwrap();
        let e = Journal::open(&out, 42, 5, Remedy::RenderAgain).unwrap_err().to_string();
        assert!(e.contains("never recorded"), "{e}");
        let _ = std::fs::remove_dir_all(&out);
    }

    #[test]
    fn damaged_states_and_logs_are_refused() {
        let out = scratch("damage");
        two_frames(&out);
        let state = out.join(STATE_DIR).join("01-arm.2.state");
        let mut bytes = std::fs::read(&state).unwrap();
        let last = bytes.len() - 1;
        bytes[last] ^= 1;
        std::fs::write(&state, &bytes).unwrap();
        let (j, _) = Journal::open(&out, 42, 5, Remedy::RenderAgain).unwrap();
        let e = j.load_state("01 arm", 2).unwrap_err().to_string();
        assert!(e.contains("checksum") && e.contains("delete"), "{e}");
        std::fs::write(&state, &bytes[..bytes.len() - 3]).unwrap();
        assert!(j.load_state("01 arm", 2).unwrap_err().to_string().contains("truncated"));
        // A damaged log.
        let log = out.join(STATE_DIR).join("frames.log");
        let mut text = std::fs::read(&log).unwrap();
        text[0] = b'7';
        std::fs::write(&log, &text).unwrap();
        assert!(Journal::open(&out, 42, 5, Remedy::RenderAgain).unwrap_err().to_string().contains("frames log"));
        let _ = std::fs::remove_dir_all(&out);
    }

    #[test]
    fn an_interrupted_frame_is_dropped_from_the_log() {
        let out = scratch("torn");
        let mut j = two_frames(&out);
        let f = out.join("0003.png");
        std::fs::write(&f, "frame 2").unwrap();
        j.record(2, &f).unwrap();
        // Appended but not committed (a kill between the log and the progress file).
        let log = out.join(STATE_DIR).join("frames.log");
        let mut file = std::fs::OpenOptions::new().append(true).open(&log).unwrap();
        file.write_all(b"2 7 0000000 0003.p").unwrap();
        drop(file);
        let (mut j, done) = Journal::open(&out, 42, 5, Remedy::RenderAgain).unwrap();
        assert_eq!(done, 2);
        j.record(2, &f).unwrap();
        j.commit(3, &[("01 arm", vec![2; 10])]).unwrap();
        let (j, done) = Journal::open(&out, 42, 5, Remedy::RenderAgain).unwrap();
        assert_eq!(done, 3);
        assert!(j.verify().is_empty());
        let _ = std::fs::remove_dir_all(&out);
    }

    #[test]
    fn changed_frames_are_found() {
        let out = scratch("frames");
        two_frames(&out);
        std::fs::write(out.join("0001.png"), "frame 9").unwrap();
        std::fs::remove_file(out.join("0002.png")).unwrap();
        let (j, _) = Journal::open(&out, 42, 5, Remedy::RenderAgain).unwrap();
        let d = j.verify();
        assert_eq!(d.len(), 2, "{d:?}");
        assert!(d[0].path.ends_with("0001.png") && d[0].what.contains("changed"), "{d:?}");
        assert!(d[1].path.ends_with("0002.png") && d[1].what.contains("cannot be read"), "{d:?}");
        std::fs::write(out.join("0002.png"), "frame 1 and more").unwrap();
        assert!(j.verify()[1].what.contains("bytes"));
        let _ = std::fs::remove_dir_all(&out);
    }

    #[test]
    fn records_stay_inside_the_output_directory() {
        assert!(FileRecord::parse("0 3 0000abcd layers/01_arm/0001.png").is_some());
        for bad in ["0 3 0000abcd /etc/passwd", "0 3 0000abcd ../x.png", "0 3 0000abcd a//b", "0 x 0 a.png"] {
            assert!(FileRecord::parse(bad).is_none(), "{bad}");
        }
    }
}
