//! `vrpt compare` and `vrpt converge`: load the scene and the reference, run the experiment
//! ([`crate::analysis::experiments`]), and write what was asked for: CSV, JSON, the PNG grid,
//! the convergence plots, the HTML report.

use super::{RegionArgs, Written};
use crate::analysis::experiments::{
    compare_entries, converge_entries, write_csv, Comparison, Convergence, Entry,
    ExperimentSettings,
};
use crate::analysis::maps::write_comparison_grid;
use crate::analysis::plots::{convergence_svg, write_convergence_plot};
use crate::analysis::report::Report;
use crate::error::{Error, Result};
use crate::image_io::{
    check_image_path, check_writable, read_exr, write_bytes, NamedPath, RgbImage,
};
use crate::limits::{parse_exposure, parse_seconds, parse_threads};
use crate::output::RenderMetadata;
use crate::render::Progress;
use crate::scene::Scene;
use crate::strategy::{Strategies, Strategy};
use std::path::PathBuf;

/// What both experiments share: the scene, the reference, the strategies and runs, and the
/// files to write (the flags of `compare` and `converge` both take).
#[derive(Clone, Debug, Default, clap::Args)]
pub struct ExperimentRequest {
    /// The scene: an .obj file, a scene.toml, or a folder holding a scene.toml.
    pub scene: PathBuf,
    /// The converged reference EXR (its size and max depth are used; its scene hash must match).
    #[arg(long)]
    pub reference: PathBuf,
    #[command(flatten)]
    pub load: super::LoadArgs,
    /// Strategies, comma-separated (default: the six presets).
    #[arg(long, value_parser = Strategies::parse, default_value = "independent,stratified,importance,combined,nee,mis",
          long_help = Strategy::list_help())]
    pub strategies: Strategies,
    /// Independent runs per strategy.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(2..))]
    pub runs: u32,
    /// Seed of the first run: the runs take the first RUNS seeds from SEED up that the
    /// reference does not hold (its seed, a merge's inputs'), so none reuses its samples.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = parse_threads)]
    pub threads: Option<usize>,
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
    pub allocation: AllocationArgs,
}

/// How the runs of `compare` and `converge` allocate their samples (their flags).
#[derive(Clone, Debug, Default, clap::Args)]
pub struct AllocationArgs {
    /// Render each run as R independent randomizations, each a complete set of spp/R samples,
    /// so each run estimates its own error honestly (shown beside the measured error) [default:
    /// 1, or 4 with --adaptive]
    #[arg(long, value_name = "R", value_parser = clap::value_parser!(u32).range(1..=256))]
    pub replicates: Option<u32>,
    /// Run every strategy twice, with uniform and with adaptive allocation ("S adaptive"), at
    /// the same replicates; the report shows the adaptive runs' samples per pixel.
    #[arg(long)]
    pub adaptive: bool,
}

impl ExperimentRequest {
    /// The experiment's entries: each strategy at the requested replicates, and with
    /// `--adaptive` its adaptive twin after it.
    pub fn entries(&self) -> Result<Vec<Entry<'static>>> {
        let a = &self.allocation;
        let r = a.replicates.unwrap_or(if a.adaptive { 4 } else { 1 });
        if a.adaptive && r < 2 {
            return Err(Error::Settings(
                "--adaptive needs at least 2 replicates: it allocates from their spread".into(),
            ));
        }
        let mut entries = Vec::new();
        for &st in &self.strategies.0 {
            entries.push(Entry::builtin(st).with_replicates(r));
            if a.adaptive {
                entries.push(Entry::builtin(st).with_replicates(r).adaptive());
            }
        }
        Ok(entries)
    }
}

/// `vrpt compare`: the strategies at equal spp, or at equal time per run.
#[derive(Clone, Debug, Default, clap::Args)]
pub struct CompareRequest {
    #[command(flatten)]
    pub experiment: ExperimentRequest,
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

/// `vrpt converge`: each strategy at each spp, from scratch.
#[derive(Clone, Debug, Default, clap::Args)]
pub struct ConvergeRequest {
    #[command(flatten)]
    pub experiment: ExperimentRequest,
    /// Sample counts, comma-separated (at least two); each is rendered from scratch.
    #[arg(long, value_delimiter = ',', default_value = "1,4,16,64,256",
          value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Vec<u32>,
    /// Write the log-log plot of MSE against spp (.svg or .png); may be given twice.
    #[arg(long = "plot", value_name = "FILE")]
    pub plots: Vec<PathBuf>,
}

/// An experiment ready to run: the scene and reference loaded and checked, the outputs checked.
pub struct Prepared<R> {
    pub request: R,
    pub scene: Scene,
    pub reference: RgbImage,
    pub settings: ExperimentSettings,
}

/// What an experiment made.
pub struct Outcome<T> {
    pub result: T,
    /// The result as the binary prints it (`Comparison::table`, `Convergence::table`).
    pub table: String,
    pub written: Vec<Written>,
}

/// A prepared experiment, whichever it is: its scene, its work, and running it.
pub trait Experiment {
    type Result;
    /// The scene loaded (its warnings are for the user).
    fn scene(&self) -> &Scene;
    /// Units of work for a progress bar.
    fn work(&self) -> u64;
    /// Run it and write its files.
    fn run(self, progress: &dyn Progress) -> Result<Outcome<Self::Result>>;
}

/// Check an experiment's files, load its scene and reference: `more` are the command's own
/// outputs and inputs (a grid, plots, a regions file), checked with the shared ones for
/// clashes before any work.
fn prepare_common(
    a: &ExperimentRequest,
    more: (&[NamedPath], &[NamedPath]),
) -> Result<(Scene, RgbImage, ExperimentSettings)> {
    for p in [&a.csv, &a.json, &a.report].into_iter().flatten() {
        check_writable(p)?;
    }
    let mut outputs = super::given(&[
        ("--csv", &a.csv),
        ("--json", &a.json),
        ("--report", &a.report),
    ]);
    outputs.extend_from_slice(more.0);
    let mut inputs = vec![
        ("SCENE", a.scene.as_path()),
        ("--reference", a.reference.as_path()),
    ];
    inputs.extend_from_slice(more.1);
    crate::image_io::check_outputs(&outputs, &inputs)?;
    if a.strategies.0.is_empty() {
        return Err(Error::Settings("no strategies to run".into()));
    }
    a.entries()?;
    let scene = a.load.load(&a.scene)?;
    // and the files the scene was read from (its textures, MTLs, scene.toml)
    super::check_against_scene(&outputs, &scene)?;
    let reference = read_exr(&a.reference)?;
    let s = ExperimentSettings::for_reference(
        &scene,
        &reference,
        &a.reference,
        a.seed,
        a.runs,
        a.threads,
    )?;
    Ok((scene, reference, s))
}

/// Write the rows as CSV and `json` as JSON where asked; the files written.
fn write_tables<R: serde::Serialize, J: serde::Serialize>(
    a: &ExperimentRequest,
    rows: &[R],
    json: &J,
) -> Result<Vec<Written>> {
    let mut written = Vec::new();
    if let Some(p) = &a.csv {
        write_csv(p, rows)?;
        written.push(Written::new(p));
    }
    if let Some(p) = &a.json {
        let text = serde_json::to_string_pretty(json).expect("plain data serializes");
        write_bytes(p, text.as_bytes())?;
        written.push(Written::new(p));
    }
    Ok(written)
}

/// How an experiment was made, for its report: scene, scene hash, reference, size, (the caller
/// inserts the spp or time at 4), runs, seeds, strategies, max depth, vrpt version.
fn settings_list<R>(
    p: &Prepared<R>,
    a: &ExperimentRequest,
    entries: &[Entry],
) -> Vec<(String, String)> {
    let reference_meta = RenderMetadata::radiance(&p.reference, &a.reference)
        .ok()
        .flatten()
        .map_or_else(
            || "no vrpt metadata".into(),
            |m| format!("{} spp, {}", m.spp, m.strategy),
        );
    let strategies: Vec<String> = entries.iter().map(|e| e.name.clone()).collect();
    let replicates = entries.first().map_or(1, |e| e.replicates);
    let seeds: Vec<String> = p.settings.run_seeds().iter().map(u64::to_string).collect();
    let s = &p.settings;
    vec![
        ("scene".into(), a.scene.display().to_string()),
        ("scene hash".into(), format!("{:016x}", p.scene.hash)),
        (
            "reference".into(),
            format!("{} ({reference_meta})", a.reference.display()),
        ),
        ("size".into(), format!("{}x{}", s.width, s.height)),
        ("runs".into(), a.runs.to_string()),
        ("seeds".into(), seeds.join(", ")),
        ("strategies".into(), strategies.join(", ")),
        ("replicates per run".into(), replicates.to_string()),
        ("max depth".into(), s.max_depth.to_string()),
        ("vrpt".into(), env!("CARGO_PKG_VERSION").into()),
    ]
}

impl CompareRequest {
    /// Check the outputs, load the scene and the reference, resolve the regions.
    pub fn prepare(self) -> Result<Prepared<CompareRequest>> {
        if let Some(g) = &self.grid {
            check_image_path(g)?;
        }
        if let Some(t) = self.equal_time {
            crate::limits::duration("--equal-time", t)?;
        }
        let grid: Vec<NamedPath> = self
            .grid
            .as_deref()
            .map(|g| ("--grid", g))
            .into_iter()
            .collect();
        let regions: Vec<NamedPath> = self
            .regions
            .regions
            .as_deref()
            .map(|r| ("--regions", r))
            .into_iter()
            .collect();
        let (scene, reference, mut settings) = prepare_common(&self.experiment, (&grid, &regions))?;
        settings.regions = self.regions.resolve(settings.width, settings.height)?;
        Ok(Prepared {
            request: self,
            scene,
            reference,
            settings,
        })
    }
}

impl Experiment for Prepared<CompareRequest> {
    type Result = Comparison;

    fn scene(&self) -> &Scene {
        &self.scene
    }

    /// One unit per run.
    fn work(&self) -> u64 {
        let a = &self.request.experiment;
        a.entries().map_or(0, |e| e.len()) as u64 * a.runs as u64
    }

    fn run(self, progress: &dyn Progress) -> Result<Outcome<Comparison>> {
        self.run_with(Vec::new(), progress)
    }
}

impl Prepared<CompareRequest> {
    /// Run it with `custom` entries (samplers of the caller's own, [`Entry::custom`]) after the
    /// strategies', and write its files.
    pub fn run_with(
        self,
        custom: Vec<Entry>,
        progress: &dyn Progress,
    ) -> Result<Outcome<Comparison>> {
        let (req, a) = (&self.request, &self.request.experiment);
        let mut entries = a.entries()?;
        entries.extend(custom);
        let c = compare_entries(
            &self.scene,
            &self.reference,
            &entries,
            req.spp,
            req.equal_time
                .map(|t| crate::limits::duration("--equal-time", t))
                .transpose()?,
            &self.settings,
            progress,
        )?;
        let mut written = write_tables(a, &c.rows, &c)?;
        if let Some(p) = &req.grid {
            write_comparison_grid(p, &c, &self.reference, req.exposure)?;
            written.push(Written::new(p));
        }
        if let Some(p) = &a.report {
            // the budget of a run: its settings row and the title's words
            let (key, value, budget) = match req.equal_time {
                Some(t) => (
                    "time per run",
                    format!("{t} s (passes of {} spp)", req.spp),
                    format!("{t} s per run"),
                ),
                None => (
                    "spp per run",
                    req.spp.to_string(),
                    format!("{} spp per run", req.spp),
                ),
            };
            let mut settings = settings_list(&self, a, &entries);
            settings.insert(4, (key.into(), value));
            let names: Vec<String> = self
                .settings
                .regions
                .iter()
                .map(|r| r.name.clone())
                .collect();
            let title = format!(
                "vrpt compare: {}, {budget}, {} runs",
                a.scene.display(),
                a.runs
            );
            let how = (title.as_str(), req.equal_time.is_some());
            Report::for_comparison(&c, &self.reference, &names, how, settings)?.write(p)?;
            written.push(Written::new(p));
        }
        Ok(Outcome {
            table: c.table(),
            result: c,
            written,
        })
    }
}

impl ConvergeRequest {
    /// Check the outputs and the sample counts, load the scene and the reference.
    pub fn prepare(self) -> Result<Prepared<ConvergeRequest>> {
        for p in &self.plots {
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
        if self.spp.len() < 2 {
            return Err(Error::Settings(
                "--spp needs at least two sample counts".into(),
            ));
        }
        let plots: Vec<NamedPath> = self.plots.iter().map(|p| ("--plot", p.as_path())).collect();
        let (scene, reference, settings) = prepare_common(&self.experiment, (&plots, &[]))?;
        Ok(Prepared {
            request: self,
            scene,
            reference,
            settings,
        })
    }
}

impl Experiment for Prepared<ConvergeRequest> {
    type Result = Convergence;

    fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The samples per pixel of every run.
    fn work(&self) -> u64 {
        let a = &self.request.experiment;
        a.entries().map_or(0, |e| e.len()) as u64
            * a.runs as u64
            * self.request.spp.iter().map(|&x| x as u64).sum::<u64>()
    }

    fn run(self, progress: &dyn Progress) -> Result<Outcome<Convergence>> {
        self.run_with(Vec::new(), progress)
    }
}

impl Prepared<ConvergeRequest> {
    /// Run it with `custom` entries (samplers of the caller's own, [`Entry::custom`]) after the
    /// strategies', and write its files.
    pub fn run_with(
        self,
        custom: Vec<Entry>,
        progress: &dyn Progress,
    ) -> Result<Outcome<Convergence>> {
        let (req, a) = (&self.request, &self.request.experiment);
        let mut entries = a.entries()?;
        entries.extend(custom);
        let c = converge_entries(
            &self.scene,
            &self.reference,
            &entries,
            &req.spp,
            &self.settings,
            progress,
        )?;
        let mut written = write_tables(a, &c.points, &c)?;
        let name = self
            .scene
            .source
            .file_stem()
            .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
        let plot_title = format!("{name}: MSE against spp ({} runs each)", self.settings.runs);
        for p in &req.plots {
            write_convergence_plot(p, &c, &plot_title)?;
            written.push(Written::new(p));
        }
        if let Some(p) = &a.report {
            let mut settings = settings_list(&self, a, &entries);
            let spps: Vec<String> = req.spp.iter().map(u32::to_string).collect();
            settings.insert(4, ("spp".into(), spps.join(", ")));
            let title = format!(
                "vrpt converge: {} ({} runs each)",
                a.scene.display(),
                a.runs
            );
            let svg = convergence_svg(&c, &plot_title)?;
            Report::for_convergence(&c, &self.reference, &title, settings, svg)?.write(p)?;
            written.push(Written::new(p));
        }
        Ok(Outcome {
            table: c.table(),
            result: c,
            written,
        })
    }
}
