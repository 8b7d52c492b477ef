//! Sensor error models: IMU (LN-200 class), GPS, control-surface position sensors, and for the EGI
//! suite an embedded GPS/INS (attitude, NED velocity) and the fuel quantity gauge.
//!
//! Fed with truth at every 120 Hz JSBSim step; returns the sensed channels of every suite (SI,
//! degrees for surfaces) in [`estimator_core::Channel`] order. The Table 1 channels draw from the
//! flight's ChaCha12 stream exactly as before the EGI suite existed; the EGI and fuel models draw
//! from stream [`EGI_STREAM`] of the same seed, so adding them changed no Table 1 value.
//!
//! The IMU path is: truth at the IMU location
//! (rates relative to inertial space, specific force moved from the CG), through the triad's
//! per-flight scale-factor and misalignment matrix (I + S + M); then per axis turn-on bias,
//! Gauss-Markov in-run bias, g-dependent gyro bias and white noise; then Δθ/Δv quantization
//! (residual carried, as an integrating IMU does) and a first-order lag: the unit's own output,
//! delivered at the 120 Hz simulation rate ([`SensorModel::fast_output`], with the surface
//! positions). The flight computer's
//! 2nd-order Butterworth anti-alias low-pass on that output makes the 20 Hz IMU channels, so that
//! the 20 Hz decimation does not fold vibration and noise into the band. Defaults and their
//! sources: `docs/sensors.md`.

use std::collections::VecDeque;
use std::path::Path;

use estimator_core::aircraft::{AIRCRAFT, SURFACE_CHANNELS};
use estimator_core::{CHANNELS, Channel};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha12Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::flight::{Every, SIM_HZ, SUB_CHANNELS, SubSampleSi};

const DT: f64 = 1.0 / SIM_HZ as f64;
const DEG_PER_H: f64 = std::f64::consts::PI / 180.0 / 3600.0;
const G0: f64 = 9.80665;

/// ChaCha stream of the EGI and fuel models (stream 0, the default, drives the Table 1 sensors).
pub const EGI_STREAM: u64 = 1;

/// Errors of one inertial sensor type, the same σ for its three axes (units of the sensor: rad/s or
/// m/s²).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InertialErrors {
    /// 1σ of the bias drawn once per flight (per axis).
    pub turn_on_bias_sigma: f64,
    /// Steady-state 1σ of the first-order Gauss-Markov in-run bias.
    pub in_run_bias_sigma: f64,
    /// Correlation time of the in-run bias, s.
    pub in_run_bias_tau_s: f64,
    /// White noise density, unit/√Hz (angle / velocity random walk).
    pub noise_density: f64,
    /// Output quantum of the integrated quantity (Δθ in rad, Δv in m/s); 0 = none.
    pub quantum: f64,
    /// 1σ of each axis's scale-factor error, drawn once per flight (dimensionless: 100e-6 = 100 ppm).
    pub scale_factor_sigma: f64,
    /// 1σ of each off-diagonal element of the triad's small-angle misalignment / non-orthogonality
    /// matrix, drawn once per flight, rad.
    pub misalignment_sigma_rad: f64,
}

/// An `[imu.gyro]` or `[imu.accel]` table as a `--sensors` file gives it: any subset of the
/// fields, each one left out taking the built-in sensor's value ([`ImuConfig::default`]: the
/// gyro's for `gyro`, the accelerometer's for `accel`), as every other table does.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct InertialOverride {
    turn_on_bias_sigma: Option<f64>,
    in_run_bias_sigma: Option<f64>,
    in_run_bias_tau_s: Option<f64>,
    noise_density: Option<f64>,
    quantum: Option<f64>,
    scale_factor_sigma: Option<f64>,
    misalignment_sigma_rad: Option<f64>,
}

impl InertialOverride {
    fn over(self, d: InertialErrors) -> InertialErrors {
        InertialErrors {
            turn_on_bias_sigma: self.turn_on_bias_sigma.unwrap_or(d.turn_on_bias_sigma),
            in_run_bias_sigma: self.in_run_bias_sigma.unwrap_or(d.in_run_bias_sigma),
            in_run_bias_tau_s: self.in_run_bias_tau_s.unwrap_or(d.in_run_bias_tau_s),
            noise_density: self.noise_density.unwrap_or(d.noise_density),
            quantum: self.quantum.unwrap_or(d.quantum),
            scale_factor_sigma: self.scale_factor_sigma.unwrap_or(d.scale_factor_sigma),
            misalignment_sigma_rad: self
                .misalignment_sigma_rad
                .unwrap_or(d.misalignment_sigma_rad),
        }
    }
}

fn gyro_over_defaults<'de, D: serde::Deserializer<'de>>(d: D) -> Result<InertialErrors, D::Error> {
    InertialOverride::deserialize(d).map(|o| o.over(ImuConfig::default().gyro))
}

fn accel_over_defaults<'de, D: serde::Deserializer<'de>>(d: D) -> Result<InertialErrors, D::Error> {
    InertialOverride::deserialize(d).map(|o| o.over(ImuConfig::default().accel))
}

/// IMU model parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ImuConfig {
    /// Gyro errors, rad/s.
    #[serde(deserialize_with = "gyro_over_defaults")]
    pub gyro: InertialErrors,
    /// Accelerometer errors, m/s².
    #[serde(deserialize_with = "accel_over_defaults")]
    pub accel: InertialErrors,
    /// g-dependent gyro bias: rad/s per m/s² of specific force along the same axis.
    pub gyro_g_sensitivity_rps_per_mps2: f64,
    /// IMU position relative to the CG, body axes (x forward, y right, z down), m.
    pub lever_arm_m: [f64; 3],
    /// First-order measurement lag (sensor bandwidth), s; 0 = none.
    pub lag_tau_s: f64,
    /// Anti-alias low-pass (2nd-order Butterworth) cut-off before 20 Hz decimation, Hz; 0 = none.
    pub antialias_cutoff_hz: f64,
}

impl Default for ImuConfig {
    fn default() -> Self {
        ImuConfig {
            gyro: InertialErrors {
                turn_on_bias_sigma: 1.0 * DEG_PER_H,
                in_run_bias_sigma: 0.35 * DEG_PER_H,
                in_run_bias_tau_s: 100.0,
                // 0.07 °/√h ARW
                noise_density: 0.07 * std::f64::consts::PI / 180.0 / 60.0,
                quantum: 2f64.powi(-19),
                scale_factor_sigma: 100e-6,
                misalignment_sigma_rad: 200e-6,
            },
            accel: InertialErrors {
                turn_on_bias_sigma: 300e-6 * G0,
                in_run_bias_sigma: 50e-6 * G0,
                in_run_bias_tau_s: 60.0,
                noise_density: 50e-6 * G0,
                // 2^-14 ft/s per Δv count
                quantum: 2f64.powi(-14) * crate::flight::FT_TO_M,
                scale_factor_sigma: 300e-6,
                misalignment_sigma_rad: 200e-6,
            },
            gyro_g_sensitivity_rps_per_mps2: 1.0 * DEG_PER_H / G0,
            lever_arm_m: estimator_core::aircraft::AIRCRAFT
                .installation
                .imu_lever_arm_m,
            lag_tau_s: 0.003,
            antialias_cutoff_hz: 6.0,
        }
    }
}

/// GPS model parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GpsConfig {
    /// White noise 1σ on the 3-D speed, m/s.
    pub speed_noise_sigma_mps: f64,
    /// White noise 1σ on altitude, m.
    pub alt_noise_sigma_m: f64,
    /// Slowly wandering altitude error (Gauss-Markov) 1σ, m.
    pub alt_bias_sigma_m: f64,
    pub alt_bias_tau_s: f64,
    /// Age of a fix when it is delivered, s.
    pub latency_s: f64,
    /// Fix rate, Hz (held between fixes).
    pub update_hz: f64,
}

impl Default for GpsConfig {
    fn default() -> Self {
        GpsConfig {
            speed_noise_sigma_mps: 0.05,
            alt_noise_sigma_m: 0.5,
            alt_bias_sigma_m: 3.0,
            alt_bias_tau_s: 600.0,
            latency_s: 0.1,
            update_hz: 10.0,
        }
    }
}

/// Surface position sensors (RVDT/LVDT through an ADC) and the throttle lever.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SurfaceConfig {
    pub noise_sigma_deg: f64,
    pub quantum_deg: f64,
    pub throttle_noise_sigma: f64,
    pub throttle_quantum: f64,
    /// Anti-alias low-pass (2nd-order Butterworth) on the surface positions before the 20 Hz
    /// decimation, Hz; 0 = none (point samples). The IMU's cut-off by default, so surfaces and
    /// accelerometers describe the same instants: the stock F-16 yaw damper drives the rudder
    /// stop to stop within single 120 Hz steps in heavy turbulence, and point samples at 20 Hz
    /// alias that chatter, whose side force the (filtered) accelerometers do see.
    pub antialias_cutoff_hz: f64,
}

impl Default for SurfaceConfig {
    fn default() -> Self {
        SurfaceConfig {
            noise_sigma_deg: 0.02,
            quantum_deg: 0.05,
            throttle_noise_sigma: 0.0,
            throttle_quantum: 1.0 / 1024.0,
            antialias_cutoff_hz: 6.0,
        }
    }
}

/// The embedded GPS/INS (EGI) outputs: attitude and velocity over the ground, each a first-order
/// Gauss-Markov error (the slowly varying error of a GPS-aided inertial solution) plus white noise,
/// `latency_s` old, refreshed at its output rate and held in between. Sources: `docs/sensors.md`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EgiConfig {
    /// Roll and pitch: Gauss-Markov 1σ, degrees, and its correlation time, s.
    pub attitude_gm_sigma_deg: f64,
    pub attitude_gm_tau_s: f64,
    /// Roll and pitch white noise 1σ, degrees.
    pub attitude_noise_sigma_deg: f64,
    /// True heading: Gauss-Markov 1σ (degrees), correlation time (s), white noise 1σ (degrees).
    pub heading_gm_sigma_deg: f64,
    pub heading_gm_tau_s: f64,
    pub heading_noise_sigma_deg: f64,
    /// Velocity north, east and down (each): Gauss-Markov 1σ (m/s), correlation time (s), white
    /// noise 1σ (m/s).
    pub velocity_gm_sigma_mps: f64,
    pub velocity_gm_tau_s: f64,
    pub velocity_noise_sigma_mps: f64,
    /// Output rates, Hz (held between outputs).
    pub attitude_hz: f64,
    pub heading_hz: f64,
    pub velocity_hz: f64,
    /// Age of an output when delivered, s.
    pub latency_s: f64,
}

impl Default for EgiConfig {
    fn default() -> Self {
        EgiConfig {
            attitude_gm_sigma_deg: 0.03,
            attitude_gm_tau_s: 300.0,
            attitude_noise_sigma_deg: 0.005,
            heading_gm_sigma_deg: 0.08,
            heading_gm_tau_s: 600.0,
            heading_noise_sigma_deg: 0.01,
            velocity_gm_sigma_mps: 0.03,
            velocity_gm_tau_s: 100.0,
            velocity_noise_sigma_mps: 0.01,
            attitude_hz: 50.0,
            heading_hz: 25.0,
            velocity_hz: 20.0,
            latency_s: 0.02,
        }
    }
}

/// The fuel quantity gauging system: per-flight bias (fraction of full scale) and scale-factor error
/// (fraction of the reading), a slowly varying error (probe wetting, slosh), quantized, refreshed at
/// `update_hz`. Sources: `docs/sensors.md`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FuelConfig {
    /// Full-scale quantity the gauge's %-of-full-scale errors refer to, kg.
    pub full_scale_kg: f64,
    /// 1σ of the per-flight bias, fraction of full scale.
    pub bias_sigma_fs: f64,
    /// 1σ of the per-flight scale-factor error, fraction of the reading.
    pub scale_factor_sigma: f64,
    /// Gauss-Markov 1σ (fraction of full scale) and correlation time (s).
    pub gm_sigma_fs: f64,
    pub gm_tau_s: f64,
    /// Output resolution, kg (0 = none).
    pub quantum_kg: f64,
    /// Output rate, Hz.
    pub update_hz: f64,
}

impl Default for FuelConfig {
    fn default() -> Self {
        FuelConfig {
            // The internal tanks the generator fills, and the gauge's resolution (the aircraft
            // description's).
            full_scale_kg: estimator_core::aircraft::AIRCRAFT
                .mass
                .internal_fuel_capacity_lb()
                * crate::flight::LB_TO_KG,
            bias_sigma_fs: 0.01,
            scale_factor_sigma: 0.01,
            gm_sigma_fs: 0.003,
            gm_tau_s: 10.0,
            quantum_kg: estimator_core::aircraft::AIRCRAFT
                .mass
                .fuel_gauge_quantum_lb
                * crate::flight::LB_TO_KG,
            update_hz: 1.0,
        }
    }
}

/// All sensor parameters (`--sensors FILE.toml`; missing sections/fields take the defaults).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SensorConfig {
    pub imu: ImuConfig,
    pub gps: GpsConfig,
    pub surfaces: SurfaceConfig,
    pub egi: EgiConfig,
    pub fuel: FuelConfig,
}

/// Why a sensor configuration cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum SensorConfigError {
    #[error("cannot read sensor config {path}: {source}")]
    Read {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
    #[error("sensor config {path} is not valid: {message}")]
    Parse {
        path: std::path::PathBuf,
        message: String,
    },
    #[error("sensor config: {field} = {value} is invalid ({why})")]
    Invalid {
        field: &'static str,
        value: f64,
        why: &'static str,
    },
}

impl SensorConfig {
    /// Loads and validates a TOML file.
    pub fn load(path: &Path) -> Result<SensorConfig, SensorConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| SensorConfigError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let cfg: SensorConfig = toml::from_str(&text).map_err(|e| SensorConfigError::Parse {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        cfg.validate()?;
        Ok(cfg)
    }

    /// Rejects negative σ, non-finite values and settings the 120 Hz model cannot honour.
    pub fn validate(&self) -> Result<(), SensorConfigError> {
        let nonneg: [(&'static str, f64); 24] = [
            (
                "imu.gyro.turn_on_bias_sigma",
                self.imu.gyro.turn_on_bias_sigma,
            ),
            (
                "imu.gyro.in_run_bias_sigma",
                self.imu.gyro.in_run_bias_sigma,
            ),
            ("imu.gyro.noise_density", self.imu.gyro.noise_density),
            ("imu.gyro.quantum", self.imu.gyro.quantum),
            (
                "imu.gyro.scale_factor_sigma",
                self.imu.gyro.scale_factor_sigma,
            ),
            (
                "imu.gyro.misalignment_sigma_rad",
                self.imu.gyro.misalignment_sigma_rad,
            ),
            (
                "imu.accel.turn_on_bias_sigma",
                self.imu.accel.turn_on_bias_sigma,
            ),
            (
                "imu.accel.in_run_bias_sigma",
                self.imu.accel.in_run_bias_sigma,
            ),
            ("imu.accel.noise_density", self.imu.accel.noise_density),
            ("imu.accel.quantum", self.imu.accel.quantum),
            (
                "imu.accel.scale_factor_sigma",
                self.imu.accel.scale_factor_sigma,
            ),
            (
                "imu.accel.misalignment_sigma_rad",
                self.imu.accel.misalignment_sigma_rad,
            ),
            ("imu.lag_tau_s", self.imu.lag_tau_s),
            ("imu.antialias_cutoff_hz", self.imu.antialias_cutoff_hz),
            ("gps.speed_noise_sigma_mps", self.gps.speed_noise_sigma_mps),
            ("gps.alt_noise_sigma_m", self.gps.alt_noise_sigma_m),
            ("gps.alt_bias_sigma_m", self.gps.alt_bias_sigma_m),
            ("gps.latency_s", self.gps.latency_s),
            ("surfaces.noise_sigma_deg", self.surfaces.noise_sigma_deg),
            ("surfaces.quantum_deg", self.surfaces.quantum_deg),
            (
                "surfaces.throttle_noise_sigma",
                self.surfaces.throttle_noise_sigma,
            ),
            ("surfaces.throttle_quantum", self.surfaces.throttle_quantum),
            (
                "imu.gyro_g_sensitivity_rps_per_mps2",
                self.imu.gyro_g_sensitivity_rps_per_mps2.abs(),
            ),
            ("gps.update_hz", self.gps.update_hz),
        ];
        let e = &self.egi;
        let f = &self.fuel;
        let nonneg_egi: [(&'static str, f64); 12] = [
            ("egi.attitude_gm_sigma_deg", e.attitude_gm_sigma_deg),
            ("egi.attitude_noise_sigma_deg", e.attitude_noise_sigma_deg),
            ("egi.heading_gm_sigma_deg", e.heading_gm_sigma_deg),
            ("egi.heading_noise_sigma_deg", e.heading_noise_sigma_deg),
            ("egi.velocity_gm_sigma_mps", e.velocity_gm_sigma_mps),
            ("egi.velocity_noise_sigma_mps", e.velocity_noise_sigma_mps),
            ("egi.latency_s", e.latency_s),
            ("fuel.bias_sigma_fs", f.bias_sigma_fs),
            ("fuel.scale_factor_sigma", f.scale_factor_sigma),
            ("fuel.gm_sigma_fs", f.gm_sigma_fs),
            ("fuel.quantum_kg", f.quantum_kg),
            ("fuel.full_scale_kg", f.full_scale_kg),
        ];
        for (field, value) in nonneg.into_iter().chain(nonneg_egi) {
            if !value.is_finite() || value < 0.0 {
                return Err(SensorConfigError::Invalid {
                    field,
                    value,
                    why: "must be finite and >= 0",
                });
            }
        }
        let positive: [(&'static str, f64); 4] = [
            (
                "imu.gyro.in_run_bias_tau_s",
                self.imu.gyro.in_run_bias_tau_s,
            ),
            (
                "imu.accel.in_run_bias_tau_s",
                self.imu.accel.in_run_bias_tau_s,
            ),
            ("gps.alt_bias_tau_s", self.gps.alt_bias_tau_s),
            ("gps.update_hz", self.gps.update_hz),
        ];
        let positive_egi: [(&'static str, f64); 8] = [
            ("egi.attitude_gm_tau_s", e.attitude_gm_tau_s),
            ("egi.heading_gm_tau_s", e.heading_gm_tau_s),
            ("egi.velocity_gm_tau_s", e.velocity_gm_tau_s),
            ("egi.attitude_hz", e.attitude_hz),
            ("egi.heading_hz", e.heading_hz),
            ("egi.velocity_hz", e.velocity_hz),
            ("fuel.gm_tau_s", f.gm_tau_s),
            ("fuel.update_hz", f.update_hz),
        ];
        for (field, value) in positive.into_iter().chain(positive_egi) {
            if !(value.is_finite() && value > 0.0) {
                return Err(SensorConfigError::Invalid {
                    field,
                    value,
                    why: "must be > 0",
                });
            }
        }
        for (field, value) in [
            ("imu.antialias_cutoff_hz", self.imu.antialias_cutoff_hz),
            (
                "surfaces.antialias_cutoff_hz",
                self.surfaces.antialias_cutoff_hz,
            ),
        ] {
            if !(0.0..SIM_HZ as f64 / 2.0).contains(&value) {
                return Err(SensorConfigError::Invalid {
                    field,
                    value,
                    why: "must be 0 (none) or below 60 Hz (half the 120 Hz simulation rate)",
                });
            }
        }
        let rates = [
            ("gps.update_hz", self.gps.update_hz),
            ("egi.attitude_hz", e.attitude_hz),
            ("egi.heading_hz", e.heading_hz),
            ("egi.velocity_hz", e.velocity_hz),
            ("fuel.update_hz", f.update_hz),
        ];
        for (field, value) in rates {
            if value > SIM_HZ as f64 {
                return Err(SensorConfigError::Invalid {
                    field,
                    value,
                    why: "cannot exceed the 120 Hz simulation rate",
                });
            }
        }
        if self.imu.lever_arm_m.iter().any(|v| !v.is_finite()) {
            return Err(SensorConfigError::Invalid {
                field: "imu.lever_arm_m",
                value: f64::NAN,
                why: "must be finite",
            });
        }
        Ok(())
    }
}

/// Truth the sensors see at one 120 Hz step (SI; surfaces in degrees).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SensorInput {
    /// Body rates p, q, r relative to inertial space, rad/s (JSBSim `velocities/{p,q,r}i-rad_sec`):
    /// what a gyro measures, so the Earth's rotation (7.292115e-5 rad/s = 15.04 °/h) is in it, not
    /// only the Earth-relative `velocities/{p,q,r}-rad_sec`.
    pub omega_rps: [f64; 3],
    /// Body angular accelerations, rad/s².
    pub omega_dot_rps2: [f64; 3],
    /// Specific force at the CG, body axes, m/s² (no gravity).
    pub f_cg_mps2: [f64; 3],
    pub gps_speed_mps: f64,
    pub alt_msl_m: f64,
    /// Surface positions, degrees, in `aircraft::SURFACE_CHANNELS` order.
    pub surfaces_deg: [f64; SURFACE_CHANNELS.len()],
    pub throttle_norm: f64,
    /// Euler angles φ, θ, ψ (3-2-1, body to local NED), rad; ψ in [0, 2π).
    pub euler_rad: [f64; 3],
    /// Body rates relative to the Earth, rad/s (`velocities/{p,q,r}-rad_sec`): what moves the EGI's
    /// lever arm relative to the ground.
    pub omega_earth_rps: [f64; 3],
    /// Velocity of the CG over the ground, local NED, m/s.
    pub v_ned_mps: [f64; 3],
    /// Fuel on board, kg.
    pub fuel_kg: f64,
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Specific force at a point `r` from the CG of a rigid body: f_cg + ω̇×r + ω×(ω×r).
pub fn specific_force_at(
    f_cg: [f64; 3],
    omega: [f64; 3],
    omega_dot: [f64; 3],
    r: [f64; 3],
) -> [f64; 3] {
    let t = cross(omega_dot, r);
    let c = cross(omega, cross(omega, r));
    [
        f_cg[0] + t[0] + c[0],
        f_cg[1] + t[1] + c[1],
        f_cg[2] + t[2] + c[2],
    ]
}

/// First-order Gauss-Markov process with steady-state σ and correlation time τ, stepped at 120 Hz.
#[derive(Clone, Debug)]
struct GaussMarkov {
    phi: f64,
    drive: f64,
    x: f64,
}

impl GaussMarkov {
    fn new(sigma: f64, tau_s: f64, rng: &mut ChaCha12Rng) -> Self {
        let phi = (-DT / tau_s).exp();
        let x0: f64 = StandardNormal.sample(rng);
        GaussMarkov {
            phi,
            drive: sigma * (1.0 - phi * phi).sqrt(),
            // Start in steady state: the flight did not just switch the IMU on.
            x: sigma * x0,
        }
    }
    fn step(&mut self, rng: &mut ChaCha12Rng) -> f64 {
        let w: f64 = StandardNormal.sample(rng);
        self.x = self.phi * self.x + self.drive * w;
        self.x
    }
}

/// 2nd-order Butterworth low-pass (bilinear transform, prewarped), direct form I.
#[derive(Clone, Debug)]
struct Biquad {
    b: [f64; 3],
    a: [f64; 2],
    x: [f64; 2],
    y: [f64; 2],
    primed: bool,
}

impl Biquad {
    fn lowpass(cutoff_hz: f64) -> Option<Self> {
        if cutoff_hz <= 0.0 {
            return None;
        }
        let k = (std::f64::consts::PI * cutoff_hz * DT).tan();
        let q = std::f64::consts::FRAC_1_SQRT_2;
        let norm = 1.0 / (1.0 + k / q + k * k);
        let b0 = k * k * norm;
        Some(Biquad {
            b: [b0, 2.0 * b0, b0],
            a: [2.0 * (k * k - 1.0) * norm, (1.0 - k / q + k * k) * norm],
            x: [0.0; 2],
            y: [0.0; 2],
            primed: false,
        })
    }
    fn step(&mut self, x: f64) -> f64 {
        if !self.primed {
            // Start at rest on the first input instead of ringing up from zero.
            self.x = [x; 2];
            self.y = [x; 2];
            self.primed = true;
        }
        let y = self.b[0] * x + self.b[1] * self.x[0] + self.b[2] * self.x[1]
            - self.a[0] * self.y[0]
            - self.a[1] * self.y[1];
        self.x = [x, self.x[0]];
        self.y = [y, self.y[0]];
        y
    }
}

/// One IMU axis: errors, quantization, lag and anti-alias filter.
#[derive(Clone, Debug)]
pub struct ImuAxis {
    turn_on: f64,
    in_run: GaussMarkov,
    noise_sigma: f64,
    quantum: f64,
    residual: f64,
    lag_alpha: f64,
    lag: Option<f64>,
    aa: Option<Biquad>,
}

/// What [`ImuAxis::filter`] gives for one raw sample.
#[derive(Clone, Copy, Debug)]
struct AxisOutput {
    /// The unit's output: the raw sample through the sensor's lag.
    unit: f64,
    /// That output through the flight computer's anti-alias filter (the 20 Hz channel's value).
    channel: f64,
}

impl ImuAxis {
    fn new(e: &InertialErrors, lag_tau_s: f64, aa_hz: f64, rng: &mut ChaCha12Rng) -> Self {
        let t: f64 = StandardNormal.sample(rng);
        ImuAxis {
            turn_on: e.turn_on_bias_sigma * t,
            in_run: GaussMarkov::new(e.in_run_bias_sigma, e.in_run_bias_tau_s, rng),
            // Discrete white noise at 120 Hz from a density: σ = N·√fs.
            noise_sigma: e.noise_density / DT.sqrt(),
            quantum: e.quantum,
            residual: 0.0,
            lag_alpha: if lag_tau_s > 0.0 {
                1.0 - (-DT / lag_tau_s).exp()
            } else {
                1.0
            },
            lag: None,
            aa: Biquad::lowpass(aa_hz),
        }
    }

    /// The raw 120 Hz output (errors + quantization), before lag and anti-alias filtering.
    pub fn raw(&mut self, truth: f64, extra_bias: f64, rng: &mut ChaCha12Rng) -> f64 {
        let w: f64 = StandardNormal.sample(rng);
        let v = truth + self.turn_on + self.in_run.step(rng) + extra_bias + self.noise_sigma * w;
        if self.quantum > 0.0 {
            // An integrating IMU outputs whole Δθ/Δv counts and carries the remainder to the next
            // interval, so quantization error does not accumulate in the integral.
            let acc = v * DT + self.residual;
            let counts = (acc / self.quantum).round();
            self.residual = acc - counts * self.quantum;
            counts * self.quantum / DT
        } else {
            v
        }
    }

    /// Lag, then anti-alias filter, applied to one raw sample.
    fn filter(&mut self, raw: f64) -> AxisOutput {
        let lagged = match self.lag {
            None => raw,
            Some(y) => y + self.lag_alpha * (raw - y),
        };
        self.lag = Some(lagged);
        let channel = match &mut self.aa {
            Some(f) => f.step(lagged),
            None => lagged,
        };
        AxisOutput {
            unit: lagged,
            channel,
        }
    }

    /// The turn-on bias drawn for this flight.
    pub fn turn_on_bias(&self) -> f64 {
        self.turn_on
    }
}

/// Scale-factor and misalignment errors of one sensor triad, drawn once per flight: E = S + M with
/// S = diag(s) (s ~ N(0, σ_sf)) and M zero on the diagonal (elements ~ N(0, σ_mis), rad). Always
/// nine draws in row-major order, whatever the σ, so the rest of the random stream does not shift
/// when a σ is set to zero.
fn draw_triad_errors(e: &InertialErrors, rng: &mut ChaCha12Rng) -> [[f64; 3]; 3] {
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            let n: f64 = StandardNormal.sample(rng);
            let sigma = if i == j {
                e.scale_factor_sigma
            } else {
                e.misalignment_sigma_rad
            };
            *v = sigma * n;
        }
    }
    m
}

/// (I + E)·v: what a triad with scale-factor/misalignment matrix E senses of the true vector v.
fn through_triad(e: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    let mut out = v;
    for (o, row) in out.iter_mut().zip(e) {
        *o += row[0] * v[0] + row[1] * v[1] + row[2] * v[2];
    }
    out
}

pub(crate) fn quantize(v: f64, q: f64) -> f64 {
    if q > 0.0 { (v / q).round() * q } else { v }
}

/// Body → local NED direction cosine matrix of the 3-2-1 Euler angles φ, θ, ψ.
fn body_to_ned(euler: [f64; 3]) -> [[f64; 3]; 3] {
    let (sf, cf) = euler[0].sin_cos();
    let (st, ct) = euler[1].sin_cos();
    let (sp, cp) = euler[2].sin_cos();
    [
        [ct * cp, sf * st * cp - cf * sp, cf * st * cp + sf * sp],
        [ct * sp, sf * st * sp + cf * cp, cf * st * sp - sf * cp],
        [-st, sf * ct, cf * ct],
    ]
}

/// `a` wrapped to [lo, lo + 2π).
fn wrap(a: f64, lo: f64) -> f64 {
    lo + (a - lo).rem_euclid(std::f64::consts::TAU)
}

/// Steps of the 120 Hz simulation between outputs at `hz` (at least 1).
fn every_steps(hz: f64) -> u64 {
    ((SIM_HZ as f64 / hz).round() as u64).max(1)
}

/// The EGI and the fuel gauge of one flight (the EGI suite's channels beyond Table 1).
struct EgiModel {
    cfg: EgiConfig,
    fuel_cfg: FuelConfig,
    rng: ChaCha12Rng,
    /// Gauss-Markov errors: roll, pitch, heading (rad), velocity N, E, D (m/s).
    gm: [GaussMarkov; 6],
    /// Truth (φ, θ, ψ, v_N, v_E, v_D at the EGI) of the last `delay_steps + 1` steps.
    delay: VecDeque<[f64; 6]>,
    delay_steps: usize,
    /// Outputs, held between updates: roll, pitch, heading, v_N, v_E, v_D.
    held: [f64; 6],
    fuel_bias_kg: f64,
    fuel_scale: f64,
    fuel_gm: GaussMarkov,
    fuel_held: f64,
    lever_arm_m: [f64; 3],
    /// Per-flight output phase of attitude, heading, velocity and fuel, in 120 Hz steps: the EGI's
    /// and the gauge's clocks are not synchronised with the 20 Hz frames.
    phase: [u64; 4],
}

impl EgiModel {
    fn new(cfg: &SensorConfig, seed: u64) -> Self {
        let mut rng = ChaCha12Rng::seed_from_u64(seed);
        rng.set_stream(EGI_STREAM);
        let e = &cfg.egi;
        let f = &cfg.fuel;
        let att = (e.attitude_gm_sigma_deg.to_radians(), e.attitude_gm_tau_s);
        let hdg = (e.heading_gm_sigma_deg.to_radians(), e.heading_gm_tau_s);
        let vel = (e.velocity_gm_sigma_mps, e.velocity_gm_tau_s);
        let gm = [att, att, hdg, vel, vel, vel].map(|(s, t)| GaussMarkov::new(s, t, &mut rng));
        let b: f64 = StandardNormal.sample(&mut rng);
        let k: f64 = StandardNormal.sample(&mut rng);
        let fuel_gm = GaussMarkov::new(f.gm_sigma_fs * f.full_scale_kg, f.gm_tau_s, &mut rng);
        let phase = [e.attitude_hz, e.heading_hz, e.velocity_hz, f.update_hz]
            .map(|hz| rng.random_range(0..every_steps(hz)));
        EgiModel {
            phase,
            gm,
            delay: VecDeque::new(),
            delay_steps: (e.latency_s * SIM_HZ as f64).round() as usize,
            held: [f64::NAN; 6],
            fuel_bias_kg: f.bias_sigma_fs * f.full_scale_kg * b,
            fuel_scale: f.scale_factor_sigma * k,
            fuel_gm,
            fuel_held: f64::NAN,
            // The EGI's IMU is the IMU of the Table 1 suite: its velocity is that point's.
            lever_arm_m: cfg.imu.lever_arm_m,
            cfg: e.clone(),
            fuel_cfg: f.clone(),
            rng,
        }
    }

    /// One 120 Hz step (`step` counts from 0): writes the EGI channels and the fuel quantity.
    fn step(&mut self, step: u64, t: &SensorInput, out: &mut [f64; CHANNELS]) {
        // Velocity of the EGI (at the IMU) over the ground: v_cg + C_bn (ω × r).
        let c = body_to_ned(t.euler_rad);
        let w = cross(t.omega_earth_rps, self.lever_arm_m);
        let mut v = t.v_ned_mps;
        for (vi, row) in v.iter_mut().zip(&c) {
            *vi += row[0] * w[0] + row[1] * w[1] + row[2] * w[2];
        }
        let [phi, theta, psi] = t.euler_rad;
        self.delay.push_back([phi, theta, psi, v[0], v[1], v[2]]);
        while self.delay.len() > self.delay_steps + 1 {
            self.delay.pop_front();
        }
        let truth = self.delay.front().copied().unwrap_or_default();
        // The slow errors evolve every step whatever the output rate.
        let mut err = [0.0; 6];
        for (e, g) in err.iter_mut().zip(self.gm.iter_mut()) {
            *e = g.step(&mut self.rng);
        }
        let e = &self.cfg;
        let groups = [
            (0..2, e.attitude_hz, e.attitude_noise_sigma_deg.to_radians()),
            (2..3, e.heading_hz, e.heading_noise_sigma_deg.to_radians()),
            (3..6, e.velocity_hz, e.velocity_noise_sigma_mps),
        ];
        // The first step always updates, so no output is ever NaN.
        for ((range, hz, sigma), phase) in groups.into_iter().zip(self.phase) {
            if step == 0 || (step + phase).is_multiple_of(every_steps(hz)) {
                for k in range {
                    let n: f64 = StandardNormal.sample(&mut self.rng);
                    self.held[k] = truth[k] + err[k] + sigma * n;
                }
            }
        }
        let held = self.held;
        out[Channel::Roll.index()] = wrap(held[0], -std::f64::consts::PI);
        out[Channel::Pitch.index()] = held[1];
        out[Channel::Heading.index()] = wrap(held[2], 0.0);
        out[Channel::VelNorth.index()] = held[3];
        out[Channel::VelEast.index()] = held[4];
        out[Channel::VelDown.index()] = held[5];

        let f = &self.fuel_cfg;
        let slow = self.fuel_gm.step(&mut self.rng);
        if step == 0 || (step + self.phase[3]).is_multiple_of(every_steps(f.update_hz)) {
            let reading = t.fuel_kg * (1.0 + self.fuel_scale) + self.fuel_bias_kg + slow;
            self.fuel_held = quantize(reading.max(0.0), f.quantum_kg);
        }
        out[Channel::Fuel.index()] = self.fuel_held;
    }
}

/// The steps at which [`SensorModel::step`] uses the inputs it does not need at every step. Step 0
/// uses every input; every input not named here is used at every step. On any other step such an
/// input may be anything, NaN included: the outputs do not change (tested), so a simulation can
/// skip reading it there (`crate::fly`: each property read is a Python call).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InputSchedule {
    /// `gps_speed_mps` and `alt_msl_m`: the truth behind each GPS fix, `latency` before it.
    pub gps: Every,
    /// `euler_rad[0..2]` (roll, pitch): the EGI's attitude output.
    pub attitude: Every,
    /// `euler_rad[2]` (heading): the EGI's heading output.
    pub heading: Every,
    /// `omega_earth_rps`, `v_ned_mps` and all three of `euler_rad` (the lever arm turned into NED):
    /// the EGI's velocity output. The Euler angles are used on these steps as well as their own.
    pub egi_velocity: Every,
    /// `fuel_kg`: the gauge's updates.
    pub fuel: Every,
}

/// The stateful sensor suite of one flight.
pub struct SensorModel {
    cfg: SensorConfig,
    rng: ChaCha12Rng,
    gyro: [ImuAxis; 3],
    accel: [ImuAxis; 3],
    /// Per-flight scale-factor/misalignment matrices E (sensed = (I + E)·true).
    gyro_triad: [[f64; 3]; 3],
    accel_triad: [[f64; 3]; 3],
    gps_alt_bias: GaussMarkov,
    gps_delay: VecDeque<(f64, f64)>,
    gps_delay_steps: usize,
    gps_every_steps: u64,
    gps_held: (f64, f64),
    /// Anti-alias filters of the seven surface channels, in [`SensorModel::step`]'s order.
    surface_aa: [Option<Biquad>; SURFACE_CHANNELS.len()],
    steps: u64,
    egi: EgiModel,
    /// The 120 Hz outputs of the last step, in [`Channel`] order (NaN for the channels without
    /// one).
    fast_out: [f64; CHANNELS],
}

impl SensorModel {
    /// A fresh suite; `seed` fixes every random draw (same seed, same inputs → same outputs).
    pub fn new(cfg: &SensorConfig, seed: u64) -> Self {
        let mut rng = ChaCha12Rng::seed_from_u64(seed);
        let i = &cfg.imu;
        let mut axis =
            |e: &InertialErrors| ImuAxis::new(e, i.lag_tau_s, i.antialias_cutoff_hz, &mut rng);
        let gyro = [axis(&i.gyro), axis(&i.gyro), axis(&i.gyro)];
        let accel = [axis(&i.accel), axis(&i.accel), axis(&i.accel)];
        let gps_alt_bias =
            GaussMarkov::new(cfg.gps.alt_bias_sigma_m, cfg.gps.alt_bias_tau_s, &mut rng);
        // Drawn after the older terms, so a seed still gives the same turn-on and GPS biases.
        let gyro_triad = draw_triad_errors(&i.gyro, &mut rng);
        let accel_triad = draw_triad_errors(&i.accel, &mut rng);
        SensorModel {
            gyro,
            accel,
            gyro_triad,
            accel_triad,
            gps_alt_bias,
            gps_delay: VecDeque::new(),
            gps_delay_steps: (cfg.gps.latency_s * SIM_HZ as f64).round() as usize,
            gps_every_steps: ((SIM_HZ as f64 / cfg.gps.update_hz).round() as u64).max(1),
            gps_held: (f64::NAN, f64::NAN),
            surface_aa: std::array::from_fn(|_| Biquad::lowpass(cfg.surfaces.antialias_cutoff_hz)),
            steps: 0,
            egi: EgiModel::new(cfg, seed),
            fast_out: [f64::NAN; CHANNELS],
            cfg: cfg.clone(),
            rng,
        }
    }

    /// When this flight's models use their slowly sampled inputs ([`InputSchedule`]).
    pub fn input_schedule(&self) -> InputSchedule {
        let gps_lag = self.gps_delay_steps as u64;
        let e = &self.egi;
        let lag = e.delay_steps as u64;
        let egi = |hz: f64, phase: u64| Every::before(every_steps(hz), phase, lag);
        InputSchedule {
            gps: Every::before(self.gps_every_steps, 0, gps_lag),
            attitude: egi(e.cfg.attitude_hz, e.phase[0]),
            heading: egi(e.cfg.heading_hz, e.phase[1]),
            egi_velocity: egi(e.cfg.velocity_hz, e.phase[2]),
            fuel: Every::before(every_steps(e.fuel_cfg.update_hz), e.phase[3], 0),
        }
    }

    /// The per-axis IMU models (gyro p, q, r), e.g. to read the drawn turn-on biases.
    pub fn gyro_axes(&self) -> &[ImuAxis; 3] {
        &self.gyro
    }

    /// The per-axis accelerometer models (x, y, z), e.g. to read the drawn turn-on biases.
    pub fn accel_axes(&self) -> &[ImuAxis; 3] {
        &self.accel
    }

    /// The gyro scale-factor/misalignment matrix E drawn for this flight (sensed rate =
    /// (I + E)·true rate): diagonal = scale-factor errors, off-diagonal = misalignment, rad. For
    /// tests and error analysis; the model itself does not expose it to the estimator.
    pub fn gyro_scale_misalignment(&self) -> [[f64; 3]; 3] {
        self.gyro_triad
    }

    /// The accelerometer scale-factor/misalignment matrix drawn for this flight, as
    /// [`SensorModel::gyro_scale_misalignment`].
    pub fn accel_scale_misalignment(&self) -> [[f64; 3]; 3] {
        self.accel_triad
    }

    /// The raw 120 Hz output of gyro `axis` for a truth rate (errors + quantization, no lag or
    /// anti-alias filter, no g term, no scale factor or misalignment): for measuring the per-axis
    /// error model back in tests.
    pub fn gyro_raw_for_test(&mut self, axis: usize, truth_rps: f64) -> f64 {
        match self.gyro.get_mut(axis) {
            Some(a) => a.raw(truth_rps, 0.0, &mut self.rng),
            None => f64::NAN,
        }
    }

    /// The raw 120 Hz IMU output for one truth step, gyro p, q, r (rad/s) then accel x, y, z
    /// (m/s²): the whole error model of [`SensorModel::step`] (lever arm, scale factor and
    /// misalignment, biases, g term, noise, quantization) without the lag and anti-alias filter,
    /// and without stepping GPS or surfaces. For measuring the error model back in tests.
    pub fn imu_raw_for_test(&mut self, t: &SensorInput) -> [f64; 6] {
        let (g, a) = self.imu_raw(t);
        [g[0], g[1], g[2], a[0], a[1], a[2]]
    }

    /// Raw gyro and accelerometer triads for one truth step (before lag and anti-alias filter).
    fn imu_raw(&mut self, t: &SensorInput) -> ([f64; 3], [f64; 3]) {
        let f_imu = specific_force_at(
            t.f_cg_mps2,
            t.omega_rps,
            t.omega_dot_rps2,
            self.cfg.imu.lever_arm_m,
        );
        // Scale factor and misalignment act on the true vector, before the per-axis bias and noise:
        // they are errors of the instrument's gain and of where its input axis points.
        let omega_sensed = through_triad(&self.gyro_triad, t.omega_rps);
        let f_sensed = through_triad(&self.accel_triad, f_imu);
        let gsens = self.cfg.imu.gyro_g_sensitivity_rps_per_mps2;
        let mut gyro = [0.0; 3];
        for (k, g) in gyro.iter_mut().enumerate() {
            *g = self.gyro[k].raw(omega_sensed[k], gsens * f_imu[k], &mut self.rng);
        }
        let mut accel = [0.0; 3];
        for (k, a) in accel.iter_mut().enumerate() {
            *a = self.accel[k].raw(f_sensed[k], 0.0, &mut self.rng);
        }
        (gyro, accel)
    }

    /// The sensors' 120 Hz output at the last [`SensorModel::step`], in [`SUB_CHANNELS`] order
    /// (NaN before the first step): the IMU unit's gyro p, q, r (rad/s) and specific force x, y, z
    /// (m/s²), every error of its path and its lag; then the seven surface positions (degrees),
    /// truth plus the step's ADC noise draw, quantized. Both before the flight computer's
    /// anti-alias filter (the 20 Hz channels carry the noise and quantization after it).
    pub fn fast_output(&self) -> SubSampleSi {
        SUB_CHANNELS.map(|c| self.fast_out[c.index()])
    }

    /// One 120 Hz step: the sensed channels of every suite at this instant.
    pub fn step(&mut self, t: &SensorInput) -> [f64; CHANNELS] {
        let mut out = [f64::NAN; CHANNELS];
        let (gyro_raw, accel_raw) = self.imu_raw(t);
        for k in 0..3 {
            let g = self.gyro[k].filter(gyro_raw[k]);
            let a = self.accel[k].filter(accel_raw[k]);
            out[Channel::GyroP.index() + k] = g.channel;
            out[Channel::AccelX.index() + k] = a.channel;
            self.fast_out[Channel::GyroP.index() + k] = g.unit;
            self.fast_out[Channel::AccelX.index() + k] = a.unit;
        }

        // GPS: a fix is the truth `latency` ago plus noise, refreshed at the fix rate and held.
        self.gps_delay.push_back((t.gps_speed_mps, t.alt_msl_m));
        while self.gps_delay.len() > self.gps_delay_steps + 1 {
            self.gps_delay.pop_front();
        }
        let alt_bias = self.gps_alt_bias.step(&mut self.rng);
        if self.steps.is_multiple_of(self.gps_every_steps) {
            let (v, h) = self
                .gps_delay
                .front()
                .copied()
                .unwrap_or((t.gps_speed_mps, t.alt_msl_m));
            let nv: f64 = StandardNormal.sample(&mut self.rng);
            let nh: f64 = StandardNormal.sample(&mut self.rng);
            self.gps_held = (
                v + self.cfg.gps.speed_noise_sigma_mps * nv,
                h + alt_bias + self.cfg.gps.alt_noise_sigma_m * nh,
            );
        }
        out[Channel::GpsSpeed.index()] = self.gps_held.0;
        out[Channel::GpsAlt.index()] = self.gps_held.1;

        let s = &self.cfg.surfaces;
        let surfaces = SURFACE_CHANNELS
            .into_iter()
            .zip(AIRCRAFT.surfaces)
            .zip(t.surfaces_deg);
        for (((c, sensor), v), aa) in surfaces.zip(self.surface_aa.iter_mut()) {
            // A surface the airframe does not have has no sensor: its channel is 0.
            if sensor.is_none() {
                out[c.index()] = 0.0;
                self.fast_out[c.index()] = 0.0;
                continue;
            }
            let filtered = aa.as_mut().map_or(v, |f| f.step(v));
            let n: f64 = StandardNormal.sample(&mut self.rng);
            out[c.index()] = quantize(filtered + s.noise_sigma_deg * n, s.quantum_deg);
            self.fast_out[c.index()] = quantize(v + s.noise_sigma_deg * n, s.quantum_deg);
        }
        let n: f64 = StandardNormal.sample(&mut self.rng);
        out[Channel::Throttle.index()] = quantize(
            t.throttle_norm + s.throttle_noise_sigma * n,
            s.throttle_quantum,
        );
        // Last, and from its own stream: nothing above depends on it.
        self.egi.step(self.steps, t, &mut out);
        self.steps += 1;
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `--sensors` table may give any subset of its fields (docs/sensors.md): in `[imu.gyro]`
    /// and `[imu.accel]` too, each field left out taking the built-in gyro's or accelerometer's
    /// value, the scale factor and misalignment included; an unknown field is still refused.
    #[test]
    fn a_partial_inertial_table_takes_the_defaults_for_what_it_leaves_out() {
        let d = ImuConfig::default();
        let c: SensorConfig = toml::from_str(
            "[imu.gyro]\nturn_on_bias_sigma = 4.8e-5\n[imu.accel]\nmisalignment_sigma_rad = 1e-3\n",
        )
        .unwrap();
        assert_eq!(
            c.imu.gyro,
            InertialErrors {
                turn_on_bias_sigma: 4.8e-5,
                ..d.gyro.clone()
            }
        );
        assert_eq!(c.imu.gyro.scale_factor_sigma, 100e-6);
        assert_eq!(
            c.imu.accel,
            InertialErrors {
                misalignment_sigma_rad: 1e-3,
                ..d.accel.clone()
            }
        );
        assert_eq!(c.imu.accel.scale_factor_sigma, 300e-6);
        assert_eq!(c.imu.lag_tau_s, d.lag_tau_s);
        // An empty table is the built-in sensor; a whole one is what it says.
        let c: SensorConfig = toml::from_str("[imu.accel]\n").unwrap();
        assert_eq!(c, SensorConfig::default());
        let json = serde_json::to_string(&SensorConfig::default()).unwrap();
        assert_eq!(
            serde_json::from_str::<SensorConfig>(&json).unwrap(),
            SensorConfig::default()
        );
        let e = toml::from_str::<SensorConfig>("[imu.gyro]\nbias = 1.0\n").unwrap_err();
        assert!(e.to_string().contains("bias"), "{e}");
    }

    #[test]
    fn lever_arm_pull_up_adds_centripetal_and_tangential_terms() {
        // Pitching at 0.5 rad/s with 1 rad/s² pitch acceleration, IMU 2 m ahead of the CG.
        let f = specific_force_at(
            [0.0, 0.0, -9.8],
            [0.0, 0.5, 0.0],
            [0.0, 1.0, 0.0],
            [2.0, 0.0, 0.0],
        );
        // ω̇×r = (0,1,0)×(2,0,0) = (0,0,-2); ω×(ω×r) = -(0.25)·(2,0,0) = (-0.5,0,0).
        assert!((f[0] + 0.5).abs() < 1e-12);
        assert!((f[2] + 11.8).abs() < 1e-12);
    }

    #[test]
    fn triad_matrix_is_identity_plus_scale_factor_plus_cross_axis() {
        let e = [[1e-3, 2e-3, 0.0], [0.0, -1e-3, 0.0], [3e-3, 0.0, 0.0]];
        let v = through_triad(&e, [2.0, -1.0, 0.5]);
        // x: 2·(1 + 1e-3) + 2e-3·(−1); y: −1·(1 − 1e-3); z: 0.5 + 3e-3·2.
        assert!((v[0] - (2.002 - 0.002)).abs() < 1e-15);
        assert!((v[1] + 0.999).abs() < 1e-15);
        assert!((v[2] - 0.506).abs() < 1e-15);
    }

    #[test]
    fn triad_draws_use_their_own_sigma_and_a_fixed_count() {
        let mut e = ImuConfig::default().gyro;
        e.scale_factor_sigma = 0.0;
        e.misalignment_sigma_rad = 1e-3;
        let mut rng = ChaCha12Rng::seed_from_u64(7);
        let m = draw_triad_errors(&e, &mut rng);
        for (i, row) in m.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                assert_eq!(*v == 0.0, i == j, "[{i}][{j}] = {v}");
            }
        }
        // Nine draws whatever the σ: the next draw is the same as with both σ non-zero.
        let next_a: f64 = StandardNormal.sample(&mut rng);
        e.scale_factor_sigma = 1e-4;
        let mut rng = ChaCha12Rng::seed_from_u64(7);
        draw_triad_errors(&e, &mut rng);
        let next_b: f64 = StandardNormal.sample(&mut rng);
        assert_eq!(next_a, next_b);
    }

    fn cruise() -> SensorInput {
        SensorInput {
            omega_rps: [0.01, 0.02, 0.0],
            f_cg_mps2: [0.1, 0.0, -9.8],
            gps_speed_mps: 200.0,
            alt_msl_m: 3000.0,
            euler_rad: [0.1, 0.05, 6.2],
            v_ned_mps: [150.0, 130.0, -2.0],
            fuel_kg: 1000.0,
            ..SensorInput::default()
        }
    }

    /// A smooth but never repeating flight: every input moves, each at its own rate.
    fn wandering(k: u64) -> SensorInput {
        let t = k as f64 / SIM_HZ as f64;
        let w = |f: f64, a: f64, b: f64| b + a * (f * t).sin();
        SensorInput {
            omega_rps: [w(1.1, 0.3, 0.0), w(0.7, 0.2, 0.01), w(1.9, 0.1, 0.0)],
            omega_dot_rps2: [w(2.3, 0.5, 0.0), w(1.3, 0.4, 0.0), w(0.9, 0.2, 0.0)],
            f_cg_mps2: [w(0.3, 2.0, 1.0), w(1.7, 1.0, 0.0), w(0.5, 5.0, -9.8)],
            gps_speed_mps: w(0.2, 30.0, 180.0),
            alt_msl_m: w(0.1, 300.0, 3000.0),
            // Elevator, aileron, rudder, LEF (`SURFACE_CHANNELS` order); the rest stay at 0.
            surfaces_deg: [
                w(0.9, 5.0, -2.0),
                w(1.5, 4.0, 0.0),
                w(2.5, 3.0, 0.0),
                w(0.4, 6.0, 8.0),
                0.0,
                0.0,
                0.0,
            ],
            throttle_norm: w(0.05, 0.3, 0.5),
            euler_rad: [w(0.6, 0.8, 0.0), w(0.35, 0.3, 0.05), w(0.15, 3.0, 3.2)],
            omega_earth_rps: [w(1.1, 0.3, 0.0), w(0.7, 0.2, 0.01), w(1.9, 0.1, 0.0)],
            v_ned_mps: [w(0.15, 150.0, 0.0), w(0.12, 150.0, 0.0), w(0.35, 20.0, 0.0)],
            fuel_kg: 3000.0 - 0.5 * t,
        }
    }

    /// The unit's 120 Hz output is what the flight computer's anti-alias filter reads: the
    /// documented 2nd-order Butterworth run over [`SensorModel::fast_output`] gives every 20 Hz IMU
    /// channel bit for bit; the output is the lagged raw sample (no anti-alias of its own). The
    /// 120 Hz positions of the surfaces the build's aircraft has follow the truth within the ADC's
    /// noise and quantum; the channel of a surface it does not have reads 0.
    #[test]
    fn the_imu_channels_are_the_anti_aliased_unit_output() {
        let cfg = SensorConfig::default();
        let mut m = SensorModel::new(&cfg, 3);
        let mut aa: [Biquad; 6] =
            std::array::from_fn(|_| Biquad::lowpass(cfg.imu.antialias_cutoff_hz).unwrap());
        let mut lag_gap: f64 = 0.0;
        let mut prev = [0.0; 6];
        for k in 0..2400 {
            let out = m.step(&wandering(k));
            let fast = m.fast_output();
            let t = wandering(k);
            // Every surface sub-channel (they follow the IMU's six); one the build's aircraft does
            // not have reads 0.
            let fast_surfaces = fast
                .iter()
                .skip(SUB_CHANNELS.len() - SURFACE_CHANNELS.len());
            let surfaces = SURFACE_CHANNELS.iter().zip(AIRCRAFT.surfaces);
            for (((c, sensor), truth), &v) in surfaces.zip(t.surfaces_deg).zip(fast_surfaces) {
                if sensor.is_some() {
                    assert!((v - truth).abs() < 0.2, "step {k} {c:?}: {v} vs {truth}");
                } else {
                    assert_eq!(v, 0.0, "step {k} {c:?}: no such surface");
                }
            }
            let unit = [fast[0], fast[1], fast[2], fast[3], fast[4], fast[5]];
            for (axis, f) in aa.iter_mut().enumerate() {
                let channel = out[Channel::GyroP.index() + axis];
                assert_eq!(
                    f.step(unit[axis]).to_bits(),
                    channel.to_bits(),
                    "step {k} axis {axis}"
                );
            }
            // The unit follows the 1.7 rad/s lateral specific force within its 3 ms lag, the
            // 6 Hz channel lags it by tens of ms: their gap is the anti-alias filter's.
            if k > 600 {
                lag_gap = lag_gap.max((unit[4] - out[Channel::AccelY.index()]).abs());
            }
            prev = unit;
        }
        assert!(prev.iter().all(|v| v.is_finite()));
        assert!(
            lag_gap > 0.01,
            "unit and channel differ by {lag_gap} at most"
        );
    }

    /// `t` with NaN in every input [`InputSchedule`] says step `k` does not use.
    fn unscheduled_nan(s: &InputSchedule, k: u64, mut t: SensorInput) -> SensorInput {
        let any = |e: &[Every]| k == 0 || e.iter().any(|e| e.contains(k));
        if !any(&[s.gps]) {
            t.gps_speed_mps = f64::NAN;
            t.alt_msl_m = f64::NAN;
        }
        if !any(&[s.attitude, s.egi_velocity]) {
            t.euler_rad[0] = f64::NAN;
            t.euler_rad[1] = f64::NAN;
        }
        if !any(&[s.heading, s.egi_velocity]) {
            t.euler_rad[2] = f64::NAN;
        }
        if !any(&[s.egi_velocity]) {
            t.omega_earth_rps = [f64::NAN; 3];
            t.v_ned_mps = [f64::NAN; 3];
        }
        if !any(&[s.fuel]) {
            t.fuel_kg = f64::NAN;
        }
        t
    }

    #[test]
    fn inputs_off_their_schedule_change_no_output_bit() {
        let mut odd = SensorConfig::default();
        odd.gps.update_hz = 7.0;
        odd.gps.latency_s = 0.23;
        odd.egi.attitude_hz = 64.0;
        odd.egi.heading_hz = 11.0;
        odd.egi.velocity_hz = 9.0;
        odd.egi.latency_s = 0.07;
        odd.fuel.update_hz = 0.5;
        for (cfg, seed) in [
            (SensorConfig::default(), 1),
            (SensorConfig::default(), 9),
            (odd, 4),
        ] {
            let mut full = SensorModel::new(&cfg, seed);
            let mut sparse = SensorModel::new(&cfg, seed);
            let s = sparse.input_schedule();
            let mut skipped = 0;
            for k in 0..3000 {
                let t = wandering(k);
                let masked = unscheduled_nan(&s, k, t);
                skipped += usize::from(masked.fuel_kg.is_nan());
                let (a, b) = (full.step(&t), sparse.step(&masked));
                for c in 0..CHANNELS {
                    assert_eq!(
                        a[c].to_bits(),
                        b[c].to_bits(),
                        "seed {seed} step {k} channel {c}"
                    );
                }
            }
            // The schedule does leave inputs out (else the test proves nothing).
            assert!(skipped > 2500, "{skipped}");
        }
    }

    #[test]
    fn every_before_names_the_steps_a_delayed_refresh_reads() {
        // Refreshed when (k + 3) % 12 == 0, i.e. k = 9, 21, …, reading the truth 5 steps old:
        // steps 4, 16, ….
        let e = Every::before(12, 3, 5);
        assert_eq!(
            e,
            Every {
                period: 12,
                offset: 4
            }
        );
        assert!(e.contains(16) && !e.contains(9));
        // A lag of whole periods lands on the refresh steps themselves.
        assert_eq!(
            Every::before(6, 0, 12),
            Every {
                period: 6,
                offset: 0
            }
        );
        assert_eq!(
            Every::before(0, 7, 7),
            Every {
                period: 1,
                offset: 0
            }
        );
    }

    #[test]
    fn egi_and_fuel_models_leave_the_table1_channels_alone() {
        let mut other = SensorConfig::default();
        other.egi.velocity_noise_sigma_mps = 3.0;
        other.egi.latency_s = 0.5;
        other.egi.attitude_hz = 7.0;
        other.fuel.update_hz = 10.0;
        let mut a = SensorModel::new(&SensorConfig::default(), 5);
        let mut b = SensorModel::new(&other, 5);
        let mut egi_differs = false;
        for _ in 0..2400 {
            let (x, y) = (a.step(&cruise()), b.step(&cruise()));
            assert_eq!(x[..TABLE1], y[..TABLE1]);
            egi_differs |= x[TABLE1..] != y[TABLE1..];
        }
        assert!(egi_differs);
    }
    const TABLE1: usize = estimator_core::channels::TABLE1_CHANNELS;

    #[test]
    fn egi_errors_have_their_configured_size_and_angles_wrap() {
        let egi = EgiConfig {
            attitude_gm_sigma_deg: 0.04,
            attitude_gm_tau_s: 0.5,
            attitude_noise_sigma_deg: 0.03,
            heading_gm_sigma_deg: 0.0,
            heading_noise_sigma_deg: 0.1,
            velocity_gm_sigma_mps: 0.03,
            velocity_gm_tau_s: 0.5,
            velocity_noise_sigma_mps: 0.04,
            attitude_hz: 120.0,
            heading_hz: 120.0,
            velocity_hz: 120.0,
            latency_s: 0.0,
            ..EgiConfig::default()
        };
        let mut cfg = SensorConfig {
            egi,
            ..SensorConfig::default()
        };
        cfg.imu.lever_arm_m = [0.0; 3];
        let mut truth = cruise();
        // Roll just below π and heading just below 2π: the errors push them across.
        truth.euler_rad = [
            std::f64::consts::PI - 1e-4,
            0.05,
            std::f64::consts::TAU - 1e-4,
        ];
        let mut m = SensorModel::new(&cfg, 11);
        let n = 120_000;
        let (mut roll, mut vel) = (Vec::new(), Vec::new());
        for _ in 0..n {
            let o = m.step(&truth);
            let r = o[Channel::Roll.index()];
            let h = o[Channel::Heading.index()];
            assert!(
                r > -std::f64::consts::PI && r <= std::f64::consts::PI,
                "{r}"
            );
            assert!((0.0..std::f64::consts::TAU).contains(&h), "{h}");
            roll.push(wrap(r - truth.euler_rad[0], -std::f64::consts::PI));
            vel.push(o[Channel::VelEast.index()] - truth.v_ned_mps[1]);
        }
        let sd = |v: &[f64]| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / v.len() as f64).sqrt()
        };
        let want_roll = 0.05f64.to_radians(); // √(0.04² + 0.03²)
        assert!((sd(&roll) / want_roll - 1.0).abs() < 0.1, "{}", sd(&roll));
        assert!((sd(&vel) / 0.05 - 1.0).abs() < 0.1, "{}", sd(&vel));
    }

    #[test]
    fn egi_velocity_is_the_imu_point_velocity_and_outputs_are_held() {
        // Pitching up at 1 rad/s with the EGI 2 m ahead of the CG: it moves 2 m/s up (v_D = -2).
        let mut cfg = SensorConfig::default();
        cfg.egi.velocity_gm_sigma_mps = 0.0;
        cfg.egi.velocity_noise_sigma_mps = 0.0;
        cfg.egi.latency_s = 0.0;
        cfg.imu.lever_arm_m = [2.0, 0.0, 0.0];
        let truth = SensorInput {
            euler_rad: [0.0, 0.0, 0.0],
            omega_earth_rps: [0.0, 1.0, 0.0],
            v_ned_mps: [200.0, 0.0, 0.0],
            ..cruise()
        };
        let mut m = SensorModel::new(&cfg, 3);
        let o = m.step(&truth);
        assert!((o[Channel::VelDown.index()] + 2.0).abs() < 1e-12);
        assert!((o[Channel::VelNorth.index()] - 200.0).abs() < 1e-12);
        // Fuel: refreshed at 1 Hz, in 10 lb counts, near the truth.
        let mut seen = std::collections::BTreeSet::new();
        for _ in 0..600 {
            let f = m.step(&truth)[Channel::Fuel.index()];
            let counts = f / cfg.fuel.quantum_kg;
            assert!((counts - counts.round()).abs() < 1e-9);
            assert!((f - 1000.0).abs() < 200.0, "{f}");
            seen.insert(f.to_bits());
        }
        assert!(seen.len() <= 6, "{} distinct readings in 5 s", seen.len());
    }

    #[test]
    fn butterworth_passes_dc_and_attenuates_near_nyquist() {
        let mut f = Biquad::lowpass(6.0).unwrap();
        let mut y = 0.0;
        for _ in 0..2000 {
            y = f.step(1.0);
        }
        assert!((y - 1.0).abs() < 1e-9);
        let mut f = Biquad::lowpass(6.0).unwrap();
        let mut peak: f64 = 0.0;
        for k in 0..4000 {
            // 50 Hz: would alias to 10 Hz at 20 Hz sampling.
            let v = f.step((2.0 * std::f64::consts::PI * 50.0 * k as f64 * DT).sin());
            if k > 1000 {
                peak = peak.max(v.abs());
            }
        }
        assert!(peak < 0.03, "50 Hz gain {peak}");
    }
}

#[cfg(test)]
mod surface_tests {
    use super::*;

    /// The rudder banging stop to stop every 120 Hz step (the stock F-16 yaw damper in heavy
    /// turbulence): point samples at 20 Hz read a stop; through the anti-alias filter the reading
    /// is the mean position, as the side force the accelerometers sense.
    #[test]
    fn surface_chatter_is_filtered_before_the_20_hz_samples() {
        let read = |cutoff_hz: f64| -> Vec<f64> {
            let mut cfg = SensorConfig::default();
            cfg.surfaces.noise_sigma_deg = 0.0;
            cfg.surfaces.antialias_cutoff_hz = cutoff_hz;
            let mut m = SensorModel::new(&cfg, 1);
            (0..1200)
                .map(|k| {
                    let rudder = if k % 2 == 0 { 30.0 } else { -30.0 };
                    let t = SensorInput {
                        surfaces_deg: [2.0, 0.0, rudder, 0.0, 0.0, 0.0, 0.0],
                        ..SensorInput::default()
                    };
                    m.step(&t)
                })
                .enumerate()
                .filter(|(k, _)| k % 6 == 0 && *k > 240)
                .map(|(_, o)| o[Channel::Rudder.index()])
                .collect()
        };
        let filtered = read(6.0);
        assert!(filtered.iter().all(|r| r.abs() <= 0.1), "{filtered:?}");
        let sampled = read(0.0);
        assert!(
            sampled.iter().all(|r| (r.abs() - 30.0).abs() < 1e-9),
            "{sampled:?}"
        );
        // A steady surface passes unchanged.
        let mut cfg = SensorConfig::default();
        cfg.surfaces.noise_sigma_deg = 0.0;
        let mut m = SensorModel::new(&cfg, 1);
        let t = SensorInput {
            surfaces_deg: [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            ..SensorInput::default()
        };
        let o = (0..600).map(|_| m.step(&t)).last().unwrap();
        assert!((o[Channel::Elevator.index()] - 2.0).abs() < 1e-9);
    }

    #[test]
    fn a_surface_cutoff_at_or_above_nyquist_is_refused() {
        let mut cfg = SensorConfig::default();
        cfg.surfaces.antialias_cutoff_hz = 60.0;
        assert!(cfg.validate().is_err());
        cfg.surfaces.antialias_cutoff_hz = -1.0;
        assert!(cfg.validate().is_err());
        cfg.surfaces.antialias_cutoff_hz = 0.0;
        assert!(cfg.validate().is_ok());
    }
}
