//! Chooses the generated files the crate compiles in.
//!
//! * Weights, in `src/model/mod.rs` ([`weights_file`]). Default: the build's aircraft's
//!   `src/model/NAME/weights.rs`, written by `trainer train --export` and committed; an aircraft without one has no model (`NO_MODEL`).
//!   `ESTIMATOR_WEIGHTS=/abs/path.rs` builds against another export (CI trains a small model and
//!   checks it end to end without touching the shipped weights).
//! * The estimate's 1σ weights, in `src/model/mod.rs`. Default: `src/model/NAME/sigma.rs`,
//!   written by `trainer fit-sigma` and committed; `ESTIMATOR_SIGMA=/abs/path.rs` builds against
//!   another fit. An aircraft without a fit gets `uncertainty::UNFITTED` (every estimate
//!   `UNCERTAIN`).
//! * The aircraft description, in `src/aircraft/mod.rs`: `src/aircraft/NAME.rs`, written by
//!   `scripts/gen-aircraft` from `aircraft/NAME.toml` and committed, for `ESTIMATOR_AIRCRAFT=NAME`
//!   (default `f16`).
//! * The filter's aerodynamic tables, in `src/aero/mod.rs`. Default: `src/aero/NAME_tables.rs` of
//!   the build's aircraft (`f16_tables.rs`), written by `scripts/extract-aero` from the JSBSim model
//!   its description names and committed.
//!   `ESTIMATOR_AERO=/abs/path/f16_tables.rs` builds against the tables of another aircraft
//!   directory (`scripts/calibrate` builds the calibrated estimator this way).
// Host build step, not flight code: a panic here is a failed build with a message.
#![allow(clippy::unwrap_used)]

use std::path::PathBuf;

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap());
    println!("cargo:rerun-if-changed=aircraft_name.rs");
    aircraft(&manifest);
    descriptions(&manifest);
    aero_tables(&manifest);
    sigma_weights(&manifest);
    filter_side_scale();
    filter_te_lift();
    let name = aircraft_name();
    println!("cargo::rustc-check-cfg=cfg(estimator_weights)");
    match weights_file(&manifest) {
        None => println!(
            "cargo:warning=no networks for the {name}: this build has no model (every estimate flags \
             NO_MODEL) until `trainer train --aircraft {name} --export` writes {} or ESTIMATOR_WEIGHTS \
             names one trained on its flights",
            committed_model_file(&manifest, "weights.rs").display()
        ),
        Some(path) => {
            // A file from before weights named their aircraft: say so, not a missing item.
            let text = std::fs::read_to_string(&path).unwrap();
            assert!(
                text.contains("pub const AIRCRAFT_NAME: &str"),
                "{} names no aircraft (`AIRCRAFT_NAME`): it was exported before weights named \
                 theirs; export it again with `trainer train --aircraft {name} --export`",
                path.display()
            );
            println!("cargo:rustc-cfg=estimator_weights");
            println!("cargo:rustc-env=ESTIMATOR_WEIGHTS_FILE={}", path.display());
        }
    }
}

/// `ESTIMATOR_FILTER_SIDE_SCALE=off` builds the air-data filter without its side-force scale
/// learning (`filter::CONFIG`: the seven-state filter), for networks trained with it; unset or
/// `on`, the shipped filter, which learns it where the aircraft's description says so
/// (`filter.learn_scales`, docs/filter.md).
fn filter_side_scale() {
    filter_switch("ESTIMATOR_FILTER_SIDE_SCALE", "off", "filter_no_side_scale");
}

/// `ESTIMATOR_FILTER_TE_LIFT=on` gives the air-data filter its ninth state, the trailing-edge lift
/// scale, whatever the description says (`filter.te_lift_sigma0` and `filter.te_lift_psd`, which
/// alone set its prior and random walk: both 0 hold it at 0): the build in which `scripts/test`
/// runs the state's own tests. `off` leaves it out whatever the description says (the eight-state
/// filter, to compare; the committed test vectors of a description that learns it do not hold
/// there). Unset, the description decides.
fn filter_te_lift() {
    filter_switch("ESTIMATOR_FILTER_TE_LIFT", "on", "filter_te_lift");
    filter_switch("ESTIMATOR_FILTER_TE_LIFT", "off", "filter_no_te_lift");
}

/// An on/off build switch of the filter: environment variable `var` set to `value` sets
/// `cfg(cfg)`; unset, `on` or `off` are the choices, anything else is a failed build.
fn filter_switch(var: &str, value: &str, cfg: &str) {
    println!("cargo:rerun-if-env-changed={var}");
    println!("cargo::rustc-check-cfg=cfg({cfg})");
    let v = std::env::var(var).unwrap_or_default();
    assert!(
        matches!(v.as_str(), "" | "on" | "off"),
        "{var} must be on or off, not `{v}`"
    );
    if v == value {
        println!("cargo:rustc-cfg={cfg}");
    }
}

/// `ESTIMATOR_SIGMA_FILE`: the estimate's 1σ weights `src/model/mod.rs` includes, the build's
/// aircraft's committed fit; without one, `cfg(estimator_no_sigma_fit)`: the crate's `UNFITTED`
/// weights, which make every estimate `UNCERTAIN`.
fn sigma_weights(manifest: &std::path::Path) {
    println!("cargo::rustc-check-cfg=cfg(estimator_no_sigma_fit)");
    let path = chosen(
        "ESTIMATOR_SIGMA",
        committed_model_file(manifest, "sigma.rs"),
        "a file written by trainer fit-sigma",
    );
    if path.is_file() {
        println!("cargo:rustc-env=ESTIMATOR_SIGMA_FILE={}", path.display());
    } else {
        println!("cargo:rustc-cfg=estimator_no_sigma_fit");
        println!(
            "cargo:warning=no 1σ fit for the {}: every estimate of this build is UNCERTAIN until \
             `trainer fit-sigma` writes {}",
            aircraft_name(),
            path.display()
        );
    }
}

/// `ESTIMATOR_AIRCRAFT_FILE`: the aircraft description `src/aircraft/mod.rs` includes,
/// `src/aircraft/NAME.rs` written by `scripts/gen-aircraft` from `aircraft/NAME.toml`, for
/// `ESTIMATOR_AIRCRAFT=NAME` (default `f16`; hil-sim's build reads the same variable).
fn aircraft(manifest: &std::path::Path) {
    let name = aircraft_name();
    let path = manifest.join("src/aircraft").join(format!("{name}.rs"));
    println!("cargo:rerun-if-changed={}", path.display());
    assert!(
        path.is_file(),
        "{} is missing: describe the aircraft in aircraft/{name}.toml and run scripts/gen-aircraft",
        path.display()
    );
    println!("cargo:rustc-env=ESTIMATOR_AIRCRAFT_FILE={}", path.display());
}

/// `ESTIMATOR_DESCRIPTIONS`: the names of every aircraft description generated into
/// `src/aircraft/` (`NAME.rs` of `aircraft/NAME.toml`), sorted and comma-separated, for a message
/// that names the aircraft this tree can be built for and for tests that need another one.
fn descriptions(manifest: &std::path::Path) {
    let dir = manifest.join("src/aircraft");
    println!("cargo:rerun-if-changed={}", dir.display());
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "rs"))
        .filter_map(|p| p.file_stem().and_then(|s| s.to_str()).map(str::to_string))
        .filter(|n| n != "mod")
        .collect();
    names.sort();
    println!("cargo:rustc-env=ESTIMATOR_DESCRIPTIONS={}", names.join(","));
}

include!("aircraft_name.rs");

/// The committed model of the build's aircraft: `estimator-core/src/model/NAME/FILE` (`weights.rs`
/// of `trainer train --export`, `sigma.rs` of `trainer fit-sigma`); `estimator_core` is the crate's
/// directory.
fn committed_model_file(estimator_core: &std::path::Path, file: &str) -> PathBuf {
    estimator_core
        .join("src/model")
        .join(aircraft_name())
        .join(file)
}

/// The networks the build compiles in: the file `ESTIMATOR_WEIGHTS` names, else the build's
/// aircraft's committed `weights.rs` if it has one, else none (the build flags `NO_MODEL`): a
/// build never takes another airframe's networks.
fn weights_file(estimator_core: &std::path::Path) -> Option<PathBuf> {
    let path = chosen(
        "ESTIMATOR_WEIGHTS",
        committed_model_file(estimator_core, "weights.rs"),
        "a weights file written by trainer train --export",
    );
    path.is_file().then_some(path)
}

/// The file the variable `var` names, or `default`; rebuilt when either changes (or appears). A
/// file asked for by name must exist (a failed build, not a build without it); `what` says what it should be.
fn chosen(var: &str, default: PathBuf, what: &str) -> PathBuf {
    println!("cargo:rerun-if-env-changed={var}");
    let path = match std::env::var_os(var) {
        Some(p) if !p.is_empty() => {
            let p = PathBuf::from(p);
            assert!(
                p.is_absolute() && p.is_file(),
                "{var}: {} is not an absolute path to {what}",
                p.display()
            );
            p
        }
        _ => default,
    };
    // A committed file that is not there yet (an aircraft without its own model): watch the
    // nearest folder that is, so that the build notices the file when it comes.
    let watched = path
        .ancestors()
        .find(|p| p.exists())
        .unwrap_or(&path)
        .to_path_buf();
    println!("cargo:rerun-if-changed={}", watched.display());
    path
}

/// `ESTIMATOR_AERO_FILE`: the tables `src/aero/mod.rs` includes. A missing file is a failed build
/// (the filter has no model without them), with the variable named.
fn aero_tables(manifest: &std::path::Path) {
    let name = aircraft_name();
    required(
        manifest,
        "ESTIMATOR_AERO",
        &format!("src/aero/{name}_tables.rs"),
        "a file written by scripts/extract-aero",
        "run scripts/extract-aero",
    );
}

/// A generated file the crate cannot build without: [`chosen`] by `var` or the committed
/// `default`, which must exist too (`remedy` says how to make it); its path goes to `var`_FILE.
fn required(manifest: &std::path::Path, var: &str, default: &str, what: &str, remedy: &str) {
    let path = chosen(var, manifest.join(default), what);
    assert!(path.is_file(), "{} is missing: {remedy}", path.display());
    println!("cargo:rustc-env={var}_FILE={}", path.display());
}
