//! Where the pilot's state machine stands ([`Stage`]), and how that reads from outside
//! ([`Activity`]).

use robot_model::grid::Move;
use robot_model::time::Instant;

/// Where the pilot's state machine stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Stage {
    /// Take the next command of the current task (or the next task).
    Next,
    /// Waiting (up to `distance_wait`) for fresh encoder and IMU readings before a move: just
    /// after power-on, Cute's first command can arrive before the sensor board's first frames.
    Waiting { mv: Move, since: Instant },
    /// Waiting for a distance reading taken at rest, before a FORWARD.
    Checking { since: Instant },
    /// A move runs on the motor controller.
    Moving { kind: Move, since: Instant },
    /// Driving back after a bumper hit or a stalled FORWARD.
    BackingOff,
    /// The sonar scan before a FORWARD: look number `look` of
    /// [`Safety::looks`](super::limits::Safety::looks) runs.
    Looking { look: usize },
    /// Waiting for a distance reading at rest after look number `look`.
    Reading { look: usize, since: Instant },
    /// A leg of a sliding way (`pilot/sliding.rs`) started at `since`: of a FORWARD, or to where
    /// the turn `turn` can be made.
    Sliding { since: Instant, turn: Option<Move> },
    /// Driving back or forth before the turn `mv`, so the turning body clears known echoes.
    Shifting { mv: Move },
    /// The turn `mv` failed: turning back to the heading it started from.
    TurningBack { mv: Move },
    /// A STOP or a disconnect cut a turn or a look: facing the stored grid heading again before
    /// the move `mv`.
    Refacing { mv: Move },
    /// After a mapping turn's `MOVE_DONE`: turning on past the new heading and, once `back`, to
    /// it again, the sonar listening (`pilot/safety.rs`, "Readings in turns"); the look started
    /// at `since`. The next command waits in the queue. With `unacked` (a mapping turn made off
    /// the centre), the look runs before that turn's `MOVE_DONE` and the body then drives back
    /// to its cell's centre.
    LookingPast { back: bool, since: Instant, unacked: Option<Move> },
    /// After the turn `turn`, made off the centre: driving back to the cell's centre before its
    /// `MOVE_DONE` (`pilot/safety.rs`, "Back to the centre").
    Recentring { turn: Move },
}

/// What the pilot is doing ([`Pilot::activity`](super::Pilot::activity)), for logs and
/// diagnostics.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Activity {
    /// Nothing to do.
    Idle,
    /// Between two commands of a task, or a task waits.
    BetweenCommands,
    /// Waiting for fresh encoder and IMU readings before a move.
    WaitingForReadings,
    /// Waiting for a distance reading at rest before a FORWARD.
    CheckingAhead,
    /// A FORWARD runs.
    DrivingForward,
    /// A turn runs.
    Turning,
    /// Driving back after the bumper, a stalled FORWARD or a pushed one.
    BackingOff,
    /// Turning to one look of the sonar scan, or back.
    ScanLook,
    /// Waiting for the reading of a look of the scan.
    ScanReading,
    /// Driving back or forth before a turn so the turning body clears known echoes.
    ShiftingBeforeTurn,
    /// Turning back to the grid heading after a turn that failed.
    TurningBack,
    /// After a turn: turning on past the new heading and back, the sonar listening.
    LookingPastTurn,
    /// Driving back to the cell's centre after a turn made off it.
    Recentring,
    /// Facing the grid heading again after a STOP or a disconnect cut a turn or a look, or a look
    /// failed.
    Refacing,
}

impl Activity {
    /// The motion in progress rotates the body on the spot (a turn or a scan look) or shifts it
    /// before a turn.
    pub fn is_turning(self) -> bool {
        matches!(
            self,
            Activity::Turning
                | Activity::ScanLook
                | Activity::ShiftingBeforeTurn
                | Activity::TurningBack
                | Activity::LookingPastTurn
                | Activity::Recentring
                | Activity::Refacing
        )
    }

    /// In words.
    pub fn describe(self) -> &'static str {
        match self {
            Activity::Idle => "idle",
            Activity::BetweenCommands => "between commands",
            Activity::WaitingForReadings => "waiting for fresh readings",
            Activity::CheckingAhead => "checking the distance ahead",
            Activity::DrivingForward => "driving forward",
            Activity::Turning => "turning",
            Activity::BackingOff => "backing off after the bumper, a stall or a push",
            Activity::ScanLook => "turning to look (scan)",
            Activity::ScanReading => "reading the sonar (scan)",
            Activity::ShiftingBeforeTurn => "shifting before a turn",
            Activity::TurningBack => "turning back after a failed turn",
            Activity::LookingPastTurn => "looking past the end of a turn",
            Activity::Recentring => "driving back to the cell's centre after a turn off it",
            Activity::Refacing => "facing the grid heading again after a cut turn",
        }
    }
}
