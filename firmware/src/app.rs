//! One estimator step per valid sensor frame, with the link and deadline accounting that travels back
//! in every estimate frame ([`Health`]).
//!
//! Sequence numbers (u16, wrapping) classify each accepted frame by `d = seq - last_seq` (mod 2¹⁶):
//! * `d == 1`: in order.
//! * `1 < d < 2¹⁵`: `d - 1` frames were lost on the way (`rx_lost`); the frame is stepped.
//! * `d == 0`: a duplicate: not stepped again (it would count as a stuck sensor) and not answered.
//! * `d ≥ 2¹⁵`: the sender went backwards, i.e. restarted its flight: the estimator forgets its history
//!   and the frame is stepped as the first of a new sequence.
//!
//! A step's ticks run from the frame's delimiter (decode, CRC, parse) to the end of the estimator
//! step; encoding the reply is a constant few hundred instructions and is left out.

use crate::clock::{Clock, elapsed};
use estimator_core::wire::estimate::{EstimateFrame, Health};
use estimator_core::wire::{self, Accumulator, MAX_FRAME};
use estimator_core::{Estimator, SensorFrame};

/// Board-dependent settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Config {
    /// The step budget in clock ticks: 50 ms at the board clock (800 000 at the 16 MHz HSI clock).
    pub budget_ticks: u32,
}

impl Config {
    /// The 50 ms budget for a clock of `ticks_per_s` ticks per second.
    pub const fn fifty_ms_at(ticks_per_s: u32) -> Config {
        Config {
            budget_ticks: ticks_per_s / 20,
        }
    }
}

/// Counters that do not travel on the wire.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Sensor frames stepped (and answered).
    pub stepped: u32,
    /// Frames with the previous frame's seq, dropped unanswered.
    pub duplicates: u32,
    /// Backward sequence jumps (sender restarts).
    pub restarts: u32,
    /// The most ticks any step took.
    pub max_step_ticks: u32,
}

/// Where an accepted frame's seq stands against the last accepted one (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeqEvent {
    /// The first frame, or the next one in order.
    InOrder,
    /// This many frames were lost on the way; the frame is stepped.
    Gap(u32),
    /// The last frame's seq again: not stepped, not answered.
    Duplicate,
    /// The sender went backwards (restarted its flight) from seq `was`: a new sequence.
    Restart { was: u16 },
}

impl SeqEvent {
    /// Whether [`App`] steps (and answers) a frame with this event.
    pub const fn stepped(self) -> bool {
        !matches!(self, SeqEvent::Duplicate)
    }
}

/// The receiving half of the firmware: bytes in, decoded sensor frames out, then each one's place
/// in the sequence. [`App`] steps what it gives; a sender can run its own copy over the bytes it
/// puts on the line to know, byte for byte, which frames the firmware will answer (hil-sim does,
/// to never send while a step is under way).
pub struct Intake {
    acc: Accumulator<MAX_FRAME>,
    last_seq: Option<u16>,
}

impl Default for Intake {
    fn default() -> Self {
        Self::new()
    }
}

impl Intake {
    pub const fn new() -> Self {
        Intake {
            acc: Accumulator::new(),
            last_seq: None,
        }
    }

    /// Feeds one received byte: `None` until it completes a frame (a delimiter), then the sensor
    /// frame or why it was refused. A frame that comes out goes to [`Intake::sequence`] next.
    #[inline(always)]
    pub fn push(&mut self, byte: u8) -> Option<Result<SensorFrame, wire::Error>> {
        match self.acc.push(byte)? {
            Ok(body) => Some(SensorFrame::parse(body)),
            Err(e) => Some(Err(e)),
        }
    }

    /// Both halves for a sender: the seq of the frame this byte completes if the firmware steps
    /// (and answers) it.
    pub fn stepped(&mut self, byte: u8) -> Option<u16> {
        let seq = self.push(byte)?.ok()?.seq;
        self.sequence(seq).stepped().then_some(seq)
    }

    /// Where a decoded frame's `seq` stands; makes it the last one unless it repeats it.
    #[inline(always)]
    pub fn sequence(&mut self, seq: u16) -> SeqEvent {
        let Some(last) = self.last_seq else {
            self.last_seq = Some(seq);
            return SeqEvent::InOrder;
        };
        let d = seq.wrapping_sub(last);
        if d == 0 {
            return SeqEvent::Duplicate;
        }
        self.last_seq = Some(seq);
        if d >= 0x8000 {
            SeqEvent::Restart { was: last }
        } else if d == 1 {
            SeqEvent::InOrder
        } else {
            // 1 < d < 2^15 here, so `d - 1` cannot wrap.
            SeqEvent::Gap(u32::from(d.wrapping_sub(1)))
        }
    }
}

/// The application: owns the frame intake, the estimator and the counters.
pub struct App<'m, C: Clock> {
    intake: Intake,
    estimator: Estimator<'m>,
    clock: C,
    config: Config,
    health: Health,
    stats: Stats,
}

impl<'m, C: Clock> App<'m, C> {
    pub fn new(estimator: Estimator<'m>, clock: C, config: Config) -> Self {
        let health = Health {
            tick_source: clock.source(),
            ..Health::default()
        };
        App {
            intake: Intake::new(),
            estimator,
            clock,
            config,
            health,
            stats: Stats::default(),
        }
    }

    /// The counters sent with the last estimate.
    pub fn health(&self) -> Health {
        self.health
    }

    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// The receiver's overrun count so far (each lost at least one byte before it reached
    /// [`App::push`]; the board's is [`crate::ByteQueue::overruns`]): sent as
    /// `rx_overruns` with the next estimate. The board layer owns the receiver, so it reports the
    /// count; the in-process firmware has no receiver queue and leaves it at 0.
    pub fn set_rx_overruns(&mut self, total: u32) {
        self.health.rx_overruns = total;
    }

    /// Feeds one received byte. When it completes a new valid sensor frame (either kind: a Table 1
    /// frame steps with the EGI channels invalid), runs one step and writes the encoded estimate
    /// frame (COBS, CRC, delimiter) to `out`, returning its length.
    pub fn push(&mut self, byte: u8, out: &mut [u8; MAX_FRAME]) -> Option<usize> {
        let start = self.clock.now();
        let frame = match self.intake.push(byte)? {
            Ok(f) => f,
            Err(e) => {
                self.health.rx_corrupt = self.health.rx_corrupt.saturating_add(1);
                warn!("frame rejected: {}", e);
                return None;
            }
        };
        match self.intake.sequence(frame.seq) {
            SeqEvent::InOrder => {}
            SeqEvent::Gap(lost) => {
                self.health.rx_lost = self.health.rx_lost.saturating_add(lost);
            }
            SeqEvent::Duplicate => {
                self.stats.duplicates = self.stats.duplicates.saturating_add(1);
                return None;
            }
            SeqEvent::Restart { was } => {
                self.stats.restarts = self.stats.restarts.saturating_add(1);
                info!("sequence restarted at {} (was {})", frame.seq, was);
                self.estimator.reset();
            }
        }
        let estimate = self.estimator.step(&frame);
        let ticks = elapsed(start, self.clock.now());
        self.health.step_ticks = ticks;
        if ticks > self.config.budget_ticks {
            self.health.deadline_misses = self.health.deadline_misses.saturating_add(1);
            warn!("deadline miss: seq {} took {} ticks", frame.seq, ticks);
        }
        self.stats.stepped = self.stats.stepped.saturating_add(1);
        self.stats.max_step_ticks = self.stats.max_step_ticks.max(ticks);
        let reply = EstimateFrame {
            estimate,
            health: self.health,
        };
        // An estimate frame always fits MAX_FRAME (it is shorter than a sensor frame).
        reply.encode(out).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimator_core::channels::ALL_VALID;
    use estimator_core::wire::estimate::TickSource;
    use estimator_core::{CHANNELS, Channel, Flags, Suite};

    /// A clock that advances a fixed amount per reading.
    struct Stepping {
        t: u32,
        per_read: u32,
    }
    impl Clock for Stepping {
        fn now(&mut self) -> u32 {
            self.t = self.t.wrapping_add(self.per_read);
            self.t
        }
        fn source(&self) -> TickSource {
            TickSource::Instructions
        }
    }

    fn app(per_read: u32, budget: u32) -> App<'static, Stepping> {
        App::new(
            Estimator::shipped(),
            Stepping {
                t: u32::MAX - 5,
                per_read,
            },
            Config {
                budget_ticks: budget,
            },
        )
    }

    fn frame(seq: u16) -> SensorFrame {
        let mut raw = [0i32; CHANNELS];
        for (i, r) in raw.iter_mut().enumerate() {
            *r = (i as i32 - 8) * 100 + i32::from(seq % 500);
        }
        raw[Channel::Throttle.index()] = 5000;
        SensorFrame {
            seq,
            time_ms: u32::from(seq) * 50,
            raw,
            valid: ALL_VALID,
            sub: estimator_core::channels::Subsamples::NONE,
        }
    }

    /// The frame as a sender of the shipped model's suite delivers it.
    fn wire(seq: u16) -> Vec<u8> {
        wire_of(Estimator::shipped().suite().unwrap_or(Suite::Table1), seq)
    }

    /// Frames `seqs` in order, each after up to `max_gap - 1` pseudo-random bytes (xorshift32 from
    /// `seed`).
    fn frames_in_garbage(seed: u32, seqs: core::ops::Range<u16>, max_gap: u32) -> Vec<u8> {
        let mut x = seed;
        let mut bytes = Vec::new();
        for seq in seqs {
            for _ in 0..(x % max_gap) {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                bytes.push((x >> 24) as u8);
            }
            bytes.extend(wire(seq));
        }
        bytes
    }

    fn wire_of(suite: Suite, seq: u16) -> Vec<u8> {
        let mut out = [0u8; MAX_FRAME];
        let n = frame(seq).encode(suite, &mut out).unwrap();
        out[..n].to_vec()
    }

    /// Feeds bytes, returns the decoded replies.
    fn feed<C: Clock>(app: &mut App<'_, C>, bytes: &[u8]) -> Vec<EstimateFrame> {
        let mut replies = Vec::new();
        let mut out = [0u8; MAX_FRAME];
        for b in bytes {
            if let Some(n) = app.push(*b, &mut out) {
                let mut acc = Accumulator::<MAX_FRAME>::new();
                let mut decoded = None;
                for b in &out[..n] {
                    if let Some(body) = acc.push(*b) {
                        decoded = Some(EstimateFrame::parse(body.unwrap()).unwrap());
                    }
                }
                replies.push(decoded.unwrap());
            }
        }
        replies
    }

    #[test]
    fn one_reply_per_frame_echoing_seq_time_and_the_estimator() {
        let mut a = app(10, 1000);
        let mut reference = Estimator::shipped();
        for seq in 0..5u16 {
            let r = feed(&mut a, &wire(seq));
            assert_eq!(r.len(), 1);
            assert_eq!(r[0].estimate, reference.step(&frame(seq)));
            assert_eq!(r[0].estimate.seq, seq);
            assert_eq!(r[0].estimate.time_ms, u32::from(seq) * 50);
            assert_eq!(r[0].health.tick_source, TickSource::Instructions);
            assert_eq!(r[0].health.rx_lost, 0);
            assert_eq!(r[0].health.rx_corrupt, 0);
        }
        if !estimator_core::model::HAS_MODEL {
            let r = feed(&mut a, &wire(5));
            assert!(r[0].estimate.flags.has(Flags::NO_MODEL));
        }
        assert_eq!(
            a.stats().stepped,
            6 - u32::from(estimator_core::model::HAS_MODEL)
        );
    }

    #[test]
    fn both_sensor_kinds_are_stepped_in_one_sequence() {
        let mut a = app(10, 1000);
        let mut reference = Estimator::shipped();
        for seq in 0..6u16 {
            let suite = if seq % 2 == 0 {
                Suite::Egi
            } else {
                Suite::Table1
            };
            let r = feed(&mut a, &wire_of(suite, seq));
            assert_eq!(r.len(), 1, "{suite:?} frame {seq}");
            let sent = frame(seq).restricted_to(suite);
            assert_eq!(r[0].estimate, reference.step(&sent));
            assert_eq!(r[0].health.rx_corrupt, 0);
        }
    }

    #[test]
    fn step_ticks_wrap_and_the_budget_is_a_parameter() {
        // The clock starts 6 ticks before the wrap and advances 10 per reading: the step spans it.
        let mut a = app(10, 10);
        let r = feed(&mut a, &wire(0));
        assert_eq!(r[0].health.step_ticks, 10);
        assert_eq!(r[0].health.deadline_misses, 0);
        let mut tight = app(10, 9);
        let r = feed(&mut tight, &[wire(0), wire(1)].concat());
        assert_eq!(r[0].health.deadline_misses, 1);
        assert_eq!(r[1].health.deadline_misses, 2);
        assert_eq!(tight.stats().max_step_ticks, 10);
    }

    #[test]
    fn gaps_count_lost_frames_across_the_u16_wrap() {
        let mut a = app(1, 1000);
        let seqs = [65533u16, 65534, 1, 2, 5];
        let r = feed(
            &mut a,
            &seqs.iter().flat_map(|s| wire(*s)).collect::<Vec<_>>(),
        );
        let lost: Vec<u32> = r.iter().map(|e| e.health.rx_lost).collect();
        // 65535 and 0 missing, then 3 and 4.
        assert_eq!(lost, [0, 0, 2, 2, 4]);
    }

    #[test]
    fn duplicates_are_neither_stepped_nor_answered() {
        let mut a = app(1, 1000);
        let r = feed(&mut a, &[wire(7), wire(7), wire(8)].concat());
        assert_eq!(r.iter().map(|e| e.estimate.seq).collect::<Vec<_>>(), [7, 8]);
        assert_eq!(r[1].health.rx_lost, 0);
        assert_eq!(a.stats().duplicates, 1);
        assert_eq!(a.stats().stepped, 2);
    }

    #[test]
    fn a_backward_jump_is_a_restart_not_a_loss() {
        let mut a = app(1, 1000);
        let r = feed(&mut a, &[wire(500), wire(501), wire(0), wire(1)].concat());
        assert_eq!(r.len(), 4);
        assert!(r.iter().all(|e| e.health.rx_lost == 0));
        assert_eq!(a.stats().restarts, 1);
    }

    #[test]
    fn garbage_is_counted_and_the_next_frame_still_decodes() {
        let mut a = app(1, 1000);
        let mut bytes = wire(1);
        bytes.extend_from_slice(&[0x55; 300]); // longer than any frame: overflow
        bytes.push(0);
        bytes.extend_from_slice(&[0x12, 0x34, 0x00]); // too short
        bytes.extend_from_slice(&[0x00, 0x00]); // empty frames are skipped
        bytes.extend(wire(2));
        let r = feed(&mut a, &bytes);
        assert_eq!(r.len(), 2);
        assert_eq!(r[1].estimate.seq, 2);
        assert_eq!(r[1].health.rx_corrupt, 2);
        assert_eq!(r[1].health.rx_lost, 0);
    }

    #[test]
    fn corrupted_frames_are_rejected_and_counted() {
        let mut a = app(1, 1000);
        let good = wire(3);
        let mut flipped = wire(4);
        flipped[10] ^= 0x04;
        let mut truncated = wire(5);
        truncated.remove(20);
        let mut estimate_kind = [0u8; MAX_FRAME];
        let n = EstimateFrame::default().encode(&mut estimate_kind).unwrap();
        // A sound frame (CRC, COBS, layout) of another aircraft: refused like a corrupted one.
        let suite = Estimator::shipped().suite().unwrap_or(Suite::Table1);
        let mut body = [0u8; MAX_FRAME];
        let len = frame(6).emit_body(suite, &mut body).unwrap();
        body[8..12].copy_from_slice(&estimator_core::wire::aircraft_tag("another").to_le_bytes());
        let mut other_aircraft = [0u8; MAX_FRAME];
        let m = estimator_core::wire::encode(&body[..len], &mut other_aircraft).unwrap();
        let bytes = [
            good,
            flipped,
            truncated,
            estimate_kind[..n].to_vec(),
            other_aircraft[..m].to_vec(),
            wire(7),
        ]
        .concat();
        let r = feed(&mut a, &bytes);
        assert_eq!(r.iter().map(|e| e.estimate.seq).collect::<Vec<_>>(), [3, 7]);
        assert_eq!(r[1].health.rx_corrupt, 4);
        assert_eq!(r[1].health.rx_lost, 3);
    }

    #[test]
    fn an_intake_beside_the_app_knows_which_bytes_it_answers() {
        // Frames in order, a gap, a duplicate, a restart, a flipped bit, a lost delimiter and
        // random bytes: after every byte, the intake says a frame will be answered exactly when
        // the app answers one, and names its seq.
        let mut flipped = wire(13);
        flipped[5] ^= 0x10;
        let mut merged = wire(14);
        merged.pop(); // its delimiter lost: 15 is glued to it and refused with it
        let mut bytes = [
            wire(10),
            wire(11),
            wire(11),
            wire(12),
            flipped,
            merged,
            wire(15),
            wire(16),
            wire(20),
            wire(3),
            wire(4),
        ]
        .concat();
        bytes.extend(frames_in_garbage(0x9e37_79b9, 5..40, 30));
        let mut a = app(1, 1000);
        let mut intake = Intake::new();
        let mut out = [0u8; MAX_FRAME];
        let mut answered = Vec::new();
        for b in &bytes {
            let predicted = intake.stepped(*b);
            let reply = a.push(*b, &mut out).map(|n| {
                let mut acc = Accumulator::<MAX_FRAME>::new();
                let mut seq = None;
                for b in &out[..n] {
                    if let Some(body) = acc.push(*b) {
                        seq = Some(EstimateFrame::parse(body.unwrap()).unwrap().estimate.seq);
                    }
                }
                seq.unwrap()
            });
            assert_eq!(predicted, reply);
            answered.extend(predicted);
        }
        // Random bytes without a zero glue onto the frame after them, which is refused with them.
        assert_eq!(answered[..7], [10, 11, 12, 16, 20, 3, 4]);
        assert!(answered.len() > 20, "{answered:?}");
        assert_eq!(a.stats().stepped as usize, answered.len());
        assert_eq!(a.stats().duplicates, 1);
        assert_eq!(a.stats().restarts, 1);
    }

    #[test]
    fn receiver_overruns_travel_with_the_next_estimate() {
        let mut a = app(1, 1000);
        let r = feed(&mut a, &wire(1));
        assert_eq!(r[0].health.rx_overruns, 0);
        // The board's queue dropped bytes of the next frame: that frame is lost (CRC), and the
        // overrun count arrives with the one after it.
        let queue = crate::ByteQueue::<8>::new();
        for b in wire(2) {
            let _ = queue.push(b);
        }
        let got: Vec<u8> = std::iter::from_fn(|| queue.pop()).collect();
        assert_eq!(queue.overruns() as usize, wire(2).len() - 8);
        a.set_rx_overruns(queue.overruns());
        assert!(feed(&mut a, &got).is_empty());
        let r = feed(
            &mut a,
            &[0].iter().copied().chain(wire(3)).collect::<Vec<_>>(),
        );
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].health.rx_overruns, queue.overruns());
        assert_eq!(r[0].health.rx_corrupt, 1);
        assert_eq!(r[0].health.rx_lost, 1);
    }

    #[test]
    fn arbitrary_bytes_never_panic_and_every_reply_decodes() {
        let mut a = app(3, 1000);
        // A deterministic pseudo-random stream with frames mixed in.
        let bytes = frames_in_garbage(0x1234_5678, 0..200, 40);
        let r = feed(&mut a, &bytes);
        assert!(!r.is_empty());
        assert!(r.windows(2).all(|w| w[1].estimate.seq > w[0].estimate.seq));
    }
}
