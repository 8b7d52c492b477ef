//! The crate's one error type. Each module keeps its own failure kinds (what went wrong, with the
//! path or value and what to do about it); [`Error`] gathers them so that a command, and any caller of
//! the library, handles one type.

/// Every failure of hil-sim.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    Dataset(#[from] crate::dataset::DatasetError),
    #[cfg(feature = "sim")]
    #[error(transparent)]
    Generate(#[from] crate::dataset::GenerateError),
    #[cfg(feature = "sim")]
    #[error(transparent)]
    Plant(#[from] crate::plant::PlantError),
    #[cfg(feature = "sim")]
    #[error(transparent)]
    Maneuver(#[from] crate::maneuver::ManeuverError),
    #[cfg(feature = "sim")]
    #[error(transparent)]
    Sensors(#[from] crate::sensors::SensorConfigError),
    #[cfg(feature = "sim")]
    #[error(transparent)]
    Run(#[from] crate::runner::RunError),
    #[error("cannot {action} {path}: {source}")]
    Io {
        action: &'static str,
        path: std::path::PathBuf,
        source: std::io::Error,
    },
    #[error("cannot format the summary as JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// Arguments that do not go together.
    #[error("{0}")]
    Usage(String),
}

/// `Result` with hil-sim's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;
