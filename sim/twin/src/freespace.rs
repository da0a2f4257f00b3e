//! The most any controller could visit while keeping a clearance: a bound over every position
//! of the body on a lattice of about 1 cm, not only the cell centres.
//!
//! [`RobotTruth::visits_with`](crate::truth::RobotTruth::visits_with) moves the body from centre
//! to centre. A Carto may do more with the same link commands: stop off the centre, slide
//! (mecanum wheels move any way without turning), drive a FORWARD on any path through the two
//! cells, and turn wherever its turning circle is clear. This bound allows all of that at once:
//!
//! - The body stands at lattice points (an odd number per cell, one on its centre, spaced
//!   `STEP_M` or a little more) facing along the rows (east, west) or along the columns (north,
//!   south). It is *in* the cell whose square holds its centre.
//! - A point counts as clear when the body there keeps the clearance less half the lattice's
//!   diagonal step (`slack`, 0.7 cm): any position that keeps the clearance has a clear lattice
//!   point within that distance, in the same cell, so the lattice misses no such position, and a
//!   path through such positions is a chain of neighbouring clear points. The same holds for the
//!   turning circle and for how far from the centre a command ends. The bound is lenient by that
//!   much, never strict — except with a clearance under the slack, where a body touching nothing
//!   is as lenient as parry's distance allows (it cannot measure a penetration).
//! - The body slides between neighbouring clear points.
//! - A turn of 90° happens at a point where the turning circle (half the body's diagonal, grown
//!   by the clearance) is clear, and changes Cute's heading by a quarter.
//! - A FORWARD from cell A to the next cell B along the heading goes on any sliding path inside
//!   A and B, facing the same way. A turn may slide within the cell to a point where it can
//!   turn, and slide back.
//! - Every command ends with the body within a given distance of the cell's centre (the `stop`
//!   of [`FreeSpace::visits`]): the report measures the position error from the centre at every
//!   `MOVE_DONE`, so a robot that stops 4 cm off the centre spends 4 of the 5 cm a run is allowed.
//! - The robot starts in any piece of its start cell, facing the start heading.
//!
//! The states are (piece of a cell the body can slide within, heading), and the tour bound is the
//! one of [`Visits`] (round trips plus the largest one-way branch; the link has no reverse). What
//! it leaves out: a body standing at other angles than the four headings, and a FORWARD that
//! passes through a third cell. The lattice holds at most [`MAX_POINTS`] points (a room of about
//! 2,000 m²); a larger grid is refused with [`TooLarge`].

use rapier2d::parry::math::{Pose, Vector};
use robot_model::grid::{GridFrame, Heading};
use robot_model::profile::RobotProfile;

use crate::grid::PlacedShape;
use crate::truth::{Solids, Visits, body_shapes, tour_over_states};

/// Lattice spacing asked for; each cell holds the nearest odd number of points (rounded down
/// when the nearest is even), one of them on its centre.
pub const STEP_M: f32 = 0.01;

/// The most lattice points [`FreeSpace::build`] lays out (about 300 MB of state).
pub const MAX_POINTS: usize = 20_000_000;

/// No lattice for a grid this large.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("the grid needs {points} lattice points for the clearance bound, more than the {max} allowed")]
pub struct TooLarge {
    /// Points the grid would need.
    pub points: usize,
    /// [`MAX_POINTS`].
    pub max: usize,
}

/// Marks "no piece" in the per-point tables.
const NONE: u32 = u32::MAX;

/// Which way the body's length lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Lie {
    AlongRows = 0,
    AlongCols = 1,
}

fn lie(h: Heading) -> Lie {
    match h {
        Heading::East | Heading::West => Lie::AlongRows,
        Heading::North | Heading::South => Lie::AlongCols,
    }
}

/// The lattice over the whole grid: `n` × `n` points per cell.
struct Lattice {
    frame: GridFrame,
    n: usize,
    width: usize,
    height: usize,
    /// Per lie, per point: the body keeps the clearance.
    clear: [Vec<bool>; 2],
    /// Per point: the turning circle keeps the clearance.
    turn: Vec<bool>,
}

/// Points per cell side: an odd number, so that one point lies on the cell's centre.
fn points_per_side(frame: &GridFrame) -> usize {
    ((frame.cell / STEP_M).round() as usize).max(1) | 1
}

/// Half the diagonal between neighbouring points: no position lies farther from its nearest
/// point, metres.
fn slack(frame: &GridFrame) -> f32 {
    frame.cell / points_per_side(frame) as f32 * std::f32::consts::FRAC_1_SQRT_2
}

impl Lattice {
    /// The lattice over `frame`; `solids` already keep the clearance less the slack.
    fn build(frame: GridFrame, solids: &Solids, profile: &RobotProfile) -> Lattice {
        let n = points_per_side(&frame);
        let step = frame.cell / n as f32;
        let (width, height) = (frame.cols * n, frame.rows * n);
        let (bodies, circle) = body_shapes(profile);
        let mut clear = [vec![false; width * height], vec![false; width * height]];
        let mut turn = vec![false; width * height];
        for gy in 0..height {
            let y = frame.top - (gy as f32 + 0.5) * step;
            for gx in 0..width {
                let pose = Pose::from_translation(Vector::new(frame.left + (gx as f32 + 0.5) * step, y));
                let i = gy * width + gx;
                for (k, body) in bodies.iter().enumerate() {
                    clear[k][i] = solids.clear(&pose, body);
                }
                // The circle holds both bodies, so it is clear only where both are.
                turn[i] = clear[0][i] && clear[1][i] && solids.clear(&pose, &circle);
            }
        }
        Lattice { frame, n, width, height, clear, turn }
    }

    /// How far point `i` lies from its cell's centre, metres.
    fn distance_to_centre(&self, i: usize) -> f32 {
        let centre = self.n as f32 * 0.5 - 0.5;
        let (lx, ly) = ((i % self.width % self.n) as f32, (i / self.width % self.n) as f32);
        (lx - centre).hypot(ly - centre) * self.frame.cell / self.n as f32
    }

    fn cell_of(&self, gx: usize, gy: usize) -> usize {
        (gy / self.n) * self.frame.cols + gx / self.n
    }

    /// The lattice points of `cell`.
    fn points(&self, cell: usize) -> impl Iterator<Item = usize> + '_ {
        let (row, col) = (cell / self.frame.cols, cell % self.frame.cols);
        (row * self.n..(row + 1) * self.n)
            .flat_map(move |gy| (col * self.n..(col + 1) * self.n).map(move |gx| gy * self.width + gx))
    }

    /// Labels the clear points of `lie` by the piece they slide within, over the points `in_area`
    /// allows: `label[i]` is a representative point of i's piece, or [`NONE`] off it.
    fn pieces(&self, lie: Lie, area: &[usize], in_area: impl Fn(usize) -> bool, label: &mut [u32]) {
        let clear = &self.clear[lie as usize];
        for &i in area {
            label[i] = NONE;
        }
        for &seed in area {
            if !clear[seed] || label[seed] != NONE {
                continue;
            }
            // `MAX_POINTS` keeps every index below `NONE`
            label[seed] = seed as u32;
            let mut stack = vec![seed];
            while let Some(i) = stack.pop() {
                let (gx, gy) = (i % self.width, i / self.width);
                let neighbours = [
                    (gx > 0).then(|| i - 1),
                    (gx + 1 < self.width).then(|| i + 1),
                    (gy > 0).then(|| i - self.width),
                    (gy + 1 < self.height).then(|| i + self.width),
                ];
                for j in neighbours.into_iter().flatten() {
                    if clear[j] && in_area(j) && label[j] == NONE {
                        label[j] = seed as u32;
                        stack.push(j);
                    }
                }
            }
        }
    }
}

/// For each cell (row-major), whether the body standing at its centre, facing along the rows or
/// along the columns, keeps `clearance_m` beyond the 1 mm of a touch from every wall and obstacle:
/// exact, without the lattice's slack. `explobot truth --clearance` rings the reachable cells where
/// it does not (the cells a robot keeping that margin must stop off the centre of, or skip).
pub fn centre_keeps(
    frame: GridFrame,
    room: &[(f32, f32)],
    obstacles: &[PlacedShape],
    profile: &RobotProfile,
    clearance_m: f32,
) -> Vec<bool> {
    let solids = Solids::new(room, obstacles, clearance_m);
    let (bodies, _) = body_shapes(profile);
    (0..frame.rows * frame.cols)
        .map(|i| {
            let (x, y) = frame.cell_center(i / frame.cols, i % frame.cols);
            let pose = Pose::from_translation(Vector::new(x, y));
            bodies.iter().any(|b| solids.clear(&pose, b))
        })
        .collect()
}

/// One piece of a cell: lattice points the body, lying one way (which [`FreeSpace::piece_at`]
/// says), can slide between without leaving the cell.
#[derive(Debug, Clone, Copy)]
struct Piece {
    cell: usize,
    /// How close to the cell's centre the body can stand in it, metres.
    from_centre_m: f32,
}

/// The free positions of the body in a room, on the lattice, for one clearance, and every
/// command the lattice model allows between them.
pub struct FreeSpace {
    pieces: Vec<Piece>,
    /// Per piece and heading (index `Heading::as_u8`), the pieces a command leads to and the
    /// heading after it.
    moves: Vec<[Vec<(usize, Heading)>; 4]>,
    /// Per lie, per lattice point: its piece ([`NONE`] where the body is not clear).
    piece_at: [Vec<u32>; 2],
    lattice: Lattice,
}

impl FreeSpace {
    /// The lattice over `frame` for the robot of `profile`, keeping `clearance_m` metres beyond the
    /// 1 mm of a touch from every wall of `room` and every obstacle (less the slack of the module
    /// docs). Refused when the grid needs more than [`MAX_POINTS`] points.
    pub fn build(
        frame: GridFrame,
        room: &[(f32, f32)],
        obstacles: &[PlacedShape],
        profile: &RobotProfile,
        clearance_m: f32,
    ) -> Result<FreeSpace, TooLarge> {
        let n = points_per_side(&frame);
        let points = (frame.rows * n).saturating_mul(frame.cols * n);
        if points > MAX_POINTS {
            return Err(TooLarge { points, max: MAX_POINTS });
        }
        let solids = Solids::new(room, obstacles, clearance_m - slack(&frame));
        let lattice = Lattice::build(frame, &solids, profile);
        let cells = frame.rows * frame.cols;
        let total = lattice.width * lattice.height;
        let owner = |j: usize| lattice.cell_of(j % lattice.width, j / lattice.width);
        // Pieces: label each cell's clear points, per lie, then number the labels.
        let mut piece_at = [vec![NONE; total], vec![NONE; total]];
        let mut pieces = Vec::new();
        let mut label = vec![NONE; total];
        for lie in [Lie::AlongRows, Lie::AlongCols] {
            for cell in 0..cells {
                let area: Vec<usize> = lattice.points(cell).collect();
                lattice.pieces(lie, &area, |j| owner(j) == cell, &mut label);
                let mut id_of_label = std::collections::BTreeMap::new();
                for &i in &area {
                    if label[i] == NONE {
                        continue;
                    }
                    let id = *id_of_label.entry(label[i]).or_insert_with(|| {
                        pieces.push(Piece { cell, from_centre_m: f32::INFINITY });
                        pieces.len() - 1
                    });
                    piece_at[lie as usize][i] = id as u32;
                    let d = lattice.distance_to_centre(i);
                    if d < pieces[id].from_centre_m {
                        pieces[id].from_centre_m = d;
                    }
                }
            }
        }
        let mut moves: Vec<[Vec<(usize, Heading)>; 4]> = vec![Default::default(); pieces.len()];
        // Turns: from a piece, at any point of it where the circle is clear.
        for i in (0..total).filter(|&i| lattice.turn[i]) {
            for h in Heading::ALL {
                let (from, to) = (piece_at[lie(h) as usize][i], piece_at[lie(h.left()) as usize][i]);
                if from != NONE && to != NONE {
                    let turns = &mut moves[from as usize][usize::from(h.as_u8())];
                    for after in [h.left(), h.right()] {
                        if !turns.contains(&(to as usize, after)) {
                            turns.push((to as usize, after));
                        }
                    }
                }
            }
        }
        // FORWARDs: from a piece to the pieces of the next cell it joins by sliding in the two;
        // each pair of cells once (east and south of each), for both ways.
        for cell in 0..cells {
            let (row, col) = (cell / frame.cols, cell % frame.cols);
            for h in [Heading::East, Heading::South] {
                let (dr, dc) = h.delta();
                let (r, c) = (row + dr as usize, col + dc as usize);
                if r >= frame.rows || c >= frame.cols {
                    continue;
                }
                let next = r * frame.cols + c;
                let area: Vec<usize> = lattice.points(cell).chain(lattice.points(next)).collect();
                lattice.pieces(lie(h), &area, |j| owner(j) == cell || owner(j) == next, &mut label);
                let ids = &piece_at[lie(h) as usize];
                // (label over both cells, piece of one cell)
                let labelled = |of: usize| {
                    let mut v: Vec<(u32, u32)> =
                        lattice.points(of).filter(|&i| ids[i] != NONE).map(|i| (label[i], ids[i])).collect();
                    v.sort_unstable();
                    v.dedup();
                    v
                };
                let (here, there) = (labelled(cell), labelled(next));
                let back = h.left().left();
                for &(l, p) in &here {
                    for &(_, q) in there.iter().filter(|&&(l2, _)| l2 == l) {
                        moves[p as usize][usize::from(h.as_u8())].push((q as usize, h));
                        moves[q as usize][usize::from(back.as_u8())].push((p as usize, back));
                    }
                }
            }
        }
        for m in moves.iter_mut().flat_map(|m| m.iter_mut()) {
            m.sort_unstable_by_key(|&(p, h)| (p, h.as_u8()));
            m.dedup();
        }
        Ok(FreeSpace { pieces, moves, piece_at, lattice })
    }

    /// [`Visits`] of the lattice model (module docs) for a robot starting in `start` facing
    /// `heading` whose commands end within `stop_within_m` of a cell's centre. The tour bound
    /// counts only the cells `counted` marks (row-major), e.g. those the truth connects to the
    /// start. Nothing is visited when the start cell has no clear point facing that way.
    pub fn visits(
        &self,
        (start, heading): ((usize, usize), Heading),
        stop_within_m: f32,
        counted: Option<&[bool]>,
    ) -> Visits {
        let frame = self.lattice.frame;
        let cells = frame.rows * frame.cols;
        if start.0 >= frame.rows || start.1 >= frame.cols {
            return Visits::none(cells);
        }
        let start_cell = start.0 * frame.cols + start.1;
        let ids = &self.piece_at[lie(heading) as usize];
        let mut starts: Vec<usize> = self
            .lattice
            .points(start_cell)
            .map(|i| ids[i])
            .filter(|&p| p != NONE)
            .map(|p| p as usize)
            .collect();
        starts.sort_unstable();
        starts.dedup();
        if starts.is_empty() {
            return Visits::none(cells);
        }
        // A command ends in a piece with a point near enough the centre.
        let reach = stop_within_m + slack(&frame) + 1e-4;
        let stops = |p: usize| self.pieces[p].from_centre_m <= reach;
        // States: piece × heading, index piece * 4 + heading; then one more, before the start,
        // whose next states are the pieces of the start cell.
        let state = |p: usize, h: Heading| p * 4 + usize::from(h.as_u8());
        let before_start = self.pieces.len() * 4;
        let next = |st: usize| {
            if st == before_start {
                return starts.iter().map(|&p| state(p, heading)).collect();
            }
            let (p, h) = (st / 4, st % 4);
            self.moves[p][h].iter().filter(|&&(q, _)| stops(q)).map(|&(q, h2)| state(q, h2)).collect()
        };
        let cell_of = |st: usize| if st == before_start { start_cell } else { self.pieces[st / 4].cell };
        tour_over_states(before_start + 1, before_start, next, cell_of, cells, counted)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::grid::room_frame;
    use crate::scenario::Scenario;

    /// A `w` × `h` m room with `obstacles`, the default robot on 0.45 m cells starting in (0, 0)
    /// facing east, and the truth's reachable cells.
    fn room(w: f32, h: f32, obstacles: &str) -> (Scenario, RobotProfile, GridFrame, Vec<bool>) {
        let text = format!(
            "Scenario(name: \"t\", room: [(0.0, 0.0), ({w:?}, 0.0), ({w:?}, {h:?}), (0.0, {h:?})], \
             start: (row: 0, col: 0, heading: East), obstacles: [{obstacles}])"
        );
        let s = Scenario::from_ron_str(&text, "t.ron").unwrap();
        let p = RobotProfile { grid_cell_m: 0.45, ..RobotProfile::default() };
        let frame = room_frame(&s.room, 0.45);
        let reachable = s.truth(&p).reachable_from((0, 0));
        (s, p, frame, reachable)
    }

    fn tour(
        s: &Scenario,
        p: &RobotProfile,
        frame: GridFrame,
        clearance: f32,
        stop: f32,
        counted: &[bool],
    ) -> usize {
        FreeSpace::build(frame, &s.room, &s.obstacle_shapes(), p, clearance)
            .unwrap()
            .visits(((0, 0), Heading::East), stop, Some(counted))
            .tour_bound
    }

    /// A wall 1 cm beside the body along two cells of a row: the truth's cells are free, a body
    /// keeping 2 cm (1.3 cm at lattice points: the 0.7 cm slack off) can pass only off the
    /// centres' line, and must stop off the centres to get there.
    #[test]
    fn a_tight_row_needs_stops_off_the_centres() {
        // the body's side at the centre line lies at y = 0.225 + 0.12 = 0.345: the wall at 0.355
        let (s, p, frame, reachable) = room(1.35, 0.45, "Segment(from: (0.45, 0.355), to: (1.35, 0.355))");
        assert_eq!(reachable.iter().filter(|&&r| r).count(), 3, "the truth: 1 cm is clear");
        assert_eq!(tour(&s, &p, frame, 0.0, 0.0, &reachable), 3);
        assert_eq!(tour(&s, &p, frame, 0.02, 0.0, &reachable), 1, "2 cm does not fit at the centres");
        assert_eq!(tour(&s, &p, frame, 0.02, 0.01, &reachable), 3, "1 cm below the line it does");
        assert_eq!(tour(&s, &p, frame, 0.03, 0.01, &reachable), 1, "3 cm needs 2 cm below the line");
        assert_eq!(tour(&s, &p, frame, 0.03, 0.02, &reachable), 3);
        assert_eq!(tour(&s, &p, frame, 0.15, 0.02, &reachable), 0, "the start itself is too tight");
    }

    /// With no clearance and stops on the centres the lattice is an upper bound of the cell model
    /// that turns after a slide (`explobot truth`'s tour bound): here, on the documented awkward
    /// cases, both reach every cell.
    #[test]
    fn on_the_centres_the_lattice_bounds_the_cell_model() {
        let loaded = crate::setup::RunSetup::load(std::path::Path::new("../docs/truth-cases.ron")).unwrap();
        let counts = crate::counts::TruthCounts::of(&loaded);
        let lattice = crate::counts::lattice_tour_bounds(&loaded, 0.0, &[0.0]).unwrap();
        assert_eq!((counts.tour_bound, lattice), (counts.reachable, vec![counts.reachable]));
    }

    /// A dead end too narrow to turn in: the robot may drive in but not out, so a tour visits the
    /// cells up to it and then the dead end's cells once, at its end (a one-way branch).
    #[test]
    fn a_dead_end_counts_as_one_branch() {
        // a corridor 35.5 cm wide, 4 cells long: the turning circle (17.7 cm + 1 mm) fits
        // nowhere in it, the body (24 cm) does
        let (s, p, frame, reachable) = room(1.8, 0.45, "Segment(from: (0.0, 0.355), to: (1.8, 0.355))");
        let space = FreeSpace::build(frame, &s.room, &s.obstacle_shapes(), &p, 0.0).unwrap();
        let v = space.visits(((0, 0), Heading::East), 0.0, Some(&reachable));
        assert_eq!(v.visitable.iter().filter(|&&x| x).count(), 4, "all four cells, eastwards");
        assert_eq!(v.round_trip.iter().filter(|&&x| x).count(), 1, "none of them can come back");
        assert_eq!(v.tour_bound, 4);
    }

    /// A grid that needs more points than allowed is refused before anything is laid out.
    #[test]
    fn a_huge_room_is_refused() {
        let (s, p, _, _) = room(1.35, 0.45, "");
        let frame = room_frame(&[(0.0, 0.0), (50.0, 0.0), (50.0, 50.0), (0.0, 50.0)], 0.45);
        let err = FreeSpace::build(frame, &s.room, &[], &p, 0.02).err().unwrap();
        assert_eq!(err.max, MAX_POINTS);
        assert!(err.points > MAX_POINTS, "{err}");
    }
}
