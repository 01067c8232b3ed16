//! The independent sampler: every value is a hash of (seed, pixel, sample index, dimension)
//! mapped to `[0, 1)`: i.i.d. uniform for all practical purposes, and reproducible.

use super::Sampler;
use crate::math::{hash_words, mix64, u64_to_unit_f32};
use glam::{UVec2, Vec2};

/// i.i.d. uniform points, keyed by (seed, pixel, index, dimension).
#[derive(Clone, Debug)]
pub struct IndependentSampler {
    seed: u64,
    key: u64,
    dim: u64,
}

impl IndependentSampler {
    /// A sampler whose draws depend on `seed`.
    pub fn new(seed: u64) -> Self {
        IndependentSampler {
            seed,
            key: 0,
            dim: 0,
        }
    }

    #[inline]
    fn next_hash(&mut self) -> u64 {
        // the key is already a full-avalanche hash: one more mix per dimension suffices
        let h = mix64(self.key ^ self.dim.wrapping_mul(0x632b_e59b_d9b4_e019));
        self.dim += 1;
        h
    }
}

impl Sampler for IndependentSampler {
    #[inline]
    fn start_pixel_sample(&mut self, pixel: UVec2, index: u32) {
        self.key = hash_words(&[
            self.seed,
            ((pixel.x as u64) << 32) | pixel.y as u64,
            index as u64,
        ]);
        self.dim = 0;
    }

    #[inline]
    fn skip_1d(&mut self, n: u32) {
        self.dim += n as u64;
    }

    /// A 2D value is one hash, one dimension index.
    #[inline]
    fn skip_2d(&mut self, n: u32) {
        self.dim += n as u64;
    }

    #[inline]
    fn next_1d(&mut self) -> f32 {
        u64_to_unit_f32(self.next_hash())
    }

    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        // Two independent 24-bit fields of one 64-bit hash.
        let h = self.next_hash();
        Vec2::new(u64_to_unit_f32(h), u64_to_unit_f32(h << 24))
    }
}
