//! vrpt: a CPU path tracer for seeing and measuring variance reduction in Monte Carlo rendering.
//!
//! Data flows one way: [`scene`] loads an OBJ (+ MTL, + optional `scene.toml`) into a
//! [`scene::Scene`]; [`accel`] builds an obvhs CWBVH over its triangles; [`render`] runs the
//! [`integrator`] over tiles with rayon, drawing every random number from a [`sampler`], into a
//! [`film::Film`]; [`image_io`] writes EXR (linear, with metadata) and PNG (tone-mapped sRGB).
//! The binary (`src/main.rs`) only parses arguments and calls [`commands`].
//!
//! Every pixel is an integral `I = ∫ f(x) dx`, estimated as `(1/N) Σ f(x_i)/p(x_i)`. The axes
//! of variance reduction are where the points come from ([`sampler::SamplerKind`]), how bounce
//! directions are chosen ([`bsdf::Directions`]), and how light is found, placed and chosen
//! ([`lights`]); a [`strategy::Strategy`] names one point on every axis.
//!
//! # Your own sampler
//!
//! A [`sampler::Sampler`] gives the numbers of one pixel sample at a time, in the dimension
//! order of [`sampler::layout`]. [`render::render_passes_with`] renders with any of them, made
//! per pass by a [`render::SamplerFactory`] (a closure `(seed, pass) → sampler`), with every
//! guarantee the built-in samplers have; [`analysis::experiments::Entry::custom`] puts it in
//! `compare` and `converge` beside the built-in ones. Here, a Kronecker sequence
//! `frac(s + i·√q_d)` per dimension `d` (`q_d` the d-th prime: rationally independent steps, so
//! the points fill the cube) with a Cranley–Patterson shift `s` per pixel and dimension, and
//! i.i.d. numbers past the eighth dimension (`examples/custom_sampler.rs` is the whole walk,
//! with a report):
//!
//! ```
//! use glam::{UVec2, Vec2};
//! use vrpt::math::{hash_words, u64_to_unit_f32};
//! use vrpt::render::{render_passes_with, NoProgress, PassPlan, RenderSettings, SamplePass};
//! use vrpt::sampler::Sampler;
//!
//! #[derive(Clone)]
//! struct Kronecker { seed: u64, pixel: UVec2, index: u32, dim: u64 }
//!
//! impl Sampler for Kronecker {
//!     fn start_pixel_sample(&mut self, pixel: UVec2, index: u32) {
//!         (self.pixel, self.index, self.dim) = (pixel, index, 0);
//!     }
//!     fn next_1d(&mut self) -> f32 {
//!         const PRIMES: [u32; 8] = [2, 3, 5, 7, 11, 13, 17, 19];
//!         let key = [self.seed, self.pixel.x as u64, self.pixel.y as u64, self.dim];
//!         let shift = u64_to_unit_f32(hash_words(&key)) as f64;
//!         let x = match PRIMES.get(self.dim as usize) {
//!             Some(&q) => (shift + self.index as f64 * (q as f64).sqrt().fract()).fract() as f32,
//!             None => u64_to_unit_f32(hash_words(&[key[0], key[1], key[2], key[3], self.index as u64])),
//!         };
//!         self.dim += 1;
//!         x.min(vrpt::sampler::ONE_MINUS_EPSILON)
//!     }
//!     fn next_2d(&mut self) -> Vec2 {
//!         Vec2::new(self.next_1d(), self.next_1d())
//!     }
//! }
//!
//! let scene = vrpt::scene::load(std::path::Path::new("scenes/cornell-box"))?;
//! let settings = RenderSettings { width: 8, height: 8, spp: 16, ..Default::default() };
//! let factory = |seed, _: SamplePass| Kronecker { seed, pixel: UVec2::ZERO, index: 0, dim: 0 };
//! let r = render_passes_with(&scene, &settings, &PassPlan::default(), &factory, &NoProgress)?;
//! assert!(r.film.mean_image().iter().all(|p| p.is_finite()));
//! # Ok::<(), vrpt::Error>(())
//! ```
// No unsafe code but the one call a CPU feature check guards: the AVX2 BVH walk (`accel`).
#![deny(unsafe_code)]

pub mod accel;
pub mod analysis;
pub mod bsdf;
pub mod camera;
pub mod commands;
pub mod environment;
pub mod error;
pub mod estimate;
pub mod film;
pub mod guiding;
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
pub mod texture;

pub use error::{Error, Result};
