//! The `dpc` command line.

use clap::Parser;

/// Descriptor Predictive Control toolkit.
#[derive(Parser)]
#[command(name = "dpc", version, about)]
struct Cli {}

fn main() {
    let _cli = Cli::parse();
}
