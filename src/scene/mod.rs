//! The scene: triangles with shading data in BVH order, materials, emitters, camera,
//! environment and render defaults, loaded from an `.obj`, a `scene.toml`, or a folder holding a
//! `scene.toml`.
//!
//! Conventions: right-handed, y up. A triangle's geometric normal `ng = (v1−v0)×(v2−v0)` follows
//! its counter-clockwise winding; emission is one-sided, on the side `ng` points to. Shading is
//! two-sided: the integrator flips the shading frame to the side the ray arrives from.
//! Without a description the camera frames the bounding box from +z, or stands inside where
//! that view shows the backs of surfaces; a scene with no emitter, or whose emitters light
//! almost nothing the camera sees, gets a studio light ([`Environment::studio`]: a grey sky and a
//! key light from behind the camera), so any OBJ
//! renders visibly ([`auto`]).

pub mod auto;
pub mod description;
pub mod files;
pub mod generate;
pub mod mtl;
pub mod obj;
pub mod objparse;

mod hash;
mod shading;

use crate::accel::{Accel, Hit, RayPacket, TraceStack, LANES};
use crate::bsdf::Bsdf;
use crate::camera::CameraDesc;
use crate::environment::{EnvMap, Environment};
use crate::error::{Error, Result};
use crate::lights::{Emitter, Lights};
use crate::material::Material;
use crate::texture::TextureSet;
use description::{Description, RenderSection};
use glam::{Vec2, Vec3};
use hash::{content_hash, texture_hash};
use shading::{shading_in_bvh_order, uvs_in_bvh_order};
pub use shading::{SurfacePoint, TriShading};
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

/// Everything the renderer needs.
pub struct Scene {
    /// The file the scene came from.
    pub source: PathBuf,
    pub accel: Accel,
    pub shading: Vec<TriShading>,
    /// The texture coordinates of each triangle's vertices in BVH order (zero where the file has
    /// none), where a material reads them (a colour, exponent, bump, normal or opacity map);
    /// else empty, and a hit reads zeros: 24 bytes a triangle an untextured scene does not
    /// keep, nor a ray's shading load from memory ([`Scene::triangle_uvs`]).
    pub uvs: Vec<[Vec2; 3]>,
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
    /// environment; texture coordinates and texels where there are textures): references
    /// record it, so a stale reference is detected.
    pub hash: u64,
    /// The materials' textures.
    pub textures: TextureSet,
    /// The files it was read from beyond the OBJ (`source`): its scene.toml, material
    /// libraries, environment map and textures, so a command can refuse to write over them
    /// ([`load`] fills it; [`Scene::read_from`] lists them all).
    pub files: Vec<PathBuf>,
    /// Whether a material has an opacity map (rays then test cutouts during traversal).
    cutouts: bool,
    /// Whether a material has a bump or normal map.
    perturbed: bool,
    /// Whether a material has a colour or exponent map.
    coloured: bool,
}

/// Optional settings for [`Scene::build`].
#[derive(Clone, Debug, Default)]
pub struct SceneOptions {
    pub camera: Option<CameraDesc>,
    pub environment: Option<Environment>,
    pub defaults: RenderSection,
    /// The materials' textures.
    pub textures: TextureSet,
    /// Where the camera or the environment is not given, choose them from a survey of the
    /// scene ([`auto`]: a view that sees the fronts of surfaces, a white environment where the
    /// emitters light almost nothing it sees), as a scene loaded without a description does;
    /// without it, the view from +z and a white environment only for a scene without emitters.
    pub auto_view: bool,
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
        check_mesh(&source, &mesh, materials.len())?;
        let accel = Accel::build_from(mesh.triangles.iter().map(|t| t.p));
        let (lo, hi) = bounds(mesh.triangles.iter().map(|t| &t.p));
        let shading = shading_in_bvh_order(&accel, &mesh);
        let cutouts = materials.iter().any(|m| m.maps.opacity.is_some());
        let perturbed = materials.iter().any(|m| m.maps.perturbs_normal());
        let coloured = materials.iter().any(|m| m.maps.colour());
        let uvs = if cutouts || perturbed || coloured {
            uvs_in_bvh_order(&accel, &mesh)
        } else {
            Vec::new()
        };
        let extent = lo
            .abs()
            .max(hi.abs())
            .max_element()
            .max((hi - lo).max_element());
        let ray_epsilon = 1e-5 * extent.max(1e-3);
        let emitters = emitters_of(&accel, &shading, &materials);
        let geometry = auto::Geometry {
            accel: &accel,
            shading: &shading,
            emitters: &emitters,
            epsilon: ray_epsilon,
        };
        let (camera, seen) = auto::camera_of(
            options.camera,
            options.auto_view,
            &geometry,
            (lo, hi),
            &mut warnings,
        );
        let environment = (options.environment).unwrap_or_else(|| {
            auto::environment_of(&camera, &emitters, seen.as_ref(), &mut warnings)
        });
        let radius = 0.5 * (hi - lo).length();
        let mut hash = content_hash(&mesh, &materials, &camera, &environment);
        if !options.textures.textures.is_empty() {
            hash = texture_hash(hash, &mesh, &materials, &options.textures);
        }
        let lights =
            Lights::build(emitters, shading.len(), environment, radius).map_err(|message| {
                Error::Scene {
                    path: source.clone(),
                    message,
                }
            })?;
        Ok(Scene {
            source,
            accel,
            shading,
            uvs,
            lights,
            camera,
            defaults: options.defaults,
            ray_epsilon,
            warnings,
            hash,
            cutouts,
            perturbed,
            coloured,
            materials,
            textures: options.textures,
            files: Vec::new(),
        })
    }

    /// Every file the scene was read from, each named for an error message: the OBJ, then
    /// [`Scene::files`] (for [`crate::image_io::check_outputs`]).
    pub fn read_from(&self) -> Vec<crate::image_io::NamedPath<'_>> {
        std::iter::once(self.source.as_path())
            .chain(self.files.iter().map(PathBuf::as_path))
            .map(|p| ("the scene's file", p))
            .collect()
    }

    /// Bytes the geometry holds: the BVH with its triangles and index maps, and the shading
    /// data (normals, materials, texture coordinates where kept), in that order.
    pub fn memory_bytes(&self) -> (usize, usize) {
        (
            self.accel.memory_bytes(),
            std::mem::size_of_val(self.shading.as_slice())
                + std::mem::size_of_val(self.uvs.as_slice()),
        )
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.accel.len()
    }

    /// The closest hit along `origin + t·dir`, `t < tmax`, passing through cutouts (where a
    /// material's `map_d` opacity is below 0.5) inside the traversal.
    #[inline]
    pub fn intersect(
        &self,
        stack: &mut TraceStack,
        origin: Vec3,
        dir: Vec3,
        tmax: f32,
    ) -> Option<Hit> {
        if self.cutouts {
            self.accel
                .intersect_filtered(stack, (origin, dir, tmax), |p, b| self.opaque(p, b))
        } else {
            self.accel.intersect_with(stack, origin, dir, tmax)
        }
    }

    /// [`Scene::intersect`] for each live lane of the packet `p`, into `out`: in lanes where
    /// [`crate::accel::Accel::intersect_packet`] takes them so and the scene has no
    /// cutouts, else ray by ray; the same hits either way, bit for bit.
    #[inline]
    pub fn intersect_packet(
        &self,
        stack: &mut TraceStack,
        p: &RayPacket,
        out: &mut [Option<Hit>; LANES],
    ) {
        if !self.cutouts {
            return self.accel.intersect_packet(stack, p, out);
        }
        for lane in p.lanes() {
            let (o, d, tmax) = p.ray(lane);
            out[lane] = self.intersect(stack, o, d, tmax);
        }
    }

    /// Whether anything but cutouts lies along `origin + t·dir`, `t ∈ (0, tmax)`.
    #[inline]
    pub fn occluded(&self, stack: &mut TraceStack, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        if self.cutouts {
            self.accel
                .occluded_filtered(stack, (origin, dir, tmax), |p, b| self.opaque(p, b))
        } else {
            self.accel.occluded_with(stack, origin, dir, tmax)
        }
    }

    /// Whether BVH-order triangle `prim` is there at barycentrics `b` (its opacity map, if
    /// any, at least 0.5).
    #[inline]
    fn opaque(&self, prim: u32, b: Vec2) -> bool {
        let sh = &self.shading[prim as usize];
        let m = &self.materials[sh.material as usize];
        if m.maps.opacity.is_none() {
            return true;
        }
        let uvs = self.triangle_uvs(prim);
        let uv = uvs[0] * (1.0 - b.x - b.y) + uvs[1] * b.x + uvs[2] * b.y;
        m.opaque_at(uv, &self.textures)
    }

    /// What rays that escape see (the environment light, kept in [`Lights`]).
    #[inline]
    pub fn environment(&self) -> &Environment {
        &self.lights.environment
    }

    /// The BSDF at a surface point: its material's, with the material's textures at `s.uv`.
    #[inline]
    pub fn bsdf_at(&self, s: &SurfacePoint) -> Bsdf {
        let m = &self.materials[s.material as usize];
        if self.coloured {
            m.bsdf_at(s.uv, &self.textures)
        } else {
            m.bsdf()
        }
    }

    /// The material at a surface point.
    #[inline]
    pub fn material_at(&self, s: &SurfacePoint) -> &Material {
        &self.materials[s.material as usize]
    }
}

/// An error unless `mesh` has a triangle and every triangle's material is one of `materials`
/// (`source` names the scene).
fn check_mesh(source: &Path, mesh: &Mesh, materials: usize) -> Result<()> {
    if mesh.triangles.is_empty() {
        return Err(Error::Scene {
            path: source.to_path_buf(),
            message: "the scene has no (non-degenerate) faces".into(),
        });
    }
    if let Some(t) = mesh
        .triangles
        .iter()
        .find(|t| t.material as usize >= materials)
    {
        return Err(Error::Scene {
            path: source.to_path_buf(),
            message: format!("material index {} out of range", t.material),
        });
    }
    Ok(())
}

/// The corners `(lo, hi)` of the bounding box of the triangles' vertices.
fn bounds<'a>(positions: impl Iterator<Item = &'a [Vec3; 3]>) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for p in positions.flatten() {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    (lo, hi)
}

/// An emitter for each triangle of an emissive material, knowing its primitive index in BVH
/// order, listed in the file's order: the lights' tables and tree, and so the light a sample
/// chooses, do not depend on how the BVH was built (a better build reordered the lights of the
/// door and the plates and changed their images).
fn emitters_of(accel: &Accel, shading: &[TriShading], materials: &[Material]) -> Vec<Emitter> {
    let mut prims: Vec<u32> = (0..shading.len() as u32)
        .filter(|&prim| materials[shading[prim as usize].material as usize].is_emissive())
        .collect();
    prims.sort_unstable_by_key(|&prim| accel.order[prim as usize]);
    prims
        .into_iter()
        .map(|prim| {
            let emission = materials[shading[prim as usize].material as usize].emission;
            Emitter::triangle(prim, accel.vertices(prim), emission)
        })
        .collect()
}

/// Load a scene from an `.obj` (with a `scene.toml` beside it that names it, if any), a
/// `scene.toml`, or a folder holding a `scene.toml`.
pub fn load(path: &Path) -> Result<Scene> {
    load_with(path, false)
}

/// [`load`], refusing with `strict` what a lenient load only warns of: a texture or material
/// library found by another name than written, a texture that cannot be found or read, a
/// malformed statement skipped ([`obj`]).
pub fn load_with(path: &Path, strict: bool) -> Result<Scene> {
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
        (path.join(&d.obj), Some((d, toml)))
    } else {
        match path.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("toml") => {
                let d = Description::load(path)?;
                (
                    path.parent().unwrap_or(Path::new(".")).join(&d.obj),
                    Some((d, path.to_path_buf())),
                )
            }
            Some(e) if e.eq_ignore_ascii_case("obj") => {
                let beside = path.with_file_name("scene.toml");
                let d = if beside.is_file() {
                    let d = Description::load(&beside)?;
                    let names_us = Path::new(&d.obj).file_name() == path.file_name();
                    names_us.then_some((d, beside))
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
    let obj = obj::load_obj(&obj_path, strict)?;
    let desc_env_file: Option<PathBuf> = desc.as_ref().and_then(|(d, toml)| {
        let map = d.environment.as_ref()?.map.as_ref()?;
        Some(toml.parent().unwrap_or(Path::new(".")).join(map.get_ref()))
    });
    let toml_file = desc.as_ref().map(|(_, toml)| toml.clone());
    let textures = obj.textures;
    let options = match desc {
        Some((d, toml)) => SceneOptions {
            camera: d.camera.map(|c| CameraDesc {
                eye: Vec3::from_array(c.eye.into_inner()),
                target: Vec3::from_array(c.target.into_inner()),
                up: Vec3::from_array(c.up.into_inner()),
                fov_deg: c.fov.into_inner(),
            }),
            environment: d.environment.map(|e| environment(&e, &toml)).transpose()?,
            defaults: d.render.unwrap_or_default(),
            textures,
            auto_view: false,
        },
        None => SceneOptions {
            textures,
            auto_view: true,
            ..SceneOptions::default()
        },
    };
    let mut scene = Scene::build(obj_path, obj.mesh, obj.materials, options, obj.warnings)?;
    scene.files = toml_file
        .into_iter()
        .chain(obj.libraries)
        .chain(desc_env_file)
        .chain(scene.textures.paths().map(Path::to_path_buf))
        .collect();
    Ok(scene)
}

/// The environment of a description's `[environment]` (validated by
/// [`Description::parse`]): its radiance, or its map read from beside `toml`. A map that cannot
/// be read, or holds a negative or non-finite pixel, is one error naming the line of `map`.
fn environment(e: &description::EnvironmentSection, toml: &Path) -> Result<Environment> {
    let Some(map) = &e.map else {
        let r = e.radiance.as_ref().map_or([0.0; 3], |r| *r.get_ref());
        return Ok(Environment::Constant(Vec3::from_array(r)));
    };
    let err = |message: String| Error::Toml {
        path: toml.to_path_buf(),
        message: format!("line {}: environment.map: {message}", e.map_line),
    };
    let file = toml.parent().unwrap_or(Path::new(".")).join(map.get_ref());
    let img = crate::image_io::read_exr(&file).map_err(|x| err(x.to_string()))?;
    let rotation = e.rotation.as_ref().map_or(0.0, |r| *r.get_ref());
    let scale = e.scale.as_ref().map_or(1.0, |s| *s.get_ref());
    EnvMap::new(img.width, img.height, &img.pixels, rotation, scale)
        .map(Environment::Map)
        .map_err(|m| err(format!("{}: {m}", file.display())))
}
