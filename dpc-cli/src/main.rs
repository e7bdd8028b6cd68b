//! The `dpc` command line. Each subcommand lives in its own module with its own argument
//! struct and `run` function; `main` only dispatches and turns errors into one stderr line.

mod analyze;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

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
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Analyze(args) => analyze::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}
