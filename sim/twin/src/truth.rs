//! What the robot can really do in a room, cell by cell: the ground truth runs are scored
//! against, measured with the robot's own footprint rather than the cell square (the scored set
//! with the robot's clearance is [`crate::scored`]).
//!
//! - A cell is **free** when the robot can stand at its centre: its footprint (body length ×
//!   width, from the profile) lies inside the room and touches no wall or obstacle, facing along
//!   the rows (east–west) or along the columns (north–south). [`Stand`] says which fit.
//! - A **move** between two 4-neighbours exists when the body swept along it touches nothing:
//!   the rectangle from one centre to the other, as wide as the body and as long as the step plus
//!   the body length. So a thin wall on the line between two free cells blocks the move even
//!   though both cells are free.
//! - A cell is **reachable** when moves connect it to the start cell.
//! - A cell is **turnable** when the circle the body sweeps turning on the spot (radius: half
//!   its diagonal) touches nothing.
//!
//! Touching means coming within 1 mm (`world::TOUCH`, the gap at which a run counts a collision;
//! parry's exact distance): a footprint 0.5 mm from a wall does not fit. Documented answers to
//! the awkward cases (each has a test below):
//! - a 4 cm table leg on a cell corner: the 0.26 × 0.24 m body at the centre of a 0.30 m cell
//!   clears the corner by 1.5 cm, so the cell stays free, moves past the leg exist, and the robot
//!   may even turn (its turning circle, 17.7 cm, ends 1.5 cm short of the leg);
//! - a wall 2 cm into a cell: facing along the wall the body (half width 12 cm) clears it by
//!   1 cm, facing across it the body (half length 13 cm) touches it. The cell is free (standing
//!   along the wall), the moves along the wall exist, the move towards the wall does not, and
//!   the robot cannot turn there.
//!
//! ```
//! use twin::grid::room_frame;
//! use twin::scenario::Scenario;
//! use twin::truth::RobotTruth;
//! use robot_model::profile::RobotProfile;
//! let s = Scenario::from_ron_str("Scenario(name: \"t\", room: [(0.0, 0.0), (1.2, 0.0), (1.2, 0.6), (0.0, 0.6)], \
//!     start: (row: 0, col: 0, heading: East), obstacles: [Segment(from: (0.6, 0.0), to: (0.6, 0.6))])", "t.ron").unwrap();
//! let p = RobotProfile { grid_cell_m: 0.30, ..RobotProfile::default() };
//! let t = RobotTruth::build(room_frame(&s.room, s.cell_size(&p)), &s.room, &s.obstacle_shapes(), &p);
//! assert!(t.is_free(0, 1) && t.is_free(0, 2));
//! assert!(!t.can_move((0, 1), (0, 2))); // the wall lies on the line between them
//! assert!(!t.reachable_from((0, 0))[2]);
//! ```

use rapier2d::parry::bounding_volume::{Aabb, BoundingVolume};
use rapier2d::parry::math::{Pose, Vector};
use rapier2d::parry::query;
use rapier2d::parry::shape::{Ball, Cuboid, Segment, Shape};
use robot_model::grid::{GridFrame, Heading, reachable};
use robot_model::profile::RobotProfile;

use crate::grid::{PlacedShape, point_in_poly2d, room_edges, room_frame, room_points};
use crate::scenario::Scenario;
use crate::world::TOUCH;

/// Which ways the robot fits standing at a cell's centre.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Stand {
    /// Facing east or west (body length along x).
    pub along_rows: bool,
    /// Facing north or south (body length along y).
    pub along_cols: bool,
}

impl Stand {
    /// Fits one way or the other.
    pub fn any(self) -> bool {
        self.along_rows || self.along_cols
    }
}

/// The body of `profile` standing along the rows and along the columns, and the circle it sweeps
/// turning on the spot (half its diagonal).
pub(crate) fn body_shapes(profile: &RobotProfile) -> ([Cuboid; 2], Ball) {
    let (half_l, half_w) = (profile.geometry.body_length_m * 0.5, profile.geometry.body_width_m * 0.5);
    (
        [Cuboid::new(Vector::new(half_l, half_w)), Cuboid::new(Vector::new(half_w, half_l))],
        Ball::new(half_l.hypot(half_w)),
    )
}

/// The robot-sized truth of a room (see the [module docs](self)).
#[derive(Debug, Clone)]
pub struct RobotTruth {
    /// The grid's placement.
    pub frame: GridFrame,
    /// Number of rows (`frame.rows`).
    pub rows: usize,
    /// Number of columns (`frame.cols`).
    pub cols: usize,
    stand: Vec<Stand>,
    /// Move (r, c) ⇄ (r, c + 1) exists.
    east: Vec<bool>,
    /// Move (r, c) ⇄ (r + 1, c) exists.
    south: Vec<bool>,
    turn: Vec<bool>,
}

/// The room's walls and obstacles as parry shapes, with bounding boxes for a quick reject.
pub(crate) struct Solids<'a> {
    /// How far apart counts as not touching: [`TOUCH`] plus the clearance asked for.
    gap: f32,
    room: Vec<Vector>,
    walls: Vec<(Segment, Aabb)>,
    obstacles: Vec<(&'a Pose, &'a dyn Shape, Aabb)>,
}

impl<'a> Solids<'a> {
    pub(crate) fn new(room: &[(f32, f32)], obstacles: &'a [PlacedShape], clearance: f32) -> Solids<'a> {
        Solids {
            gap: (TOUCH + clearance).max(0.0),
            room: room_points(room),
            walls: room_edges(room).map(|w| (w, w.compute_aabb(&Pose::IDENTITY))).collect(),
            obstacles: obstacles.iter().map(|(p, s)| (p, s.as_ref(), s.compute_aabb(p))).collect(),
        }
    }

    /// Whether `shape` at `pose` lies in the room and touches nothing: it stays more than
    /// [`TOUCH`] away from every wall and obstacle, the gap at which the run's collision counter
    /// starts counting a contact (so a turn the truth allows is never a counted collision when
    /// made exactly at the centre), plus the clearance asked for: 0 for the truth itself, less the
    /// lattice's slack in [`crate::freespace`] (never below 0: not touching at all, parry's
    /// distance cannot measure a penetration). A pair parry cannot measure counts as touching
    /// (the safe side).
    pub(crate) fn clear(&self, pose: &Pose, shape: &dyn Shape) -> bool {
        if !point_in_poly2d(pose.translation, &self.room) {
            return false;
        }
        let aabb = shape.compute_aabb(pose).loosened(self.gap);
        let apart = |p: &Pose, s: &dyn Shape, b: &Aabb| {
            !aabb.intersects(b) || query::distance(pose, shape, p, s).is_ok_and(|d| d.distance > self.gap)
        };
        self.walls.iter().all(|(w, b)| apart(&Pose::IDENTITY, w, b))
            && self.obstacles.iter().all(|(p, s, b)| apart(p, *s, b))
    }
}

impl RobotTruth {
    /// Measures every cell and move of the grid `frame` over `room` (a polygon) with
    /// `obstacles`, for the robot of `profile`.
    pub fn build(
        frame: GridFrame,
        room: &[(f32, f32)],
        obstacles: &[PlacedShape],
        profile: &RobotProfile,
    ) -> RobotTruth {
        let solids = Solids::new(room, obstacles, 0.0);
        let (length, width) = (profile.geometry.body_length_m, profile.geometry.body_width_m);
        let half_w = width * 0.5;
        let ([along_rows, along_cols], turn_circle) = body_shapes(profile);
        let sweep_east = Cuboid::new(Vector::new((frame.cell + length) * 0.5, half_w));
        let sweep_south = Cuboid::new(Vector::new(half_w, (frame.cell + length) * 0.5));
        let at = |x: f32, y: f32| Pose::from_translation(Vector::new(x, y));
        let n = frame.rows * frame.cols;
        let (mut stand, mut east, mut south, mut turn) =
            (Vec::with_capacity(n), vec![false; n], vec![false; n], Vec::with_capacity(n));
        for row in 0..frame.rows {
            for col in 0..frame.cols {
                let (x, y) = frame.cell_center(row, col);
                let pose = at(x, y);
                stand.push(Stand {
                    along_rows: solids.clear(&pose, &along_rows),
                    along_cols: solids.clear(&pose, &along_cols),
                });
                turn.push(solids.clear(&pose, &turn_circle));
            }
        }
        for row in 0..frame.rows {
            for col in 0..frame.cols {
                let i = row * frame.cols + col;
                let (x, y) = frame.cell_center(row, col);
                if col + 1 < frame.cols && stand[i].along_rows && stand[i + 1].along_rows {
                    east[i] = solids.clear(&at(x + frame.cell * 0.5, y), &sweep_east);
                }
                if row + 1 < frame.rows && stand[i].along_cols && stand[i + frame.cols].along_cols {
                    south[i] = solids.clear(&at(x, y - frame.cell * 0.5), &sweep_south);
                }
            }
        }
        RobotTruth { frame, rows: frame.rows, cols: frame.cols, stand, east, south, turn }
    }

    fn index(&self, row: usize, col: usize) -> Option<usize> {
        (row < self.frame.rows && col < self.frame.cols).then_some(row * self.frame.cols + col)
    }

    /// Which ways the robot fits at (row, col); nothing off the grid.
    pub fn stand(&self, row: usize, col: usize) -> Stand {
        self.index(row, col).map_or_else(Stand::default, |i| self.stand[i])
    }

    /// Whether the robot can stand at (row, col) one way or the other.
    pub fn is_free(&self, row: usize, col: usize) -> bool {
        self.stand(row, col).any()
    }

    /// Whether the robot can turn on the spot at (row, col).
    pub fn can_turn(&self, row: usize, col: usize) -> bool {
        self.index(row, col).is_some_and(|i| self.turn[i])
    }

    /// Whether the move between 4-neighbours `a` and `b` exists (either way).
    pub fn can_move(&self, a: (usize, usize), b: (usize, usize)) -> bool {
        let (first, second) = if a <= b { (a, b) } else { (b, a) };
        let Some(i) = self.index(first.0, first.1) else {
            return false;
        };
        if self.index(second.0, second.1).is_none() {
            return false;
        }
        match (second.0 - first.0, second.1 - first.1) {
            (0, 1) => self.east[i],
            (1, 0) => self.south[i],
            _ => false,
        }
    }

    /// What a robot limited to the link protocol's moves — FORWARD one cell, turn on the spot;
    /// no reverse, no sideways step — can visit without touching anything, starting at `start`
    /// facing `heading`: it turns only where [`RobotTruth::can_turn`] allows and drives only along
    /// moves that exist. See [`Visits`].
    pub fn visits_from(&self, start: (usize, usize), heading: Heading) -> Visits {
        self.visits_with(start, heading, |r, c| self.can_turn(r, c))
    }

    /// [`RobotTruth::visits_from`] with another rule for where the robot can turn, such as
    /// [`turnable_after_slide`].
    pub fn visits_with(
        &self,
        start: (usize, usize),
        heading: Heading,
        can_turn: impl Fn(usize, usize) -> bool,
    ) -> Visits {
        let (rows, cols) = (self.rows, self.cols);
        let cells = rows * cols;
        let Some(start_cell) = self.index(start.0, start.1).filter(|_| self.is_free(start.0, start.1)) else {
            return Visits::none(cells);
        };
        // Heading::ALL lists the headings in wire order, so `as_u8` is the index.
        let state = |cell: usize, h: Heading| cell * 4 + usize::from(h.as_u8());
        // The states one step after `st`.
        let next = |st: usize| {
            let (cell, h) = (st / 4, Heading::ALL[st % 4]);
            let (row, col) = (cell / cols, cell % cols);
            let mut out = Vec::with_capacity(3);
            if can_turn(row, col) {
                out.push(state(cell, h.left()));
                out.push(state(cell, h.right()));
            }
            let (dr, dc) = h.delta();
            if let (Some(r), Some(c)) =
                (row.checked_add_signed(dr as isize), col.checked_add_signed(dc as isize))
                && r < rows
                && c < cols
                && self.can_move((row, col), (r, c))
            {
                out.push(state(r * cols + c, h));
            }
            out
        };
        tour_over_states(cells * 4, state(start_cell, heading), next, |st| st / 4, cells, None)
    }

    /// For every cell, whether moves connect it to `start`; row-major.
    pub fn reachable_from(&self, start: (usize, usize)) -> Vec<bool> {
        reachable(
            self.frame.rows,
            self.frame.cols,
            start,
            |(r, c)| self.is_free(r, c),
            |a, b| self.can_move(a, b),
        )
    }
}

/// [`Visits`] over any directed graph of `states` (each in the cell `cell_of` gives, of `cells`),
/// from `start`, with the states one step later from `next`; the tour bound counts only the cells
/// `counted` marks (all when `None`).
pub(crate) fn tour_over_states(
    states: usize,
    start: usize,
    next: impl Fn(usize) -> Vec<usize>,
    cell_of: impl Fn(usize) -> usize,
    cells: usize,
    counted: Option<&[bool]>,
) -> Visits {
    let counts = |cell: usize| counted.is_none_or(|c| c.get(cell).copied().unwrap_or(false));
    let mut visitable = vec![false; cells];
    let mut round_trip = vec![false; cells];
    if start >= states {
        return Visits::none(cells);
    }
    // Forward: every state reachable from the start state.
    let mut seen = vec![false; states];
    let mut edges_back: Vec<Vec<usize>> = vec![Vec::new(); states];
    let mut stack = vec![start];
    seen[start] = true;
    while let Some(st) = stack.pop() {
        for n in next(st) {
            edges_back[n].push(st);
            if !seen[n] {
                seen[n] = true;
                stack.push(n);
            }
        }
    }
    // Backward from the start state, over the edges met: the states that can return.
    let mut back = vec![false; states];
    let mut stack = vec![start];
    back[start] = true;
    while let Some(st) = stack.pop() {
        for &p in &edges_back[st] {
            if !back[p] {
                back[p] = true;
                stack.push(p);
            }
        }
    }
    for st in 0..states {
        visitable[cell_of(st)] |= seen[st];
        round_trip[cell_of(st)] |= seen[st] && back[st];
    }
    // A tour leaves the round trips at most once, into one branch: bound what it adds by the
    // cells visitable from each state just outside them.
    let mut branch_max = 0;
    let mut mark = vec![false; states];
    let mut searched = vec![false; states];
    for st in (0..states).filter(|&st| seen[st] && back[st]) {
        for first in next(st).into_iter().filter(|&n| !back[n]) {
            if std::mem::replace(&mut searched[first], true) {
                continue; // another exit leads into the same state
            }
            mark.fill(false);
            let mut new_cells = vec![false; cells];
            let mut stack = vec![first];
            mark[first] = true;
            while let Some(b) = stack.pop() {
                let cell = cell_of(b);
                new_cells[cell] = !round_trip[cell] && counts(cell);
                for n in next(b) {
                    if !mark[n] {
                        mark[n] = true;
                        stack.push(n);
                    }
                }
            }
            branch_max = branch_max.max(new_cells.iter().filter(|&&x| x).count());
        }
    }
    let tour_bound = (0..cells).filter(|&c| round_trip[c] && counts(c)).count() + branch_max;
    Visits { visitable, round_trip, tour_bound }
}

/// The cells a FORWARD-and-turn robot can visit without a touch ([`RobotTruth::visits_from`]),
/// row-major. Coverage counts the cells moves connect to the start ([`RobotTruth::reachable_from`]);
/// some of those can only be entered or left through a turn the body cannot make there (a dead
/// end too narrow to turn in, a corridor entered through a cell beside a wall), so a robot that
/// moves as this model does (FORWARD between cell centres, turns on the spot) cannot map them
/// without touching something.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Visits {
    /// The robot can get there.
    pub visitable: Vec<bool>,
    /// The robot can get there and back to the start (in the start's heading), so a tour can go
    /// on afterwards. A cell that is visitable but not `round_trip` is a one-way branch: at most
    /// one such branch can be in a tour, at its end.
    pub round_trip: Vec<bool>,
    /// At most this many cells can be visited in one tour without a touch: the round trips plus
    /// the largest one-way branch (an upper bound: a branch's cells are counted as if one walk
    /// could visit them all).
    pub tour_bound: usize,
}

impl Visits {
    /// Nothing visited among `cells` cells.
    pub fn none(cells: usize) -> Visits {
        Visits { visitable: vec![false; cells], round_trip: vec![false; cells], tour_bound: 0 }
    }
}

/// For each cell (row-major), whether the robot could turn on the spot there after sliding from
/// the centre to some point of the cell (mecanum wheels move any way without turning) and back:
/// the turning circle at that point touches nothing, and the body, standing either way, touches
/// nothing along the straight slide. A relaxation of [`RobotTruth::can_turn`], which turns at the
/// centre only: Carto shifts before a turn, so bounds on what any Carto can do use this one.
/// Sampled every 1.5 cm across the cell and every 1 cm along the slide.
pub fn turnable_after_slide(
    frame: GridFrame,
    room: &[(f32, f32)],
    obstacles: &[PlacedShape],
    profile: &RobotProfile,
) -> Vec<bool> {
    const STEP_M: f32 = 0.015;
    const SLIDE_STEP_M: f32 = 0.01;
    let solids = Solids::new(room, obstacles, 0.0);
    let (bodies, circle) = body_shapes(profile);
    let at = |x: f32, y: f32| Pose::from_translation(Vector::new(x, y));
    let reach = (frame.cell * 0.5 / STEP_M).floor() as i32;
    let mut offsets: Vec<(f32, f32)> = (-reach..=reach)
        .flat_map(|i| (-reach..=reach).map(move |j| (i as f32 * STEP_M, j as f32 * STEP_M)))
        .collect();
    offsets.sort_by(|a, b| a.0.hypot(a.1).total_cmp(&b.0.hypot(b.1)));
    let mut out = Vec::with_capacity(frame.rows * frame.cols);
    for row in 0..frame.rows {
        for col in 0..frame.cols {
            let (x, y) = frame.cell_center(row, col);
            let both_ways = bodies.iter().all(|b| solids.clear(&at(x, y), b));
            // The slide's first point is the centre, checked once above.
            let slide_clear = |dx: f32, dy: f32| {
                let steps = (dx.hypot(dy) / SLIDE_STEP_M).ceil().max(1.0) as usize;
                (1..=steps).all(|k| {
                    let t = k as f32 / steps as f32;
                    bodies.iter().all(|b| solids.clear(&at(x + dx * t, y + dy * t), b))
                })
            };
            out.push(
                both_ways
                    && offsets
                        .iter()
                        .any(|&(dx, dy)| solids.clear(&at(x + dx, y + dy), &circle) && slide_clear(dx, dy)),
            );
        }
    }
    out
}

impl Scenario {
    /// What the robot of `profile` can really do in this room (see [`RobotTruth`]), on the grid
    /// [`room_frame`] lays over it. [`crate::setup::RunSetup`] builds it once, after checking the grid.
    pub fn truth(&self, profile: &RobotProfile) -> RobotTruth {
        RobotTruth::build(
            room_frame(&self.room, self.cell_size(profile)),
            &self.room,
            &self.obstacle_shapes(),
            profile,
        )
    }
}

#[cfg(test)]
mod tests;
