//! What a scene knows of a surface where a ray hits it: the per-triangle shading record in BVH
//! order ([`TriShading`]: vertex normals, geometric normal, material), the texture coordinates
//! kept apart where a material reads them ([`Scene::triangle_uvs`]), and the [`SurfacePoint`]
//! of a hit: the point, the interpolated shading normal (under a bump or normal map where there
//! is one) and the texture coordinates at its barycentrics.

use super::{Mesh, Scene};
use crate::accel::{Accel, Hit};
use glam::{Vec2, Vec3};

/// Shading data of one triangle, stored in BVH order beside the accelerator's triangles (56
/// bytes; the texture coordinates, which only maps read, are kept apart: [`Scene::uvs`]).
#[derive(Clone, Copy, Debug)]
pub struct TriShading {
    pub normals: [Vec3; 3],
    /// Unit geometric normal by winding.
    pub ng: Vec3,
    pub material: u32,
    /// Whether the three vertex normals are `ng`, bit for bit (the file gives none, or gives
    /// the geometric one): the shading normal is then `ng` itself, not interpolated and
    /// normalised again.
    pub flat: bool,
}

/// The local geometry at a ray hit.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    pub p: Vec3,
    /// Unit geometric normal (winding).
    pub ng: Vec3,
    /// Unit interpolated shading normal, on the same side as `ng`.
    pub ns: Vec3,
    /// Interpolated texture coordinates (zero where the mesh has none, and in a scene whose
    /// materials read none: no textures, no bump or normal maps).
    pub uv: Vec2,
    pub material: u32,
}

impl Scene {
    /// The texture coordinates of BVH-order triangle `prim`'s vertices (zeros where the scene
    /// keeps none: no material reads them).
    #[inline(always)]
    pub fn triangle_uvs(&self, prim: u32) -> [Vec2; 3] {
        self.uvs
            .get(prim as usize)
            .copied()
            .unwrap_or([Vec2::ZERO; 3])
    }

    /// The surface at a hit (inlined into the integrator: measured 6% of a render's
    /// instructions as a call). A flat triangle's shading normal is its geometric one as it is
    /// (interpolated and normalised again it came back within an ulp of it, for a square root
    /// and a division a hit on the path's chain: the render of Mitsuba's box took 0.97× the
    /// time, images within rounding).
    #[inline(always)]
    pub fn surface(&self, hit: &Hit) -> SurfacePoint {
        let sh = &self.shading[hit.prim as usize];
        let [a, b, c] = self.accel.vertices(hit.prim);
        let b0 = 1.0 - hit.b1 - hit.b2;
        let p = a * b0 + b * hit.b1 + c * hit.b2;
        let mut ns = if sh.flat {
            sh.ng
        } else {
            let n = sh.normals[0] * b0 + sh.normals[1] * hit.b1 + sh.normals[2] * hit.b2;
            n.try_normalize().unwrap_or(sh.ng)
        };
        if ns.dot(sh.ng) < 0.0 {
            ns = -ns;
        }
        // only textures and normal maps read the coordinates
        let uv = if self.coloured || self.perturbed {
            let uvs = self.triangle_uvs(hit.prim);
            uvs[0] * b0 + uvs[1] * hit.b1 + uvs[2] * hit.b2
        } else {
            Vec2::ZERO
        };
        if self.perturbed {
            ns = self.perturb(hit.prim, ns, uv);
        }
        SurfacePoint {
            p,
            ng: sh.ng,
            ns,
            uv,
            material: sh.material,
        }
    }

    /// The shading normal `ns` of BVH-order triangle `prim` at `uv` under its material's bump
    /// or normal map (see [`crate::material::Maps`]), in the frame of the texture coordinates'
    /// derivatives `∂p/∂u`, `∂p/∂v` across the triangle:
    /// - bump: the height `h` displaces the surface along `ns`, `∂p'/∂u = ∂p/∂u + m·∂h/∂u·ns`
    ///   (likewise v; ∂h by central differences one texel wide, `m` the `-bm` multiplier), and
    ///   `ns' = ∂p'/∂u × ∂p'/∂v` turned to the side of `ns`;
    /// - normal map: `ns' = t·x + b·y + ns·z` for the texel `(x, y, z) = 2c − 1`, with `t`
    ///   the unit ∂p/∂u made orthogonal to `ns` and `b = ns × t` (turned to the side of ∂p/∂v).
    ///
    /// The two-sided rules stay: a perturbed normal that would fall on the other side of the
    /// geometric normal than `ns` is dropped (`ns` kept), as is any on a triangle whose texture
    /// coordinates are degenerate.
    #[inline(never)]
    fn perturb(&self, prim: u32, ns: Vec3, uv: Vec2) -> Vec3 {
        let sh = &self.shading[prim as usize];
        let maps = &self.materials[sh.material as usize].maps;
        if !maps.perturbs_normal() {
            return ns;
        }
        let [a, b, c] = self.accel.vertices(prim);
        let (e1, e2) = (b - a, c - a);
        let uvs = self.triangle_uvs(prim);
        let (d1, d2) = (uvs[1] - uvs[0], uvs[2] - uvs[0]);
        let det = d1.x * d2.y - d1.y * d2.x;
        if det.abs() < 1e-20 {
            return ns;
        }
        let dpdu = (e1 * d2.y - e2 * d1.y) / det;
        let dpdv = (e2 * d1.x - e1 * d2.x) / det;
        let mut n = ns;
        if let Some((r, mult)) = maps.bump {
            let t = self.textures.get(&r);
            let (w, h) = t.size();
            // one texel in the texture's coordinates, back in the surface's
            let (du, dv) = (
                0.5 / (w as f32 * r.scale.x.abs().max(1e-12)),
                0.5 / (h as f32 * r.scale.y.abs().max(1e-12)),
            );
            let height = |d: Vec2| t.bilinear(r.map(uv + d)).x;
            let dhdu = (height(Vec2::new(du, 0.0)) - height(Vec2::new(-du, 0.0))) / (2.0 * du);
            let dhdv = (height(Vec2::new(0.0, dv)) - height(Vec2::new(0.0, -dv))) / (2.0 * dv);
            let pu = dpdu + ns * (mult * dhdu);
            let pv = dpdv + ns * (mult * dhdv);
            let m = pu.cross(pv);
            let m = if m.dot(ns) < 0.0 { -m } else { m };
            n = m.try_normalize().unwrap_or(ns);
        }
        if let Some(r) = maps.normal {
            let c = self.textures.get(&r).bilinear(r.map(uv)).truncate() * 2.0 - Vec3::ONE;
            let t = (dpdu - n * n.dot(dpdu)).try_normalize();
            if let Some(t) = t {
                let mut bt = n.cross(t);
                if bt.dot(dpdv) < 0.0 {
                    bt = -bt;
                }
                n = (t * c.x + bt * c.y + n * c.z).try_normalize().unwrap_or(n);
            }
        }
        if n.dot(sh.ng) > 0.0 {
            n
        } else {
            ns
        }
    }
}

/// The shading data of the mesh's triangles in the BVH's order: the unit geometric normal by
/// winding, the unit vertex normals (the geometric one where the file has none), the material.
pub(super) fn shading_in_bvh_order(accel: &Accel, mesh: &Mesh) -> Vec<TriShading> {
    use rayon::prelude::*;
    accel
        .order
        .par_iter()
        .map(|&i| {
            let t = &mesh.triangles[i as usize];
            let ng = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).normalize_or_zero();
            let normals = t.normals.map_or([ng; 3], |n| n.map(|v| v.normalize()));
            TriShading {
                normals,
                ng,
                material: t.material,
                // bit for bit: a file's normal of −0 where ng has +0 would turn the
                // shading frame (`Frame::from_normal` takes the sign of z)
                flat: normals
                    .iter()
                    .all(|n| n.to_array().map(f32::to_bits) == ng.to_array().map(f32::to_bits)),
            }
        })
        .collect()
}

/// The texture coordinates of the mesh's triangles in the BVH's order (zero where the file has
/// none).
pub(super) fn uvs_in_bvh_order(accel: &Accel, mesh: &Mesh) -> Vec<[Vec2; 3]> {
    use rayon::prelude::*;
    accel
        .order
        .par_iter()
        .map(|&i| mesh.triangles[i as usize].uvs.unwrap_or([Vec2::ZERO; 3]))
        .collect()
}
