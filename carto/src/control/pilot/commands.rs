//! Starting a command: checks that it can run (a pose, the grid, both boards, fresh readings),
//! then the obstacle check of a FORWARD or the (safe) turn.

use robot_model::grid::Move;
use robot_model::time::Instant;

use super::tasks::TaskKind;
use super::{Io, Pilot, Stage};

/// A failed re-facing this close to the grid heading lets the move start anyway, degrees
/// ([`Pilot::refacing_failed`]).
const REFACE_CLOSE_DEG: f64 = 10.0;
/// Re-facings that may fail in a row before the grid heading is learnt from the IMU again.
const REFACE_TRIES: u8 = 3;

impl Pilot {
    pub(super) fn start_command(&mut self, io: &mut Io<'_>, kind: TaskKind, command: Result<Move, u8>) {
        let mv = match command {
            Ok(mv) => mv,
            Err(other) => {
                self.counters.bad_values += 1;
                match kind {
                    TaskKind::Cartography => {
                        self.note(
                            "command is not a move",
                            true,
                            format!("cartography command {other} is not a move"),
                        );
                        self.counters.moves_failed += 1;
                        self.end_task(io.now);
                    }
                    TaskKind::Trajectory => {
                        self.note(
                            "command is not a move",
                            true,
                            format!("trajectory command {other} is not a move: skipped"),
                        );
                    }
                }
                return;
            }
        };
        if kind == TaskKind::Cartography && self.place.pose().is_none() {
            return self.fail(io.now, "no robot position yet");
        }
        if mv == Move::Forward && self.place.pose().is_some_and(|p| p.ahead().is_none()) {
            return self.fail(io.now, "the cell ahead is off the grid");
        }
        if !io.health.motor_board {
            return self.fail(io.now, "motor board lost");
        }
        if !io.health.sensor_board {
            return self.fail(io.now, "sensor board lost");
        }
        if self.readings_fresh(io) {
            self.begin_move(io, mv);
        } else {
            self.stage = Stage::Waiting { mv, since: io.now };
        }
    }

    /// Whether encoder counts and the IMU heading are both recent enough to start a move.
    pub(super) fn readings_fresh(&self, io: &Io<'_>) -> bool {
        let fresh = |at: Instant| io.now.saturating_since(at) <= self.stale_after;
        io.sensors.counts().is_some_and(|c| fresh(c.at)) && io.sensors.yaw_deg().is_some_and(|y| fresh(y.at))
    }

    pub(super) fn begin_move(&mut self, io: &mut Io<'_>, mv: Move) {
        if io.motor.rotation_was_cut() {
            // a STOP or a disconnect cut a turn or a look: face the stored heading again first
            tracing::info!(?mv, "facing the grid heading again after a cut rotation");
            return match io.motor.start_look(io.now, 0.0, io.sensors) {
                Ok(()) => self.stage = Stage::Refacing { mv },
                Err(e) => self.refacing_failed(io, mv, &e.to_string()),
            };
        }
        match mv {
            Move::Forward => self.stage = Stage::Checking { since: io.now },
            Move::Right | Move::Left => self.turn_safely(io, mv),
        }
    }

    /// Facing the grid heading again after a cut rotation failed (over `lossy-motor`'s damaged
    /// link a small rotation can stall long enough to count as jammed):
    /// - within [`REFACE_CLOSE_DEG`] of the reference, the move `mv` starts from where the body
    ///   faces: a FORWARD's heading hold and a turn's absolute target take the rest, and the
    ///   reference stays (learning it from the IMU here would take the angle the look stalled at
    ///   for the grid heading);
    /// - farther off, the move fails and the reference stays, so the next move faces it again;
    ///   after [`REFACE_TRIES`] such failures in a row the heading is learnt from the IMU again,
    ///   so the robot is never stuck refusing every move.
    pub(super) fn refacing_failed(&mut self, io: &mut Io<'_>, mv: Move, why: &str) {
        let off = io.motor.off_reference_deg(io.sensors);
        if off.is_some_and(|d| d.abs() <= REFACE_CLOSE_DEG) {
            tracing::warn!(why, off_deg = off, "facing the grid heading again failed close to it: moving on");
            self.reface_failures = 0;
            io.motor.accept_rotation_cut();
            // readings from now on are taken at rest, not during the stalled rotation
            self.rest_since = io.now;
            return self.begin_move(io, mv);
        }
        self.reface_failures += 1;
        if self.reface_failures >= REFACE_TRIES {
            self.reface_failures = 0;
            io.motor.forget_reference();
        }
        self.fail(io.now, &format!("facing the grid heading again: {why}"));
    }

    pub(super) fn start_turn(&mut self, io: &mut Io<'_>, mv: Move) {
        self.look_pending = None;
        match io.motor.start_turn(io.now, mv == Move::Right, io.sensors) {
            Ok(()) => self.stage = Stage::Moving { kind: mv, since: io.now },
            Err(e) => self.fail(io.now, &e.to_string()),
        }
    }
}
