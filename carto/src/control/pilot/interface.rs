//! What goes into the pilot and comes out of it: requests from Cute, replies to it, the
//! context of one poll ([`Io`]), counters and notes for the log.

use robot_model::grid::{Heading, Move};
use robot_model::time::Instant;

use crate::motor::Motor;
use crate::sensors::SensorState;
use crate::ultrasound::Ultrasound;

/// A request from Cute, in Carto's terms. A command or direction byte that is not a move or a
/// heading is kept raw (`Err(byte)`) so it can be counted and reported.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Request {
    /// `SEND_ROBOT_POSITION`.
    SetPose {
        /// Row.
        x: u8,
        /// Column.
        y: u8,
        /// Facing, or the raw byte when it is not a heading.
        direction: Result<Heading, u8>,
    },
    /// `SEND_MOVE_CARTOGRAPHY`.
    Cartography {
        /// The move, or the raw byte when it is not one (3 STOP, unknown values).
        command: Result<Move, u8>,
    },
    /// One `SEND_MOVES_TRAJECTORY` frame.
    Trajectory {
        /// Batch length this frame belongs to.
        n_total: u8,
        /// The move, or the raw byte when it is not one.
        command: Result<Move, u8>,
    },
    /// `STOP_ROBOT`.
    Stop,
    /// A message Carto does not act on (unknown id, or one that only Carto sends), by raw id.
    Ignored {
        /// Raw message id.
        msg: u16,
    },
}

/// A message for Cute.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reply {
    /// `ROBOT_POSITION_RECEIVED`.
    PositionReceived,
    /// `SET_OBSTACLE_POSITION`.
    Obstacle {
        /// Row of the blocked cell.
        x: u8,
        /// Column of the blocked cell.
        y: u8,
    },
    /// `SET_ROBOT_POSITION`.
    RobotPosition {
        /// Row of the robot's new cell.
        x: u8,
        /// Column of the robot's new cell.
        y: u8,
    },
    /// `MOVE_DONE`.
    MoveDone,
}

/// Whether the boards are usable, as the caller sees them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Health {
    /// The sensor board sends keep-state.
    pub sensor_board: bool,
    /// The motor board link is up.
    pub motor_board: bool,
}

/// What one call of the pilot acts on: the time now, the motor controller it drives and what
/// the boards say. [`crate::Carto`] builds it once per poll, after it polled the motor at `now`;
/// every step of the pilot's state machine takes it whole rather than its parts.
#[derive(Debug)]
pub struct Io<'a> {
    /// The time of this poll.
    pub now: Instant,
    /// The motor controller, polled at `now` already (it holds the outcome of a move that just
    /// ended).
    pub motor: &'a mut Motor,
    /// The latest readings of the sensor board.
    pub sensors: &'a SensorState,
    /// The distance sensor's latest readings.
    pub us: &'a Ultrasound,
    /// Whether the boards are usable.
    pub health: Health,
}

/// Counters kept by the pilot.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PilotCounters {
    /// Moves (FORWARD/RIGHT/LEFT) completed within tolerance.
    pub moves_done: u64,
    /// Moves that could not run or failed.
    pub moves_failed: u64,
    /// `SET_OBSTACLE_POSITION` sent (or obstacles found without a pose).
    pub obstacles: u64,
    /// Bumper hits during a FORWARD.
    pub bumps: u64,
    /// Partial trajectory batches discarded by a different `n_total`.
    pub batches_discarded: u64,
    /// Requests with bad values (direction > 3, `n_total` 0, command > 3).
    pub bad_values: u64,
    /// FORWARDs refused because an echo of the scan lay in the body's path.
    pub corridor_blocked: u64,
    /// FORWARDs driven on a track beside the line through the centres, clear of an echo
    /// (`pilot/safety.rs`, "Corridor").
    pub forwards_aside: u64,
    /// FORWARDs driven by a sliding way through their two cells (`pilot/sliding.rs`).
    pub forwards_slid: u64,
    /// Turns that first drove back or forth to clear a known echo.
    pub turns_shifted: u64,
    /// Turns made off the centre that drove back to it before their `MOVE_DONE`.
    pub turns_recentred: u64,
    /// Turns refused: no shift along the heading cleared the known echoes.
    pub turns_refused: u64,
    /// Readings at rest that corrected the belief (`estimate/localiser.rs`).
    pub pose_fixes: u64,
    /// Looks aside taken to correct the belief across the heading against a floor plan
    /// (`pilot/safety.rs`, "Looking aside").
    pub looks_aside: u64,
    /// Turns that failed (any move error) whose turn back to the heading they started from was
    /// started.
    pub turns_undone: u64,
    /// Sonar readings kept while a turn ran (`pilot/safety.rs`, "Readings in turns").
    pub turn_readings: u64,
    /// Sonar readings kept while a FORWARD drove (`pilot/safety.rs`, "Readings while driving").
    pub drive_readings: u64,
    /// FORWARDs stopped because the range held while the wheels drove (`pilot/stall.rs`).
    pub stalls: u64,
    /// FORWARDs stopped because the IMU saw the body turned under its wheels (module docs,
    /// "Pushed").
    pub pushes: u64,
}
/// A line about the client's input (a position, a STOP, a bad value) that the pilot wants
/// logged. The pilot does not log these itself: [`crate::Carto`] takes them with
/// [`Pilot::take_notes`](super::Pilot::take_notes) and logs them through its rate limiter, per
/// kind and client, so a flood of frames cannot flood the log.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InputNote {
    /// The rate limiter's kind (a constant per call site).
    pub kind: &'static str,
    /// A warning (bad input) rather than information.
    pub warn: bool,
    /// The line.
    pub text: String,
}
