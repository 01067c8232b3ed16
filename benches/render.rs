//! Whole renders of the shipped scenes at small size, per preset (the mission's four with BSDF
//! sampling only, then nee and mis): path samples per second (criterion's elements/s), on all
//! cores. The independent strategy is the baseline.

use clap::ValueEnum;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;
use vrpt::render::{render, NoProgress, RenderSettings};
use vrpt::strategy::Preset;

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

criterion_group!(benches, scenes);
criterion_main!(benches);
