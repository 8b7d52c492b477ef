//! Train → quantize → evaluate one angle's cascade; evaluate the compiled-in model.
use crate::data::{Dataset, Flight, Role};
use crate::metrics::FlightMetrics;
use crate::model::{Cascade, Curves, FloatLayer, TrainConfig, predict_all, train};
use crate::prep::{Angle, Prep};
use crate::quant::{QCascade, quantize_cascade};
use estimator_core::{Estimator, Feature, Suite};

/// Network sizes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Size {
    /// CI: α 32-16, β 16-8 per part.
    Small,
    /// α 64-32-16, β 32-16 per part: for the larger datasets.
    Medium,
    /// α 128-64-32, β 64-32-16 per part: the largest that keeps both cascades, the filter and the
    /// link inside the Cortex-M4F step budget (`docs/results/wcet.md`).
    Large,
    /// α as `Medium`, β as `Large` (α 64-32-16, β 64-32-16 per part): the shipped sizes, each
    /// angle's the better on the validation flights over three seeds (`docs/results/hybrid.md`).
    MediumWideBeta,
    /// α as `Medium`, β 128-64-32 per part: a wider β (on the c172p's image 210,000 instructions
    /// at the worst step and 209,656 B of flash, inside the target's limits:
    /// `docs/results/c172p.md`).
    MediumWiderBeta,
    /// Paper Table/Section VI: α 512-256-128-64-32, β 32-16-8-4-2 per part.
    Paper,
}

impl Size {
    /// Every size, in the order `--config`'s messages list them.
    pub const ALL: [Size; 6] = [
        Size::Small,
        Size::Medium,
        Size::Large,
        Size::MediumWideBeta,
        Size::MediumWiderBeta,
        Size::Paper,
    ];

    pub fn parse(s: &str) -> Option<Size> {
        Size::ALL.into_iter().find(|z| z.name() == s)
    }

    /// "small, medium, …, medium-wider-beta or paper": the names a `--config` may take.
    pub fn choices() -> String {
        let names: Vec<&str> = Size::ALL.iter().map(|z| z.name()).collect();
        match names.split_last() {
            Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
            None => String::new(),
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Size::Small => "small",
            Size::Medium => "medium",
            Size::Large => "large",
            Size::MediumWideBeta => "medium-wide-beta",
            Size::MediumWiderBeta => "medium-wider-beta",
            Size::Paper => "paper",
        }
    }
    pub fn default_epochs(self) -> usize {
        match self {
            Size::Small => 40,
            Size::Medium
            | Size::Large
            | Size::MediumWideBeta
            | Size::MediumWiderBeta
            | Size::Paper => 30,
        }
    }
    pub fn hidden(self, a: Angle) -> &'static [usize] {
        match (self, a) {
            (Size::Small, Angle::Alpha) => &[32, 16],
            (Size::Small, Angle::Beta) => &[16, 8],
            (Size::Medium | Size::MediumWideBeta | Size::MediumWiderBeta, Angle::Alpha) => {
                &[64, 32, 16]
            }
            (Size::Medium, Angle::Beta) => &[32, 16],
            (Size::Large, Angle::Alpha) => &[128, 64, 32],
            (Size::Large | Size::MediumWideBeta, Angle::Beta) => &[64, 32, 16],
            (Size::MediumWiderBeta, Angle::Beta) => &[128, 64, 32],
            (Size::Paper, Angle::Alpha) => &[512, 256, 128, 64, 32],
            (Size::Paper, Angle::Beta) => &[32, 16, 8, 4, 2],
        }
    }
}

/// (flight, truth, float prediction, int8 prediction), degrees.
pub type TestSeries = (String, Vec<f64>, Vec<f64>, Vec<f64>);

/// A trained and quantized cascade with its test metrics.
pub struct Trained {
    pub angle: Angle,
    pub model: Cascade,
    pub part1: Vec<FloatLayer>,
    pub part2: Vec<FloatLayer>,
    pub q: QCascade,
    pub curves: Curves,
    pub float_test: FlightMetrics,
    pub int_test: FlightMetrics,
    /// Integer-reference metrics on the validation flights: what a model choice may look at (the
    /// test flights only report it).
    pub int_val: FlightMetrics,
    /// Float and int8 predictions (degrees) per test flight, for plots.
    pub series: Vec<TestSeries>,
}

pub fn flights(ds: &Dataset, role: Role) -> Vec<&Flight> {
    ds.flights(role).collect()
}

/// Evenly spread training rows' inputs for activation calibration.
pub fn calibration(prep: &Prep, train: &[&Flight], max_rows: usize) -> Vec<Vec<f32>> {
    crate::data::spread_rows(train, max_rows)
        .into_iter()
        .map(|(fl, i)| {
            let mut x = Vec::new();
            prep.input(&fl.features[i], &mut x);
            x
        })
        .collect()
}

/// What training an angle reads from the training and validation flights, taken before training
/// so that the training flights' features can go ([`Dataset::drop_training_features`]) while it
/// runs.
pub struct Prepared {
    pub angle: Angle,
    prep: Prep,
    hidden: &'static [usize],
    train: crate::model::Matrix,
    val: crate::model::Matrix,
    /// Evenly spread training rows' inputs, for the activation calibration of the quantization.
    calib: Vec<Vec<f32>>,
}

/// The scaling, envelopes, matrices and calibration rows of one angle's training ([`Prepared`]);
/// without the dataset's gyro-bias twins unless `twins` (the angle then trains on exactly the rows
/// it would without them).
pub fn prepare_angle(
    ds: &Dataset,
    angle: Angle,
    features: &[Feature],
    size: Size,
    twins: bool,
) -> Prepared {
    let mut tr = flights(ds, Role::Train);
    tr.retain(|f| twins || !f.gyro_bias_twin);
    let va = flights(ds, Role::Val);
    let mut prep = Prep::fit(angle, features, &tr);
    if features.iter().any(|f| f.needs_filter()) {
        // Only an exported model carries it: the scaling fits of baselines and benches skip it.
        prep.turbulence = crate::prep::turbulence_envelope(&tr);
        prep.lift_scale = crate::prep::lift_scale_envelope(&tr);
    }
    Prepared {
        angle,
        hidden: size.hidden(angle),
        train: prep.matrix(&tr),
        val: prep.matrix(&va),
        calib: calibration(&prep, &tr, 20_000),
        prep,
    }
}

/// Trains a [`Prepared`] angle, quantizes it and scores it on `ds`'s validation and test flights
/// (never its training flights, which may have gone).
pub fn train_prepared(p: Prepared, ds: &Dataset, cfg: &TrainConfig) -> Trained {
    let Prepared {
        angle,
        prep,
        hidden,
        train: tm,
        val: vm,
        calib,
    } = p;
    let n_in = prep.n_inputs();
    let (model, curves) = train(|d| Cascade::new(n_in, hidden, d), cfg, &tm, &vm);
    drop((tm, vm));
    let part1 = model.part1.export();
    let part2 = model.part2.export();
    let q = quantize_cascade(&prep, &part1, &part2, &calib);
    let (float_test, int_test, series) = evaluate(&model, &q, ds);
    let int_val = int8_metrics(&q, ds, Role::Val);
    Trained {
        angle,
        model,
        part1,
        part2,
        q,
        curves,
        float_test,
        int_test,
        int_val,
        series,
    }
}

pub fn train_angle(
    ds: &Dataset,
    angle: Angle,
    features: &[Feature],
    size: Size,
    cfg: &TrainConfig,
) -> Trained {
    train_prepared(prepare_angle(ds, angle, features, size, true), ds, cfg)
}

/// A model's answers per flight (name, degrees).
pub type Answers = Vec<(String, Vec<f64>)>;

/// A cascade's float and int8 (integer reference) answers on one flight, degrees.
fn flight_answers(model: &Cascade, q: &QCascade, fl: &Flight) -> (Vec<f64>, Vec<f64>) {
    let prep = &q.prep;
    let (_, po) = predict_all(model, &prep.inputs(&[fl]), prep.n_inputs());
    let float = po.iter().map(|z| prep.out_deg(*z as f64)).collect();
    (float, int8_answers(q, fl))
}

/// A cascade's int8 (integer reference) answers on one flight, degrees.
fn int8_answers(q: &QCascade, fl: &Flight) -> Vec<f64> {
    int8_mean_answers(std::slice::from_ref(q), fl)
}

/// The mean of several cascades' int8 answers on one flight, degrees: each frame's in
/// millidegrees, rounded half away from zero (one cascade: its own answers).
fn int8_mean_answers(qs: &[QCascade], fl: &Flight) -> Vec<f64> {
    let n = qs.len().max(1) as i64;
    fl.features
        .iter()
        .map(|v| {
            let sum: i64 = qs.iter().map(|q| i64::from(q.reference(v).angle)).sum();
            mean_rounded(sum, n) as f64 / 1000.0
        })
        .collect()
}

/// Integer-reference metrics of a cascade on the flights of `role` (no float pass).
pub fn int8_metrics(q: &QCascade, ds: &Dataset, role: Role) -> FlightMetrics {
    int8_mean_metrics(std::slice::from_ref(q), ds, role)
}

/// Integer-reference metrics of the mean of several cascades of one angle (an ensemble: each
/// frame's answer is the mean of theirs in millidegrees, rounded half away from zero) on the
/// flights of `role`. One cascade gives its own metrics; no cascade gives empty metrics.
pub fn int8_mean_metrics(qs: &[QCascade], ds: &Dataset, role: Role) -> FlightMetrics {
    let Some(first) = qs.first() else {
        return FlightMetrics::default();
    };
    let target = first.prep.angle.target();
    let per_flight: Vec<_> = ds
        .flights(role)
        .map(|fl| {
            let truth = fl.truth(target).to_vec();
            (fl.name.clone(), int8_mean_answers(qs, fl), truth)
        })
        .collect();
    FlightMetrics::of_banded(&per_flight, first.prep.angle.bands())
}

/// `sum / n` rounded half away from zero (`n` > 0).
fn mean_rounded(sum: i64, n: i64) -> i64 {
    let half = n / 2;
    if sum >= 0 {
        (sum + half) / n
    } else {
        (sum - half) / n
    }
}

/// A trained cascade's float and int8 (integer reference) answers on `flights`, degrees.
pub fn answers(t: &Trained, flights: &[&Flight]) -> (Answers, Answers) {
    flights
        .iter()
        .map(|fl| {
            let (f, i) = flight_answers(&t.model, &t.q, fl);
            ((fl.name.clone(), f), (fl.name.clone(), i))
        })
        .unzip()
}

/// Float and integer-reference metrics of a cascade on the test flights.
pub fn evaluate(
    model: &Cascade,
    q: &QCascade,
    ds: &Dataset,
) -> (FlightMetrics, FlightMetrics, Vec<TestSeries>) {
    let prep = &q.prep;
    let mut fl_f = Vec::new();
    let mut fl_i = Vec::new();
    let mut series = Vec::new();
    for fl in ds.flights(Role::Test) {
        let (pf, pi) = flight_answers(model, q, fl);
        let truth = fl.truth(prep.angle.target()).to_vec();
        fl_f.push((fl.name.clone(), pf.clone(), truth.clone()));
        fl_i.push((fl.name.clone(), pi.clone(), truth.clone()));
        series.push((fl.name.clone(), truth, pf, pi));
    }
    let bands = prep.angle.bands();
    (
        FlightMetrics::of_banded(&fl_f, bands),
        FlightMetrics::of_banded(&fl_i, bands),
        series,
    )
}

/// Result of running the compiled-in model through `Estimator::shipped()` on one split's flights.
pub struct ShippedEval {
    pub alpha: FlightMetrics,
    pub beta: FlightMetrics,
    /// The same errors by flight regime (true α band, true |β| band).
    pub regimes: crate::metrics::Regimes,
    /// Frames whose estimate was held or missing, out of envelope, or in turbulence beyond the
    /// trained envelope, per flight.
    pub flagged: Vec<FlagCounts>,
    /// How often the error lay within the estimate's 1σ and 2σ, over the computed frames.
    pub sigma: [crate::uncertainty::Coverage; 2],
    pub provenance: Option<&'static str>,
}

/// Steps a fresh `Estimator::shipped()` through every flight of `role`, frame by frame, exactly as the
/// firmware would (including held values on invalid or stuck channels), with the frames a sender of
/// `suite` delivers (`SensorFrame::restricted_to`): a model reading a channel the suite lacks is
/// held as `INVALID_INPUT`, as on target.
///
/// `uncertain_hold`: how many frames `UNCERTAIN` stays raised ([`Estimator::with_uncertain_hold`];
/// the firmware's is [`estimator_core::UNCERTAIN_HOLD_FRAMES`]).
pub fn eval_shipped(ds: &Dataset, role: Role, suite: Suite, uncertain_hold: u8) -> ShippedEval {
    let mut a = Vec::new();
    let mut b = Vec::new();
    let mut flagged = Vec::new();
    // (1σ, error) per angle: the coverage needs no terms.
    let mut pairs: [Vec<(u16, f64)>; 2] = Default::default();
    for fl in ds.flights(role) {
        let ans = answers_of(
            Estimator::shipped().with_uncertain_hold(uncertain_hold),
            fl,
            suite,
        );
        let truth = [
            fl.truth(Angle::Alpha.target()),
            fl.truth(Angle::Beta.target()),
        ];
        for (k, p) in pairs.iter_mut().enumerate() {
            p.extend(sigma_errors(&ans, k, truth[k]).map(|(_, s, e)| (s, e)));
        }
        let held = ans.flags.iter().filter(|f| !f.is_usable()).count();
        let count = |bit: u16| ans.flags.iter().filter(|f| f.has(bit)).count();
        let [ta, tb] = truth;
        let (silent, _) =
            crate::metrics::silent_frames((&ans.alpha_deg, ta), (&ans.beta_deg, tb), |i| {
                ans.flags.get(i).is_some_and(|f| f.0 == 0)
            });
        let counts = FlagCounts {
            flight: fl.name.clone(),
            not_usable: held,
            out_of_envelope: count(estimator_core::Flags::OUT_OF_ENVELOPE),
            turbulence: count(estimator_core::Flags::TURBULENCE),
            alpha_from_filter: count(estimator_core::Flags::ALPHA_FROM_FILTER),
            beta_disagrees: count(estimator_core::Flags::BETA_DISAGREES),
            filter_diverged: count(estimator_core::Flags::FILTER_DIVERGED),
            uncertain: count(estimator_core::Flags::UNCERTAIN),
            gyro_disagrees: count(estimator_core::Flags::GYRO_DISAGREES),
            any_flag: ans.flags.iter().filter(|f| f.0 != 0).count(),
            silent,
        };
        a.push((fl.name.clone(), ans.alpha_deg, ta.to_vec()));
        b.push((fl.name.clone(), ans.beta_deg, tb.to_vec()));
        flagged.push(counts);
    }
    ShippedEval {
        alpha: FlightMetrics::of(&a),
        beta: FlightMetrics::of(&b),
        regimes: crate::metrics::Regimes::of(&a, &b),
        flagged,
        sigma: pairs.map(|p| crate::uncertainty::Coverage::of(p.into_iter())),
        provenance: estimator_core::model::SHIPPED_PROVENANCE,
    }
}

/// How many frames of one flight carried which flags.
#[derive(Debug, Clone, serde::Serialize)]
pub struct FlagCounts {
    pub flight: String,
    /// Held or no estimate (`!Flags::is_usable`).
    pub not_usable: usize,
    pub out_of_envelope: usize,
    pub turbulence: usize,
    /// α from the air-data filter (`Flags::ALPHA_FROM_FILTER`).
    pub alpha_from_filter: usize,
    /// The network's and the filter's β disagree (`Flags::BETA_DISAGREES`).
    pub beta_disagrees: usize,
    /// The air-data filter restarted, kept failing its gate, or gave its prediction alone (a
    /// rejected measurement; the first frame after a start or an outage) (`Flags::FILTER_DIVERGED`).
    pub filter_diverged: usize,
    /// A 1σ above its limit (`Flags::UNCERTAIN`).
    pub uncertain: usize,
    /// A gyro the networks read disagrees with the EGI (`Flags::GYRO_DISAGREES`).
    pub gyro_disagrees: usize,
    /// Any flag at all: the frames a user cannot take at face value.
    pub any_flag: usize,
    /// Silent frames: every flag clear and |α error| > 2° or |β error| > 1° (`crate::ood`).
    pub silent: usize,
}

/// What an estimator answered on one flight, frame by frame: α, β (degrees), the flags, each
/// angle's 1σ (millidegrees, `SIGMA_UNKNOWN` when held) and the terms it was computed from.
pub struct FlightAnswers {
    pub alpha_deg: Vec<f64>,
    pub beta_deg: Vec<f64>,
    pub flags: Vec<estimator_core::Flags>,
    pub sigma_mdeg: Vec<[u16; 2]>,
    pub sigma_terms: Vec<[[u32; estimator_core::uncertainty::TERMS]; 2]>,
}

/// A fresh `Estimator::shipped()` stepped over `fl`'s frames as a sender of `suite` delivers them,
/// exactly as the firmware steps it.
pub fn shipped_answers(fl: &Flight, suite: Suite) -> FlightAnswers {
    answers_of(Estimator::shipped(), fl, suite)
}

/// `est` stepped over `fl`'s frames as a sender of `suite` delivers them.
fn answers_of(mut est: Estimator, fl: &Flight, suite: Suite) -> FlightAnswers {
    let mut a = FlightAnswers {
        alpha_deg: Vec::with_capacity(fl.len()),
        beta_deg: Vec::with_capacity(fl.len()),
        flags: Vec::with_capacity(fl.len()),
        sigma_mdeg: Vec::with_capacity(fl.len()),
        sigma_terms: Vec::with_capacity(fl.len()),
    };
    for f in &fl.frames {
        let e = est.step(&f.restricted_to(suite));
        a.alpha_deg.push(e.alpha_deg());
        a.beta_deg.push(e.beta_deg());
        a.flags.push(e.flags);
        a.sigma_mdeg.push([e.sigma_alpha_mdeg, e.sigma_beta_mdeg]);
        a.sigma_terms.push(est.sigma_terms());
    }
    a
}

/// The 1σ rows of one flight's answers ([`crate::uncertainty::Rows`], α then β): every frame
/// whose angle was computed and has a truth, with its error against `truth` (degrees); `flight`
/// is the flight's position in the caller's list of flight names (`write_rows`).
pub fn sigma_rows(
    ans: &FlightAnswers,
    truth: [&[f64]; 2],
    flight: u32,
) -> [crate::uncertainty::Rows; 2] {
    [0, 1].map(|k| {
        let mut rows = crate::uncertainty::Rows::default();
        for (i, sigma, err) in sigma_errors(ans, k, truth[k]) {
            if let Some(terms) = ans.sigma_terms.get(i) {
                let frame = u32::try_from(i).unwrap_or(u32::MAX);
                rows.push(terms[k], sigma, err, (flight, frame));
            }
        }
        rows
    })
}

/// (frame, 1σ, error in millidegrees) of angle `k` (0 α, 1 β) on every frame where it was computed
/// and has a truth.
fn sigma_errors<'a>(
    ans: &'a FlightAnswers,
    k: usize,
    truth: &'a [f64],
) -> impl Iterator<Item = (usize, u16, f64)> + 'a {
    let est = if k == 0 {
        &ans.alpha_deg
    } else {
        &ans.beta_deg
    };
    est.iter()
        .zip(truth)
        .zip(&ans.sigma_mdeg)
        .enumerate()
        .filter_map(move |(i, ((e, t), s))| {
            let sigma = s.get(k).copied()?;
            (sigma != estimator_core::uncertainty::SIGMA_UNKNOWN && t.is_finite())
                .then(|| (i, sigma, (e - t) * 1000.0))
        })
}

/// The smallest sensor suite the compiled-in model reads, if this build has one (the estimator's
/// own answer, `Estimator::suite`).
pub fn shipped_suite() -> Option<Suite> {
    Estimator::shipped().suite()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_ensembles_mean_rounds_half_away_from_zero() {
        assert_eq!(mean_rounded(3, 2), 2);
        assert_eq!(mean_rounded(-3, 2), -2);
        assert_eq!(mean_rounded(2, 2), 1);
        assert_eq!(mean_rounded(4, 3), 1);
        assert_eq!(mean_rounded(5, 3), 2);
        assert_eq!(mean_rounded(-5, 3), -2);
        assert_eq!(mean_rounded(-7, 1), -7);
    }

    #[test]
    fn the_shipped_sizes_of_the_builds_aircraft_are_a_known_configuration() {
        let name = estimator_core::aircraft::AIRCRAFT.estimator.config;
        let size = Size::parse(name).unwrap();
        assert_eq!(size.name(), name);
        assert_ne!(size, Size::Paper);
    }

    #[test]
    fn every_size_parses_from_its_name_and_the_choices_list_them_all() {
        for z in Size::ALL {
            assert_eq!(Size::parse(z.name()), Some(z));
        }
        assert_eq!(
            Size::choices(),
            "small, medium, large, medium-wide-beta, medium-wider-beta or paper"
        );
        assert_eq!(Size::parse("huge"), None);
    }

    #[test]
    fn the_wider_beta_keeps_alpha_at_the_medium_sizes() {
        assert_eq!(
            Size::MediumWiderBeta.hidden(Angle::Alpha),
            Size::Medium.hidden(Angle::Alpha)
        );
        assert_eq!(Size::MediumWiderBeta.hidden(Angle::Beta), &[128, 64, 32]);
        assert_eq!(
            Size::parse("medium-wider-beta"),
            Some(Size::MediumWiderBeta)
        );
    }
}
