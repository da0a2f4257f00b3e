//! `explobot truth SCENARIO`: what the robot can really do in a room, as the runs score it
//! ([`crate::truth::RobotTruth`]), printed as counts and drawn as `truth.png`.
//!
//! The picture shows the true room (as `map.png` does), each cell tinted by the truth — green
//! scored (reachable keeping the profile's clearance, [`crate::scored`]), purple tight (reachable
//! only closer than that: not scored), yellow free but not reachable (a closed pocket), red the
//! robot cannot stand there —, a dark dot on free cells where the robot cannot turn on the spot, a
//! magenta bar on the line between two free cells whose move is blocked (a thin wall between
//! them), and the start cell framed in blue; with `--clearance`, an orange ring in every reachable
//! cell whose centre does not keep the first clearance asked for. A legend under the picture
//! repeats this.
//!
//! ```
//! let loaded = sim::scenario::LoadedScenario::builtin_default()?;
//! let counts = sim::truthimg::TruthCounts::of(&loaded);
//! assert_eq!(counts.reachable, 67); // the default room, zero clearance
//! assert_eq!(counts.scored + counts.tight, counts.reachable); // scored: coverage's denominator
//! let png = sim::truthimg::truth_picture(&loaded);
//! assert!(png.width() > 100);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::PathBuf;

use image::RgbImage;
use serde::Serialize;

use crate::freespace::FreeSpace;
use crate::mapimg::{PALETTE, room_canvas};
use crate::picture::{LegendEntry, Swatch, blend, fill, line, with_legend};
use crate::scenario::{LoadedScenario, ScenarioError};
use crate::scored::ScoredSet;

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

/// The truth of a room in numbers.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TruthCounts {
    /// Grid rows and columns.
    pub rows: usize,
    /// Grid columns.
    pub cols: usize,
    /// Cells where the robot can stand.
    pub free: usize,
    /// Free cells connected to the start by moves, at zero clearance.
    pub reachable: usize,
    /// Reachable cells a body keeping the profile's clearance, stopping near the centres, can
    /// reach: what coverage counts ([`crate::scored`]).
    pub scored: usize,
    /// Reachable cells that are not scored.
    pub tight: usize,
    /// The clearance and the stop distance of the scored set, metres.
    pub scoring_m: (f32, f32),
    /// Reachable cells where the robot can also turn on the spot.
    pub reachable_turnable: usize,
    /// Moves between two free neighbours that the body's sweep blocks.
    pub blocked_moves: usize,
    /// Reachable cells a FORWARD-and-turn robot can visit without a touch, sliding within a
    /// cell before it turns ([`crate::truth::turnable_after_slide`]).
    pub visitable: usize,
    /// Of those, the cells it can also come back from.
    pub round_trip: usize,
    /// At most this many can be visited in one touch-free tour ([`crate::truth::Visits`]):
    /// an upper bound on the coverage a run with 0 collisions can reach, in the truth's model of
    /// motion (FORWARD between cell centres, turns after a straight slide).
    pub tour_bound: usize,
    /// The same bound for a robot that turns at cell centres only.
    pub tour_bound_at_centres: usize,
}

impl TruthCounts {
    /// Counts the truth of `loaded` from its start cell.
    pub fn of(loaded: &LoadedScenario) -> TruthCounts {
        TruthCounts::with_set(loaded, &ScoredSet::of(loaded))
    }

    /// [`TruthCounts::of`], with the scored set already computed.
    pub fn with_set(loaded: &LoadedScenario, set: &ScoredSet) -> TruthCounts {
        let t = loaded.truth();
        let start = (usize::from(loaded.scenario.start.row), usize::from(loaded.scenario.start.col));
        let reachable = &set.reachable;
        let cells = || (0..t.rows).flat_map(|r| (0..t.cols).map(move |c| (r, c)));
        let mut blocked_moves = 0;
        for (r, c) in cells() {
            for next in [(r, c + 1), (r + 1, c)] {
                if t.is_free(r, c) && t.is_free(next.0, next.1) && !t.can_move((r, c), next) {
                    blocked_moves += 1;
                }
            }
        }
        let start_heading = loaded.scenario.start.heading;
        let s = &loaded.scenario;
        let slide =
            crate::truth::turnable_after_slide(t.frame, &s.room, &s.obstacle_shapes(), &loaded.profile);
        let visits = t.visits_with(start, start_heading, |r, c| slide[r * t.cols + c]);
        let count = |v: &[bool]| v.iter().zip(reachable).filter(|&(&a, &b)| a && b).count();
        TruthCounts {
            visitable: count(&visits.visitable),
            round_trip: count(&visits.round_trip),
            tour_bound: visits.tour_bound,
            tour_bound_at_centres: t.visits_from(start, start_heading).tour_bound,
            rows: t.rows,
            cols: t.cols,
            free: cells().filter(|&(r, c)| t.is_free(r, c)).count(),
            reachable: reachable.iter().filter(|&&x| x).count(),
            scored: set.scored_count(),
            tight: set.tight_count(),
            scoring_m: (set.clearance_m, set.stop_within_m),
            reachable_turnable: cells()
                .filter(|&(r, c)| reachable[r * t.cols + c] && t.can_turn(r, c))
                .count(),
            blocked_moves,
        }
    }

    /// What `explobot truth` prints for a room `label` on cells of `cell` metres, with the
    /// lattice tour bounds asked for.
    pub fn text(&self, label: &str, cell: f32, bounds: &[ClearanceBound]) -> String {
        let pct = |n: usize| 100.0 * n as f64 / self.reachable.max(1) as f64;
        let mut lines = vec![
            format!("{label}: {} × {} cells of {cell:.2} m", self.rows, self.cols),
            format!("  free (the robot fits)        {}", self.free),
            format!("  reachable from the start     {}  (at zero clearance)", self.reachable),
            format!(
                "  scored                       {}  (reachable keeping {:.1} cm, stopping ≤ {:.1} cm off centres: what coverage counts)",
                self.scored,
                self.scoring_m.0 * 100.0,
                self.scoring_m.1 * 100.0
            ),
            format!(
                "  tight                        {}  (reachable only closer: counted neither way)",
                self.tight
            ),
            format!("  reachable, turn on the spot  {}", self.reachable_turnable),
            format!("  free but not reachable       {}", self.free - self.reachable),
            format!("  moves blocked between free   {}", self.blocked_moves),
            format!(
                "  visitable without a touch    {}  (FORWARD and turns, sliding in a cell to turn)",
                self.visitable
            ),
            format!("  … and back again             {}", self.round_trip),
            format!(
                "  one touch-free tour, at most {}  ({:.1}% of reachable: the best coverage with 0 collisions)",
                self.tour_bound,
                pct(self.tour_bound)
            ),
            format!(
                "  … turning at centres only    {}  ({:.1}%)",
                self.tour_bound_at_centres,
                pct(self.tour_bound_at_centres)
            ),
        ];
        for b in bounds {
            lines.push(format!(
                "  keeping {:.1} cm clear, stopping ≤ {:.1} cm off centres: one tour at most {}  ({:.1}%)",
                b.clearance_m * 100.0,
                b.stop_within_m * 100.0,
                b.tour_bound,
                pct(b.tour_bound)
            ));
        }
        lines.iter().map(|l| format!("{l}\n")).collect()
    }
}

/// At most how many cells one touch-free tour can visit in the lattice model of
/// [`crate::freespace`] — the body anywhere in its cells between commands, any path within a
/// FORWARD's two cells, turns wherever the circle is clear — keeping `clearance_m` from
/// everything, for each distance from the centre that commands may end within in `stops_m`.
/// Counts the cells the truth connects to the start, as coverage does.
pub fn lattice_tour_bounds(
    loaded: &LoadedScenario,
    clearance_m: f32,
    stops_m: &[f32],
) -> Result<Vec<usize>, crate::freespace::TooLarge> {
    let s = &loaded.scenario;
    let t = loaded.truth();
    let start = (usize::from(s.start.row), usize::from(s.start.col));
    let reachable = t.reachable_from(start);
    let space = FreeSpace::build(t.frame, &s.room, &s.obstacle_shapes(), &loaded.profile, clearance_m)?;
    Ok(stops_m
        .iter()
        .map(|&stop| space.visits((start, s.start.heading), stop, Some(&reachable)).tour_bound)
        .collect())
}

/// One line of `explobot truth --clearance`: [`lattice_tour_bounds`] for one clearance and stop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClearanceBound {
    /// Metres kept from everything.
    pub clearance_m: f32,
    /// How far off a cell's centre commands may end.
    pub stop_within_m: f32,
    /// At most this many reachable cells in one touch-free tour.
    pub tour_bound: usize,
}

/// Draws `truth.png` for `loaded` (see the module docs).
pub fn truth_picture(loaded: &LoadedScenario) -> RgbImage {
    truth_picture_ringing(loaded, &ScoredSet::of(loaded), None)
}

/// [`truth_picture`] with the scored set `set`, and an orange ring inside every reachable cell
/// whose centre `keeps` (row-major, [`crate::freespace::centre_keeps`]) says does not keep a
/// clearance.
pub fn truth_picture_ringing(loaded: &LoadedScenario, set: &ScoredSet, keeps: Option<&[bool]>) -> RgbImage {
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

/// Arguments of `explobot truth`.
#[derive(Debug, Clone, clap::Args)]
pub struct TruthArgs {
    /// Scenario file (default: the built-in default room).
    pub scenario: Option<PathBuf>,
    /// Where to write the picture (default: runs/NAME/truth.png).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Also bound one touch-free tour for a body that keeps this many metres from everything,
    /// anywhere in its cells (`sim/src/freespace.rs`); repeat for several, e.g.
    /// `--clearance 0.01 --clearance 0.02`.
    #[arg(long, value_name = "METRES", value_parser = parse_metres)]
    pub clearance: Vec<f32>,
    /// With `--clearance`: how far from a cell's centre a command may leave the body, metres
    /// (repeat for several; default 0 and 0.02).
    #[arg(long, value_name = "METRES", value_parser = parse_metres, requires = "clearance")]
    pub stop_within: Vec<f32>,
}

/// A distance in metres: finite, 0 to 0.2.
fn parse_metres(text: &str) -> Result<f32, String> {
    let m: f32 = text.parse().map_err(|_| format!("`{text}` is not a number of metres"))?;
    if m.is_finite() && (0.0..=0.2).contains(&m) {
        Ok(m)
    } else {
        Err(format!("expected 0 to 0.2 m, not {text}"))
    }
}

/// Why `explobot truth` failed.
#[derive(Debug, thiserror::Error)]
pub enum TruthError {
    /// The scenario could not be loaded.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The picture could not be written.
    #[error("writing {path}: {message}")]
    Write {
        /// Where.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// The room is too large for the clearance bound's lattice.
    #[error(transparent)]
    TooLarge(#[from] crate::freespace::TooLarge),
}

impl TruthArgs {
    /// Prints the counts and writes the picture.
    pub fn run(&self) -> Result<(), TruthError> {
        let loaded = LoadedScenario::load_or_default(self.scenario.as_deref())?;
        let set = ScoredSet::of(&loaded);
        let c = TruthCounts::with_set(&loaded, &set);
        let stops = if self.stop_within.is_empty() { vec![0.0, 0.02] } else { self.stop_within.clone() };
        let mut bounds = Vec::new();
        for &clearance_m in &self.clearance {
            let tours = lattice_tour_bounds(&loaded, clearance_m, &stops)?;
            bounds.extend(stops.iter().zip(tours).map(|(&stop_within_m, tour_bound)| ClearanceBound {
                clearance_m,
                stop_within_m,
                tour_bound,
            }));
        }
        let mut text = c.text(&loaded.label, loaded.truth().frame.cell, &bounds);
        let path = self
            .out
            .clone()
            .unwrap_or_else(|| crate::output::default_out_dir(&loaded.scenario.name).join("truth.png"));
        let write = |message: String| TruthError::Write { path: path.clone(), message };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| write(e.to_string()))?;
        }
        let s = &loaded.scenario;
        let keeps = self.clearance.first().map(|&c| {
            crate::freespace::centre_keeps(
                loaded.truth().frame,
                &s.room,
                &s.obstacle_shapes(),
                &loaded.profile,
                c,
            )
        });
        truth_picture_ringing(&loaded, &set, keeps.as_deref())
            .save(&path)
            .map_err(|e| write(e.to_string()))?;
        text.push_str(&format!("wrote {}\n", path.display()));
        crate::output::print_stdout(&text)
            .map_err(|e| TruthError::Write { path: "<stdout>".into(), message: e.to_string() })
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    /// The awkward cases of [`crate::truth`]'s module docs: a thin wall on a cell line, a leg on a cell corner and
    /// a wall 2 cm into a row, counted and drawn.
    #[test]
    fn the_documented_cases_count_as_the_readme_says() {
        let loaded = LoadedScenario::load(std::path::Path::new("docs/truth-cases.ron")).unwrap();
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
        let room = crate::generate::generate(crate::generate::RoomStyle::Flat, 19).unwrap();
        let loaded =
            LoadedScenario::from_ron_str(&room.to_ron(), "flat-19.ron", std::path::Path::new(".")).unwrap();
        let set = ScoredSet::of(&loaded);
        let c = TruthCounts::with_set(&loaded, &set);
        assert_eq!((c.tight, c.scored + c.tight), (2, c.reachable), "{c:?}");
        assert!(c.text("flat 19", 0.45, &[]).contains("tight                        2  "));
        let png = truth_picture_ringing(&loaded, &set, None);
        let purple = blend(PALETTE.floor, TIGHT_CELL.0, TIGHT_CELL.1);
        let tinted = png.pixels().filter(|p| p.0 == purple).count();
        assert!(tinted > 200, "tight cells are drawn ({tinted} px)");
        let furnished = LoadedScenario::load(std::path::Path::new("../scenarios/furnished.ron")).unwrap();
        assert_eq!(ScoredSet::of(&furnished).tight_count(), 0);
    }

    /// `--clearance` rings the reachable cells whose centre does not keep it, and says so in the
    /// legend; without it there is no ring.
    #[test]
    fn tight_cells_are_ringed_only_when_a_clearance_is_asked() {
        let loaded = LoadedScenario::load(std::path::Path::new("docs/truth-cases.ron")).unwrap();
        let s = &loaded.scenario;
        let frame = loaded.truth().frame;
        let keeps =
            crate::freespace::centre_keeps(frame, &s.room, &s.obstacle_shapes(), &loaded.profile, 0.02);
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
