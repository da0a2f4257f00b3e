//! The control law of [`Motor`]: the phase of a move, fresh readings, the errors it steers
//! on, and one step of the running move (see the parent module's docs).

use super::*;

impl Motor {
    /// The Active phase of `m` from `now`, heading for its goal (forwards when the remaining
    /// error is unknown yet: the Active step itself reports missing readings).
    pub(super) fn active_phase(&self, m: &Move, now: Instant, s: &SensorState) -> Phase {
        Phase::Active { since: now, sign: self.error(m, now, s, true).map_or(1.0, sign_of) }
    }

    pub(super) fn fresh_counts(&self, now: Instant, s: &SensorState) -> Result<[i32; 4], MoveError> {
        let c = s.counts().ok_or(MoveError::MissingReading { sensor: "encoder" })?;
        let age = now.saturating_since(c.at);
        if age > self.cfg.boards.sensor_stale_after {
            return Err(MoveError::StaleReading { sensor: "encoder", age_ms: age.total_millis() });
        }
        Ok(c.value)
    }

    pub(super) fn fresh_yaw(&self, now: Instant, s: &SensorState) -> Result<f64, MoveError> {
        let y = s.yaw_deg().ok_or(MoveError::MissingReading { sensor: "imu heading" })?;
        let age = now.saturating_since(y.at);
        if age > self.cfg.boards.sensor_stale_after {
            return Err(MoveError::StaleReading { sensor: "imu heading", age_ms: age.total_millis() });
        }
        Ok(y.value)
    }

    pub(super) fn hold_reference(&mut self, now: Instant, s: &SensorState) -> Result<f64, MoveError> {
        let yaw = self.fresh_yaw(now, s)?;
        let reference = match self.reference_deg {
            Some(r) if (r - yaw).abs() <= 20.0 => r,
            Some(r) => {
                tracing::info!(
                    reference = r,
                    imu = yaw,
                    "imu disagrees with the reference heading, re-learning it"
                );
                yaw
            }
            None => yaw,
        };
        self.reference_deg = Some(reference);
        self.odo.set_frame(reference);
        Ok(reference)
    }

    /// Remaining error: metres for a distance goal, degrees for a yaw goal. `predict` extrapolates
    /// to `now`; otherwise the last readings are used as they are.
    pub(super) fn error(&self, m: &Move, now: Instant, s: &SensorState, predict: bool) -> Option<f64> {
        match m.goal {
            Goal::Distance { baseline, target_m } => {
                let counts = if predict {
                    s.predicted_counts(now, &self.cfg)?
                } else {
                    s.counts()?.value.map(f64::from)
                };
                Some(target_m - mean_delta(&counts, &baseline) / self.cfg.encoder_counts_per_metre())
            }
            Goal::Yaw { target_deg } => {
                let yaw = if predict { s.predicted_yaw(now, &self.cfg)? } else { s.yaw_deg()?.value };
                Some(target_deg - yaw)
            }
        }
    }

    /// The robot's systematic overshoot after a stop, beyond the motor-lag model, learnt from the
    /// FORWARDs so far, metres (subtracted from the stop point).
    pub fn coast_bias_m(&self) -> f64 {
        self.coast_bias_m
    }

    /// Learns the stop bias from a distance move's first stop: an overshoot of `o` moves the stop
    /// point earlier by `gain × o` next time (integral action, clamped).
    pub(super) fn learn_coast(&mut self, m: &Move) {
        let (Goal::Distance { target_m, .. }, Some(err)) = (m.goal, m.first_stop_err) else {
            return;
        };
        let overshoot = -err * sign_of(target_m);
        let cfg = &self.cfg;
        self.coast_bias_m = (self.coast_bias_m + cfg.motion.coast_learn_gain * overshoot)
            .clamp(-0.5 * cfg.motion.distance_tolerance_m, 2.0 * cfg.motion.distance_tolerance_m);
    }

    /// Heading hold on `omega`, percent.
    pub(super) fn hold_omega(&self, m: &Move, now: Instant, s: &SensorState) -> f64 {
        let cfg = &self.cfg;
        match (m.hold_deg, s.predicted_yaw(now, cfg)) {
            (Some(h), Some(y)) => (cfg.motion.hold_gain_pct_per_deg * (h - y))
                .clamp(-cfg.motion.hold_max_pct, cfg.motion.hold_max_pct),
            _ => 0.0,
        }
    }

    /// Lateral speed of the body from the wheel rates, m/s left.
    pub(super) fn lateral_speed_mps(&self, now: Instant, s: &SensorState) -> f64 {
        let rates = core::array::from_fn(|i| s.wheel_rate_cps(i, now, &self.cfg));
        Odometry::body_delta(rates, &self.cfg).1
    }

    /// Readings a running move needs: encoders for a distance, the IMU for a turn or a hold.
    pub(super) fn check_fresh(&self, m: &Move, now: Instant, s: &SensorState) -> Result<(), MoveError> {
        if matches!(m.goal, Goal::Distance { .. }) {
            self.fresh_counts(now, s)?;
        }
        if !matches!(m.goal, Goal::Distance { .. }) || m.hold_deg.is_some() {
            self.fresh_yaw(now, s)?;
        }
        Ok(())
    }

    pub(super) fn step(&self, now: Instant, m: &mut Move, s: &SensorState) -> Step {
        let cfg = &self.cfg;
        let elapsed = now.saturating_since(m.started);
        if elapsed >= cfg.motion.move_timeout {
            return Step::Finished(Err(MoveError::Timeout { after_ms: elapsed.total_millis() }));
        }
        let is_distance = matches!(m.goal, Goal::Distance { .. });
        match m.phase {
            Phase::Rest { until } => {
                // Readings at rest, or, once the encoder readings have gone stale (the turn itself
                // needs only the IMU), the settle time on the clock.
                let at_rest = s.counts_since().is_some_and(|t| t >= until)
                    || (self.fresh_counts(now, s).is_err() && now >= until);
                if !at_rest {
                    return Step::Continue(Drive::STOP);
                }
                m.phase = self.active_phase(m, now, s);
                self.step(now, m, s)
            }
            Phase::Active { since, sign } => {
                // Readings must keep coming while moving.
                if let Err(e) = self.check_fresh(m, now, s) {
                    return Step::Finished(Err(e));
                }
                let Some(err) = self.error(m, now, s, true) else {
                    return Step::Finished(Err(MoveError::MissingReading { sensor: "odometry" }));
                };
                let ramp = now.saturating_since(since).as_secs_f64() * cfg.motion.accel_pct_per_s;
                if is_distance {
                    let speed = s.forward_speed_mps(now, cfg).abs();
                    let lead = (speed * cfg.motion.stop_lead_s + self.coast_bias_m)
                        .max(0.3 * cfg.motion.distance_tolerance_m);
                    if err.abs() <= lead || sign_of(err) != sign {
                        m.phase = Phase::Settling { stopped_at: now };
                        return Step::Continue(Drive::STOP);
                    }
                    let pct = (cfg.motion.slow_gain_pct_per_m * err.abs())
                        .min(cfg.motion.cruise_pct)
                        .min(cfg.motion.min_drive_pct + ramp)
                        .max(cfg.motion.min_drive_pct);
                    // Lateral hold: strafe back to the track while driving.
                    let left = self.odo.predicted(now, s, cfg).left_m - m.track_left_m;
                    let vy = (-cfg.motion.lateral_gain_pct_per_m * left)
                        .clamp(-cfg.motion.lateral_max_pct, cfg.motion.lateral_max_pct);
                    Step::Continue(Drive {
                        vx: pct_i8(sign * pct),
                        vy: pct_i8(vy),
                        omega: pct_i8(self.hold_omega(m, now, s)),
                    })
                } else {
                    let rate = s.yaw_rate_dps(now, cfg).abs();
                    let lead = (rate * cfg.motion.stop_lead_s).max(0.25 * cfg.motion.heading_tolerance_deg);
                    if err.abs() <= lead || sign_of(err) != sign {
                        m.phase = Phase::Settling { stopped_at: now };
                        return Step::Continue(Drive::STOP);
                    }
                    // Jammed: the wheels turn, the IMU says the body does not. Measured on the IMU's
                    // own samples: the prediction extrapolates with the wheels' rate, which a jam
                    // does not stop.
                    let left_now = self.error(m, now, s, false).map_or(err.abs(), f64::abs);
                    match m.progress {
                        Some((at, left)) if at >= since && left_now > left - JAM_PROGRESS_DEG => {
                            let stuck = now.saturating_since(at);
                            if stuck >= cfg.motion.jam_after {
                                return Step::Finished(Err(MoveError::Jammed {
                                    after_ms: stuck.total_millis(),
                                    left_deg: left_now,
                                }));
                            }
                        }
                        _ => m.progress = Some((now, left_now)),
                    }
                    let pct = (cfg.motion.turn_gain_pct_per_deg * err.abs())
                        .min(cfg.motion.turn_max_pct)
                        .min(cfg.motion.turn_min_pct + ramp)
                        .max(cfg.motion.turn_min_pct);
                    Step::Continue(Drive { vx: 0, vy: 0, omega: pct_i8(sign * pct) })
                }
            }
            Phase::Strafe { sign } => {
                if let Err(e) = self.check_fresh(m, now, s) {
                    return Step::Finished(Err(e));
                }
                let err = m.track_left_m - self.odo.predicted(now, s, cfg).left_m;
                let speed = self.lateral_speed_mps(now, s).abs();
                let lead = (speed * cfg.motion.stop_lead_s).max(0.3 * cfg.motion.lateral_tolerance_m);
                if err.abs() <= lead || sign_of(err) != sign {
                    m.phase = Phase::Settling { stopped_at: now };
                    return Step::Continue(Drive::STOP);
                }
                let pct = (cfg.motion.lateral_gain_pct_per_m * err.abs()).max(cfg.motion.min_strafe_pct);
                Step::Continue(Drive {
                    vx: 0,
                    vy: pct_i8(sign * pct),
                    omega: pct_i8(self.hold_omega(m, now, s)),
                })
            }
            Phase::Settling { stopped_at } => {
                let rest = stopped_at + cfg.motion.settle_time;
                let settled = if is_distance {
                    s.counts_since().is_some_and(|t| t >= rest)
                } else {
                    s.yaw_deg().is_some_and(|y| y.at >= rest)
                };
                if !settled {
                    return Step::Continue(Drive::STOP);
                }
                let Some(err) = self.error(m, now, s, false) else {
                    return Step::Finished(Err(MoveError::MissingReading { sensor: "odometry" }));
                };
                let tol = if is_distance {
                    cfg.motion.distance_tolerance_m
                } else {
                    cfg.motion.heading_tolerance_deg
                };
                // A distance move also ends on its track (the odometry has integrated the readings
                // at rest by now: `poll` updates it first).
                let left = if is_distance { self.odo.offset().left_m - m.track_left_m } else { 0.0 };
                if let Goal::Distance { target_m, .. } = m.goal
                    && m.corrections == 0
                    && m.first_stop_err.is_none()
                    && target_m.abs() >= 0.05
                {
                    m.first_stop_err = Some(err);
                }
                let on_track = left.abs() <= cfg.motion.lateral_tolerance_m;
                if err.abs() <= tol && on_track {
                    tracing::debug!(error = err, left_m = left, corrections = m.corrections, "move done");
                    return Step::Finished(Ok(()));
                }
                if m.corrections >= cfg.motion.max_corrections {
                    if err.abs() <= tol {
                        // Off the track but at the target: the next FORWARD keeps correcting.
                        tracing::warn!(left_m = left, "move ends off its track after all corrections");
                        return Step::Finished(Ok(()));
                    }
                    // Close enough where lost frames or a slow link ate the nudges. A cell move
                    // near the next centre: the robot is in the next cell, the odometry keeps the
                    // residual and the next FORWARD, which aims at a centre, absorbs it. A turn
                    // within a few degrees (each nudge's zero command landed after the robot had
                    // passed the target): the reference heading still moves by exactly 90°, and
                    // the next FORWARD's heading hold steers the rest out.
                    let close_enough = if is_distance {
                        m.advance_m != 0.0 && err.abs() <= 0.25 * m.advance_m.abs()
                    } else {
                        err.abs() <= TURN_ACCEPT_TOLERANCES * tol
                    };
                    if close_enough {
                        tracing::warn!(error = err, "move ends off its target after all corrections");
                        return Step::Finished(Ok(()));
                    }
                    return Step::Finished(Err(MoveError::NotConverged {
                        corrections: m.corrections,
                        error: err,
                    }));
                }
                m.corrections += 1;
                tracing::debug!(
                    error = err,
                    left_m = left,
                    correction = m.corrections,
                    "move outside tolerance, correcting"
                );
                m.phase = if err.abs() > tol {
                    Phase::Active { since: now, sign: sign_of(err) }
                } else {
                    Phase::Strafe { sign: sign_of(-left) }
                };
                self.step(now, m, s)
            }
        }
    }
}

/// After all corrections, a turn still more than this many heading tolerances off its target
/// has failed; closer, it counts as done (5° with the default 2° tolerance).
const TURN_ACCEPT_TOLERANCES: f64 = 2.5;

pub(super) enum Step {
    Continue(Drive),
    Finished(Result<(), MoveError>),
}

pub(super) fn sign_of(v: f64) -> f64 {
    if v < 0.0 { -1.0 } else { 1.0 }
}

pub(super) fn mean_delta(counts: &[f64; 4], baseline: &[i32; 4]) -> f64 {
    counts.iter().zip(baseline).map(|(c, b)| c - f64::from(*b)).sum::<f64>() / 4.0
}

pub(super) fn pct_i8(v: f64) -> i8 {
    v.round().clamp(-100.0, 100.0) as i8
}
