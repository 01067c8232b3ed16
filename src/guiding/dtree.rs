//! The directional quadtree of a guide leaf: its energies per quadrant, its density and sampling
//! by hierarchical warping, recording, and refinement (see the parent module's doc).

use super::{canonical_to_dir, dir_to_canonical, MAX_QUAD_DEPTH, MAX_QUAD_NODES};
use crate::sampling::ONE_MINUS_EPSILON;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

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
    /// The mean of its records' values: an estimate of `∫ L_i dω` over the sphere, so that
    /// `radiance · pdf(ω)` estimates the radiance arriving from `ω`.
    radiance: f32,
    /// How the sampling density maps back to the learned one ([`DTree::learned_density`]):
    /// 1 and 0 for an uncompensated tree; for a compensated one its total over the learned
    /// tree's, and 1 (the mean density).
    scale: f32,
    floor: f32,
}

impl Default for DTree {
    fn default() -> Self {
        DTree {
            nodes: vec![QNode::default()],
            total: 0.0,
            radiance: 0.0,
            scale: 1.0,
            floor: 0.0,
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
            radiance: 0.0,
            scale: 1.0,
            floor: 0.0,
        };
        t.build();
        t
    }

    /// The energy recorded in all (a positive total means the tree can be sampled).
    pub fn total(&self) -> f32 {
        self.total
    }

    /// `∫ L_i dω` over the sphere, as learned (0 before).
    #[inline]
    pub fn radiance(&self) -> f32 {
        self.radiance
    }

    /// The learned density (per unit area of the square, normalised to 1 over it) at a point
    /// where this tree's sampling density is `pdf`: `pdf` itself for an uncompensated tree;
    /// for a compensated one ([`DTree::compensated`]) exactly the learned density where `pdf`
    /// is positive, `scale·pdf + 1`, and where it is zero the mean density 1, an upper bound
    /// of the learned one there.
    #[inline]
    pub fn learned_density(&self, pdf: f32) -> f32 {
        self.scale * pdf + self.floor
    }

    /// Set it from the number of records the tree was built from.
    pub(super) fn set_records(&mut self, n: u64) {
        self.radiance = if n > 0 { self.total / n as f32 } else { 0.0 };
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
    pub fn sample_canonical(&self, u: Vec2) -> Vec2 {
        self.sample_canonical_pdf(u).0
    }

    /// [`DTree::sample_canonical`] and the density there ([`DTree::pdf_canonical`] of the
    /// leaf it chose), from the one descent.
    #[inline]
    pub fn sample_canonical_pdf(&self, mut u: Vec2) -> (Vec2, f32) {
        if self.total <= 0.0 {
            return (u, 1.0);
        }
        let mut pdf = 1.0f32;
        let (mut origin, mut size) = (Vec2::ZERO, 1.0f32);
        let mut n = 0usize;
        loop {
            // a column by `u.x·total < left`, then `u.x` rescaled within it: one division on
            // the chain from one level's `u.x` to the next's (two before, `left/total` and then
            // `u.x/p_left`); the same for the row. A side of zero energy is never taken
            // (`u.x·total` can round up to `total` = `left`).
            let s = self.nodes[n].sum;
            let (left, right) = (s[0] + s[2], s[1] + s[3]);
            let total = left + right;
            let x = u.x * total;
            let ix = if x < left || right <= 0.0 {
                u.x = x / left;
                0
            } else {
                u.x = (x - left) / right;
                1
            };
            let (lo, hi) = (s[ix], s[ix + 2]);
            let y = u.y * (lo + hi);
            let iy = if y < lo || hi <= 0.0 {
                u.y = y / lo;
                0
            } else {
                u.y = (y - lo) / hi;
                1
            };
            u = u.clamp(Vec2::ZERO, Vec2::splat(ONE_MINUS_EPSILON));
            size *= 0.5;
            origin += Vec2::new(ix as f32, iy as f32) * size;
            let i = ix | iy << 1;
            pdf *= 4.0 * s[i] / total;
            let c = self.nodes[n].child[i];
            if c == 0 {
                return ((origin + u * size).min(Vec2::splat(ONE_MINUS_EPSILON)), pdf);
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
    #[cfg(test)]
    pub(super) fn record(&mut self, mut p: Vec2, value: f32) {
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

    /// Add `value` spread by a box filter over directions (Müller et al.'s code): over the
    /// square of the leaf's own size centred on `p`, each leaf quadrant it overlaps getting
    /// `value × overlap / box area`, so neighbouring quadrants learn alike and a direction next
    /// to a recorded one is not left at zero. The box keeps all of `value`: `v = φ/2π` wraps, so
    /// the part of the box past `v = 0` or 1 lands on the other side, and `u = (cosθ + 1)/2`
    /// ends at the poles, so a box past `u = 0` or 1 spreads `value` over its part inside
    /// (Müller et al. clip both, losing up to half a record next to `φ = 0` or a pole).
    pub(super) fn record_box(&mut self, p: Vec2, value: f32) {
        // the depth of the leaf at p
        let (mut n, mut q, mut size) = (0usize, p, 1.0f32);
        loop {
            let (i, r) = QNode::quadrant(q);
            size *= 0.5;
            match self.nodes[n].child[i] {
                0 => break,
                c => (n, q) = (c as usize, r),
            }
        }
        let lo = p - Vec2::splat(0.5 * size);
        let hi = lo + Vec2::splat(size);
        let (u0, u1) = (lo.x.max(0.0), hi.x.min(1.0));
        let width = if (u0, u1) == (lo.x, hi.x) {
            size
        } else {
            u1 - u0
        };
        let density = value / (width * size);
        self.splat(
            0,
            Vec2::ZERO,
            1.0,
            (Vec2::new(u0, lo.y), Vec2::new(u1, hi.y)),
            density,
        );
        for shift in [-1.0f32, 1.0] {
            let (a, b) = (lo.y + shift, hi.y + shift);
            if b > 0.0 && a < 1.0 {
                self.splat(
                    0,
                    Vec2::ZERO,
                    1.0,
                    (Vec2::new(u0, a), Vec2::new(u1, b)),
                    density,
                );
            }
        }
    }

    /// Add `density ×` the overlap of box `(lo, hi)` with each leaf quadrant below node `n`
    /// (which spans `origin .. origin + size`).
    fn splat(&mut self, n: usize, origin: Vec2, size: f32, (lo, hi): (Vec2, Vec2), density: f32) {
        let half = 0.5 * size;
        for i in 0..4 {
            let o = origin + Vec2::new((i & 1) as f32, (i >> 1) as f32) * half;
            let w = (hi.min(o + Vec2::splat(half)) - lo.max(o)).max(Vec2::ZERO);
            let area = w.x * w.y;
            if area > 0.0 {
                match self.nodes[n].child[i] {
                    0 => self.nodes[n].sum[i] += density * area,
                    c => self.splat(c as usize, o, half, (lo, hi), density),
                }
            }
        }
    }

    /// Sum the leaves' energies up to the root (children have higher indices than their
    /// parents, so one pass from the back does it).
    pub(super) fn build(&mut self) {
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

    /// Replace each leaf quadrant's energy `s` by `f(s, a)`, `a` the quadrant's share of the
    /// square's area, and sum the tree up again.
    pub(super) fn map_leaves(&mut self, f: impl Fn(f32, f32) -> f32) {
        // children have higher indices than their parents: one pass from the front gives
        // every node the area of its quadrants before its children are reached
        let mut area = vec![0.0f32; self.nodes.len()];
        area[0] = 0.25;
        for n in 0..self.nodes.len() {
            for i in 0..4 {
                match self.nodes[n].child[i] {
                    0 => self.nodes[n].sum[i] = f(self.nodes[n].sum[i], area[n]),
                    c => area[c as usize] = area[n] * 0.25,
                }
            }
        }
        self.build();
    }

    /// This (built) tree compensated for the BSDF strategy it is mixed with (Karlík, Šik,
    /// Vévoda, Skřivan, Křivánek 2019): each leaf quadrant's energy `s` (over area `a` of the
    /// square) becomes `max(0, s − T·a)`, `T` the tree's total, i.e. its density less the
    /// mean density, so the guide spends its samples where the radiance is above average and
    /// the defensive strategy covers the rest. A tree with nothing above its mean (uniform, or
    /// empty) is returned as it is. `∫ L_i dω` ([`DTree::radiance`]) stays the learned one.
    pub fn compensated(&self) -> DTree {
        let mut t = self.clone();
        let mean = self.total;
        t.map_leaves(|s, a| (s - mean * a).max(0.0));
        if t.total > 0.0 {
            t.scale = t.total / self.total;
            t.floor = 1.0;
            t
        } else {
            self.clone()
        }
    }

    /// An empty tree whose quadrants are split where this (built) tree held more than `rho` of
    /// its energy (a quadrant this tree did not split goes on splitting with a quarter of its
    /// energy per child, as the authors' code does), at most [`MAX_QUAD_DEPTH`] deep.
    pub(super) fn refined(&self, rho: f32) -> DTree {
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

#[cfg(test)]
mod tests;
