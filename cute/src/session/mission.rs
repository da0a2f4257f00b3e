//! The session's missions: [`Mapping`] (cartography, one move at a time) and [`Moving`] (a
//! trajectory, one batch at a time), each owning the move or batch it has in flight.
//!
//! Concept: the session asks its [`Mission`] what to send next ([`Mission::next`], only while the
//! link is ready) and hands it Carto's answers (`on_position`, `on_obstacle`, `on_move_done`) and
//! disconnects. Both work on the session's [`Belief`] (the map and the robot's cell and
//! heading) and return what the session must send or report; they never encode, count or queue
//! events themselves.
//!
//! - `Mapping`: a SET_ROBOT_POSITION / SET_OBSTACLE_POSITION before MOVE_DONE is the move's
//!   result; MOVE_DONE feeds it to the [`Cartographer`]. A bare MOVE_DONE after a FORWARD means
//!   Carto did not execute it: the move is re-sent, up to [`MAX_REJECTED`] times in a row. After a
//!   disconnect a result already reported is applied, an unanswered move re-sent.
//! - `Moving`: each SET_ROBOT_POSITION moves the robot one FORWARD along the batch; MOVE_DONE puts
//!   it at the batch's last cell; an obstacle aborts. After a disconnect the rest is re-planned
//!   from the last reported cell. With the original Carto ([`Compat::Explobot2024`]) every batch
//!   goes out at once and the session assumes the robot at the destination.
//!
//! Invariants: at most one move or batch is in flight; [`Mission::next`] returns
//! [`Next::Wait`] while one is.
//!
//! ```
//! use cute::session::{Cute, CuteConfig, Status};
//! use robot_model::grid::Heading;
//! use robot_model::time::Instant;
//! let mut cute = Cute::new(CuteConfig { rows: 1, cols: 2, heading: Heading::East,
//!     ..CuteConfig::default() }).unwrap();
//! cute.on_connected(Instant::ZERO);
//! cute.on_bytes(Instant::ZERO, &[0x00, 0x02, 0x08, 0x00]); // ROBOT_POSITION_RECEIVED
//! cute.start_cartography().unwrap();
//! cute.take_outgoing();                                     // FORWARD in flight
//! cute.on_bytes(Instant::from_millis(1), &[0x00, 0x04, 0x05, 0x00, 0, 1]); // SET_ROBOT_POSITION
//! cute.on_bytes(Instant::from_millis(2), &[0x00, 0x02, 0x03, 0x00]);       // MOVE_DONE
//! assert_eq!(cute.robot().1, 1);
//! assert_eq!(cute.status(), Status::Done); // both cells known
//! ```

use std::collections::VecDeque;

use robot_model::grid::{Cell, Heading, Move};
use robot_model::time::{Duration, Instant};
use tracing::warn;

use super::Compat;
use crate::cartography::{CartoStats, Cartographer, MoveResult};
use crate::map::Map;
use crate::trajectory::Planner;

/// Consecutive cartography moves answered by a bare MOVE_DONE before mapping gives up.
pub const MAX_REJECTED: u32 = 3;

/// A cell and a heading.
type Pose = (Cell, Heading);

/// What the session believes: the map and the robot's cell and heading on it.
#[derive(Debug, Clone)]
pub(crate) struct Belief {
    pub(crate) map: Map,
    pub(crate) robot: Cell,
    pub(crate) heading: Heading,
}

impl Belief {
    /// Moves the robot marker to `cell` if it is on the map.
    pub(crate) fn set_robot(&mut self, cell: Cell) {
        if self.map.set_robot(usize::from(cell.0), usize::from(cell.1)).is_ok() {
            self.robot = cell;
        }
    }

    /// Marks `(x, y)` as an obstacle, unless the robot stands there. Used outside mapping (a
    /// trajectory, an unsolicited report), where the map may be older than the room: a box put
    /// down since is the likelier story than a thin wall, so the cell is marked even if the robot
    /// once stood there. Mapping blocks the move instead ([`Map::note_refused_forward`]).
    pub(crate) fn mark_obstacle(&mut self, x: u8, y: u8) {
        if (x, y) != self.robot {
            let _ = self.map.set_obstacle(usize::from(x), usize::from(y));
        }
    }

    /// Moves the robot to where `commands` take it, with no feedback (the original Carto's
    /// silent trajectories).
    pub(crate) fn assume_driven(&mut self, commands: &[Move]) {
        let (_, (cell, heading)) =
            simulate((self.robot, self.heading), commands, self.map.rows(), self.map.cols());
        self.set_robot(cell);
        self.heading = heading;
    }

    /// A fresh cartographer from the robot's pose.
    fn cartographer(&self) -> Option<Cartographer> {
        Cartographer::new(self.map.rows(), self.map.cols(), self.robot, self.heading).ok()
    }
}

/// What the session should do next for its mission.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Next {
    /// Nothing to send: no mission, or an answer is awaited.
    Wait,
    /// Send this cartography move.
    Cartography(Move),
    /// Send this trajectory batch (one frame per command).
    Batch(Vec<Move>),
    /// Send every batch now (the robot is not moved yet). The mission is over.
    FireAndForget(Vec<Vec<Move>>),
    /// Cartography is complete. The mission is over.
    Mapped(CartoStats),
    /// The robot is at the destination. The mission is over.
    Arrived,
    /// The rest of the trajectory could not be planned to this cell. The mission is over.
    NoPath(Cell),
}

/// How a SET_OBSTACLE_POSITION fitted the mission.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Obstacle {
    /// It is the result of the move in flight.
    Recorded,
    /// The trajectory met it: marked on the map; the mission is over.
    Aborted,
    /// Nothing asked for it.
    Unsolicited,
}

/// How a MOVE_DONE fitted the mission.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Answer {
    /// It ended the move or batch in flight.
    Applied,
    /// Carto refused this cartography move [`MAX_REJECTED`] times; the mission is over.
    Rejected(Move),
    /// Nothing was in flight.
    Unsolicited,
}

/// The running mission, if any.
#[derive(Debug, Clone)]
pub(crate) enum Mission {
    None,
    Mapping(Mapping),
    Moving(Moving),
}

impl Mission {
    /// What to send or report now, the link being ready at `now`.
    pub(crate) fn next(
        &mut self,
        belief: &mut Belief,
        planner: &mut Planner,
        now: Instant,
        timeout: Duration,
    ) -> Next {
        match self {
            Mission::None => Next::Wait,
            Mission::Mapping(m) => m.next(&belief.map, now + timeout),
            Mission::Moving(m) => m.next(belief, planner, now, timeout),
        }
    }

    /// Headings the cartographer took from Carto's replies so far (0 outside cartography).
    pub(crate) fn heading_resyncs(&self) -> u64 {
        match self {
            Mission::Mapping(m) => m.carto.stats().heading_resyncs,
            _ => 0,
        }
    }

    /// The deadline of the move or batch in flight.
    pub(crate) fn deadline(&self) -> Option<Instant> {
        match self {
            Mission::Mapping(Mapping { flight: Some(f), .. }) => Some(f.deadline),
            Mission::Moving(Moving { flight: Some(f), .. }) => Some(f.deadline),
            _ => None,
        }
    }

    /// SET_ROBOT_POSITION `(x, y)` (on the map). Returns false if nothing was in flight.
    pub(crate) fn on_position(&mut self, belief: &mut Belief, x: u8, y: u8) -> bool {
        match self {
            Mission::Mapping(Mapping { flight: Some(f), .. }) => {
                f.result = Some(MoveResult::Moved { x, y });
                true
            }
            Mission::Moving(Moving { flight: Some(b), .. }) => {
                if let Some(&(_, h)) = b.steps.get(b.seen) {
                    belief.heading = h;
                }
                b.seen += 1;
                belief.set_robot((x, y));
                true
            }
            _ => false,
        }
    }

    /// SET_ROBOT_POSITION with the robot's own cell right after SET_OBSTACLE_POSITION `at`:
    /// Carto refused the FORWARD because the way into `at` is not clear, and nothing says `at`
    /// is occupied (`protocol/README.md`). True if it is the answer of the cartography move in
    /// flight (applied at MOVE_DONE); false otherwise (a trajectory already ended on it).
    pub(crate) fn on_way_not_clear(&mut self, at: (u8, u8)) -> bool {
        match self {
            Mission::Mapping(Mapping { flight: Some(f), .. })
                if f.result == Some(MoveResult::Blocked { x: at.0, y: at.1 }) =>
            {
                f.result = Some(MoveResult::WayNotClear { x: at.0, y: at.1 });
                true
            }
            _ => false,
        }
    }

    /// SET_OBSTACLE_POSITION `(x, y)`.
    pub(crate) fn on_obstacle(&mut self, belief: &mut Belief, x: u8, y: u8) -> Obstacle {
        match self {
            Mission::Mapping(Mapping { flight: Some(f), .. }) => {
                f.result = Some(MoveResult::Blocked { x, y });
                Obstacle::Recorded
            }
            Mission::Moving(_) => {
                if let Some(h) = Heading::between(belief.robot, (x, y)) {
                    belief.heading = h;
                }
                belief.map.clear_trajectory();
                belief.mark_obstacle(x, y);
                Obstacle::Aborted
            }
            _ => Obstacle::Unsolicited,
        }
    }

    /// MOVE_DONE.
    pub(crate) fn on_move_done(&mut self, belief: &mut Belief) -> Answer {
        match self {
            Mission::Mapping(m) => m.on_move_done(belief),
            Mission::Moving(m) => m.on_move_done(belief),
            Mission::None => Answer::Unsolicited,
        }
    }

    /// The link dropped: keep what happened, prepare to resume.
    pub(crate) fn on_disconnected(&mut self, belief: &mut Belief) {
        match self {
            Mission::Mapping(m) => {
                // A result already reported did happen; otherwise the move is re-sent later.
                if let Some(f) = m.flight.take()
                    && let Some(result) = f.result
                {
                    m.apply(belief, f.command, result);
                }
            }
            Mission::Moving(m) => {
                if m.flight.take().is_some() || !m.batches.is_empty() {
                    m.batches.clear();
                    m.replan = true;
                }
            }
            Mission::None => {}
        }
    }
}

#[derive(Debug, Clone)]
struct CartoFlight {
    command: Move,
    deadline: Instant,
    result: Option<MoveResult>,
}

/// Cartography: the cartographer, the move in flight and its result so far.
#[derive(Debug, Clone)]
pub(crate) struct Mapping {
    carto: Box<Cartographer>,
    flight: Option<CartoFlight>,
    /// Consecutive bare MOVE_DONEs after a FORWARD.
    rejected: u32,
}

impl Mapping {
    /// Cartography driven by `carto`.
    pub(crate) fn new(carto: Cartographer) -> Mapping {
        Mapping { carto: Box::new(carto), flight: None, rejected: 0 }
    }

    /// The cartographer.
    pub(crate) fn cartographer(&self) -> &Cartographer {
        &self.carto
    }

    /// Starts over from the robot's pose after a map reset; a move in flight is applied to the
    /// pose when it is answered, then yet another fresh cartographer starts from there.
    pub(crate) fn restart(&mut self, belief: &Belief) {
        if let Some(fresh) = belief.cartographer() {
            *self.carto = fresh;
        }
    }

    fn next(&mut self, map: &Map, deadline: Instant) -> Next {
        if self.flight.is_some() {
            return Next::Wait;
        }
        match self.carto.next_command(map) {
            Some(command) => {
                self.flight = Some(CartoFlight { command, deadline, result: None });
                Next::Cartography(command)
            }
            None => Next::Mapped(self.carto.stats()),
        }
    }

    fn on_move_done(&mut self, belief: &mut Belief) -> Answer {
        let Some(f) = self.flight.take() else {
            return Answer::Unsolicited;
        };
        let result = f.result.unwrap_or(if f.command.is_turn() {
            MoveResult::Turned
        } else {
            MoveResult::NotExecuted
        });
        if result == MoveResult::NotExecuted {
            self.rejected += 1;
            if self.rejected >= MAX_REJECTED {
                warn!(command = %f.command, "Carto keeps refusing the move; mapping stopped");
                self.carto.cancel_pending();
                return Answer::Rejected(f.command);
            }
        } else {
            self.rejected = 0;
        }
        self.apply(belief, f.command, result);
        Answer::Applied
    }

    /// Feeds a move's result to the cartographer and mirrors the pose.
    fn apply(&mut self, belief: &mut Belief, command: Move, result: MoveResult) {
        if self.carto.pending() == Some(command) {
            self.carto.on_result(&mut belief.map, result);
            belief.robot = self.carto.pose();
            belief.heading = self.carto.heading();
            return;
        }
        // The cartographer was replaced (map reset) while the move was in flight.
        match result {
            MoveResult::Moved { x, y } => belief.set_robot((x, y)),
            MoveResult::Turned => belief.heading = belief.heading.after(command),
            MoveResult::Blocked { x, y } => belief.mark_obstacle(x, y),
            MoveResult::WayNotClear { x, y } => {
                let _ = belief.map.note_way_not_clear(belief.robot, (x, y));
            }
            MoveResult::NotExecuted => {}
        }
        self.carto.cancel_pending();
        if let Some(fresh) = belief.cartographer() {
            *self.carto = fresh;
        }
    }
}

#[derive(Debug, Clone)]
struct BatchFlight {
    /// `(cell, heading)` after each FORWARD of the batch, in order.
    steps: Vec<Pose>,
    /// The heading after the whole batch.
    end_heading: Heading,
    /// SET_ROBOT_POSITION frames received for this batch.
    seen: usize,
    deadline: Instant,
}

/// A trajectory: the destination, the batches still to send and the batch in flight.
#[derive(Debug, Clone)]
pub(crate) struct Moving {
    dest: Cell,
    compat: Compat,
    batches: VecDeque<Vec<Move>>,
    flight: Option<BatchFlight>,
    /// Plan again from the robot's cell before the next batch (after a disconnect).
    replan: bool,
}

impl Moving {
    /// Drives `commands` to `dest`, in batches `compat` accepts.
    pub(crate) fn new(dest: Cell, commands: &[Move], compat: Compat) -> Moving {
        Moving { dest, compat, batches: batches(commands, compat), flight: None, replan: false }
    }

    fn next(&mut self, belief: &mut Belief, planner: &mut Planner, now: Instant, timeout: Duration) -> Next {
        if self.flight.is_some() {
            return Next::Wait;
        }
        if self.replan {
            self.replan = false;
            match planner.plan_on_map(&mut belief.map, belief.robot, belief.heading, self.dest) {
                Ok(t) if t.commands.is_empty() => {}
                Ok(t) => self.batches = batches(&t.commands, self.compat),
                Err(e) => {
                    warn!(error = %e, "cannot resume the trajectory");
                    return Next::NoPath(self.dest);
                }
            }
        }
        if self.compat == Compat::Explobot2024 {
            // Fire and forget: the original Carto never answers a trajectory. The session moves
            // the belief ([`Belief::assume_driven`]) unless the original drops the batch.
            return Next::FireAndForget(self.batches.drain(..).collect());
        }
        let Some(batch) = self.batches.pop_front() else {
            return Next::Arrived;
        };
        let (steps, end) =
            simulate((belief.robot, belief.heading), &batch, belief.map.rows(), belief.map.cols());
        let deadline = now + Duration::from_micros(timeout.total_micros().saturating_mul(batch.len() as u64));
        self.flight = Some(BatchFlight { steps, end_heading: end.1, seen: 0, deadline });
        Next::Batch(batch)
    }

    fn on_move_done(&mut self, belief: &mut Belief) -> Answer {
        let Some(b) = self.flight.take() else {
            return Answer::Unsolicited;
        };
        // MOVE_DONE ends the batch: the robot is at its last cell (also when Carto sent no
        // positions, like the original).
        if let Some(&(cell, _)) = b.steps.last() {
            belief.set_robot(cell);
        }
        belief.heading = b.end_heading;
        Answer::Applied
    }
}

fn batches(commands: &[Move], compat: Compat) -> VecDeque<Vec<Move>> {
    commands.chunks(compat.max_batch()).map(<[Move]>::to_vec).collect()
}

/// The `(cell, heading)` after each FORWARD of `commands`, and the final pose.
fn simulate(start: Pose, commands: &[Move], rows: usize, cols: usize) -> (Vec<Pose>, Pose) {
    let (mut cell, mut h) = start;
    let mut steps = Vec::new();
    for &c in commands {
        if c == Move::Forward {
            cell = h.step(cell, rows, cols).unwrap_or(cell);
            steps.push((cell, h));
        } else {
            h = h.after(c);
        }
    }
    (steps, (cell, h))
}

#[cfg(test)]
mod tests;
