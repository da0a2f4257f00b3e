//! Mecanum kinematics (X configuration, wheel order FL, FR, RL, RR) and the motor board's
//! percent mixing.
//!
//! # Conventions
//! - Twists are body-frame: `vx` forward, `vy` **left**, `omega` **counter-clockwise** (see
//!   [`crate::pose`]).
//! - A wheel's speed is positive when it rolls the robot **forward** (its contact point pushes
//!   backwards), whichever side the motor sits on; mirrored motor wiring is the firmware's
//!   business, not the model's.
//! - Wheel `i` sits at `(±a, ±b)` with `a` = half wheelbase, `b` = half track. Its ground-contact
//!   roller axis makes the roller angle `γ` (45°) with the wheel axis, and the contact rollers'
//!   axes point towards the chassis centre (FL and RR along forward-left, FR and RL along
//!   forward-right): the standard layout that strafes and turns on the spot. Seen from above,
//!   the *upper* rollers then form the familiar diamond.
//!
//! # Inverse kinematics (twist → wheel angular speeds)
//! A roller transmits force only across its own axis, so the body velocity at the contact point
//! projected on the roller's normal must equal the wheel's rim speed projected on it. With
//! `t = tan γ` and the rotation arm `L = b + t·a` this gives
//!
//! ```text
//! r·ω_FL = vx − t·vy − L·ω        r·ω_FR = vx + t·vy + L·ω
//! r·ω_RL = vx + t·vy − L·ω        r·ω_RR = vx − t·vy + L·ω
//! ```
//!
//! The columns of this matrix are orthogonal, so the forward kinematics (least squares, exact
//! when the wheels do not slip) is `vx = r/4·(ω₁+ω₂+ω₃+ω₄)`, `vy = r/(4t)·(−ω₁+ω₂+ω₃−ω₄)`,
//! `ω = r/(4L)·(−ω₁+ω₂−ω₃+ω₄)`.
//!
//! # The board's percent mixing agrees with "vy left, ω CCW"
//! The firmware mixes `FL = vx − vy − k·ω`, `FR = vx + vy + k·ω`, `RL = vx + vy − k·ω`,
//! `RR = vx − vy + k·ω` (percent), then scales all four down together if one exceeds 100. At
//! γ = 45° (t = 1) this is the inverse kinematics above, term for term and sign for sign, with
//! `vy` **left** positive and `ω` **counter-clockwise** positive: `+vy` turns FL and RR backwards
//! and FR and RL forwards (strafe left), `+ω` turns both left wheels backwards and both right
//! wheels forwards (turn left, CCW). So the wire convention of drive v2 needs no sign change.
//! Scale: 100 % on a wheel is `max_wheel_rpm`, so 100 % `vx` is the maximum rim speed `v_max`
//! forwards, 100 % `vy` is `v_max/t` to the left, and 100 % `ω` is `k·v_max/L` rad/s
//! ([`MecanumKinematics::percent_to_twist`]). Drive v1 has no rotation axis and its `dir_x` is
//! strafe **right**, so the board maps it to `vy = −dir_x`.
//!
//! ```
//! use robot_model::kinematics::{mix_percent, MecanumKinematics};
//! use robot_model::pose::Twist;
//! use robot_model::profile::RobotProfile;
//!
//! let kin = MecanumKinematics::from_profile(&RobotProfile::default());
//! let wheels = kin.inverse(Twist::new(0.0, 0.0, 1.0)); // spin CCW at 1 rad/s
//! assert!(wheels[0] < 0.0 && wheels[1] > 0.0 && wheels[2] < 0.0 && wheels[3] > 0.0);
//! let back = kin.forward(wheels);
//! assert!((back.omega - 1.0).abs() < 1e-5);
//!
//! // The board: full forward plus full strafe saturates and scales down together.
//! assert_eq!(mix_percent(100.0, 100.0, 0.0, 1.0), [0.0, 100.0, 100.0, 0.0]);
//! ```

use core::f32::consts::TAU;

use crate::pose::Twist;
use crate::profile::RobotProfile;

/// Wheel indices in the order used everywhere: FL, FR, RL, RR.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Wheel {
    /// Front left, index 0.
    FrontLeft = 0,
    /// Front right, index 1.
    FrontRight = 1,
    /// Rear left, index 2.
    RearLeft = 2,
    /// Rear right, index 3.
    RearRight = 3,
}

impl Wheel {
    /// All wheels in array order.
    pub const ALL: [Wheel; 4] = [Wheel::FrontLeft, Wheel::FrontRight, Wheel::RearLeft, Wheel::RearRight];

    /// The wheel's index in `[_; 4]` arrays.
    pub const fn index(self) -> usize {
        self as usize
    }

    /// The wheel's contact position in the body frame, `(x forward, y left)`, metres.
    pub fn position(self, half_wheelbase: f32, half_track: f32) -> (f32, f32) {
        match self {
            Wheel::FrontLeft => (half_wheelbase, half_track),
            Wheel::FrontRight => (half_wheelbase, -half_track),
            Wheel::RearLeft => (-half_wheelbase, half_track),
            Wheel::RearRight => (-half_wheelbase, -half_track),
        }
    }
}

/// Converts rpm to rad/s.
pub fn rpm_to_rad_s(rpm: f32) -> f32 {
    rpm * TAU / 60.0
}

/// Converts rad/s to rpm.
pub fn rad_s_to_rpm(rad_s: f32) -> f32 {
    rad_s * 60.0 / TAU
}

/// A drive command in the board's percent units (each nominally within ±100).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PercentCommand {
    /// Forward, percent.
    pub vx: f32,
    /// Left, percent.
    pub vy: f32,
    /// Counter-clockwise, percent.
    pub omega: f32,
}

/// The motor board's mixing: percent command → four wheel percents (FL, FR, RL, RR), all four
/// scaled down together when one exceeds 100 in magnitude. Non-finite inputs count as zero.
pub fn mix_percent(vx: f32, vy: f32, omega: f32, k: f32) -> [f32; 4] {
    let f = |v: f32| if v.is_finite() { v } else { 0.0 };
    let (vx, vy, w) = (f(vx), f(vy), f(k) * f(omega));
    let mut out = [vx - vy - w, vx + vy + w, vx + vy - w, vx - vy + w];
    let peak = out.iter().fold(0.0f32, |m, v| m.max(v.abs()));
    if peak > 100.0 {
        let s = 100.0 / peak;
        for v in &mut out {
            *v *= s;
        }
    }
    out
}

/// Mecanum geometry for twist ⇄ wheel-speed conversions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MecanumKinematics {
    /// Wheel radius, metres.
    pub wheel_radius: f32,
    /// Half the wheelbase (front–rear), metres.
    pub half_wheelbase: f32,
    /// Half the track (left–right), metres.
    pub half_track: f32,
    /// `tan` of the roller angle (1 at 45°).
    pub roller_tan: f32,
    /// Wheel speed at 100 %, rpm.
    pub max_wheel_rpm: f32,
    /// Rotation gain of the board's mixing.
    pub mixing_k: f32,
}

impl MecanumKinematics {
    /// Builds the kinematics from a (validated) profile.
    pub fn from_profile(p: &RobotProfile) -> Self {
        MecanumKinematics {
            wheel_radius: p.geometry.wheel_radius_m,
            half_wheelbase: p.geometry.wheelbase_m / 2.0,
            half_track: p.geometry.track_m / 2.0,
            roller_tan: p.wheels.roller_angle_deg.to_radians().tan(),
            max_wheel_rpm: p.motor.max_wheel_rpm,
            mixing_k: p.motor_board.mixing_k,
        }
    }

    /// The rotation arm `L = b + tan γ · a`, metres (0.19 m for the default robot).
    pub fn rotation_arm(&self) -> f32 {
        self.half_track + self.roller_tan * self.half_wheelbase
    }

    /// Rim speed at 100 % command, m/s.
    pub fn max_rim_speed(&self) -> f32 {
        rpm_to_rad_s(self.max_wheel_rpm) * self.wheel_radius
    }

    /// Inverse kinematics: body twist → wheel angular speeds (rad/s, FL, FR, RL, RR).
    pub fn inverse(&self, t: Twist) -> [f32; 4] {
        let r = self.wheel_radius;
        let vy = self.roller_tan * t.vy;
        let w = self.rotation_arm() * t.omega;
        [(t.vx - vy - w) / r, (t.vx + vy + w) / r, (t.vx + vy - w) / r, (t.vx - vy + w) / r]
    }

    /// Forward kinematics: wheel angular speeds (rad/s, FL, FR, RL, RR) → body twist.
    pub fn forward(&self, w: [f32; 4]) -> Twist {
        let r = self.wheel_radius;
        Twist {
            vx: r / 4.0 * (w[0] + w[1] + w[2] + w[3]),
            vy: r / (4.0 * self.roller_tan) * (-w[0] + w[1] + w[2] - w[3]),
            omega: r / (4.0 * self.rotation_arm()) * (-w[0] + w[1] - w[2] + w[3]),
        }
    }

    /// Forward kinematics from wheel speeds in rpm.
    pub fn forward_rpm(&self, rpm: [f32; 4]) -> Twist {
        self.forward(rpm.map(rpm_to_rad_s))
    }

    /// Wheel percents (100 % = `max_wheel_rpm`) → wheel speeds in rpm.
    pub fn percent_to_rpm(&self, percent: [f32; 4]) -> [f32; 4] {
        percent.map(|p| p / 100.0 * self.max_wheel_rpm)
    }

    /// The body twist an (unsaturated) percent command means, per the board's mixing.
    pub fn percent_to_twist(&self, c: PercentCommand) -> Twist {
        let v = self.max_rim_speed() / 100.0;
        Twist {
            vx: c.vx * v,
            vy: c.vy * v / self.roller_tan,
            omega: c.omega * self.mixing_k * v / self.rotation_arm(),
        }
    }

    /// The percent command that asks the board for `t` (inverse of [`Self::percent_to_twist`];
    /// not clamped: values beyond ±100 will saturate on the wire).
    pub fn twist_to_percent(&self, t: Twist) -> PercentCommand {
        let v = self.max_rim_speed() / 100.0;
        PercentCommand {
            vx: t.vx / v,
            vy: t.vy * self.roller_tan / v,
            omega: t.omega * self.rotation_arm() / (self.mixing_k * v),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn kin() -> MecanumKinematics {
        MecanumKinematics::from_profile(&RobotProfile::default())
    }

    fn assert_close4(a: [f32; 4], b: [f32; 4], tol: f32) {
        for i in 0..4 {
            assert!((a[i] - b[i]).abs() <= tol, "wheel {i}: {a:?} vs {b:?}");
        }
    }

    #[test]
    fn pure_forward_turns_all_wheels_equally() {
        // 0.39 m/s on r = 0.039 m: 10 rad/s on every wheel.
        assert_close4(kin().inverse(Twist::new(0.39, 0.0, 0.0)), [10.0; 4], 1e-4);
    }

    #[test]
    fn strafe_left_turns_fl_rr_backwards() {
        // vy = 0.39 m/s left, tan 45° = 1: FL −10, FR +10, RL +10, RR −10 rad/s.
        assert_close4(kin().inverse(Twist::new(0.0, 0.39, 0.0)), [-10.0, 10.0, 10.0, -10.0], 1e-4);
    }

    #[test]
    fn spin_ccw_turns_left_wheels_backwards() {
        // ω = 1 rad/s, L = 0.09 + 0.10 = 0.19 m: rim speed 0.19 m/s → 0.19/0.039 = 4.871795 rad/s.
        let w = 0.19 / 0.039;
        assert!((kin().rotation_arm() - 0.19).abs() < 1e-6);
        assert_close4(kin().inverse(Twist::new(0.0, 0.0, 1.0)), [-w, w, -w, w], 1e-4);
    }

    #[test]
    fn combination_adds_term_by_term() {
        // vx 0.39, vy −0.195, ω 0.5: rim = [0.39+0.195−0.095, 0.39−0.195+0.095, 0.39−0.195−0.095, 0.39+0.195+0.095]
        let rim = [0.49f32, 0.29, 0.1, 0.68];
        assert_close4(kin().inverse(Twist::new(0.39, -0.195, 0.5)), rim.map(|v| v / 0.039), 1e-3);
    }

    #[test]
    fn firmware_mixing_matches_inverse_kinematics_signs() {
        // At k = 1 and 45° rollers, mixing a percent command equals the inverse kinematics of
        // the twist that command means, expressed in percent of max rim speed.
        let k = kin();
        let c = PercentCommand { vx: 20.0, vy: -15.0, omega: 30.0 };
        let mixed = mix_percent(c.vx, c.vy, c.omega, 1.0);
        let wheel_rad_s = k.inverse(k.percent_to_twist(c));
        let as_percent = wheel_rad_s.map(|w| w * k.wheel_radius / k.max_rim_speed() * 100.0);
        assert_close4(mixed, as_percent, 1e-3);
    }

    #[test]
    fn mixing_hand_values() {
        assert_eq!(mix_percent(50.0, 0.0, 0.0, 1.0), [50.0; 4]);
        assert_eq!(mix_percent(0.0, 40.0, 0.0, 1.0), [-40.0, 40.0, 40.0, -40.0]);
        assert_eq!(mix_percent(0.0, 0.0, 30.0, 1.0), [-30.0, 30.0, -30.0, 30.0]);
        assert_eq!(mix_percent(0.0, 0.0, 30.0, 0.0), [0.0; 4]); // Arduino firmware: k = 0
        assert_eq!(mix_percent(50.0, -20.0, 10.0, 1.0), [60.0, 40.0, 20.0, 80.0]);
    }

    #[test]
    fn saturation_scales_all_four_together() {
        // raw: FL 100−50−50 = 0, FR 200, RL 100, RR 100 → ×0.5
        assert_eq!(mix_percent(100.0, 50.0, 50.0, 1.0), [0.0, 100.0, 50.0, 50.0]);
        // raw: FL 0+50−100 = −50, FR −50+100 = 50, RL −50−100 = −150, RR 50+100 = 150 → ×2/3
        assert_close4(mix_percent(0.0, -50.0, 100.0, 1.0), [-33.333_336, 33.333_336, -100.0, 100.0], 1e-4);
        assert_eq!(mix_percent(f32::NAN, 10.0, f32::INFINITY, 1.0), [-10.0, 10.0, 10.0, -10.0]);
    }

    #[test]
    fn percent_twist_scale() {
        let k = kin();
        let t = k.percent_to_twist(PercentCommand { vx: 100.0, vy: 0.0, omega: 100.0 });
        assert!((t.vx - 1.225_221).abs() < 1e-4);
        assert!((t.omega - 1.225_221 / 0.19).abs() < 1e-3);
    }

    proptest! {
        #[test]
        fn forward_inverts_inverse(vx in -2.0f32..2.0, vy in -2.0f32..2.0, w in -8.0f32..8.0) {
            let k = kin();
            let t = k.forward(k.inverse(Twist::new(vx, vy, w)));
            prop_assert!((t.vx - vx).abs() < 1e-4 && (t.vy - vy).abs() < 1e-4 && (t.omega - w).abs() < 1e-3,
                "{t:?} vs {vx} {vy} {w}");
        }

        #[test]
        fn percent_twist_round_trip(vx in -100.0f32..100.0, vy in -100.0f32..100.0, w in -100.0f32..100.0) {
            let k = kin();
            let c = k.twist_to_percent(k.percent_to_twist(PercentCommand { vx, vy, omega: w }));
            prop_assert!((c.vx - vx).abs() < 1e-3 && (c.vy - vy).abs() < 1e-3 && (c.omega - w).abs() < 1e-3);
        }

        #[test]
        fn mixing_never_exceeds_100(vx in -100.0f32..100.0, vy in -100.0f32..100.0, w in -100.0f32..100.0) {
            let m = mix_percent(vx, vy, w, 1.0);
            prop_assert!(m.iter().all(|v| v.abs() <= 100.0 + 1e-3));
        }
    }
}
