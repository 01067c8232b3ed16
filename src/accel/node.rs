//! The CWBVH node test: which of a node's 8 children a ray hits, as the traversal's hit mask
//! (obvhs's own test, and the same test 8 wide with AVX2).

#[cfg(target_arch = "x86_64")]
use glam::Vec3A;
use obvhs::{cwbvh::node::CwBvhNode, ray::Ray};

/// The children of `node` that `ray` hits: obvhs's own test (SSE where the target has it).
#[inline(always)]
pub(super) fn node_hits(node: &CwBvhNode, ray: &Ray, oct_inv4: u32) -> u32 {
    node.intersect_ray(ray, oct_inv4)
}

/// The `tmin` floor of obvhs's node test (its crate-private `EPSILON`).
const NODE_EPSILON: f32 = 0.0001;

/// The children of `node` that `ray` (octant `oct_inv4`) hits, as the traversal's hit mask:
/// obvhs's `intersect_ray_simd` with its 8 children in one 8-wide test instead of two 4-wide
/// ones ([`child_spans_avx2`]), and the mask assembled in the 8 lanes without a branch. The
/// arithmetic is the same, so the mask is the same bits and so are the traversal and the image.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn node_hits_avx2(node: &CwBvhNode, ray: &Ray, oct_inv4: u32) -> u32 {
    use std::arch::x86_64::*;
    let (_, hits) = child_spans_avx2(node, ray);
    hit_bits_avx2(node, _mm256_castps_si256(hits), oct_inv4)
}

/// The traversal's hit mask of `node`'s children hit where `hits` is all ones (lane `i` child
/// slot `i`) for a ray of octant `oct_inv4`: each hit child's bits (an inner child's one bit at
/// 24 + its place in the octant's order, a leaf's triangles in unary at their offset) shifted to
/// their place in the 8 lanes (obvhs loops over the hit children: a branch per child), then the
/// lanes OR-ed together.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn hit_bits_avx2(
    node: &CwBvhNode,
    hits: std::arch::x86_64::__m256i,
    oct_inv4: u32,
) -> u32 {
    use std::arch::x86_64::*;
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

/// Where `ray` enters each of the 8 children of `node` (lane `i` is child slot `i`) and whether
/// it hits it (a lane of all ones): obvhs's slab test of `intersect_ray_simd`, operation for
/// operation (a multiply, then an add, not a fused multiply-add; the same operand order of every
/// `min` and `max`), each child plane's 8 quantized bytes widened to floats by two instructions.
/// The entry distance is floored at obvhs's `tmin` of 10⁻⁴, as its test floors it.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn child_spans_avx2(
    node: &CwBvhNode,
    ray: &Ray,
) -> (std::arch::x86_64::__m256, std::arch::x86_64::__m256) {
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
    (tmin, _mm256_cmp_ps::<_CMP_LE_OQ>(tmin, tmax))
}
