//! One synthesized frame of the engine (issue 5), on the horse-like workload of
//! `src/cli/workload.rs` scaled to 500×400 (≈ 27 000 masked pixels, a quarter of the
//! paper's `horse`) so that a criterion sample stays short; the full-size end-to-end figure
//! comes from `fluidymation bench`.
//!
//! The measured frame is a steady-state one (the third): the state after the first two frames
//! (NNF, time shift, Ω) is saved once and restored before every iteration, so each iteration
//! runs the whole multi-scale step with the temporal term, exactly as inside a sequence.
//!
//! `cargo bench --bench synth`

use criterion::{Criterion, criterion_group, criterion_main};
use fluidymation::guide::{FrameGuides, GuideStream};
use fluidymation::synth::{Params, Source, Synthesizer};
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

#[path = "../src/cli/workload.rs"]
mod workload;

const W: usize = 500;
const H: usize = 400;

fn synth(c: &mut Criterion) {
    let exemplar = workload::horse_exemplar().expect("the generated exemplar");
    let params = Params::default();
    let source = Source::prepare(&exemplar, &params).expect("exemplar preparation");
    let guides: Vec<FrameGuides> = GuideStream::new(3, |k| Ok(workload::horse_mask(W, H, k)), params.guide())
        .expect("target guides")
        .map(|g| g.expect("target guides"))
        .collect();
    let mut warm = Synthesizer::new(source.clone(), params.clone()).expect("synthesizer");
    for g in &guides[..2] {
        warm.step(g).expect("warm-up frame");
    }
    let state = warm.save_state();

    let mut g = c.benchmark_group("synth_500x400");
    g.sample_size(10).measurement_time(Duration::from_secs(30));
    g.bench_function("steady_frame", |b| {
        b.iter(|| {
            let mut s = Synthesizer::new(source.clone(), params.clone()).expect("synthesizer");
            s.load_state(&state, Path::new("bench")).expect("state");
            black_box(s.step(&guides[2]).expect("frame"))
        });
    });
    g.bench_function("first_frame", |b| {
        b.iter(|| {
            let mut s = Synthesizer::new(source.clone(), params.clone()).expect("synthesizer");
            black_box(s.step(&guides[0]).expect("frame"))
        });
    });
    g.finish();
}

criterion_group!(benches, synth);
criterion_main!(benches);
