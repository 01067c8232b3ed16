//! What each command of the `vrpt` binary does, as library functions: a typed request in, a
//! typed outcome out, no printing. A command is prepared first (inputs read and checked, output
//! paths checked, the scene loaded: its warnings can be shown before the long part), then run.
//! The binary (`src/cli.rs`) only turns flags into requests, shows progress and prints outcomes;
//! tests call these functions directly.
//!
//! - [`render`]: a scene to an EXR or PNG, in passes, shards, under a time limit or a stop flag;
//! - [`merge`]: renders of the same scene and settings into one image;
//! - [`diff`]: an image against a reference: metrics, regions, error map, report;
//! - [`experiment`]: `compare` and `converge`, with their CSV, JSON, grid, plots and report;
//! - [`guide`]: what path guiding learned at one point, beside the incident radiance there;
//! - [`points`]: a sampler's points in the unit square, their discrepancy and spectrum;
//! - [`integrate`]: known-answer integrals by each sampler against the variance formulas;
//! - [`warptest`]: every warp's samples against its integrated pdf, chi-square and ∫pdf.

pub mod diff;
pub mod experiment;
pub mod guide;
pub mod integrate;
pub mod merge;
pub mod points;
pub mod render;
pub mod warptest;

use crate::analysis::metrics::Region;
use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// Regions given on the command line and in a file of `NAME X,Y,W,H` lines, checked against a
/// `width × height` image: what `diff` and `compare` report on their own.
pub fn resolve_regions(
    given: &[Region],
    file: Option<&Path>,
    width: u32,
    height: u32,
) -> Result<Vec<Region>> {
    let mut all = given.to_vec();
    if let Some(p) = file {
        let text = crate::error::read_text(p)?;
        all.extend(Region::parse_list(&text).map_err(|message| Error::Scene {
            path: p.to_path_buf(),
            message,
        })?);
    }
    for r in &all {
        r.check(width, height).map_err(Error::Settings)?;
    }
    Ok(all)
}

/// The paths among `flags` that were given, each with its flag (for
/// [`crate::image_io::check_outputs`]).
pub(crate) fn given<'a>(
    flags: &[(&'a str, &'a Option<PathBuf>)],
) -> Vec<crate::image_io::NamedPath<'a>> {
    flags
        .iter()
        .filter_map(|&(f, p)| p.as_deref().map(|p| (f, p)))
        .collect()
}

/// Check, before any work, the outputs of a command that draws a picture (`-o`) and writes
/// numbers (`--json`): distinct paths, writable, and the picture a `.png` (or `.svg` where the
/// command draws vectors), each refusal one line.
pub(crate) fn check_picture_and_json(
    output: &Option<PathBuf>,
    json: &Option<PathBuf>,
    svg: bool,
) -> Result<()> {
    crate::image_io::check_outputs(&given(&[("-o", output), ("--json", json)]), &[])?;
    if let Some(p) = output {
        let ext = p
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => {}
            Some("svg") if svg => {}
            _ => {
                return Err(crate::error::Error::Write {
                    path: p.clone(),
                    message: format!(
                        "a picture is written as {}",
                        if svg { ".png or .svg" } else { ".png" }
                    ),
                })
            }
        }
        crate::image_io::check_writable(p)?;
    }
    if let Some(p) = json {
        crate::image_io::check_writable(p)?;
    }
    Ok(())
}

/// Write `value` to `path` as pretty JSON (atomically).
pub(crate) fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| Error::Settings(format!("{}: {e}", path.display())))?;
    crate::image_io::write_bytes(path, text.as_bytes())
}

/// A file a command wrote, and what it holds (for the binary to say so).
#[derive(Clone, Debug, PartialEq)]
pub struct Written {
    pub path: PathBuf,
    /// What else to say of it, e.g. an error map's colour range; may be empty.
    pub note: String,
}

impl Written {
    fn new(path: &Path) -> Written {
        Written {
            path: path.to_path_buf(),
            note: String::new(),
        }
    }
}
