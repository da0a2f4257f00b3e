//! The front HC-SR04 as the obstacle check before every FORWARD sees it.
//!
//! Concept: the sensor board streams distance readings (10 Hz by default). Before a FORWARD, the
//! pilot asks [`Ultrasound::check`] with `rest_since`, the time the robot came to rest at its
//! current cell and heading. Only a reading that *arrived at or after* `rest_since` counts: an
//! older one was measured from another place or facing another way (after a turn or a move), so it
//! says nothing about the cell ahead now. Nor does a reading older than the maximum age (default
//! 300 ms, three sensor periods), even with the robot at rest: something may have stepped in front. Until such a reading arrives the answer is
//! [`Check::Pending`]; the pilot waits up to [`Safety::distance_wait`](crate::config::Safety::distance_wait) and then gives
//! the move up without moving (fail safe: never drive blind).
//!
//! Invariants:
//! - a reading at or below the threshold (default one cell: 45 cm for the default 0.45 m cell) is an obstacle;
//! - a negative reading (−1.0 = no echo) is clear: nothing within the sensor's 4 m range;
//! - readings with an error status, NaN or infinity are dropped and counted, never used.
//!
//! ```
//! use carto::ultrasound::{Check, Ultrasound};
//! use robot_model::time::{Duration, Instant};
//! let mut us = Ultrasound::new(30.0, Duration::from_millis(300));
//! let rest = Instant::from_millis(1000);
//! us.on_reading(Instant::from_millis(900), 12.0, true);
//! let now = Instant::from_millis(1000);
//! assert_eq!(us.check(now, rest), Check::Pending); // measured before the robot came to rest
//! us.on_reading(Instant::from_millis(1050), 12.0, true);
//! assert_eq!(us.check(Instant::from_millis(1100), rest), Check::Obstacle { cm: 12.0 });
//! assert_eq!(us.check(Instant::from_millis(1400), rest), Check::Pending); // too old now
//! us.on_reading(Instant::from_millis(1450), -1.0, true);
//! assert_eq!(us.check(Instant::from_millis(1450), rest), Check::Clear { cm: None });
//! ```

use robot_model::time::{Duration, Instant};

use crate::sensors::Stamped;

/// The outcome of an obstacle check.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Check {
    /// Nothing within the threshold; the distance if there was an echo.
    Clear {
        /// The measured distance, `None` for no echo.
        cm: Option<f32>,
    },
    /// An echo at or below the threshold.
    Obstacle {
        /// The measured distance.
        cm: f32,
    },
    /// No reading taken at rest yet.
    Pending,
}

/// Latest front distance reading and the obstacle rule.
#[derive(Debug, Clone)]
pub struct Ultrasound {
    threshold_cm: f32,
    max_age: Duration,
    latest: Option<Stamped<f32>>,
    readings: u64,
    rejected: u64,
}

impl Ultrasound {
    /// An ultrasound with the obstacle threshold `threshold_cm`, trusting readings up to `max_age`.
    pub fn new(threshold_cm: f32, max_age: Duration) -> Self {
        Ultrasound { threshold_cm, max_age, latest: None, readings: 0, rejected: 0 }
    }

    /// Records a reading that arrived at `now`; `ok` is the sensor's status (false = error).
    pub fn on_reading(&mut self, now: Instant, cm: f32, ok: bool) {
        if !ok || !cm.is_finite() {
            self.rejected += 1;
            return;
        }
        self.readings += 1;
        self.latest = Some(Stamped { value: cm, at: now });
    }

    /// The obstacle rule applied to the latest reading, if it arrived at or after `rest_since`
    /// and is at most the maximum age at `now`.
    pub fn check(&self, now: Instant, rest_since: Instant) -> Check {
        self.check_ahead(now, rest_since, 0.0)
    }

    /// [`Ultrasound::check`] for a robot `done_cm` past its cell's centre along its heading (a
    /// FORWARD cut short, or a shift before a turn; negative: behind the centre). The FORWARD
    /// still ends on the next cell's centre, so the threshold shrinks by what is done: the rule
    /// stays "the front face at the next centre would reach the echo".
    pub fn check_ahead(&self, now: Instant, rest_since: Instant, done_cm: f32) -> Check {
        let threshold_cm = self.threshold_cm - done_cm;
        match self.latest {
            Some(r) if r.at >= rest_since && now.saturating_since(r.at) <= self.max_age => {
                if r.value < 0.0 {
                    Check::Clear { cm: None }
                } else if r.value <= threshold_cm {
                    Check::Obstacle { cm: r.value }
                } else {
                    Check::Clear { cm: Some(r.value) }
                }
            }
            _ => Check::Pending,
        }
    }

    /// The latest accepted reading, whenever it arrived.
    pub fn latest(&self) -> Option<Stamped<f32>> {
        self.latest
    }

    /// Readings accepted so far.
    pub fn readings(&self) -> u64 {
        self.readings
    }

    /// Readings dropped (error status, NaN, infinity).
    pub fn rejected(&self) -> u64 {
        self.rejected
    }

    /// The obstacle threshold, cm.
    pub fn threshold_cm(&self) -> f32 {
        self.threshold_cm
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn threshold_is_inclusive_and_no_echo_is_clear() {
        let mut us = Ultrasound::new(30.0, Duration::from_millis(300));
        let t = Instant::from_millis(10);
        us.on_reading(t, 30.0, true);
        assert_eq!(us.check(t, t), Check::Obstacle { cm: 30.0 });
        us.on_reading(t, 30.5, true);
        assert_eq!(us.check(t, t), Check::Clear { cm: Some(30.5) });
        us.on_reading(t, -1.0, true);
        assert_eq!(us.check(t, t), Check::Clear { cm: None });
    }

    #[test]
    fn a_robot_past_its_centre_checks_only_the_rest_of_the_move() {
        let mut us = Ultrasound::new(45.0, Duration::from_millis(300));
        let t = Instant::from_millis(10);
        // a FORWARD cut short 16 cm in: a wall 36 cm ahead is 7 cm beyond the front face's stop
        us.on_reading(t, 36.0, true);
        assert_eq!(us.check(t, t), Check::Obstacle { cm: 36.0 });
        assert_eq!(us.check_ahead(t, t, 16.0), Check::Clear { cm: Some(36.0) });
        // 5 cm behind the centre the move is 50 cm long: a wall 47 cm ahead blocks it
        us.on_reading(t, 47.0, true);
        assert_eq!(us.check(t, t), Check::Clear { cm: Some(47.0) });
        assert_eq!(us.check_ahead(t, t, -5.0), Check::Obstacle { cm: 47.0 });
    }

    #[test]
    fn error_status_and_nan_are_rejected_and_keep_the_previous_reading() {
        let mut us = Ultrasound::new(30.0, Duration::from_millis(300));
        us.on_reading(Instant::from_millis(1), 100.0, true);
        us.on_reading(Instant::from_millis(2), 5.0, false);
        us.on_reading(Instant::from_millis(3), f32::NAN, true);
        assert_eq!(us.rejected(), 2);
        assert_eq!(us.latest().unwrap().value, 100.0);
        assert_eq!(us.check(Instant::from_millis(3), Instant::from_millis(2)), Check::Pending);
    }
}
