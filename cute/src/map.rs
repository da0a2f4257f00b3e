//! The operator's map: a `rows × cols` grid of [`CellValue`]s, at most 256 × 256.
//!
//! Concept: the map is what Cute knows about the room. Every cell starts unknown (2). Cartography
//! turns cells into free (1) or obstacle (0); a planned trajectory paints waypoints (3) and the
//! destination (4); the robot's cell shows 5. The numbers are Cute's `map.h` encoding (research
//! §1.8), used whenever a map is written or read as numbers.
//!
//! Coordinates follow the `link` protocol: `x` is the row (grows downward), `y` the column
//! (grows rightward), origin top-left, one byte each.
//!
//! Besides the cells, the map keeps the **blocked moves**: pairs of neighbouring cells the robot
//! cannot drive between, either although it has stood in both (a thin wall on the cell line, a
//! leg on the corner) or because Carto found the way between them not clear of the body. [`Map::note_refused_forward`] and
//! [`Map::note_way_not_clear`] are the rules that turn a refused FORWARD into a blocked move or an
//! obstacle; A* plans round both ([`crate::trajectory::fill_grid`]).
//!
//! Invariants: at most one cell holds [`CellValue::Robot`] and it is [`Map::robot`]; at most one
//! holds [`CellValue::Destination`] and it is [`Map::destination`]; cells are stored and iterated
//! in row-major order. Waypoint, destination and robot cells are known to be free. A blocked
//! move joins two 4-neighbours on the map. The text form ([`Map::to_text`], [`Map::parse`])
//! carries the cells only, as the original's map files do: blocked moves are not saved.
//!
//! ```
//! use cute::map::{CellValue, Map};
//! let mut map = Map::new(3, 4).unwrap();
//! assert_eq!(map.get(2, 3), Some(CellValue::Unknown));
//! map.set(0, 1, CellValue::Obstacle).unwrap();
//! map.set_robot(0, 0).unwrap();
//! assert_eq!(map.to_text(), "5022\n2222\n2222\n");
//! assert_eq!(Map::parse(&map.to_text()).unwrap(), map);
//! ```

use core::fmt;
use std::collections::BTreeSet;

use robot_model::grid::Heading;
use thiserror::Error;

/// The largest number of rows or columns (coordinates are one byte on the wire).
pub const MAX_SIDE: usize = 256;

/// What one cell of the map holds; the discriminant is Cute's number for it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
#[repr(u8)]
pub enum CellValue {
    /// 0: blocked, the robot cannot enter.
    Obstacle = 0,
    /// 1: free, the robot has been there (or it is known free).
    Free = 1,
    /// 2: not explored yet (the initial value).
    #[default]
    Unknown = 2,
    /// 3: a free cell on the planned trajectory.
    Waypoint = 3,
    /// 4: the trajectory's destination.
    Destination = 4,
    /// 5: the robot's cell.
    Robot = 5,
}

impl CellValue {
    /// Cute's number for this value (0..=5).
    pub const fn as_u8(self) -> u8 {
        self as u8
    }

    /// The value for a number, `None` above 5.
    pub const fn from_u8(v: u8) -> Option<CellValue> {
        match v {
            0 => Some(CellValue::Obstacle),
            1 => Some(CellValue::Free),
            2 => Some(CellValue::Unknown),
            3 => Some(CellValue::Waypoint),
            4 => Some(CellValue::Destination),
            5 => Some(CellValue::Robot),
            _ => None,
        }
    }

    /// True for cells known to be free: free, waypoint, destination and robot.
    pub const fn is_known_free(self) -> bool {
        matches!(self, CellValue::Free | CellValue::Waypoint | CellValue::Destination | CellValue::Robot)
    }

    /// The digit used by [`Map::to_text`].
    pub const fn to_char(self) -> char {
        (b'0' + self as u8) as char
    }
}

impl From<CellValue> for u8 {
    fn from(v: CellValue) -> u8 {
        v.as_u8()
    }
}

impl TryFrom<u8> for CellValue {
    type Error = MapError;
    fn try_from(v: u8) -> Result<CellValue, MapError> {
        CellValue::from_u8(v).ok_or(MapError::BadValue { value: v })
    }
}

/// Why a map operation or a map text was refused.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum MapError {
    /// A side is zero or above [`MAX_SIDE`].
    #[error("map size {rows}x{cols} is outside 1..=256 per side")]
    BadSize {
        /// Requested rows.
        rows: usize,
        /// Requested columns.
        cols: usize,
    },
    /// A coordinate lies outside the map.
    #[error("cell ({x}, {y}) is outside the {rows}x{cols} map")]
    OutOfBounds {
        /// Row.
        x: usize,
        /// Column.
        y: usize,
        /// Map rows.
        rows: usize,
        /// Map columns.
        cols: usize,
    },
    /// Two cells that are not 4-neighbours, given as a move.
    #[error("cells {a:?} and {b:?} are not neighbours")]
    NotNeighbours {
        /// One cell.
        a: (u8, u8),
        /// The other.
        b: (u8, u8),
    },
    /// A number that is not a cell value.
    #[error("{value} is not a cell value (0..=5)")]
    BadValue {
        /// The number.
        value: u8,
    },
    /// A map text is wrong at one place (1-based line and column, counted in characters of the
    /// line as written).
    #[error("line {line}, column {column}: {problem}")]
    Text {
        /// 1-based line number in the text.
        line: usize,
        /// 1-based column (characters) in that line.
        column: usize,
        /// What is wrong there.
        problem: TextProblem,
    },
}

/// What is wrong at one place of a map text ([`MapError::Text`]).
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum TextProblem {
    /// A character that is not a digit 0..=5 (nor a space, tab or comma).
    #[error("{found:?} is not a cell value (0..=5)")]
    BadChar {
        /// The offending character.
        found: char,
    },
    /// A row with a different number of cells from the first row; the column is that of the
    /// first extra cell, or just after the last one if the row is short.
    #[error("{got} cells on this row, expected {expected} as on the first row")]
    RaggedRow {
        /// Cells on that row.
        got: usize,
        /// Cells on the first row.
        expected: usize,
    },
    /// A second robot (5) or destination (4) cell.
    #[error("a second {what} cell")]
    Duplicate {
        /// "robot" or "destination".
        what: &'static str,
    },
}

impl MapError {
    /// A [`MapError::Text`].
    pub const fn text(line: usize, column: usize, problem: TextProblem) -> MapError {
        MapError::Text { line, column, problem }
    }
}

/// A `rows × cols` grid of cell values with the robot and destination markers.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Map {
    rows: usize,
    cols: usize,
    cells: Vec<CellValue>,
    robot: Option<(u8, u8)>,
    destination: Option<(u8, u8)>,
    /// Each blocked move once, the smaller cell first.
    blocked_moves: BTreeSet<((u8, u8), (u8, u8))>,
}

/// What [`Map::note_refused_forward`] or [`Map::note_way_not_clear`] concluded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refusal {
    /// The move is blocked and the cell keeps its value (it is known free, the robot stood
    /// there, or the way was not clear). `new` is false if the move was already known blocked.
    MoveBlocked {
        /// First time this move is blocked.
        new: bool,
    },
    /// The cell ahead was not known free: it is now an obstacle.
    Obstacle,
    /// Nothing written: the cell is off the map or the robot's own cell.
    Nothing,
}

impl Map {
    /// A map of `rows × cols` unknown cells; each side must be in `1..=256`.
    pub fn new(rows: usize, cols: usize) -> Result<Map, MapError> {
        if rows == 0 || cols == 0 || rows > MAX_SIDE || cols > MAX_SIDE {
            return Err(MapError::BadSize { rows, cols });
        }
        Ok(Map {
            rows,
            cols,
            cells: vec![CellValue::Unknown; rows * cols],
            robot: None,
            destination: None,
            blocked_moves: BTreeSet::new(),
        })
    }

    /// Number of rows (the `x` range).
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of columns (the `y` range).
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// True if `(x, y)` lies on the map.
    pub fn contains(&self, x: usize, y: usize) -> bool {
        x < self.rows && y < self.cols
    }

    /// The row-major index of `(x, y)`, `None` outside the map.
    pub fn index(&self, x: usize, y: usize) -> Option<usize> {
        self.contains(x, y).then_some(x * self.cols + y)
    }

    /// The value at `(x, y)`, `None` outside the map.
    pub fn get(&self, x: usize, y: usize) -> Option<CellValue> {
        self.index(x, y).map(|i| self.cells[i])
    }

    /// The value at `(x, y)` given as wire bytes, `None` outside the map.
    pub fn at(&self, cell: (u8, u8)) -> Option<CellValue> {
        self.get(usize::from(cell.0), usize::from(cell.1))
    }

    /// All cells in row-major order.
    pub fn cells(&self) -> &[CellValue] {
        &self.cells
    }

    /// The cells of row `x`, `None` outside the map.
    pub fn row(&self, x: usize) -> Option<&[CellValue]> {
        (x < self.rows).then(|| &self.cells[x * self.cols..(x + 1) * self.cols])
    }

    /// Every cell with its coordinates, in row-major order.
    pub fn iter(&self) -> impl Iterator<Item = ((u8, u8), CellValue)> + '_ {
        let cols = self.cols;
        // Both sides are at most 256, so the quotient and remainder fit a byte.
        self.cells.iter().enumerate().map(move |(i, v)| (((i / cols) as u8, (i % cols) as u8), *v))
    }

    /// How many cells hold `value`.
    pub fn count(&self, value: CellValue) -> usize {
        self.cells.iter().filter(|v| **v == value).count()
    }

    fn checked_index(&self, x: usize, y: usize) -> Result<usize, MapError> {
        self.index(x, y).ok_or(MapError::OutOfBounds { x, y, rows: self.rows, cols: self.cols })
    }

    /// Writes `value` at `(x, y)`, keeping the robot and destination markers consistent.
    ///
    /// Writing [`CellValue::Robot`] or [`CellValue::Destination`] moves that marker (the old
    /// cell becomes free); overwriting the marker's cell with anything else drops the marker.
    pub fn set(&mut self, x: usize, y: usize, value: CellValue) -> Result<(), MapError> {
        let i = self.checked_index(x, y)?;
        // In bounds, so both fit a byte.
        let here = (x as u8, y as u8);
        match value {
            CellValue::Robot => return self.set_robot(x, y),
            CellValue::Destination => return self.set_destination(x, y),
            _ => {}
        }
        if self.robot == Some(here) {
            self.robot = None;
        }
        if self.destination == Some(here) {
            self.destination = None;
        }
        self.cells[i] = value;
        Ok(())
    }

    /// Marks `(x, y)` as an obstacle (0).
    pub fn set_obstacle(&mut self, x: usize, y: usize) -> Result<(), MapError> {
        self.set(x, y, CellValue::Obstacle)
    }

    /// Marks `(x, y)` as free (1).
    pub fn set_free(&mut self, x: usize, y: usize) -> Result<(), MapError> {
        self.set(x, y, CellValue::Free)
    }

    /// Marks `(x, y)` as a waypoint (3).
    pub fn set_waypoint(&mut self, x: usize, y: usize) -> Result<(), MapError> {
        self.set(x, y, CellValue::Waypoint)
    }

    /// Moves the robot marker (5) to `(x, y)`; its previous cell becomes free (1).
    pub fn set_robot(&mut self, x: usize, y: usize) -> Result<(), MapError> {
        let i = self.checked_index(x, y)?;
        if let Some((ox, oy)) = self.robot.take() {
            let o = usize::from(ox) * self.cols + usize::from(oy);
            self.cells[o] = CellValue::Free;
        }
        if self.destination == Some((x as u8, y as u8)) {
            self.destination = None;
        }
        self.cells[i] = CellValue::Robot;
        self.robot = Some((x as u8, y as u8));
        Ok(())
    }

    /// The robot's cell, if one is marked.
    pub fn robot(&self) -> Option<(u8, u8)> {
        self.robot
    }

    /// Moves the destination marker (4) to `(x, y)`; its previous cell becomes free (1).
    pub fn set_destination(&mut self, x: usize, y: usize) -> Result<(), MapError> {
        let i = self.checked_index(x, y)?;
        if let Some((ox, oy)) = self.destination.take() {
            let o = usize::from(ox) * self.cols + usize::from(oy);
            self.cells[o] = CellValue::Free;
        }
        if self.robot == Some((x as u8, y as u8)) {
            self.robot = None;
        }
        self.cells[i] = CellValue::Destination;
        self.destination = Some((x as u8, y as u8));
        Ok(())
    }

    /// The destination's cell, if one is marked.
    pub fn destination(&self) -> Option<(u8, u8)> {
        self.destination
    }

    /// Turns every waypoint (3) and the destination (4) back into free cells (1).
    pub fn clear_trajectory(&mut self) {
        for v in &mut self.cells {
            if matches!(v, CellValue::Waypoint | CellValue::Destination) {
                *v = CellValue::Free;
            }
        }
        self.destination = None;
    }

    /// Sets every cell back to unknown (2), drops both markers and every blocked move (the RESET
    /// button).
    pub fn reset(&mut self) {
        self.cells.fill(CellValue::Unknown);
        self.robot = None;
        self.destination = None;
        self.blocked_moves.clear();
    }

    /// Records that the robot cannot drive between the 4-neighbours `a` and `b` (both ways).
    /// Returns whether it is new; an error if either cell is off the map or they are not
    /// neighbours. The cells keep their values.
    pub fn block_move(&mut self, a: (u8, u8), b: (u8, u8)) -> Result<bool, MapError> {
        for (x, y) in [a, b] {
            self.checked_index(usize::from(x), usize::from(y))?;
        }
        if Heading::between(a, b).is_none() {
            return Err(MapError::NotNeighbours { a, b });
        }
        Ok(self.blocked_moves.insert((a.min(b), a.max(b))))
    }

    /// True if the move between `a` and `b` was recorded blocked ([`Map::block_move`]).
    pub fn is_move_blocked(&self, a: (u8, u8), b: (u8, u8)) -> bool {
        self.blocked_moves.contains(&(a.min(b), a.max(b)))
    }

    /// Every blocked move, each once (the smaller cell first), in order.
    pub fn blocked_moves(&self) -> impl Iterator<Item = ((u8, u8), (u8, u8))> + '_ {
        self.blocked_moves.iter().copied()
    }

    /// Carto refused a FORWARD from `from` into its neighbour `ahead` (SET_OBSTACLE_POSITION).
    /// A cell the map knows free had the robot in it, so the robot fits there: what was met lies
    /// between the two cells, and the *move* is blocked. Any other cell becomes an obstacle: one
    /// refusal cannot tell a thin wall from a box. The robot's own cell and cells off the map
    /// are left alone.
    pub fn note_refused_forward(&mut self, from: (u8, u8), ahead: (u8, u8)) -> Refusal {
        let Some(value) = self.at(ahead) else {
            return Refusal::Nothing;
        };
        if ahead == from {
            return Refusal::Nothing;
        }
        if value.is_known_free()
            && let blocked @ Refusal::MoveBlocked { .. } = self.note_way_not_clear(from, ahead)
        {
            return blocked;
        }
        match self.set_obstacle(usize::from(ahead.0), usize::from(ahead.1)) {
            Ok(()) => Refusal::Obstacle,
            Err(_) => Refusal::Nothing,
        }
    }

    /// Carto refused a FORWARD from `from` into its neighbour `ahead` because the robot's way
    /// there is not clear of its width, with nothing placed in `ahead` itself
    /// ([`crate::cartography::MoveResult::WayNotClear`]). The move is blocked whatever the cell
    /// holds, and the cell keeps its value: an unknown cell may still be reached another way.
    /// The robot's own cell and cells off the map are left alone.
    pub fn note_way_not_clear(&mut self, from: (u8, u8), ahead: (u8, u8)) -> Refusal {
        if ahead == from {
            return Refusal::Nothing;
        }
        match self.block_move(from, ahead) {
            Ok(new) => Refusal::MoveBlocked { new },
            Err(_) => Refusal::Nothing,
        }
    }

    /// The map as text: one line per row, one digit (the cell's number) per cell.
    pub fn to_text(&self) -> String {
        let mut s = String::with_capacity(self.rows * (self.cols + 1));
        for x in 0..self.rows {
            for v in &self.cells[x * self.cols..(x + 1) * self.cols] {
                s.push(v.to_char());
            }
            s.push('\n');
        }
        s
    }

    /// Parses [`Map::to_text`]'s format: one line per row, one digit 0..=5 per cell. Blank
    /// lines and lines starting with `#` are skipped; spaces, tabs and commas between digits are
    /// ignored. Errors name the 1-based line and column ([`MapError::Text`]).
    pub fn parse(text: &str) -> Result<Map, MapError> {
        let mut rows: Vec<Vec<CellValue>> = Vec::new();
        let mut robot = None;
        let mut destination = None;
        let mut first_len = 0;
        for (n, line) in text.lines().enumerate() {
            let line_no = n + 1;
            let trimmed = line.trim();
            if trimmed.is_empty() || trimmed.starts_with('#') {
                continue;
            }
            let mut row = Vec::with_capacity(trimmed.len());
            let mut end_column = 1;
            for (i, ch) in line.chars().enumerate() {
                let column = i + 1;
                if matches!(ch, ' ' | '\t' | ',') {
                    continue;
                }
                let at = |problem| MapError::text(line_no, column, problem);
                let v = ch
                    .to_digit(10)
                    .and_then(|d| CellValue::from_u8(d as u8))
                    .ok_or_else(|| at(TextProblem::BadChar { found: ch }))?;
                if !rows.is_empty() && row.len() == first_len {
                    let got = line.chars().filter(|c| !matches!(c, ' ' | '\t' | ',')).count();
                    return Err(at(TextProblem::RaggedRow { got, expected: first_len }));
                }
                let here = (rows.len(), row.len());
                if v == CellValue::Robot && robot.replace(here).is_some() {
                    return Err(at(TextProblem::Duplicate { what: "robot" }));
                }
                if v == CellValue::Destination && destination.replace(here).is_some() {
                    return Err(at(TextProblem::Duplicate { what: "destination" }));
                }
                row.push(v);
                end_column = column + 1;
            }
            if rows.is_empty() {
                first_len = row.len();
            } else if row.len() != first_len {
                let problem = TextProblem::RaggedRow { got: row.len(), expected: first_len };
                return Err(MapError::text(line_no, end_column, problem));
            }
            rows.push(row);
        }
        let mut map = Map::new(rows.len(), first_len)?;
        for (x, row) in rows.into_iter().enumerate() {
            map.cells[x * first_len..(x + 1) * first_len].copy_from_slice(&row);
        }
        map.robot = robot.map(|(x, y)| (x as u8, y as u8));
        map.destination = destination.map(|(x, y)| (x as u8, y as u8));
        Ok(map)
    }
}

impl fmt::Display for Map {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.to_text())
    }
}

#[cfg(test)]
mod tests;
