//! What Carto knows from the boards: the latest IMU heading, wheel encoder counts, motor
//! telemetry and bumper state, each stamped with the time it arrived, plus the keep-state session
//! with the sensor board.
//!
//! Concept: readings arrive at a few hertz (encoders 5 Hz, NavX 10 Hz) while the controller runs
//! every millisecond, so [`SensorState`] also *extrapolates*: a wheel's count now = last count +
//! its rate × the time since (rate from fresh motor telemetry, else from its last two counts),
//! capped at [`Boards::max_extrapolation`](crate::config::Boards::max_extrapolation). The same for the heading.
//!
//! Invariants:
//! - the heading is kept as an *unwrapped* counter-clockwise yaw in degrees (the NavX reports
//!   0–360 clockwise; each new sample adds the shortest signed difference), so targets never wrap;
//! - wheels are indexed FL, FR, RL, RR (sensor ids 1–4); a count grows when the wheel rolls
//!   forward.
//!
//! ```
//! use carto::sensors::{SensorEvent, SensorState};
//! use carto::CartoConfig;
//! use robot_model::time::Instant;
//! let cfg = CartoConfig::default();
//! let mut s = SensorState::default();
//! s.ingest(Instant::from_millis(0), SensorEvent::Heading { cw_deg: 350.0 });
//! s.ingest(Instant::from_millis(100), SensorEvent::Heading { cw_deg: 10.0 });
//! // 350° → 10° is 20° clockwise, i.e. −20° counter-clockwise (not +340°): −350° → −370°
//! assert_eq!(s.yaw_deg().unwrap().value, -370.0);
//! // the yaw rate from the last two samples is −200°/s; 50 ms later the prediction is −380°
//! assert!((s.predicted_yaw(Instant::from_millis(150), &cfg).unwrap() + 380.0).abs() < 1e-9);
//! ```

use robot_model::time::{Duration, Instant};

use crate::CartoConfig;

mod keep_state;
mod line;

pub use keep_state::{KeepState, PeerEvent};
pub use line::LineTimer;

/// The heading four wheel counts give, degrees counter-clockwise from where the counts were zero:
/// mecanum forward kinematics, (−FL + FR − RL + RR) / (4 · lever).
fn wheel_yaw_of([fl, fr, rl, rr]: [f64; 4], cfg: &CartoConfig) -> f64 {
    ((-fl + fr - rl + rr) / 4.0 / cfg.encoder_counts_per_metre() / cfg.rotation_lever_m()).to_degrees()
}

/// A gap between the IMU's and the wheels' headings this much larger than the drift estimate
/// explains is slip (a collision turned the body under slipping wheels, or the counters were
/// reset), not drift: the estimate is re-anchored instead of following it, degrees.
pub const DRIFT_JUMP_DEG: f64 = 2.0;

/// After such a jump the gap is taken as slip for this long more (the push that turned the body
/// may go on), so the part of it below [`DRIFT_JUMP_DEG`] does not become drift either.
pub const SLIP_HOLD: Duration = Duration::from_millis(2000);

/// A jump of the gap between the IMU's and the wheels' headings larger than this, beyond the
/// drift estimate, is a push: something the body touches turned it under its wheels, degrees.
/// A FORWARD that sees one stops ([`ImuDrift::push_watch`](crate::config::ImuDrift::push_watch), `pilot.rs`, "Pushed").
///
/// A jump is what [`SensorState::estimate_imu_drift`] calls one: one of its samples (the IMU
/// reports at 10 Hz; no sample is taken in a turn, nor while either heading turns faster than
/// 3°/s) whose gap lies more than [`DRIFT_JUMP_DEG`] beyond the estimate, not within
/// [`SLIP_HOLD`] of an earlier jump. So a push is missed when the gap grows past 2° before it
/// passes 3° (a slow push), within 2 s of an earlier jump, or on the one sample the watch
/// excuses; and an encoder or telemetry frame damaged past its checksum can open a gap without
/// any touch (the FORWARD then stops and reports a free cell blocked). The threshold is above
/// [`DRIFT_JUMP_DEG`]: over a motor link that loses frames a FORWARD that touches nothing can
/// open a gap of nearly 3°.
pub const PUSH_JUMP_DEG: f64 = 3.0;

/// After a slip the new anchor is the mean of this many samples taken once the hold is over,
/// not the last sample of the hold: one IMU sample carries its 0.2° noise and the wheels' heading
/// its encoder timing (spikes of up to 1.5°), and anchored on one sample the drift estimate
/// loses a little at every slip, never to get it back.
pub const SLIP_SETTLE_SAMPLES: usize = 20;

/// A value and the time it arrived.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stamped<T> {
    /// The value.
    pub value: T,
    /// When it arrived.
    pub at: Instant,
}

/// One decoded message from the sensor or motor board, in Carto's terms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SensorEvent {
    /// Keep-state from the sensor board.
    KeepState {
        /// Status byte (the board sends 1).
        status: u8,
        /// Sequence number.
        sequence: u16,
    },
    /// NavX fused heading, degrees clockwise, 0–360.
    Heading {
        /// Degrees, clockwise.
        cw_deg: f64,
    },
    /// A wheel encoder count.
    Encoder {
        /// 0 = FL, 1 = FR, 2 = RL, 3 = RR.
        wheel: usize,
        /// Cumulative count, growing forward.
        count: i32,
    },
    /// The front distance sensor, cm; negative = no echo.
    Distance {
        /// Centimetres.
        cm: f32,
    },
    /// The front bumper.
    Bumper {
        /// Whether it is pressed.
        pressed: bool,
    },
    /// Motor board telemetry: wheel speeds in rpm, FL, FR, RL, RR.
    WheelRpm {
        /// Rpm per wheel, positive forward.
        rpm: [f32; 4],
    },
    /// A reading whose sensor reported an error status, or a sensor Carto does not use.
    Ignored,
}

/// The latest readings of every sensor Carto uses, with extrapolation.
#[derive(Debug, Clone, Default)]
pub struct SensorState {
    yaw: Option<Stamped<f64>>,
    prev_yaw: Option<Stamped<f64>>,
    last_cw: f64,
    encoders: [Option<Stamped<i32>>; 4],
    prev_encoders: [Option<Stamped<i32>>; 4],
    rpm: Option<Stamped<[f32; 4]>>,
    bumper: Option<Stamped<bool>>,
    drift: DriftEstimate,
    smooth: Option<SmoothYaw>,
}

/// The IMU's yaw smoothed with the wheels' heading (see [`SensorState::smooth_yaw`]).
#[derive(Debug, Clone, Copy, PartialEq)]
struct SmoothYaw {
    /// Smoothed yaw, degrees, drift not removed.
    value: f64,
    /// Time of the IMU sample it includes last.
    at: Instant,
    /// The wheels' heading at that sample, degrees.
    wheel_deg: f64,
}

/// The IMU's slow heading drift, estimated against the wheel odometry's heading.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct DriftEstimate {
    /// (IMU yaw − wheel yaw) when the estimate was anchored, degrees.
    anchor: Option<f64>,
    /// Estimated drift of the IMU since the anchor, degrees (subtracted from its readings).
    drift_deg: f64,
    /// Time of the IMU sample last used.
    last: Option<Instant>,
    /// Until then the gap is slip (a push goes on after it was first seen): every sample
    /// re-anchors.
    slipping_until: Option<Instant>,
    /// Jumps taken for slip so far.
    jumps: u64,
    /// Of those, jumps larger than [`PUSH_JUMP_DEG`].
    pushes: u64,
    /// Samples taken so far.
    samples: u64,
    /// After a slip, the (IMU − wheel − drift) of the samples since the hold ended; the anchor
    /// is their mean once there are [`SLIP_SETTLE_SAMPLES`]. `None`: not settling.
    settling: Option<Settling>,
}

/// Counts of the drift estimate's samples, for the push watch of a FORWARD
/// ([`SensorState::drift_counts`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DriftCounts {
    /// Samples taken.
    pub samples: u64,
    /// Of those, jumps larger than [`PUSH_JUMP_DEG`].
    pub pushes: u64,
}

/// The samples gathered for a new anchor after a slip (see [`SLIP_SETTLE_SAMPLES`]): their sum
/// and how many.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Settling {
    sum: f64,
    n: usize,
}

impl SensorState {
    /// Records one event received at `now`. Distance and keep-state are handled elsewhere.
    pub fn ingest(&mut self, now: Instant, event: SensorEvent) {
        match event {
            SensorEvent::Heading { cw_deg } if cw_deg.is_finite() => {
                let yaw = match self.yaw {
                    None => -cw_deg,
                    Some(prev) => prev.value - wrap180(cw_deg - self.last_cw),
                };
                self.last_cw = cw_deg;
                self.prev_yaw = self.yaw;
                self.yaw = Some(Stamped { value: yaw, at: now });
            }
            SensorEvent::Encoder { wheel, count } if wheel < 4 => {
                self.prev_encoders[wheel] = self.encoders[wheel];
                self.encoders[wheel] = Some(Stamped { value: count, at: now });
            }
            SensorEvent::WheelRpm { rpm } if rpm.iter().all(|r| r.is_finite()) => {
                self.rpm = Some(Stamped { value: rpm, at: now });
            }
            SensorEvent::Bumper { pressed } => self.bumper = Some(Stamped { value: pressed, at: now }),
            _ => {}
        }
    }

    /// The last heading as an unwrapped counter-clockwise yaw, degrees, smoothed with the wheels'
    /// heading ([`SensorState::smooth_yaw`]) and with the estimated IMU drift removed (see
    /// [`SensorState::estimate_imu_drift`]).
    pub fn yaw_deg(&self) -> Option<Stamped<f64>> {
        let y = self.yaw?;
        let value = match self.smooth {
            Some(smooth) if smooth.at == y.at => smooth.value,
            _ => y.value,
        };
        Some(Stamped { value: value - self.drift.drift_deg, at: y.at })
    }

    /// Smooths the newest IMU sample with the wheels' heading (call every poll; `turning`: the
    /// controller drives a turn or a look). [`SensorState::yaw_deg`] then gives the smoothed yaw.
    ///
    /// A complementary filter: the change of the wheels' heading since the last sample predicts
    /// the yaw, and the IMU pulls the prediction with time constant
    /// [`ImuSmoothing::tau_s`](crate::config::ImuSmoothing::tau_s) (no smoothing: `None`). The wheels' heading is smooth but slips;
    /// the IMU's does not slip but carries white noise (the profile's 0.2°). Without smoothing
    /// that noise drives the heading hold, the wheels' heading wanders with it, and the drift
    /// estimate, which follows the wheels, takes that for drift (measured:
    /// `docs/journal/real-rooms.md`). The filter restarts from the raw IMU while
    /// `turning` (a turn or a look runs, or ended less than [`crate::motor::SETTLE_AFTER_TURN`]
    /// ago: the wheels slip most then) and when the IMU disagrees with the prediction by
    /// more than [`ImuSmoothing::reset_deg`](crate::config::ImuSmoothing::reset_deg) (a slip, a collision).
    pub fn smooth_yaw(&mut self, cfg: &CartoConfig, turning: bool) {
        let Some(smoothing) = cfg.imu.smoothing.as_ref().filter(|s| s.tau_s > 0.0) else {
            self.smooth = None;
            return;
        };
        if let (Some(last), Some(y)) = (self.smooth, self.yaw)
            && last.at == y.at
        {
            return; // no new IMU sample since the last poll
        }
        let (Some(y), Some(wheel_deg)) = (self.yaw, self.wheel_yaw_deg(cfg)) else {
            self.smooth = None;
            return;
        };
        let restart = SmoothYaw { value: y.value, at: y.at, wheel_deg };
        self.smooth = match self.smooth {
            Some(last) if !turning && y.at > last.at => {
                let predicted = last.value + (wheel_deg - last.wheel_deg);
                let innovation = y.value - predicted;
                if innovation.abs() > smoothing.reset_deg {
                    Some(restart)
                } else {
                    let k = ((y.at - last.at).as_secs_f64() / smoothing.tau_s).min(1.0);
                    Some(SmoothYaw { value: predicted + k * innovation, at: y.at, wheel_deg })
                }
            }
            _ => Some(restart),
        };
    }

    /// How often the gap between the IMU's and the wheels' headings jumped (slip, not drift) and
    /// re-anchored the drift estimate.
    pub fn imu_drift_jumps(&self) -> u64 {
        self.drift.jumps
    }

    /// How many samples the drift estimate has taken, and how many of them jumped by more than
    /// [`PUSH_JUMP_DEG`] (see [`Self::estimate_imu_drift`]).
    pub fn drift_counts(&self) -> DriftCounts {
        DriftCounts { samples: self.drift.samples, pushes: self.drift.pushes }
    }

    /// The IMU drift currently removed from its readings, degrees counter-clockwise.
    pub fn imu_drift_deg(&self) -> f64 {
        self.drift.drift_deg
    }

    /// The heading the wheels alone give, degrees counter-clockwise from where the counts were
    /// zero: mecanum forward kinematics, (−FL + FR − RL + RR) / (4 · lever). `None` until all four
    /// wheels reported.
    pub fn wheel_yaw_deg(&self, cfg: &CartoConfig) -> Option<f64> {
        Some(wheel_yaw_of(self.counts()?.value.map(f64::from), cfg))
    }

    /// Every wheel's count moved to time `at` (before or after its sample) at its rate as of
    /// `now`, at most [`Boards::max_extrapolation`](crate::config::Boards::max_extrapolation) either way; `None` until all four
    /// reported.
    fn counts_at(&self, at: Instant, now: Instant, cfg: &CartoConfig) -> Option<[f64; 4]> {
        let mut out = [0.0; 4];
        let max = cfg.boards.max_extrapolation.as_secs_f64();
        for (i, e) in self.encoders.iter().enumerate() {
            let e = (*e)?;
            let dt = if at >= e.at { (at - e.at).as_secs_f64() } else { -(e.at - at).as_secs_f64() };
            out[i] = f64::from(e.value) + self.wheel_rate_cps(i, now, cfg) * dt.clamp(-max, max);
        }
        Some(out)
    }

    /// Updates the IMU drift estimate (call every poll; a no-op unless a new IMU sample arrived).
    ///
    /// The difference between the IMU heading and the wheels' heading is constant while neither
    /// drifts nor slips; its slow change is taken to be IMU drift (a NavX drifts about 0.5°/min).
    /// It is sampled only while the robot is not turning (both rates under 3°/s), low-pass filtered
    /// with [`ImuDrift::tau_s`](crate::config::ImuDrift::tau_s), and the estimate moves at most
    /// [`ImuDrift::max_deg_per_min`](crate::config::ImuDrift::max_deg_per_min), so wheel slip (a collision, a turn) can only
    /// pull it slowly. A gap more than [`DRIFT_JUMP_DEG`] beyond the estimate is slip, not drift: a
    /// collision turned the body under slipping wheels, or the counters were reset. It re-anchors
    /// the estimate, and so does every sample for [`SLIP_HOLD`] after it (the push may go on); then
    /// the anchor is set from the mean of the next [`SLIP_SETTLE_SAMPLES`] samples, and the
    /// estimate follows the gap again only after that. The wheels' heading is taken at the IMU
    /// sample's time (each encoder's count moved along at its rate), so encoders that report at
    /// different moments open no gap while driving. No sample is taken while `turning` (the
    /// controller drives a turn or a look, or one ended less than
    /// [`crate::motor::SETTLE_AFTER_TURN`] ago): the rates alone let the ends of a turn through,
    /// where the IMU's noise decides which samples pass and the estimate was pulled off by a few
    /// tenths of a degree.
    pub fn estimate_imu_drift(&mut self, now: Instant, cfg: &CartoConfig, turning: bool) {
        let Some(drift) = cfg.imu.drift.as_ref().filter(|d| d.tau_s > 0.0) else { return };
        if turning {
            return;
        }
        // The wheels' heading at the IMU sample's time: the four encoders report at different
        // moments, and the raw counts of a robot driving at 0.36 m/s differ by a few centimetres
        // between wheels, a few degrees of false heading.
        let Some(y) = self.yaw else {
            return;
        };
        let Some(wheel) = self.counts_at(y.at, now, cfg).map(|c| wheel_yaw_of(c, cfg)) else {
            return;
        };
        if self.drift.last.is_some_and(|t| y.at <= t) {
            return;
        }
        let imu_rate = match self.prev_yaw {
            Some(a) if y.at > a.at => (y.value - a.value) / (y.at - a.at).as_secs_f64(),
            _ => 0.0,
        };
        let wheel_rate = wheel_yaw_of(core::array::from_fn(|i| self.wheel_rate_cps(i, now, cfg)), cfg);
        if imu_rate.abs() > 3.0 || wheel_rate.abs() > 3.0 {
            return;
        }
        let diff = y.value - wheel;
        let dt = self.drift.last.map_or(0.0, |t| (y.at - t).as_secs_f64().min(1.0));
        self.drift.last = Some(y.at);
        self.drift.samples += 1;
        let Some(anchor) = self.drift.anchor else {
            self.drift.anchor = Some(diff - self.drift.drift_deg);
            return;
        };
        let seen = diff - anchor;
        let slipping = self.drift.slipping_until.is_some_and(|until| y.at < until);
        let jump = (seen - self.drift.drift_deg).abs();
        if slipping || jump > DRIFT_JUMP_DEG {
            if !slipping {
                self.drift.jumps += 1;
                if jump > PUSH_JUMP_DEG {
                    self.drift.pushes += 1;
                }
                tracing::warn!(seen, "imu and wheel headings jumped apart: drift estimate re-anchored");
                self.drift.slipping_until = Some(y.at + SLIP_HOLD);
            }
            self.drift.anchor = Some(diff - self.drift.drift_deg);
            self.drift.settling = Some(Settling { sum: 0.0, n: 0 });
            return;
        }
        if let Some(settling) = self.drift.settling.as_mut() {
            settling.sum += diff - self.drift.drift_deg;
            settling.n += 1;
            if settling.n == SLIP_SETTLE_SAMPLES {
                // the mean, not the median: the estimate then follows the mean gap, and a
                // median differing from it (the wheels' timing spikes are one-sided) would
                // move the estimate by that difference at every slip
                self.drift.anchor = Some(settling.sum / SLIP_SETTLE_SAMPLES as f64);
                self.drift.settling = None;
            }
            return;
        }
        let max_step = drift.max_deg_per_min / 60.0 * dt;
        let step = ((seen - self.drift.drift_deg) * dt / drift.tau_s).clamp(-max_step, max_step);
        self.drift.drift_deg += step;
    }

    /// The last count of every wheel, with the time of the oldest of them; `None` until all four
    /// wheels have reported.
    pub fn counts(&self) -> Option<Stamped<[i32; 4]>> {
        let mut out = [0; 4];
        let mut oldest: Option<Instant> = None;
        for (i, e) in self.encoders.iter().enumerate() {
            let e = (*e)?;
            out[i] = e.value;
            oldest = Some(oldest.map_or(e.at, |o| o.min(e.at)));
        }
        Some(Stamped { value: out, at: oldest? })
    }

    /// The earliest arrival time among the last samples of all four wheels.
    pub fn counts_since(&self) -> Option<Instant> {
        self.counts().map(|c| c.at)
    }

    /// Whether the bumper's latest report, received at or after `since`, says pressed.
    pub fn bumper_pressed_since(&self, since: Instant) -> bool {
        matches!(self.bumper, Some(b) if b.value && b.at >= since)
    }

    /// Whether the bumper's latest report says pressed.
    pub fn bumper_pressed(&self) -> bool {
        matches!(self.bumper, Some(b) if b.value)
    }

    /// The latest telemetry's wheel speeds, if recent and possible: a wheel at more than twice
    /// the motors' top speed is a corrupted frame that passed the motor link's one-byte checksum
    /// (two bytes changed in one frame: about one frame in 5,000 at `lossy-motor`'s 1 % byte
    /// errors), and extrapolating with it would throw the odometry metres away.
    fn fresh_rpm(&self, now: Instant, cfg: &CartoConfig) -> Option<[f32; 4]> {
        let possible = 2.0 * cfg.chassis.max_wheel_rpm;
        self.rpm
            .filter(|r| now.saturating_since(r.at) <= cfg.boards.telemetry_fresh)
            .filter(|r| r.value.iter().all(|v| f64::from(v.abs()) <= possible))
            .map(|r| r.value)
    }

    /// Rate of a wheel's count, counts per second: from fresh telemetry, else from its last two
    /// encoder samples, else zero.
    pub fn wheel_rate_cps(&self, wheel: usize, now: Instant, cfg: &CartoConfig) -> f64 {
        if let Some(rpm) = self.fresh_rpm(now, cfg) {
            return f64::from(rpm[wheel.min(3)]) * cfg.chassis.encoder_counts_per_wheel_rev / 60.0;
        }
        match (self.prev_encoders.get(wheel).copied().flatten(), self.encoders.get(wheel).copied().flatten())
        {
            (Some(a), Some(b)) if b.at > a.at && b.at - a.at <= Duration::from_millis(1000) => {
                f64::from(b.value.wrapping_sub(a.value)) / (b.at - a.at).as_secs_f64()
            }
            _ => 0.0,
        }
    }

    /// Every wheel's count extrapolated to `now`, as floats; `None` until all four reported.
    pub fn predicted_counts(&self, now: Instant, cfg: &CartoConfig) -> Option<[f64; 4]> {
        self.counts_at(now, now, cfg)
    }

    /// Mean forward speed of the four wheels, m/s (signed).
    pub fn forward_speed_mps(&self, now: Instant, cfg: &CartoConfig) -> f64 {
        let sum: f64 = (0..4).map(|i| self.wheel_rate_cps(i, now, cfg)).sum();
        sum / 4.0 / cfg.encoder_counts_per_metre()
    }

    /// Yaw rate, degrees per second counter-clockwise: from fresh telemetry (mecanum inverse
    /// kinematics), else from the last two NavX samples, else zero.
    pub fn yaw_rate_dps(&self, now: Instant, cfg: &CartoConfig) -> f64 {
        if let Some(rpm) = self.fresh_rpm(now, cfg) {
            let [fl, fr, rl, rr] = rpm.map(f64::from);
            let rim =
                (-fl + fr - rl + rr) / 4.0 / 60.0 * 2.0 * core::f64::consts::PI * cfg.chassis.wheel_radius_m;
            return (rim / cfg.rotation_lever_m()).to_degrees();
        }
        match (self.prev_yaw, self.yaw) {
            (Some(a), Some(b)) if b.at > a.at && b.at - a.at <= Duration::from_millis(1000) => {
                (b.value - a.value) / (b.at - a.at).as_secs_f64()
            }
            _ => 0.0,
        }
    }

    /// The yaw extrapolated to `now`, degrees counter-clockwise (unwrapped).
    pub fn predicted_yaw(&self, now: Instant, cfg: &CartoConfig) -> Option<f64> {
        let y = self.yaw_deg()?;
        let dt = now.saturating_since(y.at).min(cfg.boards.max_extrapolation).as_secs_f64();
        Some(y.value + self.yaw_rate_dps(now, cfg) * dt)
    }

    /// Forgets every reading (used when the sensor board is lost). The IMU drift estimate is
    /// kept and re-anchored on the next readings.
    pub fn clear(&mut self) {
        let drift = DriftEstimate { anchor: None, last: None, ..self.drift };
        *self = SensorState { drift, ..SensorState::default() };
    }
}

/// Wraps an angle in degrees into (−180, 180].
pub fn wrap180(deg: f64) -> f64 {
    let mut a = deg % 360.0;
    if a > 180.0 {
        a -= 360.0;
    } else if a <= -180.0 {
        a += 360.0;
    }
    a
}

#[cfg(test)]
mod tests;
