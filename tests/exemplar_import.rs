//! Importing footage, tested on frames rendered by the generator (where the masks are known).

use fluidymation::NoProgress;
use fluidymation::exemplar::generate::{GeneratorParams, Pigment, generate};
use fluidymation::exemplar::import::{ImportOptions, import, iou};
use fluidymation::exemplar::parse_hex_color;

fn check(params: GeneratorParams, min_iou: f32) {
    let truth = generate(&params, "truth", &NoProgress).unwrap();
    let dir = std::env::temp_dir().join(format!("fm-import-{}-{}", params.pigment, std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (i, f) in truth.frames.iter().enumerate() {
        fluidymation::img::save_rgb(&dir.join(format!("shot_{}.png", i + 1)), f).unwrap();
    }
    let opts = ImportOptions::default().name("imported");
    let ex = import(&dir, &opts, &NoProgress).unwrap();
    assert_eq!(ex.len(), truth.len());
    let ious: Vec<f32> = ex.masks.iter().zip(&truth.masks).map(|(a, b)| iou(a, b)).collect();
    let areas: Vec<(usize, usize)> = ex
        .masks
        .iter()
        .zip(&truth.masks)
        .map(|(a, b)| (a.data().iter().filter(|&&v| v >= 0.5).count(), b.data().iter().filter(|&&v| v >= 0.5).count()))
        .collect();
    eprintln!("areas (imported, truth): {areas:?}");
    let mean = ious.iter().sum::<f32>() / ious.len() as f32;
    let worst = ious.iter().copied().fold(1.0, f32::min);
    eprintln!("{}: import mask IoU mean {mean:.3}, worst {worst:.3}", params.pigment);
    assert!(mean >= min_iou && worst >= min_iou - 0.1, "{}: IoU mean {mean}, worst {worst} ({ious:?})", params.pigment);
    let (p, q) = (parse_hex_color(&ex.meta.paper).unwrap(), truth.paper());
    assert!((0..3).all(|i| (p[i] - q[i]).abs() < 0.03), "paper {:?} vs {:?}", p, q);
    // Crop and scale.
    let opts = opts.crop([10, 10, 100, 90]).scale(0.5);
    let small = import(&dir, &opts, &NoProgress).unwrap();
    assert_eq!((small.width(), small.height()), (50, 45));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn import_recovers_generated_masks() {
    let base = GeneratorParams::default().size(120, 120).frames(8).seed(5);
    check(base.clone().pigment(Pigment::Blue), 0.95);
    check(base.clone().pigment(Pigment::Rose).rim(0.5).bloom(1.5), 0.95);
    check(base.pigment(Pigment::Yellow).granulation(2.0), 0.95);
}

#[test]
fn import_errors_are_clear() {
    let dir = std::env::temp_dir().join(format!("fm-import-err-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let blank = fluidymation::img::Plane::filled(40, 40, [0.95f32, 0.94, 0.9]);
    fluidymation::img::save_rgb(&dir.join("a1.png"), &blank).unwrap();
    // One frame is a still; blank paper has no paint in it, and the error names the file.
    let e = import(&dir, &ImportOptions::default(), &NoProgress).unwrap_err().to_string();
    assert!(e.contains("a1.png") && e.contains("no paint found"), "{e}");
    let e = import(&dir.join("a1.png"), &ImportOptions::default(), &NoProgress).unwrap_err().to_string();
    assert!(e.contains("a1.png") && e.contains("no paint found"), "{e}");
    fluidymation::img::save_rgb(&dir.join("a2.png"), &blank).unwrap();
    let e = import(&dir, &ImportOptions::default(), &NoProgress).unwrap_err().to_string();
    assert!(e.contains("a1.png") && e.contains("no paint found"), "{e}");
    let opts = ImportOptions::default().crop([30, 30, 20, 20]);
    let e = import(&dir, &opts, &NoProgress).unwrap_err().to_string();
    assert!(e.contains("crop") && e.contains("40x40"), "{e}");
    let opts = ImportOptions::default().name("../evil");
    assert!(import(&dir, &opts, &NoProgress).is_err());
    // Paint to every edge, no paper: refused (it took the paint for paper and made noise).
    let wash = fluidymation::img::Plane::from_fn(40, 40, |x, y| {
        let n = ((x * 7 + y * 13) % 5) as f32 * 0.01;
        [0.19 + n, 0.27 + n, 0.54 + n]
    });
    let full = dir.join("wash.png");
    fluidymation::img::save_rgb(&full, &wash).unwrap();
    let e = import(&full, &ImportOptions::default(), &NoProgress).unwrap_err().to_string();
    assert!(e.contains("wash.png") && e.contains("paper") && e.contains("--crop"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}
