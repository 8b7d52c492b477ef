//! Step timing behind a small trait: the DWT cycle counter on silicon, TIM2 counting instructions under
//! QEMU `-icount shift=0`, the host clock in the in-process firmware, a scripted clock in tests.

use estimator_core::wire::estimate::TickSource;

/// A free-running 32-bit counter. Differences are taken with wrapping arithmetic, so a step may span
/// one wrap (at 168 MHz a 32-bit cycle counter wraps every 25 s, far longer than a 50 ms step).
pub trait Clock {
    /// The counter now.
    fn now(&mut self) -> u32;
    /// What one tick is.
    fn source(&self) -> TickSource;
}

/// A clock that never advances: for builds with no timer at all (`TickSource::None`).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoClock;

impl Clock for NoClock {
    fn now(&mut self) -> u32 {
        0
    }
    fn source(&self) -> TickSource {
        TickSource::None
    }
}

/// Ticks elapsed between two readings of a wrapping 32-bit counter.
pub fn elapsed(start: u32, end: u32) -> u32 {
    end.wrapping_sub(start)
}
