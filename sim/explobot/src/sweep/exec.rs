//! Running the runs: one run per worker thread, each run single-threaded and deterministic.
//!
//! A run is the plain lockstep loop ([`Lockstep::step`], no Bevy), the same steps `explobot run`
//! takes in its headless app. A run that panics is caught ([`std::panic::catch_unwind`]) and
//! recorded with verdict `panic`; one that outlives `--timeout` (wall seconds, off by default)
//! is stopped and recorded with verdict `timeout`; the sweep goes on either way.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Instant as WallInstant;

use serde::Serialize;
use serde_json::{Map, Value};

use super::plan::{Plan, Run};
use twin::runner::Lockstep;

/// Lockstep steps between two looks at the wall clock when `--timeout` is set.
const TIMEOUT_CHECK_EVERY: u64 = 2000;

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    /// The run panicked.
    Panic,
    /// The run could not be set up (e.g. a grid Cute refuses).
    Error,
    /// The run outlived `--timeout` (wall clock).
    Timeout,
    /// An expectation failed, a mission step failed, or the mission was not complete at the
    /// scenario's time limit.
    Fail,
    /// Every expectation holds and the mission completed.
    Pass,
}

impl Verdict {
    /// Whether the run passed.
    pub fn passed(self) -> bool {
        self == Verdict::Pass
    }
}

/// Wall-clock figures of one run: the only part of a `results.jsonl` line that differs between
/// two sweeps of the same runs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct Wall {
    /// The whole run: setup, steps, report, line.
    pub total_s: f64,
    /// Building the run: scenario copy, truth grid, world, Carto, Cute, links.
    pub setup_s: f64,
    /// Stepping the simulation.
    pub steps_s: f64,
    /// The report: map scores and the SHA-256 of every byte on every link.
    pub report_s: f64,
    /// Freeing the run (its world and every logged byte).
    pub teardown_s: f64,
    /// Writing the run's `results.jsonl` line.
    pub write_s: f64,
    /// Simulated seconds per wall second while stepping.
    pub real_time_factor: f64,
}

impl Wall {
    /// What a sweep adds to the run: everything but the steps and the report (setup, teardown,
    /// writing its line).
    pub fn overhead_s(&self) -> f64 {
        (self.total_s - self.steps_s - self.report_s).max(0.0)
    }
}

/// One finished run: its `results.jsonl` line (no newline) and what the progress bar needs.
#[derive(Debug, Clone)]
pub struct Finished {
    /// Place in the run list.
    pub index: usize,
    /// Verdict.
    pub verdict: Verdict,
    /// The line.
    pub line: String,
    /// Wall-clock figures (also in the line).
    pub wall: Wall,
}

#[derive(Serialize)]
struct Line<'a> {
    index: usize,
    room: &'a str,
    scenario: &'a str,
    seed: u64,
    verdict: Verdict,
    #[serde(skip_serializing_if = "Option::is_none")]
    reason: Option<String>,
    #[serde(flatten)]
    report: Map<String, Value>,
    wall: Wall,
}

/// Runs `run` of `plan`; `timeout_s` bounds its wall time.
pub fn execute(plan: &Plan, run: Run, timeout_s: Option<f64>) -> Finished {
    let room = &plan.rooms[run.room];
    let start = WallInstant::now();
    let mut wall = Wall::default();
    let outcome = catch(|| -> Result<_, String> {
        let mut lockstep = Lockstep::new(room.loaded.clone(), Some(run.seed)).map_err(|e| e.to_string())?;
        wall.setup_s = start.elapsed().as_secs_f64();
        let stepping = WallInstant::now();
        let mut steps = 0u64;
        let mut timed_out = false;
        while lockstep.step() {
            steps += 1;
            if let Some(limit) = timeout_s
                && steps.is_multiple_of(TIMEOUT_CHECK_EVERY)
                && stepping.elapsed().as_secs_f64() > limit
            {
                timed_out = true;
                break;
            }
        }
        wall.steps_s = stepping.elapsed().as_secs_f64();
        let reporting = WallInstant::now();
        let report = lockstep.report(wall.steps_s);
        wall.report_s = reporting.elapsed().as_secs_f64();
        let teardown = WallInstant::now();
        drop(lockstep);
        wall.teardown_s = teardown.elapsed().as_secs_f64();
        Ok((report, timed_out))
    });
    let (verdict, reason, report) = match outcome {
        Ok(Ok((report, timed_out))) => {
            let verdict = if timed_out {
                Verdict::Timeout
            } else if report.passed && report.mission_complete {
                Verdict::Pass
            } else {
                Verdict::Fail
            };
            let reason = match verdict {
                Verdict::Timeout => Some(format!(
                    "stopped by --timeout {} s at {:.1} s simulated",
                    timeout_s.unwrap_or_default(),
                    report.sim_time_s
                )),
                Verdict::Fail => Some(fail_reason(&report)),
                _ => None,
            };
            wall.real_time_factor = report.real_time_factor;
            let mut map = match serde_json::to_value(&report) {
                Ok(Value::Object(map)) => map,
                _ => Map::new(),
            };
            for key in ["scenario", "seed", "wall_time_s", "real_time_factor"] {
                map.remove(key);
            }
            // Every touch is in the run's report.json; a sweep line keeps their figures only.
            if let Some(Value::Object(touches)) = map.get_mut("touches") {
                touches.remove("list");
            }
            (verdict, reason, map)
        }
        Ok(Err(setup)) => (Verdict::Error, Some(setup), Map::new()),
        Err(message) => (Verdict::Panic, Some(format!("panicked: {message}")), Map::new()),
    };
    let mut line = Line {
        index: run.index,
        room: &room.id,
        scenario: &room.loaded.scenario.name,
        seed: run.seed,
        verdict,
        reason,
        report,
        wall,
    };
    // Serialising a map of plain values cannot fail; an empty line would be rejected on reading.
    let writing = WallInstant::now();
    let _ = serde_json::to_string(&line).unwrap_or_default();
    line.wall.write_s = writing.elapsed().as_secs_f64();
    line.wall.total_s = start.elapsed().as_secs_f64();
    let text = serde_json::to_string(&line).unwrap_or_default();
    Finished { index: run.index, verdict, line: text, wall: line.wall }
}

/// Runs `f`, turning a panic into its message.
fn catch<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    catch_unwind(AssertUnwindSafe(f)).map_err(|payload| {
        payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "a panic without a message".into())
    })
}

/// The failed checks and mission errors of a failed run, one phrase each.
fn fail_reason(report: &twin::report::Report) -> String {
    let mut parts: Vec<String> = report
        .checks
        .iter()
        .filter(|c| !c.pass)
        .map(|c| format!("{} expected {} got {}", c.name, c.expected, c.actual))
        .collect();
    parts.extend(report.mission_errors.iter().map(|e| format!("mission error: {e}")));
    if !report.mission_complete {
        parts.push(format!("mission not complete at the time limit ({:.0} s)", report.sim_time_s));
    }
    parts.join("; ")
}

/// Runs `runs` on `jobs` worker threads (each run whole on one thread) and hands each finished
/// run to `done` on the calling thread, in finishing order.
pub fn run_all(
    plan: &Plan,
    runs: &[Run],
    jobs: usize,
    timeout_s: Option<f64>,
    mut done: impl FnMut(Finished),
) {
    let next = AtomicUsize::new(0);
    let (tx, rx) = mpsc::channel();
    std::thread::scope(|scope| {
        let mut workers = 0;
        for _ in 0..jobs.clamp(1, runs.len().max(1)) {
            let tx = tx.clone();
            let next = &next;
            // A run's Cute and Carto plan on the stack; give them the main thread's room.
            let spawned = std::thread::Builder::new().stack_size(16 << 20).spawn_scoped(scope, move || {
                quiet_logs(|| {
                    while let Some(&run) = runs.get(next.fetch_add(1, Ordering::Relaxed)) {
                        if tx.send(execute(plan, run, timeout_s)).is_err() {
                            break;
                        }
                    }
                })
            });
            workers += usize::from(spawned.is_ok());
        }
        drop(tx);
        if workers == 0 {
            tracing::warn!("no worker thread could be started; running on the main thread");
            quiet_logs(|| {
                while let Some(&run) = runs.get(next.fetch_add(1, Ordering::Relaxed)) {
                    done(execute(plan, run, timeout_s));
                }
            });
        }
        for finished in rx {
            done(finished);
        }
    });
}

/// Runs `f` without the runs' log lines (a hundred runs' warnings would bury the progress bar
/// and could not be told apart), unless `RUST_LOG` asks for them.
fn quiet_logs<T>(f: impl FnOnce() -> T) -> T {
    if std::env::var_os("RUST_LOG").is_some() {
        f()
    } else {
        tracing::subscriber::with_default(tracing::subscriber::NoSubscriber::default(), f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[allow(clippy::panic)]
    fn a_panic_becomes_its_message() {
        assert_eq!(catch(|| 7), Ok(7));
        assert_eq!(catch(|| -> u8 { panic!("static text") }), Err("static text".to_string()));
        let n = 3;
        assert_eq!(catch(|| -> u8 { panic!("formatted {n}") }), Err("formatted 3".to_string()));
    }
}
