//! [`RateLimiter`]: repeated warnings of one kind become one line and a count, at most once per
//! period — so a flood of bad input (1 MB of unknown ids) cannot flood the log.
//!
//! Concept: sans-IO, time passed in. The first warning of a kind is logged and opens a window of
//! `period`; further warnings of that kind inside the window are only counted. When the window
//! is over — seen by the next [`RateLimiter::check`] of that kind or by [`RateLimiter::drain`],
//! which the owner calls from its `poll` — the count is reported once ("N more like this").
//!
//! Invariants: per kind, at most one logged warning and one summary per `period`; counts are
//! never lost (each suppressed warning appears in exactly one summary, once a later `check` or
//! `drain` passes the window's end); memory grows with the number of kinds only.
//!
//! ```
//! use carto::ratelimit::RateLimiter;
//! use robot_model::time::{Duration, Instant};
//! let mut limiter = RateLimiter::new(Duration::from_secs(1));
//! let t = Instant::from_millis;
//! assert!(limiter.check("unknown message", t(0)).log);
//! assert!(!limiter.check("unknown message", t(10)).log);
//! assert!(!limiter.check("unknown message", t(20)).log);
//! assert!(limiter.drain(t(500)).is_empty());
//! assert_eq!(limiter.drain(t(1000)), vec![("unknown message", 2)]);
//! ```

use std::collections::BTreeMap;

use robot_model::time::{Duration, Instant};

/// What to do with one warning.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Verdict {
    /// Log this warning.
    pub log: bool,
    /// Warnings of this kind suppressed in the window that just ended: report them first.
    pub more: u64,
}

#[derive(Debug, Clone, Copy)]
struct Window {
    until: Instant,
    suppressed: u64,
}

/// Per-kind warning limiter (see the module docs).
#[derive(Debug, Clone)]
pub struct RateLimiter {
    period: Duration,
    windows: BTreeMap<&'static str, Window>,
}

impl RateLimiter {
    /// A limiter allowing one warning per kind per `period`.
    pub fn new(period: Duration) -> Self {
        RateLimiter { period, windows: BTreeMap::new() }
    }

    /// One warning of `kind` at `now`: whether to log it, and what to report before it.
    pub fn check(&mut self, kind: &'static str, now: Instant) -> Verdict {
        match self.windows.get_mut(kind) {
            Some(w) if now < w.until => {
                w.suppressed += 1;
                Verdict { log: false, more: 0 }
            }
            Some(w) => {
                let more = w.suppressed;
                *w = Window { until: now + self.period, suppressed: 0 };
                Verdict { log: true, more }
            }
            None => {
                self.windows.insert(kind, Window { until: now + self.period, suppressed: 0 });
                Verdict { log: true, more: 0 }
            }
        }
    }

    /// Closes every window that ended by `now` and returns the kinds with warnings suppressed in
    /// it, with their counts (in kind order).
    pub fn drain(&mut self, now: Instant) -> Vec<(&'static str, u64)> {
        if self.windows.is_empty() {
            return Vec::new();
        }
        let mut out = Vec::new();
        self.windows.retain(|kind, w| {
            if now < w.until {
                return true;
            }
            if w.suppressed > 0 {
                out.push((*kind, w.suppressed));
            }
            false
        });
        out
    }
}

/// Logs a rate-limited warning: `warn_limited!(limiter, now, "kind", fields…; "message")`.
/// The summary of the previous window, if any, comes first.
#[macro_export]
macro_rules! warn_limited {
    ($limiter:expr, $now:expr, $kind:expr, $($rest:tt)+) => {{
        let verdict = $limiter.check($kind, $now);
        if verdict.more > 0 {
            tracing::warn!(kind = $kind, more = verdict.more, "{} more like this in the last second", verdict.more);
        }
        if verdict.log {
            tracing::warn!($($rest)+);
        }
    }};
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(ms: u64) -> Instant {
        Instant::from_millis(ms)
    }

    #[test]
    fn issue_15_a_flood_logs_once_per_second_per_kind() {
        let mut l = RateLimiter::new(Duration::from_secs(1));
        let mut logged = 0;
        let mut summaries = Vec::new();
        // 10,000 warnings of one kind over 5 s, and one of another kind.
        for i in 0..10_000u64 {
            let v = l.check("flood", t(i / 2));
            logged += u64::from(v.log);
            if v.more > 0 {
                summaries.push(v.more);
            }
            summaries.extend(l.drain(t(i / 2)).into_iter().map(|(_, n)| n));
        }
        assert!(l.check("other", t(4999)).log);
        summaries.extend(l.drain(t(10_000)).into_iter().map(|(_, n)| n));
        assert_eq!(logged, 5);
        assert_eq!(logged + summaries.iter().sum::<u64>(), 10_000);
        assert!(summaries.len() <= 5, "{summaries:?}");
    }

    #[test]
    fn a_quiet_kind_logs_every_time() {
        let mut l = RateLimiter::new(Duration::from_secs(1));
        for s in 0..5 {
            assert_eq!(l.check("rare", t(s * 1500)), Verdict { log: true, more: 0 });
            assert!(l.drain(t(s * 1500 + 1200)).is_empty());
        }
    }
}
