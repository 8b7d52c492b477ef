//! The plant: JSBSim flying the build's aircraft (its description's model; the F-16), stepped by a
//! pinned Python bridge (`bridge/jsbsim_bridge.py`).
//!
//! The bridge only loads scripts, steps and reads the watched properties; everything else (which
//! properties, sampling, sensors, cutting a bad flight) is here. [`fly_script`] runs a JSBSim runscript to its
//! end at the script's own dt (which must be 120 Hz), feeding the sensor models every step and keeping
//! truth + sensed values at 20 Hz. A script is flown exactly as stock JSBSim flies it
//! (`load_script(script, 0.0, initfile)`): same dt, same clock, same event instants, so truth is
//! bit-identical to a stock run (`hil-sim/tests/data_stock_replay.rs`).

use std::io::{BufRead, BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::sync::{Arc, Mutex};

use crate::flight::{Every, Truth};
pub use crate::flight::{FT_TO_M, LB_TO_KG, SAMPLE_HZ, SIM_HZ, STEPS_PER_SAMPLE};
use estimator_core::aircraft::AIRCRAFT;

/// How far a script's rate may be from [`SIM_HZ`] (relative) and still be flown: the stock scripts
/// write `dt="0.00833333"` (120.000005 Hz), which the 120 Hz sensor models and the 6-step decimation
/// treat as 120 Hz with a timing error of 5e-7; anything further is refused.
pub const SIM_HZ_TOLERANCE: f64 = 1e-4;
/// Below this height above ground an airborne flight counts as having hit the ground.
pub const GROUND_CUT_AGL_FT: f64 = 10.0;
/// A flight counts as airborne once it has been this high above the ground.
pub(crate) const AIRBORNE_AGL_FT: f64 = 50.0;

const BRIDGE_SOURCE: &str = include_str!("../bridge/jsbsim_bridge.py");

/// Everything that can go wrong between a script file and a flight.
#[derive(Debug, thiserror::Error)]
pub enum PlantError {
    #[error(
        "the JSBSim bridge cannot start with {python}: {why}. Run `scripts/bootstrap` to create the \
         pinned .venv with jsbsim, or point HIL_PYTHON at a Python that has jsbsim==1.3.3"
    )]
    BridgeUnavailable { python: PathBuf, why: String },
    #[error("cannot read JSBSim script {path}: {source}")]
    ScriptUnreadable {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path} is not a JSBSim runscript: {why}")]
    NotAScript { path: PathBuf, why: String },
    #[error(
        "{0} is not a JSBSim aircraft directory: it has no {model}/{model}.xml (make one with scripts/airframe-variant, or copy JSBSim's aircraft/{model} into it)",
        model = AIRCRAFT.jsbsim_model
    )]
    NoAircraft(PathBuf),
    #[error(
        "{path} is a script for aircraft `{aircraft}`; this build flies the JSBSim `{model}` ({title}, aircraft/{name}.toml)",
        model = AIRCRAFT.jsbsim_model,
        title = AIRCRAFT.title,
        name = AIRCRAFT.name
    )]
    WrongAircraft { path: PathBuf, aircraft: String },
    #[error("JSBSim rejected {path}: {message}")]
    ScriptRejected { path: PathBuf, message: String },
    #[error(
        "{path} runs at dt = {dt_s} s ({hz:.4} Hz); hil-sim's sensor models and its 20 Hz frames \
         need {SIM_HZ} Hz: set `<run ... dt=\"0.008333333333333333\">` (1/120 s) in the script"
    )]
    UnsupportedRate { path: PathBuf, dt_s: f64, hz: f64 },
    #[error("JSBSim bridge error in `{command}`: {message}")]
    Bridge { command: String, message: String },
    #[error("JSBSim bridge died ({why}); its last messages:\n{stderr_tail}")]
    BridgeDied { why: String, stderr_tail: String },
}

impl PlantError {
    /// JSBSim could not trim the aircraft at the script's initial condition (its `TrimFailureError`).
    pub fn is_trim_failure(&self) -> bool {
        matches!(self, PlantError::Bridge { message, .. } if message.contains("TrimFailure"))
    }
}

/// Which Python runs the bridge: `HIL_PYTHON`, else the workspace's `.venv` made by `scripts/bootstrap`.
pub fn python_path() -> PathBuf {
    match std::env::var_os("HIL_PYTHON") {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ => Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join(".venv")
            .join("bin")
            .join("python"),
    }
}

/// A running JSBSim bridge process.
pub struct Plant {
    child: Child,
    stdin: BufWriter<ChildStdin>,
    stdout: BufReader<ChildStdout>,
    stderr_tail: Arc<Mutex<String>>,
    watched: usize,
    version: String,
    aircraft_xml: PathBuf,
}

/// A JSBSim aircraft directory as `--aircraft-dir` names it: absolute, holding `MODEL/MODEL.xml`
/// for the aircraft description's JSBSim model (`f16/f16.xml`).
pub fn aircraft_dir(dir: &Path) -> Result<PathBuf, PlantError> {
    let model = AIRCRAFT.jsbsim_model;
    let xml = dir.join(model).join(format!("{model}.xml"));
    if !xml.is_file() {
        return Err(PlantError::NoAircraft(dir.to_path_buf()));
    }
    std::path::absolute(dir).map_err(|e| PlantError::BridgeUnavailable {
        python: python_path(),
        why: format!("cannot make {} absolute: {e}", dir.display()),
    })
}

/// `--aircraft-dir`, on every command that flies.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct AircraftArgs {
    /// A JSBSim aircraft directory holding MODEL/MODEL.xml (and what it includes) for the build's
    /// aircraft (its description's JSBSim model, e.g. f16/f16.xml): the model to fly, loaded as
    /// stock JSBSim's set_aircraft_path loads it (scripts/airframe-variant writes one) [default:
    /// the jsbsim package's own].
    #[arg(long = "aircraft-dir", value_name = "DIR")]
    pub dir: Option<PathBuf>,
}

impl AircraftArgs {
    /// The directory, checked and absolute.
    pub fn dir(&self) -> Result<Option<PathBuf>, PlantError> {
        self.dir.as_deref().map(aircraft_dir).transpose()
    }
}

impl Plant {
    /// Starts the bridge on JSBSim's own F-16 and waits for its hello (the JSBSim version).
    pub fn spawn() -> Result<Plant, PlantError> {
        Plant::spawn_for(None)
    }

    /// Starts the bridge on this build's aircraft in a JSBSim aircraft directory
    /// (`DIR/MODEL/MODEL.xml`, loaded as stock JSBSim's `set_aircraft_path(DIR)` loads it), or in
    /// JSBSim's own with `None`.
    pub fn spawn_for(aircraft: Option<&Path>) -> Result<Plant, PlantError> {
        let aircraft = aircraft.map(aircraft_dir).transpose()?;
        let python = python_path();
        let unavailable = |why: String| PlantError::BridgeUnavailable {
            python: python.clone(),
            why,
        };
        if !python.exists() {
            return Err(unavailable("that file does not exist".into()));
        }
        let mut child = Command::new(&python)
            .arg("-u")
            .arg("-c")
            .arg(BRIDGE_SOURCE)
            // The aircraft directory ("" for JSBSim's own) and the model, whose file the bridge reports.
            .arg(
                aircraft
                    .as_deref()
                    .map_or(std::ffi::OsStr::new(""), Path::as_os_str),
            )
            .arg(AIRCRAFT.jsbsim_model)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| unavailable(e.to_string()))?;
        let (Some(stdin), Some(stdout), Some(stderr)) =
            (child.stdin.take(), child.stdout.take(), child.stderr.take())
        else {
            let _ = child.kill();
            return Err(unavailable("no pipes to the child process".into()));
        };
        // JSBSim talks a lot on stderr; drain it so the pipe never blocks, keeping the tail for errors.
        let stderr_tail = Arc::new(Mutex::new(String::new()));
        let tail = Arc::clone(&stderr_tail);
        std::thread::spawn(move || {
            let mut r = BufReader::new(stderr);
            let mut line = String::new();
            while r.read_line(&mut line).unwrap_or(0) > 0 {
                if let Ok(mut t) = tail.lock() {
                    t.push_str(&line);
                    if t.len() > 8192 {
                        let cut = t.len() - 4096;
                        let cut = (cut..t.len()).find(|i| t.is_char_boundary(*i)).unwrap_or(0);
                        t.drain(..cut);
                    }
                }
                line.clear();
            }
        });
        let mut plant = Plant {
            child,
            stdin: BufWriter::new(stdin),
            stdout: BufReader::new(stdout),
            stderr_tail,
            watched: 0,
            version: String::new(),
            aircraft_xml: PathBuf::new(),
        };
        match plant.read_frame("start") {
            Ok(v) => {
                let hello = String::from_utf8_lossy(&v).into_owned();
                let (version, xml) = hello.split_once('\n').unwrap_or((hello.as_str(), ""));
                plant.version = version.to_string();
                plant.aircraft_xml = PathBuf::from(xml);
            }
            Err(PlantError::Bridge { message, .. }) => return Err(unavailable(message)),
            Err(PlantError::BridgeDied { why, stderr_tail }) => {
                return Err(unavailable(format!("{why}: {stderr_tail}")));
            }
            Err(e) => return Err(e),
        }
        Ok(plant)
    }

    /// The JSBSim version the bridge imported.
    pub fn jsbsim_version(&self) -> &str {
        &self.version
    }

    /// The model file this bridge loads, `MODEL/MODEL.xml` (JSBSim's own, or `--aircraft-dir`'s).
    pub fn aircraft_xml(&self) -> &Path {
        &self.aircraft_xml
    }

    fn died(&mut self, why: String) -> PlantError {
        // Give the stderr thread a moment to collect the traceback.
        let _ = self.child.wait();
        std::thread::sleep(std::time::Duration::from_millis(50));
        let stderr_tail = self
            .stderr_tail
            .lock()
            .map(|t| t.clone())
            .unwrap_or_default();
        PlantError::BridgeDied { why, stderr_tail }
    }

    fn read_frame(&mut self, command: &str) -> Result<Vec<u8>, PlantError> {
        let mut head = [0u8; 5];
        if let Err(e) = self.stdout.read_exact(&mut head) {
            return Err(self.died(format!("no reply to `{command}`: {e}")));
        }
        let len = u32::from_le_bytes([head[1], head[2], head[3], head[4]]) as usize;
        let mut payload = vec![0u8; len];
        if let Err(e) = self.stdout.read_exact(&mut payload) {
            return Err(self.died(format!("truncated reply to `{command}`: {e}")));
        }
        match head[0] {
            b'O' => Ok(payload),
            b'E' => Err(PlantError::Bridge {
                command: command.to_string(),
                message: String::from_utf8_lossy(&payload).into_owned(),
            }),
            other => Err(self.died(format!("bad reply status byte {other:#x}"))),
        }
    }

    fn request(&mut self, fields: &[&str]) -> Result<Vec<u8>, PlantError> {
        // Tabs and newlines are the protocol's separators: a field holding one cannot be sent.
        if let Some(bad) = fields.iter().find(|f| f.contains(['\t', '\n'])) {
            return Err(PlantError::Bridge {
                command: fields.first().copied().unwrap_or("").to_string(),
                message: format!("argument {bad:?} contains a tab or newline"),
            });
        }
        let line = fields.join("\t");
        if let Err(e) = writeln!(self.stdin, "{line}").and_then(|_| self.stdin.flush()) {
            return Err(self.died(format!("cannot send `{}`: {e}", fields[0])));
        }
        self.read_frame(fields.first().copied().unwrap_or(""))
    }

    /// Loads a runscript at the dt it declares (`initfile`: an initialize file path, or `None` to let
    /// JSBSim look in the aircraft folder) and runs its initial conditions. Returns JSBSim's dt, s.
    pub fn load_script(
        &mut self,
        script: &Path,
        initfile: Option<&Path>,
    ) -> Result<f64, PlantError> {
        let s = script.to_string_lossy();
        let i = initfile.map(|p| p.to_string_lossy()).unwrap_or_default();
        let payload = self.request(&["load", &s, &i])?;
        payload
            .first_chunk::<8>()
            .map(|b| f64::from_le_bytes(*b))
            .ok_or_else(|| PlantError::Bridge {
                command: "load".into(),
                message: "reply has no dt".into(),
            })
    }

    /// Chooses the properties returned after every step, each read at every step. A name prefixed
    /// with `?` is optional: a property the loaded model and script do not have reads NaN instead
    /// of failing.
    pub fn watch(&mut self, props: &[&str]) -> Result<(), PlantError> {
        self.watch_planned(props, &ReadPlan::every_step(props.len()))
    }

    /// [`Plant::watch`], each property read only at the steps `plan` names and NaN at the others:
    /// each read is a Python call per 120 Hz step, so what is needed only at some steps (the truth
    /// at the 20 Hz samples, the truth behind a GPS fix) is read only there.
    pub fn watch_planned(&mut self, props: &[&str], plan: &ReadPlan) -> Result<(), PlantError> {
        if plan.width() != props.len() {
            return Err(PlantError::Bridge {
                command: "watch".into(),
                message: format!(
                    "read plan for {} properties, {} watched",
                    plan.width(),
                    props.len()
                ),
            });
        }
        let masks = plan.hex_masks();
        let period = masks.len().to_string();
        let mut f = vec!["watch", period.as_str()];
        f.extend(masks.iter().map(String::as_str));
        f.extend_from_slice(props);
        self.request(&f)?;
        self.watched = props.len();
        Ok(())
    }

    /// Runs up to `n` steps; returns one row of watched values per step done. Fewer rows than `n`
    /// means the script reached its end.
    pub fn step(&mut self, n: u32) -> Result<Rows, PlantError> {
        let payload = self.request(&["step", &n.to_string()])?;
        let bad = |why: &str| PlantError::Bridge {
            command: "step".into(),
            message: why.into(),
        };
        let (count, body) = payload
            .split_first_chunk::<4>()
            .ok_or_else(|| bad("reply shorter than its count"))?;
        let count = u32::from_le_bytes(*count) as usize;
        if self.watched == 0 || body.len() != count * self.watched * 8 {
            return Err(bad("reply length does not match the watched properties"));
        }
        let (words, _) = body.as_chunks::<8>();
        Ok(Rows {
            values: words.iter().map(|b| f64::from_le_bytes(*b)).collect(),
            width: self.watched,
        })
    }

    /// Runs up to `n` steps without reading any property (raw JSBSim stepping: the baseline of
    /// `hil-sim bench`); returns the steps done, fewer than `n` when the script ended.
    pub fn run_raw(&mut self, n: u32) -> Result<u32, PlantError> {
        let payload = self.request(&["run", &n.to_string()])?;
        let count = payload
            .first_chunk::<4>()
            .ok_or_else(|| PlantError::Bridge {
                command: "run".into(),
                message: "reply shorter than its count".into(),
            })?;
        Ok(u32::from_le_bytes(*count))
    }
}

/// Which watched properties the bridge reads at each step. Step `k` (counted from 0 after `load`)
/// reads every property when `k == 0`, and otherwise those its cycle marks at `k % cycle length`;
/// the others read NaN.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReadPlan {
    /// Per step of the cycle, per property: read?
    cycle: Vec<Vec<bool>>,
    /// Step 0: every property.
    all: Vec<bool>,
}

/// The longest cycle a [`ReadPlan`] keeps (20 s at 120 Hz); the steps of a longer one read every
/// property.
pub const MAX_READ_CYCLE: u64 = 2400;

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 { a } else { gcd(b, a % b) }
}

impl ReadPlan {
    /// Every property at every step.
    pub fn every_step(width: usize) -> ReadPlan {
        ReadPlan {
            cycle: vec![vec![true; width]],
            all: vec![true; width],
        }
    }

    /// Property `i` read at the steps in any of `when[i]`, or at every step for `None`. When the
    /// periods' least common multiple exceeds [`MAX_READ_CYCLE`], every property at every step.
    pub fn new(when: &[Option<Vec<Every>>]) -> ReadPlan {
        let len = when.iter().flatten().flatten().try_fold(1, |l: u64, e| {
            let p = e.period.max(1);
            (l / gcd(l, p))
                .checked_mul(p)
                .filter(|l| *l <= MAX_READ_CYCLE)
        });
        let Some(len) = len else {
            return ReadPlan::every_step(when.len());
        };
        let cycle = (0..len)
            .map(|k| {
                let at = |es: &Vec<Every>| es.iter().any(|e| e.contains(k));
                when.iter().map(|w| w.as_ref().is_none_or(at)).collect()
            })
            .collect();
        ReadPlan {
            cycle,
            all: vec![true; when.len()],
        }
    }

    /// Properties per step.
    pub fn width(&self) -> usize {
        self.all.len()
    }

    /// Steps before the plan repeats.
    pub fn cycle_len(&self) -> usize {
        self.cycle.len()
    }

    /// Which properties step `k` reads, in watch order.
    pub fn at(&self, k: u64) -> &[bool] {
        let n = self.cycle.len().max(1) as u64;
        match self.cycle.get((k % n) as usize) {
            Some(m) if k > 0 => m,
            _ => &self.all,
        }
    }

    /// The cycle as the bridge takes it: per step, a hexadecimal number whose bit `i` is set when
    /// property `i` is read.
    fn hex_masks(&self) -> Vec<String> {
        self.cycle
            .iter()
            .map(|m| {
                let nibbles = m.len().div_ceil(4).max(1);
                (0..nibbles)
                    .rev()
                    .map(|n| {
                        let v = (0..4)
                            .filter(|b| m.get(n * 4 + b).copied().unwrap_or(false))
                            .fold(0, |v, b| v | (1 << b));
                        char::from_digit(v, 16).unwrap_or('0')
                    })
                    .collect()
            })
            .collect()
    }
}

/// The watched values of the steps one [`Plant::step`] ran, in one flat buffer (no allocation per
/// row): row `k` is `values[k·width .. (k+1)·width]`, in [`Plant::watch`]'s order.
#[derive(Debug, Clone, PartialEq)]
pub struct Rows {
    values: Vec<f64>,
    width: usize,
}

impl Rows {
    /// Steps done.
    pub fn len(&self) -> usize {
        self.values.len() / self.width.max(1)
    }
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }
    /// Step `k`'s values.
    pub fn row(&self, k: usize) -> Option<&[f64]> {
        self.iter().nth(k)
    }
    /// One slice per step.
    pub fn iter(&self) -> std::slice::ChunksExact<'_, f64> {
        self.values.chunks_exact(self.width.max(1))
    }
}

impl<'a> IntoIterator for &'a Rows {
    type Item = &'a [f64];
    type IntoIter = std::slice::ChunksExact<'a, f64>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

impl Drop for Plant {
    fn drop(&mut self) {
        let _ = writeln!(self.stdin, "quit").and_then(|_| self.stdin.flush());
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Positions of the [`WATCH`] properties in a step row.
pub(crate) mod at {
    pub const TIME: usize = 0;
    pub const ALPHA: usize = 1;
    pub const BETA: usize = 2;
    pub const U_AERO: usize = 3;
    pub const V_AERO: usize = 4;
    pub const W_AERO: usize = 5;
    pub const VT: usize = 6;
    pub const MACH: usize = 7;
    pub const QBAR: usize = 8;
    pub const H_SL: usize = 9;
    pub const H_AGL: usize = 10;
    pub const P: usize = 11;
    pub const Q: usize = 12;
    pub const R: usize = 13;
    pub const PHI: usize = 14;
    pub const THETA: usize = 15;
    pub const PSI: usize = 16;
    pub const PDOT: usize = 17;
    pub const QDOT: usize = 18;
    pub const RDOT: usize = 19;
    pub const FBX: usize = 20;
    pub const FBY: usize = 21;
    pub const FBZ: usize = 22;
    pub const MASS: usize = 23;
    pub const GPS_SPEED: usize = 24;
    /// The surface positions, one per `aircraft::SURFACE_CHANNELS` from here on (their sensors'
    /// properties, the aircraft description's).
    pub const SURFACES: usize = 25;
    pub const THROTTLE: usize = SURFACES + estimator_core::aircraft::SURFACE_CHANNELS.len();
    pub const LAT: usize = 33;
    pub const LON: usize = 34;
    pub const PI: usize = 35;
    pub const QI: usize = 36;
    pub const RI: usize = 37;
    pub const V_NORTH: usize = 38;
    pub const V_EAST: usize = 39;
    pub const V_DOWN: usize = 40;
    pub const FUEL: usize = 41;
    pub const WIND_NORTH: usize = 42;
    pub const WIND_EAST: usize = 43;
    pub const WIND_DOWN: usize = 44;
    /// The generator's zone state (optional: NaN for scripts that do not have it).
    pub const ZONE: usize = 45;
    /// Engine 0's core speed and throttle position (optional: a piston engine has no N2).
    pub const ENGINE_N2: usize = 46;
    pub const ENGINE_THROTTLE: usize = 47;
    /// Engine 0's propeller speed (optional: a turbine with a direct thruster has none).
    pub const ENGINE_PROPELLER_RPM: usize = 48;
    /// Properties watched.
    pub const COUNT: usize = ENGINE_PROPELLER_RPM + 1;
}

/// The properties a flight watches, each written next to its position in [`at`]; a position left
/// without a name fails the build. When each is read is `crate::fly`'s read plan: the truth at
/// the 20 Hz sample instants, each sensor input where its model uses it.
pub(crate) const WATCH: [&str; at::COUNT] = {
    let mut w = [""; at::COUNT];
    w[at::TIME] = "simulation/sim-time-sec";
    w[at::ALPHA] = "aero/alpha-deg";
    w[at::BETA] = "aero/beta-deg";
    w[at::U_AERO] = "velocities/u-aero-fps";
    w[at::V_AERO] = "velocities/v-aero-fps";
    w[at::W_AERO] = "velocities/w-aero-fps";
    w[at::VT] = "velocities/vt-fps";
    w[at::MACH] = "velocities/mach";
    w[at::QBAR] = "aero/qbar-psf";
    w[at::H_SL] = "position/h-sl-ft";
    w[at::H_AGL] = "position/h-agl-ft";
    w[at::P] = "velocities/p-rad_sec";
    w[at::Q] = "velocities/q-rad_sec";
    w[at::R] = "velocities/r-rad_sec";
    w[at::PHI] = "attitude/phi-rad";
    w[at::THETA] = "attitude/theta-rad";
    w[at::PSI] = "attitude/psi-rad";
    w[at::PDOT] = "accelerations/pdot-rad_sec2";
    w[at::QDOT] = "accelerations/qdot-rad_sec2";
    w[at::RDOT] = "accelerations/rdot-rad_sec2";
    w[at::FBX] = "forces/fbx-total-lbs";
    w[at::FBY] = "forces/fby-total-lbs";
    w[at::FBZ] = "forces/fbz-total-lbs";
    w[at::MASS] = "inertia/mass-slugs";
    w[at::GPS_SPEED] = "velocities/ned-velocity-mag-fps";
    let mut i = 0;
    while i < AIRCRAFT.surfaces.len() {
        // A surface the airframe does not have reads nothing (an optional name that is never
        // there: NaN, and its channel carries 0).
        w[at::SURFACES + i] = match AIRCRAFT.surfaces[i] {
            Some(s) => s.property,
            None => "?hil-sim/no-such-surface",
        };
        i += 1;
    }
    w[at::THROTTLE] = match AIRCRAFT.throttle_properties.first() {
        Some(p) => p,
        None => panic!("the aircraft description names no throttle (gen-aircraft refuses that)"),
    };
    w[at::LAT] = "position/lat-geod-deg";
    w[at::LON] = "position/long-gc-deg";
    // Body rates relative to inertial space (Earth rate included): what a gyro measures.
    w[at::PI] = "velocities/pi-rad_sec";
    w[at::QI] = "velocities/qi-rad_sec";
    w[at::RI] = "velocities/ri-rad_sec";
    // Velocity over the ground in the local NED frame (what a GPS/INS measures, at the CG).
    w[at::V_NORTH] = "velocities/v-north-fps";
    w[at::V_EAST] = "velocities/v-east-fps";
    w[at::V_DOWN] = "velocities/v-down-fps";
    w[at::FUEL] = "propulsion/total-fuel-lbs";
    // Steady wind + turbulence + gusts, NED: truth only, for evaluating wind estimators.
    w[at::WIND_NORTH] = "atmosphere/total-wind-north-fps";
    w[at::WIND_EAST] = "atmosphere/total-wind-east-fps";
    w[at::WIND_DOWN] = "atmosphere/total-wind-down-fps";
    w[at::ZONE] = "?maneuver/zone";
    // The flight-test record's engine channels (`crate::boom`): never a sensor frame's.
    w[at::ENGINE_N2] = "?propulsion/engine/n2";
    w[at::ENGINE_THROTTLE] = "?fcs/throttle-pos-norm";
    w[at::ENGINE_PROPELLER_RPM] = "?propulsion/engine/propeller-rpm";
    let mut i = 0;
    while i < at::COUNT {
        assert!(!w[i].is_empty(), "every position in `at` has a property");
        i += 1;
    }
    w
};

/// Which [`WATCH`] properties are optional (`?`: the generator's zone, NaN for scripts without
/// it, and the surfaces the airframe does not have): a flight is not cut on their NaN.
pub(crate) const OPTIONAL: [bool; at::COUNT] = {
    let mut m = [false; at::COUNT];
    let mut i = 0;
    while i < at::COUNT {
        m[i] = matches!(WATCH[i].as_bytes().first(), Some(b'?'));
        i += 1;
    }
    m
};

/// The [`WATCH`] positions only [`truth_of`] and the engine record read: air data, position, wind,
/// the engine. They are needed at the 20 Hz sample instants only.
pub(crate) const TRUTH_ONLY: [usize; 16] = [
    at::ALPHA,
    at::BETA,
    at::U_AERO,
    at::V_AERO,
    at::W_AERO,
    at::VT,
    at::MACH,
    at::QBAR,
    at::LAT,
    at::LON,
    at::WIND_NORTH,
    at::WIND_EAST,
    at::WIND_DOWN,
    at::ENGINE_N2,
    at::ENGINE_THROTTLE,
    at::ENGINE_PROPELLER_RPM,
];

pub(crate) const SLUG_TO_KG: f64 = 14.593_902_937;
pub(crate) const PSF_TO_PA: f64 = 47.880_258_98;
pub(crate) const G0_FPS2: f64 = 32.174_048_56;

/// What `<use aircraft=… initialize=…/>` of a runscript says.
#[derive(Debug, PartialEq)]
pub struct ScriptUse {
    pub aircraft: String,
    pub initialize: Option<String>,
}

fn attr(tag: &str, name: &str) -> Option<String> {
    let key = format!("{name}=");
    let at = tag.find(&key)? + key.len();
    let rest = tag.get(at..)?.trim_start();
    let q = rest.chars().next().filter(|c| *c == '"' || *c == '\'')?;
    let body = rest.get(1..)?;
    Some(body.get(..body.find(q)?)?.trim().to_string())
}

/// Reads the aircraft and initialize file a runscript names. Enough XML for that one tag: JSBSim
/// itself parses the file fully (and the bridge reports its XML errors with line numbers).
pub fn script_use(path: &Path) -> Result<ScriptUse, PlantError> {
    let text = std::fs::read_to_string(path).map_err(|source| PlantError::ScriptUnreadable {
        path: path.to_path_buf(),
        source,
    })?;
    let not = |why: &str| PlantError::NotAScript {
        path: path.to_path_buf(),
        why: why.to_string(),
    };
    if !text.contains("<runscript") {
        return Err(not("no <runscript> element"));
    }
    let at = text
        .find("<use ")
        .ok_or_else(|| not("no <use aircraft=… initialize=…/> element"))?;
    let tag = &text[at..at
        + text[at..]
            .find('>')
            .ok_or_else(|| not("unclosed <use> tag"))?];
    let aircraft = attr(tag, "aircraft").ok_or_else(|| not("<use> has no aircraft attribute"))?;
    Ok(ScriptUse {
        aircraft,
        initialize: attr(tag, "initialize"),
    })
}

/// Engine 0's state at one step.
pub(crate) fn engine_of(r: &[f64]) -> crate::flight::EngineState {
    crate::flight::EngineState {
        n2_pct: Some(r[at::ENGINE_N2]).filter(|v| v.is_finite()),
        throttle_pos: r[at::ENGINE_THROTTLE],
        propeller_rpm: Some(r[at::ENGINE_PROPELLER_RPM]).filter(|v| v.is_finite()),
    }
}

/// Truth at one step, in dataset units.
pub(crate) fn truth_of(r: &[f64]) -> Truth {
    Truth {
        alpha_deg: r[at::ALPHA],
        beta_deg: r[at::BETA],
        u_aero_mps: r[at::U_AERO] * FT_TO_M,
        v_aero_mps: r[at::V_AERO] * FT_TO_M,
        w_aero_mps: r[at::W_AERO] * FT_TO_M,
        vt_mps: r[at::VT] * FT_TO_M,
        mach: r[at::MACH],
        qbar_pa: r[at::QBAR] * PSF_TO_PA,
        alt_msl_m: r[at::H_SL] * FT_TO_M,
        p_true_rps: r[at::P],
        q_true_rps: r[at::Q],
        r_true_rps: r[at::R],
        phi_deg: r[at::PHI].to_degrees(),
        theta_deg: r[at::THETA].to_degrees(),
        psi_deg: r[at::PSI].to_degrees(),
        // Load factor along -z body from the total (non-gravity) force: 1 in level flight.
        nz_g: -r[at::FBZ] / (r[at::MASS] * G0_FPS2),
        mass_kg: r[at::MASS] * SLUG_TO_KG,
        lat_deg: r[at::LAT],
        lon_deg: r[at::LON],
        v_north_mps: r[at::V_NORTH] * FT_TO_M,
        v_east_mps: r[at::V_EAST] * FT_TO_M,
        v_down_mps: r[at::V_DOWN] * FT_TO_M,
        fuel_kg: r[at::FUEL] * LB_TO_KG,
        wind_north_mps: r[at::WIND_NORTH] * FT_TO_M,
        wind_east_mps: r[at::WIND_EAST] * FT_TO_M,
        wind_down_mps: r[at::WIND_DOWN] * FT_TO_M,
    }
}

/// A runscript loaded into the bridge.
#[derive(Clone, Debug, PartialEq)]
pub struct Loaded {
    /// The script's canonical path.
    pub path: PathBuf,
    /// JSBSim's integration step, the script's own `dt`, s.
    pub dt_s: f64,
}

/// Loads a runscript for this build's aircraft (its description's JSBSim model) into `plant` at its
/// own dt and runs its initial conditions: the initialize file is taken from beside the script when
/// it is there, else JSBSim looks in the aircraft folder. A script whose rate is not [`SIM_HZ`]
/// (within [`SIM_HZ_TOLERANCE`]) is refused.
pub fn load_runscript(plant: &mut Plant, script: &Path) -> Result<Loaded, PlantError> {
    let script = std::fs::canonicalize(script).map_err(|source| PlantError::ScriptUnreadable {
        path: script.to_path_buf(),
        source,
    })?;
    let uses = script_use(&script)?;
    if uses.aircraft != AIRCRAFT.jsbsim_model {
        return Err(PlantError::WrongAircraft {
            path: script.clone(),
            aircraft: uses.aircraft,
        });
    }
    let beside = uses.initialize.as_ref().and_then(|name| {
        let dir = script.parent()?;
        [dir.join(name), dir.join(format!("{name}.xml"))]
            .into_iter()
            .find(|p| p.is_file())
    });
    let dt_s = plant
        .load_script(&script, beside.as_deref())
        .map_err(|e| match e {
            PlantError::Bridge { message, .. } => PlantError::ScriptRejected {
                path: script.clone(),
                message,
            },
            other => other,
        })?;
    let hz = 1.0 / dt_s;
    if !(hz.is_finite() && (hz / f64::from(SIM_HZ) - 1.0).abs() <= SIM_HZ_TOLERANCE) {
        return Err(PlantError::UnsupportedRate {
            path: script,
            dt_s,
            hz,
        });
    }
    Ok(Loaded { path: script, dt_s })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn read_plan_cycles_over_the_periods_common_multiple() {
        let e = |period, offset| Every { period, offset };
        let plan = ReadPlan::new(&[None, Some(vec![e(6, 5)]), Some(vec![e(4, 1), e(6, 0)])]);
        assert_eq!((plan.width(), plan.cycle_len()), (3, 12));
        assert_eq!(plan.at(0), [true; 3], "step 0 reads everything");
        assert_eq!(plan.at(1), [true, false, true]);
        assert_eq!(plan.at(5), [true, true, true]);
        assert_eq!(plan.at(6), [true, false, true]);
        assert_eq!(plan.at(7), [true, false, false]);
        assert_eq!(plan.at(12 + 7), plan.at(7));
        // Bit i of each step's mask is property i, most significant nibble first.
        let masks = plan.hex_masks();
        assert_eq!(
            (masks[0].as_str(), masks[1].as_str(), masks[5].as_str()),
            ("5", "5", "7")
        );
        assert_eq!(masks[7], "1");
        let wide = ReadPlan::new(&vec![Some(vec![e(2, 1)]); 9]);
        assert_eq!(wide.hex_masks(), ["000", "1ff"]);
    }

    #[test]
    fn a_read_plan_too_long_to_cycle_reads_everything() {
        let e = |period| Some(vec![Every { period, offset: 1 }]);
        // 7 · 11 · 13 · 3 = 3003 steps > MAX_READ_CYCLE.
        let plan = ReadPlan::new(&[e(7), e(11), e(13), e(3)]);
        assert_eq!(plan, ReadPlan::every_step(4));
        assert_eq!(plan.at(5), [true; 4]);
        assert_eq!(ReadPlan::new(&[e(7), e(11), e(13)]).cycle_len(), 1001);
    }

    #[test]
    fn use_tag_attributes_are_read() {
        let tag = r#"<use aircraft="f16" initialize='reset00'/"#;
        assert_eq!(attr(tag, "aircraft").as_deref(), Some("f16"));
        assert_eq!(attr(tag, "initialize").as_deref(), Some("reset00"));
        assert_eq!(attr(tag, "missing"), None);
    }
}
