//! The pose estimator: an extended Kalman filter over the robot's position, heading and the
//! gyro's bias (style rule 17: a motion model and a sensor model, each a small part; the filter
//! itself knows neither's details).
//!
//! Why a Kalman filter and not particles: Carto starts from a pose Cute gives (no global
//! localisation to solve), its one sonar gives one range at a time, and the Pi's 60 ms cycle
//! favours a 4 × 4 update over hundreds of ray casts. A particle filter earns its cost when the
//! belief has several modes; here it has one, widened by slips and touches.
//!
//! Contract:
//! - **State** `[x, y, θ, b]`: metres in Carto's frame ([`Pose2`]), θ counter-clockwise from
//!   east in radians, `b` the gyro's bias in rad/s. [`PoseFilter::mean`] is Carto's belief.
//! - **Predict** ([`PoseFilter::predict`]) from the wheels' displacement in the body frame (along,
//!   left) and the gyro's turn over `dt`, less the bias. The noise grows per motion component,
//!   as AMCL's omni model does: along and across with the distance driven (mecanum rollers slip
//!   sideways), the heading with the turn and with time (gyro noise), the bias as a random walk.
//! - **Correct** ([`PoseFilter::correct_range`]) from a sonar range against the evidence grid:
//!   the range expected along the sonar's axis to the first occupied cell, and its derivatives
//!   from the surface's normal there (the principal axis of the occupied cells round the hit).
//!   A range more than [`GATE_SIGMAS`] standard deviations from the expected one is rejected
//!   (another object, or an echo from the cone's edge), and so is a surface met at a grazing
//!   angle (the echo would be lost: [`MAX_INCIDENCE_DEG`]).
//! - **Correct against an earlier pose** ([`PoseFilter::correct_position_since`]): a range to a
//!   surface placed from an earlier pose measures the motion since then, not the position; only
//!   the variance added since is corrected (stochastic cloning, the correlation taken whole).
//! - **Widen** ([`PoseFilter::widen`]) after a touch, a push or a stall: the body moved in a way
//!   the wheels did not see.
//!
//! ```
//! use carto::estimate::grid::{EvidenceGrid, GridParams};
//! use carto::estimate::pose::{MotionNoise, PoseFilter, RangeUpdate};
//! use carto::surroundings::Pose2;
//! let mut grid = EvidenceGrid::new(GridParams::default());
//! grid.pin_segment((1.2, -1.0), (1.2, 1.0)); // a wall across, 1.2 m east
//! let mut f = PoseFilter::new(Pose2 { x: 0.0, y: 0.0, yaw_deg: 0.0 }, 0.03, 0.5);
//! f.predict(0.45, 0.0, 0.0, 1.5, &MotionNoise::default()); // the wheels say 45 cm
//! // the body really went 50 cm: the sonar, 13 cm ahead of the centre, reads 57 cm
//! let update = f.correct_range(&grid, 0.13, 0.57, 0.003);
//! assert!(matches!(update, RangeUpdate::Applied { .. }));
//! assert!((f.mean().x - 0.50).abs() < 0.02, "{}", f.mean().x);
//! ```

use nalgebra::{Matrix4, RowVector4, Vector4};

use super::grid::EvidenceGrid;
use crate::surroundings::Pose2;

/// A vector in the plane, metres or unitless: `(x, y)`.
type Vec2 = (f64, f64);

/// A range further from the expected one than this many standard deviations is rejected.
pub const GATE_SIGMAS: f64 = 3.0;
/// A surface met more than this far from head-on gives no correction, degrees: the HC-SR04
/// loses echoes past about 22.5° (the default profile's incidence limit); 60° keeps the ones
/// whose expected range is still well defined.
pub const MAX_INCIDENCE_DEG: f64 = 60.0;

/// A cell at or above this evidence is a surface the filter expects echoes from, log-odds
/// (p 0.62): two readings that agree on it. Lower than the grid's "occupied" (which the safety
/// checks act on): a range compared with a surface that is not there is gated out, while a
/// surface heard from afar takes several readings to reach "occupied".
pub const SURFACE_LOG_ODDS: f64 = 0.85;

/// A run of occupied cells along a ray deeper than this is taken as this deep (a thick piece
/// of furniture): the surface is at the middle of at most this much, metres.
pub const MAX_SURFACE_DEPTH_M: f64 = 0.06;

/// The standard deviation of the gyro bias before anything is learnt of it, degrees per second.
pub const INITIAL_BIAS_SIGMA_DEG_PER_S: f64 = 0.05;

/// How much each motion component adds to the uncertainty.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionNoise {
    /// Along-track standard deviation per metre driven.
    pub along_per_m: f64,
    /// Sideways standard deviation per metre driven (roller slip).
    pub across_per_m: f64,
    /// Heading standard deviation per radian turned.
    pub turn_per_rad: f64,
    /// Gyro heading noise, rad per √s.
    pub gyro_rad_per_sqrt_s: f64,
    /// Bias random walk, rad/s per √s.
    pub bias_walk: f64,
}

impl Default for MotionNoise {
    /// The default robot: 1 % along (the odometry's σ over a cell), 1.2 % across (measured in
    /// the twin, `docs/journal/world-model.md`, "Round 4"), 2 % of a turn, 0.1° per √s of gyro
    /// noise, a bias that wanders 0.01°/s per √s.
    fn default() -> Self {
        MotionNoise {
            along_per_m: 0.01,
            across_per_m: 0.012,
            turn_per_rad: 0.02,
            gyro_rad_per_sqrt_s: 0.1f64.to_radians(),
            bias_walk: 0.01f64.to_radians(),
        }
    }
}

/// What one range did to the estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RangeUpdate {
    /// The estimate moved by the gain times `innovation` (measured − expected, metres).
    Applied {
        /// Measured minus expected range, metres.
        innovation: f64,
    },
    /// Too far from the expected range (`sigmas` standard deviations): not used.
    Rejected {
        /// The innovation in standard deviations.
        sigmas: f64,
    },
    /// No occupied cell along the axis up to the range measured (and its uncertainty): what
    /// answered is not on the map. Or the surface is met too obliquely.
    NoSurface,
}

/// The filter (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct PoseFilter {
    state: Vector4<f64>,
    cov: Matrix4<f64>,
}

impl PoseFilter {
    /// A filter at `pose`, with position and heading standard deviations `sigma_xy_m` and
    /// `sigma_deg`, and a bias of 0 known to [`INITIAL_BIAS_SIGMA_DEG_PER_S`].
    pub fn new(pose: Pose2, sigma_xy_m: f64, sigma_deg: f64) -> Self {
        let state = Vector4::new(pose.x, pose.y, pose.yaw_deg.to_radians(), 0.0);
        let cov = Matrix4::from_diagonal(&Vector4::new(
            sigma_xy_m.powi(2),
            sigma_xy_m.powi(2),
            sigma_deg.to_radians().powi(2),
            INITIAL_BIAS_SIGMA_DEG_PER_S.to_radians().powi(2),
        ));
        PoseFilter { state, cov }
    }

    /// The mean: Carto's belief.
    pub fn mean(&self) -> Pose2 {
        Pose2 { x: self.state[0], y: self.state[1], yaw_deg: self.state[2].to_degrees() }
    }

    /// The gyro bias estimate, degrees per second.
    pub fn bias_deg_per_s(&self) -> f64 {
        self.state[3].to_degrees()
    }

    /// The covariance of `[x, y, θ, b]` (metres, radians).
    pub fn covariance(&self) -> &Matrix4<f64> {
        &self.cov
    }

    /// The standard deviation of the position along `yaw_deg`, metres.
    pub fn sigma_along(&self, yaw_deg: f64) -> f64 {
        let (s, c) = yaw_deg.to_radians().sin_cos();
        let p = &self.cov;
        (c * c * p[(0, 0)] + 2.0 * s * c * p[(0, 1)] + s * s * p[(1, 1)]).max(0.0).sqrt()
    }

    /// Moves the estimate by the wheels' displacement `along`, `left` (body frame, metres) and
    /// the gyro's turn `gyro_turn_rad` over `dt_s`, less the bias, and grows the covariance.
    pub fn predict(&mut self, along: f64, left: f64, gyro_turn_rad: f64, dt_s: f64, noise: &MotionNoise) {
        let dt = dt_s.max(0.0);
        let (theta, bias) = (self.state[2], self.state[3]);
        let turn = gyro_turn_rad - bias * dt;
        let mid = theta + turn / 2.0;
        let (s, c) = mid.sin_cos();
        let dx = along * c - left * s;
        let dy = along * s + left * c;
        // d(dx, dy)/d(mid); mid depends on θ (1) and on b (−dt/2)
        let (dx_dmid, dy_dmid) = (-along * s - left * c, along * c - left * s);
        let f = Matrix4::new(
            1.0,
            0.0,
            dx_dmid,
            -dt / 2.0 * dx_dmid, //
            0.0,
            1.0,
            dy_dmid,
            -dt / 2.0 * dy_dmid, //
            0.0,
            0.0,
            1.0,
            -dt, //
            0.0,
            0.0,
            0.0,
            1.0,
        );
        self.state += Vector4::new(dx, dy, turn, 0.0);
        let dist = along.hypot(left);
        let var_along = (noise.along_per_m * dist).powi(2);
        let var_across = (noise.across_per_m * dist).powi(2);
        // body-frame noise into the world frame
        let q_xx = c * c * var_along + s * s * var_across;
        let q_yy = s * s * var_along + c * c * var_across;
        let q_xy = s * c * (var_along - var_across);
        let var_turn = (noise.turn_per_rad * turn).powi(2) + noise.gyro_rad_per_sqrt_s.powi(2) * dt;
        let q = Matrix4::new(
            q_xx,
            q_xy,
            0.0,
            0.0, //
            q_xy,
            q_yy,
            0.0,
            0.0, //
            0.0,
            0.0,
            var_turn,
            0.0, //
            0.0,
            0.0,
            0.0,
            noise.bias_walk.powi(2) * dt,
        );
        self.cov = f * self.cov * f.transpose() + q;
    }

    /// Widens the position by `sigma_xy_m` and the heading by `sigma_deg` (a touch, a push, a
    /// stall: the body moved in a way the wheels did not see).
    pub fn widen(&mut self, sigma_xy_m: f64, sigma_deg: f64) {
        self.cov[(0, 0)] += sigma_xy_m.powi(2);
        self.cov[(1, 1)] += sigma_xy_m.powi(2);
        self.cov[(2, 2)] += sigma_deg.to_radians().powi(2);
    }

    /// Corrects the estimate from the sonar's range `range_m` (σ `sigma_m`), the sonar mounted
    /// `mount_m` ahead of the body's centre on its axis, against `grid`, looking along the axis
    /// only (see the module docs).
    pub fn correct_range(
        &mut self,
        grid: &EvidenceGrid,
        mount_m: f64,
        range_m: f64,
        sigma_m: f64,
    ) -> RangeUpdate {
        let axis = Fan { ray_offsets_deg: &[0.0], incidence_limit_deg: MAX_INCIDENCE_DEG };
        self.correct_echo(grid, mount_m, &axis, range_m, sigma_m)
    }

    /// Corrects the estimate from an echo at `range_m` (σ `sigma_m`) of a sonar mounted `mount_m`
    /// ahead of the body's centre, whose cone `fan` samples: the expected range is the nearest
    /// surface any ray of the fan meets within the incidence limit, as the sonar hears the
    /// nearest audible echo in its cone; the derivatives are those of that ray.
    pub fn correct_echo(
        &mut self,
        grid: &EvidenceGrid,
        mount_m: f64,
        fan: &Fan,
        range_m: f64,
        sigma_m: f64,
    ) -> RangeUpdate {
        let theta = self.state[2];
        let axis = (theta.cos(), theta.sin());
        let max_m = range_m + GATE_SIGMAS * (sigma_m + self.sigma_along(theta.to_degrees())) + 0.1;
        let Some((expected, u, normal, facing)) = nearest_echo(grid, self.mean(), mount_m, fan, max_m) else {
            return RangeUpdate::NoSurface;
        };
        // r = n·(p0 − s)/(n·u) with s = (x, y) + m·axis: the derivatives for a plane through the
        // hit; turning the body turns both the mount and the ray
        let n_perp = |v: (f64, f64)| normal.0 * -v.1 + normal.1 * v.0;
        let h = RowVector4::new(
            normal.0 / facing,
            normal.1 / facing,
            (mount_m * n_perp(axis) + expected * n_perp(u)) / facing,
            0.0,
        );
        self.update(h, range_m - expected, sigma_m)
    }

    /// Corrects the estimate from a measurement of the position along the unit vector `u` that
    /// was made *relative to an earlier pose*: `measured_m` is the depth of a surface placed from
    /// that pose (whose position along `u` then had variance `earlier_var_m2`), less the range to
    /// it now, with standard deviation `sigma_m` (the two readings' noise).
    ///
    /// The surface's depth carries the earlier pose's error, and so does the estimate now: only
    /// the variance added since (the motion, a touch) is seen by this measurement, the rest
    /// cancels. This is the update of stochastic cloning (the earlier pose kept as a state,
    /// correlated with the current one) with the correlation taken as all of the earlier
    /// variance: the gain along `u` is `added / (added + σ²)` with `added` the along-`u`
    /// variance now less `earlier_var_m2`, and the variance left along `u` never falls below
    /// the earlier one. Treated as an absolute position instead, every fix would count the
    /// earlier uncertainty as news and pull the belief by too much. Gated on the same
    /// innovation variance.
    pub fn correct_position_since(
        &mut self,
        u: (f64, f64),
        measured_m: f64,
        sigma_m: f64,
        earlier_var_m2: f64,
    ) -> RangeUpdate {
        let h = RowVector4::new(u.0, u.1, 0.0, 0.0);
        let innovation = measured_m - (u.0 * self.state[0] + u.1 * self.state[1]);
        let now_var = self.variance_along(u);
        let added = (now_var - earlier_var_m2.max(0.0)).max(0.0);
        let s = added + sigma_m.powi(2);
        if s <= 0.0 || now_var <= 0.0 {
            return RangeUpdate::NoSurface;
        }
        let sigmas = innovation.abs() / s.sqrt();
        if sigmas > GATE_SIGMAS {
            return RangeUpdate::Rejected { sigmas };
        }
        let k = self.cov * h.transpose() * (added / now_var) / s;
        self.state += k * innovation;
        self.cov -= k * k.transpose() * s;
        self.cov = 0.5 * (self.cov + self.cov.transpose());
        RangeUpdate::Applied { innovation }
    }

    /// The variance of the position along the unit vector `u`, square metres.
    pub fn variance_along(&self, u: (f64, f64)) -> f64 {
        let p = &self.cov;
        (u.0 * u.0 * p[(0, 0)] + 2.0 * u.0 * u.1 * p[(0, 1)] + u.1 * u.1 * p[(1, 1)]).max(0.0)
    }

    /// The Kalman update with measurement row `h` and `innovation`, gated at [`GATE_SIGMAS`].
    fn update(&mut self, h: RowVector4<f64>, innovation: f64, sigma_m: f64) -> RangeUpdate {
        let s = (h * self.cov * h.transpose())[(0, 0)] + sigma_m.powi(2);
        let sigmas = innovation.abs() / s.sqrt();
        if sigmas > GATE_SIGMAS {
            return RangeUpdate::Rejected { sigmas };
        }
        let k = self.cov * h.transpose() / s;
        self.state += k * innovation;
        // Joseph form: stays symmetric and positive
        let i_kh = Matrix4::identity() - k * h;
        self.cov = i_kh * self.cov * i_kh.transpose() + k * k.transpose() * sigma_m.powi(2);
        RangeUpdate::Applied { innovation }
    }

    /// Takes the heading from outside: `yaw_deg` known to `sigma_deg`, uncorrelated with the
    /// position and the bias (Carto's heading is the IMU's, its drift tracked elsewhere).
    pub fn set_heading(&mut self, yaw_deg: f64, sigma_deg: f64) {
        self.state[2] = yaw_deg.to_radians();
        for k in 0..4 {
            self.cov[(2, k)] = 0.0;
            self.cov[(k, 2)] = 0.0;
        }
        self.cov[(2, 2)] = sigma_deg.to_radians().powi(2);
    }

    /// Moves the mean to `pose` and keeps the covariance and the bias: the caller's dead
    /// reckoning, which already holds every correction made, is the mean between corrections.
    pub fn set_mean(&mut self, pose: Pose2) {
        self.state[0] = pose.x;
        self.state[1] = pose.y;
        self.state[2] = pose.yaw_deg.to_radians();
    }
}

/// The rays that sample a sonar's cone and the incidence past which a surface is silent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fan<'a> {
    /// Each ray's angle from the sonar's axis, counter-clockwise degrees.
    pub ray_offsets_deg: &'a [f64],
    /// A surface met further than this from head-on returns no echo, degrees.
    pub incidence_limit_deg: f64,
}

/// The echo the grid's surfaces would return to a sonar mounted `mount_m` ahead of a body at
/// `robot`, its fan's rays cast to `max_m`: the nearest surface a ray meets within the incidence
/// limit, as (range, the ray's unit vector, the surface's normal, the cos of the incidence).
fn nearest_echo(
    grid: &EvidenceGrid,
    robot: Pose2,
    mount_m: f64,
    fan: &Fan,
    max_m: f64,
) -> Option<(f64, Vec2, Vec2, f64)> {
    let theta = robot.yaw_deg.to_radians();
    let sensor = (robot.x + mount_m * theta.cos(), robot.y + mount_m * theta.sin());
    let cos_limit = fan.incidence_limit_deg.min(MAX_INCIDENCE_DEG).to_radians().cos();
    let mut nearest: Option<(f64, Vec2, Vec2, f64)> = None;
    for offset in fan.ray_offsets_deg {
        let ray = theta + offset.to_radians();
        let u = (ray.cos(), ray.sin());
        let Some((expected, hit)) = first_occupied(grid, sensor, u, max_m) else { continue };
        if nearest.is_some_and(|(d, ..)| d <= expected) {
            continue;
        }
        let normal = surface_normal(grid, hit, u);
        let facing = -(normal.0 * u.0 + normal.1 * u.1);
        if facing >= cos_limit {
            nearest = Some((expected, u, normal, facing));
        }
    }
    nearest
}

/// The range the grid's surfaces would return to a sonar mounted `mount_m` ahead of a body at
/// `robot` ([`PoseFilter::correct_echo`]'s expectation), up to `max_m`; `None` for no echo.
pub fn expected_range(grid: &EvidenceGrid, robot: Pose2, mount_m: f64, fan: &Fan, max_m: f64) -> Option<f64> {
    nearest_echo(grid, robot, mount_m, fan, max_m).map(|(range, ..)| range)
}

/// The distance along `u` from `from` to the first surface within `max_m`, and a point on it:
/// the middle of the first run of occupied cells the ray crosses (a wall's cells, or the band
/// an echo marked), so that a surface seen from where it was mapped is expected where it was
/// heard, not a half band short. Marched in quarter cells.
fn first_occupied(
    grid: &EvidenceGrid,
    from: (f64, f64),
    u: (f64, f64),
    max_m: f64,
) -> Option<(f64, (f64, f64))> {
    let step = grid.params().resolution_m / 4.0;
    let at = |d: f64| (from.0 + d * u.0, from.1 + d * u.1);
    let occupied = |d: f64| {
        let p = at(d);
        grid.log_odds(grid.cell_of(p.0, p.1)) >= SURFACE_LOG_ODDS
    };
    let mut d = 0.0;
    while d <= max_m && !occupied(d) {
        d += step;
    }
    if d > max_m {
        return None;
    }
    let entry = d;
    while d - entry < MAX_SURFACE_DEPTH_M && occupied(d + step) {
        d += step;
    }
    let middle = 0.5 * (entry + d);
    Some((middle, at(middle)))
}

/// The unit normal of the surface at `hit`, facing against `u`: across the principal axis of the
/// occupied cells within three cells of it; head-on (−u) when they are too few to tell.
fn surface_normal(grid: &EvidenceGrid, hit: (f64, f64), u: (f64, f64)) -> (f64, f64) {
    let pts: Vec<(f64, f64)> = grid
        .cells_in_circle(hit, 3.0 * grid.params().resolution_m)
        .into_iter()
        .filter(|&c| grid.log_odds(c) >= SURFACE_LOG_ODDS)
        .map(|c| grid.centre(c))
        .collect();
    if pts.len() < 3 {
        return (-u.0, -u.1);
    }
    let n = pts.len() as f64;
    let (mx, my) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0 / n, a.1 + p.1 / n));
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for p in &pts {
        let (dx, dy) = (p.0 - mx, p.1 - my);
        sxx += dx * dx;
        syy += dy * dy;
        sxy += dx * dy;
    }
    // the principal axis's angle; the normal is across it
    let axis = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let (s, c) = axis.sin_cos();
    let normal = (-s, c);
    if normal.0 * u.0 + normal.1 * u.1 > 0.0 { (-normal.0, -normal.1) } else { normal }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::grid::GridParams;

    fn walls() -> EvidenceGrid {
        let mut g = EvidenceGrid::new(GridParams::default());
        g.pin_segment((2.0, -2.0), (2.0, 2.0)); // east wall
        g.pin_segment((-2.0, 1.0), (2.0, 1.0)); // north wall
        g
    }

    #[test]
    fn driving_grows_the_uncertainty_along_and_across() {
        let mut f = PoseFilter::new(Pose2 { x: 0.0, y: 0.0, yaw_deg: 0.0 }, 0.001, 0.1);
        for _ in 0..10 {
            f.predict(0.1, 0.0, 0.0, 0.3, &MotionNoise::default());
        }
        assert!((f.mean().x - 1.0).abs() < 1e-9);
        let (p, noise) = (f.covariance(), MotionNoise::default());
        // ten steps of 0.1 m, each adding its own variance; across, the heading's adds to it
        let steps = 10f64.sqrt() * 0.1;
        assert!(p[(0, 0)].sqrt() >= 0.999 * steps * noise.along_per_m, "{p}");
        assert!(p[(1, 1)].sqrt() > steps * noise.across_per_m, "{p}");
        // a heading error grows the across-track error with the distance
        assert!(p[(1, 2)] > 0.0);
    }

    #[test]
    fn the_bias_is_taken_off_the_gyros_turn() {
        let mut f = PoseFilter::new(Pose2::default(), 0.001, 0.1);
        f.state[3] = 1f64.to_radians();
        f.predict(0.0, 0.0, 10f64.to_radians(), 2.0, &MotionNoise::default());
        assert!((f.mean().yaw_deg - 8.0).abs() < 1e-9, "{}", f.mean().yaw_deg);
    }

    #[test]
    fn a_wall_ahead_corrects_along_the_track_only() {
        // believed at x = 0.5, really at 0.55: the sonar (13 cm ahead) reads 2.0 − 0.68 = 1.32
        let mut f = PoseFilter::new(Pose2 { x: 0.5, y: 0.0, yaw_deg: 0.0 }, 0.03, 1.0);
        let before = *f.covariance();
        let r = f.correct_range(&walls(), 0.13, 1.32, 0.005);
        assert!(matches!(r, RangeUpdate::Applied { .. }), "{r:?}");
        let m = f.mean();
        assert!((m.x - 0.55).abs() < 0.015, "x {}", m.x);
        assert!(m.y.abs() < 1e-6, "y moved: {}", m.y);
        assert!(f.covariance()[(0, 0)] < before[(0, 0)] / 4.0);
        assert!((f.covariance()[(1, 1)] - before[(1, 1)]).abs() < 1e-12, "nothing learnt across");
    }

    #[test]
    fn a_wall_to_the_side_corrects_across() {
        // facing north at y = 0.0 (believed), really at y = 0.04: the north wall 1.0 − 0.17
        let mut f = PoseFilter::new(Pose2 { x: 0.0, y: 0.0, yaw_deg: 90.0 }, 0.03, 1.0);
        let r = f.correct_range(&walls(), 0.13, 0.83, 0.005);
        assert!(matches!(r, RangeUpdate::Applied { .. }), "{r:?}");
        assert!((f.mean().y - 0.04).abs() < 0.015, "y {}", f.mean().y);
    }

    #[test]
    fn an_outlier_is_rejected_and_changes_nothing() {
        let mut f = PoseFilter::new(Pose2 { x: 0.5, y: 0.0, yaw_deg: 0.0 }, 0.01, 0.5);
        let before = f.clone();
        // 1.60 m where the map has the wall at 1.37 m (an echo from the cone's edge, a door
        // left open)
        let r = f.correct_range(&walls(), 0.13, 1.60, 0.005);
        assert!(matches!(r, RangeUpdate::Rejected { sigmas } if sigmas > 3.0), "{r:?}");
        assert_eq!(f, before);
        // a chair 40 cm ahead, which the map does not hold: nothing to compare with
        assert_eq!(f.correct_range(&walls(), 0.13, 0.40, 0.005), RangeUpdate::NoSurface);
        assert_eq!(f, before);
    }

    #[test]
    fn nothing_ahead_or_a_grazing_wall_gives_no_correction() {
        let mut f = PoseFilter::new(Pose2 { x: 0.0, y: 0.0, yaw_deg: 180.0 }, 0.01, 0.5);
        assert_eq!(f.correct_range(&walls(), 0.13, 1.0, 0.005), RangeUpdate::NoSurface);
        // along the north wall, 80° from its normal
        let mut g = f.clone();
        g.state[1] = 0.9;
        g.state[2] = 10f64.to_radians();
        assert_eq!(g.correct_range(&walls(), 0.13, 1.0, 0.005), RangeUpdate::NoSurface);
    }

    #[test]
    fn a_fix_against_an_earlier_pose_corrects_only_what_was_added_since() {
        let east = Pose2 { x: 0.0, y: 0.0, yaw_deg: 0.0 };
        // 3 cm of uncertainty already when the surface was placed, 0.5 cm added by one cell
        let mut f = PoseFilter::new(east, 0.03, 0.5);
        let earlier = f.variance_along((1.0, 0.0));
        f.predict(0.45, 0.0, 0.0, 1.5, &MotionNoise { along_per_m: 0.005 / 0.45, ..MotionNoise::default() });
        let added = f.variance_along((1.0, 0.0)) - earlier;
        // the surface says the body is 1 cm further than the wheels; the readings' σ is 5 mm
        let update = f.correct_position_since((1.0, 0.0), 0.46, 0.005, earlier);
        assert!(matches!(update, RangeUpdate::Applied { .. }), "{update:?}");
        let gain = added / (added + 0.005f64.powi(2));
        assert!((f.mean().x - (0.45 + gain * 0.01)).abs() < 1e-6, "{} vs gain {gain}", f.mean().x);
        // what was known before the motion is not learnt again
        assert!(f.variance_along((1.0, 0.0)) >= earlier, "{} < {earlier}", f.variance_along((1.0, 0.0)));
        // the same innovation, taken as an absolute position with the same noise, moves it more
        let mut absolute = PoseFilter::new(east, 0.03, 0.5);
        absolute.predict(
            0.45,
            0.0,
            0.0,
            1.5,
            &MotionNoise { along_per_m: 0.005 / 0.45, ..MotionNoise::default() },
        );
        absolute.correct_position_since((1.0, 0.0), 0.46, 0.005, 0.0);
        assert!(absolute.mean().x - 0.45 > 1.5 * (f.mean().x - 0.45));
        // nothing added since: nothing to correct, and 5 σ off is another surface
        let still = f.clone();
        let now = f.variance_along((1.0, 0.0));
        let one_sigma_on = f.mean().x + 0.005;
        assert!(matches!(
            f.correct_position_since((1.0, 0.0), one_sigma_on, 0.005, now),
            RangeUpdate::Applied { .. }
        ));
        assert_eq!(f.mean(), still.mean());
        assert!(matches!(
            f.correct_position_since((1.0, 0.0), 0.60, 0.005, 0.0),
            RangeUpdate::Rejected { .. }
        ));
    }

    #[test]
    fn a_widened_belief_takes_more_of_the_next_range() {
        let correct = |widen: bool| {
            let mut f = PoseFilter::new(Pose2 { x: 0.5, y: 0.0, yaw_deg: 0.0 }, 0.005, 0.5);
            if widen {
                f.widen(0.05, 2.0);
            }
            let _ = f.correct_range(&walls(), 0.13, 1.30, 0.005);
            f.mean().x - 0.5
        };
        assert!(correct(true) > 2.0 * correct(false), "{} vs {}", correct(true), correct(false));
    }
}
