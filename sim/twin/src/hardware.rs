//! [`Twin`]: everything past Carto's serial ports — the motor board, the sensor board, and the
//! robot's body in the room — as one unit that speaks bytes on two [`Link`]s.
//!
//! Both runtimes use it: the lockstep runner gives it in-memory links on a virtual clock
//! ([`crate::runner`]); `explobot sim --serve` gives it pseudo-terminals or TCP sockets and the
//! wall clock (`explobot::serve`).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use robot_model::boards::{MotorBoard, SensorBoard, SensorInputs};
use robot_model::time::{Duration, Instant};
use transport::Link;

use crate::body::RobotBody;
use crate::grid::GridFrame;
use crate::setup::RunSetup;

/// A trail point is recorded every this many physics steps.
const TRAIL_EVERY: u64 = 20;

/// Bytes a board wants to send that its UART has not taken yet.
#[derive(Debug, Default)]
pub struct Outbox {
    pending: Vec<u8>,
}

impl Outbox {
    /// Queues `bytes` and writes as much as the link takes, at most `limit` bytes (a UART's byte
    /// budget for this instant; `usize::MAX` when the link models byte time itself).
    pub fn send<L: Link>(&mut self, bytes: Vec<u8>, link: &mut L, limit: usize) -> usize {
        self.pending.extend(bytes);
        if self.pending.is_empty() {
            return 0;
        }
        let n = self.pending.len().min(limit);
        match link.write(&self.pending[..n]) {
            Ok(n) => {
                self.pending.drain(..n);
                n
            }
            Err(_) => {
                // A board talking into an unplugged cable: the bytes are lost, as on the robot.
                self.pending.clear();
                0
            }
        }
    }
}

/// Per-instant limits on what each board may write (bytes), for links without byte timing.
#[derive(Debug, Clone, Copy)]
pub struct WriteBudget {
    /// Motor board UART.
    pub motor: usize,
    /// Sensor board UART.
    pub sensor: usize,
}

impl WriteBudget {
    /// No limit: the link models byte time itself.
    pub const UNLIMITED: WriteBudget = WriteBudget { motor: usize::MAX, sensor: usize::MAX };
}

/// What one round of board I/O did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BoardIo {
    /// Whether the motor link still works.
    pub motor_up: bool,
    /// Whether the sensor link still works.
    pub sensor_up: bool,
    /// Bytes the motor board wrote.
    pub motor_sent: usize,
    /// Bytes the sensor board wrote.
    pub sensor_sent: usize,
}

/// The motor board, the sensor board and the robot's body.
pub struct Twin {
    body: RobotBody,
    motor_board: MotorBoard,
    sensor_board: SensorBoard,
    rng: ChaCha8Rng,
    motor_out: Outbox,
    sensor_out: Outbox,
    frame: GridFrame,
    trail: Vec<(f32, f32)>,
    steps: u64,
}

impl Twin {
    /// The scenario's robot at its start cell, boards powered on at time zero, stepping by `dt`
    /// (the runtimes pass [`RunSetup::dt`]).
    pub fn new(loaded: &RunSetup, seed: u64, dt: Duration) -> Twin {
        let scenario = &loaded.scenario;
        let profile = &loaded.profile;
        let frame = loaded.frame();
        let start = loaded.start_pose();
        Twin {
            body: RobotBody::new(scenario, profile, start, dt),
            motor_board: MotorBoard::new(profile),
            sensor_board: SensorBoard::new(profile),
            rng: ChaCha8Rng::seed_from_u64(seed),
            motor_out: Outbox::default(),
            sensor_out: Outbox::default(),
            frame,
            trail: vec![(start.x, start.y)],
            steps: 0,
        }
    }

    /// The boards read their UARTs and answer.
    pub fn board_io<M: Link, S: Link>(
        &mut self,
        now: Instant,
        motor: &mut M,
        sensor: &mut S,
        budget: WriteBudget,
    ) -> BoardIo {
        let mut rx = Vec::new();
        let motor_up = motor.read_available(&mut rx).is_ok();
        if !rx.is_empty() {
            self.motor_board.receive(now, &rx);
        }
        let telemetry = self.motor_board.poll(now);
        let motor_sent = self.motor_out.send(telemetry, motor, budget.motor);

        rx.clear();
        let sensor_up = sensor.read_available(&mut rx).is_ok();
        if !rx.is_empty() {
            self.sensor_board.receive(now, &rx);
        }
        let inputs = SensorInputs {
            distance_cm: self.body.sonar_cm(),
            heading_deg: self.body.imu_heading(now, &mut self.rng),
            encoder_counts: self.body.encoder_counts(),
            encoder_forward: self.body.encoder_forward(),
            bumper_pressed: self.body.bumper(),
        };
        let frames = self.sensor_board.poll(now, &inputs);
        let sensor_sent = self.sensor_out.send(frames, sensor, budget.sensor);
        BoardIo { motor_up, sensor_up, motor_sent, sensor_sent }
    }

    /// One physics step: the motor board's setpoints drive the wheels; the sonar measures when due.
    pub fn physics_step(&mut self, now: Instant) {
        self.body.step(self.motor_board.wheel_setpoints_rpm());
        self.motor_board.set_measured(self.body.wheel_rpm());
        self.body.sample_sonar(now, &mut self.rng);
        self.steps += 1;
        if self.steps.is_multiple_of(TRAIL_EVERY) {
            let p = self.body.pose();
            self.trail.push((p.x, p.y));
        }
    }

    /// The robot's body.
    pub fn body(&self) -> &RobotBody {
        &self.body
    }

    /// The robot's body, to collect what its sonar heard ([`RobotBody::collect_new_heard`]).
    pub fn body_mut(&mut self) -> &mut RobotBody {
        &mut self.body
    }

    /// The motor board twin.
    pub fn motor_board(&self) -> &MotorBoard {
        &self.motor_board
    }

    /// The sensor board twin.
    pub fn sensor_board(&self) -> &SensorBoard {
        &self.sensor_board
    }

    /// The robot's trail, world metres.
    pub fn trail(&self) -> &[(f32, f32)] {
        &self.trail
    }

    /// The grid cell the robot is in now.
    pub fn cell(&self) -> Option<(usize, usize)> {
        let p = self.body.pose();
        self.frame.cell_at(p.x, p.y)
    }
}
