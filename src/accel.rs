//! The ray-triangle accelerator: an obvhs compressed wide BVH (CWBVH, 8-wide) over all
//! triangles, with the triangles stored in BVH leaf order so a hit indexes them directly.
//!
//! Triangles are `obvhs::rt_triangle::RtTriangle` (`v0`, `e1 = v0 − v1`, `e2 = v2 − v0`), the
//! layout its Möller–Trumbore test is fastest with. A hit reports the barycentrics `(b1, b2)` of
//! `v1` and `v2`: the point is `(1 − b1 − b2)·v0 + b1·v1 + b2·v2`. Indices in a [`Hit`] and in
//! [`Accel::order`] are BVH-order indices; `order[i]` is the input index of BVH triangle `i`.

use glam::{Vec3, Vec3A};
use obvhs::{
    cwbvh::{builder::build_cwbvh_from_tris, CwBvh},
    ray::{Ray, RayHit},
    rt_triangle::RtTriangle,
    triangle::Triangle,
    BvhBuildParams,
};
use std::time::{Duration, Instant};

/// A closest hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the (unit) ray direction.
    pub t: f32,
    /// BVH-order triangle index.
    pub prim: u32,
    /// Barycentric weight of `v1`.
    pub b1: f32,
    /// Barycentric weight of `v2`.
    pub b2: f32,
}

/// The BVH and the triangles in its order.
pub struct Accel {
    bvh: CwBvh,
    tris: Vec<RtTriangle>,
    /// `order[i]` = input index of BVH-order triangle `i`.
    pub order: Vec<u32>,
    /// Wall time of the build (AABBs, PLOC, reinsertion, CWBVH conversion, reordering).
    pub build_time: Duration,
}

impl Accel {
    /// Build over `triangles` (each `[v0, v1, v2]`). Must not be empty.
    pub fn build(triangles: &[[Vec3; 3]]) -> Accel {
        assert!(!triangles.is_empty(), "Accel::build needs triangles");
        let start = Instant::now();
        let input: Vec<Triangle> = triangles
            .iter()
            .map(|t| Triangle {
                v0: t[0].into(),
                v1: t[1].into(),
                v2: t[2].into(),
            })
            .collect();
        let mut core = Duration::ZERO;
        let bvh = build_cwbvh_from_tris(&input, BvhBuildParams::medium_build(), &mut core);
        let order = bvh.primitive_indices.clone();
        let tris = order
            .iter()
            .map(|&i| {
                let t = &input[i as usize];
                RtTriangle::new(t.v0, t.v1, t.v2)
            })
            .collect();
        Accel {
            bvh,
            tris,
            order,
            build_time: start.elapsed(),
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// Always false: an Accel holds at least one triangle.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// Bytes held by the BVH nodes, the index map and the triangles.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.bvh.nodes.as_slice())
            + std::mem::size_of_val(self.bvh.primitive_indices.as_slice())
            + std::mem::size_of_val(self.order.as_slice())
            + std::mem::size_of_val(self.tris.as_slice())
    }

    /// The vertices of BVH-order triangle `prim`.
    #[inline]
    pub fn vertices(&self, prim: u32) -> [Vec3; 3] {
        let t = &self.tris[prim as usize];
        [t.v0.into(), (t.v0 - t.e1).into(), (t.v0 + t.e2).into()]
    }

    /// Closest hit along `origin + t·dir` for `t ∈ (0, tmax)`; `dir` must be unit length.
    #[inline]
    pub fn intersect(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        let ray = Ray::new(Vec3A::from(origin), Vec3A::from(dir), 0.0, tmax);
        let mut hit = RayHit::none();
        if self
            .bvh
            .ray_traverse(ray, &mut hit, |r, id| self.tris[id].intersect(r))
        {
            let prim = hit.primitive_id;
            let bary = self.tris[prim as usize].compute_barycentric(&ray);
            Some(Hit {
                t: hit.t,
                prim,
                b1: bary.x,
                b2: bary.y,
            })
        } else {
            None
        }
    }

    /// True if anything lies along `origin + t·dir` for `t ∈ (0, tmax)` (any hit, early out).
    #[inline]
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        let ray = Ray::new(Vec3A::from(origin), Vec3A::from(dir), 0.0, tmax);
        !self
            .bvh
            .ray_traverse_miss(ray, |r, id| self.tris[id].intersect(r))
    }

    /// Closest hit by testing every triangle: the reference for tests and benchmarks.
    pub fn intersect_brute_force(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        let ray = Ray::new(Vec3A::from(origin), Vec3A::from(dir), 0.0, tmax);
        let mut best: Option<Hit> = None;
        for (i, tri) in self.tris.iter().enumerate() {
            let t = tri.intersect(&ray);
            if t < best.map_or(tmax, |h| h.t) {
                let bary = tri.compute_barycentric(&ray);
                best = Some(Hit {
                    t,
                    prim: i as u32,
                    b1: bary.x,
                    b2: bary.y,
                });
            }
        }
        best
    }
}
