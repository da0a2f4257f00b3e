//! Headings and the three moves the robot knows, on the grid of the `link` protocol.
//!
//! Concept: the robot stands in one cell and faces one of four headings. `x` is the row (grows
//! downward), `y` the column (grows rightward). [`Heading`] uses the wire values of
//! `protocol::link::Direction` (0 SOUTH +row, 1 NORTH −row, 2 WEST −col, 3 EAST +col), and
//! [`Command`] those of `protocol::link::Command` (0 FORWARD, 1 RIGHT clockwise, 2 LEFT
//! counter-clockwise).
//!
//! Invariants: `h.right().left() == h`; [`turns_between`] returns at most two turns, and a 180°
//! turn is always `RIGHT, RIGHT` (the original planner's single-LEFT bug is fixed).
//!
//! ```
//! use cute::motion::{turns_between, Command, Heading};
//! assert_eq!(Heading::East.right(), Heading::South);
//! assert_eq!(turns_between(Heading::East, Heading::West), &[Command::Right, Command::Right]);
//! assert_eq!(Heading::East.step((2, 3), 20, 20), Some((2, 4)));
//! assert_eq!(Heading::North.step((0, 3), 20, 20), None);
//! ```

use core::fmt;

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

    /// The heading after executing `command` (FORWARD keeps it).
    pub const fn after(self, command: Command) -> Heading {
        match command {
            Command::Forward => self,
            Command::Right => self.right(),
            Command::Left => self.left(),
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

    /// The heading that moves from `from` to the 4-adjacent cell `to`, `None` if not adjacent.
    pub fn between(from: (u8, u8), to: (u8, u8)) -> Option<Heading> {
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
    pub fn step(self, cell: (u8, u8), rows: usize, cols: usize) -> Option<(u8, u8)> {
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

/// A move Cute asks of the robot; values are the wire's `command` byte (STOP is a separate action).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum Command {
    /// Advance one cell; wire value 0.
    Forward = 0,
    /// Turn 90° clockwise on the spot; wire value 1.
    Right = 1,
    /// Turn 90° counter-clockwise on the spot; wire value 2.
    Left = 2,
}

impl Command {
    /// The wire value (0 FORWARD, 1 RIGHT, 2 LEFT).
    pub const fn as_u8(self) -> u8 {
        self as u8
    }

    /// The command for a wire value, `None` for STOP (3) and anything unknown.
    pub const fn from_u8(v: u8) -> Option<Command> {
        match v {
            0 => Some(Command::Forward),
            1 => Some(Command::Right),
            2 => Some(Command::Left),
            _ => None,
        }
    }

    /// True for RIGHT and LEFT.
    pub const fn is_turn(self) -> bool {
        !matches!(self, Command::Forward)
    }
}

impl fmt::Display for Command {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Command::Forward => "FORWARD",
            Command::Right => "RIGHT",
            Command::Left => "LEFT",
        })
    }
}

/// The turns that bring heading `from` to `to`: none, one RIGHT, one LEFT, or RIGHT RIGHT for 180°.
pub const fn turns_between(from: Heading, to: Heading) -> &'static [Command] {
    if from as u8 == to as u8 {
        &[]
    } else if from.right() as u8 == to as u8 {
        &[Command::Right]
    } else if from.left() as u8 == to as u8 {
        &[Command::Left]
    } else {
        &[Command::Right, Command::Right]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wire_values_round_trip() {
        for h in Heading::ALL {
            assert_eq!(Heading::from_u8(h.as_u8()), Some(h));
        }
        assert_eq!(Heading::from_u8(4), None);
        for c in [Command::Forward, Command::Right, Command::Left] {
            assert_eq!(Command::from_u8(c.as_u8()), Some(c));
        }
        assert_eq!(Command::from_u8(3), None);
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
        }
    }

    #[test]
    fn turns_between_is_shortest_and_consistent() {
        for from in Heading::ALL {
            for to in Heading::ALL {
                let turns = turns_between(from, to);
                let end = turns.iter().fold(from, |h, c| h.after(*c));
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
}
