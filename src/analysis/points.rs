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
//! - **Discrepancy against N**: the root mean square of `D₂*` over realisations at
//!   `N = 16, 32, …`, and the slope of `log D` against `log N` (independent points `−½`;
//!   jittered ones `−¾`, from `E[D₂*²] = O(N^{-3/2})`; Sobol points near `−1`).
//!
//! A set can also be shown *after a warp* ([`PointWarp`]), the way a render uses it: onto the
//! hemisphere (uniform, cosine-weighted, a Phong lobe), drawn by Lambert's equal-area
//! projection `ρ = √(1 − cosθ)` at azimuth `φ` (equal areas of the hemisphere stay equal in
//! the unit disk, so the density seen is the warp's pdf per solid angle), or onto a triangle
//! by area. And the *dependent pair* `(x, x + ½ mod 1)` of a set's first coordinates: the
//! lecture's counter-example, whose box fraction is far from `ab` ([`dependent_pair`]).

use crate::render::{SamplePass, SamplerFactory};
use crate::sampler::layout::{Dim, BOUNCE_DIMS, CAMERA_DIMS};
use crate::sampler::Sampler;
use crate::sampling::{
    sample_cosine_hemisphere, sample_phong_lobe, sample_uniform_hemisphere, sample_uniform_triangle,
};
use glam::{UVec2, Vec2, Vec3};

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

/// The root mean square of [`l2_star_discrepancy`] over `sets`.
pub fn rms_discrepancy(sets: &[Vec<Vec2>]) -> f64 {
    let m = sets.len().max(1) as f64;
    (sets
        .iter()
        .map(|s| l2_star_discrepancy(s).powi(2))
        .sum::<f64>()
        / m)
        .sqrt()
}

/// The set sizes of the discrepancy curve: `16, 32, …, 2048`.
pub const CURVE_SIZES: [u32; 8] = [16, 32, 64, 128, 256, 512, 1024, 2048];

/// The dependent pair of `points`: `(xᵢ, xᵢ + ½ mod 1)`. Its two coordinates are each uniform,
/// but jointly they lie on two segments, so the fraction in `[0,a)×[0,b)` is
/// `|[0,a) ∩ [½, ½ + b)|` (0 for `a ≤ ½`), not `ab`.
pub fn dependent_pair(points: &[Vec2]) -> Vec<Vec2> {
    points
        .iter()
        .map(|p| Vec2::new(p.x, (p.x + 0.5).fract()))
        .collect()
}

/// Where a point set is shown: the unit square as drawn, or after a warp a render applies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PointWarp {
    /// The unit square itself.
    Square,
    /// Uniform directions on the hemisphere (`sample_uniform_hemisphere`).
    Uniform,
    /// Cosine-weighted directions (`sample_cosine_hemisphere`).
    Cosine,
    /// A Phong lobe of this exponent about the pole (`sample_phong_lobe`).
    Phong(f32),
    /// Uniform by area on the triangle `(0,0), (1,0), (½, √3/2)` (`sample_uniform_triangle`).
    Triangle,
}

impl std::str::FromStr for PointWarp {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad =
            || format!("'{s}' is not a warp: square, uniform, cosine, phong:E (E > 0) or triangle");
        Ok(match s {
            "square" => PointWarp::Square,
            "uniform" => PointWarp::Uniform,
            "cosine" => PointWarp::Cosine,
            "triangle" => PointWarp::Triangle,
            _ => {
                let e: f32 = s
                    .strip_prefix("phong:")
                    .and_then(|e| e.parse().ok())
                    .ok_or_else(bad)?;
                if !(e > 0.0 && e <= 1e6) {
                    return Err(bad());
                }
                PointWarp::Phong(e)
            }
        })
    }
}

impl std::fmt::Display for PointWarp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PointWarp::Square => write!(f, "square"),
            PointWarp::Uniform => write!(f, "uniform"),
            PointWarp::Cosine => write!(f, "cosine"),
            PointWarp::Phong(e) => write!(f, "phong:{e}"),
            PointWarp::Triangle => write!(f, "triangle"),
        }
    }
}

impl PointWarp {
    /// The direction of a hemisphere warp (`None` for the square and the triangle).
    pub fn direction(self, u: Vec2) -> Option<Vec3> {
        match self {
            PointWarp::Uniform => Some(sample_uniform_hemisphere(u)),
            PointWarp::Cosine => Some(sample_cosine_hemisphere(u)),
            PointWarp::Phong(e) => Some(sample_phong_lobe(e, u)),
            PointWarp::Square | PointWarp::Triangle => None,
        }
    }

    /// Where `u` is drawn in the picture: itself on the square; the triangle's point; a
    /// direction's equal-area projection `√(1 − cosθ) (cosφ, sinφ)` in the unit disk.
    pub fn picture(self, u: Vec2) -> Vec2 {
        match self {
            PointWarp::Square => u,
            PointWarp::Triangle => {
                let b = sample_uniform_triangle(u);
                // b0·(0,0) + b1·(1,0) + (1 − b0 − b1)·(½, √3/2)
                let b2 = 1.0 - b.x - b.y;
                Vec2::new(b.y + 0.5 * b2, 0.866_025_4 * b2)
            }
            _ => {
                let d = self.direction(u).unwrap_or(Vec3::Z);
                let s = (d.x * d.x + d.y * d.y).sqrt();
                if s <= 0.0 {
                    return Vec2::ZERO;
                }
                Vec2::new(d.x, d.y) * ((1.0 - d.z).max(0.0).sqrt() / s)
            }
        }
    }

    /// The picture's extent `(x range, y range)`.
    pub fn extent(self) -> ((f32, f32), (f32, f32)) {
        match self {
            PointWarp::Square => ((0.0, 1.0), (0.0, 1.0)),
            PointWarp::Triangle => ((0.0, 1.0), (0.0, 0.9)),
            _ => ((-1.0, 1.0), (-1.0, 1.0)),
        }
    }
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

    /// The discrepancy curve's slopes over `N = 16 … 2048` ([`CURVE_SIZES`]), 16 sets each, for
    /// three seeds. Independent: `−½` within ±0.1 (`E[D²] = 5/(36N)` exactly; one set's `D²`
    /// has a relative spread below 1, so the rms over 16 sets has a log spread near
    /// ½·1/√16 = 0.125, and the fitted slope over eight sizes spanning ln 128 (Σ(x − x̄)² = 9.9)
    /// a standard error near 0.125/√9.9 = 0.04: ±0.1 is 2.5 of those, over three seeds. The
    /// spread is an upper bound; measured slopes are −0.49 to −0.51). Stratified: below −0.65
    /// (jittered theory −¾).
    #[test]
    fn discrepancy_falls_as_n_to_the_minus_half_for_independent_points_and_faster_stratified() {
        use crate::analysis::fit::log_log_slope;
        use crate::render::{independent, stratified};
        let pixel = UVec2::new(2, 9);
        for seed in [5u64, 500, 50_000] {
            let slope = |strat: bool| {
                let d: Vec<f64> = CURVE_SIZES
                    .iter()
                    .map(|&n| {
                        let sets: Vec<Vec<Vec2>> = (0..16)
                            .map(|r| {
                                if strat {
                                    draw_points(&stratified, seed + r, n, pixel, 0)
                                } else {
                                    draw_points(&independent, seed + r, n, pixel, 0)
                                }
                            })
                            .collect();
                        rms_discrepancy(&sets)
                    })
                    .collect();
                let ns: Vec<f64> = CURVE_SIZES.iter().map(|&n| n as f64).collect();
                log_log_slope(&ns, &d)
            };
            let (ind, strat) = (slope(false), slope(true));
            assert!(
                (ind + 0.5).abs() < 0.1,
                "seed {seed}: independent slope {ind}"
            );
            assert!(strat < -0.65, "seed {seed}: stratified slope {strat}");
        }
    }

    /// The dependent pair fails the box test for any set: in `[0,½)×[0,0.3)` it has no point (a
    /// point with `x < ½` has second coordinate `x + ½ ≥ ½`), while the independent set's
    /// fraction lies within 4 binomial standard deviations of `ab`; the pair's second
    /// coordinate alone is still uniform (within 4 standard deviations).
    #[test]
    fn the_dependent_pair_fails_the_box_test() {
        use crate::render::independent;
        for seed in [1u64, 2, 3] {
            let pts = draw_points(&independent, seed, 4096, UVec2::new(1, 1), 0);
            let (a, b) = (0.5f32, 0.3f32);
            let area = (a * b) as f64;
            let sd = (area * (1.0 - area) / 4096.0).sqrt();
            assert!((fraction_in_box(&pts, a, b) - area).abs() < 4.0 * sd);
            assert_eq!(fraction_in_box(&dependent_pair(&pts), a, b), 0.0);
            // each coordinate alone is still uniform
            let dep = dependent_pair(&pts);
            let below = dep.iter().filter(|p| p.y < b).count() as f64 / 4096.0;
            let sd = (b as f64 * (1.0 - b as f64) / 4096.0).sqrt();
            assert!((below - b as f64).abs() < 4.0 * sd, "{below}");
        }
    }

    /// The pictures of the warps keep area: uniform hemisphere directions put a fraction `r²` of
    /// the points within radius `r` of the disk's centre (`ρ² = 1 − cosθ`, and `cosθ` is
    /// uniform), cosine ones `1 − (1 − r²)²` (`P(cosθ > c) = 1 − c²`), and points uniform on the
    /// triangle put `¾` below half its height; all within 4 binomial standard deviations for
    /// 8192 points, and every point inside its domain.
    #[test]
    fn the_warp_pictures_keep_area() {
        use crate::render::independent;
        let pts = draw_points(&independent, 11, 8192, UVec2::new(4, 4), 0);
        let n = pts.len() as f64;
        let check = |w: PointWarp, inside: &dyn Fn(Vec2) -> bool, want: f64| {
            let got = pts.iter().filter(|&&u| inside(w.picture(u))).count() as f64 / n;
            let sd = (want * (1.0 - want) / n).sqrt();
            assert!((got - want).abs() < 4.0 * sd, "{w}: {got} vs {want}");
        };
        for r in [0.3f32, 0.6, 0.9] {
            let r2 = (r * r) as f64;
            check(PointWarp::Uniform, &|q| q.length() < r, r2);
            check(
                PointWarp::Cosine,
                &|q| q.length() < r,
                1.0 - (1.0 - r2).powi(2),
            );
        }
        let h = 0.866_025_4f32;
        check(PointWarp::Triangle, &|q| q.y < 0.5 * h, 0.75);
        for w in [
            PointWarp::Uniform,
            PointWarp::Cosine,
            PointWarp::Phong(30.0),
        ] {
            assert!(
                pts.iter().all(|&u| w.picture(u).length() <= 1.0 + 1e-5),
                "{w}"
            );
        }
        assert!(pts.iter().all(|&u| {
            let q = PointWarp::Triangle.picture(u);
            q.y >= -1e-6 && q.y <= h * (1.0 - (2.0 * q.x - 1.0).abs()) + 1e-5
        }));
        assert_eq!("phong:20".parse::<PointWarp>(), Ok(PointWarp::Phong(20.0)));
        assert!("phong:-1".parse::<PointWarp>().is_err());
        assert!("sphere".parse::<PointWarp>().is_err());
        assert_eq!(PointWarp::Phong(20.0).to_string(), "phong:20");
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
