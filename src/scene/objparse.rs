//! The Wavefront OBJ text, read as the reference loaders read it (tinyobjloader, Blender's and
//! Mitsuba's importers), into positions, texture coordinates, normals and faces.
//!
//! - `#` starts a comment anywhere on a line (in a name only as a word of its own:
//!   `uncommented`); a statement ending in `\` continues on the next line.
//! - `v x y z [w]` (or `v x y z r g b`: the colour is skipped), `vt u [v [w]]`, `vn x y z`: their
//!   numbers must parse, be finite and (positions) at most [`MAX_MAGNITUDE`]; a malformed number
//!   here is refused with its line.
//! - `f` corners `v`, `v/vt`, `v//vn`, `v/vt/vn` (1-based, or negative: relative to the elements
//!   defined before the line), at least three; a polygon is a fan `(c₀, cᵢ, cᵢ₊₁)`. `l` and `p`
//!   are checked the same way and not drawn. A position index must point at a position defined
//!   before its line; a texture coordinate or normal index that does not is dropped from its
//!   corner and counted (tinyobjloader's regression files reference normals commented out).
//! - `usemtl`, `mtllib` (several files, or one name with spaces), `o`, `g`, `s` are read;
//!   any other statement (free-form curves and surfaces, `usemap`, `maplib`, …) is skipped
//!   whatever it holds and counted by kind.
//!
//! The text is cut into chunks at line ends and the chunks are parsed in parallel (rayon);
//! then, in file order, relative indices are resolved against the elements before each line and
//! every index is checked, so an error names the first line at fault, as one pass would.

use crate::error::clip;
use crate::limits::MAX_MAGNITUDE;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Bytes of text per chunk parsed on its own (a chunk per thread would leave threads idle when
/// chunks differ in cost; 1 MiB chunks keep them busy and cost a few allocations each).
const CHUNK_BYTES: usize = 1 << 20;

/// A polygon, line or point statement: its line in its chunk (from 0), its corners (a range of
/// the chunk's `corners`), the counts of `v`, `vt`, `vn` before it in its chunk, and whether it
/// is a face (drawn).
#[derive(Clone, Copy, Debug)]
struct Poly {
    line: u32,
    first: u32,
    len: u32,
    before: [u32; 3],
    face: bool,
}

/// What one chunk of lines holds, indices as written (1-based or negative; 0: absent).
#[derive(Default)]
struct Chunk {
    lines: usize,
    positions: Vec<Vec3>,
    texcoords: Vec<Vec2>,
    normals: Vec<Vec3>,
    corners: Vec<[i32; 3]>,
    polys: Vec<Poly>,
    /// `usemtl NAME` before poly number k of the chunk.
    usemtl: Vec<(u32, String)>,
    mtllib: Vec<String>,
    skipped: BTreeMap<String, usize>,
    /// A smoothing group other than `off`/`0` was named.
    smoothing: bool,
    /// The first error of the chunk: its line (from 0) and message.
    error: Option<(usize, String)>,
}

/// One corner of a triangle: indices of its position, texture coordinate and normal
/// (`u32::MAX`: none).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Corner {
    pub v: u32,
    pub vt: u32,
    pub vn: u32,
}

/// No texture coordinate or normal at a corner.
pub const NONE: u32 = u32::MAX;

/// An OBJ file read: its elements, its triangles (fans of its faces, in file order) with the
/// name of the material each was given (`usemtl`; an index into `materials`, or `None` before
/// any), the `mtllib` names in order, the statements skipped by kind, and whether it names
/// smoothing groups.
#[derive(Default)]
pub struct ObjText {
    pub positions: Vec<Vec3>,
    pub texcoords: Vec<Vec2>,
    pub normals: Vec<Vec3>,
    pub triangles: Vec<[Corner; 3]>,
    /// Per triangle, its `usemtl` name (an index into `material_names`).
    pub material: Vec<Option<u32>>,
    pub material_names: Vec<String>,
    pub mtllib: Vec<String>,
    pub skipped: BTreeMap<String, usize>,
    pub smoothing: bool,
    /// Faces with a corner whose texture coordinate or normal index points at nothing defined
    /// before its line (drawn without that attribute), and the first such index (`line N: …`).
    pub dangling: usize,
    pub first_dangling: Option<String>,
}

/// The statements OBJ defines that vrpt has no use for and passes over without a word (grouping
/// and smoothing groups; `s` is noted separately).
const SILENT: [&str; 3] = ["o", "g", "s"];

/// Parse `text` (an error is one line, `line N: …`).
pub fn parse(text: &str) -> Result<ObjText, String> {
    let chunks: Vec<Chunk> = split(text).into_par_iter().map(parse_chunk).collect();
    assemble(chunks)
}

/// `text` cut into pieces of about [`CHUNK_BYTES`], each ending at a line end that no `\`
/// continues.
fn split(text: &str) -> Vec<&str> {
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    let mut start = 0;
    while start < bytes.len() {
        let mut end = (start + CHUNK_BYTES).min(bytes.len());
        while end < bytes.len() {
            match bytes[end..].iter().position(|&b| b == b'\n') {
                Some(k) => {
                    end += k + 1;
                    let before = &bytes[start..end - 1];
                    let continued = before
                        .strip_suffix(b"\r")
                        .unwrap_or(before)
                        .ends_with(b"\\");
                    if !continued {
                        break;
                    }
                }
                None => end = bytes.len(),
            }
        }
        out.push(&text[start..end]);
        start = end;
    }
    out
}

/// The statements (OBJ and MTL) whose text after the keyword is a name: a material, a library,
/// a group, a texture file.
const NAMED: [&str; 8] = [
    "newmtl", "usemtl", "mtllib", "o", "g", "bump", "norm", "refl",
];

/// The statement of a line without its comment, trimmed. `#` starts a comment anywhere on a
/// line, except in a name (a material, library, group or file) where it does only as a word of
/// its own: `newmtl _Material #25` names `_Material #25` (3ds Max writes such names), `newmtl
/// red # the wall` names `red`.
pub(super) fn uncommented(line: &str) -> &str {
    let t = line.trim();
    let tag = t.split_whitespace().next().unwrap_or("");
    let named =
        NAMED.contains(&tag) || tag.len() > 4 && tag.as_bytes()[..4].eq_ignore_ascii_case(b"map_");
    if !named {
        let hash = t.as_bytes().iter().position(|&b| b == b'#');
        return hash.map_or(t, |k| t[..k].trim_end());
    }
    let b = t.as_bytes();
    let cut = (0..b.len()).find(|&k| {
        b[k] == b'#'
            && (k == 0 || b[k - 1].is_ascii_whitespace())
            && (k + 1 == b.len() || b[k + 1].is_ascii_whitespace())
    });
    cut.map_or(t, |k| t[..k].trim_end())
}

/// Parse one chunk's lines (stops at its first error).
fn parse_chunk(text: &str) -> Chunk {
    let mut c = Chunk::default();
    let mut lines = text.split('\n').enumerate();
    while let Some((no, raw)) = lines.next() {
        c.lines = no + 1;
        let line = raw.strip_suffix('\r').unwrap_or(raw);
        // (a line that does not end in `\` needs no closer look)
        let result = if line.trim_end().ends_with('\\') && uncommented(line).ends_with('\\') {
            // a `\` at the end continues the statement on the next line
            let mut joined = String::new();
            let mut part = line;
            while let Some(head) = uncommented(part).strip_suffix('\\') {
                joined.push_str(head);
                joined.push(' ');
                part = match lines.next() {
                    Some((k, next)) => {
                        c.lines = k + 1;
                        next.strip_suffix('\r').unwrap_or(next)
                    }
                    None => "",
                };
            }
            joined.push_str(part);
            statement(&mut c, &joined, no)
        } else {
            statement(&mut c, line, no)
        };
        if let Err(e) = result {
            c.error = Some((no, e));
            return c;
        }
    }
    c
}

/// Read one statement (its line `no` in the chunk) into `c`.
fn statement(c: &mut Chunk, line: &str, no: usize) -> Result<(), String> {
    let text = uncommented(line);
    let mut words = text.split_whitespace();
    let Some(tag) = words.next() else {
        return Ok(());
    };
    let at = |what: String| format!("{what}: '{}'", clip(text));
    match tag {
        "v" => {
            let x = floats(tag, words, 3, 7).map_err(at)?;
            // x y z, x y z w (a weight: the point is x/w…, checked, not applied, as the
            // reference loaders read polygons), x y z r g b (a colour), x y z w r g b
            let w = if x.len() == 4 || x.len() == 7 {
                x[3]
            } else {
                1.0
            };
            if x.len() == 5 {
                return Err(at(
                    "v needs 3, 4 (x y z w) or 6 (x y z r g b) numbers".into()
                ));
            }
            if w == 0.0 {
                return Err(at("v: the weight w is 0".into()));
            }
            if x[..3].iter().any(|c| (c / w).abs() > MAX_MAGNITUDE) {
                return Err(at(format!("v: a coordinate is beyond ±{MAX_MAGNITUDE:e}")));
            }
            c.positions.push(Vec3::new(x[0], x[1], x[2]));
        }
        "vt" => {
            let x = floats(tag, words, 1, 3).map_err(at)?;
            c.texcoords
                .push(Vec2::new(x[0], x.get(1).copied().unwrap_or(0.0)));
        }
        "vn" => {
            let x = floats(tag, words, 3, 3).map_err(at)?;
            c.normals.push(Vec3::new(x[0], x[1], x[2]));
        }
        "f" | "l" | "p" => {
            let min = match tag {
                "f" => 3,
                "l" => 2,
                _ => 1,
            };
            let first = c.corners.len() as u32;
            for r in words {
                c.corners.push(corner(r).map_err(at)?);
            }
            let len = c.corners.len() as u32 - first;
            if (len as usize) < min {
                return Err(at(format!("{tag} needs at least {min} vertices")));
            }
            c.polys.push(Poly {
                line: no as u32,
                first,
                len,
                before: [
                    c.positions.len() as u32,
                    c.texcoords.len() as u32,
                    c.normals.len() as u32,
                ],
                face: tag == "f",
            });
        }
        "usemtl" => {
            // words joined by one space, as `newmtl` names are read
            let name = words.collect::<Vec<_>>().join(" ");
            c.usemtl.push((c.polys.len() as u32, name));
        }
        "mtllib" => c.mtllib.push(text[tag.len()..].trim().to_string()),
        "s" => {
            let g = words.next().unwrap_or("off");
            c.smoothing |= !(g == "off" || g == "0");
        }
        _ if SILENT.contains(&tag) => {}
        _ => *c.skipped.entry(clip(tag).into_owned()).or_default() += 1,
    }
    Ok(())
}

/// Between `min` and `max` finite numbers after a statement's keyword.
fn floats<'a>(
    tag: &str,
    words: impl Iterator<Item = &'a str>,
    min: usize,
    max: usize,
) -> Result<Vec<f32>, String> {
    let mut out = Vec::with_capacity(max);
    for w in words {
        if out.len() == max {
            let n = if min == max {
                min.to_string()
            } else {
                format!("{min} to {max}")
            };
            return Err(format!("{tag} needs {n} numbers, found more"));
        }
        match w.parse::<f32>() {
            Ok(x) if x.is_finite() => out.push(x),
            Ok(_) => return Err(format!("{tag}: '{}' is not a finite number", clip(w))),
            Err(_) => return Err(format!("{tag}: '{}' is not a number", clip(w))),
        }
    }
    if out.len() < min {
        let n = if min == max {
            min.to_string()
        } else {
            format!("{min} to {max}")
        };
        return Err(format!("{tag} needs {n} numbers, found {}", out.len()));
    }
    Ok(out)
}

/// One corner as written: `v`, `v/vt`, `v//vn`, `v/vt/vn`, `v/` (0: absent).
fn corner(r: &str) -> Result<[i32; 3], String> {
    const WHAT: [&str; 3] = ["position", "texture coordinate", "normal"];
    let mut out = [0i32; 3];
    let mut parts = r.split('/');
    for (k, slot) in out.iter_mut().enumerate() {
        let Some(idx) = parts.next() else { break };
        if idx.is_empty() {
            if k == 0 {
                return Err(format!("'{}' is not a vertex reference", clip(r)));
            }
            continue;
        }
        let i: i64 = idx
            .parse()
            .map_err(|_| format!("'{}' is not an index", clip(idx)))?;
        if i == 0 || i.unsigned_abs() > i32::MAX as u64 {
            return Err(format!("{} index {} is out of range", WHAT[k], clip(idx)));
        }
        *slot = i as i32;
    }
    if parts.next().is_some() {
        return Err(format!("'{}' is not a vertex reference", clip(r)));
    }
    Ok(out)
}

/// The chunks in file order: elements concatenated, every index resolved and checked, faces
/// fanned into triangles with their `usemtl` names. The first error by line wins.
fn assemble(chunks: Vec<Chunk>) -> Result<ObjText, String> {
    let mut out = ObjText::default();
    let (mut line0, mut prefix) = (0usize, [0u32; 3]);
    let mut names: BTreeMap<String, u32> = BTreeMap::new();
    let mut current: Option<u32> = None;
    for c in chunks {
        let mut events = c.usemtl.iter().peekable();
        let stop = c.error.as_ref().map_or(u32::MAX, |(l, _)| *l as u32);
        for (k, p) in c.polys.iter().enumerate() {
            while let Some((_, name)) = events.next_if(|(at, _)| *at as usize == k) {
                let n = names.len() as u32;
                let id = *names.entry(name.clone()).or_insert(n);
                if id == n {
                    out.material_names.push(name.clone());
                }
                current = Some(id);
            }
            if p.line > stop {
                break;
            }
            let corners = &c.corners[p.first as usize..(p.first + p.len) as usize];
            let line = line0 + p.line as usize + 1;
            let (resolved, dangling) =
                resolve(corners, p, prefix).map_err(|e| format!("line {line}: {e}"))?;
            if let Some(e) = dangling {
                out.dangling += 1;
                out.first_dangling
                    .get_or_insert(format!("line {line}: {e}"));
            }
            if p.face {
                for i in 1..resolved.len() - 1 {
                    out.triangles
                        .push([resolved[0], resolved[i], resolved[i + 1]]);
                    out.material.push(current);
                }
            }
        }
        // events after the chunk's last poly carry over to the next chunk
        for (_, name) in events {
            let n = names.len() as u32;
            let id = *names.entry(name.clone()).or_insert(n);
            if id == n {
                out.material_names.push(name.clone());
            }
            current = Some(id);
        }
        if let Some((l, e)) = c.error {
            return Err(format!("line {}: {e}", line0 + l + 1));
        }
        line0 += c.lines.saturating_sub(1);
        prefix[0] += c.positions.len() as u32;
        prefix[1] += c.texcoords.len() as u32;
        prefix[2] += c.normals.len() as u32;
        out.positions.extend(c.positions);
        out.texcoords.extend(c.texcoords);
        out.normals.extend(c.normals);
        out.mtllib.extend(c.mtllib);
        for (k, n) in c.skipped {
            *out.skipped.entry(k).or_default() += n;
        }
        out.smoothing |= c.smoothing;
    }
    Ok(out)
}

/// The corners of `p` as 0-based indices: each written index must point at an element defined
/// before the line (`prefix` the chunks' before this one, `p.before` this chunk's). A position
/// that does not is an error; a texture coordinate or normal that does not is dropped (the
/// corner has none), and the first such index comes back with the corners.
type Resolved = (Vec<Corner>, Option<String>);

fn resolve(corners: &[[i32; 3]], p: &Poly, prefix: [u32; 3]) -> Result<Resolved, String> {
    const WHAT: [&str; 3] = ["position", "texture coordinate", "normal"];
    let mut out = Vec::with_capacity(corners.len());
    let mut dangling = None;
    for c in corners {
        let mut r = [NONE; 3];
        for k in 0..3 {
            let i = c[k] as i64;
            if i == 0 {
                if k == 0 {
                    return Err("a vertex without a position".into());
                }
                continue;
            }
            let n = (prefix[k] + p.before[k]) as i64;
            let at = if i > 0 { i - 1 } else { n + i };
            if at < 0 || at >= n {
                let e = format!(
                    "{} index {i} is out of range ({n} defined before this line)",
                    WHAT[k]
                );
                if k == 0 {
                    return Err(e);
                }
                dangling.get_or_insert(e);
                continue;
            }
            r[k] = at as u32;
        }
        out.push(Corner {
            v: r[0],
            vt: r[1],
            vn: r[2],
        });
    }
    Ok((out, dangling))
}
