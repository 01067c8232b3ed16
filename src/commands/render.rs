//! `vrpt render`: load a scene, render it with the settings asked for (flags over the scene's
//! `[render]` defaults over the built-in ones), in passes, a shard, under a time limit or a stop
//! flag, and write the image (EXR with metadata, or PNG) and, if asked, the variance image.

use crate::analysis::plots::write_spp_map;
use crate::error::{Error, Result};
use crate::image_io::{check_image_path, check_outputs, Format, NamedPath};
use crate::output::{write_render, EstimateRecord, RenderMetadata};
use crate::render::{
    render_passes, shard_range, PassPlan, Progress, RenderSettings, RenderStats, ACTING_REPLICATES,
};
use crate::scene::{self, Scene};
use crate::strategy::Strategy;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// What to render and where to write it; `None` takes the scene's default, then the built-in.
#[derive(Clone, Debug, Default)]
pub struct RenderRequest {
    /// An `.obj`, a `scene.toml`, or a folder holding a `scene.toml`.
    pub scene: PathBuf,
    /// `.png` or `.exr`; default `SCENE-NAME.png` in the current folder ([`default_output`]).
    pub output: Option<PathBuf>,
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: Option<u32>,
    pub max_depth: Option<u32>,
    pub seed: u64,
    pub first_sample: u32,
    pub strategy: Strategy,
    /// Worker threads; `None`: all cores.
    pub threads: Option<usize>,
    /// Stop at the first whole pass that ends after this many seconds.
    pub time_limit: Option<f64>,
    /// Samples per pixel per pass (default: all in one pass, or 16 with a time limit).
    pub pass_spp: Option<u32>,
    /// Render only shard `i` of `n`.
    pub shard: Option<(u32, u32)>,
    /// Exposure of a PNG, in stops.
    pub exposure: f32,
    /// Also write the variance of the mean to this EXR.
    pub variance: Option<PathBuf>,
    /// Time the traversals ([`RenderStats::timing`]).
    pub time_traces: bool,
    /// A flag that stops the render after its current batch (set by a signal handler).
    pub stop: Option<&'static AtomicBool>,
    /// Replicates, adaptive sampling, a target error and the spp map.
    pub error: ErrorArgs,
}

/// How a render estimates its error, and whether it acts on it (`vrpt render`'s flags).
#[derive(Clone, Debug, Default, clap::Args)]
pub struct ErrorArgs {
    /// Independent randomizations of every pixel, each a complete stratified or Sobol set of
    /// spp/R samples; their spread estimates the image's error honestly for every sampler
    /// (printed, and stored in an EXR as `estimated_variance.R/G/B` and `vrpt.estimated_rel_mse`).
    /// 1: one set, the error then estimated per sample (s²/n: unbiased for independent
    /// points, an upper bound for stratified and Sobol points, which do better than
    /// independent ones) [default: 1, or 4 with --adaptive or --target-error]
    #[arg(long, value_name = "R", value_parser = clap::value_parser!(u32).range(1..=256))]
    pub replicates: Option<u32>,
    /// Adaptive sampling: rounds of samples sent where the estimated relative error is, the
    /// image weighing each round by its planned size (unbiased); needs R ≥ 2.
    #[arg(long, conflicts_with = "shard")]
    pub adaptive: bool,
    /// With --adaptive: allocate a round by relative error only where the gain of doing so,
    /// cross-validated on the rounds before, is at least G; below it after the first round the
    /// render finishes as uniform passes of one set of points (0: always allocate) [default: 1.2]
    #[arg(long, value_name = "G", requires = "adaptive", value_parser = parse_gain, allow_negative_numbers = true)]
    pub min_allocation_gain: Option<f64>,
    /// Stop after the first round whose estimated relMSE of the image is at most E (or at
    /// --spp or --time-limit, whichever comes first; without --spp the cap is 65536 spp).
    #[arg(long, value_name = "E", value_parser = crate::limits::parse_target)]
    pub target_error: Option<f64>,
    /// Also write the samples of each pixel as a false-colour PNG with its colour bar.
    #[arg(long, value_name = "PNG")]
    pub spp_map: Option<PathBuf>,
}

/// A gain: a finite number ≥ 0.
fn parse_gain(s: &str) -> std::result::Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x >= 0.0 && x.is_finite() => Ok(x),
        _ => Err(format!("'{s}' is not a gain (a finite number ≥ 0)")),
    }
}

/// The cap on spp of a `--target-error` render without `--spp`.
pub const TARGET_ERROR_SPP_CAP: u32 = 65536;

/// A render ready to run: the scene loaded, the settings and passes resolved, the outputs
/// checked.
pub struct PreparedRender {
    pub scene: Scene,
    pub settings: RenderSettings,
    pub plan: PassPlan,
    pub output: PathBuf,
    /// Wall time of loading the scene (the BVH build included).
    pub load_time: Duration,
    /// The samples this render takes (relative to its first sample): all, or its shard's.
    pub samples: Range<u32>,
    exposure: f32,
    variance: Option<PathBuf>,
    spp_map: Option<PathBuf>,
    time_limit: Option<f64>,
    shard: Option<(u32, u32)>,
}

/// What a render did.
pub struct RenderOutcome {
    pub output: PathBuf,
    /// The settings, with the spp and first sample actually rendered.
    pub settings: RenderSettings,
    pub stats: RenderStats,
    /// The spp asked for (the shard's, for a shard).
    pub requested_spp: u32,
    /// Whether the stop flag ended it before all its samples.
    pub interrupted: bool,
    /// The scene, the speed and the rays, in three lines ([`RenderStats::summary`]).
    pub summary: String,
    /// Where the time went ([`RenderStats::timing`]).
    pub timing: String,
}

/// `SCENE-NAME.png` in the current folder (`render.png` for a bare `scene.toml`).
pub fn default_output(scene_path: &Path) -> PathBuf {
    let stem = if scene_path.is_dir() {
        scene_path.file_name()
    } else {
        scene_path.file_stem()
    };
    let stem = stem.map_or("render".into(), |s| s.to_string_lossy().into_owned());
    let stem = if stem == "scene" {
        "render".into()
    } else {
        stem
    };
    PathBuf::from(format!("{stem}.png"))
}

impl RenderRequest {
    /// Check the outputs, load the scene and resolve the settings.
    pub fn prepare(&self) -> Result<PreparedRender> {
        let output = self
            .output
            .clone()
            .unwrap_or_else(|| default_output(&self.scene));
        check_image_path(&output)?;
        if let Some(v) = &self.variance {
            if check_image_path(v)? != Format::Exr {
                return Err(Error::Settings(format!(
                    "--variance {}: the variance image must be an .exr",
                    v.display()
                )));
            }
        }
        if let Some(p) = &self.error.spp_map {
            if check_image_path(p)? != Format::Png {
                return Err(Error::Settings(format!(
                    "--spp-map {}: the spp map is a .png",
                    p.display()
                )));
            }
        }
        let outputs: Vec<NamedPath> = [
            ("-o", Some(output.as_path())),
            ("--variance", self.variance.as_deref()),
            ("--spp-map", self.error.spp_map.as_deref()),
        ]
        .into_iter()
        .filter_map(|(f, p)| p.map(|p| (f, p)))
        .collect();
        let toml = self.scene.join("scene.toml");
        let mut inputs = vec![("SCENE", self.scene.as_path())];
        if self.scene.is_dir() {
            inputs.push(("SCENE", toml.as_path()));
        }
        check_outputs(&outputs, &inputs)?;
        let start = Instant::now();
        let scene = scene::load(&self.scene)?;
        let load_time = start.elapsed();
        // and the files the scene was read from: its OBJ, environment map and textures
        let read: Vec<NamedPath> = std::iter::once(scene.source.as_path())
            .chain(scene.files.iter().map(PathBuf::as_path))
            .map(|p| ("the scene's file", p))
            .collect();
        check_outputs(&outputs, &read)?;
        let d = RenderSettings::for_scene(&scene);
        let settings = RenderSettings {
            width: self.width.unwrap_or(d.width),
            height: self.height.unwrap_or(d.height),
            spp: match (self.spp, self.error.target_error) {
                (Some(s), _) => s,
                (None, Some(_)) => TARGET_ERROR_SPP_CAP,
                (None, None) => d.spp,
            },
            first_sample: self.first_sample,
            max_depth: self.max_depth.unwrap_or(d.max_depth),
            seed: self.seed,
            strategy: self.strategy,
            threads: self.threads,
            time_traces: self.time_traces,
            guide_pdf_scale: 1.0,
            replicates: self.error.replicates.unwrap_or(
                if self.error.adaptive || self.error.target_error.is_some() {
                    ACTING_REPLICATES
                } else {
                    1
                },
            ),
        };
        let plan = PassPlan {
            pass_spp: self.pass_spp.or((self.time_limit.is_some()
                || self.error.target_error.is_some())
            .then(|| 16.min(settings.spp))),
            time_limit: self
                .time_limit
                .map(|t| crate::limits::duration("--time-limit", t))
                .transpose()?,
            shard: self.shard,
            stop: self.stop,
            adaptive: self.error.adaptive,
            min_allocation_gain: self.error.min_allocation_gain,
            target_error: self.error.target_error,
        };
        let samples = match self.shard {
            Some(s) => shard_range(settings.spp, s)?,
            None => 0..settings.spp,
        };
        Ok(PreparedRender {
            scene,
            settings,
            plan,
            output,
            load_time,
            samples,
            exposure: self.exposure,
            variance: self.variance.clone(),
            spp_map: self.error.spp_map.clone(),
            time_limit: self.time_limit,
            shard: self.shard,
        })
    }
}

impl RenderOutcome {
    /// What the user must hear about: dropped non-finite samples, an interrupted render.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if self.stats.nonfinite > 0 {
            w.push(format!(
                "{} non-finite radiance samples were dropped (not written into the image)",
                self.stats.nonfinite
            ));
        }
        if self.interrupted {
            w.push(format!(
                "interrupted: wrote {} with the {} of {} spp taken (its metadata says so)",
                self.output.display(),
                self.settings.spp,
                self.requested_spp
            ));
        }
        w
    }
}

impl PreparedRender {
    /// Pixel samples the render will take at most (for a progress bar).
    pub fn pixel_samples(&self) -> u64 {
        self.settings.width as u64 * self.settings.height as u64 * self.samples.len() as u64
    }

    /// Render and write the image(s).
    pub fn run(self, progress: &dyn Progress) -> Result<RenderOutcome> {
        let r = render_passes(&self.scene, &self.settings, &self.plan, progress)?;
        let requested = self.samples.len() as u32;
        let settings = RenderSettings {
            spp: r.spp,
            first_sample: r.first_sample,
            ..self.settings
        };
        let meta = RenderMetadata {
            estimate: Some(EstimateRecord::new(self.settings.replicates, &r.estimate)),
            adaptive_rounds: r.rounds,
            target_error: self.plan.target_error,
            pass_spp: self.plan.pass_spp,
            time_limit_seconds: self.time_limit,
            shard: self.shard,
            requested_spp: (r.spp < requested).then_some(requested as u64),
            interrupted: r.interrupted,
            ..RenderMetadata::new(&self.scene, &settings, &r.stats)
        };
        write_render(
            &self.output,
            (&r.film, Some(&r.estimate)),
            &meta,
            self.exposure,
            self.variance.as_deref(),
        )?;
        if let Some(p) = &self.spp_map {
            write_spp_map(p, &r.film.sample_counts(), (r.film.width, r.film.height))?;
        }
        let adaptive = match r.rounds {
            Some(n) => format!(
                "adaptive: {n} rounds{}, {} to {} samples per pixel\n",
                match r.uniform_rounds {
                    0 => String::new(),
                    u =>
                        format!(
                        " ({u} of them uniform: the cross-validated gain of allocating from the \
                         rounds before was below {})",
                        self.plan.min_allocation_gain.unwrap_or(crate::estimate::ALLOCATE_ABOVE)
                    ),
                },
                r.film.sample_counts().iter().min().copied().unwrap_or(0),
                r.film.sample_counts().iter().max().copied().unwrap_or(0)
            ),
            None => String::new(),
        } + &r.finished_uniformly.map_or(String::new(), |gain| {
            format!(
                "adaptive: after the first round the cross-validated gain of allocating was \
                 {gain:.2}, below {}: the rest rendered as uniform passes of one set of points\n",
                self.plan
                    .min_allocation_gain
                    .unwrap_or(crate::estimate::ALLOCATE_ABOVE)
            )
        }) + &r.allocation.map_or(String::new(), |g| {
            format!(
                "adaptive: relMSE gain over uniform at equal spp, bounds from this image: ideal \
                 (n ∝ e) {:.2}, this schedule (first round {:.0}%, uniform share {:.0}%) {:.2}; \
                 a round allocated from estimates this noisy, cross-validated {:.2}\n",
                g.ideal,
                100.0 * g.first_share,
                100.0 * crate::estimate::UNIFORM_SHARE,
                g.schedule,
                g.cross_validated
            )
        });
        Ok(RenderOutcome {
            summary: r.stats.summary(&self.scene, &settings) + &adaptive + &r.estimate.summary(),
            timing: r.stats.timing(self.load_time, self.scene.accel.build_time),
            output: self.output,
            settings,
            stats: r.stats,
            requested_spp: requested,
            interrupted: r.interrupted,
        })
    }
}
