//! Next-event estimation at a vertex: one light sample `y` (direction `ωᵢ`, pdf `p_light` per
//! solid angle, the light's choice included) and a shadow ray; what it adds is
//! `β f(ωₒ, ωᵢ) cosθᵢ Le(y) w / p_light` if `y` is visible, with `w = 1` under `nee` and the power
//! heuristic `w(p_light, p_bsdf)` under `mis`, `p_bsdf` the pdf with which the bounce's own
//! direction strategy (the guided mixture where there is a guide) would have drawn `ωᵢ`.

use super::{mis_weight, timed, Path, Phase, RayCounts, Vertex};
use crate::accel::TraceStack;
use crate::bsdf::Bsdf;
use crate::guiding::GuideAt;
use crate::lights::LightStrategy;
use crate::sampler::layout::BounceSample;
use glam::Vec3;

/// A light sample that reached its light: the direction in the vertex's shading frame, the
/// BSDF toward it, the light's radiance, the MIS weight and the pdf (per solid angle).
#[derive(Clone, Copy, Debug)]
pub(super) struct LightHit {
    pub(super) wi_local: Vec3,
    pub(super) f: Vec3,
    pub(super) le: Vec3,
    pub(super) w: f32,
    pub(super) pdf: f32,
}

impl Path<'_> {
    /// What the light sample at `v` adds to the path's radiance (throughput `beta` so far), or
    /// `None` where it adds nothing (`share`: the probability a bounce samples `bsdf`, less than
    /// 1 beside a delta lobe, so the bounce's pdf in the MIS weight is `share·p_bsdf`): no light sampling (`bsdf`, or a scene without lights), no
    /// light, a light behind the surface, a black BSDF in its direction, or a blocked shadow ray.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn next_event(
        &self,
        v: &Vertex,
        bsdf: (&Bsdf, f32),
        g: Option<&GuideAt>,
        u: &BounceSample,
        beta: Vec3,
        rays: &mut RayCounts,
        stack: &mut TraceStack,
    ) -> Option<Vec3> {
        let h = self.light_sample(v, bsdf, g, u, rays, stack)?;
        Some(beta * h.f * h.le * (h.wi_local.z * h.w / h.pdf))
    }

    /// The light sample of [`Self::next_event`] in its parts, where it reached its light.
    #[inline(always)]
    pub(super) fn light_sample(
        &self,
        v: &Vertex,
        (bsdf, share): (&Bsdf, f32),
        g: Option<&GuideAt>,
        u: &BounceSample,
        rays: &mut RayCounts,
        stack: &mut TraceStack,
    ) -> Option<LightHit> {
        if !self.sample_lights {
            return None;
        }
        let (scene, settings) = (self.scene, self.settings);
        let ls = self.lights.sample(v.p, v.ns, u.light, u.light_point);
        rays.mark(Phase::Light);
        let ls = ls?;
        let wi_local = v.frame.to_local(ls.wi);
        // light from below the geometric surface cannot arrive (as for BSDF samples)
        if !(ls.wi.dot(v.ng) > 0.0 && wi_local.z > 0.0) {
            return None;
        }
        let f = bsdf.eval(v.wo_local, wi_local);
        rays.mark(Phase::Bsdf);
        if f.max_element() > 0.0 {
            let (to, tmax) = if ls.dist.is_finite() {
                let y = v.p + ls.wi * ls.dist;
                let d = y - v.spawn;
                let len = d.length();
                (d / len, len - 2.0 * scene.ray_epsilon)
            } else {
                (ls.wi, f32::INFINITY)
            };
            rays.shadow += 1;
            let blocked = tmax <= 0.0
                || timed(settings.time_traces, rays, || {
                    scene.occluded(stack, v.spawn, to, tmax)
                });
            rays.mark(Phase::Shadow);
            if !blocked {
                let w = match settings.lights {
                    LightStrategy::Mis => {
                        let p = bsdf.pdf(v.wo_local, wi_local, settings.directions) * share;
                        let p = g.map_or(p, |g| g.mixture_pdf(ls.wi, p));
                        mis_weight(ls.pdf, p)
                    }
                    _ => 1.0,
                };
                rays.mark(Phase::Bsdf);
                return Some(LightHit {
                    wi_local,
                    f,
                    le: ls.le,
                    w,
                    pdf: ls.pdf,
                });
            }
        }
        None
    }
}
