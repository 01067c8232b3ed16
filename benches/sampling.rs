//! Samplers and warps: draws per second. The independent sampler is the baseline; the
//! stratified sampler adds a hashed permutation per dimension. Each iteration draws one path
//! sample's worth of dimensions (the renderer's layout: camera, then 4 bounces) for 4096
//! samples.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::{UVec2, Vec2};
use std::hint::black_box;
use std::time::Duration;
use vrpt::sampler::layout::{BounceSample, CameraSample, BOUNCE_DIMS, CAMERA_DIMS};
use vrpt::sampler::{IndependentSampler, Sampler, SobolSampler, StratifiedSampler};
use vrpt::sampling::*;

const SAMPLES: u32 = 4096;
/// Bounces per path sample.
const BOUNCES: usize = 4;
/// Dimensions drawn per sample.
const DRAWS: u64 = (CAMERA_DIMS.len() + BOUNCES * BOUNCE_DIMS.len()) as u64;

fn draw_path<S: Sampler>(s: &mut S) -> f32 {
    let mut acc = 0.0;
    for i in 0..SAMPLES {
        s.start_pixel_sample(UVec2::new(7, 3), i);
        acc += CameraSample::draw(s).pixel.x;
        for _ in 0..BOUNCES {
            let b = BounceSample::draw(s, true);
            acc += b.lobe + b.direction.y + b.roulette;
        }
    }
    acc
}

fn samplers(c: &mut Criterion) {
    let mut g = c.benchmark_group("sampler_draws");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(SAMPLES as u64 * DRAWS));
    let mut ind = IndependentSampler::new(1);
    g.bench_function("independent", |b| b.iter(|| black_box(draw_path(&mut ind))));
    let mut st = StratifiedSampler::new(1, SAMPLES);
    g.bench_function("stratified", |b| b.iter(|| black_box(draw_path(&mut st))));
    let mut so = SobolSampler::new(1);
    g.bench_function("sobol", |b| b.iter(|| black_box(draw_path(&mut so))));
    g.finish();
}

/// Draws as a render makes them: 64 pixels, each a whole pass of 64 samples of a 4-bounce path
/// (per-pixel work such as a table build is paid 64 times per iteration, as in a render).
fn draw_pixels<S: Sampler>(s: &mut S) -> f32 {
    let mut acc = 0.0;
    for p in 0..PIXELS {
        let pixel = UVec2::new(p % 8, p / 8);
        for i in 0..PASS {
            s.start_pixel_sample(pixel, i);
            acc += CameraSample::draw(s).pixel.x;
            for _ in 0..BOUNCES {
                let b = BounceSample::draw(s, true);
                acc += b.lobe + b.direction.y + b.roulette;
            }
        }
    }
    acc
}

const PIXELS: u32 = 64;
const PASS: u32 = 64;

fn samplers_in_pixels(c: &mut Criterion) {
    let mut g = c.benchmark_group("sampler_draws_per_pixel");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements((PIXELS * PASS) as u64 * DRAWS));
    let mut ind = IndependentSampler::new(1);
    g.bench_function("independent", |b| {
        b.iter(|| black_box(draw_pixels(&mut ind)))
    });
    let mut st = StratifiedSampler::new(1, PASS);
    g.bench_function("stratified", |b| b.iter(|| black_box(draw_pixels(&mut st))));
    let mut so = SobolSampler::new(1);
    g.bench_function("sobol", |b| b.iter(|| black_box(draw_pixels(&mut so))));
    g.finish();
}

/// The warps, each direction's three components summed (with `z` alone the compiler dropped
/// the azimuth's `sin_cos` from the uniform and Phong warps, whose `z` does not need it).
fn warps(c: &mut Criterion) {
    let mut g = c.benchmark_group("warps");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(SAMPLES as u64));
    let us: Vec<Vec2> = (0..SAMPLES)
        .map(|i| {
            Vec2::new(
                (i as f32 + 0.5) / SAMPLES as f32,
                ((i * 7919) % SAMPLES) as f32 / SAMPLES as f32,
            )
        })
        .collect();
    g.bench_function("uniform_hemisphere", |b| {
        b.iter(|| {
            us.iter()
                .map(|&u| sample_uniform_hemisphere(u).element_sum())
                .sum::<f32>()
        })
    });
    g.bench_function("cosine_hemisphere", |b| {
        b.iter(|| {
            us.iter()
                .map(|&u| sample_cosine_hemisphere(u).element_sum())
                .sum::<f32>()
        })
    });
    g.bench_function("phong_lobe_n100", |b| {
        b.iter(|| {
            us.iter()
                .map(|&u| sample_phong_lobe(100.0, u).element_sum())
                .sum::<f32>()
        })
    });
    g.bench_function("phong_lobe_pdf_n100", |b| {
        b.iter(|| us.iter().map(|&u| phong_lobe_pdf(100.0, u.x)).sum::<f32>())
    });
    g.finish();
}

/// A receiver of the light benches: point, normal, the light choice's and the point's numbers.
type Receiver = (glam::Vec3, glam::Vec3, f32, Vec2);

/// [`SAMPLES`] receivers, the `i`-th at `place(i, a, b)` (point and normal) with `a`, `b`
/// spread over `[0, 1)` (a rank-1 lattice), and the numbers `b` and `(a, 1 − b)`.
fn spread_receivers(place: impl Fn(u32, f32, f32) -> (glam::Vec3, glam::Vec3)) -> Vec<Receiver> {
    (0..SAMPLES)
        .map(|i| {
            let (a, b) = (
                (i as f32 + 0.5) / SAMPLES as f32,
                ((i * 7919) % SAMPLES) as f32 / SAMPLES as f32,
            );
            let (p, n) = place(i, a, b);
            (p, n, b, Vec2::new(a, 1.0 - b))
        })
        .collect()
}

/// One light sample for each of `receivers`, the sum of their pdfs kept.
fn bench_light_samples(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    sampler: &vrpt::lights::LightSampler,
    receivers: &[Receiver],
) {
    g.bench_function(name, |b| {
        b.iter(|| {
            receivers
                .iter()
                .filter_map(|&(p, n, u, v)| sampler.sample(p, n, u, v))
                .map(|s| s.pdf)
                .sum::<f32>()
        })
    });
}

/// One light sample per receiver on the shipped night hall (160 emitters): choose a light
/// (uniform, power, tree) and place a point on it (area, solid angle, projected), for 4096
/// receivers spread over the floor and walls. `choose` alone is the cost of a tree lookup;
/// `pmf` is what MIS pays for a BSDF sample that hits an emitter.
fn lights(c: &mut Criterion) {
    use glam::Vec3;
    use vrpt::lights::{LightChoice, LightPoints};
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/night-hall");
    let scene = vrpt::scene::load(std::path::Path::new(path)).expect("the shipped night hall");
    let receivers = spread_receivers(|i, a, b| match i % 3 {
        0 | 1 => (Vec3::new(8.0 * a - 4.0, 0.0, -60.0 * b), Vec3::Y),
        _ => (Vec3::new(-4.0, 4.4 * a, -60.0 * b), Vec3::X),
    });
    let mut g = c.benchmark_group("lights");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(SAMPLES as u64));
    for choice in [LightChoice::Uniform, LightChoice::Power, LightChoice::Tree] {
        let sampler = scene.lights.sampler(LightPoints::Area, choice);
        g.bench_function(format!("choose_{choice}"), |b| {
            b.iter(|| {
                receivers
                    .iter()
                    .filter_map(|&(p, n, u, _)| sampler.choose(p, n, u))
                    .map(|(_, pmf)| pmf)
                    .sum::<f32>()
            })
        });
    }
    let tree = scene.lights.sampler(LightPoints::Area, LightChoice::Tree);
    g.bench_function("pmf_tree", |b| {
        b.iter(|| {
            receivers
                .iter()
                .enumerate()
                .map(|(i, &(p, n, _, _))| tree.pmf(p, n, (i % 160) as u32))
                .sum::<f32>()
        })
    });
    for points in [
        LightPoints::Area,
        LightPoints::SolidAngle,
        LightPoints::Projected,
        LightPoints::Auto,
    ] {
        let sampler = scene.lights.sampler(points, LightChoice::Tree);
        bench_light_samples(
            &mut g,
            &format!("sample_{points}_tree"),
            &sampler,
            &receivers,
        );
    }
    g.finish();
}

/// One light sample per receiver in the shipped Cornell box: one quad light, so this is the
/// light sampler's cost where there is nothing to choose (the race box's case), for 4096
/// receivers spread over the floor, the back wall and the left wall, with the default `auto`
/// points (solid angle where the light looks large, area elsewhere) and area points alone.
fn lights_one(c: &mut Criterion) {
    use glam::Vec3;
    use vrpt::lights::{LightChoice, LightPoints};
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell-box");
    let scene = vrpt::scene::load(std::path::Path::new(path)).expect("the shipped Cornell box");
    let receivers = spread_receivers(|i, a, b| match i % 3 {
        0 => (Vec3::new(550.0 * a, 0.0, 559.0 * b), Vec3::Y),
        1 => (Vec3::new(550.0 * a, 548.0 * b, 559.0), Vec3::NEG_Z),
        _ => (Vec3::new(556.0, 548.0 * a, 559.0 * b), Vec3::NEG_X),
    });
    let mut g = c.benchmark_group("lights_one");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(SAMPLES as u64));
    for points in [LightPoints::Area, LightPoints::Auto] {
        let sampler = scene.lights.sampler(points, LightChoice::Tree);
        bench_light_samples(&mut g, &format!("sample_{points}"), &sampler, &receivers);
        g.bench_function(format!("pdf_{points}"), |b| {
            b.iter(|| {
                receivers
                    .iter()
                    .map(|&(p, n, _, v)| {
                        sampler.pdf(
                            0,
                            p,
                            n,
                            Vec3::new(213.0 + 130.0 * v.x, 548.0, 227.0 + 105.0 * v.y),
                        )
                    })
                    .sum::<f32>()
            })
        });
    }
    g.finish();
}

/// The environment map of sun-sky: a direction drawn by luminance, and the pdf of a direction.
fn environment(c: &mut Criterion) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/sun-sky");
    let scene = vrpt::scene::load(std::path::Path::new(path)).expect("the shipped sun-sky");
    let map = scene.environment().map().expect("sun-sky's sky is a map");
    let us: Vec<Vec2> = (0..SAMPLES)
        .map(|i| {
            Vec2::new(
                (i as f32 + 0.5) / SAMPLES as f32,
                ((i * 7919) % SAMPLES) as f32 / SAMPLES as f32,
            )
        })
        .collect();
    let dirs: Vec<glam::Vec3> = us
        .iter()
        .filter_map(|&u| map.sample(u).map(|s| s.0))
        .collect();
    let mut g = c.benchmark_group("environment");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(SAMPLES as u64));
    g.bench_function("sample_map", |b| {
        b.iter(|| {
            us.iter()
                .filter_map(|&u| map.sample(u))
                .map(|s| s.2)
                .sum::<f32>()
        })
    });
    g.bench_function("pdf_map", |b| {
        b.iter(|| dirs.iter().map(|&d| map.pdf(d)).sum::<f32>())
    });
    g.bench_function("radiance_map", |b| {
        b.iter(|| dirs.iter().map(|&d| map.radiance(d).x).sum::<f32>())
    });
    g.finish();
}

/// Path guiding's lookups on a guide learned on the gap scene (64×48, 256 spp: 127 spp of
/// training, a few hundred leaves), at receivers on the dark room's floor: the leaf of a point
/// (the S-tree descent each vertex pays), a guided direction with its density (one quadtree
/// descent), and the density of a given direction (an `atan2` and a descent: what a BSDF-sampled
/// direction and NEE's MIS weight pay).
fn guide(c: &mut Criterion) {
    use glam::Vec3;
    use vrpt::guiding::{dir_to_canonical, GuideAt};
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/gap");
    let scene = vrpt::scene::load(std::path::Path::new(path)).expect("the shipped gap");
    let settings = vrpt::render::RenderSettings {
        width: 64,
        height: 48,
        spp: 256,
        max_depth: 10,
        strategy: vrpt::strategy::Strategy {
            directions: vrpt::bsdf::Directions::Guided,
            ..Default::default()
        },
        ..Default::default()
    };
    let (tree, _) = vrpt::render::learn_guide(&scene, &settings).expect("a guide");
    let points: Vec<(Vec3, Vec2, Vec3)> = (0..SAMPLES)
        .map(|i| {
            let (a, b) = (
                (i as f32 * 0.754_877_7).fract(),
                (i as f32 * 0.569_840_3).fract(),
            );
            let d = Vec3::new(a - 0.5, b, 0.3 - a * b).normalize();
            (Vec3::new(4.0 * a, 0.0, 5.0 * b), Vec2::new(b, a), d)
        })
        .collect();
    let mut g = c.benchmark_group("guide");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(SAMPLES as u64));
    g.bench_function("leaf", |b| {
        b.iter(|| points.iter().map(|&(p, _, _)| tree.leaf_at(p)).sum::<u32>())
    });
    let at: Vec<GuideAt> = points
        .iter()
        .map(|&(p, _, _)| GuideAt::new(&tree, p))
        .collect();
    g.bench_function("sample_with_pdf", |b| {
        b.iter(|| {
            at.iter()
                .zip(&points)
                .map(|(g, &(_, u, _))| g.dtree.sample_canonical_pdf(u).1)
                .sum::<f32>()
        })
    });
    g.bench_function("dir_to_canonical", |b| {
        b.iter(|| {
            (points.iter())
                .map(|&(_, _, d)| dir_to_canonical(black_box(d)).y)
                .sum::<f32>()
        })
    });
    g.bench_function("pdf_of_direction", |b| {
        b.iter(|| {
            at.iter()
                .zip(&points)
                .map(|(g, &(_, _, d))| g.guide_pdf_canonical(dir_to_canonical(d)))
                .sum::<f32>()
        })
    });
    g.finish();
}

/// One EARS decision (`--roulette ears`): the factor at a vertex, its octree lookup (the
/// deepest node on the way down that has learned the outgoing direction's bin) and the rule,
/// on a cache taught 10⁶ records spread over the unit box with a bright corner (two
/// iterations: 73 nodes, the 64 cells it starts with split where a bin passed 4096
/// records), at points spread the same way: about 22 ns a decision (criterion, 2-core EPYC).
fn ears(c: &mut Criterion) {
    use glam::Vec3;
    use vrpt::integrator::rrs::{direction_bin, RrsCache, RrsLearned, RrsPath, RrsRecord};
    let mut cache = RrsCache::new(Vec3::ZERO, Vec3::ONE);
    let point = |i: u32| {
        let f = |k: f32| (i as f32 * k).fract();
        Vec3::new(f(0.754_877_7), f(0.569_840_3), f(0.438_579_6))
    };
    for _ in 0..2 {
        for i in 0..500_000u32 {
            let p = point(i);
            let lr = Vec3::splat(if p.max_element() > 0.9 { 10.0 } else { 0.1 } * (i % 3) as f32);
            let r = RrsRecord {
                p,
                bin: (i % 16) as u8,
                first: false,
                lr,
                cost: 2.0 + (i % 5) as f32,
            };
            cache.add(&r);
        }
        cache.finish_iteration();
    }
    let path = RrsPath {
        learned: RrsLearned {
            cache: Some(&cache),
            image: 3.0,
        },
        pixel_norm: Vec3::splat(2.0),
        extra: 64,
        records: None,
    };
    let at: Vec<(Vec3, u8, Vec3)> = (0..SAMPLES)
        .map(|i| {
            let p = point(i * 7 + 3);
            let wo = Vec3::new(p.y - 0.5, p.z - 0.5, p.x - 0.5).normalize();
            (p, direction_bin(wo), Vec3::splat(0.2 + p.x))
        })
        .collect();
    let mut g = c.benchmark_group("ears");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(SAMPLES as u64));
    eprintln!("ears: a cache of {} nodes", cache.len());
    g.bench_function("factor", |b| {
        b.iter(|| {
            at.iter()
                .map(|&(p, bin, beta)| path.factor(p, bin, beta, 2))
                .sum::<f32>()
        })
    });
    g.finish();
}

criterion_group!(
    benches,
    ears,
    samplers,
    samplers_in_pixels,
    warps,
    lights,
    lights_one,
    environment,
    guide
);
criterion_main!(benches);
