//! End-to-end through the JSBSim bridge. These need the pinned venv (`scripts/bootstrap`); without it
//! they fail with the bridge's "run scripts/bootstrap" error rather than skipping.

use std::path::{Path, PathBuf};

use hil_sim::dataset::Flight;
use hil_sim::flight::Every;
use hil_sim::fly::{self, FlyConfig};
use hil_sim::maneuver::{self, Profile, ProfileKind};
use hil_sim::plant::{self, Plant, PlantError, ReadPlan};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn stock_script(name: &str) -> PathBuf {
    let lib = root().join(".venv").join("lib");
    let entries = std::fs::read_dir(&lib)
        .unwrap_or_else(|e| panic!("{}: {e}; run scripts/bootstrap", lib.display()));
    for e in entries.flatten() {
        let p = e.path().join("site-packages/jsbsim/scripts").join(name);
        if p.is_file() {
            return p;
        }
    }
    panic!(
        "stock JSBSim script {name} not found under {}; run scripts/bootstrap",
        lib.display()
    );
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("hil-data-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The stock-format test flight (`flights/`), its first 6 s flown through the bridge.
fn first_6_s_of_the_test_flight() -> (PathBuf, Flight) {
    let script = root().join("flights/f16_test_flight.xml");
    let cfg = FlyConfig {
        max_time_s: Some(6.0),
        ..FlyConfig::default()
    };
    let flight = fly::fly_script(&script, &cfg).unwrap();
    (script, flight)
}

/// Truth α/β at the 20 Hz samples are JSBSim's own aero/alpha-deg, aero/beta-deg at those steps.
#[test]
fn truth_alpha_is_jsbsims_alpha_at_the_same_step() {
    let (script, flight) = first_6_s_of_the_test_flight();
    assert_eq!(flight.samples.len(), 120, "6 s at 20 Hz");
    assert!(flight.cut.is_none());

    let mut p = Plant::spawn().unwrap();
    let init = root().join("flights/f16_cruise_init.xml");
    p.load_script(&std::fs::canonicalize(&script).unwrap(), Some(&init))
        .unwrap();
    p.watch(&["aero/alpha-deg", "aero/beta-deg"]).unwrap();
    let rows = p.step(720).unwrap();
    for (k, s) in flight.samples.iter().enumerate() {
        let r = rows.row((k + 1) * 6 - 1).unwrap();
        assert_eq!(s.truth.alpha_deg, r[0], "sample {k}");
        assert_eq!(s.truth.beta_deg, r[1], "sample {k}");
        assert!((s.time_s - (k + 1) as f64 * 0.05).abs() < 1e-12);
    }
    // Trimmed cruise: α is a sensible positive angle and the accelerometer sees ≈ −1 g.
    let a = flight.samples[100].truth.alpha_deg;
    assert!(a > 0.5 && a < 6.0, "α {a}");
    let az = flight.samples[100].sensed[estimator_core::Channel::AccelZ.index()];
    assert!((az + 9.8).abs() < 1.5, "accel z {az}");

    // Position: the init file's 47° N (geocentric, JSBSim's default: tan φd = tan φc / (1 − e²)
    // gives 47.19° geodetic) 122° E, heading east; over the 5.95 s between the first and the last
    // sample the track runs east at the true airspeed (no wind, level), within 1 %.
    let (a, z) = (&flight.samples[0].truth, &flight.samples[119].truth);
    let geodetic = (47f64.to_radians().tan() / (1.0 - 6.694_38e-3))
        .atan()
        .to_degrees();
    assert!((a.lat_deg - geodetic).abs() < 2e-3, "lat {}", a.lat_deg);
    assert!((a.lon_deg - 122.0).abs() < 1e-2, "lon {}", a.lon_deg);
    let (north, east) =
        hil_sim::dataset::report::north_east_m(a.lat_deg, a.lon_deg, z.lat_deg, z.lon_deg);
    let mean_vt: f64 =
        flight.samples.iter().map(|s| s.truth.vt_mps).sum::<f64>() / flight.samples.len() as f64;
    let expected = mean_vt * 5.95;
    assert!(
        (east - expected).abs() < 0.01 * expected,
        "east {east} m, expected {expected} m"
    );
    assert!(north.abs() < 0.01 * expected, "north {north} m");
}

/// A planned watch reads exactly what a read at every step gives where the plan says so, NaN
/// elsewhere, everything at step 0, and keeps its step count across `step` requests.
#[test]
fn a_read_plan_reads_the_same_values_where_it_reads() {
    let script = stock_script("f16_test.xml");
    let props = ["aero/alpha-deg", "velocities/p-rad_sec", "attitude/phi-rad"];
    let e = |period, offset| Every { period, offset };
    let plan = ReadPlan::new(&[None, Some(vec![e(6, 5)]), Some(vec![e(4, 1), e(6, 0)])]);
    let run = |plan: &ReadPlan| {
        let mut p = Plant::spawn().unwrap();
        plant::load_runscript(&mut p, &script).unwrap();
        p.watch_planned(&props, plan).unwrap();
        let mut rows: Vec<f64> = Vec::new();
        for n in [37, 50, 13] {
            let r = p.step(n).unwrap();
            rows.extend((0..r.len()).flat_map(|k| r.row(k).unwrap().to_vec()));
        }
        rows
    };
    let all = run(&ReadPlan::every_step(props.len()));
    let some = run(&plan);
    assert_eq!(all.len(), 100 * props.len());
    for (k, (a, s)) in all.chunks(3).zip(some.chunks(3)).enumerate() {
        for (i, read) in plan.at(k as u64).iter().enumerate() {
            if *read {
                assert_eq!(a[i].to_bits(), s[i].to_bits(), "step {k} property {i}");
            } else {
                assert!(s[i].is_nan(), "step {k} property {i}: {}", s[i]);
            }
        }
    }
    let mut p = Plant::spawn().unwrap();
    plant::load_runscript(&mut p, &script).unwrap();
    let err = p.watch_planned(&props[..2], &plan).unwrap_err();
    assert!(
        err.to_string()
            .contains("read plan for 3 properties, 2 watched"),
        "{err}"
    );
}

/// The benchmark's raw stepping (`run`, nothing read) flies the same flight as `fly_script`: after
/// 719 raw steps and one watched step, α is bit-identical to the recorded sample at 6 s.
#[test]
fn raw_stepping_flies_the_same_flight() {
    let (script, flight) = first_6_s_of_the_test_flight();
    let mut p = Plant::spawn().unwrap();
    plant::load_runscript(&mut p, &script).unwrap();
    assert_eq!(p.run_raw(719).unwrap(), 719);
    p.watch(&["aero/alpha-deg", "simulation/sim-time-sec"])
        .unwrap();
    let rows = p.step(1).unwrap();
    let row = rows.row(0).unwrap();
    let last = flight.samples.last().unwrap();
    assert_eq!(row[0], last.truth.alpha_deg);
    assert!((row[1] - 6.0).abs() < 1e-9, "t {}", row[1]);
}

/// A stock runway script (initialize file in the aircraft folder) flies a few seconds.
#[test]
fn stock_runway_script_runs() {
    let cfg = FlyConfig {
        max_time_s: Some(3.0),
        ..FlyConfig::default()
    };
    let f = fly::fly_script(&stock_script("f16_test.xml"), &cfg).unwrap();
    assert_eq!(f.samples.len(), 60);
    assert!(f.cut.is_none());
}

#[test]
fn bad_scripts_give_the_right_errors() {
    let cfg = FlyConfig {
        max_time_s: Some(1.0),
        ..FlyConfig::default()
    };
    let missing = fly::fly_script(Path::new("/no/such/script.xml"), &cfg).unwrap_err();
    assert!(
        matches!(missing, PlantError::ScriptUnreadable { .. }),
        "{missing}"
    );
    assert!(missing.to_string().contains("/no/such/script.xml"));

    let c172 = fly::fly_script(&stock_script("c1721.xml"), &cfg).unwrap_err();
    assert!(
        matches!(&c172, PlantError::WrongAircraft { aircraft, .. } if aircraft == "c172x" || aircraft.starts_with("c172")),
        "{c172}"
    );

    let d = tmp("bad");
    let broken = d.join("broken.xml");
    std::fs::write(
        &broken,
        "<?xml version=\"1.0\"?>\n<runscript name=\"x\">\n<use aircraft=\"f16\" initialize=\"reset00\"/>\n<run start=\"0\" end=\"1\" dt=\"0.00833\">\n<event><condition> simulation/sim-time-sec ge 0 </condition></run>\n</runscript>\n",
    )
    .unwrap();
    let e = fly::fly_script(&broken, &cfg).unwrap_err();
    assert!(
        matches!(&e, PlantError::ScriptRejected { message, .. } if message.contains("invalid XML")),
        "{e}"
    );
    assert!(e.to_string().contains("broken.xml"));

    // Another integration rate: refused with the rate named, not flown with mis-timed sensors.
    let slow = d.join("slow.xml");
    std::fs::write(
        &slow,
        "<?xml version=\"1.0\"?>\n<runscript name=\"x\">\n<use aircraft=\"f16\" initialize=\"reset00\"/>\n<run start=\"0\" end=\"1\" dt=\"0.01\">\n</run>\n</runscript>\n",
    )
    .unwrap();
    let e = fly::fly_script(&slow, &cfg).unwrap_err();
    assert!(
        matches!(&e, PlantError::UnsupportedRate { dt_s, .. } if *dt_s == 0.01),
        "{e}"
    );
    assert!(e.to_string().contains("100.0000 Hz"), "{e}");

    let not_script = d.join("init.xml");
    std::fs::write(&not_script, "<initialize name=\"x\"/>").unwrap();
    let e = fly::fly_script(&not_script, &cfg).unwrap_err();
    assert!(matches!(e, PlantError::NotAScript { .. }), "{e}");
    std::fs::remove_dir_all(&d).ok();
}

/// A flight into the ground is cut at the contact and says so.
#[test]
fn ground_contact_cuts_the_flight() {
    let d = tmp("ground");
    std::fs::write(
        d.join("dive_init.xml"),
        "<?xml version=\"1.0\"?>\n<initialize name=\"dive_init\">\n<latitude unit=\"DEG\"> 47 </latitude>\n<longitude unit=\"DEG\"> 122 </longitude>\n<altitude unit=\"FT\"> 600 </altitude>\n<vc unit=\"KTS\"> 350 </vc>\n<psi unit=\"DEG\"> 0 </psi>\n<gamma unit=\"DEG\"> -30 </gamma>\n<theta unit=\"DEG\"> -28 </theta>\n<running> -1 </running>\n</initialize>\n",
    )
    .unwrap();
    std::fs::write(
        d.join("dive.xml"),
        "<?xml version=\"1.0\"?>\n<runscript name=\"dive\">\n<use aircraft=\"f16\" initialize=\"dive_init\"/>\n<run start=\"0\" end=\"30\" dt=\"0.00833333\">\n</run>\n</runscript>\n",
    )
    .unwrap();
    let f = fly::fly_script(&d.join("dive.xml"), &FlyConfig::default()).unwrap();
    let cut = f.cut.clone().expect("the dive must be cut");
    assert!(cut.contains("ground contact"), "{cut}");
    assert!(f.duration_s() < 10.0);
    assert!(f.samples.last().unwrap().truth.alt_msl_m < 50.0);
    std::fs::remove_dir_all(&d).ok();
}

/// Same seed → identical CSV bytes; another sensor seed → other bytes, same truth.
#[test]
fn same_seed_identical_csv_bytes() {
    let script = root().join("flights/f16_test_flight.xml");
    let d = tmp("det");
    let fly = |seed: u64, name: &str| {
        let cfg = FlyConfig {
            seed,
            max_time_s: Some(25.0),
            ..FlyConfig::default()
        };
        let f = fly::fly_script(&script, &cfg).unwrap();
        let p = d.join(name);
        f.write_csv(&p).unwrap();
        (f, std::fs::read(&p).unwrap())
    };
    let (fa, a) = fly(7, "a.csv");
    let (_, b) = fly(7, "b.csv");
    let (fc, c) = fly(8, "c.csv");
    assert_eq!(a, b);
    assert_ne!(a, c);
    assert_eq!(fa.samples[300].truth, fc.samples[300].truth);
    std::fs::remove_dir_all(&d).ok();
}

/// A generated maneuver saved as XML and flown again through JSBSim's script loader reproduces the
/// flight stored in the dataset CSV.
#[test]
fn saved_generated_maneuver_reproduces_the_flight() {
    let d = tmp("gen");
    let m = maneuver::generate(&Profile::preset(ProfileKind::Aggressive), 42, "agg", 40.0).unwrap();
    let script = m.write(&d).unwrap();
    let cfg = FlyConfig {
        seed: 3,
        ..FlyConfig::default()
    };
    let first = fly::fly_script(&script, &cfg).unwrap();
    first.write_csv(&d.join("agg.csv")).unwrap();
    let stored = Flight::read_csv(&d.join("agg.csv")).unwrap();

    // Fresh copy of the files in another folder, flown by a fresh bridge.
    let d2 = tmp("gen2");
    std::fs::copy(&script, d2.join("agg.xml")).unwrap();
    std::fs::copy(d.join("agg_init.xml"), d2.join("agg_init.xml")).unwrap();
    let again = fly::fly_script(&d2.join("agg.xml"), &cfg).unwrap();
    assert_eq!(stored.samples.len(), 800);
    assert_eq!(stored.samples, again.samples);
    // It really maneuvers: the targets and sticks move α and bank.
    let (lo, hi) = again
        .samples
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), s| {
            (a.min(s.truth.alpha_deg), b.max(s.truth.alpha_deg))
        });
    assert!(hi - lo > 3.0, "α range {lo}..{hi}");
    std::fs::remove_dir_all(&d).ok();
    std::fs::remove_dir_all(&d2).ok();
}

/// The `ood` preset's conditions are what JSBSim flies: the mass cases' weights 15 % beyond the
/// trained range (16,006 and 27,175 lb, from the tanks and point mass the script sets before the
/// trim), the wind case's 25 m/s, and otherwise the twin's flight (the same initial state).
#[test]
fn ood_cases_fly_their_conditions() {
    use hil_sim::maneuver::OodCase;
    let d = tmp("ood");
    let cfg = FlyConfig {
        seed: 1,
        max_time_s: Some(12.0),
        ..FlyConfig::default()
    };
    let p = Profile::preset(ProfileKind::Gentle);
    let fly_case = |case: Option<OodCase>, name: &str| {
        let m = maneuver::generate_case(&p, 7, name, 60.0, case).unwrap();
        fly::fly_script(&m.write(&d).unwrap(), &cfg).unwrap()
    };
    let lb = |kg: f64| kg / plant::LB_TO_KG;
    let nominal = fly_case(None, "nominal");
    let low = fly_case(Some(OodCase::MassLow), "low");
    let high = fly_case(Some(OodCase::MassHigh), "high");
    let wind = fly_case(Some(OodCase::Wind25), "wind");
    let w = nominal.samples[0].truth.mass_kg;
    assert!((lb(w) - 17_630.0) > 2.0 * 600.0 - 1.0 && (lb(w) - 17_630.0) < 2.0 * 3_000.0 + 1.0);
    for s in &low.samples {
        assert!(
            (lb(s.truth.mass_kg) - 16_005.5).abs() < 1.0,
            "{}",
            lb(s.truth.mass_kg)
        );
    }
    for s in &high.samples {
        assert!(
            (lb(s.truth.mass_kg) - 27_174.5).abs() < 1.0,
            "{}",
            lb(s.truth.mass_kg)
        );
    }
    // The wind ramps in from 0.5 s with a 5-s time constant; at 12 s the truth (steady wind plus
    // the twin's turbulence) is within 1 m/s of 25 m/s (trained: at most 12.2 m/s).
    let last = wind.samples.last().unwrap().truth;
    let speed = last.wind_north_mps.hypot(last.wind_east_mps);
    assert!((speed - 25.0).abs() < 1.0, "wind {speed} m/s");
    // Same initial state as the twin: the cases change conditions, not the draw.
    assert_eq!(
        nominal.samples[0].truth.alt_msl_m,
        wind.samples[0].truth.alt_msl_m
    );
    std::fs::remove_dir_all(&d).ok();
}
