//! Calibration: how far the twin is from a robot, measured on a recording of the robot's own
//! calibration drive (`carto --calibration-drive --record FILE`), and a profile fitted to it.
//!
//! Concept: [`Recorded::from_recording`] takes from Carto's side of a recording the bytes Carto
//! wrote to both boards, with their times, and what the boards answered: the motor board's wheel
//! speeds, the IMU's heading and the sonar's ranges. [`open_loop`] plays the written bytes into
//! the twin's boards at the same times with the twin's own noise off, so the twin answers what
//! its model predicts; [`Predicted::lagged`] sets the link's round trip (a fitted nuisance
//! value) by which the recorded answers trail the commands.
//! [`Gap::measure`] compares the two streams (`explobot replay REC --compare`);
//! [`fit::fit`] moves the profile's physical values until they agree (`explobot calibrate`).
//!
//! The streams compared, and why:
//! - **wheel speeds** (motor telemetry, 20 Hz, every moment): the motors' time constant and dead
//!   band; they do not depend on the floor.
//! - **heading** (IMU, 10 Hz, every moment, less its value at the start): the wheel radius
//!   through the turns, the IMU's drift through the still periods.
//! - **range at rest** (sonar, 10 Hz, only when the recorded wheels have stood still for
//!   [`REST_S`]): the wheel radius through the straight runs towards the wall; their spread, the
//!   sonar's noise. Ranges in motion are left out: the sonar measures on its own 60 ms cycle, so
//!   a range in motion says as much about the cycle's phase as about the robot.
//!
//! Invariants: nothing here reads a clock; a recording that lacks a stream is a clear
//! [`CalibrateError`], never a panic.

pub mod fit;

use protocol::motor::{Decoder as MotorDecoder, MotorPacket};
use protocol::sensor::Decoder as SensorDecoder;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use robot_model::profile::RobotProfile;
use robot_model::time::{Duration, Instant};
use transport::recording::{Dir, Recording};

use crate::hardware::{Twin, WriteBudget};
use crate::scenario::Scenario;
use crate::setup::RunSetup;

/// The recorded wheels count as standing still after this long below [`STILL_RPM`], seconds.
pub const REST_S: f64 = 0.4;
/// A wheel turning slower than this stands still, rpm.
pub const STILL_RPM: f64 = 0.5;
/// The first this many seconds set the heading's offset (the IMU reads from an arbitrary zero).
pub const HEADING_ZERO_S: f64 = 2.0;

/// A recording that cannot be calibrated against.
#[derive(Debug, thiserror::Error)]
pub enum CalibrateError {
    /// A stream the fit needs is missing.
    #[error(
        "the recording has no {0}: record the calibration drive with `carto --calibration-drive --record FILE`"
    )]
    Missing(&'static str),
    /// The room or the profile does not load.
    #[error(transparent)]
    Scenario(#[from] crate::scenario::ScenarioError),
    /// The optimiser failed.
    #[error("the fit failed: {0}")]
    Fit(String),
}

/// Bytes Carto wrote to a board.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Written {
    pub(crate) at_s: f64,
    pub(crate) to_motor: bool,
    pub(crate) bytes: Vec<u8>,
}

/// What a recording holds for calibration: Carto's writes and the boards' answers.
#[derive(Debug, Clone, PartialEq)]
pub struct Recorded {
    pub(crate) writes: Vec<Written>,
    /// Wheel speeds, rpm, FL FR RL RR, at Carto's time of reading, seconds.
    pub rpm: Vec<(f64, [f64; 4])>,
    /// IMU heading, degrees clockwise, unwrapped.
    pub heading: Vec<(f64, f64)>,
    /// Sonar ranges, cm (`None`: no echo).
    pub range: Vec<(f64, Option<f64>)>,
    /// The last byte's time, seconds.
    pub end_s: f64,
}

impl Recorded {
    /// Carto's side of `rec` (endpoint `carto` of the `motor` and `sensor` links).
    pub fn from_recording(rec: &Recording) -> Result<Recorded, CalibrateError> {
        let log = |link: &str| rec.logs.iter().find(|l| l.link == link && l.endpoint == "carto");
        let motor = log("motor").ok_or(CalibrateError::Missing("motor link"))?;
        let sensor = log("sensor").ok_or(CalibrateError::Missing("sensor link"))?;
        let mut out = Recorded {
            writes: Vec::new(),
            rpm: Vec::new(),
            heading: Vec::new(),
            range: Vec::new(),
            end_s: 0.0,
        };
        let mut motor_in = MotorDecoder::default();
        for c in &motor.chunks {
            let at_s = c.at.as_secs_f64();
            out.end_s = out.end_s.max(at_s);
            match c.direction {
                Dir::Written => out.writes.push(Written { at_s, to_motor: true, bytes: c.bytes.clone() }),
                Dir::Read => {
                    for p in motor_in.feed(&c.bytes).into_iter().flatten() {
                        if let MotorPacket::Telemetry(t) = p {
                            out.rpm.push((at_s, t.wheel_rpm.map(f64::from)));
                        }
                    }
                }
            }
        }
        let mut sensor_in = SensorDecoder::new();
        let mut last_heading: Option<f64> = None;
        for c in &sensor.chunks {
            let at_s = c.at.as_secs_f64();
            out.end_s = out.end_s.max(at_s);
            match c.direction {
                Dir::Written => out.writes.push(Written { at_s, to_motor: false, bytes: c.bytes.clone() }),
                Dir::Read => {
                    for p in sensor_in.feed(&c.bytes).into_iter().flatten() {
                        match carto::wire::sensor_event(&p) {
                            carto::sensors::SensorEvent::Heading { cw_deg } => {
                                let h = unwrap_deg(last_heading, cw_deg);
                                last_heading = Some(h);
                                out.heading.push((at_s, h));
                            }
                            carto::sensors::SensorEvent::Distance { cm } if cm.is_finite() => {
                                out.range.push((at_s, (cm >= 0.0).then_some(f64::from(cm))));
                            }
                            _ => {}
                        }
                    }
                }
            }
        }
        out.writes.sort_by(|a, b| a.at_s.total_cmp(&b.at_s));
        if out.rpm.is_empty() {
            return Err(CalibrateError::Missing("motor telemetry"));
        }
        if out.heading.is_empty() {
            return Err(CalibrateError::Missing("IMU heading"));
        }
        if out.range.is_empty() {
            return Err(CalibrateError::Missing("sonar range"));
        }
        if !out.writes.iter().any(|w| w.to_motor) {
            return Err(CalibrateError::Missing("drive command"));
        }
        Ok(out)
    }

    /// Whether the recorded wheels stood still over the [`REST_S`] before `t`.
    pub fn at_rest(&self, t: f64) -> bool {
        let from = self.rpm.partition_point(|s| s.0 < t - REST_S);
        let to = self.rpm.partition_point(|s| s.0 <= t);
        to > from
            && to - from >= 4
            && self.rpm[from..to].iter().all(|(_, r)| r.iter().all(|v| v.abs() < STILL_RPM))
    }
}

/// `cw_deg` in [0, 360) unwrapped to the turn nearest `last`.
fn unwrap_deg(last: Option<f64>, cw_deg: f64) -> f64 {
    match last {
        None => cw_deg,
        Some(l) => l + (cw_deg - l + 180.0).rem_euclid(360.0) - 180.0,
    }
}

/// The twin's answers to the recorded commands, one sample per physics step, as Carto would
/// have received them `lag_s` (the link's round trip) after the commands.
///
/// The round trip is applied to the answers, not to the commands: for the twin, which does not
/// change with time, the two are the same, but a command reaches the twin's boards only at a
/// step, so delaying the commands would move the answers by whole steps and leave the fit's
/// cost flat between two (a simplex stalls there: time constants 7–10 % short through the
/// real-time link). Delayed answers are read between steps, so the cost is smooth in it.
#[derive(Debug, Clone)]
pub struct Predicted {
    dt_s: f64,
    lag_s: f64,
    rpm: Vec<[f64; 4]>,
    heading: Vec<f64>,
    range: Vec<Option<f64>>,
}

impl Predicted {
    /// The same answers received `lag_s` after the commands.
    pub fn lagged(self, lag_s: f64) -> Predicted {
        Predicted { lag_s: lag_s.max(0.0), ..self }
    }

    /// The fractional step of what Carto received at `t`: the boards answer at a step's start,
    /// before it moves, so they report the state after the step before.
    fn step(&self, t: f64) -> f64 {
        ((t - self.lag_s) / self.dt_s - 1.0).max(0.0)
    }

    /// The step at or before `t` and the fraction to the next (linear interpolation).
    fn between(&self, t: f64) -> (usize, f64) {
        let x = self.step(t);
        let i = (x.floor() as usize).min(self.rpm.len().saturating_sub(2));
        (i, (x - i as f64).clamp(0.0, 1.0))
    }

    /// Wheel speeds at `t`, rpm (linear between steps).
    pub fn rpm_at(&self, t: f64) -> [f64; 4] {
        let (i, f) = self.between(t);
        std::array::from_fn(|w| self.rpm[i][w] * (1.0 - f) + self.rpm[i + 1][w] * f)
    }

    /// Heading at `t`, degrees clockwise, unwrapped (linear between steps).
    pub fn heading_at(&self, t: f64) -> f64 {
        let (i, f) = self.between(t);
        self.heading[i] * (1.0 - f) + self.heading[i + 1] * f
    }

    /// The latest sonar result at `t`, cm (the nearest step: the sonar reports whole results).
    pub fn range_at(&self, t: f64) -> Option<f64> {
        self.range[(self.step(t).round() as usize).min(self.range.len().saturating_sub(1))]
    }
}

#[derive(Debug, thiserror::Error)]
#[error("never fails")]
struct Never;

impl transport::LinkError for Never {
    fn kind(&self) -> transport::ErrorKind {
        transport::ErrorKind::Io(std::io::ErrorKind::Other)
    }
}

/// `profile` with the noise of its sensors off: what the model predicts.
pub fn noiseless(profile: &RobotProfile) -> RobotProfile {
    let mut p = profile.clone();
    p.sonar.noise_sigma_cm = 0.0;
    p.imu.noise_sigma_deg = 0.0;
    p
}

/// Plays the recorded writes into a twin of `profile` standing at `room`'s start, at their
/// recorded times, until the recording ends (round trip 0: see [`Predicted::lagged`]).
pub fn open_loop(
    room: &Scenario,
    profile: &RobotProfile,
    rec: &Recorded,
) -> Result<Predicted, CalibrateError> {
    let setup = RunSetup::with_profile(room.clone(), noiseless(profile), "", "<calibration room>")?;
    let dt = setup.dt();
    let dt_s = dt.as_secs_f64();
    let mut twin = Twin::new(&setup, room.seed, dt);
    let (mut motor, mut sensor) = (Capture::default(), Capture::default());
    let mut rng = ChaCha8Rng::seed_from_u64(room.seed);
    let steps = ((rec.end_s + 0.5) / dt_s).ceil() as usize;
    let mut out = Predicted {
        dt_s,
        lag_s: 0.0,
        rpm: Vec::with_capacity(steps + 1),
        heading: Vec::with_capacity(steps + 1),
        range: Vec::with_capacity(steps + 1),
    };
    let mut next = 0;
    let mut last_heading = None;
    for k in 0..=steps {
        let now = Instant::ZERO + Duration::from_micros(dt.total_micros() * k as u64);
        let t = now.as_secs_f64();
        while let Some(w) = rec.writes.get(next) {
            if w.at_s > t {
                break;
            }
            if w.to_motor { &mut motor } else { &mut sensor }.rx.extend_from_slice(&w.bytes);
            next += 1;
        }
        twin.board_io(now, &mut motor, &mut sensor, WriteBudget::UNLIMITED);
        // the boards' answers are not needed: the twin's state is read instead
        motor.tx.clear();
        sensor.tx.clear();
        twin.physics_step(now);
        let body = twin.body();
        out.rpm.push(body.wheel_rpm().map(f64::from));
        let h = unwrap_deg(last_heading, f64::from(body.imu_heading(now, &mut rng)));
        last_heading = Some(h);
        out.heading.push(h);
        out.range.push(body.sonar_cm().map(f64::from));
    }
    Ok(out)
}

/// A byte pipe for one board: Carto's bytes in, what the board wrote kept.
#[derive(Debug, Default)]
struct Capture {
    rx: Vec<u8>,
    tx: Vec<u8>,
}

impl transport::Link for Capture {
    type Error = Never;
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Never> {
        let n = buf.len().min(self.rx.len());
        buf[..n].copy_from_slice(&self.rx[..n]);
        self.rx.drain(..n);
        Ok(n)
    }
    fn write(&mut self, buf: &[u8]) -> Result<usize, Never> {
        self.tx.extend_from_slice(buf);
        Ok(buf.len())
    }
}

/// The calibration drive ([`carto::calibration`]) run in the twin of `profile` (its noise on,
/// seeded by `seed`) standing in `room`, recorded as `carto --record` records it on the robot:
/// a stand-in for the robot, for tests and for trying `explobot calibrate` without one. Carto's
/// bytes reach the boards `lag_s` after it wrote them, and the boards' answers reach it as late.
pub fn drive_in_twin(
    room: &Scenario,
    profile: &RobotProfile,
    seed: u64,
    lag_s: f64,
) -> Result<Recording, CalibrateError> {
    use carto::calibration::CalibrationDrive;
    use transport::recording::{Chunk, EndpointLog, FORMAT_VERSION, Oracle};
    let setup = RunSetup::with_profile(room.clone(), profile.clone(), "", "<calibration room>")?;
    let dt = setup.dt();
    let mut twin = Twin::new(&setup, seed, dt);
    let (mut motor, mut sensor) = (Capture::default(), Capture::default());
    let start = Instant::from_millis(1000);
    let end = start + CalibrationDrive::length() + Duration::from_millis(1000);
    let mut drive = CalibrationDrive::new(start);
    let lag = Duration::from_micros((lag_s.max(0.0) * 1e6) as u64);
    // (due at the board, bytes, to the motor board)
    let mut in_flight: Vec<(Instant, Vec<u8>, bool)> = Vec::new();
    let (mut motor_log, mut sensor_log) = (Vec::new(), Vec::new());
    let mut keep_seq = 0u16;
    let mut next_keep = Instant::ZERO;
    let mut k = 0u64;
    loop {
        let now = Instant::from_micros(dt.total_micros() * k);
        if now > end {
            break;
        }
        k += 1;
        // Carto's side: keep-state twice a second, the plan's drives
        if now >= next_keep {
            let bytes = carto::wire::encode_keep_state(keep_seq);
            keep_seq = keep_seq.wrapping_add(1);
            next_keep = now + Duration::from_millis(500);
            sensor_log.push(Chunk { at: now, direction: Dir::Written, bytes: bytes.clone() });
            in_flight.push((now + lag, bytes, false));
        }
        if now >= start
            && let Some(d) = drive.poll(now)
        {
            let bytes = carto::wire::encode_drive(d, 100);
            motor_log.push(Chunk { at: now, direction: Dir::Written, bytes: bytes.clone() });
            in_flight.push((now + lag, bytes, true));
        }
        for (_, bytes, to_motor) in in_flight.iter().filter(|f| f.0 <= now) {
            if *to_motor { &mut motor } else { &mut sensor }.rx.extend_from_slice(bytes);
        }
        in_flight.retain(|f| f.0 > now);
        twin.board_io(now, &mut motor, &mut sensor, WriteBudget::UNLIMITED);
        twin.physics_step(now);
        for (link, log) in [(&mut motor, &mut motor_log), (&mut sensor, &mut sensor_log)] {
            if !link.tx.is_empty() {
                log.push(Chunk { at: now + lag, direction: Dir::Read, bytes: std::mem::take(&mut link.tx) });
            }
        }
    }
    for log in [&mut motor_log, &mut sensor_log] {
        log.sort_by_key(|c| c.at);
    }
    let endpoint = |link: &str, chunks| EndpointLog { link: link.into(), endpoint: "carto".into(), chunks };
    Ok(Recording {
        version: FORMAT_VERSION,
        scenario_label: "the calibration drive in the twin".into(),
        scenario_ron: String::new(),
        profile_ron: profile.to_ron_string().unwrap_or_default(),
        seed,
        logs: vec![endpoint("motor", motor_log), endpoint("sensor", sensor_log)],
        oracle: Oracle::None,
    })
}

/// The weights of the three streams: one σ each, in their units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sigmas {
    /// Wheel speed, rpm.
    pub rpm: f64,
    /// Heading, degrees.
    pub heading_deg: f64,
    /// Range, cm.
    pub range_cm: f64,
}

impl Sigmas {
    /// The base profile's noise (a floor of 1 rpm, 0.05°, 0.1 cm: the telemetry is exact and the
    /// fit needs a scale).
    pub fn of(profile: &RobotProfile) -> Sigmas {
        Sigmas {
            rpm: 1.0,
            heading_deg: f64::from(profile.imu.noise_sigma_deg).max(0.05),
            range_cm: f64::from(profile.sonar.noise_sigma_cm).max(0.1),
        }
    }
}

/// The residuals of one stream, recorded less predicted, with their times.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Residuals {
    /// Wheel speed, rpm (the four wheels of each sample in turn).
    pub rpm: Vec<(f64, f64)>,
    /// Heading, degrees.
    pub heading: Vec<(f64, f64)>,
    /// Range at rest, cm, where both sides heard an echo.
    pub range: Vec<(f64, f64)>,
    /// Every range at rest: the difference, 0 when neither side heard an echo, `None` when only
    /// one did (the fit counts it as [`MISMATCH_SIGMAS`] σ).
    pub range_all: Vec<Option<f64>>,
    /// Ranges at rest that one side heard and the other did not.
    pub range_mismatches: usize,
}

/// A range at rest heard on one side only weighs as an error of this many σ in the fit.
pub const MISMATCH_SIGMAS: f64 = 3.0;

impl Residuals {
    /// Recorded less predicted, for every sample of `rec`.
    pub fn of(rec: &Recorded, p: &Predicted) -> Residuals {
        let mut r = Residuals::default();
        for (t, rpm) in &rec.rpm {
            let pred = p.rpm_at(*t);
            r.rpm.extend((0..4).map(|w| (*t, rpm[w] - pred[w])));
        }
        let zero: Vec<f64> = rec
            .heading
            .iter()
            .filter(|(t, _)| *t < HEADING_ZERO_S)
            .map(|(t, h)| h - p.heading_at(*t))
            .collect();
        let offset = if zero.is_empty() { 0.0 } else { zero.iter().sum::<f64>() / zero.len() as f64 };
        r.heading = rec.heading.iter().map(|(t, h)| (*t, h - offset - p.heading_at(*t))).collect();
        for (t, cm) in &rec.range {
            if !rec.at_rest(*t) {
                continue;
            }
            match (cm, p.range_at(*t)) {
                (Some(a), Some(b)) => {
                    r.range.push((*t, a - b));
                    r.range_all.push(Some(a - b));
                }
                (None, None) => r.range_all.push(Some(0.0)),
                _ => {
                    r.range_mismatches += 1;
                    r.range_all.push(None);
                }
            }
        }
        r
    }

    /// Every residual divided by its σ, in one vector (the fit's).
    pub fn weighted(&self, s: Sigmas) -> Vec<f64> {
        let scaled = |v: &[(f64, f64)], sigma: f64| v.iter().map(|(_, e)| e / sigma).collect::<Vec<_>>();
        let range = self.range_all.iter().map(|e| e.map_or(MISMATCH_SIGMAS, |e| e / s.range_cm)).collect();
        [scaled(&self.rpm, s.rpm), scaled(&self.heading, s.heading_deg), range].concat()
    }
}

/// Root mean square of the second members.
pub fn rms(v: &[(f64, f64)]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    (v.iter().map(|(_, e)| e * e).sum::<f64>() / v.len() as f64).sqrt()
}

/// The link's round trip that best explains the recorded wheel speeds for `profile`: the one of
/// 0, 1, …, 100 ms with the least squared wheel-speed residual (`replay --compare` without a fit).
pub fn best_lag(room: &Scenario, profile: &RobotProfile, rec: &Recorded) -> Result<f64, CalibrateError> {
    let mut p = open_loop(room, profile, rec)?;
    let mut best = (f64::INFINITY, 0.0);
    for ms in 0..=100 {
        let lag = f64::from(ms) / 1000.0;
        p = p.lagged(lag);
        let cost = rms(&Residuals::of(rec, &p).rpm);
        if cost < best.0 {
            best = (cost, lag);
        }
    }
    Ok(best.1)
}

/// How far the twin of one profile is from a recording (`explobot replay REC --compare`).
#[derive(Debug, Clone, PartialEq)]
pub struct Gap {
    /// The profile's name.
    pub profile: String,
    /// The residuals.
    pub residuals: Residuals,
}

/// One row of [`Gap::table`]: a stream's RMS and largest error.
#[derive(Debug, Clone, PartialEq)]
pub struct GapRow {
    /// The stream.
    pub stream: &'static str,
    /// Its unit.
    pub unit: &'static str,
    /// Samples compared.
    pub samples: usize,
    /// RMS of recorded less predicted.
    pub rms: f64,
    /// Largest |recorded less predicted|, and when.
    pub max: (f64, f64),
}

impl Gap {
    /// Replays `rec` in the twin of `profile` standing in `room` (round trip `lag_s`).
    pub fn measure(
        room: &Scenario,
        profile: &RobotProfile,
        rec: &Recorded,
        lag_s: f64,
    ) -> Result<Gap, CalibrateError> {
        let p = open_loop(room, profile, rec)?.lagged(lag_s);
        Ok(Gap { profile: profile.name.clone(), residuals: Residuals::of(rec, &p) })
    }

    /// One row per stream.
    pub fn table(&self) -> Vec<GapRow> {
        let row = |stream, unit, v: &[(f64, f64)]| GapRow {
            stream,
            unit,
            samples: v.len(),
            rms: rms(v),
            max: v.iter().fold((0.0, 0.0), |m, (t, e)| if e.abs() > m.0 { (e.abs(), *t) } else { m }),
        };
        vec![
            row("wheel speed", "rpm", &self.residuals.rpm),
            row("heading", "deg", &self.residuals.heading),
            row("range at rest", "cm", &self.residuals.range),
        ]
    }

    /// The RMS of each stream over windows of `window_s` seconds: (window start, rpm, deg, cm).
    pub fn over_time(&self, window_s: f64) -> Vec<(f64, f64, f64, f64)> {
        let end = [&self.residuals.rpm, &self.residuals.heading, &self.residuals.range]
            .iter()
            .filter_map(|v| v.last().map(|s| s.0))
            .fold(0.0, f64::max);
        let mut out = Vec::new();
        let mut from = 0.0;
        while from <= end {
            let part = |v: &[(f64, f64)]| -> Vec<(f64, f64)> {
                v.iter().filter(|(t, _)| *t >= from && *t < from + window_s).copied().collect()
            };
            out.push((
                from,
                rms(&part(&self.residuals.rpm)),
                rms(&part(&self.residuals.heading)),
                rms(&part(&self.residuals.range)),
            ));
            from += window_s;
        }
        out
    }
}

#[cfg(test)]
mod tests;
