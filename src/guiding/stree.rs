//! The spatial binary tree of the guide (the S-tree): its leaves, each with the D-tree that
//! samples and the one being recorded, the records' arrival and the splits between iterations.

use super::fraction::FractionLearner;
use super::{
    DTree, Record, ENERGY_FRACTION, GUIDE_FRACTION, MAX_GUIDE_FRACTION, REFERENCE_PATHS,
    SPATIAL_THRESHOLD,
};
use crate::sampling::ONE_MINUS_EPSILON;
use glam::Vec3;
use rayon::prelude::*;

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

/// The SD-tree: an S-tree over the scene's bounding cube with a [`Leaf`] per leaf.
#[derive(Clone, Debug, PartialEq)]
pub struct SdTree {
    min: Vec3,
    /// Edge of the bounding cube.
    size: f32,
    nodes: Vec<SNode>,
    pub(super) leaves: Vec<Leaf>,
    /// The image's mean luminance as the last training iteration estimated it.
    image_mean: f32,
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
            image_mean: 1.0,
        }
    }

    /// The index of the leaf holding point `p` (points outside the cube go to the nearest
    /// leaf).
    #[inline]
    pub fn leaf_at(&self, p: Vec3) -> u32 {
        self.leaf_and_extent(p).0
    }

    /// The index of the leaf holding point `p`, and the leaf box's edges (world units).
    #[inline]
    pub fn leaf_and_extent(&self, p: Vec3) -> (u32, Vec3) {
        let mut q = ((p - self.min) / self.size).clamp(Vec3::ZERO, Vec3::splat(ONE_MINUS_EPSILON));
        let mut extent = Vec3::splat(self.size);
        let mut n = 0usize;
        loop {
            let node = self.nodes[n];
            if node.child == 0 {
                return (node.leaf, extent);
            }
            let a = node.axis as usize;
            extent[a] *= 0.5;
            if q[a] < 0.5 {
                q[a] *= 2.0;
                n = node.child as usize;
            } else {
                q[a] = (q[a] - 0.5) * 2.0;
                n = node.child as usize + 1;
            }
        }
    }

    /// The leaf a record made at `p` goes to, by the stochastic box filter of Müller et al.'s
    /// code: `p` moved by `(u − ½) ⊙ extent`, the extent of `p`'s own leaf, so a record
    /// teaches the leaves within one leaf size of where it was made, each in proportion to
    /// the overlap (on average), and neighbouring leaves learn alike.
    #[inline]
    pub fn splat_leaf(&self, p: Vec3, u: Vec3) -> u32 {
        let extent = self.leaf_and_extent(p).1;
        self.leaf_at(p + (u - Vec3::splat(0.5)) * extent)
    }

    /// The image's mean luminance as training estimated it (1 before).
    #[inline]
    pub fn image_mean(&self) -> f32 {
        self.image_mean
    }

    /// Set it.
    pub fn set_image_mean(&mut self, m: f32) {
        if m.is_finite() && m > 0.0 {
            self.image_mean = m;
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
                // α is learned only where a distribution sampled (Müller's code: once the
                // tree is built); before, the guide's pdf is the uniform stand-in
                let learn = leaf.sampling.total() > 0.0;
                for r in &records[lo..hi] {
                    leaf.building.record_box(r.point, r.value);
                    if learn {
                        leaf.fraction.learn(r);
                    }
                }
                leaf.samples += (hi - lo) as u64;
            });
    }

    /// End a training iteration of `paths` path samples: what it recorded becomes the sampling
    /// distribution, the S-tree is refined by the counts and the D-trees rebuilt empty by the
    /// energies (see the module doc).
    pub fn finish_iteration(&mut self, paths: u64) {
        self.leaves.par_iter_mut().for_each(|leaf| {
            leaf.building.build();
            leaf.building.set_records(leaf.samples);
            leaf.sampling = leaf.building.compensated();
        });
        let threshold = SPATIAL_THRESHOLD * (paths as f64 / REFERENCE_PATHS).sqrt();
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
            leaf.building = leaf.building.refined(ENERGY_FRACTION);
            leaf.alpha = leaf.fraction.alpha().min(MAX_GUIDE_FRACTION);
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

#[cfg(test)]
mod spatial {
    use super::*;
    use crate::guiding::{canonical_to_dir, dir_to_canonical};
    use glam::Vec2;

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
            t.finish_iteration(20000 << k);
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
