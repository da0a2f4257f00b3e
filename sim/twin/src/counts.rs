//! A room's ground truth in numbers, as `explobot truth` prints it: free, reachable, scored and
//! tight cells, blocked moves, and upper bounds on one touch-free tour.
//!
//! ```
//! let setup = twin::setup::RunSetup::builtin_default()?;
//! let counts = twin::counts::TruthCounts::of(&setup);
//! assert_eq!(counts.reachable, 67); // the default room, zero clearance
//! assert_eq!(counts.scored + counts.tight, counts.reachable); // scored: coverage's denominator
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use serde::Serialize;

use crate::freespace::FreeSpace;
use crate::scored::ScoredSet;
use crate::setup::RunSetup;

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
    pub fn of(loaded: &RunSetup) -> TruthCounts {
        TruthCounts::with_set(loaded, &ScoredSet::of(loaded))
    }

    /// [`TruthCounts::of`], with the scored set already computed.
    pub fn with_set(loaded: &RunSetup, set: &ScoredSet) -> TruthCounts {
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
    loaded: &RunSetup,
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
