//! A small scene's walk: at most [`SMALL_BLOCKS`] blocks of 8 triangles, tested without the
//! tree. Where the blocks' boxes are expected to spare block tests ([`BOX_TEST_COST`]), a ray
//! tests them first, 8 at once (the slab test: `t = (corner − o)·(1/d)` per axis, entry the
//! largest near `t`, exit the smallest far `t`, clipped to `[0, tmax]`); then it tests each
//! block (whose box it enters), 8 triangles at once, in block order, skipping a block whose box
//! it enters past its closest hit so far. A shadow ray stops at the first block that blocks it.
//!
//! Each box is padded by `10⁻⁵` of the largest coordinate of the scene's box (a few hundred
//! ulps of any coordinate): a block whose triangles lie in one plane has a flat box, which a
//! ray enters and leaves at the same `t` as it meets the plane, up to rounding; with the pad the
//! box is entered before any of its triangles' hits, so a block holding a hit as near as the
//! closest so far (a tie: [`super::triangles::closer`]) is tested, and the walk finds the
//! tree's hit.

use super::triangles::TriBlock;
#[cfg(target_arch = "x86_64")]
use super::triangles::{block_any_avx2, block_closest_avx2};
use super::Accel;
use glam::{Vec2, Vec3A};
use obvhs::ray::Ray;

/// Most blocks of 8 triangles a scene may have for its rays to skip the tree (128 triangles):
/// a walk pays its stack, its node tests (1.6 a ray on Mitsuba's box) and a branch per hit
/// child. Measured first with every block tested and no boxes (1 thread, 128², 16 spp, three
/// interleaved pairs; `--stats`' trace rate while tracing, tree → every block): the Cornell box
/// (4 blocks) 10.7 → 16.5 M rays/s, Mitsuba's box (5) 11.1 → 14.0, the gap (6) 9.6 → 11.6, the
/// door (7) 8.3 → 13.6, the lamp (8) 9.5 → 11.9, but the glossy plates (12) 10.6 → 8.9 and
/// sun-sky (13) 13.2 → 7.7; with the boxes tested first, the plates 9.5 → 14.0 and sun-sky 14.1
/// → 15.9 against the tree.
pub(super) const SMALL_BLOCKS: usize = 16;

/// What a test of the blocks' boxes costs, in tests of a block: the boxes are tested first
/// only where they are expected to spare more block tests than this. A line through the scene's
/// box crosses a block's box with probability about their surface areas' ratio, so the test is
/// expected to spare `blocks − Σ area_k / area` block tests. Measured (1 thread, 128², 32 spp,
/// three interleaved pairs, trace rate while tracing, boxes first against every block): the
/// Cornell box (1.2 spared) 0.86× and 0.77× as fast, Mitsuba's box (2.6) 0.98×, the door (3.8)
/// 0.96×, the gap (3.3) 1.06×, the lamp (5.3) 1.22×, the plates and sun-sky (11, 12) far
/// faster than the tree. The runs drift by ±10% (five more pairs on the two boxes later read
/// 1.09× and 0.95×), so below 3 the choice matters little either way. (A path's rays start inside
/// the room, where the areas' ratio says too little: a ray from inside enters the boxes of the
/// walls around it.)
const BOX_TEST_COST: f32 = 3.0;

/// The empty box, and the union of two boxes `(lo, hi)`.
const EMPTY: (Vec3A, Vec3A) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
fn union((a, b): (Vec3A, Vec3A), (lo, hi): (Vec3A, Vec3A)) -> (Vec3A, Vec3A) {
    (a.min(lo), b.max(hi))
}

/// The boxes of a small scene's blocks, each axis's lower and upper planes a row of 16 lanes
/// (one lane a block; the second 8 tested only where there are more than 8 blocks), padded
/// (see the module doc); `lanes` has a bit for each block.
#[derive(Clone, Debug)]
#[repr(C, align(32))]
pub(super) struct BlockBoxes {
    pub(super) lo: [[f32; 16]; 3],
    pub(super) hi: [[f32; 16]; 3],
    pub(super) lanes: u32,
    /// Whether the boxes are tested first ([`BlockBoxes::new`] says when).
    pub(super) culls: bool,
}

impl BlockBoxes {
    /// The boxes of `blocks` (the first `count` triangles in them), or `None` past
    /// [`SMALL_BLOCKS`].
    pub(super) fn new(blocks: &[TriBlock], count: usize) -> Option<BlockBoxes> {
        if blocks.len() > SMALL_BLOCKS {
            return None;
        }
        let mut boxes = BlockBoxes {
            lo: [[0.0; 16]; 3],
            hi: [[0.0; 16]; 3],
            lanes: (1u32 << blocks.len()) - 1,
            culls: false,
        };
        let bounds: Vec<(Vec3A, Vec3A)> = (0..blocks.len())
            .map(|k| {
                (8 * k..count.min(8 * k + 8))
                    .map(|i| blocks[k].bounds(i % 8))
                    .fold(EMPTY, union)
            })
            .collect();
        let largest = bounds
            .iter()
            .map(|(lo, hi)| lo.abs().max(hi.abs()).max_element())
            .fold(0.0f32, f32::max);
        let pad = largest * 1e-5;
        let area = |(lo, hi): &(Vec3A, Vec3A)| {
            let e = (*hi - *lo).max(Vec3A::ZERO);
            e.x * e.y + e.y * e.z + e.z * e.x
        };
        let all = bounds.iter().copied().fold(EMPTY, union);
        let entered: f32 = bounds
            .iter()
            .map(|b| area(b) / area(&all).max(f32::MIN_POSITIVE))
            .sum();
        boxes.culls = blocks.len() as f32 - entered > BOX_TEST_COST;
        for (k, (lo, hi)) in bounds.into_iter().enumerate() {
            for axis in 0..3 {
                boxes.lo[axis][k] = lo[axis] - pad;
                boxes.hi[axis][k] = hi[axis] + pad;
            }
        }
        Some(boxes)
    }

    /// The blocks whose boxes `ray` enters within `[0, tmax]`, as a bit mask, and each one's
    /// entry `t`.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(super) fn entered_avx2(&self, ray: &Ray) -> (u32, [f32; 16]) {
        use std::arch::x86_64::*;
        // SAFETY: each row is 8 f32s at a 32-byte boundary (BlockBoxes is align(32))
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

/// The closest kept hit of a small scene (see the module doc).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn small_closest_avx2(
    acc: &Accel,
    boxes: &BlockBoxes,
    ray: &mut Ray,
    best: &mut Option<(u32, Vec2, f32)>,
    keep: &impl Fn(u32, Vec2) -> bool,
) {
    let (mut blocks, entry) = if boxes.culls {
        boxes.entered_avx2(ray)
    } else {
        (boxes.lanes, [0.0; 16])
    };
    while blocks != 0 {
        let block = blocks.trailing_zeros() as usize;
        blocks &= blocks - 1;
        if entry[block] <= ray.tmax {
            block_closest_avx2(acc, (block, 0xff), ray, best, keep);
        }
    }
}

/// Whether any triangle of a small scene blocks `ray` and `keep` accepts it.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn small_any_avx2(
    acc: &Accel,
    boxes: &BlockBoxes,
    ray: &Ray,
    keep: &impl Fn(u32, Vec2) -> bool,
) -> bool {
    let mut blocks = if boxes.culls {
        boxes.entered_avx2(ray).0
    } else {
        boxes.lanes
    };
    while blocks != 0 {
        let block = blocks.trailing_zeros() as usize;
        blocks &= blocks - 1;
        if block_any_avx2(acc, (block, 0xff), ray, keep) {
            return true;
        }
    }
    false
}
