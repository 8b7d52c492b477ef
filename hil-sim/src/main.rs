use anyhow::Result;
use clap::{Parser, Subcommand};
use hil_sim::commands::{BenchArgs, FlyArgs, GenerateArgs, MergeArgs};

/// Flight simulation and hardware-in-the-loop runner for the synthetic air data estimator.
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
    /// The aircraft (its description, `aircraft/NAME.toml`). A build carries one aircraft, the
    /// default; another name is refused with how to build for it.
    #[arg(long, global = true, value_name = "NAME", value_parser = hil_sim::cli_values::this_builds_aircraft)]
    // Checked by its value parser: a parsed value is this build's aircraft.
    #[allow(dead_code)]
    aircraft: Option<String>,
}

#[derive(Subcommand)]
enum Cmd {
    /// Stream a flight through the simulated serial link to the firmware (in-process, QEMU or a
    /// board) and score its estimates.
    Run(Box<hil_sim::runner::cli::RunArgs>),
    /// Fly one JSBSim runscript (of the build's aircraft) and write a one-flight dataset (CSV + manifest).
    Fly(FlyArgs),
    /// Generate a random-maneuver dataset (maneuver XML, CSV per flight, manifest, plots, report).
    Generate(GenerateArgs),
    /// Join the shards of `generate --shard K/N` into the dataset one machine would have written
    /// (checks that every shard is there once and that they belong together).
    Merge(MergeArgs),
    /// Benchmark: wall time of `generate` against raw JSBSim stepping of the same flights, side by
    /// side on the same workers.
    Bench(BenchArgs),
}

fn main() -> std::process::ExitCode {
    hil_sim::error_text::exit(run())
}

fn run() -> Result<()> {
    match Cli::parse().cmd {
        Cmd::Run(a) => hil_sim::runner::cli::run(&a).map(|_| ())?,
        Cmd::Fly(a) => hil_sim::commands::fly(&a)?,
        Cmd::Generate(a) => hil_sim::commands::generate(&a)?,
        Cmd::Merge(a) => hil_sim::commands::merge(&a)?,
        Cmd::Bench(a) => hil_sim::commands::bench(&a)?,
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    /// Every `hil-sim` command line in README.md and docs/ parses against this CLI: its flags exist
    /// and its values parse (a line may leave out required flags, as prose does).
    #[test]
    fn every_hil_sim_command_in_the_docs_parses() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let (n, bad) =
            hil_sim::docs_cli::unparsed::<super::Cli>(&root, "hil-sim").expect("reading the docs");
        assert!(n >= 10, "only {n} hil-sim commands found");
        assert!(bad.is_empty(), "{}", bad.join("\n"));
    }
}
