//! The whole-daemon fuzz property: [`run`] drives a [`CartoRuntime`] over in-memory links with an
//! arbitrary interleaving of client bytes, motor-board bytes, sensor-board bytes, client
//! connects and disconnects, board link losses and returns, and time steps, and checks after
//! every step:
//!
//! - no panic (the caller sees it);
//! - memory bounded: the runtime's unsent bytes, the rate limiter's windows and the pilot's
//!   pending commands stay under fixed bounds ([`Violation::Unbounded`]);
//! - no drive frame other than zero reaches the motor board after a STOP or the loss of the
//!   client, until the client sends the next move ([`Violation::DriveAfterStop`]). Before the
//!   first move the same holds: nothing drives the wheels unless a client asked.
//!
//! Concept: the input is a byte string ([`decode`]), so the same function serves libFuzzer
//! (`carto/fuzz/`), a bounded proptest in CI (`carto/tests/session_fuzz.rs`) and a stable
//! mutation runner (`cargo run --release -p carto --example session_fuzz`). [`encode`] writes
//! [`Op`]s back, to turn recorded runs into seeds. Time is virtual: one step per millisecond.
//!
//! Input format, one op per tag byte `t` (`len = (t >> 3) + 1`, 1..=32):
//!
//! | `t & 7` | op |
//! |---|---|
//! | 0 | the next `len` bytes from the client |
//! | 1 | the next `len` bytes from the motor board |
//! | 2 | the next `len` bytes from the sensor board |
//! | 3 | `len` milliseconds pass, one step each |
//! | 4 | `t & 8` = 0: the client disconnects; else a client connects (if none is open) |
//! | 5 | the motor board link is lost, or comes back if it is down |
//! | 6 | the sensor board link is lost, or comes back if it is down |
//! | 7 | frame `(t >> 3) % 16` of a dictionary of valid client and board frames ([`dictionary`]) |
//!
//! ```
//! use carto::fuzzing::{Op, encode, run};
//! let input = encode(&[Op::Connect, Op::Client(vec![0x00, 0x02, 0x06, 0x00]), Op::Advance(20)]);
//! let outcome = run(&input).expect("no violation");
//! assert_eq!(outcome.steps, 22); // and 2 more at the end, to handle what came last
//! ```

use protocol::link::{Decoder as LinkDecoder, GuiMessage};
use protocol::motor::{ChecksumPolicy, Decoder as MotorDecoder, MotorCommand, MotorPacket};
use robot_model::time::{Duration, Instant};
use transport::{Connector, Link, MemConnector, MemLink, MemListener, MockClock, mem_listener};

use crate::runtime::{MAX_BOARD_BACKLOG, MAX_CLIENT_BACKLOG};
use crate::{Carto, CartoConfig, CartoRuntime};

/// Longest input [`run`] looks at; the rest is ignored (keeps one execution short).
pub const MAX_INPUT: usize = 64 * 1024;
/// Bound on the runtime's unsent bytes (client backlog plus both board backlogs, plus one step's
/// worth of new output).
pub const MAX_BUFFERED: usize = MAX_CLIENT_BACKLOG + 2 * MAX_BOARD_BACKLOG + 64 * 1024;
/// Bound on the rate limiter's open windows.
pub const MAX_LIMITER_WINDOWS: usize = crate::ratelimit::MAX_WINDOWS + 64;

/// One event of a session.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Op {
    /// Bytes from the client (1..=32 per op when encoded; longer ones are split).
    Client(Vec<u8>),
    /// Bytes from the motor board.
    Motor(Vec<u8>),
    /// Bytes from the sensor board.
    Sensor(Vec<u8>),
    /// This many milliseconds pass (1..=32 per op when encoded; longer ones are split).
    Advance(u32),
    /// The client closes its connection.
    Disconnect,
    /// A client connects, if none is open.
    Connect,
    /// The motor board link is lost, or comes back if it is down.
    MotorToggle,
    /// The sensor board link is lost, or comes back if it is down.
    SensorToggle,
    /// A dictionary frame ([`dictionary`]), by index.
    Dict(u8),
}

/// Where a dictionary frame goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum To {
    /// From the client.
    Client,
    /// From the motor board.
    Motor,
    /// From the sensor board.
    Sensor,
}

/// Sixteen valid frames that take a random input deeper than bytes alone would: a position, each
/// move, a batch, STOP, and the sensor board's keep-state (without which no move runs).
pub fn dictionary(i: u8) -> (To, &'static [u8]) {
    const D: [(To, &[u8]); 16] = [
        (To::Client, &[0x00, 0x05, 0x07, 0x00, 0, 0, 3]), // position (0, 0) east
        (To::Client, &[0x00, 0x03, 0x02, 0x00, 0]),       // cartography FORWARD
        (To::Client, &[0x00, 0x03, 0x02, 0x00, 1]),       // cartography RIGHT
        (To::Client, &[0x00, 0x03, 0x02, 0x00, 2]),       // cartography LEFT
        (To::Client, &[0x00, 0x04, 0x01, 0x00, 2, 0]),    // trajectory of 2, FORWARD
        (To::Client, &[0x00, 0x04, 0x01, 0x00, 1, 1]),    // trajectory of 1, RIGHT
        (To::Client, &[0x00, 0x02, 0x06, 0x00]),          // STOP
        (To::Client, &[0x00, 0x05, 0x07, 0x00, 2, 3, 1]), // position (2, 3) north
        (To::Sensor, &[0x01, 0x03, 0x02, 0x01, 0x02]),    // keep-state
        (To::Sensor, &[0x01, 0x03, 0x01, 0x00, 0x01]),
        (To::Sensor, &[0x03, 0x08, 0x04, 0x01, 0x01, 0x04, 0x42, 0xF6, 0x80, 0x00]), // distance
        (To::Client, &[0x00, 0x03, 0x02, 0x00, 9]),                                  // bad command
        (To::Client, &[0x00, 0x04, 0x01, 0x00, 0, 0]),                               // n_total 0
        (To::Client, &[0x00, 0x02, 0x03, 0x00]),                                     // MOVE_DONE
        (To::Client, &[0xFF, 0xFF, 0x07, 0x00]),                                     // oversize
        (
            To::Motor,
            &[
                0xAA, 0x20, 0x04, 0x00, 0x00, 0xC8, 0x42, 0x00, 0x00, 0xC8, 0xC2, 0x00, 0x00, 0x4A, 0x42,
                0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xC8, 0x41, 0x00, 0x00, 0xC8, 0xC1, 0x00, 0x00, 0x48,
                0x41, 0x00, 0x00, 0x00, 0x00, 0x5F,
            ],
        ), // telemetry
    ];
    D[usize::from(i) % D.len()]
}

/// The ops of an input (see the module docs); a truncated last op is dropped.
pub fn decode(data: &[u8]) -> Vec<Op> {
    let data = &data[..data.len().min(MAX_INPUT)];
    let mut ops = Vec::new();
    let mut i = 0;
    while let Some(&t) = data.get(i) {
        i += 1;
        let len = usize::from(t >> 3) + 1;
        let bytes = |i: &mut usize| -> Option<Vec<u8>> {
            let b = data.get(*i..*i + len)?.to_vec();
            *i += len;
            Some(b)
        };
        let op = match t & 7 {
            0 => bytes(&mut i).map(Op::Client),
            1 => bytes(&mut i).map(Op::Motor),
            2 => bytes(&mut i).map(Op::Sensor),
            3 => Some(Op::Advance(len as u32)),
            4 if t & 8 == 0 => Some(Op::Disconnect),
            4 => Some(Op::Connect),
            5 => Some(Op::MotorToggle),
            6 => Some(Op::SensorToggle),
            _ => Some(Op::Dict(t >> 3)),
        };
        match op {
            Some(op) => ops.push(op),
            None => break,
        }
    }
    ops
}

/// The input that [`decode`]s to `ops` (byte ops and long advances split into several).
pub fn encode(ops: &[Op]) -> Vec<u8> {
    let mut out = Vec::new();
    let chunks = |out: &mut Vec<u8>, tag: u8, bytes: &[u8]| {
        for c in bytes.chunks(32) {
            out.push(tag | (((c.len() - 1) as u8) << 3));
            out.extend_from_slice(c);
        }
    };
    for op in ops {
        match op {
            Op::Client(b) => chunks(&mut out, 0, b),
            Op::Motor(b) => chunks(&mut out, 1, b),
            Op::Sensor(b) => chunks(&mut out, 2, b),
            Op::Advance(ms) => {
                let mut left = *ms;
                while left > 0 {
                    let n = left.min(32);
                    out.push(3 | (((n - 1) as u8) << 3));
                    left -= n;
                }
            }
            Op::Disconnect => out.push(4),
            Op::Connect => out.push(4 | 8),
            Op::MotorToggle => out.push(5),
            Op::SensorToggle => out.push(6),
            Op::Dict(i) => out.push(7 | ((i % 32) << 3)),
        }
    }
    out
}

/// A broken property.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum Violation {
    /// A drive other than zero reached the motor board after a STOP or the loss of the client,
    /// before the next move.
    #[error("drive (vx {vx}, vy {vy}, omega {omega}) at {at_ms} ms after {after} and before any move")]
    DriveAfterStop {
        /// Virtual time, ms.
        at_ms: u64,
        /// Forward, %.
        vx: i8,
        /// Left, %.
        vy: i8,
        /// Counter-clockwise, %.
        omega: i8,
        /// What should have stopped the wheels.
        after: &'static str,
    },
    /// A buffer grew past its bound.
    #[error("{what}: {size} exceeds the bound {bound}")]
    Unbounded {
        /// Which buffer.
        what: &'static str,
        /// Its size.
        size: usize,
        /// The bound.
        bound: usize,
    },
}

/// What one execution did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Outcome {
    /// Ops executed.
    pub ops: u64,
    /// Runtime steps (virtual milliseconds).
    pub steps: u64,
    /// Drive frames Carto sent, zero or not.
    pub drives: u64,
    /// Drive frames other than zero.
    pub moving_drives: u64,
}

struct Harness {
    clock: MockClock,
    rt: CartoRuntime<MemListener, MemLink, MemLink>,
    connector: MemConnector,
    client: Option<MemLink>,
    motor: MemLink,
    sensor: MemLink,
    now: Instant,
    /// Mirror of Carto's client decoder, fed what the client wrote, to see STOPs and moves.
    mirror: LinkDecoder,
    mirror_dead: bool,
    /// Why the wheels must stay still (`None`: a move was asked for since).
    must_stop: Option<&'static str>,
    drives: MotorDecoder,
    outcome: Outcome,
    frames_from_client: usize,
}

impl Harness {
    fn new() -> Harness {
        let clock = MockClock::new();
        let (listener, connector) = mem_listener(None, clock.clone());
        let (m_carto, motor) = MemLink::pair(None, clock.clone());
        let (s_carto, sensor) = MemLink::pair(None, clock.clone());
        let mut cfg = CartoConfig::default();
        cfg.client.idle_limit = Some(Duration::from_secs(5));
        Harness {
            rt: CartoRuntime::new(Carto::new(cfg.clone()), listener, m_carto, s_carto),
            clock,
            connector,
            client: None,
            motor,
            sensor,
            now: Instant::ZERO,
            mirror: LinkDecoder::new(cfg.client.max_frame),
            mirror_dead: false,
            must_stop: Some("start"),
            drives: MotorDecoder::new(ChecksumPolicy::Sum),
            outcome: Outcome::default(),
            frames_from_client: 0,
        }
    }

    fn client_bytes(&mut self, bytes: &[u8]) {
        let Some(c) = self.client.as_mut() else {
            return;
        };
        if c.write(bytes).is_err() {
            return;
        }
        if self.mirror_dead {
            return;
        }
        for item in self.mirror.feed(bytes) {
            match item {
                Ok(msg) => {
                    self.frames_from_client += 1;
                    match msg {
                        GuiMessage::StopRobot => self.must_stop = Some("a STOP"),
                        GuiMessage::SendMoveCartography { .. } | GuiMessage::SendMovesTrajectory { .. } => {
                            self.must_stop = None;
                        }
                        _ => {}
                    }
                }
                Err(e) if e.is_fatal() => {
                    // Carto closes the connection after a fatal framing error: a lost client.
                    self.mirror_dead = true;
                    self.must_stop = Some("a fatal framing error closed the client");
                    break;
                }
                Err(_) => self.frames_from_client += 1,
            }
        }
    }

    fn disconnect(&mut self) {
        if let Some(mut c) = self.client.take() {
            c.close();
            self.must_stop = Some("the client left");
        }
    }

    fn connect(&mut self) {
        if self.client.is_some() {
            return;
        }
        if let Ok(c) = self.connector.connect() {
            self.client = Some(c);
            self.mirror = LinkDecoder::new(self.rt.carto().config().client.max_frame);
            self.mirror_dead = false;
        }
    }

    fn toggle_motor(&mut self) {
        if self.rt.motor_up() {
            self.motor.close();
        } else {
            let (carto_end, board_end) = MemLink::pair(None, self.clock.clone());
            self.motor = board_end;
            self.drives = MotorDecoder::new(ChecksumPolicy::Sum);
            self.rt.set_motor_link(carto_end, self.now);
        }
    }

    fn toggle_sensor(&mut self) {
        if self.rt.sensor_up() {
            self.sensor.close();
        } else {
            let (carto_end, board_end) = MemLink::pair(None, self.clock.clone());
            self.sensor = board_end;
            self.rt.set_sensor_link(carto_end, self.now);
        }
    }

    fn advance(&mut self, ms: u32) -> Result<(), Violation> {
        for _ in 0..ms {
            self.now += Duration::from_millis(1);
            self.clock.set(self.now);
            let report = self.rt.step(self.now);
            self.outcome.steps += 1;
            if report.client_closed && !self.rt.has_client() {
                // closed by Carto (idle limit, protocol error, not reading): a lost client
                self.client = None;
                self.must_stop = Some("Carto closed the client");
            }
            self.check()?;
        }
        Ok(())
    }

    fn check(&mut self) -> Result<(), Violation> {
        let mut buf = [0u8; 1024];
        // What Carto sent the client is read and dropped; what it sent the boards is decoded.
        if let Some(c) = self.client.as_mut() {
            while let Ok(1..) = c.read(&mut buf) {}
        }
        while let Ok(1..) = self.sensor.read(&mut buf) {}
        while let Ok(n @ 1..) = self.motor.read(&mut buf) {
            for packet in self.drives.feed(&buf[..n]).into_iter().flatten() {
                let MotorPacket::Drive(cmd) = packet else { continue };
                self.outcome.drives += 1;
                let (vx, vy, omega) = match cmd {
                    MotorCommand::V2 { vx, vy, omega, .. } => (vx, vy, omega),
                    _ => continue,
                };
                if (vx, vy, omega) == (0, 0, 0) {
                    continue;
                }
                self.outcome.moving_drives += 1;
                if let Some(after) = self.must_stop {
                    return Err(Violation::DriveAfterStop {
                        at_ms: self.now.total_millis(),
                        vx,
                        vy,
                        omega,
                        after,
                    });
                }
            }
        }
        let buffered = self.rt.buffered_bytes();
        if buffered > MAX_BUFFERED {
            return Err(Violation::Unbounded { what: "runtime output", size: buffered, bound: MAX_BUFFERED });
        }
        let windows = self.rt.carto_mut().limiter().open_windows();
        if windows > MAX_LIMITER_WINDOWS {
            return Err(Violation::Unbounded {
                what: "rate limiter windows",
                size: windows,
                bound: MAX_LIMITER_WINDOWS,
            });
        }
        Ok(())
    }

    fn check_pending(&mut self) -> Result<(), Violation> {
        // Every pending command came from a frame: the queue cannot outgrow the input.
        let pending = self.rt.carto().status().pending;
        if pending > self.frames_from_client {
            return Err(Violation::Unbounded {
                what: "pending commands",
                size: pending,
                bound: self.frames_from_client,
            });
        }
        Ok(())
    }
}

/// Runs one input (see the module docs) and checks the properties after every step.
pub fn run(data: &[u8]) -> Result<Outcome, Violation> {
    let mut h = Harness::new();
    for op in decode(data) {
        h.outcome.ops += 1;
        match op {
            Op::Client(b) => h.client_bytes(&b),
            Op::Motor(b) => {
                let _ = h.motor.write(&b);
            }
            Op::Sensor(b) => {
                let _ = h.sensor.write(&b);
            }
            Op::Advance(ms) => {
                h.advance(ms)?;
                h.check_pending()?;
            }
            Op::Disconnect => h.disconnect(),
            Op::Connect => h.connect(),
            Op::MotorToggle => h.toggle_motor(),
            Op::SensorToggle => h.toggle_sensor(),
            Op::Dict(i) => match dictionary(i) {
                (To::Client, b) => h.client_bytes(b),
                (To::Motor, b) => {
                    let _ = h.motor.write(b);
                }
                (To::Sensor, b) => {
                    let _ = h.sensor.write(b);
                }
            },
        }
    }
    // Whatever was written last is handled, and checked.
    h.advance(2)?;
    h.check_pending()?;
    Ok(h.outcome)
}
