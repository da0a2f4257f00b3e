//! The sensor board twin: keep-state and commands in, sensor frames out.
//!
//! Behaviour (protocols.md §3, seed 004 reference node, our command ids):
//! - Keep-state (status 1) at `keep_state_hz`, sequence starting at 1 and wrapping
//!   `0xFFFF → 0`.
//! - Readings, one sensor per frame, all status 1 (operational): distance (id 1, cm, −1.0 for no
//!   echo) at `distance_hz`; NavX (id 1, heading degrees clockwise in `[0, 360)`) at `navx_hz`;
//!   encoders ids 1–4 = FL, FR, RL, RR at `encoder_hz` each (the four go out together);
//!   bumper (id 1, 1 pressed / 2 released) on every change and at `bumper_heartbeat_hz`. On a
//!   poll where several are due they go out in that order: keep-state, bumper, distance, NavX,
//!   encoders. A stream fires at the first poll, then every period (see [`super`]).
//! - Commands from Carto: 1 sets the distance period in ms (`parameter ≥ 1`, else rejected and
//!   counted), 2 resets the encoder counts, 3 zeroes the heading. The board applies 2 and 3
//!   itself, as firmware would, by keeping offsets: from the next poll on, reported counts and
//!   heading are relative to the inputs of that poll. Callers therefore never reset the
//!   [`Encoder`](crate::sensors::Encoder)/[`Imu`](crate::sensors::Imu) models for these
//!   commands.
//! - Peer lost: no keep-state from Carto for more than `peer_lost_timeout_ms` (counted from the
//!   board's first poll before any arrives) sets [`SensorBoard::peer_lost`], bumps
//!   `peer_lost_events` and logs a warning once per loss; the next keep-state clears it.
//! - Byte budget: [`SensorBoard::planned_bytes_per_sec`] sums rate × frame size over the streams
//!   (≈ 757 bytes/s by default) against `sensor_baud / 10` (960 at 9600 baud). When the plan
//!   exceeds the budget, at construction or after a period command, the board logs one
//!   `tracing::warn!` (once per board) and [`SensorBoard::budget_exceeded`] turns true. The
//!   resulting growing latency belongs to the link model, which times bytes at the baud rate.
//!
//! The board needs no randomness: sensor noise is added by the sensor models, which take the
//! caller's seeded RNG.
//!
//! Invariant: nothing here panics on any input bytes; output frames always decode with
//! [`protocol::sensor::Decoder`].
//!
//! ```
//! use protocol::sensor::{Decoder, SensorPacket};
//! use robot_model::boards::{SensorBoard, SensorInputs};
//! use robot_model::profile::RobotProfile;
//! use robot_model::time::Instant;
//!
//! let mut board = SensorBoard::new(&RobotProfile::default());
//! let inputs = SensorInputs { distance_cm: Some(42.0), heading_deg: 90.0, ..Default::default() };
//! let bytes = board.poll(Instant::ZERO, &inputs); // every stream fires on the first poll
//! let packets = Decoder::new().feed(&bytes);
//! assert_eq!(packets.len(), 8); // keep-state, bumper, distance, NavX, 4 encoders
//! assert_eq!(packets[0], Ok(SensorPacket::KeepState { status: 1, sequence: 1 }));
//! assert!(!board.budget_exceeded());
//! ```

use protocol::sensor::{
    CommandId, DecodeError, Decoder, DecoderStats, EncoderDirection, NavX, SensorPacket, SensorReading,
    SensorStatus, SensorValue, SwitchState,
};

use super::Periodic;
use crate::pose::wrap_degrees_360;
use crate::profile::RobotProfile;
use crate::time::line_bytes_per_sec;
use crate::time::{Duration, Instant};

/// What the physics and sensor models measured, handed to [`SensorBoard::poll`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorInputs {
    /// Latest HC-SR04 result in cm; `None` (no echo) is sent as −1.0.
    pub distance_cm: Option<f32>,
    /// IMU heading, degrees clockwise (from [`Imu`](crate::sensors::Imu)).
    pub heading_deg: f32,
    /// Raw encoder counts, FL, FR, RL, RR (from [`Encoder`](crate::sensors::Encoder)).
    pub encoder_counts: [i32; 4],
    /// Whether each wheel last turned forward.
    pub encoder_forward: [bool; 4],
    /// Whether the front bumper is pressed.
    pub bumper_pressed: bool,
}

impl Default for SensorInputs {
    fn default() -> Self {
        SensorInputs {
            distance_cm: None,
            heading_deg: 0.0,
            encoder_counts: [0; 4],
            encoder_forward: [true; 4],
            bumper_pressed: false,
        }
    }
}

/// What the sensor board has seen and done since it started.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SensorBoardCounters {
    /// Frames decoded from Carto.
    pub frames_received: u64,
    /// Keep-state frames from Carto.
    pub keep_states_received: u64,
    /// Keep-states from Carto whose sequence was not the previous one plus one.
    pub peer_sequence_gaps: u64,
    /// Commands applied.
    pub commands_applied: u64,
    /// Commands with a known id but an unusable parameter.
    pub commands_rejected: u64,
    /// Commands with an unknown id.
    pub unknown_commands: u64,
    /// Valid frames a board does not act on (readings sent to it).
    pub ignored_frames: u64,
    /// Decoder errors (one per loss of sync).
    pub decode_errors: u64,
    /// Times the peer was declared lost.
    pub peer_lost_events: u64,
    /// Frames sent.
    pub frames_sent: u64,
    /// Keep-state frames sent.
    pub keep_states_sent: u64,
    /// Bytes received.
    pub bytes_received: u64,
    /// Bytes sent.
    pub bytes_sent: u64,
}

/// The sensor board twin (see the module docs).
#[derive(Debug, Clone)]
pub struct SensorBoard {
    decoder: Decoder,
    keep_state: Periodic,
    distance: Periodic,
    navx: Periodic,
    encoders: Periodic,
    bumper_heartbeat: Periodic,
    sequence: u16,
    last_bumper: Option<bool>,
    peer_timeout: Duration,
    peer_reference: Option<Instant>,
    peer_lost: bool,
    last_peer_sequence: Option<u16>,
    reset_encoders: bool,
    zero_heading: bool,
    encoder_offset: [i32; 4],
    heading_offset_deg: f32,
    baud: u32,
    budget_warned: bool,
    counters: SensorBoardCounters,
}

// Wire sizes of each frame (TYPE + LEN + DATA), from the protocol crate.
fn frame_len(packet: SensorPacket) -> f32 {
    packet.buffer_len() as f32
}

fn reading(sensor_id: u8, value: SensorValue) -> SensorPacket {
    SensorPacket::Reading(SensorReading { sensor_id, status: SensorStatus::Operational, value })
}

impl SensorBoard {
    /// A freshly booted board configured from the profile's `sensor_board` and `serial`
    /// sections; warns once if the configured rates exceed the line's byte budget.
    pub fn new(profile: &RobotProfile) -> Self {
        let p = &profile.sensor_board;
        let mut board = SensorBoard {
            decoder: Decoder::new(),
            keep_state: Periodic::from_hz(p.keep_state_hz),
            distance: Periodic::from_hz(p.distance_hz),
            navx: Periodic::from_hz(p.navx_hz),
            encoders: Periodic::from_hz(p.encoder_hz),
            bumper_heartbeat: Periodic::from_hz(p.bumper_heartbeat_hz),
            sequence: 1,
            last_bumper: None,
            peer_timeout: Duration::from_millis(u64::from(p.peer_lost_timeout_ms)),
            peer_reference: None,
            peer_lost: false,
            last_peer_sequence: None,
            reset_encoders: false,
            zero_heading: false,
            encoder_offset: [0; 4],
            heading_offset_deg: 0.0,
            baud: profile.serial.sensor_baud,
            budget_warned: false,
            counters: SensorBoardCounters::default(),
        };
        board.check_budget();
        board
    }

    /// Feeds bytes received from Carto at `now` (keep-state and commands).
    pub fn receive(&mut self, now: Instant, bytes: &[u8]) {
        self.counters.bytes_received += bytes.len() as u64;
        for item in self.decoder.feed(bytes) {
            match item {
                Ok(packet) => {
                    self.counters.frames_received += 1;
                    self.handle(now, packet);
                }
                Err(e) => {
                    self.counters.decode_errors += 1;
                    log_decode_error(&e);
                }
            }
        }
    }

    /// Runs the board's timers at `now` with the latest measurements; returns the bytes it sends.
    pub fn poll(&mut self, now: Instant, inputs: &SensorInputs) -> Vec<u8> {
        let reference = *self.peer_reference.get_or_insert(now);
        if !self.peer_lost && now.saturating_since(reference) > self.peer_timeout {
            self.peer_lost = true;
            self.counters.peer_lost_events += 1;
            tracing::warn!(%now, "sensor board: no keep-state from Carto for {} ms, peer lost",
                self.peer_timeout.total_millis());
        }
        if self.reset_encoders {
            self.encoder_offset = inputs.encoder_counts;
            self.reset_encoders = false;
        }
        if self.zero_heading {
            self.heading_offset_deg = if inputs.heading_deg.is_finite() { inputs.heading_deg } else { 0.0 };
            self.zero_heading = false;
        }

        let mut packets = Vec::new();
        if self.keep_state.fire(now) {
            packets.push(SensorPacket::KeepState { status: 1, sequence: self.sequence });
            self.sequence = self.sequence.wrapping_add(1);
            self.counters.keep_states_sent += 1;
        }
        let pressed = inputs.bumper_pressed;
        if self.last_bumper != Some(pressed) {
            self.last_bumper = Some(pressed);
            self.bumper_heartbeat.restart(now);
            packets.push(self.bumper_packet(pressed));
        } else if self.bumper_heartbeat.fire(now) {
            packets.push(self.bumper_packet(pressed));
        }
        if self.distance.fire(now) {
            let cm = inputs.distance_cm.filter(|v| v.is_finite()).unwrap_or(-1.0);
            packets.push(reading(1, SensorValue::Distance { cm }));
        }
        if self.navx.fire(now) {
            packets.push(self.navx_packet(inputs.heading_deg));
        }
        if self.encoders.fire(now) {
            for i in 0..4 {
                let count = inputs.encoder_counts[i].wrapping_sub(self.encoder_offset[i]);
                let direction = if inputs.encoder_forward[i] {
                    EncoderDirection::Forward
                } else {
                    EncoderDirection::Reverse
                };
                packets.push(reading(i as u8 + 1, SensorValue::Encoder { count, direction }));
            }
        }

        let mut out = Vec::new();
        for p in &packets {
            out.extend_from_slice(&p.to_bytes());
        }
        self.counters.frames_sent += packets.len() as u64;
        self.counters.bytes_sent += out.len() as u64;
        out
    }

    /// Whether Carto's keep-state has been missing for longer than the timeout.
    pub fn peer_lost(&self) -> bool {
        self.peer_lost
    }

    /// The sequence number the next keep-state will carry.
    pub fn next_sequence(&self) -> u16 {
        self.sequence
    }

    /// The distance report period in force (`None` = off).
    pub fn distance_period(&self) -> Option<Duration> {
        self.distance.period()
    }

    /// Bytes per second the configured rates produce (`rate × frame size`, summed).
    pub fn planned_bytes_per_sec(&self) -> f32 {
        let keep = frame_len(SensorPacket::KeepState { status: 1, sequence: 1 });
        let distance = frame_len(reading(1, SensorValue::Distance { cm: 0.0 }));
        let navx = frame_len(reading(1, SensorValue::NavX(NavX::default())));
        let encoder =
            frame_len(reading(1, SensorValue::Encoder { count: 0, direction: EncoderDirection::Forward }));
        let bumper = frame_len(reading(1, SensorValue::Switch(SwitchState::Released)));
        self.keep_state.rate_hz() * keep
            + self.distance.rate_hz() * distance
            + self.navx.rate_hz() * navx
            + self.encoders.rate_hz() * 4.0 * encoder
            + self.bumper_heartbeat.rate_hz() * bumper
    }

    /// The line's byte budget (`sensor_baud / 10`, 8N1).
    pub fn budget_bytes_per_sec(&self) -> f32 {
        line_bytes_per_sec(self.baud) as f32
    }

    /// Whether the configured rates exceed the line's byte budget.
    pub fn budget_exceeded(&self) -> bool {
        self.planned_bytes_per_sec() > self.budget_bytes_per_sec()
    }

    /// Whether the over-budget warning has been logged (it is logged at most once).
    pub fn budget_warned(&self) -> bool {
        self.budget_warned
    }

    /// Counters since start.
    pub fn counters(&self) -> SensorBoardCounters {
        self.counters
    }

    /// The frame decoder's own counters.
    pub fn decoder_stats(&self) -> DecoderStats {
        self.decoder.stats()
    }

    /// The next instant at which `poll` has something to do (a stream or the peer timeout).
    pub fn next_deadline(&self) -> Option<Instant> {
        let peer = (!self.peer_lost)
            .then(|| self.peer_reference.map(|r| r + self.peer_timeout + Duration::from_micros(1)));
        [
            self.keep_state.next(),
            self.distance.next(),
            self.navx.next(),
            self.encoders.next(),
            self.bumper_heartbeat.next(),
            peer.flatten(),
        ]
        .into_iter()
        .flatten()
        .min()
    }

    fn handle(&mut self, now: Instant, packet: SensorPacket) {
        match packet {
            SensorPacket::KeepState { sequence, .. } => {
                self.counters.keep_states_received += 1;
                if self.last_peer_sequence.is_some_and(|s| s.wrapping_add(1) != sequence) {
                    self.counters.peer_sequence_gaps += 1;
                }
                self.last_peer_sequence = Some(sequence);
                self.peer_reference = Some(now);
                if self.peer_lost {
                    self.peer_lost = false;
                    tracing::info!(%now, "sensor board: keep-state from Carto again");
                }
            }
            SensorPacket::Command { id, parameter } => match id {
                CommandId::SetDistancePeriod if parameter >= 1 => {
                    let period = Duration::from_millis(parameter as u64);
                    self.distance.set_period(Some(period));
                    self.counters.commands_applied += 1;
                    self.check_budget();
                }
                CommandId::SetDistancePeriod => {
                    self.counters.commands_rejected += 1;
                    tracing::debug!(parameter, "sensor board: distance period must be at least 1 ms");
                }
                CommandId::ResetEncoders => {
                    self.reset_encoders = true;
                    self.counters.commands_applied += 1;
                }
                CommandId::ZeroHeading => {
                    self.zero_heading = true;
                    self.counters.commands_applied += 1;
                }
                CommandId::Unknown(raw) => {
                    self.counters.unknown_commands += 1;
                    tracing::debug!(id = raw, parameter, "sensor board: unknown command ignored");
                }
            },
            SensorPacket::Reading(_) => self.counters.ignored_frames += 1,
        }
    }

    fn bumper_packet(&self, pressed: bool) -> SensorPacket {
        let state = if pressed { SwitchState::Pressed } else { SwitchState::Released };
        reading(1, SensorValue::Switch(state))
    }

    fn navx_packet(&self, heading_deg: f32) -> SensorPacket {
        let (status, heading_deg) = if heading_deg.is_finite() {
            (SensorStatus::Operational, wrap_degrees_360(heading_deg - self.heading_offset_deg))
        } else {
            (SensorStatus::Error, 0.0)
        };
        let navx = NavX {
            altitude: 0.0,
            pressure: 1013.25,
            heading_deg,
            temperature: 20.0,
            accel: [0.0; 3],
            mag: [0.0; 2],
        };
        SensorPacket::Reading(SensorReading { sensor_id: 1, status, value: SensorValue::NavX(navx) })
    }

    fn check_budget(&mut self) {
        let planned = self.planned_bytes_per_sec();
        let budget = self.budget_bytes_per_sec();
        if planned > budget && !self.budget_warned {
            self.budget_warned = true;
            tracing::warn!(
                planned_bytes_per_sec = planned,
                budget_bytes_per_sec = budget,
                baud = self.baud,
                "sensor board: configured rates exceed the serial line's byte budget; latency will grow"
            );
        }
    }
}

fn log_decode_error(e: &DecodeError) {
    tracing::debug!(error = %e, "sensor board: lost sync on the sensor line");
}

#[cfg(test)]
mod tests;
