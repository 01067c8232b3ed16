//! Scaling of the accelerator and the renderer with triangle count: builds terrains of 10³…10⁶+
//! triangles and prints, per size, the BVH build time and memory, closest-hit throughput for
//! camera (coherent) and bounce-like (incoherent) rays on one thread, the time per ray, and a
//! whole render's samples/s on all threads.
//!
//! `cargo run --release --example scaling` (the README's scaling table comes from it).

use glam::{Vec2, Vec3};
use std::time::Instant;
use vrpt::accel::Accel;
use vrpt::material::Material;
use vrpt::math::{hash_words, u64_to_unit_f32};
use vrpt::render::{render, NoProgress, RenderSettings};
use vrpt::sampling::sample_uniform_hemisphere;
use vrpt::scene::generate::{terrain, terrain_side_for};
use vrpt::scene::{Mesh, MeshTriangle, Scene, SceneOptions};

fn u(i: usize, k: u64) -> f32 {
    u64_to_unit_f32(hash_words(&[i as u64, k]))
}

fn rays(coherent: bool, n: usize) -> Vec<(Vec3, Vec3)> {
    (0..n)
        .map(|i| {
            if coherent {
                let eye = Vec3::new(0.0, 1.5, 2.5);
                let side = (n as f64).sqrt() as usize;
                let (x, y) = (
                    (i % side) as f32 / side as f32,
                    (i / side) as f32 / side as f32,
                );
                let t = Vec3::new(-1.0 + 2.0 * x, 0.0, -1.0 + 2.0 * y);
                (eye, (t - eye).normalize())
            } else {
                let o = Vec3::new(-0.9 + 1.8 * u(i, 1), 0.3, -0.9 + 1.8 * u(i, 2));
                let d = sample_uniform_hemisphere(Vec2::new(u(i, 3), u(i, 4)));
                (o, Vec3::new(d.x, if i % 2 == 0 { -d.z } else { d.z }, d.y))
            }
        })
        .collect()
}

/// Closest-hit rays per second on this thread (best of 3).
fn mrays(accel: &Accel, rays: &[(Vec3, Vec3)]) -> f64 {
    (0..3)
        .map(|_| {
            let t = Instant::now();
            let mut hits = 0u32;
            for &(o, d) in rays {
                hits += accel.intersect(o, d, f32::INFINITY).is_some() as u32;
            }
            std::hint::black_box(hits);
            rays.len() as f64 / t.elapsed().as_secs_f64() / 1e6
        })
        .fold(0.0, f64::max)
}

fn main() {
    let sizes = [1_000usize, 10_000, 100_000, 1_000_000, 4_000_000];
    let coherent = rays(true, 1 << 16);
    let incoherent = rays(false, 1 << 16);
    println!(
        "| triangles | BVH build ms | BVH memory MB | coherent Mrays/s | ns/ray | incoherent Mrays/s | ns/ray | render M samples/s |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|");
    for n in sizes {
        let tris = terrain(terrain_side_for(n));
        let t = Instant::now();
        let accel = Accel::build(&tris);
        let build_ms = t.elapsed().as_secs_f64() * 1e3;
        let mem = accel.memory_bytes() as f64 / (1 << 20) as f64;
        let c = mrays(&accel, &coherent);
        let i = mrays(&accel, &incoherent);
        drop(accel);
        // a whole render: the terrain, grey and diffuse, under a white sky, 4 bounces
        let mesh = Mesh {
            triangles: tris
                .iter()
                .map(|&p| MeshTriangle {
                    p,
                    normals: None,
                    uvs: None,
                    material: 0,
                })
                .collect(),
        };
        let scene = Scene::build(
            "terrain".into(),
            mesh,
            vec![Material::diffuse("grey", Vec3::splat(0.6))],
            SceneOptions {
                camera: Some(vrpt::camera::CameraDesc {
                    eye: Vec3::new(0.0, 1.5, 2.5),
                    target: Vec3::ZERO,
                    up: Vec3::Y,
                    fov_deg: 45.0,
                }),
                environment: Some(Vec3::ONE.into()),
                ..Default::default()
            },
            Vec::new(),
        )
        .expect("terrain scene");
        let s = RenderSettings {
            width: 128,
            height: 128,
            spp: 8,
            max_depth: 5,
            ..Default::default()
        };
        let (_, stats) = render(&scene, &s, &NoProgress).expect("render");
        println!(
            "| {} | {build_ms:.1} | {mem:.1} | {c:.2} | {:.0} | {i:.2} | {:.0} | {:.2} |",
            tris.len(),
            1e3 / c,
            1e3 / i,
            stats.samples_per_second() / 1e6
        );
    }
}
