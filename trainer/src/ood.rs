//! Out-of-distribution evaluation: every estimator that runs on the target, scored on the
//! `ood` preset's flights (`hil-sim generate --preset ood`) against its own score on each flight's
//! in-distribution twin (same maneuver seed, nominal conditions), with the failures a user cannot see
//! called out: frames whose flags are all clear while the error exceeds 2° in α or 1° in β.
//!
//! Estimators, each frame by frame in flight order on the frames the link delivers (faults applied):
//! * the shipped estimator: `Estimator::shipped()` on the frames its suite sends, exactly as the
//!   firmware steps it (int8 networks, the filter inside its feature state, every flag);
//! * the model-based filter alone (`estimator_core::filter`, `CONFIG`), its own flags.
use estimator_core::filter::CONFIG;
use serde::Serialize;

use crate::data::{Dataset, Role, Target};
use crate::filter_eval::run_flight;
use crate::metrics::Metrics;

pub use crate::metrics::{SILENT_ALPHA_DEG, SILENT_BETA_DEG};

/// One estimator's answers on one flight: α, β (degrees) and whether every flag was clear.
pub struct Answers {
    pub alpha_deg: Vec<f64>,
    pub beta_deg: Vec<f64>,
    pub clear: Vec<bool>,
    /// α came from the air-data filter (`Flags::ALPHA_FROM_FILTER`; never for the filter alone).
    pub alpha_from_filter: Vec<bool>,
}

/// An estimator under test.
pub struct Estimator {
    pub name: &'static str,
    pub run: fn(&crate::data::Flight) -> Answers,
}

/// The estimators this build can run: the shipped one (if the build has a model) and the filter.
pub fn estimators() -> Vec<Estimator> {
    let mut v = Vec::new();
    if crate::pipeline::shipped_suite().is_some() {
        v.push(Estimator {
            name: "shipped (int8, as on target)",
            run: run_shipped,
        });
    }
    v.push(Estimator {
        name: "model-based filter alone",
        run: run_filter,
    });
    v
}

fn run_shipped(fl: &crate::data::Flight) -> Answers {
    let suite = crate::pipeline::shipped_suite().unwrap_or(estimator_core::Suite::Table1);
    let a = crate::pipeline::shipped_answers(fl, suite);
    Answers {
        clear: a.flags.iter().map(|f| f.0 == 0).collect(),
        alpha_from_filter: a
            .flags
            .iter()
            .map(|f| f.has(estimator_core::Flags::ALPHA_FROM_FILTER))
            .collect(),
        alpha_deg: a.alpha_deg,
        beta_deg: a.beta_deg,
    }
}

fn run_filter(fl: &crate::data::Flight) -> Answers {
    let out = run_flight(CONFIG, &fl.frames);
    let (alpha_deg, beta_deg) = crate::filter_eval::degrees(&out);
    Answers {
        alpha_deg,
        beta_deg,
        clear: out
            .iter()
            .map(|o| estimator_core::filter::flags::clear(o.flags))
            .collect(),
        alpha_from_filter: vec![false; out.len()],
    }
}

/// One estimator on one flight.
#[derive(Debug, Clone, Serialize)]
pub struct FlightScore {
    pub flight: String,
    /// `nominal` for a twin, else the `OodCase` name.
    pub case: String,
    pub profile: String,
    pub alpha: Metrics,
    pub beta: Metrics,
    /// MAE on this flight over MAE on its twin (1 for the twin itself; NaN without a twin).
    pub alpha_ratio: f64,
    pub beta_ratio: f64,
    /// Share of frames with at least one flag raised.
    pub flagged_share: f64,
    /// Share of frames whose α came from the air-data filter.
    pub alpha_from_filter_share: f64,
    /// Frames with every flag clear and |α error| > 2° or |β error| > 1°, and the longest run of
    /// them in seconds.
    pub silent_frames: usize,
    pub silent_longest_s: f64,
}

/// One estimator on every flight.
#[derive(Debug, Clone, Serialize)]
pub struct EstimatorScores {
    pub estimator: String,
    pub flights: Vec<FlightScore>,
}

/// The whole evaluation.
#[derive(Debug, Clone, Serialize)]
pub struct OodReport {
    pub dataset: String,
    pub manifest_sha256: String,
    pub model: Option<String>,
    /// Each case's name and what it flies (the manifest's `ood_cases`).
    pub cases: Vec<(String, String)>,
    pub estimators: Vec<EstimatorScores>,
}

/// `ood_<case>_<profile>` → (case, profile); other names are their own case.
pub fn case_and_profile(name: &str) -> (String, String) {
    let rest = name.strip_prefix("ood_").unwrap_or(name);
    match rest.split_once('_') {
        Some((case, profile)) => (case.to_string(), profile.to_string()),
        None => (rest.to_string(), String::new()),
    }
}

/// Scores `est` on every test flight of `ds`.
pub fn score(ds: &Dataset, est: &Estimator) -> EstimatorScores {
    let mut flights = Vec::new();
    for fl in ds.flights(Role::Test) {
        let ans = (est.run)(fl);
        let ta = fl.truth(Target::AlphaDeg);
        let tb = fl.truth(Target::BetaDeg);
        let (case, profile) = case_and_profile(&fl.name);
        let (silent, longest) =
            crate::metrics::silent_frames((&ans.alpha_deg, ta), (&ans.beta_deg, tb), |i| {
                ans.clear.get(i).copied().unwrap_or(false)
            });
        let n = fl.len().max(1) as f64;
        flights.push(FlightScore {
            flight: fl.name.clone(),
            case,
            profile,
            alpha: Metrics::of(&ans.alpha_deg, ta),
            beta: Metrics::of(&ans.beta_deg, tb),
            alpha_ratio: f64::NAN,
            beta_ratio: f64::NAN,
            flagged_share: ans.clear.iter().filter(|c| !**c).count() as f64 / n,
            alpha_from_filter_share: ans.alpha_from_filter.iter().filter(|c| **c).count() as f64
                / n,
            silent_frames: silent,
            silent_longest_s: longest as f64 / f64::from(hil_sim::flight::SAMPLE_HZ),
        });
    }
    let twins: Vec<(String, f64, f64)> = flights
        .iter()
        .filter(|f| f.case == "nominal")
        .map(|f| (f.profile.clone(), f.alpha.mae, f.beta.mae))
        .collect();
    for f in &mut flights {
        if let Some((_, a, b)) = twins.iter().find(|t| t.0 == f.profile) {
            f.alpha_ratio = f.alpha.mae / a;
            f.beta_ratio = f.beta.mae / b;
        }
    }
    EstimatorScores {
        estimator: est.name.to_string(),
        flights,
    }
}

/// Every estimator of this build on `ds`.
pub fn run(ds: &Dataset) -> OodReport {
    OodReport {
        dataset: ds.dir.display().to_string(),
        manifest_sha256: ds.manifest_sha256.clone(),
        model: estimator_core::model::SHIPPED_PROVENANCE.map(str::to_string),
        cases: ds.ood_cases.clone(),
        estimators: estimators().iter().map(|e| score(ds, e)).collect(),
    }
}

/// The flights on which an estimator's flags stayed clear through errors beyond the limits.
pub fn silent_failures(r: &OodReport) -> Vec<(&str, &FlightScore)> {
    r.estimators
        .iter()
        .flat_map(|e| {
            e.flights
                .iter()
                .filter(|f| f.silent_frames > 0)
                .map(move |f| (e.estimator.as_str(), f))
        })
        .collect()
}

/// The degradation table and the call-outs, Markdown.
pub fn markdown(r: &OodReport) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Dataset `{}` (manifest sha256 `{}`). MAE in degrees over every frame, flagged or not; \
         ratio = MAE on the flight / MAE on its in-distribution twin (`nominal`, same maneuver seed). \
         Flagged = share of frames with any flag raised. α from filter = share of frames whose α the \
         air-data filter gave because the α network was out of its envelope (`ALPHA_FROM_FILTER`). Silent = frames with every flag clear and \
         |α error| > {SILENT_ALPHA_DEG}° or |β error| > {SILENT_BETA_DEG}° (longest run).\n",
        r.dataset, r.manifest_sha256
    );
    s.push_str(
        "Cases (`OodCase` of hil-sim's maneuver generator, sized by the aircraft description's `[ood]`; \
         each flight has its twin's seed, so the same maneuver draws; 6 min each, gentle and high-α \
         profiles), as the dataset's manifest describes them:\n",
    );
    if r.cases.is_empty() {
        s.push_str("- (the manifest describes none: a dataset written before manifests described their cases)\n");
    }
    for (name, text) in &r.cases {
        let _ = writeln!(s, "- `{name}`: {text}.");
    }
    s.push('\n');
    for e in &r.estimators {
        let _ = writeln!(s, "### {}\n", e.estimator);
        s.push_str("| flight | case | α MAE | α ×twin | α max | β MAE | β ×twin | β max | flagged | α from filter | silent frames (longest) |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
        for f in &e.flights {
            let _ = writeln!(
                s,
                "| {} | {} | {:.3} | {:.2} | {:.2} | {:.3} | {:.2} | {:.2} | {:.1} % | {:.1} % | {} ({:.1} s) |",
                f.flight,
                f.case,
                f.alpha.mae,
                f.alpha_ratio,
                f.alpha.max,
                f.beta.mae,
                f.beta_ratio,
                f.beta.max,
                100.0 * f.flagged_share,
                100.0 * f.alpha_from_filter_share,
                f.silent_frames,
                f.silent_longest_s
            );
        }
        s.push('\n');
    }
    let silent = silent_failures(r);
    s.push_str("### Failures a user cannot see\n\n");
    if silent.is_empty() {
        s.push_str("None: on every flight, every frame with an error beyond the limits had a flag raised.\n");
    } else {
        for (est, f) in silent {
            let _ = writeln!(
                s,
                "- **{}** on `{}`: {} frames ({:.1} % of the flight, longest {:.1} s) with clear flags and an error beyond the limits (α max {:.2}°, β max {:.2}°).",
                est,
                f.flight,
                f.silent_frames,
                100.0 * f.silent_frames as f64 / f.alpha.n.max(1) as f64,
                f.silent_longest_s,
                f.alpha.max,
                f.beta.max
            );
        }
    }
    s
}

/// Two panels (α, β): MAE per flight, one bar per estimator.
pub fn plot(r: &OodReport, path: &std::path::Path) -> crate::Result<()> {
    let names: Vec<String> = r.estimators.iter().map(|e| e.estimator.clone()).collect();
    let flights: Vec<String> = r
        .estimators
        .first()
        .map(|e| e.flights.iter().map(|f| f.flight.clone()).collect())
        .unwrap_or_default();
    let values = |alpha: bool| -> Vec<(String, Vec<f64>)> {
        flights
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let v = r
                    .estimators
                    .iter()
                    .map(|e| {
                        e.flights
                            .get(i)
                            .map_or(f64::NAN, |f| if alpha { f.alpha.mae } else { f.beta.mae })
                    })
                    .collect();
                (name.trim_start_matches("ood_").to_string(), v)
            })
            .collect()
    };
    crate::plots::grouped_bar_panels(
        path,
        &[
            (
                "α MAE per OOD flight".to_string(),
                "α MAE, deg",
                values(true),
            ),
            (
                "β MAE per OOD flight".to_string(),
                "β MAE, deg",
                values(false),
            ),
        ],
        &names,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn case_and_profile_split_the_flight_name() {
        assert_eq!(
            case_and_profile("ood_mass-low_high-alpha"),
            ("mass-low".to_string(), "high-alpha".to_string())
        );
        assert_eq!(
            case_and_profile("ood_nominal_gentle"),
            ("nominal".to_string(), "gentle".to_string())
        );
        assert_eq!(
            case_and_profile("test_gentle_00"),
            ("test".to_string(), "gentle_00".to_string())
        );
    }
}
