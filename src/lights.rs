//! The lights of a scene and how they are sampled: every emissive triangle, and the constant
//! environment when it is not black.
//!
//! - **Emissive triangles** are one-sided: a triangle emits `Le` on the side its
//!   counter-clockwise normal `n_l` points to. A point on it is chosen uniformly by area
//!   ([`sample_uniform_triangle`], pdf `1/A`); seen from a point `x` the pdf per unit solid angle
//!   is `p_ω = p_A · d² / cosθ_l`, with `d = |y − x|` and `cosθ_l = n_l · (x − y)/d > 0`.
//! - **The environment** (radiance `L_env` for every escaping ray) is sampled by a cosine
//!   distribution about the shading normal `n` of the vertex it lights: `p_ω = cosθ/π`, zero
//!   below. Under a diffuse BSDF `f cosθ / p_ω = kd`, so a white furnace has no variance.
//! - **Selection**: one light per vertex, chosen with probability proportional to its power
//!   (a [`Discrete`] distribution, binary search, O(log n)): `Φ = π A lum(Le)` for a triangle (a
//!   one-sided Lambertian emitter) and `Φ = 4π · πR² · lum(L_env)` for the environment seen by a
//!   scene of bounding radius `R` (pbrt's estimate). Any positive choice is unbiased; power keeps
//!   the weights tame. The pmf the pdfs divide by is exactly the frequency of each choice (whole
//!   units of 2⁻²⁴), also with 10⁶ emitters.
//!
//! Every pdf this module returns is per unit solid angle at the receiving point and includes
//! the selection probability. [`Lights::light_of`] maps a BVH-order primitive to its light, so a
//! BSDF-sampled ray that hits an emitter finds the light pdf of the same path for MIS.

use crate::math::Frame;
use crate::sampling::{
    cosine_hemisphere_pdf, sample_cosine_hemisphere, sample_uniform_triangle, uniform_triangle_pdf,
    Discrete,
};
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// How light is found at a vertex (the `--lights` flag): the third axis of variance reduction.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum LightStrategy {
    /// BSDF sampling only: emission counts when a sampled ray happens to hit it.
    Bsdf,
    /// Next-event estimation: sample one light per vertex and trace a shadow ray; emission
    /// hit by BSDF-sampled rays after the camera ray is not added.
    Nee,
    /// Both, weighted by the power heuristic (multiple importance sampling).
    #[default]
    Mis,
}

impl std::fmt::Display for LightStrategy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&crate::names::value_name(self))
    }
}

/// Index in the primitive → light map of a primitive that is no light.
const NO_LIGHT: u32 = u32::MAX;

/// An emissive triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleLight {
    /// BVH-order triangle index.
    pub prim: u32,
    /// The vertices.
    pub v: [Vec3; 3],
    /// Unit normal of the emitting side (counter-clockwise winding).
    pub n: Vec3,
    /// Area of the triangle.
    pub area: f32,
    /// Emitted radiance on the front side.
    pub emission: Vec3,
}

impl TriangleLight {
    /// The emissive triangle `v` (BVH-order primitive `prim`) of front radiance `emission`.
    pub fn new(prim: u32, v: [Vec3; 3], emission: Vec3) -> TriangleLight {
        let c = (v[1] - v[0]).cross(v[2] - v[0]);
        TriangleLight {
            prim,
            v,
            n: c.normalize_or_zero(),
            area: 0.5 * c.length(),
            emission,
        }
    }
}

/// A sampled light direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit direction from the receiving point toward the light.
    pub wi: Vec3,
    /// Distance to the sampled point (infinite for the environment).
    pub dist: f32,
    /// Radiance arriving along `-wi` if nothing is in between.
    pub le: Vec3,
    /// Probability density of `wi` per unit solid angle, selection included.
    pub pdf: f32,
}

/// All lights of a scene, and the distribution that chooses among them.
#[derive(Clone, Debug, Default)]
pub struct Lights {
    /// The emissive triangles, in BVH order.
    pub triangles: Vec<TriangleLight>,
    /// Radiance of the environment (zero: it is no light).
    pub environment: Vec3,
    /// `light_index[prim]`: the light of BVH-order triangle `prim`, or [`NO_LIGHT`].
    light_index: Vec<u32>,
    /// The choice of a light: each triangle light, then the environment (last).
    choice: Discrete,
}

/// Luminance (Rec. 709 weights) of linear RGB.
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

impl Lights {
    /// The lights of a scene of `primitives` triangles: the emissive `triangles` (each
    /// knowing its BVH-order primitive), and the environment of radiance `environment` lighting
    /// a scene of bounding radius `radius`. Err with more than 2²⁴ emitters (see [`Discrete`]).
    pub fn build(
        triangles: Vec<TriangleLight>,
        primitives: usize,
        environment: Vec3,
        radius: f32,
    ) -> Result<Lights, String> {
        let mut light_index = vec![NO_LIGHT; primitives];
        for (i, t) in triangles.iter().enumerate() {
            light_index[t.prim as usize] = i as u32;
        }
        let mut power: Vec<f64> = triangles
            .iter()
            .map(|t| (PI * t.area * luminance(t.emission).max(0.0)) as f64)
            .collect();
        power.push((4.0 * PI * PI * radius * radius * luminance(environment).max(0.0)) as f64);
        Ok(Lights {
            triangles,
            environment,
            light_index,
            choice: Discrete::new(&power)?,
        })
    }

    /// Number of emissive triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// True when the scene has no emissive triangle.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// True when something can be sampled (an emitter, or a non-black environment).
    pub fn any(&self) -> bool {
        self.choice.any()
    }

    /// The light that BVH-order triangle `prim` is, if it emits.
    #[inline]
    pub fn light_of(&self, prim: u32) -> Option<u32> {
        match self.light_index.get(prim as usize) {
            Some(&i) if i != NO_LIGHT => Some(i),
            _ => None,
        }
    }

    /// The probability of choosing triangle light `i` (exactly the frequency of
    /// [`Lights::choose`]).
    #[inline]
    pub fn pmf(&self, i: u32) -> f32 {
        self.choice.pmf(i as usize)
    }

    /// The probability of choosing the environment.
    #[inline]
    pub fn environment_pmf(&self) -> f32 {
        self.choice.pmf(self.triangles.len())
    }

    /// Choose a light with `u ∈ [0,1)`: `Some(i)` for triangle `i`, `None` for the environment
    /// (or when nothing can be chosen: [`Lights::any`] is false).
    #[inline]
    pub fn choose(&self, u: f32) -> Option<u32> {
        match self.choice.sample(u) {
            Some(i) if i < self.triangles.len() => Some(i as u32),
            _ => None,
        }
    }

    /// Sample a light for the point `p` with shading normal `n` (on the side light is gathered
    /// from): `u_choose` picks the light, `u` the point on it (or the environment direction).
    /// `None` when nothing is sampled or the point sees the back of the chosen triangle.
    #[inline]
    pub fn sample(&self, p: Vec3, n: Vec3, u_choose: f32, u: Vec2) -> Option<LightSample> {
        if !self.any() {
            return None;
        }
        match self.choose(u_choose) {
            Some(i) => {
                let t = &self.triangles[i as usize];
                let b = sample_uniform_triangle(u);
                let y = t.v[0] * b.x + t.v[1] * b.y + t.v[2] * (1.0 - b.x - b.y);
                let d = y - p;
                let dist2 = d.length_squared();
                let dist = dist2.sqrt();
                if dist <= 0.0 {
                    return None;
                }
                let wi = d / dist;
                let cos_l = -t.n.dot(wi);
                if cos_l <= 0.0 {
                    return None;
                }
                Some(LightSample {
                    wi,
                    dist,
                    le: t.emission,
                    pdf: self.pmf(i) * uniform_triangle_pdf(t.area) * dist2 / cos_l,
                })
            }
            None => {
                let local = sample_cosine_hemisphere(u);
                let pdf = self.environment_pmf() * cosine_hemisphere_pdf(local.z);
                if pdf <= 0.0 {
                    return None;
                }
                Some(LightSample {
                    wi: Frame::from_normal(n).to_world(local),
                    dist: f32::INFINITY,
                    le: self.environment,
                    pdf,
                })
            }
        }
    }

    /// The pdf per solid angle with which [`Lights::sample`] at `p` returns the point `y` of
    /// triangle light `i` (0 when `p` sees its back).
    #[inline]
    pub fn triangle_pdf(&self, i: u32, p: Vec3, y: Vec3) -> f32 {
        let t = &self.triangles[i as usize];
        let d = y - p;
        let dist2 = d.length_squared();
        let cos_l = -t.n.dot(d) / dist2.sqrt();
        if cos_l <= 0.0 || dist2 <= 0.0 {
            return 0.0;
        }
        self.pmf(i) * uniform_triangle_pdf(t.area) * dist2 / cos_l
    }

    /// The pdf per solid angle with which [`Lights::sample`] at a point of shading normal `n`
    /// returns the environment direction `wi`.
    #[inline]
    pub fn environment_pdf(&self, n: Vec3, wi: Vec3) -> f32 {
        self.environment_pmf() * cosine_hemisphere_pdf(n.dot(wi))
    }
}
