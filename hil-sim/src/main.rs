use anyhow::Result;
use clap::{Parser, Subcommand};

/// Flight simulation and hardware-in-the-loop runner for the synthetic air data estimator.
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {}

fn main() -> Result<()> {
    let cli = Cli::parse();
    match cli.cmd {}
}
