//! The pilot: Carto's side of the link session with Cute, as a sans-IO state machine.
//!
//! Concept: decoded [`Request`]s come in through [`Pilot::handle`]; [`Pilot::poll`] runs the work
//! they created — one *task* at a time, each a list of commands — by asking the
//! [`Ultrasound`](crate::ultrasound::Ultrasound) and driving the [`Motor`](crate::motor::Motor);
//! [`Reply`]s to send back pile up for [`Pilot::take_replies`].
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
//! - A turn that fails — jammed (the IMU shows no progress for [`Motion::jam_after`](crate::config::Motion::jam_after)), timed
//!   out, not converged, a reading gone stale — is turned back to the grid heading it started
//!   from before `MOVE_DONE`, so the body faces the heading Carto still stores (Cute learns from
//!   the next FORWARD's reply that the turn was not made). A reconnect whose re-sent pose takes
//!   that turn as made defeats this: the stored heading then follows Cute (a known limit).
//! - The bumper, pressed while a FORWARD runs, stops it: `SET_OBSTACLE_POSITION(cell ahead)`, the
//!   rest is aborted, and the robot drives back to the cell it started from before
//!   `MOVE_DONE`. Pressed at the obstacle check, it counts as an obstacle.
//! - A FORWARD whose sonar range holds while the wheels drive is stalled (`pilot/stall.rs`,
//!   [`Safety::stall_watch`](crate::config::Safety::stall_watch)): it is stopped, the odometry takes the sonar's word, and it
//!   ends as after the bumper (`SET_OBSTACLE_POSITION(cell ahead)`, back-off, `MOVE_DONE`).
//! - **Pushed.** A FORWARD during which the gap between the IMU's and the wheels' headings jumps
//!   by more than [`crate::sensors::PUSH_JUMP_DEG`] has met something beside the bumper: a corner
//!   or a leg turned the body under its wheels, and mecanum rollers give way sideways
//!   ([`ImuDrift::push_watch`](crate::config::ImuDrift::push_watch)). It ends as after the bumper. The first sample of the drift
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
//! Parts: the [`Pilot`] owns five components, each with its own state and methods, none reaching
//! into another's: `tasks.rs` (the task queue and the partial batch), `localisation.rs` (the
//! stored pose and the belief around it), `echoes.rs` (the echo points the safety checks ask),
//! `forward.rs` (the watches of a running FORWARD) and `sliding.rs` (local motion: the legs of
//! a sliding way). The pilot itself holds the stage machine
//! (`stage.rs`) and sequences the parts: requests and link events (`session.rs`), starting a
//! command (`commands.rs`), the scan, corridor and turn checks (`safety.rs`), a FORWARD stopped
//! short (`stopped.rs`). Every step of a
//! poll takes one [`Io`]: the time, the motor and the readings.
//!
//! ```
//! use carto::pilot::{Health, Io, Pilot, Reply, Request};
//! use carto::{motor::Motor, sensors::SensorState, ultrasound::Ultrasound, CartoConfig};
//! use robot_model::grid::{Heading, Move};
//! use robot_model::time::Instant;
//! let cfg = CartoConfig::default();
//! let (mut pilot, mut motor) = (Pilot::new(&cfg), Motor::new(cfg.clone()));
//! let (sensors, us) = (SensorState::default(), Ultrasound::new(30.0, cfg.safety.distance_max_age));
//! let now = Instant::ZERO;
//! pilot.handle(now, Request::SetPose { x: 2, y: 3, direction: Ok(Heading::East) }, &mut motor);
//! // a cartography move without the sensor board cannot run: MOVE_DONE only
//! pilot.handle(now, Request::Cartography { command: Ok(Move::Forward) }, &mut motor);
//! let health = Health { sensor_board: false, motor_board: true };
//! pilot.poll(&mut Io { now, motor: &mut motor, sensors: &sensors, us: &us, health });
//! assert_eq!(pilot.take_replies(), vec![Reply::PositionReceived, Reply::MoveDone]);
//! ```

use robot_model::time::{Duration, Instant};

use crate::CartoConfig;
use crate::estimate::grid::EvidenceGrid;
#[cfg(doc)]
use crate::estimate::localiser::Localiser;
use crate::ultrasound::Check;
use robot_model::grid::{GridPose, Move};

mod commands;
mod echoes;
mod forward;
mod interface;
mod limits;
mod localisation;
mod safety;
mod session;
mod sliding;
mod stage;
mod stall;
mod stopped;
mod tasks;

use echoes::Echoes;
use forward::ForwardWatch;
use limits::Safety;
use localisation::Localisation;
use sliding::Sliding;
use tasks::{Next, Tasks};

pub use interface::{Health, InputNote, Io, PilotCounters, Reply, Request};
pub use stage::Activity;
use stage::Stage;

/// The link session's state machine (see the module docs).
#[derive(Debug, Clone)]
pub struct Pilot {
    distance_wait: Duration,
    stale_after: Duration,
    /// The geometry and limits of the safety checks.
    safety: Safety,
    /// The running task, the queued ones and the partial batch.
    tasks: Tasks,
    /// The stored pose and the belief around it.
    place: Localisation,
    /// The echo points the safety checks ask.
    echoes: Echoes,
    /// The watches of the running FORWARD.
    forward: ForwardWatch,
    /// The sliding way of the running FORWARD or turn.
    sliding: Sliding,
    stage: Stage,
    rest_since: Instant,
    /// A reading of the running scan never came.
    scan_missing: bool,
    /// This FORWARD's scan is a look aside to this side (+1 left, −1 right) by this many
    /// degrees, to correct the belief (`pilot/safety.rs`, "Looking aside").
    looking_aside: Option<(f64, f64)>,
    /// The mapping turn that just succeeded: once its task has ended, the robot looks past it.
    look_pending: Option<Move>,
    /// Re-facings of the grid heading that failed in a row ([`Pilot::refacing_failed`]).
    reface_failures: u8,
    replies: Vec<Reply>,
    notes: Vec<InputNote>,
    counters: PilotCounters,
}

impl Pilot {
    /// An idle pilot with no pose.
    pub fn new(cfg: &CartoConfig) -> Self {
        let safety = Safety::new(cfg);
        Pilot {
            distance_wait: cfg.safety.distance_wait,
            stale_after: cfg.boards.sensor_stale_after,
            safety,
            tasks: Tasks::default(),
            place: Localisation::new(cfg),
            echoes: Echoes::new(safety),
            forward: ForwardWatch::new(cfg),
            sliding: Sliding::default(),
            stage: Stage::Next,
            rest_since: Instant::ZERO,
            scan_missing: false,
            looking_aside: None,
            look_pending: None,
            reface_failures: 0,
            replies: Vec::new(),
            notes: Vec::new(),
            counters: PilotCounters::default(),
        }
    }

    /// The stored pose, if Cute sent one.
    pub fn pose(&self) -> Option<GridPose> {
        self.place.pose()
    }

    /// Every echo point the safety checks hold now, in the grid's metric frame
    /// ([`crate::surroundings`]): those kept at rest and those heard moving (not the floor plan).
    pub fn echo_points(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.echoes.points()
    }

    /// The evidence grid the localiser builds from the readings (and the floor plan, when one is
    /// given), in the grid's metric frame.
    pub fn evidence(&self) -> &EvidenceGrid {
        self.place.localiser().grid()
    }

    /// The covariance of the believed position, m² ([`Localiser::position_covariance`]).
    pub fn position_covariance(&self) -> Option<[[f64; 2]; 2]> {
        self.place.localiser().position_covariance()
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
            // the legs of a sliding way are parts of its FORWARD, or shift before a turn
            Stage::Sliding { turn: None, .. } => Activity::DrivingForward,
            Stage::Sliding { turn: Some(_), .. } => Activity::ShiftingBeforeTurn,
            Stage::TurningBack { .. } => Activity::TurningBack,
            Stage::LookingPast { .. } => Activity::LookingPastTurn,
            Stage::Recentring { .. } => Activity::Recentring,
            Stage::Refacing { .. } => Activity::Refacing,
        }
    }

    /// Gives the safety checks known surface points ([`crate::Carto::add_known_surfaces`]).
    pub fn add_known_surfaces(&mut self, points: impl IntoIterator<Item = (f64, f64)>) {
        let points: Vec<(f64, f64)> = points.into_iter().collect();
        self.place.pin(points.iter().copied());
        self.echoes.add_fixed(points);
    }

    /// Whether a task runs or waits.
    pub fn is_busy(&self) -> bool {
        // a look past a turn runs after the turn's task has ended
        self.tasks.any() || !matches!(self.stage, Stage::Next)
    }

    /// Commands waiting: the rest of the current task, queued tasks and a partial batch.
    pub fn pending(&self) -> usize {
        self.tasks.pending()
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

    /// Ends the current task (completed or aborted): `MOVE_DONE`, back to the next task.
    fn end_task(&mut self, now: Instant) {
        self.tasks.end_current();
        self.stage = Stage::Next;
        self.rest_since = now;
        self.replies.push(Reply::MoveDone);
    }

    fn fail(&mut self, now: Instant, why: &str) {
        self.note("move cannot run", true, format!("move cannot run ({why}): task ends with MOVE_DONE only"));
        self.counters.moves_failed += 1;
        self.sliding.forget_way_in();
        self.end_task(now);
    }

    /// Runs pending work. `io.motor` must have been polled at `io.now` already (it holds the
    /// outcome of a move that just ended).
    pub fn poll(&mut self, io: &mut Io<'_>) {
        // Bounded: each pass either waits (returns) or consumes a command or a task.
        for _ in 0..1024 {
            match self.stage {
                Stage::Next => {
                    if !self.tasks.running()
                        && let Some(turn) = self.look_pending.take()
                    {
                        // the turn's MOVE_DONE has gone out: Cute and Carto hold the new heading
                        // whatever cuts the look; the next command waits in the queue
                        self.look_past(io, turn, None);
                        continue;
                    }
                    match self.tasks.next() {
                        Next::Idle => return,
                        Next::EndOfTask => {
                            self.end_task(io.now);
                            continue;
                        }
                        Next::Command(kind, command) => self.start_command(io, kind, command),
                    }
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
                    let done_cm = if self.place.pose().is_some() {
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
                            let pressed = io.sensors.bumper_pressed();
                            if !pressed {
                                self.localise(io, Some(cm));
                            }
                            self.note_reading(io, Some(cm));
                            if !pressed && let Some(way) = self.way_back() {
                                self.start_way_back(io, way, "an echo straight ahead");
                            } else {
                                self.note(
                                    "obstacle ahead",
                                    false,
                                    format!("obstacle ahead at {cm} cm: no motion"),
                                );
                                // a pressed bumper met the cell ahead; an echo straight ahead is
                                // what the plan, if any, says of that cell
                                if pressed {
                                    self.report_obstacle();
                                } else {
                                    self.report_refused_forward(true);
                                }
                                self.end_task(io.now);
                            }
                        }
                        Check::Clear { cm } => {
                            tracing::debug!(?cm, "path clear");
                            self.localise(io, cm);
                            self.note_reading(io, cm);
                            self.scan_missing = false;
                            self.plan_look_aside(io);
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
                    if kind == Move::Forward && io.motor.is_busy() && self.forward.pushed(io.sensors) {
                        self.pushed(io);
                        continue;
                    }
                    // not on the poll the FORWARD ended: the odometry's origin has moved on
                    if kind == Move::Forward
                        && io.motor.is_busy()
                        && let Some(r) = self.forward.new_reading(io, since)
                    {
                        self.note_drive_reading(io, r);
                        if let Some(stall) = self.forward.stalled(r) {
                            self.stalled(io, stall);
                            continue;
                        }
                    }
                    match io.motor.take_outcome() {
                        None if io.motor.is_busy() => return,
                        None => {
                            // The move vanished (stopped from outside): treat as failed.
                            self.counters.moves_failed += 1;
                            self.echoes.forget_moving();
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
                                self.echoes.forget_moving();
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
                Stage::Sliding { since, turn } => {
                    if !self.poll_slide(io, since, turn) {
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
                    // a sliding way is retraced leg by leg
                    None | Some(Ok(())) if self.retrace_slide(io) => {}
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
        let from = self.place.pose();
        if kind == Move::Forward {
            self.sliding.forward_made(from);
        }
        let Some((pose, entered)) = self.place.move_made(kind) else {
            // without a pose the echo points cannot follow the robot
            self.echoes.forget();
            return;
        };
        if let Some((x, y)) = entered {
            self.replies.push(Reply::RobotPosition { x, y });
        }
        tracing::info!(pose = %pose, "move done");
    }

    fn report_obstacle(&mut self) {
        self.counters.obstacles += 1;
        match self.place.cell_ahead() {
            Some((x, y)) => self.replies.push(Reply::Obstacle { x, y }),
            None => tracing::info!("obstacle ahead, but no robot position to report it against"),
        }
    }

    /// A FORWARD refused because the body's way to the next centre is not clear of its width
    /// (an echo point in the corridor, `pilot/safety.rs`), while no reading at rest put anything
    /// straight ahead within the threshold. The reply is the 2024 one, SET_OBSTACLE_POSITION
    /// with the cell ahead, followed by SET_ROBOT_POSITION with the cell the robot stays in:
    /// the move is blocked, but nothing says the cell ahead is occupied, so Cute keeps it unknown
    /// and may reach it another way (`protocol/README.md`, "Refused FORWARD").
    fn report_way_not_clear(&mut self) {
        self.report_obstacle();
        if let Some(p) = self.place.pose() {
            self.replies.push(Reply::RobotPosition { x: p.x, y: p.y });
        }
    }

    /// Answers a refused FORWARD: the cell ahead occupied, or only the way there not clear.
    /// With a complete floor plan the plan decides: occupied only when the body itself cannot
    /// stand in the cell ([`Pilot::fits_in_cell_ahead`]); without one, `occupied_without_plan`.
    fn report_refused_forward(&mut self, occupied_without_plan: bool) {
        if self.fits_in_cell_ahead().map_or(occupied_without_plan, |fits| !fits) {
            self.report_obstacle();
        } else {
            self.report_way_not_clear();
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
}
