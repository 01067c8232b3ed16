//! Wavefront OBJ + MTL loading through tobj: triangulated (fan), one index per vertex.
//!
//! MTL → material: `Kd → kd` (default 0.5 grey, or 0 for a material that only emits), `Ks → ks`
//! (default 0), `Ns → n` (default 1), `Ke → emission` (default 0). A missing MTL file or a
//! `usemtl` naming an unknown material falls back to a grey diffuse material with a warning that
//! names it; a malformed MTL is an error. OBJ parse errors are located by line number with a
//! light pre-scan (tobj reports the kind of error only).

use super::{Mesh, MeshTriangle};
use crate::error::{Error, Result};
use crate::material::Material;
use glam::{Vec2, Vec3};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Load `path` into a triangle soup, its materials and any warnings.
pub fn load_obj(path: &Path) -> Result<(Mesh, Vec<Material>, Vec<String>)> {
    let text = crate::error::read_text(path)?;
    let mut warnings = Vec::new();
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, materials) = tobj::load_obj(path, &options).map_err(|e| Error::Obj {
        path: path.to_path_buf(),
        message: locate_obj_error(&text).unwrap_or_else(|| e.to_string()),
    })?;

    let mtl_path = mtllib_path(path, &text);
    let mut mats: Vec<Material> = Vec::new();
    match materials {
        Ok(list) => {
            for m in &list {
                let (mat, scaled) = convert_material(m);
                if scaled {
                    warnings.push(format!(
                        "material '{}': Kd + Ks > 1, scaled down to conserve energy",
                        m.name
                    ));
                }
                mats.push(mat);
            }
        }
        Err(tobj::LoadError::OpenFileFailed) => {
            if let Some(p) = &mtl_path {
                warnings.push(format!(
                    "{}: material library not found, using grey diffuse",
                    p.display()
                ));
            }
        }
        Err(e) => {
            return Err(Error::Mtl {
                path: mtl_path.unwrap_or_else(|| path.to_path_buf()),
                message: e.to_string(),
            })
        }
    }
    // Names used by `usemtl` that no MTL defines: warn once per name.
    let known: BTreeSet<&str> = mats.iter().map(|m| m.name.as_str()).collect();
    let unknown: BTreeSet<&str> = text
        .lines()
        .filter_map(|l| l.trim().strip_prefix("usemtl "))
        .map(str::trim)
        .filter(|n| !known.contains(n))
        .collect();
    for n in &unknown {
        warnings.push(format!(
            "{}: material '{n}' is not defined, using grey diffuse",
            path.display()
        ));
    }
    let fallback = mats.len() as u32;
    let mut used_fallback = false;

    let mut triangles = Vec::new();
    let mut degenerate = 0usize;
    for model in &models {
        let mesh = &model.mesh;
        let material = match mesh.material_id {
            Some(id) if id < mats.len() => id as u32,
            _ => {
                used_fallback = true;
                fallback
            }
        };
        let pos = |i: u32| {
            let i = i as usize * 3;
            Vec3::new(
                mesh.positions[i],
                mesh.positions[i + 1],
                mesh.positions[i + 2],
            )
        };
        let has_normals = mesh.normals.len() == mesh.positions.len();
        let has_uvs =
            !mesh.texcoords.is_empty() && mesh.texcoords.len() / 2 == mesh.positions.len() / 3;
        let uv = |i: u32| {
            let i = i as usize * 2;
            Vec2::new(mesh.texcoords[i], mesh.texcoords[i + 1])
        };
        let nrm = |i: u32| {
            let i = i as usize * 3;
            Vec3::new(mesh.normals[i], mesh.normals[i + 1], mesh.normals[i + 2])
        };
        for f in mesh.indices.chunks_exact(3) {
            let p = [pos(f[0]), pos(f[1]), pos(f[2])];
            if !p.iter().all(|v| v.is_finite()) {
                return Err(Error::Obj {
                    path: path.to_path_buf(),
                    message: "a vertex position is not a finite number".into(),
                });
            }
            if (p[1] - p[0]).cross(p[2] - p[0]).length_squared() == 0.0 {
                degenerate += 1;
                continue;
            }
            let normals = if has_normals {
                let n = [nrm(f[0]), nrm(f[1]), nrm(f[2])];
                n.iter()
                    .all(|v| v.is_finite() && v.length_squared() > 0.0)
                    .then_some(n)
            } else {
                None
            };
            let uvs = has_uvs.then(|| [uv(f[0]), uv(f[1]), uv(f[2])]);
            triangles.push(MeshTriangle {
                p,
                normals,
                uvs,
                material,
            });
        }
    }
    if degenerate > 0 {
        warnings.push(format!(
            "{}: skipped {degenerate} degenerate (zero-area) triangles",
            path.display()
        ));
    }
    if used_fallback {
        mats.push(Material::default_grey("default-grey"));
    }
    Ok((Mesh { triangles }, mats, warnings))
}

fn convert_material(m: &tobj::Material) -> (Material, bool) {
    let v = |a: Option<[f32; 3]>, d: f32| a.map_or(Vec3::splat(d), Vec3::from_array);
    let ke = v(m.emissive, 0.0);
    let kd_default = if ke.max_element() > 0.0 { 0.0 } else { 0.5 };
    Material::new(
        &m.name,
        v(m.diffuse, kd_default),
        v(m.specular, 0.0),
        m.shininess.unwrap_or(1.0),
        ke,
    )
}

/// The path of the first `mtllib` of the OBJ, relative to its folder.
fn mtllib_path(obj: &Path, text: &str) -> Option<PathBuf> {
    let name = text
        .lines()
        .find_map(|l| l.trim().strip_prefix("mtllib "))?
        .trim();
    Some(obj.parent().unwrap_or(Path::new(".")).join(name))
}

/// Find the first line that tobj would reject, for an error message with a line number.
fn locate_obj_error(text: &str) -> Option<String> {
    let mut counts = [0usize; 3]; // v, vt, vn
    for (no, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let Some(tag) = words.next() else { continue };
        let rest: Vec<&str> = words.collect();
        let floats_ok = |min: usize, max: usize| {
            rest.len() >= min && rest.len() <= max && rest.iter().all(|w| w.parse::<f32>().is_ok())
        };
        let bad = match tag {
            "v" => {
                counts[0] += 1;
                !floats_ok(3, 7)
            }
            "vt" => {
                counts[1] += 1;
                !floats_ok(1, 3)
            }
            "vn" => {
                counts[2] += 1;
                !floats_ok(3, 3)
            }
            "f" => {
                rest.len() < 3
                    || rest.iter().any(|w| {
                        w.split('/').enumerate().any(|(k, idx)| {
                            if idx.is_empty() {
                                return k == 0;
                            }
                            match idx.parse::<i64>() {
                                Ok(i) => {
                                    let n = counts[[0, 1, 2][k.min(2)]] as i64;
                                    i == 0 || i > n || -i > n
                                }
                                Err(_) => true,
                            }
                        })
                    })
            }
            _ => false,
        };
        if bad {
            return Some(format!("line {}: cannot parse '{}'", no + 1, line.trim()));
        }
    }
    None
}
