//! hil-sim: the flight side of the hardware-in-the-loop system.
//!
//! Data flow, one module each: [`maneuver`] → [`plant`] → [`sensors`] → [`frames`] → [`link`] →
//! (firmware, through [`runner`]) → [`score`]. [`dataset`] stores flights on disk.
//!
//! Feature `sim` (default) builds the simulator, the sensor models, the link and the runner. Without
//! it the crate is only the flight records ([`flight`]), the dataset format and provenance
//! ([`dataset`]), sample → frame ([`frames`]), scripted sensor faults on frames ([`faults`]) and
//! the plot font, progress reporting and the docs' command-line extractor: what the trainer
//! depends on.

// Flight records and the dataset on disk: what the trainer reads, with no simulator behind it.
pub mod boom;
pub mod cli_values;
pub mod dataset;
pub mod docs_cli;
pub mod error;
pub mod error_text;
pub mod faults;
pub mod flight;
pub mod font;
pub mod frames;
pub mod progress;

// The simulator and the HIL runner (the `sim` feature, on by default; the trainer builds without it).
#[cfg(feature = "sim")]
pub mod commands;
#[cfg(feature = "sim")]
pub mod fly;
#[cfg(feature = "sim")]
pub mod link;
#[cfg(feature = "sim")]
pub mod maneuver;
#[cfg(feature = "sim")]
pub mod plant;
#[cfg(feature = "sim")]
pub mod runner;
#[cfg(feature = "sim")]
pub mod score;
#[cfg(feature = "sim")]
pub mod sensors;

pub use error::{Error, Result};
