//! Exemplar folders: writing, loading, validation errors, lookup by name, the bundled set,
//! border-width estimates.

use fluidymation::exemplar::border::estimate_border_width;
use fluidymation::exemplar::generate::{GeneratorParams, generate};
use fluidymation::exemplar::{self, Exemplar, Location, Origin, SearchPath};
use fluidymation::{Error, NoProgress};
use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("fm-exfmt-{}-{}", name, std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn small(name: &str) -> Exemplar {
    generate(&GeneratorParams::default().size(48, 40).frames(4).steps_per_frame(6), name, &NoProgress).unwrap()
}

#[test]
fn save_then_load_roundtrips() {
    let d = tmp("roundtrip");
    let ex = small("tiny");
    ex.save(&d.join("tiny"), false).unwrap();
    let back = Exemplar::load(&d.join("tiny")).unwrap();
    assert_eq!(back.meta, ex.meta);
    assert_eq!((back.width(), back.height(), back.len()), (48, 40, 4));
    for (a, b) in ex.masks.iter().zip(&back.masks) {
        assert_eq!(a, b);
    }
    let max_err = ex.frames[3]
        .data()
        .iter()
        .zip(back.frames[3].data())
        .flat_map(|(a, b)| (0..3).map(move |i| (a[i] - b[i]).abs()))
        .fold(0.0f32, f32::max);
    assert!(max_err <= 0.5 / 255.0 + 1e-6, "8-bit quantization only, got {max_err}");
    // No temporary folders are left behind, and an existing exemplar is not overwritten.
    let names: Vec<String> =
        std::fs::read_dir(&d).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    assert_eq!(names, vec!["tiny".to_string()]);
    let e = ex.save(&d.join("tiny"), false).unwrap_err().to_string();
    assert!(e.contains("already exists"), "{e}");
    ex.save(&d.join("tiny"), true).unwrap();
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
    std::fs::remove_dir_all(&d).unwrap();
}

fn broken(d: &Path, f: impl FnOnce(&Path)) -> String {
    let dir = d.join("ex");
    let _ = std::fs::remove_dir_all(&dir);
    small("ex").save(&dir, false).unwrap();
    f(&dir);
    Exemplar::load(&dir).unwrap_err().to_string()
}

#[test]
fn invalid_folders_give_errors_naming_the_file() {
    let d = tmp("invalid");
    let e = broken(&d, |dir| std::fs::write(dir.join("exemplar.toml"), "name = [").unwrap());
    assert!(e.contains("exemplar.toml") && e.contains("TOML"), "{e}");
    let e = broken(&d, |dir| std::fs::write(dir.join("exemplar.toml"), "name = \"x\"\npaper = \"white\"\n").unwrap());
    assert!(e.contains("paper color 'white'"), "{e}");
    let e = broken(&d, |dir| {
        std::fs::write(dir.join("exemplar.toml"), "name = \"x\"\npaper = \"#ffffff\"\nfps = -3\n").unwrap()
    });
    assert!(e.contains("'fps' is -3"), "{e}");
    let e = broken(&d, |dir| std::fs::remove_file(dir.join("masks/0004.png")).unwrap());
    assert!(e.contains("4 frames but 3 masks"), "{e}");
    let e = broken(&d, |dir| {
        for i in 1..=4 {
            std::fs::remove_file(dir.join(format!("frames/{i:04}.png"))).unwrap();
            std::fs::remove_file(dir.join(format!("masks/{i:04}.png"))).unwrap();
        }
    });
    assert!(e.contains("frames") && e.contains("no png"), "{e}");
    // One frame is a still exemplar, not an error.
    let dir = d.join("ex");
    for i in 2..=4 {
        std::fs::remove_file(dir.join(format!("frames/{i:04}.png"))).ok();
    }
    small("ex").save(&dir, true).unwrap();
    for i in 2..=4 {
        std::fs::remove_file(dir.join(format!("frames/{i:04}.png"))).unwrap();
        std::fs::remove_file(dir.join(format!("masks/{i:04}.png"))).unwrap();
    }
    assert_eq!(Exemplar::load(&dir).unwrap().len(), 1);
    let e = broken(&d, |dir| {
        fluidymation::img::save_gray(&dir.join("masks/0002.png"), &fluidymation::img::Plane::new(48, 40)).unwrap()
    });
    assert!(e.contains("0002.png") && e.contains("empty"), "{e}");
    let e = broken(&d, |dir| {
        fluidymation::img::save_gray(&dir.join("masks/0003.png"), &fluidymation::img::Plane::filled(10, 10, 1.0))
            .unwrap()
    });
    assert!(e.contains("0003.png") && e.contains("10x10"), "{e}");
    let e = broken(&d, |dir| std::fs::write(dir.join("frames/0002.png"), b"not a png").unwrap());
    assert!(e.contains("0002.png"), "{e}");
    let e = Exemplar::load(&d.join("missing")).unwrap_err().to_string();
    assert!(e.contains("missing"), "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn find_by_path_and_by_name_in_order() {
    let d = tmp("find");
    let (a, b) = (d.join("a"), d.join("b"));
    small("same").save(&a.join("same"), false).unwrap();
    small("other").save(&b.join("same"), false).unwrap();
    small("only-b").save(&b.join("only-b"), false).unwrap();
    let sp = SearchPath::new().dir(&a, Origin::Argument).dir(&b, Origin::Environment);
    assert_eq!(exemplar::find("same", &sp).unwrap().dir.unwrap(), a.join("same"));
    assert_eq!(exemplar::find("only-b", &sp).unwrap().meta.name, "only-b");
    let by_path = b.join("same");
    assert_eq!(exemplar::find(by_path.to_str().unwrap(), &sp).unwrap().meta.name, "other");
    match exemplar::find("nope", &sp) {
        Err(Error::UnknownExemplar { name, available }) => {
            assert_eq!(name, "nope");
            assert_eq!(available, vec!["only-b".to_string(), "same".to_string()]);
        }
        other => panic!("expected UnknownExemplar, got {other:?}"),
    }
    let all = exemplar::list(&sp);
    assert_eq!(all.len(), 3);
    assert!(all.iter().any(|i| i.name == "same"
        && i.shadowed
        && i.location == Location::Folder(b.join("same"), Some(Origin::Environment))));
    assert!(all.iter().all(|i| i.size == (48, 40) && i.frames == 4));
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn bundled_set_is_embedded_and_valid() {
    let sp = SearchPath::new().with_bundled(true);
    let all = exemplar::list(&sp);
    assert!(all.len() >= 5, "{} bundled exemplars", all.len());
    assert!(all.iter().any(|i| i.name == exemplar::DEFAULT));
    for info in &all {
        assert_eq!(info.location, Location::Bundled);
        // Videos of 20–40 frames at 200 × 200, and one still (a single, larger image).
        let video = (20..=40).contains(&info.frames) && info.size == (200, 200);
        assert!(video || (info.frames == 1 && info.name == "blue-swatch"), "{info:?}");
    }
    let ex = exemplar::find(exemplar::DEFAULT, &sp).unwrap();
    assert_eq!(ex.meta.name, exemplar::DEFAULT);
    assert!(ex.dir.is_none());
    // The stored border width is what the estimator finds, and it is plausible.
    let est = estimate_border_width(&ex);
    assert_eq!(est.width, ex.meta.border_width);
    assert!((6.0..=20.0).contains(&est.width), "border width {}", est.width);
}

#[test]
fn border_estimate_follows_a_synthetic_rim() {
    // Discs of growing radius whose rim band (5 px) is dark and whose interior is flat.
    let (w, h) = (120, 120);
    let mut ex = small("synthetic");
    ex.frames.clear();
    ex.masks.clear();
    ex.meta.paper = "#ffffff".into();
    for r in [30.0f32, 35.0, 40.0, 45.0, 50.0] {
        let mut s = 1u64;
        let frame = fluidymation::img::Plane::from_fn(w, h, |x, y| {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let noise = ((s >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * 0.04;
            let d = r - (x as f32 - 60.0).hypot(y as f32 - 60.0);
            let v = if d < 0.0 {
                1.0
            } else if d < 5.0 {
                0.35
            } else {
                0.7
            };
            [v + noise; 3]
        });
        let mask = fluidymation::img::Plane::from_fn(w, h, |x, y| {
            if (x as f32 - 60.0).hypot(y as f32 - 60.0) <= r { 1.0 } else { 0.0 }
        });
        ex.frames.push(frame);
        ex.masks.push(mask);
    }
    let est = estimate_border_width(&ex);
    assert!((4.0..=8.0).contains(&est.width), "estimated {} for a 5 px rim", est.width);
}
