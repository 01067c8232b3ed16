//! Merging renders of the same scene and settings made with different seeds or sample ranges,
//! as a reference is built in pieces. Each pixel's means are combined weighted by the number of
//! samples in them, `M = Σ nᵢ mᵢ / Σ nᵢ`, with `nᵢ` the input's per-pixel count (its `samples`
//! channel: the spp less the non-finite samples the film dropped in that pixel; the metadata's
//! spp for an image made before the channel existed). Where every input carries the variance
//! of its mean `vᵢ`, the sums of squares are recovered exactly, `Σx² = vᵢ nᵢ (nᵢ − 1) + nᵢ mᵢ²`,
//! and the merged variance of the mean is `(Σx² − N M²) / (N (N − 1))`. This equals one render of
//! all the samples (one film holding every input's sums), up to f32 storage rounding.
//!
//! Where every input carries an estimated variance from replicates (`estimated_variance.*`),
//! the merge's is `Σ (nᵢ/N)² vᵢ`, the variance of a weighted mean of independent means (its
//! metadata says `error_estimate = merged`): exact for renders of different seeds, and only
//! about right for shards of one render, whose replicates are split between them. Adaptive
//! renders do not merge: their pixels weigh rounds, not samples.

use crate::error::{Error, Result};
use crate::image_io::RgbImage;
use crate::output::{EstimateRecord, RenderMetadata};
use glam::{DVec3, Vec3};
use std::path::PathBuf;

/// One input of a merge: the image, its file (for messages) and its metadata.
pub struct MergeInput {
    /// Where the input was read from.
    pub path: PathBuf,
    /// Its pixels, variance and counts.
    pub image: RgbImage,
    /// Its metadata.
    pub meta: RenderMetadata,
}

impl MergeInput {
    /// An input read from `path`: it must be a vrpt render whose metadata fits its pixels.
    pub fn read(path: &std::path::Path) -> Result<MergeInput> {
        let image = crate::image_io::read_exr(path)?;
        let meta = RenderMetadata::require(&image, path)?;
        check_counts(&image, &meta).map_err(|message| Error::ImageRead {
            path: path.to_path_buf(),
            message,
        })?;
        Ok(MergeInput {
            path: path.to_path_buf(),
            image,
            meta,
        })
    }
}

/// A merge weighs each pixel by its `samples` channel, so the channel must agree with the
/// metadata (`read_exr` has already checked that every count is a whole number and every
/// variance finite and non-negative): no pixel holds more than the file's spp (an adaptive
/// render does not merge), and the counts add up to the spp over every pixel less the
/// non-finite samples dropped. The error names the first pixel that disagrees.
fn check_counts(image: &RgbImage, meta: &RenderMetadata) -> std::result::Result<(), String> {
    let Some(counts) = &image.samples else {
        return Ok(());
    };
    let w = image.width as usize;
    if meta.adaptive_rounds.is_none() {
        if let Some(k) = counts.iter().position(|&n| n as u64 > meta.spp) {
            return Err(format!(
                "pixel ({}, {}) holds {} samples, more than the file's spp, {}",
                k % w,
                k / w,
                counts[k],
                meta.spp
            ));
        }
    }
    let sum: u64 = counts.iter().map(|&n| n as u64).sum();
    let expected = (counts.len() as u64 * meta.spp).checked_sub(meta.nonfinite_samples);
    if meta.adaptive_rounds.is_none() && Some(sum) != expected {
        return Err(format!(
            "its pixels hold {sum} samples in all, but its metadata says {} spp over {} pixels \
             less {} non-finite samples dropped",
            meta.spp,
            counts.len(),
            meta.nonfinite_samples
        ));
    }
    if let Some(k) = counts.iter().position(|&n| n == 0) {
        if image.pixels[k] != Vec3::ZERO {
            return Err(format!(
                "pixel ({}, {}) holds no samples but its value is {}",
                k % w,
                k / w,
                image.pixels[k]
            ));
        }
    }
    Ok(())
}

/// Merge `inputs` into one image and its metadata.
pub fn merge(inputs: &[MergeInput]) -> Result<(RgbImage, RenderMetadata)> {
    check_inputs(inputs)?;
    let first = &inputs[0].meta;
    let merged = merge_pixels(inputs)?;
    let meta = merged_metadata(inputs, &merged);
    let image = RgbImage {
        width: first.width,
        height: first.height,
        pixels: merged.pixels,
        variance: merged.variance,
        samples: Some(merged.samples),
        estimated_variance: merged.estimated,
        metadata: meta.to_attributes(),
    };
    Ok((image, meta))
}

/// Whether `inputs` can merge: at least two, all of one scene and settings, none adaptive or
/// itself a merge, and no two holding the same samples of one seed. The error names the input.
fn check_inputs(inputs: &[MergeInput]) -> Result<()> {
    if inputs.len() < 2 {
        return Err(Error::Settings("merge needs at least two images".into()));
    }
    let bad = |i: usize, m: String| Error::Settings(format!("{}: {m}", inputs[i].path.display()));
    let first = &inputs[0].meta;
    let mut ranges: Vec<(u64, u64, u64)> = Vec::new();
    for (i, input) in inputs.iter().enumerate() {
        let m = &input.meta;
        if let Some(key) = differing_setting(m, first) {
            let show = |x: &std::collections::BTreeMap<String, String>| match key {
                "size" => format!("{}×{}", x["width"], x["height"]),
                // written only where it is on
                "reuse" => x.get("reuse").map_or("1 (off)".into(), |k| k.clone()),
                "roulette" => x.get("roulette").map_or("classic".into(), |k| k.clone()),
                "edge_rays" => x.get("edge_rays").map_or("0 (off)".into(), |k| k.clone()),
                k => x.get(k).cloned().unwrap_or_else(|| "absent".into()),
            };
            return Err(bad(
                i,
                format!(
                    "{key} is {} but {} has {}: only renders of the same scene and settings merge",
                    show(&m.to_attributes()),
                    inputs[0].path.display(),
                    show(&first.to_attributes())
                ),
            ));
        }
        if m.adaptive_rounds.is_some() {
            return Err(bad(
                i,
                "is an adaptive render: its pixels weigh rounds, not samples, so it does not merge"
                    .into(),
            ));
        }
        let Some(seed) = m.seed else {
            return Err(bad(
                i,
                "is itself a merge; merge the original renders".into(),
            ));
        };
        let (start, n) = (m.first_sample, m.spp);
        if let Some((_, a, b)) = ranges
            .iter()
            .find(|(s, a, b)| *s == seed && start < *b && start + n > *a)
        {
            return Err(bad(
                i,
                format!("samples {start}..{} of seed {seed} overlap samples {a}..{b} of another input: the same samples would count twice", start + n),
            ));
        }
        ranges.push((seed, start, start + n));
    }
    Ok(())
}

/// The first setting (by its metadata key, or `size`) in which `m` differs from `first`, the
/// settings that must agree for two renders to merge.
fn differing_setting(m: &RenderMetadata, first: &RenderMetadata) -> Option<&'static str> {
    let differs = [
        ("scene_hash", m.scene_hash != first.scene_hash),
        ("size", (m.width, m.height) != (first.width, first.height)),
        ("max_depth", m.max_depth != first.max_depth),
        ("reuse", m.reuse != first.reuse),
        ("roulette", m.roulette != first.roulette),
        ("edge_rays", m.edge_rays != first.edge_rays),
        ("sampler", m.strategy.sampler != first.strategy.sampler),
        (
            "directions",
            m.strategy.directions != first.strategy.directions,
        ),
        ("lights", m.strategy.lights != first.strategy.lights),
        (
            "light_points",
            m.strategy.light_points != first.strategy.light_points,
        ),
        (
            "light_choice",
            m.strategy.light_choice != first.strategy.light_choice,
        ),
    ];
    differs.iter().find(|(_, d)| *d).map(|(key, _)| *key)
}

/// The merged pixels: means, variances of the mean and estimated variances (where every input
/// has them) and per-pixel sample counts.
struct MergedPixels {
    pixels: Vec<Vec3>,
    variance: Option<Vec<Vec3>>,
    estimated: Option<Vec<Vec3>>,
    samples: Vec<u32>,
}

/// Samples in pixel `p` of `input`: its `samples` channel, else the metadata's spp.
fn count(input: &MergeInput, p: usize) -> u64 {
    input
        .image
        .samples
        .as_ref()
        .map_or(input.meta.spp, |s| s[p] as u64)
}

/// Each pixel's inputs combined, weighted by their sample counts (see the module doc); an error
/// where a pixel would hold more samples than a u32 counts.
fn merge_pixels(inputs: &[MergeInput]) -> Result<MergedPixels> {
    let with_var = inputs.iter().all(|i| i.image.variance.is_some());
    let px = inputs[0].image.pixels.len();
    let mut pixels = vec![Vec3::ZERO; px];
    let mut variance = with_var.then(|| vec![Vec3::ZERO; px]);
    // the inputs' estimated variances combine as those of independent means, Σ (nᵢ/N)² vᵢ
    let with_estimate = inputs.iter().all(|i| i.image.estimated_variance.is_some());
    let mut estimated = with_estimate.then(|| vec![Vec3::ZERO; px]);
    let mut samples = vec![0u32; px];
    for p in 0..px {
        let (mut sum, mut sum_sq, mut nt) = (DVec3::ZERO, DVec3::ZERO, 0u64);
        for input in inputs {
            let n = count(input, p);
            let (m, nf) = (input.image.pixels[p].as_dvec3(), n as f64);
            sum += m * nf;
            nt += n;
            if let Some(v) = &input.image.variance {
                sum_sq += v[p].as_dvec3() * nf * (nf - 1.0).max(0.0) + m * m * nf;
            }
        }
        samples[p] = u32::try_from(nt).map_err(|_| {
            Error::Settings(format!(
                "the merge would hold {nt} samples in one pixel, more than a u32 counts"
            ))
        })?;
        let n = nt as f64;
        let mean = if nt > 0 { sum / n } else { DVec3::ZERO };
        pixels[p] = mean.as_vec3();
        if let Some(est) = &mut estimated {
            let mut e = DVec3::ZERO;
            for input in inputs {
                let w = count(input, p) as f64 / n.max(1.0);
                let v = input.image.estimated_variance.as_ref().expect("checked")[p];
                e += w * w * v.as_dvec3();
            }
            est[p] = e.as_vec3();
        }
        if let Some(var) = &mut variance {
            var[p] = if nt > 1 {
                ((sum_sq - mean * mean * n) / (n * (n - 1.0)))
                    .max(DVec3::ZERO)
                    .as_vec3()
            } else {
                Vec3::ZERO
            };
        }
    }
    Ok(MergedPixels {
        pixels,
        variance,
        estimated,
        samples,
    })
}

/// The merge's metadata: the first input's settings with the inputs' spp, seeds, times and
/// dropped samples summed, their files named, and the merged error estimate where there is one.
fn merged_metadata(inputs: &[MergeInput], merged: &MergedPixels) -> RenderMetadata {
    let first = &inputs[0].meta;
    let names: Vec<String> = inputs
        .iter()
        .map(|i| i.path.display().to_string())
        .collect();
    let mut seeds: Vec<u64> = inputs.iter().flat_map(|i| i.meta.seeds()).collect();
    seeds.sort_unstable();
    seeds.dedup();
    RenderMetadata {
        spp: inputs.iter().map(|i| i.meta.spp).sum(),
        seed: None,
        merged_seeds: seeds,
        first_sample: 0,
        merged_from: Some(names.join(", ")),
        render_seconds: inputs.iter().map(|i| i.meta.render_seconds).sum(),
        nonfinite_samples: inputs.iter().map(|i| i.meta.nonfinite_samples).sum(),
        pass_spp: None,
        passes: Vec::new(),
        time_limit_seconds: None,
        image: None,
        auto: None,
        guide_gate: None,
        shard: None,
        requested_spp: None,
        interrupted: inputs.iter().any(|i| i.meta.interrupted),
        estimate: merged.estimated.as_ref().map(|v| {
            let (mse, rel_mse) = crate::estimate::image_error(first.width, &merged.pixels, v);
            EstimateRecord {
                replicates: inputs
                    .iter()
                    .map(|i| i.meta.estimate.as_ref().map_or(1, |e| e.replicates))
                    .sum(),
                method: crate::output::EstimateMethod::Merged,
                mse,
                rel_mse,
            }
        }),
        target_error: None,
        ..first.clone()
    }
}
