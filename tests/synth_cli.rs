//! `synth` and `bench --save-workload` end to end, spawning the binary: the workload written to
//! disk is what `synth` reads, the frames asked for are the frames written, their alpha is the
//! target's mask, the summary says where the time went, and a missing input is an error that
//! names it.

mod cli_support;

use cli_support::{run, stderr};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    cli_support::scratch("synth-cli", name)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn saved_workload_is_synthesized_frame_by_frame() {
    let dir = scratch("workload");
    let o = run(&["bench", "--frames", "4", "--size", "200x160", "--save-workload", s(&dir)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let masks = dir.join("masks");
    let names: Vec<String> = {
        let mut v: Vec<String> =
            std::fs::read_dir(&masks).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    };
    assert_eq!(names, ["0001.png", "0002.png", "0003.png", "0004.png"]);
    assert!(dir.join("exemplar/exemplar.toml").is_file());

    let out = dir.join("out");
    let o = run(&[
        "synth",
        "--exemplar",
        s(&dir.join("exemplar")),
        "--masks",
        s(&masks),
        "-o",
        s(&out),
        "--frames",
        "2..3",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut written: Vec<String> =
        std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    written.sort();
    assert_eq!(written, ["0002.png", "0003.png"], "only the frames asked for, no temporary left");
    // The alpha is the target's mask (anti-aliased edge pixels aside), and inside it the paint
    // is not the paper: the exemplar's paint.
    let frame = image::open(out.join("0003.png")).unwrap().to_rgba8();
    let mask = image::open(masks.join("0003.png")).unwrap().to_luma8();
    assert_eq!(frame.dimensions(), (200, 160));
    let (mut agree, mut inside, mut painted) = (0, 0, 0);
    for (p, m) in frame.pixels().zip(mask.pixels()) {
        let want = m[0] >= 128;
        agree += ((p[3] == 255) == want) as usize;
        if want {
            inside += 1;
            painted += (p[0].min(p[1]).min(p[2]) < 200) as usize;
        }
    }
    assert!(agree as f64 >= 0.99 * 200.0 * 160.0, "alpha agrees with the mask on {agree} pixels");
    assert!(inside > 500 && painted as f64 >= 0.5 * inside as f64, "{painted} of {inside} mask pixels painted");
    let err = stderr(&o);
    for phase in ["reading the masks", "preparing the exemplar", "target guides", "synthesis", "writing"] {
        assert!(err.contains(phase), "the summary names '{phase}': {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn synth_names_a_missing_input() {
    let dir = scratch("missing");
    let nowhere = dir.join("no-such-masks");
    let o = run(&["synth", "--exemplar", "blue-bloom", "--masks", s(&nowhere), "-o", s(&dir.join("out"))]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("no-such-masks"), "{}", stderr(&o));
    let masks = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("exemplars/blue-bloom/masks");
    let o = run(&["synth", "-e", "blue-bloom", "--masks", s(&masks), "-o", s(&dir.join("out")), "--target-scale", "0"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("invalid value '0' for '--target-scale <F>'"), "{}", stderr(&o));
    assert!(!dir.join("out").join("0001.png").exists(), "nothing written before the error");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `synth --keyframe`: no exemplar needed; the keyframe's frame is the painting, every frame is
/// written; a painting of the wrong size or a malformed value is an error that names it.
#[test]
fn synth_paints_from_a_keyframe() {
    let dir = scratch("keyframe");
    let o = run(&["bench", "--frames", "4", "--size", "160x128", "--save-workload", s(&dir)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let masks = dir.join("masks");
    // The painting of frame 2: a striped paint over the whole frame (only its mask's part counts).
    let painting = image::RgbImage::from_fn(160, 128, |x, y| {
        let v = if (x / 3 + y / 5) % 2 == 0 { 60 } else { 200 };
        image::Rgb([v, 90, 255 - v])
    });
    let key = dir.join("key.png");
    painting.save(&key).unwrap();
    let out = dir.join("out");
    let keyframe = format!("2={}", s(&key));
    let o = run(&["synth", "--masks", s(&masks), "--keyframe", &keyframe, "-o", s(&out), "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let frame2 = image::open(out.join("0002.png")).unwrap().into_rgba8();
    let mask2 = image::open(masks.join("0002.png")).unwrap().into_luma8();
    let mut inside = 0;
    for (x, y, p) in frame2.enumerate_pixels() {
        if mask2.get_pixel(x, y)[0] > 200 && p[3] == 255 {
            assert_eq!(&p.0[..3], &painting.get_pixel(x, y).0[..], "({x}, {y})");
            inside += 1;
        }
    }
    assert!(inside > 500, "{inside} painted pixels");
    for k in 1..=4 {
        assert!(out.join(format!("{k:04}.png")).is_file(), "frame {k}");
    }
    // Errors name what is wrong.
    image::RgbImage::new(20, 20).save(dir.join("small.png")).unwrap();
    let small = format!("2={}", s(&dir.join("small.png")));
    let o = run(&["synth", "--masks", s(&masks), "--keyframe", &small, "-o", s(&out)]);
    assert!(
        !o.status.success() && stderr(&o).contains("small.png") && stderr(&o).contains("160x128"),
        "{}",
        stderr(&o)
    );
    let o = run(&["synth", "--masks", s(&masks), "--keyframe", "nine=key.png", "-o", s(&out)]);
    assert!(!o.status.success() && stderr(&o).contains("nine=key.png"), "{}", stderr(&o));
    let o = run(&["synth", "--masks", s(&masks), "-o", s(&out)]);
    assert!(!o.status.success() && stderr(&o).contains("--exemplar"), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A single PNG is a one-frame mask sequence wherever a folder or glob of masks is taken
/// (`synth --masks`, `inspect`, `eval --masks`), as a glob matching that one file is; a file of
/// another kind, one that is not a PNG inside, or none at all is an error naming it.
#[test]
fn a_single_png_is_a_one_frame_mask_sequence() {
    let dir = scratch("one-png");
    let one = dir.join("disc.png");
    image::GrayImage::from_fn(64, 48, |x, y| {
        let (dx, dy) = (x as f32 - 32.0, y as f32 - 24.0);
        image::Luma([if dx * dx + dy * dy < 300.0 { 255 } else { 0 }])
    })
    .save(&one)
    .unwrap();
    let o = run(&["inspect", s(&one)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("64x48 px") && text.contains("1 frame ") && text.contains("disc"), "{text}");
    let out = dir.join("out");
    let o = run(&["synth", "-e", "ink-rims", "--masks", s(&one), "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let frame = image::open(out.join("0001.png")).unwrap();
    assert_eq!((frame.width(), frame.height()), (64, 48));
    assert!(!out.join("0002.png").exists());
    // eval reads the one frame against the one mask (and gets past the listing to the measures).
    let o = run(&["eval", s(&out.join("0001.png")), "-e", "ink-rims", "--masks", s(&one)]);
    assert!(!stderr(&o).contains("could not read"), "{}", stderr(&o));
    // Not a mask: each error names the file and says what is wrong.
    let text_file = dir.join("notes.txt");
    std::fs::write(&text_file, "x").unwrap();
    let fake = dir.join("fake.png");
    std::fs::write(&fake, "not a png").unwrap();
    let missing = dir.join("missing.png");
    for (masks, says) in [
        (&text_file, "unknown input: expected"),
        (&fake, "format could not be determined"),
        (&missing, "no such file or directory"),
    ] {
        let o = run(&["synth", "-e", "ink-rims", "--masks", s(masks), "-o", s(&dir.join("bad"))]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(stderr(&o).contains(s(masks)) && stderr(&o).contains(says), "{}", stderr(&o));
    }
    let o = run(&["eval", s(&out), "-e", "ink-rims", "--masks", s(&text_file)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("notes.txt': is a .txt file, not a sequence"), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&dir);
}
