//! What Carto has seen around the robot: the echo points of the front sonar, kept in the grid's
//! metric frame so that a FORWARD and a turn can be checked against them (the turning-circle
//! check before a turn and the swept-body check before a FORWARD).
//!
//! Concept: the HC-SR04 sees a narrow cone (15°) straight ahead. One reading before a FORWARD
//! covers the middle 10 cm of a 24 cm wide body's path at 40 cm; a leg or a furniture corner at
//! the side of the path is invisible to it. So Carto keeps every echo it measured at rest as a
//! point, placed along the sonar's central ray from the pose it believed at the time, and asks two
//! questions of them:
//! - [`Surroundings::first_in_corridor`]: does a point lie in the rectangle the body sweeps along
//!   a FORWARD (as wide as the body plus a margin, from the body's front face to the front face at
//!   the next cell's centre)?
//! - [`Surroundings::inside_circle`]: does a point lie inside the circle the body sweeps turning
//!   on the spot (half its diagonal plus a margin)?
//!
//! Frame: `x` east, `y` north, metres; a cell `(row, col)` has its centre at
//! `(col · cell, −row · cell)`; yaw is counter-clockwise from east, degrees.
//!
//! An echo also says what is *not* there: nothing lies in the cone closer than its range.
//! [`Surroundings::add_reading`] removes the points it sees through, so something that has gone,
//! or a point misplaced by dead reckoning, does not block the robot for ever. A reading without
//! echo clears nothing: a surface turned more than the sensor's incidence limit away returns no
//! echo (specular loss), so "no echo" does not mean "nothing there". For the same reason a
//! reading clears only the points heard along a ray within [`CLEARS_HEARD_WITHIN_DEG`] of its
//! own: a sofa's top heard head-on from the row above lies at the edge of the cone of a robot
//! driving along the row beside it, at a glancing angle that gives no echo, and the far wall's
//! echo would wipe it out.
//!
//! Invariants: at most [`MAX_POINTS`] points are kept (the oldest go first), and points further
//! than [`FORGET_BEYOND_M`] from the robot are dropped when a new one is added: a stale point far
//! behind can only be wrong (dead reckoning drifts) and never matters for the next move.
//! A point is an estimate: the echo may come from anywhere in the cone at that range; the
//! central ray is the best single guess, and the margins absorb the rest.
//!
//! A floor plan can be given too ([`Surroundings::add_fixed`], [`crate::Carto::add_known_surfaces`]):
//! points on the room's surfaces, which the checks treat as echoes and which nothing clears or
//! forgets. The twin uses it for `--known-room` runs, which take the sonar's blind spots out of
//! the picture (`docs/explanation/sensor-limits.md`).
//!
//! ```
//! use carto::surroundings::{Pose2, Surroundings};
//! let mut s = Surroundings::default();
//! let robot = Pose2 { x: 0.0, y: 0.0, yaw_deg: 0.0 };
//! s.add_echo(robot, 0.13, 0.20); // something 20 cm ahead of the front face
//! assert!(s.first_in_corridor(robot, 0.13, 0.53, 0.13).is_some());
//! assert!(s.inside_circle(robot, 0.19).is_none()); // 33 cm away: turning is safe
//! ```

use std::collections::VecDeque;

use crate::sensors::wrap180;

/// Most echo points kept.
pub const MAX_POINTS: usize = 256;
/// Points further than this from the robot are forgotten, metres.
pub const FORGET_BEYOND_M: f64 = 1.5;
/// A reading clears the points this much closer than its echo (sonar noise), metres.
const SEEN_THROUGH_MARGIN_M: f64 = 0.02;
/// A reading clears only the points heard from a direction this close to its own, degrees: a
/// surface the sonar heard head-on from one side returns no echo to a cone that passes along it
/// from another (the incidence limit), so that cone's silence says nothing of it.
pub const CLEARS_HEARD_WITHIN_DEG: f64 = 20.0;

/// A believed robot pose in the grid's metric frame (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose2 {
    /// East, metres.
    pub x: f64,
    /// North, metres.
    pub y: f64,
    /// Counter-clockwise from east, degrees.
    pub yaw_deg: f64,
}

impl Pose2 {
    /// The point `along` ahead and `left` to the left of this pose.
    pub fn offset(self, along: f64, left: f64) -> (f64, f64) {
        let (sin, cos) = self.yaw_deg.to_radians().sin_cos();
        (self.x + along * cos - left * sin, self.y + along * sin + left * cos)
    }

    /// `(along, left)` of the point `(x, y)` seen from this pose.
    pub fn local(self, point: (f64, f64)) -> (f64, f64) {
        self.localiser()(point)
    }

    /// [`Pose2::local`] with the heading's sine and cosine worked out once, for a loop over many
    /// points (the checks run at every reading, and the sim runs 1,500 times faster than real
    /// time).
    fn localiser(self) -> impl Fn((f64, f64)) -> (f64, f64) {
        let (sin, cos) = self.yaw_deg.to_radians().sin_cos();
        move |(x, y)| {
            let (dx, dy) = (x - self.x, y - self.y);
            (dx * cos + dy * sin, -dx * sin + dy * cos)
        }
    }
}

/// One echo point, and the direction of the ray it was heard along.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Echo {
    at: (f64, f64),
    /// Counter-clockwise from east, degrees.
    heard_yaw_deg: f64,
}

/// Echo points around the robot (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct Surroundings {
    points: VecDeque<Echo>,
    /// Points known beforehand (a floor plan), never cleared nor forgotten.
    fixed: Vec<(f64, f64)>,
}

impl Surroundings {
    /// Records an echo `range_m` from a sonar mounted `mount_m` ahead of the centre of a robot at
    /// `robot`, along its central ray; forgets the points now far away.
    pub fn add_echo(&mut self, robot: Pose2, mount_m: f64, range_m: f64) {
        if !(range_m.is_finite() && range_m >= 0.0) {
            return;
        }
        self.add_point(robot, robot.offset(mount_m + range_m, 0.0));
    }

    /// Records a point at `at`, kept as if heard along `robot`'s heading (which decides the
    /// readings that may clear it, [`CLEARS_HEARD_WITHIN_DEG`]); forgets the points now far
    /// away.
    pub fn add_point(&mut self, robot: Pose2, at: (f64, f64)) {
        self.points.push_back(Echo { at, heard_yaw_deg: robot.yaw_deg });
        self.points.retain(|e| (e.at.0 - robot.x).hypot(e.at.1 - robot.y) <= FORGET_BEYOND_M);
        while self.points.len() > MAX_POINTS {
            self.points.pop_front();
        }
    }

    /// Records a reading: clears the points inside the cone (`half_cone_deg` either side of the
    /// central ray) closer than the echo and keeps the echo as a point; no echo (`None`) changes
    /// nothing (see the module docs). `max_range_m` bounds what an echo can clear.
    pub fn add_reading(
        &mut self,
        robot: Pose2,
        mount_m: f64,
        range_m: Option<f64>,
        half_cone_deg: f64,
        max_range_m: f64,
    ) {
        let Some(range_m) = range_m else {
            return;
        };
        self.clear_seen_through(robot, mount_m, range_m, half_cone_deg, max_range_m);
        self.add_echo(robot, mount_m, range_m);
    }

    /// Forgets the points inside the cone closer than the echo `range_m` (what [`Self::add_reading`]
    /// clears), without keeping the echo.
    pub fn clear_seen_through(
        &mut self,
        robot: Pose2,
        mount_m: f64,
        range_m: f64,
        half_cone_deg: f64,
        max_range_m: f64,
    ) {
        let (sx, sy) = robot.offset(mount_m, 0.0);
        let sonar = Pose2 { x: sx, y: sy, yaw_deg: robot.yaw_deg };
        let seen_through = range_m.min(max_range_m) - SEEN_THROUGH_MARGIN_M;
        let tan = half_cone_deg.to_radians().tan();
        let local = sonar.localiser();
        self.points.retain(|e| {
            let (along, left) = local(e.at);
            let facing = wrap180(e.heard_yaw_deg - sonar.yaw_deg).abs() <= CLEARS_HEARD_WITHIN_DEG;
            !(facing && along > 0.0 && along < seen_through && left.abs() <= along * tan)
        });
    }

    /// Forgets the points inside the body's rectangle at `robot` (`half_length_m` ahead and
    /// behind, `half_width_m` either side): the body stands there, so nothing else does. Such a
    /// point was placed from a pose dead reckoning got wrong (a push in a collision, slip); kept,
    /// it lay inside every turning circle from then on and Carto refused every turn where it
    /// stood, until the room's time limit.
    pub fn clear_footprint(&mut self, robot: Pose2, half_length_m: f64, half_width_m: f64) {
        let local = robot.localiser();
        self.points.retain(|e| {
            let (along, left) = local(e.at);
            along.abs() > half_length_m || left.abs() > half_width_m
        });
    }

    /// Adds known points (a floor plan in the grid's metric frame, or points given as a run
    /// goes): the checks treat them as echoes, and nothing clears them.
    pub fn add_fixed(&mut self, points: impl IntoIterator<Item = (f64, f64)>) {
        self.fixed.extend(points);
    }

    /// The echo points and the floor plan's.
    fn all(&self) -> impl Iterator<Item = &(f64, f64)> {
        self.points.iter().map(|e| &e.at).chain(self.fixed.iter())
    }

    /// Forgets every point (a new pose from Cute: the old points were placed from another one).
    pub fn clear(&mut self) {
        self.points.clear();
    }

    /// The echo points kept (not the floor plan's), in the grid's metric frame.
    pub fn points(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.points.iter().map(|e| e.at)
    }

    /// Every point, the floor plan's too, as `(along, left)` from `frame`, with `along` in
    /// `along_m` and `left` in `left_m` (both inclusive ranges, smaller bound first).
    pub fn in_box(&self, frame: Pose2, along_m: (f64, f64), left_m: (f64, f64)) -> Vec<(f64, f64)> {
        let local = frame.localiser();
        self.all()
            .map(|&p| local(p))
            .filter(|&(a, l)| (along_m.0..=along_m.1).contains(&a) && (left_m.0..=left_m.1).contains(&l))
            .collect()
    }

    /// Echo points kept (the floor plan's not counted).
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether no echo point is kept.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The nearest point, as `(along, left)` from `robot`, inside the rectangle `from_m..=to_m`
    /// ahead and `half_width_m` either side.
    pub fn first_in_corridor(
        &self,
        robot: Pose2,
        from_m: f64,
        to_m: f64,
        half_width_m: f64,
    ) -> Option<(f64, f64)> {
        self.first_in_strip(robot, (from_m, to_m), (-half_width_m, half_width_m))
    }

    /// The nearest point, as `(along, left)` from `robot`, with `along` in `along_m` and `left`
    /// in `left_m` (both inclusive ranges, smaller bound first).
    pub fn first_in_strip(
        &self,
        robot: Pose2,
        along_m: (f64, f64),
        left_m: (f64, f64),
    ) -> Option<(f64, f64)> {
        let local = robot.localiser();
        self.all()
            .map(|&p| local(p))
            .filter(|&(along, left)| {
                along >= along_m.0 && along <= along_m.1 && left >= left_m.0 && left <= left_m.1
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }

    /// The smallest shift `(along, left)` of `robot`, metres, after which no point lies closer
    /// than `radius_m` to its centre, on a grid of `step_m` up to `max_m` each way; no part is a
    /// single step (a move ends within its tolerance and might not drive it). Shifts along the
    /// heading come first (the robot came from behind and ranged ahead), then shifts with a
    /// sideways part, shortest first (the mecanum wheels strafe). `None` when none clears.
    pub fn clearing_shift(&self, robot: Pose2, radius_m: f64, max_m: f64, step_m: f64) -> Option<(f64, f64)> {
        let reach = radius_m + 2.0 * max_m;
        let near: Vec<(f64, f64)> =
            self.all().copied().filter(|&(x, y)| (x - robot.x).hypot(y - robot.y) < reach).collect();
        let clears = |(along, left): (f64, f64)| {
            let (x, y) = robot.offset(along, left);
            nearest_inside(near.iter(), Pose2 { x, y, ..robot }, radius_m).is_none()
        };
        let steps = (max_m / step_m).floor() as i32;
        let along = (2..=steps).flat_map(|k| [-k, k]).map(|k| (f64::from(k) * step_m, 0.0));
        if let Some(shift) = along.into_iter().find(|&d| clears(d)) {
            return Some(shift);
        }
        // no part of one step: a move ends within its tolerance (1 cm) and might not drive it
        let mut sideways: Vec<(i32, i32)> = (-steps..=steps)
            .filter(|a| *a == 0 || a.abs() >= 2)
            .flat_map(|a| (-steps..=steps).filter(|l| l.abs() >= 2).map(move |l| (a, l)))
            .collect();
        sideways.sort_by_key(|&(a, l)| (a * a + l * l, a, l));
        sideways.into_iter().map(|(a, l)| (f64::from(a) * step_m, f64::from(l) * step_m)).find(|&d| clears(d))
    }

    /// The nearest point, as `(along, left)` from `robot`, closer than `radius_m` to its centre.
    pub fn inside_circle(&self, robot: Pose2, radius_m: f64) -> Option<(f64, f64)> {
        nearest_inside(self.all(), robot, radius_m)
    }
}

/// The nearest of `points`, as `(along, left)` from `robot`, closer than `radius_m` to its centre.
fn nearest_inside<'a>(
    points: impl Iterator<Item = &'a (f64, f64)>,
    robot: Pose2,
    radius_m: f64,
) -> Option<(f64, f64)> {
    let local = robot.localiser();
    points
        .map(|&p| local(p))
        .filter(|&(along, left)| along.hypot(left) < radius_m)
        .min_by(|a, b| a.0.hypot(a.1).total_cmp(&b.0.hypot(b.1)))
}

#[cfg(test)]
mod tests {
    use super::*;

    const MOUNT: f64 = 0.13;

    #[test]
    fn floor_plan_points_block_like_echoes_and_are_never_cleared() {
        let robot = Pose2 { x: 0.0, y: 0.0, yaw_deg: 0.0 };
        let blocked = |s: &Surroundings| {
            s.first_in_corridor(robot, MOUNT, 0.58, 0.14)
                .is_some_and(|(along, left)| (along - 0.30).abs() < 1e-9 && (left - 0.10).abs() < 1e-9)
        };
        let mut s = Surroundings::default();
        // a leg 30 cm ahead, 10 cm left: in the body's path, outside the turning circle
        s.add_fixed([(0.30, 0.10)]);
        assert!(blocked(&s));
        assert!(s.inside_circle(robot, 0.197).is_none());
        // a reading that sees through it, the body standing on it, a new pose: it stays
        s.add_reading(robot, MOUNT, Some(1.0), 7.5, 4.0);
        s.clear_footprint(Pose2 { x: 0.30, ..robot }, 0.13, 0.12);
        s.clear();
        assert!(blocked(&s));
        assert!(s.is_empty(), "the floor plan's points are not echo points");
        // a turn 18 cm beside it shifts until the circle clears it
        let beside = Pose2 { x: 0.30, y: -0.08, yaw_deg: 0.0 };
        assert!(s.inside_circle(beside, 0.197).is_some());
        let (along, left) = s.clearing_shift(beside, 0.197, 0.11, 0.01).expect("a shift clears it");
        let shifted = Pose2 { x: 0.30 + along, y: -0.08 + left, yaw_deg: 0.0 };
        assert!(s.inside_circle(shifted, 0.197).is_none());
    }

    #[test]
    fn a_corner_needs_a_shift_across_the_heading() {
        // facing east at the origin: a wall 16 cm ahead and one 16 cm to the left, the turning
        // circle 19.7 cm
        let robot = Pose2 { x: 0.0, y: 0.0, yaw_deg: 0.0 };
        let mut s = Surroundings::default();
        s.add_echo(robot, MOUNT, 0.16 - MOUNT);
        s.add_echo(Pose2 { yaw_deg: 90.0, ..robot }, MOUNT, 0.16 - MOUNT);
        // shifts along the heading come first, so a shift with a sideways part says that backing
        // off alone leaves the left wall in the circle
        let (along, left) = s.clearing_shift(robot, 0.197, 0.11, 0.01).expect("a diagonal shift");
        assert!(along <= -0.037 && left <= -0.037, "({along}, {left})");
        assert!(along.hypot(left) < 0.06, "not the shortest: ({along}, {left})");
        // one wall only: backing off along the heading is enough, and comes first
        let mut one = Surroundings::default();
        one.add_echo(robot, MOUNT, 0.16 - MOUNT);
        assert_eq!(one.clearing_shift(robot, 0.197, 0.11, 0.01), Some((-0.04, 0.0)));
        // walls ahead and behind: nothing within 11 cm clears both
        one.add_echo(Pose2 { yaw_deg: 180.0, ..robot }, MOUNT, 0.16 - MOUNT);
        assert_eq!(one.clearing_shift(robot, 0.197, 0.11, 0.01), None);
    }

    #[test]
    fn an_echo_lies_on_the_central_ray_in_the_grid_frame() {
        let mut s = Surroundings::default();
        // facing north (90°) from (1, 2): an echo 0.27 m away lies at (1, 2 + 0.40)
        let robot = Pose2 { x: 1.0, y: 2.0, yaw_deg: 90.0 };
        s.add_echo(robot, MOUNT, 0.27);
        let east = Pose2 { x: 1.0, y: 2.0, yaw_deg: 0.0 };
        let (along, left) = s.inside_circle(east, 0.5).expect("point kept");
        assert!(along.abs() < 1e-9 && (left - 0.40).abs() < 1e-9, "{along} {left}");
    }

    #[test]
    fn corridor_takes_the_nearest_point_inside_and_ignores_the_sides() {
        let mut s = Surroundings::default();
        let at = |yaw_deg| Pose2 { x: 0.0, y: 0.0, yaw_deg };
        s.add_echo(at(30.0), MOUNT, 0.30); // (0.37, 0.215): left of a 0.14 half width
        s.add_echo(at(-10.0), MOUNT, 0.25); // (0.374, -0.066): inside
        s.add_echo(at(0.0), MOUNT, 0.20); // (0.33, 0): inside, nearer
        let hit = s.first_in_corridor(at(0.0), MOUNT, 0.53, 0.14).expect("inside");
        assert!((hit.0 - 0.33).abs() < 1e-9 && hit.1.abs() < 1e-9, "{hit:?}");
        // seen from a robot turned around, all of them are behind
        assert!(s.first_in_corridor(at(180.0), MOUNT, 0.53, 0.14).is_none());
    }

    #[test]
    fn a_reading_clears_what_it_sees_through() {
        let mut s = Surroundings::default();
        let robot = Pose2::default();
        s.add_echo(robot, MOUNT, 0.30);
        s.add_echo(Pose2 { yaw_deg: 45.0, ..robot }, MOUNT, 0.30); // outside the cone below
        // a longer echo straight ahead: the first point was not there after all
        s.add_reading(robot, MOUNT, Some(0.60), 7.5, 4.0);
        assert!(s.first_in_corridor(robot, MOUNT, 1.0, 0.05).is_some_and(|(a, _)| (a - 0.73).abs() < 1e-9));
        assert_eq!(s.len(), 2, "the 45-degree point stays, the new echo is kept");
        // no echo clears nothing: a slanted surface may simply not answer
        s.add_reading(robot, MOUNT, None, 7.5, 4.0);
        assert_eq!(s.len(), 2);
    }

    #[test]
    fn the_body_clears_the_points_it_stands_on() {
        let mut s = Surroundings::default();
        let robot = Pose2 { x: 1.0, y: 2.0, yaw_deg: 90.0 };
        // 3 cm left of the centre: inside a 0.26 x 0.24 body facing north
        let echo = |along, left| Echo { at: robot.offset(along, left), heard_yaw_deg: 90.0 };
        s.points.push_back(echo(0.0, 0.03));
        // 2 cm beyond the front face, and 2 cm beyond the left side
        s.points.push_back(echo(0.15, 0.0));
        s.points.push_back(echo(0.0, 0.14));
        assert!(
            s.inside_circle(robot, 0.197).is_some_and(|(a, l)| a.abs() < 1e-9 && (l - 0.03).abs() < 1e-9)
        );
        s.clear_footprint(robot, 0.13, 0.12);
        assert_eq!(s.len(), 2);
        let kept: Vec<(f64, f64)> = s.points.iter().map(|e| robot.local(e.at)).collect();
        assert!(kept.iter().all(|&(a, l)| a > 0.13 || l > 0.12), "{kept:?}");
    }

    #[test]
    fn a_reading_clears_only_points_heard_from_its_own_direction() {
        let mut s = Surroundings::default();
        let sofa = (0.0, -0.15);
        let near_sofa =
            |s: &Surroundings| s.inside_circle(Pose2 { x: sofa.0, y: sofa.1, yaw_deg: 0.0 }, 0.01);
        // a sofa's top, heard head-on from the north, 15 cm south of the line y = 0
        let north = Pose2 { x: 0.0, y: 0.5, yaw_deg: -90.0 };
        s.add_echo(north, MOUNT, 0.5 - sofa.1 - MOUNT);
        assert!(near_sofa(&s).is_some());
        // driving west along y = 0, the cone passes over that point at a glancing angle (no
        // echo from the sofa) and hears something beyond it: the sofa's point stays
        let west = Pose2 { x: 1.4, y: 0.0, yaw_deg: 180.0 };
        let (along, left) = Pose2 { x: 1.4 - MOUNT, ..west }.local(sofa);
        assert!(left.abs() <= along * 7.5_f64.to_radians().tan(), "the point lies in the cone");
        s.add_reading(west, MOUNT, Some(1.35), 7.5, 4.0);
        assert!(near_sofa(&s).is_some());
        // from the north again, a longer echo says the sofa is gone
        s.add_reading(north, MOUNT, Some(1.0), 7.5, 4.0);
        assert!(near_sofa(&s).is_none());
    }

    #[test]
    fn far_points_are_forgotten_and_the_count_is_bounded() {
        let mut s = Surroundings::default();
        s.add_echo(Pose2::default(), MOUNT, 0.1);
        s.add_echo(Pose2 { x: 3.0, y: 0.0, yaw_deg: 0.0 }, MOUNT, 0.1);
        assert_eq!(s.len(), 1, "the point near the origin is 2.8 m behind now");
        for i in 0..(MAX_POINTS + 10) {
            s.add_echo(Pose2 { x: 3.0, y: 0.0, yaw_deg: i as f64 }, MOUNT, 0.1);
        }
        assert_eq!(s.len(), MAX_POINTS);
        s.add_echo(Pose2::default(), MOUNT, f64::NAN);
        assert_eq!(s.len(), MAX_POINTS, "a NaN range adds nothing");
    }
}
