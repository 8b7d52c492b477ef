// The build's aircraft, for the build scripts of estimator-core and hil-sim (both `include!` this
// file, so the two crates always read the same variable the same way).

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
