//! Trajectory: from the robot's cell and heading to a destination, as robot commands.
//!
//! Concept: [`Planner::plan`] runs A* ([`crate::astar`], `Reference` order by default so the
//! original's paths come out) over the map's *known free* cells, then turns the path into
//! commands: for each step, the turns that face the next cell (none, RIGHT, LEFT, or RIGHT RIGHT
//! for 180°) then one FORWARD. [`Planner::plan_on_map`] also paints the map the way Cute's
//! TRAJECTOIRE did: previous waypoints and destination cleared, path cells waypoints (3), the
//! destination 4, the robot 5.
//!
//! Fixes over the original (research §1.8, §1.10): a 180° turn is `RIGHT, RIGHT` and the heading
//! is tracked correctly; an adjacent destination yields commands; "no path" is a
//! [`PlanError::NoPath`]. The start heading is a parameter (the original always assumed EAST).
//!
//! Passable cells: free (1), waypoint (3), destination (4) and the robot's cell (5). Unknown (2)
//! counts as an obstacle, as in the original, and the destination must be a known free cell —
//! unless the planner is built [`Planner::through_unknown`] (Cute's `--compat explobot-2024`: the
//! original Carto cannot map, so its users send the robot across cells nobody has seen). Then
//! unknown cells cost the same as free ones and may be the destination, so the paths are those of
//! an all-free map (what the original Cute planned on its demo map).
//!
//! Invariants: `commands` contains exactly `path.len() - 1` FORWARDs, each preceded by at most two
//! turns; replaying `commands` from the start pose ends on the destination, facing
//! `final_heading`.
//!
//! ```
//! use cute::map::Map;
//! use robot_model::grid::{Heading, Move};
//! use cute::trajectory::Planner;
//! let mut map = Map::parse("5111\n0201\n0001\n0004\n").unwrap();
//! let t = Planner::new().plan_on_map(&mut map, (0, 0), Heading::East, (3, 3)).unwrap();
//! let numbers: Vec<u8> = t.commands.iter().map(|c| c.as_u8()).collect();
//! assert_eq!(numbers, [0, 0, 0, 1, 0, 0, 0]); // the original's first test vector
//! assert_eq!(map.to_text(), "5333\n0203\n0003\n0004\n");
//! ```

use thiserror::Error;

use crate::astar::{AStar, Grid, TieBreak};
use crate::map::{CellValue, Map};
use robot_model::grid::{Heading, Move, turns_between};

/// Why no trajectory could be planned.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum PlanError {
    /// The start or the destination lies outside the map.
    #[error("cell ({x}, {y}) is outside the {rows}x{cols} map")]
    OutOfBounds {
        /// Row.
        x: u8,
        /// Column.
        y: u8,
        /// Map rows.
        rows: usize,
        /// Map columns.
        cols: usize,
    },
    /// The destination is not a known free cell (it is unknown or an obstacle).
    #[error("destination ({x}, {y}) is not a known free cell (value {value:?})")]
    DestinationNotFree {
        /// Row.
        x: u8,
        /// Column.
        y: u8,
        /// What the map holds there.
        value: CellValue,
    },
    /// Known free cells do not connect the robot to the destination.
    #[error("no path from ({from_x}, {from_y}) to ({to_x}, {to_y})")]
    NoPath {
        /// Start row.
        from_x: u8,
        /// Start column.
        from_y: u8,
        /// Destination row.
        to_x: u8,
        /// Destination column.
        to_y: u8,
    },
    /// A mission is running (the session refuses to plan until it ends or is stopped).
    #[error("the robot is busy with another mission")]
    Busy,
    /// Two consecutive path cells are not 4-neighbours.
    #[error("path step ({from_x}, {from_y}) -> ({to_x}, {to_y}) is not one 4-neighbour move")]
    NotAdjacent {
        /// Row of the cell left.
        from_x: u8,
        /// Column of the cell left.
        from_y: u8,
        /// Row of the cell entered.
        to_x: u8,
        /// Column of the cell entered.
        to_y: u8,
    },
}

/// A planned trajectory: the cells, the commands that drive them, and the heading at the end.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Trajectory {
    /// Every cell `(x, y)` from the robot's cell (first) to the destination (last).
    pub path: Vec<(u8, u8)>,
    /// Turns and FORWARDs, in order.
    pub commands: Vec<Move>,
    /// The robot's heading after the last command.
    pub final_heading: Heading,
}

/// The commands that drive `path` (start cell first) from `heading`, and the final heading.
pub fn commands_for_path(path: &[(u8, u8)], heading: Heading) -> Result<(Vec<Move>, Heading), PlanError> {
    let mut commands = Vec::with_capacity(path.len() * 2);
    let mut h = heading;
    for w in path.windows(2) {
        let want = Heading::between(w[0], w[1]).ok_or(PlanError::NotAdjacent {
            from_x: w[0].0,
            from_y: w[0].1,
            to_x: w[1].0,
            to_y: w[1].1,
        })?;
        commands.extend_from_slice(turns_between(h, want));
        commands.push(Move::Forward);
        h = want;
    }
    Ok((commands, h))
}

/// Builds the A* grid for a map: known free cells cost 1, unknown cells cost `unknown_cost`
/// (0 = impassable), obstacles are blocked, and so are the map's blocked moves.
pub fn grid_from_map(map: &Map, unknown_cost: u8) -> Grid {
    let mut grid = Grid::for_map(map);
    fill_grid(&mut grid, map, unknown_cost);
    grid
}

/// Refreshes `grid` (same size as `map`) from the map, as [`grid_from_map`] does: the cells'
/// costs and the map's blocked moves.
pub fn fill_grid(grid: &mut Grid, map: &Map, unknown_cost: u8) {
    for ((x, y), v) in map.iter() {
        let cost = match v {
            CellValue::Obstacle => 0,
            CellValue::Unknown => unknown_cost,
            _ => 1,
        };
        grid.set_cost(usize::from(x), usize::from(y), cost);
    }
    grid.open_all_moves();
    for (a, b) in map.blocked_moves() {
        grid.block_move((usize::from(a.0), usize::from(a.1)), (usize::from(b.0), usize::from(b.1)));
    }
}

/// A trajectory planner that keeps its A* buffers between plans.
#[derive(Debug, Clone)]
pub struct Planner {
    astar: AStar,
    grid: Option<Grid>,
    tie_break: TieBreak,
    through_unknown: bool,
}

impl Default for Planner {
    fn default() -> Self {
        Planner::new()
    }
}

impl Planner {
    /// A planner using the original's `(f, row, col)` order ([`TieBreak::Reference`]).
    pub fn new() -> Planner {
        Planner { astar: AStar::new(), grid: None, tie_break: TieBreak::Reference, through_unknown: false }
    }

    /// The same planner, crossing (and ending on) unknown cells as if they were free when `yes`.
    pub fn through_unknown(self, yes: bool) -> Planner {
        Planner { through_unknown: yes, ..self }
    }

    /// True if unknown cells are planned as free ([`Planner::through_unknown`]).
    pub fn plans_through_unknown(&self) -> bool {
        self.through_unknown
    }

    /// A planner using the given A* open-list order.
    pub fn with_tie_break(tie_break: TieBreak) -> Planner {
        Planner { tie_break, ..Planner::new() }
    }

    /// Plans from `from` (facing `heading`) to `to` over known free cells, without touching the map.
    pub fn plan(
        &mut self,
        map: &Map,
        from: (u8, u8),
        heading: Heading,
        to: (u8, u8),
    ) -> Result<Trajectory, PlanError> {
        for (x, y) in [from, to] {
            if !map.contains(usize::from(x), usize::from(y)) {
                return Err(PlanError::OutOfBounds { x, y, rows: map.rows(), cols: map.cols() });
            }
        }
        let value = map.at(to).unwrap_or(CellValue::Obstacle);
        if from == to {
            return Ok(Trajectory { path: vec![from], commands: Vec::new(), final_heading: heading });
        }
        let unknown_ok = self.through_unknown && value == CellValue::Unknown;
        if !value.is_known_free() && !unknown_ok {
            return Err(PlanError::DestinationNotFree { x: to.0, y: to.1, value });
        }
        let unknown_cost = u8::from(self.through_unknown);
        let grid = match &mut self.grid {
            Some(g) if g.rows() == map.rows() && g.cols() == map.cols() => {
                fill_grid(g, map, unknown_cost);
                g
            }
            slot => slot.insert(grid_from_map(map, unknown_cost)),
        };
        let path = self
            .astar
            .search_with(
                grid,
                (usize::from(from.0), usize::from(from.1)),
                (usize::from(to.0), usize::from(to.1)),
                self.tie_break,
            )
            .ok_or(PlanError::NoPath { from_x: from.0, from_y: from.1, to_x: to.0, to_y: to.1 })?;
        // Grid cells are map cells, at most 256 per side: they fit a byte.
        let path: Vec<(u8, u8)> = path.cells.iter().map(|&(x, y)| (x as u8, y as u8)).collect();
        let (commands, final_heading) = commands_for_path(&path, heading)?;
        Ok(Trajectory { path, commands, final_heading })
    }

    /// Clears the previous trajectory from the map, plans, and paints the new one (robot 5,
    /// waypoints 3, destination 4). On error the map keeps the cleared state.
    pub fn plan_on_map(
        &mut self,
        map: &mut Map,
        from: (u8, u8),
        heading: Heading,
        to: (u8, u8),
    ) -> Result<Trajectory, PlanError> {
        map.clear_trajectory();
        let t = self.plan(map, from, heading, to)?;
        paint(map, &t);
        Ok(t)
    }
}

/// Paints a trajectory: robot on the first cell, waypoints in between, destination on the last.
pub fn paint(map: &mut Map, t: &Trajectory) {
    let (Some(&first), Some(&last)) = (t.path.first(), t.path.last()) else {
        return;
    };
    // Cells of a planned path lie on the map, so these writes cannot fail.
    let _ = map.set_robot(usize::from(first.0), usize::from(first.1));
    if t.path.len() > 1 {
        for &(x, y) in &t.path[1..t.path.len() - 1] {
            let _ = map.set_waypoint(usize::from(x), usize::from(y));
        }
        let _ = map.set_destination(usize::from(last.0), usize::from(last.1));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn nums(c: &[Move]) -> Vec<u8> {
        c.iter().map(|c| c.as_u8()).collect()
    }

    /// Replays commands on the map, checking every FORWARD enters a known free cell.
    fn replay(map: &Map, from: (u8, u8), heading: Heading, cmds: &[Move]) -> ((u8, u8), Heading) {
        let (mut pos, mut h) = (from, heading);
        for c in cmds {
            if *c == Move::Forward {
                pos = h.step(pos, map.rows(), map.cols()).unwrap();
                assert!(map.at(pos).unwrap().is_known_free(), "drove into {:?}", pos);
            } else {
                h = h.after(*c);
            }
        }
        (pos, h)
    }

    fn reference(text: &str) -> Vec<u8> {
        let mut map = Map::parse(text).unwrap();
        let (from, to) = (map.robot().unwrap(), map.destination().unwrap());
        let original =
            Planner::with_tie_break(TieBreak::Original).plan(&map, from, Heading::East, to).unwrap();
        let t = Planner::new().plan_on_map(&mut map, from, Heading::East, to).unwrap();
        assert_eq!(replay(&map, from, Heading::East, &t.commands).0, to);
        assert_eq!(original.commands, t.commands);
        nums(&t.commands)
    }

    #[test]
    fn original_reference_vector_1() {
        assert_eq!(reference("5111\n0201\n0001\n0004"), [0, 0, 0, 1, 0, 0, 0]);
    }

    #[test]
    fn original_reference_vector_2() {
        assert_eq!(reference("4111\n0001\n0001\n2115"), [2, 0, 0, 0, 2, 0, 0, 0]);
    }

    #[test]
    fn original_reference_vector_3() {
        assert_eq!(reference("5100\n0110\n0010\n0014"), [0, 1, 0, 2, 0, 1, 0, 0, 2, 0]);
    }

    #[test]
    fn straight_line_needs_no_turn() {
        let map = Map::parse("1111\n").unwrap();
        let t = Planner::new().plan(&map, (0, 0), Heading::East, (0, 3)).unwrap();
        assert_eq!(nums(&t.commands), [0, 0, 0]);
        assert_eq!(t.final_heading, Heading::East);
        assert_eq!(t.path, vec![(0, 0), (0, 1), (0, 2), (0, 3)]);
    }

    #[test]
    fn one_turn() {
        let map = Map::parse("11\n01\n01\n").unwrap();
        let t = Planner::new().plan(&map, (0, 0), Heading::East, (2, 1)).unwrap();
        assert_eq!(replay(&map, (0, 0), Heading::East, &t.commands).0, (2, 1));
        assert_eq!(nums(&t.commands), [0, 1, 0, 0]);
        assert_eq!(t.final_heading, Heading::South);
    }

    #[test]
    fn issue_180_degree_turn_is_right_right() {
        // The original emitted a single LEFT here ("2,0,2,0") and drove the wrong way.
        let map = Map::parse("111\n111\n").unwrap();
        let t = Planner::new().plan(&map, (1, 1), Heading::East, (1, 0)).unwrap();
        assert_eq!(nums(&t.commands), [1, 1, 0]);
        assert_eq!(t.final_heading, Heading::West);
    }

    #[test]
    fn issue_adjacent_destination_yields_commands() {
        let map = Map::parse("11\n11\n").unwrap();
        let t = Planner::new().plan(&map, (0, 0), Heading::East, (0, 1)).unwrap();
        assert_eq!(nums(&t.commands), [0]);
        let t = Planner::new().plan(&map, (0, 0), Heading::East, (1, 0)).unwrap();
        assert_eq!(nums(&t.commands), [1, 0]);
    }

    #[test]
    fn no_path_is_an_error() {
        let map = Map::parse("101\n101\n").unwrap();
        assert_eq!(
            Planner::new().plan(&map, (0, 0), Heading::East, (0, 2)),
            Err(PlanError::NoPath { from_x: 0, from_y: 0, to_x: 0, to_y: 2 })
        );
    }

    /// A blocked move on the map (a thin wall between two free cells) is planned round, and a
    /// planner that keeps its grid forgets it after a reset.
    #[test]
    fn blocked_moves_are_planned_round() {
        let mut map = Map::parse("111\n111\n").unwrap();
        let mut planner = Planner::new();
        let straight = planner.plan(&map, (0, 0), Heading::East, (0, 2)).unwrap();
        assert_eq!(straight.path, vec![(0, 0), (0, 1), (0, 2)]);
        map.block_move((0, 1), (0, 2)).unwrap();
        let round = planner.plan(&map, (0, 0), Heading::East, (0, 2)).unwrap();
        assert_eq!(round.path.len(), 5, "{:?}", round.path);
        assert_eq!(round.path[3..], [(1, 2), (0, 2)]);
        map.reset();
        for x in 0..2 {
            for y in 0..3 {
                map.set_free(x, y).unwrap();
            }
        }
        assert_eq!(planner.plan(&map, (0, 0), Heading::East, (0, 2)).unwrap(), straight);
    }

    #[test]
    fn unknown_and_obstacle_destinations_are_refused() {
        let map = Map::parse("120\n").unwrap();
        assert!(matches!(
            Planner::new().plan(&map, (0, 0), Heading::East, (0, 1)),
            Err(PlanError::DestinationNotFree { value: CellValue::Unknown, .. })
        ));
        assert!(matches!(
            Planner::new().plan(&map, (0, 0), Heading::East, (0, 2)),
            Err(PlanError::DestinationNotFree { value: CellValue::Obstacle, .. })
        ));
        assert!(matches!(
            Planner::new().plan(&map, (0, 0), Heading::East, (3, 0)),
            Err(PlanError::OutOfBounds { x: 3, .. })
        ));
    }

    #[test]
    fn unknown_cells_are_not_crossed() {
        let map = Map::parse("121\n111\n").unwrap();
        let t = Planner::new().plan(&map, (0, 0), Heading::East, (0, 2)).unwrap();
        assert_eq!(t.path, vec![(0, 0), (1, 0), (1, 1), (1, 2), (0, 2)]);
    }

    #[test]
    fn issue_14_through_unknown_plans_as_on_an_all_free_map() {
        // The original Cute, robot (0, 0) facing EAST, destination (2, 3): F F F R F F (observed).
        let unknown = Map::new(20, 20).unwrap();
        assert!(matches!(
            Planner::new().plan(&unknown, (0, 0), Heading::East, (2, 3)),
            Err(PlanError::DestinationNotFree { value: CellValue::Unknown, .. })
        ));
        let mut p = Planner::new().through_unknown(true);
        assert!(p.plans_through_unknown());
        let t = p.plan(&unknown, (0, 0), Heading::East, (2, 3)).unwrap();
        assert_eq!(nums(&t.commands), [0, 0, 0, 1, 0, 0]);
        let free = Map::parse(&format!("{}\n", "1".repeat(20)).repeat(20)).unwrap();
        assert_eq!(Planner::new().plan(&free, (0, 0), Heading::East, (2, 3)).unwrap(), t);
        // Known obstacles are still avoided.
        let walled = Map::parse("1022\n1022\n2222\n").unwrap();
        let t = p.plan(&walled, (0, 0), Heading::East, (0, 2)).unwrap();
        assert_eq!(t.path, vec![(0, 0), (1, 0), (2, 0), (2, 1), (2, 2), (1, 2), (0, 2)]);
        assert!(matches!(
            p.plan(&walled, (0, 0), Heading::East, (0, 1)),
            Err(PlanError::DestinationNotFree { .. })
        ));
    }

    #[test]
    fn around_an_obstacle_and_map_painting() {
        let mut map = Map::parse(
            "11111\n\
             11011\n\
             11011\n\
             11111\n",
        )
        .unwrap();
        let mut p = Planner::new();
        let t = p.plan_on_map(&mut map, (1, 1), Heading::North, (1, 3)).unwrap();
        assert_eq!(t.path.len() - 1, 4);
        assert_eq!(replay(&map, (1, 1), Heading::North, &t.commands), ((1, 3), t.final_heading));
        assert_eq!(map.count(CellValue::Waypoint), 3);
        assert_eq!(map.destination(), Some((1, 3)));
        assert_eq!(map.robot(), Some((1, 1)));
        // A second plan clears the first one's waypoints.
        let t2 = p.plan_on_map(&mut map, (1, 1), Heading::North, (3, 0)).unwrap();
        assert_eq!(map.count(CellValue::Waypoint), t2.path.len() - 2);
        assert_eq!(map.count(CellValue::Destination), 1);
    }

    #[test]
    fn same_cell_is_an_empty_trajectory() {
        let map = Map::parse("5\n").unwrap();
        let t = Planner::new().plan(&map, (0, 0), Heading::West, (0, 0)).unwrap();
        assert!(t.commands.is_empty());
        assert_eq!(t.final_heading, Heading::West);
    }

    #[test]
    fn commands_for_path_rejects_jumps() {
        assert!(matches!(
            commands_for_path(&[(0, 0), (1, 1)], Heading::East),
            Err(PlanError::NotAdjacent { .. })
        ));
    }
}
