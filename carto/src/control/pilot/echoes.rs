//! The echoes the safety checks ask (`pilot/safety.rs`): those heard at rest (and a floor plan
//! given beforehand), and those heard moving, in turns, looks and FORWARDs, each kept on the
//! cone's edge farther from the line of the FORWARD after it.
//!
//! Invariants: the echoes heard moving feed only the corridor checks, never the turn check, but
//! for the one that refused a FORWARD ([`Echoes::keep_as_at_rest`]); a reading at rest clears
//! both kinds where it saw through them and under the body; all points are in the frame of
//! [`crate::surroundings`], placed from the stored pose, so a new pose forgets them
//! ([`Echoes::forget`]); with a complete floor plan no reading adds a point
//! ([`Echoes::plan_is_complete`]).

use robot_model::time::Instant;

use super::limits::{ASIDE_STEP_M, FAR_SIGMAS, Safety};
use crate::odometry::CellOffset;
use crate::surroundings::{Pose2, Surroundings};

/// Where an echo in a FORWARD's corridor lies ([`Echoes::in_way`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Hit {
    /// Ahead of and left of the robot, metres.
    pub(super) at: (f64, f64),
    /// Heard moving rather than at rest.
    pub(super) heard_moving: bool,
}

/// The echo points the safety checks hold.
#[derive(Debug, Clone)]
pub(super) struct Echoes {
    /// The geometry of the checks.
    safety: Safety,
    /// Echoes heard at rest, and known surface points.
    at_rest: Surroundings,
    /// Echoes heard while the robot moved (in turns, looks and FORWARDs), each kept on the cone's
    /// edge farther from the line of the FORWARD after it (`pilot/safety.rs`, "Readings in
    /// turns", "Readings while driving", "Kept while they hold"): only the corridor checks ask
    /// them. The one that refuses a FORWARD is copied into `at_rest`.
    moving: Surroundings,
    /// When the last reading kept during a turn arrived.
    last_turn_reading: Option<Instant>,
    /// A complete floor plan is held: readings add no point ([`Echoes::plan_is_complete`]).
    plan_complete: bool,
}

impl Echoes {
    /// No echo yet.
    pub(super) fn new(safety: Safety) -> Echoes {
        Echoes {
            safety,
            at_rest: Surroundings::default(),
            moving: Surroundings::default(),
            last_turn_reading: None,
            plan_complete: false,
        }
    }

    /// The floor plan held is complete ([`crate::Carto::add_floor_plan`]): every surface is one
    /// of its points, so a reading adds none. An echo point stands for a surface anywhere across
    /// the cone and is placed on its axis or edge; beside the plan's exact points it only adds
    /// surfaces that are not there.
    pub(super) fn plan_is_complete(&mut self) {
        self.plan_complete = true;
        self.at_rest.clear();
        self.moving.clear();
    }

    /// Whether a complete floor plan is held ([`Echoes::plan_is_complete`]): space without a
    /// point is known free.
    pub(super) fn has_complete_plan(&self) -> bool {
        self.plan_complete
    }

    /// Every echo point held, in the grid's metric frame: those kept at rest and those heard
    /// moving (not the floor plan).
    pub(super) fn points(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.at_rest.points().chain(self.moving.points())
    }

    /// Known surface points ([`crate::Carto::add_known_surfaces`]).
    pub(super) fn add_fixed(&mut self, points: Vec<(f64, f64)>) {
        self.at_rest.add_fixed(points);
    }

    /// Forgets every echo point (a new pose from Cute, or none: they were placed from another).
    pub(super) fn forget(&mut self) {
        self.at_rest.clear();
        self.moving.clear();
    }

    /// Forgets the echoes heard moving: they were placed from odometry that was wrong (a
    /// FORWARD stopped short or failed).
    pub(super) fn forget_moving(&mut self) {
        self.moving.clear();
    }

    /// Whether a reading that arrived `at`, while a turn runs, is newer than the last one kept in
    /// a turn; it is then the last one.
    pub(super) fn take_turn_reading(&mut self, at: Instant) -> bool {
        if self.last_turn_reading.is_some_and(|t| at <= t) {
            return false;
        }
        self.last_turn_reading = Some(at);
        true
    }

    /// Keeps a reading taken at rest from `robot`: the echo `cm` from the sonar as a point
    /// (`None`: no echo), and clears the points it saw through and those under the body.
    pub(super) fn note_at_rest(&mut self, robot: Pose2, cm: Option<f32>) {
        if self.plan_complete {
            return;
        }
        let s = self.safety;
        let range = cm.map(|cm| f64::from(cm) / 100.0);
        self.at_rest.clear_footprint(robot, s.half_length_m, s.half_width_m);
        self.at_rest.add_reading(robot, s.mount_m, range, s.half_cone_deg, s.max_range_m);
        self.moving.clear_footprint(robot, s.half_length_m, s.half_width_m);
        if let Some(range) = range {
            self.moving.clear_seen_through(robot, s.mount_m, range, s.half_cone_deg, s.max_range_m);
        }
    }

    /// Keeps the echo `range` heard moving from `robot` as a point for the next FORWARD's
    /// corridor check, on the edge of the cone farther from that FORWARD's line (through `robot`,
    /// heading `line_deg`). The echo may come from anywhere across the cone: so placed, it
    /// blocks the FORWARD only when the whole arc lies in the body's path. It is kept
    /// [`FAR_SIGMAS`] sonar σ beyond its range too: a FORWARD hears ten readings a second, and
    /// the closest of many noisy readings of a wall just past the corridor's end would otherwise
    /// fall inside it.
    pub(super) fn keep_on_far_edge(&mut self, robot: Pose2, line_deg: f64, range: f64) {
        if self.plan_complete {
            return;
        }
        let s = self.safety;
        let range = range + FAR_SIGMAS * s.sonar_sigma_m;
        let line = Pose2 { yaw_deg: line_deg, ..robot };
        let (sx, sy) = robot.offset(s.mount_m, 0.0);
        let edge = |side: f64| Pose2 { x: sx, y: sy, yaw_deg: robot.yaw_deg + side * s.half_cone_deg };
        let beside_line = |edge: Pose2| line.local(edge.offset(range, 0.0)).1.abs();
        let (right, left) = (edge(-1.0), edge(1.0));
        let farther = if beside_line(right) >= beside_line(left) { right } else { left };
        self.moving.add_echo(farther, 0.0, range);
    }

    /// The first echo in the way of a FORWARD from `robot` to `to_m` ahead that ends on a track
    /// `track_m` left of it: one heard at rest first, else one heard moving. The way is the
    /// corridor from the sonar to `to_m`, `half_m` either side, and, when the body must strafe
    /// to its track (the motor holds the track while driving), the strip its flank sweeps getting
    /// there, from its back face on (`pilot/safety.rs`, "Corridor").
    pub(super) fn in_way(&self, robot: Pose2, to_m: f64, half_m: f64, track_m: f64) -> Option<Hit> {
        let first = |points: &Surroundings| {
            points
                .first_in_corridor(robot, self.safety.mount_m, to_m, half_m)
                .or_else(|| self.in_strafe_strip(points, robot, to_m, half_m, track_m))
        };
        if let Some(at) = first(&self.at_rest) {
            return Some(Hit { at, heard_moving: false });
        }
        Some(Hit { at: first(&self.moving)?, heard_moving: true })
    }

    /// The nearest of `points` in the strip beside `robot` that its flank sweeps strafing
    /// `track_m` to the left (to the right when negative) to its track, from its back face to
    /// `to_m` ahead, beyond the `half_m` either side its corridor covers; `None` without a strafe.
    fn in_strafe_strip(
        &self,
        points: &Surroundings,
        robot: Pose2,
        to_m: f64,
        half_m: f64,
        track_m: f64,
    ) -> Option<(f64, f64)> {
        if track_m == 0.0 {
            return None;
        }
        let beside = if track_m > 0.0 { (half_m, track_m + half_m) } else { (track_m - half_m, -half_m) };
        points.first_in_strip(robot, (-self.safety.half_length_m, to_m), beside)
    }

    /// Every point held, heard at rest, moving (unless `at_rest_only`) or known beforehand, as
    /// `(along, left)` from `frame`, within `along_m` and `left_m` of it (inclusive ranges,
    /// smaller bound first).
    pub(super) fn in_box(
        &self,
        frame: Pose2,
        along_m: (f64, f64),
        left_m: (f64, f64),
        at_rest_only: bool,
    ) -> Vec<(f64, f64)> {
        let mut points = self.at_rest.in_box(frame, along_m, left_m);
        if !at_rest_only {
            points.extend(self.moving.in_box(frame, along_m, left_m));
        }
        points
    }

    /// Keeps the echo heard moving at `at` (ahead, left of `robot`) from now on as if heard at
    /// rest: it refused a FORWARD, so the turn that may follow keeps clear of it too.
    pub(super) fn keep_as_at_rest(&mut self, robot: Pose2, at: (f64, f64)) {
        self.at_rest.add_point(robot, robot.offset(at.0, at.1));
    }

    /// The track nearest the line through the cells' centres (that line first), within
    /// [`Safety::aside_max_m`] of it, along which
    /// the FORWARD's corridor (`to_m` ahead, `half_m` either side) holds no echo point, from
    /// `robot`, whose believed position is `left_m` left of the line through the centres
    /// (`pilot/safety.rs`, "Corridor"). `None` when no such track clears.
    pub(super) fn sidestep(&self, robot: Pose2, left_m: f64, to_m: f64, half_m: f64) -> Option<f64> {
        let s = self.safety;
        let steps = (s.aside_max_m / ASIDE_STEP_M).floor() as i32;
        let tracks = (1..=steps).flat_map(|k| [f64::from(k) * ASIDE_STEP_M, -f64::from(k) * ASIDE_STEP_M]);
        std::iter::once(0.0).chain(tracks).find(|&track| {
            // the body strafes from where it stands to the track as it starts: the corridor on
            // the track is checked from the body's back face, beside it too
            let (x, y) = robot.offset(0.0, track - left_m);
            let on_track = Pose2 { x, y, ..robot };
            [&self.at_rest, &self.moving].iter().all(|points| {
                points.first_in_corridor(on_track, -s.half_length_m, to_m, half_m).is_none()
                    && self.in_strafe_strip(points, robot, to_m, half_m, track - left_m).is_none()
            })
        })
    }

    /// The nearest known echo (ahead, left of the body, metres) inside the circle the body sweeps
    /// turning at `robot`, after forgetting the echoes under the body: it stands there, so they
    /// came from a wrong pose. Both turn checks ask this. After a shift that ended off target the
    /// believed pose is the least sure, and an echo it puts under the body is forgotten all the
    /// same: a reading at rest would forget it too, and keeping it would refuse every turn from
    /// there.
    pub(super) fn in_turning_circle(&mut self, robot: Pose2) -> Option<(f64, f64)> {
        let s = self.safety;
        self.at_rest.clear_footprint(robot, s.half_length_m, s.half_width_m);
        self.at_rest.inside_circle(robot, s.turn_clear_m)
    }

    /// The smallest shift (ahead, left in the frame `frame`, metres, at most `max_m`, in steps of
    /// `step_m`) after which the turning circle holds no echo heard at rest
    /// ([`Surroundings::clearing_shift`]).
    pub(super) fn clearing_shift(&self, frame: Pose2, max_m: f64, step_m: f64) -> Option<(f64, f64)> {
        let s = self.safety;
        self.at_rest.clearing_shift(frame, s.turn_clear_m, max_m, step_m)
    }

    /// How much of the way from `robot` back to its cell's centre (`off` from it), in steps of
    /// `step_m`, the body and its clearance sweep no echo heard at rest: 0 to 1.
    pub(super) fn clear_part_of_way_back(&self, robot: Pose2, off: CellOffset, step_m: f64) -> f64 {
        let s = self.safety;
        let (hl, hw) = (s.half_length_m + s.clearance_m, s.half_width_m + s.clearance_m);
        // from where the body is towards the centre, as far as the way is clear
        let steps = (off.norm() / step_m).ceil() as i32;
        (1..=steps)
            .map(|k| f64::from(k) / f64::from(steps))
            .take_while(|&t| {
                let (x, y) = robot.offset(-off.along_m * t, -off.left_m * t);
                self.at_rest.first_in_corridor(Pose2 { x, y, ..robot }, -hl, hl, hw).is_none()
            })
            .last()
            .unwrap_or(0.0)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::CartoConfig;

    /// A robot 8 cm right of the line through the centres, facing east at the origin, and a
    /// known point 30 cm ahead and 18 cm left of it: outside the corridor ahead of the body
    /// (14 cm either side), but in the way of the body strafing back to the line while it drives.
    #[test]
    fn the_way_of_a_forward_includes_the_strip_the_body_strafes_through_to_its_track() {
        let cfg = CartoConfig::default();
        let mut echoes = Echoes::new(Safety::new(&cfg));
        echoes.add_fixed(vec![(0.30, 0.18)]);
        let robot = Pose2 { x: 0.0, y: 0.0, yaw_deg: 0.0 };
        let (to, half) = (0.45 + 0.13, 0.12 + 0.02);
        assert!(echoes.in_way(robot, to, half, 0.0).is_none(), "straight ahead, the way is clear");
        let hit = echoes.in_way(robot, to, half, 0.08).unwrap();
        assert!((hit.at.0 - 0.30).abs() < 1e-9 && (hit.at.1 - 0.18).abs() < 1e-9, "{:?}", hit.at);
        assert!(echoes.in_way(robot, to, half, -0.08).is_none(), "strafing the other way");
        // no track within 1 cm of the line clears it: the robot is 8 cm from the line
        assert_eq!(echoes.sidestep(robot, -0.08, to, half), None);
        // from the line itself, the point 10 cm left lies in the corridor; 5 cm further out it
        // does not, and the track on the line is taken
        let mut far = Echoes::new(Safety::new(&cfg));
        far.add_fixed(vec![(0.30, 0.23)]);
        assert_eq!(far.sidestep(robot, -0.08, to, half), Some(0.0));
    }

    /// With a complete floor plan a reading adds no point, heard at rest or moving; the plan's
    /// own points still stand in the way.
    #[test]
    fn with_a_complete_plan_readings_add_no_points() {
        let cfg = CartoConfig::default();
        let robot = Pose2 { x: 0.0, y: 0.0, yaw_deg: 0.0 };
        let (to, half) = (0.45 + 0.13, 0.12 + 0.02);
        let mut heard = Echoes::new(Safety::new(&cfg));
        heard.note_at_rest(robot, Some(30.0));
        heard.keep_on_far_edge(robot, 0.0, 0.5);
        assert!(heard.points().count() >= 2);
        let mut planned = Echoes::new(Safety::new(&cfg));
        planned.add_fixed(vec![(0.40, 0.0)]);
        planned.note_at_rest(robot, Some(30.0));
        planned.plan_is_complete();
        assert_eq!(planned.points().count(), 0, "the reading before the plan was forgotten");
        planned.note_at_rest(robot, Some(30.0));
        planned.keep_on_far_edge(robot, 0.0, 0.5);
        assert_eq!(planned.points().count(), 0);
        let hit = planned.in_way(robot, to, half, 0.0).unwrap();
        assert!((hit.at.0 - 0.40).abs() < 1e-9 && !hit.heard_moving, "{hit:?}");
    }
}
