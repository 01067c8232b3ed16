//! The stratified samplers: `stratified` (jittered strata, 2D points multi-jittered) and
//! `jittered` (the lecture's: one uniform point per stratum; [`StratifiedSampler::jittered`]).
//!
//! With N samples per pixel per pass, a 1D dimension is split into N strata `[k/N, (k+1)/N)` and
//! a 2D dimension into an a×b grid (a·b = N, a the largest divisor of N not above √N, so a prime
//! N gives a 1×N grid of slabs: square N stratify best). Sample `j` of the pass takes stratum
//! `π_d(j)`, a random permutation of `0..N` of its own for each (seed, pixel, pass, dimension) —
//! a different order per dimension, so dimensions are not correlated — and is jittered
//! uniformly inside it.
//!
//! 2D points are Kensler's correlated multi-jittered pattern: besides its a×b cell `(sx, sy)`,
//! a point sits in one of the b sub-columns of its column and one of the a sub-rows of its row,
//! `x = (sx·b + σ(sy) + ξ₁)/N`, `y = (sy·a + τ(sx) + ξ₂)/N`, with σ, τ random permutations of
//! their own for each (pixel, pass, dimension). The N samples keep one per cell, and each
//! coordinate alone is stratified into N intervals (a Latin hypercube): what an axis-aligned
//! edge in a pixel, a shadow of an axis-aligned box or a rectangular light integrates. With
//! jitter inside cells only, a coordinate was stratified into a intervals (8 at 64 spp, against
//! 64 now); on Mitsuba's Cornell box at 64 spp the change lowered vrpt's MSE from 2.08e-4 to
//! 1.24e-4 (median of 5 seeds; Mitsuba's own multijitter sampler: 1.15e-4).
//!
//! **How the permutations are made.** For passes of at most [`TABLE_MAX_N`] samples and the
//! first [`TABLE_DIMS`] dimensions, each dimension's π (and σ, τ) is a table, built at the
//! dimension's first draw in a (pixel, pass) by a Fisher–Yates shuffle driven by a hash of
//! (seed, pixel, pass, N, dimension), and a 2D table stores each sample's two stratum indices:
//! a draw is a lookup and one jitter hash (issue 19: the hashed permutation per draw made a
//! sample cost a third more than an independent one). Other passes and dimensions evaluate
//! Kensler's hashed permutation ([`permute_index`]) per draw. Either way a value is a pure
//! function of (seed, pixel, sample index, dimension, N), whatever order or batches the samples
//! are drawn in; the render batches whole passes where it can, so a table is built once per
//! pixel and pass.
//!
//! Each pass of N samples (sample indices `pN .. (p+1)N`) is a
//! complete, independent stratified set, so runs of several passes stay unbiased and
//! stratified pass by pass.
//!
//! **Which set a sample belongs to.** A set is keyed by its size N and its first sample index
//! `s`: a set whose `s` is a multiple of N by `(N, s/N)` (the pass number), any other by
//! `(N, s/N, s)`. So two sets share points only when they are the same set (same N, same
//! first index), and two different sample indices never draw the same points, whatever ranges
//! of which sets two renders took: a render cut inside its set (Ctrl-C, a time limit) and a
//! resume from the next index with the same N (`--first-sample`) are independent, and `vrpt
//! merge` of the two counts no sample twice. (Keyed by `⌊s/N⌋` alone, a set starting at 5
//! was the set starting at 0 again, one slot on.)

use super::strata::{grid_shape, mask_of, permute_with, shuffle, uniform, FastDiv};
use super::{Sampler, ONE_MINUS_EPSILON};
use crate::math::{hash_words, mix64};
use glam::{UVec2, Vec2};

/// `s + j` for stratum `s` and jitter `j ∈ [0, 1)`, kept below `s + 1`: in f32, `s + j` rounds
/// up to `s + 1` when `j` is within half an ulp of `s` of 1, which would put the sample on the
/// next stratum's boundary.
#[inline]
fn jitter_in(s: u32, j: f32) -> f32 {
    (s as f32 + j).min(((s + 1) as f32).next_down())
}

/// The largest pass whose strata orders are tables (see the module doc): a table of N `u32`
/// per dimension, 16 KiB at 4096.
pub const TABLE_MAX_N: u32 = 4096;
/// The dimensions (from 0) whose strata orders are tables: the camera and the first three
/// bounces of the layout, which nearly every sample draws. A table costs N shuffle steps per
/// pixel and pass whether one sample or all draw the dimension, and later bounces are drawn by
/// the few paths that Russian roulette and escapes leave (tables for all 37 dimensions of depth
/// 8 were 17 % of a Cornell box render's instructions): those are hashed per draw.
pub const TABLE_DIMS: u32 = 16;

/// A dropped sampler's buffers (tags, table, scratch), kept per thread for the next one.
type Buffers = (Vec<u64>, Vec<u32>, Vec<u32>);

thread_local! {
    static SPARE: std::cell::RefCell<Vec<Buffers>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// The most buffers a thread keeps.
const SPARE_MAX: usize = 4;

impl Drop for StratifiedSampler {
    fn drop(&mut self) {
        let buffers = (
            std::mem::take(&mut self.tags),
            std::mem::take(&mut self.table),
            std::mem::take(&mut self.scratch),
        );
        // a thread being torn down has no pool left to return to: the buffers are then freed
        let _ = SPARE.try_with(|s| {
            let mut s = s.borrow_mut();
            if s.len() < SPARE_MAX {
                s.push(buffers);
            }
        });
    }
}

/// Jittered strata per dimension, N samples per pixel per pass.
#[derive(Clone, Debug)]
pub struct StratifiedSampler {
    seed: u64,
    n: u32,
    grid: (u32, u32),
    /// Division by N, by the grid width a and height b, the permutation masks of N, a and b,
    /// and 1/N.
    div_n: FastDiv,
    div_a: FastDiv,
    div_b: FastDiv,
    mask: u32,
    mask_a: u32,
    mask_b: u32,
    inv: f32,
    /// `log2 N` when N is a power of two up to 2²⁴ (exact placement in a stratum), else none.
    log2: Option<u32>,
    /// 2D points multi-jittered (each coordinate also stratified into N intervals: the
    /// `stratified` sampler), or jittered only (one uniform point per cell: `jittered`).
    multi: bool,
    /// Key of the current (pixel, pass, N), the pixel and pass it belongs to, and the count of
    /// (pixel, pass)es entered (a table is current when its tag holds this generation).
    key: u64,
    pixel: UVec2,
    pass: u32,
    generation: u32,
    /// Index of the current sample within its pass.
    j: u32,
    dim: u32,
    /// Index of the first sample of the first pass, that pass's number (`origin / N`), and
    /// whether `origin` is a multiple of N (then every set's first index is).
    origin: u32,
    pass_base: u32,
    aligned: bool,
    /// Whether this N uses tables, their tags per dimension, the tables (N entries per
    /// dimension: a stratum in 1D, `x | y << 16` stratum indices in 2D), and room for σ, τ.
    tables: bool,
    /// Per dimension: `2 · generation + (1 if 2D)` of the table it holds (0: none).
    tags: Vec<u64>,
    table: Vec<u32>,
    scratch: Vec<u32>,
}

impl StratifiedSampler {
    /// A sampler for `samples_per_pass` samples per pixel per pass (normally the spp), passes
    /// starting at sample 0.
    pub fn new(seed: u64, samples_per_pass: u32) -> Self {
        Self::with_origin(seed, samples_per_pass, 0)
    }

    /// A sampler whose passes of `samples_per_pass` start at sample `origin`: sample `i` is
    /// number `(i − origin) mod N` of the set that starts at `origin + ⌊(i − origin)/N⌋·N`, so
    /// an origin that is a multiple of N gives the passes of [`StratifiedSampler::new`], and a
    /// shorter last pass of a render (spp not a multiple of the pass size) is one whole set of
    /// its own size. Sets that start at different indices are independent (the module doc).
    /// Indices below `origin` are not valid.
    pub fn with_origin(seed: u64, samples_per_pass: u32, origin: u32) -> Self {
        Self::make(seed, samples_per_pass, origin, true)
    }

    /// The lecture's stratification, `--sampler jittered`: as [`StratifiedSampler::with_origin`]
    /// (the same strata in 1D, the same a×b cells in 2D, visited in a random order per
    /// dimension), but a 2D point is uniform in its cell, with no constraint between cells: the
    /// estimator's variance is then exactly `(1/N²) Σᵢ σ²ᵢ` over the cells. Other streams than
    /// `stratified`'s.
    pub fn jittered(seed: u64, samples_per_pass: u32, origin: u32) -> Self {
        Self::make(
            seed ^ 0x4a49_5454_4552_4544,
            samples_per_pass,
            origin,
            false,
        ) // "JITTERED"
    }

    fn make(seed: u64, samples_per_pass: u32, origin: u32, multi: bool) -> Self {
        let n = samples_per_pass.max(1);
        let (a, b) = grid_shape(n);
        // buffers a dropped sampler of this thread left (an adaptive round makes one sampler
        // per pixel: allocating them anew cost 6% of its time); emptied, so no stale tag of the
        // old sampler can pass for current
        let (mut tags, mut table, mut scratch) =
            SPARE.with(|s| s.borrow_mut().pop()).unwrap_or_default();
        tags.clear();
        table.clear();
        scratch.clear();
        StratifiedSampler {
            seed,
            n,
            grid: (a, b),
            div_n: FastDiv::new(n),
            div_a: FastDiv::new(a),
            div_b: FastDiv::new(b),
            mask: mask_of(n),
            mask_a: mask_of(a),
            mask_b: mask_of(b),
            inv: 1.0 / n as f32,
            log2: (n.is_power_of_two() && n <= 1 << 24).then(|| n.trailing_zeros()),
            multi,
            key: 0,
            pixel: UVec2::MAX,
            pass: u32::MAX,
            generation: 0,
            j: 0,
            dim: 0,
            origin,
            pass_base: origin / n,
            aligned: origin.is_multiple_of(n),
            tables: (2..=TABLE_MAX_N).contains(&n),
            tags,
            table,
            scratch,
        }
    }

    /// The key of dimension `d` in the current (pixel, pass): seeds its shuffles, its jitter
    /// and its hashed permutations.
    #[inline(always)]
    fn dim_key(&self, d: u32) -> u64 {
        mix64(self.key ^ (d as u64).wrapping_mul(0xd6e8_feb8_6659_fd93))
    }

    /// Entry `self.j` of dimension `d`'s table (`d` < TABLE_DIMS) for the current (pixel,
    /// pass), built first if it is not current: π by Fisher–Yates; for 2D also σ, τ, and each
    /// entry then holds the sample's x and y stratum indices.
    #[inline(always)]
    fn table_entry(&mut self, d: u32, two_d: bool) -> u32 {
        let want = 2 * self.generation as u64 + two_d as u64;
        if self.tags.get(d as usize) != Some(&want) {
            self.build(d, two_d);
        }
        self.table[(d * self.n + self.j) as usize]
    }

    #[cold]
    #[inline(never)]
    fn build(&mut self, d: u32, two_d: bool) {
        let n = self.n as usize;
        if self.tags.len() <= d as usize {
            self.tags.resize(d as usize + 1, 0);
            self.table.resize((d as usize + 1) * n, 0);
        }
        let mut draws = self.dim_key(d);
        let t = &mut self.table[d as usize * n..(d as usize + 1) * n];
        if two_d && !self.multi {
            // each cell's point uniform in it: a sub-column of its b and a sub-row of its a,
            // each uniform and independent (the jitter places it inside the sub-cell)
            let (a, b) = self.grid;
            self.scratch.clear();
            self.scratch.resize(2 * n, 0);
            let (px, py) = self.scratch.split_at_mut(n);
            uniform(px, b, &mut draws);
            uniform(py, a, &mut draws);
            for (k, e) in t.iter_mut().enumerate() {
                let (sx, sy) = (k as u32 % a, k as u32 / a);
                *e = (sx * b + px[k]) | (sy * a + py[k]) << 16;
            }
        } else if two_d {
            // σ (b sub-columns) and τ (a sub-rows), and a random cyclic shift per column (c)
            // and per row (r): column sx's sub-columns are σ shifted by c[sx], row sy's sub-rows
            // τ shifted by r[sy]. Then the cells' packed stratum indices in cell order (cell
            // sy·a + sx), shuffled: entry j is cell π(j)'s (x, y), π uniform
            let (a, b) = self.grid;
            let (au, bu) = (a as usize, b as usize);
            self.scratch.clear();
            self.scratch.extend(0..b);
            self.scratch.extend(0..a);
            self.scratch.resize(2 * (au + bu), 0);
            let (sigma, rest) = self.scratch.split_at_mut(bu);
            let (tau, rest) = rest.split_at_mut(au);
            let (c, r) = rest.split_at_mut(au);
            shuffle(sigma, &mut draws);
            shuffle(tau, &mut draws);
            uniform(c, b, &mut draws);
            uniform(r, a, &mut draws);
            for ((row, sy), (&sig, &rs)) in t
                .chunks_exact_mut(au)
                .zip(0u32..)
                .zip(sigma.iter().zip(r.iter()))
            {
                for ((e, sx), (&ta, &cs)) in
                    row.iter_mut().zip(0u32..).zip(tau.iter().zip(c.iter()))
                {
                    let px = if sig + cs >= b {
                        sig + cs - b
                    } else {
                        sig + cs
                    };
                    let py = if ta + rs >= a { ta + rs - a } else { ta + rs };
                    *e = (sx * b + px) | (sy * a + py) << 16;
                }
            }
        } else {
            for (e, i) in t.iter_mut().zip(0u32..) {
                *e = i;
            }
        }
        shuffle(t, &mut draws);
        self.tags[d as usize] = 2 * self.generation as u64 + two_d as u64;
    }

    /// The value in stratum `s` of N at jitter `r` (the top 24 bits of `r`): `(s + r/2²⁴)/N`,
    /// strictly inside the stratum. For N = 2^k the value's 24 bits are s's k bits then r's top
    /// 24 − k: exact, no rounding; else the float sum is kept below the next stratum.
    #[inline(always)]
    fn place(&self, s: u32, r: u64) -> f32 {
        let r24 = (r >> 40) as u32;
        match self.log2 {
            Some(k) => ((s << (24 - k)) | (r24 >> k)) as f32 * (1.0 / (1u32 << 24) as f32),
            None => (jitter_in(s, r24 as f32 * (1.0 / (1u32 << 24) as f32)) * self.inv)
                .min(ONE_MINUS_EPSILON),
        }
    }

    /// The current sample's jitter hash in dimension `d`.
    #[inline(always)]
    fn jitter(&self, d: u32) -> u64 {
        mix64(
            self.key
                ^ (d as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
                ^ (self.j as u64).wrapping_mul(0xbf58_476d_1ce4_e5b9),
        )
    }
}

impl Sampler for StratifiedSampler {
    #[inline]
    fn start_pixel_sample(&mut self, pixel: UVec2, index: u32) {
        let rel = index.wrapping_sub(self.origin);
        let p = self.div_n.div(rel);
        self.j = rel - p * self.n;
        let pass = p + self.pass_base;
        if (pixel, pass) != (self.pixel, self.pass) {
            (self.pixel, self.pass) = (pixel, pass);
            let words = [
                self.seed ^ 0x5354_5241_5449_4649, // "STRATIFI": other streams than independent
                ((pixel.x as u64) << 32) | pixel.y as u64,
                ((self.n as u64) << 32) | pass as u64,
                // a set off the grid of multiples of N: its first index too (module doc)
                self.origin as u64 + p as u64 * self.n as u64,
            ];
            self.key = hash_words(if self.aligned { &words[..3] } else { &words });
            // a new generation makes every table stale (tags hold 2·generation + kind in a
            // u64, so a wrapped u32 generation cannot look current: it restarts at 1 below)
            self.generation = self.generation.wrapping_add(1);
            if self.generation == 0 {
                self.generation = 1;
                self.tags.iter_mut().for_each(|t| *t = 0);
            }
        }
        self.dim = 0;
    }

    #[inline]
    fn skip_1d(&mut self, n: u32) {
        self.dim += n;
    }

    /// A 2D value is one stratum of one dimension index.
    #[inline]
    fn skip_2d(&mut self, n: u32) {
        self.dim += n;
    }

    #[inline(always)]
    fn next_1d(&mut self) -> f32 {
        let d = self.dim;
        self.dim += 1;
        let h = self.jitter(d);
        let s = if self.tables && d < TABLE_DIMS {
            self.table_entry(d, false)
        } else if self.n > 1 {
            permute_with(self.j, &self.div_n, self.mask, self.dim_key(d) as u32)
        } else {
            0
        };
        self.place(s, h)
    }

    /// Kensler's correlated multi-jitter: cell `(sx, sy) = π(j)` of the a×b grid, sub-column
    /// `σ(sy)` of its b, sub-row `τ(sx)` of its a, with σ and τ one permutation each per
    /// (pixel, pass, dimension), so a column holds every sub-column once and a row every
    /// sub-row. π, σ and τ are independent (from one shuffle stream, or independent keys):
    /// correlated σ and τ left sub-cells unsampled (a bias, found in an earlier version).
    #[inline(always)]
    fn next_2d(&mut self) -> Vec2 {
        let d = self.dim;
        self.dim += 1;
        let h = self.jitter(d);
        let (x, y) = if self.tables && d < TABLE_DIMS {
            let e = self.table_entry(d, true);
            (e & 0xffff, e >> 16)
        } else {
            let dk = self.dim_key(d);
            let s = if self.n > 1 {
                permute_with(self.j, &self.div_n, self.mask, dk as u32)
            } else {
                0
            };
            let (a, b) = self.grid;
            let sy = self.div_a.div(s);
            let sx = s - sy * a;
            if !self.multi {
                // a uniform sub-column and sub-row (Lemire's multiply-shift of 32 hashed bits:
                // a bias below b/2³²)
                let k = mix64(dk ^ (self.j as u64).wrapping_mul(0x94d0_49bb_1331_11eb));
                let px = (((k & 0xffff_ffff) * b as u64) >> 32) as u32;
                let py = (((k >> 32) * a as u64) >> 32) as u32;
                return Vec2::new(self.place(sx * b + px, h), self.place(sy * a + py, h << 24));
            }
            let px = if b > 1 {
                let k = mix64(dk ^ 0xd1b5_4a32_d192_ed03);
                permute_with(sy, &self.div_b, self.mask_b, k as u32)
            } else {
                0
            };
            let py = if a > 1 {
                let k = mix64(dk ^ 0xaef1_7502_108e_f2d9);
                permute_with(sx, &self.div_a, self.mask_a, k as u32)
            } else {
                0
            };
            (sx * b + px, sy * a + py)
        };
        Vec2::new(self.place(x, h), self.place(y, h << 24))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::{permute_index, stratifiable};

    #[test]
    fn grid_shapes() {
        // sizes the clock picks keep a grid near square, losing fewer than √n samples
        for n in 1..5000u64 {
            let k = stratifiable(n);
            let (a, _) = grid_shape(k as u32);
            let m = (k as f64).sqrt() as u32;
            assert!(k <= n && n - k < (n as f64).sqrt() as u64 + 1, "{n} -> {k}");
            assert!(2 * a >= m, "{n} -> {k}: grid {a}");
        }
        assert_eq!(stratifiable(4093), 63 * 64);
        assert_eq!(stratifiable(4096), 4096);
        assert_eq!(stratifiable(32), 32);
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

    /// The N points of a 2D dimension: one per a×b cell, and each coordinate alone one per
    /// interval of width 1/N (correlated multi-jitter), for square, oblong and prime N, in
    /// several dimensions, pixels and passes.
    #[test]
    fn points_2d_fill_cells_and_both_projections() {
        // tables (n ≤ TABLE_MAX_N, dimensions below TABLE_DIMS) and hashed permutations (n
        // above, and later dimensions)
        for n in [1u32, 7, 8, 12, 16, 64, 100, TABLE_MAX_N + 3] {
            let (a, b) = grid_shape(n);
            let mut sampler = StratifiedSampler::new(5, n);
            for (pixel, pass) in [(UVec2::new(0, 0), 0u32), (UVec2::new(3, 9), 2)] {
                for dim in (0..4).chain(TABLE_DIMS - 1..TABLE_DIMS + 2) {
                    let (mut cells, mut xs, mut ys) = (
                        vec![0; n as usize],
                        vec![0; n as usize],
                        vec![0; n as usize],
                    );
                    for j in 0..n {
                        sampler.start_pixel_sample(pixel, pass * n + j);
                        sampler.skip_2d(dim);
                        let p = sampler.next_2d();
                        assert!((0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y));
                        let (cx, cy) = ((p.x * a as f32) as u32, (p.y * b as f32) as u32);
                        cells[(cy * a + cx) as usize] += 1;
                        xs[(p.x * n as f32) as usize] += 1;
                        ys[(p.y * n as f32) as usize] += 1;
                    }
                    for (what, v) in [("cell", &cells), ("x interval", &xs), ("y interval", &ys)] {
                        assert!(
                            v.iter().all(|&c| c == 1),
                            "n={n} dim={dim}: a {what} holds {v:?}"
                        );
                    }
                }
            }
        }
    }

    /// A set that starts off the grid of multiples of N (a resume after a render cut inside
    /// its set) shares no point with the set of the same N that starts on the grid before it:
    /// keyed by `⌊origin/N⌋` alone it was that set again, one slot on (issue 46). Sets that start
    /// on the grid keep their points (images without the defect do not change).
    #[test]
    fn sets_that_start_at_different_indices_share_no_point() {
        let points = |n: u32, origin: u32, dim: u32| -> Vec<(u32, u32)> {
            let mut s = StratifiedSampler::with_origin(11, n, origin);
            (origin..origin + n)
                .map(|i| {
                    s.start_pixel_sample(UVec2::new(2, 5), i);
                    s.skip_2d(dim);
                    let p = s.next_2d();
                    (p.x.to_bits(), p.y.to_bits())
                })
                .collect()
        };
        for n in [2u32, 7, 16, 37, 64, TABLE_MAX_N + 3] {
            for dim in [0, TABLE_DIMS + 1] {
                let first = points(n, 0, dim);
                for origin in [1, n / 2, n - 1, n + 1, 3 * n + 2] {
                    let shifted = points(n, origin, dim);
                    assert!(
                        shifted.iter().all(|p| !first.contains(p)),
                        "n={n} origin={origin} dim={dim}: a point of the set at 0 again"
                    );
                }
                // on the grid: the set starting at 2N is pass 2 of the sampler from 0
                let mut from0 = StratifiedSampler::new(11, n);
                let pass2: Vec<(u32, u32)> = (2 * n..3 * n)
                    .map(|i| {
                        from0.start_pixel_sample(UVec2::new(2, 5), i);
                        from0.skip_2d(dim);
                        let p = from0.next_2d();
                        (p.x.to_bits(), p.y.to_bits())
                    })
                    .collect();
                assert_eq!(points(n, 2 * n, dim), pass2, "n={n} dim={dim}");
            }
        }
    }

    /// The jittered sampler's N points of a 2D dimension: one in each a×b cell (tables and
    /// hashed draws), without the Latin constraint: a coordinate alone repeats some of its N
    /// intervals in most sets (a uniform point per cell falls in one of the b intervals of its
    /// column at random).
    #[test]
    fn jittered_points_fill_cells_only() {
        for n in [7u32, 16, 64, TABLE_MAX_N + 3] {
            let (a, b) = grid_shape(n);
            let mut sampler = StratifiedSampler::jittered(5, n, 0);
            let mut repeats = 0;
            for dim in [0, 2, TABLE_DIMS + 1] {
                let (mut cells, mut xs) = (vec![0; n as usize], vec![0; n as usize]);
                for j in 0..n {
                    sampler.start_pixel_sample(UVec2::new(3, 9), j);
                    sampler.skip_2d(dim);
                    let p = sampler.next_2d();
                    assert!((0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y));
                    let (cx, cy) = ((p.x * a as f32) as u32, (p.y * b as f32) as u32);
                    cells[(cy * a + cx) as usize] += 1;
                    xs[(p.x * n as f32) as usize] += 1;
                }
                assert!(cells.iter().all(|&c| c == 1), "n={n} dim={dim}: {cells:?}");
                repeats += xs.iter().any(|&c| c > 1) as u32;
            }
            if b > 1 {
                assert!(repeats > 0, "n={n}: every set Latin: not plain jittering");
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
