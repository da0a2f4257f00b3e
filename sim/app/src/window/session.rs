//! The window's run as the user lives it: the scenario's script plays first, then the user
//! drives; the verdict on the scenario's expectations is taken when the script ends; Restart
//! starts the scenario again.
//!
//! Concept: the window's runner is [`Lockstep::interactive`]: it takes exactly the steps of a
//! headless run up to the point where `explobot run` stops ([`Lockstep::headless_end`]: the
//! script done and settled, or `max_sim_s`), and then goes on until the window is closed.
//! [`Handover`] holds the report taken at that very step (so its figures are those the headless
//! report would show, the wall time aside), and [`ScriptState`] words where the run stands for the
//! status bar: the script playing, or over and the user driving.
//!
//! Invariants: the verdict is taken once per run, at the step the headless run would end (the
//! pacing loop checks after every step); a restart builds a fresh runner from the same loaded
//! scenario and seed and forgets the verdict, the pop-ups and the speed measurement.

use bevy::ecs::system::{Res, ResMut};
use bevy::prelude::Resource;
use bevy::time::{Real, Time};
use cute::gui::CuteUiState;
use robot_model::time::Instant;

use crate::pacing::Pacing;
use crate::plugin::Sim;
use twin::report::Report;
use twin::runner::Lockstep;

/// The last report (rebuilt every `REPORT_EVERY_S` in `panels`) and when it was made.
#[derive(Resource, Default)]
pub(crate) struct StatusCache {
    pub(super) report: Option<Report>,
    pub(super) made_at_s: f64,
    pub(super) sim_at: Option<Instant>,
}

/// The run's handover from script to user: the verdict taken at the headless end, and a
/// restart asked for.
#[derive(Resource, Debug, Default)]
pub struct Handover {
    /// The report taken at the step where a headless run ends, with its expectation checks.
    pub verdict: Option<Report>,
    /// Set by the Restart button; the restart happens before the next steps.
    pub restart: bool,
    /// Why the last restart failed, if it did.
    pub error: Option<String>,
}

impl Handover {
    /// Takes the verdict if `run` has just reached its headless end; returns whether it did.
    /// The report is also printed, as `explobot run` prints it.
    pub fn take_verdict(&mut self, run: &Lockstep, wall_s: f64) -> bool {
        if self.verdict.is_some() || run.headless_end().is_none() {
            return false;
        }
        let report = run.report(wall_s);
        println!("{}", ScriptState::of(run).text());
        print!("{}", report.to_text());
        self.verdict = Some(report);
        true
    }

    /// One line on the expectations: `expectations PASS (4/4)`, the failing ones named.
    pub fn verdict_line(&self) -> Option<String> {
        let r = self.verdict.as_ref()?;
        if r.checks.is_empty() {
            return Some("no expectations".to_string());
        }
        let passed = r.checks.iter().filter(|c| c.pass).count();
        let failing: Vec<String> = r
            .checks
            .iter()
            .filter(|c| !c.pass)
            .map(|c| format!("{} {} (wanted {})", c.name, c.actual, c.expected))
            .collect();
        Some(if failing.is_empty() {
            format!("expectations PASS ({passed}/{})", r.checks.len())
        } else {
            format!("expectations FAIL ({passed}/{}): {}", r.checks.len(), failing.join(", "))
        })
    }
}

/// Where the run stands between the script and the user.
#[derive(Debug, Clone, PartialEq)]
pub enum ScriptState {
    /// The scenario has no script: the user drives from the start.
    NoScript,
    /// The script plays: steps done, steps in all, and the step waited on.
    Playing {
        /// Steps completed.
        done: usize,
        /// Steps in the script.
        total: usize,
        /// The step being played.
        step: String,
    },
    /// The script is over (and settled) at this sim time: the user drives.
    Done(Instant),
    /// The scenario's time limit passed before the script ended (a headless run stops there);
    /// the script goes on playing and the user can drive too.
    LimitPassed {
        /// Steps completed.
        done: usize,
        /// Steps in the script.
        total: usize,
        /// The limit, `max_sim_s`.
        limit: Instant,
    },
}

impl ScriptState {
    /// The state of `run` now.
    pub fn of(run: &Lockstep) -> ScriptState {
        let op = run.operator();
        let (done, total) = op.progress();
        if total == 0 {
            return ScriptState::NoScript;
        }
        match (op.finished_at(), run.headless_end()) {
            (Some(_), Some(at)) => ScriptState::Done(at),
            (None, Some(_)) => ScriptState::LimitPassed { done, total, limit: run.time_limit() },
            _ => ScriptState::Playing {
                done,
                total,
                step: op.current().map_or_else(|| "settling".to_string(), |s| format!("{s:?}")),
            },
        }
    }

    /// Whether the user is the only one driving now.
    pub fn user_drives(&self) -> bool {
        matches!(self, ScriptState::NoScript | ScriptState::Done(_))
    }

    /// The status bar's words for it.
    pub fn text(&self) -> String {
        match self {
            ScriptState::NoScript => "no script, you drive".to_string(),
            ScriptState::Playing { done, total, step } => {
                format!("script step {}/{total}: {step}", (done + 1).min(*total))
            }
            ScriptState::Done(at) => format!("script done at {:.1} s, you drive", at.as_secs_f64()),
            ScriptState::LimitPassed { done, total, limit } => format!(
                "time limit {:.0} s passed (a headless run stops here), script at step {}/{total}; you can drive",
                limit.as_secs_f64(),
                (done + 1).min(*total)
            ),
        }
    }
}

/// Restarts the scenario when the Restart button asked for it (before this frame's steps).
pub(super) fn restart_when_asked(
    mut handover: ResMut<Handover>,
    mut sim: ResMut<Sim>,
    mut pacing: ResMut<Pacing>,
    mut ui: ResMut<CuteUiState>,
    mut cache: ResMut<StatusCache>,
    time: Res<Time<Real>>,
) {
    if !std::mem::take(&mut handover.restart) {
        return;
    }
    match sim.0.restart() {
        Ok(mut run) => {
            // A Foxglove/MCAP publisher follows the run into its restart.
            if let Some(observer) = sim.0.take_observer() {
                run.set_observer(observer);
            }
            sim.0 = run;
            *handover = Handover::default();
            *ui = CuteUiState::default();
            *cache = StatusCache::default();
            pacing.forget_speed();
            pacing.stop_at = None;
            println!("restarted at {:.1} s wall (seed {})", time.elapsed_secs_f64(), sim.0.seed());
        }
        Err(e) => handover.error = Some(format!("restart failed: {e}")),
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use twin::setup::RunSetup;

    fn run_with(mission: &str) -> Lockstep {
        let text = format!(
            "Scenario(name: \"t\", room: [(0.0, 0.0), (1.3, 0.0), (1.3, 0.7), (0.0, 0.7)], \
             start: (row: 0, col: 0, heading: East), mission: [{mission}], \
             expect: (collisions_max: Some(0)))"
        );
        let loaded = RunSetup::from_ron_str(&text, "t", std::path::Path::new(".")).unwrap();
        Lockstep::new(loaded, None).unwrap().interactive()
    }

    #[test]
    fn issue_16_no_script_hands_over_at_once_and_the_run_goes_on() {
        let mut run = run_with("");
        assert_eq!(ScriptState::of(&run), ScriptState::NoScript);
        let mut handover = Handover::default();
        for _ in 0..400 {
            assert!(run.step(), "an interactive run never ends");
            handover.take_verdict(&run, 1.0);
        }
        assert!(run.headless_end().is_some());
        assert_eq!(handover.verdict_line().unwrap(), "expectations PASS (1/1)");
        assert!(ScriptState::of(&run).user_drives());
        assert_eq!(ScriptState::of(&run).text(), "no script, you drive");
    }

    #[test]
    fn issue_16_the_script_plays_then_the_user_drives_and_restart_starts_again() {
        let mut run = run_with("Wait(1.0)");
        assert!(matches!(ScriptState::of(&run), ScriptState::Playing { done: 0, total: 1, .. }));
        while run.headless_end().is_none() {
            assert!(run.step());
        }
        // The wait started at the first step (5 ms), ended 1 s later and settled 0.5 s after.
        assert_eq!(ScriptState::of(&run), ScriptState::Done(Instant::from_millis(1505)));
        assert_eq!(ScriptState::of(&run).text(), "script done at 1.5 s, you drive");
        for _ in 0..100 {
            assert!(run.step());
        }
        let again = run.restart().unwrap();
        assert_eq!((again.now(), again.seed(), again.is_interactive()), (Instant::ZERO, run.seed(), true));
        assert_eq!(again.body().pose(), Lockstep::new(run.loaded().clone(), None).unwrap().body().pose());
    }
}
