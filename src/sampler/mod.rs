//! Samplers: where the points `u ∈ [0,1)^d` that feed every random decision come from.
//!
//! A path sample consumes dimensions in the fixed order of [`layout`], each `next_*` call
//! advancing to the next dimension. Every draw is a pure function of (seed, pixel, sample index, dimension), so the
//! image does not depend on the number of threads or on the order in which tiles are rendered.
//! Hot loops are generic over [`Sampler`]; the kind is chosen once, with a `match` on
//! [`SamplerKind`].

#![warn(missing_docs)]

mod independent;
pub mod layout;
mod sobol;
mod strata;
mod stratified;

pub use independent::IndependentSampler;
pub use sobol::SobolSampler;
pub use strata::{grid_shape, permute_index, stratifiable};
pub use stratified::StratifiedSampler;

use glam::{UVec2, Vec2};

/// Every sampler's values lie in `[0, ONE_MINUS_EPSILON]`.
pub use crate::sampling::ONE_MINUS_EPSILON;

/// A source of sample points for one pixel sample at a time.
pub trait Sampler: Clone + Send + Sync {
    /// Start sample `index` of `pixel`: the dimension counter goes back to 0.
    fn start_pixel_sample(&mut self, pixel: UVec2, index: u32);
    /// The next 1D dimension of the current sample, in `[0, 1)`.
    fn next_1d(&mut self) -> f32;
    /// The next 2D dimension of the current sample, in `[0, 1)^2`.
    fn next_2d(&mut self) -> Vec2;
    /// Pass over `n` 1D dimensions of the layout without using them: afterwards the sampler is
    /// where `n` calls of [`Sampler::next_1d`] would leave it. The default draws them; a
    /// sampler whose draws depend on the dimension index only overrides it to advance its
    /// counter, at no cost.
    #[inline]
    fn skip_1d(&mut self, n: u32) {
        for _ in 0..n {
            self.next_1d();
        }
    }
    /// Pass over `n` 2D dimensions: where `n` calls of [`Sampler::next_2d`] would leave it. A
    /// sampler counts a 2D value in its own units (one index for the stratified and
    /// independent samplers, two Sobol dimensions for Sobol), so the layout skips 1D and 2D
    /// values separately and every later decision keeps its dimension.
    #[inline]
    fn skip_2d(&mut self, n: u32) {
        for _ in 0..n {
            self.next_2d();
        }
    }
}

/// Which sampler draws the points (the `--sampler` flag).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum SamplerKind {
    /// Every number i.i.d. uniform.
    Independent,
    /// The lecture's stratification: N strata in 1D, an a×b grid of cells in 2D (a·b = N, as
    /// square as N allows), one uniform point in each, visited in an order that differs per
    /// dimension: the variance is exactly (1/N²) Σ σ²ᵢ over the cells.
    Jittered,
    /// Jittered strata per dimension, their 2D points also multi-jittered (Kensler: each
    /// coordinate alone stratified into N intervals); square spp (16, 64, 256) stratify best in
    /// 2D, a prime spp gives N×1 slabs.
    #[default]
    Stratified,
    /// Owen-scrambled Sobol points (Burley 2020): every dimension of the path jointly
    /// stratified, one scrambled sequence per pixel; powers of two stratify best.
    Sobol,
}

impl std::fmt::Display for SamplerKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&crate::names::value_name(self))
    }
}
