//! `truth.png`: what the robot can really do in a room, as the runs score it
//! ([`twin::truth::RobotTruth`]; `explobot truth` prints the counts, [`twin::counts`]).
//!
//! The picture shows the true room (as `map.png` does), each cell tinted by the truth — green
//! scored (reachable keeping the profile's clearance, [`twin::scored`]), purple tight (reachable
//! only closer than that: not scored), yellow free but not reachable (a closed pocket), red the
//! robot cannot stand there —, a dark dot on free cells where the robot cannot turn on the spot, a
//! magenta bar on the line between two free cells whose move is blocked (a thin wall between
//! them), and the start cell framed in blue; with `--clearance`, an orange ring in every reachable
//! cell whose centre does not keep the first clearance asked for. A legend under the picture
//! repeats this.
//!
//! ```
//! let loaded = twin::setup::RunSetup::builtin_default()?;
//! let png = twin_pictures::truthimg::truth_picture(&loaded);
//! assert!(png.width() > 100);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use image::RgbImage;
use twin::scored::ScoredSet;
use twin::setup::RunSetup;

use crate::mapimg::{PALETTE, room_canvas};
use crate::picture::{LegendEntry, Swatch, blend, fill, line, with_legend};

const REACHABLE: ([u8; 3], f32) = ([60, 200, 90], 0.35);
const POCKET: ([u8; 3], f32) = ([240, 200, 40], 0.5);
const TIGHT_CELL: ([u8; 3], f32) = ([150, 70, 220], 0.45);
const NOT_FREE: ([u8; 3], f32) = ([230, 40, 40], 0.45);
const NO_TURN: [u8; 3] = [60, 60, 60];
const BLOCKED_MOVE: [u8; 3] = [220, 0, 200];
const START: [u8; 3] = [30, 80, 230];
const TIGHT: [u8; 3] = [255, 140, 0];

/// The legend entry of the rings `explobot truth --clearance` adds.
const TIGHT_ENTRY: LegendEntry =
    LegendEntry::new(Swatch::Line(TIGHT), "ring: centre not --clearance clear (first value)");

/// What the colours of `truth.png` mean.
pub const LEGEND: [LegendEntry; 9] = [
    LegendEntry::new(Swatch::Fill(PALETTE.obstacle), "wall/obstacle"),
    LegendEntry::new(Swatch::Fill(PALETTE.outside), "outside the room"),
    LegendEntry::new(
        Swatch::Tint { base: PALETTE.floor, tint: REACHABLE.0, alpha: REACHABLE.1 },
        "scored (reachable, clearance kept)",
    ),
    LegendEntry::new(
        Swatch::Tint { base: PALETTE.floor, tint: TIGHT_CELL.0, alpha: TIGHT_CELL.1 },
        "tight: reachable only closer (not scored)",
    ),
    LegendEntry::new(
        Swatch::Tint { base: PALETTE.floor, tint: POCKET.0, alpha: POCKET.1 },
        "free, not reachable",
    ),
    LegendEntry::new(
        Swatch::Tint { base: PALETTE.floor, tint: NOT_FREE.0, alpha: NOT_FREE.1 },
        "robot does not fit",
    ),
    LegendEntry::new(Swatch::Fill(NO_TURN), "dot: cannot turn there"),
    LegendEntry::new(Swatch::Line(BLOCKED_MOVE), "move blocked"),
    LegendEntry::new(Swatch::Line(START), "start cell"),
];

/// Draws `truth.png` for `loaded` (see the module docs).
pub fn truth_picture(loaded: &RunSetup) -> RgbImage {
    truth_picture_ringing(loaded, &ScoredSet::of(loaded), None)
}

/// [`truth_picture`] with the scored set `set`, and an orange ring inside every reachable cell
/// whose centre `keeps` (row-major, [`twin::freespace::centre_keeps`]) says does not keep a
/// clearance.
pub fn truth_picture_ringing(loaded: &RunSetup, set: &ScoredSet, keeps: Option<&[bool]>) -> RgbImage {
    let t = loaded.truth();
    let frame = t.frame;
    let start = (usize::from(loaded.scenario.start.row), usize::from(loaded.scenario.start.col));
    let reachable = &set.reachable;
    let (mut img, grid) = room_canvas(&loaded.scenario, &frame, |row, col, c| {
        let i = row * frame.cols + col;
        let (tint, alpha) = if set.tight.get(i).copied().unwrap_or(false) {
            TIGHT_CELL
        } else if reachable.get(i).copied().unwrap_or(false) {
            REACHABLE
        } else if t.is_free(row, col) {
            POCKET
        } else {
            NOT_FREE
        };
        blend(c, tint, alpha)
    });
    let to_px = |x: f32, y: f32| grid.to_px(x, y);
    let dot = (grid.scale * 0.03).max(2.0) as u32;
    for row in 0..t.rows {
        for col in 0..t.cols {
            let (x, y) = frame.cell_center(row, col);
            if t.is_free(row, col) && !t.can_turn(row, col) {
                let (px, py) = to_px(x, y);
                let (px, py) = (px.max(0.0) as u32, py.max(0.0) as u32);
                fill(
                    &mut img,
                    (px.saturating_sub(dot / 2), py.saturating_sub(dot / 2)),
                    (px + dot / 2 + 1, py + dot / 2 + 1),
                    NO_TURN,
                );
            }
            // The shared edge of (row, col) and its east / south neighbour.
            let half = frame.cell / 2.0;
            let edges = [
                ((row, col + 1), (x + half, y + half), (x + half, y - half)),
                ((row + 1, col), (x - half, y - half), (x + half, y - half)),
            ];
            for (next, a, b) in edges {
                if t.is_free(row, col) && t.is_free(next.0, next.1) && !t.can_move((row, col), next) {
                    thick_line(&mut img, to_px(a.0, a.1), to_px(b.0, b.1), BLOCKED_MOVE);
                }
            }
        }
    }
    let square = |img: &mut RgbImage, (row, col): (usize, usize), inset: f32, color: [u8; 3]| {
        let (x, y) = frame.cell_center(row, col);
        let h = frame.cell / 2.0 - inset;
        let corners = [(x - h, y - h), (x + h, y - h), (x + h, y + h), (x - h, y + h)];
        for i in 0..4 {
            let (a, b) = (corners[i], corners[(i + 1) % 4]);
            thick_line(img, to_px(a.0, a.1), to_px(b.0, b.1), color);
        }
    };
    let mut legend = LEGEND.to_vec();
    if let Some(keeps) = keeps {
        let marked =
            |i: usize| reachable.get(i).copied().unwrap_or(false) && !keeps.get(i).copied().unwrap_or(true);
        for i in (0..t.rows * t.cols).filter(|&i| marked(i)) {
            square(&mut img, (i / t.cols, i % t.cols), frame.cell * 0.3, TIGHT);
        }
        legend.push(TIGHT_ENTRY);
    }
    square(&mut img, start, 0.01, START);
    with_legend(img, &legend)
}

/// A 4-pixel line.
fn thick_line(img: &mut RgbImage, a: (f32, f32), b: (f32, f32), color: [u8; 3]) {
    for (ox, oy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
        line(img, (a.0 + ox, a.1 + oy), (b.0 + ox, b.1 + oy), color);
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use twin::counts::TruthCounts;

    use super::*;

    /// The awkward cases of [`twin::truth`]'s module docs: a thin wall on a cell line, a leg on a cell corner and
    /// a wall 2 cm into a row, counted and drawn.
    #[test]
    fn the_documented_cases_count_as_the_readme_says() {
        let loaded = RunSetup::load(std::path::Path::new("../docs/truth-cases.ron")).unwrap();
        let c = TruthCounts::of(&loaded);
        assert_eq!((c.rows, c.cols, c.free, c.reachable), (5, 8, 40, 40));
        // 3 across the thin wall, 3 from row 3 towards the wall 2 cm into row 4.
        assert_eq!(c.blocked_moves, 6);
        // Only cells off the walls turn: the 3 × 6 interior, less the four beside the thin wall.
        assert_eq!(c.reachable_turnable, 14);
        let t = loaded.truth();
        assert!(t.can_turn(1, 1) && t.can_turn(1, 2), "the leg on the corner leaves room to turn");
        assert!(!t.can_move((3, 6), (4, 6)) && t.can_move((4, 5), (4, 6)));

        let png = truth_picture(&loaded);
        let blocked = png.pixels().filter(|p| p.0 == BLOCKED_MOVE).count();
        assert!(blocked > 100, "blocked moves are drawn ({blocked} px)");
        assert!(png.height() > png.width() * 5 / 8, "a legend is added under the room");
    }

    /// Generated flat room 19 has two cells the body reaches only closer than Carto's 2 cm
    /// (stopping within 2 cm of the centres): they are counted apart and tinted purple. (The
    /// furnished scenarios, hand-drawn or measured, have none with the default profile.)
    #[test]
    fn a_room_with_tight_cells_shows_them() {
        let room = twin_roomgen::generate(twin_roomgen::RoomStyle::Flat, 19).unwrap();
        let loaded =
            RunSetup::from_ron_str(&room.to_ron(), "flat-19.ron", std::path::Path::new(".")).unwrap();
        let set = ScoredSet::of(&loaded);
        let c = TruthCounts::with_set(&loaded, &set);
        assert_eq!((c.tight, c.scored + c.tight), (2, c.reachable), "{c:?}");
        assert!(c.text("flat 19", 0.45, &[]).contains("tight                        2  "));
        let png = truth_picture_ringing(&loaded, &set, None);
        let purple = blend(PALETTE.floor, TIGHT_CELL.0, TIGHT_CELL.1);
        let tinted = png.pixels().filter(|p| p.0 == purple).count();
        assert!(tinted > 200, "tight cells are drawn ({tinted} px)");
        let furnished = RunSetup::load(std::path::Path::new("../../scenarios/furnished.ron")).unwrap();
        assert_eq!(ScoredSet::of(&furnished).tight_count(), 0);
    }

    /// `--clearance` rings the reachable cells whose centre does not keep it, and says so in the
    /// legend; without it there is no ring.
    #[test]
    fn tight_cells_are_ringed_only_when_a_clearance_is_asked() {
        let loaded = RunSetup::load(std::path::Path::new("../docs/truth-cases.ron")).unwrap();
        let s = &loaded.scenario;
        let frame = loaded.truth().frame;
        let keeps =
            twin::freespace::centre_keeps(frame, &s.room, &s.obstacle_shapes(), &loaded.profile, 0.02);
        // 0.30 m cells: every cell against a wall has 3 cm beside the 24 cm body at most
        assert!(keeps.iter().any(|&k| k) && !keeps.iter().all(|&k| k), "{keeps:?}");
        let ringed = |png: &RgbImage| png.pixels().filter(|p| p.0 == TIGHT).count();
        assert_eq!(ringed(&truth_picture(&loaded)), 0);
        let set = ScoredSet::of(&loaded);
        let legend_only = ringed(&truth_picture_ringing(&loaded, &set, Some(&vec![true; keeps.len()])));
        assert!(legend_only > 0, "the legend's swatch");
        assert!(ringed(&truth_picture_ringing(&loaded, &set, Some(&keeps))) > legend_only + 100);
    }
}
