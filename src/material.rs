//! A material as the MTL describes it: `Kd → kd`, `Ks → ks`, `Ns → n`, `Ke → emission`
//! (one-sided, on the front face). Where `kd + ks > 1` in a channel both are scaled down in that
//! channel, so the modified Phong BSDF ([`crate::bsdf`]) that `Scene::bsdf_at` builds from it
//! conserves energy. A mirror or glass (`illum` 3–7 in the MTL) scatters with a delta lobe
//! instead ([`Material::specular`], [`crate::bsdf::Specular`]): its Phong reflectances are zero.
//!
//! Textures ([`Maps`], the MTL's `map_Kd`, `map_Ks`, `map_Ns`) multiply their constants, as the
//! MTL format says (`Kd 1 1 1` with `map_Kd` shows the texture as it is): at a point of texture
//! coordinates `uv`, `kd·T_kd(uv)`, `ks·T_ks(uv)`, `n·T_Ns(uv)` (the scalar maps read their red
//! channel), scaled down per channel where `kd + ks > 1` (only an HDR texture can get there).

use crate::bsdf::{Bsdf, Specular};
use crate::texture::{TextureRef, TextureSet};
use glam::{Vec2, Vec3};

/// The textures of a material.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Maps {
    /// `map_Kd`: multiplies kd (sRGB-decoded).
    pub kd: Option<TextureRef>,
    /// `map_Ks`: multiplies ks (sRGB-decoded).
    pub ks: Option<TextureRef>,
    /// `map_Ns`: multiplies the exponent (linear, red channel).
    pub ns: Option<TextureRef>,
    /// `map_d`: opacity (the alpha channel where the file has one, else its red channel);
    /// below 0.5 the surface is not there ([`Material::opaque_at`]).
    pub opacity: Option<TextureRef>,
    /// `bump` / `map_Bump`: a height map (linear, red channel) and its `-bm` multiplier.
    pub bump: Option<(TextureRef, f32)>,
    /// `norm`: a tangent-space normal map (linear, `n = 2c − 1`).
    pub normal: Option<TextureRef>,
}

impl Maps {
    /// True when a map changes the BSDF's reflectances or exponent.
    #[inline]
    pub fn colour(&self) -> bool {
        self.kd.is_some() || self.ks.is_some() || self.ns.is_some()
    }

    /// True when a map perturbs the shading normal.
    #[inline]
    pub fn perturbs_normal(&self) -> bool {
        self.bump.is_some() || self.normal.is_some()
    }
}

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
    /// Its textures (none by default).
    pub maps: Maps,
    /// A mirror's or glass's delta lobe (none by default), beside a diffuse Phong part (a
    /// mirror of `illum 3` reflects `Ks` over a diffuse `Kd`, as the MTL spec's model says) or
    /// alone (glass; a mirror of black `Kd`).
    pub specular: Option<Specular>,
    /// The probability a bounce takes the delta lobe: 1 where it is alone, else its share of
    /// the albedo, `avg(Ks)/(avg(Ks) + avg(Kd))`.
    pub delta_share: f32,
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
            maps: Maps::default(),
            specular: None,
            delta_share: 0.0,
        };
        (m, scaled)
    }

    /// A material that scatters with the delta lobe `specular` (a mirror or glass) over a
    /// diffuse part `kd` (black for glass), emitting `emission`: a mirror's reflectance and `kd`
    /// scaled down per channel where they add up to more than 1 (the flag says whether).
    pub fn with_delta(name: &str, kd: Vec3, specular: Specular, emission: Vec3) -> (Self, bool) {
        let (specular, kd, scaled) = match specular {
            Specular::Mirror {
                reflectance,
                schlick,
            } => {
                let (r, kd) = (reflectance.max(Vec3::ZERO), kd.max(Vec3::ZERO));
                let scale = Vec3::ONE / (r + kd).max(Vec3::ONE);
                let reflectance = r * scale;
                let m = Specular::Mirror {
                    reflectance,
                    schlick,
                };
                (m, kd * scale, (r + kd).max_element() > 1.0)
            }
            glass => (glass, Vec3::ZERO, false),
        };
        let mut m = Material::new(name, kd, Vec3::ZERO, 1.0, emission).0;
        let share = match specular {
            Specular::Mirror { reflectance, .. } => {
                let (r, d) = (crate::math::average(reflectance), crate::math::average(kd));
                if r + d > 0.0 {
                    r / (r + d)
                } else {
                    1.0
                }
            }
            Specular::Dielectric { .. } => 1.0,
        };
        m.specular = Some(specular);
        m.delta_share = share;
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

    /// The BSDF at texture coordinates `uv` (the textures of `textures`): kd, ks and the
    /// exponent times their maps, scaled down per channel where `kd + ks > 1`.
    #[inline]
    pub fn bsdf_at(&self, uv: Vec2, textures: &TextureSet) -> Bsdf {
        if !self.maps.colour() {
            return self.bsdf;
        }
        let rgb = |r: &Option<TextureRef>| {
            r.map_or(Vec3::ONE, |r| {
                textures.get(&r).bilinear(r.map(uv)).truncate()
            })
        };
        let kd = self.kd * rgb(&self.maps.kd);
        let ks = self.ks * rgb(&self.maps.ks);
        let n = self.exponent * rgb(&self.maps.ns).x;
        let scale = Vec3::ONE / (kd + ks).max(Vec3::ONE);
        Bsdf::new(kd * scale, ks * scale, n.max(0.0))
    }

    /// Whether the surface is there at `uv`: its `map_d` opacity is at least 0.5 (always, for
    /// a material without one).
    #[inline]
    pub fn opaque_at(&self, uv: Vec2, textures: &TextureSet) -> bool {
        self.maps.opacity.is_none_or(|r| {
            let t = textures.get(&r);
            let v = t.bilinear(r.map(uv));
            (if t.has_alpha() { v.w } else { v.x }) >= 0.5
        })
    }

    /// True when the material emits.
    #[inline]
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}
