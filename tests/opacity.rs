//! Layers at partial opacity — a fill's or a layer's, animated or not — are painted with the
//! shape they have and laid over what is below with their opacity, as their flat rendering is:
//! a fade-in is painted from its first visible frame and grows in strength smoothly, instead of
//! appearing at full strength when its alpha passes ½.

use fluidymation::NoProgress;
use fluidymation::anim::{self, Animation};
use fluidymation::img::{self, Plane, Rgb};
use fluidymation::render::{self, RenderOptions};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("fm-opacity-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A 200 × 200 Lottie file: one square (120 px, centred), violet, whose layer opacity goes
/// from 0 to 100 % over its 10 frames.
fn fade(dir: &Path) -> Animation {
    let json = r#"{"v": "5.5.2", "fr": 30, "ip": 0, "op": 10, "w": 200, "h": 200, "nm": "t", "ddd": 0, "assets": [],
      "layers": [{"ddd": 0, "ind": 1, "ty": 4, "nm": "box", "sr": 1, "ao": 0, "ip": 0, "op": 10, "st": 0, "bm": 0,
        "ks": {"o": {"a": 1, "k": [{"t": 0, "s": [0], "i": {"x": [1], "y": [1]}, "o": {"x": [0], "y": [0]}}, {"t": 9, "s": [100]}]},
               "r": {"a": 0, "k": 0}, "p": {"a": 0, "k": [0, 0, 0]}, "a": {"a": 0, "k": [0, 0, 0]}, "s": {"a": 0, "k": [100, 100, 100]}},
        "shapes": [{"ty": "gr", "nm": "G", "it": [
          {"ty": "rc", "nm": "R", "p": {"a": 0, "k": [100, 100]}, "s": {"a": 0, "k": [120, 120]}, "r": {"a": 0, "k": 0}, "d": 1},
          {"ty": "fl", "nm": "F", "c": {"a": 0, "k": [0.25, 0, 1, 1]}, "o": {"a": 0, "k": 100}, "r": 1},
          {"ty": "tr", "p": {"a": 0, "k": [0, 0]}, "a": {"a": 0, "k": [0, 0]}, "s": {"a": 0, "k": [100, 100]}, "r": {"a": 0, "k": 0}, "o": {"a": 0, "k": 100}}]}]}]}"#;
    let path = dir.join("fade.json");
    std::fs::write(&path, json).unwrap();
    anim::load(&path, &Default::default()).unwrap()
}

fn render_all(a: &Animation, out: &Path, style: &str) -> Vec<Plane<Rgb>> {
    let mut opts = RenderOptions::new(out.to_path_buf(), 0..a.frames);
    opts.default_style = Some(style.into());
    render::render(a, &opts, &NoProgress).unwrap();
    (0..a.frames).map(|k| img::load_rgb(&out.join(format!("{:04}.png", k + 1))).unwrap()).collect()
}

/// Mean luminance-like value (mean of R, G, B) over the square's inner 80 × 80 px.
fn inner_mean(p: &Plane<Rgb>) -> f32 {
    let mut s = 0.0;
    for y in 60..140 {
        for x in 60..140 {
            let c = p.get(x, y);
            s += (c[0] + c[1] + c[2]) / 3.0;
        }
    }
    s / 6400.0
}

/// Measured (blue-bloom, seed 1): the painted square's inner mean (of R, G, B in sRGB) follows
/// the flat one within 0.003–0.052 over the fade (frames 2–9, opacity 11–89 %; at 100 % the
/// paint is its own look, 0.126 lighter than flat: texture, blooms, and the square's green at 0
/// floored, `TINT_FLOOR`) and falls at every frame; its texture in linear light is 0.96–1.00 of
/// the full layer's per unit of opacity. Floors: within opacity × the full layer's difference,
/// plus 0.01 (0.024–0.122), strictly falling, texture > 0.6 (0.8 until the interior's paint
/// aged, `ParamsBuilder::aging`, 2026-12-05: the texture is measured against the last frame's,
/// and the paint now dries on from frame to frame, so its texture per unit of opacity rises
/// with the frames, 0.78, 0.79, 0.82, 0.86, 0.89, 0.93, 0.96, 0.98 over frames 2–9; flat
/// paint would read 0). Before (measured with the previous
/// build on the same file), the square was absent at frames 2–3 (0.033 and 0.068 from flat) and
/// at full strength from frame 4 on (0.428 from flat there), the same at every frame after.
#[test]
fn a_fading_layer_is_painted_with_its_opacity() {
    let dir = scratch("fade");
    let a = fade(&dir);
    // The engine's mask: the shape at any opacity above 0.
    let rf = a.render(0, 3).unwrap();
    let alpha = rf.fill.get(100, 100)[3];
    assert!(alpha > 0.2 && alpha < 0.5, "frame 4's opacity {alpha}");
    let cov = rf.coverage();
    assert_eq!(cov.get(100, 100), 1.0);
    assert_eq!(cov.threshold(0.5).count(), a.render(0, 9).unwrap().coverage().threshold(0.5).count());

    let painted = render_all(&a, &dir.join("painted"), "blue-bloom");
    let flat = render_all(&a, &dir.join("flat"), "none");
    let means: Vec<(f32, f32)> = painted.iter().zip(&flat).map(|(p, f)| (inner_mean(p), inner_mean(f))).collect();
    // At full opacity the paint differs from flat by its own look (its texture, lighter
    // blooms, its pure channel floored); at opacity o by about o times that.
    let gap = (means[9].0 - means[9].1).abs();
    for k in 1..9 {
        let (p, f) = means[k];
        let o = a.render(0, k).unwrap().fill.get(100, 100)[3];
        eprintln!("frame {}: opacity {o:.2}, inner mean painted {p:.3}, flat {f:.3} (at 100 %: {gap:.3})", k + 1);
        assert!((p - f).abs() <= o * gap + 0.01, "frame {}: painted {p:.3}, flat {f:.3}", k + 1);
        assert!(p < means[k - 1].0, "frame {}: not darker than the frame before ({:?})", k + 1, means);
    }
    // Painted, not flat: the square has the paint's texture from its first visible frame on,
    // in proportion to its opacity (in linear light, where the layer is blended).
    let linear = |v: f32| if v <= 0.04045 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) };
    let sigma = |p: &Plane<Rgb>| {
        let v: Vec<f32> =
            (60..140).flat_map(|y| (60..140).map(move |x| (x, y))).map(|(x, y)| linear(p.get(x, y)[0])).collect();
        let m = v.iter().sum::<f32>() / v.len() as f32;
        (v.iter().map(|x| (x - m).powi(2)).sum::<f32>() / v.len() as f32).sqrt()
    };
    let full = sigma(&painted[9]);
    let mut thin = Vec::new();
    for (k, frame) in painted.iter().enumerate().take(9).skip(1) {
        let o = a.render(0, k).unwrap().fill.get(100, 100)[3];
        let relative = sigma(frame) / o / full;
        eprintln!("frame {}: opacity {o:.2}, texture {relative:.2} of the full layer's per unit opacity", k + 1);
        if relative <= 0.6 {
            thin.push(format!("frame {}: texture {relative:.2} of the full layer's, opacity {o:.2}", k + 1));
        }
    }
    assert!(thin.is_empty(), "{thin:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A mask sequence's gray is coverage, not opacity: a soft edge (a ramp over 12 px) stays where
/// the mask puts it — the engine's mask is its gray at ½ — and is not widened as an opacity
/// would be (the alpha over its neighbourhood's largest put the edge 2 px from the ramp's
/// foot, 4 px further out here).
#[test]
fn a_mask_sequence_keeps_its_soft_edges() {
    let dir = scratch("soft");
    let masks = dir.join("masks");
    std::fs::create_dir_all(&masks).unwrap();
    let soft = image::GrayImage::from_fn(64, 64, |x, _| {
        image::Luma([((x as f32 - 20.0) / 12.0 * 255.0).clamp(0.0, 255.0).round() as u8])
    });
    for k in 1..=2 {
        soft.save(masks.join(format!("{k:04}.png"))).unwrap();
    }
    let a = anim::load(&masks, &Default::default()).unwrap();
    let cov = a.render(0, 0).unwrap().coverage();
    for x in 0..64 {
        let want = soft.get_pixel(x as u32, 10)[0] as f32 / 255.0;
        assert!((cov.get(x, 10) - want).abs() < 1e-3, "x {x}: coverage {} for gray {want}", cov.get(x, 10));
    }
    // The ½ crossing is mid-ramp (x = 26), where the gray says.
    assert!(cov.get(25, 10) < 0.5 && cov.get(27, 10) > 0.5);
    std::fs::remove_dir_all(&dir).unwrap();
}
