//! Edge rays (`--edge-rays M`, `vrpt::render::edges`): an unbiased estimator of the same image,
//! the same on any number of threads, changing only the pixels along an edge of emission, and
//! there with a much smaller variance.
//!
//! Unbiasedness is tested as path reuse's is (`reuse.rs`): each region's mean over `RUNS`
//! independent renders against a render without edge rays, `t` with `RUNS − 1` degrees of
//! freedom (an edge pixel's samples are points of one stratified set, so a render's own
//! per-sample variance would overstate its error: the runs' spread measures it), Šidák's
//! α = 0.001 over every test. A render that counted the light's edge twice (the path's camera
//! ray and the edge rays both) or not at all moves an edge pixel by a fraction of the light's
//! radiance (~17 on the Cornell box), its 4×4 region's mean by ~1/16 of that: tens of standard
//! errors at these samples.

use crate::common;
use crate::reuse::{regions, smallest_p};

use common::render_quiet;
use vrpt::integrator::rrs::Roulette;
use vrpt::render::RenderSettings;
use vrpt::sampler::SamplerKind;
use vrpt::stats::sidak;
use vrpt::strategy::Strategy;

/// A grey sphere under a sky map of radiance 1 with a sun of 5000 (a 2×2-texel disc of a 64×32
/// map, ~11° wide), the camera looking at the sun past the sphere: the sun's disc is a light in
/// the sky ([`vrpt::render::edges::SKY_STEP`]).
fn sun_scene(dir: &std::path::Path) -> vrpt::scene::Scene {
    use glam::Vec3;
    use vrpt::image_io::{write_exr, RgbImage};
    let mut pixels = vec![Vec3::ONE; 64 * 32];
    for (x, y) in [(40, 10), (41, 10), (40, 11), (41, 11)] {
        pixels[y * 64 + x] = Vec3::splat(5000.0);
    }
    let sky = RgbImage {
        width: 64,
        height: 32,
        pixels,
        ..RgbImage::default()
    };
    write_exr(&dir.join("sky.exr"), &sky).unwrap();
    common::write(dir, "s.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n");
    let obj = format!("mtllib s.mtl\n{}", common::icosphere_obj(1.0, 3, "grey"));
    common::write(dir, "s.obj", &obj);
    let toml = |target: Vec3| {
        format!(
            "obj = \"s.obj\"\n[camera]\neye = [0, 0, 0]\ntarget = [{}, {}, {}]\nfov = 30\n\
             [environment]\nmap = \"sky.exr\"\n",
            target.x, target.y, target.z
        )
    };
    common::write(dir, "scene.toml", &toml(Vec3::Z));
    let scene = vrpt::scene::load(dir).unwrap();
    let vrpt::environment::Environment::Map(m) = scene.environment() else {
        panic!("no map")
    };
    let sun = m.direction(glam::Vec2::new(41.0 / 64.0, 11.0 / 32.0));
    // from 4 units back along the sun's direction, the sphere beside the line of sight
    let eye = -4.0 * sun + 1.6 * sun.cross(Vec3::Y).normalize();
    let text = toml(eye + sun).replace(
        "eye = [0, 0, 0]",
        &format!("eye = [{}, {}, {}]", eye.x, eye.y, eye.z),
    );
    common::write(dir, "scene.toml", &text);
    vrpt::scene::load(dir).unwrap()
}

/// The shipped Cornell box (16×16, its light in view) with edge rays under the default strategy,
/// with independent points and path reuse, and with EARS's paths; and a sun in a sky map seen
/// directly: each agrees region by region with a render without edge rays.
#[test]
fn edge_rays_agree_with_the_path_tracer() {
    let independent = Strategy {
        sampler: SamplerKind::Independent,
        ..Strategy::default()
    };
    let dir = tempfile::tempdir().unwrap();
    // (scene, width, height, the (M, strategy, reuse, roulette) renders)
    type Case<'a> = (
        vrpt::scene::Scene,
        u32,
        u32,
        &'a [(u32, Strategy, u32, Roulette)],
    );
    let cases: [Case; 2] = [
        (
            common::shipped("cornell-box"),
            16,
            16,
            &[
                (8, Strategy::default(), 1, Roulette::Classic),
                (3, independent, 2, Roulette::Classic),
                (8, Strategy::default(), 1, Roulette::Ears),
            ],
        ),
        (
            sun_scene(dir.path()),
            16,
            16,
            &[(16, Strategy::default(), 1, Roulette::Classic)],
        ),
    ];
    let tests: usize = cases
        .iter()
        .map(|c| (c.1 / 4 * c.2 / 4) as usize * 3 * c.3.len())
        .sum();
    let alpha = sidak(1e-3, tests);
    for (s, (scene, w, h, runs)) in cases.into_iter().enumerate() {
        let name = scene.source.display().to_string();
        let base = RenderSettings {
            width: w,
            height: h,
            spp: 128,
            ..RenderSettings::for_scene(&scene)
        };
        let (reference, _) = render_quiet(
            &scene,
            &RenderSettings {
                spp: 8192,
                edge_rays: 0,
                seed: common::seed(7000 + s as u64),
                ..base.clone()
            },
        );
        let reference = regions(&reference);
        for (j, &(m, strategy, reuse, roulette)) in runs.iter().enumerate() {
            let settings = RenderSettings {
                edge_rays: m,
                strategy,
                reuse,
                roulette,
                ..base.clone()
            };
            // the renders spend edge rays: the map's finding (at least the probe's four a
            // pixel), then at least one a sample in each edge pixel it found
            let (_, stats) = render_quiet(&scene, &settings);
            let probe = 4 * (w * h) as u64;
            assert!(
                stats.edge_pixels > 0
                    && stats.edge_finding >= probe
                    && stats.rays.edge - stats.edge_finding
                        >= stats.edge_pixels * settings.spp as u64,
                "{name}: {} edge rays, {} of them finding {} edge pixels",
                stats.rays.edge,
                stats.edge_finding,
                stats.edge_pixels
            );
            let seed = common::seed(7100 + 100 * (4 * s + j) as u64);
            let (p, lit) = smallest_p(&scene, &settings, seed, &reference);
            // (the sun scene's sky regions, pure sky of radiance 1, are exact in both renders)
            assert!(2 * lit >= reference.len() * 3, "{name}: only {lit} lit");
            assert!(
                p >= alpha,
                "{name}, {m} edge rays, {strategy}, reuse {reuse}, {roulette}: a region \
                 disagrees with the reference (p {p:.2e} < {alpha:.2e})"
            );
        }
    }
}

/// Edge rays give the same image on 1 and 2 threads; against a render without them, only the
/// edge pixels change (the paths draw the same numbers: edge rays take their points from a
/// sequence of their own), and there the per-sample variance falls well below half: the
/// light's edge is a step of its whole radiance, which one camera ray a sample sees or misses,
/// where eight stratified ones a sample see its share (the ratio measured ~0.1).
#[test]
fn edge_rays_change_only_the_edge_pixels_and_lower_their_variance() {
    let scene = common::shipped("cornell-box");
    let base = RenderSettings {
        width: 40,
        height: 32,
        spp: 64,
        seed: common::seed(3),
        edge_rays: 8,
        ..RenderSettings::for_scene(&scene)
    };
    let render = |s: RenderSettings| render_quiet(&scene, &s).0;
    let one = render(RenderSettings {
        threads: Some(1),
        ..base.clone()
    });
    let two = render(RenderSettings {
        threads: Some(2),
        ..base.clone()
    });
    let off = render(RenderSettings {
        edge_rays: 0,
        ..base.clone()
    });
    let n = one.len();
    assert!((0..n).all(|i| one.mean(i) == two.mean(i)));
    let changed: Vec<usize> = (0..n).filter(|&i| one.mean(i) != off.mean(i)).collect();
    assert!(
        !changed.is_empty() && changed.len() * 10 <= n,
        "{} of {n} pixels changed: the edge pixels are a few",
        changed.len()
    );
    let var = |f: &vrpt::film::Film| -> f64 {
        changed
            .iter()
            .map(|&i| f.variance_of_mean(i).element_sum())
            .sum()
    };
    let (with, without) = (var(&one), var(&off));
    eprintln!(
        "{} edge pixels: variance of the mean {with:.3e} with edge rays, {without:.3e} without",
        changed.len()
    );
    assert!(with < 0.5 * without, "{with:.3e} against {without:.3e}");
}

/// A bad `--edge-rays` is one line and a non-zero exit; renders with other edge rays do not
/// merge (their estimators differ), and the metadata says which.
#[test]
fn edge_rays_flag_is_checked_and_recorded() {
    let cornell = common::cornell_path();
    let out = common::vrpt(&["render", cornell.to_str().unwrap(), "--edge-rays", "1000"]);
    common::assert_one_line_error(&out, "--edge-rays 1000", "--edge-rays");
    let dir = tempfile::tempdir().unwrap();
    let refusal = ["edge_rays is 0 (off) but"];
    let a = common::assert_merge_refused(dir.path(), "--edge-rays", ("8", "0"), &refusal);
    let img = vrpt::image_io::read_exr(&a).unwrap();
    let meta = vrpt::output::RenderMetadata::from_attributes(&img.metadata).unwrap();
    assert_eq!(meta.edge_rays, 8);
}
