//! The planning grid laid over a room, and the room's geometry as parry shapes.
//!
//! The grid covers the room's bounding box with whole cells; what is left over is split evenly
//! as a margin on each side. Row 0 is the top row (largest world `y`), column 0 the leftmost.
//! What the robot can do on that grid — the ground truth Cute's map is scored against — is
//! [`crate::truth::RobotTruth`].
//!
//! This module knows polygons and parry shapes, not scenarios: [`crate::scenario`] turns its
//! obstacles into shapes and builds the truth once per scenario
//! ([`crate::setup::RunSetup::truth`]).
//!
//! ```
//! use twin::grid::room_frame;
//! let frame = room_frame(&[(0.0, 0.0), (1.3, 0.0), (1.3, 0.95), (0.0, 0.95)], 0.3);
//! assert_eq!((frame.rows, frame.cols), (3, 4));
//! assert_eq!(frame.cell_at(0.06, 0.9), Some((0, 0)));
//! ```

use rapier2d::parry::bounding_volume::Aabb;
use rapier2d::parry::math::{Pose, Vector};
use rapier2d::parry::shape::{Segment, Shape};
pub use rapier2d::parry::utils::point_in_poly2d;

pub use robot_model::grid::{GridFrame, MAX_CELLS};

/// A fixed shape and where it stands in the world.
pub type PlacedShape = (Pose, Box<dyn Shape>);

/// The planning grid over `room`'s bounding box with cells of `cell` metres.
pub fn room_frame(room: &[(f32, f32)], cell: f32) -> GridFrame {
    let aabb = room_aabb(room);
    GridFrame::for_bounds((aabb.mins.x, aabb.mins.y), (aabb.maxs.x, aabb.maxs.y), cell)
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

/// Whether (x, y) lies inside the polygon `poly` (parry's [`point_in_poly2d`]; converts the
/// polygon on every call: for many points, convert once with [`room_points`]).
pub fn point_in_polygon(poly: &[(f32, f32)], x: f32, y: f32) -> bool {
    point_in_poly2d(Vector::new(x, y), &room_points(poly))
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
    use super::*;

    #[test]
    fn grid_is_centred_in_the_room_with_whole_cells() {
        // The frame itself is tested in robot_model::grid; here, that the room's bounds feed it.
        let room = [(0.0, 0.0), (1.3, 0.0), (1.3, 0.95), (0.0, 0.95)];
        let f = room_frame(&room, 0.3);
        assert_eq!((f.rows, f.cols), (3, 4));
        assert!((f.left - 0.05).abs() < 1e-5);
        assert!((f.top - 0.925).abs() < 1e-5);
        assert_eq!(room_extent(&room), (1.3, 0.95));
        assert!(point_in_polygon(&room, 0.1, 0.1) && !point_in_polygon(&room, 1.31, 0.1));
    }
}
