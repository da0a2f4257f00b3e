//! The work Cute asked for: the task that runs, the tasks queued behind it, and the trajectory
//! batch still being received.
//!
//! Invariants: tasks run one at a time, in arrival order; a batch becomes a task only once it
//! holds `n_total` commands, and a frame with another `n_total` discards the partial one; a task
//! is never interrupted by a new request, only dropped ([`Tasks::clear`]).

use std::collections::VecDeque;

use robot_model::grid::Move;

/// Where a task came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum TaskKind {
    /// One `SEND_MOVE_CARTOGRAPHY`.
    Cartography,
    /// A complete `SEND_MOVES_TRAJECTORY` batch.
    Trajectory,
}

#[derive(Debug, Clone, PartialEq, Eq)]
struct Task {
    kind: TaskKind,
    commands: VecDeque<Result<Move, u8>>,
}

/// What one trajectory frame did to the batch ([`Tasks::add_frame`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Framed {
    /// A partial batch of another `n_total` was discarded: its `n_total` and length.
    pub(super) discarded: Option<(u8, usize)>,
    /// The batch is complete and queued as a task of this many commands.
    pub(super) completed: Option<u8>,
}

/// What to do next ([`Tasks::next`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Next {
    /// No task runs or waits.
    Idle,
    /// The running task has no command left: it ends.
    EndOfTask,
    /// The next command of the running task.
    Command(TaskKind, Result<Move, u8>),
}

/// The task queue and the partial batch.
#[derive(Debug, Clone, Default)]
pub(super) struct Tasks {
    batch: Option<(u8, Vec<Result<Move, u8>>)>,
    queue: VecDeque<Task>,
    current: Option<Task>,
}

impl Tasks {
    /// Queues a cartography move as a task of its own.
    pub(super) fn push_cartography(&mut self, command: Result<Move, u8>) {
        self.queue.push_back(Task { kind: TaskKind::Cartography, commands: VecDeque::from([command]) });
    }

    /// Adds one trajectory frame of a batch of `n_total` (not 0) to the partial batch.
    pub(super) fn add_frame(&mut self, n_total: u8, command: Result<Move, u8>) -> Framed {
        let mut discarded = None;
        let batch = match self.batch.take() {
            Some((n, mut cmds)) if n == n_total => {
                cmds.push(command);
                (n, cmds)
            }
            Some((n, cmds)) => {
                discarded = Some((n, cmds.len()));
                (n_total, vec![command])
            }
            None => (n_total, vec![command]),
        };
        let mut completed = None;
        if batch.1.len() >= usize::from(batch.0) {
            completed = Some(batch.0);
            self.queue.push_back(Task { kind: TaskKind::Trajectory, commands: batch.1.into() });
        } else {
            self.batch = Some(batch);
        }
        Framed { discarded, completed }
    }

    /// Takes the next command, starting the next queued task when none runs.
    pub(super) fn next(&mut self) -> Next {
        if self.current.is_none() {
            match self.queue.pop_front() {
                Some(t) => self.current = Some(t),
                None => return Next::Idle,
            }
        }
        let Some(task) = self.current.as_mut() else {
            return Next::Idle;
        };
        match task.commands.pop_front() {
            Some(command) => Next::Command(task.kind, command),
            None => Next::EndOfTask,
        }
    }

    /// Whether a task runs.
    pub(super) fn running(&self) -> bool {
        self.current.is_some()
    }

    /// Whether a task runs or waits in the queue.
    pub(super) fn any(&self) -> bool {
        self.current.is_some() || !self.queue.is_empty()
    }

    /// Whether the running task is a cartography move (a mapping task).
    pub(super) fn mapping(&self) -> bool {
        self.current.as_ref().is_some_and(|t| t.kind == TaskKind::Cartography)
    }

    /// Commands waiting: the rest of the running task, queued tasks and a partial batch.
    pub(super) fn pending(&self) -> usize {
        self.current.as_ref().map_or(0, |t| t.commands.len())
            + self.queue.iter().map(|t| t.commands.len()).sum::<usize>()
            + self.batch.as_ref().map_or(0, |(_, c)| c.len())
    }

    /// The running task ended (completed or aborted).
    pub(super) fn end_current(&mut self) {
        self.current = None;
    }

    /// Drops the running task, the queued ones and the partial batch.
    pub(super) fn clear(&mut self) {
        self.queue.clear();
        self.current = None;
        self.batch = None;
    }
}
