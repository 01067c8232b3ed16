//! The Sobol sampler: the (0,2)-sequence property of its first two dimensions, independence
//! between pixels, unbiasedness on a known integral and in images, convergence slopes against
//! padded strata (checker plane in tests/suite/experiments.rs; lit-checker and the Cornell box here),
//! and renders past the crate's 2¹⁶ samples per sequence.

use crate::common;

use glam::{UVec2, Vec2};
use vrpt::analysis::experiments::converge;
use vrpt::render::NoProgress;
use vrpt::render::RenderSettings;
use vrpt::sampler::{Sampler, SobolSampler};
use vrpt::stats::{normal_critical_value, sidak};
use vrpt::strategy::Strategy;

/// For N = 2^k, the first N samples of a pixel put exactly one point in every elementary
/// interval `[a/2^i, (a+1)/2^i) × [b/2^j, (b+1)/2^j)` with `i + j = k` of the first two
/// dimensions (the pixel position), for every shape at once — and every value is in [0, 1).
#[test]
fn first_two_dimensions_are_a_0_2_sequence() {
    for k in [2u32, 5, 8, 10] {
        let n = 1u32 << k;
        for (seed, pixel) in [
            (0u64, UVec2::ZERO),
            (7, UVec2::new(13, 2)),
            (99, UVec2::new(400, 300)),
        ] {
            let mut s = SobolSampler::new(common::seed(seed));
            let pts: Vec<Vec2> = (0..n)
                .map(|i| {
                    s.start_pixel_sample(pixel, i);
                    let p = s.next_2d();
                    // the rest of a path's dimensions stay in [0, 1) too
                    for _ in 0..40 {
                        let v = s.next_1d();
                        assert!((0.0..1.0).contains(&v));
                    }
                    p
                })
                .collect();
            for i in 0..=k {
                let (cx, cy) = (1u32 << i, 1u32 << (k - i));
                let mut hit = vec![0u32; n as usize];
                for p in &pts {
                    assert!((0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y));
                    let (a, b) = ((p.x * cx as f32) as u32, (p.y * cy as f32) as u32);
                    hit[(b * cx + a) as usize] += 1;
                }
                assert!(
                    hit.iter().all(|&c| c == 1),
                    "k={k} seed={seed} pixel={pixel} shape {cx}×{cy}"
                );
            }
        }
    }
}

/// Pixels get independent scrambles: Pearson's r between the same dimension of two
/// neighbouring pixels, over N = 256 samples, for 64 pixel pairs × 4 dimensions.
/// - No systematic correlation: the mean of the 256 r's is zero within 4.4 standard errors
///   (t-test with their own spread; two-sided ≈ 1e-5).
/// - No strong dependence: the spread of r is within 1.5× that of independent uniform pairs,
///   1/√(N−1), and every |r| < 0.5. The nested (Owen) index shuffle pairs samples in a
///   structured way, so r is wider than for i.i.d. pairs — measured over 2,000 pairs: sd 0.078
///   against 0.063, max |r| 0.30 — while one scramble shared by all pixels gives r = 1.
#[test]
fn pixels_are_independent() {
    let n = 256u32;
    let mut s = SobolSampler::new(common::seed(3));
    let draws = |s: &mut SobolSampler, p: UVec2, d: usize| -> Vec<f64> {
        (0..n)
            .map(|i| {
                s.start_pixel_sample(p, i);
                s.skip_1d(d as u32);
                s.next_1d() as f64
            })
            .collect()
    };
    let mut rs = Vec::new();
    for k in 0..64u32 {
        for d in [0usize, 1, 3, 7] {
            let a = draws(&mut s, UVec2::new(k % 8, k / 8), d);
            let b = draws(&mut s, UVec2::new(k % 8 + 1, k / 8), d);
            rs.push(vrpt::analysis::fit::pearson(&a, &b));
        }
    }
    let m = rs.len() as f64;
    let mean = rs.iter().sum::<f64>() / m;
    let sd = (rs.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / (m - 1.0)).sqrt();
    let worst = rs.iter().fold(0.0f64, |w, r| w.max(r.abs()));
    let iid = 1.0 / ((n - 1) as f64).sqrt();
    eprintln!("mean r {mean:.4}, sd {sd:.4} (iid {iid:.4}), max |r| {worst:.3}");
    assert!(mean.abs() < 4.4 * sd / m.sqrt(), "mean r {mean}");
    assert!(sd < 1.5 * iid, "sd of r {sd}");
    assert!(worst < 0.5, "max |r| {worst}");
}

/// Unbiased on a known integral: `∫∫ e^(x+y) = (e − 1)²`, estimated with N = 64 points of R =
/// 400 independently scrambled pixels (each a different scramble); the mean of the R
/// estimates has standard error s/√R, and |mean − truth| must stay within 4.4 of those
/// (two-sided 1e-5). An unscrambled or biased point set fails by far: its error is shared.
#[test]
fn unbiased_on_a_known_integral() {
    let truth = (std::f64::consts::E - 1.0).powi(2);
    let (n, r) = (64u32, 400u32);
    let mut s = SobolSampler::new(common::seed(11));
    let est: Vec<f64> = (0..r)
        .map(|k| {
            (0..n)
                .map(|i| {
                    s.start_pixel_sample(UVec2::new(k, 0), i);
                    let u = s.next_2d();
                    ((u.x + u.y) as f64).exp()
                })
                .sum::<f64>()
                / n as f64
        })
        .collect();
    let mean = est.iter().sum::<f64>() / r as f64;
    let sd = (est.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (r - 1) as f64).sqrt();
    let z = (mean - truth) / (sd / (r as f64).sqrt());
    eprintln!("mean {mean:.6} truth {truth:.6} sd {sd:.2e} z {z:.2}");
    assert!(z.abs() < 4.4, "z = {z}");
    // and the scrambled points integrate far better than 1/√N: sd ≪ the i.i.d. sd / 8
    assert!(sd < 0.25 * 0.49 / 8.0, "sd {sd}");
}

/// The padding limit on the shipped lit-checker (32×24, NEE, depth 2: a 4D pixel × light-point
/// integral with edges): independent −1, padded strata stall (measured −1.14 at 128×96),
/// Sobol steeper (−1.63 there). Asserted: independent within −1 ± 0.15 and sobol at least 0.2
/// steeper than stratified. Slopes over 4…1024 spp from 6 runs per point: a mean MSE is known
/// to a few percent, so a fitted slope to ~0.02; the measured gap is ~0.5.
///
/// The light points are pinned to `area` (uniform on the lamp): that is the 4D integrand with
/// edges this test is about. The default `projected` points warp the lamp by solid angle and
/// cosine, which smooths the light dimensions so much that padded strata converge nearly as
/// fast (measured at 32×24: stratified −1.58, sobol −1.72).
#[test]
fn lit_checker_sobol_beats_padded_strata() {
    let scene = common::shipped("lit-checker");
    let (w, h) = (32, 24);
    let r = common::as_image(
        &scene,
        &RenderSettings {
            width: w,
            height: h,
            spp: 16384,
            max_depth: 2,
            seed: common::seed(77),
            strategy: Strategy::parse("sobol+cosine+nee+area+power").unwrap(),
            ..Default::default()
        },
    );
    let strategies: Vec<Strategy> = ["independent", "stratified", "sobol"]
        .iter()
        .map(|s| Strategy::parse(&format!("{s}+cosine+nee+area+power")).unwrap())
        .collect();
    let c = converge(
        &scene,
        &r,
        &strategies,
        &[4, 16, 64, 256, 1024],
        &common::experiment_settings(w, h, 2, 6),
        &NoProgress,
    )
    .unwrap();
    eprint!("{}", c.table());
    let slope = |name: &str| {
        c.slopes
            .iter()
            .find(|s| s.strategy.starts_with(name))
            .unwrap()
            .mse_slope
    };
    assert!((slope("independent") + 1.0).abs() <= 0.15, "{}", c.table());
    assert!(slope("sobol") <= slope("stratified") - 0.2, "{}", c.table());
}

/// The seed's promise on the shipped Cornell box once light sampling is on (MIS, phong,
/// 32×32, against a 32768-spp MIS reference): at every spp from 4 to 1024, Sobol's MSE is at
/// most independent's, and stratified's at most independent's × N/(N−1) (Owen's bound for
/// Latin-hypercube-like padded strata). At low spp a run's MSE is dominated by the rare
/// caustic paths of the glossy box, so it swings between seed sets (independent at 4 spp:
/// 2.5e-2 to 4.6e-2 over 6 runs, and once below Sobol's); the points at 4–64 spp are therefore
/// averaged over 48 runs (√8 ≈ 2.8× steadier), those at 256 and 1024 over 6. Measured ratios
/// to independent: sobol 0.2–0.65, stratified 0.2–0.9. Checked over five seed sets
/// (`VRPT_TEST_SEED=0..4`).
#[test]
fn cornell_box_with_mis_every_stratifying_sampler_beats_independent() {
    let scene = common::shipped("cornell-box");
    let (w, h) = (32, 32);
    let r = common::as_image(
        &scene,
        &RenderSettings {
            width: w,
            height: h,
            spp: 32768,
            max_depth: 8,
            // far from the runs' seeds (from common::seed(1)): seed 9 was run 8's too, which
            // compare now refuses (issue 24)
            seed: common::seed(900_000),
            edge_rays: 0, // as the compare runs (`analysis::experiments`)
            ..Default::default()
        },
    );
    let strategies: Vec<Strategy> = ["independent", "stratified", "sobol"]
        .iter()
        .map(|s| Strategy::parse(&format!("{s}+phong+mis")).unwrap())
        .collect();
    let mut points = Vec::new();
    let mut tables = String::new();
    for (spps, runs) in [(vec![4u32, 16, 64], 48), (vec![256, 1024], 6)] {
        let c = converge(
            &scene,
            &r,
            &strategies,
            &spps,
            &common::experiment_settings(w, h, 8, runs),
            &NoProgress,
        )
        .unwrap();
        tables += &c.table();
        points.extend(c.points);
    }
    eprint!("{tables}");
    let mse = |name: &str, spp: u32| {
        points
            .iter()
            .find(|p| p.strategy.starts_with(name) && p.spp == spp)
            .unwrap()
            .mse
    };
    for n in [4u32, 16, 64, 256, 1024] {
        let ind = mse("independent", n);
        assert!(mse("sobol", n) <= ind, "{n} spp\n{tables}");
        let bound = ind * n as f64 / (n - 1) as f64;
        // the stratified preset with MIS is named "mis"
        assert!(mse("mis", n) <= bound, "{n} spp\n{tables}");
    }
}

/// Past the crate's 2¹⁶ samples per sequence the sampler continues with fresh scrambles: a
/// 70,000-spp render of a tiny lit-checker is finite and agrees with a 4,096-spp one, pixel by
/// pixel (z of the difference with both variances of the mean; the film's variance
/// over-estimates a Sobol estimate's, so the test is lenient, never wrong; Šidák bound at
/// family-wise 10⁻³ over 12 pixels × 3 channels).
#[test]
fn renders_past_two_to_the_sixteen_samples() {
    let scene = common::shipped("lit-checker");
    let base = RenderSettings {
        width: 4,
        height: 3,
        max_depth: 2,
        strategy: Strategy::parse("sobol+cosine+nee").unwrap(),
        ..Default::default()
    };
    let (big, stats) = common::render_quiet(
        &scene,
        &RenderSettings {
            spp: 70_000,
            ..base.clone()
        },
    );
    assert_eq!(stats.nonfinite, 0);
    let (small, _) = common::render_quiet(
        &scene,
        &RenderSettings {
            spp: 4096,
            seed: common::seed(5),
            ..base
        },
    );
    let z_crit = normal_critical_value(sidak(1e-3, 12 * 3));
    for i in 0..big.len() {
        let (a, b) = (big.mean(i), small.mean(i));
        let v = big.variance_of_mean(i) + small.variance_of_mean(i);
        assert!(a.is_finite());
        for c in 0..3 {
            if v[c] == 0.0 {
                assert_eq!(a[c], b[c], "pixel {i}");
                continue;
            }
            let z = (a[c] - b[c]).abs() / v[c].sqrt();
            assert!(
                z <= z_crit,
                "pixel {i} channel {c}: {} vs {} (z {z:.2})",
                a[c],
                b[c]
            );
        }
    }
}
