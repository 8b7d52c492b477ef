//! The compiled-in model (estimator-core/src/model/weights.rs) reproduces the test vectors the trainer
//! wrote next to it with its independent integer reference, through `Estimator::shipped()` stepped over
//! each run of consecutive frames (fresh at every `reset`).
use estimator_core::Estimator;
use trainer::quant::parse_vectors;

#[test]
fn shipped_model_matches_its_vectors() {
    if !estimator_core::model::HAS_MODEL {
        eprintln!("no compiled-in model: nothing to check");
        return;
    }
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../estimator-core/tests/vectors/shipped.txt"
    );
    let text = std::fs::read_to_string(path)
        .expect("vectors written by `trainer train` next to weights.rs");
    let vs = parse_vectors(&text).expect("well-formed vectors");
    assert!(vs.len() > 50);
    let mut est = Estimator::shipped();
    for (i, v) in vs.iter().enumerate() {
        if v.reset {
            est = Estimator::shipped();
        }
        let e = est.step(&v.frame);
        let all_valid = v.frame.valid == estimator_core::channels::ALL_VALID;
        if all_valid {
            assert_eq!(
                (e.w_aero_mms, e.alpha_mdeg),
                (v.alpha.mid, v.alpha.angle),
                "vector {i}"
            );
            assert_eq!(
                (e.v_aero_mms, e.beta_mdeg),
                (v.beta.mid, v.beta.angle),
                "vector {i}"
            );
            let any_clamped = v.alpha.clamped || v.beta.clamped;
            assert_eq!(
                e.flags.has(estimator_core::Flags::OUT_OF_ENVELOPE),
                any_clamped,
                "vector {i}"
            );
        }
    }
}
