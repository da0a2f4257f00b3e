#![doc = include_str!("../README.md")]
#![warn(missing_docs)]

mod carto;
pub mod config;
pub mod motor;
pub mod odometry;
pub mod pilot;
pub mod runtime;
pub mod sensors;
pub mod ultrasound;
pub mod wire;

pub use crate::carto::{Carto, CartoStats, CartoStatus};
pub use config::CartoConfig;
pub use runtime::{CartoRuntime, RuntimeStats, StepReport};
