//! Local motion for a FORWARD: a sliding way for the body through its two cells, planned over
//! what is known (issue 42, item 3).
//!
//! A FORWARD takes the body from the cell it stands in (A) to the centre of the next (B), facing
//! the same way all along: the mecanum wheels slide it in any direction without turning. When the
//! straight way is blocked, [`plan`] searches a lattice of body positions over A and B for a
//! way that keeps every known point out of the body grown by the clearance, and that ends on a
//! track near enough the line through the centres for the move to stop within its tolerance.
//! This is the FORWARD the twin's scored set allows ("any sliding path inside A and B",
//! `sim/twin/src/freespace.rs`).
//!
//! Frame: metres `(along, left)` from the centre of cell A, along the FORWARD's heading.
//!
//! Contract:
//! - A lattice point is clear when no point lies in the body's rectangle there grown by the
//!   clearance, and, beyond the band of tracks a straight FORWARD may take, when the caller says
//!   the space the body adds beside that band is known free (a complete floor plan says so of all
//!   space without a point; an evidence grid could, of the cells it holds free).
//! - The body moves between neighbouring clear points (a diagonal step only when both steps
//!   along the axes are clear too), so every position on the lattice way keeps the clearance: a
//!   rectangle moved by less than its size along one axis stays within the two rectangles at
//!   its ends, and one inside a lattice square stays within the four at its corners.
//! - A body that stands within the clearance of something may move onto points whose deepest
//!   intrusion is no deeper than where it stands (so a robot stopped close to a wall is not
//!   stuck), never onto one whose body itself holds a point. The rule compares the deepest
//!   intrusion only: such a body may come as near another point as it stands to the nearest.
//! - The way found is the cheapest, a step across costing [`ACROSS_COST`] times a step along
//!   (a slide sideways is slower and less precise than a drive), and a lattice point whose grown
//!   body comes within [`COMFORT_M`] of a point costing up to [`NEAR_COST`] steps more, the
//!   nearer the dearer: where the space allows, the way keeps farther than the clearance, as a
//!   costmap's inflation does, so that the belief's error (2 cm at the 95th percentile with the
//!   room known, `docs/journal/world-model.md`) is not spent at every pass. It is returned as
//!   straight legs, joined greedily from the start as far as every lattice square a leg crosses
//!   is clear (sampled at an eighth of a step), then a last drive straight along its track to B's
//!   centre.
//! - The motor does not drive a diagonal leg on its straight line: it drives along the heading
//!   first and strafes the rest ([`crate::motor::Motor::start_shift`]), up to about a centimetre
//!   off the checked line; the comfort cost is the only margin for that. Legs along one axis
//!   only (driven as checked) were measured and lost significantly: more strafing, a worse
//!   belief (`docs/journal/world-model.md`, round 11).
//! - The way ends on B's centre line across the heading, within the band of the line; when no
//!   such point clears, anywhere within the band of B's centre ([`Slide::stop_along_m`]): a
//!   surface a few millimetres inside the clearance at B's centre stops the FORWARD short, not
//!   the robot's tour, and a FORWARD slid one way round a leg can be made back.
//! - `None` when no way exists: the caller refuses the FORWARD.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Lattice spacing asked for, metres (the cell holds a whole number of steps).
pub const STEP_M: f64 = 0.01;
/// A step across the heading costs this many steps along it.
pub const ACROSS_COST: u32 = 2;
/// Beyond the clearance, a way keeps this much more where it can, metres.
pub const COMFORT_M: f64 = 0.02;
/// A lattice point whose grown body touches a point (no comfort left) costs this many steps
/// more; the cost falls linearly to none at [`COMFORT_M`].
pub const NEAR_COST: u32 = 4;

/// The body and the geometry of the move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlideGeometry {
    /// Side of a cell, metres.
    pub cell_m: f64,
    /// Half the body's length (along the heading), metres.
    pub half_length_m: f64,
    /// Half the body's width, metres.
    pub half_width_m: f64,
    /// Kept from every known point, metres.
    pub clearance_m: f64,
    /// How far beside the line through the centres a straight FORWARD's track may lie (and this
    /// way's last leg may end), metres.
    pub band_m: f64,
    /// The radius of the circle the body sweeps turning on the spot, plus the clearance, metres.
    pub turn_clear_m: f64,
    /// How far from a cell's centre a command may leave the body, metres.
    pub stop_within_m: f64,
}

impl SlideGeometry {
    /// The geometry of the robot `cfg` describes: its band is
    /// [`Safety::stop_within_m`](crate::config::Safety::stop_within_m) less the lateral tolerance
    /// a move ends within.
    pub fn from_config(cfg: &crate::CartoConfig) -> SlideGeometry {
        SlideGeometry {
            cell_m: cfg.cell_size_m,
            half_length_m: 0.5 * cfg.chassis.body_length_m,
            half_width_m: 0.5 * cfg.chassis.body_width_m,
            clearance_m: cfg.safety.clearance_m,
            band_m: (cfg.safety.stop_within_m - cfg.motion.lateral_tolerance_m).max(0.0),
            turn_clear_m: cfg.turn_radius_m() + cfg.safety.clearance_m,
            stop_within_m: cfg.safety.stop_within_m,
        }
    }
}

/// A way found by [`plan`].
#[derive(Debug, Clone, PartialEq)]
pub struct Slide {
    /// The points the body slides to in turn, `(along, left)` from A's centre, before the last
    /// drive.
    pub legs: Vec<(f64, f64)>,
    /// The track of the last drive to B's centre, metres left of the line.
    pub track_left_m: f64,
    /// Where the last drive stops, metres ahead of B's centre (negative: short of it); 0 unless
    /// B's centre line holds no clear point within the band.
    pub stop_along_m: f64,
}

/// The lattice over A and B.
#[derive(Default)]
struct Lattice {
    step: f64,
    /// Index of A's centre along and across.
    origin: (i32, i32),
    size: (i32, i32),
    clear: Vec<bool>,
    /// Whether each lattice point's body lies in space known free, points apart.
    free: Vec<bool>,
    /// How deep the nearest point lies inside each lattice point's grown body, metres (0 when
    /// none does): a body that stands within the clearance of something may still move, as long
    /// as it comes no nearer ([`Lattice::passable`]).
    intrusion: Vec<f64>,
    /// What entering each lattice point costs beyond the step ([`NEAR_COST`]).
    near: Vec<u32>,
}

impl Lattice {
    fn index(&self, (i, j): (i32, i32)) -> Option<usize> {
        ((0..self.size.0).contains(&i) && (0..self.size.1).contains(&j))
            .then(|| (i * self.size.1 + j) as usize)
    }

    fn is_clear(&self, node: (i32, i32)) -> bool {
        self.index(node).is_some_and(|k| self.clear[k])
    }

    /// Whether the body may move onto `node` from where the intrusion is `from` metres: onto a
    /// clear point, or, from within the clearance, onto one no deeper in it and known free.
    fn passable(&self, node: (i32, i32), from: f64) -> bool {
        self.index(node).is_some_and(|k| self.clear[k] || (self.free[k] && self.intrusion[k] <= from))
    }

    fn intrusion_at(&self, node: (i32, i32)) -> f64 {
        self.index(node).map_or(f64::INFINITY, |k| self.intrusion[k])
    }

    fn position(&self, (i, j): (i32, i32)) -> (f64, f64) {
        (f64::from(i - self.origin.0) * self.step, f64::from(j - self.origin.1) * self.step)
    }

    /// The lattice index nearest `(along, left)` (it may lie outside the lattice; far values
    /// are clamped well outside it).
    fn nearest(&self, (along, left): (f64, f64)) -> (i32, i32) {
        let index = |v: f64, origin: i32| (v / self.step).round().clamp(-1e6, 1e6) as i32 + origin;
        (index(along, self.origin.0), index(left, self.origin.1))
    }
}

/// Plans a FORWARD's way from `start` (the body's position from A's centre) to B's centre, a
/// cell ahead, keeping clear of `points` (`(along, left)` from A's centre); `known_free(along,
/// left)` says whether a rectangle (two ranges, metres, smaller bound first) beside the band of
/// straight tracks is known free. See the module docs.
pub fn plan(
    g: &SlideGeometry,
    start: (f64, f64),
    points: &[(f64, f64)],
    known_free: &dyn Fn((f64, f64), (f64, f64)) -> bool,
) -> Option<Slide> {
    // the body's centre stays in A or B
    let (lattice, per_cell) = Lattice::build(g, start, 1, points, known_free)?;
    let from = lattice.nearest(start);
    let off_centre = |(i, j): (i32, i32)| {
        let (along, left) = lattice.position((i, j));
        (along - f64::from(per_cell) * lattice.step, left)
    };
    // on B's centre line across when it can, else anywhere within the band of it
    let path = search(&lattice, from, |node| {
        let (along, left) = off_centre(node);
        along.abs() < 1e-9 && left.abs() <= g.band_m + 1e-9 && lattice.is_clear(node)
    })
    .or_else(|| {
        search(&lattice, from, |node| {
            let (along, left) = off_centre(node);
            along.hypot(left) <= g.band_m + 1e-9 && lattice.is_clear(node)
        })
    })?;
    let stop_along_m = path.last().map_or(0.0, |&goal| off_centre(goal).0);
    Some(Slide { stop_along_m, ..into_legs(&lattice, start, &path, true) })
}

/// Plans where in cell A a turn on the spot can be made: the place cheapest to reach by sliding
/// from `start` facing the heading where no point lies within the turning circle grown by the
/// clearance ([`SlideGeometry::turn_clear_m`]), with the comfort beyond it when one such place
/// is reachable, else with half a lattice diagonal (the body stands up to that far from its
/// lattice point). The legs to slide to it; empty when the body can turn where it stands; `None`
/// when no place in the cell clears. `known_free` as for [`plan`].
pub fn plan_turn(
    g: &SlideGeometry,
    start: (f64, f64),
    points: &[(f64, f64)],
    known_free: &dyn Fn((f64, f64), (f64, f64)) -> bool,
) -> Option<Vec<(f64, f64)>> {
    let (lattice, _) = Lattice::build(g, start, 0, points, known_free)?;
    let from = lattice.nearest(start);
    let circle_gap = |node: (i32, i32)| {
        let (a, l) = lattice.position(node);
        points.iter().map(|&(pa, pl)| (pa - a).hypot(pl - l) - g.turn_clear_m).fold(f64::INFINITY, f64::min)
    };
    let path = search(&lattice, from, |node| circle_gap(node) >= COMFORT_M).or_else(|| {
        search(&lattice, from, |node| circle_gap(node) > lattice.step * std::f64::consts::FRAC_1_SQRT_2)
    })?;
    Some(into_legs(&lattice, start, &path, false).legs)
}

/// Whether the body, facing the heading and grown by `keep_m`, holds none of `points`
/// (`(along, left)` from A's centre) somewhere within [`SlideGeometry::stop_within_m`] of
/// `centre`, searched at the lattice spacing: the body fits in the cell there. A FORWARD
/// refused into a cell where the body itself fits was refused for its way, not for the cell.
pub fn fits_near(g: &SlideGeometry, centre: (f64, f64), keep_m: f64, points: &[(f64, f64)]) -> bool {
    let (reach_along, reach_left) = (g.half_length_m + keep_m, g.half_width_m + keep_m);
    let steps = (g.stop_within_m / STEP_M).floor() as i32;
    (-steps..=steps)
        .flat_map(|i| (-steps..=steps).map(move |j| (f64::from(i) * STEP_M, f64::from(j) * STEP_M)))
        .filter(|(da, dl)| da.hypot(*dl) <= g.stop_within_m + 1e-9)
        .any(|(da, dl)| {
            let (a, l) = (centre.0 + da, centre.1 + dl);
            points.iter().all(|&(pa, pl)| (pa - a).abs() > reach_along || (pl - l).abs() > reach_left)
        })
}

impl Lattice {
    /// The lattice over cell A and `ahead` cells past it, `points` and `known_free` as for
    /// [`plan`]; with the number of lattice steps in a cell.
    fn build(
        g: &SlideGeometry,
        start: (f64, f64),
        ahead: i32,
        points: &[(f64, f64)],
        known_free: &dyn Fn((f64, f64), (f64, f64)) -> bool,
    ) -> Option<(Lattice, i32)> {
        if !(g.cell_m > 0.0 && start.0.is_finite() && start.1.is_finite()) {
            return None;
        }
        let per_cell = (g.cell_m / STEP_M).round().max(2.0) as i32;
        let step = g.cell_m / f64::from(per_cell);
        let half = per_cell / 2;
        // the body's centre stays in the cells: half a cell behind A's centre to the last one's,
        // half a cell either side
        let lattice_size = (2 * half + ahead * per_cell + 1, 2 * half + 1);
        let mut lattice = Lattice { step, origin: (half, half), size: lattice_size, ..Lattice::default() };
        let (reach_along, reach_left) = (g.half_length_m + g.clearance_m, g.half_width_m + g.clearance_m);
        let nodes = (lattice_size.0 * lattice_size.1) as usize;
        let mut clear = vec![true; nodes];
        let mut intrusion = vec![0.0f64; nodes];
        // the gap between each lattice point's grown body and the nearest point, up to the comfort
        let mut gap = vec![COMFORT_M; nodes];
        for &(pa, pl) in points {
            if !(pa.is_finite() && pl.is_finite()) {
                continue;
            }
            // the lattice points whose grown body holds this point or comes within the comfort
            let lo = lattice.nearest((pa - reach_along - COMFORT_M, pl - reach_left - COMFORT_M));
            let hi = lattice.nearest((pa + reach_along + COMFORT_M, pl + reach_left + COMFORT_M));
            for i in (lo.0 - 1).max(0)..=(hi.0 + 1).min(lattice_size.0 - 1) {
                for j in (lo.1 - 1).max(0)..=(hi.1 + 1).min(lattice_size.1 - 1) {
                    let k = (i * lattice_size.1 + j) as usize;
                    let (a, l) = lattice.position((i, j));
                    let (da, dl) = ((pa - a).abs() - reach_along, (pl - l).abs() - reach_left);
                    if da <= 0.0 && dl <= 0.0 {
                        clear[k] = false;
                        intrusion[k] = intrusion[k].max((-da).min(-dl));
                    } else {
                        gap[k] = gap[k].min(da.max(0.0).hypot(dl.max(0.0)));
                    }
                }
            }
        }
        lattice.near = gap
            .iter()
            .map(|&g| (f64::from(NEAR_COST) * (1.0 - g / COMFORT_M)).round().max(0.0) as u32)
            .collect();
        // beyond the band, the space the body adds beside it must be known free
        let band_edge = g.band_m + reach_left;
        let mut free = vec![true; nodes];
        for i in 0..lattice_size.0 {
            for j in 0..lattice_size.1 {
                let k = (i * lattice_size.1 + j) as usize;
                let (a, l) = lattice.position((i, j));
                if l.abs() > g.band_m + 1e-9 {
                    let outer = l.abs() + reach_left;
                    let across = if l > 0.0 { (band_edge, outer) } else { (-outer, -band_edge) };
                    free[k] = known_free((a - reach_along, a + reach_along), across);
                }
                // a point inside the body itself, not only its clearance, bars it for good
                if intrusion[k] > g.clearance_m {
                    free[k] = false;
                }
            }
        }
        lattice.clear = clear.iter().zip(&free).map(|(&c, &f)| c && f).collect();
        lattice.free = free;
        lattice.intrusion = intrusion;
        // the body stands where it stands: its own lattice point is passable
        let from_k = lattice.index(lattice.nearest(start))?;
        lattice.free[from_k] = true;
        Some((lattice, per_cell))
    }
}

/// The cheapest way over clear lattice points from `from` to a point `is_goal` accepts.
fn search(
    lattice: &Lattice,
    from: (i32, i32),
    is_goal: impl Fn((i32, i32)) -> bool,
) -> Option<Vec<(i32, i32)>> {
    let n = lattice.clear.len();
    let mut cost = vec![u32::MAX; n];
    let mut came_from = vec![usize::MAX; n];
    let mut open = BinaryHeap::new();
    let from_k = lattice.index(from)?;
    cost[from_k] = 0;
    open.push(Reverse((0u32, from_k)));
    let width = lattice.size.1 as usize;
    let node_of = |k: usize| ((k / width) as i32, (k % width) as i32);
    // along, across and diagonal steps, as (di, dj, cost)
    let diagonal = ACROSS_COST + 1;
    let moves = [
        (1, 0, 1),
        (-1, 0, 1),
        (0, 1, ACROSS_COST),
        (0, -1, ACROSS_COST),
        (1, 1, diagonal),
        (1, -1, diagonal),
        (-1, 1, diagonal),
        (-1, -1, diagonal),
    ];
    while let Some(Reverse((c, k))) = open.pop() {
        if c > cost[k] {
            continue;
        }
        let node = node_of(k);
        if is_goal(node) {
            let mut path = vec![node];
            let mut at = k;
            while came_from[at] != usize::MAX {
                at = came_from[at];
                path.push(node_of(at));
            }
            path.reverse();
            return Some(path);
        }
        for (di, dj, step_cost) in moves {
            let next = (node.0 + di, node.1 + dj);
            let from = lattice.intrusion_at(node);
            if !lattice.passable(next, from) {
                continue;
            }
            // a diagonal step keeps the clearance when both steps along the axes do
            if di != 0
                && dj != 0
                && !(lattice.passable((node.0 + di, node.1), from)
                    && lattice.passable((node.0, node.1 + dj), from))
            {
                continue;
            }
            let Some(nk) = lattice.index(next) else { continue };
            let nc = c + step_cost + lattice.near[nk];
            if nc < cost[nk] {
                cost[nk] = nc;
                came_from[nk] = k;
                open.push(Reverse((nc, nk)));
            }
        }
    }
    None
}

/// The fewest straight legs along `path` whose lattice squares are all clear, then, with
/// `final_drive`, the drive along the last track.
fn into_legs(lattice: &Lattice, start: (f64, f64), path: &[(i32, i32)], final_drive: bool) -> Slide {
    let Some(&goal) = path.last() else {
        return Slide { legs: Vec::new(), track_left_m: start.1, stop_along_m: 0.0 };
    };
    // the last drive: back along the path while it keeps the goal's track
    let mut drive_from = path.len() - 1;
    while final_drive
        && drive_from > 0
        && path[drive_from - 1].1 == goal.1
        && path[drive_from - 1].0 < path[drive_from].0
    {
        drive_from -= 1;
    }
    let mut legs = Vec::new();
    let mut at = 0;
    while at < drive_from {
        // the farthest point on the path a straight leg reaches from here
        let next = (at + 1..=drive_from)
            .rev()
            .find(|&k| k == at + 1 || leg_clear(lattice, path[at], path[k], near_on(lattice, &path[at..=k])))
            .unwrap_or(at + 1);
        legs.push(lattice.position(path[next]));
        at = next;
    }
    let track_left_m = lattice.position(goal).1;
    // a first leg onto the lattice point the body stands nearest to adds nothing
    if legs.first().is_some_and(|&(a, l)| (a - start.0).hypot(l - start.1) < 0.5 * lattice.step) {
        legs.remove(0);
    }
    Slide { legs, track_left_m, stop_along_m: 0.0 }
}

/// The dearest nearness ([`NEAR_COST`]) on the lattice points `nodes`.
fn near_on(lattice: &Lattice, nodes: &[(i32, i32)]) -> u32 {
    nodes.iter().filter_map(|&n| lattice.index(n)).map(|k| lattice.near[k]).max().unwrap_or(0)
}

/// Whether every lattice square the straight leg from `a` to `b` crosses has four clear corners,
/// none nearer a point than `near` allows: a leg cuts no corner the lattice way kept away from.
fn leg_clear(lattice: &Lattice, a: (i32, i32), b: (i32, i32), near: u32) -> bool {
    let from = lattice.intrusion_at(a);
    let ok =
        |node| lattice.passable(node, from) && lattice.index(node).is_some_and(|k| lattice.near[k] <= near);
    let (di, dj) = (b.0 - a.0, b.1 - a.1);
    // along one axis the leg runs on lattice points
    if di == 0 || dj == 0 {
        let n = di.abs().max(dj.abs());
        return (0..=n).all(|t| ok((a.0 + di.signum() * t, a.1 + dj.signum() * t)));
    }
    // the lattice squares the segment crosses, met by sampling at an eighth of a step; a sample
    // on a lattice line needs only the corners on that line
    let samples = 8 * di.abs().max(dj.abs());
    (0..=samples).all(|t| {
        let f = f64::from(t) / f64::from(samples);
        let (x, y) = (f64::from(a.0) + f * f64::from(di), f64::from(a.1) + f * f64::from(dj));
        let span = |v: f64| {
            let lo = v.floor() as i32;
            if v == v.floor() { lo..=lo } else { lo..=lo + 1 }
        };
        span(x).all(|i| span(y).all(|j| ok((i, j))))
    })
}

#[cfg(test)]
mod tests;
