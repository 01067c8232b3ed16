//! A scene without a description still gives a picture a person recognises: where the camera
//! stands, and whether the scene's own emitters light what it sees.
//!
//! **A survey** of a camera ([`survey`]): a 24×24 grid of primary rays (each jittered by a hash
//! of its pixel, so the result is a function of the scene alone). For each it records whether
//! the ray hits something, and whether it hits the front of the surface (the side its winding's
//! normal points to: models are made to be seen from there); at the point it hits, the direct
//! light of the emitters, estimated by four points on emitters (chosen in proportion to power,
//! each uniform on its emitter) and shadow rays: `L ≈ ρ/π · Σ Le cosθ cosθ' / (d² p)` with an
//! albedo `ρ = ½`, and `Le` itself where the ray hits an emitter's front. The mean of `L` over
//! the grid is the brightness of the picture to come, before any bounce.
//!
//! **The camera** ([`choose_camera`]): the view of the bounding box from +z (the default since
//! the first scenes), or from above at 35° where that sees almost nothing (a flat world seen
//! edge-on), unless at most half of what it hits is the front of a surface: then the
//! view from −z, +x or −x that sees most fronts (a Cornell box open toward −z). Where that still
//! sees mostly backs and the scene has emitters (the outside of a room whose normals point in, lit from inside: the
//! picture would be the backs of its walls, dark). Then the camera goes inside: near one end of
//! a horizontal axis of the box, at 40 % of its height, looking along that axis (both ends of
//! both horizontal axes are tried; the view of the brightest direct light wins, if it is
//! brighter than the outside view's).
//!
//! **The light** ([`too_dark`]): a scene whose emitters give the chosen view a mean direct
//! brightness below [`DARK`] (an outdoor world whose only emitter is a small dim lamp, emitters
//! hidden from everything the camera sees) is lit as a scene without emitters is, by the studio
//! light (`Environment::studio`: a grey sky and a key light from behind the camera), and the
//! loader says so.

use super::TriShading;
use crate::accel::{Accel, TraceStack};
use crate::camera::{Camera, CameraDesc};
use crate::environment::Environment;
use crate::lights::{luminance, Emitter, Shape};
use crate::math::{hash_words, u64_to_unit_f32};
use glam::{UVec2, Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

/// The survey's grid side, in rays.
const GRID: u32 = 24;

/// Points on emitters per surveyed hit.
const LIGHT_SAMPLES: u32 = 4;

/// The mean direct brightness (radiance, albedo ½) below which a scene's emitters are taken to
/// light nothing the camera sees: a thousandth of what a white sky gives the same surfaces.
pub const DARK: f32 = 5e-4;

/// What a camera sees of a scene (see the module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Survey {
    /// The share of rays that hit anything.
    pub hits: f32,
    /// The share of rays that hit the front of a surface.
    pub front: f32,
    /// The mean direct brightness over all rays.
    pub direct: f32,
}

/// The scene's geometry as the survey reads it.
pub struct Geometry<'a> {
    pub accel: &'a Accel,
    pub shading: &'a [TriShading],
    /// The emissive triangles, in the order of their BVH-order primitives.
    pub emitters: &'a [Emitter],
    /// The scene's ray offset.
    pub epsilon: f32,
}

/// A number in `[0, 1)` from the hash of `words`.
fn unit(words: &[u64]) -> f32 {
    u64_to_unit_f32(hash_words(words))
}

/// A point uniform on emitter `e` from `u`.
fn point_on(e: &Emitter, u: Vec2) -> Vec3 {
    match e.shape {
        Shape::Triangle([a, b, c]) => {
            let s = u.x.sqrt();
            a * (1.0 - s) + b * (s * (1.0 - u.y)) + c * (s * u.y)
        }
        Shape::Rectangle { s, ex, ey } => s + ex * u.x + ey * u.y,
    }
}

/// Survey the view of `desc` (module doc).
pub fn survey(g: &Geometry, desc: &CameraDesc) -> Survey {
    let Some(camera) = Camera::new(desc, GRID, GRID) else {
        return Survey::default();
    };
    // the emitters' power, summed in order (a choice by power is a binary search)
    let mut cdf: Vec<f32> = g.emitters.iter().map(|e| e.power()).collect();
    let mut total = 0.0f32;
    for c in cdf.iter_mut() {
        total += *c;
        *c = total;
    }
    let mut stack = TraceStack::default();
    let (mut hits, mut front, mut direct) = (0u32, 0u32, 0.0f64);
    for y in 0..GRID {
        for x in 0..GRID {
            let k = (y * GRID + x) as u64;
            let u = Vec2::new(unit(&[k, 1]), unit(&[k, 2]));
            let (o, d) = camera.generate_ray(UVec2::new(x, y), u);
            let Some(hit) = g.accel.intersect_with(&mut stack, o, d, f32::INFINITY) else {
                continue;
            };
            hits += 1;
            let sh = &g.shading[hit.prim as usize];
            let faces = sh.ng.dot(-d) > 0.0;
            front += faces as u32;
            let p = o + d * hit.t;
            let n = if faces { sh.ng } else { -sh.ng };
            direct += light_at(g, (p, n, hit.prim), &cdf, k, &mut stack) as f64;
        }
    }
    let n = (GRID * GRID) as f32;
    Survey {
        hits: hits as f32 / n,
        front: front as f32 / n,
        direct: direct as f32 / n,
    }
}

/// The direct brightness at point `p` (normal `n` on the viewer's side) of BVH-order triangle
/// `prim` (the emitter's `Le` where it is one seen from the front), from [`LIGHT_SAMPLES`] points
/// on emitters chosen by power (`cdf`: the powers summed in order); `k` keys their numbers.
fn light_at(
    g: &Geometry,
    (p, n, prim): (Vec3, Vec3, u32),
    cdf: &[f32],
    k: u64,
    stack: &mut TraceStack,
) -> f32 {
    // the emitters are in the order of their primitives
    if let Ok(i) = g.emitters.binary_search_by_key(&prim, |e| e.prims[0]) {
        let e = &g.emitters[i];
        if e.n.dot(n) > 0.0 {
            return luminance(e.emission);
        }
    }
    let total = cdf.last().copied().unwrap_or(0.0);
    if total.is_nan() || total <= 0.0 {
        return 0.0;
    }
    let mut sum = 0.0;
    for j in 0..LIGHT_SAMPLES as u64 {
        // an emitter by power, then a point on it
        let pick = unit(&[k, 3, j]) * total;
        let i = cdf.partition_point(|&c| c <= pick).min(cdf.len() - 1);
        let power = cdf[i] - if i > 0 { cdf[i - 1] } else { 0.0 };
        let e = &g.emitters[i];
        let y = point_on(e, Vec2::new(unit(&[k, 4, j]), unit(&[k, 5, j])));
        let to = y - p;
        let d2 = to.length_squared();
        let w = to / d2.sqrt();
        let (cos, cos_e) = (n.dot(w), -e.n.dot(w));
        if cos <= 0.0 || cos_e <= 0.0 || d2 <= 0.0 {
            continue;
        }
        let origin = p + n * g.epsilon;
        let tmax = (y - origin).length() - 2.0 * g.epsilon;
        if g.accel.occluded_with(stack, origin, w, tmax) {
            continue;
        }
        let pdf_area = power / total / e.area;
        sum += luminance(e.emission) * cos * cos_e / (d2 * pdf_area);
    }
    0.5 * FRAC_1_PI * sum / LIGHT_SAMPLES as f32
}

/// The camera of a scene without a description, looking at the box `(lo, hi)`: `outside` (the
/// default view) unless at most half its rays hit a front face and the scene has emitters (one
/// without is lit from outside, by the studio light, and two-sided shading shows the backs
/// of surfaces as well as their fronts); then the inside view whose direct light is brightest,
/// if it is brighter than the outside's (module doc). Also the chosen view's survey.
pub fn choose_camera(
    g: &Geometry,
    (lo, hi): (Vec3, Vec3),
    outside: CameraDesc,
) -> (CameraDesc, Survey) {
    let mut first = (outside, survey(g, &outside));
    if first.1.hits < 0.05 {
        // a flat world seen edge-on (a terrain, a ground plane): from above, at 35°
        let desc = frame_from(lo, hi, Vec3::new(0.0, 0.7, 1.0).normalize());
        let s = survey(g, &desc);
        if s.hits > first.1.hits {
            first = (desc, s);
        }
    }
    if first.1.front > 0.5 * first.1.hits {
        return first;
    }
    // the other sides first: a Cornell box open toward -z is seen from there
    for dir in [-Vec3::Z, Vec3::X, -Vec3::X] {
        let desc = frame_from(lo, hi, dir);
        let s = survey(g, &desc);
        if s.front > first.1.front {
            first = (desc, s);
        }
    }
    let (outside, first) = first;
    if first.front > 0.5 * first.hits || g.emitters.is_empty() {
        return (outside, first);
    }
    let (centre, ext) = (0.5 * (lo + hi), hi - lo);
    let eye_y = lo.y + 0.4 * ext.y;
    let mut best = (outside, first);
    for (axis, length) in [(Vec3::X, ext.x), (Vec3::Z, ext.z)] {
        for sign in [1.0f32, -1.0] {
            let dir = axis * sign;
            let mut eye = centre - dir * (0.4 * length);
            eye.y = eye_y;
            let desc = CameraDesc {
                eye,
                target: eye + dir,
                up: Vec3::Y,
                fov_deg: 60.0,
            };
            let s = survey(g, &desc);
            if (s.direct, s.front) > (best.1.direct, best.1.front) {
                best = (desc, s);
            }
        }
    }
    best
}

/// A camera looking at the box `(lo, hi)` from direction `dir` (a unit vector, not vertical),
/// far enough back to see all of it at 40°.
pub fn frame_from(lo: Vec3, hi: Vec3, dir: Vec3) -> CameraDesc {
    let centre = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(1e-3);
    let fov_deg = 40.0f32;
    let dist = radius / (0.5 * fov_deg.to_radians()).sin();
    CameraDesc {
        eye: centre + dir * dist,
        target: centre,
        up: Vec3::Y,
        fov_deg,
    }
}

/// Whether the scene's emitters light the view of `s` too little to make a picture (a mean
/// direct brightness below [`DARK`]).
pub fn too_dark(s: &Survey) -> bool {
    s.direct < DARK
}

/// A scene's camera: its own (`camera`), else a frame of its bounds `(lo, hi)` seen from +z, or
/// with `auto_view` a view that sees the fronts of surfaces ([`choose_camera`], with a
/// warning when that is not the view from +z) and what that view sees.
pub(super) fn camera_of(
    camera: Option<CameraDesc>,
    auto_view: bool,
    g: &Geometry,
    (lo, hi): (Vec3, Vec3),
    warnings: &mut Vec<String>,
) -> (CameraDesc, Option<Survey>) {
    match camera {
        Some(c) => (c, None),
        None if !auto_view => (frame_bounds(lo, hi), None),
        None => {
            let outside = frame_bounds(lo, hi);
            let (c, s) = choose_camera(g, (lo, hi), outside);
            if c != outside {
                let inside = (lo.cmple(c.eye) & c.eye.cmple(hi)).all();
                warnings.push(format!(
                    "the view from +z sees mostly the backs of surfaces, or almost nothing: \
                     the camera is placed {}, at {} looking toward {} (a [camera] in \
                     scene.toml chooses another)",
                    if inside { "inside" } else { "outside" },
                    show(c.eye),
                    show(c.target)
                ));
            }
            (c, Some(s))
        }
    }
}

/// The environment of a scene without one of its own: none (black) when its emitters light
/// what the camera sees; the studio (a grey sky and a key light from behind the camera, above
/// and to its right, so the faces the camera sees are lit and shadows fall away from it) when
/// it has no emitters or they light almost nothing of what the view `seen` sees, with a warning.
pub(super) fn environment_of(
    camera: &CameraDesc,
    emitters: &[Emitter],
    seen: Option<&Survey>,
    warnings: &mut Vec<String>,
) -> Environment {
    let key = {
        let back = (camera.eye - camera.target).normalize_or(Vec3::Z);
        let right = camera.up.cross(back).normalize_or(Vec3::X);
        (back + camera.up.normalize_or(Vec3::Y) + 0.5 * right).normalize()
    };
    if emitters.is_empty() {
        warnings.push(
            "no emitters: lighting with a grey sky and a key light from behind the camera \
             ([environment] in scene.toml chooses another)"
                .into(),
        );
        Environment::studio(key)
    } else if seen.is_some_and(too_dark) {
        let power: f32 = emitters.iter().map(|e| e.power()).sum();
        warnings.push(format!(
            "the scene's {} emitting triangles (power {power:.3}) light almost nothing \
             the camera sees (direct brightness {:.1e}): lighting it also with a \
             grey sky and a key light from behind the camera ([environment] radiance = \
             [0, 0, 0] in scene.toml keeps it dark)",
            emitters.len(),
            seen.map_or(0.0, |s| s.direct)
        ));
        Environment::studio(key)
    } else {
        Environment::Constant(Vec3::ZERO)
    }
}

/// `(x, y, z)` to three significant digits, for a message.
fn show(v: Vec3) -> String {
    format!("({:.3}, {:.3}, {:.3})", v.x, v.y, v.z)
}

/// A camera looking at the bounding box from +z, far enough back to see all of it at 40°.
fn frame_bounds(lo: Vec3, hi: Vec3) -> CameraDesc {
    frame_from(lo, hi, Vec3::Z)
}
