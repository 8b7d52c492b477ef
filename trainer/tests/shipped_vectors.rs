//! The compiled-in model (estimator-core/src/model/NAME/weights.rs) reproduces the test vectors the trainer
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
    let path = format!(
        "{}/../estimator-core/tests/vectors/{}.txt",
        env!("CARGO_MANIFEST_DIR"),
        estimator_core::aircraft::AIRCRAFT.name
    );
    let text = std::fs::read_to_string(&path)
        .expect("vectors written by `trainer train` next to weights.rs");
    let vs = parse_vectors(&text).expect("well-formed vectors");
    assert!(vs.len() > 50);
    let mut est = Estimator::shipped();
    let mut checked = 0;
    for (i, v) in vs.iter().enumerate() {
        if v.reset {
            est = Estimator::shipped();
        }
        let e = est.step(&v.frame);
        // Every channel of the vector file's suite valid (a Table 1 file has no EGI channel) and
        // none at an IMU full scale (the step holds those: estimator_core::health).
        let all_valid = estimator_core::Suite::ALL
            .iter()
            .any(|s| v.frame.valid == s.channels())
            && !e.flags.has(estimator_core::Flags::SATURATED);
        if all_valid {
            checked += 1;
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
    assert!(
        checked > 50,
        "only {checked} vectors with every channel valid"
    );
}
