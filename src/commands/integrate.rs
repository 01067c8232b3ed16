//! `vrpt integrate`: known-answer integrals estimated by each sampler and direction strategy
//! over many repetitions, the measured mean and variance beside the exact value and the
//! variance formulas ([`crate::analysis::integrate`] has them), and the covariance of two
//! samples of one estimate. A table on the terminal; `--json` writes the rows.

use crate::analysis::integrate::{
    covariance, estimates, mean_var, predicted_variance, variance_se, Domain, Integrand,
};
use crate::error::Result;
use crate::image_io::check_writable;
use crate::sampler::SamplerKind;
use std::path::PathBuf;

/// What to estimate (the flags of `vrpt integrate`).
#[derive(Clone, Debug, clap::Args)]
pub struct IntegrateRequest {
    /// Integrands, comma-separated: smooth, disk, cosine, lobe.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "smooth,disk,cosine,lobe"
    )]
    pub integrand: Vec<Integrand>,
    /// Samplers, comma-separated: independent, stratified, sobol.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "independent,stratified,sobol"
    )]
    pub sampler: Vec<SamplerKind>,
    /// Samples per estimate, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "16,64,256",
          value_parser = clap::value_parser!(u32).range(2..=4096))]
    pub n: Vec<u32>,
    /// Independent repetitions of every estimate.
    #[arg(long, default_value_t = 4000, value_parser = clap::value_parser!(u32).range(100..=1_000_000))]
    pub repetitions: u32,
    /// Seed of the first repetition.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The rows as JSON.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

/// One measured row: an estimate's mean and variance, or a covariance of two of its samples.
#[derive(Clone, Debug, serde::Serialize)]
pub struct IntegrateRow {
    pub integrand: Integrand,
    pub sampler: String,
    pub directions: Domain,
    pub n: u32,
    pub repetitions: u32,
    pub exact: f64,
    /// The mean of the estimates and its 99% interval (`None` on covariance rows).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mean: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mean_ci: Option<[f64; 2]>,
    /// The estimates' variance, its 99% interval (from its fourth moment), and the formula's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub variance: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub variance_ci: Option<[f64; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub predicted_variance: Option<f64>,
    /// `sigma2/N` (an equality), `jittered bound` (an upper bound) or none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prediction: Option<String>,
    /// Covariance rows: which pair, the covariance and its 99% interval.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pair: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub covariance: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub covariance_ci: Option<[f64; 2]>,
}

/// The rows, and the files written.
#[derive(Clone, Debug)]
pub struct IntegrateOutcome {
    pub rows: Vec<IntegrateRow>,
    pub written: Vec<PathBuf>,
}

/// Estimate every integral asked for; write the JSON asked for.
pub fn run(req: &IntegrateRequest) -> Result<IntegrateOutcome> {
    if let Some(p) = &req.json {
        check_writable(p)?;
    }
    let mut rows = Vec::new();
    for &f in &req.integrand {
        for &d in f.domains() {
            for &kind in &req.sampler {
                for (k, &n) in req.n.iter().enumerate() {
                    let e = estimates(f, d, kind, n, (req.seed, req.repetitions));
                    let xs: Vec<f64> = e.iter().map(|t| t.0).collect();
                    let (m, v, half) = mean_var(&xs);
                    let se = 2.576 * variance_se(&xs);
                    let p = predicted_variance(f, d, kind, n);
                    let base = IntegrateRow {
                        integrand: f,
                        sampler: kind.to_string(),
                        directions: d,
                        n,
                        repetitions: req.repetitions,
                        exact: f.exact(),
                        mean: Some(m),
                        mean_ci: Some([m - half, m + half]),
                        variance: Some(v),
                        variance_ci: Some([(v - se).max(0.0), v + se]),
                        predicted_variance: p.map(|p| p.0),
                        prediction: p.map(|p| p.1.to_string()),
                        pair: None,
                        covariance: None,
                        covariance_ci: None,
                    };
                    if k == 0 {
                        let pairs: Vec<(f64, f64)> = e.iter().map(|t| (t.1, t.2)).collect();
                        let (c, h) = covariance(&pairs);
                        rows.push(IntegrateRow {
                            mean: None,
                            mean_ci: None,
                            variance: None,
                            variance_ci: None,
                            predicted_variance: None,
                            prediction: None,
                            pair: Some("samples 0 and 1 of one estimate".into()),
                            covariance: Some(c),
                            covariance_ci: Some([c - h, c + h]),
                            ..base.clone()
                        });
                    }
                    rows.push(base);
                }
            }
        }
    }
    let mut written = Vec::new();
    if let Some(p) = &req.json {
        super::write_json(p, &rows)?;
        written.push(p.clone());
    }
    Ok(IntegrateOutcome { rows, written })
}

impl IntegrateOutcome {
    /// The rows as a table for the terminal.
    pub fn table(&self) -> String {
        let name =
            |r: &IntegrateRow| format!("{:?}/{:?}", r.integrand, r.directions).to_lowercase();
        let mut s = format!(
            "{:<16} {:<12} {:>5} {:>11} {:>11} {:>11} {:>11} {:>8}  {}\n",
            "integral",
            "sampler",
            "N",
            "mean",
            "exact",
            "variance",
            "predicted",
            "ratio",
            "prediction"
        );
        for r in &self.rows {
            if let Some(c) = r.covariance {
                let ci = r.covariance_ci.unwrap_or([c, c]);
                s += &format!(
                    "{:<16} {:<12} {:>5} covariance of samples 0 and 1: {c:+.3e} (99%: {:+.2e} .. {:+.2e})\n",
                    name(r), r.sampler, r.n, ci[0], ci[1]
                );
                continue;
            }
            let (v, p) = (r.variance.unwrap_or(0.0), r.predicted_variance);
            // no ratio where the formula says zero (a perfect importance sampler: what is
            // measured there is f32 rounding)
            let tiny = 1e-12 * r.exact * r.exact;
            let ratio = p
                .filter(|&p| p > tiny)
                .map_or("—".into(), |p| format!("{:.3}", v / p));
            s += &format!(
                "{:<16} {:<12} {:>5} {:>11.6} {:>11.6} {:>11.3e} {:>11} {:>8}  {}\n",
                name(r),
                r.sampler,
                r.n,
                r.mean.unwrap_or(0.0),
                r.exact,
                v,
                p.map_or("—".into(), |p| format!("{p:.3e}")),
                ratio,
                r.prediction.as_deref().unwrap_or("none")
            );
        }
        s
    }
}
