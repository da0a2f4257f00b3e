//! `cute`: the operator's window on a running Carto, over TCP, in real time.
//!
//! A thin layer over the library: a [`CuteRuntime`] dialling Carto with a [`TcpConnector`] (the
//! session's back-off), pumped by one Bevy system on the wall clock, and [`CutePlugin`] for the
//! map and the buttons.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use bevy::app::{App, AppExit, Startup, Update};
use bevy::ecs::system::{Res, ResMut};
use bevy::prelude::{ClearColor, Resource};
use clap::Parser;
use cute::gui::{
    AutoScreenshot, BACKGROUND, CuteAccess, CutePlugin, continuous_updates, setup_camera, window_plugins,
};
use cute::{Compat, Cute, CuteConfig, CuteRuntime};
use robot_model::grid::Heading;
use robot_model::time::Instant;
use transport::{Clock, TcpConnector, WallClock};

/// How long one connection attempt may block the frame.
const CONNECT_TIMEOUT: std::time::Duration = std::time::Duration::from_millis(200);

#[derive(Parser)]
#[command(name = "cute", version, about = "Cute: ExploBot's operator window (map, cartography, go-to)")]
struct Cli {
    /// Carto's address, HOST:PORT (e.g. 127.0.0.1:12345).
    #[arg(long, value_name = "HOST:PORT")]
    connect: String,
    /// Which Carto is on the other end. `explobot-2024`, the original 2024 Carto: little-endian
    /// `Msg`, trajectories only (batches of at most 50, no answer expected), a click plans through
    /// unknown cells as if free (with a warning), and after a STOP the original drops the next
    /// batch, so Cute keeps the robot where it was and warns when it sends that batch.
    #[arg(long, value_enum, value_name = "MODE", default_value_t = Compat::Default)]
    compat: Compat,
    /// A known map to start from: one line per row, one digit per cell (0 obstacle, 1 free,
    /// 2 unknown, 3 waypoint, 4 destination, 5 robot), `#` comments; sets rows, columns and, if
    /// it has a 5, the start cell.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["rows", "cols"])]
    map: Option<PathBuf>,
    /// Map rows.
    #[arg(long, default_value_t = 20)]
    rows: usize,
    /// Map columns.
    #[arg(long, default_value_t = 20)]
    cols: usize,
    /// The robot's starting row (default 0, or the row of the map's 5).
    #[arg(long)]
    start_row: Option<u8>,
    /// The robot's starting column (default 0, or the column of the map's 5).
    #[arg(long)]
    start_col: Option<u8>,
    /// The robot's starting heading: north, south, east or west.
    #[arg(long, default_value = "east")]
    heading: Heading,
    /// Start cartography as soon as Carto acknowledges the position (demos, screenshots).
    #[arg(long)]
    cartography: bool,
    /// Save a PNG of the window after `--screenshot-after` seconds, then exit.
    #[arg(long, value_name = "FILE")]
    screenshot: Option<PathBuf>,
    /// Wall-clock seconds before the screenshot.
    #[arg(long, default_value_t = 3.0, value_name = "SECONDS")]
    screenshot_after: f64,
}

/// The session, its socket and the wall clock.
#[derive(Resource)]
struct Remote {
    runtime: CuteRuntime<TcpConnector>,
    clock: WallClock,
    start_cartography: bool,
}

impl CuteAccess for Remote {
    fn cute(&self) -> &Cute {
        self.runtime.cute()
    }
    fn cute_mut(&mut self) -> &mut Cute {
        self.runtime.cute_mut()
    }
}

impl Remote {
    fn now(&self) -> Instant {
        self.clock.now()
    }

    /// One frame of I/O; `--cartography` starts mapping once Carto has acknowledged the position.
    fn pump(&mut self) {
        let now = self.now();
        let start = &mut self.start_cartography;
        self.runtime.step_with(now, |cute| {
            if *start && cute.is_ready() {
                *start = false;
                if let Err(e) = cute.start_cartography() {
                    tracing::warn!("cannot start cartography: {e}");
                }
            }
        });
    }
}

fn pump(mut remote: ResMut<Remote>) {
    remote.pump();
}

fn screenshot_when_due(remote: Res<Remote>, after: Res<ScreenshotAfter>, mut shot: ResMut<AutoScreenshot>) {
    if remote.now().as_secs_f64() >= after.0 {
        shot.ready = true;
    }
}

#[derive(Resource)]
struct ScreenshotAfter(f64);

fn run(cli: Cli) -> Result<ExitCode> {
    let given = match (cli.start_row, cli.start_col) {
        (None, None) => None,
        (row, col) => Some((row.unwrap_or(0), col.unwrap_or(0))),
    };
    let mut config = CuteConfig {
        rows: cli.rows,
        cols: cli.cols,
        start: given.unwrap_or((0, 0)),
        heading: cli.heading,
        compat: cli.compat,
        ..CuteConfig::default()
    };
    if let Some(path) = &cli.map {
        let map = cute::load_map(path)?;
        config = config.with_map(map, given).with_context(|| format!("{}", path.display()))?;
    }
    let cute = Cute::new(config).context("bad map settings")?;
    let connector = TcpConnector::new(cli.connect.clone()).timeout(CONNECT_TIMEOUT);
    let remote = Remote {
        runtime: CuteRuntime::new(cute, connector),
        clock: WallClock::start(),
        start_cartography: cli.cartography,
    };
    let mut app = App::new();
    app.add_plugins(window_plugins(&format!("Cute — {}", cli.connect), 1024, 768, false))
        .insert_resource(continuous_updates())
        .insert_resource(ClearColor(BACKGROUND))
        .insert_resource(remote)
        .add_plugins(CutePlugin::<Remote>::new())
        .add_systems(Startup, setup_camera)
        .add_systems(Update, pump);
    if let Some(path) = cli.screenshot {
        app.insert_resource(AutoScreenshot::new(path))
            .insert_resource(ScreenshotAfter(cli.screenshot_after))
            .add_systems(Update, screenshot_when_due);
    }
    Ok(match app.run() {
        AppExit::Success => ExitCode::SUCCESS,
        AppExit::Error(_) => ExitCode::FAILURE,
    })
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn".into()),
        )
        .with_writer(std::io::stderr)
        .init();
    match run(Cli::parse()) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("cute: {e:#}");
            ExitCode::from(2)
        }
    }
}
