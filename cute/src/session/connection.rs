//! The session's connection: when to dial (reconnect back-off), whether the link is up and the
//! position acknowledged, and the framing (encoding in the compat byte order, decoding with
//! resync).
//!
//! Concept: a [`Connection`] is *down* (dial at `retry_at`) or *up* (waiting for
//! ROBOT_POSITION_RECEIVED until `ack_deadline`, or ready). The first attempt is due at once; each
//! failed attempt waits [`RECONNECT_MIN`] the first time, then twice the previous delay, up to
//! [`RECONNECT_MAX`]. A lost connection is retried after [`RECONNECT_MIN`], and failures from
//! there double again. Encoded frames collect in an outgoing buffer the runtime drains.
//!
//! Invariants: the decoder and the outgoing buffer are emptied at every connect and disconnect,
//! so no partial frame or stale command crosses from one connection to the next; the delay is
//! always within `RECONNECT_MIN..=RECONNECT_MAX`.
//!
//! ```
//! use cute::session::{Cute, CuteConfig, RECONNECT_MIN};
//! use robot_model::time::Instant;
//! let mut cute = Cute::new(CuteConfig::default()).unwrap();
//! assert_eq!(cute.next_connect_at(Instant::ZERO), Some(Instant::ZERO)); // dial at once
//! cute.on_connect_failed(Instant::ZERO);
//! assert_eq!(cute.next_connect_at(Instant::ZERO), Some(Instant::ZERO + RECONNECT_MIN));
//! cute.on_connect_failed(Instant::from_millis(250));
//! assert_eq!(cute.next_connect_at(Instant::ZERO), Some(Instant::from_millis(750))); // 250 + 500
//! ```

use protocol::link::{DecodeError, Decoder, GuiMessage, MsgOrder};
use robot_model::time::{Duration, Instant};

/// First reconnect delay after a disconnect.
pub const RECONNECT_MIN: Duration = Duration::from_millis(250);
/// Largest reconnect delay.
pub const RECONNECT_MAX: Duration = Duration::from_secs(4);

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    /// Not connected: dial at `retry_at`; `backoff` is the delay that led there.
    Down { retry_at: Instant, backoff: Duration, ever_connected: bool },
    /// Connected; `ack_deadline` is set while the position is not acknowledged.
    Up { ack_deadline: Option<Instant> },
}

/// Link state, back-off and framing of one session (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct Connection {
    state: State,
    order: MsgOrder,
    decoder: Decoder,
    outgoing: Vec<u8>,
}

impl Connection {
    /// Down, first attempt due at once; frames encoded in `order`, incoming `Size` up to
    /// `max_frame`.
    pub(crate) fn new(order: MsgOrder, max_frame: usize) -> Connection {
        Connection {
            state: State::Down { retry_at: Instant::ZERO, backoff: RECONNECT_MIN, ever_connected: false },
            order,
            decoder: Decoder::new(max_frame),
            outgoing: Vec::new(),
        }
    }

    /// True while the link is up.
    pub(crate) fn is_up(&self) -> bool {
        matches!(self.state, State::Up { .. })
    }

    /// True while the link is up and nothing is awaiting an acknowledgement.
    pub(crate) fn is_ready(&self) -> bool {
        matches!(self.state, State::Up { ack_deadline: None })
    }

    /// When to dial next; `None` while up.
    pub(crate) fn next_connect_at(&self) -> Option<Instant> {
        match self.state {
            State::Down { retry_at, .. } => Some(retry_at),
            State::Up { .. } => None,
        }
    }

    /// An attempt failed at `now`: wait longer before the next one.
    pub(crate) fn connect_failed(&mut self, now: Instant) {
        if let State::Down { retry_at, backoff, ever_connected } = &mut self.state {
            let next = if *retry_at == Instant::ZERO && !*ever_connected {
                RECONNECT_MIN
            } else {
                Duration::from_micros((backoff.total_micros() * 2).min(RECONNECT_MAX.total_micros()))
            };
            *backoff = next;
            *retry_at = now + next;
        }
    }

    /// The link is up, waiting for an acknowledgement until `ack_deadline` if given. Returns
    /// `None` if it already was up, else whether this is a reconnect.
    pub(crate) fn connected(&mut self, ack_deadline: Option<Instant>) -> Option<bool> {
        let State::Down { ever_connected, .. } = self.state else {
            return None;
        };
        self.state = State::Up { ack_deadline };
        self.clear();
        Some(ever_connected)
    }

    /// The link went down at `now`: retry after [`RECONNECT_MIN`]. Returns whether it was up.
    pub(crate) fn disconnected(&mut self, now: Instant) -> bool {
        if !self.is_up() {
            return false;
        }
        self.state =
            State::Down { retry_at: now + RECONNECT_MIN, backoff: RECONNECT_MIN, ever_connected: true };
        self.clear();
        true
    }

    /// Carto acknowledged the position. Returns whether one was awaited.
    pub(crate) fn acknowledge(&mut self) -> bool {
        if let State::Up { ack_deadline: Some(_) } = self.state {
            self.state = State::Up { ack_deadline: None };
            return true;
        }
        false
    }

    /// If the acknowledgement is overdue at `now`, waits for it again until `next` and returns
    /// true (the caller re-sends the position).
    pub(crate) fn ack_overdue(&mut self, now: Instant, next: Instant) -> bool {
        if let State::Up { ack_deadline: Some(deadline) } = self.state
            && now >= deadline
        {
            self.state = State::Up { ack_deadline: Some(next) };
            return true;
        }
        false
    }

    /// Queues `msg` for the wire; returns its length in bytes.
    pub(crate) fn encode(&mut self, msg: &GuiMessage) -> usize {
        let bytes = msg.to_bytes(self.order);
        self.outgoing.extend_from_slice(&bytes);
        bytes.len()
    }

    /// Frames (or errors) completed by `bytes`.
    pub(crate) fn decode(&mut self, bytes: &[u8]) -> Vec<Result<GuiMessage, DecodeError>> {
        self.decoder.feed(bytes)
    }

    /// Takes the bytes queued for the wire.
    pub(crate) fn take_outgoing(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.outgoing)
    }

    fn clear(&mut self) {
        self.decoder.reset();
        self.outgoing.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::link::DEFAULT_MAX_FRAME;

    fn conn() -> Connection {
        Connection::new(MsgOrder::BigEndian, DEFAULT_MAX_FRAME)
    }

    /// Fails every attempt as soon as it is due and returns the delays between attempts.
    fn delays(c: &mut Connection, from: Instant, attempts: usize) -> Vec<u64> {
        let mut now = from;
        let mut out = Vec::new();
        for _ in 0..attempts {
            now = c.next_connect_at().unwrap_or(now).max(now);
            c.connect_failed(now);
            let next = c.next_connect_at().unwrap_or(now);
            out.push((next - now).total_micros() / 1000);
        }
        out
    }

    #[test]
    fn back_off_doubles_from_250_ms_to_4_s() {
        let mut c = conn();
        assert_eq!(c.next_connect_at(), Some(Instant::ZERO));
        assert_eq!(delays(&mut c, Instant::ZERO, 7), [250, 500, 1000, 2000, 4000, 4000, 4000]);
    }

    #[test]
    fn a_lost_connection_retries_after_250_ms_then_doubles_again() {
        let mut c = conn();
        c.connect_failed(Instant::ZERO);
        c.connect_failed(Instant::from_millis(250));
        assert_eq!(c.connected(Some(Instant::from_secs(10))), Some(false));
        assert!(c.is_up() && !c.is_ready() && c.next_connect_at().is_none());
        assert!(c.disconnected(Instant::from_secs(3)));
        assert_eq!(c.next_connect_at(), Some(Instant::from_millis(3250)));
        assert_eq!(delays(&mut c, Instant::from_millis(3250), 3), [500, 1000, 2000]);
        assert_eq!(c.connected(None), Some(true), "the second connection is a reconnect");
        assert!(c.is_ready());
    }

    #[test]
    fn connect_and_disconnect_are_idempotent() {
        let mut c = conn();
        assert!(!c.disconnected(Instant::ZERO));
        assert_eq!(c.connected(None), Some(false));
        assert_eq!(c.connected(None), None);
        c.connect_failed(Instant::from_secs(1));
        assert!(c.next_connect_at().is_none(), "a failure report while up changes nothing");
    }

    #[test]
    fn acknowledgement_and_its_timeout() {
        let mut c = conn();
        c.connected(Some(Instant::from_secs(5)));
        assert!(!c.ack_overdue(Instant::from_millis(4999), Instant::from_secs(10)));
        assert!(c.ack_overdue(Instant::from_secs(5), Instant::from_secs(10)));
        assert!(!c.ack_overdue(Instant::from_secs(9), Instant::from_secs(15)), "re-armed at 10 s");
        assert!(c.acknowledge());
        assert!(c.is_ready());
        assert!(!c.acknowledge(), "a second acknowledgement is unsolicited");
        assert!(!c.ack_overdue(Instant::from_secs(60), Instant::from_secs(65)));
    }

    #[test]
    fn a_new_connection_starts_with_empty_buffers() {
        let mut c = conn();
        c.connected(None);
        assert_eq!(c.encode(&GuiMessage::StopRobot), 4);
        assert_eq!(c.decode(&[0x00, 0x02]), []); // half a frame
        c.disconnected(Instant::ZERO);
        assert!(c.take_outgoing().is_empty(), "nothing queued crosses a disconnect");
        c.connected(None);
        // The old half frame is gone: a whole ROBOT_POSITION_RECEIVED decodes on its own.
        assert_eq!(c.decode(&[0x00, 0x02, 0x08, 0x00]), [Ok(GuiMessage::RobotPositionReceived)]);
    }

    #[test]
    fn frames_are_encoded_in_the_compat_byte_order() {
        let mut c = Connection::new(MsgOrder::LittleEndian, DEFAULT_MAX_FRAME);
        c.encode(&GuiMessage::StopRobot);
        let big = GuiMessage::StopRobot.to_bytes(MsgOrder::BigEndian);
        let little = c.take_outgoing();
        assert_eq!(little, GuiMessage::StopRobot.to_bytes(MsgOrder::LittleEndian));
        assert_ne!(little, big);
    }
}
