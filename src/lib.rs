//! # fluidymation
//!
//! Stylizes vector animations with the *moving* appearance of real paint, after
//! Platkevič, Curtis and Sýkora, *Fluidymation: Stylizing Animations Using Natural Dynamics of
//! Artistic Media* (EGSR 2021) and Platkevič's master's thesis (CTU Prague 2021).
//!
//! The pipeline runs in one direction:
//!
//! 1. [`anim`] reads a Lottie file, an SVG frame sequence or a PNG mask sequence and renders
//!    each region (layer) per frame into a flat RGBA image whose alpha is the mask `T^mask`;
//! 2. [`guide`] derives the guidance channels (distance, border, flow, motion extent) of the
//!    exemplar `S` and the target `T`;
//! 3. [`exemplar`] loads, generates and imports style exemplars (`S^rgb`, `S^mask`);
//! 4. [`synth`] runs the Fluidymation synthesis, frame by frame;
//! 5. [`composite`] recolors and layers the results, [`output`] writes PNG frames and a GIF;
//! 6. [`eval`] measures a stylized sequence, [`quality`] runs the engine on generated targets
//!    and measures it.
#![warn(missing_docs)]

pub mod anim;
pub mod composite;
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
pub mod resume;
mod rng;
pub mod seq;
pub mod synth;
pub mod workload;

pub use error::{Error, Result};
pub use progress::{NoProgress, Progress};
