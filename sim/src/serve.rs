//! `explobot sim SCENARIO --serve`: the twin in real time, its boards behind real ports.
//!
//! The motor board and the sensor board appear as pseudo-terminals (stable symlinks
//! `run/tty-motor` and `run/tty-sensor`, real paths printed) or as TCP ports, so an unchanged
//! `carto` binary opens them exactly as it would open `/dev/ttyAMA0` and `/dev/ttyUSB0`. The
//! physics steps at its fixed `dt`, paced to the wall clock times `speed`.
//!
//! A pty ignores baud settings, so the twin enforces each UART's byte budget itself
//! (`baud / 10` bytes per second, a 64-byte FIFO of credit): a sensor configuration that
//! exceeds 9600 baud shows up as growing latency, as on the robot.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

use robot_model::time::{Duration, Instant};
use transport::{Clock, Error, Link, Listener, PtyLink, TcpLink, TcpListenerLink};

use crate::scenario::LoadedScenario;
use crate::twin::{Twin, WriteBudget};

/// Largest burst a UART may send at once, bytes (its FIFO).
const FIFO: f64 = 64.0;

/// Where the boards are exposed.
#[derive(Debug, Clone)]
pub enum Ports {
    /// Pseudo-terminals with symlinks `DIR/tty-motor` and `DIR/tty-sensor`.
    Pty {
        /// Folder for the symlinks (created if missing).
        dir: PathBuf,
    },
    /// TCP listeners, one client each.
    Tcp {
        /// Motor board address.
        motor: SocketAddr,
        /// Sensor board address.
        sensor: SocketAddr,
    },
}

/// How to serve.
#[derive(Debug, Clone)]
pub struct ServeOptions {
    /// Where the boards are exposed.
    pub ports: Ports,
    /// Simulated seconds per wall second (1.0 = real time).
    pub speed: f64,
    /// Stop after this much simulated time (`None` = until interrupted).
    pub duration: Option<Duration>,
    /// Print a status line this often (simulated time; `None` = never).
    pub status_every: Option<Duration>,
}

/// One board's port: a pty, or a TCP listener with at most one client.
pub enum BoardPort {
    /// A pseudo-terminal master.
    Pty(PtyLink),
    /// A TCP listener and its current client.
    Tcp(TcpListenerLink, Option<TcpLink>),
}

impl BoardPort {
    fn describe(&self) -> String {
        match self {
            BoardPort::Pty(p) => match p.symlink_path() {
                Some(link) => format!("{} -> {}", link.display(), p.slave_path().display()),
                None => p.slave_path().display().to_string(),
            },
            BoardPort::Tcp(l, _) => format!("tcp://{}", l.local_addr()),
        }
    }
}

impl Link for BoardPort {
    type Error = Error;

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Error> {
        match self {
            BoardPort::Pty(p) => match p.read(buf) {
                // A pty outlives its clients: a departure is news, not an end.
                Err(e) if e.is_disconnected() => {
                    tracing::info!("a client closed {}", p.slave_path().display());
                    Ok(0)
                }
                other => other,
            },
            BoardPort::Tcp(listener, conn) => {
                if let Ok(Some((link, peer))) = listener.accept() {
                    tracing::info!("board client connected from {peer}");
                    *conn = Some(link);
                }
                match conn {
                    Some(c) => match c.read(buf) {
                        Err(e) if e.is_disconnected() => {
                            tracing::info!("board client left");
                            *conn = None;
                            Ok(0)
                        }
                        other => other,
                    },
                    None => Ok(0),
                }
            }
        }
    }

    fn write(&mut self, buf: &[u8]) -> Result<usize, Error> {
        match self {
            BoardPort::Pty(p) => p.write(buf),
            // Nobody attached: the UART sends into an unplugged cable.
            BoardPort::Tcp(_, None) => Ok(buf.len()),
            BoardPort::Tcp(_, Some(c)) => match c.write(buf) {
                Err(e) if e.is_disconnected() => Ok(buf.len()),
                other => other,
            },
        }
    }
}

/// Byte credit of one UART.
struct Pacer {
    bytes_per_s: f64,
    credit: f64,
}

impl Pacer {
    fn new(baud: u32) -> Self {
        Pacer { bytes_per_s: robot_model::time::line_bytes_per_sec(baud), credit: FIFO }
    }

    fn tick(&mut self, dt: Duration) -> usize {
        self.credit = (self.credit + self.bytes_per_s * dt.as_secs_f64()).min(FIFO);
        self.credit.floor() as usize
    }

    fn spend(&mut self, n: usize) {
        self.credit -= n as f64;
    }
}

/// Opens both boards' ports.
pub fn open_ports(ports: &Ports) -> Result<(BoardPort, BoardPort), Error> {
    Ok(match ports {
        Ports::Pty { dir } => {
            std::fs::create_dir_all(dir)
                .map_err(|e| Error::from_io(&e, format!("creating {}", dir.display())))?;
            let motor = PtyLink::open_with_symlink(dir.join("tty-motor"))?;
            let sensor = PtyLink::open_with_symlink(dir.join("tty-sensor"))?;
            (BoardPort::Pty(motor), BoardPort::Pty(sensor))
        }
        Ports::Tcp { motor, sensor } => (
            BoardPort::Tcp(TcpListenerLink::bind(motor)?, None),
            BoardPort::Tcp(TcpListenerLink::bind(sensor)?, None),
        ),
    })
}

/// Runs the twin in real time, paced by `clock`, until `stop` is set or the duration is over.
/// `ready` is called once with the port descriptions (motor, sensor) when they are open;
/// `status` every `status_every` of simulated time.
pub fn serve(
    loaded: &LoadedScenario,
    seed: Option<u64>,
    options: &ServeOptions,
    clock: &impl Clock,
    stop: &AtomicBool,
    ready: impl FnOnce(&str, &str),
    mut status: impl FnMut(Instant, &Twin),
) -> Result<(), Error> {
    let seed = seed.unwrap_or(loaded.scenario.seed);
    let dt = Duration::from_secs_f64(f64::from(loaded.scenario.physics.step_ms) / 1000.0);
    let mut twin = Twin::new(loaded, seed, dt);
    let (mut motor, mut sensor) = open_ports(&options.ports)?;
    ready(&motor.describe(), &sensor.describe());
    let mut motor_pacer = Pacer::new(loaded.profile.serial.motor_baud);
    let mut sensor_pacer = Pacer::new(loaded.profile.serial.sensor_baud);
    let mut now = Instant::ZERO;
    let mut next_status = options.status_every.map(|d| Instant::ZERO + d);
    // Simulated time owed to the wall clock is caught up at most this much per pass; after a
    // longer stall (a suspended process, a too-high speed) the twin drops the backlog instead of
    // racing through it, so it stays responsive and Ctrl-C works.
    let max_catch_up = Duration::from_millis(50);
    let mut offset_micros = 0.0f64;
    while !stop.load(Ordering::SeqCst) {
        let mut wall = clock.now().total_micros() as f64 * options.speed.max(1e-6) - offset_micros;
        let behind = wall - now.total_micros() as f64;
        if behind > max_catch_up.total_micros() as f64 {
            let dropped = behind - max_catch_up.total_micros() as f64;
            offset_micros += dropped;
            wall -= dropped;
            tracing::warn!(behind_ms = behind / 1000.0, "twin fell behind the wall clock; skipping ahead");
        }
        while (now + dt).total_micros() as f64 <= wall && !stop.load(Ordering::SeqCst) {
            now += dt;
            let budget = WriteBudget { motor: motor_pacer.tick(dt), sensor: sensor_pacer.tick(dt) };
            let io = twin.board_io(now, &mut motor, &mut sensor, budget);
            motor_pacer.spend(io.motor_sent);
            sensor_pacer.spend(io.sensor_sent);
            twin.physics_step(now);
            if let Some(at) = next_status
                && now >= at
            {
                status(now, &twin);
                next_status = options.status_every.map(|d| at + d);
            }
        }
        if options.duration.is_some_and(|d| now >= Instant::ZERO + d) {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    Ok(())
}
