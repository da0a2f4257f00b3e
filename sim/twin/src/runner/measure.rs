//! What the runner measures each step for the score: Carto's belief against the truth
//! ([`crate::belief`]) and every touch with its severity ([`crate::touches`]). Observation only:
//! nothing here writes to a link or moves the body.

use robot_model::time::Instant;

use crate::touches::{NoticeCounters, StepMotion};

use super::Lockstep;

/// Belief samples are taken at least this often, sim microseconds.
const BELIEF_EVERY_US: u64 = 1_000_000;

impl Lockstep {
    /// After the physics step at `now`: follows the touches, and samples Carto's belief when a
    /// move ended (`move_ended`), Carto refused something, a whole second passed or the run is
    /// at its end (`at_end`).
    pub(super) fn measure(&mut self, now: Instant, move_ended: bool, at_end: bool) {
        let stats = self.carto.carto().stats();
        let counters = NoticeCounters {
            bumps: stats.pilot.bumps,
            pushes: stats.pilot.pushes,
            stalls: stats.pilot.stalls,
        };
        let body = self.twin.body();
        let ((vx, vy), _) = body.world().robot_velocity();
        let motion =
            StepMotion { body_velocity: (vx, vy), heading: body.pose().theta, wheel_rpm: body.wheel_rpm() };
        let world = body.world();
        let carto = self.carto.carto();
        self.touches.step(
            now.as_secs_f64(),
            self.dt.as_secs_f64(),
            (world.contacts_started(), world.contacts_ended()),
            motion,
            counters,
            || carto.activity().describe().to_string(),
        );

        let refusals = stats.pilot.obstacles + stats.pilot.turns_refused;
        let refused = refusals != self.refusals_seen;
        self.refusals_seen = refusals;
        let second = now.total_micros() / BELIEF_EVERY_US != (now - self.dt).total_micros() / BELIEF_EVERY_US;
        if (move_ended || refused || second || at_end)
            && let Some(belief) = self.carto.carto().belief(now)
        {
            self.belief.sample(
                now.as_secs_f64(),
                &self.truth.frame,
                (belief, self.carto.carto().position_covariance()),
                self.twin.body().pose(),
                move_ended,
            );
        }
    }
}
