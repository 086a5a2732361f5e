//! `fluidymation inspect` as a user runs it.

use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fluidymation"))
}

fn demo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/demo/waving.json")
}

#[test]
fn inspect_lists_the_demo() {
    let out = bin().arg("inspect").arg(demo()).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("400x400 px, 24 fps, 48 frames (2.00 s)"), "{text}");
    assert!(text.contains("background: #f3ede2 paper"), "{text}");
    for name in ["01  arm", "02  head", "03  scarf", "04  dress", "05  legs"] {
        assert!(text.contains(name), "{name} in {text}");
    }
    assert!(text.contains("#3366d9"), "dress color in {text}");
}

#[test]
fn inspect_json_and_masks() {
    let dir = std::env::temp_dir().join(format!("fm-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = bin()
        .args(["inspect", "--json", "--frames", "2..4", "--scale", "0.5", "--masks"])
        .arg(&dir)
        .arg(demo())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["width"], 200);
    assert_eq!(v["frames"], 48);
    assert_eq!(v["regions"].as_array().unwrap().len(), 5);
    assert_eq!(v["regions"][1]["has_strokes"], true);
    assert!(v["regions"][3]["mean_coverage"].as_f64().unwrap() > 0.03);
    // Frames 2..4 (1-based, inclusive) are written under their own numbers.
    let files: Vec<String> = std::fs::read_dir(dir.join("04_dress"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    assert_eq!(files, ["0002.png", "0003.png", "0004.png"]);
    let img = image::open(dir.join("04_dress/0002.png")).unwrap().to_luma8();
    assert_eq!(img.dimensions(), (200, 200));
    assert_eq!(img.get_pixel(100, 120)[0], 255);
    assert_eq!(img.get_pixel(5, 5)[0], 0);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn errors_exit_1_with_the_reason() {
    let bad = std::env::temp_dir().join(format!("fm-cli-bad-{}.json", std::process::id()));
    std::fs::write(&bad, "{\"w\": 10,\n \"h\": }").unwrap();
    let out = bin().arg("inspect").arg(&bad).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("error:") && err.contains("line 2"), "{err}");
    // serde_json's message gives the position; it is said once, not repeated as a cause.
    assert_eq!(err.matches("line 2").count(), 1, "{err}");
    let out = bin().args(["inspect", "--frames", "50..60"]).arg(demo()).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("only 48 frames"));
    let _ = std::fs::remove_file(&bad);
}

#[test]
fn inspect_writes_guide_previews() {
    let dir = std::env::temp_dir().join(format!("fm-cli-guides-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = bin().args(["inspect", "--frames", "10..14", "--guides"]).arg(&dir).arg(demo()).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stdout).contains("guide previews written to"));
    let load = |name: &str| image::open(dir.join("01_arm").join(name)).unwrap();
    for f in 10..=14 {
        for kind in ["flow", "ext_pos", "ext_neg", "border"] {
            let img = load(&format!("{kind}_{f:04}.png"));
            assert_eq!((img.width(), img.height()), (400, 400), "{kind} {f}");
        }
    }
    let lum = |name: &str| load(name).to_luma8().into_raw();
    // The extents accumulate motion: nothing before the first frame of the range, nothing after
    // its last; in between, the waving arm has moved.
    assert!(lum("ext_pos_0010.png").iter().all(|&v| v == 0));
    assert!(lum("ext_neg_0014.png").iter().all(|&v| v == 0));
    assert!(lum("ext_pos_0014.png").iter().filter(|&&v| v > 64).count() > 50);
    assert!(lum("ext_neg_0010.png").iter().filter(|&&v| v > 64).count() > 50);
    // The flow of the moving arm is drawn in color (hue = direction), black where still.
    let flow = load("flow_0012.png").to_rgb8();
    let colored = flow.pixels().filter(|p| p.0.iter().max().unwrap() - p.0.iter().min().unwrap() > 40).count();
    assert!(colored > 100, "{colored} colored flow pixels");
    // The border channel rises from the edge into the interior: several levels inside.
    let border = lum("border_0012.png");
    let mut levels: Vec<u8> = border.iter().copied().filter(|&v| v > 0).collect();
    levels.sort_unstable();
    levels.dedup();
    assert!(levels.len() >= 5, "{levels:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A layer drawn with strokes alone has no fill region to paint into, and `inspect` says so.
#[test]
fn inspect_names_a_stroke_only_layer() {
    let path = std::env::temp_dir().join(format!("fm-cli-strokes-{}.json", std::process::id()));
    let rect = |ty: &str, extra: &str| {
        format!(
            r#"{{"ty":"gr","it":[{{"ty":"rc","p":{{"a":0,"k":[50,50]}},"s":{{"a":0,"k":[40,40]}},"r":{{"a":0,"k":0}}}},
               {{"ty":"{ty}","c":{{"a":0,"k":[0.2,0.4,0.8,1]}},"o":{{"a":0,"k":100}}{extra}}},
               {{"ty":"tr","p":{{"a":0,"k":[0,0]}},"a":{{"a":0,"k":[0,0]}},"s":{{"a":0,"k":[100,100]}},"r":{{"a":0,"k":0}},"o":{{"a":0,"k":100}}}}]}}"#
        )
    };
    let layer = |ind: u32, name: &str, shape: String| {
        format!(
            r#"{{"ty":4,"ind":{ind},"nm":"{name}","ip":0,"op":10,"st":0,
               "ks":{{"o":{{"a":0,"k":100}},"r":{{"a":0,"k":0}},"p":{{"a":0,"k":[0,0]}},"a":{{"a":0,"k":[0,0]}},"s":{{"a":0,"k":[100,100]}}}},
               "shapes":[{shape}]}}"#
        )
    };
    let json = format!(
        r#"{{"v":"5.7.0","fr":24,"ip":0,"op":10,"w":100,"h":100,"layers":[{},{}]}}"#,
        layer(1, "outline", rect("st", r#","w":{"a":0,"k":4},"lc":1,"lj":1"#)),
        layer(2, "body", rect("fl", ""))
    );
    std::fs::write(&path, json).unwrap();
    let out = bin().arg("inspect").arg(&path).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let line = |name: &str| text.lines().find(|l| l.contains(name)).unwrap_or_default().to_string();
    assert!(line("outline").contains("strokes only"), "{text}");
    assert!(!line("body").contains("strokes"), "{text}");
    let _ = std::fs::remove_file(&path);
}

/// What `inspect` makes of folders, globs and single files: a still from one SVG file, frames
/// chosen by a `[...]` class, and for inputs that are no animation, what they hold instead.
#[test]
fn inspect_reads_stills_classes_and_says_what_a_folder_holds() {
    let dir = std::env::temp_dir().join(format!("fm-cli-inputs-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (seq, lottie, empty) = (dir.join("seq"), dir.join("lottie"), dir.join("empty"));
    for d in [&seq, &lottie, &empty] {
        std::fs::create_dir_all(d).unwrap();
    }
    for k in 1..=4 {
        let svg = format!(
            "<svg xmlns='http://www.w3.org/2000/svg' width='64' height='48'><g id='dot'>\
             <circle cx='{}' cy='24' r='10' fill='#3366d9'/></g></svg>",
            10 + 8 * k
        );
        std::fs::write(seq.join(format!("f0{k}.svg")), svg).unwrap();
    }
    let inspect = |input: &Path| bin().arg("inspect").arg(input).output().unwrap();
    let ok = |input: &Path| {
        let o = inspect(input);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8(o.stdout).unwrap()
    };
    let failed = |input: &Path| {
        let o = inspect(input);
        assert_eq!(o.status.code(), Some(1));
        String::from_utf8(o.stderr).unwrap()
    };
    // One SVG file: a still of one frame, its groups the layers.
    let text = ok(&seq.join("f02.svg"));
    assert!(text.contains("64x48 px, 24 fps, 1 frame (0.04 s)"), "{text}");
    assert!(text.contains("01  dot") && text.contains("1..1"), "{text}");
    // A class selects frames.
    let text = ok(&seq.join("f0[2-4].svg"));
    assert!(text.contains("3 frames"), "{text}");
    // A folder of Lottie files, a glob matching several, an empty folder.
    std::fs::copy(demo(), lottie.join("a.json")).unwrap();
    std::fs::copy(demo(), lottie.join("b.json")).unwrap();
    let l = lottie.display().to_string();
    let err = failed(&lottie);
    assert!(err.contains(&format!("'{l}': holds 2 .json files but no SVG frames (.svg) or PNG masks (.png)")), "{err}");
    assert!(err.contains("`inspect` takes one file"), "{err}");
    let err = failed(&lottie.join("*.json"));
    assert!(err.contains(&format!("'{l}/*.json': matches 2 Lottie .json files (a.json, b.json)")), "{err}");
    assert!(!err.contains("SVG/XML"), "{err}");
    // A glob matching one Lottie file is that file.
    assert!(ok(&lottie.join("[a].json")).contains("48 frames"));
    let err = failed(&empty);
    let e = empty.display();
    assert!(err.contains(&format!("'{e}': no SVG frames (.svg) or PNG masks (.png) found: it holds 0 files")), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A Lottie field of the wrong type fails the file (exit 1, never a panic) with its JSON path
/// and what was expected, for `inspect` and `render` alike; before, a string `fr` read as
/// "missing 'fr'", a string `ip` or `layers[2].ind` was silently ignored, and a `ks` that is a
/// number gave serde's message with a line and column only.
#[test]
fn wrongly_typed_lottie_fields_are_named_by_their_json_path() {
    let dir = std::env::temp_dir().join(format!("fm-cli-fields-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let shape = |i: u32| {
        serde_json::json!({"ty": 4, "nm": format!("s{i}"), "ind": i, "ip": 0, "op": 10, "st": 0, "ks": {},
            "shapes": [{"ty": "rc", "p": {"a": 0, "k": [50, 50]}, "s": {"a": 0, "k": [40, 40]}, "r": {"a": 0, "k": 0}},
                       {"ty": "fl", "c": {"a": 0, "k": [1, 0, 0, 1]}, "o": {"a": 0, "k": 100}}]})
    };
    let base = serde_json::json!({"v": "5.7.1", "fr": 24, "ip": 0, "op": 10, "w": 100, "h": 100,
        "assets": [{"id": "a", "layers": [shape(1)]}], "layers": [shape(1), shape(2), shape(3)]});
    type Edit = fn(&mut serde_json::Value);
    let cases: &[(&str, Edit, &str)] = &[
        ("fr-string", |d| d["fr"] = "abc".into(), r#"fr is "abc", expected a number (the frame rate)"#),
        ("ip-string", |d| d["ip"] = "abc".into(), r#"ip is "abc", expected a number (the first frame)"#),
        ("op-string", |d| d["op"] = "abc".into(), r#"op is "abc", expected a number (the end frame)"#),
        ("w-string", |d| d["w"] = "abc".into(), r#"w is "abc", expected a number (the canvas width)"#),
        ("h-string", |d| d["h"] = "abc".into(), r#"h is "abc", expected a number (the canvas height)"#),
        ("fr-zero", |d| d["fr"] = 0.into(), "frame rate 'fr' is 0; it must be at least 0.01"),
        ("fr-negative", |d| d["fr"] = (-5).into(), "frame rate 'fr' is -5; it must be at least 0.01"),
        ("op-zero", |d| d["op"] = 0.into(), "end frame 'op' (0) is not after the first frame 'ip' (0)"),
        ("op-negative", |d| d["op"] = (-5).into(), "end frame 'op' (-5) is not after the first frame 'ip' (0)"),
        ("w-zero", |d| d["w"] = 0.into(), "canvas width 'w' is 0; it must be at least 1 pixel"),
        ("h-negative", |d| d["h"] = (-5).into(), "canvas height 'h' is -5; it must be at least 1 pixel"),
        ("ind-string", |d| d["layers"][2]["ind"] = "abc".into(), r#"layers[2].ind is "abc", expected a number"#),
        ("parent-string", |d| d["layers"][1]["parent"] = "x".into(), r#"layers[1].parent is "x", expected a number"#),
        ("layer-ip-string", |d| d["layers"][1]["ip"] = "x".into(), r#"layers[1].ip is "x", expected a number"#),
        (
            "ks-number",
            |d| d["layers"][1]["ks"] = 5.into(),
            "layers[1].ks is 5, expected an object (the layer's transform)",
        ),
        (
            "shapes-object",
            |d| d["layers"][0]["shapes"] = serde_json::json!({}),
            "layers[0].shapes is an object, expected a list of shape items",
        ),
        ("layer-number", |d| d["layers"][1] = 5.into(), "layers[1] is 5, expected an object (a layer)"),
        ("layers-object", |d| d["layers"] = serde_json::json!({}), "layers is an object, expected a list of layers"),
        ("assets-number", |d| d["assets"] = 5.into(), "assets is 5, expected a list"),
        (
            "asset-layer-ind",
            |d| d["assets"][0]["layers"][0]["ind"] = "q".into(),
            r#"assets[0].layers[0].ind is "q", expected a number"#,
        ),
    ];
    for (name, edit, says) in cases {
        let mut doc = base.clone();
        edit(&mut doc);
        let file = dir.join(format!("{name}.json"));
        std::fs::write(&file, doc.to_string()).unwrap();
        let out = dir.join(format!("{name}-out"));
        let commands: [Vec<&std::ffi::OsStr>; 2] = [
            vec!["inspect".as_ref(), file.as_ref()],
            vec!["render".as_ref(), file.as_ref(), "-o".as_ref(), out.as_ref(), "-e".as_ref(), "none".as_ref()],
        ];
        for args in commands {
            let o = bin().args(&args).output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(1), "{name} {:?}: {err}", args[0]);
            assert!(err.contains(&format!("'{}': {says}", file.display())), "{name} {:?}: {err}", args[0]);
            assert!(!err.contains("panicked") && !err.contains("not valid JSON"), "{name}: {err}");
        }
        assert!(!out.exists(), "{name}: nothing written");
    }
    // The untouched file and a negative first frame (allowed by Lottie) load.
    let file = dir.join("negative-ip.json");
    let mut doc = base.clone();
    doc["ip"] = (-5).into();
    std::fs::write(&file, doc.to_string()).unwrap();
    let o = bin().arg("inspect").arg(&file).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}
