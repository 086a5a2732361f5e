//! What one SVG frame holds that will not be drawn as written: text (no fonts), filters,
//! `<foreignObject>`, top-level elements that are neither layers nor
//! definitions. Each is a [`Finding`] naming the element (its id, else its tag, and its line)
//! and the layer it is in; the loader gathers them over the frames into warnings that also
//! name the frame file (see [`Findings`]).

use super::{TopLevel, is_shape};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use usvg::roxmltree::{self, Node, NodeId};

const SVG_NS: &str = "http://www.w3.org/2000/svg";

/// Longest id or href quoted in a message, characters (a data: URL can be megabytes).
const MAX_QUOTE: usize = 48;

/// Most warnings about elements given for one layer (and for elements outside any layer);
/// one more line says how many were left out.
pub const MAX_SHOWN: usize = 10;

/// One problem with one element of one frame.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Finding {
    /// The layer the element is in; `None` outside any layer (definitions, ignored elements).
    pub layer: Option<String>,
    /// `<image id="logo">`, or `<image>` when it has no id.
    pub element: String,
    /// Line of the element in the file, from 1 (not part of the identity across frames).
    pub line: u32,
    /// What is wrong and what is done about it.
    pub what: String,
}

/// `s` in single quotes, shortened to [`MAX_QUOTE`] characters.
pub fn quote(s: &str) -> String {
    if s.chars().count() > MAX_QUOTE {
        format!("'{}…'", s.chars().take(MAX_QUOTE).collect::<String>())
    } else {
        format!("'{s}'")
    }
}

/// `<tag id="…">`, or `<tag>` when the element has no id.
pub fn describe(node: Node) -> String {
    let tag = node.tag_name().name();
    match node.attribute("id").map(str::trim).filter(|s| !s.is_empty()) {
        Some(id) => format!("<{tag} id=\"{}\">", quote(id).trim_matches('\'')),
        None => format!("<{tag}>"),
    }
}

/// The line of `node` in its document, from 1.
pub fn line_of(doc: &roxmltree::Document, node: Node) -> u32 {
    doc.text_pos_at(node.range().start).row
}

/// Top-level elements that draw nothing themselves and are not reported.
fn is_definition(tag: &str) -> bool {
    matches!(
        tag,
        "defs"
            | "style"
            | "metadata"
            | "title"
            | "desc"
            | "script"
            | "linearGradient"
            | "radialGradient"
            | "pattern"
            | "clipPath"
            | "mask"
            | "marker"
            | "symbol"
            | "filter"
            | "font"
            | "font-face"
            | "color-profile"
            | "cursor"
            | "view"
            | "animate"
            | "animateMotion"
            | "animateTransform"
            | "set"
    )
}

/// The `filter` an element sets (attribute or inline style), unless `none`.
fn filter_of<'a>(node: Node<'a, '_>) -> Option<&'a str> {
    let attr = node.attribute("filter").map(str::trim);
    let style = node.attribute("style").and_then(|st| {
        st.split(';').find_map(|decl| {
            let (k, v) = decl.split_once(':')?;
            (k.trim() == "filter").then(|| v.trim().trim_end_matches("!important").trim())
        })
    });
    style.or(attr).filter(|v| !v.is_empty() && *v != "none")
}

/// The findings of one frame (`path`, parsed as `doc`, with its layers `layers`).
pub fn frame(doc: &roxmltree::Document, layers: &[TopLevel]) -> Vec<Finding> {
    let layer_of: HashMap<NodeId, &str> = layers.iter().map(|l| (l.node, l.name.as_str())).collect();
    let mut out = Vec::new();
    let mut add = |node: Node, layer: Option<&str>, what: String| {
        out.push(Finding { layer: layer.map(str::to_string), element: describe(node), line: line_of(doc, node), what });
    };
    for top in doc.root_element().children().filter(|c| c.is_element()) {
        let layer = layer_of.get(&top.id()).copied();
        let tag = top.tag_name().name();
        let svg = top.tag_name().namespace().is_none_or(|ns| ns == SVG_NS);
        if layer.is_none() && svg && !is_definition(tag) && !is_shape(tag) && tag != "g" && tag != "foreignObject" {
            add(top, None, "is not a group or a shape, so it is not a layer; ignored".into());
            continue;
        }
        for node in top.descendants().filter(|n| n.is_element()) {
            if node.tag_name().namespace().is_some_and(|ns| ns != SVG_NS) {
                continue;
            }
            match node.tag_name().name() {
                "text" if !node.ancestors().skip(1).any(|a| a.has_tag_name((SVG_NS, "text"))) => {
                    add(node, layer, "SVG text is not drawn (no fonts are loaded); convert text to paths".into())
                }
                "foreignObject" => add(node, layer, "<foreignObject> is not supported; not drawn".into()),
                "style" if node.text().is_some_and(|t| t.contains("filter")) => add(
                    node,
                    layer,
                    "sets a filter in CSS; SVG filters (blur, shadows, …) are not drawn; drawn without".into(),
                ),
                _ => {}
            }
            if let Some(f) = filter_of(node) {
                add(
                    node,
                    layer,
                    format!("its filter {} is not drawn (SVG filters are ignored); drawn without", quote(f)),
                );
            }
        }
    }
    out
}

/// Findings gathered over the frames: one warning per element, layer and problem, naming the
/// first frame that has it and counting the others.
#[derive(Default)]
pub struct Findings {
    /// Per finding (without its line): the first frame, its line there, and how many frames.
    seen: HashMap<Finding, (PathBuf, u32, usize)>,
    order: Vec<Finding>,
}

impl Findings {
    /// Adds the findings of frame `path`.
    pub fn add(&mut self, path: &Path, found: Vec<Finding>) {
        let mut here: Vec<Finding> = Vec::new();
        for mut f in found {
            let line = std::mem::take(&mut f.line);
            if here.contains(&f) {
                continue;
            }
            here.push(f.clone());
            match self.seen.get_mut(&f) {
                Some(s) => s.2 += 1,
                None => {
                    self.seen.insert(f.clone(), (path.to_path_buf(), line, 1));
                    self.order.push(f);
                }
            }
        }
    }

    /// The warnings about elements of `layer` (`None`: outside any layer), at most
    /// [`MAX_SHOWN`] and a line counting the rest.
    pub fn warnings(&self, layer: Option<&str>) -> Vec<String> {
        let mine: Vec<&Finding> = self.order.iter().filter(|f| f.layer.as_deref() == layer).collect();
        let mut out: Vec<String> = mine
            .iter()
            .take(MAX_SHOWN)
            .map(|f| {
                let (path, line, n) = &self.seen[*f];
                let more = match n - 1 {
                    0 => String::new(),
                    1 => " (also in 1 more frame)".to_string(),
                    m => format!(" (also in {m} more frames)"),
                };
                let at = format!("{} in '{}' line {line}: {}{more}", f.element, path.display(), f.what);
                match &f.layer {
                    Some(l) => format!("layer '{l}': {at}"),
                    None => at,
                }
            })
            .collect();
        if mine.len() > MAX_SHOWN {
            let rest = mine.len() - MAX_SHOWN;
            out.push(match layer {
                Some(l) => format!("layer '{l}': {rest} more warnings about its elements are not shown"),
                None => format!("{rest} more warnings about SVG elements are not shown"),
            });
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quotes_are_shortened_and_elements_described() {
        assert_eq!(quote("a.png"), "'a.png'");
        let long = "x".repeat(100);
        assert_eq!(quote(&long).chars().count(), MAX_QUOTE + 3);
        let doc = roxmltree::Document::parse("<svg><rect id=' r1 '/><rect/></svg>").unwrap();
        let rects: Vec<_> = doc.root_element().children().collect();
        assert_eq!(describe(rects[0]), "<rect id=\"r1\">");
        assert_eq!(describe(rects[1]), "<rect>");
    }

    #[test]
    fn findings_are_counted_over_frames_and_capped() {
        let f = |layer: Option<&str>, el: &str, line| Finding {
            layer: layer.map(str::to_string),
            element: el.to_string(),
            line,
            what: "bad".into(),
        };
        let mut all = Findings::default();
        all.add(Path::new("a/f1.svg"), vec![f(Some("arm"), "<text>", 3)]);
        all.add(Path::new("a/f2.svg"), vec![f(Some("arm"), "<text>", 7), f(None, "<x>", 2)]);
        assert_eq!(all.warnings(Some("arm")), ["layer 'arm': <text> in 'a/f1.svg' line 3: bad (also in 1 more frame)"]);
        assert_eq!(all.warnings(None), ["<x> in 'a/f2.svg' line 2: bad"]);
        let mut many = Findings::default();
        many.add(Path::new("f.svg"), (0..MAX_SHOWN + 3).map(|i| f(Some("a"), &format!("<r{i}>"), 1)).collect());
        let w = many.warnings(Some("a"));
        assert_eq!(w.len(), MAX_SHOWN + 1);
        assert_eq!(w[MAX_SHOWN], "layer 'a': 3 more warnings about its elements are not shown");
    }
}
