//! The pilot's safety checks: the sonar scan and the swept-body check before a
//! FORWARD, and the turning-circle check before a turn, against the echo points of
//! [`crate::surroundings`].
//!
//! - **Scan.** After the straight reading of a FORWARD is clear, the robot looks
//!   [`Safety::scan_deg`](crate::config::Safety::scan_deg) to the left, then to the right, taking one reading at rest each, and
//!   turns back to the grid heading. A reading that does not come within
//!   [`Safety::distance_wait`](crate::config::Safety::distance_wait) leaves the scan incomplete and the FORWARD is not driven
//!   (never drive blind); the robot still turns back first.
//! - **Corridor.** The FORWARD runs only if no echo point lies in the rectangle the body sweeps:
//!   as wide as the body plus [`Safety::clearance_m`](crate::config::Safety::clearance_m) either side, from the front face to the
//!   front face at the next cell's centre (a straight echo blocks exactly as the one-cell
//!   threshold does). A body off the line through the centres (a turn made off the centre, a
//!   stop within its tolerance) strafes back to its track while it drives: the strip its flank
//!   sweeps on the way there, from its back face to the corridor's end, must hold no point
//!   either. When an echo point lies in the way, the FORWARD may run on a track beside the
//!   line through the centres, up to [`Safety::stop_within_m`](crate::config::Safety::stop_within_m) less
//!   [`Motion::lateral_tolerance_m`](crate::config::Motion::lateral_tolerance_m) from it (the move ends within that tolerance of its
//!   track), in steps of [`ASIDE_STEP_M`](super::limits::ASIDE_STEP_M), nearest first: the corridor along that track must hold
//!   no point (the mecanum wheels strafe to it while driving; the body's own footprint is free).
//!   The reason: a passage that leaves the body less than the clearance at the centre, but
//!   enough a centimetre aside, is one the twin counts as reachable, and without the step aside
//!   the robot that came through it one way was refused the way back, a trap Cute could not
//!   leave. When no track clears and a complete floor plan is given, the FORWARD may go by a
//!   sliding way through its two cells (`pilot/sliding.rs`, [`crate::slide`]). When none exists
//!   either, the answer says what the point is evidence of. A point inside the body standing at
//!   the next centre makes the cell ahead occupied: `SET_OBSTACLE_POSITION`, as for a close
//!   straight echo. With a complete floor plan the cell is occupied only when the body itself
//!   cannot stand in it within [`Safety::stop_within_m`](crate::config::Safety::stop_within_m)
//!   of its centre ([`crate::slide::fits_near`], keeping no clearance), whatever was met, a close
//!   straight echo too (unless the bumper is pressed). A point anywhere else in the corridor (on
//!   the way, or within the clearance beside the body) says only that the way is not clear:
//!   `SET_OBSTACLE_POSITION`, then `SET_ROBOT_POSITION` with the robot's own cell, which Cute
//!   reads as a blocked move, the cell left unknown (`protocol/README.md`, "Refused FORWARD").
//! - **Footprint.** Before every reading at rest and every turn check, the points inside the
//!   body's rectangle where Carto believes it stands are forgotten, the echoes heard moving
//!   (below) too ([`crate::surroundings::Surroundings::clear_footprint`]).
//! - **Turns.** A turn starts only if no echo point lies inside the circle the body sweeps (half
//!   its diagonal plus the clearance). Otherwise, with a complete floor plan, the body slides in
//!   its cell to the nearest place where the circle clears (`pilot/sliding.rs`); without one,
//!   Carto first drives back or forth along its heading, by the smallest shift (from 2 cm, twice
//!   the distance tolerance, in 1 cm steps, at most a quarter cell) after which the circle is
//!   clear. "Its heading" is the heading of the
//!   last FORWARD, not the one the body faces: back along it is the way the body came (space it
//!   swept), ahead is where it ranged; after a turn on the spot, behind the new heading is space
//!   no reading covered, and a shift there met walls never heard; when none is, it refuses the turn:
//!   the reason is logged and the command answered with `MOVE_DONE` only — the link protocol has
//!   no message that could carry the reason, so Cute takes the turn as done (a known limit,
//!   `docs/explanation/carto-design.md`). A shift that ends outside its tolerance is checked again from
//!   where the robot believes it stopped: the turn runs if the circle is clear from there.
//! - **Back to the centre.** A turn made more than [`RECENTRE_FROM_M`] from its cell's centre
//!   (after such a shift, or any other offset: an along-track fix, a stall's correction, an
//!   offset kept across a reconnect) ends with the body driving back towards the centre,
//!   holding the new heading, before the turn's `MOVE_DONE`: Cute believes the robot stands at
//!   its cell's centre, the next FORWARD's corridor check is made from there, and a run's
//!   position error is measured from it at every `MOVE_DONE`. Mapping, the look past the turn
//!   runs first, where the turning circle was clear. The drive stops where a known echo would come into the body's rectangle plus the
//!   clearance (the body turned 90° is 1 cm longer across the old heading than before); the
//!   next FORWARD takes the rest back. A STOP or a disconnect in the look or the drive, before
//!   the `MOVE_DONE`, takes the turn back in Carto's belief (Cute never heard of it), and the
//!   next move faces the old heading first, as after a turn cut in the middle.
//!
//! - **Belief.** Every straight reading at rest goes to the localiser
//!   ([`crate::estimate::localiser`]): the pose filter, grown by the motion since the last
//!   reading, corrects the position along the heading from the range to a surface heard before
//!   from the same row or column, or to the one heard from the cell behind (with a floor plan,
//!   against the plan in every direction), and the odometry is moved by the correction. A bump,
//!   a push or a stall widens the belief first, so the gate opens and the next readings weigh
//!   more than the wheels.
//!
//! - **Looking aside.** One forward sonar measures the position along the heading only; across
//!   it the belief grows with every cell driven (the IMU's heading error turns into a sideways
//!   error), and nothing corrects it until the robot faces another way. With a floor plan (the
//!   twin's `--known-room`) a surface beside the row can be asked instead: when, after the
//!   straight reading at rest has cleared a FORWARD, the belief's standard deviation across the
//!   heading exceeds [`super::localisation::LOOK_ASIDE_SIGMA_M`] (a third of the 5 cm a run's
//!   belief may be off), no scan is configured and the turning circle holds no known echo, the
//!   robot turns
//!   [`LOOK_ASIDE_DEG`] towards the side where the plan puts the nearer echo (within
//!   [`crate::estimate::localiser::LOOK_ASIDE_MAX_M`]). When neither side has one there (the
//!   middle of an open room), it turns a quarter turn instead, towards the nearer echo within
//!   [`QUARTER_LOOK_MAX_M`]: a surface faced square gives a range that depends on the heading
//!   to second order only, so a far one still places the body across the row. Neither: no
//!   look. It takes one reading at rest, corrects the belief from it against the plan
//!   ([`crate::estimate::localiser::Localiser::at_look`]) and turns back before the corridor
//!   check. One look, not two: one range across the row is what the belief lacks. Without a
//!   plan there is no look: the echoes heard so far are placed from the belief being
//!   corrected, and a range to them would measure nothing.
//! - **Readings in turns.** The sonar keeps measuring while the robot turns on the spot. A
//!   reading that arrives while the heading is within [`TURN_READING_WINDOW_DEG`] of the turn's
//!   target, with an echo no farther than one cell, is kept:
//!   near the end of a turn the cone sweeps beside the path of the FORWARD that may follow,
//!   where the straight reading at rest does not look (a chair leg or a box corner at the side
//!   of the next cell), and it sees a sofa too close for the reading at rest (an echo under
//!   the HC-SR04's 2 cm minimum reads "no echo"). They are kept as long as the echoes heard at
//!   rest are (below, "Kept while they hold"). The heading is
//!   the IMU's, carried at the yaw rate to when the sonar measured ([`Sonar::lag`](crate::config::Sonar::lag),
//!   half its cycle, before the frame arrived; carried at most
//!   [`Boards::max_extrapolation`](crate::config::Boards::max_extrapolation)). The echo could come from anywhere across the cone; it
//!   is kept on the cone's edge farther from the next FORWARD's line (the heading's line through
//!   where the robot was), [`FAR_SIGMAS`](super::limits::FAR_SIGMAS) sonar σ beyond its range, so it blocks that FORWARD
//!   only when the whole arc lies in the body's path. These points feed only the corridor
//!   check, never the turn check (but for the one that refuses a FORWARD, "Kept while they
//!   hold"): a turn would shift away from an echo whose position is this uncertain. Readings at
//!   rest clear them as they clear the others.
//!
//!   The end of a turn sweeps the cone across one side of the next FORWARD's path only (the
//!   side the turn comes from). So after a mapping turn and its `MOVE_DONE` the robot turns on
//!   past the new heading, the way the turn went, by [`Safety::look_past_turn_deg`](crate::config::Safety::look_past_turn_deg), and
//!   back, as a look (the reference heading stays), and keeps the readings of that sweep (all
//!   of them, within the look's angle plus 5°) by the same rules: the other side. Cute's next
//!   command waits in the queue meanwhile; the `MOVE_DONE` has gone out, so Cute and Carto agree
//!   on the heading whatever cuts the look (a cut look is faced again before the next move,
//!   [`crate::motor::Motor::rotation_was_cut`]). The body sweeps
//!   almost nothing new: turning 90° on the spot, its four corners have just swept the whole
//!   turning circle's rim but for two arcs of 5°. Trajectory batches do not look: their one
//!   `MOVE_DONE` ends the batch, so after a STOP Cute cannot tell which of its turns were made,
//!   and a look would make a STOP land before the batch's first position more often. With a
//!   complete floor plan there is no look either: a reading adds no point then (the plan holds
//!   every surface), so the look would only cost its time.
//! - **Readings while driving.** The sonar keeps measuring while a FORWARD drives, and from
//!   farther back its cone is wider: 24 cm across at 0.9 m, about the body's width, against
//!   12 cm at 0.45 m, from the next cell's centre. Every echo heard while a FORWARD drives, no
//!   farther than the next FORWARD's corridor can reach, is kept,
//!   placed from where the odometry, carried to when the
//!   sonar measured, says the robot was, on the cone's edge farther from the heading's line as
//!   a reading in a turn is, and a little beyond its range: [`FAR_SIGMAS`](super::limits::FAR_SIGMAS) sonar σ (the closest
//!   of the ten readings a second of a wall just past the corridor's end would otherwise fall
//!   inside it) plus [`CartoConfig::drive_timing_m`](crate::CartoConfig::drive_timing_m), the distance the robot drives in the
//!   sonar's mean lag (the frame carries a result measured 0–2 mean lags before it; one is
//!   assumed, so a fresher one was heard from up to that much farther on). The margin also
//!   covers the along-track shortening of the edge's placement, r·(1 − cos 7.5°): 8 mm at
//!   0.9 m. They feed the corridor checks, as the readings in turns do, and are forgotten at
//!   once when this FORWARD does not end on its cell (the bumper, a stall, a failed move: they
//!   were placed from odometry that was wrong): a chair leg or a box corner beside the next
//!   cell's path, outside the cone from the cell the robot stops in, blocks that FORWARD. With
//!   0.45 m cells an echo whose along-track place lies in the next corridor was heard from at
//!   most 0.9 m, where the whole arc lies in the body's path.
//! - **Kept while they hold.** The echoes heard moving (in turns, looks and FORWARDs) stay until
//!   a reading at rest sees through them, the body stands on them, the robot is
//!   [`crate::surroundings::FORGET_BEYOND_M`] away, or Cute sends a new pose, as the echoes
//!   heard at rest do; they are not forgotten when the next FORWARD or turn starts. The turn
//!   check does not ask them, with one exception: the point that refuses a FORWARD is kept from
//!   then on as if heard at rest, so the turn Cute asks for next (it usually turns away from a
//!   refused cell) keeps clear of it too: Carto has just acted on that point.
//!
//! Without a pose from Cute (the original Cute's trajectories) the points cannot be placed on the
//! grid across moves: they are kept for one FORWARD's check only and turns are not checked.

use robot_model::grid::Move;
use robot_model::time::Instant;

use super::forward::DriveReading;
use super::localisation::heading_deg;
use super::{Io, Pilot, Stage};
use crate::estimate::localiser::LOOK_ASIDE_MAX_M;
use crate::estimate::sonar::Reading;
use crate::surroundings::Pose2;

/// Step of the shift search before a turn, metres.
const SHIFT_STEP_M: f64 = 0.01;
/// A turn made farther than this from its cell's centre is followed by a drive back to the
/// centre, metres: a move ends within 1 cm, a shift is at least 2 cm, and a run's position error
/// is measured from the centre of the cell Cute believes at every `MOVE_DONE`.
const RECENTRE_FROM_M: f64 = 0.03;
/// Readings in turns are kept only while the heading is this close to the turn's target,
/// degrees: they look beside the path of the FORWARD that may follow.
pub(super) const TURN_READING_WINDOW_DEG: f64 = 20.0;
/// How far each way a look aside turns the body, degrees: a range taken there measures the
/// position mostly across the heading (sin 60° = 0.87 of it).
pub(super) const LOOK_ASIDE_DEG: f64 = 60.0;
/// With nothing within reach of a look aside, the body turns this far instead, degrees: a
/// quarter turn, square to the surfaces along the row.
pub(super) const QUARTER_LOOK_DEG: f64 = 90.0;
/// A quarter look faces a surface up to this far: a range taken square to it depends on the
/// heading to second order only, metres.
pub(super) const QUARTER_LOOK_MAX_M: f64 = 3.0;
impl Pilot {
    /// The looks before this FORWARD (the signs of each, the last back to the grid heading) and
    /// their angle: the scan's, else a look aside when one is due, else none.
    fn looks_now(&self) -> (&'static [f64], f64) {
        match (self.safety.scan_deg, self.looking_aside) {
            (deg, _) if deg > 0.0 => (self.safety.looks(), deg),
            (_, Some((side, deg))) if side > 0.0 => (&[1.0, 0.0], deg),
            (_, Some((_, deg))) => (&[-1.0, 0.0], deg),
            _ => (&[], 0.0),
        }
    }

    /// Decides, after the straight reading at rest has cleared a FORWARD, whether it starts with
    /// a look aside (module docs, "Looking aside"): no scan is configured, one is due, and the
    /// turning circle holds no known echo.
    pub(super) fn plan_look_aside(&mut self, io: &Io<'_>) {
        self.looking_aside = None;
        let Some(robot) = self.place.believed(io) else { return };
        if self.safety.scan_deg > 0.0
            || !self.place.wants_look_aside(io.now, robot)
            || self.echoes.in_turning_circle(robot).is_some()
        {
            return;
        }
        let localiser = self.place.localiser();
        self.looking_aside = localiser
            .look_aside_side(robot, LOOK_ASIDE_DEG, LOOK_ASIDE_MAX_M)
            .map(|side| (side, LOOK_ASIDE_DEG))
            .or_else(|| {
                localiser
                    .look_aside_side(robot, QUARTER_LOOK_DEG, QUARTER_LOOK_MAX_M)
                    .map(|side| (side, QUARTER_LOOK_DEG))
            });
        if self.looking_aside.is_some() {
            self.counters.looks_aside += 1;
        }
    }
}

impl Pilot {
    /// Corrects the belief from the straight reading `cm` taken at rest now (module docs,
    /// "Belief").
    pub(super) fn localise(&mut self, io: &mut Io<'_>, cm: Option<f32>) {
        if self.place.at_rest(io, cm) {
            self.counters.pose_fixes += 1;
        }
    }

    /// Keeps a reading taken at rest: the echo `cm` from the sonar as a point (`None`: no echo),
    /// and clears the points it saw through.
    pub(super) fn note_reading(&mut self, io: &Io<'_>, cm: Option<f32>) {
        if let Some(robot) = self.place.believed(io) {
            self.echoes.note_at_rest(robot, cm);
        }
    }

    /// Keeps the newest reading if it arrived while a turn or a look past one, started at
    /// `since`, runs towards `target_deg` from the stored pose's heading, and the heading lies
    /// within `window_deg` of that target (module docs, "Readings in turns").
    pub(super) fn note_turn_reading(
        &mut self,
        io: &Io<'_>,
        target_deg: f64,
        window_deg: f64,
        since: Instant,
    ) {
        let s = self.safety;
        let Some(r) = io.us.latest() else { return };
        // a turn that ended on this poll has already moved the reference heading to its target
        // while the stored pose still faces the old one: the believed heading would be 90° off
        if !io.motor.is_busy() || r.at < since || !self.echoes.take_turn_reading(r.at) {
            return;
        }
        let range = f64::from(r.value) / 100.0;
        let (Some(pose), Some(mut robot), Some(yaw)) =
            (self.place.pose(), self.place.believed(io), io.sensors.yaw_deg())
        else {
            return;
        };
        if !(0.0..=s.cell_m).contains(&range) {
            return;
        }
        // the heading when the sonar measured: the last IMU sample carried at the yaw rate to
        // the frame's arrival, less the sonar's lag
        let cfg = io.motor.config();
        let max_s = cfg.boards.max_extrapolation.as_secs_f64();
        let measured_after_sample_s = (r.at.saturating_since(yaw.at).as_secs_f64()
            - yaw.at.saturating_since(r.at).as_secs_f64()
            - s.sonar_lag_s)
            .clamp(-max_s, max_s);
        robot.yaw_deg += io.sensors.yaw_rate_dps(io.now, cfg) * measured_after_sample_s;
        let target = heading_deg(pose.heading) + target_deg;
        if crate::sensors::wrap180(robot.yaw_deg - target).abs() > window_deg {
            return;
        }
        tracing::trace!(x = robot.x, y = robot.y, yaw = robot.yaw_deg, range, "reading kept during a turn");
        self.counters.turn_readings += 1;
        self.place.learn(robot, Reading::Echo(range));
        self.echoes.keep_on_far_edge(robot, target, range);
    }

    /// Whether the robot should look past the mapping turn that just succeeded (module docs,
    /// "Readings in turns"): on, with a pose, in a mapping task, and without a complete floor
    /// plan. A trajectory's one
    /// `MOVE_DONE` ends the whole batch, so after a STOP in it Cute cannot tell which turns were
    /// made; a look would make a STOP land before the batch's first position more often.
    pub(super) fn look_wanted(&self) -> bool {
        let s = self.safety;
        s.look_past_deg > 0.0
            && self.place.pose().is_some()
            && self.tasks.mapping()
            && !self.free_space_known()
    }

    /// After the mapping turn `turn` and its `MOVE_DONE`: turns on past the new heading, the way
    /// the turn went, by [`Safety::look_past_turn_deg`](crate::config::Safety::look_past_turn_deg), the sonar listening, then back.
    /// When the look cannot start, the next command follows at once.
    pub(super) fn look_past(&mut self, io: &mut Io<'_>, turn: Move, unacked: Option<Move>) {
        let past = if turn == Move::Left { self.safety.look_past_deg } else { -self.safety.look_past_deg };
        match io.motor.start_look(io.now, past, io.sensors) {
            Ok(()) => self.stage = Stage::LookingPast { back: false, since: io.now, unacked },
            Err(e) => {
                tracing::warn!(error = %e, "cannot look past the turn");
                if let Some(turn) = unacked {
                    self.recentre(io, turn);
                }
            }
        }
    }

    /// A turn succeeded (the stored pose faces its new heading). Made at its cell's centre, the
    /// task ends and, mapping, the robot looks past the turn after its `MOVE_DONE`. Made off the
    /// centre (shifted clear of an echo), the look runs at once, where the turning circle was
    /// clear, and the body then drives back to the centre before the `MOVE_DONE` ("Back to the
    /// centre" in the module docs).
    pub(super) fn turn_made(&mut self, io: &mut Io<'_>, turn: Move) {
        if self.place.pose().is_none() || io.motor.odometry().offset().norm() <= RECENTRE_FROM_M {
            self.look_pending = self.look_wanted().then_some(turn);
        } else if self.look_wanted() {
            self.look_past(io, turn, Some(turn));
        } else {
            self.recentre(io, turn);
        }
    }

    /// Drives the body back to its cell's centre, holding the heading, when the way there is
    /// clear of known echoes ("Back to the centre" in the module docs); otherwise the task ends
    /// where the body is.
    pub(super) fn recentre(&mut self, io: &mut Io<'_>, turn: Move) {
        let off = io.motor.odometry().offset();
        let Some(robot) = self.place.believed(io) else {
            return;
        };
        if off.norm() <= RECENTRE_FROM_M {
            return;
        }
        let clear_to = self.echoes.clear_part_of_way_back(robot, off, SHIFT_STEP_M);
        if clear_to * off.norm() < 2.0 * SHIFT_STEP_M {
            tracing::info!(
                along = off.along_m,
                left = off.left_m,
                "turned off the centre: an echo bars the way back, staying"
            );
            return;
        }
        tracing::info!(
            along = off.along_m,
            left = off.left_m,
            part = clear_to,
            "turned off the centre: driving back towards it"
        );
        match io.motor.start_shift(io.now, -off.along_m * clear_to, -off.left_m * clear_to, io.sensors) {
            Ok(()) => {
                self.counters.turns_recentred += 1;
                self.stage = Stage::Recentring { turn };
            }
            Err(e) => tracing::warn!(error = %e, "cannot drive back to the cell's centre after a turn"),
        }
    }

    /// Faces the grid heading again after looking past a turn; if that cannot start, the body
    /// may face off the heading, and the next move faces it first ([`Motor::rotation_was_cut`](crate::motor::Motor::rotation_was_cut)).
    pub(super) fn look_back(&mut self, io: &mut Io<'_>, since: Instant, unacked: Option<Move>) {
        match io.motor.start_look(io.now, 0.0, io.sensors) {
            Ok(()) => self.stage = Stage::LookingPast { back: true, since, unacked },
            Err(e) => {
                tracing::warn!(error = %e, "cannot face the grid heading again after looking past a turn");
                io.motor.mark_rotation_cut();
                self.rest_since = io.now;
                self.stage = Stage::Next;
            }
        }
    }

    /// Keeps the reading `r`, taken while a FORWARD drives (module docs, "Readings while
    /// driving"), placed from where the odometry says the robot was when the sonar measured.
    pub(super) fn note_drive_reading(&mut self, io: &Io<'_>, r: DriveReading) {
        let s = self.safety;
        let range = f64::from(r.cm) / 100.0;
        // farther than this from the sonar, nothing can lie in the next FORWARD's corridor
        let reach_m = 2.0 * s.cell_m + s.half_length_m;
        if !(0.0..=reach_m).contains(&range) {
            return;
        }
        let Some(pose) = self.place.pose() else { return };
        let Some(robot) = self.place.believed_with(io, r.offset) else {
            return;
        };
        tracing::trace!(
            x = robot.x,
            y = robot.y,
            yaw = robot.yaw_deg,
            range,
            "reading kept during a FORWARD"
        );
        self.counters.drive_readings += 1;
        // the frame carries a result measured 0–2 mean lags before it and one is assumed: from a
        // fresher one the body was up to this much farther on, and the echo that much farther
        self.echoes.keep_on_far_edge(robot, heading_deg(pose.heading), range + s.drive_timing_m);
    }

    /// Starts look number `look` of the scan, or, after the last, the FORWARD itself.
    pub(super) fn look(&mut self, io: &mut Io<'_>, look: usize) {
        let (looks, deg) = self.looks_now();
        let Some(&sign) = looks.get(look) else {
            return self.drive_forward(io);
        };
        if look == 0
            && let Err(e) = io.motor.learn_reference(io.now, io.sensors)
        {
            return self.fail(io.now, &format!("scan before FORWARD: {e}"));
        }
        match io.motor.start_look(io.now, sign * deg, io.sensors) {
            Ok(()) => self.stage = Stage::Looking { look },
            Err(e) => self.fail(io.now, &format!("scan before FORWARD: {e}")),
        }
    }

    /// Waits for the reading after look number `look`; `false` while it has not come.
    pub(super) fn scan_reading(&mut self, io: &mut Io<'_>, look: usize, since: Instant) -> bool {
        let last = look + 1 >= self.looks_now().0.len();
        if !last {
            match io.us.latest() {
                Some(r) if r.at >= self.rest_since => {
                    let cm = (r.value >= 0.0).then_some(r.value);
                    if self.looking_aside.is_some() && self.place.at_look(io, cm) {
                        self.counters.pose_fixes += 1;
                    }
                    self.note_reading(io, cm);
                }
                _ if io.now.saturating_since(since) < self.distance_wait => return false,
                _ => {
                    tracing::warn!(look, "no distance reading at rest during the scan");
                    self.scan_missing = true;
                }
            }
        }
        self.look(io, look + 1);
        true
    }

    /// The corridor check, then the FORWARD.
    fn drive_forward(&mut self, io: &mut Io<'_>) {
        self.sliding.forget();
        if self.scan_missing {
            return self.fail(io.now, "scan incomplete: no distance reading at rest");
        }
        let s = self.safety;
        let mut track_left_m = 0.0;
        if let Some(robot) = self.place.believed(io) {
            let off = io.motor.odometry().offset();
            // along the track the move stops within its tolerance: the far end is the front face
            // at the next centre, so a straight echo blocks exactly as the one-cell threshold does
            let to = s.cell_m - off.along_m + s.half_length_m;
            let half = s.half_width_m + s.clearance_m;
            // the move ends on the line through the centres: the body strafes back to it
            if let Some(hit) = self.echoes.in_way(robot, to, half, -off.left_m) {
                match self.echoes.sidestep(robot, off.left_m, to, half) {
                    Some(track) => {
                        tracing::info!(
                            track_left_m = track,
                            echo_along_m = hit.at.0,
                            echo_left_m = hit.at.1,
                            "FORWARD on a track aside, clear of an echo beside the path"
                        );
                        self.counters.forwards_aside += 1;
                        track_left_m = track;
                    }
                    None => {
                        if let Some(way) = self.way_back() {
                            return self.start_way_back(io, way, "an echo in its corridor");
                        }
                        if let Some(way) = self.slide_way(io) {
                            return self.start_slide(io, way);
                        }
                        if hit.heard_moving {
                            // what refused this FORWARD, the turn that may follow keeps clear of
                            // too ("Kept while they hold")
                            self.echoes.keep_as_at_rest(robot, hit.at);
                        }
                        tracing::info!(
                            along_m = hit.at.0,
                            left_m = hit.at.1,
                            "echo in the body's path: no motion"
                        );
                        self.counters.corridor_blocked += 1;
                        // without a plan: inside the body standing at the next centre, the
                        // cell is occupied; anywhere else in the corridor only the way there is
                        // not clear
                        let centre_along_m = s.cell_m - off.along_m;
                        let in_footprint = (hit.at.0 - centre_along_m).abs() <= s.half_length_m
                            && (hit.at.1 + off.left_m).abs() <= s.half_width_m;
                        self.report_refused_forward(in_footprint);
                        return self.end_task(io.now);
                    }
                }
            }
        }
        if self.place.pose().is_none() {
            self.echoes.forget();
        }
        self.sliding.forget_way_in();
        let off = io.motor.odometry().offset();
        self.sliding.straight_began((off.along_m, off.left_m), track_left_m);
        self.forward.start(io, self.place.straight_range_m());
        match io.motor.start_next_cell_on(io.now, track_left_m, io.sensors).map(|_| ()) {
            Ok(()) => self.stage = Stage::Moving { kind: Move::Forward, since: io.now },
            Err(e) => self.fail(io.now, &e.to_string()),
        }
    }

    /// After a shift that did not end within tolerance: the turn runs if the circle is clear from
    /// where the robot believes it is now.
    pub(super) fn turn_after_failed_shift(&mut self, io: &mut Io<'_>, mv: Move, why: &str) {
        let clear = self.place.believed(io).is_none_or(|r| self.echoes.in_turning_circle(r).is_none());
        if clear {
            tracing::info!(why, "shift before a turn ended off target, but the turning circle is clear");
            self.start_turn(io, mv);
        } else {
            self.counters.turns_refused += 1;
            self.fail(io.now, &format!("turn refused: the shift before it failed ({why})"));
        }
    }

    /// A turn whose swept circle clears every known echo: at once, after a shift, or refused.
    pub(super) fn turn_safely(&mut self, io: &mut Io<'_>, mv: Move) {
        let s = self.safety;
        let Some(robot) = self.place.believed(io) else {
            return self.start_turn(io, mv);
        };
        let Some(hit) = self.echoes.in_turning_circle(robot) else {
            return self.start_turn(io, mv);
        };
        if self.free_space_known() {
            return match self.turn_place(io) {
                Some(legs) => self.slide_to_turn(io, mv, legs),
                None => {
                    self.counters.turns_refused += 1;
                    let why = format!(
                        "turn refused: an echo {:.0} cm ahead and {:.0} cm left lies in the turning circle and no place in the cell clears it",
                        hit.0 * 100.0,
                        hit.1 * 100.0
                    );
                    self.fail(io.now, &why)
                }
            };
        }
        let max_m = 0.25 * s.cell_m;
        // searched in the frame of the last FORWARD's heading: behind is the way the body came
        // (swept), ahead the way it ranged; after a turn on the spot, behind the new heading is
        // space no reading covered (module docs, "Turns")
        let turned_deg = self.place.travel_turned_deg();
        let travel_frame = Pose2 { yaw_deg: robot.yaw_deg + turned_deg, ..robot };
        let shift = self.echoes.clearing_shift(travel_frame, max_m, SHIFT_STEP_M).map(|(along, left)| {
            // into the body's frame, where the shift is driven
            let (sin, cos) = turned_deg.to_radians().sin_cos();
            let round = |v: f64| (v / SHIFT_STEP_M).round() * SHIFT_STEP_M;
            (round(along * cos - left * sin) + 0.0, round(along * sin + left * cos) + 0.0)
        });
        match shift {
            Some((metres, left_m)) => {
                tracing::info!(
                    metres,
                    left_m,
                    echo_along_m = hit.0,
                    echo_left_m = hit.1,
                    "turn: driving clear of a known echo first"
                );
                self.counters.turns_shifted += 1;
                match io.motor.start_shift(io.now, metres, left_m, io.sensors) {
                    Ok(()) => self.stage = Stage::Shifting { mv },
                    Err(e) => self.fail(io.now, &format!("shift before a turn: {e}")),
                }
            }
            None => {
                self.counters.turns_refused += 1;
                let why = format!(
                    "turn refused: an echo {:.0} cm ahead and {:.0} cm left lies in the turning circle and no shift of up to {:.0} cm along or across clears it",
                    hit.0 * 100.0,
                    hit.1 * 100.0,
                    0.25 * s.cell_m * 100.0
                );
                self.fail(io.now, &why);
            }
        }
    }
}
