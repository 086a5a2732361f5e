//! Rasterizing every region of every frame, at the file's own size.
//!
//! Two corpus files: `ios_TypeFace_S.json`, the largest file in bytes (80×100, 37 frames,
//! 9 regions, masks and mattes), and `ios_LottieLogo1.json`, the largest job
//! (375×667, 179 frames, 45 regions, trims and parenting). One iteration renders all regions of
//! all frames; frames per second = frames / time per iteration. Two variants:
//!
//! - `region_frames`: through `Animation::render`, as the pipeline calls it (fills and, where a
//!   region has them, strokes, each converted to a full-canvas straight-RGBA `f32` plane);
//! - `pixmaps`: the rasterizer alone (`lottie::render` of every root layer, regions
//!   or not, fills and strokes in one premultiplied 8-bit pixmap), which shows how much of
//!   the cost is the conversion.
//!
//! `cargo bench --bench rasterize`

use criterion::{Criterion, criterion_group, criterion_main};
use fluidymation::anim::lottie;
use fluidymation::anim::{self, LoadOptions};
use std::path::Path;
use std::time::{Duration, Instant};

fn bench(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/lottie");
    let mut group = c.benchmark_group("rasterize_all_regions_all_frames");
    group.sample_size(10).measurement_time(Duration::from_secs(10));
    for file in ["ios_TypeFace_S.json", "ios_LottieLogo1.json"] {
        let path = root.join(file);
        let a = anim::load(&path, &LoadOptions::default()).expect("corpus file loads");
        let (frames, regions) = (a.frames, a.regions.len());
        group.bench_function(format!("pixmaps/{file} ({frames} frames)"), |b| {
            let text = std::fs::read_to_string(&path).expect("readable");
            let model = lottie::parse(&path, &text).expect("parses");
            let (w, h) = (a.width, a.height);
            let layers = model.layer_count();
            b.iter_custom(|iters| {
                let start = Instant::now();
                for _ in 0..iters {
                    for f in 0..frames {
                        for l in 0..layers {
                            let t = lottie::Target { layer: l, child: None };
                            let pm =
                                lottie::render(&model, t, model.first_frame() + f as f32, w, h, 1.0, lottie::Pass::All);
                            std::hint::black_box(pm);
                        }
                    }
                }
                start.elapsed()
            })
        });
        group.bench_function(format!("region_frames/{file} ({frames} frames x {regions} regions)"), |b| {
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
