//! Model-based air-data filter: an extended Kalman filter that estimates the wind vector and a lift
//! scale from EGI kinematics and the aircraft's aerodynamic model, and from them α and β.
//!
//! # Why this works
//! With attitude and the GPS/INS velocity, the body-axis air velocity is exact once the wind is
//! known: `v_air = C_bn · (v_ground − wind)`, α = atan2(w, u), β = asin(v / |v|). The wind is what is
//! unknown, and the specific force tells it: the accelerometers measure the aerodynamic force over
//! the mass, and the model ([`crate::aero`], extracted from the JSBSim F-16 the plant flies) predicts
//! that force from α, β, dynamic pressure, rates and surfaces. A wrong wind gives a wrong α and β,
//! hence a normal and lateral specific force that disagree with the IMU, and the filter corrects it.
//! Changes of heading and attitude make every wind component observable over time; in long straight
//! flight the along-track component is not, which the covariance shows and the flags report.
//!
//! # State (8, or 9 with the trailing-edge lift scale; [`STATES`])
//! `[mean wind N, E, D; gust N, E, D; lift scale k]`, m/s and 1. The mean wind is a random walk; the
//! gust a first-order Gauss–Markov process (turbulence changes α within a second; the model force sees
//! it at once); `k` multiplies the predicted force and takes up what the mass from the fuel gauge and
//! the model get wrong (≈ 1). Where the description says so, a side-force scale `k_y` on the
//! lateral force (`filter.learn_scales`; held at 1 otherwise or with `ESTIMATOR_FILTER_SIDE_SCALE=off`)
//! and a trailing-edge lift scale `s` (`filter.te_lift_sigma0`, `filter.te_lift_psd`; [`LEARNS_TE_LIFT`]):
//! the lift of the model's terms that read the aileron, the flaperon mix or the flap is `(1 + s)`
//! times the model's. The ailerons move in every roll and every gust, so `s` is observable apart
//! from the wind (docs/filter.md).
//!
//! # Measurement (2)
//! Body y and z specific force at the centre of gravity (IMU reading minus the lever-arm terms),
//! compared with `k · q̄ · S · C_{Y,Z} / m`. The axial force is not used: thrust is not measured. The
//! model is evaluated with the inputs of the instant the accelerometers represent: the surface
//! positions pass the same anti-alias filter as the accelerometers, and the EGI attitude and
//! velocity are interpolated [`Config::accel_delay_s`] back between frames. The
//! Jacobian is a forward difference of the model in the body air velocity, chained through the
//! attitude matrix. A normalised innovation above [`Config::gate`] is not used.
//!
//! # Outputs and trust
//! α and β are kinematic, at the current frame, with the estimated wind (mean + gust); their 1σ comes
//! from the wind covariance. [`flags`] say when not to trust them: inputs missing, innovations gated
//! for a while, covariance blow-up (the filter then restarts), confidence worse than a limit
//! (including the unobservable wind of long straight flight).
//!
//! f32, no heap, no panics; NaN or Inf never leaves: a step whose arithmetic is not finite restarts
//! the filter and says so.

use nalgebra::{Matrix2, Matrix3, SMatrix, SVector, Vector2, Vector3};

use crate::aero::{self, AirState, MODEL, Surfaces, Unsteady};
use crate::aircraft::AIRCRAFT;
use crate::channels::{Channel, SUBSAMPLES, SensorFrame, Subsamples, Suite};

/// Whether the build's filter has a trailing-edge lift scale, a ninth state: the description's
/// `filter.te_lift_sigma0` or `filter.te_lift_psd` above 0, or a build with
/// `ESTIMATOR_FILTER_TE_LIFT=on` (build.rs), whose state the description's prior still holds at 0
/// unless it says otherwise; never in a build with `ESTIMATOR_FILTER_TE_LIFT=off`.
pub const LEARNS_TE_LIFT: bool = !cfg!(filter_no_te_lift)
    && (AIRCRAFT.filter.te_lift_sigma0 > 0.0
        || AIRCRAFT.filter.te_lift_psd > 0.0
        || cfg!(filter_te_lift));

/// Number of states: mean wind (3), gust (3), lift scale, side-force scale, and the trailing-edge
/// lift scale where the description learns it ([`LEARNS_TE_LIFT`]).
pub const STATES: usize = if LEARNS_TE_LIFT { 9 } else { 8 };
const K: usize = 6;
const KY: usize = 7;
const TE: usize = 8;

type Vec7 = SVector<f32, STATES>;
type Mat7 = SMatrix<f32, STATES, STATES>;
type Mat27 = SMatrix<f32, 2, STATES>;

/// Output flags.
pub mod flags {
    /// The inputs the filter needs (EGI attitude and velocity, IMU, surfaces, altitude) were not all
    /// valid this step: prediction only, outputs held from the last good step.
    pub const NO_INPUT: u8 = 1 << 0;
    /// Innovations failed the gate for [`super::Config::gate_run`] steps in a row: the model and
    /// the sensors disagree (model error, sensor fault, unmodelled configuration).
    pub const GATED: u8 = 1 << 1;
    /// The covariance blew up or a step was not finite: the filter restarted this step.
    pub const RESTARTED: u8 = 1 << 2;
    /// 1σ of α or β above [`super::Config::max_sigma_rad`]: too uncertain to use (start-up, long
    /// straight flight with an unobservable wind component, after an outage).
    pub const LOW_CONFIDENCE: u8 = 1 << 3;
    /// Airspeed below [`super::Config::min_airspeed_mps`]: α and β are not defined well enough.
    pub const SLOW: u8 = 1 << 4;
    /// GPS altitude missing: the altitude (for air density and Mach) is the last GPS altitude
    /// carried on by the EGI's vertical velocity, for at most [`super::MAX_ALT_COAST_S`].
    pub const ALT_COASTED: u8 = 1 << 5;
    /// The outputs are the prediction alone, with every input present: this step's innovation
    /// failed [`super::Config::gate`] (from the first such step on; [`GATED`] waits for
    /// [`super::Config::gate_run`] of them), or no update was made (the first step after a start
    /// or an outage, or after a restart that dropped the step's input, has no previous step to
    /// time the model by; or the update's arithmetic failed). With [`RESTARTED`] the outputs are
    /// the held ones instead. Not a standing condition: [`clear`] lets it pass (docs/filter.md).
    pub const PREDICTED: u8 = 1 << 6;
    /// The y or z specific force the accelerometers measure disagrees with the one the EGI's
    /// velocity change and gravity give ([`super::Config::kinematic_gate_mps2`]): a channel in
    /// error, kept out of the update this step ([`PREDICTED`] too, and [`GATED`] once the run is
    /// [`super::Config::gate_run`] steps long). The check's running mean outlasts an outage, a
    /// restart and a start again, and so do this flag (from the first step with inputs) and the
    /// run.
    pub const DISAGREES: u8 = 1 << 7;

    /// No standing flag: every flag clear but [`PREDICTED`], a single step's. The filter's outputs
    /// may stand beside a network's and count as trusted; the estimator flags a [`PREDICTED`]
    /// step on its own (`FILTER_DIVERGED`).
    pub const fn clear(flags: u8) -> bool {
        flags & !PREDICTED == 0
    }
}

/// Tuning and installation constants.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Random-walk power spectral density of the mean wind, (m/s)²/s, N, E, D.
    pub mean_wind_psd: [f32; 3],
    /// Initial 1σ of the mean wind, m/s, N, E, D.
    pub mean_wind_sigma0: [f32; 3],
    /// Gust: correlation time, s, and steady-state 1σ, m/s.
    pub gust_tau_s: f32,
    pub gust_sigma: f32,
    /// Lift scale: random-walk PSD (1/s) and initial 1σ. It scales the whole model force.
    pub lift_scale_psd: f32,
    pub lift_scale_sigma0: f32,
    /// Side-force scale, on top of the lift scale on the lateral force only: random-walk PSD
    /// (1/s) and initial 1σ. Both 0 (the default) hold it at 1: the filter of seven states.
    pub side_scale_psd: f32,
    pub side_scale_sigma0: f32,
    /// Trailing-edge lift scale s: the lift of the terms reading a trailing-edge surface is
    /// (1 + s) times the model's; random-walk PSD (1/s) and initial 1σ. Both 0 hold s at 0.
    pub te_lift_psd: f32,
    pub te_lift_sigma0: f32,
    /// Measurement 1σ of the y and z specific force at the CG, m/s² (model error dominates).
    pub accel_sigma: [f32; 2],
    /// Normalised-innovation gate (χ², 2 degrees of freedom).
    pub gate: f32,
    /// Consecutive gated steps before [`flags::GATED`].
    pub gate_run: u16,
    /// IMU position from the centre of gravity, body axes (forward, right, down), m.
    pub lever_arm_m: [f32; 3],
    /// Group delay of the accelerometers' anti-alias filter, s.
    pub accel_delay_s: f32,
    /// Operating empty weight (aircraft and pilot), kg: the mass is this plus the fuel quantity.
    pub empty_mass_kg: f32,
    /// [`flags::LOW_CONFIDENCE`] above this 1σ of α or β, rad.
    pub max_sigma_rad: f32,
    /// Restart when any wind variance exceeds this, (m/s)².
    pub max_wind_var: f32,
    /// [`flags::SLOW`] below this airspeed, m/s.
    pub min_airspeed_mps: f32,
    /// Landing-gear position the force model assumes, 0 up … 1 down (no channel carries it).
    pub gear_norm: f32,
    /// Adaptive measurement noise (innovation-based covariance matching): time constant, s, of
    /// the running mean of each innovation's square, from which the measurement variance is taken
    /// as that mean less the state's share `(H P Hᵀ)ᵢᵢ`. 0 keeps [`Config::accel_sigma`] fixed.
    pub r_adapt_tau_s: f32,
    /// Bounds `[low, high]` of the adapted measurement 1σ of the y and the z specific force, as
    /// multiples of [`Config::accel_sigma`] (`[1, 1]` keeps that axis fixed).
    pub r_adapt_range: [[f32; 2]; 2],
    /// What the measurement reads from a frame's 120 Hz sub-samples, when it carries them.
    pub subsamples: SubsampleUse,
    /// Largest running mean (over [`KINEMATIC_TAU_S`]) of the y or the z specific force the
    /// accelerometers measure less the one the EGI's velocity change over the step and gravity
    /// give, m/s², above which the step makes no update ([`flags::DISAGREES`]). In flight the two
    /// differ by the sensors' errors, their timing and the lever arm (docs/filter.md); well
    /// beyond that is an accelerometer channel in error, which the update would otherwise take in
    /// as wind. 0 turns the check off.
    pub kinematic_gate_mps2: f32,
    /// Largest running mean (over [`GYRO_TAU_S`]) of a gyro's rate less the body rate the EGI's
    /// attitude change over the step gives, rad/s, above which that gyro disagrees
    /// ([`Output::gyro_disagrees`]): the filter then takes the running mean off that gyro for its
    /// model, and the estimator flags an angle whose networks read it. In flight the two differ by
    /// the EGI's output timing and the sensors' errors (docs/filter.md); well beyond that is a
    /// gyro in error. 0 turns the check off.
    pub gyro_gate_rps: f32,
}

/// Time constant of the gyro check's running mean ([`Config::gyro_gate_rps`]), s: the EGI's
/// attitude comes at 50 Hz (heading 25 Hz) with a phase of its own against the frames, so a
/// step's attitude change spans a little more or less than the step; over a second that
/// averages out to a few hundredths of a rad/s in the hardest maneuvers.
pub const GYRO_TAU_S: f32 = 1.0;

/// Time constant, s, of a disagreeing gyro's running mean once its residual has been within half
/// the gate ([`Config::gyro_gate_rps`]) for [`GYRO_RELEASE_STEPS`] steps in a row: the check lets
/// go of a gyro whose error has gone in about a quarter of [`GYRO_TAU_S`]. It applies only to a
/// gyro whose running mean is beyond the gate, one the check already holds in error.
pub const GYRO_RELEASE_TAU_S: f32 = 0.25;

/// Steps in a row (0.15 s at 20 Hz) a disagreeing gyro's residual must be within half the gate
/// before [`GYRO_RELEASE_TAU_S`] applies.
pub const GYRO_RELEASE_STEPS: u8 = 3;

/// The gyro check's share of this frame's 20 Hz gyro in a step's rate where a frame lacks the
/// gyros' sub-samples (the previous frame's takes the rest): the 6 Hz anti-alias filter delays a
/// 20 Hz reading about 0.0375 s, and the EGI's attitude change over a step is centred about
/// 0.05 s before the frame, a quarter of the way from this reading's instant to the previous
/// one's.
pub const GYRO_20HZ_SHARE: f32 = 0.75;

/// Time constant of the kinematic check's running mean ([`Config::kinematic_gate_mps2`]), s.
pub const KINEMATIC_TAU_S: f32 = 0.5;

/// How far apart in time the kinematic check's two specific forces may be, s: the EGI's velocity
/// change is the mean over a step that ends up to 0.07 s before the frame (its age and its output
/// held at 20 Hz), the accelerometers' reading lags by their anti-alias filter. The part of the
/// residual that a specific force changing at this step's rate over that time can make is taken
/// off each step's residual (a dead band as wide as that change), so that the gate can be set for
/// a steady channel error rather than for the timing of the hardest maneuvers. Equal to the frame
/// period, the band takes the whole of a reading's change over a step: an error that changes by
/// its own size every frame stays inside it (docs/filter.md).
pub const KINEMATIC_TIMING_S: f32 = 0.05;

/// The longest step the kinematic check folds into its running mean, s (two frames: one lost
/// frame). Over a longer gap the velocity change averages the acceleration over the whole gap
/// while the accelerometers read the frame's instant, and the step's mean attitude no longer
/// turns it: the running mean, and its verdict, stand as they are.
pub const KINEMATIC_MAX_DT_S: f32 = 0.1;

/// How the filter's measurement reads a frame's 120 Hz [`crate::channels::Subsamples`] (IMU and
/// surfaces, before the anti-alias filter), when the frame carries every one it needs; otherwise
/// it reads the 20 Hz channels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SubsampleUse {
    /// The 20 Hz channels (behind the 6 Hz anti-alias filter) only.
    Off,
    /// The last sub-sample: the frame instant's, behind the IMU's own lag only.
    Latest,
    /// The mean of the period's six: the Δv/Δθ of the period over its length, centred 2.5
    /// sub-samples (21 ms) back.
    Mean,
}

impl Config {
    /// The aircraft's mass for a fuel-gauge reading: the empty mass (with the pilot) plus the fuel.
    pub fn mass_kg(&self, fuel_kg: f32) -> f32 {
        self.empty_mass_kg + fuel_kg.max(0.0)
    }
}

/// The lift scale's random-walk PSD (1/s) and initial 1σ where it is learned.
pub const LEARNED_LIFT_SCALE: [f32; 2] = [1e-6, 0.05];

/// The side-force scale's random-walk PSD (1/s) and initial 1σ where it is learned (the values
/// measured in docs/filter.md, where 1e-5 and 1e-7 for the PSD score the same).
pub const LEARNED_SIDE_SCALE: [f32; 2] = [1e-6, 0.1];

/// A scale's PSD and initial 1σ that hold it at 1.
const HELD: [f32; 2] = [0.0, 0.0];

/// A scale's PSD and initial 1σ: `learned` where it is learned, [`HELD`] otherwise.
const fn prior(learned: [f32; 2], learn: bool) -> [f32; 2] {
    if learn { learned } else { HELD }
}

/// The lift scale's PSD and initial 1σ in [`CONFIG`]: learned where the aircraft's description
/// says so (`filter.learn_scales`), held at 1 otherwise.
const LIFT_SCALE: [f32; 2] = prior(LEARNED_LIFT_SCALE, AIRCRAFT.filter.learn_scales);

/// The side-force scale's PSD and initial 1σ in [`CONFIG`]: as the lift scale's, and held at 1 in
/// a build with `ESTIMATOR_FILTER_SIDE_SCALE=off` (build.rs) too.
const SIDE_SCALE: [f32; 2] = prior(
    LEARNED_SIDE_SCALE,
    AIRCRAFT.filter.learn_scales && !cfg!(filter_no_side_scale),
);

/// The filter for the build's aircraft in hil-sim's installation: the IMU lever arm, empty weight,
/// pilot and gear of its description ([`crate::aircraft`]; the F-16's, `aircraft/f16.toml`), the
/// anti-alias filter of `docs/sensors.md`. The measurement noise and the accelerometer delay are
/// tuned on the training flights of the `paper` preset, never the test flights
/// (`trainer eval-filter --split train --tune ...`, table in `docs/filter.md`).
pub const CONFIG: Config = Config {
    mean_wind_psd: [0.02, 0.02, AIRCRAFT.filter.mean_wind_down_psd],
    mean_wind_sigma0: [15.0, 15.0, AIRCRAFT.filter.mean_wind_down_sigma_mps],
    gust_tau_s: AIRCRAFT.filter.gust_tau_s,
    gust_sigma: AIRCRAFT.filter.gust_sigma_mps,
    lift_scale_psd: LIFT_SCALE[0],
    lift_scale_sigma0: LIFT_SCALE[1],
    side_scale_psd: SIDE_SCALE[0],
    side_scale_sigma0: SIDE_SCALE[1],
    te_lift_psd: AIRCRAFT.filter.te_lift_psd,
    te_lift_sigma0: AIRCRAFT.filter.te_lift_sigma0,
    accel_sigma: AIRCRAFT.filter.accel_sigma_mps2,
    gate: 25.0,
    gate_run: 20,
    lever_arm_m: AIRCRAFT.installation.imu_lever_arm_f32(),
    accel_delay_s: 0.03,
    empty_mass_kg: AIRCRAFT.mass.empty_mass_kg(),
    max_sigma_rad: AIRCRAFT.filter.max_sigma_rad,
    max_wind_var: 400.0,
    min_airspeed_mps: AIRCRAFT.filter.min_airspeed_mps as f32,
    // JSBSim's F-16 starts with the gear down and neither the generated maneuver scripts nor the
    // stock F-16 scripts retract it: every flight the plant flies is gear-down (CDgear 0.027,
    // part of the body side force at sideslip).
    gear_norm: AIRCRAFT.mass.gear_norm as f32,
    // Off: the adaptive y noise improved the filter's own β (training flights 0.162 → 0.130) but
    // cost its α (0.228 → 0.257), and the hybrid fed with it scored worse on validation (α 0.144
    // → 0.149, β 0.068 → 0.072; docs/filter.md).
    r_adapt_tau_s: 0.0,
    r_adapt_range: [[1.0, 1.0], [1.0, 1.0]],
    subsamples: SubsampleUse::Off,
    kinematic_gate_mps2: AIRCRAFT.filter.kinematic_gate_mps2,
    gyro_gate_rps: AIRCRAFT.filter.gyro_gate_rps,
};

/// One frame of what the filter reads, in SI units and radians.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Input {
    /// Time since the previous input, s.
    pub dt_s: f32,
    /// EGI roll, pitch, heading, rad.
    pub euler_rad: [f32; 3],
    /// EGI velocity over the ground, north, east, down, m/s.
    pub vel_ned_mps: [f32; 3],
    /// GPS altitude, m.
    pub alt_m: f32,
    /// Gyro p, q, r, rad/s.
    pub gyro_rps: [f32; 3],
    /// Specific force at the IMU, body x, y, z, m/s².
    pub accel_mps2: [f32; 3],
    /// Elevator, aileron, rudder, left flaperon, trailing-edge flap, speedbrake, degrees.
    pub elevator_deg: f32,
    pub aileron_deg: f32,
    pub rudder_deg: f32,
    pub flaperon_left_deg: f32,
    pub tef_deg: f32,
    pub speedbrake_deg: f32,
    /// Fuel quantity, kg.
    pub fuel_kg: f32,
    /// The gyros' mean p, q, r over the older and the newer half of the frame period, rad/s, from
    /// the frame's 120 Hz sub-samples when it carries all of them (the gyro check's); `None`
    /// without them.
    pub gyro_halves_rps: Option<[[f32; 3]; 2]>,
}

/// The channels [`Input::from_frame`] reads, as a bit mask: the `egi` suite less GPS speed (the
/// EGI velocity vector replaces it), the LEF actuator (the aero model reads the scheduled LEF,
/// computed from α and Mach) and the throttle (thrust is not modelled).
pub const NEEDED_MASK: u32 = Suite::Egi.channels()
    & !(Channel::GpsSpeed.bit() | Channel::Lef.bit() | Channel::Throttle.bit());

/// The sub-sampled channels among [`NEEDED_MASK`], as a mask of [`Subsamples::valid`] bits: the
/// IMU and every surface but the LEF actuator. All of them valid, or the 20 Hz channels.
const SUBSAMPLES_NEEDED: u16 = Subsamples::mask_of(NEEDED_MASK);

/// The gyros, p, q, r: the order of [`Input::gyro_rps`] and of the gyro check's running means.
const GYROS: [Channel; 3] = [Channel::GyroP, Channel::GyroQ, Channel::GyroR];

/// The gyros' sub-samples, as a mask of [`Subsamples::valid`] bits: the gyro check reads them
/// whenever a frame carries all three, whatever [`Config::subsamples`] says.
const GYRO_SUBSAMPLES: u16 =
    Subsamples::mask_of(Channel::GyroP.bit() | Channel::GyroQ.bit() | Channel::GyroR.bit());

impl Input {
    /// The filter's input from a sensor frame: integer channels to SI (f32), and the EGI velocity,
    /// which is the IMU point's, moved to the centre of gravity (`v_cg = v_imu − C_nb (ω × r)`).
    /// `None` if a [`NEEDED_MASK`] channel is not valid (a `table1` frame has no EGI channels).
    pub fn from_frame(
        f: &SensorFrame,
        dt_s: f32,
        lever_arm_m: [f32; 3],
        sub: SubsampleUse,
    ) -> Option<Input> {
        if f.valid & NEEDED_MASK != NEEDED_MASK {
            return None;
        }
        let fast = match sub {
            SubsampleUse::Off => None,
            _ if f.sub.valid & SUBSAMPLES_NEEDED != SUBSAMPLES_NEEDED => None,
            use_ => Some(use_),
        };
        // Channel values are below 2^24 in magnitude for any flight value, so the f32 conversion
        // is exact; the product with the LSB rounds once. A sub-sampled channel reads the last
        // sub-sample or the period's mean (six values below 2^24: the sum is exact in i64).
        let at = |k: usize, i: usize| f.sub.raw.get(k).and_then(|s| s.get(i)).copied();
        let si = |c: Channel| {
            // Only a frame whose sub-samples are read looks up the channel's position.
            let sub = fast.and_then(|u| Some((u, Subsamples::position(c)?)));
            let raw = match sub {
                Some((SubsampleUse::Latest, i)) => at(SUBSAMPLES - 1, i).unwrap_or(0) as f32,
                Some((SubsampleUse::Mean, i)) => {
                    let sum: i64 = (0..SUBSAMPLES)
                        .map(|k| i64::from(at(k, i).unwrap_or(0)))
                        .sum();
                    sum as f32 / SUBSAMPLES as f32
                }
                _ => f.get(c) as f32,
            };
            raw * c.lsb() as f32
        };
        let euler = [si(Channel::Roll), si(Channel::Pitch), si(Channel::Heading)];
        let gyro = GYROS.map(si);
        let gyro_halves_rps = (f.sub.valid & GYRO_SUBSAMPLES == GYRO_SUBSAMPLES).then(|| {
            // Three sub-samples a half, oldest first (exact sums in i64, as above).
            const HALF: usize = SUBSAMPLES / 2;
            let half = |c: Channel, skip: usize| {
                let i = Subsamples::position(c).unwrap_or(0);
                let sum: i64 = (f.sub.raw.iter().skip(skip).take(HALF))
                    .map(|s| i64::from(s.get(i).copied().unwrap_or(0)))
                    .sum();
                sum as f32 / HALF as f32 * c.lsb() as f32
            };
            [0, HALF].map(|skip| GYROS.map(|c| half(c, skip)))
        });
        let v_imu = Vector3::new(
            si(Channel::VelNorth),
            si(Channel::VelEast),
            si(Channel::VelDown),
        );
        let v_cg = v_imu - arm_velocity_ned(&c_bn(euler), gyro, lever_arm_m);
        Some(Input {
            dt_s,
            euler_rad: euler,
            vel_ned_mps: [v_cg.x, v_cg.y, v_cg.z],
            alt_m: si(Channel::GpsAlt),
            gyro_rps: gyro,
            accel_mps2: [
                si(Channel::AccelX),
                si(Channel::AccelY),
                si(Channel::AccelZ),
            ],
            elevator_deg: si(Channel::Elevator),
            aileron_deg: si(Channel::Aileron),
            rudder_deg: si(Channel::Rudder),
            flaperon_left_deg: si(Channel::Flaperon),
            tef_deg: si(Channel::Tef),
            speedbrake_deg: si(Channel::Speedbrake),
            fuel_kg: si(Channel::Fuel),
            gyro_halves_rps,
        })
    }

    fn is_finite(&self) -> bool {
        let scalars = [
            self.dt_s,
            self.alt_m,
            self.elevator_deg,
            self.aileron_deg,
            self.rudder_deg,
            self.flaperon_left_deg,
            self.tef_deg,
            self.speedbrake_deg,
            self.fuel_kg,
        ];
        scalars
            .iter()
            .chain(&self.euler_rad)
            .chain(&self.vel_ned_mps)
            .chain(&self.gyro_rps)
            .chain(&self.accel_mps2)
            .chain(self.gyro_halves_rps.iter().flatten().flatten())
            .all(|v| v.is_finite())
    }

    /// `self`'s EGI attitude, velocity and altitude moved `back` (0…1) of the way toward `prev`
    /// (heading along the short arc); the surfaces stay.
    fn toward(&self, prev: &Input, back: f32) -> Input {
        let l = |a: f32, b: f32| a + (b - a) * back;
        let l3 = |a: [f32; 3], b: [f32; 3]| [l(a[0], b[0]), l(a[1], b[1]), l(a[2], b[2])];
        let mut out = *self;
        let dpsi = wrap_pi(prev.euler_rad[2] - self.euler_rad[2]);
        out.euler_rad = [
            l(self.euler_rad[0], prev.euler_rad[0]),
            l(self.euler_rad[1], prev.euler_rad[1]),
            self.euler_rad[2] + dpsi * back,
        ];
        out.vel_ned_mps = l3(self.vel_ned_mps, prev.vel_ned_mps);
        out.alt_m = l(self.alt_m, prev.alt_m);
        // The surface positions come through the same anti-alias path as the accelerometers
        // (docs/sensors.md): they already describe the accelerometers' instant.
        out
    }
}

/// What the filter reports each step.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Output {
    pub alpha_rad: f32,
    pub beta_rad: f32,
    /// Estimated wind (mean + gust), north, east, down, m/s (the air mass's velocity).
    pub wind_ned_mps: [f32; 3],
    /// True airspeed, m/s.
    pub airspeed_mps: f32,
    /// Lift scale (≈ 1).
    pub lift_scale: f32,
    /// Side-force scale (1 unless [`Config::side_scale_sigma0`] lets it move).
    pub side_scale: f32,
    /// Trailing-edge lift scale s (0 unless the filter learns it, [`LEARNS_TE_LIFT`]).
    pub te_lift: f32,
    /// 1σ of α and β from the covariance, rad.
    pub sigma_alpha_rad: f32,
    pub sigma_beta_rad: f32,
    /// Normalised innovation squared of this step's measurement (0 when none).
    pub nis: f32,
    /// Running mean of the NIS over [`NIS_TAU_S`] (steps with a measurement only). A consistent
    /// filter averages the measurement's degrees of freedom, 2; model or sensor trouble and
    /// turbulence the model does not follow push it up. It starts at [`Config::gate`] after a
    /// start, a restart or a step without inputs (the held output of that step keeps the old
    /// value), so the filter proves consistency again rather than assume it.
    pub nis_mean: f32,
    /// Turbulence index, rad: the RMS over [`TURBULENCE_TAU_S`] of the frame-to-frame change of
    /// the estimated wind over the airspeed (the angle the air mass turned the relative wind by
    /// between two 20 Hz frames), see [`AirDataFilter::step`]. 0 after a start or restart; held,
    /// not updated, for [`TURBULENCE_SETTLE_STEPS`] after one and after a step without inputs.
    /// Until the running mean has seen [`TURBULENCE_TAU_S`] of changes it is their mean so far,
    /// not a mean that starts from calm air: the index does not read low in the seconds after a
    /// start or a restart in turbulence.
    pub turbulence_rad: f32,
    /// [`flags`].
    pub flags: u8,
    /// The gyros that disagree with the EGI ([`Config::gyro_gate_rps`]) as they stand after this
    /// step, as channel bits ([`Channel::bit`] of `GyroP`, `GyroQ`, `GyroR`): the check's running
    /// mean outlasts an outage, a restart and a start again, as the kinematic check's does.
    pub gyro_disagrees: u32,
}

/// The filter.
#[derive(Clone, Debug)]
pub struct AirDataFilter {
    cfg: Config,
    x: Vec7,
    p: Mat7,
    prev: Option<Input>,
    /// The NED → body matrix of `prev`'s attitude, set with it (the kinematic check's): kept, not
    /// derived again, as computing it costs the 20 Hz step about 8,000 instructions; carried
    /// inside `prev` as one value it is copied with `prev` every step (the F-16's 20-minute flight
    /// step max / median 172,515 / 162,600 against 170,751 / 162,518, `scripts/hil --json`).
    prev_cbn: Matrix3<f32>,
    gated_run: u16,
    last: Output,
    /// Altitude of the last step (GPS or coasted), m, and seconds coasted since the last GPS one.
    alt: Option<(f32, f32)>,
    /// The turbulence index's running mean square, rad² (the previous wind is `last`'s), started
    /// at 0 ...
    turb_ms: f32,
    /// ... and the running mean of 1 over the same steps, started at 0 as well: `turb_ms /
    /// turb_weight` is the mean of the squares seen since the start or restart, weighted as the
    /// running mean weighs them (the startup bias of a running mean started at 0, divided out).
    turb_weight: f32,
    /// Steps with inputs still to pass before the index takes wind changes in again, after a start,
    /// a restart or a step without inputs ([`TURBULENCE_SETTLE_STEPS`]).
    turb_settle: u16,
    /// [`Output::nis_mean`]'s running mean.
    nis_mean: f32,
    /// Running mean of the y and z innovations' squares, (m/s²)² ([`Config::r_adapt_tau_s`]).
    nu_ms: [f32; 2],
    /// Time, s, of accepted updates folded into `nu_ms` since the last start, restart or step
    /// without inputs: the adapted noise applies once it reaches [`Config::r_adapt_tau_s`].
    r_adapt_age_s: f32,
    /// The model's stall latch ([`aero::Model::stall_latch`]) as the filter's α moved it.
    stall_latched: bool,
    /// Running mean of the y and z kinematic residual, m/s² ([`Config::kinematic_gate_mps2`]).
    kinematic: [f32; 2],
    /// Running mean of each gyro's rate less the EGI's, rad/s ([`Config::gyro_gate_rps`]).
    gyro: [f32; 3],
    /// Steps in a row on which each gyro's residual was within half the gate
    /// ([`GYRO_RELEASE_STEPS`]).
    gyro_agrees: [u8; 3],
}

/// Time constant of [`Output::nis_mean`], s: a few gust correlation times, so one large innovation
/// does not decide it, short enough to notice within seconds that the model stopped fitting.
pub const NIS_TAU_S: f32 = 2.0;

/// Time constant of the turbulence index's running mean square, s: long enough to average a
/// gust's random increments, short enough to follow a change of air mass within a few seconds.
pub const TURBULENCE_TAU_S: f32 = 2.0;

/// The sensor frame period the turbulence index is scaled to, s (20 Hz).
const TURBULENCE_FRAME_S: f32 = 0.05;

/// Steps (1 s at 20 Hz) the turbulence index holds after a start, a restart or an input outage:
/// the wind estimate then moves because the filter re-converges, not because the air does (a gust
/// state that decayed through an outage is re-learnt in its first updates).
pub const TURBULENCE_SETTLE_STEPS: u16 = 20;

/// Longest GPS altitude outage the filter bridges with the EGI's vertical velocity, s. The EGI's
/// velocity error (0.05 m/s class, docs/sensors.md) makes that a few metres, nothing for the air
/// density; beyond it the filter stops (no input) rather than trust an old altitude.
pub const MAX_ALT_COAST_S: f32 = 120.0;

/// One step of an exponential running mean with time constant `tau_s` over a step of `dt` s.
fn running_mean(mean: &mut f32, value: f32, dt: f32, tau_s: f32) {
    let a = dt / (tau_s + dt);
    *mean += a * (value - *mean);
}

fn wrap_pi(a: f32) -> f32 {
    let two_pi = 2.0 * core::f32::consts::PI;
    a - two_pi * libm::floorf((a + core::f32::consts::PI) / two_pi)
}

/// The velocity, NED, that the body's rotation `w` (rad/s) adds at a point `r` (body axes, m from
/// the CG): `C_nb (ω × r)`, `cbn` being the NED → body matrix. The EGI velocity is the IMU point's;
/// less this (the gyros' rates, `r` the lever arm) it is the CG's.
fn arm_velocity_ned(cbn: &Matrix3<f32>, w: [f32; 3], r: [f32; 3]) -> Vector3<f32> {
    cbn.transpose() * Vector3::from(w).cross(&Vector3::from(r))
}

/// NED → body direction-cosine matrix from roll, pitch, heading.
pub fn c_bn(euler: [f32; 3]) -> Matrix3<f32> {
    let (sf, cf) = (libm::sinf(euler[0]), libm::cosf(euler[0]));
    let (st, ct) = (libm::sinf(euler[1]), libm::cosf(euler[1]));
    let (sp, cp) = (libm::sinf(euler[2]), libm::cosf(euler[2]));
    Matrix3::new(
        ct * cp,
        ct * sp,
        -st,
        sf * st * cp - cf * sp,
        sf * st * sp + cf * cp,
        sf * ct,
        cf * st * cp + sf * sp,
        cf * st * sp - sf * cp,
        cf * ct,
    )
}

/// ISA density (kg/m³) and speed of sound (m/s) at a geometric altitude (m): troposphere and the
/// isothermal layer above it.
pub fn isa(alt_m: f32) -> (f32, f32) {
    const R_EARTH: f32 = 6_356_766.0;
    const T0: f32 = 288.15;
    const P0: f32 = 101_325.0;
    const LAPSE: f32 = -0.0065;
    const R_AIR: f32 = 287.052_87;
    const G0: f32 = 9.806_65;
    let h = R_EARTH * alt_m / (R_EARTH + alt_m);
    let t11 = T0 + LAPSE * 11_000.0;
    let expo = -G0 / (LAPSE * R_AIR);
    let (t, p) = if h < 11_000.0 {
        let t = T0 + LAPSE * h;
        (t, P0 * libm::powf(t / T0, expo))
    } else {
        let p11 = P0 * libm::powf(t11 / T0, expo);
        (t11, p11 * libm::expf(-G0 * (h - 11_000.0) / (R_AIR * t11)))
    };
    (p / (R_AIR * t), libm::sqrtf(1.4 * R_AIR * t))
}

/// The leading-edge flap the aero model reads (`fcs/lef-pos-rad`), scheduled by the aircraft's
/// flight-control system from α, Mach and the gear in flight (its description's
/// `[fcs.lef_schedule]`; the F-16's: 25° above 15° α with the gear up, 15° above 5° α, −2° above
/// Mach 0.9, else 0). The gear is up only at `gear_norm` 0, as f16.xml's switch tests it. In
/// degrees; 0 for an aircraft without one.
fn lef_schedule_deg(alpha_rad: f32, mach: f32, gear_norm: f32) -> f32 {
    let Some(s) = AIRCRAFT.fcs.lef_schedule else {
        return 0.0;
    };
    let gear_up: &[(f32, f32)] = if gear_norm <= 0.0 {
        s.gear_up_alpha_steps
    } else {
        &[]
    };
    let step = gear_up
        .iter()
        .chain(s.alpha_steps.iter())
        .find(|(above, _)| alpha_rad > *above);
    let rad = match step {
        Some(&(_, lef)) => lef,
        None if mach > s.mach_above => s.mach_lef_rad,
        None => 0.0,
    };
    rad * (180.0 / core::f32::consts::PI)
}

/// The right flaperon, which no channel carries, from the left one and the trailing-edge flap by
/// the description's `[fcs.flaperon_mix]` ([`crate::aircraft::FlaperonMix`]); the left one for an
/// aircraft without the mix.
fn flaperon_right_deg(inp: &Input, mach: f32) -> f32 {
    let Some(m) = AIRCRAFT.fcs.flaperon_mix else {
        return inp.flaperon_left_deg;
    };
    let per = aero::FLAPERON_DEG_PER_NORM;
    let left = inp.flaperon_left_deg / per;
    let tef = inp.tef_deg / per;
    let right = if libm::fabsf(left) > m.stop_norm {
        let a = inp.aileron_deg.to_radians() / m.aileron_rad_per_norm
            * (1.0 - m.mach_compensation * mach).clamp(m.min_compensation, 1.0);
        tef - a
    } else {
        left + 2.0 * tef
    };
    right.clamp(-1.0, 1.0) * per
}

/// The surfaces the aero model reads for a frame's input at α and Mach: the channels' positions,
/// the LEF as the flight-control system schedules it and the right flaperon from the mix (what
/// the filter's force model and the flight-test calibration evaluate the model with).
pub fn surfaces(inp: &Input, alpha_rad: f32, mach: f32, gear_norm: f32) -> Surfaces {
    Surfaces {
        elevator_deg: inp.elevator_deg,
        aileron_deg: inp.aileron_deg,
        rudder_deg: inp.rudder_deg,
        lef_deg: lef_schedule_deg(alpha_rad, mach, gear_norm),
        flaperon_left_deg: inp.flaperon_left_deg,
        flaperon_right_deg: flaperon_right_deg(inp, mach),
        speedbrake_deg: inp.speedbrake_deg,
        flap_deg: inp.tef_deg,
        gear_norm,
    }
}

/// The input's EGI velocity (at the CG) in body axes, m/s: the air velocity in calm air.
pub fn body_velocity(inp: &Input) -> [f32; 3] {
    let v = c_bn(inp.euler_rad) * Vector3::from(inp.vel_ned_mps);
    [v.x, v.y, v.z]
}

/// The force model's operating point for a frame's input at an air-data point (α, β in rad, Mach,
/// true airspeed in m/s), with the gyro's body rates as the aero rates (calm air), the surfaces of
/// [`surfaces`] and no ground effect: where the filter and the flight-test calibration evaluate
/// the model (`None` if an input is not finite or the airspeed not positive).
/// `unsteady` is what the model reads beyond the air-data point: α̇ ([`alpha_rate`]) and the
/// stall latch ([`aero::Model::stall_latch`]).
#[allow(clippy::too_many_arguments)]
pub fn model_point(
    inp: &Input,
    gyro: [f32; 3],
    alpha_rad: f32,
    beta_rad: f32,
    mach: f32,
    tas_mps: f32,
    gear_norm: f32,
    unsteady: Unsteady,
) -> Option<aero::Point> {
    let air = AirState {
        alpha_rad,
        beta_rad,
        mach,
        tas_mps,
        p_rps: gyro[0],
        q_rps: gyro[1],
        r_rps: gyro[2],
        h_over_b: AirState::NO_GROUND_EFFECT,
        unsteady,
    };
    aero::Point::new(&MODEL, &air, &surfaces(inp, alpha_rad, mach, gear_norm))
}

/// α̇ (rad/s) as JSBSim defines `aero/alphadot-rad_sec`: the body-axis rate of change of the
/// aircraft's velocity (specific force `f_cg` plus gravity, less ω × v, all body axes) against the
/// air velocity `vb_air` (body axes), `(u·ẇ − w·u̇) / (u² + w²)`. A steady wind moves the air
/// velocity as the inertial one, so the IMU and the EGI give it without differencing the noisy α;
/// 0 below 1 m/s of airspeed in the symmetry plane.
pub fn alpha_rate(
    vb_air: &Vector3<f32>,
    cbn: &Matrix3<f32>,
    vel_ned_mps: [f32; 3],
    f_cg: &Vector3<f32>,
    gyro_rps: [f32; 3],
) -> f32 {
    let v = cbn * Vector3::from(vel_ned_mps);
    let g = cbn * Vector3::new(0.0, 0.0, GRAVITY_MPS2);
    let vdot = f_cg + g - Vector3::from(gyro_rps).cross(&v);
    let uw2 = vb_air.x * vb_air.x + vb_air.z * vb_air.z;
    let rate = (vb_air.x * vdot.z - vb_air.z * vdot.x) / uw2;
    if uw2 > 1.0 && rate.is_finite() {
        rate
    } else {
        0.0
    }
}

/// Standard gravity, m/s² (the JSBSim models flown here fly a constant-gravity earth near the
/// ground).
const GRAVITY_MPS2: f32 = 9.80665;

/// Dynamic pressure times the wing area over the mass: the specific force (m/s²) of a unit force
/// coefficient at density `rho` (kg/m³) and true airspeed `tas_mps`.
pub fn qs_over_m(rho: f32, tas_mps: f32, mass_kg: f32) -> f32 {
    let s_m2 = MODEL.wing_area_ft2 * 0.3048 * 0.3048;
    0.5 * rho * tas_mps * tas_mps * s_m2 / mass_kg
}

/// Specific force at the CG, body axes (m/s²): the IMU's, less ω̇ × r and ω × (ω × r) for the
/// lever arm r, with ω̇ the gyro change since `prev` over `inp.dt_s` (zero for a non-positive dt).
pub fn specific_force_cg(inp: &Input, prev: &Input, lever_arm_m: [f32; 3]) -> Vector3<f32> {
    let dt = inp.dt_s;
    let w = Vector3::from(inp.gyro_rps);
    let w_prev = Vector3::from(prev.gyro_rps);
    let w_dot = if dt > 0.0 {
        (w - w_prev) / dt
    } else {
        Vector3::zeros()
    };
    let r = Vector3::from(lever_arm_m);
    Vector3::from(inp.accel_mps2) - w_dot.cross(&r) - w.cross(&w.cross(&r))
}

/// Specific force at the CG per unit lift scale, body axes, for a body air velocity; `None` when the
/// model cannot be evaluated there.
#[allow(clippy::too_many_arguments)]
fn model_force(
    vb: &Vector3<f32>,
    inp: &Input,
    gyro: [f32; 3],
    rho: f32,
    a_sound: f32,
    mass_kg: f32,
    gear_norm: f32,
    unsteady: Unsteady,
) -> Option<Vector3<f32>> {
    model_force_parts(
        vb, inp, gyro, rho, a_sound, mass_kg, gear_norm, unsteady, false,
    )
    .map(|(f, _)| f)
}

/// [`model_force`], and with `te` the part of it the lift terms reading a trailing-edge surface
/// make ([`aero::Model::trailing_edge_lift_body`]; zero without `te`), from one model point.
#[allow(clippy::too_many_arguments)]
fn model_force_parts(
    vb: &Vector3<f32>,
    inp: &Input,
    gyro: [f32; 3],
    rho: f32,
    a_sound: f32,
    mass_kg: f32,
    gear_norm: f32,
    unsteady: Unsteady,
    te: bool,
) -> Option<(Vector3<f32>, Vector3<f32>)> {
    let v = vb.norm();
    if v.is_nan() || v <= 1.0 {
        return None;
    }
    let alpha = libm::atan2f(vb.z, vb.x);
    let beta = libm::asinf((vb.y / v).clamp(-1.0, 1.0));
    let mach = v / a_sound;
    let point = model_point(inp, gyro, alpha, beta, mach, v, gear_norm, unsteady)?;
    let c = MODEL.coefficients_at(&point);
    if !c.valid {
        return None;
    }
    let qs = qs_over_m(rho, v, mass_kg);
    let te = if te {
        let [x, y, z] = MODEL.trailing_edge_lift_body(&point)?;
        Vector3::new(x, y, z) * qs
    } else {
        Vector3::zeros()
    };
    Some((Vector3::new(c.body.x, c.body.y, c.body.z) * qs, te))
}

impl AirDataFilter {
    pub fn new(cfg: Config) -> Self {
        let mut f = AirDataFilter {
            cfg,
            x: Vec7::zeros(),
            p: Mat7::zeros(),
            prev: None,
            prev_cbn: Matrix3::identity(),
            gated_run: 0,
            alt: None,
            last: Output::default(),
            turb_ms: 0.0,
            turb_weight: 0.0,
            turb_settle: TURBULENCE_SETTLE_STEPS,
            nis_mean: cfg.gate,
            nu_ms: [0.0; 2],
            r_adapt_age_s: 0.0,
            stall_latched: false,
            kinematic: [0.0; 2],
            gyro: [0.0; 3],
            gyro_agrees: [0; 3],
        };
        f.restart();
        f
    }

    /// A fresh filter's state after a gap in the frames, keeping only the running means of the
    /// kinematic and the gyro check and, while the kinematic means stand beyond the gate, the run
    /// of gated steps (as [`AirDataFilter::restart`] does: they compare the sensors with each
    /// other, not with the filter's state).
    pub fn start_again(&mut self) {
        let (kinematic, gyro, gyro_agrees, gated_run) =
            (self.kinematic, self.gyro, self.gyro_agrees, self.gated_run);
        *self = AirDataFilter::new(self.cfg);
        self.kinematic = kinematic;
        self.gyro = gyro;
        self.gyro_agrees = gyro_agrees;
        self.gated_run = gated_run;
        // The restart's rule for the run, with the running means back.
        self.restart();
    }

    /// Back to the initial state and covariance (wind unknown, lift scale 1).
    pub fn restart(&mut self) {
        let c = &self.cfg;
        self.x = Vec7::zeros();
        for i in [K, KY] {
            if let Some(k) = self.x.get_mut(i) {
                *k = 1.0;
            }
        }
        let sq = |v: f32| v * v;
        let p0 = [
            sq(c.mean_wind_sigma0[0]),
            sq(c.mean_wind_sigma0[1]),
            sq(c.mean_wind_sigma0[2]),
            sq(c.gust_sigma),
            sq(c.gust_sigma),
            sq(c.gust_sigma),
            sq(c.lift_scale_sigma0),
            sq(c.side_scale_sigma0),
            sq(c.te_lift_sigma0),
        ];
        self.p = Mat7::from_diagonal(&Vec7::from_fn(|i, _| p0.get(i).copied().unwrap_or(0.0)));
        // A run of steps kept out for a channel in error goes on: the restart does not mend it.
        if !self.kinematics_beyond_gate() {
            self.gated_run = 0;
        }
        self.turb_ms = 0.0;
        self.turb_weight = 0.0;
        self.last.turbulence_rad = 0.0;
        self.stall_latched = false;
        self.nu_ms = c.accel_sigma.map(sq);
        self.unsettle();
    }

    /// What a start, a restart and a step without inputs all forget: the previous input, the
    /// settled wind the turbulence index compares against, and the proof that the model fits (the
    /// NIS mean starts again at the gate). The kinematic check's running mean is kept: it compares
    /// the sensors with each other, not with the filter's state, and an accelerometer in error
    /// before an outage or a restart is in error after it until the steps show otherwise.
    fn unsettle(&mut self) {
        self.prev = None;
        self.turb_settle = TURBULENCE_SETTLE_STEPS;
        self.nis_mean = self.cfg.gate;
        self.r_adapt_age_s = 0.0;
    }

    /// Folds this step's kinematic residual into its running mean (nothing with the check off;
    /// [`AirDataFilter::kinematics_beyond_gate`] gives the verdict). The residual is the y and z specific force at the
    /// CG (`f_cg`, the accelerometers' less the lever-arm terms) less the one the EGI gives,
    /// `C_bn · (Δv / Δt − g)` with the input's CG velocity: the velocity change is the step's mean
    /// acceleration, so it is turned into body axes with the mean of the step's two attitude
    /// matrices (`cbn` is this frame's, `prev_cbn` the previous one's), not this frame's alone,
    /// which a rolling aircraft has turned away from it. What of it the two sources' timing can
    /// explain is taken off before it is folded in ([`KINEMATIC_TIMING_S`]). `dt` is
    /// [`AirDataFilter::step`]'s sanitised step (finite, 0–1 s).
    fn fold_kinematics(
        &mut self,
        inp: &Input,
        prev: &Input,
        f_cg: &Vector3<f32>,
        cbn: &Matrix3<f32>,
        dt: f32,
    ) {
        // With the check off there is nothing to keep; with no velocity change to compare, or one
        // over a gap, the running mean stands as it is.
        if self.cfg.kinematic_gate_mps2 <= 0.0 || dt <= 0.0 || dt > KINEMATIC_MAX_DT_S {
            return;
        }
        let a_ned = (Vector3::from(inp.vel_ned_mps) - Vector3::from(prev.vel_ned_mps)) / dt;
        let c_mid = (cbn + self.prev_cbn) * 0.5;
        let f_egi = c_mid * (a_ned - Vector3::new(0.0, 0.0, GRAVITY_MPS2));
        // How fast the specific force changes in body axes: by itself (the accelerometers'
        // change over the step) and as the axes turn under the velocity change (ω × f).
        let turning = Vector3::from(inp.gyro_rps).cross(f_cg);
        let change = (Vector3::from(inp.accel_mps2) - Vector3::from(prev.accel_mps2)) / dt;
        let r = f_cg - f_egi;
        let axes = [(r.y, turning.y, change.y), (r.z, turning.z, change.z)];
        for (mean, (r, w, change)) in self.kinematic.iter_mut().zip(axes) {
            let excess =
                libm::fabsf(r) - KINEMATIC_TIMING_S * (libm::fabsf(w) + libm::fabsf(change));
            // A step whose residual or band overflowed says nothing: the mean stands.
            if excess.is_finite() {
                running_mean(
                    mean,
                    libm::copysignf(libm::fmaxf(excess, 0.0), r),
                    dt,
                    KINEMATIC_TAU_S,
                );
            }
        }
    }

    /// Whether the kinematic check's running mean, as it stands, is beyond its gate (never with
    /// the check off).
    fn kinematics_beyond_gate(&self) -> bool {
        let gate = self.cfg.kinematic_gate_mps2;
        gate > 0.0 && self.kinematic.iter().any(|m| libm::fabsf(*m) > gate)
    }

    /// Folds this step's gyro residual into its running means (nothing with the check off;
    /// [`AirDataFilter::gyros_beyond_gate`] gives the verdict): each gyro's mean over the step,
    /// the newer half of the previous frame period and the older half of this one, less the body
    /// rate that turns the previous frame's EGI attitude (`prev_cbn`) into this one's (`cbn`).
    /// The EGI's attitude is 0.02 s plus up to one output period old at a frame (0.02 s, heading
    /// 0.04 s), so the half-period shift lines the two up where both frames carry the gyros'
    /// sub-samples; otherwise the two frames' 20 Hz gyros, weighted to the same instant
    /// ([`GYRO_20HZ_SHARE`]). `dt` is [`AirDataFilter::step`]'s sanitised step (finite, 0–1 s);
    /// over a gap longer than [`KINEMATIC_MAX_DT_S`] the means stand, as the kinematic check's do.
    fn fold_gyros(&mut self, inp: &Input, prev: &Input, cbn: &Matrix3<f32>, dt: f32) {
        if self.cfg.gyro_gate_rps <= 0.0 || dt <= 0.0 || dt > KINEMATIC_MAX_DT_S {
            return;
        }
        // C_k · C_{k-1}ᵀ ≈ I − [ω×]·Δt: its skew part is sin θ along the turn's axis; to the
        // angle θ to second order (the F-16's fastest roll turns 0.26 rad in a step: 1 % more).
        let m = cbn * self.prev_cbn.transpose();
        let s = Vector3::new(m.m23 - m.m32, m.m31 - m.m13, m.m12 - m.m21) * 0.5;
        let egi = s * ((1.0 + s.norm_squared() / 6.0) / dt);
        let gyro = match (prev.gyro_halves_rps, inp.gyro_halves_rps) {
            (Some([_, newer]), Some([older, _])) => {
                (Vector3::from(newer) + Vector3::from(older)) * 0.5
            }
            _ => {
                Vector3::from(inp.gyro_rps) * GYRO_20HZ_SHARE
                    + Vector3::from(prev.gyro_rps) * (1.0 - GYRO_20HZ_SHARE)
            }
        };
        let r = gyro - egi;
        let gate = self.cfg.gyro_gate_rps;
        for ((mean, agrees), r) in self
            .gyro
            .iter_mut()
            .zip(&mut self.gyro_agrees)
            .zip(r.iter())
        {
            // A step whose residual overflowed says nothing: the mean and the run stand.
            if r.is_finite() {
                *agrees = if libm::fabsf(*r) <= 0.5 * gate {
                    agrees.saturating_add(1)
                } else {
                    0
                };
                // A gyro that disagrees and has read within half the gate for a few steps in a
                // row lets go faster: its error has gone, and the mean would otherwise take a
                // second to fall under the gate, taking a stale error off a good gyro all that
                // time. (One step within it is not enough: a bias near the gate plus noise dips
                // there now and then.)
                let release = libm::fabsf(*mean) > gate && *agrees >= GYRO_RELEASE_STEPS;
                let tau = if release {
                    GYRO_RELEASE_TAU_S
                } else {
                    GYRO_TAU_S
                };
                running_mean(mean, *r, dt, tau);
            }
        }
    }

    /// The gyros whose running mean, as it stands, is beyond the gate, as channel bits (none with
    /// the check off).
    fn gyros_beyond_gate(&self) -> u32 {
        let gate = self.cfg.gyro_gate_rps;
        self.gyro
            .iter()
            .zip(GYROS)
            .filter(|(m, _)| gate > 0.0 && libm::fabsf(**m) > gate)
            .fold(0, |bits, (_, c)| bits | c.bit())
    }

    /// `inp` with the gyro check's running mean taken off each gyro that disagrees: what the model
    /// and the lever-arm terms read. The EGI velocity, which [`Input::from_frame`] moved to the CG
    /// with the raw gyros (`v_cg = v_imu − C_nb (ω × r)`), is moved again with the rates less that
    /// mean: `+ C_nb (e × r)` for the error `e` taken off, `cbn` being `inp`'s attitude matrix,
    /// which the step has already computed.
    fn without_gyro_error(&self, inp: &Input, disagrees: u32, cbn: &Matrix3<f32>) -> Input {
        let mut out = *inp;
        let mut taken = [0.0f32; 3];
        for (((rate, mean), e), c) in (out.gyro_rps.iter_mut().zip(self.gyro))
            .zip(taken.iter_mut())
            .zip(GYROS)
        {
            if disagrees & c.bit() != 0 {
                *rate -= mean;
                *e = mean;
            }
        }
        let v = Vector3::from(out.vel_ned_mps) + arm_velocity_ned(cbn, taken, self.cfg.lever_arm_m);
        out.vel_ned_mps = [v.x, v.y, v.z];
        out
    }

    /// Folds this step's wind change into the turbulence index; returns the index, rad.
    ///
    /// Milspec-like turbulence adds near-white increments to the gust, so the per-frame change of
    /// the estimated wind, over the airspeed, measures how far the air mass moves α and β faster
    /// than any sensor behind the anti-alias filter can follow. A step of `dt` other than one
    /// frame is scaled by √(frame / dt), as a random walk's increment would be. For
    /// [`TURBULENCE_SETTLE_STEPS`] after a start, restart or outage the index holds its value;
    /// past them, `last` is the previous step's output (every path that skips one resets the
    /// settle count).
    fn turbulence(&mut self, wind: Vector3<f32>, airspeed: f32, dt: f32) -> f32 {
        if self.turb_settle > 0 {
            self.turb_settle = self.turb_settle.saturating_sub(1);
        } else if dt > 0.0 {
            // `output` returns `None` below 1 m/s, so the divisor is at least the flag's floor.
            let v = airspeed.max(self.cfg.min_airspeed_mps);
            let d = (wind - Vector3::from(self.last.wind_ned_mps)).norm() / v;
            let d2 = d * d * (TURBULENCE_FRAME_S / dt);
            if d2.is_finite() {
                running_mean(&mut self.turb_ms, d2, dt, TURBULENCE_TAU_S);
                running_mean(&mut self.turb_weight, 1.0, dt, TURBULENCE_TAU_S);
            }
        }
        // The weight is 0 until the first change is taken in (then turb_ms is 0 as well), and at
        // most 1; a weight of 0 reads as calm air, as before the first change.
        let ms = if self.turb_weight > 0.0 {
            self.turb_ms / self.turb_weight
        } else {
            0.0
        };
        libm::sqrtf(ms.max(0.0))
    }

    pub fn wind(&self) -> Vector3<f32> {
        self.x.fixed_rows::<3>(0) + self.x.fixed_rows::<3>(3)
    }

    pub fn lift_scale(&self) -> f32 {
        self.x.get(K).copied().unwrap_or(1.0)
    }

    /// The trailing-edge lift scale s (0 unless the filter learns it, [`LEARNS_TE_LIFT`], and
    /// [`Config::te_lift_sigma0`] or [`Config::te_lift_psd`] lets it move).
    pub fn te_lift(&self) -> f32 {
        self.x.get(TE).copied().unwrap_or(0.0)
    }

    /// The side-force scale (1 unless [`Config::side_scale_sigma0`] lets it move).
    pub fn side_scale(&self) -> f32 {
        self.x.get(KY).copied().unwrap_or(1.0)
    }

    fn predict(&mut self, dt: f32) {
        let c = &self.cfg;
        let phi = libm::expf(-dt / c.gust_tau_s);
        let f = Mat7::from_diagonal(&Vec7::from_fn(
            |i, _| if (3..6).contains(&i) { phi } else { 1.0 },
        ));
        let gust_q = c.gust_sigma * c.gust_sigma * (1.0 - phi * phi);
        let [qn, qe, qd] = c.mean_wind_psd;
        let q0 = [
            qn * dt,
            qe * dt,
            qd * dt,
            gust_q,
            gust_q,
            gust_q,
            c.lift_scale_psd * dt,
            c.side_scale_psd * dt,
            c.te_lift_psd * dt,
        ];
        let q = Mat7::from_diagonal(&Vec7::from_fn(|i, _| q0.get(i).copied().unwrap_or(0.0)));
        self.x = f * self.x;
        self.p = f * self.p * f.transpose() + q;
    }

    /// The measurement update; returns the NIS, or `None` when there was nothing to compare.
    /// `step_dt` is [`AirDataFilter::step`]'s sanitised step (finite, 0–1 s), for the adaptive
    /// noise's running means.
    fn update(
        &mut self,
        inp: &Input,
        prev: &Input,
        f_cg: &Vector3<f32>,
        step_dt: f32,
    ) -> Option<f32> {
        let c = self.cfg;
        let dt = inp.dt_s;
        let back = if dt > 0.0 {
            (c.accel_delay_s / dt).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let u = inp.toward(prev, back);
        let (rho, a_sound) = isa(u.alt_m);
        let mass = c.mass_kg(inp.fuel_kg);

        let cbn = c_bn(u.euler_rad);
        let vb = cbn * (Vector3::from(u.vel_ned_mps) - self.wind());
        // α̇ and the latch are inputs of the model here, not functions of the state.
        let unsteady = Unsteady {
            alpha_dot_rps: alpha_rate(&vb, &cbn, u.vel_ned_mps, f_cg, inp.gyro_rps),
            stall_latched: self.stall_latched,
        };
        let learn_te = STATES > TE && (c.te_lift_sigma0 > 0.0 || c.te_lift_psd > 0.0);
        let (f0, f_te) = model_force_parts(
            &vb,
            &u,
            inp.gyro_rps,
            rho,
            a_sound,
            mass,
            c.gear_norm,
            unsteady,
            learn_te,
        )?;
        let k = self.lift_scale();
        let s_te = self.te_lift();
        // d f / d v_body by forward differences, then d h / d wind = −k · (df/dvb) · C_bn.
        const D: f32 = 0.01;
        let mut dfdvb = Matrix3::zeros();
        for j in 0..3 {
            let mut vj = vb;
            if let Some(e) = vj.get_mut(j) {
                *e += D;
            }
            let fj = model_force(
                &vj,
                &u,
                inp.gyro_rps,
                rho,
                a_sound,
                mass,
                c.gear_norm,
                unsteady,
            )?;
            dfdvb.set_column(j, &((fj - f0) / D));
        }
        let ky = self.side_scale();
        let dhdw = -(dfdvb * cbn) * k;
        // The model's force with the trailing-edge lift scaled (the wind columns keep the plain
        // model's slopes: s is small).
        let f0 = if learn_te { f0 + f_te * s_te } else { f0 };
        // Rows: the y and z specific force. Mean wind and gust enter alike; k scales the model,
        // ky its lateral force on top.
        let mut h = Mat27::zeros();
        for (row, axis, side) in [(0usize, 1usize, ky), (1, 2, 1.0)] {
            let d = dhdw.row(axis) * side;
            h.fixed_view_mut::<1, 3>(row, 0).copy_from(&d);
            h.fixed_view_mut::<1, 3>(row, 3).copy_from(&d);
            let f = f0.get(axis).copied().unwrap_or(0.0);
            if let Some(e) = h.get_mut((row, K)) {
                *e = side * f;
            }
            if row == 0
                && let Some(e) = h.get_mut((row, KY))
            {
                *e = k * f;
            }
            if learn_te && let Some(e) = h.get_mut((row, TE)) {
                *e = k * side * f_te.get(axis).copied().unwrap_or(0.0);
            }
        }
        let nu = Vector2::new(f_cg.y - k * ky * f0.y, f_cg.z - k * f0.z);
        let hph = h * self.p * h.transpose();
        let r = self.measurement_variance(&hph);
        let rm = Matrix2::new(r[0], 0.0, 0.0, r[1]);
        let s = hph + rm;
        let s_inv = s.try_inverse()?;
        let nis = (nu.transpose() * s_inv * nu).x;
        if !nis.is_finite() {
            return None;
        }
        if nis > c.gate {
            self.gated_run = self.gated_run.saturating_add(1);
            return Some(nis);
        }
        self.gated_run = 0;
        // Only accepted innovations: a sustained mismatch must stay gated and flagged, not raise
        // the noise until it passes.
        self.track_innovation(&nu, &s, step_dt);
        let gain = self.p * h.transpose() * s_inv;
        self.x += gain * nu;
        let ikh = Mat7::identity() - gain * h;
        self.p = ikh * self.p * ikh.transpose() + gain * rm * gain.transpose();
        Some(nis)
    }

    /// The measurement variance of the y and z specific force this step: [`Config::accel_sigma`]²,
    /// or with [`Config::r_adapt_tau_s`] the innovations' running mean square less the state's
    /// share `hph`, within [`Config::r_adapt_range`]. Until the mean has `r_adapt_tau_s` of
    /// accepted updates behind it (after a start, restart or outage, while the state's variance is
    /// still large), the nominal variance.
    fn measurement_variance(&self, hph: &Matrix2<f32>) -> [f32; 2] {
        let c = &self.cfg;
        let mut r = c.accel_sigma.map(|s| s * s);
        if c.r_adapt_tau_s > 0.0 && self.r_adapt_age_s >= c.r_adapt_tau_s {
            let adapt = r.iter_mut().zip(c.r_adapt_range).zip(self.nu_ms);
            for (i, ((nominal, [lo, hi]), ms)) in adapt.enumerate() {
                let matched = ms - hph.get((i, i)).copied().unwrap_or(0.0);
                // NaN-safe: `max`/`min` return the other operand for a NaN.
                *nominal = matched.max(lo * lo * *nominal).min(hi * hi * *nominal);
            }
        }
        r
    }

    /// Folds this step's innovation into the running mean squares ([`Config::r_adapt_tau_s`]),
    /// each square capped at [`Config::gate`] times its predicted variance so one wild sample
    /// cannot hold the adapted noise up. `dt` is the step's, already sanitised by `step`.
    fn track_innovation(&mut self, nu: &Vector2<f32>, s: &Matrix2<f32>, dt: f32) {
        let tau = self.cfg.r_adapt_tau_s;
        if tau.is_nan() || tau <= 0.0 {
            return;
        }
        self.r_adapt_age_s = (self.r_adapt_age_s + dt).min(tau);
        for (i, ms) in self.nu_ms.iter_mut().enumerate() {
            let n = nu.get(i).copied().unwrap_or(0.0);
            let cap = self.cfg.gate * s.get((i, i)).copied().unwrap_or(0.0);
            let sq = (n * n).min(cap);
            if sq.is_finite() {
                running_mean(ms, sq, dt, tau);
            }
        }
    }

    fn healthy(&self) -> bool {
        let diag = self.p.diagonal();
        let var_ok = diag
            .iter()
            .take(6)
            .all(|v| *v >= 0.0 && *v <= self.cfg.max_wind_var)
            // The scales': not negative, not NaN (no upper bound: a scale nothing observes for a
            // while may widen by its random walk without the filter being wrong).
            && diag.iter().skip(6).all(|v| *v >= 0.0);
        let (k, ky) = (self.lift_scale(), self.side_scale());
        var_ok
            && self.x.iter().all(|v| v.is_finite())
            && (0.5..=1.5).contains(&k)
            && (0.5..=1.5).contains(&ky)
            && (-0.5..=0.5).contains(&self.te_lift())
    }

    /// One step on a sensor frame; `dt_s` is the time since the previous frame.
    ///
    /// Without a valid GPS altitude, but with everything else, the altitude is carried on from the
    /// last step's by the EGI's vertical velocity for up to [`MAX_ALT_COAST_S`], and the output
    /// says [`flags::ALT_COASTED`].
    pub fn step_frame(&mut self, f: &SensorFrame, dt_s: f32) -> Output {
        let alt_bit = Channel::GpsAlt.bit();
        let mut frame = *f;
        let mut coasted = false;
        if f.valid & alt_bit == 0
            && (f.valid | alt_bit) & NEEDED_MASK == NEEDED_MASK
            && let Some((alt, since)) = self.alt
        {
            let dt = if dt_s.is_finite() { dt_s.max(0.0) } else { 0.0 };
            let since = since + dt;
            let v_down = f.get(Channel::VelDown) as f32 * Channel::VelDown.lsb() as f32;
            let alt = alt - v_down * dt;
            let raw = libm::roundf(alt / Channel::GpsAlt.lsb() as f32);
            if since <= MAX_ALT_COAST_S && raw.is_finite() && libm::fabsf(raw) < 2.0e9 {
                if let Some(r) = frame.raw.get_mut(Channel::GpsAlt.index()) {
                    *r = raw as i32;
                }
                frame.valid |= alt_bit;
                coasted = true;
                self.alt = Some((alt, since));
            }
        }
        let c = &self.cfg;
        let mut out = match Input::from_frame(&frame, dt_s, c.lever_arm_m, c.subsamples) {
            Some(inp) => {
                if !coasted {
                    self.alt = Some((inp.alt_m, 0.0));
                }
                self.step(&inp, true)
            }
            None => {
                self.alt = None;
                self.step(
                    &Input {
                        dt_s,
                        ..Input::default()
                    },
                    false,
                )
            }
        };
        if coasted {
            out.flags |= flags::ALT_COASTED;
            self.last.flags = out.flags;
        }
        out
    }

    /// One 20 Hz step. `inputs_valid` false (or any input not finite) runs the prediction only and
    /// holds the outputs.
    pub fn step(&mut self, inp: &Input, inputs_valid: bool) -> Output {
        let mut flags = 0;
        let dt = if inp.dt_s.is_finite() {
            inp.dt_s.clamp(0.0, 1.0)
        } else {
            0.0
        };
        self.predict(dt);
        if !inputs_valid || !inp.is_finite() {
            self.unsettle();
            if !self.healthy() {
                self.restart();
                flags |= flags::RESTARTED;
            }
            let mut out = self.last;
            out.flags = flags | flags::NO_INPUT | flags::LOW_CONFIDENCE;
            out.nis = 0.0;
            out.gyro_disagrees = self.gyros_beyond_gate();
            self.last = out;
            return out;
        }
        // The attitude of this frame: the checks' and the outputs'.
        let cbn = c_bn(inp.euler_rad);
        let raw = inp;
        if let Some(prev) = self.prev {
            self.fold_gyros(raw, &prev, &cbn, dt);
        }
        // From here on the gyros are those the model reads: a gyro that disagrees less its error
        // (copies of the inputs only then).
        let gyro_disagrees = self.gyros_beyond_gate();
        let fixed;
        let inp = if gyro_disagrees == 0 {
            raw
        } else {
            fixed = self.without_gyro_error(raw, gyro_disagrees, &cbn);
            &fixed
        };
        let prev = self.prev.map(|p| {
            let p = if gyro_disagrees == 0 {
                p
            } else {
                self.without_gyro_error(&p, gyro_disagrees, &self.prev_cbn)
            };
            (specific_force_cg(inp, &p, self.cfg.lever_arm_m), p)
        });
        // Without a previous input (the first step after a start, an outage or a restart) there
        // is no velocity change to fold, but the running mean's verdict stands.
        if let Some((f_cg, prev)) = &prev {
            self.fold_kinematics(inp, prev, f_cg, &cbn, dt);
        }
        let nis = if self.kinematics_beyond_gate() {
            self.gated_run = self.gated_run.saturating_add(1);
            flags |= flags::DISAGREES;
            None
        } else if let Some((f_cg, prev)) = &prev {
            self.update(inp, prev, f_cg, dt)
        } else {
            None
        };
        if let Some(n) = nis {
            // `update` returns finite values only; a gated one counts as the gate, so one wild
            // innovation cannot hold the mean up for long.
            running_mean(&mut self.nis_mean, n.min(self.cfg.gate), dt, NIS_TAU_S);
        }
        if nis.is_none_or(|n| n > self.cfg.gate) {
            flags |= flags::PREDICTED;
        }
        let nis = nis.unwrap_or(0.0);
        // The gyro check compares the gyros as they read.
        self.prev = Some(*raw);
        self.prev_cbn = cbn;
        if !self.healthy() {
            self.restart();
            self.prev = Some(*raw);
            flags |= flags::RESTARTED;
        }
        if self.gated_run >= self.cfg.gate_run {
            flags |= flags::GATED;
        }
        match self.output(inp, &cbn, nis) {
            Some(mut out) => {
                if out.sigma_alpha_rad > self.cfg.max_sigma_rad
                    || out.sigma_beta_rad > self.cfg.max_sigma_rad
                {
                    flags |= flags::LOW_CONFIDENCE;
                }
                if out.airspeed_mps < self.cfg.min_airspeed_mps {
                    flags |= flags::SLOW;
                }
                out.turbulence_rad =
                    self.turbulence(Vector3::from(out.wind_ned_mps), out.airspeed_mps, dt);
                self.stall_latched = MODEL.stall_latch(self.stall_latched, out.alpha_rad);
                out.flags = flags;
                out.gyro_disagrees = gyro_disagrees;
                self.last = out;
                out
            }
            None => {
                self.restart();
                let mut out = self.last;
                out.flags = flags | flags::RESTARTED | flags::LOW_CONFIDENCE;
                out.gyro_disagrees = gyro_disagrees;
                self.last = out;
                out
            }
        }
    }

    /// α, β, their 1σ and the rest at the current frame; `None` if anything is not finite.
    fn output(&self, inp: &Input, cbn: &Matrix3<f32>, nis: f32) -> Option<Output> {
        let wind = self.wind();
        let vb = cbn * (Vector3::from(inp.vel_ned_mps) - wind);
        let v = vb.norm();
        if v.is_nan() || v <= 1.0 {
            return None;
        }
        let alpha = libm::atan2f(vb.z, vb.x);
        let beta = libm::asinf((vb.y / v).clamp(-1.0, 1.0));
        // ∂α/∂vb and ∂β/∂vb, then through vb = C_bn (v − wind): ∂/∂wind = −(∂/∂vb) C_bn.
        let uw2 = vb.x * vb.x + vb.z * vb.z;
        let da = Vector3::new(-vb.z / uw2, 0.0, vb.x / uw2);
        let sq = libm::sqrtf(uw2);
        let db = Vector3::new(-vb.x * vb.y, uw2, -vb.z * vb.y) / (v * v * sq);
        let pw = self.p.fixed_view::<3, 3>(0, 0)
            + self.p.fixed_view::<3, 3>(3, 3)
            + self.p.fixed_view::<3, 3>(0, 3)
            + self.p.fixed_view::<3, 3>(3, 0);
        let ja = cbn.transpose() * da;
        let jb = cbn.transpose() * db;
        let var_a = (ja.transpose() * pw * ja).x;
        let var_b = (jb.transpose() * pw * jb).x;
        let out = Output {
            alpha_rad: alpha,
            beta_rad: beta,
            wind_ned_mps: [wind.x, wind.y, wind.z],
            airspeed_mps: v,
            lift_scale: self.lift_scale(),
            side_scale: self.side_scale(),
            te_lift: self.te_lift(),
            sigma_alpha_rad: libm::sqrtf(var_a.max(0.0)),
            sigma_beta_rad: libm::sqrtf(var_b.max(0.0)),
            nis,
            nis_mean: self.nis_mean,
            turbulence_rad: 0.0,
            flags: 0,
            gyro_disagrees: 0,
        };
        let finite = [
            out.alpha_rad,
            out.beta_rad,
            out.airspeed_mps,
            out.lift_scale,
            out.sigma_alpha_rad,
            out.sigma_beta_rad,
            out.nis,
            out.nis_mean,
        ]
        .iter()
        .chain(&out.wind_ned_mps)
        .all(|v| v.is_finite());
        finite.then_some(out)
    }
}

#[cfg(test)]
pub(crate) mod tests;
