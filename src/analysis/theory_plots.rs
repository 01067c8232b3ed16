//! The pictures of `vrpt points` and `vrpt integrate`: the lecture's theory drawn where it is
//! simplest ([`crate::analysis::points`] and [`crate::analysis::integrate`] compute what is
//! drawn).
//!
//! - [`write_points_picture`]: one panel per point set (its points, after a warp if asked, with
//!   the stratified sampler's strata and the box `[0,a)×[0,b)` carried through the same warp),
//!   under them each set's periodogram `P(k)` as an image (`k ∈ [−m, m]²`, the origin at the
//!   centre, power 0 to 2 on a linear scale: independent points are an even 1), and at the
//!   bottom the radially averaged spectra beside the discrepancy against `N` on log-log axes
//!   with the independent points' expectation `√(5/(36N))`.
//! - [`write_integrate_picture`]: per integrand and direction strategy, the variance of the
//!   estimate against `N` on log-log axes, one line per sampler with its fitted slope, and the
//!   formulas `σ²/N` and `(1/N²) Σ σᵢ²` dashed;
//! - [`write_lecture_figure`]: the lecture's Figure 2, a curve sampled without and with strata.
//!
//! SVG by the path's extension, else PNG.

use crate::analysis::plots::{draw_err, register_font, FONT, PALETTE};
use crate::analysis::points::PointWarp;
use crate::error::Result;
use glam::Vec2;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// One point set's panel of [`write_points_picture`].
pub struct Panel<'a> {
    /// The set's name (the legend's).
    pub label: &'a str,
    /// Its points in the unit square (before the warp).
    pub points: &'a [Vec2],
    /// Where they are shown.
    pub warp: PointWarp,
    /// The strata grid `(a, b)` to draw (a stratified set), if any.
    pub strata: Option<(u32, u32)>,
    /// The box `[0,a)×[0,b)` drawn over the points.
    pub box_size: (f32, f32),
    /// The line over the panel.
    pub caption: String,
    /// Its radially averaged power spectrum, `[frequency, power]`.
    pub spectrum: &'a [[f64; 2]],
    /// Its periodogram, `(2m+1)²` values row-major, and `m`.
    pub periodogram: (&'a [f64], u32),
    /// Its discrepancy against N, `[n, rms D₂*]`, and the fitted slope.
    pub curve: (&'a [[f64; 2]], f64),
}

/// Write the point sets' picture (see the module doc) to `path`.
pub fn write_points_picture(path: &Path, panels: &[Panel]) -> Result<()> {
    let size = ((340 * panels.len().max(3)) as u32, 1060u32);
    write_either(path, size, &PointsFigure(panels))
}

/// A picture that any plotters backend can draw.
trait Figure {
    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), String>;
}

struct PointsFigure<'a, 'b>(&'a [Panel<'b>]);

impl Figure for PointsFigure<'_, '_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), String> {
        draw_points(root, self.0)
    }
}

/// Draw `figure` with the backend the extension names: SVG for `.svg`, else PNG.
fn write_either(path: &Path, size: (u32, u32), figure: &impl Figure) -> Result<()> {
    register_font();
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"))
    {
        let mut svg = String::new();
        figure
            .draw(SVGBackend::with_string(&mut svg, size).into_drawing_area())
            .map_err(|m| draw_err(path, m))?;
        crate::image_io::write_bytes(path, svg.as_bytes())
    } else {
        crate::image_io::Format::from_path(path)?;
        let mut buf = vec![0u8; (size.0 * size.1 * 3) as usize];
        figure
            .draw(crate::analysis::plots::bitmap(&mut buf, size).into_drawing_area())
            .map_err(|m| draw_err(path, m))?;
        crate::image_io::write_png_rgb8(path, size.0, size.1, &buf)
    }
}

/// `(a, b)`'s segment in the unit square as the warp shows it (64 steps where it bends).
fn warped_segment(w: PointWarp, a: Vec2, b: Vec2) -> Vec<(f32, f32)> {
    let steps = if w == PointWarp::Square { 1 } else { 64 };
    (0..=steps)
        .map(|i| {
            let p = w.picture(a.lerp(b, i as f32 / steps as f32));
            (p.x, p.y)
        })
        .collect()
}

fn draw_points<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    panels: &[Panel],
) -> std::result::Result<(), String> {
    let e = |x: plotters::drawing::DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let (top, rest) = root.split_vertically(380);
    let (middle, bottom) = rest.split_vertically(320);
    let cells = top.split_evenly((1, panels.len().max(1)));
    for (k, (area, p)) in cells.iter().zip(panels).enumerate() {
        draw_point_panel(area, PALETTE[k % PALETTE.len()], p).map_err(e)?;
    }
    let cells = middle.split_evenly((1, panels.len().max(1)));
    for (area, p) in cells.iter().zip(panels) {
        draw_periodogram(area, p).map_err(e)?;
    }
    let (left, right) = bottom.split_horizontally(bottom.dim_in_pixel().0 / 2);
    draw_spectra(&left, panels).map_err(e)?;
    draw_discrepancy(&right, panels).map_err(e)?;
    root.present().map_err(e)
}

/// One set's points in `colour`, where its warp shows them: over the warp's domain outlined,
/// the strata's grid (grey) and the box (red), both carried through the warp.
fn draw_point_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    colour: RGBColor,
    p: &Panel,
) -> DrawResult<DB> {
    let ((x0, x1), (y0, y1)) = p.warp.extent();
    let mut chart = ChartBuilder::on(area)
        .caption(&p.caption, (FONT, 12))
        .margin(10)
        .x_label_area_size(20)
        .y_label_area_size(30)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .label_style((FONT, 11))
        .x_labels(3)
        .y_labels(3)
        .draw()?;
    let grey = RGBColor(200, 200, 200);
    if let Some(outline) = domain_outline(p.warp) {
        chart.draw_series(LineSeries::new(outline, BLACK.stroke_width(1)))?;
    }
    if let Some(strata) = p.strata {
        for line in strata_lines(p.warp, strata) {
            chart.draw_series(LineSeries::new(line, grey))?;
        }
    }
    let outline = box_outline(p.warp, p.box_size);
    chart.draw_series([Polygon::new(outline.clone(), RED.mix(0.12).filled())])?;
    chart.draw_series(LineSeries::new(outline, RED.stroke_width(1)))?;
    chart.draw_series(p.points.iter().map(|&q| {
        let q = p.warp.picture(q);
        Circle::new((q.x, q.y), 2, colour.filled())
    }))?;
    Ok(())
}

/// The outline of the domain a warp's picture fills: the triangle, or the unit circle (the
/// hemisphere warps' directions seen from above); none for the square itself.
fn domain_outline(w: PointWarp) -> Option<Vec<(f32, f32)>> {
    match w {
        PointWarp::Square => None,
        PointWarp::Triangle => Some(vec![(0.0, 0.0), (1.0, 0.0), (0.5, 0.866), (0.0, 0.0)]),
        _ => Some(
            (0..=128)
                .map(|i| {
                    let a = i as f32 / 128.0 * std::f32::consts::TAU;
                    (a.cos(), a.sin())
                })
                .collect(),
        ),
    }
}

/// The inner lines of an `a × b` strata grid of the square, carried through warp `w`.
fn strata_lines(w: PointWarp, (a, b): (u32, u32)) -> Vec<Vec<(f32, f32)>> {
    let mut lines = Vec::new();
    for i in 1..a {
        let x = i as f32 / a as f32;
        lines.push(warped_segment(w, Vec2::new(x, 0.0), Vec2::new(x, 1.0)));
    }
    for j in 1..b {
        let y = j as f32 / b as f32;
        lines.push(warped_segment(w, Vec2::new(0.0, y), Vec2::new(1.0, y)));
    }
    lines
}

/// The outline of the box `[0,bx)×[0,by)`, carried through warp `w`.
fn box_outline(w: PointWarp, (bx, by): (f32, f32)) -> Vec<(f32, f32)> {
    let corners = [
        Vec2::ZERO,
        Vec2::new(bx, 0.0),
        Vec2::new(bx, by),
        Vec2::new(0.0, by),
    ];
    (0..4)
        .flat_map(|i| warped_segment(w, corners[i], corners[(i + 1) % 4]))
        .collect()
}

type DrawResult<DB> = std::result::Result<
    (),
    plotters::drawing::DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>,
>;

/// One set's periodogram as an image: power 0 (dark) to 2 (bright), linear.
fn draw_periodogram<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &Panel,
) -> DrawResult<DB> {
    let (values, m) = p.periodogram;
    let side = 2 * m as i32 + 1;
    let r = m as f32 + 0.5;
    let mut chart = ChartBuilder::on(area)
        .caption(format!("{}: periodogram P(k)", p.label), (FONT, 12))
        .margin(10)
        .x_label_area_size(20)
        .y_label_area_size(30)
        .build_cartesian_2d(-r..r, -r..r)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .label_style((FONT, 11))
        .x_labels(5)
        .y_labels(5)
        .draw()?;
    chart.draw_series(values.iter().enumerate().map(|(i, &v)| {
        let (kx, ky) = (
            (i as i32 % side - m as i32) as f32,
            (i as i32 / side - m as i32) as f32,
        );
        let [r, g, b] = crate::analysis::metrics::colormap((v / 2.0).clamp(0.0, 1.0));
        Rectangle::new(
            [(kx - 0.5, ky - 0.5), (kx + 0.5, ky + 0.5)],
            RGBColor(r, g, b).filled(),
        )
    }))?;
    Ok(())
}

/// The radially averaged spectra, one line per set.
fn draw_spectra<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panels: &[Panel],
) -> DrawResult<DB> {
    let top = panels
        .iter()
        .flat_map(|p| p.spectrum.iter().map(|s| s[1]))
        .fold(1.0f64, f64::max)
        .min(2.0)
        * 1.1;
    let kmax = panels
        .iter()
        .flat_map(|p| p.spectrum.iter().map(|s| s[0]))
        .fold(1.0f64, f64::max);
    let mut chart = ChartBuilder::on(area)
        .caption(
            "radially averaged power spectrum (independent: 1)",
            (FONT, 14),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(45)
        .build_cartesian_2d(0f64..kmax, 0f64..top)?;
    chart
        .configure_mesh()
        .x_desc("frequency |k|")
        .y_desc("power")
        .label_style((FONT, 12))
        .draw()?;
    for (k, p) in panels.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        chart
            .draw_series(LineSeries::new(
                p.spectrum.iter().map(|s| (s[0], s[1].min(top))),
                colour.stroke_width(2),
            ))?
            .label(p.label.to_string())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
    }
    chart
        .configure_series_labels()
        .label_font((FONT, 12))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerRight)
        .draw()
}

/// The discrepancy against N on log-log axes, with `√(5/(36N))` dashed.
fn draw_discrepancy<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panels: &[Panel],
) -> DrawResult<DB> {
    let all = || panels.iter().flat_map(|p| p.curve.0.iter());
    let (n0, n1) = all().fold((f64::MAX, 1.0f64), |(a, b), c| (a.min(c[0]), b.max(c[0])));
    let n0 = n0.min(n1);
    let (d0, d1) = all()
        .map(|c| c[1])
        .chain([(5.0 / (36.0 * n0)).sqrt(), (5.0 / (36.0 * n1)).sqrt()])
        .filter(|d| *d > 0.0)
        .fold((f64::MAX, 0.0f64), |(a, b), d| (a.min(d), b.max(d)));
    let mut chart = ChartBuilder::on(area)
        .caption("L2-star discrepancy against N", (FONT, 14))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (n0 / 1.3..n1 * 1.3).log_scale(),
            (d0 / 1.5..d1 * 1.5).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("points N")
        .y_desc("rms D2*")
        .label_style((FONT, 12))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .x_label_formatter(&|x| format!("{x:.0}"))
        .draw()?;
    let theory = [n0, n1].map(|n| (n, (5.0 / (36.0 * n)).sqrt()));
    chart
        .draw_series(DashedLineSeries::new(theory, 6, 4, BLACK.stroke_width(1)))?
        .label("independent: (5/36N)^½")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(1)));
    for (k, p) in panels.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        let pts: Vec<(f64, f64)> = p
            .curve
            .0
            .iter()
            .filter(|c| c[1] > 0.0)
            .map(|c| (c[0], c[1]))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))?
            .label(format!("{} (slope {:.2})", p.label, p.curve.1))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart.draw_series(pts.iter().map(|&q| Circle::new(q, 3, colour.filled())))?;
    }
    chart
        .configure_series_labels()
        .label_font((FONT, 12))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerLeft)
        .draw()
}

/// One integrand × direction strategy's plot of [`write_integrate_picture`].
pub struct ConvergencePanel {
    /// Its title (integrand and directions).
    pub title: String,
    /// Per sampler: its name, `[N, variance]` points and the fitted slope.
    pub lines: Vec<(String, Vec<[f64; 2]>, f64)>,
    /// The formula `σ²/N` at each N (empty where it is 0: `p ∝ f`).
    pub predicted: Vec<[f64; 2]>,
    /// The jittered formula `(1/N²) Σ σᵢ²` at each N (empty without jittered rows).
    pub jittered: Vec<[f64; 2]>,
}

/// Write the variance-against-N plots (see the module doc), three to a row, to `path`.
pub fn write_integrate_picture(path: &Path, panels: &[ConvergencePanel]) -> Result<()> {
    let cols = panels.len().clamp(1, 3);
    let rows = panels.len().div_ceil(cols).max(1);
    let size = (420 * cols as u32, 340 * rows as u32);
    write_either(path, size, &IntegrateFigure(panels, (rows, cols)))
}

struct IntegrateFigure<'a>(&'a [ConvergencePanel], (usize, usize));

impl Figure for IntegrateFigure<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), String> {
        let e = |x: plotters::drawing::DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
        root.fill(&WHITE).map_err(e)?;
        for (area, p) in root.split_evenly(self.1).iter().zip(self.0) {
            draw_integrate_panel(area, p).map_err(e)?;
        }
        root.present().map_err(e)
    }
}

fn draw_integrate_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &ConvergencePanel,
) -> DrawResult<DB> {
    let all = || {
        p.lines
            .iter()
            .flat_map(|l| l.1.iter())
            .chain(p.predicted.iter())
            .chain(p.jittered.iter())
            .filter(|q| q[1] > 0.0)
    };
    let (n0, n1) = all().fold((f64::MAX, 1.0f64), |(a, b), q| (a.min(q[0]), b.max(q[0])));
    let (v0, v1) = all().fold((f64::MAX, 0.0f64), |(a, b), q| (a.min(q[1]), b.max(q[1])));
    let (n0, v0, v1) = if v0 <= v1 {
        (n0, v0, v1)
    } else {
        (1.0, 1e-6, 1.0)
    };
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, (FONT, 14))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d(
            (n0 / 1.3..n1 * 1.3).log_scale(),
            (v0 / 2.0..v1 * 2.0).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("N")
        .y_desc("variance")
        .label_style((FONT, 11))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .x_label_formatter(&|x| format!("{x:.0}"))
        .draw()?;
    for (k, (name, pts, slope)) in p.lines.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        let pts: Vec<(f64, f64)> = pts
            .iter()
            .filter(|q| q[1] > 0.0)
            .map(|q| (q[0], q[1]))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))?
            .label(format!("{name} (slope {slope:.2})"))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart.draw_series(pts.iter().map(|&q| Circle::new(q, 3, colour.filled())))?;
    }
    // the formulas last, over the lines they predict
    draw_formula(&mut chart, &p.predicted, (6, 4), "σ²/N")?;
    draw_formula(&mut chart, &p.jittered, (3, 3), "(1/N²) Σ σ_i²")?;
    chart
        .configure_series_labels()
        .label_font((FONT, 11))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerLeft)
        .draw()
}

/// A formula's curve `pts` (none: nothing drawn) dashed (`dash` on, `gap` off) in black, with
/// its legend `label`.
fn draw_formula<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<LogCoord<f64>, LogCoord<f64>>>,
    pts: &[[f64; 2]],
    (dash, gap): (i32, i32),
    label: &str,
) -> DrawResult<DB> {
    if pts.is_empty() {
        return Ok(());
    }
    let line = DashedLineSeries::new(pts.iter().map(|q| (q[0], q[1])), dash, gap, BLACK.into());
    chart
        .draw_series(line)?
        .label(label)
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(1)));
    Ok(())
}

/// The lecture's Figure 2 (`vrpt integrate --figure`): a 1D integrand with N points from `p`
/// (top) and with one point in each of N strata (bottom), each with its variance as `vrpt
/// integrate` measures and predicts it.
pub struct LectureFigure {
    /// The points of each set (N).
    pub n: u32,
    /// The independent points and their variance.
    pub unstratified: LectureSet,
    /// The jittered points and their variance.
    pub stratified: LectureSet,
}

/// One set of the figure: its points, and the estimator's variance predicted and measured (with
/// its standard error) over `repetitions` sets.
#[derive(Clone, Debug, PartialEq)]
pub struct LectureSet {
    /// The set's points in `[0, 1)`.
    pub points: Vec<f64>,
    /// The formula's variance of the estimator.
    pub predicted: f64,
    /// The measured variance over `repetitions` sets.
    pub measured: f64,
    /// The standard error of `measured` (from the estimates' fourth moment).
    pub measured_se: f64,
    /// How many sets were measured.
    pub repetitions: u32,
}

/// Write [`LectureFigure`] to `path` (SVG by its extension, else PNG).
pub fn write_lecture_figure(path: &Path, figure: &LectureFigure) -> Result<()> {
    write_either(path, (900, 620), figure)
}

impl Figure for LectureFigure {
    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), String> {
        let e = |x: plotters::drawing::DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
        root.fill(&WHITE).map_err(e)?;
        let (top, bottom) = root.split_vertically(310);
        let n = self.n;
        let set = &self.unstratified;
        let caption = format!("unstratified: all {n} points from p = 1");
        let said = variance_words(set, "σ²/N");
        draw_lecture_panel(&top, (&caption, &said), &set.points, None, PALETTE[0]).map_err(e)?;
        let set = &self.stratified;
        let caption = format!("stratified: one point from p restricted to each of {n} strata");
        let said = variance_words(set, "(1/N²) Σ σ_i²");
        draw_lecture_panel(&bottom, (&caption, &said), &set.points, Some(n), PALETTE[1])
            .map_err(e)?;
        root.present().map_err(e)
    }
}

/// `Var = formula = predicted; measured ± se over R sets` for a set.
fn variance_words(s: &LectureSet, formula: &str) -> String {
    format!(
        "Var[Ĩ] = {formula} = {:.3e}; measured {:.3e} ± {:.1e} ({} sets)",
        s.predicted, s.measured, s.measured_se, s.repetitions
    )
}

/// One panel of the lecture's figure: the curve, the points dropped onto it, the strata.
fn draw_lecture_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (caption, said): (&str, &str),
    points: &[f64],
    strata: Option<u32>,
    colour: RGBColor,
) -> DrawResult<DB> {
    use crate::analysis::integrate::{Domain, Integrand};
    let f = |x: f64| Integrand::Curve.g(Domain::Line, Vec2::new(x as f32, 0.0));
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FONT, 15))
        .margin(12)
        .x_label_area_size(28)
        .y_label_area_size(40)
        .build_cartesian_2d(0.0..1.0f64, 0.0..2.6f64)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x")
        .y_desc("f(x)")
        .label_style((FONT, 11))
        .x_label_formatter(&|x| format!("{x:.1}"))
        .y_label_formatter(&|y| format!("{y:.1}"))
        .draw()?;
    if let Some(n) = strata {
        for k in 0..n {
            let (a, b) = (k as f64 / n as f64, (k + 1) as f64 / n as f64);
            let shade = if k % 2 == 0 { 0.10 } else { 0.04 };
            chart.draw_series(std::iter::once(Rectangle::new(
                [(a, 0.0), (b, 2.45)],
                colour.mix(shade).filled(),
            )))?;
        }
    }
    let curve: Vec<(f64, f64)> = (0..=400)
        .map(|i| i as f64 / 400.0)
        .map(|x| (x, f(x)))
        .collect();
    chart.draw_series(LineSeries::new(curve, BLACK.stroke_width(2)))?;
    for &x in points {
        let y = f(x);
        chart.draw_series(LineSeries::new(
            vec![(x, 0.0), (x, y)],
            colour.stroke_width(1),
        ))?;
        chart.draw_series(std::iter::once(Circle::new((x, y), 4, colour.filled())))?;
    }
    chart.draw_series(std::iter::once(Text::new(
        said.to_string(),
        (0.33, 2.4),
        (FONT, 12).into_font(),
    )))?;
    Ok(())
}
