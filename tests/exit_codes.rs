//! The exit codes the README promises — 0 done, 1 error, 2 usage, 130 interrupted (the last
//! is checked by `render_cli`'s resume test) — and limits that are errors before any work.

mod cli_support;

use cli_support::{bin, root, run, stderr};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    cli_support::scratch("exit", name)
}

/// The bundled demo animation's path, for a command line.
fn demo() -> String {
    root().join("fixtures/demo/waving.json").to_str().unwrap().to_string()
}

/// A fresh scratch folder's path ([`scratch`]), for a command line.
fn scratch_arg(name: &str) -> String {
    scratch(name).to_str().unwrap().to_string()
}

#[test]
fn done_error_and_usage_have_their_codes() {
    let demo = demo();
    let demo = demo.as_str();
    assert_eq!(run(&["inspect", demo]).status.code(), Some(0));
    assert_eq!(run(&["--version"]).status.code(), Some(0));
    // Errors: the input, a value checked against it.
    let o = run(&["inspect", "nowhere.json"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).starts_with("error: "));
    assert_eq!(run(&["inspect", demo, "--frames", "60..70"]).status.code(), Some(1));
    // Usage: what the command line itself gets wrong.
    for args in [&["render", "--no-such-flag"][..], &["render"], &["inspect", demo, "--scale", "big"], &["paint"]] {
        let o = run(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(err.starts_with("error: ") && (err.contains("Usage") || err.contains("--help")), "{err}");
    }
}

/// One rule for every count and scale option: a value outside the option's fixed range is a
/// malformed command line (exit 2, nothing run), refused by the option's value parser with a
/// message that names the option and the range. (Before, `--threads 0` was 1 and `--threads -1`
/// 2, `bench --frames 0` ran, and the message of each range came from another place.)
#[test]
fn out_of_range_counts_are_usage_errors_that_name_the_option() {
    let (demo, out) = (demo(), scratch_arg("counts"));
    let (demo, out) = (demo.as_str(), out.as_str());
    // A command line: its first words, then the case's.
    let line =
        |head: &[&str], extra: &[&str]| -> Vec<String> { head.iter().chain(extra).map(|s| s.to_string()).collect() };
    let render = |extra: &[&str]| line(&["render", demo, "-o", out], extra);
    let layer = |extra: &[&str]| line(&["render-layer", demo, "-o", out, "--layer", "1"], extra);
    let plain = |command: &str, extra: &[&str]| line(&[command], extra);
    // (command line, the option as clap names it, the range in the message)
    let cases: Vec<(Vec<String>, &str, &str)> = vec![
        (render(&["--threads", "0"]), "'--threads <N>'", "from 1 to 1024"),
        (render(&["--threads", "-1"]), "'--threads <N>'", "from 1 to 1024"),
        (render(&["--threads", "1025"]), "'--threads <N>'", "from 1 to 1024"),
        (render(&["--parallel-files", "0"]), "'--parallel-files <N>'", "at least 1"),
        (render(&["--scale", "0"]), "'--scale <SCALE>'", "(0, 16]"),
        (render(&["--src-speed", "0"]), "'--src-speed <N>'", "from 1 to 1000"),
        (render(&["--target-scale", "0"]), "'--target-scale <F>'", "(0.01, 16]"),
        (layer(&["--threads", "0"]), "'--threads <N>'", "from 1 to 1024"),
        (layer(&["--scale", "0"]), "'--scale <SCALE>'", "(0, 16]"),
        (plain("inspect", &[demo, "--scale", "0"]), "'--scale <SCALE>'", "(0, 16]"),
        (plain("quality", &["--jobs", "0"]), "'--jobs <JOBS>'", "from 1 to 64"),
        (plain("quality", &["--threads", "0"]), "'--threads <N>'", "from 1 to 1024"),
        (plain("quality", &["--frames", "0"]), "'--frames <FRAMES>'", "from 2 to 10000"),
        (plain("quality", &["--long-frames", "1"]), "'--long-frames <LONG_FRAMES>'", "from 2 to 10000"),
        (plain("quality", &["--window", "0"]), "'--window <WINDOW>'", "at least 1"),
        (plain("quality", &["--scale", "0"]), "'--scale <SCALE>'", "(0, 4]"),
        (plain("bench", &["--frames", "0"]), "'--frames <FRAMES>'", "at least 1"),
        (plain("bench", &["--threads", "0"]), "'--threads <N>'", "from 1 to 1024"),
        (
            plain("synth", &["-e", "ink-rims", "--masks", demo, "-o", out, "--threads", "0"]),
            "'--threads <N>'",
            "1 to 1024",
        ),
        (
            plain("synth", &["-e", "ink-rims", "--masks", demo, "-o", out, "--target-scale", "0"]),
            "'--target-scale <F>'",
            "(0.01, 16]",
        ),
        (
            plain("eval", &[out, "-e", "ink-rims", "--masks", out, "--patch-samples", "0"]),
            "'--patch-samples <PATCH_SAMPLES>'",
            "at least 1",
        ),
        (
            plain("eval", &[out, "-e", "ink-rims", "--masks", out, "--flow-radius", "0"]),
            "'--flow-radius <FLOW_RADIUS>'",
            "from 1 to 32",
        ),
        (
            plain("eval", &[out, "-e", "ink-rims", "--masks", out, "--src-speed", "0"]),
            "'--src-speed <N>'",
            "at least 1",
        ),
        (plain("exemplar", &["show", "ink-rims", "--columns", "0"]), "'--columns <COLUMNS>'", "from 1 to 64"),
        (plain("exemplar", &["show", "ink-rims", "--cell", "0"]), "'--cell <CELL>'", "from 8 to 1024"),
        (
            plain("exemplar", &["generate", "--name", "x", "-o", out, "--frames", "0"]),
            "'--frames <FRAMES>'",
            "from 2 to 1000",
        ),
        (
            plain("exemplar", &["generate", "--name", "x", "-o", out, "--drops", "0"]),
            "'--drops <DROPS>'",
            "from 1 to 16",
        ),
        (
            plain("exemplar", &["generate", "--name", "x", "-o", out, "--steps-per-frame", "0"]),
            "'--steps-per-frame <STEPS_PER_FRAME>'",
            "from 1 to 100",
        ),
    ];
    for (args, option, range) in &cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = run(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.starts_with("error: invalid value") && err.contains(option) && err.contains(range),
            "{args:?}: {err}"
        );
        assert!(err.contains("--help"), "{args:?}: {err}");
    }
    assert!(!Path::new(out).join("0001.png").exists() && !Path::new(out).join("x").exists(), "nothing was run");
}

#[test]
fn frames_past_the_end_are_said() {
    let o = run(&["inspect", &demo(), "--frames", "47..1000000"]);
    assert_eq!(o.status.code(), Some(0));
    assert!(
        stderr(&o).contains("warning: --frames '47..1000000': the input has only 48 frames; using 47..48"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn limits_are_errors_before_any_work() {
    let tmp = scratch("limits");
    let demo = demo();
    // A render too large for the memory limit: refused at once, nothing created.
    let out = tmp.join("big");
    let o = bin()
        .args(["render", &demo, "-o", out.to_str().unwrap(), "--scale", "16"])
        .env_remove("FLUIDYMATION_MEMORY_LIMIT")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("memory this render needs") && err.contains("6400x6400") && err.contains("--scale"), "{err}");
    assert!(!out.exists());
    // inspect's previews of that canvas (about 3.8 GB) over a 1 GB limit: refused the same way.
    let masks = tmp.join("masks");
    let o = bin()
        .args(["inspect", &demo, "--masks", masks.to_str().unwrap(), "--scale", "16", "--frames", "1"])
        .env("FLUIDYMATION_MEMORY_LIMIT", "1G")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("mask and guide previews need") && err.contains("6400x6400") && err.contains("--scale"),
        "{err}"
    );
    assert!(!masks.exists());
    // A precomp containing itself twice over a masked solid (ran for 40 s before).
    let solid = serde_json::json!({"ty": 1, "nm": "solid", "sc": "#ff0000", "sw": 200, "sh": 200, "ks": {},
        "masksProperties": [{"mode": "a", "pt": {"a": 0, "k": {"c": true, "v": [[10, 10], [190, 10], [190, 190]],
        "i": [[0, 0], [0, 0], [0, 0]], "o": [[0, 0], [0, 0], [0, 0]]}}}]});
    let pre = |i: u32| serde_json::json!({"ty": 0, "nm": format!("self {i}"), "ind": i, "refId": "a", "w": 200, "h": 200, "ks": {}});
    let doc = serde_json::json!({"v": "5.7.1", "fr": 24, "ip": 0, "op": 10, "w": 200, "h": 200,
        "assets": [{"id": "a", "layers": [pre(1), pre(2), solid]}], "layers": [pre(1)]});
    let file = tmp.join("selfref.json");
    std::fs::write(&file, doc.to_string()).unwrap();
    let o = run(&["inspect", file.to_str().unwrap(), "--frames", "5"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("precomp asset 'a' contains itself"), "{}", stderr(&o));
    // A canvas that --scale makes larger than the largest side is refused, not cropped.
    let wide = serde_json::json!({"v": "5.7.1", "fr": 24, "ip": 0, "op": 2, "w": 2000, "h": 1000, "layers": [
        {"ty": 4, "nm": "dot", "ks": {}, "shapes": [{"ty": "el", "p": {"a": 0, "k": [50, 50]}, "s": {"a": 0, "k": [20, 20]}},
        {"ty": "fl", "c": {"a": 0, "k": [1, 0, 0, 1]}, "o": {"a": 0, "k": 100}}]}]});
    let file = tmp.join("wide.json");
    std::fs::write(&file, wide.to_string()).unwrap();
    let o = run(&["inspect", file.to_str().unwrap(), "--scale", "10"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("canvas width at --scale 10 is 20000 but at most 16384"), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(Path::new(&tmp));
}

#[test]
fn negative_and_huge_numbers_are_named_not_taken_for_flags() {
    let (demo, out) = (demo(), scratch_arg("negative"));
    let (demo, out) = (demo.as_str(), out.as_str());
    // Each refused with the option's own message (before: "unexpected argument '-1'" and a tip
    // that turned the number into a second input).
    for (args, says) in [
        (&["--scale", "-1"][..], "'--scale <SCALE>': expected a number in (0, 16]"),
        (&["--seed", "-1"], "expected a whole number from 0 to 18446744073709551615"),
        (&["--frames", "-3..2"], "--frames '-3..2': frames are numbered from 1"),
        (&["--frames", "1..99999999999999999999"], "frame number 99999999999999999999 is too large"),
    ] {
        let o = run(&[&["render", demo, "-o", out][..], args].concat());
        assert!(matches!(o.status.code(), Some(1 | 2)), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(says), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("-- -"), "{args:?}: no tip to pass it after --");
    }
    assert!(!Path::new(out).join("0001.png").exists());
}

#[test]
fn results_that_cannot_be_written_fail_before_the_work() {
    let tmp = scratch("unwritable");
    let file = tmp.join("a-file");
    std::fs::write(&file, b"not a folder").unwrap();
    let under = file.join("report.json");
    // The quality suite would paint first and fail at the end (it can take an hour).
    let o = run(&["quality", "-e", "ink-rims", "--target", "still", "--json", under.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("--json: cannot write the report there"), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).is_empty(), "nothing was run");
    let o = run(&["quality", "-e", "ink-rims", "--target", "still", "-o", file.to_str().unwrap()]);
    assert!(stderr(&o).contains("exists and is not a directory"), "{}", stderr(&o));
    let painted = root().join("fixtures/demo/painted-0024.png");
    let o = run(&["exemplar", "import", painted.to_str().unwrap(), "--name", "x", "-o", file.to_str().unwrap()]);
    assert!(stderr(&o).contains("-o: cannot create the exemplar folder there"), "{}", stderr(&o));
    // An exemplar folder without its masks says what an exemplar folder holds.
    let ex = tmp.join("no-masks");
    std::fs::create_dir_all(ex.join("frames")).unwrap();
    std::fs::copy(root().join("exemplars/ink-rims/exemplar.toml"), ex.join("exemplar.toml")).unwrap();
    std::fs::copy(root().join("exemplars/ink-rims/frames/0001.png"), ex.join("frames/0001.png")).unwrap();
    let o = run(&["exemplar", "show", ex.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("has no masks/ folder; an exemplar folder holds exemplar.toml"), "{}", stderr(&o));
}
