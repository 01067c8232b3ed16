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
use crate::render::{
    render_passes, render_passes_with, with_threads, NoProgress, PassPlan, Progress,
    RenderSettings, Rendered, SamplerFactory,
};
use crate::scene::Scene;
use crate::strategy::Strategy;
use glam::Vec3;
use std::path::Path;
use std::time::Duration;

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
            render: Box::new(|scene, settings, plan| {
                render_passes(scene, settings, plan, &NoProgress)
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
}

impl std::fmt::Debug for Entry<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Entry")
            .field("name", &self.name)
            .field("strategy", &self.strategy)
            .field("replicates", &self.replicates)
            .field("adaptive", &self.adaptive)
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

/// One strategy's row of a comparison.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CompareRow {
    /// The entry's name.
    pub strategy: String,
    /// Runs averaged.
    pub runs: u32,
    /// Mean spp per run (equal-time runs reach different spp).
    pub spp: f64,
    /// Mean wall time per run.
    pub seconds: f64,
    /// Mean over runs of each run's error metrics.
    pub mse: f64,
    /// Mean relMSE, `mean((x − r)²/(r² + 0.01))`.
    pub rel_mse: f64,
    /// Mean RMSE.
    pub rmse: f64,
    /// Mean absolute error.
    pub mae: f64,
    /// Per-pixel variance of one run, across runs (averaged over pixels and channels).
    pub variance: f64,
    /// Mean over runs of the MSE each run estimated for itself ([`crate::estimate`]).
    pub est_mse: f64,
    /// Mean over runs of the relMSE each run estimated for itself.
    pub est_rel_mse: f64,
    /// How the runs estimated it: "replicates" (honest for every sampler) or "per-sample"
    /// (one replicate: `s²/n`, an overestimate for stratified and Sobol points).
    pub estimate: String,
    /// Bias test of the runs against the reference: Student's t and its two-sided p.
    pub bias_t: f64,
    /// Two-sided p of `bias_t`.
    pub bias_p: f64,
    /// `MSE_baseline / MSE`.
    pub mse_reduction: f64,
    /// `(MSE_baseline · t_baseline) / (MSE · t)`.
    pub efficiency: f64,
}

/// One strategy's metrics over one region (means over runs).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RegionRow {
    /// The entry's name.
    pub strategy: String,
    /// The region's name.
    pub region: String,
    /// Mean MSE over the region.
    pub mse: f64,
    /// Mean relMSE over the region.
    pub rel_mse: f64,
    /// Mean RMSE over the region.
    pub rmse: f64,
    /// Mean absolute error over the region.
    pub mae: f64,
    /// `MSE_baseline / MSE` in this region.
    pub mse_reduction: f64,
}

/// A comparison: one row per strategy and each strategy's first run's image.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Comparison {
    /// One row per entry, in the order given.
    pub rows: Vec<CompareRow>,
    /// Per strategy (in the order of `rows`) and region (in the settings' order).
    pub regions: Vec<RegionRow>,
    /// The name of the baseline row (independent, or the first).
    pub baseline: String,
    #[serde(skip)]
    /// Each entry's first run's image (row-major).
    pub images: Vec<Vec<Vec3>>,
    /// The per-pixel variance of the mean of each strategy's first run (for the report).
    #[serde(skip)]
    pub variances: Vec<Vec<Vec3>>,
    /// For each adaptive entry (`None` for the others), its first run's samples per pixel.
    #[serde(skip)]
    pub spp_maps: Vec<Option<Vec<u32>>>,
    /// The reference's mean variance of the mean, if it records one: the floor under every MSE.
    pub reference_variance: Option<f64>,
}

fn mean_of<T>(v: &[T], f: impl Fn(&T) -> f64) -> f64 {
    v.iter().map(f).sum::<f64>() / v.len() as f64
}

/// Compare `strategies` at `spp` per run (or `equal_time` per run, in passes of `spp`).
///
/// ```
/// use vrpt::analysis::experiments::{compare, ExperimentSettings};
/// use vrpt::image_io::RgbImage;
/// use vrpt::render::{render, NoProgress, RenderSettings};
/// use vrpt::strategy::Strategy;
/// let scene = vrpt::scene::load(std::path::Path::new("scenes/cornell-box"))?;
/// // a reference (in earnest: thousands of spp, `vrpt render`, read with `read_exr`)
/// let r = RenderSettings { width: 8, height: 8, spp: 256, seed: 1000, ..Default::default() };
/// let (film, _) = render(&scene, &r, &NoProgress)?;
/// let reference = RgbImage { width: 8, height: 8, pixels: film.mean_image(), ..Default::default() };
/// let s = ExperimentSettings {
///     width: 8, height: 8, max_depth: 8, seed: 1, reference_seeds: vec![1000],
///     runs: 2, threads: None, regions: Vec::new(),
/// };
/// let strategies = Strategy::parse_list("independent,mis").map_err(vrpt::Error::Settings)?;
/// let c = compare(&scene, &reference, &strategies, 4, None, &s, &NoProgress)?;
/// print!("{}", c.table());
/// assert!(c.rows[1].mse < c.rows[0].mse); // MIS beats uniform directions without light sampling
/// # Ok::<(), vrpt::Error>(())
/// ```
pub fn compare(
    scene: &Scene,
    reference: &RgbImage,
    strategies: &[Strategy],
    spp: u32,
    equal_time: Option<Duration>,
    s: &ExperimentSettings,
    progress: &dyn Progress,
) -> Result<Comparison> {
    let entries: Vec<Entry> = strategies.iter().map(|&st| Entry::builtin(st)).collect();
    compare_entries(scene, reference, &entries, spp, equal_time, s, progress)
}

/// [`compare`] over entries, built-in or custom.
pub fn compare_entries(
    scene: &Scene,
    reference: &RgbImage,
    strategies: &[Entry],
    spp: u32,
    equal_time: Option<Duration>,
    s: &ExperimentSettings,
    progress: &dyn Progress,
) -> Result<Comparison> {
    check_reference(scene, reference, s)?;
    if strategies.is_empty() || s.runs < 2 || spp == 0 {
        return Err(Error::Settings(
            "compare needs at least one strategy, 2 runs and 1 spp".into(),
        ));
    }
    // one thread pool for the whole job: no run pays for starting one
    with_threads(s.threads, || -> Result<Comparison> {
        warm_up(scene, s)?;
        let mut rows = Vec::new();
        let mut region_rows: Vec<RegionRow> = Vec::new();
        let mut images = Vec::new();
        let mut variances = Vec::new();
        let mut spp_maps = Vec::new();
        for st in strategies {
            let mut runs: Vec<Vec<Vec3>> = Vec::new();
            let (mut secs, mut spps, mut ms) = (Vec::new(), Vec::new(), Vec::<Metrics>::new());
            let (mut est, mut method) = (Vec::new(), String::new());
            let mut region_ms: Vec<Vec<Metrics>> = vec![Vec::new(); s.regions.len()];
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
                    ..PassPlan::default()
                };
                let r = (st.render)(scene, &settings, &plan)?;
                let (film, stats, reached) = (r.film, r.stats, r.spp);
                let img = film.mean_image();
                if k == 0 {
                    variances.push(film.variance_image());
                    spp_maps.push(st.adaptive.then(|| samples_per_pixel(&film)));
                    method = r.estimate.method.name().to_string();
                }
                est.push((r.estimate.mse, r.estimate.rel_mse));
                ms.push(metrics(&img, &reference.pixels));
                for (r, m) in s.regions.iter().zip(&mut region_ms) {
                    m.push(region_metrics(&img, &reference.pixels, s.width, r));
                }
                secs.push(stats.elapsed.as_secs_f64());
                spps.push(reached as f64);
                runs.push(img);
                progress.finished(&format!("{} run {}/{}", st.name, k + 1, s.runs));
                progress.advance(1);
            }
            for (r, m) in s.regions.iter().zip(&region_ms) {
                region_rows.push(RegionRow {
                    strategy: st.name.clone(),
                    region: r.name.clone(),
                    mse: mean_of(m, |m| m.mse),
                    rel_mse: mean_of(m, |m| m.rel_mse),
                    rmse: mean_of(m, |m| m.rmse),
                    mae: mean_of(m, |m| m.mae),
                    mse_reduction: 1.0,
                });
            }
            let bias = bias_test(&runs, &reference.pixels);
            rows.push(CompareRow {
                strategy: st.name.clone(),
                runs: s.runs,
                spp: mean_of(&spps, |x| *x),
                seconds: mean_of(&secs, |x| *x),
                mse: mean_of(&ms, |m| m.mse),
                rel_mse: mean_of(&ms, |m| m.rel_mse),
                rmse: mean_of(&ms, |m| m.rmse),
                mae: mean_of(&ms, |m| m.mae),
                variance: variance_across_runs(&runs),
                est_mse: mean_of(&est, |e| e.0),
                est_rel_mse: mean_of(&est, |e| e.1),
                estimate: method,
                bias_t: bias.t,
                bias_p: bias.p,
                mse_reduction: 1.0,
                efficiency: 1.0,
            });
            images.push(runs.swap_remove(0));
        }
        let base = rows
            .iter()
            .position(|r| r.strategy == "independent")
            .unwrap_or(0);
        let (base_mse, base_t) = (rows[base].mse, rows[base].seconds);
        for r in &mut rows {
            r.mse_reduction = base_mse / r.mse;
            r.efficiency = (base_mse * base_t) / (r.mse * r.seconds);
        }
        // region rows are strategy-major: the baseline's rows start at base × regions
        let nr = s.regions.len();
        for k in 0..region_rows.len() {
            region_rows[k].mse_reduction = region_rows[base * nr + k % nr].mse / region_rows[k].mse;
        }
        let reference_variance = reference.variance.as_deref().map(mean_variance);
        Ok(Comparison {
            baseline: rows[base].strategy.clone(),
            rows,
            regions: region_rows,
            images,
            variances,
            spp_maps,
            reference_variance,
        })
    })?
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
        guide_pdf_scale: 1.0,
        replicates: st.replicates,
    }
}

/// The samples each pixel of `film` holds, row-major (what an adaptive run spent where).
fn samples_per_pixel(film: &crate::film::Film) -> Vec<u32> {
    (0..film.len())
        .map(|i| film.count(i).min(u32::MAX as u64) as u32)
        .collect()
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

/// One point of a convergence sweep.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ConvergePoint {
    /// The entry's name.
    pub strategy: String,
    /// Samples per pixel of each run.
    pub spp: u32,
    /// Mean MSE of a run.
    pub mse: f64,
    /// Mean relMSE of a run.
    pub rel_mse: f64,
    /// Mean wall time per run.
    pub seconds: f64,
    /// Mean over runs of the MSE each run estimated for itself ([`crate::estimate`]).
    pub est_mse: f64,
    /// Mean over runs of the relMSE each run estimated for itself.
    pub est_rel_mse: f64,
}

/// A sweep: points in (strategy, spp) order, and per strategy the fitted log-log slopes of MSE
/// and relMSE against spp.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Convergence {
    /// Every (entry, spp) point.
    pub points: Vec<ConvergePoint>,
    /// One fit per entry.
    pub slopes: Vec<ConvergeSlope>,
    /// Per point (in the order of `points`), the first run's image and the per-pixel variance
    /// of its mean (for the report).
    #[serde(skip)]
    pub images: Vec<(Vec<Vec3>, Vec<Vec3>)>,
    /// Per point, for adaptive entries (`None` for the others), the first run's samples per
    /// pixel.
    #[serde(skip)]
    pub spp_maps: Vec<Option<Vec<u32>>>,
}

/// The fitted convergence rates of one strategy.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ConvergeSlope {
    /// The entry's name.
    pub strategy: String,
    /// Least-squares slope of log MSE against log spp.
    pub mse_slope: f64,
    /// Least-squares slope of log relMSE against log spp.
    pub rel_mse_slope: f64,
}

/// Render each strategy at each spp from scratch, `runs` times, against `reference`.
pub fn converge(
    scene: &Scene,
    reference: &RgbImage,
    strategies: &[Strategy],
    spps: &[u32],
    s: &ExperimentSettings,
    progress: &dyn Progress,
) -> Result<Convergence> {
    let entries: Vec<Entry> = strategies.iter().map(|&st| Entry::builtin(st)).collect();
    converge_entries(scene, reference, &entries, spps, s, progress)
}

/// [`converge`] over entries, built-in or custom.
pub fn converge_entries(
    scene: &Scene,
    reference: &RgbImage,
    strategies: &[Entry],
    spps: &[u32],
    s: &ExperimentSettings,
    progress: &dyn Progress,
) -> Result<Convergence> {
    check_reference(scene, reference, s)?;
    if strategies.is_empty() || spps.len() < 2 || s.runs < 1 || spps.contains(&0) {
        return Err(Error::Settings(
            "converge needs at least one strategy, two spp values ≥ 1 and one run".into(),
        ));
    }
    with_threads(s.threads, || -> Result<Convergence> {
        warm_up(scene, s)?;
        let mut points = Vec::new();
        let mut slopes = Vec::new();
        let mut images = Vec::new();
        let mut spp_maps = Vec::new();
        for st in strategies {
            let mut xs = Vec::new();
            let (mut ys, mut rs) = (Vec::new(), Vec::new());
            for &spp in spps {
                let (mut mse, mut rel, mut secs) = (0.0, 0.0, 0.0);
                let (mut est_mse, mut est_rel) = (0.0, 0.0);
                for (k, seed) in s.run_seeds().into_iter().enumerate() {
                    let settings = run_settings(st, s, spp, seed);
                    let plan = PassPlan {
                        adaptive: st.adaptive,
                        ..PassPlan::default()
                    };
                    let r = (st.render)(scene, &settings, &plan)?;
                    est_mse += r.estimate.mse;
                    est_rel += r.estimate.rel_mse;
                    let (film, stats) = (r.film, r.stats);
                    let img = film.mean_image();
                    let m = metrics(&img, &reference.pixels);
                    if k == 0 {
                        spp_maps.push(st.adaptive.then(|| samples_per_pixel(&film)));
                        images.push((img, film.variance_image()));
                    }
                    mse += m.mse;
                    rel += m.rel_mse;
                    secs += stats.elapsed.as_secs_f64();
                    progress.finished(&format!("{} spp {spp} run {}/{}", st.name, k + 1, s.runs));
                    progress.advance(spp as u64);
                }
                let k = s.runs as f64;
                points.push(ConvergePoint {
                    strategy: st.name.clone(),
                    spp,
                    mse: mse / k,
                    rel_mse: rel / k,
                    seconds: secs / k,
                    est_mse: est_mse / k,
                    est_rel_mse: est_rel / k,
                });
                xs.push(spp as f64);
                ys.push(mse / k);
                rs.push(rel / k);
            }
            slopes.push(ConvergeSlope {
                strategy: st.name.clone(),
                mse_slope: log_log_slope(&xs, &ys),
                rel_mse_slope: log_log_slope(&xs, &rs),
            });
        }
        Ok(Convergence {
            points,
            slopes,
            images,
            spp_maps,
        })
    })?
}

impl Comparison {
    /// The comparison as a table (what `vrpt compare` prints).
    pub fn table(&self) -> String {
        let mut s = format!(
            "{:<22} {:>7} {:>9} {:>11} {:>11} {:>11} {:>11} {:>8} {:>8} {:>10} {:>10}\n",
            "strategy",
            "spp",
            "time s",
            "MSE",
            "est. MSE",
            "relMSE",
            "variance",
            "bias t",
            "bias p",
            "MSE red.",
            "efficiency"
        );
        for r in &self.rows {
            s += &format!(
                "{:<22} {:>7.1} {:>9.3} {:>11.4e} {:>11.4e} {:>11.4e} {:>11.4e} {:>+8.2} {:>8.3} {:>9.2}x {:>9.2}x\n",
                r.strategy, r.spp, r.seconds, r.mse, r.est_mse, r.rel_mse, r.variance, r.bias_t, r.bias_p, r.mse_reduction, r.efficiency
            );
        }
        s += &format!(
            "(MSE reduction and efficiency 1/(MSE·time) relative to {}; means over {} runs; \
             est. MSE: what each run estimated for itself, {}",
            self.baseline,
            self.rows.first().map_or(0, |r| r.runs),
            match self.rows.first().map(|r| r.estimate.as_str()) {
                Some("replicates") => "from its replicates",
                _ => "per sample (s²/n, too high for stratified and Sobol points: --replicates)",
            }
        );
        if let Some(v) = self.reference_variance {
            s += &format!("; the reference's own variance, {v:.3e}, is a floor under every MSE");
        }
        s += ")\n";
        if !self.regions.is_empty() {
            s += "\nMSE per region (best in each region marked *):\n";
            s += &format!("{:<22}", "region");
            for r in &self.rows {
                s += &format!(" {:>22}", r.strategy);
            }
            s += "\n";
            let nr = self.regions.len() / self.rows.len().max(1);
            for k in 0..nr {
                let row: Vec<&RegionRow> = (0..self.rows.len())
                    .map(|i| &self.regions[i * nr + k])
                    .collect();
                let best = row.iter().map(|r| r.mse).fold(f64::INFINITY, f64::min);
                s += &format!("{:<22}", row[0].region);
                for r in &row {
                    let mark = if r.mse == best { "*" } else { " " };
                    s += &format!(" {:>21.4e}{mark}", r.mse);
                }
                s += "\n";
            }
        }
        s
    }
}

impl Convergence {
    /// The sweep as a table of points and slopes (what `vrpt converge` prints).
    pub fn table(&self) -> String {
        let mut s = format!(
            "{:<22} {:>7} {:>11} {:>11} {:>11} {:>9}\n",
            "strategy", "spp", "MSE", "est. MSE", "relMSE", "time s"
        );
        for p in &self.points {
            s += &format!(
                "{:<22} {:>7} {:>11.4e} {:>11.4e} {:>11.4e} {:>9.3}\n",
                p.strategy, p.spp, p.mse, p.est_mse, p.rel_mse, p.seconds
            );
        }
        s += "fitted slopes of log error against log spp:\n";
        for sl in &self.slopes {
            s += &format!(
                "{:<22} MSE {:+.3}   relMSE {:+.3}\n",
                sl.strategy, sl.mse_slope, sl.rel_mse_slope
            );
        }
        s
    }
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
