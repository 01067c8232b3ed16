//! The edge pixels' tests: their allocation, their flags, and the edge rays in packets.

use super::*;
use crate::integrator::seen_emission;
use crate::render::settings::camera_for;
use crate::render::RenderSettings;

/// `λ` minimises `(S/λ + B)(C + c_e λ S)` (the image's MSE × time with `M_i = λ√a_i`, in
/// units of `c_e`) where the cost bound does not bind: the product is lower there than at
/// 0.8λ and 1.25λ; where `B` is 0 the edge rays cost [`EDGE_COST`] times the paths.
#[test]
fn the_allocation_is_the_optimum_of_mse_times_time() {
    let f = |lambda: f64, (pixels, paths, rays, b): (u64, u64, u64, f64), s: f64| {
        let c = pixels as f64 * 2.0 * rays as f64 / paths as f64;
        let big_b = b * pixels as f64 / (paths as f64 / 2.0);
        (s / lambda + big_b) * (c + lambda * s)
    };
    for (pilot, s) in [
        ((12288, 1536, 4600, 2.0), 40.0),
        ((49152, 6144, 30000, 900.0), 5.0),
        ((1024, 128, 500, 0.01), 3.0),
    ] {
        let (pixels, paths, rays, b) = pilot;
        let lambda = allocation_scale(pixels, (paths, rays, b), s);
        let bound = EDGE_COST * pixels as f64 * 2.0 * rays as f64 / paths as f64 / s;
        assert!(lambda > 0.0 && lambda <= bound);
        if lambda < bound * 0.999 {
            let here = f(lambda, pilot, s);
            assert!(here < f(0.8 * lambda, pilot, s) && here < f(1.25 * lambda, pilot, s));
        }
    }
    let lambda = allocation_scale(1000, (100, 100, 0.0), 10.0);
    assert!((lambda * 10.0 - EDGE_COST * 1000.0 * 2.0).abs() < 1e-6);
    assert_eq!(allocation_scale(1000, (0, 0, 0.0), 10.0), 0.0);
}

/// On the shipped Cornell box at 32×32 (its light in view), with each pixel's share of the
/// light measured on a 16×16 grid of camera rays: every pixel the light's edge crosses well
/// inside (a share of 0.1 to 0.9) is an edge pixel, and no edge pixel has a 3×3
/// neighbourhood the light covers wholly or not at all (grid share exactly 0 or 1
/// throughout): the flags are the edge, no more.
#[test]
fn the_edge_pixels_are_those_along_the_lights_edge() {
    let scene = crate::scene::load(std::path::Path::new("scenes/cornell-box")).unwrap();
    let settings = RenderSettings {
        width: 32,
        height: 32,
        ..RenderSettings::for_scene(&scene)
    };
    let camera = camera_for(&scene, &settings).unwrap();
    let image = UVec2::new(32, 32);
    let alloc = Allocation {
        seed: 1,
        integrator: settings.integrator(),
        most: MAX_EDGE_RAYS,
    };
    let map = EdgeMap::new(&scene, &camera, image, alloc);
    let (mut rays, mut stack) = (RayCounts::default(), TraceStack::default());
    let share: Vec<f32> = (0..32 * 32)
        .map(|i| {
            let pixel = UVec2::new(i % 32, i / 32);
            let mut lit = 0;
            for k in 0..256 {
                let u = Vec2::new((k % 16) as f32 + 0.5, (k / 16) as f32 + 0.5) / 16.0;
                let e = seen_emission(&scene, camera.generate_ray(pixel, u), &mut rays, &mut stack);
                lit += (e.max_element() > 0.0) as u32;
            }
            lit as f32 / 256.0
        })
        .collect();
    let mut partial = 0;
    for y in 0..32i32 {
        for x in 0..32i32 {
            let s = share[(y * 32 + x) as usize];
            let m = map.at(UVec2::new(x as u32, y as u32));
            let flagged = m > 0;
            assert!(m <= MAX_EDGE_RAYS);
            if (0.1..=0.9).contains(&s) {
                partial += 1;
                assert!(
                    flagged,
                    "pixel ({x}, {y}), {s} of it lit, is not an edge pixel"
                );
            }
            let around: Vec<f32> = (-1..=1)
                .flat_map(|dy| (-1..=1).map(move |dx| (x + dx, y + dy)))
                .filter(|&(a, b)| (0..32).contains(&a) && (0..32).contains(&b))
                .map(|(a, b)| share[(b * 32 + a) as usize])
                .collect();
            let uniform = around.iter().all(|&v| v == 0.0) || around.iter().all(|&v| v == 1.0);
            assert!(
                !(flagged && uniform),
                "pixel ({x}, {y}) is flagged in a uniform region"
            );
        }
    }
    assert!(
        partial >= 4,
        "the light's edge crosses only {partial} pixels"
    );
    // each tile probes its 16×16 pixels and the ring inside the image: 17×17, four rays
    // each; the pilot 16 more in each edge pixel, and two paths' camera rays in each of
    // its (32/4)² pixels
    let pilot = PILOT_EDGE_RAYS as u64 * map.count + 2 * 8 * 8;
    assert_eq!(map.rays.edge, 4 * 17 * 17 * 4 + pilot);
}

/// A render handed its edge map (as `--strategy auto` hands its pilots and its render the
/// map it found once) renders the same image as one that finds it, and counts only its own
/// rays: the finder's are not in its count (a pilot's cost in rays is its own). The render
/// that finds the map counts the map's rays, and says how many of its edge rays found it.
#[test]
fn a_handed_map_renders_the_same_and_counts_only_its_own_rays() {
    use crate::render::{render_passes, NoProgress, PassPlan};
    let scene = crate::scene::load(std::path::Path::new("scenes/cornell-box")).unwrap();
    let settings = RenderSettings {
        width: 32,
        height: 32,
        spp: 4,
        ..RenderSettings::for_scene(&scene)
    };
    let own = render_passes(&scene, &settings, &PassPlan::default(), &NoProgress).unwrap();
    let camera = camera_for(&scene, &settings).unwrap();
    let map = edge_map(&scene, &camera, &settings, &PassPlan::default()).unwrap();
    let plan = PassPlan {
        edges: Some(Arc::new(map)),
        ..PassPlan::default()
    };
    let handed = render_passes(&scene, &settings, &plan, &NoProgress).unwrap();
    let map = plan.edges.as_deref().unwrap();
    assert!(map.count > 0 && map.rays.total() > 0);
    assert_eq!(handed.film.mean_image(), own.film.mean_image());
    assert_eq!(handed.stats.edge_pixels, own.stats.edge_pixels);
    assert_eq!(
        (own.stats.rays.total(), own.stats.rays.edge),
        (
            handed.stats.rays.total() + map.rays.total(),
            handed.stats.rays.edge + map.rays.edge
        )
    );
    assert_eq!(
        (own.stats.edge_finding, handed.stats.edge_finding),
        (map.rays.edge, 0)
    );
}

/// The edge rays traced as packets give what they gave ray by ray, bit for bit, and count
/// the same rays: every pixel of a coarse Cornell box (the light's edge among them) and of
/// the sun and sky (whose sky's radiance differs from ray to ray, so that a sum in another
/// order would differ in its last bits; its blocks' boxes are tested first), for counts
/// that fill packets, leave one part-full and stay below one.
#[test]
fn edge_rays_in_packets_sum_as_ray_by_ray() {
    // a light whose radiance has all 24 bits (Mitsuba's box's, where a sum of its copies
    // in another grouping rounds differently; the shipped scenes' are short of bits) behind
    // a smaller dark square, which hides part of it
    let dir = std::env::temp_dir().join(format!("vrpt-edge-packets-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let obj = "mtllib l.mtl\nv -1 -1 -3\nv 1 -1 -3\nv 1 1 -3\nv -1 1 -3\n\
               v -0.4 -0.5 -2\nv 0.5 -0.4 -2\nv 0.3 0.6 -2\nusemtl light\nf 1 2 3 4\n\
               usemtl dark\nf 5 6 7\n";
    std::fs::write(dir.join("l.obj"), obj).unwrap();
    let mtl = "newmtl light\nKd 0 0 0\nKe 18.387 13.9873 6.75357\nnewmtl dark\nKd 0.5 0.5 0.5\n";
    std::fs::write(dir.join("l.mtl"), mtl).unwrap();
    let light = dir.join("l.obj");
    for (name, size) in [("scenes/cornell-box", 24), ("scenes/sun-sky", 6)] {
        edge_rays_in_packets_in(std::path::Path::new(name), size);
    }
    edge_rays_in_packets_in(&light, 12);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// [`edge_rays_in_packets_sum_as_ray_by_ray`] on `name` at `size`² pixels (few: a pixel
/// then spans many of the sky map's texels).
fn edge_rays_in_packets_in(name: &std::path::Path, size: u32) {
    let scene = crate::scene::load(name).unwrap();
    let settings = RenderSettings {
        width: size,
        height: size,
        ..RenderSettings::for_scene(&scene)
    };
    let camera = camera_for(&scene, &settings).unwrap();
    let mut stack = TraceStack::default();
    let mut lit = 0;
    for i in 0..size * size {
        let pixel = UVec2::new(i % size, i / size);
        for (m, index) in [(1u32, 3u64), (7, 0), (8, 5), (13, 2), (256, 1)] {
            let (mut by_packet, mut by_ray) = (RayCounts::default(), RayCounts::default());
            let got = seen_by_edge_rays(
                &scene,
                &camera,
                pixel,
                (9, index, m),
                &mut by_packet,
                &mut stack,
            );
            // the same points (the function's own Sobol points), one ray at a time
            let mut sum = Vec3::ZERO;
            for k in index * m as u64..(index + 1) * m as u64 {
                let words = [
                    9 ^ 0x4544_4745_2052_4159,
                    pixel.x as u64,
                    pixel.y as u64,
                    k >> 16,
                ];
                let scramble = hash_words(&words) as u32;
                let j = (k & 0xffff) as u32;
                let u = Vec2::new(
                    sobol_burley::sample(j, 0, scramble),
                    sobol_burley::sample(j, 1, scramble),
                );
                sum += seen_emission(
                    &scene,
                    camera.generate_ray(pixel, u),
                    &mut by_ray,
                    &mut stack,
                );
            }
            let want = sum / m as f32;
            assert_eq!(
                got.to_array().map(f32::to_bits),
                want.to_array().map(f32::to_bits),
                "{name:?} {pixel} m {m}"
            );
            assert_eq!(
                (by_packet.camera, by_packet.edge),
                (by_ray.camera, by_ray.edge)
            );
            lit += (want.max_element() > 0.0) as u32;
        }
    }
    // the light covers a few percent of the box's image, the sky half the other: some
    // pixels see them
    assert!(lit > 5, "{name:?}: {lit}");
}
