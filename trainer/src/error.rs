//! Typed errors of the trainer library.
use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file or directory that cannot be read, written or created (`action` says which).
    #[error("cannot {action} {path}: {source}")]
    Io {
        action: &'static str,
        path: PathBuf,
        source: std::io::Error,
    },
    /// A dataset that does not read (manifest, CSV, columns, numbers).
    #[error(
        "{0} (generate a dataset with `hil-sim generate --out DIR`; format in docs/architecture.md)"
    )]
    Dataset(#[from] hil_sim::dataset::DatasetError),
    #[error("dataset {0}: {1}")]
    Split(PathBuf, String),
    /// A flight's frames and its truth records that do not pair up one to one.
    #[error("{frames} frames but {truth} truth records: one truth record per frame is needed")]
    TruthLength { frames: usize, truth: usize },
    /// A model card that cannot stand for the model in a flight-test calibration.
    #[error("model card {card}: {why}")]
    ModelCard { card: PathBuf, why: String },
    /// A first calibration (`calibration.json`) whose carried moments cannot be read.
    #[error(
        "first calibration {path}: {why} (give the calibration.json trainer calibrate wrote beside the aircraft.toml the moment cards flew)"
    )]
    FirstCalibration { path: PathBuf, why: String },
    /// Sweep results that cannot be read or do not belong to the grid.
    #[error("sweep: {0}")]
    Sweep(String),
    /// A manifest fault the reader cannot parse.
    #[error("{0} (in a dataset manifest's `faults`)")]
    Fault(#[from] hil_sim::faults::FaultError),
    #[error("unknown feature `{0}` (known: {1})")]
    UnknownFeature(String, String),
    #[error(
        "`{0}` is air data and can never be a model input (it is what the model estimates, or derived from it)"
    )]
    Leakage(String),
    /// A feature the run's sensor suite does not deliver.
    #[error(
        "feature `{feature}` needs the `{needs}` sensor suite, but this run uses `{suite}` \
         (pass --suite {needs}, or choose features of the {suite} suite)"
    )]
    SuiteFeature {
        feature: String,
        needs: &'static str,
        suite: &'static str,
    },
    /// A dataset that does not carry the run's sensor suite.
    #[error(
        "dataset {dir} carries the sensor suites {carries:?}, not `{suite}` (regenerate it with this \
         build's `hil-sim generate`, which writes every suite)"
    )]
    DatasetSuite {
        dir: PathBuf,
        carries: Vec<String>,
        suite: &'static str,
    },
    #[error("unknown sensor suite `{0}` (known: table1, egi, egi120)")]
    UnknownSuite(String),
    #[error("model file {path}: {msg}")]
    Model { path: PathBuf, msg: String },
    #[error("{0}")]
    Plot(String),
    /// The PyTorch side of `trainer bench-train`.
    #[error("PyTorch benchmark: {0}")]
    Torch(String),
    #[error("numerical problem: {0}")]
    Numeric(String),
}

pub type Result<T> = std::result::Result<T, Error>;

/// [`Error::Io`] of `action` ("read", "write", "create") on `path`, for `map_err`.
pub(crate) fn io(
    action: &'static str,
    path: impl Into<PathBuf>,
) -> impl FnOnce(std::io::Error) -> Error {
    let path = path.into();
    move |source| Error::Io {
        action,
        path,
        source,
    }
}
