//! Cartography: the design document's serpentine coverage with A* detours, sans-IO.
//!
//! Concept: the robot does not know the room. Every map cell is unknown (2) until the robot
//! stands in it (free, 1) or bumps into it (obstacle, 0). The route is a serpentine from the
//! top-left corner: row 0 left to right, row 1 right to left, and so on. The [`Cartographer`]
//! always aims at the *first cell of the route that is still unknown* and drives there one
//! command at a time ([`Cartographer::next_command`]); the caller executes the command and
//! reports what happened ([`Cartographer::on_result`]): a FORWARD either moved the robot (the
//! cell becomes free) or met an obstacle (the cell ahead becomes 0).
//!
//! Detours ("follow the obstacle's contour by the shortest way, preferring cells already mapped,
//! aiming at the next cell of the route"): when the target is not adjacent (or is, but no turn
//! towards it is left here), or the planned next cell turns out blocked, A* plans from the
//! robot's cell and heading to the target over known free cells (cost 1) **and unknown cells at
//! a higher cost** ([`DEFAULT_UNKNOWN_COST`]), with a cost for each quarter turn and without the
//! turns seen failing (`cartography/reach.rs`).
//! Unknown cells on the way are probed by driving into them, which maps them too; a bump
//! triggers a new plan. We chose one weighted search over "known cells first, then fall back"
//! because it gives the same path whenever a known detour is nearly as short, and explores
//! otherwise, with one search instead of two.
//!
//! Blocked moves: a FORWARD Carto refuses into a cell the robot has stood in does not make that
//! cell an obstacle (the robot stood there, so it fits). What was met lies between the two cells
//! (a thin wall on the cell line, a table leg on the corner, or an echo Carto keeps), so the
//! *move* is recorded blocked on the map, both ways ([`Map::note_refused_forward`]), and A* and
//! the unreachable flood go round it; other ways into the cell stay open. A blocked move is not
//! tried again until the map is reset: the sweep must end, and Carto would refuse it again for
//! the same echo. A FORWARD refused into a cell nobody has stood in makes the cell an obstacle
//! when Carto met something in it (a reading straight ahead, a contact): one refusal cannot tell
//! a thin wall from a box, so that cell is not entered from elsewhere either. When Carto says
//! only that the robot's way is not clear ([`MoveResult::WayNotClear`]), nothing says the cell
//! is occupied: the move is blocked, the cell stays unknown, and the sweep may reach it another
//! way ([`Map::note_way_not_clear`]); once every way in is blocked, the flood below ends it.
//!
//! Unreachable cells: if A* finds no path through free and unknown cells, the target cannot be
//! reached (every truly free cell is known free or unknown, so no real path exists). A flood from
//! the robot then marks *every* unknown cell it cannot reach as unreachable at once (a closed
//! pocket costs one flood, not one search per cell); they stay unknown (2) on the map.
//!
//! Turns not made: Carto answers a turn it refused or could not finish (jammed, turned back) with
//! MOVE_DONE alone, as a turn it made. The next FORWARD's reply shows the heading the robot really
//! has (a FORWARD refused twice after a turn, when the old heading faces the grid's edge, shows it
//! too),
//! and that turn from that cell and heading is remembered as failed: detours plan round it (the
//! robot drives on to a cell where it can turn), the cartographer turns the other way round
//! there, drives out straight ahead when no turn is left (at most
//! [`MAX_ESCAPES_PER_CELL`] times per cell), and otherwise gives the target up as unreachable, so
//! a robot that cannot turn ends the sweep instead of asking the same turn until the time limit.
//!
//! Invariants: [`Cartographer::next_command`] returns `None` (done) only when every map cell is
//! known, proven unreachable, or given up because no turn towards it is left (above); with every
//! turn made, every cell reachable from the start by moves not refused has been visited. It never
//! asks for a FORWARD into a cell the map shows as an obstacle or off the map, nor along a blocked
//! move, nor a turn it has seen fail from the same cell and heading. Each search, bump or failed
//! turn gains information, so the sweep always ends. The room's outer walls need not be known:
//! cells outside the room are met as obstacles like any other.
//!
//! ```
//! use cute::cartography::{Cartographer, MoveResult};
//! use cute::map::Map;
//! use robot_model::grid::{Heading, Move};
//! // A 1 x 3 corridor whose last cell is blocked.
//! let mut map = Map::new(1, 3).unwrap();
//! map.set_robot(0, 0).unwrap();
//! let mut carto = Cartographer::new(1, 3, (0, 0), Heading::East).unwrap();
//! assert_eq!(carto.next_command(&map), Some(Move::Forward));
//! carto.on_result(&mut map, MoveResult::Moved { x: 0, y: 1 });
//! assert_eq!(carto.next_command(&map), Some(Move::Forward));
//! carto.on_result(&mut map, MoveResult::Blocked { x: 0, y: 2 });
//! assert_eq!(carto.next_command(&map), None); // done
//! assert_eq!(map.to_text(), "150\n");
//! ```

use thiserror::Error;
use tracing::{debug, warn};

use crate::map::{CellValue, MAX_SIDE, Map, Refusal};
use robot_model::grid::{Heading, Move};

/// Cost of entering an unknown cell in a detour, against 1 for a known free cell.
pub const DEFAULT_UNKNOWN_COST: u8 = 2;

/// What happened to the last command, as Carto reported it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MoveResult {
    /// FORWARD succeeded: the robot is now in cell `(x, y)` (SET_ROBOT_POSITION).
    Moved {
        /// Row.
        x: u8,
        /// Column.
        y: u8,
    },
    /// FORWARD met an obstacle in cell `(x, y)`; the robot did not move (SET_OBSTACLE_POSITION).
    Blocked {
        /// Row.
        x: u8,
        /// Column.
        y: u8,
    },
    /// FORWARD refused because the robot's way into cell `(x, y)` is not clear of its width,
    /// with nothing placed in the cell itself; the robot did not move (SET_OBSTACLE_POSITION,
    /// then SET_ROBOT_POSITION with the robot's own cell: `protocol/README.md`).
    WayNotClear {
        /// Row.
        x: u8,
        /// Column.
        y: u8,
    },
    /// RIGHT or LEFT was executed (MOVE_DONE alone after a turn).
    Turned,
    /// Carto answered MOVE_DONE without doing anything (e.g. it had no pose yet).
    NotExecuted,
}

/// Why a cartographer could not be created.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum CartoError {
    /// A side is zero or above 256.
    #[error("area size {rows}x{cols} is outside 1..=256 per side")]
    BadSize {
        /// Rows.
        rows: usize,
        /// Columns.
        cols: usize,
    },
    /// The start cell lies outside the area.
    #[error("start ({x}, {y}) is outside the {rows}x{cols} area")]
    StartOutside {
        /// Row.
        x: u8,
        /// Column.
        y: u8,
        /// Rows.
        rows: usize,
        /// Columns.
        cols: usize,
    },
}

/// Counters kept by a [`Cartographer`], for reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CartoStats {
    /// Commands issued (FORWARD + turns); a command re-issued after `NotExecuted` counts again.
    pub commands: u64,
    /// FORWARDs issued.
    pub forwards: u64,
    /// RIGHTs and LEFTs issued.
    pub turns: u64,
    /// FORWARDs answered with an obstacle or a way not clear.
    pub bumps: u64,
    /// A* searches run for detours.
    pub searches: u64,
    /// Cells concluded unreachable.
    pub unreachable: usize,
    /// Replies that showed the robot facing another way than believed (a turn Carto refused or
    /// did not finish): the heading was taken from the reply.
    pub heading_resyncs: u64,
    /// Turns such a reply showed were not made, remembered so they are not asked again from the
    /// same cell and heading.
    pub turns_failed: u64,
    /// FORWARDs sent only because no turn towards the planned cell was left in the robot's cell.
    pub turn_escapes: u64,
    /// Moves remembered as blocked: a FORWARD refused into a cell the robot had stood in, or
    /// whose way was not clear.
    pub blocked_moves: u64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Known {
    Free,
    Unknown,
    Blocked,
}

/// The coverage state machine: call [`Cartographer::next_command`], execute, then
/// [`Cartographer::on_result`], until `next_command` returns `None`.
#[derive(Debug, Clone)]
pub struct Cartographer {
    rows: usize,
    cols: usize,
    pose: (u8, u8),
    heading: Heading,
    /// Index in the serpentine route; every cell before it is known or unreachable.
    cursor: usize,
    unreachable: Vec<bool>,
    target: Option<(u8, u8)>,
    /// Remaining cells of the current plan, next cell last.
    plan: Vec<(u8, u8)>,
    pending: Option<Move>,
    unknown_cost: u8,
    done: bool,
    stats: CartoStats,
    /// The turns taken as made since the last FORWARD's reply: (heading before, turn).
    unconfirmed_turns: Vec<(Heading, Move)>,
    /// Bare MOVE_DONEs to a FORWARD since the last reply or turn.
    refused_forwards: u8,
    /// Turns a reply showed were not made: (cell, heading before the turn, turn).
    failed_turns: Vec<((u8, u8), Heading, Move)>,
    /// FORWARDs sent from each cell because no turn was left there (`turn_escapes`), row-major.
    escapes: Vec<u8>,
}

/// A cell where no turn towards the plan is left lets the robot out straight ahead at most this
/// often; then the target is given up as unreachable (the robot would go back and forth).
pub const MAX_ESCAPES_PER_CELL: u8 = 2;

impl Cartographer {
    /// A cartographer for a `rows × cols` area, robot at `start` facing `heading`.
    pub fn new(
        rows: usize,
        cols: usize,
        start: (u8, u8),
        heading: Heading,
    ) -> Result<Cartographer, CartoError> {
        if rows == 0 || cols == 0 || rows > MAX_SIDE || cols > MAX_SIDE {
            return Err(CartoError::BadSize { rows, cols });
        }
        if usize::from(start.0) >= rows || usize::from(start.1) >= cols {
            return Err(CartoError::StartOutside { x: start.0, y: start.1, rows, cols });
        }
        Ok(Cartographer {
            rows,
            cols,
            pose: start,
            heading,
            cursor: 0,
            unreachable: vec![false; rows * cols],
            target: None,
            plan: Vec::new(),
            pending: None,
            unknown_cost: DEFAULT_UNKNOWN_COST,
            done: false,
            stats: CartoStats::default(),
            unconfirmed_turns: Vec::new(),
            refused_forwards: 0,
            failed_turns: Vec::new(),
            escapes: vec![0; rows * cols],
        })
    }

    /// Sets the cost of entering an unknown cell during detours (clamped to 1..=255).
    pub fn with_unknown_cost(mut self, cost: u8) -> Cartographer {
        self.unknown_cost = cost.max(1);
        self
    }

    /// The robot's cell as the cartographer believes it.
    pub fn pose(&self) -> (u8, u8) {
        self.pose
    }

    /// The robot's heading as the cartographer believes it.
    pub fn heading(&self) -> Heading {
        self.heading
    }

    /// The cell the sweep is heading for, if any.
    pub fn target(&self) -> Option<(u8, u8)> {
        self.target
    }

    /// The command sent and not yet answered, if any.
    pub fn pending(&self) -> Option<Move> {
        self.pending
    }

    /// True once every cell is known or proven unreachable.
    pub fn is_done(&self) -> bool {
        self.done
    }

    /// The counters so far.
    pub fn stats(&self) -> CartoStats {
        self.stats
    }

    /// True if `(x, y)` was concluded unreachable from the robot.
    pub fn is_unreachable(&self, x: u8, y: u8) -> bool {
        self.index((x, y)).is_some_and(|i| self.unreachable[i])
    }

    /// Every cell concluded unreachable, in row-major order.
    pub fn unreachable_cells(&self) -> Vec<(u8, u8)> {
        (0..self.rows * self.cols)
            .filter(|&i| self.unreachable[i])
            .map(|i| ((i / self.cols) as u8, (i % self.cols) as u8))
            .collect()
    }

    /// Forgets the unanswered command (after a STOP), so the next call plans afresh.
    pub fn cancel_pending(&mut self) {
        self.pending = None;
        self.plan.clear();
    }

    /// The `i`-th cell of the serpentine route.
    pub fn route_cell(&self, i: usize) -> Option<(u8, u8)> {
        if i >= self.rows * self.cols {
            return None;
        }
        let row = i / self.cols;
        let k = i % self.cols;
        let col = if row.is_multiple_of(2) { k } else { self.cols - 1 - k };
        Some((row as u8, col as u8))
    }

    fn index(&self, c: (u8, u8)) -> Option<usize> {
        let (x, y) = (usize::from(c.0), usize::from(c.1));
        (x < self.rows && y < self.cols).then_some(x * self.cols + y)
    }

    fn classify(&self, map: &Map, c: (u8, u8)) -> Known {
        if c == self.pose {
            return Known::Free;
        }
        match map.at(c) {
            None | Some(CellValue::Obstacle) => Known::Blocked,
            Some(CellValue::Unknown) => Known::Unknown,
            Some(_) => Known::Free,
        }
    }

    /// True if `to` is next to the robot, not known blocked, and the move there is not blocked.
    fn can_step(&self, map: &Map, to: (u8, u8)) -> bool {
        Heading::between(self.pose, to).is_some()
            && !map.is_move_blocked(self.pose, to)
            && self.classify(map, to) != Known::Blocked
    }

    fn is_open_target(&self, map: &Map, c: (u8, u8)) -> bool {
        self.classify(map, c) == Known::Unknown && self.index(c).is_some_and(|i| !self.unreachable[i])
    }

    /// The next command to execute, or `None` when the sweep is complete. Until
    /// [`Cartographer::on_result`] is called, it keeps returning the same command (re-send it
    /// after a reconnect).
    pub fn next_command(&mut self, map: &Map) -> Option<Move> {
        if let Some(c) = self.pending {
            return Some(c);
        }
        // Each pass either returns, or moves the cursor / marks cells unreachable: bounded.
        for _ in 0..(2 * self.rows * self.cols + 4) {
            let target = match self.target {
                Some(t) if self.is_open_target(map, t) => t,
                _ => {
                    self.plan.clear();
                    self.target = None;
                    while let Some(c) = self.route_cell(self.cursor) {
                        if self.is_open_target(map, c) {
                            self.target = Some(c);
                            break;
                        }
                        self.cursor += 1;
                    }
                    match self.target {
                        Some(t) => t,
                        None => {
                            self.done = true;
                            return None;
                        }
                    }
                }
            };
            let stale = match self.plan.last() {
                None => true,
                Some(&n) => !self.can_step(map, n),
            };
            if stale {
                self.plan.clear();
                let turnable =
                    Heading::between(self.pose, target).is_some_and(|h| self.turn_towards(h).is_some());
                if self.can_step(map, target) && turnable {
                    self.plan.push(target);
                } else if !self.plan_detour(map, target) {
                    self.mark_unreachable(map, target);
                    continue;
                }
            }
            let Some(&next) = self.plan.last() else {
                continue;
            };
            let Some(want) = Heading::between(self.pose, next) else {
                continue;
            };
            let cmd = match self.turn_towards(want) {
                Some(cmd) => cmd,
                None => match self.escape(map) {
                    Some(cmd) => cmd,
                    None => {
                        warn!(
                            cell = ?self.pose,
                            heading = %self.heading,
                            ?target,
                            "no turn left in this cell and no way out ahead: target given up"
                        );
                        self.give_up(target);
                        continue;
                    }
                },
            };
            self.pending = Some(cmd);
            self.stats.commands += 1;
            if cmd == Move::Forward {
                self.stats.forwards += 1;
            } else {
                self.stats.turns += 1;
            }
            return Some(cmd);
        }
        warn!("cartography made no progress; stopping the sweep");
        self.done = true;
        None
    }

    /// The first command that turns the robot from its heading to `want` (FORWARD when it faces
    /// it already): the shorter way round whose turns have not failed in this cell, RIGHT on a
    /// tie (as [`robot_model::grid::turns_between`]); `None` when a failed turn bars both ways.
    fn turn_towards(&self, want: Heading) -> Option<Move> {
        if self.heading == want {
            return Some(Move::Forward);
        }
        let turns_needed = |dir: Move| {
            let mut heading = self.heading;
            let mut n = 0;
            while heading != want {
                if self.turn_failed(self.pose, heading, dir) {
                    return None;
                }
                heading = heading.after(dir);
                n += 1;
            }
            Some(n)
        };
        match (turns_needed(Move::Right), turns_needed(Move::Left)) {
            (Some(r), Some(l)) if l < r => Some(Move::Left),
            (Some(_), _) => Some(Move::Right),
            (None, Some(_)) => Some(Move::Left),
            (None, None) => None,
        }
    }

    fn remember_failed_turn(&mut self, heading: Heading, turn: Move) {
        if !self.turn_failed(self.pose, heading, turn) {
            self.failed_turns.push((self.pose, heading, turn));
            self.stats.turns_failed += 1;
        }
    }

    fn turn_failed(&self, cell: (u8, u8), heading: Heading, turn: Move) -> bool {
        self.failed_turns.contains(&(cell, heading, turn))
    }

    /// No turn towards the plan is left here: FORWARD, if the cell ahead is not known blocked and
    /// this cell has not let the robot out too often already.
    fn escape(&mut self, map: &Map) -> Option<Move> {
        let i = self.index(self.pose)?;
        let ahead = self.heading.step(self.pose, self.rows, self.cols)?;
        if !self.can_step(map, ahead) || self.escapes[i] >= MAX_ESCAPES_PER_CELL {
            return None;
        }
        self.escapes[i] += 1;
        self.stats.turn_escapes += 1;
        self.plan.clear();
        debug!(cell = ?self.pose, heading = %self.heading, "no turn left here: out straight ahead");
        Some(Move::Forward)
    }

    /// A FORWARD's reply names the cell ahead of the robot as Carto knows it (the cell it moved
    /// into, or the blocked one). When that neighbour is not the one ahead in the believed heading,
    /// the robot faces another way — a turn Carto refused for safety (the link protocol has no
    /// "not turned" answer) or did not finish — and the reply is the better evidence: the heading
    /// follows it, so the next commands turn the robot the right way instead of repeating a
    /// FORWARD that meets the same obstacle for ever.
    fn follow_reply(&mut self, cell: (u8, u8)) {
        match Heading::between(self.pose, cell) {
            Some(faced) if faced != self.heading => {
                warn!(
                    believed = %self.heading,
                    faced = %faced,
                    "Carto's reply shows the robot facing another way (a turn not made); following it"
                );
                self.stats.heading_resyncs += 1;
                // Carto turns a failed turn back. Facing where the first of the turns started, all
                // of them failed (each turns 90°), so the first certainly did; any other heading
                // leaves open which one failed, and nothing is remembered.
                if let Some(&(before, turn)) = self.unconfirmed_turns.first()
                    && before == faced
                {
                    self.remember_failed_turn(before, turn);
                }
                self.heading = faced;
                self.plan.clear();
            }
            _ => {}
        }
    }

    /// Feeds back what the last command did, updating the map and the robot's pose.
    pub fn on_result(&mut self, map: &mut Map, result: MoveResult) {
        let cmd = self.pending.take();
        match result {
            MoveResult::Turned => match cmd {
                Some(c) if c.is_turn() => {
                    self.unconfirmed_turns.push((self.heading, c));
                    self.refused_forwards = 0;
                    self.heading = self.heading.after(c);
                }
                other => warn!(?other, "turn reported for a command that was not a turn"),
            },
            MoveResult::Moved { x, y } => {
                if !map.contains(usize::from(x), usize::from(y)) || self.index((x, y)).is_none() {
                    warn!(x, y, "robot reported outside the map; ignored");
                    self.plan.clear();
                    return;
                }
                self.follow_reply((x, y));
                self.unconfirmed_turns.clear();
                self.refused_forwards = 0;
                let (px, py) = (usize::from(self.pose.0), usize::from(self.pose.1));
                if map.at(self.pose).is_some_and(|v| !v.is_known_free()) {
                    let _ = map.set_free(px, py);
                }
                let _ = map.set_robot(usize::from(x), usize::from(y));
                if self.plan.last() == Some(&(x, y)) {
                    self.plan.pop();
                } else {
                    self.plan.clear();
                }
                self.pose = (x, y);
            }
            MoveResult::Blocked { x, y } | MoveResult::WayNotClear { x, y } => {
                self.stats.bumps += 1;
                self.follow_reply((x, y));
                self.unconfirmed_turns.clear();
                self.refused_forwards = 0;
                // Outside the map nothing is written, and needs not be: it is never planned.
                let refusal = if matches!(result, MoveResult::WayNotClear { .. }) {
                    map.note_way_not_clear(self.pose, (x, y))
                } else {
                    map.note_refused_forward(self.pose, (x, y))
                };
                if refusal == (Refusal::MoveBlocked { new: true }) {
                    self.stats.blocked_moves += 1;
                    debug!(from = ?self.pose, to = ?(x, y), "move blocked; the cell keeps its value");
                }
                self.plan.clear();
            }
            MoveResult::NotExecuted => {
                // Carto refuses a FORWARD off the grid, every time. Refused twice after turns
                // taken as made, where the heading before them faces the grid's edge, the likelier
                // story is that they were not made (a single refusal may be a reading that came
                // late).
                if cmd == Some(Move::Forward)
                    && let Some(&(before, turn)) = self.unconfirmed_turns.first()
                {
                    self.refused_forwards = self.refused_forwards.saturating_add(1);
                    if self.refused_forwards >= 2 && before.step(self.pose, self.rows, self.cols).is_none() {
                        warn!(%before, "FORWARD refused twice after a turn, facing the grid's edge: the turn was not made");
                        self.stats.heading_resyncs += 1;
                        self.remember_failed_turn(before, turn);
                        self.heading = before;
                        self.unconfirmed_turns.clear();
                        self.refused_forwards = 0;
                        self.plan.clear();
                    }
                }
            }
        }
    }
}

mod reach;
#[cfg(test)]
mod tests;
