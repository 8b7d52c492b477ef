//! Generating a dataset: planned maneuvers flown through the plant on worker threads, written in
//! plan order (needs the `sim` feature: the JSBSim bridge).

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{
    AircraftRecord, DatasetError, FlightEntry, Manifest, git_rev, par_map, sha256_file,
    write_flight,
};
use crate::flight::Flight;
use crate::maneuver::{Plan, PlannedFlight};

/// Why `generate` failed.
#[derive(Debug, thiserror::Error)]
pub enum GenerateError {
    #[error(transparent)]
    Plant(#[from] crate::plant::PlantError),
    #[error(transparent)]
    Maneuver(#[from] crate::maneuver::ManeuverError),
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// Shard records that do not make one dataset, or cannot be written.
    #[error("{0}")]
    Shard(String),
    /// `hil-sim bench`: the two sides did different work, so their times cannot be compared.
    #[error(
        "bench: {0}; generate and raw stepping did not fly the same steps, so no ratio is \
         reported (a cut flight records fewer samples: `hil-sim generate` prints why it was cut)"
    )]
    NotComparable(String),
    /// `hil-sim bench --out` that holds what bench did not write.
    #[error(
        "{0} holds files without `hil-sim bench`'s mark (a dataset, or a bench's scratch from before \
         benches marked theirs), and bench writes over its --out on every repeat: delete it if it is \
         a bench's scratch, or give a new or empty directory (default out/bench/generate)"
    )]
    BenchOut(std::path::PathBuf),
    /// Every draw of a flight's start failed JSBSim's trim.
    #[error(
        "no start of profile {profile} trimmed in {draws} draws (each a new altitude and speed \
         from its init_alt_ft and init_vc_kts): the profile asks for more than the aircraft holds \
         in level flight; narrow those ranges in the aircraft's description (docs/aircraft.md). \
         Last: {last}"
    )]
    Untrimmable {
        profile: String,
        draws: u64,
        last: Box<GenerateError>,
    },
    #[error("flight {name}: {source}")]
    Flight {
        name: String,
        source: Box<GenerateError>,
    },
}

/// One progress tick, when there is a bar.
pub(crate) fn tick(progress: Option<&indicatif::ProgressBar>) {
    if let Some(pb) = progress {
        pb.inc(1);
    }
}

/// Sensor seed of a flight: distinct from the maneuver seed so the two random streams are unrelated.
pub fn sensor_seed(flight_seed: u64) -> u64 {
    flight_seed ^ 0x5e45_5e45_5e45_5e45
}

/// Re-draws of a flight whose random initial condition JSBSim cannot trim, before giving up. A
/// re-draw changes only flights whose earlier draws all failed, so a larger budget leaves every
/// dataset that was written before as it was; ten make a lost dataset unlikely even for a profile
/// a third of whose starts its airframe cannot hold level (0.3^11 ≈ 2·10⁻⁶ per flight; the light
/// single's fastest profile is such a one).
pub const TRIM_RETRIES: u64 = 10;

/// Maneuver seed of re-draw `attempt` (0 = the planned seed).
pub fn redraw_seed(planned: u64, attempt: u64) -> u64 {
    planned ^ attempt.wrapping_mul(0x7472_696d_0000_0000)
}

/// Generates a dataset: writes each planned maneuver ([`crate::maneuver::files`]) into `out`,
/// flies it through [`crate::fly::fly_script_with`] (the same path as `hil-sim fly --script`) on
/// `workers` threads, and writes the CSVs and `manifest.json`. Flights are written in plan order
/// whatever order the workers finish in, so the manifest is deterministic; the flights come back
/// too, in the same order, for [`super::report::write_report_of`]. A flight JSBSim cannot
/// trim is re-drawn with [`redraw_seed`] (up to [`TRIM_RETRIES`] times; the seed flown is the one
/// in the manifest), so one unlucky initial condition does not lose a whole dataset.
pub fn generate(
    plan: &Plan,
    out: &Path,
    sensors: &crate::sensors::SensorConfig,
    workers: usize,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<(Manifest, Vec<Flight>), GenerateError> {
    create_dir(out)?;
    let planned = plan.flights()?;
    let (entries, flights, flown) = fly_plan(
        &planned,
        plan.aircraft_dir.as_deref(),
        out,
        sensors,
        workers,
        progress,
        true,
    )?;
    let manifest = assemble(plan, &planned, sensors, entries, flown, out)?;
    manifest.write(out)?;
    Ok((manifest, flights))
}

fn create_dir(out: &Path) -> Result<(), GenerateError> {
    std::fs::create_dir_all(out).map_err(|source| DatasetError::Io {
        action: "create",
        path: out.to_path_buf(),
        source,
    })?;
    Ok(())
}

/// Flies `plan` (a preset's plan or a shard of it) into `out`: the flights' entries in `plan` order,
/// the flights themselves (with `keep`; none otherwise, so a shard lets each go once written) and
/// the JSBSim version (empty for an empty plan).
fn fly_plan(
    plan: &[PlannedFlight],
    aircraft_dir: Option<&Path>,
    out: &Path,
    sensors: &crate::sensors::SensorConfig,
    workers: usize,
    progress: Option<&indicatif::ProgressBar>,
    keep: bool,
) -> Result<(Vec<FlightEntry>, Vec<Flight>, Flown), GenerateError> {
    use crate::fly::FlyConfig;
    use crate::maneuver;
    let version = std::sync::OnceLock::new();
    let results = par_map(
        plan,
        workers,
        || tick(progress),
        |f| {
            (|| -> Result<(FlightEntry, Option<Flight>), GenerateError> {
                let mut attempt = 0;
                loop {
                    let seed = redraw_seed(f.seed, attempt);
                    let m = maneuver::generate_planned(
                        &f.profile(),
                        seed,
                        &f.name,
                        f.duration_s,
                        f.ood,
                        f.card.as_ref(),
                    )?;
                    let script = m.write(out)?;
                    // A fresh bridge per attempt: a failed trim can leave one in any state.
                    let mut plant = crate::plant::Plant::spawn_for(aircraft_dir)?;
                    version.get_or_init(|| {
                        (
                            plant.jsbsim_version().to_string(),
                            plant.aircraft_xml().to_path_buf(),
                        )
                    });
                    let cfg = FlyConfig {
                        seed: sensor_seed(seed),
                        sensors: sensors.clone(),
                        max_time_s: None,
                        name: Some(f.name.clone()),
                        aircraft_dir: aircraft_dir.map(Path::to_path_buf),
                    };
                    match crate::fly::fly_script_with(&mut plant, &script, &cfg) {
                        Err(e) if e.is_trim_failure() && attempt < TRIM_RETRIES => attempt += 1,
                        Err(e) if e.is_trim_failure() => {
                            break Err(GenerateError::Untrimmable {
                                profile: f.profile.name().to_string(),
                                draws: attempt + 1,
                                last: Box::new(e.into()),
                            });
                        }
                        r => {
                            let flight = r?;
                            let mut entry =
                                write_flight(out, &flight, f.split, f.profile.name(), seed)?;
                            entry.faults = f
                                .ood
                                .map_or(&[][..], |c| c.faults())
                                .iter()
                                .map(|s| s.to_string())
                                .collect();
                            if f.card.is_some() {
                                entry.boom = Some(write_boom(out, &flight, cfg.seed)?);
                            }
                            break Ok((entry, keep.then_some(flight)));
                        }
                    }
                }
            })()
            .map_err(|e| GenerateError::Flight {
                name: f.name.clone(),
                source: Box::new(e),
            })
        },
    );
    let (entries, flights): (Vec<_>, Vec<_>) = results
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .unzip();
    let flights = flights.into_iter().flatten().collect();
    let flown = match version.into_inner() {
        Some((jsbsim_version, xml)) => Flown {
            jsbsim_version,
            aircraft: Some(AircraftRecord::of(aircraft_dir, &xml)?),
        },
        None => Flown::default(),
    };
    Ok((entries, flights, flown))
}

/// Writes the flight-test nose boom's record of `flight` beside its CSV (`NAME.boom.csv`).
fn write_boom(out: &Path, flight: &Flight, seed: u64) -> Result<super::RecordFile, GenerateError> {
    let samples = crate::boom::record(flight, &crate::boom::BoomConfig::default(), seed);
    let file = format!("{}.boom.csv", flight.name);
    let path = out.join(&file);
    // Hashed on the way out, as the flight CSVs are.
    let mut hashed = super::Hashing::create(&path)?;
    crate::boom::write_csv(&mut hashed, &samples).map_err(|e| DatasetError::Csv {
        path: path.clone(),
        message: e.to_string(),
    })?;
    Ok(super::RecordFile {
        sha256: hashed.hex(),
        file,
    })
}

/// What the bridge reported while flying a plan: the JSBSim version and the aircraft flown (empty
/// and `None` for an empty plan).
#[derive(Default)]
struct Flown {
    jsbsim_version: String,
    aircraft: Option<AircraftRecord>,
}

/// The manifest of a whole preset: its flights' entries in plan order, the maneuver files' hashes
/// (read from `out`) and the generation config.
fn assemble(
    spec: &Plan,
    plan: &[PlannedFlight],
    sensors: &crate::sensors::SensorConfig,
    flights: Vec<FlightEntry>,
    flown: Flown,
    out: &Path,
) -> Result<Manifest, GenerateError> {
    use crate::maneuver::{self, Profile};
    let mut files = std::collections::BTreeMap::new();
    for f in plan {
        let (script, init) = maneuver::files(out, &f.name);
        for p in [script, init] {
            let name = p
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            files.insert(name, sha256_file(&p)?);
        }
    }
    let mut config = serde_json::json!({
        "seed": spec.seed,
        "plan": plan,
        "profiles": crate::maneuver::ProfileKind::ALL.iter().map(|k| Profile::preset(*k)).collect::<Vec<_>>(),
        "sensors": sensors,
    });
    // A flight test says how its boom measures.
    if plan.iter().any(|f| f.card.is_some()) {
        config["boom"] = serde_json::to_value(crate::boom::BoomConfig::default())
            .map_err(|e| GenerateError::Shard(e.to_string()))?;
    }
    // An `ood` dataset says what each of its cases flies on this aircraft (`trainer ood` prints it).
    if plan.iter().any(|f| f.ood.is_some()) {
        config["ood_cases"] = serde_json::to_value(
            maneuver::OodCase::ALL
                .iter()
                .map(|c| (c.name(), c.describe()))
                .collect::<Vec<_>>(),
        )
        .map_err(|e| GenerateError::Shard(e.to_string()))?;
    }
    // Only a campaign says what it was asked for (the other presets' manifests stay as they were).
    if let Some(c) = &spec.campaign {
        config["campaign"] =
            serde_json::to_value(c).map_err(|e| GenerateError::Shard(e.to_string()))?;
    }
    Ok(Manifest {
        format: Manifest::FORMAT,
        suites: Manifest::written_suites(),
        preset: spec.preset.name().to_string(),
        jsbsim_version: flown.jsbsim_version,
        git_rev: git_rev(),
        config,
        flights,
        files,
        aircraft: flown.aircraft,
    })
}

/// Shard `index` of `count` (`--shard K/N`, `0 ≤ K < N`, as Slurm's `SLURM_ARRAY_TASK_ID` counts):
/// the planned flights whose position in the plan is `K` modulo `N`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

/// A `--shard` text that is not `K/N` with `0 ≤ K < N`.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
#[error(
    "`{0}`: write K/N with 0 ≤ K < N, e.g. 0/4 (Slurm: $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT)"
)]
pub struct BadShard(pub String);

impl std::str::FromStr for Shard {
    type Err = BadShard;
    fn from_str(s: &str) -> Result<Shard, BadShard> {
        let bad = || BadShard(s.to_string());
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count): (usize, usize) = (
            k.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// This shard's flights of `plan`, in plan order.
    pub fn of(self, plan: &[PlannedFlight]) -> Vec<PlannedFlight> {
        plan.iter()
            .enumerate()
            .filter(|(i, _)| i % self.count == self.index)
            .map(|(_, f)| f.clone())
            .collect()
    }

    /// The record a finished shard leaves in the dataset directory.
    pub fn record_path(self, out: &Path) -> std::path::PathBuf {
        out.join(format!("shard-{}-of-{}.json", self.index, self.count))
    }
}

/// What a finished shard leaves beside its flights: enough for `merge` to check it belongs to the
/// same dataset as the others and to build the one-machine manifest.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardRecord {
    pub plan: Plan,
    pub shard: Shard,
    /// Compared as the typed config: its f32 fields do not survive a trip through a JSON value.
    pub sensors: crate::sensors::SensorConfig,
    pub jsbsim_version: String,
    pub git_rev: String,
    pub flights: Vec<FlightEntry>,
    /// The aircraft flown (`None`: a record written before it was recorded, or an empty shard).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aircraft: Option<AircraftRecord>,
}

impl ShardRecord {
    /// What makes this record another dataset's than the one of `plan`, `sensors` and `count`
    /// shards (`theirs` names that one in the text, e.g. "this run"): its preset, seed, shard
    /// count, the rest of its plan or its sensor config; `None` when they are one dataset's.
    fn differs_in(
        &self,
        plan: &Plan,
        sensors: &crate::sensors::SensorConfig,
        count: usize,
        theirs: &str,
    ) -> Option<String> {
        if self.plan.preset != plan.preset {
            Some(format!(
                "preset {} ({theirs}: {})",
                self.plan.preset.name(),
                plan.preset.name()
            ))
        } else if self.plan.seed != plan.seed {
            Some(format!("seed {} ({theirs}: {})", self.plan.seed, plan.seed))
        } else if self.shard.count != count {
            Some(format!(
                "shard count {} ({theirs}: {count})",
                self.shard.count
            ))
        } else if self.plan != *plan {
            Some("campaign, --test-only or --aircraft-dir".to_string())
        } else if self.sensors != *sensors {
            Some("sensor config (--sensors)".to_string())
        } else {
            None
        }
    }
}

/// What [`generate_shard`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShardOutcome {
    /// Flew its flights (this many).
    Flown(usize),
    /// Its record was already there and every CSV it lists still has the recorded hash.
    AlreadyComplete(usize),
}

/// One shard of [`generate`]: flies this shard's share of the plan into `out` (which the other
/// shards may share) and writes its [`ShardRecord`] last, so a record means a finished shard. A
/// re-run finds a complete record for the same dataset and skips the work.
pub fn generate_shard(
    plan: &Plan,
    out: &Path,
    sensors: &crate::sensors::SensorConfig,
    workers: usize,
    shard: Shard,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<ShardOutcome, GenerateError> {
    create_dir(out)?;
    check_shard_siblings(out, plan, sensors, shard)?;
    let path = shard.record_path(out);
    if let Ok(text) = std::fs::read_to_string(&path)
        && let Ok(r) = serde_json::from_str::<ShardRecord>(&text)
    {
        let same = r.plan == *plan && r.shard == shard && r.sensors == *sensors;
        let intact = r
            .flights
            .iter()
            .all(|f| sha256_file(&out.join(&f.file)).is_ok_and(|h| h == f.sha256));
        if same && intact {
            return Ok(ShardOutcome::AlreadyComplete(r.flights.len()));
        }
    }
    let share = shard.of(&plan.flights()?);
    let (flights, _, flown) = fly_plan(
        &share,
        plan.aircraft_dir.as_deref(),
        out,
        sensors,
        workers,
        progress,
        false,
    )?;
    let n = flights.len();
    let record = ShardRecord {
        plan: plan.clone(),
        shard,
        sensors: sensors.clone(),
        jsbsim_version: flown.jsbsim_version,
        git_rev: git_rev(),
        flights,
        aircraft: flown.aircraft,
    };
    let text =
        serde_json::to_string_pretty(&record).map_err(|e| GenerateError::Shard(e.to_string()))?;
    // Written under a temporary name and renamed: a record is never seen half written.
    let tmp = path.with_extension("json.tmp");
    std::fs::write(&tmp, text)
        .and_then(|()| std::fs::rename(&tmp, &path))
        .map_err(|source| DatasetError::Io {
            action: "write",
            path: path.clone(),
            source,
        })?;
    Ok(ShardOutcome::Flown(n))
}

/// Refuses to fly a shard into `out` when a shard record there (this shard's own included) is of
/// another dataset: another preset, seed, shard count, campaign or sensor config. Such shards never
/// merge, and flying into their directory mixes two datasets' flights. A record that does not
/// read is left to [`generate_shard`] (its own is flown again) and to [`merge`].
fn check_shard_siblings(
    out: &Path,
    plan: &Plan,
    sensors: &crate::sensors::SensorConfig,
    shard: Shard,
) -> Result<(), GenerateError> {
    let Ok(entries) = std::fs::read_dir(out) else {
        return Ok(());
    };
    for p in entries.flatten().map(|e| e.path()) {
        let name = p.file_name().map(|n| n.to_string_lossy().into_owned());
        if !name.is_some_and(|n| n.starts_with("shard-") && n.ends_with(".json")) {
            continue;
        }
        let Some(r) = std::fs::read_to_string(&p)
            .ok()
            .and_then(|t| serde_json::from_str::<ShardRecord>(&t).ok())
        else {
            continue;
        };
        if let Some(what) = r.differs_in(plan, sensors, shard.count, "this run") {
            return Err(GenerateError::Shard(format!(
                "{} is shard {} of another dataset, by its {what}: the shards of one dataset share \
                 them all. Give this shard another --out (or run it with the same settings)",
                p.display(),
                r.shard
            )));
        }
    }
    Ok(())
}

/// Joins the shards in `out` into the dataset a one-machine [`generate`] writes: checks that the
/// records are one complete set (every shard of the same N, each once, the same preset, seed,
/// sensors, JSBSim and git revision; every planned flight exactly once), writes `manifest.json`
/// and removes the records. The report (`dataset::report::write_report`) is the caller's, as after
/// `generate`.
pub fn merge(out: &Path) -> Result<Manifest, GenerateError> {
    let entries = std::fs::read_dir(out).map_err(|source| DatasetError::Io {
        action: "read",
        path: out.to_path_buf(),
        source,
    })?;
    let mut records = Vec::new();
    for e in entries.flatten() {
        let p = e.path();
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if name.starts_with("shard-") && name.ends_with(".json") {
            let text = std::fs::read_to_string(&p).map_err(|source| DatasetError::Io {
                action: "read",
                path: p.clone(),
                source,
            })?;
            let r: ShardRecord = serde_json::from_str(&text)
                .map_err(|e| GenerateError::Shard(format!("{}: {e}", p.display())))?;
            records.push((p, r));
        }
    }
    // In name order: the same set of records gives the same message on every file system.
    records.sort_by(|a, b| a.0.cmp(&b.0));
    let Some((_, first)) = records.first() else {
        return Err(GenerateError::Shard(format!(
            "no shard records (shard-K-of-N.json) in {}: run `hil-sim generate --shard K/N --out {}` for every K first",
            out.display(),
            out.display()
        )));
    };
    let first = first.clone();
    let n = first.shard.count;
    let mut seen = vec![false; n];
    for (p, r) in &records {
        let differs = |what: &str| {
            GenerateError::Shard(format!(
                "{} differs from shard {} in its {what}: the shards are not one dataset",
                p.display(),
                first.shard
            ))
        };
        let theirs = format!("shard {}", first.shard);
        if let Some(what) = r.differs_in(&first.plan, &first.sensors, n, &theirs) {
            return Err(differs(&what));
        }
        if r.git_rev != first.git_rev {
            return Err(differs("git revision"));
        }
        if !r.jsbsim_version.is_empty()
            && !first.jsbsim_version.is_empty()
            && r.jsbsim_version != first.jsbsim_version
        {
            return Err(differs("JSBSim version"));
        }
        if let (Some(a), Some(b)) = (&r.aircraft, &first.aircraft)
            && (a.model_xml_sha256 != b.model_xml_sha256 || a.name != b.name)
        {
            return Err(differs("aircraft (description or model XML)"));
        }
        match seen.get_mut(r.shard.index) {
            Some(s) if !*s => *s = true,
            _ => {
                return Err(GenerateError::Shard(format!(
                    "shard {} appears twice in {}",
                    r.shard,
                    out.display()
                )));
            }
        }
    }
    let missing: Vec<String> = seen
        .iter()
        .enumerate()
        .filter(|(_, s)| !**s)
        .map(|(k, _)| format!("{k}/{n}"))
        .collect();
    if !missing.is_empty() {
        return Err(GenerateError::Shard(format!(
            "missing shards {}: run `hil-sim generate --preset {} --seed {} --shard K/{n} --out {}` for each",
            missing.join(", "),
            first.plan.preset.name(),
            first.plan.seed,
            out.display()
        )));
    }
    let sensors = first.sensors.clone();
    let plan = first.plan.flights()?;
    let mut flights = Vec::with_capacity(plan.len());
    for f in &plan {
        let mut found = records
            .iter()
            .flat_map(|(_, r)| r.flights.iter())
            .filter(|e| e.name == f.name);
        let (Some(e), None) = (found.next(), found.next()) else {
            return Err(GenerateError::Shard(format!(
                "planned flight {} is not in exactly one shard record",
                f.name
            )));
        };
        flights.push(e.clone());
    }
    let listed: usize = records.iter().map(|(_, r)| r.flights.len()).sum();
    if listed != plan.len() {
        return Err(GenerateError::Shard(format!(
            "the shard records list {listed} flights, the plan has {}",
            plan.len()
        )));
    }
    // Every file the records list, as recorded, before anything is written or removed: a set with
    // a missing or changed CSV stays a set of shards, to re-fly that shard and merge again.
    for (_, r) in &records {
        for (file, sha256) in r.flights.iter().flat_map(|e| {
            std::iter::once((&e.file, &e.sha256)).chain(e.boom.iter().map(|b| (&b.file, &b.sha256)))
        }) {
            let path = out.join(file);
            let what = match sha256_file(&path) {
                Ok(h) if h == *sha256 => continue,
                Ok(_) => "differs from what its shard record lists (SHA-256)".to_string(),
                Err(e) => format!("cannot be read ({e})"),
            };
            return Err(GenerateError::Shard(format!(
                "{} of shard {} {what}: nothing was merged; fly that shard again (the same \
                 `hil-sim generate ... --shard {} --out {}`), then merge",
                path.display(),
                r.shard,
                r.shard,
                out.display()
            )));
        }
    }
    let flown = Flown {
        jsbsim_version: records
            .iter()
            .map(|(_, r)| r.jsbsim_version.clone())
            .find(|v| !v.is_empty())
            .unwrap_or_default(),
        aircraft: records.iter().find_map(|(_, r)| r.aircraft.clone()),
    };
    let manifest = assemble(&first.plan, &plan, &sensors, flights, flown, out)?;
    manifest.write(out)?;
    for (p, _) in &records {
        std::fs::remove_file(p).map_err(|source| DatasetError::Io {
            action: "remove",
            path: p.clone(),
            source,
        })?;
    }
    Ok(manifest)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-shard `ci` set in a fresh directory: a record listing every planned flight, each CSV
    /// and maneuver file a few bytes.
    fn one_shard_set(tag: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("hil-merge-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let plan = Plan::new(crate::maneuver::Preset::Ci, 1);
        let shard = Shard { index: 0, count: 1 };
        let mut flights = Vec::new();
        for f in plan.flights().unwrap() {
            let file = format!("{}.csv", f.name);
            std::fs::write(dir.join(&file), &f.name).unwrap();
            let (script, init) = crate::maneuver::files(&dir, &f.name);
            std::fs::write(script, "<runscript/>").unwrap();
            std::fs::write(init, "<initialize/>").unwrap();
            flights.push(FlightEntry {
                sha256: sha256_file(&dir.join(&file)).unwrap(),
                file,
                name: f.name.clone(),
                split: f.split,
                profile: f.profile.name().to_string(),
                seed: f.seed,
                duration_s: f.duration_s,
                samples: 1,
                cut: None,
                zones: None,
                faults: Vec::new(),
                boom: None,
            });
        }
        let record = ShardRecord {
            plan,
            shard,
            sensors: crate::sensors::SensorConfig::default(),
            jsbsim_version: "test".into(),
            git_rev: "test".into(),
            flights,
            aircraft: None,
        };
        std::fs::write(
            shard.record_path(&dir),
            serde_json::to_string_pretty(&record).unwrap(),
        )
        .unwrap();
        dir
    }

    /// A shard is not flown into a directory whose records are of another dataset, and the
    /// message says what differs; one of the same dataset (another shard, or its own) is fine.
    #[test]
    fn a_shard_of_another_dataset_is_not_flown_beside_the_records() {
        let dir = one_shard_set("siblings");
        let sensors = crate::sensors::SensorConfig::default();
        let ci = |seed| Plan::new(crate::maneuver::Preset::Ci, seed);
        let one = Shard { index: 0, count: 1 };
        check_shard_siblings(&dir, &ci(1), &sensors, one).unwrap();
        for (plan, shard, says) in [
            (ci(7), one, "seed 1 (this run: 7)"),
            (
                ci(1),
                Shard { index: 1, count: 5 },
                "shard count 1 (this run: 5)",
            ),
            (
                Plan::new(crate::maneuver::Preset::Paper, 1),
                one,
                "preset ci (this run: paper)",
            ),
        ] {
            let e = check_shard_siblings(&dir, &plan, &sensors, shard).unwrap_err();
            let text = e.to_string();
            assert!(
                matches!(&e, GenerateError::Shard(m) if m.contains("shard-0-of-1.json is shard 0/1 of another dataset") && m.contains(says)),
                "{text}"
            );
        }
        let mut other = sensors.clone();
        other.gps.latency_s += 0.1;
        let e = check_shard_siblings(&dir, &ci(1), &other, one).unwrap_err();
        assert!(e.to_string().contains("sensor config"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A shard set with a missing or changed CSV is refused before `manifest.json` is written or
    /// a record removed: once the file is as recorded again, the same set merges.
    #[test]
    fn merge_checks_every_csv_before_writing_or_removing_anything() {
        let dir = one_shard_set("csv");
        let record = Shard { index: 0, count: 1 }.record_path(&dir);
        let csv = dir.join("test_aggressive_00.csv");
        let good = std::fs::read(&csv).unwrap();
        for bad in [Some(&b"changed"[..]), None] {
            match bad {
                Some(b) => std::fs::write(&csv, b).unwrap(),
                None => std::fs::remove_file(&csv).unwrap(),
            }
            let e = merge(&dir).unwrap_err();
            let text = e.to_string();
            assert!(
                matches!(&e, GenerateError::Shard(m) if m.contains("test_aggressive_00.csv of shard 0/1")),
                "{text}"
            );
            assert!(
                text.contains(if bad.is_some() {
                    "differs"
                } else {
                    "cannot be read"
                }),
                "{text}"
            );
            assert!(record.is_file(), "the record was removed");
            assert!(
                !dir.join("manifest.json").exists(),
                "a manifest was written"
            );
        }
        std::fs::write(&csv, good).unwrap();
        let m = merge(&dir).unwrap();
        assert_eq!(m.flights.len(), 5);
        assert!(!record.exists() && dir.join("manifest.json").is_file());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// What a larger re-draw budget relies on to leave earlier datasets as they were: draw 0 is the
    /// planned seed and draw k's seed depends on k alone, so a flight that trimmed on draw k flies
    /// the same seed whatever the budget; the draws a budget allows are all different.
    #[test]
    fn redraws_are_fixed_by_their_index_and_all_different() {
        for planned in [0u64, 15_503, u64::MAX] {
            assert_eq!(redraw_seed(planned, 0), planned);
            let seeds: std::collections::BTreeSet<u64> = (0..=TRIM_RETRIES)
                .map(|k| redraw_seed(planned, k))
                .collect();
            assert_eq!(seeds.len() as u64, TRIM_RETRIES + 1, "{planned}");
        }
        // A `paper` test flight of seed 15 that needed its 6th draw (on the light single).
        assert_eq!(redraw_seed(15_503, 5), 5_060_936_715_665_947_791);
    }
}
