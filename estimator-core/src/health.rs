//! Channel health: which channels of a frame may be used, beyond the sender's valid bits.
//!
//! A sensor can fail without saying so. Two failures are visible in the data itself:
//! * **stuck**: a noisy channel (IMU, GPS, EGI: [`Channel::is_noisy`]) repeats exactly the same value
//!   for [`STUCK_FRAMES`] frames. One repeat proves nothing (at 20 Hz a quantized noisy output
//!   repeats now and then); twenty in a row do not happen in flight. So a stuck channel is flagged
//!   on the [`STUCK_FRAMES`]th identical frame, 1 s after it froze, and clears on the first change.
//! * **saturated**: an IMU output at or beyond its measuring range ([`Channel::full_scale`]) is the
//!   sensor's clip level, not the aircraft's motion. Flagged on the frame it happens, whether the
//!   20 Hz value or one of the period's 120 Hz sub-samples ([`crate::Subsamples`]) clipped.
//!
//! [`Health::check`] returns both as masks; [`crate::FeatureState`] hides such channels from the
//! air-data filter and the delta history (as if their valid bit were clear), and
//! [`crate::Estimator`] holds the angle whose model reads one and flags why.

use crate::channels::{CHANNELS, Channel, SensorFrame};

/// Identical consecutive values of a noisy channel that make it stuck (1 s at 20 Hz).
pub const STUCK_FRAMES: u16 = 20;

/// What is wrong with a frame's channels, bit per [`Channel`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Status {
    /// Noisy channels unchanged for [`STUCK_FRAMES`] frames (this one included).
    pub stuck: u32,
    /// Valid IMU channels at or beyond their full scale, in the 20 Hz value or a sub-sample.
    pub saturated: u32,
}

impl Status {
    /// Channels that are valid in `frame` and neither stuck nor saturated.
    pub fn usable(&self, frame: &SensorFrame) -> u32 {
        frame.valid & !self.stuck & !self.saturated
    }
}

/// Per-channel repeat counts (the only state health needs).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Health {
    repeats: [u16; CHANNELS],
}

impl Default for Health {
    fn default() -> Self {
        Self::new()
    }
}

impl Health {
    pub const fn new() -> Self {
        Health {
            repeats: [0; CHANNELS],
        }
    }

    /// Checks `frame` against the channel values of the frame before it (`None` before the first).
    pub fn check(&mut self, frame: &SensorFrame, previous: Option<&[i32; CHANNELS]>) -> Status {
        let previous = previous.unwrap_or(&[0; CHANNELS]);
        let mut status = Status::default();
        for (((c, raw), last), n) in Channel::ALL
            .iter()
            .zip(&frame.raw)
            .zip(previous)
            .zip(self.repeats.iter_mut())
        {
            if let Some(fs) = c.full_scale()
                && frame.is_valid(*c)
                && raw.unsigned_abs().max(frame.sub.peak(*c)) >= fs.unsigned_abs()
            {
                status.saturated |= c.bit();
            }
            if !c.is_noisy() {
                continue;
            }
            // The repeat count saturates, and so must the comparison: `n + 1` wrapped to 0 once the
            // count reached u16::MAX (55 minutes of one value), clearing the flag for good.
            *n = if raw == last { n.saturating_add(1) } else { 0 };
            if n.saturating_add(1) >= STUCK_FRAMES {
                status.stuck |= c.bit();
            }
        }
        status
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::channels::ALL_VALID;

    fn frame(k: i32) -> SensorFrame {
        let mut f = SensorFrame {
            valid: ALL_VALID,
            ..SensorFrame::default()
        };
        for (i, r) in f.raw.iter_mut().enumerate() {
            *r = 1000 * i as i32 + k;
        }
        f
    }

    #[test]
    fn a_frozen_channel_is_stuck_on_the_twentieth_identical_frame_and_clears_on_change() {
        let mut h = Health::new();
        let mut prev: Option<SensorFrame> = None;
        let mut first_stuck = None;
        for k in 0..40 {
            let mut f = frame(k);
            if (10..30).contains(&k) {
                f.raw[Channel::GyroR.index()] = 77;
            }
            let s = h.check(&f, prev.as_ref().map(|p| &p.raw));
            assert_eq!(s.stuck & !Channel::GyroR.bit(), 0);
            if s.stuck != 0 && first_stuck.is_none() {
                first_stuck = Some(k);
            }
            if k == 30 {
                assert_eq!(s.stuck, 0, "cleared on the first change");
            }
            prev = Some(f);
        }
        // Frozen from frame 10: frame 10 is the first of the value, 29 its 20th.
        assert_eq!(first_stuck, Some(10 + i32::from(STUCK_FRAMES) - 1));
    }

    #[test]
    fn surfaces_never_count_as_stuck() {
        let mut h = Health::new();
        let f = frame(0);
        let mut s = Status::default();
        for _ in 0..100 {
            s = h.check(&f, Some(&f.raw));
        }
        for c in Channel::ALL {
            assert_eq!(s.stuck & c.bit() != 0, c.is_noisy(), "{c:?}");
        }
    }

    #[test]
    fn imu_at_full_scale_is_saturated_at_once_and_only_while_valid() {
        let mut h = Health::new();
        let mut f = frame(1);
        f.raw[Channel::AccelZ.index()] = -39_226_600;
        f.raw[Channel::GyroP.index()] = 17_453_292;
        let s = h.check(&f, None);
        assert_eq!(s.saturated, Channel::AccelZ.bit());
        assert_eq!(s.usable(&f), ALL_VALID & !Channel::AccelZ.bit());
        f.raw[Channel::GyroP.index()] = i32::MIN;
        f.valid &= !Channel::AccelZ.bit();
        let s = h.check(&f, None);
        assert_eq!(s.saturated, Channel::GyroP.bit());
        assert_eq!(
            s.usable(&f),
            ALL_VALID & !(Channel::AccelZ.bit() | Channel::GyroP.bit())
        );
    }

    #[test]
    fn a_subsample_at_full_scale_saturates_its_channel_though_the_20_hz_value_did_not_clip() {
        use crate::channels::Subsamples;
        let mut h = Health::new();
        let mut f = frame(1);
        f.sub.valid = Subsamples::ALL_VALID;
        let Some(i) = Subsamples::position(Channel::GyroR) else {
            panic!("gyro r is sub-sampled")
        };
        f.sub.raw[2][i] = -17_453_293; // −1000 °/s in µrad/s, inside the period
        assert_eq!(h.check(&f, None).saturated, Channel::GyroR.bit());
        // One count short of full scale is motion, not a clip; invalid sub-samples are not read.
        f.sub.raw[2][i] = -17_453_292;
        assert_eq!(h.check(&f, None).saturated, 0);
        f.sub.raw[2][i] = i32::MIN;
        f.sub.valid &= !(1 << i);
        assert_eq!(h.check(&f, None).saturated, 0);
    }
}
