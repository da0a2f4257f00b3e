//! Sweeps: many runs, one verdict.
//!
//! `explobot sweep [SCENARIO…] [--generate STYLE:COUNT]… [--seeds A..B] [--jobs N]
//! [--shard K/N | --shard auto] [--out DIR]` runs every room with every seed, one run per worker
//! thread, and writes one folder:
//!
//! - `results.jsonl`: one JSON object per run, in run-list order whatever order the runs
//!   finished in: `index`, `room`, `scenario`, `seed`, `verdict` (`pass`, `fail`, `timeout`,
//!   `error`, `panic`), `reason` (when not `pass`), then every field of the run's report
//!   (`report.json` of `explobot run`: `checks`, `coverage`, `map_accuracy`, `collisions`,
//!   `sim_time_s`, `link_log_sha256`, …) and last `wall`, the wall-clock figures. Everything
//!   but `wall` is the same on every machine, for every `--jobs` and every sharding.
//! - `summary.md` and `junit.xml`: computed from the lines, no wall-clock figures at all, so
//!   byte-identical between runs of the same sweep.
//! - `sweep.json`: the run list (rooms with the SHA-256 of their text, seeds), for `merge`.
//!
//! The run list ([`plan`]) is the rooms in the order given (scenario files, then generated
//! rooms) × the seeds. `--generate STYLE:COUNT` adds `explobot generate --style STYLE --seed S`
//! for S in `1..=COUNT` (room id `gen:STYLE:S`); the generator seed only shapes the room, the run
//! seed (`--seeds`) drives noise and faults. Without `--seeds` each room runs once with its own
//! seed (a generated room's is its generator seed).
//!
//! A run passes when every expectation holds, no mission step failed and the mission completed
//! before the scenario's time limit. Exit code 0: every run passes; 1: some run does not; 2: bad
//! input (a scenario file's errors come with file:line:column).
//!
//! `explobot sweep merge DIR… --out DIR` joins shard folders into the folder a one-machine run
//! of the same sweep writes. `explobot sweep compare OLD NEW` pairs two sweeps' runs by room and
//! seed ([`compare`]). `summary.md` opens with the pass rate and its Wilson 95 % interval and
//! gives the continuous figures per scenario or style ([`stats`]).
//!
//! ```no_run
//! use clap::Parser;
//! #[derive(Parser)]
//! struct Cli { #[command(flatten)] sweep: explobot::sweep::SweepArgs }
//! let cli = Cli::parse_from(["explobot", "scenarios/empty.ron", "--seeds", "1..4", "--jobs", "2"]);
//! let exit_code = cli.sweep.run()?; // 0: all pass, 1: some run fails
//! # let _ = exit_code;
//! # Ok::<(), explobot::sweep::SweepError>(())
//! ```

pub mod compare;
pub mod exec;
pub mod mcap;
pub mod merge;
pub mod output;
pub mod plan;
pub mod record;
pub mod stats;
pub mod summary;

use std::collections::BTreeMap;
use std::num::NonZeroUsize;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant as WallInstant;

use indicatif::{ProgressBar, ProgressStyle};

use exec::{Finished, Wall, run_all};
use plan::{GenerateSpec, Plan, Run, Seeds, Shard, ShardArg};
use twin::scenario::ScenarioError;
use twin_roomgen::GenerateError;

/// Why a sweep could not run (exit code 2).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SweepError {
    /// A scenario file does not load: `file:line:column: message`.
    #[error("{0}")]
    Scenario(ScenarioError),
    /// A generated room could not be made.
    #[error("--generate: {0}")]
    Generate(GenerateError),
    /// Bad arguments, environment or shard folders.
    #[error("{0}")]
    Input(String),
    /// A file could not be read or written.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// The system's reason.
        message: String,
    },
}

/// `explobot sweep`: run a sweep, or `merge` shard folders.
#[derive(clap::Args, Debug, Clone)]
#[command(args_conflicts_with_subcommands = true)]
pub struct SweepArgs {
    /// `merge`.
    #[command(subcommand)]
    pub command: Option<SweepCommand>,
    /// The sweep to run.
    #[command(flatten)]
    pub sweep: RunArgs,
}

/// Subcommands of `explobot sweep`.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum SweepCommand {
    /// Merge shard folders into the folder a one-machine run of the same sweep writes.
    Merge(merge::MergeArgs),
    /// Pair the runs of two sweeps by room and seed: flips, McNemar's test, figures, link bytes.
    Compare(compare::CompareArgs),
}

/// Arguments of a sweep run.
#[derive(clap::Args, Debug, Clone)]
pub struct RunArgs {
    /// Scenario files, run in this order.
    pub scenarios: Vec<PathBuf>,
    /// Generated rooms: STYLE:COUNT runs generator seeds 1..=COUNT of STYLE (repeatable).
    #[arg(long = "generate", value_name = "STYLE:COUNT")]
    pub generate: Vec<GenerateSpec>,
    /// Run seeds, inclusive: `1..10`, `7`, `1..5,9` (default: each room's own seed).
    #[arg(long, value_name = "A..B")]
    pub seeds: Option<Seeds>,
    /// Worker threads, one run each (default: every core).
    #[arg(long)]
    pub jobs: Option<NonZeroUsize>,
    /// Run only runs with index % N == K-1 (K in 1..=N), or `auto`: from EXPLOBOT_SHARD=K/N, a
    /// Slurm job array, or a Kubernetes Indexed Job (JOB_COMPLETION_INDEX + EXPLOBOT_SHARD_COUNT).
    #[arg(long, value_name = "K/N|auto")]
    pub shard: Option<ShardArg>,
    /// Output folder.
    #[arg(long, default_value = "runs/sweep")]
    pub out: PathBuf,
    /// Stop a run after this many wall-clock seconds and record it as `timeout` (default: no
    /// limit; a timeout depends on the machine, so a sweep that hits one is not reproducible).
    #[arg(long, value_name = "SECONDS")]
    pub timeout: Option<f64>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Write an MCAP file of each run that does not pass to OUT/mcap/ (the run again, with a
    /// recorder; see `explobot run --mcap`).
    #[arg(long)]
    pub mcap: bool,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub known: crate::args::KnownRoomArg,
}

impl SweepArgs {
    /// Runs the sweep or the merge; the exit code is 0 when every run passes, 1 otherwise.
    pub fn run(&self) -> Result<ExitCode, SweepError> {
        match &self.command {
            Some(SweepCommand::Merge(args)) => args.run(),
            Some(SweepCommand::Compare(args)) => args.run(),
            None => self.sweep.run(),
        }
    }
}

impl RunArgs {
    /// Runs this process's share of the sweep and writes the folder.
    pub fn run(&self) -> Result<ExitCode, SweepError> {
        let started = WallInstant::now();
        let shard = match self.shard {
            None => Shard::ALL,
            Some(ShardArg::Fixed(s)) => s,
            Some(ShardArg::Auto) => {
                Shard::from_env(|k| std::env::var(k).ok()).map_err(|e| SweepError::Input(e.to_string()))?
            }
        };
        if let Some(t) = self.timeout
            && !(t.is_finite() && t > 0.0)
        {
            return Err(SweepError::Input(format!("--timeout {t}: give a number of seconds > 0")));
        }
        let plan = Plan::build(&self.scenarios, &self.generate, self.seeds.as_ref(), self.known.oracle())?;
        let mine: Vec<Run> = plan.runs.iter().filter(|r| shard.contains(r.index)).copied().collect();
        let jobs =
            self.jobs.or_else(|| std::thread::available_parallelism().ok()).map_or(1, NonZeroUsize::get);
        let workers = jobs.min(mine.len()).max(1);
        if shard != Shard::ALL {
            eprintln!("sweep: shard {shard}: {} of {} runs", mine.len(), plan.runs.len());
        }
        let bar = if self.quiet { ProgressBar::hidden() } else { ProgressBar::new(mine.len() as u64) };
        bar.set_style(
            ProgressStyle::with_template(
                "{bar:40} {pos}/{len} runs [{elapsed_precise} ETA {eta_precise}] {msg}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        bar.enable_steady_tick(std::time::Duration::from_millis(500));
        let loading_s = started.elapsed().as_secs_f64();
        let (mut pass, mut fail) = (0, 0);
        let mut done: BTreeMap<usize, Finished> = BTreeMap::new();
        bar.set_message("pass 0 fail 0");
        run_all(&plan, &mine, workers, self.timeout, |f| {
            if f.verdict.passed() {
                pass += 1
            } else {
                fail += 1
            }
            bar.inc(1);
            bar.set_message(format!("pass {pass} fail {fail}"));
            done.insert(f.index, f);
        });
        bar.finish_and_clear();
        let writing = WallInstant::now();
        let lines: Vec<String> = done.values().map(|f| f.line.clone()).collect();
        let totals = output::write_folder(&self.out, &plan.manifest, &lines)?;
        let writing_s = writing.elapsed().as_secs_f64();
        let walls: Vec<Wall> = done.values().map(|f| f.wall).collect();
        eprintln!("{}", timing(&walls, workers, loading_s, writing_s, started.elapsed().as_secs_f64()));
        if self.mcap {
            let failed = mcap::failed(&plan, done.values());
            let (files, notes) = mcap::write_all(&plan, &failed, &self.out, workers, self.timeout);
            for note in &notes {
                eprintln!("sweep: mcap: {note}");
            }
            // the files are written: a closed standard output loses nothing
            let _ = crate::output::print_stdout(&format!(
                "sweep: wrote {} MCAP file(s) of runs that did not pass to {}/mcap/\n",
                files.len(),
                self.out.display()
            ));
        }
        Ok(verdict(&self.out, totals))
    }
}

/// Prints the verdict line and gives the exit code.
fn verdict(out: &std::path::Path, totals: output::Totals) -> ExitCode {
    // the files are written: a closed standard output loses nothing
    let _ = crate::output::print_stdout(&format!(
        "sweep: {} of {} runs pass; wrote {}/results.jsonl, summary.md, junit.xml\n",
        totals.passed,
        totals.runs,
        out.display()
    ));
    if totals.passed == totals.runs { ExitCode::SUCCESS } else { ExitCode::from(1) }
}

/// The figures printed on stderr at the end of a sweep, as shares of the core time used (each
/// run's whole wall time, plus loading and writing the folder, which keep every worker waiting):
/// the *overhead* (each run's setup — scenario copy, truth grid, world, Carto, Cute —, freeing
/// it and writing its line, plus loading and writing) and, apart, the report (map scores and the link-log SHA-256).
pub fn timing(walls: &[Wall], workers: usize, loading_s: f64, writing_s: f64, total_s: f64) -> String {
    let sum = |f: fn(&Wall) -> f64| walls.iter().map(f).sum::<f64>();
    let n = walls.len().max(1) as f64;
    let serial = workers as f64 * (loading_s + writing_s);
    let used = (sum(|w| w.total_s) + serial).max(1e-9);
    format!(
        "timing: {} runs in {total_s:.1} s on {workers} workers; per run {:.3} s: setup {:.2} ms, steps {:.1} ms, \
         report {:.2} ms, teardown {:.2} ms, line {:.3} ms; loading {:.3} s, writing {:.3} s\n\
         timing: overhead (setup, teardown, line, loading, writing) {:.2}% of core time; report (scores, link-log SHA-256) {:.2}%",
        walls.len(),
        sum(|w| w.total_s) / n,
        1000.0 * sum(|w| w.setup_s) / n,
        1000.0 * sum(|w| w.steps_s) / n,
        1000.0 * sum(|w| w.report_s) / n,
        1000.0 * sum(|w| w.teardown_s) / n,
        1000.0 * sum(|w| w.write_s) / n,
        loading_s,
        writing_s,
        100.0 * (sum(Wall::overhead_s) + serial) / used,
        100.0 * sum(|w| w.report_s) / used,
    )
}
