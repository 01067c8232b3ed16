//! Known-answer integrals, estimated with the samplers renders use, against the formulas.
//!
//! The estimator `Ĩ = (1/N) Σ g(uᵢ)`, `g = f(x(u))/p(x(u))`, with `u` a sampler's 2D points in the
//! pixel's dimensions ([`crate::analysis::points::draw_points`]) and `x(u)` the identity on the
//! unit square or a warp onto the hemisphere (`p` its pdf per solid angle). Over `R` independent
//! repetitions (seeds) the mean of `Ĩ` and its variance are measured, each with its standard
//! error (the variance's from the fourth moment, [`variance_se`]: heavy-tailed estimates widen
//! it beyond the chi-square law), beside what the formulas predict:
//!
//! - independent points: `Var[Ĩ] = σ²{g}/N`, with `σ²{g} = ∫ f²/p − I²` in closed form (zero
//!   when `p ∝ f`: the cosine integrand under cosine directions, the lobe under its own pdf);
//! - stratified points: the jittered formula `(1/N²) Σᵢ σᵢ²` over the `a × b` cells of the
//!   sampler's grid, each `σᵢ²` the variance of `g` over cell `i` by a 16×16 midpoint rule. vrpt's
//!   2D strata are multi-jittered (each coordinate alone is stratified too), which correlates the
//!   cells negatively: the formula is then an upper bound, printed as such;
//! - Sobol points: no closed form.
//!
//! Covariance between two samples of one estimate (samples 0 and 1 of a pixel, across the
//! repetitions) shows statement 1 itself: about 0 for independent points, negative for a
//! stratified set.
//!
//! The integrands: `smooth` = sin(πx) sin(πy) on [0,1)² (`I = 4/π²`); `disk` = the indicator of
//! the disk of radius 0.4 at the square's centre (`I = 0.16π`); `cosine` = cosθ over the
//! hemisphere (`I = π`); `lobe` = cos²⁰θ over the hemisphere (`I = 2π/21`).

use crate::analysis::points::draw_points;
use crate::render::{independent, sobol, stratified, SamplerFactory};
use crate::sampler::{grid_shape, SamplerKind};
use crate::sampling::{
    cosine_hemisphere_pdf, phong_lobe_pdf, sample_cosine_hemisphere, sample_phong_lobe,
    sample_uniform_hemisphere, uniform_hemisphere_pdf,
};
use glam::{UVec2, Vec2};
use std::f64::consts::PI;

/// The lobe integrand's exponent.
pub const LOBE_EXPONENT: f64 = 20.0;

/// A known-answer integrand.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Integrand {
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
    /// The unit square itself (`p = 1`).
    Square,
    /// Uniform directions on the hemisphere.
    Uniform,
    /// Cosine-distributed directions.
    Cosine,
    /// Directions by the lobe's own pdf.
    Phong,
}

impl Integrand {
    /// Its exact value.
    pub fn exact(self) -> f64 {
        match self {
            Integrand::Smooth => 4.0 / (PI * PI),
            Integrand::Disk => PI * 0.16,
            Integrand::Cosine => PI,
            Integrand::Lobe => 2.0 * PI / (LOBE_EXPONENT + 1.0),
        }
    }

    /// The domains it is estimated over.
    pub fn domains(self) -> &'static [Domain] {
        match self {
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

    /// `g(u) = f(x(u))/p(x(u))` for a point `u` of the unit square.
    pub fn g(self, domain: Domain, u: Vec2) -> f64 {
        let (x, y) = (u.x as f64, u.y as f64);
        match (self, domain) {
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

/// What the formulas predict for `Var[Ĩ]` with `n` points of `kind` (`None`: no closed form),
/// and whether it is an equality or a bound.
pub fn predicted_variance(
    f: Integrand,
    domain: Domain,
    kind: SamplerKind,
    n: u32,
) -> Option<(f64, &'static str)> {
    match kind {
        SamplerKind::Independent => Some((f.sample_variance(domain) / n as f64, "sigma2/N")),
        SamplerKind::Stratified => {
            let (a, b) = grid_shape(n);
            let q = 16;
            let mut sum = 0.0;
            for i in 0..a {
                for j in 0..b {
                    let (mut s, mut s2) = (0.0, 0.0);
                    for k in 0..q * q {
                        let u = Vec2::new(
                            (i as f32 + ((k % q) as f32 + 0.5) / q as f32) / a as f32,
                            (j as f32 + ((k / q) as f32 + 0.5) / q as f32) / b as f32,
                        );
                        let g = f.g(domain, u);
                        s += g;
                        s2 += g * g;
                    }
                    let m = (q * q) as f64;
                    sum += (s2 / m - (s / m).powi(2)).max(0.0);
                }
            }
            Some((sum / (n as f64 * n as f64), "jittered bound"))
        }
        SamplerKind::Sobol => None,
    }
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
        SamplerKind::Stratified => estimates_with(&stratified, f, domain, n, runs),
        SamplerKind::Sobol => estimates_with(&sobol, f, domain, n, runs),
    }
}

/// [`estimates`] with any sampler: `repetitions` sets of `n` points of the pixel's dimensions,
/// seeds spread from `seed`.
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
            let pts = draw_points(factory, s, n, UVec2::new(11, 5), 0);
            let gs: Vec<f64> = pts.iter().map(|&u| f.g(domain, u)).collect();
            let mean = gs.iter().sum::<f64>() / n as f64;
            (mean, gs[0], *gs.get(1).unwrap_or(&gs[0]))
        })
        .collect()
}

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
}
