//! Generating a dataset: planned maneuvers flown through the plant on worker threads, written in
//! plan order (needs the `sim` feature: the JSBSim bridge).

use std::path::Path;

use super::{DatasetError, FlightEntry, Manifest, git_rev, sha256_file, write_flight};

/// Why `generate` failed.
#[derive(Debug, thiserror::Error)]
pub enum GenerateError {
    #[error(transparent)]
    Plant(#[from] crate::plant::PlantError),
    #[error(transparent)]
    Maneuver(#[from] crate::maneuver::ManeuverError),
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    #[error("flight {name}: {source}")]
    Flight {
        name: String,
        source: Box<GenerateError>,
    },
}

/// `f` over `items` on `workers` threads (each takes the next unstarted item), results in item
/// order whatever order they finish in; ticks `progress` once per item.
pub fn par_map<T: Sync, R: Send>(
    items: &[T],
    workers: usize,
    progress: Option<&indicatif::ProgressBar>,
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let next = AtomicUsize::new(0);
    let done: std::sync::Mutex<Vec<(usize, R)>> = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..workers.clamp(1, items.len().max(1)) {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    let Some(item) = items.get(i) else { break };
                    let r = f(item);
                    if let Some(pb) = progress {
                        pb.inc(1);
                    }
                    if let Ok(mut d) = done.lock() {
                        d.push((i, r));
                    }
                }
            });
        }
    });
    let mut done = done.into_inner().unwrap_or_default();
    done.sort_by_key(|(i, _)| *i);
    done.into_iter().map(|(_, r)| r).collect()
}

/// Sensor seed of a flight: distinct from the maneuver seed so the two random streams are unrelated.
pub fn sensor_seed(flight_seed: u64) -> u64 {
    flight_seed ^ 0x5e45_5e45_5e45_5e45
}

/// Re-draws of a flight whose random initial condition JSBSim cannot trim, before giving up.
pub const TRIM_RETRIES: u64 = 3;

/// Maneuver seed of re-draw `attempt` (0 = the planned seed).
pub fn redraw_seed(planned: u64, attempt: u64) -> u64 {
    planned ^ attempt.wrapping_mul(0x7472_696d_0000_0000)
}

/// Generates a dataset: writes each planned maneuver ([`crate::maneuver::files`]) into `out`,
/// flies it through [`crate::fly::fly_script_with`] (the same path as `hil-sim fly --script`) on
/// `workers` threads, and writes the CSVs and `manifest.json`. Flights are written in plan order
/// whatever order the workers finish in, so the manifest is deterministic. A flight JSBSim cannot
/// trim is re-drawn with [`redraw_seed`] (up to [`TRIM_RETRIES`] times; the seed flown is the one
/// in the manifest), so one unlucky initial condition does not lose a whole dataset.
pub fn generate(
    preset: crate::maneuver::Preset,
    base_seed: u64,
    out: &Path,
    sensors: &crate::sensors::SensorConfig,
    workers: usize,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<Manifest, GenerateError> {
    use crate::fly::FlyConfig;
    use crate::maneuver::{self, Profile};
    std::fs::create_dir_all(out).map_err(|source| DatasetError::Io {
        action: "create",
        path: out.to_path_buf(),
        source,
    })?;
    let plan = preset.plan(base_seed);
    let version = std::sync::OnceLock::new();
    let results = par_map(&plan, workers, progress, |f| {
        (|| -> Result<FlightEntry, GenerateError> {
            let mut attempt = 0;
            loop {
                let seed = redraw_seed(f.seed, attempt);
                let m = maneuver::generate_case(
                    &Profile::preset(f.profile),
                    seed,
                    &f.name,
                    f.duration_s,
                    f.ood,
                )?;
                let script = m.write(out)?;
                // A fresh bridge per attempt: a failed trim can leave one in any state.
                let mut plant = crate::plant::Plant::spawn()?;
                version.get_or_init(|| plant.jsbsim_version().to_string());
                let cfg = FlyConfig {
                    seed: sensor_seed(seed),
                    sensors: sensors.clone(),
                    max_time_s: None,
                    name: Some(f.name.clone()),
                };
                match crate::fly::fly_script_with(&mut plant, &script, &cfg) {
                    Err(e) if e.is_trim_failure() && attempt < TRIM_RETRIES => attempt += 1,
                    r => {
                        let mut entry = write_flight(out, &r?, f.split, f.profile.name(), seed)?;
                        entry.faults = f
                            .ood
                            .map_or(&[][..], |c| c.faults())
                            .iter()
                            .map(|s| s.to_string())
                            .collect();
                        break Ok(entry);
                    }
                }
            }
        })()
        .map_err(|e| GenerateError::Flight {
            name: f.name.clone(),
            source: Box::new(e),
        })
    });
    let flights = results.into_iter().collect::<Result<Vec<_>, _>>()?;
    let mut files = std::collections::BTreeMap::new();
    for f in &plan {
        let (script, init) = maneuver::files(out, &f.name);
        for p in [script, init] {
            let name = p
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            files.insert(name, sha256_file(&p)?);
        }
    }
    let manifest = Manifest {
        format: Manifest::FORMAT,
        suites: Manifest::written_suites(),
        preset: preset.name().to_string(),
        jsbsim_version: version.into_inner().unwrap_or_default(),
        git_rev: git_rev(),
        config: serde_json::json!({
            "seed": base_seed,
            "plan": plan,
            "profiles": crate::maneuver::ProfileKind::ALL.iter().map(|k| Profile::preset(*k)).collect::<Vec<_>>(),
            "sensors": sensors,
        }),
        flights,
        files,
    };
    manifest.write(out)?;
    Ok(manifest)
}
