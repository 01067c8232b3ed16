//! The scene: triangles with shading data in BVH order, materials, emitters, camera,
//! environment and render defaults, loaded from an `.obj`, a `scene.toml`, or a folder holding a
//! `scene.toml`.
//!
//! Conventions: right-handed, y up. A triangle's geometric normal `ng = (v1−v0)×(v2−v0)` follows
//! its counter-clockwise winding; emission is one-sided, on the side `ng` points to. Shading is
//! two-sided: the integrator flips the shading frame to the side the ray arrives from.
//! Without a description the camera frames the bounding box from +z, and a scene with no
//! emitter gets a uniform white environment (radiance 1) so any OBJ renders visibly.

pub mod description;
pub mod generate;
pub mod obj;

use crate::accel::{Accel, Hit};
use crate::bsdf::Bsdf;
use crate::camera::CameraDesc;
use crate::error::{Error, Result};
use crate::lights::{Emitter, Lights};
use crate::material::Material;
use crate::math::hash_words;
use description::{Description, RenderSection};
use glam::{Vec2, Vec3};
use std::path::{Path, PathBuf};

/// One triangle of a mesh before the BVH is built.
#[derive(Clone, Debug)]
pub struct MeshTriangle {
    pub p: [Vec3; 3],
    /// Per-vertex shading normals, if the file has them.
    pub normals: Option<[Vec3; 3]>,
    /// Per-vertex texture coordinates, if the file has them.
    pub uvs: Option<[Vec2; 3]>,
    pub material: u32,
}

/// A triangle soup.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub triangles: Vec<MeshTriangle>,
}

/// Shading data of one triangle, stored in BVH order beside the accelerator's triangles.
#[derive(Clone, Copy, Debug)]
pub struct TriShading {
    pub normals: [Vec3; 3],
    /// Unit geometric normal by winding.
    pub ng: Vec3,
    /// Texture coordinates of the vertices (zero where the file has none).
    pub uvs: [Vec2; 3],
    pub material: u32,
}

/// The local geometry at a ray hit.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    pub p: Vec3,
    /// Unit geometric normal (winding).
    pub ng: Vec3,
    /// Unit interpolated shading normal, on the same side as `ng`.
    pub ns: Vec3,
    /// Interpolated texture coordinates (zero where the mesh has none).
    pub uv: Vec2,
    pub material: u32,
}

/// Everything the renderer needs.
pub struct Scene {
    /// The file the scene came from.
    pub source: PathBuf,
    pub accel: Accel,
    pub shading: Vec<TriShading>,
    pub materials: Vec<Material>,
    /// The emissive triangles, and which primitive is which light.
    pub lights: Lights,
    pub camera: CameraDesc,
    /// Defaults from `scene.toml` (flags override them).
    pub defaults: RenderSection,
    /// Origin offset along the geometric normal for spawned rays, scaled to the scene.
    pub ray_epsilon: f32,
    /// Things the user should hear about (missing materials, scaled materials, …).
    pub warnings: Vec<String>,
    /// A hash of everything that determines the image (geometry, materials, camera,
    /// environment): references record it, so a stale reference is detected.
    pub hash: u64,
}

/// Optional settings for [`Scene::build`].
#[derive(Clone, Debug, Default)]
pub struct SceneOptions {
    pub camera: Option<CameraDesc>,
    pub environment: Option<Vec3>,
    pub defaults: RenderSection,
}

impl Scene {
    /// Build the BVH and the shading arrays from a mesh and its materials.
    pub fn build(
        source: PathBuf,
        mesh: Mesh,
        materials: Vec<Material>,
        options: SceneOptions,
        mut warnings: Vec<String>,
    ) -> Result<Scene> {
        if mesh.triangles.is_empty() {
            return Err(Error::Scene {
                path: source,
                message: "the scene has no (non-degenerate) faces".into(),
            });
        }
        if let Some(t) = mesh
            .triangles
            .iter()
            .find(|t| t.material as usize >= materials.len())
        {
            return Err(Error::Scene {
                path: source,
                message: format!("material index {} out of range", t.material),
            });
        }
        let positions: Vec<[Vec3; 3]> = mesh.triangles.iter().map(|t| t.p).collect();
        let accel = Accel::build(&positions);
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for p in positions.iter().flatten() {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let shading: Vec<TriShading> = accel
            .order
            .iter()
            .map(|&i| {
                let t = &mesh.triangles[i as usize];
                let ng = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).normalize_or_zero();
                let normals = t.normals.map_or([ng; 3], |n| n.map(|v| v.normalize()));
                TriShading {
                    normals,
                    ng,
                    uvs: t.uvs.unwrap_or([Vec2::ZERO; 3]),
                    material: t.material,
                }
            })
            .collect();
        let has_emitters = shading
            .iter()
            .any(|s| materials[s.material as usize].is_emissive());
        let environment = options.environment.unwrap_or_else(|| {
            if !has_emitters {
                warnings.push("no emitters: lighting with a uniform white environment".into());
                Vec3::ONE
            } else {
                Vec3::ZERO
            }
        });
        let radius = 0.5 * (hi - lo).length();
        let emitters = shading
            .iter()
            .enumerate()
            .filter(|(_, s)| materials[s.material as usize].is_emissive())
            .map(|(prim, s)| {
                let emission = materials[s.material as usize].emission;
                Emitter::triangle(prim as u32, accel.vertices(prim as u32), emission)
            })
            .collect();
        let lights =
            Lights::build(emitters, shading.len(), environment, radius).map_err(|message| {
                Error::Scene {
                    path: source.clone(),
                    message,
                }
            })?;
        let camera = options.camera.unwrap_or_else(|| frame_bounds(lo, hi));
        let hash = content_hash(&mesh, &materials, &camera, environment);
        let extent = lo
            .abs()
            .max(hi.abs())
            .max_element()
            .max((hi - lo).max_element());
        Ok(Scene {
            source,
            accel,
            shading,
            materials,
            lights,
            camera,
            defaults: options.defaults,
            ray_epsilon: 1e-5 * extent.max(1e-3),
            warnings,
            hash,
        })
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.accel.len()
    }

    /// The surface at a hit (inlined into the integrator: measured 6% of a render's
    /// instructions as a call).
    #[inline(always)]
    pub fn surface(&self, hit: &Hit) -> SurfacePoint {
        let sh = &self.shading[hit.prim as usize];
        let [a, b, c] = self.accel.vertices(hit.prim);
        let b0 = 1.0 - hit.b1 - hit.b2;
        let p = a * b0 + b * hit.b1 + c * hit.b2;
        let n = sh.normals[0] * b0 + sh.normals[1] * hit.b1 + sh.normals[2] * hit.b2;
        let mut ns = n.try_normalize().unwrap_or(sh.ng);
        if ns.dot(sh.ng) < 0.0 {
            ns = -ns;
        }
        SurfacePoint {
            p,
            ng: sh.ng,
            ns,
            uv: sh.uvs[0] * b0 + sh.uvs[1] * hit.b1 + sh.uvs[2] * hit.b2,
            material: sh.material,
        }
    }

    /// Radiance of rays that escape (the environment light's, kept in [`Lights`]).
    #[inline]
    pub fn environment(&self) -> Vec3 {
        self.lights.environment
    }

    /// The BSDF at a surface point: the one place where a texture would enter.
    #[inline]
    pub fn bsdf_at(&self, s: &SurfacePoint) -> Bsdf {
        self.materials[s.material as usize].bsdf()
    }

    /// The material at a surface point.
    #[inline]
    pub fn material_at(&self, s: &SurfacePoint) -> &Material {
        &self.materials[s.material as usize]
    }
}

/// Hash of the scene's content, in input order: every float by its bits.
fn content_hash(mesh: &Mesh, materials: &[Material], camera: &CameraDesc, env: Vec3) -> u64 {
    fn put(words: &mut Vec<u64>, vs: &[Vec3]) {
        for v in vs {
            words.extend(v.to_array().map(|x| x.to_bits() as u64));
        }
    }
    let mut w: Vec<u64> = Vec::with_capacity(mesh.triangles.len() * 20 + 64);
    for t in &mesh.triangles {
        put(&mut w, &t.p);
        if let Some(n) = &t.normals {
            put(&mut w, n);
        }
        w.push(t.material as u64);
    }
    for m in materials {
        put(&mut w, &[m.kd(), m.ks(), m.emission]);
        w.push(m.exponent().to_bits() as u64);
    }
    put(&mut w, &[camera.eye, camera.target, camera.up, env]);
    w.push(camera.fov_deg.to_bits() as u64);
    hash_words(&w)
}

/// A camera looking at the bounding box from +z, far enough back to see all of it at 40°.
fn frame_bounds(lo: Vec3, hi: Vec3) -> CameraDesc {
    let centre = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(1e-3);
    let fov_deg = 40.0f32;
    let dist = radius / (0.5 * fov_deg.to_radians()).sin();
    CameraDesc {
        eye: centre + Vec3::Z * dist,
        target: centre,
        up: Vec3::Y,
        fov_deg,
    }
}

/// Load a scene from an `.obj` (with a `scene.toml` beside it that names it, if any), a
/// `scene.toml`, or a folder holding a `scene.toml`.
pub fn load(path: &Path) -> Result<Scene> {
    if !path.exists() {
        return Err(Error::NotFound {
            path: path.to_path_buf(),
        });
    }
    let (obj_path, desc) = if path.is_dir() {
        let toml = path.join("scene.toml");
        if !toml.is_file() {
            return Err(Error::Scene {
                path: path.to_path_buf(),
                message: "folder holds no scene.toml".into(),
            });
        }
        let d = Description::load(&toml)?;
        (path.join(&d.obj), Some(d))
    } else {
        match path.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("toml") => {
                let d = Description::load(path)?;
                (
                    path.parent().unwrap_or(Path::new(".")).join(&d.obj),
                    Some(d),
                )
            }
            Some(e) if e.eq_ignore_ascii_case("obj") => {
                let beside = path.with_file_name("scene.toml");
                let d = if beside.is_file() {
                    let d = Description::load(&beside)?;
                    let names_us = Path::new(&d.obj).file_name() == path.file_name();
                    names_us.then_some(d)
                } else {
                    None
                };
                (path.to_path_buf(), d)
            }
            _ => {
                return Err(Error::Scene {
                    path: path.to_path_buf(),
                    message: "not a scene: expected an .obj, a scene.toml or a folder".into(),
                })
            }
        }
    };
    let (mesh, materials, warnings) = obj::load_obj(&obj_path)?;
    let options = match desc {
        Some(d) => SceneOptions {
            camera: d.camera.map(|c| CameraDesc {
                eye: Vec3::from_array(c.eye.into_inner()),
                target: Vec3::from_array(c.target.into_inner()),
                up: Vec3::from_array(c.up.into_inner()),
                fov_deg: c.fov.into_inner(),
            }),
            environment: d
                .environment
                .map(|e| Vec3::from_array(e.radiance.into_inner())),
            defaults: d.render.unwrap_or_default(),
        },
        None => SceneOptions::default(),
    };
    Scene::build(obj_path, mesh, materials, options, warnings)
}
