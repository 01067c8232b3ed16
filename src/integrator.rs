//! Unidirectional path tracing with BSDF sampling.
//!
//! `L = Σ_k β_k L_e(x_k)` along a path built by sampling each bounce from the material with the
//! chosen [`Directions`] strategy, where the throughput is `β_{k+1} = β_k · f · cosθᵢ / p`.
//! Emission is one-sided (front faces only); rays that escape see the constant environment.
//!
//! Path length: `max_depth` is the largest number of segments of a path, counting the camera
//! ray (1 = only directly visible emitters, as Mitsuba's `max_depth`). Russian roulette from the
//! third bounce on keeps a path with probability `q = min(max β, 0.95)` and divides by `q`: an
//! unbiased termination.
//!
//! Every bounce draws the same dimensions in the same order ([`BounceSample`], the layout in
//! [`crate::sampler::layout`]), used or not, so a dimension index means the same decision in
//! every sample — which is what stratification needs.

use crate::bsdf::Directions;
use crate::math::Frame;
use crate::sampler::layout::BounceSample;
use crate::sampler::Sampler;
use crate::scene::Scene;
use glam::Vec3;

/// Bounces (vertices after the camera) before Russian roulette may end a path.
pub const RR_START_BOUNCE: u32 = 3;

/// What the integrator needs to know besides the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IntegratorSettings {
    /// Largest number of path segments, counting the camera ray (≥ 1).
    pub max_depth: u32,
    pub directions: Directions,
}

/// Radiance arriving at `origin` from direction `dir` (unit), and the number of rays traced.
#[inline]
pub fn radiance<S: Sampler>(
    scene: &Scene,
    mut origin: Vec3,
    mut dir: Vec3,
    sampler: &mut S,
    settings: &IntegratorSettings,
) -> (Vec3, u64) {
    let mut l = Vec3::ZERO;
    let mut beta = Vec3::ONE;
    let mut rays = 0u64;
    for segment in 1..=settings.max_depth {
        rays += 1;
        let Some(hit) = scene.accel.intersect(origin, dir, f32::INFINITY) else {
            l += beta * scene.environment;
            break;
        };
        let s = scene.surface(&hit);
        let m = scene.material_at(&s);
        let wo = -dir;
        let front = s.ng.dot(wo) > 0.0;
        if front && m.is_emissive() {
            l += beta * m.emission;
        }
        if segment == settings.max_depth {
            break;
        }
        let u = BounceSample::draw(sampler);
        let bsdf = scene.bsdf_at(&s);
        if bsdf.is_black() {
            break;
        }
        // Two-sided shading: put both normals on the side the ray came from.
        let (ng, mut ns) = if front { (s.ng, s.ns) } else { (-s.ng, -s.ns) };
        if ns.dot(wo) <= 0.0 {
            ns = ng; // the shading normal faces away from the viewer: fall back to geometry
        }
        let frame = Frame::from_normal(ns);
        let wo_local = frame.to_local(wo);
        let Some(bs) = bsdf.sample(wo_local, u.lobe, u.direction, settings.directions) else {
            break;
        };
        let wi = frame.to_world(bs.wi);
        if wi.dot(ng) <= 0.0 {
            break; // below the geometric surface: no light passes through
        }
        beta *= bs.f * (bs.wi.z / bs.pdf);
        let bounce = segment; // vertices so far after the camera
        if bounce >= RR_START_BOUNCE {
            let q = beta.max_element().min(0.95);
            if u.roulette >= q {
                break;
            }
            beta /= q;
        }
        origin = s.p + ng * scene.ray_epsilon;
        dir = wi;
    }
    (l, rays)
}
