//! The render loop: rayon over 16×16 tiles; per pixel, samples `first_sample ..
//! first_sample + spp` from a [`Sampler`] through the [`integrator`](crate::integrator) into a [`Film`].
//!
//! Each pixel's samples are summed in index order by one thread, and each draw depends only on
//! (seed, pixel, sample index, dimension), so the image is bit-identical whatever the number of
//! threads or the order in which tiles finish. Non-finite samples are counted and dropped (the
//! pixel's count excludes them), never written into the image.
//!
//! The rooms: this file holds the entry points ([`render`], [`render_passes`],
//! [`render_passes_with`]), the sampler dispatch and the job every pass shares; `settings` the
//! settings and their checks, `passes` the uniform passes and the stop condition, `adaptive` the
//! adaptive rounds, `training` the guide's training, `combine` its images kept, `rrs_training` EARS's, `tile` the tile
//! kernel, `stats` what a render counts and its text, `strip` a render of some of the image's
//! tiles, `auto` the pilots of `--strategy auto`.

#![warn(missing_docs)]

use crate::accel::TraceStack;
use crate::bsdf::Directions;
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::estimate::{self, ErrorEstimate, Replicates};
use crate::film::Film;
use crate::guiding::{Guide, Record, TreeSize};
use crate::integrator::rrs::Roulette;
use crate::integrator::{radiance_guided, IntegratorSettings, RayCounts};
use crate::sampler::layout::CameraSample;
use crate::sampler::{IndependentSampler, Sampler, SamplerKind, SobolSampler, StratifiedSampler};
use crate::scene::Scene;
use glam::{DVec3, UVec2};
use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

mod adaptive;
pub mod auto;
mod combine;
pub mod edges;
pub mod gate;
mod passes;
mod rrs_training;
mod settings;
mod stats;
mod strip;
mod tile;
mod training;
pub use combine::{Combination, KEPT_BYTES_PER_PIXEL, KEPT_ITERATIONS};
use settings::camera_for;
pub use settings::{
    RenderSettings, ACTING_REPLICATES, DEFAULT_EDGE_RAYS, MAX_EDGE_RAYS, MAX_REUSE,
};
pub use stats::{GuideStats, RenderStats, RrsStats};
pub use strip::TileStrip;
use tile::{tile_count, Alloc, Batch, BatchOutput, Kernel, Samples};
use training::Trainer;
pub use training::{learn_guide, learn_guide_with, LearnedGuide, TrainingBudget};

/// Tile edge in pixels.
pub const TILE: u32 = 16;

/// How many sample indices there are: a sample index is a `u32`, so a render's samples
/// `first_sample .. first_sample + spp` end at most here (the metadata check agrees).
pub const SAMPLE_INDICES: u64 = 1 << 32;

/// Something told how much is done (a progress bar): a render advances it by pixel samples,
/// an experiment by its units of work, naming each finished piece.
pub trait Progress: Sync {
    /// `units` more are done.
    fn advance(&self, units: u64);
    /// The piece of work that just finished (e.g. "mis run 3/8").
    fn finished(&self, _label: &str) {}
}

/// No progress reporting.
pub struct NoProgress;

impl Progress for NoProgress {
    fn advance(&self, _: u64) {}
}

/// Run `f` on a pool of `threads` workers, built once for the whole job; `None` runs it on the
/// current pool (rayon's global one: all cores).
pub fn with_threads<T: Send>(threads: Option<usize>, f: impl FnOnce() -> T + Send) -> Result<T> {
    match threads {
        Some(n) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n.max(1))
                .build()
                .map_err(|e| Error::Settings(format!("cannot start {n} threads: {e}")))?;
            Ok(pool.install(f))
        }
        None => Ok(f()),
    }
}

/// Render `scene` with `settings` into a new film: one pass of all the spp, with the sampler
/// `settings.strategy.sampler` names.
pub fn render(
    scene: &Scene,
    settings: &RenderSettings,
    progress: &dyn Progress,
) -> Result<(Film, RenderStats)> {
    render_passes(scene, settings, &PassPlan::default(), progress).map(|r| (r.film, r.stats))
}

/// A pass: the stratified set of `size` samples starting at sample index `origin`. A sampler
/// that stratifies over a known count (the stratified sampler's strata) builds its set from it;
/// one that does not (independent, Sobol) ignores it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SamplePass {
    /// The pass's first sample index.
    pub origin: u32,
    /// Its number of samples per pixel.
    pub size: u32,
}

/// Makes the sampler of one pass of a render: `(seed, pass) → sampler`. The render loop clones
/// it per worker thread and calls [`Sampler::start_pixel_sample`] for every sample of the pass,
/// with sample indices `pass.origin .. pass.origin + pass.size` (a stopped or sharded render
/// takes a part of them). A closure `Fn(u64, SamplePass) -> S` is a factory:
///
/// ```
/// use vrpt::render::SamplePass;
/// use vrpt::sampler::IndependentSampler;
/// let factory = |seed: u64, _pass: SamplePass| IndependentSampler::new(seed);
/// # fn is_factory<F: vrpt::render::SamplerFactory>(_: &F) {}
/// # is_factory(&factory);
/// ```
pub trait SamplerFactory: Sync {
    /// The sampler it makes.
    type Sampler: Sampler;
    /// The sampler of `pass` of a render with seed `seed`.
    fn make(&self, seed: u64, pass: SamplePass) -> Self::Sampler;
}

impl<S: Sampler, F: Fn(u64, SamplePass) -> S + Sync> SamplerFactory for F {
    type Sampler = S;
    #[inline]
    fn make(&self, seed: u64, pass: SamplePass) -> S {
        self(seed, pass)
    }
}

/// The built-in samplers' factories, one per [`SamplerKind`]: independent points.
pub fn independent(seed: u64, _: SamplePass) -> IndependentSampler {
    IndependentSampler::new(seed)
}
/// Stratified points, the pass's set.
pub fn stratified(seed: u64, pass: SamplePass) -> StratifiedSampler {
    StratifiedSampler::with_origin(seed, pass.size, pass.origin)
}

/// The jittered sampler's factory: the lecture's stratification, one uniform point per cell.
pub fn jittered(seed: u64, pass: SamplePass) -> StratifiedSampler {
    StratifiedSampler::jittered(seed, pass.size, pass.origin)
}
/// Owen-scrambled Sobol points.
pub fn sobol(seed: u64, _: SamplePass) -> SobolSampler {
    SobolSampler::new(seed)
}

/// Work done with whichever built-in sampler a render names: [`with_sampler`] is the one
/// `match` on [`SamplerKind`], so a new sampler is one arm there (renders and guide training
/// both go through it).
pub(crate) trait WithSampler {
    type Out;
    /// Do the work with the samplers `factory` makes.
    fn run<F: SamplerFactory>(self, factory: &F) -> Self::Out;
}

/// `work` run with the factory of the built-in sampler `kind`.
pub(crate) fn with_sampler<W: WithSampler>(kind: SamplerKind, work: W) -> W::Out {
    match kind {
        SamplerKind::Independent => work.run(&independent),
        SamplerKind::Stratified => work.run(&stratified),
        SamplerKind::Jittered => work.run(&jittered),
        SamplerKind::Sobol => work.run(&sobol),
    }
}

/// The guide a render samples with, and whether it records for the next one.
#[derive(Clone, Copy)]
struct Guiding<'a> {
    tree: Option<&'a Guide>,
    record: bool,
}

/// How a render is split into passes, which part of it is rendered, and when it stops.
#[derive(Clone, Debug, Default)]
pub struct PassPlan {
    /// Samples per pixel per pass (the stratification unit); `None`: one pass of all the spp.
    pub pass_spp: Option<u32>,
    /// Stop after the first whole pass that ends past this wall time (at least one pass runs).
    pub time_limit: Option<Duration>,
    /// Render only shard `i` of `n`: the samples `⌊i·spp/n⌋ .. ⌊(i+1)·spp/n⌋` of the render,
    /// with the render's passes (a shard may begin or end inside a pass).
    pub shard: Option<(u32, u32)>,
    /// A flag that, once set (by a signal handler, or by the Python binding on Ctrl-C), stops
    /// the render after the current batch of samples; the render is then cut into batches of
    /// about [`BATCH_SECONDS`]. Shared, so each render can have its own.
    pub stop: Option<Arc<AtomicBool>>,
    /// Adaptive sampling: rounds whose samples go where the estimated relative error is
    /// ([`crate::estimate`]); needs at least 2 replicates, and no shard.
    pub adaptive: bool,
    /// Adaptive rounds allocate only where the cross-validated gain of allocating is at least
    /// this ([`crate::estimate::cross_validated_gain`]); `None`:
    /// [`crate::estimate::ALLOCATE_ABOVE`]. 0 allocates every round whatever the gain; infinity
    /// never does (the render finishes as uniform passes after its first round).
    pub min_allocation_gain: Option<f64>,
    /// Stop after the first pass (a whole round of the replicates) after which the image's
    /// estimated relMSE is at most this.
    pub target_error: Option<f64>,
    /// Render only some whole tiles of the image, side by side ([`TileStrip`]): the settings'
    /// width and height are then the strip's, the camera the image's. `--strategy auto`'s
    /// pilots render one.
    pub strip: Option<Arc<TileStrip>>,
    /// A guide learned before the render: a guided render samples with it and does not train
    /// (`--strategy auto` hands over its guided pilot's; [`LearnedGuide`]). Ignored by a render
    /// whose directions are not guided.
    pub guide: Option<Arc<LearnedGuide>>,
    /// A guided render that trains its own guide keeps its last training iterations in the
    /// image, combined with the final iteration by inverse variance (`render::combine`),
    /// unless this is set (`--training-images discard`), or it renders several replicates, a
    /// shard or adaptive rounds (their estimates and merges count the final samples alone), or
    /// reuses paths (training paths are not reused, and their heavier tails cost more than
    /// their samples bring: with `--reuse 4` at 10 s, kept at a third of the time, 0.95× on the
    /// door, 1.00× on door-dark and 0.76× on the gap of the image without them).
    pub discard_training: bool,
    /// The image's edge pixels and their edge rays, found before the render, or `None`: the
    /// render finds them (`edges::edge_map`). `--strategy auto` finds them once, with the render's
    /// seed and its first candidate's integrator, for its pilots, and hands them to the render
    /// it chooses where they are the map that render would find itself (`edges::edges_fit`).
    /// A render handed its map does not count the rays that found it (the finder traced them):
    /// a pilot's cost in rays is its own.
    pub edges: Option<Arc<edges::EdgeMap>>,
    /// A guided render that trains its own guide over the whole image probes the guide against
    /// Phong directions during its training and renders the rest without it where it loses
    /// ([`gate`]; where it gates: `gates`), unless this is set (`--guide-gate off`): then it
    /// guides whatever it reads.
    pub ungated: bool,
    /// Whether such a render's gate, where it discards the training images (path reuse), also
    /// takes the early look ([`gate::Gate::looking_early`]): set by `--strategy auto` for its
    /// guided twin where the probe found no light coming as caustics.
    pub gate_early: bool,
}

/// Wall time the samples that a stopped render takes after the stop aim at (see
/// [`render_passes`]).
pub const BATCH_SECONDS: f64 = 0.25;

/// The samples `lo..hi` (relative to the render's first sample) of shard `i` of `n` of a render
/// of `spp` samples per pixel: `⌊i·spp/n⌋ .. ⌊(i+1)·spp/n⌋`, so the shards are disjoint, cover
/// the render, and differ in size by at most one sample.
pub fn shard_range(spp: u32, (i, n): (u32, u32)) -> Result<Range<u32>> {
    if n == 0 || i >= n {
        return Err(Error::Settings(format!(
            "shard {i}/{n}: the shard index must be below the shard count"
        )));
    }
    let at = |k: u32| (k as u64 * spp as u64 / n as u64) as u32;
    let r = at(i)..at(i + 1);
    if r.is_empty() {
        return Err(Error::Settings(format!(
            "shard {i}/{n} of {spp} spp holds no samples: use at most {spp} shards"
        )));
    }
    Ok(r)
}

/// What [`render_passes`] made.
pub struct Rendered {
    /// The image's sums.
    pub film: Film,
    /// What it cost.
    pub stats: RenderStats,
    /// The samples rendered: `first_sample .. first_sample + spp` (the same for every pixel).
    pub first_sample: u32,
    /// Samples per pixel rendered.
    pub spp: u32,
    /// Each uniform pass's samples per pixel, in order (an adaptive render that finished
    /// uniformly: its first round's, then its passes'; empty for adaptive rounds).
    pub passes: Vec<u32>,
    /// Whether the stop flag ended the render before all its samples.
    pub interrupted: bool,
    /// The independent sets of points (replicates) that hold samples: fewer than
    /// `settings.replicates` where the spp or the clock ran out before every replicate had a
    /// pass (`--replicates 4 --pass-spp 64 --spp 64` renders one), 1 where an adaptive render
    /// finished as uniform passes of one set.
    pub replicates: u32,
    /// The image's estimated error.
    pub estimate: ErrorEstimate,
    /// The rounds of an adaptive render (`None`: every pixel took the same samples).
    pub rounds: Option<u32>,
    /// Of an adaptive render's rounds after the first, those that gave every pixel the same
    /// samples because allocating could not pay ([`crate::estimate::ALLOCATE_ABOVE`]).
    pub uniform_rounds: u32,
    /// An adaptive render that finished as uniform passes after its first round: the
    /// cross-validated gain of allocating that said it could not pay.
    pub finished_uniformly: Option<f64>,
    /// An adaptive render's bounds on its relMSE gain over uniform sampling, from its own
    /// estimates ([`crate::estimate::allocation_gains`]).
    pub allocation: Option<crate::estimate::AllocationGains>,
    /// Under `--roulette ears`: the learned factor at the first vertex of each pixel's central
    /// ray (row-major; 0 where there is no Phong vertex), the cache made visible.
    pub ears_map: Option<Vec<f32>>,
}

/// The pass that holds sample `done` (relative to the render's first sample) of a render of
/// `spp` samples per pixel in passes of `pass`: `⌊done/pass⌋·pass .. min(that + pass, spp)`.
/// In u64, so no sum of two sample counts wraps (a u32 sum did, and the render spun for ever).
pub fn pass_bounds(done: u64, pass: u64, spp: u64) -> Range<u64> {
    let start = done / pass * pass;
    start..(start + pass).min(spp)
}

/// Render `settings.spp` samples per pixel as passes of `plan.pass_spp` samples (sample indices
/// `first_sample + k·pass_spp ..`, a shorter last pass being a set of its own), merging them
/// exactly; only the samples of `plan.shard`, if given. Stops early at a whole pass when
/// `plan.time_limit` runs out, and soon after `plan.stop` is set. Sample arithmetic is in u64.
///
/// Each pixel renders the samples of a pass in one go, so per-pixel work of the sampler (the
/// stratified sampler's tables) is done once per pixel and pass. A render that can be stopped
/// reads the stop flag before every pixel (and every 256 samples of one); a stop drops the pass
/// under way and renders every pixel's first samples of it instead (one, timed, then as many
/// more as fill about [`BATCH_SECONDS`] at that speed), so every pixel holds the same
/// samples and a stop waits about a quarter of a second. A partial pass is an unbiased estimate
/// (every sample of a stratified or Sobol set is uniform on its own), and the image does not
/// depend on how a pass was cut: a pixel's sums go on in sample order.
///
/// The sampler is the one `settings.strategy.sampler` names; [`render_passes_with`] takes any.
pub fn render_passes(
    scene: &Scene,
    settings: &RenderSettings,
    plan: &PassPlan,
    progress: &dyn Progress,
) -> Result<Rendered> {
    struct Passes<'a>(
        &'a Scene,
        &'a RenderSettings,
        &'a PassPlan,
        &'a dyn Progress,
    );
    impl WithSampler for Passes<'_> {
        type Out = Result<Rendered>;
        fn run<F: SamplerFactory>(self, factory: &F) -> Self::Out {
            render_passes_with(self.0, self.1, self.2, factory, self.3)
        }
    }
    with_sampler(
        settings.strategy.sampler,
        Passes(scene, settings, plan, progress),
    )
}

/// [`render_passes`] with the samplers `factory` makes, whatever `settings.strategy.sampler`
/// says: the entry point for a sampler written outside vrpt. It keeps every guarantee of the
/// built-in samplers (passes, shards, `first_sample`, time limits, the stop flag, films that
/// merge, images independent of the thread count), which go through it too.
///
/// ```
/// use vrpt::render::{render_passes_with, NoProgress, PassPlan, RenderSettings, SamplePass};
/// use vrpt::sampler::StratifiedSampler;
/// let scene = vrpt::scene::load(std::path::Path::new("scenes/cornell-box"))?;
/// let settings = RenderSettings { width: 8, height: 8, spp: 4, ..Default::default() };
/// let factory = |seed, pass: SamplePass| StratifiedSampler::with_origin(seed, pass.size, pass.origin);
/// let r = render_passes_with(&scene, &settings, &PassPlan::default(), &factory, &NoProgress)?;
/// assert_eq!((r.spp, r.film.width), (4, 8));
/// # Ok::<(), vrpt::Error>(())
/// ```
pub fn render_passes_with<F: SamplerFactory>(
    scene: &Scene,
    settings: &RenderSettings,
    plan: &PassPlan,
    factory: &F,
    progress: &dyn Progress,
) -> Result<Rendered> {
    let camera = strip_camera(scene, settings, plan)?;
    check_plan(settings, plan)?;
    let start = Instant::now();
    with_threads(settings.threads, || {
        let mut stats = RenderStats::default();
        let edges = edges::of_render(scene, &camera, (settings, plan), &mut stats);
        let edges = edges.as_deref();
        let guided = settings.strategy.directions == Directions::Guided;
        let learned = plan.guide.as_deref().filter(|_| guided);
        if let Some(l) = learned {
            stats.guide = Some(l.stats);
        }
        let mut kept = keeps_training(settings, plan).then(combine::KeptIterations::default);
        let trainer = Trainer {
            scene,
            camera: &camera,
            settings,
            plan,
            factory,
            edges,
        };
        let tree = (guided && learned.is_none()).then(|| {
            let budget = TrainingBudget::of_render(settings, plan);
            let gate = gates(settings, plan)
                .then(|| gate::Gate::new(kept.is_some()).looking_early(plan.gate_early));
            trainer.train(start, budget, &mut stats, kept.as_mut(), gate)
        });
        let tree = learned.map(|l| &l.tree).or(tree.as_ref());
        let closed = stats.guide.and_then(|g| g.gate).is_some_and(|g| g.closed());
        let guide = Guiding {
            tree,
            record: false,
        };
        let rrs = (settings.roulette == Roulette::Ears)
            .then(|| trainer.train_rrs(tree.filter(|_| !closed), &mut stats));
        let training = start.elapsed();
        let kernel = Kernel::new(scene, &camera, settings, factory, guide, progress);
        let job = Job {
            kernel: if closed { kernel.unguided() } else { kernel }
                .with_rrs(rrs.as_ref().map(|r| r.kernel()))
                .with_strip(plan.strip.as_deref())
                .with_edges(edges),
            settings,
            plan,
            start,
        };
        let mut r = if plan.adaptive {
            job.adaptive(&mut stats)?
        } else {
            job.uniform(&mut stats)?
        };
        if let (Some(kept), Some(g)) = (kept.filter(|_| learned.is_none()), &mut stats.guide) {
            g.combined = Some(kept.combine_into(&mut r.film, closed));
            r.estimate = ErrorEstimate::of(&Replicates::new(1, r.film.len()), &r.film);
        }
        stats.elapsed = start.elapsed();
        if let (Some(t), Some(g)) = (tree, &mut stats.guide) {
            g.final_time = stats.elapsed - training;
            g.tree = t.size();
        }
        if let Some(r) = &mut stats.rrs {
            r.final_time = stats.elapsed - training;
        }
        r.stats = stats;
        // (a strip's pixels are not the image's: no map of it)
        r.ears_map = (rrs.as_ref().filter(|_| plan.strip.is_none()))
            .map(|s| s.first_vertex_map(scene, &camera, (settings.width, settings.height)));
        Ok(r)
    })?
}

/// Whether a guided render of `settings` under `plan` that trains its own guide keeps its
/// training iterations in the image ([`PassPlan::discard_training`]).
fn keeps_training(settings: &RenderSettings, plan: &PassPlan) -> bool {
    trains_alone(settings, plan) && !plan.discard_training && settings.reuse <= 1
}

/// Whether a guided render of `settings` under `plan` that trains its own guide tests it with
/// its [`gate`] while it trains, unless [`PassPlan::ungated`]: over the whole image (no strip).
/// With path reuse too (its training iterations are rendered without reuse, as their paths
/// record their own bounces, and so are the probes: the gate compares the guide against Phong
/// directions as a render without reuse would; it is the same verdict as with reuse on the
/// shipped scenes, `docs/guiding.md`), and where the training images are discarded: its
/// probes are then discarded too.
fn gates(settings: &RenderSettings, plan: &PassPlan) -> bool {
    trains_alone(settings, plan) && !plan.ungated && plan.strip.is_none()
}

/// Whether a render of `settings` under `plan` trains its own guide as one image: guided, no
/// guide handed to it, one replicate, no shard (every shard of a render decides alike),
/// uniform passes.
fn trains_alone(settings: &RenderSettings, plan: &PassPlan) -> bool {
    settings.strategy.directions == Directions::Guided
        && plan.guide.is_none()
        && settings.replicates == 1
        && plan.shard.is_none()
        && !plan.adaptive
}

/// The camera of a render of `settings` under `plan`: the image's, whose size is the strip's
/// image where `plan` renders a strip (checked against the settings' size, the strip's).
pub(super) fn strip_camera(
    scene: &Scene,
    settings: &RenderSettings,
    plan: &PassPlan,
) -> Result<Camera> {
    match &plan.strip {
        Some(strip) => {
            strip.check(settings.width, settings.height)?;
            let image = RenderSettings {
                width: strip.image.x,
                height: strip.image.y,
                ..settings.clone()
            };
            camera_for(scene, &image)
        }
        None => camera_for(scene, settings),
    }
}

/// Whether `plan` can render `settings`: replicates that fit the spp, adaptive rounds with the
/// replicates they allocate from and not in a shard, a positive target error.
fn check_plan(settings: &RenderSettings, plan: &PassPlan) -> Result<()> {
    if settings.replicates == 0 {
        return Err(Error::Settings("--replicates must be at least 1".into()));
    }
    if settings.replicates > settings.spp {
        // every replicate (and every adaptive round of it) takes at least one sample per pixel
        return Err(Error::Settings(format!(
            "--replicates {} needs at least {} spp (a sample per replicate), but --spp is {}",
            settings.replicates, settings.replicates, settings.spp
        )));
    }
    if plan.adaptive && settings.replicates < 2 {
        return Err(Error::Settings(
            "--adaptive needs at least 2 replicates: it allocates from their spread".into(),
        ));
    }
    if plan.adaptive && plan.shard.is_some() {
        return Err(Error::Settings(
            "--adaptive cannot render a shard: each round's allocation depends on every sample \
             before it"
                .into(),
        ));
    }
    if let Some(e) = plan.target_error {
        if !(e > 0.0 && e.is_finite()) {
            return Err(Error::Settings(format!(
                "--target-error {e}: the target relMSE must be a positive number"
            )));
        }
    }
    Ok(())
}

/// The seed of replicate `r` of a render with seed `seed`: the seed itself for replicate 0 (a
/// render of one replicate is the render it always was), a hash of both for the others.
pub fn replicate_seed(seed: u64, r: u32) -> u64 {
    match r {
        0 => seed,
        _ => crate::math::mix64(seed ^ (r as u64).wrapping_mul(0xd1b5_4a32_d192_ed03)),
    }
}

/// What every pass of a render shares: the kernel its batches render with, its settings, its
/// plan and when it began.
struct Job<'a, F: SamplerFactory> {
    kernel: Kernel<'a, F>,
    settings: &'a RenderSettings,
    plan: &'a PassPlan,
    start: Instant,
}

impl<F: SamplerFactory> Job<'_, F> {
    fn stopped(&self) -> bool {
        self.plan
            .stop
            .as_ref()
            .is_some_and(|f| f.load(Ordering::Relaxed))
    }

    /// Render the samples `samples` of every tile into `film` with replicate `rep`'s seed,
    /// reading `stop`; add the counts to `stats`; (wall seconds per pixel sample of the pixels
    /// completed, if any; whether the stop flag cut a tile).
    fn batch(
        &self,
        rep: u32,
        samples: Samples,
        stop: Option<&AtomicBool>,
        film: &mut Film,
        stats: &mut RenderStats,
    ) -> (Option<f64>, bool) {
        let kernel = self
            .kernel
            .with_seed(replicate_seed(self.settings.seed, rep));
        let batch = Batch {
            samples,
            tiles: 0..tile_count(self.settings),
            stop,
        };
        let out = kernel.render(&batch, Some(film));
        let s = out.stats;
        stats.rays.add(&s.rays);
        stats.samples += s.samples;
        stats.nonfinite += s.nonfinite;
        stats.thread_time += s.thread_time;
        let rate = (s.samples > 0).then(|| s.elapsed.as_secs_f64() / s.samples as f64);
        (rate, out.cut)
    }
}
