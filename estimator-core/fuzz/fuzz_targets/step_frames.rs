//! Arbitrary sensor frames (any channel values, any validity bits, any sequence) through the shipped
//! estimator: never a panic, and the documented output invariants hold.
#![no_main]
use estimator_core::{CHANNELS, Estimator, Flags, SensorFrame};
use libfuzzer_sys::fuzz_target;

const FRAME_BYTES: usize = 2 + 4 + 4 * CHANNELS + 4;

fuzz_target!(|data: &[u8]| {
    let mut e = Estimator::shipped();
    for chunk in data.chunks_exact(FRAME_BYTES) {
        let u16_at = |i: usize| u16::from_le_bytes([chunk[i], chunk[i + 1]]);
        let u32_at = |i: usize| u32::from_le_bytes([chunk[i], chunk[i + 1], chunk[i + 2], chunk[i + 3]]);
        let raw = core::array::from_fn(|c| u32_at(6 + 4 * c) as i32);
        let f = SensorFrame { seq: u16_at(0), time_ms: u32_at(2), raw, valid: u32_at(6 + 4 * CHANNELS), sub: estimator_core::channels::Subsamples::NONE };
        let out = e.step(&f);
        assert_eq!(out.seq, f.seq);
        if out.flags.has(Flags::NO_ESTIMATE) {
            // Per angle: a held angle without a previous good value reads zero.
            let alpha_empty = out.flags.has(Flags::ALPHA_HELD) && (out.alpha_mdeg, out.w_aero_mms) == (0, 0);
            let beta_empty = out.flags.has(Flags::BETA_HELD) && (out.beta_mdeg, out.v_aero_mms) == (0, 0);
            assert!(alpha_empty || beta_empty, "{out:?}");
        }
        // Held angles are never computed from this frame; live ones lie in the training range.
        assert!(out.alpha_mdeg.abs() <= 90_000 && out.beta_mdeg.abs() <= 90_000, "{out:?}");
        // A held angle has no 1σ; a computed one has one, at most SIGMA_MAX.
        let unknown = estimator_core::uncertainty::SIGMA_UNKNOWN;
        assert_eq!(out.flags.has(Flags::ALPHA_HELD), out.sigma_alpha_mdeg == unknown, "{out:?}");
        assert_eq!(out.flags.has(Flags::BETA_HELD), out.sigma_beta_mdeg == unknown, "{out:?}");
    }
});
