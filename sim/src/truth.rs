//! What the robot can really do in a room, cell by cell: the ground truth of issue 10 ("real
//! rooms"), measured with the robot's own footprint rather than the cell square.
//!
//! - A cell is **free** when the robot can stand at its centre: its footprint (body length ×
//!   width, from the profile) lies inside the room and touches no wall or obstacle, facing along
//!   the rows (east–west) or along the columns (north–south). [`Stand`] says which fit.
//! - A **move** between two 4-neighbours exists when the body swept along it touches nothing:
//!   the rectangle from one centre to the other, as wide as the body and as long as the step plus
//!   the body length. So a thin wall on the line between two free cells blocks the move even
//!   though both cells are free.
//! - A cell is **reachable** when moves connect it to the start cell.
//! - A cell is **turnable** when the circle the body sweeps turning on the spot (radius: half
//!   its diagonal) touches nothing.
//!
//! Touching means coming within 1 mm (`world::TOUCH`, the gap at which a run counts a collision;
//! parry's exact distance): a footprint 0.5 mm from a wall does not fit. Documented answers to
//! the awkward cases (each has a test below):
//! - a 4 cm table leg on a cell corner: the 0.26 × 0.24 m body at the centre of a 0.30 m cell
//!   clears the corner by 1.5 cm, so the cell stays free, moves past the leg exist, and the robot
//!   may even turn (its turning circle, 17.7 cm, ends 1.5 cm short of the leg);
//! - a wall 2 cm into a cell: facing along the wall the body (half width 12 cm) clears it by
//!   1 cm, facing across it the body (half length 13 cm) touches it. The cell is free (standing
//!   along the wall), the moves along the wall exist, the move towards the wall does not, and
//!   the robot cannot turn there.
//!
//! ```
//! use sim::grid::room_frame;
//! use sim::scenario::Scenario;
//! use sim::truth::RobotTruth;
//! use robot_model::profile::RobotProfile;
//! let s = Scenario::from_ron_str("Scenario(name: \"t\", room: [(0.0, 0.0), (1.2, 0.0), (1.2, 0.6), (0.0, 0.6)], \
//!     start: (row: 0, col: 0, heading: East), obstacles: [Segment(from: (0.6, 0.0), to: (0.6, 0.6))])", "t.ron").unwrap();
//! let p = RobotProfile { grid_cell_m: 0.30, ..RobotProfile::default() };
//! let t = RobotTruth::build(room_frame(&s.room, s.cell_size(&p)), &s.room, &s.obstacle_shapes(), &p);
//! assert!(t.is_free(0, 1) && t.is_free(0, 2));
//! assert!(!t.can_move((0, 1), (0, 2))); // the wall lies on the line between them
//! assert!(!t.reachable_from((0, 0))[2]);
//! ```

use rapier2d::parry::bounding_volume::{Aabb, BoundingVolume};
use rapier2d::parry::math::{Pose, Vector};
use rapier2d::parry::query;
use rapier2d::parry::shape::{Ball, Cuboid, Segment, Shape};
use robot_model::grid::{GridFrame, reachable};
use robot_model::profile::RobotProfile;

use crate::grid::{PlacedShape, point_in_poly2d, room_edges, room_points};
use crate::world::TOUCH;

/// Which ways the robot fits standing at a cell's centre.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Stand {
    /// Facing east or west (body length along x).
    pub along_rows: bool,
    /// Facing north or south (body length along y).
    pub along_cols: bool,
}

impl Stand {
    /// Fits one way or the other.
    pub fn any(self) -> bool {
        self.along_rows || self.along_cols
    }
}

/// The robot-sized truth of a room (see the [module docs](self)).
#[derive(Debug, Clone)]
pub struct RobotTruth {
    /// The grid's placement.
    pub frame: GridFrame,
    /// Number of rows (`frame.rows`).
    pub rows: usize,
    /// Number of columns (`frame.cols`).
    pub cols: usize,
    stand: Vec<Stand>,
    /// Move (r, c) ⇄ (r, c + 1) exists.
    east: Vec<bool>,
    /// Move (r, c) ⇄ (r + 1, c) exists.
    south: Vec<bool>,
    turn: Vec<bool>,
}

/// The room's walls and obstacles as parry shapes, with bounding boxes for a quick reject.
struct Solids<'a> {
    room: Vec<Vector>,
    walls: Vec<(Segment, Aabb)>,
    obstacles: Vec<(&'a Pose, &'a dyn Shape, Aabb)>,
}

impl<'a> Solids<'a> {
    fn new(room: &[(f32, f32)], obstacles: &'a [PlacedShape]) -> Solids<'a> {
        Solids {
            room: room_points(room),
            walls: room_edges(room).map(|w| (w, w.compute_aabb(&Pose::IDENTITY))).collect(),
            obstacles: obstacles.iter().map(|(p, s)| (p, s.as_ref(), s.compute_aabb(p))).collect(),
        }
    }

    /// Whether `shape` at `pose` lies in the room and touches nothing: it stays more than
    /// [`TOUCH`] away from every wall and obstacle, the gap at which the run's collision counter
    /// starts counting a contact (so a turn the truth allows is never a counted collision when
    /// made exactly at the centre). A pair parry cannot measure counts as touching (the safe side).
    fn clear(&self, pose: &Pose, shape: &dyn Shape) -> bool {
        if !point_in_poly2d(pose.translation, &self.room) {
            return false;
        }
        let aabb = shape.compute_aabb(pose).loosened(TOUCH);
        let apart = |p: &Pose, s: &dyn Shape, b: &Aabb| {
            !aabb.intersects(b) || query::distance(pose, shape, p, s).is_ok_and(|d| d.distance > TOUCH)
        };
        self.walls.iter().all(|(w, b)| apart(&Pose::IDENTITY, w, b))
            && self.obstacles.iter().all(|(p, s, b)| apart(p, *s, b))
    }
}

impl RobotTruth {
    /// Measures every cell and move of the grid `frame` over `room` (a polygon) with
    /// `obstacles`, for the robot of `profile`.
    pub fn build(
        frame: GridFrame,
        room: &[(f32, f32)],
        obstacles: &[PlacedShape],
        profile: &RobotProfile,
    ) -> RobotTruth {
        let solids = Solids::new(room, obstacles);
        let (length, width) = (profile.geometry.body_length_m, profile.geometry.body_width_m);
        let (half_l, half_w) = (length * 0.5, width * 0.5);
        let along_rows = Cuboid::new(Vector::new(half_l, half_w));
        let along_cols = Cuboid::new(Vector::new(half_w, half_l));
        let sweep_east = Cuboid::new(Vector::new((frame.cell + length) * 0.5, half_w));
        let sweep_south = Cuboid::new(Vector::new(half_w, (frame.cell + length) * 0.5));
        let turn_circle = Ball::new(half_l.hypot(half_w));
        let at = |x: f32, y: f32| Pose::from_translation(Vector::new(x, y));
        let n = frame.rows * frame.cols;
        let (mut stand, mut east, mut south, mut turn) =
            (Vec::with_capacity(n), vec![false; n], vec![false; n], Vec::with_capacity(n));
        for row in 0..frame.rows {
            for col in 0..frame.cols {
                let (x, y) = frame.cell_center(row, col);
                let pose = at(x, y);
                stand.push(Stand {
                    along_rows: solids.clear(&pose, &along_rows),
                    along_cols: solids.clear(&pose, &along_cols),
                });
                turn.push(solids.clear(&pose, &turn_circle));
            }
        }
        for row in 0..frame.rows {
            for col in 0..frame.cols {
                let i = row * frame.cols + col;
                let (x, y) = frame.cell_center(row, col);
                if col + 1 < frame.cols && stand[i].along_rows && stand[i + 1].along_rows {
                    east[i] = solids.clear(&at(x + frame.cell * 0.5, y), &sweep_east);
                }
                if row + 1 < frame.rows && stand[i].along_cols && stand[i + frame.cols].along_cols {
                    south[i] = solids.clear(&at(x, y - frame.cell * 0.5), &sweep_south);
                }
            }
        }
        RobotTruth { frame, rows: frame.rows, cols: frame.cols, stand, east, south, turn }
    }

    fn index(&self, row: usize, col: usize) -> Option<usize> {
        (row < self.frame.rows && col < self.frame.cols).then_some(row * self.frame.cols + col)
    }

    /// Which ways the robot fits at (row, col); nothing off the grid.
    pub fn stand(&self, row: usize, col: usize) -> Stand {
        self.index(row, col).map_or_else(Stand::default, |i| self.stand[i])
    }

    /// Whether the robot can stand at (row, col) one way or the other.
    pub fn is_free(&self, row: usize, col: usize) -> bool {
        self.stand(row, col).any()
    }

    /// Whether the robot can turn on the spot at (row, col).
    pub fn can_turn(&self, row: usize, col: usize) -> bool {
        self.index(row, col).is_some_and(|i| self.turn[i])
    }

    /// Whether the move between 4-neighbours `a` and `b` exists (either way).
    pub fn can_move(&self, a: (usize, usize), b: (usize, usize)) -> bool {
        let (first, second) = if a <= b { (a, b) } else { (b, a) };
        let Some(i) = self.index(first.0, first.1) else {
            return false;
        };
        if self.index(second.0, second.1).is_none() {
            return false;
        }
        match (second.0 - first.0, second.1 - first.1) {
            (0, 1) => self.east[i],
            (1, 0) => self.south[i],
            _ => false,
        }
    }

    /// For every cell, whether moves connect it to `start`; row-major.
    pub fn reachable_from(&self, start: (usize, usize)) -> Vec<bool> {
        reachable(
            self.frame.rows,
            self.frame.cols,
            start,
            |(r, c)| self.is_free(r, c),
            |a, b| self.can_move(a, b),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 × 3-cell room (1.2 × 0.9 m, no margin) with `obstacles`.
    fn truth(obstacles: &str) -> RobotTruth {
        truth_in(1.2, 0.9, obstacles)
    }

    /// A `w` × `h` m room with `obstacles`, on the 0.30 m cells the documented cases are about.
    fn truth_in(w: f32, h: f32, obstacles: &str) -> RobotTruth {
        let text = format!(
            "Scenario(name: \"t\", room: [(0.0, 0.0), ({w:?}, 0.0), ({w:?}, {h:?}), (0.0, {h:?})], \
             start: (row: 0, col: 0, heading: East), obstacles: [{obstacles}])"
        );
        let s = crate::scenario::Scenario::from_ron_str(&text, "t.ron").unwrap();
        let p = RobotProfile { grid_cell_m: 0.30, ..RobotProfile::default() };
        RobotTruth::build(
            crate::grid::room_frame(&s.room, s.cell_size(&p)),
            &s.room,
            &s.obstacle_shapes(),
            &p,
        )
    }

    #[test]
    fn an_empty_room_on_cell_lines_is_all_free_and_connected() {
        let t = truth("");
        assert_eq!((t.frame.rows, t.frame.cols), (3, 4));
        for r in 0..3 {
            for c in 0..4 {
                assert_eq!(t.stand(r, c), Stand { along_rows: true, along_cols: true }, "({r}, {c})");
                // Against a wall the body cannot turn on the spot: its corners sweep 17.7 cm and
                // the wall is 15 cm from the cell's centre.
                let inner = r == 1 && (1..3).contains(&c);
                assert_eq!(t.can_turn(r, c), inner, "({r}, {c})");
            }
        }
        assert!(t.reachable_from((0, 0)).iter().all(|&r| r));
        assert!(!t.can_move((0, 0), (1, 1)), "diagonals are not moves");
        assert!(!t.can_move((0, 3), (0, 4)), "off the grid");
    }

    #[test]
    fn a_thin_wall_on_a_cell_line_blocks_the_move_not_the_cells() {
        // x = 0.6 is the line between columns 1 and 2.
        let t = truth("Segment(from: (0.6, 0.0), to: (0.6, 0.9))");
        assert!((0..3).all(|r| t.is_free(r, 1) && t.is_free(r, 2)));
        assert!((0..3).all(|r| !t.can_move((r, 1), (r, 2))));
        assert!(t.can_move((0, 1), (1, 1)));
        let reach = t.reachable_from((0, 0));
        assert!(reach[1] && !reach[2] && !reach[3]);
    }

    #[test]
    fn a_thin_leg_on_a_cell_corner_blocks_nothing() {
        // A 5 × 4-cell room; a 4 cm leg on the corner of cells (1, 1), (1, 2), (2, 1), (2, 2),
        // at x 0.6, y 0.6.
        let t = truth_in(1.5, 1.2, "Circle(center: (0.6, 0.6), radius: 0.02)");
        for cell in [(1, 1), (1, 2), (2, 1), (2, 2)] {
            assert!(t.is_free(cell.0, cell.1) && t.can_turn(cell.0, cell.1), "{cell:?}");
        }
        assert!(t.can_move((1, 1), (1, 2)) && t.can_move((1, 1), (2, 1)));
        // A 9 cm pillar there leaves no room for the body in any of the four cells.
        let t = truth_in(1.5, 1.2, "Circle(center: (0.6, 0.6), radius: 0.045)");
        for cell in [(1, 1), (1, 2), (2, 1), (2, 2)] {
            assert!(!t.is_free(cell.0, cell.1), "{cell:?}");
        }
        assert!(t.is_free(0, 0) && t.can_move((0, 0), (1, 0)));
    }

    #[test]
    fn a_wall_two_cm_into_a_cell_leaves_it_free_along_the_wall_only() {
        // Row 0 spans y 0.6..0.9; a wall 2 cm below its top edge, across the whole room.
        let t = truth("Box(center: (0.6, 0.88), size: (1.2, 0.001))");
        assert_eq!(t.stand(0, 1), Stand { along_rows: true, along_cols: false });
        assert!(!t.can_turn(0, 1));
        assert!(t.can_move((0, 1), (0, 2)), "along the wall");
        assert!(!t.can_move((0, 1), (1, 1)), "across it, the body touches the wall at row 0");
        assert!(!t.reachable_from((1, 1))[1], "so row 0 cannot be entered from below");
    }

    /// The truth and the collision counter agree on what touching is: a turn at a cell's centre
    /// that would pass within 1 mm of a wall is not allowed (found in a generated room where the
    /// truth allowed a turn with 0.2 mm to spare and the run counted a collision).
    #[test]
    fn clearance_under_the_collision_gap_counts_as_touching() {
        // Cell (1, 1) is centred at (0.45, 0.45); the turning circle has a radius of
        // hypot(0.13, 0.12) = 0.1769 m. A thin wall at x = 0.45 + radius + gap.
        let radius = 0.13f32.hypot(0.12);
        let wall_at = |gap: f32| {
            let x = 0.45 + radius + gap;
            truth(&format!("Segment(from: ({x:?}, 0.0), to: ({x:?}, 0.9))"))
        };
        assert!(!wall_at(0.0005).can_turn(1, 1), "0.5 mm: the counter would count a contact");
        assert!(wall_at(0.002).can_turn(1, 1), "2 mm: clear");
    }

    #[test]
    fn a_cell_the_body_cannot_fit_in_is_an_obstacle_cell() {
        // A box covering most of cell (1, 1) (x 0.3..0.6, y 0.3..0.6).
        let t = truth("Box(center: (0.45, 0.45), size: (0.1, 0.1), angle_deg: 30.0)");
        assert!(!t.is_free(1, 1));
        assert!(t.is_free(1, 0) && t.is_free(0, 1));
    }

    #[test]
    fn a_closed_pocket_is_free_but_unreachable() {
        // Walls around the bottom-right cell (2, 3): x 0.9..1.2, y 0..0.3.
        let t = truth("Segment(from: (0.9, 0.0), to: (0.9, 0.3)), Segment(from: (0.9, 0.3), to: (1.2, 0.3))");
        assert!(t.is_free(2, 3));
        assert!(!t.reachable_from((0, 0))[2 * 4 + 3]);
        assert!(t.reachable_from((0, 0))[2 * 4 + 2]);
    }
}
