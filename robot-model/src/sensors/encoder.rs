//! Wheel encoder: wheel angle → pulse count and direction flag.
//!
//! The count is `floor((angle − angle₀) / 2π · ppr)` with `ppr` = pulses per **wheel**
//! revolution (11 × 18.8 = 206.8 on the default robot): an edge every `2π/ppr` radians of wheel
//! rotation, counting down when the wheel turns backwards. The angle is positive when the wheel
//! rolls the robot forward (see [`crate::kinematics`]); it is `f64` because it accumulates over a
//! whole run. The direction flag follows the last non-zero change of angle (forward at start).
//!
//! Invariant: the count saturates at `i32::MIN`/`i32::MAX` instead of wrapping (`as` casts
//! from float saturate).

use core::f64::consts::TAU;

use crate::profile::RobotProfile;

/// One wheel encoder.
#[derive(Debug, Clone, PartialEq)]
pub struct Encoder {
    pulses_per_wheel_rev: f64,
    zero_angle: f64,
    angle: f64,
    forward: bool,
}

impl Encoder {
    /// An encoder with `pulses_per_wheel_rev` pulses per wheel turn, at angle 0, count 0.
    pub fn new(pulses_per_wheel_rev: f64) -> Self {
        Encoder { pulses_per_wheel_rev, zero_angle: 0.0, angle: 0.0, forward: true }
    }

    /// An encoder with the profile's pulses per motor turn × gear ratio.
    pub fn from_profile(p: &RobotProfile) -> Self {
        Self::new(decimal_f64(p.encoder.pulses_per_motor_rev) * decimal_f64(p.motor.gear_ratio))
    }

    /// Feeds the wheel's absolute angle (radians, forward positive); returns the new count.
    pub fn update(&mut self, wheel_angle_rad: f64) -> i32 {
        if wheel_angle_rad.is_finite() {
            if wheel_angle_rad > self.angle {
                self.forward = true;
            } else if wheel_angle_rad < self.angle {
                self.forward = false;
            }
            self.angle = wheel_angle_rad;
        }
        self.count()
    }

    /// The pulse count since the last reset.
    pub fn count(&self) -> i32 {
        ((self.angle - self.zero_angle) / TAU * self.pulses_per_wheel_rev).floor() as i32
    }

    /// Whether the wheel last turned forward.
    pub fn forward(&self) -> bool {
        self.forward
    }

    /// Sets the count to zero at the current angle.
    pub fn reset(&mut self) {
        self.zero_angle = self.angle;
    }

    /// Pulses per wheel revolution.
    pub fn pulses_per_wheel_rev(&self) -> f64 {
        self.pulses_per_wheel_rev
    }
}

/// Widens an `f32` through its shortest decimal form, so `18.8f32` becomes `18.8f64`, not
/// `18.799999237…`; five wheel turns then count 1034 pulses, not 1033.
fn decimal_f64(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(f64::from(v))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_206_8_pulses_per_wheel_turn() {
        let mut e = Encoder::from_profile(&RobotProfile::default());
        assert!((e.pulses_per_wheel_rev() - 206.8).abs() < 1e-4);
        assert_eq!(e.update(TAU), 206);
        assert_eq!(e.update(5.0 * TAU), 1034); // whole pulses land exactly on the turn
        assert_eq!(e.update(10.0 * TAU), 2068);
        assert!(e.forward());
    }

    #[test]
    fn backwards_counts_down_and_flags_reverse() {
        let mut e = Encoder::new(100.0);
        e.update(TAU);
        assert_eq!(e.update(TAU / 2.0), 50);
        assert!(!e.forward());
        assert_eq!(e.update(-TAU / 100.0 * 0.5), -1); // half a pulse behind zero: edge passed
        e.update(-TAU / 100.0 * 0.5); // no change keeps the flag
        assert!(!e.forward());
    }

    #[test]
    fn reset_zeroes_at_the_current_angle() {
        let mut e = Encoder::new(100.0);
        e.update(3.0);
        e.reset();
        assert_eq!(e.count(), 0);
        assert_eq!(e.update(3.0 + TAU), 100);
        assert_eq!(e.update(f64::NAN), 100); // ignored
    }
}
