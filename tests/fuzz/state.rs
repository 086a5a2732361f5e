//! Resume state: the state an interrupted render left (`tests/resume_support`), damaged the
//! way disks, editors and half-finished copies do — and the way a hostile hand does, field by
//! field with the checksums made to match: the progress file's numbers, the frames log's
//! records, the checkpoint's sizes, window, field bits and matches (positions, rotations,
//! frames, extents), mask levels, and the frames already written. Then `--resume`: it must
//! either refuse, or finish with exactly the files of an uninterrupted render.

use super::harness::{Files, Reader, Rng};
use crate::resume_support::{Case, SynthState, files, frame, unframe, with_checksum};
use fluidymation::render;
use std::path::Path;
use std::sync::OnceLock;

pub const READER: Reader = Reader { name: "state", make, check };

/// The output folder of a render interrupted after 3 frames, as files.
fn interrupted() -> &'static Files {
    static I: OnceLock<Files> = OnceLock::new();
    I.get_or_init(|| {
        let c = Case::new("fuzz-interrupted");
        c.interrupt_after(3);
        let mut out: Files = Vec::new();
        let state = files(&c.state_dir());
        for (name, bytes) in files(&c.out) {
            out.push((format!("out/{name}"), bytes));
        }
        for (name, bytes) in state {
            out.push((format!("out/{}/{name}", render::STATE_DIR), bytes));
        }
        out
    })
}

fn f32_hostile(rng: &mut Rng, v: f32) -> f32 {
    rng.hostile_f64(v as f64) as f32
}

fn edit_checkpoint(s: &mut SynthState, rng: &mut Rng) {
    let u = |rng: &mut Rng, v: u64| -> u64 {
        *rng.pick(&[0, 1, v.wrapping_sub(1), v + 1, v * 2, 60_000, 1 << 16, 1 << 40, u64::MAX, v / 2])
    };
    match rng.below(12) {
        0 => s.frame = u(rng, s.frame),
        1 => s.size.0 = u(rng, s.size.0),
        2 => s.size.1 = u(rng, s.size.1),
        3 => s.origin.0 = u(rng, s.origin.0),
        4 => s.origin.1 = u(rng, s.origin.1),
        5 => std::mem::swap(&mut s.w, &mut s.h),
        6 => s.w = u(rng, s.w),
        7 => {
            if !s.bits.is_empty() {
                let i = rng.below(s.bits.len());
                s.bits[i] ^= 1 << rng.below(8);
            }
        }
        8 => s.has_prev = u(rng, s.has_prev),
        // Any other factor than the one the target gives is refused.
        10 if rng.chance(0.5) => s.ext_factor = f32_hostile(rng, s.ext_factor),
        9 => {
            if !s.masks.is_empty() {
                let l = rng.below(s.masks.len());
                if rng.chance(0.5) {
                    s.masks[l].0 = u(rng, s.masks[l].0);
                } else {
                    s.masks.remove(l);
                }
            }
        }
        _ => {
            let n = s.matches.len();
            for _ in 0..rng.range(1, 20) {
                if n == 0 {
                    break;
                }
                let m = &mut s.matches[rng.below(n)];
                match rng.below(9) {
                    // Only impossible flows: a plausible one is a forgery the checksums cannot
                    // tell from the real state (they guard against damage).
                    7 => m.flow.0 = *rng.pick(&[f32::NAN, f32::INFINITY, -f32::INFINITY, 3.4e38, -1e30]),
                    8 => m.flow.1 = *rng.pick(&[f32::NAN, f32::INFINITY, -f32::INFINITY, 3.4e38, -1e30]),
                    0 => m.x = f32_hostile(rng, m.x),
                    1 => m.y = f32_hostile(rng, m.y),
                    2 => m.c = f32_hostile(rng, m.c),
                    3 => m.s = f32_hostile(rng, m.s),
                    4 => m.ext = f32_hostile(rng, m.ext),
                    5 => m.i = *rng.pick(&[m.i.wrapping_add(1), 1000, u16::MAX]),
                    _ => m.flip = *rng.pick(&[0, 1, 2, 255]),
                }
            }
        }
    }
}

fn make(rng: &mut Rng) -> Files {
    // The uninterrupted render is made once, before the first case's clock starts.
    Case::new("fuzz-warm-up").reference();
    let mut files = interrupted().clone();
    let input = ("blob.json".to_string(), crate::resume_support::animation_json().into_bytes());
    for _ in 0..rng.range(1, 3) {
        let k = rng.below(files.len());
        let (name, bytes) = &mut files[k];
        let fix = rng.chance(0.7);
        if name.ends_with(".state")
            && rng.chance(0.8)
            && let Some(mut s) = unframe(bytes).and_then(|p| SynthState::decode(&p))
        {
            edit_checkpoint(&mut s, rng);
            let mut f = frame(&s.encode());
            if !fix {
                f[16] ^= 1; // the checksum no longer matches
            }
            *bytes = f;
            continue;
        }
        if name.ends_with("progress.toml") && rng.chance(0.8) {
            let text = String::from_utf8_lossy(bytes).into_owned();
            let key = *rng.pick(&["version", "fingerprint", "frames", "done", "log_bytes", "log_crc"]);
            let value =
                *rng.pick(&["0", "1", "2", "4", "6", "7", "99999", "-1", "x", "18446744073709551615", "ffffffff"]);
            let edited: String = text
                .lines()
                .map(|l| if l.starts_with(key) { format!("{key} = {value}\n") } else { format!("{l}\n") })
                .collect();
            *bytes = if fix { with_checksum(&edited) } else { edited }.into_bytes();
            continue;
        }
        if name.ends_with("frames.log") && rng.chance(0.7) {
            let text = String::from_utf8_lossy(bytes).into_owned();
            let mut lines: Vec<String> = text.lines().map(String::from).collect();
            if !lines.is_empty() {
                let i = rng.below(lines.len());
                let mut parts: Vec<String> = lines[i].splitn(4, ' ').map(String::from).collect();
                let j = rng.below(parts.len());
                parts[j] = rng
                    .pick(&["0", "5", "../../escape.png", "/etc/passwd", "00000000", "99999999999", "0001.png", "x"])
                    .to_string();
                lines[i] = parts.join(" ");
                if rng.chance(0.3) {
                    lines.swap(0, i);
                }
            }
            let new: String = lines.iter().map(|l| format!("{l}\n")).collect();
            *bytes = new.into_bytes();
            if fix {
                // Make the progress file vouch for the edited log.
                let crc = crc32fast::hash(bytes);
                let len = bytes.len();
                if let Some((_, p)) = files.iter_mut().find(|(n, _)| n.ends_with("progress.toml")) {
                    let text = String::from_utf8_lossy(p).into_owned();
                    let edited: String = text
                        .lines()
                        .map(|l| {
                            if l.starts_with("log_bytes") {
                                format!("log_bytes = {len}\n")
                            } else if l.starts_with("log_crc") {
                                format!("log_crc = {crc:08x}\n")
                            } else {
                                format!("{l}\n")
                            }
                        })
                        .collect();
                    *p = with_checksum(&edited).into_bytes();
                }
            }
            continue;
        }
        // Raw damage to any file: a flipped bit, truncation, removal.
        match rng.below(3) {
            0 if !bytes.is_empty() => {
                let i = rng.below(bytes.len());
                bytes[i] ^= 1 << rng.below(8);
            }
            1 => {
                let n = rng.below(bytes.len().max(1));
                bytes.truncate(n);
            }
            _ => {
                files.remove(k);
            }
        }
    }
    files.push(input);
    files
}

fn check(dir: &Path) {
    let case = Case::at(dir);
    let before = case.frames();
    match case.resume() {
        Ok(_) => assert!(
            case.frames() == case.reference(),
            "--resume succeeded with other files than an uninterrupted render"
        ),
        Err(e) => {
            assert!(!e.to_string().is_empty());
            assert!(case.frames() == before, "a refused resume changed the output: {e}");
        }
    }
}
