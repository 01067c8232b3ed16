//! Path guiding's directional quadtrees: sampling agrees with the pdf (chi-square), the pdf
//! integrates to 1, and the maps between directions and the canonical square agree — for a
//! hand-built tree and for trees learned in the shipped Cornell box; and a guide handed to a
//! render is the guide it samples with.
//!
//! The chi-square bins the canonical square `[0,1)²` into a 32×32 grid. A quadtree's density is
//! constant on dyadic squares no deeper than the tree, so each bin's expected mass is computed
//! exactly by the midpoint rule on the `2^D × 2^D` grid, `D` the tree's depth (at least 5: a
//! bin is then a whole number of cells). Bins expecting fewer than 5 samples are pooled. The
//! bound: p > 1e-4 per tree (four trees; family-wise about 4e-4 under a right sampler); a
//! sampler that puts 5% of a quadrant of mass 0.2 elsewhere moves 200,000·0.01 = 2000 samples,
//! far beyond the ≈ √(4·10⁴) = 200 noise of such a quadrant: the power test shows it caught.

use crate::common;

use glam::{Vec2, Vec3};
use rand::{rngs::SmallRng, Rng, SeedableRng};
use vrpt::bsdf::Directions;
use vrpt::guiding::{canonical_to_dir, dir_to_canonical, DTree};
use vrpt::lights::LightStrategy;
use vrpt::render::{learn_guide, RenderSettings};
use vrpt::sampler::SamplerKind;
use vrpt::stats::chi2_sf;
use vrpt::strategy::Strategy;

const BINS: usize = 32;
const SAMPLES: usize = 200_000;

/// Expected probability per bin of `pdf` (piecewise constant on dyadic squares of depth ≤ `depth`).
fn expected(pdf: impl Fn(Vec2) -> f32, depth: u32) -> Vec<f64> {
    let cells = 1usize << depth.max(5);
    let per_bin = cells / BINS;
    let mut e = vec![0.0f64; BINS * BINS];
    let area = 1.0 / (cells * cells) as f64;
    for j in 0..cells {
        for i in 0..cells {
            let p = Vec2::new(
                (i as f32 + 0.5) / cells as f32,
                (j as f32 + 0.5) / cells as f32,
            );
            e[(j / per_bin) * BINS + i / per_bin] += pdf(p) as f64 * area;
        }
    }
    e
}

/// The chi-square p-value of `sample` against the bin probabilities `expected`, and the total
/// expected probability (the pdf's integral).
fn chi2(mut sample: impl FnMut(Vec2) -> Vec2, expected: &[f64], seed: u64) -> (f64, f64) {
    let mut rng = SmallRng::seed_from_u64(seed);
    let mut observed = vec![0.0f64; BINS * BINS];
    for _ in 0..SAMPLES {
        let p = sample(Vec2::new(rng.random(), rng.random()));
        assert!(p.x >= 0.0 && p.x < 1.0 && p.y >= 0.0 && p.y < 1.0, "{p}");
        let (i, j) = ((p.x * BINS as f32) as usize, (p.y * BINS as f32) as usize);
        observed[j.min(BINS - 1) * BINS + i.min(BINS - 1)] += 1.0;
    }
    let integral: f64 = expected.iter().sum();
    // pool bins expecting fewer than 5 samples, smallest first
    let mut bins: Vec<(f64, f64)> = expected
        .iter()
        .map(|e| e * SAMPLES as f64)
        .zip(observed)
        .collect();
    bins.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut pooled = Vec::new();
    let (mut pe, mut po) = (0.0, 0.0);
    for (e, o) in bins {
        if e < 5.0 || pe > 0.0 && pe < 5.0 {
            pe += e;
            po += o;
            if pe >= 5.0 {
                pooled.push((pe, po));
                pe = 0.0;
                po = 0.0;
            }
        } else {
            pooled.push((e, o));
        }
    }
    if pe > 0.0 {
        pooled.push((pe, po));
    }
    let stat: f64 = pooled
        .iter()
        .map(|(e, o)| {
            if *e > 0.0 {
                (o - e).powi(2) / e
            } else {
                *o * 1e9
            }
        })
        .sum();
    (chi2_sf(stat, (pooled.len() - 1) as f64), integral)
}

fn check_tree(name: &str, t: &DTree, seed: u64) {
    let e = expected(|p| t.pdf_canonical(p), t.depth() + 1);
    let (p, integral) = chi2(|u| t.sample_canonical(u), &e, seed);
    eprintln!(
        "{name}: {} nodes, depth {}, chi-square p {p:.4}, ∫pdf {integral:.6}",
        t.node_count(),
        t.depth()
    );
    assert!((integral - 1.0).abs() < 1e-4, "{name}: ∫pdf = {integral}");
    assert!(p > 1e-4, "{name}: chi-square p = {p}");
    // the world-direction routines are the canonical ones through the equal-area map
    let mut rng = SmallRng::seed_from_u64(seed + 1);
    for _ in 0..1000 {
        let u = Vec2::new(rng.random(), rng.random());
        let d = t.sample(u);
        assert!((d.length() - 1.0).abs() < 1e-5);
        let c = t.sample_canonical(u);
        assert!((canonical_to_dir(c) - d).length() < 1e-6);
        let back = dir_to_canonical(d);
        // dω = 4π du dv
        let (a, b) = (
            t.pdf(d),
            t.pdf_canonical(back) / (4.0 * std::f32::consts::PI),
        );
        assert!((a - b).abs() <= 1e-5 * a.max(b), "{a} {b}");
    }
}

/// A hand-built tree: uneven energies, a split quadrant, a zero-energy quadrant (never sampled,
/// pdf 0) and a deep chain.
fn hand_built() -> DTree {
    DTree::from_nodes(&[
        ([0.0, 0.0, 5.0, 1.0], [1, 0, 2, 0]),
        ([1.0, 3.0, 0.0, 2.0], [0, 0, 0, 3]),
        ([0.5, 0.25, 0.125, 4.0], [0, 0, 0, 0]),
        ([2.0, 1.0, 1.0, 7.0], [0, 0, 0, 4]),
        ([1.0, 2.0, 3.0, 4.0], [0, 0, 0, 0]),
    ])
}

#[test]
fn hand_built_quadtree_samples_its_pdf() {
    let t = hand_built();
    assert_eq!(t.depth(), 4);
    // a zero-energy quadrant has pdf 0 and is never drawn
    assert_eq!(t.pdf_canonical(Vec2::new(0.7, 0.2)), 0.0);
    check_tree("hand-built", &t, common::seed(1));
}

/// A sampler off by 5% is caught: the hand-built tree sampled with about 5% of the samples of
/// one root quadrant (u < ½, v ≥ ½: a fifth of the mass) mirrored into another, against the
/// true pdf.
#[test]
fn a_wrong_quadtree_sampler_is_caught() {
    let t = hand_built();
    let e = expected(|p| t.pdf_canonical(p), t.depth() + 1);
    let (p, _) = chi2(
        |u| {
            let c = t.sample_canonical(u);
            let in_q2 = c.x < 0.5 && c.y >= 0.5;
            // the quadrant's samples drawn with u.x < 0.05 (about 5% of them: the column is
            // chosen by u.x < 0.96, the row by u.y) land mirrored in the quadrant beside it
            if in_q2 && u.x < 0.05 {
                Vec2::new(1.0 - c.x, c.y).min(Vec2::splat(0.999_999))
            } else {
                c
            }
        },
        &e,
        common::seed(2),
    );
    assert!(p < 1e-10, "a 5% error must be caught: p = {p}");
}

/// Trees learned in the shipped Cornell box (guided MIS, 64×64 at 64 spp: 31 spp of training):
/// the leaves at a floor point, a wall point and the tall box's top.
#[test]
fn learned_quadtrees_sample_their_pdf() {
    let scene = common::shipped("cornell-box");
    let settings = RenderSettings {
        width: 64,
        height: 64,
        spp: 64,
        max_depth: 6,
        seed: common::seed(5),
        strategy: Strategy::of(
            SamplerKind::Stratified,
            Directions::Guided,
            LightStrategy::Mis,
        ),
        ..Default::default()
    };
    let (tree, stats) = learn_guide(&scene, &settings).unwrap();
    let g = stats.guide.expect("guided training reports itself");
    assert_eq!(g.training_spp, 31);
    assert!(tree.size().leaves > 1, "{:?}", tree.size());
    for (k, p) in [
        Vec3::new(278.0, 0.0, 280.0),
        Vec3::new(0.0, 300.0, 300.0),
        Vec3::new(370.0, 330.0, 350.0),
    ]
    .into_iter()
    .enumerate()
    {
        let t = tree.sampling(tree.leaf_at(p));
        assert!(t.total() > 0.0, "the leaf at {p} learned nothing");
        assert!(t.node_count() > 4, "{p}: {} nodes", t.node_count());
        check_tree(&format!("learned at {p}"), t, common::seed(10 + k as u64));
    }
}

/// A guide handed to a render ([`PassPlan::guide`], as `--strategy auto` hands over its guided
/// pilot's) is the guide the render samples with, and the render trains none of its own: a
/// guided render given the guide `learn_guide` learns with the render's own seeds and budget is
/// the render that trains it itself and discards its training images, bit for bit, with the
/// same training stats (keeping them, the image differs, and says so); given a guide
/// learned with another seed, its image differs (so the given guide is what sampled it); a
/// render whose directions are not guided ignores a given guide.
#[test]
fn a_handed_over_guide_renders_as_the_guide_learned_in_place() {
    use std::sync::Arc;
    use vrpt::render::{render_passes, LearnedGuide, NoProgress, PassPlan};
    let scene = common::shipped("cornell-box");
    let settings = RenderSettings {
        width: 32,
        height: 32,
        spp: 16,
        max_depth: 5,
        seed: common::seed(21),
        strategy: Strategy::of(
            SamplerKind::Stratified,
            Directions::Guided,
            LightStrategy::Mis,
        ),
        ..Default::default()
    };
    let learned = |settings: &RenderSettings| {
        let (tree, stats) = learn_guide(&scene, settings).unwrap();
        let stats = stats.guide.unwrap();
        Some(Arc::new(LearnedGuide { tree, stats }))
    };
    let render_with = |settings: &RenderSettings, guide, discard_training| {
        let plan = PassPlan {
            guide,
            discard_training,
            ..PassPlan::default()
        };
        render_passes(&scene, settings, &plan, &NoProgress).unwrap()
    };
    let render = |settings: &RenderSettings, guide| render_with(settings, guide, false);
    let own = render_with(&settings, None, true);
    assert_eq!(own.stats.guide.unwrap().combined, None);
    let kept = render(&settings, None);
    let c = kept
        .stats
        .guide
        .unwrap()
        .combined
        .expect("training images kept");
    // 16 spp: training 1 + 2 + 4 spp, the last two with a variance to weigh
    assert_eq!(c.iterations, 2);
    assert!(c.final_weight > 0.0 && c.final_weight < 1.0, "{c:?}");
    assert_ne!(kept.film.mean_image(), own.film.mean_image());
    assert_eq!(kept.film.count(0), own.film.count(0) + 6);
    let given = learned(&settings);
    let handed = render(&settings, given.clone());
    assert_eq!(handed.film.mean_image(), own.film.mean_image());
    let (a, b) = (handed.stats.guide.unwrap(), own.stats.guide.unwrap());
    assert_eq!(
        (a.iterations, a.training_spp),
        (b.iterations, b.training_spp)
    );
    assert_eq!(a.tree, b.tree);
    // the training's rays are the learner's, not the render's: the handed render traced fewer
    assert!(handed.stats.rays.total() < own.stats.rays.total());
    let other = learned(&RenderSettings {
        seed: common::seed(22),
        ..settings.clone()
    });
    assert_ne!(
        render(&settings, other).film.mean_image(),
        own.film.mean_image()
    );
    let phong = RenderSettings {
        strategy: Strategy::default(),
        ..settings.clone()
    };
    let plain = render(&phong, None);
    let ignored = render(&phong, given);
    assert_eq!(ignored.film.mean_image(), plain.film.mean_image());
    assert!(ignored.stats.guide.is_none());
}

/// An image's mean and the variance of that mean: the sum of its pixels' variances of the mean
/// over the pixels squared (independent pixels).
fn image_mean(film: &vrpt::film::Film) -> (glam::DVec3, glam::DVec3) {
    let (mut m, mut v) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
    for i in 0..film.len() {
        m += film.mean(i);
        v += film.variance_of_mean(i);
    }
    let n = film.len() as f64;
    (m / n, v / (n * n))
}

/// The guide's gate (`vrpt::render::gate`) on the scenes it was built for, at 128×96 pixels and
/// 256 spp (64 on the door; training up to half: its iterations from 16 spp on hold 2¹⁷ paths),
/// seeds 1–3. On the glossy plates, whose guide learns nothing NEE and the Phong lobes
/// do not already carry, the probes read Phong directions more efficient (1.4–1.9× at z 5 to 61
/// over seeds and sizes while building it) and the gate closes: the training ends, the image
/// holds the probes, the final iteration samples with Phong directions (with path reuse too,
/// seed 1: its training and probes render without reuse); on the door, where
/// the light comes through a slit, it opens for good (the guide ahead at z −4 to −34). The
/// closed image is unbiased: its mean against a `--directions phong` render of the same size
/// and 256 spp, `z = Δ/√(σ_a² + σ_b²)` per channel with each image mean's variance the sum of its
/// pixels' variances of the mean over the pixels squared (independent pixels; each image
/// holds 3M paths or more, so the mean is near normal); nine tests, bound 4.4 (two-sided,
/// about 1e-4 in all; with `--reuse 4` on seed 1 three more: ten in all).
#[test]
fn the_gate_closes_on_the_glossy_plates_and_opens_on_the_door() {
    use vrpt::render::{gate::Verdict, render_passes, NoProgress, PassPlan};
    let settings = |name: &str, seed: u64, directions| RenderSettings {
        width: 128,
        height: 96,
        spp: if name == "door" { 64 } else { 256 },
        max_depth: if name == "door" { 10 } else { 4 },
        seed: common::seed(seed),
        strategy: Strategy::of(SamplerKind::Stratified, directions, LightStrategy::Mis),
        ..Default::default()
    };
    let plates = common::shipped("glossy-plates");
    let door = common::shipped("door");
    for seed in 1..=3 {
        let plan = PassPlan::default();
        let s = settings("glossy-plates", seed, Directions::Guided);
        let r = render_passes(&plates, &s, &plan, &NoProgress).unwrap();
        let g = r.stats.guide.unwrap();
        let gate = g.gate.expect("the plates' training reaches the probes");
        assert_eq!(gate.verdict, Verdict::Closed, "seed {seed}: {gate:?}");
        assert!(gate.last.unwrap().ratio > 1.0, "{gate:?}");
        let c = g.combined.expect("training images kept");
        assert_eq!(c.probes, gate.readings, "{c:?}");
        assert!(g.training_spp < 127, "the training ended early: {g:?}");
        let phong = RenderSettings {
            seed: common::seed(100 + seed),
            ..settings("glossy-plates", seed, Directions::Phong)
        };
        let p = render_passes(&plates, &phong, &plan, &NoProgress).unwrap();
        let ((ma, va), (mb, vb)) = (image_mean(&r.film), image_mean(&p.film));
        let z = (ma - mb) / (va + vb).powf(0.5);
        assert!(z.abs().max_element() < 4.4, "seed {seed}: z {z}");
        if seed == 1 {
            // with path reuse the gate reads the same (training and probes both render
            // without reuse) and closes; the probes and training images are not kept
            let s = RenderSettings { reuse: 4, ..s };
            let r = render_passes(&plates, &s, &plan, &NoProgress).unwrap();
            let g = r.stats.guide.unwrap();
            let gate = g.gate.expect("the reusing render gates too");
            assert_eq!(gate.verdict, Verdict::Closed, "reuse: {gate:?}");
            assert!(g.combined.is_none() && g.training_spp < 127, "{g:?}");
            let (mr, vr) = image_mean(&r.film);
            let z = (mr - mb) / (vr + vb).powf(0.5);
            assert!(z.abs().max_element() < 4.4, "reuse: z {z}");
        }

        let r = render_passes(
            &door,
            &settings("door", seed, Directions::Guided),
            &plan,
            &NoProgress,
        )
        .unwrap();
        let gate = r
            .stats
            .guide
            .unwrap()
            .gate
            .expect("the door's training reaches the probes");
        assert_eq!(gate.verdict, Verdict::Open, "seed {seed}: {gate:?}");
        assert!(gate.last.unwrap().z < -3.0, "seed {seed}: {gate:?}");
    }
}

/// The gate's early look (`Gate::looking_early`: `--strategy auto`'s guided twin where no light
/// came as caustics), at 128×96 with `--reuse 4` and 64 spp, seed 1: the first probe comes at
/// 16 spp (2¹⁷ paths), the early look at 8 spp against that probe's first half. On the glossy
/// plates (Phong directions 1.4–1.9× as efficient: the test above) it closes the gate at 8 spp,
/// the training ends after 15 spp, and the image is unbiased (its mean against a Phong render's,
/// as above: three tests, bound 4.4). On the door, where the guide wins, it does not close, and
/// the render is the one without it: the same reading at 16 spp (the probe's halves pooled add
/// its sums in another order: within 1e-9) and the same image, bit for bit.
#[test]
fn the_early_look_closes_where_the_guide_loses_and_changes_nothing_else() {
    use vrpt::render::{gate::Verdict, render_passes, NoProgress, PassPlan};
    let settings = |directions, max_depth| RenderSettings {
        width: 128,
        height: 96,
        spp: 64,
        max_depth,
        reuse: 4,
        seed: common::seed(1),
        strategy: Strategy::of(SamplerKind::Stratified, directions, LightStrategy::Mis),
        ..Default::default()
    };
    let early = PassPlan {
        gate_early: true,
        ..PassPlan::default()
    };
    let plates = common::shipped("glossy-plates");
    let r = render_passes(
        &plates,
        &settings(Directions::Guided, 4),
        &early,
        &NoProgress,
    )
    .unwrap();
    let g = r.stats.guide.unwrap();
    let gate = g.gate.expect("the plates' training reaches the early look");
    assert_eq!(gate.verdict, Verdict::Closed, "{gate:?}");
    assert_eq!((gate.readings, gate.last.unwrap().spp), (1, 8), "{gate:?}");
    assert!(gate.record().contains("an early look"), "{}", gate.record());
    assert_eq!(g.training_spp, 15, "{g:?}");
    let phong = RenderSettings {
        seed: common::seed(101),
        reuse: 1,
        ..settings(Directions::Phong, 4)
    };
    let p = render_passes(&plates, &phong, &PassPlan::default(), &NoProgress).unwrap();
    let ((ma, va), (mb, vb)) = (image_mean(&r.film), image_mean(&p.film));
    let z = (ma - mb) / (va + vb).powf(0.5);
    assert!(z.abs().max_element() < 4.4, "z {z}");

    let door = common::shipped("door");
    let s = settings(Directions::Guided, 10);
    let looked = render_passes(&door, &s, &early, &NoProgress).unwrap();
    let plain = render_passes(&door, &s, &PassPlan::default(), &NoProgress).unwrap();
    let gate = |r: &vrpt::render::Rendered| r.stats.guide.unwrap().gate.unwrap();
    let (a, b) = (gate(&looked), gate(&plain));
    assert!(a.early && !b.early, "{a:?} {b:?}");
    assert_eq!(a.verdict, Verdict::Open, "{a:?}");
    assert_eq!(
        (a.verdict, a.readings),
        (b.verdict, b.readings),
        "{a:?} {b:?}"
    );
    let (ra, rb) = (a.last.unwrap(), b.last.unwrap());
    assert!(
        ra.spp == 16 && (ra.ratio / rb.ratio - 1.0).abs() < 1e-9,
        "{ra:?} {rb:?}"
    );
    assert_eq!(looked.film.mean_image(), plain.film.mean_image());
}
