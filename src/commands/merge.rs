//! `vrpt merge`: renders of the same scene and settings (other seeds or sample ranges) into one
//! EXR, each pixel weighted by its sample count ([`crate::analysis::merge`]).

use crate::analysis::merge::{merge, MergeInput};
use crate::error::{Error, Result};
use crate::image_io::{check_image_path, check_outputs, write_exr, Format};
use std::path::PathBuf;

/// The renders to merge and the EXR to write (the flags of `vrpt merge`: the request is its
/// arguments).
#[derive(Clone, Debug, Default, clap::Args)]
pub struct MergeRequest {
    /// The EXR renders to merge (at least two).
    #[arg(required = true, num_args = 2..)]
    pub inputs: Vec<PathBuf>,
    /// The merged EXR.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// What a merge made.
#[derive(Clone, Debug, PartialEq)]
pub struct MergeOutcome {
    /// Number of inputs.
    pub inputs: usize,
    /// Samples per pixel of the merge (the inputs' summed).
    pub spp: u64,
}

/// Read the inputs, merge them and write the result.
pub fn run(req: &MergeRequest) -> Result<MergeOutcome> {
    let inputs: Vec<crate::image_io::NamedPath> =
        req.inputs.iter().map(|p| ("input", p.as_path())).collect();
    check_outputs(&[("-o", &req.output)], &inputs)?;
    if check_image_path(&req.output)? != Format::Exr {
        return Err(Error::Settings(format!(
            "-o {}: a merge is written as .exr",
            req.output.display()
        )));
    }
    let inputs = req
        .inputs
        .iter()
        .map(|p| MergeInput::read(p))
        .collect::<Result<Vec<_>>>()?;
    let (image, meta) = merge(&inputs)?;
    write_exr(&req.output, &image)?;
    Ok(MergeOutcome {
        inputs: inputs.len(),
        spp: meta.spp,
    })
}
