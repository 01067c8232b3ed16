//! The render loop: rayon over 16×16 tiles; per pixel, samples `first_sample ..
//! first_sample + spp` from a [`Sampler`] through the [`integrator`] into a [`Film`].
//!
//! Each pixel's samples are summed in index order by one thread, and each draw depends only on
//! (seed, pixel, sample index, dimension), so the image is bit-identical whatever the number of
//! threads or the order in which tiles finish. Non-finite samples are counted and dropped (the
//! pixel's count excludes them), never written into the image.

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::film::Film;
use crate::integrator::{radiance, IntegratorSettings};
use crate::material::Directions;
use crate::sampler::{IndependentSampler, Sampler, SamplerKind, StratifiedSampler};
use crate::scene::Scene;
use glam::{DVec3, UVec2};
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// Tile edge in pixels.
pub const TILE: u32 = 16;

/// What to render, and how.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Index of the first sample (a render of samples `k..k+spp` merges with one of `0..k`).
    pub first_sample: u32,
    pub max_depth: u32,
    pub seed: u64,
    pub sampler: SamplerKind,
    pub directions: Directions,
    /// Worker threads; `None` uses rayon's global pool (all cores).
    pub threads: Option<usize>,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 256,
            height: 256,
            spp: 16,
            first_sample: 0,
            max_depth: 8,
            seed: 0,
            sampler: SamplerKind::default(),
            directions: Directions::default(),
            threads: None,
        }
    }
}

/// Counts and times of one render.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderStats {
    pub elapsed: Duration,
    /// Rays traced (camera and bounce rays).
    pub rays: u64,
    /// Path samples taken (including dropped ones).
    pub samples: u64,
    /// Samples dropped because their radiance was NaN or infinite.
    pub nonfinite: u64,
}

impl RenderStats {
    /// Millions of rays per second of wall time.
    pub fn mrays_per_second(&self) -> f64 {
        self.rays as f64 / self.elapsed.as_secs_f64().max(1e-9) / 1e6
    }

    /// Path samples per second of wall time.
    pub fn samples_per_second(&self) -> f64 {
        self.samples as f64 / self.elapsed.as_secs_f64().max(1e-9)
    }
}

/// Something told how many pixels are done (a progress bar).
pub trait Progress: Sync {
    fn advance(&self, pixels: u64);
}

impl Progress for indicatif::ProgressBar {
    fn advance(&self, pixels: u64) {
        self.inc(pixels);
    }
}

/// No progress reporting.
pub struct NoProgress;

impl Progress for NoProgress {
    fn advance(&self, _: u64) {}
}

/// Render `scene` with `settings` into a new film.
pub fn render(
    scene: &Scene,
    settings: &RenderSettings,
    progress: &dyn Progress,
) -> Result<(Film, RenderStats)> {
    if settings.width == 0 || settings.height == 0 || settings.spp == 0 || settings.max_depth == 0 {
        return Err(Error::Settings(
            "width, height, spp and max depth must be at least 1".into(),
        ));
    }
    let camera = Camera::new(&scene.camera, settings.width, settings.height).ok_or_else(|| {
        Error::Settings(format!(
            "degenerate camera (eye {}, target {}, up {}, fov {}°)",
            scene.camera.eye, scene.camera.target, scene.camera.up, scene.camera.fov_deg
        ))
    })?;
    let run = || match settings.sampler {
        SamplerKind::Independent => render_with(
            scene,
            &camera,
            settings,
            IndependentSampler::new(settings.seed),
            progress,
        ),
        SamplerKind::Stratified => render_with(
            scene,
            &camera,
            settings,
            StratifiedSampler::new(settings.seed, settings.spp),
            progress,
        ),
    };
    match settings.threads {
        Some(n) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n.max(1))
                .build()
                .map_err(|e| Error::Settings(format!("cannot start {n} threads: {e}")))?;
            Ok(pool.install(run))
        }
        None => Ok(run()),
    }
}

/// How a render is split into passes, and when it stops.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct PassPlan {
    /// Samples per pixel per pass (the stratification unit); `None`: one pass of all the spp.
    pub pass_spp: Option<u32>,
    /// Stop after the first whole pass that ends past this wall time (at least one pass runs).
    pub time_limit: Option<Duration>,
}

/// Render `settings.spp` samples per pixel as passes of `plan.pass_spp` samples (sample indices
/// `first_sample + k·pass_spp ..`), merging them exactly, and stop early at a whole pass when
/// `plan.time_limit` runs out. Returns the film, the summed stats and the spp reached.
pub fn render_passes(
    scene: &Scene,
    settings: &RenderSettings,
    plan: &PassPlan,
    progress: &dyn Progress,
) -> Result<(Film, RenderStats, u32)> {
    let pass = plan
        .pass_spp
        .unwrap_or(settings.spp)
        .clamp(1, settings.spp.max(1));
    let start = Instant::now();
    let mut film = Film::new(settings.width, settings.height);
    let mut stats = RenderStats::default();
    let mut done = 0u32;
    while done < settings.spp {
        let n = pass.min(settings.spp - done);
        let pass_settings = RenderSettings {
            spp: n,
            first_sample: settings.first_sample + done,
            ..settings.clone()
        };
        let (f, s) = render(scene, &pass_settings, progress)?;
        film.merge(&f);
        stats.rays += s.rays;
        stats.samples += s.samples;
        stats.nonfinite += s.nonfinite;
        done += n;
        if plan.time_limit.is_some_and(|t| start.elapsed() >= t) {
            break;
        }
    }
    stats.elapsed = start.elapsed();
    Ok((film, stats, done))
}

/// One tile's result: pixel sums and counters.
struct TileResult {
    origin: UVec2,
    size: UVec2,
    sums: Vec<(DVec3, DVec3, u64)>,
    rays: u64,
    samples: u64,
    nonfinite: u64,
}

fn render_with<S: Sampler>(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    sampler: S,
    progress: &dyn Progress,
) -> (Film, RenderStats) {
    let start = Instant::now();
    let integrator = IntegratorSettings {
        max_depth: settings.max_depth,
        directions: settings.directions,
    };
    let tiles_x = settings.width.div_ceil(TILE);
    let tiles_y = settings.height.div_ceil(TILE);
    let tiles: Vec<TileResult> = (0..tiles_x * tiles_y)
        .into_par_iter()
        .map_with(sampler, |sampler, t| {
            let origin = UVec2::new((t % tiles_x) * TILE, (t / tiles_x) * TILE);
            let size = UVec2::new(
                TILE.min(settings.width - origin.x),
                TILE.min(settings.height - origin.y),
            );
            let mut tile = TileResult {
                origin,
                size,
                sums: Vec::with_capacity((size.x * size.y) as usize),
                rays: 0,
                samples: 0,
                nonfinite: 0,
            };
            for y in origin.y..origin.y + size.y {
                for x in origin.x..origin.x + size.x {
                    let pixel = UVec2::new(x, y);
                    let (mut sum, mut sum_sq, mut n) = (DVec3::ZERO, DVec3::ZERO, 0u64);
                    for index in settings.first_sample..settings.first_sample + settings.spp {
                        sampler.start_pixel_sample(pixel, index);
                        let (o, d) = camera.generate_ray(pixel, sampler.next_2d());
                        let (l, rays) = radiance(scene, o, d, sampler, &integrator);
                        tile.rays += rays;
                        if l.is_finite() {
                            let v = l.as_dvec3();
                            sum += v;
                            sum_sq += v * v;
                            n += 1;
                        } else {
                            tile.nonfinite += 1;
                        }
                    }
                    tile.samples += settings.spp as u64;
                    tile.sums.push((sum, sum_sq, n));
                }
            }
            progress.advance((size.x * size.y) as u64);
            tile
        })
        .collect();
    let mut film = Film::new(settings.width, settings.height);
    let mut stats = RenderStats::default();
    for tile in tiles {
        let mut k = 0;
        for y in tile.origin.y..tile.origin.y + tile.size.y {
            for x in tile.origin.x..tile.origin.x + tile.size.x {
                let (s, s2, n) = tile.sums[k];
                film.add_pixel_sums(film.index(x, y), s, s2, n);
                k += 1;
            }
        }
        stats.rays += tile.rays;
        stats.samples += tile.samples;
        stats.nonfinite += tile.nonfinite;
    }
    stats.elapsed = start.elapsed();
    (film, stats)
}

/// The named points of the (sampler, directions) grid, in the mission's words.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Strategy {
    /// independent points, uniform hemisphere directions: the naive baseline.
    Independent,
    /// stratified points, uniform hemisphere directions.
    Stratified,
    /// independent points, Phong-lobe importance sampling.
    Importance,
    /// stratified points, Phong-lobe importance sampling: the best combination.
    Combined,
}

impl Strategy {
    /// All presets, in the order experiments report them.
    pub const ALL: [Strategy; 4] = [
        Strategy::Independent,
        Strategy::Stratified,
        Strategy::Importance,
        Strategy::Combined,
    ];

    /// The (sampler, directions) pair this preset names.
    pub fn axes(self) -> (SamplerKind, Directions) {
        match self {
            Strategy::Independent => (SamplerKind::Independent, Directions::Uniform),
            Strategy::Stratified => (SamplerKind::Stratified, Directions::Uniform),
            Strategy::Importance => (SamplerKind::Independent, Directions::Phong),
            Strategy::Combined => (SamplerKind::Stratified, Directions::Phong),
        }
    }

    /// The preset that names this pair, if any.
    pub fn from_axes(sampler: SamplerKind, directions: Directions) -> Option<Strategy> {
        Strategy::ALL
            .into_iter()
            .find(|s| s.axes() == (sampler, directions))
    }

    /// The name used on the command line and in metadata.
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Independent => "independent",
            Strategy::Stratified => "stratified",
            Strategy::Importance => "importance",
            Strategy::Combined => "combined",
        }
    }
}

impl std::fmt::Display for Strategy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
