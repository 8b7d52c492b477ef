//! Random maneuver generator (Karali et al. 2023, Fig. 3) producing complete JSBSim runscripts.
//!
//! A generated flight is a plain JSBSim runscript plus its initialize file: random commands are
//! timed tables writing `maneuver/*` properties, and the zone logic and control laws are continuous
//! events whose `<set>` is a `<function>` of aircraft properties, evaluated in file order each step
//! at dt = exactly 1/120 s ([`SCRIPT_DT_S`]). The zone state `maneuver/zone` is 0 before t = 1 s and
//! then one of three values at every step:
//!
//! - **0 Flight Zone**: random attitude / α targets with random stick perturbations, rudder,
//!   throttle and speedbrake held for random durations.
//! - **1 Danger Zone**, entered from any zone whenever the trigger fires (low, with an 8 s sink
//!   look-ahead; above the ceiling; steep bank or pitch; slow; α out of range): the recovery law
//!   (wings level, no rudder or speedbrake, pitch toward a safe altitude and speed, nose down while
//!   slow, power by speed) stops the hazard.
//! - **2 Re-climb Zone**, entered from Danger when the hazard is over, with hysteresis against the
//!   trigger (sink stopped over a 15 s look-ahead, wings within 30°, α in −3…12°, pitch not steep,
//!   30 kt above the slow limit, below the ceiling): the attitude controller climbs wings level at
//!   up to [`Profile::reclimb_pitch_deg`] (descends if above the band) with at least military power,
//!   back into the safe band; it hands back to the Flight Zone once the aircraft is well inside it
//!   (2,500 ft above the floor, 3,000 ft below the ceiling, recovery speed, calm attitude and α).
//!   The chain is strict: a short hazard met already inside the safe band (a brief α excursion at
//!   altitude) passes Danger → Re-climb → Flight, so many Re-climb visits last a single step.
//!
//! g protection (the F-16 model has no g-limiter) eases the stick in every zone when the load factor
//! leaves the profile's band. Because everything is in the script, flying the saved file through
//! JSBSim's own loader reproduces the flight; the script's header comment gives the stock command.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha12Rng;
use serde::{Deserialize, Serialize};

use estimator_core::aircraft::AIRCRAFT;

use crate::flight::SIM_HZ;

/// The script's time step: exactly 1/[`SIM_HZ`], written as the shortest decimal that reads back
/// as that double (JSBSim adds dt up each step; a truncated value such as 0.00833333333333 is
/// another rate, and its clock drifts from k/120 s).
pub const SCRIPT_DT_S: f64 = 1.0 / SIM_HZ as f64;

/// `maneuver/zone` values (Karali et al. 2023, Fig. 3), exact small integers in a double.
pub const ZONE_FLIGHT: f64 = 0.0;
pub const ZONE_DANGER: f64 = 1.0;
pub const ZONE_RECLIMB: f64 = 2.0;

/// The zones' hysteresis and the Re-climb law of this build's aircraft (its description's
/// `[zones]`).
const Z: Zones = presets::ZONES;

/// The four training profiles of the paper preset.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum ProfileKind {
    Gentle,
    HighAlpha,
    ClimbDescent,
    Aggressive,
}

impl ProfileKind {
    pub const ALL: [ProfileKind; 4] = [
        ProfileKind::Gentle,
        ProfileKind::HighAlpha,
        ProfileKind::ClimbDescent,
        ProfileKind::Aggressive,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ProfileKind::Gentle => "gentle",
            ProfileKind::HighAlpha => "high-alpha",
            ProfileKind::ClimbDescent => "climb-descent",
            ProfileKind::Aggressive => "aggressive",
        }
    }
}

/// A closed interval to draw uniformly from.
pub type Range = (f64, f64);

/// Out-of-distribution test cases: one condition outside what any training flight
/// sees, on a flight whose maneuvers are otherwise drawn exactly as its in-distribution twin's (the
/// same seed and the same random draws in the same order; only the case's value replaces the draw).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OodCase {
    /// 15 % below the lightest trained mass (18,830 lb: empty 17,400 + pilot 230 + 2 × 600 lb of
    /// fuel): 16,006 lb. Below the empty weight, so the pilot's point mass becomes a negative mass
    /// at the empty CG (a lighter structure, CG and inertia barely moved) with 2 × 300 lb of fuel.
    MassLow,
    /// 15 % above the heaviest trained mass (23,630 lb: 2 × 3,000 lb of fuel): 27,175 lb, both
    /// internal tanks full (2 × 3,486 lb) and the rest in the two external tanks.
    MassHigh,
    /// A steady wind of 25 m/s (trained: at most 40 ft/s = 12.2 m/s), from the drawn direction.
    Wind25,
    /// MIL-spec turbulence severity 7, one above the highest trained (6).
    TurbulencePlus,
    /// Every 1-cosine gust of the flight at 15 m/s (trained: 5-25 ft/s, at most 7.6 m/s).
    Gust15,
    /// The flight of the twin; its frames lose the GPS fix for 30 s (`gps-loss`, `crate::faults`).
    GpsOutage,
    /// The flight of the twin; its normal accelerometer (the strongest α cue) sticks for 10 s.
    ImuStuck,
}

impl OodCase {
    pub const ALL: [OodCase; 7] = [
        OodCase::MassLow,
        OodCase::MassHigh,
        OodCase::Wind25,
        OodCase::TurbulencePlus,
        OodCase::Gust15,
        OodCase::GpsOutage,
        OodCase::ImuStuck,
    ];

    pub fn name(self) -> &'static str {
        match self {
            OodCase::MassLow => "mass-low",
            OodCase::MassHigh => "mass-high",
            OodCase::Wind25 => "wind-25",
            OodCase::TurbulencePlus => "turbulence-plus",
            OodCase::Gust15 => "gust-15",
            OodCase::GpsOutage => "gps-outage",
            OodCase::ImuStuck => "imu-stuck",
        }
    }

    /// The sensor faults of the case, in `crate::faults` notation (applied to the frames).
    pub fn faults(self) -> &'static [&'static str] {
        match self {
            OodCase::GpsOutage => &["gps-loss@120+30"],
            OodCase::ImuStuck => &["stuck:accel_z_mps2@120+10"],
            _ => &[],
        }
    }
}

/// Mass of an OOD case: fuel in each internal and external tank (the aircraft description's), and
/// the pilot's point mass (weight, x station) where it changes.
struct MassOverride {
    internal_lbs: f64,
    external_lbs: f64,
    pointmass: Option<(f64, f64)>,
}

/// The model's empty weight and CG station, and its pilot point mass (the aircraft description).
const EMPTY_WEIGHT_LBS: f64 = AIRCRAFT.mass.empty_weight_lb;
const EMPTY_CG_X_IN: f64 = AIRCRAFT.mass.empty_cg_x_in;
const PILOT_LBS: f64 = AIRCRAFT.mass.pilot_lb;
/// How many internal and external tanks the description names.
const INTERNAL_TANKS: f64 = AIRCRAFT.mass.internal_tanks.len() as f64;
const EXTERNAL_TANKS: f64 = AIRCRAFT.mass.external_tanks.len() as f64;
const INTERNAL_TANK_CAPACITY_LBS: f64 = AIRCRAFT.mass.internal_tank_capacity_lb;
/// How far the `ood` preset leaves the training ranges (the description's `[ood]`).
const OOD: OodSizes = presets::OOD;

/// The `ood` preset's sizes for an airframe (its description's `[ood]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OodSizes {
    /// The mass cases' margin beyond the training mass range, each way (0.15: 15 %).
    pub mass_margin: f64,
    /// Fuel in each internal tank of the light case, lb (below the profiles' lowest).
    pub low_fuel_per_tank_lb: f64,
    /// The steady wind of the `wind-25` case, m/s.
    pub wind_mps: f64,
    /// Milspec severity of the `turb-plus` case.
    pub turbulence_severity: u32,
    /// Every discrete gust's size in the `gust-15` case, m/s.
    pub gust_mps: f64,
}

/// The union of the preset profiles' ranges of `field` (a profile's fuel per tank, wind, …).
fn profiles_range<T: PartialOrd + Copy>(field: impl Fn(&Profile) -> (T, T)) -> (T, T) {
    let widest = |(lo, hi): (T, T), (a, b): (T, T)| {
        (if a < lo { a } else { lo }, if b > hi { b } else { hi })
    };
    ProfileKind::ALL
        .iter()
        .map(|k| field(&Profile::preset(*k)))
        .fold(field(&Profile::preset(ProfileKind::Gentle)), widest)
}

/// The training mass range: empty + pilot + the preset profiles' fuel per internal tank.
fn trained_mass_lbs() -> Range {
    let fuel = profiles_range(|p| p.fuel_per_tank_lbs);
    (
        EMPTY_WEIGHT_LBS + PILOT_LBS + INTERNAL_TANKS * fuel.0,
        EMPTY_WEIGHT_LBS + PILOT_LBS + INTERNAL_TANKS * fuel.1,
    )
}

/// Whole pounds with thousands separators (16,006).
fn lbs(x: f64) -> String {
    let digits = format!("{:.0}", x.abs());
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    if x < -0.5 { format!("-{out}") } else { out }
}

impl OodCase {
    /// What the case flies on this build's aircraft, beside what its training flights cover (one
    /// Markdown line, for the out-of-distribution table).
    pub fn describe(self) -> String {
        let (light, heavy) = trained_mass_lbs();
        let fps = crate::flight::FT_TO_M;
        match self {
            OodCase::MassLow => format!(
                "{} lb, {:.0} % below the lightest trained mass ({} lb)",
                lbs(light * (1.0 - OOD.mass_margin)),
                100.0 * OOD.mass_margin,
                lbs(light)
            ),
            OodCase::MassHigh => format!(
                "{} lb, {:.0} % above the heaviest trained mass ({} lb)",
                lbs(heavy * (1.0 + OOD.mass_margin)),
                100.0 * OOD.mass_margin,
                lbs(heavy)
            ),
            OodCase::Wind25 => format!(
                "a steady {:.1} m/s wind (trained: at most {:.1} m/s, every direction)",
                OOD.wind_mps,
                profiles_range(|p| p.steady_wind_fps).1 * fps
            ),
            OodCase::TurbulencePlus => format!(
                "MIL-spec severity {} (trained: at most {})",
                OOD.turbulence_severity,
                profiles_range(|p| p.turb_severity).1
            ),
            OodCase::Gust15 => format!(
                "every 1-cosine gust at {:.1} m/s (trained: at most {:.1} m/s)",
                OOD.gust_mps,
                profiles_range(|p| p.gust_fps).1 * fps
            ),
            OodCase::GpsOutage => {
                "the twin's flight with no GPS fix from 120 s to 150 s".to_string()
            }
            OodCase::ImuStuck => {
                "the twin's flight with the normal accelerometer stuck from 120 s to 130 s"
                    .to_string()
            }
        }
    }

    fn mass(self) -> Option<MassOverride> {
        match self {
            OodCase::MassLow => {
                let target = trained_mass_lbs().0 * (1.0 - OOD.mass_margin);
                let structure = target - INTERNAL_TANKS * OOD.low_fuel_per_tank_lb;
                Some(MassOverride {
                    internal_lbs: OOD.low_fuel_per_tank_lb,
                    external_lbs: 0.0,
                    pointmass: Some((structure - EMPTY_WEIGHT_LBS, EMPTY_CG_X_IN)),
                })
            }
            OodCase::MassHigh => {
                let target = trained_mass_lbs().1 * (1.0 + OOD.mass_margin);
                let fuel = target - EMPTY_WEIGHT_LBS - PILOT_LBS;
                let beyond_internal = fuel - INTERNAL_TANKS * INTERNAL_TANK_CAPACITY_LBS;
                // An airframe without external tanks carries the rest as ballast at its empty CG,
                // in the pilot's point mass (so the ballast includes the pilot).
                Some(if EXTERNAL_TANKS > 0.0 {
                    MassOverride {
                        internal_lbs: INTERNAL_TANK_CAPACITY_LBS,
                        external_lbs: beyond_internal / EXTERNAL_TANKS,
                        pointmass: None,
                    }
                } else {
                    MassOverride {
                        internal_lbs: INTERNAL_TANK_CAPACITY_LBS,
                        external_lbs: 0.0,
                        pointmass: Some((beyond_internal + PILOT_LBS, EMPTY_CG_X_IN)),
                    }
                })
            }
            _ => None,
        }
    }
}

/// Everything that shapes one family of random flights.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Profile {
    pub kind: ProfileKind,
    /// Initial altitude and calibrated airspeed.
    pub init_alt_ft: Range,
    pub init_vc_kts: Range,
    /// Fuel per internal tank (the aircraft description's), lb; frozen so each flight has its own
    /// constant mass.
    pub fuel_per_tank_lbs: Range,
    /// Pitch-attitude targets, deg, and how long each is held, s.
    pub theta_target_deg: Range,
    pub target_hold_s: Range,
    /// Share of pitch segments that track an α target instead of a pitch attitude.
    pub alpha_mode_share: f64,
    pub alpha_target_deg: Range,
    /// Bank targets (sign random), deg.
    pub bank_target_deg: Range,
    /// Open-loop stick perturbations added to the laws (normalised stick), and their hold times.
    pub pitch_stick_amp: f64,
    pub roll_stick_amp: f64,
    pub stick_hold_s: Range,
    pub rudder_amp: f64,
    pub rudder_hold_s: Range,
    pub throttle: Range,
    pub throttle_hold_s: Range,
    /// Probability that a speedbrake segment deploys it.
    pub speedbrake_share: f64,
    /// Probability that a flap segment lowers the flap (to one of the description's `[flaps]`
    /// settings, below its flap speed); 0 where the aircraft has no pilot-set flap.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub flap_share: f64,
    /// Danger Zone limits.
    pub min_agl_ft: f64,
    pub ceiling_ft: f64,
    pub max_bank_deg: f64,
    pub max_pitch_deg: f64,
    pub min_vc_kts: f64,
    /// Calibrated airspeed the Re-climb Zone reaches before handing back to the Flight Zone.
    pub recover_vc_kts: f64,
    /// Re-climb Zone: the largest pitch-attitude target of the climb back to a safe altitude, deg.
    pub reclimb_pitch_deg: f64,
    pub max_alpha_deg: f64,
    /// Below this α (the aero tables end at −10°) the Danger Zone takes over too.
    pub min_alpha_deg: f64,
    /// Time constant of the ramp to each new attitude / α target, s.
    pub target_ramp_s: f64,
    /// g protection band.
    pub max_nz_g: f64,
    pub min_nz_g: f64,
    /// Dryden turbulence severity (0 = off … 7), drawn as an integer from this range.
    pub turb_severity: (u32, u32),
    /// Steady wind magnitude, ft/s (random direction).
    pub steady_wind_fps: Range,
    /// 1-cosine gusts: magnitude (ft/s) and interval between gusts (s).
    pub gust_fps: Range,
    pub gust_interval_s: Range,
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

/// The flap the pilot sets (the description's `[flaps]`): random segments in the Flight Zone lower
/// it to one of `settings`, and it retracts as the calibrated airspeed rises through the
/// `retract_band_kts` below `max_vc_kts`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Flaps {
    /// The flap command (a JSBSim property, 0 = up).
    pub command_property: &'static str,
    /// The commands of the flap's detents, each within (0, 1].
    pub settings: &'static [f64],
    pub max_vc_kts: f64,
    pub retract_band_kts: f64,
}

impl Profile {
    /// The preset profiles: the aircraft description's `[profiles.*]` (`aircraft/NAME.toml`,
    /// generated into `src/maneuver/NAME.rs` by `scripts/gen-aircraft`).
    pub fn preset(kind: ProfileKind) -> Profile {
        presets::preset(kind)
    }
}

/// The maneuver generator's control laws for an airframe (its description's `[control_laws]`):
/// gains from attitude, α, bank, load-factor, altitude and speed errors to the normalised surface
/// and throttle commands (`fcs/*-cmd-norm`) of the three zones.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControlLaws {
    /// Flight Zone elevator per degree of pitch-attitude error.
    pub pitch_per_deg: f64,
    /// α mode: elevator feed-forward per degree of α target, and per degree of α error.
    pub alpha_feedforward_per_deg: f64,
    pub alpha_per_deg: f64,
    /// Danger and Re-climb elevator per degree of pitch-attitude error, applied only while the bank
    /// is within `recovery_max_bank_deg`.
    pub recovery_pitch_per_deg: f64,
    pub recovery_max_bank_deg: f64,
    /// Elevator command limits (nose down, nose up), normalised.
    pub elevator_cmd: Range,
    /// Aileron per degree of bank error (Flight), and per degree of bank (wings level).
    pub bank_per_deg: f64,
    pub wings_level_per_deg: f64,
    /// Elevator per g outside the load-factor band.
    pub g_protect_per_g: f64,
    /// Danger Zone pitch target: per ft below the mid altitude, per kt below the recovery speed,
    /// and its limit either way.
    pub danger_pitch_per_ft: f64,
    pub danger_pitch_per_kt: f64,
    pub danger_pitch_limit_deg: f64,
    /// Re-climb Zone: nose down per kt within the slow margin.
    pub reclimb_pitch_per_kt: f64,
    /// Danger Zone throttle: this, plus this per kt below the recovery speed + a margin.
    pub danger_throttle: f64,
    pub danger_throttle_per_kt: f64,
    pub danger_throttle_margin_kts: f64,
    /// Re-climb Zone throttle: at least this, plus this per kt below the recovery speed + a margin.
    pub reclimb_throttle: f64,
    pub reclimb_throttle_per_kt: f64,
    pub reclimb_throttle_margin_kts: f64,
}

/// The flight-test card's sizes for an airframe (its description's `[flight_test_card]`); the
/// card's sequence and timing are [`card_inputs`]'s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlightTestCard {
    /// Normalised amplitudes of the first pass: pitch doublet, pitch 3-2-1-1, roll doublet, rudder
    /// doublet, rudder 3-2-1-1, the steady-heading sideslips' rudder.
    pub pitch_doublet: f64,
    pub pitch_multistep: f64,
    pub roll_doublet: f64,
    pub rudder_doublet: f64,
    pub rudder_multistep: f64,
    pub sideslip_rudder: f64,
    /// The second pass's inputs over the first's.
    pub second_pass_scale: f64,
    /// Wind-up turn: the bank, the α target it starts at, the α target at its peak (plus this per
    /// unit of pass scale) and the α target it ends at.
    pub windup_bank_deg: f64,
    pub windup_alpha_start_deg: f64,
    pub windup_alpha_deg: f64,
    pub windup_alpha_per_scale_deg: f64,
    pub windup_alpha_end_deg: f64,
    /// Pull-up then push-over: pitch-attitude offsets per unit of pass scale.
    pub pull_up_theta_deg: f64,
    pub push_over_theta_deg: f64,
    /// Once per flight, after the second pass: a stall approach, `stall_approach_s` at idle with
    /// the speedbrake out while the altitude is held, so that the speed decays, then a wind-up
    /// turn at [`FlightTestCard::windup_bank_deg`] with the α target raised from
    /// [`FlightTestCard::windup_alpha_deg`] at `stall_approach_rate_deg_s` toward
    /// `stall_approach_alpha_deg`.
    pub stall_approach_s: f64,
    pub stall_approach_alpha_deg: f64,
    pub stall_approach_rate_deg_s: f64,
    /// Between inputs: pitch attitude `hold_pitch_deg` plus `altitude_hold_per_ft` per ft below the
    /// test point (within ±`altitude_hold_limit_deg`), throttle `speed_hold_throttle` plus
    /// `speed_hold_per_kt` per kt below its speed; the throttle the card starts from.
    pub hold_pitch_deg: f64,
    pub altitude_hold_per_ft: f64,
    pub altitude_hold_limit_deg: f64,
    pub speed_hold_throttle: f64,
    pub speed_hold_per_kt: f64,
    pub initial_throttle: f64,
    /// Fuel in each internal tank during the card, lb (a mid-range mass).
    pub fuel_per_tank_lb: f64,
}

/// How the generator moves between its zones on an airframe (its description's `[zones]`): the
/// Danger Zone trigger's look-ahead, the hysteresis that ends the Danger Zone and the Re-climb
/// Zone against the profile's limits, and the Re-climb law's targets. Sizes of the airframe's
/// speeds and attitudes: a light aircraft's speed margins are a fraction of a fighter's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Zones {
    /// Danger Zone trigger: the low-altitude limit applies to the height this many seconds ahead
    /// along the sink rate.
    pub trigger_lookahead_s: f64,
    /// Danger → Re-climb (the immediate hazard is over), each with hysteresis against the
    /// trigger: a longer sink look-ahead that must stay `calm_floor_margin_ft` above the floor,
    /// `calm_ceiling_margin_ft` below the ceiling, bank within `calm_bank_deg`, α within
    /// `calm_alpha_deg`, pitch within `calm_pitch_deg` and `calm_pitch_inside_deg` inside the
    /// trigger's, the speed `calm_vc_margin_kts` above the slow limit.
    pub calm_lookahead_s: f64,
    pub calm_floor_margin_ft: f64,
    pub calm_ceiling_margin_ft: f64,
    pub calm_bank_deg: f64,
    pub calm_alpha_deg: Range,
    pub calm_pitch_deg: f64,
    pub calm_pitch_inside_deg: f64,
    pub calm_vc_margin_kts: f64,
    /// Re-climb → Flight (back well inside the Flight Zone): this far above the floor and below
    /// the ceiling, pitch within `safe_pitch_deg` (with the recovery speed and the calm bank and
    /// α).
    pub safe_floor_margin_ft: f64,
    pub safe_ceiling_margin_ft: f64,
    pub safe_pitch_deg: f64,
    /// Re-climb law: it aims this far beyond the safe band (so the exit is crossed still
    /// climbing), with this pitch gain per foot, a descent (from above the ceiling) no steeper
    /// than this, and the nose lowered while within this margin of the slow limit.
    pub reclimb_overshoot_ft: f64,
    pub reclimb_pitch_per_ft: f64,
    pub reclimb_descent_pitch_deg: f64,
    pub reclimb_vc_margin_kts: f64,
}

/// The generated profiles of this build's aircraft (build.rs picks the file).
#[rustfmt::skip]
mod presets {
    use super::{ControlLaws, Flaps, FlightTestCard, OodSizes, Profile, ProfileKind, Zones};
    include!(env!("HIL_PROFILES_FILE"));
}

/// One generated flight.
#[derive(Clone, Debug, PartialEq)]
pub struct Maneuver {
    pub name: String,
    pub script_xml: String,
    pub init_xml: String,
    pub duration_s: f64,
}

/// Why a maneuver cannot be written.
#[derive(Debug, thiserror::Error)]
pub enum ManeuverError {
    #[error("cannot write maneuver file {path}: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("maneuver name {0:?} must be letters, digits, '-' or '_' (it becomes a file name)")]
    BadName(String),
    #[error("maneuver duration {0} s must be between 1 and 7200 s")]
    BadDuration(f64),
    #[error(
        "--hours {0}: give the campaign's flight-hours, more than 0 and at most {max} (e.g. \
         --hours 40)",
        max = Campaign::MAX_HOURS
    )]
    BadCampaignHours(f64),
    #[error("--flight-min {0}: give each flight's length in minutes, between 1 and 120")]
    BadFlightMin(f64),
}

fn draw(rng: &mut ChaCha12Rng, r: Range) -> f64 {
    if r.1 > r.0 {
        rng.random_range(r.0..=r.1)
    } else {
        r.0
    }
}

fn signed(rng: &mut ChaCha12Rng, r: Range) -> f64 {
    let v = draw(rng, r);
    if rng.random_bool(0.5) { v } else { -v }
}

/// Timed event: at `t`, set each `(prop, value)`.
fn timed(out: &mut String, t: f64, sets: &[(&str, f64)]) {
    let _ = writeln!(out, "    <event>");
    let _ = writeln!(
        out,
        "      <condition> simulation/sim-time-sec ge {t:.3} </condition>"
    );
    for (prop, value) in sets {
        let _ = writeln!(out, "      <set name=\"{prop}\" value=\"{value:.4}\"/>");
    }
    let _ = writeln!(out, "    </event>");
}

/// Continuous event holding `prop` at `initial`, then at each `(t, value, hold)` ramping linearly to
/// `value` over `ramp` seconds (at most half the hold), as a table of sim time.
fn schedule(prop: &str, initial: f64, seq: &[(f64, f64, f64)], ramp: f64) -> String {
    let mut rows = format!("            0.0 {initial:.4}\n");
    let mut prev = initial;
    for (t, v, hold) in seq {
        let r = ramp.min(0.5 * hold).max(0.01);
        let _ = writeln!(
            rows,
            "            {t:.3} {prev:.4}\n            {:.3} {v:.4}",
            t + r
        );
        prev = *v;
    }
    format!(
        "    <event name=\"{prop} schedule\" continuous=\"true\">\n      <condition> simulation/sim-time-sec ge 0.0 </condition>\n      <set name=\"{prop}\">\n        <function>\n          <table>\n            <independentVar lookup=\"row\">simulation/sim-time-sec</independentVar>\n            <tableData>\n{rows}            </tableData>\n          </table>\n        </function>\n      </set>\n    </event>\n"
    )
}

/// Continuous event computing `prop` from a function body.
fn law(out: &mut String, name: &str, prop: &str, function: &str) {
    let _ = write!(
        out,
        "    <event name=\"{name}\" continuous=\"true\">\n      <condition> simulation/sim-time-sec ge 1.0 </condition>\n      <set name=\"{prop}\">\n        <function>\n{function}        </function>\n      </set>\n    </event>\n"
    );
}

fn clamp(lo: f64, hi: f64, inner: &str) -> String {
    format!("<max><value>{lo}</value><min><value>{hi}</value>{inner}</min></max>")
}

/// The initialisation file: an airborne start at a random place, altitude, speed and heading.
fn init_file(p: &Profile, rng: &mut ChaCha12Rng, seed: u64, name: &str, init_name: &str) -> String {
    let alt = draw(rng, p.init_alt_ft);
    let vc = draw(rng, p.init_vc_kts);
    let psi = draw(rng, (0.0, 360.0));
    let lat = draw(rng, (-50.0, 60.0));
    let lon = draw(rng, (-170.0, 170.0));
    // Latitude/longitude before vc: JSBSim re-derives the speed when position changes afterwards.
    format!(
        "<?xml version=\"1.0\"?>\n<!-- hil-sim maneuver {name}: airborne start (profile {}, seed {seed}). -->\n<initialize name=\"{init_name}\">\n  <latitude unit=\"DEG\"> {lat:.4} </latitude>\n  <longitude unit=\"DEG\"> {lon:.4} </longitude>\n  <altitude unit=\"FT\"> {alt:.1} </altitude>\n  <vc unit=\"KTS\"> {vc:.1} </vc>\n  <psi unit=\"DEG\"> {psi:.1} </psi>\n  <phi unit=\"DEG\"> 0.0 </phi>\n  <gamma unit=\"DEG\"> 0.0 </gamma>\n  <running> -1 </running>\n</initialize>\n",
        p.kind.name()
    )
}

/// The runscript's head: the comment that says how to run it, `<use>`, `<run>` and the maneuver
/// properties with their initial values.
fn script_head(p: &Profile, seed: u64, name: &str, init_name: &str, duration_s: f64) -> String {
    let mut s = String::new();
    // No "--" inside an XML comment: the C++ command line's options are named, not spelled.
    let _ = write!(
        s,
        "<?xml version=\"1.0\"?>\n<!-- Generated by hil-sim (profile {}, seed {seed}): a plain JSBSim runscript; maneuver/zone\n     is 0 Flight, 1 Danger, 2 Re-climb. Stock JSBSim must be given the initialize file\n     {init_name}.xml beside it (else it looks in aircraft/{model}/). From this folder (absolute\n     paths: Python resolves relative ones against the JSBSim root; dt 0.0 = this script's dt):\n       python -c \"import jsbsim, os; f = jsbsim.FGFDMExec(None); f.load_script(os.path.abspath('{name}.xml'), 0.0, os.path.abspath('{init_name}.xml')); f.run_ic(); all(iter(f.run, False))\"\n     The C++ JSBSim takes the same two files as its script and initfile options. -->\n<runscript name=\"hil-sim maneuver {name}\">\n  <use aircraft=\"{model}\" initialize=\"{init_name}\"/>\n  <run start=\"0.0\" end=\"{duration_s:.3}\" dt=\"{SCRIPT_DT_S}\">\n",
        p.kind.name(),
        model = AIRCRAFT.jsbsim_model
    );
    for (prop, v) in [
        ("maneuver/theta-target-deg", 0.0),
        ("maneuver/alpha-target-deg", 5.0),
        ("maneuver/alpha-mode", 0.0),
        ("maneuver/bank-target-deg", 0.0),
        ("maneuver/pitch-stick", 0.0),
        ("maneuver/roll-stick", 0.0),
        ("maneuver/rudder", 0.0),
        ("maneuver/throttle", 0.6),
        ("maneuver/speedbrake", 0.0),
        ("maneuver/trigger", 0.0),
        ("maneuver/hazard-over", 0.0),
        ("maneuver/recovered", 0.0),
        ("maneuver/zone", ZONE_FLIGHT),
        ("maneuver/danger", 0.0),
        ("maneuver/reclimb", 0.0),
        ("maneuver/theta-recover-deg", 0.0),
        ("maneuver/theta-reclimb-deg", 0.0),
        ("maneuver/nz-g", 1.0),
        ("maneuver/g-protect", 0.0),
    ] {
        let _ = writeln!(s, "    <property value=\"{v}\"> {prop} </property>");
    }
    if presets::FLAPS.is_some() {
        let _ = writeln!(s, "    <property value=\"0\"> maneuver/flap </property>");
    }

    s
}

/// Fuel in both internal tanks (frozen) and JSBSim's trim at the start; an OOD mass also fills the
/// external tanks and moves or lightens the pilot's point mass, before the trim.
fn fuel_and_trim(s: &mut String, fuel: f64, mass: Option<&MassOverride>) {
    let internal = mass.map_or(fuel, |m| m.internal_lbs);
    s.push_str("    <event name=\"fuel and trim\">\n      <condition> simulation/sim-time-sec ge 0.0 </condition>\n");
    let tanks = |s: &mut String, tanks: &[u8], lbs: f64| {
        for t in tanks {
            let _ = writeln!(
                s,
                "      <set name=\"propulsion/tank[{t}]/contents-lbs\" value=\"{lbs:.1}\"/>"
            );
        }
    };
    tanks(s, AIRCRAFT.mass.internal_tanks, internal);
    if let Some(m) = mass {
        tanks(s, AIRCRAFT.mass.external_tanks, m.external_lbs);
        if let Some((w, x)) = m.pointmass {
            let i = AIRCRAFT.mass.pilot_pointmass;
            let _ = write!(
                s,
                "      <set name=\"inertia/pointmass-weight-lbs[{i}]\" value=\"{w:.1}\"/>\n      <set name=\"inertia/pointmass-location-X-inches[{i}]\" value=\"{x:.1}\"/>\n"
            );
        }
    }
    s.push_str("      <set name=\"propulsion/fuel_freeze\" value=\"1\"/>\n      <set name=\"simulation/do_simple_trim\" value=\"1\"/>\n    </event>\n");
}

/// Milspec turbulence (its own repeatable seed) and a steady wind, set at 0.5 s.
fn wind(s: &mut String, p: &Profile, rng: &mut ChaCha12Rng, ood: Option<OodCase>) {
    let mut sev = rng.random_range(p.turb_severity.0..=p.turb_severity.1.max(p.turb_severity.0));
    let mut wind = draw(rng, p.steady_wind_fps);
    match ood {
        Some(OodCase::TurbulencePlus) => sev = OOD.turbulence_severity,
        Some(OodCase::Wind25) => wind = OOD.wind_mps / crate::flight::FT_TO_M,
        _ => {}
    }
    let wdir = draw(rng, (0.0, std::f64::consts::TAU));
    let turb_seed = rng.random_range(1..1_000_000u32);
    let _ = write!(
        s,
        "    <event name=\"wind\">\n      <condition> simulation/sim-time-sec ge 0.5 </condition>\n      <set name=\"atmosphere/randomseed\" value=\"{turb_seed}\"/>\n      <set name=\"atmosphere/turb-type\" value=\"{}\"/>\n      <set name=\"atmosphere/turbulence/milspec/windspeed_at_20ft_AGL-fps\" value=\"{:.1}\"/>\n      <set name=\"atmosphere/turbulence/milspec/severity\" value=\"{sev}\"/>\n      <set name=\"atmosphere/wind-north-fps\" value=\"{:.2}\" action=\"FG_RAMP\" tc=\"5\"/>\n      <set name=\"atmosphere/wind-east-fps\" value=\"{:.2}\" action=\"FG_RAMP\" tc=\"5\"/>\n    </event>\n",
        if sev > 0 { 3 } else { 0 },
        15.0 + 5.0 * f64::from(sev),
        wind * wdir.cos(),
        wind * wdir.sin(),
    );
}

/// The zone logic (Karali et al. 2023, Fig. 3), evaluated every step in this order: three 0/1
/// conditions, then the zone state machine (it reads its own value of the previous step), then the
/// zones' pitch targets and the load-factor protection.
fn zone_laws(s: &mut String, p: &Profile) {
    let k = &presets::LAWS;
    // Zone logic, evaluated every step in this order (the command tables go just before it): three
    // 0/1 conditions, then the zone state machine (it reads its own value of the previous step),
    // then the laws, each blending the three zones' commands by the zone flags.
    // The low-altitude limit looks 8 s ahead along the sink rate: fast dives overshot a plain
    // height limit.
    let trigger = format!(
        "<or><lt><sum><property>position/h-agl-ft</property><product><value>{}</value><min><value>0</value><property>velocities/h-dot-fps</property></min></product></sum><value>{}</value></lt><gt><property>position/h-sl-ft</property><value>{}</value></gt><gt><abs><property>attitude/phi-deg</property></abs><value>{}</value></gt><gt><abs><property>attitude/theta-deg</property></abs><value>{}</value></gt><lt><property>velocities/vc-kts</property><value>{}</value></lt><gt><property>aero/alpha-deg</property><value>{}</value></gt><lt><property>aero/alpha-deg</property><value>{}</value></lt></or>",
        Z.trigger_lookahead_s,
        p.min_agl_ft,
        p.ceiling_ft,
        p.max_bank_deg,
        p.max_pitch_deg,
        p.min_vc_kts,
        p.max_alpha_deg,
        p.min_alpha_deg
    );
    law(
        s,
        "zone: Danger Zone trigger (low with sink look-ahead, ceiling, bank, pitch, slow, alpha)",
        "maneuver/trigger",
        &format!("          {trigger}\n"),
    );
    // Every limit with hysteresis against the trigger: a longer sink look-ahead and a floor margin,
    // a ceiling margin, bank and α well inside, pitch at least 20° inside, a speed margin.
    let hazard_over = format!(
        "<and><gt><sum><property>position/h-agl-ft</property><product><value>{}</value><min><value>0</value><property>velocities/h-dot-fps</property></min></product></sum><value>{}</value></gt><lt><property>position/h-sl-ft</property><value>{}</value></lt><lt><abs><property>attitude/phi-deg</property></abs><value>{}</value></lt><lt><abs><property>attitude/theta-deg</property></abs><value>{}</value></lt><gt><property>velocities/vc-kts</property><value>{}</value></gt><lt><property>aero/alpha-deg</property><value>{}</value></lt><gt><property>aero/alpha-deg</property><value>{}</value></gt></and>",
        Z.calm_lookahead_s,
        p.min_agl_ft + Z.calm_floor_margin_ft,
        p.ceiling_ft - Z.calm_ceiling_margin_ft,
        Z.calm_bank_deg,
        (p.max_pitch_deg - Z.calm_pitch_inside_deg).min(Z.calm_pitch_deg),
        p.min_vc_kts + Z.calm_vc_margin_kts,
        Z.calm_alpha_deg.1,
        Z.calm_alpha_deg.0,
    );
    law(
        s,
        "zone: Danger over (sink stopped, wings near level, alpha normal, pitch not steep, speed margin)",
        "maneuver/hazard-over",
        &format!("          {hazard_over}\n"),
    );
    let recovered = format!(
        "<and><gt><property>position/h-agl-ft</property><value>{}</value></gt><lt><property>position/h-sl-ft</property><value>{}</value></lt><lt><abs><property>attitude/phi-deg</property></abs><value>{}</value></lt><lt><abs><property>attitude/theta-deg</property></abs><value>{}</value></lt><gt><property>velocities/vc-kts</property><value>{}</value></gt><lt><property>aero/alpha-deg</property><value>{}</value></lt><gt><property>aero/alpha-deg</property><value>{}</value></gt></and>",
        p.min_agl_ft + Z.safe_floor_margin_ft,
        p.ceiling_ft - Z.safe_ceiling_margin_ft,
        Z.calm_bank_deg,
        Z.safe_pitch_deg,
        p.recover_vc_kts,
        Z.calm_alpha_deg.1,
        Z.calm_alpha_deg.0,
    );
    law(
        s,
        "zone: back well inside the Flight Zone (safe altitude band, recovered speed)",
        "maneuver/recovered",
        &format!("          {recovered}\n"),
    );
    let zone = |v: f64| format!("<value>{v}</value>");
    let is_zone = |v: f64| format!("<eq><property>maneuver/zone</property><value>{v}</value></eq>");
    law(
        s,
        "zone: 0 Flight, 1 Danger, 2 Re-climb (the trigger sends any zone to Danger)",
        "maneuver/zone",
        &format!(
            "          <ifthen><property>maneuver/trigger</property>{danger}\n            <ifthen>{in_danger}<ifthen><property>maneuver/hazard-over</property>{reclimb}{danger}</ifthen>\n              <ifthen>{in_reclimb}<ifthen><property>maneuver/recovered</property>{flight}{reclimb}</ifthen>\n                {flight}</ifthen></ifthen></ifthen>\n",
            danger = zone(ZONE_DANGER),
            reclimb = zone(ZONE_RECLIMB),
            flight = zone(ZONE_FLIGHT),
            in_danger = is_zone(ZONE_DANGER),
            in_reclimb = is_zone(ZONE_RECLIMB),
        ),
    );
    law(
        s,
        "zone flag: in the Danger Zone",
        "maneuver/danger",
        &format!("          {}\n", is_zone(ZONE_DANGER)),
    );
    law(
        s,
        "zone flag: in the Re-climb Zone",
        "maneuver/reclimb",
        &format!("          {}\n", is_zone(ZONE_RECLIMB)),
    );
    let mid_alt = (p.min_agl_ft + 4_000.0).max((p.init_alt_ft.0 + p.init_alt_ft.1) / 2.0);
    law(
        s,
        "Danger Zone pitch target: toward a safe altitude, nose down while slow",
        "maneuver/theta-recover-deg",
        &format!(
            "          {}\n",
            clamp(
                -k.danger_pitch_limit_deg,
                k.danger_pitch_limit_deg,
                &format!(
                    "<sum><product><value>{}</value><difference><value>{mid_alt:.0}</value><property>position/h-sl-ft</property></difference></product><product><value>{}</value><min><value>0</value><difference><property>velocities/vc-kts</property><value>{}</value></difference></min></product></sum>",
                    k.danger_pitch_per_ft, k.danger_pitch_per_kt, p.recover_vc_kts
                )
            )
        ),
    );
    // Re-climb: climb (or descend) to a little beyond the Flight Zone's safe band so the exit is
    // crossed with the climb still going, level inside it; lower the nose while close to the slow
    // limit (power is up, so the speed comes back).
    law(
        s,
        "Re-climb Zone pitch target: climb back into the safe altitude band, level inside it",
        "maneuver/theta-reclimb-deg",
        &format!(
            "          {}\n",
            clamp(
                -Z.reclimb_descent_pitch_deg,
                p.reclimb_pitch_deg,
                &format!(
                    "<difference><product><value>{}</value><difference><max><value>0</value><difference><value>{:.0}</value><property>position/h-agl-ft</property></difference></max><max><value>0</value><difference><property>position/h-sl-ft</property><value>{:.0}</value></difference></max></difference></product><product><value>{}</value><max><value>0</value><difference><value>{}</value><property>velocities/vc-kts</property></difference></max></product></difference>",
                    Z.reclimb_pitch_per_ft,
                    p.min_agl_ft + Z.safe_floor_margin_ft + Z.reclimb_overshoot_ft,
                    p.ceiling_ft - Z.safe_ceiling_margin_ft - Z.reclimb_overshoot_ft,
                    k.reclimb_pitch_per_kt,
                    p.min_vc_kts + Z.reclimb_vc_margin_kts,
                )
            )
        ),
    );
    law(
        s,
        "load factor from the total non-gravity force",
        "maneuver/nz-g",
        "          <quotient><product><value>-1</value><property>forces/fbz-total-lbs</property></product><property>inertia/weight-lbs</property></quotient>\n",
    );
    law(
        s,
        "g protection: push when above the band, pull when below (the FCS has no g-limiter)",
        "maneuver/g-protect",
        &format!(
            "          <sum><product><value>{g}</value><max><value>0</value><difference><property>maneuver/nz-g</property><value>{}</value></difference></max></product><product><value>{g}</value><min><value>0</value><difference><property>maneuver/nz-g</property><value>{}</value></difference></min></product></sum>\n",
            p.max_nz_g,
            p.min_nz_g,
            g = k.g_protect_per_g
        ),
    );
}

/// The control laws: each surface and the throttle blend the three zones' commands by the zone
/// flags.
fn control_laws(s: &mut String, p: &Profile) {
    let k = &presets::LAWS;
    // α mode: at low speed a fly-by-wire stick roughly commands α (the F-16's: full aft ≈ the ~28°
    // limiter), so a feed-forward of the target plus a proportional correction holds it.
    let flight_elev = format!(
        "<sum><property>maneuver/pitch-stick</property><product><difference><value>1</value><property>maneuver/alpha-mode</property></difference><value>{}</value><difference><property>attitude/theta-deg</property><property>maneuver/theta-target-deg</property></difference></product><product><property>maneuver/alpha-mode</property><sum><product><value>{}</value><property>maneuver/alpha-target-deg</property></product><product><value>{}</value><difference><property>aero/alpha-deg</property><property>maneuver/alpha-target-deg</property></difference></product></sum></product></sum>",
        k.pitch_per_deg, k.alpha_feedforward_per_deg, k.alpha_per_deg
    );
    // Danger and Re-climb pitch only once the wings are near level (pulling inverted dives).
    let pitch_to = |target: &str| {
        format!(
            "<product><lt><abs><property>attitude/phi-deg</property></abs><value>{}</value></lt><value>{}</value><difference><property>attitude/theta-deg</property><property>{target}</property></difference></product>",
            k.recovery_max_bank_deg, k.recovery_pitch_per_deg
        )
    };
    // Commands by zone: Flight × (1 − danger − reclimb) + Danger × danger + Re-climb × reclimb.
    let blend = |flight: &str, danger: &str, reclimb: &str| {
        format!(
            "<sum><product><difference><value>1</value><sum><property>maneuver/danger</property><property>maneuver/reclimb</property></sum></difference>{flight}</product><product><property>maneuver/danger</property>{danger}</product><product><property>maneuver/reclimb</property>{reclimb}</product></sum>"
        )
    };
    law(
        s,
        "elevator: Flight Zone targets + stick, Danger recovery or Re-climb attitude; then g protection",
        "fcs/elevator-cmd-norm",
        &format!(
            "          {}\n",
            clamp(
                k.elevator_cmd.0,
                k.elevator_cmd.1,
                &format!(
                    "<sum>{}<property>maneuver/g-protect</property></sum>",
                    blend(
                        &flight_elev,
                        &pitch_to("maneuver/theta-recover-deg"),
                        &pitch_to("maneuver/theta-reclimb-deg")
                    )
                )
            )
        ),
    );
    let flight_ail = format!(
        "<sum><property>maneuver/roll-stick</property><product><value>{}</value><difference><property>maneuver/bank-target-deg</property><property>attitude/phi-deg</property></difference></product></sum>",
        k.bank_per_deg
    );
    let wings_level = format!(
        "<product><value>{}</value><property>attitude/phi-deg</property></product>",
        k.wings_level_per_deg
    );
    law(
        s,
        "aileron: bank target + stick, or wings level",
        "fcs/aileron-cmd-norm",
        &format!(
            "          {}\n",
            clamp(-1.0, 1.0, &blend(&flight_ail, &wings_level, &wings_level))
        ),
    );
    law(
        s,
        "rudder: random in the Flight Zone only",
        "fcs/rudder-cmd-norm",
        &format!(
            "          {}\n",
            clamp(
                -1.0,
                1.0,
                &blend(
                    "<property>maneuver/rudder</property>",
                    "<value>0</value>",
                    "<value>0</value>"
                )
            )
        ),
    );
    // Flight Zone: the random draws, down to idle (0) as a speed-holding pilot or autothrottle flies
    // it. Danger: by airspeed, idle when fast. Re-climb: at least military power, afterburner as
    // the speed falls toward the recovery speed.
    let throttle = format!(
        "          {}\n",
        clamp(
            0.0,
            1.0,
            &blend(
                "<property>maneuver/throttle</property>",
                &format!(
                    "<sum><value>{}</value><product><value>{}</value><difference><value>{}</value><property>velocities/vc-kts</property></difference></product></sum>",
                    k.danger_throttle,
                    k.danger_throttle_per_kt,
                    p.recover_vc_kts + k.danger_throttle_margin_kts
                ),
                &format!(
                    "<max><value>{t}</value><sum><value>{t}</value><product><value>{}</value><difference><value>{}</value><property>velocities/vc-kts</property></difference></product></sum></max>",
                    k.reclimb_throttle_per_kt,
                    p.recover_vc_kts + k.reclimb_throttle_margin_kts,
                    t = k.reclimb_throttle
                )
            )
        )
    );
    // Every engine's throttle moves together (one law each: an event sets one property).
    for (engine, prop) in AIRCRAFT.throttle_properties.iter().enumerate() {
        let name = if engine == 0 {
            "throttle: random, by airspeed in Danger, power up in Re-climb".to_string()
        } else {
            format!("throttle of engine {engine}: as engine 0's")
        };
        law(s, &name, prop, &throttle);
    }
    law(
        s,
        "speedbrake: random in the Flight Zone only",
        "fcs/speedbrake-cmd-norm",
        &format!(
            "          {}\n",
            blend(
                "<property>maneuver/speedbrake</property>",
                "<value>0</value>",
                "<value>0</value>"
            )
        ),
    );
    // The flap: the random setting in the Flight Zone and kept through a Danger recovery (no flap
    // change while recovering), up for the Re-climb; whatever the zone, retracted as the speed
    // rises through the band below the flap speed.
    if let Some(f) = presets::FLAPS {
        let gate = clamp(
            0.0,
            1.0,
            &format!(
                "<product><value>{}</value><difference><value>{}</value><property>velocities/vc-kts</property></difference></product>",
                1.0 / f.retract_band_kts,
                f.max_vc_kts
            ),
        );
        let setting = format!("<product><property>maneuver/flap</property>{gate}</product>");
        law(
            s,
            "flap: random in the Flight Zone below the flap speed, held in Danger, up in Re-climb",
            f.command_property,
            &format!(
                "          {}\n",
                blend(&setting, &setting, "<value>0</value>")
            ),
        );
    }
}

/// How long a flap segment holds its setting, s.
const FLAP_HOLD_S: Range = (20.0, 90.0);

/// First time a random command may change, s.
const COMMANDS_START_S: f64 = 8.0;

/// The random commands, each channel its own sequence of held values, as one table of sim time per
/// channel.
fn command_tables(p: &Profile, rng: &mut ChaCha12Rng, duration_s: f64, throttle0: f64) -> String {
    // Random commands, each channel its own sequence of held values. Each sequence is one table of
    // sim time (one continuous event), not one event per change: JSBSim evaluates every pending
    // event's condition every step, and thousands of timed events made long flights ~10x slower.
    let start = COMMANDS_START_S;
    let mut mode = Vec::new();
    let (mut theta_t, mut alpha_t, mut bank_t) = (Vec::new(), Vec::new(), Vec::new());
    let mut t = start;
    while t < duration_s {
        let hold = draw(rng, p.target_hold_s);
        let alpha_mode = rng.random_bool(p.alpha_mode_share.clamp(0.0, 1.0));
        mode.push((t, if alpha_mode { 1.0 } else { 0.0 }, hold));
        theta_t.push((t, draw(rng, p.theta_target_deg), hold));
        alpha_t.push((t, draw(rng, p.alpha_target_deg), hold));
        bank_t.push((t, signed(rng, p.bank_target_deg), hold));
        t += hold;
    }
    let mut tables = String::new();
    tables.push_str(&schedule("maneuver/alpha-mode", 0.0, &mode, 0.0));
    // Targets move smoothly: a step would be a full-stick jerk the profile does not ask for.
    tables.push_str(&schedule(
        "maneuver/theta-target-deg",
        0.0,
        &theta_t,
        p.target_ramp_s,
    ));
    tables.push_str(&schedule(
        "maneuver/alpha-target-deg",
        5.0,
        &alpha_t,
        p.target_ramp_s,
    ));
    tables.push_str(&schedule(
        "maneuver/bank-target-deg",
        0.0,
        &bank_t,
        p.target_ramp_s,
    ));
    let mut channel = |prop: &str,
                       initial: f64,
                       hold: Range,
                       tc: f64,
                       value: &mut dyn FnMut(&mut ChaCha12Rng) -> f64| {
        let mut t = start + draw(rng, (0.0, hold.1));
        let mut seq = Vec::new();
        while t < duration_s {
            let h = draw(rng, hold);
            seq.push((t, value(rng), h));
            t += h;
        }
        tables.push_str(&schedule(prop, initial, &seq, tc));
    };
    let (pa, ra, rda) = (p.pitch_stick_amp, p.roll_stick_amp, p.rudder_amp);
    // Half of the stick segments are neutral so the targets also get flown cleanly.
    channel(
        "maneuver/pitch-stick",
        0.0,
        p.stick_hold_s,
        0.15,
        &mut |r| {
            if r.random_bool(0.5) {
                0.0
            } else {
                r.random_range(-pa..=pa)
            }
        },
    );
    channel("maneuver/roll-stick", 0.0, p.stick_hold_s, 0.1, &mut |r| {
        if r.random_bool(0.5) {
            0.0
        } else {
            r.random_range(-ra..=ra)
        }
    });
    channel("maneuver/rudder", 0.0, p.rudder_hold_s, 0.2, &mut |r| {
        r.random_range(-rda..=rda)
    });
    let thr = p.throttle;
    channel(
        "maneuver/throttle",
        throttle0,
        p.throttle_hold_s,
        2.0,
        &mut |r| draw(r, thr),
    );
    let sb = p.speedbrake_share.clamp(0.0, 1.0);
    channel("maneuver/speedbrake", 0.0, (15.0, 60.0), 0.0, &mut |r| {
        if r.random_bool(sb) { 1.0 } else { 0.0 }
    });
    // Flap segments (long: a pilot sets the flap for a phase of flight), each down to a random
    // detent with the profile's share.
    if let Some(f) = presets::FLAPS {
        let share = p.flap_share.clamp(0.0, 1.0);
        channel(
            "maneuver/flap",
            0.0,
            FLAP_HOLD_S,
            0.0,
            &mut |r| match f.settings.len() {
                n if n > 0 && r.random_bool(share) => {
                    f.settings.get(r.random_range(0..n)).copied().unwrap_or(0.0)
                }
                _ => 0.0,
            },
        );
    }
    tables
}

/// The flight-test card's inputs at `scale` (1 = the first pass), from `t0`; returns the tables and
/// the time the card ends. Each input is a held value on one maneuver channel, back to neutral
/// after it, with time to settle between inputs: pitch doublet, pitch 3-2-1-1, roll doublet, rudder
/// doublet, rudder 3-2-1-1, steady-heading sideslips both ways (rudder held, the bank law holding
/// the wings level), a wind-up turn (banked, α target ramped up), a pull-up/push-over and an
/// accel/decel (full throttle, then idle with the speedbrake).
fn card_inputs(scale: f64, t0: f64, seq: &mut CardSeq) -> f64 {
    let c = &presets::CARD;
    let mut t = t0;
    // A doublet: +a for w, −a for w, then neutral; `settle` after.
    let doublet = |ch: &mut Vec<(f64, f64, f64)>, t: &mut f64, a: f64, w: f64, settle: f64| {
        ch.push((*t, a, w));
        ch.push((*t + w, -a, w));
        ch.push((*t + 2.0 * w, 0.0, settle));
        *t += 2.0 * w + settle;
    };
    // 3-2-1-1 in units of `u` s.
    let multistep = |ch: &mut Vec<(f64, f64, f64)>, t: &mut f64, a: f64, u: f64, settle: f64| {
        let mut at = *t;
        for (n, sign) in [(3.0, 1.0), (2.0, -1.0), (1.0, 1.0), (1.0, -1.0)] {
            ch.push((at, sign * a, n * u));
            at += n * u;
        }
        ch.push((at, 0.0, settle));
        *t = at + settle;
    };
    doublet(&mut seq.pitch, &mut t, c.pitch_doublet * scale, 1.0, 8.0);
    multistep(&mut seq.pitch, &mut t, c.pitch_multistep * scale, 0.4, 8.0);
    doublet(&mut seq.roll, &mut t, c.roll_doublet * scale, 1.0, 8.0);
    doublet(&mut seq.rudder, &mut t, c.rudder_doublet * scale, 1.0, 8.0);
    multistep(
        &mut seq.rudder,
        &mut t,
        c.rudder_multistep * scale,
        0.5,
        8.0,
    );
    for sign in [1.0, -1.0] {
        seq.rudder.push((t, sign * c.sideslip_rudder * scale, 12.0));
        seq.rudder.push((t + 12.0, 0.0, 8.0));
        t += 20.0;
    }
    // Wind-up turn: the card's bank, its α target ramped from start to peak (the peak growing with
    // scale); wings level first, then back to the pitch attitude (leaving α hold while banked pulls
    // the nose through).
    seq.bank.push((t, c.windup_bank_deg, 24.0));
    seq.mode.push((t + 3.0, 1.0, 27.0));
    seq.alpha.push((t + 3.0, c.windup_alpha_start_deg, 5.0));
    seq.alpha.push((
        t + 8.0,
        c.windup_alpha_deg + c.windup_alpha_per_scale_deg * scale,
        14.0,
    ));
    seq.alpha.push((t + 22.0, c.windup_alpha_end_deg, 8.0));
    seq.bank.push((t + 24.0, 0.0, 21.0));
    seq.mode.push((t + 30.0, 0.0, 15.0));
    t += 45.0;
    // Pull-up then push-over: offsets to the altitude-holding pitch attitude.
    seq.theta.push((t, c.pull_up_theta_deg * scale, 8.0));
    seq.theta
        .push((t + 8.0, c.push_over_theta_deg * scale, 8.0));
    seq.theta.push((t + 16.0, 0.0, 14.0));
    t += 30.0;
    // Accel/decel: the speed hold off, full throttle, then idle with the speedbrake.
    seq.hold.push((t, 0.0, 50.0));
    seq.throttle.push((t, 1.0, 25.0));
    seq.throttle.push((t + 25.0, 0.0, 25.0));
    seq.speedbrake.push((t + 25.0, 1.0, 25.0));
    seq.hold.push((t + 50.0, 1.0, 15.0));
    seq.speedbrake.push((t + 50.0, 0.0, 15.0));
    t + 65.0
}

/// The card's stall approach from `t0` (see [`FlightTestCard::stall_approach_s`]): the speed
/// hold off, the throttle at idle and the speedbrake out while the pitch attitude keeps holding
/// the altitude; at the slow speed, the banked α sweep in one-second steps (still at idle, so the
/// speed keeps falling); then full throttle, wings level, and the speed hold back on. Returns the
/// time it ends.
fn stall_approach(t0: f64, seq: &mut CardSeq) -> f64 {
    let c = &presets::CARD;
    let (decel_s, recover_s) = (c.stall_approach_s, 20.0);
    let (from, to) = (c.windup_alpha_deg, c.stall_approach_alpha_deg);
    let steps = ((to - from) / c.stall_approach_rate_deg_s).ceil().max(1.0);
    let pull_s = steps + 1.0;
    seq.hold.push((t0, 0.0, decel_s + pull_s + recover_s));
    seq.throttle.push((t0, 0.0, decel_s + pull_s));
    seq.speedbrake.push((t0, 1.0, decel_s));
    seq.speedbrake.push((t0 + decel_s, 0.0, pull_s));
    let t1 = t0 + decel_s;
    seq.bank.push((t1 - 3.0, c.windup_bank_deg, pull_s + 3.0));
    seq.bank.push((t1 + pull_s, 0.0, recover_s));
    seq.mode.push((t1, 1.0, pull_s));
    for k in 0..=steps as usize {
        let a = from + (to - from) * k as f64 / steps;
        seq.alpha.push((t1 + k as f64, a, 1.0));
    }
    seq.alpha.push((t1 + pull_s, c.windup_alpha_end_deg, 8.0));
    seq.mode.push((t1 + pull_s + 3.0, 0.0, recover_s));
    seq.throttle.push((t1 + pull_s, 1.0, recover_s));
    let end = t1 + pull_s + recover_s;
    seq.hold.push((end, 1.0, 10.0));
    end
}

/// The card's held values per channel (`(t, value, hold)`, as [`schedule`] takes them).
#[derive(Default)]
struct CardSeq {
    pitch: Vec<(f64, f64, f64)>,
    roll: Vec<(f64, f64, f64)>,
    rudder: Vec<(f64, f64, f64)>,
    mode: Vec<(f64, f64, f64)>,
    alpha: Vec<(f64, f64, f64)>,
    theta: Vec<(f64, f64, f64)>,
    bank: Vec<(f64, f64, f64)>,
    throttle: Vec<(f64, f64, f64)>,
    speedbrake: Vec<(f64, f64, f64)>,
    /// 1: the throttle holds the test point's speed; 0: `throttle` is the throttle.
    hold: Vec<(f64, f64, f64)>,
}

/// The flight-test card flown twice (the second pass with `second_pass_scale` times the inputs) as
/// maneuver tables, at `point`: between inputs the pitch attitude holds its altitude and the
/// throttle its speed, as a test pilot re-trims before each input.
fn card_tables(duration_s: f64, point: &TestPoint) -> String {
    let mut seq = CardSeq::default();
    let c = &presets::CARD;
    let end = card_inputs(1.0, COMMANDS_START_S + 10.0, &mut seq);
    let end = card_inputs(c.second_pass_scale, end + 10.0, &mut seq);
    stall_approach(end + 5.0, &mut seq);
    let keep = |v: Vec<(f64, f64, f64)>| -> Vec<(f64, f64, f64)> {
        v.into_iter().filter(|(t, _, _)| *t < duration_s).collect()
    };
    let mut tables = String::new();
    for (prop, initial) in [
        ("maneuver/card-theta-offset-deg", 0.0),
        ("maneuver/card-throttle", c.initial_throttle),
        ("maneuver/card-speed-hold", 1.0),
    ] {
        let _ = writeln!(
            tables,
            "    <property value=\"{initial}\"> {prop} </property>"
        );
    }
    for (prop, initial, v, ramp) in [
        ("maneuver/alpha-mode", 0.0, keep(seq.mode), 0.0),
        ("maneuver/card-theta-offset-deg", 0.0, keep(seq.theta), 2.0),
        ("maneuver/alpha-target-deg", 5.0, keep(seq.alpha), 3.0),
        ("maneuver/bank-target-deg", 0.0, keep(seq.bank), 3.0),
        ("maneuver/pitch-stick", 0.0, keep(seq.pitch), 0.05),
        ("maneuver/roll-stick", 0.0, keep(seq.roll), 0.05),
        ("maneuver/rudder", 0.0, keep(seq.rudder), 0.1),
        (
            "maneuver/card-throttle",
            c.initial_throttle,
            keep(seq.throttle),
            1.0,
        ),
        ("maneuver/card-speed-hold", 1.0, keep(seq.hold), 0.0),
        ("maneuver/speedbrake", 0.0, keep(seq.speedbrake), 0.0),
    ] {
        tables.push_str(&schedule(prop, initial, &v, ramp));
    }
    // θ target: 2° plus the card's offset plus 0.4° per 100 ft below the test point (±5°).
    law(
        &mut tables,
        "card: pitch attitude holding the test point's altitude, plus the card's offset",
        "maneuver/theta-target-deg",
        &format!(
            "          <sum><value>{}</value><property>maneuver/card-theta-offset-deg</property>{}</sum>\n",
            c.hold_pitch_deg,
            clamp(
                -c.altitude_hold_limit_deg,
                c.altitude_hold_limit_deg,
                &format!(
                    "<product><value>{}</value><difference><value>{}</value><property>position/h-sl-ft</property></difference></product>",
                    c.altitude_hold_per_ft, point.alt_ft
                )
            )
        ),
    );
    // Throttle: the test point's speed (0.02 per knot about 0.5), or the card's own.
    law(
        &mut tables,
        "card: throttle holding the test point's speed, or the card's accel/decel",
        "maneuver/throttle",
        &format!(
            "          <sum><product><property>maneuver/card-speed-hold</property>{}</product><product><difference><value>1</value><property>maneuver/card-speed-hold</property></difference><property>maneuver/card-throttle</property></product></sum>\n",
            clamp(
                0.0,
                1.0,
                &format!(
                    "<sum><value>{}</value><product><value>{}</value><difference><value>{}</value><property>velocities/vc-kts</property></difference></product></sum>",
                    c.speed_hold_throttle, c.speed_hold_per_kt, point.vc_kts
                )
            )
        ),
    );
    tables
}

/// 1-cosine gusts in random directions, each a timed event.
fn gusts(
    s: &mut String,
    p: &Profile,
    rng: &mut ChaCha12Rng,
    duration_s: f64,
    ood: Option<OodCase>,
) {
    let start = COMMANDS_START_S;
    let mut t = start + draw(rng, p.gust_interval_s);
    while t < duration_s {
        let drawn = draw(rng, p.gust_fps);
        let mag = if ood == Some(OodCase::Gust15) {
            OOD.gust_mps / crate::flight::FT_TO_M
        } else {
            drawn
        };
        let az = draw(rng, (0.0, std::f64::consts::TAU));
        let el = draw(rng, (-0.5, 0.5));
        let ramp = draw(rng, (0.5, 3.0));
        let steady = draw(rng, (0.0, 5.0));
        timed(
            s,
            t,
            &[
                ("atmosphere/cosine-gust/startup-duration-sec", ramp),
                ("atmosphere/cosine-gust/steady-duration-sec", steady),
                ("atmosphere/cosine-gust/end-duration-sec", ramp),
                ("atmosphere/cosine-gust/magnitude-ft_sec", mag),
                ("atmosphere/cosine-gust/frame", 3.0),
                (
                    "atmosphere/cosine-gust/X-velocity-ft_sec",
                    el.cos() * az.cos(),
                ),
                (
                    "atmosphere/cosine-gust/Y-velocity-ft_sec",
                    el.cos() * az.sin(),
                ),
                ("atmosphere/cosine-gust/Z-velocity-ft_sec", el.sin()),
                ("atmosphere/cosine-gust/start", 1.0),
            ],
        );
        t += draw(rng, p.gust_interval_s);
    }
}

/// Generates the flight `name` (used for its file names) of `duration_s` seconds. The random draws
/// happen in a fixed order (initial state, fuel and throttle, wind, commands, gusts), so a seed
/// always gives the same files.
pub fn generate(
    profile: &Profile,
    seed: u64,
    name: &str,
    duration_s: f64,
) -> Result<Maneuver, ManeuverError> {
    generate_case(profile, seed, name, duration_s, None)
}

/// [`generate`] with an out-of-distribution case: the same draws in the same order, the case's
/// value in place of its draw (sensor-fault cases fly exactly the in-distribution script).
pub fn generate_case(
    profile: &Profile,
    seed: u64,
    name: &str,
    duration_s: f64,
    ood: Option<OodCase>,
) -> Result<Maneuver, ManeuverError> {
    generate_planned(profile, seed, name, duration_s, ood, None)
}

/// [`generate_case`], or with `card` the flight-test card's inputs in place of the random commands
/// (the random draws of the initial state, mass, wind and gusts happen as for any flight).
pub fn generate_planned(
    profile: &Profile,
    seed: u64,
    name: &str,
    duration_s: f64,
    ood: Option<OodCase>,
    card: Option<&TestPoint>,
) -> Result<Maneuver, ManeuverError> {
    if name.is_empty()
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
    {
        return Err(ManeuverError::BadName(name.to_string()));
    }
    if !(1.0..=7200.0).contains(&duration_s) {
        return Err(ManeuverError::BadDuration(duration_s));
    }
    let p = profile;
    let mut rng = ChaCha12Rng::seed_from_u64(seed);
    let init_name = format!("{name}_init");
    let init_xml = init_file(p, &mut rng, seed, name, &init_name);
    let mut s = script_head(p, seed, name, &init_name, duration_s);
    let fuel = draw(&mut rng, p.fuel_per_tank_lbs);
    let throttle0 = draw(&mut rng, p.throttle);
    let mass = ood.and_then(OodCase::mass);
    fuel_and_trim(&mut s, fuel, mass.as_ref());
    wind(&mut s, p, &mut rng, ood);
    // The command tables go before the laws that read them (JSBSim runs the events in file order).
    if let Some(point) = card {
        s.push_str(&card_tables(duration_s, point));
    } else {
        s.push_str(&command_tables(p, &mut rng, duration_s, throttle0));
    }
    zone_laws(&mut s, p);
    control_laws(&mut s, p);
    gusts(&mut s, p, &mut rng, duration_s, ood);
    s.push_str("  </run>\n</runscript>\n");
    Ok(Maneuver {
        name: name.to_string(),
        script_xml: s,
        init_xml,
        duration_s,
    })
}

/// The files of maneuver `name` in `dir`: the runscript `NAME.xml` and its initialize file
/// `NAME_init.xml`.
pub fn files(dir: &Path, name: &str) -> (PathBuf, PathBuf) {
    (
        dir.join(format!("{name}.xml")),
        dir.join(format!("{name}_init.xml")),
    )
}

impl Maneuver {
    /// Writes its [`files`] into `dir`; returns the script path.
    pub fn write(&self, dir: &Path) -> Result<PathBuf, ManeuverError> {
        let (script, init) = files(dir, &self.name);
        for (path, text) in [(&script, &self.script_xml), (&init, &self.init_xml)] {
            std::fs::write(path, text).map_err(|source| ManeuverError::Write {
                path: path.clone(),
                source,
            })?;
        }
        Ok(script)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_campaign_plans_its_hours_with_its_ranges() {
        let c = Campaign {
            hours: 10.0,
            flight_min: 20.0,
            ranges: ProfileRanges {
                fuel_per_tank_lbs: (100.0, 3_400.0),
                steady_wind_fps: (0.0, 60.0),
                turb_severity: Some((2, 7)),
                gust_interval_s: None,
            },
            profiles: None,
        };
        let plan = Plan {
            campaign: Some(c.clone()),
            ..Plan::new(Preset::Campaign, 5)
        };
        let f = plan.flights().unwrap();
        assert_eq!(f.len(), 30);
        assert_eq!(
            f.iter()
                .filter(|x| x.split == crate::flight::Split::Test)
                .count(),
            3
        );
        assert_eq!(f[9].name, "test_high-alpha_00009");
        let mut seeds: Vec<u64> = f.iter().map(|x| x.seed).collect();
        seeds.sort_unstable();
        seeds.dedup();
        assert_eq!(seeds.len(), 30);
        for x in &f {
            let p = x.profile();
            assert_eq!(p.fuel_per_tank_lbs, (100.0, 3_400.0));
            assert_eq!(p.turb_severity, (2, 7));
            assert_eq!(p.kind, x.profile);
            assert_eq!(x.duration_s, 1_200.0);
        }
        // The same plan from the same spec; another seed, other flights.
        assert_eq!(plan.flights().unwrap(), f);
        let other = Plan {
            seed: 6,
            ..plan.clone()
        };
        assert_ne!(other.flights().unwrap()[0].seed, f[0].seed);
        // A campaign flight's script draws from the campaign's ranges: severity 2..7.
        let m = generate(&f[0].profile(), f[0].seed, "c", 60.0).unwrap();
        assert!(m.script_xml.contains("milspec/severity"));

        // Without a turbulence range, each profile keeps its own; mass and wind still change.
        let own = Plan {
            campaign: Some(Campaign {
                ranges: ProfileRanges {
                    turb_severity: None,
                    ..c.ranges.clone()
                },
                ..c
            }),
            ..plan
        };
        let mut kinds = std::collections::BTreeSet::new();
        for x in &own.flights().unwrap() {
            let p = x.profile();
            assert_eq!(p.turb_severity, Profile::preset(x.profile).turb_severity);
            assert_eq!(p.fuel_per_tank_lbs, (100.0, 3_400.0));
            kinds.insert(p.turb_severity);
        }
        assert_eq!(kinds.len(), 4, "{kinds:?}");
    }

    #[test]
    fn a_campaign_of_chosen_profiles_flies_them_with_its_gust_interval() {
        let mut c = Campaign {
            hours: 2.0,
            flight_min: 20.0,
            ..Campaign::default()
        };
        let all = Plan {
            campaign: Some(c.clone()),
            ..Plan::new(Preset::Campaign, 5)
        };
        c.profiles = Some(vec![ProfileKind::HighAlpha]);
        c.ranges.gust_interval_s = Some((10.0, 30.0));
        let plan = Plan {
            campaign: Some(c),
            ..Plan::new(Preset::Campaign, 5)
        };
        let f = plan.flights().unwrap();
        assert_eq!(f.len(), 6);
        for x in &f {
            assert_eq!(x.profile, ProfileKind::HighAlpha);
            assert_eq!(x.profile().gust_interval_s, (10.0, 30.0));
            assert_eq!(
                x.profile().alpha_target_deg,
                Profile::preset(ProfileKind::HighAlpha).alpha_target_deg
            );
        }
        // The same seeds as the four-profile campaign, flown on the chosen profile.
        let seeds = |p: &Plan| {
            p.flights()
                .unwrap()
                .iter()
                .map(|x| x.seed)
                .collect::<Vec<_>>()
        };
        assert_eq!(seeds(&plan), seeds(&all));
        // A 20-min flight of gusts every 10-30 s has many more of them than one at 40-150 s.
        let count = |x: &PlannedFlight| {
            let m = generate(&x.profile(), x.seed, "g", 1_200.0).unwrap();
            m.script_xml.matches("cosine-gust/start").count()
        };
        let dense = count(&f[0]);
        let sparse = count(&all.flights().unwrap()[1]);
        assert!(dense >= 40 && sparse <= 30, "{dense} against {sparse}");
        // A campaign without them writes the manifest it wrote before (no new keys).
        let json = serde_json::to_string(&all).unwrap();
        assert!(
            !json.contains("profiles") && !json.contains("gust_interval"),
            "{json}"
        );
    }

    #[test]
    fn a_campaign_of_no_or_absurd_hours_is_refused_before_planning() {
        let plan = |hours: f64, flight_min: f64| Plan {
            campaign: Some(Campaign {
                hours,
                flight_min,
                ..Campaign::default()
            }),
            ..Plan::new(Preset::Campaign, 1)
        };
        for hours in [f64::INFINITY, f64::NAN, 1e15, 10_000.5, 0.0, -1.0] {
            assert!(
                matches!(plan(hours, 20.0).flights(), Err(ManeuverError::BadCampaignHours(h)) if h.to_bits() == hours.to_bits()),
                "{hours}"
            );
        }
        for m in [0.5, 121.0, f64::NAN, f64::INFINITY] {
            assert!(
                matches!(plan(10.0, m).flights(), Err(ManeuverError::BadFlightMin(_))),
                "{m}"
            );
        }
        // The cap itself plans: 10,000 h of 120-min flights, and the count of 1-min flights.
        assert_eq!(plan(10_000.0, 120.0).flights().unwrap().len(), 5_000);
        let most = Campaign {
            hours: Campaign::MAX_HOURS,
            flight_min: 1.0,
            ..Campaign::default()
        };
        assert_eq!(most.flight_count().unwrap(), 600_000);
        assert_eq!(plan(1e-9, 20.0).flights().unwrap().len(), 1);
    }

    #[test]
    fn ood_plan_pairs_every_case_with_its_twin() {
        let plan = Preset::Ood.plan(1);
        assert_eq!(plan.len(), 2 * (1 + OodCase::ALL.len()));
        for f in &plan {
            assert_eq!(f.split, crate::flight::Split::Test);
            let twin = plan
                .iter()
                .find(|t| t.ood.is_none() && t.profile == f.profile)
                .unwrap();
            assert_eq!(f.seed, twin.seed, "{}", f.name);
            let case = f.ood.map_or("nominal", OodCase::name);
            assert_eq!(f.name, format!("ood_{case}_{}", f.profile.name()));
        }
        // No other preset's seed: training seeds end below 400, test seeds are 500 + k.
        let others: Vec<u64> = [Preset::Large, Preset::Ci]
            .iter()
            .flat_map(|p| p.plan(1))
            .map(|f| f.seed)
            .collect();
        assert!(plan.iter().all(|f| !others.contains(&f.seed)));
        // Other presets' manifests do not change: no `ood` key when there is no case.
        let paper = serde_json::to_string(&Preset::Paper.plan(1)).unwrap();
        assert!(!paper.contains("ood"));
    }

    #[test]
    fn ood_cases_change_only_their_condition() {
        let p = Profile::preset(ProfileKind::HighAlpha);
        let nominal = generate_case(&p, 9, "x", 300.0, None).unwrap().script_xml;
        // The script without the lines that set the case's condition.
        let without = |text: &str, keys: &[&str]| -> Vec<String> {
            text.lines()
                .filter(|l| !keys.iter().any(|k| l.contains(k)))
                .map(str::to_string)
                .collect()
        };
        for case in OodCase::ALL {
            let s = generate_case(&p, 9, "x", 300.0, Some(case))
                .unwrap()
                .script_xml;
            let keys: &[&str] = match case {
                OodCase::GpsOutage | OodCase::ImuStuck => &[],
                OodCase::MassLow | OodCase::MassHigh => &["contents-lbs", "pointmass-"],
                OodCase::Wind25 => &["wind-north-fps", "wind-east-fps"],
                OodCase::TurbulencePlus => &["milspec/", "turb-type"],
                OodCase::Gust15 => &["magnitude-ft_sec"],
            };
            assert_ne!(
                case != OodCase::GpsOutage && case != OodCase::ImuStuck,
                s == nominal
            );
            assert_eq!(without(&s, keys), without(&nominal, keys), "{case:?}");
            // The aircraft's weight as the script sets it: empty, the pilot's point mass (as
            // set, else the description's pilot) and every tank's fuel.
            let weight = || {
                let value = |l: &str| -> f64 {
                    let v = &l[l.find("value=\"").unwrap() + 7..];
                    v[..v.find('"').unwrap()].parse().unwrap()
                };
                let set = |key: &str| -> Vec<f64> {
                    s.lines().filter(|l| l.contains(key)).map(value).collect()
                };
                let pilot = set("pointmass-weight-lbs")
                    .first()
                    .copied()
                    .unwrap_or(PILOT_LBS);
                EMPTY_WEIGHT_LBS + pilot + set("contents-lbs").iter().sum::<f64>()
            };
            let (trained_low, trained_high) = trained_mass_lbs();
            match case {
                OodCase::MassLow => {
                    let target = trained_low * (1.0 - OOD.mass_margin);
                    assert!((weight() - target).abs() < 1.0, "{} vs {target}", weight());
                    assert!(s.contains(&format!(
                        "tank[{}]/contents-lbs\" value=\"{:.1}\"",
                        AIRCRAFT.mass.internal_tanks[0], OOD.low_fuel_per_tank_lb
                    )));
                }
                OodCase::MassHigh => {
                    let target = trained_high * (1.0 + OOD.mass_margin);
                    assert!((weight() - target).abs() < 1.0, "{} vs {target}", weight());
                }
                OodCase::TurbulencePlus => assert!(s.contains(&format!(
                    "milspec/severity\" value=\"{}\"",
                    OOD.turbulence_severity
                ))),
                OodCase::Gust15 => {
                    let gust = format!("value=\"{:.4}\"", OOD.gust_mps / crate::flight::FT_TO_M);
                    assert!(
                        s.lines()
                            .filter(|l| l.contains("magnitude-ft_sec"))
                            .all(|l| l.contains(&gust)),
                        "{gust}"
                    )
                }
                _ => {}
            }
            assert!(
                case.faults()
                    .iter()
                    .all(|f| f.parse::<crate::faults::Fault>().is_ok())
            );
        }
    }

    #[test]
    fn same_seed_same_script_other_seed_other_script() {
        let p = Profile::preset(ProfileKind::Aggressive);
        let a = generate(&p, 3, "a", 120.0).unwrap();
        let b = generate(&p, 3, "a", 120.0).unwrap();
        let c = generate(&p, 4, "a", 120.0).unwrap();
        assert_eq!(a, b);
        assert_ne!(a.script_xml, c.script_xml);
        assert!(a.script_xml.contains(&format!(
            "<use aircraft=\"{}\" initialize=\"a_init\"/>",
            AIRCRAFT.jsbsim_model
        )));
    }

    #[test]
    fn large_plan_extends_paper_without_changing_it() {
        let paper = Preset::Paper.plan(1);
        let large = Preset::Large.plan(1);
        assert_eq!(paper.len(), 20);
        assert_eq!(large.len(), 68);
        assert_eq!(&large[..20], &paper[..]);
        let names: std::collections::BTreeSet<_> = large.iter().map(|f| &f.name).collect();
        let seeds: std::collections::BTreeSet<_> = large.iter().map(|f| f.seed).collect();
        assert_eq!((names.len(), seeds.len()), (68, 68));
        let tests = large
            .iter()
            .filter(|f| f.split == crate::flight::Split::Test);
        assert_eq!(tests.count(), 4);
    }

    #[test]
    fn script_dt_is_exactly_one_over_sim_hz() {
        let m = generate(&Profile::preset(ProfileKind::Gentle), 1, "g", 60.0).unwrap();
        let at = m.script_xml.find(" dt=\"").unwrap() + 5;
        let text = &m.script_xml[at..at + m.script_xml[at..].find('"').unwrap()];
        assert_eq!(text, "0.008333333333333333");
        assert_eq!(text.parse::<f64>().unwrap(), 1.0 / 120.0);
        assert_eq!(SCRIPT_DT_S, 1.0 / f64::from(SIM_HZ));
    }

    #[test]
    fn zone_event_chain_is_present_in_order() {
        for kind in ProfileKind::ALL {
            let x = generate(&Profile::preset(kind), 5, "z", 300.0)
                .unwrap()
                .script_xml;
            // Declared 0 before the events run.
            assert!(x.contains("<property value=\"0\"> maneuver/zone </property>"));
            // Conditions, state machine, flags, then the laws that read them, after the tables.
            let order = [
                "<event name=\"maneuver/bank-target-deg schedule\"",
                "<event name=\"zone: Danger Zone trigger",
                "<event name=\"zone: Danger over",
                "<event name=\"zone: back well inside the Flight Zone",
                "<event name=\"zone: 0 Flight, 1 Danger, 2 Re-climb",
                "<event name=\"zone flag: in the Danger Zone\"",
                "<event name=\"zone flag: in the Re-climb Zone\"",
                "<event name=\"Re-climb Zone pitch target",
                "<event name=\"elevator:",
                "<event name=\"throttle:",
            ];
            let at: Vec<usize> = order
                .iter()
                .map(|e| x.find(e).unwrap_or_else(|| panic!("{kind:?}: no {e}")))
                .collect();
            assert!(at.windows(2).all(|w| w[0] < w[1]), "{kind:?}: order {at:?}");
            // One writer of the zone, from t = 1 s, reading its own previous value and only ever
            // producing the three codes.
            assert_eq!(x.matches("<set name=\"maneuver/zone\">").count(), 1);
            let ev = &x[at[4]..at[5]];
            assert!(ev.contains("<condition> simulation/sim-time-sec ge 1.0 </condition>"));
            assert!(ev.contains("<property>maneuver/trigger</property><value>1</value>"));
            assert!(ev.contains("<eq><property>maneuver/zone</property><value>1</value></eq>"));
            assert!(ev.contains("<eq><property>maneuver/zone</property><value>2</value></eq>"));
            let values: std::collections::BTreeSet<&str> = ev
                .split("<value>")
                .skip(1)
                .map(|v| &v[..v.find('<').unwrap()])
                .collect();
            assert_eq!(values, ["0", "1", "2"].into_iter().collect());
            // The laws blend all three zones.
            let elev = &x[at[8]..at[9]];
            for p in [
                "maneuver/danger",
                "maneuver/reclimb",
                "maneuver/theta-recover-deg",
                "maneuver/theta-reclimb-deg",
            ] {
                assert!(elev.contains(p), "{kind:?}: elevator law without {p}");
            }
        }
    }

    #[test]
    fn ood_cases_describe_their_sizes() {
        assert_eq!(
            [lbs(999.0), lbs(1_000.0), lbs(16_005.7), lbs(1_234_567.0)],
            ["999", "1,000", "16,006", "1,234,567"]
        );
        let light = trained_mass_lbs().0;
        assert!(OodCase::MassLow.describe().starts_with(&format!(
            "{} lb, {:.0} % below the lightest trained mass ({} lb)",
            lbs(light * (1.0 - OOD.mass_margin)),
            100.0 * OOD.mass_margin,
            lbs(light)
        )));
        assert!(
            OodCase::Wind25
                .describe()
                .starts_with(&format!("a steady {:.1} m/s wind", OOD.wind_mps))
        );
        assert!(
            OodCase::TurbulencePlus
                .describe()
                .contains(&format!("severity {}", OOD.turbulence_severity))
        );
        for case in OodCase::ALL {
            assert!(!case.describe().is_empty() && !case.describe().contains('\n'));
        }
    }

    #[test]
    fn the_flap_follows_the_description() {
        for kind in ProfileKind::ALL {
            let p = Profile::preset(kind);
            let x = generate(&p, 7, "f", 1200.0).unwrap().script_xml;
            let Some(f) = presets::FLAPS else {
                assert!(
                    !x.contains("maneuver/flap"),
                    "{kind:?}: a flap without [flaps]"
                );
                continue;
            };
            assert!(x.contains("<property value=\"0\"> maneuver/flap </property>"));
            // One law sets the command, after the table it reads; it reads the speed (the
            // retraction band) and the zone flags.
            let set = format!("<set name=\"{}\">", f.command_property);
            assert_eq!(x.matches(&set).count(), 1, "{kind:?}");
            let table = x.find("<event name=\"maneuver/flap schedule\"").unwrap();
            let law = x.find(&set).unwrap();
            assert!(table < law, "{kind:?}: the law before its table");
            let law_xml = &x[law..law + x[law..].find("</event>").unwrap()];
            for needle in [
                "velocities/vc-kts",
                "maneuver/reclimb",
                &format!("<value>{}</value>", f.max_vc_kts),
            ] {
                assert!(
                    law_xml.contains(needle),
                    "{kind:?}: flap law without {needle}"
                );
            }
            // Every scheduled value is up or one of the detents; some are down where the profile
            // lowers the flap, none where it does not.
            let rows = &x[table..];
            let rows =
                &rows[rows.find("<tableData>").unwrap() + 11..rows.find("</tableData>").unwrap()];
            let values: Vec<f64> = rows
                .lines()
                .filter_map(|l| l.split_whitespace().nth(1))
                .map(|v| v.parse().unwrap())
                .collect();
            assert!(values.len() > 20, "{kind:?}: {} rows", values.len());
            for v in &values {
                assert!(
                    *v == 0.0 || f.settings.iter().any(|s| (s - v).abs() < 1e-4),
                    "{kind:?}: flap command {v} is no detent of {:?}",
                    f.settings
                );
            }
            let down = values.iter().filter(|v| **v > 0.0).count();
            assert_eq!(down > 0, p.flap_share > 0.0, "{kind:?}: {down} rows down");
        }
    }

    #[test]
    fn header_tells_the_stock_command_and_stays_well_formed() {
        let x = generate(&Profile::preset(ProfileKind::HighAlpha), 2, "h_1", 60.0)
            .unwrap()
            .script_xml;
        assert!(x.contains(
            "f.load_script(os.path.abspath('h_1.xml'), 0.0, os.path.abspath('h_1_init.xml'))"
        ));
        // XML comments may not contain "--"; the first "<use " is the element, not a comment.
        for c in x.split("<!--").skip(1) {
            let body = &c[..c.find("-->").unwrap()];
            assert!(!body.contains("--"), "comment with --: {body}");
        }
        assert!(
            x[x.find("<use ").unwrap()..]
                .starts_with(&format!("<use aircraft=\"{}\"", AIRCRAFT.jsbsim_model))
        );
        assert!(x.find("<use ").unwrap() > x.find("-->").unwrap());
    }

    #[test]
    fn names_that_are_not_file_names_are_refused() {
        let p = Profile::preset(ProfileKind::Gentle);
        assert!(matches!(
            generate(&p, 1, "../x", 60.0),
            Err(ManeuverError::BadName(_))
        ));
        assert!(matches!(
            generate(&p, 1, "x", 0.0),
            Err(ManeuverError::BadDuration(_))
        ));
    }
}

/// Dataset presets of `hil-sim generate`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Preset {
    /// 16 training flights (4 per profile) of 15–20 min, plus 4 test flights (one per profile) of 6–7 min.
    Paper,
    /// 4 training flights (one per profile) of 3 min plus 1 test flight of 3 min.
    Ci,
    /// The `paper` preset's flights (same seeds, same bytes, same test flights) plus 12 more training
    /// flights per profile: 64 training flights, about 19 h (18.8 h training + 0.4 h test). More flights, each with its own mass,
    /// wind and maneuvers, is what lets a model generalise to unseen flights.
    Large,
    /// Out-of-distribution test flights, kept apart from every training preset: for the gentle and
    /// the high-α profile, an in-distribution twin (`ood_nominal_<profile>`) and one flight per
    /// case (`ood_<case>_<profile>`: mass 15 % below and above the trained range, 25 m/s wind,
    /// turbulence severity 7, 15 m/s gusts, a 30 s GPS loss, a stuck accelerometer) with the twin's seed,
    /// 6 min each (16 flights; docs/results/ood.md).
    Ood,
    /// A flight campaign of any size: its flight-hours and the mass, wind and turbulence ranges of
    /// every profile (`hil-sim generate --preset campaign --hours H ...`).
    Campaign,
    /// Flight-test cards for calibration, 30 min in calm air: at three altitude/speed points, pitch,
    /// roll and rudder doublets, 3-2-1-1 multisteps, steady-heading sideslips, a wind-up turn, a
    /// push-over/pull-up and an accel/decel, flown twice; each flight records the flight-test nose
    /// boom (α/β vanes, pitot-static) in NAME.boom.csv (docs/sensors.md).
    #[value(name = "flight-test")]
    #[serde(rename = "flight-test")]
    FlightTest,
}

/// The mass, wind and turbulence ranges a campaign gives every profile in place of its own.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ProfileRanges {
    pub fuel_per_tank_lbs: Range,
    pub steady_wind_fps: Range,
    /// `None`: every profile keeps its own severity range (slow high-α flight stays in lighter
    /// turbulence than aggressive flight, as in the training presets).
    pub turb_severity: Option<(u32, u32)>,
    /// The time between two 1-cosine gusts, s; `None`: every profile keeps its own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gust_interval_s: Option<Range>,
}

impl ProfileRanges {
    pub fn apply(&self, p: &mut Profile) {
        p.fuel_per_tank_lbs = self.fuel_per_tank_lbs;
        p.steady_wind_fps = self.steady_wind_fps;
        if let Some(t) = self.turb_severity {
            p.turb_severity = t;
        }
        if let Some(g) = self.gust_interval_s {
            p.gust_interval_s = g;
        }
    }
}

/// A campaign: flights of `flight_min` minutes, its profiles (the four unless it names some) in
/// turn, until `hours` of flight; every tenth flight is a test flight. Seeds come from their own
/// stream of the base seed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Campaign {
    pub hours: f64,
    pub flight_min: f64,
    pub ranges: ProfileRanges,
    /// The profiles flown in turn; `None`: all four.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub profiles: Option<Vec<ProfileKind>>,
}

impl Default for Campaign {
    /// 100 h of 20-min flights over the training presets' ranges.
    fn default() -> Campaign {
        Campaign {
            hours: 100.0,
            flight_min: 20.0,
            ranges: ProfileRanges {
                fuel_per_tank_lbs: profiles_range(|p| p.fuel_per_tank_lbs),
                steady_wind_fps: profiles_range(|p| p.steady_wind_fps),
                turb_severity: Some(profiles_range(|p| p.turb_severity)),
                gust_interval_s: None,
            },
            profiles: None,
        }
    }
}

/// Every tenth campaign flight is a test flight.
const CAMPAIGN_TEST_EVERY: usize = 10;

impl Campaign {
    /// The largest campaign planned, flight-hours: docs/scale.md projects one of 10,000 h (at most
    /// 600,000 flights of a minute). A larger one is refused before anything is planned.
    pub const MAX_HOURS: f64 = 10_000.0;
    /// The flight lengths a campaign may have, minutes.
    pub const FLIGHT_MIN: Range = (1.0, 120.0);

    /// How many flights the campaign plans, or why it cannot be planned (hours not in
    /// (0, [`Self::MAX_HOURS`]], flight length not in [`Self::FLIGHT_MIN`]).
    pub fn flight_count(&self) -> Result<usize, ManeuverError> {
        if !(self.hours > 0.0 && self.hours <= Self::MAX_HOURS) {
            return Err(ManeuverError::BadCampaignHours(self.hours));
        }
        let (lo, hi) = Self::FLIGHT_MIN;
        if !(self.flight_min >= lo && self.flight_min <= hi) {
            return Err(ManeuverError::BadFlightMin(self.flight_min));
        }
        // In 1..=600,000 by the two checks above: the conversion is exact.
        let n = (self.hours * 60.0 / self.flight_min).ceil().max(1.0);
        Ok(n as usize)
    }

    fn flights(&self, base_seed: u64) -> Result<Vec<PlannedFlight>, ManeuverError> {
        let n = self.flight_count()?;
        let mut rng = ChaCha12Rng::seed_from_u64(base_seed ^ 0x6361_6d70_6169_676e);
        let profiles = match &self.profiles {
            Some(p) if !p.is_empty() => p.as_slice(),
            _ => ProfileKind::ALL.as_slice(),
        };
        Ok((0..n)
            .map(|i| {
                let profile = profiles[i % profiles.len()];
                let test = i % CAMPAIGN_TEST_EVERY == CAMPAIGN_TEST_EVERY - 1;
                PlannedFlight {
                    name: format!(
                        "{}_{}_{i:05}",
                        if test { "test" } else { "train" },
                        profile.name()
                    ),
                    split: if test {
                        crate::flight::Split::Test
                    } else {
                        crate::flight::Split::Train
                    },
                    profile,
                    seed: rng.random::<u64>(),
                    duration_s: self.flight_min * 60.0,
                    ood: None,
                    ranges: Some(self.ranges.clone()),
                    card: None,
                }
            })
            .collect())
    }
}

/// What a dataset is planned from: a preset, the base seed, and for a campaign its parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    pub preset: Preset,
    pub seed: u64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub campaign: Option<Campaign>,
    /// The JSBSim aircraft directory whose `MODEL/MODEL.xml` (the description's model,
    /// `f16/f16.xml`) every flight flies (`--aircraft-dir`); `None`: JSBSim's own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aircraft_dir: Option<std::path::PathBuf>,
    /// Only the preset's test flights (the same flights, seeds and bytes as in the whole preset):
    /// scoring a model on another aircraft needs nothing else.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub test_only: bool,
}

impl Plan {
    pub fn new(preset: Preset, seed: u64) -> Plan {
        Plan {
            preset,
            seed,
            campaign: None,
            aircraft_dir: None,
            test_only: false,
        }
    }

    /// The planned flights; a campaign that cannot be planned ([`Campaign::flight_count`]) is an
    /// error.
    pub fn flights(&self) -> Result<Vec<PlannedFlight>, ManeuverError> {
        let mut f = match (self.preset, &self.campaign) {
            (Preset::Campaign, Some(c)) => c.flights(self.seed)?,
            (p, _) => p.plan(self.seed),
        };
        if self.test_only {
            f.retain(|f| f.split == crate::flight::Split::Test);
        }
        Ok(f)
    }
}

/// One planned flight of a preset.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlannedFlight {
    pub name: String,
    pub split: crate::flight::Split,
    pub profile: ProfileKind,
    pub seed: u64,
    pub duration_s: f64,
    /// The out-of-distribution case (`ood` preset only; absent from other presets' manifests).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ood: Option<OodCase>,
    /// Ranges that replace the profile's own (`campaign` preset only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ranges: Option<ProfileRanges>,
    /// The flight-test card's test point (`flight-test` preset only): the card's inputs instead of
    /// random ones, in calm air, at this altitude and speed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub card: Option<TestPoint>,
}

/// A flight-test point: trimmed start altitude and calibrated airspeed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TestPoint {
    pub alt_ft: f64,
    pub vc_kts: f64,
}

/// The `flight-test` preset's test points, the aircraft description's (the F-16's: low and slow,
/// medium, high).
pub fn test_points() -> impl Iterator<Item = TestPoint> {
    AIRCRAFT.flight_test_points.iter().map(|p| TestPoint {
        alt_ft: p.alt_ft,
        vc_kts: p.vc_kts,
    })
}

/// Length of one test point's flight (the card flown twice, the second time with larger inputs), s.
pub const CARD_FLIGHT_S: f64 = 600.0;

impl PlannedFlight {
    /// The profile this flight is drawn from, with the campaign's ranges if it has them.
    pub fn profile(&self) -> Profile {
        let mut p = Profile::preset(self.profile);
        if let Some(r) = &self.ranges {
            r.apply(&mut p);
        }
        if let Some(c) = &self.card {
            // A flight test is flown at its point in calm air, at a mid-range mass.
            p.init_alt_ft = (c.alt_ft, c.alt_ft);
            p.init_vc_kts = (c.vc_kts, c.vc_kts);
            let fuel = presets::CARD.fuel_per_tank_lb;
            p.fuel_per_tank_lbs = (fuel, fuel);
            p.turb_severity = (0, 0);
            p.steady_wind_fps = (0.0, 0.0);
            p.gust_fps = (0.0, 0.0);
            p.gust_interval_s = (1e9, 1e9);
            let throttle = presets::CARD.initial_throttle;
            p.throttle = (throttle, throttle);
        }
        p
    }
}

impl PlannedFlight {
    /// Training flight `k` of profile number `pi`: seed `base × 1000 + pi × 100 + k`, duration drawn.
    fn train(
        base_seed: u64,
        pi: usize,
        kind: ProfileKind,
        k: usize,
        rng: &mut ChaCha12Rng,
        len: Range,
    ) -> PlannedFlight {
        PlannedFlight {
            name: format!("train_{}_{k:02}", kind.name()),
            split: crate::flight::Split::Train,
            profile: kind,
            seed: base_seed
                .wrapping_mul(1000)
                .wrapping_add((pi * 100 + k) as u64),
            duration_s: draw(rng, len).round(),
            ood: None,
            ranges: None,
            card: None,
        }
    }
}

impl Preset {
    pub fn name(self) -> &'static str {
        match self {
            Preset::Paper => "paper",
            Preset::Ci => "ci",
            Preset::Large => "large",
            Preset::Ood => "ood",
            Preset::Campaign => "campaign",
            Preset::FlightTest => "flight-test",
        }
    }

    /// The flights of this preset for a base seed. Test flights take seeds from a separate range so
    /// no test flight repeats a training one.
    pub fn plan(self, base_seed: u64) -> Vec<PlannedFlight> {
        use crate::flight::Split;
        // Paper: 4 training flights of 15–20 min per profile.
        const PAPER_PER_PROFILE: usize = 4;
        const PAPER_TRAIN_LEN: Range = (900.0, 1200.0);
        if self == Preset::Ood {
            return Self::ood_plan(base_seed);
        }
        if self == Preset::Campaign {
            // The default campaign (100 h of 20-min flights) always plans.
            return Campaign::default().flights(base_seed).unwrap_or_default();
        }
        if self == Preset::FlightTest {
            return test_points()
                .enumerate()
                .map(|(k, c)| PlannedFlight {
                    name: format!(
                        "flighttest_{:02}kft_{:.0}kts",
                        (c.alt_ft / 1000.0).round(),
                        c.vc_kts
                    ),
                    split: Split::Test,
                    profile: ProfileKind::Gentle,
                    seed: base_seed.wrapping_mul(1000).wrapping_add(800 + k as u64),
                    duration_s: CARD_FLIGHT_S,
                    ood: None,
                    ranges: None,
                    card: Some(c),
                })
                .collect();
        }
        if self == Preset::Large {
            // Paper's plan untouched, then 12 more per profile from their own random stream.
            let mut out = Preset::Paper.plan(base_seed);
            let mut rng = ChaCha12Rng::seed_from_u64(base_seed ^ 0x6c61_7267_6570_6c61);
            for (pi, kind) in ProfileKind::ALL.iter().enumerate() {
                for k in PAPER_PER_PROFILE..16 {
                    out.push(PlannedFlight::train(
                        base_seed,
                        pi,
                        *kind,
                        k,
                        &mut rng,
                        PAPER_TRAIN_LEN,
                    ));
                }
            }
            return out;
        }
        let mut rng = ChaCha12Rng::seed_from_u64(base_seed ^ 0x6d61_6e65_7576_6572);
        let mut out = Vec::new();
        let (per_profile, train_len, test_profiles, test_len): (
            usize,
            Range,
            &[ProfileKind],
            Range,
        ) = match self {
            // (Large, Ood, Campaign and FlightTest returned above.)
            Preset::Paper | Preset::Large | Preset::Ood | Preset::Campaign | Preset::FlightTest => {
                (
                    PAPER_PER_PROFILE,
                    PAPER_TRAIN_LEN,
                    &ProfileKind::ALL,
                    (360.0, 420.0),
                )
            }
            Preset::Ci => (
                1,
                (180.0, 180.0),
                &[ProfileKind::Aggressive],
                (180.0, 180.0),
            ),
        };
        for (pi, kind) in ProfileKind::ALL.iter().enumerate() {
            for k in 0..per_profile {
                out.push(PlannedFlight::train(
                    base_seed, pi, *kind, k, &mut rng, train_len,
                ));
            }
        }
        for (k, kind) in test_profiles.iter().enumerate() {
            out.push(PlannedFlight {
                name: format!("test_{}_{k:02}", kind.name()),
                split: Split::Test,
                profile: *kind,
                seed: base_seed.wrapping_mul(1000).wrapping_add(500 + k as u64),
                duration_s: draw(&mut rng, test_len).round(),
                ood: None,
                ranges: None,
                card: None,
            });
        }
        out
    }

    /// The `ood` preset: seeds `base × 1000 + 700 + profile number`, a range no other preset uses.
    fn ood_plan(base_seed: u64) -> Vec<PlannedFlight> {
        const OOD_PROFILES: [ProfileKind; 2] = [ProfileKind::Gentle, ProfileKind::HighAlpha];
        const OOD_LEN_S: f64 = 360.0;
        let mut out = Vec::new();
        for (pi, kind) in OOD_PROFILES.iter().enumerate() {
            let seed = base_seed.wrapping_mul(1000).wrapping_add(700 + pi as u64);
            let cases = std::iter::once(None).chain(OodCase::ALL.iter().copied().map(Some));
            for ood in cases {
                out.push(PlannedFlight {
                    name: format!(
                        "ood_{}_{}",
                        ood.map_or("nominal", OodCase::name),
                        kind.name()
                    ),
                    split: crate::flight::Split::Test,
                    profile: *kind,
                    seed,
                    duration_s: OOD_LEN_S,
                    ood,
                    ranges: None,
                    card: None,
                });
            }
        }
        out
    }
}
