//! A FORWARD stopped short, by the bumper, a stall or a push: the motors stop, the cell ahead
//! is reported blocked, and the robot backs off to the cell it started from (over its sliding
//! way when it was slid) before `MOVE_DONE` (module docs of `pilot.rs`).

use super::stall::Stall;
use super::{Io, Pilot, Stage};

impl Pilot {
    pub(super) fn bumped(&mut self, io: &mut Io<'_>) {
        io.motor.stop(io.now);
        self.counters.bumps += 1;
        tracing::warn!(travelled_m = ?io.motor.travelled_m(io.sensors), "bumper pressed during FORWARD: stopped");
        self.end_stopped_forward(io);
    }

    /// Something turned the body under its wheels during a FORWARD: stop and end as after the
    /// bumper (module docs, "Pushed").
    pub(super) fn pushed(&mut self, io: &mut Io<'_>) {
        io.motor.stop(io.now);
        self.counters.pushes += 1;
        tracing::warn!(
            travelled_m = ?io.motor.travelled_m(io.sensors),
            "the IMU saw the body turned under its wheels during a FORWARD: stopped"
        );
        self.end_stopped_forward(io);
    }

    /// Ends a FORWARD stopped short (the bumper, a stall, a push): the echoes heard while it
    /// drove are forgotten (placed from odometry that did not see what stopped it), the cell
    /// ahead is reported blocked, and the robot drives back before `MOVE_DONE`.
    fn end_stopped_forward(&mut self, io: &mut Io<'_>) {
        self.echoes.forget_moving();
        self.place.touched();
        self.report_obstacle();
        self.back_off_or_end(io);
    }

    /// The FORWARD is stalled (`pilot/stall.rs`): stop, take the sonar's word for how far the
    /// body went, report the cell ahead as blocked and drive back, as after the bumper.
    pub(super) fn stalled(&mut self, io: &mut Io<'_>, stall: Stall) {
        io.motor.stop(io.now);
        self.counters.stalls += 1;
        tracing::warn!(
            driven_m = stall.driven_m,
            wheels_m = stall.wheels_m,
            "FORWARD stalled: the range held while the wheels drove; stopped"
        );
        // the wheels went on after that echo while the body stood: the odometry now says where
        // the sonar put the body
        let now_m = io.motor.cell_offset(io.now, io.sensors).along_m;
        io.motor.correct_along(self.forward.stall_correction_m(stall, now_m));
        self.end_stopped_forward(io);
    }

    /// After a FORWARD stopped short: drive back to the cell it started from (over its sliding
    /// way, when it was slid: `pilot/sliding.rs`), then `MOVE_DONE` (at once when the motor
    /// cannot start the way back).
    pub(super) fn back_off_or_end(&mut self, io: &mut Io<'_>) {
        if self.retrace_slide(io) {
            self.stage = Stage::BackingOff;
            return;
        }
        match io.motor.start_return(io.now, io.sensors) {
            Ok(()) => {
                self.stage = Stage::BackingOff;
                return;
            }
            Err(e) => tracing::warn!(error = %e, "cannot back off"),
        }
        self.end_task(io.now);
    }
}
