//! The keep-state session with the sensor board ([`KeepState`]) and the board's liveness
//! ([`PeerEvent`]).

use robot_model::time::{Duration, Instant};

#[cfg(doc)]
use crate::CartoConfig;

/// A change in the sensor board's liveness.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PeerEvent {
    /// No keep-state for [`Boards::peer_lost_after`](crate::config::Boards::peer_lost_after).
    Lost,
    /// Keep-state heard again after a loss.
    Back,
}

/// The keep-state session with the sensor board: Carto's own 2 Hz keep-state (status 2, sequence
/// from 1, wrapping to 0 after 0xFFFF) and the board's liveness.
#[derive(Debug, Clone)]
pub struct KeepState {
    period: Duration,
    lost_after: Duration,
    /// The sequence number the next keep-state carries (the tests set it to check the wrap).
    pub(super) next_seq: u16,
    next_send: Option<Instant>,
    watch_since: Option<Instant>,
    last_heard: Option<Instant>,
    lost: bool,
}

impl KeepState {
    /// A session that sends every `period` and declares the peer lost after `lost_after`.
    pub fn new(period: Duration, lost_after: Duration) -> Self {
        KeepState {
            period,
            lost_after,
            next_seq: 1,
            next_send: None,
            watch_since: None,
            last_heard: None,
            lost: false,
        }
    }

    /// Records a keep-state from the board; returns [`PeerEvent::Back`] after a loss.
    pub fn heard(&mut self, now: Instant) -> Option<PeerEvent> {
        self.last_heard = Some(now);
        if self.lost {
            self.lost = false;
            return Some(PeerEvent::Back);
        }
        None
    }

    /// Whether the board currently counts as lost.
    pub fn is_lost(&self) -> bool {
        self.lost
    }

    /// Marks the board lost at once (its link went away).
    pub fn force_lost(&mut self) -> bool {
        let was = self.lost;
        self.lost = true;
        !was
    }

    /// Advances the session: a sequence number to send now, and a liveness change if any.
    pub fn poll(&mut self, now: Instant) -> (Option<u16>, Option<PeerEvent>) {
        let mut send = None;
        let due = self.next_send.is_none_or(|t| now >= t);
        if due {
            send = Some(self.next_seq);
            self.next_seq = self.next_seq.wrapping_add(1);
            // Keep a fixed cadence; if the caller fell far behind, restart it from now.
            let base = match self.next_send {
                Some(t) if now.saturating_since(t) < self.period => t,
                _ => now,
            };
            self.next_send = Some(base + self.period);
        }
        let since = *self.watch_since.get_or_insert(now);
        let reference = self.last_heard.unwrap_or(since);
        let mut event = None;
        if !self.lost && now.saturating_since(reference) >= self.lost_after {
            self.lost = true;
            event = Some(PeerEvent::Lost);
        }
        (send, event)
    }

    /// The next time `poll` has something to do.
    pub fn next_deadline(&self) -> Option<Instant> {
        self.next_send
    }

    /// When `poll` would declare the board lost if nothing is heard before (`None`: already
    /// lost, or not watching yet).
    pub fn lost_deadline(&self) -> Option<Instant> {
        if self.lost {
            return None;
        }
        let since = self.watch_since?;
        Some(self.last_heard.unwrap_or(since) + self.lost_after)
    }
}
