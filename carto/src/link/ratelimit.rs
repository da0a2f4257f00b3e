//! [`RateLimiter`]: repeated log lines of one kind from one source become one line and a count, at
//! most once per period — so a flood of bad input (1 MB of unknown ids, of STOP frames, of
//! connections) cannot flood the log.
//!
//! Concept: sans-IO, time passed in. Every line Carto logs about client or board input goes
//! through one limiter (`log_limited!`, `warn_limited!`), keyed by a kind and a source (the
//! client's host, see [`host_of`]; `""` for the boards). The first line of a kind and source is
//! logged and opens a window of `period`; further lines of that kind and source inside the
//! window are only counted. When the window
//! is over — seen by the next [`RateLimiter::check`] of that kind or by [`RateLimiter::drain`],
//! which the owner calls from its `poll` — the count is reported once ("N more like this").
//!
//! Invariants: per kind and source, at most one logged line and one summary per `period`; counts
//! are never lost (each suppressed line appears in exactly one summary, once a later `check` or
//! `drain` passes the window's end); memory is bounded: at most [`MAX_WINDOWS`] windows, beyond
//! which new sources share one ([`OTHER_SOURCES`]).
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
//! assert_eq!(limiter.drain(t(1000))[0].count, 2);
//! // per source: each client host has its own budget
//! assert!(limiter.check_from("unknown message", "10.0.0.2", t(1000)).log);
//! assert!(!limiter.check_from("unknown message", "10.0.0.2", t(1001)).log);
//! assert!(limiter.check_from("unknown message", "10.0.0.3", t(1001)).log);
//! ```

use std::collections::BTreeMap;

use robot_model::time::{Duration, Instant};

/// Most windows open at once; past it, warnings from new sources share the source
/// [`OTHER_SOURCES`], so a flood of peers cannot grow the limiter without bound.
pub const MAX_WINDOWS: usize = 1024;
/// The source under which warnings are counted once [`MAX_WINDOWS`] windows are open.
pub const OTHER_SOURCES: &str = "(other sources)";

/// What to do with one warning.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Verdict {
    /// Log this warning.
    pub log: bool,
    /// Warnings of this kind suppressed in the window that just ended: report them first.
    pub more: u64,
}

/// Warnings of one kind from one source that were counted but not logged in a window.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Suppressed {
    /// The warning's kind.
    pub kind: &'static str,
    /// Where it came from (a client's host, `""` for Carto's own links).
    pub source: String,
    /// How many were not logged.
    pub count: u64,
}

#[derive(Debug, Clone, Copy)]
struct Window {
    until: Instant,
    suppressed: u64,
}

/// Per-kind, per-source warning limiter (see the module docs).
#[derive(Debug, Clone)]
pub struct RateLimiter {
    period: Duration,
    windows: BTreeMap<(&'static str, String), Window>,
}

impl RateLimiter {
    /// A limiter allowing one warning per kind and source per `period`.
    pub fn new(period: Duration) -> Self {
        RateLimiter { period, windows: BTreeMap::new() }
    }

    /// One warning of `kind` at `now`, not tied to a peer: whether to log it, and what to report
    /// before it.
    pub fn check(&mut self, kind: &'static str, now: Instant) -> Verdict {
        self.check_from(kind, "", now)
    }

    /// One warning of `kind` caused by `source` (a client's host) at `now`.
    pub fn check_from(&mut self, kind: &'static str, source: &str, now: Instant) -> Verdict {
        let mut key = (kind, source.to_owned());
        if self.windows.len() >= MAX_WINDOWS && !self.windows.contains_key(&key) {
            key.1 = OTHER_SOURCES.to_owned();
        }
        match self.windows.get_mut(&key) {
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
                self.windows.insert(key, Window { until: now + self.period, suppressed: 0 });
                Verdict { log: true, more: 0 }
            }
        }
    }

    /// Closes every window that ended by `now` and returns what was suppressed in them (in kind,
    /// then source order).
    pub fn drain(&mut self, now: Instant) -> Vec<Suppressed> {
        if self.windows.is_empty() {
            return Vec::new();
        }
        let mut out = Vec::new();
        self.windows.retain(|(kind, source), w| {
            if now < w.until {
                return true;
            }
            if w.suppressed > 0 {
                out.push(Suppressed { kind, source: source.clone(), count: w.suppressed });
            }
            false
        });
        out
    }

    /// The earliest time a window ends (when [`RateLimiter::drain`] has something to do).
    pub fn next_deadline(&self) -> Option<Instant> {
        self.windows.values().map(|w| w.until).min()
    }

    /// Windows open now (bounded by [`MAX_WINDOWS`] + kinds).
    pub fn open_windows(&self) -> usize {
        self.windows.len()
    }
}

/// The host part of a peer address (`"10.0.0.2:5000"` → `"10.0.0.2"`, `"[::1]:80"` → `"[::1]"`):
/// the source a client's warnings are counted under, so reconnecting does not reset the budget.
pub fn host_of(peer: &str) -> &str {
    match peer.rsplit_once(':') {
        Some((host, port)) if !host.is_empty() && port.bytes().all(|b| b.is_ascii_digit()) => host,
        _ => peer,
    }
}

/// Logs a rate-limited warning: `warn_limited!(limiter, now, "kind", fields…; "message")`.
/// The summary of the previous window, if any, comes first.
#[macro_export]
macro_rules! warn_limited {
    ($limiter:expr, $now:expr, $kind:expr, $($rest:tt)+) => {
        $crate::log_limited!(warn, $limiter, $now, $kind, "", $($rest)+)
    };
}

/// Logs a line about input from `source` at `level` (`info`, `warn`, `error`), rate-limited per
/// kind and source: `log_limited!(warn, limiter, now, "kind", source, fields…; "message")`.
/// The summary of the previous window, if any, comes first.
#[macro_export]
macro_rules! log_limited {
    ($level:ident, $limiter:expr, $now:expr, $kind:expr, $source:expr, $($rest:tt)+) => {{
        let source: &str = $source;
        let verdict = $limiter.check_from($kind, source, $now);
        if verdict.more > 0 {
            tracing::warn!(kind = $kind, from = source, more = verdict.more, "{} more like this in the last second", verdict.more);
        }
        if verdict.log {
            tracing::$level!($($rest)+);
        }
    }};
}

/// Logs the summaries [`RateLimiter::drain`] returned.
pub fn log_suppressed(summaries: Vec<Suppressed>) {
    for s in summaries {
        tracing::warn!(kind = s.kind, from = %s.source, more = s.count, "{} more like this in the last second", s.count);
    }
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
            summaries.extend(l.drain(t(i / 2)).into_iter().map(|s| s.count));
        }
        assert!(l.check("other", t(4999)).log);
        summaries.extend(l.drain(t(10_000)).into_iter().map(|s| s.count));
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
