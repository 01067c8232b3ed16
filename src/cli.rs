//! The command line (the binary's side): the commands, each taking its library request as its
//! flags ([`vrpt::commands`]: the argument struct is the request), `--quiet` where a command
//! shows progress (`Quiet`; `RenderArgs`, whose `--quiet` also hides the statistics), progress
//! bars, and printing the outcomes. Errors come back to `main` as one line.

use clap::{Args, Parser, Subcommand};
use std::io::IsTerminal;
use std::process::ExitCode;
use vrpt::commands::experiment::{CompareRequest, ConvergeRequest, Experiment};
use vrpt::commands::{diff, merge, render, Written};
use vrpt::error::Result;
use vrpt::render::Progress;

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
    Diff(diff::DiffRequest),
    /// Compare strategies' error against a reference over runs, at equal spp or equal time.
    Compare(Quiet<CompareRequest>),
    /// Render a scene with several strategies at several spp and fit how fast the error falls.
    Converge(Quiet<ConvergeRequest>),
    /// Draw a sampler's points in the unit square, with their discrepancy and power spectrum.
    Points(vrpt::commands::points::PointsRequest),
    /// Estimate known integrals with each sampler: measured mean and variance against the formulas.
    Integrate(vrpt::commands::integrate::IntegrateRequest),
    /// Test every warp's samples against its integrated pdf: chi-square, p-value and ∫pdf.
    Warptest(vrpt::commands::warptest::WarptestRequest),
    /// Show what path guiding learned at a pixel's first hit, beside the incident radiance there
    /// (the guide of a render of --spp, whose training takes about half of them).
    Guide(vrpt::commands::guide::GuideRequest),
    /// Say what the loader finds in a scene: files, triangles, bounds, materials, emitters and
    /// their power, textures, the camera it would use, memory, and every warning.
    Info(vrpt::commands::info::InfoRequest),
}

/// An experiment's request, and whether to show its progress bar.
#[derive(Debug, Clone, Args)]
pub struct Quiet<R: Args> {
    #[command(flatten)]
    pub request: R,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
}

/// `vrpt render`: its request, and whether to keep quiet on the terminal.
#[derive(Debug, Clone, Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub request: render::RenderRequest,
    /// No progress bar and no statistics (errors and warnings still print).
    #[arg(short, long, conflicts_with = "time_traces")]
    pub quiet: bool,
}

/// Run a parsed command line; the exit code of a command that ran (130: a render was
/// interrupted and wrote the samples taken).
pub fn run(cli: Cli) -> Result<ExitCode> {
    let ok = |r: Result<()>| r.map(|()| ExitCode::SUCCESS);
    match cli.command {
        Command::Render(args) => run_render(args),
        Command::Merge(args) => ok(run_merge(args)),
        Command::Diff(args) => ok(run_diff(args)),
        Command::Compare(a) => ok(experiment(a.quiet, a.request.prepare()?)),
        Command::Converge(a) => ok(experiment(a.quiet, a.request.prepare()?)),
        Command::Points(r) => ok(vrpt::commands::points::run(&r).map(|o| out(&o.table()))),
        Command::Integrate(r) => ok(vrpt::commands::integrate::run(&r).map(|o| out(&o.table()))),
        Command::Warptest(r) => ok(vrpt::commands::warptest::run(&r).map(|o| out(&o.table()))),
        Command::Guide(r) => ok(vrpt::commands::guide::run(&r).map(|o| out(&o.summary()))),
        Command::Info(r) => ok(vrpt::commands::info::run(&r).map(|o| out(&o.text()))),
    }
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

fn run_render(args: RenderArgs) -> Result<ExitCode> {
    crate::GRACEFUL.store(true, std::sync::atomic::Ordering::SeqCst);
    let request = render::RenderRequest {
        stop: Some(crate::STOP.clone()),
        ..args.request
    };
    let job = request.prepare()?;
    warn(&job.scene.warnings);
    let template = "{spinner} [{elapsed_precise}] {bar:40} {percent}% ETA {eta}";
    let bar = Bar::new(args.quiet, job.pixel_samples(), template);
    let r = job.run(&bar)?;
    drop(bar);
    if !args.quiet {
        let timing = if request.time_traces {
            r.timing.as_str()
        } else {
            ""
        };
        let wrote = r.output.as_ref().map(|p| p.display().to_string());
        eprintln!("{}{timing}wrote {}", r.summary, wrote.unwrap_or_default());
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

fn run_diff(request: diff::DiffRequest) -> Result<()> {
    let d = diff::run(&request)?;
    print_outcome(&d.table(), &d.written);
    Ok(())
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
