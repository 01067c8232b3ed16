//! The stratified (jittered) sampler, with no stored sample tables.
//!
//! With N samples per pixel per pass, a 1D dimension is split into N strata `[k/N, (k+1)/N)` and
//! a 2D dimension into an a×b grid (a·b = N, a the largest divisor of N not above √N, so a prime
//! N gives a 1×N grid of slabs: square N stratify best). Sample `j` of the pass takes stratum
//! `π_d(j)`, where `π_d` is Kensler's hashed permutation of `0..N` keyed by (seed, pixel, pass,
//! dimension) — a different order per dimension, so dimensions are not correlated — and is
//! jittered uniformly inside it (the permutation key also holds N, so sets of different sizes
//! never share strata orders). Each pass of N samples (sample indices `pN .. (p+1)N`) is a
//! complete, independent stratified set, so runs of several passes stay unbiased and
//! stratified pass by pass.

use super::{Sampler, ONE_MINUS_EPSILON};
use crate::math::{hash_words, mix64, u64_to_unit_f32};
use glam::{UVec2, Vec2};

/// The 2D grid `(a, b)` for N strata: `a·b = N`, `a ≤ b`, as square as N allows.
pub fn grid_shape(n: u32) -> (u32, u32) {
    let n = n.max(1);
    let mut a = (n as f64).sqrt() as u32;
    while a > 1 && !n.is_multiple_of(a) {
        a -= 1;
    }
    let a = a.max(1);
    (a, n / a)
}

/// Element `i` of a pseudo-random permutation of `0..n` chosen by `key` (Kensler 2013,
/// "Correlated multi-jittered sampling": a keyed bijection on the next power of two, with cycle
/// walking back into `0..n`).
#[inline]
pub fn permute_index(i: u32, n: u32, key: u32) -> u32 {
    if n <= 1 {
        return 0;
    }
    permute_with(i, &FastDiv::new(n), mask_of(n), key)
}

/// The smallest `2^k − 1 ≥ n − 1`.
fn mask_of(n: u32) -> u32 {
    let mut w = n.max(1) - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    w
}

/// [`permute_index`] with the divisor and mask of `n` precomputed (n ≥ 2).
#[inline]
fn permute_with(mut i: u32, n: &FastDiv, w: u32, key: u32) -> u32 {
    let p = key;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170_893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | p >> 27);
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < n.d {
            break;
        }
    }
    // (i + p) mod n without overflow: i < n, so add p mod n and subtract n once if needed
    let r = i + n.rem(p);
    if r >= n.d {
        r - n.d
    } else {
        r
    }
}

/// Division and remainder by a fixed `d` with one multiplication each (Lemire, Kaser & Kurz
/// 2019, "Faster remainder by direct computation"): `m = ⌊(2⁶⁴ − 1)/d⌋ + 1`, then
/// `a / d = ⌊m·a / 2⁶⁴⌋` and `a mod d = ⌊(m·a mod 2⁶⁴)·d / 2⁶⁴⌋`, exact for all 32-bit `a`.
#[derive(Clone, Copy, Debug)]
struct FastDiv {
    d: u32,
    m: u64,
}

impl FastDiv {
    fn new(d: u32) -> Self {
        let d = d.max(1);
        FastDiv {
            d,
            m: (u64::MAX / d as u64).wrapping_add(1),
        }
    }

    #[inline]
    fn div(&self, a: u32) -> u32 {
        if self.d == 1 {
            return a;
        }
        ((self.m as u128 * a as u128) >> 64) as u32
    }

    #[inline]
    fn rem(&self, a: u32) -> u32 {
        let low = self.m.wrapping_mul(a as u64);
        ((low as u128 * self.d as u128) >> 64) as u32
    }
}

/// `s + j` for stratum `s` and jitter `j ∈ [0, 1)`, kept below `s + 1`: in f32, `s + j` rounds
/// up to `s + 1` when `j` is within half an ulp of `s` of 1, which would put the sample on the
/// next stratum's boundary.
#[inline]
fn jitter_in(s: u32, j: f32) -> f32 {
    (s as f32 + j).min(((s + 1) as f32).next_down())
}

/// Jittered strata per dimension, N samples per pixel per pass.
#[derive(Clone, Debug)]
pub struct StratifiedSampler {
    seed: u64,
    n: u32,
    grid: (u32, u32),
    /// Division by N and by the grid width, the permutation mask, and 1/N, 1/a, 1/b.
    div_n: FastDiv,
    div_a: FastDiv,
    mask: u32,
    inv: (f32, f32, f32),
    /// Key of the current (pixel, pass, N).
    key: u64,
    /// Index of the current sample within its pass.
    j: u32,
    dim: u64,
}

impl StratifiedSampler {
    /// A sampler for `samples_per_pass` samples per pixel per pass (normally the spp).
    pub fn new(seed: u64, samples_per_pass: u32) -> Self {
        let n = samples_per_pass.max(1);
        let (a, b) = grid_shape(n);
        StratifiedSampler {
            seed,
            n,
            grid: (a, b),
            div_n: FastDiv::new(n),
            div_a: FastDiv::new(a),
            mask: mask_of(n),
            inv: (1.0 / n as f32, 1.0 / a as f32, 1.0 / b as f32),
            key: 0,
            j: 0,
            dim: 0,
        }
    }

    /// (stratum of the current sample, jitter hash) in the next dimension.
    #[inline(always)]
    fn next_stratum(&mut self) -> (u32, u64) {
        let dk = mix64(self.key ^ self.dim.wrapping_mul(0xd6e8_feb8_6659_fd93));
        self.dim += 1;
        let jitter = mix64(dk ^ (self.j as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let s = if self.n > 1 {
            permute_with(self.j, &self.div_n, self.mask, dk as u32)
        } else {
            0
        };
        (s, jitter)
    }
}

impl Sampler for StratifiedSampler {
    #[inline]
    fn start_pixel_sample(&mut self, pixel: UVec2, index: u32) {
        let pass = self.div_n.div(index);
        self.j = index - pass * self.n;
        self.key = hash_words(&[
            self.seed ^ 0x5354_5241_5449_4649, // "STRATIFI": other streams than independent
            ((pixel.x as u64) << 32) | pixel.y as u64,
            ((self.n as u64) << 32) | pass as u64,
        ]);
        self.dim = 0;
    }

    #[inline]
    fn skip(&mut self, n: u32) {
        self.dim += n as u64;
    }

    #[inline(always)]
    fn next_1d(&mut self) -> f32 {
        let (s, h) = self.next_stratum();
        (jitter_in(s, u64_to_unit_f32(h)) * self.inv.0).min(ONE_MINUS_EPSILON)
    }

    #[inline(always)]
    fn next_2d(&mut self) -> Vec2 {
        let (s, h) = self.next_stratum();
        let sy = self.div_a.div(s);
        let sx = s - sy * self.grid.0;
        Vec2::new(
            (jitter_in(sx, u64_to_unit_f32(h)) * self.inv.1).min(ONE_MINUS_EPSILON),
            (jitter_in(sy, u64_to_unit_f32(h << 24)) * self.inv.2).min(ONE_MINUS_EPSILON),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_shapes() {
        assert_eq!(grid_shape(16), (4, 4));
        assert_eq!(grid_shape(8), (2, 4));
        assert_eq!(grid_shape(7), (1, 7));
        assert_eq!(grid_shape(1), (1, 1));
        assert_eq!(grid_shape(4096), (64, 64));
    }

    #[test]
    fn fast_division_is_exact() {
        for d in [1u32, 2, 3, 7, 16, 17, 100, 4096, 65535, 1 << 20, u32::MAX] {
            let f = FastDiv::new(d);
            for a in [
                0u32,
                1,
                2,
                5,
                99,
                4095,
                4096,
                65536,
                1 << 31,
                u32::MAX - 1,
                u32::MAX,
            ] {
                assert_eq!(f.div(a), a / d, "{a}/{d}");
                assert_eq!(f.rem(a), a % d, "{a}%{d}");
            }
        }
    }

    #[test]
    fn permutation_is_a_bijection() {
        for n in [1u32, 2, 3, 16, 17, 100, 256] {
            for key in [0u32, 1, 0xdead_beef] {
                let mut seen = vec![false; n as usize];
                for i in 0..n {
                    let p = permute_index(i, n, key) as usize;
                    assert!(!seen[p], "n={n} key={key}: {p} twice");
                    seen[p] = true;
                }
            }
        }
    }
}
