//! The triangles in blocks of 8 (`TriBlock`) and the tests of a traversal's group of them: one
//! at a time (obvhs's Möller–Trumbore test), and a block's 8 at once with AVX2, the same bits.

use super::Accel;
use glam::{Vec2, Vec3A};
use obvhs::{ray::Ray, rt_triangle::RtTriangle};

/// The test of `RtTriangle::intersect` (the same arithmetic, so the same bits), returning the
/// hit's `t` and the numerators of its barycentrics and their denominator, or `None`.
#[inline(always)]
pub(super) fn hit_triangle(tri: &Tri, ray: &Ray) -> Option<(f32, Vec2, f32)> {
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

/// Whether a hit `(t, det, prim)` replaces the closest so far (`best`, at `tmax`): it is
/// nearer, or as near and a better choice between coincident triangles: the one that faces the
/// ray (counter-clockwise seen from the ray's origin, as OBJ's front faces are; obvhs's
/// `ng = e1 × e2` is the opposite of that face's normal, so `det = ng·d > 0`) over one that faces away, else the lower index. So two faces of a
/// zero-thickness wall, each facing its own side, are each seen from their side, and the hit is
/// the same whichever order a traversal tests the tied triangles in (the tree's order by the
/// ray's octant, or a small scene's blocks in their order: `small.rs`).
#[inline(always)]
pub(super) fn closer(
    (t, det, prim): (f32, f32, u32),
    tmax: f32,
    best: &Option<(u32, Vec2, f32)>,
) -> bool {
    t < tmax
        || (t == tmax
            && best.is_some_and(|(id, _, best_det)| {
                let (front, best_front) = (det > 0.0, best_det > 0.0);
                (front && !best_front) || (front == best_front && prim < id)
            }))
}

/// One triangle as the test reads it (obvhs's `RtTriangle` fields).
#[derive(Clone, Copy, Debug)]
pub(super) struct Tri {
    pub(super) v0: Vec3A,
    /// `v0 − v1`.
    pub(super) e1: Vec3A,
    /// `v2 − v0`.
    pub(super) e2: Vec3A,
    /// `e1 × e2`.
    pub(super) ng: Vec3A,
}

/// Eight triangles (in [`super::Accel`]'s blocks, BVH-order indices `8k .. 8k + 8` of block
/// `k`; a small scene's walk keeps each lane's index beside its blocks), each coordinate a row
/// of 8 lanes: rows 0–2 `v0`, 3–5 `e1`, 6–8 `e2`, 9–11 `ng` (x, y, z). Lanes past the last
/// triangle are zeros and never tested.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
pub(super) struct TriBlock {
    pub(super) rows: [[f32; 8]; 12],
}

impl TriBlock {
    /// Lane `i`'s triangle.
    #[inline(always)]
    pub(super) fn get(&self, i: usize) -> Tri {
        let r = &self.rows;
        let v = |k: usize| Vec3A::new(r[k][i], r[k + 1][i], r[k + 2][i]);
        Tri {
            v0: v(0),
            e1: v(3),
            e2: v(6),
            ng: v(9),
        }
    }

    /// The corners of the box of lane `i`'s triangle (its vertices `v0`, `v0 − e1`, `v0 + e2`
    /// as rounded from the rows: within an ulp or two of the input's).
    pub(super) fn bounds(&self, i: usize) -> (Vec3A, Vec3A) {
        let t = self.get(i);
        let (v1, v2) = (t.v0 - t.e1, t.v0 + t.e2);
        (t.v0.min(v1).min(v2), t.v0.max(v1).max(v2))
    }

    /// Put `t` in lane `i`.
    pub(super) fn set(&mut self, i: usize, t: &RtTriangle) {
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
pub(super) fn group_closest(
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
            if closer((t, det, id), ray.tmax, best) && keep(id, n / det) {
                ray.tmax = t;
                *best = Some((id, n, det));
            }
        }
    }
}

/// Whether a triangle of a group (as [`group_closest`]) blocks `ray` and `keep` accepts it.
#[inline(always)]
pub(super) fn group_any(
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
    let (hits, t, nu, nv, det) = block_test_avx2(b, ray);
    let hits = _mm256_movemask_ps(hits) as u32;
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

/// [`block_hits_avx2`] in vectors: the lanes hit (all bits set), `t`, the barycentric
/// numerators and the denominator.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
#[allow(clippy::type_complexity)]
fn block_test_avx2(
    b: &TriBlock,
    ray: &Ray,
) -> (
    std::arch::x86_64::__m256,
    std::arch::x86_64::__m256,
    std::arch::x86_64::__m256,
    std::arch::x86_64::__m256,
    std::arch::x86_64::__m256,
) {
    use std::arch::x86_64::*;
    // SAFETY: a row is 8 f32s at a 32-byte boundary (TriBlock is align(32))
    #[allow(unsafe_code)]
    let row = |i: usize| unsafe { _mm256_load_ps(b.rows[i].as_ptr()) };
    let (o, d) = (ray.origin, ray.direction);
    let tri = std::array::from_fn(row);
    let test = lane_test_avx2(
        tri,
        [o.x, o.y, o.z].map(|x| _mm256_set1_ps(x)),
        [d.x, d.y, d.z].map(|x| _mm256_set1_ps(x)),
    );
    let (tmin, tmax) = (_mm256_set1_ps(ray.tmin), _mm256_set1_ps(ray.tmax));
    let hits = test.verdict(tmin, tmax);
    (hits, test.t, test.nu, test.nv, test.det)
}

/// [`hit_triangle`] on 8 (triangle, ray) pairs, a pair a lane, its vectors: the denominator
/// `det`, `1/det`, the barycentric numerators, `u`, `v`, `w` and `t`.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
pub(super) struct LaneTest {
    pub(super) det: std::arch::x86_64::__m256,
    pub(super) inv_det: std::arch::x86_64::__m256,
    pub(super) nu: std::arch::x86_64::__m256,
    pub(super) nv: std::arch::x86_64::__m256,
    pub(super) u: std::arch::x86_64::__m256,
    pub(super) v: std::arch::x86_64::__m256,
    pub(super) w: std::arch::x86_64::__m256,
    pub(super) t: std::arch::x86_64::__m256,
}

/// [`hit_triangle`] operation for operation in each lane (glam's cross product and dot
/// products in their order, a multiply then an add, never fused; the same division), so each
/// lane's values are the scalar test's bits: `tri` the rows `v0`, `e1`, `e2`, `ng` (x, y, z
/// each), `o` and `d` the rays' origins and directions. A block's 8 triangles against one ray
/// broadcast, or one triangle broadcast against a packet's 8 rays (`packet.rs`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn lane_test_avx2(
    tri: [std::arch::x86_64::__m256; 12],
    [ox, oy, oz]: [std::arch::x86_64::__m256; 3],
    [dx, dy, dz]: [std::arch::x86_64::__m256; 3],
) -> LaneTest {
    use std::arch::x86_64::*;
    let (mul, add, sub) = (_mm256_mul_ps, _mm256_add_ps, _mm256_sub_ps);
    // c = v0 − origin; r = d × c as glam computes it
    let cx = sub(tri[0], ox);
    let cy = sub(tri[1], oy);
    let cz = sub(tri[2], oz);
    let rx = sub(mul(dy, cz), mul(cy, dz));
    let ry = sub(mul(dz, cx), mul(cz, dx));
    let rz = sub(mul(dx, cy), mul(cx, dy));
    // glam's dot: (x·x' + y·y') + z·z'
    let dot = |ax, ay, az, bx, by, bz| add(add(mul(ax, bx), mul(ay, by)), mul(az, bz));
    let (ngx, ngy, ngz) = (tri[9], tri[10], tri[11]);
    let det = dot(ngx, ngy, ngz, dx, dy, dz);
    let inv_det = _mm256_div_ps(_mm256_set1_ps(1.0), det);
    let nu = dot(rx, ry, rz, tri[6], tri[7], tri[8]);
    let nv = dot(rx, ry, rz, tri[3], tri[4], tri[5]);
    let (u, v) = (mul(nu, inv_det), mul(nv, inv_det));
    let w = sub(sub(_mm256_set1_ps(1.0), u), v);
    let t = mul(dot(ngx, ngy, ngz, cx, cy, cz), inv_det);
    LaneTest {
        det,
        inv_det,
        nu,
        nv,
        u,
        v,
        w,
        t,
    }
}

#[cfg(target_arch = "x86_64")]
impl LaneTest {
    /// The lanes hit (all bits set): `1/det ≠ 0`, none of `u`, `v`, `w` with its sign bit set
    /// (a lane is negative where one is), and `t ∈ [tmin, tmax]`: [`hit_triangle`]'s verdict.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(super) fn verdict(
        &self,
        tmin: std::arch::x86_64::__m256,
        tmax: std::arch::x86_64::__m256,
    ) -> std::arch::x86_64::__m256 {
        use std::arch::x86_64::*;
        let negative = _mm256_castsi256_ps(_mm256_srai_epi32::<31>(_mm256_castps_si256(
            _mm256_or_ps(_mm256_or_ps(self.u, self.v), self.w),
        )));
        _mm256_andnot_ps(
            negative,
            _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_NEQ_UQ>(self.inv_det, _mm256_setzero_ps()),
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_GE_OQ>(self.t, tmin),
                    _mm256_cmp_ps::<_CMP_LE_OQ>(self.t, tmax),
                ),
            ),
        )
    }
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

/// [`group_closest`] with a block's 8 triangles tested at once ([`block_closest_avx2`]): the
/// hits taken in another order than the scalar walk's, but the rule of [`closer`] orders every
/// hit, so the result is the scalar one's bits, `keep` included.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn group_closest_avx2(
    acc: &Accel,
    base: u32,
    bits: u32,
    ray: &mut Ray,
    best: &mut Option<(u32, Vec2, f32)>,
    keep: &impl Fn(u32, Vec2) -> bool,
) {
    for (block, lanes) in group_blocks(base, bits) {
        let id = |i: usize| (block * 8 + i) as u32;
        block_closest_avx2(&acc.blocks[block], (lanes, id), ray, best, keep);
    }
}

/// The hits of the triangles of `b` in `lanes` (a bit a lane; lane `i`'s BVH-order index
/// `id(i)`), tested at once ([`block_hits_avx2`]), taken into the closest kept hit `best`: one
/// that [`closer`] prefers and `keep` accepts shortens the ray and becomes `best`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn block_closest_avx2(
    b: &TriBlock,
    (lanes, id): (u32, impl Fn(usize) -> u32),
    ray: &mut Ray,
    best: &mut Option<(u32, Vec2, f32)>,
    keep: &impl Fn(u32, Vec2) -> bool,
) {
    let (hits, [t, nu, nv, det]) = block_hits_avx2(b, ray);
    let mut hits = hits & lanes;
    while hits != 0 {
        let i = hits.trailing_zeros() as usize;
        hits &= hits - 1;
        let id = id(i);
        let n = Vec2::new(nu[i], nv[i]);
        if closer((t[i], det[i], id), ray.tmax, best) && keep(id, n / det[i]) {
            ray.tmax = t[i];
            *best = Some((id, n, det[i]));
        }
    }
}

/// [`group_any`] with a block's 8 triangles tested at once.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn group_any_avx2(
    acc: &Accel,
    base: u32,
    bits: u32,
    ray: &Ray,
    keep: &impl Fn(u32, Vec2) -> bool,
) -> bool {
    group_blocks(base, bits).any(|(block, lanes)| {
        let id = |i: usize| (block * 8 + i) as u32;
        block_any_avx2(&acc.blocks[block], (lanes, id), ray, keep)
    })
}

/// Whether a triangle of `b` in `lanes` (lane `i`'s BVH-order index `id(i)`) blocks `ray` and
/// `keep` accepts it.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn block_any_avx2(
    b: &TriBlock,
    (lanes, id): (u32, impl Fn(usize) -> u32),
    ray: &Ray,
    keep: &impl Fn(u32, Vec2) -> bool,
) -> bool {
    let (hits, [_, nu, nv, det]) = block_hits_avx2(b, ray);
    let mut hits = hits & lanes;
    while hits != 0 {
        let i = hits.trailing_zeros() as usize;
        hits &= hits - 1;
        if keep(id(i), Vec2::new(nu[i], nv[i]) / det[i]) {
            return true;
        }
    }
    false
}
