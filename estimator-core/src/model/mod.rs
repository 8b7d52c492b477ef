//! The compiled-in model: `weights.rs`, written by `trainer train`, and `sigma.rs`, written by
//! `trainer fit-sigma`, never edited by hand. `ESTIMATOR_WEIGHTS=/path/weights.rs` and
//! `ESTIMATOR_SIGMA=/path/sigma.rs` at build time select others (see `build.rs`).

#[cfg(estimator_weights)]
mod generated {
    #![allow(clippy::all, clippy::unreadable_literal)]
    include!(env!("ESTIMATOR_WEIGHTS_FILE"));
}
#[cfg(estimator_weights)]
pub use generated::*;

/// The weights of the estimate's 1σ (`src/model/sigma.rs`, written by `trainer fit-sigma`;
/// `ESTIMATOR_SIGMA=/path/sigma.rs` selects another fit, see `build.rs`).
mod sigma {
    #![allow(clippy::all, clippy::unreadable_literal)]
    include!(env!("ESTIMATOR_SIGMA_FILE"));
}
pub use sigma::{SIGMA, SIGMA_MODEL_PROVENANCE, SIGMA_PROVENANCE};

/// Whether the compiled-in 1σ weights were fitted for the compiled-in networks. A build with other
/// weights (`ESTIMATOR_WEIGHTS`) keeps the committed fit, whose 1σ is then not that model's: refit
/// with `scripts/fit-sigma` after `--install`ing another estimator.
pub fn sigma_fitted_for_this_model() -> bool {
    SHIPPED_PROVENANCE == Some(SIGMA_MODEL_PROVENANCE)
}

/// Whether this build has a model.
pub const HAS_MODEL: bool = cfg!(estimator_weights);

/// How the compiled-in model was trained (its `PROVENANCE`), `None` in a build without a model.
#[cfg(estimator_weights)]
pub const SHIPPED_PROVENANCE: Option<&str> = Some(PROVENANCE);
/// How the compiled-in model was trained (its `PROVENANCE`), `None` in a build without a model.
#[cfg(not(estimator_weights))]
pub const SHIPPED_PROVENANCE: Option<&str> = None;

#[cfg(test)]
mod tests {
    /// A build for another aircraft than the one the committed networks are for carries no model
    /// unless `ESTIMATOR_WEIGHTS` named one: its estimates are never another airframe's networks'.
    #[test]
    fn another_aircrafts_build_does_not_take_the_committed_networks() {
        let named = option_env!("ESTIMATOR_WEIGHTS").is_some_and(|p| !p.is_empty());
        if env!("ESTIMATOR_BUILD_AIRCRAFT") != env!("ESTIMATOR_DEFAULT_AIRCRAFT") && !named {
            assert_eq!((super::HAS_MODEL, super::SHIPPED_PROVENANCE), (false, None));
        }
    }

    /// The committed `sigma.rs` belongs to the committed `weights.rs` (a retrained or installed
    /// estimator needs `scripts/fit-sigma`). A build without a model (another aircraft's, before
    /// its own networks) has no networks for a fit to belong to.
    #[test]
    fn the_sigma_weights_were_fitted_for_the_compiled_in_networks() {
        assert!(
            !super::HAS_MODEL || super::sigma_fitted_for_this_model(),
            "src/model/sigma.rs was fitted for other networks: run scripts/fit-sigma"
        );
    }
}
