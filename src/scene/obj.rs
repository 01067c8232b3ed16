//! Wavefront OBJ + MTL loading through tobj: triangulated (fan), one index per vertex.
//!
//! MTL → material: `Kd → kd` (default 0.5 grey, or 0 for a material that only emits), `Ks → ks`
//! (default 0), `Ns → n` (default 1), `Ke → emission` (default 0). A missing MTL file or a
//! `usemtl` naming an unknown material falls back to a grey diffuse material with a warning that
//! names it; a malformed MTL is an error. OBJ parse errors are located by line number with a
//! light pre-scan (tobj reports the kind of error only).
//!
//! Textures: the MTL's `map_Kd`, `map_Ks`, `map_Ns`, `map_d`, `bump`/`map_Bump` and `norm`
//! statements are read here ([`parse_maps`]: the options `-s`, `-o`, `-bm`; others skipped and
//! named in one warning), their files loaded once each ([`crate::texture::TextureSet`]) into the
//! materials' [`crate::material::Maps`]; a file that cannot be read is an error naming the MTL
//! line.

use super::{Mesh, MeshTriangle};
use crate::error::{clip, Error, Result};
use crate::limits::MAX_MAGNITUDE;
use crate::material::Material;
use crate::texture::{Decode, TextureRef, TextureSet};
use glam::{Vec2, Vec3};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// What an OBJ file gave: its triangles, materials and their textures, the material libraries
/// it read, and what the user should hear about.
pub struct ObjFile {
    pub mesh: Mesh,
    pub materials: Vec<Material>,
    pub textures: TextureSet,
    /// The MTL files read (those its `mtllib` statements name that exist).
    pub libraries: Vec<PathBuf>,
    pub warnings: Vec<String>,
}

/// Load `path` into a triangle soup, its materials, their textures and any warnings.
pub fn load_obj(path: &Path) -> Result<ObjFile> {
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
    let (libraries, map_lines) = read_mtl_maps(path, &text, &mut warnings)?;
    let (models, materials) =
        tobj::load_obj(path, &options).map_err(|e| obj_error(e.to_string()))?;
    let mut mats = convert_materials(path, &text, materials, &mut warnings)?;
    warn_unknown_materials(path, &text, &mats, &mut warnings);
    let fallback = mats.len() as u32;
    let mut used_fallback = false;

    let mut triangles = Vec::new();
    let mut degenerate = 0usize;
    for model in &models {
        let material = match model.mesh.material_id {
            Some(id) if id < mats.len() => id as u32,
            _ => {
                used_fallback = true;
                fallback
            }
        };
        degenerate += mesh_triangles(path, &model.mesh, material, &mut triangles)?;
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
    let textures = attach_maps(&mut mats, &map_lines)?;
    Ok(ObjFile {
        mesh: Mesh { triangles },
        materials: mats,
        textures,
        libraries,
        warnings,
    })
}

/// The MTL files read, and each texture statement with its MTL's path.
type MtlMaps = (Vec<PathBuf>, Vec<(PathBuf, MapLine)>);

/// The MTLs the OBJ `text` names (`mtllib`) that exist, and the texture statements of each,
/// with its MTL's path; a warning per MTL that names the statements and options it ignores.
fn read_mtl_maps(
    path: &Path,
    text: &str,
    warnings: &mut Vec<String>,
) -> Result<MtlMaps> {
    let folder = path.parent().unwrap_or(Path::new("."));
    let mut map_lines: Vec<(PathBuf, MapLine)> = Vec::new();
    let mut libraries = Vec::new();
    for name in text
        .lines()
        .filter_map(|l| l.trim().strip_prefix("mtllib "))
    {
        let p = folder.join(name.trim());
        if p.is_file() {
            let mtl = crate::error::read_text(&p)?;
            check_mtl_text(&mtl).map_err(|message| Error::Mtl {
                path: p.clone(),
                message,
            })?;
            let mut ignored = BTreeSet::new();
            let maps = parse_maps(&mtl, &mut ignored).map_err(|message| Error::Mtl {
                path: p.clone(),
                message,
            })?;
            if !ignored.is_empty() {
                let list: Vec<&str> = ignored.iter().map(String::as_str).collect();
                warnings.push(format!(
                    "{}: ignored texture statements and options: {}",
                    p.display(),
                    clip(&list.join(", "))
                ));
            }
            map_lines.extend(maps.into_iter().map(|m| (p.clone(), m)));
            libraries.push(p);
        }
    }
    Ok((libraries, map_lines))
}

/// vrpt's materials from tobj's reading of the MTL: none (with a warning) where the MTL file is
/// missing, an error where it is malformed, a warning for each material scaled to conserve energy.
fn convert_materials(
    path: &Path,
    text: &str,
    materials: std::result::Result<Vec<tobj::Material>, tobj::LoadError>,
    warnings: &mut Vec<String>,
) -> Result<Vec<Material>> {
    let mtl_path = mtllib_path(path, text);
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
    Ok(mats)
}

/// Warn once per name used by `usemtl` in the OBJ `text` that no material in `mats` has.
fn warn_unknown_materials(path: &Path, text: &str, mats: &[Material], warnings: &mut Vec<String>) {
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
}

/// Push the triangles of one tobj mesh, all of `material`, onto `triangles`, with their vertex
/// normals (where all three are finite and non-zero) and texture coordinates where the mesh has
/// them. Returns how many zero-area triangles it skipped; an error for a non-finite position.
fn mesh_triangles(
    path: &Path,
    mesh: &tobj::Mesh,
    material: u32,
    triangles: &mut Vec<MeshTriangle>,
) -> Result<usize> {
    let mut degenerate = 0usize;
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
    Ok(degenerate)
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

/// Load the textures of `lines` (each with its MTL) once per file and decoding, and give each
/// material its maps (by name: a statement under `newmtl X` belongs to the material X). A file
/// that cannot be read is one error naming the MTL and the statement's line.
fn attach_maps(mats: &mut [Material], lines: &[(PathBuf, MapLine)]) -> Result<TextureSet> {
    let mut set = TextureSet::default();
    for (mtl, m) in lines {
        let Some(mat) = mats.iter_mut().find(|x| x.name == m.material) else {
            continue;
        };
        let decode = match m.key.as_str() {
            "map_kd" | "map_ks" => Decode::Srgb,
            _ => Decode::Linear,
        };
        let file = mtl.parent().unwrap_or(Path::new(".")).join(&m.file);
        let index = set.load(&file, decode).map_err(|e| Error::Mtl {
            path: mtl.clone(),
            message: format!("line {}: {}: {e}", m.line, m.tag),
        })?;
        let r = TextureRef {
            index,
            scale: m.scale,
            offset: m.offset,
        };
        let maps = &mut mat.maps;
        match m.key.as_str() {
            "map_kd" => maps.kd = Some(r),
            "map_ks" => maps.ks = Some(r),
            "map_ns" => maps.ns = Some(r),
            "map_d" => maps.opacity = Some(r),
            "norm" => maps.normal = Some(r),
            _ => maps.bump = Some((r, m.bump_mult)),
        }
    }
    Ok(set)
}

/// One texture statement of an MTL (`map_Kd`, `map_Ks`, `map_Ns`, `map_d`, `bump`,
/// `map_Bump`, `norm`): its material, keyword (lower case), file (relative to the MTL) and
/// options, and its line.
#[derive(Clone, Debug, PartialEq)]
pub struct MapLine {
    pub material: String,
    /// The keyword as written, and in lower case.
    pub tag: String,
    pub key: String,
    pub file: String,
    /// `-s u v`: scale of the texture coordinates (default 1).
    pub scale: Vec2,
    /// `-o u v`: offset of the texture coordinates (default 0).
    pub offset: Vec2,
    /// `-bm m`: the bump multiplier (default 1).
    pub bump_mult: f32,
    /// Its line in the MTL, from 1.
    pub line: usize,
}

/// The texture keywords vrpt reads.
const MAP_KEYS: [&str; 7] = [
    "map_kd", "map_ks", "map_ns", "map_d", "bump", "map_bump", "norm",
];

/// How many values each option of a texture statement takes (the MTL format's options; `-s`,
/// `-o` and `-t` take up to three numbers, read while they are numbers).
fn option_arity(opt: &str) -> Option<usize> {
    Some(match opt {
        "-blendu" | "-blendv" | "-cc" | "-clamp" | "-imfchan" | "-type" | "-boost" | "-texres"
        | "-bm" => 1,
        "-mm" => 2,
        "-s" | "-o" | "-t" => 3,
        _ => return None,
    })
}

/// The texture statements of an MTL text. Options other than `-s`, `-o` and `-bm` are skipped,
/// each named once in `ignored`; other texture keywords (`map_Ka`, `disp`, `refl`, …) are
/// named there too. Err (one line, with the line number) for a statement without a file or a
/// malformed number.
pub fn parse_maps(
    text: &str,
    ignored: &mut BTreeSet<String>,
) -> std::result::Result<Vec<MapLine>, String> {
    let mut out = Vec::new();
    let mut material = String::new();
    for (no, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let Some(tag) = words.next() else { continue };
        if tag == "newmtl" {
            material = words.collect::<Vec<_>>().join(" ");
            continue;
        }
        let key = tag.to_ascii_lowercase();
        if !MAP_KEYS.contains(&key.as_str()) {
            if key.starts_with("map_") || ["disp", "decal", "refl"].contains(&key.as_str()) {
                ignored.insert(tag.to_string());
            }
            continue;
        }
        let rest: Vec<&str> = words.collect();
        let mut m = MapLine {
            material: material.clone(),
            tag: tag.to_string(),
            key,
            file: String::new(),
            scale: Vec2::ONE,
            offset: Vec2::ZERO,
            bump_mult: 1.0,
            line: no + 1,
        };
        let k = parse_map_options(&rest, &mut m, ignored)?;
        m.file = rest[k..].join(" ");
        if m.file.is_empty() {
            return Err(format!("line {}: {tag}: no file named", no + 1));
        }
        out.push(m);
    }
    Ok(out)
}

/// Read the options at the start of the words `rest` after a texture keyword into `m` (`-s`,
/// `-o`, `-bm`; others named in `ignored`). Returns the index of the first word of the file name.
fn parse_map_options(
    rest: &[&str],
    m: &mut MapLine,
    ignored: &mut BTreeSet<String>,
) -> std::result::Result<usize, String> {
    let (line, tag) = (m.line, m.tag.clone());
    let at = |what: String| format!("line {line}: {tag}: {what}");
    let number = |w: &str| -> std::result::Result<f32, String> {
        match w.parse::<f32>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(at(format!("'{}' is not a finite number", clip(w)))),
        }
    };
    let mut k = 0;
    while k < rest.len() && rest[k].starts_with('-') && rest[k].parse::<f32>().is_err() {
        let opt = rest[k];
        k += 1;
        let Some(arity) = option_arity(opt) else {
            ignored.insert(opt.to_string());
            // an unknown option: skip the numbers after it
            while k < rest.len() && rest[k].parse::<f32>().is_ok() {
                k += 1;
            }
            continue;
        };
        let numeric = matches!(opt, "-s" | "-o" | "-t" | "-mm" | "-bm" | "-boost");
        let mut values = Vec::new();
        while values.len() < arity && k < rest.len() {
            if numeric && rest[k].parse::<f32>().is_err() {
                break;
            }
            values.push(rest[k]);
            k += 1;
        }
        if values.is_empty() {
            return Err(at(format!("{opt} needs a value")));
        }
        match opt {
            "-s" | "-o" => {
                let default = if opt == "-s" { 1.0 } else { 0.0 };
                let u = number(values[0])?;
                let v = values.get(1).map_or(Ok(default), |w| number(w))?;
                if opt == "-s" {
                    m.scale = Vec2::new(u, v);
                } else {
                    m.offset = Vec2::new(u, v);
                }
            }
            "-bm" => m.bump_mult = number(values[0])?,
            _ => {
                ignored.insert(opt.to_string());
            }
        }
    }
    Ok(k)
}
