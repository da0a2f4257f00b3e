//! A grid-only stand-in for the robot: no physics, one cell per FORWARD.
//!
//! Concept: a [`World`] is the true room, a grid of free and blocked cells the robot cannot see.
//! A [`FakeRobot`] stands in it and executes [`Move`]s exactly as Carto reports them: a
//! FORWARD into a blocked cell or off the grid is [`MoveResult::Blocked`] with the cell ahead
//! (no motion), otherwise [`MoveResult::Moved`]; a turn is [`MoveResult::Turned`]. Tests use it to
//! drive the [`crate::cartography::Cartographer`] and to check coverage against
//! [`World::reachable_from`].
//!
//! Invariants: the robot never stands in a blocked cell; `moves` counts every command executed.
//!
//! ```
//! use cute::gridsim::{FakeRobot, World};
//! use cute::cartography::MoveResult;
//! use robot_model::grid::{Heading, Move};
//! let world = World::parse("..#\n...\n").unwrap();
//! let mut robot = FakeRobot::new(world, (0, 0), Heading::East);
//! assert_eq!(robot.execute(Move::Forward), MoveResult::Moved { x: 0, y: 1 });
//! assert_eq!(robot.execute(Move::Forward), MoveResult::Blocked { x: 0, y: 2 });
//! assert_eq!(robot.execute(Move::Right), MoveResult::Turned);
//! assert_eq!(robot.pose(), ((0, 1), Heading::South));
//! ```

use crate::cartography::MoveResult;
use crate::map::{MAX_SIDE, MapError, TextProblem};
use robot_model::grid::{Heading, Move};

/// The true room: `rows × cols` cells, each free or blocked.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct World {
    rows: usize,
    cols: usize,
    blocked: Vec<bool>,
}

impl World {
    /// Parses `.` (free) and `#` (blocked) lines; blank lines are skipped. Error columns count
    /// from the first non-blank character of the line.
    pub fn parse(text: &str) -> Result<World, MapError> {
        let mut blocked = Vec::new();
        let (mut rows, mut cols) = (0, 0);
        for (n, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() {
                continue;
            }
            let before = blocked.len();
            for (i, ch) in line.chars().enumerate() {
                match ch {
                    '.' => blocked.push(false),
                    '#' => blocked.push(true),
                    other => {
                        let problem = TextProblem::BadChar { found: other };
                        return Err(MapError::text(n + 1, i + 1, problem));
                    }
                }
            }
            let len = blocked.len() - before;
            if rows == 0 {
                cols = len;
            } else if len != cols {
                let problem = TextProblem::RaggedRow { got: len, expected: cols };
                return Err(MapError::text(n + 1, len.min(cols) + 1, problem));
            }
            rows += 1;
        }
        World::from_cells(rows, cols, blocked)
    }

    /// A world from row-major `blocked` flags.
    pub fn from_cells(rows: usize, cols: usize, blocked: Vec<bool>) -> Result<World, MapError> {
        if rows == 0 || cols == 0 || rows > MAX_SIDE || cols > MAX_SIDE || blocked.len() != rows * cols {
            return Err(MapError::BadSize { rows, cols });
        }
        Ok(World { rows, cols, blocked })
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of columns.
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// True if `(x, y)` is blocked or off the grid.
    pub fn is_blocked(&self, x: usize, y: usize) -> bool {
        x >= self.rows || y >= self.cols || self.blocked[x * self.cols + y]
    }

    /// Row-major flags: true for every free cell 4-connected to `start` (empty if `start` is blocked).
    pub fn reachable_from(&self, start: (u8, u8)) -> Vec<bool> {
        let start = (usize::from(start.0), usize::from(start.1));
        robot_model::grid::reachable(
            self.rows,
            self.cols,
            start,
            |(x, y)| !self.is_blocked(x, y),
            |_, _| true,
        )
    }
}

/// A robot on a [`World`] that executes commands one cell at a time.
#[derive(Debug, Clone)]
pub struct FakeRobot {
    world: World,
    pose: (u8, u8),
    heading: Heading,
    moves: u64,
}

impl FakeRobot {
    /// A robot at `pose` facing `heading` (the caller makes sure `pose` is free).
    pub fn new(world: World, pose: (u8, u8), heading: Heading) -> FakeRobot {
        FakeRobot { world, pose, heading, moves: 0 }
    }

    /// The true cell and heading.
    pub fn pose(&self) -> ((u8, u8), Heading) {
        (self.pose, self.heading)
    }

    /// Commands executed so far.
    pub fn moves(&self) -> u64 {
        self.moves
    }

    /// The world the robot drives in.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// Executes one command and reports it the way Carto would.
    pub fn execute(&mut self, command: Move) -> MoveResult {
        self.moves += 1;
        match command {
            Move::Forward => match self.heading.step(self.pose, self.world.rows, self.world.cols) {
                Some(n) if !self.world.is_blocked(usize::from(n.0), usize::from(n.1)) => {
                    self.pose = n;
                    MoveResult::Moved { x: n.0, y: n.1 }
                }
                Some(n) => MoveResult::Blocked { x: n.0, y: n.1 },
                None => {
                    // Off the grid: Carto reports the cell ahead, wrapped to a byte.
                    let (dx, dy) = self.heading.delta();
                    let x = (i32::from(self.pose.0) + dx) as u8;
                    let y = (i32::from(self.pose.1) + dy) as u8;
                    MoveResult::Blocked { x, y }
                }
            },
            turn => {
                self.heading = self.heading.after(turn);
                MoveResult::Turned
            }
        }
    }
}
