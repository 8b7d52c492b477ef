//! The cascaded α/β estimator: one [`Estimator::step`] per 20 Hz sensor frame.
//!
//! # What bad input gives
//! | input | result |
//! |---|---|
//! | a channel a model uses is marked invalid (sensor flag, NaN, ±Inf, out of the wire range) | `INVALID_INPUT`; that angle's last good value is held (`ALPHA_HELD`/`BETA_HELD`), or it reads zero with `NO_ESTIMATE` if there is none |
//! | a noisy channel (IMU, GPS, EGI) a model uses repeats the same value for [`STUCK_FRAMES`] frames | `STUCK_SENSOR` on that frame, held as above, until it changes ([`crate::health`]) |
//! | an IMU channel a model uses is at its full scale in its 20 Hz value or a 120 Hz sub-sample (the sensor clipped) | `SATURATED` on that frame, held as above |
//! | the air-data filter a model reads restarted, keeps failing its innovation gate, or gives its prediction alone on this frame (the innovation failed the gate: sensors and model more than 5σ apart; or no update was made: its first step after a start or an outage, an update whose arithmetic failed) | `FILTER_DIVERGED`, estimate computed |
//! | GPS speed or altitude invalid (no fix) while the EGI velocity is valid | both filled from the EGI (altitude for at most 120 s): `GPS_SUBSTITUTED`, estimate computed |
//! | a feature outside the range seen in training | clamped to that range, estimate computed, `OUT_OF_ENVELOPE` |
//! | the air-data filter's lift scale outside the range seen in training, for a model that runs the filter (whether or not it reads the lift scale: [`CascadeNet::lift_scale`]) | estimate computed, `OUT_OF_ENVELOPE` |
//! | GPS speed below [`crate::features::MIN_SPEED_MMS`] | derived features saturate: `OUT_OF_ENVELOPE` |
//! | EGI ground speed below [`crate::features::MIN_SPEED_MMS`], for a model reading the EGI velocity | kinematic angles are noise: `OUT_OF_ENVELOPE` |
//! | a model reads an EGI channel and the frame is of the Table 1 suite (the channel is absent) | as an invalid channel: `INVALID_INPUT`, held |
//! | the network's output outside the training range of α/β | clamped to it, `OUT_OF_ENVELOPE` |
//! | the air-data filter's turbulence index above what the model trained on at the filter's airspeed | `TURBULENCE`, estimate computed |
//! | the α network out of its envelope while the filter it reads is consistent ([`filter_alpha_fallback`]), where the aircraft's description allows it (`estimator.alpha_from_filter`) | α is the filter's: `OUT_OF_ENVELOPE` and `ALPHA_FROM_FILTER` |
//! | the β network's answer and an unflagged filter's β more than 2° and 3σ apart ([`beta_disagrees_with_filter`]) | β computed (the network's), `BETA_DISAGREES` |
//! | a gyro a model reads disagrees with the EGI's attitude change (the air-data filter's gyro check, `filter.gyro_gate_rps`: a bias or scale error) | estimate computed, `GYRO_DISAGREES`, each 1σ at least just above its `UNCERTAIN` limit, so `UNCERTAIN` too; the filter takes the error off that gyro |
//! | a computed angle's 1σ above [`UNCERTAIN_ALPHA_MDEG`] / [`UNCERTAIN_BETA_MDEG`], or above it within that angle's last [`UNCERTAIN_HOLD_FRAMES`] computed frames | estimate computed, `UNCERTAIN` |
//! | a lag a model's delta features use lacks its exact lagged frame for some channel (first second, lost frames, time jump, a channel invalid back then) | delta rate-scaled from the nearest stored frame or 0 (see [`crate::features`]), estimate computed, `HISTORY_SHORT` |
//!
//! α and β are handled independently: a bad rudder sensor holds β and leaves α live. No input makes
//! the step panic or return anything but the integers described here.

use crate::channels::{Channel, SensorFrame};
use crate::features::{Feature, FeatureState, FeatureValues, VELOCITY_SOURCES};
use crate::filter;
use crate::nn::{Aligned, Layer};
use crate::normalize::{Envelope, Norm, TurbulenceEnvelope};
use crate::uncertainty::{self, SIGMA_UNKNOWN};

pub use crate::health::STUCK_FRAMES;

/// Estimate flags (bit set).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Flags(pub u16);

impl Flags {
    /// A channel used by α or β is invalid.
    pub const INVALID_INPUT: u16 = 1 << 0;
    /// A feature or an output was outside the training envelope and clamped, or the air-data
    /// filter's lift scale was outside its training range ([`CascadeNet::lift_scale`]).
    pub const OUT_OF_ENVELOPE: u16 = 1 << 1;
    /// A noisy channel used by α or β has not changed for [`STUCK_FRAMES`] frames.
    pub const STUCK_SENSOR: u16 = 1 << 2;
    /// α is the last good value, not computed from this frame.
    pub const ALPHA_HELD: u16 = 1 << 3;
    /// β is the last good value, not computed from this frame.
    pub const BETA_HELD: u16 = 1 << 4;
    /// An angle that had to be held (`ALPHA_HELD`/`BETA_HELD`) had no good value yet: that angle and
    /// its intermediate are zero and meaningless. The other angle may still be live.
    pub const NO_ESTIMATE: u16 = 1 << 5;
    /// The estimator has no compiled-in model (a build without weights).
    pub const NO_MODEL: u16 = 1 << 6;
    /// A computed angle reads delta features at a lag for which some channel's delta was not taken
    /// over the exact lag (the first second after a start or reset, lost frames, a channel invalid in
    /// the lagged frame): the estimate is computed but may be less accurate.
    pub const HISTORY_SHORT: u16 = 1 << 7;
    /// An IMU channel used by α or β is at its full scale ([`crate::Channel::full_scale`]) in its
    /// 20 Hz value or one of the period's 120 Hz sub-samples: the sensor clipped. Held as for
    /// `INVALID_INPUT`.
    pub const SATURATED: u16 = 1 << 8;
    /// A computed angle reads the air-data filter's outputs and the filter is diverging: it
    /// restarted this step (covariance blow-up, non-finite arithmetic) or its innovations have
    /// failed the gate for [`crate::filter::Config::gate_run`] steps in a row, or its outputs this
    /// frame are its prediction alone ([`crate::filter::flags::PREDICTED`]: the innovation failed
    /// the gate, the sensors disagreeing with its model by more than 5σ, a sensor fault or a
    /// manoeuvre the model does not follow; or no update was made, as on its first step after a
    /// start or an outage, whose wind is seconds of prediction old). The estimate is computed but
    /// its filter features are not what training saw.
    pub const FILTER_DIVERGED: u16 = 1 << 9;
    /// A computed angle reads GPS speed or altitude and the GPS had none: they came from the EGI
    /// (ground speed from its velocity, altitude coasted on its vertical velocity, at most
    /// [`crate::features::GPS_COAST_MAX_MS`]). The estimate is computed, from substitutes.
    pub const GPS_SUBSTITUTED: u16 = 1 << 10;
    /// A computed angle reads the air-data filter, and the filter's turbulence index is above the
    /// 99.9th percentile of what the model was trained on at this airspeed
    /// ([`crate::normalize::TurbulenceEnvelope`]): the estimate is computed, but the air mass
    /// moves α and β faster than training flew it, and errors of degrees are possible.
    pub const TURBULENCE: u16 = 1 << 11;
    /// α (and `w_aero_mms`) are the air-data filter's, not the α network's: the network was out of
    /// its envelope (`OUT_OF_ENVELOPE` is set too) while the filter reported no flag and its
    /// innovations were consistent ([`filter_alpha_fallback`]). β is still the network's.
    pub const ALPHA_FROM_FILTER: u16 = 1 << 12;
    /// The network's β and the air-data filter's disagree by more than
    /// [`BETA_CROSSCHECK_MIN_MDEG`] and [`BETA_CROSSCHECK_SIGMAS`] of the filter's 1σ while the
    /// filter has no standing flag ([`beta_disagrees_with_filter`]): one of the two is wrong by
    /// degrees. On the validation flights it was mostly the network (a sideslip beyond what it
    /// was trained on, which the filter's kinematics follow); in heavy turbulence it can be the
    /// filter. β is still the network's.
    pub const BETA_DISAGREES: u16 = 1 << 13;
    /// A computed angle's 1σ is above [`UNCERTAIN_ALPHA_MDEG`] (α) or [`UNCERTAIN_BETA_MDEG`]
    /// (β), or was within its last [`UNCERTAIN_HOLD_FRAMES`] computed frames: an error as large as
    /// a flight-control computer would act on (2° α, 1° β) is then a 4σ event or likelier. The
    /// estimate is computed; its 1σ says how far to trust it.
    pub const UNCERTAIN: u16 = 1 << 14;
    /// A gyro a computed angle reads disagrees with the EGI's attitude change: its 1-s running
    /// mean is off by more than the aircraft's `filter.gyro_gate_rps` (a bias, a scale error).
    /// The networks read the gyro as it is; the air-data filter takes the running mean off it.
    /// Each computed angle's 1σ is then at least just above its `UNCERTAIN` limit
    /// ([`GYRO_SIGMA_FLOOR`]), so the frame is `UNCERTAIN` too.
    pub const GYRO_DISAGREES: u16 = 1 << 15;

    /// The flags that say an angle was computed from less than training saw and raise the 1σ's
    /// `Caution` term ([`crate::uncertainty::Term::Caution`]). `FILTER_DIVERGED`, also a caution,
    /// raises a term of its own ([`crate::uncertainty::Term::FilterDiverged`]).
    pub const CAUTIONS: u16 = Self::HISTORY_SHORT
        | Self::GPS_SUBSTITUTED
        | Self::ALPHA_FROM_FILTER
        | Self::BETA_DISAGREES;

    /// Every flag bit with its name, in bit order: the names of the estimates CSV's flag columns
    /// and of the summaries' flag counts.
    pub const NAMED: [(u16, &'static str); 16] = [
        (Self::INVALID_INPUT, "invalid_input"),
        (Self::OUT_OF_ENVELOPE, "out_of_envelope"),
        (Self::STUCK_SENSOR, "stuck_sensor"),
        (Self::ALPHA_HELD, "alpha_held"),
        (Self::BETA_HELD, "beta_held"),
        (Self::NO_ESTIMATE, "no_estimate"),
        (Self::NO_MODEL, "no_model"),
        (Self::HISTORY_SHORT, "history_short"),
        (Self::SATURATED, "saturated"),
        (Self::FILTER_DIVERGED, "filter_diverged"),
        (Self::GPS_SUBSTITUTED, "gps_substituted"),
        (Self::TURBULENCE, "turbulence"),
        (Self::ALPHA_FROM_FILTER, "alpha_from_filter"),
        (Self::BETA_DISAGREES, "beta_disagrees"),
        (Self::UNCERTAIN, "uncertain"),
        (Self::GYRO_DISAGREES, "gyro_disagrees"),
    ];

    pub fn has(self, bit: u16) -> bool {
        self.0 & bit != 0
    }

    /// Both angles were computed from this frame's data (none held, no `NO_ESTIMATE`/`NO_MODEL`).
    pub fn is_usable(self) -> bool {
        self.0 & (Self::NO_ESTIMATE | Self::NO_MODEL | Self::ALPHA_HELD | Self::BETA_HELD) == 0
    }
}

/// One estimate. Its `Default` is all zero with no 1σ ([`SIGMA_UNKNOWN`]): nothing was computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Estimate {
    /// Sequence number and time of the sensor frame it answers.
    pub seq: u16,
    pub time_ms: u32,
    /// Angle of attack, millidegrees.
    pub alpha_mdeg: i32,
    /// Sideslip angle, millidegrees.
    pub beta_mdeg: i32,
    /// Part 1 of the α cascade: body z air-relative velocity, mm/s.
    pub w_aero_mms: i32,
    /// Part 1 of the β cascade: body y air-relative velocity, mm/s.
    pub v_aero_mms: i32,
    pub flags: Flags,
    /// 1σ of α, millidegrees ([`crate::uncertainty`]); [`crate::uncertainty::SIGMA_UNKNOWN`] when
    /// α was not computed from this frame (held, or no estimate).
    pub sigma_alpha_mdeg: u16,
    /// 1σ of β, millidegrees, as for α.
    pub sigma_beta_mdeg: u16,
}

impl Default for Estimate {
    fn default() -> Self {
        Estimate {
            seq: 0,
            time_ms: 0,
            alpha_mdeg: 0,
            beta_mdeg: 0,
            w_aero_mms: 0,
            v_aero_mms: 0,
            flags: Flags::default(),
            sigma_alpha_mdeg: SIGMA_UNKNOWN,
            sigma_beta_mdeg: SIGMA_UNKNOWN,
        }
    }
}

impl Estimate {
    pub fn alpha_deg(&self) -> f64 {
        self.alpha_mdeg as f64 * 1e-3
    }
    pub fn beta_deg(&self) -> f64 {
        self.beta_mdeg as f64 * 1e-3
    }
}

/// A cascaded network for one angle, as the estimator sees it.
pub trait AngleNet: Sync {
    /// The features it reads, in input order.
    fn features(&self) -> &[Feature];
    /// Runs both parts on the selected, clamped, normalised features. Returns
    /// `(intermediate, angle)` in (mm/s, millidegrees) and whether anything was clamped.
    fn run(&self, values: &FeatureValues) -> (i32, i32, bool);
    /// Multiply-accumulates per run.
    fn macs(&self) -> usize;
    /// Channels the features are computed from.
    fn sources(&self) -> u32 {
        self.features().iter().fold(0, |m, f| m | f.sources())
    }
    /// Lags of the delta features it reads (bit per [`crate::features::Lag`]).
    fn lags(&self) -> u8 {
        self.features().iter().fold(0, |m, f| m | f.lags())
    }
    /// The turbulence it was trained on, by airspeed.
    fn turbulence(&self) -> TurbulenceEnvelope {
        TurbulenceEnvelope::ANY
    }
}

/// Part 1 maps the `N` features to the intermediate; part 2 maps the features plus the normalised
/// intermediate (`N1 = N + 1`, checked at compile time) to the angle.
///
/// A cascade of two features whose part 2 takes three inputs:
/// ```
/// # use estimator_core::nn::{Dense, Output, Requant};
/// # use estimator_core::normalize::{Envelope, Norm, TurbulenceEnvelope};
/// # use estimator_core::{AngleNet, CascadeNet, Channel, Feature, FeatureValues, History, SensorFrame};
/// let one = Norm { center: 0, mult: 1 << 20, shift: 20 };
/// let net: CascadeNet<Output<2, 1>, Output<3, 1>, 2, 3> = CascadeNet {
///     features: [Feature::Sensor(Channel::GyroQ), Feature::Sensor(Channel::Elevator)],
///     norm: [one; 2],
///     envelope: [Envelope::ANY; 2],
///     part1: Output(Dense::new([[1, 1]], [7], [Requant::ONE])),
///     mid_norm: one,
///     part2: Output(Dense::new([[1, 1, 1]], [0], [Requant::ONE])),
///     out_range: Envelope::ANY,
///     turbulence: TurbulenceEnvelope::ANY,
///     lift_scale: Envelope::ANY,
/// };
/// let values = FeatureValues::compute(&SensorFrame::default(), &History::new());
/// assert_eq!(net.run(&values), (7, 7, false));
/// ```
/// A part 2 that does not take exactly the features plus the intermediate does not compile (the
/// check runs where the cascade is used as an [`AngleNet`], as the estimator uses every model):
/// ```compile_fail,E0080
/// # use estimator_core::nn::{Dense, Output, Requant};
/// # use estimator_core::normalize::{Envelope, Norm, TurbulenceEnvelope};
/// # use estimator_core::{AngleNet, CascadeNet, Channel, Feature, FeatureValues, History, SensorFrame};
/// let one = Norm { center: 0, mult: 1 << 20, shift: 20 };
/// let net: CascadeNet<Output<2, 1>, Output<4, 1>, 2, 4> = CascadeNet {
///     features: [Feature::Sensor(Channel::GyroQ), Feature::Sensor(Channel::Elevator)],
///     norm: [one; 2],
///     envelope: [Envelope::ANY; 2],
///     part1: Output(Dense::new([[1, 1]], [7], [Requant::ONE])),
///     mid_norm: one,
///     part2: Output(Dense::new([[1, 1, 1, 1]], [0], [Requant::ONE])),
///     out_range: Envelope::ANY,
///     turbulence: TurbulenceEnvelope::ANY,
///     lift_scale: Envelope::ANY,
/// };
/// let values = FeatureValues::compute(&SensorFrame::default(), &History::new());
/// assert_eq!(net.run(&values), (7, 7, false));
/// ```
pub struct CascadeNet<P1, P2, const N: usize, const N1: usize> {
    pub features: [Feature; N],
    pub norm: [Norm; N],
    pub envelope: [Envelope; N],
    pub part1: P1,
    /// Intermediate (mm/s) → part 2 input.
    pub mid_norm: Norm,
    pub part2: P2,
    /// Training range of the angle, millidegrees.
    pub out_range: Envelope,
    /// Turbulence trained on, by filter airspeed ([`TurbulenceEnvelope::ANY`] if it does not read
    /// the filter).
    pub turbulence: TurbulenceEnvelope,
    /// Range of the air-data filter's lift scale over the training frames ([`Envelope::ANY`] if it
    /// does not read the filter). Outside it, the aerodynamic model and the sensors disagree in a
    /// way training never flew (mass, configuration, severe turbulence): [`AngleNet::run`] reports
    /// the model as clamped, whether or not the lift scale is one of its inputs.
    pub lift_scale: Envelope,
}

impl<P1, P2, const N: usize, const N1: usize> CascadeNet<P1, P2, N, N1>
where
    P1: Layer<N, 1, Out = i32>,
    P2: Layer<N1, 1, Out = i32>,
{
    const SHAPE_OK: () = assert!(
        N1 == N + 1,
        "part 2 takes the features plus one intermediate"
    );

    fn inputs(&self, values: &FeatureValues) -> (Aligned<N>, bool) {
        let mut clamped = false;
        let mut x = Aligned([0i16; N]);
        for (((x, f), n), e) in
            x.0.iter_mut()
                .zip(&self.features)
                .zip(&self.norm)
                .zip(&self.envelope)
        {
            let (v, out) = e.clamp(values.get(*f));
            clamped |= out;
            *x = n.apply(v);
        }
        (x, clamped)
    }
}

impl<P1, P2, const N: usize, const N1: usize> AngleNet for CascadeNet<P1, P2, N, N1>
where
    P1: Layer<N, 1, Out = i32> + Sync,
    P2: Layer<N1, 1, Out = i32> + Sync,
{
    fn features(&self) -> &[Feature] {
        &self.features
    }

    fn run(&self, values: &FeatureValues) -> (i32, i32, bool) {
        let () = Self::SHAPE_OK;
        let (x, mut clamped) = self.inputs(values);
        let mut mid = [0i32; 1];
        self.part1.forward(&x.0, &mut mid);
        let mut x1 = Aligned([0i16; N1]);
        for (d, s) in x1.0.iter_mut().zip(x.0.iter()) {
            *d = *s;
        }
        if let Some(last) = x1.0.last_mut() {
            *last = self.mid_norm.apply(mid[0]);
        }
        let mut out = [0i32; 1];
        self.part2.forward(&x1.0, &mut out);
        let (angle, out_clamped) = self.out_range.clamp(out[0]);
        let sources = self.sources();
        clamped |= out_clamped
            || self
                .lift_scale
                .clamp(values.get(Feature::FilterLiftScale))
                .1
            || values.low_speed && sources & Channel::GpsSpeed.bit() != 0
            || values.low_ground_speed && sources & VELOCITY_SOURCES != 0;
        (mid[0], angle, clamped)
    }

    fn turbulence(&self) -> TurbulenceEnvelope {
        self.turbulence
    }

    fn macs(&self) -> usize {
        // A benchmark figure: a count saturates (it cannot come near usize::MAX anyway).
        self.part1.macs().saturating_add(self.part2.macs())
    }
}

/// Largest [`crate::filter::Output::nis_mean`] (in the 1e-3 of [`Feature::FilterNisMean`]) at which
/// the filter may stand in for the α network: 2, the expected NIS of a consistent filter with the
/// measurement's two degrees of freedom. Asking the 2-s mean to stay at or below it asks the filter
/// to be at least as conservative as its covariance claims. Its measurement noise is set for model
/// error, so where its model fits the mean sits far below (0.006 on the mass flights); above 2 the innovations
/// are larger than the covariance accounts for (turbulence it does not follow, an unmodelled
/// configuration, a sensor fault), and its α is no better founded than a network outside its
/// envelope. Not fitted to any flight.
pub const FALLBACK_NIS_MEAN_MAX: i32 = 2_000;

/// The air-data filter's α (millidegrees) and the body-z air velocity it implies (mm/s,
/// `V·sin α·cos β`), when the filter is fit to stand in for an α network that is out of its
/// envelope: its outputs are this step's and it raised no flag at all (inputs present, its
/// measurement used, no restart, no gate run, confident, not slow, GPS altitude present), and its
/// NIS mean is at most [`FALLBACK_NIS_MEAN_MAX`]. `None` otherwise, and for a state without a filter (airspeed 0).
///
/// A fallback α that is later held (the α sources go bad on the next frame) carries `ALPHA_HELD`
/// only, like any held value. The choice is made frame by frame, without hysteresis.
///
/// Why the α only: the filter's α rests on lift, which the aerodynamic model and the lift scale
/// carry through mass and wind outside the training envelope (the `mass-*` flights of
/// `docs/results/ood.md`). Its β rests on the side force, which it follows less well than the
/// network does even there.
pub fn filter_alpha_fallback(values: &FeatureValues) -> Option<(i32, i32)> {
    // Standing in for a network needs no flag at all, `PREDICTED` included: an updated filter.
    if !values.filter_clear()
        || values.filter_flags != 0
        || values.get(Feature::FilterNisMean) > FALLBACK_NIS_MEAN_MAX
    {
        return None;
    }
    let airspeed_mms = values.get(Feature::FilterAirspeed);
    let rad = |f: Feature| values.get(f) as f32 * 1e-6;
    let (alpha, beta) = (rad(Feature::FilterAlpha), rad(Feature::FilterBeta));
    let w = airspeed_mms as f32 * libm::sinf(alpha) * libm::cosf(beta);
    let mdeg = alpha * (180_000.0 / core::f32::consts::PI);
    // Both are finite (the features are integers) and far inside i32; `as` saturates anyway.
    Some((libm::roundf(w) as i32, libm::roundf(mdeg) as i32))
}

/// [`Flags::BETA_DISAGREES`] needs at least this difference between the network's and the
/// filter's β, millidegrees. Chosen on the validation flights of `large-egi` with the shipped
/// networks: 113 of 209,880 frames flagged, 72 of them with the network's β off by more than 1°
/// (of the 55 that carried no other flag, 48; docs/filter.md).
pub const BETA_CROSSCHECK_MIN_MDEG: i64 = 2_000;

/// ... and at least this many of the filter's β 1σ.
pub const BETA_CROSSCHECK_SIGMAS: i64 = 3;

/// Whether `beta_mdeg` (the network's β) and the air-data filter's β in `values` disagree
/// ([`Flags::BETA_DISAGREES`]). Never while the filter has a standing flag raised (no input,
/// restarted, gated, low confidence, ...: any but `PREDICTED`) or has not run (airspeed 0).
/// Integer arithmetic: µrad to millidegrees as `µrad · 180,000 / 3,141,593`.
pub fn beta_disagrees_with_filter(values: &FeatureValues, beta_mdeg: i32) -> bool {
    if !values.filter_clear() {
        return false;
    }
    let mdeg = crate::features::urad_to_mdeg;
    let diff = i64::from(beta_mdeg)
        .saturating_sub(mdeg(i64::from(values.get(Feature::FilterBeta))))
        .saturating_abs();
    // The multiple of σ is taken in µrad, before the conversion truncates.
    let sigmas = i64::from(values.get(Feature::FilterSigmaBeta))
        .saturating_abs()
        .saturating_mul(BETA_CROSSCHECK_SIGMAS);
    diff > BETA_CROSSCHECK_MIN_MDEG.max(mdeg(sigmas))
}

/// [`Flags::UNCERTAIN`] is raised above this α 1σ, millidegrees: a quarter of the 2° α error a
/// flight-control computer would act on. Not fitted to any flight.
pub const UNCERTAIN_ALPHA_MDEG: u16 = 500;

/// ... and above this β 1σ: a quarter of 1° β.
pub const UNCERTAIN_BETA_MDEG: u16 = 250;

/// With [`Flags::GYRO_DISAGREES`] each computed angle's 1σ is at least its `UNCERTAIN` limit
/// plus this, millidegrees: the 1σ's terms were fitted on flights without a gyro in error (the
/// flag is raised on none of them), and the networks read the gyro as it is; a 0.2 rad/s pitch
/// gyro bias moved the F-16's α by up to 0.85° without the check (docs/results/dropout.md).
pub const GYRO_SIGMA_FLOOR: u16 = 1;

/// After a computed angle's 1σ was last above its limit, [`Flags::UNCERTAIN`] stays raised for
/// this many more frames in which that angle is computed (2 s at 20 Hz), whatever its 1σ: set at
/// once, cleared late. The networks' errors stay correlated for seconds (a lag behind a fast α
/// change near the stall), so a 1σ that has just come back under the limit does not yet mean the
/// error has. Measured on the validation flights of `large` with the shipped estimator: frames
/// with α off by more than 2° or β by more than 1° and no flag, against the share of frames
/// flagged `UNCERTAIN`, for holds of 0, 20, 30, 40, 50 and 60 frames: 16, 9, 1, 1, 1, 1 frames
/// and 8.9, 11.0, 11.6, 12.0, 12.3, 12.7 % (docs/filter.md). One constant for every aircraft: 40
/// was chosen on an earlier 1σ fit, and with the current one 30 and 40 leave the same one frame.
pub const UNCERTAIN_HOLD_FRAMES: u8 = 40;

/// One angle's [`Flags::UNCERTAIN`]: raised at once when its 1σ goes above the limit, lowered
/// a number of frames ([`UNCERTAIN_HOLD_FRAMES`]) after it last was.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UncertainHold {
    /// Frames left for which the flag stays raised with the 1σ at or under the limit.
    left: u8,
}

impl UncertainHold {
    /// Whether this frame's computed angle, of 1σ `sigma_mdeg`, raises `UNCERTAIN`, held for
    /// `hold_frames` after the 1σ was last above `limit_mdeg`. Called once per frame in which the
    /// angle is computed (a held angle neither raises it nor counts).
    pub fn uncertain(&mut self, sigma_mdeg: u16, limit_mdeg: u16, hold_frames: u8) -> bool {
        if above_limit(sigma_mdeg, limit_mdeg) {
            self.left = hold_frames;
            true
        } else if let Some(left) = self.left.checked_sub(1) {
            self.left = left;
            true
        } else {
            false
        }
    }
}

/// Whether a 1σ raises [`Flags::UNCERTAIN`]: a computed angle's (not [`SIGMA_UNKNOWN`]) above
/// `limit`.
pub fn above_limit(sigma_mdeg: u16, limit_mdeg: u16) -> bool {
    sigma_mdeg != SIGMA_UNKNOWN && sigma_mdeg > limit_mdeg
}

/// A model and what [`Estimator::step`] asks of it every frame, worked out once (both are folds
/// over its feature list).
#[derive(Clone, Copy)]
struct Model<'m> {
    net: &'m dyn AngleNet,
    sources: u32,
    lags: u8,
    reads_filter: bool,
    /// Its turbulence envelope (judged only if it reads the filter).
    turbulence: TurbulenceEnvelope,
}

impl<'m> Model<'m> {
    fn new(net: &'m dyn AngleNet) -> Self {
        let reads_filter = net.features().iter().any(|f| f.needs_filter());
        Model {
            net,
            sources: net.sources(),
            lags: net.lags(),
            reads_filter,
            turbulence: net.turbulence(),
        }
    }
}

/// The 20 Hz estimator: both cascades plus the per-channel health state.
pub struct Estimator<'m> {
    alpha: Option<Model<'m>>,
    beta: Option<Model<'m>>,
    last_alpha: Option<(i32, i32)>,
    last_beta: Option<(i32, i32)>,
    /// Past frames for the deltas, and the air-data filter when a model reads its outputs.
    state: FeatureState,
    /// The 1σ terms of α and β of the last step ([`Estimator::sigma_terms`]).
    terms: [[u32; uncertainty::TERMS]; 2],
    /// The running mean of each angle's disagreement with the filter.
    slow: [uncertainty::SlowMean; 2],
    /// Per angle, how long `UNCERTAIN` stays raised ([`UNCERTAIN_HOLD_FRAMES`]).
    uncertain_hold: [UncertainHold; 2],
    /// [`UNCERTAIN_HOLD_FRAMES`] unless [`Estimator::with_uncertain_hold`] says otherwise.
    uncertain_hold_frames: u8,
}

impl<'m> Estimator<'m> {
    pub fn new(alpha: &'m dyn AngleNet, beta: &'m dyn AngleNet) -> Self {
        Self::with(Some(alpha), Some(beta))
    }

    fn with(alpha: Option<&'m dyn AngleNet>, beta: Option<&'m dyn AngleNet>) -> Self {
        let (alpha, beta) = (alpha.map(Model::new), beta.map(Model::new));
        let needs_filter = |m: Option<Model>| m.is_some_and(|m| m.reads_filter);
        Estimator {
            alpha,
            beta,
            last_alpha: None,
            last_beta: None,
            state: FeatureState::new(needs_filter(alpha) || needs_filter(beta)),
            terms: [[0; uncertainty::TERMS]; 2],
            slow: [uncertainty::SlowMean::default(); 2],
            uncertain_hold: [UncertainHold::default(); 2],
            uncertain_hold_frames: UNCERTAIN_HOLD_FRAMES,
        }
    }

    /// The compiled-in model, or an estimator that flags `NO_MODEL` on every step if this build has none.
    pub fn shipped() -> Estimator<'static> {
        #[cfg(estimator_weights)]
        {
            Estimator::new(&crate::model::ALPHA, &crate::model::BETA)
        }
        #[cfg(not(estimator_weights))]
        {
            Estimator::with(None, None)
        }
    }

    /// The smallest sensor suite whose frames carry everything the models read (`None` without a
    /// model): what a sender must deliver to this estimator.
    pub fn suite(&self) -> Option<crate::Suite> {
        let (Some(a), Some(b)) = (self.alpha, self.beta) else {
            return None;
        };
        crate::Suite::covering(a.sources | b.sources)
    }

    /// Multiply-accumulates per step.
    pub fn macs(&self) -> usize {
        let macs = |m: Option<Model>| m.map_or(0, |m| m.net.macs());
        macs(self.alpha).saturating_add(macs(self.beta))
    }

    /// The same estimator with `UNCERTAIN` held for `frames` instead of [`UNCERTAIN_HOLD_FRAMES`]
    /// (0: raised exactly when a 1σ is above its limit). For measuring the choice
    /// (`trainer eval --uncertain-hold`); the firmware keeps the default.
    pub fn with_uncertain_hold(mut self, frames: u8) -> Self {
        self.uncertain_hold_frames = frames;
        self
    }

    /// Forgets health history, past frames and held values (e.g. after a long link outage).
    pub fn reset(&mut self) {
        *self = Self::with(self.alpha.map(|m| m.net), self.beta.map(|m| m.net))
            .with_uncertain_hold(self.uncertain_hold_frames);
    }

    /// The 1σ terms of α and β in the last step (`[alpha, beta]`, each in
    /// [`uncertainty::Term::ALL`] order; zero for an angle that was not computed): what
    /// `trainer fit-sigma` fits the weights on.
    pub fn sigma_terms(&self) -> [[u32; uncertainty::TERMS]; 2] {
        self.terms
    }

    pub fn step(&mut self, frame: &SensorFrame) -> Estimate {
        let mut e = Estimate {
            seq: frame.seq,
            time_ms: frame.time_ms,
            ..Estimate::default()
        };
        self.terms = [[0; uncertainty::TERMS]; 2];
        let (Some(alpha), Some(beta)) = (self.alpha, self.beta) else {
            e.flags.0 = Flags::NO_MODEL | Flags::NO_ESTIMATE;
            return e;
        };
        let values = self.state.next(frame);
        let health = values.health;
        let diverged = values.filter_flags
            & (filter::flags::GATED | filter::flags::PREDICTED | filter::flags::RESTARTED)
            != 0;
        let mut flags = 0u16;
        let mut angle = |m: Model,
                         last: &mut Option<(i32, i32)>,
                         held_flag: u16,
                         fallback: bool|
         -> (i32, i32) {
            // Sources the features could not use (a channel the EGI filled in is usable): why.
            let bad = m.sources & !values.usable;
            let invalid = bad & !frame.valid != 0;
            let is_stuck = bad & health.stuck != 0;
            let saturated = bad & health.saturated != 0;
            if invalid {
                flags |= Flags::INVALID_INPUT;
            }
            if is_stuck {
                flags |= Flags::STUCK_SENSOR;
            }
            if saturated {
                flags |= Flags::SATURATED;
            }
            if bad != 0 {
                flags |= held_flag;
                return match *last {
                    Some(v) => v,
                    None => {
                        flags |= Flags::NO_ESTIMATE;
                        (0, 0)
                    }
                };
            }
            let (mut mid, mut out, clamped) = m.net.run(&values);
            if clamped {
                flags |= Flags::OUT_OF_ENVELOPE;
            }
            if m.lags & values.short_lags != 0 {
                flags |= Flags::HISTORY_SHORT;
            }
            if m.reads_filter && diverged {
                flags |= Flags::FILTER_DIVERGED;
            }
            // Held filter outputs (no input this step, or a restart) are not judged again.
            let turbulent = m.reads_filter
                && values.filter_fresh()
                && m.turbulence.exceeded(
                    values.get(Feature::FilterAirspeed),
                    values.get(Feature::FilterTurbulence),
                );
            if turbulent {
                flags |= Flags::TURBULENCE;
            }
            if fallback
                && clamped
                && m.reads_filter
                && !turbulent
                && let Some((w, a)) = filter_alpha_fallback(&values)
            {
                (mid, out) = (w, a);
                flags |= Flags::ALPHA_FROM_FILTER;
            }
            if m.sources & values.substituted != 0 {
                flags |= Flags::GPS_SUBSTITUTED;
            }
            if m.sources & values.gyro_disagrees != 0 {
                flags |= Flags::GYRO_DISAGREES;
            }
            *last = Some((mid, out));
            (mid, out)
        };
        // α may take the filter's where the aircraft's description allows it; β never.
        let alpha_fallback = crate::aircraft::AIRCRAFT.estimator.alpha_from_filter;
        (e.w_aero_mms, e.alpha_mdeg) = angle(
            alpha,
            &mut self.last_alpha,
            Flags::ALPHA_HELD,
            alpha_fallback,
        );
        (e.v_aero_mms, e.beta_mdeg) = angle(beta, &mut self.last_beta, Flags::BETA_HELD, false);
        if flags & Flags::BETA_HELD == 0
            && beta.reads_filter
            && beta_disagrees_with_filter(&values, e.beta_mdeg)
        {
            flags |= Flags::BETA_DISAGREES;
        }
        e.flags = Flags(flags);
        // The 1σ of each computed angle; a held or missing one has none.
        let weights = &crate::model::SIGMA;
        // The flags are the frame's, shared by both angles (as the flags field is): a clamp or a
        // caution of either model raises both angles' indicator terms.
        let indicators = uncertainty::Indicators {
            out_of_envelope: flags & Flags::OUT_OF_ENVELOPE != 0,
            turbulent: flags & Flags::TURBULENCE != 0,
            caution: flags & Flags::CAUTIONS != 0,
            filter_diverged: flags & Flags::FILTER_DIVERGED != 0,
        };
        let angles = [
            (
                uncertainty::Angle::Alpha,
                Flags::ALPHA_HELD,
                e.alpha_mdeg,
                &mut e.sigma_alpha_mdeg,
                UNCERTAIN_ALPHA_MDEG,
            ),
            (
                uncertainty::Angle::Beta,
                Flags::BETA_HELD,
                e.beta_mdeg,
                &mut e.sigma_beta_mdeg,
                UNCERTAIN_BETA_MDEG,
            ),
        ];
        for ((angle, held, value, sigma, limit), ((slow, terms), hold)) in angles.into_iter().zip(
            self.slow
                .iter_mut()
                .zip(self.terms.iter_mut())
                .zip(self.uncertain_hold.iter_mut()),
        ) {
            // A missing angle is held too (`NO_ESTIMATE` comes with its held flag).
            if flags & held != 0 {
                continue;
            }
            *terms = uncertainty::terms(angle, &values, value, indicators, slow.mdeg());
            *sigma = uncertainty::sigma(weights.of(angle), terms);
            if flags & Flags::GYRO_DISAGREES != 0 {
                *sigma = (*sigma).max(limit.saturating_add(GYRO_SIGMA_FLOOR));
            }
            if hold.uncertain(*sigma, limit, self.uncertain_hold_frames) {
                flags |= Flags::UNCERTAIN;
            }
            slow.track(terms);
        }
        e.flags = Flags(flags);
        e
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nn::{Dense, Output, Requant};
    use crate::{FeatureValues, History, SensorFrame};

    /// Filter features of a consistent filter: α 0.1 rad, β −0.02 rad, 150 m/s, NIS mean 0.5.
    fn consistent() -> FeatureValues {
        let mut v = FeatureValues::compute(&SensorFrame::default(), &History::new());
        v.set_filter(&filter::Output {
            alpha_rad: 0.1,
            beta_rad: -0.02,
            airspeed_mps: 150.0,
            nis_mean: 0.5,
            ..Default::default()
        });
        v
    }

    #[test]
    fn uncertain_is_a_computed_sigma_strictly_above_the_limit() {
        assert!(!above_limit(UNCERTAIN_ALPHA_MDEG, UNCERTAIN_ALPHA_MDEG));
        assert!(above_limit(UNCERTAIN_ALPHA_MDEG + 1, UNCERTAIN_ALPHA_MDEG));
        assert!(above_limit(uncertainty::SIGMA_MAX, UNCERTAIN_BETA_MDEG));
        assert!(!above_limit(SIGMA_UNKNOWN, UNCERTAIN_BETA_MDEG));
        assert!(!above_limit(0, 0));
    }

    #[test]
    fn uncertain_is_held_for_exactly_the_hold_frames_after_the_last_sigma_above_the_limit() {
        const H: u8 = UNCERTAIN_HOLD_FRAMES;
        let mut h = UncertainHold::default();
        assert!(!h.uncertain(UNCERTAIN_ALPHA_MDEG, UNCERTAIN_ALPHA_MDEG, H));
        assert!(h.uncertain(UNCERTAIN_ALPHA_MDEG + 1, UNCERTAIN_ALPHA_MDEG, H));
        for k in 0..UNCERTAIN_HOLD_FRAMES {
            assert!(h.uncertain(0, UNCERTAIN_ALPHA_MDEG, H), "frame {k} after");
        }
        assert!(!h.uncertain(0, UNCERTAIN_ALPHA_MDEG, H));
        // A 1σ above the limit again restarts the hold; an unknown 1σ is never above it.
        assert!(h.uncertain(u16::MAX - 1, UNCERTAIN_ALPHA_MDEG, H));
        for _ in 0..10 {
            assert!(h.uncertain(0, UNCERTAIN_ALPHA_MDEG, H));
        }
        assert!(h.uncertain(UNCERTAIN_ALPHA_MDEG + 1, UNCERTAIN_ALPHA_MDEG, H));
        for _ in 0..UNCERTAIN_HOLD_FRAMES {
            assert!(h.uncertain(SIGMA_UNKNOWN, UNCERTAIN_ALPHA_MDEG, H));
        }
        assert!(!h.uncertain(SIGMA_UNKNOWN, UNCERTAIN_ALPHA_MDEG, H));
        // A hold of 0 frames: raised exactly when the 1σ is above the limit.
        let mut h = UncertainHold::default();
        assert!(h.uncertain(UNCERTAIN_ALPHA_MDEG + 1, UNCERTAIN_ALPHA_MDEG, 0));
        assert!(!h.uncertain(UNCERTAIN_ALPHA_MDEG, UNCERTAIN_ALPHA_MDEG, 0));
    }

    #[test]
    fn a_reset_ends_a_running_hold_and_keeps_the_hold_length() {
        let mut e = Estimator::with(None, None).with_uncertain_hold(7);
        assert!(e.uncertain_hold[0].uncertain(UNCERTAIN_ALPHA_MDEG + 1, UNCERTAIN_ALPHA_MDEG, 7));
        assert_ne!(e.uncertain_hold[0], UncertainHold::default());
        e.reset();
        assert_eq!(e.uncertain_hold, [UncertainHold::default(); 2]);
        assert_eq!(e.uncertain_hold_frames, 7);
        assert_eq!(
            Estimator::with(None, None).uncertain_hold_frames,
            UNCERTAIN_HOLD_FRAMES
        );
    }

    #[test]
    fn beta_disagreement_needs_two_degrees_three_sigma_and_an_unflagged_filter() {
        // Filter β −0.02 rad = −1145.9 mdeg → −1145 (truncated); 1σ 0 → the 2° floor rules.
        let v = consistent();
        assert!(!beta_disagrees_with_filter(&v, -1145 + 2000));
        assert!(beta_disagrees_with_filter(&v, -1145 + 2001));
        assert!(!beta_disagrees_with_filter(&v, -1145 - 2000));
        assert!(beta_disagrees_with_filter(&v, -1145 - 2001));
        // A 1σ of 0.02 rad: 3σ = 0.06 rad = 3437.7 mdeg → 3437 is the bound.
        let mut w = v;
        w.raw[Feature::FilterSigmaBeta.index()] = 20_000;
        assert!(!beta_disagrees_with_filter(&w, -1145 + 3437));
        assert!(beta_disagrees_with_filter(&w, -1145 + 3438));
        // Any filter flag, or no filter, and there is no judgement; but a step without an update
        // leaves the filter's prediction to judge by.
        for bit in 0..8 {
            let mut f = v;
            f.filter_flags = 1 << bit;
            assert_eq!(
                beta_disagrees_with_filter(&f, 30_000),
                f.filter_flags == filter::flags::PREDICTED,
                "filter flag bit {bit}"
            );
        }
        let none = FeatureValues::compute(&SensorFrame::default(), &History::new());
        assert!(!beta_disagrees_with_filter(&none, 30_000));
        // Extreme inputs do not overflow.
        let mut x = v;
        x.raw[Feature::FilterBeta.index()] = i32::MIN;
        x.raw[Feature::FilterSigmaBeta.index()] = i32::MIN;
        assert!(beta_disagrees_with_filter(&x, i32::MAX));
        assert!(beta_disagrees_with_filter(&x, i32::MIN));
        let filter_mdeg = (i64::from(i32::MIN) * 180_000 / 3_141_593) as i32;
        assert!(!beta_disagrees_with_filter(&x, filter_mdeg));
    }

    #[test]
    fn the_filter_stands_in_for_alpha_only_while_it_is_unflagged_and_consistent() {
        let v = consistent();
        // α 0.1 rad = 5.729578°; w = 150 m/s · sin 0.1 · cos 0.02 = 14.9721 m/s.
        assert_eq!(filter_alpha_fallback(&v), Some((14_972, 5_730)));
        // Every filter flag on its own forbids it.
        for bit in 0..8 {
            let mut f = v;
            f.filter_flags = 1 << bit;
            assert_eq!(filter_alpha_fallback(&f), None, "filter flag bit {bit}");
        }
        // The NIS mean one LSB below the bound and at it is fine, one LSB above it is not.
        let mut f = v;
        f.raw[Feature::FilterNisMean.index()] = FALLBACK_NIS_MEAN_MAX - 1;
        assert!(filter_alpha_fallback(&f).is_some());
        f.raw[Feature::FilterNisMean.index()] = FALLBACK_NIS_MEAN_MAX;
        assert!(filter_alpha_fallback(&f).is_some());
        f.raw[Feature::FilterNisMean.index()] = FALLBACK_NIS_MEAN_MAX + 1;
        assert_eq!(filter_alpha_fallback(&f), None);
        // No filter (its features read 0): nothing to stand in with.
        let none = FeatureValues::compute(&SensorFrame::default(), &History::new());
        assert_eq!(filter_alpha_fallback(&none), None);
    }

    type TinyNet = CascadeNet<Output<2, 1>, Output<3, 1>, 2, 3>;

    /// A one-layer cascade reading `first` and the filter's air speed: part 1 `w1·x + b1`, part 2
    /// `w2·(x, mid) + b2`, unscaled; `hi` bounds both inputs' envelope.
    fn tiny_net(first: Feature, hi: i32, (w1, b1): (i8, i32), (w2, b2): (i8, i32)) -> TinyNet {
        let one = Norm {
            center: 0,
            mult: 1 << 20,
            shift: 30,
        };
        CascadeNet {
            features: [first, Feature::FilterAirspeed],
            norm: [one; 2],
            envelope: [Envelope { lo: -hi, hi }; 2],
            part1: Output(Dense::new([[w1, w1]], [b1], [Requant::ONE])),
            mid_norm: one,
            part2: Output(Dense::new([[w2, w2, w2]], [b2], [Requant::ONE])),
            out_range: Envelope::ANY,
            turbulence: TurbulenceEnvelope::ANY,
            lift_scale: Envelope::ANY,
        }
    }

    /// Reads the filter's α and air speed.
    fn filter_net(hi: i32) -> TinyNet {
        tiny_net(Feature::FilterAlpha, hi, (1, 7), (1, 3))
    }

    /// Reads the filter's β and air speed and answers `beta_mdeg` whatever they are.
    fn constant_beta_net(beta_mdeg: i32) -> TinyNet {
        tiny_net(Feature::FilterBeta, i32::MAX, (0, 0), (0, beta_mdeg))
    }

    #[test]
    fn a_beta_that_parts_from_a_consistent_filter_is_flagged_and_kept() {
        // 60 s of a turn at β 1° whose IMU reads the filter's own force model.
        let frames: Vec<SensorFrame> = crate::filter::tests::consistent_frames(1200).collect();
        let alpha = filter_net(i32::MAX);
        let run = |beta_mdeg: i32| {
            let b = constant_beta_net(beta_mdeg);
            let mut e = Estimator::new(&alpha, &b);
            let mut state = FeatureState::new(true);
            frames
                .iter()
                .map(|f| (e.step(f), state.next(f)))
                .collect::<Vec<_>>()
        };
        // A β network that agrees with the filter (the turn flies 1°): never.
        assert!(
            run(1_000)
                .iter()
                .all(|(e, _)| !e.flags.has(Flags::BETA_DISAGREES))
        );
        // One 4° off: flagged on exactly the frames the filter is unflagged, which is most of the
        // flight once it has converged; β stays the network's.
        let mut flagged = 0;
        for (k, (e, values)) in run(5_000).iter().enumerate() {
            assert_eq!(e.beta_mdeg, 5_000, "frame {k}");
            let filter_ok = values.filter_clear();
            assert_eq!(e.flags.has(Flags::BETA_DISAGREES), filter_ok, "frame {k}");
            flagged += usize::from(filter_ok);
        }
        assert!(flagged > 600, "only {flagged} frames flagged");
    }

    #[test]
    fn an_angle_whose_network_reads_a_gyro_in_error_is_flagged() {
        // The consistent turn, its yaw gyro 0.2 rad/s off from frame 600 (30 s) to 800: β's
        // network reads it (α's reads the filter, which reads the gyros too). The air-data
        // filter's gyro check passes its gate a few frames into the error and keeps the flag up
        // about a second after it.
        let error = 0.2f32.max(2.0 * filter::CONFIG.gyro_gate_rps);
        let frames: Vec<SensorFrame> = crate::filter::tests::consistent_frames(1200)
            .map(|mut f| {
                if (600..800).contains(&f.seq) {
                    let lsb = Channel::GyroR.lsb() as f32;
                    if let Some(r) = f.raw.get_mut(Channel::GyroR.index()) {
                        *r += libm::roundf(error / lsb) as i32;
                    }
                }
                f
            })
            .collect();
        let alpha = filter_net(i32::MAX);
        let beta = tiny_net(Feature::Sensor(Channel::GyroR), i32::MAX, (1, 0), (1, 0));
        let mut e = Estimator::new(&alpha, &beta);
        let mut flagged = 0;
        for (k, f) in frames.iter().enumerate() {
            let out = e.step(f);
            let says = out.flags.has(Flags::GYRO_DISAGREES);
            if !(600..850).contains(&k) {
                assert!(!says, "frame {k}: no error");
            }
            if (620..800).contains(&k) {
                assert!(says, "frame {k}: the yaw gyro is in error");
            }
            if says {
                // Each 1σ just above its limit at least, so the frame is UNCERTAIN too.
                assert!(out.sigma_alpha_mdeg > UNCERTAIN_ALPHA_MDEG, "frame {k}");
                assert!(out.sigma_beta_mdeg > UNCERTAIN_BETA_MDEG, "frame {k}");
                assert!(out.flags.has(Flags::UNCERTAIN), "frame {k}");
            }
            flagged += usize::from(says);
        }
        assert!(flagged > 180, "flagged on {flagged} frames");
    }

    /// Where the aircraft's description allows it (`estimator.alpha_from_filter`); where it does
    /// not, the network's α stands, flagged `OUT_OF_ENVELOPE`, and no frame takes the filter's.
    #[test]
    fn an_alpha_network_out_of_its_envelope_gives_way_to_a_consistent_filter() {
        // 60 s of a turn whose IMU reads the filter's own force model.
        let frames: Vec<SensorFrame> = crate::filter::tests::consistent_frames(1200).collect();
        let inside = filter_net(i32::MAX);
        let outside = filter_net(1);
        let run = |a: &TinyNet, b: &TinyNet| {
            let mut e = Estimator::new(a, b);
            frames.iter().map(|f| e.step(f)).collect::<Vec<_>>()
        };
        // Inside its envelope the network answers on every frame.
        for (k, e) in run(&inside, &outside).iter().enumerate() {
            assert!(!e.flags.has(Flags::ALPHA_FROM_FILTER), "frame {k}");
        }
        // Outside it, the filter takes over α once it has proven consistent (its NIS mean starts at
        // the gate, 25, and falls at most by a factor e every 2 s: about 100 frames to reach 2),
        // and β never.
        let out = run(&outside, &outside);
        if !crate::aircraft::AIRCRAFT.estimator.alpha_from_filter {
            let mut state = FeatureState::new(true);
            for (k, (e, f)) in out.iter().zip(&frames).enumerate() {
                let (w, a, _) = outside.run(&state.next(f));
                assert!(e.flags.has(Flags::OUT_OF_ENVELOPE), "frame {k}");
                assert!(!e.flags.has(Flags::ALPHA_FROM_FILTER), "frame {k}");
                assert_eq!(
                    (e.w_aero_mms, e.alpha_mdeg),
                    (w, a),
                    "α is the network's, frame {k}"
                );
            }
            return;
        }
        let mut state = FeatureState::new(true);
        let mut from_filter = 0;
        for (k, (e, f)) in out.iter().zip(&frames).enumerate() {
            let values = state.next(f);
            assert!(e.flags.has(Flags::OUT_OF_ENVELOPE), "frame {k}");
            if e.flags.has(Flags::ALPHA_FROM_FILTER) {
                from_filter += 1;
                assert!(k >= 100, "frame {k}");
                let (w, a) = filter_alpha_fallback(&values).unwrap();
                assert_eq!((e.w_aero_mms, e.alpha_mdeg), (w, a), "frame {k}");
                // The turn's α (6° but for a slow aircraft).
                let world_mdeg =
                    (crate::filter::tests::world_alpha_rad().to_degrees() * 1e3) as i32;
                assert!(
                    (e.alpha_mdeg - world_mdeg).abs() < 300,
                    "frame {k}: {}",
                    e.alpha_mdeg
                );
                assert_eq!(
                    (e.v_aero_mms, e.beta_mdeg),
                    (outside.run(&values).0, outside.run(&values).1),
                    "β is the network's, frame {k}"
                );
            } else {
                assert_eq!(filter_alpha_fallback(&values), None, "frame {k}");
            }
        }
        assert!(
            from_filter > 600,
            "only {from_filter} frames from the filter"
        );
    }
}
