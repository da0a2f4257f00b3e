//! The calibration drive: a fixed list of open-loop drive commands that exercises what
//! `explobot calibrate` fits (`docs/how-to/real-robot.md`, "Calibrate").
//!
//! Concept: [`CalibrationDrive`] is a sans-IO timer over [`PLAN`]. [`CalibrationDrive::poll`]
//! says which [`Drive`] to send now: on every change of segment and every
//! [`RESEND`] in between, so the motor board's 500 ms watchdog never trips. Carto sends it
//! instead of its pilot's commands while the drive runs ([`crate::Carto::start_calibration_drive`]).
//!
//! The plan, for a robot standing about 1.5 m from a flat wall and facing it, with at least
//! 0.6 m free on either side: still (the IMU's drift, the sonar's noise at one distance), small
//! steps forward at speeds around the motor's dead band, straight runs at two speeds towards the
//! wall and back (ranges at several distances, the motor's time constant, the wheel radius
//! through the sonar), sideways shifts both ways, turns both ways (the wheel radius through the
//! IMU, ranges to the wall at several angles), and still again. Every move is undone by its
//! mirror, so the robot ends where it started (within the slip of the wheels).
//!
//! Invariants: the plan holds every segment for at least one resend period; it ends with a
//! stop; nothing here reads a clock.

use robot_model::time::{Duration, Instant};

use crate::motor::Drive;

/// A drive is sent again this often while it holds.
pub const RESEND: Duration = Duration::from_millis(100);

/// One step of the plan: a drive held for a time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Segment {
    /// What the motor board is told (percent of full speed).
    pub drive: Drive,
    /// How long, milliseconds.
    pub hold_ms: u64,
    /// What this segment is for (logged when it starts).
    pub what: &'static str,
}

const fn seg(vx: i8, vy: i8, omega: i8, hold_ms: u64, what: &'static str) -> Segment {
    Segment { drive: Drive { vx, vy, omega }, hold_ms, what }
}

const REST_MS: u64 = 1500;

/// The calibration drive (module docs).
pub const PLAN: [Segment; 36] = [
    seg(0, 0, 0, 12_000, "still: IMU drift and sonar noise"),
    // steps around the dead band (5 % of full speed on the default robot), 1 % apart: the
    // protocol's resolution
    seg(2, 0, 0, 800, "creep forward at 2 %"),
    seg(3, 0, 0, 800, "creep forward at 3 %"),
    seg(4, 0, 0, 800, "creep forward at 4 %"),
    seg(5, 0, 0, 800, "creep forward at 5 %"),
    seg(6, 0, 0, 800, "creep forward at 6 %"),
    seg(7, 0, 0, 800, "creep forward at 7 %"),
    seg(0, 0, 0, REST_MS, "rest: range to the wall"),
    seg(-7, 0, 0, 800, "creep back at 7 %"),
    seg(-6, 0, 0, 800, "creep back at 6 %"),
    seg(-5, 0, 0, 800, "creep back at 5 %"),
    seg(-4, 0, 0, 800, "creep back at 4 %"),
    seg(-3, 0, 0, 800, "creep back at 3 %"),
    seg(-2, 0, 0, 800, "creep back at 2 %"),
    seg(0, 0, 0, REST_MS, "rest: range to the wall"),
    // straight runs: step responses and ranges at several distances
    seg(20, 0, 0, 1000, "forward at 20 %"),
    seg(0, 0, 0, REST_MS, "rest: range to the wall"),
    seg(35, 0, 0, 600, "forward at 35 %"),
    seg(0, 0, 0, REST_MS, "rest: range to the wall"),
    seg(-35, 0, 0, 600, "back at 35 %"),
    seg(0, 0, 0, REST_MS, "rest: range to the wall"),
    seg(-20, 0, 0, 1000, "back at 20 %"),
    seg(0, 0, 0, REST_MS, "rest: range to the wall"),
    // sideways shifts
    seg(0, 25, 0, 800, "shift left at 25 %"),
    seg(0, 0, 0, REST_MS, "rest: range to the wall"),
    seg(0, -25, 0, 800, "shift right at 25 %"),
    seg(0, 0, 0, REST_MS, "rest: range to the wall"),
    // turns both ways: ranges to the wall at an angle
    seg(0, 0, 12, 500, "turn left at 12 %"),
    seg(0, 0, 0, REST_MS, "rest: range at an angle"),
    seg(0, 0, -12, 500, "turn right at 12 %"),
    seg(0, 0, 0, REST_MS, "rest: range to the wall"),
    seg(0, 0, -25, 700, "turn right at 25 %"),
    seg(0, 0, 0, REST_MS, "rest: range at an angle"),
    seg(0, 0, 25, 700, "turn left at 25 %"),
    seg(0, 0, 0, REST_MS, "rest: range to the wall"),
    seg(0, 0, 0, 10_000, "still: IMU drift"),
];

/// Where the drive is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CalibrationDrive {
    started: Instant,
    /// The segment now running, and when the last frame went out.
    segment: usize,
    last_sent: Option<Instant>,
}

impl CalibrationDrive {
    /// A drive starting at `now`.
    pub fn new(now: Instant) -> CalibrationDrive {
        CalibrationDrive { started: now, segment: 0, last_sent: None }
    }

    /// The whole plan's length.
    pub fn length() -> Duration {
        Duration::from_millis(PLAN.iter().map(|s| s.hold_ms).sum())
    }

    /// The segment running at `now` (its index), or `None` once the plan is over.
    fn segment_at(&self, now: Instant) -> Option<usize> {
        let mut end_ms = 0;
        let elapsed = now.saturating_since(self.started).total_millis();
        PLAN.iter().position(|s| {
            end_ms += s.hold_ms;
            elapsed < end_ms
        })
    }

    /// The drive to send at `now`, if one is due: at a change of segment and every [`RESEND`]; a
    /// stop once when the plan is over. Logs each segment as it starts.
    pub fn poll(&mut self, now: Instant) -> Option<Drive> {
        match self.segment_at(now) {
            Some(i) => {
                let changed = i != self.segment || self.last_sent.is_none();
                let due = self.last_sent.is_none_or(|at| now.saturating_since(at) >= RESEND);
                if changed {
                    tracing::info!(
                        segment = i + 1,
                        of = PLAN.len(),
                        what = PLAN[i].what,
                        "calibration drive"
                    );
                }
                self.segment = i;
                (changed || due).then(|| {
                    self.last_sent = Some(now);
                    PLAN[i].drive
                })
            }
            None if self.segment < PLAN.len() => {
                self.segment = PLAN.len();
                tracing::info!("calibration drive done");
                Some(Drive::STOP)
            }
            None => None,
        }
    }

    /// Whether the plan is over and its final stop has been handed out.
    pub fn is_done(&self) -> bool {
        self.segment >= PLAN.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_segment_is_sent_then_resent_and_the_drive_ends_with_one_stop() {
        let t0 = Instant::from_millis(5_000);
        let mut cal = CalibrationDrive::new(t0);
        let mut sent = Vec::new();
        let end = t0 + CalibrationDrive::length() + Duration::from_millis(500);
        let mut now = t0;
        while now <= end {
            if let Some(d) = cal.poll(now) {
                sent.push((now, d));
            }
            now += Duration::from_millis(10);
        }
        assert!(cal.is_done());
        // never a gap of a watchdog's length
        assert!(sent.windows(2).all(|w| w[1].0.saturating_since(w[0].0) <= RESEND), "gap in {sent:?}");
        // the drives sent, runs of one value merged, are the plan's, runs merged, then a stop
        let mut runs: Vec<Drive> = sent.iter().map(|s| s.1).collect();
        runs.dedup();
        let mut planned: Vec<Drive> = PLAN.iter().map(|s| s.drive).chain([Drive::STOP]).collect();
        planned.dedup();
        assert_eq!(runs, planned);
        assert_eq!(sent.last().map(|s| s.1), Some(Drive::STOP));
        assert_eq!(cal.poll(end + Duration::from_millis(100)), None, "one stop, then nothing");
        // the moves undo each other: the sums of vx, vy and omega times their holds are zero
        let sum =
            |f: fn(&Drive) -> i8| PLAN.iter().map(|s| i64::from(f(&s.drive)) * s.hold_ms as i64).sum::<i64>();
        assert_eq!(sum(|d| d.vx), 0);
        assert_eq!(sum(|d| d.vy), 0);
        assert_eq!(sum(|d| d.omega), 0);
        assert!(CalibrationDrive::length() >= Duration::from_millis(40_000));
    }
}
