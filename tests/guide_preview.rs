//! Preview pictures of the guides (flow as hue and brightness like the paper's Fig. 4b, ext+ and
//! ext− as grayscale, the border channel).

use fluidymation::guide::preview::{self, PreviewOptions};
use fluidymation::guide::{FrameGuides, GuideParams, compute_sequence};
use fluidymation::img::{self, Plane};
use std::path::Path;

fn disc_sequence(w: usize, h: usize, n: usize, at: impl Fn(usize) -> (f32, f32, f32)) -> Vec<Plane<f32>> {
    (0..n)
        .map(|i| {
            let (cx, cy, r) = at(i);
            Plane::from_fn(w, h, |x, y| {
                let (dx, dy) = (x as f32 - cx, y as f32 - cy);
                if dx * dx + dy * dy < r * r { 1.0 } else { 0.0 }
            })
        })
        .collect()
}

#[test]
fn previews_are_written_and_encode_the_channels() {
    let seq = disc_sequence(90, 60, 12, |i| (30.0 + 2.0 * i as f32, 30.0, 15.0));
    let g = compute_sequence(&seq, &GuideParams::default().blur_sigma(2.0)).unwrap();
    let dir = std::env::temp_dir().join(format!("fm-guide-preview-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let opts = PreviewOptions::default().border_width(5.0);
    let scales = preview::write_previews(&g[6], &dir, 6, &opts).unwrap();
    let flow = img::load_rgb(&dir.join("flow_0006.png")).unwrap();
    let ext_pos = img::load_gray(&dir.join("ext_pos_0006.png")).unwrap();
    let ext_neg = img::load_gray(&dir.join("ext_neg_0006.png")).unwrap();
    let border = img::load_gray(&dir.join("border_0006.png")).unwrap();
    assert_eq!(flow.size(), (90, 60));
    // The disc moves right: red inside (hue 0), black outside.
    let c = (30 + 12, 30);
    let px = flow.get(c.0, c.1);
    assert!(px[0] > 0.5 && px[1] < 0.25 && px[2] < 0.25, "{px:?}");
    assert_eq!(flow.get(2, 2), [0.0, 0.0, 0.0]);
    // Grayscale extents on the shared scale; the brightest pixel is the scale.
    assert!(
        (scales.ext - g[6].ext_pos.data().iter().chain(g[6].ext_neg.data()).fold(0f32, |a, &b| a.max(b))).abs() < 1e-5
    );
    let e = g[6].ext_pos.get(c.0, c.1) / scales.ext;
    assert!((ext_pos.get(c.0, c.1) - e).abs() <= 1.0 / 255.0);
    let brightest = ext_pos.data().iter().chain(ext_neg.data()).fold(0f32, |a, &b| a.max(b));
    assert_eq!(brightest, 1.0);
    assert!(ext_neg.data().iter().any(|&v| v > 0.5));
    // Border channel: white deep inside, black outside, in between at the rim.
    assert_eq!(border.get(c.0, c.1), 1.0);
    assert_eq!(border.get(2, 2), 0.0);
    let rim = (0..90).map(|x| border.get(x, 30)).filter(|&v| v > 0.0 && v < 1.0).count();
    assert!(rim >= 4, "{rim}");
    // A missing directory is an error, not a panic.
    assert!(preview::write_previews(&g[6], &dir.join("missing"), 0, &opts).is_err());
    std::fs::remove_dir_all(&dir).unwrap();
}

fn save_montage(g: &FrameGuides, name: &str, opts: &PreviewOptions) {
    let (m, scales) = preview::montage(g, opts);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs").join(name);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    img::save_rgb(&path, &m).unwrap();
    eprintln!(
        "{}: flow at full brightness {:.2} px/frame, extent white at {:.1} px",
        path.display(),
        scales.flow,
        scales.ext
    );
}

/// Regenerates `docs/guides-spread.png` and `docs/guides-move.png`:
/// `cargo test --release --test guide_preview -- --ignored`.
#[test]
#[ignore]
fn generate_docs_pictures() {
    let (w, h) = (200, 150);
    let opts = PreviewOptions::default().border_width(8.0);
    // Paint spreading unevenly from a drop: three lobes growing at different speeds.
    let spread: Vec<Plane<f32>> = (0..30)
        .map(|i| {
            let t = i as f32;
            Plane::from_fn(w, h, move |x, y| {
                let (dx, dy) = (x as f32 - 95.0, y as f32 - 78.0);
                let a = dy.atan2(dx);
                let r = 18.0 + t * (1.1 + 0.6 * (3.0 * a).sin() + 0.3 * (5.0 * a + 1.0).cos());
                if dx * dx + dy * dy < r * r { 1.0 } else { 0.0 }
            })
        })
        .collect();
    let g = compute_sequence(&spread, &GuideParams::default()).unwrap();
    save_montage(&g[18], "guides-spread.png", &opts);
    // A blob sliding right and down while it stretches.
    let moving: Vec<Plane<f32>> = (0..30)
        .map(|i| {
            let t = i as f32;
            Plane::from_fn(w, h, move |x, y| {
                let (dx, dy) = (x as f32 - 50.0 - 3.0 * t, y as f32 - 60.0 - 1.0 * t);
                let (rx, ry) = (28.0 + 0.5 * t, 22.0);
                if (dx / rx).powi(2) + (dy / ry).powi(2) < 1.0 { 1.0 } else { 0.0 }
            })
        })
        .collect();
    let g = compute_sequence(&moving, &GuideParams::default()).unwrap();
    save_montage(&g[15], "guides-move.png", &opts);
}
