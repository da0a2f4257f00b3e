//! Motor + gearbox model: a first-order lag on wheel speed with a dead band and saturation.
//!
//! Each step the setpoint is first shaped — magnitudes below the dead band (a share of
//! `max_rpm`) become zero (the motor cannot overcome static friction), larger ones are clamped to
//! `±max_rpm`, non-finite ones count as zero — and the wheel speed then moves towards that
//! target with time constant `τ`, using the exact discretisation
//! `rpm += (target − rpm)·(1 − e^(−dt/τ))`. The response is therefore the same whatever the step
//! size: after one `τ` it has covered 63.2 % of a step.
//!
//! Invariant: `|rpm()| ≤ max_rpm` always.
//!
//! ```
//! use robot_model::motor::MotorModel;
//! use robot_model::time::Duration;
//! let mut m = MotorModel::new(80.0, 5.0, 300.0); // τ 80 ms, dead band 5 %, 300 rpm max
//! let rpm = m.step(150.0, Duration::from_millis(80));
//! assert!((rpm - 150.0 * (1.0 - (-1.0f32).exp())).abs() < 1e-3);
//! assert_eq!(m.step(10.0, Duration::from_secs(5)).round(), 0.0); // 10 rpm < 15 rpm dead band
//! ```

use crate::profile::RobotProfile;
use crate::time::Duration;

/// One wheel's motor, gearbox and driver, seen as wheel speed in rpm.
#[derive(Debug, Clone, PartialEq)]
pub struct MotorModel {
    tau_s: f32,
    dead_band_rpm: f32,
    max_rpm: f32,
    rpm: f32,
}

impl MotorModel {
    /// A motor at rest with time constant `tau_ms`, dead band in percent of `max_rpm`.
    pub fn new(tau_ms: f32, dead_band_percent: f32, max_rpm: f32) -> Self {
        let max_rpm = if max_rpm.is_finite() { max_rpm.abs() } else { 0.0 };
        let tau_s = if tau_ms.is_finite() { tau_ms.max(0.0) / 1000.0 } else { 0.0 };
        let db = if dead_band_percent.is_finite() { dead_band_percent.clamp(0.0, 100.0) } else { 0.0 };
        MotorModel { tau_s, dead_band_rpm: db / 100.0 * max_rpm, max_rpm, rpm: 0.0 }
    }

    /// A motor at rest with the profile's motor parameters.
    pub fn from_profile(p: &RobotProfile) -> Self {
        Self::new(p.motor.tau_ms, p.motor.dead_band_percent, p.motor.max_wheel_rpm)
    }

    /// The target speed the motor tends to for a setpoint (dead band and saturation applied).
    pub fn target(&self, setpoint_rpm: f32) -> f32 {
        if !setpoint_rpm.is_finite() || setpoint_rpm.abs() < self.dead_band_rpm {
            0.0
        } else {
            setpoint_rpm.clamp(-self.max_rpm, self.max_rpm)
        }
    }

    /// Advances the motor by `dt` towards `setpoint_rpm`; returns the new wheel speed, rpm.
    pub fn step(&mut self, setpoint_rpm: f32, dt: Duration) -> f32 {
        let target = self.target(setpoint_rpm);
        let dt_s = dt.as_secs_f32();
        let alpha = if self.tau_s <= 0.0 { 1.0 } else { 1.0 - (-dt_s / self.tau_s).exp() };
        self.rpm += (target - self.rpm) * alpha;
        self.rpm = self.rpm.clamp(-self.max_rpm, self.max_rpm);
        self.rpm
    }

    /// The current wheel speed, rpm.
    pub fn rpm(&self) -> f32 {
        self.rpm
    }

    /// Forces the wheel speed (e.g. to zero after a collision reset).
    pub fn set_rpm(&mut self, rpm: f32) {
        self.rpm = if rpm.is_finite() { rpm.clamp(-self.max_rpm, self.max_rpm) } else { 0.0 };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn motor() -> MotorModel {
        MotorModel::from_profile(&RobotProfile::default())
    }

    #[test]
    fn reaches_63_percent_at_tau_whatever_the_step() {
        for step_us in [1_000u64, 5_000, 80_000] {
            let mut m = motor();
            let mut t = 0;
            while t < 80_000 {
                m.step(200.0, Duration::from_micros(step_us));
                t += step_us;
            }
            let want = 200.0 * (1.0 - (-1.0f32).exp());
            assert!((m.rpm() - want).abs() < 0.01, "step {step_us}: {} vs {want}", m.rpm());
        }
    }

    #[test]
    fn settles_on_the_setpoint() {
        let mut m = motor();
        for _ in 0..200 {
            m.step(-150.0, Duration::from_millis(5));
        } // 1 s = 12.5 τ
        assert!((m.rpm() + 150.0).abs() < 1e-3, "{}", m.rpm());
    }

    #[test]
    fn dead_band_holds_zero() {
        let mut m = motor();
        for _ in 0..100 {
            m.step(14.9, Duration::from_millis(10)); // just under 5 % of 300 rpm
        }
        assert_eq!(m.rpm(), 0.0);
        m.step(15.0, Duration::from_secs(2));
        assert!((m.rpm() - 15.0).abs() < 1e-3);
        // A running motor whose setpoint drops into the dead band coasts to zero.
        m.step(-5.0, Duration::from_secs(2));
        assert!(m.rpm().abs() < 1e-3);
    }

    #[test]
    fn saturates_at_max_rpm() {
        let mut m = motor();
        m.step(1e6, Duration::from_secs(10));
        assert_eq!(m.rpm(), 300.0);
        m.step(f32::NEG_INFINITY, Duration::from_secs(10)); // non-finite → 0
        assert!(m.rpm().abs() < 1e-3);
        m.step(-450.0, Duration::from_secs(10));
        assert_eq!(m.rpm(), -300.0);
    }

    #[test]
    fn zero_tau_follows_instantly() {
        let mut m = MotorModel::new(0.0, 0.0, 100.0);
        assert_eq!(m.step(42.0, Duration::from_micros(1)), 42.0);
        assert_eq!(m.step(42.0, Duration::ZERO), 42.0);
    }
}
