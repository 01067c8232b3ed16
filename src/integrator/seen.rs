//! What the camera sees directly: the one term of a path that `--edge-rays` estimates apart
//! ([`crate::render::edges`]), here so that its rays and the path's camera ray read the scene
//! the same way.

use super::RayCounts;
use crate::accel::{Hit, RayPacket, TraceStack, LANES};
use crate::scene::Scene;
use glam::Vec3;

/// What a camera ray meets first ([`seen`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Seen {
    /// A surface that emits nothing toward it (it may reflect light: a path goes on there).
    Surface,
    /// The front of an emitting surface.
    Light,
    /// Nothing: it escapes to the environment (nothing goes on).
    Sky,
}

/// What the camera sees directly along `ray` (unit direction) and what it meets: the
/// environment's radiance where it escapes, what the surface it hits emits toward it (from its
/// front only), else zero: exactly the term a path's camera ray adds
/// ([`super::IntegratorSettings::camera_emission`]). The ray is counted as a camera ray and an
/// edge ray in `rays`.
#[inline]
pub fn seen(
    scene: &Scene,
    (origin, dir): (Vec3, Vec3),
    rays: &mut RayCounts,
    stack: &mut TraceStack,
) -> (Vec3, Seen) {
    rays.camera += 1;
    rays.edge += 1;
    seen_at(
        scene,
        dir,
        scene.intersect(stack, origin, dir, f32::INFINITY),
    )
}

/// [`seen`] of a camera ray of direction `dir` whose closest hit is `hit` (already traced, and
/// counted: a packet's lane, [`seen_packet`]).
#[inline]
fn seen_at(scene: &Scene, dir: Vec3, hit: Option<Hit>) -> (Vec3, Seen) {
    let Some(hit) = hit else {
        return (scene.environment().radiance(dir), Seen::Sky);
    };
    let s = scene.surface(&hit);
    let m = scene.material_at(&s);
    if m.is_emissive() && s.ng.dot(-dir) > 0.0 {
        (m.emission, Seen::Light)
    } else {
        (Vec3::ZERO, Seen::Surface)
    }
}

/// The emission [`seen`] along `ray`.
#[inline]
pub fn seen_emission(
    scene: &Scene,
    ray: (Vec3, Vec3),
    rays: &mut RayCounts,
    stack: &mut TraceStack,
) -> Vec3 {
    seen(scene, ray, rays, stack).0
}

/// [`seen_emission`] along each of the `rays` (at most [`LANES`]; the lanes past them zero),
/// traced as one packet ([`Scene::intersect_packet`]): the same values, bit for bit. Each ray
/// is counted as a camera ray and an edge ray in `counts`.
#[inline]
pub fn seen_packet(
    scene: &Scene,
    rays: &[(Vec3, Vec3)],
    counts: &mut RayCounts,
    stack: &mut TraceStack,
) -> [Vec3; LANES] {
    let mut p = RayPacket::new();
    for (lane, &(o, d)) in rays.iter().enumerate() {
        p.set(lane, o, d, f32::INFINITY);
    }
    let mut hits = [None; LANES];
    scene.intersect_packet(stack, &p, &mut hits);
    counts.camera += rays.len() as u64;
    counts.edge += rays.len() as u64;
    let mut seen = [Vec3::ZERO; LANES];
    for ((e, &(_, d)), hit) in seen.iter_mut().zip(rays).zip(hits) {
        *e = seen_at(scene, d, hit).0;
    }
    seen
}
