//! SVG frame sequences: layers from top-level groups, identity by name, sizes, errors.

use fluidymation::Error;
use fluidymation::anim::{self, LoadOptions, RegionKind};
use std::path::Path;

/// An empty folder of one test under the temp folder, removed (with what was written in it)
/// when dropped, panics included; it derefs to its path.
struct Dir(tempfile::TempDir);

impl std::ops::Deref for Dir {
    type Target = Path;

    fn deref(&self) -> &Path {
        self.0.path()
    }
}

fn dir(name: &str) -> Dir {
    Dir(tempfile::Builder::new().prefix(&format!("fm-svg-{name}-")).tempdir().unwrap())
}

fn frame(body: &str, w: u32, h: u32) -> String {
    format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" width="{w}" height="{h}" viewBox="0 0 {w} {h}">{body}</svg>"#
    )
}

#[test]
fn groups_are_layers_named_and_tracked_by_name() {
    let d = dir("layers");
    for i in 1..=10 {
        let x = i * 2;
        let mut body = format!(
            r##"<defs><linearGradient id="g"><stop offset="0" stop-color="#00f"/></linearGradient></defs>
            <g id="layer1" inkscape:label="Body"><rect x="{x}" y="10" width="10" height="10" fill="#ff0000"/></g>
            <rect x="0" y="30" width="4" height="4" fill="#000"/>"##
        );
        if i != 5 {
            body.push_str(r##"<g id="arm"><rect x="30" y="0" width="5" height="20" fill="url(#g)"/></g>"##);
        }
        body.push_str(r##"<g><circle cx="5" cy="5" r="3" fill="#0f0" stroke="#000"/></g>"##);
        // frame10 must sort after frame9 (natural order).
        std::fs::write(d.join(format!("frame{i}.svg")), frame(&body, 40, 40)).unwrap();
    }
    let a = anim::load(&d, &LoadOptions::default()).unwrap();
    assert_eq!((a.width, a.height, a.frames), (40, 40, 10));
    let names: Vec<&str> = a.regions.iter().map(|r| r.name.as_str()).collect();
    // Top-most first: the last group in the document first.
    assert_eq!(names, ["layer 1", "arm", "root", "Body"]);
    assert_eq!(a.regions[2].kind, RegionKind::SvgRoot);
    assert_eq!(a.regions[3].kind, RegionKind::SvgGroup);
    // Body: 100 px, red, moving right by 2 px a frame in natural file order.
    let body = a.find_region("Body").unwrap();
    assert!((a.regions[body].color[0] - 1.0).abs() < 0.01 && a.regions[body].color[1] < 0.01);
    for f in [0, 8, 9] {
        let fr = a.render(body, f).unwrap();
        assert_eq!(fr.fill.data().iter().filter(|c| c[3] > 0.99).count(), 100);
        let x = (f + 1) * 2;
        assert!(fr.fill.get(x, 10)[3] > 0.99 && fr.fill.get(x - 1, 10)[3] < 0.01, "frame {f}");
    }
    // The arm is missing in the 5th file: empty there, and warned about.
    let arm = a.find_region("arm").unwrap();
    assert_eq!(a.regions[arm].visible, 0..10);
    assert!(!a.regions[arm].warnings.is_empty());
    assert_eq!(a.render(arm, 4).unwrap().fill.data().iter().filter(|c| c[3] > 0.0).count(), 0);
    assert_eq!(a.render(arm, 3).unwrap().fill.data().iter().filter(|c| c[3] > 0.99).count(), 100);
    // Root shapes outside groups: the 4×4 square.
    let root = a.find_region("root").unwrap();
    assert_eq!(a.render(root, 0).unwrap().fill.data().iter().filter(|c| c[3] > 0.99).count(), 16);
    // Fills and strokes apart: the stroked circle of the unnamed group.
    let circle = a.find_region("layer 1").unwrap();
    assert!(a.regions[circle].has_strokes && !a.regions[body].has_strokes);
    let fr = a.render(circle, 0).unwrap();
    let strokes = fr.strokes.expect("stroke plane");
    assert!(fr.fill.get(5, 5)[3] > 0.99 && fr.fill.get(5, 5)[1] > 0.99, "green fill inside");
    assert!(fr.fill.get(5, 1)[3] < 0.5, "no stroke in the fill plane");
    assert!(strokes.get(5, 2)[3] > 0.4 && strokes.get(5, 5)[3] == 0.0, "ring only");
    assert!(a.render(body, 0).unwrap().strokes.is_none());
    // A glob selects the same files.
    let g = anim::load(&d.join("frame*.svg"), &LoadOptions::default().scale(0.5)).unwrap();
    assert_eq!((g.width, g.height, g.frames), (20, 20, 10));
}

#[test]
fn mismatched_sizes_and_bad_files_are_errors() {
    let d = dir("sizes");
    std::fs::write(d.join("a1.svg"), frame("<g id='x'><rect width='5' height='5'/></g>", 40, 40)).unwrap();
    std::fs::write(d.join("a2.svg"), frame("<g id='x'><rect width='5' height='5'/></g>", 50, 40)).unwrap();
    match anim::load(&d, &LoadOptions::default()).unwrap_err() {
        Error::SizeMismatch { path, expected, found } => {
            assert!(path.ends_with("a2.svg"));
            assert_eq!((expected, found), ((40, 40), (50, 40)));
        }
        e => panic!("{e}"),
    }
    let d = dir("broken");
    std::fs::write(d.join("a1.svg"), "<svg xmlns='http://www.w3.org/2000/svg' width='4' height='4'><g>").unwrap();
    let e = anim::load(&d, &LoadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("a1.svg") && e.contains("line"), "{e}");
    let d = dir("empty");
    std::fs::write(d.join("a1.svg"), frame("<defs/>", 10, 10)).unwrap();
    assert!(matches!(anim::load(&d, &LoadOptions::default()).unwrap_err(), Error::Empty { .. }));
    let e = anim::load(&dir("nothing").join("*.svg"), &LoadOptions::default()).unwrap_err();
    assert!(matches!(e, Error::Empty { .. }), "{e}");
    // No width, height or viewBox: the size would be guessed from the drawing (and differ from
    // frame to frame); said as such, naming the frame.
    let d = dir("nosize");
    let bare = "<svg xmlns='http://www.w3.org/2000/svg'><g id='x'><rect width='15' height='9'/></g></svg>";
    std::fs::write(d.join("a1.svg"), bare).unwrap();
    let e = anim::load(&d, &LoadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("a1.svg") && e.contains("no width and height and no viewBox"), "{e}");
}

#[test]
fn pattern_tiles_are_bounded_before_drawing() {
    // resvg draws a pattern's tile into a picture of its own: a tile 10^7 units wide under a
    // skew asked for 30 GB. A tile of ordinary size loads and draws; one larger than the
    // canvas and 2^24 px is refused at load, naming the file.
    let tiled = |width: &str, transform: &str| {
        format!(
            r##"<defs><pattern id="p" width="{width}" height="8" patternUnits="userSpaceOnUse"><rect width="4" height="4" fill="#f00"/></pattern></defs>
            <g id="a" transform="{transform}"><rect x="2" y="2" width="30" height="30" fill="url(#p)"/></g>"##
        )
    };
    let d = dir("pattern-ok");
    std::fs::write(d.join("f1.svg"), frame(&tiled("8", "skewX(80)"), 40, 40)).unwrap();
    let a = anim::load(&d, &LoadOptions::default()).unwrap();
    let fr = a.render(0, 0).unwrap();
    assert!(fr.fill.data().iter().any(|c| c[3] > 0.99), "the pattern is drawn");
    // At --scale 4 the same tile is still small.
    assert!(anim::load(&d, &LoadOptions::default().scale(4.0)).is_ok());

    let d = dir("pattern-huge");
    let f = d.join("f1.svg");
    std::fs::write(&f, frame(&tiled("10000000", "skewX(80)"), 40, 40)).unwrap();
    let e = anim::load(&d, &LoadOptions::default()).unwrap_err();
    assert!(matches!(e, Error::Limit { .. }), "{e}");
    let text = e.to_string();
    assert!(text.contains("pattern tile") && text.contains("f1.svg"), "{text}");
}

/// The warnings of the animation and of all its regions.
fn all_warnings(a: &anim::Animation) -> Vec<String> {
    a.warnings.iter().chain(a.regions.iter().flat_map(|r| &r.warnings)).cloned().collect()
}

/// The one warning containing every one of `parts`.
fn warning_with(warnings: &[String], parts: &[&str]) -> String {
    let found: Vec<&String> = warnings.iter().filter(|w| parts.iter().all(|p| w.contains(p))).collect();
    assert_eq!(found.len(), 1, "one warning with {parts:?} in {warnings:#?}");
    found[0].clone()
}

#[test]
fn warnings_name_the_frame_file_and_the_element() {
    let d = dir("warnings");
    for i in 1..=3 {
        // Line 1 is the <svg> element; the body starts on line 2.
        let mut body = String::from(
            "\n<defs><filter id=\"blur\"><feGaussianBlur stdDeviation=\"2\"/></filter></defs>
<g id=\"Body\"><rect id=\"r\" width=\"9\" height=\"9\" filter=\"url(#blur)\"/>
<text id=\"title\" y=\"20\">Hi</text></g>\n",
        );
        if i != 2 {
            body.push_str("<g id=\"arm\"><rect x=\"20\" width=\"5\" height=\"5\"/></g>\n");
        } else {
            body.push_str("<g id=\"fx\"><g><circle r=\"3\" style=\"fill:red;filter:url(#blur)\"/></g></g>\n");
        }
        if i == 1 {
            body.push_str("<foreignObject id=\"html\" width=\"5\" height=\"5\"/>\n<frob/>\n");
        }
        if i == 3 {
            // A nested <svg> draws like a shape: it belongs to the root layer, not ignored.
            body.push_str(
                "<svg id=\"inner\" x=\"30\" width=\"4\" height=\"4\"><rect width=\"4\" height=\"4\"/></svg>\n",
            );
        }
        std::fs::write(d.join(format!("f{i}.svg")), frame(&body, 40, 40)).unwrap();
    }
    let a = anim::load(&d, &LoadOptions::default()).unwrap();
    let w = all_warnings(&a);
    let f1 = d.join("f1.svg").display().to_string();
    let f2 = d.join("f2.svg").display().to_string();
    // Each names the layer, the element by id (else its tag), the first frame file and the
    // line there, what is wrong and what is done; repeated in later frames, counted.
    let body = &a.regions[a.find_region("Body").unwrap()].warnings;
    assert_eq!(
        warning_with(body, &["<text id=\"title\">"]),
        format!(
            "layer 'Body': <text id=\"title\"> in '{f1}' line 4: SVG text is not drawn (no fonts are loaded); \
             convert text to paths (also in 2 more frames)"
        )
    );
    assert_eq!(
        warning_with(body, &["<rect id=\"r\">"]),
        format!(
            "layer 'Body': <rect id=\"r\"> in '{f1}' line 3: its filter 'url(#blur)' is not drawn \
             (SVG filters are ignored); drawn without (also in 2 more frames)"
        )
    );
    // No id: the tag and the line; an inline style's filter too.
    let fx = warning_with(&w, &["<circle>"]);
    assert_eq!(
        fx,
        format!(
            "layer 'fx': <circle> in '{f2}' line 5: its filter 'url(#blur)' is not drawn (SVG filters are ignored); \
             drawn without"
        )
    );
    // Outside any layer: in the animation's warnings.
    let fo = warning_with(&a.warnings, &["<foreignObject id=\"html\">"]);
    assert!(
        fo.starts_with(&format!("<foreignObject id=\"html\"> in '{f1}' line 6: ")) && fo.contains("not drawn"),
        "{fo}"
    );
    let frob = warning_with(&a.warnings, &["<frob>"]);
    assert_eq!(frob, format!("<frob> in '{f1}' line 7: is not a group or a shape, so it is not a layer; ignored"));
    assert!(!w.iter().any(|w| w.contains("<svg")), "{w:#?}");
    let root = a.find_region("root").unwrap();
    assert_eq!(a.render(root, 2).unwrap().fill.data().iter().filter(|c| c[3] > 0.99).count(), 16);
    assert_eq!(a.render(a.find_region("Body").unwrap(), 2).unwrap().fill.get(31, 1)[3], 0.0);
    // A layer missing in some frames names them.
    let arm = warning_with(&w, &["layer 'arm'"]);
    assert_eq!(arm, format!("layer 'arm' is missing from 1 frame of its range ('{f2}'); it is empty there"));
}

#[test]
fn broken_images_are_warned_about_naming_the_frame_and_the_image() {
    let d = dir("images");
    let mut png = Vec::new();
    image::RgbaImage::from_pixel(4, 4, image::Rgba([255, 0, 0, 255]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    std::fs::write(d.join("ok.png"), &png).unwrap();
    std::fs::write(d.join("cut.png"), &png[..png.len() / 2]).unwrap();
    std::fs::write(d.join("notes.png"), "not an image").unwrap();
    let body = "
<g id=\"pics\"><image id=\"ok\" href=\"ok.png\" width=\"4\" height=\"4\"/>
<image id=\"gone\" href=\"missing.png\" width=\"4\" height=\"4\"/>
<image id=\"cut\" href=\"cut.png\" width=\"4\" height=\"4\"/>
<image xmlns:xlink=\"http://www.w3.org/1999/xlink\" xlink:href=\"notes.png\" width=\"4\" height=\"4\"/>
<image id=\"nohref\" width=\"4\" height=\"4\"/>
<image id=\"data\" href=\"data:image/png;base64,iVBORw0KGgo=\" width=\"4\" height=\"4\"/>
<image id=\"web\" href=\"https://example.com/a.png\" width=\"4\" height=\"4\"/></g>";
    for i in 1..=2 {
        std::fs::write(d.join(format!("f{i}.svg")), frame(body, 10, 10)).unwrap();
    }
    let a = anim::load(&d, &LoadOptions::default()).unwrap();
    let pics = a.find_region("pics").unwrap();
    let w = &a.regions[pics].warnings;
    let f1 = d.join("f1.svg").display().to_string();
    let missing = d.join("missing.png").display().to_string();
    assert_eq!(
        warning_with(w, &["<image id=\"gone\">"]),
        format!(
            "layer 'pics': <image id=\"gone\"> in '{f1}' line 3: broken image: 'missing.png' was not found \
             (looked for '{missing}'); not drawn (also in 1 more frame)"
        )
    );
    let cut = warning_with(w, &["<image id=\"cut\">", &f1, "line 4"]);
    assert!(
        cut.contains("broken image: 'cut.png' is not a readable PNG image (")
            && cut.ends_with("; not drawn (also in 1 more frame)"),
        "{cut}"
    );
    // No id: the tag and the line, and the href says which.
    let notes = warning_with(w, &["<image>", &f1, "line 5"]);
    assert!(notes.contains("'notes.png' is not a PNG, JPEG, GIF, WebP or SVG image; not drawn"), "{notes}");
    warning_with(w, &["<image id=\"nohref\">", "line 6", "broken image: has no href; not drawn"]);
    warning_with(w, &["<image id=\"data\">", "line 7", "broken image: its data: URL is not a readable PNG image"]);
    warning_with(w, &["<image id=\"web\">", "line 8", "'https://example.com/a.png' is a URL"]);
    assert!(!w.iter().any(|w| w.contains("\"ok\"")), "{w:#?}");
    assert_eq!(w.len(), 6, "{w:#?}");
    // The good image is drawn.
    assert!(a.render(pics, 0).unwrap().fill.get(1, 1)[3] > 0.99);
}

#[test]
fn groups_sharing_a_name_stay_distinct_layers() {
    let d = dir("dup-ids");
    for i in 1..=3 {
        let mut body = String::from("\n<g id=\"arm\"><rect width=\"5\" height=\"5\"/></g>\n");
        if i != 3 {
            body.push_str("<g id=\"arm\"><rect x=\"20\" width=\"5\" height=\"5\"/></g>\n");
        }
        std::fs::write(d.join(format!("f{i}.svg")), frame(&body, 40, 40)).unwrap();
    }
    let a = anim::load(&d, &LoadOptions::default()).unwrap();
    let names: Vec<&str> = a.regions.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(names, ["arm (2)", "arm"]);
    let (first, second) = (a.find_region("arm").unwrap(), a.find_region("arm (2)").unwrap());
    let fr = a.render(first, 0).unwrap();
    assert!(fr.fill.get(1, 1)[3] > 0.99 && fr.fill.get(21, 1)[3] == 0.0, "the first group alone");
    let fr = a.render(second, 1).unwrap();
    assert!(fr.fill.get(1, 1)[3] == 0.0 && fr.fill.get(21, 1)[3] > 0.99, "the second group alone");
    assert_eq!((a.regions[first].visible.clone(), a.regions[second].visible.clone()), (0..3, 0..2));
    let f1 = d.join("f1.svg").display().to_string();
    assert_eq!(
        a.regions[second].warnings,
        [format!(
            "layer 'arm (2)': <g id=\"arm\"> in '{f1}' line 3: an earlier top-level group in this frame is also \
             named 'arm'; kept apart as layer 'arm (2)', not merged (groups sharing a name are told apart by their \
             order in each frame) (also in 1 more frame)"
        )]
    );
    assert!(a.regions[first].warnings.is_empty(), "{:?}", a.regions[first].warnings);

    // A group itself named like a renamed one: refused, naming the frame, in one frame or
    // across frames.
    let d = dir("dup-clash");
    let body = "<g id=\"arm\"/><g id=\"arm\"/><g inkscape:label=\"arm (2)\"><rect width=\"5\" height=\"5\"/></g>";
    std::fs::write(d.join("f1.svg"), frame(body, 40, 40)).unwrap();
    let e = anim::load(&d, &LoadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("f1.svg") && e.contains("'arm (2)'") && e.contains("distinct ids or labels"), "{e}");
    let d = dir("dup-clash-frames");
    std::fs::write(
        d.join("f1.svg"),
        frame("<g inkscape:label=\"arm (2)\"><rect width=\"5\" height=\"5\"/></g>", 40, 40),
    )
    .unwrap();
    std::fs::write(d.join("f2.svg"), frame("<g id=\"arm\"/><g id=\"arm\"/>", 40, 40)).unwrap();
    let e = anim::load(&d, &LoadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("f1.svg") && e.contains("f2.svg") && e.contains("'arm (2)'"), "{e}");
}

/// `Animation::fill_motion` of an SVG sequence: the same elements drawn again in every frame
/// give their motion, whether a frame moves them by a transform or writes their coordinates
/// anew. A square turns 9° a frame about its center while the group slides right 1 px a frame:
/// written once with `transform` attributes and once with its corners computed into a path —
/// both give the analytic step (the turn included, which a mask cannot show); a frame that
/// draws one more element gives none.
#[test]
fn svg_fill_motion_is_the_elements_step() {
    let turn = |i: u32| 9.0 * i as f64;
    let corners = |i: u32| -> String {
        let (s, c) = turn(i).to_radians().sin_cos();
        let (cx, cy) = (20.0 + i as f64, 20.0);
        let pts: Vec<String> = [(-5.0, -5.0), (5.0, -5.0), (5.0, 5.0), (-5.0, 5.0)]
            .iter()
            .map(|&(x, y)| format!("{:.6},{:.6}", cx + c * x - s * y, cy + s * x + c * y))
            .collect();
        format!("M{} L{} L{} L{} Z", pts[0], pts[1], pts[2], pts[3])
    };
    // The frames are read again when drawn: their folders live as long as the animations.
    let (transformed, recomputed) = (dir("motion-transform"), dir("motion-coordinates"));
    let written = |d: &Path, body: &dyn Fn(u32) -> String| {
        for i in 0..6 {
            std::fs::write(d.join(format!("f{i}.svg")), frame(&body(i), 60, 40)).unwrap();
        }
        anim::load(d, &LoadOptions::default()).unwrap()
    };
    let by_transform = written(&transformed, &|i| {
        let extra = if i == 5 { r##"<rect x="50" y="30" width="3" height="3" fill="#0f0"/>"## } else { "" };
        format!(
            r##"<g id="sq" transform="translate({i} 0)"><rect x="15" y="15" width="10" height="10" fill="#f00" transform="rotate({} 20 20)"/>{extra}</g>"##,
            turn(i)
        )
    });
    let by_coordinates =
        written(&recomputed, &|i| format!(r##"<g id="sq"><path d="{}" fill="#f00"/></g>"##, corners(i)));
    for a in [&by_transform, &by_coordinates] {
        let frame = 2;
        let v = a.fill_motion(0, frame).unwrap().expect("the same elements in both frames");
        let (th0, th1) = (turn(frame as u32).to_radians() as f32, turn(frame as u32 + 1).to_radians() as f32);
        let c0 = glam::Vec2::new(20.0 + frame as f32, 20.0);
        let mut covered = 0;
        for (k, m) in v.data().iter().enumerate() {
            let Some(m) = m else { continue };
            covered += 1;
            let p = glam::Vec2::new((k % 60) as f32 + 0.5, (k / 60) as f32 + 0.5);
            let local = glam::Vec2::from_angle(-th0).rotate(p - c0);
            let next = glam::Vec2::from_angle(th1).rotate(local) + c0 + glam::Vec2::new(1.0, 0.0);
            assert!((*m - (next - p)).length() < 1e-3, "({p}): {m} against {}", next - p);
        }
        assert!((90..=110).contains(&covered), "{covered} pixels with a motion");
    }
    assert!(by_transform.fill_motion(0, 4).unwrap().is_none(), "frame 5 draws one more element");
    assert!(by_transform.fill_motion(0, 5).unwrap().is_none(), "the last frame has no next");
}

#[test]
fn a_single_file_is_a_still_and_classes_select_frames() {
    let d = dir("still");
    for k in 1..=5 {
        let body = format!("<g id='box'><rect x='{k}' y='2' width='6' height='6' fill='#00f'/></g>");
        std::fs::write(d.join(format!("f0{k}.svg")), frame(&body, 20, 12)).unwrap();
    }
    // One file: one frame, the file's own layers, drawn like the same frame of the sequence.
    let still = anim::load(&d.join("f03.svg"), &LoadOptions::default()).unwrap();
    assert_eq!((still.width, still.height, still.frames, still.fps), (20, 12, 1, 24.0));
    assert_eq!(still.regions.len(), 1);
    assert_eq!((still.regions[0].name.as_str(), still.regions[0].visible.clone()), ("box", 0..1));
    let seq = anim::load(&d, &LoadOptions::default()).unwrap();
    assert_eq!(still.render(0, 0).unwrap().fill.data(), seq.render(0, 2).unwrap().fill.data());
    assert_eq!(anim::source(&d.join("f03.svg")).unwrap(), anim::Source::Svg(vec![d.join("f03.svg")]));
    // Classes, as a shell has them.
    let files = |glob: &str| match anim::source(&d.join(glob)).unwrap() {
        anim::Source::Svg(files) => {
            files.iter().map(|f| f.file_name().unwrap().to_string_lossy().into_owned()).collect::<Vec<_>>()
        }
        s => panic!("{s:?}"),
    };
    assert_eq!(files("f0[1-3].svg"), ["f01.svg", "f02.svg", "f03.svg"]);
    assert_eq!(files("f0[!1-3].svg"), ["f04.svg", "f05.svg"]);
    assert_eq!(files("f0[52].svg"), ["f02.svg", "f05.svg"]);
    let a = anim::load(&d.join("f0[2-4].svg"), &LoadOptions::default()).unwrap();
    assert_eq!(a.frames, 3);
    assert_eq!(a.render(0, 0).unwrap().fill.data(), seq.render(0, 1).unwrap().fill.data());
    // A glob's matches of other kinds are left out, as a folder's are.
    std::fs::write(d.join("f06.txt"), "notes").unwrap();
    assert_eq!(files("f0*").len(), 5);
}

#[test]
fn folders_and_globs_of_other_files_say_what_they_hold() {
    let d = dir("kinds");
    std::fs::write(d.join("a.json"), "{}").unwrap();
    std::fs::write(d.join("b.json"), "{}").unwrap();
    std::fs::write(d.join("c.txt"), "").unwrap();
    let e = anim::load(&d, &LoadOptions::default()).unwrap_err();
    assert!(matches!(e, Error::Empty { .. }), "{e}");
    let e = e.to_string();
    assert!(e.contains("holds 2 .json files and 1 .txt file but no SVG frames (.svg) or PNG masks (.png)"), "{e}");
    assert!(e.contains("(a.json, b.json) are given as files"), "{e}");
    // A glob of Lottie files is each file, for the caller to load one by one.
    let both = anim::source(&d.join("*.json")).unwrap();
    assert_eq!(both, anim::Source::LottieFiles(vec![d.join("a.json"), d.join("b.json")]));
    assert_eq!(anim::source(&d.join("[a].json")).unwrap(), anim::Source::Lottie(d.join("a.json")));
    let e = anim::load(&d.join("*.json"), &LoadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("matches 2 Lottie .json files (a.json, b.json)"), "{e}");
    let e = anim::load(&d.join("*.txt"), &LoadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("matches 1 .txt file but no SVG frames (.svg), PNG masks (.png) or Lottie files"), "{e}");
}
