//! The robot profile: every physical and firmware parameter of one robot, loaded from RON.
//!
//! A profile is data, never code: the default robot lives in
//! `scenarios/robots/mecanum-4wd.ron` (values and sources in `docs/reference/robot-profile.md`), and
//! [`RobotProfile::default`] returns exactly the same values (a test checks the shipped file
//! parses and equals the default). A user with another chassis writes another file.
//!
//! Invariants:
//! - Every field is required and unknown fields are rejected, so a typo is an error with its
//!   file, line and column ([`ProfileError::Parse`]), never a silently ignored value.
//! - A profile returned by [`RobotProfile::from_ron_str`] or [`RobotProfile::load`] has passed
//!   [`RobotProfile::validate`]: lengths, masses, rates and baud rates are finite and in range.
//! - Units are in the field names (`_m`, `_ms`, `_deg`, `_cm`, `_hz`, `_rpm`). A rate of `0.0` Hz
//!   turns that periodic stream off.
//!
//! ```
//! use robot_model::profile::{ProfileError, RobotProfile};
//! let text = std::fs::read_to_string(concat!(
//!     env!("CARGO_MANIFEST_DIR"),
//!     "/../scenarios/robots/mecanum-4wd.ron"
//! ))
//! .unwrap();
//! let profile = RobotProfile::from_ron_str(&text, "mecanum-4wd.ron").unwrap();
//! assert_eq!(profile, RobotProfile::default());
//! assert_eq!(profile.geometry.wheel_radius_m, 0.039);
//!
//! // Errors carry the file, line and column.
//! let err = RobotProfile::from_ron_str("(name: 3)", "bad.ron").unwrap_err();
//! assert!(matches!(err, ProfileError::Parse { line: 1, .. }));
//! assert!(err.to_string().starts_with("bad.ron:1:"));
//! ```

use std::path::Path;

use serde::{Deserialize, Serialize};

/// Errors from loading or validating a robot profile.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ProfileError {
    /// The file could not be read.
    #[error("{path}: cannot read robot profile: {message}")]
    Io {
        /// The file.
        path: String,
        /// The IO error kind.
        kind: std::io::ErrorKind,
        /// The IO error text.
        message: String,
    },
    /// The text is not valid RON for a profile (syntax, type, missing or unknown field).
    #[error("{path}:{line}:{column}: {message}")]
    Parse {
        /// The file.
        path: String,
        /// 1-based line of the error.
        line: usize,
        /// 1-based column of the error.
        column: usize,
        /// What went wrong, as RON reports it.
        message: String,
    },
    /// A value parsed but is out of range.
    #[error("{path}: invalid `{field}` = {value}: {rule}")]
    Invalid {
        /// The file.
        path: String,
        /// Dotted path of the field, e.g. `geometry.wheel_radius_m`.
        field: &'static str,
        /// The offending value.
        value: f64,
        /// The rule it breaks.
        rule: &'static str,
    },
}

/// Every parameter of one robot (see the module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotProfile {
    /// Human-readable name of the robot.
    pub name: String,
    /// Chassis geometry and mass.
    pub geometry: Geometry,
    /// Motor, gearbox and speed limits.
    pub motor: MotorParams,
    /// Wheel–floor contact.
    pub wheels: WheelParams,
    /// Wheel encoders.
    pub encoder: EncoderParams,
    /// The front HC-SR04 ultrasonic sensor.
    pub sonar: SonarParams,
    /// The IMU (NavX-style fused heading).
    pub imu: ImuParams,
    /// The front bumper switch.
    pub bumper: BumperParams,
    /// Serial line speeds.
    pub serial: SerialParams,
    /// Motor board firmware behaviour.
    pub motor_board: MotorBoardParams,
    /// Sensor board firmware behaviour.
    pub sensor_board: SensorBoardParams,
    /// Default grid cell size for this robot, metres. Half a cell must hold the circle the body
    /// sweeps turning on the spot (half its diagonal: 17.7 cm for 0.26 × 0.24 m) plus the 5 cm
    /// position error a run may have, so the default is 2 × (17.7 + 4.8) cm = 0.45 m. The
    /// design's 0.30 m leaves 15 cm to a wall on a cell line: the robot cannot turn there.
    /// A scenario may set its own (`cell:`); every part of a run then uses that one.
    pub grid_cell_m: f32,
    /// How a run of this robot is scored: the margin it keeps, how far off a cell's centre a stop
    /// may end, and the pass criteria generated rooms get ([`Scoring`]).
    pub scoring: Scoring,
}

/// How a run of this robot is scored. The cells a body keeping `clearance_m` from everything,
/// ending every command within `stop_within_m` of a cell's centre, can reach from its start cell
/// are the *scored set*: coverage and accuracy count those; cells reachable only with less
/// clearance are *tight* and count neither way.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scoring {
    /// The margin the controller keeps from everything, metres (Carto keeps 2 cm).
    pub clearance_m: f32,
    /// How far from a cell's centre a command may end, metres.
    pub stop_within_m: f32,
    /// The pass criteria a generated room gets (a scenario file sets its own).
    pub pass: PassCriteria,
}

/// The pass criteria of a run (each `None` is not checked). Touches and hard collisions are
/// defined by the twin's report: a *hard collision* is a contact that began at 0.10 m/s or more
/// or pushed the body 2 cm or more from where its wheels drove it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PassCriteria {
    /// Least fraction (0–1) of the scored set Cute's map shows free.
    pub coverage_min: Option<f64>,
    /// Least fraction (0–1) of the classified cells (tight cells left out) that are right.
    pub map_accuracy_min: Option<f64>,
    /// Most touches of any kind (`Some(0)`: a robot that senses beside its body).
    pub touches_max: Option<u32>,
    /// Most hard collisions.
    pub hard_collisions_max: Option<u32>,
    /// Most touches per 100 moves Cute sent.
    pub touches_per_100_moves_max: Option<f64>,
    /// Largest distance between the true body centre and Carto's belief, metres.
    pub belief_error_max_m: Option<f64>,
    /// 95th percentile of that distance over the run's samples, metres.
    pub belief_error_p95_max_m: Option<f64>,
    /// Largest angle between the true heading and Carto's believed heading, degrees.
    pub belief_heading_error_max_deg: Option<f64>,
    /// `Some(true)`: at the end, Cute's cell for the robot is the true one.
    pub believed_cell_true: Option<bool>,
}

impl Default for Scoring {
    /// The one-sonar robot of 2024: 2 cm kept, 2 cm off a centre, the criteria of
    /// `scenarios/robots/mecanum-4wd.ron`.
    fn default() -> Self {
        Scoring {
            clearance_m: 0.02,
            stop_within_m: 0.02,
            pass: PassCriteria {
                coverage_min: Some(0.98),
                map_accuracy_min: Some(0.95),
                touches_max: None,
                hard_collisions_max: Some(0),
                touches_per_100_moves_max: Some(1.0),
                belief_error_max_m: Some(0.05),
                belief_error_p95_max_m: Some(0.03),
                belief_heading_error_max_deg: Some(3.0),
                believed_cell_true: Some(true),
            },
        }
    }
}

/// Chassis geometry and mass.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Geometry {
    /// Wheel radius, metres.
    pub wheel_radius_m: f32,
    /// Distance between front and rear axles, metres.
    pub wheelbase_m: f32,
    /// Distance between left and right wheel contact lines, metres.
    pub track_m: f32,
    /// Body length along `x` (forward), metres.
    pub body_length_m: f32,
    /// Body width along `y` (left), metres.
    pub body_width_m: f32,
    /// Total mass, kilograms.
    pub mass_kg: f32,
}

/// Motor, gearbox and speed limits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotorParams {
    /// Gearbox reduction, motor turns per wheel turn.
    pub gear_ratio: f32,
    /// Wheel speed at 100 % command, rpm.
    pub max_wheel_rpm: f32,
    /// First-order time constant of the wheel speed response, milliseconds.
    pub tau_ms: f32,
    /// Commands below this share of full speed do not move the wheel, percent.
    pub dead_band_percent: f32,
}

/// Wheel–floor contact.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WheelParams {
    /// Friction coefficient along the wheel's driving direction.
    pub friction_mu: f32,
    /// Angle between the rollers' axes and the wheel axis, degrees (45 for mecanum).
    pub roller_angle_deg: f32,
}

/// Wheel encoders.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EncoderParams {
    /// Encoder pulses per motor revolution (times `motor.gear_ratio` per wheel revolution).
    pub pulses_per_motor_rev: f32,
}

/// The front HC-SR04 ultrasonic sensor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SonarParams {
    /// Mount position ahead of the chassis centre, metres (body `x`).
    pub mount_x_m: f32,
    /// Mount position left of the chassis centre, metres (body `y`).
    pub mount_y_m: f32,
    /// Mount direction, degrees CCW from body forward.
    pub mount_heading_deg: f32,
    /// Full cone width, degrees.
    pub cone_deg: f32,
    /// Number of rays cast across the cone (the twin casts them; Carto expects ranges from the
    /// same fan, `CartoConfig.sonar.rays`).
    pub rays: u32,
    /// Shortest distance that gives an echo, centimetres.
    pub min_cm: f32,
    /// Longest distance that gives an echo, centimetres.
    pub max_cm: f32,
    /// Measurement cycle, milliseconds.
    pub cycle_ms: u32,
    /// Echoes hitting a surface beyond this incidence (from the normal) are lost, degrees.
    pub incidence_limit_deg: f32,
    /// Gaussian noise on the distance, standard deviation in centimetres.
    pub noise_sigma_cm: f32,
}

/// The IMU.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImuParams {
    /// Gaussian noise on the heading, standard deviation in degrees.
    pub noise_sigma_deg: f32,
    /// Linear heading drift, degrees per minute (positive = reading grows clockwise).
    pub drift_deg_per_min: f32,
}

/// The front bumper switch.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BumperParams {
    /// Width of the switch's contact strip across the front face, centred, metres.
    pub face_width_m: f32,
}

/// Serial line speeds (8N1: ten bits per byte).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SerialParams {
    /// Carto ⇄ motor board, baud.
    pub motor_baud: u32,
    /// Carto ⇄ sensor board, baud.
    pub sensor_baud: u32,
}

/// Telemetry payload form sent by the motor board (see protocols.md §2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum TelemetryFormSetting {
    /// 32 bytes: wheel rpm ×4, motor power ×4 (the seed's form).
    Motor32,
    /// 36 bytes: motor id + 3 padding bytes, then the 32 bytes (later firmware).
    Motor36,
    /// 104 bytes: motor block + odometry + IMU (our extension, in no firmware).
    Complete104,
}

/// Checksum the motor board puts on the frames it sends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ChecksumSetting {
    /// `(LEN + TYPE + Σ payload) mod 256` (the seed's rule).
    Sum,
    /// XOR of the payload bytes (Zephyr firmware).
    XorPayload,
    /// The constant `0xFC` (Arduino firmware).
    ConstFc,
}

impl From<ChecksumSetting> for protocol::motor::ChecksumKind {
    fn from(s: ChecksumSetting) -> Self {
        match s {
            ChecksumSetting::Sum => protocol::motor::ChecksumKind::Sum,
            ChecksumSetting::XorPayload => protocol::motor::ChecksumKind::XorPayload,
            ChecksumSetting::ConstFc => protocol::motor::ChecksumKind::ConstFc,
        }
    }
}

impl From<ChecksumSetting> for protocol::motor::ChecksumPolicy {
    /// The receive policy that checks what a board with this setting sends.
    fn from(s: ChecksumSetting) -> Self {
        match s {
            ChecksumSetting::Sum => protocol::motor::ChecksumPolicy::Sum,
            ChecksumSetting::XorPayload => protocol::motor::ChecksumPolicy::XorPayload,
            ChecksumSetting::ConstFc => protocol::motor::ChecksumPolicy::ConstFc,
        }
    }
}

/// Checksums the motor board accepts on the frames it receives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum AcceptChecksumSetting {
    /// Only the sum checksum.
    Sum,
    /// Only XOR of the payload.
    XorPayload,
    /// Only the constant `0xFC`.
    ConstFc,
    /// Any checksum byte (what every real firmware receiver does).
    Ignore,
}

impl From<AcceptChecksumSetting> for protocol::motor::ChecksumPolicy {
    fn from(s: AcceptChecksumSetting) -> Self {
        match s {
            AcceptChecksumSetting::Sum => protocol::motor::ChecksumPolicy::Sum,
            AcceptChecksumSetting::XorPayload => protocol::motor::ChecksumPolicy::XorPayload,
            AcceptChecksumSetting::ConstFc => protocol::motor::ChecksumPolicy::ConstFc,
            AcceptChecksumSetting::Ignore => protocol::motor::ChecksumPolicy::Ignore,
        }
    }
}

/// Motor board firmware behaviour.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotorBoardParams {
    /// Whether the command watchdog stops the wheels when drive frames stop coming.
    pub watchdog_enabled: bool,
    /// Watchdog timeout, milliseconds.
    pub watchdog_ms: u32,
    /// Telemetry payload form.
    pub telemetry_form: TelemetryFormSetting,
    /// Telemetry rate, Hz (0 = off).
    pub telemetry_hz: f32,
    /// Checksum on emitted frames.
    pub checksum: ChecksumSetting,
    /// Checksum policy on received frames.
    pub accept_checksum: AcceptChecksumSetting,
    /// Rotation gain `k` of the board's mixing (`FL = vx − vy − k·ω`, …).
    pub mixing_k: f32,
    /// Motor id written in the 36-byte telemetry form.
    pub motor_id: u8,
}

/// Sensor board firmware behaviour; rates in Hz, `0.0` turns a periodic stream off.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorBoardParams {
    /// Keep-state rate, Hz.
    pub keep_state_hz: f32,
    /// Distance (HC-SR04) report rate, Hz.
    pub distance_hz: f32,
    /// NavX report rate, Hz.
    pub navx_hz: f32,
    /// Report rate of each encoder, Hz.
    pub encoder_hz: f32,
    /// Bumper heartbeat rate, Hz (it also reports on every change).
    pub bumper_heartbeat_hz: f32,
    /// No keep-state from Carto for this long means the peer is lost, milliseconds.
    pub peer_lost_timeout_ms: u32,
}

impl Default for RobotProfile {
    /// The default robot, equal to `scenarios/robots/mecanum-4wd.ron`.
    fn default() -> Self {
        RobotProfile {
            name: "mecanum-4wd".to_owned(),
            geometry: Geometry {
                wheel_radius_m: 0.039,
                wheelbase_m: 0.20,
                track_m: 0.18,
                body_length_m: 0.26,
                body_width_m: 0.24,
                mass_kg: 1.6,
            },
            motor: MotorParams {
                gear_ratio: 18.8,
                max_wheel_rpm: 300.0,
                tau_ms: 80.0,
                dead_band_percent: 5.0,
            },
            wheels: WheelParams { friction_mu: 0.8, roller_angle_deg: 45.0 },
            encoder: EncoderParams { pulses_per_motor_rev: 11.0 },
            sonar: SonarParams {
                mount_x_m: 0.13,
                mount_y_m: 0.0,
                mount_heading_deg: 0.0,
                cone_deg: 15.0,
                rays: 5,
                min_cm: 2.0,
                max_cm: 400.0,
                cycle_ms: 60,
                incidence_limit_deg: 22.5,
                noise_sigma_cm: 0.3,
            },
            imu: ImuParams { noise_sigma_deg: 0.2, drift_deg_per_min: 0.5 },
            bumper: BumperParams { face_width_m: 0.24 },
            serial: SerialParams { motor_baud: 115_200, sensor_baud: 9_600 },
            motor_board: MotorBoardParams {
                watchdog_enabled: true,
                watchdog_ms: 500,
                telemetry_form: TelemetryFormSetting::Motor32,
                telemetry_hz: 20.0,
                checksum: ChecksumSetting::Sum,
                accept_checksum: AcceptChecksumSetting::Sum,
                mixing_k: 1.0,
                motor_id: 1,
            },
            sensor_board: SensorBoardParams {
                keep_state_hz: 2.0,
                distance_hz: 10.0,
                navx_hz: 10.0,
                encoder_hz: 5.0,
                bumper_heartbeat_hz: 1.0,
                peer_lost_timeout_ms: 1500,
            },
            grid_cell_m: 0.45,
            scoring: Scoring::default(),
        }
    }
}

impl RobotProfile {
    /// Parses and validates a profile; `path_for_errors` names the source in error messages.
    pub fn from_ron_str(text: &str, path_for_errors: impl AsRef<Path>) -> Result<Self, ProfileError> {
        let path = path_for_errors.as_ref().display().to_string();
        let profile: RobotProfile =
            ron::Options::default().from_str(text).map_err(|e| ProfileError::Parse {
                path: path.clone(),
                line: e.span.start.line,
                column: e.span.start.col,
                message: e.code.to_string(),
            })?;
        profile.validate_with_path(&path)?;
        Ok(profile)
    }

    /// Reads, parses and validates a profile file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ProfileError> {
        let path = path.as_ref();
        let text = crate::files::read_text_bounded(path, crate::files::TEXT_FILE_LIMIT).map_err(|e| {
            ProfileError::Io { path: path.display().to_string(), kind: e.kind(), message: e.to_string() }
        })?;
        Self::from_ron_str(&text, path)
    }

    /// Serialises the profile as pretty RON (loads back to an equal profile).
    pub fn to_ron_string(&self) -> Result<String, ron::Error> {
        ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::default())
    }

    /// Checks every value's range; errors name the field and the rule (path shown as `<profile>`).
    pub fn validate(&self) -> Result<(), ProfileError> {
        self.validate_with_path("<profile>")
    }

    /// Encoder pulses per wheel revolution (`pulses_per_motor_rev × gear_ratio`).
    pub fn pulses_per_wheel_rev(&self) -> f32 {
        self.encoder.pulses_per_motor_rev * self.motor.gear_ratio
    }

    /// Rim speed of a wheel at 100 % command, m/s.
    pub fn max_rim_speed_mps(&self) -> f32 {
        self.motor.max_wheel_rpm * core::f32::consts::TAU / 60.0 * self.geometry.wheel_radius_m
    }

    fn validate_scoring(&self, path: &str) -> Result<(), ProfileError> {
        let bad = |field: &'static str, value: f64, rule: &'static str| {
            Err(ProfileError::Invalid { path: path.to_owned(), field, value, rule })
        };
        let s = &self.scoring;
        let half_cell = 0.5 * self.grid_cell_m;
        for (field, v) in [("scoring.clearance_m", s.clearance_m), ("scoring.stop_within_m", s.stop_within_m)]
        {
            if !(v.is_finite() && v >= 0.0 && v < half_cell) {
                return bad(field, decimal(v), "must be a finite number, zero or more, under half a cell");
            }
        }
        let p = &s.pass;
        for (field, v) in [
            ("scoring.pass.coverage_min", p.coverage_min),
            ("scoring.pass.map_accuracy_min", p.map_accuracy_min),
        ] {
            if let Some(v) = v
                && !(0.0..=1.0).contains(&v)
            {
                return bad(field, v, "must be a fraction in [0, 1]");
            }
        }
        for (field, v) in [
            ("scoring.pass.touches_per_100_moves_max", p.touches_per_100_moves_max),
            ("scoring.pass.belief_error_max_m", p.belief_error_max_m),
            ("scoring.pass.belief_error_p95_max_m", p.belief_error_p95_max_m),
            ("scoring.pass.belief_heading_error_max_deg", p.belief_heading_error_max_deg),
        ] {
            if let Some(v) = v
                && !(v.is_finite() && v >= 0.0)
            {
                return bad(field, v, "must be a finite number, zero or more");
            }
        }
        Ok(())
    }

    fn validate_with_path(&self, path: &str) -> Result<(), ProfileError> {
        let bad = |field: &'static str, value: f64, rule: &'static str| {
            Err(ProfileError::Invalid { path: path.to_owned(), field, value, rule })
        };
        let positive: [(&'static str, f32); 15] = [
            ("geometry.wheel_radius_m", self.geometry.wheel_radius_m),
            ("geometry.wheelbase_m", self.geometry.wheelbase_m),
            ("geometry.track_m", self.geometry.track_m),
            ("geometry.body_length_m", self.geometry.body_length_m),
            ("geometry.body_width_m", self.geometry.body_width_m),
            ("geometry.mass_kg", self.geometry.mass_kg),
            ("motor.gear_ratio", self.motor.gear_ratio),
            ("motor.max_wheel_rpm", self.motor.max_wheel_rpm),
            ("encoder.pulses_per_motor_rev", self.encoder.pulses_per_motor_rev),
            ("sonar.cone_deg", self.sonar.cone_deg),
            ("sonar.max_cm", self.sonar.max_cm),
            ("bumper.face_width_m", self.bumper.face_width_m),
            ("motor_board.mixing_k", self.motor_board.mixing_k),
            ("grid_cell_m", self.grid_cell_m),
            ("wheels.roller_angle_deg", self.wheels.roller_angle_deg),
        ];
        for (field, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return bad(field, decimal(v), "must be a finite number greater than zero");
            }
        }
        let non_negative: [(&'static str, f32); 12] = [
            ("motor.tau_ms", self.motor.tau_ms),
            ("wheels.friction_mu", self.wheels.friction_mu),
            ("sonar.min_cm", self.sonar.min_cm),
            ("sonar.noise_sigma_cm", self.sonar.noise_sigma_cm),
            ("imu.noise_sigma_deg", self.imu.noise_sigma_deg),
            ("motor_board.telemetry_hz", self.motor_board.telemetry_hz),
            ("sensor_board.keep_state_hz", self.sensor_board.keep_state_hz),
            ("sensor_board.distance_hz", self.sensor_board.distance_hz),
            ("sensor_board.navx_hz", self.sensor_board.navx_hz),
            ("sensor_board.encoder_hz", self.sensor_board.encoder_hz),
            ("sensor_board.bumper_heartbeat_hz", self.sensor_board.bumper_heartbeat_hz),
            ("sonar.incidence_limit_deg", self.sonar.incidence_limit_deg),
        ];
        for (field, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return bad(field, decimal(v), "must be a finite number, zero or more");
            }
        }
        let finite: [(&'static str, f32); 4] = [
            ("sonar.mount_x_m", self.sonar.mount_x_m),
            ("sonar.mount_y_m", self.sonar.mount_y_m),
            ("sonar.mount_heading_deg", self.sonar.mount_heading_deg),
            ("imu.drift_deg_per_min", self.imu.drift_deg_per_min),
        ];
        for (field, v) in finite {
            if !v.is_finite() {
                return bad(field, decimal(v), "must be a finite number");
            }
        }
        if self.motor.dead_band_percent < 0.0 || self.motor.dead_band_percent >= 100.0 {
            return bad(
                "motor.dead_band_percent",
                decimal(self.motor.dead_band_percent),
                "must be in [0, 100)",
            );
        }
        if self.wheels.roller_angle_deg >= 90.0 {
            return bad(
                "wheels.roller_angle_deg",
                decimal(self.wheels.roller_angle_deg),
                "must be in (0, 90)",
            );
        }
        if self.sonar.cone_deg >= 180.0 {
            return bad("sonar.cone_deg", decimal(self.sonar.cone_deg), "must be in (0, 180)");
        }
        if self.sonar.rays == 0 {
            return bad("sonar.rays", 0.0, "must be at least 1");
        }
        if self.sonar.min_cm >= self.sonar.max_cm {
            return bad("sonar.min_cm", decimal(self.sonar.min_cm), "must be less than sonar.max_cm");
        }
        if self.sonar.cycle_ms == 0 {
            return bad("sonar.cycle_ms", 0.0, "must be at least 1");
        }
        if self.sonar.incidence_limit_deg > 90.0 {
            return bad(
                "sonar.incidence_limit_deg",
                decimal(self.sonar.incidence_limit_deg),
                "must be in [0, 90]",
            );
        }
        self.validate_scoring(path)?;
        if self.serial.motor_baud == 0 {
            return bad("serial.motor_baud", 0.0, "must be at least 1");
        }
        if self.serial.sensor_baud == 0 {
            return bad("serial.sensor_baud", 0.0, "must be at least 1");
        }
        if self.motor_board.watchdog_enabled && self.motor_board.watchdog_ms == 0 {
            return bad("motor_board.watchdog_ms", 0.0, "must be at least 1 when the watchdog is enabled");
        }
        if self.sensor_board.peer_lost_timeout_ms == 0 {
            return bad("sensor_board.peer_lost_timeout_ms", 0.0, "must be at least 1");
        }
        Ok(())
    }
}

/// Widens an `f32` through its shortest decimal form (`-0.039f32` → `-0.039`), for messages.
fn decimal(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(f64::from(v))
}

#[cfg(test)]
mod tests;
