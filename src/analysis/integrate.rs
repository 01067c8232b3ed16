//! Known-answer integrals, estimated with the samplers renders use, against the formulas.
//!
//! The estimator `Ĩ = (1/N) Σ g(uᵢ)`, `g = f(x(u))/p(x(u))`, with `u` a sampler's points in the
//! pixel's dimensions ([`crate::analysis::points::draw_points`]; the 1D curve takes a 1D
//! dimension's) and `x(u)` the identity on the unit interval or square, or a warp onto the
//! hemisphere (`p` its pdf per solid angle). Over `R` independent repetitions (seeds) the mean
//! of `Ĩ` and its variance are measured, each with its standard error (the variance's from the
//! fourth moment, [`variance_se`]: heavy-tailed estimates widen it beyond the chi-square law),
//! beside what the lecture's formulas predict ([`predicted_variance`]):
//!
//! - independent points: `Var[Ĩ] = σ²{g}/N`, with `σ²{g} = ∫ f²/p − I²` in closed form (zero
//!   when `p ∝ f`: the cosine integrand under cosine directions, the lobe under its own pdf);
//! - jittered points (one uniform point in each of N strata: N intervals in 1D, the a×b cells
//!   of the sampler's grid in 2D): `Var[Ĩ] = (1/N²) Σᵢ σ²ᵢ`, `σ²ᵢ` the variance of `g` over
//!   stratum `i` under `p` restricted to it, computed exactly per stratum ([`jittered_variance`]:
//!   in closed form for the curve, the smooth, cosine and lobe-under-uniform integrands; for the
//!   disk, whose edge cells hold a part of it, the area of the disk in each cell by adaptive
//!   quadrature of its chords, and for the lobe under cosine directions by adaptive cubature,
//!   each with the bound on its error it reports);
//! - multi-jittered (`stratified`) and Sobol points: the jittered formula as a reference, not a
//!   bound: their measured variance over it says what the Latin constraint (each coordinate
//!   alone stratified) and joint stratification buy, or cost, on that integrand.
//!
//! Covariance between two samples of one estimate (samples 0 and 1 of a pixel, across the
//! repetitions) shows statement 1 itself: about 0 for independent points, negative for a
//! stratified set.
//!
//! The integrands: `curve` = 0.25 + 12x(1 − x)² on [0, 1) (`I = 1.25`: the lecture's Figure 2);
//! `smooth` = sin(πx) sin(πy) on [0,1)² (`I = 4/π²`); `disk` = the indicator of the disk of
//! radius 0.4 at the square's centre (`I = 0.16π`); `cosine` = cosθ over the hemisphere
//! (`I = π`); `lobe` = cos²⁰θ over the hemisphere (`I = 2π/21`).

use crate::analysis::points::draw_points;
use crate::render::{independent, jittered, sobol, stratified, SamplerFactory};
use crate::sampler::{grid_shape, SamplerKind};
use crate::sampling::{
    cosine_hemisphere_pdf, phong_lobe_pdf, sample_cosine_hemisphere, sample_phong_lobe,
    sample_uniform_hemisphere, uniform_hemisphere_pdf,
};
use glam::{UVec2, Vec2};
use std::f64::consts::PI;

/// The lobe integrand's exponent.
pub const LOBE_EXPONENT: f64 = 20.0;

/// The curve's polynomial, lowest power first: `0.25 + 12x(1 − x)² = 0.25 + 12x − 24x² + 12x³`.
const CURVE: [f64; 4] = [0.25, 12.0, -24.0, 12.0];

/// A known-answer integrand.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Integrand {
    /// 0.25 + 12x(1 − x)² on the unit interval (the lecture's Figure 2).
    Curve,
    /// sin(πx) sin(πy) on the unit square.
    Smooth,
    /// The indicator of a disk of radius 0.4 in the unit square: an edge.
    Disk,
    /// cosθ over the hemisphere.
    Cosine,
    /// cos²⁰θ over the hemisphere (a Phong lobe about the normal).
    Lobe,
}

/// How the points become the integration variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Domain {
    /// The unit interval (`p = 1`), from a 1D dimension.
    Line,
    /// The unit square itself (`p = 1`).
    Square,
    /// Uniform directions on the hemisphere.
    Uniform,
    /// Cosine-distributed directions.
    Cosine,
    /// Directions by the lobe's own pdf.
    Phong,
}

/// `∫ₐᵇ Σ cₖ xᵏ dx` of a polynomial (lowest power first).
fn poly_integral(c: &[f64], a: f64, b: f64) -> f64 {
    c.iter()
        .enumerate()
        .map(|(k, &ck)| ck * (b.powi(k as i32 + 1) - a.powi(k as i32 + 1)) / (k as f64 + 1.0))
        .sum()
}

/// The square of a polynomial.
fn poly_square(c: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; 2 * c.len() - 1];
    for (i, a) in c.iter().enumerate() {
        for (j, b) in c.iter().enumerate() {
            out[i + j] += a * b;
        }
    }
    out
}

impl Integrand {
    /// Its exact value.
    pub fn exact(self) -> f64 {
        match self {
            Integrand::Curve => poly_integral(&CURVE, 0.0, 1.0),
            Integrand::Smooth => 4.0 / (PI * PI),
            Integrand::Disk => PI * 0.16,
            Integrand::Cosine => PI,
            Integrand::Lobe => 2.0 * PI / (LOBE_EXPONENT + 1.0),
        }
    }

    /// The domains it is estimated over.
    pub fn domains(self) -> &'static [Domain] {
        match self {
            Integrand::Curve => &[Domain::Line],
            Integrand::Smooth | Integrand::Disk => &[Domain::Square],
            Integrand::Cosine => &[Domain::Uniform, Domain::Cosine],
            Integrand::Lobe => &[Domain::Uniform, Domain::Cosine, Domain::Phong],
        }
    }

    /// `σ²{g} = ∫ f²/p − I²` for one sample over `domain`, in closed form.
    pub fn sample_variance(self, domain: Domain) -> f64 {
        let i2 = self.exact().powi(2);
        let n = LOBE_EXPONENT;
        let second = match (self, domain) {
            (Integrand::Curve, _) => poly_integral(&poly_square(&CURVE), 0.0, 1.0),
            (Integrand::Smooth, _) => 0.25,
            (Integrand::Disk, _) => self.exact(),
            // ∫ cos² / (1/2π) dω = 2π · 2π/3; ∫ cos²/(cos/π) dω = π · π
            (Integrand::Cosine, Domain::Uniform) => 4.0 * PI * PI / 3.0,
            (Integrand::Cosine, _) => PI * PI,
            (Integrand::Lobe, Domain::Uniform) => 4.0 * PI * PI / (2.0 * n + 1.0),
            (Integrand::Lobe, Domain::Cosine) => PI * PI / n,
            (Integrand::Lobe, _) => i2,
        };
        (second - i2).max(0.0)
    }

    /// Whether `p ∝ f` over `domain`: `g` is constant, its variance zero (what is measured is
    /// `f32` rounding).
    pub fn constant(self, domain: Domain) -> bool {
        matches!(
            (self, domain),
            (Integrand::Cosine, Domain::Cosine) | (Integrand::Lobe, Domain::Phong)
        )
    }

    /// `g(u) = f(x(u))/p(x(u))` for a point `u` of the unit square (the curve reads `u.x`).
    pub fn g(self, domain: Domain, u: Vec2) -> f64 {
        let (x, y) = (u.x as f64, u.y as f64);
        match (self, domain) {
            (Integrand::Curve, _) => CURVE.iter().rev().fold(0.0, |acc, c| acc * x + c),
            (Integrand::Smooth, _) => (PI * x).sin() * (PI * y).sin(),
            (Integrand::Disk, _) => {
                let r2 = (x - 0.5).powi(2) + (y - 0.5).powi(2);
                if r2 < 0.16 {
                    1.0
                } else {
                    0.0
                }
            }
            (f, d) => {
                let (w, pdf) = match d {
                    Domain::Uniform => (sample_uniform_hemisphere(u), uniform_hemisphere_pdf()),
                    Domain::Cosine => {
                        let w = sample_cosine_hemisphere(u);
                        (w, cosine_hemisphere_pdf(w.z))
                    }
                    _ => {
                        let w = sample_phong_lobe(LOBE_EXPONENT as f32, u);
                        (w, phong_lobe_pdf(LOBE_EXPONENT as f32, w.z))
                    }
                };
                let c = (w.z as f64).max(0.0);
                let value = match f {
                    Integrand::Cosine => c,
                    _ => c.powf(LOBE_EXPONENT),
                };
                if pdf > 0.0 {
                    value / pdf as f64
                } else {
                    0.0
                }
            }
        }
    }
}

/// What a formula predicts for `Var[Ĩ]`: its value, the bound on its numerical error, whether
/// it is the variance of the sampler it is shown for (an equality) or a reference, and its name.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prediction {
    /// The predicted `Var[Ĩ]`.
    pub value: f64,
    /// A bound on its numerical error (quadrature; 0 for closed forms).
    pub error: f64,
    /// Whether it is the variance of the sampler it is asked for (else a reference).
    pub exact: bool,
    /// The formula's name.
    pub formula: &'static str,
}

/// What the formulas predict for `Var[Ĩ]` with `n` points of `kind`: `σ²/N` for independent
/// points and `(1/N²) Σ σ²ᵢ` for jittered ones (equalities); the latter as a reference for
/// multi-jittered and Sobol points.
pub fn predicted_variance(f: Integrand, domain: Domain, kind: SamplerKind, n: u32) -> Prediction {
    match kind {
        SamplerKind::Independent => Prediction {
            value: f.sample_variance(domain) / n as f64,
            error: 0.0,
            exact: true,
            formula: "sigma2/N",
        },
        _ => {
            let (value, error) = jittered_variance(f, domain, n);
            Prediction {
                value,
                error,
                exact: kind == SamplerKind::Jittered,
                formula: "(1/N^2) sum sigma_i^2",
            }
        }
    }
}

/// The jittered formula `(1/N²) Σᵢ σ²ᵢ` over the strata of `n` points (N intervals for the
/// curve; the a×b cells of [`grid_shape`] for the 2D domains, a columns along `u.x`), and the
/// bound on its numerical error.
pub fn jittered_variance(f: Integrand, domain: Domain, n: u32) -> (f64, f64) {
    let (a, b) = match domain {
        Domain::Line => (n, 1),
        _ => grid_shape(n),
    };
    let (mut sum, mut err) = (0.0, 0.0);
    for i in 0..a {
        for j in 0..b {
            let x = (i as f64 / a as f64, (i + 1) as f64 / a as f64);
            let y = (j as f64 / b as f64, (j + 1) as f64 / b as f64);
            let ([m1, m2], e) = cell_moments(f, domain, x, y);
            sum += (m2 - m1 * m1).max(0.0);
            err += e * (1.0 + 2.0 * m1.abs());
        }
    }
    let n2 = n as f64 * n as f64;
    (sum / n2, err / n2)
}

/// The mean of `g` and of `g²` over the cell `x × y` of the unit square (uniform on it: `p`
/// restricted to the cell), and a bound on the error of each.
fn cell_moments(f: Integrand, domain: Domain, x: (f64, f64), y: (f64, f64)) -> ([f64; 2], f64) {
    let ((x0, x1), (y0, y1)) = (x, y);
    let (dx, dy) = (x1 - x0, y1 - y0);
    // sin(πt) and sin²(πt) over [t0, t1], each divided by the length
    let s = |t0: f64, t1: f64| ((PI * t0).cos() - (PI * t1).cos()) / (PI * (t1 - t0));
    let q = |t0: f64, t1: f64| {
        0.5 - ((2.0 * PI * t1).sin() - (2.0 * PI * t0).sin()) / (4.0 * PI * (t1 - t0))
    };
    let n = LOBE_EXPONENT;
    match (f, domain) {
        (Integrand::Curve, _) => {
            let m1 = poly_integral(&CURVE, x0, x1) / dx;
            let m2 = poly_integral(&poly_square(&CURVE), x0, x1) / dx;
            ([m1, m2], 0.0)
        }
        (Integrand::Smooth, _) => ([s(x0, x1) * s(y0, y1), q(x0, x1) * q(y0, y1)], 0.0),
        (Integrand::Disk, _) => {
            let (area, e) = disk_area_in(x, y);
            let frac = area / (dx * dy);
            ([frac, frac], e / (dx * dy))
        }
        // the uniform warp's cosθ is u.x: g = 2π u.x, and the lobe's 2π u.x²⁰
        (Integrand::Cosine, Domain::Uniform) => {
            let m1 = PI * (x0 + x1);
            let m2 = 4.0 * PI * PI * (x0 * x0 + x0 * x1 + x1 * x1) / 3.0;
            ([m1, m2], 0.0)
        }
        (Integrand::Lobe, Domain::Uniform) => {
            let p = |k: f64| (x1.powf(k + 1.0) - x0.powf(k + 1.0)) / ((k + 1.0) * dx);
            ([2.0 * PI * p(n), 4.0 * PI * PI * p(2.0 * n)], 0.0)
        }
        (Integrand::Lobe, Domain::Cosine) => lobe_under_cosine(x, y),
        // p ∝ f: g is the integral itself
        _ => ([f.exact(), f.exact() * f.exact()], 0.0),
    }
}

/// The area of the disk of radius 0.4 at (0.5, 0.5) inside the cell `x × y`: the integral over
/// `x` of the length of its chord inside `y`, by adaptive Simpson to 1e-14 per cell (the chord
/// is continuous, with kinks where it meets the cell's edges); the area and its error bound.
fn disk_area_in((x0, x1): (f64, f64), (y0, y1): (f64, f64)) -> (f64, f64) {
    let (c, r) = (0.5, 0.4);
    let chord = |x: f64| {
        let h2 = r * r - (x - c) * (x - c);
        if h2 <= 0.0 {
            return 0.0;
        }
        let h = h2.sqrt();
        ((c + h).min(y1) - (c - h).max(y0)).max(0.0)
    };
    let (a, b) = (x0.max(c - r), x1.min(c + r));
    if a >= b {
        return (0.0, 0.0);
    }
    adaptive_simpson(&chord, a, b, 1e-14, 40)
}

/// `∫ₐᵇ f` by adaptive Simpson (Richardson-corrected), to `tol`; the value and the bound on its
/// error (the sum of the accepted pieces' |S₂ − S₁|/15).
fn adaptive_simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64, tol: f64, depth: u32) -> (f64, f64) {
    fn simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64) -> f64 {
        (b - a) / 6.0 * (f(a) + 4.0 * f(0.5 * (a + b)) + f(b))
    }
    fn go(f: &dyn Fn(f64) -> f64, a: f64, b: f64, whole: f64, tol: f64, depth: u32) -> (f64, f64) {
        let m = 0.5 * (a + b);
        let (l, r) = (simpson(f, a, m), simpson(f, m, b));
        let diff = l + r - whole;
        if depth == 0 || diff.abs() <= 15.0 * tol {
            return (l + r + diff / 15.0, diff.abs() / 15.0);
        }
        let (lv, le) = go(f, a, m, l, 0.5 * tol, depth - 1);
        let (rv, re) = go(f, m, b, r, 0.5 * tol, depth - 1);
        (lv + rv, le + re)
    }
    go(f, a, b, simpson(f, a, b), tol, depth)
}

/// The moments of the lobe under cosine directions over a cell: the concentric map takes `u` to
/// a disk point of radius `ρ = max(|2u.x − 1|, |2u.y − 1|)`, so `cosθ = √(1 − ρ²)` and
/// `g = π cos¹⁹θ`; the cell integrals by adaptive cubature (a 4-point Gauss–Legendre rule per
/// axis, each piece accepted when it agrees with its four quarters to 1e-13 of the cell: `ρ`
/// has kinks along the diagonals).
fn lobe_under_cosine(x: (f64, f64), y: (f64, f64)) -> ([f64; 2], f64) {
    let g = |ux: f64, uy: f64| {
        let rho = (2.0 * ux - 1.0).abs().max((2.0 * uy - 1.0).abs());
        let z2 = (1.0 - rho * rho).max(0.0);
        PI * z2.powf(0.5 * (LOBE_EXPONENT - 1.0))
    };
    let area = (x.1 - x.0) * (y.1 - y.0);
    let ([i1, i2], e) = cubature(&g, x, y, 1e-13 * area, 14);
    ([i1 / area, i2 / area], e / area)
}

/// `∫∫ g` and `∫∫ g²` over `x × y` by adaptive tensor Gauss–Legendre (4 points per axis),
/// to `tol`; the two integrals and the bound on their error.
fn cubature(
    g: &dyn Fn(f64, f64) -> f64,
    x: (f64, f64),
    y: (f64, f64),
    tol: f64,
    depth: u32,
) -> ([f64; 2], f64) {
    const NODES: [f64; 4] = [
        -0.861_136_311_594_052_6,
        -0.339_981_043_584_856_3,
        0.339_981_043_584_856_3,
        0.861_136_311_594_052_6,
    ];
    const WEIGHTS: [f64; 4] = [
        0.347_854_845_137_453_9,
        0.652_145_154_862_546_1,
        0.652_145_154_862_546_1,
        0.347_854_845_137_453_9,
    ];
    let rule = |x: (f64, f64), y: (f64, f64)| {
        let (hx, hy) = (0.5 * (x.1 - x.0), 0.5 * (y.1 - y.0));
        let (cx, cy) = (0.5 * (x.0 + x.1), 0.5 * (y.0 + y.1));
        let mut out = [0.0; 2];
        for (a, wa) in NODES.iter().zip(WEIGHTS) {
            for (b, wb) in NODES.iter().zip(WEIGHTS) {
                let v = g(cx + hx * a, cy + hy * b);
                out[0] += wa * wb * v;
                out[1] += wa * wb * v * v;
            }
        }
        [out[0] * hx * hy, out[1] * hx * hy]
    };
    let whole = rule(x, y);
    let (mx, my) = (0.5 * (x.0 + x.1), 0.5 * (y.0 + y.1));
    let quarters = [
        ((x.0, mx), (y.0, my)),
        ((mx, x.1), (y.0, my)),
        ((x.0, mx), (my, y.1)),
        ((mx, x.1), (my, y.1)),
    ];
    let parts: Vec<[f64; 2]> = quarters.iter().map(|&(qx, qy)| rule(qx, qy)).collect();
    let split = [
        parts.iter().map(|p| p[0]).sum::<f64>(),
        parts.iter().map(|p| p[1]).sum::<f64>(),
    ];
    let diff = (split[0] - whole[0]).abs().max((split[1] - whole[1]).abs());
    if depth == 0 || diff <= tol {
        return (split, diff);
    }
    let mut out = ([0.0; 2], 0.0);
    for (qx, qy) in quarters {
        let (v, e) = cubature(g, qx, qy, 0.25 * tol, depth - 1);
        out.0[0] += v[0];
        out.0[1] += v[1];
        out.1 += e;
    }
    out
}

/// One estimate `Ĩ` per repetition, and the first two samples' `g` of each (for covariances),
/// with the built-in sampler `kind`.
pub fn estimates(
    f: Integrand,
    domain: Domain,
    kind: SamplerKind,
    n: u32,
    runs: (u64, u32),
) -> Vec<(f64, f64, f64)> {
    match kind {
        SamplerKind::Independent => estimates_with(&independent, f, domain, n, runs),
        SamplerKind::Jittered => estimates_with(&jittered, f, domain, n, runs),
        SamplerKind::Stratified => estimates_with(&stratified, f, domain, n, runs),
        SamplerKind::Sobol => estimates_with(&sobol, f, domain, n, runs),
    }
}

/// [`estimates`] with any sampler: `repetitions` sets of `n` points of the pixel's dimensions
/// (the curve: of the first bounce's 1D light-choice dimension), seeds spread from `seed`.
pub fn estimates_with<F: SamplerFactory>(
    factory: &F,
    f: Integrand,
    domain: Domain,
    n: u32,
    (seed, repetitions): (u64, u32),
) -> Vec<(f64, f64, f64)> {
    (0..repetitions as u64)
        .map(|r| {
            let s = seed.wrapping_add(r.wrapping_mul(0x9e37_79b9));
            let dim = if domain == Domain::Line { LINE_DIM } else { 0 };
            let pts = draw_points(factory, s, n, UVec2::new(11, 5), dim);
            let gs: Vec<f64> = pts.iter().map(|&u| f.g(domain, u)).collect();
            let mean = gs.iter().sum::<f64>() / n as f64;
            (mean, gs[0], *gs.get(1).unwrap_or(&gs[0]))
        })
        .collect()
}

/// The layout dimension the curve's 1D points come from: the first bounce's light choice.
pub const LINE_DIM: usize = 1;

/// The standard error of the sample variance of `xs`, from their fourth central moment:
/// `Var(s²) ≈ (m₄ − s⁴ (R − 3)/(R − 1))/R`. Heavy tails (a narrow lobe sampled uniformly, an
/// indicator) widen it well beyond the chi-square law's `s²√(2/(R − 1))`, which holds for
/// normal values only.
pub fn variance_se(xs: &[f64]) -> f64 {
    let r = xs.len() as f64;
    let (m, v, _) = mean_var(xs);
    let m4 = xs.iter().map(|x| (x - m).powi(4)).sum::<f64>() / r;
    ((m4 - v * v * (r - 3.0) / (r - 1.0)).max(0.0) / r).sqrt()
}

/// The mean, sample variance and the 99% half-width of the mean of `xs`.
pub fn mean_var(xs: &[f64]) -> (f64, f64, f64) {
    let n = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / n;
    let v = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (m, v, 2.576 * (v / n).sqrt())
}

/// The covariance of pairs `(a, b)` and the 99% half-width of its estimate (the spread of the
/// products of deviations over √R).
pub fn covariance(pairs: &[(f64, f64)]) -> (f64, f64) {
    let n = pairs.len() as f64;
    let (ma, mb) = (
        pairs.iter().map(|p| p.0).sum::<f64>() / n,
        pairs.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let prods: Vec<f64> = pairs.iter().map(|p| (p.0 - ma) * (p.1 - mb)).collect();
    let (c, v, _) = mean_var(&prods);
    (c * n / (n - 1.0), 2.576 * (v / n).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed forms against a fine midpoint rule in `u` (their own definition).
    #[test]
    fn closed_forms_match_quadrature() {
        let q = 600;
        for f in [
            Integrand::Curve,
            Integrand::Smooth,
            Integrand::Disk,
            Integrand::Cosine,
            Integrand::Lobe,
        ] {
            for &d in f.domains() {
                let (mut s, mut s2) = (0.0, 0.0);
                for k in 0..q * q {
                    let u = Vec2::new(
                        ((k % q) as f32 + 0.5) / q as f32,
                        ((k / q) as f32 + 0.5) / q as f32,
                    );
                    let g = f.g(d, u);
                    s += g;
                    s2 += g * g;
                }
                let m = (q * q) as f64;
                let (mean, var) = (s / m, s2 / m - (s / m).powi(2));
                assert!((mean / f.exact() - 1.0).abs() < 2e-3, "{f:?} {d:?}: {mean}");
                let want = f.sample_variance(d);
                assert!(
                    (var - want).abs() < 5e-3 * (want + f.exact().powi(2)),
                    "{f:?} {d:?}: σ² {var} vs {want}"
                );
            }
        }
    }

    /// The per-stratum moments (closed forms, chord quadrature, cubature) against a fine midpoint
    /// rule in each stratum of a 4×4 grid (N = 16), and each against its own stated error.
    #[test]
    fn jittered_formula_matches_a_fine_rule_per_stratum() {
        for f in [
            Integrand::Curve,
            Integrand::Smooth,
            Integrand::Disk,
            Integrand::Cosine,
            Integrand::Lobe,
        ] {
            for &d in f.domains() {
                let (a, b) = if d == Domain::Line { (16, 1) } else { (4, 4) };
                let q = 400;
                let mut sum = 0.0;
                for i in 0..a {
                    for j in 0..b {
                        let (mut s1, mut s2) = (0.0, 0.0);
                        for k in 0..q * q {
                            let u = Vec2::new(
                                (i as f32 + ((k % q) as f32 + 0.5) / q as f32) / a as f32,
                                (j as f32 + ((k / q) as f32 + 0.5) / q as f32) / b as f32,
                            );
                            let g = f.g(d, u);
                            s1 += g;
                            s2 += g * g;
                        }
                        let m = (q * q) as f64;
                        sum += (s2 / m - (s1 / m).powi(2)).max(0.0);
                    }
                }
                let want = sum / 256.0;
                let (got, err) = jittered_variance(f, d, 16);
                let scale = f.exact().powi(2) / 256.0;
                assert!(err <= 1e-8 * got, "{f:?} {d:?}: error bound {err} of {got}");
                assert!(
                    (got - want).abs() <= 2e-3 * (want + 1e-3 * scale),
                    "{f:?} {d:?}: {got} against the fine rule's {want}"
                );
            }
        }
    }
}
