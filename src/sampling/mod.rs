//! Warps: maps from uniform points `u ∈ [0,1)^2` to directions, each beside its pdf.
//!
//! Conventions: directions are unit vectors in a local frame whose z axis is the pole of the
//! distribution (the shading normal, or the mirror direction for the Phong lobe); every pdf is
//! per unit solid angle. Each warp is a measure-preserving-in-strata map (the concentric disk map
//! for the cosine hemisphere), so a stratified `u` stays stratified on the sphere.
//!
//! | warp | pdf |
//! |---|---|
//! | [`sample_uniform_hemisphere`] | `1/(2π)` |
//! | [`sample_cosine_hemisphere`] | `cosθ/π` |
//! | [`sample_phong_lobe`] | `(n+1)/(2π) cosⁿα` |
//! | [`sample_uniform_triangle`] | `1/A` per unit area |
//!
//! The triangle warp returns barycentric coordinates; it is the low-distortion map of Heitz
//! 2019 ("A low-distortion map between triangle and square"), which keeps strata of the square
//! compact on the triangle.
//!
//! [`Discrete`] chooses an index with a probability proportional to a weight, and its pmf is
//! exact for the values drawn: the probabilities are whole multiples of 2⁻²⁴, the resolution of
//! a sampler's `u` (see its doc).
//!
//! **Points on lights by solid angle.** [`SphericalTriangle`] (Arvo 1995, "Stratified sampling
//! of spherical triangles", as in pbrt-v4) and [`SphericalRectangle`] (Ureña, Fajardo & King
//! 2013, "An area-preserving parametrization for spherical rectangles") map `u ∈ [0,1)²` to a
//! direction uniform in the solid angle a triangle or a rectangle subtends from a point (pdf
//! `1/Ω`), each with its exact inverse (direction → `u`), which the pdf of the cosine warp needs.
//! They compute in f64: the angle sums lose digits in f32 for small or nearly flat domains.
//! [`sample_bilinear`]/[`bilinear_pdf`] warp `u` by a bilinear function of four corner weights
//! (pbrt-v4's approximation of the receiver's cosine over the domain, "projected solid angle").

use crate::math::sin_cos_quarter;
use glam::{Vec2, Vec3};

mod spherical;
pub use spherical::{SphericalRectangle, SphericalTriangle};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4, PI};

const INV_2PI: f32 = 0.5 * FRAC_1_PI;

/// Uniform point on the unit disk by Shirley & Chiu's concentric map (low distortion, so strata
/// of the square stay compact on the disk).
#[inline]
pub fn sample_concentric_disk(u: Vec2) -> Vec2 {
    concentric(u).0
}

/// [`sample_concentric_disk`]'s point and its radius, the larger of `|2u − 1|`'s coordinates:
/// the radius is known before the angle's division and polynomial, so what depends on it alone
/// (the height of a cosine-weighted direction) does not wait on them.
#[inline(always)]
fn concentric(u: Vec2) -> (Vec2, f32) {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return (Vec2::ZERO, 0.0);
    }
    // the angle θ = φ in the wedges about ±x, θ = π/2 − φ in those about ±y, |φ| ≤ π/4:
    // there cos θ = sin φ and sin θ = cos φ
    if o.x.abs() > o.y.abs() {
        let (s, c) = sin_cos_quarter(FRAC_PI_4 * (o.y / o.x));
        (Vec2::new(o.x * c, o.x * s), o.x.abs())
    } else {
        let (s, c) = sin_cos_quarter(FRAC_PI_4 * (o.x / o.y));
        (Vec2::new(o.y * s, o.y * c), o.y.abs())
    }
}

/// Uniform direction on the upper hemisphere (z ≥ 0): `z = u₀`, `φ = 2π u₁`.
#[inline]
pub fn sample_uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = (2.0 * PI * u.y).sin_cos();
    Vec3::new(r * c, r * s, z)
}

/// The pdf of [`sample_uniform_hemisphere`]: `1/(2π)` per steradian.
#[inline]
pub fn uniform_hemisphere_pdf() -> f32 {
    INV_2PI
}

/// Cosine-weighted direction on the upper hemisphere (Malley's method: a concentric-disk point
/// lifted to the hemisphere).
#[inline]
pub fn sample_cosine_hemisphere(u: Vec2) -> Vec3 {
    let (d, r) = concentric(u);
    let z = (1.0 - r * r).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// The pdf of [`sample_cosine_hemisphere`]: `cosθ/π` (zero below the horizon).
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Direction about the z axis with density `∝ cosⁿα` on the whole sphere of directions with
/// `cosα > 0`: `cosα = u₀^(1/(n+1))`, `φ = 2π u₁`. `1 − cosα` is computed with `exp_m1` so very
/// sharp lobes (n = 10⁴ and more) keep their shape in f32.
#[inline]
pub fn sample_phong_lobe(exponent: f32, u: Vec2) -> Vec3 {
    // 1 - u0^(1/(n+1)) = -expm1(ln(u0)/(n+1)); u0 = 0 maps to the horizon.
    let one_minus_cos = if u.x > 0.0 {
        -(u.x.ln() / (exponent + 1.0)).exp_m1()
    } else {
        1.0
    };
    let cos_a = 1.0 - one_minus_cos;
    let sin_a = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0).sqrt();
    let (s, c) = (2.0 * PI * u.y).sin_cos();
    Vec3::new(sin_a * c, sin_a * s, cos_a)
}

/// The pdf of [`sample_phong_lobe`]: `(n+1)/(2π) cosⁿα` for `cosα > 0`, else 0.
#[inline]
pub fn phong_lobe_pdf(exponent: f32, cos_alpha: f32) -> f32 {
    if cos_alpha <= 0.0 {
        return 0.0;
    }
    (exponent + 1.0) * INV_2PI * cos_alpha.powf(exponent)
}

/// A point uniform by area on a triangle, as barycentrics `(b0, b1)` of its first two vertices
/// (`b2 = 1 − b0 − b1`): Heitz's low-distortion map, which folds the square onto the triangle
/// along its diagonal and shears each half, so nearby `u` give nearby points.
#[inline]
pub fn sample_uniform_triangle(u: Vec2) -> Vec2 {
    if u.x < u.y {
        let b0 = 0.5 * u.x;
        Vec2::new(b0, u.y - b0)
    } else {
        let b1 = 0.5 * u.y;
        Vec2::new(u.x - b1, b1)
    }
}

/// The pdf of [`sample_uniform_triangle`] per unit area of a triangle of area `area`: `1/A`.
#[inline]
pub fn uniform_triangle_pdf(area: f32) -> f32 {
    1.0 / area
}

/// Bits of resolution of a 1D sample `u ∈ [0, 1)`: every sampler's values are (at least) this
/// fine, so `⌊u·2²⁴⌋` is uniform on `0..2²⁴`.
pub const UNIT_BITS: u32 = 24;
/// The units of `u`'s resolution, `2^UNIT_BITS`, that an exact choice splits.
pub const UNITS: u32 = 1 << UNIT_BITS;

/// A discrete distribution over `0..n` with probabilities approximately proportional to given
/// weights, whose pmf is **exactly** the probability with which [`Discrete::sample`] returns
/// each index. Each index of positive weight gets a whole number `wᵢ ≥ 1` of the 2²⁴ units of
/// `[0, 1)` (largest-remainder rounding of `2²⁴·weightᵢ/Σweight`), so `pmf(i) = wᵢ/2²⁴` (exact
/// in f32) and `sample(u)` returns `i` for `⌊u·2²⁴⌋` in its `wᵢ` units. A CDF of f32 or f64
/// reals does not have that property: with 10⁶ entries of pmf ≈ 10⁻⁶ the 2⁻²⁴ steps of `u`
/// (and of an f32 CDF near 1) make the actual frequencies differ from the pmf by several per
/// cent, a bias wherever the pmf divides. The price: a probability is rounded by at most one
/// unit, 6·10⁻⁸, and at most 2²⁴ indices can have a positive weight.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Discrete {
    /// `cdf[i]` = units of indices `0..=i`; the last is 2²⁴ (or 0 when every weight is 0).
    cdf: Vec<u32>,
}

impl Discrete {
    /// The distribution of `weights` (finite, non-negative). All zero (or empty): an empty
    /// distribution, whose [`Discrete::sample`] is `None`. Err when more than 2²⁴ weights are
    /// positive.
    pub fn new(weights: &[f64]) -> Result<Discrete, String> {
        let total: f64 = weights.iter().filter(|w| **w > 0.0).sum();
        let positive = weights.iter().filter(|w| **w > 0.0).count();
        if positive as u64 > UNITS as u64 {
            return Err(format!(
                "{positive} entries of positive weight: at most 2^{UNIT_BITS} can be chosen exactly"
            ));
        }
        if positive == 0 || !total.is_finite() {
            return Ok(Discrete {
                cdf: vec![0; weights.len()],
            });
        }
        let ideal: Vec<f64> = weights
            .iter()
            .map(|&w| {
                if w > 0.0 {
                    w / total * UNITS as f64
                } else {
                    0.0
                }
            })
            .collect();
        let mut units: Vec<u32> = ideal
            .iter()
            .map(|&x| {
                if x > 0.0 {
                    (x.floor() as u32).max(1)
                } else {
                    0
                }
            })
            .collect();
        let sum: u64 = units.iter().map(|&u| u as u64).sum();
        if sum < UNITS as u64 {
            // the units left go to the largest remainders (at most one each: the floors lost
            // less than one unit per index)
            let mut order: Vec<usize> = (0..units.len()).filter(|&i| ideal[i] > 0.0).collect();
            order.sort_by(|&a, &b| {
                let (ra, rb) = (ideal[a] - units[a] as f64, ideal[b] - units[b] as f64);
                rb.total_cmp(&ra).then(a.cmp(&b))
            });
            for &i in order.iter().cycle().take((UNITS as u64 - sum) as usize) {
                units[i] += 1;
            }
        } else if sum > UNITS as u64 {
            // indices raised to one unit took more than there are: take them back, one at a
            // time, from the largest (there are enough: at most 2²⁴ indices hold one each)
            let mut order: Vec<usize> = (0..units.len()).filter(|&i| units[i] > 1).collect();
            order.sort_by(|&a, &b| units[b].cmp(&units[a]).then(a.cmp(&b)));
            let mut excess = sum - UNITS as u64;
            while excess > 0 {
                for &i in &order {
                    if excess > 0 && units[i] > 1 {
                        units[i] -= 1;
                        excess -= 1;
                    }
                }
            }
        }
        let mut acc = 0u32;
        let cdf = units
            .iter()
            .map(|&u| {
                acc += u;
                acc
            })
            .collect();
        Ok(Discrete { cdf })
    }

    /// Number of indices.
    pub fn len(&self) -> usize {
        self.cdf.len()
    }

    /// True with no index.
    pub fn is_empty(&self) -> bool {
        self.cdf.is_empty()
    }

    /// True when some index can be chosen.
    pub fn any(&self) -> bool {
        self.cdf.last().is_some_and(|&c| c > 0)
    }

    /// The units of index `i` (its probability times 2²⁴).
    #[inline]
    pub fn units(&self, i: usize) -> u32 {
        self.cdf[i] - if i > 0 { self.cdf[i - 1] } else { 0 }
    }

    /// The probability that [`Discrete::sample`] returns `i`: `wᵢ/2²⁴`, exactly.
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.units(i) as f32 * (1.0 / UNITS as f32)
    }

    /// The index whose units hold `⌊u·2²⁴⌋` (u ∈ [0, 1)); `None` when nothing can be chosen.
    #[inline]
    pub fn sample(&self, u: f32) -> Option<usize> {
        if !self.any() {
            return None;
        }
        let k = ((u * UNITS as f32) as u32).min(UNITS - 1);
        // the first cumulative count above k; indices of zero units are passed over
        Some(self.cdf.partition_point(|&c| c <= k))
    }
}

/// The largest f32 below 1, where the warps clamp what must stay in `[0, 1)`.
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// `x ∈ [0, 1)` with density `∝ lerp(x, a, b)` (`a, b ≥ 0`, not both 0).
#[inline]
pub fn sample_linear(u: f32, a: f32, b: f32) -> f32 {
    if u == 0.0 && a == 0.0 {
        return 0.0;
    }
    let x = u * (a + b) / (a + (a * a + u * (b * b - a * a)).max(0.0).sqrt());
    x.min(ONE_MINUS_EPSILON)
}

/// The `u` for which [`sample_linear`] returns `x`: the CDF, `x(a(2 − x) + bx)/(a + b)`.
#[inline]
pub fn invert_linear(x: f32, a: f32, b: f32) -> f32 {
    x * (a * (2.0 - x) + b * x) / (a + b)
}

/// A point of `[0,1)²` with density `∝` the bilinear interpolation of the corner weights
/// `w = [w(0,0), w(1,0), w(0,1), w(1,1)]` (all > 0): y from its marginal, then x given y.
#[inline]
pub fn sample_bilinear(u: Vec2, w: [f32; 4]) -> Vec2 {
    let y = sample_linear(u.y, w[0] + w[1], w[2] + w[3]);
    let x = sample_linear(u.x, w[0] + (w[2] - w[0]) * y, w[1] + (w[3] - w[1]) * y);
    Vec2::new(x, y)
}

/// The density of [`sample_bilinear`] at `p` (0 outside `[0,1]²`).
#[inline]
pub fn bilinear_pdf(p: Vec2, w: [f32; 4]) -> f32 {
    if !(0.0..=1.0).contains(&p.x) || !(0.0..=1.0).contains(&p.y) {
        return 0.0;
    }
    let sum = w[0] + w[1] + w[2] + w[3];
    if sum == 0.0 {
        return 1.0;
    }
    4.0 * ((1.0 - p.x) * (1.0 - p.y) * w[0]
        + p.x * (1.0 - p.y) * w[1]
        + (1.0 - p.x) * p.y * w[2]
        + p.x * p.y * w[3])
        / sum
}

/// The `u` for which [`sample_bilinear`] returns `p`.
#[inline]
pub fn invert_bilinear(p: Vec2, w: [f32; 4]) -> Vec2 {
    Vec2::new(
        invert_linear(p.x, w[0] + (w[2] - w[0]) * p.y, w[1] + (w[3] - w[1]) * p.y),
        invert_linear(p.y, w[0] + w[1], w[2] + w[3]),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every one of the 2²⁴ values of `⌊u·2²⁴⌋` chooses an index, and each index is chosen for
    /// exactly `pmf·2²⁴` of them; weights of 0 are never chosen, tiny positive ones are.
    #[test]
    fn discrete_pmf_is_the_frequency_of_every_value_of_u() {
        let weights = [0.0, 3.0, 1e-12, 0.0, 7.5, 1.0, 0.0];
        let d = Discrete::new(&weights).unwrap();
        let mut counts = [0u32; 7];
        for k in 0..UNITS {
            counts[d.sample(k as f32 / UNITS as f32).unwrap()] += 1;
        }
        for (i, &c) in counts.iter().enumerate() {
            assert_eq!(c, d.units(i), "index {i}");
            assert_eq!(d.pmf(i) as f64 * UNITS as f64, c as f64);
            let ideal = weights[i] / 11.5 * UNITS as f64;
            assert!(
                (c as f64 - ideal).abs() <= 1.0,
                "index {i}: {c} against {ideal}"
            );
        }
        assert_eq!(counts[0] + counts[3] + counts[6], 0);
        assert_eq!(counts[2], 1);
        assert!(!Discrete::new(&[0.0, 0.0]).unwrap().any());
        assert_eq!(Discrete::new(&[0.0, 0.0]).unwrap().sample(0.5), None);
    }

    #[test]
    fn warps_give_unit_vectors_in_their_domain() {
        for i in 0..64 {
            for j in 0..64 {
                let u = Vec2::new(i as f32 / 64.0, j as f32 / 64.0);
                for w in [
                    sample_uniform_hemisphere(u),
                    sample_cosine_hemisphere(u),
                    sample_phong_lobe(1.0, u),
                    sample_phong_lobe(1e4, u),
                ] {
                    assert!((w.length() - 1.0).abs() < 1e-4, "{w}");
                    assert!(w.z >= 0.0);
                }
                assert!(sample_concentric_disk(u).length() <= 1.0 + 1e-6);
            }
        }
    }

    /// A cosine-weighted direction lifts its concentric disk point: the same `x`, `y`, and a
    /// height from the point's radius that makes it a unit vector to within 4 ulps (the
    /// radius is taken from `2u − 1`, not from the point: they differ by the sine and cosine's
    /// roundings, 2 ulps each), on a 512² grid of `u` with its far edges.
    #[test]
    fn cosine_directions_lift_their_disk_points() {
        let n = 512;
        for i in 0..=n {
            for j in 0..=n {
                let u = Vec2::new(i as f32, j as f32) / n as f32;
                let u = u.min(Vec2::splat(ONE_MINUS_EPSILON));
                let (w, d) = (sample_cosine_hemisphere(u), sample_concentric_disk(u));
                assert_eq!((w.x, w.y), (d.x, d.y));
                assert!(w.z >= 0.0);
                let len = (w.as_dvec3()).length();
                assert!(
                    (len - 1.0).abs() < 4.0 * f32::EPSILON as f64,
                    "{u}: {w} {len}"
                );
            }
        }
    }
}
