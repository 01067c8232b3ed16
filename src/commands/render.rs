//! `vrpt render`: load a scene, render it with the settings asked for (flags over the scene's
//! `[render]` defaults over the built-in ones), in passes, a shard, under a time limit or a stop
//! flag, and write the image (EXR with metadata, or PNG) and, if asked, the variance image.

pub use super::black::{why_black, BLACK_LUMINANCE};
use super::outcome::{adaptive_summary, passes_record};
use super::ImageArgs;
use crate::analysis::maps::{write_ears_map, write_spp_map};
use crate::error::{Error, Result};
use crate::estimate::ErrorEstimate;
use crate::film::Film;
use crate::image_io::{check_image_path, check_outputs, Format, NamedPath};
use crate::limits::{parse_exposure, parse_gain, parse_seconds, parse_shard, parse_threads};
use crate::output::{write_render, EstimateRecord, RenderMetadata};
use crate::render::auto::{self, Candidate, Candidates, Choice};
use crate::render::{
    render_passes, render_passes_with, shard_range, PassPlan, Progress, RenderSettings,
    RenderStats, Rendered, SamplerFactory, ACTING_REPLICATES,
};
use crate::scene::Scene;
use crate::strategy::StrategyArgs;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// What to render and where to write it: `vrpt render`'s flags. Each `None` takes the scene's
/// default, then the built-in one.
#[derive(Clone, Debug, Default, clap::Args)]
pub struct RenderRequest {
    /// The scene: an .obj file, a scene.toml, or a folder holding a scene.toml.
    pub scene: PathBuf,
    /// Output: .png (tone-mapped sRGB) or .exr (linear, with metadata); default SCENE-NAME.png
    /// in the current folder.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub image: ImageArgs,
    #[command(flatten)]
    pub load: super::LoadArgs,
    /// Seed of every random number: the same seed gives the same image.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Index of the first sample: renders of 0..N and N..2N (same seed) merge into one of 2N.
    #[arg(long, default_value_t = 0)]
    pub first_sample: u32,
    /// Stop at the first whole pass that ends after this many seconds (--spp is then a cap).
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds, allow_negative_numbers = true)]
    pub time_limit: Option<f64>,
    /// Samples per pixel per pass, the unit of stratification (default: all, or 16 with
    /// --time-limit, whose passes then double while the time left allows).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub pass_spp: Option<u32>,
    /// Render only shard I of N (from 0): samples ⌊I·spp/N⌋ .. ⌊(I+1)·spp/N⌋; `vrpt merge` of
    /// all N equals one render of all (job arrays: examples/slurm, examples/kubernetes).
    #[arg(long, value_name = "I/N", value_parser = parse_shard, conflicts_with_all = ["time_limit", "first_sample"])]
    pub shard: Option<(u32, u32)>,
    /// Worker threads (default: all cores). The image does not depend on it.
    #[arg(long, value_parser = parse_threads)]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub strategy: StrategyArgs,
    /// With --strategy auto: the candidates its pilot chooses from, comma-separated strategies,
    /// each with +reuseK for path reuse in K×K blocks (`mis+reuse3`) or +ears for
    /// efficiency-aware roulette and splitting (`mis+ears`); the first is kept unless another is
    /// more efficient beyond the pilot's noise; a guided candidate is piloted only where an
    /// unguided one beat the first [default: mis,mis+reuse4,stratified+guided+mis+reuse4]
    #[arg(long, value_name = "CANDIDATES", value_parser = Candidates::parse)]
    pub auto_candidates: Option<Candidates>,
    #[command(flatten)]
    pub error: ErrorArgs,
    /// Path reuse across pixels (Bekaert et al. 2002): in blocks of K×K pixels each pixel's
    /// first bounce is connected to every path of the block beyond its second vertex, the K²
    /// ways weighted by the balance heuristic (unbiased; K² − 1 shadow rays more per sample;
    /// neighbours' errors then correlate). 1: off [default: 1]
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..=crate::render::MAX_REUSE as i64))]
    pub reuse: Option<u32>,
    /// Edge rays: in a pixel where the emission seen directly varies (the edge of a light, of
    /// the sun), each sample estimates it apart with up to M camera rays of its own at the
    /// pixel's stratified points, and the path's camera ray no longer counts it (unbiased; the
    /// pixels are found by a probe of four rays a pixel before the render, and each one's count
    /// by a pilot, where it lowers MSE × time most). 0: off
    #[arg(long, value_name = "M", default_value_t = crate::render::DEFAULT_EDGE_RAYS,
          value_parser = clap::value_parser!(u32).range(0..=crate::render::MAX_EDGE_RAYS as i64))]
    pub edge_rays: u32,
    /// How paths end and split: `classic` Russian roulette from the third bounce, or `ears`,
    /// efficiency-aware roulette and splitting (Rath et al. 2022) learned in a short training
    /// (at most an eighth of the spp or time) and then frozen: unbiased, a path may split into
    /// up to 20 continuations where that pays [default: classic]
    #[arg(long, value_name = "KIND")]
    pub roulette: Option<crate::integrator::rrs::Roulette>,
    /// With --directions guided: `keep` combines the last training iterations' images with the
    /// final iteration's by inverse variance (unbiased: each pixel's weights come from the
    /// other half of the tiles), `discard` makes the image of the final iteration alone (as
    /// does --reuse K > 1, whose final samples outweigh the unreused training's) [default: keep]
    #[arg(long, value_name = "WHAT", value_parser = ["keep", "discard"])]
    pub training_images: Option<String>,
    /// With --directions guided: `on` probes the guide against Phong directions during its
    /// training (up to three iterations, from the first of 2^17 paths) and renders the rest
    /// without it where it loses beyond the noise twice in a row, or once far beyond it (the
    /// glossy plates); where the training images are discarded (--reuse K > 1, or `discard`) the
    /// guide must be ahead by 1.11x to stay. `off` guides whatever the probes would read
    /// [default: on]
    #[arg(long, value_name = "ON/OFF", value_parser = ["on", "off"])]
    pub guide_gate: Option<String>,
    /// With --roulette ears: also write the learned factor at each pixel's first vertex (over
    /// 1: the paths split there; under 1: they end more often) as a false-colour PNG.
    #[arg(long, value_name = "PNG")]
    pub ears_map: Option<PathBuf>,
    /// Exposure of the PNG, in stops (pixels × 2^EXPOSURE before tone mapping), within ±64.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = parse_exposure)]
    pub exposure: f32,
    /// Also write the per-pixel variance of the mean to this EXR.
    #[arg(long, value_name = "EXR")]
    pub variance: Option<PathBuf>,
    /// Also say where the time went: scene load, BVH build, traversal against shading (one ray
    /// in 16 is timed, about 1% slower).
    #[arg(long = "stats")]
    pub time_traces: bool,
    /// A flag that stops the render after its current batch (set by a signal handler).
    #[arg(skip)]
    pub stop: Option<Arc<AtomicBool>>,
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

/// The cap on spp of a `--target-error` render without `--spp`.
pub const TARGET_ERROR_SPP_CAP: u32 = 65536;

/// A render ready to run: the scene loaded, the settings and passes resolved, the outputs
/// checked.
pub struct PreparedRender {
    pub scene: Scene,
    pub settings: RenderSettings,
    pub plan: PassPlan,
    /// Where the image goes; `None`: nowhere, the render is kept in memory
    /// ([`RenderRequest::prepare_in_memory`]).
    pub output: Option<PathBuf>,
    /// Wall time of loading the scene (the BVH build included).
    pub load_time: Duration,
    /// The samples this render takes (relative to its first sample): all, or its shard's.
    pub samples: Range<u32>,
    exposure: f32,
    variance: Option<PathBuf>,
    spp_map: Option<PathBuf>,
    ears_map: Option<PathBuf>,
    time_limit: Option<f64>,
    shard: Option<(u32, u32)>,
    /// `--strategy auto`'s candidates (the settings are then the first's, until chosen).
    auto: Option<Vec<Candidate>>,
}

/// What a render did, and the image it made.
pub struct RenderOutcome {
    /// The file written (`None` for a render kept in memory).
    pub output: Option<PathBuf>,
    /// The settings, with the spp and first sample actually rendered.
    pub settings: RenderSettings,
    pub stats: RenderStats,
    /// The spp asked for (the shard's, for a shard).
    pub requested_spp: u32,
    /// Whether the stop flag ended it before all its samples.
    pub interrupted: bool,
    /// The replicates asked for, where fewer rendered (`settings.replicates` says how many).
    pub missing_replicates: Option<u32>,
    /// Why the image is black or nearly so, and what would light it (none where it is not).
    pub black: Option<String>,
    /// What `--strategy auto`'s pilots measured and chose.
    pub auto: Option<Choice>,
    /// The scene, the speed and the rays, in three lines ([`RenderStats::summary`]).
    pub summary: String,
    /// Where the time went ([`RenderStats::timing`]).
    pub timing: String,
    /// The image's sums (mean, variance of the mean, samples per pixel).
    pub film: Film,
    /// The image's estimated error.
    pub estimate: ErrorEstimate,
    /// The metadata an EXR of it records.
    pub meta: RenderMetadata,
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
        // contradictory flags first, before any file is read
        self.candidates()?;
        let output = self
            .output
            .clone()
            .unwrap_or_else(|| default_output(&self.scene));
        let outputs = self.check_outputs(&output)?;
        let prepared = self.load_and_resolve(Some(output.clone()))?;
        // and the files the scene was read from
        super::check_against_scene(&outputs, &prepared.scene)?;
        Ok(prepared)
    }

    /// Load the scene and resolve the settings of a render that writes no file: its image stays
    /// in the [`RenderOutcome`] (the Python binding's `vrpt.render`). The flags that name files
    /// (`-o`, `--variance`, `--spp-map`) are refused.
    pub fn prepare_in_memory(&self) -> Result<PreparedRender> {
        self.candidates()?;
        let named = [
            ("-o", &self.output),
            ("--variance", &self.variance),
            ("--spp-map", &self.error.spp_map),
            ("--ears-map", &self.ears_map),
        ];
        if let Some((flag, _)) = named.iter().find(|(_, p)| p.is_some()) {
            return Err(Error::Settings(format!(
                "{flag}: a render kept in memory writes no file (save it once it is done)"
            )));
        }
        self.load_and_resolve(None)
    }

    /// Load the scene, resolve the settings and the passes.
    fn load_and_resolve(&self, output: Option<PathBuf>) -> Result<PreparedRender> {
        let start = Instant::now();
        let scene = self.load.load(&self.scene)?;
        let load_time = start.elapsed();
        let settings = self.settings(&scene)?;
        let plan = self.plan(&settings)?;
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
            ears_map: self.ears_map.clone(),
            time_limit: self.time_limit,
            shard: self.shard,
            auto: self.candidates()?,
        })
    }

    /// The outputs (`output`, the variance image, the spp map), each of the right kind, none
    /// the same file as another or as the scene's: the named paths, for the check against the
    /// scene's files once it is loaded.
    fn check_outputs<'a>(&'a self, output: &'a Path) -> Result<Vec<NamedPath<'a>>> {
        check_image_path(output)?;
        if let Some(v) = &self.variance {
            if check_image_path(v)? != Format::Exr {
                return Err(Error::Settings(format!(
                    "--variance {}: the variance image must be an .exr",
                    v.display()
                )));
            }
        }
        let maps = [
            ("--spp-map", "spp map", &self.error.spp_map),
            ("--ears-map", "EARS map", &self.ears_map),
        ];
        for (flag, what, map) in maps {
            if let Some(p) = map {
                if check_image_path(p)? != Format::Png {
                    return Err(Error::Settings(format!(
                        "{flag} {}: the {what} is a .png",
                        p.display()
                    )));
                }
            }
        }
        if self.ears_map.is_some() && self.roulette != Some(crate::integrator::rrs::Roulette::Ears)
        {
            return Err(Error::Settings(
                "--ears-map: only --roulette ears learns splitting factors to draw".into(),
            ));
        }
        let mut outputs: Vec<NamedPath> = vec![("-o", output)];
        outputs.extend(super::given(&[
            ("--variance", &self.variance),
            ("--spp-map", &self.error.spp_map),
            ("--ears-map", &self.ears_map),
        ]));
        let toml = self.scene.join("scene.toml");
        let mut inputs = vec![("SCENE", self.scene.as_path())];
        if self.scene.is_dir() {
            inputs.push(("SCENE", toml.as_path()));
        }
        check_outputs(&outputs, &inputs)?;
        Ok(outputs)
    }

    /// `--strategy auto`'s candidates (`None` for a render of one strategy); an error for
    /// contradictory strategy flags.
    fn candidates(&self) -> Result<Option<Vec<Candidate>>> {
        if !self.strategy.is_auto().map_err(Error::Settings)? {
            if self.auto_candidates.is_some() {
                return Err(Error::Settings(
                    "--auto-candidates: only --strategy auto chooses among candidates".into(),
                ));
            }
            self.strategy.resolve().map_err(Error::Settings)?;
            return Ok(None);
        }
        let c = (self.auto_candidates.clone()).map_or_else(auto::default_candidates, |c| c.0);
        if c.is_empty() {
            return Err(Error::Settings("--auto-candidates: no strategies".into()));
        }
        if let Some(k) = self.reuse {
            return Err(Error::Settings(format!(
                "--strategy auto chooses path reuse too: name it among the candidates \
                 (--auto-candidates mis,mis+reuse{k}), not with --reuse {k}"
            )));
        }
        if let Some(r) = self.roulette {
            let with = match r {
                crate::integrator::rrs::Roulette::Ears => "mis,mis+ears",
                crate::integrator::rrs::Roulette::Classic => "mis,mis+reuse4",
            };
            return Err(Error::Settings(format!(
                "--strategy auto chooses the roulette too: name it among the candidates \
                 (--auto-candidates {with}), not with --roulette {r}"
            )));
        }
        if self.shard.is_some() || self.error.adaptive {
            return Err(Error::Settings(
                "--strategy auto: not with --shard or --adaptive (the shards of one render, or \
                 its rounds, could choose differently)"
                    .into(),
            ));
        }
        Ok(Some(c))
    }

    /// The settings: the flags over the scene's defaults over the built-in ones; a target error
    /// without `--spp` caps at [`TARGET_ERROR_SPP_CAP`], and a render that acts on its error
    /// estimate takes [`ACTING_REPLICATES`] without `--replicates`.
    fn settings(&self, scene: &Scene) -> Result<RenderSettings> {
        let acting = self.error.adaptive || self.error.target_error.is_some();
        let cap = self.error.target_error.map(|_| TARGET_ERROR_SPP_CAP);
        let auto = self.candidates()?;
        Ok(RenderSettings {
            first_sample: self.first_sample,
            seed: self.seed,
            strategy: match &auto {
                Some(c) => c[0].strategy,
                None => self.strategy.resolve().map_err(Error::Settings)?,
            },
            threads: self.threads,
            time_traces: self.time_traces,
            edge_rays: self.edge_rays,
            reuse: match &auto {
                Some(c) => c[0].reuse,
                None => self.reuse.unwrap_or(1),
            },
            roulette: match &auto {
                Some(c) => c[0].roulette,
                None => self.roulette.unwrap_or_default(),
            },
            replicates: (self.error.replicates).unwrap_or(if acting {
                ACTING_REPLICATES
            } else {
                1
            }),
            ..self.image.settings(scene, cap)
        })
    }

    /// The passes: `--pass-spp`, else 16 under a time limit or a target error (else one pass);
    /// the time limit, shard, stop flag and adaptive rounds as asked.
    fn plan(&self, settings: &RenderSettings) -> Result<PassPlan> {
        let steady = self.time_limit.is_some() || self.error.target_error.is_some();
        let auto = self.strategy.is_auto().map_err(Error::Settings)?;
        if self.training_images.is_some()
            && (auto || settings.strategy.directions != crate::bsdf::Directions::Guided)
        {
            return Err(Error::Settings(
                "--training-images: only a guided render (--directions guided) trains, and so \
                 has training images"
                    .into(),
            ));
        }
        if self.guide_gate.is_some()
            && (auto || settings.strategy.directions != crate::bsdf::Directions::Guided)
        {
            return Err(Error::Settings(
                "--guide-gate: only a guided render (--directions guided) trains a guide to \
                 gate"
                    .into(),
            ));
        }
        if self.training_images.as_deref() == Some("keep") && settings.reuse > 1 {
            return Err(Error::Settings(format!(
                "--training-images keep: a render that reuses paths (--reuse {}) keeps the final \
                 iteration alone (training paths are not reused, and kept they cost more than \
                 they bring)",
                settings.reuse
            )));
        }
        Ok(PassPlan {
            pass_spp: self.pass_spp.or(steady.then(|| 16.min(settings.spp))),
            time_limit: self
                .time_limit
                .map(|t| crate::limits::duration("--time-limit", t))
                .transpose()?,
            shard: self.shard,
            stop: self.stop.clone(),
            adaptive: self.error.adaptive,
            min_allocation_gain: self.error.min_allocation_gain,
            target_error: self.error.target_error,
            strip: None,
            guide: None,
            edges: None,
            discard_training: self.training_images.as_deref() == Some("discard"),
            ungated: self.guide_gate.as_deref() == Some("off"),
            // auto's twin only (see `PassPlan::gate_early`): the lamp's caustics, which an
            // immature guide has not found yet, would close it wrongly
            gate_early: false,
        })
    }
}

impl PreparedRender {
    /// Pixel samples the render will take at most (for a progress bar).
    pub fn pixel_samples(&self) -> u64 {
        self.settings.width as u64 * self.settings.height as u64 * self.samples.len() as u64
    }

    /// Render and write the image(s).
    pub fn run(mut self, progress: &dyn Progress) -> Result<RenderOutcome> {
        let choice = self.choose()?;
        let r = render_passes(&self.scene, &self.settings, &self.plan, progress)?;
        self.finish(r, choice)
    }

    /// With `--strategy auto`: render the pilots, take the strategy they choose, and leave the
    /// render the time they did not use.
    fn choose(&mut self) -> Result<Option<Choice>> {
        let Some(candidates) = &self.auto else {
            return Ok(None);
        };
        let choice = auto::choose(&self.scene, &self.settings, &self.plan, candidates)?;
        self.settings = choice.settings(&self.settings);
        self.plan = choice.plan(&self.plan);
        Ok(Some(choice))
    }

    /// Render with the samplers `factory` makes (a sampler of the caller's own, see
    /// [`crate::render::SamplerFactory`]) instead of the strategy's, and write the image(s).
    pub fn run_with<F: SamplerFactory>(
        self,
        factory: &F,
        progress: &dyn Progress,
    ) -> Result<RenderOutcome> {
        if self.auto.is_some() {
            return Err(Error::Settings(
                "--strategy auto renders with vrpt's own samplers, not a sampler of yours".into(),
            ));
        }
        let r = render_passes_with(&self.scene, &self.settings, &self.plan, factory, progress)?;
        self.finish(r, None)
    }

    /// The metadata of what rendered, the files written, and what to say.
    fn finish(self, r: Rendered, auto: Option<Choice>) -> Result<RenderOutcome> {
        let requested = self.samples.len() as u32;
        let asked_replicates = self.settings.replicates;
        let settings = RenderSettings {
            spp: r.spp,
            first_sample: r.first_sample,
            replicates: r.replicates,
            ..self.settings
        };
        let meta = RenderMetadata {
            // the sets of points that rendered (not those asked for)
            estimate: Some(EstimateRecord::new(r.replicates, &r.estimate)),
            adaptive_rounds: r.rounds,
            target_error: self.plan.target_error,
            pass_spp: self.plan.pass_spp,
            passes: passes_record(&r.passes, self.plan.pass_spp),
            time_limit_seconds: self.time_limit,
            shard: self.shard,
            requested_spp: (r.spp < requested).then_some(requested as u64),
            interrupted: r.interrupted,
            auto: auto.as_ref().map(Choice::record),
            // the pilots' time too, as a time limit counts it (the summary's rates are the
            // render's own)
            render_seconds: (r.stats.elapsed + auto.as_ref().map_or(Duration::ZERO, |c| c.elapsed))
                .as_secs_f64(),
            ..RenderMetadata::new(&self.scene, &settings, &r.stats)
        };
        if let Some(output) = &self.output {
            write_render(
                output,
                (&r.film, Some(&r.estimate)),
                &meta,
                self.exposure,
                self.variance.as_deref(),
            )?;
        }
        if let Some(p) = &self.spp_map {
            write_spp_map(p, &r.film.sample_counts(), (r.film.width, r.film.height))?;
        }
        if let (Some(p), Some(map)) = (&self.ears_map, &r.ears_map) {
            write_ears_map(p, map, (r.film.width, r.film.height))?;
        }
        let bar = (self.plan.min_allocation_gain).unwrap_or(crate::estimate::ALLOCATE_ABOVE);
        let adaptive = adaptive_summary(&r, bar);
        let pilots = auto.as_ref().map_or(String::new(), Choice::table);
        Ok(RenderOutcome {
            summary: pilots
                + &r.stats.summary(&self.scene, &settings)
                + &adaptive
                + &r.estimate.summary(),
            timing: r.stats.timing(self.load_time, &self.scene),
            output: self.output,
            settings,
            stats: r.stats,
            requested_spp: requested,
            interrupted: r.interrupted,
            missing_replicates: (r.finished_uniformly.is_none() && r.replicates < asked_replicates)
                .then_some(asked_replicates),
            black: why_black(&self.scene, &r.film),
            film: r.film,
            estimate: r.estimate,
            meta,
            auto,
        })
    }
}
