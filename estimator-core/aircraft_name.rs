// The build's aircraft, for the build scripts of estimator-core, hil-sim and the trainer (all
// `include!` this file, so the crates always read the same variables the same way).

/// The aircraft a build is for when `ESTIMATOR_AIRCRAFT` is not set, and the one whose networks,
/// 1σ weights and test vectors are committed (`estimator-core/src/model/weights.rs`, `sigma.rs`,
/// `tests/vectors/shipped.txt`): a build for another aircraft compiles no model unless
/// `ESTIMATOR_WEIGHTS` names that aircraft's own, so an estimate is never computed with another
/// airframe's networks.
#[allow(dead_code)]
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

/// The networks the build compiles in: the file `ESTIMATOR_WEIGHTS` names, else the `committed`
/// one when the build is for [`DEFAULT_AIRCRAFT`], else none: another airframe's build takes no
/// committed networks.
#[allow(dead_code)]
fn weights_file(committed: std::path::PathBuf) -> Option<std::path::PathBuf> {
    let named = std::env::var_os("ESTIMATOR_WEIGHTS").is_some_and(|p| !p.is_empty());
    if !named && aircraft_name() != DEFAULT_AIRCRAFT {
        println!("cargo:rerun-if-env-changed=ESTIMATOR_WEIGHTS");
        return None;
    }
    Some(chosen(
        "ESTIMATOR_WEIGHTS",
        committed,
        "a weights file written by trainer train --export",
    ))
}

/// The file the variable `var` names, or `default`; rebuilt when either changes. A file asked for
/// by name must exist (a failed build, not a build without it); `what` says what it should be.
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
    println!("cargo:rerun-if-changed={}", path.display());
    path
}
