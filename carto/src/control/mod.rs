//! Carto's control: what it does with a command of the link.
//!
//! - [`pilot`]: the link session's state machine, which turns each command into checked moves
//!   (the safety checks against what Carto knows, then the motor) and answers Cute.
//! - [`motor`]: closed-loop moves as drive v2 set-points on the encoders and the IMU.
//! - [`slide`]: local motion, a FORWARD's sliding way through its two cells over what is known.
//! - [`ultrasound`]: the 2024 obstacle rule on a distance reading at rest.
//! - [`calibration`]: the calibration drive (`carto --calibration-drive`).

pub mod calibration;
pub mod motor;
pub mod pilot;
pub mod slide;
pub mod ultrasound;
