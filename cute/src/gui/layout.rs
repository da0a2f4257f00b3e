//! The plain geometry of the GUI: which part of the window the plugin draws in
//! ([`CuteView`]), where each map cell lies in it ([`MapLayout`]), window points to world
//! points, and the colour of each cell value.

use bevy::math::{Rect, Vec2};
use bevy::prelude::Resource;

use super::{MAP_PADDING, TOOLBAR_HEIGHT};
use crate::map::CellValue;
use robot_model::grid::Heading;

/// The part of the window the plugin draws in.
#[derive(Resource, Debug, Clone, Copy, PartialEq)]
pub struct CuteView {
    /// The region as fractions of the window (0..1 each way, origin top-left, y down).
    pub region: Rect,
    /// Logical pixels kept free at the bottom of the region (another plugin's status bar).
    pub inset_bottom: f32,
}

impl Default for CuteView {
    fn default() -> Self {
        CuteView { region: Rect::new(0.0, 0.0, 1.0, 1.0), inset_bottom: 0.0 }
    }
}

impl CuteView {
    /// The region in logical pixels for a window of `window` logical pixels.
    pub fn region_px(&self, window: Vec2) -> Rect {
        Rect::from_corners(self.region.min * window, self.region.max * window)
    }
}

/// Where the map lies in the window: logical pixels, origin top-left, y down.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapLayout {
    /// Top-left corner of cell (0, 0).
    pub origin: Vec2,
    /// Side of one cell.
    pub cell: f32,
    /// Map rows.
    pub rows: usize,
    /// Map columns.
    pub cols: usize,
}

impl MapLayout {
    /// Fits a `rows × cols` map, square cells, centred in the view's region below the toolbar.
    /// Cells of 4 px or more get a whole number of pixels, so grid lines stay crisp.
    pub fn compute(window: Vec2, view: &CuteView, rows: usize, cols: usize) -> MapLayout {
        let region = view.region_px(window);
        let top = region.min.y + TOOLBAR_HEIGHT + MAP_PADDING;
        let bottom = region.max.y - view.inset_bottom - MAP_PADDING;
        let left = region.min.x + MAP_PADDING;
        let right = region.max.x - MAP_PADDING;
        let (w, h) = ((right - left).max(1.0), (bottom - top).max(1.0));
        let (rows, cols) = (rows.max(1), cols.max(1));
        let mut cell = (w / cols as f32).min(h / rows as f32);
        if cell >= 4.0 {
            cell = cell.floor();
        }
        let size = Vec2::new(cell * cols as f32, cell * rows as f32);
        let origin = Vec2::new(left + (w - size.x) * 0.5, top + (h - size.y) * 0.5).round();
        MapLayout { origin, cell, rows, cols }
    }

    /// The whole map.
    pub fn map_rect(&self) -> Rect {
        Rect::from_corners(
            self.origin,
            self.origin + Vec2::new(self.cols as f32, self.rows as f32) * self.cell,
        )
    }

    /// The square of cell (row, col).
    pub fn cell_rect(&self, row: usize, col: usize) -> Rect {
        let min = self.origin + Vec2::new(col as f32, row as f32) * self.cell;
        Rect::from_corners(min, min + Vec2::splat(self.cell))
    }

    /// The side two neighbouring cells share, as a segment (for a blocked move); `None` if they
    /// are not 4-neighbours.
    pub fn shared_side(&self, a: (u8, u8), b: (u8, u8)) -> Option<(Vec2, Vec2)> {
        let (first, second) = (a.min(b), a.max(b));
        let r = self.cell_rect(usize::from(first.0), usize::from(first.1));
        // the smaller cell is the upper or the left one
        match Heading::between(first, second)? {
            Heading::East => Some((Vec2::new(r.max.x, r.min.y), r.max)),
            _ => Some((Vec2::new(r.min.x, r.max.y), r.max)),
        }
    }

    /// The cell under logical point `p`, if any.
    pub fn cell_at(&self, p: Vec2) -> Option<(u8, u8)> {
        let rel = (p - self.origin) / self.cell;
        if rel.x < 0.0 || rel.y < 0.0 {
            return None;
        }
        let (row, col) = (rel.y.floor() as usize, rel.x.floor() as usize);
        if row >= self.rows || col >= self.cols {
            return None;
        }
        Some((u8::try_from(row).ok()?, u8::try_from(col).ok()?))
    }
}

/// Logical window point (origin top-left, y down) to world point for a `Camera2d` at the
/// origin with the default projection.
pub fn logical_to_world(window: Vec2, p: Vec2) -> Vec2 {
    Vec2::new(p.x - window.x * 0.5, window.y * 0.5 - p.y)
}

/// The sRGB colour of a cell value, as the original Cute drew it.
pub const fn cell_rgb(value: CellValue) -> [u8; 3] {
    match value {
        CellValue::Obstacle => [20, 20, 20],
        CellValue::Free => [190, 190, 190],
        CellValue::Unknown => [250, 250, 250],
        CellValue::Waypoint => [220, 40, 40],
        CellValue::Destination => [245, 150, 20],
        CellValue::Robot => [40, 90, 230],
    }
}
