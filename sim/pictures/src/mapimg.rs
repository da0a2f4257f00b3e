//! `map.png`: Cute's map drawn over the true room.
//!
//! The true room is drawn first (outside the walls dark grey, obstacles black, floor white), then
//! each grid cell is tinted by what Cute's map says (free green, obstacle red, unknown left
//! untinted), then the grid lines, the moves Cute recorded blocked (a magenta bar on the side
//! the two cells share), the robot's true trail (blue), the trail Carto believed (dashed
//! orange: the centre of the cell Carto stores plus its dead-reckoned offset, see
//! [`twin::localisation::carto_belief`]) and the final pose (a box with a line towards its
//! heading). Carto's own evidence grid ([`twin::carto_map`]) is drawn over Cute's cells: its
//! free cells as a faint cyan wash, its occupied cells in dark teal; its belief at the end is an
//! orange heading tick in the 2σ ellipse of its position filter. A legend strip under the picture
//! says what each colour means. A cell that is red over white floor, or green over black, is a
//! map error; teal off the black surfaces is Carto's grid placed wrong; where the orange trail
//! leaves the blue one, Carto was lost. The room itself is rasterised by [`twin::raster`], as
//! the window's floor is.

use image::{Rgb, RgbImage};
use robot_model::grid::Heading;

use crate::picture::{LegendEntry, Swatch, blend, dashed_polyline, line, with_legend};
use twin::carto_map::{BeliefEllipse, CartoMap, Occupancy};
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
/// Carto's evidence grid: free cells (a wash) and occupied cells.
const CARTO_FREE_TINT: ([u8; 3], f32) = ([0, 170, 210], 0.22);
const CARTO_OCCUPIED: [u8; 3] = [0, 120, 130];
/// A move Cute's map records as blocked.
const BLOCKED_MOVE: [u8; 3] = [200, 0, 170];

/// What the colours of `map.png` mean, in the order the legend shows them.
pub const LEGEND: [LegendEntry; 12] = [
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
    LegendEntry::new(
        Swatch::Tint { base: PALETTE.floor, tint: CARTO_FREE_TINT.0, alpha: CARTO_FREE_TINT.1 },
        "Carto's grid: free",
    ),
    LegendEntry::new(Swatch::Fill(CARTO_OCCUPIED), "Carto's grid: occupied"),
    LegendEntry::new(Swatch::Line(TRUE_TRAIL), "true trail"),
    LegendEntry::new(Swatch::Dashed(BELIEVED_TRAIL), "Carto's belief"),
    LegendEntry::new(Swatch::Line(BELIEVED_TRAIL), "its 2-sigma ellipse at the end"),
    LegendEntry::new(Swatch::Line(ROBOT), "robot at the end"),
];

/// Pixels per metre for rooms up to ~25 m; larger rooms are scaled down to fit [`MAX_SIDE`].
const SCALE: f32 = 160.0;
/// Longest side of the picture, pixels.
const MAX_SIDE: f32 = 4096.0;
/// Border around the room, pixels.
const BORDER: u32 = 12;

/// A move between two neighbouring cells, `(row, col)` from and to.
pub type CellMove = ((u8, u8), (u8, u8));

/// What to draw.
pub struct MapPicture<'a> {
    /// The room.
    pub scenario: &'a Scenario,
    /// The grid's placement.
    pub frame: GridFrame,
    /// Cute's knowledge per cell, row-major: `Some(true)` free, `Some(false)` obstacle.
    pub known: &'a [Option<bool>],
    /// Moves Cute's map records as blocked: pairs of neighbouring `(row, col)` cells.
    pub blocked_moves: &'a [CellMove],
    /// The robot's true trail, world metres.
    pub trail: &'a [(f32, f32)],
    /// Where Carto believed the robot was, sampled with the true trail, world metres.
    pub believed_trail: &'a [(f32, f32)],
    /// Carto's evidence grid at the end.
    pub carto_map: &'a CartoMap,
    /// Carto's belief at the end, with its uncertainty.
    pub belief: Option<BeliefEllipse>,
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
        self.draw_carto_map(&mut img, &to_px);
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
        if let Some(belief) = &self.belief {
            let outline: Vec<(f32, f32)> = belief.outline(48).iter().map(|&(x, y)| to_px(x, y)).collect();
            for k in 0..outline.len() {
                line(&mut img, outline[k], outline[(k + 1) % outline.len()], BELIEVED_TRAIL);
            }
            let (bx, by, bth) = belief.pose;
            let tick = hl * 0.8;
            line(
                &mut img,
                to_px(bx, by),
                to_px(bx + tick * bth.cos(), by + tick * bth.sin()),
                BELIEVED_TRAIL,
            );
        }
        with_legend(img, &LEGEND)
    }

    /// Carto's grid over the room: free cells washed, occupied cells filled.
    fn draw_carto_map(&self, img: &mut RgbImage, to_px: &impl Fn(f32, f32) -> (f32, f32)) {
        let half = self.carto_map.cell_m * 0.5;
        for &((x, y), occupancy) in &self.carto_map.cells {
            let (p, q) = (to_px(x - half, y + half), to_px(x + half, y - half));
            let (x0, y0) = (p.0.round().max(0.0) as u32, p.1.round().max(0.0) as u32);
            let (x1, y1) =
                ((q.0.round().max(0.0) as u32).max(x0 + 1), (q.1.round().max(0.0) as u32).max(y0 + 1));
            for py in y0..y1.min(img.height()) {
                for px in x0..x1.min(img.width()) {
                    let here = img.get_pixel(px, py).0;
                    let colour = match occupancy {
                        Occupancy::Occupied => CARTO_OCCUPIED,
                        Occupancy::Free => blend(here, CARTO_FREE_TINT.0, CARTO_FREE_TINT.1),
                        Occupancy::Unknown => continue,
                    };
                    img.put_pixel(px, py, Rgb(colour));
                }
            }
        }
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

    #[test]
    fn carto_s_grid_and_belief_are_drawn_where_they_lie_in_the_room() {
        let loaded = twin::setup::RunSetup::builtin_default().expect("the built-in room");
        let frame = twin::grid::room_frame(&loaded.scenario.room, 0.3);
        // an occupied cell and the belief on open floor of the default room
        let (cell, belief) = ((0.33, 2.21), (0.9, 2.2));
        let map = CartoMap { cell_m: 0.02, cells: vec![(cell, Occupancy::Occupied)] };
        let ellipse =
            BeliefEllipse::from_covariance((belief.0, belief.1, 0.0), [[2.5e-3, 0.0], [0.0, 2.5e-3]]);
        let picture = MapPicture {
            scenario: &loaded.scenario,
            frame,
            known: &[],
            blocked_moves: &[],
            trail: &[],
            believed_trail: &[],
            carto_map: &map,
            belief: Some(ellipse),
            pose: (0.3, 0.3, 0.0),
            body: (0.2, 0.15),
        };
        let img = picture.render();
        let (_, grid) = room_canvas(&loaded.scenario, &frame, |_, _, c| c);
        let at = |x: f32, y: f32| {
            let (px, py) = grid.to_px(x, y);
            img.get_pixel(px as u32, py as u32).0
        };
        assert_eq!(at(cell.0, cell.1), CARTO_OCCUPIED);
        // σ 5 cm: the 2σ ellipse passes 10 cm east of the believed centre
        let east = grid.to_px(belief.0 + 0.1, belief.1);
        let near =
            (-1..=1).any(|d| img.get_pixel(east.0 as u32, (east.1 as i32 + d) as u32).0 == BELIEVED_TRAIL);
        assert!(near, "no ellipse 10 cm east of the belief");
        assert_ne!(at(belief.0 + 0.05, belief.1 + 0.02), BELIEVED_TRAIL, "inside the ellipse is not drawn");
    }
}
