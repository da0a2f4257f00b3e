//! The pilot's side of the link session: requests from Cute ([`Pilot::handle`]) and the
//! events of the links (a disconnect, a board fault, a lost link), which stop the motors and
//! drop work.
//!
//! Invariants: a request never interrupts a running task (only STOP does); STOP, a disconnect
//! and a lost board link drop the running task, the queued ones and the partial batch without
//! `MOVE_DONE`, while a board fault fails only the running move, whose task ends with
//! `MOVE_DONE`; a pose that differs from the stored one forgets the echoes, the belief's surfaces
//! and the odometry's offset.

use robot_model::grid::{GridPose, Move};
use robot_model::time::Instant;

use super::{Pilot, Reply, Request, Stage};
use crate::motor::Motor;

impl Pilot {
    /// Handles one request from Cute.
    pub fn handle(&mut self, now: Instant, req: Request, motor: &mut Motor) {
        match req {
            Request::SetPose { x, y, direction } => {
                match direction {
                    Ok(heading) => {
                        let pose = GridPose { x, y, heading };
                        self.note(
                            "robot position received",
                            false,
                            format!("robot position received: {pose}"),
                        );
                        // A new pose names a cell: the robot is taken to be at its centre. The
                        // pose Carto already holds (Cute re-sends it after a reconnect) keeps the
                        // dead-reckoned offset, e.g. of a FORWARD cut short by the disconnect, so
                        // the next move still ends on a cell centre.
                        if self.place.set_pose(pose) {
                            self.sliding.forget_way_in();
                            self.look_pending = None;
                            self.reface_failures = 0;
                            if motor.rotation_was_cut() {
                                // the body faces where the new pose says: learn it from the IMU
                                motor.forget_reference();
                            }
                            motor.reset_odometry();
                            self.echoes.forget();
                        }
                    }
                    Err(direction) => {
                        self.counters.bad_values += 1;
                        self.note(
                            "robot position with an invalid direction",
                            true,
                            format!(
                                "robot position ({x}, {y}) with an invalid direction {direction}: not stored"
                            ),
                        );
                    }
                }
                self.replies.push(Reply::PositionReceived);
            }
            Request::Cartography { command } => {
                self.tasks.push_cartography(command);
            }
            Request::Trajectory { n_total, command } => self.trajectory_frame(n_total, command),
            Request::Stop => {
                let dropped = self.pending();
                self.note("stop", false, format!("stop: motors stopped, {dropped} pending commands dropped"));
                self.drop_everything(now, motor);
            }
            Request::Ignored { msg } => {
                tracing::debug!(msg = format_args!("{msg:#06x}"), "message ignored");
            }
        }
    }

    fn trajectory_frame(&mut self, n_total: u8, command: Result<Move, u8>) {
        if n_total == 0 {
            self.counters.bad_values += 1;
            self.note(
                "trajectory frame with n_total 0",
                true,
                format!("trajectory frame with n_total 0 ignored (command {command:?})"),
            );
            return;
        }
        let framed = self.tasks.add_frame(n_total, command);
        if let Some((n, len)) = framed.discarded {
            self.counters.batches_discarded += 1;
            self.note(
                "n_total changed",
                true,
                format!("n_total changed from {n} to {n_total}: partial batch of {len} discarded"),
            );
        }
        if let Some(n) = framed.completed {
            self.note("trajectory batch complete", false, format!("trajectory batch of {n} complete"));
        }
    }

    /// Stops the motors and forgets every pending command, the partial batch and unsent replies
    /// (Cute went away).
    pub fn on_disconnect(&mut self, now: Instant, motor: &mut Motor) {
        self.drop_everything(now, motor);
        self.replies.clear();
    }

    /// A board failed while a task may be running: the motors stop, the current move fails and
    /// its task ends with `MOVE_DONE`. Queued tasks stay (they will fail in turn while the board
    /// is down).
    pub fn on_fault(&mut self, now: Instant, motor: &mut Motor, why: &str) {
        motor.stop(now);
        if matches!(self.stage, Stage::Next) {
            return;
        }
        if self.tasks.running() {
            tracing::warn!(why, "current move failed");
            self.counters.moves_failed += 1;
            self.end_task(now);
        }
    }

    /// A board link went away (unplugged, twin restarted): the motors stop and the current task,
    /// the queued ones and the partial batch are dropped **without** `MOVE_DONE` — the moves did
    /// not happen, so nothing claims they ended. Replies already earned (a `SET_ROBOT_POSITION`
    /// of a completed FORWARD) stay. Cute's move timeout then reports the missing `MOVE_DONE`.
    pub fn on_link_lost(&mut self, now: Instant, motor: &mut Motor, why: &str) {
        if self.tasks.running() {
            self.counters.moves_failed += 1;
        }
        let dropped = self.pending();
        if self.tasks.running() || dropped > 0 {
            tracing::warn!(why, dropped, "moves dropped, no MOVE_DONE: the robot did not make them");
        }
        self.drop_everything(now, motor);
    }

    fn drop_everything(&mut self, now: Instant, motor: &mut Motor) {
        motor.stop(now);
        self.place.forget_last_reading();
        self.look_pending = None;
        self.reface_failures = 0;
        let mapping = self.tasks.mapping();
        if let (Stage::LookingPast { unacked: Some(turn), .. } | Stage::Recentring { turn }, true) =
            (self.stage, mapping)
        {
            self.unmake_turn(turn, motor);
        }
        if !matches!(self.stage, Stage::Next) {
            // stopped in the middle of a scan or a shift: the robot may face off the grid heading
            // and is somewhere Carto did not plan; what it saw from there is not trusted
            self.echoes.forget();
        }
        self.tasks.clear();
        self.sliding.forget_way_in();
        self.stage = Stage::Next;
        self.rest_since = now;
    }

    /// A STOP or a disconnect cut the look or the drive back after the mapping turn `turn`
    /// (made off the centre), before its `MOVE_DONE`: for Cute that turn did not happen, so Carto
    /// takes back its stored heading and reference, and the next move faces that heading again
    /// first ([`Motor::rotation_was_cut`]), as after a turn cut in the middle. Keeping the new
    /// heading put the body 90° off the heading both held once Cute re-sent its pose and the
    /// turn.
    fn unmake_turn(&mut self, turn: Move, motor: &mut Motor) {
        let Some(pose) = self.place.unmake_turn(turn) else {
            return;
        };
        motor.turn_reference(if turn == Move::Left { -90.0 } else { 90.0 });
        motor.mark_rotation_cut();
        tracing::info!(
            ?pose,
            "cut before the MOVE_DONE of a turn made off the centre: the turn is taken back"
        );
    }
}
