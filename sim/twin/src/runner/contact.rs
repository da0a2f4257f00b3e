//! What the runner notes about contacts as they happen: stops, obstacle reports, and the
//! first contact with what Carto was doing and what the truth says of it.

use robot_model::grid::GridPose;
use robot_model::time::Instant;

use super::Lockstep;
use crate::localisation::carto_belief;
use crate::oracle::to_carto_frame;
use crate::report::{ContactCause, FirstContact, HEARD_NEAR_M, Heard};

impl Lockstep {
    /// A debug line when Carto stops a FORWARD as stalled (`carto/src/control/pilot/stall.rs`) or pushed
    /// (`carto/src/control/pilot.rs`, "Pushed"): where the robot really is, how far from it Carto's
    /// belief now lies, and how many collisions the run has had so far (a push stop whose count
    /// did not rise since the FORWARD began, nor in the seconds before it, touched nothing).
    pub(super) fn note_stop(&self, now: Instant, what: &str) {
        let p = self.twin.body().pose();
        let believed = self.carto.carto().believed_pose();
        let belief_error_m = believed
            .and_then(|(pose, offset)| carto_belief(&self.truth.frame, pose, offset))
            .map(|(bx, by)| (p.x - bx).hypot(p.y - by));
        let along = self.along_true_and_believed();
        tracing::debug!(
            t_s = now.as_secs_f64(),
            x = p.x,
            y = p.y,
            ?belief_error_m,
            true_along_m = along.map(|a| a.0),
            carto_along_m = along.map(|a| a.1),
            collisions = self.twin.body().world().collisions(),
            "{what}"
        );
    }

    /// How far the body really is from the centre of the cell Carto believes it is in, along the
    /// stored heading, and how far Carto believes, metres.
    pub(super) fn along_true_and_believed(&self) -> Option<(f32, f64)> {
        let p = self.twin.body().pose();
        let (pose, offset) = self.carto.carto().believed_pose()?;
        let (cx, cy) = carto_belief(&self.truth.frame, pose, Default::default())?;
        let (sin, cos) = pose.heading.world_angle().sin_cos();
        Some(((p.x - cx) * cos + (p.y - cy) * sin, offset.along_m))
    }

    /// A debug line for each cell Carto reports blocked (`SET_OBSTACLE_POSITION`): what the truth
    /// says of the move it refused, so that blocks of free moves can be counted.
    pub(super) fn note_obstacle_report(&self, now: Instant) {
        let p = self.twin.body().pose();
        let Some((pose, _)) = self.carto.carto().believed_pose() else { return };
        let along = self.along_true_and_believed();
        tracing::debug!(
            t_s = now.as_secs_f64(),
            x = p.x,
            y = p.y,
            from = ?(pose.x, pose.y),
            to = ?pose.ahead(),
            true_cell = ?self.twin.cell(),
            true_along_m = along.map(|a| a.0),
            carto_along_m = along.map(|a| a.1),
            move_exists = ?self.move_ahead_exists(pose),
            "Carto reported the cell ahead blocked"
        );
    }

    /// Whether the truth has the FORWARD from `pose`'s cell to the one ahead (`None` off the
    /// grid).
    pub(super) fn move_ahead_exists(&self, pose: GridPose) -> Option<bool> {
        let (r, c) = pose.ahead()?;
        Some(
            self.truth.can_move((usize::from(pose.x), usize::from(pose.y)), (usize::from(r), usize::from(c))),
        )
    }

    /// Notes a new contact: the report's [`FirstContact`], and a debug line for each one with
    /// when, where the robot really is, where Carto and Cute believe it is, what Carto was doing
    /// and what the truth says of the cell and of the move ahead (`RUST_LOG=crate::runner=debug`).
    pub(super) fn note_contact(&mut self, now: Instant) {
        let p = self.twin.body().pose();
        let cell = self.twin.cell();
        let carto = self.carto.carto();
        let activity = carto.activity();
        let believed = carto.believed_pose();
        let carto_believes =
            believed.and_then(|(pose, offset)| carto_belief(&self.truth.frame, pose, offset));
        // Whether the FORWARD Carto may be driving from its stored cell exists in the truth.
        let move_ahead_exists = believed.and_then(|(pose, _)| self.move_ahead_exists(pose));
        let cell_turnable = cell.map(|(r, c)| self.truth.can_turn(r, c));
        tracing::debug!(
            t_s = now.as_secs_f64(),
            x = p.x,
            y = p.y,
            heading_deg = p.theta.to_degrees(),
            ?cell,
            ?cell_turnable,
            ?carto_believes,
            cute_believes = ?self.cute.cute().robot(),
            carto = activity.describe(),
            ?move_ahead_exists,
            "collision: new contact"
        );
        if self.first_contact.is_none() {
            let off_centre_m = cell.map_or(0.0, |(r, c)| {
                let (cx, cy) = self.truth.frame.cell_center(r, c);
                f64::from((p.x - cx).hypot(p.y - cy))
            });
            let start = self.twin.body().world().contacts_started().first().copied();
            self.first_contact = Some(FirstContact {
                t_s: now.as_secs_f64(),
                cell,
                carto_activity: activity.describe().to_string(),
                off_centre_m,
                belief_error_m: carto_believes.map(|(bx, by)| f64::from((p.x - bx).hypot(p.y - by))),
                cause: ContactCause::classify(activity, move_ahead_exists, cell_turnable),
                touched: start.map(|c| c.touched),
                touched_heard: start.map(|c| {
                    match self.twin.body().first_heard_near(c.part, c.at, HEARD_NEAR_M) {
                        Some(h) => Heard::Before {
                            first_s: h.first.as_secs_f64(),
                            nearest_m: f64::from(h.nearest_m),
                        },
                        None => Heard::Never,
                    }
                }),
                touched_held_m: start.and_then(|c| self.nearest_held_echo_m(c.at)),
            });
        }
    }

    /// How far from the world point `at` the nearest echo point Carto holds lies, metres, with
    /// Carto's grid frame laid on the true one (`None` when it holds none).
    pub(super) fn nearest_held_echo_m(&self, at: (f32, f32)) -> Option<f64> {
        let (ax, ay) = to_carto_frame(&self.truth.frame, (f64::from(at.0), f64::from(at.1)));
        self.carto.carto().echo_points().map(|(x, y)| (x - ax).hypot(y - ay)).min_by(f64::total_cmp)
    }
}
