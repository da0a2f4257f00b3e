//! Simulation and controller time: microseconds since the run started.
//!
//! Logic never reads a clock. Runtimes own the clock and pass `now: Instant` into every
//! `poll(now)`; the lockstep runner advances a virtual clock by a fixed step, the real-time
//! runtime samples the OS clock in the binary and converts it here.
//!
//! ```
//! use robot_model::time::{Duration, Instant};
//! let start = Instant::ZERO;
//! let later = start + Duration::from_millis(60);
//! assert_eq!(later - start, Duration::from_micros(60_000));
//! assert_eq!(later.total_micros(), 60_000);
//! ```

use core::fmt;
use core::ops::{Add, AddAssign, Sub, SubAssign};

use serde::{Deserialize, Serialize};

/// A point in run time, in microseconds since the run started.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default, Serialize, Deserialize)]
pub struct Instant {
    micros: u64,
}

/// A span of run time in microseconds. Never negative: subtraction saturates at zero.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default, Serialize, Deserialize)]
pub struct Duration {
    micros: u64,
}

impl Instant {
    /// The start of the run.
    pub const ZERO: Instant = Instant { micros: 0 };

    /// An instant `micros` microseconds after the start.
    pub const fn from_micros(micros: u64) -> Self {
        Instant { micros }
    }

    /// An instant `millis` milliseconds after the start.
    pub const fn from_millis(millis: u64) -> Self {
        Instant { micros: millis * 1000 }
    }

    /// An instant `secs` whole seconds after the start.
    pub const fn from_secs(secs: u64) -> Self {
        Instant { micros: secs * 1_000_000 }
    }

    /// An instant `secs` seconds after the start (rounded to the microsecond, negative → zero).
    pub fn from_secs_f64(secs: f64) -> Self {
        Instant { micros: secs_to_micros(secs) }
    }

    /// Microseconds since the start.
    pub const fn total_micros(self) -> u64 {
        self.micros
    }

    /// Milliseconds since the start, rounded down.
    pub const fn total_millis(self) -> u64 {
        self.micros / 1000
    }

    /// Seconds since the start.
    pub fn as_secs_f64(self) -> f64 {
        self.micros as f64 * 1e-6
    }

    /// Time elapsed since `earlier`, zero if `earlier` is later.
    pub fn saturating_since(self, earlier: Instant) -> Duration {
        Duration { micros: self.micros.saturating_sub(earlier.micros) }
    }
}

impl Duration {
    /// No time at all.
    pub const ZERO: Duration = Duration { micros: 0 };

    /// A duration of `micros` microseconds.
    pub const fn from_micros(micros: u64) -> Self {
        Duration { micros }
    }

    /// A duration of `millis` milliseconds.
    pub const fn from_millis(millis: u64) -> Self {
        Duration { micros: millis * 1000 }
    }

    /// A duration of `secs` seconds.
    pub const fn from_secs(secs: u64) -> Self {
        Duration { micros: secs * 1_000_000 }
    }

    /// A duration of `secs` seconds (rounded to the microsecond, negative → zero).
    pub fn from_secs_f64(secs: f64) -> Self {
        Duration { micros: secs_to_micros(secs) }
    }

    /// The duration in microseconds.
    pub const fn total_micros(self) -> u64 {
        self.micros
    }

    /// The duration in whole milliseconds, rounded down.
    pub const fn total_millis(self) -> u64 {
        self.micros / 1000
    }

    /// The duration in seconds.
    pub fn as_secs_f64(self) -> f64 {
        self.micros as f64 * 1e-6
    }

    /// The duration in seconds, as `f32` (for physics).
    pub fn as_secs_f32(self) -> f32 {
        self.as_secs_f64() as f32
    }
}

fn secs_to_micros(secs: f64) -> u64 {
    if secs.is_finite() && secs > 0.0 { (secs * 1e6).round() as u64 } else { 0 }
}

impl Add<Duration> for Instant {
    type Output = Instant;
    fn add(self, rhs: Duration) -> Instant {
        Instant { micros: self.micros.saturating_add(rhs.micros) }
    }
}

impl AddAssign<Duration> for Instant {
    fn add_assign(&mut self, rhs: Duration) {
        *self = *self + rhs;
    }
}

impl Sub<Duration> for Instant {
    type Output = Instant;
    fn sub(self, rhs: Duration) -> Instant {
        Instant { micros: self.micros.saturating_sub(rhs.micros) }
    }
}

impl Sub<Instant> for Instant {
    type Output = Duration;
    fn sub(self, rhs: Instant) -> Duration {
        self.saturating_since(rhs)
    }
}

impl Add for Duration {
    type Output = Duration;
    fn add(self, rhs: Duration) -> Duration {
        Duration { micros: self.micros.saturating_add(rhs.micros) }
    }
}

impl AddAssign for Duration {
    fn add_assign(&mut self, rhs: Duration) {
        *self = *self + rhs;
    }
}

impl Sub for Duration {
    type Output = Duration;
    fn sub(self, rhs: Duration) -> Duration {
        Duration { micros: self.micros.saturating_sub(rhs.micros) }
    }
}

impl SubAssign for Duration {
    fn sub_assign(&mut self, rhs: Duration) {
        *self = *self - rhs;
    }
}

impl From<Duration> for core::time::Duration {
    fn from(d: Duration) -> Self {
        core::time::Duration::from_micros(d.micros)
    }
}

impl From<core::time::Duration> for Duration {
    fn from(d: core::time::Duration) -> Self {
        Duration { micros: u64::try_from(d.as_micros()).unwrap_or(u64::MAX) }
    }
}

/// Bits a byte takes on an 8N1 UART line: start bit, eight data bits, stop bit.
pub const BITS_PER_BYTE: u32 = 10;

/// Bytes per second an 8N1 line at `baud` carries.
pub fn line_bytes_per_sec(baud: u32) -> f64 {
    f64::from(baud) / f64::from(BITS_PER_BYTE)
}

/// Microseconds one byte takes on an 8N1 line at `baud`; 0 for a baud rate of 0 (no timing).
pub fn line_byte_micros(baud: u32) -> f64 {
    if baud == 0 { 0.0 } else { 1.0e6 * f64::from(BITS_PER_BYTE) / f64::from(baud) }
}

impl fmt::Display for Instant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{:06}s", self.micros / 1_000_000, self.micros % 1_000_000)
    }
}

impl fmt::Display for Duration {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{:06}s", self.micros / 1_000_000, self.micros % 1_000_000)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arithmetic_saturates_instead_of_wrapping() {
        let t = Instant::from_millis(5);
        assert_eq!(t - Duration::from_millis(10), Instant::ZERO);
        assert_eq!(Instant::ZERO - t, Duration::ZERO);
        assert_eq!(Instant::from_micros(u64::MAX) + Duration::from_micros(1), Instant::from_micros(u64::MAX));
    }

    #[test]
    fn seconds_round_to_the_microsecond() {
        assert_eq!(Duration::from_secs_f64(0.0000015).total_micros(), 2);
        assert_eq!(Duration::from_secs_f64(-1.0), Duration::ZERO);
        assert_eq!(Duration::from_secs_f64(f64::NAN), Duration::ZERO);
        assert_eq!(Instant::from_secs_f64(1.5).to_string(), "1.500000s");
    }

    #[test]
    fn line_rates_count_ten_bits_per_byte() {
        assert_eq!(line_bytes_per_sec(9600), 960.0);
        assert_eq!(line_byte_micros(115_200), 1.0e7 / 115_200.0);
        assert_eq!(line_byte_micros(0), 0.0);
    }
}
