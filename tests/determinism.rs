//! Same input and seed, same bytes, whatever the number of threads: the demo rendered (three
//! frames at half size, every layer stylized, composited and written) in rayon pools of 1, 2,
//! 3, 8 and 16 threads — more threads than this machine has cores, and more than the parts
//! the occurrence map and the PatchMatch bands are split into.

use fluidymation::NoProgress;
use fluidymation::anim::{self, LoadOptions};
use fluidymation::render::{self, RenderOptions};
use fluidymation::synth::Params;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .filter(|e| e.path().is_file())
        .map(|e| (e.file_name().to_string_lossy().into_owned(), std::fs::read(e.path()).unwrap()))
        .collect()
}

#[test]
fn byte_identical_output_at_1_2_3_8_and_16_threads() {
    let demo = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/demo/waving.json");
    let a = anim::load(&demo, &LoadOptions::default().scale(0.5)).unwrap();
    let root = std::env::temp_dir().join(format!("fm-threads-{}", std::process::id()));
    let run = |threads: usize| {
        let out = root.join(threads.to_string());
        let mut opts = RenderOptions::new(out.clone(), 0..3);
        opts.params = Params::builder().seed(7).build().unwrap();
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| render::render(&a, &opts, &NoProgress)).unwrap();
        files(&out)
    };
    let one = run(1);
    assert_eq!(one.len(), 3, "{:?}", one.keys());
    for threads in [2, 3, 8, 16] {
        assert!(run(threads) == one, "{threads} threads give other bytes than 1 thread");
    }
    let _ = std::fs::remove_dir_all(&root);
}

/// FNV-1a, 64 bits.
fn fnv1a(bytes: impl IntoIterator<Item = u8>) -> u64 {
    bytes.into_iter().fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3))
}

/// The engine's output is pinned: the demo's first four frames at half size, one thread, seed 7,
/// default parameters — the hash of their decoded pixels (not of the PNG bytes, which an
/// encoder update may change). Many commits change the code without meaning to change the
/// output ("output unchanged"); this test is what holds them to it. Four frames, so that the
/// carried-over field (SHIFTNNF and its advection) is covered: with two, a change of the
/// advection went unseen.
///
/// Update `PINNED` only in a commit that changes the output on purpose, and say so in its
/// message (the last: the tone and grain corrections reach a round shape's middle, whose deepest
/// depth bins have too few pixels for their own (`tone::from_shallower`), issue 13; before: the
/// grain keeps its amplitude inside the rim, `ParamsBuilder::grain_match`).
#[test]
fn engine_output_is_pinned() {
    const PINNED: u64 = 0x1659_df96_b664_a425;
    let demo = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/demo/waving.json");
    let a = anim::load(&demo, &LoadOptions::default().scale(0.5)).unwrap();
    let out = std::env::temp_dir().join(format!("fm-pinned-{}", std::process::id()));
    let mut opts = RenderOptions::new(out.clone(), 0..4);
    opts.params = Params::builder().seed(7).build().unwrap();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    pool.install(|| render::render(&a, &opts, &NoProgress)).unwrap();
    let mut pixels = Vec::new();
    for (name, _) in files(&out).iter().filter(|(n, _)| n.ends_with(".png")) {
        let img = image::open(out.join(name)).unwrap().into_rgba16();
        pixels.extend(name.bytes());
        pixels.extend(img.as_raw().iter().flat_map(|v| v.to_le_bytes()));
    }
    let _ = std::fs::remove_dir_all(&out);
    let hash = fnv1a(pixels);
    assert_eq!(hash, PINNED, "the engine's output changed: {hash:#018x}");
}
