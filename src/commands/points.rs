//! `vrpt points`: the lecture's first pictures, made by the samplers vrpt renders with. N points
//! of each sampler in one 2D dimension of the layout (the pixel position by default), side by
//! side: the stratified sampler's strata drawn, the box `[0,a)×[0,b)` with the fraction of
//! points inside beside its area `ab` (independence), the L2-star discrepancy, and below them
//! the radially averaged power spectrum over M realisations ([`crate::analysis::points`] has
//! the formulas). PNG or SVG by the extension of `-o`; `--json` writes the numbers.

use crate::analysis::points::{
    dimension_index, draw_points, fraction_in_box, l2_star_discrepancy, periodogram,
    radial_spectrum,
};
use crate::error::{Error, Result};
use crate::image_io::{check_outputs, check_writable, Format};
use crate::render::{independent, sobol, stratified};
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
    /// The box `[a, b]` and the mean fraction of points inside it.
    #[serde(rename = "box")]
    pub box_size: [f32; 2],
    pub box_fraction: f64,
    /// The first realisation's points (for the picture; not in the JSON).
    #[serde(skip)]
    pub points: Vec<Vec2>,
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
        let mut s = format!(
            "{:<12} {:>6} {:>12} {:>14} {:>22}\n",
            "sampler", "n", "dims", "L2* discrep.", "box fraction (area)"
        );
        for r in &self.rows {
            let low = r.radial_spectrum.iter().take(3).map(|p| p[1]).sum::<f64>() / 3.0;
            s += &format!(
                "{:<12} {:>6} {:>12} {:>14.3e} {:>13.4} ({:.4})   power at |k| ≤ 3: {low:.3}\n",
                r.sampler,
                r.n,
                r.dims,
                r.l2_star_discrepancy,
                r.box_fraction,
                r.box_size[0] * r.box_size[1]
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
                SamplerKind::Stratified => draw_points(&stratified, s, n, pixel, dim),
                SamplerKind::Sobol => draw_points(&sobol, s, n, pixel, dim),
            }
        })
        .collect()
}

/// Draw and measure every sampler's sets; write the picture and the JSON asked for.
pub fn run(req: &PointsRequest) -> Result<PointsOutcome> {
    check_outputs(
        &super::given(&[("-o", &req.output), ("--json", &req.json)]),
        &[],
    )?;
    if let Some(p) = &req.output {
        let svg = p.extension().is_some_and(|e| e.eq_ignore_ascii_case("svg"));
        if !svg {
            Format::from_path(p)?;
        }
        check_writable(p)?;
    }
    if let Some(p) = &req.json {
        check_writable(p)?;
    }
    let dim = dimension_index(&req.dims)
        .ok_or_else(|| Error::Settings(format!("--dims {}: no such 2D dimension", req.dims)))?;
    let (a, b) = req.box_size;
    let rows: Vec<PointsRow> = req
        .sampler
        .iter()
        .map(|&kind| {
            let sets = realisations(kind, req.seed, req.n, dim, req.realisations);
            let m = sets.len() as f64;
            let d2 = sets
                .iter()
                .map(|s| l2_star_discrepancy(s).powi(2))
                .sum::<f64>()
                / m;
            let spectrum =
                radial_spectrum(&periodogram(&sets, req.max_frequency), req.max_frequency);
            PointsRow {
                sampler: kind.to_string(),
                n: req.n,
                dims: req.dims.clone(),
                l2_star_discrepancy: d2.sqrt(),
                radial_spectrum: spectrum.iter().map(|&(k, p)| [k, p]).collect(),
                box_size: [a, b],
                box_fraction: sets.iter().map(|s| fraction_in_box(s, a, b)).sum::<f64>() / m,
                points: sets[0].clone(),
            }
        })
        .collect();
    let mut written = Vec::new();
    if let Some(p) = &req.output {
        crate::analysis::points::write_picture(p, &rows_view(&rows))?;
        written.push(p.clone());
    }
    if let Some(p) = &req.json {
        super::write_json(p, &rows)?;
        written.push(p.clone());
    }
    Ok(PointsOutcome { rows, written })
}

/// What the picture needs of each row.
fn rows_view(rows: &[PointsRow]) -> Vec<crate::analysis::points::Panel<'_>> {
    rows.iter()
        .map(|r| crate::analysis::points::Panel {
            label: &r.sampler,
            points: &r.points,
            strata: (r.sampler == "stratified").then(|| crate::sampler::grid_shape(r.n)),
            box_size: (r.box_size[0], r.box_size[1]),
            caption: format!(
                "{}: D2* {:.2e}; box {:.3} vs {:.3}",
                r.sampler,
                r.l2_star_discrepancy,
                r.box_fraction,
                r.box_size[0] * r.box_size[1]
            ),
            spectrum: &r.radial_spectrum,
        })
        .collect()
}
