//! `fluidymation eval` run as a user runs it: files on disk, the binary spawned.

mod eval_support;

use eval_support::*;
use fluidymation::img;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const FRAMES: usize = 6;
const SIZE: usize = 64;

/// A scratch folder with an exemplar, stylized frames and target masks.
struct Scene {
    root: PathBuf,
}

impl Scene {
    fn new(name: &str) -> Scene {
        let root = std::env::temp_dir().join(format!("fm-eval-cli-{}-{}", name, std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let b = Bloom { size: SIZE, frames: FRAMES };
        for d in ["ex/frames", "ex/masks", "out", "masks"] {
            std::fs::create_dir_all(root.join(d)).unwrap();
        }
        std::fs::write(root.join("ex/exemplar.toml"), "name = \"cli-bloom\"\npaper = \"#f5f0e6\"\n").unwrap();
        for t in 0..FRAMES {
            let file = format!("{:04}.png", t + 1);
            img::save_rgb(&root.join("ex/frames").join(&file), &b.frame(t)).unwrap();
            img::save_gray(&root.join("ex/masks").join(&file), &b.mask(t)).unwrap();
            img::save_rgba(&root.join("out").join(&file), &with_alpha(&b.field(t), &b.mask(t))).unwrap();
            img::save_gray(&root.join("masks").join(&file), &b.mask(t)).unwrap();
        }
        Scene { root }
    }

    fn path(&self, p: &str) -> PathBuf {
        self.root.join(p)
    }

    fn run(&self, extra: &[&str]) -> Output {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_fluidymation"));
        cmd.arg("eval").arg(self.path("out")).arg("--exemplar").arg(self.path("ex"));
        cmd.arg("--masks").arg(self.path("masks")).args(extra);
        cmd.output().unwrap()
    }
}

impl Drop for Scene {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.root);
    }
}

fn text(o: &Output) -> (String, String) {
    (String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned())
}

fn fails_with(o: &Output, needles: &[&str]) {
    let (_, err) = text(o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.starts_with("error: "), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "missing '{n}' in: {err}");
    }
}

#[test]
fn prints_a_table_json_and_a_chart() {
    let s = Scene::new("ok");
    let o = s.run(&["--per-frame"]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(out.contains("exemplar 'cli-bloom'"), "{out}");
    assert!(out.contains("coverage IoU") && out.contains("1.0000"), "{out}");
    assert!(out.contains("temporal change (stationary interior)"), "{out}");
    assert!(out.contains("edge darkening") && out.contains("incoherent change"), "{out}");
    let table = out.split_once("frame      IoU").expect("per-frame table").1;
    assert_eq!(table.lines().filter(|l| l.trim_start().starts_with(|c: char| c.is_ascii_digit())).count(), FRAMES);

    let chart = s.path("chart.png");
    let o = s.run(&["--json", "--plot", chart.to_str().unwrap()]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    // The exemplar's frames evaluated against the exemplar (through 8-bit PNGs).
    assert_eq!(v["summary"]["coverage_iou"], 1.0);
    assert!((v["summary"]["contrast_ratio"].as_f64().unwrap() - 1.0).abs() < 0.01, "{}", v["summary"]);
    assert!(v["summary"]["palette_distance_mean"].as_f64().unwrap() < 0.005);
    for ratio in ["edge_darkening_ratio", "incoherent_change_ratio"] {
        assert!((v["summary"][ratio].as_f64().unwrap() - 1.0).abs() < 0.05, "{ratio}: {}", v["summary"]);
    }
    assert!(v["per_frame"][1]["incoherent_change"].is_number());
    // The rim's distances are flags.
    let o2 = s.run(&["--json", "--rim-band", "3", "--rim-interior", "9"]);
    let (out2, err2) = text(&o2);
    assert!(o2.status.success(), "{err2}");
    let narrow: serde_json::Value = serde_json::from_str(&out2).unwrap();
    assert_eq!(narrow["options"]["rim"]["band"], 3.0);
    assert_ne!(narrow["summary"]["edge_darkening"], v["summary"]["edge_darkening"]);
    assert_eq!(v["per_frame"].as_array().unwrap().len(), FRAMES);
    assert!(v["per_frame"][0]["temporal_change"].is_null());
    assert_eq!(v["painted"], "alpha");
    let png = img::load_rgba(&chart).unwrap();
    assert_eq!(png.width(), 960);
    assert!(err.contains("chart written"), "{err}");
}

#[test]
fn opaque_frames_use_the_background() {
    let s = Scene::new("opaque");
    let b = Bloom { size: SIZE, frames: FRAMES };
    for t in 0..FRAMES {
        let f = composited(&b.field(t), &b.mask(t), [1.0, 1.0, 1.0]);
        img::save_rgba(&s.path("out").join(format!("{:04}.png", t + 1)), &f).unwrap();
    }
    // A name, as `render --background` takes it.
    let o = s.run(&["--json", "--background", "white"]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["painted"]["color"]["background"], serde_json::json!([1.0, 1.0, 1.0]));
    // Antialiased edge pixels of coverage < 0.5 differ from white by more than 0.1 too.
    assert!(v["summary"]["coverage_iou"].as_f64().unwrap() > 0.95, "{}", v["summary"]);
    assert_eq!(v["summary"]["palette_distance_mean"], 0.0);
}

#[test]
fn clear_errors_and_exit_code_1() {
    let s = Scene::new("errors");
    // A missing output directory.
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_fluidymation"));
    let o = cmd.args(["eval", "/nonexistent/out", "--exemplar"]).arg(s.path("ex")).arg("--masks").arg(s.path("masks"));
    fails_with(&o.output().unwrap(), &["could not read the stylized frames in '/nonexistent/out'"]);
    // An exemplar that is not a folder.
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_fluidymation"));
    let o = cmd.arg("eval").arg(s.path("out")).args(["--exemplar", "no-such-exemplar", "--masks"]).arg(s.path("masks"));
    fails_with(&o.output().unwrap(), &["no exemplar named 'no-such-exemplar'"]);
    // A bad option.
    fails_with(&s.run(&["--background", "paper"]), &["--background 'paper': expected an opaque color, #rrggbb"]);
    fails_with(&s.run(&["--background", "#ff000080"]), &["--background '#ff000080': expected an opaque color"]);
    // A chart that cannot be written: said before the measuring.
    std::fs::write(s.path("a-file"), b"").unwrap();
    let chart = s.path("a-file/chart.png");
    fails_with(&s.run(&["--plot", chart.to_str().unwrap()]), &["--plot: cannot write the chart there"]);
    fails_with(&s.run(&["--interior-margin=-1"]), &["--interior-margin"]);
    fails_with(
        &s.run(&["--rim-band", "5", "--rim-interior", "4"]),
        &["--rim-interior", "a distance >= the band (5 px)"],
    );
    // A mask of another size, named.
    img::save_gray(&s.path("masks/0003.png"), &fluidymation::img::Plane::filled(60, SIZE, 1.0)).unwrap();
    fails_with(&s.run(&[]), &["0003.png", "is 60x64", "0001.png", "is 64x64"]);
    // One mask missing: the counts and the frame without a mask are named.
    std::fs::remove_file(s.path("masks/0006.png")).unwrap();
    fails_with(&s.run(&[]), &["holds 6 frames", "holds 5 masks", "0006.png' has no mask"]);
    // A broken exemplar.
    std::fs::remove_file(s.path("ex/exemplar.toml")).unwrap();
    img::save_gray(&s.path("masks/0006.png"), &Bloom { size: SIZE, frames: FRAMES }.mask(5)).unwrap();
    img::save_gray(&s.path("masks/0003.png"), &Bloom { size: SIZE, frames: FRAMES }.mask(2)).unwrap();
    fails_with(&s.run(&[]), &["could not load exemplar", "exemplar.toml"]);
    assert!(Path::new(&s.path("out/0001.png")).exists());
}

#[test]
fn masks_of_something_else_are_warned_about() {
    let s = Scene::new("other-masks");
    // The masks moved far off the paint: the measures would read paper.
    let b = Bloom { size: SIZE, frames: FRAMES };
    for t in 0..FRAMES {
        let m = b.mask(t);
        let off =
            fluidymation::img::Plane::from_fn(SIZE, SIZE, |x, y| m.get((x + SIZE / 2) % SIZE, (y + SIZE / 2) % SIZE));
        img::save_gray(&s.path("masks").join(format!("{:04}.png", t + 1)), &off).unwrap();
    }
    let o = s.run(&[]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("hardly lies inside the masks of") && err.contains("are these the masks of this output?"),
        "{err}"
    );
    assert!(!out.contains("NaN"), "{out}");
    // The right masks: no warning.
    let ok = Scene::new("own-masks").run(&[]);
    assert!(!text(&ok).1.contains("hardly lies inside"), "{}", text(&ok).1);
}
