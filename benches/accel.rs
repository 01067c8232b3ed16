//! BVH build time and ray throughput (closest hit and occlusion; coherent camera rays and
//! incoherent bounce-like rays) on generated terrains of 10³…10⁶ triangles, against a
//! brute-force loop over all triangles at small sizes. Throughput is reported in elements/s =
//! rays/s.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use std::hint::black_box;
use std::time::Duration;
use vrpt::accel::Accel;
use vrpt::math::{hash_words, u64_to_unit_f32};
use vrpt::sampling::sample_uniform_hemisphere;
use vrpt::scene::generate::{terrain, terrain_side_for};

const SIZES: [usize; 4] = [1_000, 10_000, 100_000, 1_000_000];
const RAYS: usize = 1 << 14;

fn u(i: usize, k: u64) -> f32 {
    u64_to_unit_f32(hash_words(&[i as u64, k]))
}

/// Camera rays: a 128×128 grid looking down at the terrain from above at a slant.
fn coherent_rays() -> Vec<(Vec3, Vec3)> {
    let eye = Vec3::new(0.0, 1.5, 2.5);
    (0..RAYS)
        .map(|i| {
            let (x, y) = ((i % 128) as f32 / 127.0, (i / 128) as f32 / 127.0);
            let target = Vec3::new(-1.0 + 2.0 * x, 0.0, -1.0 + 2.0 * y);
            (eye, (target - eye).normalize())
        })
        .collect()
}

/// Bounce-like rays: origins on the terrain's surface layer, directions uniform over the upper
/// hemisphere (half of them hit the terrain again nearby, half escape).
fn incoherent_rays() -> Vec<(Vec3, Vec3)> {
    (0..RAYS)
        .map(|i| {
            let o = Vec3::new(-0.9 + 1.8 * u(i, 1), 0.3, -0.9 + 1.8 * u(i, 2));
            let d = sample_uniform_hemisphere(glam::Vec2::new(u(i, 3), u(i, 4)));
            // hemisphere about -y for half, +y for the other half
            let d = Vec3::new(d.x, if i % 2 == 0 { -d.z } else { d.z }, d.y);
            (o, d)
        })
        .collect()
}

fn build(c: &mut Criterion) {
    let mut g = c.benchmark_group("bvh_build");
    g.sample_size(10).warm_up_time(Duration::from_secs(1));
    for n in SIZES {
        let tris = terrain(terrain_side_for(n));
        g.throughput(Throughput::Elements(tris.len() as u64));
        g.bench_with_input(BenchmarkId::from_parameter(tris.len()), &tris, |b, t| {
            b.iter(|| black_box(Accel::build(t)))
        });
    }
    g.finish();
}

fn trace(c: &mut Criterion) {
    for (kind, rays) in [
        ("coherent", coherent_rays()),
        ("incoherent", incoherent_rays()),
    ] {
        let mut g = c.benchmark_group(format!("trace_{kind}"));
        g.sample_size(20)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(3))
            .throughput(Throughput::Elements(RAYS as u64));
        for n in SIZES {
            let accel = Accel::build(&terrain(terrain_side_for(n)));
            let id = accel.len();
            g.bench_with_input(BenchmarkId::new("closest", id), &accel, |b, a| {
                b.iter(|| {
                    let mut hits = 0u32;
                    for &(o, d) in &rays {
                        hits += a.intersect(o, d, f32::INFINITY).is_some() as u32;
                    }
                    black_box(hits)
                })
            });
            g.bench_with_input(BenchmarkId::new("occluded", id), &accel, |b, a| {
                b.iter(|| {
                    let mut hits = 0u32;
                    for &(o, d) in &rays {
                        hits += a.occluded(o, d, f32::INFINITY) as u32;
                    }
                    black_box(hits)
                })
            });
            if n <= 1_000 {
                // the baseline: every ray against every triangle (only a slice of the rays)
                let few = &rays[..RAYS / 16];
                g.throughput(Throughput::Elements(few.len() as u64));
                g.bench_with_input(BenchmarkId::new("brute_force", id), &accel, |b, a| {
                    b.iter(|| {
                        let mut hits = 0u32;
                        for &(o, d) in few {
                            hits += a.intersect_brute_force(o, d, f32::INFINITY).is_some() as u32;
                        }
                        black_box(hits)
                    })
                });
                g.throughput(Throughput::Elements(RAYS as u64));
            }
        }
        g.finish();
    }
}

criterion_group!(benches, build, trace);
criterion_main!(benches);
