//! The `dpc` command line. Each subcommand lives in its own module with its own argument
//! struct and `run` function; `main` only dispatches and turns errors into one stderr line.

mod analyze;
mod simulate;

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
    /// Run a closed-loop scenario: summary.json, trajectory.csv and plots in --out.
    Simulate(simulate::SimulateArgs),
    /// Run every combination of --set values of a scenario in parallel.
    Sweep(simulate::SweepArgs),
    /// List the models scenarios can name.
    Models,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Analyze(args) => analyze::run(&args),
        Command::Simulate(args) => simulate::simulate(&args),
        Command::Sweep(args) => simulate::sweep(&args),
        Command::Models => {
            for m in dpc_models::registry::MODELS {
                println!("{:<16} {}", m.name, m.summary);
            }
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}
