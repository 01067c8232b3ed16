//! A path's vertex on a mirror or glass ([`Specular`]), alone or beside a Phong part: which lobe
//! it takes, and the bounce (see [`Path::delta_vertex`]).

use super::*;

impl<'a> Path<'a> {
    /// A vertex with a delta lobe (a mirror or glass, [`Specular`]), alone or beside the Phong
    /// part `bsdf` with probability `share` (`lobes`: the lobe, its share, and whether the ray
    /// arrived from the surface's front, the outside of glass). The delta lobe is taken with
    /// probability `share`, its weight `f|cosθ|/p` divided by it; the Phong part otherwise, its
    /// pdf times `1 − share`, with a light sample and Russian roulette as at any vertex. No light
    /// sample reaches through the delta lobe, the guide is not used (its dimensions are skipped),
    /// and roulette skips a delta bounce. What the light sample adds, and the next ray (origin,
    /// direction, and the vertex it left) unless the path ends.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn delta_vertex<S: Sampler>(
        &self,
        v: &Vertex,
        bsdf: &Bsdf,
        (lobe, share, front): (Specular, f32, bool),
        segment: u32,
        sampler: &mut S,
        (beta, rr_scale): (&mut Vec3, Vec3),
        rays: &mut RayCounts,
        stack: &mut TraceStack,
    ) -> (Vec3, Option<(Vec3, Vec3, Previous)>) {
        let mixed = share < 1.0;
        let roulette = mixed && segment >= RR_START_BOUNCE;
        let u = BounceSample::draw_needed(
            sampler,
            match mixed {
                true => self.light_values,
                false => LightValues::None,
            },
            mixed || lobe.chooses(),
            roulette,
            false,
        );
        if self.settings.directions == Directions::Guided {
            sampler.skip_1d(1);
            sampler.skip_2d(1);
        }
        let mut nee = Vec3::ZERO;
        if mixed {
            if let Some(d) = self.next_event(v, (bsdf, 1.0 - share), None, &u, *beta, rays, stack) {
                nee = d;
            }
        }
        if !mixed || u.lobe < share {
            let u_choice = if mixed { u.lobe / share } else { u.lobe };
            let Some(smp) = lobe.sample(v.wo_local, front, u_choice) else {
                return (nee, None);
            };
            let wi = v.frame.to_world(smp.wi);
            let side = wi.dot(v.ng);
            // a reflection stays on the viewer's side of the geometry, a refraction crosses it
            if (smp.transmitted && side >= 0.0) || (!smp.transmitted && side <= 0.0) {
                return (nee, None);
            }
            *beta *= smp.weight / share;
            let origin = if smp.transmitted {
                v.p - v.ng * self.scene.ray_epsilon
            } else {
                v.spawn
            };
            let prev = Previous {
                delta: true,
                ..Previous::left(v, 0.0)
            };
            return (nee, Some((origin, wi, prev)));
        }
        let directions = self.settings.directions;
        let Some(bs) = bsdf.sample(v.wo_local, u.lobe, u.direction, directions) else {
            return (nee, None);
        };
        let pdf = bs.pdf * (1.0 - share);
        let wi = v.frame.to_world(bs.wi);
        if wi.dot(v.ng) <= 0.0 || pdf <= 0.0 {
            return (nee, None);
        }
        *beta *= bs.f * (bs.wi.z / pdf);
        if roulette && !survives(beta, rr_scale, u.roulette, None) {
            return (nee, None);
        }
        (nee, Some((v.spawn, wi, Previous::left(v, pdf))))
    }
}
