//! The no_std aero evaluator is JSBSim's on aircraft other than the F-16: the force terms of every
//! fixture in `hil-sim/tests/aero/` (JSBSim package models extracted by `scripts/extract-aero
//! --jsbsim-model`, listed in its generated `fixtures.rs`), evaluated at JSBSim's own property
//! values over a flight of each (`NAME_parity.xml` beside it, flown by stock JSBSim through
//! `scripts/jsbsim-stock`), agree with JSBSim's `aero/coefficient/*` term by term and with the
//! wind-axis force sums, and so do their roll, pitch and yaw moment terms where extracted (over
//! `qbar·Sw·bw`, in pitch `qbar·Sw·cbarw`), and where an engine deck is extracted (`ENGINE`) each engine's thrust from its
//! N2, throttle position, Mach and density altitude is JSBSim's. The fixtures read what the F-16
//! does not: |β| and |δe| (slope: the
//! sign), a left aileron, α̇, a flap in degrees, 2-D tables in α × Mach and α × flap, and a stall
//! latch as a table key.
//!
//!     cargo test --release -p hil-sim --test aero_parity_other -- --nocapture   # prints the figures

// Host test code: the flight-code lints of `[workspace.lints]` do not apply (a panic is how it fails).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use std::collections::HashMap;

#[path = "aero/stock_flight.rs"]
mod stock_flight;

use estimator_core::aero::{Engine, Model, Moments, Point, Term};

/// The generated fixtures, each in a module whose parent offers the names they `use super::…`.
mod fixtures {
    pub use estimator_core::aero::{
        Engine, EngineTable, Factor, Model, Moments, Table1, Table2, Term, Var, strictly_ascending,
    };
    include!("aero/fixtures.rs");
}

/// Largest error allowed, as a fraction of the coefficient's range over the flight (as for the F-16:
/// f32 rounding of the inputs and the arithmetic).
const TOLERANCE: f64 = 1e-6;

/// The evaluator's inputs, by the JSBSim property each stands for (|β| and |δe| are derived from
/// β and δe), and what the coefficients are divided by.
const INPUTS: [&str; 19] = [
    "aero/alpha-rad",
    "aero/beta-rad",
    "velocities/mach",
    "fcs/elevator-pos-rad",
    "fcs/rudder-pos-rad",
    "fcs/left-aileron-pos-rad",
    "velocities/p-aero-rad_sec",
    "velocities/q-aero-rad_sec",
    "velocities/r-aero-rad_sec",
    "aero/bi2vel",
    "aero/ci2vel",
    "aero/h_b-mac-ft",
    "aero/alphadot-rad_sec",
    "fcs/flap-pos-deg",
    "aero/stall-hyst-norm",
    "aero/qbar-psf",
    "metrics/Sw-sqft",
    "metrics/bw-ft",
    "metrics/cbarw-ft",
];
const FORCES: [&str; 3] = [
    "forces/fwx-aero-lbs",
    "forces/fwy-aero-lbs",
    "forces/fwz-aero-lbs",
];

fn terms<'a>(m: &'a Model<'a>) -> impl Iterator<Item = &'a Term<'a>> {
    m.drag.iter().chain(m.side).chain(m.lift)
}

/// The roll, pitch and yaw moment terms, where extracted, each with the length JSBSim's moment
/// carries beside qbar·Sw (the span in roll and yaw, the mean chord in pitch).
fn moment_terms<'a>(
    m: &'a Option<Moments<'a>>,
) -> impl Iterator<Item = (&'a Term<'a>, &'static str)> {
    m.iter().flat_map(|m| {
        let with = |terms: &'a [Term<'a>], length| terms.iter().map(move |t| (t, length));
        with(m.roll, "metrics/bw-ft")
            .chain(with(m.pitch, "metrics/cbarw-ft"))
            .chain(with(m.yaw, "metrics/bw-ft"))
    })
}

/// Engine `i`'s deck inputs and JSBSim's thrust, by property.
fn engine_props(i: u8) -> [String; 4] {
    [
        format!("propulsion/engine[{i}]/n2"),
        format!("fcs/throttle-pos-norm[{i}]"),
        format!("propulsion/engine[{i}]/thrust-lbs"),
        "atmosphere/density-altitude".to_string(),
    ]
}

/// Every step of `aircraft`'s parity flight: each property by name.
fn flight(
    aircraft: &str,
    model: &Model<'_>,
    moments: &Option<Moments<'_>>,
    engine: &Option<Engine<'_>>,
) -> Vec<HashMap<String, f64>> {
    let names: Vec<String> = INPUTS
        .iter()
        .chain(FORCES.iter())
        .map(|s| s.to_string())
        .chain(terms(model).map(|t| t.name.to_string()))
        .chain(moment_terms(moments).map(|(t, _)| t.name.to_string()))
        .chain(
            engine
                .iter()
                .flat_map(|e| (0..e.count).flat_map(engine_props)),
        )
        .collect();
    let here = stock_flight::root().join("hil-sim/tests/aero");
    stock_flight::fly(
        &here.join(format!("{aircraft}_parity.xml")),
        &here.join(format!("{aircraft}_parity_init.xml")),
        &names,
    )
}

/// JSBSim's own values as an operating point.
fn point(s: &HashMap<String, f64>) -> Point {
    let g = |p: &str| s[p] as f32;
    Point {
        alpha_rad: g("aero/alpha-rad"),
        beta_rad: g("aero/beta-rad"),
        mach: g("velocities/mach"),
        elevator_rad: g("fcs/elevator-pos-rad"),
        rudder_rad: g("fcs/rudder-pos-rad"),
        left_aileron_rad: g("fcs/left-aileron-pos-rad"),
        p_aero_rps: g("velocities/p-aero-rad_sec"),
        q_aero_rps: g("velocities/q-aero-rad_sec"),
        r_aero_rps: g("velocities/r-aero-rad_sec"),
        bi2vel_s: g("aero/bi2vel"),
        ci2vel_s: g("aero/ci2vel"),
        h_over_b: g("aero/h_b-mac-ft"),
        alpha_dot_rps: g("aero/alphadot-rad_sec"),
        flap_deg: g("fcs/flap-pos-deg"),
        stall_hyst_norm: g("aero/stall-hyst-norm"),
        mag_beta_rad: g("aero/beta-rad").abs(),
        mag_elevator_rad: g("fcs/elevator-pos-rad").abs(),
        ..Point::default()
    }
}

/// Largest error of each term and wind-axis sum over the flight, against its own range; and of
/// each roll, pitch and yaw moment term, where extracted.
fn parity(
    aircraft: &str,
    model: &Model<'_>,
    moments: &Option<Moments<'_>>,
    engine: &Option<Engine<'_>>,
) {
    let steps = flight(aircraft, model, moments, engine);
    println!("{aircraft}: {} JSBSim steps", steps.len());
    assert!(steps.len() > 4_000, "{aircraft}: {} steps", steps.len());
    let names: Vec<&str> = terms(model)
        .map(|t| t.name)
        .chain(["CD", "CY", "CL"])
        .chain(moment_terms(moments).map(|(t, _)| t.name))
        .collect();
    // (max |err|, min, max) of each quantity; a NaN anywhere fails.
    let mut worst = vec![(0.0f64, f64::MAX, f64::MIN); names.len()];
    let mut nan = Vec::new();
    for s in &steps {
        let qs = s["aero/qbar-psf"] * s["metrics/Sw-sqft"];
        let p = point(s);
        let ours = terms(model)
            .map(|t| t.eval(&p).expect("finite").value)
            .chain({
                let c = model.coefficients_at(&p);
                assert!(c.valid, "{aircraft}: invalid at α {}", p.alpha_rad);
                [c.wind.drag, c.wind.side, c.wind.lift]
            })
            .chain(moment_terms(moments).map(|(t, _)| t.eval(&p).expect("finite").value));
        // JSBSim: each term's property is its force (lbs), as are the wind-axis sums (drag, side,
        // lift with JSBSim's signs, as `Wind` has them).
        let theirs = terms(model)
            .map(|t| s[t.name] / qs)
            .chain(FORCES.map(|f| s[f] / qs))
            // A moment term's property is its moment (lbs·ft): over qbar·Sw·bw (pitch: ·cbarw).
            .chain(moment_terms(moments).map(|(t, length)| s[t.name] / (qs * s[length])));
        for (((w, o), j), n) in worst.iter_mut().zip(ours).zip(theirs).zip(&names) {
            let e = (f64::from(o) - j).abs();
            if e.is_nan() {
                nan.push(*n);
            }
            *w = (w.0.max(e), w.1.min(j), w.2.max(j));
        }
    }
    let mut failed = Vec::new();
    for (n, (err, lo, hi)) in names.iter().zip(&worst) {
        // A term that stays constant over the flight (a zero coefficient) is held to an absolute
        // 1e-9.
        let scale = (hi - lo).max(1e-3);
        println!(
            "{aircraft} {n:32} max |err| {err:9.3e}  range {:9.3e}  err/range {:9.3e}",
            hi - lo,
            err / scale
        );
        if *err > TOLERANCE * scale {
            failed.push(*n);
        }
    }
    // Each engine's thrust, against the military thrust (a thrust held the whole flight has no
    // range of its own).
    for i in 0..engine.map_or(0, |e| e.count) {
        let Some(e) = engine else { break };
        let [n2, throttle, thrust, alt] = engine_props(i);
        let err = steps
            .iter()
            .map(|s| {
                let g = |p: &str| s[p] as f32;
                let ours = e.thrust_lbf(g(&n2), g(&throttle), g("velocities/mach"), g(&alt));
                ours.map_or(f64::NAN, |t| (f64::from(t) - s[&thrust]).abs())
            })
            .fold(0.0f64, |w, x| {
                if w.is_nan() || x.is_nan() {
                    f64::NAN
                } else {
                    w.max(x)
                }
            });
        let scale = f64::from(e.mil_thrust_lbf);
        println!(
            "{aircraft} engine {i} thrust            max |err| {err:9.3e} lbf  err/military {:9.3e}",
            err / scale
        );
        if err.is_nan() || err > TOLERANCE * scale {
            failed.push("thrust");
        }
    }
    assert!(nan.is_empty(), "{aircraft}: NaN in {nan:?}");
    assert!(
        failed.is_empty(),
        "{aircraft}: {failed:?} differ from JSBSim"
    );
}

#[test]
fn every_fixture_force_model_is_jsbsims() {
    assert!(
        fixtures::ALL.len() >= 2,
        "the fixtures: {}",
        fixtures::ALL.len()
    );
    for (name, model, moments, engine) in fixtures::ALL {
        parity(name, model, moments, engine);
    }
}
