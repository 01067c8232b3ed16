//! Light sampling and MIS, piece by piece: the light selection pmf is proportional to power and
//! the sampler follows it (also with 10⁶ emitters); the light tree's pmf sums to 1 from any
//! point and is the frequency of its choices; points on a triangle are uniform by area; points by
//! solid angle and projected solid angle follow their pdfs (chi-square, for triangles and
//! rectangles seen frontally, at grazing angles and from close by), and the pdfs integrate to
//! 1; the per-solid-angle pdf integrates to the choice probability over the directions that
//! reach the light; and for every path both strategies can make, the light pdf and the BSDF
//! pdf that the two MIS weights use are the same two numbers, so the weights sum to 1 (all
//! direction strategies, every way of placing points and choosing lights).

use crate::common;

use glam::{Vec2, Vec3};
use rand::{rngs::SmallRng, Rng, SeedableRng};
use vrpt::bsdf::Directions;
use vrpt::integrator::mis_weight;
use vrpt::lights::{luminance, Chosen, Emitter, LightChoice, LightPoints, Lights};
use vrpt::math::Frame;
use vrpt::sampling::{sample_uniform_triangle, ONE_MINUS_EPSILON};
use vrpt::stats::{chi2_sf, pooled_chi2, sidak};

/// Family-wise α = 0.01 over the chi-square tests of this file: the power choice, the
/// triangle's area map, 4 tree receivers, and 2 shapes × 4 methods × 3 receivers of warps.
fn alpha() -> f64 {
    sidak(0.01, 2 + 4 + 24)
}

/// Every way of placing points on lights.
const POINTS: [LightPoints; 4] = [
    LightPoints::Area,
    LightPoints::SolidAngle,
    LightPoints::Projected,
    LightPoints::Auto,
];
/// Every way of choosing lights.
const CHOICES: [LightChoice; 3] = [LightChoice::Uniform, LightChoice::Power, LightChoice::Tree];

/// pmf(i) = π·Aᵢ·lum(Leᵢ) / Σ to one unit of 2⁻²⁴ (the choice's resolution, see
/// `vrpt::sampling::Discrete`), and 10⁶ choices with uniform `u` follow it
/// (chi-square over the 80 triangles of the glossy plates' four icosahedral lights, whose
/// radiances span 900× while their total powers are equal).
#[test]
fn light_choice_is_proportional_to_power() {
    let scene = common::shipped("glossy-plates");
    let lights = scene.lights.sampler(LightPoints::Area, LightChoice::Power);
    assert_eq!(scene.lights.len(), 80);
    let (p0, n0) = (Vec3::ZERO, Vec3::Y);
    let power: Vec<f64> = scene
        .lights
        .emitters
        .iter()
        .map(|t| std::f64::consts::PI * t.area as f64 * luminance(t.emission) as f64)
        .collect();
    let total: f64 = power.iter().sum();
    for (i, p) in power.iter().enumerate() {
        let pmf = lights.pmf(p0, n0, i as u32) as f64;
        assert!(
            (pmf - p / total).abs() <= 2f64.powi(-24),
            "light {i}: {pmf} against {}",
            p / total
        );
    }
    // the black environment is never chosen
    assert_eq!(lights.environment_pmf(), 0.0);
    // the four lights have equal power (Ke·r² is constant): each gets a quarter
    for l in 0..4 {
        let s: f64 = (0..20).map(|k| lights.pmf(p0, n0, l * 20 + k) as f64).sum();
        assert!((s - 0.25).abs() < 1e-4, "light {l}: {s}");
    }
    let n = 1_000_000;
    let mut rng = SmallRng::seed_from_u64(common::seed(1));
    let mut counts = vec![0f64; 80];
    for _ in 0..n {
        let Some((Chosen::Emitter(i), _)) = lights.choose(p0, n0, rng.random()) else {
            panic!("the environment is black: a triangle is chosen");
        };
        counts[i as usize] += 1.0;
    }
    let expected: Vec<f64> = (0..80)
        .map(|i| n as f64 * lights.pmf(p0, n0, i) as f64)
        .collect();
    let (stat, dof) = pooled_chi2(&counts, &expected);
    let p = chi2_sf(stat, dof as f64);
    eprintln!("light choice: chi2 {stat:.1} dof {dof} p {p:.3}");
    assert!(p > alpha(), "p = {p}");
}

/// Issue 24, with 10⁶ emitters: a million small emissive triangles whose powers span six
/// decades (random areas and radiances, an f32 CDF of them got frequencies several per cent off
/// the pmf). Every one of the 2²⁴ values a sampler's `u` can take on the choice's grid is fed
/// to `choose`: each light is chosen for exactly `pmf·2²⁴` of them (so the pmf that MIS and NEE
/// divide by is the frequency), every light can be chosen, and the pmf stays proportional to
/// power up to the units rounding (total variation below 2 units per light).
#[test]
fn light_pmf_is_the_frequency_of_every_choice_with_a_million_emitters() {
    use vrpt::material::Material;
    use vrpt::scene::{Mesh, MeshTriangle, Scene, SceneOptions};
    let n = 1_000_000usize;
    let mut rng = SmallRng::seed_from_u64(common::seed(11));
    let mut triangles = Vec::with_capacity(n);
    let mut materials = Vec::new();
    // 64 radiances over three decades, areas over three more
    for m in 0..64 {
        let le = 10f32.powf(3.0 * m as f32 / 63.0);
        materials.push(
            Material::new(
                &format!("e{m}"),
                Vec3::ZERO,
                Vec3::ZERO,
                1.0,
                Vec3::splat(le),
            )
            .0,
        );
    }
    let side = 1000usize;
    for k in 0..n {
        let (x, z) = ((k % side) as f32, (k / side) as f32);
        let s = 0.5 * 10f32.powf(-1.5 * rng.random::<f32>());
        triangles.push(MeshTriangle {
            p: [
                Vec3::new(x, 0.0, z),
                Vec3::new(x, 0.0, z + s),
                Vec3::new(x + s, 0.0, z),
            ],
            normals: None,
            uvs: None,
            material: rng.random_range(0..64),
        });
    }
    let scene = Scene::build(
        "inline".into(),
        Mesh { triangles },
        materials,
        SceneOptions::default(),
        Vec::new(),
    )
    .unwrap();
    assert_eq!(scene.lights.len(), n);
    let lights = scene.lights.sampler(LightPoints::Area, LightChoice::Power);
    let (p0, n0) = (Vec3::ZERO, Vec3::Y);
    let units = 1u32 << 24;
    let mut counts = vec![0u32; n];
    for k in 0..units {
        let Some((Chosen::Emitter(i), _)) = lights.choose(p0, n0, k as f32 / units as f32) else {
            panic!("the environment is black: a triangle is chosen");
        };
        counts[i as usize] += 1;
    }
    let power: Vec<f64> = scene
        .lights
        .emitters
        .iter()
        .map(|t| t.area as f64 * luminance(t.emission) as f64)
        .collect();
    let total: f64 = power.iter().sum();
    let mut tv = 0.0;
    for (i, &c) in counts.iter().enumerate() {
        let pmf = lights.pmf(p0, n0, i as u32) as f64;
        assert_eq!(
            c as f64,
            pmf * units as f64,
            "light {i}: chosen {c} times, pmf {pmf}"
        );
        assert!(c >= 1, "light {i} is never chosen");
        tv += (c as f64 - power[i] / total * units as f64).abs();
    }
    eprintln!(
        "{n} lights: total |units − ideal| = {tv:.0} ({:.2} per light)",
        tv / n as f64
    );
    assert!(tv <= 2.0 * n as f64, "total |units − ideal| = {tv}");
}

/// Points on a triangle, binned into the k² congruent sub-triangles of a regular subdivision
/// (equal areas, so each expects N/k²): a chi-square test of uniformity by area, for the
/// low-distortion warp. 400,000 points, k = 20 (1000 expected per bin).
#[test]
fn triangle_points_are_uniform_by_area() {
    let k = 20usize;
    let n = 400_000;
    let mut rng = SmallRng::seed_from_u64(common::seed(2));
    let mut counts = vec![0f64; 2 * k * k];
    for _ in 0..n {
        let b = sample_uniform_triangle(Vec2::new(rng.random(), rng.random()));
        let (b0, b1) = (b.x as f64, b.y as f64);
        assert!(b0 >= 0.0 && b1 >= 0.0 && b0 + b1 <= 1.0 + 1e-6);
        // cell (i, j) of the k×k grid in (b0, b1), split by its anti-diagonal into a lower and
        // an upper sub-triangle; the lower ones with i + j ≤ k − 1 and the upper ones with
        // i + j ≤ k − 2 tile the triangle (k² cells of area 1/(2k²) each)
        let (x, y) = (b0 * k as f64, b1 * k as f64);
        let (i, j) = ((x as usize).min(k - 1), (y as usize).min(k - 1));
        let upper = (x - i as f64) + (y - j as f64) > 1.0;
        counts[(i * k + j) * 2 + upper as usize] += 1.0;
    }
    let expected: Vec<f64> = (0..2 * k * k)
        .map(|c| {
            let (i, j, upper) = (c / 2 / k, c / 2 % k, c % 2 == 1);
            let inside = if upper { i + j + 2 <= k } else { i + j < k };
            if inside {
                n as f64 / (k * k) as f64
            } else {
                0.0 // a point here is outside the triangle: the statistic becomes infinite
            }
        })
        .collect();
    let (stat, dof) = pooled_chi2(&counts, &expected);
    let p = chi2_sf(stat, dof as f64);
    eprintln!("triangle points: chi2 {stat:.1} dof {dof} p {p:.3}");
    assert!(p > alpha(), "p = {p}");
}

/// An emitter in the plane z = 0 facing +z: a triangle, or a rectangle made of two triangles
/// (which `Lights::build` pairs into one emitter).
fn plane_light(rectangle: bool) -> (Lights, Vec<Vec3>) {
    let le = Vec3::splat(2.0);
    let corners = if rectangle {
        let (s, ex, ey) = (
            Vec3::new(-1.0, -0.7, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 1.4, 0.0),
        );
        vec![s, s + ex, s + ex + ey, s + ey]
    } else {
        vec![
            Vec3::new(-1.0, -0.8, 0.0),
            Vec3::new(1.2, -0.5, 0.0),
            Vec3::new(0.1, 1.0, 0.0),
        ]
    };
    let tris = if rectangle {
        vec![
            Emitter::triangle(0, [corners[0], corners[1], corners[2]], le),
            Emitter::triangle(1, [corners[0], corners[2], corners[3]], le),
        ]
    } else {
        vec![Emitter::triangle(
            0,
            [corners[0], corners[1], corners[2]],
            le,
        )]
    };
    let lights = Lights::build(tris, 2, Vec3::ZERO, 10.0).unwrap();
    assert_eq!(lights.len(), 1);
    (lights, corners)
}

/// Whether the ray `p + t w` meets the plane light of `corners` (convex, counter-clockwise
/// about +z), and where.
fn hit_plane_light(corners: &[Vec3], p: Vec3, w: Vec3) -> Option<Vec3> {
    let t = -p.z / w.z;
    if t.is_nan() || t <= 0.0 {
        return None;
    }
    let y = p + w * t;
    let inside = (0..corners.len()).all(|i| {
        let (a, b) = (corners[i], corners[(i + 1) % corners.len()]);
        (b - a).cross(y - a).z >= 0.0
    });
    inside.then_some(y)
}

/// The receivers of the warp tests: (name, point, normal). Frontal (2 above the light), grazing
/// (2.4° above its plane, 6 away: `cosθ_l` ≈ 0.04), close (0.2 above: the light fills most of
/// the hemisphere, 4–5 sr, still below the 6.22 sr where area sampling takes over).
fn receivers() -> [(&'static str, Vec3, Vec3); 3] {
    [
        (
            "frontal",
            Vec3::new(0.1, 0.2, 2.0),
            Vec3::new(0.2, 0.0, -1.0).normalize(),
        ),
        (
            "grazing",
            Vec3::new(6.0, 0.3, 0.25),
            Vec3::new(-1.0, 0.1, 0.3).normalize(),
        ),
        (
            "close",
            Vec3::new(0.1, 0.05, 0.2),
            Vec3::new(0.4, 0.0, -1.0).normalize(),
        ),
    ]
}

/// A chi-square test of points on the plane light of `corners` (3: a triangle, 4: a rectangle)
/// against their density per unit area `pdf_area`: bins tile the light exactly (the rectangle's
/// 40 × 40 grid in its edge coordinates, or the triangle's 20² congruent sub-triangles), each
/// expecting N ∫_bin pdf_A dA by a 4 × 4 (rectangle) or 16-point (triangle) midpoint rule, plus
/// a bin for failed samples expecting N (1 − ∫ pdf_A dA). Returns (p-value, ∫ pdf_A dA, failed).
fn chi2_on_light(
    corners: &[Vec3],
    mut sample: impl FnMut() -> Option<Vec3>,
    pdf_area: impl Fn(Vec3) -> f64,
    n: usize,
) -> (f64, f64, usize) {
    let rectangle = corners.len() == 4;
    let (k, q) = if rectangle {
        (40usize, 4usize)
    } else {
        (20, 4)
    };
    let bins = if rectangle { k * k } else { 2 * k * k };
    let v0 = corners[0];
    let (e1, e2) = if rectangle {
        (corners[1] - v0, corners[3] - v0)
    } else {
        (corners[1] - v0, corners[2] - v0)
    };
    // (a, b): y = v0 + a e1 + b e2
    let coords = |y: Vec3| {
        let d = y - v0;
        let (g11, g12, g22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (r1, r2) = (d.dot(e1), d.dot(e2));
        let det = g11 * g22 - g12 * g12;
        ((r1 * g22 - r2 * g12) / det, (r2 * g11 - r1 * g12) / det)
    };
    let at = |a: f64, b: f64| v0 + e1 * a as f32 + e2 * b as f32;
    let bin_of = |a: f32, b: f32| -> usize {
        let (x, y) = (a as f64 * k as f64, b as f64 * k as f64);
        let (i, j) = (
            (x.max(0.0) as usize).min(k - 1),
            (y.max(0.0) as usize).min(k - 1),
        );
        if rectangle {
            i * k + j
        } else {
            let upper = (x - i as f64) + (y - j as f64) > 1.0;
            (i * k + j) * 2 + upper as usize
        }
    };
    let mut observed = vec![0f64; bins + 1];
    for _ in 0..n {
        match sample() {
            None => observed[bins] += 1.0,
            Some(y) => {
                let (a, b) = coords(y);
                observed[bin_of(a, b)] += 1.0;
            }
        }
    }
    let area = e1.cross(e2).length() as f64 * if rectangle { 1.0 } else { 0.5 };
    let mut expected = vec![0f64; bins + 1];
    for (c, e) in expected.iter_mut().enumerate().take(bins) {
        let (i, j, upper) = if rectangle {
            (c / k, c % k, false)
        } else {
            (c / 2 / k, c / 2 % k, c % 2 == 1)
        };
        if !rectangle && !(if upper { i + j + 2 <= k } else { i + j < k }) {
            continue; // outside the triangle
        }
        let (mut sum, mut m) = (0.0, 0usize);
        for s in 0..q {
            for t in 0..q {
                let (mut x, mut y) = ((s as f64 + 0.5) / q as f64, (t as f64 + 0.5) / q as f64);
                if !rectangle {
                    // fold the unit cell's points into its lower or upper half
                    let lower = x + y < 1.0;
                    if lower == upper {
                        (x, y) = (1.0 - x, 1.0 - y);
                    }
                }
                sum += pdf_area(at((i as f64 + x) / k as f64, (j as f64 + y) / k as f64));
                m += 1;
            }
        }
        // a cell of the rectangle and a half cell of the triangle both cover area / k²
        *e = sum / m as f64 * area / (k * k) as f64;
    }
    let integral: f64 = expected[..bins].iter().sum();
    expected[bins] = (1.0 - integral).max(0.0);
    for e in &mut expected {
        *e *= n as f64;
    }
    let (stat, dof) = pooled_chi2(&observed, &expected);
    (chi2_sf(stat, dof as f64), integral, observed[bins] as usize)
}

/// Points on a triangle and on a rectangle, by area, by solid angle and by projected solid
/// angle, seen from the three receivers: the points follow the pdf the sampler reports for them
/// (converted to a density per unit area, `p_A = p_ω cosθ_l/d²`; chi-square binned on the light,
/// 200,000 samples, ~125 expected per bin), and that density integrates to 1 over the light
/// (1%). A pdf 5% off fails: the last checks scale the projected pdf by 1.05 and must be
/// rejected.
#[test]
fn light_points_follow_their_pdfs() {
    let mut k = 0u64;
    let mut run =
        |name: &str, rectangle: bool, points: LightPoints, r: (&str, Vec3, Vec3), scale: f64| {
            let (lights, corners) = plane_light(rectangle);
            let sampler = lights.sampler(points, LightChoice::Tree);
            let (_, p, n) = r;
            k += 1;
            let mut rng = SmallRng::seed_from_u64(common::seed(100 + k));
            let nl = Vec3::Z;
            let (pv, integral, failed) = chi2_on_light(
                &corners,
                || {
                    let u = Vec2::new(rng.random(), rng.random());
                    sampler.sample(p, n, 0.5, u).map(|ls| p + ls.wi * ls.dist)
                },
                |y| {
                    let d = y - p;
                    let cos_l = nl.dot(-d).max(0.0) / d.length();
                    scale * sampler.pdf(0, p, n, y) as f64 * cos_l as f64
                        / d.length_squared() as f64
                },
                200_000,
            );
            eprintln!("{name}: p {pv:.3e}, ∫pdf {integral:.4}, failed {failed}");
            (pv, integral, failed)
        };
    for rectangle in [false, true] {
        for points in POINTS {
            for r in receivers() {
                let name = format!(
                    "{} {points} {}",
                    if rectangle { "rectangle" } else { "triangle" },
                    r.0
                );
                let (pv, integral, failed) = run(&name, rectangle, points, r, 1.0);
                assert!(pv > alpha(), "{name}: p = {pv}");
                assert!((integral - 1.0).abs() < 0.01, "{name}: ∫pdf = {integral}");
                assert_eq!(failed, 0, "{name}");
            }
        }
    }
    // power: a projected pdf 5% too high fails, frontally and from close by, on either shape
    for rectangle in [false, true] {
        for r in [receivers()[0], receivers()[2]] {
            let (pv, _, _) = run(
                "projected ×1.05",
                rectangle,
                LightPoints::Projected,
                r,
                1.05,
            );
            assert!(pv < 1e-6, "{}: a 5% pdf error passed (p = {pv})", r.0);
        }
    }
}

/// The solid angle that the spherical methods divide by is the light's: the directions that
/// meet the light, integrated by a 700×700 midpoint grid over a cap that holds it (error from
/// the outline's cells, below 0.5%), equal 1/pdf of the solid-angle method, for both shapes and
/// the three receivers.
#[test]
fn the_solid_angle_is_the_lights() {
    for rectangle in [false, true] {
        let (lights, corners) = plane_light(rectangle);
        let sampler = lights.sampler(LightPoints::SolidAngle, LightChoice::Tree);
        for (name, p, n) in receivers() {
            let centre = corners.iter().sum::<Vec3>() / corners.len() as f32;
            let axis = (centre - p).normalize();
            let cos_max = corners
                .iter()
                .map(|c| (*c - p).normalize().dot(axis))
                .fold(1.0f32, f32::min) as f64
                - 1e-3;
            let frame = Frame::from_normal(axis);
            let m = 700usize;
            let (dz, dphi) = (
                (1.0 - cos_max) / m as f64,
                2.0 * std::f64::consts::PI / m as f64,
            );
            let mut omega = 0.0f64;
            let mut inv_pdf = 0.0f64;
            for a in 0..m {
                let z = cos_max + (a as f64 + 0.5) * dz;
                let r = (1.0 - z * z).sqrt();
                for b in 0..m {
                    let phi = (b as f64 + 0.5) * dphi;
                    let w = frame.to_world(Vec3::new(
                        (r * phi.cos()) as f32,
                        (r * phi.sin()) as f32,
                        z as f32,
                    ));
                    if let Some(y) = hit_plane_light(&corners, p, w) {
                        omega += dz * dphi;
                        inv_pdf = 1.0 / sampler.pdf(0, p, n, y) as f64;
                    }
                }
            }
            eprintln!("{name}: Ω by quadrature {omega:.5}, 1/pdf {inv_pdf:.5}");
            assert!(
                (omega - inv_pdf).abs() < 5e-3 * omega,
                "{name}: Ω {omega} against 1/pdf {inv_pdf}"
            );
        }
    }
}

/// A town at night for the light tree: 300 rectangular lamps of random sizes (0.1–2), powers
/// (over three decades) and orientations, in a 100 × 100 square, and a dim sky.
fn town() -> Lights {
    let mut rng = SmallRng::seed_from_u64(common::seed(77));
    let mut tris = Vec::new();
    for k in 0..300u32 {
        let c = Vec3::new(
            rng.random_range(-50.0..50.0),
            rng.random_range(0.0..10.0),
            rng.random_range(-50.0..50.0),
        );
        let normal = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize();
        let f = Frame::from_normal(normal);
        let (w, h) = (rng.random_range(0.1..2.0), rng.random_range(0.1..2.0));
        let (ex, ey) = (f.s * w, f.t * h);
        let s = c - 0.5 * (ex + ey);
        let le = Vec3::splat(10f32.powf(rng.random_range(0.0..3.0)));
        // counter-clockwise about `normal`: s, s + ex, s + ex + ey, s + ey (f.s × f.t = normal)
        tris.push(Emitter::triangle(2 * k, [s, s + ex, s + ex + ey], le));
        tris.push(Emitter::triangle(2 * k + 1, [s, s + ex + ey, s + ey], le));
    }
    let lights = Lights::build(tris, 600, Vec3::splat(0.002), 80.0).unwrap();
    assert_eq!(lights.len(), 300, "every lamp is one rectangle");
    lights
}

/// The light tree's pmf from a receiving point: the pmfs of all lights and the sky, and the
/// share of choices that find no light, sum to 1 exactly (whole units of 2⁻²⁴; the descent can
/// reach a node whose merged cone admitted the point while neither child's does, as in pbrt-v4,
/// and those lamps face away: the sample is lost, not biased), and 10⁶ choices with uniform `u`
/// from that point follow them, "no light" included (chi-square, pooled bins), from four
/// receivers of the town. The tree gives most of the choices to lamps near the receiver.
#[test]
fn the_light_trees_pmf_is_the_frequency_of_its_choices() {
    let lights = town();
    let tree = lights.sampler(LightPoints::Area, LightChoice::Tree);
    let mut rng = SmallRng::seed_from_u64(common::seed(78));
    for r in 0..4 {
        let p = Vec3::new(
            rng.random_range(-40.0..40.0),
            0.0,
            rng.random_range(-40.0..40.0),
        );
        let n = Vec3::new(
            rng.random_range(-0.3..0.3),
            1.0,
            rng.random_range(-0.3..0.3),
        )
        .normalize();
        let pmf: Vec<f32> = (0..300).map(|i| tree.pmf(p, n, i)).collect();
        let total: f32 = pmf.iter().sum::<f32>() + tree.environment_pmf();
        assert!(
            total <= 1.0 && total > 0.5,
            "receiver {r}: the pmfs sum to {total}"
        );
        // the units that find no light: those are a whole number too
        let none = 1.0 - total;
        assert_eq!(
            none * (1u32 << 24) as f32,
            (none * (1u32 << 24) as f32).round()
        );
        let draws = 1_000_000;
        let mut counts = vec![0f64; 302];
        for _ in 0..draws {
            match tree.choose(p, n, rng.random()) {
                Some((Chosen::Emitter(i), q)) => {
                    assert_eq!(q, pmf[i as usize]);
                    counts[i as usize] += 1.0;
                }
                Some((Chosen::Environment, _)) => counts[300] += 1.0,
                None => counts[301] += 1.0,
            }
        }
        let mut expected: Vec<f64> = pmf.iter().map(|&q| q as f64 * draws as f64).collect();
        expected.push(tree.environment_pmf() as f64 * draws as f64);
        expected.push(none as f64 * draws as f64);
        let (stat, dof) = pooled_chi2(&counts, &expected);
        let pv = chi2_sf(stat, dof as f64);
        let mut top: Vec<f32> = pmf.clone();
        top.sort_by(|a, b| b.total_cmp(a));
        eprintln!(
            "receiver {r}: chi2 {stat:.1} dof {dof} p {pv:.3}; largest pmfs {:.3?}, zero pmfs {}, \
             no light {none:.4}",
            &top[..4],
            pmf.iter().filter(|&&q| q == 0.0).count()
        );
        assert!(pv > alpha(), "receiver {r}: p = {pv}");
    }
}

/// Every light pdf, integrated numerically over the directions from a point that reach the
/// light, gives the probability of choosing the light (1 for the Cornell box's only light, a
/// rectangle, seen from the floor), for each way of placing points: `area` (`p_A d²/cosθ_l`),
/// `solid-angle` (`1/Ω`) and `projected` (the bilinear cosine warp over `1/Ω`, here with the
/// floor's normal). The point (front right of the floor, where neither box is in the way) sees
/// the light obliquely, `cosθ_l` in 0.81–0.92 (measured), so an area pdf missing its cosine
/// would integrate to ~1.16. Quadrature: an 800×800 midpoint grid in (cos α, φ) over a cap about
/// the direction to the light that holds it; the error comes from the cells cut by the light's
/// outline (~4·800 of the ~3·10⁵ cells inside), about 1%: the bound is 2%.
#[test]
fn light_pdfs_integrate_to_the_light_choice() {
    let scene = common::shipped("cornell-box");
    assert_eq!(
        scene.lights.len(),
        1,
        "the light's two triangles are one rectangle"
    );
    let p = Vec3::new(500.0, 0.1, 50.0); // front right of the floor: no box in the way
    let n = Vec3::Y;
    let vertices: Vec<Vec3> = scene
        .accel
        .order
        .iter()
        .enumerate()
        .filter(|(k, _)| scene.lights.light_of(*k as u32).is_some())
        .flat_map(|(k, _)| scene.accel.vertices(k as u32))
        .collect();
    let centre = vertices.iter().sum::<Vec3>() / vertices.len() as f32;
    let axis = (centre - p).normalize();
    // the cap: every light vertex lies inside it
    let cos_max = vertices
        .iter()
        .map(|v| (*v - p).normalize().dot(axis))
        .fold(1.0f32, f32::min) as f64
        - 1e-3;
    let frame = Frame::from_normal(axis);
    let m = 800usize;
    let (dz, dphi) = (
        (1.0 - cos_max) / m as f64,
        2.0 * std::f64::consts::PI / m as f64,
    );
    let samplers = POINTS.map(|pts| scene.lights.sampler(pts, LightChoice::Tree));
    let mut integral = [0.0f64; POINTS.len()];
    let mut cos_l_range = (1.0f32, 0.0f32);
    for a in 0..m {
        let z = cos_max + (a as f64 + 0.5) * dz;
        let r = (1.0 - z * z).sqrt();
        for b in 0..m {
            let phi = (b as f64 + 0.5) * dphi;
            let w = frame
                .to_world(Vec3::new(
                    (r * phi.cos()) as f32,
                    (r * phi.sin()) as f32,
                    z as f32,
                ))
                .normalize();
            if let Some(hit) = scene.accel.intersect(p, w, f32::INFINITY) {
                if let Some(i) = scene.lights.light_of(hit.prim) {
                    let y = p + w * hit.t;
                    for (k, s) in samplers.iter().enumerate() {
                        integral[k] += s.pdf(i, p, n, y) as f64 * dz * dphi;
                    }
                    let c = -scene.lights.emitters[i as usize].n.dot(w);
                    cos_l_range = (cos_l_range.0.min(c), cos_l_range.1.max(c));
                }
            }
        }
    }
    eprintln!(
        "∫ p_ω dω = {integral:.5?} (area, solid angle, projected, auto); cosθ_l in {cos_l_range:?}"
    );
    assert!(
        cos_l_range.1 < 0.95,
        "the test point must see the light obliquely"
    );
    for (k, v) in integral.iter().enumerate() {
        assert!((v - 1.0).abs() < 0.02, "{}: ∫ p_ω dω = {v}", POINTS[k]);
    }
}

/// For random vertices of the Cornell box (floor, walls, boxes) and random outgoing
/// directions: every light sample that reaches the light unoccluded is a path the BSDF could
/// also have sampled. The light pdf that a BSDF-sampled ray hitting that point would be
/// weighted with (computed from the hit, as the integrator does) equals the light sample's own
/// pdf, and the BSDF pdf the light sample is weighted with equals what `Bsdf::sample` reports
/// for that direction, so `w_light + w_bsdf = 1` — for each direction strategy, each way of
/// placing points and each way of choosing lights.
#[test]
fn mis_weights_of_both_strategies_sum_to_one() {
    let scene = common::shipped("cornell-box");
    let mut rng = SmallRng::seed_from_u64(common::seed(3));
    let mut checked = [[0usize; 3]; 12];
    let cam = vrpt::camera::Camera::new(&scene.camera, 64, 64).unwrap();
    let samplers: Vec<_> = POINTS
        .iter()
        .flat_map(|&p| CHOICES.map(|c| scene.lights.sampler(p, c)))
        .collect();
    for _ in 0..6_000 {
        let px = glam::UVec2::new(rng.random_range(0..64), rng.random_range(0..64));
        let (o, d) = cam.generate_ray(px, Vec2::new(rng.random(), rng.random()));
        let Some(hit) = scene.accel.intersect(o, d, f32::INFINITY) else {
            continue;
        };
        let s = scene.surface(&hit);
        let bsdf = scene.bsdf_at(&s);
        if bsdf.is_black() {
            continue;
        }
        let wo = -d;
        let (ng, ns) = if s.ng.dot(wo) > 0.0 {
            (s.ng, s.ns)
        } else {
            (-s.ng, -s.ns)
        };
        let frame = Frame::from_normal(ns);
        let wo_local = frame.to_local(wo);
        for (m, lights) in samplers.iter().enumerate() {
            let u = (rng.random(), Vec2::new(rng.random(), rng.random()));
            let Some(ls) = lights.sample(s.p, ns, u.0, u.1) else {
                continue;
            };
            let wi_local = frame.to_local(ls.wi);
            if ls.wi.dot(ng) <= 0.0 || wi_local.z <= 0.0 {
                continue;
            }
            let origin = s.p + ng * scene.ray_epsilon;
            let Some(h2) = scene.accel.intersect(origin, ls.wi, f32::INFINITY) else {
                continue;
            };
            let Some(light) = scene.lights.light_of(h2.prim) else {
                continue; // occluded: no path
            };
            let y = scene.surface(&h2).p;
            let p_light_at_hit = lights.pdf(light, s.p, ns, y);
            // The ray leaves from the offset origin (ε along the normal), as in the integrator,
            // so it meets the light up to ~ε/cosθ_l from the sampled point: a relative pdf change
            // of ~ε/(d cosθ_l), large only at grazing angles (measured 0.4% at cosθ_l ~ 1e-3),
            // where the weight sum moves by at most half of it. The projected pdf goes through
            // the inverse map, exact to ~1e-6 in u.
            let cos_l = -scene.lights.emitters[light as usize].n.dot(ls.wi);
            let tolerance = 1e-3 + 4.0 * scene.ray_epsilon / (ls.dist * cos_l);
            assert!(
                (p_light_at_hit - ls.pdf).abs() <= tolerance * ls.pdf,
                "{lights:?}: light pdf {} from the hit vs {} from the sample (cosθ_l {cos_l})",
                p_light_at_hit,
                ls.pdf
            );
            for (k, dirs) in [Directions::Uniform, Directions::Cosine, Directions::Phong]
                .into_iter()
                .enumerate()
            {
                let p_bsdf = bsdf.pdf(wo_local, wi_local, dirs);
                if p_bsdf <= 0.0 {
                    continue;
                }
                let sum = mis_weight(ls.pdf, p_bsdf) + mis_weight(p_bsdf, p_light_at_hit);
                assert!(
                    (sum - 1.0).abs() <= 1e-4 + 0.5 * tolerance,
                    "{lights:?} {dirs}: weights sum to {sum}"
                );
                checked[m][k] += 1;
            }
        }
    }
    eprintln!("paths checked per (points, choice) and direction strategy: {checked:?}");
    assert!(checked.iter().flatten().all(|&c| c > 1000), "{checked:?}");
}

/// Veach's picture on the shipped glossy plates, in numbers: per plate × light region (the
/// scene's regions.txt, halved with the image to 128×96), at equal spp (16, 8 runs), against
/// a 1024-spp MIS reference:
/// - BSDF sampling beats light sampling (asserted: by 10×) on the sharpest plate with the
///   largest light (measured here: 5.9e-4 against 7.1, a factor of 10⁴);
/// - light sampling beats BSDF sampling (asserted: by 10×) on the roughest plate with the
///   smallest light (0.030 against 15.8, a factor of 500);
/// - MIS is within 1.3× of the better of the two in every region (measured: at most 1.03×;
///   where nee is the better, nee and mis share their light samples — same seeds, same
///   dimensions — so their MSEs are strongly correlated and the ratio is stable; where BSDF
///   sampling is the better, mis measured 0.6–1.03× of it).
///
/// The 1024-spp reference adds its own variance to every MSE (1/64 of MIS's at 16 spp), which
/// can only pull ratios toward 1.
#[test]
fn veach_picture_on_the_glossy_plates() {
    use vrpt::analysis::experiments::{compare, ExperimentSettings};
    use vrpt::analysis::metrics::Region;
    use vrpt::render::NoProgress;
    use vrpt::strategy::Strategy;
    let scene = common::shipped("glossy-plates");
    let text =
        std::fs::read_to_string(common::shipped_path("glossy-plates").join("regions.txt")).unwrap();
    let regions: Vec<Region> = Region::parse_list(&text)
        .unwrap()
        .into_iter()
        .map(|r| Region {
            x: r.x / 2,
            y: r.y / 2,
            w: r.w / 2,
            h: r.h / 2,
            ..r
        })
        .collect();
    assert_eq!(regions.len(), 16);
    let (w, h, depth) = (128, 96, 4);
    let reference = common::as_image(
        &scene,
        &vrpt::render::RenderSettings {
            width: w,
            height: h,
            spp: 1024,
            max_depth: depth,
            seed: common::seed(999),
            ..Default::default()
        },
    );
    let strategies: Vec<Strategy> = ["stratified+phong+bsdf", "stratified+phong+nee", "mis"]
        .iter()
        .map(|s| Strategy::parse(s).unwrap())
        .collect();
    let settings = ExperimentSettings {
        regions: regions.clone(),
        ..common::experiment_settings(w, h, depth, 8)
    };
    let c = compare(
        &scene,
        &reference,
        &strategies,
        16,
        None,
        &settings,
        &NoProgress,
    )
    .unwrap();
    eprint!("{}", c.table());
    let mse = |strategy: usize, region: &str| {
        let k = regions.iter().position(|r| r.name == region).unwrap();
        c.regions[strategy * regions.len() + k].mse
    };
    let (bsdf, nee, mis) = (0, 1, 2);
    assert!(
        mse(bsdf, "p10000-l3") * 10.0 < mse(nee, "p10000-l3"),
        "sharpest plate, largest light: bsdf {} nee {}",
        mse(bsdf, "p10000-l3"),
        mse(nee, "p10000-l3")
    );
    assert!(
        mse(nee, "p10-l0") * 10.0 < mse(bsdf, "p10-l0"),
        "roughest plate, smallest light: nee {} bsdf {}",
        mse(nee, "p10-l0"),
        mse(bsdf, "p10-l0")
    );
    for r in &regions {
        let best = mse(bsdf, &r.name).min(mse(nee, &r.name));
        let m = mse(mis, &r.name);
        assert!(
            m <= 1.3 * best,
            "{}: mis {m} against the better {best}",
            r.name
        );
    }
}

/// Second review (issue 34): pairing emissive triangles into rectangles is linear in the
/// triangles, however many share an edge. 100,000 coplanar triangles fanned around one edge
/// (same emission and normal, so every pair passes the cheap tests): trying every pair, as
/// before, is 5·10⁹ attempts (20,000 of them already added 5 s to a load), so this test would
/// not finish; now each triangle tries at most `PAIR_CANDIDATES` per edge. None of them makes a
/// rectangle with another; a real rectangle beside the fan still pairs.
#[test]
fn pairing_rectangles_is_linear_in_a_fan_of_emitters() {
    let n = 100_000u32;
    let le = Vec3::splat(2.0);
    let mut tris: Vec<Emitter> = (0..n)
        .map(|k| {
            let y = 0.1 + k as f32 * 1e-4;
            let v = [
                Vec3::ZERO,
                Vec3::X,
                Vec3::new(0.3 + 0.4 * (k % 7) as f32 / 7.0, y, 0.0),
            ];
            Emitter::triangle(k, v, le)
        })
        .collect();
    // a unit square at z = 1, its two halves sharing the diagonal (0,0)-(1,1)
    let s = [
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(0.0, 1.0, 1.0),
    ];
    tris.push(Emitter::triangle(n, [s[0], s[1], s[2]], le));
    tris.push(Emitter::triangle(n + 1, [s[0], s[2], s[3]], le));
    let lights = Lights::build(tris, n as usize + 2, Vec3::ZERO, 10.0).unwrap();
    assert_eq!(
        lights.len(),
        n as usize + 1,
        "the fan stays triangles, the square pairs"
    );
}

/// Second review (issue 34, suspected by reading): a light's path in the tree is stored as one
/// bit per level in a u64, so a tree deeper than 64 levels made deep lights' paths collide and
/// their pmf (what MIS weighs with) disagree with their choice. A thousand lights spaced
/// geometrically along a line (x = 10 + 1.035^k, brighter with k) make the SAOH split peel
/// about one light per level down to depth 48, where splits go by count; the 70,000 lights
/// clustered at the origin are then split by count, 17 levels more (65 in all before the fix).
/// The tree must stay within
/// the trail's 64 bits (since the tree has four children a node, two bits a level of half as
/// many levels), and for receivers near the cluster every unit `k` chooses a light whose pmf,
/// followed along its own path, gives exactly the units the choice reported.
#[test]
fn a_deep_light_tree_keeps_every_lights_path() {
    use vrpt::lights::LightTree;
    let tri = |k: u32, c: Vec3, s: f32, le: f32| {
        let v = [c, c + Vec3::new(s, 0.0, 0.0), c + Vec3::new(0.0, 0.0, s)];
        Emitter::triangle(k, v, Vec3::splat(le))
    };
    let mut emitters: Vec<Emitter> = (0..1000u32)
        .map(|k| {
            let x = 10.0 + 1.035f32.powi(k as i32);
            tri(k, Vec3::new(x, 1.0, 0.0), 1e-3 * x, 1.0 + k as f32)
        })
        .collect();
    let side = 264u32;
    for j in 0..70_000u32 {
        let c = Vec3::new(
            (j % side) as f32 / side as f32,
            1.0,
            (j / side) as f32 / side as f32,
        );
        emitters.push(tri(1000 + j, c, 1e-3, 1.0));
    }
    let tree = LightTree::build(&emitters);
    // the binary build is about 60 levels deep; collapsed, two of them make one level of
    // four ways, two bits of the trail each
    assert!(
        tree.depth() >= 28,
        "the test needs a deep tree: depth {}",
        tree.depth()
    );
    assert!(
        tree.depth() <= 32,
        "depth {}: past the trail's 64 bits",
        tree.depth()
    );
    let units = 1u32 << 24;
    let mut checked = 0;
    for p in [Vec3::new(0.5, 0.0, 0.5), Vec3::new(0.1, 0.5, 0.9)] {
        let n = Vec3::Y;
        for j in 0..50_000u32 {
            let k = (j as u64 * units as u64 / 50_000) as u32;
            if let Some((i, got)) = tree.choose(p, n, k, 0..units) {
                assert_eq!(tree.units(p, n, i, 0..units), got, "light {i} from {p}");
                checked += 1;
            }
        }
    }
    assert!(checked > 50_000);
}

/// Where one light has power, every chooser picks it (with the same pmf) whatever the choice's
/// value, so a path does not draw that value (`LightSampler::chooses` false, the image the
/// same bits: `tools/same_images.py`); with two lights, or a tree over two emitters of which
/// one has no power, the value is drawn. Checked at every receiver of a grid against the
/// choice at `u = 0` (what a path that skips the value passes), for values at both ends of
/// every unit range a chooser could split at (`u` over 2¹² steps and next to 1).
#[test]
fn one_light_is_chosen_whatever_the_value() {
    let le = Vec3::splat(2.0);
    let tri = |i: u32, z: f32, le: Vec3| {
        let c = [
            Vec3::new(-1.0, -1.0, z),
            Vec3::new(1.0, -1.0, z),
            Vec3::new(0.0, 1.0, z),
        ];
        Emitter::triangle(i, c, le)
    };
    let cases = [
        ("one emitter", vec![tri(0, 0.0, le)], Vec3::ZERO, false),
        ("the sky alone", vec![], Vec3::splat(0.5), false),
        (
            "a dark emitter and the sky",
            vec![tri(0, 0.0, Vec3::ZERO)],
            Vec3::splat(0.5),
            false,
        ),
        (
            "an emitter and the sky",
            vec![tri(0, 0.0, le)],
            Vec3::splat(0.5),
            true,
        ),
        (
            "two emitters",
            vec![tri(0, 0.0, le), tri(1, 0.5, le)],
            Vec3::ZERO,
            true,
        ),
    ];
    let us: Vec<f32> = (0..4096)
        .map(|k| k as f32 / 4096.0)
        .chain([ONE_MINUS_EPSILON])
        .collect();
    for (name, tris, sky, chooses) in cases {
        let lights = Lights::build(tris, 2, sky, 10.0).unwrap();
        for choice in [LightChoice::Tree, LightChoice::Power, LightChoice::Uniform] {
            let s = lights.sampler(LightPoints::SolidAngle, choice);
            assert_eq!(s.chooses(), chooses, "{name}, {choice:?}");
            if chooses {
                continue;
            }
            for (x, y) in (0..5).flat_map(|x| (0..5).map(move |y| (x, y))) {
                let p = Vec3::new(x as f32 - 2.0, y as f32 - 2.0, 1.5);
                let n = Vec3::new(0.1 * x as f32, 0.2, -1.0).normalize();
                let at_zero = s.choose(p, n, 0.0);
                for &u in &us {
                    assert_eq!(s.choose(p, n, u), at_zero, "{name}, {choice:?}, u {u}");
                }
            }
        }
    }
}
