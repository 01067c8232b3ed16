//! The light tree (`--light-choice tree`): a BVH over the emitters whose nodes bound their
//! power, box and cone of normals (Conty Estevez & Kulla 2018; pbrt-v4's `BVHLightSampler`),
//! built by the bucketed surface-area-orientation heuristic. A receiver descends it choosing
//! each child in proportion to an importance bound; [`LightTree::units`] follows one emitter's
//! stored path to give the exact pmf of [`LightTree::choose`] (whole units of 2⁻²⁴).

use super::Emitter;
use glam::{Vec3, Vec4};

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
    radius2: Vec4,
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
        radius2: Vec4::ZERO,
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
        self.radius2[i] = b.radius2;
        self.min_d2[i] = b.min_d2;
        self.wx[i] = b.w.x;
        self.wy[i] = b.w.y;
        self.wz[i] = b.w.z;
        self.phi[i] = b.phi;
        self.cos_theta_o[i] = b.cos_theta_o;
        self.sin_theta_o[i] = b.sin_theta_o;
        self.cos_theta_e[i] = b.cos_theta_e;
    }

    /// [`NodeBounds::importance`] of the four lanes at once (the same operations, in the same
    /// order, each lane's the scalar one's bits); 0 in unused lanes.
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
        // cos(a − b) and sin(a − b), clamped at 0 when b ≥ a
        #[inline(always)]
        fn cos_sub(sin_a: Vec4, cos_a: Vec4, sin_b: Vec4, cos_b: Vec4) -> Vec4 {
            Vec4::select(cos_a.cmpgt(cos_b), Vec4::ONE, cos_a * cos_b + sin_a * sin_b)
        }
        #[inline(always)]
        fn sin_sub(sin_a: Vec4, cos_a: Vec4, sin_b: Vec4, cos_b: Vec4) -> Vec4 {
            Vec4::select(
                cos_a.cmpgt(cos_b),
                Vec4::ZERO,
                sin_a * cos_b - cos_a * sin_b,
            )
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
        let inv = sqrt(dist2).recip();
        let (wix, wiy, wiz) = (vx * inv, vy * inv, vz * inv);
        let far = dist2.cmpgt(Vec4::ZERO);
        let cos_w = Vec4::select(
            far,
            self.wx * wix + self.wy * wiy + self.wz * wiz,
            Vec4::ONE,
        );
        let sin_w = sqrt(pos(Vec4::ONE - cos_w * cos_w));
        // the cone of directions from p that the box subtends (its bounding sphere)
        let cos_b = Vec4::select(
            dist2.cmplt(self.radius2),
            Vec4::NEG_ONE,
            sqrt(pos(Vec4::ONE - self.radius2 / dist2)),
        );
        let sin_b = sqrt(pos(Vec4::ONE - cos_b * cos_b));
        let cos_x = cos_sub(sin_w, cos_w, self.sin_theta_o, self.cos_theta_o);
        let sin_x = sin_sub(sin_w, cos_w, self.sin_theta_o, self.cos_theta_o);
        let cos_p = cos_sub(sin_x, cos_x, sin_b, cos_b);
        let lit = cos_p.cmpgt(self.cos_theta_e);
        let dot_n = wix * Vec4::splat(n.x) + wiy * Vec4::splat(n.y) + wiz * Vec4::splat(n.z);
        let cos_i = Vec4::select(far, dot_n.abs(), Vec4::ONE);
        let sin_i = sqrt(pos(Vec4::ONE - cos_i * cos_i));
        let importance =
            self.phi * cos_p * cos_sub(sin_i, cos_i, sin_b, cos_b) / dist2.max(self.min_d2);
        Vec4::select(lit, pos(importance), Vec4::ZERO)
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

    /// The collapsed node of binary node `at` (its children, each interior one replaced by its
    /// two), at collapsed depth `depth` on path `trail`; its index.
    fn collapse(&mut self, binary: &[TreeNode], at: usize, trail: u64, depth: u32) -> u32 {
        assert!(depth < 32, "a light tree deeper than its trail's 64 bits");
        let node = &binary[at];
        let mut lanes = [0usize; WIDTH];
        let mut count = 0;
        if node.leaf {
            lanes[0] = at;
            count = 1;
        } else {
            for c in [at + 1, node.child_or_light as usize] {
                if binary[c].leaf {
                    lanes[count] = c;
                    count += 1;
                } else {
                    lanes[count] = c + 1;
                    lanes[count + 1] = binary[c].child_or_light as usize;
                    count += 2;
                }
            }
        }
        let index = self.nodes.len();
        self.nodes.push(WideNode::EMPTY);
        let mut wide = WideNode::EMPTY;
        wide.count = count as u8;
        for (lane, &b) in lanes[..count].iter().enumerate() {
            wide.set_lane(lane, &binary[b].bounds);
            let path = trail | (lane as u64) << (2 * depth);
            if binary[b].leaf {
                let light = binary[b].child_or_light;
                wide.child[lane] = light;
                wide.leaves |= 1 << lane;
                self.trail[light as usize] = path;
            } else {
                wide.child[lane] = self.collapse(binary, b, path, depth + 1);
            }
        }
        self.nodes[index] = wide;
        index as u32
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
    #[inline]
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
            let (mut cum, mut given) = (0.0f64, 0u32);
            for i in 0..WIDTH {
                if imp[i] > 0.0 {
                    cum += imp[i] as f64;
                    given += 1;
                }
                // extra · cum/total, rounded (len ≤ 2²⁴ is exact in f64)
                let e = if given == m {
                    extra
                } else {
                    ((extra as f64 * cum / total + 0.5) as u32).min(extra)
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

/// The binary build of `items[range]` at depth `depth`, depth first into `nodes` (a node's
/// first child follows it); the range's bounds.
fn build_range(
    nodes: &mut Vec<TreeNode>,
    items: &mut [(u32, LightBounds)],
    range: std::ops::Range<usize>,
    depth: u32,
) -> LightBounds {
    let (start, end) = (range.start, range.end);
    if end - start == 1 {
        let (light, b) = items[start];
        nodes.push(TreeNode {
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
    let at = nodes.len();
    nodes.push(TreeNode {
        bounds: NodeBounds::of(&items[start].1),
        child_or_light: 0,
        leaf: false,
    });
    let b0 = build_range(nodes, items, start..mid, depth + 1);
    let second = nodes.len() as u32;
    let b1 = build_range(nodes, items, mid..end, depth + 1);
    let b = LightBounds::union(Some(b0), b1);
    nodes[at] = TreeNode {
        bounds: NodeBounds::of(&b),
        child_or_light: second,
        leaf: false,
    };
    b
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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::SmallRng;
    use rand::{Rng, SeedableRng};

    /// The four lanes of a collapsed node compute pbrt-v4's importance bound bit for bit as the
    /// scalar [`NodeBounds::importance`] does for each child alone (the same operations in the
    /// same order; `sqrtps` rounds as `sqrtss`), zero included (behind a cone, inside a box),
    /// and an unused lane has none. Random emitters and their unions, random receivers inside
    /// and around them.
    #[test]
    fn a_nodes_lanes_are_the_scalar_importance() {
        let mut rng = SmallRng::seed_from_u64(7);
        let mut v = || Vec3::new(rng.random(), rng.random(), rng.random()) * 4.0 - 2.0;
        let (mut zero, mut positive) = (0, 0);
        for _ in 0..2000 {
            let tri = |c: Vec3, a: Vec3, b: Vec3, le: f32| {
                LightBounds::of(&Emitter::triangle(0, [c, c + a, c + b], Vec3::splat(le)))
            };
            let e: Vec<LightBounds> = (0..4)
                .map(|k| tri(v(), 0.3 * v(), 0.3 * v(), 1.0 + k as f32))
                .collect();
            let lanes = [
                e[0],
                LightBounds::union(Some(e[0]), e[1]),
                LightBounds::union(Some(e[2]), e[3]),
            ];
            let mut node = WideNode::EMPTY;
            node.count = 3;
            for (i, b) in lanes.iter().enumerate() {
                node.set_lane(i, &NodeBounds::of(b));
            }
            let (p, n) = (v(), v().normalize_or(Vec3::Y));
            let wide = node.importance(p, n).to_array();
            for (i, b) in lanes.iter().enumerate() {
                let scalar = NodeBounds::of(b).importance(p, n);
                assert_eq!(wide[i].to_bits(), scalar.to_bits(), "lane {i}: {wide:?}");
                if scalar > 0.0 {
                    positive += 1;
                } else {
                    zero += 1;
                }
            }
            assert_eq!(wide[3], 0.0, "an unused lane");
        }
        assert!(
            zero > 100 && positive > 1000,
            "{zero} zero, {positive} positive"
        );
    }

    /// A node's split gives every lane of positive importance at least one unit while there
    /// are enough, nothing to a lane without, the whole range in order, and each lane within a
    /// unit of its share of the importance.
    #[test]
    fn a_split_follows_the_importance_in_whole_units() {
        let mut rng = SmallRng::seed_from_u64(11);
        let emitters: Vec<Emitter> = (0..40u32)
            .map(|k| {
                let c = Vec3::new(rng.random(), rng.random(), rng.random()) * 10.0;
                let le = Vec3::splat(rng.random_range(0.1..10.0));
                Emitter::triangle(k, [c, c + Vec3::X, c + Vec3::Z], le)
            })
            .collect();
        let tree = LightTree::build(&emitters);
        for _ in 0..500 {
            let p = Vec3::new(rng.random(), rng.random(), rng.random()) * 12.0 - 1.0;
            let len: u32 = rng.random_range(1..200);
            let range = 5..5 + len;
            let node = &tree.nodes[rng.random_range(0..tree.nodes.len())];
            let Some(b) = tree.split_units(node, p, Vec3::Y, &range) else {
                continue;
            };
            let imp = node.importance(p, Vec3::Y).to_array();
            let m = imp.iter().filter(|&&c| c > 0.0).count() as u32;
            let total: f64 = imp.iter().map(|&c| c as f64).sum();
            assert_eq!((b[0], b[WIDTH]), (range.start, range.end));
            for i in 0..WIDTH {
                let units = b[i + 1] - b[i];
                if imp[i] <= 0.0 {
                    assert_eq!(units, 0, "lane {i} without importance: {imp:?}");
                } else if len >= m {
                    let share = (len - m) as f64 * imp[i] as f64 / total;
                    assert!(units >= 1 && (units as f64 - 1.0 - share).abs() <= 1.0);
                }
            }
        }
    }
}
