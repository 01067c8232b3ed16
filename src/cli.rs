//! The command line: argument definitions (clap) and what each command does. `main.rs` only
//! parses and calls [`run`]; errors come back as one line for it to print.

use crate::error::{Error, Result};
use crate::image_io::{write_exr, write_image, Format};
use crate::material::Directions;
use crate::render::{render, NoProgress, Progress, RenderSettings, RenderStats, Strategy};
use crate::sampler::SamplerKind;
use crate::scene::{self, Scene};
use clap::{Args, Parser, Subcommand};
use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

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

/// Run a parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render(args) => run_render(&args),
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
        first_sample: 0,
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

/// Check before a long render that `path` can be written (format and folder).
fn check_output(path: &Path) -> Result<()> {
    Format::from_path(path)?;
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
    if let Some(dir) = dir {
        if !dir.is_dir() {
            return Err(Error::Write {
                path: path.to_path_buf(),
                message: format!("folder {} does not exist", dir.display()),
            });
        }
    }
    if path.is_dir() {
        return Err(Error::Write {
            path: path.to_path_buf(),
            message: "is a folder".into(),
        });
    }
    Ok(())
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
    let show_progress = !args.quiet && std::io::stderr().is_terminal();
    let bar = if show_progress {
        let bar = indicatif::ProgressBar::new(settings.width as u64 * settings.height as u64);
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
    let (film, stats) = render(&scene, &settings, progress)?;
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let meta = metadata(&scene, &settings, &stats);
    write_image(
        &output,
        film.width,
        film.height,
        &film.mean_image(),
        &meta,
        args.exposure,
    )?;
    if let Some(v) = &args.variance {
        let mut vmeta = meta.clone();
        vmeta.insert("image".into(), "variance of the mean".into());
        write_exr(v, film.width, film.height, &film.variance_image(), &vmeta)?;
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
            "rendered {}x{} at {} spp ({} + {}, max depth {}) in {:.3} s: {:.3} M samples/s, {} rays, {:.2} Mrays/s",
            settings.width,
            settings.height,
            settings.spp,
            settings.sampler,
            settings.directions,
            settings.max_depth,
            stats.elapsed.as_secs_f64(),
            stats.samples_per_second() / 1e6,
            stats.rays,
            stats.mrays_per_second()
        );
        eprintln!("wrote {}", output.display());
    }
    Ok(())
}
