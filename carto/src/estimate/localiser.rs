//! Carto's belief of where the robot is: the pose filter ([`super::pose`]) run on the dead
//! reckoning and corrected at every straight reading at rest, against the surfaces heard before
//! (or the floor plan, when one is given).
//!
//! Contract:
//! - **Between corrections the mean is the dead reckoning** the motor controller steers by: the
//!   stored cell's centre plus the odometry's offset, facing the IMU's heading (the pilot's
//!   `believed`). At every reading taken at rest, [`Localiser::at_rest`] grows the covariance by
//!   the motion since the last one (along, across, turned, time), corrects the position, and
//!   returns the correction; the pilot moves the odometry by it, so the next FORWARD aims at the
//!   next cell's centre from the corrected position.
//! - **What a range is compared with.** With a floor plan (the twin's `--known-room`), the
//!   nearest surface the sensor model's fan of rays ([`Sonar::rays`](crate::config::Sonar::rays), the fan the
//!   twin casts) meets within the incidence limit ([`PoseFilter::correct_echo`]): the plan is
//!   exact, so every direction it has surfaces in corrects. A fan with rays the sensor does not
//!   have expects echoes it never returns (a leg between two of its rays), and the oblique
//!   surface behind such a ray turns the difference into a sideways pull. Without one, the
//!   surfaces heard straight ahead at rest ([`crate::walls`]): a surface kept from an echo
//!   within [`WALL_MAX_M`] when facing the same heading from the same row or column, else the
//!   reading of the cell behind (within [`RELATIVE_MAX_M`]), each a measurement of the position
//!   along the heading with the noise of two readings, *relative to
//!   the pose the surface was placed from* ([`PoseFilter::correct_position_since`]): the
//!   surface's depth carries that pose's error, so only the uncertainty added since (the motion,
//!   a touch) is corrected; taken as absolute positions, the fixes counted the old uncertainty
//!   again at every reading and pulled the belief too far (`docs/journal/world-model.md`). Why not the
//!   evidence grid: an echo marks an arc across the cone, and seen from another row its off-axis
//!   cells lie up to `1 − cos 7.5°` of the range nearer than the surface; ranges compared with
//!   those arcs pulled the belief away from the walls (`docs/journal/world-model.md`).
//! - **Looks aside** ([`Localiser::at_look`]): with a floor plan, a reading at rest taken with
//!   the body turned off the grid heading (`pilot/safety.rs`, "Looking aside") corrects the
//!   position against the plan as a straight one does, and leaves what the straight readings
//!   keep (the surfaces heard ahead, the last straight reading) alone. Which side to look to is
//!   the plan's answer too ([`Localiser::look_aside_side`]).
//! - **The gate is the filter's**: a range more than 3 σ of the innovation from the expected one
//!   is another object. It widens with the belief's uncertainty, so after a touch a range that
//!   disagrees by centimetres is taken, where a fixed window would refuse it.
//! - **The heading stays the IMU's.** One range per FORWARD says little of it, and the IMU's
//!   drift is tracked already (`sensors.rs`). At every reading the filter takes the IMU's heading
//!   as known to [`IMU_HEADING_SIGMA_DEG`], uncorrelated with the position: left to grow with
//!   the gyro's noise over a whole mission, the heading's variance would be taken for position
//!   error through the cross-terms, and one small innovation would move the belief by
//!   centimetres.
//! - **The grid** learns from every reading at rest and every reading kept in a turn, placed
//!   from the corrected pose: the body's footprint certainly free, the reading by the sonar
//!   model (the map the next steps plan in; nothing reads it yet). A reading from where the
//!   last one was learnt (the sonar within [`SAME_SPOT_M`] and [`SAME_SPOT_DEG`]) is not learnt
//!   again: it is the same echo of the same surfaces, not new evidence, and counted again it
//!   would harden the whole arc of a far echo into a surface. Surfaces known before the run
//!   are pinned.
//! - **A touch** (a bump, a push, a stall) widens the position by [`TOUCH_SIGMA_M`] and the
//!   heading by [`TOUCH_SIGMA_DEG`]: the body moved in a way the wheels did not see, and the next
//!   readings weigh more than the wheels.
//! - **A new pose from Cute** starts a new grid, new surfaces and a new filter (their frame is
//!   the pose's); pinned surfaces are pinned again.
//!
//! ```
//! use carto::CartoConfig;
//! use carto::estimate::localiser::Localiser;
//! use carto::estimate::sonar::Reading;
//! use carto::surroundings::Pose2;
//! use robot_model::grid::{GridPose, Heading};
//! use robot_model::time::Instant;
//! let mut loc = Localiser::new(&CartoConfig::default());
//! let (east, start) = (Pose2 { x: 0.0, y: 0.0, yaw_deg: 0.0 }, GridPose { x: 0, y: 0, heading: Heading::East });
//! // a wall 80 cm ahead of the sonar (13 cm ahead of the centre) is kept as a surface
//! loc.at_rest(Instant::from_millis(0), start, east, Reading::Echo(0.80));
//! loc.touched(); // a bump on the way: the wheels are trusted less
//! // the wheels say one cell (45 cm), the body went 50: the wall reads 30 cm
//! let next = GridPose { y: 1, ..start };
//! let fix = loc.at_rest(Instant::from_millis(3000), next, Pose2 { x: 0.45, ..east }, Reading::Echo(0.30));
//! assert!((fix.0 - 0.05).abs() < 0.01 && fix.1.abs() < 1e-9, "{fix:?}");
//! ```

use robot_model::time::Instant;

use super::grid::{EvidenceGrid, GridParams};
use super::pose::{Fan, MotionNoise, PoseFilter, RangeUpdate, expected_range};
use super::sonar::{Reading, SonarModel};
use robot_model::grid::{GridPose, Heading};

use crate::CartoConfig;
use crate::surroundings::Pose2;
use crate::walls::{self, Walls};

/// How well Carto knows where it is when Cute names its cell, metres and degrees. The grid is
/// built in the frame of that pose, so what matters is the error relative to it, which starts
/// small; a floor plan given before the run (the twin's `--known-room`) is exact.
pub const START_SIGMA_M: f64 = 0.005;
/// See [`START_SIGMA_M`].
pub const START_SIGMA_DEG: f64 = 0.5;
/// How well the IMU's heading is known at a reading, degrees (its noise and what is left of its
/// drift after `sensors.rs` has estimated it).
pub const IMU_HEADING_SIGMA_DEG: f64 = 0.5;
/// How far a touch may have moved the body unseen, metres (one σ): touches measured in the twin
/// push the body 4–23 cm.
pub const TOUCH_SIGMA_M: f64 = 0.05;
/// How far a touch may have turned the body unseen, degrees (one σ).
pub const TOUCH_SIGMA_DEG: f64 = 3.0;
/// A reading taken this close to the last one learnt, metres and degrees, teaches the grid
/// nothing new (see the module docs).
pub const SAME_SPOT_M: f64 = 0.02;
/// See [`SAME_SPOT_M`].
pub const SAME_SPOT_DEG: f64 = 3.0;
/// Echoes farther than this are not kept as surfaces nor matched with them, metres: the cone is
/// then wider than the body, and what answers may be another face than the one kept.
pub const WALL_MAX_M: f64 = 1.0;

/// The farthest echo a look aside is taken for, metres ([`Localiser::look_aside_side`]): with the
/// heading known to [`IMU_HEADING_SIGMA_DEG`], a surface met 30° off head-on at this range is
/// placed to under 1 cm.
pub const LOOK_ASIDE_MAX_M: f64 = 1.5;
/// Echoes farther than this are not paired with the reading of the next cell, metres.
pub const RELATIVE_MAX_M: f64 = 2.0;

/// What the localiser did, for the counters.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LocaliserCounters {
    /// Ranges that corrected the position.
    pub applied: u64,
    /// Ranges too far from the expected range (another object, an echo from the cone's edge).
    pub rejected: u64,
    /// Ranges with nothing on the map to compare with.
    pub unmatched: u64,
    /// Touches that widened the belief.
    pub touches: u64,
}

impl LocaliserCounters {
    /// Counts one range's outcome.
    fn count(&mut self, update: &RangeUpdate) {
        match update {
            RangeUpdate::Applied { .. } => self.applied += 1,
            RangeUpdate::Rejected { .. } => self.rejected += 1,
            RangeUpdate::NoSurface => self.unmatched += 1,
        }
    }
}

/// A straight reading at rest: where it was taken, the depth along the heading of the surface it
/// heard, and the variance of the position along the heading then.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Straight {
    pose: GridPose,
    depth_m: f64,
    placed_var_m2: f64,
}

/// The belief (see the module docs).
#[derive(Debug, Clone)]
pub struct Localiser {
    grid: EvidenceGrid,
    sonar: SonarModel,
    noise: MotionNoise,
    /// The filter, the pose its mean was last set to, and when.
    filter: Option<(PoseFilter, Pose2, Instant)>,
    /// A touch since the last reading, to widen the filter with (or the start, if none yet).
    touched: bool,
    known: Vec<(f64, f64)>,
    /// The surfaces known before the run, pinned, and nothing else: the map a range is compared
    /// with when there is one.
    known_grid: Option<EvidenceGrid>,
    /// Surfaces heard straight ahead at rest, as depths along a grid heading.
    walls: Walls,
    /// The last straight reading at rest.
    last_straight: Option<Straight>,
    /// Where the sonar was when the grid last learnt a reading, and what it read.
    last_learnt: Option<(Pose2, Reading)>,
    fan_deg: Vec<f64>,
    incidence_limit_deg: f64,
    mount_m: f64,
    range_sigma_m: f64,
    /// The σ of one range against another of the same surface (two readings' noise and steps).
    pair_sigma_m: f64,
    half_length_m: f64,
    half_width_m: f64,
    counters: LocaliserCounters,
}

impl Localiser {
    /// A localiser for the robot `cfg` describes, with an empty grid and no pose yet.
    pub fn new(cfg: &CartoConfig) -> Self {
        let params = GridParams::default();
        let sonar = SonarModel::from_config(cfg);
        let half_cone = cfg.sonar.cone_deg / 2.0;
        let fan_deg = sonar_fan_deg(half_cone, cfg.sonar.rays);
        // one range against the grid: the sonar's noise, its 1 cm steps and where in its cell
        // the surface lies (a uniform error over a step has σ = step / √12)
        let uniform = |step: f64| step / 12f64.sqrt();
        let range_sigma_m = (cfg.sonar.sigma_m.powi(2)
            + uniform(sonar.quantisation_m).powi(2)
            + uniform(params.resolution_m).powi(2))
        .sqrt();
        Localiser {
            grid: EvidenceGrid::new(params),
            sonar,
            noise: MotionNoise { along_per_m: cfg.chassis.odometry_sigma_per_m, ..MotionNoise::default() },
            filter: None,
            touched: false,
            known: Vec::new(),
            known_grid: None,
            walls: Walls::default(),
            last_straight: None,
            last_learnt: None,
            fan_deg,
            incidence_limit_deg: cfg.sonar.incidence_deg,
            mount_m: cfg.sonar.mount_m,
            range_sigma_m,
            pair_sigma_m: (2.0 * (cfg.sonar.sigma_m.powi(2) + uniform(sonar.quantisation_m).powi(2))).sqrt(),
            half_length_m: cfg.chassis.body_length_m / 2.0,
            half_width_m: cfg.chassis.body_width_m / 2.0,
            counters: LocaliserCounters::default(),
        }
    }

    /// Forgets the grid and the filter (a new pose from Cute: a new frame); pinned surfaces stay.
    pub fn reset(&mut self) {
        self.grid = EvidenceGrid::new(*self.grid.params());
        for &p in &self.known {
            self.grid.pin_segment(p, p);
        }
        self.filter = None;
        self.touched = false;
        self.last_learnt = None;
        self.walls.clear();
        self.last_straight = None;
    }

    /// Forgets the last straight reading: the robot was stopped somewhere Carto did not plan.
    pub fn forget_last_reading(&mut self) {
        self.last_straight = None;
    }

    /// Pins surface points known for good, in Carto's frame.
    pub fn pin(&mut self, points: impl IntoIterator<Item = (f64, f64)>) {
        let known = self.known_grid.get_or_insert_with(|| EvidenceGrid::new(*self.grid.params()));
        for p in points {
            self.grid.pin_segment(p, p);
            known.pin_segment(p, p);
            self.known.push(p);
        }
    }

    /// A touch: the next reading finds the belief widened (see the module docs).
    pub fn touched(&mut self) {
        self.touched = true;
        self.counters.touches += 1;
    }

    /// A reading taken at rest at `now` in the stored cell and heading `pose`, the dead
    /// reckoning saying `believed`: grows the covariance by the motion since the last reading,
    /// corrects the position from the range and teaches the grid the reading from the corrected
    /// pose. Returns the correction `(dx, dy)` in Carto's frame, metres (zero when the range
    /// told nothing).
    pub fn at_rest(&mut self, now: Instant, pose: GridPose, believed: Pose2, reading: Reading) -> (f64, f64) {
        self.predict_to(now, believed);
        let Some((filter, ..)) = self.filter.as_mut() else { return (0.0, 0.0) };
        let u = unit(pose.heading);
        let Reading::Echo(range) = reading else {
            self.last_straight = None;
            return self.finish(now, believed, reading);
        };
        let ahead = self.mount_m + range;
        let lateral = walls::lateral(pose);
        let mut matched_wall = false;
        let update = if let Some(known) = &self.known_grid {
            let fan = Fan { ray_offsets_deg: &self.fan_deg, incidence_limit_deg: self.incidence_limit_deg };
            filter.correct_echo(known, self.mount_m, &fan, range, self.range_sigma_m)
        } else {
            let depth = u.0 * filter.mean().x + u.1 * filter.mean().y + ahead;
            let mut update = RangeUpdate::NoSurface;
            if range <= WALL_MAX_M
                && let Some(wall) = self.walls.nearest(pose.heading, lateral, depth)
            {
                let at = wall.depth_m - ahead;
                update = filter.correct_position_since(u, at, self.pair_sigma_m, wall.placed_var_m2);
                matched_wall = matches!(update, RangeUpdate::Applied { .. });
            }
            if !matched_wall
                && let Some(prev) = self.last_straight
                && prev.pose.heading == pose.heading
                && prev.pose.ahead() == Some((pose.x, pose.y))
            {
                let at = prev.depth_m - ahead;
                update = filter.correct_position_since(u, at, self.pair_sigma_m, prev.placed_var_m2);
            }
            update
        };
        tracing::debug!(
            x = believed.x,
            y = believed.y,
            yaw = believed.yaw_deg,
            range,
            ?update,
            "range at rest"
        );
        self.counters.count(&update);
        let depth_m = u.0 * filter.mean().x + u.1 * filter.mean().y + ahead;
        let placed_var_m2 = filter.variance_along(u);
        if range <= WALL_MAX_M && !matched_wall {
            self.walls.remember(pose.heading, lateral, depth_m, placed_var_m2);
        }
        self.last_straight = (range <= RELATIVE_MAX_M).then_some(Straight { pose, depth_m, placed_var_m2 });
        self.finish(now, believed, reading)
    }

    /// Grows the filter by the motion from the last reading to `believed` at `now` (started there
    /// on the first), widened after a touch, and moves its mean to `believed`.
    fn predict_to(&mut self, now: Instant, believed: Pose2) {
        let noise = self.noise;
        let (filter, synced, at) = self.filter.get_or_insert_with(|| {
            (PoseFilter::new(believed, START_SIGMA_M, START_SIGMA_DEG), believed, now)
        });
        grow(filter, (*synced, *at), (believed, now), &noise);
        if core::mem::take(&mut self.touched) {
            filter.widen(TOUCH_SIGMA_M, TOUCH_SIGMA_DEG);
        }
        filter.set_mean(believed);
        filter.set_heading(believed.yaw_deg, IMU_HEADING_SIGMA_DEG);
    }

    /// Whether a floor plan was given: every range at rest, in any direction, then corrects.
    pub fn has_plan(&self) -> bool {
        self.known_grid.is_some()
    }

    /// The standard deviation of the position across the heading `yaw_deg`, metres, as it would
    /// be after predicting to `believed` at `now`; `None` before the first reading.
    pub fn sigma_across_m(&self, now: Instant, believed: Pose2) -> Option<f64> {
        let (mut filter, synced, at) = self.filter.clone()?;
        grow(&mut filter, (synced, at), (believed, now), &self.noise);
        let yaw = believed.yaw_deg.to_radians();
        Some(filter.variance_along((-yaw.sin(), yaw.cos())).sqrt())
    }

    /// The side to look aside to from `robot`, `deg` each way (module docs of
    /// `pilot/safety.rs`, "Looking aside"): +1 (left) or −1 (right), whichever the floor plan
    /// puts the nearer echo on, within `max_m` ([`LOOK_ASIDE_MAX_M`] for the 60° look); `None`
    /// without a plan or an echo.
    pub fn look_aside_side(&self, robot: Pose2, deg: f64, max_m: f64) -> Option<f64> {
        let known = self.known_grid.as_ref()?;
        let fan = Fan { ray_offsets_deg: &self.fan_deg, incidence_limit_deg: self.incidence_limit_deg };
        [1.0, -1.0]
            .into_iter()
            .filter_map(|side: f64| {
                let looking = Pose2 { yaw_deg: robot.yaw_deg + side * deg, ..robot };
                expected_range(known, looking, self.mount_m, &fan, max_m).map(|r| (r, side))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, side)| side)
    }

    /// A reading taken at rest facing `believed`'s heading, off the grid heading (a look aside,
    /// `pilot/safety.rs`, "Looking aside"), with a floor plan given: corrects the position
    /// against the plan as [`Localiser::at_rest`] does, without touching what the straight
    /// readings keep. Returns the correction; zero without a plan.
    pub fn at_look(&mut self, now: Instant, believed: Pose2, reading: Reading) -> (f64, f64) {
        if self.known_grid.is_none() {
            return (0.0, 0.0);
        }
        self.predict_to(now, believed);
        let (Some(known), Some((filter, ..))) = (&self.known_grid, self.filter.as_mut()) else {
            return (0.0, 0.0);
        };
        let fan = Fan { ray_offsets_deg: &self.fan_deg, incidence_limit_deg: self.incidence_limit_deg };
        let update = match reading {
            Reading::Echo(range) => filter.correct_echo(known, self.mount_m, &fan, range, self.range_sigma_m),
            Reading::NoEcho => RangeUpdate::NoSurface,
        };
        tracing::debug!(
            x = believed.x,
            y = believed.y,
            yaw = believed.yaw_deg,
            ?reading,
            ?update,
            "range looking aside"
        );
        self.counters.count(&update);
        self.finish(now, believed, reading)
    }

    /// Ends a reading at rest: the filter's mean is the corrected pose, facing the IMU's heading;
    /// the grid learns the reading from there. Returns the correction.
    fn finish(&mut self, now: Instant, believed: Pose2, reading: Reading) -> (f64, f64) {
        let Some((filter, synced, at)) = self.filter.as_mut() else { return (0.0, 0.0) };
        let corrected = Pose2 { yaw_deg: believed.yaw_deg, ..filter.mean() };
        filter.set_mean(corrected);
        filter.set_heading(believed.yaw_deg, IMU_HEADING_SIGMA_DEG);
        (*synced, *at) = (corrected, now);
        self.learn(corrected, reading);
        (corrected.x - believed.x, corrected.y - believed.y)
    }

    /// Teaches the grid a reading taken from the body at `robot` (a reading kept in a turn): the
    /// footprint free, the reading by the sonar model. The filter is not corrected.
    pub fn learn(&mut self, robot: Pose2, reading: Reading) {
        self.grid.set_robot(robot.x, robot.y);
        self.grid.clear_rect(robot, -self.half_length_m, self.half_length_m, self.half_width_m);
        let (x, y) = robot.offset(self.mount_m, 0.0);
        let sonar = Pose2 { x, y, yaw_deg: robot.yaw_deg };
        let same_spot = self.last_learnt.is_some_and(|(last, heard)| {
            (last.x - sonar.x).hypot(last.y - sonar.y) <= SAME_SPOT_M
                && crate::sensors::wrap180(last.yaw_deg - sonar.yaw_deg).abs() <= SAME_SPOT_DEG
                && same_reading(heard, reading)
        });
        if !same_spot {
            self.sonar.update(&mut self.grid, sonar, reading);
            self.last_learnt = Some((sonar, reading));
        }
    }

    /// The standard deviation of the position, metres (the larger axis); `None` before the first
    /// reading.
    pub fn sigma_m(&self) -> Option<f64> {
        self.position_covariance().map(|p| p[0][0].max(p[1][1]).sqrt())
    }

    /// The covariance of the position, m², in Carto's metric frame (`[[xx, xy], [xy, yy]]`), as
    /// the filter last left it; `None` before the first reading.
    pub fn position_covariance(&self) -> Option<[[f64; 2]; 2]> {
        self.filter.as_ref().map(|(f, ..)| {
            let p = f.covariance();
            [[p[(0, 0)], p[(0, 1)]], [p[(1, 0)], p[(1, 1)]]]
        })
    }

    /// The grid.
    pub fn grid(&self) -> &EvidenceGrid {
        &self.grid
    }

    /// The counters.
    pub fn counters(&self) -> LocaliserCounters {
        self.counters
    }
}

/// The sensor model's rays, degrees from the axis: `rays` spread evenly from `-half_cone` to
/// `+half_cone`, one ray along the axis when there is only one.
fn sonar_fan_deg(half_cone: f64, rays: u32) -> Vec<f64> {
    match rays {
        0 | 1 => vec![0.0],
        n => (0..n).map(|k| -half_cone + 2.0 * half_cone * f64::from(k) / f64::from(n - 1)).collect(),
    }
}

/// Whether two readings heard the same thing (the same echo within a range step, or both none).
fn same_reading(a: Reading, b: Reading) -> bool {
    match (a, b) {
        (Reading::Echo(a), Reading::Echo(b)) => (a - b).abs() <= 0.02,
        (Reading::NoEcho, Reading::NoEcho) => true,
        _ => false,
    }
}

/// The unit vector of a grid heading in Carto's frame (x east, y north): its step on the grid,
/// whose rows grow southward.
fn unit(h: Heading) -> (f64, f64) {
    let (rows, cols) = h.delta();
    (f64::from(cols), -f64::from(rows))
}

/// Grows `filter` by the motion from `from` (the pose and time it was last synced at) to `to`.
fn grow(filter: &mut PoseFilter, from: (Pose2, Instant), to: (Pose2, Instant), noise: &MotionNoise) {
    let ((synced, at), (believed, now)) = (from, to);
    let dt = now.saturating_since(at).as_secs_f64();
    let mid = (0.5 * (synced.yaw_deg + believed.yaw_deg)).to_radians();
    let (dx, dy) = (believed.x - synced.x, believed.y - synced.y);
    let along = dx * mid.cos() + dy * mid.sin();
    let left = -dx * mid.sin() + dy * mid.cos();
    filter.predict(along, left, (believed.yaw_deg - synced.yaw_deg).to_radians(), dt, noise);
}

#[cfg(test)]
mod tests;
