//! Carto's tuning: geometry, control gains, tolerances and timeouts, in one plain struct.
//!
//! Every number the controller uses lives here, so a user with another chassis changes the robot
//! profile (or this struct), never code. [`CartoConfig::default`] matches the default robot of
//! `robot.md` (mecanum 4WD) with 0.45 m cells (the design's 0.30 m cannot hold the turning body:
//! see `RobotProfile::grid_cell_m`); [`CartoConfig::from_profile`] derives the geometry from a
//! [`robot_model::profile::RobotProfile`] and keeps the controller defaults.
//!
//! Invariants: lengths in metres, angles in degrees, speeds as drive v2 percentages (±100, where
//! 100 % is the profile's maximum wheel speed), times as [`Duration`].
//!
//! ```
//! use carto::CartoConfig;
//! let cfg = CartoConfig::default();
//! assert!((cfg.cell_size_m - 0.45).abs() < 1e-9);
//! // 11 pulses × 18.8 per wheel revolution, wheel radius 0.039 m → about 844 counts per metre
//! assert!((cfg.encoder_counts_per_metre() - 843.9).abs() < 0.5);
//! ```

use protocol::motor::ChecksumPolicy;
use robot_model::profile::RobotProfile;
use robot_model::time::Duration;

/// Everything Carto needs to know about the robot and how to drive it, in typed sections.
///
/// An optional behaviour is an `Option` (or, without parameters of its own, one `bool`) in the
/// section that owns it, and a behaviour that needs another lives inside it
/// ([`ImuDrift::push_watch`] cannot be on without the drift estimate it watches). What every robot
/// does (readings kept while turning and driving, turns checked against the memory, shifts across
/// the heading, backing off after a contact) has no switch.
#[derive(Debug, Clone, PartialEq)]
pub struct CartoConfig {
    /// Side of one grid cell, metres: one FORWARD drives this far.
    pub cell_size_m: f64,
    /// The body, its wheels and encoders.
    pub chassis: Chassis,
    /// The forward ultrasonic sensor.
    pub sonar: Sonar,
    /// How close Carto lets the body come to what it knows, and how it looks first.
    pub safety: Safety,
    /// Speed laws, tolerances and timeouts of a move.
    pub motion: Motion,
    /// How the IMU's heading is combined with the wheels'.
    pub imu: Imu,
    /// The two boards: line speeds, checksums, periods, timeouts.
    pub boards: Boards,
    /// The TCP client (Cute).
    pub client: Client,
}

/// The body, its wheels and encoders (the profile's geometry, wheels, encoder and motor).
#[derive(Debug, Clone, PartialEq)]
pub struct Chassis {
    /// Wheel radius, metres.
    pub wheel_radius_m: f64,
    /// Distance between the front and rear axles, metres.
    pub wheelbase_m: f64,
    /// Distance between the left and right wheels, metres.
    pub track_m: f64,
    /// `tan` of the mecanum roller angle (1 at 45°): strafe distance = wheel travel / this.
    pub roller_tan: f64,
    /// Encoder counts per wheel revolution (pulses per motor revolution × gear ratio).
    pub encoder_counts_per_wheel_rev: f64,
    /// Wheel speed that a 100 % drive command means, rpm.
    pub max_wheel_rpm: f64,
    /// Body length (front to back), metres: the footprint the corridor and turn checks sweep.
    pub body_length_m: f64,
    /// Body width, metres.
    pub body_width_m: f64,
    /// Standard deviation of the wheels' distance per metre driven (slip, stop error), metres.
    pub odometry_sigma_per_m: f64,
}

/// The forward ultrasonic sensor (the profile's `sonar`).
#[derive(Debug, Clone, PartialEq)]
pub struct Sonar {
    /// How far ahead of the robot's centre the sonar sits, metres.
    pub mount_m: f64,
    /// Full opening angle of the cone, degrees (the HC-SR04's 15°).
    pub cone_deg: f64,
    /// Rays the sensor model spreads evenly across the cone, the nearest audible one answering
    /// (the profile's `sonar.rays`, the fan the twin casts): the localiser expects a range from
    /// the same fan (`estimate/localiser.rs`).
    pub rays: u32,
    /// The range: no echo means nothing closer than this, metres.
    pub max_m: f64,
    /// A surface met further than this from head-on returns no echo, degrees (the profile's
    /// incidence limit; the localiser's sensor model).
    pub incidence_deg: f64,
    /// Standard deviation of one reading, metres (the profile's noise).
    pub sigma_m: f64,
    /// How long before a distance frame arrives its reading was measured, on average: half the
    /// HC-SR04's measuring cycle (the board sends the latest result). Places readings taken
    /// while moving.
    pub lag: Duration,
}

/// How close Carto lets the body come to what it knows, and how it looks before it moves
/// (`pilot/safety.rs`).
#[derive(Debug, Clone, PartialEq)]
pub struct Safety {
    /// An ultrasound echo at or closer than this blocks the cell ahead, cm (default: one cell).
    pub obstacle_threshold_cm: f32,
    /// How long the obstacle check waits for a distance reading taken at rest before giving up.
    pub distance_wait: Duration,
    /// A distance reading older than this never counts for the obstacle check (the HC-SR04
    /// reports at 10 Hz: three periods).
    pub distance_max_age: Duration,
    /// Room kept between the swept body and any echo point Carto knows, metres.
    pub clearance_m: f64,
    /// How far from a cell's centre a FORWARD may end, metres: a FORWARD whose corridor lacks
    /// [`Safety::clearance_m`] on one side drives on a track moved aside by up to this less
    /// [`Motion::lateral_tolerance_m`] (`pilot/safety.rs`, "Corridor"). The twin scores the
    /// cells a robot reaches stopping within the same 2 cm (the profile's `scoring`).
    pub stop_within_m: f64,
    /// Before a FORWARD whose straight reading is clear, the sonar also looks this far left and
    /// right of the grid heading (two small turns on the spot and back), degrees. `None`: one
    /// straight reading, as in the design document. See [`crate::surroundings`].
    pub scan_deg: Option<f64>,
    /// After each mapping turn the robot turns on past its new heading by this much and back,
    /// its sonar listening: the end of the turn sweeps the cone across one side of the next
    /// FORWARD's path, this sweeps it across the other. Degrees; `None`: no look. Not after a
    /// STOP in a trajectory batch: Cute cannot tell which of its turns were made
    /// (`docs/explanation/carto-design.md`).
    pub look_past_turn_deg: Option<f64>,
    /// Watch the sonar while a FORWARD runs: a range that holds while the wheels drive means the
    /// body is stuck and the wheels slip; Carto stops, corrects its position by the sonar, answers
    /// `SET_OBSTACLE_POSITION` and drives back (`pilot/stall.rs`).
    pub stall_watch: bool,
}

/// Speed laws, tolerances and timeouts of a move (`motor/`).
#[derive(Debug, Clone, PartialEq)]
pub struct Motion {
    /// Cruise speed of a FORWARD, percent.
    pub cruise_pct: f64,
    /// Slowest drive command that still moves the robot (above the motor dead band), percent.
    pub min_drive_pct: f64,
    /// Acceleration ramp at the start of a FORWARD, percent per second.
    pub accel_pct_per_s: f64,
    /// Slow-down near the target: commanded speed = gain × remaining distance, percent per metre.
    pub slow_gain_pct_per_m: f64,
    /// Heading hold while driving straight: omega = gain × heading error, percent per degree.
    pub hold_gain_pct_per_deg: f64,
    /// Largest heading-hold correction, percent.
    pub hold_max_pct: f64,
    /// Lateral hold while driving a cell: vy = −gain × offset left of the track, percent per metre.
    pub lateral_gain_pct_per_m: f64,
    /// Largest lateral-hold strafe, percent.
    pub lateral_max_pct: f64,
    /// Turn speed law: omega = gain × remaining angle, percent per degree.
    pub turn_gain_pct_per_deg: f64,
    /// Fastest turn, percent.
    pub turn_max_pct: f64,
    /// Slowest turn that still moves the robot, percent.
    pub turn_min_pct: f64,
    /// Motion continues this long after a zero command (motor lag): stop that much early, seconds.
    pub stop_lead_s: f64,
    /// How fast the stop point learns the robot's systematic overshoot: after each FORWARD the
    /// stop moves earlier by this fraction of the overshoot seen at rest (0: it never learns).
    pub coast_learn_gain: f64,
    /// A FORWARD ends within this distance of its target, metres.
    pub distance_tolerance_m: f64,
    /// A FORWARD that ends further than this off its track strafes back (a correction), metres.
    pub lateral_tolerance_m: f64,
    /// Slowest strafe that still moves the robot sideways (settle corrections), percent.
    pub min_strafe_pct: f64,
    /// A turn ends within this angle of its target, degrees.
    pub heading_tolerance_deg: f64,
    /// After a zero command, readings count as "at rest" once taken this long after the stop.
    pub settle_time: Duration,
    /// Corrective nudges allowed after the first stop before a move fails.
    pub max_corrections: u8,
    /// A move that has not finished after this long is stopped and fails.
    pub move_timeout: Duration,
    /// A turn whose heading has not come [`crate::motor::JAM_PROGRESS_DEG`] closer to its target
    /// for this long is jammed: it stops and fails (then Carto turns back), instead of pushing
    /// whatever blocks the body until [`Motion::move_timeout`].
    pub jam_after: Duration,
}

/// How the IMU's heading is combined with the wheels' (`sensors.rs`).
#[derive(Debug, Clone, PartialEq)]
pub struct Imu {
    /// Estimate the IMU's drift against the wheels' heading; `None`: take the IMU as it reads.
    pub drift: Option<ImuDrift>,
    /// Pull the wheels' heading towards the IMU in the yaw the controller steers by
    /// (`SensorState::smooth_yaw`); `None`: steer by the raw IMU.
    pub smoothing: Option<ImuSmoothing>,
}

/// The IMU drift estimate against the wheels' heading.
#[derive(Debug, Clone, PartialEq)]
pub struct ImuDrift {
    /// Time constant of the estimate, seconds.
    pub tau_s: f64,
    /// Fastest change of the estimate, degrees per minute.
    pub max_deg_per_min: f64,
    /// Watch the estimate's jumps while a FORWARD runs: when the gap between the IMU's and the
    /// wheels' headings jumps by more than [`crate::sensors::PUSH_JUMP_DEG`], something the body
    /// touches turned it under its wheels; Carto stops, answers `SET_OBSTACLE_POSITION` and
    /// drives back, as after the bumper (`pilot.rs`, "Pushed").
    pub push_watch: bool,
}

/// The smoothed yaw the controller steers by.
#[derive(Debug, Clone, PartialEq)]
pub struct ImuSmoothing {
    /// Time constant with which the IMU pulls the wheels' heading, seconds.
    pub tau_s: f64,
    /// The smoothed yaw restarts from the IMU when the two disagree by more than this, degrees.
    pub reset_deg: f64,
}

/// The two boards: line speeds, checksums, periods and timeouts.
#[derive(Debug, Clone, PartialEq)]
pub struct Boards {
    /// A reading older than this is stale: a move cannot start, a running move stops and fails.
    pub sensor_stale_after: Duration,
    /// Motor telemetry (wheel rpm) younger than this is used to extrapolate odometry.
    pub telemetry_fresh: Duration,
    /// Odometry is extrapolated from the last reading by at most this long.
    pub max_extrapolation: Duration,
    /// While a move runs, the drive command is repeated this often (board watchdog: 500 ms).
    pub drive_resend_period: Duration,
    /// While idle, the zero drive command is repeated this often.
    pub idle_resend_period: Duration,
    /// `speed_ratio` byte of every drive v2 frame (unused by the firmware).
    pub speed_ratio: u8,
    /// Carto's keep-state period towards the sensor board (2 Hz).
    pub keep_state_period: Duration,
    /// No keep-state from the sensor board for this long → peer lost.
    pub peer_lost_after: Duration,
    /// First wait before reopening a board port that went away; doubles up to
    /// [`Boards::retry_max`].
    pub retry_initial: Duration,
    /// Longest wait between two attempts to reopen a board port.
    pub retry_max: Duration,
    /// Checksums accepted on the motor board's frames (what its firmware emits).
    pub motor_checksum: ChecksumPolicy,
    /// Motor board line speed, baud, for reading time stamps (0 = take arrival times as is).
    pub motor_baud: u32,
    /// Sensor board line speed, baud, for reading time stamps (0 = take arrival times as is).
    pub sensor_baud: u32,
}

/// The TCP client (Cute).
#[derive(Debug, Clone, PartialEq)]
pub struct Client {
    /// Largest accepted link frame `Size`, bytes.
    pub max_frame: usize,
    /// A client that sends no byte for this long is closed and the next one served (`None`: never;
    /// Cute may stay silent while the operator watches, so this is off by default).
    pub idle_limit: Option<Duration>,
    /// A client whose host stops answering (no bytes and no TCP keepalive answer) is dropped after
    /// about this long (`None`: the system's keepalive, i.e. off). Applied by the binary to the
    /// TCP socket; the in-memory links of the simulator ignore it.
    pub dead_after: Option<Duration>,
}

impl Default for CartoConfig {
    fn default() -> Self {
        CartoConfig {
            cell_size_m: 0.45,
            chassis: Chassis {
                wheel_radius_m: 0.039,
                wheelbase_m: 0.20,
                track_m: 0.18,
                roller_tan: 1.0,
                encoder_counts_per_wheel_rev: 11.0 * 18.8,
                max_wheel_rpm: 300.0,
                body_length_m: 0.26,
                body_width_m: 0.24,
                odometry_sigma_per_m: 0.01,
            },
            sonar: Sonar {
                mount_m: 0.13,
                cone_deg: 15.0,
                rays: 5,
                max_m: 4.0,
                incidence_deg: 22.5,
                sigma_m: 0.003,
                lag: Duration::from_millis(30),
            },
            safety: Safety {
                obstacle_threshold_cm: 45.0,
                distance_wait: Duration::from_millis(1000),
                distance_max_age: Duration::from_millis(300),
                clearance_m: 0.02,
                stop_within_m: 0.02,
                scan_deg: None,
                look_past_turn_deg: Some(20.0),
                stall_watch: true,
            },
            motion: Motion {
                cruise_pct: 30.0,
                min_drive_pct: 8.0,
                accel_pct_per_s: 120.0,
                slow_gain_pct_per_m: 150.0,
                hold_gain_pct_per_deg: 1.5,
                hold_max_pct: 10.0,
                lateral_gain_pct_per_m: 200.0,
                lateral_max_pct: 6.0,
                turn_gain_pct_per_deg: 0.5,
                turn_max_pct: 25.0,
                turn_min_pct: 8.0,
                stop_lead_s: 0.08,
                coast_learn_gain: 0.5,
                distance_tolerance_m: 0.01,
                lateral_tolerance_m: 0.01,
                min_strafe_pct: 8.0,
                heading_tolerance_deg: 2.0,
                settle_time: Duration::from_millis(200),
                max_corrections: 4,
                move_timeout: Duration::from_secs(8),
                jam_after: Duration::from_millis(750),
            },
            imu: Imu {
                drift: Some(ImuDrift { tau_s: 2.0, max_deg_per_min: 3.0, push_watch: true }),
                smoothing: Some(ImuSmoothing { tau_s: 0.5, reset_deg: 1.0 }),
            },
            boards: Boards {
                sensor_stale_after: Duration::from_millis(600),
                telemetry_fresh: Duration::from_millis(150),
                max_extrapolation: Duration::from_millis(300),
                drive_resend_period: Duration::from_millis(100),
                idle_resend_period: Duration::from_millis(500),
                speed_ratio: 100,
                keep_state_period: Duration::from_millis(500),
                peer_lost_after: Duration::from_millis(1500),
                retry_initial: Duration::from_millis(250),
                retry_max: Duration::from_secs(2),
                motor_checksum: ChecksumPolicy::Sum,
                motor_baud: 115_200,
                sensor_baud: 9600,
            },
            client: Client { max_frame: 1024, idle_limit: None, dead_after: Some(Duration::from_secs(15)) },
        }
    }
}

impl CartoConfig {
    /// The controller defaults with the geometry, encoder, speed, cell size, motor checksum and
    /// peer-lost timeout of `profile`; the obstacle threshold is one cell.
    pub fn from_profile(profile: &RobotProfile) -> Self {
        let g = &profile.geometry;
        // Profile values are f32: keep their 7 significant digits so 0.30 stays 0.30 in f64.
        let f = |v: f32| {
            let v = f64::from(v);
            if v == 0.0 || !v.is_finite() {
                return v;
            }
            let scale = 10f64.powi(6 - v.abs().log10().floor() as i32);
            (v * scale).round() / scale
        };
        let cell = f(profile.grid_cell_m);
        let default = CartoConfig::default();
        CartoConfig {
            cell_size_m: cell,
            chassis: Chassis {
                wheel_radius_m: f(g.wheel_radius_m),
                wheelbase_m: f(g.wheelbase_m),
                track_m: f(g.track_m),
                roller_tan: (f(profile.wheels.roller_angle_deg).to_radians().tan() * 1e9).round() / 1e9,
                encoder_counts_per_wheel_rev: f(profile.encoder.pulses_per_motor_rev)
                    * f(profile.motor.gear_ratio),
                max_wheel_rpm: f(profile.motor.max_wheel_rpm),
                body_length_m: f(g.body_length_m),
                body_width_m: f(g.body_width_m),
                ..default.chassis
            },
            sonar: Sonar {
                mount_m: f(profile.sonar.mount_x_m),
                cone_deg: f(profile.sonar.cone_deg),
                rays: profile.sonar.rays,
                max_m: f(profile.sonar.max_cm) / 100.0,
                incidence_deg: f(profile.sonar.incidence_limit_deg),
                sigma_m: f(profile.sonar.noise_sigma_cm) / 100.0,
                lag: Duration::from_micros(u64::from(profile.sonar.cycle_ms) * 500),
            },
            safety: Safety { obstacle_threshold_cm: (cell * 100.0) as f32, ..default.safety },
            boards: Boards {
                peer_lost_after: Duration::from_millis(u64::from(profile.sensor_board.peer_lost_timeout_ms)),
                motor_baud: profile.serial.motor_baud,
                sensor_baud: profile.serial.sensor_baud,
                motor_checksum: ChecksumPolicy::from(profile.motor_board.checksum),
                ..default.boards
            },
            ..default
        }
    }

    /// Encoder counts per metre of wheel travel.
    pub fn encoder_counts_per_metre(&self) -> f64 {
        self.chassis.encoder_counts_per_wheel_rev
            / (2.0 * core::f64::consts::PI * self.chassis.wheel_radius_m)
    }

    /// Wheel rim speed at 100 % drive, m/s.
    pub fn max_wheel_speed_mps(&self) -> f64 {
        self.chassis.max_wheel_rpm / 60.0 * 2.0 * core::f64::consts::PI * self.chassis.wheel_radius_m
    }

    /// How far a FORWARD at cruise speed drives in the sonar's mean lag, metres: how far off a
    /// reading taken while driving can be placed along the track (the frame carries a result
    /// measured up to twice the mean lag before it).
    pub fn drive_timing_m(&self) -> f64 {
        0.01 * self.motion.cruise_pct * self.max_wheel_speed_mps() * self.sonar.lag.as_secs_f64()
    }

    /// Radius of the circle the body sweeps turning on the spot (half its diagonal), metres.
    pub fn turn_radius_m(&self) -> f64 {
        0.5 * self.chassis.body_length_m.hypot(self.chassis.body_width_m)
    }

    /// Half track + tan γ × half wheelbase: the lever arm of a mecanum wheel for rotation, metres
    /// (0.19 m for the default robot).
    pub fn rotation_lever_m(&self) -> f64 {
        0.5 * self.chassis.track_m + self.chassis.roller_tan * 0.5 * self.chassis.wheelbase_m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_default_profile_matches_the_built_in_default() {
        let from = CartoConfig::from_profile(&RobotProfile::default());
        assert_eq!(from, CartoConfig::default());
    }
}
