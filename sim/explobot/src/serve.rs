//! `explobot sim SCENARIO --serve`: the twin in real time, its boards behind real ports.
//!
//! The motor board and the sensor board appear as pseudo-terminals (stable symlinks
//! `run/tty-motor` and `run/tty-sensor`, real paths printed), as TCP ports, or on real serial
//! devices (`--motor-port /dev/ttyUSB0 --sensor-port /dev/ttyUSB1`: USB-serial adapters wired to
//! the Raspberry Pi's UARTs, hardware in the loop). An unchanged `carto` binary opens them exactly
//! as it would open the boards. The physics steps at its fixed `dt`, paced to the wall clock times
//! `speed` ([`twin_app::pacing`], as the window is).
//!
//! Each UART's byte budget is enforced by the twin itself (`baud / 10` bytes per second, a 64-byte
//! FIFO of credit), as a pty ignores baud settings: a sensor configuration that exceeds 9600 baud
//! shows up as growing latency, as on the robot. Baud rates are the profile's (`serial`), or
//! `--motor-baud` / `--sensor-baud`; a real serial port is opened at the same rates.
//!
//! A real serial port that cannot be opened, or that goes away while serving (an adapter
//! unplugged), ends the run with an error naming the port; a pty or TCP client that leaves does
//! not (the next one is served).

use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use robot_model::time::{Duration, Instant};
use transport::{
    Clock, Error, ErrorKind, Link, Listener, MockClock, PtyLink, SerialLink, TcpLink, TcpListenerLink, Tracer,
};

use twin::hardware::{Twin, WriteBudget};
use twin::runner::Endpoint;
use twin::setup::RunSetup;
use twin_app::pacing::Owed;
use twin_viz::TwinPublisher;

/// Largest burst a UART may send at once, bytes (its FIFO).
const FIFO: f64 = 64.0;
/// Most simulated time the twin catches up in one pass, seconds: after a longer stall (a
/// suspended process, a too-high speed) it drops the backlog instead of racing through it, so it
/// stays responsive and Ctrl-C works.
const MAX_CATCH_UP_S: f64 = 0.05;

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
    /// Real serial devices (or anything that opens as one), at the serving baud rates.
    Serial {
        /// Motor board device, e.g. `/dev/ttyUSB0`.
        motor: String,
        /// Sensor board device, e.g. `/dev/ttyUSB1`.
        sensor: String,
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
    /// Motor board baud rate (`None`: the profile's).
    pub motor_baud: Option<u32>,
    /// Sensor board baud rate (`None`: the profile's).
    pub sensor_baud: Option<u32>,
}

/// `explobot sim --serve`'s arguments.
#[derive(clap::Args, Clone, Debug)]
pub struct ServeArgs {
    /// Scenario file (RON); the built-in default room when omitted.
    pub scenario: Option<PathBuf>,
    /// Serve the boards (required: the twin has no other real-time mode).
    #[arg(long, required = true)]
    pub serve: bool,
    /// Expose the boards as TCP ports BASE (motor) and BASE+1 (sensor) instead of ptys.
    #[arg(long, value_name = "BASE", conflicts_with = "motor_port")]
    pub tcp: Option<u16>,
    /// Serve the motor board on this serial device (e.g. /dev/ttyUSB0, a USB-serial adapter
    /// wired to the Pi's motor UART) instead of a pty; needs --sensor-port.
    #[arg(long, value_name = "PATH", requires = "sensor_port")]
    pub motor_port: Option<String>,
    /// Serve the sensor board on this serial device (e.g. /dev/ttyUSB1); needs --motor-port.
    #[arg(long, value_name = "PATH", requires = "motor_port")]
    pub sensor_port: Option<String>,
    /// Motor board baud rate (default: the profile's, 115200 for the default robot).
    #[arg(long, value_name = "BAUD")]
    pub motor_baud: Option<u32>,
    /// Sensor board baud rate (default: the profile's, 9600 for the default robot).
    #[arg(long, value_name = "BAUD")]
    pub sensor_baud: Option<u32>,
    /// Address the TCP ports bind to.
    #[arg(long, default_value = "127.0.0.1")]
    pub bind: String,
    /// Folder for the pty symlinks.
    #[arg(long, default_value = "run")]
    pub run_dir: PathBuf,
    /// Simulated seconds per wall-clock second.
    #[arg(long, default_value_t = 1.0)]
    pub speed: f64,
    /// Stop after this many simulated seconds (default: run until Ctrl-C).
    #[arg(long)]
    pub duration: Option<f64>,
    /// Seed (default: the scenario's).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Print the robot's pose this often, simulated seconds (0 = never).
    #[arg(long, default_value_t = 1.0)]
    pub status_every: f64,
    /// Also serve the twin live over the Foxglove WebSocket protocol: true pose, sonar, room and
    /// the boards' traffic (default address 127.0.0.1:8765).
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = twin_viz::DEFAULT_ADDR)]
    pub foxglove: Option<SocketAddr>,
}

/// `explobot sim --serve` arguments that do not make a set of serving options.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum OptionsError {
    /// `--speed` is not a positive number.
    #[error("--speed must be a positive number")]
    Speed,
    /// `--tcp BASE` is the last port.
    #[error("--tcp BASE must leave room for BASE+1")]
    TcpBase,
    /// `--motor-baud` or `--sensor-baud` out of range.
    #[error("--{which}-baud {baud}: a UART runs at 50 to 4000000 baud")]
    Baud {
        /// `motor` or `sensor`.
        which: &'static str,
        /// The rate given.
        baud: u32,
    },
    /// `--bind` with a port is not a socket address.
    #[error("bad --bind address {bind}: {message}")]
    Bind {
        /// The address as given.
        bind: String,
        /// Why it does not parse.
        message: String,
    },
}

impl ServeArgs {
    /// The serving options these arguments ask for, or what is wrong with them.
    pub fn options(&self) -> Result<ServeOptions, OptionsError> {
        if !(self.speed.is_finite() && self.speed > 0.0) {
            return Err(OptionsError::Speed);
        }
        let ports = match self.tcp {
            Some(base) => {
                let sensor = base.checked_add(1).ok_or(OptionsError::TcpBase)?;
                let addr = |port: u16| {
                    format!("{}:{port}", self.bind).parse().map_err(|e: std::net::AddrParseError| {
                        OptionsError::Bind { bind: self.bind.clone(), message: e.to_string() }
                    })
                };
                Ports::Tcp { motor: addr(base)?, sensor: addr(sensor)? }
            }
            None => match (&self.motor_port, &self.sensor_port) {
                (Some(motor), Some(sensor)) => Ports::Serial { motor: motor.clone(), sensor: sensor.clone() },
                _ => Ports::Pty { dir: self.run_dir.clone() },
            },
        };
        for (which, baud) in [("motor", self.motor_baud), ("sensor", self.sensor_baud)] {
            if let Some(baud) = baud
                && !(50..=4_000_000).contains(&baud)
            {
                return Err(OptionsError::Baud { which, baud });
            }
        }
        Ok(ServeOptions {
            ports,
            speed: self.speed,
            duration: self.duration.map(Duration::from_secs_f64),
            status_every: (self.status_every > 0.0).then(|| Duration::from_secs_f64(self.status_every)),
            motor_baud: self.motor_baud,
            sensor_baud: self.sensor_baud,
        })
    }

    /// What is printed once the ports are open: where the boards are and how to start Carto.
    pub fn ready_text(&self, scenario_name: &str, motor: &str, sensor: &str) -> String {
        let transport = match (self.tcp, &self.motor_port) {
            (Some(_), _) => "tcp",
            (None, Some(_)) => "serial (on the machine wired to these ports)",
            (None, None) => "sim",
        };
        format!(
            "twin of '{scenario_name}' serving at {}x real time\nmotor board  {motor}\nsensor board {sensor}\nstart Carto with: carto --transport {transport}",
            self.speed
        )
    }
}

/// A flag that Ctrl-C sets, for [`serve`]'s `stop`.
pub fn stop_on_ctrl_c() -> Result<Arc<AtomicBool>, ctrlc::Error> {
    let stop = Arc::new(AtomicBool::new(false));
    let on_signal = stop.clone();
    ctrlc::set_handler(move || on_signal.store(true, Ordering::SeqCst))?;
    Ok(stop)
}

/// The status line printed every `status_every`: time, pose, cell and wheel setpoints.
pub fn status_line(now: Instant, twin: &Twin) -> String {
    let p = twin.body().pose();
    let cell = twin.cell().map_or("off grid".to_string(), |(r, c)| format!("({r}, {c})"));
    format!(
        "t={:>8.2}s  x={:.3} y={:.3} heading={:6.1}deg  cell {cell}  wheels {:?} rpm",
        now.as_secs_f64(),
        p.x,
        p.y,
        p.theta.to_degrees(),
        twin.motor_board().wheel_setpoints_rpm().map(|v| v.round())
    )
}

/// One board's port: a pty, or a TCP listener with at most one client.
pub enum BoardPort {
    /// A pseudo-terminal master.
    Pty(PtyLink),
    /// A TCP listener and its current client.
    Tcp(TcpListenerLink, Option<TcpLink>),
    /// A real serial device.
    Serial(SerialLink),
}

impl BoardPort {
    fn describe(&self) -> String {
        match self {
            BoardPort::Pty(p) => match p.symlink_path() {
                Some(link) => format!("{} -> {}", link.display(), p.slave_path().display()),
                None => p.slave_path().display().to_string(),
            },
            BoardPort::Tcp(l, _) => format!("tcp://{}", l.local_addr()),
            BoardPort::Serial(p) => format!("{} ({} baud)", p.path(), p.baud()),
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
            // A real port that fails is news the caller ends on (see `run_paced`).
            BoardPort::Serial(p) => p.read(buf),
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
            BoardPort::Serial(p) => p.write(buf),
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

/// Opens both boards' ports; serial devices at `bauds` (motor, sensor).
pub fn open_ports(
    ports: &Ports,
    (motor_baud, sensor_baud): (u32, u32),
) -> Result<(BoardPort, BoardPort), Error> {
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
        Ports::Serial { motor, sensor } => {
            let open = |which: &str, path: &str, baud: u32| {
                SerialLink::builder(path, baud)
                    .open()
                    .map_err(|e| Error::new(e.kind(), format!("the {which} board's port: {}", e.context())))
            };
            (
                BoardPort::Serial(open("motor", motor, motor_baud)?),
                BoardPort::Serial(open("sensor", sensor, sensor_baud)?),
            )
        }
    })
}

/// The baud rates served: the options' overrides, else the profile's (motor, sensor).
pub fn bauds(loaded: &RunSetup, options: &ServeOptions) -> (u32, u32) {
    (
        options.motor_baud.unwrap_or(loaded.profile.serial.motor_baud),
        options.sensor_baud.unwrap_or(loaded.profile.serial.sensor_baud),
    )
}

/// Runs the twin in real time, paced by `clock`, until `stop` is set or the duration is over.
/// `ready` is called once with the port descriptions (motor, sensor) when they are open;
/// `status` every `status_every` of simulated time. With a `publisher`, each step's state and
/// the bytes through both ports go to it (the ports are traced on the sim clock).
#[allow(clippy::too_many_arguments)]
pub fn serve(
    loaded: &RunSetup,
    seed: Option<u64>,
    options: &ServeOptions,
    clock: &impl Clock,
    stop: &AtomicBool,
    publisher: Option<&mut TwinPublisher>,
    ready: impl FnOnce(&str, &str),
    status: impl FnMut(Instant, &Twin),
) -> Result<(), Error> {
    let (motor, sensor) = open_ports(&options.ports, bauds(loaded, options))?;
    ready(&motor.describe(), &sensor.describe());
    let Some(publisher) = publisher else {
        return run_paced(loaded, seed, options, clock, stop, (motor, sensor), status, |_| {}, |_, _| {});
    };
    let sim_clock = MockClock::new();
    let (motor, sensor) = (Tracer::new(motor, sim_clock.clone()), Tracer::new(sensor, sim_clock.clone()));
    let handles = [("motor", motor.handle()), ("sensor", sensor.handle())];
    let mut records = Vec::new();
    let after = |now: Instant, twin: &Twin| {
        records.clear();
        for (link, handle) in &handles {
            let at = Endpoint { link, endpoint: "board", connection: None };
            records.extend(handle.take().into_iter().map(|r| (at, r)));
        }
        publisher.after_step(now, twin, &records);
    };
    run_paced(loaded, seed, options, clock, stop, (motor, sensor), status, |now| sim_clock.set(now), after)
}

/// The paced loop of [`serve`]: `before` and `after` are called around each step.
#[allow(clippy::too_many_arguments)]
fn run_paced<M: Link, S: Link>(
    loaded: &RunSetup,
    seed: Option<u64>,
    options: &ServeOptions,
    clock: &impl Clock,
    stop: &AtomicBool,
    (mut motor, mut sensor): (M, S),
    mut status: impl FnMut(Instant, &Twin),
    mut before: impl FnMut(Instant),
    mut after: impl FnMut(Instant, &Twin),
) -> Result<(), Error> {
    let seed = seed.unwrap_or(loaded.scenario.seed);
    let dt = loaded.dt();
    let dt_s = dt.as_secs_f64();
    let mut twin = Twin::new(loaded, seed, dt);
    let (motor_baud, sensor_baud) = bauds(loaded, options);
    let mut motor_pacer = Pacer::new(motor_baud);
    let mut sensor_pacer = Pacer::new(sensor_baud);
    let mut now = Instant::ZERO;
    let mut next_status = options.status_every.map(|d| Instant::ZERO + d);
    let speed = options.speed.max(1e-6);
    let mut owed = Owed::default();
    let mut last_wall = Instant::ZERO;
    while !stop.load(Ordering::SeqCst) {
        let wall = clock.now();
        let wall_s = wall.total_micros().saturating_sub(last_wall.total_micros()) as f64 / 1e6;
        last_wall = wall;
        let behind_s = owed.seconds() + wall_s * speed;
        if owed.add(wall_s, speed, MAX_CATCH_UP_S) > 0.0 {
            tracing::warn!(behind_ms = behind_s * 1000.0, "twin fell behind the wall clock; skipping ahead");
        }
        let mut done = 0;
        while done < owed.steps(dt_s) && !stop.load(Ordering::SeqCst) {
            now += dt;
            done += 1;
            before(now);
            let budget = WriteBudget { motor: motor_pacer.tick(dt), sensor: sensor_pacer.tick(dt) };
            let io = twin.board_io(now, &mut motor, &mut sensor, budget);
            // Only a real serial port reports a failure here (a pty or TCP client leaving is not one).
            if let Ports::Serial { motor, sensor } = &options.ports
                && !(io.motor_up && io.sensor_up)
            {
                let (which, path) = if io.motor_up { ("sensor", sensor) } else { ("motor", motor) };
                return Err(Error::new(
                    ErrorKind::Disconnected,
                    format!("the {which} board's serial port {path} stopped working (adapter unplugged?)"),
                ));
            }
            motor_pacer.spend(io.motor_sent);
            sensor_pacer.spend(io.sensor_sent);
            twin.physics_step(now);
            after(now, &twin);
            if let Some(at) = next_status
                && now >= at
            {
                status(now, &twin);
                next_status = options.status_every.map(|d| at + d);
            }
        }
        owed.ran(done, dt_s);
        if options.duration.is_some_and(|d| now >= Instant::ZERO + d) {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        serve: ServeArgs,
    }

    fn parse(args: &[&str]) -> Result<ServeArgs, clap::Error> {
        Cli::try_parse_from([&["sim", "--serve"], args].concat()).map(|c| c.serve)
    }

    #[test]
    fn serial_devices_and_baud_overrides_become_the_options() {
        let args = parse(&[
            "--motor-port",
            "/dev/ttyUSB0",
            "--sensor-port",
            "/dev/ttyUSB1",
            "--sensor-baud",
            "19200",
        ])
        .unwrap();
        let options = args.options().unwrap();
        assert!(
            matches!(&options.ports, Ports::Serial { motor, sensor } if motor == "/dev/ttyUSB0" && sensor == "/dev/ttyUSB1")
        );
        assert_eq!((options.motor_baud, options.sensor_baud), (None, Some(19200)));
        let loaded = RunSetup::builtin_default().unwrap();
        assert_eq!(bauds(&loaded, &options), (115_200, 19_200));
        assert!(args.ready_text("default", "m", "s").contains("--transport serial"));
    }

    #[test]
    fn one_serial_device_alone_or_with_tcp_and_a_bad_baud_are_refused() {
        assert!(parse(&["--motor-port", "/dev/ttyUSB0"]).is_err());
        assert!(parse(&["--motor-port", "/dev/a", "--sensor-port", "/dev/b", "--tcp", "5000"]).is_err());
        let args = parse(&["--motor-baud", "0"]).unwrap();
        assert_eq!(args.options().unwrap_err(), OptionsError::Baud { which: "motor", baud: 0 });
    }

    #[test]
    fn a_missing_device_is_not_found_naming_the_board_and_the_path() {
        let ports =
            Ports::Serial { motor: "/dev/ttyUSB-explobot-missing".into(), sensor: "/dev/null".into() };
        let err = open_ports(&ports, (115_200, 9600)).err().unwrap();
        assert_eq!(err.kind(), ErrorKind::NotFound);
        let text = err.to_string();
        assert!(text.contains("motor board") && text.contains("/dev/ttyUSB-explobot-missing"), "{text}");
    }
}
