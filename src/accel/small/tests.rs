//! The small scenes' walks (`small.rs`) against the tree's and every triangle's hits, bit for
//! bit, for every kind of walk; the regrouping's partition and a room's blocks.

use super::super::tests::{hit_bits, random_triangles, tree_avx2, KEEPS};
use super::super::*;
use super::{groups, SmallScene, SMALL_BLOCKS};
use rand::{rngs::SmallRng, Rng, SeedableRng};

/// The walks of a small scene a test compares (`small.rs`): the one its build chose; every
/// block tested in BVH order; the same blocks after their boxes; the fewest blocks of
/// [`groups`] after theirs; and the triangles shuffled into blocks of up to 8 (so a block's
/// lanes hold BVH indices in any order), with their boxes first and without.
pub(in crate::accel) fn small_walks(accel: &Accel, seed: u64) -> Vec<(&'static str, SmallScene)> {
    let n = accel.len() as u32;
    let in_order: Vec<Vec<u32>> = (0..n.div_ceil(8))
        .map(|k| (8 * k..n.min(8 * k + 8)).collect())
        .collect();
    let bounds: Vec<_> = (0..n as usize)
        .map(|i| accel.blocks[i / 8].bounds(i % 8))
        .collect();
    let fewest = groups(&bounds)
        .into_iter()
        .find(|g| !g.is_empty())
        .expect("a grouping");
    let mut rng = SmallRng::seed_from_u64(seed);
    let mut ids: Vec<u32> = (0..n).collect();
    for i in (1..ids.len()).rev() {
        ids.swap(i, rng.random_range(0..=i));
    }
    let mut shuffled = Vec::new();
    while !ids.is_empty() {
        // at least n/16 a block (so at most 16 blocks), the last the rest
        let take = rng.random_range(n.div_ceil(16) as usize..=8).min(ids.len());
        shuffled.push(ids.split_off(ids.len() - take));
    }
    assert!(shuffled.len() <= SMALL_BLOCKS, "{} blocks", shuffled.len());
    let of = |g: &[Vec<u32>], culls| SmallScene::of_groups(&accel.blocks, g, culls);
    vec![
        ("built", accel.small.clone().expect("a small scene")),
        ("in order", of(&in_order, false)),
        ("in order, boxes", of(&in_order, true)),
        ("fewest groups, boxes", of(&fewest, true)),
        ("shuffled", of(&shuffled, false)),
        ("shuffled, boxes", of(&shuffled, true)),
    ]
}

/// A small scene's walk (`small.rs`: the blocks' boxes tested first or not) finds the tree's
/// hit, bit for bit, on random triangles with duplicates (ties of `t`, facing the same way and
/// the other way) and a filter: the tie rule makes the hit independent of the order the
/// triangles are tested in, and the boxes' pad keeps a tied block from being skipped. Rays
/// whose hit is closer than the tree's node epsilon are not compared (the module doc says why).
#[test]
#[cfg(target_arch = "x86_64")]
fn a_small_scene_finds_the_trees_hit() {
    if !has_avx2() {
        return;
    }
    let mut tris = random_triangles(77, 80, 0.8);
    let copies: Vec<[Vec3; 3]> = tris.iter().step_by(4).copied().collect();
    tris.extend(copies.iter().step_by(2));
    tris.extend(copies.iter().skip(1).step_by(2).map(|t| [t[0], t[2], t[1]]));
    let accel = Accel::build(&tris);
    assert!(accel.bvh.nodes.len() > 1);
    let walks = small_walks(&accel, 55);
    let mut rng = SmallRng::seed_from_u64(5);
    let mut stack = TraceStack::default();
    let (mut hits, mut near) = (0, 0);
    for i in 0..20_000 {
        let o = Vec3::new(rng.random(), rng.random(), rng.random()) * 6.0 - 3.0;
        let t = tris[rng.random_range(0..tris.len())];
        let target = t[0] + (t[1] - t[0]) * rng.random::<f32>() * 0.5 + (t[2] - t[0]) * 0.4;
        let d = (target - o).normalize_or(Vec3::X);
        let tmax = if i % 4 == 0 { 2.0 } else { f32::INFINITY };
        for keep in KEEPS {
            let (tree, tree_any) = tree_avx2(&accel, &mut stack, (o, d, tmax), keep);
            for (walk, boxes) in &walks {
                // SAFETY: the CPU has AVX2 (checked above)
                #[allow(unsafe_code)]
                let (small, small_any) = unsafe {
                    (
                        accel.closest_small_avx2(boxes, (o, d, tmax), keep),
                        small_any_avx2(boxes, &ray_of(o, d, tmax), &keep),
                    )
                };
                if small.is_some_and(|h| h.t < 1e-3) {
                    near += 1;
                    continue;
                }
                assert_eq!(hit_bits(small), hit_bits(tree), "ray {i}, {walk}");
                assert_eq!(small_any, tree_any, "ray {i}, {walk}");
                hits += small.is_some() as u32;
            }
        }
    }
    assert!(near < 120, "{near}");
    assert!(hits > 90_000 && hits < 240_000, "{hits}");
}

/// Flat blocks (a tiled wall in the plane `z = 0.3`, each tile also as a face turned the other
/// way) with the blocks' boxes tested first: a ray meets a flat box at the `t` it meets its
/// triangles, up to rounding, and the boxes' pad makes it enter the box no later than any of
/// its triangles' hits (without the pad this fails within the first 30 rays), so the walk
/// finds the brute-force hit, the face turned toward the ray, from either side.
#[test]
#[cfg(target_arch = "x86_64")]
fn flat_blocks_keep_their_ties() {
    if !has_avx2() {
        return;
    }
    let mut tris = Vec::new();
    for i in 0..6 {
        for j in 0..4 {
            let (x, y) = (i as f32 * 0.7 - 2.0, j as f32 * 0.9 - 1.7);
            let t = [
                Vec3::new(x, y, 0.3),
                Vec3::new(x + 0.7, y, 0.3),
                Vec3::new(x, y + 0.9, 0.3),
            ];
            tris.push(t);
            tris.push([t[0], t[2], t[1]]);
        }
    }
    let accel = Accel::build(&tris);
    for (walk, boxes) in small_walks(&accel, 88) {
        let boxes = SmallScene {
            culls: true,
            ..boxes
        };
        let mut rng = SmallRng::seed_from_u64(8);
        let (mut hits, mut entries) = (0, 0);
        for i in 0..10_000 {
            let side = if i % 2 == 0 { 1.0 } else { -1.0 };
            let o = Vec3::new(rng.random(), rng.random(), 0.0) * 4.0 - Vec3::new(2.0, 2.0, -0.3)
                + Vec3::Z * side * (0.1 + 2.0 * rng.random::<f32>());
            let target =
                Vec3::new(rng.random(), rng.random(), 0.0) * 4.0 - Vec3::new(2.0, 2.0, -0.3);
            let d = (target - o).normalize();
            let (o, d, inf) = (o, d, f32::INFINITY);
            // SAFETY: the CPU has AVX2 (checked above)
            #[allow(unsafe_code)]
            let small = unsafe { accel.closest_small_avx2(&boxes, (o, d, inf), |_, _| true) };
            let brute = accel.intersect_brute_force(o, d, inf);
            assert_eq!(small, brute, "ray {i}, {walk}");
            // every triangle the ray hits lies in a box it enters, and enters no later
            let ray = ray_of(o, d, inf);
            // SAFETY: the CPU has AVX2 (checked above)
            #[allow(unsafe_code)]
            let (entered, entry) = unsafe { boxes.entered_avx2(&ray) };
            for prim in 0..accel.len() as u32 {
                if let Some((t, _, _)) = hit_triangle(&accel.tri(prim), &ray) {
                    let block = (0..boxes.blocks.len())
                        .find(|&k| {
                            let lanes = boxes.full[k].count_ones() as usize;
                            boxes.ids[k][..lanes].contains(&prim)
                        })
                        .expect("every triangle in a block");
                    assert!(entered & (1 << block) != 0 && entry[block] <= t, "ray {i}");
                    entries += 1;
                }
            }
            if let Some(h) = small {
                let v = tris[accel.order[h.prim as usize] as usize];
                let facing = (v[1] - v[0]).cross(v[2] - v[0]).dot(d) < 0.0;
                assert!(facing, "ray {i} hit the face turned away, {walk}");
                hits += 1;
            }
        }
        // a triangle covers half its tile and the tiles about 0.9 of the targets: ~45% hit
        assert!(hits > 3_500, "{hits}, {walk}");
        assert!(entries >= 2 * hits, "{entries}, {walk}");
    }
}

/// [`groups`] partitions the triangles: for each count of groups it made, that many
/// groups of 1 to 8 triangles, each triangle in one.
#[test]
fn groups_partition_the_triangles() {
    for (seed, n) in [(1, 5), (2, 36), (3, 100), (4, 128)] {
        let tris = random_triangles(seed, n, 0.5);
        let accel = Accel::build(&tris);
        let bounds: Vec<_> = (0..n).map(|i| accel.blocks[i / 8].bounds(i % 8)).collect();
        let groupings = groups(&bounds);
        let made: Vec<usize> = (0..groupings.len())
            .filter(|&k| !groupings[k].is_empty())
            .collect();
        // from a group a triangle down, every count up to 16 passes, to the fewest reached
        assert!(!made.is_empty(), "{n}: no grouping of 16 or fewer");
        let fewest = made[0];
        assert!(
            fewest >= n.div_ceil(8) && fewest <= n.div_ceil(8) + 2,
            "{n}: {fewest}"
        );
        assert_eq!(made, (fewest..=n.min(16)).collect::<Vec<_>>(), "{n}");
        for k in made {
            let mut seen = vec![0; n];
            assert_eq!(groupings[k].len(), k);
            for g in &groupings[k] {
                assert!(!g.is_empty() && g.len() <= 8, "{n}, {k}: {}", g.len());
                g.iter().for_each(|&i| seen[i as usize] += 1);
            }
            assert!(seen.iter().all(|&c| c == 1), "{n}, {k}");
        }
    }
}

/// A room as Mitsuba's box is built (five walls and a light, each a quad of two triangles, and
/// two boxes of 12) is walked wall by wall: its walk tests the blocks' boxes first, over more
/// blocks than the fewest (5), each quad's two triangles share a block, and no wall shares one
/// with a box's face out of its plane.
#[test]
fn a_room_is_walked_wall_by_wall() {
    let quad = |o: Vec3, u: Vec3, v: Vec3| [[o, o + u, o + u + v], [o, o + u + v, o + v]];
    let (x, y, z) = (Vec3::X * 2.0, Vec3::Y * 2.0, Vec3::Z * 2.0);
    let c = Vec3::splat(-1.0);
    let mut quads = vec![
        quad(c, x, z),
        quad(c + y, z, x),
        quad(c, y, x),
        quad(c, z, y),
        quad(c + x, y, z),
        quad(Vec3::new(-0.2, 0.99, -0.2), Vec3::Z * 0.4, Vec3::X * 0.4),
    ];
    for (lo, size) in [
        (Vec3::new(-0.7, -1.0, -0.6), 0.6),
        (Vec3::new(0.1, -1.0, -0.2), 0.5),
    ] {
        let (x, y, z) = (Vec3::X * size, Vec3::Y * size * 2.0, Vec3::Z * size);
        quads.extend([
            quad(lo, x, z),
            quad(lo + y, z, x),
            quad(lo, y, x),
            quad(lo + z, x, y),
            quad(lo, z, y),
            quad(lo + x, y, z),
        ]);
    }
    let tris: Vec<[Vec3; 3]> = quads.iter().flatten().copied().collect();
    assert_eq!(tris.len(), 36);
    let accel = Accel::build(&tris);
    let small = accel.small.as_ref().expect("a small scene");
    assert!(
        small.culls && small.blocks.len() > 5,
        "{}",
        small.blocks.len()
    );
    let mut block_of = vec![usize::MAX; tris.len()];
    for (k, ids) in small.ids.iter().enumerate() {
        for &id in &ids[..small.full[k].count_ones() as usize] {
            block_of[accel.order[id as usize] as usize] = k;
        }
    }
    for q in 0..quads.len() {
        assert_eq!(block_of[2 * q], block_of[2 * q + 1], "quad {q}");
        assert!(block_of[2 * q] < small.blocks.len());
    }
    // the walls are quads 0–4, the boxes' faces quads 6 on (triangles 12 on): a wall's block
    // holds no box face but one in its plane (the boxes' bottoms lie on the floor)
    for wall in 0..5 {
        let k = block_of[2 * wall];
        let [a, b, c] = tris[2 * wall];
        let n = (b - a).cross(c - a).normalize();
        for (i, t) in tris.iter().enumerate().skip(12) {
            let in_plane = t.iter().all(|&v| (v - a).dot(n).abs() < 1e-5);
            assert!(
                block_of[i] != k || in_plane,
                "wall {wall} shares a block with a box"
            );
        }
    }
}
