//! Every flight the project records is the flight stock JSBSim flies from the same files.
//!
//! Each script is flown twice: once by hil-sim (bridge, sensors, dataset), once by
//! `scripts/jsbsim-stock`, which is the pinned `jsbsim` package and nothing else
//! (`load_script(script, 0.0, initfile)`, `run_ic()`, `run()` to the end). Truth α and β must agree
//! to 1e-9° at every recorded instant, and the recorded time must be JSBSim's own clock. Covered:
//! every flight of a generated `ci` dataset, the build's aircraft's test flight, the package's own
//! `scripts/f16_test.xml` (declared at dt 0.00833333, not 1/120: flown at its own rate), and
//! `hil-sim fly --aircraft-dir` on an airframe variant against stock JSBSim with that aircraft path.

use std::path::{Path, PathBuf};

use hil_sim::dataset::{self, Flight};
use hil_sim::fly::{self, FlyConfig};
use hil_sim::maneuver::{self, Plan, Preset};
use hil_sim::sensors::SensorConfig;

const TOLERANCE_DEG: f64 = 1e-9;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("hil-replay-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// (sim time, α, β) after every step of a stock run of `script`.
fn stock_run(script: &Path, initfile: Option<&Path>, out: &Path) -> Vec<[f64; 3]> {
    stock_run_on(script, initfile, None, out)
}

/// [`stock_run`] with the aircraft loaded from `aircraft_dir` (`set_aircraft_path`).
fn stock_run_on(
    script: &Path,
    initfile: Option<&Path>,
    aircraft_dir: Option<&Path>,
    out: &Path,
) -> Vec<[f64; 3]> {
    let mut cmd = std::process::Command::new(root().join("scripts/jsbsim-stock"));
    cmd.arg(script);
    if let Some(i) = initfile {
        cmd.arg(i);
    }
    if let Some(d) = aircraft_dir {
        cmd.arg("--aircraft-dir").arg(d);
    }
    // JSBSim's banner and <notify/> lines go to stdout: keep them out of the test log.
    let status = cmd
        .arg("--out")
        .arg(out)
        .stdout(std::process::Stdio::null())
        .status()
        .unwrap();
    assert!(status.success(), "jsbsim-stock {} failed", script.display());
    std::fs::read_to_string(out)
        .unwrap()
        .lines()
        .map(|l| {
            let v: Vec<f64> = l.split('\t').map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}

/// The stock run has every recorded sample at the same instant with the same α and β. Returns the
/// number of samples compared.
fn assert_same_truth(what: &str, flight: &Flight, stock: &[[f64; 3]]) -> usize {
    assert!(!flight.samples.is_empty(), "{what}: no samples");
    let mut rows = stock.iter();
    for (k, s) in flight.samples.iter().enumerate() {
        // Samples are every 6th step; the stock run has every step: find the same instant.
        let row = rows
            .find(|r| r[0] == s.time_s)
            .unwrap_or_else(|| panic!("{what}: stock run has no step at t = {} s", s.time_s));
        let (da, db) = (
            (row[1] - s.truth.alpha_deg).abs(),
            (row[2] - s.truth.beta_deg).abs(),
        );
        assert!(
            da <= TOLERANCE_DEG && db <= TOLERANCE_DEG,
            "{what}: sample {k} at t = {} s: α {} vs stock {}, β {} vs stock {}",
            s.time_s,
            s.truth.alpha_deg,
            row[1],
            s.truth.beta_deg,
            row[2]
        );
    }
    // The 20 Hz samples are the stock clock's every 6th step.
    let want: Vec<f64> = stock.iter().skip(5).step_by(6).map(|r| r[0]).collect();
    let got: Vec<f64> = flight.samples.iter().map(|s| s.time_s).collect();
    assert_eq!(&want[..got.len()], &got[..], "{what}: sample instants");
    flight.samples.len()
}

#[test]
fn generated_dataset_is_what_stock_jsbsim_flies() {
    let dir = tmp("ci");
    let (m, _) = dataset::generate(
        &Plan::new(Preset::Ci, 11),
        &dir,
        &SensorConfig::default(),
        2,
        None,
    )
    .unwrap();
    assert_eq!(m.flights.len(), 5);
    for f in &m.flights {
        let (script, init) = maneuver::files(&dir, &f.name);
        // The emitted dt is exactly 1/120 in binary.
        let xml = std::fs::read_to_string(&script).unwrap();
        assert!(xml.contains("dt=\"0.008333333333333333\""), "{}", f.name);
        let flight = Flight::read_csv(&dir.join(&f.file)).unwrap();
        let stock = stock_run(&script, Some(&init), &dir.join(format!("{}.tsv", f.name)));
        let n = assert_same_truth(&f.name, &flight, &stock);
        if f.cut.is_none() {
            assert_eq!(n, 3600, "{}: all 180 s compared", f.name);
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The build's aircraft's 20-minute test flight, `flights/NAME_test_flight.xml` with its
/// `NAME_cruise_init.xml`.
#[test]
fn project_test_flight_is_what_stock_jsbsim_flies() {
    let dir = tmp("test-flight");
    let name = estimator_core::aircraft::AIRCRAFT.name;
    let script = root().join(format!("flights/{name}_test_flight.xml"));
    let xml = std::fs::read_to_string(&script).unwrap();
    assert!(xml.contains("dt=\"0.008333333333333333\""));
    let flight = fly::fly_script(&script, &FlyConfig::default()).unwrap();
    assert!(flight.cut.is_none(), "{:?}", flight.cut);
    let stock = stock_run(
        &script,
        Some(&root().join(format!("flights/{name}_cruise_init.xml"))),
        &dir.join("stock.tsv"),
    );
    assert_eq!(
        assert_same_truth(&format!("{name}_test_flight"), &flight, &stock),
        24_000
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn package_f16_test_script_is_what_stock_jsbsim_flies() {
    let lib = root().join(".venv").join("lib");
    let script = std::fs::read_dir(&lib)
        .unwrap_or_else(|e| panic!("{}: {e}; run scripts/bootstrap", lib.display()))
        .flatten()
        .map(|e| e.path().join("site-packages/jsbsim/scripts/f16_test.xml"))
        .find(|p| p.is_file())
        .expect("the jsbsim package's scripts/f16_test.xml; run scripts/bootstrap");
    let dir = tmp("f16-test");
    let flight = fly::fly_script(&script, &FlyConfig::default()).unwrap();
    // Its initialize file (reset00) is in the aircraft folder, where stock JSBSim looks.
    let stock = stock_run(&script, None, &dir.join("stock.tsv"));
    let n = assert_same_truth("f16_test.xml", &flight, &stock);
    if flight.cut.is_none() {
        // 700 s at dt 0.00833333: the script's own rate, so its clock ends a little past 700 s.
        assert!(n >= 13_999, "{n} samples");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `hil-sim fly --aircraft-dir DIR` flies what stock JSBSim flies with `set_aircraft_path(DIR)`,
/// records DIR's f16.xml in the manifest, and the variant is not the stock F-16 (else this would
/// prove nothing).
#[test]
fn fly_with_an_aircraft_dir_is_what_stock_jsbsim_flies_with_that_aircraft_path() {
    let dir = tmp("aircraft-dir");
    let variant = dir.join("variant");
    let status = std::process::Command::new(root().join("scripts/airframe-variant"))
        .arg(root().join("airframes/f16-variants/a-soft-stall.toml"))
        .arg("--out")
        .arg(&variant)
        .stdout(std::process::Stdio::null())
        .status()
        .unwrap();
    assert!(status.success(), "scripts/airframe-variant failed");
    let script = root().join("flights/f16_test_flight.xml");
    let init = root().join("flights/f16_cruise_init.xml");
    let out = dir.join("fly");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_hil-sim"))
        .args(["fly", "--max-time-s", "300", "--script"])
        .arg(&script)
        .arg("--aircraft-dir")
        .arg(&variant)
        .arg("--out")
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .status()
        .unwrap();
    assert!(status.success(), "hil-sim fly --aircraft-dir failed");
    let m = dataset::Manifest::read(&out).unwrap();
    let flight = Flight::read_csv(&out.join(&m.flights[0].file)).unwrap();
    let xml = variant.join("f16/f16.xml");
    assert_eq!(
        m.aircraft.as_ref().map(|a| a.model_xml_sha256.clone()),
        Some(dataset::sha256_file(&xml).unwrap())
    );
    let stock = stock_run_on(&script, Some(&init), Some(&variant), &dir.join("stock.tsv"));
    assert_eq!(assert_same_truth("variant", &flight, &stock), 6000);
    // The same script on JSBSim's own F-16 flies another α.
    let own = stock_run(&script, Some(&init), &dir.join("own.tsv"));
    let last = flight.samples.last().unwrap();
    let own_row = own.iter().find(|r| r[0] == last.time_s).unwrap();
    assert!(
        (own_row[1] - last.truth.alpha_deg).abs() > 0.01,
        "the variant flies the stock α ({} vs {})",
        own_row[1],
        last.truth.alpha_deg
    );
    std::fs::remove_dir_all(&dir).ok();
}
