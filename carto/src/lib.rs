#![doc = include_str!("../README.md")]
#![warn(missing_docs)]

mod carto;
pub mod config;
pub mod control;
pub mod estimate;
pub mod fuzzing;
pub mod link;

// The parts under their short names: the folders show the design, the paths stay as they were.
pub use control::{calibration, motor, pilot, slide, ultrasound};
pub use estimate::{odometry, surroundings, walls};
pub use link::{backoff, ratelimit, recording, runtime, sensors, wire};

pub use crate::carto::{Belief, Carto, CartoStats, CartoStatus};
pub use config::CartoConfig;
pub use runtime::{CartoRuntime, RuntimeStats, StepReport};
