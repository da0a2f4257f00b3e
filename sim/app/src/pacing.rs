//! Real-time pacing: how many fixed steps to run for the wall time that passed × a speed.
//!
//! Concept: [`Owed`] is the sim time owed to the wall clock. Each pass adds the wall time since
//! the last one times the speed, the caller runs [`Owed::steps`] whole steps of `dt` (or fewer)
//! and reports them with [`Owed::ran`]; the remainder carries to the next pass. Both real-time
//! runtimes use it: `explobot sim --serve` (`explobot::serve`) at a fixed speed, and the window
//! through [`Pacing`], which adds pause, single steps, `Max` and a stop time.
//!
//! Invariants: nothing here reads a clock (callers pass the wall time); what is owed never
//! exceeds the cap given with the wall time, so a stall (a suspended process, a too-high speed)
//! drops the backlog instead of racing through it afterwards.
//!
//! ```
//! use twin_app::pacing::Owed;
//! let mut owed = Owed::default();
//! // 16 ms of wall time at 10x is 160 ms of sim time: 32 steps of 5 ms.
//! assert_eq!(owed.add(0.016, 10.0, 0.25), 0.0);
//! assert_eq!(owed.steps(0.005), 32);
//! owed.ran(32, 0.005);
//! assert_eq!(owed.steps(0.005), 0);
//! ```

use bevy::prelude::Resource;
use robot_model::time::Instant;

/// Most sim time a paced window speed may owe after a slow frame, seconds (× the speed factor
/// above 1).
pub const MAX_OWED_S: f64 = 0.25;

/// Wall time over which [`Pacing::achieved`] is measured, seconds.
pub const ACHIEVED_WINDOW_S: f64 = 0.5;

/// Sim time owed to the wall clock, seconds.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Owed {
    seconds: f64,
}

impl Owed {
    /// Adds `wall_s × factor` of sim time, capped at `max_s`; returns the sim seconds the cap
    /// dropped (0 when none).
    pub fn add(&mut self, wall_s: f64, factor: f64, max_s: f64) -> f64 {
        let owed = self.seconds + wall_s.max(0.0) * factor;
        self.seconds = owed.min(max_s);
        (owed - self.seconds).max(0.0)
    }

    /// Whole steps of `dt_s` that are due.
    pub fn steps(&self, dt_s: f64) -> u64 {
        (self.seconds / dt_s).floor() as u64
    }

    /// Records that `done` steps of `dt_s` ran.
    pub fn ran(&mut self, done: u64, dt_s: f64) {
        self.seconds = (self.seconds - done as f64 * dt_s).max(0.0);
    }

    /// Forgets what is owed.
    pub fn clear(&mut self) {
        self.seconds = 0.0;
    }

    /// Sim seconds owed now.
    pub fn seconds(&self) -> f64 {
        self.seconds
    }
}

/// How fast the twin runs in the window.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Speed {
    /// Stopped; the Step button runs single steps.
    Paused,
    /// Sim time follows wall time.
    RealTime,
    /// Ten sim seconds per wall second.
    Times10,
    /// As many steps as fit in the window's frame budget.
    Max,
}

impl Speed {
    /// Sim seconds per wall second; `None` for paused and max.
    pub fn factor(self) -> Option<f64> {
        match self {
            Speed::RealTime => Some(1.0),
            Speed::Times10 => Some(10.0),
            Speed::Paused | Speed::Max => None,
        }
    }

    /// Button label.
    pub fn label(self) -> &'static str {
        match self {
            Speed::Paused => "Pause",
            Speed::RealTime => "1x",
            Speed::Times10 => "10x",
            Speed::Max => "Max",
        }
    }
}

/// The window's clock: speed, single steps asked for, and what was achieved.
#[derive(Resource, Debug, Clone)]
pub struct Pacing {
    /// Current speed.
    pub speed: Speed,
    /// Single steps still to run (the Step button).
    pub single_steps: u32,
    /// The runner never goes past this time (screenshots).
    pub stop_at: Option<Instant>,
    /// Sim seconds per wall second over the last [`ACHIEVED_WINDOW_S`] of running; `None` while
    /// paused and until the first measurement after a start.
    pub achieved: Option<f64>,
    /// Steps run in the last frame.
    pub last_steps: u64,
    owed: Owed,
    /// Sim and wall seconds of the measurement under way.
    measuring: (f64, f64),
}

impl Default for Pacing {
    fn default() -> Self {
        Pacing {
            speed: Speed::RealTime,
            single_steps: 0,
            stop_at: None,
            achieved: None,
            last_steps: 0,
            owed: Owed::default(),
            measuring: (0.0, 0.0),
        }
    }
}

impl Pacing {
    /// Full speed until sim time `at` (a screenshot's), then no further.
    pub fn max_until(at: Instant) -> Pacing {
        Pacing { speed: Speed::Max, stop_at: Some(at), ..Pacing::default() }
    }

    /// How many steps to run this frame for `wall_s` seconds of wall time and a step of `dt_s`
    /// (before the frame budget); updates what is owed.
    pub fn steps_for(&mut self, wall_s: f64, dt_s: f64) -> u64 {
        match self.speed {
            Speed::Paused => {
                self.owed.clear();
                u64::from(std::mem::take(&mut self.single_steps))
            }
            Speed::Max => u64::MAX,
            Speed::RealTime | Speed::Times10 => {
                let factor = self.speed.factor().unwrap_or(1.0);
                self.owed.add(wall_s, factor, MAX_OWED_S * factor.max(1.0));
                self.owed.steps(dt_s)
            }
        }
    }

    /// Records that `done` steps of `dt_s` ran in a frame of `wall_s`.
    pub fn ran(&mut self, done: u64, dt_s: f64, wall_s: f64) {
        if self.speed.factor().is_some() {
            self.owed.ran(done, dt_s);
        }
        self.last_steps = done;
        if self.speed == Speed::Paused {
            self.forget_speed();
            return;
        }
        self.measuring.0 += done as f64 * dt_s;
        self.measuring.1 += wall_s.max(0.0);
        if self.measuring.1 >= ACHIEVED_WINDOW_S {
            self.achieved = Some(self.measuring.0 / self.measuring.1);
            self.measuring = (0.0, 0.0);
        }
    }

    /// Forgets the achieved speed and what is owed (pause, restart): the next figure is a fresh
    /// measurement.
    pub fn forget_speed(&mut self) {
        self.achieved = None;
        self.measuring = (0.0, 0.0);
        self.owed.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paced_speeds_owe_wall_time_times_factor() {
        let mut p = Pacing { speed: Speed::Times10, ..Pacing::default() };
        // 16 ms at 10x = 160 ms = 32 steps of 5 ms.
        assert_eq!(p.steps_for(0.016, 0.005), 32);
        p.ran(32, 0.005, 0.016);
        assert_eq!(p.steps_for(0.0, 0.005), 0);
        p.speed = Speed::RealTime;
        assert_eq!(p.steps_for(0.016, 0.005), 3);
        p.ran(3, 0.005, 0.016);
        // The 1 ms left over carries to the next frame: 1 + 4 = 5 ms.
        assert_eq!(p.steps_for(0.004, 0.005), 1);
    }

    #[test]
    fn slow_frames_do_not_pile_up_a_backlog() {
        let mut p = Pacing { speed: Speed::RealTime, ..Pacing::default() };
        let n = p.steps_for(5.0, 0.005);
        assert_eq!(n, (MAX_OWED_S / 0.005) as u64);
    }

    #[test]
    fn paused_runs_only_requested_single_steps() {
        let mut p = Pacing { speed: Speed::Paused, single_steps: 2, ..Pacing::default() };
        assert_eq!(p.steps_for(1.0, 0.005), 2);
        assert_eq!(p.steps_for(1.0, 0.005), 0);
        p.speed = Speed::Max;
        assert_eq!(p.steps_for(0.0, 0.005), u64::MAX);
    }

    #[test]
    fn achieved_speed_is_measured_over_half_a_second_and_forgotten_when_paused() {
        let mut p = Pacing { speed: Speed::Max, ..Pacing::default() };
        p.ran(100, 0.005, 0.25);
        assert_eq!(p.achieved, None, "not measured yet");
        p.ran(300, 0.005, 0.25);
        assert_eq!(p.achieved, Some(4.0), "2 s of sim in 0.5 s of wall");
        p.speed = Speed::Paused;
        p.ran(0, 0.005, 0.25);
        assert_eq!(p.achieved, None);
    }

    #[test]
    fn the_cap_reports_what_it_dropped() {
        let mut owed = Owed::default();
        let dropped = owed.add(0.2, 1.0, 0.05);
        assert!((dropped - 0.15).abs() < 1e-12, "{dropped}");
        assert!((owed.seconds() - 0.05).abs() < 1e-12);
        assert_eq!(owed.steps(0.005), 10);
    }
}
