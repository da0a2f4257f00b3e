//! Surfaces the sonar ranged straight ahead at rest, remembered on the grid: what the localiser
//! (`estimate/localiser.rs`) compares a later straight range with.
//!
//! Concept: a straight reading at rest says where a surface is along the grid heading, `depth`
//! metres from the grid's origin: the robot's believed position along the heading, plus the
//! sonar's mount offset, plus the range. The first reading of a surface is kept as a [`Wall`]. A
//! later reading along the same heading, from the same row (facing east or west) or column
//! (facing north or south), is compared with the kept wall whose depth is nearest: the
//! difference is how far the dead reckoning drifted since the wall was first seen, and the
//! localiser's filter weighs it (its gate decides whether it is the same surface).
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
//! - a wall keeps its first depth: the earliest reading carries the least drift, and averaging
//!   later readings in would let the drift move the wall;
//! - a reading that matches no wall becomes a new wall;
//! - walls live in the grid of the pose Cute sent: a different pose clears them
//!   ([`Walls::clear`]); a re-sent identical pose (a reconnect) keeps them.
//!
//! ```
//! use carto::walls::Walls;
//! use robot_model::grid::{GridPose, Heading};
//! let mut walls = Walls::default();
//! let cell = 0.45;
//! // row 3, column 2, facing EAST: a wall 0.60 m ahead of the sonar (mounted 0.13 m ahead of
//! // the centre) is first seen: nothing to correct yet.
//! let here = GridPose { x: 3, y: 2, heading: Heading::East };
//! assert_eq!(walls.observe(here, cell, 0.0, 0.13 + 0.60), None);
//! // One cell on, the odometry says 1 cm past the centre of column 3 (0.14 m to go), and the
//! // same wall reads 0.125 m: the robot is really 1.5 cm farther along than it believes.
//! let later = GridPose { x: 3, y: 3, heading: Heading::East };
//! let fix = walls.observe(later, cell, 0.01, 0.13 + 0.125).unwrap();
//! assert!((fix - 0.015).abs() < 1e-9, "{fix}");
//! ```

use robot_model::grid::{GridPose, Heading};

/// A reading farther than this from every wall's depth is another surface, metres.
pub const MATCH_M: f64 = 0.03;
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
    /// Metres from the grid's origin along the heading (see the module docs).
    pub depth_m: f64,
}

/// The walls seen so far (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct Walls {
    walls: Vec<Wall>,
}

impl Walls {
    /// Forgets every wall (a new pose from Cute: a new grid).
    pub fn clear(&mut self) {
        self.walls.clear();
    }

    /// The walls kept, oldest first.
    pub fn iter(&self) -> impl Iterator<Item = &Wall> {
        self.walls.iter()
    }

    /// A straight reading at rest in cell `pose`, `along_m` past its centre by the odometry, the
    /// echo `ahead_m` from the robot's centre (mount plus range). Returns how much farther along
    /// the heading the robot really is than it believes, when the reading matches a kept wall;
    /// otherwise keeps the reading as a new wall and returns `None`.
    pub fn observe(&mut self, pose: GridPose, cell_m: f64, along_m: f64, ahead_m: f64) -> Option<f64> {
        let drift = self.drift(pose, cell_m, along_m, ahead_m);
        if drift.is_none() {
            self.remember(pose, cell_m, along_m, ahead_m);
        }
        drift
    }

    /// How much farther along the heading the robot really is than it believes, by the nearest
    /// kept wall within [`MATCH_M`] of this reading (see [`Walls::observe`]); `None` if none.
    pub fn drift(&self, pose: GridPose, cell_m: f64, along_m: f64, ahead_m: f64) -> Option<f64> {
        let (lateral, depth_m) = place(pose, cell_m, along_m, ahead_m);
        self.walls
            .iter()
            .filter(|w| w.heading == pose.heading && w.lateral == lateral)
            .map(|w| w.depth_m - depth_m)
            .filter(|gap| gap.abs() <= MATCH_M)
            .min_by(|a, b| a.abs().total_cmp(&b.abs()))
    }

    /// Keeps this reading as a new wall (see [`Walls::observe`]).
    pub fn remember(&mut self, pose: GridPose, cell_m: f64, along_m: f64, ahead_m: f64) {
        let (lateral, depth_m) = place(pose, cell_m, along_m, ahead_m);
        if self.walls.len() >= CAPACITY {
            self.walls.remove(0);
        }
        self.walls.push(Wall { heading: pose.heading, lateral, depth_m });
    }
}

/// The cell index across `pose`'s heading: the row facing east or west, the column facing north
/// or south (the `lateral` of a [`Wall`]).
pub fn lateral(pose: GridPose) -> i32 {
    cells(pose).1
}

impl Walls {
    /// The kept wall facing `heading` from the row or column `lateral` whose depth is nearest
    /// `depth_m`: how much deeper it lies, metres. `None` without one.
    pub fn nearest_gap(&self, heading: Heading, lateral: i32, depth_m: f64) -> Option<f64> {
        self.walls
            .iter()
            .filter(|w| w.heading == heading && w.lateral == lateral)
            .map(|w| w.depth_m - depth_m)
            .min_by(|a, b| a.abs().total_cmp(&b.abs()))
    }

    /// Keeps a surface at `depth_m` facing `heading` from `lateral` (see [`Walls::remember`]).
    pub fn remember_depth(&mut self, heading: Heading, lateral: i32, depth_m: f64) {
        if self.walls.len() >= CAPACITY {
            self.walls.remove(0);
        }
        self.walls.push(Wall { heading, lateral, depth_m });
    }
}

/// Where a reading puts its surface: the row or column across the heading, and the depth along
/// it (see the module docs).
fn place(pose: GridPose, cell_m: f64, along_m: f64, ahead_m: f64) -> (i32, f64) {
    let (along_cells, lateral) = cells(pose);
    (lateral, f64::from(along_cells) * cell_m + along_m + ahead_m)
}

/// The cell index along the pose's heading (growing in that direction) and across it.
fn cells(pose: GridPose) -> (i32, i32) {
    let (row, col) = (i32::from(pose.x), i32::from(pose.y));
    // rows grow southward, columns eastward (the frame of crate::surroundings)
    match pose.heading {
        Heading::East => (col, row),
        Heading::West => (-col, row),
        Heading::North => (-row, col),
        Heading::South => (row, col),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CELL: f64 = 0.45;

    fn at(row: u8, col: u8, heading: Heading) -> GridPose {
        GridPose { x: row, y: col, heading }
    }

    #[test]
    fn the_same_wall_from_every_heading_gives_the_drift() {
        // a wall 2 cells plus 0.30 m from the robot's start cell, in each direction
        for heading in [Heading::East, Heading::West, Heading::North, Heading::South] {
            let mut walls = Walls::default();
            assert_eq!(walls.observe(at(10, 10, heading), CELL, 0.0, 2.0 * CELL + 0.30), None);
            let ahead = match heading {
                Heading::East => at(10, 11, heading),
                Heading::West => at(10, 9, heading),
                Heading::North => at(9, 10, heading),
                Heading::South => at(11, 10, heading),
            };
            // one cell on, the robot believes it is at the centre but reads 2 cm less: it is
            // 2 cm farther along
            let fix = walls.observe(ahead, CELL, 0.0, CELL + 0.28).unwrap();
            assert!((fix - 0.02).abs() < 1e-9, "{heading:?}: {fix}");
        }
    }

    #[test]
    fn other_headings_other_rows_and_other_depths_are_other_walls() {
        let mut walls = Walls::default();
        assert_eq!(walls.observe(at(5, 5, Heading::East), CELL, 0.0, 0.5), None);
        // facing west, the same depth number is another surface
        assert_eq!(walls.observe(at(5, 5, Heading::West), CELL, 0.0, 0.5), None);
        // the next row
        assert_eq!(walls.observe(at(6, 5, Heading::East), CELL, 0.0, 0.5), None);
        // 4 cm off
        assert_eq!(walls.observe(at(5, 5, Heading::East), CELL, 0.0, 0.54), None);
        assert_eq!(walls.iter().count(), 4);
        // same row, 1.5 cm beyond the first and 2.5 cm short of the other: the nearer one
        let fix = walls.observe(at(5, 5, Heading::East), CELL, 0.0, 0.515).unwrap();
        assert!((fix + 0.015).abs() < 1e-9, "{fix}");
        let fix = walls.observe(at(5, 5, Heading::East), CELL, 0.0, 0.53).unwrap();
        assert!((fix - 0.01).abs() < 1e-9, "{fix}");
        assert_eq!(walls.iter().count(), 4, "a matched reading adds no wall");
        // facing north the lateral index is the column: another row, same column matches
        assert_eq!(walls.observe(at(5, 5, Heading::North), CELL, 0.0, 0.5), None);
        let fix = walls.observe(at(6, 5, Heading::North), CELL, 0.0, 0.5 + CELL + 0.01).unwrap();
        assert!((fix + 0.01).abs() < 1e-9, "{fix}");
    }

    #[test]
    fn a_wall_keeps_its_first_depth() {
        let mut walls = Walls::default();
        walls.observe(at(0, 0, Heading::East), CELL, 0.0, 1.0);
        for _ in 0..5 {
            let fix = walls.observe(at(0, 0, Heading::East), CELL, 0.0, 0.98).unwrap();
            assert!((fix - 0.02).abs() < 1e-9);
        }
        walls.clear();
        assert_eq!(walls.iter().count(), 0);
    }

    #[test]
    fn the_oldest_wall_goes_first_when_full() {
        let mut walls = Walls::default();
        for i in 0..=CAPACITY {
            walls.observe(at(0, 0, Heading::East), CELL, 0.0, 1.0 + 0.1 * i as f64);
        }
        assert_eq!(walls.iter().count(), CAPACITY);
        assert!((walls.iter().next().unwrap().depth_m - 1.1).abs() < 1e-9);
    }
}
