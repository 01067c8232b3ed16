//! Unidirectional path tracing, with the light found by BSDF sampling, next-event estimation or
//! both under multiple importance sampling ([`LightStrategy`]).
//!
//! A path is built by sampling each bounce from the BSDF with the chosen [`Directions`]
//! strategy; the throughput is `β_{k+1} = β_k · f · cosθᵢ / p_bsdf`. What a vertex `x_k` adds:
//!
//! - `bsdf`: `β_k Le(x_k)` when `x_k` is an emitter seen from its front, or the environment
//!   when the ray escapes (Veach's "BSDF sampling").
//! - `nee`: at every vertex one light sample `y` (direction `ωᵢ`, pdf `p_light` per solid angle)
//!   and a shadow ray: `β_k f(ωₒ, ωᵢ) cosθᵢ Le(y) / p_light` if `y` is visible. Emission reached
//!   by BSDF-sampled rays after the camera ray is not added: the light samples counted it.
//! - `mis`: both, weighted by the power heuristic [`mis_weight`]: the light sample by
//!   `w(p_light, p_bsdf)`, emission hit by a BSDF-sampled ray by `w(p_bsdf, p_light)`, with
//!   `p_bsdf` the pdf of the current `--directions` strategy and `p_light` the pdf with which
//!   light sampling at the previous vertex picks the same direction. For every path both can
//!   make the two weights sum to 1, so the estimator is unbiased.
//!
//! Emission is one-sided (front faces only). Path length: `max_depth` is the largest number of
//! segments of a path, counting the camera ray (1 = only directly visible emitters, as
//! Mitsuba's `max_depth`); a light sample at the vertex ending segment `k` makes a path of
//! `k + 1` segments, so it is taken only where a bounce would be. Russian roulette from the
//! third bounce on keeps a path with probability `q = min(max β, 0.95)` and divides by `q`:
//! unbiased termination, after the light sample of that vertex (roulette does not enter the
//! MIS weights: any weights that sum to 1 keep the estimator unbiased). With a guide, `q` is
//! the larger of that and the guide's [`GuideAt::survival`]: a guided bounce toward a small
//! bright opening has a large pdf, so a small `β`, and the throughput rule alone cut nearly
//! every such path (on the door at 10 s guided MSE 1.2× lower with the guide's rule).
//!
//! With `--directions guided` a bounce samples its direction from the mixture of the Phong
//! lobes and the learned guide of [`crate::guiding`] (one-sample MIS, pdf
//! `α·p_guide + (1−α)·p_bsdf`), and that mixture pdf is `p_bsdf` in both MIS weights above. A
//! training render also records, at each bounce, the radiance that came back along the sampled
//! direction (see [`crate::guiding`]) into a [`Record`] buffer, in the S-tree leaf the spatial
//! box filter picks (jittered by a hash of the vertex and the direction: training only, so the
//! image's samples are untouched).
//!
//! Every bounce draws the same dimensions in the same order ([`BounceSample`], the layout in
//! [`crate::sampler::layout`]), used or not, so a dimension index means the same decision in
//! every sample — which is what stratification needs.
//!
//! Rooms: this module holds the path loop (`Path::trace`: what a vertex adds, the bounce, the
//! roulette) and the one emission weight; `bounce` the bounce's direction (the BSDF's, or the
//! guided mixture's); `direct` the light sample of a vertex (next-event
//! estimation and its MIS weight); `recorder` what a training render keeps of a path
//! (a `PathRecorder`, the guide's records; an image's paths have none), so guided and
//! unguided paths are one loop.

mod bounce;
mod branching;
mod direct;
mod recorder;
pub mod reuse;
pub mod rrs;
mod seen;
pub use seen::{seen, seen_emission, seen_packet, Seen};

pub use branching::MAX_RRS_DEPTH;
pub use recorder::MAX_RECORDED_BOUNCES;
use recorder::{Mixture, PathRecorder, Training};
use reuse::Split;

use crate::accel::TraceStack;
use crate::bsdf::{Bsdf, Directions, Specular};
use crate::guiding::{Guide, GuideAt, Record};
use crate::lights::{LightChoice, LightPoints, LightSampler, LightStrategy};
use crate::math::{luminance, Frame};
use crate::sampler::layout::{BounceSample, LightValues};
use crate::sampler::Sampler;
use crate::scene::{Scene, SurfacePoint};
use glam::Vec3;

mod counts;
mod delta;
use counts::timed;
pub use counts::{
    clock_overhead_ns, Phase, RayCounts, PHASES, PHASE_NAMES, TIMED_PATH_EVERY, TIMED_RAY_EVERY,
};

/// Bounces (vertices after the camera) before Russian roulette may end a path.
pub const RR_START_BOUNCE: u32 = 3;

/// What the integrator needs to know besides the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IntegratorSettings {
    /// Largest number of path segments, counting the camera ray (≥ 1).
    pub max_depth: u32,
    pub directions: Directions,
    pub lights: LightStrategy,
    /// How points on lights are placed and lights chosen.
    pub light_points: LightPoints,
    pub light_choice: LightChoice,
    /// Time one traversal (closest hit or shadow ray) in every [`TIMED_RAY_EVERY`] into
    /// [`RayCounts::trace_ns`]; off unless asked for (`vrpt render --stats`).
    pub time_traces: bool,
    /// Whether a path counts what its camera ray sees directly (the emission of the surface it
    /// hits, or the environment where it escapes). Off for a pixel whose seen emission is
    /// estimated apart, by rays of its own ([`seen_emission`], `--edge-rays`).
    pub camera_emission: bool,
}

/// The power heuristic (β = 2) of Veach & Guibas 1995 for a sample drawn by the strategy of pdf
/// `p_a`, when the strategy of pdf `p_b` could have drawn it too:
/// `w_a = p_a² / (p_a² + p_b²)`. Both pdfs per unit solid angle; `w_a + w_b = 1` whenever
/// either is positive. Written as `1 / (1 + (p_b/p_a)²)` so huge pdfs do not overflow.
#[inline]
pub fn mis_weight(p_a: f32, p_b: f32) -> f32 {
    if p_a <= 0.0 {
        return 0.0;
    }
    let r = p_b / p_a;
    1.0 / (1.0 + r * r)
}

/// What a path carries from vertex to vertex in [`Path::trace`].
struct PathState {
    /// The radiance gathered so far (from the reused second vertex on: the continuation's).
    l: Vec3,
    /// The throughput.
    beta: Vec3,
    /// What roulette multiplies `beta` by to see the path's whole throughput: 1, but for the
    /// continuation of a reusable second vertex, traced with `beta` from 1.
    rr_scale: Vec3,
    /// Whether this path's second vertex is reused ([`reuse`]): from there `l` and `beta`
    /// count from zero and one, the light sample and bounce are kept apart in the split.
    reusing: bool,
    /// The vertex the last ray left; `None` for the camera ray, whose hit counts fully in every
    /// mode.
    prev: Option<Previous>,
}

/// Where a path's ray ends ([`Path::reach`]): escaped, with the environment's radiance and its
/// MIS weight; or at a surface (`t`, the point, `wo`, hit from its front), with what it emits
/// toward the path and its weight, if anything.
enum Reached {
    Escaped(Vec3, f32),
    Surface((f32, SurfacePoint, Vec3, bool), Option<(Vec3, f32)>),
}

/// The vertex a BSDF-sampled ray left from: what the MIS weight of what it hits needs.
#[derive(Clone, Copy, Debug)]
struct Previous {
    /// Position of the vertex.
    p: Vec3,
    /// Its shading normal, on the side the ray left from.
    n: Vec3,
    /// The BSDF pdf of the sampled direction.
    pdf: f32,
    /// Whether the direction came from a delta lobe (a mirror or glass): no light sample could
    /// have found what it reaches, which then counts whole.
    delta: bool,
}

impl Previous {
    /// The vertex `v` a ray left in a direction of BSDF pdf `pdf`.
    #[inline(always)]
    fn left(v: &Vertex, pdf: f32) -> Self {
        Previous {
            p: v.p,
            n: v.ns,
            pdf,
            delta: false,
        }
    }
}

/// Russian roulette after a bounce: the path goes on with probability `q = min(max β, 0.95)`
/// (with a guided bounce the larger of that and the guide's [`GuideAt::survival`]), decided by
/// `u`; a path that goes on has its throughput `beta` divided by `q`. Whether it goes on. The
/// path's whole throughput is `β·scale` (`scale` 1 but for a reused continuation, traced
/// from β = 1).
#[inline(always)]
fn survives(beta: &mut Vec3, scale: Vec3, u: f32, guided: Option<(&GuideAt, &Mixture)>) -> bool {
    let whole = *beta * scale;
    let q = whole.max_element().min(0.95);
    let q = match guided {
        Some((g, mix)) => q.max(g.survival(whole, mix.p_guide)),
        None => q,
    };
    if u >= q {
        return false;
    }
    *beta /= q;
    true
}

/// A surface vertex as a bounce sees it: both normals on the side the ray came from, the
/// shading frame, `wo` in it, and the point new rays leave from.
struct Vertex {
    p: Vec3,
    /// The geometric normal, on the side of `wo`.
    ng: Vec3,
    /// The shading normal, on the side of `wo` (the geometric one where it faced away).
    ns: Vec3,
    frame: Frame,
    wo_local: Vec3,
    /// `p` offset along `ng` by the scene's ray epsilon.
    spawn: Vec3,
}

impl Vertex {
    /// Two-sided shading: both normals are put on the side the ray came from (`wo` points
    /// back along it).
    #[inline(always)]
    fn new(scene: &Scene, s: &SurfacePoint, front: bool, wo: Vec3) -> Self {
        let (ng, mut ns) = if front { (s.ng, s.ns) } else { (-s.ng, -s.ns) };
        if ns.dot(wo) <= 0.0 {
            ns = ng; // the shading normal faces away from the viewer: fall back to geometry
        }
        let frame = Frame::from_normal(ns);
        Vertex {
            p: s.p,
            ng,
            ns,
            wo_local: frame.to_local(wo),
            frame,
            spawn: s.p + ng * scene.ray_epsilon,
        }
    }
}

/// Radiance arriving at `origin` from direction `dir` (unit); rays traced are added to `rays`,
/// on the thread's traversal stack `stack`.
#[inline]
pub fn radiance<S: Sampler>(
    scene: &Scene,
    ray: (Vec3, Vec3),
    sampler: &mut S,
    settings: &IntegratorSettings,
    rays: &mut RayCounts,
    stack: &mut TraceStack,
) -> Vec3 {
    radiance_guided(scene, ray, sampler, settings, rays, stack, None, None)
}

/// [`radiance`] with path guiding: directions of `--directions guided` are sampled from the
/// mixture of the Phong lobes and `guide` (which must be given for them), and with `records`
/// every bounce's radiance record is appended to it (a training iteration).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn radiance_guided<S: Sampler>(
    scene: &Scene,
    ray: (Vec3, Vec3),
    sampler: &mut S,
    settings: &IntegratorSettings,
    rays: &mut RayCounts,
    stack: &mut TraceStack,
    guide: Option<&Guide>,
    records: Option<&mut Vec<Record>>,
) -> Vec3 {
    let path = Path::new(scene, settings, guide);
    match records {
        Some(out) => path.trace(
            ray,
            sampler,
            rays,
            stack,
            Some(&mut Training::new(out)),
            None,
        ),
        None => path.trace(ray, sampler, rays, stack, None, None),
    }
}

/// [`radiance`] for path reuse ([`reuse`]): the path's first vertex, its reusable second vertex
/// and what it found are left in `split` (a fresh [`Split`]) for [`reuse::combine`]. The same
/// numbers are drawn as by [`radiance_guided`] without records.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn radiance_split<'a, S: Sampler>(
    scene: &'a Scene,
    ray: (Vec3, Vec3),
    sampler: &mut S,
    settings: &'a IntegratorSettings,
    rays: &mut RayCounts,
    stack: &mut TraceStack,
    guide: Option<&'a Guide>,
    split: &mut Split,
) {
    Path::new(scene, settings, guide).trace(ray, sampler, rays, stack, None, Some(split));
}

/// [`radiance_guided`] under `--roulette ears` ([`rrs`]): the path splits and ends by the
/// factors `rrs` gives, and a training iteration's continuations are recorded there. No guide
/// records: a guide learns from classic paths before.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn radiance_rrs<S: Sampler>(
    scene: &Scene,
    ray: (Vec3, Vec3),
    sampler: &mut S,
    settings: &IntegratorSettings,
    rays: &mut RayCounts,
    stack: &mut TraceStack,
    guide: Option<&Guide>,
    rrs: &mut rrs::RrsPath,
) -> Vec3 {
    let path = Path::new(scene, settings, guide);
    path.trace_rrs(ray, None, 1, Vec3::ONE, sampler, rays, stack, rrs)
}

/// What every vertex of one path's estimate reads: the scene, the settings, the light sampler
/// they choose and the guide (only for guided directions).
struct Path<'a> {
    scene: &'a Scene,
    settings: &'a IntegratorSettings,
    lights: LightSampler<'a>,
    guide: Option<&'a Guide>,
    /// Whether vertices take a light sample (`nee` or `mis`, and the scene has a light).
    sample_lights: bool,
    /// The light values a Phong vertex draws: none without light samples, and the choice only
    /// where the chooser has more than one light to choose from.
    light_values: LightValues,
}

impl<'a> Path<'a> {
    fn new(scene: &'a Scene, settings: &'a IntegratorSettings, guide: Option<&'a Guide>) -> Self {
        let lights = scene
            .lights
            .sampler(settings.light_points, settings.light_choice);
        let sample_lights = settings.lights != LightStrategy::Bsdf && lights.any();
        Path {
            scene,
            settings,
            sample_lights,
            light_values: LightValues::of(sample_lights, lights.chooses()),
            lights,
            guide: guide.filter(|_| settings.directions == Directions::Guided),
        }
    }

    /// The estimate of one path from `ray`: emission found by the path (weighted by
    /// [`Self::emission_weight`]), a light sample at every vertex ([`Self::next_event`]), a
    /// bounce ([`Self::sample_direction`]) and Russian roulette ([`Self::surface_vertex`] at a
    /// Phong vertex, [`Self::delta_vertex`] at a mirror or glass); `rec`, where there is one (a
    /// training iteration), sees every guided bounce and the path's end.
    #[inline(always)]
    fn trace<S: Sampler>(
        &self,
        (mut origin, mut dir): (Vec3, Vec3),
        sampler: &mut S,
        rays: &mut RayCounts,
        stack: &mut TraceStack,
        mut rec: Option<&mut dyn PathRecorder>,
        mut split: Option<&mut Split>,
    ) -> Vec3 {
        let (scene, settings) = (self.scene, self.settings);
        let mut st = PathState {
            l: Vec3::ZERO,
            beta: Vec3::ONE,
            rr_scale: Vec3::ONE,
            reusing: false,
            prev: None,
        };
        // whether a Phong vertex came before: emission then reached through a delta lobe is a
        // caustic ([`RayCounts::caustic`])
        let mut phong_before = false;
        // the light found up to the second vertex's emission ([`RayCounts::indirect`])
        let mut direct = None;
        for segment in 1..=settings.max_depth {
            let caustic = phong_before && st.prev.is_some_and(|p| p.delta);
            let (at, found) = match self.reach(st.prev, (origin, dir), rays, stack) {
                Reached::Escaped(le, w) => (None, st.beta * le * w),
                Reached::Surface(at, Some((le, w))) => (Some(at), st.beta * le * w),
                Reached::Surface(at, None) => (Some(at), Vec3::ZERO),
            };
            st.l += found;
            if caustic {
                rays.caustic += luminance(found) as f64;
            }
            if segment == 2 {
                direct = Some(st.l);
            }
            let Some((t, s, wo, front)) = at else { break };
            if segment == settings.max_depth {
                rays.mark(Phase::Shade);
                break;
            }
            let bsdf = scene.bsdf_at(&s);
            let delta = scene.material_at(&s).specular.filter(|d| !d.is_black());
            let next = if let Some(d) = delta {
                let v = Vertex::new(scene, &s, front, wo);
                let lobes = (d, scene.material_at(&s).delta_share, front);
                let beta = (&mut st.beta, st.rr_scale);
                let (nee, next) =
                    self.delta_vertex(&v, &bsdf, lobes, segment, sampler, beta, rays, stack);
                st.l += nee;
                next.map(|(o, wi, p)| ((o, wi), p))
            } else {
                if bsdf.is_black() {
                    break;
                }
                phong_before = true;
                let at = (segment, &s, front, wo, t);
                let (rec, split) = (rec.as_deref_mut(), split.as_deref_mut());
                self.surface_vertex(at, &bsdf, sampler, rays, stack, rec, split, &mut st)
            };
            let Some((ray, p)) = next else { break };
            ((origin, dir), st.prev) = (ray, Some(p));
        }
        rays.light += luminance(st.l) as f64;
        rays.indirect += match (st.reusing, direct) {
            (true, _) => luminance(st.l),
            (false, Some(d)) => luminance(st.l - d).max(0.0),
            (false, None) => 0.0,
        } as f64;
        if let Some(rec) = rec {
            rec.finish(st.l);
        }
        if let Some(sp) = split {
            sp.finish(st.l, st.reusing);
        }
        st.l
    }

    /// Where the ray `(origin, dir)`, left from `prev` (`None`: the camera), ends, the ray
    /// counted in `rays`: the environment's radiance and its weight
    /// ([`Self::emission_weight`]) where it escapes, else the surface (`t` along the ray, the
    /// point, `wo`, whether it was hit from its front) and what it emits toward the path with
    /// its weight ([`Self::emitted`]).
    #[inline(always)]
    fn reach(
        &self,
        prev: Option<Previous>,
        (origin, dir): (Vec3, Vec3),
        rays: &mut RayCounts,
        stack: &mut TraceStack,
    ) -> Reached {
        let scene = self.scene;
        *if prev.is_none() {
            &mut rays.camera
        } else {
            &mut rays.bounce
        } += 1;
        let hit = timed(self.settings.time_traces, rays, || {
            scene.intersect(stack, origin, dir, f32::INFINITY)
        });
        rays.mark(Phase::Trace);
        let Some(hit) = hit else {
            let w = self.emission_weight(prev, |v| self.lights.environment_pdf(v.n, dir));
            return Reached::Escaped(scene.environment().radiance(dir), w);
        };
        let s = scene.surface(&hit);
        let wo = -dir;
        let front = s.ng.dot(wo) > 0.0;
        let emitted = self.emitted(prev, hit.prim, &s, front);
        Reached::Surface((hit.t, s, wo, front), emitted)
    }

    /// The vertex ending segment `segment` at surface point `s` (hit from `wo`, from its
    /// `front` or not, `t` along the ray) with the Phong BSDF `bsdf`: a light sample, a bounce
    /// and Russian roulette, the guide asked where there is one, the second vertex handed to
    /// path reuse's `split` where it is reused. The next ray (origin, direction) and the vertex
    /// it leaves, or `None` where the path ends.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn surface_vertex<'r, S: Sampler>(
        &self,
        (segment, s, front, wo, t): (u32, &SurfacePoint, bool, Vec3, f32),
        bsdf: &Bsdf,
        sampler: &mut S,
        rays: &mut RayCounts,
        stack: &mut TraceStack,
        rec: Option<&mut (dyn PathRecorder + 'r)>,
        mut split: Option<&mut Split>,
        st: &mut PathState,
    ) -> Option<((Vec3, Vec3), Previous)> {
        let (scene, settings) = (self.scene, self.settings);
        rays.mark(Phase::Shade);
        // values this bounce cannot use are skipped, not drawn (the same image, fewer hashes)
        let u = BounceSample::draw_needed(
            sampler,
            self.light_values,
            bsdf.chooses_lobe(settings.directions),
            segment >= RR_START_BOUNCE,
            settings.directions == Directions::Guided,
        );
        rays.mark(Phase::Sampler);
        let v = Vertex::new(scene, s, front, wo);
        let diffuse = bsdf.diffuse_share();
        let g = match (self.guide, rec.is_some()) {
            (Some(t), true) => Some(GuideAt::new(t, s.p).for_bsdf(diffuse)),
            (Some(t), false) => GuideAt::for_image(t, s.p, diffuse),
            (None, _) => None,
        };
        rays.mark(Phase::Shade);
        if let Some(sp) = split.as_deref_mut().filter(|_| segment <= 2) {
            let arrival = (st.prev.map_or(0.0, |p| p.pdf), t, -wo);
            st.reusing = sp.vertex(segment, &v, *bsdf, settings.directions, arrival);
            if st.reusing {
                (sp.own, st.l) = (st.l, Vec3::ZERO);
            }
        }
        let tail = st.reusing && segment == 2;
        if tail {
            let h = self.light_sample(&v, (bsdf, 1.0), g.as_ref(), &u, rays, stack);
            split.as_deref_mut().unwrap().light_at_tail(h);
        } else if let Some(d) =
            self.next_event(&v, (bsdf, 1.0), g.as_ref(), &u, st.beta, rays, stack)
        {
            st.l += d;
        }
        let sampled = self.sample_direction(&v, bsdf, g.as_ref(), &u);
        rays.mark(Phase::Bsdf);
        let (wi, bs, mix) = sampled?;
        if wi.dot(v.ng) <= 0.0 {
            return None; // below the geometric surface: no light passes through
        }
        if tail {
            // the continuation counts from here: its throughput relative to this bounce's
            st.rr_scale = st.beta * bs.f * (bs.wi.z / bs.pdf);
            st.beta = Vec3::ONE;
            split.unwrap().bounce_at_tail(bs.wi, bs.pdf);
        } else {
            st.beta *= bs.f * (bs.wi.z / bs.pdf);
        }
        if let (Some(g), Some(mix), Some(rec)) = (&g, &mix, rec) {
            rec.bounce(g, v.p, mix, &bs, st.beta, st.l);
        }
        // segment = the vertices so far after the camera
        let guided = g.as_ref().zip(mix.as_ref());
        if segment >= RR_START_BOUNCE && !survives(&mut st.beta, st.rr_scale, u.roulette, guided) {
            return None;
        }
        Some(((v.spawn, wi), Previous::left(&v, bs.pdf)))
    }

    /// What the surface hit at `s` (primitive `prim`, seen from its front or not) emits toward
    /// the path, and its weight ([`Self::emission_weight`]); `None` where it emits nothing.
    #[inline(always)]
    fn emitted(
        &self,
        prev: Option<Previous>,
        prim: u32,
        s: &SurfacePoint,
        front: bool,
    ) -> Option<(Vec3, f32)> {
        let m = self.scene.material_at(s);
        if !(front && m.is_emissive()) {
            return None;
        }
        let w = self.emission_weight(prev, |v| {
            let light = self.scene.lights.light_of(prim);
            light.map_or(0.0, |i| self.lights.pdf(i, v.p, v.n, s.p))
        });
        Some((m.emission, w))
    }

    /// The weight of emission a path reaches (a surface's, or the environment's where it
    /// escapes), seen from the vertex `prev` it left (`None`: the camera): 1 for the camera ray,
    /// under `bsdf` and after a delta lobe (no light sample can reach through one), 0 under
    /// `nee` (the light samples counted it), and under `mis` `w(p_bsdf, p_light)` with
    /// `p_light(prev)` the pdf light sampling at `prev` gives it.
    #[inline(always)]
    fn emission_weight(
        &self,
        prev: Option<Previous>,
        p_light: impl FnOnce(&Previous) -> f32,
    ) -> f32 {
        match (self.settings.lights, prev) {
            // what the camera sees is estimated apart where it does not count here
            (_, None) if !self.settings.camera_emission => 0.0,
            (_, None) | (LightStrategy::Bsdf, _) => 1.0,
            (_, Some(v)) if v.delta => 1.0,
            (LightStrategy::Nee, _) => 0.0,
            (LightStrategy::Mis, Some(v)) => mis_weight(v.pdf, p_light(&v)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_heuristic_weights_sum_to_one() {
        for (a, b) in [(1.0f32, 1.0f32), (0.1, 10.0), (1e30, 1e-30), (3.0, 0.0)] {
            let s = mis_weight(a, b) + mis_weight(b, a);
            assert!((s - 1.0).abs() < 1e-6, "{a} {b}: {s}");
        }
        assert_eq!(mis_weight(0.0, 1.0), 0.0);
        assert!((mis_weight(1.0, 1.0) - 0.5).abs() < 1e-7);
        assert!((mis_weight(2.0, 1.0) - 0.8).abs() < 1e-7);
    }
}
