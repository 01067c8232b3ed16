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

/// One S-tree leaf as a render reads it: the distribution that samples this iteration.
#[derive(Clone, Debug, PartialEq)]
pub struct Leaf {
    /// What this iteration samples from (built from the previous iteration's records).
    pub sampling: DTree,
    /// The probability of sampling the guide here this iteration.
    pub alpha: f32,
}

/// What one S-tree leaf records into during an iteration, which no render reads: kept apart
/// from [`Leaf`] so that a chunk's records can be added while the next chunk renders
/// ([`SdTree::add_records_during`]).
#[derive(Clone, Debug, PartialEq)]
struct Learner {
    /// The distribution being built from this iteration's records.
    building: DTree,
    /// Records this iteration.
    samples: u64,
    /// What learns the leaf's `alpha`.
    fraction: FractionLearner,
}

/// The SD-tree: an S-tree over the scene's bounding cube with a [`Leaf`] per leaf.
#[derive(Clone, Debug, PartialEq)]
pub struct SdTree {
    min: Vec3,
    /// Edge of the bounding cube.
    size: f32,
    nodes: Vec<SNode>,
    /// The node at depth [`TOP_BITS`] (or the leaf above it) for each value of a point's first
    /// `TOP_BITS` Morton digits, with its depth: `node | depth << TOP_DEPTH_SHIFT`
    /// ([`Self::index_top`]). A lookup starts there, a dozen dependent loads later than the root.
    top: Vec<u32>,
    pub(super) leaves: Vec<Leaf>,
    /// Each leaf's [`Learner`], by the same index.
    learners: Vec<Learner>,
    /// The image's mean luminance as the last training iteration estimated it.
    image_mean: f32,
}

/// Levels of the S-tree a lookup skips through [`SdTree`]'s `top` table (4096 entries, 16 KiB).
const TOP_BITS: u32 = 12;

/// Where a `top` entry's depth starts (its node index below, at most 2^26 nodes).
const TOP_DEPTH_SHIFT: u32 = 26;

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

/// Binary digits of each coordinate in an S-tree lookup's Morton code (3 × 21 = 63 levels).
const MORTON_BITS: u32 = 21;

/// `2^MORTON_BITS`: a coordinate in `[0, 1)` times this, truncated, is its first digits.
const MORTON_SCALE: f32 = (1u32 << MORTON_BITS) as f32;

/// The low 21 bits of `v` spread to every third bit (bit `i` to bit `3i`).
#[inline]
fn spread3(v: u32) -> u64 {
    let mut x = (v & 0x1f_ffff) as u64;
    x = (x | x << 32) & 0x1f_0000_0000_ffff;
    x = (x | x << 16) & 0x1f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

/// The Morton code of three 21-bit coordinates, x's digit first at each level: bit 62 is x's
/// top digit, bit 61 y's, bit 60 z's, bit 59 x's second, and so on.
#[inline]
fn morton3(x: u32, y: u32, z: u32) -> u64 {
    spread3(x) << 2 | spread3(y) << 1 | spread3(z)
}

impl SdTree {
    /// An untrained tree over the box `min..max` (made a cube, slightly enlarged so that every
    /// surface point lies inside).
    pub fn new(min: Vec3, max: Vec3) -> SdTree {
        let extent = (max - min).max_element().max(1e-6);
        let pad = extent * 1e-3;
        let mut t = SdTree {
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
                alpha: GUIDE_FRACTION,
            }],
            learners: vec![Learner {
                building: DTree::default().refined(ENERGY_FRACTION),
                samples: 0,
                fraction: FractionLearner::default(),
            }],
            image_mean: 1.0,
            top: Vec::new(),
        };
        t.index_top();
        t
    }

    /// Rebuild the `top` table after the nodes changed: for each value of the first
    /// [`TOP_BITS`] Morton digits, the descent of [`Self::leaf_and_extent`] that far.
    fn index_top(&mut self) {
        assert!(
            self.nodes.len() < 1 << TOP_DEPTH_SHIFT,
            "an S-tree of 2^26 nodes"
        );
        self.top = (0..1u32 << TOP_BITS)
            .map(|digits| {
                let (mut n, mut d) = (0usize, 0u32);
                while d < TOP_BITS && self.nodes[n].child != 0 {
                    n = self.nodes[n].child as usize + (digits >> (TOP_BITS - 1 - d) & 1) as usize;
                    d += 1;
                }
                n as u32 | d << TOP_DEPTH_SHIFT
            })
            .collect();
    }

    /// The index of the leaf holding point `p` (points outside the cube go to the nearest
    /// leaf).
    #[inline]
    pub fn leaf_at(&self, p: Vec3) -> u32 {
        self.leaf_and_extent(p).0
    }

    /// The index of the leaf holding point `p`, and the leaf box's edges (world units).
    ///
    /// The split axes cycle with the depth (the root splits x, its children y, theirs z, …), so
    /// the half a point lies in at depth `d` is the next binary digit of its coordinate along
    /// axis `d mod 3`: the descent reads the digits from one 63-bit Morton code of the first 21
    /// digits of each coordinate (the digits the two-branch form `q ≥ ½`, `q ← 2q − (q ≥ ½)`
    /// read, exactly; below depth 63 it goes on so), and starts at depth 12 (`TOP_BITS`) from the
    /// `top` table. A level is then a node load and a shift: the descent was 10–14% of a guided
    /// render's profile on the door (21 levels deep at 900 leaves), a float coordinate per level
    /// carried through memory and a branch on a coin flip.
    #[inline]
    pub fn leaf_and_extent(&self, p: Vec3) -> (u32, Vec3) {
        let q = ((p - self.min) / self.size).clamp(Vec3::ZERO, Vec3::splat(ONE_MINUS_EPSILON));
        let s = q * MORTON_SCALE;
        let code = morton3(s.x as u32, s.y as u32, s.z as u32);
        let top = self.top[(code >> (3 * MORTON_BITS - TOP_BITS)) as usize];
        let mut n = (top & ((1 << TOP_DEPTH_SHIFT) - 1)) as usize;
        let mut d = top >> TOP_DEPTH_SHIFT;
        loop {
            let node = self.nodes[n];
            if node.child == 0 {
                return (node.leaf, self.extent_at_depth(d));
            }
            if d == 3 * MORTON_BITS {
                return self.descend_deep(n, s - s.floor());
            }
            let upper = ((code >> (3 * MORTON_BITS - 1 - d)) & 1) as usize;
            n = node.child as usize + upper;
            d += 1;
        }
    }

    /// The index of the node (a leaf) holding `p`: [`Self::leaf_and_extent`]'s descent.
    #[cfg(test)]
    fn leaf_node(&self, p: Vec3) -> usize {
        let leaf = self.leaf_and_extent(p).0;
        (self.nodes.iter())
            .position(|n| n.child == 0 && n.leaf == leaf)
            .unwrap()
    }

    /// The edges of a leaf `d` levels deep: the cube's, halved along x `⌈d/3⌉` times, along y
    /// `⌈(d−1)/3⌉`, along z `⌊d/3⌋` (exact: powers of two).
    #[inline]
    fn extent_at_depth(&self, d: u32) -> Vec3 {
        let half = |h: u32| self.size * f32::from_bits((127 - h.min(126)) << 23);
        Vec3::new(half(d.div_ceil(3)), half((d + 1) / 3), half(d / 3))
    }

    /// The descent below depth `3·MORTON_BITS` from node `n`, with `q` the coordinates' digits
    /// past the Morton code's (as fractions): one digit a level, as [`Self::leaf_and_extent`]
    /// reads them.
    #[cold]
    fn descend_deep(&self, mut n: usize, q: Vec3) -> (u32, Vec3) {
        let mut q = q.to_array();
        let mut d = 3 * MORTON_BITS;
        loop {
            let node = self.nodes[n];
            if node.child == 0 {
                return (node.leaf, self.extent_at_depth(d));
            }
            let a = (d % 3) as usize;
            let upper = (q[a] >= 0.5) as usize;
            q[a] = q[a] * 2.0 - upper as f32;
            n = node.child as usize + upper;
            d += 1;
        }
    }

    /// The leaf a record made at `p` goes to, by the stochastic box filter of Müller et al.'s
    /// code: `p` moved by `(u − ½) ⊙ extent`, `extent` the edges of `p`'s own leaf (as
    /// [`Self::leaf_and_extent`] gives them; a caller that looked `p` up already passes them
    /// on), so a record teaches the leaves within one leaf size of where it was made, each in
    /// proportion to the overlap (on average), and neighbouring leaves learn alike.
    #[inline]
    pub fn splat_leaf(&self, p: Vec3, extent: Vec3, u: Vec3) -> u32 {
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

    /// Add `records` (in the order the renders made them) to the distributions being built.
    pub fn add_records(&mut self, records: &[Record]) {
        record(&self.leaves, &mut self.learners, &[records]);
    }

    /// Run `work` on this tree while the sets of `records` are added to it, as if
    /// concatenated, as [`Self::add_records`] would: a render samples only from what the last
    /// iteration built, and records go only into what this one builds, so a training chunk
    /// renders while the chunk before it is recorded (on the door the records took a fifth of
    /// the training's wall time, the render waiting). `work`'s result.
    pub fn add_records_during<R: Send>(
        &mut self,
        records: Vec<Vec<Record>>,
        work: impl FnOnce(&SdTree) -> R + Send,
    ) -> R {
        let mut learners = std::mem::take(&mut self.learners);
        let tree = &*self;
        let (out, ()) = rayon::join(
            || work(tree),
            || record(&tree.leaves, &mut learners, &records),
        );
        self.learners = learners;
        out
    }

    /// End a training iteration of `paths` path samples: what it recorded becomes the sampling
    /// distribution, the S-tree is refined by the counts and the D-trees rebuilt empty by the
    /// energies (see the module doc).
    pub fn finish_iteration(&mut self, paths: u64) {
        self.leaves
            .par_iter_mut()
            .zip(self.learners.par_iter_mut())
            .for_each(|(leaf, learner)| {
                learner.building.build();
                learner.building.set_records(learner.samples);
                leaf.sampling = learner.building.compensated();
            });
        let threshold = SPATIAL_THRESHOLD * (paths as f64 / REFERENCE_PATHS).sqrt();
        // split leaves breadth-first by index order (deterministic); a split leaf's halves each
        // take half its count and a copy of its distribution
        let mut n = 0;
        while n < self.nodes.len() {
            let node = self.nodes[n];
            let at = node.leaf as usize;
            if node.child == 0 && self.learners[at].samples as f64 > threshold {
                let learner = self.learners[at].clone();
                let half = Learner {
                    samples: learner.samples / 2,
                    ..learner
                };
                let child = self.nodes.len() as u32;
                let axis = (node.axis + 1) % 3;
                self.learners[at] = half.clone();
                let second = self.leaves.len() as u32;
                self.leaves.push(self.leaves[at].clone());
                self.learners.push(half);
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
        self.index_top();
        self.leaves
            .par_iter_mut()
            .zip(self.learners.par_iter_mut())
            .for_each(|(leaf, learner)| {
                learner.building = learner.building.refined(ENERGY_FRACTION);
                leaf.alpha = learner.fraction.alpha().min(MAX_GUIDE_FRACTION);
                learner.samples = 0;
            });
    }

    /// How big the tree is.
    pub fn size(&self) -> TreeSize {
        TreeSize {
            leaves: self.leaves.len(),
            quad_nodes: self.leaves.iter().map(|l| l.sampling.node_count()).sum(),
            bytes: self.nodes.capacity() * std::mem::size_of::<SNode>()
                + self.leaves.capacity() * std::mem::size_of::<Leaf>()
                + self.learners.capacity() * std::mem::size_of::<Learner>()
                + self
                    .leaves
                    .iter()
                    .zip(&self.learners)
                    .map(|(l, b)| l.sampling.memory_bytes() + b.building.memory_bytes())
                    .sum::<usize>(),
        }
    }
}

/// Add `records` (the sets in order, each in its order) to the `learners` of the tree whose
/// leaves are `leaves`: grouped by leaf ([`group_by_leaf`]), each leaf adding its own in
/// order, leaves in parallel — the same bits for any thread count.
fn record<S: AsRef<[Record]>>(leaves: &[Leaf], learners: &mut [Learner], records: &[S]) {
    let (records, start) = group_by_leaf(records, leaves.len());
    let records = &records;
    learners
        .par_iter_mut()
        .zip(leaves.par_iter())
        .enumerate()
        .for_each(|(i, (learner, leaf))| {
            let (lo, hi) = (start[i], start[i + 1]);
            // α is learned only where a distribution sampled (Müller's code: once the tree is
            // built); before, the guide's pdf is the uniform stand-in
            let learn = leaf.sampling.total() > 0.0;
            for r in &records[lo..hi] {
                learner.building.record_box(r.point, r.value);
                if learn {
                    learner.fraction.learn(r);
                }
            }
            learner.samples += (hi - lo) as u64;
        });
}

/// The records of the sets `records`, as if concatenated, grouped by leaf (of `leaves`
/// leaves), each leaf's records in their given order, and where each leaf's run starts
/// (`leaves + 1` offsets): a counting sort, the order a stable sort by leaf gives. (The stable merge sort it replaces took ~58 ns a record, 40% of
/// adding a training chunk's records on the door, while the render waited; this takes two
/// passes over them.)
fn group_by_leaf<S: AsRef<[Record]>>(records: &[S], leaves: usize) -> (Vec<Record>, Vec<usize>) {
    let mut start = vec![0usize; leaves + 1];
    for r in records.iter().flat_map(S::as_ref) {
        start[r.leaf as usize + 1] += 1;
    }
    for i in 0..leaves {
        start[i + 1] += start[i];
    }
    let mut next = start[..leaves].to_vec();
    let mut grouped = vec![Record::default(); start[leaves]];
    for r in records.iter().flat_map(S::as_ref) {
        let slot = &mut next[r.leaf as usize];
        grouped[*slot] = *r;
        *slot += 1;
    }
    (grouped, start)
}

#[cfg(test)]
mod learning_tests;

#[cfg(test)]
mod spatial {
    use super::*;
    use crate::guiding::{canonical_to_dir, dir_to_canonical};
    use glam::Vec2;

    /// The descent as it was written before the Morton code: a float coordinate per axis,
    /// halved into `2q − (q ≥ ½)` at each split of its axis, the extent halved with it.
    fn descend_by_halving(t: &SdTree, p: Vec3) -> (u32, Vec3) {
        let mut q = ((p - t.min) / t.size).clamp(Vec3::ZERO, Vec3::splat(ONE_MINUS_EPSILON));
        let mut extent = Vec3::splat(t.size);
        let mut n = 0usize;
        loop {
            let node = t.nodes[n];
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

    /// The Morton descent finds the leaf and the extent the halving one does, bit for bit, in
    /// a tree split at random to 40 levels and along one path to 90 (past the code's 63 digits,
    /// where it goes on by halving), at random points and at points on every split plane of
    /// the deep path (where a digit decides: `q = ½` exactly) and outside the cube.
    #[test]
    fn morton_descent_reads_the_digits_halving_reads() {
        let mut t = SdTree::new(Vec3::new(-3.0, 0.5, 2.0), Vec3::new(7.0, 4.0, 9.0));
        use rand::{rngs::SmallRng, Rng, SeedableRng};
        let mut rng = SmallRng::seed_from_u64(7);
        let split = |t: &mut SdTree, n: usize| {
            let axis = (t.nodes[n].axis + 1) % 3;
            let child = t.nodes.len() as u32;
            for _ in 0..2 {
                t.nodes.push(SNode {
                    axis,
                    child: 0,
                    leaf: t.nodes.len() as u32,
                });
            }
            t.nodes[n].child = child;
            t.index_top();
        };
        // random splits to depth 40
        let mut frontier = vec![(0usize, 0u32)];
        while let Some((n, d)) = frontier.pop() {
            if d < 40 && (d < 6 || rng.random::<f32>() < 0.62) {
                split(&mut t, n);
                let c = t.nodes[n].child as usize;
                frontier.extend([(c, d + 1), (c + 1, d + 1)]);
            }
        }
        // one path to depth 90, toward a fixed point
        let deep = Vec3::new(1.234567, 2.345678, 5.4321);
        let mut n = t.leaf_node(deep);
        for _ in 0..90 {
            if t.nodes[n].child == 0 {
                split(&mut t, n);
            }
            n = t.leaf_node(deep);
        }
        assert!(t.nodes.len() > 1000, "{}", t.nodes.len());
        let mut points: Vec<Vec3> = (0..100_000)
            .map(|_| {
                let u = Vec3::new(
                    rng.random::<f32>(),
                    rng.random::<f32>(),
                    rng.random::<f32>(),
                );
                Vec3::new(-3.5, 0.0, 1.5) + u * Vec3::new(11.0, 11.0, 11.0)
            })
            .collect();
        points.extend((0..2000).map(|i| deep + Vec3::splat(i as f32 * 1e-7)));
        let mut deepest = 0;
        for p in points {
            let (a, b) = (t.leaf_and_extent(p), descend_by_halving(&t, p));
            assert_eq!(a.0, b.0, "{p}");
            assert_eq!(
                a.1.to_array().map(f32::to_bits),
                b.1.to_array().map(f32::to_bits)
            );
            deepest = deepest.max((t.size / a.1.z).log2() as u32);
        }
        assert!(
            deepest >= 29,
            "the deep path was reached: {deepest} z splits"
        );
    }

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
            t.add_records(&recs);
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
