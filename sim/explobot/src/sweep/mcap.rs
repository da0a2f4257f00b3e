//! `explobot sweep --mcap`: an MCAP file for each run that did not pass.
//!
//! Concept: runs are deterministic, so a failed run is run again, this time with a
//! [`twin_viz::Recorder`] on it, once the sweep is over: the passing runs pay
//! nothing, and the file shows exactly the run the results describe. The second run's link-log
//! hash is compared with the first's; a difference is reported (it would mean the run is not
//! deterministic) and the file is kept.
//!
//! Files: `OUT/mcap/INDEX-NAME-seedSEED.mcap` (INDEX four digits; lz4-compressed chunks, since
//! a CI job keeps them), for verdicts `fail`, `timeout` (stopped at the same wall-clock limit)
//! and `panic` (cut where it panicked).

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant as WallInstant;

use tracing_subscriber::prelude::*;

use super::exec::{Finished, Verdict};
use super::plan::{Plan, Run};
use twin::runner::Lockstep;
use twin_viz::{Recorder, logs};

/// Where the MCAP file of `run` goes in `out`.
pub fn path_of(out: &Path, plan: &Plan, run: Run) -> PathBuf {
    let name = plan.rooms.get(run.room).map_or("room", |r| r.loaded.scenario.name.as_str());
    out.join("mcap").join(format!("{:04}-{name}-seed{}.mcap", run.index, run.seed))
}

/// The runs among `finished` worth a file: those that ran and did not pass, each with the
/// link-log hash its second run must have (for runs that ran to their end: verdict `fail`).
pub fn failed<'a>(
    plan: &Plan,
    finished: impl IntoIterator<Item = &'a Finished>,
) -> Vec<(Run, Option<String>)> {
    finished
        .into_iter()
        .filter(|f| !f.verdict.passed() && f.verdict != Verdict::Error)
        .filter_map(|f| {
            let run = plan.runs.get(f.index).copied()?;
            let hash = (f.verdict == Verdict::Fail)
                .then(|| serde_json::from_str::<serde_json::Value>(&f.line).ok())
                .flatten()
                .and_then(|v| v.get("link_log_sha256").and_then(|h| h.as_str()).map(str::to_owned));
            Some((run, hash))
        })
        .collect()
}

/// Runs each of `runs` again with a recorder on `jobs` threads; the files written and one line
/// per problem.
pub fn write_all(
    plan: &Plan,
    runs: &[(Run, Option<String>)],
    out: &Path,
    jobs: usize,
    timeout_s: Option<f64>,
) -> (Vec<PathBuf>, Vec<String>) {
    let next = AtomicUsize::new(0);
    let results = Mutex::new((Vec::new(), Vec::new()));
    std::thread::scope(|scope| {
        for _ in 0..jobs.clamp(1, runs.len().max(1)) {
            let _ = std::thread::Builder::new().stack_size(16 << 20).spawn_scoped(scope, || {
                // Only the capture layer: the re-runs' events go to their files, not to stderr.
                let subscriber = tracing_subscriber::registry().with(logs::layer());
                tracing::subscriber::with_default(subscriber, || {
                    while let Some((run, hash)) = runs.get(next.fetch_add(1, Ordering::Relaxed)) {
                        let path = path_of(out, plan, *run);
                        let outcome = write_one(plan, *run, hash.as_deref(), &path, timeout_s);
                        let mut r = results.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
                        match outcome {
                            Ok(None) => r.0.push(path),
                            Ok(Some(note)) => {
                                r.0.push(path);
                                r.1.push(note);
                            }
                            Err(e) => r.1.push(e),
                        }
                    }
                });
            });
        }
    });
    let (mut files, notes) = results.into_inner().unwrap_or_else(std::sync::PoisonError::into_inner);
    files.sort();
    (files, notes)
}

/// One run again into `path`: `Ok(Some(note))` when the file was written but the run differs.
fn write_one(
    plan: &Plan,
    run: Run,
    hash: Option<&str>,
    path: &Path,
    timeout_s: Option<f64>,
) -> Result<Option<String>, String> {
    let room = plan.rooms.get(run.room).ok_or("no such room")?;
    let what = format!("run {} ({} seed {})", run.index, room.id, run.seed);
    let mut lockstep =
        Lockstep::new(room.loaded.clone(), Some(run.seed)).map_err(|e| format!("{what}: {e}"))?;
    let recorder = Recorder::new().write_mcap(path, true).map_err(|e| format!("{what}: {e}"))?;
    lockstep.set_observer(Box::new(recorder.publisher(&lockstep)));
    let started = WallInstant::now();
    let stepped = catch_unwind(AssertUnwindSafe(|| {
        let mut steps = 0u64;
        while lockstep.step() {
            steps += 1;
            if timeout_s.is_some_and(|t| steps.is_multiple_of(2000) && started.elapsed().as_secs_f64() > t) {
                break;
            }
        }
        let report = lockstep.report(started.elapsed().as_secs_f64());
        (report, lockstep.now())
    }));
    logs::stop_capturing();
    match stepped {
        Ok((report, now)) => {
            recorder.finish(Some((&report, now))).map_err(|e| format!("{what}: {e}"))?;
            Ok(hash.filter(|h| *h != report.link_log_sha256).map(|_| {
                format!(
                    "{what}: the second run's link-log hash differs from the first's (not deterministic?)"
                )
            }))
        }
        Err(_) => {
            recorder.finish(None).map_err(|e| format!("{what}: {e}"))?;
            Ok(None)
        }
    }
}
