//! The `vrpt` binary: parse arguments ([`cli`]), call the library, print errors as one line.

mod cli;

use clap::Parser;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, LazyLock};

/// Set by the first SIGINT/SIGTERM during a render: the render stops after its current batch
/// of samples and writes what it has.
pub static STOP: LazyLock<Arc<AtomicBool>> = LazyLock::new(Default::default);
/// Whether the command under way stops gracefully (a render); any other command, and a second
/// signal, end the process at once.
pub static GRACEFUL: AtomicBool = AtomicBool::new(false);

/// First signal of a render: ask it to stop. Otherwise: remove the temporary files of writes
/// under way (the outputs they would replace stay as they were) and exit with 130.
fn on_signal() {
    if GRACEFUL.load(Ordering::SeqCst) && !STOP.swap(true, Ordering::SeqCst) {
        eprintln!(
            "\ninterrupted: finishing the current batch of samples, then writing the image \
             (interrupt again to abort without writing)"
        );
    } else {
        vrpt::image_io::remove_temp_files();
        eprintln!("\naborted");
        std::process::exit(130);
    }
}

fn main() -> ExitCode {
    let cli = match cli::Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(
                e.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) {
                let _ = e.print();
                return if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
                    ExitCode::from(2)
                } else {
                    ExitCode::SUCCESS
                };
            }
            // clap's message, its first paragraph on one line: "error: invalid value 'x' for
            // '--spp <SPP>': ...", or "error: the following required arguments were not
            // provided: --adaptive" (the names clap lists on the lines below)
            let text = e.render().to_string();
            let line = text
                .lines()
                .take_while(|l| !l.trim().is_empty() && !l.starts_with("Usage:"))
                .map(str::trim)
                .collect::<Vec<_>>()
                .join(" ");
            let line = if line.is_empty() {
                "error: bad arguments".to_string()
            } else {
                line
            };
            eprintln!("{}", vrpt::error::clip_line(&line));
            return ExitCode::from(2);
        }
    };
    if let Err(e) = ctrlc::set_handler(on_signal) {
        eprintln!("warning: cannot handle Ctrl-C: {e}");
    }
    match cli::run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("{}", vrpt::error::clip_line(&format!("error: {e}")));
            ExitCode::FAILURE
        }
    }
}
