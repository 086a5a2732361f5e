//! Structure-aware fuzzing of every reader — Lottie files, SVG frame sequences, PNG mask
//! sequences, exemplar folders and the resume state of interrupted renders — with a time
//! budget (2 s a case in release builds) and a memory bound (512 MiB a case) that count as
//! failures like a panic does. Failures are saved under `tests/fuzz/regressions/<reader>/`
//! and replayed by every run ([`regressions_still_pass`]).
//!
//! `cargo test --release --test fuzz` runs a few hundred new cases per reader (a new seed each
//! run, printed; `FM_FUZZ_SEED=N` repeats one); `cargo test --release --test fuzz -- --ignored`
//! runs the heavy campaign of 201 500 cases and prints per reader the cases, failures, the
//! slowest case and the largest peak.

#[path = "../alloc_support/mod.rs"]
mod alloc_support;
mod exemplar;
mod harness;
mod lottie;
mod masks;
#[path = "../resume_support/mod.rs"]
mod resume_support;
mod state;
mod svg;

use harness::{Reader, Report};

#[global_allocator]
static ALLOC: alloc_support::Counting = alloc_support::Counting;

const READERS: [Reader; 5] = [lottie::READER, svg::READER, masks::READER, exemplar::READER, state::READER];

#[track_caller]
fn passed(reader: &Reader, report: &Report) {
    assert!(report.failures.is_empty(), "fuzz {}: {report}\n{}", reader.name, report.failures.join("\n"));
}

fn fuzz(reader: &Reader, cases: usize) {
    let seed = harness::seed();
    eprintln!("fuzz {}: seed {seed}", reader.name);
    let report = harness::run(reader, seed, cases);
    assert_eq!(report.cases, cases);
    passed(reader, &report);
}

#[test]
fn lottie_files() {
    fuzz(&lottie::READER, 1000);
}

#[test]
fn svg_sequences() {
    fuzz(&svg::READER, 400);
}

#[test]
fn png_mask_sequences() {
    fuzz(&masks::READER, 400);
}

#[test]
fn exemplar_folders() {
    fuzz(&exemplar::READER, 200);
}

#[test]
fn resume_states() {
    fuzz(&state::READER, 40);
}

#[test]
fn regressions_still_pass() {
    for reader in &READERS {
        let report = harness::replay(reader);
        eprintln!("regressions {}: {report}", reader.name);
        passed(reader, &report);
    }
}

#[test]
fn every_lottie_corpus_file_loads() {
    lottie::corpus_loads();
}

/// The heavy campaign, 201 500 cases over the five readers, one test per reader so that
/// they can run side by side: `cargo test --release --test fuzz heavy -- --ignored`.
fn heavy(reader: &Reader, cases: usize) {
    let seed = harness::seed();
    eprintln!("heavy {}: seed {seed}", reader.name);
    let report = harness::run(reader, seed, cases);
    passed(reader, &report);
}

#[test]
#[ignore = "heavy: 110 000 cases"]
fn heavy_lottie() {
    heavy(&lottie::READER, 110_000);
}

#[test]
#[ignore = "heavy: 40 000 cases"]
fn heavy_svg() {
    heavy(&svg::READER, 40_000);
}

#[test]
#[ignore = "heavy: 30 000 cases"]
fn heavy_masks() {
    heavy(&masks::READER, 30_000);
}

#[test]
#[ignore = "heavy: 20 000 cases"]
fn heavy_exemplar() {
    heavy(&exemplar::READER, 20_000);
}

#[test]
#[ignore = "heavy: 1 500 cases"]
fn heavy_state() {
    heavy(&state::READER, 1_500);
}

/// Writes one case's input into `FM_FUZZ_DUMP` (a folder), from `FM_FUZZ_SEED`,
/// `FM_FUZZ_READER` and `FM_FUZZ_CASE`, to look at it or to keep it as a regression.
#[test]
#[ignore = "a tool: writes one fuzz case to a folder"]
fn dump_case() {
    let var = |k: &str| std::env::var(k).unwrap_or_else(|_| panic!("set {k}"));
    let reader = READERS.iter().find(|r| r.name == var("FM_FUZZ_READER")).expect("a reader name");
    let case: usize = var("FM_FUZZ_CASE").parse().unwrap();
    harness::dump(reader, harness::seed(), case, std::path::Path::new(&var("FM_FUZZ_DUMP")));
}
