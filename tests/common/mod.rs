//! Helpers shared by the integration tests: scenes written on the fly, small renders.
#![allow(dead_code)]

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use vrpt::analysis::experiments::ExperimentSettings;
use vrpt::film::Film;
use vrpt::image_io::RgbImage;
use vrpt::output::RenderMetadata;
use vrpt::render::{render, NoProgress, RenderSettings, RenderStats};
use vrpt::scene::Scene;

/// `base` shifted by `VRPT_TEST_SEED` (default 0): the statistical tests take their seeds
/// through this, so they can be rerun with other random streams (`VRPT_TEST_SEED=3 cargo test`)
/// to check that they hold for any seed, not just the committed ones.
pub fn seed(base: u64) -> u64 {
    let offset: u64 = std::env::var("VRPT_TEST_SEED")
        .ok()
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or(0);
    base.wrapping_add(offset.wrapping_mul(1_000_003))
}

/// The shipped Cornell box.
pub fn cornell_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box")
}

/// The folder of a shipped scene.
pub fn shipped_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

/// Load a shipped scene by folder name.
pub fn shipped(name: &str) -> Scene {
    vrpt::scene::load(&shipped_path(name)).unwrap()
}

/// Write `text` to `dir/name` and return the path.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// An icosphere of radius `r` as OBJ text (faces wound outward, no normals, so shading uses the
/// flat geometric normals and the mesh is exactly convex).
pub fn icosphere_obj(r: f32, subdivisions: u32, material: &str) -> String {
    let mut s = String::new();
    let tris = vrpt::scene::generate::icosphere(subdivisions);
    for t in &tris {
        for p in t {
            writeln!(s, "v {} {} {}", p.x * r, p.y * r, p.z * r).unwrap();
        }
    }
    writeln!(s, "usemtl {material}").unwrap();
    for k in 0..tris.len() {
        writeln!(s, "f {} {} {}", 3 * k + 1, 3 * k + 2, 3 * k + 3).unwrap();
    }
    s
}

/// Render quietly.
pub fn render_quiet(scene: &Scene, settings: &RenderSettings) -> (Film, RenderStats) {
    render(scene, settings, &NoProgress).unwrap()
}

/// Render quietly and return the image as an EXR would hold it (mean, variance, metadata).
pub fn as_image(scene: &Scene, s: &RenderSettings) -> RgbImage {
    let (film, stats) = render_quiet(scene, s);
    vrpt::output::render_image(&film, &RenderMetadata::new(scene, s, &stats))
}

/// Experiment settings for `runs` runs from seed 1 on all cores, no regions.
pub fn experiment_settings(w: u32, h: u32, max_depth: u32, runs: u32) -> ExperimentSettings {
    ExperimentSettings {
        width: w,
        height: h,
        max_depth,
        seed: seed(1),
        reference_seeds: Vec::new(),
        runs,
        threads: None,
        regions: Vec::new(),
    }
}
