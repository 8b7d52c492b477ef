//! On the host, the firmware logic's log lines reach the `log` facade (target "firmware"): a
//! corrupted frame and a sequence restart say so.

// Host test code: the flight-code lints of `[workspace.lints]` do not apply (a panic is how it fails).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects
)]

use std::sync::Mutex;

use estimator_core::wire::MAX_FRAME;
use estimator_core::{Estimator, SensorFrame, Suite};
use firmware::{App, Config, NoClock};

static LINES: Mutex<Vec<(log::Level, String, String)>> = Mutex::new(Vec::new());

struct Capture;

impl log::Log for Capture {
    fn enabled(&self, _: &log::Metadata) -> bool {
        true
    }
    fn log(&self, r: &log::Record) {
        LINES
            .lock()
            .unwrap()
            .push((r.level(), r.target().to_string(), r.args().to_string()));
    }
    fn flush(&self) {}
}

fn send(app: &mut App<NoClock>, bytes: &[u8]) {
    let mut out = [0u8; MAX_FRAME];
    for b in bytes {
        app.push(*b, &mut out);
    }
}

fn wire(seq: u16) -> Vec<u8> {
    let f = SensorFrame {
        seq,
        time_ms: u32::from(seq) * 50,
        ..SensorFrame::default()
    };
    let mut buf = [0u8; MAX_FRAME];
    let n = f.encode(Suite::Table1, &mut buf).unwrap();
    buf[..n].to_vec()
}

#[test]
fn corrupted_frames_and_restarts_are_logged_with_target_firmware() {
    log::set_logger(&Capture).unwrap();
    log::set_max_level(log::LevelFilter::Info);
    let mut app = App::new(Estimator::shipped(), NoClock, Config { budget_ticks: 1 });
    send(&mut app, &wire(100));
    let mut bad = wire(101);
    bad[3] ^= 0x40;
    send(&mut app, &bad);
    send(&mut app, &wire(5));
    let lines = LINES.lock().unwrap().clone();
    assert!(
        lines.iter().all(|(_, target, _)| target == "firmware"),
        "{lines:?}"
    );
    assert!(
        lines
            .iter()
            .any(|(l, _, m)| *l == log::Level::Warn && m.starts_with("frame rejected: ")),
        "{lines:?}"
    );
    assert!(
        lines
            .iter()
            .any(|(l, _, m)| *l == log::Level::Info && m == "sequence restarted at 5 (was 100)"),
        "{lines:?}"
    );
}
