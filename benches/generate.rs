//! Time of the watercolor generator (simulation and rendering, not PNG writing).
//!
//! `cargo bench --bench generate` — the target: 200×200 × 30 frames in under 30 s
//! on 2 cores in release mode.

use criterion::{Criterion, criterion_group, criterion_main};
use fluidymation::NoProgress;
use fluidymation::exemplar::generate::{GeneratorParams, generate};
use std::hint::black_box;
use std::time::{Duration, Instant};

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("generate");
    group.sample_size(10).measurement_time(Duration::from_secs(20)).warm_up_time(Duration::from_secs(1));
    for (w, frames) in [(100usize, 30usize), (200, 30)] {
        let params = GeneratorParams::default().size(w, w).frames(frames);
        group.bench_function(format!("{w}x{w}x{frames}"), |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    let start = Instant::now();
                    black_box(generate(&params, "bench", &NoProgress).expect("valid parameters"));
                    total += start.elapsed();
                }
                total
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
