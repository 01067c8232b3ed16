//! How records reach the S-tree's learners: grouped by leaf in their order, and the same tree
//! whether they are added alone or while a render reads the tree.

use super::*;
use glam::Vec2;
use rand::{rngs::SmallRng, Rng, SeedableRng};

/// `n` records at random points of the cube `[0, 4)³`, each in the leaf of `tree` its point
/// lies in, with random directions, values and pdfs.
fn random_records(tree: &SdTree, rng: &mut SmallRng, n: usize) -> Vec<Record> {
    (0..n)
        .map(|_| {
            let p = Vec3::new(rng.random(), rng.random(), rng.random()) * 4.0;
            let pdf = rng.random_range(0.05..2.0);
            Record {
                leaf: tree.leaf_and_extent(p).0,
                point: Vec2::new(rng.random(), rng.random()),
                value: rng.random_range(0.0..3.0),
                product: rng.random_range(0.0..1.0),
                pdf,
                p_bsdf: pdf * rng.random_range(0.5..1.5),
                p_guide: rng.random_range(0.05..2.0),
            }
        })
        .collect()
}

/// The counting sort gives what a stable sort by leaf gives, with the runs where they start,
/// leaves with no record included (records in 50 of 64 leaves, at random).
#[test]
fn grouping_by_leaf_is_a_stable_sort() {
    let mut rng = SmallRng::seed_from_u64(11);
    let records: Vec<Record> = (0..5000)
        .map(|i| Record {
            leaf: rng.random_range(0..50u32) * 64 / 50,
            point: Vec2::new(i as f32, 0.0), // the record's place in the input: its order
            ..Record::default()
        })
        .collect();
    // in three sets of uneven length, as a batch's tiles hand them over
    let sets = [&records[..1200], &records[1200..1201], &records[1201..]];
    let (grouped, start) = group_by_leaf(&sets, 64);
    let mut sorted = records.clone();
    sorted.sort_by_key(|r| r.leaf);
    assert_eq!(grouped, sorted);
    assert_eq!(start.len(), 65);
    for leaf in 0..64u32 {
        let run = &grouped[start[leaf as usize]..start[leaf as usize + 1]];
        assert!(run.iter().all(|r| r.leaf == leaf));
        assert_eq!(run.len(), records.iter().filter(|r| r.leaf == leaf).count());
    }
}

/// Two training iterations of three record sets each, added alone to one tree and while a
/// "render" reads the other: the two trees are equal (bit for bit: the learners' sums and the
/// learned `α` depend on the records' order), and the render's result comes back.
#[test]
fn records_added_during_a_render_make_the_same_tree() {
    let mut rng = SmallRng::seed_from_u64(5);
    let mut alone = SdTree::new(Vec3::ZERO, Vec3::splat(4.0));
    let mut during = alone.clone();
    for iteration in 0..2 {
        let sets: Vec<Vec<Record>> = (0..3)
            .map(|_| random_records(&alone, &mut rng, 40_000))
            .collect();
        for set in &sets {
            alone.add_records(set);
        }
        let leaves = during.add_records_during(sets, |t| t.size().leaves);
        assert_eq!(leaves, during.leaves.len());
        alone.finish_iteration(120_000);
        during.finish_iteration(120_000);
        assert_eq!(alone, during, "iteration {iteration}");
    }
    // the records taught something: the tree split and its leaves sample
    assert!(alone.leaves.len() > 1, "{}", alone.leaves.len());
    assert!(alone.leaves.iter().all(|l| l.sampling.total() > 0.0));
}
