//! One sensor fault, side by side with the fault-free run: the first 150 s of the build's
//! aircraft's test flight (as `tests/dropout.rs` flies it) through the air-data filter alone and
//! through the shipped estimator, with and without the fault. Prints every 10th frame from 5 s
//! before the fault: the filter's α, β and wind (faulted less fault-free) and its flags, and the
//! estimate's α and β (faulted less fault-free) and flags; the figures of the bias paragraph of
//! `docs/results/dropout.md`.
//!
//! ```sh
//! cargo run --release -p tests --example fault_twin -- 'bias:accel_z_mps2=-39.2266@60+10'
//! ESTIMATOR_AIRCRAFT=c172p CARGO_TARGET_DIR=target/c172p cargo run --release -p tests --example fault_twin -- 'bias:accel_z_mps2=-39.2266@60+10'
//! ```

// Host analysis code: the flight-code lints of `[workspace.lints]` do not apply.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects
)]

#[path = "../tests/common/mod.rs"]
mod common;

use estimator_core::filter::{AirDataFilter, CONFIG, Output};
use estimator_core::{Estimate, Estimator, SensorFrame, Suite};
use hil_sim::faults::{Fault, apply};

fn main() -> anyhow::Result<()> {
    let arg = std::env::args().nth(1).ok_or_else(|| {
        anyhow::anyhow!("give one fault as hil-sim run --fault takes it, e.g. 'bias:accel_z_mps2=-39.2266@60+10'")
    })?;
    let fault: Fault = arg
        .parse()
        .map_err(|e| anyhow::anyhow!("fault `{arg}`: {e}"))?;
    let flight = common::first_150_s_of_the_test_flight();
    let samples = hil_sim::runner::samples_of(&flight);
    let suite = match Estimator::shipped().suite() {
        Some(s) if s.delivers(Suite::Egi) => s,
        _ => Suite::Egi,
    };
    let clean: Vec<SensorFrame> = samples
        .iter()
        .map(|s| s.frame.restricted_to(suite))
        .collect();
    let times: Vec<f64> = samples.iter().map(|s| s.time_s).collect();
    let mut faulted = clean.clone();
    apply(&[fault], &mut faulted, &times);

    let filter = |frames: &[SensorFrame]| -> Vec<Output> {
        let mut f = AirDataFilter::new(CONFIG);
        frames.iter().map(|x| f.step_frame(x, 0.05)).collect()
    };
    let estimator = |frames: &[SensorFrame]| -> Vec<Estimate> {
        let mut e = Estimator::shipped();
        frames.iter().map(|x| e.step(x)).collect()
    };
    let (fa, fb) = (filter(&clean), filter(&faulted));
    let (ea, eb) = (estimator(&clean), estimator(&faulted));

    println!(
        "{} `{arg}`: faulted less fault-free; filter flags {{1 NO_INPUT, 2 GATED, 4 RESTARTED, 8 LOW_CONFIDENCE, 16 SLOW, 32 ALT_COASTED, 64 PREDICTED, 128 DISAGREES}}, estimate flags as estimator_core::Flags::NAMED (hex)",
        estimator_core::aircraft::AIRCRAFT.name
    );
    println!(
        "| t, s | filter dα, ° | filter dβ, ° | filter dwind N / E / D, m/s | filter flags | estimate dα, ° | estimate dβ, ° | estimate flags |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let start = times
        .iter()
        .position(|t| *t >= fault.start_s - 5.0)
        .unwrap_or(0);
    let deg = |a: f32, b: f32| f64::from(b - a).to_degrees();
    for i in (start..times.len()).step_by(10) {
        let (a, b) = (&fa[i], &fb[i]);
        let w = |k: usize| b.wind_ned_mps[k] - a.wind_ned_mps[k];
        println!(
            "| {:.2} | {:.3} | {:.3} | {:.2} / {:.2} / {:.2} | {} | {:.3} | {:.3} | {:#06x} |",
            times[i],
            deg(a.alpha_rad, b.alpha_rad),
            deg(a.beta_rad, b.beta_rad),
            w(0),
            w(1),
            w(2),
            b.flags,
            f64::from(eb[i].alpha_mdeg - ea[i].alpha_mdeg) / 1000.0,
            f64::from(eb[i].beta_mdeg - ea[i].beta_mdeg) / 1000.0,
            eb[i].flags.0,
        );
    }
    Ok(())
}
