//! Helpers shared by the integration tests: scenes written on the fly, small renders.
#![allow(dead_code)]

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
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

/// Run the `vrpt` binary with `args`.
pub fn vrpt(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vrpt"))
        .args(args)
        .output()
        .expect("run vrpt")
}

/// `out`, after asserting it succeeded (its stderr otherwise).
pub fn ok(out: Output) -> Output {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Run `vrpt` with `args` and assert it succeeded.
pub fn vrpt_ok(args: &[&str]) -> Output {
    let o = vrpt(args);
    assert!(
        o.status.success(),
        "vrpt {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// One error line holding every string of `expect`, a non-zero exit, no panic.
pub fn assert_refused(out: &Output, what: &str, expect: &[&str]) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{what}: should fail");
    assert!(!stderr.contains("panicked"), "{what}: panicked: {stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{what}: one line expected, got: {stderr}");
    for e in expect {
        assert!(lines[0].contains(e), "{what}: '{}' lacks '{e}'", lines[0]);
    }
}

/// [`assert_refused`] with one expected string.
pub fn assert_one_line_error(out: &Output, what: &str, expect: &str) {
    assert_refused(out, what, &[expect]);
}

/// Two 8×8, 2-spp renders of the Cornell box into `dir`, with `flag` at the values `a` and
/// `b` (and seeds 1 and 2), then their merge, which must be refused in one line holding every
/// string of `expect`, writing nothing. The first render's path is returned (for its metadata).
pub fn assert_merge_refused(
    dir: &Path,
    flag: &str,
    (a, b): (&str, &str),
    expect: &[&str],
) -> PathBuf {
    let scene = cornell_path();
    let (pa, pb, m) = (dir.join("a.exr"), dir.join("b.exr"), dir.join("m.exr"));
    for (out, value, seed) in [(&pa, a, "1"), (&pb, b, "2")] {
        vrpt_ok(&[
            "render",
            scene.to_str().unwrap(),
            "--width",
            "8",
            "--height",
            "8",
            "--spp",
            "2",
            "--seed",
            seed,
            flag,
            value,
            "-q",
            "-o",
            out.to_str().unwrap(),
        ]);
    }
    let out = vrpt(&[
        "merge",
        pa.to_str().unwrap(),
        pb.to_str().unwrap(),
        "-o",
        m.to_str().unwrap(),
    ]);
    assert_refused(&out, &format!("merge {flag} {a} and {b}"), expect);
    assert!(!m.exists(), "a refused merge wrote {}", m.display());
    pa
}

/// Independent uniform points of the unit square from `seed`.
pub fn uniform_pairs(seed: u64) -> impl FnMut() -> glam::Vec2 {
    use rand::{rngs::SmallRng, Rng, SeedableRng};
    let mut rng = SmallRng::seed_from_u64(seed);
    move || glam::Vec2::new(rng.random(), rng.random())
}
