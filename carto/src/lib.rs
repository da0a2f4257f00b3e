#![doc = include_str!("../README.md")]
#![warn(missing_docs)]

pub mod backoff;
pub mod calibration;
mod carto;
pub mod config;
pub mod estimate;
pub mod fuzzing;
pub mod motor;
pub mod odometry;
pub mod pilot;
pub mod ratelimit;
pub mod recording;
pub mod runtime;
pub mod sensors;
pub mod surroundings;
pub mod ultrasound;
pub mod walls;
pub mod wire;

pub use crate::carto::{Belief, Carto, CartoStats, CartoStatus};
pub use config::CartoConfig;
pub use runtime::{CartoRuntime, RuntimeStats, StepReport};
