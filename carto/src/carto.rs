//! [`Carto`]: the whole controller as one sans-IO state machine — bytes in from Cute and both
//! boards, `poll(now)`, bytes out.
//!
//! Concept: the caller (the lockstep runner, or [`crate::CartoRuntime`] in the binary) owns the
//! sockets, the serial ports and the clock. It hands every received chunk to `on_*_bytes(now, …)`,
//! calls [`Carto::poll`] often (every millisecond, or every simulation step), and writes whatever
//! `take_*_bytes()` returns to the matching link. Carto never reads a clock, never blocks, and never
//! panics on what it receives.
//!
//! Invariants:
//! - replies leave in the order the requests were handled, always with big-endian `Msg`;
//! - the motor board always has a valid drive frame younger than 500 ms (resend cadence), and a
//!   zero frame goes out at once on STOP, disconnect, peer loss and move failure;
//! - after a fatal framing error, [`Carto::should_close_client`] stays true and the client's bytes
//!   are ignored until [`Carto::on_client_disconnected`];
//! - while a board link is down (`on_*_link_lost` until `on_*_link_up`) no move runs and none is
//!   reported done: the move that was running and every move asked for meanwhile end without
//!   `MOVE_DONE` (Cute's move timeout fires); positions are still acknowledged;
//! - every line logged because of what a client or a board sent (connects and closes, positions,
//!   STOPs, unknown ids, bad frames and values, moves refused or failed; the pilot's through
//!   [`crate::pilot::InputNote`]s) is rate-limited per kind and client host
//!   ([`crate::ratelimit`]): one line, then "N more like this", at most once a second.
//!
//! ```
//! use carto::{Carto, CartoConfig};
//! use robot_model::time::Instant;
//! let mut carto = Carto::new(CartoConfig::default());
//! carto.on_client_connected(Instant::ZERO, "127.0.0.1:5000");
//! // SEND_ROBOT_POSITION (2, 3) facing EAST, little-endian Msg as the 2024 Cute sends it
//! carto.on_client_bytes(Instant::ZERO, &[0x00, 0x05, 0x00, 0x07, 2, 3, 3]);
//! carto.poll(Instant::ZERO);
//! assert_eq!(carto.take_client_bytes(), vec![0x00, 0x02, 0x08, 0x00]); // ROBOT_POSITION_RECEIVED, big-endian
//! assert_eq!(carto.status().pose.map(|p| (p.x, p.y)), Some((2, 3)));
//! assert!(!carto.take_motor_bytes().is_empty()); // the idle zero drive
//! ```

use protocol::link::GuiMessage;
use robot_model::time::Instant;

mod view;

use crate::CartoConfig;
use crate::calibration::CalibrationDrive;
use crate::log_limited;
use crate::motor::{Drive, Motor};
use crate::pilot::{Health, Io, Pilot, PilotCounters, Request};
use crate::ratelimit::{RateLimiter, host_of, log_suppressed};
use crate::sensors::{LineTimer, PeerEvent, SensorEvent, SensorState};
use crate::ultrasound::Ultrasound;
use crate::wire;
use robot_model::grid::GridPose;

/// Counters over Carto's lifetime.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CartoStats {
    /// Clients accepted.
    pub clients: u64,
    /// Link frames decoded from Cute (any id).
    pub client_frames_in: u64,
    /// Link frames sent to Cute.
    pub client_frames_out: u64,
    /// Link protocol errors (bad length, bad size).
    pub protocol_errors: u64,
    /// Of those, fatal framing errors that closed the connection.
    pub fatal_errors: u64,
    /// Frames with an unknown `Msg`, ignored.
    pub unknown_messages: u64,
    /// Moves asked for while a board link was down, dropped without `MOVE_DONE`.
    pub moves_refused: u64,
    /// What the pilot counted: moves, refusals, shifts, looks, readings kept, stops.
    pub pilot: PilotCounters,
    /// Jumps of the gap between the IMU's and the wheels' headings (slip, or a push), each of
    /// which re-anchored the IMU drift estimate ([`crate::sensors::SensorState::estimate_imu_drift`]).
    pub heading_jumps: u64,
    /// Of those, jumps larger than [`crate::sensors::PUSH_JUMP_DEG`], whether or not a FORWARD's
    /// push watch acted on them.
    pub push_jumps: u64,
    /// Times the sensor board was declared lost.
    pub peer_lost_events: u64,
    /// Drive frames sent to the motor board.
    pub drive_frames_out: u64,
    /// Frames decoded from the motor board.
    pub motor_frames_in: u64,
    /// Motor board decode errors (checksum, length).
    pub motor_errors: u64,
    /// Keep-state frames sent to the sensor board.
    pub keep_states_out: u64,
    /// Frames decoded from the sensor board.
    pub sensor_frames_in: u64,
    /// Sensor board decode errors.
    pub sensor_errors: u64,
}

/// Where Carto believes the robot is ([`Carto::belief`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Belief {
    /// The stored pose: a cell and a grid heading.
    pub pose: GridPose,
    /// The dead-reckoned offset from that cell's centre, in the stored heading's frame,
    /// extrapolated to the moment asked for.
    pub offset: crate::odometry::CellOffset,
    /// How far the body faces from the stored heading, counter-clockwise degrees (the IMU,
    /// extrapolated to the moment asked for, against the reference heading; 0 before a
    /// reference is learnt).
    pub off_heading_deg: f64,
}

/// A snapshot of Carto's state, for status lines and tests.
#[derive(Debug, Clone, PartialEq)]
pub struct CartoStatus {
    /// The stored pose.
    pub pose: Option<GridPose>,
    /// A task runs or waits.
    pub busy: bool,
    /// Commands waiting (current task's rest, queued tasks, partial batch).
    pub pending: usize,
    /// The connected client's address.
    pub client: Option<String>,
    /// The sensor board sends keep-state and its link is up.
    pub sensor_board_ok: bool,
    /// The motor board link is up.
    pub motor_board_ok: bool,
    /// The drive command in force.
    pub command: Drive,
    /// Latest IMU yaw, degrees counter-clockwise (unwrapped).
    pub yaw_deg: Option<f64>,
    /// Latest front distance, cm (negative = no echo).
    pub distance_cm: Option<f32>,
    /// Dead-reckoned offset from the centre of the current cell (last complete encoder sample).
    pub cell_offset: crate::odometry::CellOffset,
    /// IMU drift currently removed from its heading, degrees.
    pub imu_drift_deg: f64,
    /// Learnt systematic overshoot of a FORWARD's stop, metres.
    pub coast_bias_m: f64,
}

/// The controller (see the module docs).
#[derive(Debug, Clone)]
pub struct Carto {
    cfg: CartoConfig,
    pilot: Pilot,
    motor: Motor,
    sensors: SensorState,
    ultrasound: Ultrasound,
    keep: crate::sensors::KeepState,
    link_decoder: protocol::link::Decoder,
    motor_decoder: protocol::motor::Decoder,
    sensor_decoder: protocol::sensor::Decoder,
    motor_line: LineTimer,
    sensor_line: LineTimer,
    peer: Option<String>,
    close_client: bool,
    client_out: Vec<u8>,
    motor_out: Vec<u8>,
    sensor_out: Vec<u8>,
    motor_link_up: bool,
    sensor_link_up: bool,
    limiter: RateLimiter,
    stats: CartoStats,
    /// The calibration drive, while it runs in place of the pilot.
    calibration: Option<CalibrationDrive>,
}

impl Carto {
    /// A controller with no client, boards assumed connected.
    pub fn new(cfg: CartoConfig) -> Self {
        Carto {
            pilot: Pilot::new(&cfg),
            motor: Motor::new(cfg.clone()),
            sensors: SensorState::default(),
            ultrasound: Ultrasound::new(cfg.safety.obstacle_threshold_cm, cfg.safety.distance_max_age),
            keep: crate::sensors::KeepState::new(cfg.boards.keep_state_period, cfg.boards.peer_lost_after),
            link_decoder: protocol::link::Decoder::new(cfg.client.max_frame),
            motor_decoder: protocol::motor::Decoder::new(cfg.boards.motor_checksum),
            sensor_decoder: protocol::sensor::Decoder::new(),
            motor_line: LineTimer::new(cfg.boards.motor_baud),
            sensor_line: LineTimer::new(cfg.boards.sensor_baud),
            peer: None,
            close_client: false,
            client_out: Vec::new(),
            motor_out: Vec::new(),
            sensor_out: Vec::new(),
            motor_link_up: true,
            sensor_link_up: true,
            limiter: RateLimiter::new(robot_model::time::Duration::from_secs(1)),
            stats: CartoStats::default(),
            calibration: None,
            cfg,
        }
    }

    /// The configuration in use.
    pub fn config(&self) -> &CartoConfig {
        &self.cfg
    }

    /// A client connected from `peer`. A previous client, if the caller forgot to report its
    /// departure, is treated as disconnected first.
    pub fn on_client_connected(&mut self, now: Instant, peer: &str) {
        if let Some(old) = self.peer.take() {
            log_limited!(warn, self.limiter, now, "new client while one was connected", host_of(&old),
                old = %old, "new client while one was connected: dropping the old session");
            self.on_client_disconnected(now);
        }
        log_limited!(info, self.limiter, now, "client connected", host_of(peer), peer, "client connected");
        self.stats.clients += 1;
        self.link_decoder.reset();
        self.close_client = false;
        self.client_out.clear();
        self.peer = Some(peer.to_owned());
    }

    /// The client went away (or was closed): the motors stop, everything pending is dropped.
    pub fn on_client_disconnected(&mut self, now: Instant) {
        match self.peer.take() {
            Some(peer) => {
                log_limited!(info, self.limiter, now, "client disconnected", host_of(&peer),
                    peer = %peer, "client disconnected: motors stopped, pending dropped");
            }
            None => tracing::debug!("client disconnected (no session)"),
        }
        self.pilot.on_disconnect(now, &mut self.motor);
        self.link_decoder.reset();
        self.close_client = false;
        self.client_out.clear();
        self.flush_motor();
    }

    /// Bytes from the client.
    pub fn on_client_bytes(&mut self, now: Instant, bytes: &[u8]) {
        if self.close_client {
            return;
        }
        let peer = self.peer.clone().unwrap_or_else(|| "?".to_owned());
        let host = host_of(&peer);
        for item in self.link_decoder.feed(bytes) {
            match item {
                Ok(msg) => {
                    self.stats.client_frames_in += 1;
                    if let GuiMessage::Unknown { msg: id, data } = &msg {
                        self.stats.unknown_messages += 1;
                        log_limited!(warn, self.limiter, now, "unknown message", host, peer = %peer, msg = format_args!("{id:#06x}"), len = data.len(), "unknown message ignored");
                        continue;
                    }
                    tracing::debug!(peer = %peer, ?msg, "request");
                    let req = wire::request_from(&msg);
                    if matches!(req, Request::Cartography { .. } | Request::Trajectory { .. })
                        && !(self.motor_link_up && self.sensor_link_up)
                    {
                        self.stats.moves_refused += 1;
                        log_limited!(warn, self.limiter, now, "move while a board link is down", host, peer = %peer, ?msg,
                            motor = self.motor_link_up, sensor = self.sensor_link_up,
                            "move dropped, no MOVE_DONE: a board link is down");
                        continue;
                    }
                    if let Request::Ignored { msg: id } = req {
                        log_limited!(info, self.limiter, now, "message for Cute", host,
                            peer = %peer, msg = format_args!("{id:#06x}"), "message for Cute received by Carto: ignored");
                    }
                    self.pilot.handle(now, req, &mut self.motor);
                    self.log_notes(now);
                    self.flush_replies();
                }
                Err(e) if e.is_fatal() => {
                    self.stats.protocol_errors += 1;
                    self.stats.fatal_errors += 1;
                    log_limited!(error, self.limiter, now, "fatal framing error", host,
                        peer = %peer, error = %e, "fatal framing error: closing the connection");
                    self.flush_replies();
                    self.close_client = true;
                    self.pilot.on_disconnect(now, &mut self.motor);
                    break;
                }
                Err(e) => {
                    self.stats.protocol_errors += 1;
                    log_limited!(warn, self.limiter, now, "bad frame", host, peer = %peer, error = %e, "bad frame skipped");
                }
            }
        }
        self.flush_motor();
    }

    /// Bytes from the motor board.
    pub fn on_motor_bytes(&mut self, now: Instant, bytes: &[u8]) {
        for item in self.motor_decoder.feed(bytes) {
            match item {
                Ok(packet) => {
                    self.stats.motor_frames_in += 1;
                    let at = self.motor_line.sampled_at(now, packet.buffer_len());
                    self.sensors.ingest(at, wire::motor_event(&packet));
                }
                Err(e) => {
                    self.stats.motor_errors += 1;
                    tracing::debug!(error = %e, "motor board frame dropped");
                }
            }
        }
    }

    /// Bytes from the sensor board.
    pub fn on_sensor_bytes(&mut self, now: Instant, bytes: &[u8]) {
        for item in self.sensor_decoder.feed(bytes) {
            match item {
                Ok(packet) => {
                    self.stats.sensor_frames_in += 1;
                    let at = self.sensor_line.sampled_at(now, packet.buffer_len());
                    match wire::sensor_event(&packet) {
                        SensorEvent::KeepState { .. } => {
                            if self.keep.heard(now) == Some(PeerEvent::Back) {
                                tracing::info!("sensor board is back");
                            }
                        }
                        SensorEvent::Distance { cm } => self.ultrasound.on_reading(at, cm, !cm.is_nan()),
                        other => self.sensors.ingest(at, other),
                    }
                }
                Err(e) => {
                    self.stats.sensor_errors += 1;
                    tracing::debug!(error = %e, "sensor board frame dropped");
                }
            }
        }
    }

    /// The motor board link is gone (the caller logs it): motors considered stopped, the current
    /// move and the queued ones are dropped without `MOVE_DONE`, moves are refused the same way
    /// until [`Carto::on_motor_link_up`].
    pub fn on_motor_link_lost(&mut self, now: Instant) {
        self.motor_link_up = false;
        self.pilot.on_link_lost(now, &mut self.motor, "motor board link lost");
        self.motor.take_drives();
        self.motor_out.clear();
        self.flush_replies();
    }

    /// The motor board link is back (reopened by the caller).
    pub fn on_motor_link_up(&mut self, now: Instant) {
        self.motor_link_up = true;
        self.motor.stop(now);
        self.flush_motor();
    }

    /// The sensor board link is gone (the caller logs it): peer lost at once, the motors stop,
    /// moves are dropped as for [`Carto::on_motor_link_lost`] until [`Carto::on_sensor_link_up`].
    pub fn on_sensor_link_lost(&mut self, now: Instant) {
        self.sensor_link_up = false;
        self.sensor_out.clear();
        if self.keep.force_lost() {
            self.stats.peer_lost_events += 1;
        }
        self.sensors.clear();
        self.pilot.on_link_lost(now, &mut self.motor, "sensor board link lost");
        self.flush_replies();
        self.flush_motor();
    }

    /// The sensor board link is back (reopened by the caller); it counts as alive once it sends
    /// keep-state.
    pub fn on_sensor_link_up(&mut self, _now: Instant) {
        self.sensor_link_up = true;
    }

    /// Runs timers and the control loops.
    pub fn poll(&mut self, now: Instant) {
        let (send, event) = self.keep.poll(now);
        if let Some(seq) = send
            && self.sensor_link_up
        {
            self.sensor_out.extend(wire::encode_keep_state(seq));
            self.stats.keep_states_out += 1;
        }
        if event == Some(PeerEvent::Lost) {
            self.stats.peer_lost_events += 1;
            tracing::error!(
                after_ms = self.cfg.boards.peer_lost_after.total_millis(),
                "sensor board lost: no keep-state; motors stopped"
            );
            self.pilot.on_fault(now, &mut self.motor, "sensor board lost");
        }
        if let Some(drive) = self.calibration.as_mut() {
            if let Some(d) = drive.poll(now)
                && self.motor_link_up
            {
                self.motor_out.extend(wire::encode_drive(d, self.cfg.boards.speed_ratio));
                self.stats.drive_frames_out += 1;
            }
            log_suppressed(self.limiter.drain(now));
            return;
        }
        let turning = self.motor.is_turning(now);
        self.sensors.smooth_yaw(&self.cfg, turning);
        self.sensors.estimate_imu_drift(now, &self.cfg, turning);
        self.motor.poll(now, &self.sensors);
        let health = self.health();
        let mut io = Io { now, motor: &mut self.motor, sensors: &self.sensors, us: &self.ultrasound, health };
        self.pilot.poll(&mut io);
        self.log_notes(now);
        self.flush_replies();
        self.flush_motor();
        log_suppressed(self.limiter.drain(now));
    }

    /// Logs the pilot's lines about the client's input through the rate limiter.
    fn log_notes(&mut self, now: Instant) {
        let notes = self.pilot.take_notes();
        if notes.is_empty() {
            return;
        }
        let peer = self.peer.as_deref().unwrap_or("-");
        let host = host_of(peer);
        for n in notes {
            if n.warn {
                log_limited!(warn, self.limiter, now, n.kind, host, peer, "{}", n.text);
            } else {
                log_limited!(info, self.limiter, now, n.kind, host, peer, "{}", n.text);
            }
        }
    }

    /// Starts the calibration drive ([`crate::calibration`]) at `now`: from then on Carto sends
    /// its drives instead of the pilot's, and the pilot waits (a client's requests queue) until
    /// it is over.
    pub fn start_calibration_drive(&mut self, now: Instant) {
        self.motor.stop(now);
        self.flush_motor();
        self.calibration = Some(CalibrationDrive::new(now));
    }

    /// Whether a calibration drive ran and is over (its final stop handed out).
    pub fn calibration_done(&self) -> bool {
        self.calibration.as_ref().is_some_and(CalibrationDrive::is_done)
    }

    /// The latest time [`Carto::poll`] must next run, for a caller that sleeps between events
    /// (the binary's event loop): `now` while a move, a task or a drive other than zero is in
    /// progress (the control loop wants every poll), otherwise the earliest of the keep-state
    /// cadence, the sensor board's liveness watch, the drive resend cadence and the end of a
    /// rate-limiter window. Bytes arriving on a link are a reason to poll sooner, which the
    /// caller sees itself. Read-only: it changes nothing Carto does.
    pub fn next_deadline(&self, now: Instant) -> Instant {
        if self.calibration.as_ref().is_some_and(|c| !c.is_done()) {
            return now;
        }
        if self.pilot.is_busy()
            || self.motor.is_busy()
            || self.motor.is_turning(now)
            || self.motor.command() != Drive::STOP
        {
            return now;
        }
        let mut next = now + self.cfg.boards.idle_resend_period;
        let candidates = [
            self.keep.next_deadline(),
            self.keep.lost_deadline(),
            self.motor.next_deadline(),
            self.limiter.next_deadline(),
        ];
        for t in candidates.into_iter().flatten() {
            next = next.min(t);
        }
        next.max(now)
    }

    /// Link frames seen from the client so far, well-formed or not (the idle limit counts time
    /// between complete frames).
    pub fn client_frames_seen(&self) -> u64 {
        self.stats.client_frames_in + self.stats.protocol_errors
    }

    /// The warning limiter, for the caller's own repeated warnings (same kinds, same budget).
    pub fn limiter(&mut self) -> &mut RateLimiter {
        &mut self.limiter
    }

    fn health(&self) -> Health {
        Health { sensor_board: self.sensor_link_up && !self.keep.is_lost(), motor_board: self.motor_link_up }
    }

    fn flush_replies(&mut self) {
        for reply in self.pilot.take_replies() {
            if self.peer.is_some() {
                self.client_out.extend(wire::encode_reply(reply));
                self.stats.client_frames_out += 1;
            }
        }
    }

    fn flush_motor(&mut self) {
        for drive in self.motor.take_drives() {
            if self.motor_link_up {
                self.motor_out.extend(wire::encode_drive(drive, self.cfg.boards.speed_ratio));
                self.stats.drive_frames_out += 1;
            }
        }
    }

    /// Bytes for the client since the last call.
    pub fn take_client_bytes(&mut self) -> Vec<u8> {
        core::mem::take(&mut self.client_out)
    }

    /// Bytes for the motor board since the last call.
    pub fn take_motor_bytes(&mut self) -> Vec<u8> {
        core::mem::take(&mut self.motor_out)
    }

    /// Bytes for the sensor board since the last call.
    pub fn take_sensor_bytes(&mut self) -> Vec<u8> {
        core::mem::take(&mut self.sensor_out)
    }

    /// Whether the caller must close the client connection (after a fatal framing error).
    pub fn should_close_client(&self) -> bool {
        self.close_client
    }

    /// Whether a client session is open.
    pub fn has_client(&self) -> bool {
        self.peer.is_some()
    }

    /// Gives the safety checks known surface points, in the grid's metric frame
    /// (`crate::surroundings`), never forgotten: a floor plan, or points added as a run goes (the
    /// twin's analyses `--known-room` and `--known-echoes`).
    pub fn add_known_surfaces(&mut self, points: impl IntoIterator<Item = (f64, f64)>) {
        self.pilot.add_known_surfaces(points);
    }

    /// Gives Carto the room's floor plan: every surface in it, as points in the grid's metric
    /// frame ([`Carto::add_known_surfaces`]). A complete plan says that space without a point is
    /// free, so a FORWARD may slide through any of it and a turn may slide to where its circle
    /// clears (`control/pilot/sliding.rs`); without one, Carto does not slide.
    pub fn add_floor_plan(&mut self, points: impl IntoIterator<Item = (f64, f64)>) {
        self.pilot.add_known_surfaces(points);
        self.pilot.know_free_space();
    }
}
