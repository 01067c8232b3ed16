//! Plots of experiments: a log-log convergence plot (SVG or PNG, by extension) with one line
//! per strategy and its fitted slope in the legend, and the calibration plot (an image's own
//! error estimate against the error measured). Drawn with plotters; text uses the Hack font
//! shipped as bytes by `epaint_default_fonts` (no system fonts needed), registered as
//! "sans-serif", through `Glyphs` (which places each glyph at its side bearing). The
//! false-colour maps and the image grid are in [`crate::analysis::maps`].

use crate::analysis::experiments::Convergence;
use crate::error::{Error, Result};
use crate::image_io::{write_bytes, write_png_rgb8, Format};
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

pub(crate) const FONT: &str = "sans-serif";

pub(crate) fn register_font() {
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

/// A bitmap of `size` over `buf` (RGB8), whose text is drawn with each glyph at its own left
/// side bearing ([`Glyphs`]).
pub(crate) fn bitmap(buf: &mut [u8], size: (u32, u32)) -> Glyphs<BitMapBackend<'_>> {
    Glyphs(BitMapBackend::with_buffer(buf, size))
}

/// A plotters backend `B` whose text is rasterized here: plotters' own ab_glyph path places each
/// glyph at the pen position without its left side bearing, so a narrow glyph (`.`, `-`, `1`)
/// is drawn against the glyph before it and leaves a gap after (the plots' tick labels read
/// `0 5`, `20 0`). Everything else goes to `B`; the layout box and the anchor are plotters'.
pub(crate) struct Glyphs<B>(pub(crate) B);

impl<B: plotters_backend::DrawingBackend> plotters_backend::DrawingBackend for Glyphs<B> {
    type ErrorType = B::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.0.get_size()
    }

    fn ensure_prepared(&mut self) -> BackendResult<B::ErrorType> {
        self.0.ensure_prepared()
    }

    fn present(&mut self) -> BackendResult<B::ErrorType> {
        self.0.present()
    }

    fn draw_pixel(
        &mut self,
        point: plotters_backend::BackendCoord,
        color: plotters_backend::BackendColor,
    ) -> BackendResult<B::ErrorType> {
        self.0.draw_pixel(point, color)
    }

    fn draw_line<S: plotters_backend::BackendStyle>(
        &mut self,
        from: plotters_backend::BackendCoord,
        to: plotters_backend::BackendCoord,
        style: &S,
    ) -> BackendResult<B::ErrorType> {
        self.0.draw_line(from, to, style)
    }

    fn draw_rect<S: plotters_backend::BackendStyle>(
        &mut self,
        upper_left: plotters_backend::BackendCoord,
        bottom_right: plotters_backend::BackendCoord,
        style: &S,
        fill: bool,
    ) -> BackendResult<B::ErrorType> {
        self.0.draw_rect(upper_left, bottom_right, style, fill)
    }

    fn draw_path<S: plotters_backend::BackendStyle, I: IntoIterator<Item = (i32, i32)>>(
        &mut self,
        path: I,
        style: &S,
    ) -> BackendResult<B::ErrorType> {
        self.0.draw_path(path, style)
    }

    fn draw_circle<S: plotters_backend::BackendStyle>(
        &mut self,
        center: plotters_backend::BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> BackendResult<B::ErrorType> {
        self.0.draw_circle(center, radius, style, fill)
    }

    fn fill_polygon<S: plotters_backend::BackendStyle, I: IntoIterator<Item = (i32, i32)>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> BackendResult<B::ErrorType> {
        self.0.fill_polygon(vert, style)
    }

    fn blit_bitmap(
        &mut self,
        pos: plotters_backend::BackendCoord,
        (iw, ih): (u32, u32),
        src: &[u8],
    ) -> BackendResult<B::ErrorType> {
        self.0.blit_bitmap(pos, (iw, ih), src)
    }

    /// plotters' default `draw_text` (layout box, anchor, transform), with each glyph's pixels
    /// moved right by its left side bearing (its outline's left edge from the pen position).
    fn draw_text<S: plotters_backend::BackendTextStyle>(
        &mut self,
        text: &str,
        style: &S,
        pos: plotters_backend::BackendCoord,
    ) -> BackendResult<B::ErrorType> {
        use ab_glyph::{Font, FontRef, ScaleFont};
        use plotters_backend::text_anchor::{HPos, VPos};
        use plotters_backend::{BackendColor, DrawingErrorKind};
        let color = style.color();
        if color.alpha == 0.0 {
            return Ok(());
        }
        let ((min_x, min_y), (max_x, max_y)) = style
            .layout_box(text)
            .map_err(|e| DrawingErrorKind::FontError(Box::new(e)))?;
        let (width, height) = (max_x - min_x, max_y - min_y);
        let dx = match style.anchor().h_pos {
            HPos::Left => 0,
            HPos::Right => -width,
            HPos::Center => -width / 2,
        };
        let dy = match style.anchor().v_pos {
            VPos::Top => 0,
            VPos::Center => -height / 2,
            VPos::Bottom => -height,
        };
        let Ok(font) = FontRef::try_from_slice(epaint_default_fonts::HACK_REGULAR) else {
            return Ok(());
        };
        let size = style.size() as f32;
        let font = font.as_scaled(size);
        let trans = style.transform();
        let (w, h) = self.get_size();
        let (mut pen, mut prev) = (0f32, None);
        for c in text.chars() {
            let id = font.glyph_id(c);
            if let Some(p) = prev {
                pen += font.kern(p, id);
            }
            prev = Some(id);
            if let Some(q) = font.outline_glyph(font.scaled_glyph(c)) {
                let rect = q.px_bounds();
                let (x0, y0) = ((pen + rect.min.x) as i32, (size / 2.0 + rect.min.y) as i32);
                let mut pixels = Vec::new();
                q.draw(|x, y, cov| pixels.push((x as i32 + x0, y as i32 + y0, cov)));
                for (x, y, cov) in pixels {
                    let (x, y) = trans.transform(x + dx - min_x, y + dy - min_y);
                    let (x, y) = (pos.0 + x, pos.1 + y);
                    if x >= 0 && x < w as i32 && y >= 0 && y < h as i32 {
                        let c = BackendColor {
                            alpha: color.alpha * cov as f64,
                            rgb: color.rgb,
                        };
                        self.0.draw_pixel((x, y), c)?;
                    }
                }
            }
            pen += font.h_advance(id);
        }
        Ok(())
    }
}

/// What a backend's drawing returns.
type BackendResult<E> = std::result::Result<(), plotters_backend::DrawingErrorKind<E>>;

pub(crate) fn draw_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Write {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

pub(crate) const PALETTE: [RGBColor; 8] = [
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

/// Write the calibration plot of an error estimate as a PNG: estimated against measured MSE
/// on log-log axes with the diagonal and the band of a factor 2 about it; `points` are the
/// replicate estimates (labelled by series, e.g. "door sobol": one colour per label's first
/// word), `per_sample` the per-sample estimates of the same images, in grey.
pub fn write_calibration_plot(
    path: &Path,
    points: &[(f64, f64, String)],
    per_sample: &[(f64, f64)],
) -> Result<()> {
    register_font();
    Format::from_path(path)?;
    let size = (900u32, 700u32);
    let mut buf = vec![0u8; (size.0 * size.1 * 3) as usize];
    draw_calibration(
        bitmap(&mut buf, size).into_drawing_area(),
        points,
        per_sample,
    )
    .map_err(|m| draw_err(path, m))?;
    write_png_rgb8(path, size.0, size.1, &buf)
}

fn draw_calibration<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    points: &[(f64, f64, String)],
    per_sample: &[(f64, f64)],
) -> std::result::Result<(), String> {
    let e = |x: plotters::drawing::DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let (lo, hi) = calibration_range(points, per_sample);
    let mut chart = ChartBuilder::on(&root)
        .caption("error estimate against measured error", (FONT, 20))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d((lo..hi).log_scale(), (lo..hi).log_scale())
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("MSE measured against the reference")
        .y_desc("MSE the image estimates")
        .label_style((FONT, 14))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .x_label_formatter(&|x| format!("{x:.0e}"))
        .draw()
        .map_err(e)?;
    for (k, style) in [
        (1.0, BLACK.stroke_width(2)),
        (2.0, BLACK.mix(0.4).stroke_width(1)),
    ] {
        for l in factor_lines(k, (lo, hi)) {
            chart.draw_series(LineSeries::new(l, style)).map_err(e)?;
        }
    }
    chart
        .draw_series(
            per_sample
                .iter()
                .map(|&(x, y)| Cross::new((x, y), 4, BLACK.mix(0.35))),
        )
        .map_err(e)?
        .label("per-sample estimate s²/n")
        .legend(|(x, y)| Cross::new((x + 10, y), 4, BLACK.mix(0.35)));
    let mut series: Vec<&str> = points
        .iter()
        .map(|p| p.2.split(' ').next().unwrap_or(""))
        .collect();
    series.dedup();
    for (i, name) in series.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        chart
            .draw_series(
                points
                    .iter()
                    .filter(|p| p.2.split(' ').next() == Some(name))
                    .map(|p| Circle::new((p.0, p.1), 4, color.filled())),
            )
            .map_err(e)?
            .label(format!("{name} (4 replicates)"))
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, color.filled()));
    }
    chart
        .configure_series_labels()
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(e)?;
    root.present().map_err(e)
}

/// The calibration plot's range on both axes: the positive finite values of `points` and
/// `per_sample` with a factor 2 of margin each side (`1e-6 .. 1` where there are none).
fn calibration_range(points: &[(f64, f64, String)], per_sample: &[(f64, f64)]) -> (f64, f64) {
    let all = points
        .iter()
        .flat_map(|p| [p.0, p.1])
        .chain(per_sample.iter().flat_map(|p| [p.0, p.1]))
        .filter(|v| *v > 0.0 && v.is_finite());
    let (lo, hi) = all.fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
    if lo < hi {
        (lo / 2.0, hi * 2.0)
    } else {
        (1e-6, 1.0)
    }
}

/// The lines `y = x` (`k` = 1), else `y = k x` and `y = x / k`, across the range `lo..hi`.
fn factor_lines(k: f64, (lo, hi): (f64, f64)) -> Vec<Vec<(f64, f64)>> {
    if k == 1.0 {
        vec![vec![(lo, lo), (hi, hi)]]
    } else {
        vec![
            vec![(lo, lo * k), (hi / k, hi)],
            vec![(lo * k, lo), (hi, hi / k)],
        ]
    }
}

/// The log-log plot of MSE against spp as SVG text (for the HTML report).
pub fn convergence_svg(c: &Convergence, title: &str) -> Result<String> {
    register_font();
    let mut svg = String::new();
    draw_convergence(
        SVGBackend::with_string(&mut svg, (900, 600)).into_drawing_area(),
        c,
        title,
    )
    .map_err(|m| Error::Settings(format!("convergence plot: {m}")))?;
    Ok(svg)
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
        draw_convergence(bitmap(&mut buf, size).into_drawing_area(), c, title)
            .map_err(|m| draw_err(path, m))?;
        write_png_rgb8(path, size.0, size.1, &buf)
    }
}
