//! Input feature sets, the sensor-suite guard (a model of a suite only reads what that suite
//! delivers) and the leakage guard: air data can never become a model input.
use crate::error::{Error, Result};
use crate::prep::Angle;
use estimator_core::{Channel, Feature, Lag, Suite};

/// Dataset truth columns straight from the simulator: air data (what the model estimates, or derived
/// from it) and the other truth values. None of them can ever be a model input. The list is the
/// dataset format's own (`hil_sim::dataset::TRUTH_COLUMNS`), so a new truth column is guarded too.
pub use hil_sim::dataset::TRUTH_COLUMNS as AIR_DATA_COLUMNS;

/// Parses a feature name. Air-data names are refused with [`Error::Leakage`] before any lookup, and
/// only names of [`Feature::ALL`] (sensed channels and features derived from them) are accepted.
pub fn parse_feature(name: &str) -> Result<Feature> {
    let name = name.trim();
    if AIR_DATA_COLUMNS.contains(&name) {
        return Err(Error::Leakage(name.to_string()));
    }
    Feature::from_name(name).ok_or_else(|| {
        Error::UnknownFeature(
            name.to_string(),
            Feature::ALL
                .iter()
                .map(|f| f.name())
                .collect::<Vec<_>>()
                .join(", "),
        )
    })
}

/// The paper's Table 1 inputs for α.
pub const TABLE1_ALPHA: [Feature; 10] = [
    Feature::Sensor(Channel::Elevator),
    Feature::Sensor(Channel::Lef),
    Feature::Sensor(Channel::Tef),
    Feature::Sensor(Channel::Flaperon),
    Feature::Sensor(Channel::Speedbrake),
    Feature::Sensor(Channel::AccelX),
    Feature::Sensor(Channel::AccelZ),
    Feature::Sensor(Channel::GpsSpeed),
    Feature::Sensor(Channel::Throttle),
    Feature::Sensor(Channel::GpsAlt),
];

/// The paper's Table 1 inputs for β.
pub const TABLE1_BETA: [Feature; 5] = [
    Feature::Sensor(Channel::Rudder),
    Feature::Sensor(Channel::Aileron),
    Feature::Sensor(Channel::GyroR),
    Feature::Sensor(Channel::GyroP),
    Feature::Sensor(Channel::AccelY),
];

/// Physics features (IMU + GPS only) added by the `physics` feature set.
pub const PHYSICS_ALPHA: [Feature; 3] = [
    Feature::FxOverRhoV2,
    Feature::FzOverRhoV2,
    Feature::MachProxy,
];
pub const PHYSICS_BETA: [Feature; 3] = [Feature::FyOverRhoV2, Feature::MachProxy, Feature::RhoV2];

/// Channels whose short-term changes the `dynamics` set adds for α, at every [`Lag`]: the load factor
/// and pitch rate building, the speed and altitude trends (energy), the elevator and throttle moving.
pub const DYNAMICS_ALPHA_DELTAS: [Channel; 8] = [
    Channel::AccelZ,
    Channel::GyroQ,
    Channel::AccelX,
    Channel::GpsSpeed,
    Channel::GpsAlt,
    Channel::Elevator,
    Channel::Lef,
    Channel::Throttle,
];

/// The same for β: lateral acceleration, yaw and roll rates, rudder and aileron.
pub const DYNAMICS_BETA_DELTAS: [Channel; 5] = [
    Channel::AccelY,
    Channel::GyroR,
    Channel::GyroP,
    Channel::Rudder,
    Channel::Aileron,
];

/// Longitudinal state for β (the side force per degree of sideslip depends on α).
pub const DYNAMICS_BETA_EXTRA: [Feature; 3] = [
    Feature::Sensor(Channel::GyroQ),
    Feature::Sensor(Channel::AccelZ),
    Feature::FzOverRhoV2,
];

/// What the `egi-dynamics` set adds to `dynamics` for α: the EGI quantities that do not depend on
/// which way the aircraft or the wind points (roll, pitch, climb rate, fuel), the ground velocity in
/// body axes and the kinematic angle of attack. Heading and the north/east velocities enter only
/// through the body-axis features: on their own they would let a model learn the training flights'
/// wind directions (random per flight), which no test flight shares.
pub const EGI_ALPHA: [Feature; 7] = [
    Feature::AlphaKin,
    Feature::UGround,
    Feature::WGround,
    Feature::Sensor(Channel::Pitch),
    Feature::Sensor(Channel::Roll),
    Feature::Sensor(Channel::VelDown),
    Feature::Sensor(Channel::Fuel),
];

/// The same for β: the kinematic sideslip, the lateral ground velocity, roll and pitch (gravity's
/// side component), and fuel.
pub const EGI_BETA: [Feature; 6] = [
    Feature::BetaKin,
    Feature::VGround,
    Feature::UGround,
    Feature::Sensor(Channel::Roll),
    Feature::Sensor(Channel::Pitch),
    Feature::Sensor(Channel::Fuel),
];

/// What the `egi-hybrid` set adds to `egi-hybrid-fast`: the filter's air speed and lift scale, the
/// outputs that re-converge slowly after an outage. With them the network sees all the model-based
/// air-data filter's estimates (`estimator_core::filter`) and learns where to trust the filter
/// (slow, high-α flight, where lift tells α) and where its own inputs do better.
pub const FILTER_SLOW_FEATURES: [Feature; 2] = [Feature::FilterAirspeed, Feature::FilterLiftScale];

/// The force scales the filter learns in flight (lift, side force): on an airframe unlike the
/// model they leave 1, and a network that reads them can tell that its model is off.
pub const FILTER_SCALE_FEATURES: [Feature; 2] =
    [Feature::FilterLiftScale, Feature::FilterSideScale];

/// The filter outputs that are back within a second of a sensor outage: α, β and their 1σ. Its air
/// speed (through the along-track wind) and lift scale re-converge over tens of seconds when an
/// outage falls in the first minutes of flight, and a network that reads them inherits that
/// (docs/results/hybrid.md). The `egi-hybrid-fast` set, and `egi-hybrid-fast-d2`, read
/// only these.
pub const FILTER_FAST_FEATURES: [Feature; 4] = [
    Feature::FilterAlpha,
    Feature::FilterBeta,
    Feature::FilterSigmaAlpha,
    Feature::FilterSigmaBeta,
];

/// The lags of the `dynamics` sets' delta features (every set built on `dynamics` reads these).
pub const DYNAMICS_LAGS: [Lag; 4] = [Lag::F1, Lag::F4, Lag::F10, Lag::F20];

/// The named feature set the build's aircraft ships (its description's `estimator.features`):
/// `trainer train`'s default and the report's shipped rows.
pub const SHIPPED: &str = estimator_core::aircraft::AIRCRAFT.estimator.features;

/// The channels whose 120 Hz sub-samples the `egi120` sets read: β's lateral force and the
/// surfaces that make it (the rudder's chatter in turbulence is in both at 120 Hz, in neither
/// channel at 20 Hz)...
pub const SUB_BETA: [Channel; 4] = [
    Channel::AccelY,
    Channel::Rudder,
    Channel::Aileron,
    Channel::GyroR,
];
/// ... and α's normal force, pitch rate and elevator.
pub const SUB_ALPHA: [Channel; 3] = [Channel::AccelZ, Channel::GyroQ, Channel::Elevator];

/// Every sub-sample of a frame period of each of `channels`.
fn subsamples(channels: &[Channel]) -> Vec<Feature> {
    channels
        .iter()
        .flat_map(|c| (0..estimator_core::channels::SUBSAMPLES as u8).map(|k| Feature::Sub(*c, k)))
        .collect()
}

/// Whether a feature reads the axial force directly (thrust less drag): the longitudinal
/// accelerometer, the throttle, F_x / ρV², and their changes and sub-samples.
fn reads_axial_balance(f: &Feature) -> bool {
    match f {
        Feature::FxOverRhoV2 => true,
        Feature::Sensor(c) | Feature::Delta(c, _) | Feature::Sub(c, _) => {
            matches!(c, Channel::AccelX | Channel::Throttle)
        }
        _ => false,
    }
}

fn deltas<'a>(channels: &'a [Channel], lags: &'a [Lag]) -> impl Iterator<Item = Feature> + 'a {
    channels
        .iter()
        .flat_map(move |c| lags.iter().map(move |l| Feature::Delta(*c, *l)))
}

/// A named feature set: `table1`, `physics` (Table 1 + specific force / ρV² + Mach proxy), `dynamics`
/// (physics + pitch rate for α, longitudinal state for β, and each angle's delta features),
/// `egi-dynamics` (dynamics + [`EGI_ALPHA`] / [`EGI_BETA`]: needs the `egi` suite), `egi-hybrid`
/// (egi-hybrid-fast + [`FILTER_SLOW_FEATURES`]: all the air-data filter's estimates), `egi-hybrid-fast`
/// (egi-dynamics + the filter outputs that recover within a second, [`FILTER_FAST_FEATURES`]),
/// `egi-hybrid-fast-d2` (egi-hybrid-fast + the β dynamics channels' 2-frame deltas), `egi120-beta`
/// and `egi120` (egi-hybrid-fast-d2 + the 120 Hz sub-samples of β's, and α's, channels: the F-16's
/// shipped set; each aircraft's is [`SHIPPED`]), `egi120-side-scale` (egi120 + the filter's side-force scale for β),
/// `egi120-gyro-p` (egi120 + the roll gyro's 120 Hz sub-samples for β), `egi120-gyro-p-beta-alpha`
/// (egi120-gyro-p with β also reading every input of α's network: the c172p's shipped set),
/// `egi120-gyro-p-beta-alpha-own` (the same without the inputs that read a sensor β's set did not),
/// `egi-hybrid-scales` (egi-hybrid-fast-d2 + the filter's lift and side-force scales),
/// `egi-hybrid-turb` (egi-hybrid + the filter's turbulence index), or explicit comma-separated
/// lists `alpha=a,b,...;beta=c,d,...`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FeatureSet {
    pub name: String,
    pub alpha: Vec<Feature>,
    pub beta: Vec<Feature>,
}

/// The sensor suite of a `--suite` argument.
pub fn parse_suite(name: &str) -> Result<Suite> {
    Suite::from_name(name.trim()).ok_or_else(|| Error::UnknownSuite(name.to_string()))
}

impl FeatureSet {
    /// The smallest sensor suite that delivers every feature of both angles.
    pub fn suite(&self) -> Suite {
        let sources = self
            .alpha
            .iter()
            .chain(&self.beta)
            .fold(0, |m, f| m | f.sources());
        Suite::covering(sources).unwrap_or(Suite::Egi120)
    }

    /// Refuses, naming the first one, a feature that `suite`'s frames do not deliver.
    pub fn check_suite(&self, suite: Suite) -> Result<()> {
        match self
            .alpha
            .iter()
            .chain(&self.beta)
            .find(|f| f.sources() & !suite.channels() != 0)
        {
            Some(f) => Err(Error::SuiteFeature {
                feature: f.name().to_string(),
                needs: f.suite().name(),
                suite: suite.name(),
            }),
            None => Ok(()),
        }
    }

    /// The inputs of `angle`'s cascade.
    pub fn for_angle(&self, angle: Angle) -> &[Feature] {
        match angle {
            Angle::Alpha => &self.alpha,
            Angle::Beta => &self.beta,
        }
    }

    /// The set without the comma-separated feature names in `names` (each must be in the set),
    /// named `<set> without <names>`; the set itself for an empty list.
    pub fn without(self, names: &str) -> Result<FeatureSet> {
        let drop = names
            .split(',')
            .filter(|n| !n.trim().is_empty())
            .map(parse_feature)
            .collect::<Result<Vec<_>>>()?;
        if drop.is_empty() {
            return Ok(self);
        }
        for f in &drop {
            if !self.alpha.contains(f) && !self.beta.contains(f) {
                return Err(Error::UnknownFeature(
                    f.name().to_string(),
                    format!("the features of `{}`", self.name),
                ));
            }
        }
        let keep = |v: Vec<Feature>| v.into_iter().filter(|f| !drop.contains(f)).collect();
        Ok(FeatureSet {
            name: format!("{} without {}", self.name, names.trim()),
            alpha: keep(self.alpha),
            beta: keep(self.beta),
        })
    }

    /// This set with `alpha` and `beta` appended to its angles' features, named `name`.
    fn extended(self, name: &str, alpha: &[Feature], beta: &[Feature]) -> Result<FeatureSet> {
        Ok(FeatureSet {
            name: name.into(),
            alpha: self
                .alpha
                .into_iter()
                .chain(alpha.iter().copied())
                .collect(),
            beta: self.beta.into_iter().chain(beta.iter().copied()).collect(),
        })
    }

    /// This set with β also reading each input of α's it does not read yet that `keep` keeps.
    fn beta_reads_alpha(self, name: &str, keep: impl Fn(&Feature) -> bool) -> Result<FeatureSet> {
        let extra: Vec<Feature> = self
            .alpha
            .iter()
            .filter(|f| !self.beta.contains(f) && keep(f))
            .copied()
            .collect();
        self.extended(name, &[], &extra)
    }

    pub fn parse(spec: &str) -> Result<FeatureSet> {
        match spec {
            "table1" => Ok(FeatureSet {
                name: "table1".into(),
                alpha: TABLE1_ALPHA.to_vec(),
                beta: TABLE1_BETA.to_vec(),
            }),
            "physics" => Ok(FeatureSet {
                name: "physics".into(),
                alpha: TABLE1_ALPHA.iter().chain(&PHYSICS_ALPHA).copied().collect(),
                beta: TABLE1_BETA.iter().chain(&PHYSICS_BETA).copied().collect(),
            }),
            "dynamics" => Ok(FeatureSet {
                name: "dynamics".into(),
                alpha: TABLE1_ALPHA
                    .iter()
                    .chain(&PHYSICS_ALPHA)
                    .copied()
                    .chain([Feature::Sensor(Channel::GyroQ)])
                    .chain(deltas(&DYNAMICS_ALPHA_DELTAS, &DYNAMICS_LAGS))
                    .collect(),
                beta: TABLE1_BETA
                    .iter()
                    .chain(&PHYSICS_BETA)
                    .chain(&DYNAMICS_BETA_EXTRA)
                    .copied()
                    .chain(deltas(&DYNAMICS_BETA_DELTAS, &DYNAMICS_LAGS))
                    .collect(),
            }),
            "egi-dynamics" => FeatureSet::parse("dynamics")?.extended(spec, &EGI_ALPHA, &EGI_BETA),
            "egi-hybrid" => FeatureSet::parse("egi-hybrid-fast")?.extended(
                spec,
                &FILTER_SLOW_FEATURES,
                &FILTER_SLOW_FEATURES,
            ),
            "egi-hybrid-fast" => FeatureSet::parse("egi-dynamics")?.extended(
                spec,
                &FILTER_FAST_FEATURES,
                &FILTER_FAST_FEATURES,
            ),
            // egi-hybrid-fast plus the β dynamics channels 2 frames back: with the 1-frame deltas,
            // the three newest samples, enough to undo the IMU's 2nd-order anti-alias filter
            // (docs/results/beta-floor.md). β only: the same deltas for α gained nothing on the
            // validation flights (docs/results/hybrid.md, "Alternatives measured and not used").
            "egi-hybrid-fast-d2" => {
                let b: Vec<Feature> = deltas(&DYNAMICS_BETA_DELTAS, &[Lag::F2]).collect();
                FeatureSet::parse("egi-hybrid-fast")?.extended(spec, &[], &b)
            }
            // egi-hybrid-fast-d2 plus the period's 120 Hz sub-samples of β's lateral channels
            // (`egi120-beta`), and of α's normal ones too (`egi120`): the egi120 suite.
            "egi120-beta" => {
                FeatureSet::parse("egi-hybrid-fast-d2")?.extended(spec, &[], &subsamples(&SUB_BETA))
            }
            "egi120" => FeatureSet::parse("egi-hybrid-fast-d2")?.extended(
                spec,
                &subsamples(&SUB_ALPHA),
                &subsamples(&SUB_BETA),
            ),
            // egi120 plus, for β, the side-force scale the filter learns in flight: on an airframe
            // whose side force is not the model's, how far the lateral force per degree of β is off.
            // Measured, not shipped: better on the model, worse on three of the four variants
            // (docs/airframes.md).
            "egi120-side-scale" => {
                FeatureSet::parse("egi120")?.extended(spec, &[], &[Feature::FilterSideScale])
            }
            // egi120 plus, for β, the roll gyro's 120 Hz sub-samples: with the yaw gyro's, the
            // body's angular accelerations, which the gust rates' roll and yaw moments move
            // (docs/results/beta-floor.md).
            "egi120-gyro-p" => {
                FeatureSet::parse("egi120")?.extended(spec, &[], &subsamples(&[Channel::GyroP]))
            }
            // egi120-gyro-p with β also reading every input of α's network: what fixes α (the
            // kinematic α, the pitch, the vertical velocity, the normal force) fixes, through the
            // lift, the dynamic pressure β's lateral force is read against.
            "egi120-gyro-p-beta-alpha" => {
                FeatureSet::parse("egi120-gyro-p")?.beta_reads_alpha(spec, |_| true)
            }
            // egi120-gyro-p-beta-alpha without the inputs that read a sensor β's own set does not
            // (the flap's position excepted, which the lift needs): a fault of the elevator's,
            // the throttle's or the axial accelerometer's does not hold β. Measured on the c172p,
            // not shipped: its validation β 3 % worse (docs/results/c172p.md).
            "egi120-gyro-p-beta-alpha-own" => {
                let s = FeatureSet::parse("egi120-gyro-p")?;
                let own = s
                    .beta
                    .iter()
                    .fold(Channel::Tef.bit(), |m, f| m | f.sources());
                s.beta_reads_alpha(spec, |f| f.sources() & !own == 0)
            }
            // egi120-gyro-p without α's inputs that read the axial force directly: the
            // longitudinal accelerometer, the throttle, F_x / ρV² and their changes (the GPS
            // speed's and altitude's changes stay). With them the c172p's α moves with its drag
            // (docs/results/c172p/airframe-sensitivity.md); without them it barely does. Measured
            // on the c172p, not shipped: α much worse on the model, little better on the
            // variants (docs/results/c172p.md).
            "egi120-gyro-p-no-axial" => {
                let mut s = FeatureSet::parse("egi120-gyro-p")?;
                s.name = spec.into();
                s.alpha.retain(|f| !reads_axial_balance(f));
                Ok(s)
            }
            // egi-hybrid-fast-d2 plus the force scales the filter learns in flight: what tells an
            // airframe unlike the model. Measured, not shipped: it loses on the 20-minute test
            // flight (docs/airframes.md).
            "egi-hybrid-scales" => FeatureSet::parse("egi-hybrid-fast-d2")?.extended(
                spec,
                &FILTER_SCALE_FEATURES,
                &FILTER_SCALE_FEATURES,
            ),
            // egi-hybrid plus the filter's turbulence index: better on the validation flights, but
            // slow to come back after a sensor outage (docs/results/hybrid.md), so not shipped.
            "egi-hybrid-turb" => {
                let t = [Feature::FilterTurbulence];
                FeatureSet::parse("egi-hybrid")?.extended(spec, &t, &t)
            }
            custom => {
                let mut alpha = None;
                let mut beta = None;
                for part in custom.split(';') {
                    let (k, v) = part.split_once('=').ok_or_else(|| {
                        Error::UnknownFeature(
                            part.into(),
                            "feature sets: table1, physics, dynamics, egi-dynamics, egi-hybrid, egi-hybrid-fast, egi-hybrid-fast-d2, egi120-beta, egi120, egi120-side-scale, egi120-gyro-p, egi120-gyro-p-beta-alpha, egi120-gyro-p-beta-alpha-own, egi120-gyro-p-no-axial, egi-hybrid-scales, egi-hybrid-turb, or alpha=a,b;beta=c,d"
                                .into(),
                        )
                    })?;
                    let list = v
                        .split(',')
                        .map(parse_feature)
                        .collect::<Result<Vec<_>>>()?;
                    match k.trim() {
                        "alpha" => alpha = Some(list),
                        "beta" => beta = Some(list),
                        other => {
                            return Err(Error::UnknownFeature(other.into(), "alpha, beta".into()));
                        }
                    }
                }
                Ok(FeatureSet {
                    name: custom.into(),
                    alpha: alpha.unwrap_or_else(|| TABLE1_ALPHA.to_vec()),
                    beta: beta.unwrap_or_else(|| TABLE1_BETA.to_vec()),
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fast_hybrid_is_the_hybrid_without_the_slowly_recovering_filter_outputs() {
        // The base of the shipped set: the ablation of docs/results/hybrid.md trained the same network as
        // `egi-hybrid --without filter_airspeed_mps,filter_lift_scale`, in the same input order.
        let h = FeatureSet::parse("egi-hybrid")
            .unwrap()
            .without("filter_airspeed_mps,filter_lift_scale")
            .unwrap();
        let f = FeatureSet::parse("egi-hybrid-fast").unwrap();
        assert_eq!((h.alpha, h.beta), (f.alpha, f.beta));
        assert_eq!(f.name, "egi-hybrid-fast");
    }

    #[test]
    fn the_two_frame_deltas_are_only_in_the_set_that_asks_for_them() {
        let fast = FeatureSet::parse("egi-hybrid-fast").unwrap();
        let d2 = FeatureSet::parse("egi-hybrid-fast-d2").unwrap();
        let lag2 = |f: &Feature| matches!(f, Feature::Delta(_, Lag::F2));
        assert!(!fast.alpha.iter().chain(&fast.beta).any(lag2));
        assert_eq!(d2.alpha, fast.alpha);
        assert_eq!(d2.beta[..fast.beta.len()], fast.beta[..]);
        assert_eq!(
            d2.beta[fast.beta.len()..],
            DYNAMICS_BETA_DELTAS.map(|c| Feature::Delta(c, Lag::F2))[..]
        );
        assert_eq!(d2.suite(), Suite::Egi);
    }

    #[test]
    fn the_scales_set_is_the_two_frame_set_with_the_filter_scales_last() {
        let d2 = FeatureSet::parse("egi-hybrid-fast-d2").unwrap();
        let s = FeatureSet::parse("egi-hybrid-scales").unwrap();
        for (with, base) in [(&s.alpha, &d2.alpha), (&s.beta, &d2.beta)] {
            assert_eq!(with[..base.len()], base[..]);
            assert_eq!(with[base.len()..], FILTER_SCALE_FEATURES[..]);
        }
        assert_eq!(s.suite(), Suite::Egi);
    }

    #[test]
    fn the_side_scale_set_is_egi120_with_the_side_force_scale_last_in_beta() {
        let base = FeatureSet::parse("egi120").unwrap();
        let s = FeatureSet::parse("egi120-side-scale").unwrap();
        assert_eq!(s.name, "egi120-side-scale");
        assert_eq!(s.alpha, base.alpha);
        assert_eq!(s.beta[..base.beta.len()], base.beta[..]);
        assert_eq!(s.beta[base.beta.len()..], [Feature::FilterSideScale]);
        assert_eq!(s.suite(), Suite::Egi120);
    }

    #[test]
    fn the_shipped_set_of_the_builds_aircraft_is_a_known_egi120_set() {
        let s = FeatureSet::parse(SHIPPED).unwrap();
        assert_eq!(s.suite(), Suite::Egi120);
    }

    #[test]
    fn the_no_axial_set_is_gyro_p_without_the_direct_axial_inputs_of_alpha() {
        let full = FeatureSet::parse("egi120-gyro-p").unwrap();
        let s = FeatureSet::parse("egi120-gyro-p-no-axial").unwrap();
        assert_eq!(s.name, "egi120-gyro-p-no-axial");
        assert_eq!(s.beta, full.beta);
        let dropped: Vec<Feature> = full
            .alpha
            .iter()
            .copied()
            .filter(|f| !s.alpha.contains(f))
            .collect();
        // AccelX and Throttle, each with its four lagged changes, and F_x / ρV².
        assert_eq!(dropped.len(), 11, "{dropped:?}");
        assert!(dropped.contains(&Feature::FxOverRhoV2));
        assert!(dropped.contains(&Feature::Sensor(Channel::Throttle)));
        assert!(s.alpha.contains(&Feature::Sensor(Channel::AccelZ)));
        assert!(s.alpha.iter().all(|f| full.alpha.contains(f)));
    }

    #[test]
    fn the_beta_alpha_set_gives_beta_every_input_of_alpha_once_and_leaves_alpha_alone() {
        let base = FeatureSet::parse("egi120-gyro-p").unwrap();
        let s = FeatureSet::parse("egi120-gyro-p-beta-alpha").unwrap();
        assert_eq!(s.name, "egi120-gyro-p-beta-alpha");
        assert_eq!(s.alpha, base.alpha);
        assert_eq!(s.beta[..base.beta.len()], base.beta[..]);
        assert!(base.alpha.iter().all(|f| s.beta.contains(f)));
        let mut unique = s.beta.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), s.beta.len());
        // Something is added: α reads the kinematic α, which β's own set does not.
        assert!(!base.beta.contains(&Feature::AlphaKin));
        assert!(s.beta.contains(&Feature::AlphaKin));
        assert_eq!(s.suite(), Suite::Egi120);
    }

    #[test]
    fn the_gyro_p_set_is_egi120_with_the_roll_gyros_sub_samples_last_in_beta() {
        let base = FeatureSet::parse("egi120").unwrap();
        let s = FeatureSet::parse("egi120-gyro-p").unwrap();
        assert_eq!(s.alpha, base.alpha);
        assert_eq!(s.beta[..base.beta.len()], base.beta[..]);
        let subs: Vec<Feature> = (0..6).map(|k| Feature::Sub(Channel::GyroP, k)).collect();
        assert_eq!(s.beta[base.beta.len()..], subs[..]);
        assert_eq!(s.suite(), Suite::Egi120);
    }

    #[test]
    fn without_drops_named_features_from_both_angles_and_refuses_strangers() {
        let full = FeatureSet::parse("egi-hybrid-turb").unwrap();
        let s = full
            .clone()
            .without("filter_airspeed_mps, filter_lift_scale")
            .unwrap();
        for f in [Feature::FilterAirspeed, Feature::FilterLiftScale] {
            assert!(!s.alpha.contains(&f) && !s.beta.contains(&f));
        }
        assert_eq!(s.alpha.len() + 2, full.alpha.len());
        assert_eq!(s.beta.len() + 2, full.beta.len());
        assert_eq!(
            s.name,
            "egi-hybrid-turb without filter_airspeed_mps, filter_lift_scale"
        );
        assert_eq!(full.clone().without("").unwrap(), full);
        // Not in the set, unknown, or air data: refused.
        let t1 = FeatureSet::parse("table1").unwrap();
        assert!(matches!(
            t1.clone().without("filter_alpha_rad"),
            Err(Error::UnknownFeature(..))
        ));
        assert!(t1.clone().without("no_such_feature").is_err());
        assert!(matches!(t1.without("alpha_deg"), Err(Error::Leakage(_))));
    }

    #[test]
    fn air_data_can_never_become_an_input() {
        for col in AIR_DATA_COLUMNS {
            assert!(
                matches!(parse_feature(col), Err(Error::Leakage(_))),
                "{col}"
            );
            let spec = format!("alpha=elevator_deg,{col}");
            assert!(FeatureSet::parse(&spec).is_err(), "{spec}");
            // No candidate feature (sensed channel or derived) carries an air-data column's name.
            assert!(Feature::ALL.iter().all(|f| f.name() != col));
        }
        // Every candidate is computed from sensed channels (and their 120 Hz sub-samples) only.
        let sensed =
            estimator_core::channels::ALL_VALID | estimator_core::channels::SUBSAMPLES_VALID;
        for f in Feature::ALL {
            assert_ne!(f.sources(), 0);
            assert_eq!(f.sources() & !sensed, 0);
        }
        for set in ["table1", "physics", "dynamics", "egi-dynamics"] {
            let s = FeatureSet::parse(set).unwrap();
            for f in s.alpha.iter().chain(&s.beta) {
                assert!(!AIR_DATA_COLUMNS.contains(&f.name()));
            }
        }
    }

    #[test]
    fn only_feature_names_are_accepted() {
        // Dataset columns that are neither air data nor a Feature (time, sequence, typos) are refused
        // with a typed error; every Feature::ALL name round-trips.
        for col in ["time_s", "seq", "", "ALPHA_DEG", "vt", "qbar", "w_aero"] {
            assert!(
                matches!(parse_feature(col), Err(Error::UnknownFeature(..))),
                "{col:?}"
            );
        }
        for f in Feature::ALL {
            assert_eq!(parse_feature(f.name()).unwrap(), f);
        }
        assert!(matches!(
            FeatureSet::parse("beta=rudder_deg,qbar_pa"),
            Err(Error::Leakage(c)) if c == "qbar_pa"
        ));
    }

    #[test]
    fn a_table1_run_cannot_select_egi_features() {
        for set in ["table1", "physics", "dynamics"] {
            let s = FeatureSet::parse(set).unwrap();
            assert_eq!(s.suite(), Suite::Table1, "{set}");
            s.check_suite(Suite::Table1).unwrap();
            s.check_suite(Suite::Egi).unwrap();
        }
        let e = FeatureSet::parse("egi-dynamics").unwrap();
        assert_eq!(e.suite(), Suite::Egi);
        e.check_suite(Suite::Egi).unwrap();
        assert!(matches!(
            e.check_suite(Suite::Table1),
            Err(Error::SuiteFeature {
                needs: "egi",
                suite: "table1",
                ..
            })
        ));
        let custom = FeatureSet::parse("alpha=elevator_deg,alpha_kin_rad").unwrap();
        let err = custom.check_suite(Suite::Table1).unwrap_err().to_string();
        assert!(
            err.contains("alpha_kin_rad") && err.contains("--suite egi"),
            "{err}"
        );
        let fuel = FeatureSet::parse("beta=fuel_qty_kg").unwrap();
        assert!(fuel.check_suite(Suite::Table1).is_err());
        // egi-dynamics is dynamics plus the EGI features, nothing of dynamics dropped.
        let d = FeatureSet::parse("dynamics").unwrap();
        assert_eq!(e.alpha[..d.alpha.len()], d.alpha[..]);
        assert_eq!(e.beta[..d.beta.len()], d.beta[..]);
        assert_eq!(parse_suite("egi").unwrap(), Suite::Egi);
        assert!(matches!(parse_suite("adc"), Err(Error::UnknownSuite(_))));
    }

    #[test]
    fn table1_and_custom_sets_parse() {
        let t = FeatureSet::parse("table1").unwrap();
        assert_eq!((t.alpha.len(), t.beta.len()), (10, 5));
        let p = FeatureSet::parse("physics").unwrap();
        assert_eq!((p.alpha.len(), p.beta.len()), (13, 8));
        let c = FeatureSet::parse("alpha=elevator_deg,mach_proxy;beta=accel_y_mps2").unwrap();
        assert_eq!(
            c.alpha,
            vec![Feature::Sensor(Channel::Elevator), Feature::MachProxy]
        );
        assert_eq!(c.beta, vec![Feature::Sensor(Channel::AccelY)]);
        assert!(FeatureSet::parse("alpha=airspeed").is_err());
    }
}
