//! `vrpt info`: what the loader found in a scene, before any render: its files, triangles,
//! bounds, materials (and the names it used that no library defines), emitters and their power,
//! the environment, textures (and those that fell back), the camera it would use (from
//! scene.toml, or placed by [`crate::scene::auto`]), its render defaults, the memory of its
//! BVH and shading data, and every warning of the load.

use super::LoadArgs;
use crate::bsdf::Specular;
use crate::environment::Environment;
use crate::error::{clip, Result};
use crate::scene::Scene;
use std::path::PathBuf;

/// `vrpt info`'s flags.
#[derive(Clone, Debug, Default, clap::Args)]
pub struct InfoRequest {
    /// The scene: an .obj file, a scene.toml, or a folder holding a scene.toml.
    pub scene: PathBuf,
    #[command(flatten)]
    pub load: LoadArgs,
}

/// What `vrpt info` found: the scene, and the time its load took.
pub struct SceneInfo {
    pub scene: Scene,
    pub load_seconds: f64,
}

/// Load the scene as `render` would.
pub fn run(req: &InfoRequest) -> Result<SceneInfo> {
    let start = std::time::Instant::now();
    let scene = req.load.load(&req.scene)?;
    Ok(SceneInfo {
        scene,
        load_seconds: start.elapsed().as_secs_f64(),
    })
}

/// How many materials are listed by name before the rest are counted.
const LISTED: usize = 24;

impl SceneInfo {
    /// The report, a line per fact (materials one per line).
    pub fn text(&self) -> String {
        let s = &self.scene;
        let v = |x: glam::Vec3| format!("({:.4}, {:.4}, {:.4})", x.x, x.y, x.z);
        let mut out = format!("scene: {}\n", s.source.display());
        for f in &s.files {
            out += &format!("  read: {}\n", f.display());
        }
        let (mut lo, mut hi) = (glam::Vec3::INFINITY, glam::Vec3::NEG_INFINITY);
        for p in (0..s.triangle_count() as u32).flat_map(|t| s.accel.vertices(t)) {
            (lo, hi) = (lo.min(p), hi.max(p));
        }
        out += &format!(
            "triangles: {}, loaded in {:.2} s (BVH {:.2} s)\nbounds: {} to {} (size {})\n",
            s.triangle_count(),
            self.load_seconds,
            s.accel.build_time.as_secs_f64(),
            v(lo),
            v(hi),
            v(hi - lo)
        );
        out += &self.materials();
        let lights = &s.lights;
        // + 0.0: an empty sum of f32 is −0.0
        let power = lights.emitters.iter().map(|e| e.power()).sum::<f32>() + 0.0;
        out += &format!(
            "emitters: {} (triangles and rectangles), total power {power:.4}\n",
            lights.emitters.len()
        );
        out += &match &lights.environment {
            Environment::Constant(c) => format!("environment: constant radiance {}\n", v(*c)),
            Environment::Map(m) => {
                let (w, h) = m.size();
                format!(
                    "environment: a {w}×{h} lat-long map, ∫L dω = {:.4} (a file under read:, or \
                     the studio light a warning names)\n",
                    lights.environment.luminance_integral()
                )
            }
        };
        out += &format!("textures: {} loaded\n", s.textures.textures.len());
        let c = &s.camera;
        out += &format!(
            "camera: eye {} target {} up {} fov {:.2}°\n",
            v(c.eye),
            v(c.target),
            v(c.up),
            c.fov_deg
        );
        let d = crate::render::RenderSettings::for_scene(s);
        out += &format!(
            "render defaults: {}x{}, {} spp, max depth {}\n",
            d.width, d.height, d.spp, d.max_depth
        );
        let bytes = s.memory_bytes().0 + s.memory_bytes().1;
        out += &format!(
            "memory: {:.1} MB for the BVH and shading data ({:.0} bytes per triangle), \
             {:.1} MB of texels\n",
            bytes as f64 / 1e6,
            bytes as f64 / s.triangle_count().max(1) as f64,
            s.textures.bytes() as f64 / 1e6
        );
        if s.warnings.is_empty() {
            out += "warnings: none\n";
        }
        for w in &s.warnings {
            out += &format!("warning: {w}\n");
        }
        out
    }

    /// A line per material (the first [`LISTED`]): its lobes and emission, how many triangles
    /// use it.
    fn materials(&self) -> String {
        let s = &self.scene;
        let mut used = vec![0usize; s.materials.len()];
        for t in &s.shading {
            used[t.material as usize] += 1;
        }
        let mut out = format!("materials: {}\n", s.materials.len());
        let v = |x: glam::Vec3| format!("({:.3}, {:.3}, {:.3})", x.x, x.y, x.z);
        for (m, n) in s.materials.iter().zip(&used).take(LISTED) {
            let lobe = match m.specular {
                Some(Specular::Mirror {
                    reflectance,
                    schlick,
                }) => format!(
                    "mirror {}{} over diffuse {}",
                    v(reflectance),
                    if schlick { " (Fresnel)" } else { "" },
                    v(m.kd())
                ),
                Some(Specular::Dielectric { ior, transmittance }) => {
                    format!("glass, index {ior}, transmittance {}", v(transmittance))
                }
                None => format!(
                    "phong kd {} ks {} Ns {}",
                    v(m.kd()),
                    v(m.ks()),
                    m.exponent()
                ),
            };
            let emits = if m.is_emissive() {
                format!(", emits {}", v(m.emission))
            } else {
                String::new()
            };
            let maps = if m.maps.colour() || m.maps.opacity.is_some() || m.maps.perturbs_normal() {
                ", textured"
            } else {
                ""
            };
            out += &format!(
                "  '{}': {lobe}{emits}{maps}; {n} triangles\n",
                clip(&m.name)
            );
        }
        if s.materials.len() > LISTED {
            out += &format!("  … and {} more\n", s.materials.len() - LISTED);
        }
        out
    }
}
