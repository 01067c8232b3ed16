//! Wavefront OBJ + MTL loading through tobj: triangulated (fan), one index per vertex.
//!
//! MTL → material: `Kd → kd` (default 0.5 grey, or 0 for a material that only emits), `Ks → ks`
//! (default 0), `Ns → n` (default 1), `Ke → emission` (default 0). A missing MTL file or a
//! `usemtl` naming an unknown material falls back to a grey diffuse material with a warning that
//! names it; a malformed MTL is an error. OBJ parse errors are located by line number with a
//! light pre-scan (tobj reports the kind of error only).

use super::{Mesh, MeshTriangle};
use crate::error::{clip, Error, Result};
use crate::limits::MAX_MAGNITUDE;
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
    let obj_error = |message: String| Error::Obj {
        path: path.to_path_buf(),
        message,
    };
    check_obj_text(&text).map_err(obj_error)?;
    let mtl_path = mtllib_path(path, &text);
    let folder = path.parent().unwrap_or(Path::new("."));
    for name in text
        .lines()
        .filter_map(|l| l.trim().strip_prefix("mtllib "))
    {
        let p = folder.join(name.trim());
        if p.is_file() {
            let mtl = crate::error::read_text(&p)?;
            check_mtl_text(&mtl).map_err(|message| Error::Mtl { path: p, message })?;
        }
    }
    let (models, materials) =
        tobj::load_obj(path, &options).map_err(|e| obj_error(e.to_string()))?;

    let mut mats: Vec<Material> = Vec::new();
    match materials {
        Ok(list) => {
            for m in &list {
                let (mat, scaled) = convert_material(m);
                if scaled {
                    warnings.push(format!(
                        "material '{}': Kd + Ks > 1, scaled down to conserve energy",
                        clip(&m.name)
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
            "{}: material '{}' is not defined, using grey diffuse",
            path.display(),
            clip(n)
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

/// Check every line of an OBJ before tobj reads it, so an error names its line: the numbers of
/// `v`, `vt`, `vn` parse, are finite and (positions) at most [`MAX_MAGNITUDE`]; the indices of
/// `f`, `l` and `p` (positions, texture coordinates and normals, 1-based or negative relative)
/// point at elements defined before them, whether or not vrpt uses that attribute.
pub fn check_obj_text(text: &str) -> std::result::Result<(), String> {
    let mut counts = [0usize; 3]; // v, vt, vn
    for (no, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let Some(tag) = words.next() else { continue };
        let at = |what: String| format!("line {}: {what}: '{}'", no + 1, clip(line.trim()));
        let floats = |min: usize, max: usize| -> std::result::Result<Vec<f32>, String> {
            let rest: Vec<&str> = line.split_whitespace().skip(1).collect();
            if rest.len() < min || rest.len() > max {
                let n = if min == max {
                    min.to_string()
                } else {
                    format!("{min} to {max}")
                };
                return Err(at(format!("{tag} needs {n} numbers, found {}", rest.len())));
            }
            rest.iter()
                .map(|w| match w.parse::<f32>() {
                    Ok(x) if x.is_finite() => Ok(x),
                    Ok(_) => Err(at(format!("{tag}: '{}' is not a finite number", clip(w)))),
                    Err(_) => Err(at(format!("{tag}: '{}' is not a number", clip(w)))),
                })
                .collect()
        };
        match tag {
            "v" => {
                let x = floats(3, 6)?;
                let p = match x.len() {
                    3 | 6 => [x[0], x[1], x[2]],
                    4 if x[3] != 0.0 => [x[0] / x[3], x[1] / x[3], x[2] / x[3]],
                    4 => return Err(at("v: the weight w is 0".into())),
                    _ => {
                        return Err(at(
                            "v needs 3, 4 (x y z w) or 6 (x y z r g b) numbers".into()
                        ))
                    }
                };
                if p.iter().any(|c| c.abs() > MAX_MAGNITUDE) {
                    return Err(at(format!("v: a coordinate is beyond ±{MAX_MAGNITUDE:e}")));
                }
                counts[0] += 1;
            }
            "vt" => {
                floats(2, 3)?;
                counts[1] += 1;
            }
            "vn" => {
                floats(3, 3)?;
                counts[2] += 1;
            }
            "f" | "l" | "p" => {
                let min = match tag {
                    "f" => 3,
                    "l" => 2,
                    _ => 1,
                };
                let refs: Vec<&str> = words.collect();
                if refs.len() < min {
                    return Err(at(format!("{tag} needs at least {min} vertices")));
                }
                for r in refs {
                    check_vertex_ref(r, &counts).map_err(&at)?;
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// One vertex of a face, line or point: `v`, `v/vt`, `v//vn` or `v/vt/vn`.
fn check_vertex_ref(r: &str, counts: &[usize; 3]) -> std::result::Result<(), String> {
    const WHAT: [&str; 3] = ["position", "texture coordinate", "normal"];
    let parts: Vec<&str> = r.split('/').collect();
    if parts.len() > 3 {
        return Err(format!("'{}' is not a vertex reference", clip(r)));
    }
    for (k, idx) in parts.iter().enumerate() {
        if idx.is_empty() {
            if k == 0 || (k == 1 && parts.len() == 2) {
                return Err(format!("'{}' is not a vertex reference", clip(r)));
            }
            continue;
        }
        let n = counts[k] as i64;
        let i: i64 = idx
            .parse()
            .map_err(|_| format!("'{}' is not an index", clip(idx)))?;
        if i == 0 || i > n || -i > n {
            return Err(format!(
                "{} index {} is out of range ({n} defined before this line)",
                WHAT[k],
                clip(idx)
            ));
        }
    }
    Ok(())
}

/// Check the numbers of an MTL file by line: colours (`Ka`, `Kd`, `Ks`, `Ke`, `Tf`) three numbers
/// (tobj reads three and panics on fewer), finite, non-negative and at most [`MAX_MAGNITUDE`]; `Ns` in `[0, 1e6]`; `Ni`, `d`, `Tr` finite.
pub fn check_mtl_text(text: &str) -> std::result::Result<(), String> {
    for (no, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let Some(tag) = words.next() else { continue };
        let at = |what: String| format!("line {}: {what}: '{}'", no + 1, clip(line.trim()));
        let (lo, hi) = match tag {
            "Ka" | "Kd" | "Ks" | "Ke" | "Tf" => (0.0, MAX_MAGNITUDE),
            "Ns" => (0.0, 1e6),
            "Ni" | "d" | "Tr" => (f32::MIN, f32::MAX),
            _ => continue,
        };
        let rest: Vec<&str> = words.collect();
        // `Kd spectral file.rfl` and `Kd xyz x y z` name other forms; vrpt reads RGB only, so
        // only plain numbers are checked
        if rest
            .first()
            .is_some_and(|w| w.eq_ignore_ascii_case("spectral") || w.eq_ignore_ascii_case("xyz"))
        {
            continue;
        }
        let colour = lo == 0.0 && hi == MAX_MAGNITUDE;
        if colour && rest.len() != 3 {
            return Err(at(format!(
                "{tag} needs 3 numbers (r g b), found {}",
                rest.len()
            )));
        }
        if rest.is_empty() {
            return Err(at(format!("{tag} has no value")));
        }
        for w in rest {
            let x: f32 = w
                .parse()
                .map_err(|_| at(format!("{tag}: '{}' is not a number", clip(w))))?;
            if !x.is_finite() {
                return Err(at(format!("{tag}: '{}' is not a finite number", clip(w))));
            }
            if !(lo..=hi).contains(&x) {
                return Err(at(format!("{tag}: {x} is outside [{lo}, {hi:e}]")));
            }
        }
    }
    Ok(())
}
