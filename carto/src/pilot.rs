//! The pilot: Carto's side of the link session with Cute, as a sans-IO state machine.
//!
//! Concept: decoded [`Request`]s come in through [`Pilot::handle`]; [`Pilot::poll`] runs the work
//! they created — one *task* at a time, each a list of commands — by asking the [`Ultrasound`] and
//! driving the [`Motor`]; [`Reply`]s to send back pile up for [`Pilot::take_replies`].
//!
//! Behaviour (`protocols.md` §1, "Carto's behaviour"):
//! - `SEND_ROBOT_POSITION` stores the pose and answers `ROBOT_POSITION_RECEIVED` (a direction above
//!   3 is logged, not stored, and still acknowledged so Cute does not wait for ever).
//! - `SEND_MOVE_CARTOGRAPHY(c)` becomes a task of one command. FORWARD checks the ultrasound first
//!   (obstacle → `SET_OBSTACLE_POSITION(cell ahead)`, no motion), else drives one cell, updates the
//!   pose and answers `SET_ROBOT_POSITION`; turns update the heading; then `MOVE_DONE`. A command
//!   that cannot run (no pose yet, cell ahead off the grid, value above 2, a board lost, a sensor
//!   silent, a failed move) is logged and answered with `MOVE_DONE` only.
//! - `SEND_MOVES_TRAJECTORY` frames accumulate into a batch of `n_total` (another `n_total`
//!   discards the partial batch, `n_total = 0` is ignored); a complete batch becomes a task run
//!   asynchronously: obstacle check before each FORWARD (obstacle → `SET_OBSTACLE_POSITION` when
//!   the pose is known, rest aborted), `SET_ROBOT_POSITION` after each FORWARD when the pose is
//!   known, `MOVE_DONE` when the batch ends (also when it is aborted). Without a pose a batch still
//!   runs (the original Cute never sends one). STOP (3) inside a batch is a no-op, an unknown value
//!   is skipped; both are logged.
//! - `STOP_ROBOT` stops the motors now and drops every pending command and partial batch; no reply.
//! - Tasks queue in arrival order; a new request never interrupts a running task (only STOP does).
//! - A turn that fails — jammed (the IMU shows no progress for [`CartoConfig::jam_after`]), timed
//!   out, not converged, a reading gone stale — is turned back to the grid heading it started
//!   from before `MOVE_DONE`, so the body faces the heading Carto still stores (Cute learns from
//!   the next FORWARD's reply that the turn was not made). A reconnect whose re-sent pose takes
//!   that turn as made defeats this: the stored heading then follows Cute (a known limit).
//! - The bumper, pressed while a FORWARD runs, stops it: `SET_OBSTACLE_POSITION(cell ahead)`, the
//!   rest is aborted, and (by default) the robot drives back to the cell it started from before
//!   `MOVE_DONE`. Pressed at the obstacle check, it counts as an obstacle.
//! - A FORWARD whose sonar range holds while the wheels drive is stalled (`pilot/stall.rs`,
//!   [`CartoConfig::stall_watch`]): it is stopped, the odometry takes the sonar's word, and it
//!   ends as after the bumper (`SET_OBSTACLE_POSITION(cell ahead)`, back-off, `MOVE_DONE`).
//! - **Pushed.** A FORWARD during which the gap between the IMU's and the wheels' headings jumps
//!   by more than [`crate::sensors::PUSH_JUMP_DEG`] has met something beside the bumper: a corner
//!   or a leg turned the body under its wheels, and mecanum rollers give way sideways
//!   ([`CartoConfig::push_watch`]). It ends as after the bumper. The first sample of the drift
//!   estimate after the FORWARD starts does not count: the estimate takes no samples in a turn
//!   and the 0.5 s after it, and a FORWARD often starts within them, so that sample still holds
//!   what the turn before did. What the watch misses is listed at
//!   [`crate::sensors::PUSH_JUMP_DEG`]. Without the watch the robot drives on, sliding along
//!   what it touched, and its belief is lost.
//!
//! Invariants: every task ends with exactly one `MOVE_DONE` unless STOP, a disconnect or a lost
//! board link ([`Pilot::on_link_lost`]) drops it;
//! the stored pose changes only by `SEND_ROBOT_POSITION` or a completed move.
//!
//! ```
//! use carto::pilot::{Health, Io, Pilot, Reply, Request};
//! use carto::{motor::Motor, sensors::SensorState, ultrasound::Ultrasound, CartoConfig};
//! use robot_model::grid::{Heading, Move};
//! use robot_model::time::Instant;
//! let cfg = CartoConfig::default();
//! let (mut pilot, mut motor) = (Pilot::new(&cfg), Motor::new(cfg.clone()));
//! let (sensors, us) = (SensorState::default(), Ultrasound::new(30.0, cfg.distance_max_age));
//! let now = Instant::ZERO;
//! pilot.handle(now, Request::SetPose { x: 2, y: 3, direction: Ok(Heading::East) }, &mut motor);
//! // a cartography move without the sensor board cannot run: MOVE_DONE only
//! pilot.handle(now, Request::Cartography { command: Ok(Move::Forward) }, &mut motor);
//! let health = Health { sensor_board: false, motor_board: true };
//! pilot.poll(&mut Io { now, motor: &mut motor, sensors: &sensors, us: &us, health });
//! assert_eq!(pilot.take_replies(), vec![Reply::PositionReceived, Reply::MoveDone]);
//! ```

use std::collections::VecDeque;

use robot_model::time::{Duration, Instant};

use crate::CartoConfig;
use crate::estimate::localiser::Localiser;
use crate::motor::Motor;
use crate::odometry::CellOffset;
use crate::sensors::{DriftCounts, SensorState};
use crate::surroundings::Surroundings;
use crate::ultrasound::{Check, Ultrasound};
use robot_model::grid::{GridPose, Heading, Move};

mod commands;
mod safety;
mod stall;

use safety::Safety;
use stall::{Stall, StallWatch};

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
    /// Turns that first drove back or forth to clear a known echo.
    pub turns_shifted: u64,
    /// Turns made off the centre that drove back to it before their `MOVE_DONE`.
    pub turns_recentred: u64,
    /// Turns refused: no shift along the heading cleared the known echoes.
    pub turns_refused: u64,
    /// Readings at rest that corrected the belief (`estimate/localiser.rs`).
    pub pose_fixes: u64,
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

/// A sonar reading taken while a FORWARD drives, with the odometry's offset from the stored
/// cell's centre when the sonar measured.
#[derive(Debug, Clone, Copy, PartialEq)]
struct DriveReading {
    /// The range, cm; negative for no echo.
    cm: f32,
    offset: CellOffset,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum TaskKind {
    Cartography,
    Trajectory,
}

#[derive(Debug, Clone, PartialEq, Eq)]
struct Task {
    kind: TaskKind,
    commands: VecDeque<Result<Move, u8>>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stage {
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
    /// The sonar scan before a FORWARD: look number `look` of [`Safety::looks`] runs.
    Looking { look: usize },
    /// Waiting for a distance reading at rest after look number `look`.
    Reading { look: usize, since: Instant },
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

/// What the pilot is doing ([`Pilot::activity`]), for logs and diagnostics.
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

/// A line about the client's input (a position, a STOP, a bad value) that the pilot wants
/// logged. The pilot does not log these itself: [`crate::Carto`] takes them with
/// [`Pilot::take_notes`] and logs them through its rate limiter, per kind and client, so a flood
/// of frames cannot flood the log.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InputNote {
    /// The rate limiter's kind (a constant per call site).
    pub kind: &'static str,
    /// A warning (bad input) rather than information.
    pub warn: bool,
    /// The line.
    pub text: String,
}

/// The link session's state machine (see the module docs).
#[derive(Debug, Clone)]
pub struct Pilot {
    distance_wait: Duration,
    stale_after: Duration,
    back_off: bool,
    pose: Option<GridPose>,
    batch: Option<(u8, Vec<Result<Move, u8>>)>,
    queue: VecDeque<Task>,
    current: Option<Task>,
    stage: Stage,
    rest_since: Instant,
    replies: Vec<Reply>,
    notes: Vec<InputNote>,
    counters: PilotCounters,
    safety: Safety,
    surroundings: Surroundings,
    /// Echoes heard while the robot moved (in turns, looks and FORWARDs), each kept on the cone's
    /// edge farther from the line of the FORWARD after it (`pilot/safety.rs`, "Readings in
    /// turns", "Readings while driving", "Kept while they hold"): only the corridor checks ask
    /// them. The one that refuses a FORWARD is copied into `surroundings`.
    edge_echoes: Surroundings,
    /// A reading of the running scan never came.
    scan_missing: bool,
    /// The last straight reading at rest, for the along-track fix of the next one.
    last_straight: Option<safety::Straight>,
    /// Surfaces seen straight ahead, for the absolute along-track fix.
    localiser: Localiser,
    /// The heading of the last FORWARD made from the stored pose (`None`: none yet): the way the
    /// body came, for the shift before a turn (`pilot/safety.rs`, "Turns").
    travel: Option<Heading>,
    /// When the last reading kept during a turn arrived.
    last_turn_reading: Option<Instant>,
    /// The echoes of the running FORWARD (`pilot/stall.rs`); `None` when the watch is off.
    stall_watch: Option<StallWatch>,
    /// The push watch of the FORWARD running: the drift estimate's counts when it started
    /// (module docs, "Pushed"); `None` when the watch is off.
    push_watch: Option<DriftCounts>,
    /// [`CartoConfig::push_watch`].
    push_watch_on: bool,
    /// When the last reading taken while a FORWARD drove arrived.
    last_drive_reading: Option<Instant>,
    /// The odometry's offset along the heading when the running FORWARD started, metres.
    forward_from_m: f64,
    /// The mapping turn that just succeeded: once its task has ended, the robot looks past it.
    look_pending: Option<Move>,
    /// Re-facings of the grid heading that failed in a row ([`Pilot::refacing_failed`]).
    reface_failures: u8,
}

impl Pilot {
    /// An idle pilot with no pose.
    pub fn new(cfg: &CartoConfig) -> Self {
        Pilot {
            distance_wait: cfg.distance_wait,
            stale_after: cfg.sensor_stale_after,
            back_off: cfg.back_off_after_bump,
            pose: None,
            batch: None,
            queue: VecDeque::new(),
            current: None,
            stage: Stage::Next,
            rest_since: Instant::ZERO,
            replies: Vec::new(),
            notes: Vec::new(),
            counters: PilotCounters::default(),
            safety: Safety::new(cfg),
            surroundings: Surroundings::default(),
            edge_echoes: Surroundings::default(),
            scan_missing: false,
            last_straight: None,
            localiser: Localiser::new(cfg),
            last_turn_reading: None,
            travel: None,
            push_watch: None,
            push_watch_on: cfg.push_watch,
            stall_watch: cfg.stall_watch.then(|| StallWatch::new(cfg.sonar_sigma_m, cfg.drive_timing_m())),
            last_drive_reading: None,
            forward_from_m: 0.0,
            look_pending: None,
            reface_failures: 0,
        }
    }

    /// The stored pose, if Cute sent one.
    pub fn pose(&self) -> Option<GridPose> {
        self.pose
    }

    /// Every echo point the safety checks hold now, in the grid's metric frame
    /// ([`crate::surroundings`]): those kept at rest and those heard moving (not the floor plan).
    pub fn echo_points(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.surroundings.points().chain(self.edge_echoes.points())
    }

    /// What the pilot is doing now.
    pub fn activity(&self) -> Activity {
        match self.stage {
            Stage::Next if self.is_busy() => Activity::BetweenCommands,
            Stage::Next => Activity::Idle,
            Stage::Waiting { .. } => Activity::WaitingForReadings,
            Stage::Checking { .. } => Activity::CheckingAhead,
            Stage::Moving { kind: Move::Forward, .. } => Activity::DrivingForward,
            Stage::Moving { .. } => Activity::Turning,
            Stage::BackingOff => Activity::BackingOff,
            Stage::Looking { .. } => Activity::ScanLook,
            Stage::Reading { .. } => Activity::ScanReading,
            Stage::Shifting { .. } => Activity::ShiftingBeforeTurn,
            Stage::TurningBack { .. } => Activity::TurningBack,
            Stage::LookingPast { .. } => Activity::LookingPastTurn,
            Stage::Recentring { .. } => Activity::Recentring,
            Stage::Refacing { .. } => Activity::Refacing,
        }
    }

    /// Gives the safety checks known surface points ([`crate::Carto::add_known_surfaces`]).
    pub fn add_known_surfaces(&mut self, points: impl IntoIterator<Item = (f64, f64)>) {
        let points: Vec<(f64, f64)> = points.into_iter().collect();
        self.localiser.pin(points.iter().copied());
        self.surroundings.add_fixed(points);
    }

    /// Whether a task runs or waits.
    pub fn is_busy(&self) -> bool {
        // a look past a turn runs after the turn's task has ended
        self.current.is_some() || !self.queue.is_empty() || !matches!(self.stage, Stage::Next)
    }

    /// Commands waiting: the rest of the current task, queued tasks and a partial batch.
    pub fn pending(&self) -> usize {
        self.current.as_ref().map_or(0, |t| t.commands.len())
            + self.queue.iter().map(|t| t.commands.len()).sum::<usize>()
            + self.batch.as_ref().map_or(0, |(_, c)| c.len())
    }

    /// The pilot's counters.
    pub fn counters(&self) -> PilotCounters {
        self.counters
    }

    /// Replies produced since the last call, in order.
    pub fn take_replies(&mut self) -> Vec<Reply> {
        core::mem::take(&mut self.replies)
    }

    /// Lines about the client's input since the last call, in order ([`InputNote`]).
    pub fn take_notes(&mut self) -> Vec<InputNote> {
        core::mem::take(&mut self.notes)
    }

    fn note(&mut self, kind: &'static str, warn: bool, text: String) {
        self.notes.push(InputNote { kind, warn, text });
    }

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
                        if self.pose != Some(pose) {
                            self.look_pending = None;
                            self.reface_failures = 0;
                            if motor.rotation_was_cut() {
                                // the body faces where the new pose says: learn it from the IMU
                                motor.forget_reference();
                            }
                            motor.reset_odometry();
                            self.forget_surroundings();
                            self.last_straight = None;
                            self.localiser.reset();
                            self.travel = None;
                        }
                        self.pose = Some(pose);
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
                self.queue
                    .push_back(Task { kind: TaskKind::Cartography, commands: VecDeque::from([command]) });
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
        let batch = match self.batch.take() {
            Some((n, mut cmds)) if n == n_total => {
                cmds.push(command);
                (n, cmds)
            }
            Some((n, cmds)) => {
                self.counters.batches_discarded += 1;
                self.note(
                    "n_total changed",
                    true,
                    format!(
                        "n_total changed from {n} to {n_total}: partial batch of {} discarded",
                        cmds.len()
                    ),
                );
                (n_total, vec![command])
            }
            None => (n_total, vec![command]),
        };
        if batch.1.len() >= usize::from(batch.0) {
            self.note(
                "trajectory batch complete",
                false,
                format!("trajectory batch of {} complete", batch.0),
            );
            self.queue.push_back(Task { kind: TaskKind::Trajectory, commands: batch.1.into() });
        } else {
            self.batch = Some(batch);
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
        if self.current.is_some() {
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
        if self.current.is_some() {
            self.counters.moves_failed += 1;
        }
        let dropped = self.pending();
        if self.current.is_some() || dropped > 0 {
            tracing::warn!(why, dropped, "moves dropped, no MOVE_DONE: the robot did not make them");
        }
        self.drop_everything(now, motor);
    }

    fn drop_everything(&mut self, now: Instant, motor: &mut Motor) {
        motor.stop(now);
        self.last_straight = None;
        self.localiser.forget_last_reading();
        self.look_pending = None;
        self.reface_failures = 0;
        let mapping = self.current.as_ref().is_some_and(|t| t.kind == TaskKind::Cartography);
        if let (Stage::LookingPast { unacked: Some(turn), .. } | Stage::Recentring { turn }, true) =
            (self.stage, mapping)
        {
            self.unmake_turn(turn, motor);
        }
        if !matches!(self.stage, Stage::Next) {
            // stopped in the middle of a scan or a shift: the robot may face off the grid heading
            // and is somewhere Carto did not plan; what it saw from there is not trusted
            self.forget_surroundings();
        }
        self.queue.clear();
        self.current = None;
        self.batch = None;
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
        let Some(pose) = self.pose.as_mut() else {
            return;
        };
        pose.heading = if turn == Move::Left { pose.heading.right() } else { pose.heading.left() };
        motor.turn_reference(if turn == Move::Left { -90.0 } else { 90.0 });
        motor.mark_rotation_cut();
        tracing::info!(
            ?pose,
            "cut before the MOVE_DONE of a turn made off the centre: the turn is taken back"
        );
    }

    /// Ends the current task (completed or aborted): `MOVE_DONE`, back to the next task.
    fn end_task(&mut self, now: Instant) {
        self.current = None;
        self.stage = Stage::Next;
        self.rest_since = now;
        self.replies.push(Reply::MoveDone);
    }

    fn fail(&mut self, now: Instant, why: &str) {
        self.note("move cannot run", true, format!("move cannot run ({why}): task ends with MOVE_DONE only"));
        self.counters.moves_failed += 1;
        self.end_task(now);
    }

    /// Runs pending work. `io.motor` must have been polled at `io.now` already (it holds the
    /// outcome of a move that just ended).
    pub fn poll(&mut self, io: &mut Io<'_>) {
        // Bounded: each pass either waits (returns) or consumes a command or a task.
        for _ in 0..1024 {
            match self.stage {
                Stage::Next => {
                    if self.current.is_none()
                        && let Some(turn) = self.look_pending.take()
                    {
                        // the turn's MOVE_DONE has gone out: Cute and Carto hold the new heading
                        // whatever cuts the look; the next command waits in the queue
                        self.look_past(io, turn, None);
                        continue;
                    }
                    if self.current.is_none() {
                        match self.queue.pop_front() {
                            Some(t) => self.current = Some(t),
                            None => return,
                        }
                    }
                    let Some(task) = self.current.as_mut() else {
                        return;
                    };
                    let kind = task.kind;
                    let Some(command) = task.commands.pop_front() else {
                        self.end_task(io.now);
                        continue;
                    };
                    self.start_command(io, kind, command);
                }
                Stage::Waiting { mv, since } => {
                    if self.readings_fresh(io) {
                        self.begin_move(io, mv);
                    } else if io.now.saturating_since(since) >= self.distance_wait {
                        self.fail(io.now, "no fresh encoder and IMU readings");
                    } else {
                        return;
                    }
                }
                Stage::Checking { since } => {
                    if !(io.health.sensor_board && io.health.motor_board) {
                        self.fail(io.now, "a board is lost");
                        continue;
                    }
                    // With a pose the odometry's offset is from the cell's centre, and the
                    // FORWARD ends on the next one (a reconnect can leave the robot mid-move).
                    let done_cm = if self.pose.is_some() {
                        (io.motor.odometry().offset().along_m * 100.0) as f32
                    } else {
                        0.0
                    };
                    let check = if io.sensors.bumper_pressed() {
                        Check::Obstacle { cm: 0.0 }
                    } else {
                        io.us.check_ahead(io.now, self.rest_since, done_cm)
                    };
                    match check {
                        Check::Pending if io.now.saturating_since(since) >= self.distance_wait => {
                            self.fail(io.now, "no distance reading taken at rest");
                        }
                        Check::Pending => return,
                        Check::Obstacle { cm } => {
                            self.note(
                                "obstacle ahead",
                                false,
                                format!("obstacle ahead at {cm} cm: no motion"),
                            );
                            if !io.sensors.bumper_pressed() {
                                self.localise(io, Some(cm));
                            }
                            self.note_reading(io, Some(cm));
                            self.report_obstacle();
                            self.end_task(io.now);
                        }
                        Check::Clear { cm } => {
                            tracing::debug!(?cm, "path clear");
                            self.localise(io, cm);
                            self.note_reading(io, cm);
                            self.scan_missing = false;
                            self.look(io, 0);
                        }
                    }
                }
                Stage::Moving { kind, since } => {
                    if kind.is_turn() {
                        let target = if kind == Move::Left { 90.0 } else { -90.0 };
                        let window = safety::TURN_READING_WINDOW_DEG;
                        self.note_turn_reading(io, target, window, since);
                    }
                    if kind == Move::Forward && io.sensors.bumper_pressed_since(since) {
                        self.bumped(io);
                        continue;
                    }
                    if kind == Move::Forward && io.motor.is_busy() && self.poll_push_watch(io) {
                        self.pushed(io);
                        continue;
                    }
                    // not on the poll the FORWARD ended: the odometry's origin has moved on
                    if kind == Move::Forward
                        && io.motor.is_busy()
                        && let Some(r) = self.new_drive_reading(io, since)
                    {
                        self.note_drive_reading(io, r);
                        if let Some(stall) = self.watch_forward(r) {
                            self.stalled(io, stall);
                            continue;
                        }
                    }
                    match io.motor.take_outcome() {
                        None if io.motor.is_busy() => return,
                        None => {
                            // The move vanished (stopped from outside): treat as failed.
                            self.counters.moves_failed += 1;
                            self.edge_echoes.clear();
                            self.end_task(io.now);
                        }
                        Some(Ok(())) => {
                            self.counters.moves_done += 1;
                            self.rest_since = io.now;
                            self.move_succeeded(kind);
                            self.stage = Stage::Next;
                            if kind.is_turn() {
                                self.turn_made(io, kind);
                            }
                        }
                        Some(Err(e)) => {
                            tracing::warn!(error = %e, ?kind, "move failed: robot stopped");
                            self.counters.moves_failed += 1;
                            if kind.is_turn() {
                                self.turn_back(io, kind);
                            } else {
                                self.edge_echoes.clear();
                                self.end_task(io.now);
                            }
                        }
                    }
                }
                Stage::Looking { look } => match io.motor.take_outcome() {
                    None if io.motor.is_busy() => return,
                    None | Some(Ok(())) => {
                        self.rest_since = io.now;
                        self.stage = Stage::Reading { look, since: io.now };
                    }
                    Some(Err(e)) => self.fail(io.now, &format!("scan before FORWARD: {e}")),
                },
                Stage::Reading { look, since } => {
                    if !self.scan_reading(io, look, since) {
                        return;
                    }
                }
                Stage::Shifting { mv } => match io.motor.take_outcome() {
                    None if io.motor.is_busy() => return,
                    None | Some(Ok(())) => self.start_turn(io, mv),
                    Some(Err(e)) => self.turn_after_failed_shift(io, mv, &e.to_string()),
                },
                Stage::TurningBack { mv } => match io.motor.take_outcome() {
                    None if io.motor.is_busy() => return,
                    None | Some(Ok(())) => {
                        tracing::info!(?mv, "turned back to the heading the failed turn started from");
                        self.rest_since = io.now;
                        self.end_task(io.now);
                    }
                    Some(Err(e)) => {
                        tracing::warn!(error = %e, ?mv, "turning back after a failed turn failed too");
                        self.end_task(io.now);
                    }
                },
                Stage::Refacing { mv } => match io.motor.take_outcome() {
                    None if io.motor.is_busy() => return,
                    None | Some(Ok(())) => {
                        self.rest_since = io.now;
                        self.reface_failures = 0;
                        self.begin_move(io, mv);
                    }
                    Some(Err(e)) => self.refacing_failed(io, mv, &e.to_string()),
                },
                Stage::LookingPast { back, since, unacked } => {
                    let window = self.safety.look_window_deg();
                    self.note_turn_reading(io, 0.0, window, since);
                    match io.motor.take_outcome() {
                        None if io.motor.is_busy() => return,
                        None | Some(Ok(())) if !back => self.look_back(io, since, unacked),
                        Some(Err(e)) if !back => {
                            tracing::warn!(error = %e, "looking past a turn failed: facing the heading again");
                            self.look_back(io, since, unacked);
                        }
                        outcome => {
                            self.rest_since = io.now;
                            self.stage = Stage::Next;
                            match outcome {
                                // the motor marked the rotation cut: the next move faces the
                                // heading first, from where the body is
                                Some(Err(e)) => tracing::warn!(
                                    error = %e,
                                    "facing the heading again after looking past a turn failed"
                                ),
                                _ => {
                                    if let Some(turn) = unacked {
                                        self.recentre(io, turn);
                                    }
                                }
                            }
                        }
                    }
                }
                Stage::Recentring { .. } => match io.motor.take_outcome() {
                    None if io.motor.is_busy() => return,
                    outcome => {
                        if let Some(Err(e)) = outcome {
                            tracing::warn!(error = %e, "driving back to the cell's centre after a turn failed");
                        }
                        self.rest_since = io.now;
                        self.stage = Stage::Next;
                    }
                },
                Stage::BackingOff => match io.motor.take_outcome() {
                    None if io.motor.is_busy() => return,
                    None | Some(Ok(())) => self.end_task(io.now),
                    Some(Err(e)) => {
                        tracing::warn!(error = %e, "back-off after the bumper, a stall or a push failed");
                        self.end_task(io.now);
                    }
                },
            }
        }
    }

    fn move_succeeded(&mut self, kind: Move) {
        let Some(pose) = self.pose.as_mut() else {
            // without a pose the echo points cannot follow the robot
            self.forget_surroundings();
            return;
        };
        match kind {
            Move::Forward => {
                self.travel = Some(pose.heading);
                if let Some((x, y)) = pose.ahead() {
                    pose.x = x;
                    pose.y = y;
                    self.replies.push(Reply::RobotPosition { x, y });
                }
            }
            Move::Right => pose.heading = pose.heading.right(),
            Move::Left => pose.heading = pose.heading.left(),
        }
        tracing::info!(pose = %pose, "move done");
    }

    fn report_obstacle(&mut self) {
        self.counters.obstacles += 1;
        match self.pose.and_then(|p| p.ahead()) {
            Some((x, y)) => self.replies.push(Reply::Obstacle { x, y }),
            None => tracing::info!("obstacle ahead, but no robot position to report it against"),
        }
    }

    /// A turn failed part way: the body faces between two grid headings while the stored pose
    /// keeps the old one. Turning back makes them agree again (the next move then holds a grid
    /// heading, not the angle the body jammed at); the task ends with `MOVE_DONE` after it. Cute
    /// takes the turn as made and learns otherwise from the next FORWARD's reply.
    fn turn_back(&mut self, io: &mut Io<'_>, mv: Move) {
        match io.motor.start_turn_back(io.now, io.sensors) {
            Ok(()) => {
                self.counters.turns_undone += 1;
                self.stage = Stage::TurningBack { mv };
            }
            Err(e) => {
                tracing::warn!(error = %e, ?mv, "cannot turn back after a failed turn");
                self.end_task(io.now);
            }
        }
    }

    fn bumped(&mut self, io: &mut Io<'_>) {
        io.motor.stop(io.now);
        self.counters.bumps += 1;
        tracing::warn!(travelled_m = ?io.motor.travelled_m(io.sensors), "bumper pressed during FORWARD: stopped");
        self.end_stopped_forward(io);
    }

    /// Feeds the push watch the drift estimate's counts now: the first sample after the FORWARD
    /// started becomes its baseline, and it fires when a later one jumped by more than
    /// [`crate::sensors::PUSH_JUMP_DEG`] (module docs, "Pushed"). Whether it fired.
    fn poll_push_watch(&mut self, io: &Io<'_>) -> bool {
        let Some(start) = self.push_watch.as_mut() else {
            return false;
        };
        let now = io.sensors.drift_counts();
        if now.samples <= start.samples + 1 {
            // that sample still holds what the turn before did
            start.pushes = now.pushes;
            return false;
        }
        now.pushes > start.pushes
    }

    /// Something turned the body under its wheels during a FORWARD: stop and end as after the
    /// bumper (module docs, "Pushed").
    fn pushed(&mut self, io: &mut Io<'_>) {
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
    /// ahead is reported blocked, and the robot drives back (by default) before `MOVE_DONE`.
    fn end_stopped_forward(&mut self, io: &mut Io<'_>) {
        self.edge_echoes.clear();
        self.localiser.touched();
        self.report_obstacle();
        self.back_off_or_end(io);
    }

    /// The newest reading if it arrived after the FORWARD started at `since` and was not taken
    /// on an earlier poll (the straight reading at rest, taken before `since`, is not one), with
    /// the odometry carried to when the sonar measured (encoder counts arrive less often than
    /// distance frames).
    fn new_drive_reading(&mut self, io: &Io<'_>, since: Instant) -> Option<DriveReading> {
        let r = io.us.latest()?;
        if r.at <= since || self.last_drive_reading.is_some_and(|t| r.at <= t) {
            return None;
        }
        self.last_drive_reading = Some(r.at);
        let offset = io.motor.cell_offset(r.at - io.motor.config().sonar_lag, io.sensors);
        // a FORWARD drives at most 1½ cells (half a cell of slack either way): anything else is
        // a bad extrapolation, not a place to put an echo
        let cell = io.motor.config().cell_size_m;
        let driven_m = offset.along_m - self.forward_from_m;
        if r.value >= 0.0 && !(-0.5 * cell..=2.0 * cell).contains(&driven_m) {
            return None;
        }
        Some(DriveReading { cm: r.value, offset })
    }

    /// Feeds the reading `r`, taken while a FORWARD drives, to the stall watch, paired with how
    /// far the wheels had driven when the sonar measured.
    fn watch_forward(&mut self, r: DriveReading) -> Option<Stall> {
        let watch = self.stall_watch.as_mut()?;
        if r.cm < 0.0 || !r.cm.is_finite() {
            watch.restart(); // no echo: the next may come from another surface
            return None;
        }
        let driven_m = r.offset.along_m - self.forward_from_m;
        tracing::trace!(driven_m, range_cm = r.cm, "echo during a FORWARD");
        watch.push(driven_m, f64::from(r.cm) / 100.0)
    }

    /// The FORWARD is stalled (`pilot/stall.rs`): stop, take the sonar's word for how far the
    /// body went, report the cell ahead as blocked and drive back, as after the bumper.
    fn stalled(&mut self, io: &mut Io<'_>, stall: Stall) {
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
        io.motor.correct_along(self.forward_from_m + stall.driven_m - now_m);
        self.end_stopped_forward(io);
    }

    /// After a FORWARD stopped short: drive back to the cell it started from (by default), then
    /// `MOVE_DONE`.
    fn back_off_or_end(&mut self, io: &mut Io<'_>) {
        if self.back_off {
            match io.motor.start_return(io.now, io.sensors) {
                Ok(()) => {
                    self.stage = Stage::BackingOff;
                    return;
                }
                Err(e) => tracing::warn!(error = %e, "cannot back off"),
            }
        }
        self.end_task(io.now);
    }
}
