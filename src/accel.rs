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
/// each lane from a scalar conversion), and the mask assembled in the 8 lanes without a branch. The arithmetic is the same, operation for operation
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
    let hits = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LE_OQ>(tmin, tmax));
    // each hit child's bits shifted to its place (obvhs loops over the hit children: a branch
    // per child), then the 8 lanes OR-ed together
    let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
    let bytes = |v: u64| _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(v as i64));
    let placed = _mm256_sllv_epi32(bytes(child_bits8), bytes(bit_index8));
    let placed = _mm256_and_si256(placed, hits);
    let half = _mm_or_si128(
        _mm256_castsi256_si128(placed),
        _mm256_extracti128_si256::<1>(placed),
    );
    let half = _mm_or_si128(half, _mm_shuffle_epi32::<0b01_00_11_10>(half));
    let half = _mm_or_si128(half, _mm_shuffle_epi32::<0b10_11_00_01>(half));
    _mm_cvtsi128_si32(half) as u32
}

/// The test of `RtTriangle::intersect` (the same arithmetic, so the same bits), returning the
/// hit's `t` and the numerators of its barycentrics and their denominator, or `None`.
#[inline(always)]
fn hit_triangle(tri: &Tri, ray: &Ray) -> Option<(f32, Vec2, f32)> {
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

/// One triangle as the test reads it (obvhs's `RtTriangle` fields).
#[derive(Clone, Copy, Debug)]
struct Tri {
    v0: Vec3A,
    /// `v0 − v1`.
    e1: Vec3A,
    /// `v2 − v0`.
    e2: Vec3A,
    /// `e1 × e2`.
    ng: Vec3A,
}

/// Eight triangles (BVH-order indices `8k .. 8k + 8` of block `k`), each coordinate a row of 8
/// lanes: rows 0–2 `v0`, 3–5 `e1`, 6–8 `e2`, 9–11 `ng` (x, y, z). Lanes past the last triangle
/// are zeros and never tested.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
struct TriBlock {
    rows: [[f32; 8]; 12],
}

impl TriBlock {
    /// Lane `i`'s triangle.
    #[inline(always)]
    fn get(&self, i: usize) -> Tri {
        let r = &self.rows;
        let v = |k: usize| Vec3A::new(r[k][i], r[k + 1][i], r[k + 2][i]);
        Tri {
            v0: v(0),
            e1: v(3),
            e2: v(6),
            ng: v(9),
        }
    }

    /// Put `t` in lane `i`.
    fn set(&mut self, i: usize, t: &RtTriangle) {
        for (k, v) in [t.v0, t.e1, t.e2, t.ng].into_iter().enumerate() {
            self.rows[3 * k][i] = v.x;
            self.rows[3 * k + 1][i] = v.y;
            self.rows[3 * k + 2][i] = v.z;
        }
    }
}

/// The closest kept hit of a group (triangles `base + k` for the bits `k` of `bits`), one
/// triangle at a time in the order obvhs's traversal takes them (the highest bit first): a hit
/// below `ray.tmax` that `keep` accepts shortens the ray and becomes `best`.
#[inline(always)]
fn group_closest(
    acc: &Accel,
    base: u32,
    mut bits: u32,
    ray: &mut Ray,
    best: &mut Option<(u32, Vec2, f32)>,
    keep: &impl Fn(u32, Vec2) -> bool,
) {
    while bits != 0 {
        let k = 31 - bits.leading_zeros();
        bits &= !(1 << k);
        let id = base + k;
        if let Some((t, n, det)) = hit_triangle(&acc.tri(id), ray) {
            if t < ray.tmax && keep(id, n / det) {
                ray.tmax = t;
                *best = Some((id, n, det));
            }
        }
    }
}

/// Whether a triangle of a group (as [`group_closest`]) blocks `ray` and `keep` accepts it.
#[inline(always)]
fn group_any(
    acc: &Accel,
    base: u32,
    mut bits: u32,
    ray: &Ray,
    keep: &impl Fn(u32, Vec2) -> bool,
) -> bool {
    while bits != 0 {
        let k = 31 - bits.leading_zeros();
        bits &= !(1 << k);
        let id = base + k;
        if let Some((_, n, det)) = hit_triangle(&acc.tri(id), ray) {
            if keep(id, n / det) {
                return true;
            }
        }
    }
    false
}

/// The lanes of `b` that `ray` hits at `t ∈ [tmin, tmax]`, as a bit mask, with each lane's `t`,
/// barycentric numerators and denominator: [`hit_triangle`] on 8 triangles at once, operation
/// for operation (glam's cross product and dot products in their order, a multiply then an add,
/// never fused; the same division), so each lane's values and verdict are its bits.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn block_hits_avx2(b: &TriBlock, ray: &Ray) -> (u32, [[f32; 8]; 4]) {
    use std::arch::x86_64::*;
    // SAFETY: a row is 8 f32s at a 32-byte boundary (TriBlock is align(32))
    #[allow(unsafe_code)]
    let row = |i: usize| unsafe { _mm256_load_ps(b.rows[i].as_ptr()) };
    let (o, d) = (ray.origin, ray.direction);
    let (mul, add, sub) = (_mm256_mul_ps, _mm256_add_ps, _mm256_sub_ps);
    let (dx, dy, dz) = (
        _mm256_set1_ps(d.x),
        _mm256_set1_ps(d.y),
        _mm256_set1_ps(d.z),
    );
    // c = v0 − origin; r = d × c as glam computes it
    let cx = sub(row(0), _mm256_set1_ps(o.x));
    let cy = sub(row(1), _mm256_set1_ps(o.y));
    let cz = sub(row(2), _mm256_set1_ps(o.z));
    let rx = sub(mul(dy, cz), mul(cy, dz));
    let ry = sub(mul(dz, cx), mul(cz, dx));
    let rz = sub(mul(dx, cy), mul(cx, dy));
    // glam's dot: (x·x' + y·y') + z·z'
    let dot = |ax, ay, az, bx, by, bz| add(add(mul(ax, bx), mul(ay, by)), mul(az, bz));
    let (ngx, ngy, ngz) = (row(9), row(10), row(11));
    let det = dot(ngx, ngy, ngz, dx, dy, dz);
    let inv = _mm256_div_ps(_mm256_set1_ps(1.0), det);
    let nu = dot(rx, ry, rz, row(6), row(7), row(8));
    let nv = dot(rx, ry, rz, row(3), row(4), row(5));
    let (u, v) = (mul(nu, inv), mul(nv, inv));
    let w = sub(sub(_mm256_set1_ps(1.0), u), v);
    let negative = _mm256_movemask_ps(_mm256_or_ps(_mm256_or_ps(u, v), w)) as u32;
    let t = mul(dot(ngx, ngy, ngz, cx, cy, cz), inv);
    let mask = |m: __m256| _mm256_movemask_ps(m) as u32;
    let hits = mask(_mm256_cmp_ps::<_CMP_NEQ_UQ>(inv, _mm256_setzero_ps()))
        & !negative
        & mask(_mm256_cmp_ps::<_CMP_GE_OQ>(t, _mm256_set1_ps(ray.tmin)))
        & mask(_mm256_cmp_ps::<_CMP_LE_OQ>(t, _mm256_set1_ps(ray.tmax)));
    let mut out = [[0.0f32; 8]; 4];
    if hits != 0 {
        for (o, v) in out.iter_mut().zip([t, nu, nv, det]) {
            // SAFETY: `o` is 8 f32s, what an unaligned store writes
            #[allow(unsafe_code)]
            unsafe {
                _mm256_storeu_ps(o.as_mut_ptr(), v)
            };
        }
    }
    (hits, out)
}

/// The blocks a group touches, from the highest: `(block, lanes)` for each block of the
/// triangles `base + k` (bits `k` of `bits`, at most 24 consecutive triangles, so at most 4
/// blocks), its lanes as a bit mask.
#[inline(always)]
fn group_blocks(base: u32, bits: u32) -> impl Iterator<Item = (usize, u32)> {
    let first = (base / 8) as usize;
    let wide = (bits as u64) << (base % 8);
    (0..4usize)
        .rev()
        .map(move |k| (first + k, ((wide >> (8 * k)) & 0xff) as u32))
        .filter(|&(_, lanes)| lanes != 0)
}

/// [`group_closest`] with a block's 8 triangles tested at once ([`block_hits_avx2`]); the hits
/// are then taken in the scalar order (the highest index first, strictly closer replaces), so
/// the result is the scalar one's bits, `keep` included.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn group_closest_avx2(
    acc: &Accel,
    base: u32,
    bits: u32,
    ray: &mut Ray,
    best: &mut Option<(u32, Vec2, f32)>,
    keep: &impl Fn(u32, Vec2) -> bool,
) {
    for (block, lanes) in group_blocks(base, bits) {
        let (hits, [t, nu, nv, det]) = block_hits_avx2(&acc.blocks[block], ray);
        let mut hits = hits & lanes;
        while hits != 0 {
            let i = (31 - hits.leading_zeros()) as usize;
            hits &= !(1 << i);
            let id = (block * 8 + i) as u32;
            let n = Vec2::new(nu[i], nv[i]);
            if t[i] < ray.tmax && keep(id, n / det[i]) {
                ray.tmax = t[i];
                *best = Some((id, n, det[i]));
            }
        }
    }
}

/// [`group_any`] with a block's 8 triangles tested at once.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn group_any_avx2(
    acc: &Accel,
    base: u32,
    bits: u32,
    ray: &Ray,
    keep: &impl Fn(u32, Vec2) -> bool,
) -> bool {
    for (block, lanes) in group_blocks(base, bits) {
        let (hits, [_, nu, nv, det]) = block_hits_avx2(&acc.blocks[block], ray);
        let mut hits = hits & lanes;
        while hits != 0 {
            let i = hits.trailing_zeros() as usize;
            hits &= hits - 1;
            if keep((block * 8 + i) as u32, Vec2::new(nu[i], nv[i]) / det[i]) {
                return true;
            }
        }
    }
    false
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
    /// The triangles in BVH order, 8 to a block.
    blocks: Vec<TriBlock>,
    /// Their number.
    count: usize,
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
        let mut blocks = vec![TriBlock::default(); order.len().div_ceil(8)];
        for (k, &i) in order.iter().enumerate() {
            let t = &input[i as usize];
            blocks[k / 8].set(k % 8, &RtTriangle::new(t.v0, t.v1, t.v2));
        }
        Accel {
            bvh,
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

    /// Bytes held by the BVH nodes, the index map and the triangles.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.bvh.nodes.as_slice())
            + std::mem::size_of_val(self.bvh.primitive_indices.as_slice())
            + std::mem::size_of_val(self.order.as_slice())
            + std::mem::size_of_val(self.blocks.as_slice())
    }

    /// The vertices of BVH-order triangle `prim`.
    #[inline]
    pub fn vertices(&self, prim: u32) -> [Vec3; 3] {
        let t = self.tri(prim);
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
        closest_walk!(
            self,
            stack,
            origin,
            dir,
            tmax,
            keep,
            node_hits_avx2,
            group_closest_avx2
        )
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

    /// Closest hit by testing every triangle: the reference for tests and benchmarks.
    pub fn intersect_brute_force(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        let ray = Ray::new(Vec3A::from(origin), positive_zeros(dir), 0.0, tmax);
        let mut best: Option<Hit> = None;
        for i in 0..self.count as u32 {
            if let Some((t, n, det)) = hit_triangle(&self.tri(i), &ray) {
                if t < best.map_or(tmax, |h| h.t) {
                    let b = n / det;
                    best = Some(Hit {
                        t,
                        prim: i,
                        b1: b.x,
                        b2: b.y,
                    });
                }
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

    /// The AVX2 group test gives the scalar walk's hits, bit for bit: the same triangle, `t` and
    /// barycentrics for the closest hit and the same verdict for shadow rays, with and without
    /// a filter, on triangles that include exact duplicates (ties in `t`, where the order in
    /// which a group's triangles are taken decides) and rays that graze them.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_avx2_triangle_test_gives_the_scalar_hits() {
        if !has_avx2() {
            return;
        }
        let mut rng = SmallRng::seed_from_u64(4949);
        let mut p = || Vec3::new(rng.random(), rng.random(), rng.random()) * 4.0 - 2.0;
        let mut tris: Vec<[Vec3; 3]> = (0..700)
            .map(|_| {
                let c = p();
                [c, c + p() * 0.3, c + p() * 0.3]
            })
            .collect();
        let copies: Vec<[Vec3; 3]> = tris.iter().step_by(5).copied().collect();
        tris.extend(copies);
        let accel = Accel::build(&tris);
        let mut rng = SmallRng::seed_from_u64(11);
        let mut stack = TraceStack::default();
        let (mut hits, mut blocked) = (0, 0);
        for i in 0..20_000 {
            let o = Vec3::new(rng.random(), rng.random(), rng.random()) * 6.0 - 3.0;
            let t = tris[rng.random_range(0..tris.len())];
            // aimed at a vertex, an edge's midpoint or a random point of a triangle
            let target = match i % 3 {
                0 => t[0],
                1 => (t[1] + t[2]) * 0.5,
                _ => t[0] + (t[1] - t[0]) * rng.random::<f32>() * 0.5 + (t[2] - t[0]) * 0.4,
            };
            let d = (target - o).normalize_or(Vec3::X);
            let tmax = if i % 4 == 0 { 3.0 } else { f32::INFINITY };
            let keep_all = |_: u32, _: Vec2| true;
            let keep_some = |prim: u32, b: Vec2| !prim.is_multiple_of(3) && b.x < 0.8;
            for keep in [&keep_all as &dyn Fn(u32, Vec2) -> bool, &keep_some] {
                // SAFETY: the CPU has AVX2 (checked above)
                #[allow(unsafe_code)]
                let (wide, wide_any) = unsafe {
                    (
                        accel.closest_avx2(&mut stack.0, o, d, tmax, keep),
                        accel.any_avx2(&mut stack.0, o, d, tmax, keep),
                    )
                };
                let scalar = accel.closest_sse(&mut stack.0, o, d, tmax, keep);
                let scalar_any = accel.any_sse(&mut stack.0, o, d, tmax, keep);
                let bits = |h: Option<Hit>| {
                    h.map(|h| (h.prim, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()))
                };
                assert_eq!(bits(wide), bits(scalar), "ray {i}");
                assert_eq!(wide_any, scalar_any, "ray {i}");
                hits += wide.is_some() as u32;
                blocked += wide_any as u32;
            }
        }
        // the comparison meant something: most aimed rays hit, and some were refused by the
        // filter or missed
        assert!(hits > 20_000 && hits < 40_000, "{hits}");
        assert!(blocked > 20_000 && blocked < 40_000, "{blocked}");
    }

    /// [`ray_of`] makes obvhs's `Ray::new`, bit for bit, for directions with components of
    /// every size (zero, below and at `f32::EPSILON`, subnormal, large) and both signs.
    #[test]
    fn rays_are_obvhs_rays() {
        let values = [
            0.0f32,
            -0.0,
            1e-40,
            -1e-40,
            f32::EPSILON,
            -f32::EPSILON,
            f32::EPSILON * 1.0001,
            -f32::EPSILON * 1.0001,
            1e-3,
            -0.7,
            0.5,
            1.0,
            -1.0,
            3e5,
        ];
        let bits = |v: Vec3A| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
        for &x in &values {
            for &y in &values {
                for &z in &values {
                    let d = Vec3::new(x, y, z);
                    let want = Ray::new(Vec3A::ONE, positive_zeros(d), 0.0, 2.0);
                    let got = ray_of(Vec3::ONE, d, 2.0);
                    assert_eq!(bits(got.inv_direction), bits(want.inv_direction), "{d}");
                    assert_eq!(bits(got.direction), bits(want.direction), "{d}");
                    assert_eq!(bits(got.origin), bits(want.origin));
                    assert_eq!((got.tmin, got.tmax), (want.tmin, want.tmax));
                }
            }
        }
    }
}
