//! The modified Phong material (Lafortune & Willems 1994), energy conserving:
//!
//! `f(wo, wi) = kd/π + ks·(n+2)/(2π)·cosⁿα`, with `α` the angle between `wi` and the mirror
//! direction of `wo` (and `cosα` clamped at 0).
//!
//! Conventions: all directions are in the local shading frame (z = shading normal, flipped by the
//! caller to the side of `wo`); `wo` points away from the surface toward the viewer, `wi` away
//! from the surface toward the next vertex; `f` does NOT include the cosine (the integrator
//! multiplies by `cosθi`); pdfs are per unit solid angle. Random numbers come in as arguments.
//!
//! How the direction is chosen is the second axis of variance reduction ([`Directions`]):
//! - `uniform`: uniform hemisphere, `p = 1/(2π)`;
//! - `cosine`: `p = cosθ/π`, importance sampling of the diffuse term;
//! - `phong`: the diffuse lobe (cosine) with probability `P_d = avg(kd)/(avg(kd)+avg(ks))`, else
//!   the specular lobe `(n+1)/(2π) cosⁿα` about the mirror direction; the weight uses the
//!   mixture pdf `P_d cosθ/π + (1−P_d)(n+1)/(2π) cosⁿα` of both lobes (one-sample MIS with the
//!   balance heuristic). A specular direction that falls below the surface is a failed sample
//!   (`None`, zero contribution) and the mixture pdf is NOT renormalized over the hemisphere:
//!   the estimator `f cosθ / p · 1[wi above]` still has expectation `∫_{H+} f cosθ dω`, because
//!   `p` is the true density of the directions that are above — the lost mass only ever
//!   contributed zero. So it stays unbiased.

use crate::math::{average, reflect_local, Frame};
use crate::sampling::{
    cosine_hemisphere_pdf, phong_lobe_pdf, sample_cosine_hemisphere, sample_phong_lobe,
    sample_uniform_hemisphere, uniform_hemisphere_pdf,
};
use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

/// How bounce directions are chosen (the `--directions` flag).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Directions {
    /// Uniform on the hemisphere, p = 1/(2π): the naive baseline.
    Uniform,
    /// Cosine-weighted, p = cosθ/π: importance sampling of the diffuse term.
    Cosine,
    /// Diffuse or Phong lobe by their albedos, weighted by the mixture pdf.
    #[default]
    Phong,
}

impl Directions {
    /// The name used on the command line and in metadata.
    pub fn name(self) -> &'static str {
        match self {
            Directions::Uniform => "uniform",
            Directions::Cosine => "cosine",
            Directions::Phong => "phong",
        }
    }

    /// Parse the name written by [`Directions::name`].
    pub fn from_name(s: &str) -> Option<Self> {
        [Directions::Uniform, Directions::Cosine, Directions::Phong]
            .into_iter()
            .find(|k| k.name() == s)
    }
}

impl std::fmt::Display for Directions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Which lobe produced a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lobe {
    /// Uniform or cosine hemisphere sampling of the whole BRDF.
    Hemisphere,
    /// The diffuse lobe of the Phong mixture.
    Diffuse,
    /// The specular (Phong) lobe of the mixture.
    Glossy,
}

/// One sampled direction with everything the integrator needs.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// The sampled direction, local frame, `wi.z > 0`.
    pub wi: Vec3,
    /// `f(wo, wi)`, without the cosine.
    pub f: Vec3,
    /// The pdf of `wi` under the strategy used, per unit solid angle.
    pub pdf: f32,
    /// The lobe that was sampled.
    pub lobe: Lobe,
}

/// A modified Phong material with optional one-sided emission.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Diffuse reflectance.
    pub kd: Vec3,
    /// Specular reflectance.
    pub ks: Vec3,
    /// Phong exponent (MTL `Ns`).
    pub exponent: f32,
    /// Emitted radiance (MTL `Ke`), on the front side only.
    pub emission: Vec3,
    /// Probability of choosing the diffuse lobe in `phong` sampling.
    p_diffuse: f32,
}

impl Material {
    /// A material; where `kd + ks > 1` in a channel both are scaled down in that channel so the
    /// material conserves energy. The flag says whether that happened (the caller warns).
    pub fn new(name: &str, kd: Vec3, ks: Vec3, exponent: f32, emission: Vec3) -> (Self, bool) {
        let kd = kd.max(Vec3::ZERO);
        let ks = ks.max(Vec3::ZERO);
        let sum = kd + ks;
        let scale = Vec3::ONE / sum.max(Vec3::ONE);
        let scaled = sum.max_element() > 1.0;
        let (kd, ks) = (kd * scale, ks * scale);
        let (ad, as_) = (average(kd), average(ks));
        let p_diffuse = if ad + as_ > 0.0 { ad / (ad + as_) } else { 1.0 };
        let m = Material {
            name: name.to_string(),
            kd,
            ks,
            exponent: exponent.max(0.0),
            emission: emission.max(Vec3::ZERO),
            p_diffuse,
        };
        (m, scaled)
    }

    /// A grey diffuse material, the fallback for missing MTL data.
    pub fn default_grey(name: &str) -> Self {
        Material::new(name, Vec3::splat(0.5), Vec3::ZERO, 1.0, Vec3::ZERO).0
    }

    /// A diffuse material of reflectance `kd`.
    pub fn diffuse(name: &str, kd: Vec3) -> Self {
        Material::new(name, kd, Vec3::ZERO, 1.0, Vec3::ZERO).0
    }

    /// True when the material reflects nothing (paths end on it).
    #[inline]
    pub fn is_black(&self) -> bool {
        self.kd.max_element() <= 0.0 && self.ks.max_element() <= 0.0
    }

    /// True when the material emits.
    #[inline]
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }

    /// `cosα` between `wi` and the mirror direction of `wo`.
    #[inline]
    fn cos_alpha(wo: Vec3, wi: Vec3) -> f32 {
        reflect_local(wo).dot(wi)
    }

    /// `f(wo, wi)` (no cosine); zero unless both directions are above the surface.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        let mut f = self.kd * FRAC_1_PI;
        if self.ks.max_element() > 0.0 {
            let ca = Self::cos_alpha(wo, wi);
            if ca > 0.0 {
                f += self.ks * ((self.exponent + 2.0) * (0.5 * FRAC_1_PI) * ca.powf(self.exponent));
            }
        }
        f
    }

    /// The pdf with which [`Material::sample`] returns `wi`, per unit solid angle.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, directions: Directions) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 || self.is_black() {
            return 0.0;
        }
        match directions {
            Directions::Uniform => uniform_hemisphere_pdf(),
            Directions::Cosine => cosine_hemisphere_pdf(wi.z),
            Directions::Phong => self.mixture_pdf(wo, wi),
        }
    }

    #[inline]
    fn mixture_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let pd = self.p_diffuse;
        let mut p = pd * cosine_hemisphere_pdf(wi.z);
        if pd < 1.0 {
            p += (1.0 - pd) * phong_lobe_pdf(self.exponent, Self::cos_alpha(wo, wi));
        }
        p
    }

    /// Sample `wi` given `wo` with the chosen strategy; `u_lobe` picks the lobe (used by `phong`
    /// only), `u` places the direction. `None` when the sample is below the surface or the
    /// material is black: the path ends with zero contribution.
    #[inline]
    pub fn sample(
        &self,
        wo: Vec3,
        u_lobe: f32,
        u: Vec2,
        directions: Directions,
    ) -> Option<BsdfSample> {
        if wo.z <= 0.0 || self.is_black() {
            return None;
        }
        let (wi, lobe) = match directions {
            Directions::Uniform => (sample_uniform_hemisphere(u), Lobe::Hemisphere),
            Directions::Cosine => (sample_cosine_hemisphere(u), Lobe::Hemisphere),
            Directions::Phong => {
                if u_lobe < self.p_diffuse {
                    (sample_cosine_hemisphere(u), Lobe::Diffuse)
                } else {
                    let local = sample_phong_lobe(self.exponent, u);
                    let frame = Frame::from_normal(reflect_local(wo));
                    (frame.to_world(local), Lobe::Glossy)
                }
            }
        };
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wo, wi, directions);
        if pdf <= 0.0 || !pdf.is_finite() {
            return None;
        }
        Some(BsdfSample {
            wi,
            f: self.eval(wo, wi),
            pdf,
            lobe,
        })
    }
}
