//! Host time per estimator step and per kernel call: `cargo bench -p estimator-core`.
//! (Instructions per step and per MAC on the Cortex-M4 come from QEMU: docs/results/wcet.md.)
//! Prints one JSON object per line so results can be collected by scripts.

// Host test code: the flight-code lints of `[workspace.lints]` do not apply (a panic is how it fails).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects
)]

use estimator_core::nn::kernel::{
    Int16Weights, accumulate_dsp, accumulate_portable, accumulate_wide,
};
use estimator_core::{CHANNELS, Channel, Estimator, SensorFrame};
use std::hint::black_box;
use std::time::Instant;

fn time<F: FnMut()>(iters: u32, mut f: F) -> f64 {
    for _ in 0..iters / 10 {
        f();
    }
    let t = Instant::now();
    for _ in 0..iters {
        f();
    }
    t.elapsed().as_secs_f64() * 1e9 / iters as f64
}

fn frame(seq: u16) -> SensorFrame {
    let mut si = [0.0f64; CHANNELS];
    si[Channel::AccelZ.index()] = -9.81;
    si[Channel::GpsSpeed.index()] = 180.0 + (seq % 50) as f64 * 0.1;
    si[Channel::GpsAlt.index()] = 4500.0;
    si[Channel::Throttle.index()] = 0.6;
    si[Channel::GyroQ.index()] = 0.01 * (seq % 13) as f64;
    si[Channel::Elevator.index()] = -2.0;
    SensorFrame::from_si(seq, seq as u32 * 50, &si)
}

fn main() {
    let mut e = Estimator::shipped();
    let macs = e.macs();
    let mut seq = 0u16;
    let ns = time(20_000, || {
        seq = seq.wrapping_add(1);
        black_box(e.step(black_box(&frame(seq))));
    });
    println!(
        "{{\"bench\":\"estimator_step\",\"model\":{},\"macs\":{macs},\"ns_per_step\":{ns:.0}}}",
        estimator_core::model::HAS_MODEL
    );

    static W: [[i8; 512]; 256] = {
        let mut w = [[0i8; 512]; 256];
        let mut o = 0;
        while o < 256 {
            let mut i = 0;
            while i < 512 {
                w[o][i] = ((o * 31 + i * 17) % 255) as i8;
                i += 1;
            }
            o += 1;
        }
        w
    };
    static W16: Int16Weights<512, 256> = Int16Weights::new(&W);
    let bias = [7i32; 256];
    let x: [i16; 512] = core::array::from_fn(|i| (i as i16).wrapping_mul(97));
    let mut acc = [0i32; 256];
    type Kernel<'a> = &'a dyn Fn(&[i16; 512], &mut [i32; 256]);
    let kernels: [(&str, Kernel); 3] = [
        ("portable", &|x, acc| accumulate_portable(&W, &bias, x, acc)),
        ("int8_sxtb16_emulated", &|x, acc| {
            accumulate_dsp(&W, &bias, x, acc)
        }),
        ("int16_emulated", &|x, acc| {
            accumulate_wide(&W16, &bias, x, acc)
        }),
    ];
    for (name, f) in kernels {
        let ns = time(2_000, || f(black_box(&x), &mut acc));
        println!(
            "{{\"bench\":\"dense_512x256_{name}\",\"ns_per_call\":{ns:.0},\"ns_per_mac\":{:.3}}}",
            ns / (512.0 * 256.0)
        );
    }
}
