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
    let a = anim::load(&demo, &LoadOptions { scale: 0.5, ..Default::default() }).unwrap();
    let root = std::env::temp_dir().join(format!("fm-threads-{}", std::process::id()));
    let run = |threads: usize| {
        let out = root.join(threads.to_string());
        let mut opts = RenderOptions::new(out.clone(), 0..3);
        opts.params = Params::builder().seed(7).build().unwrap();
        opts.scale = 0.5;
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
