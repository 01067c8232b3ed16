//! The ray-triangle accelerator: an obvhs compressed wide BVH (CWBVH, 8-wide) over all
//! triangles, with the triangles stored in BVH leaf order so a hit indexes them directly.
//!
//! Triangles are `obvhs::rt_triangle::RtTriangle` (`v0`, `e1 = v0 − v1`, `e2 = v2 − v0`, and the
//! normal `ng = e1 × e2`: one 64-byte line each), the layout its Möller–Trumbore test is fastest
//! with. A hit reports the barycentrics `(b1, b2)` of `v1` and `v2`: the point is
//! `(1 − b1 − b2)·v0 + b1·v1 + b2·v2`. Indices in a [`Hit`] and in [`Accel::order`] are BVH-order
//! indices; `order[i]` is the input index of BVH triangle `i`.
//!
//! **Traversal** is obvhs's own loop (its `traverse!` macro over the CWBVH nodes), driven from
//! here so a renderer pays no per-ray cost it does not need (issue 19): the node stack is a
//! [`TraceStack`] that a thread keeps from ray to ray (obvhs's entry points zero a fresh 256-byte
//! stack for every ray: 2 % of a render's instructions), the triangle test keeps the numerators
//! of the barycentrics of the closest hit so far (obvhs's path ran the test again after the
//! traversal to get them: same arithmetic, same bits), and shadow rays stop at the first hit.

use glam::{UVec2, Vec2};
use glam::{Vec3, Vec3A};
use obvhs::{
    cwbvh::{builder::build_cwbvh_from_tris, node::CwBvhNode, CwBvh},
    faststack::{FastStack, HeapStack, StackStack},
    ray::Ray,
    rt_triangle::RtTriangle,
    triangle::Triangle,
    BvhBuildParams,
};
use std::time::{Duration, Instant};

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

/// The node stack of a traversal, kept by a thread from ray to ray (no allocation and no zeroing
/// per ray). Deep enough for any CWBVH obvhs builds (its own traversal uses 32 entries).
pub struct TraceStack(HeapStack<UVec2>);

impl Default for TraceStack {
    fn default() -> Self {
        TraceStack(HeapStack::new_with_capacity(TRAVERSAL_STACK))
    }
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

/// The closest-hit walk over the CWBVH of `$acc` (obvhs's `traverse!`), each node tested by the
/// function `$nodes(node, &ray, oct_inv4) -> hit mask`: a macro so that the AVX2 instance is compiled
/// inside a function that enables AVX2 and its node test inlines there.
macro_rules! closest_walk {
    ($acc:expr, $stack:expr, $origin:expr, $dir:expr, $tmax:expr, $keep:expr, $nodes:path) => {{
        let mut ray = Ray::new(Vec3A::from($origin), positive_zeros($dir), 0.0, $tmax);
        let mut state = Walk::new($stack, ray.direction, $acc.bvh.nodes.is_empty());
        let mut node;
        // the closest hit so far: primitive, barycentric numerators, denominator
        let mut best: Option<(u32, Vec2, f32)> = None;
        obvhs::traverse!($acc.bvh, node, state, $nodes(node, &ray, state.oct_inv4), {
            let id = state.primitive_id;
            if let Some((t, n, det)) = hit_triangle(&$acc.tris[id as usize], &ray) {
                if t < ray.tmax && $keep(id, n / det) {
                    ray.tmax = t;
                    best = Some((id, n, det));
                }
            }
        });
        best.map(|(prim, n, det)| {
            // compute_barycentric's division, on the numerators of the test
            let b = n / det;
            Hit {
                t: ray.tmax,
                prim,
                b1: b.x,
                b2: b.y,
            }
        })
    }};
}

/// The any-hit walk (stops at the first kept hit), as [`closest_walk`].
macro_rules! any_walk {
    ($acc:expr, $stack:expr, $origin:expr, $dir:expr, $tmax:expr, $keep:expr, $nodes:path) => {{
        let ray = Ray::new(Vec3A::from($origin), positive_zeros($dir), 0.0, $tmax);
        let mut state = Walk::new($stack, ray.direction, $acc.bvh.nodes.is_empty());
        let mut node;
        let mut hit = false;
        'walk: {
            obvhs::traverse!($acc.bvh, node, state, $nodes(node, &ray, state.oct_inv4), {
                let id = state.primitive_id;
                if let Some((_, n, det)) = hit_triangle(&$acc.tris[id as usize], &ray) {
                    if $keep(id, n / det) {
                        hit = true;
                        break 'walk;
                    }
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

/// The children of `node` that `ray` hits: obvhs's own test (SSE where the target has it).
#[inline(always)]
fn node_hits(node: &CwBvhNode, ray: &Ray, oct_inv4: u32) -> u32 {
    node.intersect_ray(ray, oct_inv4)
}

/// The `tmin` floor of obvhs's node test (its crate-private `EPSILON`).
const NODE_EPSILON: f32 = 0.0001;

/// The children of `node` that `ray` (octant `oct_inv4`) hits, as the traversal's hit mask:
/// obvhs's `intersect_ray_simd` with its 8 children in one 8-wide test instead of two 4-wide
/// ones, each child plane's 8 quantized bytes widened to floats by two instructions (obvhs sets
/// each lane from a scalar conversion). The arithmetic is the same, operation for operation
/// (a multiply, then an add, not a fused multiply-add; the same operand order of every `min`
/// and `max`), so the mask is the same bits and so are the traversal and the image.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn node_hits_avx2(node: &CwBvhNode, ray: &Ray, oct_inv4: u32) -> u32 {
    use std::arch::x86_64::*;
    let dir_inv = node.compute_extent() * ray.inv_direction;
    let orig = (Vec3A::from(node.p) - ray.origin) * ray.inv_direction;
    // 8 bytes to 8 floats
    let q = |v: &[u8; 8]| {
        let bytes = _mm_set_epi64x(0, i64::from_le_bytes(*v));
        _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(bytes))
    };
    let axis = |lo: &[u8; 8], hi: &[u8; 8], negative: bool, inv: f32, o: f32| {
        let (near, far) = if negative {
            (q(hi), q(lo))
        } else {
            (q(lo), q(hi))
        };
        let (inv, o) = (_mm256_set1_ps(inv), _mm256_set1_ps(o));
        (
            _mm256_add_ps(_mm256_mul_ps(near, inv), o),
            _mm256_add_ps(_mm256_mul_ps(far, inv), o),
        )
    };
    let d = ray.direction;
    let (tmin_x, tmax_x) = axis(
        &node.child_min_x,
        &node.child_max_x,
        d.x < 0.0,
        dir_inv.x,
        orig.x,
    );
    let (tmin_y, tmax_y) = axis(
        &node.child_min_y,
        &node.child_max_y,
        d.y < 0.0,
        dir_inv.y,
        orig.y,
    );
    let (tmin_z, tmax_z) = axis(
        &node.child_min_z,
        &node.child_max_z,
        d.z < 0.0,
        dir_inv.z,
        orig.z,
    );
    let tmin = _mm256_max_ps(tmin_x, _mm256_max_ps(tmin_y, tmin_z));
    let tmax = _mm256_min_ps(tmax_x, _mm256_min_ps(tmax_y, tmax_z));
    let tmin = _mm256_max_ps(tmin, _mm256_set1_ps(NODE_EPSILON));
    let tmax = _mm256_min_ps(tmax, _mm256_set1_ps(ray.tmax));
    let mut hits = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tmin, tmax)) as u32;
    let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
    let mut mask = 0u32;
    while hits != 0 {
        let j = hits.trailing_zeros() as u64;
        hits &= hits - 1;
        let child_bits = ((child_bits8 >> (j * 8)) & 0xff) as u32;
        let bit_index = ((bit_index8 >> (j * 8)) & 0xff) as u32;
        mask |= child_bits << bit_index;
    }
    mask
}

/// The test of `RtTriangle::intersect` (the same arithmetic, so the same bits), returning the
/// hit's `t` and the numerators of its barycentrics and their denominator, or `None`.
#[inline(always)]
fn hit_triangle(tri: &RtTriangle, ray: &Ray) -> Option<(f32, Vec2, f32)> {
    let c = tri.v0 - ray.origin;
    let r = ray.direction.cross(c);
    let det = tri.ng.dot(ray.direction);
    let inv_det = 1.0 / det;
    let (nu, nv) = (r.dot(tri.e2), r.dot(tri.e1));
    let u = nu * inv_det;
    let v = nv * inv_det;
    let w = 1.0 - u - v;
    let signs = u.to_bits() | v.to_bits() | w.to_bits();
    if inv_det != 0.0 && signs & 0x8000_0000 == 0 {
        let t = tri.ng.dot(c) * inv_det;
        if t >= ray.tmin && t <= ray.tmax {
            return Some((t, Vec2::new(nu, nv), det));
        }
    }
    None
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

/// The BVH and the triangles in its order.
pub struct Accel {
    bvh: CwBvh,
    tris: Vec<RtTriangle>,
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
        let bvh = build_cwbvh_from_tris(&input, BvhBuildParams::medium_build(), &mut core);
        let order = bvh.primitive_indices.clone();
        let tris = order
            .iter()
            .map(|&i| {
                let t = &input[i as usize];
                RtTriangle::new(t.v0, t.v1, t.v2)
            })
            .collect();
        Accel {
            bvh,
            tris,
            order,
            build_time: start.elapsed(),
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// Always false: an Accel holds at least one triangle.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// Bytes held by the BVH nodes, the index map and the triangles.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.bvh.nodes.as_slice())
            + std::mem::size_of_val(self.bvh.primitive_indices.as_slice())
            + std::mem::size_of_val(self.order.as_slice())
            + std::mem::size_of_val(self.tris.as_slice())
    }

    /// The vertices of BVH-order triangle `prim`.
    #[inline]
    pub fn vertices(&self, prim: u32) -> [Vec3; 3] {
        let t = &self.tris[prim as usize];
        [t.v0.into(), (t.v0 - t.e1).into(), (t.v0 + t.e2).into()]
    }

    /// Closest hit along `origin + t·dir` for `t ∈ (0, tmax)`; `dir` must be unit length. (A
    /// fresh stack per call; a renderer keeps one: [`Accel::intersect_with`].)
    #[inline]
    pub fn intersect(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        self.closest(
            &mut StackStack::<UVec2, TRAVERSAL_STACK>::default(),
            origin,
            dir,
            tmax,
            |_, _| true,
        )
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
        self.closest(&mut stack.0, origin, dir, tmax, |_, _| true)
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
        self.closest(&mut stack.0, origin, dir, tmax, keep)
    }

    /// [`Accel::occluded_with`] where a triangle hit blocks only if `keep(prim, (b1, b2))`.
    #[inline]
    pub fn occluded_filtered(
        &self,
        stack: &mut TraceStack,
        (origin, dir, tmax): (Vec3, Vec3, f32),
        keep: impl Fn(u32, Vec2) -> bool,
    ) -> bool {
        self.any(&mut stack.0, origin, dir, tmax, keep)
    }

    /// True if anything lies along `origin + t·dir` for `t ∈ (0, tmax)` (any hit, early out).
    #[inline]
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        self.any(
            &mut StackStack::<UVec2, TRAVERSAL_STACK>::default(),
            origin,
            dir,
            tmax,
            |_, _| true,
        )
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
        self.any(&mut stack.0, origin, dir, tmax, |_, _| true)
    }

    /// The closest hit (see [`Accel::intersect_with`]): with AVX2 where the CPU has it (asked
    /// once, then a cached flag), else obvhs's SSE node test.
    #[inline(always)]
    fn closest<S: FastStack<UVec2>>(
        &self,
        stack: &mut S,
        origin: Vec3,
        dir: Vec3,
        tmax: f32,
        keep: impl Fn(u32, Vec2) -> bool,
    ) -> Option<Hit> {
        #[cfg(target_arch = "x86_64")]
        if has_avx2() {
            // SAFETY: the CPU has AVX2, all the function asks
            #[allow(unsafe_code)]
            return unsafe { self.closest_avx2(stack, origin, dir, tmax, keep) };
        }
        self.closest_sse(stack, origin, dir, tmax, keep)
    }

    /// [`Accel::any`] as [`Accel::closest`] dispatches.
    #[inline(always)]
    fn any<S: FastStack<UVec2>>(
        &self,
        stack: &mut S,
        origin: Vec3,
        dir: Vec3,
        tmax: f32,
        keep: impl Fn(u32, Vec2) -> bool,
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if has_avx2() {
            // SAFETY: the CPU has AVX2, all the function asks
            #[allow(unsafe_code)]
            return unsafe { self.any_avx2(stack, origin, dir, tmax, keep) };
        }
        self.any_sse(stack, origin, dir, tmax, keep)
    }

    /// The closest-hit walk with AVX2 node tests ([`node_hits_avx2`]), compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn closest_avx2<S: FastStack<UVec2>>(
        &self,
        stack: &mut S,
        origin: Vec3,
        dir: Vec3,
        tmax: f32,
        keep: impl Fn(u32, Vec2) -> bool,
    ) -> Option<Hit> {
        closest_walk!(self, stack, origin, dir, tmax, keep, node_hits_avx2)
    }

    /// The any-hit walk with AVX2 node tests, compiled for AVX2.
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
        any_walk!(self, stack, origin, dir, tmax, keep, node_hits_avx2)
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
        closest_walk!(self, stack, origin, dir, tmax, keep, node_hits)
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
        any_walk!(self, stack, origin, dir, tmax, keep, node_hits)
    }

    /// Closest hit by testing every triangle: the reference for tests and benchmarks.
    pub fn intersect_brute_force(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        let ray = Ray::new(Vec3A::from(origin), Vec3A::from(dir), 0.0, tmax);
        let mut best: Option<Hit> = None;
        for (i, tri) in self.tris.iter().enumerate() {
            let t = tri.intersect(&ray);
            if t < best.map_or(tmax, |h| h.t) {
                let bary = tri.compute_barycentric(&ray);
                best = Some(Hit {
                    t,
                    prim: i as u32,
                    b1: bary.x,
                    b2: bary.y,
                });
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{rngs::SmallRng, Rng, SeedableRng};

    /// The AVX2 node test gives obvhs's mask, bit for bit, on every node of a BVH over random
    /// triangles, for rays of every octant (signed zeros included) and short and long `tmax`:
    /// the claim that makes images bit-identical whichever test the CPU runs.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_avx2_node_test_gives_obvhs_mask() {
        if !has_avx2() {
            return;
        }
        let mut rng = SmallRng::seed_from_u64(49);
        let mut p = || Vec3::new(rng.random(), rng.random(), rng.random()) * 4.0 - 2.0;
        let tris: Vec<[Vec3; 3]> = (0..500)
            .map(|_| {
                let c = p();
                [c, c + p() * 0.1, c + p() * 0.1]
            })
            .collect();
        let accel = Accel::build(&tris);
        assert!(accel.bvh.nodes.len() > 10);
        let mut rng = SmallRng::seed_from_u64(7);
        let (mut checked, mut some_hit) = (0, 0);
        for i in 0..2000 {
            let o = Vec3::new(rng.random(), rng.random(), rng.random()) * 6.0 - 3.0;
            // half the rays aimed at a triangle, so that deep nodes are hit too
            let mut d = Vec3::new(rng.random(), rng.random(), rng.random()) * 2.0 - 1.0;
            if i % 2 == 0 {
                d = tris[rng.random_range(0..tris.len())][0] - o;
            }
            if i % 7 == 0 {
                d.y = if i % 2 == 0 { 0.0 } else { -0.0 };
            }
            let d = positive_zeros(d.normalize_or(Vec3::X));
            let tmax = if i % 3 == 0 {
                rng.random::<f32>() * 2.0
            } else {
                f32::INFINITY
            };
            let ray = Ray::new(Vec3A::from(o), d, 0.0, tmax);
            let oct_inv4 = Walk::new(&mut HeapStack::new_with_capacity(1), d, false).oct_inv4;
            for node in &accel.bvh.nodes {
                let want = node.intersect_ray(&ray, oct_inv4);
                // SAFETY: the CPU has AVX2 (checked above)
                #[allow(unsafe_code)]
                let got = unsafe { node_hits_avx2(node, &ray, oct_inv4) };
                assert_eq!(got, want, "ray {i}");
                checked += 1;
                some_hit += (want != 0) as usize;
            }
        }
        // the comparison meant something: masks of both kinds were compared
        assert!(
            some_hit > checked / 50 && some_hit < checked,
            "{some_hit} of {checked}"
        );
    }
}
