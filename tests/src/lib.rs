//! Cross-crate integration tests live in tests/tests/: the ones that need more than one of
//! estimator-core, trainer and hil-sim (e.g. the trainer's vectors replayed by hil-sim on QEMU).
