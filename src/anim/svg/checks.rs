//! What one SVG frame holds that will not be drawn as written: text (no fonts), filters,
//! `<foreignObject>`, broken `<image>`s, top-level elements that are neither layers nor
//! definitions. Each is a [`Finding`] naming the element (its id, else its tag, and its line)
//! and the layer it is in; the loader gathers them over the frames into warnings that also
//! name the frame file (see [`Findings`]).

use super::{TopLevel, is_shape};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use usvg::roxmltree::{self, Node, NodeId};

const SVG_NS: &str = "http://www.w3.org/2000/svg";
const XLINK_NS: &str = "http://www.w3.org/1999/xlink";

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

/// Whether an `<image>`'s content is missing or broken, by the resolved file or data, so that
/// an image used by every frame is read once.
#[derive(Default)]
pub struct ImageCache {
    checked: HashMap<u64, Option<String>>,
}

impl ImageCache {
    /// Why the image that `href` names (relative paths from `dir`) is not drawn, if it is not.
    fn problem(&mut self, href: &str, dir: &Path) -> Option<String> {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        (href, dir).hash(&mut h);
        let key = h.finish();
        if let Some(p) = self.checked.get(&key) {
            return p.clone();
        }
        let p = image_problem(href, dir);
        self.checked.insert(key, p.clone());
        p
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Raster(image::ImageFormat),
    Webp,
    Svg,
}

/// The image kind by magic bytes, as usvg tells them apart.
fn sniff(data: &[u8]) -> Option<Kind> {
    if data.starts_with(b"\x89PNG\r\n\x1a\n") {
        Some(Kind::Raster(image::ImageFormat::Png))
    } else if data.starts_with(b"\xff\xd8\xff") {
        Some(Kind::Raster(image::ImageFormat::Jpeg))
    } else if data.starts_with(b"GIF87a") || data.starts_with(b"GIF89a") {
        Some(Kind::Raster(image::ImageFormat::Gif))
    } else if data.len() >= 12 && &data[..4] == b"RIFF" && &data[8..12] == b"WEBP" {
        Some(Kind::Webp)
    } else {
        None
    }
}

/// Why the image that `href` names is not drawn, or `None` when it is readable. Follows
/// usvg's resolution: a `data:` URL by its MIME type (or its bytes, for `text/plain`), else a
/// file path relative to the frame's folder, by its extension (`.svg`, `.svgz`) or its bytes.
/// PNG, JPEG and GIF are decoded in full (a damaged file is found only so); WebP is checked by
/// its signature only.
fn image_problem(href: &str, dir: &Path) -> Option<String> {
    let (data, kind, name) = if let Ok(url) = data_url::DataUrl::process(href) {
        let name = "its data: URL".to_string();
        let Ok((data, _)) = url.decode_to_vec() else {
            return Some(format!("{name} does not decode (bad base64)"));
        };
        let mime = format!("{}/{}", url.mime_type().type_, url.mime_type().subtype);
        let kind = match mime.as_str() {
            "image/jpg" | "image/jpeg" => Some(Kind::Raster(image::ImageFormat::Jpeg)),
            "image/png" => Some(Kind::Raster(image::ImageFormat::Png)),
            "image/gif" => Some(Kind::Raster(image::ImageFormat::Gif)),
            "image/webp" => Some(Kind::Webp),
            "image/svg+xml" => Some(Kind::Svg),
            "text/plain" => Some(sniff(&data).unwrap_or(Kind::Svg)),
            _ => None,
        };
        let Some(kind) = kind else {
            return Some(format!("{name} has type '{mime}', not PNG, JPEG, GIF, WebP or SVG"));
        };
        (data, kind, name)
    } else {
        let name = quote(href);
        if href.contains("://") {
            return Some(format!(
                "{name} is a URL; only files (relative to the frame's folder) and data: URLs are read"
            ));
        }
        let path = dir.join(href);
        let data = match std::fs::read(&path) {
            Ok(d) => d,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                return Some(format!("{name} was not found (looked for '{}')", path.display()));
            }
            Err(e) => return Some(format!("{name} could not be read ({e})")),
        };
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_lowercase);
        let kind = if matches!(ext.as_deref(), Some("svg" | "svgz")) { Some(Kind::Svg) } else { sniff(&data) };
        let Some(kind) = kind else {
            return Some(format!("{name} is not a PNG, JPEG, GIF, WebP or SVG image"));
        };
        (data, kind, name)
    };
    match kind {
        Kind::Raster(format) => {
            let what = format!("{format:?}").to_uppercase();
            match crate::img::decode(&data, Path::new("image"), crate::img::MAX_IMAGE_SIDE) {
                // Too large to check here, which does not make it broken.
                Ok(_) | Err(crate::error::Error::Limit { .. }) => None,
                Err(e) => Some(format!("{name} is not a readable {what} image ({})", short_cause(&e))),
            }
        }
        Kind::Webp => None,
        Kind::Svg => match usvg::Tree::from_data(&data, &usvg::Options::default()) {
            Ok(_) => None,
            Err(e) => Some(format!("{name} is not a readable SVG image ({e})")),
        },
    }
}

/// The decoder's message, without the file (the warning names it already).
fn short_cause(e: &crate::error::Error) -> String {
    match e {
        crate::error::Error::Image { message, .. } => message.clone(),
        e => e.to_string(),
    }
}

/// The findings of one frame (`path`, parsed as `doc`, with its layers `layers`).
pub fn frame(path: &Path, doc: &roxmltree::Document, layers: &[TopLevel], images: &mut ImageCache) -> Vec<Finding> {
    let dir = path.parent().unwrap_or(Path::new(""));
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
                "image" => {
                    let href = node.attribute((XLINK_NS, "href")).or_else(|| node.attribute("href"));
                    let problem = match href.map(str::trim).filter(|h| !h.is_empty()) {
                        None => Some("has no href".to_string()),
                        Some(h) => images.problem(h, dir),
                    };
                    if let Some(p) = problem {
                        add(node, layer, format!("broken image: {p}; not drawn"));
                    }
                }
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
