//! Flights in memory and on disk: one CSV per flight plus `manifest.json` (format in
//! `docs/architecture.md`, "Dataset format").

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use estimator_core::channels::TABLE1_CHANNELS;
use estimator_core::{CHANNELS, Channel, Suite};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

pub use crate::flight::{
    Flight, NO_SUBSAMPLES, SUB_CHANNELS, SUBSAMPLES, Sample, Split, SubSampleSi, SubsamplesSi,
    TRUTH_COLUMNS, TRUTH_COUNT, Truth, Zone, ZoneTimes,
};

/// Truth columns added by format 4 (NaN when reading a format-3 flight).
const TRUTH_SINCE_FORMAT_4: usize = 7;

/// Dataset read/write failures.
#[derive(Debug, thiserror::Error)]
pub enum DatasetError {
    #[error("cannot {action} {path}: {source}")]
    Io {
        action: &'static str,
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Csv { path: PathBuf, message: String },
    #[error("{path}: missing column `{column}` (is this a hil-sim flight CSV?)")]
    MissingColumn { path: PathBuf, column: String },
    #[error("{path} line {line}: column `{column}`: `{value}` is not a number")]
    BadValue {
        path: PathBuf,
        line: u64,
        column: String,
        value: String,
    },
    #[error("manifest {path}: {message}")]
    Manifest { path: PathBuf, message: String },
    #[error("{path}: {message}")]
    TimeBase { path: PathBuf, message: String },
    #[error(
        "{path} already exists and is not empty: choose another --out, or pass --force to replace it"
    )]
    Exists { path: PathBuf },
    /// An output directory that names an existing file.
    #[error(
        "{path} is a file, not a directory: give --out a directory (a new one, or an empty one)"
    )]
    NotADirectory { path: PathBuf },
}

/// A dataset directory written under a temporary name beside its final one and renamed into place
/// only when complete, so that a killed or failed run leaves no half-written dataset at `--out`
/// (at most a hidden `.NAME.partial` beside it, removed by the next run). An existing, non-empty
/// `--out` is refused unless `force`, and then replaced only once the new dataset is complete.
pub struct Staging {
    out: PathBuf,
    tmp: PathBuf,
    force: bool,
    committed: bool,
}

/// Whether `dir` is a directory with at least one entry.
fn holds_something(dir: &Path) -> bool {
    std::fs::read_dir(dir).is_ok_and(|mut d| d.next().is_some())
}

/// `DatasetError::Io` of `action` on `path`, for `map_err`.
fn io(action: &'static str, path: &Path) -> impl FnOnce(std::io::Error) -> DatasetError {
    let path = path.to_path_buf();
    move |source| DatasetError::Io {
        action,
        path,
        source,
    }
}

impl Staging {
    pub fn begin(out: &Path, force: bool) -> Result<Staging, DatasetError> {
        // A file at `out` is refused before any work, not when the finished dataset cannot replace
        // it (even --force replaces a dataset, not a file).
        if out.exists() && !out.is_dir() {
            return Err(DatasetError::NotADirectory {
                path: out.to_path_buf(),
            });
        }
        if holds_something(out) && !force {
            return Err(DatasetError::Exists {
                path: out.to_path_buf(),
            });
        }
        let name = out
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "dataset".into());
        let parent = out.parent().filter(|p| !p.as_os_str().is_empty());
        let tmp = parent
            .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
            .join(format!(".{name}.partial"));
        if tmp.exists() {
            std::fs::remove_dir_all(&tmp).map_err(io("remove the stale", &tmp))?;
        }
        std::fs::create_dir_all(&tmp).map_err(io("create", &tmp))?;
        Ok(Staging {
            out: out.to_path_buf(),
            tmp,
            force,
            committed: false,
        })
    }

    /// Where the dataset is written until [`Staging::commit`].
    pub fn path(&self) -> &Path {
        &self.tmp
    }

    /// Moves the complete dataset to `--out` (replacing an old one under `force`).
    pub fn commit(mut self) -> Result<(), DatasetError> {
        if self.out.exists() {
            if !self.force && holds_something(&self.out) {
                return Err(DatasetError::Exists {
                    path: self.out.clone(),
                });
            }
            std::fs::remove_dir_all(&self.out).map_err(io("replace", &self.out))?;
        }
        std::fs::rename(&self.tmp, &self.out)
            .map_err(io("move the finished dataset to", &self.out))?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.tmp);
        }
    }
}

/// Number of CSV columns: time, truth, sensed channels, sub-samples.
const COLUMNS: usize = 1 + TRUTH_COUNT + CHANNELS + SUBSAMPLES * SUB_CHANNELS.len();

/// The sub-sample columns (format 5), in file order: for each sub-sample `k` (oldest first) the
/// [`SUB_CHANNELS`]' names with `_sub{k}`, e.g. `accel_y_mps2_sub5` (the sample instant's).
static SUB_COLUMNS: std::sync::LazyLock<Vec<String>> = std::sync::LazyLock::new(|| {
    (0..SUBSAMPLES)
        .flat_map(|k| {
            SUB_CHANNELS
                .iter()
                .map(move |c| format!("{}_sub{k}", c.name()))
        })
        .collect()
});

/// All CSV column names in file order: time, truth, one sensed column per channel of every
/// suite, then the IMU's sub-samples.
pub fn columns() -> Vec<&'static str> {
    let mut c = vec!["time_s"];
    c.extend_from_slice(&TRUTH_COLUMNS);
    c.extend(Channel::ALL.iter().map(|c| c.name()));
    c.extend(SUB_COLUMNS.iter().map(String::as_str));
    c
}

/// Whether column `k` of [`columns`] is a truth column.
fn is_truth(k: usize) -> bool {
    (1..1 + TRUTH_COUNT).contains(&k)
}

/// Whether column `k` of [`columns`] is a sub-sample (format 5; absent in older datasets and
/// optional in a flight log, all or none).
fn is_subsample(k: usize) -> bool {
    k >= 1 + TRUTH_COUNT + CHANNELS
}

/// A flight's samples must be the estimator's 20 Hz: times strictly increasing, every step one
/// period (within 5 %). Anything else is refused with what was found; resample the log first.
pub fn check_time_base(path: &Path, f: &Flight) -> Result<(), DatasetError> {
    let period = 1.0 / f64::from(crate::flight::SAMPLE_HZ);
    let bad = |message: String| DatasetError::TimeBase {
        path: path.to_path_buf(),
        message,
    };
    // Order first: a row out of place also leaves a gap, and the order is what to fix then.
    for (k, w) in f.samples.windows(2).enumerate() {
        let (a, b) = (w[0].time_s, w[1].time_s);
        if !(a.is_finite() && b.is_finite()) {
            return Err(bad(format!("row {}: time_s is not a number", k + 2)));
        }
        if b <= a {
            return Err(bad(format!(
                "time_s does not increase at row {} ({a} s, then {b} s): sort the log by time",
                k + 3
            )));
        }
    }
    for (k, w) in f.samples.windows(2).enumerate() {
        let dt = w[1].time_s - w[0].time_s;
        if (dt - period).abs() > 0.05 * period {
            return Err(bad(format!(
                "rows {} and {} are {dt:.4} s apart ({:.1} Hz); the estimator runs at {} Hz: resample the log to a {period} s step",
                k + 2,
                k + 3,
                1.0 / dt,
                crate::flight::SAMPLE_HZ
            )));
        }
    }
    Ok(())
}

/// Columns a flight CSV of format 3 lacks (the format-4 truth columns and the EGI sensed columns):
/// read as NaN when all of them are absent.
fn since_format_4(column: usize) -> bool {
    let truth = 1 + TRUTH_COUNT - TRUTH_SINCE_FORMAT_4..1 + TRUTH_COUNT;
    let egi = 1 + TRUTH_COUNT + TABLE1_CHANNELS..1 + TRUTH_COUNT + CHANNELS;
    truth.contains(&column) || egi.contains(&column)
}

impl Flight {
    /// Duration from the first to the last sample, s.
    pub fn duration_s(&self) -> f64 {
        match (self.samples.first(), self.samples.last()) {
            (Some(a), Some(b)) => b.time_s - a.time_s,
            _ => 0.0,
        }
    }

    /// Writes the CSV bytes (`{}` formatting: shortest exact round trip, so reading gives the same f64s).
    /// Every value is formatted into one reused buffer: no allocation per value.
    pub fn write_csv_to<W: Write>(&self, w: W) -> Result<(), csv::Error> {
        use std::fmt::Write as _;
        let mut wr = csv::Writer::from_writer(w);
        wr.write_record(columns())?;
        let mut field = String::with_capacity(32);
        for s in &self.samples {
            let truth = s.truth.to_array();
            let values = std::iter::once(&s.time_s)
                .chain(&truth)
                .chain(&s.sensed)
                .chain(s.sub.iter().flatten());
            for v in values {
                field.clear();
                // Writing into a String cannot fail. (ryu finds the same digits faster but breaks
                // ties the other way: -853633233828841.25 is "…841.2" there, "…841.3" here.)
                let _ = write!(field, "{v}");
                wr.write_field(&field)?;
            }
            wr.write_record(None::<&[u8]>)?;
        }
        wr.flush()?;
        Ok(())
    }

    /// Writes the flight as a CSV file; returns the file's SHA-256 (lowercase hex), hashed on the
    /// way out rather than read back.
    pub fn write_csv(&self, path: &Path) -> Result<String, DatasetError> {
        let mut hashed = Hashing::create(path)?;
        self.write_csv_to(&mut hashed)
            .map_err(|e| DatasetError::Csv {
                path: path.to_path_buf(),
                message: e.to_string(),
            })?;
        Ok(hex(hashed.hash))
    }

    /// Reads a flight CSV (columns found by name; extra columns are ignored). The name is the file stem;
    /// `cut` is not stored in the CSV (it is in the manifest). A format-3 flight (no EGI sensed
    /// columns, none of the format-4 truth columns) reads them as NaN: the EGI channels are then
    /// absent (invalid) in its frames. A flight before format 5 has no sub-samples:
    /// [`NO_SUBSAMPLES`]. Some but not all of the columns of a format is an error.
    pub fn read_csv(path: &Path) -> Result<Flight, DatasetError> {
        Flight::read(path, true).map(|(f, _)| f)
    }

    /// Reads a flight log (docs/flight-log.md): `time_s` and every Table 1 sensed column are
    /// required, the EGI sensed columns all or none, the sub-samples all or none, each truth
    /// column optional (absent or empty: NaN, not scored). An empty sensed cell is a sensor that
    /// gave nothing (NaN: sent invalid).
    pub fn read_log(path: &Path) -> Result<Flight, DatasetError> {
        Flight::read(path, false).map(|(f, _)| f)
    }

    /// [`Flight::read_log`] of a file that may be a dataset's flight: when a `manifest.json`
    /// beside it lists the file, the manifest's promises hold ([`Manifest::read_flight`]). With the
    /// flight, the richest sensor suite whose columns the file has (table1: no EGI columns; egi:
    /// no sub-sample columns; egi120: both).
    pub fn read_log_in_dataset(path: &Path) -> Result<(Flight, Suite), DatasetError> {
        let (flight, has) = Flight::read(path, false)?;
        if let Some((dir, m, _)) = Manifest::listing(path)? {
            if let Some(why) = m.other_aircraft() {
                return Err(DatasetError::Manifest {
                    path: dir.join("manifest.json"),
                    message: format!("{} not read: {why}", path.display()),
                });
            }
            m.check_subsamples(dir, path, has == Suite::Egi120)?;
        }
        Ok((flight, has))
    }

    /// The flight, and the richest sensor suite whose columns its file has.
    fn read(path: &Path, truth_required: bool) -> Result<(Flight, Suite), DatasetError> {
        let f = std::fs::File::open(path).map_err(|source| DatasetError::Io {
            action: "open",
            path: path.to_path_buf(),
            source,
        })?;
        let mut rd = csv::Reader::from_reader(std::io::BufReader::new(f));
        let csv_err = |e: csv::Error| DatasetError::Csv {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let header = rd.headers().map_err(csv_err)?.clone();
        let find = |name: &str| {
            header
                .iter()
                .position(|h| h == name)
                .ok_or_else(|| DatasetError::MissingColumn {
                    path: path.to_path_buf(),
                    column: name.to_string(),
                })
        };
        let all = columns();
        let format3 = (0..all.len())
            .filter(|k| since_format_4(*k))
            .all(|k| header.iter().all(|h| h != all[k]));
        let no_sub = (0..all.len())
            .filter(|k| is_subsample(*k))
            .all(|k| header.iter().all(|h| h != all[k]));
        let idx: Vec<Option<usize>> = all
            .iter()
            .enumerate()
            .map(|(k, c)| match find(c) {
                Err(_) if format3 && since_format_4(k) => Ok(None),
                Err(_) if no_sub && is_subsample(k) => Ok(None),
                Err(_) if !truth_required && is_truth(k) => Ok(None),
                r => r.map(Some),
            })
            .collect::<Result<_, _>>()?;
        let mut samples = Vec::new();
        for rec in rd.records() {
            let rec = rec.map_err(csv_err)?;
            let line = rec.position().map(|p| p.line()).unwrap_or(0);
            let mut vals = [f64::NAN; COLUMNS];
            for (k, (i, v)) in idx.iter().zip(vals.iter_mut()).enumerate() {
                let Some(i) = *i else { continue };
                let s = rec.get(i).unwrap_or("");
                if !truth_required && k > 0 && s.trim().is_empty() {
                    continue; // nothing recorded: NaN
                }
                *v = s
                    .trim()
                    .parse::<f64>()
                    .map_err(|_| DatasetError::BadValue {
                        path: path.to_path_buf(),
                        line,
                        column: columns()[k].to_string(),
                        value: s.to_string(),
                    })?;
            }
            let mut truth = [0.0; TRUTH_COUNT];
            truth.copy_from_slice(&vals[1..1 + TRUTH_COUNT]);
            let mut sensed = [0.0; CHANNELS];
            sensed.copy_from_slice(&vals[1 + TRUTH_COUNT..1 + TRUTH_COUNT + CHANNELS]);
            let mut sub: SubsamplesSi = NO_SUBSAMPLES;
            let subsamples = vals[1 + TRUTH_COUNT + CHANNELS..].chunks_exact(SUB_CHANNELS.len());
            for (to, from) in sub.iter_mut().zip(subsamples) {
                to.copy_from_slice(from);
            }
            samples.push(Sample {
                time_s: vals[0],
                truth: Truth::from_array(&truth),
                sensed,
                sub,
            });
        }
        let flight = Flight {
            name: path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            samples,
            cut: None,
            zones: None,
            engine: Vec::new(),
        };
        let has = if format3 {
            Suite::Table1
        } else if no_sub {
            Suite::Egi
        } else {
            Suite::Egi120
        };
        Ok((flight, has))
    }
}

/// One flight of a dataset.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlightEntry {
    /// CSV file name, relative to the dataset directory.
    pub file: String,
    pub name: String,
    pub split: Split,
    pub profile: String,
    pub seed: u64,
    pub duration_s: f64,
    pub samples: usize,
    /// SHA-256 of the CSV file, hex.
    pub sha256: String,
    pub cut: Option<String>,
    /// Time in each maneuver-generator zone (absent for scripts without zone state).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub zones: Option<ZoneTimes>,
    /// Sensor faults to apply to this flight's frames (`crate::faults` notation; `ood` preset).
    /// The CSV holds what the healthy sensors measured; a reader applies these on the frames.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub faults: Vec<String>,
    /// The flight-test nose boom's record, `NAME.boom.csv` (`flight-test` preset only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub boom: Option<RecordFile>,
}

/// A file written beside a flight's CSV, with its SHA-256.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RecordFile {
    pub file: String,
    pub sha256: String,
}

impl FlightEntry {
    /// The sensor faults this flight's frames get (`faults`, parsed).
    pub fn faults(&self) -> Result<Vec<crate::faults::Fault>, crate::faults::FaultError> {
        self.faults.iter().map(|f| f.parse()).collect()
    }
}

/// `manifest.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    pub format: u32,
    /// The sensor suites whose channels every flight carries (`estimator_core::Suite` names). A
    /// format-3 manifest has no such field: it carries `table1` only.
    #[serde(default = "table1_only")]
    pub suites: Vec<String>,
    pub preset: String,
    pub jsbsim_version: String,
    pub git_rev: String,
    pub config: serde_json::Value,
    pub flights: Vec<FlightEntry>,
    /// SHA-256 of the other files written with the dataset (maneuver XML, plots), by file name.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub files: std::collections::BTreeMap<String, String>,
    /// The aircraft every flight flew (absent in datasets written before it was recorded: JSBSim's
    /// own F-16).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aircraft: Option<AircraftRecord>,
}

/// Which aircraft a dataset's flights flew: `name` its description (`aircraft/NAME.toml`), `dir`
/// the `--aircraft-dir` (none: JSBSim's own aircraft folder) and the SHA-256 of the model XML
/// loaded (`MODEL/MODEL.xml`). Datasets of different aircraft are never mixed silently: the
/// SHA-256 is compared wherever two datasets meet.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct AircraftRecord {
    /// The aircraft description (absent in manifests written before it was recorded: `f16`).
    #[serde(default = "f16_name")]
    pub name: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dir: Option<String>,
    /// (Named `f16_xml_sha256` in manifests written before the aircraft was a description.)
    #[serde(alias = "f16_xml_sha256")]
    pub model_xml_sha256: String,
}

fn f16_name() -> String {
    "f16".into()
}

impl AircraftRecord {
    /// The record of the model XML at `xml` flown from `dir` (`--aircraft-dir`, or none), of this
    /// build's aircraft.
    pub fn of(dir: Option<&Path>, xml: &Path) -> Result<AircraftRecord, DatasetError> {
        Ok(AircraftRecord {
            name: estimator_core::aircraft::AIRCRAFT.name.into(),
            dir: dir.map(|d| d.display().to_string()),
            model_xml_sha256: sha256_file(xml)?,
        })
    }

    /// How a message names it: the description, the directory (or JSBSim's own folder) and the
    /// hash's first digits.
    pub fn describe(r: Option<&AircraftRecord>) -> String {
        match r {
            None => "JSBSim's own F-16 (not recorded)".into(),
            Some(r) => format!(
                "`{}` from {} (model XML sha256 {})",
                r.name,
                r.dir.as_deref().unwrap_or("JSBSim's own aircraft folder"),
                r.model_xml_sha256.get(..12).unwrap_or(&r.model_xml_sha256)
            ),
        }
    }
}

impl Manifest {
    /// 5: the IMU's own 120 Hz outputs, six sub-samples per row (`*_sub0` … `*_sub5`). 4: the
    /// sensor suites: EGI sensed columns (attitude, NED velocity, fuel) and truth NED velocity,
    /// fuel and wind, `suites` in the manifest (3: time on JSBSim's own clock, IMU with Earth rate,
    /// scale factor and misalignment, zone times per flight; 2: time as whole steps / 120 Hz, gyros
    /// blind to the Earth's rotation; 1 had no position). Formats 3 and 4 are still read, without
    /// the IMU sub-samples (format 3 as a Table 1 dataset): their other columns mean what they mean
    /// in format 5.
    pub const FORMAT: u32 = 5;

    /// The oldest format this build reads.
    pub const OLDEST_READ: u32 = 3;

    /// The suites a dataset written by this build carries.
    pub fn written_suites() -> Vec<String> {
        Suite::ALL.iter().map(|s| s.name().to_string()).collect()
    }

    /// [`Manifest::suites`] as suites.
    pub fn suites(&self) -> Vec<Suite> {
        self.suites
            .iter()
            .filter_map(|n| Suite::from_name(n))
            .collect()
    }

    /// Whether every flight carries `suite`'s channels.
    pub fn carries(&self, suite: Suite) -> bool {
        self.suites().contains(&suite)
    }

    /// Why this build may not read the dataset's flights, when they flew another aircraft
    /// description than the build's (one aircraft per build: its features, scaling and networks),
    /// with how to build for theirs; `None` when they are this build's (or the record predates
    /// descriptions: the F-16).
    pub fn other_aircraft(&self) -> Option<String> {
        let theirs = self.aircraft.as_ref()?;
        let how = crate::cli_values::this_builds_aircraft(&theirs.name).err()?;
        Some(format!(
            "its flights flew the aircraft `{}`; {how}",
            theirs.name
        ))
    }

    /// The `manifest.json` beside the flight CSV at `csv` and its entry for the file, when there is
    /// such a manifest and it lists the file (with the dataset's directory).
    pub fn listing(csv: &Path) -> Result<Option<(&Path, Manifest, FlightEntry)>, DatasetError> {
        let Some(dir) = csv.parent().filter(|d| d.join("manifest.json").is_file()) else {
            return Ok(None);
        };
        let m = Manifest::read(dir)?;
        let name = csv.file_name().map(|n| n.to_string_lossy().into_owned());
        let entry = m
            .flights
            .iter()
            .find(|f| Some(&f.file) == name.as_ref())
            .cloned();
        Ok(entry.map(|e| (dir, m, e)))
    }

    /// Reads the flight CSV `file` of the dataset in `dir` ([`Flight::read_csv`]) and refuses one
    /// that lacks what the manifest promises: a dataset that lists `egi120` has the 120 Hz
    /// sub-sample columns in every flight.
    pub fn read_flight(&self, dir: &Path, file: &str) -> Result<Flight, DatasetError> {
        let path = dir.join(file);
        let (flight, has) = Flight::read(&path, true)?;
        self.check_subsamples(dir, &path, has == Suite::Egi120)?;
        Ok(flight)
    }

    /// Refuses the flight at `path` of the dataset in `dir` when the manifest lists `egi120` and
    /// the file has no sub-sample columns.
    fn check_subsamples(&self, dir: &Path, path: &Path, has_sub: bool) -> Result<(), DatasetError> {
        if has_sub || !self.carries(Suite::Egi120) {
            return Ok(());
        }
        Err(DatasetError::Csv {
            path: path.to_path_buf(),
            message: format!(
                "no 120 Hz sub-sample columns (`{}` …), though {} lists the egi120 suite: \
                 regenerate the dataset with this build's `hil-sim generate` (or `fly`), or \
                 take egi120 out of the manifest's `suites`",
                SUB_COLUMNS.first().map_or("", String::as_str),
                dir.join("manifest.json").display()
            ),
        })
    }

    pub fn write(&self, dir: &Path) -> Result<PathBuf, DatasetError> {
        let path = dir.join("manifest.json");
        let text = serde_json::to_string_pretty(self).map_err(|e| DatasetError::Manifest {
            path: path.clone(),
            message: e.to_string(),
        })?;
        std::fs::write(&path, text + "\n").map_err(|source| DatasetError::Io {
            action: "write",
            path: path.clone(),
            source,
        })?;
        Ok(path)
    }

    /// Reads `DIR/manifest.json`.
    pub fn read(dir: &Path) -> Result<Manifest, DatasetError> {
        let path = dir.join("manifest.json");
        let text = std::fs::read_to_string(&path).map_err(|source| DatasetError::Io {
            action: "read",
            path: path.clone(),
            source,
        })?;
        let m: Manifest = serde_json::from_str(&text).map_err(|e| DatasetError::Manifest {
            path: path.clone(),
            message: e.to_string(),
        })?;
        if !(Self::OLDEST_READ..=Self::FORMAT).contains(&m.format) {
            return Err(DatasetError::Manifest {
                path,
                message: format!(
                    "format {} (this build reads {} to {}); regenerate the dataset with this \
                     build's `hil-sim generate` (or `fly`)",
                    m.format,
                    Self::OLDEST_READ,
                    Self::FORMAT
                ),
            });
        }
        if let Some(bad) = m.suites.iter().find(|n| Suite::from_name(n).is_none()) {
            return Err(DatasetError::Manifest {
                path,
                message: format!(
                    "unknown sensor suite `{bad}` (this build knows {})",
                    Self::written_suites().join(", ")
                ),
            });
        }
        if m.format < 5 && m.carries(Suite::Egi120) {
            return Err(DatasetError::Manifest {
                path,
                message: format!(
                    "format {} has no 120 Hz sub-samples, yet it lists the egi120 suite; \
                     regenerate the dataset with this build's `hil-sim generate`",
                    m.format
                ),
            });
        }
        if m.format < 4 && m.suites != table1_only() {
            return Err(DatasetError::Manifest {
                path,
                message: format!(
                    "format {} carries table1 only, not {:?}",
                    m.format, m.suites
                ),
            });
        }
        if let Some(message) = m.flights_problem() {
            return Err(DatasetError::Manifest { path, message });
        }
        Ok(m)
    }

    /// A flight whose file is not inside the dataset directory (an absolute path, or one through
    /// `..`), or a flight name listed twice: what no writer of a dataset writes, and what would
    /// read another directory's file or score a flight twice.
    fn flights_problem(&self) -> Option<String> {
        let inside = |file: &str| {
            !file.is_empty()
                && Path::new(file).components().all(|c| {
                    matches!(
                        c,
                        std::path::Component::Normal(_) | std::path::Component::CurDir
                    )
                })
        };
        let mut names = std::collections::BTreeSet::new();
        for f in &self.flights {
            let files = std::iter::once(&f.file).chain(f.boom.iter().map(|b| &b.file));
            if let Some(file) = files.into_iter().find(|file| !inside(file)) {
                return Some(format!(
                    "flight `{}`: file `{file}` is not inside the dataset directory (a path \
                     relative to it, without `..`)",
                    f.name
                ));
            }
            if !names.insert(f.name.as_str()) {
                return Some(format!(
                    "flight `{}` is listed twice: every flight once, under its own name",
                    f.name
                ));
            }
        }
        None
    }
}

fn table1_only() -> Vec<String> {
    vec![Suite::Table1.name().to_string()]
}

#[cfg(feature = "sim")]
pub mod bench;
#[cfg(feature = "sim")]
mod generator;
pub mod report;

#[cfg(feature = "sim")]
pub use generator::{
    BadShard, GenerateError, Shard, ShardOutcome, ShardRecord, TRIM_RETRIES, generate,
    generate_shard, merge, redraw_seed, sensor_seed,
};

/// `f` over `items` on `workers` threads (each takes the next unstarted item), results in item
/// order whatever order they finish in; calls `done_one` after each item (a progress tick).
pub fn par_map<T: Sync, R: Send>(
    items: &[T],
    workers: usize,
    done_one: impl Fn() + Sync,
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
                    done_one();
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

/// A writer that hashes every byte it passes on (the CSV's SHA-256 without reading the file back).
struct Hashing<W> {
    inner: W,
    hash: Sha256,
}

impl Hashing<std::io::BufWriter<std::fs::File>> {
    /// A buffered file at `path`, hashed as it is written.
    fn create(path: &Path) -> Result<Self, DatasetError> {
        let f = std::fs::File::create(path).map_err(io("create", path))?;
        Ok(Hashing {
            inner: std::io::BufWriter::new(f),
            hash: Sha256::new(),
        })
    }

    /// The SHA-256 of everything written, lowercase hex (the generator's boom records).
    #[cfg(feature = "sim")]
    fn hex(self) -> String {
        hex(self.hash)
    }
}

impl<W: Write> Write for Hashing<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hash.update(buf.get(..n).unwrap_or(buf));
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// A finished SHA-256 as lowercase hex.
fn hex(h: Sha256) -> String {
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// SHA-256 of a file, lowercase hex.
pub fn sha256_file(path: &Path) -> Result<String, DatasetError> {
    let mut f = std::fs::File::open(path).map_err(|source| DatasetError::Io {
        action: "open",
        path: path.to_path_buf(),
        source,
    })?;
    let mut h = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = f.read(&mut buf).map_err(|source| DatasetError::Io {
            action: "read",
            path: path.to_path_buf(),
            source,
        })?;
        if n == 0 {
            break;
        }
        h.update(&buf[..n]);
    }
    Ok(hex(h))
}

/// The workspace's git revision (`-dirty` when the tree has changes), or `unknown`.
pub fn git_rev() -> String {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let run = |args: &[&str]| {
        std::process::Command::new("git")
            .args(args)
            .current_dir(dir)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    match run(&["rev-parse", "HEAD"]) {
        Some(rev) => match run(&["status", "--porcelain", "--untracked-files=no"]) {
            Some(s) if !s.is_empty() => format!("{rev}-dirty"),
            _ => rev,
        },
        None => "unknown".into(),
    }
}

/// "AMD EPYC, 2 cores available, x86_64 linux, release build, 2026-12-02 UTC": where and when a
/// figure was measured (the date from `date -u`, or `date unknown`).
pub fn machine() -> String {
    let date = std::process::Command::new("date")
        .args(["-u", "+%F"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| format!("{} UTC", String::from_utf8_lossy(&o.stdout).trim()))
        .unwrap_or_else(|| "date unknown".into());
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    format!(
        "{cpu}, {cores} cores available, {} {}, {} build, {date}",
        std::env::consts::ARCH,
        std::env::consts::OS,
        if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        }
    )
}

/// Writes one flight's CSV into `dir` and returns its manifest entry.
pub fn write_flight(
    dir: &Path,
    flight: &Flight,
    split: Split,
    profile: &str,
    seed: u64,
) -> Result<FlightEntry, DatasetError> {
    let file = format!("{}.csv", flight.name);
    let path = dir.join(&file);
    let sha256 = flight.write_csv(&path)?;
    Ok(FlightEntry {
        file,
        name: flight.name.clone(),
        split,
        profile: profile.to_string(),
        seed,
        duration_s: flight.duration_s(),
        samples: flight.samples.len(),
        sha256,
        cut: flight.cut.clone(),
        zones: flight.zones,
        faults: Vec::new(),
        boom: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trip_is_exact() {
        let mut s = Sample {
            time_s: 0.05,
            truth: Truth::default(),
            sensed: [0.0; CHANNELS],
            sub: crate::flight::NO_SUBSAMPLES,
        };
        s.truth.alpha_deg = 1.0 / 3.0;
        s.truth.mass_kg = 9876.54321;
        s.sensed[3] = -1e-7;
        s.sensed[15] = 0.123456789012345;
        s.sensed[Channel::Heading.index()] = 5.4321;
        s.sensed[Channel::Fuel.index()] = 1234.5;
        s.truth.wind_down_mps = -0.25;
        for (k, v) in s.sub.iter_mut().flatten().enumerate() {
            *v = k as f64 / 7.0 - 2.0;
        }
        let f = Flight {
            name: "t".into(),
            samples: vec![s, s],
            cut: None,
            zones: None,
            engine: Vec::new(),
        };
        let dir = std::env::temp_dir().join(format!("hil-ds-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("t.csv");
        let hash = f.write_csv(&p).unwrap();
        let g = Flight::read_csv(&p).unwrap();
        assert_eq!(f, g);
        // The hash taken on the way out is the file's.
        assert_eq!(hash, sha256_file(&p).unwrap());
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn an_aircraft_record_of_before_the_descriptions_reads_as_the_f16() {
        let old: AircraftRecord =
            serde_json::from_str(r#"{"dir": "x", "f16_xml_sha256": "ab"}"#).unwrap();
        assert_eq!(old.name, "f16");
        assert_eq!(old.model_xml_sha256, "ab");
        let text = serde_json::to_string(&old).unwrap();
        assert_eq!(text, r#"{"name":"f16","dir":"x","model_xml_sha256":"ab"}"#);
    }

    /// A manifest whose flight points outside its directory, or lists a name twice, is refused
    /// when it is read, saying which flight.
    /// A one-sample test flight `name` in `file`, for manifests the tests write.
    fn entry(name: &str, file: &str) -> FlightEntry {
        FlightEntry {
            file: file.into(),
            name: name.into(),
            split: Split::Test,
            profile: "gentle".into(),
            seed: 0,
            duration_s: 0.05,
            samples: 1,
            sha256: String::new(),
            cut: None,
            zones: None,
            faults: Vec::new(),
            boom: None,
        }
    }

    #[test]
    fn a_manifest_flight_outside_the_dataset_or_listed_twice_is_refused() {
        let dir = std::env::temp_dir().join(format!("hil-ds-escape-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut m = Manifest {
            format: Manifest::FORMAT,
            suites: Manifest::written_suites(),
            preset: "ci".into(),
            jsbsim_version: String::new(),
            git_rev: String::new(),
            config: serde_json::json!({}),
            flights: vec![entry("a", "a.csv"), entry("b", "./b.csv")],
            files: Default::default(),
            aircraft: None,
        };
        m.write(&dir).unwrap();
        assert!(Manifest::read(&dir).is_ok());
        for (flights, says) in [
            (
                vec![entry("a", "../x.csv")],
                "flight `a`: file `../x.csv` is not inside",
            ),
            (
                vec![entry("a", "/tmp/x.csv")],
                "flight `a`: file `/tmp/x.csv` is not inside",
            ),
            (vec![entry("a", "d/../../x.csv")], "is not inside"),
            (vec![entry("a", "")], "is not inside"),
            (
                vec![entry("a", "a.csv"), entry("a", "b.csv")],
                "flight `a` is listed twice",
            ),
        ] {
            m.flights = flights;
            m.write(&dir).unwrap();
            let e = Manifest::read(&dir).unwrap_err();
            assert!(
                matches!(&e, DatasetError::Manifest { message, .. } if message.contains(says)),
                "{e}"
            );
        }
        m.flights = vec![entry("a", "a.csv")];
        m.flights[0].boom = Some(RecordFile {
            file: "../a.boom.csv".into(),
            sha256: String::new(),
        });
        m.write(&dir).unwrap();
        assert!(Manifest::read(&dir).is_err());
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn column_names_are_unique() {
        let c = columns();
        let set: std::collections::BTreeSet<&str> = c.iter().copied().collect();
        assert_eq!(set.len(), c.len());
    }

    #[test]
    fn a_format_4_flight_reads_without_subsamples_and_half_of_them_is_refused() {
        let cols = columns();
        let n4 = 1 + TRUTH_COUNT + CHANNELS;
        assert_eq!(cols.len(), n4 + 6 * 13);
        assert_eq!(cols[n4], "gyro_p_rps_sub0");
        assert_eq!(cols[n4 + 8], "rudder_deg_sub0");
        assert_eq!(cols[cols.len() - 1], "speedbrake_deg_sub5");
        let dir = std::env::temp_dir().join(format!("hil-ds4-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("old.csv");
        let write = |n: usize| {
            let row: Vec<String> = (0..n).map(|k| format!("{}", k as f64 * 0.25)).collect();
            let text = format!("{}\n{}\n", cols[..n].join(","), row.join(","));
            std::fs::write(&p, text).unwrap();
        };
        write(n4);
        let g = Flight::read_csv(&p).unwrap();
        let s = &g.samples[0];
        assert!(s.sub.iter().flatten().all(|v| v.is_nan()));
        assert_eq!(s.sensed[CHANNELS - 1], (n4 - 1) as f64 * 0.25);
        write(n4 + SUB_CHANNELS.len());
        let err = Flight::read_csv(&p).unwrap_err().to_string();
        assert!(err.contains("gyro_p_rps_sub1"), "{err}");
        // A manifest that lists egi120 promises the sub-samples: a flight without them is refused,
        // and so is such a manifest of a format before 5.
        write(n4);
        let mut m = Manifest {
            format: Manifest::FORMAT,
            suites: Manifest::written_suites(),
            preset: "t".into(),
            jsbsim_version: String::new(),
            git_rev: String::new(),
            config: serde_json::Value::Null,
            flights: Vec::new(),
            files: Default::default(),
            aircraft: None,
        };
        let err = m.read_flight(&dir, "old.csv").unwrap_err().to_string();
        assert!(
            err.contains("gyro_p_rps_sub0") && err.contains("egi120"),
            "{err}"
        );
        // The columns count, not their values: a flight whose sub-samples are all empty (a dead
        // sensor bus) has them.
        let empty_subs = format!(
            "{},{}\n{}{}\n",
            cols[..n4].join(","),
            cols[n4..].join(","),
            (0..n4)
                .map(|k| format!("{},", k as f64 * 0.25))
                .collect::<String>(),
            vec!["NaN"; cols.len() - n4].join(",")
        );
        std::fs::write(dir.join("dead.csv"), empty_subs).unwrap();
        assert!(m.read_flight(&dir, "dead.csv").is_ok());
        // `hil-sim run --dataset` of a flight listed in the manifest beside it: the same check.
        m.flights = vec![entry("old", "old.csv")];
        m.write(&dir).unwrap();
        let err = Flight::read_log_in_dataset(&p).unwrap_err().to_string();
        assert!(err.contains("egi120"), "{err}");
        let (_, has) = Flight::read_log_in_dataset(&dir.join("dead.csv")).unwrap();
        assert_eq!(has, Suite::Egi120);
        m.suites = vec!["table1".into(), "egi".into()];
        assert!(m.read_flight(&dir, "old.csv").is_ok());
        m.format = 4;
        m.suites = Manifest::written_suites();
        m.write(&dir).unwrap();
        let err = Manifest::read(&dir).unwrap_err().to_string();
        assert!(err.contains("format 4") && err.contains("egi120"), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_format_3_flight_reads_with_the_egi_channels_absent() {
        // The format-3 columns: time, the first 19 truth columns, the 16 Table 1 channels.
        let cols = columns();
        let keep: Vec<usize> = (0..cols.len())
            .filter(|k| !since_format_4(*k) && !is_subsample(*k))
            .collect();
        assert_eq!(keep.len(), 1 + 19 + TABLE1_CHANNELS);
        let row: Vec<String> = keep
            .iter()
            .map(|k| format!("{}", *k as f64 * 0.5))
            .collect();
        let header: Vec<&str> = keep.iter().map(|k| cols[*k]).collect();
        let text = format!("{}\n{}\n", header.join(","), row.join(","));
        let dir = std::env::temp_dir().join(format!("hil-ds3-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("old.csv");
        std::fs::write(&p, text).unwrap();
        let g = Flight::read_csv(&p).unwrap();
        let s = &g.samples[0];
        assert_eq!(
            s.sensed[Channel::Throttle.index()],
            (1 + TRUTH_COUNT + 15) as f64 * 0.5
        );
        assert!(s.sensed[TABLE1_CHANNELS..].iter().all(|v| v.is_nan()));
        assert!(s.truth.fuel_kg.is_nan() && s.truth.wind_north_mps.is_nan());
        assert!(s.sub.iter().flatten().all(|v| v.is_nan()));
        assert_eq!(s.truth.lon_deg, 19.0 * 0.5);
        // Half of the new columns is not a format-3 file: refused, naming the missing column.
        let mut header = header.clone();
        header.push("fuel_true_kg");
        let text = format!("{}\n{},1\n", header.join(","), row.join(","));
        std::fs::write(&p, text).unwrap();
        let err = Flight::read_csv(&p).unwrap_err().to_string();
        assert!(err.contains("missing column"), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
