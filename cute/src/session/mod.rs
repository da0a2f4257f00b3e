//! The Carto client as a sans-IO state machine over `protocol::link`.
//!
//! Concept: [`Cute`] owns the map, the robot's believed pose and the current mission
//! (cartography or a trajectory). The runtime that owns the socket calls
//! [`Cute::on_connected`], [`Cute::on_bytes`], [`Cute::on_disconnected`] and [`Cute::poll`] with
//! the current time, writes out [`Cute::take_outgoing`], and asks [`Cute::next_connect_at`] when
//! to dial again. The GUI calls the user actions ([`Cute::start_cartography`], [`Cute::go_to`],
//! [`Cute::stop`], [`Cute::reset_map`]) and shows [`Cute::take_events`] as pop-ups. Nothing here
//! reads a clock or a socket; user actions use the last `now` the runtime passed in.
//!
//! Behaviour (`protocols.md` §1, research §1.7 and §1.10):
//! - On connect: SEND_ROBOT_POSITION, then nothing else until ROBOT_POSITION_RECEIVED.
//! - Cartography: one SEND_MOVE_CARTOGRAPHY at a time. SET_ROBOT_POSITION / SET_OBSTACLE_POSITION
//!   before MOVE_DONE give the move's result, which feeds the [`Cartographer`] and the map when
//!   MOVE_DONE arrives (MOVE_DONE alone after a turn means the turn was made; after a FORWARD it
//!   means Carto could not execute it: re-sent up to [`MAX_REJECTED`] times).
//! - Go to: A* over known free cells, then one SEND_MOVES_TRAJECTORY frame per command, each
//!   with the batch's `n_total` (batches of at most 255, or 50 in compat mode). Each
//!   SET_ROBOT_POSITION moves the robot on the map; MOVE_DONE ends the batch (the robot is then
//!   at the batch's last cell); SET_OBSTACLE_POSITION aborts the mission (obstacle marked,
//!   [`CuteEvent::ObstacleMet`]).
//! - STOP: STOP_ROBOT, mission dropped, back to idle.
//! - Disconnect: the mission is kept; reconnect after 0.25 s, doubling to 4 s per failed attempt
//!   ([`Cute::next_connect_at`], [`Cute::on_connect_failed`]). After reconnecting the position
//!   is sent again and the mission resumes: an unanswered cartography move is re-sent, an
//!   interrupted trajectory is re-planned from the last reported cell.
//! - `--compat explobot-2024` (the original Carto): `Msg` little-endian, never
//!   SEND_ROBOT_POSITION nor SEND_MOVE_CARTOGRAPHY (they crash it), batches of at most 50. The
//!   original replies nothing to trajectories, so a compat trajectory is fire-and-forget: all
//!   batches are sent at once and the robot is assumed at the destination
//!   ([`CuteEvent::TrajectorySent`]); any position Carto does report still updates the map.
//!   The original cannot map, so a click plans through unknown cells as if they were free
//!   ([`CuteEvent::PlannedThroughUnknown`]); those cells go back to unknown when the trajectory
//!   is cleared. After a STOP the original drops the next batch: Cute sends only the first batch
//!   of the next trajectory, keeps the robot where it was and reports
//!   [`CuteEvent::BatchDropped`] (the rest would run from the wrong cell) — see [`quirks`].
//! - No ROBOT_POSITION_RECEIVED for [`HINT_AFTER`] requests in a row → [`CuteEvent::CompatHint`]
//!   ([`COMPAT_HINT`]): the original Carto ignores our big-endian ids.
//! - Always tolerated: unsolicited ROBOT_POSITION_RECEIVED, stray MOVE_DONE, unknown ids, frames
//!   split or merged arbitrarily. A fatal framing error drops the connection
//!   ([`Cute::close_requested`]).
//! - Timeouts: no ROBOT_POSITION_RECEIVED within `ack_timeout` → [`CuteEvent::MoveTimeout`] and
//!   the position is re-sent; no MOVE_DONE within `move_timeout` per command →
//!   [`CuteEvent::MoveTimeout`], STOP_ROBOT, mission dropped.
//!
//! Layout: `config` (settings, [`Compat`], [`CuteError`]), `events` ([`Status`], [`CuteEvent`],
//! [`Counters`]), `connection` (back-off and framing), `mission` (the `Mapping` and `Moving`
//! missions and what they own in flight); this file ties them together in [`Cute`].
//!
//! Invariants: at most one move (cartography) or one batch (trajectory) is unanswered at a time;
//! no move is sent before the position is acknowledged; the map's robot marker is the believed
//! robot cell.
//!
//! ```
//! use cute::session::{Cute, CuteConfig, Status};
//! use robot_model::grid::Heading;
//! use robot_model::time::Instant;
//! let mut cute = Cute::new(CuteConfig { rows: 4, cols: 4, start: (0, 0), heading: Heading::East,
//!     ..CuteConfig::default() }).unwrap();
//! cute.on_connected(Instant::ZERO);
//! assert_eq!(cute.take_outgoing(), [0x00, 0x05, 0x07, 0x00, 0, 0, 3]); // SEND_ROBOT_POSITION
//! cute.start_cartography().unwrap();
//! assert!(cute.take_outgoing().is_empty()); // waits for ROBOT_POSITION_RECEIVED
//! cute.on_bytes(Instant::from_millis(5), &[0x00, 0x02, 0x08, 0x00]);
//! assert_eq!(cute.take_outgoing(), [0x00, 0x03, 0x02, 0x00, 0]); // SEND_MOVE_CARTOGRAPHY FORWARD
//! assert_eq!(cute.status(), Status::Mapping);
//! ```

use protocol::link::GuiMessage;
use robot_model::grid::{Heading, Move};
use robot_model::time::Instant;
use tracing::{debug, info, warn};

mod config;
mod connection;
mod events;
mod mission;
pub mod quirks;

pub use config::{Compat, CuteConfig, CuteError, MAX_BATCH, MAX_BATCH_COMPAT};
pub use connection::{RECONNECT_MAX, RECONNECT_MIN};
pub use events::{Counters, CuteEvent, Status, Waiting};
pub use mission::MAX_REJECTED;
pub use quirks::{COMPAT_HINT, HINT_AFTER};

use crate::cartography::{CartoStats, Cartographer};
use crate::map::{CellValue, Map};
use crate::trajectory::{self, PlanError, Planner};
use connection::Connection;
use mission::{Answer, Belief, Mapping, Mission, Moving, Next, Obstacle};
use quirks::Quirks;

/// The Cute side of the link: map, robot, missions and the protocol state machine.
#[derive(Debug, Clone)]
pub struct Cute {
    config: CuteConfig,
    belief: Belief,
    status: Status,
    mission: Mission,
    connection: Connection,
    events: Vec<CuteEvent>,
    counters: Counters,
    planner: Planner,
    now: Instant,
    close_requested: bool,
    last_carto_stats: Option<CartoStats>,
    quirks: Quirks,
    /// Cells of the painted trajectory that were unknown before (compat): unknown again when
    /// the trajectory is cleared.
    unknown_path: Vec<(u8, u8)>,
    /// The last message was SET_OBSTACLE_POSITION: its cell and what the map held there before.
    /// A SET_ROBOT_POSITION next to it right after says the way was not clear
    /// ([`CuteEvent::WayNotClear`]).
    last_obstacle: Option<((u8, u8), CellValue)>,
}

impl Cute {
    /// A session with an all-unknown map (or `config.map`) and the robot at `config.start`, not
    /// connected.
    pub fn new(config: CuteConfig) -> Result<Cute, CuteError> {
        let mut map = match &config.map {
            Some(known) if (known.rows(), known.cols()) != (config.rows, config.cols) => {
                let (rows, cols, map_rows, map_cols) = (config.rows, config.cols, known.rows(), known.cols());
                return Err(CuteError::MapSize { rows, cols, map_rows, map_cols });
            }
            Some(known) => known.clone(),
            None => Map::new(config.rows, config.cols)?,
        };
        map.clear_trajectory();
        // Validates the start cell the same way cartography will.
        Cartographer::new(config.rows, config.cols, config.start, config.heading)?;
        if map.at(config.start) == Some(CellValue::Obstacle) {
            return Err(CuteError::StartBlocked { x: config.start.0, y: config.start.1 });
        }
        map.set_robot(usize::from(config.start.0), usize::from(config.start.1))?;
        let planner = Planner::new().through_unknown(config.compat.plans_through_unknown());
        Ok(Cute {
            belief: Belief { map, robot: config.start, heading: config.heading },
            connection: Connection::new(config.compat.msg_order(), config.max_frame),
            config,
            status: Status::Idle,
            mission: Mission::None,
            events: Vec::new(),
            counters: Counters::default(),
            planner,
            now: Instant::ZERO,
            close_requested: false,
            last_carto_stats: None,
            quirks: Quirks::default(),
            unknown_path: Vec::new(),
            last_obstacle: None,
        })
    }

    // ----- views -----------------------------------------------------------------------------

    /// The map.
    pub fn map(&self) -> &Map {
        &self.belief.map
    }

    /// The robot's believed cell and heading: `(x, y, heading)`.
    pub fn robot(&self) -> (u8, u8, Heading) {
        (self.belief.robot.0, self.belief.robot.1, self.belief.heading)
    }

    /// What the session is doing.
    pub fn status(&self) -> Status {
        self.status
    }

    /// The settings.
    pub fn config(&self) -> &CuteConfig {
        &self.config
    }

    /// True while the connection is up.
    pub fn is_connected(&self) -> bool {
        self.connection.is_up()
    }

    /// True once the position is acknowledged (or in compat mode) and moves may be sent.
    pub fn is_ready(&self) -> bool {
        self.connection.is_ready()
    }

    /// The counters.
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// Compat: true while the original Carto is believed to drop the next batch (a STOP went
    /// out since the last batch).
    pub fn batch_drop_pending(&self) -> bool {
        self.quirks.drop_pending()
    }

    /// The running cartographer, if mapping.
    pub fn cartographer(&self) -> Option<&Cartographer> {
        match &self.mission {
            Mission::Mapping(m) => Some(m.cartographer()),
            _ => None,
        }
    }

    /// Counters of the last cartography run (running or finished).
    pub fn cartography_stats(&self) -> Option<CartoStats> {
        self.cartographer().map(|c| c.stats()).or(self.last_carto_stats)
    }

    /// Takes the bytes to write to the socket.
    pub fn take_outgoing(&mut self) -> Vec<u8> {
        self.connection.take_outgoing()
    }

    /// Takes the events since the last call.
    pub fn take_events(&mut self) -> Vec<CuteEvent> {
        std::mem::take(&mut self.events)
    }

    /// True (once) when the runtime should close the connection after a fatal protocol error.
    pub fn close_requested(&mut self) -> bool {
        std::mem::take(&mut self.close_requested)
    }

    /// When to try connecting next; `None` while connected. May be in the past: try now.
    pub fn next_connect_at(&self, now: Instant) -> Option<Instant> {
        let _ = now;
        self.connection.next_connect_at()
    }

    // ----- network -----------------------------------------------------------------------------

    /// The connection is up: send the position (unless compat) and resume the mission.
    pub fn on_connected(&mut self, now: Instant) {
        self.now = now;
        let ack_deadline = match self.config.compat {
            Compat::Explobot2024 => None,
            Compat::Default => Some(now + self.config.ack_timeout),
        };
        let Some(reconnect) = self.connection.connected(ack_deadline) else {
            return;
        };
        if reconnect {
            self.counters.reconnects += 1;
        }
        info!(reconnect, "connected to Carto");
        self.events.push(CuteEvent::Connected);
        if ack_deadline.is_some() {
            self.send_position();
        }
        self.pump();
    }

    /// A connection attempt failed: back off (doubling up to [`RECONNECT_MAX`]).
    pub fn on_connect_failed(&mut self, now: Instant) {
        self.now = now;
        self.connection.connect_failed(now);
    }

    /// The connection dropped: keep the mission, schedule a reconnect.
    pub fn on_disconnected(&mut self, now: Instant) {
        self.now = now;
        if !self.connection.disconnected(now) {
            return;
        }
        warn!("connection to Carto lost");
        self.events.push(CuteEvent::ConnectionLost);
        self.mission.on_disconnected(&mut self.belief);
    }

    /// Bytes from Carto, in any chunking.
    pub fn on_bytes(&mut self, now: Instant, bytes: &[u8]) {
        self.now = now;
        if !self.is_connected() {
            return;
        }
        self.counters.bytes_in += bytes.len() as u64;
        for item in self.connection.decode(bytes) {
            match item {
                Ok(msg) => {
                    self.counters.frames_in += 1;
                    self.handle(msg);
                }
                Err(e) => {
                    self.counters.decode_errors += 1;
                    let fatal = e.is_fatal();
                    warn!(error = %e, fatal, "bad frame from Carto");
                    self.events.push(CuteEvent::ProtocolError { message: e.to_string(), fatal });
                    if fatal {
                        self.close_requested = true;
                        self.on_disconnected(now);
                        return;
                    }
                }
            }
        }
        self.pump();
    }

    /// Checks timeouts and sends whatever is due.
    pub fn poll(&mut self, now: Instant) {
        self.now = now;
        if self.connection.ack_overdue(now, now + self.config.ack_timeout) {
            self.counters.timeouts += 1;
            self.events.push(CuteEvent::MoveTimeout { waiting_for: Waiting::PositionAck });
            if self.quirks.position_unanswered() {
                warn!("{COMPAT_HINT}");
                self.events.push(CuteEvent::CompatHint);
            }
            self.send_position();
        }
        if self.mission.deadline().is_some_and(|deadline| now >= deadline) {
            warn!("no MOVE_DONE in time; stopping the robot");
            self.counters.timeouts += 1;
            self.events.push(CuteEvent::MoveTimeout { waiting_for: Waiting::MoveDone });
            self.send_stop();
            self.end_mission(Status::Idle);
        }
        self.pump();
    }

    // ----- user actions --------------------------------------------------------------------------

    /// Starts cartography from the robot's current pose.
    pub fn start_cartography(&mut self) -> Result<(), CuteError> {
        if self.config.compat == Compat::Explobot2024 {
            return Err(CuteError::Unsupported { what: "cartography" });
        }
        if self.is_busy() {
            return Err(CuteError::Busy { status: self.status });
        }
        let (robot, heading) = (self.belief.robot, self.belief.heading);
        let carto = Cartographer::new(self.config.rows, self.config.cols, robot, heading)?;
        self.clear_trajectory();
        self.mission = Mission::Mapping(Mapping::new(carto));
        self.status = Status::Mapping;
        self.pump();
        Ok(())
    }

    /// Plans to `(x, y)` over known free cells (compat: also unknown ones, with a warning) and
    /// starts driving there.
    pub fn go_to(&mut self, x: u8, y: u8) -> Result<(), PlanError> {
        if self.is_busy() {
            return Err(PlanError::Busy);
        }
        self.clear_trajectory();
        let b = &mut self.belief;
        let t = match self.planner.plan(&b.map, b.robot, b.heading, (x, y)) {
            Ok(t) => t,
            Err(e) => {
                if matches!(e, PlanError::NoPath { .. }) {
                    self.events.push(CuteEvent::NoPath { x, y });
                }
                return Err(e);
            }
        };
        let unknown: Vec<(u8, u8)> =
            t.path.iter().copied().filter(|&c| b.map.at(c) == Some(CellValue::Unknown)).collect();
        trajectory::paint(&mut b.map, &t);
        if !unknown.is_empty() {
            let cells = unknown.len();
            warn!(x, y, cells, "path planned through unknown cells as if they were free");
            self.events.push(CuteEvent::PlannedThroughUnknown { x, y, cells });
        }
        self.unknown_path = unknown;
        if t.commands.is_empty() {
            self.events.push(CuteEvent::Reached { x, y });
            return Ok(());
        }
        self.mission = Mission::Moving(Moving::new((x, y), &t.commands, self.config.compat));
        self.status = Status::Moving;
        self.pump();
        Ok(())
    }

    /// STOP: stops the robot now and drops the mission. Compat: the original Carto will drop the
    /// next batch ([`quirks`]).
    pub fn stop(&mut self) {
        if self.is_connected() {
            self.send_stop();
        }
        self.clear_trajectory();
        self.end_mission(Status::Idle);
        self.events.push(CuteEvent::Stopped);
    }

    /// RESET: every cell back to unknown (the robot stays where it is). A running cartography
    /// restarts from scratch after the move in flight.
    pub fn reset_map(&mut self) {
        let robot = self.belief.robot;
        self.unknown_path.clear();
        self.belief.map.reset();
        let _ = self.belief.map.set_robot(usize::from(robot.0), usize::from(robot.1));
        if let Mission::Mapping(m) = &mut self.mission {
            m.restart(&self.belief);
        }
    }

    // ----- internals ---------------------------------------------------------------------------

    fn is_busy(&self) -> bool {
        matches!(self.status, Status::Mapping | Status::Moving)
    }

    fn send(&mut self, msg: &GuiMessage) {
        let n = self.connection.encode(msg);
        self.counters.frames_out += 1;
        self.counters.bytes_out += n as u64;
    }

    fn send_stop(&mut self) {
        self.send(&GuiMessage::StopRobot);
        self.quirks.stop_sent(self.config.compat);
    }

    /// Clears the painted trajectory; cells it painted over unknown ones are unknown again.
    fn clear_trajectory(&mut self) {
        for (x, y) in self.unknown_path.drain(..) {
            let map = &mut self.belief.map;
            if matches!(map.at((x, y)), Some(CellValue::Waypoint | CellValue::Destination)) {
                let _ = map.set(usize::from(x), usize::from(y), CellValue::Unknown);
            }
        }
        self.belief.map.clear_trajectory();
    }

    fn send_position(&mut self) {
        let (x, y) = self.belief.robot;
        self.send(&GuiMessage::SendRobotPosition { x, y, direction: self.belief.heading.into() });
    }

    fn send_batch(&mut self, batch: &[Move]) {
        // Batches are at most 255 long (chunks of at most MAX_BATCH).
        let n_total = batch.len().min(MAX_BATCH) as u8;
        for &c in batch {
            self.counters.moves_sent += 1;
            self.send(&GuiMessage::SendMovesTrajectory { n_total, command: c.into() });
        }
    }

    fn end_mission(&mut self, status: Status) {
        if let Mission::Mapping(m) = &self.mission {
            self.last_carto_stats = Some(m.cartographer().stats());
        }
        self.mission = Mission::None;
        self.status = status;
    }

    /// Sends the next move or batch when the link is ready and nothing is in flight.
    fn pump(&mut self) {
        if !self.is_ready() {
            return;
        }
        let timeout = self.config.move_timeout;
        match self.mission.next(&mut self.belief, &mut self.planner, self.now, timeout) {
            Next::Wait => {}
            Next::Cartography(command) => {
                self.counters.moves_sent += 1;
                self.send(&GuiMessage::SendMoveCartography { command: command.into() });
            }
            Next::Batch(batch) => self.send_batch(&batch),
            Next::FireAndForget(all) => {
                if self.quirks.take_drop() {
                    // The original skips this batch; the rest would run from the wrong cell.
                    let first = all.first().map(Vec::as_slice).unwrap_or_default();
                    self.send_batch(first);
                    let (x, y) = self.belief.robot;
                    warn!(x, y, commands = first.len(), "the 2024 Carto drops the first batch after a STOP");
                    self.events.push(CuteEvent::BatchDropped { commands: first.len(), x, y });
                    self.clear_trajectory();
                } else {
                    for batch in &all {
                        self.send_batch(batch);
                    }
                    // One move of the marker: cells between batches were not seen either.
                    self.belief.assume_driven(&all.concat());
                    let commands = all.iter().map(Vec::len).sum();
                    self.events.push(CuteEvent::TrajectorySent { commands });
                }
                self.end_mission(Status::Idle);
            }
            Next::Mapped(stats) => {
                let map = &self.belief.map;
                let free = map.cells().iter().filter(|v| v.is_known_free()).count();
                let obstacles = map.count(CellValue::Obstacle);
                info!(free, obstacles, moves = stats.commands, "cartography done");
                self.events.push(CuteEvent::MappingDone {
                    free,
                    obstacles,
                    unreachable: stats.unreachable,
                    moves: stats.commands,
                });
                self.end_mission(Status::Done);
            }
            Next::Arrived => {
                self.clear_trajectory();
                let (x, y) = self.belief.robot;
                self.events.push(CuteEvent::Reached { x, y });
                self.end_mission(Status::Idle);
            }
            Next::NoPath((x, y)) => {
                self.events.push(CuteEvent::NoPath { x, y });
                self.clear_trajectory();
                self.end_mission(Status::Idle);
            }
        }
    }

    /// Carto refused a FORWARD from `robot` into `cell` because the way is not clear (the pair
    /// SET_OBSTACLE_POSITION, SET_ROBOT_POSITION). In cartography the move's result says so; a
    /// trajectory has already ended on the obstacle, so the cell gets back what it held and the
    /// move is blocked.
    fn way_not_clear(&mut self, robot: (u8, u8), cell: (u8, u8), before: CellValue) {
        self.events.push(CuteEvent::WayNotClear { x: cell.0, y: cell.1 });
        if self.mission.on_way_not_clear(cell) {
            return;
        }
        // a painted trajectory is cleared by now: its cells were known free
        let before = if before.is_known_free() { CellValue::Free } else { before };
        if self.belief.map.at(cell) == Some(CellValue::Obstacle) && before != CellValue::Obstacle {
            let _ = self.belief.map.set(usize::from(cell.0), usize::from(cell.1), before);
        }
        self.belief.set_robot(robot);
        let _ = self.belief.map.note_way_not_clear(robot, cell);
    }

    fn handle(&mut self, msg: GuiMessage) {
        debug!(?msg, "from Carto");
        let last_obstacle = self.last_obstacle.take();
        match msg {
            GuiMessage::RobotPositionReceived => {
                self.quirks.position_answered();
                if self.connection.acknowledge() {
                    self.events.push(CuteEvent::PositionAcknowledged);
                } else {
                    self.counters.unsolicited += 1;
                }
            }
            GuiMessage::SetRobotPosition { x, y } => {
                if !self.belief.map.contains(usize::from(x), usize::from(y)) {
                    warn!(x, y, "robot position outside the map; ignored");
                    return;
                }
                if let Some((cell, before)) = last_obstacle
                    && Heading::between((x, y), cell).is_some()
                {
                    return self.way_not_clear((x, y), cell, before);
                }
                if !self.mission.on_position(&mut self.belief, x, y) {
                    self.counters.unsolicited += 1;
                    self.belief.set_robot((x, y));
                }
            }
            GuiMessage::SetObstaclePosition { x, y } => {
                self.counters.obstacles += 1;
                self.last_obstacle = self.belief.map.at((x, y)).map(|before| ((x, y), before));
                match self.mission.on_obstacle(&mut self.belief, x, y) {
                    Obstacle::Recorded => {}
                    Obstacle::Aborted => {
                        self.events.push(CuteEvent::ObstacleMet { x, y });
                        self.end_mission(Status::Idle);
                    }
                    Obstacle::Unsolicited => {
                        self.counters.unsolicited += 1;
                        self.belief.mark_obstacle(x, y);
                    }
                }
            }
            GuiMessage::MoveDone => {
                self.counters.moves_done += 1;
                let resyncs = self.mission.heading_resyncs();
                match self.mission.on_move_done(&mut self.belief) {
                    Answer::Applied => {
                        if self.mission.heading_resyncs() > resyncs {
                            self.events.push(CuteEvent::TurnNotMade { faced: self.belief.heading });
                        }
                    }
                    Answer::Rejected(command) => {
                        self.events.push(CuteEvent::MoveRejected { command });
                        self.end_mission(Status::Idle);
                    }
                    Answer::Unsolicited => self.counters.unsolicited += 1,
                }
            }
            GuiMessage::Unknown { msg, .. } => {
                self.counters.unknown_frames += 1;
                debug!(msg, "unknown message id ignored");
            }
            other => {
                self.counters.unknown_frames += 1;
                warn!(?other, "client-to-server message received from Carto; ignored");
            }
        }
    }
}
