//! The theory where it is simplest: the sample points themselves, in the unit square.
//!
//! A sampler's points for one 2D dimension of the layout ([`crate::sampler::layout`]: the pixel
//! position, or a bounce's light point or direction) are drawn exactly as a render draws them:
//! sample `i` of a pixel starts with `start_pixel_sample(pixel, i)` and takes the layout's
//! dimensions in order, through the same [`SamplerFactory`] as renders (so a library user's own
//! sampler is drawn like the built-in ones). What is measured of a set `x₁ … x_N ∈ [0,1)²`:
//!
//! - **L2-star discrepancy** (Warnock's closed form, `d = 2`):
//!   `D₂*² = 1/9 − (2/N) Σᵢ Πₖ (1 − xᵢₖ²)/2 + (1/N²) Σᵢ Σⱼ Πₖ (1 − max(xᵢₖ, xⱼₖ))`,
//!   the mean squared difference between the fraction of points in `[0,a)×[0,b)` and its area
//!   `ab`, over all `(a, b)`. For independent uniform points `E[D₂*²] = (1/N)(1/4 − 1/9) =
//!   5/(36N)`: the discrepancy falls as `N^{-1/2}`.
//! - **Periodogram** `P(k) = |Σⱼ e^{−2πi k·xⱼ}|² / N` at integer frequencies `k ≠ 0`, averaged
//!   over realisations (seeds). Independent points have `E[P(k)] = 1` everywhere (a flat
//!   spectrum: no frequency is favoured); jittered points have `E[P(k)] = 1 − sinc²(k_x/n)
//!   sinc²(k_y/n)` on an `n × n` grid (`sinc(t) = sin(πt)/(πt)`), near zero where `|k| ≪ n`:
//!   the low frequencies, where a smooth integrand's energy is, carry almost no error.
//! - **Radially averaged power**: the mean of `P(k)` over the integer `k` with
//!   `r − ½ ≤ |k| < r + ½`, for `r = 1, 2, …`.

use crate::render::{SamplePass, SamplerFactory};
use crate::sampler::layout::{Dim, BOUNCE_DIMS, CAMERA_DIMS};
use crate::sampler::Sampler;
use glam::{UVec2, Vec2};

/// The 2D dimensions of the layout a point set can be drawn from, by name: `pixel`, and for
/// bounce `b` (from 1) `light-b` (the point on the light) and `direction-b`.
pub fn dimension_names(bounces: u32) -> Vec<String> {
    let mut v = vec!["pixel".to_string()];
    for b in 1..=bounces {
        v.push(format!("light-{b}"));
        v.push(format!("direction-{b}"));
    }
    v
}

/// The index, among the dimensions a sample draws in order, of the 2D dimension `name`
/// ([`dimension_names`]), and how many dimensions come before it; `None` for an unknown name.
pub fn dimension_index(name: &str) -> Option<usize> {
    let layout: Vec<(String, Dim)> = layout_until(16);
    layout.iter().position(|(n, _)| n == name)
}

/// The layout's dimensions for `bounces` bounces, each named (the 1D ones by what they decide).
fn layout_until(bounces: u32) -> Vec<(String, Dim)> {
    let mut v: Vec<(String, Dim)> = CAMERA_DIMS.iter().map(|&d| ("pixel".into(), d)).collect();
    for b in 1..=bounces {
        for &d in BOUNCE_DIMS.iter() {
            let name = match d {
                Dim::Two("point on the light") => format!("light-{b}"),
                Dim::Two("direction") => format!("direction-{b}"),
                Dim::Two(other) | Dim::One(other) => format!("{other} {b}"),
            };
            v.push((name, d));
        }
    }
    v
}

/// `n` points of the sampler `factory` makes (seed `seed`, one pass of `n` samples) for pixel
/// `pixel`, in the 2D dimension at position `dim` of the layout ([`dimension_index`]).
pub fn draw_points<F: SamplerFactory>(
    factory: &F,
    seed: u64,
    n: u32,
    pixel: UVec2,
    dim: usize,
) -> Vec<Vec2> {
    let layout = layout_until(16);
    let mut s = factory.make(seed, SamplePass { origin: 0, size: n });
    (0..n)
        .map(|i| {
            s.start_pixel_sample(pixel, i);
            let mut out = Vec2::ZERO;
            for (k, (_, d)) in layout.iter().enumerate().take(dim + 1) {
                let v = match d {
                    Dim::One(_) => Vec2::new(s.next_1d(), 0.0),
                    Dim::Two(_) => s.next_2d(),
                };
                if k == dim {
                    out = v;
                }
            }
            out
        })
        .collect()
}

/// The L2-star discrepancy of `points` in `[0,1)²` (Warnock's closed form; O(N²)).
pub fn l2_star_discrepancy(points: &[Vec2]) -> f64 {
    let n = points.len() as f64;
    if points.is_empty() {
        return 0.0;
    }
    let p: Vec<(f64, f64)> = points.iter().map(|v| (v.x as f64, v.y as f64)).collect();
    let single: f64 = p
        .iter()
        .map(|&(x, y)| (1.0 - x * x) / 2.0 * (1.0 - y * y) / 2.0)
        .sum();
    let mut pairs = 0.0;
    for &(xi, yi) in &p {
        for &(xj, yj) in &p {
            pairs += (1.0 - xi.max(xj)) * (1.0 - yi.max(yj));
        }
    }
    (1.0 / 9.0 - 2.0 / n * single + pairs / (n * n))
        .max(0.0)
        .sqrt()
}

/// The periodogram `|Σ e^{−2πi k·x}|²/N` of each set in `sets`, averaged over the sets, at the
/// integer frequencies `k ∈ [−m, m]²`: row-major, `(2m+1)²` values, `k = (0, 0)` at the centre
/// (its value, `N`, is the set's mean squared and carries no information about its spread).
pub fn periodogram(sets: &[Vec<Vec2>], m: u32) -> Vec<f64> {
    let side = (2 * m + 1) as usize;
    let mut out = vec![0.0; side * side];
    for pts in sets {
        let n = pts.len().max(1) as f64;
        // e^{−2πi k x} for every point and k ∈ [−m, m] per axis, by powers of the unit step
        let phases = |c: f64| -> Vec<(f64, f64)> {
            (0..side)
                .map(|j| {
                    let k = j as f64 - m as f64;
                    let a = -2.0 * std::f64::consts::PI * k * c;
                    (a.cos(), a.sin())
                })
                .collect()
        };
        let px: Vec<Vec<(f64, f64)>> = pts.iter().map(|p| phases(p.x as f64)).collect();
        let py: Vec<Vec<(f64, f64)>> = pts.iter().map(|p| phases(p.y as f64)).collect();
        for ky in 0..side {
            for kx in 0..side {
                let (mut re, mut im) = (0.0, 0.0);
                for (ex, ey) in px.iter().zip(&py) {
                    let (a, b) = ex[kx];
                    let (c, d) = ey[ky];
                    re += a * c - b * d;
                    im += a * d + b * c;
                }
                out[ky * side + kx] += (re * re + im * im) / n / sets.len() as f64;
            }
        }
    }
    out
}

/// The radially averaged power of a periodogram of [`periodogram`]'s layout (`k ∈ [−m, m]²`):
/// `(r, mean of P(k) over r − ½ ≤ |k| < r + ½)` for `r = 1 … m`.
pub fn radial_spectrum(p: &[f64], m: u32) -> Vec<(f64, f64)> {
    let side = (2 * m + 1) as usize;
    let mut sum = vec![0.0; m as usize + 1];
    let mut count = vec![0u32; m as usize + 1];
    for ky in 0..side {
        for kx in 0..side {
            let (x, y) = (kx as f64 - m as f64, ky as f64 - m as f64);
            let r = (x * x + y * y).sqrt().round() as usize;
            if (1..=m as usize).contains(&r) {
                sum[r] += p[ky * side + kx];
                count[r] += 1;
            }
        }
    }
    (1..=m as usize)
        .map(|r| (r as f64, sum[r] / count[r].max(1) as f64))
        .collect()
}

/// The fraction of `points` in the box `[0,a)×[0,b)`: for independent uniform points its
/// expectation is the box's area `ab` (the lecture's picture of independence).
pub fn fraction_in_box(points: &[Vec2], a: f32, b: f32) -> f64 {
    let inside = points.iter().filter(|p| p.x < a && p.y < b).count();
    inside as f64 / points.len().max(1) as f64
}

/// One sampler's panel of the picture of [`write_picture`].
pub struct Panel<'a> {
    /// The sampler's name.
    pub label: &'a str,
    /// Its points.
    pub points: &'a [Vec2],
    /// The strata grid `(a, b)` to draw (a stratified set), if any.
    pub strata: Option<(u32, u32)>,
    /// The box `[0,a)×[0,b)` drawn over the points.
    pub box_size: (f32, f32),
    /// The line under the panel.
    pub caption: String,
    /// Its radially averaged power spectrum, `[frequency, power]`.
    pub spectrum: &'a [[f64; 2]],
}

/// Write the panels side by side (points, strata, box, caption) over one plot of their radial
/// spectra, to `path`: SVG by its extension, else PNG.
pub fn write_picture(path: &std::path::Path, panels: &[Panel]) -> crate::error::Result<()> {
    use crate::analysis::plots::{draw_err, register_font};
    use plotters::prelude::*;
    register_font();
    let size = ((360 * panels.len().max(1)) as u32, 760u32);
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"))
    {
        let mut svg = String::new();
        draw_picture(
            SVGBackend::with_string(&mut svg, size).into_drawing_area(),
            panels,
        )
        .map_err(|m| draw_err(path, m))?;
        crate::image_io::write_bytes(path, svg.as_bytes())
    } else {
        let mut buf = vec![0u8; (size.0 * size.1 * 3) as usize];
        draw_picture(
            BitMapBackend::with_buffer(&mut buf, size).into_drawing_area(),
            panels,
        )
        .map_err(|m| draw_err(path, m))?;
        crate::image_io::write_png_rgb8(path, size.0, size.1, &buf)
    }
}

fn draw_picture<DB: plotters::prelude::DrawingBackend>(
    root: plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    panels: &[Panel],
) -> std::result::Result<(), String> {
    use crate::analysis::plots::{FONT, PALETTE};
    use plotters::prelude::*;
    let e = |x: plotters::drawing::DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let (top, bottom) = root.split_vertically(400);
    let cells = top.split_evenly((1, panels.len().max(1)));
    for (k, (area, p)) in cells.iter().zip(panels).enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        let mut chart = ChartBuilder::on(area)
            .caption(&p.caption, (FONT, 13))
            .margin(12)
            .x_label_area_size(20)
            .y_label_area_size(30)
            .build_cartesian_2d(0f32..1f32, 0f32..1f32)
            .map_err(e)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .label_style((FONT, 11))
            .x_labels(3)
            .y_labels(3)
            .draw()
            .map_err(e)?;
        if let Some((a, b)) = p.strata {
            let grey = RGBColor(200, 200, 200);
            for i in 1..a {
                let x = i as f32 / a as f32;
                chart
                    .draw_series(LineSeries::new([(x, 0.0), (x, 1.0)], grey))
                    .map_err(e)?;
            }
            for j in 1..b {
                let y = j as f32 / b as f32;
                chart
                    .draw_series(LineSeries::new([(0.0, y), (1.0, y)], grey))
                    .map_err(e)?;
            }
        }
        let (bx, by) = p.box_size;
        chart
            .draw_series([Rectangle::new(
                [(0.0, 0.0), (bx, by)],
                RED.mix(0.12).filled(),
            )])
            .map_err(e)?;
        chart
            .draw_series([Rectangle::new([(0.0, 0.0), (bx, by)], RED.stroke_width(1))])
            .map_err(e)?;
        chart
            .draw_series(
                p.points
                    .iter()
                    .map(|q| Circle::new((q.x, q.y), 2, colour.filled())),
            )
            .map_err(e)?;
    }
    let top_power = panels
        .iter()
        .flat_map(|p| p.spectrum.iter().map(|s| s[1]))
        .fold(1.0f64, f64::max)
        * 1.1;
    let kmax = panels
        .iter()
        .flat_map(|p| p.spectrum.iter().map(|s| s[0]))
        .fold(1.0f64, f64::max);
    let mut chart = ChartBuilder::on(&bottom)
        .caption(
            "radially averaged power spectrum (independent points: 1)",
            (FONT, 16),
        )
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0f64..kmax, 0f64..top_power)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("frequency |k|")
        .y_desc("power")
        .label_style((FONT, 12))
        .draw()
        .map_err(e)?;
    for (k, p) in panels.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        chart
            .draw_series(LineSeries::new(
                p.spectrum.iter().map(|s| (s[0], s[1])),
                colour.stroke_width(2),
            ))
            .map_err(e)?
            .label(p.label.to_string())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
    }
    chart
        .configure_series_labels()
        .label_font((FONT, 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerRight)
        .draw()
        .map_err(e)?;
    root.present().map_err(e)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Warnock's formula against its definition on a tiny set: the mean over a fine grid of
    /// boxes of (fraction inside − area)², square-rooted.
    #[test]
    fn discrepancy_matches_its_definition() {
        let pts = [
            Vec2::new(0.2, 0.7),
            Vec2::new(0.6, 0.1),
            Vec2::new(0.9, 0.5),
        ];
        let g = 2000;
        let mut acc = 0.0;
        for i in 0..g {
            for j in 0..g {
                let (a, b) = ((i as f64 + 0.5) / g as f64, (j as f64 + 0.5) / g as f64);
                let f = fraction_in_box(&pts, a as f32, b as f32);
                acc += (f - a * b).powi(2);
            }
        }
        let direct = (acc / (g * g) as f64).sqrt();
        let warnock = l2_star_discrepancy(&pts);
        assert!((direct - warnock).abs() < 1e-3, "{direct} vs {warnock}");
    }

    /// A centred n×n lattice: its periodogram is N on the multiples of n in both coordinates
    /// and 0 elsewhere, and its L2-star discrepancy is `√(1/(18n²) + 7/(288n⁴))` (Warnock's sum
    /// factorises over the axes: with `A = 1/3 + 1/(24n²)` and `B = 1/3 + 1/(6n²)`,
    /// `D² = 1/9 − 2A² + B²`).
    #[test]
    fn a_lattice_has_its_closed_form_spectrum_and_discrepancy() {
        for n in [4u32, 8] {
            let pts: Vec<Vec2> = (0..n * n)
                .map(|i| {
                    let (x, y) = (i % n, i / n);
                    Vec2::new((x as f32 + 0.5) / n as f32, (y as f32 + 0.5) / n as f32)
                })
                .collect();
            let m = 20;
            let p = periodogram(std::slice::from_ref(&pts), m);
            let side = (2 * m + 1) as i32;
            for (k, &v) in p.iter().enumerate() {
                let (kx, ky) = (k as i32 % side - m as i32, k as i32 / side - m as i32);
                let on = kx % n as i32 == 0 && ky % n as i32 == 0;
                let want = if on { (n * n) as f64 } else { 0.0 };
                assert!(
                    (v - want).abs() < 1e-6 * (n * n) as f64,
                    "k ({kx}, {ky}): {v}"
                );
            }
            let n4 = (n as f64).powi(4);
            let want = (1.0 / (18.0 * (n * n) as f64) + 7.0 / (288.0 * n4)).sqrt();
            let got = l2_star_discrepancy(&pts);
            assert!((got - want).abs() < 1e-6, "n {n}: {got} vs {want}");
        }
    }

    /// Independent points: a flat spectrum (every `E[P(k)] = 1`; the mean over 32 frequencies
    /// per axis and 16 sets averages about 50,000 values of unit variance, so it lies within
    /// ±0.05 of 1, over ten standard deviations), and `E[D₂*²] = 5/(36N)` (the mean of N·D²·36/5
    /// over 64 sets lies within ±25 %: each set's value has a relative spread below 1, so the
    /// mean's is below 1/8, and 25% is two of those). Stratified points: the power at the
    /// lowest frequencies, `|k| ≤ 3` on a 16×16 grid, is below 0.15 (jittered theory
    /// `1 − sinc²(k_x/16) sinc²(k_y/16)`: 0.06 averaged there), against about 1 for independent
    /// points. Checked over three seeds.
    #[test]
    fn independent_spectra_are_flat_and_stratified_ones_vanish_at_low_frequency() {
        use crate::render::{independent, stratified};
        let pixel = UVec2::new(3, 5);
        for seed in [0u64, 1000, 77_777] {
            let sets = |f: &dyn Fn(u64) -> Vec<Vec2>, m: u64| -> Vec<Vec<Vec2>> {
                (0..m).map(|r| f(seed + r)).collect()
            };
            let ind = sets(&|s| draw_points(&independent, s, 256, pixel, 0), 16);
            let spec = radial_spectrum(&periodogram(&ind, 32), 32);
            let mean = spec.iter().map(|p| p.1).sum::<f64>() / spec.len() as f64;
            assert!(
                (mean - 1.0).abs() < 0.05,
                "independent spectrum mean {mean}"
            );
            let low = spec.iter().take(3).map(|p| p.1).sum::<f64>() / 3.0;
            assert!(low > 0.6, "independent power at |k| ≤ 3: {low}");
            let strat = sets(&|s| draw_points(&stratified, s, 256, pixel, 0), 16);
            let spec = radial_spectrum(&periodogram(&strat, 32), 32);
            let low = spec.iter().take(3).map(|p| p.1).sum::<f64>() / 3.0;
            assert!(low < 0.15, "stratified power at |k| ≤ 3: {low}");
            for n in [16u32, 256] {
                let many = sets(&|s| draw_points(&independent, s, n, pixel, 0), 64);
                let ratio = many
                    .iter()
                    .map(|p| l2_star_discrepancy(p).powi(2) * n as f64 * 36.0 / 5.0)
                    .sum::<f64>()
                    / 64.0;
                assert!((ratio - 1.0).abs() < 0.25, "N {n}: N·D²·36/5 = {ratio}");
            }
        }
    }

    /// The layout's names: the pixel first, then each bounce's light point and direction.
    #[test]
    fn dimension_names_follow_the_layout() {
        assert_eq!(dimension_index("pixel"), Some(0));
        assert_eq!(dimension_index("light-1"), Some(2));
        assert_eq!(dimension_index("direction-1"), Some(4));
        assert_eq!(dimension_index("light-2"), Some(7));
        assert_eq!(dimension_index("nothing"), None);
        assert!(dimension_names(2)
            .iter()
            .all(|n| dimension_index(n).is_some()));
    }
}
