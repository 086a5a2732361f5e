//! Guide computation speed at 1000×800 (issue 3: all target guides of one frame well under
//! 100 ms). The target is a deforming, moving blob covering about 15 % of the frame.
//!
//! `cargo bench --bench guides`

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use fluidymation::guide::{GuideParams, GuideStream, compute_sequence, laplace, preprocess_mask, sdf};
use fluidymation::img::Plane;
use glam::Vec2;
use std::hint::black_box;
use std::time::{Duration, Instant};

const W: usize = 1000;
const H: usize = 800;

/// Coverage of frame `i`: a wobbly blob of radius ~220 px drifting right, ~15 % of the frame.
fn blob(i: usize) -> Plane<f32> {
    let t = i as f32;
    let (cx, cy) = (420.0 + 3.0 * t, 400.0 + t);
    Plane::from_fn(W, H, |x, y| {
        let (dx, dy) = (x as f32 - cx, y as f32 - cy);
        let a = dy.atan2(dx);
        let r = 215.0 + 1.5 * t + 25.0 * (3.0 * a + 0.2 * t).sin() + 12.0 * (5.0 * a - 0.1 * t).cos();
        if dx * dx + dy * dy < r * r { 1.0 } else { 0.0 }
    })
}

fn guides(c: &mut Criterion) {
    let params = GuideParams::default();
    let n = 16;
    let frames: Vec<_> = (0..n).map(blob).collect();
    let coverage = frames[8].data().iter().filter(|&&v| v > 0.5).count() as f64 / (W * H) as f64;
    eprintln!("blob covers {:.1} % of the frame", 100.0 * coverage);

    let mut g = c.benchmark_group("guides_1000x800");
    g.sample_size(10).measurement_time(Duration::from_secs(20)).throughput(Throughput::Elements(n as u64));
    // Everything for n frames held in memory (the exemplar path); time per element = per frame.
    g.bench_function("in_memory_per_frame", |b| {
        b.iter(|| black_box(compute_sequence(&frames, &params).unwrap()));
    });
    // The streaming target path: backward pass, then frame by frame.
    g.bench_function("stream_per_frame", |b| {
        b.iter(|| {
            let s = GuideStream::new(n, |i| Ok(frames[i].clone()), &params).unwrap();
            for f in s {
                black_box(f.unwrap());
            }
        });
    });
    g.finish();

    // The pieces, one frame.
    let mut g = c.benchmark_group("guide_parts_1000x800");
    g.sample_size(20);
    let mask = preprocess_mask(&frames[8], &params);
    g.bench_function("preprocess_mask", |b| b.iter(|| black_box(preprocess_mask(&frames[8], &params))));
    g.bench_function("sdf_full_frame", |b| b.iter(|| black_box(sdf(&mask))));
    // Laplace on the mask's interior with a rotational boundary flow, as in the flow estimate.
    let (cells, values) = laplace_problem(&mask);
    g.bench_function("laplace_solve", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let mut v = values.clone();
                let t = Instant::now();
                black_box(laplace::solve(&cells, &mut v, laplace::TOLERANCE));
                total += t.elapsed();
            }
            total
        })
    });
    g.finish();
}

fn laplace_problem(mask: &Plane<bool>) -> (Plane<laplace::Cell>, Plane<Vec2>) {
    let (w, h) = mask.size();
    let out = |x: usize, y: usize, dx: isize, dy: isize| {
        let (a, b) = (x as isize + dx, y as isize + dy);
        a >= 0 && b >= 0 && (a as usize) < w && (b as usize) < h && !mask.get(a as usize, b as usize)
    };
    let cells = Plane::from_fn(w, h, |x, y| {
        if !mask.get(x, y) {
            laplace::Cell::Outside
        } else if out(x, y, -1, 0) || out(x, y, 1, 0) || out(x, y, 0, -1) || out(x, y, 0, 1) {
            laplace::Cell::Fixed
        } else {
            laplace::Cell::Free
        }
    });
    let values = Plane::from_fn(w, h, |x, y| {
        if cells.get(x, y) == laplace::Cell::Fixed {
            let p = Vec2::new(x as f32 - 450.0, y as f32 - 408.0);
            Vec2::new(-p.y, p.x) * 0.01 + Vec2::new(3.0, 1.0)
        } else {
            Vec2::ZERO
        }
    });
    (cells, values)
}

criterion_group!(benches, guides);
criterion_main!(benches);
