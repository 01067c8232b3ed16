//! The command line: argument definitions (clap) and what each command does. `main.rs` only
//! parses and calls [`run`]; errors come back as one line for it to print.

use crate::analysis::experiments::{
    compare, converge, Comparison, Convergence, ExperimentProgress, ExperimentSettings, Silent,
    StrategySpec,
};
use crate::analysis::merge::merge;
use crate::analysis::metrics::{bias_z_scores, false_colour, metrics, relative_error_map};
use crate::analysis::plots::{error_scale, write_convergence_plot, write_image_grid, GridRow};
use crate::error::{Error, Result};
use crate::image_io::{read_exr, write_exr, write_image, write_png_rgb8, Format, RgbImage};
use crate::material::Directions;
use crate::render::{
    render_passes, NoProgress, PassPlan, Progress, RenderSettings, RenderStats, Strategy,
};
use crate::sampler::SamplerKind;
use crate::scene::{self, Scene};
use clap::{Args, Parser, Subcommand};
use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Built-in defaults, used where neither a flag nor scene.toml says otherwise.
pub const DEFAULT_WIDTH: u32 = 256;
pub const DEFAULT_HEIGHT: u32 = 256;
pub const DEFAULT_SPP: u32 = 16;
pub const DEFAULT_MAX_DEPTH: u32 = 8;

/// vrpt: a path tracer for seeing and measuring variance reduction in Monte Carlo rendering.
#[derive(Debug, Parser)]
#[command(name = "vrpt", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render a scene to an EXR (linear, with metadata) or PNG (tone-mapped sRGB).
    Render(RenderArgs),
    /// Merge renders of the same scene and settings (other seeds or sample ranges) into one
    /// image, weighting by spp: how a long reference is built in pieces.
    Merge(MergeArgs),
    /// Print the error metrics of an EXR against a reference EXR; optionally write an error map.
    Diff(DiffArgs),
    /// Render a scene with several strategies over several runs and compare their error against
    /// a reference, at equal spp or equal time.
    Compare(CompareArgs),
    /// Render a scene with several strategies at several spp and fit how fast the error falls.
    Converge(ConvergeArgs),
}

/// How points and directions are sampled: a preset, or the two axes separately.
#[derive(Debug, Clone, Args)]
pub struct StrategyArgs {
    /// Named strategy: independent (= independent + uniform), stratified (= stratified +
    /// uniform), importance (= independent + phong), combined (= stratified + phong). Cannot
    /// be combined with a --sampler or --directions that disagrees with it.
    #[arg(long, value_enum)]
    pub strategy: Option<Strategy>,
    /// Where sample points come from: independent (i.i.d. uniform) or stratified (jittered
    /// strata per dimension; square spp such as 16, 64, 256 stratify best in 2D, a prime spp
    /// gives N×1 slabs). Default: stratified.
    #[arg(long, value_enum)]
    pub sampler: Option<SamplerKind>,
    /// How bounce directions are chosen: uniform (hemisphere), cosine (cosine-weighted) or
    /// phong (diffuse/Phong lobes by albedo, mixture pdf). Default: phong.
    #[arg(long, value_enum)]
    pub directions: Option<Directions>,
}

impl StrategyArgs {
    /// The (sampler, directions) pair the flags ask for; an error if they conflict.
    pub fn resolve(&self) -> Result<(SamplerKind, Directions)> {
        let (ds, dd) = Strategy::Combined.axes();
        match self.strategy {
            None => Ok((self.sampler.unwrap_or(ds), self.directions.unwrap_or(dd))),
            Some(st) => {
                let (s, d) = st.axes();
                if self.sampler.is_some_and(|x| x != s) {
                    return Err(Error::Settings(format!(
                        "--strategy {st} uses --sampler {s}, not --sampler {}",
                        self.sampler.unwrap()
                    )));
                }
                if self.directions.is_some_and(|x| x != d) {
                    return Err(Error::Settings(format!(
                        "--strategy {st} uses --directions {d}, not --directions {}",
                        self.directions.unwrap()
                    )));
                }
                Ok((s, d))
            }
        }
    }
}

/// `vrpt render`.
#[derive(Debug, Clone, Args)]
pub struct RenderArgs {
    /// The scene: an .obj file, a scene.toml, or a folder holding a scene.toml.
    pub scene: PathBuf,
    /// Output image: .png (tone-mapped sRGB) or .exr (linear RGB with metadata).
    /// Default: SCENE-NAME.png in the current folder.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
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
    /// lighting, ... (default: scene.toml's, else 8). Russian roulette ends paths earlier,
    /// without bias.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub max_depth: Option<u32>,
    /// Seed of every random number: the same seed gives the same image.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Index of the first sample: renders of samples 0..N and N..2N (same seed) merge into one
    /// of 2N samples.
    #[arg(long, default_value_t = 0)]
    pub first_sample: u32,
    /// Stop at the end of the first whole pass that finishes after this many seconds (the spp
    /// reached is printed and recorded); --spp is then the most it renders.
    #[arg(long, value_name = "SECONDS", value_parser = positive_seconds, allow_negative_numbers = true)]
    pub time_limit: Option<f64>,
    /// Samples per pixel per pass, the unit of stratification (default: all of --spp in one
    /// pass, or 16 with --time-limit).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub pass_spp: Option<u32>,
    /// Worker threads (default: all cores). The image does not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
    #[command(flatten)]
    pub strategy: StrategyArgs,
    /// Exposure for the PNG, in stops: pixels are scaled by 2^EXPOSURE before tone mapping.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// Also write the per-pixel variance of the mean to this EXR.
    #[arg(long, value_name = "EXR")]
    pub variance: Option<PathBuf>,
    /// No progress bar and no statistics (errors and warnings still print).
    #[arg(short, long)]
    pub quiet: bool,
}

fn positive_seconds(s: &str) -> std::result::Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x > 0.0 && x.is_finite() => Ok(x),
        _ => Err(format!("'{s}' is not a positive number of seconds")),
    }
}

/// A comma-separated list of strategies (one flag value).
#[derive(Clone, Debug, PartialEq)]
pub struct StrategyList(pub Vec<StrategySpec>);

/// A comma-separated list of sample counts (one flag value).
#[derive(Clone, Debug, PartialEq)]
pub struct SppList(pub Vec<u32>);

fn strategy_list(s: &str) -> std::result::Result<StrategyList, String> {
    if s.trim() == "all" {
        return Ok(StrategyList(StrategySpec::all_pairs()));
    }
    s.split(',')
        .map(StrategySpec::parse)
        .collect::<std::result::Result<_, _>>()
        .map(StrategyList)
}

fn spp_list(s: &str) -> std::result::Result<SppList, String> {
    s.split(',')
        .map(|x| match x.trim().parse::<u32>() {
            Ok(n) if n > 0 => Ok(n),
            _ => Err(format!("'{x}' is not a positive sample count")),
        })
        .collect::<std::result::Result<_, _>>()
        .map(SppList)
}

/// `vrpt merge`.
#[derive(Debug, Clone, Args)]
pub struct MergeArgs {
    /// The EXR renders to merge (at least two).
    #[arg(required = true, num_args = 2..)]
    pub inputs: Vec<PathBuf>,
    /// The merged EXR.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// `vrpt diff`.
#[derive(Debug, Clone, Args)]
pub struct DiffArgs {
    /// The image to judge (EXR).
    pub image: PathBuf,
    /// The reference (EXR).
    pub reference: PathBuf,
    /// Write a false-colour map of the per-pixel relative squared error to this PNG.
    #[arg(long, value_name = "PNG")]
    pub error_map: Option<PathBuf>,
}

/// Options shared by `compare` and `converge`.
#[derive(Debug, Clone, Args)]
pub struct ExperimentArgs {
    /// The scene: an .obj file, a scene.toml, or a folder holding a scene.toml.
    pub scene: PathBuf,
    /// The converged reference (an EXR from `vrpt render` or `vrpt merge`); its size and max
    /// depth are used, and its scene hash must match the scene.
    #[arg(long)]
    pub reference: PathBuf,
    /// Strategies, comma-separated: independent, stratified, importance, combined, or
    /// SAMPLER+DIRECTIONS (e.g. stratified+cosine); `all` for all six pairs.
    #[arg(long, value_parser = strategy_list, default_value = "independent,stratified,importance,combined")]
    pub strategies: StrategyList,
    /// Independent runs per strategy (seeds SEED, SEED+1, …).
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(2..))]
    pub runs: u32,
    /// Seed of the first run.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
    /// Write the results as CSV to this file.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Write the results as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
}

/// `vrpt compare`.
#[derive(Debug, Clone, Args)]
pub struct CompareArgs {
    #[command(flatten)]
    pub common: ExperimentArgs,
    /// Samples per pixel of each run (with --equal-time: per pass).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: u32,
    /// Give each run of each strategy this many seconds instead of a fixed spp (whole passes
    /// of --spp samples).
    #[arg(long, value_name = "SECONDS", value_parser = positive_seconds, allow_negative_numbers = true)]
    pub equal_time: Option<f64>,
    /// Write a PNG grid: per strategy its first run's image and error map.
    #[arg(long, value_name = "PNG")]
    pub grid: Option<PathBuf>,
    /// Exposure of the images in the grid, in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
}

/// `vrpt converge`.
#[derive(Debug, Clone, Args)]
pub struct ConvergeArgs {
    #[command(flatten)]
    pub common: ExperimentArgs,
    /// Sample counts, comma-separated; each is rendered from scratch.
    #[arg(long, value_parser = spp_list, default_value = "1,4,16,64,256")]
    pub spp: SppList,
    /// Write the log-log plot of MSE against spp (.svg or .png); may be given twice.
    #[arg(long, value_name = "FILE")]
    pub plot: Vec<PathBuf>,
}

/// Run a parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render(args) => run_render(&args),
        Command::Merge(args) => run_merge(&args),
        Command::Diff(args) => run_diff(&args),
        Command::Compare(args) => run_compare(&args),
        Command::Converge(args) => run_converge(&args),
    }
}

fn warn(msg: &str) {
    eprintln!("warning: {msg}");
}

/// Render settings from flags over scene.toml defaults over built-in defaults.
pub fn render_settings(args: &RenderArgs, scene: &Scene) -> Result<RenderSettings> {
    let (sampler, directions) = args.strategy.resolve()?;
    let d = &scene.defaults;
    Ok(RenderSettings {
        width: args.width.or(d.width).unwrap_or(DEFAULT_WIDTH),
        height: args.height.or(d.height).unwrap_or(DEFAULT_HEIGHT),
        spp: args.spp.or(d.spp).unwrap_or(DEFAULT_SPP),
        first_sample: args.first_sample,
        max_depth: args.max_depth.or(d.max_depth).unwrap_or(DEFAULT_MAX_DEPTH),
        seed: args.seed,
        sampler,
        directions,
        threads: args.threads.map(|t| t as usize),
    })
}

/// The metadata vrpt records in every EXR it writes.
pub fn metadata(
    scene: &Scene,
    s: &RenderSettings,
    stats: &RenderStats,
) -> BTreeMap<String, String> {
    let strategy = Strategy::from_axes(s.sampler, s.directions).map_or("custom", |x| x.name());
    [
        ("scene", scene.source.display().to_string()),
        ("scene_hash", format!("{:016x}", scene.hash)),
        ("width", s.width.to_string()),
        ("height", s.height.to_string()),
        ("spp", s.spp.to_string()),
        ("first_sample", s.first_sample.to_string()),
        ("seed", s.seed.to_string()),
        ("sampler", s.sampler.to_string()),
        ("directions", s.directions.to_string()),
        ("strategy", strategy.to_string()),
        ("max_depth", s.max_depth.to_string()),
        (
            "render_seconds",
            format!("{:.6}", stats.elapsed.as_secs_f64()),
        ),
        ("nonfinite_samples", stats.nonfinite.to_string()),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect()
}

fn default_output(scene_path: &Path) -> PathBuf {
    let stem = if scene_path.is_dir() {
        scene_path.file_name()
    } else {
        scene_path.file_stem()
    };
    let stem = stem.map_or("render".into(), |s| s.to_string_lossy().into_owned());
    let stem = if stem == "scene" {
        "render".to_string()
    } else {
        stem
    };
    PathBuf::from(format!("{stem}.png"))
}

/// Check before a long render that `path` can be written: a known image format, an existing
/// folder.
fn check_output(path: &Path) -> Result<()> {
    Format::from_path(path)?;
    check_output_any(path)
}

fn run_render(args: &RenderArgs) -> Result<()> {
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(&args.scene));
    check_output(&output)?;
    if let Some(v) = &args.variance {
        if Format::from_path(v)? != Format::Exr {
            return Err(Error::Settings(format!(
                "--variance {}: the variance image must be an .exr",
                v.display()
            )));
        }
        check_output(v)?;
    }
    let scene = scene::load(&args.scene)?;
    for w in &scene.warnings {
        warn(w);
    }
    let settings = render_settings(args, &scene)?;
    let plan = PassPlan {
        pass_spp: args
            .pass_spp
            .or(args.time_limit.map(|_| 16.min(settings.spp))),
        time_limit: args.time_limit.map(Duration::from_secs_f64),
    };
    let show_progress = !args.quiet && std::io::stderr().is_terminal();
    let bar = if show_progress {
        let passes = settings.spp.div_ceil(plan.pass_spp.unwrap_or(settings.spp)) as u64;
        let bar =
            indicatif::ProgressBar::new(settings.width as u64 * settings.height as u64 * passes);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:40} {percent}% ETA {eta}",
            )
            .expect("static template"),
        );
        Some(bar)
    } else {
        None
    };
    let progress: &dyn Progress = match &bar {
        Some(b) => b,
        None => &NoProgress,
    };
    let (film, stats, reached) = render_passes(&scene, &settings, &plan, progress)?;
    let settings = RenderSettings {
        spp: reached,
        ..settings
    };
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let mut meta = metadata(&scene, &settings, &stats);
    if let Some(p) = plan.pass_spp {
        meta.insert("pass_spp".into(), p.to_string());
    }
    if let Some(t) = args.time_limit {
        meta.insert("time_limit_seconds".into(), t.to_string());
    }
    let mean = film.mean_image();
    match Format::from_path(&output)? {
        // EXRs carry the variance of the mean too, so they can be merged and compared exactly
        Format::Exr => write_exr(
            &output,
            film.width,
            film.height,
            &mean,
            Some(&film.variance_image()),
            &meta,
        )?,
        Format::Png => write_image(
            &output,
            film.width,
            film.height,
            &mean,
            &meta,
            args.exposure,
        )?,
    }
    if let Some(v) = &args.variance {
        let mut vmeta = meta.clone();
        vmeta.insert("image".into(), "variance of the mean".into());
        write_exr(
            v,
            film.width,
            film.height,
            &film.variance_image(),
            None,
            &vmeta,
        )?;
    }
    if stats.nonfinite > 0 {
        warn(&format!(
            "{} non-finite radiance samples were dropped (not written into the image)",
            stats.nonfinite
        ));
    }
    if !args.quiet {
        eprintln!(
            "{}: {} triangles, BVH built in {:.1} ms ({:.1} KiB)",
            scene.source.display(),
            scene.triangle_count(),
            scene.accel.build_time.as_secs_f64() * 1e3,
            scene.accel.memory_bytes() as f64 / 1024.0
        );
        eprintln!(
            "rendered {}x{} at {} spp ({} + {}, max depth {}) in {:.3} s: {:.3} M samples/s, {:.2} Mrays/s",
            settings.width,
            settings.height,
            settings.spp,
            settings.sampler,
            settings.directions,
            settings.max_depth,
            stats.elapsed.as_secs_f64(),
            stats.samples_per_second() / 1e6,
            stats.mrays_per_second()
        );
        eprintln!(
            "rays: {} ({} camera, {} bounce; {:.2} per sample)",
            stats.rays,
            stats.samples,
            stats.rays - stats.samples,
            stats.rays as f64 / stats.samples.max(1) as f64
        );
        eprintln!("wrote {}", output.display());
    }
    Ok(())
}

fn experiment_bar(quiet: bool, total: u64) -> Option<indicatif::ProgressBar> {
    if quiet || !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = indicatif::ProgressBar::new(total);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:30} {percent}% ETA {eta} {msg}",
        )
        .expect("static template"),
    );
    Some(bar)
}

fn run_merge(args: &MergeArgs) -> Result<()> {
    check_output(&args.output)?;
    if Format::from_path(&args.output)? != Format::Exr {
        return Err(Error::Settings(format!(
            "-o {}: a merge is written as .exr",
            args.output.display()
        )));
    }
    let images = args
        .inputs
        .iter()
        .map(|p| read_exr(p))
        .collect::<Result<Vec<_>>>()?;
    let names: Vec<String> = args
        .inputs
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    let m = merge(&images, &names)?;
    write_exr(
        &args.output,
        m.width,
        m.height,
        &m.pixels,
        m.variance.as_deref(),
        &m.metadata,
    )?;
    eprintln!(
        "merged {} renders into {} ({} spp)",
        images.len(),
        args.output.display(),
        m.metadata["spp"]
    );
    Ok(())
}

fn run_diff(args: &DiffArgs) -> Result<()> {
    let a = read_exr(&args.image)?;
    let r = read_exr(&args.reference)?;
    if (a.width, a.height) != (r.width, r.height) {
        return Err(Error::Settings(format!(
            "{} is {}×{} but {} is {}×{}",
            args.image.display(),
            a.width,
            a.height,
            args.reference.display(),
            r.width,
            r.height
        )));
    }
    if let Some(p) = &args.error_map {
        check_output(p)?;
    }
    let m = metrics(&a.pixels, &r.pixels);
    println!("MSE                {:.6e}", m.mse);
    println!("relMSE (eps 0.01)  {:.6e}", m.rel_mse);
    println!("RMSE               {:.6e}", m.rmse);
    println!("MAE                {:.6e}", m.mae);
    println!("mean signed error  {:+.6e}", m.mean_signed_error);
    if let Some(v) = &a.variance {
        let mean_var =
            v.iter().map(|p| (p.x + p.y + p.z) as f64).sum::<f64>() / (3 * v.len()) as f64;
        println!("variance of mean   {mean_var:.6e}");
        let z = bias_z_scores(&a.pixels, v, &r.pixels, r.variance.as_deref());
        let (mut sum_d, mut sum_v, mut max_z) = (0.0f64, 0.0f64, 0.0f64);
        for i in 0..a.pixels.len() {
            for c in 0..3 {
                sum_d += (a.pixels[i][c] - r.pixels[i][c]) as f64;
                sum_v += (v[i][c] + r.variance.as_ref().map_or(0.0, |rv| rv[i][c])) as f64;
                max_z = max_z.max((z[i][c] as f64).abs());
            }
        }
        if sum_v > 0.0 {
            println!("bias z (image)     {:+.3}", sum_d / sum_v.sqrt());
        }
        println!("max |z| (pixel)    {max_z:.3}");
    }
    if let Some(p) = &args.error_map {
        let map = relative_error_map(&a.pixels, &r.pixels);
        let (lo, hi) = error_scale(&[&map]);
        let rgb: Vec<u8> = false_colour(&map, lo, hi).into_iter().flatten().collect();
        write_png_rgb8(p, a.width, a.height, &rgb)?;
        eprintln!(
            "wrote {} (relative squared error, log scale {lo:.1e}..{hi:.1e})",
            p.display()
        );
    }
    Ok(())
}

/// Scene, reference and the settings both experiments share.
fn experiment_setup(a: &ExperimentArgs) -> Result<(Scene, RgbImage, ExperimentSettings)> {
    let scene = scene::load(&a.scene)?;
    for w in &scene.warnings {
        warn(w);
    }
    let reference = read_exr(&a.reference)?;
    let max_depth = match reference.metadata.get("max_depth") {
        Some(d) => d.parse().map_err(|_| {
            Error::Settings(format!(
                "{}: max_depth '{d}' is not a number",
                a.reference.display()
            ))
        })?,
        None => scene.defaults.max_depth.unwrap_or(DEFAULT_MAX_DEPTH),
    };
    let s = ExperimentSettings {
        width: reference.width,
        height: reference.height,
        max_depth,
        seed: a.seed,
        runs: a.runs,
        threads: a.threads.map(|t| t as usize),
    };
    crate::analysis::experiments::check_reference(&scene, &reference, &s)?;
    for p in [&a.csv, &a.json].into_iter().flatten() {
        check_output_any(p)?;
    }
    Ok((scene, reference, s))
}

/// Check that `path` can be written: its folder exists and it is not a folder.
fn check_output_any(path: &Path) -> Result<()> {
    let err = |message: String| Error::Write {
        path: path.to_path_buf(),
        message,
    };
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            return Err(err(format!("folder {} does not exist", dir.display())));
        }
    }
    if path.is_dir() {
        return Err(err("is a folder".into()));
    }
    Ok(())
}

fn write_text(path: &Path, text: &str) -> Result<()> {
    crate::image_io::write_bytes(path, text.as_bytes())
}

fn json<T: serde::Serialize>(v: &T) -> String {
    serde_json::to_string_pretty(v).expect("plain data serializes")
}

/// The comparison as a table (what `vrpt compare` prints).
pub fn compare_table(c: &Comparison) -> String {
    let mut s = format!(
        "{:<22} {:>7} {:>9} {:>11} {:>11} {:>11} {:>8} {:>8} {:>10} {:>10}\n",
        "strategy",
        "spp",
        "time s",
        "MSE",
        "relMSE",
        "variance",
        "bias t",
        "bias p",
        "MSE red.",
        "efficiency"
    );
    for r in &c.rows {
        s += &format!(
            "{:<22} {:>7.1} {:>9.3} {:>11.4e} {:>11.4e} {:>11.4e} {:>+8.2} {:>8.3} {:>9.2}x {:>9.2}x\n",
            r.strategy, r.spp, r.seconds, r.mse, r.rel_mse, r.variance, r.bias_t, r.bias_p, r.mse_reduction, r.efficiency
        );
    }
    s += &format!(
        "(MSE reduction and efficiency 1/(MSE·time) relative to {}; means over {} runs",
        c.baseline,
        c.rows.first().map_or(0, |r| r.runs)
    );
    if let Some(v) = c.reference_variance {
        s += &format!("; the reference's own variance, {v:.3e}, is a floor under every MSE");
    }
    s += ")\n";
    s
}

fn run_compare(args: &CompareArgs) -> Result<()> {
    let a = &args.common;
    let (scene, reference, s) = experiment_setup(a)?;
    if let Some(g) = &args.grid {
        check_output(g)?;
    }
    let strategies: Vec<StrategySpec> = a.strategies.0.clone();
    let bar = experiment_bar(a.quiet, strategies.len() as u64 * a.runs as u64);
    let progress: &dyn ExperimentProgress = match &bar {
        Some(b) => b,
        None => &Silent,
    };
    let c = compare(
        &scene,
        &reference,
        &strategies,
        args.spp,
        args.equal_time.map(Duration::from_secs_f64),
        &s,
        progress,
    )?;
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    print!("{}", compare_table(&c));
    if let Some(p) = &a.csv {
        let mut t = String::from(
            "strategy,runs,spp,seconds,mse,rel_mse,rmse,mae,variance,bias_t,bias_p,mse_reduction,efficiency\n",
        );
        for r in &c.rows {
            t += &format!(
                "{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                r.strategy,
                r.runs,
                r.spp,
                r.seconds,
                r.mse,
                r.rel_mse,
                r.rmse,
                r.mae,
                r.variance,
                r.bias_t,
                r.bias_p,
                r.mse_reduction,
                r.efficiency
            );
        }
        write_text(p, &t)?;
    }
    if let Some(p) = &a.json {
        write_text(p, &json(&c.rows))?;
    }
    if let Some(p) = &args.grid {
        let maps: Vec<Vec<f64>> = c
            .images
            .iter()
            .map(|img| relative_error_map(img, &reference.pixels))
            .collect();
        let rows: Vec<GridRow> = c
            .rows
            .iter()
            .zip(&c.images)
            .zip(&maps)
            .map(|((r, img), m)| GridRow {
                label: format!("{}  {:.0} spp  MSE {:.2e}", r.strategy, r.spp, r.mse),
                image: img,
                error: m,
            })
            .collect();
        write_image_grid(
            p,
            s.width,
            s.height,
            &rows,
            args.exposure,
            "rel. error² (log)",
        )?;
    }
    Ok(())
}

/// The sweep as a table of points and slopes (what `vrpt converge` prints).
pub fn converge_table(c: &Convergence) -> String {
    let mut s = format!(
        "{:<22} {:>7} {:>11} {:>11} {:>9}\n",
        "strategy", "spp", "MSE", "relMSE", "time s"
    );
    for p in &c.points {
        s += &format!(
            "{:<22} {:>7} {:>11.4e} {:>11.4e} {:>9.3}\n",
            p.strategy, p.spp, p.mse, p.rel_mse, p.seconds
        );
    }
    s += "fitted slopes of log error against log spp:\n";
    for sl in &c.slopes {
        s += &format!(
            "{:<22} MSE {:+.3}   relMSE {:+.3}\n",
            sl.strategy, sl.mse_slope, sl.rel_mse_slope
        );
    }
    s
}

fn run_converge(args: &ConvergeArgs) -> Result<()> {
    let a = &args.common;
    let (scene, reference, s) = experiment_setup(a)?;
    for p in &args.plot {
        check_output_any(p)?;
        let ok = p
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("svg") || e.eq_ignore_ascii_case("png"));
        if !ok {
            return Err(Error::Write {
                path: p.clone(),
                message: "a plot is written as .svg or .png".into(),
            });
        }
    }
    let spps = &args.spp.0;
    if spps.len() < 2 {
        return Err(Error::Settings(
            "--spp needs at least two sample counts".into(),
        ));
    }
    let total =
        a.strategies.0.len() as u64 * a.runs as u64 * spps.iter().map(|&x| x as u64).sum::<u64>();
    let bar = experiment_bar(a.quiet, total);
    let progress: &dyn ExperimentProgress = match &bar {
        Some(b) => b,
        None => &Silent,
    };
    let c = converge(&scene, &reference, &a.strategies.0, spps, &s, progress)?;
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    print!("{}", converge_table(&c));
    if let Some(p) = &a.csv {
        let mut t = String::from("strategy,spp,mse,rel_mse,seconds\n");
        for q in &c.points {
            t += &format!(
                "{},{},{},{},{}\n",
                q.strategy, q.spp, q.mse, q.rel_mse, q.seconds
            );
        }
        write_text(p, &t)?;
    }
    if let Some(p) = &a.json {
        write_text(p, &json(&c))?;
    }
    let name = scene
        .source
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    for p in &args.plot {
        write_convergence_plot(
            p,
            &c,
            &format!("{name}: MSE against spp ({} runs each)", s.runs),
        )?;
    }
    Ok(())
}
