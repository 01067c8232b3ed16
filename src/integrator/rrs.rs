//! Efficiency-aware Russian roulette and splitting (EARS: Rath, Grittmann, Herholz, Vévoda,
//! Slusallek, Vorba, SIGGRAPH 2022), `--roulette ears`.
//!
//! At a Phong vertex `x` a path may end (roulette) or go on in several independent
//! continuations (splitting): it takes `N = ⌊n + u⌋` continuations (`u` uniform, so `E[N] = n`),
//! each a light sample and a bounce with everything after it, and adds their sum divided by `n`.
//! For any `n > 0` that depends only on what the path did before `x` the estimator stays
//! unbiased: `E[Σᵢ₌₁ᴺ Lᵢ / n] = E[N]·E[L] / n = E[L]`. EARS chooses `n` to maximise the image's
//! efficiency 1/(variance × cost). With the reflected radiance `L_r(x)` a continuation brings
//! back, its cost `C(x)` (here: the rays it traces, the light sample's included) and the
//! path's throughput `T` relative to its pixel, the factor that minimises variance × cost is
//!
//! ```text
//! n_R = √(T² · E[L_r²] / C) · √(C_img / V_img)        (roulette, n < 1)
//! n_S = √(T² · Var[L_r] / C) · √(C_img / V_img)       (splitting, n > 1)
//! n   = n_R if n_R ≤ 1, else max(n_S, 1)               clamped to [0.05, 20]
//! ```
//!
//! where `C_img` is a camera sample's cost and `V_img` the image's variance per sample, and
//! every product of colours is averaged over the three channels (as the paper's code does).
//! vrpt's error is the relative MSE `(x − r)²/(r² + 0.01)` ([`crate::analysis::metrics`]), so
//! the throughput is taken relative to `√(Î² + 0.01)`, `Î` the pixel's estimate from training,
//! and `V_img` is the mean over pixels of `Var[L]/(Î² + 0.01)`.
//!
//! `E[L_r²]`, `Var[L_r]` and `C` are learned per region of space and outgoing direction in an
//! octree over the scene's box ([`RrsCache`]; each node's cell in 4×4 bins of the outgoing
//! direction's cylindrical coordinates, as the paper's cache), from [`RrsRecord`]s: one per
//! continuation a training path took. The training ([`crate::render`]) renders iterations of
//! 2, 2, 4, 8 … spp, the first with classic roulette, each with the cache the earlier ones
//! taught, and the image rendered afterwards uses the cache frozen: its splitting factors are
//! a function of the path's history alone, so it is unbiased.
//!
//! Two guards keep a path's work bounded without bias (both fix `n` before `N` is drawn): `n`
//! is clamped to `[0.05, 20]`, and a camera sample may start at most [`MAX_EXTRA_BRANCHES`]
//! continuations beyond its first one at each vertex (`n` is capped by what is left).
//!
//! Mirror and glass vertices keep their classic roulette; the first vertex takes part (the
//! paper's `rrDepth` 1), so the camera ray's cost is shared by the continuations it splits
//! into. The first continuation of a vertex draws from the sampler as a classic path would
//! (it keeps the layout, and a stratified sampler's strata); the others draw from independent
//! streams keyed by the vertex. Classic roulette ([`Roulette::Classic`], the default) is the
//! integrator's path loop; the tree of continuations is `integrator/branching.rs`.

#[cfg(doc)]
use crate::guiding::dir_to_canonical;
use glam::{DVec3, Vec3};

/// How a path is ended or split (`--roulette`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Roulette {
    /// Russian roulette from the third bounce on with `q = min(max β, 0.95)`, no splitting.
    #[default]
    Classic,
    /// Efficiency-aware roulette and splitting (Rath et al. 2022), learned while rendering.
    Ears,
}

impl std::fmt::Display for Roulette {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&crate::names::value_name(self))
    }
}

/// The smallest and largest splitting factor (the paper's clamp).
pub const FACTOR_RANGE: (f32, f32) = (0.05, 20.0);

/// Continuations a camera sample may add beyond one per vertex, in all.
pub const MAX_EXTRA_BRANCHES: u32 = 64;

/// Outgoing-direction bins of a cache cell (4 × 4 in cylindrical coordinates).
const BINS: usize = 16;

/// A bin's records before it is used for sampling (measured on the glossy plates at 10 s:
/// 4096 or the paper's 40000 gave no lower error than 256 with vrpt's short trainings).
const MIN_SAMPLING_WEIGHT: f64 = 256.0;

/// A leaf splits into 8 once one of its bins holds this many records.
const SPLIT_WEIGHT: f64 = 4096.0;

/// The cache's nodes at most (a node is about 2 KiB in all: 32 MiB).
const MAX_NODES: usize = 16 * 1024;

/// Deepest level of the octree.
const MAX_DEPTH: u32 = 16;

/// One continuation of a training path: where it left (its vertex and outgoing direction's
/// bin), the reflected radiance it brought back per unit throughput at the vertex, and the
/// rays it traced.
#[derive(Clone, Copy, Debug)]
pub struct RrsRecord {
    pub p: Vec3,
    pub bin: u8,
    /// Whether it left the camera ray's vertex.
    pub first: bool,
    pub lr: Vec3,
    pub cost: f32,
}

/// What a bin learned from its records: `E[L_r²]/C` and `Var[L_r]/C`, per channel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Learned {
    pub second_moment: Vec3,
    pub variance: Vec3,
}

/// A bin's sums over its records (kept across iterations: the paper's incremental training).
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    weight: f64,
    lr: DVec3,
    lr_sq: DVec3,
    cost: f64,
}

impl Sums {
    fn add(&mut self, o: &Sums) {
        self.weight += o.weight;
        self.lr += o.lr;
        self.lr_sq += o.lr_sq;
        self.cost += o.cost;
    }

    /// The factors these sums give, once there are enough of them.
    fn learned(&self) -> Option<Learned> {
        if self.weight < MIN_SAMPLING_WEIGHT {
            return None;
        }
        let mean = self.lr / self.weight;
        let m2 = self.lr_sq / self.weight;
        let cost = self.cost / self.weight;
        if cost <= 0.0 {
            return Some(Learned::default()); // nothing traced from here: nothing to gain
        }
        Some(Learned {
            second_moment: (m2 / cost).as_vec3(),
            variance: ((m2 - mean * mean).max(DVec3::ZERO) / cost).as_vec3(),
        })
    }
}

#[derive(Clone, Debug)]
struct Node {
    /// Index of the first of 8 consecutive children; 0 for a leaf.
    children: u32,
    train: [Sums; BINS],
}

impl Node {
    fn leaf() -> Self {
        Node {
            children: 0,
            train: [Sums::default(); BINS],
        }
    }
}

/// The octree of what continuations bring back and cost, over the scene's box (see the
/// module doc). A lookup answers from the deepest node on the point's way down whose bin has
/// learned enough; records go to the leaf; [`RrsCache::finish_iteration`] sums every node's
/// records from its children, learns from them and splits the leaves that hold enough.
#[derive(Clone, Debug)]
pub struct RrsCache {
    lo: Vec3,
    inv_size: Vec3,
    nodes: Vec<Node>,
    /// What each node's bins learned (apart from the sums: 448 bytes a node, not 1.5 KiB, so
    /// a lookup's one read of it stays in cache more often).
    learned: Vec<[Option<Learned>; BINS]>,
    /// What a lookup reads on its way down, apart and small (the nodes are ~1.5 KiB): each
    /// node's first child (0: a leaf) and which of its bins have learned (bit per bin).
    walk: Vec<Walk>,
}

#[derive(Clone, Copy, Debug)]
struct Walk {
    children: u32,
    valid: u16,
}

/// The bin of outgoing direction `wo` (unit, world): 4 × 4 cells of its cylindrical
/// coordinates `((cosθ + 1)/2, φ/2π)` (as [`dir_to_canonical`]), the four of φ its quadrants,
/// read from the signs of `x` and `y` without an `atan2`.
#[inline]
pub fn direction_bin(wo: Vec3) -> u8 {
    let z = ((wo.z + 1.0) * 2.0).clamp(0.0, 3.0) as u8;
    let quadrant = match (wo.x >= 0.0, wo.y >= 0.0) {
        (true, true) => 0,
        (false, true) => 1,
        (false, false) => 2,
        (true, false) => 3,
    };
    z + 4 * quadrant
}

impl RrsCache {
    /// An empty cache over the box `lo..hi`, cut in 8 × 8 cells to begin with.
    pub fn new(lo: Vec3, hi: Vec3) -> Self {
        let size = (hi - lo).max(Vec3::splat(1e-6)) * 1.0001;
        let mut c = RrsCache {
            lo,
            inv_size: size.recip(),
            nodes: vec![Node::leaf()],
            learned: vec![[None; BINS]],
            walk: vec![Walk {
                children: 0,
                valid: 0,
            }],
        };
        c.split(0);
        for i in 1..9 {
            c.split(i);
        }
        c
    }

    fn split(&mut self, i: usize) {
        let first = self.nodes.len() as u32;
        let (learned, valid) = (self.learned[i], self.walk[i].valid);
        for _ in 0..8 {
            self.nodes.push(Node::leaf());
            self.learned.push(learned);
            self.walk.push(Walk { children: 0, valid });
        }
        self.nodes[i].children = first;
        self.walk[i].children = first;
    }

    /// The nodes on `p`'s way down, root first, to its leaf: calls `visit` with each.
    #[inline]
    fn descend(&self, p: Vec3, mut visit: impl FnMut(usize)) {
        let mut x = ((p - self.lo) * self.inv_size).clamp(Vec3::ZERO, Vec3::splat(0.999_999));
        let mut i = 0usize;
        loop {
            visit(i);
            let first = self.walk[i].children;
            if first == 0 {
                return;
            }
            let b = x.cmpge(Vec3::splat(0.5));
            let bits = b.bitmask() as usize;
            x = x * 2.0 - Vec3::select(b, Vec3::ONE, Vec3::ZERO);
            i = first as usize + bits;
        }
    }

    /// What the deepest node on `p`'s way down has learned of bin `bin`, if any.
    #[inline]
    pub fn lookup(&self, p: Vec3, bin: u8) -> Option<Learned> {
        let mut found = usize::MAX;
        let bit = 1u16 << bin;
        self.descend(p, |i| {
            if self.walk[i].valid & bit != 0 {
                found = i;
            }
        });
        self.learned.get(found).and_then(|l| l[bin as usize])
    }

    /// Add one record to its leaf.
    pub fn add(&mut self, r: &RrsRecord) {
        let mut leaf = 0;
        self.descend(r.p, |i| leaf = i);
        let lr = r.lr.as_dvec3();
        let s = &mut self.nodes[leaf].train[r.bin as usize];
        s.weight += 1.0;
        s.lr += lr;
        s.lr_sq += lr * lr;
        s.cost += r.cost as f64;
    }

    /// After an iteration's records: every inner node's sums become its children's, every
    /// bin with enough records learns from them, and leaves that hold enough split (their
    /// children answer with the parent's factors until they have learned their own).
    pub fn finish_iteration(&mut self) {
        self.sum_and_learn(0, 0);
    }

    fn sum_and_learn(&mut self, i: usize, depth: u32) -> [Sums; BINS] {
        let first = self.nodes[i].children as usize;
        if first != 0 {
            let mut sum = [Sums::default(); BINS];
            for c in first..first + 8 {
                let s = self.sum_and_learn(c, depth + 1);
                for (a, b) in sum.iter_mut().zip(&s) {
                    a.add(b);
                }
            }
            self.nodes[i].train = sum;
        }
        let train = self.nodes[i].train;
        for (l, s) in self.learned[i].iter_mut().zip(&train) {
            if let Some(learned) = s.learned() {
                *l = Some(learned);
            }
        }
        let valid = (self.learned[i].iter().enumerate())
            .fold(0u16, |m, (b, l)| m | ((l.is_some() as u16) << b));
        self.walk[i].valid = valid;
        let heavy = train.iter().any(|s| s.weight >= SPLIT_WEIGHT);
        if first == 0 && heavy && depth < MAX_DEPTH && self.nodes.len() + 8 <= MAX_NODES {
            self.split(i);
        }
        train
    }

    /// Nodes in the tree.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether the tree has only its root (never: it starts cut).
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }
}

/// The EARS factor (see the module doc) for a path of throughput `t` relative to its pixel at
/// a vertex whose bin learned `l`, in an image of factor `image = √(C_img/V_img)`: the
/// roulette factor where it is below one, else the splitting factor (at least one), clamped.
/// 1 where nothing is known or the numbers are not finite.
#[inline]
pub fn ears_factor(t: Vec3, l: Option<Learned>, image: f32) -> f32 {
    let Some(l) = l else { return 1.0 };
    let t2 = t * t;
    let r = (t2 * l.second_moment).element_sum() / 3.0;
    let n_r = r.sqrt() * image;
    if !n_r.is_finite() {
        return 1.0;
    }
    let n = if n_r > 1.0 {
        let n_s = ((t2 * l.variance).element_sum() / 3.0).sqrt() * image;
        if n_s.is_finite() {
            n_s.max(1.0)
        } else {
            1.0
        }
    } else {
        n_r
    };
    n.clamp(FACTOR_RANGE.0, FACTOR_RANGE.1)
}

/// What the learned roulette gives the integrator for one render: the cache (`None`: classic
/// roulette, recorded, the first training iteration) and the image's factor `√(C_img/V_img)`.
#[derive(Clone, Copy, Debug)]
pub struct RrsLearned<'a> {
    pub cache: Option<&'a RrsCache>,
    pub image: f32,
}

/// One camera sample's view of the learned roulette: the render's [`RrsLearned`], the pixel's
/// `1/√(Î² + 0.01)` per channel, the continuations it may still add, and where a training
/// iteration's records go.
pub struct RrsPath<'a, 'r> {
    pub learned: RrsLearned<'a>,
    pub pixel_norm: Vec3,
    pub extra: u32,
    pub records: Option<&'r mut Vec<RrsRecord>>,
}

impl RrsPath<'_, '_> {
    /// The factor `n` at vertex `p` left toward `wo` (bin `bin`) by a path of whole throughput
    /// `beta` (its `segment`-th vertex): EARS's with a cache; classic roulette's
    /// `min(max β, 0.95)` from the third bounce on without one; capped so the continuations
    /// stay within the sample's [`MAX_EXTRA_BRANCHES`].
    #[inline]
    pub fn factor(&self, p: Vec3, bin: u8, beta: Vec3, segment: u32) -> f32 {
        let n = match self.learned.cache {
            Some(c) => ears_factor(beta * self.pixel_norm, c.lookup(p, bin), self.learned.image),
            None if segment >= super::RR_START_BOUNCE => beta.max_element().min(0.95),
            None => 1.0,
        };
        n.min(1.0 + self.extra as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule of the paper's code: roulette where `n_R ≤ 1`, split by `n_S` (at least one)
    /// where `n_R > 1`, clamped to [0.05, 20]; nothing learned or a non-finite value: 1.
    #[test]
    fn the_factor_follows_the_rule() {
        let l = |m2: f32, var: f32| {
            Some(Learned {
                second_moment: Vec3::splat(m2),
                variance: Vec3::splat(var),
            })
        };
        let t = Vec3::ONE;
        assert_eq!(ears_factor(t, None, 1.0), 1.0);
        assert!((ears_factor(t, l(0.25, 0.1), 1.0) - 0.5).abs() < 1e-6);
        assert!((ears_factor(t, l(16.0, 9.0), 1.0) - 3.0).abs() < 1e-6);
        assert_eq!(ears_factor(t, l(16.0, 0.25), 1.0), 1.0); // n_R > 1 > n_S
        assert_eq!(ears_factor(t, l(1e-8, 0.0), 1.0), 0.05);
        assert_eq!(ears_factor(t, l(1e8, 1e8), 1.0), 20.0);
        assert_eq!(ears_factor(t, l(f32::INFINITY, 1.0), 1.0), 1.0);
        // the throughput and the image factor scale n linearly
        assert!((ears_factor(t * 2.0, l(0.01, 0.0), 3.0) - 0.6).abs() < 1e-6);
        // channels are averaged: T² E[L²] = (0, 0, 3)/3 → n = 1·image
        let l3 = Some(Learned {
            second_moment: Vec3::new(0.0, 0.0, 0.48),
            variance: Vec3::ZERO,
        });
        assert!((ears_factor(t, l3, 1.0) - 0.4).abs() < 1e-6);
    }

    /// Records reach their leaf; a bin answers once it holds enough, with `E[L²]/C` and
    /// `Var/C` of its records, and so do the nodes above it (their sums hold them); a heavy
    /// leaf splits.
    #[test]
    fn the_cache_learns_moments_and_splits() {
        let mut c = RrsCache::new(Vec3::ZERO, Vec3::ONE);
        let p = Vec3::new(0.1, 0.2, 0.3);
        let bin = direction_bin(Vec3::Z);
        assert_eq!(c.lookup(p, bin), None);
        let n0 = c.len();
        // L_r alternates 1 and 3 (mean 2, E[L²] 5, variance 1), cost 2
        for i in 0..SPLIT_WEIGHT as usize {
            let lr = Vec3::splat(if i % 2 == 0 { 1.0 } else { 3.0 });
            c.add(&RrsRecord {
                p,
                bin,
                first: false,
                lr,
                cost: 2.0,
            });
        }
        c.finish_iteration();
        let l = c.lookup(p, bin).expect("learned");
        assert!((l.second_moment - Vec3::splat(2.5)).abs().max_element() < 1e-5);
        assert!((l.variance - Vec3::splat(0.5)).abs().max_element() < 1e-5);
        assert_eq!(c.len(), n0 + 8, "the heavy leaf split");
        // the other side of the box answers from the root, which sums every record; another
        // bin has learned nothing anywhere
        assert_eq!(c.lookup(Vec3::splat(0.9), bin), Some(l));
        assert_eq!(c.lookup(p, (bin + 1) % 16), None);
        assert!((0..16).all(|b| b == bin || c.lookup(p, b).is_none()));
    }

    /// The bin read from signs is the 4 × 4 cell of the cylindrical coordinates.
    #[test]
    fn direction_bins_are_cells_of_the_cylindrical_coordinates() {
        let mut h = 0x1234_5678u64;
        for _ in 0..10_000 {
            let mut u = || {
                h = crate::math::mix64(h);
                crate::math::u64_to_unit_f32(h)
            };
            let mut d = crate::sampling::sample_uniform_hemisphere(glam::Vec2::new(u(), u()));
            if u() < 0.5 {
                d.z = -d.z;
            }
            let c = crate::guiding::dir_to_canonical(d) * 4.0;
            let expected = (c.x as u8).min(3) + 4 * (c.y as u8).min(3);
            assert_eq!(direction_bin(d), expected, "{d}");
        }
    }

    /// Classic roulette without a cache, the cap on continuations with one.
    #[test]
    fn without_a_cache_the_factor_is_classic_roulette() {
        let mut path = RrsPath {
            learned: RrsLearned {
                cache: None,
                image: 1.0,
            },
            pixel_norm: Vec3::ONE,
            extra: 0,
            records: None,
        };
        let beta = Vec3::new(0.2, 0.5, 0.1);
        assert_eq!(path.factor(Vec3::ZERO, 0, beta, 1), 1.0);
        assert_eq!(path.factor(Vec3::ZERO, 0, beta, 3), 0.5);
        assert_eq!(path.factor(Vec3::ZERO, 0, Vec3::splat(4.0), 5), 0.95);
        let mut c = RrsCache::new(Vec3::ZERO, Vec3::ONE);
        // L_r 0 or 200: E[L²]/C = 20000, Var/C = 10000, so n_R ≈ 141 and n_S = 100
        for i in 0..SPLIT_WEIGHT as usize {
            let r = RrsRecord {
                p: Vec3::splat(0.5),
                bin: 0,
                first: true,
                lr: Vec3::splat(if i % 2 == 0 { 0.0 } else { 200.0 }),
                cost: 1.0,
            };
            c.add(&r);
        }
        c.finish_iteration();
        path.learned.cache = Some(&c);
        let at = |path: &RrsPath| path.factor(Vec3::splat(0.5), 0, Vec3::ONE, 1);
        assert_eq!(at(&path), 1.0, "no continuation left to add");
        path.extra = 5;
        assert_eq!(at(&path), 6.0, "capped by what is left");
        path.extra = MAX_EXTRA_BRANCHES;
        assert_eq!(at(&path), FACTOR_RANGE.1, "clamped");
    }
}
