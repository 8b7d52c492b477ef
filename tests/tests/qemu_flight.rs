//! The shipped estimator in QEMU and on the host, bit for bit with its flags, on two flights: the
//! first 150 s of the stock test flight (the paths the trainer's short vector runs never reach,
//! the air-data filter after a minute of flight), and 150 s of a gentle flight 15 % lighter than
//! any trained (the `mass-low` case of the `ood` preset), where the filter's α stands in for the α
//! network out of its envelope (`ALPHA_FROM_FILTER`). Needs
//! `cargo fw` and qemu-system-arm (`scripts/bootstrap` + `cargo fw`; `scripts/test` builds the
//! image before the tests). Without them it fails with the command to run, never skips.

// Host test code: the flight-code lints of `[workspace.lints]` do not apply (a panic is how it fails).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

use estimator_core::Flags;
use hil_sim::maneuver;
use hil_sim::runner::target::default_elf;
use hil_sim::runner::{self, InProcess, Qemu, QemuLink, RunConfig};

/// Flies `flight` on the host and in QEMU; asserts every estimate equal and returns how many
/// took α from the filter.
fn host_and_qemu_agree(flight: &hil_sim::flight::Flight) -> usize {
    let samples = runner::samples_of(flight);
    let cfg = RunConfig::default();
    let host = runner::run(&mut InProcess::new(), &samples, &cfg).unwrap();
    let mut q = Qemu::start("qemu-system-arm", &default_elf(), QemuLink::Semihost).unwrap();
    let qemu = runner::run(&mut q, &samples, &cfg).unwrap();
    assert_eq!(host.records.len(), qemu.records.len());
    let mut from_filter = 0;
    for (h, q) in host.records.iter().zip(&qemu.records) {
        let (h, q) = (
            h.reply.expect("host answered").estimate,
            q.reply.expect("QEMU answered").estimate,
        );
        assert_eq!(h, q, "seq {}", h.seq);
        if q.flags.has(Flags::ALPHA_FROM_FILTER) {
            from_filter += 1;
        }
    }
    from_filter
}

#[test]
fn the_flight_image_in_qemu_answers_the_test_flight_as_the_host_does() {
    host_and_qemu_agree(&common::first_150_s_of_the_test_flight());
}

#[test]
fn the_flight_image_in_qemu_takes_alpha_from_the_filter_as_the_host_does() {
    let dir = tests::scratch(env!("CARGO_TARGET_TMPDIR"), "qemu-flight-mass-low");
    let m = maneuver::generate_case(
        &maneuver::Profile::preset(maneuver::ProfileKind::Gentle),
        1,
        "mass_low_gentle",
        150.0,
        Some(maneuver::OodCase::MassLow),
    )
    .unwrap();
    let script = m.write(&dir).unwrap();
    let source = hil_sim::runner::cli::Source {
        dataset: None,
        script: Some(script),
    };
    let flight = hil_sim::runner::cli::flight(&source, 1, None).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let from_filter = host_and_qemu_agree(&flight);
    assert!(
        from_filter > 0,
        "no frame of the light flight took α from the filter: with this model the test no longer \
         covers the fallback on the target; fly a flight where it does"
    );
}
