//! Path guiding: the SD-tree of Müller, Gross & Novák 2017, "Practical Path Guiding for
//! Efficient Light-Transport Simulation" — a learned estimate of the radiance arriving at each
//! region of the scene from each direction, which `--directions guided` samples from.
//!
//! **The tree.** A binary tree over the scene's bounding cube (the *S-tree*), split at the
//! middle along x, y, z in turn; each of its leaves holds a quadtree over the sphere of
//! directions (the *D-tree*) in the cylindrical equal-area map
//! `(u, v) = ((cosθ + 1)/2, φ/2π)` (world axes, θ from +z), which maps solid angle to area
//! uniformly: `dω = 4π du dv`. A quadtree node holds, per quadrant, the sum of the radiance
//! estimates recorded in it. Its sampling density is piecewise constant on the leaves, in
//! proportion to the recorded energy: descending, quadrant `i` is taken with probability
//! `s_i / Σs`, so `p(u, v) = Π 4 s_i/Σs` along the path and `p(ω) = p(u, v) / 4π` per unit solid
//! angle ([`DTree::pdf`]); [`DTree::sample`] draws from it by hierarchical warping of one 2D
//! point (the x half by `u.x`, then the y half of that column by `u.y`, each rescaled to
//! `[0, 1)` and used again below), and the point inside the last leaf is the rescaled `u`.
//!
//! **Learning.** Training renders iterations of 1, 2, 4, … samples per pixel. Iteration `k`
//! samples with the D-trees built from iteration `k − 1` and records, at every bounce of every
//! path, the radiance that arrived along the sampled direction: the path's radiance gathered
//! after the bounce divided by the throughput up to and including it, `L_i ≈ ΔL / β`, averaged
//! over the three channels, divided by the direction's pdf (a one-sample estimate of the
//! radiance integral over the quadrant it falls in). Emission that the bounce's own ray hits
//! is learned whole under `bsdf` and `mis` (under `mis` the estimator took the MIS weight `w`
//! of it; the record adds the `1 − w` that next-event estimation was to carry), so the guide
//! learns which part of a light is visible — what NEE, blind to occlusion, cannot know (the
//! door's slit). Under `nee` it is left out: the estimator never counts a BSDF-sampled light.
//! Each record also feeds the leaf's learner of `α` (Adam on the variance, see the sampling paragraph). After the
//! iteration each leaf's quadtree is
//! summed up to its root and becomes the leaf's sampling distribution; then an S-tree leaf that
//! recorded more than `c·√(2^k)` samples ([`SPATIAL_THRESHOLD`] `c`) is halved until its halves
//! have not (each half starts from a copy of the leaf's distribution), and each D-tree is
//! rebuilt empty with a quadrant split where it held more than [`ENERGY_FRACTION`] `ρ` of its
//! leaf's energy (at most [`MAX_QUAD_DEPTH`] levels).
//!
//! **Sampling** (the integrator): one-sample MIS between the BSDF's own strategy (the Phong
//! lobes) and the guide, the guide chosen with probability `α`, learned per leaf from
//! [`GUIDE_FRACTION`] on by stochastic gradient descent (Adam) on the variance of the mixture
//! estimator, as in Müller's 2019 follow-up (a leaf that has learned nothing samples the guide
//! uniformly over the sphere, as in the authors' code); the direction's pdf is the mixture
//! `α·p_guide + (1−α)·p_bsdf`, and that mixture is the BSDF pdf NEE's and the light's MIS
//! weights see. A guided direction below the surface is a failed sample, as for the Phong lobe.
//!
//! **Unbiased.** The image is the final iteration alone: the training iterations use their own
//! seeds (the render's seed mixed with the iteration number), so the tree that samples the final
//! iteration is a function of samples independent of the final ones. Given the tree, every final
//! sample is an ordinary importance-sampled estimate with a pdf that is positive wherever the
//! BSDF's is (`1 − α ≥ 0.5`), hence unbiased; averaging over trees keeps it so. Training samples
//! are discarded: combining them with weights fixed in advance would also be unbiased, but the
//! early iterations' variance is far higher and fixed weights cannot know by how much.
//!
//! **Deterministic.** Tiles record into their own buffers; after each chunk of tiles the records
//! are put in tile order, stably sorted by S-tree leaf, and each leaf adds its own records in
//! that order (leaves in parallel). So the learned tree — sums, splits, everything — is the same
//! bits whatever the thread count or the order tiles finish in, and so is the image.

use crate::sampling::ONE_MINUS_EPSILON;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::f32::consts::PI;

/// `α` of a leaf before it has learned its own: the probability of sampling the guide.
pub const GUIDE_FRACTION: f32 = 0.5;

/// `c`: an S-tree leaf that recorded more than `c·√(2^k)` samples in iteration `k` is split.
/// The paper's value (measured on the door scene at 10 s: 1,000 and 4,000 learned no better).
pub const SPATIAL_THRESHOLD: f64 = 12000.0;

/// `ρ`: a quadrant is split when it holds more than this fraction of its D-tree's energy.
pub const ENERGY_FRACTION: f32 = 0.01;

/// Deepest a quadtree grows (a leaf at depth 20 spans 2^-20 of the square's side).
pub const MAX_QUAD_DEPTH: u32 = 20;

/// Most nodes of one quadtree (refinement stops adding nodes past it).
pub const MAX_QUAD_NODES: usize = 1 << 16;

/// The cylindrical equal-area coordinates `((cosθ + 1)/2, φ/2π)` of unit direction `d`.
#[inline]
pub fn dir_to_canonical(d: Vec3) -> Vec2 {
    let cos_theta = d.z.clamp(-1.0, 1.0);
    let mut phi = d.y.atan2(d.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    Vec2::new(
        ((cos_theta + 1.0) * 0.5).min(ONE_MINUS_EPSILON),
        (phi * (0.5 / PI)).min(ONE_MINUS_EPSILON),
    )
}

/// The unit direction of canonical point `p` (the inverse of [`dir_to_canonical`]).
#[inline]
pub fn canonical_to_dir(p: Vec2) -> Vec3 {
    let cos_theta = 2.0 * p.x - 1.0;
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let (s, c) = (2.0 * PI * p.y).sin_cos();
    Vec3::new(sin_theta * c, sin_theta * s, cos_theta)
}

/// A quadtree node: per quadrant (bit 0: the upper half in `u`, bit 1: the upper half in `v`)
/// the energy recorded there and its child node (0: the quadrant is a leaf; the root, node 0,
/// is nobody's child).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct QNode {
    sum: [f32; 4],
    child: [u32; 4],
}

impl QNode {
    /// The quadrant of `p` (in the node's `[0,1)²`), and `p` in the quadrant's own `[0,1)²`.
    #[inline]
    fn quadrant(p: Vec2) -> (usize, Vec2) {
        let (ix, x) = if p.x < 0.5 {
            (0, p.x * 2.0)
        } else {
            (1, (p.x - 0.5) * 2.0)
        };
        let (iy, y) = if p.y < 0.5 {
            (0, p.y * 2.0)
        } else {
            (1, (p.y - 0.5) * 2.0)
        };
        (ix | iy << 1, Vec2::new(x, y))
    }

    fn total(&self) -> f32 {
        self.sum.iter().sum()
    }
}

/// A directional quadtree: the learned distribution of one S-tree leaf (see the module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct DTree {
    nodes: Vec<QNode>,
    /// The root's energy once built (0 before, or when nothing was recorded).
    total: f32,
}

impl Default for DTree {
    fn default() -> Self {
        DTree {
            nodes: vec![QNode::default()],
            total: 0.0,
        }
    }
}

impl DTree {
    /// A built quadtree from explicit nodes (per node, per quadrant — bit 0 the upper half in u, bit 1 in v — its energy and its child, 0 for none):
    /// for tests of the sampling routines on hand-made trees. Each node's `(sum, child)` pairs
    /// are per quadrant; a quadrant with a child gets its energy from the child.
    pub fn from_nodes(nodes: &[([f32; 4], [u32; 4])]) -> DTree {
        let mut t = DTree {
            nodes: nodes
                .iter()
                .map(|&(sum, child)| QNode { sum, child })
                .collect(),
            total: 0.0,
        };
        t.build();
        t
    }

    /// The energy recorded in all (a positive total means the tree can be sampled).
    pub fn total(&self) -> f32 {
        self.total
    }

    /// Number of quadtree nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes of its nodes.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<QNode>()
    }

    /// Depth of the deepest leaf (1: the root's quadrants are leaves).
    pub fn depth(&self) -> u32 {
        fn go(t: &DTree, n: usize) -> u32 {
            1 + t.nodes[n]
                .child
                .iter()
                .filter(|&&c| c != 0)
                .map(|&c| go(t, c as usize))
                .max()
                .unwrap_or(0)
        }
        go(self, 0)
    }

    /// The density at canonical point `p` per unit area of the square (integrates to 1 over
    /// it); uniform (1) when the tree holds no energy.
    #[inline]
    pub fn pdf_canonical(&self, mut p: Vec2) -> f32 {
        if self.total <= 0.0 {
            return 1.0;
        }
        let mut pdf = 1.0;
        let mut n = 0usize;
        loop {
            let node = &self.nodes[n];
            let (i, q) = QNode::quadrant(p);
            let s = node.sum[i];
            if s <= 0.0 {
                return 0.0;
            }
            pdf *= 4.0 * s / node.total();
            if node.child[i] == 0 {
                return pdf;
            }
            n = node.child[i] as usize;
            p = q;
        }
    }

    /// The density of direction `d` (unit, world) per unit solid angle: `pdf_canonical / 4π`.
    #[inline]
    pub fn pdf(&self, d: Vec3) -> f32 {
        self.pdf_canonical(dir_to_canonical(d)) * (0.25 / PI)
    }

    /// A canonical point drawn with density [`DTree::pdf_canonical`] from `u ∈ [0,1)²`, by
    /// hierarchical warping (`u` itself when the tree holds no energy).
    #[inline]
    pub fn sample_canonical(&self, mut u: Vec2) -> Vec2 {
        if self.total <= 0.0 {
            return u;
        }
        let (mut origin, mut size) = (Vec2::ZERO, 1.0f32);
        let mut n = 0usize;
        loop {
            let s = self.nodes[n].sum;
            let left = s[0] + s[2];
            let total = left + s[1] + s[3];
            let p_left = left / total;
            let ix = if u.x < p_left {
                u.x /= p_left;
                0
            } else {
                u.x = (u.x - p_left) / (1.0 - p_left);
                1
            };
            let (lo, hi) = (s[ix], s[ix + 2]);
            let p_low = lo / (lo + hi);
            let iy = if u.y < p_low {
                u.y /= p_low;
                0
            } else {
                u.y = (u.y - p_low) / (1.0 - p_low);
                1
            };
            u = u.clamp(Vec2::ZERO, Vec2::splat(ONE_MINUS_EPSILON));
            size *= 0.5;
            origin += Vec2::new(ix as f32, iy as f32) * size;
            let i = ix | iy << 1;
            let c = self.nodes[n].child[i];
            if c == 0 {
                return (origin + u * size).min(Vec2::splat(ONE_MINUS_EPSILON));
            }
            n = c as usize;
        }
    }

    /// A direction (unit, world) drawn with density [`DTree::pdf`].
    #[inline]
    pub fn sample(&self, u: Vec2) -> Vec3 {
        canonical_to_dir(self.sample_canonical(u))
    }

    /// Add `value` to the leaf quadrant holding canonical point `p`.
    #[inline]
    fn record(&mut self, mut p: Vec2, value: f32) {
        let mut n = 0usize;
        loop {
            let (i, q) = QNode::quadrant(p);
            let c = self.nodes[n].child[i];
            if c == 0 {
                self.nodes[n].sum[i] += value;
                return;
            }
            n = c as usize;
            p = q;
        }
    }

    /// Sum the leaves' energies up to the root (children have higher indices than their
    /// parents, so one pass from the back does it).
    fn build(&mut self) {
        for n in (0..self.nodes.len()).rev() {
            for i in 0..4 {
                let c = self.nodes[n].child[i];
                if c != 0 {
                    self.nodes[n].sum[i] = self.nodes[c as usize].total();
                }
            }
        }
        let total = self.nodes[0].total();
        self.total = if total.is_finite() && total > 0.0 {
            total
        } else {
            0.0
        };
    }

    /// An empty tree whose quadrants are split where this (built) tree held more than `rho` of
    /// its energy (a quadrant this tree did not split goes on splitting with a quarter of its
    /// energy per child, as the authors' code does), at most [`MAX_QUAD_DEPTH`] deep.
    fn refined(&self, rho: f32) -> DTree {
        let mut out = DTree::default();
        let total = self.total;
        // (node of `out`, the energies of the matching region's quadrants, their children in
        // `self` (0: none), depth)
        let mut stack = vec![(0usize, self.nodes[0].sum, self.nodes[0].child, 1u32)];
        while let Some((n, sums, children, depth)) = stack.pop() {
            for i in 0..4 {
                let fraction = if total > 0.0 {
                    sums[i] / total
                } else {
                    0.25f32.powi(depth as i32)
                };
                if depth < MAX_QUAD_DEPTH && fraction > rho && out.nodes.len() < MAX_QUAD_NODES {
                    let c = out.nodes.len();
                    out.nodes.push(QNode::default());
                    out.nodes[n].child[i] = c as u32;
                    let (s, ch) = match children[i] {
                        0 => ([sums[i] * 0.25; 4], [0; 4]),
                        k => (self.nodes[k as usize].sum, self.nodes[k as usize].child),
                    };
                    stack.push((c, s, ch, depth + 1));
                }
            }
        }
        out
    }
}

/// A node of the S-tree: split along `axis` at its middle into nodes `child` and `child + 1`
/// (the lower and upper halves), or a leaf (`child == 0`) holding [`Leaf`] `leaf`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct SNode {
    axis: u8,
    child: u32,
    leaf: u32,
}

/// One S-tree leaf: the distribution that samples this iteration and the one being recorded.
#[derive(Clone, Debug, PartialEq)]
pub struct Leaf {
    /// What this iteration samples from (built from the previous iteration's records).
    pub sampling: DTree,
    /// What this iteration records into.
    building: DTree,
    /// Records this iteration.
    samples: u64,
    /// The probability of sampling the guide here this iteration.
    pub alpha: f32,
    /// What learns it.
    fraction: FractionLearner,
}

/// Learns the guide's share `α` of a leaf's samples by stochastic gradient descent (Adam) on
/// the variance of the one-sample mixture estimator, as in Müller's 2019 follow-up ("Practical
/// Path Guiding in Production", the authors' `bsdfSamplingFractionLoss = var`): with the BSDF
/// fraction `s = σ(θ)` and mixture `q = s·p_b + (1−s)·p_g`, a record `(F = L_i f cosθ, p)` of
/// a direction drawn with pdf `p` gives `∂V/∂s ≈ −(F/q)² (p_b − p_g) / p`, and Adam moves `θ`
/// against it (learning rate 0.01, L2 pull of 0.01·θ toward `s = ½`, `θ` kept in ±20). Records
/// arrive in a fixed order, so the learned `α = 1 − σ(θ)` is deterministic too.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct FractionLearner {
    theta: f32,
    m: f32,
    v: f32,
    steps: i32,
    batch: f32,
    weight: f32,
}

impl FractionLearner {
    const RATE: f32 = 0.01;
    const BETA1: f32 = 0.9;
    const BETA2: f32 = 0.999;

    fn alpha(&self) -> f32 {
        1.0 - 1.0 / (1.0 + (-self.theta).exp())
    }

    fn learn(&mut self, r: &Record) {
        if !(r.product > 0.0 && r.pdf > 0.0) {
            return;
        }
        let s = 1.0 / (1.0 + (-self.theta).exp());
        let q = s * r.p_bsdf + (1.0 - s) * r.p_guide;
        let ratio = (r.product / q).powi(2);
        let d_s = -ratio / r.pdf * (r.p_bsdf - r.p_guide);
        let g = d_s * s * (1.0 - s) + 0.01 * self.theta;
        if !g.is_finite() {
            return;
        }
        self.batch += g;
        self.weight += 1.0;
        if self.weight > 1.0 {
            let g = self.batch / self.weight;
            self.batch = 0.0;
            self.weight = 0.0;
            self.steps += 1;
            let t = self.steps;
            let rate =
                Self::RATE * (1.0 - Self::BETA2.powi(t)).sqrt() / (1.0 - Self::BETA1.powi(t));
            self.m = Self::BETA1 * self.m + (1.0 - Self::BETA1) * g;
            self.v = Self::BETA2 * self.v + (1.0 - Self::BETA2) * g * g;
            self.theta = (self.theta - rate * self.m / (self.v.sqrt() + 1e-8)).clamp(-20.0, 20.0);
        }
    }
}

/// One radiance record: the S-tree leaf of the vertex, the canonical point of the sampled
/// direction, `L_i / p` (see the module doc), and what learning `α` needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    /// Index of the S-tree leaf the vertex lies in.
    pub leaf: u32,
    /// The direction, canonical.
    pub point: Vec2,
    /// The radiance estimate divided by the direction's pdf.
    pub value: f32,
    /// `L_i · f · cosθ` (channel average).
    pub product: f32,
    /// The pdf the direction was drawn with (the mixture).
    pub pdf: f32,
    /// Its BSDF and guide pdfs.
    pub p_bsdf: f32,
    pub p_guide: f32,
}

/// The SD-tree: an S-tree over the scene's bounding cube with a [`Leaf`] per leaf.
#[derive(Clone, Debug, PartialEq)]
pub struct SdTree {
    min: Vec3,
    /// Edge of the bounding cube.
    size: f32,
    nodes: Vec<SNode>,
    leaves: Vec<Leaf>,
}

/// How big a tree is.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TreeSize {
    /// S-tree leaves.
    pub leaves: usize,
    /// Quadtree nodes of the sampling distributions, summed over the leaves.
    pub quad_nodes: usize,
    /// Bytes of the whole tree (both distributions of every leaf, and the S-tree).
    pub bytes: usize,
}

impl SdTree {
    /// An untrained tree over the box `min..max` (made a cube, slightly enlarged so that every
    /// surface point lies inside).
    pub fn new(min: Vec3, max: Vec3) -> SdTree {
        let extent = (max - min).max_element().max(1e-6);
        let pad = extent * 1e-3;
        SdTree {
            min: min - Vec3::splat(pad),
            size: extent + 2.0 * pad,
            nodes: vec![SNode {
                axis: 0,
                child: 0,
                leaf: 0,
            }],
            // the first iteration records into a uniform tree of a few levels (an empty tree's
            // refinement splits by area: depth 4, 85 nodes)
            leaves: vec![Leaf {
                sampling: DTree::default(),
                building: DTree::default().refined(ENERGY_FRACTION),
                samples: 0,
                alpha: GUIDE_FRACTION,
                fraction: FractionLearner::default(),
            }],
        }
    }

    /// The index of the leaf holding point `p` (points outside the cube go to the nearest
    /// leaf).
    #[inline]
    pub fn leaf_at(&self, p: Vec3) -> u32 {
        let mut q = ((p - self.min) / self.size).clamp(Vec3::ZERO, Vec3::splat(ONE_MINUS_EPSILON));
        let mut n = 0usize;
        loop {
            let node = self.nodes[n];
            if node.child == 0 {
                return node.leaf;
            }
            let a = node.axis as usize;
            if q[a] < 0.5 {
                q[a] *= 2.0;
                n = node.child as usize;
            } else {
                q[a] = (q[a] - 0.5) * 2.0;
                n = node.child as usize + 1;
            }
        }
    }

    /// The distribution that samples at leaf `leaf`.
    #[inline]
    pub fn sampling(&self, leaf: u32) -> &DTree {
        &self.leaves[leaf as usize].sampling
    }

    /// Add `records` (in the order the renders made them) to the distributions being built:
    /// stably sorted by leaf, each leaf adding its own in order, leaves in parallel — the same
    /// bits for any thread count.
    pub fn add_records(&mut self, mut records: Vec<Record>) {
        records.par_sort_by_key(|r| r.leaf);
        let records = &records;
        self.leaves
            .par_iter_mut()
            .enumerate()
            .for_each(|(i, leaf)| {
                let i = i as u32;
                let lo = records.partition_point(|r| r.leaf < i);
                let hi = records.partition_point(|r| r.leaf <= i);
                for r in &records[lo..hi] {
                    leaf.building.record(r.point, r.value);
                    leaf.fraction.learn(r);
                }
                leaf.samples += (hi - lo) as u64;
            });
    }

    /// End training iteration `k` (0-based, of `2^k` spp): what it recorded becomes the sampling
    /// distribution, the S-tree is refined by the counts and the D-trees rebuilt empty by the
    /// energies (see the module doc).
    pub fn finish_iteration(&mut self, k: u32) {
        self.leaves.par_iter_mut().for_each(|leaf| {
            leaf.building.build();
            leaf.sampling = leaf.building.clone();
        });
        let threshold = SPATIAL_THRESHOLD * 2f64.powf(k as f64 * 0.5);
        // split leaves breadth-first by index order (deterministic); a split leaf's halves each
        // take half its count and a copy of its distribution
        let mut n = 0;
        while n < self.nodes.len() {
            let node = self.nodes[n];
            if node.child == 0 && self.leaves[node.leaf as usize].samples as f64 > threshold {
                let leaf = self.leaves[node.leaf as usize].clone();
                let half = Leaf {
                    samples: leaf.samples / 2,
                    ..leaf
                };
                let child = self.nodes.len() as u32;
                let axis = (node.axis + 1) % 3;
                self.leaves[node.leaf as usize] = half.clone();
                let second = self.leaves.len() as u32;
                self.leaves.push(half);
                self.nodes.push(SNode {
                    axis,
                    child: 0,
                    leaf: node.leaf,
                });
                self.nodes.push(SNode {
                    axis,
                    child: 0,
                    leaf: second,
                });
                self.nodes[n].child = child;
            }
            n += 1;
        }
        self.leaves.par_iter_mut().for_each(|leaf| {
            leaf.building = leaf.sampling.refined(ENERGY_FRACTION);
            leaf.alpha = leaf.fraction.alpha();
            leaf.samples = 0;
        });
    }

    /// How big the tree is.
    pub fn size(&self) -> TreeSize {
        TreeSize {
            leaves: self.leaves.len(),
            quad_nodes: self.leaves.iter().map(|l| l.sampling.node_count()).sum(),
            bytes: self.nodes.capacity() * std::mem::size_of::<SNode>()
                + self.leaves.capacity() * std::mem::size_of::<Leaf>()
                + self
                    .leaves
                    .iter()
                    .map(|l| l.sampling.memory_bytes() + l.building.memory_bytes())
                    .sum::<usize>(),
        }
    }
}

/// The guide at one vertex: the leaf's distribution and `α`.
#[derive(Clone, Copy, Debug)]
pub struct GuideAt<'a> {
    /// The leaf's index.
    pub leaf: u32,
    /// Its sampling distribution.
    pub dtree: &'a DTree,
    /// The probability of sampling it.
    pub alpha: f32,
}

impl<'a> GuideAt<'a> {
    /// The guide at point `p` of `tree`.
    #[inline]
    pub fn new(tree: &'a SdTree, p: Vec3) -> Self {
        let leaf = tree.leaf_at(p);
        let dtree = tree.sampling(leaf);
        GuideAt {
            leaf,
            dtree,
            alpha: tree.leaves[leaf as usize].alpha,
        }
    }

    /// The mixture pdf `α·p_guide(wi) + (1−α)·p_bsdf` of world direction `wi`.
    #[inline]
    pub fn mixture_pdf(&self, wi: Vec3, p_bsdf: f32) -> f32 {
        self.mixture_pdf_canonical(dir_to_canonical(wi), p_bsdf).0
    }

    /// The mixture pdf of the direction of canonical point `c`, and the guide's pdf of it (per
    /// unit solid angle).
    #[inline]
    pub fn mixture_pdf_canonical(&self, c: Vec2, p_bsdf: f32) -> (f32, f32) {
        let p_guide = self.dtree.pdf_canonical(c) * (0.25 / PI);
        (self.alpha * p_guide + (1.0 - self.alpha) * p_bsdf, p_guide)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn canonical_map_round_trips() {
        for &(x, y) in &[(0.1f32, 0.2f32), (0.5, 0.5), (0.9, 0.99), (0.01, 0.7)] {
            let p = Vec2::new(x, y);
            let q = dir_to_canonical(canonical_to_dir(p));
            assert!((p - q).abs().max_element() < 1e-5, "{p} {q}");
        }
    }

    /// Refinement splits where the energy is, and the refined tree's records build sums that
    /// add up.
    #[test]
    fn refine_and_build() {
        let mut t = DTree::default();
        for k in 0..1000 {
            let p = Vec2::new(0.1 + 0.001 * (k % 10) as f32, 0.8);
            t.record(p, 1.0);
        }
        t.record(Vec2::new(0.9, 0.1), 1.0);
        t.build();
        assert_eq!(t.total(), 1001.0);
        let r = t.refined(ENERGY_FRACTION);
        assert!(r.node_count() > 4, "{}", r.node_count());
        assert!(r.depth() >= 4);
        assert_eq!(r.total(), 0.0);
    }
}

#[cfg(test)]
mod spatial {
    use super::*;

    /// Records made at points of a plane, each toward one point above it, teach every leaf the
    /// direction to that point: after four iterations (and spatial splits) the learned density
    /// at two far-apart points peaks within 12° of their own directions.
    #[test]
    fn records_teach_the_leaf_they_were_made_in() {
        let target = Vec3::new(5.0, 10.0, 5.0);
        let mut t = SdTree::new(Vec3::ZERO, Vec3::splat(10.0));
        for k in 0..4 {
            let mut recs = Vec::new();
            for i in 0..20000u32 {
                let p = Vec3::new((i % 100) as f32 * 0.1, 0.0, (i / 100 % 100) as f32 * 0.1);
                let d = (target - p).normalize();
                recs.push(Record {
                    leaf: t.leaf_at(p),
                    point: dir_to_canonical(d),
                    value: 1.0,
                    product: 0.0,
                    pdf: 1.0,
                    p_bsdf: 1.0,
                    p_guide: 1.0,
                });
            }
            t.add_records(recs);
            t.finish_iteration(k);
        }
        assert!(t.size().leaves > 1);
        for p in [Vec3::new(1.5, 0.0, 8.0), Vec3::new(8.0, 0.0, 1.0)] {
            let d = (target - p).normalize();
            let g = t.sampling(t.leaf_at(p));
            let mut best = (0.0f32, Vec3::ZERO);
            for i in 0..256 {
                for j in 0..128 {
                    let c = Vec2::new((j as f32 + 0.5) / 128.0, (i as f32 + 0.5) / 256.0);
                    let q = canonical_to_dir(c);
                    if g.pdf(q) > best.0 {
                        best = (g.pdf(q), q);
                    }
                }
            }
            assert!(
                best.1.dot(d) > 12f32.to_radians().cos(),
                "{p}: {d} vs {:?}",
                best
            );
        }
    }
}
