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

use glam::{DVec3, Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, PI};

const INV_2PI: f32 = 0.5 * FRAC_1_PI;

/// Uniform point on the unit disk by Shirley & Chiu's concentric map (low distortion, so strata
/// of the square stay compact on the disk).
#[inline]
pub fn sample_concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y))
    };
    let (s, c) = theta.sin_cos();
    Vec2::new(r * c, r * s)
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
    let d = sample_concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
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
const UNITS: u32 = 1 << UNIT_BITS;

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

/// The angle between unit vectors, accurate for nearly parallel and nearly opposite ones.
#[inline]
fn angle_between(a: DVec3, b: DVec3) -> f64 {
    if a.dot(b) < 0.0 {
        std::f64::consts::PI - 2.0 * ((a + b).length() / 2.0).min(1.0).asin()
    } else {
        2.0 * ((b - a).length() / 2.0).min(1.0).asin()
    }
}

/// `v` without its component along the unit `w`.
#[inline]
fn gram_schmidt(v: DVec3, w: DVec3) -> DVec3 {
    v - v.dot(w) * w
}

/// The spherical triangle that a triangle `v` subtends from a point `p`: its vertex directions,
/// the angle at `a` and its area (= its solid angle, `α + β + γ − π`). Sampling is Arvo's: `u₀`
/// picks the area of the sub-triangle `(a, b, c′)` with `c′` on the arc `ac`, `u₁` the point on
/// the arc `b c′` so the density is uniform; `u = (·, 0)` maps to `b`, `(0, 1)` to `a`, `(1, 1)`
/// to `c` (the corners of a [`sample_bilinear`] warp: weights `[b, b, a, c]`).
#[derive(Clone, Copy, Debug)]
pub struct SphericalTriangle {
    a: DVec3,
    b: DVec3,
    c: DVec3,
    alpha: f64,
    area: f64,
}

impl SphericalTriangle {
    /// `None` when `p` lies on the triangle's plane or a vertex: no solid angle to sample.
    pub fn new(v: [Vec3; 3], p: Vec3) -> Option<SphericalTriangle> {
        let p = p.as_dvec3();
        let a = (v[0].as_dvec3() - p).try_normalize()?;
        let b = (v[1].as_dvec3() - p).try_normalize()?;
        let c = (v[2].as_dvec3() - p).try_normalize()?;
        let n_ab = a.cross(b).try_normalize()?;
        let n_bc = b.cross(c).try_normalize()?;
        let n_ca = c.cross(a).try_normalize()?;
        let alpha = angle_between(n_ab, -n_ca);
        let beta = angle_between(n_bc, -n_ab);
        let gamma = angle_between(n_ca, -n_bc);
        let area = alpha + beta + gamma - std::f64::consts::PI;
        (area > 0.0).then_some(SphericalTriangle {
            a,
            b,
            c,
            alpha,
            area,
        })
    }

    /// Its solid angle.
    pub fn area(&self) -> f64 {
        self.area
    }

    /// The vertex directions `[a, b, c]` (unit).
    pub fn vertices(&self) -> [DVec3; 3] {
        [self.a, self.b, self.c]
    }

    /// A direction uniform in the spherical triangle (unit, world space).
    pub fn sample(&self, u: Vec2) -> Vec3 {
        let (a, b, c) = (self.a, self.b, self.c);
        let (u0, u1) = (u.x as f64, u.y as f64);
        let pi = std::f64::consts::PI;
        // the sub-triangle (a, b, c′) of area A′ = u₀ A: its angle sum A′ + π
        let ap_pi = pi + u0 * self.area;
        let (sin_alpha, cos_alpha) = self.alpha.sin_cos();
        let (sin_ap, cos_ap) = ap_pi.sin_cos();
        let sin_phi = sin_ap * cos_alpha - cos_ap * sin_alpha;
        let cos_phi = cos_ap * cos_alpha + sin_ap * sin_alpha;
        let k1 = cos_phi + cos_alpha;
        let k2 = sin_phi - sin_alpha * a.dot(b);
        let cos_bp = ((k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha)
            / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha))
            .clamp(-1.0, 1.0);
        let sin_bp = (1.0 - cos_bp * cos_bp).max(0.0).sqrt();
        let cp = cos_bp * a + sin_bp * gram_schmidt(c, a).normalize_or_zero();
        let cos_theta = 1.0 - u1 * (1.0 - cp.dot(b));
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let w = cos_theta * b + sin_theta * gram_schmidt(cp, b).normalize_or_zero();
        w.normalize_or_zero().as_vec3()
    }

    /// The `u` for which [`SphericalTriangle::sample`] returns the direction `w` (in it).
    pub fn invert(&self, w: Vec3) -> Vec2 {
        let (a, b, c) = (self.a, self.b, self.c);
        let w = w.as_dvec3().normalize_or_zero();
        // c′: where the great circle through b and w meets the arc ac
        let mut cp = b.cross(w).cross(c.cross(a)).normalize_or_zero();
        if cp.dot(a + c) < 0.0 {
            cp = -cp;
        }
        let u0 = if a.dot(cp) > 1.0 - 1e-15 {
            0.0
        } else {
            // the area of (a, b, c′) by Van Oosterom & Strackee
            let ap = 2.0
                * a.dot(b.cross(cp))
                    .atan2(1.0 + a.dot(b) + b.dot(cp) + cp.dot(a));
            ap.abs() / self.area
        };
        let den = 1.0 - cp.dot(b);
        let u1 = if den > 0.0 {
            (1.0 - w.dot(b)) / den
        } else {
            0.0
        };
        Vec2::new(u0.clamp(0.0, 1.0) as f32, u1.clamp(0.0, 1.0) as f32)
    }
}

/// The spherical rectangle that a rectangle (corner `s`, perpendicular edges `ex`, `ey`)
/// subtends from a point: Ureña, Fajardo & King's parametrization. In the frame of the
/// rectangle (x along `ex`, y along `ey`, z toward the point's side flipped so the rectangle
/// lies at `z₀ < 0`), `u₀` picks x by the solid angle of the sub-rectangle left of it and `u₁`
/// picks y uniformly in solid angle given x. `u = (0, 0)` maps to the corner `s`, `(1, 0)` to
/// `s + ex`, `(0, 1)` to `s + ey` (the corners of a [`sample_bilinear`] warp).
#[derive(Clone, Copy, Debug)]
pub struct SphericalRectangle {
    origin: DVec3,
    x_axis: DVec3,
    y_axis: DVec3,
    z_axis: DVec3,
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    z0: f64,
    b0: f64,
    b1: f64,
    /// `(cos k, sin k)`, `k = 2π − γ₂ − γ₃`.
    k: (f64, f64),
    area: f64,
}

/// What Ureña's sampling needs of the rectangle `[x0, x1] × [y0, y1]` at `z = z0 < 0` seen from
/// the origin: its solid angle `Ω = Σγᵢ − 2π` (the internal angles' sum), `b0`, `b1` (the z of
/// the normals of the planes through the edges at y0 and y1) and `(cos k, sin k)` for
/// `k = 2π − γ₂ − γ₃`. In this frame the normals of the planes through the origin and each edge
/// have closed forms, `n₀ ∝ (0, z₀, −y₀)`, `n₁ ∝ (−z₀, 0, x₁)`, `n₂ ∝ (0, −z₀, y₁)`,
/// `n₃ ∝ (z₀, 0, −x₀)`, and so do the cosines and sines of the internal angles `γᵢ` between
/// `−nᵢ` and `nᵢ₊₁`: e.g. `cos γ₀ = x₁y₀/(L_{y0} L_{x1})`, `sin γ₀ = |z₀| |c₁₀|/(L_{y0} L_{x1})`
/// with `L_{y0} = √(z₀² + y₀²)` and `c₁₀` the corner `(x₁, y₀, z₀)`. `Ω` is then the argument of
/// `Π (cos γᵢ + i sin γᵢ)` in (0, 2π]: one arctangent, no arccosines.
fn rectangle_angles(
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    z0: f64,
) -> Option<(f64, f64, f64, (f64, f64))> {
    if z0 == 0.0 || x1 <= x0 || y1 <= y0 {
        return None;
    }
    let z2 = z0 * z0;
    let (lx0, lx1) = ((z2 + x0 * x0).sqrt(), (z2 + x1 * x1).sqrt());
    let (ly0, ly1) = ((z2 + y0 * y0).sqrt(), (z2 + y1 * y1).sqrt());
    let corner = |x: f64, y: f64| (x * x + y * y + z2).sqrt();
    let z = z0.abs();
    // (cos γᵢ, sin γᵢ) at the corners (x1, y0), (x1, y1), (x0, y1), (x0, y0)
    let g = [
        (x1 * y0, z * corner(x1, y0), ly0 * lx1),
        (-x1 * y1, z * corner(x1, y1), lx1 * ly1),
        (x0 * y1, z * corner(x0, y1), ly1 * lx0),
        (-x0 * y0, z * corner(x0, y0), lx0 * ly0),
    ]
    .map(|(c, s, l)| (c / l, s / l));
    let mul = |a: (f64, f64), b: (f64, f64)| (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
    let g23 = mul(g[2], g[3]);
    let all = mul(mul(g[0], g[1]), g23);
    let tau = 2.0 * std::f64::consts::PI;
    let mut omega = all.1.atan2(all.0);
    if omega <= 0.0 {
        omega += tau;
    }
    // e^{ik} = e^{−i(γ₂+γ₃)}
    Some((omega, -y0 / ly0, y1 / ly1, (g23.0, -g23.1)))
}

impl SphericalRectangle {
    /// `None` when `p` lies on the rectangle's plane (no solid angle).
    pub fn new(s: Vec3, ex: Vec3, ey: Vec3, p: Vec3) -> Option<SphericalRectangle> {
        let (s, ex, ey, p) = (s.as_dvec3(), ex.as_dvec3(), ey.as_dvec3(), p.as_dvec3());
        let (exl, eyl) = (ex.length(), ey.length());
        let x_axis = ex / exl;
        let y_axis = ey / eyl;
        let mut z_axis = x_axis.cross(y_axis);
        let d = s - p;
        let (x0, y0) = (d.dot(x_axis), d.dot(y_axis));
        let mut z0 = d.dot(z_axis);
        if z0 > 0.0 {
            z0 = -z0;
            z_axis = -z_axis;
        }
        if z0 == 0.0 {
            return None;
        }
        let (x1, y1) = (x0 + exl, y0 + eyl);
        let (area, b0, b1, k) = rectangle_angles(x0, y0, x1, y1, z0)?;
        (area > 0.0).then_some(SphericalRectangle {
            origin: p,
            x_axis,
            y_axis,
            z_axis,
            x0,
            y0,
            x1,
            y1,
            z0,
            b0,
            b1,
            k,
            area,
        })
    }

    /// Its solid angle.
    pub fn area(&self) -> f64 {
        self.area
    }

    /// The point on the rectangle (world space) in the direction sampled uniformly in solid angle.
    pub fn sample(&self, u: Vec2) -> Vec3 {
        let (u0, u1) = (u.x as f64, u.y as f64);
        let (z0, b0, b1) = (self.z0, self.b0, self.b1);
        // au = u₀Ω + k, by the angle sum of (u₀Ω) and k
        let (sin_a, cos_a) = (u0 * self.area).sin_cos();
        let (cos_k, sin_k) = self.k;
        let (sin_au, cos_au) = (sin_a * cos_k + cos_a * sin_k, cos_a * cos_k - sin_a * sin_k);
        let fu = (cos_au * b0 - b1) / sin_au;
        let cu = (1.0 / (fu * fu + b0 * b0).sqrt())
            .copysign(fu)
            .clamp(-1.0 + 1e-15, 1.0 - 1e-15);
        let xu = (-(cu * z0) / (1.0 - cu * cu).max(0.0).sqrt()).clamp(self.x0, self.x1);
        let d = (xu * xu + z0 * z0).sqrt();
        let h0 = self.y0 / (d * d + self.y0 * self.y0).sqrt();
        let h1 = self.y1 / (d * d + self.y1 * self.y1).sqrt();
        let hv = h0 + u1 * (h1 - h0);
        let yv = if hv * hv < 1.0 - 1e-12 {
            (hv * d / (1.0 - hv * hv).sqrt()).clamp(self.y0, self.y1)
        } else {
            self.y1
        };
        (self.origin + xu * self.x_axis + yv * self.y_axis + z0 * self.z_axis).as_vec3()
    }

    /// The `u` for which [`SphericalRectangle::sample`] returns the point `q` of the rectangle:
    /// `u₀` = the solid angle of the part of the rectangle left of `q` over the whole, `u₁` from
    /// `h = y/√(d² + y²)` linear between its values at the rectangle's two y edges.
    pub fn invert(&self, q: Vec3) -> Vec2 {
        let v = q.as_dvec3() - self.origin;
        let xu = v.dot(self.x_axis).clamp(self.x0, self.x1);
        let yv = v.dot(self.y_axis).clamp(self.y0, self.y1);
        let z0 = self.z0;
        let u0 = if xu <= self.x0 {
            0.0
        } else {
            rectangle_angles(self.x0, self.y0, xu, self.y1, z0).map_or(0.0, |a| a.0) / self.area
        };
        let d2 = xu * xu + z0 * z0;
        let h = |y: f64| y / (d2 + y * y).sqrt();
        let (h0, h1) = (h(self.y0), h(self.y1));
        let u1 = if h1 != h0 {
            (h(yv) - h0) / (h1 - h0)
        } else {
            0.0
        };
        Vec2::new(u0.clamp(0.0, 1.0) as f32, u1.clamp(0.0, 1.0) as f32)
    }
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

    /// Sampling then inverting gives back `u`; sampled directions hit the shape; a rectangle's
    /// solid angle is the sum of its two triangles'.
    #[test]
    fn spherical_warps_round_trip_and_stay_on_their_shape() {
        let v = [
            Vec3::new(-1.0, 0.2, -2.0),
            Vec3::new(1.5, -0.3, -2.5),
            Vec3::new(0.1, 1.2, -1.8),
        ];
        let (s, ex, ey) = (
            Vec3::new(-1.0, 2.0, -1.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 1.5),
        );
        for p in [
            Vec3::ZERO,
            Vec3::new(0.3, 1.9, -0.2),
            Vec3::new(5.0, -1.0, 3.0),
        ] {
            let tri = SphericalTriangle::new(v, p).unwrap();
            let rect = SphericalRectangle::new(s, ex, ey, p).unwrap();
            let halves = SphericalTriangle::new([s, s + ex, s + ex + ey], p)
                .unwrap()
                .area()
                + SphericalTriangle::new([s, s + ex + ey, s + ey], p)
                    .unwrap()
                    .area();
            assert!((rect.area() - halves).abs() < 1e-9 * halves, "{p}");
            let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
            for i in 1..16 {
                for j in 1..16 {
                    let u = Vec2::new(i as f32 / 16.0, j as f32 / 16.0);
                    let w = tri.sample(u);
                    let back = tri.invert(w);
                    assert!((back - u).abs().max_element() < 2e-4, "{p} {u} -> {back}");
                    // the ray p + t w meets the triangle's plane inside the triangle
                    let t = n.dot(v[0] - p) / n.dot(w);
                    let q = p + w * t;
                    let (a, b) = ((v[1] - v[0]).cross(q - v[0]), (v[2] - v[1]).cross(q - v[1]));
                    let c = (v[0] - v[2]).cross(q - v[2]);
                    assert!(t > 0.0 && a.dot(n) > -1e-4 && b.dot(n) > -1e-4 && c.dot(n) > -1e-4);
                    let q = rect.sample(u);
                    let (x, y) = (
                        (q - s).dot(ex) / ex.length_squared(),
                        (q - s).dot(ey) / ey.length_squared(),
                    );
                    assert!((-1e-5..=1.0 + 1e-5).contains(&x) && (-1e-5..=1.0 + 1e-5).contains(&y));
                    assert!((q - s).dot(ex.cross(ey)).abs() < 1e-4);
                    let back = rect.invert(q);
                    assert!((back - u).abs().max_element() < 2e-4, "{p} {u} -> {back}");
                    let wts = [0.3, 1.0, 0.05, 2.0];
                    let b = sample_bilinear(u, wts);
                    assert!((invert_bilinear(b, wts) - u).abs().max_element() < 1e-5);
                }
            }
        }
        // the corners of u: (x, 0) → b, (0, 1) → a, (1, 1) → c
        let tri = SphericalTriangle::new(v, Vec3::ZERO).unwrap();
        let [a, b, c] = tri.vertices().map(|d| d.as_vec3());
        assert!((tri.sample(Vec2::new(0.3, 0.0)) - b).length() < 1e-5);
        assert!((tri.sample(Vec2::new(0.0, 1.0)) - a).length() < 1e-5);
        assert!((tri.sample(Vec2::new(1.0, 1.0)) - c).length() < 1e-5);
        assert!(SphericalTriangle::new(v, v[0]).is_none());
    }
}
