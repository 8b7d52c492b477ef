//! The trainer's test vectors (expected outputs from its independent i64 reference,
//! `trainer::quant`) replayed through hil-sim's link to the flight image on QEMU. Needs `cargo fw` and
//! qemu-system-arm (`scripts/bootstrap` + `cargo fw`; `scripts/test` builds the image before the
//! tests). Without them it fails with the command to run, never skips.

use estimator_core::{Flags, SensorFrame};
use hil_sim::runner::target::default_elf;
use hil_sim::runner::{self, Qemu, QemuLink, RunConfig, Sample};
use trainer::quant::{Vector, parse_vectors};

/// The vector runs are streamed back to back into one firmware instance: a run starts more than
/// 2 s (twice the longest delta lag) away from the frame before it, so no stored frame is ever used
/// across runs, exactly as after the run's `reset`. The extreme-value vectors (one frame per run,
/// all at the same instant) are checked on the host by `estimator-core/tests/vectors.rs`; streamed
/// into one instance their repeated values would trip the stuck-sensor detector, so they are left
/// out here.
#[test]
fn qemu_reproduces_the_trainer_vectors() {
    let path = format!(
        "{}/../estimator-core/tests/vectors/{}.txt",
        env!("CARGO_MANIFEST_DIR"),
        estimator_core::aircraft::AIRCRAFT.name
    );
    let text = std::fs::read_to_string(&path).unwrap();
    let vectors = parse_vectors(&text).expect("malformed vector line");
    // Runs of consecutive frames: a reset line followed by non-reset lines (at least two lines).
    let runs: Vec<&[Vector]> = vectors
        .chunk_by(|_, next| !next.reset)
        .filter(|run| run.len() > 1)
        .collect();
    assert!(
        runs.len() >= 4,
        "expected runs of consecutive frames in {path}"
    );
    let mut samples = Vec::new();
    let mut expected = Vec::new();
    let mut last_time: Option<u32> = None;
    for run in &runs {
        for (k, v) in run.iter().enumerate() {
            let time_ms = v.frame.time_ms;
            if let (0, Some(t)) = (k, last_time) {
                let gap = time_ms.wrapping_sub(t);
                assert!(gap > 2_000, "run starts {gap} ms after the previous frame");
            }
            last_time = Some(time_ms);
            samples.push(Sample {
                frame: SensorFrame {
                    seq: samples.len() as u16,
                    ..v.frame
                },
                time_s: f64::from(time_ms) * 1e-3,
                alpha_true_deg: 0.0,
                beta_true_deg: 0.0,
            });
            expected.push((
                v.alpha.mid,
                v.alpha.angle,
                v.beta.mid,
                v.beta.angle,
                v.alpha.clamped || v.beta.clamped,
            ));
        }
    }
    let mut q = Qemu::start("qemu-system-arm", &default_elf(), QemuLink::Usart).unwrap();
    let out = runner::run(&mut q, &samples, &RunConfig::default()).unwrap();
    assert_eq!(out.records.len(), expected.len());
    for (r, want) in out.records.iter().zip(&expected) {
        let e = r.reply.unwrap().estimate;
        let got = (
            e.w_aero_mms,
            e.alpha_mdeg,
            e.v_aero_mms,
            e.beta_mdeg,
            e.flags.has(Flags::OUT_OF_ENVELOPE),
        );
        assert_eq!(got, *want, "vector frame seq {}", e.seq);
    }
}
