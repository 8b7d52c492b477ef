//! The data-side commands of `hil-sim`: `fly` (one script → a one-flight dataset), `generate` (a
//! planned dataset) and `bench` (generation against raw JSBSim stepping). `run` is
//! [`crate::runner::cli`]. `main.rs` parses and dispatches; what the commands do and print is here,
//! on top of every other module.

use std::path::PathBuf;

use crate::dataset::{self, Manifest, Split};
use crate::error::{Error, Result};
use crate::fly::{self, FlyConfig};
use crate::sensors::SensorConfig;

#[derive(clap::Args)]
pub struct FlyArgs {
    /// JSBSim runscript; its initialize file is taken from beside it, else from the aircraft folder.
    #[arg(long)]
    script: PathBuf,
    /// Dataset directory to write (a one-flight dataset: CSV, manifest, report and plots).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Replace --out if it already holds something (only once the new dataset is complete).
    #[arg(long)]
    force: bool,
    /// Seed of the sensor error models.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Sensor model parameters (TOML; see docs/sensors.md). Defaults: LN-200-class IMU.
    #[arg(long)]
    sensors: Option<PathBuf>,
    /// Stop after this many simulated seconds (default: the script's end time).
    #[arg(long, value_parser = crate::cli_values::positive_seconds, allow_hyphen_values = true)]
    max_time_s: Option<f64>,
    #[command(flatten)]
    aircraft: crate::plant::AircraftArgs,
}

pub fn fly(a: &FlyArgs) -> Result<()> {
    let sensors = sensors_of(&a.sensors)?;
    let aircraft_dir = a.aircraft.dir()?;
    let cfg = FlyConfig {
        seed: a.seed,
        sensors: sensors.clone(),
        max_time_s: a.max_time_s,
        name: None,
        aircraft_dir: aircraft_dir.clone(),
    };
    let started = std::time::Instant::now();
    let staging = dataset::Staging::begin(&a.out, a.force)?;
    let dir = staging.path();
    let mut bridge = crate::plant::Plant::spawn_for(aircraft_dir.as_deref())?;
    let aircraft = dataset::AircraftRecord::of(aircraft_dir.as_deref(), bridge.aircraft_xml())?;
    let version = bridge.jsbsim_version().to_string();
    let flight = fly::fly_script_with(&mut bridge, &a.script, &cfg)?;
    drop(bridge);
    if flight.samples.is_empty() {
        return Err(Error::Usage(format!(
            "{} gave no samples (does it end before its first 20 Hz sample?)",
            a.script.display()
        )));
    }
    let entry = dataset::write_flight(dir, &flight, Split::Test, "script", a.seed)?;
    let manifest = Manifest {
        format: Manifest::FORMAT,
        suites: Manifest::written_suites(),
        preset: "fly".into(),
        jsbsim_version: version,
        git_rev: dataset::git_rev(),
        config: serde_json::json!({
            "script": a.script.display().to_string(),
            "max_time_s": a.max_time_s,
            "sensors": sensors,
        }),
        flights: vec![entry.clone()],
        files: Default::default(),
        aircraft: Some(aircraft),
    };
    manifest.write(dir)?;
    // The same pictures and dataset.md as `generate` writes (envelope, α/β histograms, time
    // histories, 3-D path and ground track).
    dataset::report::write_report(dir)?;
    staging.commit()?;
    let mpath = a.out.join("manifest.json");
    println!(
        "flew {} for {:.1} s ({} samples at 20 Hz) in {:.1} s wall{}",
        a.script.display(),
        entry.duration_s,
        entry.samples,
        started.elapsed().as_secs_f64(),
        match &entry.cut {
            Some(c) => format!("; CUT: {c}"),
            None => String::new(),
        }
    );
    println!(
        "wrote {} and {} (report: dataset.md, plots: *.png)",
        a.out.join(&entry.file).display(),
        mpath.display()
    );
    Ok(())
}

#[derive(clap::Args)]
pub struct GenerateArgs {
    /// `paper`: 16 training flights of 15–20 min + 4 test flights; `large`: paper + 48 more training
    /// flights (≈ 19 h); `ci`: 5 flights of 3 min; `ood`: 16 out-of-distribution test flights of
    /// 6 min, kept apart from training (docs/results/ood.md); `campaign`: any number of flight-hours
    /// with chosen profiles, mass, wind, turbulence and gust ranges (--hours, --profiles,
    /// --fuel-lbs, --wind-mps, --turbulence, --gust-interval-s).
    #[arg(long, value_enum)]
    preset: crate::maneuver::Preset,
    /// Dataset directory to write. Without --shard the dataset is written under a temporary name
    /// and moved here when complete.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Replace --out if it already holds a dataset (only once the new one is complete).
    #[arg(long)]
    force: bool,
    /// Fly only the preset's test flights (the same flights as in the whole preset), e.g. to score
    /// the estimator on another aircraft (--aircraft-dir).
    #[arg(long)]
    test_only: bool,
    #[command(flatten)]
    flights: FlightsArgs,
    /// Fly only shard K of N (0 ≤ K < N: the flights at plan positions ≡ K mod N) into --out, which
    /// the other shards may share, and leave a shard-K-of-N.json record; a re-run with a complete
    /// record does nothing. `hil-sim merge --dataset DIR` then writes the dataset one machine would
    /// have.
    #[arg(long)]
    shard: Option<dataset::Shard>,
    #[command(flatten)]
    campaign: CampaignArgs,
}

/// `--preset campaign` only: its size (required) and the ranges every profile draws from (defaults:
/// 20-min flights over the training presets' ranges).
#[derive(clap::Args)]
pub struct CampaignArgs {
    /// Flight-hours of the campaign (required with --preset campaign; more than 0, at most 10,000).
    #[arg(long)]
    hours: Option<f64>,
    /// Length of each flight, minutes (default 20).
    #[arg(long)]
    flight_min: Option<f64>,
    /// Fuel per main tank, lb, `LO:HI` (mass: empty 17,400 + pilot 230 + 2 × fuel).
    #[arg(long, value_parser = parse_range)]
    fuel_lbs: Option<(f64, f64)>,
    /// Steady wind speed, m/s, `LO:HI` (random direction).
    #[arg(long, value_parser = parse_range)]
    wind_mps: Option<(f64, f64)>,
    /// MIL-spec turbulence severity, `LO:HI` in 0..7, for every profile (default 0:6).
    #[arg(long, value_parser = parse_severity, conflicts_with = "turbulence_per_profile")]
    turbulence: Option<(u32, u32)>,
    /// Keep each profile's own turbulence range (gentle 0-3, high-α 0-4, climb 0-5, aggressive
    /// 2-6) instead of one range for all: the flag envelope of slow flight stays the presets'.
    #[arg(long)]
    turbulence_per_profile: bool,
    /// The profiles flown in turn, comma-separated (default: all four), e.g. `high-alpha` for a
    /// campaign of slow, high-α flight. Every tenth flight is a test flight, so with two profiles
    /// all test flights are of the second. Mass, wind and turbulence are drawn from the ranges of
    /// all four profiles unless set (--turbulence-per-profile keeps each profile's own severity).
    #[arg(long, value_delimiter = ',')]
    profiles: Option<Vec<crate::maneuver::ProfileKind>>,
    /// The time between the starts of two 1-cosine gusts, s, `LO:HI` with LO at least 1 (default:
    /// each profile's own, 40:150 on the F-16), e.g. 10:30 for a campaign rich in gusts. A gust
    /// lasts up to 11 s; one that has not ended when the next starts is cut short by it.
    #[arg(long, value_parser = parse_gust_interval)]
    gust_interval_s: Option<(f64, f64)>,
}

/// A `--fuel-lbs`/`--wind-mps`/`--gust-interval-s` range that is not `LO:HI` with finite LO ≤ HI.
#[derive(Debug, thiserror::Error)]
#[error("`{0}`: write LO:HI with LO ≤ HI, e.g. 0:25")]
pub struct BadRange(String);

/// A `--gust-interval-s` that is not `LO:HI` with 1 ≤ LO ≤ HI.
#[derive(Debug, thiserror::Error)]
#[error(
    "`{0}`: write LO:HI in seconds with 1 ≤ LO ≤ HI (a gust takes seconds to pass), e.g. 10:30"
)]
pub struct BadGustInterval(String);

fn parse_gust_interval(s: &str) -> std::result::Result<(f64, f64), BadGustInterval> {
    match parse_range(s) {
        Ok((lo, hi)) if lo >= 1.0 => Ok((lo, hi)),
        _ => Err(BadGustInterval(s.to_string())),
    }
}

fn parse_range(s: &str) -> std::result::Result<(f64, f64), BadRange> {
    let bad = || BadRange(s.to_string());
    let (a, b) = s.split_once(':').ok_or_else(bad)?;
    let (a, b): (f64, f64) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    if a.is_finite() && b.is_finite() && a <= b {
        Ok((a, b))
    } else {
        Err(bad())
    }
}

fn parse_severity(s: &str) -> std::result::Result<(u32, u32), BadRange> {
    let (a, b) = parse_range(s)?;
    if a < 0.0 || b > 7.0 || a.fract() != 0.0 || b.fract() != 0.0 {
        return Err(BadRange(s.to_string()));
    }
    Ok((a as u32, b as u32))
}

impl GenerateArgs {
    /// The plan: the preset and seed, and for a campaign its parameters. Campaign flags on another
    /// preset are refused rather than ignored.
    fn plan(&self) -> Result<crate::maneuver::Plan> {
        use crate::maneuver::{Campaign, Plan, Preset};
        let c = &self.campaign;
        let any = c.hours.is_some()
            || c.flight_min.is_some()
            || c.fuel_lbs.is_some()
            || c.wind_mps.is_some()
            || c.turbulence.is_some()
            || c.turbulence_per_profile
            || c.profiles.is_some()
            || c.gust_interval_s.is_some();
        let mut plan = Plan::new(self.preset, self.flights.seed);
        plan.aircraft_dir = self.flights.aircraft.dir()?;
        plan.test_only = self.test_only;
        if self.preset != Preset::Campaign {
            if any {
                return Err(Error::Usage(
                    "--hours, --flight-min, --fuel-lbs, --wind-mps, --turbulence[-per-profile], --profiles and --gust-interval-s go with --preset campaign".into(),
                ));
            }
            return Ok(plan);
        }
        let mut k = Campaign::default();
        match c.hours {
            Some(h) => k.hours = h,
            None => {
                return Err(Error::Usage(
                    "--preset campaign needs --hours H: the flight-hours to generate (e.g. --hours 40)"
                        .into(),
                ));
            }
        }
        if let Some(m) = c.flight_min {
            k.flight_min = m;
        }
        if let Some(r) = c.fuel_lbs {
            k.ranges.fuel_per_tank_lbs = r;
        }
        if let Some((lo, hi)) = c.wind_mps {
            k.ranges.steady_wind_fps = (lo / crate::flight::FT_TO_M, hi / crate::flight::FT_TO_M);
        }
        if let Some(t) = c.turbulence {
            k.ranges.turb_severity = Some(t);
        }
        if c.turbulence_per_profile {
            k.ranges.turb_severity = None;
        }
        k.ranges.gust_interval_s = c.gust_interval_s;
        k.profiles = c.profiles.clone();
        // Non-finite, absurd (above `Campaign::MAX_HOURS`) or no hours are refused here, before
        // anything is planned or written.
        k.flight_count()?;
        plan.campaign = Some(k);
        Ok(plan)
    }
}

/// What `generate` and `bench` share.
#[derive(clap::Args)]
pub struct FlightsArgs {
    /// Base seed; flight and sensor seeds derive from it.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Sensor model parameters (TOML; see docs/sensors.md).
    #[arg(long)]
    sensors: Option<PathBuf>,
    /// Parallel flights (one JSBSim bridge process each).
    #[arg(long, default_value_t = 2, value_parser = crate::cli_values::at_least_one, allow_hyphen_values = true)]
    workers: usize,
    #[command(flatten)]
    aircraft: crate::plant::AircraftArgs,
}

fn sensors_of(path: &Option<PathBuf>) -> Result<SensorConfig> {
    Ok(match path {
        Some(p) => SensorConfig::load(p)?,
        None => SensorConfig::default(),
    })
}

fn flights_bar(n: usize) -> indicatif::ProgressBar {
    crate::progress::bar(n as u64, "flights")
}

pub fn generate(a: &GenerateArgs) -> Result<()> {
    let sensors = sensors_of(&a.flights.sensors)?;
    let started = std::time::Instant::now();
    let plan = a.plan()?;
    if let Some(shard) = a.shard {
        if a.out.join("manifest.json").exists() && !a.force {
            return Err(Error::Usage(format!(
                "{} already holds a merged dataset: choose another --out, or pass --force to add shards to it",
                a.out.display()
            )));
        }
        let pb = flights_bar(shard.of(&plan.flights()?).len());
        let outcome =
            dataset::generate_shard(&plan, &a.out, &sensors, a.flights.workers, shard, Some(&pb))?;
        pb.finish_and_clear();
        match outcome {
            dataset::ShardOutcome::Flown(n) => println!(
                "shard {shard}: flew {n} flights in {:.1} s wall; wrote {}",
                started.elapsed().as_secs_f64(),
                shard.record_path(&a.out).display()
            ),
            dataset::ShardOutcome::AlreadyComplete(n) => println!(
                "shard {shard}: already complete ({n} flights, every CSV as recorded); nothing to do"
            ),
        }
        println!(
            "when every shard is done: hil-sim merge --dataset {}",
            a.out.display()
        );
        return Ok(());
    }
    let staging = dataset::Staging::begin(&a.out, a.force)?;
    let pb = flights_bar(plan.flights()?.len());
    let (m, flights) = dataset::generate(
        &plan,
        staging.path(),
        &sensors,
        a.flights.workers,
        Some(&pb),
    )?;
    pb.finish_and_clear();
    let report = dataset::report::write_report_of(staging.path(), m.clone(), flights)?;
    staging.commit()?;
    summarize(&m, &a.out, "generated", started, report)
}

#[derive(clap::Args)]
pub struct MergeArgs {
    /// The dataset directory the shards were generated into (`generate --shard K/N --out DIR`);
    /// the merged dataset is written there.
    #[arg(long, value_name = "DIR")]
    dataset: PathBuf,
}

/// `hil-sim merge`: the shards' flights joined into the dataset one machine would have written.
pub fn merge(a: &MergeArgs) -> Result<()> {
    let started = std::time::Instant::now();
    let m = dataset::merge(&a.dataset)?;
    let report = dataset::report::write_report(&a.dataset)?;
    summarize(&m, &a.dataset, "merged", started, report)
}

/// Prints what `generate` and `merge` made, with the dataset report's numbers.
fn summarize(
    m: &Manifest,
    out: &std::path::Path,
    verb: &str,
    started: std::time::Instant,
    report: dataset::report::Report,
) -> Result<()> {
    let samples: usize = m.flights.iter().map(|f| f.samples).sum();
    let cut = m.flights.iter().filter(|f| f.cut.is_some()).count();
    println!(
        "{verb} {} flights ({} samples, {:.1} min of flight, {} cut) in {:.1} s wall",
        m.flights.len(),
        samples,
        samples as f64 / f64::from(crate::flight::SAMPLE_HZ) / 60.0,
        cut,
        started.elapsed().as_secs_f64()
    );
    for f in m.flights.iter().filter(|f| f.cut.is_some()) {
        println!("  {} cut: {}", f.name, f.cut.as_deref().unwrap_or(""));
    }
    if m.flights.iter().any(|f| f.split == Split::Train) {
        let over15 = report.train.above_15_share();
        println!(
            "training: α {:.1}..{:.1}° ({:.1}% above 15°), β {:.1}..{:.1}°, Mach {:.2}..{:.2}",
            report.train.alpha_deg.0,
            report.train.alpha_deg.1,
            over15 * 100.0,
            report.train.beta_deg.0,
            report.train.beta_deg.1,
            report.train.mach.0,
            report.train.mach.1
        );
    } else {
        println!("test flights only (no training flights in this preset)");
    }
    println!("wrote {} (report: dataset.md, plots: *.png)", out.display());
    Ok(())
}

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Preset to generate and raw-step (docs/results/generate-bench.md measures `paper`); any but
    /// `campaign`.
    #[arg(long, value_enum, default_value = "paper")]
    preset: crate::maneuver::Preset,
    /// Scratch dataset directory (overwritten every repeat): a new or empty one, or an earlier
    /// bench's; anything else is refused.
    #[arg(long, default_value = "out/bench/generate")]
    out: PathBuf,
    /// The same `--workers` on both sides.
    #[command(flatten)]
    flights: FlightsArgs,
    /// Runs of each side (alternating which goes first); the best of each is reported.
    #[arg(long, default_value_t = 3, value_parser = crate::cli_values::at_least_one, allow_hyphen_values = true)]
    repeats: usize,
    /// Print the summary as JSON instead of a table.
    #[arg(long)]
    json: bool,
}

pub fn bench(a: &BenchArgs) -> Result<()> {
    use crate::maneuver::Preset;
    // A campaign's size is the user's (--hours), which bench does not take: it would fly the
    // default 100 h campaign twice over.
    if a.preset == Preset::Campaign {
        let fixed: Vec<&str> = <Preset as clap::ValueEnum>::value_variants()
            .iter()
            .filter(|p| **p != Preset::Campaign)
            .map(|p| p.name())
            .collect();
        return Err(Error::Usage(format!(
            "bench times the fixed presets ({}), not campaign; to time a campaign, time \
             `hil-sim generate --preset campaign --hours H`",
            fixed.join(", ")
        )));
    }
    let sensors = sensors_of(&a.flights.sensors)?;
    let n = a.preset.plan(a.flights.seed).len();
    // One tick per flight per side per repeat.
    let pb = flights_bar(2 * a.repeats.max(1) * n);
    let mut plan = crate::maneuver::Plan::new(a.preset, a.flights.seed);
    plan.aircraft_dir = a.flights.aircraft.dir()?;
    let r = crate::dataset::bench::run(
        &plan,
        &a.out,
        &sensors,
        a.flights.workers,
        a.repeats,
        Some(&pb),
    )?;
    pb.finish_and_clear();
    if a.json {
        println!("{}", serde_json::to_string_pretty(&r)?);
        return Ok(());
    }
    let list = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:.2}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    println!(
        "preset {} seed {}: {} flights, {:.2} h of flight, {} JSBSim steps at 120 Hz, {} workers \
         ({})",
        r.preset, r.seed, r.flights, r.flight_hours, r.steps, r.workers, r.machine
    );
    println!(
        "| side | runs, s | best, s | per 4 h of flight, s | µs per 120 Hz step |\n|---|---|---|---|---|"
    );
    println!(
        "| raw JSBSim stepping | {} | {:.2} | {:.2} | {:.2} |",
        list(&r.raw_s),
        r.raw_best_s,
        r.raw_per_4h_s,
        r.raw_us_per_step
    );
    println!(
        "| hil-sim generate (+ report {:.2} s) | {} | {:.2} | {:.2} | {:.2} |",
        r.report_s,
        list(&r.generate_s),
        r.generate_total_best_s,
        r.generate_per_4h_s,
        r.generate_us_per_step
    );
    println!(
        "generate costs {:.2}× raw stepping; 4 h of flight in {:.1} s (target ≤ 30 s on 2 cores)",
        r.overhead_ratio, r.generate_per_4h_s,
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_gust_interval_is_seconds_lo_to_hi_from_one() {
        assert_eq!(parse_gust_interval("10:30").unwrap(), (10.0, 30.0));
        assert_eq!(parse_gust_interval(" 1 : 1 ").unwrap(), (1.0, 1.0));
        for bad in ["0.5:30", "30:10", "10", "a:b", "nan:3", "-5:5", ""] {
            let e = parse_gust_interval(bad).unwrap_err().to_string();
            assert!(e.contains("e.g. 10:30"), "{bad}: {e}");
        }
    }
}
