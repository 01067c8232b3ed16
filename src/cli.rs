//! The command line (the binary's side): argument definitions (clap), and for each command the
//! calls into the library, the progress bars and the printing. Errors come back to `main` as
//! one line.

use clap::{Args, Parser, Subcommand};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};
use vrpt::analysis::experiments::{
    compare, converge, write_csv, ExperimentProgress, ExperimentSettings, Silent,
};
use vrpt::analysis::merge::{merge, MergeInput};
use vrpt::analysis::metrics::{image_bias, mean_variance, metrics, region_metrics, Region};
use vrpt::analysis::plots::{
    convergence_svg, write_comparison_grid, write_convergence_plot, write_error_map,
};
use vrpt::analysis::report::{number, Column, Report, Table};
use vrpt::bsdf::Directions;
use vrpt::error::{Error, Result};
use vrpt::image_io::{check_image_path, check_writable, read_exr, write_bytes, write_exr, Format};
use vrpt::lights::LightStrategy;
use vrpt::output::{parse_shard, write_render, RenderMetadata};
use vrpt::render::{render_passes, NoProgress, PassPlan, Progress, RenderSettings};
use vrpt::sampler::SamplerKind;
use vrpt::scene::{self, Scene};
use vrpt::strategy::{Preset, Strategy};

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

/// How points, directions and lights are sampled: a preset, or the axes separately.
#[derive(Debug, Clone, Args)]
pub struct StrategyArgs {
    /// Named strategy (SAMPLER/DIRECTIONS/LIGHTS): independent = independent/uniform/bsdf,
    /// stratified = stratified/uniform/bsdf, importance = independent/phong/bsdf, combined =
    /// stratified/phong/bsdf, nee = stratified/phong/nee, mis = stratified/phong/mis (the
    /// default). Cannot be combined with a --sampler, --directions or --lights that disagrees
    /// with it.
    #[arg(long, value_enum)]
    pub strategy: Option<Preset>,
    /// Where sample points come from: independent (i.i.d. uniform), stratified (jittered
    /// strata per dimension; square spp such as 16, 64, 256 stratify best in 2D, a prime spp
    /// gives N×1 slabs) or sobol (Owen-scrambled Sobol points, all dimensions stratified
    /// jointly; powers of two stratify best). Default: stratified.
    #[arg(long, value_enum)]
    pub sampler: Option<SamplerKind>,
    /// How bounce directions are chosen: uniform (hemisphere), cosine (cosine-weighted) or
    /// phong (diffuse/Phong lobes by albedo, mixture pdf). Default: phong.
    #[arg(long, value_enum)]
    pub directions: Option<Directions>,
    /// How light is found at each vertex: bsdf (only when a sampled ray hits an emitter), nee
    /// (sample a light and trace a shadow ray at every vertex) or mis (both, weighted by the
    /// power heuristic). Default: mis.
    #[arg(long, value_enum)]
    pub lights: Option<LightStrategy>,
}

impl StrategyArgs {
    /// The strategy the flags ask for; an error if a flag contradicts the preset.
    pub fn resolve(&self) -> Result<Strategy> {
        let Some(preset) = self.strategy else {
            let d = Strategy::default();
            return Ok(Strategy {
                sampler: self.sampler.unwrap_or(d.sampler),
                directions: self.directions.unwrap_or(d.directions),
                lights: self.lights.unwrap_or(d.lights),
            });
        };
        let st = preset.strategy();
        let conflict = |flag: &str, uses: String, asked: String| {
            Error::Settings(format!(
                "--strategy {preset} uses --{flag} {uses}, not --{flag} {asked}"
            ))
        };
        if let Some(x) = self.sampler.filter(|&x| x != st.sampler) {
            return Err(conflict("sampler", st.sampler.to_string(), x.to_string()));
        }
        if let Some(x) = self.directions.filter(|&x| x != st.directions) {
            return Err(conflict(
                "directions",
                st.directions.to_string(),
                x.to_string(),
            ));
        }
        if let Some(x) = self.lights.filter(|&x| x != st.lights) {
            return Err(conflict("lights", st.lights.to_string(), x.to_string()));
        }
        Ok(st)
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
    /// Render only shard I of N (I from 0): the samples ⌊I·spp/N⌋ .. ⌊(I+1)·spp/N⌋ of the image,
    /// same seed, same passes. `vrpt merge` of all N shards equals one render of all the
    /// samples; each shard alone is an unbiased estimate. For job arrays on clusters
    /// (examples/slurm, examples/kubernetes).
    #[arg(long, value_name = "I/N", value_parser = parse_shard, conflicts_with_all = ["time_limit", "first_sample"])]
    pub shard: Option<(u32, u32)>,
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
    /// Also report where the time went: scene load and BVH build, and the share of the render
    /// spent in BVH traversal against shading and sampling (one ray in 16 is timed, which slows
    /// the render by about 1%).
    #[arg(long, conflicts_with = "quiet")]
    pub stats: bool,
}

fn positive_seconds(s: &str) -> std::result::Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x > 0.0 && x.is_finite() => Ok(x),
        _ => Err(format!("'{s}' is not a positive number of seconds")),
    }
}

/// A comma-separated list given as one flag value (a newtype, so clap takes it as one value).
#[derive(Clone, Debug, PartialEq)]
pub struct List<T>(pub Vec<T>);

/// A comma-separated list of strategies, or `all`.
fn strategy_list(s: &str) -> std::result::Result<List<Strategy>, String> {
    if s.trim() == "all" {
        return Ok(List(Strategy::all()));
    }
    s.split(',')
        .map(Strategy::parse)
        .collect::<std::result::Result<_, _>>()
        .map(List)
}

/// A comma-separated list of positive sample counts.
fn spp_list(s: &str) -> std::result::Result<List<u32>, String> {
    s.split(',')
        .map(|x| match x.trim().parse::<u32>() {
            Ok(n) if n > 0 => Ok(n),
            _ => Err(format!("'{x}' is not a positive sample count")),
        })
        .collect::<std::result::Result<_, _>>()
        .map(List)
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

/// Parts of the image to report on their own.
#[derive(Debug, Clone, Args)]
pub struct RegionArgs {
    /// A region whose metrics are also reported on their own: X,Y,W,H in pixels (rows from the
    /// top), or NAME=X,Y,W,H. May be given several times.
    #[arg(long, value_name = "X,Y,W,H", value_parser = Region::parse)]
    pub region: Vec<Region>,
    /// A file of named regions, one `NAME X,Y,W,H` per line (`#` starts a comment), e.g.
    /// scenes/glossy-plates/regions.txt.
    #[arg(long, value_name = "FILE")]
    pub regions: Option<PathBuf>,
}

impl RegionArgs {
    /// The regions of the flags and the file, checked against a `width × height` image.
    fn resolve(&self, width: u32, height: u32) -> Result<Vec<Region>> {
        let mut all = self.region.clone();
        if let Some(p) = &self.regions {
            let text = vrpt::error::read_text(p)?;
            all.extend(Region::parse_list(&text).map_err(|message| Error::Scene {
                path: p.clone(),
                message,
            })?);
        }
        for r in &all {
            r.check(width, height).map_err(Error::Settings)?;
        }
        Ok(all)
    }
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
    /// Write a self-contained HTML report to this file: both images as HDR data with exposure,
    /// A/B slider, false-colour error views with their scale, pixel inspection and the metrics.
    #[arg(long, value_name = "HTML")]
    pub report: Option<PathBuf>,
    #[command(flatten)]
    pub regions: RegionArgs,
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
    /// Strategies, comma-separated (default: the six presets).
    #[arg(long, value_parser = strategy_list, default_value = "independent,stratified,importance,combined,nee,mis",
          long_help = Strategy::list_help())]
    pub strategies: List<Strategy>,
    /// Independent runs per strategy.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(2..))]
    pub runs: u32,
    /// Seed of the first run. The runs take the first RUNS seeds from SEED upward that the
    /// reference does not hold (its seed, or its merged inputs' seeds), so no run reuses the
    /// reference's random numbers.
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
    /// Write a self-contained HTML report to this file: the reference and each strategy's
    /// first run as HDR images with exposure, A/B slider, false-colour error views with their
    /// scale and pixel inspection, the sortable metrics, and the settings of the run.
    #[arg(long, value_name = "HTML")]
    pub report: Option<PathBuf>,
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
    #[command(flatten)]
    pub regions: RegionArgs,
}

/// `vrpt converge`.
#[derive(Debug, Clone, Args)]
pub struct ConvergeArgs {
    #[command(flatten)]
    pub common: ExperimentArgs,
    /// Sample counts, comma-separated; each is rendered from scratch.
    #[arg(long, value_parser = spp_list, default_value = "1,4,16,64,256")]
    pub spp: List<u32>,
    /// Write the log-log plot of MSE against spp (.svg or .png); may be given twice.
    #[arg(long, value_name = "FILE")]
    pub plot: Vec<PathBuf>,
}

/// Run a parsed command line; the exit code of a command that ran (130: a render was
/// interrupted and wrote the samples taken).
pub fn run(cli: Cli) -> Result<ExitCode> {
    let ok = |r: Result<()>| r.map(|()| ExitCode::SUCCESS);
    match cli.command {
        Command::Render(args) => run_render(&args),
        Command::Merge(args) => ok(run_merge(&args)),
        Command::Diff(args) => ok(run_diff(&args)),
        Command::Compare(args) => ok(run_compare(&args)),
        Command::Converge(args) => ok(run_converge(&args)),
    }
}

/// Print to stdout; a closed pipe (`vrpt diff … | head -1`) ends the output quietly.
fn out(text: &str) {
    use std::io::Write;
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}

fn warn(msg: &str) {
    eprintln!("warning: {msg}");
}

/// A progress bar, when stderr is a terminal and the user did not ask for quiet.
struct Bar(indicatif::ProgressBar);

impl Bar {
    fn new(quiet: bool, total: u64, template: &str) -> Option<Bar> {
        if quiet || !std::io::stderr().is_terminal() {
            return None;
        }
        let bar = indicatif::ProgressBar::new(total);
        bar.set_style(indicatif::ProgressStyle::with_template(template).expect("static template"));
        Some(Bar(bar))
    }
}

impl Progress for Bar {
    fn advance(&self, pixels: u64) {
        self.0.inc(pixels);
    }
}

impl ExperimentProgress for Bar {
    fn finished(&self, label: &str, weight: u64) {
        self.0.set_message(label.to_string());
        self.0.inc(weight);
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}

/// Render settings: flags over scene.toml's defaults over the built-in ones.
fn render_settings(args: &RenderArgs, scene: &Scene) -> Result<RenderSettings> {
    let d = RenderSettings::for_scene(scene);
    Ok(RenderSettings {
        width: args.width.unwrap_or(d.width),
        height: args.height.unwrap_or(d.height),
        spp: args.spp.unwrap_or(d.spp),
        first_sample: args.first_sample,
        max_depth: args.max_depth.unwrap_or(d.max_depth),
        seed: args.seed,
        strategy: args.strategy.resolve()?,
        threads: args.threads.map(|t| t as usize),
        time_traces: args.stats,
    })
}

/// `SCENE-NAME.png` in the current folder (`render.png` for a bare scene.toml).
fn default_output(scene_path: &Path) -> PathBuf {
    let stem = if scene_path.is_dir() {
        scene_path.file_name()
    } else {
        scene_path.file_stem()
    };
    let stem = stem.map_or("render".into(), |s| s.to_string_lossy().into_owned());
    let stem = if stem == "scene" {
        "render".into()
    } else {
        stem
    };
    PathBuf::from(format!("{stem}.png"))
}

fn run_render(args: &RenderArgs) -> Result<ExitCode> {
    crate::GRACEFUL.store(true, std::sync::atomic::Ordering::SeqCst);
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(&args.scene));
    check_image_path(&output)?;
    if let Some(v) = &args.variance {
        if check_image_path(v)? != Format::Exr {
            return Err(Error::Settings(format!(
                "--variance {}: the variance image must be an .exr",
                v.display()
            )));
        }
    }
    let load_start = Instant::now();
    let scene = scene::load(&args.scene)?;
    let load_time = load_start.elapsed();
    for w in &scene.warnings {
        warn(w);
    }
    let settings = render_settings(args, &scene)?;
    let plan = PassPlan {
        pass_spp: args
            .pass_spp
            .or(args.time_limit.map(|_| 16.min(settings.spp))),
        time_limit: args.time_limit.map(Duration::from_secs_f64),
        shard: args.shard,
        stop: Some(&crate::STOP),
    };
    let range = match args.shard {
        Some(s) => vrpt::render::shard_range(settings.spp, s)?,
        None => 0..settings.spp,
    };
    let pixels = settings.width as u64 * settings.height as u64;
    let bar = Bar::new(
        args.quiet,
        pixels * range.len() as u64,
        "{spinner} [{elapsed_precise}] {bar:40} {percent}% ETA {eta}",
    );
    let progress: &dyn Progress = bar.as_ref().map_or(&NoProgress, |b| b);
    let r = render_passes(&scene, &settings, &plan, progress)?;
    drop(bar);
    let (film, stats) = (r.film, r.stats);
    let requested = range.len() as u32;
    let settings = RenderSettings {
        spp: r.spp,
        first_sample: r.first_sample,
        ..settings
    };
    let meta = RenderMetadata {
        pass_spp: plan.pass_spp,
        time_limit_seconds: args.time_limit,
        shard: args.shard,
        requested_spp: (r.spp < requested).then_some(requested as u64),
        interrupted: r.interrupted,
        ..RenderMetadata::new(&scene, &settings, &stats)
    };
    write_render(
        &output,
        &film,
        &meta,
        args.exposure,
        args.variance.as_deref(),
    )?;

    if stats.nonfinite > 0 {
        warn(&format!(
            "{} non-finite radiance samples were dropped (not written into the image)",
            stats.nonfinite
        ));
    }
    if !args.quiet {
        eprint!("{}", stats.summary(&scene, &settings));
        if args.stats {
            eprint!("{}", stats.timing(load_time, scene.accel.build_time));
        }
        eprintln!("wrote {}", output.display());
    }
    if r.interrupted {
        warn(&format!(
            "interrupted: wrote {} with the {} of {requested} spp taken (its metadata says so)",
            output.display(),
            r.spp
        ));
        return Ok(ExitCode::from(130));
    }
    Ok(ExitCode::SUCCESS)
}

fn run_merge(args: &MergeArgs) -> Result<()> {
    if check_image_path(&args.output)? != Format::Exr {
        return Err(Error::Settings(format!(
            "-o {}: a merge is written as .exr",
            args.output.display()
        )));
    }
    let inputs = args
        .inputs
        .iter()
        .map(|p| MergeInput::read(p))
        .collect::<Result<Vec<_>>>()?;
    let (m, meta) = merge(&inputs)?;
    write_exr(&args.output, &m)?;
    eprintln!(
        "merged {} renders into {} ({} spp)",
        inputs.len(),
        args.output.display(),
        meta.spp
    );
    Ok(())
}

/// The largest `|a − b| / max(|a|, |b|)` over pixels and channels (0 where both are 0): how
/// far two images are from equal, e.g. a merge of shards and the render of all their samples
/// (which agree to f32 rounding, a few 1e-7).
fn max_relative_difference(a: &[glam::Vec3], b: &[glam::Vec3]) -> f32 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| (0..3).map(move |c| (x[c], y[c])))
        .map(|(x, y)| {
            let m = x.abs().max(y.abs());
            if m > 0.0 {
                (x - y).abs() / m
            } else {
                0.0
            }
        })
        .fold(0.0, f32::max)
}

fn run_diff(args: &DiffArgs) -> Result<()> {
    let a = read_exr(&args.image)?;
    let r = read_exr(&args.reference)?;
    RenderMetadata::radiance(&a, &args.image)?;
    RenderMetadata::radiance(&r, &args.reference)?;
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
        check_image_path(p)?;
    }
    if let Some(p) = &args.report {
        check_writable(p)?;
    }
    let regions = args.regions.resolve(a.width, a.height)?;
    let m = metrics(&a.pixels, &r.pixels);
    let mut t = format!("MSE                {:.6e}\n", m.mse);
    t += &format!("relMSE (eps 0.01)  {:.6e}\n", m.rel_mse);
    t += &format!("RMSE               {:.6e}\n", m.rmse);
    t += &format!("MAE                {:.6e}\n", m.mae);
    t += &format!("mean signed error  {:+.6e}\n", m.mean_signed_error);
    t += &format!(
        "max relative difference {:.3e}\n",
        max_relative_difference(&a.pixels, &r.pixels)
    );
    if let Some(v) = &a.variance {
        t += &format!("variance of mean   {:.6e}\n", mean_variance(v));
        let b = image_bias(&a.pixels, v, &r.pixels, r.variance.as_deref());
        if let Some(z) = b.z {
            t += &format!("bias z (image)     {z:+.3}\n");
        }
        t += &format!("max |z| (pixel)    {:.3}\n", b.max_pixel_z);
    }
    if !regions.is_empty() {
        t += &format!(
            "{:<22} {:>12} {:>12} {:>12} {:>12}\n",
            "region", "MSE", "relMSE", "RMSE", "MAE"
        );
        for reg in &regions {
            let m = region_metrics(&a.pixels, &r.pixels, a.width, reg);
            t += &format!(
                "{:<22} {:>12.4e} {:>12.4e} {:>12.4e} {:>12.4e}\n",
                reg.name, m.mse, m.rel_mse, m.rmse, m.mae
            );
        }
    }
    out(&t);
    if let Some(p) = &args.report {
        let row = |name: &str, m: &vrpt::analysis::metrics::Metrics| {
            let mut o = serde_json::Map::new();
            o.insert("region".into(), name.into());
            o.insert("mse".into(), number(m.mse));
            o.insert("rel_mse".into(), number(m.rel_mse));
            o.insert("rmse".into(), number(m.rmse));
            o.insert("mae".into(), number(m.mae));
            o.insert("mean_signed_error".into(), number(m.mean_signed_error));
            o
        };
        let mut rows = vec![row("whole image", &m)];
        for reg in &regions {
            rows.push(row(
                &reg.name,
                &region_metrics(&a.pixels, &r.pixels, a.width, reg),
            ));
        }
        let table = Table {
            title: "error against the reference".into(),
            columns: vec![
                Column::text("region", "region"),
                Column::number("mse", "MSE"),
                Column::number("rel_mse", "relMSE"),
                Column::number("rmse", "RMSE"),
                Column::number("mae", "MAE"),
                Column::number("mean_signed_error", "mean signed error"),
            ],
            rows,
            row_key: "region".into(),
        };
        let describe = |img: &vrpt::image_io::RgbImage, path: &Path| {
            RenderMetadata::radiance(img, path)
                .ok()
                .flatten()
                .map_or_else(
                    || format!("{} (no vrpt metadata)", path.display()),
                    |m| {
                        format!(
                            "{} ({} spp, {}, seed {}, scene hash {})",
                            path.display(),
                            m.spp,
                            m.strategy,
                            m.seed.map_or("merged".into(), |s| s.to_string()),
                            m.scene_hash_hex()
                        )
                    },
                )
        };
        let settings = vec![
            ("image".into(), describe(&a, &args.image)),
            ("reference".into(), describe(&r, &args.reference)),
            ("size".into(), format!("{}x{}", a.width, a.height)),
            ("vrpt".into(), env!("CARGO_PKG_VERSION").into()),
        ];
        let name = args
            .image
            .file_name()
            .map_or("image".into(), |n| n.to_string_lossy().into_owned());
        let title = format!(
            "vrpt diff: {} against {}",
            args.image.display(),
            args.reference.display()
        );
        Report::for_diff(&name, &a, &r, table, &title, settings).write(p)?;
        out(&format!("wrote {}\n", p.display()));
    }
    if let Some(p) = &args.error_map {
        let (lo, hi) = write_error_map(p, &a, &r)?;
        out(&format!(
            "wrote {} (relative squared error, log scale {lo:.1e}..{hi:.1e})\n",
            p.display()
        ));
    }
    Ok(())
}

/// Scene, reference and the settings both experiments share; checks the output paths.
fn experiment_setup(
    a: &ExperimentArgs,
) -> Result<(Scene, vrpt::image_io::RgbImage, ExperimentSettings)> {
    for p in [&a.csv, &a.json, &a.report].into_iter().flatten() {
        check_writable(p)?;
    }
    let scene = scene::load(&a.scene)?;
    for w in &scene.warnings {
        warn(w);
    }
    let reference = read_exr(&a.reference)?;
    let s = ExperimentSettings::for_reference(
        &scene,
        &reference,
        &a.reference,
        a.seed,
        a.runs,
        a.threads.map(|t| t as usize),
    )?;
    Ok((scene, reference, s))
}

/// Print an experiment's table; write its rows as CSV and `json` as JSON where asked.
fn report<R: serde::Serialize, J: serde::Serialize>(
    a: &ExperimentArgs,
    table: &str,
    rows: &[R],
    json: &J,
) -> Result<()> {
    out(table);
    if let Some(p) = &a.csv {
        write_csv(p, rows)?;
    }
    if let Some(p) = &a.json {
        let text = serde_json::to_string_pretty(json).expect("plain data serializes");
        write_bytes(p, text.as_bytes())?;
    }
    Ok(())
}

/// How an experiment was made, for its report: scene, scene hash, reference, size, (the caller
/// inserts the spp or time at 4), runs, seeds, strategies, max depth, vrpt version.
fn experiment_settings_list(
    a: &ExperimentArgs,
    scene: &Scene,
    reference: &vrpt::image_io::RgbImage,
    s: &ExperimentSettings,
) -> Vec<(String, String)> {
    let reference_meta = RenderMetadata::radiance(reference, &a.reference)
        .ok()
        .flatten()
        .map_or_else(
            || "no vrpt metadata".into(),
            |m| format!("{} spp, {}", m.spp, m.strategy),
        );
    let strategies: Vec<String> = a.strategies.0.iter().map(|s| s.to_string()).collect();
    vec![
        ("scene".into(), a.scene.display().to_string()),
        ("scene hash".into(), format!("{:016x}", scene.hash)),
        (
            "reference".into(),
            format!("{} ({reference_meta})", a.reference.display()),
        ),
        ("size".into(), format!("{}x{}", s.width, s.height)),
        ("runs".into(), a.runs.to_string()),
        ("seeds".into(), {
            let seeds: Vec<String> = s.run_seeds().iter().map(u64::to_string).collect();
            seeds.join(", ")
        }),
        ("strategies".into(), strategies.join(", ")),
        ("max depth".into(), s.max_depth.to_string()),
        ("vrpt".into(), env!("CARGO_PKG_VERSION").into()),
    ]
}

const EXPERIMENT_BAR: &str = "{spinner} [{elapsed_precise}] {bar:30} {percent}% ETA {eta} {msg}";

fn run_compare(args: &CompareArgs) -> Result<()> {
    let a = &args.common;
    if let Some(g) = &args.grid {
        check_image_path(g)?;
    }
    let (scene, reference, mut s) = experiment_setup(a)?;
    s.regions = args.regions.resolve(s.width, s.height)?;
    let bar = Bar::new(
        a.quiet,
        a.strategies.0.len() as u64 * a.runs as u64,
        EXPERIMENT_BAR,
    );
    let progress: &dyn ExperimentProgress = bar.as_ref().map_or(&Silent, |b| b);
    let c = compare(
        &scene,
        &reference,
        &a.strategies.0,
        args.spp,
        args.equal_time.map(Duration::from_secs_f64),
        &s,
        progress,
    )?;
    drop(bar);
    report(a, &c.table(), &c.rows, &c)?;
    if let Some(p) = &args.grid {
        write_comparison_grid(p, &c, &reference, args.exposure)?;
    }
    if let Some(p) = &a.report {
        // the budget of a run: its settings row and the title's words
        let (key, value, budget) = match args.equal_time {
            Some(t) => (
                "time per run",
                format!("{t} s (passes of {} spp)", args.spp),
                format!("{t} s per run"),
            ),
            None => (
                "spp per run",
                args.spp.to_string(),
                format!("{} spp per run", args.spp),
            ),
        };
        let mut settings = experiment_settings_list(a, &scene, &reference, &s);
        settings.insert(4, (key.into(), value));
        let names: Vec<String> = s.regions.iter().map(|r| r.name.clone()).collect();
        let title = format!(
            "vrpt compare: {}, {budget}, {} runs",
            a.scene.display(),
            a.runs
        );
        Report::for_comparison(&c, &reference, &names, &title, settings)?.write(p)?;
        out(&format!("wrote {}\n", p.display()));
    }
    Ok(())
}

fn run_converge(args: &ConvergeArgs) -> Result<()> {
    let a = &args.common;
    for p in &args.plot {
        check_writable(p)?;
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
    if args.spp.0.len() < 2 {
        return Err(Error::Settings(
            "--spp needs at least two sample counts".into(),
        ));
    }
    let (scene, reference, s) = experiment_setup(a)?;
    let total = a.strategies.0.len() as u64
        * a.runs as u64
        * args.spp.0.iter().map(|&x| x as u64).sum::<u64>();
    let bar = Bar::new(a.quiet, total, EXPERIMENT_BAR);
    let progress: &dyn ExperimentProgress = bar.as_ref().map_or(&Silent, |b| b);
    let c = converge(
        &scene,
        &reference,
        &a.strategies.0,
        &args.spp.0,
        &s,
        progress,
    )?;
    drop(bar);
    report(a, &c.table(), &c.points, &c)?;
    let name = scene
        .source
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    let plot_title = format!("{name}: MSE against spp ({} runs each)", s.runs);
    for p in &args.plot {
        write_convergence_plot(p, &c, &plot_title)?;
    }
    if let Some(p) = &a.report {
        let mut settings = experiment_settings_list(a, &scene, &reference, &s);
        let spps: Vec<String> = args.spp.0.iter().map(u32::to_string).collect();
        settings.insert(4, ("spp".into(), spps.join(", ")));
        let title = format!(
            "vrpt converge: {} ({} runs each)",
            a.scene.display(),
            a.runs
        );
        let svg = convergence_svg(&c, &plot_title)?;
        Report::for_convergence(&c, &reference, &title, settings, svg)?.write(p)?;
        out(&format!("wrote {}\n", p.display()));
    }
    Ok(())
}
