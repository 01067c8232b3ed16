//! `vrpt diff`: an image against a reference: MSE, relMSE, RMSE, MAE, the mean signed error, the
//! largest relative difference, where the image records it the variance of its mean and the
//! bias z-scores, the same per region, and optionally a false-colour error map and a report;
//! with `--pair-denominator`, the relMSE of one of two independent renders estimated from the
//! pair ([`pair_rel_mse`]).

use super::{RegionArgs, Written};
use crate::analysis::maps::write_error_map;
use crate::analysis::metrics::{
    image_bias, mean_relative_variance, mean_variance, metrics, pair_rel_mse, region_metrics,
    ImageBias, Metrics,
};
use crate::analysis::report::{number, Column, Report, Table};
use crate::error::{Error, Result};
use crate::image_io::{check_image_path, check_writable, file_key, read_exr, RgbImage};
use crate::output::{EstimateMethod, RenderMetadata};
use glam::Vec3;
use std::path::{Path, PathBuf};

/// What to compare, and what to write: `vrpt diff`'s flags.
#[derive(Clone, Debug, Default, clap::Args)]
pub struct DiffRequest {
    /// The image to judge (EXR).
    pub image: PathBuf,
    /// The reference (EXR).
    pub reference: PathBuf,
    /// Write a false-colour map of the per-pixel relative squared error to this PNG.
    #[arg(long, value_name = "PNG")]
    pub error_map: Option<PathBuf>,
    /// Write a self-contained HTML report: both images (HDR), error views, metrics.
    #[arg(long, value_name = "HTML")]
    pub report: Option<PathBuf>,
    /// IMAGE and REFERENCE are two independent renders of one estimator: also print the relMSE of
    /// one of them, mean (a−b)²/(2(c²+0.01)), with c this image (a third render, independent of
    /// both; give every estimator compared the same one). The other metrics still take
    /// REFERENCE as the reference.
    #[arg(long, value_name = "EXR")]
    pub pair_denominator: Option<PathBuf>,
    #[command(flatten)]
    pub regions: RegionArgs,
}

/// The metrics of a diff, and the files written.
#[derive(Clone, Debug)]
pub struct DiffOutcome {
    pub metrics: Metrics,
    /// With `--pair-denominator`: the relMSE of one render of the pair ([`pair_rel_mse`]).
    pub pair_rel_mse: Option<f64>,
    /// The largest `|a − b| / max(|a|, |b|)` over pixels and channels.
    pub max_relative_difference: f32,
    /// The image's mean variance of the mean, when it records one.
    pub variance: Option<f64>,
    /// The bias z-scores, when the image records its variance.
    pub bias: Option<ImageBias>,
    /// Each region's metrics.
    pub regions: Vec<(String, Metrics)>,
    /// The image's own estimate of its error (its `estimated_variance` channels), to set
    /// beside the measured one: (how it was made, estimated MSE, estimated relMSE).
    pub estimate: Option<(String, f64, f64)>,
    /// The reference's mean variance of the mean (per sample): the floor under the MSE.
    pub reference_variance: Option<f64>,
    /// The reference's mean `v/(r² + 0.01)`: the floor under the relMSE.
    pub reference_rel_variance: Option<f64>,
    pub written: Vec<Written>,
}

/// The largest `|a − b| / max(|a|, |b|)` over pixels and channels (0 where both are 0): how
/// far two images are from equal, e.g. a merge of shards and the render of all their samples
/// (which agree to f32 rounding, a few 1e-7).
pub fn max_relative_difference(a: &[Vec3], b: &[Vec3]) -> f32 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| (0..3).map(move |c| (x[c], y[c])))
        .map(|(x, y)| {
            let m = x.abs().max(y.abs());
            if m > 0.0 {
                (x - y).abs() / m
            } else {
                0.0
            }
        })
        .fold(0.0, f32::max)
}

/// Read both images, compute the metrics, write what was asked for.
pub fn run(req: &DiffRequest) -> Result<DiffOutcome> {
    let outputs = super::given(&[("--error-map", &req.error_map), ("--report", &req.report)]);
    let mut inputs = vec![
        ("IMAGE", req.image.as_path()),
        ("REFERENCE", req.reference.as_path()),
    ];
    inputs.extend(req.regions.regions.as_deref().map(|p| ("--regions", p)));
    inputs.extend(
        req.pair_denominator
            .as_deref()
            .map(|p| ("--pair-denominator", p)),
    );
    crate::image_io::check_outputs(&outputs, &inputs)?;
    let a = read_exr(&req.image)?;
    let r = read_exr(&req.reference)?;
    RenderMetadata::radiance(&a, &req.image)?;
    RenderMetadata::radiance(&r, &req.reference)?;
    same_size((&a, &req.image), (&r, &req.reference))?;
    if let Some(p) = &req.error_map {
        check_image_path(p)?;
    }
    if let Some(p) = &req.report {
        check_writable(p)?;
    }
    let regions = req.regions.resolve(a.width, a.height)?;
    let pair = pair_rel_mse_of(req, &a, &r)?;
    let mut out = DiffOutcome {
        metrics: metrics(&a.pixels, &r.pixels),
        pair_rel_mse: pair,
        max_relative_difference: max_relative_difference(&a.pixels, &r.pixels),
        variance: a.variance.as_deref().map(mean_variance),
        bias: a
            .variance
            .as_deref()
            .map(|v| image_bias(&a.pixels, v, &r.pixels, r.variance.as_deref())),
        regions: regions
            .iter()
            .map(|reg| {
                let m = region_metrics(&a.pixels, &r.pixels, a.width, reg);
                (reg.name.clone(), m)
            })
            .collect(),
        estimate: a.estimated_variance.as_deref().map(|v| {
            let (mse, rel) = crate::estimate::image_error(a.width, &a.pixels, v);
            let how = RenderMetadata::radiance(&a, &req.image)
                .ok()
                .flatten()
                .and_then(|m| m.estimate)
                .map_or("replicates".into(), |e| match e.method {
                    EstimateMethod::Replicates => format!("{} replicates", e.replicates),
                    m => m.name().to_string(),
                });
            (how, mse, rel)
        }),
        reference_variance: r.variance.as_deref().map(mean_variance),
        reference_rel_variance: r
            .variance
            .as_deref()
            .map(|v| mean_relative_variance(v, &r.pixels)),
        written: Vec::new(),
    };
    if let Some(p) = &req.report {
        report(req, &a, &r, &out).write(p)?;
        out.written.push(Written::new(p));
    }
    if let Some(p) = &req.error_map {
        let (lo, hi) = write_error_map(p, &a, &r)?;
        out.written.push(Written {
            path: p.clone(),
            note: format!("relative squared error, log scale {lo:.1e}..{hi:.1e}"),
        });
    }
    Ok(out)
}

/// An error naming both files unless the images `x` (read from `xp`) and `y` have one size.
fn same_size((x, xp): (&RgbImage, &Path), (y, yp): (&RgbImage, &Path)) -> Result<()> {
    if (x.width, x.height) == (y.width, y.height) {
        return Ok(());
    }
    Err(Error::Settings(format!(
        "{} is {}×{} but {} is {}×{}",
        xp.display(),
        x.width,
        x.height,
        yp.display(),
        y.width,
        y.height
    )))
}

/// With `--pair-denominator`: the relMSE of one of the renders `a` and `r` ([`pair_rel_mse`]),
/// the denominator's image read and checked (a third file, of their size).
fn pair_rel_mse_of(req: &DiffRequest, a: &RgbImage, r: &RgbImage) -> Result<Option<f64>> {
    let Some(p) = &req.pair_denominator else {
        return Ok(None);
    };
    let key = file_key(p);
    for (name, other) in [("IMAGE", &req.image), ("REFERENCE", &req.reference)] {
        if file_key(other) == key {
            return Err(Error::Settings(format!(
                "--pair-denominator {} is {name}: the relMSE's r must come from a third \
                 render, independent of both",
                p.display()
            )));
        }
    }
    let c = read_exr(p)?;
    RenderMetadata::radiance(&c, p)?;
    same_size((&c, p), (a, &req.image))?;
    Ok(Some(pair_rel_mse(&a.pixels, &r.pixels, &c.pixels)))
}

impl DiffOutcome {
    /// The metrics as `vrpt diff` prints them.
    pub fn table(&self) -> String {
        let m = &self.metrics;
        let mut t = format!("MSE                {:.6e}\n", m.mse);
        t += &format!("relMSE (eps 0.01)  {:.6e}\n", m.rel_mse);
        t += &format!("RMSE               {:.6e}\n", m.rmse);
        t += &format!("MAE                {:.6e}\n", m.mae);
        t += &format!("mean signed error  {:+.6e}\n", m.mean_signed_error);
        if let Some(p) = self.pair_rel_mse {
            t += &format!(
                "relMSE of one (pair) {p:.6e} (the two as independent renders of one estimator: \
                 mean (a−b)²/(2(c²+0.01)), c the --pair-denominator image)\n"
            );
        }
        t += &format!(
            "max relative difference {:.3e}\n",
            self.max_relative_difference
        );
        if let Some(v) = self.variance {
            t += &format!("variance of mean   {v:.6e}\n");
        }
        if let Some((how, mse, rel)) = &self.estimate {
            t += &format!(
                "estimated MSE      {mse:.6e} (the image's own estimate, {how}; measured/estimated {:.3})\n",
                m.mse / mse
            );
            t += &format!(
                "estimated relMSE   {rel:.6e} (measured/estimated {:.3})\n",
                m.rel_mse / rel
            );
        }
        if let Some(v) = self.reference_variance {
            t += &format!("reference variance {v:.6e} (of its mean: the floor under the MSE)\n");
        }
        if let Some(v) = self.reference_rel_variance {
            t += &format!(
                "reference relative variance {v:.6e} (its mean v/(r²+0.01): the floor under the relMSE)\n"
            );
        }
        if let Some(b) = &self.bias {
            if let Some(z) = b.z {
                t += &format!("bias z (image)     {z:+.3}\n");
            }
            t += &format!("max |z| (pixel)    {:.3}\n", b.max_pixel_z);
        }
        if !self.regions.is_empty() {
            t += &format!(
                "{:<22} {:>12} {:>12} {:>12} {:>12}\n",
                "region", "MSE", "relMSE", "RMSE", "MAE"
            );
            for (name, m) in &self.regions {
                t += &format!(
                    "{:<22} {:>12.4e} {:>12.4e} {:>12.4e} {:>12.4e}\n",
                    name, m.mse, m.rel_mse, m.rmse, m.mae
                );
            }
        }
        t
    }
}

/// The report of a diff: both images, one table of the whole image and each region, and how
/// the images were made.
fn report(req: &DiffRequest, a: &RgbImage, r: &RgbImage, out: &DiffOutcome) -> Report {
    let row = |name: &str, m: &Metrics| {
        let mut o = serde_json::Map::new();
        o.insert("region".into(), name.into());
        o.insert("mse".into(), number(m.mse));
        o.insert("rel_mse".into(), number(m.rel_mse));
        o.insert("rmse".into(), number(m.rmse));
        o.insert("mae".into(), number(m.mae));
        o.insert("mean_signed_error".into(), number(m.mean_signed_error));
        o
    };
    let mut rows = vec![row("whole image", &out.metrics)];
    rows.extend(out.regions.iter().map(|(n, m)| row(n, m)));
    let table = Table {
        title: "error against the reference".into(),
        columns: vec![
            Column::text("region", "region"),
            Column::number("mse", "MSE"),
            Column::number("rel_mse", "relMSE"),
            Column::number("rmse", "RMSE"),
            Column::number("mae", "MAE"),
            Column::number("mean_signed_error", "mean signed error"),
        ],
        rows,
        row_key: "region".into(),
    };
    let settings = vec![
        ("image".into(), describe(a, &req.image)),
        ("reference".into(), describe(r, &req.reference)),
        ("size".into(), format!("{}x{}", a.width, a.height)),
        ("vrpt".into(), env!("CARGO_PKG_VERSION").into()),
    ];
    let name = req
        .image
        .file_name()
        .map_or("image".into(), |n| n.to_string_lossy().into_owned());
    let title = format!(
        "vrpt diff: {} against {}",
        req.image.display(),
        req.reference.display()
    );
    Report::for_diff(&name, a, r, table, &title, settings)
}

/// How an image was made, in one line: its file, spp, strategy, seed and scene hash.
fn describe(img: &RgbImage, path: &Path) -> String {
    RenderMetadata::radiance(img, path)
        .ok()
        .flatten()
        .map_or_else(
            || format!("{} (no vrpt metadata)", path.display()),
            |m| {
                format!(
                    "{} ({} spp, {}, seed {}, scene hash {})",
                    path.display(),
                    m.spp,
                    m.strategy,
                    m.seed.map_or("merged".into(), |s| s.to_string()),
                    m.scene_hash_hex()
                )
            },
        )
}
