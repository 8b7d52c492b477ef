//! The no_std aero evaluator is JSBSim's on aircraft other than the F-16: the force terms of every
//! fixture in `hil-sim/tests/aero/` (JSBSim package models extracted by `scripts/extract-aero
//! --jsbsim-model`, listed in its generated `fixtures.rs`), evaluated at JSBSim's own property
//! values over a flight of each (`NAME_parity.xml` beside it, flown by stock JSBSim through
//! `scripts/jsbsim-stock`), agree with JSBSim's `aero/coefficient/*` term by term and with the
//! wind-axis force sums, and so do their roll, pitch and yaw moment terms where extracted (over
//! `qbar·Sw·bw`, in pitch `qbar·Sw·cbarw`), and where the engines are extracted (`ENGINE`) each
//! engine's thrust is JSBSim's: a turbine's from its N2, throttle position, Mach and density
//! altitude, a propeller's from its speed, the airspeed, density and speed of sound. The fixtures
//! read what the F-16 does not: |β| and |δe| (slope: the sign), a left aileron, α̇, a flap in
//! degrees, 2-D tables in α × Mach and α × flap, a stall latch as a table key, and a propeller.
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

use estimator_core::aero::{Engine, Model, Moments, Point, Propeller, Term, Turbine};

/// The generated fixtures, each in a module whose parent offers the names they `use super::…`.
mod fixtures {
    pub use estimator_core::aero::{
        Engine, EngineTable, Factor, Model, Moments, Propeller, PropellerTable, Table1, Table2,
        Term, Turbine, Var, strictly_ascending,
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

/// Engine `i`'s deck inputs and JSBSim's thrust, by property: a turbine's N2, throttle position,
/// thrust and density altitude; a propeller's speed, thrust, advance ratio, helical tip Mach,
/// thrust coefficient, and the airspeed along body x, density and speed of sound.
fn engine_props(engine: &Engine<'_>, i: u8) -> Vec<String> {
    let e = |p: &str| format!("propulsion/engine[{i}]/{p}");
    match engine {
        Engine::Turbine(_) => vec![
            e("n2"),
            format!("fcs/throttle-pos-norm[{i}]"),
            e("thrust-lbs"),
            "atmosphere/density-altitude".to_string(),
        ],
        Engine::Propeller(_) => vec![
            e("propeller-rpm"),
            e("thrust-lbs"),
            e("advance-ratio"),
            e("helical-tip-Mach"),
            e("thrust-coefficient"),
            "velocities/u-aero-fps".to_string(),
            "velocities/vt-fps".to_string(),
            e("prop-induced-velocity_fps"),
            "atmosphere/rho-slugs_ft3".to_string(),
            "atmosphere/a-fps".to_string(),
        ],
    }
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
                .flat_map(|e| (0..e.count()).flat_map(|i| engine_props(e, i))),
        )
        .collect();
    let here = stock_flight::root().join("hil-sim/tests/aero");
    stock_flight::fly(
        &here.join(format!("{aircraft}_parity.xml")),
        &here.join(format!("{aircraft}_parity_init.xml")),
        &names,
    )
}

/// JSBSim's own values as an operating point, the slipstream's dynamic pressure over q̄ from
/// JSBSim's propeller-induced velocity where a moment term reads it.
fn point(s: &HashMap<String, f64>, moments: &Option<Moments<'_>>) -> Point {
    let g = |p: &str| s[p] as f32;
    let slipstream = moments
        .filter(|m| m.slipstream_induced_factor > 0.0)
        .map_or(Some(1.0), |m| {
            m.slipstream_qbar_ratio(
                g("velocities/vt-fps"),
                g("velocities/u-aero-fps"),
                g("propulsion/engine[0]/prop-induced-velocity_fps"),
            )
        })
        .unwrap_or(f32::NAN);
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
        slipstream_qbar_ratio: slipstream,
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
        let p = point(s, moments);
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
        // 1e-9, plus one f32 rounding of its value (the c172p's Cmo, 0.1, is 1.5e-9 off in f32).
        let scale = (hi - lo).max(1e-3);
        let rounding = f64::from(f32::EPSILON) * lo.abs().max(hi.abs());
        println!(
            "{aircraft} {n:32} max |err| {err:9.3e}  range {:9.3e}  err/range {:9.3e}",
            hi - lo,
            err / scale
        );
        if *err > TOLERANCE * scale + rounding {
            failed.push(*n);
        }
    }
    // Each engine's thrust.
    for i in 0..engine.map_or(0, |e| e.count()) {
        let ok = match engine {
            Some(Engine::Turbine(t)) => turbine_parity(aircraft, t, i, &steps),
            Some(Engine::Propeller(p)) => propeller_parity(aircraft, p, i, &steps),
            None => true,
        };
        if !ok {
            failed.push("thrust");
        }
    }
    assert!(nan.is_empty(), "{aircraft}: NaN in {nan:?}");
    assert!(
        failed.is_empty(),
        "{aircraft}: {failed:?} differ from JSBSim"
    );
}

/// The largest of `errs`, NaN if any is.
fn worst(errs: impl Iterator<Item = f64>) -> f64 {
    errs.fold(0.0f64, |w, x| {
        if w.is_nan() || x.is_nan() {
            f64::NAN
        } else {
            w.max(x)
        }
    })
}

/// A turbine's thrust from its N2, throttle position, Mach and density altitude, against the
/// military thrust (a thrust held the whole flight has no range of its own).
fn turbine_parity(aircraft: &str, e: &Turbine<'_>, i: u8, steps: &[HashMap<String, f64>]) -> bool {
    let props = engine_props(&Engine::Turbine(*e), i);
    let [n2, throttle, thrust, alt] = [0, 1, 2, 3].map(|k| props[k].as_str());
    let err = worst(steps.iter().map(|s| {
        let g = |p: &str| s[p] as f32;
        let ours = e.thrust_lbf(g(n2), g(throttle), g("velocities/mach"), g(alt));
        ours.map_or(f64::NAN, |t| (f64::from(t) - s[thrust]).abs())
    }));
    let scale = f64::from(e.mil_thrust_lbf);
    println!(
        "{aircraft} engine {i} thrust            max |err| {err:9.3e} lbf  err/military {:9.3e}",
        err / scale
    );
    !err.is_nan() && err <= TOLERANCE * scale
}

/// A propeller's thrust, against the largest over the flight. JSBSim's thrust at a step is
/// computed from the propeller speed and airspeed of the step before (it then turns the propeller
/// faster or slower) and the density of this one: with JSBSim's own advance ratio and helical tip
/// Mach of the step (the airspeed and speed of sound they imply) the evaluator's C_T(J), its
/// `CT_MACH` factor and C_T·n²·D⁴·ρ are JSBSim's to f32 rounding. What flight-test calibration
/// has is the speed, the airspeed along body x at the CG and the standard day's density and speed
/// of sound at the step itself: that thrust is held to 1 % of the largest (0.63 % on the c172p's
/// flight: a throttle step moves the propeller speed within one 1/120 s step, and the rotation's
/// share of the airspeed at the propeller is left out).
fn propeller_parity(
    aircraft: &str,
    p: &Propeller<'_>,
    i: u8,
    steps: &[HashMap<String, f64>],
) -> bool {
    let props = engine_props(&Engine::Propeller(*p), i);
    let [rpm, thrust, j, tip, ct, u, _, induced, rho, a] =
        [0, 1, 2, 3, 4, 5, 6, 7, 8, 9].map(|k| props[k].as_str());
    let d = f64::from(p.diameter_ft);
    let largest = worst(steps.iter().map(|s| s[thrust].abs()));
    let (mut exact, mut ct_err, mut induced_err) = (Vec::new(), Vec::new(), Vec::new());
    for (before, s) in steps.iter().zip(steps.iter().skip(1)) {
        let n = before[rpm] / 60.0;
        // The airspeed along the shaft and the speed of sound JSBSim's J and tip Mach imply.
        let axial = s[j] * n * d;
        let sound = ((std::f64::consts::PI * n * d).powi(2) + axial * axial).sqrt() / s[tip];
        let ours = p.thrust_lbf(
            before[rpm] as f32,
            axial as f32,
            s[rho] as f32,
            sound as f32,
        );
        exact.push(ours.map_or(f64::NAN, |t| (f64::from(t) - s[thrust]).abs()));
        let c = p.thrust_coefficient.at(s[j] as f32).map(|c| {
            f64::from(
                c * p.ct_factor
                    * p.tip_mach_factor
                        .map_or(Some(1.0), |m| m.at(s[tip] as f32))
                        .unwrap_or(f32::NAN),
            )
        });
        ct_err.push(c.map_or(f64::NAN, |c| (c - s[ct]).abs()));
        // The induced velocity from JSBSim's thrust and the airspeed along the shaft.
        let v = p.induced_fps(s[thrust] as f32, axial as f32, s[rho] as f32);
        induced_err.push(v.map_or(f64::NAN, |v| (f64::from(v) - s[induced]).abs()));
    }
    let at_step = worst(steps.iter().map(|s| {
        let ours = p.thrust_lbf(s[rpm] as f32, s[u] as f32, s[rho] as f32, s[a] as f32);
        ours.map_or(f64::NAN, |t| (f64::from(t) - s[thrust]).abs())
    }));
    let (exact, ct_err) = (worst(exact.into_iter()), worst(ct_err.into_iter()));
    let induced_err = worst(induced_err.into_iter());
    let induced_max = worst(steps.iter().map(|s| s[induced].abs()));
    let running = steps.iter().filter(|s| s[rpm] > 500.0).count();
    println!(
        "{aircraft} engine {i} propeller: {running} steps above 500 rpm, largest thrust {largest:.1} lbf; \
         C_T max |err| {ct_err:9.3e}; thrust max |err| {exact:9.3e} lbf ({:9.3e} of the largest), \
         at the step's own speed and airspeed {at_step:.2} lbf ({:.2e}); induced velocity max \
         |err| {induced_err:9.3e} ft/s of {induced_max:.1}",
        exact / largest,
        at_step / largest
    );
    running > steps.len() / 2
        && ct_err <= 1e-6
        && exact <= TOLERANCE * largest
        && at_step <= 0.01 * largest
        && induced_err <= TOLERANCE * induced_max
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
