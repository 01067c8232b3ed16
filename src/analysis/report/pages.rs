//! The pages of `vrpt compare`, `vrpt converge` and `vrpt diff`: which images, tables and
//! settings each report holds (see the [module above](super)).

use super::*;

/// The columns of a comparison's rows ([`CompareRow`]), as `--json` names them.
fn compare_columns() -> Vec<Column> {
    vec![
        Column::text("strategy", "strategy"),
        Column::number("spp", "spp"),
        Column::number("seconds", "time (s)"),
        Column::number("mse", "MSE"),
        Column::number("rel_mse", "relMSE"),
        Column::number("rmse", "RMSE"),
        Column::number("mae", "MAE"),
        Column::number("variance", "variance"),
        Column::number("est_mse", "estimated MSE"),
        Column::number("est_rel_mse", "estimated relMSE"),
        Column::text("estimate", "estimated from"),
        Column::number("bias_t", "bias t"),
        Column::number("bias_p", "bias p"),
        Column::number("mse_reduction", "MSE reduction"),
        Column::number("efficiency", "efficiency"),
    ]
}

impl ReportImage {
    /// The reference's image, first in every report.
    fn reference(reference: &RgbImage) -> ReportImage {
        ReportImage {
            name: "reference".into(),
            group: String::new(),
            reference: true,
            rgb: reference.pixels.clone(),
            variance: reference.variance.clone(),
        }
    }
}

impl Report {
    /// The report of `vrpt compare`: the summary (ranked by efficiency for `equal_time` runs,
    /// else by MSE), the reference and each strategy's first run, the metrics (whole image,
    /// then one table per region), and `settings`.
    pub fn for_comparison(
        c: &Comparison,
        reference: &RgbImage,
        region_names: &[String],
        (title, equal_time): (&str, bool),
        settings: Vec<(String, String)>,
    ) -> Result<Report> {
        let mut images = vec![ReportImage::reference(reference)];
        for ((row, img), var) in c.rows.iter().zip(&c.images).zip(&c.variances) {
            images.push(ReportImage {
                name: row.strategy.clone(),
                group: String::new(),
                reference: false,
                rgb: img.clone(),
                variance: Some(var.clone()),
            });
        }
        let mut tables = vec![Table::of(
            &format!(
                "whole image (MSE reduction and efficiency against {})",
                c.baseline
            ),
            compare_columns(),
            &c.rows,
            "strategy",
        )?];
        for name in region_names {
            let rows: Vec<&RegionRow> = c.regions.iter().filter(|r| &r.region == name).collect();
            tables.push(Table::of(
                &format!("region {name}"),
                vec![
                    Column::text("strategy", "strategy"),
                    Column::number("mse", "MSE"),
                    Column::number("rel_mse", "relMSE"),
                    Column::number("rmse", "RMSE"),
                    Column::number("mae", "MAE"),
                    Column::number("mse_reduction", "MSE reduction"),
                ],
                &rows,
                "strategy",
            )?);
        }
        Ok(Report {
            kind: "compare".into(),
            title: title.into(),
            settings,
            width: reference.width,
            height: reference.height,
            images,
            tables,
            plot_svg: None,
            summary: Some(Summary::of(c, equal_time)),
            spp_maps: c
                .rows
                .iter()
                .zip(&c.spp_maps)
                .filter_map(|(row, m)| Some((row, m.as_ref()?)))
                .map(|(row, m)| SppMap::new(&row.strategy, m, (reference.width, reference.height)))
                .collect::<Result<_>>()?,
        })
    }

    /// The report of `vrpt converge`: the reference, each strategy's first run at each spp (one
    /// group per spp), the MSE and relMSE by spp, the fitted slopes and the plot.
    pub fn for_convergence(
        c: &Convergence,
        reference: &RgbImage,
        title: &str,
        settings: Vec<(String, String)>,
        plot_svg: String,
    ) -> Result<Report> {
        let mut images = vec![ReportImage::reference(reference)];
        let mut spps: Vec<u32> = c.points.iter().map(|p| p.spp).collect();
        spps.sort_unstable();
        spps.dedup();
        images.extend(images_by_spp(c, &spps));
        let tables = vec![
            Table::of(
                "fitted log-log slopes (theory: −1 for independent samples)",
                vec![
                    Column::text("strategy", "strategy"),
                    Column::number("mse_slope", "MSE slope"),
                    Column::number("rel_mse_slope", "relMSE slope"),
                ],
                &c.slopes,
                "strategy",
            )?,
            by_spp(c, &spps, "mse", "MSE"),
            by_spp(c, &spps, "est_mse", "estimated MSE"),
            by_spp(c, &spps, "rel_mse", "relMSE"),
        ];
        Ok(Report {
            kind: "converge".into(),
            title: title.into(),
            settings,
            width: reference.width,
            height: reference.height,
            images,
            tables,
            plot_svg: Some(plot_svg),
            summary: None,
            spp_maps: c
                .points
                .iter()
                .zip(&c.spp_maps)
                .filter_map(|(p, m)| Some((p, m.as_ref()?)))
                .map(|(p, m)| {
                    let name = format!("{}, {} spp", p.strategy, p.spp);
                    SppMap::new(&name, m, (reference.width, reference.height))
                })
                .collect::<Result<_>>()?,
        })
    }

    /// The report of `vrpt diff`: the image and the reference, and `rows` of metrics (the
    /// whole image, then each region) keyed by "region".
    pub fn for_diff(
        image_name: &str,
        image: &RgbImage,
        reference: &RgbImage,
        rows: Table,
        title: &str,
        settings: Vec<(String, String)>,
    ) -> Report {
        Report {
            kind: "diff".into(),
            title: title.into(),
            settings,
            width: reference.width,
            height: reference.height,
            images: vec![
                ReportImage::reference(reference),
                ReportImage {
                    name: image_name.into(),
                    group: String::new(),
                    reference: false,
                    rgb: image.pixels.clone(),
                    variance: image.variance.clone(),
                },
            ],
            tables: vec![rows],
            plot_svg: None,
            summary: None,
            spp_maps: Vec::new(),
        }
    }
}

/// Each point's first run of a sweep, one group per spp of `spps` (ascending), the strategies
/// in the run's order within each.
fn images_by_spp(c: &Convergence, spps: &[u32]) -> Vec<ReportImage> {
    let mut images = Vec::new();
    for &spp in spps {
        for (p, (img, var)) in c.points.iter().zip(&c.images) {
            if p.spp == spp {
                images.push(ReportImage {
                    name: p.strategy.clone(),
                    group: format!("{spp} spp"),
                    reference: false,
                    rgb: img.clone(),
                    variance: Some(var.clone()),
                });
            }
        }
    }
    images
}

/// A table of one metric of a sweep (`key`: `mse`, `est_mse` or `rel_mse`; called `label`):
/// a row per strategy, a column per spp of `spps`.
fn by_spp(c: &Convergence, spps: &[u32], key: &str, label: &str) -> Table {
    let mut columns = vec![Column::text("strategy", "strategy")];
    columns.extend(
        spps.iter()
            .map(|n| Column::number(&format!("{key}_{n}"), &format!("{label} {n} spp"))),
    );
    let rows: Vec<serde_json::Map<String, serde_json::Value>> = c
        .slopes
        .iter()
        .map(|s| {
            let mut m = serde_json::Map::new();
            m.insert("strategy".into(), s.strategy.clone().into());
            for p in c.points.iter().filter(|p| p.strategy == s.strategy) {
                let v = match key {
                    "mse" => p.mse,
                    "est_mse" => p.est_mse,
                    _ => p.rel_mse,
                };
                m.insert(format!("{key}_{}", p.spp), number(v));
            }
            m
        })
        .collect();
    Table {
        title: format!("{label} by spp (mean over runs)"),
        columns,
        rows,
        row_key: "strategy".into(),
    }
}
