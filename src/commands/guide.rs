//! `vrpt guide`: what path guiding learned at one point of a scene, beside the truth.
//!
//! The guide of a guided render of the scene (its size, spp and seed: the same training, so the
//! same tree) is learned, and the camera ray through the centre of the chosen pixel is traced to
//! its first hit `x`. Two maps of the sphere of directions at `x`, both in the guide's
//! cylindrical equal-area map (`cosθ` from world +z down the rows, from +1 at the top, and `φ`
//! about +z along the columns, so that equal areas are equal solid angles):
//!
//! - **learned**: the density the guide samples at `x` (its leaf's quadtree), per unit area of
//!   the map: the radiance it learned less its mean, clamped at zero (MIS compensation,
//!   [`crate::guiding::DTree::compensated`]), so what lies below the mean is not drawn (the
//!   BSDF's own samples cover it);
//! - **incident**: the radiance arriving at `x` from each direction, by brute force: every texel
//!   the mean of `brute_spp` paths (`stratified+phong+mis`) from `x` through jittered directions
//!   of the texel, zero below the surface; normalized to a density like the other map.
//!
//! Both on one log colour scale. Under `nee` and `mis` the guide does not learn emitters that
//! `x` sees directly (next-event estimation carries them), so a light in view of `x` appears in
//! the right map only. The total variation distance between the two densities,
//! `½ Σ |p − q| ΔA`, says how much of the sampling mass sits where the light does not come from.

use super::{ImageArgs, Written};
use crate::analysis::maps::write_density_pair;
use crate::bsdf::Directions;
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::guiding::{canonical_to_dir, TreeSize};
use crate::image_io::{check_writable, Format};
use crate::integrator::{radiance, IntegratorSettings, RayCounts};
use crate::render::{learn_guide, RenderSettings};
use crate::sampler::{IndependentSampler, Sampler};
use crate::scene::Scene;
use crate::strategy::{Strategy, StrategyArgs};
use glam::{UVec2, Vec2, Vec3};
use rayon::prelude::*;
use std::path::PathBuf;

/// What to show: the flags of `vrpt guide`.
#[derive(Clone, Debug, clap::Args)]
pub struct GuideRequest {
    /// The scene: an .obj file, a scene.toml, or a folder holding a scene.toml.
    pub scene: PathBuf,
    /// The pixel whose first hit is shown: X,Y (column, row from the top left).
    #[arg(long, value_parser = parse_pixel)]
    pub pixel: (u32, u32),
    /// The PNG to write.
    #[arg(short, long, default_value = "guide.png")]
    pub output: PathBuf,
    /// The render whose guide is learned (its training takes about half its spp).
    #[command(flatten)]
    pub image: ImageArgs,
    #[command(flatten)]
    pub load: super::LoadArgs,
    /// Seed of the render whose guide is learned.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// The strategy, whose directions must be `guided` (the default here).
    #[command(flatten)]
    pub strategy: StrategyArgs,
    /// Paths per texel of the brute-force map of incident radiance.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..))]
    pub brute_spp: u32,
    /// Columns of each map (rows: half as many).
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(2..4097))]
    pub map_width: u32,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = crate::limits::parse_threads)]
    pub threads: Option<usize>,
}

impl GuideRequest {
    /// The strategy the flags ask for, with guided directions where they name none.
    pub fn strategy(&self) -> Result<Strategy> {
        let directions = self.strategy.directions.or(Some(Directions::Guided));
        let flags = StrategyArgs {
            directions,
            ..self.strategy
        };
        flags.resolve().map_err(Error::Settings)
    }
}

/// `X,Y` as two pixel coordinates.
pub fn parse_pixel(s: &str) -> std::result::Result<(u32, u32), String> {
    let (x, y) = s
        .split_once(',')
        .ok_or_else(|| format!("'{s}': give the pixel as X,Y"))?;
    let p = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("'{s}': pixel coordinates are whole numbers ≥ 0"))
    };
    Ok((p(x)?, p(y)?))
}

/// What was learned at the point.
#[derive(Clone, Debug)]
pub struct GuideOutcome {
    /// The first hit of the pixel's ray.
    pub point: Vec3,
    /// The total variation distance between the learned and the incident density.
    pub total_variation: f64,
    /// The whole tree's size, and the node count of the point's quadtree.
    pub tree: TreeSize,
    pub point_nodes: usize,
    /// Seconds of training.
    pub training_seconds: f64,
    pub written: Written,
}

impl GuideOutcome {
    /// What `vrpt guide` prints.
    pub fn summary(&self) -> String {
        format!(
            "first hit at ({:.3}, {:.3}, {:.3}): its quadtree has {} nodes; the tree {} leaves, \
             {} quadtree nodes, {:.2} MiB, trained in {:.2} s\n\
             total variation distance between the learned and the incident density: {:.3}\n\
             wrote {}\n",
            self.point.x,
            self.point.y,
            self.point.z,
            self.point_nodes,
            self.tree.leaves,
            self.tree.quad_nodes,
            self.tree.bytes as f64 / (1024.0 * 1024.0),
            self.training_seconds,
            self.total_variation,
            self.written.path.display()
        )
    }
}

/// Learn the guide, trace the pixel, draw both maps.
pub fn run(req: &GuideRequest) -> Result<GuideOutcome> {
    check_request(req)?;
    let (scene, settings) = load_scene(req)?;
    let (tree, stats) = learn_guide(&scene, &settings)?;
    let (point, n) = first_hit(&scene, &settings, req.pixel)?;
    let dtree = tree.sampling(tree.leaf_at(point));
    let (w, h) = (req.map_width, req.map_width / 2);
    let learned: Vec<f64> = (0..w * h)
        .map(|k| {
            let (i, j) = ((k % w) as f32 + 0.5, (k / w) as f32 + 0.5);
            dtree.pdf_canonical(canonical(i, j, (w, h))) as f64
        })
        .collect();
    let origin = point + n * scene.ray_epsilon;
    let mut incident = crate::render::with_threads(req.threads, || {
        incident_radiance(&scene, &settings, req, (origin, n))
    })?;
    let total_variation = total_variation(&learned, &mut incident, dtree.total() > 0.0);
    write_density_pair(
        &req.output,
        (&learned, &incident),
        (w, h),
        ("guide, as it samples", "incident radiance, brute force"),
        "density per unit area of the equal-area map, log scale",
    )?;
    Ok(GuideOutcome {
        point,
        total_variation,
        tree: tree.size(),
        point_nodes: dtree.node_count(),
        training_seconds: stats.elapsed.as_secs_f64(),
        written: Written {
            path: req.output.clone(),
            note: format!("total variation distance {total_variation:.3}"),
        },
    })
}

/// The checks on the request that need no scene: a guided strategy, a brute-force spp and map
/// width in range, and a PNG output that can be written and is not the scene.
fn check_request(req: &GuideRequest) -> Result<()> {
    let strategy = req.strategy()?;
    if strategy.directions != Directions::Guided {
        return Err(Error::Settings(format!(
            "vrpt guide shows a guided strategy's guide, not {} (use --directions guided)",
            strategy.axes_name()
        )));
    }
    if req.brute_spp == 0 || req.map_width < 2 {
        return Err(Error::Settings(
            "--brute-spp must be at least 1 and --map-width at least 2".into(),
        ));
    }
    if Format::from_path(&req.output)? != Format::Png {
        return Err(Error::Settings(format!(
            "{}: vrpt guide writes a PNG",
            req.output.display()
        )));
    }
    check_writable(&req.output)?;
    crate::image_io::check_outputs(&[("-o", &req.output)], &[("SCENE", &req.scene)])?;
    Ok(())
}

/// The scene and the settings of the render whose guide is learned (the scene's, overridden by
/// the request's); an error where the output would overwrite a file of the scene or the pixel
/// lies outside the image.
fn load_scene(req: &GuideRequest) -> Result<(Scene, RenderSettings)> {
    let scene = req.load.load(&req.scene)?;
    super::check_against_scene(&[("-o", &req.output)], &scene)?;
    let settings = RenderSettings {
        seed: req.seed,
        strategy: req.strategy()?,
        threads: req.threads,
        ..req.image.settings(&scene, None)
    };
    let (px, py) = req.pixel;
    if px >= settings.width || py >= settings.height {
        return Err(Error::Settings(format!(
            "pixel {px},{py} lies outside the {}x{} image",
            settings.width, settings.height
        )));
    }
    Ok((scene, settings))
}

/// The first hit of the camera ray through the centre of pixel `(px, py)`, and its geometric
/// normal turned towards the camera.
fn first_hit(
    scene: &Scene,
    settings: &RenderSettings,
    (px, py): (u32, u32),
) -> Result<(Vec3, Vec3)> {
    let camera = Camera::new(&scene.camera, settings.width, settings.height)
        .ok_or_else(|| Error::Settings("degenerate camera".into()))?;
    let (o, d) = camera.generate_ray(UVec2::new(px, py), Vec2::splat(0.5));
    let hit = scene
        .accel
        .intersect(o, d, f32::INFINITY)
        .ok_or_else(|| Error::Settings(format!("the ray of pixel {px},{py} hits nothing")))?;
    let s = scene.surface(&hit);
    let n = if s.ng.dot(-d) > 0.0 { s.ng } else { -s.ng };
    Ok((s.p, n))
}

/// The canonical `(u, v) = ((cosθ+1)/2, φ/2π)` of the point `(i, j)` of a `w`×`h` map, in
/// texels (column `i`: φ, row `j`: cosθ from +1 at the top).
fn canonical(i: f32, j: f32, (w, h): (u32, u32)) -> Vec2 {
    Vec2::new(1.0 - j / h as f32, i / w as f32)
}

/// The brute-force map of incident radiance at `origin`, row by row in parallel: each texel the
/// mean over `req.brute_spp` jittered directions of the grey radiance arriving from them, zero
/// below the surface of normal `n`; not yet a density.
fn incident_radiance(
    scene: &Scene,
    settings: &RenderSettings,
    req: &GuideRequest,
    (origin, n): (Vec3, Vec3),
) -> Vec<f64> {
    let (w, h) = (req.map_width, req.map_width / 2);
    // the incident radiance: paths one segment shorter than the render's, Phong directions, MIS
    let integrator = IntegratorSettings {
        max_depth: settings.max_depth.saturating_sub(1).max(1),
        directions: Directions::Phong,
        lights: crate::lights::LightStrategy::Mis,
        ..settings.integrator()
    };
    (0..h)
        .into_par_iter()
        .flat_map_iter(|j| {
            let mut stack = crate::accel::TraceStack::default();
            let mut rays = RayCounts::default();
            let mut sampler = IndependentSampler::new(req.seed ^ 0x6775_6964);
            (0..w)
                .map(|i| {
                    let mut sum = 0.0f64;
                    for k in 0..req.brute_spp {
                        sampler.start_pixel_sample(UVec2::new(i, j), k);
                        let u = sampler.next_2d();
                        let c = canonical(i as f32 + u.x, j as f32 + u.y, (w, h));
                        let dir = canonical_to_dir(c);
                        if dir.dot(n) <= 0.0 {
                            continue;
                        }
                        let l = radiance(
                            scene,
                            (origin, dir),
                            &mut sampler,
                            &integrator,
                            &mut rays,
                            &mut stack,
                        );
                        if l.is_finite() {
                            sum += ((l.x + l.y + l.z) / 3.0) as f64;
                        }
                    }
                    sum / req.brute_spp as f64
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

/// Scale `incident` to a density per unit area of the map (mean 1) and return the total
/// variation distance `½ Σ |p − q| ΔA` to `learned`: 1 where either map is all zero.
fn total_variation(learned: &[f64], incident: &mut [f64], learned_nonzero: bool) -> f64 {
    let texels = incident.len() as f64;
    let total: f64 = incident.iter().sum::<f64>() / texels;
    if total > 0.0 {
        incident.iter_mut().for_each(|v| *v /= total);
    }
    if total > 0.0 && learned_nonzero {
        0.5 * learned
            .iter()
            .zip(incident.iter())
            .map(|(p, q)| (p - q).abs())
            .sum::<f64>()
            / texels
    } else {
        1.0
    }
}
