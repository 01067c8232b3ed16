//! `scene.toml`: the optional description beside an OBJ — which OBJ, the camera, the
//! environment radiance and render defaults. Unknown keys are errors, so a typo is reported
//! rather than silently ignored.
//!
//! ```toml
//! obj = "cornell-box.obj"
//! [camera]
//! eye = [278.0, 273.0, -800.0]
//! target = [278.0, 273.0, 0.0]
//! up = [0.0, 1.0, 0.0]
//! fov = 39.3            # vertical, degrees
//! [environment]
//! radiance = [0.0, 0.0, 0.0]   # or, instead of radiance: an HDR lat-long map
//! # map = "sky.exr"            # relative to this file; see crate::environment
//! # rotation = 0.0             # degrees about +y
//! # scale = 1.0                # multiplies the map's radiance
//! [render]
//! width = 256
//! height = 256
//! spp = 64
//! max_depth = 8
//! ```

use crate::error::{Error, Result};
use crate::limits::{MAX_DEPTH, MAX_MAGNITUDE, MAX_SIDE};
use serde::Deserialize;
use std::path::Path;
use toml::Spanned;

/// A value with where it stood in the file (byte range), for errors that name the line.
pub type At<T> = Spanned<T>;

/// The whole file.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Description {
    /// The OBJ file, relative to the description's folder.
    pub obj: String,
    pub camera: Option<CameraSection>,
    pub environment: Option<EnvironmentSection>,
    pub render: Option<RenderSection>,
}

/// `[camera]`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraSection {
    pub eye: At<[f32; 3]>,
    pub target: At<[f32; 3]>,
    #[serde(default = "default_up")]
    pub up: At<[f32; 3]>,
    /// Vertical field of view in degrees.
    #[serde(default = "default_fov")]
    pub fov: At<f32>,
}

fn default_up() -> At<[f32; 3]> {
    Spanned::new(0..0, [0.0, 1.0, 0.0])
}

fn default_fov() -> At<f32> {
    Spanned::new(0..0, 40.0)
}

/// `[environment]`: what rays that escape see: a constant `radiance`, or an HDR lat-long `map`
/// (an EXR, relative to the description) turned by `rotation` degrees about +y and multiplied
/// by `scale` (see [`crate::environment`]).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentSection {
    pub radiance: Option<At<[f32; 3]>>,
    pub map: Option<At<String>>,
    pub rotation: Option<At<f32>>,
    pub scale: Option<At<f32>>,
    /// The line `map` stands on (for errors reading it), set by [`Description::parse`].
    #[serde(skip)]
    pub map_line: usize,
}

/// `[render]`: defaults that command-line flags override.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RenderSection {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: Option<u32>,
    pub max_depth: Option<u32>,
}

impl Description {
    /// Read and parse `path`.
    pub fn load(path: &Path) -> Result<Description> {
        let text = crate::error::read_text(path)?;
        Self::parse(&text).map_err(|message| Error::Toml {
            path: path.to_path_buf(),
            message,
        })
    }

    /// Parse the text of a description; the error is one line with the TOML position, and a
    /// value out of range names its line and field.
    pub fn parse(text: &str) -> Result<Description, String> {
        let mut d: Description = toml::from_str(text).map_err(|e| {
            let msg = crate::error::clip_line(e.message().trim()).into_owned();
            match e.span() {
                Some(span) => format!("line {}: {msg}", line_of(text, span.start)),
                None => msg,
            }
        })?;
        if let Some(c) = &d.camera {
            check_camera(text, c)?;
        }
        if let Some(e) = &mut d.environment {
            check_environment(text, e)?;
        }
        if let Some(r) = &d.render {
            check_render(text, r)?;
        }
        Ok(d)
    }
}

/// The line (from 1) of byte `at` of `text`.
fn line_of(text: &str, at: usize) -> usize {
    text[..at.min(text.len())].matches('\n').count() + 1
}

/// The error "line N: camera.eye: ..." for the value of `field` at `span` of `text` (no line for
/// a default, whose span is empty and which is always valid).
fn bad(text: &str, span: std::ops::Range<usize>, field: &str, what: String) -> String {
    if span.is_empty() {
        format!("{field}: {what}")
    } else {
        format!("line {}: {field}: {what}", line_of(text, span.start))
    }
}

/// An error unless every number of `v` is in `[min, MAX_MAGNITUDE]` (so finite).
fn check_coords(text: &str, v: &At<[f32; 3]>, field: &str, min: f32) -> Result<(), String> {
    let m = MAX_MAGNITUDE;
    match v.get_ref().iter().find(|x| !(min..=m).contains(*x)) {
        None => Ok(()),
        Some(x) if !x.is_finite() => Err(bad(
            text,
            v.span(),
            field,
            format!("{x} is not a finite number"),
        )),
        Some(x) => Err(bad(
            text,
            v.span(),
            field,
            format!("{x} is outside [{min:e}, {m:e}]"),
        )),
    }
}

/// `[camera]`: finite points within [`MAX_MAGNITUDE`], and a field of view in (0, 180) degrees.
fn check_camera(text: &str, c: &CameraSection) -> Result<(), String> {
    let m = MAX_MAGNITUDE;
    check_coords(text, &c.eye, "camera.eye", -m)?;
    check_coords(text, &c.target, "camera.target", -m)?;
    check_coords(text, &c.up, "camera.up", -m)?;
    let fov = *c.fov.get_ref();
    if !(fov > 0.0 && fov < 180.0) {
        return Err(bad(
            text,
            c.fov.span(),
            "camera.fov",
            format!("{fov} is not in (0, 180) degrees"),
        ));
    }
    Ok(())
}

/// `[environment]`: a radiance in range or a map (not both, not neither); rotation and scale only
/// for a map, finite and in range. Sets `map_line` to the line of `map`.
fn check_environment(text: &str, e: &mut EnvironmentSection) -> Result<(), String> {
    if let Some(r) = &e.radiance {
        check_coords(text, r, "environment.radiance", 0.0)?;
    }
    match (&e.radiance, &e.map) {
        (Some(r), Some(_)) => {
            return Err(bad(
                text,
                r.span(),
                "environment",
                "give radiance or map, not both".into(),
            ))
        }
        (None, None) => return Err("environment: give radiance or map".into()),
        (Some(_), None) => {
            if let Some(k) = [("rotation", &e.rotation), ("scale", &e.scale)]
                .into_iter()
                .find(|(_, v)| v.is_some())
            {
                return Err(format!("environment.{}: only for a map", k.0));
            }
        }
        (None, Some(m)) => e.map_line = line_of(text, m.span().start),
    }
    if let Some(r) = &e.rotation {
        if !r.get_ref().is_finite() {
            return Err(bad(
                text,
                r.span(),
                "environment.rotation",
                "not finite".into(),
            ));
        }
    }
    if let Some(sc) = &e.scale {
        let x = *sc.get_ref();
        if !(0.0..=MAX_MAGNITUDE).contains(&x) {
            return Err(bad(
                text,
                sc.span(),
                "environment.scale",
                format!("{x} is outside [0, {MAX_MAGNITUDE:e}]"),
            ));
        }
    }
    Ok(())
}

/// `[render]`: width and height in `1..=MAX_SIDE`, spp at least 1, max depth in
/// `1..=MAX_DEPTH`; the error names the key's line where it can be found.
fn check_render(text: &str, r: &RenderSection) -> Result<(), String> {
    for (name, v, max) in [
        ("width", r.width, MAX_SIDE),
        ("height", r.height, MAX_SIDE),
        ("spp", r.spp, u32::MAX),
        ("max_depth", r.max_depth, MAX_DEPTH),
    ] {
        if let Some(v) = v.filter(|&v| v == 0 || v > max) {
            let line =
                key_line(text, "render", name).map_or(String::new(), |n| format!("line {n}: "));
            return Err(format!("{line}render.{name}: {v} is not in 1..={max}"));
        }
    }
    Ok(())
}

/// The line (from 1) where `key = …` stands in `[section]`.
fn key_line(text: &str, section: &str, key: &str) -> Option<usize> {
    let mut current = "";
    for (n, line) in text.lines().enumerate() {
        let l = line.trim();
        if let Some(h) = l.strip_prefix('[').and_then(|h| h.strip_suffix(']')) {
            current = h.trim();
        } else if current == section
            && l.strip_prefix(key)
                .is_some_and(|r| r.trim_start().starts_with('='))
        {
            return Some(n + 1);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_rejects() {
        let d = Description::parse(
            "obj = \"a.obj\"\n[camera]\neye=[0,0,1]\ntarget=[0,0,0]\n[render]\nspp = 4\n",
        )
        .unwrap();
        assert_eq!(d.obj, "a.obj");
        assert_eq!(*d.camera.unwrap().fov.get_ref(), 40.0);
        assert_eq!(d.render.unwrap().spp, Some(4));
        let e = Description::parse("obj = \"a.obj\"\n[camera]\neye=[0,0,1]\ntargt=[0,0,0]\n")
            .unwrap_err();
        assert!(e.starts_with("line 4"), "{e}");
        assert!(Description::parse("obj = \"a.obj\"\n[render]\nspp = 0\n").is_err());
        assert!(Description::parse("[render]\nspp = 4\n").is_err());
    }
}
