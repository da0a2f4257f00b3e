//! The motor board twin: drive frames in, wheel setpoints and telemetry frames out.
//!
//! Behaviour (protocols.md §2, seed 000 firmware):
//! - Drive **v2** (`0x10`): `vx`, `vy`, `omega` are clamped to ±100 % (`speed_ratio` and the
//!   reserved bytes are ignored, as the firmware does), mixed with
//!   [`mix_percent`] (scale-down included) and turned into wheel
//!   setpoints: 100 % = `max_wheel_rpm`.
//! - Drive **v1** (`0x01`): offset-binary axes (`0x80` neutral; `0x00` → −100 %, `0xFF` →
//!   +100 %) scaled by `min(gear, 8) / 8`; `dir_y` is forward, `dir_x` is strafe **right**, so
//!   `vx = dir_y`, `vy = −dir_x`, `ω = 0` (v1 cannot turn), then the same mixing.
//! - Watchdog (on by default, `motor_board.watchdog_*`): when no valid drive frame arrived for
//!   the timeout, setpoints go to zero; `watchdog_trips` counts the times it stopped moving
//!   wheels. The next drive frame re-arms it. The original firmware has none: turn it off in the
//!   profile for faithful behaviour.
//! - Telemetry at `telemetry_hz` in the configured form and checksum: `wheel_rpm` is what the
//!   physics reported last ([`MotorBoard::set_measured`]), `motor_power` the commanded wheel
//!   percents. The 104-byte form also carries dead-reckoned odometry (wheel speeds integrated
//!   between polls) and a zero IMU block (the IMU lives on the sensor board).
//! - Bad checksums and framing errors are counted and dropped; unknown types are counted and
//!   ignored; a telemetry frame received by the board is counted as ignored.
//!
//! Invariants: setpoints are always within `±max_wheel_rpm`; `poll` emits at most one telemetry
//! frame per call; nothing here panics on any input bytes.
//!
//! ```
//! use protocol::motor::{MotorCommand, MotorPacket};
//! use robot_model::boards::MotorBoard;
//! use robot_model::profile::RobotProfile;
//! use robot_model::time::Instant;
//!
//! let mut board = MotorBoard::new(&RobotProfile::default());
//! let forward = MotorPacket::Drive(MotorCommand::V2 {
//!     vx: 50, vy: 0, omega: 0, speed_ratio: 0, reserved: [0; 2],
//! });
//! board.receive(Instant::ZERO, &forward.to_bytes());
//! assert_eq!(board.wheel_setpoints_rpm(), [150.0; 4]); // 50 % of 300 rpm
//! board.set_measured([148.0; 4]);
//! let telemetry = board.poll(Instant::ZERO); // one 32-byte-form frame, 36 bytes on the wire
//! assert_eq!(telemetry.len(), 36);
//! ```

use protocol::motor::{
    ChecksumKind, ChecksumPolicy, DecodeError, Decoder, DecoderStats, MotorCommand, MotorPacket, Telemetry,
    TelemetryForm,
};

use super::Periodic;
use crate::kinematics::{MecanumKinematics, PercentCommand, mix_percent};
use crate::pose::{Pose2, Twist};
use crate::profile::{RobotProfile, TelemetryFormSetting};
use crate::time::line_bytes_per_sec;
use crate::time::{Duration, Instant};

/// What the motor board has seen and done since it started.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MotorBoardCounters {
    /// Frames that passed checksum and length checks with a known type.
    pub frames_ok: u64,
    /// Drive frames applied (a subset of `frames_ok`).
    pub drive_frames: u64,
    /// Frames dropped for a bad checksum.
    pub bad_checksums: u64,
    /// Frames dropped for any other framing error (bad length, …).
    pub framing_errors: u64,
    /// Frames of an unknown type (counted, ignored).
    pub unknown_types: u64,
    /// Valid frames a board does not act on (telemetry sent to it).
    pub ignored_frames: u64,
    /// Times the watchdog stopped wheels that were commanded to move.
    pub watchdog_trips: u64,
    /// Telemetry frames sent.
    pub telemetry_sent: u64,
    /// Bytes received.
    pub bytes_received: u64,
    /// Bytes sent.
    pub bytes_sent: u64,
}

/// The motor board twin (see the module docs).
#[derive(Debug, Clone)]
pub struct MotorBoard {
    kin: MecanumKinematics,
    decoder: Decoder,
    emit_kind: ChecksumKind,
    form: TelemetryForm,
    motor_id: u8,
    telemetry: Periodic,
    watchdog: Option<Duration>,
    baud: u32,
    command: PercentCommand,
    wheel_percent: [f32; 4],
    last_command: Option<MotorCommand>,
    last_drive: Option<Instant>,
    watchdog_tripped: bool,
    measured_rpm: [f32; 4],
    odometry: Pose2,
    last_poll: Option<Instant>,
    counters: MotorBoardCounters,
}

impl MotorBoard {
    /// A board at rest, configured from the profile's `motor_board`, `motor`, `geometry` and
    /// `serial` sections.
    pub fn new(profile: &RobotProfile) -> Self {
        let p = &profile.motor_board;
        let policy = ChecksumPolicy::from(p.accept_checksum);
        let emit_kind = ChecksumKind::from(p.checksum);
        let form = match p.telemetry_form {
            TelemetryFormSetting::Motor32 => TelemetryForm::Motor32,
            TelemetryFormSetting::Motor36 => TelemetryForm::Motor36,
            TelemetryFormSetting::Complete104 => TelemetryForm::Complete104,
        };
        MotorBoard {
            kin: MecanumKinematics::from_profile(profile),
            decoder: Decoder::new(policy),
            emit_kind,
            form,
            motor_id: p.motor_id,
            telemetry: Periodic::from_hz(p.telemetry_hz),
            watchdog: p.watchdog_enabled.then(|| Duration::from_millis(u64::from(p.watchdog_ms))),
            baud: profile.serial.motor_baud,
            command: PercentCommand::default(),
            wheel_percent: [0.0; 4],
            last_command: None,
            last_drive: None,
            watchdog_tripped: false,
            measured_rpm: [0.0; 4],
            odometry: Pose2::ORIGIN,
            last_poll: None,
            counters: MotorBoardCounters::default(),
        }
    }

    /// Feeds bytes received from Carto at `now`; drive frames take effect immediately.
    pub fn receive(&mut self, now: Instant, bytes: &[u8]) {
        self.counters.bytes_received += bytes.len() as u64;
        for item in self.decoder.feed(bytes) {
            match item {
                Ok(MotorPacket::Drive(command)) => {
                    self.counters.frames_ok += 1;
                    self.counters.drive_frames += 1;
                    self.apply(command);
                    self.last_drive = Some(now);
                    self.watchdog_tripped = false;
                }
                Ok(MotorPacket::Telemetry(_)) => {
                    self.counters.frames_ok += 1;
                    self.counters.ignored_frames += 1;
                }
                Ok(MotorPacket::Unknown { packet_type, .. }) => {
                    self.counters.unknown_types += 1;
                    tracing::debug!(packet_type, "motor board: unknown packet type ignored");
                }
                Err(DecodeError::BadChecksum { expected, actual }) => {
                    self.counters.bad_checksums += 1;
                    tracing::debug!(expected, actual, "motor board: bad checksum, frame dropped");
                }
                Err(e) => {
                    self.counters.framing_errors += 1;
                    tracing::debug!(error = %e, "motor board: bad frame dropped");
                }
            }
        }
        self.check_watchdog(now);
    }

    /// Runs the board's timers at `now`; returns the bytes it sends (telemetry when due).
    pub fn poll(&mut self, now: Instant) -> Vec<u8> {
        self.check_watchdog(now);
        self.integrate_odometry(now);
        if !self.telemetry.fire(now) {
            return Vec::new();
        }
        let twist = self.kin.forward_rpm(self.measured_rpm);
        let o = self.odometry;
        let telemetry = Telemetry {
            form: self.form,
            motor_id: self.motor_id,
            wheel_rpm: self.measured_rpm,
            motor_power: self.wheel_percent,
            odometry: [o.x, o.y, o.theta, twist.vx, twist.vy, twist.omega],
            imu: [0.0; 12],
        };
        let bytes = MotorPacket::Telemetry(telemetry).to_bytes_with(self.emit_kind);
        self.counters.telemetry_sent += 1;
        self.counters.bytes_sent += bytes.len() as u64;
        bytes
    }

    /// Wheel speed setpoints for the physics, rpm, order FL, FR, RL, RR (forward positive).
    pub fn wheel_setpoints_rpm(&self) -> [f32; 4] {
        self.kin.percent_to_rpm(self.wheel_percent)
    }

    /// Commanded wheel power after mixing, percent (what telemetry reports as `motor_power`).
    pub fn wheel_percent(&self) -> [f32; 4] {
        self.wheel_percent
    }

    /// The percent command in force (clamped; zero after a watchdog trip).
    pub fn command(&self) -> PercentCommand {
        self.command
    }

    /// The last drive frame applied, as received.
    pub fn last_command(&self) -> Option<MotorCommand> {
        self.last_command
    }

    /// Reports the wheel speeds the physics measured (rpm, FL, FR, RL, RR) for telemetry.
    pub fn set_measured(&mut self, wheel_rpm: [f32; 4]) {
        self.measured_rpm = wheel_rpm.map(|v| if v.is_finite() { v } else { 0.0 });
    }

    /// Whether the watchdog has stopped the wheels and no drive frame came since.
    pub fn watchdog_tripped(&self) -> bool {
        self.watchdog_tripped
    }

    /// Counters since start.
    pub fn counters(&self) -> MotorBoardCounters {
        self.counters
    }

    /// The frame decoder's own counters.
    pub fn decoder_stats(&self) -> DecoderStats {
        self.decoder.stats()
    }

    /// Dead-reckoned pose from the measured wheel speeds (sent in the 104-byte form).
    pub fn odometry(&self) -> Pose2 {
        self.odometry
    }

    /// The next instant at which `poll` has something to do (telemetry or watchdog), if known.
    pub fn next_deadline(&self) -> Option<Instant> {
        let watchdog = match (self.watchdog, self.last_drive) {
            (Some(timeout), Some(last)) if !self.watchdog_tripped => Some(last + timeout),
            _ => None,
        };
        match (self.telemetry.next(), watchdog) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// Telemetry bytes per second at the configured rate and form.
    pub fn telemetry_bytes_per_sec(&self) -> f32 {
        self.telemetry.rate_hz() * (f32::from(self.form.payload_len()) + 4.0)
    }

    /// The line's byte budget (`motor_baud / 10`).
    pub fn budget_bytes_per_sec(&self) -> f32 {
        line_bytes_per_sec(self.baud) as f32
    }

    fn apply(&mut self, command: MotorCommand) {
        self.command = match command {
            MotorCommand::V2 { vx, vy, omega, .. } => {
                let pct = |v: i8| f32::from(v).clamp(-100.0, 100.0);
                PercentCommand { vx: pct(vx), vy: pct(vy), omega: pct(omega) }
            }
            MotorCommand::V1 { dir_x, dir_y, gear } => {
                let scale = f32::from(gear.min(8)) / 8.0;
                PercentCommand {
                    vx: axis_percent(dir_y) * scale,
                    vy: -axis_percent(dir_x) * scale,
                    omega: 0.0,
                }
            }
        };
        self.last_command = Some(command);
        let c = self.command;
        self.wheel_percent = mix_percent(c.vx, c.vy, c.omega, self.kin.mixing_k);
    }

    fn check_watchdog(&mut self, now: Instant) {
        let (Some(timeout), Some(last)) = (self.watchdog, self.last_drive) else {
            return;
        };
        if self.watchdog_tripped || now.saturating_since(last) < timeout {
            return;
        }
        self.watchdog_tripped = true;
        if self.wheel_percent.iter().any(|p| *p != 0.0) {
            self.counters.watchdog_trips += 1;
            tracing::debug!(%now, "motor board: command watchdog stopped the wheels");
        }
        self.command = PercentCommand::default();
        self.wheel_percent = [0.0; 4];
    }

    fn integrate_odometry(&mut self, now: Instant) {
        if let Some(last) = self.last_poll {
            let dt = now.saturating_since(last).as_secs_f32();
            let twist: Twist = self.kin.forward_rpm(self.measured_rpm);
            self.odometry = self.odometry.integrate(twist, dt);
        }
        self.last_poll = Some(now);
    }
}

/// An offset-binary axis byte as percent: 0x80 → 0, 0x00 → −100, 0xFF → +100.
fn axis_percent(raw: u8) -> f32 {
    let d = f32::from(raw) - 128.0;
    if d >= 0.0 { d / 127.0 * 100.0 } else { d / 128.0 * 100.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::ChecksumSetting;

    fn v2(vx: i8, vy: i8, omega: i8) -> Vec<u8> {
        MotorPacket::Drive(MotorCommand::V2 { vx, vy, omega, speed_ratio: 6, reserved: [0; 2] }).to_bytes()
    }

    fn v1(dir_x: u8, dir_y: u8, gear: u8) -> Vec<u8> {
        MotorPacket::Drive(MotorCommand::V1 { dir_x, dir_y, gear }).to_bytes()
    }

    #[test]
    fn v2_clamps_to_100_percent() {
        let mut b = MotorBoard::new(&RobotProfile::default());
        b.receive(Instant::ZERO, &v2(127, 0, 0));
        assert_eq!(b.command().vx, 100.0);
        assert_eq!(b.wheel_setpoints_rpm(), [300.0; 4]);
        b.receive(Instant::ZERO, &v2(-128, 0, 0)); // 0x80 as i8 → −128 → −100 %
        assert_eq!(b.wheel_setpoints_rpm(), [-300.0; 4]);
    }

    #[test]
    fn v2_mixing_scales_down_together() {
        let mut b = MotorBoard::new(&RobotProfile::default());
        b.receive(Instant::ZERO, &v2(100, 50, 50)); // raw [0, 200, 100, 100] → ×½
        assert_eq!(b.wheel_percent(), [0.0, 100.0, 50.0, 50.0]);
        assert_eq!(b.wheel_setpoints_rpm(), [0.0, 300.0, 150.0, 150.0]);
    }

    #[test]
    fn seed_v1_frame_is_neutral() {
        let mut b = MotorBoard::new(&RobotProfile::default());
        // The seed's example frame, verbatim.
        b.receive(Instant::ZERO, &[0xAA, 0x03, 0x01, 0x80, 0x80, 0x06, 0x0A]);
        assert_eq!(b.counters().drive_frames, 1);
        assert_eq!(b.wheel_setpoints_rpm(), [0.0; 4]);
    }

    #[test]
    fn v1_axes_are_forward_and_strafe_right() {
        let mut b = MotorBoard::new(&RobotProfile::default());
        b.receive(Instant::ZERO, &v1(0x80, 0xFF, 8)); // full forward, full gear
        assert_eq!(b.wheel_percent(), [100.0; 4]);
        b.receive(Instant::ZERO, &v1(0xFF, 0x80, 4)); // strafe right at half gear
        assert_eq!(b.command().vy, -50.0);
        // strafe right: FL, RR forward; FR, RL backward
        assert_eq!(b.wheel_percent(), [50.0, -50.0, -50.0, 50.0]);
        b.receive(Instant::ZERO, &v1(0x80, 0x00, 200)); // gear above 8 clamps
        assert_eq!(b.wheel_percent(), [-100.0; 4]);
        b.receive(Instant::ZERO, &v1(0x00, 0xFF, 0)); // gear 0 stops
        assert_eq!(b.wheel_percent(), [0.0; 4]);
    }

    #[test]
    fn unknown_types_and_telemetry_are_counted_not_applied() {
        let mut b = MotorBoard::new(&RobotProfile::default());
        b.receive(Instant::ZERO, &v2(40, 0, 0));
        b.receive(Instant::ZERO, &MotorPacket::Unknown { packet_type: 0x33, payload: vec![1, 2] }.to_bytes());
        b.receive(Instant::ZERO, &MotorPacket::Telemetry(Telemetry::motor([1.0; 4], [2.0; 4])).to_bytes());
        let c = b.counters();
        assert_eq!((c.unknown_types, c.ignored_frames, c.frames_ok, c.drive_frames), (1, 1, 2, 1));
        assert_eq!(b.wheel_percent(), [40.0; 4]);
    }

    #[test]
    fn watchdog_off_keeps_the_last_command() {
        let mut p = RobotProfile::default();
        p.motor_board.watchdog_enabled = false;
        let mut b = MotorBoard::new(&p);
        b.receive(Instant::ZERO, &v2(40, 0, 0));
        b.poll(Instant::from_secs_f64(10.0));
        assert_eq!(b.wheel_percent(), [40.0; 4]);
        assert!(!b.watchdog_tripped());
    }

    #[test]
    fn telemetry_uses_configured_form_and_checksum() {
        let mut p = RobotProfile::default();
        p.motor_board.telemetry_form = TelemetryFormSetting::Motor36;
        p.motor_board.checksum = ChecksumSetting::ConstFc;
        let mut b = MotorBoard::new(&p);
        b.set_measured([100.0, -100.0, 50.5, 0.0]);
        let bytes = b.poll(Instant::ZERO);
        assert_eq!(bytes.len(), 40);
        assert_eq!(&bytes[..7], &[0xAA, 0x24, 0x04, 0x01, 0x00, 0x00, 0x00]);
        assert_eq!(*bytes.last().unwrap(), 0xFC);
        let mut d = Decoder::new(ChecksumPolicy::ConstFc);
        match d.feed(&bytes).as_slice() {
            [Ok(MotorPacket::Telemetry(t))] => assert_eq!(t.wheel_rpm, [100.0, -100.0, 50.5, 0.0]),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn complete_form_carries_dead_reckoned_odometry() {
        let mut p = RobotProfile::default();
        p.motor_board.telemetry_form = TelemetryFormSetting::Complete104;
        let mut b = MotorBoard::new(&p);
        // 1 m/s forward: rpm = 60 / (2π · 0.039)
        let rpm = 60.0 / (core::f32::consts::TAU * 0.039);
        b.set_measured([rpm; 4]);
        b.poll(Instant::ZERO);
        let mut last = Vec::new();
        for ms in (5..=1000).step_by(5) {
            let out = b.poll(Instant::from_millis(ms));
            if !out.is_empty() {
                last = out;
            }
        }
        assert_eq!(last.len(), 108);
        let mut d = Decoder::new(ChecksumPolicy::Sum);
        match d.feed(&last).as_slice() {
            [Ok(MotorPacket::Telemetry(t))] => {
                assert!((t.odometry[0] - 1.0).abs() < 1e-3, "{:?}", t.odometry);
                assert!((t.odometry[3] - 1.0).abs() < 1e-4);
                assert!(t.odometry[1].abs() < 1e-5 && t.odometry[2].abs() < 1e-5);
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn telemetry_budget_is_far_below_115200_baud() {
        let b = MotorBoard::new(&RobotProfile::default());
        assert_eq!(b.telemetry_bytes_per_sec(), 20.0 * 36.0);
        assert_eq!(b.budget_bytes_per_sec(), 11_520.0);
    }
}
