//! [`compare`]: every strategy at the same spp or the same wall time per run, over K runs,
//! against the reference (see the [module above](super)).

use super::*;

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
#[derive(Clone, Debug, Default, serde::Serialize)]
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
        let mut c = Comparison {
            reference_variance: reference.variance.as_deref().map(mean_variance),
            ..Comparison::default()
        };
        for st in strategies {
            let mut runs = run_entry(scene, st, s, (spp, equal_time), progress, (&st.name, 1))?;
            let (row, regions) = entry_rows(st, &runs, reference, s);
            c.rows.push(row);
            c.regions.extend(regions);
            c.images.push(runs.images.swap_remove(0));
            c.variances.push(runs.first_variance);
            c.spp_maps.push(runs.first_spp_map);
        }
        relative_to_baseline(&mut c, s.regions.len());
        Ok(c)
    })?
}

/// One entry's row and its rows per region: means over its runs of their metrics against
/// `reference`, the variance across runs and the bias test; the reductions are left at 1.
fn entry_rows(
    st: &Entry,
    runs: &EntryRuns,
    reference: &RgbImage,
    s: &ExperimentSettings,
) -> (CompareRow, Vec<RegionRow>) {
    let ms: Vec<Metrics> = runs
        .images
        .iter()
        .map(|img| metrics(img, &reference.pixels))
        .collect();
    let regions = s
        .regions
        .iter()
        .map(|r| {
            let m: Vec<Metrics> = runs
                .images
                .iter()
                .map(|img| region_metrics(img, &reference.pixels, s.width, r))
                .collect();
            RegionRow {
                strategy: st.name.clone(),
                region: r.name.clone(),
                mse: mean_of(&m, |m| m.mse),
                rel_mse: mean_of(&m, |m| m.rel_mse),
                rmse: mean_of(&m, |m| m.rmse),
                mae: mean_of(&m, |m| m.mae),
                mse_reduction: 1.0,
            }
        })
        .collect();
    let bias = bias_test(&runs.images, &reference.pixels);
    let row = CompareRow {
        strategy: st.name.clone(),
        runs: s.runs,
        spp: mean_of(&runs.spp, |x| *x),
        seconds: mean_of(&runs.seconds, |x| *x),
        mse: mean_of(&ms, |m| m.mse),
        rel_mse: mean_of(&ms, |m| m.rel_mse),
        rmse: mean_of(&ms, |m| m.rmse),
        mae: mean_of(&ms, |m| m.mae),
        variance: variance_across_runs(&runs.images),
        est_mse: mean_of(&runs.estimates, |e| e.0),
        est_rel_mse: mean_of(&runs.estimates, |e| e.1),
        estimate: runs.method.clone(),
        bias_t: bias.t,
        bias_p: bias.p,
        mse_reduction: 1.0,
        efficiency: 1.0,
    };
    (row, regions)
}

/// Name the baseline (independent, or the first row) and set every row's MSE reduction and
/// efficiency, and every region row's MSE reduction, against it (`nr` regions per entry).
fn relative_to_baseline(c: &mut Comparison, nr: usize) {
    let rows = &mut c.rows;
    let base = rows
        .iter()
        .position(|r| r.strategy == "independent")
        .unwrap_or(0);
    let (base_mse, base_t) = (rows[base].mse, rows[base].seconds);
    for r in rows.iter_mut() {
        r.mse_reduction = base_mse / r.mse;
        r.efficiency = (base_mse * base_t) / (r.mse * r.seconds);
    }
    // region rows are strategy-major: the baseline's rows start at base × regions
    let region_rows = &mut c.regions;
    for k in 0..region_rows.len() {
        region_rows[k].mse_reduction = region_rows[base * nr + k % nr].mse / region_rows[k].mse;
    }
    c.baseline = rows[base].strategy.clone();
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
