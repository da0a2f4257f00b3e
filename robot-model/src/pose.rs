//! Planar poses and body twists.
//!
//! **Conventions** (shared by the simulator, Carto and the board twins):
//! - *World frame*: metres, `x` to the right, `y` up, `theta` counter-clockwise from `+x`, in
//!   radians. This is the usual right-handed top-down frame; the simulator draws it this way.
//! - *Body frame*: origin at the chassis centre, `x` forward, `y` to the left, rotation
//!   counter-clockwise. A [`Twist`] is always expressed in the body frame.
//! - Scalars are `f32`, the type the physics engine uses, so values cross the boundary without
//!   conversion. Cumulative quantities that would lose precision in `f32` over a long run (wheel
//!   angles for the encoders) are `f64` in their own modules.
//!
//! Invariant: functions that return an angle return it wrapped to `(-π, π]` (see [`wrap_angle`]),
//! except [`Pose2::new`], which stores what it is given.
//!
//! ```
//! use robot_model::pose::{Pose2, Twist};
//! use core::f32::consts::FRAC_PI_2;
//! // Facing +y (up), driving forward at 1 m/s for 1 s moves the robot 1 m up.
//! let start = Pose2::new(0.0, 0.0, FRAC_PI_2);
//! let end = start.integrate(Twist::new(1.0, 0.0, 0.0), 1.0);
//! assert!((end.x - 0.0).abs() < 1e-6 && (end.y - 1.0).abs() < 1e-6);
//! // A point 0.13 m ahead of the robot, in world coordinates:
//! let (px, py) = end.transform_point(0.13, 0.0);
//! assert!((py - 1.13).abs() < 1e-6 && px.abs() < 1e-6);
//! ```

use core::f32::consts::{PI, TAU};

use serde::{Deserialize, Serialize};

/// A pose in the world frame: position in metres, heading in radians CCW from `+x`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Pose2 {
    /// Position along world `+x` (right), metres.
    pub x: f32,
    /// Position along world `+y` (up), metres.
    pub y: f32,
    /// Heading, radians, counter-clockwise from world `+x`.
    pub theta: f32,
}

/// A body-frame velocity: forward and leftward speed (m/s) and yaw rate (rad/s, CCW positive).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Twist {
    /// Forward speed along body `+x`, m/s.
    pub vx: f32,
    /// Leftward speed along body `+y`, m/s.
    pub vy: f32,
    /// Yaw rate, rad/s, counter-clockwise positive.
    pub omega: f32,
}

/// Wraps an angle to `(-π, π]`.
pub fn wrap_angle(a: f32) -> f32 {
    if !a.is_finite() {
        return a;
    }
    let mut w = a.rem_euclid(TAU); // [0, 2π)
    if w > PI {
        w -= TAU;
    }
    w
}

/// Wraps an angle in degrees to `[0, 360)`.
pub fn wrap_degrees_360(d: f32) -> f32 {
    if !d.is_finite() {
        return d;
    }
    let w = d.rem_euclid(360.0);
    // rem_euclid can round up to exactly 360.0 for tiny negative inputs
    if w >= 360.0 { 0.0 } else { w }
}

impl Pose2 {
    /// The world origin, facing `+x`.
    pub const ORIGIN: Pose2 = Pose2 { x: 0.0, y: 0.0, theta: 0.0 };

    /// A pose at `(x, y)` metres with heading `theta` radians (CCW from `+x`).
    pub const fn new(x: f32, y: f32, theta: f32) -> Self {
        Pose2 { x, y, theta }
    }

    /// The unit vector the robot faces, in world coordinates.
    pub fn heading_vector(&self) -> (f32, f32) {
        (self.theta.cos(), self.theta.sin())
    }

    /// Maps a body-frame point (`bx` forward, `by` left) to world coordinates.
    pub fn transform_point(&self, bx: f32, by: f32) -> (f32, f32) {
        let (s, c) = self.theta.sin_cos();
        (self.x + c * bx - s * by, self.y + s * bx + c * by)
    }

    /// Maps a body-frame vector (no translation) to world coordinates.
    pub fn rotate_vector(&self, bx: f32, by: f32) -> (f32, f32) {
        let (s, c) = self.theta.sin_cos();
        (c * bx - s * by, s * bx + c * by)
    }

    /// Composes `self ∘ other`: `other` is a pose expressed in `self`'s body frame.
    pub fn compose(&self, other: &Pose2) -> Pose2 {
        let (x, y) = self.transform_point(other.x, other.y);
        Pose2 { x, y, theta: wrap_angle(self.theta + other.theta) }
    }

    /// Moves the pose by a constant body twist held for `dt` seconds (exact arc integration).
    pub fn integrate(&self, twist: Twist, dt: f32) -> Pose2 {
        let dth = twist.omega * dt;
        // Body-frame displacement of a constant twist: V(dθ) · v · dt (SE(2) exponential).
        let (a, b) = if dth.abs() < 1e-6 {
            (1.0 - dth * dth / 6.0, dth / 2.0)
        } else {
            (dth.sin() / dth, (1.0 - dth.cos()) / dth)
        };
        let dx = (a * twist.vx - b * twist.vy) * dt;
        let dy = (b * twist.vx + a * twist.vy) * dt;
        let (wx, wy) = self.rotate_vector(dx, dy);
        Pose2 { x: self.x + wx, y: self.y + wy, theta: wrap_angle(self.theta + dth) }
    }
}

impl Twist {
    /// A zero twist.
    pub const ZERO: Twist = Twist { vx: 0.0, vy: 0.0, omega: 0.0 };

    /// A twist: `vx` forward and `vy` left in m/s, `omega` CCW in rad/s.
    pub const fn new(vx: f32, vy: f32, omega: f32) -> Self {
        Twist { vx, vy, omega }
    }

    /// The linear part rotated into the world frame for a robot at heading `theta`.
    pub fn world_velocity(&self, theta: f32) -> (f32, f32) {
        let (s, c) = theta.sin_cos();
        (c * self.vx - s * self.vy, s * self.vx + c * self.vy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::FRAC_PI_2;

    fn close(a: f32, b: f32) -> bool {
        (a - b).abs() < 1e-5
    }

    #[test]
    fn wrap_angle_lands_in_half_open_interval() {
        assert!(close(wrap_angle(3.0 * PI), PI));
        assert!(close(wrap_angle(-PI), PI));
        assert!(close(wrap_angle(-FRAC_PI_2), -FRAC_PI_2));
        assert!(close(wrap_angle(TAU + 0.25), 0.25));
        assert_eq!(wrap_degrees_360(-90.0), 270.0);
        assert_eq!(wrap_degrees_360(720.5), 0.5);
        assert!(wrap_degrees_360(-1e-9) < 360.0);
    }

    #[test]
    fn body_left_is_world_up_when_facing_right() {
        let p = Pose2::ORIGIN;
        let (x, y) = p.transform_point(0.0, 1.0);
        assert!(close(x, 0.0) && close(y, 1.0));
        let q = p.integrate(Twist::new(0.0, 0.5, 0.0), 2.0);
        assert!(close(q.x, 0.0) && close(q.y, 1.0) && close(q.theta, 0.0));
    }

    #[test]
    fn quarter_turn_arc_ends_on_the_circle() {
        // v = 1 m/s, ω = π/2 rad/s for 1 s: a quarter circle of radius 2/π, CCW.
        let r = 2.0 / PI;
        let q = Pose2::ORIGIN.integrate(Twist::new(1.0, 0.0, FRAC_PI_2), 1.0);
        assert!(close(q.x, r) && close(q.y, r) && close(q.theta, FRAC_PI_2), "{q:?}");
    }

    #[test]
    fn compose_applies_rotation_then_translation() {
        let a = Pose2::new(1.0, 2.0, FRAC_PI_2);
        let b = Pose2::new(0.5, 0.0, FRAC_PI_2);
        let c = a.compose(&b);
        assert!(close(c.x, 1.0) && close(c.y, 2.5) && close(c.theta, PI), "{c:?}");
    }
}
