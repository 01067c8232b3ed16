//! A small scene's walk: at most [`SMALL_BLOCKS`] blocks of 8 triangles, tested without the
//! tree. Of three walks, [`SmallScene::new`] takes the one expected to test the fewest blocks
//! ([`BOX_TEST_COST`]): every block of the BVH's order (8 triangles at consecutive indices);
//! the same blocks, after a test of their boxes; or the triangles regrouped into blocks of
//! nearby triangles ([`groups`]: a wall's, a box's), after a test of theirs. The boxes are
//! tested 8 at once (the slab test: `t = (corner − o)·(1/d)` per axis, entry the largest near
//! `t`, exit the smallest far `t`, clipped to `[0, tmax]`); then the ray tests the blocks whose
//! boxes it enters, 8 triangles at once, the smallest boxes first, skipping a block whose box
//! it enters past its closest hit so far. A shadow ray stops at the first block that blocks it.
//!
//! Regrouped, a room's walls are blocks of their own with flat boxes: a ray from inside enters
//! the box of the wall it hits and of little else, so on Mitsuba's box a closest-hit ray tests
//! about 1.3 of 8 blocks and a shadow ray 0.9, where every one of the BVH order's 5 was tested
//! (a simulation of the box's path rays, 2026-11-30; the smallest boxes first test as few as
//! the nearest entry first would, without sorting, which cost more than it spared).
//!
//! Each box is padded by `10⁻⁵` of the largest coordinate of the scene's box (a few hundred
//! ulps of any coordinate): a block whose triangles lie in one plane has a flat box, which a
//! ray enters and leaves at the same `t` as it meets the plane, up to rounding; with the pad the
//! box is entered before any of its triangles' hits, so a block holding a hit as near as the
//! closest so far (a tie: [`super::triangles::closer`]) is tested. Ties are decided by the
//! triangles' BVH-order indices (kept for each lane in [`SmallScene::ids`]), not by the order
//! the blocks are tested in, so every walk finds the tree's hit, bit for bit.

use super::triangles::TriBlock;
#[cfg(target_arch = "x86_64")]
use super::triangles::{block_any_avx2, block_closest_avx2};
use glam::{Vec2, Vec3A};
use obvhs::ray::Ray;

#[cfg(test)]
pub(super) mod tests;

/// Most blocks of 8 triangles a scene may have for its rays to skip the tree (128 triangles):
/// a walk pays its stack, its node tests (1.6 a ray on Mitsuba's box) and a branch per hit
/// child. Measured first with every block tested and no boxes (1 thread, 128², 16 spp, three
/// interleaved pairs; `--stats`' trace rate while tracing, tree → every block): the Cornell box
/// (4 blocks) 10.7 → 16.5 M rays/s, Mitsuba's box (5) 11.1 → 14.0, the gap (6) 9.6 → 11.6, the
/// door (7) 8.3 → 13.6, the lamp (8) 9.5 → 11.9, but the glossy plates (12) 10.6 → 8.9 and
/// sun-sky (13) 13.2 → 7.7; with the boxes tested first, the plates 9.5 → 14.0 and sun-sky 14.1
/// → 15.9 against the tree.
pub(super) const SMALL_BLOCKS: usize = 16;

/// What a test of the blocks' boxes costs, in tests of a block. A line through the scene's box
/// crosses a block's box with probability about their surface areas' ratio, so a walk with
/// boxes is expected to cost `⌈blocks/8⌉·BOX_TEST_COST + Σ area_k / area` block tests, one
/// without them a test a block ([`SmallScene::new`]). Measured with the regrouping (1 thread,
/// 128², 16 spp, two interleaved pairs, `--stats`' trace rate while tracing, against testing
/// the BVH order's blocks, with their boxes where 3 block tests were expected to be spared):
/// Mitsuba's box 19.2–21.3 → 24.8–26.4 M rays/s (256², 32 spp, three pairs), sun-sky 23.3 →
/// 31–37, the door 16.4–17.1 → 19.2–19.8, the glossy plates 21.1 → 24.5, the Cornell box
/// 21.5–22.5 → 22.6–23.3, the gap and the lamp (which keeps the BVH's blocks, with boxes)
/// within ±5%; with the cost at 1 every scene chose a walk no slower than before.
const BOX_TEST_COST: f32 = 1.0;

/// The empty box, and the union of two boxes `(lo, hi)`.
const EMPTY: (Vec3A, Vec3A) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
fn union((a, b): (Vec3A, Vec3A), (lo, hi): (Vec3A, Vec3A)) -> (Vec3A, Vec3A) {
    (a.min(lo), b.max(hi))
}

/// Half the surface area of a box (0 for the empty one).
fn area((lo, hi): (Vec3A, Vec3A)) -> f32 {
    let e = (hi - lo).max(Vec3A::ZERO);
    e.x * e.y + e.y * e.z + e.z * e.x
}

/// The groupings of triangles (their boxes `bounds`) into groups of at most 8, for each count
/// of groups from [`SMALL_BLOCKS`] down to the fewest reached: `out[k]` has `k` groups (empty
/// where none was made). Agglomerative: from a group a triangle, the two groups whose union's
/// box adds the least surface area to theirs are merged, while some two fit in 8 (two halves of
/// a quad have one box, so they merge first; a flat wall's triangles next, then its neighbours).
pub(super) fn groups(bounds: &[(Vec3A, Vec3A)]) -> Vec<Vec<Vec<u32>>> {
    let n = bounds.len();
    let mut members: Vec<Vec<u32>> = (0..n as u32).map(|i| vec![i]).collect();
    let mut boxes = bounds.to_vec();
    let mut alive: Vec<bool> = vec![true; n];
    let cost = |members: &[Vec<u32>], boxes: &[(Vec3A, Vec3A)], a: usize, b: usize| {
        if members[a].len() + members[b].len() > 8 {
            f32::INFINITY
        } else {
            area(union(boxes[a], boxes[b])) - area(boxes[a]) - area(boxes[b])
        }
    };
    // cost[a * n + b] for a < b
    let mut costs = vec![f32::INFINITY; n * n];
    for a in 0..n {
        for b in a + 1..n {
            costs[a * n + b] = cost(&members, &boxes, a, b);
        }
    }
    let mut out = vec![Vec::new(); SMALL_BLOCKS + 1];
    let mut count = n;
    loop {
        if count <= SMALL_BLOCKS {
            out[count] = (0..n)
                .filter(|&k| alive[k])
                .map(|k| members[k].clone())
                .collect();
        }
        let mut best = (f32::INFINITY, 0, 0);
        for a in (0..n).filter(|&a| alive[a]) {
            for b in (a + 1..n).filter(|&b| alive[b]) {
                if costs[a * n + b] < best.0 {
                    best = (costs[a * n + b], a, b);
                }
            }
        }
        let (c, a, b) = best;
        if c == f32::INFINITY {
            return out;
        }
        let moved = std::mem::take(&mut members[b]);
        members[a].extend(moved);
        boxes[a] = union(boxes[a], boxes[b]);
        alive[b] = false;
        count -= 1;
        for k in (0..n).filter(|&k| alive[k] && k != a) {
            let (lo, hi) = (k.min(a), k.max(a));
            costs[lo * n + hi] = cost(&members, &boxes, lo, hi);
        }
    }
}

/// A small scene's blocks for its walk, and their boxes, each axis's lower and upper planes a
/// row of 16 lanes (one lane a block; the second 8 tested only where there are more than 8
/// blocks), padded (see the module doc).
#[derive(Clone, Debug)]
#[repr(C, align(32))]
pub(super) struct SmallScene {
    pub(super) lo: [[f32; 16]; 3],
    pub(super) hi: [[f32; 16]; 3],
    /// A bit for each block.
    pub(super) lanes: u32,
    /// Whether the boxes are tested first ([`SmallScene::new`] says when).
    pub(super) culls: bool,
    /// The triangles: a regrouping ([`groups`]) or the BVH order's blocks (where the boxes are
    /// tested first, in the order of their boxes' areas).
    pub(super) blocks: Vec<TriBlock>,
    /// The BVH-order index of each block's lanes' triangles.
    pub(super) ids: Vec<[u32; 8]>,
    /// Each block's lanes that hold a triangle, a bit each.
    pub(super) full: Vec<u32>,
}

impl SmallScene {
    /// The walk of the triangles of `blocks` (in BVH order, the first `count` of them), or
    /// `None` past [`SMALL_BLOCKS`] blocks: of every block tested in the BVH's order, the same
    /// blocks after a test of their boxes, and the regroupings of [`groups`] after a test of
    /// theirs, the walk expected to cost least ([`BOX_TEST_COST`]).
    pub(super) fn new(blocks: &[TriBlock], count: usize) -> Option<SmallScene> {
        if blocks.len() > SMALL_BLOCKS {
            return None;
        }
        let tri = |i: usize| blocks[i / 8].bounds(i % 8);
        let bounds: Vec<(Vec3A, Vec3A)> = (0..count).map(tri).collect();
        let all = bounds.iter().copied().fold(EMPTY, union);
        let box_of = |g: &[u32]| g.iter().map(|&i| bounds[i as usize]).fold(EMPTY, union);
        let culled_cost = |g: &[Vec<u32>]| {
            let entered: f32 =
                g.iter().map(|g| area(box_of(g))).sum::<f32>() / area(all).max(f32::MIN_POSITIVE);
            g.len().div_ceil(8) as f32 * BOX_TEST_COST + entered
        };
        let in_order: Vec<Vec<u32>> = (0..blocks.len())
            .map(|k| (8 * k as u32..count.min(8 * k + 8) as u32).collect())
            .collect();
        let mut walks = vec![(blocks.len() as f32, false, in_order.clone())];
        walks.push((culled_cost(&in_order), true, in_order));
        for g in groups(&bounds).into_iter().filter(|g| !g.is_empty()) {
            walks.push((culled_cost(&g), true, g));
        }
        // (a cost from non-finite coordinates is NaN: that walk is not taken; the first's is
        // a count of blocks)
        let (_, culls, mut grouping) = walks
            .into_iter()
            .filter(|w| !w.0.is_nan())
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .expect("one walk at least");
        if culls {
            // the smallest boxes first: a ray enters them past its hit, and skips them, more
            // often than the large ones it leaves the scene through
            grouping.sort_by(|a, b| area(box_of(a)).total_cmp(&area(box_of(b))));
        }
        Some(SmallScene::of_groups(blocks, &grouping, culls))
    }

    /// The walk of the triangles of `blocks` (in BVH order) grouped as `groups` says (each group
    /// at most 8 BVH-order indices, a block each, in their order), testing the blocks' boxes
    /// first where `culls`.
    pub(super) fn of_groups(blocks: &[TriBlock], groups: &[Vec<u32>], culls: bool) -> SmallScene {
        assert!(groups.len() <= SMALL_BLOCKS && groups.iter().all(|g| g.len() <= 8));
        let bounds = |g: &[u32]| {
            g.iter()
                .map(|&i| blocks[i as usize / 8].bounds(i as usize % 8))
                .fold(EMPTY, union)
        };
        let all = groups.iter().map(|g| bounds(g)).fold(EMPTY, union);
        let pad = all.0.abs().max(all.1.abs()).max_element() * 1e-5;
        let mut scene = SmallScene {
            lo: [[0.0; 16]; 3],
            hi: [[0.0; 16]; 3],
            lanes: (1u32 << groups.len()) - 1,
            culls,
            blocks: vec![TriBlock::default(); groups.len()],
            ids: vec![[0; 8]; groups.len()],
            full: vec![0; groups.len()],
        };
        for (k, group) in groups.iter().enumerate() {
            for (lane, &id) in group.iter().enumerate() {
                let (block, i) = (id as usize / 8, id as usize % 8);
                for row in 0..12 {
                    scene.blocks[k].rows[row][lane] = blocks[block].rows[row][i];
                }
                scene.ids[k][lane] = id;
                scene.full[k] |= 1 << lane;
            }
            let (lo, hi) = bounds(group);
            for axis in 0..3 {
                scene.lo[axis][k] = lo[axis] - pad;
                scene.hi[axis][k] = hi[axis] + pad;
            }
        }
        scene
    }

    /// The blocks whose boxes `ray` enters within `[0, tmax]`, as a bit mask, and each one's
    /// entry `t`.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(super) fn entered_avx2(&self, ray: &Ray) -> (u32, [f32; 16]) {
        use std::arch::x86_64::*;
        // SAFETY: each row is 8 f32s at a 32-byte boundary (SmallScene is align(32))
        #[allow(unsafe_code)]
        let load = |row: &[f32; 16], h: usize| unsafe { _mm256_load_ps(row.as_ptr().add(8 * h)) };
        let mut entry = [0.0f32; 16];
        let mut mask = 0;
        for h in 0..(self.lanes > 0xff) as usize + 1 {
            let mut near = _mm256_setzero_ps();
            let mut far = _mm256_set1_ps(ray.tmax);
            for axis in 0..3 {
                let (o, inv) = (
                    _mm256_set1_ps(ray.origin[axis]),
                    _mm256_set1_ps(ray.inv_direction[axis]),
                );
                let t0 = _mm256_mul_ps(_mm256_sub_ps(load(&self.lo[axis], h), o), inv);
                let t1 = _mm256_mul_ps(_mm256_sub_ps(load(&self.hi[axis], h), o), inv);
                near = _mm256_max_ps(near, _mm256_min_ps(t0, t1));
                far = _mm256_min_ps(far, _mm256_max_ps(t0, t1));
            }
            mask |= (_mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(near, far)) as u32) << (8 * h);
            // SAFETY: `entry` holds 16 f32s; 8 are written from lane 8h
            #[allow(unsafe_code)]
            unsafe {
                _mm256_storeu_ps(entry.as_mut_ptr().add(8 * h), near)
            };
        }
        (mask & self.lanes, entry)
    }
}

/// The closest kept hit of a small scene (see the module doc): with the boxes, the blocks whose
/// boxes the ray enters, in the scene's order, each skipped if entered past the closest hit.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn small_closest_avx2(
    scene: &SmallScene,
    ray: &mut Ray,
    best: &mut Option<(u32, Vec2, f32)>,
    keep: &impl Fn(u32, Vec2) -> bool,
) {
    let (mut blocks, entry) = if scene.culls {
        scene.entered_avx2(ray)
    } else {
        (scene.lanes, [0.0; 16])
    };
    while blocks != 0 {
        let k = blocks.trailing_zeros() as usize;
        blocks &= blocks - 1;
        if entry[k] <= ray.tmax {
            let ids = &scene.ids[k];
            block_closest_avx2(
                &scene.blocks[k],
                (scene.full[k], |i| ids[i]),
                ray,
                best,
                keep,
            );
        }
    }
}

/// Whether any triangle of a small scene blocks `ray` and `keep` accepts it.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn small_any_avx2(
    scene: &SmallScene,
    ray: &Ray,
    keep: &impl Fn(u32, Vec2) -> bool,
) -> bool {
    let mut blocks = if scene.culls {
        scene.entered_avx2(ray).0
    } else {
        scene.lanes
    };
    while blocks != 0 {
        let k = blocks.trailing_zeros() as usize;
        blocks &= blocks - 1;
        let ids = &scene.ids[k];
        if block_any_avx2(&scene.blocks[k], (scene.full[k], |i| ids[i]), ray, keep) {
            return true;
        }
    }
    false
}
