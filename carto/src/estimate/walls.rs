//! Surfaces the sonar ranged straight ahead at rest: what the localiser
//! (`estimate/localiser.rs`) compares a later straight range with.
//!
//! Concept: a straight reading at rest says where a surface is along the grid heading, its
//! `depth` in metres along that heading in Carto's frame: the robot's believed position along the
//! heading, plus the sonar's mount offset, plus the range. The first reading of a surface is kept
//! as a [`Wall`], with the variance the position along the heading had then. A later reading
//! along the same heading, from the same row (facing east or west) or column (facing north or
//! south), is compared with the kept wall whose depth is nearest: the difference is how far the
//! belief moved from the truth since the wall was placed, and the localiser's filter weighs it
//! as a measurement relative to that earlier pose (its gate decides whether it is the same
//! surface).
//!
//! Why: a serpentine sweep faces the same walls from the same row or column again and again
//! (the wall it turns towards at every row end, every cell of a row on the second pass): against
//! a reading taken when the robot still knew where it was, those readings hold the position.
//!
//! Decisions:
//! - only echoes closer than `estimate::localiser::WALL_MAX_M` (1 m) are kept or matched: the cone
//!   is then no wider than the body, so the echo comes from what lies straight ahead. Far echoes
//!   come from whatever is nearest in a wide cone; matching them against near ones moved the
//!   robot by centimetres in furnished rooms;
//! - only the same row or column matches: with ±2 rows, faces of different furniture at similar
//!   depths were taken for one surface, and runs that passed failed;
//! - a wall keeps its first depth and variance: the earliest reading carries the least drift,
//!   and averaging later readings in would let the drift move the wall;
//! - walls live in the frame of the pose Cute sent: a different pose clears them
//!   ([`Walls::clear`]); a re-sent identical pose (a reconnect) keeps them;
//! - at most [`CAPACITY`] walls; the oldest is forgotten first.
//!
//! ```
//! use carto::walls::{lateral, Walls};
//! use robot_model::grid::{GridPose, Heading};
//! let mut walls = Walls::default();
//! // row 3, column 2, facing EAST: a surface 0.73 m along the heading, placed when the position
//! // was known to 1 cm
//! let here = GridPose { x: 3, y: 2, heading: Heading::East };
//! walls.remember(here.heading, lateral(here), 0.73, 0.01f64.powi(2));
//! // from the next cell of the same row, a reading places it at 0.715 m: 1.5 cm deeper than
//! // this reading says, so the robot is 1.5 cm farther along than it believes
//! let later = GridPose { x: 3, y: 3, heading: Heading::East };
//! let wall = walls.nearest(later.heading, lateral(later), 0.715).unwrap();
//! assert!((wall.depth_m - 0.715 - 0.015).abs() < 1e-9);
//! // another row has no wall
//! assert!(walls.nearest(Heading::East, 4, 0.715).is_none());
//! ```

use robot_model::grid::{GridPose, Heading};

/// Walls kept at most; the oldest is forgotten first (a 10 × 10 m room at 0.45 m cells has
/// 4 · 22 heading-and-row-or-column pairs, a few surfaces each).
pub const CAPACITY: usize = 512;

/// One surface seen straight ahead.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wall {
    /// The grid heading the robot faced.
    pub heading: Heading,
    /// The cell index across that heading (the row facing east or west, the column facing north
    /// or south).
    pub lateral: i32,
    /// Metres along the heading in Carto's frame (see the module docs).
    pub depth_m: f64,
    /// The variance of the robot's position along the heading when the wall was placed, m².
    pub placed_var_m2: f64,
}

/// The walls seen so far (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct Walls {
    walls: Vec<Wall>,
}

impl Walls {
    /// Forgets every wall (a new pose from Cute: a new frame).
    pub fn clear(&mut self) {
        self.walls.clear();
    }

    /// The walls kept, oldest first.
    pub fn iter(&self) -> impl Iterator<Item = &Wall> {
        self.walls.iter()
    }

    /// The kept wall facing `heading` from the row or column `lateral` whose depth is nearest
    /// `depth_m`; `None` without one.
    pub fn nearest(&self, heading: Heading, lateral: i32, depth_m: f64) -> Option<&Wall> {
        self.walls
            .iter()
            .filter(|w| w.heading == heading && w.lateral == lateral)
            .min_by(|a, b| (a.depth_m - depth_m).abs().total_cmp(&(b.depth_m - depth_m).abs()))
    }

    /// Keeps a surface at `depth_m` facing `heading` from `lateral`, placed from a position whose
    /// variance along the heading was `placed_var_m2`.
    pub fn remember(&mut self, heading: Heading, lateral: i32, depth_m: f64, placed_var_m2: f64) {
        if self.walls.len() >= CAPACITY {
            self.walls.remove(0);
        }
        self.walls.push(Wall { heading, lateral, depth_m, placed_var_m2 });
    }
}

/// The cell index across `pose`'s heading: the row facing east or west, the column facing north
/// or south (the `lateral` of a [`Wall`]).
pub fn lateral(pose: GridPose) -> i32 {
    let (row, col) = (i32::from(pose.x), i32::from(pose.y));
    match pose.heading {
        Heading::East | Heading::West => row,
        Heading::North | Heading::South => col,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(row: u8, col: u8, heading: Heading) -> GridPose {
        GridPose { x: row, y: col, heading }
    }

    #[test]
    fn the_lateral_index_is_the_row_across_east_and_west_and_the_column_across_north_and_south() {
        assert_eq!(lateral(at(5, 7, Heading::East)), 5);
        assert_eq!(lateral(at(5, 7, Heading::West)), 5);
        assert_eq!(lateral(at(5, 7, Heading::North)), 7);
        assert_eq!(lateral(at(5, 7, Heading::South)), 7);
    }

    #[test]
    fn only_the_same_heading_and_row_match_and_the_nearest_depth_wins() {
        let mut walls = Walls::default();
        walls.remember(Heading::East, 5, 1.00, 1e-4);
        walls.remember(Heading::East, 5, 1.04, 2e-4);
        walls.remember(Heading::West, 5, 1.00, 0.0);
        walls.remember(Heading::East, 6, 1.00, 0.0);
        let w = walls.nearest(Heading::East, 5, 1.015).copied();
        assert_eq!(w, Some(Wall { heading: Heading::East, lateral: 5, depth_m: 1.00, placed_var_m2: 1e-4 }));
        assert_eq!(walls.nearest(Heading::East, 5, 1.03).map(|w| w.depth_m), Some(1.04));
        assert!(walls.nearest(Heading::North, 5, 1.0).is_none());
        walls.clear();
        assert_eq!(walls.iter().count(), 0);
    }

    #[test]
    fn the_oldest_wall_goes_first_when_full() {
        let mut walls = Walls::default();
        for i in 0..=CAPACITY {
            walls.remember(Heading::East, 0, 1.0 + 0.1 * i as f64, 0.0);
        }
        assert_eq!(walls.iter().count(), CAPACITY);
        assert!(walls.iter().next().is_some_and(|w| (w.depth_m - 1.1).abs() < 1e-9));
    }
}
