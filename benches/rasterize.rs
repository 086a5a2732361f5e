//! Rasterizing every region of every frame, at the file's own size.
//!
//! Two corpus files: `ios_TypeFace_S.json`, the largest file in bytes (80×100, 37 frames,
//! 11 regions, masks and mattes), and `ios_LottieLogo1.json`, the largest job
//! (375×667, 179 frames, 45 regions). One iteration renders all regions of all frames
//! (fills and, where a region has them, strokes) through `Animation::render`, as the pipeline
//! does; criterion reports the time per iteration, so frames per second = frames / time.
//!
//! `cargo bench --bench rasterize`

use criterion::{Criterion, criterion_group, criterion_main};
use fluidymation::anim::{self, LoadOptions};
use std::path::Path;
use std::time::{Duration, Instant};

fn bench(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/lottie");
    let mut group = c.benchmark_group("rasterize_all_regions_all_frames");
    group.sample_size(10).measurement_time(Duration::from_secs(20));
    for file in ["ios_TypeFace_S.json", "ios_LottieLogo1.json"] {
        let a = anim::load(&root.join(file), &LoadOptions::default()).expect("corpus file loads");
        let (frames, regions) = (a.frames, a.regions.len());
        group.bench_function(format!("{file} ({frames} frames x {regions} regions)"), |b| {
            b.iter_custom(|iters| {
                let start = Instant::now();
                for _ in 0..iters {
                    for f in 0..frames {
                        for r in 0..regions {
                            std::hint::black_box(a.render(r, f).expect("renders"));
                        }
                    }
                }
                start.elapsed()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
