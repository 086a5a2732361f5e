//! Recoloring and compositing on synthetic "synthesized" layers whose pigment amount is known.

use super::color::{linear_to_srgb, srgb_to_linear};
use super::recolor::recolor;
use crate::composite::{self, Background, LayerFrame, Pigment, Recolor, StrokeMode, recolor_with};
use crate::img::{Mask, Plane, Rgb, Rgba};

const W: usize = 96;
const H: usize = 96;
/// Exemplar paper, slightly warm white (sRGB).
const PAPER: Rgb = [0.97, 0.96, 0.93];
/// Blue pigment: linear-light optical density per unit amount.
const BLUE: [f32; 3] = [1.5, 0.8, 0.15];

fn hash(x: i64, y: i64, seed: u64) -> f32 {
    let mut h = (x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F) ^ seed;
    h ^= h >> 31;
    h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h ^= h >> 29;
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// Smooth value noise in `0..1`, period `cell` pixels.
fn value_noise(x: f32, y: f32, cell: f32, seed: u64) -> f32 {
    let (fx, fy) = (x / cell, y / cell);
    let (ix, iy) = (fx.floor() as i64, fy.floor() as i64);
    let (tx, ty) = (fx - ix as f32, fy - iy as f32);
    let s = |t: f32| t * t * (3.0 - 2.0 * t);
    let (sx, sy) = (s(tx), s(ty));
    let a = hash(ix, iy, seed) * (1.0 - sx) + hash(ix + 1, iy, seed) * sx;
    let b = hash(ix, iy + 1, seed) * (1.0 - sx) + hash(ix + 1, iy + 1, seed) * sx;
    a * (1.0 - sy) + b * sy
}

/// Pigment amount of a watercolor-like wash inside the disk of radius `r` around `(cx, cy)`:
/// around 1, with soft blooms, a dark rim and granulation; 0 outside.
fn wash_amount(x: usize, y: usize, cx: f32, cy: f32, r: f32) -> f32 {
    let (xf, yf) = (x as f32 + 0.5, y as f32 + 0.5);
    let dist = r - ((xf - cx).powi(2) + (yf - cy).powi(2)).sqrt();
    if dist < 0.0 {
        return 0.0;
    }
    let blooms = 0.7 + 0.6 * value_noise(xf, yf, 14.0, 1);
    let rim = 0.9 * (-dist / 2.5).exp();
    let grain = 0.25 * (hash(x as i64, y as i64, 7) - 0.5);
    (blooms + rim + grain).max(0.0) * (dist / 1.5).min(1.0)
}

/// The exemplar's look of a pigment amount: paper × e^(−a·k), in sRGB.
fn paint(amount: f32, k: [f32; 3]) -> Rgb {
    [0, 1, 2].map(|i| linear_to_srgb(srgb_to_linear(PAPER[i]) * (-amount * k[i]).exp()))
}

/// A synthesized frame of a disk: (rgb in exemplar colors, mask with a 4 px paper margin,
/// pigment amount).
fn disk_frame(cx: f32, cy: f32, r: f32) -> (Plane<Rgb>, Mask, Plane<f32>) {
    let amount = Plane::from_fn(W, H, |x, y| wash_amount(x, y, cx, cy, r));
    let rgb = amount.map(|a| paint(a, BLUE));
    let mask =
        Plane::from_fn(W, H, |x, y| ((x as f32 + 0.5 - cx).powi(2) + (y as f32 + 0.5 - cy).powi(2)).sqrt() <= r + 4.0);
    (rgb, mask, amount)
}

/// Flat rendering of a disk (antialiased coverage), its color given per pixel.
fn flat_disk(cx: f32, cy: f32, r: f32, color: impl Fn(usize, usize) -> Rgb) -> Plane<Rgba> {
    Plane::from_fn(W, H, |x, y| {
        let d = ((x as f32 + 0.5 - cx).powi(2) + (y as f32 + 0.5 - cy).powi(2)).sqrt();
        let a = (r - d + 0.5).clamp(0.0, 1.0);
        let c = color(x, y);
        [c[0], c[1], c[2], a]
    })
}

fn hue_deg(c: [f32; 3]) -> f32 {
    let (r, g, b) = (c[0], c[1], c[2]);
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    let d = max - min;
    if d <= 1e-6 {
        return 0.0;
    }
    let h = if max == r {
        ((g - b) / d).rem_euclid(6.0)
    } else if max == g {
        (b - r) / d + 2.0
    } else {
        (r - g) / d + 4.0
    };
    h * 60.0
}

fn hue_distance(a: f32, b: f32) -> f32 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

fn luminance(c: [f32; 4]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

fn mean_std(v: &[f32]) -> (f32, f32) {
    let n = v.len() as f32;
    let m = v.iter().sum::<f32>() / n;
    (m, (v.iter().map(|x| (x - m).powi(2)).sum::<f32>() / n).sqrt())
}

fn mean_color(p: &Plane<Rgba>, select: impl Fn(usize, usize) -> bool) -> [f32; 3] {
    let mut s = [0.0f64; 3];
    let mut n = 0.0;
    for y in 0..p.height() {
        for x in 0..p.width() {
            if select(x, y) {
                let c = p.get(x, y);
                for i in 0..3 {
                    s[i] += c[i] as f64;
                }
                n += 1.0;
            }
        }
    }
    s.map(|v| (v / n) as f32)
}

fn white() -> Background {
    Background::Color([1.0; 4])
}

fn composite_one(layer: &composite::StylizedLayer, bg: &Background) -> Plane<Rgba> {
    composite::composite(W, H, bg, &[LayerFrame::stylized(layer, None)], StrokeMode::Keep).unwrap()
}

const RED: Rgb = [0.85, 0.12, 0.10];
const GREEN: Rgb = [0.15, 0.65, 0.20];

#[test]
fn red_glaze_is_red_and_keeps_the_texture() {
    let (rgb, mask, amount) = disk_frame(48.0, 48.0, 34.0);
    let flat = flat_disk(48.0, 48.0, 34.0, |_, _| RED);
    let layer = recolor(&rgb, &mask, &flat, PAPER, Recolor::Glaze).unwrap();
    let out = composite_one(&layer, &white());
    let painted = |x: usize, y: usize| amount.get(x, y) > 0.2;
    let hue = hue_deg(mean_color(&out, painted));
    let d = hue_distance(hue, hue_deg(RED));
    println!("glaze hue {hue:.2}° vs flat {:.2}° (distance {d:.2}°)", hue_deg(RED));
    assert!(d < 4.0, "hue {hue} is not the flat red's");

    // Texture: luminance spread inside, relative to the exemplar's.
    let lum = |p: &Plane<Rgba>| {
        (0..W * H).filter(|i| painted(i % W, i / W)).map(|i| luminance(p.data()[i])).collect::<Vec<_>>()
    };
    let exemplar = rgb.map(|c| [c[0], c[1], c[2], 1.0]);
    let (m_ex, s_ex) = mean_std(&lum(&exemplar));
    let (m_out, s_out) = mean_std(&lum(&out));
    println!("luminance exemplar mean {m_ex:.3} std {s_ex:.4}; glaze mean {m_out:.3} std {s_out:.4}");
    assert!(s_out > 0.8 * s_ex, "texture lost: std {s_out} vs exemplar {s_ex}");

    // The texture is the exemplar's: the recovered amount follows the true amount.
    let pairs: Vec<(f32, f32)> = (0..W * H)
        .filter(|i| painted(i % W, i / W))
        .map(|i| (amount.data()[i], layer.amount(i % W, i / W).unwrap()))
        .collect();
    let corr = correlation(&pairs);
    println!("correlation of recovered and true pigment amount: {corr:.5}");
    assert!(corr > 0.99);
}

fn correlation(p: &[(f32, f32)]) -> f32 {
    let n = p.len() as f32;
    let (ma, mb) = (p.iter().map(|v| v.0).sum::<f32>() / n, p.iter().map(|v| v.1).sum::<f32>() / n);
    let cov: f32 = p.iter().map(|v| (v.0 - ma) * (v.1 - mb)).sum();
    let va: f32 = p.iter().map(|v| (v.0 - ma).powi(2)).sum();
    let vb: f32 = p.iter().map(|v| (v.1 - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

#[test]
fn two_colored_flat_keeps_both_hues() {
    let (rgb, mask, amount) = disk_frame(48.0, 48.0, 34.0);
    let flat = flat_disk(48.0, 48.0, 34.0, |x, _| if x < W / 2 { RED } else { GREEN });
    for mode in [Recolor::Glaze, Recolor::Over] {
        let layer = recolor(&rgb, &mask, &flat, PAPER, mode).unwrap();
        let out = composite_one(&layer, &white());
        let left = hue_deg(mean_color(&out, |x, y| x < W / 2 - 2 && amount.get(x, y) > 0.2));
        let right = hue_deg(mean_color(&out, |x, y| x > W / 2 + 2 && amount.get(x, y) > 0.2));
        println!(
            "{mode:?}: left hue {left:.2}° (red {:.2}°), right hue {right:.2}° (green {:.2}°)",
            hue_deg(RED),
            hue_deg(GREEN)
        );
        assert!(hue_distance(left, hue_deg(RED)) < 4.0);
        assert!(hue_distance(right, hue_deg(GREEN)) < 4.0);
    }
}

#[test]
fn paper_margin_takes_the_nearest_flat_color() {
    let (rgb, mask, _) = disk_frame(48.0, 48.0, 30.0);
    let flat = flat_disk(48.0, 48.0, 30.0, |x, _| if x < W / 2 { RED } else { GREEN });
    let layer = recolor(&rgb, &mask, &flat, PAPER, Recolor::Glaze).unwrap();
    // (48 - 33, 48) lies in the 4 px margin left of the disk, (48 + 33, 48) right of it.
    let left = layer.tint(15, 48).unwrap();
    let right = layer.tint(81, 48).unwrap();
    println!("margin tints: left {left:?}, right {right:?}");
    assert!(hue_distance(hue_deg(left), hue_deg(RED)) < 4.0 && left[0] > 0.6);
    assert!(hue_distance(hue_deg(right), hue_deg(GREEN)) < 4.0 && right[1] > 0.5);
    assert!(layer.tint(2, 2).is_none(), "outside the mask there is no layer");
}

#[test]
fn overlapping_glazes_multiply() {
    let (rgb_a, mask_a, amount_a) = disk_frame(36.0, 48.0, 26.0);
    let (rgb_b, mask_b, amount_b) = disk_frame(60.0, 48.0, 26.0);
    let flat_a = flat_disk(36.0, 48.0, 26.0, |_, _| [0.95, 0.80, 0.20]);
    let flat_b = flat_disk(60.0, 48.0, 26.0, |_, _| [0.30, 0.60, 0.90]);
    let pigment = Pigment::new(PAPER, [1.5 * 1.05, 0.8 * 1.05, 0.15 * 1.05]);
    let a = recolor_with(&rgb_a, &mask_a, &flat_a, &pigment, Recolor::Glaze).unwrap();
    let b = recolor_with(&rgb_b, &mask_b, &flat_b, &pigment, Recolor::Glaze).unwrap();
    let bg = white();
    let only_a = composite_one(&a, &bg);
    let only_b = composite_one(&b, &bg);
    let both = composite::composite(
        W,
        H,
        &bg,
        &[LayerFrame::stylized(&a, None), LayerFrame::stylized(&b, None)],
        StrokeMode::Keep,
    )
    .unwrap();
    let overlap = |x: usize, y: usize| amount_a.get(x, y) > 0.2 && amount_b.get(x, y) > 0.2;
    let (la, lb, lab) = (
        luminance_of(mean_color(&only_a, overlap)),
        luminance_of(mean_color(&only_b, overlap)),
        luminance_of(mean_color(&both, overlap)),
    );
    println!("overlap luminance: a {la:.3}, b {lb:.3}, both {lab:.3}");
    assert!(lab < la - 0.05 && lab < lb - 0.05);
    // Exactly multiplicative on white, in linear light, pixel by pixel.
    let mut max_err: f32 = 0.0;
    for y in 0..H {
        for x in 0..W {
            if overlap(x, y) {
                for i in 0..3 {
                    let expect = srgb_to_linear(only_a.get(x, y)[i]) * srgb_to_linear(only_b.get(x, y)[i]);
                    max_err = max_err.max((srgb_to_linear(both.get(x, y)[i]) - expect).abs());
                }
            }
        }
    }
    println!("max deviation from T_a * T_b: {max_err:.2e}");
    assert!(max_err < 1e-3);
    // Glazing does not depend on the order on white paper.
    let swapped = composite::composite(
        W,
        H,
        &bg,
        &[LayerFrame::stylized(&b, None), LayerFrame::stylized(&a, None)],
        StrokeMode::Keep,
    )
    .unwrap();
    assert!(both.data().iter().zip(swapped.data()).all(|(p, q)| (0..4).all(|i| (p[i] - q[i]).abs() < 1e-3)));
}

fn luminance_of(c: [f32; 3]) -> f32 {
    luminance([c[0], c[1], c[2], 1.0])
}

#[test]
fn outside_the_mask_the_background_is_untouched() {
    let (rgb, mask, _) = disk_frame(48.0, 48.0, 20.0);
    let flat = flat_disk(48.0, 48.0, 20.0, |_, _| RED);
    let texture = Plane::from_fn(W, H, |x, y| [0.9 - 0.3 * hash(x as i64, y as i64, 3), 0.85, 0.8, 1.0]);
    for mode in [Recolor::Glaze, Recolor::Over, Recolor::None] {
        let layer = recolor(&rgb, &mask, &flat, PAPER, mode).unwrap();
        for bg in [Background::Color([0.2, 0.3, 0.4, 1.0]), Background::Image(texture.clone()), Background::Transparent]
        {
            let out = composite_one(&layer, &bg);
            for y in 0..H {
                for x in 0..W {
                    if !mask.get(x, y) {
                        assert_eq!(out.get(x, y), bg.pixel(x, y), "{mode:?} changed ({x}, {y})");
                    }
                }
            }
        }
    }
}

#[test]
fn none_reproduces_the_exemplar_over_its_paper() {
    let (rgb, mask, _) = disk_frame(48.0, 48.0, 30.0);
    let flat = flat_disk(48.0, 48.0, 30.0, |_, _| RED);
    let layer = recolor(&rgb, &mask, &flat, PAPER, Recolor::None).unwrap();
    let out = composite_one(&layer, &Background::Color([PAPER[0], PAPER[1], PAPER[2], 1.0]));
    let mut max_err: f32 = 0.0;
    for y in 0..H {
        for x in 0..W {
            let (o, e) = (out.get(x, y), rgb.get(x, y));
            for i in 0..3 {
                max_err = max_err.max((o[i] - e[i]).abs());
            }
        }
    }
    println!("none over paper: max error {:.3} levels", max_err * 255.0);
    assert!(max_err * 255.0 < 0.5);
}

#[test]
fn over_at_full_density_is_the_flat_color() {
    // Uniform paint at the reference density: a = 1 everywhere inside.
    let k = [1.2, 0.9, 0.4];
    let rgb = Plane::filled(W, H, paint(1.0, k));
    let mask = Plane::filled(W, H, true);
    // Channels at or above the tint floor (linear 0.01, sRGB 0.0998): below it see
    // `pure_colors_show_the_paint`.
    let ramp = |t: f32| 0.1 + 0.9 * t;
    let flat = Plane::from_fn(W, H, |x, y| [ramp(x as f32 / W as f32), ramp(y as f32 / H as f32), 0.5, 1.0]);
    let pigment = Pigment::new(PAPER, k);
    for mode in [Recolor::Over, Recolor::Glaze] {
        let layer = recolor_with(&rgb, &mask, &flat, &pigment, mode).unwrap();
        for bg in [white(), Background::Color([0.1, 0.2, 0.6, 1.0])] {
            let out = composite_one(&layer, &bg);
            let err = out
                .data()
                .iter()
                .zip(flat.data())
                .flat_map(|(o, f)| (0..4).map(move |i| (o[i] - f[i]).abs()))
                .fold(0.0f32, f32::max);
            println!("{mode:?} at a = 1 over {bg:?}: max error {:.3} levels", err * 255.0);
            assert!(err * 255.0 < 0.5, "{mode:?}: {err}");
        }
    }
}

#[test]
fn glaze_on_transparent_looks_the_same_over_white() {
    let (rgb, mask, _) = disk_frame(48.0, 48.0, 30.0);
    let flat = flat_disk(48.0, 48.0, 30.0, |_, _| RED);
    let layer = recolor(&rgb, &mask, &flat, PAPER, Recolor::Glaze).unwrap();
    let on_white = composite_one(&layer, &white());
    let alone = layer.to_rgba();
    assert_eq!(alone, composite_one(&layer, &Background::Transparent));
    let mut max_err: f32 = 0.0;
    for (a, w) in alone.data().iter().zip(on_white.data()) {
        for i in 0..3 {
            let over_white = srgb_to_linear(a[i]) * a[3] + (1.0 - a[3]);
            max_err = max_err.max((linear_to_srgb(over_white) - w[i]).abs());
        }
    }
    println!("transparent glaze over white vs glaze on white: {:.3} levels", max_err * 255.0);
    assert!(max_err * 255.0 < 0.6);
    assert_eq!(alone.get(1, 1)[3], 0.0);
    assert!(alone.get(48, 48)[3] > 0.5);
}

#[test]
fn light_layer_on_dark_background_lifts_like_reserved_paper() {
    let (rgb, mask, amount) = disk_frame(48.0, 48.0, 30.0);
    let cloud = [0.95, 0.95, 0.97];
    let flat = flat_disk(48.0, 48.0, 30.0, |_, _| cloud);
    let layer = recolor(&rgb, &mask, &flat, PAPER, Recolor::Glaze).unwrap();
    let out = composite_one(&layer, &Background::Color([0.1, 0.2, 0.5, 1.0]));
    let inside = mean_color(&out, |x, y| amount.get(x, y) > 0.2);
    println!("white glaze on navy: mean {inside:?}");
    assert!(inside.iter().all(|&v| v > 0.7), "a white layer must show on a dark background");
}

#[test]
fn flat_layers_and_strokes() {
    let fill = flat_disk(48.0, 48.0, 20.0, |_, _| GREEN);
    let strokes = Plane::from_fn(W, H, |x, _| if x == 48 { [0.0, 0.0, 0.0, 1.0] } else { [0.0; 4] });
    let bg = white();
    let layers = [LayerFrame::flat(&fill, Some(&strokes))];
    let keep = composite::composite(W, H, &bg, &layers, StrokeMode::Keep).unwrap();
    let drop = composite::composite(W, H, &bg, &layers, StrokeMode::Drop).unwrap();
    assert_eq!(keep.get(48, 5), [0.0, 0.0, 0.0, 1.0]);
    assert_eq!(drop.get(48, 5), [1.0; 4]);
    // A flat layer under `Stylize` keeps its strokes (merged with the fill): the same as `Keep`.
    let stylize = composite::composite(W, H, &bg, &layers, StrokeMode::Stylize).unwrap();
    assert!(stylize == keep, "a flat layer's strokes were dropped under Stylize");
    let c = drop.get(40, 48);
    assert!((0..3).all(|i| (c[i] - GREEN[i]).abs() < 1.0 / 255.0), "{c:?}");
    let merged = composite::merge_strokes(&fill, Some(&strokes));
    assert_eq!(merged.get(48, 48), [0.0, 0.0, 0.0, 1.0]);
    assert_eq!(merged.get(40, 48)[3], 1.0);
}

#[test]
fn sizes_must_match() {
    let (rgb, mask, _) = disk_frame(48.0, 48.0, 20.0);
    let small: Plane<Rgba> = Plane::new(10, 10);
    let err = recolor(&rgb, &mask, &small, PAPER, Recolor::Glaze).unwrap_err().to_string();
    assert!(err.contains("10x10") && err.contains("96x96"), "{err}");
    let err = composite::composite(20, 20, &white(), &[LayerFrame::flat(&small, None)], StrokeMode::Keep).unwrap_err();
    assert!(err.to_string().contains("20x20"));
}

#[test]
fn backgrounds_parse_and_load() {
    use crate::render::Background as Spec;
    assert_eq!("none".parse::<Spec>().unwrap(), Spec::Transparent);
    assert_eq!("#ff0000".parse::<Spec>().unwrap(), Spec::Color([1.0, 0.0, 0.0, 1.0]));
    assert_eq!("no-such-paper.png".parse::<Spec>().unwrap(), Spec::Image("no-such-paper.png".into()));

    let dir = std::env::temp_dir().join(format!("fm-composite-bg-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("paper.png");
    let src = Plane::from_fn(40, 20, |x, _| if x < 20 { [0.2, 0.2, 0.2, 1.0] } else { [0.8, 0.8, 0.8, 1.0] });
    crate::img::save_rgba(&file, &src).unwrap();
    let Background::Image(img) = Background::load_image(&file, 30, 30).unwrap() else {
        panic!("expected an image background");
    };
    assert_eq!(img.size(), (30, 30));
    assert!(img.get(0, 15)[0] < 0.25 && img.get(29, 15)[0] > 0.75);
    let broken = dir.join("broken.png");
    std::fs::write(&broken, b"not a png").unwrap();
    let err = Background::load_image(&broken, 30, 30).unwrap_err().to_string();
    assert!(err.contains("broken.png") && err.contains("background"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn pigment_from_colors_finds_the_typical_density() {
    let (rgb, _, amount) = disk_frame(48.0, 48.0, 34.0);
    let paint_px = rgb.data().iter().zip(amount.data()).filter(|(_, a)| **a > 0.0).map(|(c, _)| *c);
    let pig = Pigment::from_colors(PAPER, paint_px);
    let mut amounts: Vec<f32> = amount.data().iter().copied().filter(|a| *a > 0.0).collect();
    amounts.sort_by(f32::total_cmp);
    let median = amounts[amounts.len() / 2];
    let k = pig.reference_density();
    for i in 0..3 {
        assert!((k[i] - median * BLUE[i]).abs() < 0.02 * BLUE[i] + 1e-3, "{k:?} vs {median} × {BLUE:?}");
    }
}

/// `opacity` and `coverage` on an antialiased disc drawn at 40 %: the edge has the opacity of
/// the paint beside it, and the coverage is the disc's at full opacity, everywhere.
#[test]
fn opacity_and_coverage_separate_alpha() {
    let disc = |o: f32| {
        Plane::from_fn(64, 64, move |x, y| {
            let d = ((x as f32 - 31.5).powi(2) + (y as f32 - 31.5).powi(2)).sqrt();
            [0.2, 0.3, 0.9, o * (20.0 - d + 0.5).clamp(0.0, 1.0)]
        })
    };
    let (full, faint) = (disc(1.0), disc(0.4));
    let o = super::opacity(&faint);
    let cov = super::coverage(&faint);
    let reference = super::coverage(&full);
    for y in 0..64 {
        for x in 0..64 {
            if full.get(x, y)[3] > 0.0 {
                assert!((o.get(x, y) - 0.4).abs() < 1e-6, "opacity at ({x}, {y}): {}", o.get(x, y));
            }
            assert!((cov.get(x, y) - reference.get(x, y)).abs() < 1e-5, "coverage at ({x}, {y})");
        }
    }
    assert!((reference.get(31, 31) - 1.0).abs() < 1e-6 && reference.get(0, 0) == 0.0);
}

/// A pure color (#ff00ff: a channel at 0) shows the paint's texture: its zero channel is
/// floored at [`super::recolor::TINT_FLOOR`], so thinner paint lets it through. Before, the
/// painted layer was exactly the flat color wherever the paint was more than a fifth of its
/// typical density.
#[test]
fn pure_colors_show_the_paint() {
    let k = [1.2, 0.9, 0.4];
    let rgb = Plane::from_fn(W, H, |x, _| paint(0.5 + x as f32 / W as f32, k));
    let mask = Plane::filled(W, H, true);
    let flat = Plane::filled(W, H, [1.0, 0.0, 1.0, 1.0]);
    let layer = recolor_with(&rgb, &mask, &flat, &Pigment::new(PAPER, k), Recolor::Glaze).unwrap();
    let out = composite_one(&layer, &white());
    let g: Vec<f32> = out.data().iter().map(|c| c[1]).collect();
    let (lo, hi) = g.iter().fold((1.0f32, 0.0f32), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    // a = 0.5 → 0.01^0.5 = 0.1 linear (sRGB 0.35); a = 1.5 → 0.001 (sRGB 0.013).
    assert!(hi > 0.3 && lo < 0.05, "the green channel spans {lo:.3}–{hi:.3}");
    assert!(out.data().iter().all(|c| c[0] > 0.99 && c[2] > 0.99), "red and blue stay full");
}
