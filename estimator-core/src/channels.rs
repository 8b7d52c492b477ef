//! The sensed channels, their integer units, and the validated sensor frame.
//!
//! This is the single definition of what a sensor frame carries and in which fixed-point unit. Every
//! value is an integer in the unit named here, as a sensor bus would deliver it; the estimator never
//! sees floats. `SensorFrame::from_si` is the host-side conversion (NaN, ±Inf and out-of-range values
//! become invalid channels, never numbers).

/// Number of sensed channels in a frame.
pub const CHANNELS: usize = 16;

/// A sensed channel, in frame order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Channel {
    /// Body roll rate, µrad/s.
    GyroP = 0,
    /// Body pitch rate, µrad/s.
    GyroQ,
    /// Body yaw rate, µrad/s.
    GyroR,
    /// Body x specific force at the IMU, 1e-5 m/s² (no gravity; ≈ 0 in level flight).
    AccelX,
    /// Body y specific force, 1e-5 m/s².
    AccelY,
    /// Body z specific force, 1e-5 m/s² (≈ -9.81 m/s² in level flight).
    AccelZ,
    /// GPS total (3-D) ground speed, mm/s.
    GpsSpeed,
    /// GPS altitude above mean sea level, cm.
    GpsAlt,
    /// Elevator position, 0.01°.
    Elevator,
    /// Aileron position, 0.01°.
    Aileron,
    /// Rudder position, 0.01°.
    Rudder,
    /// Leading-edge flap position, 0.01°.
    Lef,
    /// Trailing-edge flap position, 0.01°.
    Tef,
    /// Flaperon position (left), 0.01°.
    Flaperon,
    /// Speedbrake position, 0.01°.
    Speedbrake,
    /// Throttle lever, 1e-4 of full travel (0.5 = military power, 1.0 = full afterburner).
    Throttle,
}

impl Channel {
    pub const ALL: [Channel; CHANNELS] = [
        Channel::GyroP,
        Channel::GyroQ,
        Channel::GyroR,
        Channel::AccelX,
        Channel::AccelY,
        Channel::AccelZ,
        Channel::GpsSpeed,
        Channel::GpsAlt,
        Channel::Elevator,
        Channel::Aileron,
        Channel::Rudder,
        Channel::Lef,
        Channel::Tef,
        Channel::Flaperon,
        Channel::Speedbrake,
        Channel::Throttle,
    ];

    pub const fn index(self) -> usize {
        self as usize
    }

    pub const fn bit(self) -> u16 {
        1 << (self as u16)
    }

    /// Size of one integer step in the SI (or degree / normalised) unit of [`Channel::name`].
    pub const fn lsb(self) -> f64 {
        match self {
            Channel::GyroP | Channel::GyroQ | Channel::GyroR => 1e-6,
            Channel::AccelX | Channel::AccelY | Channel::AccelZ => 1e-5,
            Channel::GpsSpeed => 1e-3,
            Channel::GpsAlt => 1e-2,
            Channel::Throttle => 1e-4,
            _ => 1e-2,
        }
    }

    /// Range the wire type can carry (surfaces and throttle are 16-bit on the wire).
    pub const fn raw_range(self) -> (i32, i32) {
        match self {
            Channel::Throttle => (0, u16::MAX as i32),
            Channel::Elevator
            | Channel::Aileron
            | Channel::Rudder
            | Channel::Lef
            | Channel::Tef
            | Channel::Flaperon
            | Channel::Speedbrake => (i16::MIN as i32, i16::MAX as i32),
            _ => (i32::MIN, i32::MAX),
        }
    }

    /// Channels whose noise makes an unchanged value over many frames a sign of a stuck sensor.
    pub const fn is_noisy(self) -> bool {
        (self as u8) <= Channel::GpsAlt as u8
    }
}

/// All channels valid.
pub const ALL_VALID: u16 = u16::MAX >> (16 - CHANNELS);

/// [`Channel::name`] and the delta-feature names from one list: `"<name>_d<frames>"` for every lag.
macro_rules! channel_names {
    ($($v:ident => $c:literal),* $(,)?) => {
        impl Channel {
            /// Column name used in datasets and reports.
            pub const fn name(self) -> &'static str {
                match self {
                    $(Channel::$v => $c,)*
                }
            }

            /// Name of `Feature::Delta(self, lag)`.
            pub(crate) const fn delta_name(self, lag: crate::features::Lag) -> &'static str {
                use crate::features::Lag;
                match self {
                    $(Channel::$v => match lag {
                        Lag::F1 => concat!($c, "_d1"),
                        Lag::F4 => concat!($c, "_d4"),
                        Lag::F10 => concat!($c, "_d10"),
                        Lag::F20 => concat!($c, "_d20"),
                    },)*
                }
            }
        }
    };
}
channel_names!(
    GyroP => "gyro_p_rps",
    GyroQ => "gyro_q_rps",
    GyroR => "gyro_r_rps",
    AccelX => "accel_x_mps2",
    AccelY => "accel_y_mps2",
    AccelZ => "accel_z_mps2",
    GpsSpeed => "gps_speed_mps",
    GpsAlt => "gps_alt_m",
    Elevator => "elevator_deg",
    Aileron => "aileron_deg",
    Rudder => "rudder_deg",
    Lef => "lef_deg",
    Tef => "tef_deg",
    Flaperon => "flaperon_deg",
    Speedbrake => "speedbrake_deg",
    Throttle => "throttle_norm",
);

/// One validated sensor sample: the payload of a sensor frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SensorFrame {
    /// Frame sequence number (wraps).
    pub seq: u16,
    /// Sample time, ms since the start of the flight (wraps after 49 days).
    pub time_ms: u32,
    /// Channel values in [`Channel`] order and units.
    pub raw: [i32; CHANNELS],
    /// Bit `c` set: channel `c` is valid (sensor self-test passed, value finite and in range).
    pub valid: u16,
}

impl SensorFrame {
    pub fn get(&self, c: Channel) -> i32 {
        self.raw.get(c.index()).copied().unwrap_or(0)
    }

    pub fn is_valid(&self, c: Channel) -> bool {
        self.valid & c.bit() != 0
    }

    /// Converts SI values (in [`Channel::name`] units) to a frame. A NaN, an infinity, or a value the
    /// channel cannot carry gives raw 0 with the channel marked invalid.
    pub fn from_si(seq: u16, time_ms: u32, si: &[f64; CHANNELS]) -> SensorFrame {
        let mut f = SensorFrame {
            seq,
            time_ms,
            raw: [0; CHANNELS],
            valid: 0,
        };
        for ((c, v), raw) in Channel::ALL.iter().zip(si.iter()).zip(f.raw.iter_mut()) {
            if let Some(q) = quantize(*v, c.lsb(), c.raw_range()) {
                *raw = q;
                f.valid |= c.bit();
            }
        }
        f
    }

    /// Channel values in SI units (invalid channels read as NaN).
    pub fn to_si(&self) -> [f64; CHANNELS] {
        core::array::from_fn(|i| match Channel::ALL.get(i) {
            Some(c) if self.is_valid(*c) => self.get(*c) as f64 * c.lsb(),
            _ => f64::NAN,
        })
    }
}

/// Rounds `v / lsb` to the nearest integer if it is finite and inside `range`.
pub fn quantize(v: f64, lsb: f64, range: (i32, i32)) -> Option<i32> {
    let q = v / lsb;
    if !q.is_finite() {
        return None;
    }
    // Round half away from zero, then check the rounded value (so the range ends themselves fit).
    // (`as i64` truncates toward zero and saturates, so huge values stay out of range.)
    let r = (if q >= 0.0 { q + 0.5 } else { q - 0.5 }) as i64;
    if r < range.0 as i64 || r > range.1 as i64 {
        return None;
    }
    Some(r as i32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_inf_and_out_of_range_become_invalid_channels() {
        let mut si = [0.0; CHANNELS];
        si[Channel::GyroP.index()] = f64::NAN;
        si[Channel::AccelZ.index()] = f64::NEG_INFINITY;
        si[Channel::Elevator.index()] = 400.0; // 40000 > i16::MAX hundredths of a degree
        si[Channel::GpsSpeed.index()] = 250.0004;
        let f = SensorFrame::from_si(7, 350, &si);
        assert!(!f.is_valid(Channel::GyroP));
        assert!(!f.is_valid(Channel::AccelZ));
        assert!(!f.is_valid(Channel::Elevator));
        assert!(f.is_valid(Channel::GpsSpeed));
        assert_eq!(f.get(Channel::GpsSpeed), 250_000);
        assert_eq!(f.get(Channel::GyroP), 0);
        assert_eq!(f.valid.count_ones(), CHANNELS as u32 - 3);
    }

    #[test]
    fn rounding_is_to_nearest_both_signs() {
        assert_eq!(quantize(-0.0149, 0.01, (-10, 10)), Some(-1));
        assert_eq!(quantize(0.0151, 0.01, (-10, 10)), Some(2));
        assert_eq!(quantize(0.105, 0.01, (-10, 10)), None);
    }

    #[test]
    fn both_ends_of_the_range_are_carried() {
        let full = (i32::MIN, i32::MAX);
        assert_eq!(quantize(i32::MIN as f64, 1.0, full), Some(i32::MIN));
        assert_eq!(quantize(i32::MAX as f64, 1.0, full), Some(i32::MAX));
        assert_eq!(quantize(-10.4, 1.0, (-10, 10)), Some(-10));
        assert_eq!(quantize(-10.5, 1.0, (-10, 10)), None);
        assert_eq!(quantize(10.4, 1.0, (-10, 10)), Some(10));
        assert_eq!(quantize(10.5, 1.0, (-10, 10)), None);
        let s16 = Channel::Rudder.raw_range();
        assert_eq!(quantize(-327.68, 0.01, s16), Some(i16::MIN as i32));
    }
}
