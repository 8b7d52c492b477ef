//! Candidate model inputs, computed in integer arithmetic from a [`SensorFrame`] and, for the
//! delta features, a [`History`] of past frames.
//!
//! The first 16 features are the sensed channels themselves. The derived ones carry the
//! dynamic-pressure information that the sensed channels lack, from sensors alone (never air data):
//! an ISA density at GPS altitude times GPS speed squared (`ρV²`, a proxy for twice the dynamic
//! pressure), specific force divided by it (≈ aerodynamic coefficient × S/m), and GPS speed over the
//! ISA speed of sound at altitude (a Mach proxy). Air-data quantities (air-relative velocities,
//! airspeeds, dynamic pressure, Mach, α, β) are not channels, so no model can take them as input.
//!
//! The delta features carry the short-term dynamics a single frame cannot show (a pull-up building,
//! a climb rate, a speed trend): [`Feature::Delta`]`(c, lag)` is channel `c` now minus channel `c`
//! `lag` frames (50 ms each) ago, in the channel's unit, read from a [`History`] of past frames.
//!
//! # When the lagged frame is missing
//! After a start, a reset or lost frames, the frame exactly `lag × 50 ms` back may not be there, or may
//! have the channel marked invalid. The delta is then taken to the stored frame (with that channel
//! valid) whose age is closest to the lag, no older than twice the lag, and scaled to the nominal lag
//! (`Δ × lag_ms / age_ms`, a rate-preserving estimate); with no such frame it is 0 (no change). Either
//! way the lag's bit is set in [`FeatureValues::short_lags`], which the estimator reports as
//! `HISTORY_SHORT` when a model uses that lag.

use crate::channels::{CHANNELS, Channel, SensorFrame};

/// Number of derived single-frame features after the sensed channels.
const DERIVED: usize = 5;

/// Number of candidate features: sensed channels, derived features, and a delta per channel and lag.
pub const FEATURE_COUNT: usize = CHANNELS + DERIVED + CHANNELS * Lag::COUNT;

/// Frames a [`History`] keeps: 1 s at 20 Hz plus room for lost frames.
pub const HISTORY_FRAMES: usize = 24;

/// Nominal sensor frame period, ms (20 Hz).
pub const FRAME_PERIOD_MS: u32 = 50;

/// How far back a delta feature looks.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Lag {
    /// 1 frame, 50 ms.
    F1,
    /// 4 frames, 200 ms.
    F4,
    /// 10 frames, 500 ms.
    F10,
    /// 20 frames, 1 s.
    F20,
}

impl Lag {
    pub const COUNT: usize = 4;
    pub const ALL: [Lag; Lag::COUNT] = [Lag::F1, Lag::F4, Lag::F10, Lag::F20];

    pub const fn index(self) -> usize {
        self as usize
    }

    /// Bit of this lag in [`FeatureValues::short_lags`].
    pub const fn bit(self) -> u8 {
        1 << (self as u8)
    }

    pub const fn frames(self) -> u32 {
        match self {
            Lag::F1 => 1,
            Lag::F4 => 4,
            Lag::F10 => 10,
            Lag::F20 => 20,
        }
    }

    pub const fn ms(self) -> u32 {
        // At most 20 × 50: cannot overflow, and would saturate rather than wrap.
        self.frames().saturating_mul(FRAME_PERIOD_MS)
    }
}

/// GPS speeds below this (mm/s) make the `ρV²`-based features meaningless: they saturate and are
/// flagged out of envelope.
pub const MIN_SPEED_MMS: i32 = 20_000;

/// GPS speeds are clamped to this (mm/s, ≈ Mach 6) before squaring, so `ρV²` cannot overflow i64.
pub const MAX_SPEED_MMS: i32 = 2_000_000;

// Every density in the table times the largest speed squared fits i64, so the `ρV²` product in
// `FeatureValues::compute` cannot wrap (interpolated densities lie between two entries).
// Const evaluation: an out-of-bounds index is a compile error.
#[allow(clippy::indexing_slicing)]
const _: () = {
    let v = MAX_SPEED_MMS as i128;
    let mut i = 0;
    while i < ISA.len() {
        assert!(ISA[i].0 as i128 * v * v <= i64::MAX as i128);
        i += 1;
    }
};

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Feature {
    /// A sensed channel, in its frame unit.
    Sensor(Channel),
    /// Body x specific force / (ρV²), 1e-7 m²/kg.
    FxOverRhoV2,
    /// Body y specific force / (ρV²), 1e-7 m²/kg.
    FyOverRhoV2,
    /// Body z specific force / (ρV²), 1e-7 m²/kg.
    FzOverRhoV2,
    /// GPS speed / ISA speed of sound at GPS altitude, 1e-4.
    MachProxy,
    /// ISA density at GPS altitude × GPS speed², Pa.
    RhoV2,
    /// The channel now minus the channel `Lag` ago, in the channel's unit.
    Delta(Channel, Lag),
}

impl Feature {
    // Const evaluation: an out-of-bounds index here is a compile error, not a runtime panic.
    #[allow(clippy::indexing_slicing)]
    pub const ALL: [Feature; FEATURE_COUNT] = {
        let mut all = [Feature::RhoV2; FEATURE_COUNT];
        let mut i = 0;
        while i < CHANNELS {
            all[i] = Feature::Sensor(Channel::ALL[i]);
            i += 1;
        }
        all[CHANNELS] = Feature::FxOverRhoV2;
        all[CHANNELS + 1] = Feature::FyOverRhoV2;
        all[CHANNELS + 2] = Feature::FzOverRhoV2;
        all[CHANNELS + 3] = Feature::MachProxy;
        all[CHANNELS + 4] = Feature::RhoV2;
        let mut c = 0;
        while c < CHANNELS {
            let mut l = 0;
            while l < Lag::COUNT {
                all[CHANNELS + DERIVED + c * Lag::COUNT + l] =
                    Feature::Delta(Channel::ALL[c], Lag::ALL[l]);
                l += 1;
            }
            c += 1;
        }
        all
    };

    // Enum discriminants only: at most 16 + 5 + 15 × 4 + 3, far from overflowing.
    #[allow(clippy::arithmetic_side_effects)]
    pub const fn index(self) -> usize {
        match self {
            Feature::Sensor(c) => c.index(),
            Feature::FxOverRhoV2 => CHANNELS,
            Feature::FyOverRhoV2 => CHANNELS + 1,
            Feature::FzOverRhoV2 => CHANNELS + 2,
            Feature::MachProxy => CHANNELS + 3,
            Feature::RhoV2 => CHANNELS + 4,
            Feature::Delta(c, l) => CHANNELS + DERIVED + c.index() * Lag::COUNT + l.index(),
        }
    }

    pub const fn name(self) -> &'static str {
        match self {
            Feature::Sensor(c) => c.name(),
            Feature::FxOverRhoV2 => "fx_over_rho_v2",
            Feature::FyOverRhoV2 => "fy_over_rho_v2",
            Feature::FzOverRhoV2 => "fz_over_rho_v2",
            Feature::MachProxy => "mach_proxy",
            Feature::RhoV2 => "rho_v2_pa",
            Feature::Delta(c, l) => c.delta_name(l),
        }
    }

    /// Size of one integer step in the feature's unit.
    pub const fn lsb(self) -> f64 {
        match self {
            Feature::Sensor(c) | Feature::Delta(c, _) => c.lsb(),
            Feature::FxOverRhoV2 | Feature::FyOverRhoV2 | Feature::FzOverRhoV2 => 1e-7,
            Feature::MachProxy => 1e-4,
            Feature::RhoV2 => 1.0,
        }
    }

    /// The channels this feature is computed from (bit per [`Channel`]).
    pub const fn sources(self) -> u16 {
        let speed_alt = Channel::GpsSpeed.bit() | Channel::GpsAlt.bit();
        match self {
            Feature::Sensor(c) | Feature::Delta(c, _) => c.bit(),
            Feature::FxOverRhoV2 => speed_alt | Channel::AccelX.bit(),
            Feature::FyOverRhoV2 => speed_alt | Channel::AccelY.bit(),
            Feature::FzOverRhoV2 => speed_alt | Channel::AccelZ.bit(),
            Feature::MachProxy | Feature::RhoV2 => speed_alt,
        }
    }

    /// Lags this feature reads from the history (bit per [`Lag`]).
    pub const fn lags(self) -> u8 {
        match self {
            Feature::Delta(_, l) => l.bit(),
            _ => 0,
        }
    }

    pub fn from_name(name: &str) -> Option<Feature> {
        Feature::ALL.iter().copied().find(|f| f.name() == name)
    }
}

/// Every candidate feature of one frame, in [`Feature::ALL`] order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FeatureValues {
    pub raw: [i32; FEATURE_COUNT],
    /// GPS speed below [`MIN_SPEED_MMS`]: the derived features are saturated.
    pub low_speed: bool,
    /// Bit per [`Lag`]: for some channel the frame exactly that lag back was missing (see the module
    /// docs), so the delta was rate-scaled from another frame or set to 0.
    pub short_lags: u8,
}

/// The last [`HISTORY_FRAMES`] sensor frames, newest last, for the delta features. Fixed size, no heap.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct History {
    past: [SensorFrame; HISTORY_FRAMES],
    /// Slot the next frame goes to.
    head: usize,
    len: usize,
}

impl Default for History {
    fn default() -> Self {
        Self::new()
    }
}

impl History {
    pub const fn new() -> History {
        History {
            past: [SensorFrame {
                seq: 0,
                time_ms: 0,
                raw: [0; CHANNELS],
                valid: 0,
            }; HISTORY_FRAMES],
            head: 0,
            len: 0,
        }
    }

    /// Forgets every stored frame.
    pub fn clear(&mut self) {
        self.len = 0;
        self.head = 0;
    }

    /// Stores a frame (the oldest is dropped when full).
    pub fn push(&mut self, frame: &SensorFrame) {
        if let Some(p) = self.past.get_mut(self.head) {
            *p = *frame;
        }
        // `head < HISTORY_FRAMES` and `len <= HISTORY_FRAMES`: neither add can overflow. The slot
        // index is modular by nature (wrapping); the count is bounded (saturating, then capped).
        self.head = self.head.wrapping_add(1) % HISTORY_FRAMES;
        self.len = self.len.saturating_add(1).min(HISTORY_FRAMES);
    }

    /// The frame stored last.
    pub fn newest(&self) -> Option<&SensorFrame> {
        self.newest_first().next()
    }

    /// Stored frames, newest first.
    fn newest_first(&self) -> impl Iterator<Item = &SensorFrame> {
        // Slot `head - k` modulo the ring: `head < HISTORY_FRAMES` and `1 <= k <= HISTORY_FRAMES`, so
        // `head + HISTORY_FRAMES - k` stays in 0..2 × HISTORY_FRAMES and nothing wraps.
        (1..=self.len).filter_map(move |k| {
            self.past
                .get(self.head.wrapping_add(HISTORY_FRAMES).wrapping_sub(k) % HISTORY_FRAMES)
        })
    }

    /// Writes `Delta(c, lag)` for every channel into `raw`; returns whether any was not exact.
    fn deltas(&self, frame: &SensorFrame, lag: Lag, raw: &mut [i32; FEATURE_COUNT]) -> bool {
        let want = lag.ms();
        // Time stamps wrap (u32 ms, 49 days), so ages are differences modulo 2^32.
        let age = |p: &SensorFrame| frame.time_ms.wrapping_sub(p.time_ms);
        let max_age = want.saturating_mul(2);
        // The stored frame whose age is closest to the lag, in (0, 2 × lag], with the `need` channels
        // valid (the first, i.e. newest, of equally close ones). Age == lag is the exact frame.
        let closest = |need: u16| {
            self.newest_first()
                .filter(|p| p.valid & need == need && age(p) > 0 && age(p) <= max_age)
                .min_by_key(|p| age(p).abs_diff(want))
        };
        // One search serves every channel valid in the frame it finds: a channel's own search could
        // only find the same frame. Only channels invalid there search again. The exact frame, when
        // stored, is the closest; looking for it first stops early in the usual case.
        let shared = self
            .newest_first()
            .find(|p| age(p) == want)
            .or_else(|| closest(0));
        let mut short = shared.is_none_or(|p| age(p) != want);
        for c in Channel::ALL {
            let bit = c.bit();
            let from = match shared {
                Some(p) if p.is_valid(c) => Some(p),
                Some(_) => {
                    short = true;
                    closest(bit)
                }
                // Nothing stored within twice the lag: no channel's search could find a frame.
                None => None,
            };
            let d = from.map_or(0, |p| {
                // Two i32 in i64: |d| < 2^32, so the subtraction cannot wrap.
                let d = i64::from(frame.get(c)).wrapping_sub(i64::from(p.get(c)));
                // Rate-scaled to the nominal lag when the frame is not the lagged one (an i64
                // division is a library call on the Cortex-M4: skip it in the usual exact case).
                // |d| × want < 2^32 × 1000 cannot wrap. Both searches only take frames with
                // 0 < age <= 2 × lag, so the divisor is never 0; were it 0, the delta would be 0,
                // the value of a delta with no usable frame, and flagged like every scaled one (the
                // lag is already in `short` whenever the frame is not the exact one).
                match age(p) {
                    a if a == want => d,
                    a => d
                        .wrapping_mul(i64::from(want))
                        .checked_div(i64::from(a))
                        .unwrap_or(0),
                }
            });
            if let Some(r) = raw.get_mut(Feature::Delta(c, lag).index()) {
                *r = sat_i32(d);
            }
        }
        short
    }
}

impl FeatureValues {
    pub fn get(&self, f: Feature) -> i32 {
        self.raw.get(f.index()).copied().unwrap_or(0)
    }

    /// Computes all features of `frame`, the deltas against `history` (the frames before it). Invalid
    /// channels are read as they are; the estimator decides what an invalid source means before it
    /// uses a value.
    pub fn compute(frame: &SensorFrame, history: &History) -> FeatureValues {
        let mut raw = [0i32; FEATURE_COUNT];
        for (r, v) in raw.iter_mut().zip(frame.raw.iter()) {
            *r = *v;
        }
        let speed = frame.get(Channel::GpsSpeed).clamp(0, MAX_SPEED_MMS) as i64;
        let alt_cm = frame.get(Channel::GpsAlt);
        let (rho, sound) = isa(alt_cm);
        // ρ [1e-6 kg/m³] × V² [1e-6 m²/s²] = 1e-12 Pa; keep µPa (1e-6 Pa). The product cannot
        // wrap: ρ comes from the table, V is clamped (checked at compile time next to MAX_SPEED_MMS).
        let rho_v2_upa = i64::from(rho).wrapping_mul(speed).wrapping_mul(speed) / 1_000_000;
        let low_speed = speed < MIN_SPEED_MMS as i64;
        let ratio = |f_raw: i32| -> i32 {
            // f [1e-5 m/s²] / ρV² [1e-6 Pa] in 1e-7 m²/kg = f × 1e8 / ρV² (|f × 1e8| < 2^58).
            let num = i64::from(f_raw).wrapping_mul(100_000_000);
            sat_i32(div_at_least_1(num, rho_v2_upa))
        };
        let set = |raw: &mut [i32; FEATURE_COUNT], f: Feature, v: i32| {
            if let Some(r) = raw.get_mut(f.index()) {
                *r = v;
            }
        };
        set(
            &mut raw,
            Feature::FxOverRhoV2,
            ratio(frame.get(Channel::AccelX)),
        );
        set(
            &mut raw,
            Feature::FyOverRhoV2,
            ratio(frame.get(Channel::AccelY)),
        );
        set(
            &mut raw,
            Feature::FzOverRhoV2,
            ratio(frame.get(Channel::AccelZ)),
        );
        set(
            &mut raw,
            Feature::MachProxy,
            // speed <= MAX_SPEED_MMS: × 1e4 < 2^35.
            sat_i32(div_at_least_1(speed.wrapping_mul(10_000), i64::from(sound))),
        );
        set(&mut raw, Feature::RhoV2, sat_i32(rho_v2_upa / 1_000_000));
        let mut short_lags = 0;
        for lag in Lag::ALL {
            if history.deltas(frame, lag, &mut raw) {
                short_lags |= lag.bit();
            }
        }
        FeatureValues {
            raw,
            low_speed,
            short_lags,
        }
    }
}

fn sat_i32(v: i64) -> i32 {
    v.clamp(i32::MIN as i64, i32::MAX as i64) as i32
}

/// `num / den` (rounded toward zero) with the divisor raised to at least 1, as for a speed or a
/// ρV² of zero: the quotient then saturates through [`sat_i32`] instead of dividing by zero. The
/// divisor is positive, so `checked_div` cannot fail and its fallback is never taken.
fn div_at_least_1(num: i64, den: i64) -> i64 {
    num.checked_div(den.max(1)).unwrap_or(0)
}

/// ISA 1976 every 1000 m from 0 to 20 km: density (1e-6 kg/m³) and speed of sound (mm/s).
const ISA_STEP_CM: i32 = 100_000;
/// Top of the table, cm.
const ISA_TOP_CM: i32 = (ISA.len() as i32 - 1) * ISA_STEP_CM;
const ISA: [(i32, i32); 21] = [
    (1_225_000, 340_294),
    (1_111_643, 336_434),
    (1_006_490, 332_529),
    (909_122, 328_578),
    (819_129, 324_579),
    (736_116, 320_529),
    (659_697, 316_428),
    (589_501, 312_273),
    (525_167, 308_063),
    (466_348, 303_793),
    (412_706, 299_463),
    (363_918, 295_069),
    (310_828, 295_069),
    (265_483, 295_069),
    (226_753, 295_069),
    (193_673, 295_069),
    (165_420, 295_069),
    (141_287, 295_069),
    (120_676, 295_069),
    (103_071, 295_069),
    (88_035, 295_069),
];

/// Density and speed of sound at a GPS altitude (cm), linear between table points, clamped to 0–20 km.
pub fn isa(alt_cm: i32) -> (i32, i32) {
    let h = alt_cm.clamp(0, ISA_TOP_CM);
    let i = (h / ISA_STEP_CM) as usize;
    let frac = (h % ISA_STEP_CM) as i64;
    match (ISA.get(i), ISA.get(i.saturating_add(1))) {
        (Some(a), Some(b)) => {
            // Table values < 2^21 and frac < 1e5: nothing here comes near wrapping.
            const STEP: i64 = ISA_STEP_CM as i64;
            let lerp = |x: i32, y: i32| {
                let (x, y) = (i64::from(x), i64::from(y));
                x.wrapping_add(y.wrapping_sub(x).wrapping_mul(frac) / STEP) as i32
            };
            (lerp(a.0, b.0), lerp(a.1, b.1))
        }
        (Some(a), None) => *a,
        _ => (ISA[0].0, ISA[0].1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn feature_indices_match_all_order() {
        for (i, f) in Feature::ALL.iter().enumerate() {
            assert_eq!(f.index(), i);
            assert_eq!(Feature::from_name(f.name()), Some(*f));
        }
    }

    #[test]
    fn isa_interpolates_and_clamps() {
        assert_eq!(isa(0), (1_225_000, 340_294));
        assert_eq!(isa(-50_000), (1_225_000, 340_294));
        // halfway, truncating toward the upper point: 1225000 - 113357/2, 340294 - 3860/2
        assert_eq!(isa(50_000), (1_168_322, 338_364));
        assert_eq!(isa(9_000_000), (88_035, 295_069));
    }

    #[test]
    fn derived_features_at_a_known_point() {
        // 200 m/s at 3000 m, level flight: fz = -9.81 m/s².
        let mut f = SensorFrame::default();
        f.raw[Channel::GpsSpeed.index()] = 200_000;
        f.raw[Channel::GpsAlt.index()] = 300_000;
        f.raw[Channel::AccelZ.index()] = -981_000;
        let v = FeatureValues::compute(&f, &History::new());
        // ρV² = 0.909122 × 40000 = 36364.88 Pa
        assert_eq!(v.get(Feature::RhoV2), 36_364);
        // fz / ρV² = -9.81 / 36364.88 = -2.6977e-4 → -2697.7 in 1e-7
        assert_eq!(v.get(Feature::FzOverRhoV2), -2697);
        // 200 / 328.578 = 0.60868
        assert_eq!(v.get(Feature::MachProxy), 6086);
        assert!(!v.low_speed);
    }

    #[test]
    fn zero_speed_saturates_without_dividing_by_zero() {
        let mut f = SensorFrame::default();
        f.raw[Channel::AccelX.index()] = i32::MAX;
        f.raw[Channel::GpsSpeed.index()] = -5;
        let v = FeatureValues::compute(&f, &History::new());
        assert!(v.low_speed);
        assert_eq!(v.get(Feature::FxOverRhoV2), i32::MAX);
        assert_eq!(v.get(Feature::RhoV2), 0);
    }

    fn ramp(t_ms: u32) -> SensorFrame {
        // Every channel rises by 7 units per ms.
        SensorFrame {
            seq: (t_ms / FRAME_PERIOD_MS) as u16,
            time_ms: t_ms,
            raw: [t_ms as i32 * 7; CHANNELS],
            valid: crate::channels::ALL_VALID,
        }
    }

    #[test]
    fn delta_names_follow_the_channel_names() {
        for c in Channel::ALL {
            for l in Lag::ALL {
                let f = Feature::Delta(c, l);
                assert_eq!(f.name(), format!("{}_d{}", c.name(), l.frames()));
                assert_eq!(f.sources(), c.bit());
                assert_eq!(f.lags(), l.bit());
            }
        }
    }

    #[test]
    fn full_history_gives_exact_deltas() {
        let mut h = History::new();
        for k in 0..30u32 {
            h.push(&ramp(k * 50));
        }
        let v = FeatureValues::compute(&ramp(1500), &h);
        assert_eq!(v.short_lags, 0);
        for l in Lag::ALL {
            assert_eq!(v.get(Feature::Delta(Channel::AccelZ, l)), 7 * l.ms() as i32);
        }
    }

    #[test]
    fn empty_history_gives_zero_deltas_and_flags_every_lag() {
        let v = FeatureValues::compute(&ramp(1000), &History::new());
        assert_eq!(v.short_lags, 0b1111);
        for l in Lag::ALL {
            assert_eq!(v.get(Feature::Delta(Channel::GyroQ, l)), 0);
        }
    }

    #[test]
    fn a_lost_frame_is_bridged_by_rate_scaling() {
        let mut h = History::new();
        for t in [0, 100, 150, 200] {
            h.push(&ramp(t)); // the frame at 50 ms was lost
        }
        let v = FeatureValues::compute(&ramp(250), &h);
        // Lag 1 (50 ms: the 200 ms frame) is there; lag 4 (200 ms: the lost 50 ms frame) is not: the
        // 100 ms frame (age 150) is the closest.
        assert_eq!(
            v.short_lags,
            Lag::F4.bit() | Lag::F10.bit() | Lag::F20.bit()
        );
        assert_eq!(v.get(Feature::Delta(Channel::GpsAlt, Lag::F1)), 7 * 50);
        assert_eq!(
            v.get(Feature::Delta(Channel::GpsAlt, Lag::F4)),
            7 * 150 * 200 / 150
        );
        // Lag 10 (500 ms): the oldest frame is 250 ms old, within 2 × 500: scaled.
        assert_eq!(v.get(Feature::Delta(Channel::GpsAlt, Lag::F10)), 7 * 500);
    }

    #[test]
    fn an_invalid_past_channel_is_not_used() {
        let mut h = History::new();
        for k in 0..=20u32 {
            let mut f = ramp(k * 50);
            if k == 20 {
                f.valid &= !Channel::Rudder.bit();
                f.raw[Channel::Rudder.index()] = i32::MIN;
            }
            h.push(&f);
        }
        // At 1050 ms lag 1 wants the 1000 ms frame, valid except the rudder: the rudder's delta comes
        // from the 950 ms frame, scaled to 50 ms.
        let v = FeatureValues::compute(&ramp(1050), &h);
        assert_eq!(v.short_lags, Lag::F1.bit());
        assert_eq!(v.get(Feature::Delta(Channel::Rudder, Lag::F1)), 7 * 50);
        assert_eq!(v.get(Feature::Delta(Channel::Aileron, Lag::F1)), 7 * 50);
    }

    #[test]
    fn time_going_backwards_or_far_jumps_give_no_delta() {
        let mut h = History::new();
        for k in 0..25u32 {
            h.push(&ramp(10_000 + k * 50));
        }
        for t in [0, 5_000, 100_000] {
            let v = FeatureValues::compute(&ramp(t), &h);
            assert_eq!(v.short_lags, 0b1111, "t={t}");
            assert_eq!(v.get(Feature::Delta(Channel::GyroP, Lag::F20)), 0);
        }
    }
}
