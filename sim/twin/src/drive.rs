//! Mecanum wheels on the floor: how wheel spin becomes force on the robot's body.
//!
//! Each wheel touches the floor through free-spinning rollers set at ±45°. A roller rolls freely
//! across its own axis but cannot slide along it, so at each wheel only one direction carries
//! force: the roller axis `a`. With the wheel turning at `ω` (rim speed `r·ω` along the body's
//! `+x`), the floor under the wheel "wants" the contact point to move at `r·ω·cos α` along `a`.
//! The difference is the **slip** `s = v_contact·a − r·ω·cos α`, and the floor pushes back with
//! `F = −k·s` along `a`, limited to `μ·N` with `N = m·g/4` (the wheel's share of the weight).
//! Beyond that limit the wheel slides: wheel slip, spinning against a wall, and losing grip on a
//! slippery floor all come out of the same rule. A small viscous term across `a` stands for the
//! rollers' bearing friction (small: the four roller axes already pin down all three degrees of
//! freedom of the body, so nothing else is needed for stability).
//!
//! Roller angles, X configuration, body frame (`x` forward, `y` left): FL −45°, FR +45°,
//! RL +45°, RR −45°. With these, `r·ω` per wheel equals the board's mixing
//! (FL = vx − vy − k·ω, FR = vx + vy + k·ω, RL = vx + vy − k·ω, RR = vx − vy + k·ω) for `vy` to the
//! left and `ω` counter-clockwise — the same convention as the drive v2 frame.
//!
//! `k` is chosen so that one step removes half a wheel's slip on its own (`k = 0.5·(m/4)/dt`),
//! capped so that the stiffest mode of the body stays stable. With four wheels the slip decays in
//! three modes — along x (`4cos²α/m`), along y (`4sin²α/m`) and in yaw
//! (`4(lx·sin α + ly·cos α)²/I`, with `I` the body's moment of inertia) — and an explicit step is
//! stable while `k·dt·λ < 2` for each; `k ≤ 1/(dt·λ_max)` keeps a factor 2 of margin for any body
//! shape and step size (for the default robot the cap is 46 N·s/m and the rule gives 40).

use robot_model::profile::RobotProfile;

use crate::world::SimWorld;

const GRAVITY: f32 = 9.81;

/// Rolling resistance of a wheel's rollers across the roller axis, N per m/s (a small bearing
/// friction: at 1 m/s sideways roll it costs 0.05 N per wheel).
const ROLLER_DAMPING: f32 = 0.05;

/// Order of wheels everywhere: front left, front right, rear left, rear right.
pub const WHEEL_NAMES: [&str; 4] = ["FL", "FR", "RL", "RR"];

#[derive(Debug, Clone, Copy)]
struct Wheel {
    /// Contact point, body frame, metres.
    x: f32,
    y: f32,
    /// Roller axis, body frame, unit vector.
    ax: f32,
    ay: f32,
    /// cos of the roller angle.
    cos_alpha: f32,
}

/// The force model of the four mecanum wheels.
#[derive(Debug, Clone)]
pub struct DriveTrain {
    wheels: [Wheel; 4],
    radius: f32,
    max_force: f32,
    slip_gain: f32,
    roller_damping: f32,
}

impl DriveTrain {
    /// The drive train of `profile`, tuned for steps of `dt` seconds.
    pub fn new(profile: &RobotProfile, dt: f32) -> DriveTrain {
        let g = &profile.geometry;
        let lx = g.wheelbase_m * 0.5;
        let ly = g.track_m * 0.5;
        let alpha = profile.wheels.roller_angle_deg.to_radians();
        let wheel = |x: f32, y: f32, sign: f32| {
            let a = sign * alpha;
            Wheel { x, y, ax: a.cos(), ay: a.sin(), cos_alpha: a.cos() }
        };
        let mass = g.mass_kg;
        let dt = dt.max(1e-4);
        // The body is a uniform box (as the collider): I = m·(L² + W²)/12.
        let inertia = mass * (g.body_length_m.powi(2) + g.body_width_m.powi(2)) / 12.0;
        let (sin, cos) = (alpha.sin().abs(), alpha.cos().abs());
        let lambda =
            [4.0 * cos * cos / mass, 4.0 * sin * sin / mass, 4.0 * (lx * sin + ly * cos).powi(2) / inertia];
        let lambda_max = lambda.into_iter().fold(0.0f32, f32::max);
        DriveTrain {
            wheels: [wheel(lx, ly, -1.0), wheel(lx, -ly, 1.0), wheel(-lx, ly, 1.0), wheel(-lx, -ly, -1.0)],
            radius: g.wheel_radius_m,
            max_force: profile.wheels.friction_mu * mass * GRAVITY / 4.0,
            slip_gain: (0.5 * (mass / 4.0) / dt).min(1.0 / (dt * lambda_max)),
            roller_damping: ROLLER_DAMPING,
        }
    }

    /// Applies the floor's reaction to wheels turning at `omega` (rad/s, positive = rolling
    /// forward) for the coming step. Call after [`SimWorld::reset_robot_forces`].
    pub fn apply(&mut self, world: &mut SimWorld, omega: [f32; 4]) {
        let theta = world.robot_pose().theta;
        let (sin, cos) = theta.sin_cos();
        for (i, w) in self.wheels.iter().enumerate() {
            let (vwx, vwy) = world.robot_point_velocity(w.x, w.y);
            // Contact velocity in the body frame.
            let vbx = cos * vwx + sin * vwy;
            let vby = -sin * vwx + cos * vwy;
            let along = vbx * w.ax + vby * w.ay;
            let across = -vbx * w.ay + vby * w.ax;
            let slip = along - self.radius * omega[i] * w.cos_alpha;
            let f_along = (-self.slip_gain * slip).clamp(-self.max_force, self.max_force);
            let f_across = -self.roller_damping * across;
            // Back to body, then world frame.
            let fbx = f_along * w.ax - f_across * w.ay;
            let fby = f_along * w.ay + f_across * w.ax;
            let fx = cos * fbx - sin * fby;
            let fy = sin * fbx + cos * fby;
            world.add_robot_force(w.x, w.y, fx, fy);
        }
    }
}
