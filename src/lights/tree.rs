//! The light tree (`--light-choice tree`): a BVH over the emitters whose nodes bound their
//! power, box and cone of normals (Conty Estevez & Kulla 2018; pbrt-v4's `BVHLightSampler`),
//! built by the bucketed surface-area-orientation heuristic. A receiver descends it choosing
//! each child in proportion to an importance bound; [`LightTree::units`] follows one emitter's
//! stored path to give the exact pmf of [`LightTree::choose`] (whole units of 2⁻²⁴).

use super::Emitter;
use glam::Vec3;

/// What a light BVH node bounds of its emitters: their box, their power, the cone of their
/// normals (axis `w`, half-angle `θ_o`) and of their emission about a normal (`θ_e`: π/2 for
/// one-sided diffuse emitters), as pbrt-v4's `LightBounds`.
#[derive(Clone, Copy, Debug)]
pub struct LightBounds {
    lo: Vec3,
    hi: Vec3,
    w: Vec3,
    phi: f32,
    cos_theta_o: f32,
    cos_theta_e: f32,
}

impl LightBounds {
    fn of(e: &Emitter) -> LightBounds {
        let (c, k) = e.corners();
        let (lo, hi) = c[..k].iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &v| (lo.min(v), hi.max(v)),
        );
        LightBounds {
            lo,
            hi,
            w: e.n,
            phi: e.power(),
            cos_theta_o: 1.0,
            cos_theta_e: 0.0,
        }
    }

    fn centroid(&self) -> Vec3 {
        0.5 * (self.lo + self.hi)
    }

    /// The union: boxes and powers add, cones merge (pbrt-v4's `DirectionCone` union).
    fn union(a: Option<LightBounds>, b: LightBounds) -> LightBounds {
        let Some(a) = a else {
            return b;
        };
        // a powerless side bounds nothing (pbrt-v4), but its box still holds its emitters
        let (w, cos_theta_o) = if a.phi == 0.0 {
            (b.w, b.cos_theta_o)
        } else if b.phi == 0.0 {
            (a.w, a.cos_theta_o)
        } else {
            cone_union((a.w, a.cos_theta_o), (b.w, b.cos_theta_o))
        };
        LightBounds {
            lo: a.lo.min(b.lo),
            hi: a.hi.max(b.hi),
            w,
            phi: a.phi + b.phi,
            cos_theta_o,
            cos_theta_e: a.cos_theta_e.min(b.cos_theta_e),
        }
    }

    /// The importance bound of these emitters for a receiver at `p` with normal `n` (pbrt-v4's
    /// `LightBounds::Importance`): `Φ cos θ′ / d²` with `θ′` the smallest angle between the
    /// emitters' normals and the direction to `p` over the box's directions, zero where `p` is
    /// outside every emission cone, times the receiver's smallest cosine toward the box.
    pub fn importance(&self, p: Vec3, n: Vec3) -> f32 {
        NodeBounds::of(self).importance(p, n)
    }
}

/// A [`LightBounds`] as the tree's descent reads it: what the importance needs, computed once
/// at build time (centre, squared bounding radius, the distance floor, the cone's sine).
#[derive(Clone, Copy, Debug)]
struct NodeBounds {
    centre: Vec3,
    /// Squared radius of the box's bounding sphere.
    radius2: f32,
    /// The floor of the squared distance: half the box's diagonal (pbrt-v4).
    min_d2: f32,
    w: Vec3,
    phi: f32,
    cos_theta_o: f32,
    sin_theta_o: f32,
    cos_theta_e: f32,
}

impl NodeBounds {
    fn of(b: &LightBounds) -> NodeBounds {
        let diag = b.hi - b.lo;
        NodeBounds {
            centre: b.centroid(),
            radius2: (0.5 * diag).length_squared(),
            min_d2: diag.length() / 2.0,
            w: b.w,
            phi: b.phi,
            cos_theta_o: b.cos_theta_o,
            sin_theta_o: (1.0 - b.cos_theta_o * b.cos_theta_o).max(0.0).sqrt(),
            cos_theta_e: b.cos_theta_e,
        }
    }

    /// The importance bound of these emitters for a receiver at `p` with normal `n` (pbrt-v4's
    /// `LightBounds::Importance`): `Φ cos θ′ / d²` with `θ′` the smallest angle between the
    /// emitters' normals and the direction to `p` over the box's directions, zero where `p` is
    /// outside every emission cone, times the receiver's smallest cosine toward the box. Angles
    /// are subtracted as (sine, cosine) pairs, without trigonometry.
    #[inline]
    fn importance(&self, p: Vec3, n: Vec3) -> f32 {
        // cos(a − b) and sin(a − b), clamped at 0 when b ≥ a
        #[inline(always)]
        fn cos_sub(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
            if cos_a > cos_b {
                1.0
            } else {
                cos_a * cos_b + sin_a * sin_b
            }
        }
        #[inline(always)]
        fn sin_sub(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
            if cos_a > cos_b {
                0.0
            } else {
                sin_a * cos_b - cos_a * sin_b
            }
        }
        let v = p - self.centre;
        let dist2 = v.length_squared();
        let wi = v * dist2.sqrt().recip();
        let cos_w = if dist2 > 0.0 { self.w.dot(wi) } else { 1.0 };
        let sin_w = (1.0 - cos_w * cos_w).max(0.0).sqrt();
        // the cone of directions from p that the box subtends (its bounding sphere)
        let cos_b = if dist2 < self.radius2 {
            -1.0
        } else {
            (1.0 - self.radius2 / dist2).max(0.0).sqrt()
        };
        let sin_b = (1.0 - cos_b * cos_b).max(0.0).sqrt();
        let cos_x = cos_sub(sin_w, cos_w, self.sin_theta_o, self.cos_theta_o);
        let sin_x = sin_sub(sin_w, cos_w, self.sin_theta_o, self.cos_theta_o);
        let cos_p = cos_sub(sin_x, cos_x, sin_b, cos_b);
        if cos_p <= self.cos_theta_e {
            return 0.0;
        }
        let cos_i = if dist2 > 0.0 { wi.dot(n).abs() } else { 1.0 };
        let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
        let importance =
            self.phi * cos_p * cos_sub(sin_i, cos_i, sin_b, cos_b) / dist2.max(self.min_d2);
        importance.max(0.0)
    }
}

/// The smallest cone holding two cones `(axis, cos half-angle)` (pbrt-v4's union).
fn cone_union(a: (Vec3, f32), b: (Vec3, f32)) -> (Vec3, f32) {
    let pi = std::f32::consts::PI;
    let (theta_a, theta_b) = (a.1.clamp(-1.0, 1.0).acos(), b.1.clamp(-1.0, 1.0).acos());
    let theta_d = a.0.dot(b.0).clamp(-1.0, 1.0).acos();
    if (theta_d + theta_b).min(pi) <= theta_a {
        return a;
    }
    if (theta_d + theta_a).min(pi) <= theta_b {
        return b;
    }
    let theta_o = (theta_a + theta_d + theta_b) / 2.0;
    if theta_o >= pi {
        return (Vec3::Z, -1.0);
    }
    let theta_r = theta_o - theta_a;
    let wr = a.0.cross(b.0);
    if wr.length_squared() == 0.0 {
        return (Vec3::Z, -1.0);
    }
    // rotate a's axis by θ_r about wr (perpendicular to it)
    let k = wr.normalize();
    let w = a.0 * theta_r.cos() + k.cross(a.0) * theta_r.sin();
    (w.normalize_or_zero(), theta_o.cos())
}

/// A light BVH over the emitters (pbrt-v4's `BVHLightSampler`): binary, depth first (a node's
/// first child follows it), built top down by the bucketed surface-area-orientation heuristic
/// of Conty Estevez & Kulla.
#[derive(Debug)]
pub struct LightTree {
    nodes: Vec<TreeNode>,
    /// Per emitter, the path from the root to its leaf: bit `k` set means the second child at
    /// depth `k`.
    trail: Vec<u64>,
}

#[derive(Clone, Copy, Debug)]
struct TreeNode {
    bounds: NodeBounds,
    /// A leaf's emitter, or an interior node's second child.
    child_or_light: u32,
    leaf: bool,
}

/// The deepest the tree may grow: a light's path is one bit per level of a u64 trail.
const MAX_TREE_DEPTH: u32 = 63;
/// Past this depth splits halve by count, so the at most 2²⁴ lights below end within
/// [`MAX_TREE_DEPTH`] (it was 48: an SAOH split that peels one light per level then left
/// 70,000 lights to halve, 65 levels in all, and deep paths shared their last bit).
const COUNT_SPLIT_DEPTH: u32 = MAX_TREE_DEPTH - 24;

impl LightTree {
    /// The tree over `emitters` (at least one).
    pub fn build(emitters: &[Emitter]) -> LightTree {
        let mut items: Vec<(u32, LightBounds)> = emitters
            .iter()
            .enumerate()
            .map(|(i, e)| (i as u32, LightBounds::of(e)))
            .collect();
        let mut tree = LightTree {
            nodes: Vec::with_capacity(2 * emitters.len()),
            trail: vec![0; emitters.len()],
        };
        if !items.is_empty() {
            let n = items.len();
            tree.build_range(&mut items, 0..n, 0, 0);
        }
        tree
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True without emitters.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Its depth: the most branchings from the root to a leaf.
    pub fn depth(&self) -> u32 {
        fn down(t: &LightTree, at: usize) -> u32 {
            let node = &t.nodes[at];
            if node.leaf {
                0
            } else {
                1 + down(t, at + 1).max(down(t, node.child_or_light as usize))
            }
        }
        if self.nodes.is_empty() {
            0
        } else {
            down(self, 0)
        }
    }

    /// Bytes the nodes and trails take.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.nodes.as_slice()) + std::mem::size_of_val(self.trail.as_slice())
    }

    fn build_range(
        &mut self,
        items: &mut [(u32, LightBounds)],
        range: std::ops::Range<usize>,
        trail: u64,
        depth: u32,
    ) -> LightBounds {
        let (start, end) = (range.start, range.end);
        if end - start == 1 {
            let (light, b) = items[start];
            self.trail[light as usize] = trail;
            self.nodes.push(TreeNode {
                bounds: NodeBounds::of(&b),
                child_or_light: light,
                leaf: true,
            });
            return b;
        }
        let mid = if depth >= COUNT_SPLIT_DEPTH {
            (start + end) / 2
        } else {
            split(&mut items[start..end]).map_or((start + end) / 2, |m| start + m)
        };
        let at = self.nodes.len();
        self.nodes.push(TreeNode {
            bounds: NodeBounds::of(&items[start].1),
            child_or_light: 0,
            leaf: false,
        });
        let b0 = self.build_range(items, start..mid, trail, depth + 1);
        let second = self.nodes.len() as u32;
        let b1 = self.build_range(
            items,
            mid..end,
            trail | (1u64 << depth.min(MAX_TREE_DEPTH)),
            depth + 1,
        );
        let b = LightBounds::union(Some(b0), b1);
        self.nodes[at] = TreeNode {
            bounds: NodeBounds::of(&b),
            child_or_light: second,
            leaf: false,
        };
        b
    }

    /// The units of `range` that node `at`'s two children get from `(p, n)`: the split point
    /// (`range.start..split` to the first child), or `None` when neither has importance.
    #[inline]
    fn split_units(
        &self,
        at: usize,
        p: Vec3,
        n: Vec3,
        range: &std::ops::Range<u32>,
    ) -> Option<u32> {
        let node = &self.nodes[at];
        let c0 = self.nodes[at + 1].bounds.importance(p, n);
        let c1 = self.nodes[node.child_or_light as usize]
            .bounds
            .importance(p, n);
        let len = range.end - range.start;
        if !(c0 > 0.0 || c1 > 0.0) {
            return None;
        }
        let share = if c1 <= 0.0 {
            len
        } else if c0 <= 0.0 {
            0
        } else if len < 2 {
            if c0 >= c1 {
                len
            } else {
                0
            }
        } else {
            // len · c0/(c0 + c1), rounded (len ≤ 2²⁴ is exact in f64)
            let s = (len as f64 * c0 as f64 / (c0 as f64 + c1 as f64) + 0.5) as u32;
            s.clamp(1, len - 1)
        };
        Some(range.start + share)
    }

    /// The emitter chosen by unit `k` of `range` for a receiver at `p` (normal `n`), and its
    /// units (its probability times 2²⁴).
    pub fn choose(
        &self,
        p: Vec3,
        n: Vec3,
        k: u32,
        mut range: std::ops::Range<u32>,
    ) -> Option<(u32, u32)> {
        let mut at = 0usize;
        loop {
            let node = &self.nodes[at];
            if node.leaf {
                // (a lone emitter is not tested: a point behind it is refused by the caller)
                return (!range.is_empty())
                    .then_some((node.child_or_light, range.end - range.start));
            }
            let s = self.split_units(at, p, n, &range)?;
            if k < s {
                range.end = s;
                at += 1;
            } else {
                range.start = s;
                at = node.child_or_light as usize;
            }
            if range.is_empty() {
                return None;
            }
        }
    }

    /// The units of `range` that emitter `i` gets from `(p, n)`: what [`LightTree::choose`]
    /// gives it, following its path.
    pub fn units(&self, p: Vec3, n: Vec3, i: u32, mut range: std::ops::Range<u32>) -> u32 {
        let mut trail = self.trail[i as usize];
        let mut at = 0usize;
        loop {
            let node = &self.nodes[at];
            if node.leaf {
                return range.end - range.start;
            }
            let Some(s) = self.split_units(at, p, n, &range) else {
                return 0;
            };
            if trail & 1 == 0 {
                range.end = s;
                at += 1;
            } else {
                range.start = s;
                at = node.child_or_light as usize;
            }
            trail >>= 1;
            if range.is_empty() {
                return 0;
            }
        }
    }
}

/// The split of `items` (two or more) by the bucketed surface-area-orientation heuristic
/// (pbrt-v4's `buildBVH`, 12 buckets per axis): the items are partitioned in place and the
/// first part's length returned; `None` when no split helps (the caller halves by count).
fn split(items: &mut [(u32, LightBounds)]) -> Option<usize> {
    const BUCKETS: usize = 12;
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    let (mut clo, mut chi) = (lo, hi);
    for (_, b) in items.iter() {
        lo = lo.min(b.lo);
        hi = hi.max(b.hi);
        clo = clo.min(b.centroid());
        chi = chi.max(b.centroid());
    }
    let diag = hi - lo;
    let bucket = |c: Vec3, dim: usize| {
        let t = (c[dim] - clo[dim]) / (chi[dim] - clo[dim]);
        ((BUCKETS as f32 * t) as usize).min(BUCKETS - 1)
    };
    let mut best: Option<(f32, usize, usize)> = None;
    for dim in 0..3 {
        if chi[dim] == clo[dim] {
            continue;
        }
        let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
        for (_, b) in items.iter() {
            let k = bucket(b.centroid(), dim);
            buckets[k] = Some(LightBounds::union(buckets[k], *b));
        }
        let merge = |r: &[Option<LightBounds>]| {
            r.iter()
                .flatten()
                .fold(None, |acc, b| Some(LightBounds::union(acc, *b)))
        };
        for i in 0..BUCKETS - 1 {
            let (Some(b0), Some(b1)) = (merge(&buckets[..=i]), merge(&buckets[i + 1..])) else {
                continue;
            };
            let cost = cost(&b0, diag, dim) + cost(&b1, diag, dim);
            if cost > 0.0 && best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, dim, i));
            }
        }
    }
    let (_, dim, at) = best?;
    let mut k = 0;
    for i in 0..items.len() {
        if bucket(items[i].1.centroid(), dim) <= at {
            items.swap(i, k);
            k += 1;
        }
    }
    (k > 0 && k < items.len()).then_some(k)
}

/// pbrt-v4's `EvaluateCost`: power × the measure of the cone of emitted directions × the box's
/// surface area, with a penalty for splitting across the box's short axes.
fn cost(b: &LightBounds, diag: Vec3, dim: usize) -> f32 {
    let pi = std::f32::consts::PI;
    let theta_o = b.cos_theta_o.clamp(-1.0, 1.0).acos();
    let theta_e = b.cos_theta_e.clamp(-1.0, 1.0).acos();
    let theta_w = (theta_o + theta_e).min(pi);
    let sin_o = (1.0 - b.cos_theta_o * b.cos_theta_o).max(0.0).sqrt();
    let m_omega = 2.0 * pi * (1.0 - b.cos_theta_o)
        + pi / 2.0
            * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o
                + b.cos_theta_o);
    let kr = diag.max_element() / diag[dim].max(1e-30);
    let d = b.hi - b.lo;
    let area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
    b.phi * m_omega * kr * area
}
