//! Watching a run step by step: a [`StepObserver`] set on a [`Lockstep`] is called around every
//! step, whoever drives the run (the headless app, the window, a sweep worker).
//!
//! Invariant: an observer only reads the run. It cannot change a byte, a decision or a random
//! draw, so a run with an observer takes exactly the steps of a run without one (same link-log
//! hash); the MCAP test and the determinism test check it.
//!
//! ```
//! use twin::runner::{Endpoint, Lockstep, StepObserver};
//! use transport::TraceRecord;
//!
//! /// Counts the bytes Carto wrote to the motor board.
//! struct Count(u64);
//! impl StepObserver for Count {
//!     fn after_step(&mut self, run: &Lockstep) {
//!         run.step_records(|at: Endpoint<'_>, r: &TraceRecord| {
//!             if at.link == "motor" && at.endpoint == "carto" && r.direction == transport::Direction::Written {
//!                 self.0 += r.bytes.len() as u64;
//!             }
//!         });
//!     }
//! }
//! let mut run = Lockstep::new(twin::setup::RunSetup::builtin_default()?, None)?;
//! run.set_observer(Box::new(Count(0)));
//! for _ in 0..400 {
//!     run.step();
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::fmt;

use transport::TraceRecord;

use super::Lockstep;

/// Called around every step of a [`Lockstep`] (see the module docs of `runner/observe.rs`).
pub trait StepObserver: Send + Sync {
    /// At the start of a step, once the clock has moved and before anything else.
    fn before_step(&mut self) {}

    /// At the end of a step: everything has moved, and the step's byte records are still
    /// readable with [`Lockstep::step_records`].
    fn after_step(&mut self, run: &Lockstep);
}

/// One traced end of a link: `motor` at `carto`, `gui` at Cute's connection 2 (`cute#2`), …
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Endpoint<'a> {
    /// `motor`, `sensor` or `gui`.
    pub link: &'a str,
    /// `carto`, `board` or `cute`.
    pub endpoint: &'a str,
    /// Cute's connection number (1, 2, … after reconnects); `None` for the board links.
    pub connection: Option<usize>,
}

impl fmt::Display for Endpoint<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.connection {
            Some(n) => write!(f, "{}@{}#{n}", self.link, self.endpoint),
            None => write!(f, "{}@{}", self.link, self.endpoint),
        }
    }
}

impl Lockstep {
    /// Sets who watches every step from now on (replacing any earlier observer).
    pub fn set_observer(&mut self, observer: Box<dyn StepObserver>) {
        self.observer = Some(observer);
    }

    /// Takes the observer off the run (e.g. to move it to a restarted run).
    pub fn take_observer(&mut self) -> Option<Box<dyn StepObserver>> {
        self.observer.take()
    }

    /// Calls `f` with every byte record of the current step (time [`Lockstep::now`]), endpoint by
    /// endpoint in a fixed order: the board links (`motor@carto`, `motor@board`, `sensor@carto`,
    /// `sensor@board`), then Cute's connections in order. Complete only while the step is being
    /// observed ([`StepObserver::after_step`]): the records then move into the link logs.
    pub fn step_records(&self, mut f: impl FnMut(Endpoint<'_>, &TraceRecord)) {
        let now = self.now;
        let mut visit = |at: Endpoint<'_>, records: &[TraceRecord]| {
            let first = records.iter().rposition(|r| r.at != now).map_or(0, |i| i + 1);
            for r in &records[first..] {
                f(at, r);
            }
        };
        for (link, endpoint, handle) in &self.traces {
            let at = Endpoint { link, endpoint, connection: None };
            handle.peek(|records| visit(at, records));
        }
        for (i, handle) in self.cute.wrapper().traces.iter().enumerate() {
            let at = Endpoint { link: "gui", endpoint: "cute", connection: Some(i + 1) };
            handle.peek(|records| visit(at, records));
        }
    }
}
