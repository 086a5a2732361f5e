//! SVG frame sequences: a directory (or `dir/*.svg` glob) of SVG files, one per frame,
//! sorted naturally and all of the same size, rendered with usvg/resvg. A single SVG file is a
//! sequence of one frame (a still).
//!
//! **Layers.** Each top-level `<g>` of the root `<svg>` is a layer, named by its
//! `inkscape:label` when it has one (Inkscape also gives every layer an automatic `id` such as
//! `layer1`, so the label is the name the designer chose), else by its `id`, else
//! `layer N` (N = its position among the top-level groups that have neither, from 1, so that
//! named groups coming and going do not renumber it). Groups of a frame that share a name
//! are not merged: the second is layer `name (2)`, the third `name (3)`, in every frame (a
//! warning says so; files where a group is itself named like that are refused). Top-level
//! shapes outside any group (`path`, `rect`, `circle`, `text`, `use`, …) are gathered into
//! **one** region named `root`, drawn in document order, because a stray shape rarely
//! deserves a layer of its own and frame-to-frame identity of unnamed shapes is not knowable.
//! `defs`, `style`, metadata and similar are not layers.
//!
//! **Identity across frames** is by name: a layer keeps its region wherever it appears in the
//! sequence, and is invisible (empty) in frames that lack it. Its `visible` range runs from the
//! first to the last frame that has it. Regions are ordered top-most first (SVG draws later
//! elements on top), merging the orders seen in the frames.
//!
//! **Rendering.** A layer is rendered by hiding every other top-level element (wrapping it in
//! `<g display="none">`, so definitions inside it stay usable) and letting resvg draw the
//! document twice: fills only (an injected `stroke: none !important` style) into
//! [`RegionFrame::fill`], and, for layers that set a stroke, strokes only (`fill: none
//! !important`) into [`RegionFrame::strokes`]. (Content inside `<mask>` elements is affected
//! by those styles too.) Text is drawn only if fonts are available to usvg, which they are not
//! by default: a warning says so. Frame rate: 24 fps (SVG files carry none).
//!
//! **Warnings** (what is not drawn as written: text, filters, `<foreignObject>`, an `<image>`
//! whose href is missing, not found, unreadable or not a decodable image, top-level elements
//! that are not layers) name the element (`<text id="title">`, or its tag), the
//! frame file and line where it is first seen, and how many more frames have it; those inside
//! a layer are that [`Region`]'s warnings, the others the [`Animation`]'s (see `checks`).

use super::motion::{Fill, fills_motion};
use super::{Animation, LoadOptions, MAX_FRAMES, MAX_SIDE, Region, RegionFrame, RegionKind, RegionRenderer};
use crate::error::{Error, Result};
use crate::img::{Plane, Rgba};
use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use usvg::roxmltree;

mod checks;

const INKSCAPE_NS: &str = "http://www.inkscape.org/namespaces/inkscape";
/// Name of the region that gathers top-level shapes outside any group.
pub const ROOT_LAYER: &str = "root";

fn is_shape(tag: &str) -> bool {
    matches!(
        tag,
        "path"
            | "rect"
            | "circle"
            | "ellipse"
            | "line"
            | "polyline"
            | "polygon"
            | "text"
            | "use"
            | "image"
            | "switch"
            | "a"
            | "svg"
    )
}

/// A top-level element of one frame: its layer name and byte range in the file.
#[derive(Clone, Debug)]
struct TopLevel {
    name: String,
    /// The element in the document it was found in.
    node: roxmltree::NodeId,
    range: Range<usize>,
    /// Something inside sets a stroke other than `none`.
    strokes: bool,
}

/// Injected style sheets (usvg honours `!important` over the file's own styles) that draw
/// only the fills, or only the strokes.
/// Filters are not drawn (like effects of Lottie layers): a blur on a skewed group costs
/// resvg seconds per frame (found by fuzzing), and what is stylized is the shapes.
const FILLS_ONLY: &str = "* { stroke: none !important; filter: none !important; }";
const STROKES_ONLY: &str = "* { fill: none !important; filter: none !important; }";

fn sets_stroke(node: roxmltree::Node) -> bool {
    node.descendants().filter(|n| n.is_element()).any(|n| {
        let attr = n.attribute("stroke").is_some_and(|v| v.trim() != "none");
        let style = n.attribute("style").is_some_and(|st| {
            st.split(';').any(|decl| {
                let mut kv = decl.splitn(2, ':');
                let (k, v) = (kv.next().unwrap_or("").trim(), kv.next().unwrap_or("").trim());
                k == "stroke" && v != "none" && !v.is_empty()
            })
        });
        attr || style
    })
}

fn parse_xml<'a>(path: &Path, text: &'a str) -> Result<roxmltree::Document<'a>> {
    let opt = roxmltree::ParsingOptions { allow_dtd: true, ..Default::default() };
    roxmltree::Document::parse_with_options(text, opt).map_err(|e| {
        let pos = e.pos();
        Error::animation(path, format!("not valid SVG/XML at line {}, column {}: {}", pos.row, pos.col, e))
    })
}

/// Largest magnitude of a number in an SVG attribute. Coordinates, radii and sizes beyond it
/// make no sense on a canvas of at most 16 384 px, and cost unbounded work when drawn (an arc
/// of radius 10^38 becomes millions of curve segments; found by fuzzing).
pub const MAX_NUMBER: f64 = 1e8;

/// Farthest a drawn shape may reach from the canvas origin, pixels.
pub const MAX_REACH: f32 = 1e6;

/// Most pixels of an SVG pattern tile, when the canvas has fewer: resvg draws one tile into
/// a picture of its own before filling with it, so a pattern 10^7 units wide under a skew
/// asked for 30 GB (found by fuzzing: regression svg/20261202-13521).
pub const MAX_PATTERN_TILE: f64 = (1u64 << 24) as f64;

/// The largest pattern tile that `group` draws with, in pixels of the canvas at scale 1: the
/// tile's size under every transform applied to it (`outer`, the shape's, the pattern's),
/// patterns inside patterns and masks included.
fn largest_pattern_tile(group: &usvg::Group, outer: tiny_skia::Transform) -> f64 {
    let mut largest = 0f64;
    for node in group.children() {
        match node {
            usvg::Node::Group(g) => {
                largest = largest.max(largest_pattern_tile(g, outer));
                if let Some(m) = g.mask() {
                    // A mask's content has its own root: the group's transform applies to it.
                    largest = largest.max(largest_pattern_tile(m.root(), outer.pre_concat(g.abs_transform())));
                }
            }
            usvg::Node::Path(p) => {
                for paint in [p.fill().map(|f| f.paint()), p.stroke().map(|s| s.paint())].into_iter().flatten() {
                    if let usvg::Paint::Pattern(pat) = paint {
                        let (sx, sy) = outer.pre_concat(p.abs_transform()).pre_concat(pat.transform()).get_scale();
                        let r = pat.rect();
                        let tile = r.width() as f64 * sx as f64 * r.height() as f64 * sy as f64;
                        largest = largest.max(if tile.is_nan() { f64::INFINITY } else { tile });
                        largest =
                            largest.max(largest_pattern_tile(pat.root(), tiny_skia::Transform::from_scale(sx, sy)));
                    }
                }
            }
            _ => {}
        }
    }
    largest
}

/// The numbers of an attribute value: in path data and point lists a letter separates them
/// (`M1e38L…`); elsewhere a number must not continue a name or a hex color (`#1e9999`).
fn numbers(value: &str, path_data: bool) -> impl Iterator<Item = f64> + '_ {
    let b = value.as_bytes();
    let mut i = 0;
    std::iter::from_fn(move || {
        while i < b.len() {
            let start = i;
            // Numbers are consumed whole, so in path data every start is a new number.
            let boundary = path_data || start == 0 || {
                let p = b[start - 1];
                !(p.is_ascii_alphanumeric() || p == b'#' || p == b'_' || p == b'.')
            };
            let mut j = i;
            if j < b.len() && (b[j] == b'-' || b[j] == b'+') {
                j += 1;
            }
            let digits = |j: &mut usize| {
                let s = *j;
                while *j < b.len() && b[*j].is_ascii_digit() {
                    *j += 1;
                }
                *j > s
            };
            let mut any = digits(&mut j);
            if j < b.len() && b[j] == b'.' {
                j += 1;
                any |= digits(&mut j);
            }
            if !any {
                i = start + 1;
                continue;
            }
            if j < b.len() && (b[j] == b'e' || b[j] == b'E') {
                let mut k = j + 1;
                if k < b.len() && (b[k] == b'-' || b[k] == b'+') {
                    k += 1;
                }
                if digits(&mut k) {
                    j = k;
                }
            }
            i = j;
            if boundary && let Ok(v) = value[start..j].parse::<f64>() {
                return Some(v);
            }
        }
        None
    })
}

/// Refuses numbers over [`MAX_NUMBER`] in the attributes of `doc` (names, references and
/// text are not looked at).
fn check_numbers(path: &Path, doc: &roxmltree::Document) -> Result<()> {
    for node in doc.descendants().filter(|n| n.is_element()) {
        for a in node.attributes() {
            let name = a.name();
            if a.namespace().is_some() || matches!(name, "id" | "class" | "href" | "font-family" | "lang") {
                continue;
            }
            let path_data = matches!(name, "d" | "points");
            if let Some(v) = numbers(a.value(), path_data).find(|v| v.is_nan() || v.abs() > MAX_NUMBER) {
                return Err(Error::Limit {
                    path: path.to_path_buf(),
                    what: format!("a number in the '{name}' of a <{}>", node.tag_name().name()),
                    value: v,
                    limit: MAX_NUMBER,
                });
            }
        }
    }
    Ok(())
}

/// A top-level group that another group before it in the same frame is named like: it is
/// kept as a layer of its own, named `name (k)` for the k-th such group.
struct Renamed {
    node: roxmltree::NodeId,
    /// The name the groups share.
    name: String,
    /// The layer name it is given, `name (k)` for the k-th such group.
    unique: String,
}

/// What [`top_level`] finds in one frame.
struct FrameInfo {
    /// The layers, bottom first.
    layers: Vec<TopLevel>,
    /// The groups renamed because an earlier group has the same name.
    renamed: Vec<Renamed>,
    /// Whether the root `<svg>` says its size: a `viewBox`, or both `width` and `height`.
    has_size: bool,
}

/// The layers of one frame, bottom first, and what else the loader checks in it.
fn top_level(path: &Path, text: &str) -> Result<FrameInfo> {
    frame_info(path, &parse_xml(path, text)?)
}

/// [`top_level`] of a parsed frame.
fn frame_info(path: &Path, doc: &roxmltree::Document) -> Result<FrameInfo> {
    check_numbers(path, doc)?;
    let root = doc.root_element();
    if root.tag_name().name() != "svg" {
        return Err(Error::animation(path, "the root element is not <svg>"));
    }
    let mut out: Vec<TopLevel> = Vec::new();
    let mut groups = 0;
    // Per group name, how many groups have it so far; the groups renamed.
    let mut seen: HashMap<String, usize> = HashMap::new();
    let mut renamed = Vec::new();
    for child in root.children().filter(|c| c.is_element()) {
        let tag = child.tag_name().name();
        let name = if tag == "g" {
            let named = child
                .attribute((INKSCAPE_NS, "label"))
                .or_else(|| child.attribute("id"))
                .map(str::to_string)
                .filter(|s| !s.trim().is_empty());
            let name = named.unwrap_or_else(|| {
                groups += 1;
                format!("layer {groups}")
            });
            let k = seen.entry(name.clone()).or_insert(0);
            *k += 1;
            if *k > 1 {
                let unique = format!("{name} ({k})");
                renamed.push(Renamed { node: child.id(), name, unique: unique.clone() });
                unique
            } else {
                name
            }
        } else if is_shape(tag) {
            ROOT_LAYER.to_string()
        } else {
            continue;
        };
        out.push(TopLevel { name, node: child.id(), range: child.range(), strokes: sets_stroke(child) });
    }
    // A group renamed `arm (2)` must not meet a group named so in the file.
    for r in &renamed {
        let unique = &r.unique;
        if let Some(other) = out.iter().find(|l| l.name == *unique && l.node != r.node) {
            let line = |id| doc.text_pos_at(doc.get_node(id).map_or(0, |n| n.range().start)).row;
            return Err(Error::animation(
                path,
                format!(
                    "top-level groups share the name '{}', so the one at line {} would be layer '{unique}', but the \
                     group at line {} is named so already; give the groups distinct ids or labels",
                    r.name,
                    line(r.node),
                    line(other.node),
                ),
            ));
        }
    }
    let has_size = root.has_attribute("viewBox") || (root.has_attribute("width") && root.has_attribute("height"));
    Ok(FrameInfo { layers: out, renamed, has_size })
}

/// The document with every top-level element not named `keep` hidden.
fn isolate(text: &str, layers: &[TopLevel], keep: &str) -> String {
    let mut out = String::with_capacity(text.len() + layers.len() * 32);
    let mut pos = 0;
    for l in layers {
        if l.name == keep {
            continue;
        }
        out.push_str(&text[pos..l.range.start]);
        out.push_str("<g display=\"none\">");
        out.push_str(&text[l.range.clone()]);
        out.push_str("</g>");
        pos = l.range.end;
    }
    out.push_str(&text[pos..]);
    out
}

struct SvgSequence {
    files: Vec<PathBuf>,
    names: Vec<String>,
    strokes: Vec<bool>,
    width: u32,
    height: u32,
    scale: (f32, f32),
}

/// The largest side a region is rendered at to find its dominant color when loading.
const COLOR_SIDE: f32 = 1024.0;

impl SvgSequence {
    /// Renders region `region` of frame `frame` on a `width`×`height` canvas, the SVG's user
    /// units scaled by `scale` (the canvas's own size and scale, or smaller ones).
    fn render_at(
        &self,
        region: usize,
        frame: usize,
        (width, height): (u32, u32),
        scale: (f32, f32),
    ) -> Result<RegionFrame> {
        let path = &self.files[frame];
        let doc = self.region_doc(region, frame)?;
        let draw = |sheet: &str| -> Result<tiny_skia::Pixmap> {
            let mut pm = tiny_skia::Pixmap::new(width, height)
                .ok_or_else(|| Error::animation(path, "could not allocate the canvas"))?;
            if let Some(doc) = &doc {
                let tree = self.parse(frame, doc, sheet)?;
                let ts = tiny_skia::Transform::from_scale(scale.0, scale.1);
                resvg::render(&tree, ts, &mut pm.as_mut());
            }
            Ok(pm)
        };
        let fill = super::lottie::to_plane(&draw(FILLS_ONLY)?);
        let strokes = if self.strokes[region] {
            let pm = draw(STROKES_ONLY)?;
            pm.pixels().iter().any(|p| p.alpha() > 0).then(|| super::lottie::to_plane(&pm))
        } else {
            None
        };
        Ok(RegionFrame { fill, strokes, opacity_in_alpha: true })
    }

    /// Frame `frame`'s document with every top-level element but region `region` hidden;
    /// `None` when the frame does not have the region.
    fn region_doc(&self, region: usize, frame: usize) -> Result<Option<String>> {
        let path = &self.files[frame];
        let name = &self.names[region];
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let layers = top_level(path, &text)?.layers;
        Ok(layers.iter().any(|l| &l.name == name).then(|| isolate(&text, &layers, name)))
    }

    /// `doc` (a [`SvgSequence::region_doc`] of frame `frame`) parsed under style sheet `sheet`.
    fn parse(&self, frame: usize, doc: &str, sheet: &str) -> Result<usvg::Tree> {
        let path = &self.files[frame];
        let opt = usvg::Options {
            resources_dir: path.parent().map(Path::to_path_buf),
            style_sheet: Some(sheet.to_string()),
            ..Default::default()
        };
        usvg::Tree::from_str(doc, &opt).map_err(|e| Error::animation(path, format!("SVG: {e}")))
    }

    /// The fills region `region` draws in frame `frame`, in document order, with their
    /// transforms to the canvas (empty when the frame does not have the region).
    fn fills(&self, region: usize, frame: usize) -> Result<Vec<Fill>> {
        let Some(doc) = self.region_doc(region, frame)? else { return Ok(Vec::new()) };
        let tree = self.parse(frame, &doc, FILLS_ONLY)?;
        let canvas = glam::Affine2::from_scale(glam::Vec2::new(self.scale.0, self.scale.1));
        let mut out = Vec::new();
        collect_fills(tree.root(), canvas, &mut out);
        Ok(out)
    }

    /// The dominant color (area-weighted mode over a 5-bit-per-channel histogram) of region
    /// `region` in `frame`, rendered at most [`COLOR_SIDE`] px a side: a canvas larger than
    /// that costs no more to load (canvases up to that size are measured at their own size).
    fn dominant_color(&self, region: usize, frame: usize) -> Option<Rgba> {
        let k = (COLOR_SIDE / self.width.max(self.height) as f32).min(1.0);
        let small = |v: u32| ((v as f32 * k).round() as u32).max(1);
        let fr = self
            .render_at(region, frame, (small(self.width), small(self.height)), (self.scale.0 * k, self.scale.1 * k))
            .ok()?;
        let mut hist = super::ColorHistogram::default();
        hist.add(&fr.fill);
        hist.dominant()
    }
}

impl RegionRenderer for SvgSequence {
    fn render(&self, region: usize, frame: usize) -> Result<RegionFrame> {
        self.render_at(region, frame, (self.width, self.height), self.scale)
    }

    /// The same fills in both frames (the same elements in the same order, each outline with
    /// the same structure) give their motion ([`fills_motion`]): moved by their transforms or
    /// by their coordinates alike, as an exporter writes every frame anew.
    fn fill_motion(&self, region: usize, from: usize, to: usize) -> Option<Plane<Option<glam::Vec2>>> {
        let (a, b) = (self.fills(region, from).ok()?, self.fills(region, to).ok()?);
        fills_motion(&a, &b, self.width, self.height)
    }
}

/// Every visible filled path under `group` (text as its outlines), in drawing order, with its
/// transform to the canvas (`canvas` · its absolute transform).
fn collect_fills(group: &usvg::Group, canvas: glam::Affine2, out: &mut Vec<Fill>) {
    for node in group.children() {
        match node {
            usvg::Node::Group(g) => collect_fills(g, canvas, out),
            usvg::Node::Text(t) => collect_fills(t.flattened(), canvas, out),
            usvg::Node::Path(p) => {
                let Some(fill) = p.fill().filter(|_| p.is_visible()) else { continue };
                let t = p.abs_transform();
                let m = glam::Affine2::from_cols_array(&[t.sx, t.ky, t.kx, t.sy, t.tx, t.ty]);
                let rule = match fill.rule() {
                    usvg::FillRule::NonZero => tiny_skia::FillRule::Winding,
                    usvg::FillRule::EvenOdd => tiny_skia::FillRule::EvenOdd,
                };
                out.push(Fill { path: p.data().clone(), m: canvas * m, rule });
            }
            usvg::Node::Image(_) => {}
        }
    }
}

/// Loads an SVG frame sequence: `files` in order, as `input` (a folder, a glob or one file)
/// names them.
pub fn load(input: &Path, files: Vec<PathBuf>, options: &LoadOptions) -> Result<Animation> {
    if files.len() > MAX_FRAMES {
        return Err(Error::Limit {
            path: input.to_path_buf(),
            what: "frame count".into(),
            value: files.len() as f64,
            limit: MAX_FRAMES as f64,
        });
    }
    let opt = usvg::Options::default();
    let mut size: Option<(f32, f32)> = None;
    // Names in z-order (bottom first), merged over frames; per name, the frames having it.
    let mut order: Vec<String> = Vec::new();
    let mut frames_of: HashMap<String, Vec<usize>> = HashMap::new();
    let mut stroked: Vec<String> = Vec::new();
    let mut findings = checks::Findings::default();
    let mut images = checks::ImageCache::default();
    // Layer names given to groups sharing a name (`arm (2)`), and names found in the files,
    // each with the first frame that has it: no name may be both.
    let mut made_unique: HashMap<String, PathBuf> = HashMap::new();
    let mut named_so: HashMap<String, PathBuf> = HashMap::new();
    // The largest pattern tile of any frame (pixels at scale 1) and its frame.
    let mut tile: Option<(f64, &PathBuf)> = None;
    for (f, path) in files.iter().enumerate() {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        if text.trim().is_empty() {
            return Err(Error::Empty { path: path.clone(), what: "the SVG file is empty".into() });
        }
        let doc = parse_xml(path, &text)?;
        let FrameInfo { layers, renamed, has_size } = frame_info(path, &doc)?;
        let mut found = checks::frame(path, &doc, &layers, &mut images);
        for r in &renamed {
            let unique = &r.unique;
            made_unique.entry(unique.clone()).or_insert_with(|| path.clone());
            if let Some(node) = doc.get_node(r.node) {
                found.push(checks::Finding {
                    layer: Some(unique.clone()),
                    element: checks::describe(node),
                    line: checks::line_of(&doc, node),
                    what: format!(
                        "an earlier top-level group in this frame is also named '{}'; kept apart as layer \
                         '{unique}', not merged (groups sharing a name are told apart by their order in each frame)",
                        r.name
                    ),
                });
            }
        }
        for l in layers.iter().filter(|l| !renamed.iter().any(|r| r.node == l.node)) {
            named_so.entry(l.name.clone()).or_insert_with(|| path.clone());
        }
        findings.add(path, found);
        // The document parsed above, with the options usvg parses text with.
        let tree = usvg::Tree::from_xmltree(&doc, &opt).map_err(|e| Error::animation(path, format!("SVG: {e}")))?;
        let s = (tree.size().width(), tree.size().height());
        if !has_size {
            return Err(Error::animation(
                path,
                format!(
                    "the <svg> element has no width and height and no viewBox, so its size ({}x{}) would be guessed \
                     from what this frame draws; give every frame the same viewBox (or width and height)",
                    s.0.round(),
                    s.1.round()
                ),
            ));
        }
        // Shapes drawn far outside the canvas cost unbounded work to stroke and fill (a
        // circle scaled 2 000 000 times hangs the rasterizer; found by fuzzing).
        let b = tree.root().abs_stroke_bounding_box();
        let reach = [b.left(), b.top(), b.right(), b.bottom()].iter().fold(0f32, |m, v| m.max(v.abs()));
        if reach.is_nan() || reach > MAX_REACH {
            return Err(Error::Limit {
                path: path.clone(),
                what: "how far a shape reaches outside the canvas, pixels".into(),
                value: reach as f64,
                limit: MAX_REACH as f64,
            });
        }
        let t = largest_pattern_tile(tree.root(), tiny_skia::Transform::identity());
        if t > tile.map_or(0.0, |(t, _)| t) {
            tile = Some((t, path));
        }
        match size {
            None => {
                if s.0 > MAX_SIDE as f32 || s.1 > MAX_SIDE as f32 {
                    return Err(Error::Limit {
                        path: path.clone(),
                        what: "canvas side".into(),
                        value: s.0.max(s.1) as f64,
                        limit: MAX_SIDE as f64,
                    });
                }
                size = Some(s);
            }
            Some(first) if (first.0 - s.0).abs() > 0.5 || (first.1 - s.1).abs() > 0.5 => {
                return Err(Error::SizeMismatch {
                    path: path.clone(),
                    expected: (first.0.round() as u32, first.1.round() as u32),
                    found: (s.0.round() as u32, s.1.round() as u32),
                });
            }
            Some(_) => {}
        }
        let mut prev: Option<usize> = None;
        let mut seen_here: Vec<&str> = Vec::new();
        for l in &layers {
            if seen_here.contains(&l.name.as_str()) {
                continue;
            }
            seen_here.push(&l.name);
            if layers.iter().any(|x| x.name == l.name && x.strokes) && !stroked.contains(&l.name) {
                stroked.push(l.name.clone());
            }
            let frames = frames_of.entry(l.name.clone()).or_default();
            frames.push(f);
            match order.iter().position(|n| n == &l.name) {
                Some(i) => prev = Some(i),
                None => {
                    let at = prev.map_or(0, |p| p + 1);
                    order.insert(at, l.name.clone());
                    prev = Some(at);
                }
            }
        }
    }
    let (w, h) = size.ok_or_else(|| Error::Empty { path: input.to_path_buf(), what: "no SVG frames".into() })?;
    let mut clashes: Vec<(&String, &PathBuf)> = made_unique.iter().filter(|(n, _)| named_so.contains_key(*n)).collect();
    clashes.sort();
    if let Some((name, renamed_in)) = clashes.first() {
        return Err(Error::animation(
            &named_so[*name],
            format!(
                "a top-level group is named '{name}', which is also the layer name given in '{}' to a group sharing \
                 its name with an earlier one; give the groups distinct ids or labels",
                renamed_in.display()
            ),
        ));
    }
    if order.is_empty() {
        return Err(Error::Empty {
            path: input.to_path_buf(),
            what: "the SVG frames have no top-level groups or shapes to stylize".into(),
        });
    }
    let (width, height) = super::scaled_canvas(input, w, h, options.scale)?;
    if let Some((t, path)) = tile {
        let px = t * (width as f64 / w as f64) * (height as f64 / h as f64);
        let limit = MAX_PATTERN_TILE.max(width as f64 * height as f64);
        if px.is_nan() || px > limit {
            return Err(Error::Limit {
                path: path.clone(),
                what: "pixels of a pattern tile (its size under its transforms and --scale; at most the canvas's, or 2^24)"
                    .into(),
                value: px.round(),
                limit,
            });
        }
    }
    let warnings = findings.warnings(None);
    let names: Vec<String> = order.into_iter().rev().collect();
    let frames = files.len();
    let strokes = names.iter().map(|n| stroked.contains(n)).collect();
    let renderer = SvgSequence { files, names, strokes, width, height, scale: (width as f32 / w, height as f32 / h) };
    let regions = renderer
        .names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let fr = &frames_of[name];
            let visible = fr[0]..fr[fr.len() - 1] + 1;
            let mut warnings = Vec::new();
            if fr.len() < visible.len() {
                let missing: Vec<usize> = visible.clone().filter(|f| fr.binary_search(f).is_err()).collect();
                let mut list: Vec<String> =
                    missing.iter().take(3).map(|&f| format!("'{}'", renderer.files[f].display())).collect();
                if missing.len() > 3 {
                    list.push(format!("{} more", missing.len() - 3));
                }
                let (n, s) = (missing.len(), if missing.len() == 1 { "" } else { "s" });
                warnings.push(format!(
                    "layer '{name}' is missing from {n} frame{s} of its range ({}); it is empty there",
                    list.join(", ")
                ));
            }
            warnings.extend(findings.warnings(Some(name)));
            Region {
                index: i + 1,
                name: name.clone(),
                kind: if name == ROOT_LAYER { RegionKind::SvgRoot } else { RegionKind::SvgGroup },
                // The dominant color of its first visible frame.
                color: renderer.dominant_color(i, visible.start).unwrap_or([1.0, 1.0, 1.0, 0.0]),
                visible,
                has_strokes: renderer.strokes[i],
                warnings,
            }
        })
        .collect::<Vec<_>>();
    Ok(Animation::new(input.to_path_buf(), width, height, 24.0, frames, regions, None, warnings, Box::new(renderer)))
}

#[cfg(test)]
mod tests {
    #[test]
    fn numbers_in_attributes() {
        let v: Vec<f64> = super::numbers("M1e38L-2.5.5 3e", true).collect();
        assert_eq!(v, [1e38, -2.5, 0.5, 3.0]);
        let v: Vec<f64> = super::numbers("#1e9999 rgb(1,2e3,3) layer1e9 12", false).collect();
        assert_eq!(v, [1.0, 2e3, 3.0, 12.0]);
    }
}
