//! The path of `--roulette ears` ([`super::rrs`]): a tree, not a line. At each Phong vertex
//! the path takes `N = ⌊n + u⌋` continuations (a light sample, a bounce and everything after
//! it, each with its own bounce sample) and returns their sum over `n`; mirror and glass
//! vertices go on as in [`Path::trace`], with its roulette. Each continuation is traced by a
//! call of [`Path::trace_rrs`] from the bounce, so the recursion is as deep as the path is
//! long ([`MAX_RRS_DEPTH`]).
//!
//! Conventions as in [`Path::trace`]: `wo` points back along the arriving ray, throughputs
//! are `f·cosθ/p`, emission is weighted by [`Path::emission_weight`] with the pdf of the
//! bounce that reached it, so MIS is unchanged. A training iteration appends one
//! [`RrsRecord`] per continuation: what it brought back per unit throughput at the vertex and
//! the rays it traced, the light sample's included.

use super::rrs::{direction_bin, RrsPath, RrsRecord};
use super::*;
use crate::math::hash_words;
use crate::sampler::IndependentSampler;
use glam::UVec2;

/// The longest path `--roulette ears` traces (`--max-depth`): its continuations recurse once
/// per vertex.
pub const MAX_RRS_DEPTH: u32 = 64;

impl<'a> Path<'a> {
    /// The radiance the ray `(origin, dir)` brings back per unit throughput at its start, the
    /// ray being segment `first` of the path (1: the camera ray, `prev` then `None`) and
    /// `scale` the path's whole throughput where it starts (what the splitting factor reads).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn trace_rrs<S: Sampler>(
        &self,
        (mut origin, mut dir): (Vec3, Vec3),
        mut prev: Option<Previous>,
        first: u32,
        scale: Vec3,
        sampler: &mut S,
        rays: &mut RayCounts,
        stack: &mut TraceStack,
        rrs: &mut RrsPath,
    ) -> Vec3 {
        let (scene, settings) = (self.scene, self.settings);
        let (mut l, mut beta) = (Vec3::ZERO, Vec3::ONE);
        for segment in first..=settings.max_depth {
            let (_, s, wo, front) = match self.reach(prev, (origin, dir), rays, stack) {
                Reached::Escaped(le, w) => {
                    l += beta * le * w;
                    break;
                }
                Reached::Surface(at, emitted) => {
                    if let Some((le, w)) = emitted {
                        l += beta * le * w;
                    }
                    at
                }
            };
            if segment == settings.max_depth {
                rays.mark(Phase::Shade);
                break;
            }
            let bsdf = scene.bsdf_at(&s);
            if let Some(d) = scene.material_at(&s).specular.filter(|d| !d.is_black()) {
                let v = Vertex::new(scene, &s, front, wo);
                let lobes = (d, scene.material_at(&s).delta_share, front);
                let b = (&mut beta, scale);
                let (nee, next) =
                    self.delta_vertex(&v, &bsdf, lobes, segment, sampler, b, rays, stack);
                l += nee;
                let Some((o, wi, p)) = next else { break };
                ((origin, dir), prev) = ((o, wi), Some(p));
                continue;
            }
            if !bsdf.is_black() {
                let at = (segment, &s, front, wo);
                let lr = self.split_vertex(at, &bsdf, scale * beta, sampler, rays, stack, rrs);
                l += beta * lr;
            }
            break;
        }
        l
    }

    /// The Phong vertex ending segment `segment` at `s` (hit from `wo`, from its `front` or
    /// not), reached with whole throughput `whole`: the factor `n` ([`RrsPath::factor`]),
    /// `⌊n + u⌋` continuations, their sum over `n`: the reflected radiance toward `wo`.
    #[allow(clippy::too_many_arguments)]
    fn split_vertex<S: Sampler>(
        &self,
        (segment, s, front, wo): (u32, &SurfacePoint, bool, Vec3),
        bsdf: &Bsdf,
        whole: Vec3,
        sampler: &mut S,
        rays: &mut RayCounts,
        stack: &mut TraceStack,
        rrs: &mut RrsPath,
    ) -> Vec3 {
        let directions = self.settings.directions;
        rays.mark(Phase::Shade);
        let lobe = bsdf.chooses_lobe(directions);
        let guided = directions == Directions::Guided;
        let first_u = BounceSample::draw_needed(sampler, self.light_values, lobe, true, guided);
        rays.mark(Phase::Sampler);
        let v = Vertex::new(self.scene, s, front, wo);
        let g = (self.guide).and_then(|t| GuideAt::for_image(t, s.p, bsdf.diffuse_share()));
        let bin = direction_bin(wo);
        let n = rrs.factor(v.p, bin, whole, segment);
        // n ≤ 1 + extra, so the count never passes what is left, but for the rounding of
        // `n + u` in f32 (16 + 0.99999994 is 17.0): bounded, or `extra` wraps (a panic in a
        // debug build, unbounded splitting in a release one; met by a test once the Cornell
        // box's ties at shared edges were broken by a fixed rule)
        let count = ((n + first_u.roulette) as u32).min(1 + rrs.extra);
        rrs.extra -= count.saturating_sub(1);
        rays.mark(Phase::Shade);
        let mut sum = Vec3::ZERO;
        let at = Continuation {
            v: &v,
            bsdf,
            g: g.as_ref(),
            bin,
            segment,
            next: whole / n,
        };
        for k in 0..count {
            sum += if k == 0 {
                self.continuation(&at, &first_u, sampler, rays, stack, rrs)
            } else {
                // its own independent stream, keyed by the vertex and the split's draw: the
                // first continuation keeps the sampler's layout (and its stratification)
                let p = v.p.to_array().map(f32::to_bits);
                let key = [first_u.roulette.to_bits(), p[0], p[1], p[2], segment, k];
                let mut stream = IndependentSampler::new(hash_words(&key.map(u64::from)));
                stream.start_pixel_sample(UVec2::ZERO, 0);
                let u =
                    BounceSample::draw_needed(&mut stream, self.light_values, lobe, true, guided);
                self.continuation(&at, &u, &mut stream, rays, stack, rrs)
            };
        }
        sum / n
    }

    /// One continuation of the vertex `at` with the bounce sample `u` (the rest of it drawn
    /// from `sampler`): a light sample, a bounce and the path after it, what it brings back
    /// per unit throughput at the vertex, recorded in a training iteration.
    fn continuation<T: Sampler>(
        &self,
        at: &Continuation,
        u: &BounceSample,
        sampler: &mut T,
        rays: &mut RayCounts,
        stack: &mut TraceStack,
        rrs: &mut RrsPath,
    ) -> Vec3 {
        let v = at.v;
        let before = rays.total();
        let mut lr = self
            .next_event(v, (at.bsdf, 1.0), at.g, u, Vec3::ONE, rays, stack)
            .unwrap_or(Vec3::ZERO);
        let sampled = self.sample_direction(v, at.bsdf, at.g, u);
        rays.mark(Phase::Bsdf);
        if let Some((wi, bs, _)) = sampled.filter(|(wi, _, _)| wi.dot(v.ng) > 0.0) {
            let w = bs.f * (bs.wi.z / bs.pdf);
            let ray = (v.spawn, wi);
            let prev = Some(Previous::left(v, bs.pdf));
            let next = at.next * w;
            let cont = self.trace_rrs(ray, prev, at.segment + 1, next, sampler, rays, stack, rrs);
            lr += w * cont;
        }
        if let Some(out) = rrs.records.as_deref_mut().filter(|_| lr.is_finite()) {
            out.push(RrsRecord {
                p: v.p,
                bin: at.bin,
                first: at.segment == 1,
                lr,
                cost: (rays.total() - before) as f32,
            });
        }
        lr
    }
}

/// What every continuation of one vertex shares: the vertex, its BSDF and guide, its
/// direction bin, its segment, and the whole throughput over `n` its bounces start from.
struct Continuation<'v, 'g> {
    v: &'v Vertex,
    bsdf: &'v Bsdf,
    g: Option<&'v GuideAt<'g>>,
    bin: u8,
    segment: u32,
    next: Vec3,
}
