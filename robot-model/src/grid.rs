//! The grid vocabulary Carto, Cute and the twin share: a cell, a heading, a move, the robot's
//! pose on the grid, and where the grid lies in the world.
//!
//! Conventions of the link protocol (`protocols.md` §1): a [`Cell`] is `(x, y)` = (row, column);
//! rows grow downward (SOUTH), columns rightward (EAST), one byte each. [`Heading`] and [`Move`]
//! carry the wire values of `protocol::link::Direction` (0 SOUTH, 1 NORTH, 2 WEST, 3 EAST) and
//! `protocol::link::Command` (0 FORWARD, 1 RIGHT, 2 LEFT). RIGHT turns clockwise on the map
//! (NORTH → EAST → SOUTH → WEST), LEFT counter-clockwise. The conversions to and from the wire
//! enums live here and nowhere else.
//!
//! Invariants: `h.right().left() == h`; [`turns_between`] returns at most two turns, and a 180°
//! turn is always `RIGHT, RIGHT`.
//!
//! ```
//! use robot_model::grid::{turns_between, GridPose, Heading, Move};
//! assert_eq!(Heading::East.right(), Heading::South);
//! assert_eq!(turns_between(Heading::East, Heading::West), &[Move::Right, Move::Right]);
//! assert_eq!(Heading::East.step((2, 3), 20, 20), Some((2, 4)));
//! assert_eq!(GridPose { x: 0, y: 0, heading: Heading::North }.ahead(), None);
//! assert_eq!("w".parse::<Heading>(), Ok(Heading::West));
//! ```

use core::fmt;
use core::str::FromStr;

use protocol::link;

/// A grid cell `(x, y)`: row (grows downward), column (grows rightward).
pub type Cell = (u8, u8);

/// Where the robot faces; values are the wire's `direction` byte. Serialised by name (`East`), as
/// in scenario files.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[repr(u8)]
pub enum Heading {
    /// +x (row + 1, down on screen); wire value 0.
    South = 0,
    /// −x (row − 1); wire value 1.
    North = 1,
    /// −y (column − 1); wire value 2.
    West = 2,
    /// +y (column + 1, right on screen); wire value 3.
    East = 3,
}

impl Heading {
    /// All four headings in wire order.
    pub const ALL: [Heading; 4] = [Heading::South, Heading::North, Heading::West, Heading::East];

    /// The wire value (0 S, 1 N, 2 W, 3 E).
    pub const fn as_u8(self) -> u8 {
        self as u8
    }

    /// The heading for a wire value, `None` above 3.
    pub const fn from_u8(v: u8) -> Option<Heading> {
        match v {
            0 => Some(Heading::South),
            1 => Some(Heading::North),
            2 => Some(Heading::West),
            3 => Some(Heading::East),
            _ => None,
        }
    }

    /// The heading after a RIGHT (90° clockwise): S→W, N→E, W→N, E→S.
    pub const fn right(self) -> Heading {
        match self {
            Heading::South => Heading::West,
            Heading::North => Heading::East,
            Heading::West => Heading::North,
            Heading::East => Heading::South,
        }
    }

    /// The heading after a LEFT (90° counter-clockwise): S→E, N→W, W→S, E→N.
    pub const fn left(self) -> Heading {
        match self {
            Heading::South => Heading::East,
            Heading::North => Heading::West,
            Heading::West => Heading::South,
            Heading::East => Heading::North,
        }
    }

    /// The opposite heading.
    pub const fn opposite(self) -> Heading {
        match self {
            Heading::South => Heading::North,
            Heading::North => Heading::South,
            Heading::West => Heading::East,
            Heading::East => Heading::West,
        }
    }

    /// The heading after executing `mv` (FORWARD keeps it).
    pub const fn after(self, mv: Move) -> Heading {
        match mv {
            Move::Forward => self,
            Move::Right => self.right(),
            Move::Left => self.left(),
        }
    }

    /// One step `(dx, dy)` in this heading: row delta, column delta.
    pub const fn delta(self) -> (i32, i32) {
        match self {
            Heading::South => (1, 0),
            Heading::North => (-1, 0),
            Heading::West => (0, -1),
            Heading::East => (0, 1),
        }
    }

    /// The world angle of this heading, radians counter-clockwise from +x (east; the map's top is
    /// north, +y).
    pub const fn world_angle(self) -> f32 {
        match self {
            Heading::East => 0.0,
            Heading::North => core::f32::consts::FRAC_PI_2,
            Heading::West => core::f32::consts::PI,
            Heading::South => -core::f32::consts::FRAC_PI_2,
        }
    }

    /// The heading that moves from `from` to the 4-adjacent cell `to`, `None` if not adjacent.
    pub fn between(from: Cell, to: Cell) -> Option<Heading> {
        let dx = i32::from(to.0) - i32::from(from.0);
        let dy = i32::from(to.1) - i32::from(from.1);
        match (dx, dy) {
            (1, 0) => Some(Heading::South),
            (-1, 0) => Some(Heading::North),
            (0, -1) => Some(Heading::West),
            (0, 1) => Some(Heading::East),
            _ => None,
        }
    }

    /// The cell one step ahead of `cell` on a `rows × cols` grid, `None` if it leaves the grid.
    pub fn step(self, cell: Cell, rows: usize, cols: usize) -> Option<Cell> {
        let (dx, dy) = self.delta();
        let x = i32::from(cell.0) + dx;
        let y = i32::from(cell.1) + dy;
        if x < 0 || y < 0 || x as usize >= rows || y as usize >= cols {
            return None;
        }
        Some((u8::try_from(x).ok()?, u8::try_from(y).ok()?))
    }
}

impl fmt::Display for Heading {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Heading::South => "SOUTH",
            Heading::North => "NORTH",
            Heading::West => "WEST",
            Heading::East => "EAST",
        })
    }
}

/// A heading name that is not one of north, south, east, west (or n, s, e, w).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown heading {0:?}: expected north, south, east or west (or n, s, e, w)")]
pub struct ParseHeadingError(pub String);

impl FromStr for Heading {
    type Err = ParseHeadingError;

    /// Parses a heading name in any case: `north`, `SOUTH`, `e`, `W`.
    fn from_str(s: &str) -> Result<Heading, ParseHeadingError> {
        match s.to_ascii_lowercase().as_str() {
            "north" | "n" => Ok(Heading::North),
            "south" | "s" => Ok(Heading::South),
            "east" | "e" => Ok(Heading::East),
            "west" | "w" => Ok(Heading::West),
            _ => Err(ParseHeadingError(s.to_owned())),
        }
    }
}

/// A move Cute asks of the robot; values are the wire's `command` byte (STOP is a separate
/// action, not a move).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum Move {
    /// Advance one cell; wire value 0.
    Forward = 0,
    /// Turn 90° clockwise on the spot; wire value 1.
    Right = 1,
    /// Turn 90° counter-clockwise on the spot; wire value 2.
    Left = 2,
}

impl Move {
    /// The wire value (0 FORWARD, 1 RIGHT, 2 LEFT).
    pub const fn as_u8(self) -> u8 {
        self as u8
    }

    /// The move for a wire value, `None` for STOP (3) and anything unknown.
    pub const fn from_u8(v: u8) -> Option<Move> {
        match v {
            0 => Some(Move::Forward),
            1 => Some(Move::Right),
            2 => Some(Move::Left),
            _ => None,
        }
    }

    /// True for RIGHT and LEFT.
    pub const fn is_turn(self) -> bool {
        !matches!(self, Move::Forward)
    }
}

impl fmt::Display for Move {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Move::Forward => "FORWARD",
            Move::Right => "RIGHT",
            Move::Left => "LEFT",
        })
    }
}

/// The turns that bring heading `from` to `to`: none, one RIGHT, one LEFT, or RIGHT RIGHT for 180°.
pub const fn turns_between(from: Heading, to: Heading) -> &'static [Move] {
    if from as u8 == to as u8 {
        &[]
    } else if from.right() as u8 == to as u8 {
        &[Move::Right]
    } else if from.left() as u8 == to as u8 {
        &[Move::Left]
    } else {
        &[Move::Right, Move::Right]
    }
}

/// The robot's cell and heading on the grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct GridPose {
    /// Row, growing downward.
    pub x: u8,
    /// Column, growing rightward.
    pub y: u8,
    /// Facing.
    pub heading: Heading,
}

impl GridPose {
    /// The pose's cell.
    pub const fn cell(&self) -> Cell {
        (self.x, self.y)
    }

    /// The cell one step ahead, `None` if it is off the 256 × 256 byte grid.
    pub fn ahead(&self) -> Option<Cell> {
        self.heading.step(self.cell(), 256, 256)
    }
}

impl fmt::Display for GridPose {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "({}, {}) facing {}", self.x, self.y, self.heading)
    }
}

// ---- the wire enums, converted in one place ----

impl From<Heading> for link::Direction {
    fn from(h: Heading) -> link::Direction {
        link::Direction::from(h.as_u8())
    }
}

impl TryFrom<link::Direction> for Heading {
    /// The raw byte of a direction that is not a heading.
    type Error = u8;

    fn try_from(d: link::Direction) -> Result<Heading, u8> {
        let v = u8::from(d);
        Heading::from_u8(v).ok_or(v)
    }
}

impl From<Move> for link::Command {
    fn from(m: Move) -> link::Command {
        link::Command::from(m.as_u8())
    }
}

impl TryFrom<link::Command> for Move {
    /// The raw byte of a command that is not a move (STOP, or unknown).
    type Error = u8;

    fn try_from(c: link::Command) -> Result<Move, u8> {
        let v = u8::from(c);
        Move::from_u8(v).ok_or(v)
    }
}

// ---- connectivity ----

/// Every cell of a `rows × cols` grid that moves connect to `start`, row-major (`start` itself
/// included when `open(start)`; all false otherwise). `open(cell)` says whether the robot may be
/// in a cell, `can_move(from, to)` whether it may go between two 4-neighbours (both open).
///
/// ```
/// use robot_model::grid::reachable;
/// // a 1 × 3 corridor with a wall between columns 1 and 2
/// let r = reachable(1, 3, (0, 0), |_| true, |a, b| !(a.1.max(b.1) == 2));
/// assert_eq!(r, vec![true, true, false]);
/// ```
pub fn reachable(
    rows: usize,
    cols: usize,
    start: (usize, usize),
    open: impl Fn((usize, usize)) -> bool,
    can_move: impl Fn((usize, usize), (usize, usize)) -> bool,
) -> Vec<bool> {
    let mut seen = vec![false; rows * cols];
    if start.0 >= rows || start.1 >= cols || !open(start) {
        return seen;
    }
    let mut queue = std::collections::VecDeque::from([start]);
    seen[start.0 * cols + start.1] = true;
    while let Some(cell) = queue.pop_front() {
        for h in Heading::ALL {
            let (dr, dc) = h.delta();
            let (Some(r), Some(c)) =
                (cell.0.checked_add_signed(dr as isize), cell.1.checked_add_signed(dc as isize))
            else {
                continue;
            };
            if r < rows && c < cols && !seen[r * cols + c] && open((r, c)) && can_move(cell, (r, c)) {
                seen[r * cols + c] = true;
                queue.push_back((r, c));
            }
        }
    }
    seen
}

// ---- where the grid lies in the world ----

/// Largest grid side: coordinates travel as one byte on the link protocol.
pub const MAX_CELLS: usize = 256;

/// Where the grid sits in the world (metres; x east, y north).
///
/// The grid covers a bounding box with whole cells; what is left over is split evenly as a margin
/// on each side. Row 0 is the top row (largest world `y`), column 0 the leftmost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridFrame {
    /// World x of the left edge of column 0.
    pub left: f32,
    /// World y of the top edge of row 0.
    pub top: f32,
    /// Cell side, metres.
    pub cell: f32,
    /// Number of rows.
    pub rows: usize,
    /// Number of columns.
    pub cols: usize,
}

impl GridFrame {
    /// The grid over the box `min`..`max` (world x, y) with cells of `cell` metres, at most
    /// [`MAX_CELLS`] a side.
    pub fn for_bounds(min: (f32, f32), max: (f32, f32), cell: f32) -> GridFrame {
        let width = (max.0 - min.0).max(0.0);
        let height = (max.1 - min.1).max(0.0);
        let cols = ((width / cell + 1e-4).floor() as usize).min(MAX_CELLS);
        let rows = ((height / cell + 1e-4).floor() as usize).min(MAX_CELLS);
        let margin_x = (width - cols as f32 * cell) * 0.5;
        let margin_y = (height - rows as f32 * cell) * 0.5;
        GridFrame { left: min.0 + margin_x, top: max.1 - margin_y, cell, rows, cols }
    }

    /// World coordinates of the centre of (row, col).
    pub fn cell_center(&self, row: usize, col: usize) -> (f32, f32) {
        (self.left + (col as f32 + 0.5) * self.cell, self.top - (row as f32 + 0.5) * self.cell)
    }

    /// The cell containing world point (x, y), if it is on the grid.
    pub fn cell_at(&self, x: f32, y: f32) -> Option<(usize, usize)> {
        let col = ((x - self.left) / self.cell).floor();
        let row = ((self.top - y) / self.cell).floor();
        if col < 0.0 || row < 0.0 {
            return None;
        }
        let (row, col) = (row as usize, col as usize);
        (row < self.rows && col < self.cols).then_some((row, col))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wire_values_round_trip_through_the_link_enums() {
        for h in Heading::ALL {
            assert_eq!(Heading::from_u8(h.as_u8()), Some(h));
            assert_eq!(Heading::try_from(link::Direction::from(h)), Ok(h));
        }
        assert_eq!(Heading::from_u8(4), None);
        assert_eq!(Heading::try_from(link::Direction::from(9)), Err(9));
        for m in [Move::Forward, Move::Right, Move::Left] {
            assert_eq!(Move::from_u8(m.as_u8()), Some(m));
            assert_eq!(Move::try_from(link::Command::from(m)), Ok(m));
        }
        assert_eq!(Move::try_from(link::Command::Stop), Err(3));
        assert_eq!(link::Direction::from(Heading::East), link::Direction::East);
        assert_eq!(link::Command::from(Move::Left), link::Command::Left);
    }

    #[test]
    fn turns_match_the_original_carto_table() {
        // RIGHT maps S->W, N->E, W->N, E->S. LEFT maps S->E, N->W, W->S, E->N (research §1.4).
        assert_eq!(Heading::South.right(), Heading::West);
        assert_eq!(Heading::North.right(), Heading::East);
        assert_eq!(Heading::West.right(), Heading::North);
        assert_eq!(Heading::East.right(), Heading::South);
        for h in Heading::ALL {
            assert_eq!(h.right().left(), h);
            assert_eq!(h.right().right(), h.opposite());
            assert_eq!(h.right().right().right().right(), h);
        }
    }

    #[test]
    fn turns_between_is_shortest_and_consistent() {
        for from in Heading::ALL {
            for to in Heading::ALL {
                let turns = turns_between(from, to);
                let end = turns.iter().fold(from, |h, m| h.after(*m));
                assert_eq!(end, to);
                assert!(turns.len() <= 2);
            }
        }
    }

    #[test]
    fn step_and_between_agree() {
        for h in Heading::ALL {
            if let Some(n) = h.step((5, 5), 10, 10) {
                assert_eq!(Heading::between((5, 5), n), Some(h));
            }
        }
        assert_eq!(Heading::South.step((9, 0), 10, 10), None);
        assert_eq!(Heading::East.step((0, 255), 256, 256), None);
        assert_eq!(Heading::between((1, 1), (2, 2)), None);
    }

    #[test]
    fn ahead_follows_the_link_convention_and_stops_at_the_byte_grid_edge() {
        let at = |heading| GridPose { x: 10, y: 20, heading }.ahead();
        assert_eq!(at(Heading::South), Some((11, 20)));
        assert_eq!(at(Heading::North), Some((9, 20)));
        assert_eq!(at(Heading::West), Some((10, 19)));
        assert_eq!(at(Heading::East), Some((10, 21)));
        assert_eq!(GridPose { x: 255, y: 0, heading: Heading::South }.ahead(), None);
        assert_eq!(GridPose { x: 0, y: 255, heading: Heading::East }.ahead(), None);
        assert_eq!(GridPose { x: 7, y: 0, heading: Heading::West }.ahead(), None);
    }

    #[test]
    fn headings_parse_in_any_case_and_print_as_the_protocol_names() {
        assert_eq!("NORTH".parse::<Heading>(), Ok(Heading::North));
        assert_eq!("s".parse::<Heading>(), Ok(Heading::South));
        assert!("up".parse::<Heading>().is_err());
        for h in Heading::ALL {
            assert_eq!(h.to_string().parse::<Heading>(), Ok(h));
        }
        assert_eq!(GridPose { x: 1, y: 2, heading: Heading::West }.to_string(), "(1, 2) facing WEST");
    }

    #[test]
    fn grid_frame_is_centred_with_whole_cells() {
        let f = GridFrame::for_bounds((0.0, 0.0), (1.3, 0.95), 0.3);
        assert_eq!((f.rows, f.cols), (3, 4));
        assert!((f.left - 0.05).abs() < 1e-5);
        assert!((f.top - 0.925).abs() < 1e-5);
        assert_eq!(f.cell_at(0.06, 0.9), Some((0, 0)));
        assert_eq!(f.cell_at(1.24, 0.03), Some((2, 3)));
        assert_eq!(f.cell_at(1.29, 0.5), None);
        let (x, y) = f.cell_center(2, 3);
        assert_eq!(f.cell_at(x, y), Some((2, 3)));
    }
}
