//! Fuzzing the Lottie reader: mutated corpus files must never panic — every input either
//! loads (and renders) or gives an `Err`.
//!
//! Mutations, applied 1–8 at a time to a random corpus file: delete a key, duplicate an
//! array element or copy a value to another key, change a value's type, set a number to a
//! huge, tiny, negative or non-finite-looking value, and truncate or corrupt the text. The
//! default run checks [`CASES`] inputs; `cargo test --release --test lottie_fuzz -- --ignored`
//! runs the heavier variant.

use fluidymation::anim::{LoadOptions, lottie};
use proptest::prelude::*;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicUsize, Ordering};

const CASES: u32 = 1000;

fn corpus() -> &'static Vec<(PathBuf, Value)> {
    static C: OnceLock<Vec<(PathBuf, Value)>> = OnceLock::new();
    C.get_or_init(|| {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/lottie");
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "json"))
            .collect();
        files.sort();
        files
            .into_iter()
            .map(|p| (p.clone(), serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap()))
            .collect()
    })
}

fn paths(v: &Value, prefix: String, out: &mut Vec<String>) {
    out.push(prefix.clone());
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                paths(x, format!("{prefix}/{}", k.replace('~', "~0").replace('/', "~1")), out);
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                paths(x, format!("{prefix}/{i}"), out);
            }
        }
        _ => {}
    }
}

#[derive(Clone, Debug)]
enum Mutation {
    Delete(u32),
    Duplicate(u32),
    Retype(u32, u8),
    Number(u32, u8),
    CopyTo(u32, u32),
}

fn parent_and_key(p: &str) -> Option<(&str, &str)> {
    let i = p.rfind('/')?;
    Some((&p[..i], &p[i + 1..]))
}

fn apply(doc: &mut Value, m: &Mutation) {
    let mut all = Vec::new();
    paths(doc, String::new(), &mut all);
    let pick = |i: u32| all[i as usize % all.len()].clone();
    match *m {
        Mutation::Delete(i) => {
            let p = pick(i);
            if let Some((parent, key)) = parent_and_key(&p) {
                match doc.pointer_mut(parent) {
                    Some(Value::Object(o)) => {
                        o.remove(&key.replace("~1", "/").replace("~0", "~"));
                    }
                    Some(Value::Array(a)) => {
                        if let Ok(k) = key.parse::<usize>()
                            && k < a.len()
                        {
                            a.remove(k);
                        }
                    }
                    _ => {}
                }
            }
        }
        Mutation::Duplicate(i) => {
            let p = pick(i);
            if let Some(Value::Array(a)) = doc.pointer_mut(&p)
                && let Some(first) = a.first().cloned()
            {
                a.push(first.clone());
                a.insert(0, first);
            }
        }
        Mutation::Retype(i, t) => {
            let p = pick(i);
            if let Some(v) = doc.pointer_mut(&p) {
                *v = match t % 6 {
                    0 => Value::Null,
                    1 => Value::String("x".into()),
                    2 => Value::Array(vec![v.clone()]),
                    3 => serde_json::json!({"k": v.clone()}),
                    4 => Value::Bool(true),
                    _ => serde_json::json!(0),
                };
            }
        }
        Mutation::Number(i, t) => {
            let nums: Vec<&String> = all.iter().filter(|p| doc.pointer(p).is_some_and(|v| v.is_number())).collect();
            if nums.is_empty() {
                return;
            }
            let p = nums[i as usize % nums.len()].clone();
            if let Some(v) = doc.pointer_mut(&p) {
                let x = v.as_f64().unwrap_or(0.0);
                *v = match t % 8 {
                    0 => serde_json::json!(1e300),
                    1 => serde_json::json!(-1e300),
                    2 => serde_json::json!(-x),
                    3 => serde_json::json!(3.4e38),
                    4 => serde_json::json!(1e-300),
                    5 => serde_json::json!(x * 1e6),
                    6 => serde_json::json!(-1),
                    _ => serde_json::json!(0),
                };
            }
        }
        Mutation::CopyTo(a, b) => {
            let (pa, pb) = (pick(a), pick(b));
            if pb.starts_with(&pa) {
                return; // would copy a value into itself
            }
            if let Some(v) = doc.pointer(&pa).cloned()
                && let Some(t) = doc.pointer_mut(&pb)
            {
                *t = v;
            }
        }
    }
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        any::<u32>().prop_map(Mutation::Delete),
        any::<u32>().prop_map(Mutation::Duplicate),
        (any::<u32>(), any::<u8>()).prop_map(|(a, b)| Mutation::Retype(a, b)),
        (any::<u32>(), any::<u8>()).prop_map(|(a, b)| Mutation::Number(a, b)),
        (any::<u32>(), any::<u32>()).prop_map(|(a, b)| Mutation::CopyTo(a, b)),
    ]
}

/// Text-level damage after the JSON mutations: 0 none, 1 truncate, 2 NaN/Infinity literal,
/// 3 stray byte.
fn text_damage(text: &str, kind: u8, at: u32) -> String {
    let n = text.len().max(1);
    let mut pos = at as usize % n;
    while pos > 0 && !text.is_char_boundary(pos) {
        pos -= 1;
    }
    match kind % 4 {
        1 => text[..pos].to_string(),
        2 => match text[pos..].find(|c: char| c.is_ascii_digit()) {
            Some(d) => format!("{}NaN{}", &text[..pos + d], &text[pos + d + 1..]),
            None => text.to_string(),
        },
        3 => format!("{}\u{0}{}", &text[..pos], &text[pos..]),
        _ => text.to_string(),
    }
}

static RUN: AtomicUsize = AtomicUsize::new(0);

fn check(file: usize, muts: &[Mutation], damage: u8, at: u32) {
    let (path, doc) = &corpus()[file % corpus().len()];
    let mut doc = doc.clone();
    for m in muts {
        apply(&mut doc, m);
    }
    let text = text_damage(&serde_json::to_string(&doc).unwrap(), damage, at);
    RUN.fetch_add(1, Ordering::Relaxed);
    let Ok(model) = lottie::parse(path, &text) else { return };
    // Small renders keep the run fast; the geometry code runs all the same.
    let scale = 48.0 / model.width.max(model.height).max(1.0);
    let opts = LoadOptions { scale, split_precomps: file.is_multiple_of(2) };
    let Ok(anim) = lottie::from_model(path, model, &opts) else { return };
    for r in 0..anim.regions.len().min(6) {
        for f in [0, anim.frames / 2, anim.frames.saturating_sub(1)] {
            let _ = anim.render(r, f);
        }
    }
}

fn fuzz(cases: u32, max_mutations: usize) {
    let before = RUN.load(Ordering::Relaxed);
    let config = ProptestConfig { cases, failure_persistence: None, ..ProptestConfig::default() };
    let mut runner = proptest::test_runner::TestRunner::new(config);
    let strategy = (
        any::<usize>(),
        proptest::collection::vec(mutation(), 1..max_mutations),
        prop_oneof![4 => Just(0u8), 1 => 1u8..4],
        any::<u32>(),
    );
    let result = runner.run(&strategy, |(file, muts, damage, at)| {
        check(file, &muts, damage, at);
        Ok(())
    });
    let ran = RUN.load(Ordering::Relaxed) - before;
    eprintln!("lottie fuzz: {ran} mutated inputs checked");
    if let Err(e) = result {
        panic!("{e}");
    }
    assert!(ran >= cases as usize, "only {ran} inputs ran");
}

#[test]
fn mutated_lottie_never_panics() {
    fuzz(CASES, 8);
}

#[test]
fn every_corpus_file_loads() {
    for (path, doc) in corpus() {
        let text = serde_json::to_string(doc).unwrap();
        let model = lottie::parse(path, &text).unwrap_or_else(|e| panic!("{e}"));
        let opts = LoadOptions { scale: 0.25, split_precomps: false };
        let anim = lottie::from_model(path, model, &opts).unwrap_or_else(|e| panic!("{e}"));
        assert!(!anim.regions.is_empty(), "{}", path.display());
    }
}

#[test]
#[ignore = "heavy: 20 000 mutated inputs"]
fn mutated_lottie_never_panics_heavy() {
    fuzz(20_000, 16);
}
