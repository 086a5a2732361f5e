//! Renders the bundled demo with the library's `Render` builder, as `fluidymation render` does:
//! every layer painted with its style, recolored to its own colors, composited and written as
//! PNG frames. Cheap: a quarter-size canvas and four frames.
//!
//! `cargo run --release --example render_demo [-- OUT_DIR]` (default `out/render_demo`).

use fluidymation::anim::{self, LoadOptions};
use fluidymation::exemplar::{self, SearchPath};
use fluidymation::render::{Background, Render, Style};
use std::path::PathBuf;

fn main() -> fluidymation::Result<()> {
    let out = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "out/render_demo".into()));
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    // A quarter-size preview: the animation knows its scale, and the render scales the paint
    // texture along with it.
    let demo = anim::load(&root.join("fixtures/demo/waving.json"), &LoadOptions::default().scale(0.25))?;
    println!(
        "{}: {}x{}, {} frames at scale {}",
        demo.path.display(),
        demo.width,
        demo.height,
        demo.frames,
        demo.scale()
    );
    // An exemplar in memory: here a bundled one, but it could be generated
    // (`exemplar::generate`) or imported from footage (`exemplar::import`).
    let ink = exemplar::find("ink-rims", &SearchPath::standard(&[]))?;
    let summary = Render::new(&demo)
        .style_all(Style::named("blue-bloom")) // a bundled exemplar, by name
        .style("dress", Style::exemplar(ink))
        .style("legs", Style::None) // left flat
        .background(Background::Color([0.98, 0.96, 0.92, 1.0]))
        .frames(0..4)
        .seed(7)
        .run(&out, &|stage: &str, done: usize, total: usize| {
            if stage == "frames" {
                println!("frame {done}/{total}");
            }
            true
        })?;
    for l in &summary.layers {
        println!("  {:02} {:<8} {:<12} {:.1} s", l.index, l.name, l.exemplar.as_deref().unwrap_or("(flat)"), l.seconds);
    }
    println!("{} frames in {:.1} s -> {}", summary.frames, summary.seconds, summary.frame_dir.display());
    Ok(())
}
