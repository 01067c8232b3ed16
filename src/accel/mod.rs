//! The ray-triangle accelerator: an obvhs compressed wide BVH (CWBVH, 8-wide) over all
//! triangles, with the triangles stored in BVH leaf order so a hit indexes them directly.
//!
//! Triangles are obvhs's `RtTriangle` values (`v0`, `e1 = v0 − v1`, `e2 = v2 − v0`, and the
//! normal `ng = e1 × e2`) stored in `TriBlock`s of 8, each coordinate a row of 8 lanes (48
//! bytes a triangle): the CWBVH hands the traversal a *group* of up to 24 triangles at
//! consecutive indices (every leaf child of a node the ray hits), and with AVX2 a block's
//! triangles are tested 8 at a time by the Möller–Trumbore test of obvhs (one triangle at a time
//! with a branch each was 45 % of a closest-hit traversal on Mitsuba's box, 3.4 triangles a ray).
//! A hit reports the barycentrics `(b1, b2)` of `v1` and `v2`: the point is
//! `(1 − b1 − b2)·v0 + b1·v1 + b2·v2`. Indices in a [`Hit`] and in [`Accel::order`] are BVH-order
//! indices; `order[i]` is the input index of BVH triangle `i`.
//!
//! **Traversal**: a closest-hit ray walks the tree nearest child first (`ordered.rs`: a child
//! beyond a hit found since it was seen is dropped unloaded; 0.92× a large mesh's render time,
//! the same hits); a shadow ray and a CPU without AVX2 take obvhs's own loop (its `traverse!`
//! macro over the CWBVH nodes). Both are driven from here so a renderer pays no per-ray cost it
//! does not need (issue 19): the node stacks are a [`TraceStack`] that a thread keeps from ray
//! to ray (obvhs's entry points zero a fresh 256-byte stack for every ray: 2 % of a render's
//! instructions), the triangle test keeps the numerators
//! of the barycentrics of the closest hit so far (obvhs's path ran the test again after the
//! traversal to get them: same arithmetic, same bits), and shadow rays stop at the first hit.
//!
//! **Small scenes** (at most 16 blocks, 128 triangles, with AVX2) skip the tree (`small.rs`):
//! a ray tests the blocks, 8 triangles at once, the closest hit shortening the ray as it goes,
//! after a test of the blocks' boxes where they are expected to spare more than it costs (the
//! triangles regrouped where that spares more, a room's walls in blocks of their own); a shadow
//! ray stops at the first block that blocks it (issue 49: every shipped scene of at most 128
//! triangles traces 1.18–1.62× as many rays a second as through the tree, Mitsuba's box
//! 1.2–1.3× more with the regrouping; the measurements in `small.rs`).
//! **Packets** ([`RayPacket`], `packet.rs`): up to 8 rays through a small scene at once, a ray
//! in each lane, each triangle tested against all of them; the same hits, bit for bit, as one
//! by one (1.30× the closest-hit rate on the Cornell box's path rays, shadow rays unchanged).
//! Elsewhere a packet's rays are traced one by one. The edge rays of a pixel use them.
//! **Ties**: of hits at the same `t` (coincident triangles: the two faces of a zero-thickness
//! wall), the one facing the ray wins, then the lower index (`triangles::closer`), so every
//! walk (the tree's in any order, every block's, the scalar one's) returns the same hit, and a
//! wall modelled as two faces shows each side its own face. (Before, the tree's order by the
//! ray's octant chose, and half the rays into the door scenes' shared wall saw the other room's
//! face.) The tree's node test skips boxes that end before `t = 10⁻⁴`, every block's test does
//! not, so a hit closer than that may be found by one and not the other.

use glam::{UVec2, Vec2};
use glam::{Vec3, Vec3A};
use obvhs::{
    cwbvh::{builder::build_cwbvh_from_tris, CwBvh},
    faststack::{FastStack, HeapStack},
    ray::Ray,
    rt_triangle::RtTriangle,
    triangle::Triangle,
    BvhBuildParams,
};
use std::time::{Duration, Instant};

mod node;
mod ordered;
mod packet;
mod small;
#[cfg(test)]
mod tests;
mod triangles;

use node::node_hits;
#[cfg(target_arch = "x86_64")]
use node::node_hits_avx2;
#[cfg(target_arch = "x86_64")]
use ordered::ordered_walk_avx2;
use ordered::OrderStack;
pub use packet::{RayPacket, LANES};
#[cfg(target_arch = "x86_64")]
use small::SmallScene;
#[cfg(target_arch = "x86_64")]
use small::{small_any_avx2, small_closest_avx2};
use triangles::{closer, group_any, group_closest, hit_triangle, Tri, TriBlock};
#[cfg(target_arch = "x86_64")]
use triangles::{group_any_avx2, group_closest_avx2};

/// A closest hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the (unit) ray direction.
    pub t: f32,
    /// BVH-order triangle index.
    pub prim: u32,
    /// Barycentric weight of `v1`.
    pub b1: f32,
    /// Barycentric weight of `v2`.
    pub b2: f32,
}

/// The node stacks of a traversal, kept by a thread from ray to ray (no allocation and no
/// zeroing per ray): obvhs's walk's (deep enough for any CWBVH obvhs builds: its own traversal
/// uses 32 entries) and the ordered walk's (`ordered.rs`; it grows if a tree needs more).
pub struct TraceStack(HeapStack<UVec2>, OrderStack);

impl Default for TraceStack {
    fn default() -> Self {
        TraceStack(
            HeapStack::new_with_capacity(TRAVERSAL_STACK),
            OrderStack::with_capacity(8 * TRAVERSAL_STACK),
        )
    }
}

thread_local! {
    /// The stacks of [`Accel::intersect`] and [`Accel::occluded`], which take none.
    static STACKS: std::cell::RefCell<TraceStack> = std::cell::RefCell::new(TraceStack::default());
}

/// Entries of a traversal stack: obvhs's own depth bound.
const TRAVERSAL_STACK: usize = 32;

/// The state obvhs's `traverse!` macro walks with: its field names, any stack.
struct Walk<'s, S: FastStack<UVec2>> {
    stack: &'s mut S,
    current_group: UVec2,
    primitive_group: UVec2,
    oct_inv4: u32,
    primitive_id: u32,
    hitmask: u32,
}

impl<'s, S: FastStack<UVec2>> Walk<'s, S> {
    /// A walk from the root for a ray of direction `dir`, on an emptied `stack`.
    #[inline(always)]
    fn new(stack: &'s mut S, dir: Vec3A, empty: bool) -> Self {
        stack.clear();
        // the octant bits of obvhs's ray_get_octant_inv4
        let oct_inv4 = (if dir.x < 0.0 { 0 } else { 0x0404_0404 })
            | (if dir.y < 0.0 { 0 } else { 0x0202_0202 })
            | (if dir.z < 0.0 { 0 } else { 0x0101_0101 });
        Walk {
            stack,
            current_group: if empty {
                UVec2::ZERO
            } else {
                UVec2::new(0, 0x8000_0000)
            },
            primitive_group: UVec2::ZERO,
            oct_inv4,
            primitive_id: 0,
            hitmask: 0,
        }
    }
}

/// The triangles of the group the traversal is on, as `(first index, bit mask)`: obvhs's
/// `traverse!` hands its primitive block one triangle (`primitive_id`, its bit already taken
/// from the group); the whole group is its bit and the bits left, and the group is then
/// emptied, so the block runs once per group.
macro_rules! take_group {
    ($state:expr) => {{
        let base = $state.primitive_group.x;
        let bits = $state.primitive_group.y | (1u32 << ($state.primitive_id - base));
        $state.primitive_group.y = 0;
        (base, bits)
    }};
}

/// The closest-hit walk over the CWBVH of `$acc` (obvhs's `traverse!`), each node tested by the
/// function `$nodes(node, &ray, oct_inv4) -> hit mask` and each group of triangles by
/// `$group(acc, base, bits, &mut ray, &mut best, &keep)`: a macro so that the AVX2 instance is
/// compiled inside a function that enables AVX2 and its tests inline there.
macro_rules! closest_walk {
    ($acc:expr, $stack:expr, $origin:expr, $dir:expr, $tmax:expr, $keep:expr, $nodes:path, $group:path) => {{
        let mut ray = ray_of($origin, $dir, $tmax);
        let mut state = Walk::new($stack, ray.direction, $acc.bvh.nodes.is_empty());
        let mut node;
        // the closest hit so far: primitive, barycentric numerators, denominator
        let mut best: Option<(u32, Vec2, f32)> = None;
        obvhs::traverse!($acc.bvh, node, state, $nodes(node, &ray, state.oct_inv4), {
            let (base, bits) = take_group!(state);
            $group($acc, base, bits, &mut ray, &mut best, &$keep);
        });
        hit_of(best, ray.tmax)
    }};
}

/// The [`Hit`] at `t` of a walk's closest hit (primitive, barycentric numerators, denominator):
/// obvhs's `compute_barycentric` division, on the numerators of the test.
#[inline(always)]
fn hit_of(best: Option<(u32, Vec2, f32)>, t: f32) -> Option<Hit> {
    best.map(|(prim, n, det)| {
        let b = n / det;
        Hit {
            t,
            prim,
            b1: b.x,
            b2: b.y,
        }
    })
}

/// The any-hit walk (stops at the first kept hit), as [`closest_walk`].
macro_rules! any_walk {
    ($acc:expr, $stack:expr, $origin:expr, $dir:expr, $tmax:expr, $keep:expr, $nodes:path, $group:path) => {{
        let ray = ray_of($origin, $dir, $tmax);
        let mut state = Walk::new($stack, ray.direction, $acc.bvh.nodes.is_empty());
        let mut node;
        let mut hit = false;
        'walk: {
            obvhs::traverse!($acc.bvh, node, state, $nodes(node, &ray, state.oct_inv4), {
                let (base, bits) = take_group!(state);
                if $group($acc, base, bits, &ray, &$keep) {
                    hit = true;
                    break 'walk;
                }
            });
        }
        hit
    }};
}

/// Whether the CPU has AVX2 (std caches the answer).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn has_avx2() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
}

/// The ray `origin + t·dir`, `t ∈ [0, tmax]`, as obvhs's `Ray::new` makes it from
/// [`positive_zeros`]`(dir)`, its three `safe_inverse`s (`1/x`, or `signum(x)/ε` where
/// `|x| ≤ ε`) done as one vector division and a select: the same values, bit for bit, without
/// three scalar divisions and their branches per ray.
#[inline(always)]
fn ray_of(origin: Vec3, dir: Vec3, tmax: f32) -> Ray {
    let direction = positive_zeros(dir);
    let small = direction.abs().cmple(Vec3A::splat(f32::EPSILON));
    let inv_direction = Vec3A::select(small, direction.signum() / f32::EPSILON, direction.recip());
    Ray {
        origin: Vec3A::from(origin),
        direction,
        inv_direction,
        tmin: 0.0,
        tmax,
    }
}

/// The ray of a small scene's walk: [`ray_of`]'s, but where the walk tests no box
/// ([`SmallScene::culls`] false) without the inverse direction, which only a box test reads
/// (the triangle test reads the origin, the direction and the interval): a division a ray less.
#[inline(always)]
fn small_ray(boxes: &SmallScene, origin: Vec3, dir: Vec3, tmax: f32) -> Ray {
    if boxes.culls {
        return ray_of(origin, dir, tmax);
    }
    Ray {
        origin: Vec3A::from(origin),
        direction: positive_zeros(dir),
        inv_direction: Vec3A::NAN,
        tmin: 0.0,
        tmax,
    }
}

/// `dir` with every −0.0 component made +0.0. obvhs inverts a zero component as
/// `signum(x)/ε` (−1/ε for −0.0) but orders the slabs and octants by `x < 0.0` (false for
/// −0.0): a ray with a −0.0 component, e.g. `-Vec3::Z`, met a flat box's slabs in the wrong order
/// and missed what it hit (found by the textures' tests: a ray straight down −z through a
/// scene of axis-aligned quads). Adding +0.0 changes nothing else.
#[inline(always)]
fn positive_zeros(dir: Vec3) -> Vec3A {
    Vec3A::from(dir) + Vec3A::ZERO
}

/// How the BVH is built: obvhs's `slow_build` without its pre-splitting. Against its
/// `medium_build` (vrpt's build before), PLOC looks at 24 neighbours, not 14, and the tree's
/// worst 20 % of nodes are reinserted, not 5 %. On 2 cores (AMD EPYC, AVX2): incoherent
/// closest-hit rays 23 % (10⁵ triangles) and 36 % (10⁶) faster on the benchmark's terrain, a
/// 10⁶-triangle scene of ten lumpy spheres rendered at 64 spp in 0.85× the whole run's time
/// (load and build included), one lumpy sphere of 327,680 triangles in Mitsuba's box about as
/// fast as before (its tree was already good); the build takes ~1.4× as long (1.28 s at 10⁶).
/// Pre-splitting stays off: it lets a triangle sit in two leaves, and a scene keeps one emitter
/// and one shading record per BVH-order triangle, so a split emissive triangle would emit twice
/// ([`Accel::order`] is a permutation: the build's test checks it).
fn build_params() -> BvhBuildParams {
    BvhBuildParams {
        pre_split: false,
        ..BvhBuildParams::slow_build()
    }
}

/// The BVH and the triangles in its order.
pub struct Accel {
    bvh: CwBvh,
    /// The triangles in BVH order, 8 to a block.
    blocks: Vec<TriBlock>,
    /// Their number.
    count: usize,
    /// The blocks and their boxes where they are few (`small.rs`): the walk without the tree.
    small: Option<SmallScene>,
    /// `order[i]` = input index of BVH-order triangle `i`.
    pub order: Vec<u32>,
    /// Wall time of the build (AABBs, PLOC, reinsertion, CWBVH conversion, reordering).
    pub build_time: Duration,
}

impl Accel {
    /// Build over `triangles` (each `[v0, v1, v2]`). Must not be empty.
    pub fn build(triangles: &[[Vec3; 3]]) -> Accel {
        Self::build_from(triangles.iter().copied())
    }

    /// [`Accel::build`] over triangles as they come (no copy of them as a slice first: a scene
    /// of a million triangles held one, 36 MB more at the build's peak).
    pub fn build_from(triangles: impl ExactSizeIterator<Item = [Vec3; 3]>) -> Accel {
        assert!(triangles.len() > 0, "Accel::build needs triangles");
        let start = Instant::now();
        let input: Vec<Triangle> = triangles
            .map(|t| Triangle {
                v0: t[0].into(),
                v1: t[1].into(),
                v2: t[2].into(),
            })
            .collect();
        let mut core = Duration::ZERO;
        let bvh = build_cwbvh_from_tris(&input, build_params(), &mut core);
        let order = bvh.primitive_indices.clone();
        let mut blocks = vec![TriBlock::default(); order.len().div_ceil(8)];
        for (k, &i) in order.iter().enumerate() {
            let t = &input[i as usize];
            blocks[k / 8].set(k % 8, &RtTriangle::new(t.v0, t.v1, t.v2));
        }
        Accel {
            bvh,
            small: SmallScene::new(&blocks, order.len()),
            blocks,
            count: order.len(),
            order,
            build_time: start.elapsed(),
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.count
    }

    /// Always false: an Accel holds at least one triangle.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// BVH-order triangle `prim`.
    #[inline(always)]
    fn tri(&self, prim: u32) -> Tri {
        self.blocks[prim as usize / 8].get(prim as usize % 8)
    }

    /// Bytes held by the BVH nodes, the index map and the triangles (a small scene's second
    /// copy of them for its walk included).
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.bvh.nodes.as_slice())
            + std::mem::size_of_val(self.bvh.primitive_indices.as_slice())
            + std::mem::size_of_val(self.order.as_slice())
            + std::mem::size_of_val(self.blocks.as_slice())
            + self.small.as_ref().map_or(0, |s| {
                std::mem::size_of_val(s.blocks.as_slice())
                    + std::mem::size_of_val(s.ids.as_slice())
                    + std::mem::size_of_val(s.full.as_slice())
            })
    }

    /// The vertices of BVH-order triangle `prim`.
    #[inline]
    pub fn vertices(&self, prim: u32) -> [Vec3; 3] {
        let t = self.tri(prim);
        [t.v0.into(), (t.v0 - t.e1).into(), (t.v0 + t.e2).into()]
    }

    /// Closest hit along `origin + t·dir` for `t ∈ (0, tmax)`; `dir` must be unit length. (On
    /// stacks the calling thread keeps for these calls; a renderer passes its own:
    /// [`Accel::intersect_with`].)
    #[inline]
    pub fn intersect(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        STACKS.with_borrow_mut(|stack| self.closest(stack, (origin, dir, tmax), |_, _| true))
    }

    /// [`Accel::intersect`] on a thread's own stack.
    #[inline]
    pub fn intersect_with(
        &self,
        stack: &mut TraceStack,
        origin: Vec3,
        dir: Vec3,
        tmax: f32,
    ) -> Option<Hit> {
        self.closest(stack, (origin, dir, tmax), |_, _| true)
    }

    /// [`Accel::intersect_with`] where a triangle hit counts only if `keep(prim, (b1, b2))`
    /// says so (alpha cutouts): a hit it refuses is passed through inside the traversal, and
    /// the closest kept hit is returned.
    #[inline]
    pub fn intersect_filtered(
        &self,
        stack: &mut TraceStack,
        (origin, dir, tmax): (Vec3, Vec3, f32),
        keep: impl Fn(u32, Vec2) -> bool,
    ) -> Option<Hit> {
        self.closest(stack, (origin, dir, tmax), keep)
    }

    /// [`Accel::occluded_with`] where a triangle hit blocks only if `keep(prim, (b1, b2))`.
    #[inline]
    pub fn occluded_filtered(
        &self,
        stack: &mut TraceStack,
        (origin, dir, tmax): (Vec3, Vec3, f32),
        keep: impl Fn(u32, Vec2) -> bool,
    ) -> bool {
        self.any(stack, origin, dir, tmax, keep)
    }

    /// True if anything lies along `origin + t·dir` for `t ∈ (0, tmax)` (any hit, early out; on
    /// the thread's stacks, as [`Accel::intersect`]).
    #[inline]
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        STACKS.with_borrow_mut(|stack| self.any(stack, origin, dir, tmax, |_, _| true))
    }

    /// [`Accel::occluded`] on a thread's own stack.
    #[inline]
    pub fn occluded_with(
        &self,
        stack: &mut TraceStack,
        origin: Vec3,
        dir: Vec3,
        tmax: f32,
    ) -> bool {
        self.any(stack, origin, dir, tmax, |_, _| true)
    }

    /// The closest hit (see [`Accel::intersect_with`]): with AVX2 where the CPU has it (asked
    /// once, then a cached flag; a small scene's blocks without the tree, `small.rs`), else
    /// obvhs's SSE node test.
    #[inline(always)]
    fn closest(
        &self,
        stack: &mut TraceStack,
        (origin, dir, tmax): (Vec3, Vec3, f32),
        keep: impl Fn(u32, Vec2) -> bool,
    ) -> Option<Hit> {
        #[cfg(target_arch = "x86_64")]
        if has_avx2() {
            if let Some(boxes) = &self.small {
                // SAFETY: the CPU has AVX2, all the function asks
                #[allow(unsafe_code)]
                return unsafe { self.closest_small_avx2(boxes, (origin, dir, tmax), keep) };
            }
            // SAFETY: the CPU has AVX2, all the function asks
            #[allow(unsafe_code)]
            return unsafe { self.closest_avx2(&mut stack.1, origin, dir, tmax, keep) };
        }
        self.closest_sse(&mut stack.0, origin, dir, tmax, keep)
    }

    /// [`Accel::any`] as [`Accel::closest`] dispatches.
    #[inline(always)]
    fn any(
        &self,
        stack: &mut TraceStack,
        origin: Vec3,
        dir: Vec3,
        tmax: f32,
        keep: impl Fn(u32, Vec2) -> bool,
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if has_avx2() {
            // SAFETY: the CPU has AVX2, all the function asks
            #[allow(unsafe_code)]
            return unsafe { self.any_avx2(&mut stack.0, origin, dir, tmax, keep) };
        }
        self.any_sse(&mut stack.0, origin, dir, tmax, keep)
    }

    /// The closest-hit walk with AVX2 node tests, nearest child first (`ordered.rs`), compiled
    /// for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn closest_avx2(
        &self,
        stack: &mut OrderStack,
        origin: Vec3,
        dir: Vec3,
        tmax: f32,
        keep: impl Fn(u32, Vec2) -> bool,
    ) -> Option<Hit> {
        let mut ray = ray_of(origin, dir, tmax);
        let mut best = None;
        ordered_walk_avx2(&self.bvh.nodes, stack, &mut ray, |base, bits, ray| {
            group_closest_avx2(self, base, bits, ray, &mut best, &keep)
        });
        hit_of(best, ray.tmax)
    }

    /// The closest hit of a small scene (`small.rs`), its blocks tested 8 triangles at once.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn closest_small_avx2(
        &self,
        boxes: &SmallScene,
        (origin, dir, tmax): (Vec3, Vec3, f32),
        keep: impl Fn(u32, Vec2) -> bool,
    ) -> Option<Hit> {
        let mut ray = small_ray(boxes, origin, dir, tmax);
        let mut best = None;
        small_closest_avx2(boxes, &mut ray, &mut best, &keep);
        hit_of(best, ray.tmax)
    }

    /// The any-hit walk with AVX2 node tests, compiled for AVX2: obvhs's order (the children by
    /// the ray's octant, leaves first). The nearest-first walk of `ordered.rs` shortens no ray
    /// here and measured no faster on a large mesh (1.003× the render's time, 12 pairs).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn any_avx2<S: FastStack<UVec2>>(
        &self,
        stack: &mut S,
        origin: Vec3,
        dir: Vec3,
        tmax: f32,
        keep: impl Fn(u32, Vec2) -> bool,
    ) -> bool {
        if let Some(boxes) = &self.small {
            let ray = small_ray(boxes, origin, dir, tmax);
            return small_any_avx2(boxes, &ray, &keep);
        }
        any_walk!(
            self,
            stack,
            origin,
            dir,
            tmax,
            keep,
            node_hits_avx2,
            group_any_avx2
        )
    }

    #[inline(always)]
    fn closest_sse<S: FastStack<UVec2>>(
        &self,
        stack: &mut S,
        origin: Vec3,
        dir: Vec3,
        tmax: f32,
        keep: impl Fn(u32, Vec2) -> bool,
    ) -> Option<Hit> {
        closest_walk!(
            self,
            stack,
            origin,
            dir,
            tmax,
            keep,
            node_hits,
            group_closest
        )
    }

    #[inline(always)]
    fn any_sse<S: FastStack<UVec2>>(
        &self,
        stack: &mut S,
        origin: Vec3,
        dir: Vec3,
        tmax: f32,
        keep: impl Fn(u32, Vec2) -> bool,
    ) -> bool {
        any_walk!(self, stack, origin, dir, tmax, keep, node_hits, group_any)
    }

    /// Closest hit by testing every triangle, one at a time: the reference for tests and
    /// benchmarks (ties broken as the traversals break them, `triangles::closer`).
    pub fn intersect_brute_force(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        let ray = Ray::new(Vec3A::from(origin), positive_zeros(dir), 0.0, tmax);
        let (mut best, mut best_t) = (None, tmax);
        for i in 0..self.count as u32 {
            if let Some((t, n, det)) = hit_triangle(&self.tri(i), &ray) {
                if closer((t, det, i), best_t, &best) {
                    (best, best_t) = (Some((i, n, det)), t);
                }
            }
        }
        hit_of(best, best_t)
    }
}
