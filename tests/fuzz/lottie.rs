//! Lottie: real-world files from `fixtures/lottie/` (and precomp structures made here), mutated
//! 1–16 times — a key deleted, an array element duplicated, a value retyped, a number made
//! hostile, a value copied elsewhere, a precomp layer inserted that may refer to its own asset
//! — then possibly damaged as text (truncated, a `NaN` literal, a stray byte). Loaded at ≤ 48 px
//! and rendered at three frames: every input loads and renders, or is an `Err`.

use super::harness::{Files, Reader, Rng};
use fluidymation::anim::{LoadOptions, lottie};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

pub const READER: Reader = Reader { name: "lottie", make, check };

fn corpus() -> &'static Vec<Value> {
    static C: OnceLock<Vec<Value>> = OnceLock::new();
    C.get_or_init(|| {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/lottie");
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "json"))
            .collect();
        files.sort();
        let mut docs: Vec<Value> =
            files.iter().map(|p| serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()).collect();
        docs.push(precomps());
        docs
    })
}

/// A file made of precomps: reuse, a masked solid, a matte, time remapping.
fn precomps() -> Value {
    let solid = json!({"ty": 1, "nm": "solid", "ind": 1, "sc": "#3366ff", "sw": 100, "sh": 100, "ks": {},
        "masksProperties": [{"mode": "a", "pt": {"a": 0, "k": {"c": true, "v": [[10, 10], [90, 10], [50, 90]],
        "i": [[0, 0], [0, 0], [0, 0]], "o": [[0, 0], [0, 0], [0, 0]]}}, "o": {"a": 0, "k": 100}}]});
    let pre = |id: &str, ind: u32| {
        json!({"ty": 0, "nm": format!("use {id}"), "ind": ind, "refId": id, "w": 100,
        "h": 100, "ip": 0, "op": 20, "st": 0, "ks": {"s": {"a": 0, "k": [50, 50]}}})
    };
    json!({"v": "5.7.1", "fr": 24, "ip": 0, "op": 20, "w": 100, "h": 100,
        "assets": [
            {"id": "inner", "layers": [solid]},
            {"id": "outer", "layers": [pre("inner", 1), pre("inner", 2), {"ty": 4, "nm": "shape", "ind": 3, "ks": {},
                "tt": 1, "shapes": [{"ty": "el", "p": {"a": 0, "k": [50, 50]}, "s": {"a": 0, "k": [60, 60]}},
                {"ty": "fl", "c": {"a": 0, "k": [1, 0, 0, 1]}, "o": {"a": 0, "k": 100}}]}]}],
        "layers": [pre("outer", 1), {"ty": 0, "nm": "remapped", "ind": 2, "refId": "inner", "w": 100, "h": 100,
            "ip": 0, "op": 20, "st": 0, "ks": {}, "tm": {"a": 1, "k": [{"t": 0, "s": [0]}, {"t": 20, "s": [0.5]}]}}]})
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

fn parent_and_key(p: &str) -> Option<(&str, &str)> {
    let i = p.rfind('/')?;
    Some((&p[..i], &p[i + 1..]))
}

fn mutate(doc: &mut Value, rng: &mut Rng) {
    let mut all = Vec::new();
    paths(doc, String::new(), &mut all);
    let p = rng.pick(&all).clone();
    match rng.below(6) {
        0 => {
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
        1 => {
            if let Some(Value::Array(a)) = doc.pointer_mut(&p)
                && let Some(first) = a.first().cloned()
            {
                a.push(first.clone());
                a.insert(0, first);
            }
        }
        2 => {
            let t = rng.below(6);
            if let Some(v) = doc.pointer_mut(&p) {
                *v = match t {
                    0 => Value::Null,
                    1 => Value::String("x".into()),
                    2 => Value::Array(vec![v.clone()]),
                    3 => json!({"k": v.clone()}),
                    4 => Value::Bool(true),
                    _ => json!(0),
                };
            }
        }
        3 => {
            let nums: Vec<&String> = all.iter().filter(|p| doc.pointer(p).is_some_and(|v| v.is_number())).collect();
            if nums.is_empty() {
                return;
            }
            let p = rng.pick(&nums).to_string();
            let x = doc.pointer(&p).and_then(|v| v.as_f64()).unwrap_or(0.0);
            let v = rng.hostile_f64(x);
            if let Some(t) = doc.pointer_mut(&p) {
                *t = if v.is_finite() { json!(v) } else { json!(-1) };
            }
        }
        4 => {
            let b = rng.pick(&all).clone();
            if b.starts_with(&p) {
                return; // would copy a value into itself
            }
            if let Some(v) = doc.pointer(&p).cloned()
                && let Some(t) = doc.pointer_mut(&b)
            {
                *t = v;
            }
        }
        _ => {
            // A precomp layer referring to an asset, possibly the one it is inserted into.
            let ids: Vec<String> = doc["assets"]
                .as_array()
                .map(|a| a.iter().filter_map(|x| x["id"].as_str().map(String::from)).collect())
                .unwrap_or_default();
            let Some(id) = (!ids.is_empty()).then(|| rng.pick(&ids).clone()) else { return };
            let layers: Vec<&String> = all.iter().filter(|p| p.ends_with("/layers")).collect();
            let Some(at) = (!layers.is_empty()).then(|| rng.pick(&layers).to_string()) else { return };
            if let Some(Value::Array(a)) = doc.pointer_mut(&at) {
                a.push(json!({"ty": 0, "nm": "inserted", "refId": id, "ind": 900, "ks": {}, "w": 100, "h": 100}));
            }
        }
    }
}

/// Text-level damage: truncation, a `NaN` literal, a stray byte.
fn damage(text: &str, rng: &mut Rng) -> String {
    let n = text.len().max(1);
    let mut pos = rng.below(n);
    while pos > 0 && !text.is_char_boundary(pos) {
        pos -= 1;
    }
    match rng.below(3) {
        0 => text[..pos].to_string(),
        1 => match text[pos..].find(|c: char| c.is_ascii_digit()) {
            Some(d) => format!("{}NaN{}", &text[..pos + d], &text[pos + d + 1..]),
            None => text.to_string(),
        },
        _ => format!("{}\u{0}{}", &text[..pos], &text[pos..]),
    }
}

fn make(rng: &mut Rng) -> Files {
    let mut doc = rng.pick(corpus()).clone();
    for _ in 0..rng.range(1, 16) {
        mutate(&mut doc, rng);
    }
    let mut text = serde_json::to_string(&doc).unwrap();
    if rng.chance(0.2) {
        text = damage(&text, rng);
    }
    let name = if rng.chance(0.5) { "case-split.json" } else { "case.json" };
    vec![(name.to_string(), text.into_bytes())]
}

fn check(dir: &Path) {
    let split = dir.join("case-split.json");
    let path = if split.exists() { split } else { dir.join("case.json") };
    let Ok(text) = std::fs::read_to_string(&path) else { return };
    let Ok(model) = lottie::parse(&path, &text) else { return };
    // Small renders keep the run fast; the geometry code runs all the same.
    let scale = (48.0 / model.width().max(model.height()).max(1.0)).min(1.0);
    let opts = LoadOptions::default().scale(scale).split_precomps(path.ends_with("case-split.json"));
    let Ok(anim) = lottie::from_model(&path, model, &opts) else { return };
    assert!(anim.width >= 1 && anim.height >= 1 && anim.frames >= 1);
    for r in 0..anim.regions.len().min(6) {
        for f in [0, anim.frames / 2, anim.frames.saturating_sub(1)] {
            if let Ok(rf) = anim.render(r, f) {
                assert_eq!(rf.fill.size(), (anim.width as usize, anim.height as usize));
            }
        }
    }
}

/// Every corpus file loads (the fuzzer's starting points are valid).
pub fn corpus_loads() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/lottie");
    for (k, doc) in corpus().iter().enumerate() {
        let path = dir.join(format!("corpus-{k}.json"));
        let model = lottie::parse(&path, &doc.to_string()).unwrap_or_else(|e| panic!("{e}"));
        let opts = LoadOptions::default().scale(0.25).split_precomps(false);
        let anim = lottie::from_model(&path, model, &opts).unwrap_or_else(|e| panic!("{e}"));
        assert!(!anim.regions.is_empty(), "corpus file {k}");
    }
}
