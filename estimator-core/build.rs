//! Chooses the generated files the crate compiles in.
//!
//! * Weights, in `src/model/mod.rs` (`weights_file` in `aircraft_name.rs`, shared with the
//!   trainer's build). Default: `src/model/weights.rs`, written by `trainer train` and committed,
//!   for `DEFAULT_AIRCRAFT` only: another aircraft's build has no model.
//!   `ESTIMATOR_WEIGHTS=/abs/path.rs` builds against another export (CI trains a small model and
//!   checks it end to end without touching the shipped weights).
//! * The estimate's 1σ weights, in `src/model/mod.rs`. Default: `src/model/sigma.rs`, written by
//!   `trainer fit-sigma` and committed; `ESTIMATOR_SIGMA=/abs/path.rs` builds against another fit.
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
    aero_tables(&manifest);
    sigma_weights(&manifest);
    filter_side_scale();
    let name = aircraft_name();
    println!("cargo:rustc-env=ESTIMATOR_DEFAULT_AIRCRAFT={DEFAULT_AIRCRAFT}");
    println!("cargo:rustc-env=ESTIMATOR_BUILD_AIRCRAFT={name}");
    println!("cargo::rustc-check-cfg=cfg(estimator_weights)");
    match weights_file(manifest.join("src/model/weights.rs")) {
        None => println!(
            "cargo:warning=the committed networks are the {DEFAULT_AIRCRAFT}'s: this {name} build has \
             no model (it flags NO_MODEL) until ESTIMATOR_WEIGHTS names one trained on its flights"
        ),
        Some(path) if path.is_file() => {
            println!("cargo:rustc-cfg=estimator_weights");
            println!("cargo:rustc-env=ESTIMATOR_WEIGHTS_FILE={}", path.display());
        }
        Some(path) => println!(
            "cargo:warning=no estimator weights at {} yet: the crate builds without a shipped model \
             (run `trainer train` to write one)",
            path.display()
        ),
    }
}

/// `ESTIMATOR_FILTER_SIDE_SCALE=off` builds the air-data filter without its side-force scale
/// learning (`filter::CONFIG`: the seven-state filter), for networks trained with it; unset or
/// `on`, the shipped filter, which learns it (docs/filter.md). Anything else is a failed build.
fn filter_side_scale() {
    println!("cargo:rerun-if-env-changed=ESTIMATOR_FILTER_SIDE_SCALE");
    println!("cargo::rustc-check-cfg=cfg(filter_no_side_scale)");
    let v = std::env::var("ESTIMATOR_FILTER_SIDE_SCALE").unwrap_or_default();
    assert!(
        matches!(v.as_str(), "" | "on" | "off"),
        "ESTIMATOR_FILTER_SIDE_SCALE must be on or off, not `{v}`"
    );
    if v == "off" {
        println!("cargo:rustc-cfg=filter_no_side_scale");
    }
}

/// `ESTIMATOR_SIGMA_FILE`: the estimate's 1σ weights `src/model/mod.rs` includes. Committed;
/// a missing file is a failed build (every estimate carries a 1σ).
fn sigma_weights(manifest: &std::path::Path) {
    required(
        manifest,
        "ESTIMATOR_SIGMA",
        "src/model/sigma.rs",
        "a file written by trainer fit-sigma",
        "run scripts/fit-sigma (or git checkout it)",
    );
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

include!("aircraft_name.rs");

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
