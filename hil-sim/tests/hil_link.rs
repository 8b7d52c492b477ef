//! The link model against the in-process firmware: corrupted frames are never accepted on either
//! side, the receivers resynchronise within one frame after garbage, and lost frames are counted,
//! not scored. Deterministic seeds: every run sees the same faults.

use estimator_core::channels::ALL_VALID;
use estimator_core::wire::estimate::EstimateFrame;
use estimator_core::wire::{Accumulator, MAX_FRAME};
use estimator_core::{CHANNELS, Channel, Estimator, SensorFrame};
use hil_sim::link::{Direction, LinkConfig};
use hil_sim::runner::{self, InProcess, RunConfig, Sample, Target};
use hil_sim::score;

/// A smooth, plausible cruise: every channel moves so nothing reads as stuck.
fn frame(seq: u16) -> SensorFrame {
    let t = f64::from(seq) * 0.05;
    let mut si = [0.0; CHANNELS];
    let w = |f: f64, a: f64| a * (f * t).sin();
    si[Channel::GyroP.index()] = w(0.7, 0.05);
    si[Channel::GyroQ.index()] = w(0.5, 0.03);
    si[Channel::GyroR.index()] = w(0.3, 0.02);
    si[Channel::AccelX.index()] = 0.5 + w(0.2, 0.3);
    si[Channel::AccelY.index()] = w(0.9, 0.4);
    si[Channel::AccelZ.index()] = -9.81 + w(0.6, 1.5);
    si[Channel::GpsSpeed.index()] = 180.0 + w(0.05, 10.0);
    si[Channel::GpsAlt.index()] = 4572.0 + w(0.02, 50.0);
    si[Channel::Elevator.index()] = -2.0 + w(0.5, 1.0);
    si[Channel::Aileron.index()] = w(0.7, 2.0);
    si[Channel::Rudder.index()] = w(0.3, 1.0);
    si[Channel::Throttle.index()] = 0.6 + w(0.1, 0.1);
    SensorFrame::from_si(seq, u32::from(seq) * 50, &si)
}

/// The first `n` frames of [`frame`]'s cruise as a flight, at α 2°, β 0.
fn cruise(n: u16) -> Vec<Sample> {
    (0..n)
        .map(|s| Sample {
            frame: frame(s),
            time_s: f64::from(s) * 0.05,
            alpha_true_deg: 2.0,
            beta_true_deg: 0.0,
        })
        .collect()
}

fn encode(f: &SensorFrame) -> Vec<u8> {
    let mut out = [0u8; MAX_FRAME];
    let n = f.encode(estimator_core::Suite::Egi, &mut out).unwrap();
    out[..n].to_vec()
}

fn faulty(seed: u64) -> Direction {
    Direction::new(
        LinkConfig {
            byte_loss: 1e-3,
            bit_flip: 1e-4,
            ..LinkConfig::default()
        },
        seed,
    )
}

#[test]
fn no_corrupted_frame_is_ever_accepted_on_either_side() {
    let frames: Vec<SensorFrame> = (0..4000u16).map(frame).collect();
    assert_eq!(frames[0].valid, ALL_VALID);
    let mut fw = firmware::App::new(
        Estimator::shipped(),
        firmware::NoClock,
        firmware::Config { budget_ticks: 1 },
    );
    let (mut up, mut down) = (faulty(7), faulty(8));
    let mut raw_replies = Vec::new();
    let mut host = Accumulator::<MAX_FRAME>::new();
    let mut host_got = Vec::new();
    let mut out = [0u8; MAX_FRAME];
    for (i, f) in frames.iter().enumerate() {
        let d = up.transmit(i as f64 * 0.05, &encode(f));
        for b in d.bytes {
            if let Some(n) = fw.push(b, &mut out) {
                let wire = out[..n].to_vec();
                let mut acc = Accumulator::<MAX_FRAME>::new();
                for &w in &wire {
                    if let Some(body) = acc.push(w) {
                        raw_replies.push(EstimateFrame::parse(body.unwrap()).unwrap());
                    }
                }
                for r in down.transmit(i as f64 * 0.05, &wire).bytes {
                    if let Some(Ok(body)) = host.push(r)
                        && let Ok(e) = EstimateFrame::parse(body)
                    {
                        host_got.push(e);
                    }
                }
            }
        }
    }
    let up_stats = up.stats();
    assert!(
        up_stats.frames_altered > 100,
        "the faults must bite: {up_stats:?}"
    );
    assert!(raw_replies.len() < frames.len());
    assert!(raw_replies.len() > frames.len() * 8 / 10);
    // Firmware side: the frames it stepped are exactly original frames, in order: replaying those
    // originals through a fresh estimator gives the same estimates bit for bit.
    let mut reference = Estimator::shipped();
    for r in &raw_replies {
        let original = &frames[usize::from(r.estimate.seq)];
        assert_eq!(r.estimate, reference.step(original));
    }
    // Lost frames are counted by sequence gaps.
    let last = raw_replies.last().unwrap();
    let answered_until_last = raw_replies.len() as u32;
    assert_eq!(
        last.health.rx_lost,
        u32::from(last.estimate.seq) + 1 - answered_until_last
    );
    assert!(last.health.rx_corrupt > 0);
    // Host side: every estimate it accepted is one the firmware sent.
    assert!(host_got.len() < raw_replies.len());
    for h in &host_got {
        assert!(
            raw_replies.contains(h),
            "host accepted a frame never sent: {h:?}"
        );
    }
}

#[test]
fn resynchronises_within_one_frame_after_garbage() {
    let mut fw = firmware::App::new(
        Estimator::shipped(),
        firmware::NoClock,
        firmware::Config { budget_ticks: 1 },
    );
    let mut x = 0xDEAD_BEEFu32;
    let mut out = [0u8; MAX_FRAME];
    for round in 0..50u16 {
        let mut bytes = encode(&frame(3 * round));
        // Garbage of any length and content, delimiters included, ending mid-"frame".
        for _ in 0..(x % 300) {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            bytes.push((x >> 11) as u8);
        }
        bytes.extend(encode(&frame(3 * round + 1)));
        bytes.extend(encode(&frame(3 * round + 2)));
        let mut answered = Vec::new();
        for b in bytes {
            if fw.push(b, &mut out).is_some() {
                answered.push(fw.health().rx_corrupt);
            }
        }
        // The frame right after the garbage may go down with it; the one after that never does.
        let stats = fw.stats();
        assert!(answered.len() >= 2, "round {round}: {answered:?} {stats:?}");
    }
}

#[test]
fn lost_frames_are_counted_not_scored() {
    let samples = cruise(1500);
    let cfg = RunConfig {
        link: LinkConfig {
            byte_loss: 1e-3,
            bit_flip: 1e-4,
            burst_rate: 1e-4,
            ..LinkConfig::default()
        },
        seed: 42,
        ..RunConfig::default()
    };
    let run = |seed| {
        let mut t = InProcess::new();
        runner::run(
            &mut t,
            &samples,
            &RunConfig {
                seed,
                ..cfg.clone()
            },
        )
        .unwrap()
    };
    let o = run(42);
    let s = score::summarize(&o);
    let unanswered = o.records.iter().filter(|r| r.reply.is_none()).count();
    assert!(unanswered > 0);
    assert_eq!(s.frames_lost, unanswered);
    assert_eq!(s.frames_answered + s.frames_lost, s.frames_sent);
    assert!(s.frames_scored <= s.frames_answered);
    assert!(s.frames_corrupt_rejected > 0);
    assert_eq!(s.unmatched_replies, 0);
    // Every reply sits on the record of the frame it answers.
    assert!(o.records.iter().all(|r| {
        r.reply
            .is_none_or(|f| f.estimate.seq == r.seq && f.estimate.time_ms == r.seq as u32 * 50)
    }));
    // Same seed, same run.
    let again = run(42);
    assert_eq!(
        again.records,
        o.records
            .iter()
            .map(|r| {
                let mut r = *r;
                // Host step time is wall-clock: not part of the comparison.
                if let (Some(a), Some(b)) = (r.reply.as_mut(), again.records[r.seq as usize].reply)
                {
                    a.health.step_ticks = b.health.step_ticks;
                }
                r
            })
            .collect::<Vec<_>>()
    );
}

/// The in-process firmware, with the wall time and length of every write to it.
struct Recording {
    fw: InProcess,
    writes: Vec<(std::time::Instant, usize)>,
}

impl runner::Target for Recording {
    fn name(&self) -> &'static str {
        "recording"
    }
    fn send(&mut self, bytes: &[u8]) -> Result<(), runner::RunError> {
        self.writes.push((std::time::Instant::now(), bytes.len()));
        self.fw.send(bytes)
    }
    fn recv(
        &mut self,
        timeout: std::time::Duration,
        out: &mut Vec<u8>,
    ) -> Result<(), runner::RunError> {
        self.fw.recv(timeout, out)
    }
    fn synchronous(&self) -> bool {
        true
    }
}

#[test]
fn realtime_paces_every_byte_at_the_link_baud() {
    // 19 200 Bd: 0.52 ms a byte, a frame takes ~33 ms of its 50 ms period, so each frame starts on
    // its period and byte k of frame i is due at 50 ms · i + (k + 1) byte times.
    const BAUD: u32 = 19_200;
    let byte_s = 10.0 / f64::from(BAUD);
    let samples = cruise(6);
    let due: Vec<f64> = samples
        .iter()
        .enumerate()
        .flat_map(|(i, s)| {
            (0..encode(&s.frame).len()).map(move |k| i as f64 * 0.05 + (k + 1) as f64 * byte_s)
        })
        .collect();
    let mut t = Recording {
        fw: InProcess::new(),
        writes: Vec::new(),
    };
    let cfg = RunConfig {
        link: LinkConfig {
            baud: BAUD,
            ..LinkConfig::default()
        },
        fast: false,
        // `encode` above counts EGI frames: send those, whatever suite the shipped model reads.
        suite: estimator_core::Suite::Egi,
        ..RunConfig::default()
    };
    let started = std::time::Instant::now();
    let o = runner::run(&mut t, &samples, &cfg).unwrap();
    assert!(o.records.iter().all(|r| r.reply.is_some()));
    // The run's lone delimiter first, at once; then the frames' bytes.
    let (first, writes) = t.writes.split_first().unwrap();
    assert_eq!(first.1, 1);
    assert_eq!(writes.iter().map(|w| w.1).sum::<usize>(), due.len());
    // No byte leaves more than the runner's 1 ms of slack before it is due (plus 0.1 ms for rounding;
    // `started` is a few microseconds before the run's own clock starts, which is lenient by as much).
    let mut sent = 0;
    for &(at, n) in writes {
        sent += n;
        let at_s = at.duration_since(started).as_secs_f64();
        assert!(
            due[sent - 1] <= at_s + 1e-3 + 1e-4,
            "byte {sent} due {} sent {at_s}",
            due[sent - 1]
        );
    }
    // And the line is really paced: the bytes trickle out in small writes, and the last one goes no
    // earlier than it is due.
    assert!(writes.len() > due.len() / 4, "{} writes", writes.len());
    let last = writes
        .last()
        .unwrap()
        .0
        .duration_since(started)
        .as_secs_f64();
    assert!(last >= due[due.len() - 1] - 1e-3, "last write at {last}");
}

/// A firmware that has already received part of a frame (a board left running on its serial
/// port) answers a run's first frame: the run starts with a lone delimiter that ends the partial
/// frame (rejected, counted as corrupt), so the first frame does not join it. A fresh firmware
/// skips that empty frame and counts nothing.
#[test]
fn a_run_ends_a_partial_frame_the_firmware_still_holds() {
    let samples = cruise(20);
    let cfg = RunConfig::default();
    let fresh = runner::run(&mut InProcess::new(), &samples, &cfg).unwrap();
    let mut stale = InProcess::new();
    let half = encode(&frame(900));
    stale.send(&half[..half.len() / 2]).unwrap();
    let run = runner::run(&mut stale, &samples, &cfg).unwrap();
    for o in [&fresh, &run] {
        assert!(o.records.iter().all(|r| r.reply.is_some()));
    }
    let last = |o: &runner::RunOutcome| o.records.last().unwrap().reply.unwrap().health.rx_corrupt;
    assert_eq!((last(&fresh), last(&run)), (0, 1));
    for (a, b) in fresh.records.iter().zip(&run.records) {
        assert_eq!(a.reply.unwrap().estimate, b.reply.unwrap().estimate);
    }
}
