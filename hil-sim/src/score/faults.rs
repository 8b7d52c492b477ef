//! How an estimator came through scripted sensor faults ([`crate::faults`]): how soon its flags said
//! so, whether they kept saying so, and how soon after the sensor's return its estimate was back.
//!
//! "Back" is measured against a reference: the same estimator on the same flight without the fault.
//! The estimate is back at the first frame from which, for [`SETTLED_FRAMES`] frames in a row, both
//! angles are computed (not held) and each is within [`BACK_TOLERANCE_DEG`] of the reference or,
//! where the flight carries truth, lies between the truth and the reference, widened by
//! [`BACK_TOLERANCE_DEG`] on both sides: a filter that starts again after a fault can come back
//! nearer the truth than the fault-free run, which has carried its own error since the start, but an
//! estimate as far off on the other side of the truth is not back.

use estimator_core::health::STUCK_FRAMES;
use estimator_core::{Estimate, Flags};
use serde::Serialize;

use crate::faults::{Fault, FaultKind};

/// Flags that say an input is missing or wrong (the estimate is held, not computed, or computed
/// from substitutes).
pub const FAULT_FLAGS: u16 = Flags::INVALID_INPUT
    | Flags::STUCK_SENSOR
    | Flags::SATURATED
    | Flags::ALPHA_HELD
    | Flags::BETA_HELD
    | Flags::NO_ESTIMATE
    | Flags::GPS_SUBSTITUTED;

/// Largest difference from the fault-free reference, or largest step outside the span from the
/// truth to the reference, that counts as back, degrees (both angles).
pub const BACK_TOLERANCE_DEG: f64 = 0.1;

/// Frames in a row the estimate must stay back (1 s at 20 Hz).
pub const SETTLED_FRAMES: usize = 20;

/// One fault's figures.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FaultScore {
    /// The fault as written on the command line.
    pub fault: String,
    /// Frame index at which the fault first shows in the data: its first frame, or for a stuck
    /// channel the [`STUCK_FRAMES`]th identical value (a frozen value cannot be told apart sooner).
    /// `None` for a bias: nothing in the frames shows it.
    pub detectable_frame: Option<usize>,
    /// Frames from `detectable_frame` to the first answered estimate carrying a [`FAULT_FLAGS`] bit
    /// (0: flagged on that very frame). `None`: never flagged.
    pub flag_latency_frames: Option<usize>,
    /// Every answered estimate from `detectable_frame` to the fault's end carries a [`FAULT_FLAGS`] bit.
    pub flagged_throughout: bool,
    /// Index of the first frame after the fault (the sensor is back).
    pub return_frame: Option<usize>,
    /// Seconds from the sensor's return to the estimate being back (see the module docs). `None`:
    /// not back before the flight (or the next fault) ended.
    pub back_after_s: Option<f64>,
    /// Largest α/β difference from the reference, degrees, over the answered estimates from the
    /// return to the end of the flight (or the next fault).
    pub max_dev_after_return_deg: f64,
    /// Largest α and β difference from the reference, degrees, over the answered estimates that
    /// carry no flag at all, from the fault's first frame to the end of the flight (or the next
    /// fault): how far the fault moved an estimate that did not say so.
    pub max_unflagged_dev_deg: (f64, f64),
}

/// Scores each fault: `estimates` the run with the faults, `reference` the same estimator on the
/// fault-free flight, `truth` each frame's true (α, β) in degrees (empty, or NaN on a frame, where
/// the flight has none), `times_s` each frame's flight time. `None` in `estimates`: no reply came
/// back. Faults are scored in start order, each up to the next one's start.
pub fn score(
    faults: &[Fault],
    estimates: &[Option<Estimate>],
    reference: &[Estimate],
    truth: &[(f64, f64)],
    times_s: &[f64],
) -> Vec<FaultScore> {
    let mut ordered: Vec<&Fault> = faults.iter().collect();
    ordered.sort_by(|a, b| a.start_s.total_cmp(&b.start_s));
    let n = times_s.len().min(estimates.len()).min(reference.len());
    ordered
        .iter()
        .enumerate()
        .map(|(i, fault)| {
            let first = times_s.iter().position(|&t| fault.active(t));
            let detectable = first.and_then(|f| match fault.kind {
                FaultKind::Stuck(_) => Some(f + usize::from(STUCK_FRAMES) - 1),
                FaultKind::Bias(..) => None,
                _ => Some(f),
            });
            let ret = first.map(|f| {
                (f..n)
                    .find(|&k| times_s.get(k).is_some_and(|&t| !fault.active(t)))
                    .unwrap_or(n)
            });
            let end = ordered
                .get(i + 1)
                .and_then(|next| times_s.iter().position(|&t| next.active(t)))
                .unwrap_or(n);
            let answered = |k: usize| estimates.get(k).copied().flatten();
            let flagged = |k: usize| answered(k).map(|e| e.flags.0 & FAULT_FLAGS != 0);
            let (latency, throughout) = match (detectable, ret) {
                (Some(d), Some(r)) => (
                    (d..r).find(|&k| flagged(k) == Some(true)).map(|k| k - d),
                    (d..r).all(|k| flagged(k) != Some(false)),
                ),
                _ => (None, false),
            };
            // The answered estimate of frame k and its α and β differences from the reference.
            let devs = |k: usize| -> Option<(Estimate, f64, f64)> {
                let e = answered(k)?;
                let r = reference.get(k)?;
                Some((
                    e,
                    (e.alpha_deg() - r.alpha_deg()).abs(),
                    (e.beta_deg() - r.beta_deg()).abs(),
                ))
            };
            let dev = |k: usize| devs(k).map(|(_, a, b)| a.max(b));
            // Frame k's estimate lies between the truth and the reference, each end widened by the
            // tolerance, in both angles (false without truth on that frame).
            let no_worse = |k: usize| {
                let within = |e: f64, r: f64, t: f64| {
                    t.is_finite()
                        && e >= t.min(r) - BACK_TOLERANCE_DEG
                        && e <= t.max(r) + BACK_TOLERANCE_DEG
                };
                match (answered(k), reference.get(k), truth.get(k)) {
                    (Some(e), Some(r), Some(&(ta, tb))) => {
                        within(e.alpha_deg(), r.alpha_deg(), ta)
                            && within(e.beta_deg(), r.beta_deg(), tb)
                    }
                    _ => false,
                }
            };
            let back = |k: usize| {
                answered(k).is_some_and(|e| e.flags.is_usable())
                    && (dev(k).is_some_and(|d| d <= BACK_TOLERANCE_DEG) || no_worse(k))
            };
            let back_after_s = ret.and_then(|r| {
                (r..end)
                    .find(|&k| k + SETTLED_FRAMES <= end && (k..k + SETTLED_FRAMES).all(back))
                    .and_then(|k| Some(super::round_ms(times_s.get(k)? - times_s.get(r)?)))
            });
            let max_dev = ret.map_or(0.0, |r| (r..end).filter_map(dev).fold(0.0, f64::max));
            let unflagged = |k: usize| {
                devs(k)
                    .filter(|(e, ..)| e.flags.0 == 0)
                    .map(|(_, a, b)| (a, b))
            };
            let max_unflagged_dev_deg = first.map_or((0.0, 0.0), |f| {
                (f..end)
                    .filter_map(unflagged)
                    .fold((0.0, 0.0), |(a, b), (x, y)| {
                        (f64::max(a, x), f64::max(b, y))
                    })
            });
            FaultScore {
                fault: fault.to_string(),
                detectable_frame: detectable,
                flag_latency_frames: latency,
                flagged_throughout: throughout,
                return_frame: ret,
                back_after_s,
                max_dev_after_return_deg: max_dev,
                max_unflagged_dev_deg,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An estimate of α (β 0) with `flags`.
    fn est(alpha_mdeg: i32, flags: u16) -> Estimate {
        est2(alpha_mdeg, 0, flags)
    }

    /// An estimate of α and β with `flags`.
    fn est2(alpha_mdeg: i32, beta_mdeg: i32, flags: u16) -> Estimate {
        Estimate {
            alpha_mdeg,
            beta_mdeg,
            flags: Flags(flags),
            ..Estimate::default()
        }
    }

    /// The flight times of `n` frames at 20 Hz.
    fn times(n: usize) -> Vec<f64> {
        (0..n).map(|k| k as f64 * 0.05).collect()
    }

    /// `n` answered estimates, frame k's from `at(k)`.
    fn answered(n: usize, at: impl Fn(usize) -> Estimate) -> Vec<Option<Estimate>> {
        (0..n).map(|k| Some(at(k))).collect()
    }

    #[test]
    fn latency_throughout_and_back_time() {
        let times = times(200);
        let fault: Fault = "dead:rudder_deg@1+2".parse().unwrap();
        let reference = vec![est(1000, 0); 200];
        // Flagged from frame 21 (one late), held to 60, then 0.3° off for 10 frames, then back.
        let run = answered(200, |k| match k {
            21..60 => est(900, Flags::INVALID_INPUT | Flags::BETA_HELD),
            60..70 => est(1300, 0),
            _ => est(1050, 0),
        });
        let s = &score(&[fault], &run, &reference, &[], &times)[0];
        assert_eq!(s.detectable_frame, Some(20));
        assert_eq!(s.flag_latency_frames, Some(1));
        assert!(!s.flagged_throughout);
        assert_eq!(s.return_frame, Some(60));
        assert_eq!(s.back_after_s, Some(10.0 * 0.05));
        assert!((s.max_dev_after_return_deg - 0.3).abs() < 1e-9);
        // Unflagged from the fault's first frame on: frame 20 (0.05°) and 60–199 (at most 0.3°).
        let (a, b) = s.max_unflagged_dev_deg;
        assert!((a - 0.3).abs() < 1e-9 && b == 0.0, "{a} {b}");
    }

    #[test]
    fn a_bias_shows_in_no_frame_and_is_scored_by_what_it_moved_unflagged() {
        let times = times(200);
        let fault: Fault = "bias:accel_z_mps2=-39.2266@1+2".parse().unwrap();
        let reference = vec![est(1000, 0); 200];
        // 2.5° off and unflagged on frame 20, flagged (and 4° off) to 60, then back.
        let run = answered(200, |k| match k {
            20 => est(3500, 0),
            21..60 => est(5000, Flags::UNCERTAIN),
            _ => est(1000, 0),
        });
        let s = &score(&[fault], &run, &reference, &[], &times)[0];
        assert_eq!(s.detectable_frame, None);
        assert_eq!(s.flag_latency_frames, None);
        assert_eq!(s.return_frame, Some(60));
        assert_eq!(s.back_after_s, Some(0.0));
        assert_eq!(s.max_unflagged_dev_deg, (2.5, 0.0));
    }

    #[test]
    fn a_stuck_channel_is_detectable_after_stuck_frames_and_lost_replies_do_not_count() {
        let times = times(200);
        let fault: Fault = "stuck:gyro_r_rps@1+3".parse().unwrap();
        let reference = vec![est(0, 0); 200];
        let run: Vec<Option<Estimate>> = (0..200)
            .map(|k| match k {
                40 | 41 => None,
                39..80 => Some(est(0, Flags::STUCK_SENSOR | Flags::BETA_HELD)),
                _ => Some(est(0, 0)),
            })
            .collect();
        let s = &score(&[fault], &run, &reference, &[], &times)[0];
        assert_eq!(s.detectable_frame, Some(20 + usize::from(STUCK_FRAMES) - 1));
        assert_eq!(s.flag_latency_frames, Some(0));
        assert!(s.flagged_throughout);
        assert_eq!(s.back_after_s, Some(0.0));
    }

    #[test]
    fn back_between_the_truth_and_the_reference_counts_where_the_flight_has_truth() {
        let times = times(100);
        let fault: Fault = "gps-loss@1+1".parse().unwrap();
        // The reference errs by +0.3° in α and -0.3° in β all flight; the truth is 2° / -1°.
        let reference = vec![est2(2300, -1300, 0); 100];
        let truth = vec![(2.0, -1.0); 100];
        // 5° off in both angles during the fault, then (α, β) in mdeg from frame 40 on.
        let after = |alpha_mdeg: i32, beta_mdeg: i32| {
            answered(100, move |k| {
                if k < 40 {
                    est2(7000, -6000, 0)
                } else {
                    est2(alpha_mdeg, beta_mdeg, 0)
                }
            })
        };
        let back = |run: &[Option<Estimate>], truth: &[(f64, f64)]| {
            score(&[fault], run, &reference, truth, &times)[0].back_after_s
        };
        // On the truth in both angles: back at once with truth, never without it (none, or NaN).
        let on_truth = after(2000, -1000);
        assert_eq!(back(&on_truth, &truth), Some(0.0));
        assert_eq!(back(&on_truth, &[]), None);
        assert_eq!(back(&on_truth, &[(f64::NAN, f64::NAN); 100]), None);
        // Up to the tolerance past the truth, or past the reference, on either angle: back.
        assert_eq!(back(&after(1910, -1000), &truth), Some(0.0));
        assert_eq!(back(&after(2000, -1390), &truth), Some(0.0));
        assert_eq!(back(&after(2150, -910), &truth), Some(0.0));
        // As far off as the reference but on the other side of the truth, in α or in β: not back.
        assert_eq!(back(&after(1700, -1000), &truth), None);
        assert_eq!(back(&after(2000, -700), &truth), None);
        // 0.15° beyond the reference, in α or in β: not back.
        assert_eq!(back(&after(2450, -1000), &truth), None);
        assert_eq!(back(&after(2000, -1450), &truth), None);
    }

    #[test]
    fn never_back_is_none() {
        let times = times(100);
        let fault: Fault = "gps-loss@1+1".parse().unwrap();
        let reference = vec![est(0, 0); 100];
        let run = vec![Some(est(500, 0)); 100];
        let s = &score(&[fault], &run, &reference, &[], &times)[0];
        assert_eq!(s.flag_latency_frames, None);
        assert_eq!(s.back_after_s, None);
    }
}
