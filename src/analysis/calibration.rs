//! Is an image's own error estimate honest? Render a scene with a sampler and seed, and set the
//! error the image estimates for itself ([`crate::estimate`]: from replicates, and per sample
//! `s²/n`) beside the error measured against a converged reference.
//!
//! The measured MSE is `mean((x − r)²)` less the reference's own variance of the mean (its
//! `variance` channels: honest when the reference was rendered with independent samples, which
//! [`reference_settings`] does), since `E[(x − r)²] = Var x + Var r` for independent images. The
//! relMSE is measured as [`crate::analysis::metrics`] does, with the reference's pixels.
//!
//! What replicates cost: [`one_set`] measures the same renders as one set of all the samples
//! (`replicates = 1`), so `measured_mse` of a case over its one-set MSE is the price of R
//! randomizations of N/R samples against one of N (1 for independent samples; more where
//! stratification or Sobol points converge faster than 1/N).

use crate::analysis::metrics::{mean_variance, metrics};
use crate::error::Result;
use crate::estimate::image_error;
use crate::image_io::RgbImage;
use crate::render::{render_passes, NoProgress, PassPlan, RenderSettings};
use crate::sampler::SamplerKind;
use crate::scene::Scene;

/// One render's estimated and measured error.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// The sampler of the render.
    pub sampler: SamplerKind,
    /// Its seed.
    pub seed: u64,
    /// MSE measured against the reference, less the reference's variance.
    pub measured_mse: f64,
    /// relMSE measured against the reference.
    pub measured_rel_mse: f64,
    /// The image's estimated MSE, from its replicates.
    pub estimated_mse: f64,
    /// The image's estimated relMSE, from its replicates.
    pub estimated_rel_mse: f64,
    /// The per-sample estimate `s²/n` of the image's MSE.
    pub per_sample_mse: f64,
    /// The per-sample estimate of its relMSE.
    pub per_sample_rel_mse: f64,
}

impl Case {
    /// Estimated over measured MSE.
    pub fn mse_ratio(&self) -> f64 {
        self.estimated_mse / self.measured_mse
    }
    /// Per-sample estimate over measured MSE.
    pub fn per_sample_ratio(&self) -> f64 {
        self.per_sample_mse / self.measured_mse
    }
}

/// The settings of a reference for [`calibrate`]: `settings` at `spp` with independent samples
/// and one replicate, so that its per-sample variance is the honest variance of its mean.
pub fn reference_settings(settings: &RenderSettings, spp: u32, seed: u64) -> RenderSettings {
    let mut s = settings.clone();
    s.strategy.sampler = SamplerKind::Independent;
    s.replicates = 1;
    s.spp = spp;
    s.seed = seed;
    s
}

/// Render `scene` with `settings` for every sampler and seed, and measure each image's error
/// against `reference` (same size) beside the image's own estimates.
pub fn calibrate(
    scene: &Scene,
    settings: &RenderSettings,
    reference: &RgbImage,
    samplers: &[SamplerKind],
    seeds: &[u64],
) -> Result<Vec<Case>> {
    let floor = reference.variance.as_deref().map_or(0.0, mean_variance);
    let mut cases = Vec::new();
    for &sampler in samplers {
        for &seed in seeds {
            let mut s = settings.clone();
            s.strategy.sampler = sampler;
            s.seed = seed;
            let r = render_passes(scene, &s, &PassPlan::default(), &NoProgress)?;
            let image = r.film.mean_image();
            let m = metrics(&image, &reference.pixels);
            let (per_sample_mse, per_sample_rel_mse) =
                image_error(s.width, &image, &r.film.variance_image());
            cases.push(Case {
                sampler,
                seed,
                measured_mse: (m.mse - floor).max(f64::MIN_POSITIVE),
                measured_rel_mse: m.rel_mse,
                estimated_mse: r.estimate.mse,
                estimated_rel_mse: r.estimate.rel_mse,
                per_sample_mse,
                per_sample_rel_mse,
            });
        }
    }
    Ok(cases)
}

/// The MSE measured against `reference` (less its variance) of the renders [`calibrate`] makes,
/// each as one set of all its samples (`replicates = 1`), in [`calibrate`]'s order (sampler
/// major, then seed).
pub fn one_set(
    scene: &Scene,
    settings: &RenderSettings,
    reference: &RgbImage,
    samplers: &[SamplerKind],
    seeds: &[u64],
) -> Result<Vec<f64>> {
    let floor = reference.variance.as_deref().map_or(0.0, mean_variance);
    let mut out = Vec::new();
    for &sampler in samplers {
        for &seed in seeds {
            let mut s = settings.clone();
            s.strategy.sampler = sampler;
            s.seed = seed;
            s.replicates = 1;
            let r = render_passes(scene, &s, &PassPlan::default(), &NoProgress)?;
            let m = metrics(&r.film.mean_image(), &reference.pixels);
            out.push((m.mse - floor).max(f64::MIN_POSITIVE));
        }
    }
    Ok(out)
}
