//! The compiled-in model: `weights.rs`, written by `trainer train`, never edited by hand.
//! `ESTIMATOR_WEIGHTS=/path/weights.rs` at build time selects another export (see `build.rs`).

#[cfg(estimator_weights)]
mod generated {
    #![allow(clippy::all, clippy::unreadable_literal)]
    include!(env!("ESTIMATOR_WEIGHTS_FILE"));
}
#[cfg(estimator_weights)]
pub use generated::*;

/// Whether this build has a model.
pub const HAS_MODEL: bool = cfg!(estimator_weights);
