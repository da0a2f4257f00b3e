//! `explobot calibrate`: the profile's physical values fitted to a recording by least squares.
//!
//! Method (standard system identification):
//! 1. **Read off directly**: the motors' dead band ([`dead_band`]: between the largest held
//!    command that left a wheel standing and the smallest that turned it), the IMU's drift and
//!    noise ([`drift_and_noise`]: one straight line per still period, sharing one slope).
//! 2. **Which values the drive can tell.** At the base profile, the derivative of the weighted
//!    residuals with respect to each value of [`PARAMS`] is taken by central differences. A value
//!    whose 10 % change moves the sum of squares by less than 1 (one σ of one sample) is *not
//!    observable* from this recording: it keeps its base value and is reported so. The mass is,
//!    in the twin: its motors follow their set-point whatever the load, and the wheels' grip
//!    scales with the weight.
//! 3. **The fit.** Nelder–Mead (`argmin`) minimises the sum of squared weighted residuals
//!    ([`super::Residuals::weighted`]) over the observable values, each scaled by its base, and
//!    the link's round trip (a nuisance value, 0–200 ms, smooth: see
//!    [`super::Predicted::lagged`]).
//! 4. **Uncertainty.** From the Jacobian at the optimum (the round trip included, so a value
//!    that trades off against it is as uncertain as that makes it), the Gauss–Newton covariance
//!    `s²·(JᵀJ)⁻¹`, with `s²` the sum of squares over its degrees of freedom (so a misjudged σ
//!    scales out): one standard deviation per value. It is statistical only: the twin's 5 ms
//!    steps bias the time constant by about 1 %, more than its σ.
//! 5. **The sonar's noise** is the spread of the ranges at rest less the model's about each still
//!    period's mean ([`range_noise`]), with its standard error.
//!
//! Invariant: every evaluation is a deterministic twin run; the same recording, room and base
//! give the same fit, byte for byte.

use argmin::core::{CostFunction, Executor};
use argmin::solver::neldermead::NelderMead;
use nalgebra::{DMatrix, DVector};
use robot_model::profile::RobotProfile;

use super::{CalibrateError, Recorded, Residuals, Sigmas, open_loop};
use crate::scenario::Scenario;

/// A physical value of the profile the fit may move.
#[derive(Debug, Clone, Copy)]
pub struct Param {
    /// Its path in the profile file.
    pub name: &'static str,
    /// Its unit.
    pub unit: &'static str,
    get: fn(&RobotProfile) -> f32,
    set: fn(&mut RobotProfile, f32),
}

impl Param {
    /// Its value in `profile`.
    pub fn of(&self, profile: &RobotProfile) -> f64 {
        f64::from((self.get)(profile))
    }
}

/// The values fitted by least squares (issue 44: mass, wheel radius, the motors' time
/// constant). The dead band, the IMU's drift and the two noises are read off directly
/// ([`dead_band`], [`drift_and_noise`]).
pub const PARAMS: [Param; 3] = [
    Param { name: "motor.tau_ms", unit: "ms", get: |p| p.motor.tau_ms, set: |p, v| p.motor.tau_ms = v },
    Param {
        name: "geometry.wheel_radius_m",
        unit: "m",
        get: |p| p.geometry.wheel_radius_m,
        set: |p, v| p.geometry.wheel_radius_m = v,
    },
    Param {
        name: "geometry.mass_kg",
        unit: "kg",
        get: |p| p.geometry.mass_kg,
        set: |p, v| p.geometry.mass_kg = v,
    },
];

/// The round trip's scale in the fit, seconds (its unit step).
const LAG_SCALE_S: f64 = 0.01;
/// The round trip the fit may choose, seconds.
const LAG_RANGE_S: (f64, f64) = (0.0, 0.2);
/// Relative change of a value for the observability test.
const PROBE: f64 = 0.1;
/// Relative step of the Jacobian's differences.
const STEP: f64 = 0.01;
/// A fitted value stays within this factor of its base.
const BOUNDS: (f64, f64) = (0.3, 3.0);
/// Nelder–Mead's iteration cap.
const MAX_ITERS: u64 = 400;

/// One fitted value.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// Its path in the profile.
    pub name: &'static str,
    /// Its unit.
    pub unit: &'static str,
    /// The base profile's value.
    pub base: f64,
    /// The fitted value (the base when not observable).
    pub value: f64,
    /// One standard deviation; `None` when not observable.
    pub sigma: Option<f64>,
}

/// What `explobot calibrate` found.
#[derive(Debug, Clone)]
pub struct Fitted {
    /// The physical values, in [`PARAMS`] order.
    pub values: Vec<Estimate>,
    /// Values read off the recording: the dead band, the IMU's drift and noise, the sonar's noise.
    pub readings: Vec<Estimate>,
    /// The link's round trip, seconds.
    pub lag_s: f64,
    /// The residuals at the fit.
    pub residuals: Residuals,
    /// Samples in the fit.
    pub samples: usize,
    /// Twin runs the fit took.
    pub evaluations: usize,
    /// The fitted profile.
    pub profile: RobotProfile,
}

struct Problem<'a> {
    room: &'a Scenario,
    base: &'a RobotProfile,
    rec: &'a Recorded,
    sigmas: Sigmas,
    /// Indices into [`PARAMS`] of the values fitted.
    free: Vec<usize>,
    evaluations: std::cell::Cell<usize>,
}

impl Problem<'_> {
    fn scale(&self, i: usize) -> f64 {
        let base = f64::from((PARAMS[i].get)(self.base));
        if base.abs() > 1e-6 { base } else { 1.0 }
    }

    /// The profile and round trip at `x` (free values scaled by their bases, then the lag).
    fn at(&self, x: &[f64]) -> (RobotProfile, f64) {
        let mut p = self.base.clone();
        for (k, &i) in self.free.iter().enumerate() {
            (PARAMS[i].set)(&mut p, (x[k] * self.scale(i)) as f32);
        }
        (p, x[self.free.len()] * LAG_SCALE_S)
    }

    fn in_bounds(&self, x: &[f64]) -> bool {
        let lag = x[self.free.len()] * LAG_SCALE_S;
        x[..self.free.len()].iter().all(|v| (BOUNDS.0..=BOUNDS.1).contains(v))
            && (LAG_RANGE_S.0..=LAG_RANGE_S.1).contains(&lag)
    }

    fn residuals(&self, x: &[f64]) -> Result<Residuals, CalibrateError> {
        self.evaluations.set(self.evaluations.get() + 1);
        let (p, lag) = self.at(x);
        Ok(Residuals::of(self.rec, &open_loop(self.room, &p, self.rec)?.lagged(lag)))
    }

    fn weighted(&self, x: &[f64]) -> Result<DVector<f64>, CalibrateError> {
        Ok(DVector::from_vec(self.residuals(x)?.weighted(self.sigmas)))
    }

    /// Central differences of the weighted residuals along the first `h.len()` coordinates,
    /// steps `h`.
    fn jacobian(&self, x: &[f64], h: &[f64]) -> Result<DMatrix<f64>, CalibrateError> {
        let mut cols = Vec::with_capacity(h.len());
        for k in 0..h.len() {
            let (mut up, mut down) = (x.to_vec(), x.to_vec());
            up[k] += h[k];
            down[k] -= h[k];
            cols.push((self.weighted(&up)? - self.weighted(&down)?) / (2.0 * h[k]));
        }
        Ok(DMatrix::from_columns(&cols))
    }
}

impl CostFunction for &Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, x: &Self::Param) -> Result<f64, argmin::core::Error> {
        if !self.in_bounds(x) {
            return Ok(f64::MAX / 4.0);
        }
        let r = self.weighted(x).map_err(|e| argmin::core::Error::msg(e.to_string()))?;
        Ok(r.norm_squared())
    }
}

/// Fits `base`'s [`PARAMS`] to `rec`, replayed in `room` (module docs).
pub fn fit(room: &Scenario, base: &RobotProfile, rec: &Recorded) -> Result<Fitted, CalibrateError> {
    let sigmas = Sigmas::of(base);
    // 1. read off directly; the fit starts from the base with these values
    let mut readings = Vec::new();
    let mut seeded = base.clone();
    if let Some(db) = dead_band(rec, base) {
        seeded.motor.dead_band_percent = db.value as f32;
        readings.push(db);
    }
    let (drift, imu_noise) = drift_and_noise(rec, base);
    if let Some(d) = drift {
        seeded.imu.drift_deg_per_min = d.value as f32;
        readings.push(d);
    }
    readings.extend(imu_noise.clone());
    let all = Problem {
        room,
        base: &seeded,
        rec,
        sigmas,
        free: (0..PARAMS.len()).collect(),
        evaluations: std::cell::Cell::new(0),
    };
    // 2. observability, at the base and a first round trip of 20 ms
    let lag0 = 0.02 / LAG_SCALE_S;
    let x0: Vec<f64> = (0..PARAMS.len()).map(|_| 1.0).chain([lag0]).collect();
    let j0 = all.jacobian(&x0, &[PROBE; PARAMS.len()])?;
    let free: Vec<usize> =
        (0..PARAMS.len()).filter(|&i| (j0.column(i) * PROBE).norm_squared() >= 1.0).collect();
    let problem =
        Problem { free: free.clone(), evaluations: std::cell::Cell::new(all.evaluations.get()), ..all };

    // 3. Nelder–Mead from the base
    let start: Vec<f64> = free.iter().map(|_| 1.0).chain([lag0]).collect();
    let mut simplex = vec![start.clone()];
    for k in 0..start.len() {
        let mut v = start.clone();
        v[k] += if k < free.len() { 0.15 } else { 2.0 };
        simplex.push(v);
    }
    let solver =
        NelderMead::new(simplex).with_sd_tolerance(1e-4).map_err(|e| CalibrateError::Fit(e.to_string()))?;
    let result = Executor::new(&problem, solver)
        .configure(|s| s.max_iters(MAX_ITERS))
        .run()
        .map_err(|e| CalibrateError::Fit(e.to_string()))?;
    let best =
        result.state.best_param.clone().ok_or_else(|| CalibrateError::Fit("no parameter found".into()))?;

    // 4. uncertainty
    let residuals = problem.residuals(&best)?;
    let r = DVector::from_vec(residuals.weighted(sigmas));
    let cost_fit = r.norm_squared();
    // the values' relative steps, then 1 ms of round trip
    let steps: Vec<f64> = free.iter().map(|_| STEP).chain([0.001 / LAG_SCALE_S]).collect();
    let j = problem.jacobian(&best, &steps)?;
    let dof = (r.len().saturating_sub(free.len() + 1)).max(1) as f64;
    let cov = (j.transpose() * &j).try_inverse().map(|inv| inv * (cost_fit / dof));
    let (profile, lag_s) = problem.at(&best);
    let values = PARAMS
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let k = free.iter().position(|&f| f == i);
            Estimate {
                name: p.name,
                unit: p.unit,
                base: p.of(base),
                value: p.of(&profile),
                sigma: k.and_then(|k| cov.as_ref().map(|c| c[(k, k)].max(0.0).sqrt() * problem.scale(i))),
            }
        })
        .collect();

    // 5. the sonar's noise, from what is left at rest
    let sonar_noise = range_noise(&residuals.range, base);
    let mut profile = profile;
    profile.sonar.noise_sigma_cm = sonar_noise.value as f32;
    if let Some(n) = &imu_noise {
        profile.imu.noise_sigma_deg = n.value as f32;
    }
    readings.push(sonar_noise);
    Ok(Fitted {
        values,
        readings,
        lag_s,
        samples: r.len(),
        residuals,
        evaluations: problem.evaluations.get(),
        profile,
    })
}

impl Fitted {
    /// Every value: the fitted ones, then those read off.
    pub fn all(&self) -> impl Iterator<Item = &Estimate> {
        self.values.iter().chain(&self.readings)
    }

    /// The fitted profile as a RON file: the base's text form with every fitted value followed by
    /// a comment naming `recording`, its uncertainty and the base value.
    pub fn profile_ron(&self, recording: &str) -> Result<String, ron::Error> {
        let text = self.profile.to_ron_string()?;
        let mut out = format!(
            "// Fitted by `explobot calibrate` to {recording}: {} samples, round trip {:.0} ms.\n",
            self.samples,
            self.lag_s * 1000.0
        );
        for line in text.lines() {
            out.push_str(line);
            let field = line.trim_start().split(':').next().unwrap_or("");
            if let Some(e) = self.all().find(|e| e.name.rsplit('.').next() == Some(field)) {
                match e.sigma {
                    Some(s) => out.push_str(&format!(
                        " // fitted to {recording}: ± {} (base {:.4})",
                        significant(s),
                        e.base
                    )),
                    None => out.push_str(&format!(" // not observable in {recording}: the base value")),
                }
            }
            out.push('\n');
        }
        Ok(out)
    }
}

/// The motor board's dead band, percent, read off the drives held at least half a second: it
/// lies above the largest wheel command that left its wheel standing and at or below the
/// smallest that turned it. The estimate is the middle of that interval, its σ the interval's
/// width over √12 (the commands are whole percents: the protocol's resolution). `None` when no
/// held command left a wheel standing, or none turned one.
pub fn dead_band(rec: &Recorded, base: &RobotProfile) -> Option<Estimate> {
    use protocol::motor::{MotorCommand, MotorPacket};
    let mut decoder = protocol::motor::Decoder::default();
    let mut held: Vec<(f64, [f32; 4])> = Vec::new();
    for w in rec.writes.iter().filter(|w| w.to_motor) {
        for p in decoder.feed(&w.bytes).into_iter().flatten() {
            if let MotorPacket::Drive(MotorCommand::V2 { vx, vy, omega, .. }) = p {
                let mix = robot_model::kinematics::mix_percent(
                    f32::from(vx),
                    f32::from(vy),
                    f32::from(omega),
                    base.motor_board.mixing_k,
                );
                if held.last().is_none_or(|h| h.1 != mix) {
                    held.push((w.at_s, mix));
                }
            }
        }
    }
    let (mut still_max, mut moving_min) = (f64::NEG_INFINITY, f64::INFINITY);
    for (k, (from, mix)) in held.iter().enumerate() {
        let to = held.get(k + 1).map_or(rec.end_s, |h| h.0);
        if to - from < 0.5 {
            continue;
        }
        // the second half of the hold: the wheels have settled
        let samples: Vec<&[f64; 4]> = rec
            .rpm
            .iter()
            .filter(|(t, _)| *t > from + 0.5 * (to - from) && *t < to)
            .map(|(_, r)| r)
            .collect();
        if samples.is_empty() {
            continue;
        }
        for (w, pct) in mix.iter().enumerate() {
            let pct = f64::from(pct.abs());
            if pct == 0.0 {
                continue;
            }
            if samples.iter().all(|r| r[w].abs() < super::STILL_RPM) {
                still_max = still_max.max(pct);
            } else if samples.iter().all(|r| r[w].abs() >= super::STILL_RPM) {
                moving_min = moving_min.min(pct);
            }
        }
    }
    (still_max.is_finite() && moving_min.is_finite() && still_max < moving_min).then(|| Estimate {
        name: "motor.dead_band_percent",
        unit: "%",
        base: f64::from(base.motor.dead_band_percent),
        value: 0.5 * (still_max + moving_min),
        sigma: Some((moving_min - still_max) / 12f64.sqrt()),
    })
}

/// Two ranges at rest further apart than this, seconds, belong to different still periods (the
/// sonar reports at 10 Hz).
const SAME_REST_S: f64 = 0.3;

/// The sonar's noise (cm) from the range residuals at rest `range` (time, recorded less
/// predicted): their spread about each still period's own mean, pooled over the periods, with
/// its standard error `σ/√(2(n − k))` for `n` ranges in `k` periods.
///
/// Each period's mean is left out because a pose the replay has a few millimetres off (the
/// link's timing differs between the recording and the replay, more so on a loaded machine)
/// moves every residual of that period alike: the RMS about zero would count that bias as
/// noise. Periods of one range say nothing.
pub fn range_noise(range: &[(f64, f64)], base: &RobotProfile) -> Estimate {
    let mut periods: Vec<Vec<f64>> = Vec::new();
    let mut last_t = f64::NEG_INFINITY;
    for &(t, e) in range {
        match periods.last_mut() {
            Some(period) if t - last_t <= SAME_REST_S => period.push(e),
            _ => periods.push(vec![e]),
        }
        last_t = t;
    }
    periods.retain(|p| p.len() >= 2);
    let n: usize = periods.iter().map(Vec::len).sum();
    let dof = n.saturating_sub(periods.len()).max(1) as f64;
    let ss: f64 = periods
        .iter()
        .map(|p| {
            let mean = p.iter().sum::<f64>() / p.len() as f64;
            p.iter().map(|e| (e - mean).powi(2)).sum::<f64>()
        })
        .sum();
    let sigma = (ss / dof).sqrt();
    Estimate {
        name: "sonar.noise_sigma_cm",
        unit: "cm",
        base: f64::from(base.sonar.noise_sigma_cm),
        value: sigma,
        sigma: Some(sigma / (2.0 * dof).sqrt()),
    }
}

/// The IMU's drift (degrees a minute) and noise (degrees), from the heading while the robot
/// stands still: one straight line per still period, sharing one slope (the drift); the spread
/// about them is the noise. The slope's σ is the regression's; the noise's, `σ/√(2n)`.
pub fn drift_and_noise(rec: &Recorded, base: &RobotProfile) -> (Option<Estimate>, Option<Estimate>) {
    // still periods: runs of samples at rest
    let mut runs: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut open = false;
    for &(t, h) in &rec.heading {
        if rec.at_rest(t) {
            if !open {
                runs.push(Vec::new());
            }
            open = true;
            if let Some(r) = runs.last_mut() {
                r.push((t, h));
            }
        } else {
            open = false;
        }
    }
    runs.retain(|r| r.len() >= 10);
    let (mut sxy, mut sxx, mut n) = (0.0, 0.0, 0usize);
    let centred: Vec<Vec<(f64, f64)>> = runs
        .iter()
        .map(|r| {
            let k = r.len() as f64;
            let (tm, hm) = (r.iter().map(|s| s.0).sum::<f64>() / k, r.iter().map(|s| s.1).sum::<f64>() / k);
            r.iter().map(|(t, h)| (t - tm, h - hm)).collect()
        })
        .collect();
    for (t, h) in centred.iter().flatten() {
        sxy += t * h;
        sxx += t * t;
        n += 1;
    }
    if n < 20 || sxx <= 0.0 {
        return (None, None);
    }
    let slope = sxy / sxx;
    let dof = (n - centred.len() - 1).max(1) as f64;
    let ss: f64 = centred.iter().flatten().map(|(t, h)| (h - slope * t).powi(2)).sum();
    let sigma = (ss / dof).sqrt();
    let drift = Estimate {
        name: "imu.drift_deg_per_min",
        unit: "deg/min",
        base: f64::from(base.imu.drift_deg_per_min),
        value: slope * 60.0,
        sigma: Some(sigma / sxx.sqrt() * 60.0),
    };
    let noise = Estimate {
        name: "imu.noise_sigma_deg",
        unit: "deg",
        base: f64::from(base.imu.noise_sigma_deg),
        value: sigma,
        sigma: Some(sigma / (2.0 * n as f64).sqrt()),
    };
    (Some(drift), Some(noise))
}

/// `x` to three significant digits (a σ of 1e-5 m stays readable).
pub fn significant(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let decimals = (2 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.decimals$}")
}
