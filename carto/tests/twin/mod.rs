//! The board-twin world shared by `tests/twin_boards.rs` and `examples/accuracy.rs`: Carto through
//! `CartoRuntime`, robot-model's `MotorBoard`/`SensorBoard` twins over baud-timed `MemLink`s, the
//! profile's motor model and mecanum kinematics (no slip), encoders and a noisy, drifting IMU with
//! a seeded RNG.

#![allow(dead_code)]
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use carto::{Carto, CartoConfig, CartoRuntime};
use protocol::link::{GuiMessage, MsgOrder};
use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::SeedableRng;
use robot_model::boards::{MotorBoard, SensorBoard, SensorInputs};
use robot_model::kinematics::MecanumKinematics;
use robot_model::motor::MotorModel;
use robot_model::profile::RobotProfile;
use robot_model::sensors::{Encoder, Imu};
use robot_model::time::{Duration, Instant};
use transport::{Connector, Link, MemLink, MemListener, MockClock, mem_listener};

pub struct Twin {
    pub clock: MockClock,
    pub rt: CartoRuntime<MemListener, MemLink, MemLink>,
    client: MemLink,
    motor_end: MemLink,
    sensor_end: MemLink,
    pub motor_board: MotorBoard,
    pub sensor_board: SensorBoard,
    motors: [MotorModel; 4],
    encoders: [Encoder; 4],
    wheel_angle: [f64; 4],
    imu: Imu,
    kin: MecanumKinematics,
    rng: ChaCha8Rng,
    pub x: f64,
    pub y: f64,
    pub theta: f64,
    pub now: Instant,
    decoder: protocol::link::Decoder,
    pub replies: Vec<GuiMessage>,
}

impl Twin {
    pub fn new(seed: u64) -> Self {
        // 0.30 m cells: the distances these tests assert are written for them
        let profile = RobotProfile { grid_cell_m: 0.30, ..RobotProfile::default() };
        let clock = MockClock::new();
        let (listener, mut connector) = mem_listener(None, clock.clone());
        let (m_carto, m_board) = MemLink::pair(Some(profile.serial.motor_baud), clock.clone());
        let (s_carto, s_board) = MemLink::pair(Some(profile.serial.sensor_baud), clock.clone());
        let client = connector.connect().unwrap();
        let carto = Carto::new(CartoConfig::from_profile(&profile));
        Twin {
            clock,
            rt: CartoRuntime::new(carto, listener, m_carto, s_carto),
            client,
            motor_end: m_board,
            sensor_end: s_board,
            motor_board: MotorBoard::new(&profile),
            sensor_board: SensorBoard::new(&profile),
            motors: core::array::from_fn(|_| MotorModel::from_profile(&profile)),
            encoders: core::array::from_fn(|_| Encoder::from_profile(&profile)),
            wheel_angle: [0.0; 4],
            imu: Imu::from_profile(&profile),
            kin: MecanumKinematics::from_profile(&profile),
            rng: ChaCha8Rng::seed_from_u64(seed),
            x: 0.0,
            y: 0.0,
            theta: 0.0,
            now: Instant::ZERO,
            decoder: protocol::link::Decoder::default(),
            replies: Vec::new(),
        }
    }

    pub fn tick(&mut self) {
        let dt = Duration::from_millis(1);
        self.now += dt;
        self.clock.set(Instant::from_micros(self.now.total_micros()));
        let mut buf = [0u8; 1024];
        // Boards receive what Carto sent.
        while let Ok(n @ 1..) = self.motor_end.read(&mut buf) {
            self.motor_board.receive(self.now, &buf[..n]);
        }
        while let Ok(n @ 1..) = self.sensor_end.read(&mut buf) {
            self.sensor_board.receive(self.now, &buf[..n]);
        }
        // Physics: motors, kinematics, sensors.
        let set = self.motor_board.wheel_setpoints_rpm();
        let mut rpm = [0.0f32; 4];
        for i in 0..4 {
            rpm[i] = self.motors[i].step(set[i], dt);
            self.wheel_angle[i] += f64::from(robot_model::kinematics::rpm_to_rad_s(rpm[i])) * 0.001;
            self.encoders[i].update(self.wheel_angle[i]);
        }
        self.motor_board.set_measured(rpm);
        let t = self.kin.forward_rpm(rpm);
        let (s, c) = self.theta.sin_cos();
        self.x += (f64::from(t.vx) * c - f64::from(t.vy) * s) * 0.001;
        self.y += (f64::from(t.vx) * s + f64::from(t.vy) * c) * 0.001;
        self.theta += f64::from(t.omega) * 0.001;
        let inputs = SensorInputs {
            distance_cm: None,
            heading_deg: self.imu.read(self.now, self.theta as f32, &mut self.rng),
            encoder_counts: core::array::from_fn(|i| self.encoders[i].count()),
            encoder_forward: core::array::from_fn(|i| self.encoders[i].forward()),
            bumper_pressed: false,
        };
        let m = self.motor_board.poll(self.now);
        let s = self.sensor_board.poll(self.now, &inputs);
        assert_eq!(self.motor_end.write(&m).unwrap(), m.len());
        assert_eq!(self.sensor_end.write(&s).unwrap(), s.len());
        self.rt.step(self.now);
        while let Ok(n @ 1..) = self.client.read(&mut buf) {
            self.replies.extend(self.decoder.feed(&buf[..n]).into_iter().map(|r| r.unwrap()));
        }
    }

    pub fn send(&mut self, msg: GuiMessage) {
        self.client.write(&msg.to_bytes(MsgOrder::BigEndian)).unwrap();
    }

    pub fn run_until_move_done(&mut self, n: usize, max_ms: u64) -> bool {
        for _ in 0..max_ms {
            if self.replies.iter().filter(|m| **m == GuiMessage::MoveDone).count() >= n {
                return true;
            }
            self.tick();
        }
        false
    }
}
