//! Pictures of experiments: a log-log convergence plot (SVG or PNG, by extension) with one line
//! per strategy and its fitted slope in the legend, and a labelled PNG grid of images and their
//! false-colour error maps. Drawn with plotters; text uses the Hack font shipped as bytes by
//! `epaint_default_fonts` (no system fonts needed), registered as "sans-serif".

use crate::analysis::experiments::{Comparison, Convergence};
use crate::analysis::metrics::{false_colour, relative_error_map};
use crate::error::{Error, Result};
use crate::image_io::{tonemap, write_bytes, write_png_rgb8, Format, RgbImage};
use glam::Vec3;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

const FONT: &str = "sans-serif";

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bytes are a valid TTF shipped by the crate; failure would be a build defect.
        let _ = plotters::style::register_font(
            FONT,
            FontStyle::Normal,
            epaint_default_fonts::HACK_REGULAR,
        );
    });
}

fn draw_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Write {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

fn draw_convergence<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    c: &Convergence,
    title: &str,
) -> std::result::Result<(), String> {
    let e = |x: plotters::drawing::DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let xs = c.points.iter().map(|p| p.spp as f64);
    let ys = c.points.iter().map(|p| p.mse).filter(|y| *y > 0.0);
    let (x0, x1) = xs.fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
    let (y0, y1) = ys.fold((f64::MAX, f64::MIN), |(a, b), y| (a.min(y), b.max(y)));
    let (y0, y1) = if y0 <= y1 {
        (y0 / 2.0, y1 * 2.0)
    } else {
        (1e-6, 1.0)
    };
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT, 20))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d((x0 / 1.5..x1 * 1.5).log_scale(), (y0..y1).log_scale())
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("samples per pixel")
        .y_desc("MSE against the reference")
        .label_style((FONT, 14))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .x_label_formatter(&|x| format!("{x:.0}"))
        .draw()
        .map_err(e)?;
    for (i, s) in c.slopes.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        let pts: Vec<(f64, f64)> = c
            .points
            .iter()
            .filter(|p| p.strategy == s.strategy && p.mse > 0.0)
            .map(|p| (p.spp as f64, p.mse))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
            .map_err(e)?
            .label(format!("{} (slope {:.2})", s.strategy, s.mse_slope))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))
            .map_err(e)?;
    }
    chart
        .configure_series_labels()
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerLeft)
        .draw()
        .map_err(e)?;
    root.present().map_err(e)
}

/// Write the log-log plot of MSE against spp to `path` (.svg or .png).
pub fn write_convergence_plot(path: &Path, c: &Convergence, title: &str) -> Result<()> {
    register_font();
    let size = (900u32, 600u32);
    let is_svg = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    if is_svg {
        let mut svg = String::new();
        draw_convergence(
            SVGBackend::with_string(&mut svg, size).into_drawing_area(),
            c,
            title,
        )
        .map_err(|m| draw_err(path, m))?;
        write_bytes(path, svg.as_bytes())
    } else {
        Format::from_path(path)?;
        let mut buf = vec![0u8; (size.0 * size.1 * 3) as usize];
        draw_convergence(
            BitMapBackend::with_buffer(&mut buf, size).into_drawing_area(),
            c,
            title,
        )
        .map_err(|m| draw_err(path, m))?;
        write_png_rgb8(path, size.0, size.1, &buf)
    }
}

/// Write the false-colour map of `image`'s per-pixel relative squared error against
/// `reference` (same size) as a PNG; returns the range of its log colour scale.
pub fn write_error_map(path: &Path, image: &RgbImage, reference: &RgbImage) -> Result<(f64, f64)> {
    let map = relative_error_map(&image.pixels, &reference.pixels);
    let (lo, hi) = error_scale(&[&map]);
    let rgb: Vec<u8> = false_colour(&map, lo, hi).into_iter().flatten().collect();
    write_png_rgb8(path, image.width, image.height, &rgb)?;
    Ok((lo, hi))
}

/// Write a comparison's grid: per strategy its first run's image (tone-mapped with
/// `exposure`) and error map against `reference`.
pub fn write_comparison_grid(
    path: &Path,
    c: &Comparison,
    reference: &RgbImage,
    exposure: f32,
) -> Result<()> {
    let maps: Vec<Vec<f64>> = c
        .images
        .iter()
        .map(|img| relative_error_map(img, &reference.pixels))
        .collect();
    let rows: Vec<GridRow> = c
        .rows
        .iter()
        .zip(&c.images)
        .zip(&maps)
        .map(|((r, img), m)| GridRow {
            label: format!("{}  {:.0} spp  MSE {:.2e}", r.strategy, r.spp, r.mse),
            image: img,
            error: m,
        })
        .collect();
    write_image_grid(
        path,
        reference.width,
        reference.height,
        &rows,
        exposure,
        "rel. error² (log)",
    )
}

/// One row of an image grid: a label, an image and its per-pixel error map.
pub struct GridRow<'a> {
    pub label: String,
    pub image: &'a [Vec3],
    pub error: &'a [f64],
}

/// The range `[lo, hi]` an error-map colour scale spans: the 1st to 99.9th percentile of the
/// positive errors of all rows, so every row shares one scale.
pub fn error_scale(maps: &[&[f64]]) -> (f64, f64) {
    let mut v: Vec<f64> = maps
        .iter()
        .flat_map(|m| m.iter().copied())
        .filter(|x| *x > 0.0 && x.is_finite())
        .collect();
    if v.is_empty() {
        return (1e-6, 1.0);
    }
    v.sort_by(f64::total_cmp);
    let q = |f: f64| v[((v.len() - 1) as f64 * f) as usize];
    let (lo, hi) = (q(0.01), q(0.999));
    (lo, hi.max(lo * 10.0))
}

/// Write a PNG grid: one row per strategy holding its image (tone-mapped with `exposure`) and
/// its error map (log scale shared by all rows), labelled.
pub fn write_image_grid(
    path: &Path,
    width: u32,
    height: u32,
    rows: &[GridRow],
    exposure: f32,
    error_title: &str,
) -> Result<()> {
    register_font();
    let scale = (256 / width.max(height)).max(1);
    let (cw, ch) = (width * scale, height * scale);
    let (pad, label_h, header_h) = (8u32, 22u32, 26u32);
    let gw = pad + 2 * (cw + pad);
    let gh = header_h + rows.len() as u32 * (label_h + ch + pad);
    let mut buf = vec![255u8; (gw * gh * 3) as usize];
    let (lo, hi) = error_scale(&rows.iter().map(|r| r.error).collect::<Vec<_>>());
    let mut blit = |x0: u32, y0: u32, px: &dyn Fn(usize) -> [u8; 3]| {
        for y in 0..ch {
            for x in 0..cw {
                let src = ((y / scale) * width + x / scale) as usize;
                let dst = (((y0 + y) * gw + x0 + x) * 3) as usize;
                buf[dst..dst + 3].copy_from_slice(&px(src));
            }
        }
    };
    for (i, r) in rows.iter().enumerate() {
        let y0 = header_h + i as u32 * (label_h + ch + pad) + label_h;
        let colours = false_colour(r.error, lo, hi);
        blit(pad, y0, &|k| tonemap(r.image[k], exposure));
        blit(2 * pad + cw, y0, &|k| colours[k]);
    }
    {
        let root = BitMapBackend::with_buffer(&mut buf, (gw, gh)).into_drawing_area();
        let style = (FONT, 15).into_font().color(&BLACK);
        let text = |s: &str, x: u32, y: u32| {
            root.draw(&Text::new(
                s.to_string(),
                (x as i32, y as i32),
                style.clone(),
            ))
            .map_err(|e| draw_err(path, e))
        };
        text("image", pad, 6)?;
        text(
            &format!("{error_title} {lo:.0e}..{hi:.0e}"),
            2 * pad + cw,
            6,
        )?;
        for (i, r) in rows.iter().enumerate() {
            text(
                &r.label,
                pad,
                header_h + i as u32 * (label_h + ch + pad) + 3,
            )?;
        }
        root.present().map_err(|e| draw_err(path, e))?;
    }
    write_png_rgb8(path, gw, gh, &buf)
}
