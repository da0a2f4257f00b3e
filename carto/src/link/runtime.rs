//! [`CartoRuntime`]: the pump between [`Carto`] and real (or in-memory) links.
//!
//! Concept: generic over the transport traits, so the lockstep simulator (in-memory links, virtual
//! clock) and the `carto` binary (TCP + serial ports, wall clock) run the very same code. One
//! [`CartoRuntime::step`] at `now`:
//! 1. accepts a waiting client when no session is open — one at a time: while a session is up the
//!    next client **stays in the listen backlog**, as with the 2024 Carto, and is served as soon
//!    as the session ends (both events logged once);
//! 2. reads everything waiting on the client and both boards and feeds it to Carto;
//! 3. polls Carto;
//! 4. writes Carto's output, keeping what a link did not take for the next step;
//! 5. closes the client after a fatal framing error, or after
//!    [`Client::idle_limit`](crate::config::Client::idle_limit) without a complete frame from it (bytes that
//!    trickle in without completing a frame do not keep the session open).
//!
//! A client's close is therefore always read before the next connection is looked at, so a
//! client that reconnects at once is served, never reset.
//!
//! Errors: a client error or disconnect ends the session (`on_client_disconnected`: motors stop);
//! a board link reporting [`transport::ErrorKind::Disconnected`] is dropped
//! (`on_*_link_lost`: motors stopped, moves dropped without `MOVE_DONE`) and reported in
//! [`StepReport`]; the owner may hand a reopened link back with
//! [`CartoRuntime::set_motor_link`] / [`CartoRuntime::set_sensor_link`]. Other board I/O errors
//! are counted and logged (rate-limited) and the link is kept.
//!
//! Invariants: nothing here reads a clock; unsent motor bytes never pile up beyond
//! [`MAX_BOARD_BACKLOG`] (older drive frames are worthless, the next one supersedes them).
//!
//! ```no_run
//! # fn demo<L: transport::Listener, M: transport::Link, S: transport::Link>(listener: L, motor: M, sensor: S) {
//! use carto::{Carto, CartoConfig, CartoRuntime};
//! use robot_model::time::Instant;
//! let mut rt = CartoRuntime::new(Carto::new(CartoConfig::default()), listener, motor, sensor);
//! rt.step(Instant::from_millis(1));
//! # }
//! ```

use robot_model::time::Instant;
use transport::{Link, LinkError, Listener};

use crate::Carto;
use crate::motor::Drive;
use crate::ratelimit::host_of;
use crate::{log_limited, warn_limited};

/// Unsent bytes kept per board link before the backlog is dropped.
pub const MAX_BOARD_BACKLOG: usize = 4096;
/// Unsent bytes kept for the client before it is considered stuck and closed.
pub const MAX_CLIENT_BACKLOG: usize = 64 * 1024;
const READ_CHUNK: usize = 1024;
const MAX_READS_PER_STEP: usize = 64;

/// What happened during one [`CartoRuntime::step`] that the caller may act on.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct StepReport {
    /// A client was accepted (its address).
    pub accepted: Option<String>,
    /// Another client waits in the listen backlog while the session is open.
    pub waiting: bool,
    /// The client session ended.
    pub client_closed: bool,
    /// The motor board link was lost in this step.
    pub motor_lost: bool,
    /// The sensor board link was lost in this step.
    pub sensor_lost: bool,
}

/// Counters kept by the runtime.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RuntimeStats {
    /// Clients that had to wait in the backlog for a session to end.
    pub waited: u64,
    /// Accept errors.
    pub accept_errors: u64,
    /// Board I/O errors other than disconnects.
    pub board_io_errors: u64,
    /// Bytes dropped from a board backlog.
    pub board_bytes_dropped: u64,
    /// Bytes read from / written to the client.
    pub client_bytes_in: u64,
    /// Bytes written to the client.
    pub client_bytes_out: u64,
    /// Bytes read from the motor board.
    pub motor_bytes_in: u64,
    /// Bytes written to the motor board.
    pub motor_bytes_out: u64,
    /// Bytes read from the sensor board.
    pub sensor_bytes_in: u64,
    /// Bytes written to the sensor board.
    pub sensor_bytes_out: u64,
}

struct Client<C> {
    link: C,
    peer: String,
    out: Vec<u8>,
    /// When the last complete frame (or the connection) arrived: what the idle limit counts from.
    last_frame: Instant,
    /// [`Carto::client_frames_seen`] at `last_frame`.
    frames_seen: u64,
}

/// Carto plus its links (see the module docs).
pub struct CartoRuntime<L: Listener, M: Link, S: Link> {
    carto: Carto,
    listener: L,
    client: Option<Client<L::Link>>,
    motor: Option<M>,
    sensor: Option<S>,
    motor_out: Vec<u8>,
    sensor_out: Vec<u8>,
    stats: RuntimeStats,
    buf: Vec<u8>,
    /// A client is known to wait in the backlog (logged once).
    waiting: bool,
    /// Bytes read and discarded from a client closed after a protocol error (0: none).
    drain_on_close: usize,
}

impl<L: Listener, M: Link, S: Link> CartoRuntime<L, M, S> {
    /// A runtime serving clients from `listener`, driving `motor` and `sensor`.
    pub fn new(carto: Carto, listener: L, motor: M, sensor: S) -> Self {
        Self::with_links(carto, listener, Some(motor), Some(sensor), Instant::ZERO)
    }

    /// A runtime whose board links may be missing at start (`None`: not open yet; Carto is told
    /// at `now` that the link is down, and moves are refused until it is handed over).
    pub fn with_links(carto: Carto, listener: L, motor: Option<M>, sensor: Option<S>, now: Instant) -> Self {
        let mut rt = CartoRuntime {
            carto,
            listener,
            client: None,
            motor: None,
            sensor: None,
            motor_out: Vec::new(),
            sensor_out: Vec::new(),
            stats: RuntimeStats::default(),
            buf: vec![0; READ_CHUNK],
            waiting: false,
            drain_on_close: 0,
        };
        match motor {
            Some(m) => rt.motor = Some(m),
            None => rt.carto.on_motor_link_lost(now),
        }
        match sensor {
            Some(s) => rt.sensor = Some(s),
            None => rt.carto.on_sensor_link_lost(now),
        }
        rt
    }

    /// Hands over a (re)opened motor board link: Carto sends it a stop frame first.
    pub fn set_motor_link(&mut self, link: M, now: Instant) {
        self.motor = Some(link);
        self.motor_out.clear();
        self.carto.on_motor_link_up(now);
    }

    /// Hands over a (re)opened sensor board link.
    pub fn set_sensor_link(&mut self, link: S, now: Instant) {
        self.sensor = Some(link);
        self.sensor_out.clear();
        self.carto.on_sensor_link_up(now);
    }

    /// Before closing a client after a protocol error, read and discard up to `limit` bytes it
    /// already sent, so that the close is a clean TCP FIN rather than a reset (a socket closed
    /// with unread data resets the connection). Off (0) by default; the binary sets it.
    pub fn set_drain_on_close(&mut self, limit: usize) {
        self.drain_on_close = limit;
    }

    /// The controller.
    pub fn carto(&self) -> &Carto {
        &self.carto
    }

    /// The controller, mutably (e.g. to stop it).
    pub fn carto_mut(&mut self) -> &mut Carto {
        &mut self.carto
    }

    /// The motor board link, while it is up (e.g. to read a wrapper's counters).
    pub fn motor_link(&self) -> Option<&M> {
        self.motor.as_ref()
    }

    /// The sensor board link, while it is up.
    pub fn sensor_link(&self) -> Option<&S> {
        self.sensor.as_ref()
    }

    /// The listener (e.g. for a caller that waits on its socket).
    pub fn listener(&self) -> &L {
        &self.listener
    }

    /// The client's link while a session is open (e.g. for a caller that waits on its socket).
    pub fn client_link(&self) -> Option<&L::Link> {
        self.client.as_ref().map(|c| &c.link)
    }

    /// Whether bytes wait to be written to a link that did not take them all.
    pub fn has_pending_output(&self) -> bool {
        !self.motor_out.is_empty()
            || !self.sensor_out.is_empty()
            || self.client.as_ref().is_some_and(|c| !c.out.is_empty())
    }

    /// Bytes held for the links that did not take them yet (bounded: see the module docs).
    pub fn buffered_bytes(&self) -> usize {
        self.motor_out.len() + self.sensor_out.len() + self.client.as_ref().map_or(0, |c| c.out.len())
    }

    /// The latest time [`CartoRuntime::step`] must next run if no byte arrives before: `now`
    /// while output waits or Carto's control loop runs, else the earliest of
    /// [`Carto::next_deadline`] and the client's idle limit. Read-only, for a caller that sleeps
    /// between events; a caller stepping at a fixed rate (the lockstep runner) ignores it.
    pub fn next_deadline(&self, now: Instant) -> Instant {
        if self.has_pending_output() {
            return now;
        }
        let mut next = self.carto.next_deadline(now);
        if let (Some(limit), Some(c)) = (self.carto.config().client.idle_limit, self.client.as_ref()) {
            next = next.min(c.last_frame + limit);
        }
        next.max(now)
    }

    /// The runtime's counters.
    pub fn stats(&self) -> RuntimeStats {
        self.stats
    }

    /// Whether a client session is open.
    pub fn has_client(&self) -> bool {
        self.client.is_some()
    }

    /// Whether the motor board link is still up.
    pub fn motor_up(&self) -> bool {
        self.motor.is_some()
    }

    /// Whether the sensor board link is still up.
    pub fn sensor_up(&self) -> bool {
        self.sensor.is_some()
    }

    /// One pump cycle at `now`.
    pub fn step(&mut self, now: Instant) -> StepReport {
        let mut report = StepReport::default();
        self.accept(now, &mut report);
        self.read_client(now, &mut report);
        if let (Some(limit), Some(c)) = (self.carto.config().client.idle_limit, self.client.as_ref())
            && now.saturating_since(c.last_frame) >= limit
        {
            let why = format!("idle limit: no complete frame for {:.1} s", limit.as_secs_f64());
            self.close_client(now, &why, &mut report);
        }
        self.read_boards(now, &mut report);
        self.carto.poll(now);
        self.write_all(now, &mut report);
        if self.client.is_some() && self.carto.should_close_client() {
            self.drain_client();
            self.close_client(now, "protocol error", &mut report);
        }
        report
    }

    /// Stops the motors and pushes the zero drive out as far as the link takes it (Ctrl-C,
    /// shutdown). Returns whether every queued motor byte was written.
    pub fn stop_motors(&mut self, now: Instant) -> bool {
        // A disconnect stops the motors and drops everything pending.
        if let Some(c) = self.client.take() {
            tracing::info!(peer = %c.peer, "closing client connection: shutting down");
        }
        self.carto.on_client_disconnected(now);
        let mut report = StepReport::default();
        self.write_all(now, &mut report);
        self.motor_out.is_empty()
    }

    /// The last resort (a panic, an error nothing else can handle): forgets everything queued for
    /// the motor board and writes a bare stop frame, without going through Carto's state
    /// machines. Returns whether the whole frame was written; the caller retries with
    /// [`CartoRuntime::flush`].
    pub fn emergency_stop(&mut self) -> bool {
        let Some(link) = self.motor.as_mut() else {
            return false;
        };
        self.motor_out = crate::wire::encode_drive(Drive::STOP, self.carto.config().boards.speed_ratio);
        match write_some(link, &mut self.motor_out) {
            Ok(n) => self.stats.motor_bytes_out += n as u64,
            Err(_) => self.stats.board_io_errors += 1,
        }
        self.motor_out.is_empty()
    }

    /// Writes what is still queued for every link, without reading or polling. Returns whether
    /// nothing is left for the motor board.
    pub fn flush(&mut self, now: Instant) -> bool {
        let mut report = StepReport::default();
        self.write_all(now, &mut report);
        self.motor_out.is_empty()
    }

    /// Closes the client session (e.g. on shutdown).
    pub fn close_client(&mut self, now: Instant, why: &str, report: &mut StepReport) {
        if let Some(mut c) = self.client.take() {
            // One last attempt to deliver what was already answered.
            if !c.out.is_empty() {
                let _ = c.link.write(&c.out);
            }
            log_limited!(info, self.carto.limiter(), now, "client closed", host_of(&c.peer),
                peer = %c.peer, why, "closing client connection");
            report.client_closed = true;
            self.carto.on_client_disconnected(now);
        }
    }

    /// Reads and discards what the client already sent, up to [`Self::set_drain_on_close`]'s
    /// limit.
    fn drain_client(&mut self) {
        let Some(c) = self.client.as_mut() else {
            return;
        };
        let mut left = self.drain_on_close;
        while left > 0 {
            match c.link.read(&mut self.buf) {
                Ok(n) if n > 0 => {
                    self.stats.client_bytes_in += n as u64;
                    left = left.saturating_sub(n);
                }
                _ => break,
            }
        }
    }

    fn accept(&mut self, now: Instant, report: &mut StepReport) {
        if let Some(current) = &self.client {
            // One session at a time: the next client stays in the backlog until this one leaves.
            if !self.waiting && self.listener.has_pending() {
                self.waiting = true;
                self.stats.waited += 1;
                log_limited!(info, self.carto.limiter(), now, "client waits", host_of(&current.peer),
                    current = %current.peer, "another client waits in the backlog: served when this session ends");
            }
            report.waiting = self.waiting;
            return;
        }
        match self.listener.accept() {
            Ok(Some((link, peer))) => {
                if std::mem::take(&mut self.waiting) {
                    log_limited!(info, self.carto.limiter(), now, "waiting client served", host_of(&peer),
                        peer = %peer, "serving the client that waited in the backlog");
                }
                self.carto.on_client_connected(now, &peer);
                report.accepted = Some(peer.clone());
                let frames_seen = self.carto.client_frames_seen();
                self.client = Some(Client { link, peer, out: Vec::new(), last_frame: now, frames_seen });
            }
            Ok(None) => {}
            Err(e) => {
                self.stats.accept_errors += 1;
                warn_limited!(self.carto.limiter(), now, "accept failed", error = %e, kind = ?e.kind(), "accept failed");
            }
        }
    }

    fn read_client(&mut self, now: Instant, report: &mut StepReport) {
        let Some(client) = self.client.as_mut() else {
            return;
        };
        let mut failure = None;
        for _ in 0..MAX_READS_PER_STEP {
            match client.link.read(&mut self.buf) {
                Ok(0) => break,
                Ok(n) => {
                    self.stats.client_bytes_in += n as u64;
                    self.carto.on_client_bytes(now, &self.buf[..n]);
                    let seen = self.carto.client_frames_seen();
                    if seen != client.frames_seen {
                        client.frames_seen = seen;
                        client.last_frame = now;
                    }
                    if self.carto.should_close_client() {
                        break;
                    }
                }
                Err(e) => {
                    failure = Some(if e.kind() == transport::ErrorKind::Disconnected {
                        "peer closed the connection".to_owned()
                    } else {
                        format!("read error: {e}")
                    });
                    break;
                }
            }
        }
        if let Some(why) = failure {
            self.close_client(now, &why, report);
        }
    }

    fn read_boards(&mut self, now: Instant, report: &mut StepReport) {
        if let Some(link) = self.motor.as_mut() {
            let end = read_into(link, &mut self.buf, &mut self.stats.motor_bytes_in, |b| {
                self.carto.on_motor_bytes(now, b)
            });
            self.board_read_ended(now, Board::Motor, end, report);
        }
        if let Some(link) = self.sensor.as_mut() {
            let end = read_into(link, &mut self.buf, &mut self.stats.sensor_bytes_in, |b| {
                self.carto.on_sensor_bytes(now, b)
            });
            self.board_read_ended(now, Board::Sensor, end, report);
        }
    }

    /// Acts on how reading `board` ended: a lost link is dropped with the output pending for it
    /// and Carto is told (its motors stop, its moves are dropped); a read error is counted and
    /// logged, rate-limited.
    fn board_read_ended<E: core::fmt::Display>(
        &mut self,
        now: Instant,
        board: Board,
        end: ReadEnd<E>,
        report: &mut StepReport,
    ) {
        match end {
            ReadEnd::Ok => {}
            ReadEnd::Lost(e) => {
                tracing::error!(error = %e, "{} link lost: motors stopped, moves dropped", board.name());
                match board {
                    Board::Motor => {
                        self.motor = None;
                        self.motor_out.clear();
                        report.motor_lost = true;
                        self.carto.on_motor_link_lost(now);
                    }
                    Board::Sensor => {
                        self.sensor = None;
                        self.sensor_out.clear();
                        report.sensor_lost = true;
                        self.carto.on_sensor_link_lost(now);
                    }
                }
            }
            ReadEnd::Error(e) => {
                self.stats.board_io_errors += 1;
                let kind = board.read_error();
                warn_limited!(self.carto.limiter(), now, kind, error = %e, "{kind}");
            }
        }
    }

    fn write_all(&mut self, now: Instant, report: &mut StepReport) {
        // Client.
        let bytes = self.carto.take_client_bytes();
        let mut client_failure = None;
        if let Some(c) = self.client.as_mut() {
            c.out.extend(bytes);
            match write_some(&mut c.link, &mut c.out) {
                Ok(n) => self.stats.client_bytes_out += n as u64,
                Err(e) => client_failure = Some(format!("write error: {e}")),
            }
            if client_failure.is_none() && c.out.len() > MAX_CLIENT_BACKLOG {
                client_failure = Some(format!("client not reading ({} bytes pending)", c.out.len()));
            }
        }
        if let Some(why) = client_failure {
            if let Some(c) = self.client.as_mut() {
                c.out.clear();
            }
            self.close_client(now, &why, report);
        }

        // Motor board.
        let bytes = self.carto.take_motor_bytes();
        if let Some(link) = self.motor.as_mut() {
            match push(link, &mut self.motor_out, bytes, &mut self.stats) {
                Ok(n) => self.stats.motor_bytes_out += n as u64,
                Err(e) if e.kind() == transport::ErrorKind::Disconnected => {
                    tracing::error!(error = %e, "motor board link lost: motors stopped, moves dropped");
                    self.motor = None;
                    self.motor_out.clear();
                    report.motor_lost = true;
                    self.carto.on_motor_link_lost(now);
                }
                Err(e) => {
                    self.stats.board_io_errors += 1;
                    warn_limited!(self.carto.limiter(), now, "motor board write error", error = %e, "motor board write error");
                }
            }
        }

        // Sensor board.
        let bytes = self.carto.take_sensor_bytes();
        if let Some(link) = self.sensor.as_mut() {
            match push(link, &mut self.sensor_out, bytes, &mut self.stats) {
                Ok(n) => self.stats.sensor_bytes_out += n as u64,
                Err(e) if e.kind() == transport::ErrorKind::Disconnected => {
                    tracing::error!(error = %e, "sensor board link lost: motors stopped, moves dropped");
                    self.sensor = None;
                    self.sensor_out.clear();
                    report.sensor_lost = true;
                    self.carto.on_sensor_link_lost(now);
                }
                Err(e) => {
                    self.stats.board_io_errors += 1;
                    warn_limited!(self.carto.limiter(), now, "sensor board write error", error = %e, "sensor board write error");
                }
            }
        }
    }
}

/// One of the two boards, for how reading its link ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Board {
    Motor,
    Sensor,
}

impl Board {
    /// The board's name in log lines.
    fn name(self) -> &'static str {
        match self {
            Board::Motor => "motor board",
            Board::Sensor => "sensor board",
        }
    }

    /// The kind a read error of this board is rate-limited and logged as.
    fn read_error(self) -> &'static str {
        match self {
            Board::Motor => "motor board read error",
            Board::Sensor => "sensor board read error",
        }
    }
}

enum ReadEnd<E> {
    Ok,
    Lost(E),
    Error(E),
}

fn read_into<K: Link>(
    link: &mut K,
    buf: &mut [u8],
    counter: &mut u64,
    mut feed: impl FnMut(&[u8]),
) -> ReadEnd<K::Error> {
    for _ in 0..MAX_READS_PER_STEP {
        match link.read(buf) {
            Ok(0) => return ReadEnd::Ok,
            Ok(n) => {
                *counter += n as u64;
                feed(&buf[..n.min(buf.len())]);
            }
            Err(e) if e.kind() == transport::ErrorKind::Disconnected => return ReadEnd::Lost(e),
            Err(e) => return ReadEnd::Error(e),
        }
    }
    ReadEnd::Ok
}

/// Writes as much of `pending` as the link takes, removing it from the front.
fn write_some<K: Link>(link: &mut K, pending: &mut Vec<u8>) -> Result<usize, K::Error> {
    let mut total = 0;
    while !pending.is_empty() {
        let n = link.write(pending)?;
        if n == 0 {
            break;
        }
        let n = n.min(pending.len());
        pending.drain(..n);
        total += n;
    }
    Ok(total)
}

fn push<K: Link>(
    link: &mut K,
    pending: &mut Vec<u8>,
    new: Vec<u8>,
    stats: &mut RuntimeStats,
) -> Result<usize, K::Error> {
    if pending.len() + new.len() > MAX_BOARD_BACKLOG {
        // Stale commands are worse than none: keep only the newest output.
        stats.board_bytes_dropped += pending.len() as u64;
        tracing::debug!(dropped = pending.len(), "board link backlog dropped");
        pending.clear();
    }
    pending.extend(new);
    write_some(link, pending)
}
