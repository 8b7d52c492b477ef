//! `hil-sim run`: flight source → link → firmware → score, with its outputs on disk.

use std::path::{Path, PathBuf};
use std::time::Duration;

use super::target::{InProcess, Qemu, QemuLink, Serial, Target, default_elf};
use super::{RunConfig, RunError, RunOutcome, samples_of};
use crate::dataset::Flight;
use crate::link::LinkConfig;
use crate::score;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FirmwareKind {
    /// The firmware's application logic in this process.
    Host,
    /// The flight image (`cargo fw`) in qemu-system-arm netduinoplus2 with -icount shift=0.
    Qemu,
    /// A flashed board on --port.
    Serial,
}

/// Where the flight comes from: exactly one of these.
#[derive(Clone, Debug, clap::Args)]
#[group(required = true, multiple = false)]
pub struct Source {
    /// A recorded flight CSV at 20 Hz: a dataset's flight, or your own flight log with only the
    /// sensed columns (truth columns optional, scored where present; docs/flight-log.md).
    #[arg(long, value_name = "CSV")]
    pub dataset: Option<PathBuf>,
    /// A JSBSim runscript (of the build's aircraft) flown now, then streamed (generated maneuvers are scripts too).
    #[arg(long)]
    pub script: Option<PathBuf>,
}

#[derive(Clone, Debug, clap::Args)]
pub struct RunArgs {
    #[command(flatten)]
    pub source: Source,
    /// Which firmware answers [default: host; serial with --port].
    #[arg(long, value_enum)]
    pub firmware: Option<FirmwareKind>,
    /// Firmware image for --firmware qemu (default: the image `cargo fw` of this build puts in its
    /// target directory, thumbv7em-none-eabihf/firmware/firmware: this build's aircraft).
    #[arg(long)]
    pub elf: Option<PathBuf>,
    /// QEMU binary, for --firmware qemu [default: qemu-system-arm].
    #[arg(long)]
    pub qemu: Option<String>,
    /// How bytes reach the image in QEMU (--firmware qemu): semihosting on QEMU's stdin/stdout,
    /// whole frames per call (fast), or USART1 on a TCP socket, the board's own path (one byte per
    /// QEMU main-loop round trip: the 20-minute flight takes minutes). The same bytes and
    /// estimates either way [default: semihost].
    #[arg(long, value_enum)]
    pub qemu_link: Option<QemuLink>,
    /// Serial device of a flashed board.
    #[arg(long)]
    pub port: Option<PathBuf>,
    /// Baud rate of --port (the board's USART1 runs 115 200 Bd, from whichever clock it got)
    /// [default: 115200].
    #[arg(long, value_parser = baud_rate)]
    pub baud: Option<u32>,
    /// Pace the link in real time: every byte leaves when the link model (at its baud, `--link-baud`)
    /// says it arrives, one frame per 50 ms of wall time. For a board on `--port`; without it frames
    /// go as fast as the firmware answers.
    #[arg(long)]
    pub realtime: bool,
    /// As fast as the firmware answers: the default, kept so that older commands still parse.
    #[arg(long, hide = true, conflicts_with = "realtime")]
    pub fast: bool,
    /// Sensor suite sent, i.e. the sensor frame kind: table1 (the paper's inputs, wire kind 1),
    /// egi (Table 1 + EGI attitude, velocity and fuel, wire kind 3) or egi120 (egi + the period's
    /// 120 Hz sub-samples of the IMU and the surfaces, wire kind 4). The firmware takes all three.
    /// Default: the suite the compiled-in (shipped) estimator reads.
    #[arg(long, value_parser = parse_suite)]
    pub suite: Option<estimator_core::Suite>,
    /// Print what the in-process firmware logs (`--firmware host`: rejected frames, deadline misses,
    /// sequence restarts) on stderr, as `firmware WARN: ...`. QEMU and boards log over defmt instead.
    #[arg(long)]
    pub firmware_log: bool,
    /// Print exactly one JSON summary object on stdout (messages go to stderr).
    #[arg(long)]
    pub json: bool,
    /// Seed of the link faults (and of the sensor models when flying a script).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Stop the flight after this many seconds.
    #[arg(long, value_parser = crate::cli_values::positive_seconds, allow_hyphen_values = true)]
    pub max_time_s: Option<f64>,
    /// Output directory of estimates.csv, summary.json and plot.png (docs/flight-log.md).
    #[arg(long, value_name = "DIR", default_value = "out/run")]
    pub out: PathBuf,
    /// Link model parameters (TOML: baud, latency_ms, jitter_ms, byte_loss, bit_flip, burst_rate,
    /// burst_len); the flags below override it.
    #[arg(long)]
    pub link: Option<PathBuf>,
    /// Simulated link's baud rate [default: 115200, the board's].
    #[arg(long)]
    pub link_baud: Option<u32>,
    /// Simulated link's one-way latency, ms [default: 0].
    #[arg(long)]
    pub latency_ms: Option<f64>,
    /// Simulated link's latency jitter (uniform ± this), ms [default: 0].
    #[arg(long)]
    pub jitter_ms: Option<f64>,
    /// Probability that a byte is lost.
    #[arg(long)]
    pub byte_loss: Option<f64>,
    /// Probability that each bit flips.
    #[arg(long)]
    pub bit_flip: Option<f64>,
    /// Probability per byte that a noise burst starts.
    #[arg(long)]
    pub burst_rate: Option<f64>,
    /// Bytes a noise burst corrupts.
    #[arg(long)]
    pub burst_len: Option<u32>,
    /// A scripted sensor fault, KIND[:CHANNEL]@START+DURATION in seconds: gps-loss@300+30,
    /// dead:accel_y_mps2@100+10 (sent invalid), stuck:gyro_r_rps@100+10 (frozen, sent valid),
    /// saturated:accel_z_mps2@100+0.5 (at the IMU's full scale), bias:accel_z_mps2=-39.2@100+10
    /// (plus a constant in the channel's unit, sent valid). Repeatable. The summary then scores
    /// each: flag latency, seconds until the estimate is back on the fault-free run's (the
    /// compiled-in estimator on the same flight, in-process), and how far it moved estimates that
    /// carried no flag.
    #[arg(long = "fault")]
    pub faults: Vec<crate::faults::Fault>,
    #[command(flatten)]
    pub aircraft: crate::plant::AircraftArgs,
    /// Stream a --dataset's rows at the times they carry, whatever their steps (irregular,
    /// backwards, wrapping), to test the firmware's own time handling (scripts/wcet does). Without
    /// it a log must be 20 Hz with increasing times.
    #[arg(long)]
    pub any_time_base: bool,
    /// Fast mode: how long to wait for the reply to a frame the firmware steps, ms.
    #[arg(long, default_value_t = 10_000)]
    pub reply_timeout_ms: u64,
}

impl RunArgs {
    pub fn link_config(&self) -> Result<LinkConfig, RunError> {
        let mut c = match &self.link {
            Some(p) => LinkConfig::load(p)?,
            None => LinkConfig::default(),
        };
        if let Some(v) = self.link_baud {
            c.baud = v;
        }
        let set = |dst: &mut f64, v: Option<f64>| {
            if let Some(v) = v {
                *dst = v;
            }
        };
        set(&mut c.latency_ms, self.latency_ms);
        set(&mut c.jitter_ms, self.jitter_ms);
        set(&mut c.byte_loss, self.byte_loss);
        set(&mut c.bit_flip, self.bit_flip);
        set(&mut c.burst_rate, self.burst_rate);
        if let Some(v) = self.burst_len {
            c.burst_len = v;
        }
        c.validate()?;
        Ok(c)
    }
}

/// The faults `manifest.json` beside a dataset CSV lists for it (the `ood` preset's sensor-fault
/// flights); none when there is no manifest or no entry for the file.
fn manifest_faults(csv: &Path) -> Result<Vec<crate::faults::Fault>, RunError> {
    match crate::dataset::Manifest::listing(csv)? {
        Some((_, _, entry)) => entry.faults().map_err(RunError::Fault),
        None => Ok(Vec::new()),
    }
}

/// Loads or flies the flight (a script on the package's model of the build's aircraft, or on
/// `--aircraft-dir`'s).
pub fn flight(source: &Source, seed: u64, max_time_s: Option<f64>) -> Result<Flight, RunError> {
    flight_on(source, None, seed, max_time_s)
}

/// Loads the flight, or flies its script on the F-16 of `aircraft_dir` (`--aircraft-dir`).
pub fn flight_on(
    source: &Source,
    aircraft_dir: Option<&Path>,
    seed: u64,
    max_time_s: Option<f64>,
) -> Result<Flight, RunError> {
    flight_and_suite(source, aircraft_dir, seed, max_time_s).map(|(f, _)| f)
}

/// [`flight_on`], with the richest sensor suite the flight carries: a log's columns say which, a
/// flown script carries every one.
fn flight_and_suite(
    source: &Source,
    aircraft_dir: Option<&Path>,
    seed: u64,
    max_time_s: Option<f64>,
) -> Result<(Flight, estimator_core::Suite), RunError> {
    if source.dataset.is_some() && aircraft_dir.is_some() {
        return Err(RunError::Usage(
            "--aircraft-dir goes with --script: a recorded flight (--dataset) already flew its aircraft"
                .into(),
        ));
    }
    let (mut f, carries) = match (&source.dataset, &source.script) {
        (Some(csv), _) => Flight::read_log_in_dataset(csv)?,
        (None, Some(script)) => (
            crate::fly::fly_script(
                script,
                &crate::fly::FlyConfig {
                    seed,
                    max_time_s,
                    aircraft_dir: aircraft_dir.map(Path::to_path_buf),
                    ..Default::default()
                },
            )?,
            estimator_core::Suite::Egi120,
        ),
        (None, None) => return Err(RunError::EmptyFlight),
    };
    let first_s = f.samples.first().map(|s| s.time_s);
    if let Some(t) = max_time_s {
        f.samples.retain(|s| s.time_s <= t + 1e-9);
        // A log that has samples, or a script flown only that long, ends before its first one.
        if f.samples.is_empty() && (first_s.is_some() || source.script.is_some()) {
            return Err(RunError::Usage(format!(
                "the flight has no sample within --max-time-s {t}{}: give a longer --max-time-s",
                first_s.map_or_else(String::new, |x| format!(" (its first is at {x:.2} s)"))
            )));
        }
    }
    if f.samples.is_empty() {
        return Err(RunError::EmptyFlight);
    }
    Ok((f, carries))
}

/// Refuses a log whose columns lack channels the frames of `suite` carry: they would go invalid
/// in every frame, and an estimator that reads them would score none.
fn check_log_suite(
    csv: &Path,
    carries: estimator_core::Suite,
    suite: estimator_core::Suite,
) -> Result<(), RunError> {
    use estimator_core::Suite;
    if carries.delivers(suite) {
        return Ok(());
    }
    let missing = if carries == Suite::Table1 {
        "EGI columns (`egi_roll_rad` … `fuel_qty_kg`)"
    } else {
        "120 Hz sub-sample columns (`gyro_p_rps_sub0` … `speedbrake_deg_sub5`)"
    };
    Err(RunError::Usage(format!(
        "{} has no {missing}, which the `{}` frames the estimator reads carry (docs/flight-log.md): \
         fly the log again with hil-sim (fly or generate write them), or run it with an estimator \
         built for the `{}` suite",
        csv.display(),
        suite.name(),
        carries.name()
    )))
}

/// The firmware that answers: `--firmware`, or serial with `--port`. A flag of another firmware
/// (`--port`/`--baud` of a board, `--elf`/`--qemu`/`--qemu-link` of QEMU) is refused rather than
/// ignored, and a board needs its `--port`.
pub fn firmware_kind(a: &RunArgs) -> Result<FirmwareKind, RunError> {
    use FirmwareKind::{Host, Qemu, Serial};
    let kind = match (a.firmware, &a.port) {
        (Some(k), _) => k,
        (None, Some(_)) => Serial,
        (None, None) => Host,
    };
    let name = |k: FirmwareKind| {
        clap::ValueEnum::to_possible_value(&k)
            .map_or_else(String::new, |v| v.get_name().to_string())
    };
    let show = |p: &Option<PathBuf>| p.as_ref().map(|p| p.display().to_string());
    let own: [(&str, Option<String>, FirmwareKind); 5] = [
        ("--port", show(&a.port), Serial),
        ("--baud", a.baud.map(|b| b.to_string()), Serial),
        ("--elf", show(&a.elf), Qemu),
        ("--qemu", a.qemu.clone(), Qemu),
        (
            "--qemu-link",
            a.qemu_link
                .and_then(|l| clap::ValueEnum::to_possible_value(&l))
                .map(|v| v.get_name().to_string()),
            Qemu,
        ),
    ];
    for (flag, value, owner) in own {
        if let Some(v) = value
            && owner != kind
        {
            let what = if owner == Serial {
                "a flashed board"
            } else {
                "QEMU"
            };
            return Err(RunError::Usage(format!(
                "{flag} {v} goes with {what} (--firmware {}), not --firmware {}: drop one of them",
                name(owner),
                name(kind)
            )));
        }
    }
    if kind == Serial && a.port.is_none() {
        return Err(RunError::Usage(
            "--firmware serial needs --port DEVICE: the board's serial port, e.g. /dev/ttyACM0"
                .into(),
        ));
    }
    Ok(kind)
}

/// Opens the firmware `kind` ([`firmware_kind`]).
pub fn open_target(a: &RunArgs, kind: FirmwareKind) -> Result<Box<dyn Target>, RunError> {
    Ok(match kind {
        FirmwareKind::Host => Box::new(InProcess::new()),
        FirmwareKind::Qemu => {
            let elf = a.elf.clone().unwrap_or_else(default_elf);
            let qemu = a.qemu.as_deref().unwrap_or("qemu-system-arm");
            Box::new(Qemu::start(qemu, &elf, a.qemu_link.unwrap_or_default())?)
        }
        FirmwareKind::Serial => {
            let port = a
                .port
                .clone()
                .ok_or_else(|| RunError::Usage("--firmware serial needs --port DEVICE".into()))?;
            Box::new(Serial::open(&port, a.baud.unwrap_or(115_200))?)
        }
    })
}

/// Where a run's files went.
pub struct Written {
    pub csv: PathBuf,
    pub json: PathBuf,
    pub png: PathBuf,
}

/// Writes estimates.csv, summary.json and plot.png into `dir`.
pub fn write_outputs(dir: &Path, o: &RunOutcome, s: &score::Summary) -> Result<Written, RunError> {
    let out = |p: &Path, e: String| RunError::Output(p.to_path_buf(), e);
    std::fs::create_dir_all(dir).map_err(|e| out(dir, e.to_string()))?;
    let w = Written {
        csv: dir.join("estimates.csv"),
        json: dir.join("summary.json"),
        png: dir.join("plot.png"),
    };
    score::write_csv(&w.csv, &o.records).map_err(|e| out(&w.csv, e.to_string()))?;
    let text = serde_json::to_string_pretty(s).map_err(|e| out(&w.json, e.to_string()))?;
    std::fs::write(&w.json, text).map_err(|e| out(&w.json, e.to_string()))?;
    score::plot::write_png(&w.png, &o.records, s).map_err(|e| out(&w.png, e.to_string()))?;
    Ok(w)
}

/// A `--baud` value: a whole number of bits per second, at least 1.
fn baud_rate(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(b) if b > 0 => Ok(b),
        _ => Err(format!(
            "`{s}`: give a baud rate, a positive whole number, e.g. 115200"
        )),
    }
}

/// A `--suite` value that names no suite.
#[derive(Debug, thiserror::Error)]
#[error("unknown sensor suite `{0}` (known: {known})", known = suite_names())]
pub struct UnknownSuite(String);

fn suite_names() -> String {
    let names: Vec<&str> = estimator_core::Suite::ALL
        .iter()
        .map(|s| s.name())
        .collect();
    names.join(", ")
}

/// A `--suite` value: a [`estimator_core::Suite`] name.
pub fn parse_suite(s: &str) -> Result<estimator_core::Suite, UnknownSuite> {
    estimator_core::Suite::from_name(s).ok_or_else(|| UnknownSuite(s.to_string()))
}

/// Refuses a suite the compiled-in estimator cannot run on: it would answer every frame with
/// `INVALID_INPUT` and score none.
pub fn check_suite(suite: estimator_core::Suite) -> Result<(), RunError> {
    let shipped = estimator_core::Estimator::shipped();
    match shipped.suite() {
        Some(needs) if !suite.delivers(needs) => Err(RunError::Usage(format!(
            "the compiled-in estimator reads the `{}` sensor suite, so `--suite {}` frames lack channels it needs: pass --suite {} (or leave --suite out)",
            needs.name(),
            suite.name(),
            needs.name()
        ))),
        _ => Ok(()),
    }
}

/// Refuses a fault that starts after the flight's last sample: it would never happen.
fn check_faults(faults: &[crate::faults::Fault], flight: &Flight) -> Result<(), RunError> {
    let (first, last) = match (flight.samples.first(), flight.samples.last()) {
        (Some(a), Some(b)) => (a.time_s, b.time_s),
        _ => return Ok(()),
    };
    for f in faults {
        if f.start_s > last {
            return Err(RunError::Usage(format!(
                "--fault {f} starts at {} s, after the flight's last sample at {last:.2} s (it runs {first:.2}–{last:.2} s): choose a start inside the flight",
                f.start_s
            )));
        }
    }
    Ok(())
}

/// The whole `hil-sim run`.
pub fn run(a: &RunArgs) -> Result<score::Summary, RunError> {
    let suite = a.suite.unwrap_or_else(super::shipped_suite);
    check_suite(suite)?;
    // A contradictory --port is refused before anything flies.
    let kind = firmware_kind(a)?;
    let cfg = RunConfig {
        link: a.link_config()?,
        seed: a.seed,
        fast: !a.realtime,
        reply_timeout: Duration::from_millis(a.reply_timeout_ms),
        suite,
        ..RunConfig::default()
    };
    if a.source.script.is_some() {
        eprintln!("flying the script in JSBSim ...");
    }
    if a.firmware_log {
        FirmwareLog::install();
    }
    let aircraft_dir = a.aircraft.dir()?;
    let (flight, carries) =
        flight_and_suite(&a.source, aircraft_dir.as_deref(), a.seed, a.max_time_s)?;
    if let Some(csv) = &a.source.dataset {
        check_log_suite(csv, carries, suite)?;
        if !a.any_time_base {
            crate::dataset::check_time_base(csv, &flight)?;
        }
    }
    check_faults(&a.faults, &flight)?;
    let mut faults = a.faults.clone();
    if let Some(csv) = &a.source.dataset {
        let listed = manifest_faults(csv)?;
        if !listed.is_empty() {
            eprintln!(
                "applying the faults the dataset's manifest lists for this flight: {}",
                listed
                    .iter()
                    .map(ToString::to_string)
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        faults.extend(listed);
    }
    let faults = &faults;
    let mut samples = samples_of(&flight);
    let times: Vec<f64> = samples.iter().map(|s| s.time_s).collect();
    // The fault-free reference: the compiled-in estimator on the clean frames as the firmware
    // decodes them (before the faults go in).
    let reference: Vec<estimator_core::Estimate> = if faults.is_empty() {
        Vec::new()
    } else {
        let mut e = estimator_core::Estimator::shipped();
        samples
            .iter()
            .map(|s| e.step(&s.frame.restricted_to(cfg.suite)))
            .collect()
    };
    let mut frames: Vec<_> = samples.iter().map(|s| s.frame).collect();
    crate::faults::apply(faults, &mut frames, &times);
    for (s, f) in samples.iter_mut().zip(frames) {
        s.frame = f;
    }
    let mut target = open_target(a, kind)?;
    let bar = progress_bar(samples.len());
    let outcome = super::run_with_progress(target.as_mut(), &samples, &cfg, &mut |p| {
        // indicatif redraws at most 20 times a second; the message is rebuilt once per flight second.
        bar.set_position(p.sent as u64);
        if p.sent % 20 == 0 || p.sent == p.total {
            bar.set_message(progress_message(p));
        }
    })?;
    bar.finish_and_clear();
    drop(target);
    let mut summary = score::summarize(&outcome);
    summary.provenance = score::Provenance {
        flight: flight.name.clone(),
        input: match (&a.source.dataset, &a.source.script) {
            (Some(p), _) => format!("--dataset {}", p.display()),
            (None, Some(p)) => format!("--script {}", p.display()),
            (None, None) => String::new(),
        },
        aircraft_dir: aircraft_dir.as_ref().map(|d| d.display().to_string()),
        seed: a.seed,
        suite: suite.name().to_string(),
        max_time_s: a.max_time_s,
        faults: faults.iter().map(ToString::to_string).collect(),
        model: estimator_core::model::SHIPPED_PROVENANCE.map(str::to_string),
        git_rev: crate::dataset::git_rev(),
        hil_sim_version: env!("CARGO_PKG_VERSION").to_string(),
        link: cfg.link.clone(),
    };
    if !faults.is_empty() {
        let estimates: Vec<_> = outcome
            .records
            .iter()
            .map(|r| r.reply.map(|f| f.estimate))
            .collect();
        let truth = super::truth_of(&samples);
        summary.faults = score::faults::score(faults, &estimates, &reference, &truth, &times);
    }
    let w = write_outputs(&a.out, &outcome, &summary)?;
    if a.json {
        eprintln!(
            "{}: {} frames, {} scored, {} lost; wrote {}, {}, {}",
            flight.name,
            summary.frames_sent,
            summary.frames_scored,
            summary.frames_lost,
            w.csv.display(),
            w.json.display(),
            w.png.display()
        );
        println!("{}", serde_json::to_string(&summary).unwrap_or_default());
    } else {
        print!("{}", table(&flight.name, &summary, &w));
    }
    Ok(summary)
}

/// Prints the in-process firmware's log lines (target "firmware") on stderr.
struct FirmwareLog;

impl FirmwareLog {
    fn install() {
        // A logger already set (a second run in one process) keeps printing: nothing to do.
        if log::set_logger(&FirmwareLog).is_ok() {
            log::set_max_level(log::LevelFilter::Info);
        }
    }
}

impl log::Log for FirmwareLog {
    fn enabled(&self, m: &log::Metadata) -> bool {
        m.target() == "firmware"
    }
    fn log(&self, r: &log::Record) {
        if self.enabled(r.metadata()) {
            eprintln!("firmware {}: {}", r.level(), r.args());
        }
    }
    fn flush(&self) {}
}

/// Frames sent, ETA and the running scores on stderr (a bar on a terminal, else a line every few
/// seconds).
fn progress_bar(frames: usize) -> indicatif::ProgressBar {
    crate::progress::bar(frames as u64, "frames")
}

fn progress_message(p: &super::Progress) -> String {
    let deg = |v: Option<f64>| v.map_or_else(|| "-".to_string(), |v| format!("{v:.3}°"));
    format!(
        "| MAE α {} β {} | deadline misses {}",
        deg(p.alpha_mae_deg),
        deg(p.beta_mae_deg),
        p.deadline_misses
    )
}

/// SYSCLK of the flight computer with its PLL up (168 MHz): DWT cycle counts from a board convert to
/// time at this rate.
const SILICON_SYSCLK_HZ: u32 = firmware::rcc::DISCOVERY.sysclk_hz();

fn cycles_to_us(cycles: u32) -> f64 {
    f64::from(cycles) * 1e6 / f64::from(SILICON_SYSCLK_HZ)
}

/// The short table printed at the end of a run (without `--json`).
fn table(flight: &str, s: &score::Summary, w: &Written) -> String {
    use std::fmt::Write as _;
    let deg = |v: Option<f64>| v.map_or_else(|| "-".to_string(), |v| format!("{v:.3}°"));
    let count = |v: Option<u32>| v.map_or_else(|| "-".to_string(), |v| v.to_string());
    let unit = match s.tick_source.as_str() {
        "Instructions" => "instructions",
        "Cycles" => "cycles",
        "HostNanos" => "ns",
        _ => "ticks",
    };
    let mut t = String::new();
    let _ = writeln!(
        t,
        "{flight} on {}: {:.0} s of flight in {:.1} s ({:.1}x real time)",
        s.firmware,
        s.flight_s,
        s.wall_s,
        s.flight_s / s.wall_s.max(1e-9)
    );
    let _ = writeln!(t, "  {:<16} {:>9} {:>9}", "", "α", "β");
    for (name, a, b) in [
        ("MAE", s.alpha_mae_deg, s.beta_mae_deg),
        ("RMSE", s.alpha_rmse_deg, s.beta_rmse_deg),
        (
            "max |error|",
            s.alpha_max_abs_err_deg,
            s.beta_max_abs_err_deg,
        ),
    ] {
        let _ = writeln!(t, "  {name:<16} {:>9} {:>9}", deg(a), deg(b));
    }
    let pct = |v: Option<f64>| v.map_or_else(|| "-".to_string(), |v| format!("{:.1} %", 100.0 * v));
    let _ = writeln!(
        t,
        "  {:<16} {:>9} {:>9}",
        "within 2σ",
        pct(s.alpha_within_2sigma),
        pct(s.beta_within_2sigma)
    );
    let _ = writeln!(
        t,
        "  {:<16} {} sent, {} answered, {} scored, {} lost, {} rejected as corrupt",
        "frames",
        s.frames_sent,
        s.frames_answered,
        s.frames_scored,
        s.frames_lost,
        s.frames_corrupt_rejected
    );
    let _ = writeln!(
        t,
        "  {:<16} max {}, median {} {unit}; deadline misses {}",
        "step",
        count(s.step_ticks_max),
        count(s.step_ticks_median),
        s.deadline_misses
    );
    if let (Some(up), Some(share)) = (s.uplink_bytes_per_frame, s.uplink_line_share) {
        let _ = writeln!(
            t,
            "  {:<16} sensor frames {up:.0} B, {:.1} % of {} Bd; estimates {:.0} B, {:.1} %",
            "link budget",
            100.0 * share,
            s.provenance.link.baud,
            s.downlink_bytes_per_frame.unwrap_or(0.0),
            100.0 * s.downlink_line_share.unwrap_or(0.0)
        );
    }
    if unit == "cycles" {
        // DWT cycles on silicon: the firmware runs at 168 MHz (firmware::rcc) once the PLL is up.
        let us = |v: Option<u32>| {
            v.map_or_else(|| "-".to_string(), |c| format!("{:.1}", cycles_to_us(c)))
        };
        let _ = writeln!(
            t,
            "  {:<16} max {} µs, median {} µs at {} MHz (budget 50,000 µs)",
            "",
            us(s.step_ticks_max),
            us(s.step_ticks_median),
            SILICON_SYSCLK_HZ / 1_000_000
        );
    }
    for f in &s.faults {
        let opt = |v: Option<String>| v.unwrap_or_else(|| "never".to_string());
        // A bias shows in no frame: no flag is owed at its start, so no latency is reported.
        let flagged = match f.detectable_frame {
            None => "not visible in the frames".to_string(),
            Some(_) => format!(
                "flagged after {} frames{}",
                opt(f.flag_latency_frames.map(|v| v.to_string())),
                if f.flagged_throughout {
                    ", throughout"
                } else {
                    ", NOT throughout"
                }
            ),
        };
        let _ = writeln!(
            t,
            "  {:<16} {}: {flagged}; unflagged estimates moved at most α {:.3}° β {:.3}°; back {} after the sensor's return (max deviation {:.3}°)",
            "fault",
            f.fault,
            f.max_unflagged_dev_deg.0,
            f.max_unflagged_dev_deg.1,
            opt(f.back_after_s.map(|v| format!("{v:.2} s"))),
            f.max_dev_after_return_deg
        );
    }
    let _ = writeln!(t, "  {:<16} {}", "plot", w.png.display());
    let _ = writeln!(t, "  {:<16} {}", "summary (JSON)", w.json.display());
    let _ = writeln!(t, "  {:<16} {}", "estimates (CSV)", w.csv.display());
    t
}

#[cfg(test)]
mod silicon_time {
    #[test]
    fn dwt_cycles_convert_at_168_mhz() {
        assert_eq!(super::SILICON_SYSCLK_HZ, 168_000_000);
        assert_eq!(super::cycles_to_us(8_400_000), 50_000.0);
        assert_eq!(super::cycles_to_us(168), 1.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(clap::Parser)]
    struct Cli {
        #[command(flatten)]
        run: RunArgs,
    }

    fn kind(args: &[&str]) -> Result<FirmwareKind, String> {
        let all = ["run", "--dataset", "f.csv"].iter().chain(args);
        let cli = <Cli as clap::Parser>::try_parse_from(all).map_err(|e| e.to_string())?;
        firmware_kind(&cli.run).map_err(|e| e.to_string())
    }

    /// A flag of another firmware is refused, not ignored, each the same way; a board needs its
    /// port; a firmware's own flags are taken.
    #[test]
    fn a_flag_of_another_firmware_is_refused() {
        for (args, says) in [
            (
                &["--firmware", "host", "--elf", "a.elf"][..],
                "--elf a.elf goes with QEMU (--firmware qemu), not --firmware host",
            ),
            (
                &["--firmware", "host", "--qemu", "q"],
                "--qemu q goes with QEMU (--firmware qemu), not --firmware host",
            ),
            (
                &["--firmware", "host", "--qemu-link", "usart"],
                "--qemu-link usart goes with QEMU (--firmware qemu), not --firmware host",
            ),
            (
                &["--firmware", "qemu", "--baud", "9600"],
                "--baud 9600 goes with a flashed board (--firmware serial), not --firmware qemu",
            ),
            (
                &["--port", "/dev/ttyACM0", "--elf", "a.elf"],
                "--elf a.elf goes with QEMU (--firmware qemu), not --firmware serial",
            ),
            (&["--firmware", "serial"], "--firmware serial needs --port"),
            (&["--baud", "0"], "give a baud rate"),
        ] {
            let e = kind(args).unwrap_err();
            assert!(e.contains(says), "{args:?}: {e}");
        }
        assert_eq!(kind(&[]), Ok(FirmwareKind::Host));
        assert_eq!(
            kind(&[
                "--firmware",
                "qemu",
                "--elf",
                "a",
                "--qemu-link",
                "usart",
                "--qemu",
                "q"
            ]),
            Ok(FirmwareKind::Qemu)
        );
        assert_eq!(
            kind(&["--port", "/dev/ttyACM0", "--baud", "9600"]),
            Ok(FirmwareKind::Serial)
        );
    }

    /// Frames of a suite whose channels the log lacks are refused, saying which columns.
    #[test]
    fn a_log_without_the_columns_the_frames_carry_is_refused() {
        use estimator_core::Suite;
        let csv = Path::new("log.csv");
        let e = check_log_suite(csv, Suite::Egi, Suite::Egi120)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no 120 Hz sub-sample columns") && e.contains("built for the `egi` suite"),
            "{e}"
        );
        let e = check_log_suite(csv, Suite::Table1, Suite::Egi)
            .unwrap_err()
            .to_string();
        assert!(e.contains("no EGI columns"), "{e}");
        assert!(check_log_suite(csv, Suite::Egi120, Suite::Egi120).is_ok());
        assert!(check_log_suite(csv, Suite::Egi, Suite::Table1).is_ok());
    }
}
