//! The sensed channels, their integer units, the sensor suites, and the validated sensor frame.
//!
//! This is the single definition of what a sensor frame carries and in which fixed-point unit. Every
//! value is an integer in the unit named here, as a sensor bus would deliver it; the estimator never
//! sees floats. `SensorFrame::from_si` is the host-side conversion (NaN, ±Inf and out-of-range values
//! become invalid channels, never numbers).
//!
//! # Sensor suites
//! A [`Suite`] is a named set of channels an aircraft delivers. [`Suite::Table1`] is exactly the
//! inputs of Karali et al. 2023, Table 1 (the first 16 channels), kept so the comparison with the
//! paper stays reproducible. [`Suite::Egi`] adds what a fighter's embedded GPS/INS also gives:
//! attitude, the GPS/INS velocity vector and the fuel quantity (channels 16–22, appended so every
//! Table 1 channel keeps its index). No suite carries an air-data quantity.

/// Number of sensed channels in a frame (every suite's channels; a frame of a smaller suite marks
/// the others invalid).
pub const CHANNELS: usize = 23;

/// Number of channels of [`Suite::Table1`]: channels `0..TABLE1_CHANNELS`.
pub const TABLE1_CHANNELS: usize = 16;

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
    /// EGI roll angle φ, µrad, in (−π, π].
    Roll,
    /// EGI pitch angle θ, µrad, in [−π/2, π/2].
    Pitch,
    /// EGI true heading ψ, µrad, wrapped to [0, 2π) (as JSBSim's `attitude/psi-rad`).
    Heading,
    /// EGI (GPS/INS) velocity north over the ground, mm/s.
    VelNorth,
    /// EGI velocity east, mm/s.
    VelEast,
    /// EGI velocity down, mm/s (positive descending).
    VelDown,
    /// Fuel quantity (gauging system total), 0.1 kg; 16-bit on the wire (0–6553.5 kg).
    Fuel,
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
        Channel::Roll,
        Channel::Pitch,
        Channel::Heading,
        Channel::VelNorth,
        Channel::VelEast,
        Channel::VelDown,
        Channel::Fuel,
    ];

    pub const fn index(self) -> usize {
        self as usize
    }

    /// This channel's bit in a validity mask ([`SensorFrame::valid`]) or a source mask.
    pub const fn bit(self) -> u32 {
        1 << (self as u32)
    }

    /// The smallest suite that carries this channel.
    pub const fn suite(self) -> Suite {
        if self.index() < TABLE1_CHANNELS {
            Suite::Table1
        } else {
            Suite::Egi
        }
    }

    /// Size of one integer step in the SI (or degree / normalised) unit of [`Channel::name`].
    pub const fn lsb(self) -> f64 {
        match self {
            Channel::GyroP | Channel::GyroQ | Channel::GyroR => 1e-6,
            Channel::AccelX | Channel::AccelY | Channel::AccelZ => 1e-5,
            Channel::GpsSpeed => 1e-3,
            Channel::GpsAlt => 1e-2,
            Channel::Throttle => 1e-4,
            Channel::Roll | Channel::Pitch | Channel::Heading => 1e-6,
            Channel::VelNorth | Channel::VelEast | Channel::VelDown => 1e-3,
            Channel::Fuel => 1e-1,
            _ => 1e-2,
        }
    }

    /// Range the wire type can carry (surfaces, throttle and fuel are 16-bit on the wire).
    pub const fn raw_range(self) -> (i32, i32) {
        match self {
            Channel::Throttle | Channel::Fuel => (0, u16::MAX as i32),
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

    /// The sensor's measuring range, raw units: an IMU output at or beyond it is clipped by the
    /// sensor, not measured ([`crate::health`]). LN-200 class: ±1000 °/s (17.453 293 rad/s) and
    /// ±40 g (392.266 m/s²); `docs/sensors.md`. `None` for channels without a clipping range.
    pub const fn full_scale(self) -> Option<i32> {
        match self {
            Channel::GyroP | Channel::GyroQ | Channel::GyroR => Some(17_453_293),
            Channel::AccelX | Channel::AccelY | Channel::AccelZ => Some(39_226_600),
            _ => None,
        }
    }

    /// Channels whose noise makes an unchanged value over many frames a sign of a stuck sensor: the
    /// IMU, GPS and EGI outputs (not the surfaces, the throttle or the coarse, slow fuel gauge).
    pub const fn is_noisy(self) -> bool {
        matches!(
            self,
            Channel::GyroP
                | Channel::GyroQ
                | Channel::GyroR
                | Channel::AccelX
                | Channel::AccelY
                | Channel::AccelZ
                | Channel::GpsSpeed
                | Channel::GpsAlt
                | Channel::Roll
                | Channel::Pitch
                | Channel::Heading
                | Channel::VelNorth
                | Channel::VelEast
                | Channel::VelDown
        )
    }
}

/// All channels valid.
pub const ALL_VALID: u32 = u32::MAX >> (32 - CHANNELS);

/// The bit after the channels' in a channel mask ([`Suite::channels`], a feature's sources, the
/// usable channels of a frame): the frame's 120 Hz [`Subsamples`], every one of the
/// [`SUB_CHANNELS`] valid. Not a channel: [`SensorFrame::valid`] never has it.
pub const SUBSAMPLES_VALID: u32 = 1 << CHANNELS;

/// A named, versioned set of sensed channels: what a frame of the wire format, a dataset and a
/// model's inputs may carry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Suite {
    /// Exactly the paper's inputs (Karali et al. 2023, Table 1): IMU rates and specific force, GPS
    /// speed and altitude, seven surfaces, throttle. Channels `0..16`.
    Table1,
    /// Table 1 plus what a fighter's embedded GPS/INS gives: roll, pitch, heading, velocity
    /// north/east/down, and the fuel quantity. All [`CHANNELS`] channels.
    Egi,
    /// The EGI suite plus the IMU's and the surface sensors' own 120 Hz outputs of each frame
    /// period ([`Subsamples`]).
    Egi120,
}

impl Suite {
    pub const ALL: [Suite; 3] = [Suite::Table1, Suite::Egi, Suite::Egi120];

    /// Name used on command lines, in manifests and reports.
    pub const fn name(self) -> &'static str {
        match self {
            Suite::Table1 => "table1",
            Suite::Egi => "egi",
            Suite::Egi120 => "egi120",
        }
    }

    pub fn from_name(name: &str) -> Option<Suite> {
        Suite::ALL.iter().copied().find(|s| s.name() == name)
    }

    /// The channels this suite carries (bit per [`Channel`]), and [`SUBSAMPLES_VALID`] if it
    /// carries the 120 Hz sub-samples.
    pub const fn channels(self) -> u32 {
        match self {
            Suite::Table1 => u32::MAX >> (32 - TABLE1_CHANNELS),
            Suite::Egi => ALL_VALID,
            Suite::Egi120 => ALL_VALID | SUBSAMPLES_VALID,
        }
    }

    pub const fn carries(self, c: Channel) -> bool {
        self.channels() & c.bit() != 0
    }

    /// Whether frames of this suite carry every channel a model reading `needs` reads.
    pub const fn delivers(self, needs: Suite) -> bool {
        needs.channels() & !self.channels() == 0
    }

    /// The smallest suite carrying every channel of `mask`, or `None` if no suite does.
    pub const fn covering(mask: u32) -> Option<Suite> {
        if mask & !Suite::Table1.channels() == 0 {
            Some(Suite::Table1)
        } else if mask & !Suite::Egi.channels() == 0 {
            Some(Suite::Egi)
        } else if mask & !Suite::Egi120.channels() == 0 {
            Some(Suite::Egi120)
        } else {
            None
        }
    }
}

/// The array of `name` with each suffix appended, at compile time.
macro_rules! suffixed {
    ($c:literal; $($suffix:literal),*) => {
        [$(concat!($c, $suffix)),*]
    };
}

/// [`Channel::name`], the delta-feature names (`"<name>_d<frames>"` for every lag) and the
/// sub-sample names (`"<name>_sub<k>"`) from one list.
macro_rules! channel_names {
    ($($v:ident => $c:literal),* $(,)?) => {
        impl Channel {
            /// Column name used in datasets and reports.
            pub const fn name(self) -> &'static str {
                match self {
                    $(Channel::$v => $c,)*
                }
            }

            /// Names of this channel's sub-sample features `"<name>_sub<k>"`, k = 0 … 5.
            pub(crate) const fn sub_names(self) -> [&'static str; 6] {
                match self {
                    $(Channel::$v => suffixed!($c; "_sub0", "_sub1", "_sub2", "_sub3", "_sub4", "_sub5"),)*
                }
            }

            /// Names of this channel's delta features over 1, 2, 4, 10 and 20 frames, in the order of
            /// the lags in `features` (which sits above this module and picks one; a test there
            /// checks the suffixes against the lags' frame counts).
            pub(crate) const fn delta_names(self) -> [&'static str; 5] {
                match self {
                    $(Channel::$v => suffixed!($c; "_d1", "_d2", "_d4", "_d10", "_d20"),)*
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
    Roll => "egi_roll_rad",
    Pitch => "egi_pitch_rad",
    Heading => "egi_heading_rad",
    VelNorth => "egi_v_north_mps",
    VelEast => "egi_v_east_mps",
    VelDown => "egi_v_down_mps",
    Fuel => "fuel_qty_kg",
);

/// Sub-samples per frame: the IMU and the surface sensors deliver at 120 Hz, six outputs per
/// 20 Hz frame period.
pub const SUBSAMPLES: usize = 6;

/// Number of [`SUB_CHANNELS`].
pub const SUB_CHANNEL_COUNT: usize = 13;

/// `N` consecutive channels of [`Channel::ALL`] from `first` on.
// Every use below stays inside `Channel::ALL` (a constant evaluation that left it would fail the
// build), so the indexing and the addition cannot fail.
#[allow(clippy::indexing_slicing, clippy::arithmetic_side_effects)]
const fn consecutive<const N: usize>(first: Channel) -> [Channel; N] {
    let mut out = [first; N];
    let mut i = 0;
    while i < N {
        out[i] = Channel::ALL[first as usize + i];
        i += 1;
    }
    out
}

/// The IMU's six axes: gyro p, q, r, accelerometer x, y, z.
pub const IMU_CHANNELS: [Channel; 6] = consecutive(Channel::GyroP);

/// The surface position channels: elevator, aileron, rudder, LEF, TEF, flaperon, speedbrake.
pub const SURFACE_CHANNELS: [Channel; 7] = consecutive(Channel::Elevator);

/// The channels a sensor bus may also deliver at 120 Hz ([`Subsamples`]): the IMU's six axes and
/// the seven surface positions, before the anti-alias filter that makes their 20 Hz values.
// `i < SUB_CHANNEL_COUNT` = 6 + 7: every index is in bounds.
#[allow(clippy::indexing_slicing, clippy::arithmetic_side_effects)]
pub const SUB_CHANNELS: [Channel; SUB_CHANNEL_COUNT] = {
    let mut out = [Channel::GyroP; SUB_CHANNEL_COUNT];
    let mut i = 0;
    while i < SUB_CHANNEL_COUNT {
        out[i] = if i < IMU_CHANNELS.len() {
            IMU_CHANNELS[i]
        } else {
            SURFACE_CHANNELS[i - IMU_CHANNELS.len()]
        };
        i += 1;
    }
    out
};

/// The 120 Hz outputs of the [`SUB_CHANNELS`] over one frame period.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Subsamples {
    /// `raw[k][i]`: sub-sample `k` (oldest first; the last at the frame's `time_ms`, the first
    /// five 120 Hz steps before it) of `SUB_CHANNELS[i]`, in that channel's unit.
    pub raw: [[i32; SUB_CHANNEL_COUNT]; SUBSAMPLES],
    /// Bit `i` set: `SUB_CHANNELS[i]` is valid in every sub-sample. 0: the frame carries none.
    pub valid: u16,
}

impl Subsamples {
    /// None carried.
    pub const NONE: Subsamples = Subsamples {
        raw: [[0; SUB_CHANNEL_COUNT]; SUBSAMPLES],
        valid: 0,
    };

    /// All [`SUB_CHANNELS`] valid.
    pub const ALL_VALID: u16 = u16::MAX >> (16 - SUB_CHANNEL_COUNT);

    /// The position of `c` in [`SUB_CHANNELS`], if it is one (usable in constants).
    // `i < SUB_CHANNEL_COUNT` (13): the increment cannot overflow.
    #[allow(clippy::arithmetic_side_effects)]
    pub const fn position(c: Channel) -> Option<usize> {
        let mut i = 0;
        while i < SUB_CHANNEL_COUNT {
            // `i < SUB_CHANNEL_COUNT`: in bounds.
            #[allow(clippy::indexing_slicing)]
            if SUB_CHANNELS[i] as u8 == c as u8 {
                return Some(i);
            }
            i += 1;
        }
        None
    }

    /// The [`Subsamples::valid`] bits of the sub-sampled channels among `channels` (a channel
    /// mask).
    // `i < SUB_CHANNEL_COUNT` (13): the shift and the increment cannot overflow.
    #[allow(clippy::arithmetic_side_effects)]
    pub const fn mask_of(channels: u32) -> u16 {
        let mut m = 0;
        let mut i = 0;
        while i < SUB_CHANNEL_COUNT {
            // `i < SUB_CHANNEL_COUNT`: in bounds.
            #[allow(clippy::indexing_slicing)]
            if channels & SUB_CHANNELS[i].bit() != 0 {
                m |= 1 << i;
            }
            i += 1;
        }
        m
    }

    /// Whether channel `c` is carried and valid.
    pub fn is_valid(&self, c: Channel) -> bool {
        Self::position(c).is_some_and(|i| self.valid & (1 << i) != 0)
    }

    /// Sub-sample `k` of channel `c` in its unit (0 when not carried).
    pub fn get(&self, k: usize, c: Channel) -> i32 {
        match Self::position(c) {
            Some(i) => self.raw.get(k).and_then(|s| s.get(i)).copied().unwrap_or(0),
            None => 0,
        }
    }

    /// The largest magnitude among channel `c`'s sub-samples, in its unit (0 when not carried or
    /// not valid): where a sensor clipped within the period although its 20 Hz value did not.
    pub fn peak(&self, c: Channel) -> u32 {
        match Self::position(c) {
            Some(i) if self.valid & (1 << i) != 0 => self
                .raw
                .iter()
                .filter_map(|s| s.get(i))
                .map(|v| v.unsigned_abs())
                .max()
                .unwrap_or(0),
            _ => 0,
        }
    }

    /// From SI values (`si[k][i]`, sub-sample `k` of `SUB_CHANNELS[i]`, in [`Channel::name`]
    /// units): a channel with a NaN, an infinity or a value it cannot carry in any sub-sample is
    /// invalid, and reads 0 in every one.
    pub fn from_si(si: &[[f64; SUB_CHANNEL_COUNT]; SUBSAMPLES]) -> Subsamples {
        let mut s = Subsamples::NONE;
        for (i, c) in SUB_CHANNELS.iter().enumerate() {
            let q: [Option<i32>; SUBSAMPLES] = core::array::from_fn(|k| {
                let v = si.get(k).and_then(|row| row.get(i)).copied();
                v.and_then(|v| quantize(v, c.lsb(), c.raw_range()))
            });
            if q.iter().all(Option::is_some) {
                for (row, v) in s.raw.iter_mut().zip(q) {
                    if let Some(r) = row.get_mut(i) {
                        *r = v.unwrap_or(0);
                    }
                }
                s.valid |= 1 << i;
            }
        }
        s
    }
}

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
    /// Bit `c` set: channel `c` is valid (sensor self-test passed, value finite and in range). A
    /// channel the sending suite does not carry is invalid.
    pub valid: u32,
    /// The 120 Hz sub-samples of the frame period ([`Subsamples::NONE`] unless the sender's
    /// suite carries them).
    pub sub: Subsamples,
}

impl SensorFrame {
    pub fn get(&self, c: Channel) -> i32 {
        self.raw.get(c.index()).copied().unwrap_or(0)
    }

    pub fn is_valid(&self, c: Channel) -> bool {
        self.valid & c.bit() != 0
    }

    /// Channel `c` to `raw`, and each of its 120 Hz sub-samples if it is a sub-sampled channel: a
    /// sensor held at one value (a stuck or saturated sensor, an extreme test value). Validity is
    /// left as it is.
    pub fn set_everywhere(&mut self, c: Channel, raw: i32) {
        self.map_everywhere(c, |_| raw);
    }

    /// Channel `c`, and each of its 120 Hz sub-samples if it is a sub-sampled channel, through
    /// `f` (a biased sensor). Validity is left as it is.
    pub fn map_everywhere(&mut self, c: Channel, f: impl Fn(i32) -> i32) {
        if let Some(r) = self.raw.get_mut(c.index()) {
            *r = f(*r);
        }
        if let Some(i) = Subsamples::position(c) {
            for sample in self.sub.raw.iter_mut() {
                if let Some(r) = sample.get_mut(i) {
                    *r = f(*r);
                }
            }
        }
    }

    /// Converts SI values (in [`Channel::name`] units) to a frame. A NaN, an infinity, or a value the
    /// channel cannot carry gives raw 0 with the channel marked invalid.
    pub fn from_si(seq: u16, time_ms: u32, si: &[f64; CHANNELS]) -> SensorFrame {
        let mut f = SensorFrame {
            seq,
            time_ms,
            raw: [0; CHANNELS],
            valid: 0,
            sub: Subsamples::NONE,
        };
        for ((c, v), raw) in Channel::ALL.iter().zip(si.iter()).zip(f.raw.iter_mut()) {
            if let Some(q) = quantize(*v, c.lsb(), c.raw_range()) {
                *raw = q;
                f.valid |= c.bit();
            }
        }
        f
    }

    /// The frame as a sender of `suite` delivers it: channels the suite does not carry are invalid
    /// and read 0 (what decoding a frame of that suite gives).
    pub fn restricted_to(&self, suite: Suite) -> SensorFrame {
        let mut f = *self;
        for (c, r) in Channel::ALL.iter().zip(f.raw.iter_mut()) {
            if !suite.carries(*c) {
                *r = 0;
            }
        }
        f.valid &= suite.channels() & ALL_VALID;
        if suite.channels() & SUBSAMPLES_VALID == 0 {
            f.sub = Subsamples::NONE;
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
    fn the_channel_groups_are_the_named_channels() {
        use Channel::*;
        assert_eq!(IMU_CHANNELS, [GyroP, GyroQ, GyroR, AccelX, AccelY, AccelZ]);
        assert_eq!(
            SURFACE_CHANNELS,
            [Elevator, Aileron, Rudder, Lef, Tef, Flaperon, Speedbrake]
        );
        assert_eq!(SUB_CHANNELS[..6], IMU_CHANNELS);
        assert_eq!(SUB_CHANNELS[6..], SURFACE_CHANNELS);
    }

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
    fn table1_channels_keep_their_indices_and_egi_ones_follow() {
        // The wire format, the datasets and the shipped model index the first 16 channels.
        assert_eq!(Channel::Throttle.index(), 15);
        assert_eq!(Channel::Roll.index(), TABLE1_CHANNELS);
        assert_eq!(Channel::Fuel.index(), CHANNELS - 1);
        for (i, c) in Channel::ALL.iter().enumerate() {
            assert_eq!(c.index(), i);
            assert_eq!(c.suite() == Suite::Table1, i < TABLE1_CHANNELS);
            assert!(Suite::Egi.carries(*c));
        }
        assert_eq!(
            Suite::Table1.channels().count_ones() as usize,
            TABLE1_CHANNELS
        );
        assert_eq!(Suite::Egi.channels(), ALL_VALID);
        assert_eq!(Suite::covering(Channel::Rudder.bit()), Some(Suite::Table1));
        assert_eq!(Suite::covering(Channel::Fuel.bit()), Some(Suite::Egi));
        assert_eq!(Suite::covering(SUBSAMPLES_VALID), Some(Suite::Egi120));
        assert_eq!(Suite::covering(1 << (CHANNELS + 1)), None);
        assert!(Suite::Egi120.delivers(Suite::Egi) && !Suite::Egi.delivers(Suite::Egi120));
        for s in Suite::ALL {
            assert_eq!(Suite::from_name(s.name()), Some(s));
        }
    }

    #[test]
    fn a_frame_restricted_to_table1_has_no_egi_channel() {
        let si = [1.0; CHANNELS];
        let f = SensorFrame::from_si(1, 50, &si);
        assert_eq!(f.valid, ALL_VALID);
        let t = f.restricted_to(Suite::Table1);
        assert_eq!(t.valid, Suite::Table1.channels());
        assert_eq!(t.get(Channel::Fuel), 0);
        assert_eq!(t.get(Channel::Throttle), f.get(Channel::Throttle));
        assert_eq!(f.restricted_to(Suite::Egi), f);
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
