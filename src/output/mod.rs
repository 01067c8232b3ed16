//! A render's outputs: the typed metadata every EXR records ([`RenderMetadata`]), and writing
//! the image (EXR with the variance channels, or PNG) plus an optional variance-only EXR.
//!
//! Metadata is stored as EXR string attributes `vrpt.KEY` (see [`crate::image_io`]);
//! `output::keys` is the one place that knows the keys, each spelled once in [`KEYS`]. Reading
//! is strict: a vrpt image must carry every required key with a well-formed value, and its recorded size must be its real size, so
//! `merge`, `diff`, `compare` and `converge` never index pixels by a claimed size.

mod keys;
mod metadata;

pub use keys::{Key, KEYS};
pub use metadata::{EstimateMethod, EstimateRecord, GuideRecord, RenderMetadata};

use crate::error::Result;
use crate::estimate::ErrorEstimate;
use crate::film::Film;
use crate::image_io::{write_exr, write_png, Format, RgbImage};
use std::path::Path;

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

    /// Metadata with every kind of field set.
    fn sample_metadata() -> RenderMetadata {
        RenderMetadata {
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
            reuse: Some(3),
            roulette: crate::integrator::rrs::Roulette::Ears,
            edge_rays: 16,
            render_seconds: 1.5,
            nonfinite_samples: 2,
            pass_spp: Some(16),
            passes: vec![16, 32, 20],
            time_limit_seconds: Some(0.5),
            merged_from: None,
            image: None,
            auto: Some("chose mis; efficiency mis 1.000, stratified+guided+mis 0.83".into()),
            guide_gate: Some(
                "closed at 8 spp: Phong directions 1.79x as efficient as the guide, z 4.2".into(),
            ),
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
                combined: 3,
                final_weight: 0.75,
            }),
            estimate: Some(EstimateRecord {
                replicates: 4,
                method: EstimateMethod::Replicates,
                mse: 1.5e-4,
                rel_mse: 2.25e-3,
            }),
            adaptive_rounds: Some(6),
            target_error: Some(1e-3),
        }
    }

    #[test]
    fn attributes_round_trip_and_errors_name_the_key() {
        let m = sample_metadata();
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
        // a malformed, missing or unknown value: the error names the key
        let broken = [
            ("spp", Some("many"), "'spp'"),
            ("max_depth", None, "'max_depth'"),
            ("sampler", Some("nosuch"), "sampler"),
        ];
        for (key, value, named) in broken {
            let mut bad = a.clone();
            match value {
                Some(v) => bad.insert(key.into(), v.into()),
                None => bad.remove(key),
            };
            let e = RenderMetadata::from_attributes(&bad).unwrap_err();
            assert!(e.contains(named), "{key}: {e}");
        }
    }

    /// A recorded size that is not the image's is refused.
    #[test]
    fn a_recorded_size_that_is_not_the_images_is_refused() {
        let a = sample_metadata().to_attributes();
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
