//! # firmware
//!
//! The estimator's application logic, independent of the board: bytes in → [`ByteQueue`] (filled by
//! the receive interrupt) → [`App`] (frame accumulation, one [`Estimator`](estimator_core::Estimator)
//! step per valid sensor frame, link and deadline counters) → encoded estimate frames out.
//!
//! Everything here is `no_std`, heap-free and tested on the host; the Cortex-M4F board layer
//! (`src/main.rs`) only moves bytes between USART1 (or, in QEMU when the host opts in, semihosting:
//! [`transport`]) and this library and reads a [`Clock`].
#![cfg_attr(not(test), no_std)]
#![deny(unsafe_code)]
// The flight-code lints (no unwrap/expect/panic/indexing, no unchecked arithmetic) come from
// `[workspace.lints]` in the root Cargo.toml; unit tests may panic, that is how they fail.
#![cfg_attr(
    test,
    allow(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing,
        clippy::arithmetic_side_effects
    )
)]

#[macro_use]
mod fmt;

pub mod app;
pub mod clock;
pub mod queue;
pub mod rcc;
pub mod transport;
pub mod usart;

pub use app::{App, Config, Intake, SeqEvent, Stats};
pub use clock::{Clock, NoClock};
pub use queue::ByteQueue;
pub use transport::Transport;
