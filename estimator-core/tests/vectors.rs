//! Host parity: the compiled-in model reproduces the trainer's test vectors, whose expected outputs
//! come from the trainer's independent i64 reference (trainer/src/quant.rs), not from this crate.
//! `ESTIMATOR_VECTORS=/path` at build time checks another export (set with `ESTIMATOR_WEIGHTS`).

// Host test code: the flight-code lints of `[workspace.lints]` do not apply (a panic is how it fails).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects
)]

#[cfg(estimator_weights)]
use estimator_core::AngleNet;
use estimator_core::channels::{
    SUB_CHANNEL_COUNT, SUBSAMPLES, SUBSAMPLES_VALID, Subsamples, TABLE1_CHANNELS,
};
use estimator_core::{CHANNELS, Estimator, FeatureState, Flags, SensorFrame};

const VECTORS: Option<&str> = option_env!("ESTIMATOR_VECTORS");

/// Numbers of an `egi120` line's frame after `seq time_ms valid`: the channels, the sub-samples'
/// validity and their values.
const EGI120_WIDTH: usize = CHANNELS + 1 + SUBSAMPLES * SUB_CHANNEL_COUNT;

#[test]
fn compiled_in_model_matches_the_trainer_vectors() {
    if !estimator_core::model::HAS_MODEL {
        panic!("this build has no weights: run `trainer train` (see README) before the tests");
    }
    // The committed vectors of the build's aircraft (`tests/vectors/NAME.txt`).
    let path = VECTORS.map(String::from).unwrap_or_else(|| {
        format!(
            "{}/tests/vectors/{}.txt",
            env!("CARGO_MANIFEST_DIR"),
            estimator_core::aircraft::AIRCRAFT.name
        )
    });
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("read {path}: {e}"));
    let mut checked = 0;
    // Lines are runs of consecutive frames; `reset` starts one on an empty history (and a fresh
    // estimator, so its own history matches).
    // The features as the trainer's integer reference made them: one FeatureState per run (delta
    // history and the air-data filter).
    let mut state = FeatureState::new(true);
    let mut est = Estimator::shipped();
    for line in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
    {
        let v: Vec<i64> = line
            .split_whitespace()
            .map(|t| t.parse().expect("integer"))
            .collect();
        // A line carries the channels of its model's suite: 16 (Table 1) or all 23 (EGI), then
        // for `egi120` the sub-samples' validity and their 6 × 13 values.
        let n = v.len() - 4 - 6;
        let channels = if n == EGI120_WIDTH { CHANNELS } else { n };
        assert!(
            n == TABLE1_CHANNELS || n == CHANNELS || n == EGI120_WIDTH,
            "malformed vector line: {line}"
        );
        if v[0] == 1 {
            state = FeatureState::new(true);
            est.reset();
        }
        let v = &v[1..];
        let raw: [i32; CHANNELS] =
            core::array::from_fn(|i| if i < channels { v[3 + i] as i32 } else { 0 });
        let mut sub = Subsamples::NONE;
        if n == EGI120_WIDTH {
            sub.valid = v[3 + CHANNELS] as u16;
            for (r, x) in sub.raw.iter_mut().flatten().zip(&v[4 + CHANNELS..3 + n]) {
                *r = *x as i32;
            }
        }
        let frame = SensorFrame {
            seq: v[0] as u16,
            time_ms: v[1] as u32,
            raw,
            valid: v[2] as u32,
            sub,
        };
        let values = state.next(&frame);
        let e = est.step(&frame);
        let o = &v[3 + n..];
        let want_alpha = (o[0] as i32, o[1] as i32, o[2] != 0);
        let want_beta = (o[3] as i32, o[4] as i32, o[5] != 0);
        #[cfg(estimator_weights)]
        {
            assert_eq!(
                estimator_core::model::ALPHA.run(&values),
                want_alpha,
                "alpha, line: {line}"
            );
            assert_eq!(
                estimator_core::model::BETA.run(&values),
                want_beta,
                "beta, line: {line}"
            );
        }
        // The full step gives the same numbers when every channel of the line's suite is valid and
        // healthy (a channel at its full scale is held by the step, see estimator_core::health).
        let suite = match n {
            EGI120_WIDTH => estimator_core::Suite::Egi120,
            CHANNELS => estimator_core::Suite::Egi,
            _ => estimator_core::Suite::Table1,
        };
        let healthy = values.health.usable(&frame) | (values.usable & SUBSAMPLES_VALID);
        if healthy & suite.channels() == suite.channels() {
            // An α network out of its envelope gives way to a consistent filter: α is the filter's.
            let want = if e.flags.has(Flags::ALPHA_FROM_FILTER) {
                assert!(want_alpha.2, "α from the filter while in envelope: {line}");
                estimator_core::estimator::filter_alpha_fallback(&values)
                    .expect("the fallback's conditions hold")
            } else {
                (want_alpha.0, want_alpha.1)
            };
            assert_eq!((e.w_aero_mms, e.alpha_mdeg), want, "step alpha: {line}");
            assert_eq!(
                (e.v_aero_mms, e.beta_mdeg),
                (want_beta.0, want_beta.1),
                "step beta: {line}"
            );
            assert_eq!(
                e.flags.has(Flags::OUT_OF_ENVELOPE),
                want_alpha.2 || want_beta.2,
                "flags: {line}"
            );
        }
        checked += 1;
    }
    assert!(checked >= 100, "only {checked} vectors in {path}");
}
