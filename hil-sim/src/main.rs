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
    hil_sim::error_text::main(run)
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

    /// The words of the bash array or string `NAME=(...)` / `NAME="..."` in `script`.
    fn script_list(script: &str, name: &str) -> std::collections::BTreeSet<String> {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let text = std::fs::read_to_string(root.join(script)).expect("reading the script");
        let (open, close) = [("=(", ')'), ("=\"", '"')]
            .into_iter()
            .find(|(o, _)| text.contains(&format!("\n{name}{o}")))
            .unwrap_or_else(|| panic!("{script} has no {name}=( or {name}=\""));
        let head = format!("\n{name}{open}");
        let start = text.find(&head).map(|i| i + head.len()).unwrap_or_default();
        let end = start + text[start..].find(close).expect("the list ends");
        text[start..end]
            .split_whitespace()
            .map(str::to_string)
            .collect()
    }

    /// scripts/hil refuses a mistyped flag before it builds anything, from its own lists of the
    /// flags `hil-sim run` takes (`run_values`, `run_switches`): they are exactly run's flags
    /// besides the ones the script handles itself.
    #[test]
    fn scripts_hil_lists_exactly_the_flags_of_run() {
        use clap::CommandFactory;
        let own = [
            "--out",
            "--firmware",
            "--dataset",
            "--script",
            "--byte-loss",
            "--bit-flip",
            "--aircraft",
            "--elf",
            "--help",
            "--version",
        ];
        let cli = super::Cli::command();
        let run = cli.find_subcommand("run").expect("a run subcommand");
        let mut values = std::collections::BTreeSet::new();
        let mut switches = std::collections::BTreeSet::new();
        for a in run.get_arguments() {
            let Some(long) = a.get_long() else { continue };
            let flag = format!("--{long}");
            if own.contains(&flag.as_str()) {
                continue;
            }
            if a.get_action().takes_values() {
                values.insert(flag);
            } else {
                switches.insert(flag);
            }
        }
        assert_eq!(script_list("scripts/hil", "run_values"), values);
        assert_eq!(script_list("scripts/hil", "run_switches"), switches);
    }

    /// scripts/build-estimator checks its preset names before it builds: every name it lists is a
    /// preset of `generate`, and its 1σ presets are all of them but `campaign` (which needs --hours).
    #[test]
    fn build_estimator_lists_presets_of_generate() {
        use clap::ValueEnum;
        let all: std::collections::BTreeSet<String> = hil_sim::maneuver::Preset::value_variants()
            .iter()
            .filter_map(|p| p.to_possible_value().map(|v| v.get_name().to_string()))
            .collect();
        let train = script_list("scripts/build-estimator", "train_presets");
        let sigma = script_list("scripts/build-estimator", "sigma_presets");
        assert!(train.is_subset(&all), "{train:?} not all in {all:?}");
        let mut expected = all.clone();
        expected.remove("campaign");
        assert_eq!(sigma, expected);
    }
}
