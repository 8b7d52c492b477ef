//! `hil-sim run`: flight source → link → firmware → score, with its outputs on disk.

use std::path::{Path, PathBuf};
use std::time::Duration;

use super::target::{InProcess, Qemu, Serial, Target, default_elf};
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
    /// A recorded flight CSV (dataset format, docs/architecture.md).
    #[arg(long)]
    pub dataset: Option<PathBuf>,
    /// A JSBSim runscript (aircraft f16) flown now, then streamed (generated maneuvers are scripts too).
    #[arg(long)]
    pub script: Option<PathBuf>,
}

#[derive(Clone, Debug, clap::Args)]
pub struct RunArgs {
    #[command(flatten)]
    pub source: Source,
    /// Which firmware answers. `--port` implies `serial`.
    #[arg(long, value_enum, default_value = "host")]
    pub firmware: FirmwareKind,
    /// Firmware image for --firmware qemu (default: target/thumbv7em-none-eabihf/firmware/firmware).
    #[arg(long)]
    pub elf: Option<PathBuf>,
    /// QEMU binary.
    #[arg(long, default_value = "qemu-system-arm")]
    pub qemu: String,
    /// Serial device of a flashed board.
    #[arg(long)]
    pub port: Option<PathBuf>,
    /// Baud rate of --port (the board's USART1 runs 115200 at the 16 MHz HSI clock).
    #[arg(long, default_value_t = 115_200)]
    pub baud: u32,
    /// Send frames as fast as the firmware answers instead of every 50 ms of wall time.
    #[arg(long)]
    pub fast: bool,
    /// Sensor suite sent, i.e. the sensor frame kind: table1 (the paper's inputs, wire kind 1) or
    /// egi (Table 1 + EGI attitude, velocity and fuel, wire kind 3). The firmware takes both.
    #[arg(long, default_value = "table1", value_parser = parse_suite)]
    pub suite: estimator_core::Suite,
    /// Print exactly one JSON summary object on stdout (messages go to stderr).
    #[arg(long)]
    pub json: bool,
    /// Seed of the link faults (and of the sensor models when flying a script).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Stop the flight after this many seconds.
    #[arg(long)]
    pub max_time_s: Option<f64>,
    /// Output directory for estimates.csv, summary.json and plot.png.
    #[arg(long, default_value = "runs/latest")]
    pub out: PathBuf,
    /// Link model parameters (TOML: baud, latency_ms, jitter_ms, byte_loss, bit_flip, burst_rate,
    /// burst_len); the flags below override it.
    #[arg(long)]
    pub link: Option<PathBuf>,
    #[arg(long)]
    pub link_baud: Option<u32>,
    #[arg(long)]
    pub latency_ms: Option<f64>,
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
    #[arg(long)]
    pub burst_len: Option<u32>,
    /// Fast mode: how long to wait for the reply to a frame the link left intact, ms.
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

/// Loads or flies the flight.
pub fn flight(source: &Source, seed: u64, max_time_s: Option<f64>) -> Result<Flight, RunError> {
    let mut f = match (&source.dataset, &source.script) {
        (Some(csv), _) => Flight::read_csv(csv)?,
        (None, Some(script)) => crate::plant::fly_script(
            script,
            &crate::plant::FlyConfig {
                seed,
                max_time_s,
                ..Default::default()
            },
        )?,
        (None, None) => return Err(RunError::EmptyFlight),
    };
    if let Some(t) = max_time_s {
        f.samples.retain(|s| s.time_s <= t + 1e-9);
    }
    if f.samples.is_empty() {
        return Err(RunError::EmptyFlight);
    }
    Ok(f)
}

/// Opens the chosen firmware.
pub fn open_target(a: &RunArgs) -> Result<Box<dyn Target>, RunError> {
    let kind = if a.port.is_some() {
        FirmwareKind::Serial
    } else {
        a.firmware
    };
    Ok(match kind {
        FirmwareKind::Host => Box::new(InProcess::new()),
        FirmwareKind::Qemu => {
            let elf = a.elf.clone().unwrap_or_else(default_elf);
            Box::new(Qemu::start(&a.qemu, &elf)?)
        }
        FirmwareKind::Serial => {
            let port = a.port.clone().ok_or_else(|| {
                RunError::Serial(
                    PathBuf::new(),
                    "--firmware serial needs --port /dev/ttyX".into(),
                )
            })?;
            Box::new(Serial::open(&port, a.baud)?)
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
    score::plot::write_png(&w.png, &o.records, s).map_err(|e| out(&w.png, e))?;
    Ok(w)
}

/// A `--suite` value: a [`estimator_core::Suite`] name.
pub fn parse_suite(s: &str) -> Result<estimator_core::Suite, String> {
    estimator_core::Suite::from_name(s).ok_or_else(|| {
        let names: Vec<&str> = estimator_core::Suite::ALL
            .iter()
            .map(|s| s.name())
            .collect();
        format!("unknown sensor suite `{s}` (known: {})", names.join(", "))
    })
}

/// The whole `hil-sim run`.
pub fn run(a: &RunArgs) -> Result<score::Summary, RunError> {
    let cfg = RunConfig {
        link: a.link_config()?,
        seed: a.seed,
        fast: a.fast,
        reply_timeout: Duration::from_millis(a.reply_timeout_ms),
        suite: a.suite,
        ..RunConfig::default()
    };
    let flight = flight(&a.source, a.seed, a.max_time_s)?;
    let samples = samples_of(&flight);
    let mut target = open_target(a)?;
    let outcome = super::run(target.as_mut(), &samples, &cfg)?;
    drop(target);
    let summary = score::summarize(&outcome);
    let w = write_outputs(&a.out, &outcome, &summary)?;
    let msg = format!(
        "{}: {} frames, {} scored, {} lost; wrote {}, {}, {}",
        flight.name,
        summary.frames_sent,
        summary.frames_scored,
        summary.frames_lost,
        w.csv.display(),
        w.json.display(),
        w.png.display()
    );
    if a.json {
        eprintln!("{msg}");
        println!("{}", serde_json::to_string(&summary).unwrap_or_default());
    } else {
        println!("{msg}");
        println!(
            "{}",
            serde_json::to_string_pretty(&summary).unwrap_or_default()
        );
    }
    Ok(summary)
}
