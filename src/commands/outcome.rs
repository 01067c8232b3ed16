//! What `vrpt render` says and writes of a finished render ([`RenderOutcome`]): its warnings
//! (dropped samples, a black image, missing replicates, an interruption), the image written
//! again on request, the pass sizes its metadata records and the lines an adaptive render adds
//! to the summary.

use super::render::RenderOutcome;
use crate::error::Result;
use crate::image_io::{check_image_path, check_writable};
use crate::output::write_render;
use crate::render::Rendered;
use std::path::Path;

impl RenderOutcome {
    /// What the user must hear about: dropped non-finite samples, an interrupted render.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if self.stats.nonfinite > 0 {
            w.push(format!(
                "{} non-finite radiance samples were dropped (not written into the image)",
                self.stats.nonfinite
            ));
        }
        if let Some(why) = &self.black {
            w.push(why.clone());
        }
        if let Some(asked) = self.missing_replicates {
            w.push(format!(
                "only {} of the {asked} replicates rendered (the spp or the time ran out after \
                 {} spp): the metadata records {}",
                self.settings.replicates, self.settings.spp, self.settings.replicates
            ));
        }
        if self.interrupted {
            let (spp, asked) = (self.settings.spp, self.requested_spp);
            w.push(match &self.output {
                Some(p) => format!(
                    "interrupted: wrote {} with the {spp} of {asked} spp taken (its metadata \
                     says so)",
                    p.display()
                ),
                None => format!("interrupted: kept the {spp} of {asked} spp taken"),
            });
        }
        w
    }

    /// Write the image as `vrpt render -o PATH --exposure EXPOSURE [--variance VARIANCE]`
    /// would have: EXR (mean, variance of the mean, samples, estimated variance, metadata) or
    /// PNG, each file written whole or not at all.
    pub fn write(&self, path: &Path, exposure: f32, variance: Option<&Path>) -> Result<()> {
        check_image_path(path)?;
        check_writable(path)?;
        write_render(
            path,
            (&self.film, Some(&self.estimate)),
            &self.meta,
            exposure,
            variance,
        )
    }
}

/// The pass sizes a render records: all of them, where any but the last differs from the
/// first (passes that grew, or a rest split off a sliver) or from the pass size asked for;
/// none where they were the plain passes of `pass_spp` (a shorter last one included).
pub(super) fn passes_record(passes: &[u32], pass_spp: Option<u32>) -> Vec<u32> {
    let plain = match passes.split_last() {
        None => true,
        Some((_, rest)) => rest
            .iter()
            .all(|&p| Some(p) == pass_spp.or(passes.first().copied())),
    };
    if plain {
        Vec::new()
    } else {
        passes.to_vec()
    }
}

/// What an adaptive render did, in a line or three (empty for a uniform render): its rounds
/// and the range of samples per pixel, the rounds that gave every pixel the same because the
/// cross-validated gain of allocating was below `bar`, or that it finished uniformly, and its
/// bounds on the gain over uniform sampling.
pub(super) fn adaptive_summary(r: &Rendered, bar: f64) -> String {
    let mut text = String::new();
    if let Some(n) = r.rounds {
        let counts = r.film.sample_counts();
        let (lo, hi) = (counts.iter().min(), counts.iter().max());
        let uniform = match r.uniform_rounds {
            0 => String::new(),
            u => format!(
                " ({u} of them uniform: the cross-validated gain of allocating from the rounds \
                 before was below {bar})"
            ),
        };
        text += &format!(
            "adaptive: {n} rounds{uniform}, {} to {} samples per pixel\n",
            lo.copied().unwrap_or(0),
            hi.copied().unwrap_or(0)
        );
    }
    if let Some(gain) = r.finished_uniformly {
        text += &format!(
            "adaptive: after the first round the cross-validated gain of allocating was \
             {gain:.2}, below {bar}: the rest rendered as uniform passes of one set of points\n"
        );
    }
    if let Some(g) = &r.allocation {
        text += &format!(
            "adaptive: relMSE gain over uniform at equal spp, bounds from this image: ideal \
             (n ∝ e) {:.2}, this schedule (first round {:.0}%, uniform share {:.0}%) {:.2}; a \
             round allocated from estimates this noisy, cross-validated {:.2}\n",
            g.ideal,
            100.0 * g.first_share,
            100.0 * crate::estimate::UNIFORM_SHARE,
            g.schedule,
            g.cross_validated
        );
    }
    text
}
