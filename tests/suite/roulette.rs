//! Efficiency-aware roulette and splitting (`--roulette ears`) is an unbiased estimator of the
//! same image, learns the same cache on any number of threads, and is refused where it cannot
//! run.
//!
//! Unbiasedness is tested region by region against a render with classic roulette, each
//! region's variance taken from the spread of `RUNS` independent renders (`reuse::smallest_p`,
//! Student's t with `RUNS − 1` degrees of freedom, Šidák's α = 0.001 over every test): an EARS
//! render's cache and pixel estimate are learned from its own training, so its pixels are
//! independent only given them, and the spread over seeds holds that randomness too.

use crate::common;
use crate::reuse::{region_runs, regions, smallest_p_of};

use common::render_quiet;
use vrpt::bsdf::Directions;
use vrpt::integrator::rrs::Roulette;
use vrpt::lights::LightStrategy;
use vrpt::render::RenderSettings;
use vrpt::sampler::SamplerKind;
use vrpt::stats::sidak;
use vrpt::strategy::Strategy;

/// The shipped Cornell box (16×16, depth 8, 128 spp: MIS with stratified points, and NEE with
/// cosine directions and independent points) and door (16×12, depth 10, 64 spp: guided
/// directions and MIS, splitting under the guide, about 17 continuations at the first vertex
/// at this size) with EARS agree with a 4096-spp render with classic roulette, region by
/// region; and the same Cornell runs catch a deliberately wrong split weight (`1.05/n`).
/// (About 30 s: the door's runs split into ~125 rays a sample.)
#[test]
fn ears_agrees_with_classic_roulette_on_the_cornell_box_and_the_door() {
    use LightStrategy::{Mis, Nee};
    use SamplerKind::{Independent, Stratified};
    // (scene, width, height, max depth, spp, strategies)
    type Case<'a> = (&'a str, u32, u32, u32, u32, &'a [Strategy]);
    let cases: [Case; 2] = [
        (
            "cornell-box",
            16,
            16,
            8,
            128,
            &[
                Strategy::of(Stratified, Directions::Phong, Mis),
                Strategy::of(Independent, Directions::Cosine, Nee),
            ],
        ),
        (
            "door",
            16,
            12,
            10,
            64,
            &[Strategy::of(Stratified, Directions::Guided, Mis)],
        ),
    ];
    let tests: usize = cases
        .iter()
        .map(|c| (c.1 / 4 * c.2 / 4) as usize * 3 * c.5.len())
        .sum();
    let alpha = sidak(1e-3, tests);
    for (s, (name, w, h, max_depth, spp, runs)) in cases.into_iter().enumerate() {
        let scene = common::shipped(name);
        let base = RenderSettings {
            width: w,
            height: h,
            spp,
            max_depth,
            ..Default::default()
        };
        let reference_settings = RenderSettings {
            spp: 4096,
            seed: common::seed(9500 + s as u64),
            ..base.clone()
        };
        let (reference, _) = render_quiet(&scene, &reference_settings);
        let reference = regions(&reference);
        for (j, &strategy) in runs.iter().enumerate() {
            let settings = RenderSettings {
                roulette: Roulette::Ears,
                strategy,
                ..base.clone()
            };
            let seed = common::seed(9600 + 100 * (4 * s + j) as u64);
            let runs = region_runs(&scene, &settings, seed);
            let label = format!("{name}, ears, {strategy}");
            let (p, lit) = smallest_p_of(&runs, &reference, &label);
            assert!(4 * lit >= 3 * reference.len() * 3, "{name}: only {lit} lit");
            assert!(
                p >= alpha,
                "{label}: a region disagrees with the reference (p {p:.2e} < {alpha:.2e})"
            );
            if (name, j) == ("cornell-box", 0) {
                // the power: a split's weight 1.05/n, not 1/n, makes every Phong vertex
                // return 1.05 times its reflected radiance, in expectation the image of the
                // box with every Kd and Ks times 1.05 (the light's are black; the tall box's
                // 0.4 + 0.5 stays below one), so the same runs against that box's classic
                // render are what this test sees of the wrong weight (measured: worst t −15.6,
                // against the bound |t| = 6.7 of Student's t with 15 degrees of freedom at
                // Šidák's α over the 132 region-channels; unbiased, the worst read 2.1–2.3)
                let dir = tempfile::tempdir().unwrap();
                let brighter =
                    crate::unbiased_images::dimmed(dir.path(), name, &["Kd", "Ks"], 1.0 / 1.05);
                let (wrong, _) = render_quiet(&brighter, &reference_settings);
                let label = format!("{label}, weights x1.05");
                let (p, _) = smallest_p_of(&runs, &regions(&wrong), &label);
                assert!(p < alpha, "{label}: not caught (p {p:.2e} >= {alpha:.2e})");
            }
        }
    }
}

/// An EARS render is the same image on 1 and 2 threads (its cache is learned in a fixed
/// order), it did split (more rays per sample than classic roulette at the first vertex's
/// continuations), and it differs from a classic render.
#[test]
fn ears_gives_the_same_image_on_any_number_of_threads() {
    let scene = common::shipped("cornell-box");
    let base = RenderSettings {
        width: 40,
        height: 24,
        spp: 32,
        roulette: Roulette::Ears,
        ..Default::default()
    };
    let render = |threads| {
        render_quiet(
            &scene,
            &RenderSettings {
                threads: Some(threads),
                ..base.clone()
            },
        )
    };
    let (one, stats) = render(1);
    let (two, _) = render(2);
    let means = |f: &vrpt::film::Film| (0..f.len()).map(|i| f.mean(i)).collect::<Vec<_>>();
    let one_means = means(&one);
    assert_eq!(one_means, means(&two));
    let r = stats.rrs.expect("ears stats");
    assert!(r.iterations >= 2 && r.nodes > 0, "{r:?}");
    assert!(r.first_split > 1.0, "the box's first vertices split: {r:?}");
    // the map of the first vertex's factor: one per pixel, 0 or within the clamp, and the
    // box's walls split
    let map = vrpt::render::render_passes(
        &scene,
        &base,
        &vrpt::render::PassPlan::default(),
        &vrpt::render::NoProgress,
    )
    .unwrap()
    .ears_map
    .expect("a map under ears");
    assert_eq!(map.len(), (base.width * base.height) as usize);
    let (lo, hi) = vrpt::integrator::rrs::FACTOR_RANGE;
    assert!(map.iter().all(|&n| n == 0.0 || (lo..=hi).contains(&n)));
    assert!(
        map.iter().filter(|&&n| n > 1.0).count() > map.len() / 4,
        "{map:?}"
    );
    let (classic, _) = render_quiet(
        &scene,
        &RenderSettings {
            roulette: Roulette::Classic,
            ..base.clone()
        },
    );
    assert!((0..classic.len()).any(|i| classic.mean(i) != one_means[i]));
}

/// What EARS cannot do yet is refused with one line: with path reuse, and past the depth its
/// recursion allows.
#[test]
fn ears_refuses_reuse_and_deep_paths() {
    let scene = common::shipped("cornell-box");
    let base = RenderSettings {
        width: 8,
        height: 8,
        spp: 4,
        roulette: Roulette::Ears,
        ..Default::default()
    };
    let err = |s: RenderSettings| match vrpt::render::render(&scene, &s, &vrpt::render::NoProgress)
    {
        Ok(_) => panic!("not refused"),
        Err(e) => e.to_string(),
    };
    let e = err(RenderSettings {
        reuse: 2,
        ..base.clone()
    });
    assert!(e.contains("--reuse"), "{e}");
    let e = err(RenderSettings {
        max_depth: vrpt::integrator::MAX_RRS_DEPTH + 1,
        ..base.clone()
    });
    assert!(e.contains("--max-depth"), "{e}");
}

/// `--ears-map` writes the map as a PNG of the image's size (scaled up, with its colour bar),
/// and is refused without `--roulette ears`, or to a file that is not a PNG.
#[test]
fn the_ears_map_is_written_and_refused_without_ears() {
    let dir = tempfile::tempdir().unwrap();
    let s = common::shipped_path("cornell-box");
    let s = s.to_str().unwrap();
    let (png, map) = (dir.path().join("a.png"), dir.path().join("map.png"));
    let (png, map) = (png.to_str().unwrap(), map.to_str().unwrap());
    let base = [
        "render", s, "--width", "16", "--height", "16", "--spp", "8", "-o", png,
    ];
    let ears = ["--roulette", "ears", "--ears-map", map, "--stats"];
    let ok = common::vrpt_ok(&[&base[..], &ears].concat());
    assert!(String::from_utf8_lossy(&ok.stderr).contains("continuations at the first vertex"));
    let img = image::open(map).unwrap();
    assert!(
        img.width() >= 256 && img.height() > 256,
        "{}×{}",
        img.width(),
        img.height()
    );
    let refused = common::vrpt(&[&base[..], &["--ears-map", map]].concat());
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(
        !refused.status.success() && err.contains("--roulette ears"),
        "{err}"
    );
    let bad = dir.path().join("map.exr");
    let args = ["--roulette", "ears", "--ears-map", bad.to_str().unwrap()];
    let refused = common::vrpt(&[&base[..], &args].concat());
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(
        !refused.status.success() && err.contains("EARS map is a .png"),
        "{err}"
    );
}
