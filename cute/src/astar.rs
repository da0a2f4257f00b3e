//! A* on a 4-connected grid with the Manhattan heuristic, built for speed.
//!
//! Concept: a [`Grid`] holds, for every cell, the cost of *entering* it (1..=255) or 0 for blocked,
//! and which of the moves between neighbouring cells are blocked (a thin wall on the line between
//! two free cells: [`Grid::block_move`]). An [`AStar`] planner keeps every buffer it needs between
//! queries (flat arrays indexed by cell id, a generation stamp instead of clearing, a reusable open
//! list), so a query allocates only the returned [`Path`]. The grid is stored with a one-cell
//! blocked border, so neighbour look-ups need no bounds checks.
//!
//! Three open-list orders ([`TieBreak`]):
//! - [`TieBreak::Reference`] follows the original planner (`trajectory.py`, research §1.8): a
//!   binary heap keyed `(f, row, col)` packed into one `u64`, neighbours tried in the order
//!   (0,+1), (+1,0), (−1,0), (0,−1), the start pushed with f = 0. It decides which of several
//!   equal-length paths comes out, so the original's test vectors reproduce. Unlike the
//!   original, a neighbour already open whose cost improves is pushed again with its new key
//!   (the old entry is skipped when popped), which keeps the result optimal.
//! - [`TieBreak::Original`] is the same loop bit for bit, including the original's quirk: an open
//!   neighbour is re-scored in place and keeps its old heap key. That can return a path longer
//!   than the shortest one (about 0.2 % of random 20 %-obstacle queries up to 11 × 11; see the
//!   test `original_planner_can_be_suboptimal`). For differential tests only.
//! - [`TieBreak::Fast`] (the default) uses a bucket queue on f (f never decreases with a
//!   consistent heuristic) and takes the most recently pushed node first within a bucket. That
//!   prefers deep nodes among equal f, so on open ground it walks straight to the goal instead of
//!   filling the whole start–goal rectangle as `(f, row, col)` does. Optimal.
//!
//! Invariants: a returned [`Path`] starts at the start, ends at the goal, moves one 4-neighbour
//! step at a time through cells of non-zero cost and never over a blocked move, and its `cost` (the
//! sum of the entered cells' costs) is minimal (except with [`TieBreak::Original`]). The start cell
//! itself may be blocked (it is where the robot stands). No path, a blocked goal or a cell outside
//! the grid give `None`, never a panic.
//!
//! ```
//! use cute::astar::{AStar, Grid, TieBreak};
//! let mut grid = Grid::open(3, 3).unwrap();
//! grid.set_cost(0, 1, 0); // blocked
//! grid.set_cost(1, 1, 0);
//! let mut planner = AStar::new();
//! let path = planner.search(&grid, (0, 0), (0, 2)).unwrap();
//! assert_eq!(path.cost, 6);
//! assert_eq!(path.cells.first(), Some(&(0, 0)));
//! assert_eq!(path.cells.last(), Some(&(0, 2)));
//! let same = planner.search_with(&grid, (0, 0), (0, 2), TieBreak::Reference).unwrap();
//! assert_eq!(same.cost, 6);
//! grid.set_cost(2, 1, 0);
//! assert!(planner.search(&grid, (0, 0), (0, 2)).is_none());
//! ```

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use thiserror::Error;

use crate::map::Map;

/// Largest number of cells a [`Grid`] may have (ids must fit 32 bits with room to spare).
pub const MAX_GRID_CELLS: usize = 1 << 28;

/// Why a grid could not be built.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum GridError {
    /// Zero rows or columns, or more than [`MAX_GRID_CELLS`] cells.
    #[error("grid size {rows}x{cols} is empty or too large")]
    BadSize {
        /// Requested rows.
        rows: usize,
        /// Requested columns.
        cols: usize,
    },
}

/// The order in which equal-f nodes leave the open list.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TieBreak {
    /// The original planner's `(f, row, col)` order (research §1.8), kept optimal.
    Reference,
    /// The original planner bit for bit, including its stale-key quirk (may be suboptimal).
    Original,
    /// Bucket queue on f, newest first within a bucket: the fastest, still optimal.
    #[default]
    Fast,
}

/// Entry costs of a `rows × cols` grid, stored with a blocked border; 0 means blocked. Moves
/// between neighbours are open unless [`Grid::block_move`] closed them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Grid {
    rows: usize,
    cols: usize,
    stride: usize,
    max_cost: u8,
    cost: Vec<u8>,
    /// Per padded cell, bit `d` set: the move towards `DELTAS[d]` is blocked (kept for both ends).
    blocked_moves: Vec<u8>,
}

impl Grid {
    /// A grid whose cells are all blocked.
    pub fn blocked(rows: usize, cols: usize) -> Result<Grid, GridError> {
        let padded = (rows + 2).checked_mul(cols + 2);
        match padded {
            Some(n) if rows > 0 && cols > 0 && n <= MAX_GRID_CELLS => Ok(Grid {
                rows,
                cols,
                stride: cols + 2,
                max_cost: 1,
                cost: vec![0; n],
                blocked_moves: vec![0; n],
            }),
            _ => Err(GridError::BadSize { rows, cols }),
        }
    }

    /// A blocked grid the size of `map` (a map's sides are 1..=256, always a valid grid).
    pub fn for_map(map: &Map) -> Grid {
        let (rows, cols) = (map.rows(), map.cols());
        let n = (rows + 2) * (cols + 2);
        Grid { rows, cols, stride: cols + 2, max_cost: 1, cost: vec![0; n], blocked_moves: vec![0; n] }
    }

    /// A grid whose cells all cost 1.
    pub fn open(rows: usize, cols: usize) -> Result<Grid, GridError> {
        let mut grid = Grid::blocked(rows, cols)?;
        for r in 0..rows {
            let base = (r + 1) * grid.stride + 1;
            grid.cost[base..base + cols].fill(1);
        }
        Ok(grid)
    }

    /// A grid whose cell `(row, col)` costs `f(row, col)` (0 = blocked).
    pub fn from_fn(
        rows: usize,
        cols: usize,
        mut f: impl FnMut(usize, usize) -> u8,
    ) -> Result<Grid, GridError> {
        let mut grid = Grid::blocked(rows, cols)?;
        for r in 0..rows {
            for c in 0..cols {
                grid.set_cost(r, c, f(r, c));
            }
        }
        Ok(grid)
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of columns.
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// True if `(row, col)` is on the grid.
    pub fn contains(&self, row: usize, col: usize) -> bool {
        row < self.rows && col < self.cols
    }

    #[inline]
    fn id(&self, row: usize, col: usize) -> usize {
        (row + 1) * self.stride + col + 1
    }

    #[inline]
    fn row_col(&self, id: usize) -> (usize, usize) {
        (id / self.stride - 1, id % self.stride - 1)
    }

    /// The cost of entering `(row, col)`; 0 if blocked or outside the grid.
    pub fn cost(&self, row: usize, col: usize) -> u8 {
        if self.contains(row, col) { self.cost[self.id(row, col)] } else { 0 }
    }

    /// True if `(row, col)` is on the grid and not blocked.
    pub fn is_passable(&self, row: usize, col: usize) -> bool {
        self.cost(row, col) != 0
    }

    /// Sets the cost of entering `(row, col)` (0 = blocked); outside the grid it does nothing.
    pub fn set_cost(&mut self, row: usize, col: usize, cost: u8) {
        if self.contains(row, col) {
            let id = self.id(row, col);
            self.cost[id] = cost;
            self.max_cost = self.max_cost.max(cost);
        }
    }

    /// The index in `DELTAS` of the step from `from` to `to`, if both are on the grid and
    /// 4-neighbours.
    fn direction(&self, from: (usize, usize), to: (usize, usize)) -> Option<usize> {
        if !self.contains(from.0, from.1) || !self.contains(to.0, to.1) {
            return None;
        }
        DELTAS.iter().position(|&(dr, dc)| {
            from.0.checked_add_signed(dr) == Some(to.0) && from.1.checked_add_signed(dc) == Some(to.1)
        })
    }

    /// Blocks the move between the neighbours `a` and `b`, both ways (the costs of the cells are
    /// left as they are). Returns false, doing nothing, if they are not 4-neighbours on the grid.
    pub fn block_move(&mut self, a: (usize, usize), b: (usize, usize)) -> bool {
        let Some(dir) = self.direction(a, b) else {
            return false;
        };
        let (ia, ib) = (self.id(a.0, a.1), self.id(b.0, b.1));
        self.blocked_moves[ia] |= 1 << dir;
        self.blocked_moves[ib] |= 1 << (3 - dir); // DELTAS[3 - d] is the opposite of DELTAS[d]
        true
    }

    /// True if `a` and `b` are 4-neighbours on the grid and the move between them is not
    /// blocked (whatever the cells' costs).
    pub fn is_move_open(&self, a: (usize, usize), b: (usize, usize)) -> bool {
        self.direction(a, b).is_some_and(|dir| self.blocked_moves[self.id(a.0, a.1)] & (1 << dir) == 0)
    }

    /// Opens every move again.
    pub fn open_all_moves(&mut self) {
        self.blocked_moves.fill(0);
    }
}

/// A path found by [`AStar`]: every cell from start to goal, and its total cost.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Path {
    /// `(row, col)` of each cell, start first, goal last.
    pub cells: Vec<(usize, usize)>,
    /// Sum of the entry costs of every cell after the start (the number of moves on a unit grid).
    pub cost: u32,
}

/// Per-cell search state, 8 bytes, so one memory access serves a whole neighbour check.
#[derive(Debug, Clone, Copy, Default)]
struct Node {
    /// Generation in which `gf` was written; any other value means "not seen yet".
    stamp: u32,
    /// Best known cost from the start in the high 28 bits, then `IN_OPEN`, `CLOSED` and the
    /// parent direction (2 bits).
    gf: u32,
}

impl Node {
    #[inline]
    fn g(self) -> u32 {
        self.gf >> FLAG_BITS
    }
}

const FLAG_BITS: u32 = 4;
const DIR_MASK: u32 = 0b11;
const CLOSED: u32 = 0b100;
const IN_OPEN: u32 = 0b1000;
/// Costs saturate here (2^28 − 1, far above any 256 × 256 map or benchmark path).
const G_MAX: u32 = (1 << (32 - FLAG_BITS)) - 1;

/// (row delta, col delta) in the original planner's neighbour order: (0,+1), (+1,0), (−1,0), (0,−1).
const DELTAS: [(isize, isize); 4] = [(0, 1), (1, 0), (-1, 0), (0, -1)];

/// A reusable A* planner: keep one and call [`AStar::search`] as often as needed.
#[derive(Debug, Clone, Default)]
pub struct AStar {
    nodes: Vec<Node>,
    generation: u32,
    heap: BinaryHeap<Reverse<u64>>,
    buckets: Vec<Vec<u32>>,
    expanded: u64,
}

impl AStar {
    /// A planner with empty buffers; they grow to the largest grid searched and stay.
    pub fn new() -> AStar {
        AStar::default()
    }

    /// Nodes expanded (taken off the open list and examined) by the last search.
    pub fn last_expanded(&self) -> u64 {
        self.expanded
    }

    /// Shortest path from `start` to `goal` with [`TieBreak::Fast`]; `None` if there is none.
    pub fn search(&mut self, grid: &Grid, start: (usize, usize), goal: (usize, usize)) -> Option<Path> {
        self.search_with(grid, start, goal, TieBreak::Fast)
    }

    /// Shortest path from `start` to `goal` with the given open-list order; `None` if there is
    /// none, if either end is off the grid, or if the goal is blocked (`start == goal` is
    /// always the one-cell path).
    pub fn search_with(
        &mut self,
        grid: &Grid,
        start: (usize, usize),
        goal: (usize, usize),
        tie_break: TieBreak,
    ) -> Option<Path> {
        self.expanded = 0;
        if !grid.contains(start.0, start.1) || !grid.contains(goal.0, goal.1) {
            return None;
        }
        if start == goal {
            return Some(Path { cells: vec![start], cost: 0 });
        }
        if !grid.is_passable(goal.0, goal.1) {
            return None;
        }
        let s = grid.id(start.0, start.1);
        let t = grid.id(goal.0, goal.1);
        let generation = self.prepare(grid);
        let cost = match tie_break {
            TieBreak::Fast => self.run_fast(grid, s, t, generation)?,
            TieBreak::Reference => self.run_reference(grid, s, t, generation, false)?,
            TieBreak::Original => self.run_reference(grid, s, t, generation, true)?,
        };
        Some(self.reconstruct(grid, s, t, cost))
    }

    /// Grows the buffers to the grid and starts a new generation.
    fn prepare(&mut self, grid: &Grid) -> u32 {
        if self.nodes.len() < grid.cost.len() {
            self.nodes.resize(grid.cost.len(), Node::default());
        }
        if self.generation == u32::MAX {
            self.nodes.fill(Node::default());
            self.generation = 0;
        }
        self.generation += 1;
        self.generation
    }

    /// Bucket-queue A*; returns the goal's cost, parents left in `nodes`.
    fn run_fast(&mut self, grid: &Grid, s: usize, t: usize, generation: u32) -> Option<u32> {
        let stride = grid.stride;
        let offsets = neighbour_offsets(stride);
        let (gr, gc) = (t / stride, t % stride);
        // f grows by at most max_cost + 1 per push, so a ring of that many buckets suffices.
        let ring = (usize::from(grid.max_cost) + 2).next_power_of_two();
        let mask = ring - 1;
        if self.buckets.len() < ring {
            self.buckets.resize_with(ring, Vec::new);
        }
        for b in &mut self.buckets {
            b.clear();
        }
        let nodes = &mut self.nodes[..grid.cost.len()];
        let cost = &grid.cost[..];

        let (sr, sc) = (s / stride, s % stride);
        let mut f = sr.abs_diff(gr) + sc.abs_diff(gc);
        nodes[s] = Node { stamp: generation, gf: 0 };
        self.buckets[f & mask].push(s as u32);
        let mut queued = 1usize;
        let mut expanded = 0u64;
        let result = loop {
            let id = loop {
                if let Some(id) = self.buckets[f & mask].pop() {
                    break Some(id as usize);
                }
                if queued == 0 {
                    break None;
                }
                f += 1;
            };
            let Some(id) = id else { break None };
            queued -= 1;
            let here = &mut nodes[id];
            if here.gf & CLOSED != 0 {
                continue; // stale duplicate of an improved node
            }
            here.gf |= CLOSED;
            expanded += 1;
            let g = here.g();
            if id == t {
                break Some(g);
            }
            let (r, c) = (id / stride, id % stride);
            let blocked = grid.blocked_moves[id];
            for (dir, off) in offsets.iter().enumerate() {
                let nb = id.wrapping_add_signed(*off);
                let step = cost[nb];
                if step == 0 || blocked & (1 << dir) != 0 {
                    continue;
                }
                let ng = (g + u32::from(step)).min(G_MAX);
                let node = &mut nodes[nb];
                if node.stamp == generation && (node.gf & CLOSED != 0 || ng >= node.g()) {
                    continue;
                }
                *node = Node { stamp: generation, gf: (ng << FLAG_BITS) | dir as u32 };
                let (nr, nc) = (r.wrapping_add_signed(DELTAS[dir].0), c.wrapping_add_signed(DELTAS[dir].1));
                let nf = ng as usize + nr.abs_diff(gr) + nc.abs_diff(gc);
                self.buckets[nf & mask].push(nb as u32);
                queued += 1;
            }
        };
        self.expanded = expanded;
        result
    }

    /// The original planner's loop (bit for bit if `original`); returns the goal's cost.
    fn run_reference(
        &mut self,
        grid: &Grid,
        s: usize,
        t: usize,
        generation: u32,
        original: bool,
    ) -> Option<u32> {
        let stride = grid.stride;
        let offsets = neighbour_offsets(stride);
        let (gr, gc) = (t / stride, t % stride);
        let nodes = &mut self.nodes[..grid.cost.len()];
        let cost = &grid.cost[..];
        let heap = &mut self.heap;
        heap.clear();
        // The padded id preserves row-major order, so `(f << 32) | id` orders as (f, row, col).
        nodes[s] = Node { stamp: generation, gf: IN_OPEN };
        heap.push(Reverse(s as u64)); // the original pushes the start with f = 0
        let mut expanded = 0u64;
        let result = loop {
            let Some(Reverse(key)) = heap.pop() else {
                break None;
            };
            let id = (key & 0xffff_ffff) as usize;
            let g = nodes[id].g();
            if !original && id != s {
                let (r, c) = (id / stride, id % stride);
                if (key >> 32) != u64::from(g) + (r.abs_diff(gr) + c.abs_diff(gc)) as u64 {
                    continue; // an entry superseded by a cheaper push
                }
            }
            nodes[id].gf &= !IN_OPEN;
            expanded += 1;
            if id == t {
                break Some(g);
            }
            let (r, c) = (id / stride, id % stride);
            let blocked = grid.blocked_moves[id];
            for (dir, off) in offsets.iter().enumerate() {
                let nb = id.wrapping_add_signed(*off);
                let step = cost[nb];
                if step == 0 || blocked & (1 << dir) != 0 {
                    continue;
                }
                let ng = (g + u32::from(step)).min(G_MAX);
                let node = &mut nodes[nb];
                let seen = node.stamp == generation;
                if seen && ng >= node.g() {
                    continue;
                }
                let open = seen && node.gf & IN_OPEN != 0;
                *node = Node { stamp: generation, gf: (ng << FLAG_BITS) | IN_OPEN | dir as u32 };
                // The original re-scores a node already open in place (the heap keeps its old
                // key); otherwise, or when not imitating it, the node is pushed with its new key.
                if !(open && original) {
                    let (nr, nc) =
                        (r.wrapping_add_signed(DELTAS[dir].0), c.wrapping_add_signed(DELTAS[dir].1));
                    let nf = u64::from(ng) + (nr.abs_diff(gr) + nc.abs_diff(gc)) as u64;
                    heap.push(Reverse((nf << 32) | nb as u64));
                }
            }
        };
        self.expanded = expanded;
        result
    }

    fn reconstruct(&self, grid: &Grid, s: usize, t: usize, cost: u32) -> Path {
        let offsets = neighbour_offsets(grid.stride);
        let mut cells = Vec::new();
        let mut id = t;
        // Every node on the chain was stamped in this generation; the chain ends at the start
        // because a parent always has a smaller g. The bound guards against a corrupted chain.
        let mut guard = grid.cost.len();
        loop {
            cells.push(grid.row_col(id));
            if id == s || guard == 0 {
                break;
            }
            guard -= 1;
            let dir = (self.nodes[id].gf & DIR_MASK) as usize;
            id = id.wrapping_add_signed(-offsets[dir]);
        }
        cells.reverse();
        Path { cells, cost }
    }
}

#[inline]
fn neighbour_offsets(stride: usize) -> [isize; 4] {
    let s = stride as isize;
    [1, s, -s, -1]
}

#[cfg(test)]
mod tests;
