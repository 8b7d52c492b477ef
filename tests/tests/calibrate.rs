//! Flight-test calibration reads only what a flight-test aircraft records, and finds a variant's
//! scales: a flight-test dataset flown on the build's aircraft's variant C
//! (`airframes/NAME-variants/c-pure-scales.toml`: lift × 0.94, side force × 1.10, drag × 1.10),
//! calibrated with and without its truth columns, against the same card flown on the model
//! (JSBSim's model of the aircraft) on four other sensor seeds (its CG and pitch moment the
//! model's too), then with its roll and yaw moments over the card flown on the first calibrated
//! aircraft. A model card on the flight test's seed is refused. scripts/test runs it in every
//! build whose aircraft has development variants.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn bin(name: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("test executable path");
    exe.parent()
        .and_then(Path::parent)
        .expect("target/<profile>/deps")
        .join(name)
}

fn ok(cmd: &mut Command) {
    let o = cmd.output().expect("start");
    assert!(
        o.status.success(),
        "{cmd:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

fn calibrate(ft: &Path, models: &[PathBuf], out: &Path) -> Command {
    let mut cmd = Command::new(bin("trainer"));
    cmd.args(["calibrate", "--flight-test"]).arg(ft);
    for m in models {
        cmd.arg("--model-flight-test").arg(m);
    }
    cmd.arg("--out").arg(out);
    cmd
}

fn calibration(ft: &Path, models: &[PathBuf], out: &Path) -> serde_json::Value {
    ok(&mut calibrate(ft, models, out));
    serde_json::from_slice(&std::fs::read(out.join("calibration.json")).unwrap()).unwrap()
}

/// Writes the build's aircraft's variant C (`airframes/NAME-variants/c-pure-scales.toml`) into
/// `dir/c`.
fn variant_c(dir: &Path) -> PathBuf {
    let air = estimator_core::aircraft::AIRCRAFT;
    let aircraft = dir.join("c");
    ok(Command::new(root().join("scripts/airframe-variant"))
        .arg(root().join(format!(
            "airframes/{}-variants/c-pure-scales.toml",
            air.name
        )))
        .args(["--model", air.jsbsim_model, "--out"])
        .arg(&aircraft));
    aircraft
}

/// The flight-test card on sensor seed `seed` into `out`, flown on the variant in `variant` or
/// (None) on the model.
fn card(seed: u32, out: &Path, variant: Option<&Path>) {
    let mut cmd = Command::new(bin("hil-sim"));
    cmd.args([
        "generate",
        "--preset",
        "flight-test",
        "--aircraft",
        estimator_core::aircraft::AIRCRAFT.name,
    ])
    .arg("--seed")
    .arg(seed.to_string())
    .arg("--out")
    .arg(out);
    if let Some(v) = variant {
        cmd.arg("--aircraft-dir").arg(v);
    }
    ok(&mut cmd);
}

#[test]
fn calibration_reads_no_truth_and_finds_the_variants_scales() {
    let dir = tests::scratch(env!("CARGO_TARGET_TMPDIR"), "calibrate");
    let aircraft = variant_c(&dir);
    let ft = dir.join("ft");
    card(1, &ft, Some(&aircraft));
    let models: Vec<PathBuf> = (2..=5)
        .map(|seed| {
            let model = dir.join(format!("model-ft-seed{seed}"));
            card(seed, &model, None);
            model
        })
        .collect();
    let with_truth = calibration(&ft, &models, &dir.join("cal"));
    assert_eq!(
        with_truth["model_card_seeds"],
        serde_json::json!([2, 3, 4, 5])
    );

    // A model card that shares the flight test's sensor draws (here the flight test itself, seed
    // 1), or another card's, is refused, and nothing is written.
    let copy = dir.join("model-ft-seed2-copy");
    std::fs::create_dir_all(&copy).unwrap();
    for e in std::fs::read_dir(&models[0]).unwrap().flatten() {
        std::fs::copy(e.path(), copy.join(e.file_name())).unwrap();
    }
    for (cards, what) in [
        (vec![ft.clone()], "sensor seed 1 is the flight test's"),
        (
            vec![models[0].clone(), copy],
            "sensor seed 2 is that of the model card",
        ),
        (vec![models[0].clone(), models[0].clone()], "given twice"),
    ] {
        let out = dir.join("cal-refused");
        let o = calibrate(&ft, &cards, &out).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(what),
            "{cards:?}: {err}"
        );
        assert!(
            !out.exists(),
            "a refused calibration wrote {}",
            out.display()
        );
    }

    // The same dataset with every truth column deleted from every flight CSV.
    let stripped = dir.join("ft-no-truth");
    strip_truth(&ft, &stripped);
    let without = calibration(&stripped, &models, &dir.join("cal-no-truth"));
    assert_eq!(with_truth, without, "the calibration read a truth column");

    // Within 2 % (lift) and 5 % (side force, the flap terms, drag) of the truth, and the error
    // inside 2σ: C scales the whole lift axis, flaps included, the whole side axis, its sideslip
    // terms as much as its surface and rate terms, and the drag axis (its thrust is the model's),
    // and has no lift offset. A model without flap terms (the F-15) has no flap scale, one without
    // engines the evaluator reads no drag scale.
    let flap_terms = with_truth["flap_terms"].as_array().unwrap();
    assert!(
        !flap_terms.is_empty() || with_truth["scales"]["flap"].is_null(),
        "a flap scale without flap terms"
    );
    // The flap terms get their own scale exactly where they move 5 % of the lift.
    let ft = &with_truth["flight_test"];
    let apart = ft["structure"]["flap_apart"].as_bool().unwrap();
    assert_eq!(
        apart,
        ft["flap_share"].as_f64().is_some_and(|s| s >= 0.05),
        "{}",
        ft["flap_share"]
    );
    assert_eq!(with_truth["scales"]["flap"].is_null(), !apart);
    for (axis, truth, tolerance) in [
        ("lift", 0.94, 0.02),
        ("flap", 0.94, 0.05),
        ("sideslip", 1.10, 0.05),
        ("side_controls", 1.10, 0.05),
        ("drag", 1.10, 0.05),
    ] {
        let e = &with_truth["scales"][axis];
        if axis == "flap" && e.is_null() {
            continue;
        }
        if axis == "drag" && estimator_core::aero::ENGINE.is_none() {
            assert!(e.is_null(), "a drag scale without an engine deck: {e}");
            assert!(with_truth["scales"]["thrust"].is_null());
            continue;
        }
        let (k, se) = (
            e["value"].as_f64().unwrap(),
            e["std_error"].as_f64().unwrap(),
        );
        assert!(
            (k / truth - 1.0).abs() < tolerance,
            "{axis} scale {k}, truth {truth}"
        );
        assert!(
            (k - truth).abs() <= 2.0 * se,
            "{axis} scale {k} ± {se}: the 1σ does not cover the error to the truth {truth}"
        );
    }
    let offset = &with_truth["scales"]["offset"];
    let (o, se) = (
        offset["value"].as_f64().unwrap(),
        offset["std_error"].as_f64().unwrap(),
    );
    assert!(
        o.abs() < 0.005 && o.abs() <= 2.0 * se,
        "lift offset {o} ± {se}, truth 0"
    );
    // C has the model's stall: the lift over α, where the card's stall approach reached a knot
    // on the flight test and on the model card, is the lift scale's (1) within 2σ; the flight
    // test reaches at least the knot after the first (the description's `stall_knots_deg`).
    let knots = |scales: &serde_json::Value| -> Vec<(f64, f64)> {
        scales["stall"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|k| !k.is_null())
            .map(|k| {
                (
                    k["value"].as_f64().unwrap(),
                    k["std_error"].as_f64().unwrap(),
                )
            })
            .collect()
    };
    assert!(
        !knots(&with_truth["flight_test"]["scales"]).is_empty(),
        "the flight test reached no stall knot: {}",
        with_truth["flight_test"]["scales"]["stall"]
    );
    // Where the model card reached a knot too, the calibrated aircraft carries one.
    let calibrated = knots(&with_truth["scales"]);
    assert!(
        knots(&with_truth["model_card"]["scales"]).is_empty() || !calibrated.is_empty(),
        "no calibrated stall knot: {}",
        with_truth["scales"]["stall"]
    );
    for (v, se) in calibrated {
        assert!(
            (v - 1.0).abs() < 0.02 && (v - 1.0).abs() <= 2.0 * se,
            "lift over α {v} ± {se}, truth 1"
        );
    }
    // C has the model's CG and pitch moment: the CG shift is 0 and the pitch scale 1 within 2σ
    // (a 1σ below 0.5 in and 0.15: the F-16's are 0.06 in and 0.006, the F-15's 0.36 in and
    // 0.11), and the calibrated aircraft keeps the model's CG. A model without extracted moments
    // has neither.
    assert!(with_truth["applied_cg_shift_in"].is_null());
    if estimator_core::aero::MOMENTS.is_none() {
        for what in ["cg_aft_in", "pitch", "roll", "yaw"] {
            assert!(
                with_truth["scales"][what].is_null(),
                "{what} without moments"
            );
        }
        std::fs::remove_dir_all(&dir).ok();
        return;
    }
    let value = |what: &str| {
        let e = &with_truth["scales"][what];
        (
            e["value"].as_f64().unwrap(),
            e["std_error"].as_f64().unwrap(),
        )
    };
    let (cg, se) = value("cg_aft_in");
    assert!(
        se < 0.5 && cg.abs() <= 2.0 * se,
        "CG shift {cg} ± {se} in, truth 0"
    );
    let (k, se) = value("pitch");
    assert!(
        se < 0.15 && (k - 1.0).abs() <= 2.0 * se,
        "pitch scale {k} ± {se}, truth 1"
    );
    moment_cards(&dir, &dir.join("ft"), &models);
    std::fs::remove_dir_all(&dir).ok();
}

/// The roll and yaw moments and the side force over the card flown on the first calibrated
/// aircraft (`cal`'s aircraft.toml, with the scales it carries): the scales are the flight test's
/// over that card's fit divided by the carried scale, C's moments (the model's) come out 1 within
/// 2σ, and the other forces stay the model cards'. Moment cards without model cards, or without the first
/// calibration, are refused and nothing is written.
fn moment_cards(dir: &Path, ft: &Path, models: &[PathBuf]) {
    let cal = dir.join("cal");
    let aircraft = dir.join("first-aircraft");
    ok(Command::new(root().join("scripts/airframe-variant"))
        .arg(cal.join("aircraft.toml"))
        .args([
            "--model",
            estimator_core::aircraft::AIRCRAFT.jsbsim_model,
            "--out",
        ])
        .arg(&aircraft));
    let moments: Vec<PathBuf> = (2..=5)
        .map(|seed| {
            let card_dir = dir.join(format!("moment-ft-seed{seed}"));
            card(seed, &card_dir, Some(&aircraft));
            card_dir
        })
        .collect();
    let with_moment_cards = |cmd: &mut Command, first: bool| {
        for m in &moments {
            cmd.arg("--moment-flight-test").arg(m);
        }
        if first {
            cmd.arg("--first-calibration")
                .arg(cal.join("calibration.json"));
        }
    };
    let refused = dir.join("cal-moments-refused");
    for (models, first, what) in [
        (&[][..], true, "needs --model-flight-test"),
        (models, false, "--first-calibration"),
    ] {
        let mut cmd = calibrate(ft, models, &refused);
        with_moment_cards(&mut cmd, first);
        let o = cmd.output().unwrap();
        assert!(
            !o.status.success() && String::from_utf8_lossy(&o.stderr).contains(what),
            "{o:?}"
        );
        assert!(!refused.exists());
    }
    let out = dir.join("cal-moments");
    let mut cmd = calibrate(ft, models, &out);
    with_moment_cards(&mut cmd, true);
    ok(&mut cmd);
    let json = |p: PathBuf| -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
    };
    let (first, r) = (
        json(cal.join("calibration.json")),
        json(out.join("calibration.json")),
    );
    assert_eq!(r["moment_card_seeds"], serde_json::json!([2, 3, 4, 5]));
    assert_eq!(r["moment_cards"], 4);
    let v = |e: &serde_json::Value| e["value"].as_f64().unwrap();
    for (i, axis) in ["roll", "yaw"].into_iter().enumerate() {
        let carried = first["applied_moments"][i].as_f64().unwrap_or(1.0);
        assert_eq!(r["moment_card_carries"][axis].as_f64(), Some(carried));
        let (k, se) = (
            v(&r["scales"][axis]),
            r["scales"][axis]["std_error"].as_f64().unwrap(),
        );
        let over =
            v(&r["flight_test"]["scales"][axis]) / (v(&r["moment_card"]["scales"][axis]) / carried);
        assert!((k - over).abs() < 1e-12, "{axis}: {k}, not {over}");
        assert!(
            (k - 1.0).abs() <= 2.0 * se,
            "{axis} scale {k} ± {se}, truth 1"
        );
    }
    // The side force's two scales over the moment cards' bias too: each card's fit over the scale
    // the first aircraft carries (its identification's).
    for what in ["sideslip", "side_controls"] {
        let carried = v(&first["scales"][what]);
        assert_eq!(r["moment_card_carries"][what].as_f64(), Some(carried));
        let over =
            v(&r["flight_test"]["scales"][what]) / (v(&r["moment_card"]["scales"][what]) / carried);
        assert!((v(&r["scales"][what]) - over).abs() < 1e-12, "{what}");
        // C's side force is the model's × 1.10, both parts.
        let (k, se) = (
            v(&r["scales"][what]),
            r["scales"][what]["std_error"].as_f64().unwrap(),
        );
        assert!(
            (k / 1.10 - 1.0).abs() < 0.05 && (k - 1.10).abs() <= 2.0 * se,
            "{what} scale {k} ± {se}, truth 1.10"
        );
    }
    // The moments carried: each drawn toward 1 by the prior, 1 + w·(k − 1), w = τ²/(τ² + σ²).
    let tau = r["moment_prior_sd"].as_f64().unwrap();
    for (i, axis) in ["roll", "yaw"].into_iter().enumerate() {
        let (k, se) = (
            v(&r["scales"][axis]),
            r["scales"][axis]["std_error"].as_f64().unwrap(),
        );
        let shrunk = 1.0 + tau * tau / (tau * tau + se * se) * (k - 1.0);
        let applied = r["applied_moments"][i].as_f64().unwrap();
        assert!(
            (applied - shrunk).abs() < 1e-12,
            "{axis}: {applied}, not {shrunk}"
        );
    }
    // The rest stays the model cards' identification.
    for what in [
        "lift",
        "flap",
        "offset",
        "drag",
        "thrust",
        "pitch",
        "cg_aft_in",
        "stall",
    ] {
        assert_eq!(r["scales"][what], first["scales"][what], "{what}");
    }
}

/// A copy of the dataset `from` in `to` with every truth column deleted from every flight CSV.
fn strip_truth(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().flatten() {
        let p = e.path();
        let name = e.file_name().to_string_lossy().into_owned();
        let is_flight = name.ends_with(".csv") && !name.ends_with(".boom.csv");
        if !is_flight {
            std::fs::copy(&p, to.join(&name)).unwrap();
            continue;
        }
        let text = std::fs::read_to_string(&p).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let keep: Vec<usize> = (0..header.len())
            .filter(|&i| !hil_sim::flight::TRUTH_COLUMNS.contains(&header[i]))
            .collect();
        assert!(keep.len() < header.len(), "{name} had truth columns");
        let mut out = String::new();
        for l in std::iter::once(header.join(",")).chain(lines.map(str::to_string)) {
            let cells: Vec<&str> = l.split(',').collect();
            let row: Vec<&str> = keep.iter().map(|&i| cells[i]).collect();
            out.push_str(&row.join(","));
            out.push('\n');
        }
        std::fs::write(to.join(&name), out).unwrap();
    }
}

/// `trainer finetune` trains on the boom's air data, never on the truth: a small network
/// fine-tuned on variant C's flight test with and without its truth columns comes out the same,
/// bit for bit. A model saved without its float weights, and an --out that holds a model already,
/// are refused.
#[test]
fn finetune_reads_no_truth() {
    let air = estimator_core::aircraft::AIRCRAFT;
    let dir = tests::scratch(env!("CARGO_TARGET_TMPDIR"), "finetune");
    let aircraft = variant_c(&dir);
    let ft = dir.join("ft");
    let ci = dir.join("ci");
    card(1, &ft, Some(&aircraft));
    ok(Command::new(bin("hil-sim"))
        .args([
            "generate",
            "--preset",
            "ci",
            "--aircraft",
            air.name,
            "--out",
        ])
        .arg(&ci));
    // The targets are what the boom measured, corrected: against the simulator's truth (which a
    // test may read) α and β within a tenth of a degree on average, unbiased, and the cascades'
    // intermediate w and v within a few tenths of a metre per second. A sign error in the
    // rotation-induced flow (6 m of arm at pitch rates up to 0.3 rad/s) or an undone lag left in
    // place would show in the 99th percentile.
    let targets = trainer::finetune::boom_targets(&ft).unwrap();
    let mut err: [Vec<f64>; 4] = Default::default();
    let truth: std::collections::HashMap<String, hil_sim::flight::Flight> = std::fs::read_dir(&ft)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            let n = p.file_name().unwrap().to_string_lossy().into_owned();
            n.ends_with(".csv") && !n.ends_with(".boom.csv")
        })
        .map(|p| {
            let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
            (stem, hil_sim::dataset::Flight::read_log(&p).unwrap())
        })
        .collect();
    for fl in targets.train.iter().chain(&targets.val) {
        let name = fl.name.split('#').next().unwrap();
        let samples = &truth[name].samples;
        for (i, t) in fl.time_s.iter().enumerate() {
            let k = samples.partition_point(|s| s.time_s < *t - 1e-6);
            let s = &samples[k].truth;
            for (j, want) in [s.alpha_deg, s.beta_deg, s.w_aero_mps, s.v_aero_mps]
                .into_iter()
                .enumerate()
            {
                err[j].push(fl.truth[j][i] - want);
            }
        }
    }
    let stats = |e: &[f64]| {
        let mean = e.iter().sum::<f64>() / e.len() as f64;
        let mut a: Vec<f64> = e.iter().map(|x| x.abs()).collect();
        a.sort_by(f64::total_cmp);
        let mae = a.iter().sum::<f64>() / a.len() as f64;
        (mean, mae, a[a.len() * 99 / 100])
    };
    for (j, (what, mae_max, p99_max)) in [
        ("α, deg", 0.1, 0.4),
        ("β, deg", 0.1, 0.4),
        ("w, m/s", 0.4, 1.5),
        ("v, m/s", 0.4, 1.5),
    ]
    .into_iter()
    .enumerate()
    {
        let (mean, mae, p99) = stats(&err[j]);
        eprintln!(
            "boom targets against the truth, {what}: mean {mean:+.4}, MAE {mae:.4}, p99 {p99:.4}"
        );
        assert!(
            mae < mae_max && p99 < p99_max && mean.abs() < mae_max / 2.0,
            "{what}: mean {mean}, MAE {mae}, p99 {p99}"
        );
    }
    let model = dir.join("model");
    ok(Command::new(bin("trainer"))
        .args(["train", "--config", "small", "--epochs", "1", "--data"])
        .arg(&ci)
        .arg("--out")
        .arg(&model));
    let stripped = dir.join("ft-no-truth");
    strip_truth(&ft, &stripped);
    let finetune = |from: &Path, out: &Path| {
        let mut cmd = Command::new(bin("trainer"));
        cmd.args(["finetune", "--epochs", "2", "--model"])
            .arg(&model)
            .arg("--flight-test")
            .arg(from)
            .arg("--out")
            .arg(out);
        cmd
    };
    // What a fine-tuning wrote, but for the paths and command line its provenance names.
    let tuned = |from: &Path, out: &Path| {
        ok(&mut finetune(from, out));
        let mut m: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("model.json")).unwrap()).unwrap();
        m["provenance"] = serde_json::Value::Null;
        let mut s: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
        for k in ["flight_test", "command"] {
            s[k] = serde_json::Value::Null;
        }
        for a in ["alpha", "beta"] {
            s[a]["curves"]["epoch_s"] = serde_json::Value::Null;
        }
        (m, s)
    };
    let (with_truth, summary) = tuned(&ft, &dir.join("tuned"));
    assert!(
        summary["train_frames"].as_u64().unwrap() > 20_000,
        "{summary}"
    );
    assert_eq!(
        (with_truth, summary),
        tuned(&stripped, &dir.join("tuned-no-truth")),
        "the fine-tuning read a truth column"
    );
    // Refused, with what to do, and nothing written.
    let o = finetune(&ft, &dir.join("tuned")).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("holds a model.json already"),
        "{err}"
    );
    let old = dir.join("model-without-float");
    std::fs::create_dir_all(&old).unwrap();
    let mut m: serde_json::Value =
        serde_json::from_slice(&std::fs::read(model.join("model.json")).unwrap()).unwrap();
    for a in ["alpha", "beta"] {
        m[a].as_object_mut().unwrap().remove("float");
    }
    std::fs::write(old.join("model.json"), m.to_string()).unwrap();
    let out = dir.join("tuned-refused");
    let o = Command::new(bin("trainer"))
        .args(["finetune", "--model"])
        .arg(&old)
        .arg("--flight-test")
        .arg(&ft)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("retrain it"), "{err}");
    assert!(
        !out.exists(),
        "a refused fine-tuning wrote {}",
        out.display()
    );
    std::fs::remove_dir_all(&dir).ok();
}
