//! What each command of the `vrpt` binary does, as library functions: a typed request in, a
//! typed outcome out, no printing. A command is prepared first (inputs read and checked, output
//! paths checked, the scene loaded: its warnings can be shown before the long part), then run.
//! Every request is its command's flags (a `clap::Args` struct: the argument struct *is* the
//! request), shared groups of flags flattened into it ([`ImageArgs`], [`RegionArgs`],
//! [`crate::strategy::StrategyArgs`]); the binary (`src/cli.rs`) adds only what concerns the
//! terminal (`--quiet`), shows progress and prints outcomes; tests call these functions
//! directly.
//!
//! - [`render`]: a scene to an EXR or PNG, in passes, shards, under a time limit or a stop flag;
//! - [`merge`]: renders of the same scene and settings into one image;
//! - [`diff`]: an image against a reference: metrics, regions, error map, report;
//! - [`experiment`]: `compare` and `converge`, with their CSV, JSON, grid, plots and report;
//! - [`guide`]: what path guiding learned at one point, beside the incident radiance there;
//! - [`info`]: what the loader found in a scene, and the camera and light it would use;
//! - [`points`]: a sampler's points in the unit square, their discrepancy and spectrum;
//! - [`integrate`]: known-answer integrals by each sampler against the variance formulas;
//! - [`warptest`]: every warp's samples against its integrated pdf, chi-square and ∫pdf.

mod black;
pub mod diff;
pub mod experiment;
pub mod guide;
pub mod info;
pub mod integrate;
pub mod merge;
mod outcome;
pub mod points;
pub mod render;
pub mod warptest;

use crate::analysis::metrics::Region;
use crate::error::{Error, Result};
use crate::render::RenderSettings;
use crate::scene::Scene;
use std::path::{Path, PathBuf};

/// The image of a render, as the flags give it: each `None` takes the scene's `[render]`
/// default, then the built-in one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::Args)]
pub struct ImageArgs {
    /// Samples per pixel (default: scene.toml's, else 16).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Option<u32>,
    /// Image width in pixels (default: scene.toml's, else 256).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub width: Option<u32>,
    /// Image height in pixels (default: scene.toml's, else 256).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub height: Option<u32>,
    /// Longest path in segments, counting the camera ray: 1 shows emitters only, 2 adds direct
    /// light (default: scene.toml's, else 8).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub max_depth: Option<u32>,
}

impl ImageArgs {
    /// The settings of a render of `scene`: these flags over its `[render]` defaults over the
    /// built-in ones ([`RenderSettings::for_scene`]); `spp` is the spp when the flag is absent.
    pub fn settings(&self, scene: &Scene, spp: Option<u32>) -> RenderSettings {
        let d = RenderSettings::for_scene(scene);
        RenderSettings {
            width: self.width.unwrap_or(d.width),
            height: self.height.unwrap_or(d.height),
            spp: self.spp.or(spp).unwrap_or(d.spp),
            max_depth: self.max_depth.unwrap_or(d.max_depth),
            ..d
        }
    }
}

/// How a command reads a scene (every command that loads one).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::Args)]
pub struct LoadArgs {
    /// Refuse what a scene made elsewhere is forgiven with a warning: a texture or material
    /// library found only by another letter case, separator or folder, a texture that cannot be
    /// found or read (otherwise its material's constant colour), a malformed statement vrpt
    /// does not use.
    #[arg(long)]
    pub strict: bool,
}

impl LoadArgs {
    /// Load the scene at `path` as these flags say.
    pub fn load(&self, path: &Path) -> Result<Scene> {
        crate::scene::load_with(path, self.strict)
    }
}

/// Parts of the image reported on their own (`diff`, `compare`).
#[derive(Clone, Debug, Default, PartialEq, clap::Args)]
pub struct RegionArgs {
    /// A region reported on its own: X,Y,W,H in pixels (rows from the top) or NAME=X,Y,W,H;
    /// repeatable.
    #[arg(long, value_name = "X,Y,W,H", value_parser = Region::parse)]
    pub region: Vec<Region>,
    /// A file of `NAME X,Y,W,H` lines (`#` comments), e.g. scenes/glossy-plates/regions.txt.
    #[arg(long, value_name = "FILE")]
    pub regions: Option<PathBuf>,
}

impl RegionArgs {
    /// The regions given and those of the file of `NAME X,Y,W,H` lines, checked against a
    /// `width × height` image.
    pub fn resolve(&self, width: u32, height: u32) -> Result<Vec<Region>> {
        let mut all = self.region.clone();
        if let Some(p) = &self.regions {
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
}

/// A command's request from its flags, parsed as the binary parses them (`args` without the
/// command's name): the same defaults, checks and messages. A refusal is clap's message in one
/// line, without its `error: ` and its usage hints (the Python binding's way in: keyword
/// arguments become flags, so `vrpt.render(scene, spp=0)` says what `vrpt render SCENE --spp 0`
/// says).
pub fn parse_flags<T: clap::Args + clap::FromArgMatches>(
    command: &'static str,
    args: &[String],
) -> Result<T> {
    // clap's message up to its usage and help hints, its lines joined
    let one_line = |e: clap::Error| {
        let text = e.to_string();
        let lines: Vec<&str> = (text.lines())
            .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .collect();
        Error::Settings(lines.join(" ").trim_start_matches("error: ").to_string())
    };
    let cmd = T::augment_args(clap::Command::new(command).no_binary_name(true));
    let matches = cmd.try_get_matches_from(args).map_err(one_line)?;
    T::from_arg_matches(&matches).map_err(one_line)
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

/// Refuse outputs that would write over a file `scene` was read from (its OBJ, scene.toml,
/// MTLs, textures, environment map): the one check of every command that loads a scene, once
/// it is loaded (the files a scene names are known only then).
pub(crate) fn check_against_scene(
    outputs: &[crate::image_io::NamedPath],
    scene: &Scene,
) -> Result<()> {
    crate::image_io::check_outputs(outputs, &scene.read_from())
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
