//! The motor controller: one closed-loop move at a time, expressed as drive v2 setpoints.
//!
//! Concept: a move is a *goal* (a distance on the mean wheel odometry, or a yaw on the IMU) run in
//! two phases. **Active**: the controller commands a speed every poll — for a distance, the
//! minimum of the cruise speed, an acceleration ramp and a slow-down proportional to the remaining
//! distance, never below the minimum that still moves the robot, with a proportional heading hold
//! on `omega` so it drives straight; for a turn, `omega` proportional to the remaining angle with a
//! minimum. It stops early by the distance the robot coasts after a zero command (motor lag,
//! [`Motion::stop_lead_s`](crate::config::Motion::stop_lead_s)). **Settling**: the command is zero and the controller waits for
//! readings taken at rest; within tolerance (±1 cm, ±2°) the move is done, otherwise it nudges
//! again at low speed, at most [`Motion::max_corrections`](crate::config::Motion::max_corrections) times. A turn still within 2.5
//! tolerances (5°) after the last nudge counts as done: on a slow motor link every nudge can
//! overshoot, and failing such a turn left Carto's heading behind Cute's.
//!
//! The cartography FORWARD ([`Motor::start_next_cell`]) is *absolute*: it drives `cell − along` to
//! the next cell's centre, where `along` comes from the [`Odometry`] this controller keeps (the
//! offset from the current cell's centre), strafes (`vy`) the lateral offset back to zero while
//! driving, and, if it still ends more than [`Motion::lateral_tolerance_m`](crate::config::Motion::lateral_tolerance_m) off its track,
//! strafes back as a settle correction (a **Strafe** phase). The stop point also learns the robot's
//! systematic overshoot ([`Motor::coast_bias_m`]).
//!
//! A turn never starts while the robot may still be coasting: when the wheels were commanded to
//! zero less than [`Motion::settle_time`](crate::config::Motion::settle_time) ago (a STOP in the middle of a FORWARD, then at once
//! a RIGHT), the turn first waits (a **Rest** phase, zero command) for encoder readings taken after
//! that time; if the encoder readings have gone stale
//! ([`Boards::sensor_stale_after`](crate::config::Boards::sensor_stale_after)), it turns once that time has passed. The odometry ignores
//! translation while turning, so coasting during a turn would be lost and the next FORWARD would
//! correct its track for the wrong offset.
//!
//! A turn whose remaining angle has not shrunk by [`JAM_PROGRESS_DEG`] for
//! [`Motion::jam_after`](crate::config::Motion::jam_after) is jammed against something and fails at once
//! ([`MoveError::Jammed`]); [`Motor::start_turn_back`] then turns the body back to the reference
//! the turn started from.
//!
//! Turns and the heading hold aim at a *reference yaw* that moves by exactly 90° per successful
//! turn, so turn errors do not accumulate; it is learnt from the IMU on the first move and re-learnt
//! when the IMU disagrees with it by more than 20° (robot pushed, a failed turn).
//!
//! Invariants:
//! - the command the board should apply is always [`Motor::command`]; it is (re)sent when it
//!   changes and otherwise every [`Boards::drive_resend_period`](crate::config::Boards::drive_resend_period) while moving and every
//!   [`Boards::idle_resend_period`](crate::config::Boards::idle_resend_period) when idle (the zero command), so the board's 500 ms
//!   watchdog never trips during a move;
//! - [`Motor::stop`] sets the zero command and queues it at once;
//! - every move ends, with success or a [`MoveError`], by [`Motion::move_timeout`](crate::config::Motion::move_timeout) at the latest.
//!
//! ```
//! use carto::motor::{Drive, Motor};
//! use carto::CartoConfig;
//! use robot_model::time::Instant;
//! let mut m = Motor::new(CartoConfig::default());
//! m.poll(Instant::ZERO, &Default::default());
//! assert_eq!(m.take_drives(), vec![Drive::STOP]); // idle: the zero command goes out at once
//! ```

use robot_model::time::{Duration, Instant};

use crate::CartoConfig;
use crate::odometry::{CellOffset, Odometry};
use crate::sensors::SensorState;

mod control;
mod drive;
mod error;

use control::{Step, mean_delta};
pub use drive::Drive;
pub use error::MoveError;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Goal {
    /// Mean wheel travel from `baseline` reaches `target_m`.
    Distance { baseline: [i32; 4], target_m: f64 },
    /// Yaw reaches `target_deg` (unwrapped, counter-clockwise).
    Yaw { target_deg: f64 },
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    /// A turn waiting for the robot to come to rest (zero command) until readings taken at
    /// `until` or later have arrived.
    Rest {
        until: Instant,
    },
    Active {
        since: Instant,
        sign: f64,
    },
    /// A settle correction of the lateral offset alone: strafe back to the track.
    Strafe {
        sign: f64,
    },
    Settling {
        stopped_at: Instant,
    },
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Move {
    goal: Goal,
    phase: Phase,
    started: Instant,
    corrections: u8,
    hold_deg: Option<f64>,
    /// On success the odometry's origin moves this far ahead (one cell for a cell move).
    advance_m: f64,
    /// Remaining error (signed along the move) at rest after the first stop, for learning.
    first_stop_err: Option<f64>,
    /// A look ([`Motor::start_look`]): a turn that leaves the reference heading where it was.
    look: bool,
    /// The lateral offset from the cell's centre the move holds and ends on, metres (0: the
    /// track through the centres; a shift before a turn, [`Motor::start_shift`], sets another).
    track_left_m: f64,
    /// A turn's last progress: when its remaining angle last shrank by [`JAM_PROGRESS_DEG`], and
    /// that remaining angle (reset whenever an Active phase starts).
    progress: Option<(Instant, f64)>,
}

/// A turn must come this much closer to its target every [`Motion::jam_after`](crate::config::Motion::jam_after), degrees.
pub const JAM_PROGRESS_DEG: f64 = 1.0;

/// How long after a turn the IMU drift estimate still waits (the body settles), see
/// [`Motor::is_turning`].
pub const SETTLE_AFTER_TURN: Duration = Duration::from_millis(500);

impl Move {
    /// A move starting now: not a look, on the track through the centres.
    fn new(now: Instant, goal: Goal, hold_deg: Option<f64>, advance_m: f64) -> Move {
        Move {
            goal,
            phase: Phase::Active { since: now, sign: 0.0 },
            started: now,
            corrections: 0,
            hold_deg,
            advance_m,
            first_stop_err: None,
            look: false,
            track_left_m: 0.0,
            progress: None,
        }
    }
}

/// The closed-loop motor controller (see the module docs).
#[derive(Debug, Clone)]
pub struct Motor {
    cfg: CartoConfig,
    current: Option<Move>,
    outcome: Option<Result<(), MoveError>>,
    command: Drive,
    last_sent: Option<(Drive, Instant)>,
    out: Vec<Drive>,
    reference_deg: Option<f64>,
    last_baseline: Option<[i32; 4]>,
    odo: Odometry,
    coast_bias_m: f64,
    /// When the last turn or look ended.
    turn_ended: Option<Instant>,
    /// When the command last went from moving to zero.
    zeroed_at: Option<Instant>,
    /// The reference heading a turn started from, while that turn runs or after it failed
    /// ([`Motor::start_turn_back`]).
    turn_from_deg: Option<f64>,
    /// A turn or a look was cut short by [`Motor::stop`], or a look failed: the body may face off
    /// the reference heading, which still names the grid heading of the stored pose.
    rotation_cut: bool,
}

impl Motor {
    /// An idle controller.
    pub fn new(cfg: CartoConfig) -> Self {
        Motor {
            cfg,
            current: None,
            outcome: None,
            command: Drive::STOP,
            last_sent: None,
            out: Vec::new(),
            reference_deg: None,
            last_baseline: None,
            odo: Odometry::default(),
            coast_bias_m: 0.0,
            turn_ended: None,
            zeroed_at: None,
            turn_from_deg: None,
            rotation_cut: false,
        }
    }

    /// The configuration it drives by.
    pub fn config(&self) -> &CartoConfig {
        &self.cfg
    }

    /// Whether a move is running.
    pub fn is_busy(&self) -> bool {
        self.current.is_some()
    }

    /// Whether a turn or a look is running, or ended less than [`SETTLE_AFTER_TURN`] ago.
    pub fn is_turning(&self, now: Instant) -> bool {
        self.current.is_some_and(|m| matches!(m.goal, Goal::Yaw { .. }))
            || self.turn_ended.is_some_and(|t| now.saturating_since(t) < SETTLE_AFTER_TURN)
    }

    /// The command the board should be applying now.
    pub fn command(&self) -> Drive {
        self.command
    }

    /// Starts a FORWARD of `metres` (negative drives backwards) on the wheel odometry, relative
    /// to where the robot is. It holds the heading and the track (lateral offset zero) but does
    /// not move the cell origin: the cartography FORWARD is [`Motor::start_next_cell`].
    pub fn start_forward(&mut self, now: Instant, metres: f64, s: &SensorState) -> Result<(), MoveError> {
        self.start_relative(now, metres, None, s)
    }

    /// Starts a shift of the body by `along_m` along the heading and `left_m` to its left (the
    /// mecanum wheels strafe), relative to where the robot is, holding the heading. The odometry
    /// keeps the new offset from the cell's centre; the next FORWARD, which aims at the next
    /// centre on the track, takes it back.
    pub fn start_shift(
        &mut self,
        now: Instant,
        along_m: f64,
        left_m: f64,
        s: &SensorState,
    ) -> Result<(), MoveError> {
        self.start_relative(now, along_m, Some(left_m), s)
    }

    /// A move of `metres` along the heading from where the robot is, holding the heading, on the
    /// track through the centres (`left_m` `None`) or `left_m` left of where the robot is now.
    fn start_relative(
        &mut self,
        now: Instant,
        metres: f64,
        left_m: Option<f64>,
        s: &SensorState,
    ) -> Result<(), MoveError> {
        let counts = self.fresh_counts(now, s)?;
        let hold = self.hold_reference(now, s)?;
        // after hold_reference: a re-learnt reference rotates the offset into its frame
        let track_left_m = left_m.map_or(0.0, |l| self.odo.offset().left_m + l);
        self.last_baseline = Some(counts);
        let goal = Goal::Distance { baseline: counts, target_m: metres };
        self.begin_move(now, Move { track_left_m, ..Move::new(now, goal, Some(hold), 0.0) }, s);
        Ok(())
    }

    /// Starts the cartography FORWARD: drive to the centre of the next cell, i.e. `cell − along`
    /// where `along` is the odometry's offset from the current cell's centre (clamped to
    /// [−½ cell, 1 cell]: a FORWARD never drives backwards nor further than 1½ cells), holding
    /// heading and track. On success the
    /// odometry's origin moves one cell ahead. Returns the distance it drives, metres.
    pub fn start_next_cell(&mut self, now: Instant, s: &SensorState) -> Result<f64, MoveError> {
        self.start_next_cell_on(now, 0.0, s)
    }

    /// [`Motor::start_next_cell`] on a track `track_left_m` left of the line through the cells'
    /// centres: the lateral hold strafes to it while driving, and the move ends on it (within
    /// [`Motion::lateral_tolerance_m`](crate::config::Motion::lateral_tolerance_m)).
    pub fn start_next_cell_on(
        &mut self,
        now: Instant,
        track_left_m: f64,
        s: &SensorState,
    ) -> Result<f64, MoveError> {
        self.start_next_cell_at(now, track_left_m, 0.0, s)
    }

    /// [`Motor::start_next_cell_on`], stopping `stop_along_m` ahead of the next cell's centre
    /// (negative: short of it; at most a quarter cell either way).
    pub fn start_next_cell_at(
        &mut self,
        now: Instant,
        track_left_m: f64,
        stop_along_m: f64,
        s: &SensorState,
    ) -> Result<f64, MoveError> {
        self.fresh_counts(now, s)?;
        self.hold_reference(now, s)?;
        let cell = self.cfg.cell_size_m;
        // The offset and the baseline counts of the same sample, so the target is consistent.
        let off = self.odo.offset();
        let stop = if stop_along_m.is_finite() { stop_along_m.clamp(-0.25 * cell, 0.25 * cell) } else { 0.0 };
        let metres = cell + stop - off.along_m.clamp(-0.5 * cell, cell);
        tracing::debug!(
            along_m = off.along_m,
            left_m = off.left_m,
            metres,
            "forward to the next cell's centre"
        );
        let counts = self.odo.baseline_counts().unwrap_or(self.fresh_counts(now, s)?);
        let hold = self.hold_reference(now, s)?;
        self.last_baseline = Some(counts);
        let goal = Goal::Distance { baseline: counts, target_m: metres };
        self.begin_move(now, Move { track_left_m, ..Move::new(now, goal, Some(hold), cell) }, s);
        Ok(metres)
    }

    /// Drives back to the centre of the cell the robot believes it is in (after the bumper stopped
    /// a FORWARD), on the odometry. Needs a FORWARD to have started before.
    pub fn start_return(&mut self, now: Instant, s: &SensorState) -> Result<(), MoveError> {
        if self.last_baseline.is_none() {
            return Err(MoveError::NothingToReturnFrom);
        }
        let fresh = self.fresh_counts(now, s)?;
        let hold = self.hold_reference(now, s)?;
        // The offset and the baseline counts of the same sample (the robot may still be coasting).
        let along = self.odo.offset().along_m;
        let counts = self.odo.baseline_counts().unwrap_or(fresh);
        self.begin(now, Goal::Distance { baseline: counts, target_m: -along }, Some(hold), 0.0, s);
        Ok(())
    }

    /// Corrects the odometry's position along the heading by `metres` (see
    /// [`Odometry::correct_along`]); the next FORWARD, which aims at a cell centre, drives it away.
    pub fn correct_along(&mut self, metres: f64) {
        self.odo.correct_along(metres);
    }

    /// Corrects the odometry's offset by `fix` in the nominal frame (see [`Odometry::correct`]).
    pub fn correct_offset(&mut self, fix: CellOffset) {
        self.odo.correct(fix);
    }

    /// The robot is at the centre of its cell: Cute sent a fresh pose (`SEND_ROBOT_POSITION`).
    pub fn reset_odometry(&mut self) {
        self.odo.reset();
    }

    /// The dead-reckoned offset from the centre of the current cell, extrapolated to `now`.
    pub fn cell_offset(&self, now: Instant, s: &SensorState) -> CellOffset {
        self.odo.predicted(now, s, &self.cfg)
    }

    /// The odometry: the offset at the last complete encoder sample, in the nominal frame.
    pub fn odometry(&self) -> &Odometry {
        &self.odo
    }

    /// Starts a 90° turn on the spot: clockwise (RIGHT) when `clockwise`, else counter-clockwise.
    pub fn start_turn(&mut self, now: Instant, clockwise: bool, s: &SensorState) -> Result<(), MoveError> {
        let reference = self.hold_reference(now, s)?;
        let target_deg = if clockwise { reference - 90.0 } else { reference + 90.0 };
        self.turn_from_deg = Some(reference);
        self.begin(now, Goal::Yaw { target_deg }, None, 0.0, s);
        Ok(())
    }

    /// Undoes a turn that failed (any [`MoveError`]: jammed, timed out, not converged, a stale
    /// reading): turns back to the grid heading it started from, which is the reference again
    /// from now on, also when the turn back fails (it runs as a look, which leaves the reference
    /// alone; a failed look counts as cut, so the next move faces the reference again first,
    /// [`Motor::rotation_was_cut`]). The way back is the way the body just came, so it is free
    /// unless the body was pushed. Only once per failed turn.
    pub fn start_turn_back(&mut self, now: Instant, s: &SensorState) -> Result<(), MoveError> {
        let from = self.turn_from_deg.take().ok_or(MoveError::NothingToTurnBack)?;
        self.fresh_yaw(now, s)?;
        self.reference_deg = Some(from);
        self.odo.set_frame(from);
        self.start_look(now, 0.0, s)
    }

    /// Starts a *look*: a turn on the spot to `offset_deg` (counter-clockwise) from the reference
    /// heading, which stays where it is (the sonar scan before a FORWARD; `0.0` faces the grid
    /// heading again). Needs a reference heading, i.e. a move before it (the scan follows the
    /// straight reading of a FORWARD, which learns it).
    pub fn start_look(&mut self, now: Instant, offset_deg: f64, s: &SensorState) -> Result<(), MoveError> {
        self.fresh_yaw(now, s)?;
        let reference =
            self.reference_deg.ok_or(MoveError::MissingReading { sensor: "reference heading" })?;
        let goal = Goal::Yaw { target_deg: reference + offset_deg };
        self.begin_move(now, Move { look: true, ..Move::new(now, goal, None, 0.0) }, s);
        Ok(())
    }

    /// The reference heading (unwrapped yaw, counter-clockwise degrees) the grid heading is at.
    pub fn reference_deg(&self) -> Option<f64> {
        self.reference_deg
    }

    /// Makes sure the reference heading is known (learnt from the IMU if not) and returns it.
    pub fn learn_reference(&mut self, now: Instant, s: &SensorState) -> Result<f64, MoveError> {
        self.hold_reference(now, s)
    }

    /// Aborts any move and commands zero at once. No outcome is reported for an aborted move.
    pub fn stop(&mut self, now: Instant) {
        if let Some(m) = self.current.take()
            && let Goal::Yaw { .. } = m.goal
        {
            // the body may still be rotating: the drift estimate waits as after a finished turn
            self.turn_ended = Some(now);
            // A turn or a look cut short leaves the body between two grid headings (also one
            // resting before it starts: the look back from a look past a turn rests first, 20°
            // off). The reference stays: the stored pose keeps the heading the turn started
            // from, and the body faces it again before the next move (the pilot asks
            // `rotation_was_cut`). Learning the reference from the IMU instead took the cut angle
            // for the grid heading.
            self.rotation_cut = true;
        }
        self.outcome = None;
        self.turn_from_deg = None;
        self.set_command(now, Drive::STOP, true);
    }

    /// Forgets the reference yaw (the IMU heading will be learnt again on the next move), and
    /// that a rotation was cut.
    pub fn forget_reference(&mut self) {
        self.reference_deg = None;
        self.rotation_cut = false;
    }

    /// Turns the reference heading by `delta_deg` (counter-clockwise) without moving: a turn
    /// made is taken back ([`crate::pilot`], a cut before its `MOVE_DONE`). The odometry's offset
    /// is expressed in the new frame.
    pub fn turn_reference(&mut self, delta_deg: f64) {
        if let Some(r) = self.reference_deg.as_mut() {
            *r += delta_deg;
            self.odo.set_frame(*r);
        }
    }

    /// Notes that the body may face off the reference heading (a look back that could not
    /// start): the next move faces it first.
    pub fn mark_rotation_cut(&mut self) {
        self.rotation_cut = true;
    }

    /// Notes that the body faces the reference heading closely enough for the next move to
    /// start from where it is (a FORWARD's heading hold and a turn's absolute target take the
    /// rest): the cut is forgotten, the reference kept.
    pub fn accept_rotation_cut(&mut self) {
        self.rotation_cut = false;
    }

    /// How far the body faces from the reference heading, counter-clockwise degrees (the IMU's
    /// latest reading against the reference); `None` without either.
    pub fn off_reference_deg(&self, s: &SensorState) -> Option<f64> {
        Some(s.yaw_deg()?.value - self.reference_deg?)
    }

    /// Whether a turn or a look was cut short or failed since the last rotation that finished:
    /// the body may face off the grid heading, and a look to `0.0` ([`Motor::start_look`]) faces
    /// it again.
    pub fn rotation_was_cut(&self) -> bool {
        self.rotation_cut
    }

    /// Metres driven since the last FORWARD started (mean wheel odometry, last readings).
    pub fn travelled_m(&self, s: &SensorState) -> Option<f64> {
        let base = self.last_baseline?;
        let counts = s.counts()?.value;
        Some(mean_delta(&counts.map(f64::from), &base) / self.cfg.encoder_counts_per_metre())
    }

    /// The outcome of the move that just ended, once.
    pub fn take_outcome(&mut self) -> Option<Result<(), MoveError>> {
        self.outcome.take()
    }

    /// Drive commands queued for the board since the last call, oldest first.
    pub fn take_drives(&mut self) -> Vec<Drive> {
        core::mem::take(&mut self.out)
    }

    /// Runs the control loop and the periodic resend. A finished move's outcome becomes
    /// available from [`Motor::take_outcome`].
    pub fn poll(&mut self, now: Instant, s: &SensorState) {
        let turning = self
            .current
            .is_some_and(|m| matches!(m.goal, Goal::Yaw { .. }) && !matches!(m.phase, Phase::Rest { .. }));
        self.odo.update_with(s, &self.cfg, !turning);
        if let Some(mut m) = self.current {
            match self.step(now, &mut m, s) {
                Step::Continue(drive) => {
                    self.current = Some(m);
                    self.set_command(now, drive, false);
                }
                Step::Finished(result) => {
                    self.current = None;
                    if matches!(m.goal, Goal::Yaw { .. }) {
                        self.turn_ended = Some(now);
                        // a look that failed leaves the body off the heading it aimed at (a turn
                        // that failed forgets the reference below and is turned back)
                        self.rotation_cut = if result.is_ok() { false } else { m.look || self.rotation_cut };
                    }
                    self.learn_coast(&m);
                    if let (Ok(()), Goal::Yaw { target_deg }, false) = (&result, m.goal, m.look) {
                        self.reference_deg = Some(target_deg);
                        self.odo.set_frame(target_deg);
                        self.turn_from_deg = None;
                    }
                    if result.is_ok() && m.advance_m != 0.0 {
                        self.odo.advance(m.advance_m);
                    }
                    // A failed look leaves the reference where it was: the grid heading did not move.
                    if result.is_err() && matches!(m.goal, Goal::Yaw { .. }) && !m.look {
                        self.reference_deg = None;
                    }
                    self.outcome = Some(result);
                    self.set_command(now, Drive::STOP, false);
                }
            }
        }
        let period = if self.current.is_some() {
            self.cfg.boards.drive_resend_period
        } else {
            self.cfg.boards.idle_resend_period
        };
        let due = self.last_sent.is_none_or(|(_, at)| now.saturating_since(at) >= period);
        if due {
            self.set_command(now, self.command, true);
        }
    }

    /// The next time `poll` must run for the resend cadence (the control loop wants every poll).
    pub fn next_deadline(&self) -> Option<Instant> {
        let period = if self.current.is_some() {
            self.cfg.boards.drive_resend_period
        } else {
            self.cfg.boards.idle_resend_period
        };
        self.last_sent.map(|(_, at)| at + period)
    }

    fn set_command(&mut self, now: Instant, drive: Drive, force: bool) {
        if drive == Drive::STOP && self.command != Drive::STOP {
            self.zeroed_at = Some(now);
        }
        self.command = drive;
        let changed = self.last_sent.is_none_or(|(d, _)| d != drive);
        if changed || force {
            self.out.push(drive);
            self.last_sent = Some((drive, now));
        }
    }

    fn begin(&mut self, now: Instant, goal: Goal, hold_deg: Option<f64>, advance_m: f64, s: &SensorState) {
        self.begin_move(now, Move::new(now, goal, hold_deg, advance_m), s);
    }

    fn begin_move(&mut self, now: Instant, mut m: Move, s: &SensorState) {
        self.outcome = None;
        let goal = m.goal;
        let coasting_until =
            self.zeroed_at.map(|at| at + self.cfg.motion.settle_time).filter(|until| now < *until);
        m.phase = match (goal, coasting_until) {
            (Goal::Yaw { .. }, Some(until)) => {
                tracing::debug!(wait_ms = until.saturating_since(now).total_millis(), "turn waits for rest");
                Phase::Rest { until }
            }
            _ => self.active_phase(&m, now, s),
        };
        self.current = Some(m);
        self.poll(now, s);
    }
}

#[cfg(test)]
mod tests;
