//! Clocks for links that need time: a [`MockClock`] the lockstep runner advances, and a
//! [`WallClock`] for the real-time binaries.
//!
//! Time here is microseconds since the run started, the same count as `robot_model::time::Instant`
//! (this crate depends on nothing in the workspace, so it carries a plain `u64`).
//!
//! Links that need time take `impl Clock + 'static` and keep it as an `Arc<dyn Clock>`; clones of
//! a [`MockClock`] share one time, so the runner keeps a clone and advances it.
//!
//! ```
//! use transport::{Clock, MockClock};
//! let clock = MockClock::new();
//! let seen_by_link = clock.clone();
//! clock.advance_micros(5_000);
//! assert_eq!(seen_by_link.now_micros(), 5_000);
//! clock.set_micros(1_000); // never backwards
//! assert_eq!(seen_by_link.now_micros(), 5_000);
//! ```

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// A source of run time in microseconds.
pub trait Clock: Send + Sync {
    /// Microseconds since the run started.
    fn now_micros(&self) -> u64;
}

impl<C: Clock + ?Sized> Clock for Arc<C> {
    fn now_micros(&self) -> u64 {
        C::now_micros(self)
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
    pub fn set_micros(&self, micros: u64) {
        self.micros.fetch_max(micros, Ordering::SeqCst);
    }

    /// Moves the time forward by `micros`.
    pub fn advance_micros(&self, micros: u64) {
        self.micros.fetch_add(micros, Ordering::SeqCst);
    }
}

impl Clock for MockClock {
    fn now_micros(&self) -> u64 {
        self.micros.load(Ordering::SeqCst)
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
    fn now_micros(&self) -> u64 {
        u64::try_from(self.start.elapsed().as_micros()).unwrap_or(u64::MAX)
    }
}
