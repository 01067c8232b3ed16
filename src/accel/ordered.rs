//! The walk of a large scene's tree nearest child first: each node's 8 children are tested at
//! once ([`child_spans_avx2`]), the triangles of the hit leaves tested at once as one group, and
//! the hit inner children pushed on a stack with the distance `t_enter` at which the ray enters
//! their boxes, ordered so that the nearest is taken next. A child popped with `t_enter` beyond
//! the ray's `tmax` (a hit found since it was pushed) is dropped without loading its node.
//!
//! obvhs's own walk (its `traverse!`) visits the hit children in a fixed order by the ray's
//! octant and keeps a node's unvisited children as one stack entry without their distances: a
//! child whose box lies beyond a hit found since is loaded and its 8 children tested before the
//! walk learns that. The closest hit is the same either way: [`super::triangles::closer`] orders
//! every hit (ties included) whatever order the triangles are tested in, and the node test is the
//! same arithmetic, so images keep their bits (the accelerator's tests compare the walks hit for
//! hit on every kind of ray and tie).

#[cfg(target_arch = "x86_64")]
use super::node::{child_spans_avx2, hit_bits_avx2};
#[cfg(target_arch = "x86_64")]
use obvhs::{cwbvh::node::CwBvhNode, ray::Ray};

/// The stack of the ordered walk: inner nodes still to visit, each with the distance at which
/// the ray enters its box. A thread keeps it from ray to ray (in a `TraceStack`).
pub(super) type OrderStack = Vec<(u32, f32)>;

/// Walks the tree `nodes` along `ray`, nearest child first, calling `leaves(base, bits, ray)`
/// for the triangles `base + k` (bit `k` of `bits`) of each node's hit leaf children, which may
/// shorten `ray.tmax`; the walk ends when no child is left that the ray enters before
/// `ray.tmax`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn ordered_walk_avx2(
    nodes: &[CwBvhNode],
    stack: &mut OrderStack,
    ray: &mut Ray,
    mut leaves: impl FnMut(u32, u32, &mut Ray),
) {
    use std::arch::x86_64::*;
    stack.clear();
    if nodes.is_empty() {
        return;
    }
    let mut at = 0u32;
    loop {
        let node = &nodes[at as usize];
        let (t_enter, hits) = child_spans_avx2(node, ray);
        let mask = _mm256_movemask_ps(hits) as u32;
        let inner = node.imask as u32;
        if mask & !inner != 0 {
            // a leaf's triangles as the traversal's hit mask places them (its low 24 bits; the
            // octant does not move a leaf's bits)
            let bits = hit_bits_avx2(node, _mm256_castps_si256(hits), 0) & 0x00ff_ffff;
            leaves(node.primitive_base_idx, bits, ray);
        }
        let mut hit_inner = mask & inner;
        if hit_inner != 0 {
            let mut t = [0.0f32; 8];
            // SAFETY: `t` is 8 f32s, what an unaligned store writes
            #[allow(unsafe_code)]
            unsafe {
                _mm256_storeu_ps(t.as_mut_ptr(), t_enter)
            };
            if hit_inner & (hit_inner - 1) == 0 {
                // one child: on to it, unless a leaf's hit lies before it
                let slot = hit_inner.trailing_zeros();
                if t[slot as usize] <= ray.tmax {
                    at = node.child_node_index(slot as usize);
                    continue;
                }
            } else {
                let first = stack.len();
                while hit_inner != 0 {
                    let slot = hit_inner.trailing_zeros();
                    hit_inner &= hit_inner - 1;
                    stack.push((node.child_node_index(slot as usize), t[slot as usize]));
                }
                nearest_last(&mut stack[first..]);
            }
        }
        loop {
            match stack.pop() {
                None => return,
                Some((index, t)) if t <= ray.tmax => {
                    at = index;
                    break;
                }
                Some(_) => {}
            }
        }
    }
}

/// Sorts at most 8 entries by distance, farthest first, so the nearest is popped first
/// (insertion sort: 1–3 entries in most nodes).
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
#[inline(always)]
fn nearest_last(entries: &mut [(u32, f32)]) {
    for i in 1..entries.len() {
        let e = entries[i];
        let mut j = i;
        while j > 0 && entries[j - 1].1 < e.1 {
            entries[j] = entries[j - 1];
            j -= 1;
        }
        entries[j] = e;
    }
}

#[cfg(test)]
mod tests {
    use super::nearest_last;
    use rand::{rngs::SmallRng, Rng, SeedableRng};

    /// The entries pushed for a node come out nearest first: on random sets of 1 to 8 entries
    /// (distances drawn from 4 values, so ties occur), the sorted slice is farthest first and a
    /// permutation of what went in. Fails if the comparison is turned round.
    #[test]
    fn pushed_children_come_out_nearest_first() {
        let mut rng = SmallRng::seed_from_u64(7);
        for _ in 0..10_000 {
            let n = rng.random_range(1..=8);
            let entries: Vec<(u32, f32)> = (0..n)
                .map(|i| (i, rng.random_range(0..4) as f32 * 0.5))
                .collect();
            let mut sorted = entries.clone();
            nearest_last(&mut sorted);
            assert!(sorted.windows(2).all(|w| w[0].1 >= w[1].1), "{sorted:?}");
            let mut ids: Vec<u32> = sorted.iter().map(|e| e.0).collect();
            ids.sort_unstable();
            assert_eq!(ids, (0..n).collect::<Vec<_>>());
            for &(id, t) in &sorted {
                assert_eq!(entries[id as usize].1, t);
            }
        }
    }
}
