//! `map.png`: Cute's map drawn over the true room.
//!
//! The true room is drawn first (outside the walls dark grey, obstacles black, floor white), then
//! each grid cell is tinted by what Cute's map says (free green, obstacle red, unknown left
//! untinted), then the grid lines, the robot's trail (blue) and its final pose (a box with a line
//! towards its heading). A cell that is red over white floor, or green over black, is a map error.
//! The room itself is rasterised by [`crate::raster`], as the window's floor is.

use image::{Rgb, RgbImage};

use crate::grid::GridFrame;
use crate::raster::{Palette, PixelGrid, RoomShapes, bounds};
use crate::scenario::Scenario;

/// The true room in `map.png`.
pub const PALETTE: Palette =
    Palette { outside: [90, 90, 90], obstacle: [20, 20, 20], floor: [255, 255, 255] };

/// Pixels per metre for rooms up to ~25 m; larger rooms are scaled down to fit [`MAX_SIDE`].
const SCALE: f32 = 160.0;
/// Longest side of the picture, pixels.
const MAX_SIDE: f32 = 4096.0;
/// Border around the room, pixels.
const BORDER: u32 = 12;

/// What to draw.
pub struct MapPicture<'a> {
    /// The room.
    pub scenario: &'a Scenario,
    /// The grid's placement.
    pub frame: GridFrame,
    /// Cute's knowledge per cell, row-major: `Some(true)` free, `Some(false)` obstacle.
    pub known: &'a [Option<bool>],
    /// The robot's trail, world metres.
    pub trail: &'a [(f32, f32)],
    /// Final pose: x, y, heading (radians CCW).
    pub pose: (f32, f32, f32),
    /// Robot body length and width, metres.
    pub body: (f32, f32),
}

impl MapPicture<'_> {
    /// Renders the picture.
    pub fn render(&self) -> RgbImage {
        let ((min_x, min_y), (max_x, max_y)) = bounds(&self.scenario.room);
        let extent = (max_x - min_x).max(max_y - min_y).max(1e-3);
        let scale = SCALE.min(MAX_SIDE / extent);
        let w = ((max_x - min_x) * scale).clamp(1.0, MAX_SIDE) as u32 + 2 * BORDER;
        let h = ((max_y - min_y) * scale).clamp(1.0, MAX_SIDE) as u32 + 2 * BORDER;
        let grid = PixelGrid { min_x, max_y, scale, border: BORDER as f32, width: w, height: h };
        let to_px = |x: f32, y: f32| grid.to_px(x, y);
        let pixels = RoomShapes::new(self.scenario).paint(&grid, &PALETTE, |x, y, c| {
            match self.frame.cell_at(x, y).and_then(|(row, col)| self.known.get(row * self.frame.cols + col))
            {
                Some(Some(true)) => blend(c, [60, 200, 90], 0.35),
                Some(Some(false)) => blend(c, [230, 40, 40], 0.55),
                _ => c,
            }
        });
        let mut img = RgbImage::from_fn(w, h, |px, py| {
            Rgb(pixels.get((py * w + px) as usize).copied().unwrap_or_default())
        });
        // Grid lines.
        let f = self.frame;
        for row in 0..=f.rows {
            let y = f.top - row as f32 * f.cell;
            line(&mut img, to_px(f.left, y), to_px(f.left + f.cols as f32 * f.cell, y), [170, 170, 200]);
        }
        for col in 0..=f.cols {
            let x = f.left + col as f32 * f.cell;
            line(&mut img, to_px(x, f.top), to_px(x, f.top - f.rows as f32 * f.cell), [170, 170, 200]);
        }
        // Trail.
        for pair in self.trail.windows(2) {
            line(&mut img, to_px(pair[0].0, pair[0].1), to_px(pair[1].0, pair[1].1), [30, 80, 230]);
        }
        // Robot: its outline and a heading line.
        let (x, y, th) = self.pose;
        let (s, c) = th.sin_cos();
        let (hl, hw) = (self.body.0 * 0.5, self.body.1 * 0.5);
        let corner = |bx: f32, by: f32| to_px(x + c * bx - s * by, y + s * bx + c * by);
        let corners = [corner(hl, hw), corner(-hl, hw), corner(-hl, -hw), corner(hl, -hw)];
        for i in 0..4 {
            line(&mut img, corners[i], corners[(i + 1) % 4], [0, 0, 160]);
        }
        line(&mut img, to_px(x, y), corner(hl * 1.6, 0.0), [0, 0, 160]);
        img
    }
}

fn blend(base: [u8; 3], tint: [u8; 3], alpha: f32) -> [u8; 3] {
    let mix = |a: u8, b: u8| (a as f32 * (1.0 - alpha) + b as f32 * alpha).round() as u8;
    [mix(base[0], tint[0]), mix(base[1], tint[1]), mix(base[2], tint[2])]
}

/// Draws a 2-pixel line, clipped to the image.
fn line(img: &mut RgbImage, from: (f32, f32), to: (f32, f32), color: [u8; 3]) {
    let (dx, dy) = (to.0 - from.0, to.1 - from.1);
    let n = dx.abs().max(dy.abs()).ceil().max(1.0) as u32;
    for i in 0..=n {
        let t = i as f32 / n as f32;
        let (x, y) = (from.0 + dx * t, from.1 + dy * t);
        for (ox, oy) in [(0.0, 0.0), (0.5, 0.0), (0.0, 0.5)] {
            let (px, py) = ((x + ox).floor(), (y + oy).floor());
            if px >= 0.0 && py >= 0.0 && (px as u32) < img.width() && (py as u32) < img.height() {
                img.put_pixel(px as u32, py as u32, Rgb(color));
            }
        }
    }
}
