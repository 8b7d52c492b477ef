//! The flight image in QEMU answers exactly like the in-process firmware. Needs `cargo fw` and
//! qemu-system-arm (both installed by `scripts/bootstrap` + `cargo fw`; `scripts/test` builds the image
//! before the tests). Without them it fails with the command to run, never skips.

use estimator_core::{CHANNELS, Channel, SensorFrame};
use hil_sim::runner::target::default_elf;
use hil_sim::runner::{self, InProcess, Qemu, RunConfig, Sample};

fn samples(n: u16) -> Vec<Sample> {
    (0..n)
        .map(|s| {
            let t = f64::from(s) * 0.05;
            let mut si = [0.0; CHANNELS];
            for (i, v) in si.iter_mut().enumerate() {
                *v = ((i as f64 + 1.0) * 0.37 * t).sin();
            }
            si[Channel::AccelZ.index()] = -9.81 + (0.6 * t).sin();
            si[Channel::GpsSpeed.index()] = 180.0 + 20.0 * (0.05 * t).sin();
            si[Channel::GpsAlt.index()] = 4572.0 + 100.0 * (0.02 * t).sin();
            si[Channel::Throttle.index()] = 0.6 + 0.3 * (0.1 * t).sin();
            // A burst of invalid channels and out-of-envelope values mid-flight.
            if (100..110).contains(&s) {
                si[Channel::GyroQ.index()] = f64::NAN;
                si[Channel::AccelZ.index()] = 500.0;
            }
            Sample {
                frame: SensorFrame::from_si(s, u32::from(s) * 50, &si),
                time_s: t,
                alpha_true_deg: 0.0,
                beta_true_deg: 0.0,
            }
        })
        .collect()
}

#[test]
fn qemu_estimates_equal_host_bit_for_bit() {
    let s = samples(200);
    let cfg = RunConfig::default();
    let host = runner::run(&mut InProcess::new(), &s, &cfg).unwrap();
    let mut q = Qemu::start("qemu-system-arm", &default_elf()).unwrap();
    let qemu = runner::run(&mut q, &s, &cfg).unwrap();
    assert_eq!(host.records.len(), qemu.records.len());
    for (h, q) in host.records.iter().zip(&qemu.records) {
        let (h, q) = (h.reply.unwrap(), q.reply.unwrap());
        assert_eq!(h.estimate, q.estimate, "seq {}", h.estimate.seq);
        assert_eq!(q.health.deadline_misses, 0);
        assert!(q.health.step_ticks > 0);
    }
}
