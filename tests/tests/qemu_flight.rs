//! The shipped estimator on the first 150 s of the stock test flight, in QEMU and on the host, bit
//! for bit with its flags: the paths the trainer's short vector runs never reach, the air-data
//! filter after a minute of flight and its α standing in where the α network is out of its
//! envelope (`ALPHA_FROM_FILTER`, from about 97 s on this flight with the shipped model). Needs
//! `cargo fw` and qemu-system-arm (`scripts/bootstrap` + `cargo fw`; `scripts/test` builds the
//! image before the tests). Without them it fails with the command to run, never skips.

// Host test code: the flight-code lints of `[workspace.lints]` do not apply (a panic is how it fails).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

use estimator_core::Flags;
use hil_sim::runner::target::default_elf;
use hil_sim::runner::{self, InProcess, Qemu, QemuLink, RunConfig};

#[test]
fn the_flight_image_in_qemu_answers_the_test_flight_as_the_host_does_fallback_included() {
    let flight = common::first_150_s_of_the_test_flight();
    let samples = runner::samples_of(&flight);
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
    assert!(
        from_filter > 0,
        "no frame of these 150 s took α from the filter: with this model the test no longer covers \
         the fallback on the target; fly a flight where it does"
    );
}
