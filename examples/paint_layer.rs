//! Paints one layer of the bundled demo with the library API and writes it as RGBA PNGs in the
//! exemplar's colors (alpha = the target mask), like `fluidymation synth`.
//!
//! `cargo run --release --example paint_layer [-- OUT_DIR]` (default `out/paint_layer`).

use fluidymation::img::{self, Plane};
use fluidymation::synth::{self, Params, Source};
use fluidymation::{anim, exemplar};
use std::path::PathBuf;

fn main() -> fluidymation::Result<()> {
    let out = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "out/paint_layer".into()));
    std::fs::create_dir_all(&out).map_err(|e| fluidymation::Error::io(&out, e))?;
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let anim = anim::load(&root.join("fixtures/demo/waving.json"), &Default::default())?;
    let dress = anim.find_region("dress")?;
    let ex = exemplar::find("blue-bloom", &exemplar::SearchPath::standard(&[]))?;
    let params = Params::builder().seed(7).lambda(4.0).build()?;
    let frames = 12.min(anim.frames);
    // The exemplar prepared, the target's guides (their backward pass runs here) and the
    // synthesizer given the target's extent scale.
    let (mut synth, masks) =
        synth::start(|| Source::prepare(&ex, &params), &params, frames, |i| Ok(anim.render(dress, i)?.coverage()))?;
    for (k, g) in masks.enumerate() {
        // T^rgb in the exemplar's colors; alpha = the target mask.
        let frame = synth.step(&g?)?;
        let rgba = Plane::from_fn(frame.rgb.width(), frame.rgb.height(), |x, y| {
            let c = frame.rgb.get(x, y);
            [c[0], c[1], c[2], if frame.mask.get(x, y) { 1.0 } else { 0.0 }]
        });
        let path = out.join(format!("{:04}.png", k + 1));
        img::save_rgba(&path, &rgba)?;
        println!("{}", path.display());
    }
    Ok(())
}
