//! The library checks what a program hands it: exemplars whose frames and masks disagree and
//! guides whose channels have other sizes give the library's `Error`, never a panic or
//! garbage.

use fluidymation::Error;
use fluidymation::exemplar::{Exemplar, ExemplarMeta};
use fluidymation::guide::{self, FrameGuides, GuideParams};
use fluidymation::img::Plane;
use fluidymation::synth::{Params, Source, Synthesizer};

fn disc(w: usize, h: usize, r: f32) -> Plane<f32> {
    Plane::from_fn(w, h, |x, y| {
        let (dx, dy) = (x as f32 - w as f32 / 2.0, y as f32 - h as f32 / 2.0);
        if dx * dx + dy * dy < r * r { 1.0 } else { 0.0 }
    })
}

fn meta() -> ExemplarMeta {
    toml::from_str("name = \"hand-built\"\npaper = \"#ffffff\"").unwrap()
}

/// A valid hand-built exemplar: a growing blue disc, 3 frames of 40×40.
fn exemplar() -> Exemplar {
    let masks: Vec<Plane<f32>> = (0..3).map(|k| disc(40, 40, 8.0 + 3.0 * k as f32)).collect();
    let frames = masks.iter().map(|m| m.map(|v| [1.0 - 0.6 * v, 1.0 - 0.3 * v, 1.0])).collect();
    Exemplar { dir: None, meta: meta(), frames, masks }
}

#[track_caller]
fn refused(ex: &Exemplar, needle: &str) {
    let params = Params::builder().build().unwrap();
    let e = Source::prepare(ex, &params).expect_err("a malformed exemplar was prepared");
    assert!(matches!(e, Error::Exemplar { .. }), "{e:?}");
    assert!(e.to_string().contains(needle), "'{needle}' not in: {e}");
}

#[test]
fn exemplars_whose_frames_and_masks_disagree_are_errors() {
    let params = Params::builder().build().unwrap();
    assert!(Source::prepare(&exemplar(), &params).is_ok());

    let mut ex = exemplar();
    ex.masks.pop();
    refused(&ex, "3 frames, 2 masks");
    let mut ex = exemplar();
    ex.frames.truncate(1);
    refused(&ex, "one mask per frame (1 frames, 3 masks)");
    // One frame with its mask is a still exemplar.
    let mut ex = exemplar();
    ex.frames.truncate(1);
    ex.masks.truncate(1);
    assert_eq!(Source::prepare(&ex, &params).unwrap().frames(), 1);
    let mut ex = exemplar();
    ex.masks[1] = disc(30, 40, 8.0);
    refused(&ex, "frame 2 is not 40x40");
    let mut ex = exemplar();
    ex.frames[2] = Plane::filled(40, 41, [1.0; 3]);
    refused(&ex, "frame 3 is not 40x40");
    let mut ex = exemplar();
    ex.masks[0] = Plane::new(40, 40);
    refused(&ex, "mask 1 is empty");
    let mut ex = exemplar();
    ex.meta.scale = f32::NAN;
    refused(&ex, "'scale'");
}

fn target(k: usize) -> Vec<FrameGuides> {
    let masks: Vec<Plane<f32>> = (0..k).map(|i| disc(48, 40, 10.0 + i as f32)).collect();
    guide::compute_sequence(&masks, &GuideParams::default()).unwrap()
}

#[test]
fn guides_of_the_wrong_size_are_errors() {
    let params = Params::builder().build().unwrap();
    let source = Source::prepare(&exemplar(), &params).unwrap();
    let mut s = Synthesizer::new(source, params.clone()).unwrap();
    let mut g = target(2);
    // One channel smaller than the mask.
    let mut bad = g[0].clone();
    bad.ext_pos = Plane::new(24, 20);
    let e = s.step(&bad).unwrap_err().to_string();
    assert!(e.contains("target guides") && e.contains("ext_pos 24x20"), "{e}");
    bad = g[0].clone();
    bad.flow = Plane::new(48, 41);
    assert!(s.step(&bad).unwrap_err().to_string().contains("flow 48x41"));
    // Nothing was consumed: the valid frames still follow.
    assert_eq!(s.frame(), 0);
    s.step(&g[0]).unwrap();
    // A frame of another size than the first.
    g[1] = target(1).remove(0);
    g[1].mask = Plane::new(40, 40);
    assert!(s.step(&g[1]).is_err());

    // Exemplar guides that do not fit their frames.
    let frames: Vec<_> = exemplar().frames;
    let masks: Vec<Plane<f32>> = exemplar().masks;
    let mut guides = guide::compute_sequence(&masks, &GuideParams::default()).unwrap();
    assert!(Source::from_parts(&frames, &guides, &params, 4.0).is_ok());
    guides[1].dist = Plane::new(40, 39);
    let e = Source::from_parts(&frames, &guides, &params, 4.0).unwrap_err().to_string();
    assert!(e.contains("exemplar guides") && e.contains("dist 40x39"), "{e}");
    let mut guides = guide::compute_sequence(&masks, &GuideParams::default()).unwrap();
    guides[2] =
        guide::compute_sequence(&[disc(40, 44, 9.0), disc(40, 44, 9.0)], &GuideParams::default()).unwrap()[0].clone();
    let e = Source::from_parts(&frames, &guides, &params, 4.0).unwrap_err().to_string();
    assert!(e.contains("frame 3") && e.contains("guides 40x44"), "{e}");
}
