//! Edge rays (`--edge-rays M`): the emission a pixel sees directly, estimated apart in the
//! pixels where it varies, by as many rays (at most `M`) as its variance asks.
//!
//! A pixel's value is `I = ∫ (E(u) + R(u)) du` over its area (`u ∈ [0,1)²`, the box filter),
//! with `E(u)` what the camera ray through `u` sees directly (a light's emission from its front,
//! the environment where it escapes) and `R(u)` the rest of the path. Where `E` varies across
//! the pixel (along the edge of a light, of the sun's disc) it is a step whose height is the
//! light's whole radiance, and a path sees one side or the other: on Mitsuba's Cornell box
//! (256², 64 spp) the 0.3% of pixels along the light's edge carry 23% of the default's MSE and
//! 66% of `--reuse 4`'s. There each sample estimates the two terms apart: `E` by the mean over
//! `M` camera rays of its own, which look for nothing but what they see ([`seen_emission`]: a
//! closest hit each, no shading, no light sample), and `R` by the path, whose camera ray no
//! longer counts what it sees
//! ([`crate::integrator::IntegratorSettings::camera_emission`]). Both estimates are unbiased,
//! so their sum is.
//!
//! The `M` points of sample `s` are points `s·M … s·M + M − 1` of the pixel's own
//! Owen-scrambled Sobol sequence in its first two dimensions (a (0,2)-sequence; Burley 2020,
//! keyed by the render's seed and the pixel; every point uniform on the pixel): over `N`
//! samples the `N·M` points are one stratified set, so across a straight edge the variance of
//! `E`'s estimate falls as `(NM)^(−3/2)`, not `(NM)^(−1)`. A replicate's or a training
//! iteration's seed gives other points; samples past 2¹⁶ points continue in a sequence of
//! another key (unbiased; not stratified across the seam).
//!
//! Which pixels (`EdgeMap`): before any sample, a probe of 2×2 camera rays per pixel, at the
//! centres of its quarters (fixed points, no random numbers: the choice is independent of every
//! sample, so each pixel's estimator is unbiased whichever it gets). A pixel is an edge pixel
//! where the probes of a 4×4 window of the probe grid, its own 2×2 and the ring next to it in
//! its neighbours, differ in some channel by more than [`EDGE_CONTRAST`] of the largest value
//! (a sky's gradient is not an edge) and one of them saw a light, or all of them saw the sky and
//! the step is a light in it ([`SKY_STEP`]): an edge between two neighbouring probes lies in one
//! of the two pixels they belong to, and both are flagged. Why a light or only sky: splitting
//! pays where `R` is small on both sides of the step (a light's own reflection, or nothing past
//! the sky), and can lose where it is not: at a roof against a bright sky the sum `E + R` steps
//! little (the lit roof is about as bright as the sky) while `R` alone steps by the roof's whole
//! radiance. On `scenes/sun-sky` such silhouettes and the sky map's texel steps were 389 of
//! 12288 pixels, and split there its MSE did not move (1.254e-4 against 1.253e-4) while its
//! time grew. A light smaller than half a pixel can fall between the probes; its pixels keep
//! the plain estimator. The probe costs four closest-hit rays a pixel (a tile's ring included,
//! ~5), once per render.
//!
//! How many (`M_i` in edge pixel `i`, at most `--edge-rays`): with `a_i` the variance of one
//! edge ray's `E` there, `b_j` a pixel's path variance and `c_e`, `c_p` the costs of an edge ray
//! and a path, the image's MSE times its time over `N` samples is `(Σ a_i/M_i + B)(C + c_e Σ M_i)`
//! with `B = Σ b_j` and `C = P·c_p` over the `P` pixels, least at `M_i = λ√a_i`, `λ = √(C/(c_e B))`.
//! A pilot after the probe estimates them, on fixed points no sample uses: `a_i` from
//! 16 edge rays in each edge pixel (at least the variance of the window's step
//! seen by one ray in 32: a pilot that saw one side only), `B` from two independent unguided
//! paths in one pixel in 16 (`(x₁ − x₂)²/2`), `c_p/c_e` as twice a pilot path's rays. Where the
//! paths hardly vary (`B` near 0: a scene that is all emission) `λ` is bounded so the edge rays
//! cost at most 4 times the paths. The counts are fixed before any sample (and the
//! same on any number of threads), so each pixel's estimator stays unbiased whatever it gets.
//! The pilot costs about 1/8 of a sample a pixel and 16 rays an edge pixel.
//!
//! [`seen_emission`]: crate::integrator::seen_emission

use super::{PassPlan, RenderSettings, RenderStats, TILE};
use crate::accel::{TraceStack, LANES};
use crate::bsdf::Directions;
use crate::camera::Camera;
use crate::integrator::{radiance, seen, seen_packet, IntegratorSettings, RayCounts, Seen};
use crate::math::hash_words;
use crate::sampler::layout::CameraSample;
use crate::sampler::{IndependentSampler, Sampler};
use crate::scene::Scene;
use glam::{UVec2, Vec2, Vec3};
use rayon::prelude::*;
use std::f64::consts::PI;
use std::sync::Arc;

/// The default `--edge-rays`, the most a sample spends in a pixel: the allocation (see the
/// module doc) decides below it. Against 16 in every edge pixel (the default before), over the
/// shipped scenes at 64 spp (`tools/readme_numbers.py`'s efficiency recipe, seeds 1–4,
/// interleaved): textured 5.7× as efficient, glossy plates 1.18×, checker-plane 1.04×,
/// lit-checker 0.90×, the rest 0.95–1.06× (no edge pixel in the door and the sky scene: noise);
/// 1.25× in the geometric mean.
pub const DEFAULT_EDGE_RAYS: u32 = 256;

/// The largest `--edge-rays`.
pub const MAX_EDGE_RAYS: u32 = 256;

/// A pixel is an edge pixel where its probes' window differs in some channel by more than this
/// share of its largest value and one probe saw a light (a sky's gradient across a pixel is
/// ~1%: not an edge).
pub const EDGE_CONTRAST: f32 = 0.25;

/// Where every probe of the window saw the sky, the step must also exceed this many times the
/// environment's mean radiance (luminance): a light in the sky (the sun's disc), not the sky's
/// own edges (on `scenes/sun-sky`, where the sky map meets its dark lower half, 226 pixels split
/// at [`EDGE_CONTRAST`] alone cost 7–10% of the time and left the MSE where it was, 1.253e-4).
pub const SKY_STEP: f32 = 10.0;

/// The edge map of a render (or a guide's training) of `settings` under `plan` through
/// `camera`: the plan's ([`super::PassPlan::edges`]), else the one [`edge_map`] finds.
pub(super) fn of_plan(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    plan: &PassPlan,
) -> Option<Arc<EdgeMap>> {
    (plan.edges.clone()).or_else(|| edge_map(scene, camera, settings, plan).map(Arc::new))
}

/// The edge map of a render of `settings` under `plan` through `camera` ([`of_plan`]), its
/// edge pixels counted in `stats`, and the rays that found it where the render found it (a map
/// handed in the plan was found, and its rays counted, by its finder: auto's pilots, each
/// handed the map, counted it in their cost in rays before, the same ~5 rays a pixel added to
/// every candidate's cost, which drew the efficiency ratios toward one).
pub(super) fn of_render(
    scene: &Scene,
    camera: &Camera,
    (settings, plan): (&RenderSettings, &PassPlan),
    stats: &mut RenderStats,
) -> Option<Arc<EdgeMap>> {
    let edges = of_plan(scene, camera, settings, plan);
    if let Some(e) = &edges {
        if plan.edges.is_none() {
            stats.rays.add(&e.rays);
            stats.edge_finding = e.rays.edge;
        }
        stats.edge_pixels = e.count;
    }
    edges
}

/// The edge pixels of a render of `settings` under `plan` through `camera` (the image's, where
/// it renders a strip), and the edge rays a sample spends in each; `None` without them.
pub(crate) fn edge_map(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    plan: &PassPlan,
) -> Option<EdgeMap> {
    let (image, alloc) = edge_allocation(settings, plan)?;
    Some(EdgeMap::new(scene, camera, image, alloc))
}

/// The image size and the allocation [`edge_map`] finds a render's map with; `None` without
/// edge rays.
fn edge_allocation(settings: &RenderSettings, plan: &PassPlan) -> Option<(UVec2, Allocation)> {
    if settings.edge_rays == 0 {
        return None;
    }
    let image = plan
        .strip
        .as_ref()
        .map_or(UVec2::new(settings.width, settings.height), |s| s.image);
    let alloc = Allocation {
        seed: settings.seed,
        integrator: settings.integrator(),
        most: settings.edge_rays,
    };
    Some((image, alloc))
}

/// Whether `map` is the edge map a render of `settings` under `plan` would find itself.
pub(crate) fn edges_fit(map: &EdgeMap, settings: &RenderSettings, plan: &PassPlan) -> bool {
    edge_allocation(settings, plan).is_some_and(|(image, alloc)| map.fits(image, alloc))
}

/// Which of an image's pixels see an edge of emission, and how many edge rays a sample spends
/// in each (see the module doc).
#[derive(Debug, PartialEq)]
pub struct EdgeMap {
    /// The image's size and the allocation the map was found for ([`EdgeMap::fits`]).
    made_for: (UVec2, Allocation),
    width: u32,
    /// Edge rays a sample in each pixel (0: not an edge pixel), row-major.
    rays_at: Vec<u16>,
    /// How many pixels are edge pixels.
    pub(super) count: u64,
    /// The probe's rays (the pilot's paths' too).
    pub(super) rays: RayCounts,
}

/// What the allocation of edge rays is computed from (see the module doc): the render's seed
/// (the pilot's points are keyed by it, apart from every sample's), its integrator (the
/// pilot's paths, their directions unguided) and the most edge rays a sample spends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Allocation {
    pub(super) seed: u64,
    pub(super) integrator: IntegratorSettings,
    pub(super) most: u32,
}

/// What one tile's probe found: per pixel (row by row) whether it is an edge pixel and the
/// variance `a` of one edge ray's estimate there (mean over channels; 0 elsewhere), and its
/// pilot paths: their number, rays, and the sum of their pixels' variance estimates.
struct TileProbe {
    flags: Vec<bool>,
    a: Vec<f32>,
    paths: u64,
    path_rays: u64,
    b: f64,
}

impl EdgeMap {
    /// The map of the `image`-sized image seen through `camera`, probed over all its tiles,
    /// with its edge rays allocated by `alloc` (a strip's map is the image's: the allocation
    /// weighs each edge pixel against the whole image's paths, so a strip renders its tiles as
    /// the image does).
    pub(super) fn new(scene: &Scene, camera: &Camera, image: UVec2, alloc: Allocation) -> Self {
        let origins: Vec<UVec2> = (0..image.y.div_ceil(TILE))
            .flat_map(|ty| (0..image.x.div_ceil(TILE)).map(move |tx| UVec2::new(tx, ty) * TILE))
            .collect();
        let tiles: Vec<(UVec2, TileProbe, RayCounts)> = origins
            .par_iter()
            .map(|&o| {
                let mut rays = RayCounts::default();
                let probe = tile_edges(scene, camera, (image, o), alloc, &mut rays);
                (o, probe, rays)
            })
            .collect();
        let mut map = EdgeMap {
            made_for: (image, alloc),
            width: image.x,
            rays_at: vec![0; (image.x * image.y) as usize],
            count: 0,
            rays: RayCounts::default(),
        };
        let (mut paths, mut path_rays, mut b, mut pixels, mut s) = (0, 0, 0.0, 0, 0.0);
        for (_, t, rays) in &tiles {
            (paths, path_rays, b) = (paths + t.paths, path_rays + t.path_rays, b + t.b);
            pixels += t.flags.len() as u64;
            s += t.a.iter().map(|&a| (a as f64).sqrt()).sum::<f64>();
            map.rays.add(rays);
        }
        let lambda = allocation_scale(pixels, (paths, path_rays, b), s);
        for (o, t, _) in &tiles {
            let w = TILE.min(image.x - o.x);
            for (k, (&f, &a)) in t.flags.iter().zip(&t.a).enumerate() {
                let (x, y) = (o.x + k as u32 % w, o.y + k as u32 / w);
                let m = if f {
                    let m = (lambda * (a as f64).sqrt()).round();
                    m.clamp(1.0, alloc.most as f64) as u16
                } else {
                    0
                };
                map.rays_at[(y * image.x + x) as usize] = m;
                map.count += f as u64;
            }
        }
        map
    }

    /// Whether this is the map of an `image`-sized image that `alloc` finds: the same bits as
    /// [`EdgeMap::new`] would give.
    pub(super) fn fits(&self, image: UVec2, alloc: Allocation) -> bool {
        self.made_for == (image, alloc)
    }

    /// The edge rays a sample spends in the image's pixel `p` (0: not an edge pixel).
    #[inline]
    pub(super) fn at(&self, p: UVec2) -> u32 {
        self.rays_at[(p.y * self.width + p.x) as usize] as u32
    }
}

/// `λ` of the allocation `M_i = λ·√a_i` (see the module doc), from the `pixels` probed, the
/// pilot's `paths` (their `rays`), the sum `b` of their pixels' variance estimates and the sum
/// `s` of the edge pixels' `√a_i`: `√(C / (c_e·B))` with `C = P·c_p` the paths' cost a sample
/// and `B ≈ b·P/(paths/2)` their variance (two paths a pilot pixel), but at most
/// `EDGE_COST·C/(c_e·S)`, where the edge rays cost [`EDGE_COST`] times the paths; a path costs
/// `c_p/c_e = 2 × its rays` edge rays (a ray that shades and samples a light against one that
/// only looks).
fn allocation_scale(pixels: u64, (paths, rays, b): (u64, u64, f64), s: f64) -> f64 {
    if paths == 0 || s == 0.0 {
        return 0.0;
    }
    let cost = pixels as f64 * 2.0 * (rays as f64 / paths as f64).max(1.0);
    let big_b = b * pixels as f64 / (paths as f64 / 2.0);
    (cost / big_b).sqrt().min(EDGE_COST * cost / s)
}

/// The probe of the tile at `o` of an `image`-sized image: its pixels and the ring of pixels
/// around it probed at the centres of their quarters, each pixel's 4×4 window of probes
/// compared (its flag), then the pilot of the allocation `alloc` (see the module doc).
fn tile_edges(
    scene: &Scene,
    camera: &Camera,
    (image, o): (UVec2, UVec2),
    alloc: Allocation,
    rays: &mut RayCounts,
) -> TileProbe {
    let end = (o + UVec2::splat(TILE)).min(image);
    let sky_step = SKY_STEP * (scene.environment().luminance_integral() / (4.0 * PI)) as f32;
    // the probed pixels: the tile and its ring, within the image
    let (lo, hi) = (o.saturating_sub(UVec2::ONE), (end + UVec2::ONE).min(image));
    let (gw, gh) = (2 * (hi.x - lo.x), 2 * (hi.y - lo.y));
    let mut stack = TraceStack::default();
    let mut probe = Vec::with_capacity((gw * gh) as usize);
    for gy in 0..gh {
        for gx in 0..gw {
            let pixel = lo + UVec2::new(gx / 2, gy / 2);
            let u = Vec2::new(0.25 + 0.5 * (gx % 2) as f32, 0.25 + 0.5 * (gy % 2) as f32);
            probe.push(seen(scene, camera.generate_ray(pixel, u), rays, &mut stack));
        }
    }
    let mut flags = Vec::with_capacity(((end.x - o.x) * (end.y - o.y)) as usize);
    let mut steps = Vec::with_capacity(flags.capacity());
    for y in o.y..end.y {
        for x in o.x..end.x {
            // the window: probe columns 2x − 1 ..= 2x + 2 of the image, clipped to the probed
            let g = |p: u32, l: u32, n: u32| {
                let first = (2 * (p - l)).saturating_sub(1);
                first..(2 * (p - l) + 3).min(n)
            };
            let (mut min, mut max) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
            let (mut light, mut sky) = (false, true);
            for gy in g(y, lo.y, gh) {
                for gx in g(x, lo.x, gw) {
                    let (v, what) = probe[(gy * gw + gx) as usize];
                    (min, max) = (min.min(v), max.max(v));
                    light |= what == Seen::Light;
                    sky &= what == Seen::Sky;
                }
            }
            let step = (max - min).max_element();
            let edge = step > EDGE_CONTRAST * max.max_element();
            flags.push(edge && (light || (sky && step > sky_step)));
            // the step's mean over the channels, as the edge rays' variance is taken
            steps.push((max - min).element_sum() / 3.0);
        }
    }
    pilot(scene, camera, (o, end), (flags, steps), alloc, rays)
}

/// The most the edge rays may cost against the paths, a sample (where the paths vary little,
/// [`allocation_scale`]'s optimum would spend without end for what it gains).
const EDGE_COST: f64 = 4.0;

/// Pilot pixels: one in [`PILOT_STRIDE`]² of the image traces two paths.
const PILOT_STRIDE: u32 = 4;

/// Edge rays the pilot traces in an edge pixel to estimate one's variance.
const PILOT_EDGE_RAYS: u32 = 16;

/// The pilot of the tile from `o` to `end` (exclusive), its edge `flags` found: in each edge
/// pixel [`PILOT_EDGE_RAYS`] edge rays at scrambled Sobol points of a key no sample uses, their
/// variance `a` (mean over channels); in each pilot pixel two independent paths of `alloc`'s
/// integrator (unguided; an edge pixel's without the camera's emission, as its samples'), the
/// variance estimate `(x₁ − x₂)²/2` (mean over channels) summed.
fn pilot(
    scene: &Scene,
    camera: &Camera,
    (o, end): (UVec2, UVec2),
    (flags, step): (Vec<bool>, Vec<f32>),
    alloc: Allocation,
    rays: &mut RayCounts,
) -> TileProbe {
    let mut stack = TraceStack::default();
    let w = end.x - o.x;
    let seed = alloc.seed ^ 0x5049_4c4f_5420_4544;
    let mut a = vec![0.0f32; flags.len()];
    for (k, _) in flags.iter().enumerate().filter(|(_, &f)| f) {
        let pixel = o + UVec2::new(k as u32 % w, k as u32 / w);
        let (mut sum, mut sum2) = (Vec3::ZERO, Vec3::ZERO);
        for j in 0..PILOT_EDGE_RAYS {
            let e = seen_by_edge_rays(scene, camera, pixel, (seed, j as u64, 1), rays, &mut stack);
            (sum, sum2) = (sum + e, sum2 + e * e);
        }
        let n = PILOT_EDGE_RAYS as f32;
        let var = (sum2 - sum * sum / n) / (n - 1.0);
        // at least the variance of the window's step seen by one ray in 2n (a pilot that
        // saw one side only: the pixel is flagged, the other side is there)
        let floor = step[k] * step[k] * (1.0 - 0.5 / n) * 0.5 / n;
        a[k] = (var.max(Vec3::ZERO).element_sum() / 3.0).max(floor);
    }
    let mut integrator = alloc.integrator;
    if integrator.directions == Directions::Guided {
        integrator.directions = Directions::Phong;
    }
    let no_camera = IntegratorSettings {
        camera_emission: false,
        ..integrator
    };
    let mut sampler = IndependentSampler::new(seed);
    let (mut paths, mut path_rays, mut b) = (0u64, 0u64, 0.0f64);
    for y in (o.y..end.y).filter(|y| y % PILOT_STRIDE == 0) {
        for x in (o.x..end.x).filter(|x| x % PILOT_STRIDE == 0) {
            let (pixel, k) = (UVec2::new(x, y), ((y - o.y) * w + x - o.x) as usize);
            let settings = if flags[k] { &no_camera } else { &integrator };
            let mut l = [Vec3::ZERO; 2];
            for (index, l) in l.iter_mut().enumerate() {
                let mut counts = RayCounts::default();
                sampler.start_pixel_sample(pixel, index as u32);
                let u = CameraSample::draw(&mut sampler).pixel;
                let ray = camera.generate_ray(pixel, u);
                *l = radiance(scene, ray, &mut sampler, settings, &mut counts, &mut stack);
                path_rays += counts.total();
                // its camera ray counted with the edge rays (what the edges cost, apart from
                // the render's paths)
                counts.edge += counts.camera;
                rays.add(&counts);
            }
            let d = l[0] - l[1];
            if d.is_finite() {
                b += (d * d).element_sum() as f64 / 6.0;
                paths += 2;
            }
        }
    }
    TileProbe {
        flags,
        a,
        paths,
        path_rays,
        b,
    }
}

/// The estimate, by `m` edge rays, of what the camera sees directly in the image's pixel
/// `pixel` for its sample `index`: the mean of [`seen_emission`] at the pixel's scrambled Sobol
/// points `index·m … index·m + m − 1` (see the module doc), keyed by `seed`.
/// The rays are traced 8 at a time as packets ([`seen_packet`]), what each sees added in their
/// order: the same sum as ray by ray.
///
/// [`seen_emission`]: crate::integrator::seen_emission
#[inline]
#[allow(clippy::too_many_arguments)]
pub(super) fn seen_by_edge_rays(
    scene: &Scene,
    camera: &Camera,
    pixel: UVec2,
    (seed, index, m): (u64, u64, u32),
    rays: &mut RayCounts,
    stack: &mut TraceStack,
) -> Vec3 {
    let first = index * m as u64;
    let mut key = None::<(u64, u32)>;
    let mut sum = Vec3::ZERO;
    // the rays 8 at a time, traced as a packet; their emission added in their order
    let mut packet = [(Vec3::ZERO, Vec3::ZERO); LANES];
    let mut n = 0;
    for k in first..first + m as u64 {
        let seq = k >> 16;
        let scramble = match key {
            Some((s, h)) if s == seq => h,
            _ => {
                let words = [
                    seed ^ 0x4544_4745_2052_4159,
                    pixel.x as u64,
                    pixel.y as u64,
                    seq,
                ];
                let h = hash_words(&words) as u32;
                key = Some((seq, h));
                h
            }
        };
        let i = (k & 0xffff) as u32;
        let u = Vec2::new(
            sobol_burley::sample(i, 0, scramble),
            sobol_burley::sample(i, 1, scramble),
        );
        packet[n] = camera.generate_ray(pixel, u);
        n += 1;
        // a full packet, or the last rays
        if n == LANES || k + 1 == first + m as u64 {
            for e in &seen_packet(scene, &packet[..n], rays, stack)[..n] {
                sum += *e;
            }
            n = 0;
        }
    }
    sum / m as f32
}

#[cfg(test)]
mod tests;
