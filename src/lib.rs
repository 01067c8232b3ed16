//! vrpt: a CPU path tracer for seeing and measuring variance reduction in Monte Carlo rendering.
//!
//! Data flows one way: [`scene`] loads an OBJ (+ MTL, + optional `scene.toml`) into a
//! [`scene::Scene`]; [`accel`] builds an obvhs CWBVH over its triangles; [`render`] runs the
//! [`integrator`] over tiles with rayon, drawing every random number from a [`sampler`], into a
//! [`film::Film`]; [`image_io`] writes EXR (linear, with metadata) and PNG (tone-mapped sRGB).
//! The binary (`src/main.rs`) only parses arguments and calls [`cli`].
//!
//! Every pixel is an integral `I = ∫ f(x) dx`, estimated as `(1/N) Σ f(x_i)/p(x_i)`. The two axes
//! of variance reduction are where the points come from ([`sampler::SamplerKind`]) and how bounce
//! directions are chosen ([`material::Directions`]).
#![forbid(unsafe_code)]

pub mod accel;
pub mod analysis;
pub mod bsdf;
pub mod camera;
pub mod commands;
pub mod error;
pub mod film;
pub mod image_io;
pub mod integrator;
pub mod lights;
pub mod limits;
pub mod material;
pub mod math;
pub mod names;
pub mod output;
pub mod render;
pub mod sampler;
pub mod sampling;
pub mod scene;
pub mod stats;
pub mod strategy;

pub use error::{Error, Result};
