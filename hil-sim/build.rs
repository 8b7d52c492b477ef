//! Picks the maneuver generator's profiles of the aircraft this build is for:
//! `src/maneuver/NAME.rs`, written by `scripts/gen-aircraft` from `aircraft/NAME.toml`, for
//! `ESTIMATOR_AIRCRAFT=NAME` (default `f16`), the variable estimator-core's build reads for the
//! rest of the description, so the two crates are always built for the same aircraft.
// Host build step, not flight code: a panic here is a failed build with a message.
#![allow(clippy::unwrap_used)]

use std::path::PathBuf;

include!("../estimator-core/aircraft_name.rs");

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap());
    println!("cargo:rerun-if-changed=../estimator-core/aircraft_name.rs");
    let name = aircraft_name();
    // The build's target directory (OUT_DIR is DIR/PROFILE/build/hil-sim-HASH/out), where
    // `cargo fw` of the same build puts the flight image of the same aircraft.
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap());
    let target_dir = out.ancestors().nth(4).unwrap();
    println!("cargo:rustc-env=HIL_TARGET_DIR={}", target_dir.display());
    let path = manifest.join("src/maneuver").join(format!("{name}.rs"));
    println!("cargo:rerun-if-changed={}", path.display());
    assert!(
        path.is_file(),
        "{} is missing: describe the aircraft in aircraft/{name}.toml and run scripts/gen-aircraft",
        path.display()
    );
    // Both halves of the description must come from the same aircraft/NAME.toml: their first
    // lines name it with its sha256.
    let core = manifest
        .join("../estimator-core/src/aircraft")
        .join(format!("{name}.rs"));
    println!("cargo:rerun-if-changed={}", core.display());
    let head = |p: &std::path::Path| {
        std::fs::read_to_string(p)
            .ok()
            .and_then(|t| t.lines().next().map(str::to_string))
    };
    assert!(
        head(&path).is_some() && head(&path) == head(&core),
        "{} and {} were not generated from the same description: run scripts/gen-aircraft",
        path.display(),
        core.display()
    );
    println!("cargo:rustc-env=HIL_PROFILES_FILE={}", path.display());
}
