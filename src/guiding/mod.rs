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
//! radiance integral over the quadrant it falls in). Under `mis` the radiance gathered is what
//! the estimator counted: emission that a bounce's own ray hits enters with its MIS weight, and
//! the light that next-event estimation found at later vertices enters whole, so the guide does
//! not learn to send samples to light NEE already carries (adding back NEE's `1 − w` share, as
//! before, cost 1.15× in MSE on the door at 10 s). A record is splatted, not dropped in its own
//! cells: in space by the stochastic box filter (it goes to the leaf at its vertex moved by up
//! to half the leaf's extent, [`SdTree::splat_leaf`]) and over directions by a box of the
//! quadtree leaf's size at its point ([`DTree`]'s `record_box`), so neighbouring cells learn
//! alike (on the door at 10 s without the directional box: 1.35× the MSE). Each record also
//! feeds the leaf's learner of `α` (Adam on the KL divergence; see `guiding/fraction.rs`). After the
//! iteration each leaf's quadtree is summed up to its root (with `∫ L_i dω` estimated as its
//! records' mean, [`DTree::radiance`]), and its *MIS-compensated* copy becomes the leaf's
//! sampling distribution (Karlík, Šik, Vévoda, Skřivan, Křivánek, "MIS Compensation: Optimizing
//! Sampling Techniques in Multiple Importance Sampling", 2019; [`DTree::compensated`]): each
//! leaf quadrant's density less the tree's mean density, at least zero. The guide is one of two
//! strategies of a mixture whose other one, the BSDF's, already covers the directions of
//! average radiance; the guide is most use where the radiance is above average and spends its
//! samples there (10 s, six seed pairs; see `MAX_GUIDE_FRACTION` for the whole change). Then an
//! S-tree leaf that recorded more than `c·√(N_k/N_0)` samples ([`SPATIAL_THRESHOLD`]) is halved
//! until its halves have not (each half starts from a copy of the leaf's distribution), and
//! each D-tree is rebuilt empty with a quadrant split where it held more than
//! [`ENERGY_FRACTION`] `ρ` of its leaf's energy (at most [`MAX_QUAD_DEPTH`] levels).
//!
//! **Sampling** (the integrator): one-sample MIS between the BSDF's own strategy (the Phong
//! lobes) and the guide, the guide chosen with probability `α`, learned per leaf from
//! [`GUIDE_FRACTION`] on and at most [`MAX_GUIDE_FRACTION`] (a leaf that has learned nothing has `α = 0`: pure BSDF sampling, as
//! in the first iteration) and scaled at each vertex by its BSDF's diffuse share
//! ([`GuideAt::for_bsdf`]: a narrow lobe is sampled by its own strategy), and an image's path
//! samples the BSDF alone where the diffuse share is below [`MIN_GUIDE_SHARE`]
//! ([`GuideAt::for_image`]);
//! the direction's pdf is the mixture `α·p_guide + (1−α)·p_bsdf`, and that mixture is the BSDF
//! pdf NEE's and the light's MIS weights see. A guided direction below
//! the surface is a failed sample, as for the Phong lobe. Russian roulette asks the guide too
//! ([`GuideAt::survival`]): a path heading where the leaf learned light survives in proportion
//! to what it is expected to bring.
//!
//! **Unbiased.** The training iterations use their own seeds (the render's seed mixed with the
//! iteration number), so the tree that samples the final iteration is a function of samples
//! independent of the final ones. Given the tree, every final sample is an ordinary
//! importance-sampled estimate with a pdf that is positive wherever the BSDF's is
//! (`1 − α ≥ σ(−20) > 0`), hence unbiased; averaging over trees keeps it so, and so is each
//! training iteration's image given the tree it sampled with. The image combines the final
//! iteration with the last training iterations by inverse variance, with weights that sum to one
//! and, per pixel, come from the other half of the image's tiles (`render::combine`;
//! `--training-images discard` keeps the final iteration alone, as before issue 51).
//!
//! **Deterministic.** Tiles record into their own buffers; after each chunk of tiles the records
//! are put in tile order, stably sorted by S-tree leaf, and each leaf adds its own records in
//! that order (leaves in parallel). So the learned tree — sums, splits, everything — is the same
//! bits whatever the thread count or the order tiles finish in, and so is the image.

mod dtree;
mod fraction;
mod stree;

pub use dtree::DTree;
pub use stree::{Leaf, SdTree, TreeSize};

use crate::sampling::ONE_MINUS_EPSILON;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// `α` of a leaf before it has learned its own: the probability of sampling the guide.
pub const GUIDE_FRACTION: f32 = 0.5;

/// The largest share `α` of a leaf's samples the guide takes, whatever its learner says: the
/// BSDF's strategy keeps at least half, as the defensive one of the mixture. The guide samples
/// its MIS-compensated density ([`DTree::compensated`]), zero wherever the learned radiance is
/// below its mean, and there the BSDF's samples alone carry the integrand, with weight
/// `1/((1 − α)·p_bsdf)`: the learner's `α` near 1 makes them fireflies.
///
/// The change as a whole (compensation, this bound, and the guide's roulette reading the
/// learned density, not the compensated one: [`GuideAt::survival`]), `--directions guided` at
/// 10 s, relMSE from six seed pairs (1–6, 11–16; two runs of three, configs interleaved, one
/// denominator per scene), before → after: door 0.127 → 0.102 (1.25×), gap 0.31 → 0.168
/// (1.84×), Cornell box 4.05e-3 → 3.70e-3 (1.10×; phong+mis 4.06e-3). Compensation with the
/// roulette reading the compensated density (0 below the mean: such paths lost the guide's
/// roulette) cost the door 2.7× and the gap 3.1×; without the bound (seeds 1–6) the change
/// gained the door 1.25×, the gap 1.66×, the box 1.02×. Learning the square root of the
/// radiance's second moment (Rath et al. 2020's variance-aware target) instead of its mean
/// gained the Cornell box up to 1.3× but lost the door 1.1–1.3× and the gap up to 1.17×, with
/// or without compensation: not kept.
pub const MAX_GUIDE_FRACTION: f32 = 0.5;

/// The least diffuse share of a BSDF ([`crate::bsdf::Bsdf::diffuse_share`]) at which an image's
/// path is guided at a vertex: below it the guide's share `α` (at most [`MAX_GUIDE_FRACTION`],
/// scaled by it) is below it too, and the vertex samples its BSDF alone, paying no S-tree
/// lookup and no quadtree descents for a mixture the guide would change by less than this (nor
/// the guide's roulette).
/// Training paths are guided at every vertex, so they record there. Unbiased either way: the
/// strategy at a vertex is a function of its BSDF. On the glossy plates (`kd` 0.05, `ks` 0.9:
/// share 0.053) at 10 s (three seed pairs, interleaved): relMSE 6.21e-4 → 5.42e-4 (1.15×), 8%
/// more samples. A rule that also skipped leaves whose learned `α` fell below it gained 1.10×
/// there but cost 1.4× on the Cornell box (whose leaves learn small `α` and then lose the
/// guide's roulette), so the share alone decides: no shipped surface but the plates is this
/// glossy, and every other shipped scene renders the same bits as before.
pub const MIN_GUIDE_SHARE: f32 = 0.1;

/// `c`: an S-tree leaf that recorded more than `c·√(N_k / N_0)` samples in an iteration of
/// `N_k` path samples is split, with `N_0` = [`REFERENCE_PATHS`]: the paper's rule (`c = 12000`,
/// `√(2^k)` at 1280×720 and 1 spp per iteration step) extended to any image size, so the leaves
/// grow as the square root of the paths traced. A fixed `c` gave a 96×64 image only 13–27
/// leaves, each mixing walls and floor: on the door at 10 s a threshold of 1,000 (what this
/// rule gives at 96×64) cut the MSE 1.7× against 12,000.
pub const SPATIAL_THRESHOLD: f64 = 12000.0;

/// `N_0` of [`SPATIAL_THRESHOLD`]: the paths of one sample per pixel at 1280×720.
pub const REFERENCE_PATHS: f64 = 1280.0 * 720.0;

/// `k` of guide-driven Russian roulette ([`GuideAt::survival`]): on the door at 10 s, 4 and 16
/// gave the same MSE, 1.2× lower than roulette by throughput alone and 1.8× lower than
/// roulette off (which made each sample 2.3× dearer).
pub const ROULETTE_SCALE: f32 = 4.0;

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
    let mut phi = crate::math::atan2(d.y, d.x);
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

/// One radiance record: the S-tree leaf of the vertex, the canonical point of the sampled
/// direction, `L_i / p` (see the module doc), and what learning `α` needs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
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

/// The guide a render learns and samples with: the SD-tree. Outside `guiding` the renderer
/// (`render`, `integrator`) names only this and [`GuideAt`], and calls only their functions
/// (`new`, `add_records`, `add_records_during`, `finish_iteration`, `set_image_mean`, `size`;
/// at a vertex `sample`, the pdfs, `survival`, `splat_leaf`), so a second guide is an enum
/// behind this name with those functions: one room. `vrpt guide` and the warp test look into the SD-tree itself
/// (`leaf_at`, `sampling`, `DTree`): they show and test that guide.
pub type Guide = SdTree;

/// The guide at one vertex: the leaf's distribution and `α`.
#[derive(Clone, Copy, Debug)]
pub struct GuideAt<'a> {
    /// The leaf's index.
    pub leaf: u32,
    /// Its sampling distribution.
    pub dtree: &'a DTree,
    /// The probability of sampling it.
    pub alpha: f32,
    /// The tree.
    pub tree: &'a SdTree,
    /// The leaf box's edges (world units), for [`Self::splat_leaf`].
    pub extent: Vec3,
}

impl<'a> GuideAt<'a> {
    /// The guide at point `p` of `tree`.
    #[inline]
    pub fn new(tree: &'a SdTree, p: Vec3) -> Self {
        let (leaf, extent) = tree.leaf_and_extent(p);
        let dtree = tree.sampling(leaf);
        // a leaf that has learned nothing does not guide (its α would sample the sphere)
        let alpha = if dtree.total() > 0.0 {
            tree.leaves[leaf as usize].alpha
        } else {
            0.0
        };
        GuideAt {
            leaf,
            dtree,
            alpha,
            tree,
            extent,
        }
    }

    /// This guide at a vertex whose BSDF takes its diffuse lobe with probability `diffuse` (1
    /// on a diffuse surface, [`crate::bsdf::Bsdf::diffuse_share`]): `α` scaled by it, as
    /// Cycles scales its guiding probability by the BSDF's diffuse sampling fraction. The guide
    /// learns the radiance arriving from each direction, a good proposal under a broad lobe
    /// and a poor one under a narrow lobe, whose own sampling follows the product far better: on
    /// the glossy plates (`kd` 0.05, `ks` 0.9) a guide sampled with the leaves' learned `α`
    /// wasted that share of the plates' samples outside their lobes, and the guided render lost
    /// 3.6× to Phong directions at 10 s. The learner of `α` is unchanged (its gradient weighs
    /// each record by the pdf it was drawn with, whatever mixture drew it).
    #[inline]
    pub fn for_bsdf(mut self, diffuse: f32) -> Self {
        self.alpha *= diffuse;
        self
    }

    /// The guide an image's path (not a training one) samples with at point `p` of `tree`,
    /// under a BSDF of diffuse share `diffuse`: `None` (the BSDF alone, no S-tree lookup) where
    /// `diffuse` is below [`MIN_GUIDE_SHARE`].
    #[inline]
    pub fn for_image(tree: &'a SdTree, p: Vec3, diffuse: f32) -> Option<Self> {
        (diffuse >= MIN_GUIDE_SHARE).then(|| GuideAt::new(tree, p).for_bsdf(diffuse))
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
        let p_guide = self.guide_pdf_canonical(c);
        (self.mixture(p_guide, p_bsdf), p_guide)
    }

    /// A direction drawn from the guide by `u`: its canonical point and the guide's pdf of it
    /// per unit solid angle (from the descent that drew it).
    #[inline]
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (c, p_c) = self.dtree.sample_canonical_pdf(u);
        (c, p_c * Self::PER_STERADIAN)
    }

    /// The leaf a training record at `p` is splatted into, `jitter` in `[0, 1)³` spreading it
    /// over a box the size of its leaf ([`SdTree::splat_leaf`]); `p` is the point this guide
    /// was looked up at, whose leaf's extent it kept (one descent of the S-tree, not two).
    #[inline]
    pub fn splat_leaf(&self, p: Vec3, jitter: Vec3) -> u32 {
        self.tree.splat_leaf(p, self.extent, jitter)
    }

    /// A density per unit area of the canonical square, per unit solid angle: `1/4π`.
    pub const PER_STERADIAN: f32 = 0.25 / PI;

    /// The guide's pdf of the direction of canonical point `c`, per unit solid angle.
    #[inline]
    pub fn guide_pdf_canonical(&self, c: Vec2) -> f32 {
        self.dtree.pdf_canonical(c) * Self::PER_STERADIAN
    }

    /// The survival probability guide-driven Russian roulette asks for a path whose
    /// throughput after this vertex's bounce is `beta`, its direction of guide pdf `p_guide`:
    /// `min(0.99, k·r)` with `r = lum(β)·L̂ / Ī` the rest of the path's expected share of a
    /// pixel — `L̂ = radiance()·p_learned` the radiance the leaf learned to arrive from the
    /// direction (`p_learned` the learned density where the compensated `p_guide` is positive,
    /// the mean density where it is zero: [`DTree::learned_density`]), `Ī` the image's mean luminance from the last training iteration — and `k` =
    /// [`ROULETTE_SCALE`]; 0 where the leaf learned nothing. The integrator keeps a path with
    /// the larger of this and the throughput rule's probability, so a path the guide expects
    /// to carry light is not cut for its small `β` (a guided bounce toward a small bright
    /// opening has a large pdf, hence a small `β`), and the rest end as before. Unbiased for
    /// any value in `(0, 1]`: a survivor is divided by it.
    #[inline]
    pub fn survival(&self, beta: Vec3, p_guide: f32) -> f32 {
        let learned =
            self.dtree.learned_density(p_guide / Self::PER_STERADIAN) * Self::PER_STERADIAN;
        let r =
            crate::math::luminance(beta) * self.dtree.radiance() * learned / self.tree.image_mean();
        if r > 0.0 {
            (ROULETTE_SCALE * r).min(0.99)
        } else {
            0.0
        }
    }

    /// The mixture `α·p_guide + (1−α)·p_bsdf`.
    #[inline]
    pub fn mixture(&self, p_guide: f32, p_bsdf: f32) -> f32 {
        self.alpha * p_guide + (1.0 - self.alpha) * p_bsdf
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

    /// A leaf that has learned nothing does not guide (`α = 0`, no survival asked); once it
    /// has, its `α` is the learned one and guide-driven roulette asks for more survival toward
    /// brighter directions and for larger throughputs, never above 0.99.
    #[test]
    fn an_untrained_leaf_does_not_guide() {
        let mut t = SdTree::new(Vec3::ZERO, Vec3::ONE);
        let p = Vec3::splat(0.5);
        let g = GuideAt::new(&t, p);
        assert_eq!(g.alpha, 0.0);
        assert_eq!(g.survival(Vec3::ONE, 1.0), 0.0);
        let up = dir_to_canonical(Vec3::Y);
        let records: Vec<Record> = (0..4000)
            .map(|k| Record {
                leaf: 0,
                point: if k % 4 == 0 {
                    dir_to_canonical(Vec3::X)
                } else {
                    up
                },
                value: 1.0,
                product: 0.0,
                pdf: 1.0,
                p_bsdf: 1.0,
                p_guide: 1.0,
            })
            .collect();
        t.add_records(&records);
        t.set_image_mean(0.5);
        t.finish_iteration(4000);
        let g = GuideAt::new(&t, p);
        assert_eq!(g.alpha, GUIDE_FRACTION);
        let (bright, dim) = (
            g.guide_pdf_canonical(up),
            g.guide_pdf_canonical(Vec2::new(0.1, 0.6)),
        );
        assert!(bright > dim, "{bright} {dim}");
        let small = Vec3::splat(1e-3);
        assert!(g.survival(small, bright) > g.survival(small, dim));
        assert!(g.survival(small * 10.0, bright) > g.survival(small, bright));
        assert_eq!(g.survival(Vec3::splat(1e6), bright), 0.99);
        // on a diffuse surface the guide keeps its share; under the glossy plates' BSDF (kd
        // 0.05, ks 0.9) it takes the diffuse lobe's share of it, and the mixture follows
        let diffuse = crate::bsdf::Bsdf::new(Vec3::splat(0.5), Vec3::ZERO, 1.0);
        let plate = crate::bsdf::Bsdf::new(Vec3::splat(0.05), Vec3::splat(0.9), 1000.0);
        assert_eq!(g.for_bsdf(diffuse.diffuse_share()).alpha, GUIDE_FRACTION);
        let on_plate = g.for_bsdf(plate.diffuse_share());
        assert!((on_plate.alpha - GUIDE_FRACTION * 0.05 / 0.95).abs() < 1e-6);
        let m = on_plate.mixture(bright, 2.0);
        assert!((m - (on_plate.alpha * bright + (1.0 - on_plate.alpha) * 2.0)).abs() < 1e-6);
        // an image's path is guided on the diffuse surface, not on the plate (share 0.053)
        let image = GuideAt::for_image(&t, p, diffuse.diffuse_share()).expect("guided");
        assert_eq!(image.alpha, GUIDE_FRACTION);
        assert!(GuideAt::for_image(&t, p, plate.diffuse_share()).is_none());
        // records that favour the guide (its pdf 40× the BSDF's where the product is) teach
        // the learner an α above ½; the leaf samples the guide with at most MAX_GUIDE_FRACTION
        for _ in 0..4 {
            let leaf = t.leaf_at(p);
            let records: Vec<Record> = (0..4000)
                .map(|_| Record {
                    leaf,
                    point: up,
                    value: 1.0,
                    product: 1.0,
                    pdf: 0.5 * 4.0 + 0.5 * 0.1,
                    p_bsdf: 0.1,
                    p_guide: 4.0,
                })
                .collect();
            t.add_records(&records);
            t.finish_iteration(4000);
        }
        assert_eq!(GuideAt::new(&t, p).alpha, MAX_GUIDE_FRACTION);
    }
}
