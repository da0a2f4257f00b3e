//! The board twins: sans-IO models of the motor board and sensor board firmware.
//!
//! Each twin takes the bytes Carto sends (`receive(now, bytes)`), and hands back the bytes the
//! board would send (`poll(now, …) -> Vec<u8>`) plus, for the motor board, the wheel setpoints
//! the physics should chase. They never read a clock, never sleep and never do IO: a lockstep
//! runner, a real-time server and the tests all drive them the same way. Bytes in and out are
//! the real wire formats of [`protocol::motor`] and [`protocol::sensor`].

mod motor_board;
mod sensor_board;

pub use motor_board::{MotorBoard, MotorBoardCounters};
pub use sensor_board::{SensorBoard, SensorBoardCounters, SensorInputs};

use crate::time::{Duration, Instant};

/// The period of a rate in Hz, `None` for a rate of zero (stream off) or a non-finite one.
pub(crate) fn period_of(hz: f32) -> Option<Duration> {
    (hz.is_finite() && hz > 0.0).then(|| Duration::from_secs_f64(1.0 / f64::from(hz)))
}

/// A fixed-rate schedule: due at the first poll, then every `period`. A poll that comes late by
/// more than a period fires once and restarts the schedule from `now` (no burst of catch-ups).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Periodic {
    period: Option<Duration>,
    next: Option<Instant>,
}

impl Periodic {
    pub(crate) fn new(period: Option<Duration>) -> Self {
        Periodic { period, next: None }
    }

    pub(crate) fn from_hz(hz: f32) -> Self {
        Self::new(period_of(hz))
    }

    /// Whether the stream fires at `now`; advances the schedule when it does.
    pub(crate) fn fire(&mut self, now: Instant) -> bool {
        let Some(period) = self.period else {
            return false;
        };
        if self.next.is_some_and(|next| now < next) {
            return false;
        }
        let mut next = self.next.unwrap_or(now) + period;
        if next <= now {
            next = now + period;
        }
        self.next = Some(next);
        true
    }

    /// Restarts the schedule so the next firing is one period after `now`.
    pub(crate) fn restart(&mut self, now: Instant) {
        self.next = self.period.map(|p| now + p);
    }

    /// Changes the period, keeping the phase of the last firing when there was one.
    pub(crate) fn set_period(&mut self, period: Option<Duration>) {
        if let (Some(old), Some(next)) = (self.period, self.next) {
            self.next = period.map(|p| next - old + p);
        }
        self.period = period;
    }

    pub(crate) fn period(&self) -> Option<Duration> {
        self.period
    }

    /// When the stream next fires (`None` before the first poll or when off).
    pub(crate) fn next(&self) -> Option<Instant> {
        self.period.and(self.next)
    }

    /// Firings per second.
    pub(crate) fn rate_hz(&self) -> f32 {
        self.period.map_or(0.0, |p| (1.0 / p.as_secs_f64()) as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn periodic_fires_on_schedule_and_skips_missed_slots() {
        let mut p = Periodic::from_hz(10.0);
        assert!(p.fire(Instant::from_millis(3)));
        assert!(!p.fire(Instant::from_millis(102)));
        assert!(p.fire(Instant::from_millis(103)));
        // Late by several periods: one firing, then one period after the late poll.
        assert!(p.fire(Instant::from_millis(550)));
        assert!(!p.fire(Instant::from_millis(649)));
        assert!(p.fire(Instant::from_millis(650)));
        assert!(!Periodic::from_hz(0.0).fire(Instant::ZERO));
    }
}
