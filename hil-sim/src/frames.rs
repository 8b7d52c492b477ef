//! Dataset samples → sensor frames, the one conversion the HIL runner and the parity tests share.

use estimator_core::SensorFrame;
use estimator_core::channels::Subsamples;

use crate::flight::{Flight, Sample};

/// Milliseconds of a sample time, rounded (20 Hz times are multiples of 50 ms up to float noise).
pub fn time_ms(time_s: f64) -> u32 {
    let ms = (time_s * 1000.0).round();
    if ms.is_finite() && ms >= 0.0 {
        // Wrap like the wire field does after 49 days.
        (ms as u64 % (u64::from(u32::MAX) + 1)) as u32
    } else {
        0
    }
}

/// The sensor frame of sample `seq` (sequence numbers wrap at u16), with the sample's 120 Hz
/// sub-samples where it carries them.
pub fn sample_to_frame(seq: u16, sample: &Sample) -> SensorFrame {
    SensorFrame {
        sub: Subsamples::from_si(&sample.sub),
        ..SensorFrame::from_si(seq, time_ms(sample.time_s), &sample.sensed)
    }
}

/// All frames of a flight, `seq` counting from 0.
pub fn flight_frames(flight: &Flight) -> impl Iterator<Item = SensorFrame> + '_ {
    flight
        .samples
        .iter()
        .enumerate()
        .map(|(i, s)| sample_to_frame(i as u16, s))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flight::Truth;
    use estimator_core::{CHANNELS, Channel};

    #[test]
    fn frame_carries_the_sample() {
        let mut sensed = [0.0; CHANNELS];
        sensed[Channel::AccelZ.index()] = -9.81;
        sensed[Channel::GpsAlt.index()] = 4572.12;
        let s = Sample {
            time_s: 12.35,
            truth: Truth::default(),
            sensed,
            sub: crate::flight::NO_SUBSAMPLES,
        };
        let f = sample_to_frame(7, &s);
        assert_eq!(f.seq, 7);
        assert_eq!(f.time_ms, 12_350);
        assert_eq!(f.get(Channel::AccelZ), -981_000);
        assert_eq!(f.get(Channel::GpsAlt), 457_212);
        assert_eq!(f.valid.count_ones() as usize, CHANNELS);
    }
}
