//! Chooses the weights file that `src/model/mod.rs` compiles in.
//!
//! Default: `src/model/weights.rs`, written by `trainer train` and committed. `ESTIMATOR_WEIGHTS=/abs/path.rs`
//! builds against another export (CI trains a small model and checks it end to end without touching the
//! shipped weights).
// Host build step, not flight code: a panic here is a failed build with a message.
#![allow(clippy::unwrap_used)]

use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-env-changed=ESTIMATOR_WEIGHTS");
    let default =
        PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap()).join("src/model/weights.rs");
    let path = match std::env::var_os("ESTIMATOR_WEIGHTS") {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ => default,
    };
    println!("cargo:rerun-if-changed={}", path.display());
    println!("cargo::rustc-check-cfg=cfg(estimator_weights)");
    if path.is_file() {
        println!("cargo:rustc-cfg=estimator_weights");
        println!("cargo:rustc-env=ESTIMATOR_WEIGHTS_FILE={}", path.display());
    } else {
        println!(
            "cargo:warning=no estimator weights at {} yet: the crate builds without a shipped model \
             (run `trainer train` to write one)",
            path.display()
        );
    }
}
