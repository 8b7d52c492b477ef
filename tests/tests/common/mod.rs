//! What several cross-crate tests share.

use std::path::PathBuf;

/// The first 150 s of the build's aircraft's stock 20-minute test flight
/// (`flights/NAME_test_flight.xml`), flown by hil-sim with sensor seed 1, exactly as `hil-sim run
/// --script … --max-time-s 150` flies it.
pub fn first_150_s_of_the_test_flight() -> hil_sim::flight::Flight {
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!(
        "../flights/{}_test_flight.xml",
        estimator_core::aircraft::AIRCRAFT.name
    ));
    let source = hil_sim::runner::cli::Source {
        dataset: None,
        script: Some(script),
    };
    hil_sim::runner::cli::flight(&source, 1, Some(150.0)).expect("fly the test flight")
}
