use super::*;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

/// The reference for the lanes of [`WideNode::importance`]: the same bound for one node's
/// emitters, one float at a time.
fn scalar_importance(b: &NodeBounds, p: Vec3, n: Vec3) -> f32 {
    // cos(a − b) and sin(a − b), clamped at 0 when b ≥ a
    #[inline(always)]
    fn cos_sub(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
        if cos_a > cos_b {
            1.0
        } else {
            cos_a * cos_b + sin_a * sin_b
        }
    }
    #[inline(always)]
    fn sin_sub(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
        if cos_a > cos_b {
            0.0
        } else {
            sin_a * cos_b - cos_a * sin_b
        }
    }
    let v = p - b.centre;
    let dist2 = v.length_squared();
    let wi = v * dist2.sqrt().recip();
    let cos_w = if dist2 > 0.0 { b.w.dot(wi) } else { 1.0 };
    let sin_w = (1.0 - cos_w * cos_w).max(0.0).sqrt();
    // the cone of directions from p that the box subtends (its bounding sphere)
    let cos_b = if dist2 < b.radius2 {
        -1.0
    } else {
        (1.0 - b.radius2 / dist2).max(0.0).sqrt()
    };
    let sin_b = (1.0 - cos_b * cos_b).max(0.0).sqrt();
    let cos_x = cos_sub(sin_w, cos_w, b.sin_theta_o, b.cos_theta_o);
    let sin_x = sin_sub(sin_w, cos_w, b.sin_theta_o, b.cos_theta_o);
    let cos_p = cos_sub(sin_x, cos_x, sin_b, cos_b);
    if cos_p <= b.cos_theta_e {
        return 0.0;
    }
    let cos_i = if dist2 > 0.0 { wi.dot(n).abs() } else { 1.0 };
    let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
    let importance = b.phi * cos_p * cos_sub(sin_i, cos_i, sin_b, cos_b) / dist2.max(b.min_d2);
    importance.max(0.0)
}

/// The four lanes of a collapsed node compute pbrt-v4's importance bound bit for bit as the
/// scalar [`scalar_importance`] does for each child alone (the same operations in the
/// same order; `sqrtps` rounds as `sqrtss`), zero included (behind a cone, inside a box),
/// and an unused lane has none. Random emitters and their unions, random receivers inside
/// and around them.
#[test]
fn a_nodes_lanes_are_the_scalar_importance() {
    let mut rng = SmallRng::seed_from_u64(7);
    let mut v = || Vec3::new(rng.random(), rng.random(), rng.random()) * 4.0 - 2.0;
    let (mut zero, mut positive) = (0, 0);
    for _ in 0..2000 {
        let tri = |c: Vec3, a: Vec3, b: Vec3, le: f32| {
            LightBounds::of(&Emitter::triangle(0, [c, c + a, c + b], Vec3::splat(le)))
        };
        let e: Vec<LightBounds> = (0..4)
            .map(|k| tri(v(), 0.3 * v(), 0.3 * v(), 1.0 + k as f32))
            .collect();
        let lanes = [
            e[0],
            LightBounds::union(Some(e[0]), e[1]),
            LightBounds::union(Some(e[2]), e[3]),
        ];
        let mut node = WideNode::EMPTY;
        node.count = 3;
        for (i, b) in lanes.iter().enumerate() {
            node.set_lane(i, &NodeBounds::of(b));
        }
        let (p, n) = (v(), v().normalize_or(Vec3::Y));
        let wide = node.importance(p, n).to_array();
        for (i, b) in lanes.iter().enumerate() {
            let scalar = scalar_importance(&NodeBounds::of(b), p, n);
            assert_eq!(wide[i].to_bits(), scalar.to_bits(), "lane {i}: {wide:?}");
            if scalar > 0.0 {
                positive += 1;
            } else {
                zero += 1;
            }
        }
        assert_eq!(wide[3], 0.0, "an unused lane");
    }
    assert!(
        zero > 100 && positive > 1000,
        "{zero} zero, {positive} positive"
    );
}

/// A node's split gives every lane of positive importance at least one unit while there
/// are enough, nothing to a lane without, the whole range in order, and each lane within a
/// unit of its share of the importance.
#[test]
fn a_split_follows_the_importance_in_whole_units() {
    let mut rng = SmallRng::seed_from_u64(11);
    let emitters: Vec<Emitter> = (0..40u32)
        .map(|k| {
            let c = Vec3::new(rng.random(), rng.random(), rng.random()) * 10.0;
            let le = Vec3::splat(rng.random_range(0.1..10.0));
            Emitter::triangle(k, [c, c + Vec3::X, c + Vec3::Z], le)
        })
        .collect();
    let tree = LightTree::build(&emitters);
    for _ in 0..500 {
        let p = Vec3::new(rng.random(), rng.random(), rng.random()) * 12.0 - 1.0;
        let len: u32 = rng.random_range(1..200);
        let range = 5..5 + len;
        let node = &tree.nodes[rng.random_range(0..tree.nodes.len())];
        let Some(b) = tree.split_units(node, p, Vec3::Y, &range) else {
            continue;
        };
        let imp = node.importance(p, Vec3::Y).to_array();
        let m = imp.iter().filter(|&&c| c > 0.0).count() as u32;
        let total: f64 = imp.iter().map(|&c| c as f64).sum();
        assert_eq!((b[0], b[WIDTH]), (range.start, range.end));
        for i in 0..WIDTH {
            let units = b[i + 1] - b[i];
            if imp[i] <= 0.0 {
                assert_eq!(units, 0, "lane {i} without importance: {imp:?}");
            } else if len >= m {
                let share = (len - m) as f64 * imp[i] as f64 / total;
                assert!(units >= 1 && (units as f64 - 1.0 - share).abs() <= 1.0);
            }
        }
    }
}
