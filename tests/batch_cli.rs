//! Batches and plans as a user runs them: `render a.json b.json -o OUT`, per-file styles,
//! failures and `--resume` per file; `plan` and its `render-layer`/`composite` jobs run by
//! hand in an order of our choosing, giving the same bytes as `render`.
//!
//! Inputs are small (`--scale 0.25`–`0.5`, a few frames): the bundled demo
//! `fixtures/demo/waving.json` and `tests/render/quads.json`.

mod farm_support;

use farm_support::*;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn run(args: &[&std::ffi::OsStr]) -> Output {
    bin().args(args).output().unwrap()
}

fn os<S: AsRef<std::ffi::OsStr> + ?Sized>(s: &S) -> &std::ffi::OsStr {
    s.as_ref()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[track_caller]
fn assert_success(o: &Output) {
    assert!(o.status.success(), "exit {:?}\n{}", o.status.code(), stderr(o));
}

fn frame_names(range: std::ops::RangeInclusive<usize>) -> Vec<String> {
    range.map(|k| format!("{k:04}.png")).collect()
}

fn rgba(path: &Path) -> image::RgbaImage {
    image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgba8()
}

#[test]
fn a_batch_writes_each_file_apart_and_a_failure_does_not_stop_the_others() {
    let tmp = Scratch::new("failure");
    let broken = tmp.join("broken.json");
    std::fs::write(&broken, "{\"v\": \"5.7.0\", \"w\": 100").unwrap();
    let out = tmp.join("out");
    let quick = ["--scale", "0.25", "--frames", "1..3", "--seed", "5"];
    let (quads, demo) = (quads(), demo());
    let mut args =
        vec![os("render"), quads.as_os_str(), broken.as_os_str(), demo.as_os_str(), os("-o"), out.as_os_str()];
    args.extend(quick.iter().map(os));
    args.push(os("--gif"));
    let o = run(&args);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(!err.contains("panicked"), "{err}");
    // The summary names every file with its result, in the order given, and the error of the
    // broken one; the last line says which failed.
    assert!(err.contains("3 files") && err.contains("2 rendered, 1 failed"), "{err}");
    let line = |name: &str| err.lines().find(|l| l.contains(name)).unwrap_or_else(|| panic!("{name} in {err}"));
    assert!(line("quads.json").contains("ok") && line("quads.json").contains("3 frames"), "{err}");
    assert!(line("waving.json").contains("ok"), "{err}");
    assert!(line("broken.json").contains("FAILED") && line("broken.json").contains("JSON"), "{err}");
    assert!(err.lines().last().unwrap().contains("1 of 3 files failed") && err.contains("broken.json"), "{err}");

    // Each good file in its own folder with its GIF beside; nothing for the broken one.
    let mut expected: Vec<String> = Vec::new();
    for stem in ["quads", "waving"] {
        expected.extend(frame_names(1..=3).iter().map(|f| format!("{stem}/{f}")));
        expected.push(format!("{stem}.gif"));
        expected.push(format!("{stem}/.fluidymation/frames.log"));
        expected.push(format!("{stem}/.fluidymation/progress.toml"));
    }
    expected.sort();
    assert_eq!(tree(&out), expected);

    // Each file's output is what rendering it alone gives, byte for byte.
    for (input, stem) in [(&quads, "quads"), (&demo, "waving")] {
        let alone = tmp.join(&format!("alone-{stem}"));
        let gif = alone.join(format!("{stem}.gif"));
        let mut args = vec![os("render"), input.as_os_str(), os("-o"), alone.as_os_str(), os("--gif"), gif.as_os_str()];
        args.extend(quick.iter().map(os));
        assert_success(&run(&args));
        for f in frame_names(1..=3) {
            assert!(
                std::fs::read(alone.join(&f)).unwrap() == std::fs::read(out.join(stem).join(&f)).unwrap(),
                "{stem}/{f}"
            );
        }
        assert!(std::fs::read(&gif).unwrap() == std::fs::read(out.join(format!("{stem}.gif"))).unwrap(), "{stem}.gif");
    }
}

#[test]
fn a_failed_file_says_its_reason_once_in_the_summary() {
    // Nothing is rendered: a truncated file, and one whose only layer is text.
    let tmp = Scratch::new("reasons");
    let (truncated, text) = (tmp.join("truncated.json"), tmp.join("text.json"));
    std::fs::write(&truncated, "{\"v\": \"5.7.0\",\n \"w\": 100,\n \"layers\": [").unwrap();
    let title = r#"{"ty": 5, "nm": "title", "ind": 1, "ip": 0, "op": 10, "ks": {}}"#;
    std::fs::write(&text, format!(r#"{{"fr": 10, "ip": 0, "op": 10, "w": 40, "h": 40, "layers": [{title}]}}"#))
        .unwrap();
    let out = tmp.join("out");
    let o = run(&[os("render"), truncated.as_os_str(), text.as_os_str(), os("-o"), out.as_os_str()]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    let line = |name: &str| err.lines().find(|l| l.contains("FAILED") && l.contains(name)).unwrap_or_default();
    let json = line("truncated.json");
    assert!(json.ends_with("is not valid JSON: EOF while parsing a list at line 3 column 12"), "{err}");
    assert_eq!(json.matches("line 3").count(), 1, "{err}");
    assert!(
        line("text.json").ends_with(
            "no layer draws anything that could be stylized: layer 1 'title' (text): text layers are not supported"
        ),
        "{err}"
    );
}

#[test]
fn per_file_styles_in_one_styles_file() {
    let tmp = Scratch::new("styles");
    let styles = tmp.join("styles.toml");
    // Everything flat, except in quads.json: painted, and its orange square flat again.
    std::fs::write(
        &styles,
        "default = \"none\"\n\n[files.\"quads.json\"]\ndefault = \"blue-bloom\"\n\n[files.\"quads.json\".layers]\norange = \"none\"\nred = \"rose-burst\"\n",
    )
    .unwrap();
    let out = tmp.join("out");
    let (q, d) = (quads(), demo());
    let mut args =
        vec![os("render"), q.as_os_str(), d.as_os_str(), os("-o"), out.as_os_str(), os("--styles"), styles.as_os_str()];
    let quick = ["--scale", "0.5", "--frames", "1..2"];
    args.extend(quick.iter().map(os));
    assert_success(&run(&args));

    // The demo is left flat: exactly its flat rendering.
    let flat = tmp.join("flat");
    let mut args = vec![os("render"), d.as_os_str(), os("-o"), flat.as_os_str(), os("--exemplar"), os("none")];
    args.extend(quick.iter().map(os));
    assert_success(&run(&args));
    for f in frame_names(1..=2) {
        assert!(std::fs::read(flat.join(&f)).unwrap() == std::fs::read(out.join("waving").join(&f)).unwrap(), "{f}");
    }
    // In quads the orange square keeps its exact color, the others are painted (the paint
    // varies inside a square; flat, it does not).
    for f in frame_names(1..=2) {
        let img = rgba(&out.join("quads").join(&f));
        let p = img.get_pixel(105, 105).0;
        assert!((0..3).all(|i| (p[i] as i32 - [240, 140, 30][i]).abs() <= 1), "{f} orange: {p:?}");
        for (x0, y0) in [(0u32, 0u32), (70, 0), (0, 70)] {
            let lum: Vec<f64> = (y0 + 22..y0 + 46)
                .flat_map(|y| (x0 + 22..x0 + 46).map(move |x| (x, y)))
                .map(|(x, y)| img.get_pixel(x, y).0.iter().take(3).map(|&v| v as f64).sum::<f64>() / 3.0)
                .collect();
            let m = lum.iter().sum::<f64>() / lum.len() as f64;
            let sd = (lum.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / lum.len() as f64).sqrt();
            assert!(sd > 4.0, "{f} quadrant at ({x0}, {y0}) is not painted (sd {sd:.1})");
        }
    }

    // A per-file table naming a layer that file does not have fails that file only.
    std::fs::write(&styles, "[files.\"quads.json\".layers]\nnose = \"ink-rims\"\n").unwrap();
    let out = tmp.join("out2");
    let mut args =
        vec![os("render"), q.as_os_str(), d.as_os_str(), os("-o"), out.as_os_str(), os("--styles"), styles.as_os_str()];
    args.extend(quick.iter().map(os));
    let o = run(&args);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("no layer named 'nose'") && err.contains("[files.\"quads.json\".layers]"), "{err}");
    assert!(err.contains("red") && err.contains("orange"), "the layers are listed: {err}");
    assert!(out.join("waving/0002.png").is_file() && !out.join("quads").exists(), "{:?}", tree(&out));
}

#[test]
fn batch_errors_before_any_work() {
    let tmp = Scratch::new("errors");
    let (q, d) = (quads(), demo());
    let out = tmp.join("out");
    let gif = tmp.join("x.gif");
    // One GIF file for several inputs.
    let o = run(&[os("render"), q.as_os_str(), d.as_os_str(), os("-o"), out.as_os_str(), os("--gif"), gif.as_os_str()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--gif") && stderr(&o).contains("<name>.gif"), "{}", stderr(&o));
    // `--gif` before the inputs takes the first one as the GIF's name: refused, the input kept.
    let input = tmp.join("walk.json");
    std::fs::copy(&d, &input).unwrap();
    let before = std::fs::read(&input).unwrap();
    let o = run(&[os("render"), os("--gif"), input.as_os_str(), q.as_os_str(), os("-o"), out.as_os_str()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("walk.json") && stderr(&o).contains("not a .gif"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&input).unwrap(), before, "the input was overwritten");
    // An existing file that is not a GIF, under a .gif name.
    let fake = tmp.join("notes.gif");
    std::fs::write(&fake, "my notes").unwrap();
    let o = run(&[os("render"), d.as_os_str(), os("-o"), out.as_os_str(), os("--gif"), fake.as_os_str()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("not a GIF"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&fake).unwrap(), "my notes");
    // Two inputs that would share a folder.
    let copy = tmp.join("other");
    std::fs::create_dir_all(&copy).unwrap();
    std::fs::copy(&q, copy.join("quads.json")).unwrap();
    let c = copy.join("quads.json");
    let o = run(&[os("render"), q.as_os_str(), c.as_os_str(), os("-o"), out.as_os_str()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("would both be written to"), "{}", stderr(&o));
    // A --style naming a layer none of the inputs has.
    let o = run(&[
        os("render"),
        q.as_os_str(),
        d.as_os_str(),
        os("-o"),
        out.as_os_str(),
        os("--style"),
        os("nose=ink-rims"),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("no layer named 'nose'"), "{}", stderr(&o));
    // Nothing to resume in any of them.
    let o = run(&[os("render"), q.as_os_str(), d.as_os_str(), os("-o"), out.as_os_str(), os("--resume")]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("no interrupted render to resume"), "{}", stderr(&o));
    // A shell-expanded glob of SVG frames.
    for k in 1..=2 {
        std::fs::write(
            tmp.join(&format!("f{k}.svg")),
            "<svg xmlns='http://www.w3.org/2000/svg' width='10' height='10'/>",
        )
        .unwrap();
    }
    let (a, b) = (tmp.join("f1.svg"), tmp.join("f2.svg"));
    let o = run(&[os("render"), a.as_os_str(), b.as_os_str(), os("-o"), out.as_os_str()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("quote the glob"), "{}", stderr(&o));
    assert!(!out.exists(), "nothing was written");
}

/// Waits until `path` exists while `child` runs, at most two minutes.
fn wait_for(child: &mut std::process::Child, path: &Path) {
    let start = Instant::now();
    while !path.exists() {
        if let Some(status) = child.try_wait().unwrap() {
            panic!("the process ended ({status}) before {} existed", path.display());
        }
        assert!(start.elapsed() < Duration::from_secs(120), "{} never appeared", path.display());
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[cfg(unix)]
#[test]
fn a_killed_batch_resumes_per_file() {
    let tmp = Scratch::new("resume");
    let (q, d) = (quads(), demo());
    let quick = ["--scale", "0.5", "--frames", "1..6", "--parallel-files", "1", "--gif"];
    let batch = |out: &Path, extra: &[&str]| {
        let mut c = bin();
        c.arg("render").arg(&q).arg(&d).arg("-o").arg(out).args(quick).args(extra);
        c
    };
    let full = tmp.join("full");
    assert_success(&batch(&full, &[]).output().unwrap());

    // Killed while the second file is half done (files run one after the other here).
    let out = tmp.join("out");
    let mut child = batch(&out, &[]).stdout(Stdio::null()).stderr(Stdio::null()).spawn().unwrap();
    wait_for(&mut child, &out.join("waving/0003.png"));
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!out.join("waving/0006.png").exists(), "the kill came too late");
    let quads_before: Vec<_> = frame_names(1..=6)
        .iter()
        .map(|f| std::fs::metadata(out.join("quads").join(f)).unwrap().modified().unwrap())
        .collect();

    let o = batch(&out, &["--resume"]).output().unwrap();
    assert_success(&o);
    let err = stderr(&o);
    let line = |name: &str| err.lines().find(|l| l.contains(name)).unwrap_or_else(|| panic!("{name} in {err}"));
    assert!(line("quads.json").contains("already complete"), "{err}");
    assert!(line("waving.json").contains("resumed"), "{err}");
    let quads_after: Vec<_> = frame_names(1..=6)
        .iter()
        .map(|f| std::fs::metadata(out.join("quads").join(f)).unwrap().modified().unwrap())
        .collect();
    assert_eq!(quads_before, quads_after, "the finished file's frames were written again");
    assert_eq!(tree(&out), tree(&full));
    assert_same_results(&out, &full);
}

/// The plan's jobs, parsed.
struct Job {
    id: String,
    kind: String,
    argv: Vec<String>,
    deps: Vec<String>,
    outputs: Vec<String>,
    cost: u64,
}

fn plan(inputs: &[&Path], out: &Path, extra: &[&str]) -> (serde_json::Value, Vec<Job>) {
    let o = bin().arg("plan").args(inputs).arg("-o").arg(out).args(extra).output().unwrap();
    assert_success(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let jobs = v["jobs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| Job {
            id: j["id"].as_str().unwrap().into(),
            kind: j["kind"].as_str().unwrap().into(),
            argv: j["argv"].as_array().unwrap().iter().map(|a| a.as_str().unwrap().to_string()).collect(),
            deps: j["deps"].as_array().unwrap().iter().map(|a| a.as_str().unwrap().to_string()).collect(),
            outputs: j["outputs"].as_array().unwrap().iter().map(|a| a.as_str().unwrap().to_string()).collect(),
            cost: j["cost"].as_u64().unwrap(),
        })
        .collect();
    (v, jobs)
}

fn run_job(job: &Job) -> Output {
    Command::new(&job.argv[0]).args(&job.argv[1..]).output().unwrap()
}

#[test]
fn plan_jobs_run_by_hand_give_the_bytes_of_render() {
    let tmp = Scratch::new("plan");
    let (q, d) = (quads(), demo());
    let opts = [
        "--scale",
        "0.25",
        "--frames",
        "2..5",
        "--seed",
        "3",
        "--keep-layers",
        "--style",
        "head=none",
        "--style",
        "red=ink-rims",
        "--gif",
    ];
    let rendered = tmp.join("render");
    let o = bin().arg("render").arg(&q).arg(&d).arg("-o").arg(&rendered).args(opts).output().unwrap();
    assert_success(&o);

    let out = tmp.join("plan");
    let (plan, jobs) = plan(&[&q, &d], &out, &opts);
    assert_eq!(plan["format"], 1);
    assert!(!out.exists(), "planning writes nothing");
    // One job per stylized layer (quads: 4; the demo: 5 less its flat head), one composite
    // per file depending on exactly its own layers.
    let layers: Vec<&Job> = jobs.iter().filter(|j| j.kind == "layer").collect();
    let composites: Vec<&Job> = jobs.iter().filter(|j| j.kind == "composite").collect();
    assert_eq!(layers.len(), 4 + 4, "{:?}", jobs.iter().map(|j| &j.id).collect::<Vec<_>>());
    assert_eq!(composites.len(), 2);
    assert!(!layers.iter().any(|j| j.id.contains("head")), "a flat layer has no job");
    for c in &composites {
        let stem = c.id.split('/').next().unwrap();
        let mut mine: Vec<&String> =
            layers.iter().filter(|j| j.id.starts_with(&format!("{stem}/"))).map(|j| &j.id).collect();
        let mut deps: Vec<&String> = c.deps.iter().collect();
        mine.sort();
        deps.sort();
        assert_eq!(deps, mine, "{}", c.id);
        assert_eq!(c.argv[1], "composite");
        assert!(c.outputs.iter().any(|o| o.ends_with(&format!("{stem}/0005.png"))), "{:?}", c.outputs);
        assert!(c.outputs.iter().any(|o| o.ends_with(&format!("{stem}.gif"))), "{:?}", c.outputs);
    }
    for l in &layers {
        assert_eq!(l.argv[1], "render-layer");
        assert!(l.deps.is_empty());
        assert!(Path::new(&l.argv[0]).is_absolute() && Path::new(&l.argv[2]).is_absolute(), "{:?}", l.argv);
    }
    // The cost is the masked pixels over the frames: the demo's dress outweighs its arm, and
    // quads' four equal squares cost about the same.
    let cost = |id: &str| layers.iter().find(|j| j.id == id).unwrap_or_else(|| panic!("{id}")).cost;
    assert!(
        cost("waving/04_dress") > 3 * cost("waving/01_arm"),
        "{} vs {}",
        cost("waving/04_dress"),
        cost("waving/01_arm")
    );
    let q: Vec<u64> = layers.iter().filter(|j| j.id.starts_with("quads/")).map(|j| j.cost).collect();
    assert!(q.iter().max().unwrap() - q.iter().min().unwrap() < q[0] / 5, "{q:?}");

    // A composite before its layers fails clearly and writes no frame.
    let o = run_job(composites[0]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("not painted") && stderr(&o).contains("render-layer"), "{}", stderr(&o));
    assert!(!out.exists() || !results(&out).keys().any(|k| k.ends_with("0002.png")), "{:?}", tree(&out));

    // The jobs in another valid order: the layers backwards, each file's composite right after
    // its last layer, one layer run twice (the second run finds it done).
    let mut done: Vec<&str> = Vec::new();
    for l in layers.iter().rev() {
        assert_success(&run_job(l));
        done.push(&l.id);
        for c in &composites {
            if c.deps.iter().all(|d| done.contains(&d.as_str())) && !done.contains(&c.id.as_str()) {
                assert_success(&run_job(c));
                done.push(&c.id);
            }
        }
    }
    assert_eq!(done.len(), jobs.len());
    let again = run_job(layers[0]);
    assert_success(&again);
    assert!(stderr(&again).contains("already complete"), "{}", stderr(&again));
    assert_same_results(&out, &rendered);

    // A composite with other engine options than its layers were painted with is refused,
    // and the frames stay as they are.
    let mut other = composites[0].argv.clone();
    let seed = other.iter().position(|a| a == "--seed").unwrap();
    other[seed + 1] = "4".into();
    let o = Command::new(&other[0]).args(&other[1..]).output().unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("painted with other options"), "{}", stderr(&o));
    assert_same_results(&out, &rendered);
}

#[cfg(unix)]
#[test]
fn a_killed_layer_job_continues_from_its_checkpoint() {
    let tmp = Scratch::new("layer-kill");
    let d = demo();
    let opts = ["--scale", "0.5", "--frames", "1..12", "--exemplar", "none", "--style", "dress=blue-bloom"];
    let rendered = tmp.join("render");
    assert_success(&bin().arg("render").arg(&d).arg("-o").arg(&rendered).args(opts).output().unwrap());

    let out = tmp.join("plan");
    let (_, jobs) = plan(&[&d], &out, &opts);
    assert_eq!(jobs.len(), 2);
    let (layer, composite) = (&jobs[0], &jobs[1]);
    assert_eq!(layer.id, "waving/04_dress");
    let mut child = Command::new(&layer.argv[0]).args(&layer.argv[1..]).stderr(Stdio::null()).spawn().unwrap();
    wait_for(&mut child, &out.join("layers/04_dress/paint/0003.png"));
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!out.join("layers/04_dress/layer.json").exists(), "the kill came too late");

    // The composite refuses the half-painted layer; the layer job, run again, continues.
    let o = run_job(composite);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let o = run_job(layer);
    assert_success(&o);
    assert!(stderr(&o).contains("resumed"), "{}", stderr(&o));
    assert_success(&run_job(composite));
    assert_same_results(&out, &rendered);
    // Nothing of the checkpoints is left, and no temporary file.
    let left: Vec<String> =
        tree(&out.join("layers/04_dress")).into_iter().filter(|n| !n.starts_with("paint/")).collect();
    assert_eq!(left, [".lock", "layer.json"]);
}

/// Kills a run of the layer job `layer` once it has painted three frames of the demo's dress.
#[cfg(unix)]
fn kill_after_three_frames(layer: &Job, dir: &Path) {
    let mut child = Command::new(&layer.argv[0]).args(&layer.argv[1..]).stderr(Stdio::null()).spawn().unwrap();
    wait_for(&mut child, &dir.join("paint/0003.png"));
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!dir.join("layer.json").exists(), "the kill came too late");
}

/// Flips one bit in the middle of a file.
#[cfg(unix)]
fn flip_a_bit(path: &Path) {
    let mut bytes = std::fs::read(path).unwrap();
    let i = bytes.len() / 2;
    bytes[i] ^= 0x10;
    std::fs::write(path, bytes).unwrap();
}

#[cfg(unix)]
#[test]
fn a_layer_job_never_uses_damaged_state_and_the_composite_refuses_changed_paint() {
    let tmp = Scratch::new("layer-damage");
    let d = demo();
    let opts = ["--scale", "0.5", "--frames", "1..12", "--exemplar", "none", "--style", "dress=blue-bloom"];
    let rendered = tmp.join("render");
    assert_success(&bin().arg("render").arg(&d).arg("-o").arg(&rendered).args(opts).output().unwrap());
    let out = tmp.join("plan");
    let (_, jobs) = plan(&[&d], &out, &opts);
    let (layer, composite) = (&jobs[0], &jobs[1]);
    let dir = out.join("layers/04_dress");

    // A complete job whose painted frame was changed afterwards: the composite refuses it
    // before writing anything, and the job, run again, paints the layer anew instead of
    // finding it complete.
    assert_success(&run_job(layer));
    flip_a_bit(&dir.join("paint/0002.png"));
    let o = run_job(composite);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("0002.png") && err.contains("changed") && err.contains("render-layer job again"), "{err}");
    assert!(results(&out).is_empty(), "the refused composite wrote {:?}", tree(&out));
    let o = run_job(layer);
    assert_success(&o);
    let err = stderr(&o);
    assert!(err.contains("painting it again") && err.contains("12 frames painted in"), "{err}");
    assert_success(&run_job(composite));
    assert_same_results(&out, &rendered);

    // An interrupted job whose checkpoint was edited, or whose painted frame was damaged, is
    // not continued from there: it starts over with a warning and still gives the bytes of
    // render.
    type Damage = fn(&Path);
    let damages: [(&str, Damage); 2] = [
        ("the checkpoint is unusable", |dir| {
            let p = dir.join(".fluidymation/progress.toml");
            let text = std::fs::read_to_string(&p).unwrap();
            let text: String = text
                .lines()
                .map(|l| if l.starts_with("done") { "done = 1\n".into() } else { format!("{l}\n") })
                .collect();
            std::fs::write(&p, text).unwrap();
        }),
        ("painting the layer again from its first frame", |dir| flip_a_bit(&dir.join("paint/0001.png"))),
    ];
    for (warning, damage) in damages {
        std::fs::remove_dir_all(&out).unwrap();
        kill_after_three_frames(layer, &dir);
        damage(&dir);
        let o = run_job(layer);
        assert_success(&o);
        let err = stderr(&o);
        assert!(err.contains(warning) && err.contains("12 frames painted in"), "{warning}: {err}");
        assert_success(&run_job(composite));
        assert_same_results(&out, &rendered);
    }
}

#[test]
fn frames_left_by_an_earlier_longer_render_are_pointed_out_single_and_batch() {
    let tmp = Scratch::new("stale");
    let (quads, demo) = (quads(), demo());
    // One input, then a batch of two: render 4 frames, then 2 into the same place.
    let single = tmp.join("single");
    let batch = tmp.join("batch");
    for frames in ["1..4", "1..2"] {
        let quick = ["--scale", "0.25", "--frames", frames];
        let mut one = vec![os("render"), quads.as_os_str(), os("-o"), single.as_os_str()];
        one.extend(quick.iter().map(os));
        let o1 = run(&one);
        assert_success(&o1);
        let mut two = vec![os("render"), quads.as_os_str(), demo.as_os_str(), os("-o"), batch.as_os_str()];
        two.extend(quick.iter().map(os));
        let o2 = run(&two);
        assert_success(&o2);
        let stale = |o: &Output, dir: &Path| {
            stderr(o).lines().any(|l| {
                l.contains(&format!("'{}'", dir.display()))
                    && l.contains("2 frame(s) from an earlier render (0003.png–0004.png)")
                    && l.contains("(1–2)")
            })
        };
        // Nothing to say after the first run; after the second each folder is named.
        let second = frames == "1..2";
        assert_eq!(stale(&o1, &single), second, "{}", stderr(&o1));
        for name in ["quads", "waving"] {
            assert_eq!(stale(&o2, &batch.join(name)), second, "{name}: {}", stderr(&o2));
        }
    }
    // The frames are kept (they may be wanted).
    assert!(single.join("0004.png").is_file() && batch.join("waving/0004.png").is_file());
}
