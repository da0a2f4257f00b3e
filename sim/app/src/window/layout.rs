//! Where things sit in the window: its size, the status bar, and [`WorldLayout`], the only map
//! from world metres to logical pixels.
//!
//! Invariant: the world view is fitted into the left half of the window, below Cute's toolbar
//! and above the status bar, with square pixels (1 m is the same length both ways); y grows up
//! in the world and down on screen.

use bevy::math::{Rect, Vec2};
use cute::gui::TOOLBAR_HEIGHT;

use twin::raster::bounds;

/// Window size, logical pixels.
pub const WINDOW_SIZE: (u32, u32) = (1280, 720);
/// Height of the status bar at the bottom, logical pixels.
pub const STATUS_HEIGHT: f32 = 46.0;

/// A room's bounding box as (min, max) corners, metres.
pub fn room_box(room: &[(f32, f32)]) -> (Vec2, Vec2) {
    let ((x0, y0), (x1, y1)) = bounds(room);
    (Vec2::new(x0, y0), Vec2::new(x1, y1))
}

/// Where the world view sits: its region and the metres-to-pixels map (logical pixels, origin
/// top-left, y down).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldLayout {
    /// The region the world is fitted into.
    pub region: Rect,
    /// Pixels per metre.
    pub scale: f32,
    /// World point (metres) drawn at the region's centre.
    pub centre: Vec2,
}

impl WorldLayout {
    /// Fits the room's bounding box into the left half of a window of `window` logical pixels,
    /// below the toolbar and above the status bar.
    pub fn compute(window: Vec2, room: &[(f32, f32)]) -> WorldLayout {
        let (min, max) = room_box(room);
        let pad = 14.0;
        let region =
            Rect::new(pad, TOOLBAR_HEIGHT + pad, window.x * 0.5 - pad, window.y - STATUS_HEIGHT - pad);
        let size = (max - min).max(Vec2::splat(1e-3));
        let scale = (region.width().max(1.0) / size.x).min(region.height().max(1.0) / size.y);
        WorldLayout { region, scale, centre: (min + max) * 0.5 }
    }

    /// World metres to logical pixels.
    pub fn to_logical(&self, x: f32, y: f32) -> Vec2 {
        let c = self.region.center();
        Vec2::new(c.x + (x - self.centre.x) * self.scale, c.y - (y - self.centre.y) * self.scale)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn world_layout_keeps_the_room_in_the_left_half() {
        let room = [(0.0, 0.0), (3.1, 0.0), (3.1, 2.5), (0.0, 2.5)];
        let win = Vec2::new(1280.0, 720.0);
        let l = WorldLayout::compute(win, &room);
        let a = l.to_logical(0.0, 2.5);
        let b = l.to_logical(3.1, 0.0);
        assert!(a.x >= 0.0 && b.x <= 640.0, "{a} {b}");
        assert!(a.y >= TOOLBAR_HEIGHT && b.y <= 720.0 - STATUS_HEIGHT, "{a} {b}");
        // y grows up in the world, down on screen.
        assert!(a.y < b.y);
        // Square pixels: 1 m is the same length both ways.
        let d = l.to_logical(1.0, 1.0) - l.to_logical(0.0, 0.0);
        assert!((d.x + d.y).abs() < 1e-3, "{d}");
    }
}
