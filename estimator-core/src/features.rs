//! Candidate model inputs, computed in integer arithmetic from a [`SensorFrame`].
//!
//! The first 16 features are the sensed channels themselves. The derived ones carry the
//! dynamic-pressure information that the sensed channels lack, from sensors alone (never air data):
//! an ISA density at GPS altitude times GPS speed squared (`ρV²`, a proxy for twice the dynamic
//! pressure), specific force divided by it (≈ aerodynamic coefficient × S/m), and GPS speed over the
//! ISA speed of sound at altitude (a Mach proxy). Air-data quantities (air-relative velocities,
//! airspeeds, dynamic pressure, Mach, α, β) are not channels, so no model can take them as input.

use crate::channels::{CHANNELS, Channel, SensorFrame};

/// Number of candidate features.
pub const FEATURE_COUNT: usize = CHANNELS + 5;

/// GPS speeds below this (mm/s) make the `ρV²`-based features meaningless: they saturate and are
/// flagged out of envelope.
pub const MIN_SPEED_MMS: i32 = 20_000;

/// GPS speeds are clamped to this (mm/s, ≈ Mach 6) before squaring, so `ρV²` cannot overflow i64.
pub const MAX_SPEED_MMS: i32 = 2_000_000;

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
        all
    };

    pub const fn index(self) -> usize {
        match self {
            Feature::Sensor(c) => c.index(),
            Feature::FxOverRhoV2 => CHANNELS,
            Feature::FyOverRhoV2 => CHANNELS + 1,
            Feature::FzOverRhoV2 => CHANNELS + 2,
            Feature::MachProxy => CHANNELS + 3,
            Feature::RhoV2 => CHANNELS + 4,
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
        }
    }

    /// Size of one integer step in the feature's unit.
    pub const fn lsb(self) -> f64 {
        match self {
            Feature::Sensor(c) => c.lsb(),
            Feature::FxOverRhoV2 | Feature::FyOverRhoV2 | Feature::FzOverRhoV2 => 1e-7,
            Feature::MachProxy => 1e-4,
            Feature::RhoV2 => 1.0,
        }
    }

    /// The channels this feature is computed from (bit per [`Channel`]).
    pub const fn sources(self) -> u16 {
        let speed_alt = Channel::GpsSpeed.bit() | Channel::GpsAlt.bit();
        match self {
            Feature::Sensor(c) => c.bit(),
            Feature::FxOverRhoV2 => speed_alt | Channel::AccelX.bit(),
            Feature::FyOverRhoV2 => speed_alt | Channel::AccelY.bit(),
            Feature::FzOverRhoV2 => speed_alt | Channel::AccelZ.bit(),
            Feature::MachProxy | Feature::RhoV2 => speed_alt,
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
}

impl FeatureValues {
    pub fn get(&self, f: Feature) -> i32 {
        self.raw.get(f.index()).copied().unwrap_or(0)
    }

    /// Computes all features. Invalid channels are read as they are; the estimator decides what an
    /// invalid source means before it uses a value.
    pub fn compute(frame: &SensorFrame) -> FeatureValues {
        let mut raw = [0i32; FEATURE_COUNT];
        for (r, v) in raw.iter_mut().zip(frame.raw.iter()) {
            *r = *v;
        }
        let speed = frame.get(Channel::GpsSpeed).clamp(0, MAX_SPEED_MMS) as i64;
        let alt_cm = frame.get(Channel::GpsAlt);
        let (rho, sound) = isa(alt_cm);
        // ρ [1e-6 kg/m³] × V² [1e-6 m²/s²] = 1e-12 Pa; keep µPa (1e-6 Pa).
        let rho_v2_upa = (rho as i64 * speed * speed) / 1_000_000;
        let low_speed = speed < MIN_SPEED_MMS as i64;
        let ratio = |f_raw: i32| -> i32 {
            // f [1e-5 m/s²] / ρV² [1e-6 Pa] in 1e-7 m²/kg = f × 1e8 / ρV².
            let num = f_raw as i64 * 100_000_000;
            let den = rho_v2_upa.max(1);
            sat_i32(num / den)
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
            sat_i32(speed * 10_000 / (sound as i64).max(1)),
        );
        set(&mut raw, Feature::RhoV2, sat_i32(rho_v2_upa / 1_000_000));
        FeatureValues { raw, low_speed }
    }
}

fn sat_i32(v: i64) -> i32 {
    v.clamp(i32::MIN as i64, i32::MAX as i64) as i32
}

/// ISA 1976 every 1000 m from 0 to 20 km: density (1e-6 kg/m³) and speed of sound (mm/s).
const ISA_STEP_CM: i32 = 100_000;
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
    let top = (ISA.len() as i32 - 1) * ISA_STEP_CM;
    let h = alt_cm.clamp(0, top);
    let i = (h / ISA_STEP_CM) as usize;
    let frac = (h % ISA_STEP_CM) as i64;
    match (ISA.get(i), ISA.get(i + 1)) {
        (Some(a), Some(b)) => {
            let lerp = |x: i32, y: i32| {
                (x as i64 + (y as i64 - x as i64) * frac / ISA_STEP_CM as i64) as i32
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
        let v = FeatureValues::compute(&f);
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
        let v = FeatureValues::compute(&f);
        assert!(v.low_speed);
        assert_eq!(v.get(Feature::FxOverRhoV2), i32::MAX);
        assert_eq!(v.get(Feature::RhoV2), 0);
    }
}
