//! A render's outputs: the typed metadata every EXR records ([`RenderMetadata`]), and writing
//! the image (EXR with the variance channels, or PNG) plus an optional variance-only EXR.
//!
//! Metadata is stored as EXR string attributes `vrpt.KEY` (see [`crate::image_io`]); this module
//! is the one place that knows the keys. Reading is strict: a vrpt image must carry every
//! required key with a well-formed value, and its recorded size must be its real size, so
//! `merge`, `diff`, `compare` and `converge` never index pixels by a claimed size.

use crate::error::{Error, Result};
use crate::estimate::ErrorEstimate;
use crate::film::Film;
use crate::image_io::{write_exr, write_png, Format, RgbImage};
use crate::lights::{LightChoice, LightPoints, LightStrategy};
use crate::names::{parse_value, value_name};
use crate::render::{RenderSettings, RenderStats};
use crate::scene::Scene;
use crate::strategy::Strategy;
use std::collections::BTreeMap;
use std::path::Path;

/// What vrpt records about how an image was made.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderMetadata {
    /// The scene file, as given.
    pub scene: String,
    /// Hash of everything in the scene that determines the image.
    pub scene_hash: u64,
    pub width: u32,
    pub height: u32,
    /// Samples per pixel (summed over the inputs of a merge).
    pub spp: u64,
    /// Index of the first sample.
    pub first_sample: u64,
    /// The seed; `None` for a merge of several renders.
    pub seed: Option<u64>,
    /// The seeds of a merge's inputs (sorted, each once; empty for a single render): which
    /// random streams the image holds, so an experiment never reuses them.
    pub merged_seeds: Vec<u64>,
    pub strategy: Strategy,
    pub max_depth: u32,
    /// Wall time of the render (summed over the inputs of a merge).
    pub render_seconds: f64,
    /// Samples dropped because their radiance was not finite.
    pub nonfinite_samples: u64,
    /// Samples per pixel per pass, when rendered in passes.
    pub pass_spp: Option<u32>,
    /// The `--time-limit` the render ran under.
    pub time_limit_seconds: Option<f64>,
    /// The inputs of a merge.
    pub merged_from: Option<String>,
    /// What the pixels are, when not the radiance (e.g. "variance of the mean").
    pub image: Option<String>,
    /// `(i, n)`: the render is shard `i` of `n` (`vrpt render --shard i/n`).
    pub shard: Option<(u32, u32)>,
    /// The spp asked for, when the render stopped before it (a time limit or a signal).
    pub requested_spp: Option<u64>,
    /// Whether a signal (Ctrl-C, SIGTERM) stopped the render: `spp` counts the samples taken.
    pub interrupted: bool,
    /// What path guiding's training did (guided renders; a merge keeps its first input's).
    pub guide: Option<GuideRecord>,
    /// The image's estimated error (keys `replicates`, `error_estimate`, `estimated_mse`,
    /// `estimated_rel_mse`); `None` for images made before vrpt estimated it.
    pub estimate: Option<EstimateRecord>,
    /// An adaptive render's rounds (key `adaptive_rounds`; `adaptive` is then `true`).
    pub adaptive_rounds: Option<u32>,
    /// The `--target-error` the render ran under (key `target_error`).
    pub target_error: Option<f64>,
}

/// An image's estimated error, as the metadata records it.
#[derive(Clone, Debug, PartialEq)]
pub struct EstimateRecord {
    /// The replicates rendered (1: one set per pass).
    pub replicates: u32,
    /// `replicates` (from their spread) or `per-sample` (s²/n).
    pub method: String,
    /// Estimated MSE and relMSE of the image against the true one.
    pub mse: f64,
    pub rel_mse: f64,
}

impl EstimateRecord {
    /// The record of `e`, for a render of `replicates` replicates.
    pub fn new(replicates: u32, e: &ErrorEstimate) -> Self {
        EstimateRecord {
            replicates,
            method: e.method.name().into(),
            mse: e.mse,
            rel_mse: e.rel_mse,
        }
    }
}

/// The training of a guided render, as the metadata records it (keys `guide_*`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuideRecord {
    /// Training iterations, and their spp in all (not in the image).
    pub iterations: u32,
    pub training_spp: u64,
    /// Wall seconds of the training and of the final iteration (the image).
    pub training_seconds: f64,
    pub final_seconds: f64,
    /// The tree: spatial leaves, quadtree nodes, bytes.
    pub leaves: u64,
    pub quad_nodes: u64,
    pub bytes: u64,
}

impl RenderMetadata {
    /// The metadata of a render of `scene` with `settings` (whose `spp` is the spp reached).
    pub fn new(scene: &Scene, settings: &RenderSettings, stats: &RenderStats) -> Self {
        RenderMetadata {
            scene: scene.source.display().to_string(),
            scene_hash: scene.hash,
            width: settings.width,
            height: settings.height,
            spp: settings.spp as u64,
            first_sample: settings.first_sample as u64,
            seed: Some(settings.seed),
            merged_seeds: Vec::new(),
            strategy: settings.strategy,
            max_depth: settings.max_depth,
            render_seconds: stats.elapsed.as_secs_f64(),
            nonfinite_samples: stats.nonfinite,
            pass_spp: None,
            time_limit_seconds: None,
            merged_from: None,
            image: None,
            shard: None,
            requested_spp: None,
            interrupted: false,
            guide: stats.guide.map(|g| GuideRecord {
                iterations: g.iterations,
                training_spp: g.training_spp,
                training_seconds: g.training.as_secs_f64(),
                final_seconds: g.final_time.as_secs_f64(),
                leaves: g.tree.leaves as u64,
                quad_nodes: g.tree.quad_nodes as u64,
                bytes: g.tree.bytes as u64,
            }),
            estimate: None,
            adaptive_rounds: None,
            target_error: None,
        }
    }

    /// Every seed whose samples the image holds: its seed, or its inputs' for a merge (empty
    /// for a merge made before merges recorded them).
    pub fn seeds(&self) -> Vec<u64> {
        match self.seed {
            Some(s) => vec![s],
            None => self.merged_seeds.clone(),
        }
    }

    /// The scene hash as written: 16 hex digits.
    pub fn scene_hash_hex(&self) -> String {
        format!("{:016x}", self.scene_hash)
    }

    /// As string attributes (keys without the `vrpt.` prefix).
    pub fn to_attributes(&self) -> BTreeMap<String, String> {
        let mut m = BTreeMap::new();
        let mut put = |k: &str, v: String| {
            m.insert(k.to_string(), v);
        };
        put("scene", self.scene.clone());
        put("scene_hash", self.scene_hash_hex());
        put("width", self.width.to_string());
        put("height", self.height.to_string());
        put("spp", self.spp.to_string());
        put("first_sample", self.first_sample.to_string());
        put(
            "seed",
            self.seed.map_or_else(|| "merged".into(), |s| s.to_string()),
        );
        put("sampler", value_name(&self.strategy.sampler));
        put("directions", value_name(&self.strategy.directions));
        put("lights", value_name(&self.strategy.lights));
        put("light_points", value_name(&self.strategy.light_points));
        put("light_choice", value_name(&self.strategy.light_choice));
        put("strategy", self.strategy.to_string());
        put("max_depth", self.max_depth.to_string());
        put("render_seconds", format!("{:.6}", self.render_seconds));
        put("nonfinite_samples", self.nonfinite_samples.to_string());
        if let Some(p) = self.pass_spp {
            put("pass_spp", p.to_string());
        }
        if let Some(t) = self.time_limit_seconds {
            put("time_limit_seconds", t.to_string());
        }
        if let Some(f) = &self.merged_from {
            put("merged_from", f.clone());
        }
        if !self.merged_seeds.is_empty() {
            let seeds: Vec<String> = self.merged_seeds.iter().map(u64::to_string).collect();
            put("merged_seeds", seeds.join(","));
        }
        if let Some(i) = &self.image {
            put("image", i.clone());
        }
        if let Some((i, n)) = self.shard {
            put("shard", format!("{i}/{n}"));
        }
        if let Some(r) = self.requested_spp {
            put("requested_spp", r.to_string());
        }
        if self.interrupted {
            put("interrupted", "true".into());
        }
        if let Some(g) = &self.guide {
            put("guide_iterations", g.iterations.to_string());
            put("guide_training_spp", g.training_spp.to_string());
            put(
                "guide_training_seconds",
                format!("{:.6}", g.training_seconds),
            );
            put("guide_final_seconds", format!("{:.6}", g.final_seconds));
            put("guide_leaves", g.leaves.to_string());
            put("guide_quad_nodes", g.quad_nodes.to_string());
            put("guide_bytes", g.bytes.to_string());
        }
        if let Some(e) = &self.estimate {
            put("replicates", e.replicates.to_string());
            put("error_estimate", e.method.clone());
            if e.mse.is_finite() && e.rel_mse.is_finite() {
                put("estimated_mse", format!("{:e}", e.mse));
                put("estimated_rel_mse", format!("{:e}", e.rel_mse));
            }
        }
        if let Some(r) = self.adaptive_rounds {
            put("adaptive", "true".into());
            put("adaptive_rounds", r.to_string());
        }
        if let Some(t) = self.target_error {
            put("target_error", format!("{t:e}"));
        }
        m
    }

    /// Parse attributes written by [`RenderMetadata::to_attributes`]; the error names the key.
    pub fn from_attributes(a: &BTreeMap<String, String>) -> std::result::Result<Self, String> {
        fn req<'a>(
            a: &'a BTreeMap<String, String>,
            k: &str,
        ) -> std::result::Result<&'a str, String> {
            a.get(k)
                .map(String::as_str)
                .ok_or_else(|| format!("no '{k}' in its metadata: not a vrpt render"))
        }
        fn num<T: std::str::FromStr>(k: &str, v: &str) -> std::result::Result<T, String> {
            v.trim()
                .parse()
                .map_err(|_| format!("metadata '{k}' is '{v}', not a valid number"))
        }
        fn non_negative(a: &BTreeMap<String, String>, k: &str) -> std::result::Result<f64, String> {
            let v: f64 = num(k, req(a, k)?)?;
            if v.is_finite() && v >= 0.0 {
                Ok(v)
            } else {
                Err(format!(
                    "metadata '{k}' must be a finite non-negative number"
                ))
            }
        }
        fn opt<T: std::str::FromStr>(
            a: &BTreeMap<String, String>,
            k: &str,
        ) -> std::result::Result<Option<T>, String> {
            a.get(k).map(|v| num(k, v)).transpose()
        }
        let hash = req(a, "scene_hash")?;
        let scene_hash = u64::from_str_radix(hash, 16)
            .map_err(|_| format!("metadata 'scene_hash' is '{hash}', not 16 hex digits"))?;
        let seed = match req(a, "seed")? {
            "merged" => None,
            s => Some(num("seed", s)?),
        };
        let spp: u64 = num("spp", req(a, "spp")?)?;
        let first_sample: u64 = opt(a, "first_sample")?.unwrap_or(0);
        if spp == 0 {
            return Err("metadata 'spp' is 0: an image of no samples".into());
        }
        if first_sample
            .checked_add(spp)
            .is_none_or(|end| end > u32::MAX as u64 + 1)
        {
            return Err(format!(
                "metadata 'first_sample' {first_sample} + 'spp' {spp} is beyond the sample indices"
            ));
        }
        let pass_spp: Option<u32> = opt(a, "pass_spp")?;
        if pass_spp == Some(0) {
            return Err("metadata 'pass_spp' is 0".into());
        }
        let render_seconds: f64 = opt(a, "render_seconds")?.unwrap_or(0.0);
        let time_limit_seconds: Option<f64> = opt(a, "time_limit_seconds")?;
        if !(render_seconds.is_finite() && render_seconds >= 0.0)
            || time_limit_seconds.is_some_and(|t| !t.is_finite())
        {
            return Err("metadata times must be finite".into());
        }
        Ok(RenderMetadata {
            scene: a.get("scene").cloned().unwrap_or_default(),
            scene_hash,
            width: num("width", req(a, "width")?)?,
            height: num("height", req(a, "height")?)?,
            spp,
            first_sample,
            seed,
            merged_seeds: match a.get("merged_seeds") {
                None => Vec::new(),
                Some(v) => v
                    .split(',')
                    .map(|s| num("merged_seeds", s))
                    .collect::<std::result::Result<_, _>>()?,
            },
            strategy: Strategy {
                sampler: parse_value(req(a, "sampler")?, "sampler")?,
                directions: parse_value(req(a, "directions")?, "directions")?,
                // renders made before the light axis existed used BSDF sampling only
                lights: match a.get("lights") {
                    Some(l) => parse_value(l, "lights")?,
                    None => LightStrategy::Bsdf,
                },
                // and before these switches, points uniform by area chosen by power
                light_points: match a.get("light_points") {
                    Some(p) => parse_value(p, "light points")?,
                    None => LightPoints::Area,
                },
                light_choice: match a.get("light_choice") {
                    Some(c) => parse_value(c, "light choice")?,
                    None => LightChoice::Power,
                },
            },
            max_depth: num("max_depth", req(a, "max_depth")?)?,
            render_seconds,
            nonfinite_samples: opt(a, "nonfinite_samples")?.unwrap_or(0),
            pass_spp,
            time_limit_seconds,
            merged_from: a.get("merged_from").cloned(),
            image: a.get("image").cloned(),
            shard: a
                .get("shard")
                .map(|v| crate::limits::parse_shard(v))
                .transpose()?,
            requested_spp: opt(a, "requested_spp")?,
            interrupted: match a.get("interrupted").map(String::as_str) {
                None | Some("false") => false,
                Some("true") => true,
                Some(v) => {
                    return Err(format!(
                        "metadata 'interrupted' is '{v}', not true or false"
                    ))
                }
            },
            guide: match opt::<u32>(a, "guide_iterations")? {
                None => None,
                Some(iterations) => {
                    let n = |k: &str| -> std::result::Result<u64, String> { num(k, req(a, k)?) };
                    let secs = |k: &str| non_negative(a, k);
                    Some(GuideRecord {
                        iterations,
                        training_spp: n("guide_training_spp")?,
                        training_seconds: secs("guide_training_seconds")?,
                        final_seconds: secs("guide_final_seconds")?,
                        leaves: n("guide_leaves")?,
                        quad_nodes: n("guide_quad_nodes")?,
                        bytes: n("guide_bytes")?,
                    })
                }
            },
            estimate: match opt::<u32>(a, "replicates")? {
                None => None,
                Some(replicates) => {
                    // an undefined estimate has no numbers (NaN in memory)
                    let method = req(a, "error_estimate")?.to_string();
                    let err = |k: &str| match method.as_str() {
                        "undefined" => Ok(f64::NAN),
                        _ => non_negative(a, k),
                    };
                    Some(EstimateRecord {
                        replicates,
                        mse: err("estimated_mse")?,
                        rel_mse: err("estimated_rel_mse")?,
                        method,
                    })
                }
            },
            adaptive_rounds: opt(a, "adaptive_rounds")?,
            target_error: opt(a, "target_error")?,
        })
    }

    /// The metadata of an image read from `path`: `None` when it carries no vrpt metadata at all
    /// (an image made elsewhere), an error when it is malformed or its recorded size is not the
    /// image's real size.
    pub fn from_image(img: &RgbImage, path: &Path) -> Result<Option<Self>> {
        if img.metadata.is_empty() {
            return Ok(None);
        }
        let err = |message: String| Error::ImageRead {
            path: path.to_path_buf(),
            message,
        };
        let m = Self::from_attributes(&img.metadata).map_err(err)?;
        if (m.width, m.height) != (img.width, img.height) {
            return Err(err(format!(
                "its metadata says {}×{} but the image is {}×{}",
                m.width, m.height, img.width, img.height
            )));
        }
        Ok(Some(m))
    }

    /// Like [`RenderMetadata::from_image`], for an image that must hold radiance: a `--variance`
    /// image is refused.
    pub fn radiance(img: &RgbImage, path: &Path) -> Result<Option<Self>> {
        let m = Self::from_image(img, path)?;
        if let Some(what) = m.as_ref().and_then(|m| m.image.as_ref()) {
            return Err(Error::ImageRead {
                path: path.to_path_buf(),
                message: format!(
                    "holds the {}, not a render's radiance",
                    crate::error::clip(what)
                ),
            });
        }
        Ok(m)
    }

    /// Like [`RenderMetadata::radiance`], but the metadata must be there.
    ///
    /// ```
    /// use vrpt::output::{write_render, RenderMetadata};
    /// use vrpt::render::{render, NoProgress, RenderSettings};
    /// let scene = vrpt::scene::load(std::path::Path::new("scenes/cornell-box"))?;
    /// let settings = RenderSettings { width: 8, height: 8, spp: 4, seed: 7, ..Default::default() };
    /// let (film, stats) = render(&scene, &settings, &NoProgress)?;
    /// let path = std::env::temp_dir().join("vrpt-doc-metadata.exr");
    /// write_render(&path, (&film, None), &RenderMetadata::new(&scene, &settings, &stats), 0.0, None)?;
    /// // read it back: the pixels, their variance and sample counts, and what made them
    /// let image = vrpt::image_io::read_exr(&path)?;
    /// let meta = RenderMetadata::require(&image, &path)?;
    /// assert_eq!((meta.spp, meta.seed, meta.strategy), (4, Some(7), settings.strategy));
    /// assert_eq!(image.samples.as_deref().map(|s| s[0]), Some(4));
    /// # std::fs::remove_file(&path).ok();
    /// # Ok::<(), vrpt::Error>(())
    /// ```
    pub fn require(img: &RgbImage, path: &Path) -> Result<Self> {
        Self::radiance(img, path)?.ok_or_else(|| Error::ImageRead {
            path: path.to_path_buf(),
            message: "no vrpt metadata: not a vrpt render".into(),
        })
    }
}

/// The image a render's film makes, as an EXR holds it: the mean, the variance of the mean, the
/// samples in each pixel's mean, and the metadata.
pub fn render_image(film: &Film, meta: &RenderMetadata) -> RgbImage {
    RgbImage {
        width: film.width,
        height: film.height,
        pixels: film.mean_image(),
        variance: Some(film.variance_image()),
        samples: Some(film.sample_counts()),
        estimated_variance: None,
        metadata: meta.to_attributes(),
    }
}

/// Write a render: `output` as EXR (mean, variance of the mean, sample counts, the estimated
/// variance of the mean when `estimate` is given, metadata) or PNG (tone-mapped with `exposure`
/// stops); and, if asked, the variance of the mean alone to the EXR `variance`. Every file is
/// written to a temporary file and renamed.
pub fn write_render(
    output: &Path,
    (film, estimate): (&Film, Option<&ErrorEstimate>),
    meta: &RenderMetadata,
    exposure: f32,
    variance: Option<&Path>,
) -> Result<()> {
    let image = RgbImage {
        estimated_variance: estimate
            .filter(|e| e.method != crate::estimate::Method::Undefined)
            .map(|e| e.variance.clone()),
        ..render_image(film, meta)
    };
    match Format::from_path(output)? {
        Format::Exr => write_exr(output, &image)?,
        Format::Png => write_png(output, film.width, film.height, &image.pixels, exposure)?,
    }
    if let Some(v) = variance {
        let vmeta = RenderMetadata {
            image: Some("variance of the mean".into()),
            ..meta.clone()
        };
        let var = RgbImage {
            pixels: image.variance.clone().expect("a render's variance"),
            variance: None,
            estimated_variance: None,
            metadata: vmeta.to_attributes(),
            ..image
        };
        write_exr(v, &var)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::strategy::Preset;

    #[test]
    fn attributes_round_trip_and_errors_name_the_key() {
        let m = RenderMetadata {
            scene: "scenes/x".into(),
            scene_hash: 0xdead_beef_0123_4567,
            width: 4,
            height: 3,
            spp: 64,
            first_sample: 32,
            seed: Some(9),
            merged_seeds: Vec::new(),
            strategy: Preset::Importance.strategy(),
            max_depth: 5,
            render_seconds: 1.5,
            nonfinite_samples: 2,
            pass_spp: Some(16),
            time_limit_seconds: Some(0.5),
            merged_from: None,
            image: None,
            shard: Some((2, 4)),
            requested_spp: Some(128),
            interrupted: true,
            guide: Some(GuideRecord {
                iterations: 5,
                training_spp: 31,
                training_seconds: 1.25,
                final_seconds: 2.5,
                leaves: 40,
                quad_nodes: 3000,
                bytes: 123456,
            }),
            estimate: Some(EstimateRecord {
                replicates: 4,
                method: "replicates".into(),
                mse: 1.5e-4,
                rel_mse: 2.25e-3,
            }),
            adaptive_rounds: Some(6),
            target_error: Some(1e-3),
        };
        let a = m.to_attributes();
        assert_eq!(a["strategy"], "importance");
        assert_eq!(RenderMetadata::from_attributes(&a).unwrap(), m);
        let merged = RenderMetadata {
            seed: None,
            merged_seeds: vec![3, 9, 12],
            ..m.clone()
        };
        assert_eq!(merged.seeds(), [3, 9, 12]);
        assert_eq!(m.seeds(), [9]);
        assert_eq!(
            RenderMetadata::from_attributes(&merged.to_attributes()).unwrap(),
            merged
        );
        let mut bad = a.clone();
        bad.insert("spp".into(), "many".into());
        assert!(RenderMetadata::from_attributes(&bad)
            .unwrap_err()
            .contains("'spp'"));
        bad = a.clone();
        bad.remove("max_depth");
        assert!(RenderMetadata::from_attributes(&bad)
            .unwrap_err()
            .contains("'max_depth'"));
        bad = a.clone();
        bad.insert("sampler".into(), "nosuch".into());
        assert!(RenderMetadata::from_attributes(&bad)
            .unwrap_err()
            .contains("sampler"));
        // a recorded size that is not the image's is refused
        let img = RgbImage {
            width: 2,
            height: 3,
            pixels: vec![glam::Vec3::ZERO; 6],
            metadata: a,
            ..RgbImage::default()
        };
        let e = RenderMetadata::from_image(&img, Path::new("x.exr")).unwrap_err();
        assert!(e.to_string().contains("4×3"), "{e}");
    }
}
