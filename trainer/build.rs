//! Mirrors estimator-core's build script: `cfg(trainer_has_model)` when estimator-core compiles
//! networks in (`weights_file`, shared with it), so `trainer eval` can print their PROVENANCE.
use std::path::PathBuf;

include!("../estimator-core/aircraft_name.rs");

fn main() {
    println!("cargo:rerun-if-changed=../estimator-core/aircraft_name.rs");
    println!("cargo::rustc-check-cfg=cfg(trainer_has_model)");
    let estimator_core = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap_or_default())
        .join("../estimator-core");
    if weights_file(&estimator_core).is_some() {
        println!("cargo:rustc-cfg=trainer_has_model");
    }
}
