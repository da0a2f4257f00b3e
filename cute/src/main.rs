//! `cute`: the operator's window on a running Carto, over TCP, in real time.
//!
//! A thin layer over the library: a [`Cute`] session, a [`TcpConnector`] dialling Carto with the
//! session's back-off, one Bevy system moving bytes between the socket and the session on the
//! wall clock, and [`CutePlugin`] for the map and the buttons.

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
use cute::{Compat, Cute, CuteConfig};
use robot_model::grid::Heading;
use robot_model::time::Instant;
use transport::{Clock, Connector, Link, TcpConnector, TcpLink, WallClock};

/// How long one connection attempt may block the frame.
const CONNECT_TIMEOUT: std::time::Duration = std::time::Duration::from_millis(200);

#[derive(Parser)]
#[command(name = "cute", version, about = "Cute: ExploBot's operator window (map, cartography, go-to)")]
struct Cli {
    /// Carto's address, HOST:PORT (e.g. 127.0.0.1:12345).
    #[arg(long, value_name = "HOST:PORT")]
    connect: String,
    /// Talk to the original 2024 Carto: `explobot-2024`.
    #[arg(long, value_name = "MODE")]
    compat: Option<String>,
    /// Map rows.
    #[arg(long, default_value_t = 20)]
    rows: usize,
    /// Map columns.
    #[arg(long, default_value_t = 20)]
    cols: usize,
    /// The robot's starting row.
    #[arg(long, default_value_t = 0)]
    start_row: u8,
    /// The robot's starting column.
    #[arg(long, default_value_t = 0)]
    start_col: u8,
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

/// The session and its socket.
#[derive(Resource)]
struct Remote {
    cute: Cute,
    connector: TcpConnector,
    link: Option<TcpLink>,
    clock: WallClock,
    unsent: Vec<u8>,
    last_error: Option<String>,
    start_cartography: bool,
}

impl CuteAccess for Remote {
    fn cute(&self) -> &Cute {
        &self.cute
    }
    fn cute_mut(&mut self) -> &mut Cute {
        &mut self.cute
    }
}

impl Remote {
    fn now(&self) -> Instant {
        self.clock.now()
    }

    fn drop_link(&mut self, now: Instant) {
        if self.link.take().is_some() {
            self.unsent.clear();
            self.cute.on_disconnected(now);
        }
    }

    /// One frame of I/O: connect when due, read, poll, write.
    fn pump(&mut self) {
        let now = self.now();
        if self.link.is_none() && self.cute.next_connect_at(now).is_some_and(|at| now >= at) {
            match self.connector.connect() {
                Ok(link) => {
                    tracing::info!(peer = link.peer_addr(), "connected");
                    self.last_error = None;
                    self.link = Some(link);
                    self.cute.on_connected(now);
                }
                Err(e) => {
                    let text = e.to_string();
                    if self.last_error.as_deref() != Some(text.as_str()) {
                        tracing::warn!("{text}");
                        self.last_error = Some(text);
                    }
                    self.cute.on_connect_failed(now);
                }
            }
        }
        let mut incoming = Vec::new();
        let mut alive = true;
        if let Some(link) = self.link.as_mut()
            && let Err(e) = link.read_available(&mut incoming)
        {
            tracing::warn!("{e}");
            alive = false;
        }
        if !incoming.is_empty() {
            self.cute.on_bytes(now, &incoming);
        }
        if !alive || self.cute.close_requested() {
            self.drop_link(now);
        }
        if self.start_cartography && self.cute.is_ready() {
            self.start_cartography = false;
            if let Err(e) = self.cute.start_cartography() {
                tracing::warn!("cannot start cartography: {e}");
            }
        }
        self.cute.poll(now);
        let out = self.cute.take_outgoing();
        if self.link.is_none() {
            return;
        }
        self.unsent.extend_from_slice(&out);
        if let Some(link) = self.link.as_mut()
            && !self.unsent.is_empty()
        {
            match link.write(&self.unsent) {
                Ok(n) => {
                    self.unsent.drain(..n);
                }
                Err(e) => {
                    tracing::warn!("{e}");
                    self.drop_link(now);
                }
            }
        }
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
    let compat = match cli.compat.as_deref() {
        Some(name) => name.parse::<Compat>()?,
        None => Compat::Default,
    };
    let cute = Cute::new(CuteConfig {
        rows: cli.rows,
        cols: cli.cols,
        start: (cli.start_row, cli.start_col),
        heading: cli.heading,
        compat,
        ..CuteConfig::default()
    })
    .context("bad map settings")?;
    let remote = Remote {
        cute,
        connector: TcpConnector::new(cli.connect.clone()).timeout(CONNECT_TIMEOUT),
        link: None,
        clock: WallClock::start(),
        unsent: Vec::new(),
        last_error: None,
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
