//! Mirrors estimator-core's build script: `cfg(trainer_has_model)` when the weights file that
//! estimator-core compiles in exists (and, without `ESTIMATOR_WEIGHTS`, when the build is for the
//! aircraft whose networks are committed), so `trainer eval` can print its PROVENANCE.
use std::path::PathBuf;

include!("../estimator-core/aircraft_name.rs");

fn main() {
    println!("cargo:rerun-if-changed=../estimator-core/aircraft_name.rs");
    println!("cargo:rerun-if-env-changed=ESTIMATOR_WEIGHTS");
    println!("cargo::rustc-check-cfg=cfg(trainer_has_model)");
    let default = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap_or_default())
        .join("../estimator-core/src/model/weights.rs");
    let path = match std::env::var_os("ESTIMATOR_WEIGHTS") {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ if aircraft_name() != DEFAULT_AIRCRAFT => return,
        _ => default,
    };
    println!("cargo:rerun-if-changed={}", path.display());
    if path.is_file() {
        println!("cargo:rustc-cfg=trainer_has_model");
    }
}
