//! # fluidymation
//!
//! Stylizes vector animations with the *moving* appearance of real paint, after
//! Platkevič, Curtis and Sýkora, *Fluidymation: Stylizing Animations Using Natural Dynamics of
//! Artistic Media* (EGSR 2021) and Platkevič's master's thesis (CTU Prague 2021).
//!
//! ```no_run
//! use fluidymation::anim::{self, LoadOptions};
//! use fluidymation::exemplar::{self, SearchPath};
//! use fluidymation::render::{Background, Render, Style};
//! use fluidymation::NoProgress;
//! # fn main() -> fluidymation::Result<()> {
//! // A quick half-size preview: the animation remembers its scale, and the paint texture
//! // is scaled along with the canvas.
//! let a = anim::load("fixtures/demo/waving.json".as_ref(), &LoadOptions::default().scale(0.5))?;
//! // An exemplar in memory (it could as well be generated or imported).
//! let ink = exemplar::find("ink-rims", &SearchPath::standard(&[]))?;
//! let summary = Render::new(&a)
//!     .style_all(Style::named("blue-bloom")) // a bundled exemplar, by name
//!     .style("dress", Style::exemplar(ink))
//!     .style("scarf", Style::still("swatch.jpg")) // one painted image
//!     .style("legs", Style::None) // left flat
//!     .background(Background::Color([1.0, 1.0, 1.0, 1.0]))
//!     .frames(0..12)
//!     .seed(7)
//!     .run("out/demo", &NoProgress)?;
//! for layer in &summary.layers {
//!     println!("{} {:?} {:.1} s", layer.name, layer.exemplar, layer.seconds);
//! }
//! # Ok(()) }
//! ```
//!
//! The pipeline runs in one direction:
//!
//! 1. [`anim`] reads a Lottie file, an SVG frame sequence or a PNG mask sequence and renders
//!    each region (layer) per frame into a flat RGBA image whose alpha is the mask `T^mask`;
//! 2. [`guide`] derives the guidance channels (distance, border, flow, motion extent) of the
//!    exemplar `S` and the target `T`;
//! 3. [`exemplar`] loads, generates and imports style exemplars (`S^rgb`, `S^mask`);
//! 4. [`synth`] runs the Fluidymation synthesis, frame by frame (one layer at a time, for
//!    those who drive the engine themselves);
//! 5. [`render`] runs all of it for a whole animation: every layer synthesized, recolored to
//!    its own colors and composited over the background; [`output`] writes PNG frames and GIFs;
//! 6. [`eval`] measures a stylized sequence, [`quality`] runs the engine on generated targets
//!    and measures it.
//!
//! [`img`] holds the image type every stage uses ([`img::Plane`]), [`seq`] lists numbered
//! frame files, [`Progress`] is how long work reports (and is cancelled), [`Error`] what fails.
//!
//! Not supported in Lottie files, each reported as a warning naming the feature and the layer
//! ([`anim::Region::warnings`]): text and image layers, expressions (the keyframed value is
//! used), effects, layer styles, blend modes, 3D, auto-orient, boolean merge paths, and the
//! offset, pucker-bloat, twist and zig-zag modifiers.
#![warn(missing_docs)]

pub mod anim;
pub(crate) mod composite;
pub mod error;
pub mod eval;
pub mod exemplar;
pub mod guide;
pub mod img;
pub mod limits;
pub mod output;
pub mod progress;
pub mod quality;
pub mod render;
pub(crate) mod resume;
mod rng;
pub mod seq;
pub mod synth;

pub use error::{Error, Result};
pub use progress::{NoProgress, Progress};
pub use render::{Render, Style};
