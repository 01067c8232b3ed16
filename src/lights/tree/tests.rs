use super::*;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

/// The reference for the lanes of [`WideNode::importance`]: the same bound for one node's
/// emitters, one float at a time, its angles as pairs of lengths `(d cos θ, d sin θ)`.
fn scalar_importance(b: &NodeBounds, p: Vec3, n: Vec3) -> f32 {
    let v = p - b.centre;
    let dist2 = v.length_squared();
    let d = dist2.sqrt();
    let scale = b.phi / dist2.max(b.min_d2);
    let radius2 = b.radius * b.radius;
    if dist2 < radius2 || dist2 <= 0.0 {
        return scale.max(0.0);
    }
    let wv = b.w.dot(v);
    let sw = (dist2 - wv * wv).max(0.0).sqrt();
    let cb = (dist2 - radius2).max(0.0).sqrt();
    let sb = b.radius;
    let (cx, sx) = if wv > d * b.cos_theta_o {
        (d, 0.0)
    } else {
        (
            wv * b.cos_theta_o + sw * b.sin_theta_o,
            sw * b.cos_theta_o - wv * b.sin_theta_o,
        )
    };
    let cp = if cx > cb { dist2 } else { cx * cb + sx * sb };
    if cp <= b.cos_theta_e * dist2 {
        return 0.0;
    }
    let nv = v.dot(n);
    let ci = nv.abs();
    let si = (dist2 - nv * nv).max(0.0).sqrt();
    let cip = if ci > cb { dist2 } else { ci * cb + si * sb };
    let inv2 = dist2.recip();
    (scale * (cp * inv2) * (cip * inv2)).max(0.0)
}

/// A node of three lanes, each bounding random triangles in [−2, 2)³ (powers from 1 to 4): one
/// triangle, the union of two, the union of three; and a random receiver with its normal.
fn random_node(rng: &mut SmallRng) -> (WideNode, [NodeBounds; 3], Vec3, Vec3) {
    let mut v = || Vec3::new(rng.random(), rng.random(), rng.random()) * 4.0 - 2.0;
    let e: Vec<LightBounds> = (0..4)
        .map(|k| {
            let (c, a, b) = (v(), 0.3 * v(), 0.3 * v());
            let le = Vec3::splat(1.0 + k as f32);
            LightBounds::of(&Emitter::triangle(0, [c, c + a, c + b], le))
        })
        .collect();
    let lanes = [
        e[0],
        LightBounds::union(Some(e[0]), e[1]),
        LightBounds::union(Some(e[2]), LightBounds::union(Some(e[1]), e[3])),
    ]
    .map(|b| NodeBounds::of(&b));
    let mut node = WideNode::EMPTY;
    node.count = 3;
    for (i, b) in lanes.iter().enumerate() {
        node.set_lane(i, b);
    }
    let (p, n) = (v(), v().normalize_or(Vec3::Y));
    (node, lanes, p, n)
}

/// The four lanes of a collapsed node compute pbrt-v4's importance bound bit for bit as the
/// scalar [`scalar_importance`] does for each child alone (the same operations in the
/// same order; `sqrtps` rounds as `sqrtss`), zero included (behind a cone, inside a box),
/// and an unused lane has none. Random emitters and their unions, random receivers inside
/// and around them.
#[test]
fn a_nodes_lanes_are_the_scalar_importance() {
    let mut rng = SmallRng::seed_from_u64(7);
    let (mut zero, mut positive) = (0, 0);
    for _ in 0..2000 {
        let (node, lanes, p, n) = random_node(&mut rng);
        let wide = node.importance(p, n).to_array();
        for (i, b) in lanes.iter().enumerate() {
            let scalar = scalar_importance(b, p, n);
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

/// pbrt-v4's importance bound with its angles, in f64: `θ′ = max(θ_w − θ_o − θ_b, 0)` (the
/// direction from the box's centre to `p` against the normals' cone, less the angle the box's
/// bounding sphere subtends), zero unless `θ′ < θ_e`, times `cos max(θ_i − θ_b, 0)` at the
/// receiver, over `max(d², min_d2)`.
fn angle_importance(b: &NodeBounds, p: Vec3, n: Vec3) -> f64 {
    let v = (p - b.centre).as_dvec3();
    let d2 = v.length_squared();
    let wi = v / d2.sqrt();
    let theta_b = if d2 < (b.radius as f64).powi(2) {
        std::f64::consts::PI
    } else {
        (b.radius as f64 / d2.sqrt()).asin()
    };
    let theta_w = b.w.as_dvec3().dot(wi).clamp(-1.0, 1.0).acos();
    let theta_o = (b.cos_theta_o as f64).acos();
    let theta_p = (theta_w - theta_o - theta_b).max(0.0);
    if theta_p.cos() <= b.cos_theta_e as f64 {
        return 0.0;
    }
    let theta_i = n.as_dvec3().dot(wi).abs().clamp(0.0, 1.0).acos();
    b.phi as f64 * theta_p.cos() * (theta_i - theta_b).max(0.0).cos() / d2.max(b.min_d2 as f64)
}

/// The lanes' sines and cosines (lengths over the distance, no trigonometry) are the angles'
/// to f32 rounding: within 10⁻³ of the bound's scale `Φ / max(d², min_d2)`. The loosest term is
/// a sine from `√(d² − (w·v)²)` near θ_w = 0 or π, good to about √(10 ε) ≈ 10⁻³ (several
/// roundings in `d²` and `w·v`, and |w| ≠ 1 by an ulp); near 0 the clamp at θ_o removes it, and it
/// reaches the bound to first order only near θ_w = π with θ_o + θ_b ≥ π/2, where random
/// receivers rarely fall. Random emitters, unions and receivers as above, the receivers kept off
/// the boxes' centres (d > 10⁻³). It shares `NodeBounds::of` (centre, radius, `min_d2`) with the
/// code it checks, and every emitter here has θ_e = π/2, as every emitter of a scene does.
#[test]
fn a_nodes_lanes_are_pbrts_angles() {
    let mut rng = SmallRng::seed_from_u64(3);
    let mut checked = 0;
    for _ in 0..2000 {
        let (node, lanes, p, n) = random_node(&mut rng);
        let wide = node.importance(p, n).to_array();
        for (i, b) in lanes.iter().enumerate() {
            let d2 = (p - b.centre).length_squared() as f64;
            if d2 < 1e-6 {
                continue;
            }
            let scale = b.phi as f64 / d2.max(b.min_d2 as f64);
            let angles = angle_importance(b, p, n);
            assert!(
                (wide[i] as f64 - angles).abs() <= 1e-3 * scale,
                "lane {i}: {} against {angles} (scale {scale})",
                wide[i]
            );
            checked += (angles > 0.0) as u32;
        }
    }
    assert!(checked > 1000, "{checked} lanes of positive importance");
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

/// A degenerate emitter (three coinciding corners: no area, no power, no normal) gives no
/// importance, not NaN, even to a receiver at its point, where the bound is 0/0.
#[test]
fn a_powerless_point_has_no_importance() {
    let c = Vec3::new(0.5, 1.0, -2.0);
    let b = LightBounds::of(&Emitter::triangle(0, [c, c, c], Vec3::ONE));
    for p in [c, c + Vec3::X] {
        let i = b.importance(p, Vec3::Y);
        assert_eq!(i, 0.0, "{i} at {p}");
    }
}
