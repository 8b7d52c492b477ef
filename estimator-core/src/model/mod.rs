//! The compiled-in model of the build's aircraft: `NAME/weights.rs`, written by `trainer train
//! --export`, and `NAME/sigma.rs`, written by `trainer fit-sigma`, never edited by hand.
//! `ESTIMATOR_WEIGHTS=/path/weights.rs` and `ESTIMATOR_SIGMA=/path/sigma.rs` at build time select
//! others (see `build.rs`). The networks name the aircraft they were trained for, and a build for
//! another aircraft does not compile.

#[cfg(estimator_weights)]
mod generated {
    #![allow(clippy::all, clippy::unreadable_literal)]
    include!(env!("ESTIMATOR_WEIGHTS_FILE"));
}
#[cfg(estimator_weights)]
pub use generated::*;

/// Networks trained on another aircraft's flights are no model of this one: a build whose weights
/// name another aircraft than its description fails here.
#[cfg(estimator_weights)]
const _: () = assert!(
    same(generated::AIRCRAFT_NAME, crate::aircraft::AIRCRAFT.name),
    "the weights were trained for another aircraft than this build's (ESTIMATOR_AIRCRAFT)"
);

/// Byte equality, at compile time.
#[cfg(estimator_weights)]
const fn same(a: &str, b: &str) -> bool {
    const fn bytes(a: &[u8], b: &[u8]) -> bool {
        match (a, b) {
            ([], []) => true,
            ([x, a @ ..], [y, b @ ..]) => *x == *y && bytes(a, b),
            _ => false,
        }
    }
    bytes(a.as_bytes(), b.as_bytes())
}

/// The weights of the estimate's 1σ (`src/model/NAME/sigma.rs`, written by `trainer fit-sigma`;
/// `ESTIMATOR_SIGMA=/path/sigma.rs` selects another fit, see `build.rs`).
#[cfg(not(estimator_no_sigma_fit))]
mod sigma {
    #![allow(clippy::all, clippy::unreadable_literal)]
    include!(env!("ESTIMATOR_SIGMA_FILE"));
}
/// No 1σ fit for the build's aircraft yet: every estimate `UNCERTAIN`.
#[cfg(estimator_no_sigma_fit)]
mod sigma {
    pub const SIGMA: crate::uncertainty::Coefficients = crate::uncertainty::UNFITTED;
    pub const SIGMA_PROVENANCE: &str =
        "no fit for this aircraft: every estimate's 1σ is the largest (run trainer fit-sigma)";
    pub const SIGMA_MODEL_PROVENANCE: &str = "";
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

/// The compiled-in α and β networks, `None` in a build without a model (for the host tools, which
/// cannot see this crate's build configuration).
#[cfg(estimator_weights)]
pub fn shipped_networks() -> Option<[&'static dyn crate::AngleNet; 2]> {
    Some([&ALPHA, &BETA])
}
/// The compiled-in α and β networks, `None` in a build without a model (for the host tools, which
/// cannot see this crate's build configuration).
#[cfg(not(estimator_weights))]
pub fn shipped_networks() -> Option<[&'static dyn crate::AngleNet; 2]> {
    None
}

/// How the compiled-in model was trained (its `PROVENANCE`), `None` in a build without a model.
#[cfg(estimator_weights)]
pub const SHIPPED_PROVENANCE: Option<&str> = Some(PROVENANCE);
/// How the compiled-in model was trained (its `PROVENANCE`), `None` in a build without a model.
#[cfg(not(estimator_weights))]
pub const SHIPPED_PROVENANCE: Option<&str> = None;

#[cfg(test)]
mod tests {
    /// A build compiles in the networks of its own aircraft, from its own folder: the committed
    /// `src/model/NAME/weights.rs` when there is one, none when there is not (unless
    /// `ESTIMATOR_WEIGHTS` named a file, which must name the same aircraft: see `AIRCRAFT_NAME`).
    #[test]
    fn a_build_takes_only_its_own_aircrafts_networks() {
        let named = option_env!("ESTIMATOR_WEIGHTS").is_some_and(|p| !p.is_empty());
        let name = crate::aircraft::AIRCRAFT.name;
        let committed = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("src/model")
            .join(name)
            .join("weights.rs");
        if !named {
            assert_eq!(
                super::HAS_MODEL,
                committed.is_file(),
                "{}",
                committed.display()
            );
        }
        #[cfg(estimator_weights)]
        assert_eq!(super::AIRCRAFT_NAME, name);
        // Every committed model lives in the folder of a described aircraft.
        let models = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/model");
        for entry in std::fs::read_dir(&models).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                let dir = path.file_name().unwrap().to_str().unwrap().to_string();
                let description = models.join(format!("../../../aircraft/{dir}.toml"));
                assert!(
                    description.is_file(),
                    "{}: no aircraft/{dir}.toml",
                    path.display()
                );
            }
        }
    }

    /// The committed `sigma.rs` belongs to the committed `weights.rs` (a retrained or installed
    /// estimator needs `scripts/fit-sigma`). A build without a model (another aircraft's, before
    /// its own networks) has no networks for a fit to belong to.
    #[test]
    fn the_sigma_weights_were_fitted_for_the_compiled_in_networks() {
        assert!(
            !super::HAS_MODEL || super::sigma_fitted_for_this_model(),
            "src/model/NAME/sigma.rs was fitted for other networks: run trainer fit-sigma"
        );
    }
}
