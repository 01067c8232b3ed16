//! Experiments over strategies, each run an independent render. Run k uses the k-th seed from
//! `seed` upward that the reference does not hold ([`ExperimentSettings::run_seeds`]): a run
//! that shared the reference's random numbers (the same samples for the independent sampler, a
//! prefix for Sobol, the same decisions under other strategies) would look closer to it than
//! it is, and make the bias test weaker.
//!
//!
//! - [`compare`]: every strategy at the same spp (or the same wall time per run) over K runs;
//!   per strategy the mean time, the mean MSE / relMSE / RMSE / MAE of a run against the
//!   reference, the variance of a run (across runs), the bias test, the MSE reduction against
//!   the baseline (independent, or the first strategy) `MSE_base / MSE`, and the relative
//!   efficiency `(MSE_base · t_base) / (MSE · t)` (efficiency is `1/(MSE·time)`).
//! - [`converge`]: for each strategy and each spp, K renders from scratch (a prefix of a longer
//!   stratified run is not stratified), the mean MSE and relMSE, and the least-squares slope of
//!   `log MSE` against `log spp` (−1 for independent samples, steeper with stratification).
//!
//! Both take built-in strategies, and [`compare_entries`] and [`converge_entries`] take
//! [`Entry`]s too: a name and a strategy with a sampler of the caller's own
//! ([`Entry::custom`]), in the same table, CSV, JSON, plot and report as the built-in ones.

use crate::analysis::fit::log_log_slope;
use crate::analysis::metrics::{
    bias_test, mean_variance, metrics, region_metrics, variance_across_runs, Metrics, Region,
};
use crate::error::{Error, Result};
use crate::image_io::RgbImage;
use crate::output::RenderMetadata;
use crate::render::auto::Candidate;
use crate::render::{
    render_passes, render_passes_with, with_threads, NoProgress, PassPlan, Progress,
    RenderSettings, Rendered, SamplerFactory,
};
use crate::scene::Scene;
use crate::strategy::Strategy;
use glam::Vec3;
use std::path::Path;
use std::time::Duration;

mod compare;
mod converge;
pub use compare::{compare, compare_entries, CompareRow, Comparison, RegionRow};
pub use converge::{converge, converge_entries, ConvergePoint, ConvergeSlope, Convergence};

/// The renderer of one [`Entry`]: `(scene, settings, plan) → rendered`.
type EntryRender<'a> = dyn Fn(&Scene, &RenderSettings, &PassPlan) -> Result<Rendered> + Sync + 'a;

/// One line of an experiment: a name, the strategy it renders with (directions, lights, light
/// points and choice; and the sampler, for a built-in entry), how its samples are allocated,
/// and the renderer.
pub struct Entry<'a> {
    /// The name in tables, files and reports.
    pub name: String,
    /// The strategy of every run (for a custom entry, its `sampler` is not used).
    pub strategy: Strategy,
    /// Replicates of every run ([`RenderSettings::replicates`]; 1 unless set with
    /// [`Entry::with_replicates`]): with 2 or more, a run's estimated error comes from their
    /// spread.
    pub replicates: u32,
    /// Adaptive sampling ([`PassPlan::adaptive`]), set by [`Entry::adaptive`].
    pub adaptive: bool,
    /// Its rounds' bar ([`PassPlan::min_allocation_gain`]; `None`: the render's default), set
    /// by [`Entry::with_min_allocation_gain`].
    pub min_allocation_gain: Option<f64>,
    /// Path reuse of every run ([`RenderSettings::reuse`]; 1, off, unless set with
    /// [`Entry::with_reuse`]).
    pub reuse: u32,
    render: Box<EntryRender<'a>>,
}

impl Entry<'static> {
    /// A built-in strategy, named as it prints.
    pub fn builtin(strategy: Strategy) -> Entry<'static> {
        Entry {
            name: strategy.to_string(),
            strategy,
            replicates: 1,
            adaptive: false,
            min_allocation_gain: None,
            reuse: 1,
            render: Box::new(|scene, settings, plan| {
                render_passes(scene, settings, plan, &NoProgress)
            }),
        }
    }
}

impl Entry<'static> {
    /// `--strategy auto` among `candidates` (the first is the default; see
    /// [`crate::render::auto`]), named "auto": every run renders the pilots with its own seed,
    /// then the strategy they chose, and its time includes the pilots'.
    pub fn auto(candidates: Vec<Candidate>) -> Entry<'static> {
        let first = candidates.first().copied();
        Entry {
            name: "auto".into(),
            strategy: first.map_or_else(Strategy::default, |c| c.strategy),
            replicates: 1,
            adaptive: false,
            min_allocation_gain: None,
            reuse: first.map_or(1, |c| c.reuse),
            render: Box::new(move |scene, settings, plan| {
                let choice = crate::render::auto::choose(scene, settings, plan, &candidates)?;
                let settings = choice.settings(settings);
                let mut r = render_passes(scene, &settings, &choice.plan(plan), &NoProgress)?;
                r.stats.elapsed += choice.elapsed;
                Ok(r)
            }),
        }
    }
}

impl<'a> Entry<'a> {
    /// A sampler of the caller's own (see [`SamplerFactory`]) with the direction and light
    /// parts of `strategy`, under `name`.
    pub fn custom<F: SamplerFactory + 'a>(name: &str, factory: F, strategy: Strategy) -> Entry<'a> {
        Entry {
            name: name.to_string(),
            strategy,
            replicates: 1,
            adaptive: false,
            min_allocation_gain: None,
            reuse: 1,
            render: Box::new(move |scene, settings, plan| {
                render_passes_with(scene, settings, plan, &factory, &NoProgress)
            }),
        }
    }
}

impl Entry<'_> {
    /// Every run as `r` replicates, each a complete set of the run's spp/r samples.
    pub fn with_replicates(mut self, r: u32) -> Self {
        self.replicates = r;
        self
    }

    /// Adaptive allocation of every run's samples, named "`<name> adaptive`" (needs at least 2
    /// replicates: the run fails otherwise).
    pub fn adaptive(mut self) -> Self {
        self.name += " adaptive";
        self.adaptive = true;
        self
    }

    /// Path reuse in `k × k` blocks for every run, named "`<name> reuse k`" (1: off).
    pub fn with_reuse(mut self, k: u32) -> Self {
        if k > 1 {
            self.name += &format!(" reuse {k}");
        }
        self.reuse = k;
        self
    }

    /// Adaptive rounds allocate only where the cross-validated gain is at least `g` (0: every
    /// round, whatever the gain).
    pub fn with_min_allocation_gain(mut self, g: f64) -> Self {
        self.min_allocation_gain = Some(g);
        self
    }
}

impl std::fmt::Debug for Entry<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Entry")
            .field("name", &self.name)
            .field("strategy", &self.strategy)
            .field("replicates", &self.replicates)
            .field("adaptive", &self.adaptive)
            .field("min_allocation_gain", &self.min_allocation_gain)
            .finish_non_exhaustive()
    }
}

/// What every experiment needs besides the strategies.
#[derive(Clone, Debug, PartialEq)]
pub struct ExperimentSettings {
    /// Image width in pixels (the reference's).
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Max path depth of every run (the reference's).
    pub max_depth: u32,
    /// The first seed of the runs (see [`ExperimentSettings::run_seeds`]).
    pub seed: u64,
    /// The seeds whose samples the reference holds (from its metadata): no run uses them.
    pub reference_seeds: Vec<u64>,
    /// Independent runs per strategy (and per spp, in a sweep).
    pub runs: u32,
    /// Worker threads; `None`: all cores.
    pub threads: Option<usize>,
    /// Parts of the image whose metrics `compare` also reports on their own.
    pub regions: Vec<Region>,
}

impl ExperimentSettings {
    /// Settings that match `reference` (read from `path`): its size, and its max depth where it
    /// records one (else the scene's default, else the renderer's). The reference is checked
    /// against the scene with [`check_reference`].
    pub fn for_reference(
        scene: &Scene,
        reference: &RgbImage,
        path: &Path,
        seed: u64,
        runs: u32,
        threads: Option<usize>,
    ) -> Result<ExperimentSettings> {
        let meta = RenderMetadata::radiance(reference, path)?;
        let reference_seeds = match &meta {
            None => Vec::new(),
            Some(m) if m.seed.is_none() && m.merged_seeds.is_empty() => {
                return Err(Error::Settings(format!(
                    "reference {}: a merge that does not record its inputs' seeds (made by an \
                     older vrpt), so the runs could reuse its samples: merge it again",
                    path.display()
                )))
            }
            Some(m) => m.seeds(),
        };
        let max_depth = meta.as_ref().map_or_else(
            || {
                scene
                    .defaults
                    .max_depth
                    .unwrap_or(RenderSettings::default().max_depth)
            },
            |m| m.max_depth,
        );
        let s = ExperimentSettings {
            width: reference.width,
            height: reference.height,
            max_depth,
            seed,
            reference_seeds,
            runs,
            threads,
            regions: Vec::new(),
        };
        check_reference(scene, reference, &s)?;
        Ok(s)
    }
}

impl ExperimentSettings {
    /// The seeds of the runs: the first `runs` seeds from `seed` upward that are not among
    /// `reference_seeds`, so no run shares the reference's random numbers.
    pub fn run_seeds(&self) -> Vec<u64> {
        (self.seed..)
            .filter(|s| !self.reference_seeds.contains(s))
            .take(self.runs as usize)
            .collect()
    }
}

/// Check that `reference` fits the scene and settings: same size, and, where the reference
/// records them, the same scene hash and max depth.
pub fn check_reference(scene: &Scene, reference: &RgbImage, s: &ExperimentSettings) -> Result<()> {
    let err = |m: String| Error::Settings(format!("reference: {m}"));
    if (reference.width, reference.height) != (s.width, s.height) {
        return Err(err(format!(
            "{}×{} image, but the experiment renders {}×{}",
            reference.width, reference.height, s.width, s.height
        )));
    }
    for r in &s.regions {
        r.check(s.width, s.height).map_err(&err)?;
    }
    let Some(meta) = RenderMetadata::radiance(reference, Path::new("reference"))? else {
        return Ok(());
    };
    if meta.scene_hash != scene.hash {
        return Err(err(format!(
            "made from another version of the scene (scene hash {}, the scene is {:016x}): \
             render the reference again",
            meta.scene_hash_hex(),
            scene.hash
        )));
    }
    let shared: Vec<u64> = s
        .run_seeds()
        .into_iter()
        .filter(|x| meta.seeds().contains(x))
        .collect();
    if !shared.is_empty() {
        return Err(err(format!(
            "holds the samples of seed {}, which a run would use too: give the runs other seeds \
             (ExperimentSettings::for_reference skips the reference's)",
            shared[0]
        )));
    }
    if meta.max_depth != s.max_depth {
        return Err(err(format!(
            "rendered with max depth {}, the experiment uses {}",
            meta.max_depth, s.max_depth
        )));
    }
    Ok(())
}

/// The render settings of run `k` of strategy `st`, on the job's thread pool.
fn run_settings(st: &Entry, s: &ExperimentSettings, spp: u32, seed: u64) -> RenderSettings {
    RenderSettings {
        width: s.width,
        height: s.height,
        spp,
        first_sample: 0,
        max_depth: s.max_depth,
        seed,
        strategy: st.strategy,
        threads: None,
        time_traces: false,
        replicates: st.replicates,
        reuse: st.reuse,
        roulette: crate::integrator::rrs::Roulette::Classic,
        // the strategy's own points everywhere: edge rays bring Sobol points of their own to
        // the light's edges, whatever sampler the experiment compares
        edge_rays: 0,
    }
}

/// The samples each pixel of `film` holds, row-major (what an adaptive run spent where).
fn samples_per_pixel(film: &crate::film::Film) -> Vec<u32> {
    (0..film.len())
        .map(|i| film.count(i).min(u32::MAX as u64) as u32)
        .collect()
}

/// The runs of one entry at one spp (or one wall time): per run, in seed order, its mean image,
/// wall time, spp reached and its own error estimate; and what the first run leaves the report.
#[derive(Default)]
struct EntryRuns {
    /// Each run's mean image (row-major).
    images: Vec<Vec<Vec3>>,
    /// Each run's wall time in seconds.
    seconds: Vec<f64>,
    /// Each run's spp reached.
    spp: Vec<f64>,
    /// Each run's estimate of its own MSE and relMSE.
    estimates: Vec<(f64, f64)>,
    /// The first run's per-pixel variance of its mean.
    first_variance: Vec<Vec3>,
    /// The first run's samples per pixel, for an adaptive entry.
    first_spp_map: Option<Vec<u32>>,
    /// How the first run estimated its error (its method's name).
    method: String,
}

/// Render entry `st` once per run seed ([`ExperimentSettings::run_seeds`]): at `spp`, or with
/// `equal_time` in passes of `spp` until that time is past. Each run is reported to `progress`
/// as "`label` run k/K" and advances it by `advance`.
fn run_entry(
    scene: &Scene,
    st: &Entry,
    s: &ExperimentSettings,
    (spp, equal_time): (u32, Option<Duration>),
    progress: &dyn Progress,
    (label, advance): (&str, u64),
) -> Result<EntryRuns> {
    let mut runs = EntryRuns::default();
    for (k, seed) in s.run_seeds().into_iter().enumerate() {
        let max_spp = if equal_time.is_some() {
            u32::MAX / 2
        } else {
            spp
        };
        let settings = run_settings(st, s, max_spp, seed);
        // equal spp: the render's own passes (one per replicate); equal time: passes of
        // `spp`, a whole pass past the limit
        let plan = PassPlan {
            pass_spp: equal_time.map(|_| spp),
            time_limit: equal_time,
            adaptive: st.adaptive,
            min_allocation_gain: st.min_allocation_gain,
            ..PassPlan::default()
        };
        let r = (st.render)(scene, &settings, &plan)?;
        if k == 0 {
            runs.first_variance = r.film.variance_image();
            runs.first_spp_map = st.adaptive.then(|| samples_per_pixel(&r.film));
            runs.method = r.estimate.method.name().to_string();
        }
        runs.images.push(r.film.mean_image());
        runs.estimates.push((r.estimate.mse, r.estimate.rel_mse));
        runs.seconds.push(r.stats.elapsed.as_secs_f64());
        runs.spp.push(r.spp as f64);
        progress.finished(&format!("{label} run {}/{}", k + 1, s.runs));
        progress.advance(advance);
    }
    Ok(runs)
}

/// One small untimed render, so the first timed run does not pay for starting the thread pool
/// and warming the caches.
fn warm_up(scene: &Scene, s: &ExperimentSettings) -> Result<()> {
    let settings = RenderSettings {
        width: s.width.min(16),
        height: s.height.min(16),
        spp: 1,
        max_depth: s.max_depth,
        ..RenderSettings::default()
    };
    render_passes(scene, &settings, &PassPlan::default(), &NoProgress).map(|_| ())
}

/// Write `rows` as CSV (a header from the field names, one line per row) to `path`, through a
/// temporary file.
pub fn write_csv<T: serde::Serialize>(path: &Path, rows: &[T]) -> Result<()> {
    let err = |e: csv::Error| Error::Write {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r).map_err(err)?;
    }
    let bytes = w.into_inner().map_err(|e| Error::Write {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    crate::image_io::write_bytes(path, &bytes)
}
