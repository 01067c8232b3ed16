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

use glam::{Vec2, Vec3};
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
