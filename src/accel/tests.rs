//! The accelerator's tests: the AVX2 node and triangle tests against the scalar ones, bit for
//! bit, and rays as obvhs makes them.

use super::*;
use rand::{rngs::SmallRng, Rng, SeedableRng};
use small::tests::small_walks;

/// `n` random triangles of edges up to `size` with corners in the cube [−2, 2]³ (seed `seed`).
pub(super) fn random_triangles(seed: u64, n: usize, size: f32) -> Vec<[Vec3; 3]> {
    let mut rng = SmallRng::seed_from_u64(seed);
    let mut p = || Vec3::new(rng.random(), rng.random(), rng.random()) * 4.0 - 2.0;
    (0..n)
        .map(|_| {
            let c = p();
            [c, c + p() * size, c + p() * size]
        })
        .collect()
}

/// The filters the walks' tests run with: every hit kept, and some refused (as a cutout's
/// opacity map refuses them).
pub(super) const KEEPS: [fn(u32, Vec2) -> bool; 2] =
    [|_, _| true, |prim, b| !prim.is_multiple_of(3) && b.x < 0.8];

/// The tree's AVX2 closest hit and any-hit answer for the ray `(o, d, tmax)` under `keep`
/// (the caller has checked the CPU has AVX2).
#[cfg(target_arch = "x86_64")]
pub(super) fn tree_avx2(
    accel: &Accel,
    stack: &mut TraceStack,
    (o, d, tmax): (Vec3, Vec3, f32),
    keep: fn(u32, Vec2) -> bool,
) -> (Option<Hit>, bool) {
    // SAFETY: the caller checked that the CPU has AVX2
    #[allow(unsafe_code)]
    unsafe {
        (
            accel.closest_avx2(&mut stack.1, o, d, tmax, keep),
            accel.any_avx2(&mut stack.0, o, d, tmax, keep),
        )
    }
}

/// A hit as the bits a bit-for-bit comparison compares.
pub(super) fn hit_bits(h: Option<Hit>) -> Option<(u32, u32, u32, u32)> {
    h.map(|h| (h.prim, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()))
}

/// The AVX2 node test gives obvhs's mask, bit for bit, on every node of a BVH over random
/// triangles, for rays of every octant (signed zeros included) and short and long `tmax`:
/// the claim that makes images bit-identical whichever test the CPU runs.
#[test]
#[cfg(target_arch = "x86_64")]
fn the_avx2_node_test_gives_obvhs_mask() {
    if !has_avx2() {
        return;
    }
    let tris = random_triangles(49, 500, 0.1);
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
    let mut tris = random_triangles(4949, 700, 0.3);
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
        for keep in KEEPS {
            let (wide, wide_any) = tree_avx2(&accel, &mut stack, (o, d, tmax), keep);
            let scalar = accel.closest_sse(&mut stack.0, o, d, tmax, keep);
            let scalar_any = accel.any_sse(&mut stack.0, o, d, tmax, keep);
            assert_eq!(hit_bits(wide), hit_bits(scalar), "ray {i}");
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

/// The build keeps each triangle in exactly one leaf: `order` is a permutation of the input
/// indices (a scene makes one emitter and one shading record per BVH-order triangle, so a
/// triangle referenced twice, as obvhs's pre-splitting makes them, would emit twice), and each
/// BVH-order triangle's vertices are its input triangle's. Long thin triangles along the
/// diagonal of the cloud of small ones, whose boxes are mostly empty, are what pre-splitting
/// splits (with it on, this scene's BVH held 4454 references to its 4200 triangles).
#[test]
fn the_build_keeps_each_triangle_once() {
    let mut tris = random_triangles(5, 4000, 0.05);
    for k in 0..200 {
        let s = k as f32 * 0.01;
        tris.push([
            Vec3::new(-1.9, -1.9 + s, -1.9),
            Vec3::new(1.9, 1.9, 1.9 - s),
            Vec3::new(1.9, 1.88, 1.9),
        ]);
    }
    let accel = Accel::build(&tris);
    assert_eq!(accel.len(), tris.len());
    let mut seen = vec![false; tris.len()];
    for (prim, &i) in accel.order.iter().enumerate() {
        assert!(!seen[i as usize], "triangle {i} is in the BVH twice");
        seen[i as usize] = true;
        let [a, b, c] = accel.vertices(prim as u32);
        for (got, want) in [a, b, c].into_iter().zip(tris[i as usize]) {
            assert!((got - want).length() < 1e-5, "triangle {i}");
        }
    }
}

/// Two coincident faces of a zero-thickness wall, facing opposite ways: a ray from either side
/// hits the face that faces it, whichever walk runs (the tree's, AVX2 and SSE; every block's;
/// the brute-force reference), and whichever of the two comes first in the triangle list.
#[test]
fn a_two_faced_wall_shows_each_side_its_own_face() {
    let up = [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    let down = [up[0], up[2], up[1]];
    // far-away clutter: with it the tree is walked, without it every block is tested
    let clutter: Vec<[Vec3; 3]> = random_triangles(3, 100, 0.2)
        .into_iter()
        .map(|t| t.map(|p| p + Vec3::new(10.0, 0.0, 0.0)))
        .collect();
    for pair in [[up, down], [down, up]] {
        for extra in [&clutter[..0], &clutter[..]] {
            let mut tris = pair.to_vec();
            tris.extend_from_slice(extra);
            let accel = Accel::build(&tris);
            for (o, d, facing) in [(Vec3::Z, -Vec3::Z, up), (-Vec3::Z, Vec3::Z, down)] {
                for x in [-0.3f32, 0.0, 0.2] {
                    let o = o + Vec3::new(x, 0.1 * x, 0.0);
                    let mut stack = TraceStack::default();
                    let mut found = vec![
                        accel.intersect_with(&mut stack, o, d, f32::INFINITY),
                        accel.intersect_brute_force(o, d, f32::INFINITY),
                        accel.closest_sse(&mut stack.0, o, d, f32::INFINITY, |_, _| true),
                    ];
                    #[cfg(target_arch = "x86_64")]
                    if has_avx2() {
                        // SAFETY: the CPU has AVX2
                        #[allow(unsafe_code)]
                        found.push(unsafe {
                            accel.closest_avx2(&mut stack.1, o, d, f32::INFINITY, |_, _| true)
                        });
                    }
                    for hit in found {
                        let hit = hit.expect("the wall is hit");
                        let v = accel.vertices(hit.prim);
                        let input = tris[accel.order[hit.prim as usize] as usize];
                        assert_eq!(input, facing, "from {o} along {d}: {v:?}");
                    }
                }
            }
        }
    }
}

/// Packet `i` of a test: its lanes live at random (a dead lane keeps its old ray), each ray
/// from a random point at a point of one of `scene`'s triangles, some with a zero direction
/// component of either sign, a third with `tmax` 2.
fn refill(p: &mut RayPacket, rng: &mut SmallRng, scene: &[[Vec3; 3]], i: usize) {
    p.clear();
    for lane in 0..LANES {
        let o = Vec3::new(rng.random(), rng.random(), rng.random()) * 6.0 - 3.0;
        let t = scene[rng.random_range(0..scene.len())];
        let mut d = (t[0] * 0.6 + t[1] * 0.3 + t[2] * 0.1 - o).normalize_or(Vec3::X);
        if (i + lane).is_multiple_of(5) {
            d.x = if lane % 2 == 0 { 0.0 } else { -0.0 };
            d = d.normalize_or(Vec3::Y);
        }
        let tmax = if lane.is_multiple_of(3) {
            2.0
        } else {
            f32::INFINITY
        };
        if rng.random::<f32>() < 0.8 {
            p.set(lane, o, d, tmax);
        }
    }
}

/// Packets of rays ([`Accel::intersect_packet`], [`Accel::occluded_packet`]) give each live
/// lane the hit and the verdict of its ray alone, bit for bit: on a small scene with
/// coincident triangles (ties of `t`, facing the same way and the other way), with the
/// blocks' boxes tested first and not, rays of every direction (zero components of either
/// sign), short and infinite `tmax`, and packets with dead lanes between live ones (whose
/// stale rays must not count), the rays' own walks checked against every triangle tested in
/// order; and ray by ray on a scene too large for packets.
#[test]
fn packets_give_each_rays_hit() {
    // every fourth triangle four times, twice each way round: the build puts coincident
    // triangles at neighbouring indices, so the ties fall among the lanes' running hits
    let mut tris = random_triangles(91, 60, 0.8);
    let copies: Vec<[Vec3; 3]> = tris.iter().step_by(4).copied().collect();
    tris.extend(&copies);
    for _ in 0..2 {
        tris.extend(copies.iter().map(|t| [t[0], t[2], t[1]]));
    }
    let large = random_triangles(92, 400, 0.3);
    let mut rng = SmallRng::seed_from_u64(6);
    let mut stack = TraceStack::default();
    let (mut hits, mut blocked, mut lanes) = (0, 0, 0);
    let mut small_scene = Accel::build(&tris);
    let mut cases: Vec<_> = small_walks(&small_scene, 66)
        .into_iter()
        .map(|(walk, small)| (walk, Some(small)))
        .collect();
    cases.push(("large", None));
    let large_scene = Accel::build(&large);
    assert!(large_scene.small.is_none());
    for (walk, small) in cases {
        let (accel, scene) = match small {
            Some(s) => {
                small_scene.small = Some(s);
                (&small_scene, &tris)
            }
            None => (&large_scene, &large),
        };
        let mut p = RayPacket::new();
        for i in 0..3000 {
            refill(&mut p, &mut rng, scene, i);
            let mut got = [None; LANES];
            accel.intersect_packet(&mut stack, &p, &mut got);
            let blocking = accel.occluded_packet(&mut stack, &p);
            assert_eq!(blocking & !p.live(), 0, "packet {i}: a dead lane blocked");
            for lane in p.lanes() {
                let (o, d, tmax) = p.ray(lane);
                let want = accel.intersect_with(&mut stack, o, d, tmax);
                assert_eq!(
                    hit_bits(got[lane]),
                    hit_bits(want),
                    "packet {i}, lane {lane}, {walk}"
                );
                if accel.small.is_some() {
                    // the walk itself against every triangle tested in index order
                    let brute = accel.intersect_brute_force(o, d, tmax);
                    assert_eq!(
                        hit_bits(want),
                        hit_bits(brute),
                        "packet {i}, lane {lane}, {walk}"
                    );
                }
                let occluded = accel.occluded_with(&mut stack, o, d, tmax);
                assert_eq!(
                    blocking & (1 << lane) != 0,
                    occluded,
                    "packet {i}, lane {lane}, {walk}"
                );
                hits += want.is_some() as u32;
                blocked += occluded as u32;
                lanes += 1;
            }
        }
    }
    // rays aimed at triangles: most hit, a third of them with tmax 2 fewer
    assert!(hits > lanes / 2 && hits < lanes, "{hits} of {lanes}");
    assert!(blocked > lanes / 3, "{blocked} of {lanes}");
}
