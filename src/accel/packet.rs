//! Packets of up to 8 rays through a small scene's blocks, a ray in each lane of an AVX2
//! vector (issue 49): every triangle of the scene is broadcast and tested against the 8 rays
//! at once, by [`super::triangles::hit_triangle`]'s arithmetic operation for operation (a
//! multiply then an add, never fused; the same division), so each lane's verdict, `t` and
//! barycentric numerators are the scalar test's bits. The closest hit keeps the whole rule of
//! [`super::triangles::closer`] (at the same `t`, the face turned toward the ray, then the
//! lower BVH index: a block's triangles may come in any order), so the result is the scalar
//! walk's hit, bit for bit. A shadow packet ends when every live lane is blocked.
//!
//! Where a walk tests the blocks' boxes first (`small.rs`), a packet skips a block whose box
//! none of its live rays enters before its closest hit so far: skipping a block that holds no
//! closer hit changes nothing, so the culling is only a saving.
//!
//! Why packets: a scalar ray's walk of the blocks is a chain (each block's test, its branch
//! on any hit, its update of the ray's `tmax`), which the core cannot overlap with another
//! ray's; 8 rays in lanes make each triangle's test one instruction stream for all of them.
//! Where the scene is not small, has cutouts or the CPU has no AVX2, [`super::Accel`] traces a
//! packet's rays one by one ([`super::Accel::intersect_packet`]).

#[cfg(target_arch = "x86_64")]
use super::has_avx2;
#[cfg(target_arch = "x86_64")]
use super::small::SmallScene;
#[cfg(target_arch = "x86_64")]
use super::triangles::{hit_triangle, lane_test_avx2};
use super::{positive_zeros, Accel, Hit, TraceStack};
use glam::Vec3;

/// Rays in a packet.
pub const LANES: usize = 8;

/// Up to [`LANES`] rays `origin + t·dir`, `t ∈ [0, tmax]`, each coordinate a row of 8 lanes
/// (directions with −0.0 made +0.0, as every walk takes them), and the lanes that hold one.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct RayPacket {
    pub(super) o: [[f32; LANES]; 3],
    pub(super) d: [[f32; LANES]; 3],
    pub(super) tmax: [f32; LANES],
    /// Bit `i`: lane `i` holds a ray.
    pub(super) live: u32,
}

impl Default for RayPacket {
    fn default() -> Self {
        RayPacket {
            o: [[0.0; LANES]; 3],
            // a dead lane's ray is a valid one (no division by zero in its box test)
            d: [[1.0; LANES]; 3],
            tmax: [0.0; LANES],
            live: 0,
        }
    }
}

impl RayPacket {
    /// An empty packet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Put the ray `origin + t·dir`, `t ∈ [0, tmax]` (`dir` unit) in `lane`.
    #[inline(always)]
    pub fn set(&mut self, lane: usize, origin: Vec3, dir: Vec3, tmax: f32) {
        let d = positive_zeros(dir);
        for axis in 0..3 {
            self.o[axis][lane] = origin[axis];
            self.d[axis][lane] = d[axis];
        }
        self.tmax[lane] = tmax;
        self.live |= 1 << lane;
    }

    /// Empty every lane.
    #[inline(always)]
    pub fn clear(&mut self) {
        self.live = 0;
    }

    /// The lanes that hold a ray, a bit each.
    #[inline(always)]
    pub fn live(&self) -> u32 {
        self.live
    }

    /// The live lanes, in increasing order.
    #[inline(always)]
    pub fn lanes(&self) -> impl Iterator<Item = usize> {
        let mut live = self.live;
        std::iter::from_fn(move || {
            (live != 0).then(|| {
                let lane = live.trailing_zeros() as usize;
                live &= live - 1;
                lane
            })
        })
    }

    /// Lane `lane`'s ray: origin, direction (with −0.0 made +0.0) and `tmax`.
    #[inline(always)]
    pub fn ray(&self, lane: usize) -> (Vec3, Vec3, f32) {
        let v = |r: &[[f32; LANES]; 3]| Vec3::new(r[0][lane], r[1][lane], r[2][lane]);
        (v(&self.o), v(&self.d), self.tmax[lane])
    }
}

impl Accel {
    /// The closest hit of each live lane of `p` into `out` (dead lanes untouched), as
    /// [`Accel::intersect_with`] gives it for that lane's ray, bit for bit: in lanes where the
    /// scene is small and the CPU has AVX2, else ray by ray on `stack`.
    #[inline]
    pub fn intersect_packet(
        &self,
        stack: &mut TraceStack,
        p: &RayPacket,
        out: &mut [Option<Hit>; LANES],
    ) {
        #[cfg(target_arch = "x86_64")]
        if has_avx2() {
            if let Some(boxes) = &self.small {
                // SAFETY: the CPU has AVX2, all the function asks
                #[allow(unsafe_code)]
                let r = unsafe { packet_closest_avx2(boxes, p) };
                for lane in p.lanes() {
                    out[lane] = lane_hit(self, p, lane, r[lane]);
                }
                return;
            }
        }
        for lane in p.lanes() {
            let (o, d, tmax) = p.ray(lane);
            out[lane] = self.intersect_with(stack, o, d, tmax);
        }
    }

    /// The live lanes of `p` whose rays something blocks, a bit each, as
    /// [`Accel::occluded_with`] finds them (see [`Accel::intersect_packet`]).
    #[inline]
    pub fn occluded_packet(&self, stack: &mut TraceStack, p: &RayPacket) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if has_avx2() {
            if let Some(boxes) = &self.small {
                // SAFETY: the CPU has AVX2, all the function asks
                #[allow(unsafe_code)]
                return unsafe { packet_any_avx2(boxes, p) };
            }
        }
        p.lanes()
            .filter(|&lane| {
                let (o, d, tmax) = p.ray(lane);
                self.occluded_with(stack, o, d, tmax)
            })
            .fold(0, |blocked, lane| blocked | 1 << lane)
    }
}

/// The closest hit of every live lane of `p` through the blocks of a small scene: per lane the
/// BVH-order triangle (−1 for none). Two running hits a lane, the even and the odd lanes' of
/// each block (each kept by the whole rule of `closer`: the blocks may hold their triangles in
/// any order), merged at the end by the same rule: a single running hit made every triangle's
/// test wait on the last one's update of `tmax` (a chain the core cannot overlap), and a branch
/// on "any lane closer" mispredicted.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn packet_closest_avx2(scene: &SmallScene, p: &RayPacket) -> [i32; LANES] {
    use std::arch::x86_64::*;
    // SAFETY: a row is 8 f32s at a 32-byte boundary (RayPacket is align(32))
    #[allow(unsafe_code)]
    let load = |r: &[f32; LANES]| unsafe { _mm256_load_ps(r.as_ptr()) };
    let (ox, oy, oz) = (load(&p.o[0]), load(&p.o[1]), load(&p.o[2]));
    let (dx, dy, dz) = (load(&p.d[0]), load(&p.d[1]), load(&p.d[2]));
    let live = lane_mask(p.live);
    let none = _mm256_set1_epi32(-1);
    // per parity: tmax, the triangle (−1: none), whether it faces the ray
    let mut even = (load(&p.tmax), none, _mm256_setzero_ps());
    let mut odd = even;
    let ray = (ox, oy, oz, dx, dy, dz, live);
    let inv = scene.culls.then(|| inverses(dx, dy, dz));
    for (k, block) in scene.blocks.iter().enumerate() {
        if let Some(inv) = inv {
            // a lane's closest so far is the nearer of its two running hits
            let tmax = _mm256_min_ps(even.0, odd.0);
            if !enters(scene, k, (ox, oy, oz), inv, tmax, live) {
                continue;
            }
        }
        // a block's triangles fill its lanes from the first
        let (ids, n) = (&scene.ids[k], scene.full[k].count_ones() as usize);
        for i in (0..n).step_by(2) {
            let (ta, ia, fa) = &mut even;
            closest_lane(block, i, ids[i] as i32, ray, (ta, ia, fa));
            if i + 1 < n {
                let (tb, ib, fb) = &mut odd;
                closest_lane(block, i + 1, ids[i + 1] as i32, ray, (tb, ib, fb));
            }
        }
    }
    // the odd triangles' hit over the even ones' by the whole rule of `closer`
    let ((ta, ia, fa), (tb, ib, fb)) = (even, odd);
    let b_valid = _mm256_castsi256_ps(_mm256_cmpgt_epi32(ib, none));
    let a_valid = _mm256_castsi256_ps(_mm256_cmpgt_epi32(ia, none));
    let lower = _mm256_castsi256_ps(_mm256_cmpgt_epi32(ia, ib));
    let same_side = _mm256_xor_ps(_mm256_xor_ps(fa, fb), _mm256_castsi256_ps(none));
    let tie = _mm256_and_ps(
        _mm256_cmp_ps::<_CMP_EQ_OQ>(tb, ta),
        _mm256_or_ps(_mm256_andnot_ps(fa, fb), _mm256_and_ps(same_side, lower)),
    );
    let b_wins = _mm256_and_ps(
        b_valid,
        _mm256_or_ps(
            _mm256_andnot_ps(a_valid, b_valid),
            _mm256_or_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(tb, ta), tie),
        ),
    );
    let best = _mm256_blendv_ps(_mm256_castsi256_ps(ia), _mm256_castsi256_ps(ib), b_wins);
    let mut out = [0i32; LANES];
    // SAFETY: `out` is 8 lanes of 4 bytes, what an unaligned store writes
    #[allow(unsafe_code)]
    unsafe {
        _mm256_storeu_ps(out.as_mut_ptr().cast(), best)
    };
    out
}

/// Triangle `i` of `block` (BVH-order index `id`) tested against the rays of a packet
/// (origins, directions, live lanes) and taken into the running hit `(tmax, triangle, faces
/// the ray)` of each lane it is closer in, by the rule of `closer`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
#[allow(clippy::type_complexity)]
fn closest_lane(
    block: &super::triangles::TriBlock,
    i: usize,
    id: i32,
    (ox, oy, oz, dx, dy, dz, live): (
        std::arch::x86_64::__m256,
        std::arch::x86_64::__m256,
        std::arch::x86_64::__m256,
        std::arch::x86_64::__m256,
        std::arch::x86_64::__m256,
        std::arch::x86_64::__m256,
        std::arch::x86_64::__m256,
    ),
    (tmax, best, best_front): (
        &mut std::arch::x86_64::__m256,
        &mut std::arch::x86_64::__m256i,
        &mut std::arch::x86_64::__m256,
    ),
) {
    use std::arch::x86_64::*;
    let tri = std::array::from_fn(|row| _mm256_set1_ps(block.rows[row][i]));
    let test = lane_test_avx2(tri, [ox, oy, oz], [dx, dy, dz]);
    let (det, t) = (test.det, test.t);
    let ok = _mm256_and_ps(live, test.verdict(_mm256_setzero_ps(), *tmax));
    let front = _mm256_cmp_ps::<_CMP_GT_OQ>(det, _mm256_setzero_ps());
    // closer: nearer, or as near and facing the ray where the best so far does not, or
    // facing as it does with a lower index
    let id = _mm256_set1_epi32(id);
    let same_side = _mm256_xor_ps(
        _mm256_xor_ps(*best_front, front),
        _mm256_castsi256_ps(_mm256_set1_epi32(-1)),
    );
    let lower = _mm256_castsi256_ps(_mm256_cmpgt_epi32(*best, id));
    let tie = _mm256_and_ps(
        _mm256_cmp_ps::<_CMP_EQ_OQ>(t, *tmax),
        _mm256_and_ps(
            _mm256_castsi256_ps(_mm256_cmpgt_epi32(*best, _mm256_set1_epi32(-1))),
            _mm256_or_ps(
                _mm256_andnot_ps(*best_front, front),
                _mm256_and_ps(same_side, lower),
            ),
        ),
    );
    let take = _mm256_and_ps(ok, _mm256_or_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(t, *tmax), tie));
    *tmax = _mm256_blendv_ps(*tmax, t, take);
    *best_front = _mm256_blendv_ps(*best_front, front, take);
    let id = _mm256_castsi256_ps(id);
    *best = _mm256_castps_si256(_mm256_blendv_ps(_mm256_castsi256_ps(*best), id, take));
}

/// The live lanes of `p` that some triangle of a small scene blocks, a bit each.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn packet_any_avx2(scene: &SmallScene, p: &RayPacket) -> u32 {
    use std::arch::x86_64::*;
    // SAFETY: as in packet_closest_avx2
    #[allow(unsafe_code)]
    let load = |r: &[f32; LANES]| unsafe { _mm256_load_ps(r.as_ptr()) };
    let (ox, oy, oz) = (load(&p.o[0]), load(&p.o[1]), load(&p.o[2]));
    let (dx, dy, dz) = (load(&p.d[0]), load(&p.d[1]), load(&p.d[2]));
    let tmax = load(&p.tmax);
    let mut open = lane_mask(p.live);
    let inv = scene.culls.then(|| inverses(dx, dy, dz));
    for (k, block) in scene.blocks.iter().enumerate() {
        if let Some(inv) = inv {
            if !enters(scene, k, (ox, oy, oz), inv, tmax, open) {
                continue;
            }
        }
        for i in 0..scene.full[k].count_ones() as usize {
            let tri = std::array::from_fn(|row| _mm256_set1_ps(block.rows[row][i]));
            let test = lane_test_avx2(tri, [ox, oy, oz], [dx, dy, dz]);
            let blocked = _mm256_and_ps(open, test.verdict(_mm256_setzero_ps(), tmax));
            open = _mm256_andnot_ps(blocked, open);
        }
        if _mm256_movemask_ps(open) == 0 {
            break;
        }
    }
    p.live & !(_mm256_movemask_ps(open) as u32)
}

/// All bits set in each lane whose bit of `live` is set.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn lane_mask(live: u32) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::*;
    let bits = _mm256_and_si256(
        _mm256_set1_epi32(live as i32),
        _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128),
    );
    _mm256_castsi256_ps(_mm256_cmpgt_epi32(bits, _mm256_setzero_si256()))
}

/// Each lane's direction's safe inverse, as [`super::ray_of`] takes it (`1/x`, or
/// `signum(x)/ε` where `|x| ≤ ε`), per axis.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn inverses(
    dx: std::arch::x86_64::__m256,
    dy: std::arch::x86_64::__m256,
    dz: std::arch::x86_64::__m256,
) -> [std::arch::x86_64::__m256; 3] {
    use std::arch::x86_64::*;
    let inv = |d: __m256| {
        let sign = _mm256_and_ps(d, _mm256_set1_ps(-0.0));
        let abs = _mm256_andnot_ps(_mm256_set1_ps(-0.0), d);
        let small = _mm256_cmp_ps::<_CMP_LE_OQ>(abs, _mm256_set1_ps(f32::EPSILON));
        let big = _mm256_or_ps(sign, _mm256_set1_ps(1.0 / f32::EPSILON));
        _mm256_blendv_ps(_mm256_div_ps(_mm256_set1_ps(1.0), d), big, small)
    };
    [inv(dx), inv(dy), inv(dz)]
}

/// Whether a lane of `live` enters block `k`'s box (padded: `small.rs`) within `[0, tmax]`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn enters(
    boxes: &SmallScene,
    k: usize,
    o: (
        std::arch::x86_64::__m256,
        std::arch::x86_64::__m256,
        std::arch::x86_64::__m256,
    ),
    inv: [std::arch::x86_64::__m256; 3],
    tmax: std::arch::x86_64::__m256,
    live: std::arch::x86_64::__m256,
) -> bool {
    use std::arch::x86_64::*;
    let mut near = _mm256_setzero_ps();
    let mut far = tmax;
    for (axis, o) in [o.0, o.1, o.2].into_iter().enumerate() {
        let lo = _mm256_set1_ps(boxes.lo[axis][k]);
        let hi = _mm256_set1_ps(boxes.hi[axis][k]);
        let t0 = _mm256_mul_ps(_mm256_sub_ps(lo, o), inv[axis]);
        let t1 = _mm256_mul_ps(_mm256_sub_ps(hi, o), inv[axis]);
        near = _mm256_max_ps(near, _mm256_min_ps(t0, t1));
        far = _mm256_min_ps(far, _mm256_max_ps(t0, t1));
    }
    _mm256_movemask_ps(_mm256_and_ps(live, _mm256_cmp_ps::<_CMP_LE_OQ>(near, far))) != 0
}

/// The [`super::Hit`] of `lane`'s ray of `p` on BVH-order triangle `prim` (its closest,
/// from [`packet_closest_avx2`]): the scalar test again on that triangle, the same arithmetic
/// as the lanes', so the same `t` and barycentrics, bit for bit.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(super) fn lane_hit(acc: &Accel, p: &RayPacket, lane: usize, prim: i32) -> Option<super::Hit> {
    if prim < 0 {
        return None;
    }
    let (o, d, _) = p.ray(lane);
    let ray = obvhs::ray::Ray {
        origin: o.into(),
        direction: d.into(),
        inv_direction: glam::Vec3A::NAN,
        tmin: 0.0,
        tmax: f32::INFINITY,
    };
    let (t, n, det) = hit_triangle(&acc.tri(prim as u32), &ray)?;
    super::hit_of(Some((prim as u32, n, det)), t)
}
