//! hil-sim: the flight side of the hardware-in-the-loop system.
//!
//! Data flow, one module each: [`maneuver`] → [`plant`] → [`sensors`] → [`frames`] → [`link`] →
//! (firmware, through [`runner`]) → [`score`]. [`dataset`] stores flights on disk.

pub mod dataset;
pub mod faults;
pub mod flight;
pub mod fly;
pub mod font;
pub mod frames;
pub mod link;
pub mod maneuver;
pub mod plant;
pub mod runner;
pub mod score;
pub mod sensors;
