//! `explobot`: the twin's command-line tool. Parses arguments and calls the library crates; the
//! argument structs of the subcommands live beside the code they drive.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant as WallInstant;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use explobot::args::ReplayArgs;
use explobot::args::{ScreenshotArgs, WindowArgs};
use explobot::bench::{self, BenchArgs};
use explobot::output::{self, RunArgs};
use explobot::serve::{self, ServeArgs};
use explobot::wiretool;
use tracing_subscriber::prelude::*;
use twin::oracle::Oracle;
use twin::record::Recording;
use twin::runner::Lockstep;
use twin::setup::RunSetup;
use twin_viz::Recorder;

#[derive(Parser)]
#[command(
    name = "explobot",
    version,
    about = "ExploBot Twin: run Carto and Cute against a physics twin of the robot"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Show Carto's and Cute's log lines (INFO and above) on the terminal; without it they go to
    /// the run folder's log.txt only. RUST_LOG, when set, decides instead.
    #[arg(short, long, global = true)]
    verbose: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scenario headless: progress bar, report, runs/NAME/{report.json,map.png,links.rec}.
    Run(RunArgs),
    /// Open the interactive window on a scenario: the true world beside Cute's map, Cute's
    /// buttons, time controls (feature `window`).
    Window(WindowArgs),
    /// Run the twin in real time with its boards on pseudo-terminals (run/tty-motor,
    /// run/tty-sensor), TCP ports or real serial devices, for the real `carto` binary to drive.
    Sim(ServeArgs),
    /// Decode frames from hex bytes: each frame, resync notes, checksum verdicts.
    Decode(wiretool::DecodeArgs),
    /// Encode one frame and print it as hex, e.g. `encode --protocol motor drive-v2 50 0 -20 6`.
    Encode(wiretool::EncodeArgs),
    /// Re-run a recording (links.rec) and report the first byte where the new run differs.
    Replay(ReplayArgs),
    /// Print throughput figures: physics steps/s (sonar off, per cycle, every step) and full-stack
    /// real-time factor per scenario.
    Bench(BenchArgs),
    /// Fit a robot profile to a recording of the calibration drive (`carto --calibration-drive
    /// --record FILE`): each value with its uncertainty, the fit's residual, the fitted profile.
    Calibrate(explobot::calibrate::CalibrateArgs),
    /// Check scenario files (syntax, values, start cell) without running them.
    Check {
        /// Scenario files.
        #[arg(required = true)]
        scenarios: Vec<PathBuf>,
    },
    /// Write a realistic generated room (flat, office, warehouse, pillars, irregular) as a
    /// scenario file; the same style and seed always give the same file.
    Generate(explobot::args::GenerateArgs),
    /// Run many rooms × seeds on every core (or one shard of them), or merge shard folders.
    Sweep(explobot::sweep::SweepArgs),
    /// Print what the robot can really do in a room (free, reachable, turnable cells, blocked
    /// moves: what runs are scored against) and draw it as runs/NAME/truth.png.
    Truth(explobot::args::TruthArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // Events go to stderr as filtered by RUST_LOG (or -v: every INFO line; by default warnings,
    // the robot programs' left out), to the MCAP/Foxglove log of the run being stepped on the
    // same thread, if any (twin_viz::logs), and to `explobot run`'s log.txt (explobot::runlog).
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| if cli.verbose { "info".into() } else { "warn,carto=off,cute=off".into() });
    let stderr = tracing_subscriber::fmt::layer().with_writer(std::io::stderr).with_filter(filter);
    tracing_subscriber::registry()
        .with(stderr)
        .with(twin_viz::logs::layer())
        .with(explobot::runlog::layer())
        .init();
    let result = match cli.command.unwrap_or(Command::Run(RunArgs::default_room())) {
        Command::Run(args) if args.wants_window() && args.known.oracle() != Oracle::None => {
            Err(anyhow::anyhow!(
                "--known-room and --known-echoes are for headless runs and sweeps, not the window"
            ))
        }
        Command::Run(args) if args.wants_window() => {
            let mcap = args.mcap.as_deref().map(|p| (p, args.mcap_lz4));
            window(args.scenario, args.seed, &args.shot, args.foxglove, mcap)
        }
        Command::Window(args) => window(args.scenario, args.seed, &args.shot, args.foxglove, None),
        Command::Run(args) => run(args),
        Command::Sim(args) => sim_serve(&args),
        Command::Decode(args) => args.decode().map_err(anyhow::Error::from).and_then(|text| {
            output::print_stdout(&text)?;
            Ok(ExitCode::SUCCESS)
        }),
        Command::Encode(args) => args.encode().map_err(anyhow::Error::from).and_then(|bytes| {
            output::print_stdout(&format!("{}\n", wiretool::to_hex(&bytes)))?;
            Ok(ExitCode::SUCCESS)
        }),
        Command::Replay(args) if args.compare => explobot::calibrate::compare(
            &args.recording,
            &args.profile,
            args.room.as_deref(),
            args.plot.as_deref(),
        )
        .and_then(|text| output::print_stdout(&text).map_err(anyhow::Error::from))
        .map(|()| ExitCode::SUCCESS),
        Command::Replay(args) => replay(&args.recording, args.mcap.as_deref().map(|p| (p, args.mcap_lz4))),
        Command::Calibrate(args) => args
            .run()
            .and_then(|text| output::print_stdout(&text).map_err(anyhow::Error::from))
            .map(|()| ExitCode::SUCCESS),
        Command::Bench(args) => bench_cmd(&args),
        Command::Check { scenarios } => check(&scenarios),
        Command::Generate(args) => args.run().map(|()| ExitCode::SUCCESS).map_err(anyhow::Error::from),
        Command::Sweep(args) => args.run().map_err(anyhow::Error::from),
        Command::Truth(args) => args.run().map(|()| ExitCode::SUCCESS).map_err(anyhow::Error::from),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("explobot: {e:#}");
            ExitCode::from(2)
        }
    }
}

/// `explobot window` / `explobot run --window`: the interactive window, or one screenshot of it;
/// served live with `--foxglove`, recorded with `--mcap`.
fn window(
    scenario: Option<PathBuf>,
    seed: Option<u64>,
    shot: &ScreenshotArgs,
    foxglove: Option<SocketAddr>,
    mcap: Option<(&Path, bool)>,
) -> Result<ExitCode> {
    let mut run = Lockstep::new(RunSetup::load_or_default(scenario.as_deref())?, seed)?;
    let recorder = recorder(&mut run, mcap, foxglove)?;
    let ok = shot.outputs().and_then(|outputs| twin_app::app::run_window(run, &outputs));
    // The file is closed whatever the window did.
    if let Some(r) = recorder {
        r.finish(None)?;
    }
    Ok(if ok? { ExitCode::SUCCESS } else { ExitCode::FAILURE })
}

/// A recorder on `run` when MCAP output (file, lz4) or a live server is asked for.
fn recorder(
    run: &mut Lockstep,
    mcap: Option<(&Path, bool)>,
    foxglove: Option<SocketAddr>,
) -> Result<Option<Recorder>> {
    if mcap.is_none() && foxglove.is_none() {
        return Ok(None);
    }
    let mut recorder = Recorder::new();
    if let Some((path, lz4)) = mcap {
        recorder = recorder.write_mcap(path, lz4)?;
    }
    if let Some(addr) = foxglove {
        recorder = recorder.serve(addr)?;
        let port = recorder.port().unwrap_or(addr.port());
        output::print_stdout(&format!(
            "foxglove: serving on ws://{}:{port} (open it in Foxglove or Lichtblick)\n",
            addr.ip()
        ))?;
    }
    run.set_observer(Box::new(recorder.publisher(run)));
    Ok(Some(recorder))
}

/// Runs `loaded` to the end headless, recording to `mcap` if given; the run, its wall time in
/// seconds, and the recorder to finish.
fn run_headless(
    loaded: RunSetup,
    seed: Option<u64>,
    quiet: bool,
    mcap: Option<(&Path, bool)>,
) -> Result<(Lockstep, f64, Option<Recorder>)> {
    let mut lockstep = Lockstep::new(loaded, seed)?;
    let recorder = recorder(&mut lockstep, mcap, None)?;
    let bar = output::Progress::new(&lockstep, quiet);
    let start = WallInstant::now();
    let run = twin_app::app::run_headless(lockstep, |sim| bar.show(sim))?;
    let wall = start.elapsed().as_secs_f64();
    bar.finish();
    Ok((run, wall, recorder))
}

/// Logs the report and closes the MCAP file, if one is being written.
fn finish_mcap(
    recorder: Option<Recorder>,
    run: &Lockstep,
    report: &twin::report::Report,
    mcap: Option<(&Path, bool)>,
) -> Result<()> {
    if let Some(r) = recorder {
        r.finish(Some((report, run.now())))?;
    }
    if let Some((path, _)) = mcap {
        output::print_stdout(&format!("wrote {}\n", path.display()))?;
    }
    Ok(())
}

fn run(args: RunArgs) -> Result<ExitCode> {
    let loaded = RunSetup::load_or_default(args.scenario.as_deref())?.with_oracle(args.known.oracle());
    let out = args.out.unwrap_or_else(|| output::default_out_dir(&loaded.scenario.name));
    let mcap = args.mcap.as_deref().map(|p| (p, args.mcap_lz4));
    explobot::runlog::start();
    let headless = run_headless(loaded, args.seed, args.quiet, mcap);
    let log = explobot::runlog::take();
    let (run, wall, recorder) = headless?;
    let report = run.report(wall);
    output::print_stdout(&report.to_text())?;
    output::write_outputs(&out, &run, &report)?;
    let log_path = out.join("log.txt");
    std::fs::write(&log_path, log.text()).with_context(|| format!("writing {}", log_path.display()))?;
    output::print_stdout(&format!(
        "log             {} lines from Carto and Cute ({} warnings, {} errors) in {} (-v shows them here)\n",
        log.lines.len() as u64 + log.dropped,
        log.warnings,
        log.errors,
        log_path.display()
    ))?;
    output::print_stdout(&format!("wrote {}/report.json, map.png, links.rec, log.txt\n", out.display()))?;
    finish_mcap(recorder, &run, &report, mcap)?;
    Ok(if report.passed { ExitCode::SUCCESS } else { ExitCode::from(1) })
}

fn sim_serve(args: &ServeArgs) -> Result<ExitCode> {
    let options = args.options()?;
    let loaded = RunSetup::load_or_default(args.scenario.as_deref())?;
    let stop = serve::stop_on_ctrl_c().context("installing the Ctrl-C handler")?;
    // the twin keeps serving whatever happens to its standard output
    let say = |text: String| {
        let _ = output::print_stdout(&format!("{text}\n"));
    };
    let ready = |motor: &str, sensor: &str| say(args.ready_text(&loaded.scenario.name, motor, sensor));
    let status = |now, twin: &twin::hardware::Twin| say(serve::status_line(now, twin));
    let recorder = match args.foxglove {
        Some(addr) => {
            let r = Recorder::new().serve(addr)?;
            let port = r.port().unwrap_or(addr.port());
            say(format!(
                "foxglove: serving on ws://{}:{port} (open it in Foxglove or Lichtblick)",
                addr.ip()
            ));
            Some(r)
        }
        None => None,
    };
    let mut publisher = recorder.as_ref().map(|r| r.twin_publisher(&loaded));
    let clock = transport::WallClock::start();
    let served = serve::serve(&loaded, args.seed, &options, &clock, &stop, publisher.as_mut(), ready, status);
    drop(publisher);
    if let Some(r) = recorder {
        r.finish(None)?;
    }
    served?;
    say("twin stopped".to_string());
    Ok(ExitCode::SUCCESS)
}

fn replay(path: &Path, mcap: Option<(&Path, bool)>) -> Result<ExitCode> {
    let rec = Recording::load(path)?;
    let loaded = twin::replay::rebuild(&rec)?;
    output::print_stdout(&format!("replaying {} (seed {}) ...\n", rec.scenario_label, rec.seed))?;
    let (run, wall, recorder) = run_headless(loaded, Some(rec.seed), true, mcap)?;
    let (same, line) = twin::replay::verdict(&rec, run.link_logs());
    output::print_stdout(&format!("{line}\n"))?;
    finish_mcap(recorder, &run, &run.report(wall), mcap)?;
    Ok(if same { ExitCode::SUCCESS } else { ExitCode::from(1) })
}

fn bench_cmd(args: &BenchArgs) -> Result<ExitCode> {
    let scenarios = args.load()?;
    output::print_stdout(&format!("{}\n", bench::physics_header(args.steps, args.rounds)))?;
    for l in &scenarios {
        let figures = bench::physics(l, args.steps, usize::from(args.rounds));
        output::print_stdout(&bench::physics_rows(&l.scenario.name, &figures, l.dt()))?;
    }
    if !args.physics_only {
        output::print_stdout(&format!("\n{}\n", bench::full_stack_header()))?;
        for loaded in scenarios {
            let (run, wall, _) = run_headless(loaded, None, true, None)?;
            output::print_stdout(&format!("{}\n", bench::full_stack_row(&run.report(wall))))?;
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn check(scenarios: &[PathBuf]) -> Result<ExitCode> {
    let mut bad = 0;
    for path in scenarios {
        let (ok, line) = RunSetup::check_line(path);
        output::print_stdout(&format!("{line}\n"))?;
        bad += usize::from(!ok);
    }
    if bad > 0 {
        bail!("{bad} scenario file(s) with errors");
    }
    Ok(ExitCode::SUCCESS)
}
