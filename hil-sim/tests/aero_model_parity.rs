//! estimator-core's aerodynamic model is JSBSim's: over every step of the project's 20-minute test
//! flight, flown by stock JSBSim (`scripts/jsbsim-stock`), each force term, the wind-axis sums and
//! the body-axis forces of `estimator_core::aero::MODEL` agree with JSBSim's own
//! (`aero/coefficient/*`, `forces/fw{x,y,z}-aero-lbs`, `forces/fb{x,y,z}-aero-lbs`, over
//! `qbar·Sw`) to a small fraction of each coefficient's range over the flight; so do the roll,
//! pitch and yaw moment terms of `aero::MOMENTS` (over `qbar·Sw·bw`, in pitch `qbar·Sw·cbarw`),
//! which flight-test calibration reads.
//!
//! Two input paths: JSBSim's own property values in JSBSim's units (checks the tables, products and
//! the wind-to-body turn alone), and the estimator's units (degrees as the sensor channels carry
//! them, airspeed in m/s), which checks the conversions as well. A model with one table cell
//! changed must fail the same comparison.
//!
//!     cargo test --release -p hil-sim --test aero_model_parity -- --nocapture   # prints the figures

use std::sync::OnceLock;

#[path = "aero/stock_flight.rs"]
mod stock_flight;

use estimator_core::aero::{
    self, AirState, Coefficients, Factor, MODEL, Model, Point, Surfaces, Table2, Term, Unsteady,
    tables,
};

/// Largest error allowed, as a fraction of the coefficient's range over the flight. f32 rounding of
/// the inputs and the arithmetic measures ≤ 1.5e-7 of it (about one f32 ulp of the largest values);
/// one unit of the XML's last digit (1e-4) in a table cell the flight uses is ~6e-5 of it.
const TOLERANCE: f64 = 1e-6;

const INPUTS: [&str; 36] = [
    "aero/alpha-rad",
    "aero/beta-rad",
    "velocities/mach",
    "velocities/vt-fps",
    "aero/qbar-psf",
    "metrics/Sw-sqft",
    "metrics/bw-ft",
    "metrics/cbarw-ft",
    "velocities/p-aero-rad_sec",
    "velocities/q-aero-rad_sec",
    "velocities/r-aero-rad_sec",
    "aero/bi2vel",
    "aero/ci2vel",
    "aero/h_b-mac-ft",
    "fcs/elevator-pos-rad",
    "fcs/elevator-pos-deg",
    "fcs/aileron-pos-rad",
    "fcs/rudder-pos-rad",
    "fcs/rudder-pos-deg",
    "fcs/lef-pos-rad",
    "fcs/speedbrake-pos-rad",
    "fcs/speedbrake-pos-deg",
    "fcs/flaperon-mix-rad",
    "fcs/left-flaperon-norm",
    "fcs/right-flaperon-norm",
    "fcs/tef-control",
    "gear/gear-pos-norm",
    "simulation/sim-time-sec",
    "aero/function/kCLge",
    "aero/alphadot-rad_sec",
    "aero/stall-hyst-norm",
    // The engine deck's inputs and JSBSim's thrust.
    "propulsion/engine/n2",
    "fcs/throttle-pos-norm",
    "atmosphere/density-altitude",
    "position/h-sl-ft",
    "propulsion/engine/thrust-lbs",
];
const FORCES: [&str; 6] = [
    "forces/fwx-aero-lbs",
    "forces/fwy-aero-lbs",
    "forces/fwz-aero-lbs",
    "forces/fbx-aero-lbs",
    "forces/fby-aero-lbs",
    "forces/fbz-aero-lbs",
];

use stock_flight::root;

fn terms() -> impl Iterator<Item = &'static Term<'static>> {
    MODEL.drag.iter().chain(MODEL.side).chain(MODEL.lift)
}

/// A moment axis: its name, its terms and JSBSim's coefficient of a term's property.
type MomentAxis = (
    &'static str,
    &'static [Term<'static>],
    fn(&Step, &str) -> f64,
);

/// The roll, pitch and yaw moment axes (flight-test calibration reads them), in the order of
/// [`aero::Moments::coefficients_at`].
fn moment_axes() -> [MomentAxis; 3] {
    let m = aero::MOMENTS.expect("JSBSim's F-16 has moments the evaluator reads");
    [
        ("ROLL", m.roll, Step::moment_coef),
        ("PITCH", m.pitch, Step::pitch_coef),
        ("YAW", m.yaw, Step::moment_coef),
    ]
}

/// One JSBSim step: every property above, by name.
struct Step {
    v: std::collections::HashMap<String, f64>,
}

impl Step {
    fn get(&self, p: &str) -> f64 {
        self.v[p]
    }

    /// A force property over qbar·Sw.
    fn coef(&self, p: &str) -> f64 {
        self.get(p) / (self.get("aero/qbar-psf") * self.get("metrics/Sw-sqft"))
    }

    /// A roll or yaw moment property over qbar·Sw·bw.
    fn moment_coef(&self, p: &str) -> f64 {
        self.coef(p) / self.get("metrics/bw-ft")
    }

    /// A pitch moment property over qbar·Sw·cbarw.
    fn pitch_coef(&self, p: &str) -> f64 {
        self.coef(p) / self.get("metrics/cbarw-ft")
    }

    /// JSBSim's own values, in JSBSim's units.
    fn point(&self) -> Point {
        let g = |p: &str| self.get(p) as f32;
        Point {
            alpha_rad: g("aero/alpha-rad"),
            beta_rad: g("aero/beta-rad"),
            mach: g("velocities/mach"),
            elevator_rad: g("fcs/elevator-pos-rad"),
            aileron_rad: g("fcs/aileron-pos-rad"),
            rudder_rad: g("fcs/rudder-pos-rad"),
            lef_rad: g("fcs/lef-pos-rad"),
            speedbrake_rad: g("fcs/speedbrake-pos-rad"),
            flaperon_mix_rad: g("fcs/flaperon-mix-rad"),
            gear_norm: g("gear/gear-pos-norm"),
            p_aero_rps: g("velocities/p-aero-rad_sec"),
            q_aero_rps: g("velocities/q-aero-rad_sec"),
            r_aero_rps: g("velocities/r-aero-rad_sec"),
            bi2vel_s: g("aero/bi2vel"),
            ci2vel_s: g("aero/ci2vel"),
            h_over_b: g("aero/h_b-mac-ft"),
            mag_beta_rad: g("aero/beta-rad").abs(),
            mag_elevator_rad: g("fcs/elevator-pos-rad").abs(),
            // The F-16's model reads none of these.
            left_aileron_rad: 0.0,
            alpha_dot_rps: 0.0,
            flap_deg: 0.0,
            stall_hyst_norm: 0.0,
            slipstream_qbar_ratio: 1.0,
        }
    }

    /// The estimator's quantities: surfaces in the channels' degrees, airspeed in m/s.
    fn estimator_inputs(&self) -> (AirState, Surfaces) {
        let g = |p: &str| self.get(p);
        let air = AirState {
            alpha_rad: g("aero/alpha-rad") as f32,
            beta_rad: g("aero/beta-rad") as f32,
            mach: g("velocities/mach") as f32,
            tas_mps: (g("velocities/vt-fps") * hil_sim::plant::FT_TO_M) as f32,
            p_rps: g("velocities/p-aero-rad_sec") as f32,
            q_rps: g("velocities/q-aero-rad_sec") as f32,
            r_rps: g("velocities/r-aero-rad_sec") as f32,
            h_over_b: g("aero/h_b-mac-ft") as f32,
            unsteady: Unsteady {
                alpha_dot_rps: g("aero/alphadot-rad_sec") as f32,
                stall_latched: g("aero/stall-hyst-norm") > 0.5,
            },
        };
        let flaperon = |p: &str| (g(p) * f64::from(aero::FLAPERON_DEG_PER_NORM)) as f32;
        let s = Surfaces {
            elevator_deg: g("fcs/elevator-pos-deg") as f32,
            aileron_deg: g("fcs/aileron-pos-rad").to_degrees() as f32,
            rudder_deg: g("fcs/rudder-pos-deg") as f32,
            // The aero's scheduled LEF, not the lagged actuator the Lef channel carries.
            lef_deg: g("fcs/lef-pos-rad").to_degrees() as f32,
            flaperon_left_deg: flaperon("fcs/left-flaperon-norm"),
            flaperon_right_deg: flaperon("fcs/right-flaperon-norm"),
            speedbrake_deg: g("fcs/speedbrake-pos-deg") as f32,
            // What the trailing-edge flap channel's sensor reads (the F-16's model reads its flaps
            // through the flaperons, not as a degree property).
            flap_deg: estimator_core::aircraft::AIRCRAFT
                .surface(estimator_core::Channel::Tef)
                .map_or(0.0, |t| (g(t.property) * t.deg_per_unit) as f32),
            gear_norm: g("gear/gear-pos-norm") as f32,
        };
        (air, s)
    }
}

/// Every step of the test flight, flown once per test binary by stock JSBSim.
fn flight() -> &'static [Step] {
    static FLIGHT: OnceLock<Vec<Step>> = OnceLock::new();
    FLIGHT.get_or_init(|| {
        let names: Vec<&'static str> = INPUTS
            .iter()
            .copied()
            .chain(terms().map(|t| t.name))
            .chain(
                moment_axes()
                    .into_iter()
                    .flat_map(|(_, a, _)| a.iter().map(|t| t.name)),
            )
            .chain(FORCES)
            .collect();
        let props: Vec<String> = names.iter().map(|n| n.to_string()).collect();
        stock_flight::fly(
            &root().join("flights/f16_test_flight.xml"),
            &root().join("flights/f16_cruise_init.xml"),
            &props,
        )
        .into_iter()
        .map(|v| Step { v })
        .collect()
    })
}

/// Largest |ours − JSBSim's| of one quantity over the flight, and JSBSim's range of it.
struct Worst {
    err: f64,
    at_time_s: f64,
    min: f64,
    max: f64,
}

impl Default for Worst {
    fn default() -> Worst {
        Worst {
            err: 0.0,
            at_time_s: f64::NAN,
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
        }
    }
}

impl Worst {
    fn add(&mut self, t: f64, ours: f32, jsbsim: f64) {
        self.min = self.min.min(jsbsim);
        self.max = self.max.max(jsbsim);
        let e = (f64::from(ours) - jsbsim).abs();
        if e > self.err || !e.is_finite() {
            (self.err, self.at_time_s) = (e, t);
        }
    }

    fn range(&self) -> f64 {
        self.max - self.min
    }
}

/// Prints one line and says whether `w.err` is within TOLERANCE of `scale` (the range of the
/// coefficient the quantity adds to).
fn report(what: &str, w: &Worst, scale: f64) -> bool {
    let ok = w.err <= TOLERANCE * scale;
    println!(
        "{what:30} max |err| {:9.3e} (t = {:8.3} s)  own range {:9.3e}  err/scale {:9.3e}{}",
        w.err,
        w.at_time_s,
        w.range(),
        w.err / scale,
        if ok { "" } else { "  <-- FAIL" }
    );
    ok
}

/// Each of `terms` at JSBSim's own inputs against its JSBSim property (`theirs`: over qbar·Sw, or
/// qbar·Sw·bw for a roll or yaw moment, qbar·Sw·cbarw for a pitch moment), within TOLERANCE of
/// `scale`.
fn compare_terms(
    steps: &[Step],
    terms: &[Term<'_>],
    scale: f64,
    theirs: fn(&Step, &str) -> f64,
) -> bool {
    let mut ok = true;
    for term in terms {
        let mut w = Worst::default();
        for s in steps {
            let ours = term.eval(&s.point()).unwrap().value;
            w.add(s.get("simulation/sim-time-sec"), ours, theirs(s, term.name));
        }
        ok &= report(term.name.trim_start_matches("aero/coefficient/"), &w, scale);
    }
    ok
}

/// JSBSim's range over the flight of a force property over qbar·Sw.
fn range_of(steps: &[Step], force: &str) -> f64 {
    let mut w = Worst::default();
    for s in steps {
        w.add(0.0, 0.0, s.coef(force));
    }
    w.range()
}

/// Wind (drag, side, lift) and body (x, y, z) totals against JSBSim's force properties.
fn compare_totals(path: &str, steps: &[Step], eval: impl Fn(&Step) -> Coefficients) -> bool {
    let mut worst: [Worst; 6] = Default::default();
    for s in steps {
        let c = eval(s);
        assert!(
            c.valid,
            "{path}: invalid at t = {}",
            s.get("simulation/sim-time-sec")
        );
        let ours = [
            c.wind.drag,
            c.wind.side,
            c.wind.lift,
            c.body.x,
            c.body.y,
            c.body.z,
        ];
        for ((w, o), f) in worst.iter_mut().zip(ours).zip(FORCES) {
            w.add(s.get("simulation/sim-time-sec"), o, s.coef(f));
        }
    }
    let names = [
        "CD (wind)",
        "CY (wind)",
        "CL (wind)",
        "CX (body)",
        "CY (body)",
        "CZ (body)",
    ];
    let mut ok = true;
    for (n, w) in names.iter().zip(&worst) {
        ok &= report(&format!("{path}: {n}"), w, w.range());
    }
    ok
}

#[test]
fn every_term_and_force_matches_jsbsim_over_the_test_flight() {
    let steps = flight();
    println!("{} JSBSim steps compared", steps.len());
    assert!(steps.len() >= 144_000, "1200 s at 120 Hz: {}", steps.len());
    let mut ok = true;
    let mut envelope = [(f64::MAX, f64::MIN); 4];
    for (k, p) in [
        "aero/alpha-rad",
        "aero/beta-rad",
        "velocities/mach",
        "fcs/elevator-pos-rad",
    ]
    .iter()
    .enumerate()
    {
        for s in steps {
            envelope[k] = (envelope[k].0.min(s.get(p)), envelope[k].1.max(s.get(p)));
        }
        println!(
            "flown: {p:22} {:+.4} … {:+.4}",
            envelope[k].0, envelope[k].1
        );
    }

    // Each term on its own, at JSBSim's own inputs, against the range of the axis it adds to.
    for (axis, force) in [
        (MODEL.drag, "forces/fwx-aero-lbs"),
        (MODEL.side, "forces/fwy-aero-lbs"),
        (MODEL.lift, "forces/fwz-aero-lbs"),
    ] {
        ok &= compare_terms(steps, axis, range_of(steps, force), Step::coef);
    }
    // The moment terms, against the range of their axis's sum; and the sums.
    for (k, (axis, moment, coef)) in moment_axes().into_iter().enumerate() {
        let sum = |s: &Step| moment.iter().map(|t| coef(s, t.name)).sum::<f64>();
        let mut total = Worst::default();
        for s in steps {
            total.add(0.0, 0.0, sum(s));
        }
        let scale = total.range();
        ok &= compare_terms(steps, moment, scale, coef);
        let mut w = Worst::default();
        let m = aero::MOMENTS.unwrap();
        for s in steps {
            let ours = m.coefficients_at(&s.point()).unwrap()[k];
            w.add(s.get("simulation/sim-time-sec"), ours, sum(s));
        }
        ok &= report(&format!("{axis} (sum)"), &w, scale);
    }
    // The ground-effect function the lift terms share.
    let mut w = Worst::default();
    for s in steps {
        let ours = Term {
            name: "",
            factors: &[Factor::Table(&tables::KCLGE)],
        }
        .eval(&s.point())
        .unwrap()
        .value;
        w.add(
            s.get("simulation/sim-time-sec"),
            ours,
            s.get("aero/function/kCLge"),
        );
    }
    // A factor of about 1 (the flight never comes near the ground: it stays at 1).
    ok &= report("kCLge", &w, 1.0);
    // The estimator's units reproduce JSBSim's bi2vel, ci2vel and flaperon mix.
    for (name, ours, theirs) in [
        ("bi2vel", 0, "aero/bi2vel"),
        ("ci2vel", 1, "aero/ci2vel"),
        ("flaperon-mix-rad", 2, "fcs/flaperon-mix-rad"),
    ] {
        let mut w = Worst::default();
        for s in steps {
            let (air, surf) = s.estimator_inputs();
            let p = Point::new(&MODEL, &air, &surf).unwrap();
            let v = [p.bi2vel_s, p.ci2vel_s, p.flaperon_mix_rad][ours];
            w.add(s.get("simulation/sim-time-sec"), v, s.get(theirs));
        }
        ok &= report(name, &w, w.range());
    }

    ok &= compare_totals("JSBSim units", steps, |s| MODEL.coefficients_at(&s.point()));
    ok &= compare_totals("estimator units", steps, |s| {
        let (air, surf) = s.estimator_inputs();
        MODEL.coefficients(&air, &surf)
    });
    assert!(
        ok,
        "the aero model differs from JSBSim (see the table above)"
    );
}

/// `MODEL` with one cell of the lift table CLDh moved by `delta`.
fn with_cldh_cell(row: usize, col: usize, delta: f32, run: impl FnOnce(&Model<'_>)) {
    let mut t: Table2<12, 5> = tables::CLDH.clone();
    t.data[row][col] += delta;
    let swap: Vec<Vec<Factor<'_>>> = MODEL
        .lift
        .iter()
        .map(|term| {
            term.factors
                .iter()
                .map(|f| match f {
                    Factor::Table(x) if std::ptr::addr_eq(*x, &tables::CLDH) => Factor::Table(&t),
                    other => *other,
                })
                .collect()
        })
        .collect();
    let lift: Vec<Term<'_>> = MODEL
        .lift
        .iter()
        .zip(&swap)
        .map(|(term, factors)| Term {
            name: term.name,
            factors,
        })
        .collect();
    run(&Model {
        lift: &lift,
        ..MODEL
    });
}

/// Worst lift error of a model against JSBSim over the flight, and whether it is within tolerance.
fn lift_error(model: &Model<'_>, steps: &[Step]) -> (Worst, bool) {
    let mut w = Worst::default();
    for s in steps {
        let c = model.coefficients_at(&s.point());
        w.add(
            s.get("simulation/sim-time-sec"),
            c.wind.lift,
            s.coef("forces/fwz-aero-lbs"),
        );
    }
    let ok = w.err <= TOLERANCE * w.range();
    (w, ok)
}

/// The engine deck (`aero::ENGINE`, flight-test calibration's thrust) gives JSBSim's thrust from
/// its N2, throttle position, Mach and density altitude; with the altitude standing in for the
/// density altitude (what calibration has: JSBSim's standard atmosphere, where they are the same)
/// within 0.1 %.
#[test]
fn the_engine_deck_gives_jsbsim_thrust() {
    let steps = flight();
    let Some(aero::Engine::Turbine(e)) = aero::ENGINE else {
        panic!("JSBSim's F-16 has a turbine deck the evaluator reads")
    };
    // One engine: `propulsion/engine/thrust-lbs` is all of it.
    assert_eq!(e.count, 1);
    let (mut exact, mut by_altitude) = (Worst::default(), Worst::default());
    let mut afterburner = 0;
    for s in steps {
        let g = |p: &str| s.get(p) as f32;
        let thrust = |alt_ft: f32| {
            e.thrust_lbf(
                g("propulsion/engine/n2"),
                g("fcs/throttle-pos-norm"),
                g("velocities/mach"),
                alt_ft,
            )
            .unwrap_or(f32::NAN)
        };
        let t = s.get("simulation/sim-time-sec");
        let jsbsim = s.get("propulsion/engine/thrust-lbs");
        exact.add(t, thrust(g("atmosphere/density-altitude")), jsbsim);
        by_altitude.add(t, thrust(g("position/h-sl-ft")), jsbsim);
        afterburner += usize::from(s.get("fcs/throttle-pos-norm") > 1.0);
    }
    println!("{afterburner} steps in afterburner");
    assert!(report("thrust", &exact, exact.range()));
    let rel = by_altitude.err / exact.max;
    println!("thrust at the altitude: worst {rel:.2e} of the largest thrust");
    assert!(rel <= 1e-3, "{rel}");
}

#[test]
fn a_model_with_one_table_cell_changed_fails() {
    let steps = flight();
    assert!(lift_error(&MODEL, steps).1);
    // The cell the cruise trim interpolates on (α 0.087 rad, elevator 0): moved by about one unit
    // of the XML's last digit (1e-4) … and by 1e-3.
    for delta in [1e-4_f32, 1e-3] {
        with_cldh_cell(3, 2, delta, |m| {
            let (w, ok) = lift_error(m, steps);
            report(&format!("CLDh[3][2] + {delta:e}: CL"), &w, w.range());
            assert!(
                !ok,
                "a lift table changed by {delta} passes the parity check"
            );
        });
    }
    // Every cell of CLDh in turn, by 1e-3: the ones the flight interpolates on are caught; the others
    // lie outside the flown α / elevator envelope (printed by the test above).
    let mut caught = Vec::new();
    for row in 0..12 {
        for col in 0..5 {
            with_cldh_cell(row, col, 1e-3, |m| {
                if !lift_error(m, steps).1 {
                    caught.push((tables::CLDH.rows[row], tables::CLDH.cols[col]));
                }
            });
        }
    }
    println!(
        "CLDh cells whose change by 1e-3 the flight detects: {} of 60: (α rad, elevator rad) {caught:?}",
        caught.len()
    );
    assert!(!caught.is_empty());
}
