//! The robot's place on Cute's grid: a cell (`x` = row, `y` = column) and a heading.
//!
//! Conventions of the link protocol (`protocols.md` §1): `x` grows downward (SOUTH), `y` grows
//! rightward (EAST), one byte each. RIGHT turns clockwise on the map (NORTH → EAST → SOUTH →
//! WEST), LEFT counter-clockwise. [`GridPose::ahead`] is `None` when the cell ahead falls off the
//! 256 × 256 byte grid, so a FORWARD there cannot be executed.
//!
//! ```
//! use carto::pose::{GridPose, Heading};
//! let p = GridPose { x: 3, y: 4, heading: Heading::East };
//! assert_eq!(p.ahead(), Some((3, 5)));
//! assert_eq!(p.heading.turned_right(), Heading::South);
//! assert_eq!(GridPose { x: 0, y: 0, heading: Heading::North }.ahead(), None);
//! ```

use core::fmt;

/// One of the four grid headings, with the link protocol's numbering.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Heading {
    /// 0: +x, down the map.
    South,
    /// 1: −x, up the map.
    North,
    /// 2: −y, left on the map.
    West,
    /// 3: +y, right on the map.
    East,
}

impl Heading {
    /// The heading for a link protocol `direction` byte, `None` for values above 3.
    pub fn from_wire(raw: u8) -> Option<Heading> {
        match raw {
            0 => Some(Heading::South),
            1 => Some(Heading::North),
            2 => Some(Heading::West),
            3 => Some(Heading::East),
            _ => None,
        }
    }

    /// The link protocol `direction` byte.
    pub fn to_wire(self) -> u8 {
        match self {
            Heading::South => 0,
            Heading::North => 1,
            Heading::West => 2,
            Heading::East => 3,
        }
    }

    /// The heading after a 90° clockwise turn (RIGHT).
    pub fn turned_right(self) -> Heading {
        match self {
            Heading::North => Heading::East,
            Heading::East => Heading::South,
            Heading::South => Heading::West,
            Heading::West => Heading::North,
        }
    }

    /// The heading after a 90° counter-clockwise turn (LEFT).
    pub fn turned_left(self) -> Heading {
        match self {
            Heading::North => Heading::West,
            Heading::West => Heading::South,
            Heading::South => Heading::East,
            Heading::East => Heading::North,
        }
    }

    /// One step along this heading as (dx, dy).
    pub fn step(self) -> (i16, i16) {
        match self {
            Heading::South => (1, 0),
            Heading::North => (-1, 0),
            Heading::West => (0, -1),
            Heading::East => (0, 1),
        }
    }
}

impl fmt::Display for Heading {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = match self {
            Heading::South => "south",
            Heading::North => "north",
            Heading::West => "west",
            Heading::East => "east",
        };
        f.write_str(s)
    }
}

/// The robot's cell and heading as Cute knows them.
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
    /// The cell one step ahead, `None` if it is off the byte grid.
    pub fn ahead(&self) -> Option<(u8, u8)> {
        let (dx, dy) = self.heading.step();
        let x = u8::try_from(i16::from(self.x) + dx).ok()?;
        let y = u8::try_from(i16::from(self.y) + dy).ok()?;
        Some((x, y))
    }
}

impl fmt::Display for GridPose {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "({}, {}) facing {}", self.x, self.y, self.heading)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn right_then_left_is_identity_and_four_rights_are_a_full_turn() {
        for raw in 0..4 {
            let h = Heading::from_wire(raw).unwrap();
            assert_eq!(h.turned_right().turned_left(), h);
            assert_eq!(h.turned_right().turned_right().turned_right().turned_right(), h);
            assert_eq!(h.to_wire(), raw);
        }
        assert_eq!(Heading::from_wire(4), None);
    }

    #[test]
    fn ahead_follows_the_link_convention_and_stops_at_the_grid_edge() {
        let at = |heading| GridPose { x: 10, y: 20, heading }.ahead();
        assert_eq!(at(Heading::South), Some((11, 20)));
        assert_eq!(at(Heading::North), Some((9, 20)));
        assert_eq!(at(Heading::West), Some((10, 19)));
        assert_eq!(at(Heading::East), Some((10, 21)));
        assert_eq!(GridPose { x: 255, y: 0, heading: Heading::South }.ahead(), None);
        assert_eq!(GridPose { x: 0, y: 255, heading: Heading::East }.ahead(), None);
        assert_eq!(GridPose { x: 7, y: 0, heading: Heading::West }.ahead(), None);
    }
}
