//! Clocks for links that need time: a [`MockClock`] the lockstep runner advances, and a
//! [`WallClock`] for the real-time binaries.
//!
//! Time here is [`Instant`]: microseconds since the run started, the one time type of the
//! workspace (`robot_model::time`).
//!
//! Links that need time take `impl Clock + 'static` and keep it as an `Arc<dyn Clock>`; clones of
//! a [`MockClock`] share one time, so the runner keeps a clone and advances it.
//!
//! ```
//! use robot_model::time::{Duration, Instant};
//! use transport::{Clock, MockClock};
//! let clock = MockClock::new();
//! let seen_by_link = clock.clone();
//! clock.advance(Duration::from_millis(5));
//! assert_eq!(seen_by_link.now(), Instant::from_micros(5_000));
//! clock.set(Instant::from_millis(1)); // never backwards
//! assert_eq!(seen_by_link.now(), Instant::from_micros(5_000));
//! ```

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use robot_model::time::{Duration, Instant};

/// A source of run time.
pub trait Clock: Send + Sync {
    /// Time since the run started.
    fn now(&self) -> Instant;
}

impl<C: Clock + ?Sized> Clock for Arc<C> {
    fn now(&self) -> Instant {
        C::now(self)
    }
}

/// A clock that only moves when told to. Clones share the same time.
#[derive(Debug, Clone, Default)]
pub struct MockClock {
    micros: Arc<AtomicU64>,
}

impl MockClock {
    /// A clock at time zero.
    pub fn new() -> Self {
        Self::default()
    }

    /// Sets the time. Time may only move forward; an earlier value is ignored.
    pub fn set(&self, at: Instant) {
        self.micros.fetch_max(at.total_micros(), Ordering::SeqCst);
    }

    /// Moves the time forward by `by`.
    pub fn advance(&self, by: Duration) {
        self.micros.fetch_add(by.total_micros(), Ordering::SeqCst);
    }
}

impl Clock for MockClock {
    fn now(&self) -> Instant {
        Instant::from_micros(self.micros.load(Ordering::SeqCst))
    }
}

/// The operating system's monotonic clock, counted from when this value was made.
/// Only binaries and real-time runtimes use it; logic never does.
#[derive(Debug, Clone, Copy)]
pub struct WallClock {
    start: std::time::Instant,
}

impl WallClock {
    /// A clock whose zero is now.
    pub fn start() -> Self {
        WallClock { start: std::time::Instant::now() }
    }
}

impl Clock for WallClock {
    fn now(&self) -> Instant {
        Instant::from_micros(u64::try_from(self.start.elapsed().as_micros()).unwrap_or(u64::MAX))
    }
}
