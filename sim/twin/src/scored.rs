//! The cells a run is scored on: what this robot can honestly be asked to cover.
//!
//! The zero-clearance truth ([`RobotTruth::reachable_from`]) counts a cell the body can enter
//! only by passing 1 mm from a wall, while Carto keeps 2 cm. So a run is scored on three sets,
//! row-major, from the profile's [`Scoring`](robot_model::profile::Scoring):
//!
//! - **reachable**: moves of the zero-clearance truth connect the cell to the start;
//! - **scored**: reachable, and a body keeping `clearance_m` from everything, ending every
//!   command within `stop_within_m` of a cell's centre, can reach it from the start cell facing
//!   the start heading — the lattice model of [`crate::freespace`] (off-centre stops, slides,
//!   turns wherever the turning circle keeps the clearance);
//! - **tight**: reachable but not scored. Tight cells count neither for nor against coverage or
//!   accuracy; the report gives their number and what Cute made of them.
//!
//! Documented answers to the awkward cases (each has a test):
//! - a cell whose only entry is tight is tight itself, and so is every cell reached only
//!   through it: the set is what the body can reach keeping the clearance, not a cell-by-cell
//!   test;
//! - a tight cell Cute marked free or obstacle counts in neither coverage nor accuracy; the
//!   report counts them apart (`tight_known_free`, `tight_marked_obstacle`);
//! - a cell the lattice reaches only standing off its centre, where the truth says the body
//!   does not fit at the centre, is not reachable and so not scored; accuracy judges it by the
//!   truth's `is_free`, as before;
//! - a grid too large for the lattice ([`crate::freespace::MAX_POINTS`], about 2,000 m²) is
//!   scored on the reachable set, and the report says so (`exact: false`).
//!
//! ```
//! use twin::setup::RunSetup;
//! use twin::scored::ScoredSet;
//! let loaded = RunSetup::builtin_default()?;
//! let set = ScoredSet::of(&loaded);
//! assert!(set.exact);
//! assert!(set.scored_count() <= set.reachable_count());
//! assert_eq!(set.scored_count() + set.tight_count(), set.reachable_count());
//! # Ok::<(), twin::scenario::ScenarioError>(())
//! ```

use robot_model::grid::Heading;
use robot_model::profile::RobotProfile;
use serde::Serialize;

use crate::freespace::FreeSpace;
use crate::grid::PlacedShape;
use crate::setup::RunSetup;
use crate::truth::RobotTruth;

/// The three sets of the module docs, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct ScoredSet {
    /// Cells the zero-clearance truth connects to the start.
    pub reachable: Vec<bool>,
    /// Cells a body keeping the clearance and stopping near the centres can reach.
    pub scored: Vec<bool>,
    /// Reachable, not scored.
    pub tight: Vec<bool>,
    /// The clearance used, metres.
    pub clearance_m: f32,
    /// The stop distance used, metres.
    pub stop_within_m: f32,
    /// `false` when the grid was too large for the lattice and `scored` is `reachable`.
    pub exact: bool,
}

impl ScoredSet {
    /// The sets of `loaded` with its profile's [`Scoring`](robot_model::profile::Scoring).
    pub fn of(loaded: &RunSetup) -> ScoredSet {
        let s = &loaded.scenario;
        let start = ((usize::from(s.start.row), usize::from(s.start.col)), s.start.heading);
        ScoredSet::build(loaded.truth(), &s.room, &s.obstacle_shapes(), &loaded.profile, start)
    }

    /// The sets for the room `room` with `obstacles`, its truth `truth`, the robot of `profile`
    /// starting in `start` facing its heading.
    pub fn build(
        truth: &RobotTruth,
        room: &[(f32, f32)],
        obstacles: &[PlacedShape],
        profile: &RobotProfile,
        start: ((usize, usize), Heading),
    ) -> ScoredSet {
        let reachable = truth.reachable_from(start.0);
        let (clearance_m, stop_within_m) = (profile.scoring.clearance_m, profile.scoring.stop_within_m);
        let (scored, exact) = match FreeSpace::build(truth.frame, room, obstacles, profile, clearance_m) {
            Ok(space) => {
                let visits = space.visits(start, stop_within_m, Some(&reachable));
                let scored = reachable.iter().zip(&visits.visitable).map(|(&r, &v)| r && v).collect();
                (scored, true)
            }
            Err(too_large) => {
                tracing::warn!(%too_large, "scoring on the zero-clearance reachable set");
                (reachable.clone(), false)
            }
        };
        let tight = reachable.iter().zip(&scored).map(|(&r, &s)| r && !s).collect();
        ScoredSet { reachable, scored, tight, clearance_m, stop_within_m, exact }
    }

    /// Cells in [`ScoredSet::reachable`].
    pub fn reachable_count(&self) -> usize {
        self.reachable.iter().filter(|&&b| b).count()
    }

    /// Cells in [`ScoredSet::scored`].
    pub fn scored_count(&self) -> usize {
        self.scored.iter().filter(|&&b| b).count()
    }

    /// Cells in [`ScoredSet::tight`].
    pub fn tight_count(&self) -> usize {
        self.tight.iter().filter(|&&b| b).count()
    }
}

/// How Cute's map compares with the true room, on the sets of [`ScoredSet`].
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct MapScore {
    /// Cells the zero-clearance truth connects to the start (scored plus tight).
    pub reachable: usize,
    /// Cells of the scored set.
    pub scored: usize,
    /// Scored cells Cute shows as free.
    pub scored_known_free: usize,
    /// Scored cells Cute shows as obstacles: coverage lost to a refusal or a bump, not to a cell
    /// left unknown.
    pub scored_marked_obstacle: usize,
    /// Tight cells (reachable, not scored): counted neither way.
    pub tight: usize,
    /// Tight cells Cute shows as free.
    pub tight_known_free: usize,
    /// Tight cells Cute shows as obstacles.
    pub tight_marked_obstacle: usize,
    /// Cells Cute has classified (free or obstacle), tight cells left out.
    pub classified: usize,
    /// Classified cells that agree with the truth.
    pub correct: usize,
    /// `false` when the room was too large for the clearance lattice and the scored set is the
    /// reachable set.
    pub exact: bool,
    /// The clearance the scored set keeps, metres.
    pub clearance_m: f64,
}

impl MapScore {
    /// Scores `known` (row-major; `Some(true)` free, `Some(false)` obstacle, `None` unknown).
    pub fn score(truth: &RobotTruth, set: &ScoredSet, known: &[Option<bool>]) -> MapScore {
        let mut s =
            MapScore { exact: set.exact, clearance_m: f64::from(set.clearance_m), ..MapScore::default() };
        for row in 0..truth.rows {
            for col in 0..truth.cols {
                let i = row * truth.cols + col;
                let k = known.get(i).copied().flatten();
                let at = |v: &[bool]| v.get(i).copied().unwrap_or(false);
                s.reachable += usize::from(at(&set.reachable));
                if at(&set.tight) {
                    s.tight += 1;
                    match k {
                        Some(true) => s.tight_known_free += 1,
                        Some(false) => s.tight_marked_obstacle += 1,
                        None => {}
                    }
                    continue;
                }
                if at(&set.scored) {
                    s.scored += 1;
                    match k {
                        Some(true) => s.scored_known_free += 1,
                        Some(false) => s.scored_marked_obstacle += 1,
                        None => {}
                    }
                }
                if let Some(free) = k {
                    s.classified += 1;
                    if free == truth.is_free(row, col) {
                        s.correct += 1;
                    }
                }
            }
        }
        s
    }

    /// Fraction of the scored set known free (1.0 for a room with none).
    pub fn coverage(&self) -> f64 {
        if self.scored == 0 { 1.0 } else { self.scored_known_free as f64 / self.scored as f64 }
    }

    /// Fraction of classified cells that are right (1.0 when none are classified).
    pub fn accuracy(&self) -> f64 {
        if self.classified == 0 { 1.0 } else { self.correct as f64 / self.classified as f64 }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::grid::room_frame;
    use crate::scenario::Scenario;

    /// A 3-cell corridor of 0.45 m cells, 0.45 m high, with `wall` placed inside it: the sets for
    /// the default robot starting in (0, 0) facing east.
    fn corridor(obstacles: &str, width_cells: usize) -> (RobotTruth, ScoredSet) {
        let w = 0.45 * width_cells as f32;
        let text = format!(
            "Scenario(name: \"t\", room: [(0.0, 0.0), ({w}, 0.0), ({w}, 0.45), (0.0, 0.45)], \
             start: (row: 0, col: 0, heading: East), obstacles: [{obstacles}])"
        );
        let s = Scenario::from_ron_str(&text, "t.ron").unwrap();
        let p = RobotProfile::default();
        let truth =
            RobotTruth::build(room_frame(&s.room, s.cell_size(&p)), &s.room, &s.obstacle_shapes(), &p);
        let set = ScoredSet::build(&truth, &s.room, &s.obstacle_shapes(), &p, ((0, 0), Heading::East));
        (truth, set)
    }

    /// Two posts on the line between cells 0 and 1 that leave the body `beside_m` on each side.
    fn posts(beside_m: f32) -> String {
        let gap = 0.24 + 2.0 * beside_m;
        let (y0, y1) = (0.225 - gap / 2.0, 0.225 + gap / 2.0);
        format!("Segment(from: (0.45, 0.0), to: (0.45, {y0})), Segment(from: (0.45, {y1}), to: (0.45, 0.45))")
    }

    #[test]
    fn an_open_corridor_is_all_scored() {
        let (_, set) = corridor("", 3);
        assert_eq!(set.reachable, vec![true; 3]);
        assert_eq!(set.scored, vec![true; 3]);
        assert_eq!(set.tight_count(), 0);
    }

    #[test]
    fn a_cell_reachable_only_past_a_wall_1_cm_away_is_tight() {
        // Two posts narrow the way into cell 1: the gap is the body's width (0.24 m) plus 1 cm
        // on each side, so the body passes 1 cm from each post (the zero-clearance truth lets
        // it through) but cannot keep 2 cm. Everything behind the narrow way is tight too.
        let (truth, set) = corridor(&posts(0.01), 3);
        assert_eq!(truth.reachable_from((0, 0)), vec![true; 3], "the zero-clearance truth passes");
        assert_eq!(set.scored, vec![true, false, false]);
        assert_eq!(set.tight, vec![false, true, true], "the cell behind the only tight entry is tight");
        // A tight cell Cute marked free or obstacle counts neither way.
        let known = [Some(true), Some(true), Some(false)];
        let m = MapScore::score(&truth, &set, &known);
        assert_eq!((m.scored, m.scored_known_free, m.tight), (1, 1, 2));
        assert_eq!((m.tight_known_free, m.tight_marked_obstacle), (1, 1));
        assert_eq!((m.classified, m.correct), (1, 1), "tight cells are left out of accuracy");
        assert_eq!(m.coverage(), 1.0);
    }

    #[test]
    fn a_gap_that_keeps_the_clearance_is_scored() {
        // The same narrow way, 3 cm on each side: scored.
        let (_, set) = corridor(&posts(0.03), 3);
        assert_eq!(set.scored, vec![true; 3]);
    }
}
