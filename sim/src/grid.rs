//! The planning grid laid over a room, and the ground truth Cute's map is scored against.
//!
//! The grid covers the room's bounding box with whole cells; what is left over is split evenly
//! as a margin on each side. Row 0 is the top row (largest world `y`), column 0 the leftmost. A
//! cell is **free** in the ground truth when its square lies inside the room and touches no
//! obstacle; **reachable** cells are the free cells 4-connected to the start cell.
//!
//! This module knows polygons and parry shapes, not scenarios: [`crate::scenario`] turns its
//! obstacles into shapes and builds the grid once per scenario
//! ([`crate::scenario::LoadedScenario::truth`]).
//!
//! ```
//! use rapier2d::parry::math::{Pose, Vector};
//! use rapier2d::parry::shape::{Ball, Shape};
//! use sim::grid::{TruthGrid, room_frame};
//! let room = [(0.0, 0.0), (1.3, 0.0), (1.3, 0.95), (0.0, 0.95)];
//! let leg: (Pose, Box<dyn Shape>) = (Pose::from_translation(Vector::new(0.2, 0.8)), Box::new(Ball::new(0.02)));
//! let truth = TruthGrid::build(room_frame(&room, 0.3), &room, &[leg]);
//! assert_eq!((truth.rows, truth.cols), (3, 4));
//! assert!(!truth.is_free(0, 0) && truth.is_free(2, 3));
//! ```

use std::collections::VecDeque;

use rapier2d::parry::bounding_volume::Aabb;
use rapier2d::parry::math::{Pose, Vector};
use rapier2d::parry::query;
use rapier2d::parry::shape::{Cuboid, Segment, Shape};
pub use rapier2d::parry::utils::point_in_poly2d;

pub use robot_model::grid::{GridFrame, MAX_CELLS};

/// A fixed shape and where it stands in the world.
pub type PlacedShape = (Pose, Box<dyn Shape>);

/// The planning grid over `room`'s bounding box with cells of `cell` metres.
pub fn room_frame(room: &[(f32, f32)], cell: f32) -> GridFrame {
    let aabb = room_aabb(room);
    GridFrame::for_bounds((aabb.mins.x, aabb.mins.y), (aabb.maxs.x, aabb.maxs.y), cell)
}

/// Which cells of the grid are free in the real room.
#[derive(Debug, Clone)]
pub struct TruthGrid {
    /// The grid's placement.
    pub frame: GridFrame,
    /// Number of rows.
    pub rows: usize,
    /// Number of columns.
    pub cols: usize,
    free: Vec<bool>,
}

impl TruthGrid {
    /// Rasterises `room` (a polygon) and `obstacles` onto `frame`.
    pub fn build(frame: GridFrame, room: &[(f32, f32)], obstacles: &[PlacedShape]) -> TruthGrid {
        let walls: Vec<Segment> = room_edges(room).collect();
        let room = room_points(room);
        // Obstacles are tested against the closed cell square: a thin wall lying on the edge
        // between two cells blocks both, as the robot cannot cross it. The room's own walls are
        // tested against a square shrunk by 1 mm, so a room that is a whole number of cells wide
        // keeps its edge cells.
        let half = frame.cell * 0.5 - 1e-3;
        let square = Cuboid::new(Vector::new(half, half));
        let closed = Cuboid::new(Vector::new(frame.cell * 0.5, frame.cell * 0.5));
        let identity = Pose::IDENTITY;
        let mut free = Vec::with_capacity(frame.rows * frame.cols);
        for row in 0..frame.rows {
            for col in 0..frame.cols {
                let (cx, cy) = frame.cell_center(row, col);
                let at = Pose::from_translation(Vector::new(cx, cy));
                let inside = [(-half, -half), (half, -half), (half, half), (-half, half)]
                    .iter()
                    .all(|&(dx, dy)| point_in_poly2d(Vector::new(cx + dx, cy + dy), &room));
                let crosses_wall = walls.iter().any(|w| intersects(&at, &square, &identity, w));
                let hits_obstacle =
                    obstacles.iter().any(|(pose, s)| intersects(&at, &closed, pose, s.as_ref()));
                free.push(inside && !crosses_wall && !hits_obstacle);
            }
        }
        TruthGrid { frame, rows: frame.rows, cols: frame.cols, free }
    }

    /// Whether (row, col) is on the grid and free.
    pub fn is_free(&self, row: usize, col: usize) -> bool {
        row < self.rows && col < self.cols && self.free[row * self.cols + col]
    }

    /// For every cell, whether it is free and 4-connected to `start`; row-major.
    pub fn reachable_from(&self, start: (usize, usize)) -> Vec<bool> {
        let mut seen = vec![false; self.rows * self.cols];
        if !self.is_free(start.0, start.1) {
            return seen;
        }
        let mut queue = VecDeque::from([start]);
        seen[start.0 * self.cols + start.1] = true;
        while let Some((r, c)) = queue.pop_front() {
            let neighbours = [(r.wrapping_sub(1), c), (r + 1, c), (r, c.wrapping_sub(1)), (r, c + 1)];
            for (nr, nc) in neighbours {
                if self.is_free(nr, nc) && !seen[nr * self.cols + nc] {
                    seen[nr * self.cols + nc] = true;
                    queue.push_back((nr, nc));
                }
            }
        }
        seen
    }
}

/// Whether two shapes overlap; a pair parry cannot test counts as overlapping (safe side).
fn intersects(p1: &Pose, s1: &dyn Shape, p2: &Pose, s2: &dyn Shape) -> bool {
    query::intersection_test(p1, s1, p2, s2).map_or(true, |i| i.intersecting)
}

/// A polygon's bounding box (empty polygon: `mins` above `maxs`).
pub fn room_aabb(room: &[(f32, f32)]) -> Aabb {
    Aabb::from_points(room.iter().map(|&(x, y)| Vector::new(x, y)))
}

/// Width and height of a polygon's bounding box, metres.
pub fn room_extent(room: &[(f32, f32)]) -> (f32, f32) {
    let aabb = room_aabb(room);
    ((aabb.maxs.x - aabb.mins.x).max(0.0), (aabb.maxs.y - aabb.mins.y).max(0.0))
}

/// A polygon's corners as parry points, for [`point_in_poly2d`].
pub fn room_points(room: &[(f32, f32)]) -> Vec<Vector> {
    room.iter().map(|&(x, y)| Vector::new(x, y)).collect()
}

/// The room polygon's edges as segments.
pub fn room_edges(room: &[(f32, f32)]) -> impl Iterator<Item = Segment> + '_ {
    (0..room.len()).map(move |i| {
        let (x0, y0) = room[i];
        let (x1, y1) = room[(i + 1) % room.len()];
        Segment::new(Vector::new(x0, y0), Vector::new(x1, y1))
    })
}

#[cfg(test)]
mod tests {
    use rapier2d::parry::shape::Ball;

    use super::*;

    const ROOM: [(f32, f32); 4] = [(0.0, 0.0), (1.3, 0.0), (1.3, 0.95), (0.0, 0.95)];

    /// The 1.3 x 0.95 m test room in 0.3 m cells, with `obstacles`.
    fn truth(obstacles: Vec<PlacedShape>) -> TruthGrid {
        TruthGrid::build(room_frame(&ROOM, 0.3), &ROOM, &obstacles)
    }

    fn wall(from: (f32, f32), to: (f32, f32)) -> PlacedShape {
        (Pose::IDENTITY, Box::new(Segment::new(Vector::new(from.0, from.1), Vector::new(to.0, to.1))))
    }

    #[test]
    fn grid_is_centred_in_the_room_with_whole_cells() {
        // The frame itself is tested in robot_model::grid; here, that the room's truth uses it.
        let g = truth(Vec::new());
        assert_eq!((g.rows, g.cols), (3, 4));
        assert!((g.frame.left - 0.05).abs() < 1e-5);
        assert!((g.frame.top - 0.925).abs() < 1e-5);
        assert_eq!(g.frame.cell_at(0.06, 0.9), Some((0, 0)));
        assert_eq!(g.frame.cell_at(1.24, 0.03), Some((2, 3)));
        assert_eq!(g.frame.cell_at(1.29, 0.5), None);
        assert!((0..3).all(|r| (0..4).all(|c| g.is_free(r, c))));
    }

    #[test]
    fn obstacles_block_the_cells_they_touch() {
        // A box over the centre of cell (1, 1) and a leg straddling columns 1 and 2 of row 0 (x = 0.65).
        let g = truth(vec![
            (Pose::from_translation(Vector::new(0.5, 0.475)), Box::new(Cuboid::new(Vector::new(0.05, 0.05)))),
            (Pose::from_translation(Vector::new(0.65, 0.8)), Box::new(Ball::new(0.02))),
        ]);
        assert!(!g.is_free(1, 1));
        assert!(!g.is_free(0, 1) && !g.is_free(0, 2));
        assert!(g.is_free(2, 3));
        let reach = g.reachable_from((0, 0));
        assert!(!reach[g.cols + 1]);
        assert!(reach[2 * g.cols + 3]);
    }

    #[test]
    fn a_thin_wall_on_a_cell_edge_blocks_both_cells() {
        let g = truth(vec![wall((0.65, 0.0), (0.65, 0.95))]);
        assert!((0..3).all(|r| !g.is_free(r, 1) && !g.is_free(r, 2)));
        assert!(!g.reachable_from((0, 0))[3]);
    }

    #[test]
    fn an_enclosed_pocket_is_free_but_unreachable() {
        // Walls around cell (2, 3), the bottom-right corner cell (x 0.95..1.25, y 0.025..0.325),
        // standing in its neighbours (2, 2) and (1, 3).
        let g = truth(vec![wall((0.94, 0.0), (0.94, 0.335)), wall((0.94, 0.335), (1.3, 0.335))]);
        assert!(g.is_free(2, 3));
        assert!(!g.is_free(2, 2) && !g.is_free(1, 3));
        assert!(!g.reachable_from((0, 0))[2 * g.cols + 3]);
    }
}
