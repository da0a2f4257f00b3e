//! `explobot`: the twin's command-line tool. A thin layer over the `sim` library.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant as WallInstant;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use sim::app::{Mode, Sim, make_app};
use sim::bench::{self, SonarLoad};
use sim::mapimg::MapPicture;
use sim::record::{FORMAT_VERSION, Recording, first_divergence};
use sim::report::Report;
use sim::runner::Lockstep;
use sim::scenario::LoadedScenario;
use sim::wiretool;

#[derive(Parser)]
#[command(
    name = "explobot",
    version,
    about = "ExploBot Twin: run Carto and Cute against a physics twin of the robot"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scenario headless: progress bar, report, runs/NAME/{report.json,map.png,links.rec}.
    Run {
        /// Scenario file (RON); the built-in default room when omitted.
        scenario: Option<PathBuf>,
        /// Seed for every random process (default: the scenario's).
        #[arg(long)]
        seed: Option<u64>,
        /// Output folder (default: runs/NAME).
        #[arg(long)]
        out: Option<PathBuf>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Open the interactive window instead (world beside Cute's map; feature `window`).
        #[arg(long)]
        window: bool,
        #[command(flatten)]
        shot: ScreenshotArgs,
    },
    /// Open the interactive window on a scenario: the true world beside Cute's map, Cute's
    /// buttons, time controls (feature `window`).
    Window {
        /// Scenario file (RON); the built-in default room when omitted.
        scenario: Option<PathBuf>,
        /// Seed for every random process (default: the scenario's).
        #[arg(long)]
        seed: Option<u64>,
        #[command(flatten)]
        shot: ScreenshotArgs,
    },
    /// Run the twin in real time with its boards on pseudo-terminals (run/tty-motor,
    /// run/tty-sensor) or TCP ports, for the real `carto` binary to drive.
    Sim {
        /// Scenario file (RON); the built-in default room when omitted.
        scenario: Option<PathBuf>,
        /// Serve the boards (required: the twin has no other real-time mode).
        #[arg(long, required = true)]
        serve: bool,
        /// Expose the boards as TCP ports BASE (motor) and BASE+1 (sensor) instead of ptys.
        #[arg(long, value_name = "BASE")]
        tcp: Option<u16>,
        /// Address the TCP ports bind to.
        #[arg(long, default_value = "127.0.0.1")]
        bind: String,
        /// Folder for the pty symlinks.
        #[arg(long, default_value = "run")]
        run_dir: PathBuf,
        /// Simulated seconds per wall-clock second.
        #[arg(long, default_value_t = 1.0)]
        speed: f64,
        /// Stop after this many simulated seconds (default: run until Ctrl-C).
        #[arg(long)]
        duration: Option<f64>,
        /// Seed (default: the scenario's).
        #[arg(long)]
        seed: Option<u64>,
        /// Print the robot's pose this often, simulated seconds (0 = never).
        #[arg(long, default_value_t = 1.0)]
        status_every: f64,
    },
    /// Decode frames from hex bytes: each frame, resync notes, checksum verdicts.
    Decode(wiretool::DecodeArgs),
    /// Encode one frame and print it as hex, e.g. `encode --protocol motor drive-v2 50 0 -20 6`.
    Encode(wiretool::EncodeArgs),
    /// Re-run a recording (links.rec) and report the first byte where the new run differs.
    Replay {
        /// The recording.
        recording: PathBuf,
    },
    /// Print throughput figures: physics steps/s (sonar off, per cycle, every step) and full-stack
    /// real-time factor per scenario.
    Bench {
        /// Scenarios (default: the built-in default room).
        scenarios: Vec<PathBuf>,
        /// Physics steps per round of a physics measurement.
        #[arg(long, default_value_t = 100_000)]
        steps: u64,
        /// Rounds per physics measurement (the median and the best round are printed).
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u16).range(1..))]
        rounds: u16,
        /// Only the physics figures.
        #[arg(long)]
        physics_only: bool,
    },
    /// Check scenario files (syntax, values, start cell) without running them.
    Check {
        /// Scenario files.
        #[arg(required = true)]
        scenarios: Vec<PathBuf>,
    },
    /// Write a realistic generated room (flat, office, warehouse, pillars, irregular) as a
    /// scenario file; the same style and seed always give the same file.
    Generate(sim::generate::GenerateArgs),
    /// Run many rooms × seeds on every core (or one shard of them), or merge shard folders.
    Sweep(sim::sweep::SweepArgs),
}

/// Window screenshots (tests, docs).
#[derive(clap::Args, Clone)]
struct ScreenshotArgs {
    /// Run at full speed to --screenshot-after sim seconds, save a PNG of the window, exit
    /// (implies --window).
    #[arg(long, value_name = "FILE")]
    screenshot: Option<PathBuf>,
    /// Sim seconds before the screenshot.
    #[arg(long, default_value_t = 10.0, value_name = "SECONDS")]
    screenshot_after: f64,
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn".into()),
        )
        .with_writer(std::io::stderr)
        .init();
    let cli = Cli::parse();
    let result = match cli.command.unwrap_or(Command::Run {
        scenario: None,
        seed: None,
        out: None,
        quiet: false,
        window: false,
        shot: ScreenshotArgs { screenshot: None, screenshot_after: 10.0 },
    }) {
        Command::Run { scenario, seed, window: true, shot, .. }
        | Command::Window { scenario, seed, shot }
        | Command::Run { scenario, seed, shot: shot @ ScreenshotArgs { screenshot: Some(_), .. }, .. } => {
            window_cmd(scenario.as_deref(), seed, shot)
        }
        Command::Run { scenario, seed, out, quiet, .. } => run(scenario.as_deref(), seed, out, quiet),
        Command::Sim { scenario, serve: _, tcp, bind, run_dir, speed, duration, seed, status_every } => {
            sim_serve(scenario.as_deref(), tcp, &bind, run_dir, speed, duration, seed, status_every)
        }
        Command::Decode(args) => args.decode().map_err(anyhow::Error::from).map(|text| {
            print!("{text}");
            ExitCode::SUCCESS
        }),
        Command::Encode(args) => args.encode().map_err(anyhow::Error::from).map(|bytes| {
            println!("{}", wiretool::to_hex(&bytes));
            ExitCode::SUCCESS
        }),
        Command::Replay { recording } => replay(&recording),
        Command::Bench { scenarios, steps, rounds, physics_only } => {
            bench_cmd(&scenarios, steps, rounds, physics_only)
        }
        Command::Check { scenarios } => check(&scenarios),
        Command::Generate(args) => args.run().map(|()| ExitCode::SUCCESS).map_err(anyhow::Error::from),
        Command::Sweep(args) => args.run().map_err(anyhow::Error::from),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("explobot: {e:#}");
            ExitCode::from(2)
        }
    }
}

/// `explobot window` / `explobot run --window`: the interactive window, or one screenshot of it.
#[cfg(feature = "window")]
fn window_cmd(scenario: Option<&Path>, seed: Option<u64>, shot: ScreenshotArgs) -> Result<ExitCode> {
    let lockstep = Lockstep::new(load(scenario)?, seed)?;
    let mut app = make_app(Mode::Window, lockstep);
    if let Some(path) = shot.screenshot {
        if !(shot.screenshot_after.is_finite() && shot.screenshot_after >= 0.0) {
            bail!("--screenshot-after must be a number of seconds >= 0");
        }
        sim::window::request_screenshot(&mut app, path, shot.screenshot_after);
    }
    Ok(match app.run() {
        bevy::app::AppExit::Success => ExitCode::SUCCESS,
        bevy::app::AppExit::Error(_) => ExitCode::FAILURE,
    })
}

#[cfg(not(feature = "window"))]
fn window_cmd(_scenario: Option<&Path>, _seed: Option<u64>, shot: ScreenshotArgs) -> Result<ExitCode> {
    let _ = (shot.screenshot, shot.screenshot_after);
    bail!(
        "this explobot was built without the window; rebuild with `cargo build --release -p sim --features window`"
    )
}

fn load(scenario: Option<&Path>) -> Result<LoadedScenario> {
    Ok(match scenario {
        Some(path) => LoadedScenario::load(path)?,
        None => LoadedScenario::builtin_default()?,
    })
}

/// Runs a scenario to the end in the headless Bevy app, with a progress bar.
fn run_headless(loaded: LoadedScenario, seed: Option<u64>, quiet: bool) -> Result<(Lockstep, f64)> {
    let lockstep = Lockstep::new(loaded, seed)?;
    let limit = lockstep.time_limit().as_secs_f64();
    let bar = if quiet { ProgressBar::hidden() } else { ProgressBar::new(limit.ceil() as u64) };
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} s sim  {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut app = make_app(Mode::Headless, lockstep);
    let start = WallInstant::now();
    loop {
        let sim = &app.world().resource::<Sim>().0;
        if sim.is_finished() {
            break;
        }
        bar.set_position(sim.now().as_secs_f64() as u64);
        bar.set_message(format!("{:?}", sim.cute().status()));
        app.update();
    }
    let wall = start.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let sim = app.world_mut().remove_resource::<Sim>().context("the simulation resource disappeared")?;
    Ok((sim.0, wall))
}

fn run(scenario: Option<&Path>, seed: Option<u64>, out: Option<PathBuf>, quiet: bool) -> Result<ExitCode> {
    let loaded = load(scenario)?;
    let (text, label) = (loaded.text.clone(), loaded.label.clone());
    let out = out.unwrap_or_else(|| Path::new("runs").join(&loaded.scenario.name));
    let profile_ron = loaded.profile.to_ron_string().context("writing the profile into the recording")?;
    let (run, wall) = run_headless(loaded, seed, quiet)?;
    let report = run.report(wall);
    print!("{}", report.to_text());
    write_outputs(
        &out,
        &run,
        &report,
        Recording {
            version: FORMAT_VERSION,
            scenario_label: label,
            scenario_ron: text,
            profile_ron,
            seed: run.seed(),
            logs: run.link_logs().to_vec(),
        },
    )?;
    println!("wrote {}/report.json, map.png, links.rec", out.display());
    Ok(if report.passed { ExitCode::SUCCESS } else { ExitCode::from(1) })
}

fn write_outputs(out: &Path, run: &Lockstep, report: &Report, recording: Recording) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let json = serde_json::to_string_pretty(report)?;
    std::fs::write(out.join("report.json"), json + "\n").context("writing report.json")?;
    let scenario = &run.loaded().scenario;
    let pose = run.body().pose();
    let geometry = &run.loaded().profile.geometry;
    let known = run.known_cells();
    let picture = MapPicture {
        scenario,
        frame: run.frame(),
        known: &known,
        trail: run.trail(),
        pose: (pose.x, pose.y, pose.theta),
        body: (geometry.body_length_m, geometry.body_width_m),
    };
    picture.render().save(out.join("map.png")).context("writing map.png")?;
    recording.save(&out.join("links.rec"))?;
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn sim_serve(
    scenario: Option<&Path>,
    tcp: Option<u16>,
    bind: &str,
    run_dir: PathBuf,
    speed: f64,
    duration: Option<f64>,
    seed: Option<u64>,
    status_every: f64,
) -> Result<ExitCode> {
    use robot_model::time::Duration;
    use sim::serve::{Ports, ServeOptions, serve};
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};

    if !(speed.is_finite() && speed > 0.0) {
        bail!("--speed must be a positive number");
    }
    let loaded = load(scenario)?;
    let ports = match tcp {
        Some(base) => {
            let sensor_port = base.checked_add(1).context("--tcp BASE must leave room for BASE+1")?;
            Ports::Tcp {
                motor: format!("{bind}:{base}")
                    .parse()
                    .with_context(|| format!("bad --bind address {bind}"))?,
                sensor: format!("{bind}:{sensor_port}")
                    .parse()
                    .with_context(|| format!("bad --bind address {bind}"))?,
            }
        }
        None => Ports::Pty { dir: run_dir },
    };
    let options = ServeOptions {
        ports,
        speed,
        duration: duration.map(Duration::from_secs_f64),
        status_every: (status_every > 0.0).then(|| Duration::from_secs_f64(status_every)),
    };
    let stop = Arc::new(AtomicBool::new(false));
    let on_signal = stop.clone();
    ctrlc::set_handler(move || on_signal.store(true, Ordering::SeqCst))
        .context("installing the Ctrl-C handler")?;
    let clock = transport::WallClock::start();
    let ready = |motor: &str, sensor: &str| {
        println!("twin of '{}' serving at {speed}x real time", loaded.scenario.name);
        println!("motor board  {motor}");
        println!("sensor board {sensor}");
        println!("start Carto with: carto --transport {}", if tcp.is_some() { "tcp" } else { "sim" });
    };
    let status = |now: robot_model::time::Instant, twin: &sim::twin::Twin| {
        let p = twin.body().pose();
        let cell = twin.cell().map_or("off grid".to_string(), |(r, c)| format!("({r}, {c})"));
        println!(
            "t={:>8.2}s  x={:.3} y={:.3} heading={:6.1}deg  cell {cell}  wheels {:?} rpm",
            now.as_secs_f64(),
            p.x,
            p.y,
            p.theta.to_degrees(),
            twin.motor_board().wheel_setpoints_rpm().map(|v| v.round())
        );
    };
    serve(&loaded, seed, &options, &clock, &stop, ready, status)?;
    println!("twin stopped");
    Ok(ExitCode::SUCCESS)
}

fn replay(path: &Path) -> Result<ExitCode> {
    let rec = Recording::load(path)?;
    // The recording carries the profile that ran, so the scenario's own `robot` file is not
    // needed (nor read): the run is rebuilt from the recording alone.
    let mut scenario = sim::scenario::Scenario::from_ron_str(&rec.scenario_ron, &rec.scenario_label)?;
    scenario.robot = None;
    let mut loaded = LoadedScenario::from_scenario(scenario)?;
    loaded.profile = robot_model::profile::RobotProfile::from_ron_str(&rec.profile_ron, "<recorded profile>")
        .context("the recording's robot profile")?;
    println!("replaying {} (seed {}) ...", rec.scenario_label, rec.seed);
    let (run, _) = run_headless(loaded, Some(rec.seed), true)?;
    match first_divergence(&rec.logs, run.link_logs()) {
        None => {
            println!("identical: {} endpoint logs, sha256 {}", rec.logs.len(), rec.link_hash());
            Ok(ExitCode::SUCCESS)
        }
        Some(d) => {
            println!("DIVERGED at {d}");
            Ok(ExitCode::from(1))
        }
    }
}

fn bench_cmd(scenarios: &[PathBuf], steps: u64, rounds: u16, physics_only: bool) -> Result<ExitCode> {
    let list: Vec<Option<&Path>> =
        if scenarios.is_empty() { vec![None] } else { scenarios.iter().map(|p| Some(p.as_path())).collect() };
    println!("physics: {steps} steps of the robot in each room, {rounds} rounds per variant, one thread");
    println!(
        "{:<20} {:<12} {:>16} {:>14} {:>12} {:>11}",
        "scenario", "sonar", "median steps/s", "best steps/s", "x real time", "collisions"
    );
    for s in &list {
        let loaded = load(*s)?;
        let dt =
            robot_model::time::Duration::from_secs_f64(f64::from(loaded.scenario.physics.step_ms) / 1000.0);
        for f in bench::physics(&loaded, steps, usize::from(rounds)) {
            let label = match f.sonar {
                SonarLoad::Off => "off",
                SonarLoad::PerCycle => "60 ms cycle",
                SonarLoad::EveryStep => "every step",
            };
            println!(
                "{:<20} {:<12} {:>16.0} {:>14.0} {:>12.0} {:>11}",
                loaded.scenario.name,
                label,
                f.median_steps_per_s(),
                f.best_steps_per_s(),
                f.real_time_factor(dt),
                f.collisions
            );
        }
    }
    if physics_only {
        return Ok(ExitCode::SUCCESS);
    }
    println!();
    println!("full stack: Cute + Carto + boards + physics, real bytes on every link, headless");
    println!("{:<20} {:>10} {:>10} {:>12} {:>10}", "scenario", "sim s", "wall s", "x real time", "result");
    for s in &list {
        let loaded = load(*s)?;
        let (run, wall) = run_headless(loaded, None, true)?;
        let r = run.report(wall);
        let verdict = if r.passed { "pass" } else { "FAIL" };
        println!(
            "{:<20} {:>10.1} {:>10.2} {:>12.0} {:>10}",
            r.scenario, r.sim_time_s, r.wall_time_s, r.real_time_factor, verdict
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn check(scenarios: &[PathBuf]) -> Result<ExitCode> {
    let mut bad = 0;
    for p in scenarios {
        match LoadedScenario::load(p) {
            Ok(l) => {
                let g = sim::grid::TruthGrid::build(&l.scenario, &l.profile);
                let start = (l.scenario.start.row as usize, l.scenario.start.col as usize);
                let reachable = g.reachable_from(start).iter().filter(|r| **r).count();
                println!("ok   {}: {}x{} grid, {reachable} reachable cells", p.display(), g.rows, g.cols);
            }
            Err(e) => {
                bad += 1;
                println!("FAIL {e}");
            }
        }
    }
    if bad > 0 {
        bail!("{bad} scenario file(s) with errors");
    }
    Ok(ExitCode::SUCCESS)
}
