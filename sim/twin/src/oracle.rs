//! What an analysis run gives Carto beyond its sonar ([`Oracle`]): the room's surfaces as points
//! in Carto's frame (`--known-room`, perception taken out of the picture), or every point the
//! sonar has heard, where it really lies (`--known-echoes`, Carto's memory taken out of it).
//!
//! Carto learns the room only through one forward sonar. To tell what fails because of what the
//! sonar cannot see from what fails for any other reason (planning, margins, localisation),
//! `explobot run --known-room` and `explobot sweep --known-room` give Carto every surface of the
//! room before the run ([`carto::Carto::add_floor_plan`]: a complete plan, so space without a
//! point is known free and Carto's local motion may slide through it): points every
//! [`SPACING_M`] along the room's walls and every obstacle's outline, in the grid's metric frame
//! (x east, y north, cell (0, 0)'s centre at the origin). Carto's safety checks then treat them
//! as echoes that are never cleared. Such a run is an analysis, a ceiling for perfect
//! perception: its report says so (`known_room: true`), and it is never the robot's result.
//!
//! `--known-echoes` gives Carto less: during the run, every point of a surface the twin's sonar
//! has reported an echo from (the nearest audible hit of each measurement, on a 1 cm grid), placed
//! where it really is and never forgotten, from the step after the measurement
//! ([`carto::Carto::add_known_surfaces`]). It asks how far a perfect memory of what the sonar
//! heard would go: Carto itself knows an echo only as a range somewhere across a 15° cone, placed
//! from its odometry, and forgets it (`docs/explanation/carto-design.md`). Such a run's report says
//! `known_echoes: true`.
//!
//! ```
//! use twin::scenario::Scenario;
//! use twin::grid::room_frame;
//! let s = Scenario::from_ron_str("Scenario(name: \"t\", room: [(0.0, 0.0), (0.9, 0.0), (0.9, 0.9), (0.0, 0.9)], \
//!     start: (row: 0, col: 0, heading: East), obstacles: [Circle(center: (0.45, 0.45), radius: 0.05)])", "t.ron").unwrap();
//! let frame = room_frame(&s.room, 0.45);
//! let points = twin::oracle::surface_points(&s, &frame, 0.01);
//! // cell (0, 0)'s centre is at the origin: the leg's centre, (0.45, 0.45) in the room, is 0.225 m
//! // east and 0.225 m south of it, and its outline 5 cm around that
//! assert!(points.iter().any(|&(x, y)| ((x - 0.225).hypot(y + 0.225) - 0.05).abs() < 1e-6));
//! ```

use rapier2d::parry::math::Vector;
use rapier2d::parry::shape::ConvexPolygon;
use robot_model::grid::GridFrame;

use crate::scenario::{Obstacle, Scenario};

/// What a run gives Carto beyond its own sensors (module docs); defined beside the recording
/// format, which stores it.
pub use transport::recording::Oracle;

/// Spacing of the points along every surface, metres: under the 2 cm clearance Carto keeps.
pub const SPACING_M: f64 = 0.01;

/// The world point `(x, y)` in the metric frame of the grid `frame`, Carto's frame (see the
/// module docs): the points given to Carto, and the world's spots compared with Carto's echo
/// points ([`crate::report::FirstContact::touched_held_m`]).
pub fn to_carto_frame(frame: &GridFrame, (x, y): (f64, f64)) -> (f64, f64) {
    let (cx, cy) = frame.cell_center(0, 0);
    (x - f64::from(cx), y - f64::from(cy))
}

/// Points at most `step_m` apart along every wall and obstacle outline of `s`, in the metric
/// frame of the grid `frame` (see the module docs).
pub fn surface_points(s: &Scenario, frame: &GridFrame, step_m: f64) -> Vec<(f64, f64)> {
    let step_m = step_m.max(1e-3);
    let mut out = Vec::new();
    let mut segment = |a: (f64, f64), b: (f64, f64)| {
        let n = ((b.0 - a.0).hypot(b.1 - a.1) / step_m).ceil().max(1.0) as usize;
        for i in 0..=n {
            let t = i as f64 / n as f64;
            out.push(to_carto_frame(frame, (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t)));
        }
    };
    let p = |(x, y): (f32, f32)| (f64::from(x), f64::from(y));
    let polygon = |corners: &[(f64, f64)], segment: &mut dyn FnMut((f64, f64), (f64, f64))| {
        for (i, &a) in corners.iter().enumerate() {
            segment(a, corners[(i + 1) % corners.len()]);
        }
    };
    let room: Vec<(f64, f64)> = s.room.iter().copied().map(p).collect();
    polygon(&room, &mut segment);
    for o in &s.obstacles {
        match o {
            Obstacle::Box { center, size, angle_deg } => {
                let (sin, cos) = f64::from(*angle_deg).to_radians().sin_cos();
                let (hx, hy) = (f64::from(size.0) / 2.0, f64::from(size.1) / 2.0);
                let c = p(*center);
                let corner = |u: f64, v: f64| (c.0 + u * cos - v * sin, c.1 + u * sin + v * cos);
                polygon(&[corner(-hx, -hy), corner(hx, -hy), corner(hx, hy), corner(-hx, hy)], &mut segment);
            }
            Obstacle::Circle { center, radius } => {
                let (c, r) = (p(*center), f64::from(*radius));
                let n = ((std::f64::consts::TAU * r / step_m).ceil() as usize).max(8);
                let at = |i: usize| {
                    let a = std::f64::consts::TAU * i as f64 / n as f64;
                    (c.0 + r * a.cos(), c.1 + r * a.sin())
                };
                let ring: Vec<(f64, f64)> = (0..n).map(at).collect();
                polygon(&ring, &mut segment);
            }
            Obstacle::Segment { from, to } => segment(p(*from), p(*to)),
            // the convex hull, as the physics has it (`Obstacle::shape`)
            Obstacle::Polygon { points } => {
                let given: Vec<Vector> = points.iter().map(|&(x, y)| Vector::new(x, y)).collect();
                if let Some(hull) = ConvexPolygon::from_convex_hull(&given) {
                    let corners: Vec<(f64, f64)> = hull.points().iter().map(|v| p((v.x, v.y))).collect();
                    polygon(&corners, &mut segment);
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::room_frame;

    #[test]
    fn a_rotated_box_and_the_walls_are_outlined_without_gaps() {
        let s = Scenario::from_ron_str(
            "Scenario(name: \"t\", room: [(0.0, 0.0), (1.35, 0.0), (1.35, 0.9), (0.0, 0.9)], \
             start: (row: 0, col: 0, heading: East), \
             obstacles: [Box(center: (0.9, 0.45), size: (0.2, 0.1), angle_deg: 30.0)])",
            "t.ron",
        )
        .unwrap();
        let frame = room_frame(&s.room, 0.45);
        let points = surface_points(&s, &frame, 0.01);
        // the grid's (0, 0) centre is (0.225, 0.675) in the room
        let room = |x: f64, y: f64| (x - 0.225, y - 0.675);
        let near = |q: (f64, f64)| points.iter().any(|&p| (p.0 - q.0).hypot(p.1 - q.1) <= 0.0051);
        // every wall, every 1 cm
        for i in 0..=135 {
            let x = f64::from(i) / 100.0;
            assert!(near(room(x, 0.0)) && near(room(x, 0.9)), "wall at x = {x}");
        }
        // a corner of the box, 30° turned: (0.9, 0.45) + R(30°)·(0.1, 0.05)
        let (sin, cos) = 30f64.to_radians().sin_cos();
        assert!(near(room(0.9 + 0.1 * cos - 0.05 * sin, 0.45 + 0.1 * sin + 0.05 * cos)));
        // and nothing inside it
        assert!(!near(room(0.9, 0.45)));
    }
}
