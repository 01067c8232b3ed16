//! The HDR environment map (issue 23): its sampling against its pdf (chi-square, texel by texel,
//! on the shipped sky and on a map with one bright pixel; and the generic direction harness on
//! a smooth map), its pdf integrating to 1, a constant white map rendering as the white furnace
//! of `radiance = [1, 1, 1]`, and region z-tests of next-event estimation and MIS with the map
//! on the shipped sun-sky scene.
//!
//! Significance: the chi-square tests of this file are held at family-wise α = 0.01 (Šidák),
//! the z-tests at family-wise 10⁻³; seeds come from `VRPT_TEST_SEED` (`common::seed`).

use crate::common;

use common::{icosphere_obj, write};
use glam::{Vec2, Vec3};
use rand::{rngs::SmallRng, Rng, SeedableRng};
use vrpt::environment::{EnvMap, Environment};
use vrpt::image_io::{write_exr, RgbImage};
use vrpt::render::RenderSettings;
use vrpt::stats::{
    chi2_directions, chi2_sf, normal_critical_value, pooled_chi2, sidak, Chi2Binning,
};
use vrpt::strategy::Strategy;

/// Chi-square tests in this file: two texel-binned maps, one smooth map in the direction
/// harness.
const CHI2_TESTS: usize = 3;

/// The map's samples binned by texel against the mass its pdf gives each texel, `∫ pdf dω`
/// over the texel by a 6×6 midpoint rule in (cos θ, φ) — a different parametrization from
/// the sampler's (u, v), so a wrong sin θ in the pdf's conversion to solid angle shows. Returns
/// (p-value, ∫ pdf over the sphere).
fn texel_chi2(m: &EnvMap, n: usize, seed: u64) -> (f64, f64) {
    let (w, h) = m.size();
    let (w, h) = (w as usize, h as usize);
    let texel = |d: Vec3| {
        let uv = m.uv(d);
        let x = ((uv.x * w as f32) as usize).min(w - 1);
        let y = ((uv.y * h as f32) as usize).min(h - 1);
        y * w + x
    };
    let mut observed = vec![0.0f64; w * h + 1];
    let mut u = common::uniform_pairs(common::seed(seed));
    for _ in 0..n {
        match m.sample(u()) {
            Some((d, _, _)) => observed[texel(d)] += 1.0,
            None => observed[w * h] += 1.0,
        }
    }
    // texel (x, y) spans φ ∈ 2π(x/w − ½) .. and θ ∈ π y/h ..; in the map's own frame, which
    // `direction` maps to the world (the rotation is a rotation: dω is unchanged)
    let k = 6;
    let mut expected = vec![0.0f64; w * h + 1];
    let pi = std::f64::consts::PI;
    for y in 0..h {
        let (z0, z1) = (
            (pi * y as f64 / h as f64).cos(),
            (pi * (y + 1) as f64 / h as f64).cos(),
        );
        for x in 0..w {
            let (p0, p1) = (
                2.0 * pi * x as f64 / w as f64,
                2.0 * pi * (x + 1) as f64 / w as f64,
            );
            let mut s = 0.0;
            for a in 0..k {
                for b in 0..k {
                    let z = z0 + (z1 - z0) * (a as f64 + 0.5) / k as f64;
                    let phi = p0 + (p1 - p0) * (b as f64 + 0.5) / k as f64;
                    // back to the map point: u = φ/2π, v = θ/π
                    let uv = Vec2::new((phi / (2.0 * pi)) as f32, (z.acos() / pi) as f32);
                    s += m.pdf(m.direction(uv)) as f64;
                }
            }
            expected[y * w + x] = s * (z0 - z1) * (p1 - p0) / (k * k) as f64;
        }
    }
    let integral: f64 = expected.iter().sum();
    for e in &mut expected {
        *e *= n as f64;
    }
    let (stat, dof) = pooled_chi2(&observed, &expected);
    (chi2_sf(stat, dof as f64), integral)
}

fn check(name: &str, (p, integral): (f64, f64)) {
    eprintln!("{name}: p {p:.4}, ∫pdf dω {integral:.6}");
    assert!(p > sidak(0.01, CHI2_TESTS), "{name}: p = {p}");
    assert!(
        (integral - 1.0).abs() < 2e-3,
        "{name}: ∫pdf dω = {integral}"
    );
}

/// The shipped sky (a 1.5° sun carrying most of the luminance) and a map whose light is one
/// pixel, turned by 40° (the rotation must not change the distribution over texels).
#[test]
fn map_sampling_fits_its_pdf_texel_by_texel() {
    let scene = common::shipped("sun-sky");
    let sky = scene.environment().map().expect("sun-sky is lit by a map");
    check("shipped sky", texel_chi2(sky, 1_000_000, 1));
    let mut px = vec![Vec3::splat(0.01); 32 * 16];
    px[5 * 32 + 20] = Vec3::new(1000.0, 800.0, 600.0);
    let one = EnvMap::new(32, 16, &px, 40.0, 1.0).unwrap();
    check("one bright pixel", texel_chi2(&one, 400_000, 2));
}

/// A smooth map (luminance 1..4) in the same direction harness as the BSDFs (bins in
/// (cos θ, φ) about a pole that is not the map's axis). Its top and bottom rows are black:
/// inside a polar row the density per solid angle of a texel-constant lat-long map grows as
/// 1/sin θ toward the pole, which the harness's midpoint rule over its bins integrates only to
/// ~3·10⁻⁴ (measured), too coarse for a 400,000-sample chi-square; the texel test above
/// integrates those rows on their own texels.
#[test]
fn map_sampling_fits_its_pdf_in_the_direction_harness() {
    let (w, h) = (24u32, 12u32);
    let px: Vec<Vec3> = (0..w * h)
        .map(|k| {
            let (x, y) = ((k % w) as f32 / w as f32, (k / w) as f32 / h as f32);
            if k / w == 0 || k / w == h - 1 {
                return Vec3::ZERO;
            }
            Vec3::new(1.0 + 3.0 * x, 1.0 + y, 2.0 - x * y)
        })
        .collect();
    let m = EnvMap::new(w, h, &px, 15.0, 2.0).unwrap();
    let b = Chi2Binning {
        pole: Vec3::new(0.3, 0.5, 0.8).normalize(),
        z_bins: 20,
        phi_bins: 40,
        quadrature: 24,
        ..Chi2Binning::default()
    };
    let r = chi2_directions(
        |u| m.sample(u).map(|s| s.0),
        |d| m.pdf(d),
        common::uniform_pairs(common::seed(3)),
        400_000,
        &b,
    );
    eprintln!(
        "smooth map: chi2 {:.1} dof {} p {:.4} ∫pdf {:.6} failed {}",
        r.statistic, r.dof, r.p_value, r.pdf_integral, r.failed
    );
    assert!(r.p_value > sidak(0.01, CHI2_TESTS), "p = {}", r.p_value);
    assert!(
        (r.pdf_integral - 1.0).abs() < 2e-3,
        "∫pdf = {}",
        r.pdf_integral
    );
    assert_eq!(r.failed, 0);
}

/// The white furnace of tests/suite/render_core.rs (a diffuse sphere of albedo 0.8, whose pixels that
/// see only the sphere have expected value 0.8) under a constant white *map* instead of
/// `radiance = [1, 1, 1]`:
/// - sampled by the cosine (`--light-points area`) the map is the constant: the images are
///   identical, bit for bit, for every light strategy;
/// - sampled by the map's luminance (uniform over the sphere for a constant map), each pixel
///   mean is 0.8 within z·σ (σ from the film's variance of the mean; independent samples, so it
///   is honest; Šidák over pixels × channels × 2 light strategies at 10⁻³).
#[test]
fn constant_white_map_is_the_white_furnace() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "s.mtl", "newmtl grey\nKd 0.8 0.8 0.8\n");
    let obj = format!("mtllib s.mtl\n{}", icosphere_obj(1.0, 4, "grey"));
    write(dir.path(), "s.obj", &obj);
    let camera = "obj = \"s.obj\"\n[camera]\neye = [0, 0, 4]\ntarget = [0, 0, 0]\nfov = 30\n";
    write_exr(
        &dir.path().join("white.exr"),
        &RgbImage {
            width: 8,
            height: 4,
            pixels: vec![Vec3::ONE; 32],
            ..RgbImage::default()
        },
    )
    .unwrap();
    let constant = dir.path().join("c");
    let map = dir.path().join("m");
    for (d, env) in [
        (&constant, "radiance = [1, 1, 1]"),
        (&map, "map = \"../white.exr\"\nrotation = 30.0"),
    ] {
        std::fs::create_dir(d).unwrap();
        write(d, "s.obj", &obj);
        write(d, "s.mtl", "newmtl grey\nKd 0.8 0.8 0.8\n");
        write(d, "scene.toml", &format!("{camera}[environment]\n{env}\n"));
    }
    let (constant, map) = (
        vrpt::scene::load(&constant).unwrap(),
        vrpt::scene::load(&map).unwrap(),
    );
    assert!(matches!(map.environment(), Environment::Map(_)));
    let (w, h) = (24u32, 24u32);
    let settings = |s: &str, spp: u32| RenderSettings {
        width: w,
        height: h,
        spp,
        max_depth: 4,
        strategy: Strategy::parse(s).unwrap(),
        seed: common::seed(5),
        ..Default::default()
    };
    for lights in ["bsdf", "nee", "mis"] {
        let s = settings(&format!("independent+phong+{lights}+area+tree"), 16);
        let (a, _) = common::render_quiet(&constant, &s);
        let (b, _) = common::render_quiet(&map, &s);
        assert_eq!(
            a.mean_image(),
            b.mean_image(),
            "{lights}: cosine-sampled map"
        );
    }
    // the pixels that see only the sphere: the centre disc well inside its silhouette
    let inside: Vec<(u32, u32)> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let (dx, dy) = (
                x as f32 + 0.5 - w as f32 / 2.0,
                y as f32 + 0.5 - h as f32 / 2.0,
            );
            dx * dx + dy * dy < 6.0 * 6.0
        })
        .collect();
    let z = normal_critical_value(sidak(1e-3, inside.len() * 3 * 2));
    for lights in ["nee", "mis"] {
        let s = settings(&format!("independent+phong+{lights}+projected+tree"), 256);
        let (film, stats) = common::render_quiet(&map, &s);
        assert_eq!(stats.nonfinite, 0);
        let mut worst = 0.0f64;
        for &(x, y) in &inside {
            let i = film.index(x, y);
            let (m, v) = (film.mean(i), film.variance_of_mean(i));
            for c in 0..3 {
                let sd = v[c].sqrt();
                assert!(sd > 0.0, "{lights}: map sampling has variance here");
                let err = (m[c] - 0.8).abs();
                assert!(
                    err <= z * sd,
                    "{lights}: pixel ({x},{y}) = {} (σ {sd})",
                    m[c]
                );
                worst = worst.max(err / sd);
            }
        }
        eprintln!("map furnace {lights}: worst |error|/σ = {worst:.2} (bound {z:.2})");
    }
}

/// Next-event estimation and MIS with the map's importance sampling are unbiased on the shipped
/// sun-sky scene: region means (a 4 × 3 grid of 8 × 8-pixel regions, 32 × 24 pixels) of
/// independent-sample renders at 1024 spp against a reference of 16384 spp (MIS), z =
/// (a − r)/√(σ²_a + σ²_r) with σ² the region's variance of the mean from the films' variance
/// channels (independent samples: honest), family-wise 10⁻³ over 12 regions × 3 channels × 2
/// strategies. The sun is sampled by the map, so neither render is heavy-tailed: each region
/// holds 65,536 samples whose sun contribution arrives in most of them (Kish ESS of the region
/// mean in the tens of thousands), where a normal z holds.
#[test]
fn nee_and_mis_with_the_map_are_unbiased_on_sun_sky() {
    let scene = common::shipped("sun-sky");
    let (w, h) = (32u32, 24u32);
    let settings = |s: &str, spp: u32, seed: u64| RenderSettings {
        width: w,
        height: h,
        spp,
        max_depth: 4,
        strategy: Strategy::parse(s).unwrap(),
        seed: common::seed(seed),
        ..Default::default()
    };
    let reference = common::render_quiet(
        &scene,
        &settings("independent+phong+mis+projected+tree", 16384, 100),
    )
    .0;
    let z = normal_critical_value(sidak(1e-3, 12 * 3 * 2));
    let region = |film: &vrpt::film::Film, rx: u32, ry: u32| {
        let (mut m, mut v) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
        for y in ry * 8..ry * 8 + 8 {
            for x in rx * 8..rx * 8 + 8 {
                let i = film.index(x, y);
                m += film.mean(i);
                v += film.variance_of_mean(i);
            }
        }
        (m / 64.0, v / (64.0 * 64.0))
    };
    for (k, lights) in ["nee", "mis"].iter().enumerate() {
        let s = settings(
            &format!("independent+phong+{lights}+projected+tree"),
            1024,
            k as u64,
        );
        let (film, _) = common::render_quiet(&scene, &s);
        let mut worst = 0.0f64;
        for ry in 0..3 {
            for rx in 0..4 {
                let ((a, va), (r, vr)) = (region(&film, rx, ry), region(&reference, rx, ry));
                for c in 0..3 {
                    let zc = (a[c] - r[c]) / (va[c] + vr[c]).sqrt();
                    assert!(
                        zc.abs() <= z,
                        "{lights}: region ({rx},{ry}) channel {c}: {} vs {} (z {zc:.2})",
                        a[c],
                        r[c]
                    );
                    worst = worst.max(zc.abs());
                }
            }
        }
        eprintln!("sun-sky {lights}: worst |z| {worst:.2} (bound {z:.2})");
    }
}

/// MIS with the map: for random first hits of sun-sky and environment samples that escape,
/// the light pdf a BSDF-sampled escaping ray along the same direction is weighted with
/// (`LightSampler::environment_pdf`, what the integrator computes when a ray escapes) equals the
/// sample's own pdf, for every way of placing points (the map's distribution for solid-angle
/// and projected, the cosine for area) and of choosing lights; with the BSDF pdf shared by both
/// sides (tests/suite/light_sampling.rs), `w_light + w_bsdf = 1`. The two pdfs come from one texel
/// lookup each, the sample's through its (u, v) and the ray's through the inverse map: equal
/// to f32 rounding, except on texel boundaries, where they may name neighbours (rare; allowed
/// for 1 in 1000).
#[test]
fn mis_weights_sum_to_one_with_the_map() {
    use vrpt::lights::{LightChoice, LightPoints};
    let scene = common::shipped("sun-sky");
    let mut rng = SmallRng::seed_from_u64(common::seed(7));
    let cam = vrpt::camera::Camera::new(&scene.camera, 64, 48).unwrap();
    let (mut checked, mut off) = (0usize, 0usize);
    for points in [
        LightPoints::Area,
        LightPoints::SolidAngle,
        LightPoints::Projected,
        LightPoints::Auto,
    ] {
        for choice in [LightChoice::Uniform, LightChoice::Power, LightChoice::Tree] {
            let lights = scene.lights.sampler(points, choice);
            for _ in 0..2000 {
                let px = glam::UVec2::new(rng.random_range(0..64), rng.random_range(0..48));
                let (o, d) = cam.generate_ray(px, Vec2::new(rng.random(), rng.random()));
                let Some(hit) = scene.accel.intersect(o, d, f32::INFINITY) else {
                    continue;
                };
                let s = scene.surface(&hit);
                let ns = if s.ng.dot(-d) > 0.0 { s.ns } else { -s.ns };
                let u = (rng.random(), Vec2::new(rng.random(), rng.random()));
                let Some(ls) = lights.sample(s.p, ns, u.0, u.1) else {
                    continue;
                };
                assert!(ls.dist.is_infinite(), "sun-sky's only light is the sky");
                assert_eq!(ls.le, scene.environment().radiance(ls.wi));
                let p = lights.environment_pdf(ns, ls.wi);
                checked += 1;
                if (p - ls.pdf).abs() > 1e-4 * ls.pdf {
                    off += 1;
                }
            }
        }
    }
    eprintln!("{checked} samples, {off} with pdfs apart");
    assert!(checked > 10_000);
    assert!(
        off * 1000 <= checked,
        "{off} of {checked} samples' pdfs disagree"
    );
}
