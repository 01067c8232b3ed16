//! Merging renders of the same scene and settings made with different seeds or sample ranges,
//! as a reference is built in pieces. Means are combined weighted by spp,
//! `M = Σ nᵢ mᵢ / Σ nᵢ`; where every input carries the variance of its mean `vᵢ`, the sums of
//! squares are recovered exactly, `Σx² = vᵢ nᵢ (nᵢ − 1) + nᵢ mᵢ²`, and the merged variance of
//! the mean is `(Σx² − N M²) / (N (N − 1))`. This equals one render of all the samples, up to
//! f32 storage rounding.

use crate::error::{Error, Result};
use crate::image_io::RgbImage;
use glam::{DVec3, Vec3};
use std::collections::BTreeMap;

/// Keys that must agree for renders to be merged.
pub const MUST_MATCH: [&str; 6] = [
    "scene_hash",
    "width",
    "height",
    "max_depth",
    "sampler",
    "directions",
];

/// Merge `inputs` (named by `names`, for messages) into one image.
pub fn merge(inputs: &[RgbImage], names: &[String]) -> Result<RgbImage> {
    if inputs.len() < 2 {
        return Err(Error::Settings("merge needs at least two images".into()));
    }
    let bad = |i: usize, m: String| Error::Settings(format!("{}: {m}", names[i]));
    let first = &inputs[0];
    let mut spp = Vec::new();
    let mut ranges: Vec<(String, u64, u64)> = Vec::new();
    for (i, img) in inputs.iter().enumerate() {
        for key in MUST_MATCH.iter().chain(["spp", "seed"].iter()) {
            if !img.metadata.contains_key(*key) {
                return Err(bad(
                    i,
                    format!("no '{key}' in its metadata: not a vrpt render"),
                ));
            }
        }
        for key in MUST_MATCH {
            if img.metadata[key] != first.metadata[key] {
                return Err(bad(
                    i,
                    format!(
                        "{key} is {} but {} has {}: only renders of the same scene and settings merge",
                        img.metadata[key], names[0], first.metadata[key]
                    ),
                ));
            }
        }
        let n: u64 = img.metadata["spp"]
            .parse()
            .map_err(|_| bad(i, "spp is not a number".into()))?;
        let start: u64 = img
            .metadata
            .get("first_sample")
            .map_or(Ok(0), |s| s.parse())
            .map_err(|_| bad(i, "first_sample is not a number".into()))?;
        let seed = img.metadata["seed"].clone();
        if seed == "merged" {
            return Err(bad(
                i,
                "is itself a merge; merge the original renders".into(),
            ));
        }
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
        spp.push(n);
    }
    let total: u64 = spp.iter().sum();
    let with_var = inputs.iter().all(|i| i.variance.is_some());
    let px = first.pixels.len();
    let mut pixels = vec![Vec3::ZERO; px];
    let mut variance = with_var.then(|| vec![Vec3::ZERO; px]);
    for p in 0..px {
        let (mut sum, mut sum_sq) = (DVec3::ZERO, DVec3::ZERO);
        for (img, &n) in inputs.iter().zip(&spp) {
            let (m, n) = (img.pixels[p].as_dvec3(), n as f64);
            sum += m * n;
            if let Some(v) = &img.variance {
                sum_sq += v[p].as_dvec3() * n * (n - 1.0) + m * m * n;
            }
        }
        let nt = total as f64;
        let mean = sum / nt;
        pixels[p] = mean.as_vec3();
        if let Some(var) = &mut variance {
            var[p] = if total > 1 {
                ((sum_sq - mean * mean * nt) / (nt * (nt - 1.0)))
                    .max(DVec3::ZERO)
                    .as_vec3()
            } else {
                Vec3::ZERO
            };
        }
    }
    let mut metadata: BTreeMap<String, String> = MUST_MATCH
        .iter()
        .map(|k| (k.to_string(), first.metadata[*k].clone()))
        .collect();
    for key in ["scene", "strategy"] {
        if let Some(v) = first.metadata.get(key) {
            metadata.insert(key.into(), v.clone());
        }
    }
    metadata.insert("spp".into(), total.to_string());
    metadata.insert("seed".into(), "merged".into());
    metadata.insert("first_sample".into(), "0".into());
    metadata.insert("merged_from".into(), names.join(", "));
    let seconds: f64 = inputs
        .iter()
        .filter_map(|i| i.metadata.get("render_seconds")?.parse::<f64>().ok())
        .sum();
    metadata.insert("render_seconds".into(), format!("{seconds:.6}"));
    Ok(RgbImage {
        width: first.width,
        height: first.height,
        pixels,
        variance,
        metadata,
    })
}
