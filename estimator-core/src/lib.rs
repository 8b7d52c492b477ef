//! # estimator-core
//!
//! The flight code of the synthetic air data system: it estimates angle of attack (α) and sideslip (β)
//! from inertial, GPS, control-surface and throttle data with two small cascaded, quantized neural
//! networks, following Karali et al., AIAA Aviation 2023.
//!
//! `#![no_std]`, no allocator, no floats on the estimation path, and no panics: every input, including
//! arbitrary bytes off a serial line, has a defined result.
//!
//! This crate is the single source of truth for
//! * the sensed channels, their order and integer units, and the sensor suites ([`channels`]),
//! * the candidate model inputs and how they are computed ([`features`]),
//! * normalisation ([`normalize`]) and the quantized layers ([`nn`]),
//! * the frame formats on the serial link ([`wire`]).
//!
//! Data flow of one step: bytes → [`wire::Accumulator`] → [`wire::sensor`] → [`SensorFrame`] →
//! [`Estimator::step`] (features, with deltas from the 24-frame History → envelope → normalise → cascade part 1 → part 2) → [`Estimate`] →
//! [`wire::estimate`] → bytes.
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

pub mod aero;
pub mod aircraft;
pub mod channels;
pub mod estimator;
pub mod features;
pub mod filter;
pub mod health;
pub mod model;
pub mod nn;
pub mod normalize;
pub mod uncertainty;
pub mod wire;

pub use channels::{CHANNELS, Channel, SensorFrame, Suite};
pub use estimator::{
    AngleNet, CascadeNet, Estimate, Estimator, Flags, UNCERTAIN_ALPHA_MDEG, UNCERTAIN_BETA_MDEG,
    UNCERTAIN_HOLD_FRAMES,
};
pub use features::{FEATURE_COUNT, Feature, FeatureState, FeatureValues, History, Lag};
