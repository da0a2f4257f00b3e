//! `link`: the Cute ⇄ Carto protocol over TCP (seed 001, Carto listens on port 12345).
//!
//! A frame is a length prefix, a message id and single-byte data items. There is no sync byte and
//! no checksum: TCP delivers the bytes in order, so a receiver that counts correctly never loses
//! the framing.
//!
//! ```text
//! ┌────────┬────────────┬──────┬──────────────────────────────────────────────┬──────────────┐
//! │ offset │ bytes      │ field│ meaning                                      │ unit         │
//! ├────────┼────────────┼──────┼──────────────────────────────────────────────┼──────────────┤
//! │ 0      │ 2          │ Size │ bytes that follow (Msg + Data), 2..=max_frame │ u16 BE       │
//! │ 2      │ 2          │ Msg  │ message id 0x0N00, N in 1..=8                │ u16 BE or LE │
//! │ 4      │ Size − 2   │ Data │ message items, one byte each                 │ u8           │
//! └────────┴────────────┴──────┴──────────────────────────────────────────────┴──────────────┘
//! ```
//!
//! | id     | [`GuiMessage`]            | Data                       | Size |
//! |--------|---------------------------|----------------------------|------|
//! | 0x0100 | `SendMovesTrajectory`     | `n_total`, `command`       | 4    |
//! | 0x0200 | `SendMoveCartography`     | `command`                  | 3    |
//! | 0x0300 | `MoveDone`                | —                          | 2    |
//! | 0x0400 | `SetObstaclePosition`     | `x` (row), `y` (column)    | 4    |
//! | 0x0500 | `SetRobotPosition`        | `x` (row), `y` (column)    | 4    |
//! | 0x0600 | `StopRobot`               | —                          | 2    |
//! | 0x0700 | `SendRobotPosition`       | `x`, `y`, `direction`      | 5    |
//! | 0x0800 | `RobotPositionReceived`   | —                          | 2    |
//!
//! **Byte order of `Msg`.** Big-endian is the default ([`MsgOrder::BigEndian`]); the original
//! 2024 Cute sends it little-endian. Every valid id is `0x0N00`, so the order is detected per
//! frame without ambiguity: `0N 00` is big-endian, `00 0N` little-endian. Any other pair is
//! [`MsgType::Unknown`] holding the two bytes read big-endian.
//!
//! **Contract** (as smoltcp's wire modules): [`Frame::check_len`] proves that every getter is in
//! bounds; [`GuiMessage::parse`] never panics (it calls `check_len` itself) and returns a typed
//! [`DecodeError`]; [`GuiMessage::emit`] never panics when the buffer is at least
//! [`GuiMessage::buffer_len`] bytes long, and writes exactly that many bytes.
//!
//! **Streaming.** [`Decoder`] is sans-IO: push whatever the socket returned into
//! [`Decoder::feed`], get back every message completed by those bytes. Its buffer holds at most
//! one partial frame (`max_frame + 2` bytes). A `Size` below 2 or above `max_frame` is fatal
//! ([`DecodeError::is_fatal`]): with no sync byte the stream cannot be re-framed, so the caller
//! closes the connection, and the decoder ignores further bytes until [`Decoder::reset`]. A known
//! message with the wrong data length (Cute 2024's `SendMoveCartography` with Size 2) is reported
//! and skipped; the framing is intact, so decoding continues.
//!
//! **What recovery is possible.** None inside one stream: the decoder trusts every `Size` it reads.
//! Bytes that are not a whole number of frames (`Size` in range) therefore shift the framing for
//! good; the first out-of-range `Size` is reported as fatal. A valid frame is decoded whenever it
//! starts where the decoder expects a frame, that is, when [`Decoder::buffered`] is 0 and the
//! decoder has not failed.
//!
//! ```
//! use protocol::link::{Command, Decoder, GuiMessage, MsgOrder};
//!
//! let msg = GuiMessage::SendMovesTrajectory { n_total: 3, command: Command::Right };
//! let bytes = msg.to_bytes(MsgOrder::BigEndian);
//! assert_eq!(bytes, [0x00, 0x04, 0x01, 0x00, 0x03, 0x01]);
//!
//! let mut decoder = Decoder::default();
//! assert!(decoder.feed(&bytes[..3]).is_empty()); // a partial frame waits
//! assert_eq!(decoder.feed(&bytes[3..]), vec![Ok(msg)]);
//! assert_eq!(decoder.last_order(), Some(MsgOrder::BigEndian));
//! ```

/// Byte ranges of the link frame.
pub mod field {
    use crate::{Field, Rest};

    /// `Size`: u16 big-endian, the number of bytes after it (Msg + Data).
    pub const SIZE: Field = 0..2;
    /// `Msg`: the message id, u16 in either byte order.
    pub const MSG: Field = 2..4;
    /// `Data`: from here to the end of the frame.
    pub const DATA: Rest = 4..;
    /// Bytes before `Data`.
    pub const HEADER_LEN: usize = 4;

    /// The `Data` range of a frame whose `Size` field is `size` (empty when `size < 2`).
    pub const fn data(size: u16) -> Field {
        let end = size as usize + 2;
        if end < HEADER_LEN { HEADER_LEN..HEADER_LEN } else { HEADER_LEN..end }
    }
}

/// Smallest valid `Size` field: the `Msg` id alone.
pub const MIN_SIZE: u16 = 2;
/// Default largest `Size` a receiver accepts.
pub const DEFAULT_MAX_FRAME: usize = 1024;
/// Largest `Data` length a frame can carry (`Size` is a u16 that includes the 2-byte `Msg`).
pub const MAX_DATA_LEN: usize = u16::MAX as usize - 2;

enum_with_unknown! {
    /// A message id, as its big-endian numeric value (`0x0100` … `0x0800`).
    pub enum MsgType(u16) {
        /// 0x0100, Cute → Carto: one command of a trajectory batch.
        SendMovesTrajectory = 0x0100,
        /// 0x0200, Cute → Carto: one cartography move.
        SendMoveCartography = 0x0200,
        /// 0x0300, Carto → Cute: the move is finished.
        MoveDone = 0x0300,
        /// 0x0400, Carto → Cute: the cell ahead is blocked.
        SetObstaclePosition = 0x0400,
        /// 0x0500, Carto → Cute: the robot's new cell.
        SetRobotPosition = 0x0500,
        /// 0x0600, Cute → Carto: stop now, drop pending commands.
        StopRobot = 0x0600,
        /// 0x0700, Cute → Carto: the robot's cell and heading.
        SendRobotPosition = 0x0700,
        /// 0x0800, Carto → Cute: position stored.
        RobotPositionReceived = 0x0800,
    }
}

impl MsgType {
    /// Decodes the two `Msg` bytes in wire order, detecting their byte order.
    ///
    /// Returns the order only for a known id; anything else is `Unknown(big-endian value)`.
    pub fn from_wire(bytes: [u8; 2]) -> (MsgType, Option<MsgOrder>) {
        let known = 1..=8u8;
        match bytes {
            [n, 0] if known.contains(&n) => (MsgType::from(u16::from(n) << 8), Some(MsgOrder::BigEndian)),
            [0, n] if known.contains(&n) => (MsgType::from(u16::from(n) << 8), Some(MsgOrder::LittleEndian)),
            _ => (MsgType::Unknown(u16::from_be_bytes(bytes)), None),
        }
    }

    /// The two `Msg` bytes in wire order; `Unknown(raw)` is always written big-endian.
    pub fn to_wire(self, order: MsgOrder) -> [u8; 2] {
        let raw = u16::from(self);
        match (self, order) {
            (MsgType::Unknown(_), _) | (_, MsgOrder::BigEndian) => raw.to_be_bytes(),
            (_, MsgOrder::LittleEndian) => raw.to_le_bytes(),
        }
    }

    /// Number of `Data` bytes this message carries, `None` for an unknown id.
    pub fn data_len(self) -> Option<usize> {
        match self {
            MsgType::SendMovesTrajectory => Some(2),
            MsgType::SendMoveCartography => Some(1),
            MsgType::MoveDone => Some(0),
            MsgType::SetObstaclePosition => Some(2),
            MsgType::SetRobotPosition => Some(2),
            MsgType::StopRobot => Some(0),
            MsgType::SendRobotPosition => Some(3),
            MsgType::RobotPositionReceived => Some(0),
            MsgType::Unknown(_) => None,
        }
    }
}

enum_with_unknown! {
    /// A move command (one byte on the wire).
    pub enum Command(u8) {
        /// 0: advance one cell.
        Forward = 0,
        /// 1: turn 90° clockwise on the spot.
        Right = 1,
        /// 2: turn 90° counter-clockwise on the spot.
        Left = 2,
        /// 3: stop the motors.
        Stop = 3,
    }
}

enum_with_unknown! {
    /// The robot's heading on the grid (one byte on the wire).
    pub enum Direction(u8) {
        /// 0: towards +x (row + 1, downward).
        South = 0,
        /// 1: towards −x (row − 1).
        North = 1,
        /// 2: towards −y (column − 1).
        West = 2,
        /// 3: towards +y (column + 1, rightward).
        East = 3,
    }
}

/// Byte order of the `Msg` field.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum MsgOrder {
    /// `01 00` for 0x0100: the documented form and our default.
    #[default]
    BigEndian,
    /// `00 01` for 0x0100: what the original 2024 Cute sends and its Carto expects.
    LittleEndian,
}

/// Errors from framing and parsing link frames.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum DecodeError {
    /// The buffer ends before the frame does.
    #[error("truncated frame: need {need} bytes, got {got}")]
    Truncated {
        /// Bytes the frame needs.
        need: usize,
        /// Bytes available.
        got: usize,
    },
    /// `Size` is below 2 (it must at least cover `Msg`). Fatal for a stream.
    #[error("size field {size} is below the minimum of 2")]
    SizeTooSmall {
        /// The `Size` field read.
        size: u16,
    },
    /// `Size` is above the receiver's maximum. Fatal for a stream.
    #[error("size field {size} exceeds the maximum of {max}")]
    SizeTooLarge {
        /// The `Size` field read.
        size: u16,
        /// The receiver's `max_frame`.
        max: usize,
    },
    /// A known message with the wrong number of data bytes. The frame is skipped.
    #[error("message {msg:?} needs {expected} data bytes, got {actual}")]
    BadLength {
        /// The message id.
        msg: MsgType,
        /// Data bytes this id carries.
        expected: usize,
        /// Data bytes the frame had.
        actual: usize,
    },
}

impl DecodeError {
    /// True when the stream cannot be re-framed: close the connection and [`Decoder::reset`].
    pub fn is_fatal(&self) -> bool {
        matches!(self, DecodeError::SizeTooSmall { .. } | DecodeError::SizeTooLarge { .. })
    }
}

/// A read/write view of one link frame over any byte buffer.
///
/// # Panics
/// Getters and setters index the buffer directly: they panic if it is shorter than the field
/// they touch. [`Frame::new_checked`] / [`Frame::check_len`] rule that out for getters, and a
/// buffer of [`GuiMessage::buffer_len`] bytes does for setters.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Frame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Frame<T> {
    /// Wraps a buffer without checking its length.
    pub const fn new_unchecked(buffer: T) -> Frame<T> {
        Frame { buffer }
    }

    /// Wraps a buffer after [`Frame::check_len`].
    pub fn new_checked(buffer: T) -> Result<Frame<T>, DecodeError> {
        let frame = Self::new_unchecked(buffer);
        frame.check_len()?;
        Ok(frame)
    }

    /// Checks that the header is present, `Size >= 2`, and the buffer holds the whole frame.
    ///
    /// Extra bytes after the frame are allowed and ignored. `max_frame` is the decoder's concern.
    pub fn check_len(&self) -> Result<(), DecodeError> {
        let got = self.buffer.as_ref().len();
        if got < field::HEADER_LEN {
            return Err(DecodeError::Truncated { need: field::HEADER_LEN, got });
        }
        let size = self.size();
        if size < MIN_SIZE {
            return Err(DecodeError::SizeTooSmall { size });
        }
        let need = self.frame_len();
        if got < need {
            return Err(DecodeError::Truncated { need, got });
        }
        Ok(())
    }

    /// Gives the buffer back.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// The `Size` field: bytes of Msg + Data.
    pub fn size(&self) -> u16 {
        let b = &self.buffer.as_ref()[field::SIZE];
        u16::from_be_bytes([b[0], b[1]])
    }

    /// Total frame length, `Size + 2`.
    pub fn frame_len(&self) -> usize {
        usize::from(self.size()) + 2
    }

    /// The two `Msg` bytes read big-endian, whatever the order on the wire.
    pub fn msg_raw(&self) -> u16 {
        u16::from_be_bytes(self.msg_bytes())
    }

    /// The `Msg` bytes in wire order.
    pub fn msg_bytes(&self) -> [u8; 2] {
        let b = &self.buffer.as_ref()[field::MSG];
        [b[0], b[1]]
    }

    /// The message id, with its byte order detected.
    pub fn msg_type(&self) -> MsgType {
        MsgType::from_wire(self.msg_bytes()).0
    }

    /// The detected byte order of `Msg`; `None` when the id is unknown.
    pub fn msg_order(&self) -> Option<MsgOrder> {
        MsgType::from_wire(self.msg_bytes()).1
    }

    /// The `Data` bytes (`Size − 2` of them).
    pub fn data(&self) -> &[u8] {
        &self.buffer.as_ref()[field::data(self.size())]
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Frame<T> {
    /// Writes the `Size` field.
    pub fn set_size(&mut self, size: u16) {
        self.buffer.as_mut()[field::SIZE].copy_from_slice(&size.to_be_bytes());
    }

    /// Writes the `Msg` field in the given order (`Unknown` ids are always big-endian).
    pub fn set_msg(&mut self, msg: MsgType, order: MsgOrder) {
        self.set_msg_bytes(msg.to_wire(order));
    }

    /// Writes the `Msg` bytes exactly as given, in wire order.
    pub fn set_msg_bytes(&mut self, bytes: [u8; 2]) {
        self.buffer.as_mut()[field::MSG].copy_from_slice(&bytes);
    }

    /// The `Data` bytes, mutable (the range follows the current `Size` field).
    pub fn data_mut(&mut self) -> &mut [u8] {
        let range = field::data(self.size());
        &mut self.buffer.as_mut()[range]
    }
}

impl<T: AsRef<[u8]>> AsRef<[u8]> for Frame<T> {
    fn as_ref(&self) -> &[u8] {
        self.buffer.as_ref()
    }
}

/// One link message: the typed representation of a frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum GuiMessage {
    /// One command of a trajectory batch of `n_total` commands.
    SendMovesTrajectory {
        /// Number of commands in the batch (every frame repeats it).
        n_total: u8,
        /// This frame's command.
        command: Command,
    },
    /// One cartography move.
    SendMoveCartography {
        /// The move.
        command: Command,
    },
    /// The last move is finished.
    MoveDone,
    /// The cell ahead is blocked.
    SetObstaclePosition {
        /// Row of the blocked cell.
        x: u8,
        /// Column of the blocked cell.
        y: u8,
    },
    /// The robot reached a new cell.
    SetRobotPosition {
        /// Row.
        x: u8,
        /// Column.
        y: u8,
    },
    /// Stop now and drop pending commands.
    StopRobot,
    /// The robot's cell and heading, from Cute.
    SendRobotPosition {
        /// Row.
        x: u8,
        /// Column.
        y: u8,
        /// Heading.
        direction: Direction,
    },
    /// Carto stored the position.
    RobotPositionReceived,
    /// An id this crate does not know, kept with its data.
    ///
    /// `msg` is the two wire bytes read big-endian and is emitted big-endian. An `Unknown` whose
    /// `msg` is a valid id in either order re-parses as that known message.
    Unknown {
        /// The raw `Msg` bytes, read big-endian.
        msg: u16,
        /// The data bytes (emit truncates to [`MAX_DATA_LEN`]).
        data: Vec<u8>,
    },
}

impl GuiMessage {
    /// The message id.
    pub fn msg_type(&self) -> MsgType {
        match self {
            GuiMessage::SendMovesTrajectory { .. } => MsgType::SendMovesTrajectory,
            GuiMessage::SendMoveCartography { .. } => MsgType::SendMoveCartography,
            GuiMessage::MoveDone => MsgType::MoveDone,
            GuiMessage::SetObstaclePosition { .. } => MsgType::SetObstaclePosition,
            GuiMessage::SetRobotPosition { .. } => MsgType::SetRobotPosition,
            GuiMessage::StopRobot => MsgType::StopRobot,
            GuiMessage::SendRobotPosition { .. } => MsgType::SendRobotPosition,
            GuiMessage::RobotPositionReceived => MsgType::RobotPositionReceived,
            GuiMessage::Unknown { msg, .. } => MsgType::from(*msg),
        }
    }

    /// Parses a frame. Never panics; checks the length itself.
    pub fn parse<T: AsRef<[u8]> + ?Sized>(frame: &Frame<&T>) -> Result<GuiMessage, DecodeError> {
        frame.check_len()?;
        let data = frame.data();
        let msg = frame.msg_type();
        let Some(expected) = msg.data_len() else {
            return Ok(GuiMessage::Unknown { msg: frame.msg_raw(), data: data.to_vec() });
        };
        if data.len() != expected {
            return Err(DecodeError::BadLength { msg, expected, actual: data.len() });
        }
        let at = |i: usize| data.get(i).copied().unwrap_or_default();
        Ok(match msg {
            MsgType::SendMovesTrajectory => {
                GuiMessage::SendMovesTrajectory { n_total: at(0), command: Command::from(at(1)) }
            }
            MsgType::SendMoveCartography => GuiMessage::SendMoveCartography { command: Command::from(at(0)) },
            MsgType::MoveDone => GuiMessage::MoveDone,
            MsgType::SetObstaclePosition => GuiMessage::SetObstaclePosition { x: at(0), y: at(1) },
            MsgType::SetRobotPosition => GuiMessage::SetRobotPosition { x: at(0), y: at(1) },
            MsgType::StopRobot => GuiMessage::StopRobot,
            MsgType::SendRobotPosition => {
                GuiMessage::SendRobotPosition { x: at(0), y: at(1), direction: Direction::from(at(2)) }
            }
            MsgType::RobotPositionReceived => GuiMessage::RobotPositionReceived,
            MsgType::Unknown(raw) => GuiMessage::Unknown { msg: raw, data: data.to_vec() },
        })
    }

    /// Number of `Data` bytes this message emits.
    pub fn data_len(&self) -> usize {
        match self {
            GuiMessage::Unknown { data, .. } => data.len().min(MAX_DATA_LEN),
            known => known.msg_type().data_len().unwrap_or_default(),
        }
    }

    /// Total frame length when emitted.
    pub fn buffer_len(&self) -> usize {
        field::HEADER_LEN + self.data_len()
    }

    /// Writes the frame into the first [`GuiMessage::buffer_len`] bytes of `frame`.
    ///
    /// Never panics when the buffer is at least `buffer_len()` bytes long.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]> + ?Sized>(&self, frame: &mut Frame<&mut T>, order: MsgOrder) {
        let data_len = self.data_len();
        // data_len <= MAX_DATA_LEN, so the sum fits a u16.
        frame.set_size(u16::try_from(data_len + 2).unwrap_or(u16::MAX));
        match self {
            GuiMessage::Unknown { msg, .. } => frame.set_msg_bytes(msg.to_be_bytes()),
            known => frame.set_msg(known.msg_type(), order),
        }
        let data = frame.data_mut();
        match self {
            GuiMessage::SendMovesTrajectory { n_total, command } => {
                data.copy_from_slice(&[*n_total, u8::from(*command)])
            }
            GuiMessage::SendMoveCartography { command } => data.copy_from_slice(&[u8::from(*command)]),
            GuiMessage::SetObstaclePosition { x, y } | GuiMessage::SetRobotPosition { x, y } => {
                data.copy_from_slice(&[*x, *y])
            }
            GuiMessage::SendRobotPosition { x, y, direction } => {
                data.copy_from_slice(&[*x, *y, u8::from(*direction)])
            }
            GuiMessage::Unknown { data: payload, .. } => data.copy_from_slice(&payload[..data_len]),
            GuiMessage::MoveDone | GuiMessage::StopRobot | GuiMessage::RobotPositionReceived => {}
        }
    }

    /// The whole frame as bytes, with `Msg` in the given order.
    pub fn to_bytes(&self, order: MsgOrder) -> Vec<u8> {
        let mut buffer = vec![0; self.buffer_len()];
        self.emit(&mut Frame::new_unchecked(&mut buffer[..]), order);
        buffer
    }
}

/// Counters kept by a [`Decoder`] since it was made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DecoderStats {
    /// Messages decoded (`Ok` items, `Unknown` included).
    pub frames: u64,
    /// Errors reported (`Err` items: bad data lengths and fatal sizes).
    pub errors: u64,
    /// `Unknown` messages among `frames`.
    pub unknown: u64,
    /// Bytes fed in total.
    pub bytes: u64,
    /// Bytes ignored from the fatal `Size` field on, until `reset`.
    pub discarded: u64,
}

/// Sans-IO streaming decoder for link frames.
///
/// Holds at most one partial frame (`max_frame + 2` bytes). See the module doc for what it can
/// and cannot recover from.
#[derive(Debug, Clone)]
pub struct Decoder {
    max_frame: usize,
    buffer: Vec<u8>,
    failed: bool,
    last_order: Option<MsgOrder>,
    stats: DecoderStats,
}

impl Default for Decoder {
    fn default() -> Self {
        Decoder::new(DEFAULT_MAX_FRAME)
    }
}

impl Decoder {
    /// A decoder accepting `Size` up to `max_frame` (raised to 2 if lower, capped at 65535).
    pub fn new(max_frame: usize) -> Self {
        let max_frame = max_frame.clamp(usize::from(MIN_SIZE), usize::from(u16::MAX));
        Decoder {
            max_frame,
            buffer: Vec::new(),
            failed: false,
            last_order: None,
            stats: DecoderStats::default(),
        }
    }

    /// The largest `Size` accepted.
    pub fn max_frame(&self) -> usize {
        self.max_frame
    }

    /// Consumes all of `bytes` and returns every message or error they complete, in order.
    ///
    /// After a fatal error the remaining bytes, and those of later calls, are ignored (counted in
    /// [`DecoderStats::discarded`]) until [`Decoder::reset`].
    pub fn feed(&mut self, bytes: &[u8]) -> Vec<Result<GuiMessage, DecodeError>> {
        let mut out = Vec::new();
        self.stats.bytes += bytes.len() as u64;
        let mut input = bytes;
        while !input.is_empty() {
            if self.failed {
                self.stats.discarded += input.len() as u64;
                break;
            }
            if self.buffer.is_empty() {
                // Fast path: decode straight from the caller's slice.
                match self.frame_len(input) {
                    Err(error) => self.fail(error, &mut out),
                    Ok(Some(total)) if input.len() >= total => {
                        self.decode(&input[..total], &mut out);
                        input = &input[total..];
                    }
                    Ok(_) => {
                        // A partial frame: at most max_frame + 1 bytes.
                        self.buffer.extend_from_slice(input);
                        input = &[];
                    }
                }
            } else {
                let need = match self.frame_len(&self.buffer) {
                    Ok(Some(total)) => total,
                    _ => 2,
                };
                let take = need.saturating_sub(self.buffer.len()).min(input.len());
                self.buffer.extend_from_slice(&input[..take]);
                input = &input[take..];
                match self.frame_len(&self.buffer) {
                    Err(error) => self.fail(error, &mut out),
                    Ok(Some(total)) if self.buffer.len() == total => {
                        let frame = core::mem::take(&mut self.buffer);
                        self.decode(&frame, &mut out);
                        self.buffer = frame;
                        self.buffer.clear();
                    }
                    Ok(_) => {}
                }
            }
        }
        out
    }

    /// Byte order of the last frame whose `Msg` was a known id.
    pub fn last_order(&self) -> Option<MsgOrder> {
        self.last_order
    }

    /// Counters since creation (not cleared by `reset`).
    pub fn stats(&self) -> DecoderStats {
        self.stats
    }

    /// Bytes of a partial frame held, waiting for the rest.
    pub fn buffered(&self) -> usize {
        self.buffer.len()
    }

    /// True after a fatal error, until [`Decoder::reset`].
    pub fn is_failed(&self) -> bool {
        self.failed
    }

    /// Drops any partial frame and the failed state, ready for a new connection.
    pub fn reset(&mut self) {
        self.buffer.clear();
        self.failed = false;
        self.last_order = None;
    }

    /// Total length of the frame starting `prefix`, once its `Size` is known.
    fn frame_len(&self, prefix: &[u8]) -> Result<Option<usize>, DecodeError> {
        let [a, b, ..] = *prefix else {
            return Ok(None);
        };
        let size = u16::from_be_bytes([a, b]);
        if size < MIN_SIZE {
            return Err(DecodeError::SizeTooSmall { size });
        }
        if usize::from(size) > self.max_frame {
            return Err(DecodeError::SizeTooLarge { size, max: self.max_frame });
        }
        Ok(Some(usize::from(size) + 2))
    }

    fn fail(&mut self, error: DecodeError, out: &mut Vec<Result<GuiMessage, DecodeError>>) {
        self.failed = true;
        self.stats.discarded += self.buffer.len() as u64;
        self.buffer.clear();
        self.stats.errors += 1;
        out.push(Err(error));
    }

    fn decode(&mut self, bytes: &[u8], out: &mut Vec<Result<GuiMessage, DecodeError>>) {
        let frame = Frame::new_unchecked(bytes);
        if let Some(order) = frame.msg_order() {
            self.last_order = Some(order);
        }
        let result = GuiMessage::parse(&frame);
        match &result {
            Ok(message) => {
                self.stats.frames += 1;
                if matches!(message, GuiMessage::Unknown { .. }) {
                    self.stats.unknown += 1;
                }
            }
            Err(_) => self.stats.errors += 1,
        }
        out.push(result);
    }
}

impl_decoder!(Decoder, GuiMessage, DecodeError, DecoderStats);

#[cfg(test)]
mod tests {
    use super::*;

    // ── Golden frames. Sources: protocols-research.md §1.6 and §1.7 (observed from the original
    // programs) and the seed's §2.4.1.4 examples (documented, big-endian Msg). No checksum exists.

    /// §1.7 observed, C→R: SEND_ROBOT_POSITION x=2 y=3 EAST, Msg little-endian.
    static OBSERVED_SEND_ROBOT_POSITION_LE: [u8; 7] = [0x00, 0x05, 0x00, 0x07, 0x02, 0x03, 0x03];
    /// §1.7 observed, R→C: ROBOT_POSITION_RECEIVED.
    static OBSERVED_ROBOT_POSITION_RECEIVED: [u8; 4] = [0x00, 0x02, 0x08, 0x00];
    /// §1.7 observed, C→R: SEND_MOVE_CARTOGRAPHY FORWARD, Msg little-endian.
    static OBSERVED_CARTOGRAPHY_FORWARD_LE: [u8; 5] = [0x00, 0x03, 0x00, 0x02, 0x00];
    /// §1.7 observed, C→R: SEND_MOVE_CARTOGRAPHY LEFT, Msg little-endian.
    static OBSERVED_CARTOGRAPHY_LEFT_LE: [u8; 5] = [0x00, 0x03, 0x00, 0x02, 0x02];
    /// §1.7 observed, R→C: SET_ROBOT_POSITION x=2 y=4.
    static OBSERVED_SET_ROBOT_POSITION: [u8; 6] = [0x00, 0x04, 0x05, 0x00, 0x02, 0x04];
    /// §1.7 observed, R→C: SET_OBSTACLE_POSITION x=2 y=4.
    static OBSERVED_SET_OBSTACLE_POSITION: [u8; 6] = [0x00, 0x04, 0x04, 0x00, 0x02, 0x04];
    /// §1.7 observed, R→C: MOVE_DONE.
    static OBSERVED_MOVE_DONE: [u8; 4] = [0x00, 0x02, 0x03, 0x00];
    /// §1.6 observed, C→R: SEND_MOVES_TRAJECTORY n=6 FORWARD, Msg little-endian.
    static OBSERVED_TRAJECTORY_LE: [u8; 6] = [0x00, 0x04, 0x00, 0x01, 0x06, 0x00];
    /// §1.6 observed, C→R: SEND_MOVES_TRAJECTORY n=6 RIGHT, Msg little-endian.
    static OBSERVED_TRAJECTORY_RIGHT_LE: [u8; 6] = [0x00, 0x04, 0x00, 0x01, 0x06, 0x01];
    /// §1.6 observed, C→R: STOP_ROBOT, Msg little-endian.
    static OBSERVED_STOP_LE: [u8; 4] = [0x00, 0x02, 0x00, 0x06];
    /// Seed §2.4.1.4.1: SEND_MOVES_TRAJECTORY n=3 LEFT.
    static DOC_TRAJECTORY: [u8; 6] = [0x00, 0x04, 0x01, 0x00, 0x03, 0x02];
    /// Seed §2.4.1.4.2: SEND_MOVE_CARTOGRAPHY FORWARD.
    static DOC_CARTOGRAPHY: [u8; 5] = [0x00, 0x03, 0x02, 0x00, 0x00];
    /// Seed §2.4.1.4.4: SET_OBSTACLE_POSITION x=9 y=21.
    static DOC_SET_OBSTACLE_POSITION: [u8; 6] = [0x00, 0x04, 0x04, 0x00, 0x09, 0x15];
    /// Seed §2.4.1.4.5: SET_ROBOT_POSITION x=33 y=2.
    static DOC_SET_ROBOT_POSITION: [u8; 6] = [0x00, 0x04, 0x05, 0x00, 0x21, 0x02];
    /// Seed §2.4.1.4.6: STOP_ROBOT.
    static DOC_STOP: [u8; 4] = [0x00, 0x02, 0x06, 0x00];
    /// Seed §2.4.1.4.7: SEND_ROBOT_POSITION x=23 y=20 SOUTH.
    static DOC_SEND_ROBOT_POSITION: [u8; 7] = [0x00, 0x05, 0x07, 0x00, 0x17, 0x14, 0x00];
    /// §1.3: Cute 2024's unused helper: SEND_MOVE_CARTOGRAPHY with Size 2 (command byte missing).
    static CUTE_2024_CARTOGRAPHY_SIZE_2: [u8; 4] = [0x00, 0x02, 0x02, 0x00];

    fn golden() -> Vec<(&'static [u8], GuiMessage, MsgOrder)> {
        use GuiMessage as M;
        use MsgOrder::{BigEndian as Be, LittleEndian as Le};
        vec![
            (
                &OBSERVED_SEND_ROBOT_POSITION_LE,
                M::SendRobotPosition { x: 2, y: 3, direction: Direction::East },
                Le,
            ),
            (&OBSERVED_ROBOT_POSITION_RECEIVED, M::RobotPositionReceived, Be),
            (&OBSERVED_CARTOGRAPHY_FORWARD_LE, M::SendMoveCartography { command: Command::Forward }, Le),
            (&OBSERVED_CARTOGRAPHY_LEFT_LE, M::SendMoveCartography { command: Command::Left }, Le),
            (&OBSERVED_SET_ROBOT_POSITION, M::SetRobotPosition { x: 2, y: 4 }, Be),
            (&OBSERVED_SET_OBSTACLE_POSITION, M::SetObstaclePosition { x: 2, y: 4 }, Be),
            (&OBSERVED_MOVE_DONE, M::MoveDone, Be),
            (&OBSERVED_TRAJECTORY_LE, M::SendMovesTrajectory { n_total: 6, command: Command::Forward }, Le),
            (
                &OBSERVED_TRAJECTORY_RIGHT_LE,
                M::SendMovesTrajectory { n_total: 6, command: Command::Right },
                Le,
            ),
            (&OBSERVED_STOP_LE, M::StopRobot, Le),
            (&DOC_TRAJECTORY, M::SendMovesTrajectory { n_total: 3, command: Command::Left }, Be),
            (&DOC_CARTOGRAPHY, M::SendMoveCartography { command: Command::Forward }, Be),
            (&DOC_SET_OBSTACLE_POSITION, M::SetObstaclePosition { x: 9, y: 21 }, Be),
            (&DOC_SET_ROBOT_POSITION, M::SetRobotPosition { x: 33, y: 2 }, Be),
            (&DOC_STOP, M::StopRobot, Be),
            (
                &DOC_SEND_ROBOT_POSITION,
                M::SendRobotPosition { x: 23, y: 20, direction: Direction::South },
                Be,
            ),
        ]
    }

    #[test]
    fn test_deconstruct() {
        let frame = Frame::new_checked(&OBSERVED_SEND_ROBOT_POSITION_LE[..]).unwrap();
        assert_eq!(frame.size(), 5);
        assert_eq!(frame.frame_len(), 7);
        assert_eq!(frame.msg_bytes(), [0x00, 0x07]);
        assert_eq!(frame.msg_raw(), 0x0007);
        assert_eq!(frame.msg_type(), MsgType::SendRobotPosition);
        assert_eq!(frame.msg_order(), Some(MsgOrder::LittleEndian));
        assert_eq!(frame.data(), &[0x02, 0x03, 0x03]);

        let frame = Frame::new_checked(&DOC_SET_OBSTACLE_POSITION[..]).unwrap();
        assert_eq!(frame.size(), 4);
        assert_eq!(frame.msg_raw(), 0x0400);
        assert_eq!(frame.msg_type(), MsgType::SetObstaclePosition);
        assert_eq!(frame.msg_order(), Some(MsgOrder::BigEndian));
        assert_eq!(frame.data(), &[0x09, 0x15]);
    }

    #[test]
    fn test_construct() {
        let mut bytes = vec![0xa5; 7];
        let mut frame = Frame::new_unchecked(&mut bytes);
        frame.set_size(5);
        frame.set_msg(MsgType::SendRobotPosition, MsgOrder::LittleEndian);
        frame.data_mut().copy_from_slice(&[0x02, 0x03, 0x03]);
        assert_eq!(frame.into_inner(), &OBSERVED_SEND_ROBOT_POSITION_LE);

        let mut bytes = vec![0xa5; 6];
        let mut frame = Frame::new_unchecked(&mut bytes);
        frame.set_size(4);
        frame.set_msg(MsgType::SetObstaclePosition, MsgOrder::BigEndian);
        frame.data_mut().copy_from_slice(&[9, 21]);
        assert_eq!(frame.into_inner(), &DOC_SET_OBSTACLE_POSITION);
    }

    #[test]
    fn test_deconstruct_construct_every_golden_frame() {
        for (bytes, message, order) in golden() {
            let frame = Frame::new_checked(bytes).unwrap();
            assert_eq!(frame.msg_type(), message.msg_type(), "{bytes:02x?}");
            assert_eq!(frame.msg_order(), Some(order), "{bytes:02x?}");
            assert_eq!(frame.data().len(), message.data_len(), "{bytes:02x?}");

            let mut out = vec![0xa5; bytes.len()];
            let mut built = Frame::new_unchecked(&mut out);
            built.set_size(frame.size());
            built.set_msg(frame.msg_type(), order);
            built.data_mut().copy_from_slice(frame.data());
            assert_eq!(&out[..], bytes);
        }
    }

    #[test]
    fn test_parse() {
        for (bytes, message, _) in golden() {
            let frame = Frame::new_checked(bytes).unwrap();
            assert_eq!(GuiMessage::parse(&frame), Ok(message), "{bytes:02x?}");
        }
    }

    #[test]
    fn test_emit() {
        for (bytes, message, order) in golden() {
            assert_eq!(message.buffer_len(), bytes.len());
            let mut out = vec![0xa5; message.buffer_len()];
            message.emit(&mut Frame::new_unchecked(&mut out), order);
            assert_eq!(&out[..], bytes, "{message:?}");
            assert_eq!(message.to_bytes(order), bytes);
        }
    }

    #[test]
    fn test_msg_order_detection_is_unambiguous_for_every_id() {
        for n in 1..=8u8 {
            let id = u16::from(n) << 8;
            assert_eq!(MsgType::from_wire([n, 0]), (MsgType::from(id), Some(MsgOrder::BigEndian)));
            assert_eq!(MsgType::from_wire([0, n]), (MsgType::from(id), Some(MsgOrder::LittleEndian)));
            assert!(!matches!(MsgType::from(id), MsgType::Unknown(_)));
        }
        assert_eq!(MsgType::from_wire([0, 0]), (MsgType::Unknown(0), None));
        assert_eq!(MsgType::from_wire([0, 9]), (MsgType::Unknown(0x0009), None));
        assert_eq!(MsgType::from_wire([1, 1]), (MsgType::Unknown(0x0101), None));
        assert_eq!(MsgType::from_wire([9, 0]), (MsgType::Unknown(0x0900), None));
    }

    #[test]
    fn test_code_enums_list_their_names() {
        assert_eq!(
            Command::NAMED,
            &[
                ("Forward", Command::Forward),
                ("Right", Command::Right),
                ("Left", Command::Left),
                ("Stop", Command::Stop)
            ]
        );
        assert_eq!(Direction::NAMED.len(), 4);
        assert!(MsgType::NAMED.iter().all(|(_, code)| !matches!(code, MsgType::Unknown(_))));
    }

    #[test]
    fn test_code_enums_keep_unknown_values() {
        assert_eq!(Command::from(3), Command::Stop);
        assert_eq!(Command::from(7), Command::Unknown(7));
        assert_eq!(u8::from(Command::Unknown(7)), 7);
        assert_eq!(Direction::from(3), Direction::East);
        assert_eq!(u8::from(Direction::West), 2);
        assert_eq!(Direction::from(200), Direction::Unknown(200));
        assert_eq!(u16::from(MsgType::StopRobot), 0x0600);
        let frame = Frame::new_checked(&[0x00, 0x03, 0x02, 0x00, 0x09][..]).unwrap();
        assert_eq!(
            GuiMessage::parse(&frame),
            Ok(GuiMessage::SendMoveCartography { command: Command::Unknown(9) })
        );
    }

    #[test]
    fn issue_2_cute_2024_cartography_without_data_is_bad_length() {
        let frame = Frame::new_checked(&CUTE_2024_CARTOGRAPHY_SIZE_2[..]).unwrap();
        let error = GuiMessage::parse(&frame).unwrap_err();
        assert_eq!(
            error,
            DecodeError::BadLength { msg: MsgType::SendMoveCartography, expected: 1, actual: 0 }
        );
        assert!(!error.is_fatal());
        assert_eq!(error.to_string(), "message SendMoveCartography needs 1 data bytes, got 0");
    }

    #[test]
    fn test_unknown_msg_keeps_raw_and_data() {
        let bytes = [0x00, 0x05, 0x12, 0x34, 0xAA, 0xBB, 0xCC];
        let frame = Frame::new_checked(&bytes[..]).unwrap();
        let message = GuiMessage::parse(&frame).unwrap();
        assert_eq!(message, GuiMessage::Unknown { msg: 0x1234, data: vec![0xAA, 0xBB, 0xCC] });
        assert_eq!(message.msg_type(), MsgType::Unknown(0x1234));
        assert_eq!(message.to_bytes(MsgOrder::LittleEndian), bytes);
    }

    #[test]
    fn test_check_len_errors() {
        assert_eq!(
            Frame::new_checked(&[0x00, 0x02, 0x03][..]),
            Err(DecodeError::Truncated { need: 4, got: 3 })
        );
        assert_eq!(
            Frame::new_checked(&[0x00, 0x01, 0x03, 0x00][..]),
            Err(DecodeError::SizeTooSmall { size: 1 })
        );
        assert_eq!(
            Frame::new_checked(&[0x00, 0x04, 0x04, 0x00, 0x02][..]),
            Err(DecodeError::Truncated { need: 6, got: 5 })
        );
        // Trailing bytes after the frame are ignored.
        let frame = Frame::new_checked(&[0x00, 0x02, 0x03, 0x00, 0xFF][..]).unwrap();
        assert_eq!(GuiMessage::parse(&frame), Ok(GuiMessage::MoveDone));
        // parse on an unchecked short frame returns an error instead of panicking.
        assert_eq!(
            GuiMessage::parse(&Frame::new_unchecked(&[0x00][..])),
            Err(DecodeError::Truncated { need: 4, got: 1 })
        );
    }

    #[test]
    fn test_extra_data_on_known_message_is_bad_length() {
        let frame = Frame::new_checked(&[0x00, 0x03, 0x03, 0x00, 0x01][..]).unwrap();
        assert_eq!(
            GuiMessage::parse(&frame),
            Err(DecodeError::BadLength { msg: MsgType::MoveDone, expected: 0, actual: 1 })
        );
    }

    #[test]
    fn test_decoder_reports_fatal_size_and_waits_for_reset() {
        let mut decoder = Decoder::new(8);
        let out = decoder.feed(&[0x00, 0x09, 0x01, 0x00]);
        assert_eq!(out, vec![Err(DecodeError::SizeTooLarge { size: 9, max: 8 })]);
        assert!(out[0].as_ref().unwrap_err().is_fatal());
        assert!(decoder.is_failed());
        assert!(decoder.feed(&OBSERVED_MOVE_DONE).is_empty());
        // The 4 bytes of the bad frame, then the 4 of MOVE_DONE.
        assert_eq!(decoder.stats().discarded, 4 + 4);
        decoder.reset();
        assert_eq!(decoder.feed(&OBSERVED_MOVE_DONE), vec![Ok(GuiMessage::MoveDone)]);
        assert_eq!(decoder.stats().errors, 1);
        assert_eq!(decoder.stats().frames, 1);
    }

    #[test]
    fn test_decoder_tracks_last_order() {
        let mut decoder = Decoder::default();
        assert_eq!(decoder.last_order(), None);
        decoder.feed(&OBSERVED_STOP_LE);
        assert_eq!(decoder.last_order(), Some(MsgOrder::LittleEndian));
        decoder.feed(&[0x00, 0x02, 0x77, 0x77]); // unknown id: order unchanged
        assert_eq!(decoder.last_order(), Some(MsgOrder::LittleEndian));
        decoder.feed(&DOC_STOP);
        assert_eq!(decoder.last_order(), Some(MsgOrder::BigEndian));
        assert_eq!(decoder.stats().unknown, 1);
        assert_eq!(decoder.stats().frames, 3);
        assert_eq!(decoder.stats().bytes, 12);
    }

    #[test]
    fn test_max_frame_clamped() {
        assert_eq!(Decoder::new(0).max_frame(), 2);
        assert_eq!(Decoder::new(usize::MAX).max_frame(), 65535);
        assert_eq!(Decoder::default().max_frame(), DEFAULT_MAX_FRAME);
    }

    #[test]
    fn test_unknown_data_longer_than_a_frame_is_truncated_on_emit() {
        let message = GuiMessage::Unknown { msg: 0x7777, data: vec![1; MAX_DATA_LEN + 10] };
        let bytes = message.to_bytes(MsgOrder::BigEndian);
        assert_eq!(bytes.len(), 4 + MAX_DATA_LEN);
        assert_eq!(&bytes[..2], &[0xFF, 0xFF]);
    }
}
