//! Warps and the material, checked statistically: chi-square goodness of fit of every sampler
//! against its pdf (one generic helper, `vrpt::stats::chi2_directions`), pdfs that integrate to
//! 1, the consistency rule `pdf(wo, s.wi) == s.pdf`, `eval(wo, s.wi) == s.f`, and energy
//! conservation (directional albedo ≤ 1 for kd + ks = 1).
//!
//! Significance: the whole family of chi-square tests in this file is held at α = 0.01 with
//! Šidák's correction, α_test = 1 − (1 − α)^(1/m). Seeds are fixed, so a pass is reproducible;
//! a wrong pdf (a missing factor, a wrong normalisation) gives p-values of 0 at these sizes.

use crate::common;
use glam::{Vec2, Vec3};
use rand::{rngs::SmallRng, Rng, SeedableRng};
use vrpt::bsdf::Directions;
use vrpt::material::Material;
use vrpt::sampling::*;
use vrpt::stats::{chi2_directions, sidak, Chi2Binning, Chi2Result};

/// Number of chi-square tests in this file (warps: 2 + 4 Phong exponents; material: 5 cases
/// × 3 strategies).
const TESTS: usize = 6 + 15;
const SAMPLES: usize = 400_000;

fn alpha() -> f64 {
    sidak(0.01, TESTS)
}

fn check(name: &str, r: &Chi2Result, normalized: bool) {
    eprintln!(
        "{name}: chi2 {:.1} dof {} p {:.4} ∫pdf {:.6} failed {}",
        r.statistic, r.dof, r.p_value, r.pdf_integral, r.failed
    );
    assert!(
        r.p_value > alpha(),
        "{name}: p = {} ≤ {}",
        r.p_value,
        alpha()
    );
    if normalized {
        assert!(
            (r.pdf_integral - 1.0).abs() < 1e-3,
            "{name}: ∫pdf = {}",
            r.pdf_integral
        );
    }
}

#[test]
fn hemisphere_warps_fit_their_pdfs() {
    let b = Chi2Binning::default();
    let r = chi2_directions(
        |u| Some(sample_uniform_hemisphere(u)),
        |w| {
            if w.z > 0.0 {
                uniform_hemisphere_pdf()
            } else {
                0.0
            }
        },
        common::uniform_pairs(1),
        SAMPLES,
        &b,
    );
    check("uniform hemisphere", &r, true);
    let r = chi2_directions(
        |u| Some(sample_cosine_hemisphere(u)),
        |w| cosine_hemisphere_pdf(w.z),
        common::uniform_pairs(2),
        SAMPLES,
        &b,
    );
    check("cosine hemisphere", &r, true);
}

#[test]
fn phong_lobe_fits_its_pdf() {
    for (k, n) in [1.0f32, 10.0, 100.0, 1000.0].into_iter().enumerate() {
        // bin cosα over [z_lo, 1] where the lobe holds all but 1e-3 of its mass:
        // P(cosα < c) = c^(n+1)
        let b = Chi2Binning {
            z_lo: 1e-3f32.powf(1.0 / (n + 1.0)),
            ..Default::default()
        };
        let r = chi2_directions(
            |u| Some(sample_phong_lobe(n, u)),
            |w| phong_lobe_pdf(n, w.z),
            common::uniform_pairs(10 + k as u64),
            SAMPLES,
            &b,
        );
        check(&format!("phong lobe n={n}"), &r, true);
    }
}

fn dir_at(theta_deg: f32, phi_deg: f32) -> Vec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// (kd, ks, n, θo in degrees): diffuse+glossy, glossy-dominated sharp, grazing glossy (many
/// failed samples), pure diffuse, pure glossy at normal incidence.
fn cases() -> Vec<(f32, f32, f32, f32)> {
    vec![
        (0.5, 0.3, 20.0, 30.0),
        (0.1, 0.8, 200.0, 60.0),
        (0.0, 0.9, 5.0, 80.0),
        (0.7, 0.0, 1.0, 45.0),
        (0.0, 0.6, 50.0, 0.0),
    ]
}

#[test]
fn material_sampling_fits_its_pdf_for_every_strategy() {
    let mut seed = 100;
    for (kd, ks, n, theta) in cases() {
        let m = Material::new("m", Vec3::splat(kd), Vec3::splat(ks), n, Vec3::ZERO)
            .0
            .bsdf();
        let wo = dir_at(theta, 20.0);
        for directions in [Directions::Uniform, Directions::Cosine, Directions::Phong] {
            seed += 1;
            // bin about the mirror direction for sharp lobes sampled by their lobe, else z
            let b = if directions == Directions::Phong && n >= 50.0 {
                Chi2Binning {
                    pole: Vec3::new(-wo.x, -wo.y, wo.z),
                    z_lo: 1e-3f32.powf(1.0 / (n + 1.0)),
                    ..Default::default()
                }
            } else {
                Chi2Binning::default()
            };
            let mut lobe_rng = SmallRng::seed_from_u64(seed + 1000);
            let r = chi2_directions(
                |u| m.sample(wo, lobe_rng.random(), u, directions).map(|s| s.wi),
                |wi| m.pdf(wo, wi, directions),
                common::uniform_pairs(seed),
                SAMPLES,
                &b,
            );
            let name = format!("material kd={kd} ks={ks} n={n} θo={theta} {directions}");
            // the Phong mixture loses the lobe's mass below the horizon (failed samples)
            check(&name, &r, directions != Directions::Phong || ks == 0.0);
            if directions == Directions::Phong && theta >= 80.0 {
                assert!(
                    r.failed > 0,
                    "{name}: grazing glossy sampling must fail sometimes"
                );
            }
        }
    }
}

#[test]
fn sample_agrees_with_eval_and_pdf() {
    let mut rng = SmallRng::seed_from_u64(5);
    let mut checked = 0;
    for (kd, ks, n, _) in cases() {
        let m = Material::new("m", Vec3::splat(kd), Vec3::splat(ks), n, Vec3::ZERO)
            .0
            .bsdf();
        for _ in 0..2000 {
            let wo = dir_at(rng.random_range(0.0..89.0), rng.random_range(0.0..360.0));
            let u = Vec2::new(rng.random(), rng.random());
            for directions in [Directions::Uniform, Directions::Cosine, Directions::Phong] {
                if let Some(s) = m.sample(wo, rng.random(), u, directions) {
                    assert!(s.wi.z > 0.0 && (s.wi.length() - 1.0).abs() < 1e-4);
                    let pdf = m.pdf(wo, s.wi, directions);
                    assert!((pdf - s.pdf).abs() <= 1e-5 * s.pdf, "{pdf} vs {}", s.pdf);
                    let f = m.eval(wo, s.wi);
                    assert!((f - s.f).abs().max_element() <= 1e-5 * s.f.max_element());
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 20_000);
    // below the surface there is nothing
    let m = Material::new("m", Vec3::splat(0.5), Vec3::splat(0.5), 10.0, Vec3::ZERO)
        .0
        .bsdf();
    assert_eq!(m.eval(Vec3::Z, -Vec3::Z), Vec3::ZERO);
    assert_eq!(m.pdf(Vec3::Z, -Vec3::Z, Directions::Phong), 0.0);
    assert!(m
        .sample(-Vec3::Z, 0.5, Vec2::splat(0.5), Directions::Cosine)
        .is_none());
}

/// The directional albedo `a(wo) = ∫ f(wo, wi) cosθi dωi`, estimated with Phong-lobe sampling
/// (mean of `f cos / p` over N samples, standard error `s/√N`). For kd + ks = 1 the modified
/// Phong model conserves energy, `a ≤ 1`, with equality at normal incidence (the specular lobe
/// integrates `(n+2)/(2π) cosⁿ⁺¹θ` to exactly 1 there). Bound: 4 standard errors (a one-sided
/// normal tail of 3e-5 per case).
#[test]
fn albedo_is_at_most_one_and_one_at_normal_incidence() {
    let n_samples = 200_000;
    let mut rng = SmallRng::seed_from_u64(9);
    for n in [1.0f32, 10.0, 100.0, 1000.0, 10000.0] {
        for kd in [0.0f32, 0.3, 0.7] {
            let m = Material::new("m", Vec3::splat(kd), Vec3::splat(1.0 - kd), n, Vec3::ZERO)
                .0
                .bsdf();
            for theta in [0.0f32, 30.0, 60.0, 85.0] {
                let wo = dir_at(theta, 0.0);
                let (mut s, mut s2) = (0.0f64, 0.0f64);
                for _ in 0..n_samples {
                    let u = Vec2::new(rng.random(), rng.random());
                    if let Some(b) = m.sample(wo, rng.random(), u, Directions::Phong) {
                        let w = (b.f.x * b.wi.z / b.pdf) as f64;
                        s += w;
                        s2 += w * w;
                    }
                }
                let mean = s / n_samples as f64;
                let se = ((s2 / n_samples as f64 - mean * mean).max(0.0) / n_samples as f64).sqrt();
                assert!(
                    mean <= 1.0 + 4.0 * se + 1e-6,
                    "n={n} kd={kd} θ={theta}: albedo {mean} ± {se}"
                );
                if theta == 0.0 {
                    assert!(
                        (mean - 1.0).abs() <= 4.0 * se + 1e-4,
                        "n={n} kd={kd}: albedo at normal incidence {mean} ± {se}"
                    );
                }
            }
        }
    }
}

/// The helper must be able to fail: a sampler tested against another pdf is rejected, even
/// when the difference is a slightly wrong exponent.
#[test]
fn chi2_rejects_a_wrong_pdf() {
    let b = Chi2Binning::default();
    let r = chi2_directions(
        |u| Some(sample_cosine_hemisphere(u)),
        |w| {
            if w.z > 0.0 {
                uniform_hemisphere_pdf()
            } else {
                0.0
            }
        },
        common::uniform_pairs(3),
        SAMPLES,
        &b,
    );
    assert!(r.p_value < 1e-10, "cosine vs uniform: p = {}", r.p_value);
    let r = chi2_directions(
        |u| Some(sample_phong_lobe(10.0, u)),
        |w| phong_lobe_pdf(11.0, w.z),
        common::uniform_pairs(4),
        SAMPLES,
        &b,
    );
    assert!(r.p_value < 1e-10, "phong 10 vs 11: p = {}", r.p_value);
}

/// Issue 37: `vrpt warptest`'s warps (hemispheres, Phong lobes, spherical triangle and
/// rectangle uniform and projected, the environment map, a triangle by area, a learned guide
/// leaf) pass their chi-square at the family
/// level (Šidák over the warps, α = 0.01) with ∫pdf within 0.5% of 1, for two seeds; and every
/// one of them is caught with its pdf 5% too high (p < 0.01: 200,000 samples move ~10,000
/// counts against a noise of ~450).
#[test]
fn warptest_passes_every_warp_and_catches_a_five_percent_error() {
    use vrpt::commands::warptest::{run, WarptestRequest};
    let req = |seed: u64, pdf_scale: f32| WarptestRequest {
        n: 200_000,
        seed: common::seed(seed),
        pdf_scale,
        output: None,
        json: None,
    };
    for seed in [1, 2] {
        let rows = run(&req(seed, 1.0)).unwrap().rows;
        let alpha = vrpt::stats::sidak(0.01, rows.len());
        for r in &rows {
            assert!(r.p_value > alpha, "{}: p = {}", r.warp, r.p_value);
            assert!(
                (r.pdf_integral - 1.0).abs() < 5e-3,
                "{}: ∫pdf {}",
                r.warp,
                r.pdf_integral
            );
        }
    }
    for r in run(&req(3, 1.05)).unwrap().rows {
        assert!(
            r.p_value < 0.01,
            "{}: a 5% pdf error passed (p = {})",
            r.warp,
            r.p_value
        );
    }
}
