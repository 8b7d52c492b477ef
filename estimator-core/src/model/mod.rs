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

/// How the compiled-in model was trained (its `PROVENANCE`), `None` in a build without a model.
#[cfg(estimator_weights)]
pub const SHIPPED_PROVENANCE: Option<&str> = Some(PROVENANCE);
/// How the compiled-in model was trained (its `PROVENANCE`), `None` in a build without a model.
#[cfg(not(estimator_weights))]
pub const SHIPPED_PROVENANCE: Option<&str> = None;
