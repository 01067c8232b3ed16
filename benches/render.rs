//! Whole renders of the shipped scenes at small size, per preset (the mission's four with BSDF
//! sampling only, then nee and mis): path samples per second (criterion's elements/s), on all
//! cores. The independent strategy is the baseline.

use clap::ValueEnum;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;
use vrpt::lights::LightPoints;
use vrpt::render::{render, NoProgress, RenderSettings};
use vrpt::strategy::{Preset, Strategy};

fn scenes(c: &mut Criterion) {
    // sun-sky: the environment map's sampling; textured: textures, cutouts, bump maps
    for name in [
        "cornell-box",
        "glossy-plates",
        "checker-plane",
        "sun-sky",
        "textured",
    ] {
        let scene = vrpt::scene::load(
            &Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("scenes")
                .join(name),
        )
        .expect("shipped scene");
        let (w, h, spp) = (64, 64, 16);
        let max_depth = scene.defaults.max_depth.unwrap_or(8);
        let mut g = c.benchmark_group(format!("render_{name}"));
        g.sample_size(10)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(3))
            .throughput(Throughput::Elements((w * h * spp) as u64));
        for preset in Preset::value_variants() {
            let st = preset.strategy();
            let s = RenderSettings {
                width: w,
                height: h,
                spp,
                max_depth,
                strategy: st,
                ..Default::default()
            };
            g.bench_with_input(BenchmarkId::from_parameter(st), &s, |b, s| {
                b.iter(|| black_box(render(&scene, s, &NoProgress).unwrap()))
            });
        }
        g.finish();
    }
}

/// The defaults' choices on the shipped Cornell box at 64×64, 16 spp (mis): each way of placing
/// points on the light, and the default render in four replicates (issue 33: the defaults are
/// chosen by efficiency; this holds what each choice costs).
fn defaults(c: &mut Criterion) {
    let scene =
        vrpt::scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box"))
            .expect("shipped scene");
    let (w, h, spp) = (64, 64, 16);
    let mut g = c.benchmark_group("render_defaults");
    g.sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
        .throughput(Throughput::Elements((w * h * spp) as u64));
    let base = RenderSettings {
        width: w,
        height: h,
        spp,
        ..Default::default()
    };
    let mut runs: Vec<(String, RenderSettings)> = LightPoints::value_variants()
        .iter()
        .map(|&p| {
            let strategy = Strategy {
                light_points: p,
                ..Strategy::default()
            };
            (
                format!("points_{p}"),
                RenderSettings {
                    strategy,
                    ..base.clone()
                },
            )
        })
        .collect();
    runs.push((
        "replicates_4".into(),
        RenderSettings {
            replicates: 4,
            ..base.clone()
        },
    ));
    for (name, s) in &runs {
        g.bench_with_input(BenchmarkId::from_parameter(name), s, |b, s| {
            b.iter(|| black_box(render(&scene, s, &NoProgress).unwrap()))
        });
    }
    g.finish();
}

/// Path guiding on the gap scene at 64×48, 64 spp (mis, stratified): Phong directions against
/// guided ones, the guided render's training (31 spp) included, as a user pays for it.
fn guided(c: &mut Criterion) {
    let scene = vrpt::scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/gap"))
        .expect("shipped scene");
    let (w, h, spp) = (64, 48, 64);
    let mut g = c.benchmark_group("render_guided");
    g.sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5))
        .throughput(Throughput::Elements((w * h * spp) as u64));
    for directions in [
        vrpt::bsdf::Directions::Phong,
        vrpt::bsdf::Directions::Guided,
    ] {
        let s = RenderSettings {
            width: w,
            height: h,
            spp,
            max_depth: 10,
            strategy: Strategy {
                directions,
                ..Strategy::default()
            },
            ..Default::default()
        };
        g.bench_with_input(BenchmarkId::from_parameter(directions), &s, |b, s| {
            b.iter(|| black_box(render(&scene, s, &NoProgress).unwrap()))
        });
    }
    g.finish();
}

/// Path reuse (`--reuse K`, issue 50) on the shipped Cornell box at 64×64, 16 spp (mis): the
/// whole render without reuse and with blocks of 2, 3 and 4, so the cost of the connections
/// (K² − 1 shadow rays and K² three-BSDF connections per pixel sample) shows per sample.
fn reuse(c: &mut Criterion) {
    let scene =
        vrpt::scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box"))
            .expect("shipped scene");
    let (w, h, spp) = (64, 64, 16);
    let mut g = c.benchmark_group("render_reuse");
    g.sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
        .throughput(Throughput::Elements((w * h * spp) as u64));
    for k in 1..=vrpt::render::MAX_REUSE {
        let s = RenderSettings {
            width: w,
            height: h,
            spp,
            reuse: k,
            ..Default::default()
        };
        g.bench_with_input(BenchmarkId::from_parameter(k), &s, |b, s| {
            b.iter(|| black_box(render(&scene, s, &NoProgress).unwrap()))
        });
    }
    g.finish();
}

/// Edge rays (`--edge-rays M`) on the shipped Cornell box at 64×64 (its light in view): the
/// whole render at 16 spp with M = 0, 16 and 64 (their cost falls on the edge pixels only), and
/// at 1 spp with M = 0 and 16, where the probe of four rays a pixel is most of the difference.
fn edge_rays(c: &mut Criterion) {
    let scene =
        vrpt::scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box"))
            .expect("shipped scene");
    let (w, h) = (64, 64);
    let mut g = c.benchmark_group("render_edges");
    g.sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    for (spp, m) in [(16, 0), (16, 16), (16, 64), (1, 0), (1, 16)] {
        let s = RenderSettings {
            width: w,
            height: h,
            spp,
            edge_rays: m,
            ..Default::default()
        };
        let id = BenchmarkId::from_parameter(format!("{spp}spp_{m}rays"));
        g.throughput(Throughput::Elements((w * h * spp) as u64));
        g.bench_with_input(id, &s, |b, s| {
            b.iter(|| black_box(render(&scene, s, &NoProgress).unwrap()))
        });
    }
    g.finish();
}

criterion_group!(benches, scenes, defaults, guided, reuse, edge_rays);
criterion_main!(benches);
