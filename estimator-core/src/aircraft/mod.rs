//! The aircraft this build is for, as its description says: `aircraft/NAME.toml` (docs/aircraft.md),
//! turned into `src/aircraft/NAME.rs` by `scripts/gen-aircraft`. `build.rs` picks the file
//! (`ESTIMATOR_AIRCRAFT=NAME`, default `f16`). What the flight code and the simulator know of an
//! airframe beyond its aerodynamic tables (`aero`) and the maneuver generator's profiles and laws
//! (hil-sim's `maneuver`) comes from here: mass properties and tanks, where the IMU and the
//! flight-test boom sit, what the surface sensors read, the flight-test points, and the flight-control
//! logic the filter reproduces (LEF schedule, flaperon mix).

use crate::Channel;

/// An aircraft description.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aircraft {
    /// The description's name (`aircraft/NAME.toml`).
    pub name: &'static str,
    pub title: &'static str,
    /// JSBSim's model: `<use aircraft=…>`, and `DIR/MODEL/MODEL.xml` in an aircraft directory.
    pub jsbsim_model: &'static str,
    pub mass: Mass,
    /// Every engine's throttle command (JSBSim properties), moved together; the throttle channel
    /// reads the first.
    pub throttle_properties: &'static [&'static str],
    pub filter: FilterSettings,
    pub estimator: EstimatorSettings,
    pub installation: Installation,
    /// What each surface position channel's sensor reads, in [`SURFACE_CHANNELS`] order; `None`
    /// where the airframe has no such surface (the channel then carries 0).
    pub surfaces: [Option<SurfaceSensor>; SURFACE_CHANNELS.len()],
    /// The `flight-test` preset's test points.
    pub flight_test_points: &'static [TestPoint],
    /// The α knots (deg) of the lift's change over α that flight-test calibration identifies
    /// (`trainer calibrate`): the lift scale alone up to the first, one parameter per knot after
    /// it. The first is where the model's lift curve leaves its straight part; the others span what
    /// the card's stall approach reaches.
    pub stall_knots_deg: [f64; STALL_KNOTS],
    /// The flight-control system's surface logic the filter reproduces for surfaces no channel
    /// carries.
    pub fcs: Fcs,
}

/// Surface logic of the aircraft's flight-control system, each part absent where the aircraft
/// has no such surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fcs {
    pub lef_schedule: Option<LefSchedule>,
    pub flaperon_mix: Option<FlaperonMix>,
}

/// The leading-edge flap as the FCS schedules it in flight: with the gear up, the deflection of
/// the first of `gear_up_alpha_steps` whose α is exceeded; else that of the first of
/// `alpha_steps`; else the Mach step's above its Mach; else 0. Radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LefSchedule {
    /// (α above, rad; deflection, rad), tried first, in order, only with the gear up (the F-16's
    /// 25° above 15° α: f16.xml's switch tests `gear/gear-pos-norm eq 0`).
    pub gear_up_alpha_steps: &'static [(f32, f32)],
    /// (α above, rad; deflection, rad), in the order they are tried, gear up or down.
    pub alpha_steps: &'static [(f32, f32)],
    pub mach_above: f32,
    pub mach_lef_rad: f32,
}

/// Flaperons mixed from the trailing-edge flap and the aileron, `left = −tef − a`,
/// `right = tef − a` (norms, each clipped to ±1): the right one, which no channel carries, is
/// `left + 2·tef` while the left one is inside `stop_norm`; at the stop `a` comes from the
/// aileron, `δa / aileron_rad_per_norm · clamp(1 − mach_compensation·M, min_compensation, 1)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlaperonMix {
    pub stop_norm: f32,
    pub aileron_rad_per_norm: f32,
    pub mach_compensation: f32,
    pub min_compensation: f32,
}

/// Mass properties of the JSBSim model and the tanks the flights use.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mass {
    pub empty_weight_lb: f64,
    /// The empty aircraft's CG station (JSBSim structural x), inches.
    pub empty_cg_x_in: f64,
    /// The empty aircraft's inertia `[ixx, iyy, izz, ixz]`, slug·ft², as JSBSim's inertia tensor
    /// carries it (`ixz` its xz element): flight-test calibration's moment equations read it.
    pub inertia_slug_ft2: [f64; 4],
    pub pilot_lb: f64,
    /// The model's point mass that is the pilot (`inertia/pointmass-*[i]`).
    pub pilot_pointmass: u8,
    /// The tanks flights fill (`propulsion/tank[i]`) and the fuel gauge measures.
    pub internal_tanks: &'static [u8],
    /// Capacity of each internal tank, lb.
    pub internal_tank_capacity_lb: f64,
    /// The tanks only an out-of-distribution heavy case fills.
    pub external_tanks: &'static [u8],
    /// The fuel gauge's resolution, lb.
    pub fuel_gauge_quantum_lb: f64,
    /// `gear/gear-pos-norm` in every flight (the filter's drag and side force read it).
    pub gear_norm: f64,
}

/// The air-data filter's settings that belong to the airframe (`filter::Config`'s fields of the
/// same names): its slow limit, and the noise sizes tuned on the airframe's training flights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterSettings {
    /// Below this airspeed the filter flags `SLOW`, m/s.
    pub min_airspeed_mps: f64,
    /// 1σ of the y and z specific-force measurement (model error and unmodelled forces), m/s².
    pub accel_sigma_mps2: [f32; 2],
    /// The gust states' 1σ, m/s, and their correlation time, s.
    pub gust_sigma_mps: f32,
    pub gust_tau_s: f32,
    /// The mean wind's vertical part: its initial 1σ, m/s, and its random-walk PSD, (m/s)²/s.
    pub mean_wind_down_sigma_mps: f32,
    pub mean_wind_down_psd: f32,
    /// `LOW_CONFIDENCE` above this 1σ of α or β, rad.
    pub max_sigma_rad: f32,
    /// Whether the filter learns its lift and side-force scales in flight; false holds both at 1
    /// (chosen per airframe, docs/aircraft.md).
    pub learn_scales: bool,
    /// Initial 1σ of the filter's trailing-edge lift scale s (the lift of the terms reading a
    /// trailing-edge surface is (1 + s) times the model's); 0 holds s at 0, and the filter keeps
    /// eight states unless the build sets `ESTIMATOR_FILTER_TE_LIFT=on` (docs/aircraft.md;
    /// `=off` leaves the state out whatever this says).
    pub te_lift_sigma0: f32,
    /// Random-walk PSD of that scale, 1/s: 0 makes s a constant learnt once; above 0 s can
    /// follow (and come back from) what moves it in flight. Above 0 the filter has the ninth
    /// state as for `te_lift_sigma0`.
    pub te_lift_psd: f32,
    /// The kinematic check's gate, m/s²: above it the running mean of the accelerometers' y or z
    /// specific force less the one the EGI's velocity change gives keeps the step out of the
    /// filter's update (`filter::Config::kinematic_gate_mps2`; at least twice the largest the
    /// airframe's generated flights reach, docs/filter.md).
    pub kinematic_gate_mps2: f32,
    /// The gyro check's gate, rad/s: above it the running mean of a gyro's rate less the one the
    /// EGI's attitude change gives says that gyro disagrees (`filter::Config::gyro_gate_rps`; at
    /// least twice the largest the airframe's generated flights reach, docs/filter.md).
    pub gyro_gate_rps: f32,
}

/// The estimator's choices that belong to the airframe, made on its own validation flights.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EstimatorSettings {
    /// Whether an α network out of its envelope gives way to a consistent air-data filter's α
    /// (`ALPHA_FROM_FILTER`, [`crate::estimator::filter_alpha_fallback`]). Either way the estimate
    /// says `OUT_OF_ENVELOPE`.
    pub alpha_from_filter: bool,
    /// The named feature set (trainer/src/features.rs) the shipped networks read: `trainer
    /// train`'s default `--features`, chosen on the aircraft's validation flights.
    pub features: &'static str,
    /// The named network sizes (trainer/src/pipeline.rs, `Size`) of the shipped networks: `trainer
    /// train`'s default `--config` and the report's shipped rows (docs/aircraft.md says where each
    /// aircraft's was chosen).
    pub config: &'static str,
}

impl Mass {
    /// Empty weight with the pilot, kg, in the flight code's precision.
    pub const fn empty_mass_kg(&self) -> f32 {
        (self.empty_weight_lb as f32 + self.pilot_lb as f32) * LB_TO_KG
    }

    /// What the fuel gauge's full scale is: every internal tank full, lb.
    pub const fn internal_fuel_capacity_lb(&self) -> f64 {
        self.internal_tanks.len() as f64 * self.internal_tank_capacity_lb
    }
}

/// Where the sensors sit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Installation {
    /// The IMU from the CG, body axes (x forward, y right, z down), m.
    pub imu_lever_arm_m: [f64; 3],
    /// The flight-test nose boom's vanes ahead of the CG, m.
    pub boom_arm_m: f64,
}

impl Installation {
    /// The IMU lever arm in the flight code's precision.
    pub const fn imu_lever_arm_f32(&self) -> [f32; 3] {
        let [x, y, z] = self.imu_lever_arm_m;
        [x as f32, y as f32, z as f32]
    }
}

/// The surface position channels, in the order of [`Aircraft::surfaces`].
pub use crate::channels::SURFACE_CHANNELS;

/// A surface position sensor: the JSBSim property it reads and that property's unit, which the
/// channel carries in degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceSensor {
    pub channel: Channel,
    /// The JSBSim property (e.g. `fcs/elevator-pos-deg`).
    pub property: &'static str,
    /// Degrees per unit of the property: 1 for a `-deg` property, 180/π for a `-rad` one, the
    /// surface's travel for a normalised one.
    pub deg_per_unit: f64,
}

impl Aircraft {
    /// The sensor of surface channel `c`: `None` when `c` is no surface channel or the airframe
    /// has no such surface.
    // `i < SURFACE_CHANNELS.len()` (7): in bounds, and the increment cannot overflow.
    #[allow(clippy::indexing_slicing, clippy::arithmetic_side_effects)]
    pub const fn surface(&self, c: Channel) -> Option<SurfaceSensor> {
        let mut i = 0;
        while i < self.surfaces.len() {
            if let Some(s) = self.surfaces[i]
                && s.channel as u8 == c as u8
            {
                return Some(s);
            }
            i += 1;
        }
        None
    }

    /// Degrees per unit of the property the sensor of surface channel `c` reads (NaN where
    /// [`Aircraft::surface`] is `None`).
    pub const fn deg_per_unit(&self, c: Channel) -> f64 {
        match self.surface(c) {
            Some(s) => s.deg_per_unit,
            None => f64::NAN,
        }
    }
}

/// How many stall knots a description gives ([`Aircraft::stall_knots_deg`]).
pub const STALL_KNOTS: usize = 5;

/// A flight-test point: trimmed start altitude and calibrated airspeed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TestPoint {
    pub alt_ft: f64,
    pub vc_kts: f64,
}

/// Pounds to kilograms (exact by definition).
pub const LB_TO_KG: f32 = 0.453_592_37;

#[rustfmt::skip]
mod generated {
    use super::*;
    include!(env!("ESTIMATOR_AIRCRAFT_FILE"));
}

pub use generated::AIRCRAFT;

/// The names of every aircraft description this tree can be built for (`src/aircraft/NAME.rs`,
/// generated from `aircraft/NAME.toml`), sorted and comma-separated; the build carries one of them,
/// [`AIRCRAFT`].
pub const DESCRIPTIONS: &str = env!("ESTIMATOR_DESCRIPTIONS");

/// The names in [`DESCRIPTIONS`], in order.
pub fn descriptions() -> impl Iterator<Item = &'static str> {
    DESCRIPTIONS.split(',')
}

/// Whether `name` is one of [`DESCRIPTIONS`].
pub fn is_described(name: &str) -> bool {
    descriptions().any(|n| n == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_flight_code_precision_values_are_the_descriptions() {
        // The filter's empty mass and lever arm are computed from the description in f32, as the
        // hand-written constants they replace were: (17,400 + 230) lb and [0.5, 0, 0.2] m.
        if AIRCRAFT.name == "f16" {
            assert_eq!(
                AIRCRAFT.mass.empty_mass_kg(),
                (17_400.0f32 + 230.0) * 0.453_592_37
            );
            assert_eq!(
                AIRCRAFT.installation.imu_lever_arm_f32(),
                [0.5f32, 0.0, 0.2]
            );
            assert_eq!(AIRCRAFT.mass.internal_fuel_capacity_lb(), 2.0 * 3_486.0);
        }
        assert!(!AIRCRAFT.jsbsim_model.is_empty());
        assert!(!AIRCRAFT.flight_test_points.is_empty());
    }

    #[test]
    fn every_surface_sensor_is_in_its_channels_slot() {
        for (s, c) in AIRCRAFT.surfaces.iter().zip(SURFACE_CHANNELS) {
            match s {
                Some(s) => {
                    assert_eq!(s.channel, c);
                    assert_eq!(AIRCRAFT.deg_per_unit(c), s.deg_per_unit);
                    assert!(s.deg_per_unit > 0.0 && !s.property.is_empty());
                }
                None => assert!(AIRCRAFT.surface(c).is_none() && AIRCRAFT.deg_per_unit(c).is_nan()),
            }
        }
        // Every airframe has the three primary controls.
        for c in [Channel::Elevator, Channel::Aileron, Channel::Rudder] {
            assert!(AIRCRAFT.surface(c).is_some(), "{c:?}");
        }
        assert!(AIRCRAFT.deg_per_unit(Channel::GyroP).is_nan());
        if AIRCRAFT.name == "f16" {
            // The aileron's property is in radians: its sensor converts exactly as `to_degrees`.
            let rad = 0.123_456_789_f64;
            assert_eq!(
                rad * AIRCRAFT.deg_per_unit(Channel::Aileron),
                rad.to_degrees()
            );
        }
    }
}
