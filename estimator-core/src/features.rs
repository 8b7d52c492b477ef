//! Candidate model inputs, computed in integer arithmetic from a [`SensorFrame`] and, for the
//! delta features, a [`History`] of past frames.
//!
//! The first [`CHANNELS`] features are the sensed channels themselves. The derived ones carry the
//! dynamic-pressure information that the sensed channels lack, from sensors alone (never air data):
//! an ISA density at GPS altitude times GPS speed squared (`ρV²`, a proxy for twice the dynamic
//! pressure), specific force divided by it (≈ aerodynamic coefficient × S/m), and GPS speed over the
//! ISA speed of sound at altitude (a Mach proxy). Air-data quantities (air-relative velocities,
//! airspeeds, dynamic pressure, Mach, α, β) are not channels, so no model can take them as input.
//!
//! # EGI kinematic features ([`crate::Suite::Egi`] only)
//! From the EGI attitude and ground velocity: the ground velocity in body axes
//! `(u_g, v_g, w_g) = C_bn(φ, θ, ψ) · (v_N, v_E, v_D)` and the wind-free kinematic angles
//! `α_kin = atan2(w_g, u_g)` and `β_kin = asin(v_g / |V_g|)` (computed as `atan2(v_g, √(u_g² + w_g²))`,
//! the same angle, better conditioned). They equal the air-data α and β only in still air; the
//! difference is the wind, which a model or a filter has to account for. Computed in `f32` with the
//! pure-Rust `libm` (sin, cos, atan2, sqrt) and basic IEEE-754 operations only, so host and
//! Cortex-M4F give bit-identical results (no fused multiply-add, no platform math library; libm's
//! `sqrtf` uses the SSE instruction on x86, which is correctly rounded like the software path). A
//! frame without all six source channels valid gives 0 for all five (the model that reads them is
//! held as `INVALID_INPUT` anyway), so a Table 1 frame costs no floating-point work.
//! [`FeatureValues::low_ground_speed`] marks a ground speed below [`MIN_SPEED_MMS`], where the
//! angles are noise.
//!
//! Delta features exist for the Table 1 channels only (`Feature::Delta` of an EGI channel is not a
//! candidate: it has no index below [`FEATURE_COUNT`] and reads 0).
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

use crate::channels::{
    CHANNELS, Channel, SUB_CHANNEL_COUNT, SUB_CHANNELS, SUBSAMPLES, SUBSAMPLES_VALID, SensorFrame,
    Subsamples, Suite, TABLE1_CHANNELS,
};

/// Number of derived single-frame features of the Table 1 channels, after the sensed channels.
const DERIVED: usize = 5;

/// Number of EGI kinematic features, after the Table 1 derived ones.
const EGI_DERIVED: usize = 5;

/// Number of air-data filter outputs offered as features, after the EGI kinematic ones.
const FILTER_DERIVED: usize = 9;

/// First filter feature.
const FILTERED: usize = CHANNELS + DERIVED + EGI_DERIVED;

/// First delta feature.
const DELTAS: usize = FILTERED + FILTER_DERIVED;

/// First sub-sample feature.
const SUBS: usize = DELTAS + TABLE1_CHANNELS * Lag::COUNT;

/// Number of candidate features: sensed channels, derived features, a delta per Table 1 channel
/// and lag, and the frame's 120 Hz sub-samples ([`Feature::Sub`]).
pub const FEATURE_COUNT: usize = SUBS + SUB_CHANNEL_COUNT * SUBSAMPLES;

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
    /// 2 frames, 100 ms: with `F1`, the three newest samples that undo the IMU's 2nd-order
    /// anti-alias filter (a fast side-force change shows up smeared over them).
    F2,
    /// 4 frames, 200 ms.
    F4,
    /// 10 frames, 500 ms.
    F10,
    /// 20 frames, 1 s.
    F20,
}

impl Lag {
    pub const COUNT: usize = 5;
    pub const ALL: [Lag; Lag::COUNT] = [Lag::F1, Lag::F2, Lag::F4, Lag::F10, Lag::F20];

    /// Every lag's bit in [`FeatureValues::short_lags`].
    pub const ALL_BITS: u8 = (1 << Lag::COUNT) - 1;

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
            Lag::F2 => 2,
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

/// An angle feature in µrad as millidegrees, `µrad · 180,000 / 3,141,593` (truncated toward 0).
/// For any feature value (|µrad| < 2³¹) the product is far inside i64; the saturating form only
/// says so to the overflow lint.
pub fn urad_to_mdeg(urad: i64) -> i64 {
    urad.saturating_mul(180_000) / 3_141_593
}

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
    /// EGI ground velocity along body x, mm/s.
    UGround,
    /// EGI ground velocity along body y, mm/s.
    VGround,
    /// EGI ground velocity along body z, mm/s.
    WGround,
    /// Wind-free kinematic angle of attack `atan2(w_g, u_g)`, µrad.
    AlphaKin,
    /// Wind-free kinematic sideslip `asin(v_g / |V_g|)`, µrad.
    BetaKin,
    /// The model-based filter's ([`crate::filter`]) angle of attack, µrad.
    FilterAlpha,
    /// The filter's sideslip, µrad.
    FilterBeta,
    /// The filter's 1σ of α, µrad.
    FilterSigmaAlpha,
    /// The filter's 1σ of β, µrad.
    FilterSigmaBeta,
    /// The filter's true airspeed, mm/s.
    FilterAirspeed,
    /// The filter's lift scale, 1e-4.
    FilterLiftScale,
    /// The filter's turbulence index ([`crate::filter::Output::turbulence_rad`]), µrad.
    FilterTurbulence,
    /// The filter's running mean of its normalised innovation squared
    /// ([`crate::filter::Output::nis_mean`]), 1e-3.
    FilterNisMean,
    /// The filter's side-force scale ([`crate::filter::Output::side_scale`]), 1e-4.
    FilterSideScale,
    /// The channel now minus the channel `Lag` ago, in the channel's unit (Table 1 channels only).
    Delta(Channel, Lag),
    /// Sub-sample `k` (0 … 5, oldest first; 5 at the frame's time) of a sub-sampled channel
    /// ([`crate::channels::SUB_CHANNELS`]), in the channel's unit: the sensor's own 120 Hz output,
    /// before the anti-alias filter of the 20 Hz channel ([`Suite::Egi120`] only).
    Sub(Channel, u8),
}

/// The EGI channels the kinematic features are computed from.
const KINEMATIC_SOURCES: u32 =
    Channel::Roll.bit() | Channel::Pitch.bit() | Channel::Heading.bit() | VELOCITY_SOURCES;

/// The EGI velocity channels: a ground speed below [`MIN_SPEED_MMS`] flags models reading them.
pub const VELOCITY_SOURCES: u32 =
    Channel::VelNorth.bit() | Channel::VelEast.bit() | Channel::VelDown.bit();

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
        all[CHANNELS + DERIVED] = Feature::UGround;
        all[CHANNELS + DERIVED + 1] = Feature::VGround;
        all[CHANNELS + DERIVED + 2] = Feature::WGround;
        all[CHANNELS + DERIVED + 3] = Feature::AlphaKin;
        all[CHANNELS + DERIVED + 4] = Feature::BetaKin;
        all[FILTERED] = Feature::FilterAlpha;
        all[FILTERED + 1] = Feature::FilterBeta;
        all[FILTERED + 2] = Feature::FilterSigmaAlpha;
        all[FILTERED + 3] = Feature::FilterSigmaBeta;
        all[FILTERED + 4] = Feature::FilterAirspeed;
        all[FILTERED + 5] = Feature::FilterLiftScale;
        all[FILTERED + 6] = Feature::FilterTurbulence;
        all[FILTERED + 7] = Feature::FilterNisMean;
        all[FILTERED + 8] = Feature::FilterSideScale;
        let mut c = 0;
        while c < TABLE1_CHANNELS {
            let mut l = 0;
            while l < Lag::COUNT {
                all[DELTAS + c * Lag::COUNT + l] = Feature::Delta(Channel::ALL[c], Lag::ALL[l]);
                l += 1;
            }
            c += 1;
        }
        let mut i = 0;
        while i < SUB_CHANNEL_COUNT {
            let mut k = 0;
            while k < SUBSAMPLES {
                all[SUBS + i * SUBSAMPLES + k] = Feature::Sub(SUB_CHANNELS[i], k as u8);
                k += 1;
            }
            i += 1;
        }
        all
    };

    /// Position in [`Feature::ALL`] and [`FeatureValues::raw`]. A delta of an EGI channel, not a
    /// candidate, gets a position at or past [`FEATURE_COUNT`] (every reader treats it as absent).
    // Enum discriminants only: at most 41 + 22 × 5 + 4 (a delta of the last channel), far from overflowing.
    #[allow(clippy::arithmetic_side_effects)]
    pub const fn index(self) -> usize {
        match self {
            Feature::Sensor(c) => c.index(),
            Feature::FxOverRhoV2 => CHANNELS,
            Feature::FyOverRhoV2 => CHANNELS + 1,
            Feature::FzOverRhoV2 => CHANNELS + 2,
            Feature::MachProxy => CHANNELS + 3,
            Feature::RhoV2 => CHANNELS + 4,
            Feature::UGround => CHANNELS + DERIVED,
            Feature::VGround => CHANNELS + DERIVED + 1,
            Feature::WGround => CHANNELS + DERIVED + 2,
            Feature::AlphaKin => CHANNELS + DERIVED + 3,
            Feature::BetaKin => CHANNELS + DERIVED + 4,
            Feature::FilterAlpha => FILTERED,
            Feature::FilterBeta => FILTERED + 1,
            Feature::FilterSigmaAlpha => FILTERED + 2,
            Feature::FilterSigmaBeta => FILTERED + 3,
            Feature::FilterAirspeed => FILTERED + 4,
            Feature::FilterLiftScale => FILTERED + 5,
            Feature::FilterTurbulence => FILTERED + 6,
            Feature::FilterNisMean => FILTERED + 7,
            Feature::FilterSideScale => FILTERED + 8,
            // Past the candidates for an EGI channel: no such feature.
            Feature::Delta(c, l) if c.index() >= TABLE1_CHANNELS => {
                FEATURE_COUNT + c.index() * Lag::COUNT + l.index()
            }
            Feature::Delta(c, l) => DELTAS + c.index() * Lag::COUNT + l.index(),
            // Past the candidates for a channel that is not sub-sampled or a k beyond the period.
            Feature::Sub(c, k) => match Subsamples::position(c) {
                Some(i) if (k as usize) < SUBSAMPLES => SUBS + i * SUBSAMPLES + k as usize,
                _ => FEATURE_COUNT + c.index() * SUBSAMPLES + k as usize,
            },
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
            Feature::UGround => "u_ground_mps",
            Feature::VGround => "v_ground_mps",
            Feature::WGround => "w_ground_mps",
            Feature::AlphaKin => "alpha_kin_rad",
            Feature::BetaKin => "beta_kin_rad",
            Feature::FilterAlpha => "filter_alpha_rad",
            Feature::FilterBeta => "filter_beta_rad",
            Feature::FilterSigmaAlpha => "filter_sigma_alpha_rad",
            Feature::FilterSigmaBeta => "filter_sigma_beta_rad",
            Feature::FilterAirspeed => "filter_airspeed_mps",
            Feature::FilterLiftScale => "filter_lift_scale",
            Feature::FilterTurbulence => "filter_turbulence_rad",
            Feature::FilterNisMean => "filter_nis_mean",
            Feature::FilterSideScale => "filter_side_scale",
            Feature::Delta(c, l) => match c.delta_names() {
                [d1, d2, d4, d10, d20] => match l {
                    Lag::F1 => d1,
                    Lag::F2 => d2,
                    Lag::F4 => d4,
                    Lag::F10 => d10,
                    Lag::F20 => d20,
                },
            },
            Feature::Sub(c, k) => match c.sub_names() {
                [s0, s1, s2, s3, s4, s5] => match k {
                    0 => s0,
                    1 => s1,
                    2 => s2,
                    3 => s3,
                    4 => s4,
                    _ => s5,
                },
            },
        }
    }

    /// Size of one integer step in the feature's unit.
    pub const fn lsb(self) -> f64 {
        match self {
            Feature::Sensor(c) | Feature::Delta(c, _) | Feature::Sub(c, _) => c.lsb(),
            Feature::FxOverRhoV2 | Feature::FyOverRhoV2 | Feature::FzOverRhoV2 => 1e-7,
            Feature::MachProxy => 1e-4,
            Feature::RhoV2 => 1.0,
            Feature::UGround | Feature::VGround | Feature::WGround => 1e-3,
            Feature::AlphaKin | Feature::BetaKin => 1e-6,
            Feature::FilterAlpha
            | Feature::FilterBeta
            | Feature::FilterSigmaAlpha
            | Feature::FilterSigmaBeta => 1e-6,
            Feature::FilterAirspeed => 1e-3,
            Feature::FilterLiftScale => 1e-4,
            Feature::FilterTurbulence => 1e-6,
            Feature::FilterNisMean => 1e-3,
            Feature::FilterSideScale => 1e-4,
        }
    }

    /// The smallest sensor suite whose frames carry every channel this feature is computed from: a
    /// model of a suite can only select features of that suite (or of a smaller one).
    pub const fn suite(self) -> Suite {
        match Suite::covering(self.sources()) {
            Some(s) => s,
            // Every source is a channel or the sub-samples, and the largest suite carries all.
            None => Suite::Egi120,
        }
    }

    /// The channels this feature is computed from (bit per [`Channel`]).
    pub const fn sources(self) -> u32 {
        let speed_alt = Channel::GpsSpeed.bit() | Channel::GpsAlt.bit();
        match self {
            Feature::Sensor(c) | Feature::Delta(c, _) => c.bit(),
            // The 20 Hz channel's bit too: a channel found stuck or invalid is not read at 120 Hz.
            Feature::Sub(c, _) => c.bit() | SUBSAMPLES_VALID,
            Feature::FxOverRhoV2 => speed_alt | Channel::AccelX.bit(),
            Feature::FyOverRhoV2 => speed_alt | Channel::AccelY.bit(),
            Feature::FzOverRhoV2 => speed_alt | Channel::AccelZ.bit(),
            Feature::MachProxy | Feature::RhoV2 => speed_alt,
            Feature::UGround
            | Feature::VGround
            | Feature::WGround
            | Feature::AlphaKin
            | Feature::BetaKin => KINEMATIC_SOURCES,
            Feature::FilterAlpha
            | Feature::FilterBeta
            | Feature::FilterSigmaAlpha
            | Feature::FilterSigmaBeta
            | Feature::FilterAirspeed
            | Feature::FilterLiftScale
            | Feature::FilterTurbulence
            | Feature::FilterNisMean
            | Feature::FilterSideScale => crate::filter::NEEDED_MASK,
        }
    }

    /// Whether this feature is an output of the air-data filter (which then has to run each step).
    pub const fn needs_filter(self) -> bool {
        matches!(
            self,
            Feature::FilterAlpha
                | Feature::FilterBeta
                | Feature::FilterSigmaAlpha
                | Feature::FilterSigmaBeta
                | Feature::FilterAirspeed
                | Feature::FilterLiftScale
                | Feature::FilterTurbulence
                | Feature::FilterNisMean
                | Feature::FilterSideScale
        )
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
    /// EGI ground speed `|(v_N, v_E, v_D)|` below [`MIN_SPEED_MMS`]: the kinematic angles are noise.
    pub low_ground_speed: bool,
    /// Bit per [`Lag`]: for some channel the frame exactly that lag back was missing (see the module
    /// docs), so the delta was rate-scaled from another frame or set to 0.
    pub short_lags: u8,
    /// Stuck and saturated channels of this frame ([`crate::health`]); [`FeatureState::next`]
    /// computed the features as if those channels' valid bits were clear.
    pub health: crate::health::Status,
    /// The air-data filter's [`crate::filter::flags`] this step (0 without a filter).
    pub filter_flags: u8,
    /// The gyro channels the air-data filter's gyro check finds in disagreement with the EGI
    /// ([`crate::filter::Output::gyro_disagrees`]; 0 without a filter).
    pub gyro_disagrees: u32,
    /// Channels [`FeatureState::next`] filled in from other sensors because the GPS had none
    /// ([`GPS_COAST_MAX_MS`]): GPS speed from the EGI velocity, GPS altitude coasted on it.
    pub substituted: u32,
    /// The channels the features were computed from: valid, neither stuck nor saturated, or
    /// substituted. A model whose sources are not all in it is held ([`crate::Estimator::step`]).
    pub usable: u32,
}

/// Longest GPS outage over which [`FeatureState::next`] carries the last GPS altitude on by the
/// EGI's vertical velocity, ms (the filter's own bridge is as long: `filter::MAX_ALT_COAST_S`).
pub const GPS_COAST_MAX_MS: u32 = 120_000;

/// A gap between frames longer than this (ms) restarts the air-data filter: its wind and
/// covariance would be extrapolated over more than a second without a measurement.
pub const FILTER_RESTART_GAP_MS: u32 = 1_000;

/// Everything a model's features need from past frames: the history for the deltas and, when a
/// model reads filter outputs, the air-data filter itself. One instance per estimator (and per
/// flight in the trainer), fed every frame in order: the single place features are made.
#[derive(Clone, Debug)]
pub struct FeatureState {
    history: History,
    health: crate::health::Health,
    filter: Option<crate::filter::AirDataFilter>,
    /// The filter as it was at two earlier frames (frame count, time, filter), taken every
    /// [`STUCK_FRAMES`] frames: a channel the filter reads is found stuck only [`STUCK_FRAMES`]
    /// frames after it froze, and the filter has digested the frozen values by then. It goes back
    /// to the newest copy from before the freeze and predicts forward (see [`FeatureState::next`]).
    checkpoints: [Option<(u32, u32, crate::filter::AirDataFilter)>; 2],
    /// Frames seen, and the stuck channels of the previous frame.
    frames: u32,
    stuck_before: u32,
    /// The last GPS (or coasted) altitude, µm, and ms coasted since the last GPS one.
    gps_alt: Option<(i64, u32)>,
    last_ms: Option<u32>,
}

impl FeatureState {
    /// `with_filter`: run the air-data filter (needed when a model reads a filter feature).
    pub fn new(with_filter: bool) -> Self {
        FeatureState {
            history: History::new(),
            health: crate::health::Health::new(),
            checkpoints: [None, None],
            frames: 0,
            stuck_before: 0,
            gps_alt: None,
            filter: with_filter.then(|| crate::filter::AirDataFilter::new(crate::filter::CONFIG)),
            last_ms: None,
        }
    }

    pub fn history(&self) -> &History {
        &self.history
    }

    /// Fills GPS speed and altitude from the EGI velocity when the GPS has none (see
    /// [`FeatureState::next`]); returns the channels filled. Integer arithmetic only.
    fn substitute_gps(&mut self, f: &mut SensorFrame, dt_ms: u32) -> u32 {
        let (speed, alt) = (Channel::GpsSpeed, Channel::GpsAlt);
        let vel_ok = f.valid & VELOCITY_SOURCES == VELOCITY_SOURCES;
        let set = |f: &mut SensorFrame, c: Channel, v: i32| {
            if let Some(r) = f.raw.get_mut(c.index()) {
                *r = v;
            }
            f.valid |= c.bit();
        };
        let mut filled = 0;
        if f.is_valid(alt) {
            // cm → µm.
            self.gps_alt = Some((i64::from(f.get(alt)).saturating_mul(10_000), 0));
        } else if let (true, Some((alt_um, since_ms))) = (vel_ok, self.gps_alt) {
            let since_ms = since_ms.saturating_add(dt_ms);
            // mm/s × ms = µm, down positive.
            let alt_um = alt_um.saturating_sub(
                i64::from(f.get(Channel::VelDown)).saturating_mul(i64::from(dt_ms)),
            );
            let raw = alt_um / 10_000;
            if since_ms <= GPS_COAST_MAX_MS
                && let Ok(raw) = i32::try_from(raw)
            {
                self.gps_alt = Some((alt_um, since_ms));
                set(f, alt, raw);
                filled |= alt.bit();
            } else {
                self.gps_alt = None;
            }
        } else {
            self.gps_alt = None;
        }
        if !f.is_valid(speed) && vel_ok {
            let sq = |c: Channel| {
                let v = i64::from(f.get(c)).unsigned_abs();
                v.saturating_mul(v)
            };
            let ground = sq(Channel::VelNorth)
                .saturating_add(sq(Channel::VelEast))
                .saturating_add(sq(Channel::VelDown))
                .isqrt();
            if let Ok(v) = i32::try_from(ground) {
                set(f, speed, v);
                filled |= speed.bit();
            }
        }
        filled
    }

    /// The features of `frame` (deltas against the frames before it), then remembers it. The filter
    /// steps with the time since the previous frame (50 ms for the first). Stuck or saturated
    /// channels ([`crate::health`]) count as invalid everywhere from here on: in the features, in
    /// the filter and in the history.
    ///
    /// Without a GPS fix (GPS speed or altitude invalid) but with the EGI velocity, the GPS speed is
    /// the EGI's ground speed `|(v_N, v_E, v_D)|` (what the GPS speed channel measures) and the GPS
    /// altitude the last one carried on by `v_D`, for up to [`GPS_COAST_MAX_MS`]; those channels
    /// are then valid and listed in [`FeatureValues::substituted`].
    pub fn next(&mut self, frame: &SensorFrame) -> FeatureValues {
        let health = self
            .health
            .check(frame, self.history.newest().map(|p| &p.raw));
        let mut frame = SensorFrame {
            valid: health.usable(frame),
            ..*frame
        };
        let gap_ms = self.last_ms.map(|p| frame.time_ms.wrapping_sub(p));
        let substituted = self.substitute_gps(&mut frame, gap_ms.unwrap_or(FRAME_PERIOD_MS));
        let frame = &frame;
        let mut values = FeatureValues::compute(frame, &self.history);
        values.substituted = substituted;
        let newly_stuck = health.stuck & !self.stuck_before & crate::filter::NEEDED_MASK != 0;
        self.stuck_before = health.stuck;
        values.health = health;
        if let Some(filter) = self.filter.as_mut() {
            // After a gap longer than FILTER_RESTART_GAP_MS (no frames: link down, sender
            // restarted) the filter starts again as a fresh one, with its verdict on the
            // accelerometers kept (`AirDataFilter::start_again`).
            let mut dt_ms = match gap_ms {
                Some(gap) if gap <= FILTER_RESTART_GAP_MS => gap,
                Some(_) => {
                    filter.start_again();
                    self.checkpoints = [None, None];
                    FRAME_PERIOD_MS
                }
                None => FRAME_PERIOD_MS,
            };
            // A channel the filter reads has just been found stuck: it froze STUCK_FRAMES − 1
            // frames ago. Back to the newest checkpoint from no later than that, and predict from
            // there to now (this frame has the channel hidden, so the step is a prediction).
            let froze_at = self
                .frames
                .wrapping_sub(u32::from(crate::health::STUCK_FRAMES).saturating_sub(1));
            if newly_stuck
                && let Some((_, at_ms, saved)) = self
                    .checkpoints
                    .iter()
                    .flatten()
                    .filter(|(n, _, _)| {
                        self.frames.wrapping_sub(*n) >= self.frames.wrapping_sub(froze_at)
                    })
                    .max_by_key(|(n, _, _)| *n)
            {
                *filter = saved.clone();
                dt_ms = frame.time_ms.wrapping_sub(*at_ms);
                // The filter predicts at most a second per step.
                while dt_ms > 1_000 {
                    filter.step_frame(&SensorFrame::default(), 1.0);
                    dt_ms = dt_ms.saturating_sub(1_000);
                }
            }
            let out = filter.step_frame(frame, dt_ms as f32 / 1000.0);
            values.set_filter(&out);
            values.filter_flags = out.flags;
            values.gyro_disagrees = out.gyro_disagrees;
            if self
                .frames
                .is_multiple_of(u32::from(crate::health::STUCK_FRAMES))
            {
                let [_, newer] = core::mem::take(&mut self.checkpoints);
                self.checkpoints = [newer, Some((self.frames, frame.time_ms, filter.clone()))];
            }
        }
        self.frames = self.frames.wrapping_add(1);
        self.last_ms = Some(frame.time_ms);
        self.history.push(frame);
        values
    }
}

/// What [`History`] keeps of a frame: its time, channel values and valid bits (not the 120 Hz
/// sub-samples, which no delta reads: they are two thirds of a frame).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PastFrame {
    pub time_ms: u32,
    pub raw: [i32; CHANNELS],
    pub valid: u32,
}

impl PastFrame {
    const EMPTY: PastFrame = PastFrame {
        time_ms: 0,
        raw: [0; CHANNELS],
        valid: 0,
    };

    fn get(&self, c: Channel) -> i32 {
        self.raw.get(c.index()).copied().unwrap_or(0)
    }

    fn is_valid(&self, c: Channel) -> bool {
        self.valid & c.bit() != 0
    }
}

/// The last [`HISTORY_FRAMES`] sensor frames, newest last, for the delta features. Fixed size, no heap.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct History {
    past: [PastFrame; HISTORY_FRAMES],
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
            past: [PastFrame::EMPTY; HISTORY_FRAMES],
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
            *p = PastFrame {
                time_ms: frame.time_ms,
                raw: frame.raw,
                valid: frame.valid,
            };
        }
        // `head < HISTORY_FRAMES` and `len <= HISTORY_FRAMES`: neither add can overflow. The slot
        // index is modular by nature (wrapping); the count is bounded (saturating, then capped).
        self.head = self.head.wrapping_add(1) % HISTORY_FRAMES;
        self.len = self.len.saturating_add(1).min(HISTORY_FRAMES);
    }

    /// The frame stored last.
    pub fn newest(&self) -> Option<&PastFrame> {
        self.newest_first().next()
    }

    /// Stored frames, newest first.
    fn newest_first(&self) -> impl Iterator<Item = &PastFrame> {
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
        let age = |p: &PastFrame| frame.time_ms.wrapping_sub(p.time_ms);
        let max_age = want.saturating_mul(2);
        // The stored frame whose age is closest to the lag, in (0, 2 × lag], with the `need` channels
        // valid (the first, i.e. newest, of equally close ones). Age == lag is the exact frame.
        let closest = |need: u32| {
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
        for c in Channel::ALL.iter().copied().take(TABLE1_CHANNELS) {
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

    /// The filter's outputs are this step's: it had inputs and did not restart (otherwise they are
    /// held from an earlier step, or there is no filter and they are 0).
    pub fn filter_fresh(&self) -> bool {
        self.filter_flags & (crate::filter::flags::NO_INPUT | crate::filter::flags::RESTARTED) == 0
    }

    /// The filter ran and has no standing flag this step ([`crate::filter::flags::clear`]: inputs
    /// present, no restart, no gate run, 1σ within its limit, not slow, GPS altitude present; a
    /// prediction-only step counts as clear): its outputs may stand beside a network's.
    pub fn filter_clear(&self) -> bool {
        crate::filter::flags::clear(self.filter_flags) && self.get(Feature::FilterAirspeed) > 0
    }

    /// Writes the air-data filter's outputs into their features (rounded to the feature's LSB;
    /// the filter never returns a non-finite value, and `as` saturates).
    pub fn set_filter(&mut self, out: &crate::filter::Output) {
        let q = |f: Feature, v: f32| (f, libm::roundf(v / f.lsb() as f32) as i32);
        for (f, v) in [
            q(Feature::FilterAlpha, out.alpha_rad),
            q(Feature::FilterBeta, out.beta_rad),
            q(Feature::FilterSigmaAlpha, out.sigma_alpha_rad),
            q(Feature::FilterSigmaBeta, out.sigma_beta_rad),
            q(Feature::FilterAirspeed, out.airspeed_mps),
            q(Feature::FilterLiftScale, out.lift_scale),
            q(Feature::FilterTurbulence, out.turbulence_rad),
            q(Feature::FilterNisMean, out.nis_mean),
            q(Feature::FilterSideScale, out.side_scale),
        ] {
            if let Some(r) = self.raw.get_mut(f.index()) {
                *r = v;
            }
        }
    }

    /// Computes all features of `frame`, the deltas against `history` (the frames before it). Invalid
    /// channels are read as they are; the estimator decides what an invalid source means before it
    /// uses a value. (The EGI kinematic features are 0 unless all six of their sources are valid.)
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
        let mut low_ground_speed = false;
        if frame.valid & KINEMATIC_SOURCES == KINEMATIC_SOURCES {
            let k = Kinematics::of(frame);
            set(&mut raw, Feature::UGround, k.body_mms[0]);
            set(&mut raw, Feature::VGround, k.body_mms[1]);
            set(&mut raw, Feature::WGround, k.body_mms[2]);
            set(&mut raw, Feature::AlphaKin, k.alpha_urad);
            set(&mut raw, Feature::BetaKin, k.beta_urad);
            low_ground_speed = k.low_speed;
        }
        let mut short_lags = 0;
        for lag in Lag::ALL {
            if history.deltas(frame, lag, &mut raw) {
                short_lags |= lag.bit();
            }
        }
        // Channel-major here ([`Feature::Sub`]'s index), sample-major in the frame.
        if let Some(subs) = raw.get_mut(SUBS..) {
            for (i, per_channel) in subs.chunks_exact_mut(SUBSAMPLES).enumerate() {
                for (r, sample) in per_channel.iter_mut().zip(&frame.sub.raw) {
                    *r = sample.get(i).copied().unwrap_or(0);
                }
            }
        }
        FeatureValues {
            raw,
            low_speed,
            low_ground_speed,
            short_lags,
            health: crate::health::Status::default(),
            filter_flags: 0,
            gyro_disagrees: 0,
            substituted: 0,
            usable: (frame.valid & crate::channels::ALL_VALID) | subsamples_usable(frame),
        }
    }
}

/// [`SUBSAMPLES_VALID`] when the frame carries the sub-samples of every sub-sampled channel whose
/// 20 Hz value is usable, else 0. A channel that is itself invalid, stuck or saturated does not
/// take the others' sub-samples away (a dead LEF leaves β's inputs alone): a feature of its own
/// sub-samples is held through its 20 Hz channel's bit ([`Feature::sources`]).
fn subsamples_usable(frame: &SensorFrame) -> u32 {
    let need = Subsamples::mask_of(frame.valid);
    if frame.sub.valid & need == need && frame.sub.valid & Subsamples::ALL_VALID != 0 {
        SUBSAMPLES_VALID
    } else {
        0
    }
}

/// The EGI kinematic features of one frame.
struct Kinematics {
    /// Ground velocity in body axes, mm/s.
    body_mms: [i32; 3],
    alpha_urad: i32,
    beta_urad: i32,
    low_speed: bool,
}

impl Kinematics {
    /// `f32` arithmetic only (see the module docs): every operation is an IEEE-754 basic operation
    /// or a pure-Rust `libm` function, evaluated in the order written, so the result is the same bit
    /// pattern on every target. Every value stays finite for any raw input: the velocities are i32
    /// (|v| < 2^31 mm/s), sin/cos of any finite f32 lie in [−1, 1], so |u|, |v|, |w| < 2^33 and their
    /// squares < 2^68, far below f32's 2^128; `atan2f(0, 0)` is 0.
    fn of(frame: &SensorFrame) -> Kinematics {
        let angle = |c: Channel| frame.get(c) as f32 * 1e-6;
        let (sf, cf) = (
            libm::sinf(angle(Channel::Roll)),
            libm::cosf(angle(Channel::Roll)),
        );
        let (st, ct) = (
            libm::sinf(angle(Channel::Pitch)),
            libm::cosf(angle(Channel::Pitch)),
        );
        let (sp, cp) = (
            libm::sinf(angle(Channel::Heading)),
            libm::cosf(angle(Channel::Heading)),
        );
        let vn = frame.get(Channel::VelNorth) as f32;
        let ve = frame.get(Channel::VelEast) as f32;
        let vd = frame.get(Channel::VelDown) as f32;
        // Rows of C_bn, the NED → body direction cosine matrix of the 3-2-1 Euler angles.
        let u = (ct * cp) * vn + (ct * sp) * ve - st * vd;
        let v = (sf * st * cp - cf * sp) * vn + (sf * st * sp + cf * cp) * ve + (sf * ct) * vd;
        let w = (cf * st * cp + sf * sp) * vn + (cf * st * sp - sf * cp) * ve + (cf * ct) * vd;
        let uw = libm::sqrtf(u * u + w * w);
        let speed = libm::sqrtf(vn * vn + ve * ve + vd * vd);
        // `as` saturates (and maps NaN, which cannot occur here, to 0).
        let round = |x: f32| libm::roundf(x) as i32;
        Kinematics {
            body_mms: [round(u), round(v), round(w)],
            alpha_urad: round(libm::atan2f(w, u) * 1e6),
            beta_urad: round(libm::atan2f(v, uw) * 1e6),
            low_speed: speed < MIN_SPEED_MMS as f32,
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

    /// An EGI frame at `k × 50 ms`: climbing at 5 m/s, ground speed 3-4-0 × 50 m/s + the climb.
    fn gps_frame(k: u32, gps: bool) -> SensorFrame {
        let mut f = SensorFrame {
            seq: k as u16,
            time_ms: k * 50,
            valid: crate::channels::ALL_VALID,
            ..SensorFrame::default()
        };
        // One LSB of noise, so the health check does not find the EGI stuck.
        let wiggle = (k % 2) as i32;
        f.raw[Channel::VelNorth.index()] = 150_000 + wiggle;
        f.raw[Channel::VelEast.index()] = 200_000 - wiggle;
        f.raw[Channel::VelDown.index()] = -5_000 - 2 * wiggle;
        f.raw[Channel::GpsSpeed.index()] = 250_050 + wiggle;
        f.raw[Channel::GpsAlt.index()] = 300_000 + 25 * k as i32;
        if !gps {
            f.valid &= !(Channel::GpsSpeed.bit() | Channel::GpsAlt.bit());
            f.raw[Channel::GpsSpeed.index()] = 0;
            f.raw[Channel::GpsAlt.index()] = 0;
        }
        f
    }

    #[test]
    fn without_a_gps_fix_the_egi_fills_speed_and_altitude_for_at_most_gps_coast_max_ms() {
        let mut st = FeatureState::new(false);
        for k in 0..20 {
            assert_eq!(st.next(&gps_frame(k, true)).substituted, 0);
        }
        // Last fix: 3000 m + 19 × 25 cm, then carried on by v_D (µm: mm/s × ms).
        let mut alt_um = i64::from(300_000 + 25 * 19) * 10_000;
        let coast_frames = GPS_COAST_MAX_MS / FRAME_PERIOD_MS;
        for k in 20..20 + coast_frames {
            let f = gps_frame(k, false);
            let v = st.next(&f);
            let both = Channel::GpsSpeed.bit() | Channel::GpsAlt.bit();
            assert_eq!(v.substituted, both, "frame {k}");
            let (n, e, d) = (
                i64::from(f.get(Channel::VelNorth)),
                i64::from(f.get(Channel::VelEast)),
                i64::from(f.get(Channel::VelDown)),
            );
            let ground = ((n * n + e * e + d * d) as f64).sqrt().floor() as i32;
            assert_eq!(v.get(Feature::Sensor(Channel::GpsSpeed)), ground);
            alt_um -= d * 50;
            assert_eq!(
                v.get(Feature::Sensor(Channel::GpsAlt)),
                (alt_um / 10_000) as i32,
                "frame {k}"
            );
        }
        // Past the limit: the altitude is no longer filled (the speed still is: it is measured).
        let v = st.next(&gps_frame(20 + coast_frames, false));
        assert_eq!(v.substituted, Channel::GpsSpeed.bit());
        // A Table 1 frame (no EGI): nothing to fill from.
        let mut t1 = gps_frame(0, false);
        t1.valid &= crate::Suite::Table1.channels();
        assert_eq!(FeatureState::new(false).next(&t1).substituted, 0);
    }
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
            sub: crate::channels::Subsamples::NONE,
        }
    }

    /// A frame with the EGI channels set: attitude in degrees, NED velocity in m/s.
    fn egi(roll_deg: f64, pitch_deg: f64, heading_deg: f64, v_ned: [f64; 3]) -> SensorFrame {
        let mut si = [0.0; CHANNELS];
        si[Channel::Roll.index()] = roll_deg.to_radians();
        si[Channel::Pitch.index()] = pitch_deg.to_radians();
        si[Channel::Heading.index()] = heading_deg.to_radians();
        si[Channel::VelNorth.index()] = v_ned[0];
        si[Channel::VelEast.index()] = v_ned[1];
        si[Channel::VelDown.index()] = v_ned[2];
        si[Channel::GpsSpeed.index()] = 200.0;
        SensorFrame::from_si(0, 0, &si)
    }

    /// A steady egi frame at `t_ms`: level flight east at 200 m/s, 3000 m, 1 g, fuel 1000 kg.
    fn steady_egi(t_ms: u32) -> SensorFrame {
        let mut si = [0.0; CHANNELS];
        si[Channel::Pitch.index()] = 3f64.to_radians();
        si[Channel::Heading.index()] = 90f64.to_radians();
        si[Channel::VelEast.index()] = 200.0;
        si[Channel::GpsSpeed.index()] = 200.0;
        si[Channel::GpsAlt.index()] = 3000.0;
        si[Channel::AccelZ.index()] = -9.81;
        si[Channel::Fuel.index()] = 1000.0;
        SensorFrame::from_si((t_ms / FRAME_PERIOD_MS) as u16, t_ms, &si)
    }

    #[test]
    fn subsample_features_read_the_frame_period_and_need_all_of_it() {
        let mut frame = ramp(1_000);
        let h = History::new();
        // Without sub-samples: the features read 0 and the frame does not make them usable.
        let v = FeatureValues::compute(&frame, &h);
        assert_eq!(v.usable & SUBSAMPLES_VALID, 0);
        assert_eq!(v.get(Feature::Sub(Channel::AccelY, 5)), 0);
        for (k, row) in frame.sub.raw.iter_mut().enumerate() {
            for (i, x) in row.iter_mut().enumerate() {
                *x = 1000 * i as i32 + k as i32;
            }
        }
        frame.sub.valid = Subsamples::ALL_VALID;
        let v = FeatureValues::compute(&frame, &h);
        assert_ne!(v.usable & SUBSAMPLES_VALID, 0);
        // AccelY is sub-channel 4, the rudder 8.
        assert_eq!(v.get(Feature::Sub(Channel::AccelY, 5)), 4005);
        assert_eq!(v.get(Feature::Sub(Channel::AccelY, 0)), 4000);
        assert_eq!(v.get(Feature::Sub(Channel::Rudder, 3)), 8003);
        let f = Feature::Sub(Channel::Rudder, 3);
        assert_eq!(f.name(), "rudder_deg_sub3");
        assert_eq!(Feature::from_name("rudder_deg_sub3"), Some(f));
        assert_eq!(f.suite(), Suite::Egi120);
        // One sub-channel missing takes them all away (a model reading any is held)...
        frame.sub.valid &= !(1 << 8);
        assert_eq!(
            FeatureValues::compute(&frame, &h).usable & SUBSAMPLES_VALID,
            0
        );
        // ... unless its 20 Hz channel is gone too: then only its own features are held.
        frame.valid &= !Channel::Rudder.bit();
        let v = FeatureValues::compute(&frame, &h);
        assert_ne!(v.usable & SUBSAMPLES_VALID, 0);
        assert_ne!(Feature::Sub(Channel::Rudder, 0).sources() & !v.usable, 0);
        assert_eq!(Feature::Sub(Channel::AccelY, 0).sources() & !v.usable, 0);
        // A sender cannot switch the sub-samples on through the channel bits.
        frame.sub.valid = 0;
        frame.valid |= SUBSAMPLES_VALID;
        assert_eq!(
            FeatureValues::compute(&frame, &h).usable & SUBSAMPLES_VALID,
            0
        );
        let mut state = FeatureState::new(false);
        assert_eq!(state.next(&frame).usable & SUBSAMPLES_VALID, 0);
        // A channel that is not sub-sampled, or a k past the period, is no candidate.
        assert!(Feature::Sub(Channel::GpsAlt, 0).index() >= FEATURE_COUNT);
        assert!(Feature::Sub(Channel::AccelY, 6).index() >= FEATURE_COUNT);
        assert!(Feature::Delta(Channel::Roll, Lag::F1).index() >= FEATURE_COUNT);
    }

    #[test]
    fn set_filter_writes_every_filter_output_in_its_feature_unit() {
        let out = crate::filter::Output {
            alpha_rad: 0.25,
            beta_rad: -0.03,
            sigma_alpha_rad: 0.004,
            sigma_beta_rad: 0.002,
            airspeed_mps: 123.456,
            lift_scale: 1.0321,
            turbulence_rad: 0.001_234,
            nis_mean: 1.5,
            side_scale: 0.8765,
            ..Default::default()
        };
        let mut v = FeatureValues::compute(&SensorFrame::default(), &History::new());
        v.set_filter(&out);
        assert_eq!(v.get(Feature::FilterAlpha), 250_000);
        assert_eq!(v.get(Feature::FilterBeta), -30_000);
        assert_eq!(v.get(Feature::FilterSigmaAlpha), 4_000);
        assert_eq!(v.get(Feature::FilterSigmaBeta), 2_000);
        assert_eq!(v.get(Feature::FilterAirspeed), 123_456);
        assert_eq!(v.get(Feature::FilterLiftScale), 10_321);
        assert_eq!(v.get(Feature::FilterTurbulence), 1_234);
        assert_eq!(v.get(Feature::FilterNisMean), 1_500);
        assert_eq!(v.get(Feature::FilterSideScale), 8_765);
    }

    #[test]
    fn feature_state_runs_the_filter_only_when_asked_and_only_on_egi_frames() {
        let mut with = FeatureState::new(true);
        let mut without = FeatureState::new(false);
        let mut table1 = FeatureState::new(true);
        for k in 0..40u32 {
            let f = steady_egi(k * FRAME_PERIOD_MS);
            let a = with.next(&f);
            let b = without.next(&f);
            let c = table1.next(&f.restricted_to(Suite::Table1));
            // Everything but the filter features is the same with and without the filter.
            for feat in Feature::ALL {
                if !feat.needs_filter() {
                    assert_eq!(a.get(feat), b.get(feat), "{}", feat.name());
                } else {
                    assert_eq!(b.get(feat), 0);
                    assert_eq!(c.get(feat), 0, "no EGI input, no filter output");
                }
            }
            if k > 0 {
                // The filter ran: outputs of a plausible size (this made-up frame need not agree
                // with the aero model, so the filter may put some of it into wind).
                let alpha = a.get(Feature::FilterAlpha) as f64 * 1e-6;
                assert!((alpha - 3f64.to_radians()).abs() < 0.1, "α {alpha}");
                assert!((a.get(Feature::FilterAirspeed) - 200_000).abs() < 60_000);
                assert!(a.get(Feature::FilterLiftScale) > 5_000);
            }
        }
    }

    #[test]
    fn kinematic_angles_of_a_climb_heading_east() {
        // Wings level, nose 5° up, flying east at 200 m/s level: α_kin = θ = 5°, no sideslip.
        let v = FeatureValues::compute(&egi(0.0, 5.0, 90.0, [0.0, 200.0, 0.0]), &History::new());
        let close = |f: Feature, want: f64, tol: f64| {
            let got = v.get(f) as f64 * f.lsb();
            assert!((got - want).abs() <= tol, "{}: {got} vs {want}", f.name());
        };
        close(Feature::AlphaKin, 5f64.to_radians(), 2e-6);
        close(Feature::BetaKin, 0.0, 2e-6);
        close(Feature::UGround, 200.0 * 5f64.to_radians().cos(), 2e-3);
        close(Feature::VGround, 0.0, 2e-3);
        close(Feature::WGround, 200.0 * 5f64.to_radians().sin(), 2e-3);
        assert!(!v.low_ground_speed);
        // A 30° bank does not change them (velocity along the nose's vertical plane is rotated with
        // the body), but a crosswind-like lateral velocity gives β = asin(v / |V|).
        let v = FeatureValues::compute(&egi(30.0, 0.0, 0.0, [200.0, 10.0, 0.0]), &History::new());
        let close = |f: Feature, want: f64, tol: f64| {
            let got = v.get(f) as f64 * f.lsb();
            assert!((got - want).abs() <= tol, "{}: {got} vs {want}", f.name());
        };
        let beta = (10.0 * 30f64.to_radians().cos() / 200.0f64.hypot(10.0)).asin();
        close(Feature::BetaKin, beta, 3e-6);
        close(
            Feature::AlphaKin,
            (-10.0 * 30f64.to_radians().sin() / 200.0f64).atan(),
            3e-6,
        );
    }

    #[test]
    fn kinematic_features_are_pinned_to_the_bit() {
        // The integers this arithmetic gives (host and Cortex-M4F alike, see the module docs): a
        // change of the operation order or of the math library shows here first.
        let v = FeatureValues::compute(
            &egi(-37.5, 12.25, 301.0, [-123.456, 87.654, -9.87]),
            &History::new(),
        );
        let got = [
            Feature::UGround,
            Feature::VGround,
            Feature::WGround,
            Feature::AlphaKin,
            Feature::BetaKin,
        ]
        .map(|f| v.get(f));
        assert_eq!(got, PINNED);
    }
    // An f64 evaluation of the same formulas gives -133466.02, -24349.19, -67940.88 mm/s and
    // -2670731.25, -161173.88 µrad.
    const PINNED: [i32; 5] = [-133_466, -24_349, -67_941, -2_670_731, -161_174];

    #[test]
    fn kinematic_features_need_all_six_egi_channels() {
        let mut f = egi(10.0, 5.0, 45.0, [100.0, 100.0, 5.0]);
        f.valid &= !Channel::Heading.bit();
        let v = FeatureValues::compute(&f, &History::new());
        assert_eq!(v.get(Feature::AlphaKin), 0);
        assert_eq!(v.get(Feature::UGround), 0);
        assert!(!v.low_ground_speed);
        // Below 20 m/s over the ground the angles are computed but flagged.
        let v = FeatureValues::compute(&egi(0.0, 0.0, 0.0, [5.0, 0.0, 0.0]), &History::new());
        assert!(v.low_ground_speed);
        assert_eq!(v.get(Feature::UGround), 5_000);
    }

    #[test]
    fn every_feature_belongs_to_the_suite_of_its_sources() {
        for f in Feature::ALL {
            assert_eq!(
                f.suite() == Suite::Table1,
                f.sources() & !Suite::Table1.channels() == 0
            );
        }
        assert_eq!(Feature::AlphaKin.suite(), Suite::Egi);
        assert_eq!(Feature::Sensor(Channel::Fuel).suite(), Suite::Egi);
        assert_eq!(Feature::MachProxy.suite(), Suite::Table1);
        // No delta of an EGI channel is a candidate.
        let d = Feature::Delta(Channel::Roll, Lag::F1);
        assert!(d.index() >= FEATURE_COUNT);
        assert!(!Feature::ALL.contains(&d));
        assert_eq!(Feature::from_name(d.name()), None);
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
        assert_eq!(v.short_lags, Lag::ALL_BITS);
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
            assert_eq!(v.short_lags, Lag::ALL_BITS, "t={t}");
            assert_eq!(v.get(Feature::Delta(Channel::GyroP, Lag::F20)), 0);
        }
    }
}
