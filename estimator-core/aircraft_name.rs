// The build's aircraft, for the build scripts of estimator-core, hil-sim and the trainer (all
// `include!` this file, so the crates always read the same variables the same way).

/// The aircraft a build is for when `ESTIMATOR_AIRCRAFT` is not set.
const DEFAULT_AIRCRAFT: &str = "f16";

/// The build's aircraft: `ESTIMATOR_AIRCRAFT` (default [`DEFAULT_AIRCRAFT`]), a name as in
/// `aircraft/NAME.toml`.
fn aircraft_name() -> String {
    println!("cargo:rerun-if-env-changed=ESTIMATOR_AIRCRAFT");
    let name = std::env::var("ESTIMATOR_AIRCRAFT").unwrap_or_default();
    let name = if name.is_empty() {
        DEFAULT_AIRCRAFT.to_string()
    } else {
        name
    };
    assert!(
        name.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-'),
        "ESTIMATOR_AIRCRAFT must name an aircraft (aircraft/NAME.toml), not `{name}`"
    );
    name
}

/// The committed model of the build's aircraft: `estimator-core/src/model/NAME/FILE` (`weights.rs`
/// of `trainer train --export`, `sigma.rs` of `trainer fit-sigma`); `estimator_core` is the crate's
/// directory.
#[allow(dead_code)]
fn committed_model_file(estimator_core: &std::path::Path, file: &str) -> std::path::PathBuf {
    estimator_core
        .join("src/model")
        .join(aircraft_name())
        .join(file)
}

/// The networks the build compiles in: the file `ESTIMATOR_WEIGHTS` names, else the build's
/// aircraft's committed `weights.rs` if it has one, else none (the build flags `NO_MODEL`): a
/// build never takes another airframe's networks.
#[allow(dead_code)]
fn weights_file(estimator_core: &std::path::Path) -> Option<std::path::PathBuf> {
    let path = chosen(
        "ESTIMATOR_WEIGHTS",
        committed_model_file(estimator_core, "weights.rs"),
        "a weights file written by trainer train --export",
    );
    path.is_file().then_some(path)
}

/// The file the variable `var` names, or `default`; rebuilt when either changes (or appears). A
/// file asked for by name must exist (a failed build, not a build without it); `what` says what it should be.
#[allow(dead_code)]
fn chosen(var: &str, default: std::path::PathBuf, what: &str) -> std::path::PathBuf {
    println!("cargo:rerun-if-env-changed={var}");
    let path = match std::env::var_os(var) {
        Some(p) if !p.is_empty() => {
            let p = std::path::PathBuf::from(p);
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
