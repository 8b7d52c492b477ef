//! `hil-sim bench`: wall time of [`super::generate`] against raw JSBSim stepping of the same
//! flights, side by side on the same workers (the target: 4 h of flight in ≤ 30 s on 2 cores).
//!
//! Raw stepping is the floor any data generator on JSBSim pays: the same maneuver scripts, loaded
//! the same way ([`crate::plant::load_script`], one bridge process per flight), run to their end
//! with the bridge's `run` command, which calls `FGFDMExec::run` and reads nothing. `generate` on top
//! of that reads the properties its read plan names at each 120 Hz step (`crate::fly`: 21 at every
//! step, the others only where the truth or a sensor model uses them), runs the sensor models in
//! Rust, and writes the CSVs and the manifest. Repeats alternate which side goes first so neither
//! always meets a cold cache.

use std::path::Path;
use std::time::Instant;

use serde::Serialize;

use super::generator::tick;
use super::{DatasetError, FlightEntry, GenerateError, Manifest, machine, par_map};
use crate::flight::Flight;
use crate::plant::{self, Plant, PlantError, SIM_HZ, STEPS_PER_SAMPLE};

/// Steps per bridge request on the raw side (one minute of flight).
const RAW_CHUNK: u32 = SIM_HZ * 60;

/// What `hil-sim bench --json` prints.
#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    pub preset: String,
    pub seed: u64,
    pub workers: usize,
    pub repeats: usize,
    pub flights: usize,
    /// Simulated flight time over all flights, hours.
    pub flight_hours: f64,
    /// 120 Hz JSBSim steps over all flights (raw side).
    pub steps: u64,
    /// Every raw flight ran exactly the steps behind the samples `generate` recorded for it. Always
    /// true: when they differ, [`run`] returns [`GenerateError::NotComparable`] instead of a report.
    pub same_flights: bool,
    /// Wall time of each `generate` repeat (flights, CSVs, manifest), s.
    pub generate_s: Vec<f64>,
    /// Wall time of each raw-stepping repeat, s.
    pub raw_s: Vec<f64>,
    /// Wall time of the dataset report (plots + dataset.md) that `hil-sim generate` adds, once, s.
    pub report_s: f64,
    /// Best `generate` + report, s: what `hil-sim generate` costs.
    pub generate_total_best_s: f64,
    /// Best raw stepping, s.
    pub raw_best_s: f64,
    /// `generate_total_best_s` / `raw_best_s`.
    pub overhead_ratio: f64,
    /// `generate_total_best_s` scaled to 4 h of flight, s (target ≤ 30 on 2 cores).
    pub generate_per_4h_s: f64,
    /// `raw_best_s` scaled to 4 h of flight, s.
    pub raw_per_4h_s: f64,
    /// Wall time per 120 Hz step of flight, µs (over all workers).
    pub generate_us_per_step: f64,
    pub raw_us_per_step: f64,
    pub jsbsim_version: String,
    pub git_rev: String,
    pub machine: String,
}

/// Runs every flight of the dataset in `dir` (written by [`super::generate`]) through raw JSBSim
/// stepping on `workers` threads; returns the 120 Hz steps per flight, in manifest order.
pub fn raw_steps(
    dir: &Path,
    m: &Manifest,
    aircraft_dir: Option<&Path>,
    workers: usize,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<Vec<u64>, PlantError> {
    par_map(
        &m.flights,
        workers,
        || tick(progress),
        |f| {
            let mut plant = Plant::spawn_for(aircraft_dir)?;
            plant::load_runscript(&mut plant, &crate::maneuver::files(dir, &f.name).0)?;
            let mut steps = 0u64;
            loop {
                let n = plant.run_raw(RAW_CHUNK)?;
                steps += u64::from(n);
                if n < RAW_CHUNK {
                    break Ok(steps);
                }
            }
        },
    )
    .into_iter()
    .collect()
}

/// The first flight whose raw step count is not the steps behind its recorded samples (a cut
/// flight, a script that ended differently), or `None` when every flight matches.
fn first_mismatch(flights: &[FlightEntry], steps: &[u64]) -> Option<String> {
    if steps.len() != flights.len() {
        return Some(format!(
            "{} flights generated, {} raw-stepped",
            flights.len(),
            steps.len()
        ));
    }
    flights
        .iter()
        .zip(steps)
        .find(|(f, s)| *s / u64::from(STEPS_PER_SAMPLE) != f.samples as u64)
        .map(|(f, s)| {
            format!(
                "flight {}: {} samples recorded, {s} raw steps ({} samples' worth)",
                f.name,
                f.samples,
                s / u64::from(STEPS_PER_SAMPLE)
            )
        })
}

/// The file that marks a directory as `hil-sim bench`'s scratch, which the next bench overwrites.
pub const SCRATCH_MARK: &str = ".hil-sim-bench";

/// Makes `out` bench's scratch directory: a new or empty one, or one a bench marked before
/// ([`SCRATCH_MARK`]). Anything else (a dataset, a file) is refused before any flight is flown,
/// since every repeat writes over it.
pub fn claim_scratch(out: &Path) -> Result<(), GenerateError> {
    if out.exists() && !out.is_dir() {
        return Err(DatasetError::NotADirectory {
            path: out.to_path_buf(),
        }
        .into());
    }
    if super::holds_something(out) && !out.join(SCRATCH_MARK).is_file() {
        return Err(GenerateError::BenchOut(out.to_path_buf()));
    }
    let mark = out.join(SCRATCH_MARK);
    std::fs::create_dir_all(out)
        .and_then(|()| {
            std::fs::write(
                &mark,
                "scratch of `hil-sim bench`: the next bench writes over this directory\n",
            )
        })
        .map_err(|source| DatasetError::Io {
            action: "write",
            path: mark,
            source,
        })?;
    Ok(())
}

/// Generates `preset` into `out` and raw-steps the same flights, `repeats` times each, alternating
/// which goes first; then writes the dataset report once and times it. `out` must be bench's
/// scratch ([`claim_scratch`]).
pub fn run(
    plan: &crate::maneuver::Plan,
    out: &Path,
    sensors: &crate::sensors::SensorConfig,
    workers: usize,
    repeats: usize,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<BenchReport, GenerateError> {
    claim_scratch(out)?;
    let repeats = repeats.max(1);
    let (mut generate_s, mut raw_s) = (Vec::new(), Vec::new());
    let generate = |times: &mut Vec<f64>| -> Result<(Manifest, Vec<Flight>), GenerateError> {
        let t = Instant::now();
        let m = super::generate(plan, out, sensors, workers, progress)?;
        times.push(t.elapsed().as_secs_f64());
        Ok(m)
    };
    let raw = |m: &Manifest, times: &mut Vec<f64>| -> Result<Vec<u64>, GenerateError> {
        let t = Instant::now();
        let steps = raw_steps(out, m, plan.aircraft_dir.as_deref(), workers, progress)?;
        times.push(t.elapsed().as_secs_f64());
        Ok(steps)
    };
    // The raw side needs the maneuver files, so the first repeat generates first; later repeats
    // alternate. Every repeat writes the same bytes (same seed).
    // Every pair is checked, so a bench whose sides do different work fails at its first pair.
    let same = |m: &Manifest, steps: &[u64]| match first_mismatch(&m.flights, steps) {
        Some(why) => Err(GenerateError::NotComparable(why)),
        None => Ok(()),
    };
    let (mut m, mut flights) = generate(&mut generate_s)?;
    let mut steps = raw(&m, &mut raw_s)?;
    same(&m, &steps)?;
    for r in 1..repeats {
        if r % 2 == 1 {
            steps = raw(&m, &mut raw_s)?;
            (m, flights) = generate(&mut generate_s)?;
        } else {
            (m, flights) = generate(&mut generate_s)?;
            steps = raw(&m, &mut raw_s)?;
        }
        same(&m, &steps)?;
    }
    // As `hil-sim generate` does: the report from the flights in memory.
    let t = Instant::now();
    super::report::write_report_of(out, m.clone(), flights)?;
    let report_s = t.elapsed().as_secs_f64();

    let total_steps: u64 = steps.iter().sum();
    let samples: usize = m.flights.iter().map(|f| f.samples).sum();
    let flight_hours = samples as f64 / f64::from(plant::SAMPLE_HZ) / 3600.0;
    let best = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let generate_total_best_s = best(&generate_s) + report_s;
    let raw_best_s = best(&raw_s);
    let per_4h = |s: f64| s * 4.0 / flight_hours.max(1e-9);
    let per_step = |s: f64| s * 1e6 / (total_steps.max(1) as f64);
    Ok(BenchReport {
        preset: plan.preset.name().to_string(),
        seed: plan.seed,
        workers,
        repeats,
        flights: m.flights.len(),
        flight_hours,
        steps: total_steps,
        same_flights: true,
        generate_s,
        raw_s,
        report_s,
        generate_total_best_s,
        raw_best_s,
        overhead_ratio: generate_total_best_s / raw_best_s,
        generate_per_4h_s: per_4h(generate_total_best_s),
        raw_per_4h_s: per_4h(raw_best_s),
        generate_us_per_step: per_step(generate_total_best_s),
        raw_us_per_step: per_step(raw_best_s),
        jsbsim_version: m.jsbsim_version.clone(),
        git_rev: m.git_rev.clone(),
        machine: machine(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flight(name: &str, samples: usize) -> FlightEntry {
        serde_json::from_value(serde_json::json!({
            "file": format!("{name}.csv"), "name": name, "split": "train", "profile": "gentle",
            "seed": 1, "duration_s": samples as f64 / 20.0, "samples": samples, "sha256": "",
            "cut": null
        }))
        .unwrap_or_else(|e| panic!("{e}"))
    }

    /// Bench writes over its --out on every repeat: only a new or empty directory, or its own
    /// scratch from an earlier bench, is taken; a dataset or a file is refused as it was.
    #[test]
    fn bench_takes_only_its_own_scratch_directory() {
        let dir = std::env::temp_dir().join(format!("hil-bench-out-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let fresh = dir.join("fresh");
        claim_scratch(&fresh).unwrap();
        assert!(fresh.join(SCRATCH_MARK).is_file());
        std::fs::write(fresh.join("manifest.json"), "{}").unwrap();
        claim_scratch(&fresh).unwrap();

        let dataset = dir.join("dataset");
        std::fs::create_dir_all(&dataset).unwrap();
        std::fs::write(dataset.join("manifest.json"), "{}").unwrap();
        let e = claim_scratch(&dataset).unwrap_err();
        assert!(
            matches!(&e, GenerateError::BenchOut(p) if *p == dataset),
            "{e}"
        );
        assert!(!dataset.join(SCRATCH_MARK).exists());

        let file = dir.join("file");
        std::fs::write(&file, "x").unwrap();
        let e = claim_scratch(&file).unwrap_err();
        assert!(
            matches!(
                &e,
                GenerateError::Dataset(DatasetError::NotADirectory { .. })
            ),
            "{e}"
        );
        assert_eq!(std::fs::read(&file).unwrap(), b"x");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_flight_with_fewer_samples_than_raw_steps_is_named() {
        let flights = [flight("a", 100), flight("b", 50)];
        assert_eq!(
            first_mismatch(&flights, &[600, 305]),
            None,
            "part of a sample: same"
        );
        let why = first_mismatch(&flights, &[600, 12_000]).unwrap_or_default();
        assert_eq!(
            why,
            "flight b: 50 samples recorded, 12000 raw steps (2000 samples' worth)"
        );
        let why = first_mismatch(&flights, &[600]).unwrap_or_default();
        assert_eq!(why, "2 flights generated, 1 raw-stepped");
    }
}
