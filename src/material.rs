//! A material as the MTL describes it: `Kd → kd`, `Ks → ks`, `Ns → n`, `Ke → emission`
//! (one-sided, on the front face). Where `kd + ks > 1` in a channel both are scaled down in that
//! channel, so the modified Phong BSDF ([`crate::bsdf`]) that `Scene::bsdf_at` builds from it
//! conserves energy.

use crate::bsdf::Bsdf;
use glam::Vec3;

/// A modified Phong material with optional one-sided emission. The reflectances are read
/// through methods: the BSDF is built from them once, so they cannot change behind its back.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Emitted radiance (MTL `Ke`), on the front side only.
    pub emission: Vec3,
    /// Diffuse reflectance.
    kd: Vec3,
    /// Specular reflectance.
    ks: Vec3,
    /// Phong exponent (MTL `Ns`).
    exponent: f32,
    /// The BSDF built from kd, ks and the exponent once, for surfaces without texture.
    bsdf: Bsdf,
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
        let (kd, ks, exponent) = (kd * scale, ks * scale, exponent.max(0.0));
        let m = Material {
            name: name.to_string(),
            kd,
            ks,
            exponent,
            emission: emission.max(Vec3::ZERO),
            bsdf: Bsdf::new(kd, ks, exponent),
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

    /// Diffuse reflectance (after energy scaling).
    pub fn kd(&self) -> Vec3 {
        self.kd
    }

    /// Specular reflectance (after energy scaling).
    pub fn ks(&self) -> Vec3 {
        self.ks
    }

    /// Phong exponent (MTL `Ns`).
    pub fn exponent(&self) -> f32 {
        self.exponent
    }

    /// The BSDF of this material where it has no texture.
    #[inline]
    pub fn bsdf(&self) -> Bsdf {
        self.bsdf
    }

    /// True when the material emits.
    #[inline]
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}
