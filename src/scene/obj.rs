//! Loading an OBJ scene: the OBJ text ([`super::objparse`]), its material libraries
//! ([`super::mtl`]), their textures, into a triangle soup and vrpt's materials. Files are read
//! as the reference loaders read them (tinyobjloader, Blender's and Mitsuba's importers), so
//! scenes made elsewhere load: comments anywhere on a line, statements vrpt does not use skipped
//! whatever they hold (one warning per file, by kind), file names with `\`, quotes or another
//! letter case found ([`super::files`]), a texture that cannot be found or read replaced by the
//! material's constant colour with a warning. A malformed number in a statement vrpt uses is
//! refused with its file and line. With `strict` every such leniency (a texture not found as
//! written or not read, a malformed statement skipped) is refused instead.
//!
//! MTL → material ([`material_of`]):
//! - `illum` 3: a mirror of reflectance `Ks` (1 where absent) over a diffuse `Kd` (0 where
//!   absent), as the MTL spec's model adds them; `illum` 5 the same with the mirror weighted by
//!   Schlick's Fresnel with `Ks` at normal incidence;
//! - `illum` 4, 6, 7, 9 on a material that lets light through (`Tf` below 1, or `d` below 1):
//!   smooth glass of index `Ni` (1.5 where absent or not above 1) and transmittance `1 − Tf`
//!   (the convention of 3ds Max and of the files that carry `Tf`: the Cornell box variants'
//!   clear water says `Tf 0.1`, and opaque materials say `Tf 1 1 1`), or 1 for glass by `d`;
//!   on an opaque material (Cinema 4D writes `illum 7` everywhere) the Phong material, noted;
//! - any other: the modified Phong material, `Kd → kd` (default 0.5 grey, or 0 for a material
//!   that only emits), `Ks → ks` (default 0), `Ns → n` (default 1); a `Ks` near 1 with a high
//!   `Ns` stays the Phong lobe it is.
//!
//! `Ke → emission` (default 0) in every case. A missing MTL file or a `usemtl` naming an unknown
//! material falls back to a grey diffuse material with a warning that names it.
//!
//! Triangles: each face a fan (in file order); vertex normals where all three corners have a
//! finite non-zero `vn`, texture coordinates where all three have a `vt`; zero-area triangles
//! skipped and counted.

use super::files::{self, Found};
use super::mtl::{self, MapLine, MtlEntry};
use super::objparse::{self, Corner, NONE};
use super::{Mesh, MeshTriangle};
use crate::bsdf::Specular;
use crate::error::{clip, Error, Result};
use crate::material::Material;
use crate::texture::{Decode, TextureRef, TextureSet};
use glam::Vec3;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// What an OBJ file gave: its triangles, materials and their textures, the material libraries
/// it read, and what the user should hear about.
pub struct ObjFile {
    pub mesh: Mesh,
    pub materials: Vec<Material>,
    pub textures: TextureSet,
    /// The MTL files read.
    pub libraries: Vec<PathBuf>,
    pub warnings: Vec<String>,
}

/// The warnings of a load, and whether leniencies are refused.
struct Notes {
    strict: bool,
    warnings: Vec<String>,
}

impl Notes {
    /// A leniency about `path`: a warning, or with `strict` the error.
    fn lenient(&mut self, path: &Path, message: String) -> Result<()> {
        if self.strict {
            return Err(Error::Scene {
                path: path.to_path_buf(),
                message: format!("{message} (refused by --strict)"),
            });
        }
        self.warnings.push(format!("{}: {message}", path.display()));
        Ok(())
    }
}

/// A text file: UTF-8 (a byte-order mark dropped, invalid bytes, names written in another
/// encoding, replaced), or UTF-16 where it starts with that byte-order mark.
pub(super) fn read_text(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => Error::NotFound {
            path: path.to_path_buf(),
        },
        _ => Error::Read {
            path: path.to_path_buf(),
            source: e,
        },
    })?;
    let utf16 = |be: bool| {
        let units: Vec<u16> = bytes[2..]
            .chunks_exact(2)
            .map(|c| match be {
                true => u16::from_be_bytes([c[0], c[1]]),
                false => u16::from_le_bytes([c[0], c[1]]),
            })
            .collect();
        String::from_utf16_lossy(&units)
    };
    Ok(match bytes.get(..3) {
        Some([0xfe, 0xff, _]) => utf16(true),
        Some([0xff, 0xfe, _]) => utf16(false),
        Some([0xef, 0xbb, 0xbf]) => String::from_utf8_lossy(&bytes[3..]).into_owned(),
        _ => String::from_utf8(bytes)
            .unwrap_or_else(|e| String::from_utf8_lossy(e.as_bytes()).into_owned()),
    })
}

/// Load `path` into a triangle soup, its materials, their textures and any warnings; with
/// `strict` a leniency is an error (module doc).
pub fn load_obj(path: &Path, strict: bool) -> Result<ObjFile> {
    let obj = read_obj(path)?;
    let mut notes = Notes {
        strict,
        warnings: Vec::new(),
    };
    if !obj.skipped.is_empty() {
        notes.warnings.push(format!(
            "{}: skipped statements vrpt does not use: {}",
            path.display(),
            kinds(&obj.skipped)
        ));
    }
    if let Some(first) = &obj.first_dangling {
        notes.lenient(
            path,
            format!(
                "{} faces name a texture coordinate or normal that is not defined (first at \
                 {first}): they are drawn without it",
                obj.dangling
            ),
        )?;
    }
    let (libraries, entries, maps) = read_libraries(path, &obj.mtllib, &mut notes)?;
    let mut materials = Vec::with_capacity(entries.len() + 1);
    for e in &entries {
        let (m, said) = material_of(e);
        notes.warnings.extend(said);
        materials.push(m);
    }
    let ids = material_ids(path, &obj, &materials, &mut notes.warnings);
    let (triangles, degenerate) = triangles(&obj, &ids, materials.len() as u32)?;
    if degenerate > 0 {
        notes.warnings.push(format!(
            "{}: skipped {degenerate} degenerate (zero-area) triangles",
            path.display()
        ));
    }
    if obj.smoothing && triangles.iter().any(|t| t.normals.is_none()) {
        notes.warnings.push(format!(
            "{}: smoothing groups (s) are not interpolated: faces without vn are shaded flat",
            path.display()
        ));
    }
    if triangles
        .iter()
        .any(|t| t.material == materials.len() as u32)
    {
        materials.push(Material::default_grey("default-grey"));
    }
    let textures = attach_maps(&mut materials, &maps, &mut notes)?;
    Ok(ObjFile {
        mesh: Mesh { triangles },
        materials,
        textures,
        libraries,
        warnings: notes.warnings,
    })
}

/// The OBJ at `path` read and parsed, within the memory limits: refused with the estimate
/// before its text is read, and before its mesh is built.
fn read_obj(path: &Path) -> Result<objparse::ObjText> {
    let memory = |what: String, bytes: u64| {
        crate::limits::check_bytes(&what, bytes).map_err(|e| Error::Scene {
            path: path.to_path_buf(),
            message: e.to_string().replace("invalid setting: ", ""),
        })
    };
    let len = std::fs::metadata(path).map_or(0, |m| m.len());
    memory(
        format!("reading its {:.0} MB of text", len as f64 / 1e6),
        len.saturating_mul(crate::limits::OBJ_BYTES_PER_TEXT_BYTE),
    )?;
    let text = read_text(path)?;
    let obj = objparse::parse(&text).map_err(|message| Error::Obj {
        path: path.to_path_buf(),
        message,
    })?;
    drop(text);
    let n = obj.triangles.len() as u64;
    memory(
        format!("a scene of {n} triangles"),
        n.saturating_mul(crate::limits::SCENE_PEAK_BYTES_PER_TRIANGLE),
    )?;
    Ok(obj)
}

/// `Ka ×12, map_Ka ×2`: the kinds of statements skipped, with their counts.
fn kinds(skipped: &BTreeMap<String, usize>) -> String {
    let list: Vec<String> = skipped.iter().map(|(k, n)| format!("{k} ×{n}")).collect();
    clip(&list.join(", ")).into_owned()
}

/// The MTL files `mtllib` statements name (each statement one file name with spaces, or several
/// names), read in order, each once: their paths, their materials in order, and their texture
/// statements (each with its MTL's path). A library not found is a warning (the materials it
/// would give fall back to grey); one found by another name a leniency.
type Libraries = (Vec<PathBuf>, Vec<MtlEntry>, Vec<(PathBuf, MapLine)>);

fn read_libraries(obj: &Path, mtllib: &[String], notes: &mut Notes) -> Result<Libraries> {
    let folder = obj.parent().unwrap_or(Path::new("."));
    let (mut paths, mut entries, mut maps) = (Vec::<PathBuf>::new(), Vec::new(), Vec::new());
    for statement in mtllib {
        let names: Vec<String> = match files::find(folder, statement) {
            Some(_) => vec![statement.clone()],
            None => statement.split_whitespace().map(String::from).collect(),
        };
        for name in names {
            let Some(Found { path, how }) = files::find(folder, &name) else {
                notes.warnings.push(format!(
                    "{}: material library not found, using grey diffuse",
                    folder.join(files::clean(&name)).display()
                ));
                continue;
            };
            if paths.contains(&path) {
                continue;
            }
            if let Some(how) = how {
                notes.lenient(obj, format!("mtllib {}: {how}", clip(&name)))?;
            }
            let text = read_text(&path)?;
            let m = mtl::parse(&text).map_err(|message| Error::Mtl {
                path: path.clone(),
                message,
            })?;
            for n in &m.notes {
                notes.lenient(&path, format!("skipped a malformed statement: {n}"))?;
            }
            if !m.skipped.is_empty() {
                notes.warnings.push(format!(
                    "{}: skipped statements vrpt does not use: {}",
                    path.display(),
                    kinds(&m.skipped)
                ));
            }
            entries.extend(m.materials);
            maps.extend(m.maps.into_iter().map(|l| (path.clone(), l)));
            paths.push(path);
        }
    }
    Ok((paths, entries, maps))
}

/// Whether a block of `illum` 4, 6, 7 or 9 lets light through: a transmission filter `Tf`
/// below 1 in some channel (3ds Max's and the Cornell box files' convention, where `Tf` is
/// 1 − transmission and opaque materials say `Tf 1 1 1`), or a dissolve `d` below 1. Exporters
/// write `illum 7` on every material of some scenes (Cinema 4D): those stay opaque.
fn lets_light_through(e: &MtlEntry) -> bool {
    e.tf.is_some_and(|t| t.min_element() < 1.0) || e.d.is_some_and(|d| d < 1.0)
}

/// vrpt's material for an MTL block (module doc), and what to say of it: a material scaled to
/// conserve energy, a dissolve that is not rendered, a glass's `Kd` that is not used, an
/// `illum` that asks for glass of an opaque material.
pub fn material_of(e: &MtlEntry) -> (Material, Vec<String>) {
    let name = clip(&e.name).into_owned();
    let mut said = Vec::new();
    let ke = e.ke.unwrap_or(Vec3::ZERO);
    let illum = e.illum.unwrap_or(2);
    let glassy = matches!(illum, 4 | 6 | 7 | 9);
    let specular = match illum {
        3 | 5 => Some(Specular::Mirror {
            reflectance: e.ks.unwrap_or(Vec3::ONE),
            schlick: illum == 5,
        }),
        _ if glassy && lets_light_through(e) => {
            let ior = e.ni.filter(|&n| n > 1.0).unwrap_or(1.5);
            // Tf as 1 − transmission (see lets_light_through); glass by dissolve alone is clear
            let transmittance =
                e.tf.filter(|t| t.min_element() < 1.0)
                    .map_or(Vec3::ONE, |t| (Vec3::ONE - t).clamp(Vec3::ZERO, Vec3::ONE));
            Some(Specular::Dielectric { ior, transmittance })
        }
        _ => None,
    };
    if glassy && specular.is_none() {
        said.push(format!(
            "material '{name}': illum {illum} without a transparency (Tf below 1 or d below 1) \
             is rendered opaque"
        ));
    }
    let kd_default = if ke.max_element() > 0.0 { 0.0 } else { 0.5 };
    if let Some(s) = specular {
        let kd = match s {
            Specular::Mirror { .. } => e.kd.unwrap_or(Vec3::ZERO),
            Specular::Dielectric { .. } => {
                if e.kd.is_some_and(|k| k.max_element() > 0.0) {
                    said.push(format!("material '{name}': glass: its Kd is not used"));
                }
                Vec3::ZERO
            }
        };
        let (m, scaled) = Material::with_delta(&e.name, kd, s, ke);
        if scaled {
            said.push(format!(
                "material '{name}': Kd + Ks > 1, scaled down to conserve energy"
            ));
        }
        return (m, said);
    }
    if e.d.is_some_and(|d| d < 1.0) {
        said.push(format!(
            "material '{name}': dissolve (d or Tr) is not rendered: the surface is opaque"
        ));
    }
    let (m, scaled) = Material::new(
        &e.name,
        e.kd.unwrap_or(Vec3::splat(kd_default)),
        e.ks.unwrap_or(Vec3::ZERO),
        e.ns.unwrap_or(1.0),
        ke,
    );
    if scaled {
        said.push(format!(
            "material '{name}': Kd + Ks > 1, scaled down to conserve energy"
        ));
    }
    (m, said)
}

/// Each `usemtl` name's material index (the last material of that name: a later definition
/// wins), or `fallback` = `materials.len()` (grey) for a name no library defines, with a warning
/// per such name.
fn material_ids(
    path: &Path,
    obj: &objparse::ObjText,
    materials: &[Material],
    warnings: &mut Vec<String>,
) -> Vec<u32> {
    let fallback = materials.len() as u32;
    let known: BTreeMap<&str, u32> = materials
        .iter()
        .enumerate()
        .map(|(i, m)| (m.name.as_str(), i as u32))
        .collect();
    let mut unknown = BTreeSet::new();
    let ids = obj
        .material_names
        .iter()
        .map(|n| {
            known.get(n.as_str()).copied().unwrap_or_else(|| {
                unknown.insert(n.as_str());
                fallback
            })
        })
        .collect();
    for n in unknown {
        warnings.push(format!(
            "{}: material '{}' is not defined, using grey diffuse",
            path.display(),
            clip(n)
        ));
    }
    ids
}

/// The triangles of `obj`, each with its material (`ids` by `usemtl` name; `fallback` before
/// any), vertex normals and texture coordinates where all three corners have them; zero-area
/// triangles skipped and counted.
fn triangles(
    obj: &objparse::ObjText,
    ids: &[u32],
    fallback: u32,
) -> Result<(Vec<MeshTriangle>, usize)> {
    use rayon::prelude::*;
    let normal = |c: &Corner| {
        (c.vn != NONE)
            .then(|| obj.normals[c.vn as usize])
            .filter(|n| n.length_squared() > 0.0)
    };
    // in parallel, in file order (collect keeps the order)
    let out: Vec<MeshTriangle> = obj
        .triangles
        .par_iter()
        .zip(&obj.material)
        .filter_map(|(t, m)| {
            let p = t.map(|c| obj.positions[c.v as usize]);
            if (p[1] - p[0]).cross(p[2] - p[0]).length_squared() == 0.0 {
                return None;
            }
            let normals = match t.map(|c| normal(&c)) {
                [Some(a), Some(b), Some(c)] => Some([a, b, c]),
                _ => None,
            };
            let uvs = t
                .iter()
                .all(|c| c.vt != NONE)
                .then(|| t.map(|c| obj.texcoords[c.vt as usize]));
            Some(MeshTriangle {
                p,
                normals,
                uvs,
                material: m.map_or(fallback, |k| ids[k as usize]),
            })
        })
        .collect();
    let degenerate = obj.triangles.len() - out.len();
    Ok((out, degenerate))
}

/// Load the textures of `lines` (each with its MTL) once per file and decoding, and give each
/// material its maps (by name: a statement under `newmtl X` belongs to the material X). A file
/// that cannot be found or read is a leniency naming the MTL and the statement's line: the
/// material keeps its constant colour.
fn attach_maps(
    mats: &mut [Material],
    lines: &[(PathBuf, MapLine)],
    notes: &mut Notes,
) -> Result<TextureSet> {
    let mut set = TextureSet::default();
    for (mtl, m) in lines {
        let Some(mat) = mats.iter_mut().rev().find(|x| x.name == m.material) else {
            continue;
        };
        let decode = match m.key.as_str() {
            "map_kd" | "map_ks" => Decode::Srgb,
            _ => Decode::Linear,
        };
        let at = format!("line {}: {} {}", m.line, m.tag, clip(&m.file));
        let folder = mtl.parent().unwrap_or(Path::new("."));
        let Some(found) = files::find(folder, &m.file) else {
            notes.lenient(
                mtl,
                format!("{at}: file not found, the material's constant colour is used"),
            )?;
            continue;
        };
        if let Some(how) = &found.how {
            notes.lenient(mtl, format!("{at}: {how}"))?;
        }
        let index = match set.load(&found.path, decode) {
            Ok(i) => i,
            Err(e) => {
                notes.lenient(
                    mtl,
                    format!("{at}: {e}; the material's constant colour is used"),
                )?;
                continue;
            }
        };
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

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(illum: u32) -> MtlEntry {
        MtlEntry {
            name: "m".into(),
            kd: Some(Vec3::ZERO),
            ks: Some(Vec3::splat(0.9)),
            ni: Some(1.33),
            tf: Some(Vec3::new(0.1, 0.0, 0.2)),
            illum: Some(illum),
            ..MtlEntry::default()
        }
    }

    /// `illum` maps to the lobes the MTL spec and the common exporters mean.
    #[test]
    fn illum_chooses_the_lobe() {
        let mirror = |schlick| Specular::Mirror {
            reflectance: Vec3::splat(0.9),
            schlick,
        };
        let glass = Specular::Dielectric {
            ior: 1.33,
            transmittance: Vec3::new(0.9, 1.0, 0.8),
        };
        for (illum, want) in [
            (3, Some(mirror(false))),
            (5, Some(mirror(true))),
            (4, Some(glass)),
            (7, Some(glass)),
            (9, Some(glass)),
            (2, None),
            (1, None),
        ] {
            let (m, _) = material_of(&entry(illum));
            assert_eq!(m.specular, want, "illum {illum}");
            assert_eq!(m.delta_share, if want.is_some() { 1.0 } else { 0.0 });
        }
        // glass without Ni is 1.5; without a transparency, illum 7 is opaque (and said so)
        let e = MtlEntry {
            ni: None,
            ..entry(4)
        };
        assert!(matches!(
            material_of(&e).0.specular,
            Some(Specular::Dielectric { ior, .. }) if ior == 1.5
        ));
        let e = MtlEntry {
            tf: Some(Vec3::ONE),
            ..entry(7)
        };
        let (m, said) = material_of(&e);
        assert!(
            m.specular.is_none() && said[0].contains("opaque"),
            "{said:?}"
        );
        // a mirror over a diffuse part shares the bounces by albedo
        let e = MtlEntry {
            kd: Some(Vec3::splat(0.3)),
            ks: Some(Vec3::splat(0.6)),
            ..entry(3)
        };
        let (m, _) = material_of(&e);
        assert!((m.delta_share - 2.0 / 3.0).abs() < 1e-6);
        assert_eq!(m.kd(), Vec3::splat(0.3));
        // a Phong material keeps a Ks near 1 and a high Ns
        let e = MtlEntry {
            ks: Some(Vec3::splat(0.99)),
            ns: Some(1000.0),
            ..entry(2)
        };
        let (m, _) = material_of(&e);
        assert_eq!((m.ks(), m.exponent()), (Vec3::splat(0.99), 1000.0));
    }
}
