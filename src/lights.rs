//! The lights of a scene: every emissive triangle (one-sided: it emits on the side its
//! counter-clockwise normal points to), with a map from BVH-order primitive to light index, so
//! a BSDF-sampled ray that hits an emitter finds its light (and, for multiple importance
//! sampling, that light's pdf).

use crate::accel::Accel;
use crate::material::Material;
use crate::scene::TriShading;
use glam::Vec3;

/// Index in the primitive → light map of a primitive that is no light.
const NO_LIGHT: u32 = u32::MAX;

/// An emissive triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleLight {
    /// BVH-order triangle index.
    pub prim: u32,
    /// Area of the triangle.
    pub area: f32,
    /// Emitted radiance on the front side.
    pub emission: Vec3,
}

/// All lights of a scene.
#[derive(Clone, Debug, Default)]
pub struct Lights {
    /// The emissive triangles, in BVH order.
    pub triangles: Vec<TriangleLight>,
    /// `light_index[prim]`: the light of BVH-order triangle `prim`, or [`NO_LIGHT`].
    light_index: Vec<u32>,
}

impl Lights {
    /// The emissive triangles among `shading` (BVH order) with their materials.
    pub fn build(accel: &Accel, shading: &[TriShading], materials: &[Material]) -> Lights {
        let mut triangles = Vec::new();
        let mut light_index = vec![NO_LIGHT; shading.len()];
        for (prim, s) in shading.iter().enumerate() {
            let m = &materials[s.material as usize];
            if !m.is_emissive() {
                continue;
            }
            let [a, b, c] = accel.vertices(prim as u32);
            light_index[prim] = triangles.len() as u32;
            triangles.push(TriangleLight {
                prim: prim as u32,
                area: 0.5 * (b - a).cross(c - a).length(),
                emission: m.emission,
            });
        }
        Lights {
            triangles,
            light_index,
        }
    }

    /// Number of emissive triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// True when the scene has no emissive triangle.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The light that BVH-order triangle `prim` is, if it emits.
    #[inline]
    pub fn light_of(&self, prim: u32) -> Option<u32> {
        match self.light_index.get(prim as usize) {
            Some(&i) if i != NO_LIGHT => Some(i),
            _ => None,
        }
    }
}
