//! What the batch and farm tests share: the binary, scratch folders, and comparing the
//! results of two ways of rendering byte for byte.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fluidymation"))
}

pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

pub fn demo() -> PathBuf {
    root().join("fixtures/demo/waving.json")
}

pub fn quads() -> PathBuf {
    root().join("tests/render/quads.json")
}

/// A scratch directory removed at the end of the test (also when it fails).
pub struct Scratch(pub PathBuf);

impl Scratch {
    pub fn new(name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("fm-farm-{}-{}", name, std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    pub fn join(&self, p: &str) -> PathBuf {
        self.0.join(p)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Every file below `dir` (relative paths, hidden ones included), sorted.
pub fn tree(dir: &Path) -> Vec<String> {
    fn walk(base: &Path, dir: &Path, out: &mut Vec<String>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(base, &p, out);
            } else {
                out.push(p.strip_prefix(base).unwrap().to_string_lossy().into_owned());
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

/// The bytes of every result file below `dir`: frames, GIFs and kept layers (not the
/// painted intermediates, the checkpoints or the manifests of a plan's jobs).
pub fn results(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    tree(dir)
        .into_iter()
        .filter(|n| {
            (n.ends_with(".png") || n.ends_with(".gif")) && !n.contains("/paint/") && !n.contains(".fluidymation")
        })
        .map(|n| (n.clone(), std::fs::read(dir.join(&n)).unwrap()))
        .collect()
}

/// The same result files below `a` and `b`, with the same bytes.
#[track_caller]
pub fn assert_same_results(a: &Path, b: &Path) {
    let (x, y) = (results(a), results(b));
    assert!(!x.is_empty(), "no results in {}", a.display());
    assert_eq!(x.keys().collect::<Vec<_>>(), y.keys().collect::<Vec<_>>(), "different files");
    for (name, bytes) in &x {
        assert!(*bytes == y[name], "{name} differs between {} and {}", a.display(), b.display());
    }
}
