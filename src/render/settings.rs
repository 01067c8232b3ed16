//! What to render and how ([`RenderSettings`]): the image, the samples, the strategy, the
//! threads, the replicates, path reuse and the roulette; their defaults, the scene's `[render]`
//! section over them, what the integrator is told of them, and the checks a render makes of
//! them before its camera is built.

use super::SAMPLE_INDICES;
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::integrator::rrs::Roulette;
use crate::integrator::{IntegratorSettings, MAX_RRS_DEPTH};
use crate::scene::Scene;
use crate::strategy::Strategy;

/// What to render, and how.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Index of the first sample (a render of samples `k..k+spp` merges with one of `0..k`).
    pub first_sample: u32,
    /// Max path segments, the camera ray included.
    pub max_depth: u32,
    /// Seed of every random stream.
    pub seed: u64,
    /// How every random decision is made.
    pub strategy: Strategy,
    /// Worker threads; `None` uses the current rayon pool (the global one: all cores).
    pub threads: Option<usize>,
    /// Time the traversals for [`super::RenderStats::timing`] (one ray in 16; off by default).
    pub time_traces: bool,
    /// Independent randomizations of every pixel (seeds [`super::replicate_seed`]), whose spread
    /// estimates the image's error ([`crate::estimate`]); 1 renders one set per pass, and the
    /// error is then estimated per sample. `vrpt render` defaults to 1, and to
    /// [`ACTING_REPLICATES`] where it acts on the estimate (`--adaptive`, `--target-error`).
    pub replicates: u32,
    /// Path reuse across pixels in blocks of `reuse × reuse` ([`crate::integrator::reuse`]):
    /// 1 (off) to [`MAX_REUSE`].
    pub reuse: u32,
    /// How paths end and split: classic roulette, or learned (EARS, [`crate::integrator::rrs`]).
    pub roulette: Roulette,
    /// Camera rays a sample spends on the emission seen directly in a pixel where it varies
    /// (the edge of a light, of the sun: [`super::edges`]); 0 counts it on the path's own
    /// camera ray everywhere.
    pub edge_rays: u32,
}

pub use super::edges::{DEFAULT_EDGE_RAYS, MAX_EDGE_RAYS};
pub use crate::integrator::reuse::MAX_REUSE;

/// The replicates of a render that acts on its error estimate (adaptive rounds, a target
/// error) when `--replicates` is not given. A render that only reports its error keeps one
/// set: four sets of N/4 stratify less than one of N (1.5–1.75× the MSE on the Cornell box at
/// 64 spp), and the per-sample estimate of one set is an upper bound.
pub const ACTING_REPLICATES: u32 = 4;

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 256,
            height: 256,
            spp: 16,
            first_sample: 0,
            max_depth: 8,
            seed: 0,
            strategy: Strategy::default(),
            threads: None,
            time_traces: false,
            replicates: 1,
            reuse: 1,
            roulette: Roulette::Classic,
            edge_rays: DEFAULT_EDGE_RAYS,
        }
    }
}

impl RenderSettings {
    /// What the integrator is told of these settings.
    pub fn integrator(&self) -> IntegratorSettings {
        IntegratorSettings {
            max_depth: self.max_depth,
            directions: self.strategy.directions,
            lights: self.strategy.lights,
            light_points: self.strategy.light_points,
            light_choice: self.strategy.light_choice,
            time_traces: self.time_traces,
            camera_emission: true,
        }
    }

    /// The built-in defaults with the scene's `[render]` section over them (flags go on top).
    pub fn for_scene(scene: &Scene) -> Self {
        let base = RenderSettings::default();
        let d = &scene.defaults;
        RenderSettings {
            width: d.width.unwrap_or(base.width),
            height: d.height.unwrap_or(base.height),
            spp: d.spp.unwrap_or(base.spp),
            max_depth: d.max_depth.unwrap_or(base.max_depth),
            ..base
        }
    }
}

/// The camera for `settings`, after checking that the settings can be rendered.
pub(super) fn camera_for(scene: &Scene, settings: &RenderSettings) -> Result<Camera> {
    if settings.width == 0 || settings.height == 0 || settings.spp == 0 || settings.max_depth == 0 {
        return Err(Error::Settings(
            "width, height, spp and max depth must be at least 1".into(),
        ));
    }
    if settings.edge_rays > MAX_EDGE_RAYS {
        return Err(Error::Settings(format!(
            "--edge-rays must be 0 (off) to {MAX_EDGE_RAYS}, not {}",
            settings.edge_rays
        )));
    }
    if !(1..=MAX_REUSE).contains(&settings.reuse) {
        return Err(Error::Settings(format!(
            "--reuse must be 1 (off) to {MAX_REUSE}, not {}",
            settings.reuse
        )));
    }
    if settings.roulette == Roulette::Ears {
        if settings.reuse > 1 {
            return Err(Error::Settings(
                "--roulette ears does not combine with --reuse yet: a reused path's second vertex \
                 would have to split with it"
                    .into(),
            ));
        }
        if settings.max_depth > MAX_RRS_DEPTH {
            return Err(Error::Settings(format!(
                "--roulette ears traces its continuations recursively: --max-depth at most \
                 {MAX_RRS_DEPTH}, not {}",
                settings.max_depth
            )));
        }
    }
    let end = settings.first_sample as u64 + settings.spp as u64;
    if end > SAMPLE_INDICES {
        return Err(Error::Settings(format!(
            "samples {} .. {end} go beyond the last sample index, {}",
            settings.first_sample,
            u32::MAX
        )));
    }
    crate::limits::check_render_memory(settings.width, settings.height, settings.replicates)?;
    if settings.strategy.directions == crate::bsdf::Directions::Guided {
        // the training images a guided render may keep (`render::combine`): each kept one and
        // each of the gate's probes, a training iteration's film (56 B) and the final
        // iteration's image when combined
        let kept = super::KEPT_ITERATIONS as u64 + super::gate::GATE_PROBES as u64;
        let per_pixel = kept * super::KEPT_BYTES_PER_PIXEL + 56 + super::KEPT_BYTES_PER_PIXEL;
        let pixels = settings.width as u64 * settings.height as u64;
        crate::limits::check_bytes(
            &format!(
                "a guided {}x{} image with its training images",
                settings.width, settings.height
            ),
            pixels * (crate::limits::BYTES_PER_PIXEL + per_pixel),
        )?;
    }
    Camera::new(&scene.camera, settings.width, settings.height).ok_or_else(|| {
        Error::Settings(format!(
            "degenerate camera (eye {}, target {}, up {}, fov {}°)",
            scene.camera.eye, scene.camera.target, scene.camera.up, scene.camera.fov_deg
        ))
    })
}
