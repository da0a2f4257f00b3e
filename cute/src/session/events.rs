//! What a session reports: its [`Status`], the [`CuteEvent`]s the GUI turns into pop-ups and a
//! scenario report counts, and the traffic and mission [`Counters`].
//!
//! Concept: events are queued by the session as they happen and drained by the caller with
//! [`Cute::take_events`](super::Cute::take_events); counters only grow.
//!
//! Invariants: each event is delivered once, in the order it happened; [`Status::Done`] is only
//! reached by a finished cartography.
//!
//! ```
//! use cute::session::{Cute, CuteConfig, CuteEvent, Status};
//! use robot_model::time::Instant;
//! let mut cute = Cute::new(CuteConfig::default()).unwrap();
//! cute.on_connected(Instant::ZERO);
//! cute.stop();
//! assert_eq!(cute.take_events(), [CuteEvent::Connected, CuteEvent::Stopped]);
//! assert!(cute.take_events().is_empty());
//! assert_eq!(cute.status(), Status::Idle);
//! assert_eq!(cute.counters().frames_out, 2); // SEND_ROBOT_POSITION, STOP_ROBOT
//! ```

use robot_model::grid::{Heading, Move};

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
    /// Compat mode: the path to `(x, y)` crosses `cells` unknown cells, planned as if free (the
    /// original Carto neither maps nor checks for obstacles during a trajectory).
    PlannedThroughUnknown {
        /// Destination row.
        x: u8,
        /// Destination column.
        y: u8,
        /// Unknown cells on the path (the destination included).
        cells: usize,
    },
    /// Compat mode: a STOP went out earlier, so the original Carto drops this batch of
    /// `commands` commands; the robot is believed to stay at `(x, y)` (see
    /// [`super::quirks`]).
    BatchDropped {
        /// Commands in the dropped batch.
        commands: usize,
        /// Row where the robot stays.
        x: u8,
        /// Column where the robot stays.
        y: u8,
    },
    /// SEND_ROBOT_POSITION went unanswered [`HINT_AFTER`](super::HINT_AFTER) times in a row:
    /// the peer may be the 2024 Carto ([`COMPAT_HINT`](super::COMPAT_HINT)).
    CompatHint,
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
    /// Carto answered a cartography move with a bare MOVE_DONE [`MAX_REJECTED`](super::MAX_REJECTED) times; mapping
    /// stopped.
    MoveRejected {
        /// The refused command.
        command: Move,
    },
    /// A FORWARD's reply showed the robot facing `faced`, not the heading Cute believed: Carto
    /// did not make a turn it was sent (it refuses a turn whose swept body would touch something
    /// it has seen; the link protocol cannot say so). Cute now follows the robot's heading.
    TurnNotMade {
        /// The heading the reply shows.
        faced: Heading,
    },
    /// Carto did not drive into `(x, y)`: the robot's way there is not clear of its width,
    /// though nothing was met in the cell itself. The move is blocked; the cell keeps what the
    /// map held (unknown stays unknown), so cartography may reach it another way.
    WayNotClear {
        /// Row.
        x: u8,
        /// Column.
        y: u8,
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
    /// `MOVE_DONE` frames received (the end of each move, solicited or not).
    pub moves_done: u64,
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
