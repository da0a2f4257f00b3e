//! What the session remembers about its peer beyond the protocol: the original 2024 Carto's
//! dropped batch after a STOP, and a server that never answers SEND_ROBOT_POSITION (the
//! [`COMPAT_HINT`]).
//!
//! Concept (research §1.5, §1.9 item 11): the original Carto's STOP_ROBOT sets a flag that makes
//! it skip the **next complete trajectory batch**, then re-arms. So in `--compat explobot-2024`
//! every STOP_ROBOT that goes out marks the next batch as dropped; the session sends that batch
//! (the original must receive it to re-arm), keeps the believed pose where it was and reports
//! [`CuteEvent::BatchDropped`](super::CuteEvent::BatchDropped). The mark lives as long as the
//! session, across reconnects: the flag is the Carto process's, not the connection's.
//!
//! The original Carto also ignores our default big-endian ids, so it never answers
//! SEND_ROBOT_POSITION. After [`HINT_AFTER`] timeouts in a row without any
//! ROBOT_POSITION_RECEIVED, the session reports [`CuteEvent::CompatHint`](super::CuteEvent::CompatHint)
//! once; an acknowledgement starts the count again.
//!
//! Invariants: the hint is reported at most once per run of unanswered requests; a batch is
//! marked dropped only after a STOP_ROBOT was queued on a live connection in compat mode.
//!
//! ```
//! use cute::session::{COMPAT_HINT, Cute, CuteConfig, CuteEvent, HINT_AFTER};
//! use robot_model::time::Instant;
//! let mut cute = Cute::new(CuteConfig::default()).unwrap(); // default mode: big-endian ids
//! cute.on_connected(Instant::ZERO);                          // SEND_ROBOT_POSITION
//! for s in 1..=HINT_AFTER {
//!     cute.poll(Instant::from_secs(5 * u64::from(s)));      // each: timeout, sent again
//! }
//! assert_eq!(cute.take_events().last(), Some(&CuteEvent::CompatHint));
//! assert!(COMPAT_HINT.contains("--compat explobot-2024"));
//! ```

use super::Compat;

/// What Cute says when SEND_ROBOT_POSITION goes unanswered [`HINT_AFTER`] times in a row.
pub const COMPAT_HINT: &str =
    "no answer to SEND_ROBOT_POSITION — if this is the 2024 Carto, start Cute with --compat explobot-2024";

/// Unanswered SEND_ROBOT_POSITION requests in a row before [`COMPAT_HINT`].
pub const HINT_AFTER: u32 = 3;

/// The peer's quirks the session tracks (see the module docs).
#[derive(Debug, Clone, Default)]
pub(crate) struct Quirks {
    /// Compat: a STOP_ROBOT went out, so the original Carto skips the next complete batch.
    drop_next_batch: bool,
    /// SEND_ROBOT_POSITION timeouts since the last ROBOT_POSITION_RECEIVED.
    unanswered: u32,
}

impl Quirks {
    /// A STOP_ROBOT was queued on a live connection.
    pub(crate) fn stop_sent(&mut self, compat: Compat) {
        if compat == Compat::Explobot2024 {
            self.drop_next_batch = true;
        }
    }

    /// True if the next batch will be dropped by the original Carto (consumes the mark).
    pub(crate) fn take_drop(&mut self) -> bool {
        std::mem::take(&mut self.drop_next_batch)
    }

    /// True while a batch sent now would be dropped.
    pub(crate) fn drop_pending(&self) -> bool {
        self.drop_next_batch
    }

    /// A SEND_ROBOT_POSITION timed out; true when this makes [`HINT_AFTER`] in a row.
    pub(crate) fn position_unanswered(&mut self) -> bool {
        self.unanswered = self.unanswered.saturating_add(1);
        self.unanswered == HINT_AFTER
    }

    /// Carto sent ROBOT_POSITION_RECEIVED.
    pub(crate) fn position_answered(&mut self) {
        self.unanswered = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hint_comes_once_on_the_third_timeout_and_an_answer_rearms_it() {
        let mut q = Quirks::default();
        let hints: Vec<bool> = (0..6).map(|_| q.position_unanswered()).collect();
        assert_eq!(hints, [false, false, true, false, false, false]);
        q.position_answered();
        assert!(!q.position_unanswered() && !q.position_unanswered() && q.position_unanswered());
    }

    #[test]
    fn only_a_compat_stop_marks_the_next_batch_dropped_and_only_once() {
        let mut q = Quirks::default();
        q.stop_sent(Compat::Default);
        assert!(!q.drop_pending() && !q.take_drop());
        q.stop_sent(Compat::Explobot2024);
        q.stop_sent(Compat::Explobot2024);
        assert!(q.drop_pending());
        assert!(q.take_drop(), "the next batch is dropped");
        assert!(!q.take_drop(), "two STOPs still drop one batch: the original's flag is a bool");
    }
}
