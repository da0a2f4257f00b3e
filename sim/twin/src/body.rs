//! [`RobotBody`]: the robot's physical side — four motors, the wheels on the floor, the body in
//! the room, and the analog sensors read off it (encoders, IMU heading, sonar, bumper).
//!
//! Each step: every motor's speed follows its setpoint through the motor model (first-order lag,
//! dead band, saturation); the wheels turn by `ω·dt` (encoders count that, slip or not); the
//! floor's reaction pushes the body ([`crate::drive`]); rapier advances the world. The sonar
//! measures once per HC-SR04 cycle by casting its rays through the world.

use std::collections::BTreeMap;

use rand_chacha::ChaCha8Rng;
use robot_model::kinematics::rpm_to_rad_s;
use robot_model::motor::MotorModel;
use robot_model::pose::Pose2;
use robot_model::profile::RobotProfile;
use robot_model::sensors::{Encoder, HcSr04, Imu, RayHit as SonarHit};
use robot_model::time::{Duration, Instant};

use crate::drive::DriveTrain;
use crate::scenario::Scenario;
use crate::world::SimWorld;

/// The grid on which the points the sonar heard are kept, metres.
const HEARD_CELL_M: f32 = 0.01;

/// Echoes the sonar reported from one place ([`RobotBody::first_heard_near`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeardSpot {
    /// The first one.
    pub first: Instant,
    /// The shortest range of any of them, metres.
    pub nearest_m: f32,
}

/// One sonar ray as cast in the last measurement, for drawing: world start, world end, hit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CastRay {
    /// Ray origin, world metres.
    pub from: (f32, f32),
    /// Where the ray ended (hit point or maximum range), world metres.
    pub to: (f32, f32),
    /// Whether the ray hit a wall or an obstacle within range (`to` is then the hit point).
    pub hit: bool,
    /// Whether this ray produced an echo the sensor could hear (hit within the incidence limit).
    pub echo: bool,
}

/// The robot's body, motors and analog sensors in the physics world.
pub struct RobotBody {
    world: SimWorld,
    drive: DriveTrain,
    motors: [MotorModel; 4],
    wheel_angle: [f64; 4],
    encoders: [Encoder; 4],
    sonar: HcSr04,
    imu: Imu,
    ray_angles: Vec<f32>,
    last_rays: Vec<CastRay>,
    dt: Duration,
    incidence_limit: f32,
    /// Where on each fixed shape ([`crate::world::RayHit::part`]) the sonar's reported echoes
    /// came from, on a [`HEARD_CELL_M`] grid: when each grid cell was first heard, and the
    /// shortest range it was heard from.
    first_heard: BTreeMap<(usize, i32, i32), HeardSpot>,
    /// The points of `first_heard` not yet taken ([`RobotBody::take_new_heard`]); `None` unless
    /// collected ([`RobotBody::collect_new_heard`]).
    new_heard: Option<Vec<(f32, f32)>>,
}

impl RobotBody {
    /// The robot of `profile` at world pose `start` in the scenario's room.
    pub fn new(scenario: &Scenario, profile: &RobotProfile, start: Pose2, dt: Duration) -> RobotBody {
        let world = SimWorld::new(scenario, profile, start, dt.as_secs_f32());
        let sonar = HcSr04::from_profile(profile);
        let mut imu = Imu::from_profile(profile);
        // The IMU reads 0° at power-on, whatever way the robot faces.
        imu.zero(Instant::ZERO, start.theta);
        RobotBody {
            drive: DriveTrain::new(profile, dt.as_secs_f32()),
            motors: std::array::from_fn(|_| MotorModel::from_profile(profile)),
            wheel_angle: [0.0; 4],
            encoders: std::array::from_fn(|_| Encoder::from_profile(profile)),
            ray_angles: sonar.ray_angles(),
            incidence_limit: profile.sonar.incidence_limit_deg.to_radians(),
            sonar,
            imu,
            world,
            last_rays: Vec::new(),
            dt,
            first_heard: BTreeMap::new(),
            new_heard: None,
        }
    }

    /// One physics step with the motors driven towards `setpoints_rpm` (FL, FR, RL, RR).
    pub fn step(&mut self, setpoints_rpm: [f32; 4]) {
        let mut omega = [0.0f32; 4];
        for i in 0..4 {
            let rpm = self.motors[i].step(setpoints_rpm[i], self.dt);
            omega[i] = rpm_to_rad_s(rpm);
            self.wheel_angle[i] += f64::from(omega[i]) * self.dt.as_secs_f64();
            self.encoders[i].update(self.wheel_angle[i]);
        }
        self.world.reset_robot_forces();
        self.drive.apply(&mut self.world, omega);
        self.world.step();
    }

    /// Takes a sonar measurement if one is due at `now`; returns whether it did.
    pub fn sample_sonar(&mut self, now: Instant, rng: &mut ChaCha8Rng) -> bool {
        if !self.sonar.due(now) {
            return false;
        }
        self.force_sonar(now, rng);
        true
    }

    /// Takes a sonar measurement now, due or not (benchmarks).
    pub fn force_sonar(&mut self, now: Instant, rng: &mut ChaCha8Rng) {
        let pose = self.world.robot_pose();
        let mount = self.sonar.mount();
        let (s, c) = pose.theta.sin_cos();
        let origin = (pose.x + c * mount.x - s * mount.y, pose.y + s * mount.x + c * mount.y);
        let max = self.sonar.max_range_m();
        let mut hits = Vec::with_capacity(self.ray_angles.len());
        // which fixed shape each ray hit
        let mut parts = Vec::with_capacity(self.ray_angles.len());
        self.last_rays.clear();
        for &a in &self.ray_angles {
            let dir_angle = pose.theta + mount.theta + a;
            let dir = (dir_angle.cos(), dir_angle.sin());
            let hit = self.world.cast_range(origin, dir, max);
            parts.push(hit.map(|h| h.part));
            let reach = hit.map_or(max, |h| h.distance);
            self.last_rays.push(CastRay {
                from: origin,
                to: (origin.0 + dir.0 * reach, origin.1 + dir.1 * reach),
                hit: hit.is_some(),
                echo: hit.is_some_and(|h| h.incidence <= self.incidence_limit),
            });
            hits.push(hit.map(|h| SonarHit { distance_m: h.distance, incidence_rad: h.incidence }));
        }
        // the reported echo comes from the sensor's nearest audible hit: its shape, at its point
        if self.sonar.measure(now, &hits, rng).is_some()
            && let Some(i) = self.sonar.nearest_audible(&hits)
            && let (Some(Some(hit)), Some(Some(part)), Some(ray)) =
                (hits.get(i), parts.get(i), self.last_rays.get(i))
        {
            let (range, (x, y)) = (hit.distance_m, ray.to);
            let key = (*part, (x / HEARD_CELL_M).round() as i32, (y / HEARD_CELL_M).round() as i32);
            if let Some(new) = self.new_heard.as_mut()
                && !self.first_heard.contains_key(&key)
            {
                new.push((x, y));
            }
            let heard = self.first_heard.entry(key).or_insert(HeardSpot { first: now, nearest_m: range });
            heard.nearest_m = heard.nearest_m.min(range);
        }
    }

    /// From now on, keeps every point the sonar reports an echo from for the first time (one per
    /// shape and `HEARD_CELL_M` cell), for [`RobotBody::take_new_heard`] (`--known-echoes`).
    pub fn collect_new_heard(&mut self) {
        self.new_heard.get_or_insert_with(Vec::new);
    }

    /// The points collected since the last call, world coordinates (empty unless
    /// [`RobotBody::collect_new_heard`] was called).
    pub fn take_new_heard(&mut self) -> Vec<(f32, f32)> {
        self.new_heard.as_mut().map(std::mem::take).unwrap_or_default()
    }

    /// The echoes the sonar reported from the fixed shape `part` (the room's edges first, then
    /// the obstacles in the scenario's order) within `radius_m` of the world point `at`: the
    /// first one's time and the shortest range; `None` if it never reported one.
    pub fn first_heard_near(&self, part: usize, at: (f32, f32), radius_m: f32) -> Option<HeardSpot> {
        // the grid columns within reach, then the distance itself
        let reach = (radius_m / HEARD_CELL_M).ceil() as i32 + 1;
        let column = (at.0 / HEARD_CELL_M).round() as i32;
        self.first_heard
            .range((part, column - reach, i32::MIN)..=(part, column + reach, i32::MAX))
            .filter(|&(&(_, ix, iy), _)| {
                let (x, y) = (ix as f32 * HEARD_CELL_M, iy as f32 * HEARD_CELL_M);
                (x - at.0).hypot(y - at.1) <= radius_m
            })
            .map(|(_, &h)| h)
            .reduce(|a, b| HeardSpot { first: a.first.min(b.first), nearest_m: a.nearest_m.min(b.nearest_m) })
    }

    /// The latest sonar result, cm (`None` = no echo).
    pub fn sonar_cm(&self) -> Option<f32> {
        self.sonar.latest()
    }

    /// Sonar measurements taken so far.
    pub fn sonar_measurements(&self) -> u64 {
        self.sonar.measurements()
    }

    /// The rays of the latest sonar measurement.
    pub fn last_rays(&self) -> &[CastRay] {
        &self.last_rays
    }

    /// A noisy IMU heading reading, degrees clockwise in `[0, 360)`.
    pub fn imu_heading(&self, now: Instant, rng: &mut ChaCha8Rng) -> f32 {
        self.imu.read(now, self.world.robot_pose().theta, rng)
    }

    /// Makes the IMU read 0° from now on (sensor board command 3).
    pub fn zero_imu(&mut self, now: Instant) {
        let theta = self.world.robot_pose().theta;
        self.imu.zero(now, theta);
    }

    /// Encoder counts, FL, FR, RL, RR.
    pub fn encoder_counts(&self) -> [i32; 4] {
        std::array::from_fn(|i| self.encoders[i].count())
    }

    /// Whether each wheel last turned forward.
    pub fn encoder_forward(&self) -> [bool; 4] {
        std::array::from_fn(|i| self.encoders[i].forward())
    }

    /// Resets every encoder count to zero (sensor board command 2).
    pub fn reset_encoders(&mut self) {
        for e in &mut self.encoders {
            e.reset();
        }
    }

    /// Actual wheel speeds, rpm (for the motor board's telemetry).
    pub fn wheel_rpm(&self) -> [f32; 4] {
        std::array::from_fn(|i| self.motors[i].rpm())
    }

    /// Whether the front bumper is pressed.
    pub fn bumper(&self) -> bool {
        self.world.front_contact()
    }

    /// The physics world.
    pub fn world(&self) -> &SimWorld {
        &self.world
    }

    /// The robot's true pose.
    pub fn pose(&self) -> Pose2 {
        self.world.robot_pose()
    }
}
