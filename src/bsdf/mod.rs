//! The BSDF at a surface point: the modified Phong model (Lafortune & Willems 1994), energy
//! conserving:
//!
//! `f(wo, wi) = kd/π + ks·(n+2)/(2π)·cosⁿα`, with `α` the angle between `wi` and the mirror
//! direction of `wo` (and `cosα` clamped at 0).
//!
//! A [`Bsdf`] is built per hit by `Scene::bsdf_at` from the [`crate::material::Material`] the
//! MTL describes, so that textures later change that one function.
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
//! - `guided`: the BSDF's part of path guiding is `phong`; the integrator mixes it with the
//!   learned guide ([`crate::guiding`]), so here `guided` samples and evaluates as `phong`.
//!
//! Mirrors and glass are delta lobes, [`Specular`] (`bsdf/specular.rs`): a surface has the Phong
//! lobes, one delta lobe, or a mirror over a diffuse part, and the path loop asks only which.

mod specular;

pub use specular::{fresnel_dielectric, fresnel_schlick, Specular, SpecularSample};

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
    /// Path guiding: the Phong lobes or, with probability 1/2 where it has learned something,
    /// the incident radiance learned by an SD-tree while rendering (see `vrpt::guiding`).
    Guided,
}

impl std::fmt::Display for Directions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&crate::names::value_name(self))
    }
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
}

/// The largest bound on the second moment of a reused bounce's weight under Phong directions
/// ([`Bsdf::reusable_bounce`]; a white diffuse surface's is 1.05). Measured at equal time (10 s):
/// sharing the Cornell box's glossy box (bound 58) gains 1.8–2.5× where not sharing it gains
/// 1.05–1.2×, and sharing the glossy plates (105 for Ns 10 to 7700 for Ns 1000) loses.
pub const MAX_REUSED_MOMENT: f32 = 64.0;

/// The modified Phong BSDF at one surface point (built by [`Bsdf::new`], which derives the
/// lobe probability from the reflectances, so the fields are not public).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bsdf {
    /// Diffuse reflectance.
    kd: Vec3,
    /// Specular reflectance.
    ks: Vec3,
    /// Phong exponent.
    exponent: f32,
    /// Probability of choosing the diffuse lobe in `phong` sampling.
    p_diffuse: f32,
}

impl Bsdf {
    /// A BSDF of reflectances `kd`, `ks` (taken as they are: the caller keeps `kd + ks ≤ 1`) and
    /// Phong exponent `exponent ≥ 0`.
    #[inline]
    pub fn new(kd: Vec3, ks: Vec3, exponent: f32) -> Bsdf {
        let (ad, as_) = (average(kd), average(ks));
        let p_diffuse = if ad + as_ > 0.0 { ad / (ad + as_) } else { 1.0 };
        Bsdf {
            kd,
            ks,
            exponent,
            p_diffuse,
        }
    }

    /// True when sampling with `directions` reads the lobe-choice number: Phong directions
    /// with both a diffuse and a specular part.
    #[inline]
    pub fn chooses_lobe(&self, directions: Directions) -> bool {
        matches!(directions, Directions::Phong | Directions::Guided)
            && self.p_diffuse > 0.0
            && self.p_diffuse < 1.0
    }

    /// The probability that Phong sampling takes the diffuse lobe, `avg(kd)/(avg(kd)+avg(ks))`
    /// (1 without a specular part).
    #[inline]
    pub fn diffuse_share(&self) -> f32 {
        self.p_diffuse
    }

    /// True when the BSDF reflects nothing (paths end on it).
    #[inline]
    pub fn is_black(&self) -> bool {
        self.kd.max_element() <= 0.0 && self.ks.max_element() <= 0.0
    }

    /// True when a bounce sampled with `directions` for one viewer may be re-evaluated for
    /// another (path reuse's tails, [`crate::integrator::reuse`]): its pdf must be positive on the
    /// whole hemisphere whatever `wo` is, and the second moment of its weight for the other
    /// viewer bounded. Uniform and cosine directions do not depend on `wo`: the weight is that of
    /// the viewer's own bounce. Phong (and guided) directions need a diffuse lobe, whose pdf
    /// `p_d cosθ/π` bounds the mixture's below, so for every `wo′` the weight
    /// `w = f(wo′, ω) cosθ / p(wo, ω)` has `E[w²] = ∫ f² cos²θ / p dω ≤ (π/p_d) ∫ f² cosθ dω
    /// ≤ (2 k_d² + k_s² (n+2)² / (2n+1)) / p_d` (per channel, the largest; divided by `1 − α`
    /// under a guide of share `α`). It must be at most [`MAX_REUSED_MOMENT`].
    #[inline]
    pub fn reusable_bounce(&self, directions: Directions) -> bool {
        !self.is_black()
            && match directions {
                Directions::Uniform | Directions::Cosine => true,
                Directions::Phong | Directions::Guided => {
                    let (kd, ks, n) = (self.kd.max_element(), self.ks.max_element(), self.exponent);
                    let moment = 2.0 * kd * kd + ks * ks * (n + 2.0) * (n + 2.0) / (2.0 * n + 1.0);
                    self.p_diffuse > 0.0 && moment <= MAX_REUSED_MOMENT * self.p_diffuse
                }
            }
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

    /// The pdf with which [`Bsdf::sample`] returns `wi`, per unit solid angle.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, directions: Directions) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 || self.is_black() {
            return 0.0;
        }
        match directions {
            Directions::Uniform => uniform_hemisphere_pdf(),
            Directions::Cosine => cosine_hemisphere_pdf(wi.z),
            Directions::Phong | Directions::Guided => self.mixture_pdf(wo, wi),
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
    /// BSDF is black: the path ends with zero contribution.
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
        let wi = match directions {
            Directions::Uniform => sample_uniform_hemisphere(u),
            Directions::Cosine => sample_cosine_hemisphere(u),
            Directions::Phong | Directions::Guided => {
                if u_lobe < self.p_diffuse {
                    sample_cosine_hemisphere(u)
                } else {
                    let local = sample_phong_lobe(self.exponent, u);
                    Frame::from_normal(reflect_local(wo)).to_world(local)
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
        })
    }
}
