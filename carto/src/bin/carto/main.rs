#![doc = include_str!("../../../README.md")]
//! `carto`: the robot controller binary, a thin shell over [`carto::CartoRuntime`] that owns the
//! wall clock, the signals and the ports.
//!
//! Every way it ends that a process can catch stops the motors first (a bare stop frame,
//! drained for at most [`DRAIN_LIMIT`]), logs why and exits with a documented code. Every signal
//! whose default action ends a process and that may be caught ([`stop_signals`]: SIGTERM,
//! SIGINT, SIGHUP, SIGQUIT, SIGUSR1, SIGUSR2, SIGALRM, SIGVTALRM, SIGPROF, SIGIO, SIGPWR,
//! SIGSTKFLT, SIGXCPU, SIGXFSZ, SIGSYS, SIGTRAP, SIGABRT and the real-time signals) only sets a
//! flag and wakes the loop; SIGPIPE is ignored (Rust's runtime does so), so a write to a closed
//! socket is an error that ends that session, not Carto. SIGKILL and SIGSTOP cannot be caught:
//! then the motor board's own watchdog stops the wheels (`carto/README.md`, "The daemon on the robot").
//!
//! The loop sleeps in `poll(2)` on the board links, the listener, the client and the signal
//! pipe, until a byte arrives or Carto's next deadline ([`CartoRuntime::next_deadline`]): every
//! millisecond while a move runs, as before, and up to the next keep-state or resend when idle.
//!
//! | code | why |
//! |---|---|
//! | 0 | SIGTERM, SIGINT or SIGHUP |
//! | 128 + N | any other caught signal N (SIGQUIT 131, SIGUSR1 138, …), after the same stop |
//! | 1 | a fatal error while running (a board link lost with `--exit-on-link-loss`, the listener failing) |
//! | 2 | it could not start: bad arguments, unreadable profile, address not available (with `--exit-on-link-loss`, a board port that does not open) |
//! | 3 | an internal error (a panic) |

use std::io::Read;
use std::os::fd::AsFd;
use std::os::unix::net::UnixStream;
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration as StdDuration;

mod boards;
mod signals;

use anyhow::{Context, Result, bail};
use boards::{Board, BoardLink};
use carto::backoff::Backoff;
use carto::recording::{MaybeTraced, TracedListener};
use carto::{Carto, CartoConfig, CartoRuntime};
use clap::{Parser, ValueEnum};
use nix::poll::{PollFd, PollFlags, PollTimeout, poll};
use robot_model::profile::RobotProfile;
use robot_model::time::{Duration, Instant};
use signals::{signal_exit_code, signal_name, stop_signals};
use transport::recorder::{Recorder, RecorderConfig};
use transport::recording::{FORMAT_VERSION, Oracle, Recording};
use transport::{Clock, KeepAlive, TcpListenerLink, TraceHandle, WallClock};

const DEFAULT_PROFILE: &str = "scenarios/robots/mecanum-4wd.ron";
/// Longest wait for the stop frame to leave on the way out.
const DRAIN_LIMIT: StdDuration = StdDuration::from_millis(200);
/// Longest a reconnection to a board over TCP may block the loop.
const BOARD_CONNECT_TIMEOUT: StdDuration = StdDuration::from_millis(200);

/// Longest the loop sleeps when nothing is due (a bound, not a cadence).
const MAX_WAIT: StdDuration = StdDuration::from_secs(1);
/// Bytes read and discarded from a client closed after a protocol error, so it sees a clean close.
const DRAIN_ON_CLOSE: usize = 1 << 20;

const EXIT_FATAL: u8 = 1;
const EXIT_START: u8 = 2;
const EXIT_PANIC: u8 = 3;

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
    /// Exit (code 1, or 2 at start) when a board link is lost or cannot be opened, instead of
    /// retrying with back-off: for a supervisor that restarts Carto.
    #[arg(long)]
    exit_on_link_loss: bool,
    /// Close a client that sends nothing for this many seconds and serve the next (0 = never).
    #[arg(long, value_name = "SECONDS", default_value_t = 0.0)]
    client_idle_limit: f64,
    /// Drop a client whose host answers neither bytes nor TCP keepalive probes for about this many
    /// seconds (0 = the system's keepalive, i.e. off).
    #[arg(long, value_name = "SECONDS", default_value_t = 15.0)]
    client_dead_after: f64,
    /// Grid cell size, metres (default: the profile's): one FORWARD drives this far, and it must
    /// be the cell size Cute and the room use. The obstacle threshold follows it (one cell).
    #[arg(long, value_name = "METRES")]
    cell: Option<f64>,
    /// Before each FORWARD, look this far left and right with the sonar and refuse the move when
    /// an echo lies in the body's path (0 = off, the default). docs/explanation/carto-design.md.
    #[arg(long, value_name = "DEGREES", default_value_t = 0.0)]
    scan_deg: f64,
    /// Record every byte of both board links and of each client connection, with its time, to
    /// FILE (the twin's `links.rec` format; endpoints `motor`/`carto`, `sensor`/`carto`,
    /// `gui`/`carto#N`). The file is rewritten every --record-flush seconds, always complete.
    #[arg(long, value_name = "FILE")]
    record: Option<PathBuf>,
    /// Largest recording, MiB: past it later bytes are not recorded (logged once).
    #[arg(long, value_name = "MIB", default_value_t = 16.0, requires = "record")]
    record_max_mib: f64,
    /// Seconds between two rewrites of the recording: what a power cut may lose.
    #[arg(long, value_name = "SECONDS", default_value_t = 10.0, requires = "record")]
    record_flush: f64,
    /// Drive the calibration plan (`carto::calibration`, about a minute) as soon as both boards answer,
    /// then stop the motors and exit 0. With --record, the recording `explobot calibrate` fits
    /// a profile to. Stand the robot 1.5 m from a flat wall, facing it.
    #[arg(long)]
    calibration_drive: bool,
}

/// Why the main loop ended.
enum Ended {
    Signal(usize),
    /// `--calibration-drive` is over.
    CalibrationDone,
    Fatal(String),
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info")),
        )
        .with_writer(std::io::stderr)
        .init();
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        tracing::error!(%info, "panic: stopping the motors");
        default_hook(info);
    }));
    let args = Args::parse();
    // Signals first: from here on every catchable terminating signal only sets this flag and
    // writes a byte to the wake pipe that the loop polls.
    let signal = Arc::new(AtomicUsize::new(0));
    let (wake_rx, wake_tx) = match UnixStream::pair().and_then(|(rx, tx)| {
        rx.set_nonblocking(true)?;
        tx.set_nonblocking(true)?;
        Ok((rx, tx))
    }) {
        Ok(pair) => pair,
        Err(e) => {
            eprintln!("carto: error: cannot create the signal pipe: {e}");
            return ExitCode::from(EXIT_START);
        }
    };
    for sig in stop_signals() {
        let installed = signal_hook::flag::register_usize(sig, Arc::clone(&signal), sig as usize)
            .and_then(|_| wake_tx.try_clone())
            .and_then(|tx| signal_hook::low_level::pipe::register(sig, tx));
        if let Err(e) = installed {
            eprintln!(
                "carto: error: cannot install the handler of signal {}: {e}",
                signal_name(sig as usize)
            );
            return ExitCode::from(EXIT_START);
        }
    }
    let mut daemon = match Daemon::start(args, signal, wake_rx) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("carto: error: {e:#}");
            tracing::error!(exit_code = EXIT_START, "carto could not start: {e:#}");
            return ExitCode::from(EXIT_START);
        }
    };
    let outcome = std::panic::catch_unwind(AssertUnwindSafe(|| daemon.serve()));
    let (why, code, emergency) = match outcome {
        Ok(Ended::Signal(sig)) => (format!("signal {}", signal_name(sig)), signal_exit_code(sig), false),
        Ok(Ended::Fatal(why)) => (why, EXIT_FATAL, false),
        Ok(Ended::CalibrationDone) => ("calibration drive done".to_owned(), 0, false),
        Err(_) => ("internal error (panic)".to_owned(), EXIT_PANIC, true),
    };
    let drained = daemon.stop_motors(emergency);
    daemon.finish_recording();
    tracing::info!(why = %why, exit_code = code, stop_frame_sent = drained, stats = ?daemon.rt.carto().stats(), "carto stopped");
    if code == EXIT_FATAL {
        eprintln!("carto: error: {why}");
    }
    ExitCode::from(code)
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

fn default_port(kind: TransportKind, which: &str) -> Result<String> {
    Ok(match (kind, which) {
        (TransportKind::Sim, "motor") => "run/tty-motor".to_owned(),
        (TransportKind::Sim, _) => "run/tty-sensor".to_owned(),
        (TransportKind::Serial, "motor") => "/dev/ttyAMA0".to_owned(),
        (TransportKind::Serial, _) => "/dev/ttyUSB0".to_owned(),
        (TransportKind::Tcp, _) => bail!("--transport tcp needs --{which}-port HOST:PORT"),
    })
}

fn seconds(flag: &str, s: f64) -> Result<Option<Duration>> {
    if !(s.is_finite() && s >= 0.0) {
        bail!("--{flag} must be a number of seconds, 0 or more (got {s})");
    }
    Ok((s > 0.0).then(|| Duration::from_secs_f64(s)))
}

/// `--record`: the recorder and the board links' traces, kept across reopenings.
struct Record {
    recorder: Recorder,
    boards: [TraceHandle; 2],
}

/// Starts the `--record` recorder, or says why not (Carto then runs without recording).
fn start_recording(args: &Args, profile: &RobotProfile) -> Result<Option<Record>> {
    let Some(path) = args.record.clone() else {
        return Ok(None);
    };
    if !(args.record_max_mib.is_finite() && args.record_max_mib > 0.0) {
        bail!("--record-max-mib must be a positive number of MiB");
    }
    let flush = seconds("record-flush", args.record_flush)?
        .with_context(|| "--record-flush must be more than 0 seconds")?;
    let header = Recording {
        version: FORMAT_VERSION,
        scenario_label: format!("carto --record {}", path.display()),
        scenario_ron: String::new(),
        profile_ron: profile.to_ron_string().context("writing the profile into the recording")?,
        seed: 0,
        logs: Vec::new(),
        oracle: Oracle::None,
    };
    let config = RecorderConfig {
        max_bytes: (args.record_max_mib * 1024.0 * 1024.0) as u64,
        flush_every: StdDuration::from_micros(flush.total_micros()),
    };
    let recorder = match Recorder::start(path.clone(), header, config) {
        Ok(r) => r,
        Err(e) => {
            tracing::error!("not recording: {e}");
            return Ok(None);
        }
    };
    let boards = [TraceHandle::default(), TraceHandle::default()];
    recorder.add("motor", "carto", boards[0].clone());
    recorder.add("sensor", "carto", boards[1].clone());
    tracing::info!(file = %path.display(), max_mib = args.record_max_mib, flush_s = args.record_flush, "recording every link");
    Ok(Some(Record { recorder, boards }))
}

/// A board link as the runtime holds it.
type BoardEnd = MaybeTraced<BoardLink>;

struct Daemon {
    rt: CartoRuntime<TracedListener<TcpListenerLink, WallClock>, BoardEnd, BoardEnd>,
    clock: WallClock,
    record: Option<Record>,
    boards: [Board; 2],
    signal: Arc<AtomicUsize>,
    /// Read end of the pipe every stop signal writes a byte to: wakes `poll`.
    wake: UnixStream,
    exit_on_link_loss: bool,
    /// `--calibration-drive`: whether it has started.
    calibration: Option<bool>,
}

impl Daemon {
    fn start(args: Args, signal: Arc<AtomicUsize>, wake: UnixStream) -> Result<Daemon> {
        let profile = load_profile(args.profile.as_deref())?;
        let mut cfg = CartoConfig::from_profile(&profile);
        if let Some(cell) = args.cell {
            if !(cell.is_finite() && (0.05..=5.0).contains(&cell)) {
                bail!("--cell {cell}: a cell is between 0.05 and 5 metres");
            }
            cfg.cell_size_m = cell;
            cfg.safety.obstacle_threshold_cm = (cell * 100.0) as f32;
        }
        if !(args.scan_deg.is_finite() && (0.0..=60.0).contains(&args.scan_deg)) {
            bail!("--scan-deg {}: between 0 and 60 degrees", args.scan_deg);
        }
        cfg.safety.scan_deg = (args.scan_deg > 0.0).then_some(args.scan_deg);
        cfg.client.idle_limit = seconds("client-idle-limit", args.client_idle_limit)?;
        cfg.client.dead_after = seconds("client-dead-after", args.client_dead_after)?;
        let board = |which: &'static str, port: Option<String>, baud: u32| -> Result<Board> {
            Ok(Board {
                which,
                kind: args.transport,
                port: match port {
                    Some(p) => p,
                    None => default_port(args.transport, which)?,
                },
                baud,
                backoff: Backoff::new(cfg.boards.retry_initial, cfg.boards.retry_max),
                down_logged: false,
            })
        };
        let mut boards = [
            board("motor", args.motor_port.clone(), profile.serial.motor_baud)?,
            board("sensor", args.sensor_port.clone(), profile.serial.sensor_baud)?,
        ];
        let clock = WallClock::start();
        let record = start_recording(&args, &profile)?;
        let mut links = Vec::new();
        for (i, b) in boards.iter_mut().enumerate() {
            match b.open(StdDuration::from_secs(3)) {
                Ok(link) => {
                    tracing::info!(board = b.which, port = %b.port, baud = b.baud, "board link open");
                    let trace = record.as_ref().map(|r| (&r.boards[i], clock));
                    links.push(Some(MaybeTraced::new(link, trace)));
                }
                Err(e) if args.exit_on_link_loss => return Err(e),
                Err(e) => {
                    tracing::warn!(
                        board = b.which,
                        "{e:#}: retrying with back-off, moves dropped until it opens"
                    );
                    b.down_logged = true;
                    b.backoff.failed(clock.now());
                    links.push(None);
                }
            }
        }
        let sensor = links.pop().flatten();
        let motor = links.pop().flatten();
        let mut listener = TcpListenerLink::bind(args.listen.as_str())
            .with_context(|| format!("cannot listen on {}", args.listen))?;
        listener.set_keepalive(
            cfg.client.dead_after.map(|d| KeepAlive::within(StdDuration::from_micros(d.total_micros()))),
        );
        tracing::info!(
            listen = %listener.local_addr(),
            robot = %profile.name,
            cell_m = cfg.cell_size_m,
            idle_limit_s = cfg.client.idle_limit.map(|d| d.as_secs_f64()),
            dead_after_s = cfg.client.dead_after.map(|d| d.as_secs_f64()),
            "carto ready: waiting for Cute"
        );
        let listener = TracedListener::new(listener, record.as_ref().map(|r| (r.recorder.feed(), clock)));
        let mut rt = CartoRuntime::with_links(Carto::new(cfg), listener, motor, sensor, clock.now());
        rt.set_drain_on_close(DRAIN_ON_CLOSE);
        let calibration = args.calibration_drive.then_some(false);
        Ok(Daemon {
            rt,
            clock,
            record,
            boards,
            signal,
            wake,
            exit_on_link_loss: args.exit_on_link_loss,
            calibration,
        })
    }

    /// Serves until a signal or a fatal error.
    fn serve(&mut self) -> Ended {
        let mut next_status = Instant::ZERO;
        loop {
            let sig = self.signal.load(Ordering::SeqCst);
            if sig != 0 {
                return Ended::Signal(sig);
            }
            let now = self.clock.now();
            match self.calibration {
                // both boards answer: the motor link is open and the IMU has reported
                Some(false) if self.rt.motor_up() && self.rt.carto().status().yaw_deg.is_some() => {
                    tracing::info!(
                        seconds = carto::calibration::CalibrationDrive::length().as_secs_f64(),
                        "calibration drive starts"
                    );
                    self.rt.carto_mut().start_calibration_drive(now);
                    self.calibration = Some(true);
                }
                Some(true) if self.rt.carto().calibration_done() && !self.rt.has_pending_output() => {
                    return Ended::CalibrationDone;
                }
                _ => {}
            }
            let report = self.rt.step(now);
            let waiting = report.waiting;
            for (lost, b) in [(report.motor_lost, 0), (report.sensor_lost, 1)] {
                if !lost {
                    continue;
                }
                let board = &mut self.boards[b];
                if self.exit_on_link_loss {
                    return Ended::Fatal(format!(
                        "the {} board link ({}) was lost (--exit-on-link-loss)",
                        board.which, board.port
                    ));
                }
                board.backoff.reset();
                board.backoff.failed(now);
                board.down_logged = false;
            }
            self.reopen_boards(now);
            if now >= next_status {
                next_status = now + Duration::from_secs(10);
                tracing::debug!(status = ?self.rt.carto().status(), stats = ?self.rt.carto().stats(), "status");
            }
            self.wait(next_status, waiting);
        }
    }

    /// Sleeps until a link, the listener or the signal pipe is readable, or until the next
    /// deadline: Carto's ([`CartoRuntime::next_deadline`]: 1 ms while its control loop runs, as
    /// the loop's old fixed sleep), a board reopening, or the status line.
    fn wait(&mut self, next_status: Instant, waiting: bool) {
        let now = self.clock.now();
        let mut deadline = self.rt.next_deadline(now).min(next_status);
        for (i, b) in self.boards.iter().enumerate() {
            let up = if i == 0 { self.rt.motor_up() } else { self.rt.sensor_up() };
            if !up {
                deadline = deadline.min(b.backoff.next_attempt().unwrap_or(now));
            }
        }
        let micros = deadline.saturating_since(now).total_micros();
        // At least 1 ms, the old loop's cadence; rounded up so the deadline has passed on waking.
        let wait = StdDuration::from_micros(micros.div_ceil(1000) * 1000)
            .clamp(StdDuration::from_millis(1), MAX_WAIT);
        let timeout = PollTimeout::try_from(wait).unwrap_or(PollTimeout::ZERO);
        let readable = PollFlags::POLLIN;
        let mut fds = Vec::with_capacity(5);
        fds.push(PollFd::new(self.wake.as_fd(), readable));
        if let Some(l) = self.rt.motor_link() {
            fds.push(PollFd::new(l.as_fd(), readable));
        }
        if let Some(l) = self.rt.sensor_link() {
            fds.push(PollFd::new(l.as_fd(), readable));
        }
        match self.rt.client_link() {
            Some(c) => {
                fds.push(PollFd::new(c.as_fd(), readable));
                // A client waiting in the backlog keeps the listener readable: watch it only
                // until the runtime has noticed that client.
                if !waiting {
                    fds.push(PollFd::new(self.rt.listener().as_fd(), readable));
                }
            }
            None => fds.push(PollFd::new(self.rt.listener().as_fd(), readable)),
        }
        if let Err(e) = poll(&mut fds, timeout)
            && e != nix::errno::Errno::EINTR
        {
            // Never spin on a broken poll: fall back to the old fixed sleep.
            tracing::debug!(error = %e, "poll failed");
            std::thread::sleep(StdDuration::from_millis(1));
        }
        drop(fds);
        let mut sink = [0u8; 64];
        while matches!(self.wake.read(&mut sink), Ok(n) if n > 0) {}
    }

    fn reopen_boards(&mut self, now: Instant) {
        for i in 0..2 {
            let up = if i == 0 { self.rt.motor_up() } else { self.rt.sensor_up() };
            let board = &mut self.boards[i];
            if up || !board.backoff.due(now) {
                continue;
            }
            match board.open(BOARD_CONNECT_TIMEOUT) {
                Ok(link) => {
                    tracing::info!(board = board.which, port = %board.port, "board link back: carrying on");
                    board.backoff.reset();
                    board.down_logged = false;
                    let now = self.clock.now();
                    let trace = self.record.as_ref().map(|r| (&r.boards[i], self.clock));
                    let link = MaybeTraced::new(link, trace);
                    if i == 0 {
                        self.rt.set_motor_link(link, now);
                    } else {
                        self.rt.set_sensor_link(link, now);
                    }
                }
                Err(e) => {
                    if !board.down_logged {
                        board.down_logged = true;
                        tracing::warn!(
                            board = board.which,
                            max_wait_s = self.rt.carto().config().boards.retry_max.as_secs_f64(),
                            "{e:#}: retrying with back-off"
                        );
                    } else {
                        tracing::debug!(board = board.which, "{e:#}");
                    }
                    board.backoff.failed(now);
                }
            }
        }
    }

    /// Writes the `--record` recording a last time (the stop frame included) and closes it.
    fn finish_recording(&mut self) {
        if let Some(r) = self.record.take() {
            let totals = r.recorder.finish();
            tracing::info!(
                recorded_bytes = totals.recorded,
                dropped_bytes = totals.dropped,
                writes = totals.writes,
                failed_writes = totals.failed_writes,
                "recording closed"
            );
        }
    }

    /// Stops the motors and waits (at most [`DRAIN_LIMIT`]) until the stop frame has left.
    /// `emergency`: after a panic, bypass Carto's state machines and write a bare stop frame.
    fn stop_motors(&mut self, emergency: bool) -> bool {
        if !self.rt.motor_up() {
            tracing::warn!("no motor board link: no stop frame can be sent");
            return false;
        }
        let now = self.clock.now();
        let attempt = std::panic::catch_unwind(AssertUnwindSafe(|| {
            if emergency { self.rt.emergency_stop() } else { self.rt.stop_motors(now) }
        }));
        let mut flushed = match attempt {
            Ok(done) => done,
            // Carto's own stop path failed: the bare frame is the last resort.
            Err(_) => self.rt.emergency_stop(),
        };
        let deadline = std::time::Instant::now() + DRAIN_LIMIT;
        while !flushed && self.rt.motor_up() && std::time::Instant::now() < deadline {
            std::thread::sleep(StdDuration::from_millis(2));
            flushed = self.rt.flush(self.clock.now());
        }
        if !flushed {
            tracing::warn!("the stop frame could not be written completely");
        }
        flushed
    }
}
