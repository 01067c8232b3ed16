//! Pictures of experiments: a log-log convergence plot (SVG or PNG, by extension) with one line
//! per strategy and its fitted slope in the legend; a labelled PNG grid of images, the reference
//! in the first column, over their false-colour error maps; error maps with their colour bar and
//! its numeric range. Drawn with plotters; text uses the Hack font shipped as bytes by
//! `epaint_default_fonts` (no system fonts needed), registered as "sans-serif".

use crate::analysis::experiments::{Comparison, Convergence};
use crate::analysis::metrics::{colormap, false_colour, relative_error_map};
use crate::error::{Error, Result};
use crate::image_io::{tonemap, write_bytes, write_png_rgb8, Format, RgbImage};
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

/// Write the false-colour map of `image`'s per-pixel relative squared error against
/// `reference` (same size) as a PNG, with its colour bar and the bar's numeric range below it;
/// returns the range of the log colour scale.
pub fn write_error_map(path: &Path, image: &RgbImage, reference: &RgbImage) -> Result<(f64, f64)> {
    let map = relative_error_map(&image.pixels, &reference.pixels);
    let (lo, hi) = error_scale(&[&map]);
    let colours = false_colour(&map, lo, hi);
    let (w, h) = (image.width, image.height);
    let scale = (256 / w.max(h)).max(1);
    let mut c = Canvas::new((w * scale).max(420), h * scale + BAR_H);
    c.blit(0, 0, w, h, scale, &|k| colours[k]);
    c.colour_bar(0, h * scale, lo, hi, ERROR_TITLE)?;
    c.write(path)?;
    Ok((lo, hi))
}

/// Write the samples of each pixel (`w × h`, row-major) as a false-colour PNG on a log scale,
/// with its colour bar and range; returns the range. What an adaptive render spent where.
pub fn write_spp_map(path: &Path, samples: &[u32], (w, h): (u32, u32)) -> Result<(f64, f64)> {
    let (c, range) = spp_map(samples, (w, h))?;
    c.write(path)?;
    Ok(range)
}

/// [`write_spp_map`]'s picture as PNG bytes (for the HTML report).
pub fn spp_map_png(samples: &[u32], (w, h): (u32, u32)) -> Result<Vec<u8>> {
    let (c, _) = spp_map(samples, (w, h))?;
    let mut out = std::io::Cursor::new(Vec::new());
    image::write_buffer_with_format(
        &mut out,
        &c.buf,
        c.w,
        c.h,
        image::ExtendedColorType::Rgb8,
        image::ImageFormat::Png,
    )
    .map_err(|e| Error::Settings(format!("spp map: {e}")))?;
    Ok(out.into_inner())
}

fn spp_map(samples: &[u32], (w, h): (u32, u32)) -> Result<(Canvas, (f64, f64))> {
    let map: Vec<f64> = samples.iter().map(|&n| n as f64).collect();
    let lo = map.iter().copied().fold(f64::INFINITY, f64::min).max(1.0);
    let hi = map.iter().copied().fold(0.0, f64::max).max(lo * 10.0);
    let c = value_map(&map, (w, h), (lo, hi), "samples per pixel, log scale")?;
    Ok((c, (lo, hi)))
}

/// A `w × h` map of positive values (row-major) in false colour on the log scale `lo..hi`,
/// over its colour bar titled `title`.
fn value_map(map: &[f64], (w, h): (u32, u32), (lo, hi): (f64, f64), title: &str) -> Result<Canvas> {
    let colours = false_colour(map, lo, hi);
    let scale = (256 / w.max(h)).max(1);
    let mut c = Canvas::new((w * scale).max(420), h * scale + BAR_H);
    c.blit(0, 0, w, h, scale, &|k| colours[k]);
    c.colour_bar(0, h * scale, lo, hi, title)?;
    Ok(c)
}

/// Write `--roulette ears`'s learned factor at each pixel's first vertex (row-major; 0 where
/// there is none, drawn as the scale's bottom) as a false-colour PNG on the log scale of the
/// factor's whole range, 0.05 to 20, so maps of different scenes compare.
pub fn write_ears_map(path: &Path, map: &[f32], (w, h): (u32, u32)) -> Result<()> {
    let (lo, hi) = crate::integrator::rrs::FACTOR_RANGE;
    let map: Vec<f64> = map.iter().map(|&n| n as f64).collect();
    let title = "EARS factor at the first vertex, log scale";
    value_map(&map, (w, h), (lo as f64, hi as f64), title)?.write(path)
}

/// Write two directional densities side by side as one false-colour PNG (log scale, shared):
/// `left` and `right` are `w × h` maps (row-major, row 0 at the top), each labelled, over one
/// colour bar titled `title`. Each map is drawn at 2× when it is small. Returns the scale.
pub fn write_density_pair(
    path: &Path,
    (left, right): (&[f64], &[f64]),
    (w, h): (u32, u32),
    (left_label, right_label): (&str, &str),
    title: &str,
) -> Result<(f64, f64)> {
    let max = left
        .iter()
        .chain(right)
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max)
        .max(1e-30);
    // four decades below the largest value
    let (lo, hi) = (max * 1e-4, max);
    let (a, b) = (false_colour(left, lo, hi), false_colour(right, lo, hi));
    let scale = (256 / w.max(h)).clamp(1, 2);
    let gap = 16;
    let label_h = 22;
    let mut c = Canvas::new(2 * w * scale + gap, h * scale + label_h + BAR_H);
    c.blit(0, label_h, w, h, scale, &|k| a[k]);
    c.blit(w * scale + gap, label_h, w, h, scale, &|k| b[k]);
    c.text(&[
        (left_label.to_string(), 4, 4),
        (right_label.to_string(), w * scale + gap + 4, 4),
    ])?;
    c.colour_bar(0, h * scale + label_h, lo, hi, title)?;
    c.write(path)?;
    Ok((lo, hi))
}

/// Write rows of two maps each (left and right, `w × h`, row-major, row 0 drawn at the top),
/// each row on its own log scale (four decades below its largest value) and labelled, as one
/// PNG: a warp's histogram beside its integrated pdf, for `vrpt warptest`.
pub fn write_density_rows(
    path: &Path,
    rows: &[(String, &[f64], &[f64])],
    (w, h): (u32, u32),
) -> Result<()> {
    let scale = 3;
    let (gap, label_h) = (16, 22);
    let row_h = label_h + h * scale + 8;
    let mut c = Canvas::new(2 * w * scale + gap, row_h * rows.len().max(1) as u32);
    let mut labels = Vec::new();
    for (k, (label, left, right)) in rows.iter().enumerate() {
        let max = left
            .iter()
            .chain(right.iter())
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0f64, f64::max)
            .max(1e-30);
        let (a, b) = (
            false_colour(left, max * 1e-4, max),
            false_colour(right, max * 1e-4, max),
        );
        let y0 = k as u32 * row_h;
        // bins run up in cosθ: draw the highest first, so the pole is at the top
        let flip = |v: &[[u8; 3]], i: usize| {
            let (x, y) = (i as u32 % w, i as u32 / w);
            v[((h - 1 - y) * w + x) as usize]
        };
        c.blit(0, y0 + label_h, w, h, scale, &|i| flip(&a, i));
        c.blit(w * scale + gap, y0 + label_h, w, h, scale, &|i| flip(&b, i));
        labels.push((label.clone(), 4, y0 + 4));
    }
    c.text(&labels)?;
    c.write(path)
}

/// What the error maps show.
const ERROR_TITLE: &str = "relative squared error (x−r)²/(r²+0.01), log scale";

/// Height of a colour bar with its labels.
const BAR_H: u32 = 48;

/// An RGB8 image being drawn: pixels blitted, colour bars and text.
struct Canvas {
    w: u32,
    h: u32,
    buf: Vec<u8>,
}

impl Canvas {
    fn new(w: u32, h: u32) -> Canvas {
        Canvas {
            w,
            h,
            buf: vec![255u8; (w * h * 3) as usize],
        }
    }

    /// Draw a `width × height` image at (x0, y0), each pixel `scale`² screen pixels.
    fn blit(
        &mut self,
        x0: u32,
        y0: u32,
        width: u32,
        height: u32,
        scale: u32,
        px: &dyn Fn(usize) -> [u8; 3],
    ) {
        for y in 0..height * scale {
            for x in 0..width * scale {
                let src = ((y / scale) * width + x / scale) as usize;
                let dst = (((y0 + y) * self.w + x0 + x) * 3) as usize;
                self.buf[dst..dst + 3].copy_from_slice(&px(src));
            }
        }
    }

    /// Write `lines` of text, the first at (x, y), 16 pixels apart.
    fn text(&mut self, lines: &[(String, u32, u32)]) -> Result<()> {
        register_font();
        let root = bitmap(&mut self.buf, (self.w, self.h)).into_drawing_area();
        let style = (FONT, 14).into_font().color(&BLACK);
        for (s, x, y) in lines {
            root.draw(&Text::new(s.clone(), (*x as i32, *y as i32), style.clone()))
                .map_err(|e| Error::Settings(format!("drawing text: {e}")))?;
        }
        root.present()
            .map_err(|e| Error::Settings(format!("drawing text: {e}")))
    }

    /// A colour bar across the canvas at height `y0`: the map from `lo` (left) to `hi` (right)
    /// on a log scale, its two ends and its middle labelled with their values, and a title.
    fn colour_bar(&mut self, x0: u32, y0: u32, lo: f64, hi: f64, title: &str) -> Result<()> {
        let (bx, bw) = (x0 + 8, self.w - x0 - 16);
        for x in 0..bw {
            let c = colormap(x as f64 / (bw - 1).max(1) as f64);
            for y in y0 + 4..y0 + 16 {
                let dst = ((y * self.w + bx + x) * 3) as usize;
                self.buf[dst..dst + 3].copy_from_slice(&c);
            }
        }
        let mid = (lo.max(1e-30).log10() + hi.max(lo * 10.0).log10()) / 2.0;
        let right = format!("{:.1e}", hi.max(lo * 10.0));
        self.text(&[
            (format!("{lo:.1e}"), bx, y0 + 18),
            (
                format!("{:.1e}", 10f64.powf(mid)),
                bx + bw / 2 - 24,
                y0 + 18,
            ),
            (right.clone(), bx + bw - 8 * right.len() as u32, y0 + 18),
            (title.to_string(), bx, y0 + 33),
        ])
    }

    fn write(self, path: &Path) -> Result<()> {
        write_png_rgb8(path, self.w, self.h, &self.buf)
    }
}

/// Write a comparison's grid as a PNG: one column per image, the reference first; the top row
/// holds the images (tone-mapped with `exposure`), the bottom row each strategy's error map
/// against the reference on one shared log scale, whose colour bar and range run below.
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
    let (lo, hi) = error_scale(&maps.iter().map(Vec::as_slice).collect::<Vec<_>>());
    let (w, h) = (reference.width, reference.height);
    let scale = (256 / w.max(h)).max(1);
    let (cw, ch, pad, label_h) = (w * scale, h * scale, 8u32, 40u32);
    let columns = 1 + c.rows.len() as u32;
    let gw = (pad + columns * (cw + pad)).max(480);
    let gh = label_h + ch + pad + ch + pad + BAR_H;
    let mut g = Canvas::new(gw, gh);
    let x_of = |col: u32| pad + col * (cw + pad);
    g.blit(x_of(0), label_h, w, h, scale, &|k| {
        tonemap(reference.pixels[k], exposure)
    });
    let mut labels = vec![("reference".to_string(), x_of(0), 4)];
    if let Ok(Some(m)) = crate::output::RenderMetadata::radiance(reference, Path::new("reference"))
    {
        labels.push((format!("{} spp", m.spp), x_of(0), 20));
    }
    labels.push((
        "error maps →".to_string(),
        x_of(0),
        label_h + ch + pad + ch / 2,
    ));
    for (i, ((row, img), map)) in c.rows.iter().zip(&c.images).zip(&maps).enumerate() {
        let x0 = x_of(i as u32 + 1);
        g.blit(x0, label_h, w, h, scale, &|k| tonemap(img[k], exposure));
        let colours = false_colour(map, lo, hi);
        g.blit(x0, label_h + ch + pad, w, h, scale, &|k| colours[k]);
        labels.push((row.strategy.clone(), x0, 4));
        labels.push((format!("{:.0} spp  MSE {:.2e}", row.spp, row.mse), x0, 20));
    }
    g.text(&labels)?;
    g.colour_bar(0, label_h + 2 * (ch + pad), lo, hi, ERROR_TITLE)?;
    g.write(path)
}

/// The range `[lo, hi]` an error-map colour scale spans: the 1st to 99.9th percentile of the
/// positive errors of all maps, so every map shares one scale.
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
