//! The watercolor generator: determinism, growth, rims, validation.

use fluidymation::NoProgress;
use fluidymation::exemplar::generate::{GeneratorParams, Pigment, generate};

fn small() -> GeneratorParams {
    GeneratorParams::default().size(96, 96).frames(10).seed(11)
}

#[test]
fn same_seed_gives_byte_identical_files() {
    let params = small().pigment(Pigment::Rose);
    let a = generate(&params, "a", &NoProgress).unwrap();
    let b = generate(&params, "a", &NoProgress).unwrap();
    let tmp = std::env::temp_dir().join(format!("fm-gen-det-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    a.save(&tmp.join("one"), false).unwrap();
    // Save the second one from a single-threaded pool: encoding is parallel, bytes must not care.
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    pool.install(|| b.save(&tmp.join("two"), false)).unwrap();
    for sub in ["exemplar.toml", "frames/0001.png", "frames/0010.png", "masks/0007.png"] {
        let x = std::fs::read(tmp.join("one").join(sub)).unwrap();
        let y = std::fs::read(tmp.join("two").join(sub)).unwrap();
        assert_eq!(x, y, "{sub} differs between two runs with the same seed");
    }
    let c = generate(&params.clone().seed(12), "a", &NoProgress).unwrap();
    assert_ne!(a.frames[9], c.frames[9], "another seed should give another exemplar");
    std::fs::remove_dir_all(&tmp).unwrap();
}

fn area(m: &fluidymation::img::Plane<f32>) -> usize {
    m.data().iter().filter(|&&v| v >= 0.5).count()
}

#[test]
fn mask_grows_over_time() {
    for p in [small(), small().bloom(2.0).pigment(Pigment::Yellow), small().drops(3).flow([0.2, 0.0])] {
        let ex = generate(&p, "g", &NoProgress).unwrap();
        let areas: Vec<usize> = ex.masks.iter().map(area).collect();
        assert!(areas.windows(2).all(|w| w[1] + 2 >= w[0]), "mask shrinks: {areas:?}");
        assert!(areas[9] as f32 > 2.0 * areas[0] as f32, "mask barely grows: {areas:?}");
        assert!(areas[9] < 96 * 96 * 3 / 4, "paint floods the frame: {areas:?}");
    }
}

/// Mean optical density (mean over RGB of −ln(I/paper)) of the last frame, in the rim
/// (0–3 px inside the edge) and the interior (deeper than 8 px).
fn rim_and_interior(p: &GeneratorParams) -> (f32, f32) {
    let ex = generate(p, "r", &NoProgress).unwrap();
    let last = ex.len() - 1;
    let dist = fluidymation::guide::sdf(&ex.masks[last].threshold(0.5)).into_vec();
    let paper = ex.paper();
    let (mut rim, mut nr, mut int, mut ni) = (0.0, 0.0, 0.0, 0.0);
    for (i, c) in ex.frames[last].data().iter().enumerate() {
        let od: f32 = (0..3).map(|k| -(c[k].max(1e-3) / paper[k]).ln()).sum::<f32>() / 3.0;
        if dist[i] >= 0.0 && dist[i] < 3.0 {
            rim += od;
            nr += 1.0;
        } else if dist[i] > 8.0 {
            int += od;
            ni += 1.0;
        }
    }
    assert!(nr > 50.0 && ni > 50.0, "too few pixels: rim {nr}, interior {ni}");
    (rim / nr, int / ni)
}

#[test]
fn rims_are_darker_than_the_interior_and_rim_strength_matters() {
    let strong = small().size(128, 128).frames(12).pigment(Pigment::Ink).rim(2.5).drying(0.2);
    let (rim, interior) = rim_and_interior(&strong);
    assert!(rim > 1.3 * interior, "strong rims: rim OD {rim:.3} vs interior {interior:.3}");
    let weak = small().size(128, 128).frames(12).pigment(Pigment::Ink).rim(0.3);
    let (wr, wi) = rim_and_interior(&weak);
    assert!(rim / interior > wr / wi, "rim strength has no effect: {:.2} vs {:.2}", rim / interior, wr / wi);
}

#[test]
fn paper_grain_is_visible_outside_the_paint() {
    let ex = generate(&small(), "p", &NoProgress).unwrap();
    let f = &ex.frames[0];
    let lum: Vec<f32> = f
        .data()
        .iter()
        .zip(ex.masks[9].data())
        .filter(|(_, m)| **m < 0.5)
        .map(|(c, _)| 0.3 * c[0] + 0.6 * c[1] + 0.1 * c[2])
        .collect();
    let mean = lum.iter().sum::<f32>() / lum.len() as f32;
    let sd = (lum.iter().map(|v| (v - mean).powi(2)).sum::<f32>() / lum.len() as f32).sqrt();
    assert!(sd > 0.004 && sd < 0.05, "paper texture standard deviation {sd}");
}

#[test]
fn invalid_parameters_are_errors_naming_value_and_range() {
    for (p, needle) in [
        (GeneratorParams::default().size(0, 0), "16–2048"),
        (GeneratorParams::default().size(100_000, 100_000), "100000x100000"),
        (GeneratorParams::default().frames(1), "frames"),
        (GeneratorParams::default().rim(-1.0), "rim"),
        (GeneratorParams::default().flow([0.9, 0.0]), "flow"),
        (GeneratorParams::default().drops(0), "drops"),
    ] {
        let e = generate(&p, "x", &NoProgress).unwrap_err().to_string();
        assert!(e.contains(needle), "'{e}' should mention '{needle}'");
    }
}

#[test]
fn progress_can_cancel() {
    let cancel = |_: &str, done: usize, _: usize| done < 2;
    let e = generate(&small(), "c", &cancel).unwrap_err();
    assert!(matches!(e, fluidymation::Error::Cancelled));
}
