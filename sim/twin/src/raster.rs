//! One rasteriser for the true room: `map.png` (`twin_pictures::mapimg`) and the window's floor
//! texture (`twin_app::window`) both colour pixels by what lies under their centres.
//!
//! Concept: [`RoomShapes`] answers "outside the walls, on an obstacle, or floor?" for a world
//! point ([`Ground`]); [`PixelGrid`] maps pixel centres to world metres (row 0 at the top, y up in
//! the world, an optional border of pixels around the room); [`RoomShapes::paint`] colours a whole
//! grid with a [`Palette`] and a per-pixel tint. Each picture keeps its own palette and size.
//!
//! Invariant: a pixel's colour depends only on its centre, so the same room gives the same
//! bytes every time. A thin wall (a segment obstacle) counts within 12 mm, so it shows.
//!
//! ```
//! use twin::raster::{Ground, RoomShapes};
//! let loaded = twin::setup::RunSetup::builtin_default()?;
//! let shapes = RoomShapes::new(&loaded.scenario);
//! assert_eq!(shapes.ground_at(1.55, 0.35), Ground::Obstacle); // the sofa
//! assert_eq!(shapes.ground_at(0.3, 2.2), Ground::Floor);
//! assert_eq!(shapes.ground_at(-1.0, -1.0), Ground::Outside);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use rapier2d::parry::math::Vector;
use rapier2d::parry::query::PointQuery;

use crate::grid::{PlacedShape, point_in_poly2d, room_aabb, room_points};
use crate::scenario::Scenario;

/// A thin wall is drawn this close to its line, metres.
const THIN_WALL_M: f32 = 0.012;

/// What lies at a point of the world.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ground {
    /// Outside the room's walls.
    Outside,
    /// Inside an obstacle (or on a thin wall).
    Obstacle,
    /// Free floor.
    Floor,
}

/// Colours of the three kinds of ground, RGB.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Palette {
    /// Outside the room.
    pub outside: [u8; 3],
    /// Obstacles.
    pub obstacle: [u8; 3],
    /// Floor.
    pub floor: [u8; 3],
}

impl Palette {
    /// The colour of `ground`.
    pub fn of(&self, ground: Ground) -> [u8; 3] {
        match ground {
            Ground::Outside => self.outside,
            Ground::Obstacle => self.obstacle,
            Ground::Floor => self.floor,
        }
    }
}

/// A room's bounding box: (min x, min y) and (max x, max y), metres.
pub fn bounds(room: &[(f32, f32)]) -> ((f32, f32), (f32, f32)) {
    let aabb = room_aabb(room);
    ((aabb.mins.x, aabb.mins.y), (aabb.maxs.x, aabb.maxs.y))
}

/// Pixel centres in world metres: pixel (0, 0) is at the top left of the room's bounding box,
/// `border` pixels in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelGrid {
    /// Left edge of the room's bounding box, metres.
    pub min_x: f32,
    /// Top edge of the room's bounding box, metres.
    pub max_y: f32,
    /// Pixels per metre.
    pub scale: f32,
    /// Pixels left free around the room.
    pub border: f32,
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
}

impl PixelGrid {
    /// The world point at the centre of pixel (`px`, `py`).
    pub fn world_at(&self, px: u32, py: u32) -> (f32, f32) {
        (
            self.min_x + (px as f32 + 0.5 - self.border) / self.scale,
            self.max_y - (py as f32 + 0.5 - self.border) / self.scale,
        )
    }

    /// The pixel position (fractional) of world point (`x`, `y`).
    pub fn to_px(&self, x: f32, y: f32) -> (f32, f32) {
        ((x - self.min_x) * self.scale + self.border, (self.max_y - y) * self.scale + self.border)
    }
}

/// The room's walls and obstacles, for point queries.
pub struct RoomShapes {
    room: Vec<Vector>,
    obstacles: Vec<PlacedShape>,
}

impl RoomShapes {
    /// The scenario's room and obstacles.
    pub fn new(scenario: &Scenario) -> RoomShapes {
        RoomShapes { room: room_points(&scenario.room), obstacles: scenario.obstacle_shapes() }
    }

    /// What lies at world point (`x`, `y`).
    pub fn ground_at(&self, x: f32, y: f32) -> Ground {
        let p = Vector::new(x, y);
        if !point_in_poly2d(p, &self.room) {
            return Ground::Outside;
        }
        let hit = self.obstacles.iter().any(|(pose, shape)| {
            shape.contains_point(pose, p)
                || shape.as_segment().is_some_and(|seg| {
                    seg.distance_to_local_point(pose.inverse_transform_point(p), true) < THIN_WALL_M
                })
        });
        if hit { Ground::Obstacle } else { Ground::Floor }
    }

    /// Every pixel of `grid`, row by row from the top: the palette's colour of its ground,
    /// passed through `tint(x, y, colour)` (world metres of the pixel centre).
    pub fn paint(
        &self,
        grid: &PixelGrid,
        palette: &Palette,
        mut tint: impl FnMut(f32, f32, [u8; 3]) -> [u8; 3],
    ) -> Vec<[u8; 3]> {
        let mut out = Vec::with_capacity(grid.width as usize * grid.height as usize);
        for py in 0..grid.height {
            for px in 0..grid.width {
                let (x, y) = grid.world_at(px, py);
                out.push(tint(x, y, palette.of(self.ground_at(x, y))));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixel_centres_and_positions_are_inverse() {
        let g = PixelGrid { min_x: -1.0, max_y: 2.0, scale: 10.0, border: 3.0, width: 40, height: 40 };
        let (x, y) = g.world_at(3, 3);
        assert!((x + 0.95).abs() < 1e-6 && (y - 1.95).abs() < 1e-6, "{x} {y}");
        let (px, py) = g.to_px(x, y);
        assert!((px - 3.5).abs() < 1e-4 && (py - 3.5).abs() < 1e-4, "{px} {py}");
    }

    #[test]
    fn paint_is_row_major_from_the_top() {
        let loaded = crate::setup::RunSetup::builtin_default().unwrap();
        let shapes = RoomShapes::new(&loaded.scenario);
        let ((min_x, _), (_, max_y)) = bounds(&loaded.scenario.room);
        let grid = PixelGrid { min_x, max_y, scale: 20.0, border: 0.0, width: 8, height: 5 };
        let palette = Palette { outside: [0, 0, 0], obstacle: [1, 1, 1], floor: [2, 2, 2] };
        let pixels = shapes.paint(&grid, &palette, |_, _, c| c);
        assert_eq!(pixels.len(), 40);
        let (x, y) = grid.world_at(7, 4);
        assert_eq!(pixels[4 * 8 + 7], palette.of(shapes.ground_at(x, y)));
    }
}
