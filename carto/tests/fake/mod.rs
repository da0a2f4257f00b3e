//! A scripted robot for Carto's tests: bytes in, bytes out, a tiny kinematic model in between.
//!
//! The motor board side decodes drive v2 frames, applies the board's watchdog (500 ms), mixes
//! them like the board (k = 1, scaled to ±100 %), passes each wheel through a 5 % dead band and a
//! first-order lag (τ = 80 ms), and integrates wheel travel into encoder counts and the body pose
//! (mecanum inverse kinematics). The sensor board side emits keep-state (2 Hz), NavX heading
//! (10 Hz), four encoders (5 Hz each), distance (10 Hz) and the bumper (on change and 1 Hz), and
//! records Carto's keep-state. Every knob a test needs is a public field.

#![allow(dead_code)]
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use carto::motor::Drive;
use carto::{Carto, CartoConfig};
use protocol::link::{GuiMessage, MsgOrder};
use protocol::motor::{MotorCommand, MotorPacket, Telemetry};
use protocol::sensor::{
    EncoderDirection, NavX, SensorPacket, SensorReading, SensorStatus, SensorValue, SwitchState,
};
use robot_model::time::{Duration, Instant};

pub struct FakeRobot {
    pub cfg: CartoConfig,
    /// World position, metres, and yaw, radians counter-clockwise.
    pub x: f64,
    pub y: f64,
    pub yaw: f64,
    pub wheel_pct: [f64; 4],
    pub target_pct: [f64; 4],
    pub counts: [f64; 4],
    pub last_drive: Option<Instant>,
    pub drives: Vec<(Instant, Drive)>,
    pub watchdog_trips: u32,
    pub carto_keep_states: Vec<(Instant, u16)>,
    /// Scripted sensor values.
    pub distance_cm: f32,
    pub bumper: bool,
    bumper_sent: Option<bool>,
    /// Streams that can be switched off.
    pub send_keep_state: bool,
    pub send_distance: bool,
    pub send_encoders: bool,
    pub send_telemetry: bool,
    /// Wheels jammed: commands are decoded but nothing moves.
    pub jammed: bool,
    /// Something holds the body: it does not move, while the wheels spin and count (slip).
    pub pinned: bool,
    /// Something beside the body: it cannot turn clockwise past this yaw, degrees (the wheels
    /// spin and count, the IMU sees the body stop).
    pub yaw_min_deg: Option<f64>,
    /// Motor time constant, seconds (Carto assumes 0.080).
    pub tau_s: f64,
    /// The motor board applies each drive frame this late (0 = at once).
    pub drive_delay: Duration,
    delayed: std::collections::VecDeque<(Instant, [f64; 4])>,
    /// Each wheel turns at this fraction of its commanded speed (worn or mismatched motors).
    pub wheel_gain: [f64; 4],
    seq: u16,
    next: [Instant; 6],
    motor_dec: protocol::motor::Decoder,
    sensor_dec: protocol::sensor::Decoder,
}

const KEEP: usize = 0;
const NAVX: usize = 1;
const ENC: usize = 2;
const DIST: usize = 3;
const BUMP: usize = 4;
const TELE: usize = 5;

impl FakeRobot {
    pub fn new(cfg: CartoConfig) -> Self {
        FakeRobot {
            cfg,
            x: 0.0,
            y: 0.0,
            yaw: 0.0,
            wheel_pct: [0.0; 4],
            target_pct: [0.0; 4],
            counts: [0.0; 4],
            last_drive: None,
            drives: Vec::new(),
            watchdog_trips: 0,
            carto_keep_states: Vec::new(),
            distance_cm: -1.0,
            bumper: false,
            bumper_sent: None,
            send_keep_state: true,
            send_distance: true,
            send_encoders: true,
            send_telemetry: false,
            jammed: false,
            pinned: false,
            yaw_min_deg: None,
            tau_s: 0.080,
            drive_delay: Duration::ZERO,
            delayed: Default::default(),
            wheel_gain: [1.0; 4],
            seq: 1,
            // Staggered phases, like a real board.
            next: [
                Instant::from_millis(3),
                Instant::from_millis(7),
                Instant::from_millis(11),
                Instant::from_millis(17),
                Instant::from_millis(19),
                Instant::from_millis(23),
            ],
            motor_dec: protocol::motor::Decoder::new(Default::default()),
            sensor_dec: protocol::sensor::Decoder::new(),
        }
    }

    /// Bytes Carto wrote to the motor board.
    pub fn motor_rx(&mut self, now: Instant, bytes: &[u8]) {
        for p in self.motor_dec.feed(bytes) {
            match p.expect("carto sends valid motor frames") {
                MotorPacket::Drive(MotorCommand::V2 { vx, vy, omega, .. }) => {
                    let d = Drive { vx, vy, omega };
                    self.drives.push((now, d));
                    self.last_drive = Some(now);
                    if self.drive_delay == Duration::ZERO {
                        self.target_pct = mix(d);
                    } else {
                        self.delayed.push_back((now + self.drive_delay, mix(d)));
                    }
                }
                other => panic!("unexpected motor packet from carto: {other:?}"),
            }
        }
    }

    /// Bytes Carto wrote to the sensor board.
    pub fn sensor_rx(&mut self, now: Instant, bytes: &[u8]) {
        for p in self.sensor_dec.feed(bytes) {
            match p.expect("carto sends valid sensor frames") {
                SensorPacket::KeepState { status, sequence } => {
                    assert_eq!(status, 2, "carto's keep-state status");
                    self.carto_keep_states.push((now, sequence));
                }
                other => panic!("unexpected sensor packet from carto: {other:?}"),
            }
        }
    }

    /// Integrates `dt` of motion ending at `now`.
    pub fn step(&mut self, now: Instant, dt: f64) {
        while self.delayed.front().is_some_and(|(at, _)| *at <= now) {
            if let Some((_, t)) = self.delayed.pop_front() {
                self.target_pct = t;
            }
        }
        if let Some(t) = self.last_drive
            && now.saturating_since(t) > Duration::from_millis(500)
            && self.target_pct != [0.0; 4]
        {
            self.watchdog_trips += 1;
            self.target_pct = [0.0; 4];
        }
        let a = 1.0 - (-dt / self.tau_s).exp();
        let rim = self.cfg.max_wheel_speed_mps();
        let mut v = [0.0; 4];
        let cpm = self.cfg.encoder_counts_per_metre();
        for (i, vi) in v.iter_mut().enumerate() {
            let target = if self.jammed || self.target_pct[i].abs() < 5.0 {
                0.0
            } else {
                self.target_pct[i] * self.wheel_gain[i]
            };
            self.wheel_pct[i] += (target - self.wheel_pct[i]) * a;
            *vi = self.wheel_pct[i] / 100.0 * rim;
            self.counts[i] += *vi * dt * cpm;
        }
        let [fl, fr, rl, rr] = v;
        let vx = (fl + fr + rl + rr) / 4.0;
        let vy = (-fl + fr + rl - rr) / 4.0;
        let w = (-fl + fr - rl + rr) / 4.0 / self.cfg.rotation_lever_m();
        if self.pinned {
            return;
        }
        let (s, c) = self.yaw.sin_cos();
        self.x += (vx * c - vy * s) * dt;
        self.y += (vx * s + vy * c) * dt;
        self.yaw += w * dt;
        if let Some(min) = self.yaw_min_deg {
            self.yaw = self.yaw.max(min.to_radians());
        }
    }

    pub fn heading_cw_deg(&self) -> f32 {
        ((-self.yaw.to_degrees()).rem_euclid(360.0)) as f32
    }

    /// Frames the boards send at `now`: (motor board bytes, sensor board bytes).
    pub fn emit(&mut self, now: Instant) -> (Vec<u8>, Vec<u8>) {
        let mut motor = Vec::new();
        let mut sensor = Vec::new();
        let ok = SensorStatus::Operational;
        if now >= self.next[KEEP] {
            self.next[KEEP] += Duration::from_millis(500);
            if self.send_keep_state {
                sensor.extend(SensorPacket::KeepState { status: 1, sequence: self.seq }.to_bytes());
                self.seq = self.seq.wrapping_add(1);
            }
        }
        if now >= self.next[NAVX] {
            self.next[NAVX] += Duration::from_millis(100);
            let navx = NavX { heading_deg: self.heading_cw_deg(), ..Default::default() };
            sensor.extend(
                SensorPacket::Reading(SensorReading {
                    sensor_id: 1,
                    status: ok,
                    value: SensorValue::NavX(navx),
                })
                .to_bytes(),
            );
        }
        if now >= self.next[ENC] {
            self.next[ENC] += Duration::from_millis(200);
            for (i, c) in self.counts.iter().enumerate().filter(|_| self.send_encoders) {
                let direction = if self.wheel_pct[i] >= 0.0 {
                    EncoderDirection::Forward
                } else {
                    EncoderDirection::Reverse
                };
                let value = SensorValue::Encoder { count: c.round() as i32, direction };
                sensor.extend(
                    SensorPacket::Reading(SensorReading { sensor_id: i as u8 + 1, status: ok, value })
                        .to_bytes(),
                );
            }
        }
        if now >= self.next[DIST] {
            self.next[DIST] += Duration::from_millis(100);
            if self.send_distance {
                let value = SensorValue::Distance { cm: self.distance_cm };
                sensor.extend(
                    SensorPacket::Reading(SensorReading { sensor_id: 1, status: ok, value }).to_bytes(),
                );
            }
        }
        if now >= self.next[BUMP] || self.bumper_sent != Some(self.bumper) {
            if now >= self.next[BUMP] {
                self.next[BUMP] += Duration::from_millis(1000);
            }
            self.bumper_sent = Some(self.bumper);
            let state = if self.bumper { SwitchState::Pressed } else { SwitchState::Released };
            sensor.extend(
                SensorPacket::Reading(SensorReading {
                    sensor_id: 1,
                    status: ok,
                    value: SensorValue::Switch(state),
                })
                .to_bytes(),
            );
        }
        if now >= self.next[TELE] {
            self.next[TELE] += Duration::from_millis(50);
            if self.send_telemetry {
                let max = self.cfg.chassis.max_wheel_rpm;
                let rpm = self.wheel_pct.map(|p| (p / 100.0 * max) as f32);
                let power = self.wheel_pct.map(|p| p as f32);
                motor.extend(MotorPacket::Telemetry(Telemetry::motor(rpm, power)).to_bytes());
            }
        }
        (motor, sensor)
    }

    /// Drive frames received at or after `since`.
    pub fn drives_since(&self, since: Instant) -> Vec<(Instant, Drive)> {
        self.drives.iter().copied().filter(|(t, _)| *t >= since).collect()
    }

    pub fn moving(&self) -> bool {
        self.wheel_pct.iter().any(|p| p.abs() > 0.5)
    }
}

/// The board's mixing, k = 1, scaled down together beyond 100 %.
pub fn mix(d: Drive) -> [f64; 4] {
    let (vx, vy, w) = (
        f64::from(d.vx).clamp(-100.0, 100.0),
        f64::from(d.vy).clamp(-100.0, 100.0),
        f64::from(d.omega).clamp(-100.0, 100.0),
    );
    let mut out = [vx - vy - w, vx + vy + w, vx + vy - w, vx - vy + w];
    let max = out.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if max > 100.0 {
        for o in &mut out {
            *o *= 100.0 / max;
        }
    }
    out
}

/// Carto wired to a fake robot, stepped 1 ms at a time.
pub struct Harness {
    pub carto: Carto,
    pub robot: FakeRobot,
    pub now: Instant,
    pub replies: Vec<(Instant, GuiMessage)>,
    dec: protocol::link::Decoder,
}

/// The default controller on 0.30 m cells with a 30 cm obstacle threshold: the grid these
/// tests were written for (the distances they assert are multiples of it).
///
/// The stall watch is off: the fake's sonar reads the scripted `distance_cm` however the body
/// moves, which is what a stalled FORWARD looks like. The stall tests turn it on and move the
/// range with the body.
pub fn test_config() -> CartoConfig {
    let mut cfg = CartoConfig { cell_size_m: 0.30, ..CartoConfig::default() };
    cfg.safety.obstacle_threshold_cm = 30.0;
    cfg.safety.stall_watch = false;
    cfg
}

/// [`test_config`] changed by `change`.
pub fn test_config_with(change: impl FnOnce(&mut CartoConfig)) -> CartoConfig {
    let mut cfg = test_config();
    change(&mut cfg);
    cfg
}

impl Harness {
    pub fn new() -> Self {
        Self::with_config(test_config())
    }

    /// `cfg` with the line-latency correction off: the fake boards deliver instantly.
    pub fn with_config(mut cfg: CartoConfig) -> Self {
        cfg.boards.motor_baud = 0;
        cfg.boards.sensor_baud = 0;
        let mut h = Harness {
            carto: Carto::new(cfg.clone()),
            robot: FakeRobot::new(cfg),
            now: Instant::ZERO,
            replies: Vec::new(),
            dec: protocol::link::Decoder::default(),
        };
        h.carto.on_client_connected(h.now, "test:1");
        h
    }

    pub fn tick(&mut self) {
        self.now += Duration::from_millis(1);
        self.robot.step(self.now, 0.001);
        let (m, s) = self.robot.emit(self.now);
        if !m.is_empty() {
            self.carto.on_motor_bytes(self.now, &m);
        }
        if !s.is_empty() {
            self.carto.on_sensor_bytes(self.now, &s);
        }
        self.carto.poll(self.now);
        self.pump();
    }

    /// Moves Carto's pending output to the robot and the reply log.
    pub fn pump(&mut self) {
        let m = self.carto.take_motor_bytes();
        self.robot.motor_rx(self.now, &m);
        let s = self.carto.take_sensor_bytes();
        self.robot.sensor_rx(self.now, &s);
        let c = self.carto.take_client_bytes();
        for r in self.dec.feed(&c) {
            self.replies.push((self.now, r.expect("carto sends valid link frames")));
        }
    }

    pub fn run_ms(&mut self, ms: u64) {
        for _ in 0..ms {
            self.tick();
        }
    }

    /// Runs until `pred` holds or `max_ms` passed; returns whether it held.
    pub fn run_until(&mut self, max_ms: u64, mut pred: impl FnMut(&Harness) -> bool) -> bool {
        for _ in 0..max_ms {
            if pred(self) {
                return true;
            }
            self.tick();
        }
        pred(self)
    }

    pub fn send(&mut self, msg: GuiMessage) {
        self.send_bytes(&msg.to_bytes(MsgOrder::BigEndian));
    }

    pub fn send_bytes(&mut self, bytes: &[u8]) {
        self.carto.on_client_bytes(self.now, bytes);
        self.pump();
    }

    pub fn reply_msgs(&self) -> Vec<GuiMessage> {
        self.replies.iter().map(|(_, m)| m.clone()).collect()
    }

    pub fn move_done_count(&self) -> usize {
        self.replies.iter().filter(|(_, m)| *m == GuiMessage::MoveDone).count()
    }

    /// Lets the sensor streams run so Carto has every reading, then clears the logs.
    pub fn warm_up(&mut self) {
        self.run_ms(500);
        self.replies.clear();
    }

    pub fn distance_from(&self, x0: f64, y0: f64) -> f64 {
        ((self.robot.x - x0).powi(2) + (self.robot.y - y0).powi(2)).sqrt()
    }
}

/// The pose the scripted tests acknowledge first: (5, 5) facing EAST.
pub const POSE: GuiMessage =
    GuiMessage::SendRobotPosition { x: 5, y: 5, direction: protocol::link::Direction::East };

impl Harness {
    /// A harness with sensors flowing and [`POSE`] acknowledged.
    pub fn ready() -> Harness {
        let mut h = Harness::new();
        h.warm_up();
        h.send(POSE);
        assert_eq!(h.reply_msgs(), vec![GuiMessage::RobotPositionReceived]);
        h.replies.clear();
        h
    }
}
