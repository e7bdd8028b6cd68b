//! The `dpc` command line for a [`Registry`] of models: [`main`] parses the arguments,
//! dispatches to a subcommand (each in its own module with its own argument struct) and turns
//! an error into one stderr line and exit status 1.

pub mod analyze;
pub mod simulate;

use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};

/// Set once standard output is found closed: nothing more is printed to it.
static STDOUT_CLOSED: AtomicBool = AtomicBool::new(false);

/// Print to standard output. When the reader has gone (`dpc sweep ... | head`), the rest of
/// the text is dropped quietly and the command goes on to finish and write its files; any
/// other failure to print is said once on standard error.
pub(crate) fn say(args: std::fmt::Arguments<'_>) {
    if STDOUT_CLOSED.load(Ordering::Relaxed) {
        return;
    }
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_fmt(args).and_then(|()| out.flush()) {
        STDOUT_CLOSED.store(true, Ordering::Relaxed);
        if e.kind() != std::io::ErrorKind::BrokenPipe {
            let _ = writeln!(
                std::io::stderr(),
                "warning: cannot print to standard output ({e}); the results are still written"
            );
        }
    }
}

/// `println!` through [`say`].
macro_rules! sayln {
    ($($arg:tt)*) => {
        $crate::cli::command::say(format_args!("{}\n", format_args!($($arg)*)))
    };
}
pub(crate) use sayln;

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use thiserror::Error;

use crate::cli::registry::Registry;
use crate::cli::ScenarioError;

/// Descriptor Predictive Control toolkit.
#[derive(Parser)]
#[command(name = "dpc", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Linear DPC analysis (paper, Section 3) of a square system given in a TOML file.
    Analyze(analyze::AnalyzeArgs),
    /// Run a closed-loop scenario: summary.json, trajectory.csv and plots in --out.
    Simulate(simulate::SimulateArgs),
    /// Run every combination of --set values of a scenario in parallel.
    Sweep(simulate::SweepArgs),
    /// List the models scenarios can name.
    Models,
    /// Print a model's listing, dimensions, relative degrees and W; for a plant file
    /// (FILE.dpc) also its diagnostics, or its errors as FILE:LINE:COLUMN lines.
    Model {
        /// The model's name (see `dpc models`), or the path of a plant file ending in .dpc.
        name: String,
    },
}

/// Why a subcommand failed; printed as one line `error: ...`.
#[derive(Debug, Error)]
pub enum CliError {
    /// A scenario, its model or its outputs.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// `dpc analyze`: the system file is unreadable, malformed or has no analysis.
    #[error(transparent)]
    Analyze(#[from] analyze::AnalyzeError),
    /// `dpc model FILE.dpc`: the plant file cannot be read or compiled.
    #[error(transparent)]
    PlantFile(#[from] dpc::runtime::PlantFileError),
}

impl CliError {
    /// The error as printed: the errors of a plant file as their `FILE:LINE:COLUMN: message`
    /// lines (whether `dpc model` or a scenario named the file), followed for a run by one line
    /// on what became of its output directory; anything else as one line `error: ...`.
    fn report(&self) -> String {
        let scenario = match self {
            CliError::PlantFile(e) => return e.to_string(),
            CliError::Scenario(e) => e,
            other => return format!("error: {other}"),
        };
        let outcome = |target: &str, previous: bool| {
            if previous {
                format!("the previous results in {target} are unchanged")
            } else {
                format!("nothing was written to {target}")
            }
        };
        match scenario {
            ScenarioError::PlantFile(e) => e.to_string(),
            ScenarioError::NotWritten {
                target,
                previous,
                cause,
            } => match cause.as_ref() {
                ScenarioError::PlantFile(e) => {
                    format!("{e}\nerror: {}", outcome(target, *previous))
                }
                _ => format!("error: {self}"),
            },
            ScenarioError::SweepFailed {
                runs,
                first,
                target,
                previous,
            } => match first.as_ref() {
                ScenarioError::PlantFile(e) => format!(
                    "{e}\nerror: all {runs} runs of the sweep failed; {}",
                    outcome(target, *previous)
                ),
                _ => format!("error: {self}"),
            },
            _ => format!("error: {self}"),
        }
    }
}

/// Run the `dpc` command line on the models of `registry`, with the process's arguments;
/// `--help` and malformed arguments are handled by clap (which exits itself).
pub fn main(registry: Registry) -> ExitCode {
    run(&registry, Cli::parse())
}

/// Run the command line on `args` (the first is the program's name), as [`main`] does;
/// for tests and for programs that build their own argument list.
pub fn main_with_args<I, A>(registry: &Registry, args: I) -> ExitCode
where
    I: IntoIterator<Item = A>,
    A: Into<std::ffi::OsString> + Clone,
{
    match Cli::try_parse_from(args) {
        Ok(cli) => run(registry, cli),
        Err(e) => {
            // clap prints help and version to stdout with success, errors to stderr.
            let _ = e.print();
            if e.use_stderr() {
                ExitCode::FAILURE
            } else {
                ExitCode::SUCCESS
            }
        }
    }
}

fn run(registry: &Registry, cli: Cli) -> ExitCode {
    let result = match cli.command {
        Command::Analyze(args) => analyze::run(&args).map_err(CliError::Analyze),
        Command::Simulate(args) => simulate::simulate(registry, &args).map_err(CliError::from),
        Command::Sweep(args) => simulate::sweep(registry, &args).map_err(CliError::from),
        Command::Models => {
            for m in registry.models() {
                sayln!("{:<16} {}", m.name(), m.summary());
            }
            Ok(())
        }
        Command::Model { name } if crate::cli::plant_file::is_plant_file(&name) => {
            crate::cli::plant_file::describe(std::path::Path::new(&name))
                .map(|text| say(format_args!("{text}")))
                .map_err(CliError::from)
        }
        Command::Model { name } => registry
            .get(&name)
            .map(|m| say(format_args!("{}", m.describe())))
            .map_err(|cause| {
                CliError::Scenario(ScenarioError::UnknownModel {
                    origin: format!("dpc model {name}"),
                    cause,
                })
            }),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // A closed standard error has nowhere to report to either.
            let _ = writeln!(std::io::stderr(), "{}", e.report());
            ExitCode::FAILURE
        }
    }
}
