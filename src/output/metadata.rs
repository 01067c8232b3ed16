//! The typed metadata every vrpt EXR records ([`RenderMetadata`]), and its one table of keys.
//!
//! Each key of the EXR's `vrpt.KEY` string attributes is spelled once, in [`KEYS`]: its name,
//! how its value is written from a [`RenderMetadata`] (or not written, where the field is
//! empty) and how it is read back into one. Reading is strict: a vrpt image must carry every
//! required key with a well-formed value (an error names the key), and the keys that came
//! later than the first images (the light switches, the estimate, guiding, adaptive rounds)
//! read as what images before them meant. Adding a key is one row of the table and one field.

use super::keys::{Value, KEYS};
use crate::error::{Error, Result};
use crate::estimate::{ErrorEstimate, Method};
use crate::image_io::RgbImage;
use crate::lights::{LightChoice, LightPoints, LightStrategy};
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
    /// Path reuse's block side (`--reuse K`), where it was on (K ≥ 2).
    pub reuse: Option<u32>,
    /// How paths ended and split (`--roulette`).
    pub roulette: crate::integrator::rrs::Roulette,
    /// The edge rays a sample spent in an edge pixel (`--edge-rays`; 0: none, as in images
    /// from before them).
    pub edge_rays: u32,
    /// Wall time of the render, `--strategy auto`'s pilots included (summed over the inputs of
    /// a merge).
    pub render_seconds: f64,
    /// Samples dropped because their radiance was not finite.
    pub nonfinite_samples: u64,
    /// Samples per pixel per pass, when rendered in passes (the first pass's, where passes
    /// followed the clock).
    pub pass_spp: Option<u32>,
    /// Every uniform pass's samples per pixel, in order, where they were not all `pass_spp`
    /// (passes that grew under a time limit, or a rest kept from a sliver of a grid; key
    /// `passes`, comma-separated); empty otherwise.
    pub passes: Vec<u32>,
    /// The `--time-limit` the render ran under.
    pub time_limit_seconds: Option<f64>,
    /// The inputs of a merge.
    pub merged_from: Option<String>,
    /// What the pixels are, when not the radiance (e.g. "variance of the mean").
    pub image: Option<String>,
    /// `--strategy auto`'s choice and what its pilots measured ([`crate::render::auto::Choice::record`]).
    pub auto: Option<String>,
    /// A guided render's gate: what its probes read and its verdict
    /// ([`crate::render::gate::Gate::record`]).
    pub guide_gate: Option<String>,
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
    /// How it was estimated.
    pub method: EstimateMethod,
    /// Estimated MSE and relMSE of the image against the true one.
    pub mse: f64,
    pub rel_mse: f64,
}

impl EstimateRecord {
    /// Its MSE and relMSE, where both are numbers (an undefined estimate has none).
    pub fn numbers(&self) -> Option<(f64, f64)> {
        (self.mse.is_finite() && self.rel_mse.is_finite()).then_some((self.mse, self.rel_mse))
    }

    /// The record of `e`, for a render of `replicates` replicates.
    pub fn new(replicates: u32, e: &ErrorEstimate) -> Self {
        EstimateRecord {
            replicates,
            method: match e.method {
                Method::Replicates(_) => EstimateMethod::Replicates,
                Method::PerSample => EstimateMethod::PerSample,
                Method::Undefined => EstimateMethod::Undefined,
            },
            mse: e.mse,
            rel_mse: e.rel_mse,
        }
    }
}

/// How an image's error was estimated, as the metadata's `error_estimate` names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EstimateMethod {
    /// From the spread of randomized replicates.
    Replicates,
    /// From the samples' variance, `s²/n` (one set).
    PerSample,
    /// None could be made: the numbers are NaN.
    Undefined,
    /// A merge of estimated images: the inputs' estimates weighted by their spp.
    Merged,
}

impl EstimateMethod {
    const ALL: [EstimateMethod; 4] = [
        EstimateMethod::Replicates,
        EstimateMethod::PerSample,
        EstimateMethod::Undefined,
        EstimateMethod::Merged,
    ];

    /// The name the metadata records.
    pub fn name(self) -> &'static str {
        match self {
            EstimateMethod::Replicates => "replicates",
            EstimateMethod::PerSample => "per-sample",
            EstimateMethod::Undefined => "undefined",
            EstimateMethod::Merged => "merged",
        }
    }

    /// The method of a recorded name.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
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
    /// The training iterations the image combines with the final one (0: the final alone),
    /// and the final iteration's mean weight in it (1 when alone).
    pub combined: u32,
    pub final_weight: f64,
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
            reuse: (settings.reuse > 1).then_some(settings.reuse),
            roulette: settings.roulette,
            edge_rays: settings.edge_rays,
            render_seconds: stats.elapsed.as_secs_f64(),
            nonfinite_samples: stats.nonfinite,
            pass_spp: None,
            passes: Vec::new(),
            time_limit_seconds: None,
            merged_from: None,
            image: None,
            auto: None,
            guide_gate: stats.guide.and_then(|g| g.gate).map(|g| g.record()),
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
                combined: g.combined.map_or(0, |c| c.iterations),
                final_weight: g.combined.map_or(1.0, |c| c.final_weight),
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

    /// As string attributes (keys without the `vrpt.` prefix): every key of [`KEYS`] whose
    /// field holds something.
    pub fn to_attributes(&self) -> BTreeMap<String, String> {
        KEYS.iter()
            .filter_map(|k| Some((k.name.to_string(), (k.write)(self)?)))
            .collect()
    }

    /// Parse attributes written by [`RenderMetadata::to_attributes`]; the error names the key.
    pub fn from_attributes(a: &BTreeMap<String, String>) -> std::result::Result<Self, String> {
        let mut m = RenderMetadata::before_keys();
        for k in KEYS {
            let value = Value {
                key: k.name,
                text: a.get(k.name).map(String::as_str),
            };
            (k.read)(&mut m, value)?;
        }
        if m.spp == 0 {
            return Err("metadata 'spp' is 0: an image of no samples".into());
        }
        if m.first_sample
            .checked_add(m.spp)
            .is_none_or(|end| end > u32::MAX as u64 + 1)
        {
            return Err(format!(
                "metadata 'first_sample' {} + 'spp' {} is beyond the sample indices",
                m.first_sample, m.spp
            ));
        }
        Ok(m)
    }

    /// What an image's metadata means before any key is read: what the keys that came later
    /// than the first images mean when absent (BSDF sampling only, points by area chosen by
    /// power, no estimate, no guide).
    fn before_keys() -> Self {
        RenderMetadata {
            scene: String::new(),
            scene_hash: 0,
            width: 0,
            height: 0,
            spp: 0,
            first_sample: 0,
            seed: None,
            merged_seeds: Vec::new(),
            strategy: Strategy {
                lights: LightStrategy::Bsdf,
                light_points: LightPoints::Area,
                light_choice: LightChoice::Power,
                ..Strategy::default()
            },
            max_depth: 0,
            reuse: None,
            roulette: Default::default(),
            edge_rays: 0,
            render_seconds: 0.0,
            nonfinite_samples: 0,
            pass_spp: None,
            passes: Vec::new(),
            time_limit_seconds: None,
            merged_from: None,
            image: None,
            auto: None,
            guide_gate: None,
            shard: None,
            requested_spp: None,
            interrupted: false,
            guide: None,
            estimate: None,
            adaptive_rounds: None,
            target_error: None,
        }
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
