//! The measurement harness on small versions of the shipped experiment scenes: references
//! computed in the test, `compare` at equal spp (importance sampling on glossy-plates,
//! stratification on checker-plane, the combination on both, no strategy biased), `converge`
//! slopes on checker-plane, and `merge` equal to one render.

use crate::common;

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::OnceLock;
use vrpt::analysis::experiments::{compare, compare_entries, converge, converge_entries, Entry};
use vrpt::analysis::merge::{merge, MergeInput};
use vrpt::image_io::{read_exr, write_exr, RgbImage};
use vrpt::output::RenderMetadata;
use vrpt::render::NoProgress;
use vrpt::render::RenderSettings;
use vrpt::sampler::SamplerKind;
use vrpt::scene::Scene;
use vrpt::stats::sidak;
use vrpt::strategy::{Preset, Strategy};

/// A converged reference: `spp` samples of the default strategy (stratified, phong, MIS), as
/// the EXR would hold it.
fn reference(scene: &Scene, w: u32, h: u32, spp: u32, max_depth: u32) -> RgbImage {
    let s = RenderSettings {
        width: w,
        height: h,
        spp,
        max_depth,
        seed: 999,
        ..Default::default()
    };
    common::as_image(scene, &s)
}

/// Family-wise α = 0.01 over the bias tests of this file (2 scenes × 4 strategies).
fn bias_alpha() -> f64 {
    sidak(0.01, 8)
}

/// The checker plane's reference (32×24, 65536 spp, depth 2), rendered once per test binary
/// and shared by the tests that need it.
fn checker_reference(scene: &Scene) -> &'static RgbImage {
    static REF: OnceLock<RgbImage> = OnceLock::new();
    REF.get_or_init(|| reference(scene, 32, 24, 65536, 2))
}

/// Compare the four presets on `scene` at 32×24, `spp` per run, 16 runs, against the reference
/// `r`; assert what holds for every scene (the strategies in `bias_tested` unbiased, the
/// baseline and the images there) and return the MSEs.
fn compare_presets(
    name: &str,
    scene: &Scene,
    r: &RgbImage,
    max_depth: u32,
    spp: u32,
    bias_tested: &[&str],
) -> BTreeMap<String, f64> {
    let (w, h) = (32, 24);
    let c = compare(
        scene,
        r,
        &Preset::mission(),
        spp,
        None,
        &common::experiment_settings(w, h, max_depth, 16),
        &NoProgress,
    )
    .unwrap();
    eprint!("{name}\n{}", c.table());
    let mse: BTreeMap<String, f64> = c.rows.iter().map(|r| (r.strategy.clone(), r.mse)).collect();
    for row in c
        .rows
        .iter()
        .filter(|r| bias_tested.contains(&r.strategy.as_str()))
    {
        assert!(
            row.bias_p > bias_alpha(),
            "{name} {}: biased? t = {}, p = {}",
            row.strategy,
            row.bias_t,
            row.bias_p
        );
    }
    assert!(c.rows.iter().all(|r| r.spp == spp as f64));
    assert_eq!(c.baseline, "independent");
    assert_eq!(c.images.len(), 4);
    mse
}

/// Glossy plates, 32×24, 16 spp, K = 16 runs, in a version written by the test from the
/// shipped files: the same geometry and plates, but the floor, the back wall and the plates'
/// diffuse part black and the two smallest lights off. Why: with BSDF sampling only, the shipped
/// scene's tiny bright lights (Ke 800 and 72) seen through the rough plate and the diffuse floor
/// give *every* strategy rare, huge samples; measured at this size over 3 seeds, importance's MSE
/// ranged 1.3–3.0 and combined beat it in one seed and lost by 1.4× in another, and
/// independent/importance ranged 2.5×–1300×. In this version importance sampling's weights are
/// tame (measured MSE 0.0105–0.0112 over 4 seeds, combined 0.0053), while uniform directions
/// still meet the n = 10⁴ lobe only rarely: their measured MSE is 0.20–5.1, ≥ 19× importance's.
/// The bias test covers the Phong-direction strategies only: uniform directions miss the sharp
/// highlights in all 16 runs often enough that their errors share a sign (measured t = −6.5) —
/// rarity, not bias (an independent render at 131072 spp agrees with the reference, image bias
/// z = +0.27); their unbiasedness is held by tests/suite/unbiased_images.rs.
#[test]
fn compare_on_glossy_plates() {
    let dir = tempfile::tempdir().unwrap();
    let src = common::shipped_path("glossy-plates");
    std::fs::copy(
        src.join("glossy-plates.obj"),
        dir.path().join("glossy-plates.obj"),
    )
    .unwrap();
    std::fs::copy(src.join("scene.toml"), dir.path().join("scene.toml")).unwrap();
    let mut mtl = std::fs::read_to_string(src.join("glossy-plates.mtl")).unwrap();
    for (from, to) in [
        ("newmtl floor\nKd 0.2 0.2 0.2", "newmtl floor\nKd 0 0 0"),
        ("Kd 0.05 0.05 0.05", "Kd 0 0 0"),
        ("Ke 800 800 800", "Ke 0 0 0"),
        ("Ke 72 72 72", "Ke 0 0 0"),
    ] {
        assert!(mtl.contains(from), "glossy-plates.mtl lacks '{from}'");
        mtl = mtl.replace(from, to);
    }
    std::fs::write(dir.path().join("glossy-plates.mtl"), mtl).unwrap();
    let scene = vrpt::scene::load(dir.path()).unwrap();
    let r = reference(&scene, 32, 24, 16384, 4);
    let mse = compare_presets(
        "glossy-plates",
        &scene,
        &r,
        4,
        16,
        &["importance", "combined"],
    );
    assert!(mse["importance"] <= mse["independent"] / 5.0, "{mse:?}");
    // the combination is within 10% of the best of the others (measured: 0.0053 against
    // importance's 0.0105–0.0112, the best of the others, over 4 seeds)
    let best_other = mse["independent"]
        .min(mse["stratified"])
        .min(mse["importance"]);
    assert!(mse["combined"] <= best_other * 1.1, "{mse:?}");
}

/// Checker plane, 32×24, 64 spp (8×8 strata), K = 16 runs: each pixel is a pure 2D integral
/// with edges, where jittered sampling's MSE falls as N^-1.5 against N^-1, so its advantage
/// grows as √N. At 16 spp (4×4 strata) it is still small: a straight edge cuts ~2√N of the N
/// strata, giving a ratio of ~3 for a single-edge pixel and less where corners and many edges
/// share a pixel (measured: 2.06 over 16 runs, too close to 2 for a test). At 64 spp the measured
/// ratio is 3.06 (printed); a run's MSE varies by a few percent between runs, so over 16 runs the
/// ratio is known to ~2%, far from the required 2.
#[test]
fn compare_on_checker_plane() {
    let scene = common::shipped("checker-plane");
    let all = ["independent", "stratified", "importance", "combined"];
    let mse = compare_presets(
        "checker-plane",
        &scene,
        checker_reference(&scene),
        2,
        64,
        &all,
    );
    assert!(mse["stratified"] <= mse["independent"] / 2.0, "{mse:?}");
    // The plane is black (Kd = Ks = 0): every path ends on it, so the direction strategy cannot
    // change the image; with the same sampler and seeds the images, hence the MSEs, are
    // identical. This fails if choosing directions ever shifts the sampler's dimensions.
    assert_eq!(mse["importance"], mse["independent"], "{mse:?}");
    assert_eq!(mse["combined"], mse["stratified"], "{mse:?}");
}

/// `converge` on the checker plane at 4…1024 spp, 8 runs each. The slope of log MSE against
/// log spp: independent −1 (tolerance ±0.15: each mean MSE is known to ~3% from 8 runs, so the
/// fitted slope over 5 points spanning a factor 256 to ~0.01); stratified ≤ −1.3 (theory −1.5
/// for edges; pixels crossed by many edges near the horizon approach it only at higher N;
/// measured −1.35 against −0.99, with a slope standard error of ~0.01); sobol ≤ −1.4 (a pixel
/// is a 2D integral here, where Owen-scrambled Sobol points converge at least as fast as
/// jittered strata, and keep doing so at every power of two instead of one fixed N).
#[test]
fn converge_slopes_on_checker_plane() {
    let scene = common::shipped("checker-plane");
    let (w, h, d) = (32, 24, 2);
    let strategies = [
        Strategy::parse("independent").unwrap(),
        Strategy::parse("stratified").unwrap(),
        Strategy::parse("sobol+uniform").unwrap(),
    ];
    let c = converge(
        &scene,
        checker_reference(&scene),
        &strategies,
        &[4, 16, 64, 256, 1024],
        &common::experiment_settings(w, h, d, 8),
        &NoProgress,
    )
    .unwrap();
    eprint!("{}", c.table());
    let ind = c
        .slopes
        .iter()
        .find(|s| s.strategy == "independent")
        .unwrap();
    let strat = c
        .slopes
        .iter()
        .find(|s| s.strategy == "stratified")
        .unwrap();
    assert!(
        (ind.mse_slope + 1.0).abs() <= 0.15,
        "independent slope {}",
        ind.mse_slope
    );
    assert!(
        strat.mse_slope <= -1.3,
        "stratified slope {}",
        strat.mse_slope
    );
    let sobol = c
        .slopes
        .iter()
        .find(|s| s.strategy.starts_with("sobol"))
        .unwrap();
    assert!(sobol.mse_slope <= -1.4, "sobol slope {}", sobol.mse_slope);
    assert_eq!(c.points.len(), 15);
}

/// Issue 22: `compare` and `converge` measure adaptive allocation beside uniform allocation.
/// An entry renders its runs as 4 replicates, its adaptive twin is named "<name> adaptive", and
/// each row carries the error its runs estimated for themselves beside the measured one. Both
/// are means over 4 runs × 768 pixels of a smooth scene (no heavy tails: the checker plane at
/// depth 2, lit directly), the estimate unbiased for the variance of the mean
/// (`src/estimate.rs`) and the reference's own variance (65536 spp) three decades below, so a
/// factor of 2 between them is many standard errors wide; the adaptive run's spp map holds
/// its budget (64 spp on average, up to the rounding of the allocation) and is not uniform.
#[test]
fn compare_and_converge_measure_adaptive_beside_uniform() {
    let scene = common::shipped("checker-plane");
    let (w, h, d) = (32, 24, 2);
    let r = checker_reference(&scene);
    let st = Strategy::parse("stratified").unwrap();
    let entries = || {
        vec![
            Entry::builtin(st).with_replicates(4),
            // every round allocated: the plumbing of adaptive entries is what is tested
            Entry::builtin(st)
                .with_replicates(4)
                .adaptive()
                .with_min_allocation_gain(0.0),
        ]
    };
    let s = common::experiment_settings(w, h, d, 4);
    let c = compare_entries(&scene, r, &entries(), 64, None, &s, &NoProgress).unwrap();
    eprint!("{}", c.table());
    let names: Vec<&str> = c.rows.iter().map(|r| r.strategy.as_str()).collect();
    assert_eq!(names, ["stratified", "stratified adaptive"]);
    for row in &c.rows {
        assert_eq!(row.estimate, "replicates");
        let ratio = row.est_mse / row.mse;
        assert!(
            (0.5..=2.0).contains(&ratio),
            "{}: estimated MSE {:.3e}, measured {:.3e}",
            row.strategy,
            row.est_mse,
            row.mse
        );
    }
    assert!(c.spp_maps[0].is_none());
    let map = c.spp_maps[1]
        .as_ref()
        .expect("the adaptive entry's spp map");
    let mean = map.iter().map(|&n| n as f64).sum::<f64>() / map.len() as f64;
    assert!((mean - 64.0).abs() <= 64.0 * 0.1, "mean spp {mean}");
    assert!(map.iter().min() < map.iter().max());
    let v = converge_entries(&scene, r, &entries(), &[16, 64], &s, &NoProgress).unwrap();
    eprint!("{}", v.table());
    assert_eq!(v.points.len(), 4);
    let adaptive: Vec<bool> = v.spp_maps.iter().map(Option::is_some).collect();
    assert_eq!(adaptive, [false, false, true, true]);
    assert!(v.points.iter().all(|p| p.est_mse > 0.0));
}

/// Issue 24: no run uses a seed whose samples the reference holds. A reference rendered with
/// seed 2 (the independent sampler, the same spp as the runs: a run of seed 2 would be the
/// reference itself, MSE 0) makes the runs from seed 1 take seeds 1, 3, 4, 5; a merged
/// reference of seeds 1 and 2 makes them 3, 4, 5, 6; and settings built by hand that would
/// reuse seed 2 are refused by `compare`.
#[test]
fn runs_never_reuse_the_references_seeds() {
    use vrpt::analysis::experiments::ExperimentSettings;
    let scene = common::shipped("checker-plane");
    let st = Strategy::parse("independent+cosine+bsdf").unwrap();
    let settings = |seed: u64, first_sample: u32| RenderSettings {
        width: 8,
        height: 6,
        spp: 4,
        first_sample,
        max_depth: 2,
        seed,
        strategy: st,
        ..Default::default()
    };
    let r2 = common::as_image(&scene, &settings(2, 0));
    let path = std::path::Path::new("ref.exr");
    let s = ExperimentSettings::for_reference(&scene, &r2, path, 1, 4, None).unwrap();
    assert_eq!(s.run_seeds(), [1, 3, 4, 5]);
    let c = compare(&scene, &r2, &[st], 4, None, &s, &NoProgress).unwrap();
    assert!(c.rows[0].mse > 0.0);
    let r1 = common::as_image(&scene, &settings(1, 4));
    let (merged, _) = merge(&[input("r1", &r1), input("r2", &r2)]).unwrap();
    let s = ExperimentSettings::for_reference(&scene, &merged, path, 1, 4, None).unwrap();
    assert_eq!(s.run_seeds(), [3, 4, 5, 6]);
    let by_hand = ExperimentSettings {
        reference_seeds: Vec::new(),
        seed: 1,
        ..s.clone()
    };
    let e = compare(&scene, &r2, &[st], 4, None, &by_hand, &NoProgress).unwrap_err();
    assert!(e.to_string().contains("seed 2"), "{e}");
}

/// A merge input made in memory, named `name`.
fn input(name: &str, image: &RgbImage) -> MergeInput {
    MergeInput {
        path: PathBuf::from(name),
        meta: RenderMetadata::from_attributes(&image.metadata).unwrap(),
        image: image.clone(),
    }
}

/// Two renders of samples 0..32 and 32..64 (same seed) merge into one render of 0..64: the same
/// samples, so the merged mean and variance equal the full render's up to f32 storage rounding
/// (relative 1e-5 with a small absolute floor for the variance's cancellation).
#[test]
fn merge_of_two_halves_equals_one_render() {
    let scene = common::shipped("cornell-box");
    for sampler in [SamplerKind::Independent, SamplerKind::Stratified] {
        let full = RenderSettings {
            width: 16,
            height: 16,
            spp: 64,
            max_depth: 4,
            seed: 3,
            strategy: Strategy {
                sampler,
                ..Preset::Combined.strategy()
            },
            ..Default::default()
        };
        // the stratified full render is two passes of 32, as the halves are
        let whole = if sampler == SamplerKind::Stratified {
            let r = vrpt::render::render_passes(
                &scene,
                &full,
                &vrpt::render::PassPlan {
                    pass_spp: Some(32),
                    ..Default::default()
                },
                &vrpt::render::NoProgress,
            )
            .unwrap();
            let (f, st) = (r.film, r.stats);
            vrpt::output::render_image(&f, &RenderMetadata::new(&scene, &full, &st))
        } else {
            common::as_image(&scene, &full)
        };
        let a = common::as_image(
            &scene,
            &RenderSettings {
                spp: 32,
                ..full.clone()
            },
        );
        let b = common::as_image(
            &scene,
            &RenderSettings {
                spp: 32,
                first_sample: 32,
                ..full.clone()
            },
        );
        let (m, meta) = merge(&[input("a", &a), input("b", &b)]).unwrap();
        assert_eq!(meta.spp, 64);
        assert_eq!(m.metadata["spp"], "64");
        let var = m.variance.as_ref().unwrap();
        let wvar = whole.variance.as_ref().unwrap();
        for i in 0..m.pixels.len() {
            for c in 0..3 {
                let (x, y) = (m.pixels[i][c], whole.pixels[i][c]);
                assert!(
                    (x - y).abs() <= 1e-5 * y.abs().max(1e-3),
                    "{sampler} pixel {i}: {x} vs {y}"
                );
                let (x, y) = (var[i][c], wvar[i][c]);
                assert!(
                    (x - y).abs() <= 1e-4 * y.abs() + 1e-9,
                    "{sampler} variance {i}: {x} vs {y}"
                );
            }
        }
        // the same samples twice, or another max depth, are refused
        assert!(merge(&[input("a", &a), input("a", &a)]).is_err());
        let mut other = b.clone();
        other.metadata.insert("max_depth".into(), "5".into());
        let e = merge(&[input("a", &a), input("b", &other)]).unwrap_err();
        assert!(e.to_string().contains("max_depth"), "{e}");
    }
}

/// Issue 24: a film drops non-finite samples per pixel, so a pixel's mean can hold fewer
/// samples than the render's spp. Two renders of 16 spp whose pixels hold 16, 11, 0 and 3
/// samples (as drops leave them), written to EXR and read back, merge into exactly the mean
/// and variance of one film holding all their samples: the merge weighs each pixel by its
/// `samples` channel. Weighing by the metadata's spp (as before) gets the dropping pixels wrong
/// by up to 40 % here.
#[test]
fn merge_weighs_each_pixel_by_its_sample_count() {
    use glam::DVec3;
    use vrpt::film::Film;
    let dir = tempfile::tempdir().unwrap();
    let scene = common::shipped("cornell-box");
    // (count, value of each sample) per pixel of each input; the sums are exact in f64
    let inputs = [
        [(16u64, 1.0f64), (11, 2.0), (0, 0.0), (3, 4.0)],
        [(16, 3.0), (5, 0.5), (9, 1.5), (16, 2.5)],
    ];
    let mut films = Vec::new();
    let mut paths = Vec::new();
    for (k, pixels) in inputs.iter().enumerate() {
        let mut f = Film::new(2, 2);
        for (i, &(n, v)) in pixels.iter().enumerate() {
            // n samples: half at v, half at 2v (a variance that is not zero)
            let (lo, hi) = (n / 2, n - n / 2);
            let sum = v * lo as f64 + 2.0 * v * hi as f64;
            let sum_sq = v * v * lo as f64 + 4.0 * v * v * hi as f64;
            f.set_pixel_sums(i, DVec3::splat(sum), DVec3::splat(sum_sq), n);
        }
        let settings = RenderSettings {
            width: 2,
            height: 2,
            spp: 16,
            seed: 40 + k as u64,
            ..Default::default()
        };
        // the render's record of what it dropped, as a real one keeps it (merge checks that
        // the counts add up to spp × pixels less this)
        let kept: u64 = pixels.iter().map(|&(n, _)| n).sum();
        let stats = vrpt::render::RenderStats {
            nonfinite: 16 * 4 - kept,
            ..Default::default()
        };
        let meta = RenderMetadata::new(&scene, &settings, &stats);
        let path = dir.path().join(format!("{k}.exr"));
        write_exr(&path, &vrpt::output::render_image(&f, &meta)).unwrap();
        paths.push(path);
        films.push(f);
    }
    let read: Vec<MergeInput> = paths.iter().map(|p| MergeInput::read(p).unwrap()).collect();
    assert_eq!(read[0].image.samples.as_deref(), Some(&[16, 11, 0, 3][..]));
    let (m, meta) = merge(&read).unwrap();
    assert_eq!(meta.spp, 32);
    assert_eq!(meta.seeds(), [40, 41]);
    let mut all = films[0].clone();
    all.merge(&films[1]).unwrap();
    assert_eq!(m.samples.as_deref(), Some(&[32, 16, 9, 19][..]));
    let var = m.variance.as_ref().unwrap();
    for (i, v) in var.iter().enumerate() {
        let (want, want_var) = (all.mean(i).x as f32, all.variance_of_mean(i).x as f32);
        assert!(
            (m.pixels[i].x - want).abs() <= 1e-6 * want.abs(),
            "pixel {i}: merged {} but the samples' mean is {want}",
            m.pixels[i].x
        );
        assert!(
            (v.x - want_var).abs() <= 1e-5 * want_var.abs(),
            "pixel {i}: merged variance {} but {want_var}",
            v.x
        );
    }
}

/// The CLI path of a reference built in pieces: render twice, `vrpt merge`, `vrpt diff`.
#[test]
fn merge_and_diff_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let bin = env!("CARGO_BIN_EXE_vrpt");
    let scene = common::cornell_path();
    let run = |args: &[&str]| std::process::Command::new(bin).args(args).output().unwrap();
    for (name, first) in [("a.exr", "0"), ("b.exr", "8")] {
        let o = run(&[
            "render",
            scene.to_str().unwrap(),
            "--width",
            "8",
            "--height",
            "8",
            "--spp",
            "8",
            "--sampler",
            "independent",
            "--first-sample",
            first,
            "-q",
            "-o",
            &p(name),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let o = run(&["merge", &p("a.exr"), &p("b.exr"), "-o", &p("m.exr")]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m = read_exr(std::path::Path::new(&p("m.exr"))).unwrap();
    assert_eq!(m.metadata["spp"], "16");
    let o = run(&[
        "diff",
        &p("a.exr"),
        &p("m.exr"),
        "--error-map",
        &p("err.png"),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("MSE") && out.contains("relMSE") && out.contains("bias z"),
        "{out}"
    );
    // the 8x8 map drawn at 32x (256 px), at least 420 px wide for the colour bar's labels,
    // and the bar (48 px) below it
    let map = image::open(p("err.png")).unwrap().to_rgb8();
    assert_eq!(map.dimensions(), (420, 8 * 32 + 48));
    // each image pixel is one flat 32x32 block of its false colour
    for (x, y) in [(0, 0), (3, 5), (7, 7)] {
        let c = map.get_pixel(32 * x, 32 * y);
        assert_eq!(
            map.get_pixel(32 * x + 31, 32 * y + 31),
            c,
            "block ({x},{y})"
        );
    }
    // metrics per region: a named one and a file of two, each reported on its own line
    std::fs::write(
        p("regions.txt"),
        "# two halves\nleft 0,0,4,8\nright 4,0,4,8\n",
    )
    .unwrap();
    let o = run(&[
        "diff",
        &p("a.exr"),
        &p("m.exr"),
        "--region",
        "corner=0,0,2,2",
        "--regions",
        &p("regions.txt"),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    for name in ["corner", "left", "right"] {
        assert!(out.lines().any(|l| l.starts_with(name)), "{name}: {out}");
    }
    // a region outside the image, or malformed, is one line of error
    for bad in ["6,6,4,4", "1,2,3"] {
        let o = run(&["diff", &p("a.exr"), &p("m.exr"), "--region", bad]);
        assert!(!o.status.success(), "{bad}");
        assert_eq!(
            String::from_utf8_lossy(&o.stderr).lines().count(),
            1,
            "{bad}"
        );
    }
    // merging a render with itself is refused with one line
    let o = run(&["merge", &p("a.exr"), &p("a.exr"), "-o", &p("x.exr")]);
    assert!(!o.status.success());
    assert_eq!(String::from_utf8_lossy(&o.stderr).lines().count(), 1);
    // a stale reference (another scene) is refused
    let o = run(&[
        "compare",
        common::shipped_path("checker-plane").to_str().unwrap(),
        "--reference",
        &p("m.exr"),
        "--runs",
        "2",
        "-q",
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("reference"), "{err}");
    // adaptive runs need replicates to allocate from: refused with one line before any run,
    // and with them the table has each strategy's adaptive twin
    let (cornell, reference) = (scene.to_str().unwrap(), p("m.exr"));
    let adaptive = |extra: &[&str]| {
        let mut args = vec!["compare", cornell, "--reference", &reference];
        args.extend(["--runs", "2", "--strategies", "mis", "--spp", "4", "-q"]);
        args.extend(extra);
        run(&args)
    };
    let o = adaptive(&["--adaptive", "--replicates", "1"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("at least 2 replicates"), "{err}");
    let o = adaptive(&["--adaptive"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("mis adaptive") && out.contains("from its replicates"),
        "{out}"
    );
    // writing an EXR by hand with other metadata and reading it back keeps the keys
    let mut meta = BTreeMap::new();
    meta.insert("spp".to_string(), "1".to_string());
    write_exr(
        &dir.path().join("h.exr"),
        &RgbImage {
            width: 1,
            height: 1,
            pixels: vec![glam::Vec3::ONE],
            metadata: meta,
            ..RgbImage::default()
        },
    )
    .unwrap();
    assert_eq!(
        read_exr(&dir.path().join("h.exr")).unwrap().metadata["spp"],
        "1"
    );
}
