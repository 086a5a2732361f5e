//! Precomps that would make a frame's work unbounded, refused before anything is drawn: a
//! precomp asset that contains itself (directly or through others), nesting deeper than
//! [`MAX_DEPTH`], and reuse that multiplies into more than [`MAX_LAYER_DRAWS`] layer draws or
//! [`MAX_OFFSCREEN_PIXELS`] pixels of masked or matted layers in one frame.

use super::model::{Content, MAX_DEPTH, MaskMode, Model};
use super::schema;
use crate::error::{Error, Result};
use std::collections::HashMap;
use std::path::Path;

/// Most layer draws one region may need in one frame, precomps expanded (every reuse of a
/// precomp draws all of its layers again).
pub const MAX_LAYER_DRAWS: usize = super::render::MAX_DRAWS;

/// Most pixels of off-screen layer copies one region may need in one frame: each drawing of
/// a masked or matted layer renders it into a canvas-sized buffer first (2^30 px: about a
/// thousand masked layers on a 1000×1000 canvas, a few seconds of work).
pub const MAX_OFFSCREEN_PIXELS: f64 = (1u64 << 30) as f64;

/// The precomp layers (`ty` 0) of a list of layers: their asset ids.
fn refs(layers: &[schema::Layer]) -> impl Iterator<Item = &str> {
    layers.iter().filter(|l| l.ty == Some(Ok(0.0))).filter_map(|l| l.refId.as_deref())
}

/// Checks the precomp references reachable from the root: no cycle, at most [`MAX_DEPTH`]
/// levels. Errors name the assets involved.
pub fn check_references(path: &Path, root: &schema::Root) -> Result<()> {
    let mut index: HashMap<&str, usize> = HashMap::new();
    for (i, a) in root.assets.iter().enumerate() {
        if let Some(id) = a.id.as_deref() {
            index.entry(id).or_insert(i);
        }
    }
    // Depth of the deepest nesting below each asset, once known.
    let mut depth: Vec<Option<usize>> = vec![None; root.assets.len()];
    let mut stack: Vec<usize> = Vec::new();
    let chain = |stack: &[usize], last: usize| -> String {
        let id = |i: usize| root.assets[i].id.clone().unwrap_or_default();
        stack.iter().chain([&last]).map(|&i| format!("'{}'", id(i))).collect::<Vec<_>>().join(" → ")
    };
    // Iterative depth-first search: (asset, next reference to visit, deepest child so far).
    let mut work: Vec<(usize, Vec<usize>, usize, usize)> = Vec::new();
    let children = |a: usize| -> Vec<usize> {
        refs(root.assets[a].layers.as_deref().unwrap_or(&[])).filter_map(|r| index.get(r).copied()).collect()
    };
    for id in refs(root.layers.as_deref().unwrap_or(&[])) {
        let Some(&start) = index.get(id) else { continue };
        if depth[start].is_some() {
            continue;
        }
        work.push((start, children(start), 0, 0));
        stack.push(start);
        while let Some((asset, kids, next, deepest)) = work.last_mut() {
            let asset = *asset;
            if *next == kids.len() {
                let d = *deepest + 1;
                depth[asset] = Some(d);
                work.pop();
                stack.pop();
                if let Some(parent) = work.last_mut() {
                    parent.3 = parent.3.max(d);
                }
                continue;
            }
            let child = kids[*next];
            *next += 1;
            if let Some(d) = depth[child] {
                if stack.len() + d > MAX_DEPTH {
                    return Err(Error::Limit {
                        path: path.to_path_buf(),
                        what: format!("precomp nesting depth ({} …)", chain(&stack[..3.min(stack.len())], child)),
                        value: (stack.len() + d) as f64,
                        limit: MAX_DEPTH as f64,
                    });
                }
                *deepest = (*deepest).max(d);
                continue;
            }
            if stack.contains(&child) {
                let from = stack.iter().position(|&a| a == child).unwrap_or(0);
                return Err(Error::animation(
                    path,
                    format!(
                        "precomp asset '{}' contains itself ({}); a composition cannot include itself: \
                         remove that precomp layer, or re-export the animation",
                        root.assets[child].id.clone().unwrap_or_default(),
                        chain(&stack[from..], child)
                    ),
                ));
            }
            if stack.len() >= MAX_DEPTH {
                return Err(Error::Limit {
                    path: path.to_path_buf(),
                    what: format!("precomp nesting depth ({} …)", chain(&stack[..3.min(stack.len())], child)),
                    value: (stack.len() + 1) as f64,
                    limit: MAX_DEPTH as f64,
                });
            }
            let k = children(child);
            work.push((child, k, 0, 0));
            stack.push(child);
        }
    }
    Ok(())
}

/// The work of drawing one layer of a composition in one frame, precomps expanded: layer
/// draws, and off-screen copies (masked or matted layers).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Work {
    /// Layers drawn.
    pub draws: f64,
    /// Canvas-sized off-screen buffers drawn.
    pub offscreen: f64,
}

impl std::ops::Add for Work {
    type Output = Work;
    fn add(self, o: Work) -> Work {
        Work { draws: self.draws + o.draws, offscreen: self.offscreen + o.offscreen }
    }
}

/// The work of every layer of composition `c` (memoized per composition in `memo`).
fn comp_work(model: &Model, c: usize, memo: &mut HashMap<usize, Work>, depth: usize) -> Work {
    if let Some(&w) = memo.get(&c) {
        return w;
    }
    let comp = &model.comps[c];
    let mut total = Work::default();
    if depth <= MAX_DEPTH {
        for li in 0..comp.layers.len() {
            total = total + layer_work(model, c, li, memo, depth);
        }
    }
    memo.insert(c, total);
    total
}

fn layer_work(model: &Model, c: usize, li: usize, memo: &mut HashMap<usize, Work>, depth: usize) -> Work {
    let l = &model.comps[c].layers[li];
    let masked = l.masks.iter().any(|m| m.mode != MaskMode::None);
    let mut w = Work { draws: 1.0, offscreen: (masked || l.matte.is_some()) as u8 as f64 };
    if let Some((_, src)) = l.matte {
        // The matte source is drawn into a buffer of its own (not its own matte again).
        w.draws += 1.0;
        w.offscreen += 1.0;
        if let Content::Precomp { comp, .. } = model.comps[c].layers[src].content {
            w = w + comp_work(model, comp, memo, depth + 1);
        }
    }
    if let Content::Precomp { comp, .. } = l.content {
        w = w + comp_work(model, comp, memo, depth + 1);
    }
    w
}

/// Checks that no root layer needs more than the limits' work per frame on a
/// `width × height` canvas.
pub fn check_work(path: &Path, model: &Model, width: u32, height: u32) -> Result<()> {
    let mut memo = HashMap::new();
    let pixels = width as f64 * height as f64;
    for li in 0..model.comps.first().map_or(0, |c| c.layers.len()) {
        let w = layer_work(model, 0, li, &mut memo, 0);
        let name = &model.comps[0].layers[li].name;
        if w.draws > MAX_LAYER_DRAWS as f64 {
            return Err(Error::Limit {
                path: path.to_path_buf(),
                what: format!("layers drawn per frame for layer '{name}' (its precomps expanded)"),
                value: w.draws,
                limit: MAX_LAYER_DRAWS as f64,
            });
        }
        if w.offscreen * pixels > MAX_OFFSCREEN_PIXELS {
            return Err(Error::Limit {
                path: path.to_path_buf(),
                what: format!(
                    "pixels of masked or matted layers drawn per frame for layer '{name}' ({} of them, its \
                     precomps expanded, on the {width}x{height} canvas; a smaller --scale draws fewer)",
                    w.offscreen
                ),
                value: w.offscreen * pixels,
                limit: MAX_OFFSCREEN_PIXELS,
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn solid(masked: bool) -> serde_json::Value {
        let mut s = json!({"ty": 1, "nm": "solid", "sc": "#ff0000", "sw": 100, "sh": 100, "ks": {}});
        if masked {
            s["masksProperties"] = json!([{"mode": "a", "pt": {"a": 0, "k": {"c": true,
                "v": [[10, 10], [90, 10], [90, 90]], "i": [[0, 0], [0, 0], [0, 0]], "o": [[0, 0], [0, 0], [0, 0]]}}}]);
        }
        s
    }

    fn pre(id: &str) -> serde_json::Value {
        json!({"ty": 0, "nm": format!("uses {id}"), "refId": id, "w": 100, "h": 100, "ks": {}})
    }

    fn doc(assets: Vec<serde_json::Value>, root: &str) -> String {
        json!({"v": "5.7.1", "fr": 24, "ip": 0, "op": 10, "w": 100, "h": 100, "assets": assets, "layers": [pre(root)]})
            .to_string()
    }

    fn parse(text: &str) -> Result<Model> {
        super::super::parse(Path::new("t.json"), text)
    }

    #[test]
    fn a_precomp_containing_itself_is_an_error_naming_it() {
        // The case: an asset using itself twice over a masked solid.
        let text = doc(vec![json!({"id": "loop", "layers": [pre("loop"), pre("loop"), solid(true)]})], "loop");
        let e = parse(&text).unwrap_err().to_string();
        assert!(e.contains("'loop' contains itself") && e.contains("'loop' → 'loop'"), "{e}");
        // Through another asset.
        let text = doc(
            vec![json!({"id": "a", "layers": [pre("b")]}), json!({"id": "b", "layers": [solid(false), pre("a")]})],
            "a",
        );
        let e = parse(&text).unwrap_err().to_string();
        assert!(e.contains("'a' → 'b' → 'a'"), "{e}");
    }

    #[test]
    fn nesting_deeper_than_the_limit_is_an_error() {
        let chain = |n: usize| {
            let assets = (0..n)
                .map(|k| {
                    let layers = if k + 1 < n { vec![pre(&format!("a{}", k + 1))] } else { vec![solid(false)] };
                    json!({"id": format!("a{k}"), "layers": layers})
                })
                .collect();
            doc(assets, "a0")
        };
        assert!(parse(&chain(MAX_DEPTH)).is_ok());
        let e = parse(&chain(MAX_DEPTH + 1)).unwrap_err();
        assert!(matches!(e, Error::Limit { .. }), "{e}");
        assert!(e.to_string().contains("precomp nesting depth") && e.to_string().contains("'a0'"), "{e}");
    }

    #[test]
    fn reuse_that_multiplies_past_the_budget_is_an_error() {
        // a0 uses a1 twice, a1 uses a2 twice, …: 2^k copies of the masked solid at the bottom.
        let dag = |n: usize| {
            let assets = (0..n)
                .map(|k| {
                    let next = format!("a{}", k + 1);
                    let layers = if k + 1 < n { vec![pre(&next), pre(&next), solid(true)] } else { vec![solid(true)] };
                    json!({"id": format!("a{k}"), "layers": layers})
                })
                .collect();
            doc(assets, "a0")
        };
        let opts = crate::anim::LoadOptions::default();
        let ok = super::super::from_model(Path::new("t.json"), parse(&dag(6)).unwrap(), &opts);
        assert!(ok.is_ok());
        let e = super::super::from_model(Path::new("t.json"), parse(&dag(14)).unwrap(), &opts).unwrap_err();
        assert!(e.to_string().contains("layers drawn per frame for layer 'uses a0'"), "{e}");
        // Fewer draws, but every one of them masked on a large canvas.
        let big = crate::anim::LoadOptions { scale: 16.0, ..Default::default() };
        let e = super::super::from_model(Path::new("t.json"), parse(&dag(9)).unwrap(), &big).unwrap_err();
        assert!(e.to_string().contains("masked or matted"), "{e}");
    }
}
