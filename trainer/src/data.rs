//! Datasets for training, read through `hil_sim::dataset` (the one reader of the format in
//! docs/architecture.md), and the exact estimator input contract: every row becomes the frame the link
//! delivers (`hil_sim::frames::sample_to_frame`, i.e. `SensorFrame::from_si` of the sensed SI
//! columns of every suite the dataset carries), then `FeatureValues::compute(&frame, &history)`
//! through one `History` per flight. A Table 1 model reads the Table 1 channels only, so it sees the
//! same values whether the dataset also carries the EGI suite or not.
use crate::error::{Error, Result};
use estimator_core::{FeatureState, FeatureValues, SensorFrame};
use hil_sim::dataset::{Manifest, Split, Truth, sha256_file};
use hil_sim::faults::Fault;
use std::path::{Path, PathBuf};

/// Training rows (train + validation flights) of the paper's experiment: 4 h of flight at the
/// dataset's sample rate (288 000 at 20 Hz).
pub const PAPER_TRAIN_ROWS: usize = 4 * 3600 * hil_sim::flight::SAMPLE_HZ as usize;

/// Which part of the experiment a flight belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Role {
    Train,
    /// A training flight held out for model selection.
    Val,
    /// A manifest test flight: unseen until evaluation.
    Test,
}

impl Role {
    pub const ALL: [Role; 3] = [Role::Test, Role::Train, Role::Val];

    /// The `--split` name.
    pub const fn name(self) -> &'static str {
        match self {
            Role::Train => "train",
            Role::Val => "val",
            Role::Test => "test",
        }
    }

    /// The role a `--split` name names.
    pub fn from_name(name: &str) -> Option<Role> {
        Role::ALL.into_iter().find(|r| r.name() == name)
    }
}

/// Truth columns used as targets (the intermediate in SI; converted to mm/s and millidegrees by users).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    AlphaDeg,
    BetaDeg,
    WAero,
    VAero,
}

impl Target {
    pub const ALL: [Target; 4] = [
        Target::AlphaDeg,
        Target::BetaDeg,
        Target::WAero,
        Target::VAero,
    ];
    pub fn column(self) -> &'static str {
        match self {
            Target::AlphaDeg => "alpha_deg",
            Target::BetaDeg => "beta_deg",
            Target::WAero => "w_aero_mps",
            Target::VAero => "v_aero_mps",
        }
    }
    /// This target's value in a truth record.
    pub fn of(self, t: &Truth) -> f64 {
        match self {
            Target::AlphaDeg => t.alpha_deg,
            Target::BetaDeg => t.beta_deg,
            Target::WAero => t.w_aero_mps,
            Target::VAero => t.v_aero_mps,
        }
    }
}

/// Hands the free pages of the allocator's heaps back to the system. glibc keeps the pages of freed
/// blocks of a few MB (a flight's frames or features), and a training matrix, one block of GBs,
/// cannot reuse them: without this, letting 13 M rows' frames go lowered nothing.
fn release_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim takes no pointer; it only returns whole free pages to the system.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// One flight: frames exactly as the estimator would receive them, their features, and the truth.
#[derive(Debug, Clone)]
pub struct Flight {
    pub name: String,
    pub role: Role,
    pub time_s: Vec<f64>,
    pub frames: Vec<SensorFrame>,
    pub features: Vec<FeatureValues>,
    /// Truth, indexed by `Target as usize`: α, β (deg), w, v (m/s).
    pub truth: [Vec<f64>; 4],
    /// True dynamic pressure, Pa (truth only: for error-by-regime plots, never a model input).
    pub qbar_pa: Vec<f64>,
    /// A gyro-bias twin of a training flight ([`Dataset::add_gyro_bias_twins`]), which an angle
    /// may train without ([`crate::pipeline::prepare_angle`]).
    pub gyro_bias_twin: bool,
}

impl Flight {
    /// Rows: one per frame, counted by their times, which every flight keeps (a training flight
    /// may have let its frames and features go, [`Dataset::drop_training_features`]).
    pub fn len(&self) -> usize {
        self.time_s.len()
    }
    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }
    pub fn truth(&self, t: Target) -> &[f64] {
        &self.truth[t as usize]
    }
}

#[derive(Debug, Clone)]
pub struct Dataset {
    pub dir: PathBuf,
    /// SHA-256 of manifest.json (which carries each flight's own SHA-256).
    pub manifest_sha256: String,
    pub preset: String,
    /// The sensor suites every flight carries (manifest `suites`).
    pub suites: Vec<estimator_core::Suite>,
    pub flights: Vec<Flight>,
    /// Each flight's seed and profile by its name here, as its manifest records them: what tells
    /// two flights of the same name apart ([`Dataset::add_training`]).
    pub flight_ids: std::collections::BTreeMap<String, (u64, String)>,
    /// Datasets whose training flights were added with [`Dataset::add_training`].
    pub extra: Vec<ExtraData>,
    /// The aircraft the flights flew (manifest `aircraft`; `None`: JSBSim's own, not recorded).
    pub aircraft: Option<hil_sim::dataset::AircraftRecord>,
    /// The datasets whose test flights replaced this one's ([`Dataset::test_on`]).
    pub test_from: Vec<ExtraData>,
    /// An `ood` dataset's cases: name and what it flies (manifest `config.ood_cases`).
    pub ood_cases: Vec<(String, String)>,
    /// The gyro-bias twins among the training flights ([`Dataset::add_gyro_bias_twins`]).
    pub gyro_bias_twins: Option<GyroBiasTwins>,
}

/// Training windows with a gyro bias ([`Dataset::add_gyro_bias_twins`]): how many, from which seed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GyroBiasTwins {
    pub flights: usize,
    pub seed: u64,
    /// Whose training reads them.
    pub angles: TwinAngles,
}

/// Which networks train on the gyro-bias twins ([`crate::pipeline::prepare_angle`]); the others
/// train on exactly the rows they would without them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum TwinAngles {
    #[default]
    Both,
    Alpha,
    Beta,
}

impl TwinAngles {
    pub fn alpha(self) -> bool {
        self != TwinAngles::Beta
    }
    pub fn beta(self) -> bool {
        self != TwinAngles::Alpha
    }
    /// For a provenance line: empty for both.
    pub fn describe(self) -> &'static str {
        match self {
            TwinAngles::Both => "",
            TwinAngles::Alpha => ", in α's training only",
            TwinAngles::Beta => ", in β's training only",
        }
    }
}

/// A gyro-bias twin's bias, rad/s: its size is drawn log-uniform between these (either sign).
/// Below the filter's gyro check (0.05-0.06 rad/s) the bias stays unflagged for as long as it
/// lasts; above it, the check flags it after about a second, and the networks read the raw gyro
/// all the while.
pub const TWIN_BIAS_RPS: [f64; 2] = [0.005, 0.3];
/// Biases per twin, each in a slot of its own along the flight (fewer in a short flight): every
/// bias is two steps (on, off), where an estimator that reads a gyro's change errs most.
pub const TWIN_BIASES: usize = 4;
/// A twin's bias lasts between these, s.
pub const TWIN_BIAS_S: [f64; 2] = [3.0, 15.0];
/// A twin's rows: from this long before its bias starts to [`TWIN_TAIL_S`] after it ends, s.
pub const TWIN_LEAD_S: f64 = 5.0;
/// See [`TWIN_LEAD_S`].
pub const TWIN_TAIL_S: f64 = 15.0;
/// A twin's first window starts at least this far into its flight (the filter has settled), so
/// its first bias at least [`TWIN_LEAD_S`] later, s.
pub const TWIN_SETTLED_S: f64 = 30.0;

/// Another dataset whose training flights joined this one's ([`Dataset::add_training`]).
#[derive(Debug, Clone)]
pub struct ExtraData {
    pub dir: PathBuf,
    pub manifest_sha256: String,
    pub preset: String,
    /// How many flights it added.
    pub flights: usize,
}

impl ExtraData {
    /// `DIR (preset P), manifest sha256 H`: where its flights came from, for a PROVENANCE.
    pub fn describe(&self) -> String {
        format!(
            "{} (preset {}), manifest sha256 {}",
            self.dir.display(),
            self.preset,
            self.manifest_sha256
        )
    }
}

/// How many training flights to hold out for validation: every `k`-th one, at least one when there
/// are two or more training flights.
pub fn validation_indices(n_train: usize, fraction: f64) -> Vec<usize> {
    if n_train < 2 {
        return Vec::new();
    }
    let n_val = ((n_train as f64 * fraction).round() as usize).clamp(1, n_train - 1);
    let step = n_train as f64 / n_val as f64;
    (0..n_val)
        .map(|k| (((k as f64 + 0.5) * step) as usize).min(n_train - 1))
        .collect()
}

impl Dataset {
    /// Loads every flight of `dir/manifest.json`. `val_fraction` of the training flights (by flight,
    /// evenly spread) become validation flights.
    pub fn load(dir: &Path, val_fraction: f64) -> Result<Dataset> {
        let ds = Dataset::load_any(dir, val_fraction)?;
        for role in [Role::Train, Role::Test] {
            if !ds.flights.iter().any(|f| f.role == role) {
                return Err(Error::Split(
                    dir.to_path_buf(),
                    format!("no {role:?} flight in the manifest"),
                ));
            }
        }
        Ok(ds)
    }

    /// [`Dataset::load`] without requiring training flights: a test-only dataset such as the `ood`
    /// preset's. A flight's manifest `faults` are applied to its frames before anything reads them.
    pub fn load_any(dir: &Path, val_fraction: f64) -> Result<Dataset> {
        let manifest = Manifest::read(dir)?;
        // A build trains and scores one aircraft: another description's flights are refused.
        if let Some(why) = manifest.other_aircraft() {
            return Err(Error::Split(dir.to_path_buf(), why));
        }
        let manifest_sha256 = sha256_file(&dir.join("manifest.json"))?;
        let train_names: Vec<&str> = manifest
            .flights
            .iter()
            .filter(|f| f.split == Split::Train)
            .map(|f| f.name.as_str())
            .collect();
        let val: Vec<&str> = validation_indices(train_names.len(), val_fraction)
            .into_iter()
            .map(|i| train_names[i])
            .collect();
        let mut flights = Vec::new();
        for mf in &manifest.flights {
            let role = match mf.split {
                Split::Train if val.contains(&mf.name.as_str()) => Role::Val,
                Split::Train => Role::Train,
                Split::Test => Role::Test,
            };
            let csv = manifest.read_flight(dir, &mf.file)?;
            // The rows read against the manifest's count: a CSV cut short or edited is refused
            // (its SHA-256 is not checked here: that would read every file a second time).
            if csv.samples.len() != mf.samples {
                return Err(Error::Split(
                    dir.join(&mf.file),
                    format!(
                        "{} rows, but the manifest lists {} samples for flight `{}`: the file was \
                         cut short or edited; regenerate the dataset (or, for a file edited on \
                         purpose, set its `samples` to {})",
                        csv.samples.len(),
                        mf.samples,
                        mf.name,
                        csv.samples.len()
                    ),
                ));
            }
            flights.push(flight_of(
                csv,
                &dir.join(&mf.file),
                &mf.name,
                role,
                &mf.faults()?,
            )?);
        }
        Ok(Dataset {
            dir: dir.to_path_buf(),
            manifest_sha256,
            preset: manifest.preset.clone(),
            suites: manifest.suites(),
            flights,
            flight_ids: manifest
                .flights
                .iter()
                .map(|f| (f.name.clone(), (f.seed, f.profile.clone())))
                .collect(),
            extra: Vec::new(),
            test_from: Vec::new(),
            gyro_bias_twins: None,
            aircraft: manifest.aircraft.clone(),
            ood_cases: manifest
                .config
                .get("ood_cases")
                .and_then(|c| serde_json::from_value(c.clone()).ok())
                .unwrap_or_default(),
        })
    }

    /// Adds every training flight of the dataset in `dir` (its test flights are left out) to this
    /// one's training flights. Validation and test stay this dataset's own flights, so models
    /// trained with and without the extra flights are selected and scored on the same flights.
    /// The other dataset must carry every sensor suite this one does. A flight this dataset holds
    /// already (the same name, seed and profile: one flight counted twice) is refused; another
    /// flight under a name held here (two campaigns name their flights alike) trains as
    /// `NAME~SEED`.
    pub fn add_training(&mut self, dir: &Path, mixed_aircraft: bool) -> Result<()> {
        let other = Dataset::load_any(dir, 0.0)?;
        for s in &self.suites {
            other.require(*s)?;
        }
        // Flights of two aircraft never train one model silently (both are this build's
        // description, `load_any` sees to that; their models may differ). A dataset written before
        // the aircraft was recorded flew JSBSim's own F-16, which a recorded one may name as well.
        let sha = |d: &Dataset| d.aircraft.as_ref().map(|a| a.model_xml_sha256.clone());
        let other_aircraft = matches!((sha(self), sha(&other)), (Some(a), Some(b)) if a != b);
        if other_aircraft && !mixed_aircraft {
            return Err(Error::Split(
                dir.to_path_buf(),
                format!(
                    "its flights flew {}, those of {} flew {}: train on one aircraft's flights (or pass --mixed-aircraft to train on several on purpose)",
                    hil_sim::dataset::AircraftRecord::describe(other.aircraft.as_ref()),
                    self.dir.display(),
                    hil_sim::dataset::AircraftRecord::describe(self.aircraft.as_ref())
                ),
            ));
        }
        // `load_any` holds one of them out for validation; here they all train. Another aircraft's
        // flights are other flights even under the same name: they carry the aircraft's hash.
        let tag = other
            .aircraft
            .as_ref()
            .filter(|_| other_aircraft)
            .map(|a| format!("@{}", a.model_xml_sha256.get(..8).unwrap_or("")))
            .unwrap_or_default();
        // Two campaigns name their flights alike (`train_high-alpha_00001`) and fly other ones: a
        // name this dataset holds with another seed or profile is another flight, named apart by
        // its seed. The same name, seed and profile are the same flight, refused below.
        let mut ids = Vec::new();
        let added: Vec<Flight> = other
            .flights
            .into_iter()
            .filter(|f| f.role != Role::Test)
            .map(|f| {
                let id = other.flight_ids.get(&f.name).cloned();
                let mut name = format!("{}{tag}", f.name);
                if let (Some(held), Some(id)) = (self.flight_ids.get(&name), &id)
                    && held != id
                {
                    name = format!("{name}~{}", id.0);
                }
                if let Some(id) = id {
                    ids.push((name.clone(), id));
                }
                Flight {
                    role: Role::Train,
                    name,
                    ..f
                }
            })
            .collect();
        self.check_new(
            dir,
            &added,
            "no training flight in the manifest to add",
            |f| {
                format!(
                    "flight `{}` (the same name, seed and profile) is already in {} or a dataset added before it (add a dataset of other flights)",
                    f.name,
                    self.dir.display()
                )
            },
        )?;
        self.extra.push(ExtraData {
            dir: dir.to_path_buf(),
            manifest_sha256: other.manifest_sha256,
            preset: other.preset,
            flights: added.len(),
        });
        self.flight_ids.extend(ids);
        self.flights.extend(added);
        Ok(())
    }

    /// Adds a gyro-bias twin of every training flight (validation and test flights stay as
    /// flown): the flight's frames with [`TWIN_BIASES`] gyro biases, each switched on and off
    /// again (a bias shift, `hil_sim::faults`), the estimator's features computed over the whole
    /// flight as in flight, and only the rows around each bias kept ([`TWIN_LEAD_S`],
    /// [`TWIN_TAIL_S`]). Each bias's gyro (p, q or r), size ([`TWIN_BIAS_RPS`], log-uniform, either
    /// sign), start (in its slot, the first at least [`TWIN_SETTLED_S`] in) and length
    /// ([`TWIN_BIAS_S`]) are drawn from `seed`, flight by flight in order; a flight too short for
    /// one slot gets no twin. The truth is the flight's:
    /// the networks learn that a gyro that steps without the forces that would turn the aircraft
    /// has not moved the air data. `angles` says whose networks train on them (a network it does
    /// not name trains on the rows it would without them). Returns how many twins were added.
    pub fn add_gyro_bias_twins(&mut self, seed: u64, angles: TwinAngles) -> usize {
        use estimator_core::Channel;
        use hil_sim::faults::FaultKind;
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut twins = Vec::new();
        // Each bias has a slot of its own: its lead, its longest length and its tail.
        let slot_s = TWIN_LEAD_S + TWIN_BIAS_S[1] + TWIN_TAIL_S;
        for f in self.flights.iter().filter(|f| f.role == Role::Train) {
            let (Some(&t0), Some(&t1)) = (f.time_s.first(), f.time_s.last()) else {
                continue;
            };
            let span = t1 - t0 - TWIN_SETTLED_S;
            let n = TWIN_BIASES.min((span / slot_s).floor().max(0.0) as usize);
            if n == 0 {
                continue;
            }
            let slot_s = span / n as f64;
            let faults: Vec<Fault> = (0..n)
                .map(|k| {
                    let channel =
                        [Channel::GyroP, Channel::GyroQ, Channel::GyroR][rng.random_range(0..3)];
                    let size =
                        (rng.random_range(TWIN_BIAS_RPS[0].ln()..TWIN_BIAS_RPS[1].ln())).exp();
                    let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
                    let slot = t0 + TWIN_SETTLED_S + k as f64 * slot_s;
                    let duration_s = rng.random_range(TWIN_BIAS_S[0]..TWIN_BIAS_S[1]);
                    // Its window, lead to tail at the longest length, stays in the slot.
                    // (`max`: a slot of exactly the minimum length may round one ulp short.)
                    let latest =
                        (slot + slot_s - TWIN_BIAS_S[1] - TWIN_TAIL_S).max(slot + TWIN_LEAD_S);
                    let start_s = rng.random_range(slot + TWIN_LEAD_S..=latest);
                    Fault {
                        kind: FaultKind::Bias(
                            channel,
                            (sign * size / channel.lsb()).round() as i32,
                        ),
                        start_s,
                        duration_s,
                    }
                })
                .collect();
            let mut frames = f.frames.clone();
            hil_sim::faults::apply(&faults, &mut frames, &f.time_s);
            let features = features_in_flight(&frames);
            let keep = |t: f64| {
                faults.iter().any(|b| {
                    t >= b.start_s - TWIN_LEAD_S && t < b.start_s + b.duration_s + TWIN_TAIL_S
                })
            };
            let rows: Vec<usize> = (0..f.len()).filter(|&i| keep(f.time_s[i])).collect();
            let pick = |v: &[f64]| rows.iter().map(|&i| v[i]).collect::<Vec<f64>>();
            let named: String = faults.iter().map(|b| format!("~{b}")).collect();
            twins.push(Flight {
                name: format!("{}{named}", f.name),
                role: Role::Train,
                time_s: pick(&f.time_s),
                frames: rows.iter().map(|&i| frames[i]).collect(),
                features: rows.iter().map(|&i| features[i]).collect(),
                truth: std::array::from_fn(|k| pick(&f.truth[k])),
                qbar_pa: pick(&f.qbar_pa),
                gyro_bias_twin: true,
            });
        }
        let n = twins.len();
        self.flights.extend(twins);
        self.gyro_bias_twins = Some(GyroBiasTwins {
            flights: n,
            seed,
            angles,
        });
        n
    }

    /// Scores on the test flights of the dataset at `dir` instead of this one's: the flights of the
    /// aircraft really flown, when the model trains on another one's (a calibrated aircraft, its
    /// airframe's flight-tested variant). Training and validation flights stay this dataset's. The
    /// first call drops this dataset's test flights, later ones add more; each flight is named
    /// `DATASET/FLIGHT` after its dataset's directory.
    pub fn test_on(&mut self, dir: &Path) -> Result<()> {
        let other = Dataset::load_any(dir, 0.0)?;
        for s in &self.suites {
            other.require(*s)?;
        }
        let label = dir.file_name().map_or_else(
            || dir.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        let tests: Vec<Flight> = other
            .flights
            .into_iter()
            .filter(|f| f.role == Role::Test)
            .map(|f| Flight {
                name: format!("{label}/{}", f.name),
                ..f
            })
            .collect();
        self.check_new(
            dir,
            &tests,
            "no test flight in the manifest to score on",
            |f| format!("test flight `{}` is given twice", f.name),
        )?;
        if self.test_from.is_empty() {
            self.flights.retain(|f| f.role != Role::Test);
        }
        self.test_from.push(ExtraData {
            dir: dir.to_path_buf(),
            manifest_sha256: other.manifest_sha256,
            preset: other.preset,
            flights: tests.len(),
        });
        self.flights.extend(tests);
        Ok(())
    }

    /// Refuses flights from `dir` to join this dataset when there are none (`none` says which) or
    /// when one has the name of a flight already here (`clash` says so).
    fn check_new(
        &self,
        dir: &Path,
        flights: &[Flight],
        none: &str,
        clash: impl Fn(&Flight) -> String,
    ) -> Result<()> {
        if flights.is_empty() {
            return Err(Error::Split(dir.to_path_buf(), none.into()));
        }
        match flights
            .iter()
            .find(|f| self.flights.iter().any(|g| g.name == f.name))
        {
            Some(f) => Err(Error::Split(dir.to_path_buf(), clash(f))),
            None => Ok(()),
        }
    }

    /// Refuses a dataset that does not carry `suite`'s channels.
    pub fn require(&self, suite: estimator_core::Suite) -> Result<()> {
        if self.suites.contains(&suite) {
            return Ok(());
        }
        Err(Error::DatasetSuite {
            dir: self.dir.clone(),
            carries: self.suites.iter().map(|s| s.name().to_string()).collect(),
            suite: suite.name(),
        })
    }

    pub fn flights(&self, role: Role) -> impl Iterator<Item = &Flight> {
        self.flights.iter().filter(move |f| f.role == role)
    }

    /// Lets the training flights' frames go, keeping their features and truth: training reads
    /// only those, and a frame with its 120 Hz sub-samples (420 bytes) is a third of a row's
    /// memory. Validation and test flights keep theirs: the compiled-in estimator and the export's
    /// vectors step over them.
    pub fn drop_training_frames(&mut self) {
        for f in self.flights.iter_mut().filter(|f| f.role == Role::Train) {
            f.frames = Vec::new();
        }
        release_freed_memory();
    }

    /// Lets the training flights' features go as well (824 bytes a row), once the networks'
    /// matrices are made of them ([`crate::pipeline::prepare_angle`]); their times and truth stay,
    /// so [`Flight::len`] and the row counts hold.
    pub fn drop_training_features(&mut self) {
        for f in self.flights.iter_mut().filter(|f| f.role == Role::Train) {
            f.frames = Vec::new();
            f.features = Vec::new();
        }
        release_freed_memory();
    }

    pub fn rows(&self, role: Role) -> usize {
        self.flights(role).map(|f| f.len()).sum()
    }

    /// Rows the models learn from: training plus validation flights (never the test flights).
    pub fn training_rows(&self) -> usize {
        self.rows(Role::Train) + self.rows(Role::Val)
    }
}

/// Row stride that keeps at most `max_rows` of `total` rows, evenly spread (every row when
/// `max_rows >= total`).
pub fn stride(total: usize, max_rows: usize) -> usize {
    total.div_ceil(max_rows.max(1)).max(1)
}

/// At most `max_rows` rows of `flights`, evenly spread, in order, as (flight, row index): row `k` of
/// the flights' concatenation is kept when `k` is a multiple of [`stride`]`(total, max_rows)`.
pub fn spread_rows<'a>(flights: &[&'a Flight], max_rows: usize) -> Vec<(&'a Flight, usize)> {
    let total: usize = flights.iter().map(|f| f.len()).sum();
    flights
        .iter()
        .flat_map(|&f| (0..f.len()).map(move |i| (f, i)))
        .step_by(stride(total, max_rows))
        .collect()
}

/// One flight CSV as read from `path`: applies `faults` to its frames (`hil_sim::faults`, none for
/// a healthy flight) and derives the estimator's inputs from them.
fn flight_of(
    csv: hil_sim::dataset::Flight,
    path: &Path,
    name: &str,
    role: Role,
    faults: &[Fault],
) -> Result<Flight> {
    // Training and scoring need the truth on every row: a NaN would turn every mean into NaN.
    for (k, s) in csv.samples.iter().enumerate() {
        let targets = Target::ALL.map(|t| (t.column(), t.of(&s.truth)));
        for (name, v) in targets.into_iter().chain([("qbar_pa", s.truth.qbar_pa)]) {
            if !v.is_finite() {
                return Err(Error::Split(
                    path.to_path_buf(),
                    format!(
                        "line {}: the truth column `{name}` is `{v}`; every row of a training or evaluation dataset needs it (regenerate the flight, or drop the row; `hil-sim run --dataset` scores a log without truth)",
                        k + 2
                    ),
                ));
            }
        }
    }
    let mut frames: Vec<SensorFrame> = hil_sim::frames::flight_frames(&csv).collect();
    let times: Vec<f64> = csv.samples.iter().map(|s| s.time_s).collect();
    hil_sim::faults::apply(faults, &mut frames, &times);
    let mut fl = Flight {
        name: name.to_string(),
        role,
        time_s: Vec::with_capacity(csv.samples.len()),
        frames: Vec::with_capacity(csv.samples.len()),
        features: features_in_flight(&frames),
        truth: Default::default(),
        qbar_pa: Vec::with_capacity(csv.samples.len()),
        gyro_bias_twin: false,
    };
    for (frame, sample) in frames.into_iter().zip(&csv.samples) {
        fl.frames.push(frame);
        fl.time_s.push(sample.time_s);
        fl.qbar_pa.push(sample.truth.qbar_pa);
        for t in Target::ALL {
            fl.truth[t as usize].push(t.of(&sample.truth));
        }
    }
    Ok(fl)
}

/// The estimator's features of a flight's frames through its own feature state: the features at
/// frame i see frames 0..i, as in flight, and the air-data filter runs over the flight in order
/// (its outputs are candidate features; on a table1 flight it has no input and they stay 0).
pub fn features_in_flight(frames: &[SensorFrame]) -> Vec<FeatureValues> {
    let mut state = FeatureState::new(true);
    frames.iter().map(|f| state.next(f)).collect()
}

/// The float value of a feature the model is trained on: the quantized raw value times its LSB.
pub fn feature_si(v: &FeatureValues, f: estimator_core::Feature) -> f64 {
    v.get(f) as f64 * f.lsb()
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimator_core::{CHANNELS, Channel};

    /// A flight of `seconds` at 20 Hz, every frame the default one, its truth α the time.
    fn still_flight(name: &str, role: Role, seconds: usize) -> Flight {
        let n = seconds * 20;
        let time_s: Vec<f64> = (0..n).map(|k| k as f64 * 0.05).collect();
        let frame = SensorFrame {
            valid: estimator_core::channels::ALL_VALID,
            ..SensorFrame::default()
        };
        let frames = vec![frame; n];
        Flight {
            name: name.to_string(),
            role,
            features: features_in_flight(&frames),
            frames,
            truth: std::array::from_fn(|_| time_s.clone()),
            qbar_pa: vec![1.0; n],
            time_s,
            gyro_bias_twin: false,
        }
    }

    #[test]
    fn dropping_the_training_rows_keeps_every_count_and_the_other_flights_rows() {
        let mut ds = Dataset {
            dir: PathBuf::from("x"),
            manifest_sha256: String::new(),
            preset: "test".into(),
            suites: Vec::new(),
            flights: vec![
                still_flight("a", Role::Train, 30),
                still_flight("v", Role::Val, 20),
                still_flight("t", Role::Test, 10),
            ],
            flight_ids: Default::default(),
            extra: Vec::new(),
            aircraft: None,
            test_from: Vec::new(),
            ood_cases: Vec::new(),
            gyro_bias_twins: None,
        };
        let rows = |d: &Dataset| Role::ALL.map(|r| d.rows(r));
        let before = rows(&ds);
        ds.drop_training_frames();
        assert_eq!(rows(&ds), before);
        // Role::ALL is test, train, validation.
        assert_eq!(before, [200, 600, 400]);
        let frames = |name: &str| {
            ds.flights
                .iter()
                .find(|f| f.name == name)
                .map(|f| f.frames.len())
        };
        assert_eq!(frames("a"), Some(0));
        assert_eq!(frames("v"), Some(400));
        assert_eq!(frames("t"), Some(200));
        let train = ds
            .flights(Role::Train)
            .next()
            .map(|f| (f.len(), f.features.len()));
        assert_eq!(train, Some((600, 600)));
        ds.drop_training_features();
        assert_eq!(rows(&ds), before);
        let kept = |r: Role| {
            ds.flights(r)
                .next()
                .map(|f| (f.len(), f.frames.len(), f.features.len()))
        };
        assert_eq!(kept(Role::Train), Some((600, 0, 0)));
        assert_eq!(kept(Role::Val), Some((400, 400, 400)));
        assert_eq!(kept(Role::Test), Some((200, 200, 200)));
    }

    #[test]
    fn gyro_bias_twins_bias_the_gyros_in_windows_of_each_training_flight() {
        use estimator_core::Channel;
        let ds = |flights| Dataset {
            dir: PathBuf::from("x"),
            manifest_sha256: String::new(),
            preset: "test".into(),
            suites: Vec::new(),
            flights,
            flight_ids: Default::default(),
            extra: Vec::new(),
            aircraft: None,
            test_from: Vec::new(),
            ood_cases: Vec::new(),
            gyro_bias_twins: None,
        };
        let flights = || {
            vec![
                still_flight("a", Role::Train, 300),
                still_flight("b", Role::Train, 300),
                still_flight("short", Role::Train, 50),
                still_flight("c", Role::Train, 100),
                still_flight("v", Role::Val, 300),
                still_flight("t", Role::Test, 300),
            ]
        };
        let (mut one, mut two) = (ds(flights()), ds(flights()));
        assert_eq!(one.add_gyro_bias_twins(7, TwinAngles::Beta), 3);
        two.add_gyro_bias_twins(7, TwinAngles::Both);
        assert_eq!(
            one.gyro_bias_twins,
            Some(GyroBiasTwins {
                flights: 3,
                seed: 7,
                angles: TwinAngles::Beta,
            })
        );
        // The twins, and only they, are marked: an angle trained without them sees the others.
        let marked: Vec<bool> = one.flights.iter().map(|f| f.gyro_bias_twin).collect();
        assert_eq!(marked, [vec![false; 6], vec![true; 3]].concat());
        assert!(TwinAngles::Both.alpha() && TwinAngles::Both.beta());
        assert!(!TwinAngles::Beta.alpha() && TwinAngles::Beta.beta());
        assert!(TwinAngles::Alpha.alpha() && !TwinAngles::Alpha.beta());
        let names = |d: &Dataset| d.flights.iter().map(|f| f.name.clone()).collect::<Vec<_>>();
        assert_eq!(names(&one), names(&two), "the draw is the seed's");
        assert_eq!(one.flights.len(), 9);
        for (kept, given) in one.flights.iter().zip(flights()) {
            assert_eq!((&kept.name, &kept.features), (&given.name, &given.features));
        }
        let gyros = [Channel::GyroP, Channel::GyroQ, Channel::GyroR];
        for twin in &one.flights[6..] {
            assert_eq!(twin.role, Role::Train);
            let (of, named) = twin.name.split_once('~').unwrap();
            let faults: Vec<Fault> = named.split('~').map(|b| b.parse().unwrap()).collect();
            // A 300-s flight holds TWIN_BIASES slots of at least 35 s after its first 30 s; the
            // 100-s one holds one.
            let (want, frames_n) = match of {
                "a" | "b" => (TWIN_BIASES, 6000),
                "c" => (1, 2000),
                _ => panic!(
                    "{}: a twin of a flight too short or not a training flight",
                    twin.name
                ),
            };
            assert_eq!(faults.len(), want, "{}", twin.name);
            let end_s = (frames_n - 1) as f64 * 0.05;
            let last = faults.last().unwrap();
            assert!(last.start_s + last.duration_s + TWIN_TAIL_S <= end_s + 1e-9);
            for (b, next) in faults.iter().zip(faults.iter().skip(1)) {
                assert!(b.start_s + b.duration_s + TWIN_TAIL_S <= next.start_s - TWIN_LEAD_S);
            }
            for b in &faults {
                let hil_sim::faults::FaultKind::Bias(c, raw) = b.kind else {
                    panic!("{}", twin.name)
                };
                assert!(gyros.contains(&c));
                let size = (raw as f64 * c.lsb()).abs();
                assert!((TWIN_BIAS_RPS[0] - 1e-6..=TWIN_BIAS_RPS[1] + 1e-6).contains(&size));
                assert!(b.start_s >= TWIN_SETTLED_S + TWIN_LEAD_S);
                assert!((TWIN_BIAS_S[0]..=TWIN_BIAS_S[1]).contains(&b.duration_s));
            }
            let kept = |t: f64| {
                faults.iter().any(|b| {
                    t >= b.start_s - TWIN_LEAD_S && t < b.start_s + b.duration_s + TWIN_TAIL_S
                })
            };
            assert!(twin.time_s.iter().all(|&t| kept(t)));
            assert_eq!(
                twin.len(),
                (0..frames_n).filter(|&k| kept(k as f64 * 0.05)).count()
            );
            assert_eq!(
                twin.truth(Target::AlphaDeg),
                &twin.time_s[..],
                "the flight's truth"
            );
            assert_eq!(
                (twin.features.len(), twin.frames.len()),
                (twin.len(), twin.time_s.len())
            );
            // Its features are those of the whole faulted flight, computed as in flight, at its
            // rows; while a bias is on they are not the clean flight's.
            let source = one.flights.iter().find(|f| f.name == of).unwrap();
            let mut frames = source.frames.clone();
            hil_sim::faults::apply(&faults, &mut frames, &source.time_s);
            let whole = features_in_flight(&frames);
            let mut biased_rows = 0;
            for (f, &t) in twin.features.iter().zip(&twin.time_s) {
                let row = (t / 0.05).round() as usize;
                assert_eq!(f, &whole[row], "{} at {t} s", twin.name);
                if faults.iter().any(|b| b.active(t)) {
                    biased_rows += 1;
                    assert_ne!(
                        f, &source.features[row],
                        "{} at {t} s: not biased",
                        twin.name
                    );
                }
            }
            assert!(biased_rows > 0);
            for (f, &t) in twin.frames.iter().zip(&twin.time_s) {
                for c in gyros {
                    let want: i32 = faults
                        .iter()
                        .filter(|b| b.active(t))
                        .map(|b| match b.kind {
                            hil_sim::faults::FaultKind::Bias(bc, raw) if bc == c => raw,
                            _ => 0,
                        })
                        .sum();
                    assert_eq!(f.get(c), want, "{} at {t} s", twin.name);
                }
            }
        }
    }

    #[test]
    fn validation_is_held_out_by_flight_and_never_everything() {
        assert!(validation_indices(1, 0.2).is_empty());
        assert_eq!(validation_indices(2, 0.2), vec![1]);
        let v = validation_indices(20, 0.15);
        assert_eq!(v.len(), 3);
        assert!(v.windows(2).all(|w| w[0] < w[1]));
        assert!(v.iter().all(|&i| i < 20));
    }

    /// A dataset in a fresh directory: `(name, split)` flights of three zero samples each, the
    /// current format and every suite unless `suites` says otherwise.
    fn tiny_dataset(tag: &str, flights: &[(&str, Split)], suites: &[&str]) -> PathBuf {
        tiny_dataset_seeded(tag, flights, suites, 0)
    }

    /// [`tiny_dataset`] whose flights have the seed `seed` (other flights under the same names).
    fn tiny_dataset_seeded(
        tag: &str,
        flights: &[(&str, Split)],
        suites: &[&str],
        seed: u64,
    ) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("trainer-data-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let samples = (0..3)
            .map(|k| hil_sim::dataset::Sample {
                time_s: k as f64 * 0.05,
                truth: Default::default(),
                sensed: [0.0; CHANNELS],
                sub: hil_sim::dataset::NO_SUBSAMPLES,
            })
            .collect();
        let csv = hil_sim::dataset::Flight {
            name: String::new(),
            samples,
            cut: None,
            zones: None,
            engine: Vec::new(),
        };
        let entries = flights
            .iter()
            .map(|&(name, split)| {
                let file = format!("{name}.csv");
                let sha256 = csv.write_csv(&dir.join(&file)).unwrap();
                hil_sim::dataset::FlightEntry {
                    file,
                    name: name.into(),
                    split,
                    profile: "gentle".into(),
                    seed,
                    duration_s: 0.1,
                    samples: 3,
                    sha256,
                    cut: None,
                    zones: None,
                    faults: Vec::new(),
                    boom: None,
                }
            })
            .collect();
        Manifest {
            format: Manifest::FORMAT,
            suites: suites.iter().map(|s| s.to_string()).collect(),
            preset: tag.into(),
            jsbsim_version: String::new(),
            git_rev: String::new(),
            config: serde_json::Value::Null,
            flights: entries,
            files: Default::default(),
            aircraft: None,
        }
        .write(&dir)
        .unwrap();
        dir
    }

    /// A CSV with fewer or more rows than its manifest's `samples` is refused when the dataset is
    /// read, naming the flight and both counts; so is a manifest whose flight is outside the
    /// directory or named twice (`Manifest::read`).
    #[test]
    fn a_flight_whose_rows_are_not_its_samples_is_refused() {
        use Split::{Test, Train};
        let dir = tiny_dataset("rows", &[("a0", Train), ("at", Test)], &["table1", "egi"]);
        assert!(Dataset::load_any(&dir, 0.0).is_ok());
        let csv = dir.join("at.csv");
        let text = std::fs::read_to_string(&csv).unwrap();
        let cut: Vec<&str> = text.lines().take(3).collect();
        std::fs::write(&csv, cut.join("\n") + "\n").unwrap();
        let e = Dataset::load_any(&dir, 0.0).unwrap_err();
        assert!(
            matches!(&e, Error::Split(p, m) if *p == csv && m.starts_with("2 rows, but the manifest lists 3 samples for flight `at`")),
            "{e}"
        );
        let mut m = Manifest::read(&dir).unwrap();
        m.flights[1].file = "../at.csv".into();
        m.write(&dir).unwrap();
        let e = Dataset::load_any(&dir, 0.0).unwrap_err().to_string();
        assert!(e.contains("is not inside the dataset directory"), "{e}");
        m.flights[1].file = "a0.csv".into();
        m.flights[1].name = "a0".into();
        m.write(&dir).unwrap();
        let e = Dataset::load_any(&dir, 0.0).unwrap_err().to_string();
        assert!(e.contains("flight `a0` is listed twice"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// Sets the `aircraft` of the manifest in `dir`.
    fn fly_on(dir: &Path, sha: &str) {
        let mut m = Manifest::read(dir).unwrap();
        m.aircraft = Some(hil_sim::dataset::AircraftRecord {
            dir: Some(format!("airframes/{sha}")),
            name: "f16".into(),
            model_xml_sha256: sha.repeat(64 / sha.len()),
        });
        m.write(dir).unwrap();
    }

    #[test]
    fn flights_of_another_aircraft_are_refused() {
        use Split::{Test, Train};
        let both = ["table1", "egi"];
        let main = tiny_dataset(
            "air-main",
            &[("a0", Train), ("a1", Train), ("at", Test)],
            &both,
        );
        fly_on(&main, "a");
        let other = tiny_dataset("air-other", &[("b0", Train)], &both);
        fly_on(&other, "b");
        let same = tiny_dataset("air-same", &[("c0", Train)], &both);
        fly_on(&same, "a");
        let mut ds = Dataset::load(&main, 0.34).unwrap();
        match ds.add_training(&other, false) {
            Err(Error::Split(_, msg)) => {
                assert!(msg.contains("train on one aircraft's flights"), "{msg}")
            }
            r => panic!("flights of another aircraft were added: {:?}", r.err()),
        }
        ds.add_training(&same, false).unwrap();
        // On purpose (domain randomisation) they are accepted, and another aircraft's flight of
        // the same name is another flight: it carries the aircraft's hash.
        ds.add_training(&other, true).unwrap();
        let twin = tiny_dataset("air-twin", &[("a0", Train)], &both);
        fly_on(&twin, "b");
        ds.add_training(&twin, true).unwrap();
        let names: Vec<&str> = ds.flights.iter().map(|f| f.name.as_str()).collect();
        assert!(
            names.contains(&"a0") && names.contains(&"a0@bbbbbbbb"),
            "{names:?}"
        );
        // Another flight of that aircraft under the same name (another campaign: its seed) trains
        // too, named apart by the seed after the aircraft's hash; the same flight again is refused.
        let again = tiny_dataset_seeded("air-again", &[("a0", Train)], &both, 5);
        fly_on(&again, "b");
        ds.add_training(&again, true).unwrap();
        assert!(ds.flights.iter().any(|f| f.name == "a0@bbbbbbbb~5"));
        assert!(matches!(
            ds.add_training(&again, true),
            Err(Error::Split(..))
        ));
        // Another description's dataset is refused outright: this build evaluates its own
        // aircraft's model.
        let name = estimator_core::aircraft::descriptions()
            .find(|n| *n != estimator_core::aircraft::AIRCRAFT.name)
            .unwrap();
        let elsewhere = tiny_dataset("air-elsewhere", &[("d0", Train), ("dt", Test)], &both);
        let mut m = Manifest::read(&elsewhere).unwrap();
        m.aircraft = Some(hil_sim::dataset::AircraftRecord {
            name: name.into(),
            dir: None,
            model_xml_sha256: "c".repeat(64),
        });
        m.write(&elsewhere).unwrap();
        match Dataset::load(&elsewhere, 0.5) {
            Err(Error::Split(_, msg)) => {
                assert!(msg.contains(&format!("ESTIMATOR_AIRCRAFT={name}")), "{msg}")
            }
            r => panic!("another aircraft's dataset loaded: {:?}", r.err()),
        }
        for d in [main, other, same, twin, again, elsewhere] {
            let _ = std::fs::remove_dir_all(d);
        }
    }

    #[test]
    fn extra_training_flights_train_and_leave_validation_and_test_alone() {
        use Split::{Test, Train};
        let both = ["table1", "egi"];
        let main = tiny_dataset(
            "main",
            &[("a0", Train), ("a1", Train), ("a2", Train), ("at", Test)],
            &both,
        );
        let mut ds = Dataset::load(&main, 0.34).unwrap();
        let roles =
            |ds: &Dataset, role| ds.flights(role).map(|f| f.name.clone()).collect::<Vec<_>>();
        let (val, test) = (roles(&ds, Role::Val), roles(&ds, Role::Test));
        assert_eq!(val.len(), 1);

        let extra = tiny_dataset(
            "extra",
            &[("b0", Train), ("b1", Train), ("bt", Test)],
            &both,
        );
        ds.add_training(&extra, false).unwrap();
        // Both of its training flights train (none held out), its test flight is not taken, and
        // this dataset's validation and test flights are what they were.
        let train = roles(&ds, Role::Train);
        assert!(train.contains(&"b0".to_string()) && train.contains(&"b1".to_string()));
        assert_eq!(train.len(), 4);
        assert_eq!(roles(&ds, Role::Val), val);
        assert_eq!(roles(&ds, Role::Test), test);
        assert_eq!(ds.extra.len(), 1);
        assert_eq!(
            (ds.extra[0].flights, ds.extra[0].preset.as_str()),
            (2, "extra")
        );

        // The same flights twice, or a dataset without this one's suites, is refused.
        assert!(matches!(
            ds.add_training(&extra, false),
            Err(Error::Split(..))
        ));
        let t1 = tiny_dataset("t1", &[("c0", Train)], &["table1"]);
        assert!(matches!(
            ds.add_training(&t1, false),
            Err(Error::DatasetSuite { suite: "egi", .. })
        ));
        assert_eq!(ds.flights.len(), 6);
        // Another campaign names its flights alike and flies other ones: a flight of another seed
        // under a name already here trains too, named apart by its seed; the same flight again
        // (same name, seed and profile, whatever its bytes) is still refused.
        let other = tiny_dataset_seeded("other", &[("b0", Train), ("b9", Train)], &both, 7);
        ds.add_training(&other, false).unwrap();
        let renamed = "b0~7".to_string();
        assert!(
            roles(&ds, Role::Train).contains(&renamed),
            "{:?}",
            roles(&ds, Role::Train)
        );
        assert_eq!(ds.flights.len(), 8);
        assert!(matches!(
            ds.add_training(&other, false),
            Err(Error::Split(..))
        ));
        for d in [main, extra, t1, other] {
            let _ = std::fs::remove_dir_all(d);
        }
    }

    #[test]
    fn rows_become_frames_exactly_like_from_si() {
        let mut si = [0.0; CHANNELS];
        si[Channel::GpsSpeed.index()] = 201.2345;
        si[Channel::AccelZ.index()] = -9.80665;
        let sample = hil_sim::dataset::Sample {
            time_s: 12.3456,
            truth: Default::default(),
            sensed: si,
            sub: hil_sim::dataset::NO_SUBSAMPLES,
        };
        let f = hil_sim::frames::sample_to_frame(70_000usize as u16, &sample);
        assert_eq!(f, SensorFrame::from_si(70_000u32 as u16, 12_346, &si));
        assert_eq!(f.get(Channel::GpsSpeed), 201_235); // 201.2345 m/s → mm/s, rounded
    }
}
