//! [`converge`]: the error against spp, each spp rendered from scratch K times, with the fitted
//! slopes (see the [module above](super)).

use super::*;

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
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
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
        let mut c = Convergence::default();
        for st in strategies {
            let mut xs = Vec::new();
            let (mut ys, mut rs) = (Vec::new(), Vec::new());
            for &spp in spps {
                let label = format!("{} spp {spp}", st.name);
                let mut runs =
                    run_entry(scene, st, s, (spp, None), progress, (&label, spp as u64))?;
                let point = point_of(st, spp, &runs, reference, s.runs);
                xs.push(spp as f64);
                ys.push(point.mse);
                rs.push(point.rel_mse);
                c.points.push(point);
                c.spp_maps.push(runs.first_spp_map);
                c.images
                    .push((runs.images.swap_remove(0), runs.first_variance));
            }
            c.slopes.push(ConvergeSlope {
                strategy: st.name.clone(),
                mse_slope: log_log_slope(&xs, &ys),
                rel_mse_slope: log_log_slope(&xs, &rs),
            });
        }
        Ok(c)
    })?
}

/// The point of entry `st` at `spp`: its `k` runs' means of their MSE and relMSE against
/// `reference`, of their wall time and of their own error estimates.
fn point_of(st: &Entry, spp: u32, runs: &EntryRuns, reference: &RgbImage, k: u32) -> ConvergePoint {
    let (mut mse, mut rel, mut secs) = (0.0, 0.0, 0.0);
    let (mut est_mse, mut est_rel) = (0.0, 0.0);
    for (i, img) in runs.images.iter().enumerate() {
        let m = metrics(img, &reference.pixels);
        est_mse += runs.estimates[i].0;
        est_rel += runs.estimates[i].1;
        mse += m.mse;
        rel += m.rel_mse;
        secs += runs.seconds[i];
    }
    let k = k as f64;
    ConvergePoint {
        strategy: st.name.clone(),
        spp,
        mse: mse / k,
        rel_mse: rel / k,
        seconds: secs / k,
        est_mse: est_mse / k,
        est_rel_mse: est_rel / k,
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
