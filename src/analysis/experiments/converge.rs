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
                        min_allocation_gain: st.min_allocation_gain,
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
