//! `map.png`: Cute's map drawn over the true room.
//!
//! The true room is drawn first (outside the walls dark grey, obstacles black, floor white), then
//! each grid cell is tinted by what Cute's map says (free green, obstacle red, unknown left
//! untinted), then the grid lines, the robot's trail (blue) and its final pose (a box with a line
//! towards its heading). A cell that is red over white floor, or green over black, is a map error.

use image::{Rgb, RgbImage};
use rapier2d::parry::math::Vector;
use rapier2d::parry::query::PointQuery;
use rapier2d::parry::shape::Shape;

use crate::grid::{GridFrame, bounds, obstacle_shape, point_in_poly2d, room_points};
use crate::scenario::Scenario;

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
        let (min_x, min_y, max_x, max_y) = bounds(&self.scenario.room);
        let extent = (max_x - min_x).max(max_y - min_y).max(1e-3);
        let scale = SCALE.min(MAX_SIDE / extent);
        let w = ((max_x - min_x) * scale).clamp(1.0, MAX_SIDE) as u32 + 2 * BORDER;
        let h = ((max_y - min_y) * scale).clamp(1.0, MAX_SIDE) as u32 + 2 * BORDER;
        let to_world = |px: u32, py: u32| {
            (
                min_x + (px as f32 + 0.5 - BORDER as f32) / scale,
                max_y - (py as f32 + 0.5 - BORDER as f32) / scale,
            )
        };
        let to_px =
            |x: f32, y: f32| ((x - min_x) * scale + BORDER as f32, (max_y - y) * scale + BORDER as f32);
        let shapes: Vec<_> = self.scenario.obstacles.iter().filter_map(obstacle_shape).collect();
        let room = room_points(&self.scenario.room);
        let mut img = RgbImage::new(w.max(1), h.max(1));
        for (px, py, pixel) in img.enumerate_pixels_mut() {
            let (x, y) = to_world(px, py);
            let mut c = if !point_in_poly2d(Vector::new(x, y), &room) {
                [90, 90, 90]
            } else if shapes.iter().any(|(pose, s)| contains(pose, s.as_ref(), x, y)) {
                [20, 20, 20]
            } else {
                [255, 255, 255]
            };
            if let Some((row, col)) = self.frame.cell_at(x, y) {
                match self.known.get(row * self.frame.cols + col).copied().flatten() {
                    Some(true) => c = blend(c, [60, 200, 90], 0.35),
                    Some(false) => c = blend(c, [230, 40, 40], 0.55),
                    None => {}
                }
            }
            *pixel = Rgb(c);
        }
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

fn contains(pose: &rapier2d::parry::math::Pose, shape: &dyn Shape, x: f32, y: f32) -> bool {
    shape.contains_point(pose, Vector::new(x, y))
        || shape.as_segment().is_some_and(|seg| {
            let p = pose.inverse_transform_point(Vector::new(x, y));
            seg.distance_to_local_point(p, true) < 0.012
        })
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
