//! The command line (the binary's side): argument definitions (clap), turning them into the
//! library's requests ([`vrpt::commands`]), progress bars, and printing the outcomes. Errors
//! come back to `main` as one line.

use clap::{Args, Parser, Subcommand};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use vrpt::analysis::metrics::Region;
use vrpt::bsdf::Directions;
use vrpt::commands::experiment::{CompareRequest, ConvergeRequest, Experiment, ExperimentRequest};
use vrpt::commands::{diff, merge, render, Written};
use vrpt::error::{Error, Result};
use vrpt::lights::{LightChoice, LightPoints, LightStrategy};
use vrpt::limits::{parse_exposure, parse_seconds, parse_shard};
use vrpt::render::Progress;
use vrpt::sampler::SamplerKind;
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
    /// Merge renders of the same scene and settings (other seeds or sample ranges) into one.
    Merge(merge::MergeRequest),
    /// Print the error metrics of an EXR against a reference EXR; optionally write an error map.
    Diff(DiffArgs),
    /// Compare strategies' error against a reference over runs, at equal spp or equal time.
    Compare(CompareArgs),
    /// Render a scene with several strategies at several spp and fit how fast the error falls.
    Converge(ConvergeArgs),
    /// Draw a sampler's points in the unit square, with their discrepancy and power spectrum.
    Points(vrpt::commands::points::PointsRequest),
    /// Estimate known integrals with each sampler: measured mean and variance against the formulas.
    Integrate(vrpt::commands::integrate::IntegrateRequest),
    /// Test every warp's samples against its integrated pdf: chi-square, p-value and ∫pdf.
    Warptest(vrpt::commands::warptest::WarptestRequest),
    /// Show what path guiding learned at a pixel's first hit, beside the incident radiance there.
    Guide {
        #[command(flatten)]
        request: vrpt::commands::guide::GuideRequest,
        #[command(flatten)]
        strategy: StrategyArgs,
    },
}

/// How points, directions and lights are sampled: a preset, or the axes separately.
#[derive(Debug, Clone, Args)]
pub struct StrategyArgs {
    /// A named strategy; a --sampler, --directions or --lights given too must agree with it.
    #[arg(long, value_enum)]
    pub strategy: Option<Preset>,
    /// Where sample points come from (default: stratified).
    #[arg(long, value_enum)]
    pub sampler: Option<SamplerKind>,
    /// How bounce directions are chosen (default: phong).
    #[arg(long, value_enum)]
    pub directions: Option<Directions>,
    /// How light is found at each vertex (default: mis).
    #[arg(long, value_enum)]
    pub lights: Option<LightStrategy>,
    /// How a point on a light is placed (default: auto).
    #[arg(long, value_enum)]
    pub light_points: Option<LightPoints>,
    /// How the light of a vertex is chosen (default: tree).
    #[arg(long, value_enum)]
    pub light_choice: Option<LightChoice>,
}

impl StrategyArgs {
    /// The strategy the flags ask for; an error if a flag contradicts the preset.
    pub fn resolve(&self) -> Result<Strategy> {
        let axes = (self.sampler, self.directions, self.lights);
        Strategy::from_parts(self.strategy, axes, (self.light_points, self.light_choice))
            .map_err(Error::Settings)
    }
}

/// `vrpt render`.
#[derive(Debug, Clone, Args)]
pub struct RenderArgs {
    /// The scene: an .obj file, a scene.toml, or a folder holding a scene.toml.
    pub scene: PathBuf,
    /// Output: .png (tone-mapped sRGB) or .exr (linear, with metadata); default SCENE-NAME.png.
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
    /// light (default: scene.toml's, else 8).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub max_depth: Option<u32>,
    /// Seed of every random number: the same seed gives the same image.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Index of the first sample: renders of 0..N and N..2N (same seed) merge into one of 2N.
    #[arg(long, default_value_t = 0)]
    pub first_sample: u32,
    /// Stop at the first whole pass that ends after this many seconds (--spp is then a cap).
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds, allow_negative_numbers = true)]
    pub time_limit: Option<f64>,
    /// Samples per pixel per pass, the unit of stratification (default: all, or 16 with
    /// --time-limit, whose passes then double while the time left allows).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub pass_spp: Option<u32>,
    /// Render only shard I of N (from 0): samples ⌊I·spp/N⌋ .. ⌊(I+1)·spp/N⌋; `vrpt merge` of
    /// all N equals one render of all (job arrays: examples/slurm, examples/kubernetes).
    #[arg(long, value_name = "I/N", value_parser = parse_shard, conflicts_with_all = ["time_limit", "first_sample"])]
    pub shard: Option<(u32, u32)>,
    /// Worker threads (default: all cores). The image does not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
    #[command(flatten)]
    pub strategy: StrategyArgs,
    #[command(flatten)]
    pub error: render::ErrorArgs,
    /// Exposure of the PNG, in stops (pixels × 2^EXPOSURE before tone mapping), within ±64.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = parse_exposure)]
    pub exposure: f32,
    /// Also write the per-pixel variance of the mean to this EXR.
    #[arg(long, value_name = "EXR")]
    pub variance: Option<PathBuf>,
    /// No progress bar and no statistics (errors and warnings still print).
    #[arg(short, long)]
    pub quiet: bool,
    /// Also say where the time went: scene load, BVH build, traversal against shading (one ray
    /// in 16 is timed, about 1% slower).
    #[arg(long, conflicts_with = "quiet")]
    pub stats: bool,
}

/// A comma-separated list as one flag value (a newtype, so clap takes it as one value).
#[derive(Clone, Debug, PartialEq)]
pub struct List<T>(pub Vec<T>);

/// A comma-separated list of strategies, or `all`.
fn strategy_list(s: &str) -> std::result::Result<List<Strategy>, String> {
    Strategy::parse_list(s).map(List)
}

/// Parts of the image to report on their own.
#[derive(Debug, Clone, Args)]
pub struct RegionArgs {
    /// A region reported on its own: X,Y,W,H in pixels (rows from the top) or NAME=X,Y,W,H;
    /// repeatable.
    #[arg(long, value_name = "X,Y,W,H", value_parser = Region::parse)]
    pub region: Vec<Region>,
    /// A file of `NAME X,Y,W,H` lines (`#` comments), e.g. scenes/glossy-plates/regions.txt.
    #[arg(long, value_name = "FILE")]
    pub regions: Option<PathBuf>,
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
    /// Write a self-contained HTML report: both images (HDR), error views, metrics.
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
    /// The converged reference EXR (its size and max depth are used; its scene hash must match).
    #[arg(long)]
    pub reference: PathBuf,
    /// Strategies, comma-separated (default: the six presets).
    #[arg(long, value_parser = strategy_list, default_value = "independent,stratified,importance,combined,nee,mis",
          long_help = Strategy::list_help())]
    pub strategies: List<Strategy>,
    /// Independent runs per strategy.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(2..))]
    pub runs: u32,
    /// Seed of the first run: the runs take the first RUNS seeds from SEED up that the
    /// reference does not hold (its seed, a merge's inputs'), so none reuses its samples.
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
    /// Write a self-contained HTML report: the summary, images (HDR), error views, metrics.
    #[arg(long, value_name = "HTML")]
    pub report: Option<PathBuf>,
    #[command(flatten)]
    pub allocation: vrpt::commands::experiment::AllocationArgs,
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
    /// Give each run this many seconds instead of a fixed spp (whole passes of --spp).
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds, allow_negative_numbers = true)]
    pub equal_time: Option<f64>,
    /// Write a PNG grid: per strategy its first run's image and error map.
    #[arg(long, value_name = "PNG")]
    pub grid: Option<PathBuf>,
    /// Exposure of the images in the grid, in stops, within ±64.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = parse_exposure)]
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
    #[arg(long, value_delimiter = ',', default_value = "1,4,16,64,256",
          value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Vec<u32>,
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
        Command::Merge(args) => ok(run_merge(args)),
        Command::Diff(args) => ok(run_diff(args)),
        Command::Compare(args) => ok(run_compare(args)),
        Command::Converge(args) => ok(run_converge(args)),
        Command::Points(r) => ok(vrpt::commands::points::run(&r).map(|o| out(&o.table()))),
        Command::Integrate(r) => ok(vrpt::commands::integrate::run(&r).map(|o| out(&o.table()))),
        Command::Warptest(r) => ok(vrpt::commands::warptest::run(&r).map(|o| out(&o.table()))),
        Command::Guide { request, strategy } => ok(run_guide(request, strategy)),
    }
}

fn run_guide(mut request: vrpt::commands::guide::GuideRequest, s: StrategyArgs) -> Result<()> {
    let directions = s.directions.or(Some(Directions::Guided));
    request.strategy = StrategyArgs { directions, ..s }.resolve()?;
    out(&vrpt::commands::guide::run(&request)?.summary());
    Ok(())
}

/// Print to stdout; a closed pipe (`vrpt diff … | head -1`) ends the output quietly.
fn out(text: &str) {
    use std::io::Write;
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}

/// Print warnings (a scene's) to stderr.
fn warn(msgs: &[String]) {
    msgs.iter().for_each(|m| eprintln!("warning: {m}"));
}

/// Print a command's text, then which files it wrote and what else it says of them.
fn print_outcome(text: &str, written: &[Written]) {
    out(text);
    for w in written {
        match w.note.as_str() {
            "" => out(&format!("wrote {}\n", w.path.display())),
            note => out(&format!("wrote {} ({note})\n", w.path.display())),
        }
    }
}

/// A progress bar, when stderr is a terminal and the user did not ask for quiet.
struct Bar(Option<indicatif::ProgressBar>);

impl Bar {
    fn new(quiet: bool, total: u64, template: &str) -> Bar {
        Bar((!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = indicatif::ProgressBar::new(total);
            bar.set_style(indicatif::ProgressStyle::with_template(template).expect("static"));
            bar
        }))
    }
}

impl Progress for Bar {
    fn advance(&self, units: u64) {
        self.0.as_ref().inspect(|b| b.inc(units));
    }
    fn finished(&self, label: &str) {
        self.0
            .as_ref()
            .inspect(|b| b.set_message(label.to_string()));
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        self.0.as_ref().inspect(|b| b.finish_and_clear());
    }
}

fn run_render(args: &RenderArgs) -> Result<ExitCode> {
    crate::GRACEFUL.store(true, std::sync::atomic::Ordering::SeqCst);
    let job = render::RenderRequest {
        scene: args.scene.clone(),
        output: args.output.clone(),
        width: args.width,
        height: args.height,
        spp: args.spp,
        max_depth: args.max_depth,
        seed: args.seed,
        first_sample: args.first_sample,
        strategy: args.strategy.resolve()?,
        threads: args.threads.map(|t| t as usize),
        time_limit: args.time_limit,
        pass_spp: args.pass_spp,
        shard: args.shard,
        exposure: args.exposure,
        variance: args.variance.clone(),
        time_traces: args.stats,
        stop: Some(&crate::STOP),
        error: args.error.clone(),
    }
    .prepare()?;
    warn(&job.scene.warnings);
    let template = "{spinner} [{elapsed_precise}] {bar:40} {percent}% ETA {eta}";
    let bar = Bar::new(args.quiet, job.pixel_samples(), template);
    let r = job.run(&bar)?;
    drop(bar);
    if !args.quiet {
        let timing = if args.stats { r.timing.as_str() } else { "" };
        eprintln!("{}{timing}wrote {}", r.summary, r.output.display());
    }
    warn(&r.warnings());
    Ok(ExitCode::from(if r.interrupted { 130 } else { 0 }))
}

fn run_merge(req: merge::MergeRequest) -> Result<()> {
    let m = merge::run(&req)?;
    let (n, spp) = (m.inputs, m.spp);
    eprintln!(
        "merged {n} renders into {} ({spp} spp)",
        req.output.display()
    );
    Ok(())
}

fn run_diff(args: DiffArgs) -> Result<()> {
    let d = diff::run(&diff::DiffRequest {
        image: args.image,
        reference: args.reference,
        error_map: args.error_map,
        report: args.report,
        regions: args.regions.region,
        regions_file: args.regions.regions,
    })?;
    print_outcome(&d.table(), &d.written);
    Ok(())
}

/// The library's request for the flags both experiments share.
fn experiment_request(a: ExperimentArgs) -> ExperimentRequest {
    ExperimentRequest {
        scene: a.scene,
        reference: a.reference,
        strategies: a.strategies.0,
        runs: a.runs,
        seed: a.seed,
        threads: a.threads.map(|t| t as usize),
        csv: a.csv,
        json: a.json,
        report: a.report,
        allocation: a.allocation,
    }
}

/// Run a prepared experiment under a progress bar and print its outcome.
fn experiment(quiet: bool, job: impl Experiment) -> Result<()> {
    warn(&job.scene().warnings);
    let template = "{spinner} [{elapsed_precise}] {bar:30} {percent}% ETA {eta} {msg}";
    let bar = Bar::new(quiet, job.work(), template);
    let c = job.run(&bar)?;
    drop(bar);
    print_outcome(&c.table, &c.written);
    Ok(())
}

fn run_compare(args: CompareArgs) -> Result<()> {
    let quiet = args.common.quiet;
    let req = CompareRequest {
        experiment: experiment_request(args.common),
        spp: args.spp,
        equal_time: args.equal_time,
        grid: args.grid,
        exposure: args.exposure,
        regions: args.regions.region,
        regions_file: args.regions.regions,
    };
    experiment(quiet, req.prepare()?)
}

fn run_converge(args: ConvergeArgs) -> Result<()> {
    let quiet = args.common.quiet;
    let req = ConvergeRequest {
        experiment: experiment_request(args.common),
        spp: args.spp,
        plots: args.plot,
    };
    experiment(quiet, req.prepare()?)
}
