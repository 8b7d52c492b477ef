//! An aircraft description (`aircraft/NAME.toml`, docs/aircraft.md) is checked before it becomes
//! code: `scripts/gen-aircraft --validate` accepts the F-16's and refuses each kind of mistake with
//! a non-zero exit and a message that names the key; the build's aircraft is the description's.

// Host test code: the flight-code lints of `[workspace.lints]` do not apply (a panic is how it fails).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// `scripts/gen-aircraft --validate` on `text`: exit success and stderr.
fn validate(text: &str, name: &str) -> (bool, String) {
    let dir = tests::scratch(env!("CARGO_TARGET_TMPDIR"), &format!("gen-aircraft-{name}"));
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, text).unwrap();
    let o = Command::new(root().join("scripts/gen-aircraft"))
        .arg("--validate")
        .arg(&file)
        .output()
        .expect("run scripts/gen-aircraft");
    let _ = std::fs::remove_file(&file);
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn descriptions_are_validated_key_by_key() {
    let f16 = std::fs::read_to_string(root().join("aircraft/f16.toml")).unwrap();
    let (ok, err) = validate(&f16, "f16");
    assert!(ok, "the shipped F-16 description is refused: {err}");
    // (edit, what the message must name)
    let cases: [(&str, &str, &str); 35] = [
        (
            "throttle_properties = [\"fcs/throttle-cmd-norm\"]",
            "throttle_properties = [\"fcs/throttle cmd\"]",
            "propulsion.throttle_properties[0] = 'fcs/throttle cmd' is not a JSBSim property path",
        ),
        (
            "low_fuel_per_tank_lb = 300.0",
            "low_fuel_per_tank_lb = 700.0",
            "ood.low_fuel_per_tank_lb 700.0 must be at least 0 and below the profiles' lowest fuel per tank (600.0)",
        ),
        (
            "turbulence_severity = 7\n",
            "turbulence_severity = 8\n",
            "ood.turbulence_severity: JSBSim's turbulence severity is 0..=7",
        ),
        (
            "fuel_per_tank_lb = 1800.0",
            "fuel_per_tank_lb = 4000.0",
            "is more than a tank holds",
        ),
        (
            "gear_norm = 1.0",
            "gear_norm = 2.0",
            "mass.gear_norm must be within 0..=1",
        ),
        (
            "external_tanks = [2, 3]",
            "external_tanks = [1, 3]",
            "name a tank twice",
        ),
        (
            "boom_arm_m = 6.0",
            "boom_arm = 6.0",
            "missing boom_arm_m; unknown boom_arm",
        ),
        (
            "ceiling_ft = 45000.0\n",
            "",
            "profiles.base: missing ceiling_ft",
        ),
        (
            "max_nz_g = 8.0",
            "max_nzz_g = 8.0",
            "profiles.aggressive: unknown max_nzz_g",
        ),
        (
            "init_vc_kts = [350.0, 550.0]",
            "init_vc_kts = [550.0, 350.0]",
            "init_vc_kts: low 550.0 is above high 350.0",
        ),
        (
            "[profiles.gentle]",
            "[profiles.gentel]",
            "missing gentle; unknown gentel",
        ),
        (
            "mach_lef_rad = -0.0349",
            "mach_lef = -0.0349",
            "lef_schedule: missing mach_lef_rad; unknown mach_lef",
        ),
        ("[fcs.flaperon_mix]", "[fcs.flaperons]", "unknown flaperons"),
        (
            "g_protect_per_g = 0.6\n",
            "",
            "control_laws: missing g_protect_per_g",
        ),
        (
            "elevator_deg = { property",
            "elevator = { property",
            "surfaces: missing elevator_deg; unknown elevator",
        ),
        (
            "speedbrake_deg = { property",
            "airbrake_deg = { property",
            "surfaces: unknown airbrake_deg",
        ),
        (
            "stall_knots_deg = [10.0, 13.0, 16.0, 19.0, 22.0]",
            "stall_knots_deg = [10.0, 13.0, 16.0, 22.0, 19.0]",
            "calibration.stall_knots_deg is 5 increasing angles within (0, 25.0] deg",
        ),
        (
            "flap_share = 0.0",
            "flap_share = 0.3",
            "profiles.base.flap_share is 0.3 but the description has no [flaps]",
        ),
        (
            "pilot_pointmass = 0",
            "pilot_pointmass = \"0\"",
            "pilot_pointmass must be an index",
        ),
        ("learn_scales = true\n", "", "filter: missing learn_scales"),
        (
            "config = \"medium-wide-beta\"\n",
            "",
            "estimator: missing config",
        ),
        (
            "config = \"medium-wide-beta\"\n",
            "config = \"medium wide\"\n",
            "estimator.config = 'medium wide' may hold only letters, digits, '_' and '-'",
        ),
        (
            "learn_scales = true\n",
            "learn_scales = 1\n",
            "filter.learn_scales must be a bool, not 1",
        ),
        (
            "mean_wind_down_sigma_mps = 0.05\n",
            "mean_wind_down_sigma_mps = 0.0\n",
            "filter.mean_wind_down_sigma_mps must be above 0, not 0.0",
        ),
        (
            "mean_wind_down_psd = 1e-6\n",
            "mean_wind_down_psd = -1e-6\n",
            "filter.mean_wind_down_psd must be 0 or above, not -1e-06",
        ),
        (
            "mean_wind_down_psd = 1e-6\n",
            "",
            "filter: missing mean_wind_down_psd",
        ),
        (
            "te_lift_sigma0 = 0.05\n",
            "te_lift_sigma0 = -0.05\n",
            "filter.te_lift_sigma0 must be at least 0 (0 holds the trailing-edge lift scale at the model's), not -0.05",
        ),
        (
            "te_lift_sigma0 = 0.05\n",
            "te_lift_sigma0 = 1e30\n",
            "filter.te_lift_sigma0 must be at most 0.5 (the filter restarts when the scale leaves ±0.5), not 1e+30",
        ),
        (
            "te_lift_psd = 0.0\n",
            "te_lift_psd = -1e-6\n",
            "filter.te_lift_psd must be at least 0 (0 makes the trailing-edge lift scale a constant), not -1e-06",
        ),
        (
            "te_lift_psd = 0.0\n",
            "te_lift_psd = 1.0\n",
            "filter.te_lift_psd must be at most 1e-3 (1/s; s's 1σ would grow by 0.3 in 100 s), not 1.0",
        ),
        (
            "kinematic_gate_mps2 = 2.0\n",
            "",
            "filter: missing kinematic_gate_mps2",
        ),
        (
            "kinematic_gate_mps2 = 2.0\n",
            "kinematic_gate_mps2 = \"26\"\n",
            "filter.kinematic_gate_mps2 must be a number, not '26'",
        ),
        (
            "kinematic_gate_mps2 = 2.0\n",
            "kinematic_gate_mps2 = -1.0\n",
            "filter.kinematic_gate_mps2 must be at least 0 (0 turns the kinematic check off), not -1.0",
        ),
        (
            "gyro_gate_rps = 0.06\n",
            "",
            "filter: missing gyro_gate_rps",
        ),
        (
            "gyro_gate_rps = 0.06\n",
            "gyro_gate_rps = -0.1\n",
            "filter.gyro_gate_rps must be at least 0 (0 turns the gyro check off), not -0.1",
        ),
    ];
    for (from, to, says) in cases {
        assert!(
            f16.contains(from),
            "the F-16 description no longer has `{from}`"
        );
        let (ok, err) = validate(&f16.replacen(from, to, 1), "f16");
        assert!(!ok, "`{from}` -> `{to}` was accepted");
        assert!(err.contains(says), "`{from}` -> `{to}`: {err}");
    }
    // An airframe without external tanks (internal fuel only) is a valid description.
    let (ok, err) = validate(
        &f16.replacen("external_tanks = [2, 3]", "external_tanks = []", 1),
        "f16",
    );
    assert!(ok, "no external tanks refused: {err}");
    // Nor is one without a leading-edge flap, flaperons or speedbrake (their channels carry 0).
    let mut bare = f16.clone();
    for line in [
        "lef_deg = {",
        "tef_deg = {",
        "flaperon_deg = {",
        "speedbrake_deg = {",
    ] {
        let start = bare.find(line).unwrap();
        let end = start + bare[start..].find('\n').unwrap() + 1;
        bare.replace_range(start..end, "");
    }
    let (ok, err) = validate(&bare, "f16");
    assert!(
        ok,
        "a description with only the primary controls refused: {err}"
    );
    // A pilot-set flap: valid with its settings within (0, 1], refused outside.
    let flaps = format!(
        "{}\n[flaps]\ncommand_property = \"fcs/flap-cmd-norm\"\nsettings = [0.5, 1.0]\nmax_vc_kts = 200.0\nretract_band_kts = 5.0\n",
        f16.replacen("flap_share = 0.0", "flap_share = 0.3", 1)
    );
    let (ok, err) = validate(&flaps, "f16");
    assert!(ok, "a description with [flaps] refused: {err}");
    let (ok, err) = validate(
        &flaps.replacen("settings = [0.5, 1.0]", "settings = [0.5, 1.5]", 1),
        "f16",
    );
    assert!(
        !ok && err.contains("flaps.settings are flap commands within (0, 1]"),
        "{err}"
    );
    // Every shipped description is valid.
    for entry in std::fs::read_dir(root().join("aircraft")).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_stem().unwrap().to_str().unwrap().to_string();
        let (ok, err) = validate(&std::fs::read_to_string(&path).unwrap(), &name);
        assert!(ok, "{}: {err}", path.display());
    }
}

#[test]
fn the_build_is_for_the_f16_description() {
    let a = estimator_core::aircraft::AIRCRAFT;
    assert_eq!((a.name, a.jsbsim_model), ("f16", "f16"));
    assert_eq!(a.mass.internal_fuel_capacity_lb(), 6_972.0);
    assert_eq!(a.flight_test_points.len(), 3);
    // The maneuver generator's envelope is the description's too.
    let p = hil_sim::maneuver::Profile::preset(hil_sim::maneuver::ProfileKind::HighAlpha);
    assert_eq!(
        (p.max_alpha_deg, p.min_vc_kts, p.ceiling_ft),
        (31.0, 90.0, 45_000.0)
    );
}

/// Every frame names its aircraft by the CRC-32 of the description's name (`wire::aircraft_tag`):
/// docs/architecture.md gives each description's tag, and the build lists every description.
#[test]
fn every_description_has_the_tag_the_docs_give() {
    let doc = std::fs::read_to_string(root().join("docs/architecture.md")).unwrap();
    let names: Vec<&str> = estimator_core::aircraft::descriptions().collect();
    let mut files: Vec<String> = std::fs::read_dir(root().join("aircraft"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| p.file_stem().unwrap().to_str().unwrap().to_string())
        .collect();
    files.sort();
    assert_eq!(
        names, files,
        "aircraft/*.toml against the generated descriptions"
    );
    for name in names {
        let tag = estimator_core::wire::aircraft_tag(name);
        let said = format!("`{name}` 0x{tag:08X}");
        assert!(doc.contains(&said), "docs/architecture.md lacks {said}");
    }
}

/// The `[estimator]` string `key` of aircraft/NAME.toml, the aircraft's weights.rs path and its
/// text (None for an aircraft without shipped networks yet).
fn estimator_setting_and_weights(name: &str, key: &str) -> (String, PathBuf, Option<String>) {
    let toml = std::fs::read_to_string(root().join(format!("aircraft/{name}.toml"))).unwrap();
    let prefix = format!("{key} = \"");
    let value = toml
        .lines()
        .find_map(|l| l.strip_prefix(prefix.as_str()))
        .and_then(|l| l.strip_suffix('"'))
        .unwrap_or_else(|| panic!("aircraft/{name}.toml has no estimator.{key}"))
        .to_string();
    let weights = root().join(format!("estimator-core/src/model/{name}/weights.rs"));
    let code = std::fs::read_to_string(&weights).ok();
    (value, weights, code)
}

/// Each aircraft's committed networks were trained with the feature set its description ships
/// (`estimator.features`, `trainer train`'s default in its build): the export's PROVENANCE names
/// the set, and the set is one the trainer knows.
#[test]
fn every_aircraft_ships_networks_of_its_descriptions_feature_set() {
    for name in estimator_core::aircraft::descriptions() {
        let (set, weights, code) = estimator_setting_and_weights(name, "features");
        trainer::features::FeatureSet::parse(&set)
            .unwrap_or_else(|e| panic!("aircraft/{name}.toml: estimator.features {set:?}: {e}"));
        let Some(code) = code else {
            continue; // an aircraft without shipped networks yet
        };
        assert!(
            code.contains(&format!("features: {set};")),
            "{} was not trained with {name}'s estimator.features {set:?}",
            weights.display()
        );
    }
}

#[test]
fn every_aircraft_ships_networks_of_its_descriptions_sizes() {
    use trainer::pipeline::Size;
    use trainer::prep::Angle;
    for name in estimator_core::aircraft::descriptions() {
        let (config, weights, code) = estimator_setting_and_weights(name, "config");
        let size = Size::parse(&config).unwrap_or_else(|| {
            panic!("aircraft/{name}.toml: estimator.config {config:?} is no size")
        });
        let Some(code) = code else {
            continue; // an aircraft without shipped networks yet
        };
        for (angle, symbol) in [(Angle::Alpha, "α"), (Angle::Beta, "β")] {
            let widths: Vec<String> = size.hidden(angle).iter().map(|w| w.to_string()).collect();
            let want = format!("hidden {} per part", widths.join("-"));
            let line = code
                .lines()
                .find(|l| l.starts_with(&format!("/// {symbol} cascade:")))
                .unwrap_or_else(|| panic!("{} has no {symbol} cascade line", weights.display()));
            assert!(
                line.contains(&want),
                "{}: {line:?} is not {name}'s estimator.config {config:?} ({want})",
                weights.display()
            );
        }
    }
}
