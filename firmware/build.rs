//! Puts the workspace root (where `memory.x` lives) on the linker search path, only for the
//! Cortex-M4F image: the host build of this crate is a plain library and links nothing special.
use std::path::PathBuf;

fn main() {
    let target = std::env::var("TARGET").unwrap_or_default();
    if target.starts_with("thumbv7em") {
        let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap_or_default());
        let root = manifest.parent().map(PathBuf::from).unwrap_or(manifest);
        println!("cargo:rustc-link-search={}", root.display());
        println!("cargo:rerun-if-changed={}", root.join("memory.x").display());
    }
    println!("cargo:rerun-if-changed=build.rs");
}
