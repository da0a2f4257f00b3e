//! The watches of a running FORWARD: the stall watch (`pilot/stall.rs`), the push watch (the
//! pilot's module docs, "Pushed") and the sonar readings heard while it drives.
//!
//! Contract: [`ForwardWatch::start`] is called as each FORWARD starts, before any reading of it
//! is fed; a reading is handed out once ([`ForwardWatch::new_reading`]), paired with the
//! odometry's offset when the sonar measured, and only while the FORWARD drives at most 1½
//! cells from where it started.

use robot_model::time::Instant;

use super::Io;
use super::stall::{Stall, StallWatch};
use crate::CartoConfig;
use crate::odometry::CellOffset;
use crate::sensors::{DriftCounts, SensorState};

/// A sonar reading taken while a FORWARD drives, with the odometry's offset from the stored
/// cell's centre when the sonar measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct DriveReading {
    /// The range, cm; negative for no echo.
    pub(super) cm: f32,
    /// The odometry's offset when the sonar measured.
    pub(super) offset: CellOffset,
}

/// The watches of the FORWARD that runs.
#[derive(Debug, Clone)]
pub(super) struct ForwardWatch {
    /// The echoes of the running FORWARD (`pilot/stall.rs`); `None` when the watch is off.
    stall: Option<StallWatch>,
    /// The push watch of the FORWARD running: the drift estimate's counts when it started
    /// (module docs, "Pushed"); `None` when the watch is off.
    push: Option<DriftCounts>,
    /// [`ImuDrift::push_watch`](crate::config::ImuDrift::push_watch).
    push_on: bool,
    /// When the last reading taken while a FORWARD drove arrived.
    last_reading: Option<Instant>,
    /// The odometry's offset along the heading when the running FORWARD started, metres.
    from_m: f64,
}

impl ForwardWatch {
    /// The watches [`Safety::stall_watch`](crate::config::Safety::stall_watch) and
    /// [`ImuDrift::push_watch`](crate::config::ImuDrift::push_watch) turn on.
    pub(super) fn new(cfg: &CartoConfig) -> ForwardWatch {
        ForwardWatch {
            stall: cfg.safety.stall_watch.then(|| StallWatch::new(cfg.sonar.sigma_m, cfg.drive_timing_m())),
            push: None,
            push_on: cfg.imu.drift.as_ref().is_some_and(|drift| drift.push_watch),
            last_reading: None,
            from_m: 0.0,
        }
    }

    /// A FORWARD starts from where the odometry is now; `straight_m`, the straight reading at
    /// rest just taken from the same pose, is the stall watch's first echo.
    pub(super) fn start(&mut self, io: &Io<'_>, straight_m: Option<f64>) {
        self.from_m = io.motor.odometry().offset().along_m;
        self.push = self.push_on.then(|| io.sensors.drift_counts());
        if let Some(watch) = self.stall.as_mut() {
            watch.restart();
            // the straight reading at rest just taken is the first echo of this FORWARD
            if let Some(range_m) = straight_m {
                watch.push(0.0, range_m);
            }
        }
    }

    /// Feeds the push watch the drift estimate's counts now: the first sample after the FORWARD
    /// started becomes its baseline, and it fires when a later one jumped by more than
    /// [`crate::sensors::PUSH_JUMP_DEG`] (module docs, "Pushed"). Whether it fired.
    pub(super) fn pushed(&mut self, sensors: &SensorState) -> bool {
        let Some(start) = self.push.as_mut() else {
            return false;
        };
        let now = sensors.drift_counts();
        if now.samples <= start.samples + 1 {
            // that sample still holds what the turn before did
            start.pushes = now.pushes;
            return false;
        }
        now.pushes > start.pushes
    }

    /// The newest reading if it arrived after the FORWARD started at `since` and was not taken
    /// on an earlier poll (the straight reading at rest, taken before `since`, is not one), with
    /// the odometry carried to when the sonar measured (encoder counts arrive less often than
    /// distance frames).
    pub(super) fn new_reading(&mut self, io: &Io<'_>, since: Instant) -> Option<DriveReading> {
        let r = io.us.latest()?;
        if r.at <= since || self.last_reading.is_some_and(|t| r.at <= t) {
            return None;
        }
        self.last_reading = Some(r.at);
        let offset = io.motor.cell_offset(r.at - io.motor.config().sonar.lag, io.sensors);
        // a FORWARD drives at most 1½ cells (half a cell of slack either way): anything else is
        // a bad extrapolation, not a place to put an echo
        let cell = io.motor.config().cell_size_m;
        let driven_m = offset.along_m - self.from_m;
        if r.value >= 0.0 && !(-0.5 * cell..=2.0 * cell).contains(&driven_m) {
            return None;
        }
        Some(DriveReading { cm: r.value, offset })
    }

    /// Feeds the reading `r`, taken while a FORWARD drives, to the stall watch, paired with how
    /// far the wheels had driven when the sonar measured.
    pub(super) fn stalled(&mut self, r: DriveReading) -> Option<Stall> {
        let watch = self.stall.as_mut()?;
        if r.cm < 0.0 || !r.cm.is_finite() {
            watch.restart(); // no echo: the next may come from another surface
            return None;
        }
        let driven_m = r.offset.along_m - self.from_m;
        tracing::trace!(driven_m, range_cm = r.cm, "echo during a FORWARD");
        watch.push(driven_m, f64::from(r.cm) / 100.0)
    }

    /// How far to move the odometry along the heading, when it reads `now_m`, so that it says
    /// where the sonar put the body at the `stall`.
    pub(super) fn stall_correction_m(&self, stall: Stall, now_m: f64) -> f64 {
        self.from_m + stall.driven_m - now_m
    }
}
