//! BVH build time, the load of an OBJ scene to its BVH (`load_obj`), and ray throughput
//! (closest hit and occlusion; coherent camera rays and
//! incoherent bounce-like rays) on generated terrains of 10³…10⁶ triangles, against a
//! brute-force loop over all triangles at small sizes. Throughput is reported in elements/s =
//! rays/s.
//!
//! `trace_cornell` traces the rays of real paths in the shipped Cornell box (camera rays, their
//! diffuse bounces and the shadow rays toward light samples, recorded once): the bare traversal
//! rate to hold against the ray rate inside a render (`vrpt render --stats` prints both the
//! render's rate and its rate while tracing), one by one and 8 to a packet
//! (`Accel::intersect_packet`, `Accel::occluded_packet`).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::{UVec2, Vec2, Vec3};
use std::hint::black_box;
use std::time::Duration;
use vrpt::accel::{Accel, RayPacket, LANES};
use vrpt::camera::Camera;
use vrpt::lights::{LightChoice, LightPoints};
use vrpt::math::Frame;
use vrpt::math::{hash_words, u64_to_unit_f32};
use vrpt::sampling::{sample_cosine_hemisphere, sample_uniform_hemisphere};
use vrpt::scene::generate::{terrain, terrain_side_for};
use vrpt::scene::Scene;

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

/// Rays of real paths in the shipped Cornell box, by kind: closest-hit rays (camera and
/// bounces) and shadow rays `(origin, direction, tmax)`. One path per pixel of the scene's
/// 256×256 camera, up to 4 bounces with cosine-distributed directions about the side the ray
/// came from, and a shadow ray toward a light sample at every vertex, as the renderer makes them.
#[allow(clippy::type_complexity)]
fn cornell_rays() -> (Scene, Vec<(Vec3, Vec3)>, Vec<(Vec3, Vec3, f32)>) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell-box");
    let scene = vrpt::scene::load(std::path::Path::new(path)).expect("the shipped Cornell box");
    let camera = Camera::new(&scene.camera, 256, 256).expect("its camera");
    let (mut closest, mut shadow) = (Vec::new(), Vec::new());
    let lights = scene.lights.sampler(LightPoints::Area, LightChoice::Power);
    for i in 0..256 * 256usize {
        let (mut o, mut d) = camera.generate_ray(
            UVec2::new((i % 256) as u32, (i / 256) as u32),
            Vec2::new(u(i, 1), u(i, 2)),
        );
        for bounce in 0..5u64 {
            closest.push((o, d));
            let Some(hit) = scene.accel.intersect(o, d, f32::INFINITY) else {
                break;
            };
            let s = scene.surface(&hit);
            let n = if s.ng.dot(d) < 0.0 { s.ng } else { -s.ng };
            let spawn = s.p + n * scene.ray_epsilon;
            let k = 10 * bounce;
            if let Some(ls) =
                lights.sample(s.p, n, u(i, k + 3), Vec2::new(u(i, k + 4), u(i, k + 5)))
            {
                if ls.wi.dot(n) > 0.0 && ls.dist.is_finite() {
                    shadow.push((spawn, ls.wi, ls.dist - 2.0 * scene.ray_epsilon));
                }
            }
            if bounce == 4 {
                break;
            }
            let local = sample_cosine_hemisphere(Vec2::new(u(i, k + 6), u(i, k + 7)));
            (o, d) = (spawn, Frame::from_normal(n).to_world(local));
        }
    }
    (scene, closest, shadow)
}

fn trace_cornell(c: &mut Criterion) {
    let (scene, closest, shadow) = cornell_rays();
    let mut g = c.benchmark_group("trace_cornell");
    g.sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    g.throughput(Throughput::Elements(closest.len() as u64));
    g.bench_function("closest", |b| {
        b.iter(|| {
            let mut hits = 0u32;
            for &(o, d) in &closest {
                hits += scene.accel.intersect(o, d, f32::INFINITY).is_some() as u32;
            }
            black_box(hits)
        })
    });
    // the same rays 8 to a packet (`Accel::intersect_packet`: in lanes on a small scene)
    let mut stack = vrpt::accel::TraceStack::default();
    g.bench_function("closest_packets", |b| {
        b.iter(|| {
            let (mut hits, mut p) = (0u32, RayPacket::new());
            let mut out = [None; LANES];
            for rays in closest.chunks(LANES) {
                p.clear();
                for (lane, &(o, d)) in rays.iter().enumerate() {
                    p.set(lane, o, d, f32::INFINITY);
                }
                scene.accel.intersect_packet(&mut stack, &p, &mut out);
                hits += out[..rays.len()].iter().filter(|h| h.is_some()).count() as u32;
            }
            black_box(hits)
        })
    });
    g.throughput(Throughput::Elements(shadow.len() as u64));
    g.bench_function("shadow_packets", |b| {
        b.iter(|| {
            let (mut hits, mut p) = (0u32, RayPacket::new());
            for rays in shadow.chunks(LANES) {
                p.clear();
                for (lane, &(o, d, t)) in rays.iter().enumerate() {
                    p.set(lane, o, d, t);
                }
                hits += scene.accel.occluded_packet(&mut stack, &p).count_ones();
            }
            black_box(hits)
        })
    });
    g.bench_function("shadow", |b| {
        b.iter(|| {
            let mut hits = 0u32;
            for &(o, d, t) in &shadow {
                hits += scene.accel.occluded(o, d, t) as u32;
            }
            black_box(hits)
        })
    });
    g.finish();
}

/// A height field of `side`² quads (2·side² triangles) as OBJ text: shared vertices with
/// normals, faces `f a//a b//b c//c d//d`, as a scanned mesh is written.
fn grid_obj(side: usize) -> String {
    use std::fmt::Write;
    let h = |x: f32, z: f32| 0.1 * (7.0 * x).sin() * (5.0 * z).cos();
    let mut s = String::from("mtllib none.mtl\n");
    let n = side + 1;
    for k in 0..n * n {
        let (x, z) = ((k % n) as f32 / side as f32, (k / n) as f32 / side as f32);
        writeln!(s, "v {x:.6} {:.6} {z:.6}", h(x, z)).unwrap();
    }
    for k in 0..n * n {
        let (x, z) = ((k % n) as f32 / side as f32, (k / n) as f32 / side as f32);
        let n = Vec3::new(
            -0.7 * (7.0 * x).cos() * (5.0 * z).cos(),
            1.0,
            0.5 * (7.0 * x).sin() * (5.0 * z).sin(),
        );
        let n = n.normalize();
        writeln!(s, "vn {:.5} {:.5} {:.5}", n.x, n.y, n.z).unwrap();
    }
    for z in 0..side {
        for x in 0..side {
            let i = z * n + x + 1;
            let (a, b, c, d) = (i, i + 1, i + n + 1, i + n);
            writeln!(s, "f {a}//{a} {d}//{d} {c}//{c} {b}//{b}").unwrap();
        }
    }
    s
}

/// Loading a scene from its OBJ to its BVH (`scene::load`: parse, mesh, BVH, shading data), on
/// height fields of 10⁵ and 10⁶ triangles written once to a temporary file.
fn load(c: &mut Criterion) {
    let mut g = c.benchmark_group("load_obj");
    g.sample_size(10).warm_up_time(Duration::from_secs(1));
    let dir = std::env::temp_dir().join(format!("vrpt-bench-load-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for side in [224, 708] {
        let path = dir.join(format!("grid{side}.obj"));
        std::fs::write(&path, grid_obj(side)).unwrap();
        let tris = 2 * side * side;
        g.throughput(Throughput::Elements(tris as u64));
        g.bench_with_input(BenchmarkId::from_parameter(tris), &path, |b, p| {
            b.iter(|| black_box(vrpt::scene::load(p).unwrap()))
        });
    }
    g.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, build, load, trace, trace_cornell);
criterion_main!(benches);
