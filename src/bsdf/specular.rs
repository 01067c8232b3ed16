//! Smooth (delta) lobes: a perfect mirror and a smooth dielectric (glass, water), which the MTL
//! asks for with `illum` 3–7 ([`crate::material`]). A delta lobe scatters into one or two
//! directions with probability mass, not density: its `f` is a Dirac delta, so it is never
//! evaluated for a given pair of directions. The path loop asks only whether a surface has one:
//! no light sample at its vertex (no light can be reached through it by a shadow ray), the
//! emission found after it counted with weight 1 (no other strategy could have found it),
//! Russian roulette and the guide skip it, and `--directions` applies to the Phong lobes only.
//! [`Specular::sample`] returns the direction and the *weight* `f·|cosθᵢ|/p` the throughput is
//! multiplied by.
//!
//! Conventions are the Phong BSDF's: the local shading frame, z the shading normal on the side
//! of `wo`, `wo` pointing away from the surface toward the viewer. A dielectric also needs the
//! side: `entering` says whether `wo` lies on the side the surface's normal (its winding) points
//! to, the outside, so the relative index of refraction is `η = Ni` entering and `1/Ni` leaving.
//!
//! - Mirror (`illum 3`): `wi = reflect(wo)`, weight `Ks`; `illum 5` weighs it by Schlick's
//!   Fresnel with `Ks` at normal incidence, `F = Ks + (1 − Ks)(1 − cosθ)⁵`.
//! - Dielectric (`illum 4, 6, 7`): the exact unpolarized Fresnel reflectance
//!   `F = (r_s² + r_p²)/2`, `r_s = (cosθᵢ − η cosθₜ)/(cosθᵢ + η cosθₜ)`,
//!   `r_p = (η cosθᵢ − cosθₜ)/(η cosθᵢ + cosθₜ)`, with `sin²θₜ = sin²θᵢ/η²` (total internal
//!   reflection, `F = 1`, where that reaches 1). Reflection is chosen with probability `F`
//!   (weight 1), refraction `wi = −wo/η + (cosθᵢ/η − cosθₜ) n` with probability `1 − F` (weight
//!   `Tf/η²`: radiance crossing into a denser medium is compressed into a smaller solid angle by
//!   η², the convention of pbrt-v4 and Mitsuba 3 for radiance transport; a ray that leaves again
//!   gets η² back, so a closed glass object in a white furnace stays white).

use glam::Vec3;

/// A delta lobe (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Specular {
    /// A perfect mirror of reflectance `reflectance`; with `schlick`, that is the reflectance at
    /// normal incidence of Schlick's Fresnel.
    Mirror { reflectance: Vec3, schlick: bool },
    /// A smooth dielectric boundary: index of refraction `ior` inside (1 outside), and a
    /// transmittance `transmittance` applied at every refraction.
    Dielectric { ior: f32, transmittance: Vec3 },
}

/// A sampled delta direction: the direction (local frame), the throughput weight
/// `f·|cosθᵢ|/p`, and whether it crosses the surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecularSample {
    pub wi: Vec3,
    pub weight: Vec3,
    pub transmitted: bool,
}

/// The Fresnel reflectance of unpolarized light at a smooth dielectric boundary, for a cosine
/// `cos_i ∈ [0, 1]` of the incident direction with the normal on its own side and the relative
/// index `eta = η_t/η_i`; also the cosine of the transmitted direction (0 under total internal
/// reflection, where the reflectance is 1).
#[inline]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> (f32, f32) {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    (0.5 * (rs * rs + rp * rp), cos_t)
}

/// Schlick's approximation of a conductor's Fresnel reflectance of normal reflectance `f0`.
#[inline]
pub fn fresnel_schlick(cos_i: f32, f0: Vec3) -> Vec3 {
    let m = (1.0 - cos_i.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3::ONE - f0) * m
}

impl Specular {
    /// Whether sampling reads its random number (a dielectric chooses between reflection and
    /// refraction; a mirror does not).
    #[inline]
    pub fn chooses(&self) -> bool {
        matches!(self, Specular::Dielectric { .. })
    }

    /// True when it scatters nothing (paths end on it).
    #[inline]
    pub fn is_black(&self) -> bool {
        match self {
            Specular::Mirror { reflectance, .. } => reflectance.max_element() <= 0.0,
            Specular::Dielectric { .. } => false,
        }
    }

    /// The direction scattered from `wo` (local frame, `wo.z > 0`), `entering` from the outside
    /// (module doc), the choice between reflection and refraction made by `u`. `None` when `wo`
    /// is not above the surface.
    #[inline]
    pub fn sample(&self, wo: Vec3, entering: bool, u: f32) -> Option<SpecularSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
        match *self {
            Specular::Mirror {
                reflectance,
                schlick,
            } => Some(SpecularSample {
                wi: mirror,
                weight: if schlick {
                    fresnel_schlick(wo.z, reflectance)
                } else {
                    reflectance
                },
                transmitted: false,
            }),
            Specular::Dielectric { ior, transmittance } => {
                let eta = if entering { ior } else { 1.0 / ior };
                let (f, cos_t) = fresnel_dielectric(wo.z, eta);
                if u < f {
                    return Some(SpecularSample {
                        wi: mirror,
                        weight: Vec3::ONE,
                        transmitted: false,
                    });
                }
                let wi = -wo / eta + Vec3::Z * (wo.z / eta - cos_t);
                Some(SpecularSample {
                    wi: wi.normalize(),
                    weight: transmittance / (eta * eta),
                    transmitted: true,
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fresnel at normal incidence is ((η − 1)/(η + 1))², the same from both sides; past the
    /// critical angle from inside it is 1; and the reflectance of the two sides agrees for a
    /// pair of directions related by Snell's law (reciprocity of the pair).
    #[test]
    fn fresnel_matches_the_closed_forms() {
        let eta = 1.5f32;
        let f0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
        assert!((fresnel_dielectric(1.0, eta).0 - f0).abs() < 1e-6);
        assert!((fresnel_dielectric(1.0, 1.0 / eta).0 - f0).abs() < 1e-6);
        let critical = (1.0 / eta).asin();
        assert_eq!(
            fresnel_dielectric((critical + 0.01).cos(), 1.0 / eta).0,
            1.0
        );
        for k in 1..50 {
            let cos_i = k as f32 / 50.0;
            let (f, cos_t) = fresnel_dielectric(cos_i, eta);
            let (back, cos_back) = fresnel_dielectric(cos_t, 1.0 / eta);
            assert!((f - back).abs() < 1e-5, "{cos_i}: {f} against {back}");
            assert!((cos_back - cos_i).abs() < 1e-5);
            assert!((0.0..=1.0).contains(&f));
        }
    }

    /// Refraction obeys Snell's law (η sinθₜ = sinθᵢ) and the plane of incidence, and a ray
    /// refracted in and back out comes back to where it started with weight 1 (η² in, 1/η² out).
    #[test]
    fn refraction_is_snell_and_round_trips() {
        let glass = Specular::Dielectric {
            ior: 1.5,
            transmittance: Vec3::ONE,
        };
        for k in 1..40 {
            let t = k as f32 / 40.0 * 1.5;
            let wo = Vec3::new(t.sin() * 0.6, t.sin() * 0.8, t.cos());
            let s = glass.sample(wo, true, 0.999).unwrap();
            assert!(s.transmitted && s.wi.z < 0.0);
            let sin_i = (1.0 - wo.z * wo.z).sqrt();
            let sin_t = (1.0 - s.wi.z * s.wi.z).sqrt();
            assert!((sin_i - 1.5 * sin_t).abs() < 1e-5, "{t}");
            assert!((s.wi.x * wo.y - s.wi.y * wo.x).abs() < 1e-6);
            // back out: seen from inside (the frame's z turned to the inside), the refracted
            // direction is the viewer's, and its refraction is the direction we came from
            let inside = Vec3::new(s.wi.x, s.wi.y, -s.wi.z);
            let back = glass.sample(inside, false, 0.999).unwrap();
            assert!(back.transmitted);
            assert!((Vec3::new(back.wi.x, back.wi.y, -back.wi.z) - wo).length() < 1e-5);
            assert!((back.weight * s.weight - Vec3::ONE).abs().max_element() < 1e-5);
        }
    }
}
