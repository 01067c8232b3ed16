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

use crate::accel::TraceStack;
use crate::bsdf::Directions;
use crate::guiding::{canonical_to_dir, dir_to_canonical, GuideAt, Record, SdTree};
use crate::lights::{LightChoice, LightPoints, LightStrategy};
use crate::math::Frame;
use crate::sampler::layout::BounceSample;
use crate::sampler::Sampler;
use crate::scene::Scene;
use glam::Vec3;

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
    /// Factor on the guided mixture pdf the estimator divides by: 1, except in the tests that
    /// show a wrong pdf is caught.
    #[doc(hidden)]
    pub guide_pdf_scale: f32,
}

/// Rays traced, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    pub camera: u64,
    /// Rays continuing a path after a bounce.
    pub bounce: u64,
    /// Occlusion rays toward light samples.
    pub shadow: u64,
    /// Nanoseconds spent in the timed traversals, when [`IntegratorSettings::time_traces`]
    /// is on.
    pub trace_ns: u64,
    /// How many traversals were timed.
    pub timed: u64,
}

impl RayCounts {
    /// All rays.
    pub fn total(&self) -> u64 {
        self.camera + self.bounce + self.shadow
    }

    /// Add `o`'s counts.
    pub fn add(&mut self, o: &RayCounts) {
        self.camera += o.camera;
        self.bounce += o.bounce;
        self.shadow += o.shadow;
        self.trace_ns += o.trace_ns;
        self.timed += o.timed;
    }

    /// Estimated time in BVH traversal: the timed rays' time, less the clock's own cost inside
    /// each interval ([`clock_overhead_ns`]), scaled to all rays (the timed ones are every
    /// [`TIMED_RAY_EVERY`]-th ray by count, of every kind).
    pub fn trace_seconds(&self) -> f64 {
        if self.timed == 0 {
            return 0.0;
        }
        let ns = (self.trace_ns as f64 - self.timed as f64 * clock_overhead_ns()).max(0.0);
        ns * 1e-9 * self.total() as f64 / self.timed as f64
    }
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

/// With timing on, one ray in this many is timed: two clock reads (~40 ns here) on every ray
/// would add a fifth to the render and inflate the traced share; one in 16 costs ~1%.
pub const TIMED_RAY_EVERY: u64 = 16;

/// The most one timed traversal counts, in nanoseconds: 16× the slowest ray measured (0.63 µs
/// per incoherent ray through 4 million triangles); longer intervals are preemption.
const MAX_TRACE_NS: u64 = 10_000;

/// What an empty interval of `timed` measures (the clock read's own cost), in nanoseconds:
/// the mean of 10,000 empty intervals, measured once per process.
pub fn clock_overhead_ns() -> f64 {
    static OVERHEAD: std::sync::OnceLock<f64> = std::sync::OnceLock::new();
    *OVERHEAD.get_or_init(|| {
        let n = 10_000u32;
        let mut total = 0u128;
        for _ in 0..n {
            let start = std::time::Instant::now();
            total += std::hint::black_box(start).elapsed().as_nanos();
        }
        total as f64 / n as f64
    })
}

/// `f()` (a traversal, already counted in `rays`), timed when `on` and it is the
/// [`TIMED_RAY_EVERY`]-th ray.
#[inline(always)]
fn timed<T>(on: bool, rays: &mut RayCounts, f: impl FnOnce() -> T) -> T {
    if on && rays.total().is_multiple_of(TIMED_RAY_EVERY) {
        let start = std::time::Instant::now();
        let r = f();
        // an interval longer than any traversal is the thread being descheduled: scaled by
        // TIMED_RAY_EVERY it would swamp the estimate, so it counts as MAX_TRACE_NS
        rays.trace_ns += (start.elapsed().as_nanos() as u64).min(MAX_TRACE_NS);
        rays.timed += 1;
        r
    } else {
        f()
    }
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

/// Bounces of a path whose radiance a training render records (the rest are not recorded).
pub const MAX_RECORDED_BOUNCES: usize = 16;

/// A bounce whose record waits for the rest of the path.
#[derive(Clone, Copy, Debug, Default)]
struct Pending {
    leaf: u32,
    point: glam::Vec2,
    /// The throughput after the bounce: `β·f·cosθ/p` (before Russian roulette).
    beta: Vec3,
    /// The path's radiance when the bounce's record starts counting.
    l_start: Vec3,
    /// `f·cosθ` of the direction.
    f_cos: Vec3,
    /// The direction's (mixture) pdf, and its BSDF and guide pdfs.
    pdf: f32,
    p_bsdf: f32,
    p_guide: f32,
}

/// [`radiance`] with path guiding: directions of `--directions guided` are sampled from the
/// mixture of the Phong lobes and `guide` (which must be given for them), and with `records`
/// every bounce's radiance record is appended to it (a training iteration).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn radiance_guided<S: Sampler>(
    scene: &Scene,
    (mut origin, mut dir): (Vec3, Vec3),
    sampler: &mut S,
    settings: &IntegratorSettings,
    rays: &mut RayCounts,
    stack: &mut TraceStack,
    guide: Option<&SdTree>,
    records: Option<&mut Vec<Record>>,
) -> Vec3 {
    let guided = settings.directions == Directions::Guided;
    let guide = if guided { guide } else { None };
    // only a training render keeps bounces waiting for their records (no array otherwise)
    let mut pending = records
        .is_some()
        .then(|| [Pending::default(); MAX_RECORDED_BOUNCES]);
    let mut n_pending = 0usize;
    // whether the previous bounce's direction awaits its record (pending[n_pending - 1])
    let mode = settings.lights;
    let lights = scene
        .lights
        .sampler(settings.light_points, settings.light_choice);
    let sample_lights = mode != LightStrategy::Bsdf && lights.any();
    let mut l = Vec3::ZERO;
    let mut beta = Vec3::ONE;
    // None for the camera ray: what it sees counts fully in every mode
    let mut prev: Option<Previous> = None;
    for segment in 1..=settings.max_depth {
        if prev.is_none() {
            rays.camera += 1;
        } else {
            rays.bounce += 1;
        }
        let Some(hit) = timed(settings.time_traces, rays, || {
            scene.intersect(stack, origin, dir, f32::INFINITY)
        }) else {
            let w = match (mode, prev) {
                (_, None) | (LightStrategy::Bsdf, _) => 1.0,
                (LightStrategy::Nee, _) => 0.0,
                (LightStrategy::Mis, Some(v)) => {
                    mis_weight(v.pdf, lights.environment_pdf(v.n, dir))
                }
            };
            let le = scene.environment().radiance(dir);
            l += beta * le * w;
            break;
        };
        let s = scene.surface(&hit);
        let m = scene.material_at(&s);
        let wo = -dir;
        let front = s.ng.dot(wo) > 0.0;
        if front && m.is_emissive() {
            let w = match (mode, prev) {
                (_, None) | (LightStrategy::Bsdf, _) => 1.0,
                (LightStrategy::Nee, _) => 0.0,
                (LightStrategy::Mis, Some(v)) => {
                    let p_light = scene
                        .lights
                        .light_of(hit.prim)
                        .map_or(0.0, |i| lights.pdf(i, v.p, v.n, s.p));
                    mis_weight(v.pdf, p_light)
                }
            };
            l += beta * m.emission * w;
        }
        if segment == settings.max_depth {
            break;
        }
        let bsdf = scene.bsdf_at(&s);
        if bsdf.is_black() {
            break;
        }
        // values this bounce cannot use are skipped, not drawn (the same image, fewer hashes)
        let u = BounceSample::draw_needed(
            sampler,
            sample_lights,
            bsdf.chooses_lobe(settings.directions),
            segment >= RR_START_BOUNCE,
            guided,
        );
        // Two-sided shading: put both normals on the side the ray came from.
        let (ng, mut ns) = if front { (s.ng, s.ns) } else { (-s.ng, -s.ns) };
        if ns.dot(wo) <= 0.0 {
            ns = ng; // the shading normal faces away from the viewer: fall back to geometry
        }
        let frame = Frame::from_normal(ns);
        let wo_local = frame.to_local(wo);
        let spawn = s.p + ng * scene.ray_epsilon;
        let g = guide.map(|t| GuideAt::new(t, s.p));
        if sample_lights {
            if let Some(ls) = lights.sample(s.p, ns, u.light, u.light_point) {
                let wi_local = frame.to_local(ls.wi);
                // light from below the geometric surface cannot arrive (as for BSDF samples)
                if ls.wi.dot(ng) > 0.0 && wi_local.z > 0.0 {
                    let f = bsdf.eval(wo_local, wi_local);
                    if f.max_element() > 0.0 {
                        let (to, tmax) = if ls.dist.is_finite() {
                            let y = s.p + ls.wi * ls.dist;
                            let d = y - spawn;
                            let len = d.length();
                            (d / len, len - 2.0 * scene.ray_epsilon)
                        } else {
                            (ls.wi, f32::INFINITY)
                        };
                        rays.shadow += 1;
                        if tmax > 0.0
                            && !timed(settings.time_traces, rays, || {
                                scene.occluded(stack, spawn, to, tmax)
                            })
                        {
                            let w = match mode {
                                LightStrategy::Mis => {
                                    let p = bsdf.pdf(wo_local, wi_local, settings.directions);
                                    let p = g.map_or(p, |g| g.mixture_pdf(ls.wi, p));
                                    mis_weight(ls.pdf, p)
                                }
                                _ => 1.0,
                            };
                            l += beta * f * ls.le * (wi_local.z * w / ls.pdf);
                        }
                    }
                }
            }
        }
        // with a guide: the direction's canonical point, and its BSDF and guide pdfs
        let (wi, bs, mix) = match g {
            Some(g) => {
                // one-sample MIS of the guide and the BSDF, weighted by the mixture pdf
                // (direction, canonical point, local direction, f, BSDF pdf, guide pdf)
                let (wi, c, wi_local, f, p_bsdf, p_guide) = if u.guide < g.alpha {
                    // the density comes from the descent that drew the point
                    let (c, p_c) = g.dtree.sample_canonical_pdf(u.guided_direction);
                    let wi = canonical_to_dir(c);
                    let wi_local = frame.to_local(wi);
                    if wi_local.z <= 0.0 {
                        break; // a guided direction below the surface: a failed sample
                    }
                    let p_bsdf = bsdf.pdf(wo_local, wi_local, settings.directions);
                    let f = bsdf.eval(wo_local, wi_local);
                    (wi, c, wi_local, f, p_bsdf, p_c * GuideAt::PER_STERADIAN)
                } else {
                    let Some(bs) = bsdf.sample(wo_local, u.lobe, u.direction, settings.directions)
                    else {
                        break;
                    };
                    let wi = frame.to_world(bs.wi);
                    let c = dir_to_canonical(wi);
                    (wi, c, bs.wi, bs.f, bs.pdf, g.guide_pdf_canonical(c))
                };
                let (pdf, p_guide) = (g.mixture(p_guide, p_bsdf), p_guide);
                let pdf = pdf * settings.guide_pdf_scale;
                if !(pdf > 0.0 && pdf.is_finite()) {
                    break;
                }
                let bs = crate::bsdf::BsdfSample {
                    wi: wi_local,
                    f,
                    pdf,
                };
                (wi, bs, Some((c, p_bsdf, p_guide)))
            }
            None => {
                let Some(bs) = bsdf.sample(wo_local, u.lobe, u.direction, settings.directions)
                else {
                    break;
                };
                (frame.to_world(bs.wi), bs, None)
            }
        };
        if wi.dot(ng) <= 0.0 {
            break; // below the geometric surface: no light passes through
        }
        beta *= bs.f * (bs.wi.z / bs.pdf);
        if let (Some(g), Some((c, p_bsdf, p_guide)), Some(pending)) = (g, mix, &mut pending) {
            if n_pending < MAX_RECORDED_BOUNCES {
                let h = crate::math::hash_words(&[
                    s.p.x.to_bits() as u64 | (s.p.y.to_bits() as u64) << 32,
                    s.p.z.to_bits() as u64 | (c.x.to_bits() as u64) << 32,
                    c.y.to_bits() as u64,
                ]);
                let jitter = Vec3::new(
                    crate::math::u64_to_unit_f32(h),
                    crate::math::u64_to_unit_f32(crate::math::mix64(h ^ 1)),
                    crate::math::u64_to_unit_f32(crate::math::mix64(h ^ 2)),
                );
                pending[n_pending] = Pending {
                    leaf: g.tree.splat_leaf(s.p, jitter),
                    point: c,
                    beta,
                    l_start: l,
                    f_cos: bs.f * bs.wi.z,
                    pdf: bs.pdf,
                    p_bsdf,
                    p_guide,
                };
                n_pending += 1;
            }
        }
        let bounce = segment; // vertices so far after the camera
        if bounce >= RR_START_BOUNCE {
            let mut q = beta.max_element().min(0.95);
            if let (Some(g), Some((_, _, p_guide))) = (g, mix) {
                q = q.max(g.survival(beta, p_guide));
            }
            if u.roulette >= q {
                break;
            }
            beta /= q;
        }
        prev = Some(Previous {
            p: s.p,
            n: ns,
            pdf: bs.pdf,
        });
        origin = spawn;
        dir = wi;
    }
    if let (Some(out), Some(pending)) = (records, &pending) {
        for v in &pending[..n_pending] {
            // L_i ≈ ΔL / β per channel (where β carries anything), averaged over the channels
            let d = l - v.l_start;
            let (mut li, mut product) = (0.0, 0.0);
            for c in 0..3 {
                if v.beta[c] > 1e-12 {
                    let lc = d[c] / v.beta[c];
                    li += lc;
                    product += lc * v.f_cos[c];
                }
            }
            let value = li / (3.0 * v.pdf);
            if value.is_finite() && value >= 0.0 {
                out.push(Record {
                    leaf: v.leaf,
                    point: v.point,
                    value,
                    product: product / 3.0,
                    pdf: v.pdf,
                    p_bsdf: v.p_bsdf,
                    p_guide: v.p_guide,
                });
            }
        }
    }
    l
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
