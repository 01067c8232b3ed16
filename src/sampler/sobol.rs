//! The Sobol sampler: Owen-scrambled Sobol points (Burley 2020, "Practical Hash-based Owen
//! Scrambling"), from the `sobol_burley` crate.
//!
//! Each pixel has its own scrambled sequence (its seed a hash of (seed, pixel)); sample `i`,
//! dimension `d` of the path layout is point `i` of that sequence in Sobol dimension `d`. So
//! all dimensions of a path are **one** low-discrepancy point set, not independently shuffled
//! strata: the pixel position and the point on the light (dimensions 0–1 and 3–4 of the
//! layout) are stratified jointly, and every 2D projection is stratified at once. Why joint
//! rather than Burley's padding (independent 4D groups): the layout's first bounce mixes the
//! pixel and the light point, exactly the product that padding leaves unstratified; the
//! measurement is in the closing note of issue 10 (lit-checker slopes).
//!
//! The prefix property: Sobol generator matrices are upper triangular, so the leading `k`
//! digits of every coordinate depend only on the low `k` bits of the index; the crate's
//! index shuffle permutes those bits, so the first `2^k` samples of a pixel hold one point
//! in every elementary interval of the first two dimensions — scrambled or not (tested).
//!
//! Speed (issue 19): a Sobol point is a GF(2)-linear function of its (shuffled, 16-bit) index,
//! so each dimension's function is four tables of 16 entries, one per 4 bits of the index
//! ([`NibbleTables`], 64 KiB for the 256 dimensions, made once from the crate's `sobol_rev`):
//! four lookups instead of a loop over the index's set bits, the same values. The pixel's key is
//! hashed once per pixel and block of samples, not per sample.
//!
//! Limits: the crate's sequences have 2¹⁶ samples and 256 dimensions. Sample `i ≥ 2¹⁶`
//! continues in a fresh sequence (seed hashed with `i / 2¹⁶`), dimension `d ≥ 256` in another
//! (seed hashed with `d / 256`, dimension `d mod 256`): each is an independent uniform point
//! set, so the estimator stays unbiased; it is only not stratified across the seam.

use super::Sampler;
use crate::math::{hash_words, mix64};
use glam::{UVec2, Vec2};
use sobol_burley::parts::{hash, owen_scramble_rev, sobol_rev, u32_to_f32_norm};

/// Samples per scrambled sequence.
pub const SEQUENCE_LEN: u32 = 1 << 16;
/// Dimensions per scrambled sequence.
pub const SEQUENCE_DIMS: u32 = sobol_burley::NUM_DIMENSIONS;

/// Each dimension's Sobol function of the reversed, shuffled index as tables:
/// `sobol_rev(x, d) = ⊕ₖ T[d][k][(x >> (16 + 4k)) & 15]` for the top 16 bits of `x` (the crate
/// reads no others), because `sobol_rev` is linear over GF(2) in `x`.
struct NibbleTables([[[u32; 16]; 4]; SEQUENCE_DIMS as usize]);

impl NibbleTables {
    /// The tables, made at the first use in the process.
    fn get() -> &'static NibbleTables {
        static TABLES: std::sync::OnceLock<Box<NibbleTables>> = std::sync::OnceLock::new();
        TABLES.get_or_init(|| {
            let mut t = Box::new(NibbleTables([[[0; 16]; 4]; SEQUENCE_DIMS as usize]));
            for (d, dim) in t.0.iter_mut().enumerate() {
                for (k, nibble) in dim.iter_mut().enumerate() {
                    for (v, e) in nibble.iter_mut().enumerate() {
                        *e = sobol_rev((v as u32) << (16 + 4 * k), d as u32);
                    }
                }
            }
            t
        })
    }

    /// `sobol_rev(index_rev, d)`.
    #[inline(always)]
    fn sobol_rev(&self, index_rev: u32, d: u32) -> u32 {
        let t = &self.0[d as usize];
        t[0][(index_rev >> 16) as usize & 15]
            ^ t[1][(index_rev >> 20) as usize & 15]
            ^ t[2][(index_rev >> 24) as usize & 15]
            ^ t[3][(index_rev >> 28) as usize & 15]
    }
}

/// Owen-scrambled Sobol points, one sequence per (pixel, block of 2¹⁶ samples, block of 256
/// dimensions).
#[derive(Clone)]
pub struct SobolSampler {
    tables: &'static NibbleTables,
    /// The pixel and sample block whose key `key` holds.
    keyed: (UVec2, u32),
    seed: u64,
    /// Key of the current (pixel, sample block).
    key: u64,
    /// Sequence seed of the current dimension block.
    seq_seed: u32,
    /// The current sample's shuffled, bit-reversed index in its sequence.
    index_rev: u32,
    /// The sample's index within its sequence (kept to reshuffle at a dimension block).
    index: u32,
    /// The dimension block entered for the current sample.
    block: u32,
    dim: u32,
}

impl std::fmt::Debug for SobolSampler {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SobolSampler")
            .field("seed", &self.seed)
            .field("index", &self.index)
            .field("dim", &self.dim)
            .finish_non_exhaustive()
    }
}

impl SobolSampler {
    /// A sampler whose points depend on `seed`.
    pub fn new(seed: u64) -> Self {
        SobolSampler {
            tables: NibbleTables::get(),
            keyed: (UVec2::MAX, u32::MAX),
            seed,
            key: 0,
            seq_seed: 0,
            index_rev: 0,
            index: 0,
            block: 0,
            dim: 0,
        }
    }

    /// Enter the sequence of dimension block `block` for the current sample.
    #[inline]
    fn enter_block(&mut self, block: u32) {
        self.seq_seed = mix64(self.key ^ (block as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)) as u32;
        // the crate's index shuffle (nested uniform scrambling of the index)
        self.index_rev =
            owen_scramble_rev(self.index.reverse_bits(), hash(self.seq_seed ^ 0x79c6_8e4a));
    }

    /// Dimension `d` of the current sample: `sobol_burley::sample(index, d mod 256, seed)`,
    /// with the index shuffle computed once per sample.
    #[inline]
    fn value(&mut self, d: u32) -> f32 {
        let (block, dim) = (d / SEQUENCE_DIMS, d % SEQUENCE_DIMS);
        if block != self.block {
            self.block = block;
            self.enter_block(block);
        }
        let sobol = self.tables.sobol_rev(self.index_rev, dim);
        let scramble = {
            let seed = self.seq_seed.wrapping_mul(0x9c8f_2d3b);
            (dim >> 2)
                ^ seed
                ^ [0x912f_69ba, 0x174f_18ab, 0x691e_72ca, 0xb40c_c1b8][dim as usize & 3]
        };
        u32_to_f32_norm(owen_scramble_rev(sobol, hash(scramble)).reverse_bits())
    }
}

impl Sampler for SobolSampler {
    #[inline]
    fn start_pixel_sample(&mut self, pixel: UVec2, index: u32) {
        let keyed = (pixel, index / SEQUENCE_LEN);
        if keyed != self.keyed {
            self.keyed = keyed;
            self.key = hash_words(&[
                self.seed ^ 0x534f_424f_4c53_4f42, // "SOBOLSOB": other streams than the others
                ((pixel.x as u64) << 32) | pixel.y as u64,
                keyed.1 as u64,
            ]);
        }
        self.index = index % SEQUENCE_LEN;
        self.dim = 0;
        self.block = 0;
        self.enter_block(0);
    }

    #[inline]
    fn skip_1d(&mut self, n: u32) {
        self.dim += n;
    }

    /// A 2D value takes two Sobol dimensions (see [`Sampler::next_2d`] below).
    #[inline]
    fn skip_2d(&mut self, n: u32) {
        self.dim += 2 * n;
    }

    #[inline]
    fn next_1d(&mut self) -> f32 {
        let d = self.dim;
        let v = self.value(d);
        self.dim += 1;
        v
    }

    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        let d = self.dim;
        let v = Vec2::new(self.value(d), self.value(d + 1));
        self.dim += 2;
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The index shuffle computed once per sample gives exactly the crate's `sample`.
    #[test]
    fn equals_the_crates_sample() {
        let mut s = SobolSampler::new(5);
        for index in [0u32, 1, 2, 7, 1000, 65535] {
            s.start_pixel_sample(UVec2::new(3, 4), index);
            let seed = s.seq_seed;
            for d in 0..40 {
                assert_eq!(
                    s.next_1d(),
                    sobol_burley::sample(index, d, seed),
                    "{index} {d}"
                );
            }
        }
    }

    /// Past 2¹⁶ samples and 256 dimensions the values stay in [0, 1) and change sequence.
    #[test]
    fn continues_past_the_crates_limits() {
        let mut s = SobolSampler::new(1);
        s.start_pixel_sample(UVec2::ZERO, 3);
        let a: Vec<f32> = (0..600).map(|_| s.next_1d()).collect();
        s.start_pixel_sample(UVec2::ZERO, 3 + SEQUENCE_LEN);
        let b: Vec<f32> = (0..600).map(|_| s.next_1d()).collect();
        assert!(a.iter().chain(&b).all(|&v| (0.0..1.0).contains(&v)));
        assert_ne!(a[..10], b[..10]);
        // dimension 256 starts another sequence, not a copy of dimension 0
        assert_ne!(a[0], a[256]);
    }
}
