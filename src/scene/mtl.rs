//! The MTL text, read as the reference loaders read it, into material descriptions and texture
//! statements.
//!
//! - `#` starts a comment anywhere on a line (in a name only as a word of its own).
//! - What vrpt uses: `newmtl`; `Kd`, `Ks`, `Ke`, `Tf` (one number is a grey, three are RGB;
//!   more are ignored, as the reference loaders do; `spectral` and `xyz` forms are skipped),
//!   `Ns`, `Ni`, `d`, `Tr` (read only where the material gives no `d`), `illum`; the texture
//!   statements `map_Kd`, `map_Ks`, `map_Ns`, `map_d`, `bump`/`map_Bump`, `norm` with their
//!   options `-s`, `-o`, `-bm` ([`MapLine`]). A malformed or out-of-range number in one of
//!   them is refused with its line: colours finite, non-negative and at most [`MAX_MAGNITUDE`],
//!   `Ns` in `[0, 10⁶]`, `Ni`, `d` and `Tr` finite, `illum` an integer from 0 to 10.
//! - Everything else (`Ka`, `map_Ka`, PBR extensions, unknown keywords) is skipped whatever it
//!   holds and counted by kind; a skipped statement whose numbers do not parse is a note
//!   (`--strict` refuses it, as vrpt refused `Ka 0 0 0c` before it read files as others do).

use super::objparse::uncommented;
use crate::error::clip;
use crate::limits::MAX_MAGNITUDE;
use glam::{Vec2, Vec3};
use std::collections::{BTreeMap, BTreeSet};

/// One `newmtl` block: what it says, each value as written (`None` where it is absent).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MtlEntry {
    pub name: String,
    pub kd: Option<Vec3>,
    pub ks: Option<Vec3>,
    pub ke: Option<Vec3>,
    pub tf: Option<Vec3>,
    pub ns: Option<f32>,
    pub ni: Option<f32>,
    /// `d`, or `1 − Tr` where the block has no `d`.
    pub d: Option<f32>,
    pub illum: Option<u32>,
}

/// An MTL file read: its materials in order, its texture statements, the statements skipped by
/// kind, and notes on what was skipped although malformed.
#[derive(Clone, Debug, Default)]
pub struct MtlText {
    pub materials: Vec<MtlEntry>,
    pub maps: Vec<MapLine>,
    pub skipped: BTreeMap<String, usize>,
    /// Malformed statements that were skipped (`--strict` refuses them), each `line N: …`.
    pub notes: Vec<String>,
}

/// Parse an MTL `text`; an error is one line, `line N: …`.
pub fn parse(text: &str) -> Result<MtlText, String> {
    let mut out = MtlText::default();
    let mut tr: Option<(usize, String)> = None;
    let mut ignored = BTreeSet::new();
    for (no, raw) in text.lines().enumerate() {
        let line = uncommented(raw);
        let mut words = line.split_whitespace();
        let Some(tag) = words.next() else { continue };
        let rest: Vec<&str> = words.collect();
        if tag == "newmtl" {
            finish_tr(&mut out, tr.take())?;
            out.materials.push(MtlEntry {
                name: rest.join(" "),
                ..MtlEntry::default()
            });
            continue;
        }
        let key = tag.to_ascii_lowercase();
        if MAP_KEYS.contains(&key.as_str()) {
            let material = out
                .materials
                .last()
                .map_or(String::new(), |m| m.name.clone());
            let m = map_line(tag, &rest, no + 1, material, &mut ignored)?;
            out.maps.push(m);
            continue;
        }
        let Some(m) = out.materials.last_mut() else {
            // a statement before any `newmtl` describes no material
            *out.skipped.entry(clip(tag).into_owned()).or_default() += 1;
            continue;
        };
        let words = (tag, rest.as_slice());
        let (skipped, notes) = (&mut out.skipped, &mut out.notes);
        statement(m, words, (no + 1, line), &mut tr, skipped, notes)?;
    }
    finish_tr(&mut out, tr)?;
    for opt in ignored {
        *out.skipped.entry(opt).or_default() += 1;
    }
    Ok(out)
}

/// One statement `tag rest…` of material `m` on line `no` (text `line`): its colour or number
/// set, `Tr` kept in `tr` for [`finish_tr`], anything else counted in `skipped` (a malformed
/// `Ka` noted in `notes` too); an error for a malformed value it reads.
fn statement(
    m: &mut MtlEntry,
    (tag, rest): (&str, &[&str]),
    (no, line): (usize, &str),
    tr: &mut Option<(usize, String)>,
    skipped: &mut BTreeMap<String, usize>,
    notes: &mut Vec<String>,
) -> Result<(), String> {
    let at = |what: String| format!("line {no}: {what}: '{}'", clip(line));
    match tag {
        "Kd" | "Ks" | "Ke" | "Tf" => {
            if is_other_colour_form(rest) {
                *skipped.entry(format!("{tag} {}", rest[0])).or_default() += 1;
                return Ok(());
            }
            let c = colour(tag, rest).map_err(at)?;
            let slot = match tag {
                "Kd" => &mut m.kd,
                "Ks" => &mut m.ks,
                "Ke" => &mut m.ke,
                _ => &mut m.tf,
            };
            *slot = Some(c);
        }
        "Ns" => m.ns = Some(number(tag, rest, 0.0, 1e6).map_err(at)?),
        "Ni" => m.ni = Some(number(tag, rest, f32::MIN, f32::MAX).map_err(at)?),
        "d" => {
            // `d -halo 0.5`: the halo form, read as its value
            let rest = match rest.first() {
                Some(&"-halo") => &rest[1..],
                _ => rest,
            };
            m.d = Some(number(tag, rest, f32::MIN, f32::MAX).map_err(at)?);
        }
        "Tr" => *tr = Some((no, line.to_string())),
        "illum" => {
            let v = number(tag, rest, 0.0, 10.0).map_err(at)?;
            if v.fract() != 0.0 {
                return Err(at(format!("illum: {v} is not an integer from 0 to 10")));
            }
            m.illum = Some(v as u32);
        }
        _ => {
            *skipped.entry(clip(tag).into_owned()).or_default() += 1;
            if tag == "Ka" && !is_other_colour_form(rest) {
                if let Err(e) = colour(tag, rest) {
                    notes.push(at(e));
                }
            }
        }
    }
    Ok(())
}

/// The block's `Tr` (line, text), read as `d = 1 − Tr` where the block gave no `d` (then a
/// malformed value is refused), else skipped.
fn finish_tr(out: &mut MtlText, tr: Option<(usize, String)>) -> Result<(), String> {
    let (Some((no, line)), Some(m)) = (tr, out.materials.last_mut()) else {
        return Ok(());
    };
    if m.d.is_some() {
        *out.skipped.entry("Tr".into()).or_default() += 1;
        return Ok(());
    }
    let rest: Vec<&str> = line.split_whitespace().skip(1).collect();
    let tr = number("Tr", &rest, f32::MIN, f32::MAX)
        .map_err(|e| format!("line {no}: {e}: '{}'", clip(&line)))?;
    m.d = Some(1.0 - tr);
    Ok(())
}

/// `Kd spectral file.rfl` and `Kd xyz x y z`: forms vrpt does not read (RGB only).
fn is_other_colour_form(rest: &[&str]) -> bool {
    rest.first()
        .is_some_and(|w| w.eq_ignore_ascii_case("spectral") || w.eq_ignore_ascii_case("xyz"))
}

/// One number (the first word: more are ignored) in `[lo, hi]`.
fn number(tag: &str, rest: &[&str], lo: f32, hi: f32) -> Result<f32, String> {
    let Some(w) = rest.first() else {
        return Err(format!("{tag} has no value"));
    };
    let x = finite(tag, w)?;
    if !(lo..=hi).contains(&x) {
        return Err(format!("{tag}: {x} is outside [{lo}, {hi:e}]"));
    }
    Ok(x)
}

fn finite(tag: &str, w: &str) -> Result<f32, String> {
    match w.parse::<f32>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(_) => Err(format!("{tag}: '{}' is not a finite number", clip(w))),
        Err(_) => Err(format!("{tag}: '{}' is not a number", clip(w))),
    }
}

/// A colour: `r` (a grey) or `r g b` (more numbers are ignored), each finite, non-negative and
/// at most [`MAX_MAGNITUDE`].
fn colour(tag: &str, rest: &[&str]) -> Result<Vec3, String> {
    let n = match rest.len() {
        0 => return Err(format!("{tag} has no value")),
        1 => 1,
        2 => {
            return Err(format!(
                "{tag} needs 1 (grey) or 3 numbers (r g b), found 2"
            ))
        }
        _ => 3,
    };
    let mut c = [0.0f32; 3];
    for (k, w) in rest[..n].iter().enumerate() {
        let x = finite(tag, w)?;
        if !(0.0..=MAX_MAGNITUDE).contains(&x) {
            return Err(format!("{tag}: {x} is outside [0, {MAX_MAGNITUDE:e}]"));
        }
        c[k] = x;
    }
    Ok(if n == 1 {
        Vec3::splat(c[0])
    } else {
        Vec3::from_array(c)
    })
}

/// One texture statement of an MTL (`map_Kd`, `map_Ks`, `map_Ns`, `map_d`, `bump`,
/// `map_Bump`, `norm`): its material, keyword (lower case), file (relative to the MTL, as
/// written: [`crate::scene::files`] finds it) and options, and its line.
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

/// The texture statement `tag rest…` on line `line` of `material`.
fn map_line(
    tag: &str,
    rest: &[&str],
    line: usize,
    material: String,
    ignored: &mut BTreeSet<String>,
) -> Result<MapLine, String> {
    let mut m = MapLine {
        material,
        tag: tag.to_string(),
        key: tag.to_ascii_lowercase(),
        file: String::new(),
        scale: Vec2::ONE,
        offset: Vec2::ZERO,
        bump_mult: 1.0,
        line,
    };
    let k = parse_map_options(rest, &mut m, ignored)?;
    m.file = rest[k..].join(" ");
    if m.file.is_empty() {
        return Err(format!("line {line}: {tag}: no file named"));
    }
    Ok(m)
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
            ignored.insert(format!("{tag} {opt}"));
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
                ignored.insert(format!("{tag} {opt}"));
            }
        }
    }
    Ok(k)
}
