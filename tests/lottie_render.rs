//! Properties of the Lottie reader that reference images cannot pin down: exact pixel counts
//! on simple shapes, mask and matte modes, evaluated keyframes, region rules, errors.

use fluidymation::Error;
use fluidymation::anim::lottie;
use fluidymation::anim::{self, LoadOptions, RegionKind};
use serde_json::{Value, json};
use std::io::Write;
use std::path::Path;

fn st(v: Value) -> Value {
    json!({"a": 0, "k": v})
}

fn rect_layer(name: &str, ind: i64, x: f64, y: f64, w: f64, h: f64, color: [f64; 4]) -> Value {
    json!({"ty": 4, "nm": name, "ind": ind, "ip": 0, "op": 10, "st": 0, "ks": {},
           "shapes": [{"ty": "gr", "it": [
               {"ty": "rc", "p": st(json!([x + w / 2.0, y + h / 2.0])), "s": st(json!([w, h])), "r": st(json!(0))},
               {"ty": "fl", "c": st(json!(color)), "o": st(json!(100)), "r": 1},
               {"ty": "tr", "p": st(json!([0, 0])), "a": st(json!([0, 0])), "s": st(json!([100, 100])),
                "r": st(json!(0)), "o": st(json!(100))}]}]})
}

fn doc(layers: Vec<Value>) -> Value {
    json!({"v": "5.7.1", "fr": 10, "ip": 0, "op": 10, "w": 40, "h": 40, "layers": layers})
}

fn model(d: &Value) -> lottie::Model {
    lottie::parse(Path::new("test.json"), &d.to_string()).unwrap()
}

/// Alpha values of one root layer at `frame`, all passes.
fn alpha(d: &Value, layer: usize, frame: f32) -> Vec<u8> {
    let m = model(d);
    let pm = lottie::render(&m, lottie::Target { layer, child: None }, frame, 40, 40, 1.0, lottie::Pass::All);
    pm.pixels().iter().map(|p| p.alpha()).collect()
}

fn count(a: &[u8], v: u8) -> usize {
    a.iter().filter(|&&x| x == v).count()
}

#[test]
fn pixel_aligned_rect_covers_exactly_its_pixels() {
    let d = doc(vec![rect_layer("r", 1, 10.0, 5.0, 10.0, 20.0, [1.0, 0.0, 0.0, 1.0])]);
    let a = alpha(&d, 0, 0.0);
    assert_eq!(count(&a, 255), 200);
    assert_eq!(count(&a, 0), 1600 - 200);
    assert_eq!(a[5 * 40 + 10], 255);
    assert_eq!(a[4 * 40 + 10], 0);
}

fn with_masks(masks: Value) -> Value {
    let mut l = rect_layer("m", 1, 0.0, 0.0, 40.0, 40.0, [0.0, 0.0, 1.0, 1.0]);
    l["masksProperties"] = masks;
    l["hasMask"] = json!(true);
    doc(vec![l])
}

fn square(x: f64, y: f64, s: f64) -> Value {
    json!({"c": true, "v": [[x, y], [x + s, y], [x + s, y + s], [x, y + s]], "i": [[0, 0], [0, 0], [0, 0], [0, 0]], "o": [[0, 0], [0, 0], [0, 0], [0, 0]]})
}

fn mask(mode: &str, inv: bool, o: f64, path: Value) -> Value {
    json!({"mode": mode, "inv": inv, "o": st(json!(o)), "x": st(json!(0)), "pt": st(path)})
}

#[test]
fn mask_modes_have_exact_areas() {
    // A = [0,20)², B = [10,30)²; overlap 100 px.
    let (a, b) = (square(0.0, 0.0, 20.0), square(10.0, 10.0, 20.0));
    let cases = [
        (vec![mask("a", false, 100.0, a.clone())], 400),
        (vec![mask("a", false, 100.0, a.clone()), mask("a", false, 100.0, b.clone())], 700),
        (vec![mask("a", false, 100.0, a.clone()), mask("s", false, 100.0, b.clone())], 300),
        (vec![mask("a", false, 100.0, a.clone()), mask("i", false, 100.0, b.clone())], 100),
        (vec![mask("a", false, 100.0, a.clone()), mask("f", false, 100.0, b.clone())], 600),
        (vec![mask("a", false, 100.0, a.clone()), mask("l", false, 100.0, b.clone())], 700),
        (vec![mask("a", false, 100.0, a.clone()), mask("d", false, 100.0, b.clone())], 100),
        (vec![mask("a", true, 100.0, a.clone())], 1600 - 400),
        (vec![mask("s", false, 100.0, a.clone())], 1600 - 400),
        (vec![mask("a", false, 100.0, a.clone()), mask("n", false, 100.0, b.clone())], 400),
    ];
    for (i, (masks, expected)) in cases.into_iter().enumerate() {
        let al = alpha(&with_masks(Value::Array(masks)), 0, 0.0);
        assert_eq!(count(&al, 255), expected, "case {i}");
        assert_eq!(count(&al, 0), 1600 - expected, "case {i}");
    }
    // Mask opacity scales coverage.
    let al = alpha(&with_masks(json!([mask("a", false, 50.0, a.clone())])), 0, 0.0);
    assert_eq!(al.iter().filter(|&&x| (126..=129).contains(&x)).count(), 400);
    // Expansion grows the mask by about x pixels on every side.
    let mut m = mask("a", false, 100.0, square(10.0, 10.0, 10.0));
    m["x"] = st(json!(2));
    let al = alpha(&with_masks(json!([m])), 0, 0.0);
    let covered: f64 = al.iter().map(|&v| v as f64 / 255.0).sum();
    assert!((covered - 14.0 * 14.0).abs() < 6.0, "{covered}");
}

#[test]
fn track_mattes_alpha_luma_and_tp() {
    let src = |color: [f64; 4]| {
        let mut s = rect_layer("matte", 1, 0.0, 0.0, 20.0, 40.0, color);
        s["td"] = json!(1);
        s
    };
    let target = |tt: i64| {
        let mut t = rect_layer("target", 2, 0.0, 0.0, 40.0, 40.0, [1.0, 0.0, 0.0, 1.0]);
        t["tt"] = json!(tt);
        t
    };
    for (tt, color, expected) in [
        (1, [1.0, 1.0, 1.0, 1.0], 800),
        (2, [1.0, 1.0, 1.0, 1.0], 800),
        (3, [1.0, 1.0, 1.0, 1.0], 800),
        (4, [1.0, 1.0, 1.0, 1.0], 800),
        (3, [0.0, 0.0, 0.0, 1.0], 0),
        (4, [0.0, 0.0, 0.0, 1.0], 1600),
    ] {
        let d = doc(vec![src(color), target(tt)]);
        let a = alpha(&d, 1, 0.0);
        assert_eq!(count(&a, 255), expected, "tt {tt} color {color:?}");
    }
    // `tp` names the matte by `ind`, even when it is not the layer right above.
    let mut t = rect_layer("target", 3, 0.0, 0.0, 40.0, 40.0, [1.0, 0.0, 0.0, 1.0]);
    t["tt"] = json!(1);
    t["tp"] = json!(1);
    let d = doc(vec![src([1.0; 4]), rect_layer("other", 2, 30.0, 30.0, 5.0, 5.0, [0.0, 1.0, 0.0, 1.0]), t]);
    assert_eq!(count(&alpha(&d, 2, 0.0), 255), 800);
    // The matte source is not a region; the other two are.
    let a = anim_of(&d, &LoadOptions::default());
    let names: Vec<&str> = a.regions.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(names, ["other", "target"]);
}

/// `text` in a `.json` file of its own under the temp folder, removed when dropped (panics
/// included). The reader reads the file once, when loading.
fn write_temp(text: &str) -> tempfile::NamedTempFile {
    let mut f = tempfile::Builder::new().prefix("fm-lottie-").suffix(".json").tempfile().unwrap();
    f.write_all(text.as_bytes()).unwrap();
    f
}

fn anim_of(d: &Value, opts: &LoadOptions) -> anim::Animation {
    let f = write_temp(&d.to_string());
    anim::load(f.path(), opts).unwrap()
}

#[test]
fn keyframes_evaluate_through_the_model() {
    // Position: linear 0 → 30 over frames 0..10 (old `e` style), then hold.
    let mut l = rect_layer("moving", 1, 0.0, 0.0, 10.0, 10.0, [1.0, 1.0, 1.0, 1.0]);
    l["ks"] = json!({"p": {"k": [
        {"t": 0, "s": [0, 0], "e": [30, 0], "i": {"x": 1, "y": 1}, "o": {"x": 0, "y": 0}},
        {"t": 6, "s": [30, 0], "h": 1}, {"t": 8, "s": [0, 20]}]}});
    let d = doc(vec![l]);
    // (The evaluated position itself is checked by the model's unit tests.) The rendering
    // moves with it: at frame 3 the square spans x 15..25, held at 30 during 6..8, then 0.
    let a = alpha(&d, 0, 3.0);
    assert_eq!(count(&a, 255), 100);
    assert_eq!(a[5 * 40 + 15], 255);
    assert_eq!(a[5 * 40 + 14], 0);
    let a = alpha(&d, 0, 7.0);
    assert_eq!(count(&a, 255), 100);
    assert_eq!(a[30], 255);
    assert_eq!(a[29], 0);
    let a = alpha(&d, 0, 9.0);
    assert_eq!(count(&a, 255), 100);
    assert_eq!(a[20 * 40], 255);
    assert_eq!(a[19 * 40], 0);
}

#[test]
fn fills_and_strokes_are_separate() {
    let mut l = rect_layer("outlined", 1, 10.0, 10.0, 20.0, 20.0, [0.0, 0.5, 0.0, 1.0]);
    l["shapes"][0]["it"].as_array_mut().unwrap().insert(
        1,
        json!({"ty": "st", "c": st(json!([1, 0, 0, 1])), "o": st(json!(100)), "w": st(json!(4)), "lc": 1, "lj": 1}),
    );
    let a = anim_of(&doc(vec![l]), &LoadOptions::default());
    assert!(a.regions[0].has_strokes);
    let f = a.render(0, 0).unwrap();
    let fill_px = f.fill.data().iter().filter(|c| c[3] > 0.99).count();
    assert_eq!(fill_px, 400);
    assert!(f.fill.data().iter().all(|c| c[3] == 0.0 || (c[1] - 0.5).abs() < 0.01), "fill keeps its color");
    let strokes = f.strokes.expect("strokes plane");
    let stroke_px = strokes.data().iter().filter(|c| c[3] > 0.99).count();
    // A 4-px stroke centred on the 20×20 outline: 24² − 16² = 320 pixels.
    assert_eq!(stroke_px, 320);
    assert!((a.regions[0].color[1] - 0.5).abs() < 0.02, "dominant color is the fill");
}

#[test]
fn regions_background_and_names() {
    let bg = json!({"ty": 1, "nm": "paper", "ind": 9, "ip": 0, "op": 10, "st": 0, "ks": {},
                    "sc": "#ff8000", "sw": 40, "sh": 40});
    let null = json!({"ty": 3, "nm": "ctrl", "ind": 5, "ip": 0, "op": 10, "st": 0, "ks": {"p": st(json!([5, 0]))}});
    let mut child = rect_layer("dup", 2, 0.0, 0.0, 5.0, 5.0, [0.0, 0.0, 0.0, 1.0]);
    child["parent"] = json!(5);
    child["ip"] = json!(2);
    child["op"] = json!(7);
    let mut hidden = rect_layer("hidden", 3, 0.0, 0.0, 5.0, 5.0, [0.0, 0.0, 0.0, 1.0]);
    hidden["hd"] = json!(true);
    let text = json!({"ty": 5, "nm": "title", "ind": 4, "ip": 0, "op": 10, "st": 0, "ks": {}});
    let d = doc(vec![child, rect_layer("dup", 1, 0.0, 0.0, 5.0, 5.0, [0.0; 4]), hidden, text, null, bg]);
    let a = anim_of(&d, &LoadOptions::default());
    let names: Vec<&str> = a.regions.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(names, ["dup", "dup (2)"]);
    assert_eq!(a.regions[0].index, 1);
    assert_eq!(a.regions[0].visible, 2..7);
    let bg = a.background.as_ref().expect("background");
    assert_eq!(bg.name, "paper");
    assert!((bg.color[0] - 1.0).abs() < 1e-6 && (bg.color[1] - 128.0 / 255.0).abs() < 1e-6);
    assert!(a.warnings.iter().any(|w| w.contains("title") && w.contains("text")), "{:?}", a.warnings);
    // The parent null moves the child by 5 px.
    let f = a.render(0, 3).unwrap();
    assert!(f.fill.get(6, 2)[3] > 0.99 && f.fill.get(4, 2)[3] == 0.0);
}

#[test]
fn split_precomps_and_time_remap() {
    let inner = |name: &str, ind: i64, x: f64| rect_layer(name, ind, x, 0.0, 10.0, 10.0, [0.0, 0.0, 1.0, 1.0]);
    let d = json!({"v": "5.7.1", "fr": 10, "ip": 0, "op": 10, "w": 40, "h": 40,
        "assets": [{"id": "c", "layers": [inner("a", 1, 0.0), inner("b", 2, 20.0)]}],
        "layers": [
            {"ty": 0, "nm": "pre", "ind": 1, "refId": "c", "w": 40, "h": 40, "ip": 0, "op": 10, "st": 0, "ks": {}},
            {"ty": 0, "nm": "again", "ind": 2, "refId": "c", "w": 15, "h": 40, "ip": 0, "op": 10, "st": 0, "ks": {},
             "tm": {"a": 1, "k": [{"t": 0, "s": [0.5], "i": {"x": 1, "y": 1}, "o": {"x": 0, "y": 0}}, {"t": 10, "s": [0.5]}]}}]});
    let a = anim_of(&d, &LoadOptions::default());
    assert_eq!(a.regions.len(), 2);
    assert_eq!(a.regions[0].kind, RegionKind::Precomp);
    // The second use is clipped to its 15-px width: only "a" shows (100 px).
    let f = a.render(1, 0).unwrap();
    assert_eq!(f.fill.data().iter().filter(|c| c[3] > 0.99).count(), 100);
    let s = anim_of(&d, &LoadOptions::default().split_precomps(true));
    let names: Vec<&str> = s.regions.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(names, ["pre/a", "pre/b", "again/a", "again/b"]);
    assert!(s.regions.iter().all(|r| r.kind == RegionKind::PrecompChild));
    let f = s.render(1, 0).unwrap();
    assert_eq!(f.fill.data().iter().filter(|c| c[3] > 0.99).count(), 100);
    assert!(f.fill.get(25, 5)[3] > 0.99);
}

#[test]
fn scale_option_scales_the_canvas() {
    let d = doc(vec![rect_layer("r", 1, 10.0, 10.0, 10.0, 10.0, [1.0; 4])]);
    let a = anim_of(&d, &LoadOptions::default().scale(0.5));
    assert_eq!((a.width, a.height), (20, 20));
    let f = a.render(0, 0).unwrap();
    assert_eq!(f.fill.data().iter().filter(|c| c[3] > 0.99).count(), 25);
}

fn load_err(text: &str) -> Error {
    let f = write_temp(text);
    anim::load(f.path(), &LoadOptions::default()).unwrap_err()
}

#[test]
fn errors_name_the_problem() {
    match load_err("{\n  \"w\": 10,\n  \"h\": 10 oops\n}") {
        e @ Error::Json { line, column, .. } => {
            assert_eq!((line, column), (3, 11));
            // The parser's own error is kept as the source, for callers that walk the chain.
            let source = std::error::Error::source(&e).expect("a JSON error keeps serde_json's error");
            assert!(source.downcast_ref::<serde_json::Error>().is_some_and(|j| j.line() == 3), "{source:?}");
        }
        e => panic!("{e}"),
    }
    let msg = |t: &str| load_err(t).to_string();
    assert!(msg(r#"{"h": 10, "fr": 30, "op": 10, "layers": []}"#).contains("missing 'w'"));
    assert!(msg(r#"{"w": 10, "h": 10, "op": 10, "layers": []}"#).contains("missing 'fr'"));
    assert!(msg(r#"{"w": 10, "h": 10, "fr": 30, "layers": []}"#).contains("missing 'op'"));
    assert!(msg(r#"{"w": 10, "h": 10, "fr": 30, "op": 10}"#).contains("missing 'layers'"));
    assert!(msg(r#"{"w": 20000, "h": 10, "fr": 30, "op": 10, "layers": []}"#).contains("at most 16384"));
    assert!(msg(r#"{"w": 10, "h": 10, "fr": 30, "ip": 0, "op": 200000, "layers": []}"#).contains("at most 100000"));
    assert!(msg(r#"{"w": 10, "h": 10, "fr": 30, "ip": 5, "op": 5, "layers": []}"#).contains("no frames"));
    assert!(msg(r#"{"w": 10, "h": 10, "fr": -1, "op": 5, "layers": []}"#).contains("at least 0.01"));
    // Valid JSON, but not an object.
    let arr = msg("[1, 2, 3]");
    assert!(arr.contains("not a Lottie file") && arr.contains("JSON object"), "{arr}");
    // Positive but no usable frame rate: refused up front, naming the file's value.
    let tiny = msg(r#"{"w": 10, "h": 10, "fr": 1e-300, "op": 5, "layers": []}"#);
    assert!(tiny.contains("1e-300") && tiny.contains("at least 0.01"), "{tiny}");
    assert!(msg(r#"{"w": 10, "h": 10, "fr": 30, "op": 5, "layers": []}"#).contains("no layers"));
    assert!(matches!(load_err("   "), Error::Empty { .. }));
    assert!(msg(r#"{"w": 1e999}"#).contains("line 1"));
    assert!(matches!(load_err(r#"{"w": NaN, "h": 10}"#), Error::Json { line: 1, column: 7, .. }));
    assert!(msg(r#"{"w": 1e300, "h": 10, "fr": 30, "op": 5, "layers": []}"#).contains("canvas width"));
    assert!(msg(r#"{"w": 10, "h": 10, "fr": 1e300, "op": 5, "layers": []}"#).contains("frame rate"));
    assert!(msg(r#"{"w": 10, "h": -3, "fr": 30, "op": 5, "layers": []}"#).contains("at least 1 pixel"));
    let missing = anim::load(Path::new("/nonexistent/x.json"), &LoadOptions::default()).unwrap_err();
    assert!(missing.to_string().contains("/nonexistent/x.json"));
}

#[test]
fn a_json_error_gives_its_position_once() {
    let mut text = doc(vec![rect_layer("r", 1, 0.0, 0.0, 10.0, 10.0, [1.0; 4])]).to_string();
    text.truncate(text.len() / 2);
    let e = load_err(&text);
    let Error::Json { line, column, .. } = &e else { panic!("{e}") };
    let msg = e.to_string();
    assert!(msg.contains("is not valid JSON: EOF while parsing"), "{msg}");
    assert!(msg.ends_with(&format!(" at line {line} column {column}")), "{msg}");
    assert_eq!(msg.matches("line").count(), 1, "{msg}");
    // The source is serde_json's error, whose text the message ends with (the CLI's chain of
    // causes leaves out a cause the message already said).
    let source = std::error::Error::source(&e).unwrap().to_string();
    assert!(msg.ends_with(&source), "{msg} / {source}");
}

/// A layer that draws nothing for the given reason: text, a null, a precomp of a missing asset.
fn bare_layer(ty: Value, name: &str, ind: i64) -> Value {
    json!({"ty": ty, "nm": name, "ind": ind, "ip": 0, "op": 10, "st": 0, "ks": {}})
}

fn load_message(d: &Value, opts: &LoadOptions) -> String {
    let f = write_temp(&d.to_string());
    let e = anim::load(f.path(), opts).unwrap_err();
    assert!(matches!(e, Error::Empty { .. }), "{e}");
    e.to_string()
}

#[test]
fn a_file_with_nothing_to_stylize_says_why_layer_by_layer() {
    let nothing = "no layer draws anything that could be stylized: ";
    let opts = LoadOptions::default();
    // The only layer is text, or a precomp whose asset does not exist: the error says so, as
    // the warnings do when another layer draws.
    let text = doc(vec![bare_layer(json!(5), "title", 1)]);
    let msg = load_message(&text, &opts);
    assert!(msg.ends_with(&format!("{nothing}layer 1 'title' (text): text layers are not supported")), "{msg}");
    let mut missing = bare_layer(json!(0), "comp", 1);
    missing["refId"] = json!("nope");
    let msg = load_message(&doc(vec![missing.clone()]), &opts);
    assert!(msg.ends_with(&format!("{nothing}layer 1 'comp' (precomp): precomp asset 'nope' does not exist")), "{msg}");
    let rect = rect_layer("ok", 2, 0.0, 0.0, 10.0, 10.0, [1.0; 4]);
    let a = anim_of(&doc(vec![missing, rect.clone()]), &opts);
    assert!(
        a.warnings.contains(&"layer 'comp': precomp asset 'nope' does not exist; nothing drawn".into()),
        "{:?}",
        a.warnings
    );
    let a = anim_of(&doc(vec![bare_layer(json!(5), "title", 1), rect]), &opts);
    assert!(
        a.warnings.contains(&"layer 'title': text layers are not supported; nothing drawn".into()),
        "{:?}",
        a.warnings
    );

    // Every kind of layer that is not a region, top-most first, each with its reason.
    let mut matte = rect_layer("matte", 3, 0.0, 0.0, 10.0, 10.0, [1.0; 4]);
    matte["td"] = json!(1);
    let mut matted = bare_layer(json!(5), "label", 4);
    matted["tt"] = json!(1);
    let mut hidden = rect_layer("hidden", 5, 0.0, 0.0, 10.0, 10.0, [1.0; 4]);
    hidden["hd"] = json!(true);
    let mut ghost = rect_layer("ghost", 6, 0.0, 0.0, 10.0, 10.0, [1.0; 4]);
    ghost["ks"] = json!({"o": st(json!(0))});
    let mut paper = bare_layer(json!(1), "paper", 7);
    paper["sc"] = json!("#ffffff");
    (paper["sw"], paper["sh"]) = (json!(40), json!(40));
    let all = doc(vec![
        bare_layer(json!(13), "camera", 1),
        bare_layer(json!(3), "ctrl", 2),
        matte,
        matted,
        hidden,
        ghost,
        paper,
    ]);
    let msg = load_message(&all, &opts);
    let expected = [
        "layer 1 'camera' (type 13): layer type 13 is not supported",
        "layer 2 'ctrl' (null): a null draws nothing (it only moves the layers parented to it)",
        "layer 3 'matte' (shape): it is the track matte of layer 4 'label', not drawn itself",
        "layer 4 'label' (text): text layers are not supported",
        "layer 5 'hidden' (shape): it is hidden (hd)",
        "layer 6 'ghost' (shape): its opacity is 0 throughout",
        "layer 7 'paper' (solid): it is the background (an opaque solid covering the canvas), which is not stylized",
    ];
    assert!(msg.ends_with(&format!("{nothing}{}", expected.join("; "))), "{msg}");

    // Many layers: the first eight are named, the rest counted.
    let many = doc((1..=11).map(|i| bare_layer(json!(3), &format!("n{i}"), i)).collect());
    let msg = load_message(&many, &opts);
    assert!(msg.contains("; layer 8 'n8' (null): ") && !msg.contains("'n9'"), "{msg}");
    assert!(msg.ends_with("; and 3 more layers"), "{msg}");

    // Split precomps: the layers inside the precomp, each with its reason.
    let d = json!({"v": "5.7.1", "fr": 10, "ip": 0, "op": 10, "w": 40, "h": 40,
        "assets": [{"id": "c", "layers": [bare_layer(json!(5), "words", 1), bare_layer(json!(2), "photo", 2)]}],
        "layers": [{"ty": 0, "nm": "pre", "ind": 1, "refId": "c", "ip": 0, "op": 10, "st": 0, "ks": {}}]});
    let msg = load_message(&d, &LoadOptions::default().split_precomps(true));
    assert!(
        msg.ends_with(
            "layer 1 'pre' (precomp): with --split-precomps each layer inside it is a region, and none draws \
             anything (layer 1 'words' (text): text layers are not supported; layer 2 'photo' (image): image \
             layers are not supported)"
        ),
        "{msg}"
    );
}

#[test]
fn an_unreadable_layer_type_is_named_by_its_json_path() {
    let rect = rect_layer("ok", 9, 0.0, 0.0, 10.0, 10.0, [1.0; 4]);
    let opts = LoadOptions::default();
    let mut no_type = bare_layer(json!(0), "untyped", 3);
    no_type.as_object_mut().unwrap().remove("ty");
    let d = doc(vec![
        bare_layer(json!("abc"), "weird", 1),
        bare_layer(json!(4.5), "half", 2),
        no_type,
        bare_layer(json!(null), "null type", 4),
        rect.clone(),
    ]);
    let a = anim_of(&d, &opts);
    assert_eq!(a.regions.len(), 1);
    for w in [
        r#"layer 'weird': layers[0].ty is "abc", expected a number (the layer type); nothing drawn"#,
        "layer 'half': layers[1].ty is 4.5, expected a whole number (the layer type); nothing drawn",
        "layer 'untyped': layers[2].ty is missing, expected a number (the layer type); nothing drawn",
        "layer 'null type': layers[3].ty is null, expected a number (the layer type); nothing drawn",
    ] {
        assert!(a.warnings.contains(&w.to_string()), "{w} in {:?}", a.warnings);
    }
    assert!(!a.warnings.iter().any(|w| w.contains("-1")), "{:?}", a.warnings);
    // Inside a precomp asset, the path goes through `assets`.
    let d = json!({"v": "5.7.1", "fr": 10, "ip": 0, "op": 10, "w": 40, "h": 40,
        "assets": [{"id": "img", "w": 10, "h": 10, "p": "x.png"},
                   {"id": "c", "layers": [rect.clone(), bare_layer(json!([4]), "boxed", 2)]}],
        "layers": [{"ty": 0, "nm": "pre", "ind": 1, "refId": "c", "ip": 0, "op": 10, "st": 0, "ks": {}}]});
    let w = &anim_of(&d, &opts).regions[0].warnings;
    let expected = "layer 'boxed': assets[1].layers[1].ty is [4], expected a number (the layer type); nothing drawn";
    assert!(w.contains(&expected.to_string()), "{w:?}");
    // The only layer: the error quotes the same reason.
    let msg = load_message(&doc(vec![bare_layer(json!("abc"), "weird", 1)]), &opts);
    assert!(msg.ends_with(r#"layer 1 'weird': layers[0].ty is "abc", expected a number (the layer type)"#), "{msg}");
}

#[test]
fn unsupported_features_warn_with_layer_name() {
    let mut l = rect_layer("fancy", 1, 0.0, 0.0, 10.0, 10.0, [1.0; 4]);
    l["ef"] = json!([{"ty": 5}]);
    l["ks"] = json!({"r": {"a": 0, "k": 10, "x": "time * 30"}});
    l["shapes"].as_array_mut().unwrap().push(json!({"ty": "pb", "a": st(json!(10))}));
    let a = anim_of(&doc(vec![l]), &LoadOptions::default());
    let w = &a.regions[0].warnings;
    for feature in ["effects", "expressions", "puker/bloat"] {
        assert!(w.iter().any(|x| x.contains(feature) && x.contains("'fancy'")), "{feature}: {w:?}");
    }
}

#[test]
fn exponential_precomp_reuse_is_refused_before_drawing() {
    // Ten nested levels, each using the next one ten times: 10^10 draws if unbounded.
    let mut assets = Vec::new();
    for level in 0..10 {
        let layers: Vec<Value> = if level == 9 {
            vec![rect_layer("leaf", 1, 0.0, 0.0, 2.0, 2.0, [1.0; 4])]
        } else {
            (0..10)
                .map(|i| {
                    json!({"ty": 0, "nm": format!("use {i}"), "ind": i + 1, "refId": format!("c{}", level + 1),
                               "w": 40, "h": 40, "ip": 0, "op": 10, "st": 0, "ks": {}})
                })
                .collect()
        };
        assets.push(json!({"id": format!("c{level}"), "layers": layers}));
    }
    let d = json!({"v": "5.7.1", "fr": 10, "ip": 0, "op": 10, "w": 40, "h": 40, "assets": assets,
        "layers": [{"ty": 0, "nm": "top", "ind": 1, "refId": "c0", "w": 40, "h": 40, "ip": 0, "op": 10, "st": 0, "ks": {}}]});
    let f = write_temp(&d.to_string());
    let e = anim::load(f.path(), &LoadOptions::default()).unwrap_err();
    assert!(matches!(e, fluidymation::Error::Limit { .. }), "{e}");
    let text = e.to_string();
    assert!(text.contains("layers drawn per frame for layer 'top'") && text.contains("at most 10000"), "{text}");
}

/// `Animation::fill_motion`: the whole motion of a fill from the transforms it is drawn with —
/// here a square whose layer slides right 1 px a frame while its group turns 9° a frame about
/// the square's center. Every covered pixel's motion is the composed step `M′·M⁻¹·p − p`,
/// including the tangential part a mask cannot show (the turn moves the corners by up to
/// 1.5 px a frame though the square's outline hardly changes). A fill whose own outline is
/// animated moves with it point by point; one that fades out leaves no motion to give, nor
/// does the last frame.
#[test]
fn fill_motion_is_the_transforms_step() {
    let mut l = rect_layer("turning", 1, 10.0, 10.0, 10.0, 10.0, [1.0, 1.0, 1.0, 1.0]);
    let linear = json!({"x": [1], "y": [1]});
    let start = json!({"x": [0], "y": [0]});
    l["ks"] = json!({"p": {"a": 1, "k": [
        {"t": 0, "s": [0, 0], "i": linear, "o": start}, {"t": 10, "s": [10, 0]}]}});
    // The group turns about the square's center (15, 15): anchor and position there.
    l["shapes"][0]["it"][2] = json!({"ty": "tr", "p": st(json!([15, 15])), "a": st(json!([15, 15])),
        "s": st(json!([100, 100])), "o": st(json!(100)),
        "r": {"a": 1, "k": [{"t": 0, "s": [0], "i": linear, "o": start}, {"t": 10, "s": [90]}]}});
    let a = anim_of(&doc(vec![l]), &LoadOptions::default());
    let frame = 4;
    let v = a.fill_motion(0, frame).unwrap().expect("a Lottie fill's motion");
    let (th0, th1) = ((9.0 * frame as f32).to_radians(), (9.0 * (frame + 1) as f32).to_radians());
    let center0 = glam::Vec2::new(15.0 + frame as f32, 15.0);
    let (mut covered, mut largest) = (0, 0f32);
    for y in 0..40 {
        for x in 0..40 {
            let Some(m) = v.get(x, y) else { continue };
            covered += 1;
            let p = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            // Back to the square's own frame at frame 4, forward at frame 5.
            let local = glam::Vec2::from_angle(-th0).rotate(p - center0);
            let next = glam::Vec2::from_angle(th1).rotate(local) + center0 + glam::Vec2::new(1.0, 0.0);
            assert!((m - (next - p)).length() < 1e-3, "({x}, {y}): {m} against {}", next - p);
            largest = largest.max(m.length());
        }
    }
    // The square (100 px) at 36°: about 100 covered pixels; corners move farthest.
    assert!((90..=110).contains(&covered), "{covered} pixels with a motion");
    assert!(largest > 1.5, "largest motion {largest}");
    assert!(a.fill_motion(0, 9).unwrap().is_none(), "the last frame has no next");
    assert!(a.fill_motion(3, 0).is_err(), "no region 3");

    // A square that grows in its own coordinates (its size keyed 10 → 20 px over 10 frames,
    // about its center (15, 15)): its outline scales, and so does every point inside, exactly.
    let mut l = rect_layer("growing", 1, 10.0, 10.0, 10.0, 10.0, [1.0, 1.0, 1.0, 1.0]);
    l["shapes"][0]["it"][0]["s"] = json!({"a": 1, "k": [
        {"t": 0, "s": [10, 10], "i": linear, "o": start}, {"t": 10, "s": [20, 20]}]});
    let a = anim_of(&doc(vec![l]), &LoadOptions::default());
    let v = a.fill_motion(0, 4).unwrap().expect("a keyed size moves the same points");
    let c = glam::Vec2::new(15.0, 15.0);
    let mut covered = 0;
    for (k, m) in v.data().iter().enumerate() {
        let Some(m) = m else { continue };
        covered += 1;
        let p = glam::Vec2::new((k % 40) as f32 + 0.5, (k / 40) as f32 + 0.5);
        let want = c + (p - c) * (15.0 / 14.0) - p;
        assert!((*m - want).length() < 1e-3, "{p}: {m} against {want}");
    }
    assert_eq!(covered, 14 * 14);

    // A path whose keyframes move one vertex of a quadrilateral (path keyframes interpolate
    // vertex by vertex): near that vertex the paint moves nearly with it (measured 0.86 of
    // its step at 3.5 px from it), at the opposite one hardly at all (0.004 px).
    let path = |v: Value| json!({"c": true, "v": v, "i": [[0, 0], [0, 0], [0, 0], [0, 0]], "o": [[0, 0], [0, 0], [0, 0], [0, 0]]});
    let quad = |corner: [f64; 2]| path(json!([[5, 5], [35, 5], corner, [5, 35]]));
    let layer = json!({"ty": 4, "nm": "bending", "ind": 1, "ip": 0, "op": 10, "st": 0, "ks": {},
        "shapes": [{"ty": "gr", "it": [
            {"ty": "sh", "ks": {"a": 1, "k": [{"t": 0, "s": [quad([35.0, 35.0])], "i": linear, "o": start},
                                              {"t": 10, "s": [quad([25.0, 25.0])]}]}},
            {"ty": "fl", "c": st(json!([1, 1, 1, 1])), "o": st(json!(100)), "r": 1},
            {"ty": "tr", "p": st(json!([0, 0])), "a": st(json!([0, 0])), "s": st(json!([100, 100])),
             "r": st(json!(0)), "o": st(json!(100))}]}]});
    let a = anim_of(&doc(vec![layer]), &LoadOptions::default());
    let v = a.fill_motion(0, 2).unwrap().expect("a keyed path with the same vertices");
    // The corner moves (−1, −1) a frame.
    let near = v.get(31, 31).expect("inside, near the moving corner");
    let far = v.get(6, 6).expect("inside, at the still corner");
    println!("near the moving corner {near}, at the still one {far}");
    assert!((near - glam::Vec2::new(-1.0, -1.0)).length() < 0.35, "{near}");
    assert!(far.length() < 0.2, "{far}");

    // Fading out at frame 6: the fills of frames 5 and 6 differ, so no motion is given there.
    let mut l = rect_layer("fading", 1, 10.0, 10.0, 10.0, 10.0, [1.0, 1.0, 1.0, 1.0]);
    l["ks"] = json!({"o": {"a": 1, "k": [{"t": 5, "s": [100], "h": 1}, {"t": 6, "s": [0]}]}});
    let a = anim_of(&doc(vec![l]), &LoadOptions::default());
    assert!(a.fill_motion(0, 4).unwrap().is_some());
    assert!(a.fill_motion(0, 5).unwrap().is_none());
}
