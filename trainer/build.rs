//! Mirrors estimator-core's build script: `cfg(trainer_has_model)` when estimator-core compiles
//! networks in (`weights_file`, shared with it), so `trainer eval` can print their PROVENANCE.
use std::path::PathBuf;

include!("../estimator-core/aircraft_name.rs");

fn main() {
    println!("cargo:rerun-if-changed=../estimator-core/aircraft_name.rs");
    println!("cargo::rustc-check-cfg=cfg(trainer_has_model)");
    let committed = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap_or_default())
        .join("../estimator-core/src/model/weights.rs");
    if weights_file(committed).is_some_and(|p| p.is_file()) {
        println!("cargo:rustc-cfg=trainer_has_model");
    }
}
