//! `vrpt points`: the lecture's first pictures, made by the samplers vrpt renders with. N points
//! of each sampler in one 2D dimension of the layout (the pixel position by default), side by
//! side: the stratified sampler's strata drawn, the box `[0,a)×[0,b)` with the fraction of
//! points inside beside its area `ab` (independence), the L2-star discrepancy; under them each
//! set's periodogram over M realisations, its radially averaged power spectrum, and the
//! discrepancy against N with its fitted slope ([`crate::analysis::points`] has the formulas,
//! [`crate::analysis::theory_plots`] draws). `--warp` shows the points where a render puts them
//! (on the hemisphere or a triangle); `--dependent` adds the pair `(x, x + ½ mod 1)` of the
//! first sampler's points, which fails the box test. PNG or SVG by the extension of `-o`;
//! `--json` writes the numbers.

use crate::analysis::fit::log_log_slope;
use crate::analysis::points::{
    dependent_pair, dimension_index, draw_points, fraction_in_box, periodogram, radial_spectrum,
    rms_discrepancy, PointWarp, CURVE_SIZES,
};
use crate::error::{Error, Result};
use crate::render::{independent, jittered, sobol, stratified};
use crate::sampler::SamplerKind;
use glam::{UVec2, Vec2};
use std::path::PathBuf;

/// What to draw (the flags of `vrpt points`).
#[derive(Clone, Debug, clap::Args)]
pub struct PointsRequest {
    /// Samplers, comma-separated: independent, stratified, sobol.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "independent,stratified,sobol"
    )]
    pub sampler: Vec<SamplerKind>,
    /// Points in a set.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub n: u32,
    /// The 2D dimension of the layout: pixel, light-B or direction-B (bounce B from 1).
    #[arg(long, default_value = "pixel", value_parser = parse_dims)]
    pub dims: String,
    /// Realisations (seeds from --seed up) the spectrum and discrepancy are averaged over.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub realisations: u32,
    /// Highest frequency per axis of the periodogram.
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u32).range(1..=128))]
    pub max_frequency: u32,
    /// Seed of the first realisation.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// The box [0,A)×[0,B) whose fraction of points is shown beside its area.
    #[arg(long = "box", value_name = "A,B", default_value = "0.5,0.3", value_parser = parse_box)]
    pub box_size: (f32, f32),
    /// Where the picture shows the points: square, or after a warp: uniform, cosine, phong:E
    /// (hemisphere, equal-area projection) or triangle (by area).
    #[arg(long, default_value = "square", value_parser = clap::value_parser!(PointWarp))]
    pub warp: PointWarp,
    /// Add the dependent pair (x, x + ½ mod 1) of the first sampler's points.
    #[arg(long)]
    pub dependent: bool,
    /// The picture: .png or .svg.
    #[arg(short = 'o', long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// The numbers as JSON.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

fn parse_dims(s: &str) -> std::result::Result<String, String> {
    dimension_index(s).map(|_| s.to_string()).ok_or_else(|| {
        format!("'{s}' is not a 2D dimension: pixel, light-B or direction-B (B from 1)")
    })
}

fn parse_box(s: &str) -> std::result::Result<(f32, f32), String> {
    let bad = || format!("'{s}' is not a box A,B with 0 < A, B ≤ 1");
    let (a, b) = s.split_once(',').ok_or_else(bad)?;
    let (a, b): (f32, f32) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    if a > 0.0 && a <= 1.0 && b > 0.0 && b <= 1.0 {
        Ok((a, b))
    } else {
        Err(bad())
    }
}

/// One sampler's set and what was measured of it.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PointsRow {
    pub sampler: String,
    pub n: u32,
    pub dims: String,
    /// Root mean square over the realisations of the L2-star discrepancy.
    pub l2_star_discrepancy: f64,
    /// `[frequency, power]`, averaged over the realisations.
    pub radial_spectrum: Vec<[f64; 2]>,
    /// `[N, rms discrepancy]` for N = 16 … 2048, and the slope of its log-log fit.
    pub discrepancy_curve: Vec<[f64; 2]>,
    pub discrepancy_slope: f64,
    /// The box `[a, b]` and the mean fraction of points inside it.
    #[serde(rename = "box")]
    pub box_size: [f32; 2],
    pub box_fraction: f64,
    /// The first realisation's points (for the picture; not in the JSON).
    #[serde(skip)]
    pub points: Vec<Vec2>,
    /// The periodogram averaged over the realisations, `(2m+1)²` values (for the picture).
    #[serde(skip)]
    pub periodogram: Vec<f64>,
}

/// Every sampler's row.
#[derive(Clone, Debug)]
pub struct PointsOutcome {
    pub rows: Vec<PointsRow>,
    /// The files written.
    pub written: Vec<PathBuf>,
}

impl PointsOutcome {
    /// A table of the rows for the terminal.
    pub fn table(&self) -> String {
        let w = self
            .rows
            .iter()
            .map(|r| r.sampler.len())
            .max()
            .unwrap_or(7)
            .max(7);
        let mut s = format!(
            "{:<w$} {:>6} {:>12} {:>13} {:>22} {:>15} {:>12}\n",
            "sampler",
            "n",
            "dims",
            "L2* discrep.",
            "box fraction (area)",
            "power |k| ≤ 3",
            "D2* slope"
        );
        for r in &self.rows {
            let low = r.radial_spectrum.iter().take(3).map(|p| p[1]).sum::<f64>() / 3.0;
            s += &format!(
                "{:<w$} {:>6} {:>12} {:>13.3e} {:>13.4} ({:.4}) {:>15.3} {:>12.2}\n",
                r.sampler,
                r.n,
                r.dims,
                r.l2_star_discrepancy,
                r.box_fraction,
                r.box_size[0] * r.box_size[1],
                low,
                r.discrepancy_slope
            );
        }
        s
    }
}

/// The sets of `kind`: `m` realisations of `n` points in layout dimension `dim`.
pub fn realisations(kind: SamplerKind, seed: u64, n: u32, dim: usize, m: u32) -> Vec<Vec<Vec2>> {
    (0..m as u64)
        .map(|r| {
            let s = seed.wrapping_add(r);
            let pixel = UVec2::new(7, 3);
            match kind {
                SamplerKind::Independent => draw_points(&independent, s, n, pixel, dim),
                SamplerKind::Jittered => draw_points(&jittered, s, n, pixel, dim),
                SamplerKind::Stratified => draw_points(&stratified, s, n, pixel, dim),
                SamplerKind::Sobol => draw_points(&sobol, s, n, pixel, dim),
            }
        })
        .collect()
}

/// Draw and measure every sampler's sets; write the picture and the JSON asked for.
pub fn run(req: &PointsRequest) -> Result<PointsOutcome> {
    super::check_picture_and_json(&req.output, &req.json, true)?;
    let dim = dimension_index(&req.dims)
        .ok_or_else(|| Error::Settings(format!("--dims {}: no such 2D dimension", req.dims)))?;
    let (a, b) = req.box_size;
    let measure = |name: String, sets: &dyn Fn(u32) -> Vec<Vec<Vec2>>| -> PointsRow {
        let main = sets(req.n);
        let m = main.len() as f64;
        let p = periodogram(&main, req.max_frequency);
        let spectrum = radial_spectrum(&p, req.max_frequency);
        let curve: Vec<[f64; 2]> = CURVE_SIZES
            .iter()
            .map(|&n| [n as f64, rms_discrepancy(&sets(n))])
            .collect();
        let xs: Vec<f64> = curve.iter().map(|c| c[0]).collect();
        let ys: Vec<f64> = curve.iter().map(|c| c[1].max(1e-300)).collect();
        PointsRow {
            sampler: name,
            n: req.n,
            dims: req.dims.clone(),
            l2_star_discrepancy: rms_discrepancy(&main),
            radial_spectrum: spectrum.iter().map(|&(k, p)| [k, p]).collect(),
            discrepancy_slope: log_log_slope(&xs, &ys),
            discrepancy_curve: curve,
            box_size: [a, b],
            box_fraction: main.iter().map(|s| fraction_in_box(s, a, b)).sum::<f64>() / m,
            points: main[0].clone(),
            periodogram: p,
        }
    };
    let mut rows: Vec<PointsRow> = req
        .sampler
        .iter()
        .map(|&kind| {
            measure(kind.to_string(), &|n| {
                realisations(kind, req.seed, n, dim, req.realisations)
            })
        })
        .collect();
    if req.dependent {
        let kind = req.sampler[0];
        rows.push(measure(format!("dependent pair of {kind}"), &|n| {
            realisations(kind, req.seed, n, dim, req.realisations)
                .iter()
                .map(|s| dependent_pair(s))
                .collect()
        }));
    }
    let mut written = Vec::new();
    if let Some(p) = &req.output {
        crate::analysis::theory_plots::write_points_picture(p, &rows_view(&rows, req))?;
        written.push(p.clone());
    }
    if let Some(p) = &req.json {
        super::write_json(p, &rows)?;
        written.push(p.clone());
    }
    Ok(PointsOutcome { rows, written })
}

/// What the picture needs of each row.
fn rows_view<'a>(
    rows: &'a [PointsRow],
    req: &PointsRequest,
) -> Vec<crate::analysis::theory_plots::Panel<'a>> {
    rows.iter()
        .map(|r| crate::analysis::theory_plots::Panel {
            label: &r.sampler,
            points: &r.points,
            warp: req.warp,
            strata: (r.sampler == "stratified" || r.sampler == "jittered")
                .then(|| crate::sampler::grid_shape(r.n)),
            box_size: (r.box_size[0], r.box_size[1]),
            caption: format!(
                "{}: D2* {:.2e}; box {:.3} vs {:.3}",
                r.sampler,
                r.l2_star_discrepancy,
                r.box_fraction,
                r.box_size[0] * r.box_size[1]
            ),
            spectrum: &r.radial_spectrum,
            periodogram: (&r.periodogram, req.max_frequency),
            curve: (&r.discrepancy_curve, r.discrepancy_slope),
        })
        .collect()
}
