//! GIF output: timing, decoding, palette quality, inter-frame updates, transparency, atomicity.

use fluidymation::img::{Plane, Rgba};
use fluidymation::output::{GifOptions, GifWriter, gif_schedule};
use std::path::{Path, PathBuf};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fm-output-gif-{}-{}", name, std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

struct Decoded {
    width: usize,
    height: usize,
    delays: Vec<u16>,
    /// The canvas after each frame, RGBA8, as a viewer shows it.
    canvases: Vec<Vec<u8>>,
    infinite: bool,
}

/// Decodes with the `gif` crate and composites frames onto the canvas (keep / background
/// disposal) the way viewers do.
fn decode(path: &Path) -> Decoded {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options.read_info(std::fs::File::open(path).unwrap()).unwrap();
    let (width, height) = (decoder.width() as usize, decoder.height() as usize);
    let mut canvas = vec![0u8; width * height * 4];
    let mut delays = Vec::new();
    let mut canvases = Vec::new();
    while let Some(frame) = decoder.read_next_frame().unwrap() {
        let (l, t, w) = (frame.left as usize, frame.top as usize, frame.width as usize);
        for (i, px) in frame.buffer.chunks_exact(4).enumerate() {
            let (x, y) = (l + i % w, t + i / w);
            if px[3] != 0 {
                canvas[4 * (y * width + x)..][..4].copy_from_slice(px);
            }
        }
        canvases.push(canvas.clone());
        delays.push(frame.delay);
        if frame.dispose == gif::DisposalMethod::Background {
            for i in 0..frame.buffer.len() / 4 {
                let (x, y) = (l + i % w, t + i / w);
                canvas[4 * (y * width + x)..][..4].copy_from_slice(&[0, 0, 0, 0]);
            }
        }
    }
    let infinite = decoder.repeat() == gif::Repeat::Infinite;
    Decoded { width, height, delays, canvases, infinite }
}

fn to8(v: f32) -> f32 {
    (v.clamp(0.0, 1.0) * 255.0 + 0.5).floor()
}

/// Mean absolute error per channel (levels) of a decoded canvas against the source frame, and
/// the same after a 5×5 box blur of both (the error the eye sees from a normal distance).
fn errors(canvas: &[u8], src: &Plane<Rgba>) -> (f32, f32) {
    let (w, h) = src.size();
    let diff: Vec<[f32; 3]> =
        (0..w * h).map(|i| [0, 1, 2].map(|c| canvas[4 * i + c] as f32 - to8(src.data()[i][c]))).collect();
    let raw = diff.iter().map(|d| d.iter().map(|v| v.abs()).sum::<f32>()).sum::<f32>() / (3 * w * h) as f32;
    let mut blurred = 0.0;
    let mut n = 0.0;
    for y in 2..h - 2 {
        for x in 2..w - 2 {
            let mut s = [0.0f32; 3];
            for dy in 0..5 {
                for dx in 0..5 {
                    let d = diff[(y + dy - 2) * w + x + dx - 2];
                    s.iter_mut().zip(d).for_each(|(s, d)| *s += d);
                }
            }
            blurred += s.iter().map(|v| (v / 25.0).abs()).sum::<f32>();
            n += 3.0;
        }
    }
    (raw, blurred / n)
}

/// A watercolor-like wash: paper white to deep blue, with a soft diagonal variation.
fn wash(w: usize, h: usize, phase: f32) -> Plane<Rgba> {
    Plane::from_fn(w, h, |x, y| {
        let t = x as f32 / (w - 1) as f32;
        let s = 0.5 + 0.5 * ((x as f32 + y as f32) * 0.05 + phase).sin();
        let a = t * (0.8 + 0.2 * s);
        [0.98 - 0.85 * a, 0.97 - 0.6 * a, 0.95 - 0.25 * a, 1.0]
    })
}

#[test]
fn schedule_keeps_the_total_duration() {
    let d24: Vec<u16> = gif_schedule(24.0, 48).into_iter().map(|(_, d)| d).collect();
    assert_eq!(d24.len(), 48);
    assert_eq!(d24.iter().map(|&d| d as u32).sum::<u32>(), 200);
    assert!(d24.iter().all(|&d| d == 4 || d == 5));
    assert_eq!(&d24[..6], &[4, 4, 5, 4, 4, 4]);
    let d30: Vec<u16> = gif_schedule(30.0, 30).into_iter().map(|(_, d)| d).collect();
    assert_eq!(d30.iter().map(|&d| d as u32).sum::<u32>(), 100);
    // 60 fps: frames shorter than 2/100 s are dropped, the duration is kept.
    let s60 = gif_schedule(60.0, 60);
    assert!(s60.len() < 60 && s60.len() >= 40, "{}", s60.len());
    assert!(s60.iter().all(|&(_, d)| d >= 2));
    assert_eq!(s60.iter().map(|&(_, d)| d as u32).sum::<u32>(), 100);
    assert_eq!(s60[0].0, 0);
}

#[test]
fn gif_decodes_to_the_right_frames_size_and_delays() {
    let dir = temp_dir("decode");
    let path = dir.join("anim.gif");
    let (w, h, n) = (64, 40, 12);
    let frames: Vec<Plane<Rgba>> = (0..n).map(|k| wash(w, h, k as f32 * 0.7)).collect();
    let mut writer = GifWriter::create(&path, w, h, GifOptions::new(24.0)).unwrap();
    for f in &frames {
        writer.add_frame(f).unwrap();
    }
    let summary = writer.finish().unwrap();
    assert_eq!((summary.frames_added, summary.frames_written, summary.duration_cs), (n, n, 50));
    let d = decode(&path);
    assert_eq!((d.width, d.height, d.delays.len()), (w, h, n));
    assert!(d.infinite);
    let total: u32 = d.delays.iter().map(|&d| d as u32).sum();
    println!("delays {:?} total {total} cs (expected {:.1})", d.delays, n as f64 * 100.0 / 24.0);
    assert_eq!(total, 50);
    for (canvas, src) in d.canvases.iter().zip(&frames) {
        let (raw, blurred) = errors(canvas, src);
        assert!(raw < 2.0 && blurred < 1.0, "raw {raw} blurred {blurred}");
    }
    assert!(std::fs::read_dir(&dir).unwrap().count() == 1, "only the GIF is left");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn smooth_gradients_stay_close_to_the_source() {
    let dir = temp_dir("quality");
    // A wash (many close colors along one direction) and a full 2D color gradient (far more
    // colors than a palette holds).
    let cases = [
        ("wash", wash(256, 96, 0.0)),
        (
            "rgb",
            Plane::from_fn(256, 256, |x, y| [x as f32 / 255.0, y as f32 / 255.0, 1.0 - (x + y) as f32 / 510.0, 1.0]),
        ),
    ];
    for (name, src) in cases {
        let mut measured = Vec::new();
        for dither in [true, false] {
            let path = dir.join(format!("{name}-{dither}.gif"));
            let options = GifOptions::new(10.0).dither(dither);
            let mut writer = GifWriter::create(&path, src.width(), src.height(), options).unwrap();
            writer.add_frame(&src).unwrap();
            writer.finish().unwrap();
            let d = decode(&path);
            measured.push(errors(&d.canvases[0], &src));
        }
        let ((raw, blurred), (raw_nd, blurred_nd)) = (measured[0], measured[1]);
        println!(
            "{name}: dithered MAE {raw:.2} levels (blurred {blurred:.2}); nearest MAE {raw_nd:.2} (blurred {blurred_nd:.2})"
        );
        match name {
            "wash" => assert!(raw < 1.0 && blurred < 0.5),
            _ => assert!(raw < 6.0 && blurred < 1.0),
        }
        assert!(blurred < blurred_nd, "dithering must reduce the visible (low-pass) error");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn still_areas_stay_still_and_moving_areas_follow() {
    let dir = temp_dir("updates");
    let path = dir.join("moving.gif");
    let (w, h) = (120, 80);
    let background = wash(w, h, 0.0);
    let frames: Vec<Plane<Rgba>> = (0..6)
        .map(|k| {
            let mut f = background.clone();
            for y in 30..50 {
                for x in 10 + 12 * k..30 + 12 * k {
                    f.set(x, y, [0.8, 0.2 + 0.05 * k as f32, 0.1, 1.0]);
                }
            }
            f
        })
        .collect();
    let mut writer = GifWriter::create(&path, w, h, GifOptions::new(12.0)).unwrap();
    for f in &frames {
        writer.add_frame(f).unwrap();
    }
    writer.finish().unwrap();
    let d = decode(&path);
    assert_eq!(d.canvases.len(), 6);
    for (k, (canvas, src)) in d.canvases.iter().zip(&frames).enumerate() {
        let (raw, _) = errors(canvas, src);
        println!("frame {k}: MAE {raw:.2} levels");
        assert!(raw < 1.5);
        // The square is exactly its color (few colors change per frame: kept exactly).
        let i = 4 * (40 * w + 15 + 12 * k);
        assert_eq!(&canvas[i..i + 3], &[204, (to8(0.2 + 0.05 * k as f32)) as u8, 26]);
    }
    // A pixel no frame changes shows the same value throughout.
    let i = 4 * (70 * w + 60);
    assert!(d.canvases.iter().all(|c| c[i..i + 4] == d.canvases[0][i..i + 4]));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn identical_frames_merge_and_fast_animations_drop_frames() {
    let dir = temp_dir("merge");
    let path = dir.join("merge.gif");
    let a = wash(32, 16, 0.0);
    let b = wash(32, 16, 1.0);
    let mut writer = GifWriter::create(&path, 32, 16, GifOptions::new(10.0)).unwrap();
    for f in [&a, &a, &a, &b] {
        writer.add_frame(f).unwrap();
    }
    let s = writer.finish().unwrap();
    assert_eq!((s.frames_added, s.frames_written, s.duration_cs), (4, 2, 40));
    assert_eq!(decode(&path).delays, vec![30, 10]);

    let path = dir.join("fast.gif");
    let mut writer = GifWriter::create(&path, 32, 16, GifOptions::new(60.0)).unwrap();
    for k in 0..12 {
        writer.add_frame(&wash(32, 16, k as f32)).unwrap();
    }
    let s = writer.finish().unwrap();
    let d = decode(&path);
    println!("60 fps: {} of 12 frames written, delays {:?}", s.frames_written, d.delays);
    assert_eq!(d.delays.iter().map(|&d| d as u32).sum::<u32>(), 20);
    assert!(d.delays.iter().all(|&d| d >= 2));
    assert_eq!(d.delays.len(), s.frames_written);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn transparent_frames_are_cleared_between_frames() {
    let dir = temp_dir("alpha");
    let path = dir.join("alpha.gif");
    let (w, h) = (40, 20);
    // A square that moves right on a transparent background.
    let frame = |x0: usize| {
        Plane::from_fn(w, h, |x, y| {
            if (x0..x0 + 10).contains(&x) && (5..15).contains(&y) { [0.2, 0.4, 0.9, 0.9] } else { [0.0; 4] }
        })
    };
    let options = GifOptions::new(10.0).transparent(true);
    let mut writer = GifWriter::create(&path, w, h, options).unwrap();
    writer.add_frame(&frame(0)).unwrap();
    writer.add_frame(&frame(20)).unwrap();
    writer.finish().unwrap();
    let d = decode(&path);
    assert_eq!(d.canvases.len(), 2);
    let alpha = |c: &[u8], x: usize, y: usize| c[4 * (y * w + x) + 3];
    assert_eq!((alpha(&d.canvases[0], 5, 10), alpha(&d.canvases[0], 25, 10)), (255, 0));
    // The second frame shows the square at its new place only: the old one was cleared.
    assert_eq!((alpha(&d.canvases[1], 5, 10), alpha(&d.canvases[1], 25, 10)), (0, 255));
    assert_eq!(&d.canvases[1][4 * (10 * w + 25)..][..3], &[51, 102, 230]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn unfinished_or_failed_gifs_leave_nothing() {
    let dir = temp_dir("atomic");
    let path = dir.join("never.gif");
    {
        let mut writer = GifWriter::create(&path, 16, 16, GifOptions::new(24.0)).unwrap();
        writer.add_frame(&wash(16, 16, 0.0)).unwrap();
        writer.add_frame(&wash(16, 16, 1.0)).unwrap();
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1, "only a temporary file while writing");
        assert!(!path.exists());
    } // dropped without finish
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);

    let writer = GifWriter::create(&path, 16, 16, GifOptions::new(24.0)).unwrap();
    let err = writer.finish().unwrap_err().to_string();
    assert!(err.contains("no frames"), "{err}");
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);

    let mut writer = GifWriter::create(&path, 16, 16, GifOptions::new(24.0)).unwrap();
    assert!(writer.add_frame(&wash(8, 8, 0.0)).unwrap_err().to_string().contains("8x8"));
    drop(writer);
    assert!(GifWriter::create(&path, 16, 16, GifOptions::new(0.0)).unwrap_err().to_string().contains("fps"));
    let err = GifWriter::create(&dir.join("missing/x.gif"), 16, 16, GifOptions::new(24.0)).unwrap_err().to_string();
    assert!(err.contains("missing/x.gif"), "the error names the destination: {err}");
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
    std::fs::remove_dir_all(&dir).unwrap();
}
