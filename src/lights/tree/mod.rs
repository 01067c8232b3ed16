//! The light tree (`--light-choice tree`): a BVH over the emitters whose nodes bound their
//! power, box and cone of normals (Conty Estevez & Kulla 2018; pbrt-v4's `BVHLightSampler`),
//! built by the bucketed surface-area-orientation heuristic. A receiver descends it choosing
//! each child in proportion to an importance bound; [`LightTree::units`] follows one emitter's
//! stored path to give the exact pmf of [`LightTree::choose`] (whole units of 2⁻²⁴).

use super::Emitter;
use glam::{Vec3, Vec4};

mod build;
#[cfg(test)]
mod tests;
use build::{build_range, cone_union};

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
        let mut node = WideNode::EMPTY;
        node.count = 1;
        node.set_lane(0, &NodeBounds::of(self));
        node.importance(p, n).x
    }
}

/// A [`LightBounds`] as the tree's descent reads it: what the importance needs, computed once
/// at build time (centre, bounding radius, the distance floor, the cone's sine).
#[derive(Clone, Copy, Debug)]
struct NodeBounds {
    centre: Vec3,
    /// Radius of the box's bounding sphere.
    radius: f32,
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
            radius: (0.5 * diag).length(),
            min_d2: diag.length() / 2.0,
            w: b.w,
            phi: b.phi,
            cos_theta_o: b.cos_theta_o,
            sin_theta_o: (1.0 - b.cos_theta_o * b.cos_theta_o).max(0.0).sqrt(),
            cos_theta_e: b.cos_theta_e,
        }
    }
}

/// Children of a node of the descent tree.
const WIDTH: usize = 4;

/// A light BVH over the emitters (pbrt-v4's `BVHLightSampler`, four children a node): built
/// binary, top down by the bucketed surface-area-orientation heuristic of Conty Estevez & Kulla,
/// then collapsed (a node's children are its binary children, each interior one replaced by its
/// own two), so a descent evaluates the importance of four children at once, lane by lane
/// (`WideNode::importance`), in half the levels. Nodes are depth first.
#[derive(Debug)]
pub struct LightTree {
    nodes: Vec<WideNode>,
    /// Per emitter, the path from the root to its leaf: bits `2k, 2k + 1` are its lane at
    /// depth `k`.
    trail: Vec<u64>,
}

/// A node of the binary build.
#[derive(Clone, Copy, Debug)]
struct TreeNode {
    bounds: NodeBounds,
    /// A leaf's emitter, or an interior node's second child.
    child_or_light: u32,
    leaf: bool,
}

/// A node of the descent: the [`NodeBounds`] of up to [`WIDTH`] children, one lane each.
#[derive(Clone, Copy, Debug)]
struct WideNode {
    cx: Vec4,
    cy: Vec4,
    cz: Vec4,
    radius: Vec4,
    min_d2: Vec4,
    wx: Vec4,
    wy: Vec4,
    wz: Vec4,
    phi: Vec4,
    cos_theta_o: Vec4,
    sin_theta_o: Vec4,
    cos_theta_e: Vec4,
    /// Per lane: its emitter (a leaf) or its node.
    child: [u32; WIDTH],
    /// Bit `i`: lane `i` is an emitter.
    leaves: u8,
    /// Lanes in use: 2 to 4, or 1 in the tree of a lone emitter.
    count: u8,
}

impl WideNode {
    /// No lanes: an unused lane has no power, so no importance.
    const EMPTY: WideNode = WideNode {
        cx: Vec4::ZERO,
        cy: Vec4::ZERO,
        cz: Vec4::ZERO,
        radius: Vec4::ZERO,
        min_d2: Vec4::ONE,
        wx: Vec4::ZERO,
        wy: Vec4::ZERO,
        wz: Vec4::ONE,
        phi: Vec4::ZERO,
        cos_theta_o: Vec4::ONE,
        sin_theta_o: Vec4::ZERO,
        cos_theta_e: Vec4::ZERO,
        child: [0; WIDTH],
        leaves: 0,
        count: 0,
    };

    fn set_lane(&mut self, i: usize, b: &NodeBounds) {
        self.cx[i] = b.centre.x;
        self.cy[i] = b.centre.y;
        self.cz[i] = b.centre.z;
        self.radius[i] = b.radius;
        self.min_d2[i] = b.min_d2;
        self.wx[i] = b.w.x;
        self.wy[i] = b.w.y;
        self.wz[i] = b.w.z;
        self.phi[i] = b.phi;
        self.cos_theta_o[i] = b.cos_theta_o;
        self.sin_theta_o[i] = b.sin_theta_o;
        self.cos_theta_e[i] = b.cos_theta_e;
    }

    /// The importance bound of each lane's emitters for a receiver at `p` with normal `n`
    /// (pbrt-v4's `LightBounds::Importance`): `Φ cos θ′ / max(d², min_d2)` with `θ′` the smallest
    /// angle between the emitters' normals and the direction to `p` over the box's directions,
    /// zero where `p` is outside every emission cone, times the receiver's smallest cosine toward
    /// the box. The four lanes at once, each the bits of the scalar formula (the tests keep it as
    /// the reference, and pbrt's angles beside it); 0 in unused lanes.
    ///
    /// No trigonometry, and no square root waits on another: with `v = p − centre` and `d = |v|`,
    /// every angle is carried as the pair `(d cos θ, d sin θ)` of lengths, `(w·v, √(d² − (w·v)²))`
    /// for the normals' axis, `(√(d² − r²), r)` for the cone of the box's bounding sphere (radius
    /// `r`); a difference of two such angles, `d² cos(a − b) = A_c B_c + A_s B_s`, is a product of
    /// two, and one reciprocal `1/d²` brings the two cosines of the bound back to numbers.
    #[inline(always)]
    fn importance(&self, p: Vec3, n: Vec3) -> Vec4 {
        #[inline(always)]
        fn sqrt(v: Vec4) -> Vec4 {
            #[cfg(target_arch = "x86_64")]
            {
                // SSE2 is part of x86-64: sqrtps, correctly rounded as the scalar sqrt
                use std::arch::x86_64::{__m128, _mm_sqrt_ps};
                // SAFETY: SSE2, hence SSE, is part of every x86-64 target
                #[allow(unsafe_code)]
                Vec4::from(unsafe { _mm_sqrt_ps(__m128::from(v)) })
            }
            #[cfg(not(target_arch = "x86_64"))]
            {
                v.sqrt()
            }
        }
        // max(x, 0) with a NaN x giving 0 (maxps returns its second operand then)
        #[inline(always)]
        fn pos(x: Vec4) -> Vec4 {
            x.max(Vec4::ZERO)
        }
        let (vx, vy, vz) = (
            Vec4::splat(p.x) - self.cx,
            Vec4::splat(p.y) - self.cy,
            Vec4::splat(p.z) - self.cz,
        );
        let dist2 = vx * vx + vy * vy + vz * vz;
        let d = sqrt(dist2);
        // what the bound is where both cosines are 1 (θ′ = θ_i′ = 0)
        let scale = self.phi / dist2.max(self.min_d2);
        // θ_w, from the normals' axis to v
        let wv = self.wx * vx + self.wy * vy + self.wz * vz;
        let sw = sqrt(pos(dist2 - wv * wv));
        // θ_b, the half-angle of the box's bounding sphere seen from p
        let radius2 = self.radius * self.radius;
        let cb = sqrt(pos(dist2 - radius2));
        let sb = self.radius;
        // θ_x = θ_w − θ_o, clamped at 0
        let in_cone = wv.cmpgt(d * self.cos_theta_o);
        let cx = Vec4::select(in_cone, d, wv * self.cos_theta_o + sw * self.sin_theta_o);
        let sx = Vec4::select(
            in_cone,
            Vec4::ZERO,
            sw * self.cos_theta_o - wv * self.sin_theta_o,
        );
        // d² cos θ′, θ′ = θ_x − θ_b clamped at 0
        let cp = Vec4::select(cx.cmpgt(cb), dist2, cx * cb + sx * sb);
        // d² cos θ_i′ at the receiver, θ_i′ = θ_i − θ_b clamped at 0
        let nv = vx * Vec4::splat(n.x) + vy * Vec4::splat(n.y) + vz * Vec4::splat(n.z);
        let ci = nv.abs();
        let si = sqrt(pos(dist2 - nv * nv));
        let cip = Vec4::select(ci.cmpgt(cb), dist2, ci * cb + si * sb);
        let inv2 = dist2.recip();
        let importance = scale * (cp * inv2) * (cip * inv2);
        // inside the bounding sphere (θ_b = π) or at its centre, both angles are 0
        let whole = dist2.cmplt(radius2) | dist2.cmple(Vec4::ZERO);
        let lit = cp.cmpgt(self.cos_theta_e * dist2);
        // pos: a powerless point box at p is 0/0, and gets 0 as before
        Vec4::select(
            whole,
            pos(scale),
            Vec4::select(lit, pos(importance), Vec4::ZERO),
        )
    }
}

/// The deepest the binary build may grow: a light's path in the collapsed tree is two bits a
/// level of a u64 trail, and a collapsed level takes two binary ones (32 levels from 63).
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
        let mut binary = Vec::with_capacity(2 * emitters.len());
        let mut tree = LightTree {
            nodes: Vec::with_capacity(emitters.len()),
            trail: vec![0; emitters.len()],
        };
        if !items.is_empty() {
            let n = items.len();
            build_range(&mut binary, &mut items, 0..n, 0);
            tree.collapse(&binary, 0, 0, 0);
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

    /// Its depth: the most branchings from the root to a leaf (each of up to four ways).
    pub fn depth(&self) -> u32 {
        fn down(t: &LightTree, at: usize) -> u32 {
            let node = &t.nodes[at];
            (0..node.count as usize)
                .filter(|&i| node.leaves & (1 << i) == 0)
                .map(|i| down(t, node.child[i] as usize))
                .max()
                .map_or(1, |d| d + 1)
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

    /// How node `at` splits the units of `range` among its lanes for a receiver at `p` with
    /// normal `n`: lane `i` gets `b[i]..b[i + 1]`; `None` when no lane has importance. With `m`
    /// lanes of positive importance and `len ≥ m` units, each gets one unit and the other
    /// `len − m` go by the cumulative importance, rounded (so a lane's share is its importance's
    /// to within a unit); with fewer units than such lanes, one unit each to the `len` of
    /// largest importance (ties to the first). A lone emitter's lane takes the whole range
    /// untested (a point behind it is refused by the caller).
    #[inline(always)]
    fn split_units(
        &self,
        node: &WideNode,
        p: Vec3,
        n: Vec3,
        range: &std::ops::Range<u32>,
    ) -> Option<[u32; WIDTH + 1]> {
        let mut b = [range.end; WIDTH + 1];
        b[0] = range.start;
        if node.count == 1 {
            return Some(b);
        }
        let imp = node.importance(p, n).to_array();
        let m = imp.iter().filter(|&&c| c > 0.0).count() as u32;
        if m == 0 {
            return None;
        }
        let len = range.end - range.start;
        if len >= m {
            let extra = len - m;
            let total: f64 = imp.iter().map(|&c| c as f64).sum();
            // units per importance: one division a node, not one a lane
            let rate = extra as f64 / total;
            let (mut cum, mut given) = (0.0f64, 0u32);
            for i in 0..WIDTH {
                if imp[i] > 0.0 {
                    cum += imp[i] as f64;
                    given += 1;
                }
                // extra · cum/total, rounded (within ~2⁻²⁷ of a unit before rounding: len ≤
                // 2²⁴, f64); the last lane of importance takes the rest exactly
                let e = if given == m {
                    extra
                } else {
                    ((cum * rate + 0.5) as u32).min(extra)
                };
                b[i + 1] = range.start + given + e;
            }
        } else {
            for i in 0..WIDTH {
                let c = imp[i];
                let above = (0..WIDTH)
                    .filter(|&j| imp[j] > c || (imp[j] == c && j < i))
                    .count() as u32;
                b[i + 1] = b[i] + (c > 0.0 && above < len) as u32;
            }
        }
        Some(b)
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
            let node = self.nodes.get(at)?;
            let b = self.split_units(node, p, n, &range)?;
            let lane = (0..node.count as usize).find(|&i| k < b[i + 1])?;
            range = b[lane]..b[lane + 1];
            if range.is_empty() {
                return None;
            }
            if node.leaves & (1 << lane) != 0 {
                return Some((node.child[lane], range.end - range.start));
            }
            at = node.child[lane] as usize;
        }
    }

    /// The units of `range` that emitter `i` gets from `(p, n)`: what [`LightTree::choose`]
    /// gives it, following its path.
    pub fn units(&self, p: Vec3, n: Vec3, i: u32, mut range: std::ops::Range<u32>) -> u32 {
        let mut trail = self.trail[i as usize];
        let mut at = 0usize;
        loop {
            let Some(node) = self.nodes.get(at) else {
                return 0;
            };
            let Some(b) = self.split_units(node, p, n, &range) else {
                return 0;
            };
            let lane = (trail & 3) as usize;
            trail >>= 2;
            range = b[lane]..b[lane + 1];
            if range.is_empty() {
                return 0;
            }
            if node.leaves & (1 << lane) != 0 {
                return range.end - range.start;
            }
            at = node.child[lane] as usize;
        }
    }
}
