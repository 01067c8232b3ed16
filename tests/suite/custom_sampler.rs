//! A sampler written outside the crate goes through the renderer and the harness like the
//! built-in ones: the generic entry point gives the built-in samplers' images bit for bit, a
//! custom sampler renders the same image on 1 and 2 threads, its shards merge into the whole
//! render, it is unbiased by a z-test against a reference (and a biased one fails that test),
//! and it sits in `compare`/`converge` tables beside the built-in strategies.

use crate::common;

use glam::{UVec2, Vec2};
use vrpt::analysis::experiments::{compare_entries, converge_entries, Entry, ExperimentSettings};
use vrpt::film::Film;
use vrpt::math::{hash_words, u64_to_unit_f32};
use vrpt::render::{
    render_passes, render_passes_with, NoProgress, PassPlan, RenderSettings, SamplePass,
};
use vrpt::sampler::{Sampler, SamplerKind, SobolSampler, StratifiedSampler};
use vrpt::stats::{sidak, student_t_two_sided_p};
use vrpt::strategy::Strategy;

/// A Kronecker (Weyl) sequence, `α_d = frac(√q_d)` for the first 16 primes `q_d` (rationally
/// independent, so the points fill the cube; multiples of one number, such as `frac(φ·d)`,
/// would put them on a lattice plane and make every pixel's estimate converge to a wrong value,
/// which this test catches), rotated by a uniform shift per (seed, pixel, dimension); deeper
/// dimensions are hashed i.i.d. `squeeze < 1` scales every value (a deliberately biased sampler,
/// for the power check).
#[derive(Clone)]
struct Kronecker {
    seed: u64,
    squeeze: f32,
    pixel: UVec2,
    index: u32,
    dim: u64,
}

impl Kronecker {
    fn new(seed: u64, squeeze: f32) -> Kronecker {
        Kronecker {
            seed,
            squeeze,
            pixel: UVec2::ZERO,
            index: 0,
            dim: 0,
        }
    }
}

impl Sampler for Kronecker {
    fn start_pixel_sample(&mut self, pixel: UVec2, index: u32) {
        (self.pixel, self.index, self.dim) = (pixel, index, 0);
    }
    fn next_1d(&mut self) -> f32 {
        let phi = (5f64.sqrt() - 1.0) / 2.0;
        let alpha = (phi * (self.dim + 1) as f64).fract();
        let words = [
            self.seed,
            self.pixel.x as u64,
            self.pixel.y as u64,
            self.dim,
        ];
        self.dim += 1;
        let shift = u64_to_unit_f32(hash_words(&words)) as f64;
        let x = (shift + self.index as f64 * alpha).fract() as f32;
        (x * self.squeeze).min(vrpt::sampler::ONE_MINUS_EPSILON)
    }
    fn next_2d(&mut self) -> Vec2 {
        Vec2::new(self.next_1d(), self.next_1d())
    }
}

fn kronecker(seed: u64, _: SamplePass) -> Kronecker {
    Kronecker::new(seed, 1.0)
}

fn settings(scene: &str, (w, h): (u32, u32), spp: u32, strategy: &str) -> RenderSettings {
    let s = common::shipped(scene);
    RenderSettings {
        width: w,
        height: h,
        spp,
        max_depth: s.defaults.max_depth.unwrap_or(8),
        seed: common::seed(5),
        strategy: Strategy::parse(strategy).unwrap(),
        ..RenderSettings::default()
    }
}

fn same_film(a: &Film, b: &Film) -> bool {
    (0..a.len()).all(|i| a.pixel_sums(i) == b.pixel_sums(i))
}

#[test]
fn the_generic_entry_point_gives_the_built_in_images_bit_for_bit() {
    let scene = common::shipped("cornell-box");
    let plan = PassPlan {
        pass_spp: Some(8),
        ..PassPlan::default()
    };
    for kind in [SamplerKind::Stratified, SamplerKind::Sobol] {
        let mut s = settings("cornell-box", (16, 16), 20, "mis");
        s.strategy.sampler = kind;
        let built_in = render_passes(&scene, &s, &plan, &NoProgress).unwrap();
        let generic = match kind {
            SamplerKind::Stratified => {
                let f =
                    |seed, p: SamplePass| StratifiedSampler::with_origin(seed, p.size, p.origin);
                render_passes_with(&scene, &s, &plan, &f, &NoProgress)
            }
            _ => render_passes_with(
                &scene,
                &s,
                &plan,
                &|seed, _| SobolSampler::new(seed),
                &NoProgress,
            ),
        }
        .unwrap();
        assert!(same_film(&built_in.film, &generic.film), "{kind}");
    }
}

#[test]
fn a_custom_sampler_is_thread_independent_and_its_shards_merge() {
    let scene = common::shipped("cornell-box");
    let s = settings("cornell-box", (24, 20), 12, "mis");
    let full = |threads, shard| {
        let s = RenderSettings {
            threads: Some(threads),
            ..s.clone()
        };
        let plan = PassPlan {
            pass_spp: Some(4),
            shard,
            ..PassPlan::default()
        };
        render_passes_with(&scene, &s, &plan, &kronecker, &NoProgress).unwrap()
    };
    let (one, two) = (full(1, None), full(2, None));
    assert!(same_film(&one.film, &two.film));
    // shards 0/2 and 1/2 (samples 0..6 and 6..12) merge into the whole render: the same counts,
    // and sums equal up to the rounding of adding two partial sums instead of one running sum
    let (a, b) = (full(2, Some((0, 2))), full(2, Some((1, 2))));
    assert_eq!((a.first_sample, a.spp, b.first_sample, b.spp), (0, 6, 6, 6));
    let mut merged = a.film;
    merged.merge(&b.film).unwrap();
    for i in 0..merged.len() {
        let ((s1, q1, n1), (s2, q2, n2)) = (merged.pixel_sums(i), one.film.pixel_sums(i));
        assert_eq!(n1, n2);
        assert!((s1 - s2).abs().max_element() <= 1e-9 * s2.abs().max_element().max(1.0));
        assert!((q1 - q2).abs().max_element() <= 1e-9 * q2.abs().max_element().max(1.0));
    }
}

/// Unbiasedness of the custom sampler on lit-checker with NEE and points by area (diffuse, max
/// depth 2, no caustics). The error of one render of a quasi-random sampler is not its sample
/// variance over N: with one shift per pixel, a Kronecker point set is a lattice whose empty
/// strips can miss a thin feature outright (measured: a pixel whose light edge covers 0.26% of
/// it got no hit in 4096 samples, z = 37 against its own variance). So the test takes R = 16
/// replicates of 256 spp (seeds 0..16: independent shifts) and, per pixel-channel, Student's
/// `t = (mean − m_ref)/√(s²/R + v_ref)` with `s²` the variance across the replicates, R − 1
/// degrees of freedom, against a 65536-spp Sobol reference; every two-sided p must be above
/// Šidák's level for α = 10⁻³ over pixels × channels × 2 samplers. The power check: the same
/// sampler with every value scaled by 0.9 (no point in the last tenth of any domain) must fail.
#[test]
fn a_custom_sampler_is_unbiased_and_a_biased_one_is_caught() {
    const R: u64 = 16;
    let scene = common::shipped("lit-checker");
    let strategy = "independent+cosine+nee+area+power";
    let mut reference = settings("lit-checker", (16, 12), 65536, strategy);
    reference.strategy.sampler = SamplerKind::Sobol;
    reference.seed = common::seed(1000);
    let reference = render_passes(&scene, &reference, &PassPlan::default(), &NoProgress)
        .unwrap()
        .film;
    let level = sidak(1e-3, 16 * 12 * 3 * 2);
    let smallest_p = |squeeze: f32| {
        let f = move |seed, _: SamplePass| Kronecker::new(seed, squeeze);
        let replicates: Vec<Film> = (0..R)
            .map(|k| {
                let s = RenderSettings {
                    seed: common::seed(k),
                    ..settings("lit-checker", (16, 12), 256, strategy)
                };
                render_passes_with(&scene, &s, &PassPlan::default(), &f, &NoProgress)
                    .unwrap()
                    .film
            })
            .collect();
        let mut smallest = 1.0f64;
        for i in 0..reference.len() {
            for c in 0..3 {
                let x: Vec<f64> = replicates.iter().map(|f| f.mean(i)[c]).collect();
                let mean = x.iter().sum::<f64>() / R as f64;
                let s2 = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (R - 1) as f64;
                let v = s2 / R as f64 + reference.variance_of_mean(i)[c];
                let d = mean - reference.mean(i)[c];
                if v == 0.0 {
                    assert!(d.abs() <= 1e-9, "pixel {i}: {mean} without variance");
                    continue;
                }
                smallest = smallest.min(student_t_two_sided_p(d / v.sqrt(), (R - 1) as f64));
            }
        }
        smallest
    };
    let (fair, squeezed) = (smallest_p(1.0), smallest_p(0.9));
    eprintln!("smallest p: kronecker {fair:.2e}, squeezed {squeezed:.2e}, level {level:.2e}");
    assert!(fair > level, "the custom sampler disagrees: p = {fair:e}");
    assert!(
        squeezed < level,
        "a 10% squeeze must be caught: p = {squeezed:e}"
    );
}

#[test]
fn custom_entries_sit_beside_the_built_in_ones_in_compare_and_converge() {
    let scene = common::shipped("cornell-box");
    let mut r = settings("cornell-box", (12, 12), 256, "mis");
    r.seed = 1000;
    let reference = render_passes(&scene, &r, &PassPlan::default(), &NoProgress).unwrap();
    let reference = vrpt::image_io::RgbImage {
        width: 12,
        height: 12,
        pixels: reference.film.mean_image(),
        ..Default::default()
    };
    let s = ExperimentSettings {
        width: 12,
        height: 12,
        max_depth: r.max_depth,
        seed: 1,
        reference_seeds: vec![1000],
        runs: 2,
        threads: None,
        regions: Vec::new(),
    };
    let mis = Strategy::parse("mis").unwrap();
    let entries = [
        Entry::builtin(mis),
        Entry::custom("kronecker", kronecker, mis),
    ];
    let c = compare_entries(&scene, &reference, &entries, 4, None, &s, &NoProgress).unwrap();
    let names: Vec<&str> = c.rows.iter().map(|r| r.strategy.as_str()).collect();
    assert_eq!(names, ["mis", "kronecker"]);
    assert!(c.rows.iter().all(|r| r.mse > 0.0 && r.mse.is_finite()));
    assert!(c.table().contains("kronecker"));
    let v = converge_entries(&scene, &reference, &entries, &[2, 8], &s, &NoProgress).unwrap();
    assert_eq!(v.slopes[1].strategy, "kronecker");
    assert_eq!(v.points.len(), 4);
}
