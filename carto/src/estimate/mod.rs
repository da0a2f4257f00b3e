//! Carto's estimate of the world and of itself: the evidence grid, the sonar's sensor model
//! that feeds it (style rule 16), and the pose filter (style rule 17).
//!
//! - [`grid`]: a bounded log-odds occupancy grid in Carto's metric frame, with shape queries
//!   (a corridor, a turning circle, a footprint) that answer free, occupied or unknown.
//! - [`sonar`]: how one sonar reading, echo or silence, changes the grid.
//! - [`pose`]: an extended Kalman filter over position, heading and gyro bias, predicting from
//!   the wheels and the gyro and correcting from sonar ranges against the grid.
//! - [`localiser`]: Carto's belief: the filter run on the dead reckoning, corrected at every
//!   reading at rest, and the grid those readings build.
//! - [`odometry`]: dead reckoning of the offset from the current cell's centre.
//! - [`surroundings`]: the echo points the safety checks ask, and known surface points.
//! - [`walls`]: surfaces the sonar ranged straight ahead, which the localiser compares a
//!   straight range with.

pub mod grid;
pub mod localiser;
pub mod odometry;
pub mod pose;
pub mod sonar;
pub mod surroundings;
pub mod walls;
