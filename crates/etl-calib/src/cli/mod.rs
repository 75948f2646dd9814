//! The `etlcal` command line. Each verb lives in its own file; `main` dispatches.
use clap::{Parser, Subcommand};

/// Calibrate and run cameras focused by an electrically tunable lens.
#[derive(Parser)]
#[command(name = "etlcal", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {}

/// Entry point of the `etlcal` binary.
pub fn main() {
    let cli = Cli::parse();
    match cli.command {}
}
