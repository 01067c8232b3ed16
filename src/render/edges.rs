//! Edge rays (`--edge-rays M`): the emission a pixel sees directly, estimated apart in the
//! pixels where it varies.
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

use super::TILE;
use crate::accel::TraceStack;
use crate::camera::Camera;
use crate::integrator::{seen, seen_emission, RayCounts, Seen};
use crate::math::hash_words;
use crate::scene::Scene;
use glam::{UVec2, Vec2, Vec3};
use rayon::prelude::*;
use std::f64::consts::PI;

/// The default `--edge-rays`: over the shipped scenes at 64 spp (`tools/readme_numbers.py`'s
/// efficiency recipe), 16 was 1.14× as efficient as 8 in the geometric mean (textured 2.0×, the
/// glossy plates 1.5×; elsewhere within the timing's noise) and 32 1.07× (checker-plane 0.8×,
/// where every sample is a camera ray and the edge rays are most of the cost).
pub const DEFAULT_EDGE_RAYS: u32 = 16;

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

/// Which of an image's pixels see an edge of emission (see the module doc).
pub(super) struct EdgeMap {
    width: u32,
    edge: Vec<bool>,
    /// How many pixels are edge pixels.
    pub(super) count: u64,
    /// The probe's rays.
    pub(super) rays: RayCounts,
}

impl EdgeMap {
    /// The map of the `image`-sized image seen through `camera`, probed on the tiles whose
    /// top-left pixels are `origins` (the rest of the image reads as no edge).
    pub(super) fn new(scene: &Scene, camera: &Camera, image: UVec2, origins: &[UVec2]) -> Self {
        let tiles: Vec<(UVec2, Vec<bool>, RayCounts)> = origins
            .par_iter()
            .map(|&o| {
                let mut rays = RayCounts::default();
                let flags = tile_edges(scene, camera, image, o, &mut rays);
                (o, flags, rays)
            })
            .collect();
        let mut map = EdgeMap {
            width: image.x,
            edge: vec![false; (image.x * image.y) as usize],
            count: 0,
            rays: RayCounts::default(),
        };
        for (o, flags, rays) in tiles {
            let w = TILE.min(image.x - o.x);
            for (k, &f) in flags.iter().enumerate() {
                let (x, y) = (o.x + k as u32 % w, o.y + k as u32 / w);
                map.edge[(y * image.x + x) as usize] = f;
                map.count += f as u64;
            }
            map.rays.add(&rays);
        }
        map
    }

    /// Whether the image's pixel `p` is an edge pixel.
    #[inline]
    pub(super) fn at(&self, p: UVec2) -> bool {
        self.edge[(p.y * self.width + p.x) as usize]
    }
}

/// The edge flags of the tile at `o` of an `image`-sized image, row by row: its pixels and the
/// ring of pixels around it probed at the centres of their quarters, then each pixel's 4×4
/// window of probes compared.
fn tile_edges(
    scene: &Scene,
    camera: &Camera,
    image: UVec2,
    o: UVec2,
    rays: &mut RayCounts,
) -> Vec<bool> {
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
        }
    }
    flags
}

/// The estimate, by `m` edge rays, of what the camera sees directly in the image's pixel
/// `pixel` for its sample `index`: the mean of [`seen_emission`] at the pixel's scrambled Sobol
/// points `index·m … index·m + m − 1` (see the module doc), keyed by `seed`.
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
        sum += seen_emission(scene, camera.generate_ray(pixel, u), rays, stack);
    }
    sum / m as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::settings::camera_for;
    use crate::render::RenderSettings;

    /// On the shipped Cornell box at 32×32 (its light in view), with each pixel's share of the
    /// light measured on a 16×16 grid of camera rays: every pixel the light's edge crosses well
    /// inside (a share of 0.1 to 0.9) is an edge pixel, and no edge pixel has a 3×3
    /// neighbourhood the light covers wholly or not at all (grid share exactly 0 or 1
    /// throughout): the flags are the edge, no more.
    #[test]
    fn the_edge_pixels_are_those_along_the_lights_edge() {
        let scene = crate::scene::load(std::path::Path::new("scenes/cornell-box")).unwrap();
        let settings = RenderSettings {
            width: 32,
            height: 32,
            ..RenderSettings::for_scene(&scene)
        };
        let camera = camera_for(&scene, &settings).unwrap();
        let image = UVec2::new(32, 32);
        let origins: Vec<UVec2> = [(0, 0), (16, 0), (0, 16), (16, 16)]
            .iter()
            .map(|&(x, y)| UVec2::new(x, y))
            .collect();
        let map = EdgeMap::new(&scene, &camera, image, &origins);
        let (mut rays, mut stack) = (RayCounts::default(), TraceStack::default());
        let share: Vec<f32> = (0..32 * 32)
            .map(|i| {
                let pixel = UVec2::new(i % 32, i / 32);
                let mut lit = 0;
                for k in 0..256 {
                    let u = Vec2::new((k % 16) as f32 + 0.5, (k / 16) as f32 + 0.5) / 16.0;
                    let e =
                        seen_emission(&scene, camera.generate_ray(pixel, u), &mut rays, &mut stack);
                    lit += (e.max_element() > 0.0) as u32;
                }
                lit as f32 / 256.0
            })
            .collect();
        let mut partial = 0;
        for y in 0..32i32 {
            for x in 0..32i32 {
                let s = share[(y * 32 + x) as usize];
                let flagged = map.at(UVec2::new(x as u32, y as u32));
                if (0.1..=0.9).contains(&s) {
                    partial += 1;
                    assert!(
                        flagged,
                        "pixel ({x}, {y}), {s} of it lit, is not an edge pixel"
                    );
                }
                let around: Vec<f32> = (-1..=1)
                    .flat_map(|dy| (-1..=1).map(move |dx| (x + dx, y + dy)))
                    .filter(|&(a, b)| (0..32).contains(&a) && (0..32).contains(&b))
                    .map(|(a, b)| share[(b * 32 + a) as usize])
                    .collect();
                let uniform = around.iter().all(|&v| v == 0.0) || around.iter().all(|&v| v == 1.0);
                assert!(
                    !(flagged && uniform),
                    "pixel ({x}, {y}) is flagged in a uniform region"
                );
            }
        }
        assert!(
            partial >= 4,
            "the light's edge crosses only {partial} pixels"
        );
        // each tile probes its 16×16 pixels and the ring inside the image: 17×17, four rays each
        assert_eq!(map.rays.edge, 4 * 17 * 17 * 4);
    }
}
