//! Streams a flight's sensor frames through the [`link`](crate::link) to a firmware [`Target`] and
//! collects its estimate frames, matched to the truth by sequence number.
//!
//! One sensor frame per 50 ms of flight time. Real-time pacing sends each byte when the link model
//! says it arrives; `fast` (the default) sends each frame as soon as the previous one is answered.
//! In fast mode the runner feeds the bytes it puts on the line (after the link's faults) to its own
//! copy of the firmware's receiving half ([`firmware::Intake`]), so it knows which frames the
//! firmware will step: it waits for the reply to each of those and sends the next frame at once
//! after one the firmware refuses. No byte reaches the firmware while a step is under way, so
//! neither its receive interrupts nor a full receive queue depend on how fast the host machine
//! is: a seeded run loses the same frames and counts the same instructions every time. A run
//! starts with a lone delimiter, which ends any partial frame a board on `--port` still holds, so
//! the copy and the firmware start from the same empty frame; only a board whose last frame had
//! the seq of the first frame it now receives intact takes that one for a duplicate, which costs
//! one `--reply-timeout-ms`.
//! Replies are matched by seq whenever they arrive; frames never answered count as lost, never
//! scored.

pub mod cli;
pub mod target;

use std::collections::HashMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use estimator_core::wire::estimate::EstimateFrame;
use estimator_core::wire::{Accumulator, DELIMITER, MAX_FRAME};
use estimator_core::{SensorFrame, Suite};

use crate::link::{Link, LinkConfig};
pub use target::{InProcess, Qemu, QemuLink, Serial, Target};

#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error("no firmware image at {0}: run `cargo fw` first (or pass --elf)")]
    NoElf(PathBuf),
    #[error("cannot start {0}: {1} (is it installed? apt-get install qemu-system-arm)")]
    Spawn(String, std::io::Error),
    #[error("QEMU exited before the firmware was ready ({0}): {1}")]
    QemuExited(String, String),
    #[error(
        "QEMU started but the firmware never signalled ready: is {0} a current `cargo fw` image? Rebuild it with `cargo fw`; an image older than the semihosting link answers only with `--qemu-link usart`"
    )]
    NotReady(PathBuf),
    #[error("cannot {0}: {1}")]
    Io(String, std::io::Error),
    #[error("{0} closed while frames were still in flight")]
    Closed(String),
    #[error("serial port {0}: {1}")]
    Serial(PathBuf, String),
    #[error(transparent)]
    Link(#[from] crate::link::LinkError),
    #[error(transparent)]
    Dataset(#[from] crate::dataset::DatasetError),
    #[error(transparent)]
    Plant(#[from] crate::plant::PlantError),
    #[error("the flight has no samples")]
    EmptyFlight,
    #[error("{0} (in the dataset manifest beside the CSV)")]
    Fault(crate::faults::FaultError),
    #[error("cannot write {0}: {1}")]
    Output(PathBuf, String),
    /// Arguments or inputs that do not go together; the message says what to change.
    #[error("{0}")]
    Usage(String),
}

/// The suite the compiled-in estimator reads (table1 for a build without a model): what a run
/// sends unless told otherwise.
pub fn shipped_suite() -> Suite {
    estimator_core::Estimator::shipped()
        .suite()
        .unwrap_or(Suite::Table1)
}

/// How to run.
#[derive(Clone, Debug)]
pub struct RunConfig {
    pub link: LinkConfig,
    pub seed: u64,
    /// Send as fast as the firmware answers; `false` paces every byte at the link's baud and one
    /// frame per 50 ms of wall time (a real board on a serial port).
    pub fast: bool,
    /// Fast mode: how long to wait for the reply to a frame the firmware steps (a firmware that
    /// does not answer in time loses the frame, and the run goes on).
    pub reply_timeout: Duration,
    /// How long to wait for late replies after the last frame.
    pub late_grace: Duration,
    /// The sensor suite sent (default: the shipped estimator's), i.e. the frame kind: as `Table1` the frames carry the paper's inputs
    /// only (the EGI channels are not sent, so the byte stream, and what the link does to it, is
    /// the same as before the EGI suite existed).
    pub suite: Suite,
}

impl Default for RunConfig {
    fn default() -> Self {
        RunConfig {
            link: LinkConfig::default(),
            seed: 1,
            fast: true,
            reply_timeout: Duration::from_secs(10),
            late_grace: Duration::from_millis(50),
            suite: shipped_suite(),
        }
    }
}

/// Sample period of the flight and the estimator.
pub use crate::score::PERIOD_S;
/// What a run produces, as the scoring reads it (defined with the scoring, below the runner).
pub use crate::score::{FrameRecord, RunOutcome};

/// A frame to send and the truth to score its estimate against.
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    pub frame: SensorFrame,
    pub time_s: f64,
    pub alpha_true_deg: f64,
    pub beta_true_deg: f64,
}

/// Where a run stands, reported after every frame sent (and its reply waited for).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Progress {
    /// Frames sent so far, of `total`.
    pub sent: usize,
    pub total: usize,
    /// Running α and β mean absolute error over the estimates scored so far, degrees.
    pub alpha_mae_deg: Option<f64>,
    pub beta_mae_deg: Option<f64>,
    /// Frames scored so far.
    pub scored: usize,
    /// The firmware's deadline-miss counter, the largest seen so far (it only grows).
    pub deadline_misses: u32,
}

/// Running sums behind [`Progress`]: fed each record once, when its reply is matched.
#[derive(Default)]
struct Running {
    scored: usize,
    alpha_abs_sum: f64,
    beta_abs_sum: f64,
    deadline_misses: u32,
}

impl Running {
    fn add(&mut self, r: &FrameRecord) {
        if let Some(f) = r.reply {
            self.deadline_misses = self.deadline_misses.max(f.health.deadline_misses);
        }
        if crate::score::scorable(r) {
            let err = |(truth, estimate): (f64, f64)| (estimate - truth).abs();
            self.scored += 1;
            self.alpha_abs_sum += err(crate::score::alpha_deg(r));
            self.beta_abs_sum += err(crate::score::beta_deg(r));
        }
    }

    fn progress(&self, sent: usize, total: usize) -> Progress {
        let mean = |sum: f64| (self.scored > 0).then(|| sum / self.scored as f64);
        Progress {
            sent,
            total,
            alpha_mae_deg: mean(self.alpha_abs_sum),
            beta_mae_deg: mean(self.beta_abs_sum),
            scored: self.scored,
            deadline_misses: self.deadline_misses,
        }
    }
}

/// Collects the firmware's output: a clean decoder for pacing, then the downlink model, then the
/// receiver hil-sim really has.
struct Downlink {
    raw: Accumulator<MAX_FRAME>,
    pending: Vec<u8>,
    host: Accumulator<MAX_FRAME>,
    replies: Vec<EstimateFrame>,
    rejected: u32,
}

impl Downlink {
    /// Feeds raw firmware bytes; returns whether among them the firmware answered `want` (seen
    /// before link faults).
    fn feed(&mut self, link: &mut Link, t_s: f64, bytes: &[u8], want: Option<u16>) -> bool {
        let mut answered = false;
        for &b in bytes {
            if let Some(Ok(f)) = self.raw.push(b).map(|r| r.and_then(EstimateFrame::parse)) {
                answered |= want == Some(f.estimate.seq);
            }
            self.pending.push(b);
            if b == estimator_core::wire::DELIMITER {
                let d = link.down.transmit(t_s, &self.pending);
                self.pending.clear();
                for &r in &d.bytes {
                    match self.host.push(r).map(|r| r.and_then(EstimateFrame::parse)) {
                        Some(Ok(f)) => self.replies.push(f),
                        Some(Err(_)) => self.rejected += 1,
                        None => {}
                    }
                }
            }
        }
        answered
    }

    /// Receives from `target` until `deadline`, until the firmware answered `want`, or after one
    /// pass for a synchronous target.
    fn pump(
        &mut self,
        target: &mut dyn Target,
        link: &mut Link,
        t_s: f64,
        deadline: Instant,
        want: Option<u16>,
        buf: &mut Vec<u8>,
    ) -> Result<(), RunError> {
        let sync = target.synchronous();
        loop {
            buf.clear();
            target.recv(deadline.saturating_duration_since(Instant::now()), buf)?;
            let answered = self.feed(link, t_s, buf, want);
            if answered || sync || Instant::now() >= deadline {
                return Ok(());
            }
        }
    }
}

/// Runs a flight through the link to `target`.
pub fn run(
    target: &mut dyn Target,
    samples: &[Sample],
    cfg: &RunConfig,
) -> Result<RunOutcome, RunError> {
    run_with_progress(target, samples, cfg, &mut |_| {})
}

/// [`run`], calling `on_frame` after each frame is sent and its reply waited for.
pub fn run_with_progress(
    target: &mut dyn Target,
    samples: &[Sample],
    cfg: &RunConfig,
    on_frame: &mut dyn FnMut(&Progress),
) -> Result<RunOutcome, RunError> {
    cfg.link.validate()?;
    let mut link = Link::new(&cfg.link, cfg.seed);
    let mut down = Downlink {
        raw: Accumulator::new(),
        pending: Vec::new(),
        host: Accumulator::new(),
        replies: Vec::new(),
        rejected: 0,
    };
    let mut records: Vec<FrameRecord> = samples
        .iter()
        .map(|s| FrameRecord {
            seq: s.frame.seq,
            time_s: s.time_s,
            alpha_true_deg: s.alpha_true_deg,
            beta_true_deg: s.beta_true_deg,
            reply: None,
        })
        .collect();
    // A seq sent twice (after u16 wraps) matches its later frame.
    let index_of: HashMap<u16, usize> = records
        .iter()
        .enumerate()
        .map(|(i, r)| (r.seq, i))
        .collect();
    let mut unmatched = 0u32;
    let mut running = Running::default();
    // Puts each reply on the record of the frame it answers, the first intact one winning.
    let mut file_replies =
        |down: &mut Downlink, records: &mut [FrameRecord], running: &mut Running| {
            for f in down.replies.drain(..) {
                match index_of
                    .get(&f.estimate.seq)
                    .and_then(|&i| records.get_mut(i))
                {
                    Some(r) if r.reply.is_none() => {
                        r.reply = Some(f);
                        running.add(r);
                    }
                    _ => unmatched += 1,
                }
            }
        };
    let start = Instant::now();
    let sync = target.synchronous();
    // The firmware's receiving half, fed what the line delivers: which frames it will step.
    let mut intake = firmware::Intake::new();
    // A lone delimiter first, past the link model: it ends any partial frame a firmware that has
    // already received bytes holds (a board on a serial port), so its receiver starts from an empty
    // frame as the copy does. A fresh firmware skips the empty frame it makes.
    target.send(&[DELIMITER])?;
    let mut buf = Vec::new();
    let mut wire = [0u8; MAX_FRAME];

    for (i, s) in samples.iter().enumerate() {
        let t = i as f64 * PERIOD_S;
        let n = s.frame.encode(cfg.suite, &mut wire).unwrap_or(0);
        let d = link.up.transmit(t, wire.get(..n).unwrap_or(&[]));
        if cfg.fast {
            target.send(&d.bytes)?;
        } else {
            // Each byte leaves when the line model says it arrives.
            let mut from = 0;
            for (k, at) in d.arrival_s.iter().enumerate() {
                let due = start + Duration::from_secs_f64(*at);
                if due > Instant::now() + Duration::from_millis(1) {
                    target.send(d.bytes.get(from..k).unwrap_or(&[]))?;
                    from = k;
                    std::thread::sleep(due.saturating_duration_since(Instant::now()));
                }
            }
            target.send(d.bytes.get(from..).unwrap_or(&[]))?;
        }
        // The seq of the last frame among these bytes that the firmware steps and answers (every
        // byte goes through the mirror, so it stays in step with the firmware's receiver).
        let mut stepped = None;
        for b in &d.bytes {
            if let Some(seq) = intake.stepped(*b) {
                stepped = Some(seq);
            }
        }
        let deadline = if !cfg.fast {
            start + Duration::from_secs_f64((i + 1) as f64 * PERIOD_S)
        } else if sync || stepped.is_none() {
            // Nothing to wait for: the firmware refuses these bytes (or has answered already).
            Instant::now()
        } else {
            Instant::now() + cfg.reply_timeout
        };
        let want = if cfg.fast { stepped } else { None };
        down.pump(target, &mut link, t, deadline, want, &mut buf)?;
        file_replies(&mut down, &mut records, &mut running);
        on_frame(&running.progress(i + 1, samples.len()));
    }
    // Late replies.
    if !sync {
        let t = samples.len() as f64 * PERIOD_S;
        let until = Instant::now() + cfg.late_grace;
        down.pump(target, &mut link, t, until, None, &mut buf)?;
        file_replies(&mut down, &mut records, &mut running);
        on_frame(&running.progress(samples.len(), samples.len()));
    }
    Ok(RunOutcome {
        target: target.name(),
        records,
        uplink: link.up.stats(),
        downlink: link.down.stats(),
        baud: cfg.link.baud,
        downlink_rejected: down.rejected,
        unmatched_replies: unmatched,
        wall_s: start.elapsed().as_secs_f64(),
    })
}

/// Each sample's true (α, β), degrees (NaN where the flight records none): the truth
/// [`crate::score::faults::score`] judges a recovery by.
pub fn truth_of(samples: &[Sample]) -> Vec<(f64, f64)> {
    samples
        .iter()
        .map(|s| (s.alpha_true_deg, s.beta_true_deg))
        .collect()
}

/// Samples of a recorded flight: frames numbered from 0 (wrapping at u16), truth from the CSV.
pub fn samples_of(flight: &crate::dataset::Flight) -> Vec<Sample> {
    flight
        .samples
        .iter()
        .zip(crate::frames::flight_frames(flight))
        .map(|(s, frame)| Sample {
            frame,
            time_s: s.time_s,
            alpha_true_deg: s.truth.alpha_deg,
            beta_true_deg: s.truth.beta_deg,
        })
        .collect()
}
