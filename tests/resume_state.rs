//! Resume trusts nothing it did not check: an interrupted render's state that was damaged or
//! edited is refused with an error that says what to do, and frames changed after they were
//! written are rendered again — `--resume` never ends with wrong or missing frames.
//!
//! Each case interrupts a small render after a few frames, tampers with what it left, and
//! resumes. The hostile states are those of the issue that asked for this: a progress file
//! claiming 99 999 frames, matches far outside the exemplar, NaN rotations, an origin of 60 000,
//! the field's width and height swapped — with their checksums made to match, so the checks
//! behind the checksums are what refuses them.

mod resume_support;

use fluidymation::{Error, NoProgress, render};
use resume_support::*;

#[test]
fn a_clean_interruption_resumes_to_the_same_bytes() {
    let case = Case::new("clean");
    case.interrupt_after(3);
    let o = case.resume().unwrap();
    assert_eq!((o.resumed, o.frames), (3, FRAMES - 3));
    assert_eq!(case.frames(), case.reference(), "resumed frames differ from the uninterrupted render");
    // After success the engine states are removed; what says the render is complete and
    // what it wrote stays, for a later --resume.
    let left = files(&case.state_dir());
    assert_eq!(left.keys().collect::<Vec<_>>(), ["frames.log", "progress.toml"], "{:?}", left.keys());
}

#[test]
fn a_progress_file_claiming_more_frames_is_refused() {
    let case = Case::new("done-99999");
    case.interrupt_after(3);
    let before = case.frames();
    // As edited by hand: the checksum no longer matches.
    case.edit_progress("done = 3", "done = 99999", false);
    case.refused(&["checksum", "delete", ".fluidymation", "render again"]);
    // With the checksum made to match, the count itself is refused.
    case.edit_progress("done = 99999", "done = 99999", true);
    case.refused(&["99999", "delete"]);
    // One frame more than was recorded.
    case.edit_progress("done = 99999", "done = 4", true);
    case.refused(&["never recorded", "delete"]);
    assert_eq!(case.frames(), before, "a refused resume touches no frame");
}

#[test]
fn damaged_state_files_are_refused() {
    let case = Case::new("damaged");
    case.interrupt_after(3);
    let state = case.state_files()[0].clone();
    let mut bytes = std::fs::read(&state).unwrap();
    let k = bytes.len() / 2;
    bytes[k] ^= 0x10;
    std::fs::write(&state, &bytes).unwrap();
    case.refused(&["checksum", "delete"]);
    std::fs::write(&state, &bytes[..k]).unwrap();
    case.refused(&["truncated", "delete"]);
    std::fs::remove_file(&state).unwrap();
    case.refused(&["delete"]);
}

/// Matches rewritten in every state file, the checksum made to match.
#[track_caller]
fn refused_with_matches(name: &str, edit: impl Fn(&mut MatchRecord), needles: &[&str]) {
    let case = Case::new(name);
    case.interrupt_after(3);
    for f in case.state_files() {
        case.edit_state(&f, |s| s.matches.iter_mut().for_each(&edit));
    }
    case.refused(needles);
}

#[test]
fn matches_outside_the_exemplar_are_refused() {
    refused_with_matches("far", |m| (m.x, m.y) = (1e9, 1e9), &["outside the", "exemplar", "delete"]);
    refused_with_matches("negative", |m| (m.x, m.y) = (-1e6, -1e6), &["outside the", "delete"]);
    refused_with_matches("frame", |m| m.i = 60000, &["exemplar frame", "delete"]);
    refused_with_matches("nan-rotation", |m| (m.c, m.s) = (f32::NAN, f32::NAN), &["rotation", "delete"]);
    refused_with_matches("scaled-rotation", |m| (m.c, m.s) = (2.0, 0.0), &["rotation", "delete"]);
    refused_with_matches("extent", |m| m.ext = f32::INFINITY, &["extent", "delete"]);
}

#[test]
fn windows_that_do_not_fit_are_refused() {
    let case = Case::new("origin");
    case.interrupt_after(3);
    let f = case.state_files()[0].clone();
    case.edit_state(&f, |s| s.origin = (60000, 60000));
    case.refused(&["does not fit", "delete"]);

    let case = Case::new("swapped");
    case.interrupt_after(3);
    let f = case.state_files()[0].clone();
    case.edit_state(&f, |s| {
        assert_ne!(s.w, s.h, "the test needs a window that is not square");
        std::mem::swap(&mut s.w, &mut s.h);
    });
    case.refused(&["window", "delete"]);

    let case = Case::new("moved");
    case.interrupt_after(3);
    let f = case.state_files()[0].clone();
    case.edit_state(&f, |s| s.origin.0 = s.origin.0.saturating_sub(8));
    case.refused(&["window", "delete"]);
}

#[test]
fn frames_changed_after_they_were_written_are_rendered_again() {
    let case = Case::new("frames");
    case.interrupt_after(3);
    let f2 = case.out.join("0002.png");
    let mut bytes = std::fs::read(&f2).unwrap();
    let k = bytes.len() - 20;
    bytes[k] ^= 1;
    std::fs::write(&f2, &bytes).unwrap();
    std::fs::remove_file(case.out.join("0003.png")).unwrap();
    let o = case.resume().unwrap();
    assert_eq!((o.resumed, o.frames), (0, FRAMES), "a damaged frame means starting again");
    assert_eq!(case.frames(), case.reference());

    // Every frame done, only the GIF was missing: a frame changed since is still caught.
    let case = Case::new("all-done");
    case.interrupt_after(FRAMES);
    std::fs::write(case.out.join("0005.png"), b"not what was written").unwrap();
    let o = case.resume().unwrap();
    assert_eq!(o.resumed, 0);
    assert_eq!(case.frames(), case.reference());
}

#[test]
fn a_state_of_another_render_is_refused() {
    let case = Case::new("other");
    case.interrupt_after(2);
    // Another seed gives another fingerprint.
    let mut opts = case.options(true);
    opts.params = opts.params.to_builder().seed(99).build().unwrap();
    let e = render::render(&case.anim(), &opts, &NoProgress).unwrap_err();
    assert!(matches!(e, Error::Stale { .. }), "{e}");
    assert!(e.to_string().contains("resume with the same options"), "{e}");
}
