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
//! radiance = [0.0, 0.0, 0.0]
//! [render]
//! width = 256
//! height = 256
//! spp = 64
//! max_depth = 8
//! ```

use crate::error::{Error, Result};
use serde::Deserialize;
use std::path::Path;

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
    pub eye: [f32; 3],
    pub target: [f32; 3],
    #[serde(default = "default_up")]
    pub up: [f32; 3],
    /// Vertical field of view in degrees.
    #[serde(default = "default_fov")]
    pub fov: f32,
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

fn default_fov() -> f32 {
    40.0
}

/// `[environment]`: constant radiance for rays that escape.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentSection {
    pub radiance: [f32; 3],
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

    /// Parse the text of a description; the error is one line with the TOML position.
    pub fn parse(text: &str) -> Result<Description, String> {
        let d: Description = toml::from_str(text).map_err(|e| {
            let msg = e.message().trim().to_string();
            match e.span() {
                Some(span) => {
                    let line = text[..span.start.min(text.len())].matches('\n').count() + 1;
                    format!("line {line}: {msg}")
                }
                None => msg,
            }
        })?;
        let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
        if let Some(c) = &d.camera {
            if !finite(&c.eye) || !finite(&c.target) || !finite(&c.up) {
                return Err("camera: coordinates must be finite numbers".into());
            }
            if !(c.fov > 0.0 && c.fov < 180.0) {
                return Err(format!("camera: fov {} is not in (0, 180) degrees", c.fov));
            }
        }
        if let Some(e) = &d.environment {
            if !finite(&e.radiance) || e.radiance.iter().any(|&x| x < 0.0) {
                return Err("environment: radiance must be finite and non-negative".into());
            }
        }
        if let Some(r) = &d.render {
            for (name, v) in [
                ("width", r.width),
                ("height", r.height),
                ("spp", r.spp),
                ("max_depth", r.max_depth),
            ] {
                if v == Some(0) {
                    return Err(format!("render: {name} must be at least 1"));
                }
            }
        }
        Ok(d)
    }
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
        assert_eq!(d.camera.unwrap().fov, 40.0);
        assert_eq!(d.render.unwrap().spp, Some(4));
        let e = Description::parse("obj = \"a.obj\"\n[camera]\neye=[0,0,1]\ntargt=[0,0,0]\n")
            .unwrap_err();
        assert!(e.starts_with("line 4"), "{e}");
        assert!(Description::parse("obj = \"a.obj\"\n[render]\nspp = 0\n").is_err());
        assert!(Description::parse("[render]\nspp = 4\n").is_err());
    }
}
