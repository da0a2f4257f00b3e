#![doc = include_str!("../README.md")]
//! `carto`: the robot controller binary, a thin shell over [`carto::CartoRuntime`].

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration as StdDuration;

use anyhow::{Context, Result, bail};
use carto::{Carto, CartoConfig, CartoRuntime};
use clap::{Parser, ValueEnum};
use robot_model::profile::RobotProfile;
use robot_model::time::Instant;
use transport::{Clock, DynLink, SerialLink, TcpLink, TcpListenerLink, WallClock};

const DEFAULT_PROFILE: &str = "scenarios/robots/mecanum-4wd.ron";

/// How Carto reaches the boards.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum TransportKind {
    /// The twin's pseudo-terminals (`explobot sim <scenario> --serve`), opened by path.
    Sim,
    /// Real UARTs, opened by path.
    Serial,
    /// The twin's board ports over TCP (HOST:PORT).
    Tcp,
}

/// ExploBot's controller: serves Cute on TCP and drives the motor and sensor boards.
#[derive(Debug, Parser)]
#[command(name = "carto", version, about)]
struct Args {
    /// How to reach the boards.
    #[arg(long, value_enum, default_value_t = TransportKind::Sim)]
    transport: TransportKind,
    /// Motor board: a device path (sim: run/tty-motor, serial: /dev/ttyAMA0) or HOST:PORT (tcp).
    #[arg(long)]
    motor_port: Option<String>,
    /// Sensor board: a device path (sim: run/tty-sensor, serial: /dev/ttyUSB0) or HOST:PORT (tcp).
    #[arg(long)]
    sensor_port: Option<String>,
    /// Address Cute connects to.
    #[arg(long, default_value = "0.0.0.0:12345")]
    listen: String,
    /// Robot profile (RON); default scenarios/robots/mecanum-4wd.ron if present, else built in.
    #[arg(long)]
    profile: Option<PathBuf>,
}

fn main() {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info")),
        )
        .with_writer(std::io::stderr)
        .init();
    if let Err(e) = run(Args::parse()) {
        eprintln!("carto: error: {e:#}");
        std::process::exit(1);
    }
}

fn load_profile(path: Option<&Path>) -> Result<RobotProfile> {
    match path {
        Some(p) => {
            RobotProfile::load(p).with_context(|| format!("cannot load the robot profile {}", p.display()))
        }
        None if Path::new(DEFAULT_PROFILE).exists() => RobotProfile::load(DEFAULT_PROFILE)
            .with_context(|| format!("cannot load the robot profile {DEFAULT_PROFILE}")),
        None => {
            tracing::info!("no {DEFAULT_PROFILE} here: using the built-in default robot");
            Ok(RobotProfile::default())
        }
    }
}

fn open_board(kind: TransportKind, which: &str, port: &str, baud: u32) -> Result<DynLink> {
    let link: DynLink = match kind {
        TransportKind::Sim | TransportKind::Serial => Box::new(
            SerialLink::builder(port, baud)
                .open()
                .with_context(|| format!("cannot open the {which} board port {port} ({baud} baud)"))?,
        ),
        TransportKind::Tcp => Box::new(
            TcpLink::connect_timeout(port, StdDuration::from_secs(3))
                .with_context(|| format!("cannot connect to the {which} board at {port}"))?,
        ),
    };
    tracing::info!(board = which, port, baud, "board link open");
    Ok(link)
}

fn default_port(kind: TransportKind, which: &str) -> Result<String> {
    Ok(match (kind, which) {
        (TransportKind::Sim, "motor") => "run/tty-motor".to_owned(),
        (TransportKind::Sim, _) => "run/tty-sensor".to_owned(),
        (TransportKind::Serial, "motor") => "/dev/ttyAMA0".to_owned(),
        (TransportKind::Serial, _) => "/dev/ttyUSB0".to_owned(),
        (TransportKind::Tcp, _) => bail!("--transport tcp needs --{which}-port HOST:PORT"),
    })
}

fn run(args: Args) -> Result<()> {
    let profile = load_profile(args.profile.as_deref())?;
    let cfg = CartoConfig::from_profile(&profile);
    let motor_port = match args.motor_port.clone() {
        Some(p) => p,
        None => default_port(args.transport, "motor")?,
    };
    let sensor_port = match args.sensor_port.clone() {
        Some(p) => p,
        None => default_port(args.transport, "sensor")?,
    };
    let motor = open_board(args.transport, "motor", &motor_port, profile.serial.motor_baud)?;
    let sensor = open_board(args.transport, "sensor", &sensor_port, profile.serial.sensor_baud)?;
    let listener = TcpListenerLink::bind(args.listen.as_str())
        .with_context(|| format!("cannot listen on {}", args.listen))?;
    tracing::info!(
        listen = %listener.local_addr(),
        robot = %profile.name,
        cell_m = cfg.cell_size_m,
        "carto ready: waiting for Cute"
    );

    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = Arc::clone(&stop);
        ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst))
            .context("cannot install the Ctrl-C handler")?;
    }

    let clock = WallClock::start();
    let now = || clock.now();
    let mut rt = CartoRuntime::new(Carto::new(cfg), listener, motor, sensor);
    let mut next_status = Instant::ZERO;
    let mut failure = None;
    while !stop.load(Ordering::SeqCst) {
        let t = now();
        let report = rt.step(t);
        let lost: Vec<String> =
            [(report.motor_lost, "motor", &motor_port), (report.sensor_lost, "sensor", &sensor_port)]
                .into_iter()
                .filter(|(lost, _, _)| *lost)
                .map(|(_, which, port)| format!("the {which} board link ({port})"))
                .collect();
        if !lost.is_empty() {
            failure = Some(format!("{} lost", lost.join(" and ")));
            break;
        }
        if t >= next_status {
            next_status = t + robot_model::time::Duration::from_secs(10);
            tracing::debug!(status = ?rt.carto().status(), stats = ?rt.carto().stats(), "status");
        }
        std::thread::sleep(StdDuration::from_millis(1));
    }

    // Stop the motors before leaving, whatever the reason.
    let mut flushed = rt.stop_motors(now());
    for _ in 0..50 {
        if flushed {
            break;
        }
        std::thread::sleep(StdDuration::from_millis(2));
        flushed = rt.flush(now());
    }
    if rt.motor_up() && !flushed {
        tracing::warn!("the stop command could not be written completely");
    }
    tracing::info!(stats = ?rt.carto().stats(), "carto stopped");
    match failure {
        Some(f) => bail!(f),
        None => Ok(()),
    }
}
