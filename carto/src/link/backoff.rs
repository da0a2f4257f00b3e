//! [`Backoff`]: when to try reopening a board port that went away, with time passed in.
//!
//! Concept: the first retry comes `initial` after the loss, each failure doubles the wait up to
//! `max`, and a success resets it. Sans-IO: the caller asks [`Backoff::due`] with its `now`, tries,
//! and reports [`Backoff::failed`] or [`Backoff::reset`].
//!
//! ```
//! use carto::backoff::Backoff;
//! use robot_model::time::{Duration, Instant};
//! let mut b = Backoff::new(Duration::from_millis(100), Duration::from_secs(2));
//! let t = Instant::from_millis;
//! b.failed(t(0));
//! assert!(!b.due(t(50)) && b.due(t(100)));
//! b.failed(t(100));
//! assert!(!b.due(t(250)) && b.due(t(300)));
//! ```

use robot_model::time::{Duration, Instant};

/// Exponential back-off between reconnection attempts (see the module docs).
#[derive(Debug, Clone)]
pub struct Backoff {
    initial: Duration,
    max: Duration,
    wait: Duration,
    next: Option<Instant>,
}

impl Backoff {
    /// A back-off starting at `initial`, doubling up to `max`; due at once until a failure.
    pub fn new(initial: Duration, max: Duration) -> Self {
        Backoff { initial, max, wait: initial, next: None }
    }

    /// Whether an attempt is due at `now`.
    pub fn due(&self, now: Instant) -> bool {
        self.next.is_none_or(|t| now >= t)
    }

    /// An attempt failed at `now`: the next one waits the current delay, which then doubles.
    pub fn failed(&mut self, now: Instant) {
        self.next = Some(now + self.wait);
        self.wait = Duration::from_micros(self.wait.total_micros().saturating_mul(2)).min(self.max);
    }

    /// When the next attempt is due (`None`: at once).
    pub fn next_attempt(&self) -> Option<Instant> {
        self.next
    }

    /// The current delay before the next attempt after a failure.
    pub fn current(&self) -> Duration {
        self.wait
    }

    /// An attempt succeeded: back to the first delay, due at once next time.
    pub fn reset(&mut self) {
        self.wait = self.initial;
        self.next = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn doubles_up_to_the_maximum_and_resets() {
        let mut b = Backoff::new(Duration::from_millis(250), Duration::from_secs(1));
        assert!(b.due(Instant::ZERO));
        let mut t = Instant::ZERO;
        let mut waits = Vec::new();
        for _ in 0..5 {
            b.failed(t);
            let mut probe = t;
            while !b.due(probe) {
                probe += Duration::from_millis(1);
            }
            waits.push((probe - t).total_millis());
            t = probe;
        }
        assert_eq!(waits, vec![250, 500, 1000, 1000, 1000]);
        b.reset();
        assert!(b.due(t));
        assert_eq!(b.current(), Duration::from_millis(250));
    }
}
