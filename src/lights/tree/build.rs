//! Building the light tree: binary, top down by the bucketed surface-area-orientation
//! heuristic (pbrt-v4's `buildBVH`), then collapsed to four children a node.

use super::*;

impl LightTree {
    /// The collapsed node of binary node `at` (its children, each interior one replaced by its
    /// two), at collapsed depth `depth` on path `trail`; its index.
    pub(super) fn collapse(
        &mut self,
        binary: &[TreeNode],
        at: usize,
        trail: u64,
        depth: u32,
    ) -> u32 {
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
}

/// The binary build of `items[range]` at depth `depth`, depth first into `nodes` (a node's
/// first child follows it); the range's bounds.
pub(super) fn build_range(
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

/// The smallest cone holding two cones `(axis, cos half-angle)` (pbrt-v4's union).
pub(super) fn cone_union(a: (Vec3, f32), b: (Vec3, f32)) -> (Vec3, f32) {
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
