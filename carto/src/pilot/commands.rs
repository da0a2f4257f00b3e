//! Starting a command: checks that it can run (a pose, the grid, both boards, fresh readings),
//! then the obstacle check of a FORWARD or the (safe) turn.

use robot_model::grid::Move;
use robot_model::time::Instant;

use super::{Pilot, Stage, TaskKind};
use crate::motor::Motor;
use crate::sensors::SensorState;

use super::Health;

/// A failed re-facing this close to the grid heading lets the move start anyway, degrees
/// ([`Pilot::refacing_failed`]).
const REFACE_CLOSE_DEG: f64 = 10.0;
/// Re-facings that may fail in a row before the grid heading is learnt from the IMU again.
const REFACE_TRIES: u8 = 3;

impl Pilot {
    pub(super) fn start_command(
        &mut self,
        now: Instant,
        kind: TaskKind,
        command: Result<Move, u8>,
        motor: &mut Motor,
        sensors: &SensorState,
        health: Health,
    ) {
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
                        self.end_task(now);
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
        if kind == TaskKind::Cartography && self.pose.is_none() {
            return self.fail(now, "no robot position yet");
        }
        if mv == Move::Forward && self.pose.is_some_and(|p| p.ahead().is_none()) {
            return self.fail(now, "the cell ahead is off the grid");
        }
        if !health.motor_board {
            return self.fail(now, "motor board lost");
        }
        if !health.sensor_board {
            return self.fail(now, "sensor board lost");
        }
        if self.readings_fresh(now, sensors) {
            self.begin_move(now, mv, motor, sensors);
        } else {
            self.stage = Stage::Waiting { mv, since: now };
        }
    }

    /// Whether encoder counts and the IMU heading are both recent enough to start a move.
    pub(super) fn readings_fresh(&self, now: Instant, sensors: &SensorState) -> bool {
        let fresh = |at: Instant| now.saturating_since(at) <= self.stale_after;
        sensors.counts().is_some_and(|c| fresh(c.at)) && sensors.yaw_deg().is_some_and(|y| fresh(y.at))
    }

    pub(super) fn begin_move(&mut self, now: Instant, mv: Move, motor: &mut Motor, sensors: &SensorState) {
        if motor.rotation_was_cut() {
            // a STOP or a disconnect cut a turn or a look: face the stored heading again first
            tracing::info!(?mv, "facing the grid heading again after a cut rotation");
            return match motor.start_look(now, 0.0, sensors) {
                Ok(()) => self.stage = Stage::Refacing { mv },
                Err(e) => self.refacing_failed(now, mv, motor, sensors, &e.to_string()),
            };
        }
        match mv {
            Move::Forward => self.stage = Stage::Checking { since: now },
            Move::Right | Move::Left => self.turn_safely(now, mv, motor, sensors),
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
    pub(super) fn refacing_failed(
        &mut self,
        now: Instant,
        mv: Move,
        motor: &mut Motor,
        sensors: &SensorState,
        why: &str,
    ) {
        let off = motor.off_reference_deg(sensors);
        if off.is_some_and(|d| d.abs() <= REFACE_CLOSE_DEG) {
            tracing::warn!(why, off_deg = off, "facing the grid heading again failed close to it: moving on");
            self.reface_failures = 0;
            motor.accept_rotation_cut();
            // readings from now on are taken at rest, not during the stalled rotation
            self.rest_since = now;
            return self.begin_move(now, mv, motor, sensors);
        }
        self.reface_failures += 1;
        if self.reface_failures >= REFACE_TRIES {
            self.reface_failures = 0;
            motor.forget_reference();
        }
        self.fail(now, &format!("facing the grid heading again: {why}"));
    }

    pub(super) fn start_turn(&mut self, now: Instant, mv: Move, motor: &mut Motor, sensors: &SensorState) {
        self.look_pending = None;
        match motor.start_turn(now, mv == Move::Right, sensors) {
            Ok(()) => self.stage = Stage::Moving { kind: mv, since: now },
            Err(e) => self.fail(now, &e.to_string()),
        }
    }
}
