//! The `ci` preset end to end: maneuver files, flights, manifest, hashes, report (a few seconds).

use hil_sim::dataset::{self, Flight, Manifest, Split};
use hil_sim::maneuver::{Plan, Preset};
use hil_sim::sensors::SensorConfig;

#[test]
fn ci_preset_writes_a_consistent_dataset() {
    let dir = std::env::temp_dir().join(format!("hil-data-gen-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (m, flights) = dataset::generate(
        &Plan::new(Preset::Ci, 9),
        &dir,
        &SensorConfig::default(),
        2,
        None,
    )
    .unwrap();
    // The report from the flights in memory (what `hil-sim generate` writes) is the report from
    // the CSVs on disk (what `merge` and a re-run write): same numbers, same dataset.md bytes.
    let from_memory = dataset::report::write_report_of(&dir, m.clone(), flights).unwrap();
    let md_memory = std::fs::read(dir.join("dataset.md")).unwrap();
    let report = dataset::report::write_report(&dir).unwrap();
    assert_eq!(from_memory, report);
    assert_eq!(md_memory, std::fs::read(dir.join("dataset.md")).unwrap());
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

/// Every file of a dataset directory, by name, with its bytes.
fn files_of(dir: &std::path::Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let p = e.unwrap().path();
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect()
}

/// `generate --shard K/N` for every K, then `merge`, writes exactly the bytes of a one-machine
/// `generate` (manifest, CSVs, maneuver files, report and plots); a finished shard is not flown
/// again; an incomplete or mixed set of shards is refused with what to run.
#[test]
fn shards_merge_into_the_one_machine_dataset() {
    use dataset::{GenerateError, Shard, ShardOutcome};
    let root = std::env::temp_dir().join(format!("hil-data-shard-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let s = SensorConfig::default();
    let one = root.join("one");
    dataset::generate(&Plan::new(Preset::Ci, 4), &one, &s, 2, None).unwrap();
    dataset::report::write_report(&one).unwrap();

    let sh = root.join("sharded");
    let shard = |k: usize, n: usize| Shard { index: k, count: n };
    // Shard 2/3 first: order does not matter. Five flights: shards of 2, 2 and 1.
    for k in [2, 0] {
        let r = dataset::generate_shard(&Plan::new(Preset::Ci, 4), &sh, &s, 1, shard(k, 3), None)
            .unwrap();
        assert_eq!(r, ShardOutcome::Flown(if k == 2 { 1 } else { 2 }));
    }
    let e = dataset::merge(&sh).unwrap_err();
    assert!(
        matches!(&e, GenerateError::Shard(m) if m.contains("missing shards 1/3")),
        "{e}"
    );
    let r =
        dataset::generate_shard(&Plan::new(Preset::Ci, 4), &sh, &s, 1, shard(1, 3), None).unwrap();
    assert_eq!(r, ShardOutcome::Flown(2));
    // A re-run finds the record complete and flies nothing.
    let r =
        dataset::generate_shard(&Plan::new(Preset::Ci, 4), &sh, &s, 1, shard(1, 3), None).unwrap();
    assert_eq!(r, ShardOutcome::AlreadyComplete(2));
    // A shard recorded twice, or a record of another shard count, in the same directory is refused.
    let stray = sh.join("shard-0-of-3-copy.json");
    let text = std::fs::read_to_string(shard(0, 3).record_path(&sh)).unwrap();
    std::fs::write(&stray, &text).unwrap();
    let e = dataset::merge(&sh).unwrap_err();
    assert!(
        matches!(&e, GenerateError::Shard(m) if m.contains("appears twice")),
        "{e}"
    );
    std::fs::write(&stray, text.replace("\"count\": 3", "\"count\": 2")).unwrap();
    let e = dataset::merge(&sh).unwrap_err();
    assert!(
        matches!(&e, GenerateError::Shard(m) if m.contains("shard count")),
        "{e}"
    );
    // A foreign shard (another seed) is refused by name, and nothing is written.
    assert!(text.contains("\"seed\": 4"));
    std::fs::write(&stray, text.replace("\"seed\": 4", "\"seed\": 5")).unwrap();
    let e = dataset::merge(&sh).unwrap_err();
    assert!(
        matches!(&e, GenerateError::Shard(m) if m.contains("in its seed") && m.contains("shard-")),
        "{e}"
    );
    assert!(
        !sh.join("manifest.json").exists(),
        "a refused merge writes nothing"
    );
    std::fs::remove_file(&stray).unwrap();

    dataset::merge(&sh).unwrap();
    dataset::report::write_report(&sh).unwrap();
    let (a, b) = (files_of(&one), files_of(&sh));
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (name, bytes) in &a {
        assert!(bytes == &b[name], "{name} differs");
    }
    assert!(a.contains_key("manifest.json") && a.contains_key("dataset.md"));
    let _ = std::fs::remove_dir_all(&root);
    // The --shard text.
    assert_eq!("2/4".parse::<Shard>().unwrap(), shard(2, 4));
    for bad in ["4/4", "0/0", "1", "a/2", "-1/3"] {
        assert_eq!(
            bad.parse::<Shard>(),
            Err(dataset::BadShard(bad.into())),
            "{bad}"
        );
    }
}

/// The `flight-test` preset: three test points, at most 30 minutes, flown whole, each with the
/// nose boom's record beside its CSV (hashed in the manifest, one row per sample, close to truth).
#[test]
fn flight_test_preset_flies_its_cards_and_records_the_boom() {
    let dir = std::env::temp_dir().join(format!("hil-data-ft-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (m, flights) = dataset::generate(
        &Plan::new(Preset::FlightTest, 1),
        &dir,
        &SensorConfig::default(),
        2,
        None,
    )
    .unwrap();
    assert_eq!(m.flights.len(), 3);
    let minutes: f64 = m.flights.iter().map(|f| f.duration_s).sum::<f64>() / 60.0;
    assert!(minutes <= 30.0, "{minutes} min of flight tests");
    assert!(
        m.config.get("boom").is_some(),
        "the boom's parameters are in the manifest"
    );
    for (e, fl) in m.flights.iter().zip(&flights) {
        assert!(e.cut.is_none(), "{}: {:?}", e.name, e.cut);
        let boom = e.boom.as_ref().unwrap();
        assert_eq!(
            dataset::sha256_file(&dir.join(&boom.file)).unwrap(),
            boom.sha256
        );
        let rec = hil_sim::boom::read_csv(&dir.join(&boom.file)).unwrap();
        assert_eq!(rec.len(), fl.samples.len());
        let close = rec
            .iter()
            .zip(&fl.samples)
            .filter(|(b, s)| (b.alpha_deg - s.truth.alpha_deg).abs() < 1.0)
            .count();
        assert!(
            close * 100 >= rec.len() * 99,
            "{}: {close} of {}",
            e.name,
            rec.len()
        );
        // The card's inputs are there: both rudder doublet halves, the wind-up turn's 60° bank.
        let xml = std::fs::read_to_string(dir.join(format!("{}.xml", e.name))).unwrap();
        assert!(xml.contains("maneuver/card-speed-hold"), "{}", e.name);
        assert!(xml.contains(" 60.0000\n"), "{}: no 60° bank", e.name);
    }
    std::fs::remove_dir_all(&dir).ok();
}
