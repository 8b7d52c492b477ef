//! Trainer of the synthetic air data estimator: dataset loading with the estimator's exact input
//! contract, feature sets and leakage guard, burn models, quantization and code generation of
//! `estimator-core/src/model/NAME/weights.rs`, an independent integer reference and test vectors,
//! baselines, feature analysis and reports.
pub mod adam;
pub mod analysis;
pub mod baselines;
pub mod bench;
pub mod calibrate;
pub mod data;
pub mod error;
pub mod export;
pub mod features;
pub mod files;
pub mod filter_eval;
pub mod finetune;
pub mod metrics;
pub mod model;
pub mod ood;
pub mod pipeline;
pub mod plots;
pub mod prep;
pub mod quant;
pub mod report;
pub mod saved;
pub mod sweep;
pub mod uncertainty;

pub use error::{Error, Result};
