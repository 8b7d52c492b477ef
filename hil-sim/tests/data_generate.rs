//! The `ci` preset end to end: maneuver files, flights, manifest, hashes, report (a few seconds).

use hil_sim::dataset::{self, Flight, Manifest, Split};
use hil_sim::maneuver::Preset;
use hil_sim::sensors::SensorConfig;

#[test]
fn ci_preset_writes_a_consistent_dataset() {
    let dir = std::env::temp_dir().join(format!("hil-data-gen-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let m = dataset::generate(Preset::Ci, 9, &dir, &SensorConfig::default(), 2, None).unwrap();
    let report = dataset::report::write_report(&dir).unwrap();
    let back = Manifest::read(&dir).unwrap();
    assert_eq!(back.flights, m.flights);
    assert_eq!(back.format, Manifest::FORMAT);
    assert_eq!(back.preset, "ci");
    assert!(!back.jsbsim_version.is_empty());
    assert_eq!(m.flights.len(), 5);
    assert_eq!(
        m.flights.iter().filter(|f| f.split == Split::Test).count(),
        1
    );
    for f in &m.flights {
        let path = dir.join(&f.file);
        assert_eq!(dataset::sha256_file(&path).unwrap(), f.sha256, "{}", f.file);
        let flight = Flight::read_csv(&path).unwrap();
        assert_eq!(flight.samples.len(), f.samples);
        if f.cut.is_none() {
            assert_eq!(f.samples, 3600, "{} runs its 180 s", f.name);
        }
        assert!(dir.join(format!("{}.xml", f.name)).is_file());
        assert!(dir.join(format!("{}_init.xml", f.name)).is_file());
    }
    for (name, sha) in &back.files {
        assert_eq!(
            &dataset::sha256_file(&dir.join(name)).unwrap(),
            sha,
            "{name}"
        );
    }
    for name in ["envelope.png", "flight_path.png", "dataset.md"] {
        assert!(
            back.files.contains_key(name),
            "{name} is hashed in the manifest"
        );
    }
    // The high-α profile is what puts training data above 15°.
    let over15: f64 = report.train.alpha_band_share[4..].iter().sum();
    assert!(over15 > 0.03, "share above 15° α: {over15}");
    let shares: f64 = report.train.alpha_band_share.iter().sum();
    assert!((shares - 1.0).abs() < 1e-9);

    assert_eq!(back.suites(), estimator_core::Suite::ALL);
    assert!(back.carries(estimator_core::Suite::Egi));

    // A format-3 manifest (no `suites` field) reads as a Table 1 dataset.
    let mut v3 = serde_json::to_value(&back).unwrap();
    v3["format"] = 3.into();
    v3.as_object_mut().unwrap().remove("suites");
    std::fs::write(dir.join("manifest.json"), v3.to_string()).unwrap();
    let m3 = Manifest::read(&dir).unwrap();
    assert_eq!(m3.suites(), [estimator_core::Suite::Table1]);
    assert!(!m3.carries(estimator_core::Suite::Egi));
    v3["suites"] = serde_json::json!(["table1", "egi"]);
    std::fs::write(dir.join("manifest.json"), v3.to_string()).unwrap();
    assert!(Manifest::read(&dir).is_err(), "format 3 cannot carry egi");

    // A dataset of an older format (no lat/lon columns) is refused with what to do.
    let old = Manifest { format: 1, ..back };
    old.write(&dir).unwrap();
    let err = Manifest::read(&dir).unwrap_err().to_string();
    assert!(
        err.contains("format 1") && err.contains("regenerate"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
