//! Scores a run: α/β error statistics over the frames that came back with a computed estimate, link
//! and firmware counters, step timing; writes the per-frame CSV, the JSON summary and a PNG plot.

use std::collections::BTreeMap;
use std::path::Path;

use estimator_core::uncertainty::SIGMA_UNKNOWN;
use estimator_core::wire::estimate::TickSource;
use estimator_core::{Estimate, Flags};
use serde::Serialize;

use crate::link::LinkStats;
use estimator_core::wire::estimate::EstimateFrame;

/// Sample period of the flight and the estimator, s.
pub const PERIOD_S: f64 = 1.0 / crate::flight::SAMPLE_HZ as f64;

/// One sensor frame sent and what came back for it (what `runner` records and this module scores).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameRecord {
    pub seq: u16,
    pub time_s: f64,
    pub alpha_true_deg: f64,
    pub beta_true_deg: f64,
    /// The estimate frame that came back intact, if any.
    pub reply: Option<EstimateFrame>,
}

/// Everything a run produced.
#[derive(Clone, Debug, Default)]
pub struct RunOutcome {
    pub target: &'static str,
    pub records: Vec<FrameRecord>,
    pub uplink: LinkStats,
    pub downlink: LinkStats,
    /// The link's baud rate (both directions), for the line shares of the link budget.
    pub baud: u32,
    /// Estimate frames hil-sim rejected (COBS, CRC, length, version, kind).
    pub downlink_rejected: u32,
    /// Intact estimate frames whose seq matched no frame sent.
    pub unmatched_replies: u32,
    pub wall_s: f64,
}

/// Error statistics of one angle, degrees.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ErrorStats {
    pub mae: f64,
    pub rmse: f64,
    pub max: f64,
}

impl ErrorStats {
    /// None when there is nothing to score.
    pub fn of(errors: &[f64]) -> Option<ErrorStats> {
        if errors.is_empty() {
            return None;
        }
        let n = errors.len() as f64;
        Some(ErrorStats {
            mae: errors.iter().map(|e| e.abs()).sum::<f64>() / n,
            rmse: (errors.iter().map(|e| e * e).sum::<f64>() / n).sqrt(),
            max: errors.iter().fold(0.0, |m: f64, e| m.max(e.abs())),
        })
    }
}

/// What a run's figures are of: the input, the settings and the model (docs/flight-log.md).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Provenance {
    /// The flight's name (the CSV's or the script's file stem).
    pub flight: String,
    /// `--dataset CSV` or `--script XML`, as given.
    pub input: String,
    /// `--aircraft-dir` of a flown script (`None`: JSBSim's own F-16, or a recorded flight).
    pub aircraft_dir: Option<String>,
    pub seed: u64,
    /// Sensor suite of the frames sent.
    pub suite: String,
    pub max_time_s: Option<f64>,
    /// Scripted faults (`--fault`, and those the dataset manifest lists for the flight).
    pub faults: Vec<String>,
    /// The compiled-in model's training provenance (`None` in a build without a model).
    pub model: Option<String>,
    /// `git describe` of the hil-sim build's tree.
    pub git_rev: String,
    pub hil_sim_version: String,
    /// The simulated link's parameters.
    pub link: crate::link::LinkConfig,
}

/// Seconds rounded to the millisecond, as a duration is read.
pub fn round_ms(s: f64) -> f64 {
    (s * 1000.0).round() / 1000.0
}

/// The `--json` object. Angles in degrees; `null` where there is nothing to measure.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub provenance: Provenance,
    pub firmware: String,
    pub has_model: bool,
    pub alpha_mae_deg: Option<f64>,
    pub beta_mae_deg: Option<f64>,
    pub alpha_rmse_deg: Option<f64>,
    pub beta_rmse_deg: Option<f64>,
    pub alpha_max_abs_err_deg: Option<f64>,
    pub beta_max_abs_err_deg: Option<f64>,
    /// Share of the frames with truth and a 1σ whose |error| ≤ 2σ (95 % is the design point).
    pub alpha_within_2sigma: Option<f64>,
    pub beta_within_2sigma: Option<f64>,
    pub frames_sent: usize,
    /// Estimates received intact.
    pub frames_answered: usize,
    /// Estimates scored: answered and computed (not `NO_MODEL`/`NO_ESTIMATE`).
    pub frames_scored: usize,
    /// Scored frames with a true α or β in the input (a flight log without truth has none; each
    /// angle's error statistics are over the frames with its truth).
    pub frames_with_truth: usize,
    /// Answered frames carrying each flag (names as in estimates.csv).
    pub flags: BTreeMap<String, usize>,
    /// Frames with no intact estimate back (lost or corrupted either way): counted, not scored.
    pub frames_lost: usize,
    /// Frames rejected on both sides: firmware `rx_corrupt` plus estimate frames hil-sim rejected.
    pub frames_corrupt_rejected: u64,
    pub firmware_rx_corrupt: u64,
    pub firmware_rx_lost: u64,
    /// Receive overruns the firmware reported (each loses at least one byte before decoding: the
    /// host sent faster than the firmware read). 0 under QEMU, whose USART holds bytes back while
    /// the firmware's queue is full.
    pub firmware_rx_overruns: u64,
    pub host_rx_corrupt: u64,
    pub unmatched_replies: u64,
    pub deadline_misses: u64,
    pub tick_source: String,
    pub step_ticks_max: Option<u32>,
    pub step_ticks_median: Option<u32>,
    pub step_instructions_max: Option<u32>,
    pub step_instructions_median: Option<u32>,
    /// Multiply-accumulates per step of hil-sim's own compiled-in model (0 without one). The estimate
    /// frames do not carry it: for an `--elf` built with other weights (`ESTIMATOR_WEIGHTS`), compute
    /// the count from that export instead.
    pub macs_per_step: usize,
    pub flight_s: f64,
    pub wall_s: f64,
    pub uplink: LinkStats,
    pub downlink: LinkStats,
    /// The link budget: the share of each direction's line the run's frames took (bytes sent ×
    /// 10 bit, 8N1, over the baud rate × the flight time; 1 is a full line, beyond it the frames
    /// queue up), and the mean bytes per frame on the wire (`null` without frames).
    pub uplink_line_share: Option<f64>,
    pub downlink_line_share: Option<f64>,
    pub uplink_bytes_per_frame: Option<f64>,
    pub downlink_bytes_per_frame: Option<f64>,
    /// Scripted sensor faults (`--fault`) and how the estimator came through each (empty without).
    pub faults: Vec<faults::FaultScore>,
}

/// α of a record: (truth, estimate), the estimate NaN when no reply came back.
pub fn alpha_deg(r: &FrameRecord) -> (f64, f64) {
    (
        r.alpha_true_deg,
        r.reply.map_or(f64::NAN, |f| f.estimate.alpha_deg()),
    )
}

/// β of a record: (truth, estimate), the estimate NaN when no reply came back.
pub fn beta_deg(r: &FrameRecord) -> (f64, f64) {
    (
        r.beta_true_deg,
        r.reply.map_or(f64::NAN, |f| f.estimate.beta_deg()),
    )
}

/// Whether the estimate in a record is one the estimator computed.
pub fn scorable(r: &FrameRecord) -> bool {
    r.reply
        .is_some_and(|f| !f.estimate.flags.has(Flags::NO_MODEL | Flags::NO_ESTIMATE))
}

fn median(v: &mut [u32]) -> Option<u32> {
    v.sort_unstable();
    v.get(v.len() / 2).copied()
}

pub fn summarize(o: &RunOutcome) -> Summary {
    let scored: Vec<&FrameRecord> = o.records.iter().filter(|r| scorable(r)).collect();
    let with_truth = scored
        .iter()
        .filter(|r| r.alpha_true_deg.is_finite() || r.beta_true_deg.is_finite())
        .count();
    // Estimate − truth over the scored records (all of which have a reply) with a true angle.
    let err = |angle: fn(&FrameRecord) -> (f64, f64)| -> Vec<f64> {
        scored
            .iter()
            .map(|r| angle(r))
            .filter(|(truth, _)| truth.is_finite())
            .map(|(truth, estimate)| estimate - truth)
            .collect()
    };
    let a = ErrorStats::of(&err(alpha_deg));
    let b = ErrorStats::of(&err(beta_deg));
    // |estimate − truth| ≤ 2σ over the scored records with a true angle and a 1σ.
    let within_2sigma = |angle: fn(&FrameRecord) -> (f64, f64), sigma: fn(&Estimate) -> u16| {
        let pairs: Vec<bool> = scored
            .iter()
            .filter_map(|r| {
                let (truth, estimate) = angle(r);
                let s = sigma(&r.reply?.estimate);
                (truth.is_finite() && s != SIGMA_UNKNOWN)
                    .then(|| (estimate - truth).abs() <= 2e-3 * f64::from(s))
            })
            .collect();
        (!pairs.is_empty())
            .then(|| pairs.iter().filter(|&&b| b).count() as f64 / pairs.len() as f64)
    };
    let replies: Vec<_> = o.records.iter().filter_map(|r| r.reply).collect();
    // The firmware's health counters only grow: the largest is the latest.
    let counter = |f: fn(&estimator_core::wire::estimate::Health) -> u32| {
        replies.iter().map(|r| f(&r.health)).max().unwrap_or(0) as u64
    };
    let source = replies
        .last()
        .map_or(TickSource::None, |r| r.health.tick_source);
    let mut ticks: Vec<u32> = replies.iter().map(|r| r.health.step_ticks).collect();
    let tmax = ticks.iter().copied().max();
    let tmed = median(&mut ticks);
    let instr = source == TickSource::Instructions;
    let fw_corrupt = counter(|h| h.rx_corrupt);
    let flags = Flags::NAMED
        .iter()
        .map(|&(bit, name)| {
            let n = replies.iter().filter(|r| r.estimate.flags.has(bit)).count();
            (name.to_string(), n)
        })
        .collect();
    let flight_s = o.records.len() as f64 * PERIOD_S;
    Summary {
        provenance: Provenance::default(),
        firmware: o.target.to_string(),
        has_model: estimator_core::model::HAS_MODEL,
        alpha_mae_deg: a.map(|s| s.mae),
        beta_mae_deg: b.map(|s| s.mae),
        alpha_rmse_deg: a.map(|s| s.rmse),
        beta_rmse_deg: b.map(|s| s.rmse),
        alpha_max_abs_err_deg: a.map(|s| s.max),
        beta_max_abs_err_deg: b.map(|s| s.max),
        alpha_within_2sigma: within_2sigma(alpha_deg, |e| e.sigma_alpha_mdeg),
        beta_within_2sigma: within_2sigma(beta_deg, |e| e.sigma_beta_mdeg),
        frames_sent: o.records.len(),
        frames_answered: replies.len(),
        frames_scored: scored.len(),
        frames_with_truth: with_truth,
        flags,
        frames_lost: o.records.len() - replies.len(),
        frames_corrupt_rejected: fw_corrupt + u64::from(o.downlink_rejected),
        firmware_rx_corrupt: fw_corrupt,
        firmware_rx_lost: counter(|h| h.rx_lost),
        firmware_rx_overruns: counter(|h| h.rx_overruns),
        host_rx_corrupt: u64::from(o.downlink_rejected),
        unmatched_replies: u64::from(o.unmatched_replies),
        deadline_misses: counter(|h| h.deadline_misses),
        tick_source: format!("{source:?}"),
        step_ticks_max: tmax,
        step_ticks_median: tmed,
        step_instructions_max: tmax.filter(|_| instr),
        step_instructions_median: tmed.filter(|_| instr),
        macs_per_step: estimator_core::Estimator::shipped().macs(),
        flight_s: round_ms(flight_s),
        wall_s: round_ms(o.wall_s),
        uplink: o.uplink,
        downlink: o.downlink,
        uplink_line_share: line_share(&o.uplink, o.baud, flight_s),
        downlink_line_share: line_share(&o.downlink, o.baud, flight_s),
        uplink_bytes_per_frame: per_frame(&o.uplink),
        downlink_bytes_per_frame: per_frame(&o.downlink),
        faults: Vec::new(),
    }
}

/// Mean bytes per transmission of a direction.
fn per_frame(s: &LinkStats) -> Option<f64> {
    (s.frames_sent > 0).then(|| s.bytes_sent as f64 / s.frames_sent as f64)
}

/// The share of a line of `baud` (8N1: 10 bit per byte) that `s`'s bytes took over `flight_s`.
fn line_share(s: &LinkStats, baud: u32, flight_s: f64) -> Option<f64> {
    let capacity_bytes = f64::from(baud) / 10.0 * flight_s;
    (capacity_bytes > 0.0).then(|| s.bytes_sent as f64 / capacity_bytes)
}

/// A 1σ in millidegrees as degrees, exactly; empty when the angle has none (held).
fn sigma_cell(mdeg: u16) -> String {
    if mdeg == SIGMA_UNKNOWN {
        String::new()
    } else {
        thousandths(i32::from(mdeg))
    }
}

/// An integer count of thousandths (millidegrees, mm/s) as the decimal it is, exactly: `-1234` →
/// `-1.234`.
pub fn thousandths(v: i32) -> String {
    let sign = if v < 0 { "-" } else { "" };
    let a = v.unsigned_abs();
    format!("{sign}{}.{:03}", a / 1000, a % 1000)
}

/// The per-frame CSV's header: angles in degrees, velocities in m/s, one 0/1 column per flag.
pub fn csv_header() -> Vec<String> {
    let mut h: Vec<String> = [
        "seq",
        "time_s",
        "alpha_true_deg",
        "beta_true_deg",
        "received",
        "alpha_deg",
        "beta_deg",
        "w_aero_mps",
        "v_aero_mps",
        "sigma_alpha_deg",
        "sigma_beta_deg",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    h.extend(Flags::NAMED.iter().map(|(_, n)| format!("flag_{n}")));
    h.extend(["step_ticks".to_string(), "tick_source".to_string()]);
    h
}

/// Per-frame CSV: truth (empty where the input has none), the estimate as sent (the integer fields
/// exactly, as decimals of their unit), each flag, step ticks. Columns: docs/flight-log.md.
pub fn write_csv(path: &Path, records: &[FrameRecord]) -> Result<(), csv::Error> {
    let mut w = csv::Writer::from_path(path)?;
    let header = csv_header();
    w.write_record(&header)?;
    let truth = |v: f64| {
        if v.is_finite() {
            format!("{v:.6}")
        } else {
            String::new()
        }
    };
    for r in records {
        let mut row = vec![
            r.seq.to_string(),
            format!("{:.3}", r.time_s),
            truth(r.alpha_true_deg),
            truth(r.beta_true_deg),
        ];
        match r.reply {
            Some(f) => {
                let e = f.estimate;
                row.extend([
                    "1".to_string(),
                    thousandths(e.alpha_mdeg),
                    thousandths(e.beta_mdeg),
                    thousandths(e.w_aero_mms),
                    thousandths(e.v_aero_mms),
                    sigma_cell(e.sigma_alpha_mdeg),
                    sigma_cell(e.sigma_beta_mdeg),
                ]);
                row.extend(
                    Flags::NAMED
                        .iter()
                        .map(|&(bit, _)| u8::from(e.flags.has(bit)).to_string()),
                );
                row.extend([
                    f.health.step_ticks.to_string(),
                    format!("{:?}", f.health.tick_source),
                ]);
            }
            None => row.push("0".to_string()),
        }
        row.resize(header.len(), String::new());
        w.write_record(&row)?;
    }
    w.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thousandths_are_exact_decimals() {
        assert_eq!(thousandths(0), "0.000");
        assert_eq!(thousandths(-1234), "-1.234");
        assert_eq!(thousandths(5), "0.005");
        assert_eq!(thousandths(-5), "-0.005");
        assert_eq!(thousandths(i32::MIN), "-2147483.648");
    }

    #[test]
    fn durations_round_to_the_millisecond() {
        assert_eq!(round_ms(0.9999999999999432), 1.0);
        assert_eq!(round_ms(1200.0000000004), 1200.0);
    }
}

pub mod faults;
pub mod plot;
