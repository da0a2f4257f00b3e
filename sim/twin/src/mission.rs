//! The scenario's mission script, played on Cute as an operator would: press a button, click a
//! cell, wait for the robot.
//!
//! Concept: [`Operator::poll`] runs at every lockstep step, between Cute reading its bytes and
//! Cute's own poll (see [`cute::CuteRuntime::step_with`]). It plays every [`Step`] that can
//! complete now and stops at the first that must wait (`WaitUntilMapped`, `WaitUntilIdle`,
//! `Wait`). A refused action (e.g. `GoTo` an unknown cell) is recorded in the errors and the
//! script goes on.
//!
//! Invariants: steps run in order, each once; the script is finished from the first poll that
//! finds no step left, and stays finished.
//!
//! ```
//! use cute::{Cute, CuteConfig};
//! use robot_model::time::Instant;
//! use twin::mission::Operator;
//! use twin::scenario::Step;
//! let mut cute = Cute::new(CuteConfig::default()).unwrap();
//! let mut op = Operator::new(vec![Step::Wait(1.0), Step::GoTo(5, 5)]);
//! op.poll(Instant::ZERO, &mut cute);
//! assert_eq!(op.finished_at(), None);
//! op.poll(Instant::from_secs(1), &mut cute);
//! assert_eq!(op.finished_at(), Some(Instant::from_secs(1)));
//! assert_eq!(op.errors().len(), 1); // (5, 5) is not known free yet
//! ```

use cute::{Cute, Status};
use robot_model::time::{Duration, Instant};

use crate::scenario::Step;

/// The mission script, played one step at a time on Cute.
#[derive(Debug, Clone)]
pub struct Operator {
    steps: Vec<Step>,
    next: usize,
    wait_until: Option<Instant>,
    /// Actions Cute refused, with the step and the time.
    pub(crate) errors: Vec<String>,
    /// When the last step completed.
    pub(crate) finished_at: Option<Instant>,
}

impl Operator {
    /// An operator about to play `steps`.
    pub fn new(steps: Vec<Step>) -> Self {
        Operator { steps, next: 0, wait_until: None, errors: Vec::new(), finished_at: None }
    }

    /// When the last step completed, once it has.
    pub fn finished_at(&self) -> Option<Instant> {
        self.finished_at
    }

    /// Steps completed and steps in the script.
    pub fn progress(&self) -> (usize, usize) {
        (self.next.min(self.steps.len()), self.steps.len())
    }

    /// The step being played (waited on), if the script is not over.
    pub fn current(&self) -> Option<&Step> {
        self.steps.get(self.next)
    }

    /// Actions Cute refused, e.g. `"GoTo(3, 4) at 12.000s: no path"`.
    pub fn errors(&self) -> &[String] {
        &self.errors
    }

    /// Plays every step that can complete at `now`.
    pub fn poll(&mut self, now: Instant, cute: &mut Cute) {
        while let Some(step) = self.steps.get(self.next).cloned() {
            let done = match step {
                Step::StartCartography => {
                    if let Err(e) = cute.start_cartography() {
                        self.errors.push(format!("StartCartography at {now}: {e}"));
                    }
                    true
                }
                Step::WaitUntilMapped => cute.status() != Status::Mapping,
                Step::GoTo(row, col) => {
                    if let Err(e) = cute.go_to(row, col) {
                        self.errors.push(format!("GoTo({row}, {col}) at {now}: {e}"));
                    }
                    true
                }
                Step::WaitUntilIdle => matches!(cute.status(), Status::Idle | Status::Done),
                Step::Stop => {
                    cute.stop();
                    true
                }
                Step::ResetMap => {
                    cute.reset_map();
                    true
                }
                Step::Wait(seconds) => {
                    let until =
                        *self.wait_until.get_or_insert(now + Duration::from_secs_f64(f64::from(seconds)));
                    now >= until
                }
            };
            if !done {
                return;
            }
            self.wait_until = None;
            self.next += 1;
        }
        self.finished_at.get_or_insert(now);
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use cute::{CuteConfig, CuteEvent};
    use robot_model::grid::Heading;

    use super::*;

    fn cute() -> Cute {
        Cute::new(CuteConfig {
            rows: 3,
            cols: 3,
            start: (0, 0),
            heading: Heading::East,
            ..CuteConfig::default()
        })
        .unwrap()
    }

    fn at(ms: u64) -> Instant {
        Instant::from_millis(ms)
    }

    #[test]
    fn a_wait_counts_from_the_step_it_is_reached() {
        let mut cute = cute();
        let mut op = Operator::new(vec![Step::Wait(0.5), Step::Stop, Step::Wait(0.5)]);
        op.poll(at(100), &mut cute);
        op.poll(at(599), &mut cute);
        assert!(cute.take_events().is_empty(), "still waiting");
        op.poll(at(600), &mut cute);
        assert_eq!(cute.take_events(), [CuteEvent::Stopped]);
        assert_eq!(op.finished_at(), None, "the second wait starts at 600 ms");
        op.poll(at(1099), &mut cute);
        assert_eq!(op.finished_at(), None);
        op.poll(at(1100), &mut cute);
        op.poll(at(2000), &mut cute);
        assert_eq!(op.finished_at(), Some(at(1100)), "finished once, and stays so");
    }

    #[test]
    fn wait_until_mapped_holds_while_cute_maps() {
        let mut cute = cute();
        let mut op = Operator::new(vec![Step::StartCartography, Step::WaitUntilMapped, Step::ResetMap]);
        op.poll(at(0), &mut cute);
        assert_eq!(cute.status(), Status::Mapping);
        op.poll(at(10), &mut cute);
        assert_eq!(op.finished_at(), None);
        cute.stop();
        op.poll(at(20), &mut cute);
        assert_eq!((op.finished_at(), op.errors()), (Some(at(20)), &[][..]));
    }

    #[test]
    fn refused_actions_are_recorded_and_the_script_goes_on() {
        let mut cute = cute();
        let mut op = Operator::new(vec![
            Step::StartCartography,
            Step::StartCartography,
            Step::WaitUntilIdle,
            Step::GoTo(2, 2),
        ]);
        op.poll(at(0), &mut cute);
        assert_eq!(op.errors().len(), 1, "{:?}", op.errors());
        assert!(op.errors()[0].starts_with("StartCartography at "), "{:?}", op.errors());
        cute.stop();
        op.poll(at(5), &mut cute);
        assert_eq!(op.errors().len(), 2);
        assert!(op.errors()[1].starts_with("GoTo(2, 2) at "), "{:?}", op.errors());
        assert_eq!(op.finished_at(), Some(at(5)));
    }
}
