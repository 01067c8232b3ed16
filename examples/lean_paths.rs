//! What vrpt's integrator costs beyond its rays (issue 49): Mitsuba's estimator — independent
//! points, next-event estimation with points on the lights by area, cosine-weighted bounces,
//! Russian roulette from the third bounce, no MIS — written as one lean loop over a diffuse
//! scene, against vrpt's renderer with the same estimator (`--sampler independent --directions
//! cosine --lights nee --light-points area --edge-rays 0`), on one thread, in turn (A B A B).
//! Both trace with the same [`vrpt::accel::Accel`]; the loop has none of the renderer's
//! generality (materials, shading normals, textures, the sampler's dimensions, the film's
//! variance, the statistics), so the difference of their rates is what that generality costs
//! a sample. Both estimate the same image: their means are printed side by side.
//!
//! The estimator at a vertex `x` (normal `n` turned toward the ray, diffuse reflectance `ρ`):
//! a point `y` on the emitters chosen by area (pdf `1/A` over their total area `A`), added
//! unless something blocks the segment: `β · ρ/π · Le · cos θ_x · cos θ_y / |y − x|² · A`; then
//! a cosine-weighted direction (`β ← β·ρ`); emission counts only where a camera ray meets it
//! (front side). A path has at most `max_depth` vertices, as the renderer's.
//!
//! With `default` as the fourth argument the loop is the renderer's default estimator instead
//! (stratified points, Phong directions, light samples under MIS with the render's light choice
//! and points; [`lean_default`]) over the same tables, built from the library's sampler, light
//! sampler and BSDF: what that estimator costs a sample when its loop is as lean. With
//! `integrator` the same loop over the pixels calls the library's path loop ([`radiance`]) for
//! each sample. On Mitsuba's box, 256², 32 spp, 1 thread, 2026-11-30, four rounds in turn:
//! `default` 1.62–1.70 M samples/s, `integrator` 1.50–1.63, `vrpt render --edge-rays 0 --threads
//! 1` 1.50–1.53; image means equal to 10⁻⁷ (`default`) and to every printed digit
//! (`integrator`). Read the renderer's rate from the CLI: this example's own call of `render`
//! ran at 1.31–1.44 there (the renderer compiled into the example is slower than the binary; with
//! Mitsuba's estimator 1.75–1.78 against the CLI's 1.78–1.83).
//!
//! `cargo run --release --example lean_paths -- SCENE [SPP] [ROUNDS] [mitsuba|default|integrator]`
//! (a scene of diffuse materials, without textures or vertex normals, lit by one emitter — a
//! triangle, or a quad the renderer samples as one rectangle — and a black environment; its camera,
//! size and depth: on these the two choose the same points on the light; `default` takes Phong
//! materials too, any lights). On Mitsuba's box (`tools/peers/mitsuba_race.py` writes it), 256², 64
//! spp, 2026-11-30: the loop 3.03–3.10 M samples/s, the renderer 1.72–1.76
//! ([performance](../docs/performance.md)).

use glam::{DVec3, UVec2, Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, TAU};
use std::time::Instant;
use vrpt::accel::TraceStack;
use vrpt::bsdf::{Bsdf, Directions};
use vrpt::camera::Camera;
use vrpt::integrator::{mis_weight, radiance, RayCounts, RR_START_BOUNCE};
use vrpt::math::Frame;
use vrpt::render::{render, NoProgress, RenderSettings};
use vrpt::sampler::layout::{BounceSample, CameraSample, LightValues};
use vrpt::sampler::{Sampler, StratifiedSampler};
use vrpt::scene::Scene;
use vrpt::strategy::Strategy;

/// What the loop reads of a triangle (BVH order), and the emitters.
struct Tables {
    /// Unit geometric normal, `(v1 − v0) × (v2 − v0)` normalised (OBJ's front side).
    ng: Vec<Vec3>,
    kd: Vec<Vec3>,
    ke: Vec<Vec3>,
    /// The BSDF of each triangle's material (the default estimator's loop).
    bsdf: Vec<Bsdf>,
    /// The emissive triangles, their radiance and the running sum of their areas.
    lights: Vec<([Vec3; 3], Vec3, f32)>,
}

impl Tables {
    /// The tables of `scene`, whose materials must be plain (no maps, mirrors or glass) and
    /// its triangles flat; for Mitsuba's estimator also diffuse (`diffuse`), lit by one emitter
    /// and a black environment.
    fn of(scene: &Scene, diffuse: bool) -> Result<Tables, String> {
        let mut t = Tables {
            ng: vec![],
            kd: vec![],
            ke: vec![],
            bsdf: vec![],
            lights: vec![],
        };
        let mut area = 0.0;
        for prim in 0..scene.accel.len() as u32 {
            let v = scene.accel.vertices(prim);
            let m = &scene.materials[scene.shading[prim as usize].material as usize];
            let maps = m.maps.colour() || m.maps.perturbs_normal() || m.maps.opacity.is_some();
            if (diffuse && m.ks() != Vec3::ZERO) || m.specular.is_some() || maps {
                return Err(format!("material {} is not plain diffuse", m.name));
            }
            let s = &scene.shading[prim as usize];
            if s.normals.iter().any(|&n| n != s.ng) {
                return Err(format!("triangle {prim} has vertex normals"));
            }
            let c = (v[1] - v[0]).cross(v[2] - v[0]);
            t.ng.push(c.normalize_or_zero());
            t.kd.push(m.kd());
            t.ke.push(m.emission);
            t.bsdf.push(m.bsdf());
            if m.emission.max_element() > 0.0 {
                area += 0.5 * c.length();
                t.lights.push((v, m.emission, area));
            }
        }
        if !diffuse {
            return Ok(t);
        }
        if t.lights.is_empty() || scene.lights.emitters.len() != 1 {
            return Err("the loop needs one emitter (a triangle or a quad)".into());
        }
        if scene.environment().luminance_integral() > 0.0 {
            return Err("the loop needs a black environment".into());
        }
        Ok(t)
    }
}

/// xorshift32: the loop's stream of uniform numbers in [0, 1).
struct Rng(u32);

impl Rng {
    fn next(&mut self) -> f32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        (x >> 8) as f32 * (1.0 / 16_777_216.0)
    }
}

/// The image (a sum of radiance a pixel) of `spp` paths a pixel.
fn lean(scene: &Scene, t: &Tables, (w, h, spp, depth): (u32, u32, u32, u32)) -> Vec<Vec3> {
    let Some(camera) = Camera::new(&scene.camera, w, h) else {
        return vec![]; // a degenerate camera: the renderer says so
    };
    let eps = scene.ray_epsilon;
    let total_area = t.lights.last().map_or(0.0, |l| l.2);
    let mut rng = Rng(0x9E37_79B9);
    let mut stack = TraceStack::default();
    let mut film = vec![Vec3::ZERO; w as usize * h as usize];
    for (pixel, sum) in film.iter_mut().enumerate() {
        let at = UVec2::new(pixel as u32 % w, pixel as u32 / w);
        for _ in 0..spp {
            let (mut o, mut d) = camera.generate_ray(at, Vec2::new(rng.next(), rng.next()));
            let (mut beta, mut vertex) = (Vec3::ONE, 0);
            while let Some(hit) = scene.accel.intersect_with(&mut stack, o, d, f32::INFINITY) {
                let prim = hit.prim as usize;
                let (ng, kd) = (t.ng[prim], t.kd[prim]);
                let p = o + d * hit.t;
                let n = if ng.dot(d) < 0.0 { ng } else { -ng };
                if vertex == 0 && ng.dot(d) < 0.0 {
                    *sum += beta * t.ke[prim];
                }
                if kd == Vec3::ZERO {
                    break; // black: nothing more to gather (the renderer ends there too)
                }
                let (u0, u1, u2) = (rng.next(), rng.next(), rng.next());
                if vertex + 1 < depth {
                    let pick = u0 * total_area;
                    let last = &t.lights[t.lights.len() - 1];
                    let (v, le, _) = t.lights.iter().find(|l| pick < l.2).unwrap_or(last);
                    let s = u1.sqrt();
                    let y = v[0] * s * (1.0 - u2) + v[1] * (1.0 - s) + v[2] * (s * u2);
                    let ny = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
                    let (to, d2) = (y - p, (y - p).length_squared());
                    let wi = to / d2.sqrt();
                    let (cx, cy) = (n.dot(wi), -ny.dot(wi));
                    // the shadow ray from the offset point to y, as the renderer traces it
                    let from = p + n * eps;
                    let len = (y - from).length();
                    let tmax = len - 2.0 * eps;
                    if cx > 0.0
                        && cy > 0.0
                        && tmax > 0.0
                        && !scene
                            .accel
                            .occluded_with(&mut stack, from, (y - from) / len, tmax)
                    {
                        *sum += beta * kd * *le * (cx * cy / d2 * total_area * FRAC_1_PI);
                    }
                }
                let (b0, b1, rr) = (rng.next(), rng.next(), rng.next());
                let (sin, cos) = (b0 * TAU).sin_cos();
                let r = b1.sqrt();
                let local = Vec3::new(r * cos, r * sin, (1.0 - b1).max(0.0).sqrt());
                d = vrpt::math::Frame::from_normal(n).to_world(local);
                o = p + n * eps;
                beta *= kd;
                vertex += 1;
                if vertex >= depth {
                    break;
                }
                if vertex >= 3 {
                    let q = beta.max_element().min(0.95);
                    if rr >= q {
                        break;
                    }
                    beta /= q;
                }
            }
        }
    }
    film
}

/// The renderer's default estimator without edge rays, as one loop over the tables: stratified
/// points (one pass of `spp` a pixel, the renderer's layout of dimensions), Phong directions,
/// light samples by the render's chooser and points under MIS (power heuristic) with the
/// emission BSDF-sampled rays reach, Russian roulette from the third bounce. The sums of
/// radiance and of its square a pixel (in f64, as the film's).
///
/// With `library`, each sample's radiance is the library's [`radiance`] instead (the renderer's
/// path loop, called from this loop over the pixels: what the renderer's pixel, tile and pass
/// machinery costs beside it).
fn lean_default(
    scene: &Scene,
    t: &Tables,
    settings: &RenderSettings,
    library: bool,
) -> Vec<(DVec3, DVec3)> {
    let (w, h, spp, depth) = (
        settings.width,
        settings.height,
        settings.spp,
        settings.max_depth,
    );
    let Some(camera) = Camera::new(&scene.camera, w, h) else {
        return vec![];
    };
    let s = settings.strategy;
    let lights = scene.lights.sampler(s.light_points, s.light_choice);
    let values = LightValues::of(lights.any(), lights.chooses());
    let eps = scene.ray_epsilon;
    let mut sampler = StratifiedSampler::new(settings.seed, spp);
    let mut stack = TraceStack::default();
    let integrator = settings.integrator();
    let mut rays = RayCounts::default();
    let mut film = vec![(DVec3::ZERO, DVec3::ZERO); w as usize * h as usize];
    for (pixel, (sum, sum_sq)) in film.iter_mut().enumerate() {
        let at = UVec2::new(pixel as u32 % w, pixel as u32 / w);
        for index in 0..spp {
            sampler.start_pixel_sample(at, index);
            let u = CameraSample::draw(&mut sampler).pixel;
            let (mut o, mut d) = camera.generate_ray(at, u);
            if library {
                let l = radiance(
                    scene,
                    (o, d),
                    &mut sampler,
                    &integrator,
                    &mut rays,
                    &mut stack,
                );
                let l = l.as_dvec3();
                (*sum, *sum_sq) = (*sum + l, *sum_sq + l * l);
                continue;
            }
            let (mut beta, mut l) = (Vec3::ONE, Vec3::ZERO);
            // the vertex the ray left (point, normal, BSDF pdf of the direction)
            let mut prev: Option<(Vec3, Vec3, f32)> = None;
            for segment in 1..=depth {
                let Some(hit) = scene.accel.intersect_with(&mut stack, o, d, f32::INFINITY) else {
                    let le = scene.environment().radiance(d);
                    let w = prev.map_or(1.0, |(_, n, pdf)| {
                        mis_weight(pdf, lights.environment_pdf(n, d))
                    });
                    l += beta * le * w;
                    break;
                };
                let prim = hit.prim as usize;
                let (ng, ke) = (t.ng[prim], t.ke[prim]);
                let p = o + d * hit.t;
                let front = ng.dot(d) < 0.0;
                if front && ke != Vec3::ZERO {
                    let w = prev.map_or(1.0, |(q, n, pdf)| {
                        let i = scene.lights.light_of(hit.prim);
                        mis_weight(pdf, i.map_or(0.0, |i| lights.pdf(i, q, n, p)))
                    });
                    l += beta * ke * w;
                }
                let bsdf = &t.bsdf[prim];
                if segment == depth || bsdf.is_black() {
                    break;
                }
                let n = if front { ng } else { -ng };
                let frame = Frame::from_normal(n);
                let wo = frame.to_local(-d);
                let lobe = bsdf.chooses_lobe(Directions::Phong);
                let rr = segment >= RR_START_BOUNCE;
                let u = BounceSample::draw_needed(&mut sampler, values, lobe, rr, false);
                let spawn = p + n * eps;
                if let Some(ls) = lights.sample(p, n, u.light, u.light_point) {
                    let wi = frame.to_local(ls.wi);
                    let f = bsdf.eval(wo, wi);
                    if ls.wi.dot(n) > 0.0 && wi.z > 0.0 && f.max_element() > 0.0 {
                        let (to, tmax) = if ls.dist.is_finite() {
                            let y = p + ls.wi * ls.dist - spawn;
                            let len = y.length();
                            (y / len, len - 2.0 * eps)
                        } else {
                            (ls.wi, f32::INFINITY)
                        };
                        if tmax > 0.0 && !scene.accel.occluded_with(&mut stack, spawn, to, tmax) {
                            let pb = bsdf.pdf(wo, wi, Directions::Phong);
                            let w = mis_weight(ls.pdf, pb);
                            l += beta * f * ls.le * (wi.z * w / ls.pdf);
                        }
                    }
                }
                let Some(bs) = bsdf.sample(wo, u.lobe, u.direction, Directions::Phong) else {
                    break;
                };
                let wi = frame.to_world(bs.wi);
                if wi.dot(n) <= 0.0 {
                    break;
                }
                beta *= bs.f * (bs.wi.z / bs.pdf);
                if rr {
                    let q = beta.max_element().min(0.95);
                    if u.roulette >= q {
                        break;
                    }
                    beta /= q;
                }
                prev = Some((p, n, bs.pdf));
                (o, d) = (spawn, wi);
            }
            let l = l.as_dvec3();
            *sum += l;
            *sum_sq += l * l;
        }
    }
    film
}

fn mean(image: &[Vec3], scale: f32) -> Vec3 {
    image.iter().fold(Vec3::ZERO, |a, &b| a + b) / (image.len() as f32 * scale)
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        return Err("usage: lean_paths SCENE [SPP] [ROUNDS] [mitsuba|default|integrator]".into());
    };
    let number = |i: usize, default: u32| {
        args.get(i).map_or(Ok(default), |s| {
            s.parse::<u32>()
                .ok()
                .filter(|&n| n > 0)
                .ok_or(format!("{s}: not a positive whole number"))
        })
    };
    let (spp, rounds) = (number(2, 64)?, number(3, 3)?);
    let (default, library) = match args.get(4).map(String::as_str) {
        None | Some("mitsuba") => (false, false),
        Some("default") => (true, false),
        Some("integrator") => (true, true),
        Some(other) => {
            return Err(format!(
                "{other}: the loop is mitsuba, default or integrator"
            ))
        }
    };
    let scene = vrpt::scene::load(std::path::Path::new(path)).map_err(|e| e.to_string())?;
    let tables = Tables::of(&scene, !default)?;
    let mut settings = RenderSettings::for_scene(&scene);
    settings.spp = spp;
    settings.threads = Some(1);
    settings.edge_rays = 0;
    if !default {
        settings.strategy = Strategy::parse("independent+cosine+nee+area+tree")?;
    }
    let (w, h, depth) = (settings.width, settings.height, settings.max_depth);
    let samples = w as f64 * h as f64 * spp as f64;
    if Camera::new(&scene.camera, w, h).is_none() {
        return Err("the scene's camera is degenerate".into());
    }
    for round in 1..=rounds {
        let start = Instant::now();
        let image = if default {
            let sums = lean_default(&scene, &tables, &settings, library);
            sums.iter().map(|s| s.0.as_vec3()).collect()
        } else {
            lean(&scene, &tables, (w, h, spp, depth))
        };
        let lean_rate = samples / start.elapsed().as_secs_f64() / 1e6;
        let (film, stats) = render(&scene, &settings, &NoProgress).map_err(|e| e.to_string())?;
        let vrpt_rate = stats.samples as f64 / stats.elapsed.as_secs_f64() / 1e6;
        println!(
            "round {round}: lean loop {lean_rate:.3} M samples/s, mean {}; renderer {vrpt_rate:.3} \
             M samples/s, mean {}; renderer/loop time {:.2}",
            mean(&image, spp as f32),
            mean(&film.mean_image(), 1.0),
            lean_rate / vrpt_rate
        );
    }
    Ok(())
}
