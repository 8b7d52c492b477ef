//! Flight records in memory: the truth and sensed values of one 20 Hz sample, a flight of them, its
//! generator zones, and the time base and units they use. No I/O: `dataset` reads and writes them,
//! `plant` fills them, everything downstream reads them.

use estimator_core::CHANNELS;
use serde::{Deserialize, Serialize};

/// JSBSim integration rate, Hz.
pub const SIM_HZ: u32 = 120;
/// Sample (sensor frame) rate of a flight record, Hz.
pub const SAMPLE_HZ: u32 = 20;
/// JSBSim steps per recorded sample.
pub const STEPS_PER_SAMPLE: u32 = SIM_HZ / SAMPLE_HZ;
/// Sub-samples per recorded sample, and the channels sub-sampled (the IMU's six axes and the
/// seven surface positions, before the flight computer's anti-alias filter): the IMU and the
/// surface position sensors deliver at the simulation rate, 120 Hz (`docs/sensors.md`, "Sensor
/// output rate"), as [`estimator_core::channels::Subsamples`] carries them.
pub use estimator_core::channels::{SUB_CHANNELS, SUBSAMPLES};
const _: () = assert!(SUBSAMPLES == STEPS_PER_SAMPLE as usize);
/// One 120 Hz output of the [`SUB_CHANNELS`], in that order, in SI units (degrees for surfaces).
pub type SubSampleSi = [f64; SUB_CHANNELS.len()];
/// The sensors' 120 Hz outputs over one 20 Hz period, oldest first: sub-sample `k` is the output
/// `SUBSAMPLES − 1 − k` simulation steps before the sample instant (the last one at it).
/// (The integer form a frame carries is [`estimator_core::channels::Subsamples`].)
pub type SubsamplesSi = [SubSampleSi; SUBSAMPLES];
/// The sub-samples of a sample that has none (a dataset older than format 5, a flight log without
/// them).
pub const NO_SUBSAMPLES: SubsamplesSi = [[f64::NAN; SUB_CHANNELS.len()]; SUBSAMPLES];
/// Feet to metres.
pub const FT_TO_M: f64 = 0.3048;
/// Pounds (mass) to kilograms.
pub const LB_TO_KG: f64 = 0.453_592_37;

/// A set of 120 Hz steps: the steps `k` with `k % period == offset`, counted from 0 (the steps
/// since a script was loaded, which are also `sensors::SensorModel::step`'s calls).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Every {
    /// At least 1.
    pub period: u64,
    /// Below `period`.
    pub offset: u64,
}

impl Every {
    /// Every `period`-th step, where `k + lead` is a multiple of `period`, `lag` steps earlier:
    /// the steps whose value a sensor refreshed on `(k + lead) % period == 0` reads when it reports
    /// the truth `lag` steps old.
    pub fn before(period: u64, lead: u64, lag: u64) -> Every {
        let period = period.max(1);
        let shift = (lead % period + lag % period) % period;
        Every {
            period,
            offset: (period - shift) % period,
        }
    }

    pub fn contains(self, k: u64) -> bool {
        k % self.period.max(1) == self.offset
    }
}

/// Truth columns, in CSV order (after `time_s`).
pub const TRUTH_COLUMNS: [&str; TRUTH_COUNT] = [
    "alpha_deg",
    "beta_deg",
    "u_aero_mps",
    "v_aero_mps",
    "w_aero_mps",
    "vt_mps",
    "mach",
    "qbar_pa",
    "alt_msl_m",
    "p_true_rps",
    "q_true_rps",
    "r_true_rps",
    "phi_deg",
    "theta_deg",
    "psi_deg",
    "nz_g",
    "mass_kg",
    "lat_deg",
    "lon_deg",
    "v_north_mps",
    "v_east_mps",
    "v_down_mps",
    "fuel_true_kg",
    "wind_north_mps",
    "wind_east_mps",
    "wind_down_mps",
];

/// Number of truth columns.
pub const TRUTH_COUNT: usize = 26;

/// Truth straight from JSBSim at a sample instant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Truth {
    pub alpha_deg: f64,
    pub beta_deg: f64,
    pub u_aero_mps: f64,
    pub v_aero_mps: f64,
    pub w_aero_mps: f64,
    pub vt_mps: f64,
    pub mach: f64,
    pub qbar_pa: f64,
    pub alt_msl_m: f64,
    pub p_true_rps: f64,
    pub q_true_rps: f64,
    pub r_true_rps: f64,
    pub phi_deg: f64,
    pub theta_deg: f64,
    pub psi_deg: f64,
    pub nz_g: f64,
    pub mass_kg: f64,
    /// Geodetic latitude (WGS84), degrees north.
    pub lat_deg: f64,
    /// Longitude, degrees east.
    pub lon_deg: f64,
    /// Velocity over the ground, local NED frame, at the CG, m/s.
    pub v_north_mps: f64,
    pub v_east_mps: f64,
    pub v_down_mps: f64,
    /// Fuel on board (all tanks), kg.
    pub fuel_kg: f64,
    /// Total wind (steady + turbulence + gusts) the aircraft flies in, NED, m/s: air data, truth only.
    pub wind_north_mps: f64,
    pub wind_east_mps: f64,
    pub wind_down_mps: f64,
}

impl Truth {
    /// Values in [`TRUTH_COLUMNS`] order.
    pub fn to_array(&self) -> [f64; TRUTH_COUNT] {
        [
            self.alpha_deg,
            self.beta_deg,
            self.u_aero_mps,
            self.v_aero_mps,
            self.w_aero_mps,
            self.vt_mps,
            self.mach,
            self.qbar_pa,
            self.alt_msl_m,
            self.p_true_rps,
            self.q_true_rps,
            self.r_true_rps,
            self.phi_deg,
            self.theta_deg,
            self.psi_deg,
            self.nz_g,
            self.mass_kg,
            self.lat_deg,
            self.lon_deg,
            self.v_north_mps,
            self.v_east_mps,
            self.v_down_mps,
            self.fuel_kg,
            self.wind_north_mps,
            self.wind_east_mps,
            self.wind_down_mps,
        ]
    }

    /// Inverse of [`Truth::to_array`].
    pub fn from_array(a: &[f64; TRUTH_COUNT]) -> Truth {
        Truth {
            alpha_deg: a[0],
            beta_deg: a[1],
            u_aero_mps: a[2],
            v_aero_mps: a[3],
            w_aero_mps: a[4],
            vt_mps: a[5],
            mach: a[6],
            qbar_pa: a[7],
            alt_msl_m: a[8],
            p_true_rps: a[9],
            q_true_rps: a[10],
            r_true_rps: a[11],
            phi_deg: a[12],
            theta_deg: a[13],
            psi_deg: a[14],
            nz_g: a[15],
            mass_kg: a[16],
            lat_deg: a[17],
            lon_deg: a[18],
            v_north_mps: a[19],
            v_east_mps: a[20],
            v_down_mps: a[21],
            fuel_kg: a[22],
            wind_north_mps: a[23],
            wind_east_mps: a[24],
            wind_down_mps: a[25],
        }
    }
}

/// One 20 Hz sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    pub time_s: f64,
    pub truth: Truth,
    /// The sensed channels in [`Channel`] order and SI units (degrees for surfaces); NaN for a
    /// channel the dataset does not carry.
    pub sensed: [f64; CHANNELS],
    /// The IMU's and the surface sensors' own outputs over the period that ends at this sample
    /// ([`SubsamplesSi`]; before the flight computer's anti-alias filter that makes their 20 Hz
    /// channels in `sensed`); [`NO_SUBSAMPLES`] when the flight does not carry them.
    pub sub: SubsamplesSi,
}

/// The maneuver generator's zones (Karali et al. 2023, Fig. 3), as its scripts code them in
/// `maneuver/zone`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Zone {
    /// Random maneuvers.
    Flight,
    /// A hazard (ground, ceiling, attitude, speed, α): the recovery law stops it.
    Danger,
    /// The attitude controller climbs back to the Flight Zone.
    Reclimb,
}

impl Zone {
    /// Position in [`ZoneTimes::from_steps`]' array.
    pub fn index(self) -> usize {
        match self {
            Zone::Flight => 0,
            Zone::Danger => 1,
            Zone::Reclimb => 2,
        }
    }

    /// The zone a `maneuver/zone` value codes (0, 1, 2), `None` for anything else (NaN: the script
    /// has no zone state).
    pub fn from_value(v: f64) -> Option<Zone> {
        match v {
            0.0 => Some(Zone::Flight),
            1.0 => Some(Zone::Danger),
            2.0 => Some(Zone::Reclimb),
            _ => None,
        }
    }
}

/// Time a flight spent in each zone, s (simulated time: JSBSim steps × dt, to the millisecond so
/// that the manifest's JSON gives back the same numbers).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ZoneTimes {
    pub flight_s: f64,
    pub danger_s: f64,
    pub reclimb_s: f64,
}

impl ZoneTimes {
    /// From the number of steps spent in each zone ([`Zone`] order) at `dt_s` per step.
    pub fn from_steps(steps: [u64; 3], dt_s: f64) -> ZoneTimes {
        let s = |n: u64| (n as f64 * dt_s * 1000.0).round() / 1000.0;
        ZoneTimes {
            flight_s: s(steps[0]),
            danger_s: s(steps[1]),
            reclimb_s: s(steps[2]),
        }
    }

    pub fn total_s(&self) -> f64 {
        self.flight_s + self.danger_s + self.reclimb_s
    }
}

/// One flight at 20 Hz.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Flight {
    pub name: String,
    pub samples: Vec<Sample>,
    /// Why the flight stops early (ground contact, NaN), or `None` if it ran to its end.
    pub cut: Option<String>,
    /// Time in each generator zone; `None` for a script without the generator's zone state.
    /// Not stored in the CSV (it is in the manifest).
    pub zones: Option<ZoneTimes>,
    /// Engine 0's state at each sample, as JSBSim flew it, for the flight-test record
    /// (`crate::boom`); empty for a flight read back from its CSV, which does not store it.
    pub engine: Vec<EngineState>,
}

/// One engine's state at a sample: what a flight-test aircraft's engine instrumentation reads.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EngineState {
    /// Core speed, % (`propulsion/engine/n2`; `None` for an engine without one, a piston engine).
    pub n2_pct: Option<f64>,
    /// The engine's throttle position (`fcs/throttle-pos-norm`; above 1 the afterburner's share).
    pub throttle_pos: f64,
    /// Propeller speed, rpm (`propulsion/engine/propeller-rpm`; `None` for an engine without a
    /// propeller).
    pub propeller_rpm: Option<f64>,
}

/// Train or test split.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Split {
    Train,
    Test,
}
