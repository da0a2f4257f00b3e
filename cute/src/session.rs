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
//! - Always tolerated: unsolicited ROBOT_POSITION_RECEIVED, stray MOVE_DONE, unknown ids, frames
//!   split or merged arbitrarily. A fatal framing error drops the connection
//!   ([`Cute::close_requested`]).
//! - Timeouts: no ROBOT_POSITION_RECEIVED within `move_timeout` → [`CuteEvent::MoveTimeout`] and
//!   the position is re-sent; no MOVE_DONE within `move_timeout` per command →
//!   [`CuteEvent::MoveTimeout`], STOP_ROBOT, mission dropped.
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

use std::collections::VecDeque;
use std::str::FromStr;

use protocol::link::{self, Decoder, GuiMessage, MsgOrder};
use robot_model::time::{Duration, Instant};
use thiserror::Error;
use tracing::{debug, info, warn};

use crate::cartography::{CartoError, Cartographer, MoveResult};
use crate::map::{CellValue, Map, MapError};
use crate::trajectory::{PlanError, Planner};
use robot_model::grid::{Heading, Move};

/// First reconnect delay after a disconnect.
pub const RECONNECT_MIN: Duration = Duration::from_millis(250);
/// Largest reconnect delay.
pub const RECONNECT_MAX: Duration = Duration::from_secs(4);
/// Largest trajectory batch on the wire (`n_total` is one byte).
pub const MAX_BATCH: usize = 255;
/// Largest batch the original Carto accepts (`--compat explobot-2024`).
pub const MAX_BATCH_COMPAT: usize = 50;
/// Consecutive cartography moves answered by a bare MOVE_DONE before mapping gives up.
pub const MAX_REJECTED: u32 = 3;

/// Which Carto the session talks to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Compat {
    /// Our Carto: big-endian `Msg`, the full protocol.
    #[default]
    Default,
    /// The original 2024 Carto: little-endian `Msg`, trajectories only, batches ≤ 50.
    Explobot2024,
}

impl FromStr for Compat {
    type Err = CuteError;
    fn from_str(s: &str) -> Result<Compat, CuteError> {
        match s {
            "default" | "none" => Ok(Compat::Default),
            "explobot-2024" => Ok(Compat::Explobot2024),
            other => Err(CuteError::UnknownCompat { name: other.to_string() }),
        }
    }
}

/// Session settings.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CuteConfig {
    /// Map rows (1..=256).
    pub rows: usize,
    /// Map columns (1..=256).
    pub cols: usize,
    /// The robot's starting cell `(x, y)`.
    pub start: (u8, u8),
    /// The robot's starting heading.
    pub heading: Heading,
    /// Which Carto is on the other end.
    pub compat: Compat,
    /// How long one move may take before [`CuteEvent::MoveTimeout`] (per command in a batch).
    pub move_timeout: Duration,
    /// Largest incoming `Size` accepted.
    pub max_frame: usize,
}

impl Default for CuteConfig {
    fn default() -> Self {
        CuteConfig {
            rows: 20,
            cols: 20,
            start: (0, 0),
            heading: Heading::East,
            compat: Compat::Default,
            move_timeout: Duration::from_secs(5),
            max_frame: link::DEFAULT_MAX_FRAME,
        }
    }
}

/// Why a session action was refused.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum CuteError {
    /// The map size is invalid.
    #[error("bad map: {0}")]
    Map(#[from] MapError),
    /// The start cell is outside the map.
    #[error("bad start: {0}")]
    Start(#[from] CartoError),
    /// The action is not possible with the original Carto.
    #[error("{what} is not supported with --compat explobot-2024")]
    Unsupported {
        /// The refused action.
        what: &'static str,
    },
    /// Another mission is running; stop it first.
    #[error("busy: {status:?}")]
    Busy {
        /// The current status.
        status: Status,
    },
    /// A compatibility mode name that does not exist.
    #[error("unknown compat mode {name:?} (expected explobot-2024)")]
    UnknownCompat {
        /// The name given.
        name: String,
    },
}

/// What the session is doing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// No mission.
    Idle,
    /// Cartography running.
    Mapping,
    /// A trajectory running.
    Moving,
    /// Cartography finished (idle, with a complete map).
    Done,
}

/// What a timeout was waiting for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Waiting {
    /// ROBOT_POSITION_RECEIVED after SEND_ROBOT_POSITION.
    PositionAck,
    /// MOVE_DONE after a move or a batch.
    MoveDone,
}

/// Something the GUI or a scenario report should hear about.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CuteEvent {
    /// The connection is up.
    Connected,
    /// The connection dropped; the mission is kept.
    ConnectionLost,
    /// Carto acknowledged the position.
    PositionAcknowledged,
    /// A trajectory met an obstacle at `(x, y)` and was aborted.
    ObstacleMet {
        /// Row.
        x: u8,
        /// Column.
        y: u8,
    },
    /// No path to the clicked destination.
    NoPath {
        /// Row.
        x: u8,
        /// Column.
        y: u8,
    },
    /// The robot reached the destination `(x, y)`.
    Reached {
        /// Row.
        x: u8,
        /// Column.
        y: u8,
    },
    /// Compat mode: a trajectory of `commands` commands was sent (no feedback expected).
    TrajectorySent {
        /// Commands sent.
        commands: usize,
    },
    /// Cartography finished.
    MappingDone {
        /// Known free cells.
        free: usize,
        /// Known obstacles.
        obstacles: usize,
        /// Cells concluded unreachable.
        unreachable: usize,
        /// Cartography commands sent.
        moves: u64,
    },
    /// An answer did not come in time.
    MoveTimeout {
        /// What was awaited.
        waiting_for: Waiting,
    },
    /// Carto answered a cartography move with a bare MOVE_DONE [`MAX_REJECTED`] times; mapping
    /// stopped.
    MoveRejected {
        /// The refused command.
        command: Move,
    },
    /// The user pressed STOP.
    Stopped,
    /// A frame could not be decoded; `fatal` means the connection is dropped.
    ProtocolError {
        /// The decoder's message.
        message: String,
        /// True if the stream cannot be re-framed.
        fatal: bool,
    },
}

/// Traffic and mission counters, for reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Counters {
    /// Move commands sent (cartography moves plus trajectory frames).
    pub moves_sent: u64,
    /// Frames sent.
    pub frames_out: u64,
    /// Frames received (decoded, unknown ids included).
    pub frames_in: u64,
    /// Bytes sent.
    pub bytes_out: u64,
    /// Bytes received.
    pub bytes_in: u64,
    /// Decode errors.
    pub decode_errors: u64,
    /// Frames with an unknown id, or a client-to-server id.
    pub unknown_frames: u64,
    /// Answers that matched no request (ROBOT_POSITION_RECEIVED, MOVE_DONE, positions).
    pub unsolicited: u64,
    /// SET_OBSTACLE_POSITION frames received.
    pub obstacles: u64,
    /// Successful connections after the first.
    pub reconnects: u64,
    /// Timeouts reported.
    pub timeouts: u64,
}

/// A cell and a heading.
type Pose = ((u8, u8), Heading);

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum LinkState {
    Down { retry_at: Instant, backoff: Duration, ever_connected: bool },
    Up { ack_deadline: Option<Instant> },
}

#[derive(Debug, Clone)]
struct CartoFlight {
    command: Move,
    deadline: Instant,
    result: Option<MoveResult>,
}

#[derive(Debug, Clone)]
struct BatchFlight {
    /// `(cell, heading)` after each FORWARD of the batch, in order.
    steps: Vec<((u8, u8), Heading)>,
    /// The heading after the whole batch.
    end_heading: Heading,
    /// SET_ROBOT_POSITION frames received for this batch.
    seen: usize,
    deadline: Instant,
}

#[derive(Debug, Clone)]
enum Mission {
    None,
    Mapping { carto: Box<Cartographer>, flight: Option<CartoFlight>, rejected: u32 },
    Moving { dest: (u8, u8), batches: VecDeque<Vec<Move>>, flight: Option<BatchFlight>, replan: bool },
}

/// The Cute side of the link: map, robot, missions and the protocol state machine.
#[derive(Debug, Clone)]
pub struct Cute {
    config: CuteConfig,
    map: Map,
    robot: (u8, u8),
    heading: Heading,
    status: Status,
    mission: Mission,
    link: LinkState,
    decoder: Decoder,
    outgoing: Vec<u8>,
    events: Vec<CuteEvent>,
    counters: Counters,
    planner: Planner,
    now: Instant,
    close_requested: bool,
    last_carto_stats: Option<crate::cartography::CartoStats>,
}

impl Cute {
    /// A session with an all-unknown map and the robot at `config.start`, not connected.
    pub fn new(config: CuteConfig) -> Result<Cute, CuteError> {
        let mut map = Map::new(config.rows, config.cols)?;
        // Validates the start cell the same way cartography will.
        Cartographer::new(config.rows, config.cols, config.start, config.heading)?;
        map.set_robot(usize::from(config.start.0), usize::from(config.start.1))?;
        Ok(Cute {
            robot: config.start,
            heading: config.heading,
            decoder: Decoder::new(config.max_frame),
            config,
            map,
            status: Status::Idle,
            mission: Mission::None,
            link: LinkState::Down { retry_at: Instant::ZERO, backoff: RECONNECT_MIN, ever_connected: false },
            outgoing: Vec::new(),
            events: Vec::new(),
            counters: Counters::default(),
            planner: Planner::new(),
            now: Instant::ZERO,
            close_requested: false,
            last_carto_stats: None,
        })
    }

    // ----- views -----------------------------------------------------------------------------

    /// The map.
    pub fn map(&self) -> &Map {
        &self.map
    }

    /// The robot's believed cell and heading: `(x, y, heading)`.
    pub fn robot(&self) -> (u8, u8, Heading) {
        (self.robot.0, self.robot.1, self.heading)
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
        matches!(self.link, LinkState::Up { .. })
    }

    /// True once the position is acknowledged (or in compat mode) and moves may be sent.
    pub fn is_ready(&self) -> bool {
        matches!(self.link, LinkState::Up { ack_deadline: None })
    }

    /// The counters.
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// The running cartographer, if mapping.
    pub fn cartographer(&self) -> Option<&Cartographer> {
        match &self.mission {
            Mission::Mapping { carto, .. } => Some(carto),
            _ => None,
        }
    }

    /// Counters of the last cartography run (running or finished).
    pub fn cartography_stats(&self) -> Option<crate::cartography::CartoStats> {
        self.cartographer().map(|c| c.stats()).or(self.last_carto_stats)
    }

    /// Takes the bytes to write to the socket.
    pub fn take_outgoing(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.outgoing)
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
        match self.link {
            LinkState::Down { retry_at, .. } => Some(retry_at),
            LinkState::Up { .. } => None,
        }
    }

    // ----- network -----------------------------------------------------------------------------

    /// The connection is up: send the position (unless compat) and resume the mission.
    pub fn on_connected(&mut self, now: Instant) {
        self.now = now;
        let was_connected = match self.link {
            LinkState::Down { ever_connected, .. } => ever_connected,
            LinkState::Up { .. } => return,
        };
        if was_connected {
            self.counters.reconnects += 1;
        }
        info!(reconnect = was_connected, "connected to Carto");
        self.decoder.reset();
        self.outgoing.clear();
        self.events.push(CuteEvent::Connected);
        if self.config.compat == Compat::Explobot2024 {
            self.link = LinkState::Up { ack_deadline: None };
        } else {
            self.link = LinkState::Up { ack_deadline: Some(now + self.config.move_timeout) };
            self.send_position();
        }
        self.pump();
    }

    /// A connection attempt failed: back off (doubling up to [`RECONNECT_MAX`]).
    pub fn on_connect_failed(&mut self, now: Instant) {
        self.now = now;
        if let LinkState::Down { retry_at, backoff, ever_connected } = &mut self.link {
            let next = if *retry_at == Instant::ZERO && !*ever_connected {
                RECONNECT_MIN
            } else {
                Duration::from_micros((backoff.total_micros() * 2).min(RECONNECT_MAX.total_micros()))
            };
            *backoff = next;
            *retry_at = now + next;
        }
    }

    /// The connection dropped: keep the mission, schedule a reconnect.
    pub fn on_disconnected(&mut self, now: Instant) {
        self.now = now;
        if !self.is_connected() {
            return;
        }
        warn!("connection to Carto lost");
        self.link =
            LinkState::Down { retry_at: now + RECONNECT_MIN, backoff: RECONNECT_MIN, ever_connected: true };
        self.decoder.reset();
        self.outgoing.clear();
        self.events.push(CuteEvent::ConnectionLost);
        match &mut self.mission {
            Mission::Mapping { carto, flight, .. } => {
                // A result already reported did happen; otherwise the move is re-sent later.
                if let Some(f) = flight.take()
                    && let Some(result) = f.result
                {
                    apply_carto_result(
                        carto,
                        &mut self.map,
                        f.command,
                        result,
                        &mut self.robot,
                        &mut self.heading,
                    );
                }
            }
            Mission::Moving { flight, batches, replan, .. } => {
                if flight.take().is_some() || !batches.is_empty() {
                    batches.clear();
                    *replan = true;
                }
            }
            Mission::None => {}
        }
    }

    /// Bytes from Carto, in any chunking.
    pub fn on_bytes(&mut self, now: Instant, bytes: &[u8]) {
        self.now = now;
        if !self.is_connected() {
            return;
        }
        self.counters.bytes_in += bytes.len() as u64;
        for item in self.decoder.feed(bytes) {
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
        if let LinkState::Up { ack_deadline: Some(deadline) } = self.link
            && now >= deadline
        {
            self.counters.timeouts += 1;
            self.events.push(CuteEvent::MoveTimeout { waiting_for: Waiting::PositionAck });
            self.link = LinkState::Up { ack_deadline: Some(now + self.config.move_timeout) };
            self.send_position();
        }
        let expired = match &self.mission {
            Mission::Mapping { flight: Some(f), .. } => now >= f.deadline,
            Mission::Moving { flight: Some(f), .. } => now >= f.deadline,
            _ => false,
        };
        if expired {
            warn!("no MOVE_DONE in time; stopping the robot");
            self.counters.timeouts += 1;
            self.events.push(CuteEvent::MoveTimeout { waiting_for: Waiting::MoveDone });
            self.send(&GuiMessage::StopRobot);
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
        if matches!(self.status, Status::Mapping | Status::Moving) {
            return Err(CuteError::Busy { status: self.status });
        }
        let carto = Cartographer::new(self.config.rows, self.config.cols, self.robot, self.heading)?;
        self.map.clear_trajectory();
        self.mission = Mission::Mapping { carto: Box::new(carto), flight: None, rejected: 0 };
        self.status = Status::Mapping;
        self.pump();
        Ok(())
    }

    /// Plans to `(x, y)` over known free cells and starts driving there.
    pub fn go_to(&mut self, x: u8, y: u8) -> Result<(), PlanError> {
        if matches!(self.status, Status::Mapping | Status::Moving) {
            return Err(PlanError::Busy);
        }
        let t = match self.planner.plan_on_map(&mut self.map, self.robot, self.heading, (x, y)) {
            Ok(t) => t,
            Err(e) => {
                if matches!(e, PlanError::NoPath { .. }) {
                    self.events.push(CuteEvent::NoPath { x, y });
                }
                return Err(e);
            }
        };
        if t.commands.is_empty() {
            self.events.push(CuteEvent::Reached { x, y });
            return Ok(());
        }
        let max = if self.config.compat == Compat::Explobot2024 { MAX_BATCH_COMPAT } else { MAX_BATCH };
        let batches = t.commands.chunks(max).map(<[Move]>::to_vec).collect();
        self.mission = Mission::Moving { dest: (x, y), batches, flight: None, replan: false };
        self.status = Status::Moving;
        self.pump();
        Ok(())
    }

    /// STOP: stops the robot now and drops the mission.
    pub fn stop(&mut self) {
        if self.is_connected() {
            self.send(&GuiMessage::StopRobot);
        }
        self.map.clear_trajectory();
        self.end_mission(Status::Idle);
        self.events.push(CuteEvent::Stopped);
    }

    /// RESET: every cell back to unknown (the robot stays where it is). A running cartography
    /// restarts from scratch after the move in flight.
    pub fn reset_map(&mut self) {
        self.map.reset();
        let _ = self.map.set_robot(usize::from(self.robot.0), usize::from(self.robot.1));
        if let Mission::Mapping { carto, .. } = &mut self.mission {
            // A move still in flight is applied to the pose when it is answered, then a fresh
            // cartographer starts from there (see `apply_carto_result`).
            if let Ok(fresh) = Cartographer::new(self.config.rows, self.config.cols, self.robot, self.heading)
            {
                **carto = fresh;
            }
        }
    }

    // ----- internals ---------------------------------------------------------------------------

    fn order(&self) -> MsgOrder {
        match self.config.compat {
            Compat::Default => MsgOrder::BigEndian,
            Compat::Explobot2024 => MsgOrder::LittleEndian,
        }
    }

    fn send(&mut self, msg: &GuiMessage) {
        let bytes = msg.to_bytes(self.order());
        self.counters.frames_out += 1;
        self.counters.bytes_out += bytes.len() as u64;
        self.outgoing.extend_from_slice(&bytes);
    }

    fn send_position(&mut self) {
        let msg = GuiMessage::SendRobotPosition {
            x: self.robot.0,
            y: self.robot.1,
            direction: self.heading.into(),
        };
        self.send(&msg);
    }

    fn end_mission(&mut self, status: Status) {
        if let Mission::Mapping { carto, .. } = &self.mission {
            self.last_carto_stats = Some(carto.stats());
        }
        self.mission = Mission::None;
        self.status = status;
    }

    /// Sends the next move or batch when the link is ready and nothing is in flight.
    fn pump(&mut self) {
        if !self.is_ready() {
            return;
        }
        let now = self.now;
        let timeout = self.config.move_timeout;
        match &mut self.mission {
            Mission::None => {}
            Mission::Mapping { carto, flight, .. } => {
                if flight.is_some() {
                    return;
                }
                match carto.next_command(&self.map) {
                    Some(command) => {
                        *flight = Some(CartoFlight { command, deadline: now + timeout, result: None });
                        self.counters.moves_sent += 1;
                        let msg = GuiMessage::SendMoveCartography { command: command.into() };
                        self.send(&msg);
                    }
                    None => {
                        let stats = carto.stats();
                        let free = self.map.cells().iter().filter(|v| v.is_known_free()).count();
                        let obstacles = self.map.count(CellValue::Obstacle);
                        info!(free, obstacles, moves = stats.commands, "cartography done");
                        self.events.push(CuteEvent::MappingDone {
                            free,
                            obstacles,
                            unreachable: stats.unreachable,
                            moves: stats.commands,
                        });
                        self.end_mission(Status::Done);
                    }
                }
            }
            Mission::Moving { dest, batches, flight, replan } => {
                if flight.is_some() {
                    return;
                }
                let dest = *dest;
                if *replan {
                    *replan = false;
                    match self.planner.plan_on_map(&mut self.map, self.robot, self.heading, dest) {
                        Ok(t) if t.commands.is_empty() => {}
                        Ok(t) => {
                            let max = if self.config.compat == Compat::Explobot2024 {
                                MAX_BATCH_COMPAT
                            } else {
                                MAX_BATCH
                            };
                            *batches = t.commands.chunks(max).map(<[Move]>::to_vec).collect();
                        }
                        Err(e) => {
                            warn!(error = %e, "cannot resume the trajectory");
                            self.events.push(CuteEvent::NoPath { x: dest.0, y: dest.1 });
                            self.map.clear_trajectory();
                            self.end_mission(Status::Idle);
                            return;
                        }
                    }
                }
                let Mission::Moving { batches, .. } = &mut self.mission else {
                    return;
                };
                if self.config.compat == Compat::Explobot2024 {
                    // Fire and forget: the original Carto never answers a trajectory.
                    let all: Vec<Vec<Move>> = batches.drain(..).collect();
                    let n: usize = all.iter().map(Vec::len).sum();
                    for batch in &all {
                        self.send_batch(batch);
                    }
                    let mut pose = (self.robot, self.heading);
                    for batch in &all {
                        pose = simulate(pose, batch, self.map.rows(), self.map.cols()).1;
                    }
                    self.set_robot(pose.0);
                    self.heading = pose.1;
                    self.events.push(CuteEvent::TrajectorySent { commands: n });
                    self.end_mission(Status::Idle);
                    return;
                }
                match batches.pop_front() {
                    Some(batch) => {
                        let (steps, end) =
                            simulate((self.robot, self.heading), &batch, self.map.rows(), self.map.cols());
                        let deadline = now
                            + Duration::from_micros(
                                timeout.total_micros().saturating_mul(batch.len() as u64),
                            );
                        if let Mission::Moving { flight, .. } = &mut self.mission {
                            *flight = Some(BatchFlight { steps, end_heading: end.1, seen: 0, deadline });
                        }
                        self.send_batch(&batch);
                    }
                    None => {
                        self.map.clear_trajectory();
                        self.events.push(CuteEvent::Reached { x: self.robot.0, y: self.robot.1 });
                        self.end_mission(Status::Idle);
                    }
                }
            }
        }
    }

    fn send_batch(&mut self, batch: &[Move]) {
        // Batches are at most 255 long (chunks of MAX_BATCH or less).
        let n_total = batch.len().min(MAX_BATCH) as u8;
        for &c in batch {
            self.counters.moves_sent += 1;
            self.send(&GuiMessage::SendMovesTrajectory { n_total, command: c.into() });
        }
    }

    fn set_robot(&mut self, cell: (u8, u8)) {
        if self.map.set_robot(usize::from(cell.0), usize::from(cell.1)).is_ok() {
            self.robot = cell;
        }
    }

    fn handle(&mut self, msg: GuiMessage) {
        debug!(?msg, "from Carto");
        match msg {
            GuiMessage::RobotPositionReceived => match self.link {
                LinkState::Up { ack_deadline: Some(_) } => {
                    self.link = LinkState::Up { ack_deadline: None };
                    self.events.push(CuteEvent::PositionAcknowledged);
                }
                _ => self.counters.unsolicited += 1,
            },
            GuiMessage::SetRobotPosition { x, y } => {
                if !self.map.contains(usize::from(x), usize::from(y)) {
                    warn!(x, y, "robot position outside the map; ignored");
                    return;
                }
                match &mut self.mission {
                    Mission::Mapping { flight: Some(f), .. } => {
                        f.result = Some(MoveResult::Moved { x, y });
                    }
                    Mission::Moving { flight: Some(b), .. } => {
                        if let Some(&(_, h)) = b.steps.get(b.seen) {
                            self.heading = h;
                        }
                        b.seen += 1;
                        self.set_robot((x, y));
                    }
                    _ => {
                        self.counters.unsolicited += 1;
                        self.set_robot((x, y));
                    }
                }
            }
            GuiMessage::SetObstaclePosition { x, y } => {
                self.counters.obstacles += 1;
                match &mut self.mission {
                    Mission::Mapping { flight: Some(f), .. } => {
                        f.result = Some(MoveResult::Blocked { x, y });
                    }
                    Mission::Moving { .. } => {
                        if let Some(h) = Heading::between(self.robot, (x, y)) {
                            self.heading = h;
                        }
                        self.map.clear_trajectory();
                        self.mark_obstacle(x, y);
                        self.events.push(CuteEvent::ObstacleMet { x, y });
                        self.end_mission(Status::Idle);
                    }
                    _ => {
                        self.counters.unsolicited += 1;
                        self.mark_obstacle(x, y);
                    }
                }
            }
            GuiMessage::MoveDone => self.on_move_done(),
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

    fn mark_obstacle(&mut self, x: u8, y: u8) {
        if (x, y) != self.robot {
            let _ = self.map.set_obstacle(usize::from(x), usize::from(y));
        }
    }

    fn on_move_done(&mut self) {
        match &mut self.mission {
            Mission::Mapping { carto, flight, rejected } => {
                let Some(f) = flight.take() else {
                    self.counters.unsolicited += 1;
                    return;
                };
                let result = f.result.unwrap_or(if f.command.is_turn() {
                    MoveResult::Turned
                } else {
                    MoveResult::NotExecuted
                });
                if result == MoveResult::NotExecuted {
                    *rejected += 1;
                    if *rejected >= MAX_REJECTED {
                        warn!(command = %f.command, "Carto keeps refusing the move; mapping stopped");
                        self.events.push(CuteEvent::MoveRejected { command: f.command });
                        carto.cancel_pending();
                        self.end_mission(Status::Idle);
                        return;
                    }
                } else {
                    *rejected = 0;
                }
                apply_carto_result(
                    carto,
                    &mut self.map,
                    f.command,
                    result,
                    &mut self.robot,
                    &mut self.heading,
                );
            }
            Mission::Moving { flight, .. } => {
                let Some(b) = flight.take() else {
                    self.counters.unsolicited += 1;
                    return;
                };
                // MOVE_DONE ends the batch: the robot is at its last cell (also when Carto sent
                // no positions, like the original).
                if let Some(&(cell, _)) = b.steps.last() {
                    self.set_robot(cell);
                }
                self.heading = b.end_heading;
            }
            Mission::None => self.counters.unsolicited += 1,
        }
    }
}

/// Feeds a cartography result to the cartographer and mirrors the pose.
fn apply_carto_result(
    carto: &mut Cartographer,
    map: &mut Map,
    command: Move,
    result: MoveResult,
    robot: &mut (u8, u8),
    heading: &mut Heading,
) {
    if carto.pending() == Some(command) {
        carto.on_result(map, result);
        *robot = carto.pose();
        *heading = carto.heading();
        return;
    }
    // The cartographer was replaced (map reset) while the move was in flight.
    match result {
        MoveResult::Moved { x, y } => {
            if map.set_robot(usize::from(x), usize::from(y)).is_ok() {
                *robot = (x, y);
            }
        }
        MoveResult::Turned => *heading = heading.after(command),
        MoveResult::Blocked { x, y } => {
            if (x, y) != *robot {
                let _ = map.set_obstacle(usize::from(x), usize::from(y));
            }
        }
        MoveResult::NotExecuted => {}
    }
    carto.cancel_pending();
    *carto = match Cartographer::new(map.rows(), map.cols(), *robot, *heading) {
        Ok(c) => c,
        Err(_) => return,
    };
}

/// The `(cell, heading)` after each FORWARD of `commands`, and the final pose.
fn simulate(start: Pose, commands: &[Move], rows: usize, cols: usize) -> (Vec<Pose>, Pose) {
    let (mut cell, mut h) = start;
    let mut steps = Vec::new();
    for &c in commands {
        if c == Move::Forward {
            cell = h.step(cell, rows, cols).unwrap_or(cell);
            steps.push((cell, h));
        } else {
            h = h.after(c);
        }
    }
    (steps, (cell, h))
}
