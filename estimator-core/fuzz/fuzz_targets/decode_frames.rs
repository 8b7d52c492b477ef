//! Arbitrary bytes off the serial line: the stream accumulator, COBS, CRC and both frame parsers.
#![no_main]
use estimator_core::wire::{self, Accumulator, MAX_FRAME, estimate::EstimateFrame, sensor::SensorPacket};
use estimator_core::SensorFrame;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut acc = Accumulator::<MAX_FRAME>::new();
    for b in data {
        if let Some(Ok(body)) = acc.push(*b) {
            if let Ok(f) = SensorFrame::parse(body) {
                // A frame that parses re-encodes, as its own kind, to a frame that parses to the same value.
                let suite = SensorPacket::new_checked(body).expect("it parsed").suite();
                let mut out = [0u8; MAX_FRAME];
                let n = f.encode(suite, &mut out).expect("a parsed frame fits MAX_FRAME");
                let mut dec = [0u8; MAX_FRAME];
                let body = wire::decode(&out[..n - 1], &mut dec).expect("own encoding decodes");
                assert_eq!(SensorFrame::parse(body), Ok(f));
            }
            let _ = EstimateFrame::parse(body);
        }
    }
    let mut out = [0u8; 1024];
    let _ = wire::decode(data, &mut out);
});
