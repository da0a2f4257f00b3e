//! `map.png`: Cute's map drawn over the true room.
//!
//! The true room is drawn first (outside the walls dark grey, obstacles black, floor white), then
//! each grid cell is tinted by what Cute's map says (free green, obstacle red, unknown left
//! untinted), then the grid lines, the moves Cute recorded blocked (a magenta bar on the side
//! the two cells share), the robot's true trail (blue), the trail Carto believed (dashed
//! orange: the centre of the cell Carto stores plus its dead-reckoned offset, see
//! [`twin::localisation::carto_belief`]) and the final pose (a box with a line towards its
//! heading). A legend strip under the picture says what each colour means. A cell that is red
//! over white floor, or green over black, is a map error; where the orange trail leaves the blue
//! one, Carto was lost. The room itself is rasterised by [`twin::raster`], as the window's floor
//! is.

use image::{Rgb, RgbImage};
use robot_model::grid::Heading;

use crate::picture::{LegendEntry, Swatch, blend, dashed_polyline, line, with_legend};
use twin::grid::GridFrame;
use twin::raster::{Palette, PixelGrid, RoomShapes, bounds};
use twin::scenario::Scenario;

/// The true room in `map.png`.
pub const PALETTE: Palette =
    Palette { outside: [90, 90, 90], obstacle: [20, 20, 20], floor: [255, 255, 255] };

/// Cell tints of Cute's map: free and obstacle, with their strengths.
const FREE_TINT: ([u8; 3], f32) = ([60, 200, 90], 0.35);
const OBSTACLE_TINT: ([u8; 3], f32) = ([230, 40, 40], 0.55);
/// The grid lines.
const GRID_LINE: [u8; 3] = [170, 170, 200];
/// Trails and the robot.
const TRUE_TRAIL: [u8; 3] = [30, 80, 230];
const BELIEVED_TRAIL: [u8; 3] = [245, 140, 0];
const ROBOT: [u8; 3] = [0, 0, 160];
/// A move Cute's map records as blocked.
const BLOCKED_MOVE: [u8; 3] = [200, 0, 170];

/// What the colours of `map.png` mean, in the order the legend shows them.
pub const LEGEND: [LegendEntry; 9] = [
    LegendEntry::new(Swatch::Fill(PALETTE.floor), "floor"),
    LegendEntry::new(Swatch::Fill(PALETTE.obstacle), "wall/obstacle"),
    LegendEntry::new(Swatch::Fill(PALETTE.outside), "outside the room"),
    LegendEntry::new(
        Swatch::Tint { base: PALETTE.floor, tint: FREE_TINT.0, alpha: FREE_TINT.1 },
        "Cute: free",
    ),
    LegendEntry::new(
        Swatch::Tint { base: PALETTE.floor, tint: OBSTACLE_TINT.0, alpha: OBSTACLE_TINT.1 },
        "Cute: obstacle",
    ),
    LegendEntry::new(Swatch::Line(BLOCKED_MOVE), "Cute: blocked move"),
    LegendEntry::new(Swatch::Line(TRUE_TRAIL), "true trail"),
    LegendEntry::new(Swatch::Dashed(BELIEVED_TRAIL), "Carto's belief"),
    LegendEntry::new(Swatch::Line(ROBOT), "robot at the end"),
];

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
    /// Moves Cute's map records as blocked: pairs of neighbouring `(row, col)` cells.
    pub blocked_moves: &'a [((u8, u8), (u8, u8))],
    /// The robot's true trail, world metres.
    pub trail: &'a [(f32, f32)],
    /// Where Carto believed the robot was, sampled with the true trail, world metres.
    pub believed_trail: &'a [(f32, f32)],
    /// Final pose: x, y, heading (radians CCW).
    pub pose: (f32, f32, f32),
    /// Robot body length and width, metres.
    pub body: (f32, f32),
}

impl MapPicture<'_> {
    /// Renders the picture, with its legend below.
    pub fn render(&self) -> RgbImage {
        let (mut img, grid) = room_canvas(self.scenario, &self.frame, |row, col, c| {
            match self.known.get(row * self.frame.cols + col) {
                Some(Some(true)) => blend(c, FREE_TINT.0, FREE_TINT.1),
                Some(Some(false)) => blend(c, OBSTACLE_TINT.0, OBSTACLE_TINT.1),
                _ => c,
            }
        });
        let to_px = |x: f32, y: f32| grid.to_px(x, y);
        for &(a, b) in self.blocked_moves {
            if let Some((p, q)) = shared_side(&self.frame, a, b) {
                let (p, q) = (to_px(p.0, p.1), to_px(q.0, q.1));
                // three pixels wide, across the side
                let across = if (p.0 - q.0).abs() < 0.5 { (1.0, 0.0) } else { (0.0, 1.0) };
                for k in [-1.0, 0.0, 1.0] {
                    let shift = |c: (f32, f32)| (c.0 + across.0 * k, c.1 + across.1 * k);
                    line(&mut img, shift(p), shift(q), BLOCKED_MOVE);
                }
            }
        }
        // Trails: the true one, then Carto's belief dashed over it.
        for pair in self.trail.windows(2) {
            line(&mut img, to_px(pair[0].0, pair[0].1), to_px(pair[1].0, pair[1].1), TRUE_TRAIL);
        }
        let believed: Vec<(f32, f32)> = self.believed_trail.iter().map(|&(x, y)| to_px(x, y)).collect();
        dashed_polyline(&mut img, &believed, BELIEVED_TRAIL, 4.0);
        // Robot: its outline and a heading line.
        let (x, y, th) = self.pose;
        let (s, c) = th.sin_cos();
        let (hl, hw) = (self.body.0 * 0.5, self.body.1 * 0.5);
        let corner = |bx: f32, by: f32| to_px(x + c * bx - s * by, y + s * bx + c * by);
        let corners = [corner(hl, hw), corner(-hl, hw), corner(-hl, -hw), corner(hl, -hw)];
        for i in 0..4 {
            line(&mut img, corners[i], corners[(i + 1) % 4], ROBOT);
        }
        line(&mut img, to_px(x, y), corner(hl * 1.6, 0.0), ROBOT);
        with_legend(img, &LEGEND)
    }
}

/// The side two 4-neighbouring cells share, world metres (`None` if they are not neighbours or
/// off the grid).
fn shared_side(frame: &GridFrame, a: (u8, u8), b: (u8, u8)) -> Option<((f32, f32), (f32, f32))> {
    let across_columns = matches!(Heading::between(a, b)?, Heading::East | Heading::West);
    let (a, b) = ((usize::from(a.0), usize::from(a.1)), (usize::from(b.0), usize::from(b.1)));
    if a.0.max(b.0) >= frame.rows || a.1.max(b.1) >= frame.cols {
        return None;
    }
    let (ca, cb) = (frame.cell_center(a.0, a.1), frame.cell_center(b.0, b.1));
    let mid = ((ca.0 + cb.0) * 0.5, (ca.1 + cb.1) * 0.5);
    let half = frame.cell * 0.5;
    Some(if across_columns {
        ((mid.0, mid.1 - half), (mid.0, mid.1 + half))
    } else {
        ((mid.0 - half, mid.1), (mid.0 + half, mid.1))
    })
}

/// The true room with each grid cell's pixels passed through `tint(row, col, colour)`, and the
/// grid lines; the pixel grid maps world metres to pixels. Shared by `map.png` and `truth.png`.
pub fn room_canvas(
    scenario: &Scenario,
    frame: &GridFrame,
    tint: impl Fn(usize, usize, [u8; 3]) -> [u8; 3],
) -> (RgbImage, PixelGrid) {
    let ((min_x, min_y), (max_x, max_y)) = bounds(&scenario.room);
    let extent = (max_x - min_x).max(max_y - min_y).max(1e-3);
    let scale = SCALE.min(MAX_SIDE / extent);
    let w = ((max_x - min_x) * scale).clamp(1.0, MAX_SIDE) as u32 + 2 * BORDER;
    let h = ((max_y - min_y) * scale).clamp(1.0, MAX_SIDE) as u32 + 2 * BORDER;
    let grid = PixelGrid { min_x, max_y, scale, border: BORDER as f32, width: w, height: h };
    let pixels = RoomShapes::new(scenario).paint(&grid, &PALETTE, |x, y, c| match frame.cell_at(x, y) {
        Some((row, col)) => tint(row, col, c),
        None => c,
    });
    let mut img = RgbImage::from_fn(w, h, |px, py| {
        Rgb(pixels.get((py * w + px) as usize).copied().unwrap_or_default())
    });
    let to_px = |x: f32, y: f32| grid.to_px(x, y);
    let f = frame;
    for row in 0..=f.rows {
        let y = f.top - row as f32 * f.cell;
        line(&mut img, to_px(f.left, y), to_px(f.left + f.cols as f32 * f.cell, y), GRID_LINE);
    }
    for col in 0..=f.cols {
        let x = f.left + col as f32 * f.cell;
        line(&mut img, to_px(x, f.top), to_px(x, f.top - f.rows as f32 * f.cell), GRID_LINE);
    }
    (img, grid)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_blocked_move_is_drawn_on_the_side_the_cells_share() {
        let frame = GridFrame::for_bounds((0.0, 0.0), (1.2, 0.9), 0.3);
        let (a, right, below) = (frame.cell_center(1, 1), frame.cell_center(1, 2), frame.cell_center(2, 1));
        let (p, q) = shared_side(&frame, (1, 1), (1, 2)).expect("neighbours");
        let x = (a.0 + right.0) * 0.5;
        assert_eq!((p.0, q.0), (x, x), "a vertical side half-way between the centres");
        assert!(((q.1 - p.1).abs() - 0.3).abs() < 1e-6, "one cell long");
        assert_eq!(shared_side(&frame, (1, 2), (1, 1)), Some((p, q)));
        let (p, q) = shared_side(&frame, (2, 1), (1, 1)).expect("neighbours");
        let y = (a.1 + below.1) * 0.5;
        assert_eq!((p.1, q.1), (y, y));
        assert_eq!(shared_side(&frame, (1, 1), (2, 2)), None);
        assert_eq!(shared_side(&frame, (2, 3), (3, 3)), None, "row 3 is off a 3-row grid");
    }
}
