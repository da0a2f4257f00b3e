//! Carto against the physics twin in lockstep, driven by a scripted client that speaks only the
//! link protocol: every behaviour of protocols.md §1, checked against where the robot really is.
//!
//! The rig is the lockstep runner without Cute: the board twins and the robot's body
//! ([`twin::hardware::Twin`]) behind baud-timed in-memory UARTs, Carto's runtime, and an in-memory
//! "TCP" listener the test connects to.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use carto::{Carto, CartoConfig, CartoRuntime};
use protocol::link::{Command, Decoder, Direction, GuiMessage, MsgOrder};
use robot_model::pose::Pose2;
use robot_model::time::{Duration, Instant};
use transport::{Connector, Link, MemConnector, MemLink, MemListener, MockClock, mem_listener};
use twin::grid::GridFrame;
use twin::hardware::{Twin, WriteBudget};
use twin::setup::RunSetup;

const DT: Duration = Duration::from_millis(5);

struct Rig {
    clock: MockClock,
    now: Instant,
    twin: Twin,
    motor: MemLink,
    sensor: MemLink,
    carto: CartoRuntime<MemListener, MemLink, MemLink>,
    connector: MemConnector,
    frame: GridFrame,
}

struct Client {
    link: MemLink,
    decoder: Decoder,
    received: Vec<GuiMessage>,
}

impl Client {
    fn send(&mut self, m: GuiMessage) {
        self.send_raw(&m.to_bytes(MsgOrder::BigEndian));
    }

    fn send_raw(&mut self, bytes: &[u8]) {
        assert_eq!(self.link.write(bytes).unwrap(), bytes.len());
    }

    /// Reads what arrived; `false` once Carto closed the connection.
    fn poll(&mut self) -> bool {
        let mut bytes = Vec::new();
        let alive = self.link.read_available(&mut bytes).is_ok();
        for m in self.decoder.feed(&bytes) {
            self.received.push(m.expect("Carto sends well-formed frames"));
        }
        alive
    }
}

/// An empty 8 x 6 room of 0.30 m cells (plus `obstacles`), robot in cell (2, 2) facing East.
fn rig(obstacles: &str) -> Rig {
    let text = format!(
        "Scenario(name: \"rig\", cell: Some(0.30), room: [(0.0, 0.0), (2.5, 0.0), (2.5, 1.9), (0.0, 1.9)], \
         start: (row: 2, col: 2, heading: East), obstacles: [{obstacles}])"
    );
    let loaded = RunSetup::from_ron_str(&text, "rig.ron", std::path::Path::new(".")).unwrap();
    let profile = loaded.profile.clone();
    let clock = MockClock::new();
    let (motor_carto, motor) = MemLink::pair(Some(profile.serial.motor_baud), clock.clone());
    let (sensor_carto, sensor) = MemLink::pair(Some(profile.serial.sensor_baud), clock.clone());
    let (listener, connector) = mem_listener(None, clock.clone());
    let carto = CartoRuntime::new(
        Carto::new(CartoConfig::from_profile(&profile)),
        listener,
        motor_carto,
        sensor_carto,
    );
    let frame = loaded.frame();
    let mut rig = Rig {
        clock,
        now: Instant::ZERO,
        twin: Twin::new(&loaded, 1, DT),
        motor,
        sensor,
        carto,
        connector,
        frame,
    };
    rig.run(1.0); // boards power up, readings flow
    rig
}

impl Rig {
    fn step(&mut self) {
        self.now += DT;
        self.clock.set(Instant::from_micros(self.now.total_micros()));
        self.twin.board_io(self.now, &mut self.motor, &mut self.sensor, WriteBudget::UNLIMITED);
        self.carto.step(self.now);
        self.twin.physics_step(self.now);
    }

    fn run(&mut self, seconds: f64) {
        for _ in 0..(seconds / DT.as_secs_f64()).round() as u64 {
            self.step();
        }
    }

    /// Steps until `done` holds for the client (or panics after `seconds`).
    fn run_until(&mut self, client: &mut Client, seconds: f64, done: impl Fn(&[GuiMessage]) -> bool) {
        for _ in 0..(seconds / DT.as_secs_f64()).round() as u64 {
            self.step();
            client.poll();
            if done(&client.received) {
                return;
            }
        }
        panic!("not done after {seconds} s; received {:?}", client.received);
    }

    fn connect(&mut self) -> Client {
        let link = self.connector.connect().unwrap();
        let mut c = Client { link, decoder: Decoder::default(), received: Vec::new() };
        self.run(0.05);
        c.poll();
        c
    }

    /// A connected client whose pose Carto has acknowledged: (2, 2) facing East.
    fn ready_client(&mut self) -> Client {
        let mut c = self.connect();
        c.send(GuiMessage::SendRobotPosition { x: 2, y: 2, direction: Direction::East });
        self.run_until(&mut c, 2.0, |r| r.contains(&GuiMessage::RobotPositionReceived));
        c.received.clear();
        c
    }

    fn pose(&self) -> Pose2 {
        self.twin.body().pose()
    }

    fn centre(&self, row: usize, col: usize) -> (f32, f32) {
        self.frame.cell_center(row, col)
    }

    fn wheels_commanded_to_zero(&self) -> bool {
        self.twin.motor_board().wheel_setpoints_rpm().iter().all(|w| *w == 0.0)
    }
}

#[test]
fn forward_with_the_way_clear_moves_one_cell_in_the_physics_world() {
    let mut rig = rig("");
    let mut c = rig.ready_client();
    c.send(GuiMessage::SendMoveCartography { command: Command::Forward });
    rig.run_until(&mut c, 10.0, |r| r.contains(&GuiMessage::MoveDone));
    assert_eq!(c.received, vec![GuiMessage::SetRobotPosition { x: 2, y: 3 }, GuiMessage::MoveDone]);
    rig.run(0.5);
    let (x, y) = rig.centre(2, 3);
    let p = rig.pose();
    assert!((p.x - x).abs() <= 0.01 && (p.y - y).abs() <= 0.01, "robot at {p:?}, cell centre ({x}, {y})");
}

#[test]
fn forward_with_a_box_ahead_reports_the_obstacle_and_does_not_move() {
    // A box filling most of cell (2, 3), right ahead of the robot.
    let mut rig = rig("Box(center: (1.1, 1.1), size: (0.2, 0.2))");
    let before = rig.pose();
    let mut c = rig.ready_client();
    c.send(GuiMessage::SendMoveCartography { command: Command::Forward });
    rig.run_until(&mut c, 10.0, |r| r.contains(&GuiMessage::MoveDone));
    assert_eq!(c.received, vec![GuiMessage::SetObstaclePosition { x: 2, y: 3 }, GuiMessage::MoveDone]);
    let after = rig.pose();
    assert!(
        (after.x - before.x).abs() < 0.005 && (after.y - before.y).abs() < 0.005,
        "{before:?} -> {after:?}"
    );
    assert_eq!(rig.twin.body().world().collisions(), 0);
}

#[test]
fn right_turns_the_physical_heading_by_minus_90_degrees() {
    let mut rig = rig("");
    let before = rig.pose().theta;
    let mut c = rig.ready_client();
    c.send(GuiMessage::SendMoveCartography { command: Command::Right });
    rig.run_until(&mut c, 10.0, |r| r.contains(&GuiMessage::MoveDone));
    assert_eq!(c.received, vec![GuiMessage::MoveDone]);
    // after a mapping turn's MOVE_DONE the robot looks 20° past the new heading and back
    // (`CartoConfig.safety.look_past_turn_deg`): about 1.5 s
    rig.run(3.0);
    let turned = (rig.pose().theta - before).to_degrees();
    assert!((turned + 90.0).abs() <= 2.0, "turned {turned:.2} deg");
}

#[test]
fn a_batch_of_six_reports_each_forward_then_move_done() {
    let mut rig = rig("");
    let mut c = rig.ready_client();
    // F F RIGHT F LEFT F from (2, 2) East: (2, 3), (2, 4), turn South, (3, 4), turn East, (3, 5).
    for cmd in [
        Command::Forward,
        Command::Forward,
        Command::Right,
        Command::Forward,
        Command::Left,
        Command::Forward,
    ] {
        c.send(GuiMessage::SendMovesTrajectory { n_total: 6, command: cmd });
    }
    rig.run_until(&mut c, 40.0, |r| r.contains(&GuiMessage::MoveDone));
    assert_eq!(
        c.received,
        vec![
            GuiMessage::SetRobotPosition { x: 2, y: 3 },
            GuiMessage::SetRobotPosition { x: 2, y: 4 },
            GuiMessage::SetRobotPosition { x: 3, y: 4 },
            GuiMessage::SetRobotPosition { x: 3, y: 5 },
            GuiMessage::MoveDone,
        ]
    );
    rig.run(0.5);
    let (x, y) = rig.centre(3, 5);
    let p = rig.pose();
    assert!((p.x - x).abs() <= 0.01 && (p.y - y).abs() <= 0.01, "robot at {p:?}, cell centre ({x}, {y})");
}

#[test]
fn stop_in_the_middle_of_a_batch_zeroes_the_wheels_within_100_ms_and_drops_the_rest() {
    let mut rig = rig("");
    let mut c = rig.ready_client();
    for _ in 0..4 {
        c.send(GuiMessage::SendMovesTrajectory { n_total: 4, command: Command::Forward });
    }
    rig.run_until(&mut c, 10.0, |r| r.contains(&GuiMessage::SetRobotPosition { x: 2, y: 3 }));
    rig.run(0.5); // in the middle of the second FORWARD
    assert!(!rig.wheels_commanded_to_zero(), "the robot should be driving");
    c.send(GuiMessage::StopRobot);
    let mut stopped_after = None;
    for i in 1..=20 {
        rig.step();
        if rig.wheels_commanded_to_zero() {
            stopped_after = Some(i * 5);
            break;
        }
    }
    let ms = stopped_after.expect("the motor board never got a zero command");
    assert!(ms <= 100, "wheels stopped after {ms} ms");
    // Nothing else happens: no more positions, no MOVE_DONE, the robot stays put.
    rig.run(1.0);
    let at = rig.pose();
    rig.run(5.0);
    c.poll();
    assert_eq!(c.received, vec![GuiMessage::SetRobotPosition { x: 2, y: 3 }]);
    let p = rig.pose();
    assert!((p.x - at.x).abs() < 0.002 && (p.y - at.y).abs() < 0.002);
    assert!(rig.wheels_commanded_to_zero());
}

/// A STOP mid-FORWARD, then at once a RIGHT and a FORWARD: the robot still coasts when the turn
/// is asked for. Carto lets it come to rest before turning (a turn's odometry ignores translation,
/// so the coasting would otherwise be lost), and the FORWARD then lands on the next cell's centre,
/// its track corrected for where the STOP really left the robot.
#[test]
fn a_turn_right_after_a_stop_mid_move_keeps_the_coasting_in_the_odometry() {
    let mut rig = rig("");
    let mut c = rig.ready_client();
    for _ in 0..2 {
        c.send(GuiMessage::SendMovesTrajectory { n_total: 2, command: Command::Forward });
    }
    rig.run_until(&mut c, 10.0, |r| r.contains(&GuiMessage::SetRobotPosition { x: 2, y: 3 }));
    rig.run(0.5); // in the middle of the second FORWARD, at cruise speed
    assert!(!rig.wheels_commanded_to_zero(), "the robot should be driving");
    c.send(GuiMessage::StopRobot);
    c.send(GuiMessage::SendMoveCartography { command: Command::Right });
    rig.run_until(&mut c, 10.0, |r| r.contains(&GuiMessage::MoveDone));
    c.received.clear();
    c.send(GuiMessage::SendMoveCartography { command: Command::Forward });
    rig.run_until(&mut c, 10.0, |r| r.contains(&GuiMessage::MoveDone));
    assert_eq!(c.received, vec![GuiMessage::SetRobotPosition { x: 3, y: 3 }, GuiMessage::MoveDone]);
    let (cx, cy) = rig.centre(3, 3);
    let p = rig.pose();
    assert!(
        (p.x - cx).abs() < 0.02 && (p.y - cy).abs() < 0.02,
        "robot at ({:.3}, {:.3}), centre of (3, 3) at ({cx:.3}, {cy:.3})",
        p.x,
        p.y
    );
}

#[test]
fn issue_14_a_second_client_waits_and_a_disconnect_stops_the_motors() {
    let mut rig = rig("");
    let mut first = rig.ready_client();
    let mut second = rig.connect();
    second.send(GuiMessage::SendRobotPosition { x: 2, y: 2, direction: Direction::East });
    rig.run(0.1);
    assert!(second.poll(), "the second client waits: it must not be closed");
    assert!(second.received.is_empty(), "the second client is not served yet: {:?}", second.received);
    assert!(first.poll(), "the first client must stay connected");
    assert_eq!(rig.carto.stats().waited, 1);

    first.send(GuiMessage::SendMoveCartography { command: Command::Forward });
    rig.run(0.8);
    assert!(!rig.wheels_commanded_to_zero(), "moving");
    drop(first);
    rig.run(0.1);
    assert!(rig.wheels_commanded_to_zero(), "a disconnect stops the motors");
    // The client that waited is served now, its early request first.
    rig.run_until(&mut second, 2.0, |r| r.contains(&GuiMessage::RobotPositionReceived));
    second.send(GuiMessage::SendMoveCartography { command: Command::Left });
    rig.run_until(&mut second, 10.0, |r| r.contains(&GuiMessage::MoveDone));
}

#[test]
fn malformed_input_is_handled_as_specified_and_the_server_keeps_serving() {
    let mut rig = rig("");

    // Size 0: a fatal framing error, this connection is closed.
    let mut c = rig.connect();
    c.send_raw(&[0x00, 0x00, 0x01, 0x00]);
    rig.run(0.1);
    assert!(!c.poll(), "Size 0 closes the connection");

    // Size 9000 (above the 1024 maximum): closed as well.
    let mut c = rig.connect();
    c.send_raw(&[0x23, 0x28, 0x01, 0x00, 0x06, 0x00]);
    rig.run(0.1);
    assert!(!c.poll(), "Size 9000 closes the connection");

    // An unknown Msg is ignored with no reply; a little-endian Msg is accepted; a frame written one
    // byte at a time is reassembled.
    let mut c = rig.connect();
    c.send_raw(&[0x00, 0x03, 0x0A, 0x00, 0x07]);
    rig.run(0.1);
    assert!(c.poll());
    assert!(c.received.is_empty(), "unknown Msg: no reply, got {:?}", c.received);
    c.send_raw(&[0x00, 0x05, 0x00, 0x07, 0x02, 0x02, 0x03]); // SEND_ROBOT_POSITION, Msg little-endian
    rig.run_until(&mut c, 2.0, |r| r.contains(&GuiMessage::RobotPositionReceived));
    c.received.clear();
    let forward = GuiMessage::SendMoveCartography { command: Command::Forward }.to_bytes(MsgOrder::BigEndian);
    for b in forward {
        c.send_raw(&[b]);
        rig.step();
    }
    rig.run_until(&mut c, 10.0, |r| r.contains(&GuiMessage::MoveDone));
    assert_eq!(c.received, vec![GuiMessage::SetRobotPosition { x: 2, y: 3 }, GuiMessage::MoveDone]);
    let stats = rig.carto.carto().stats();
    assert_eq!((stats.fatal_errors, stats.unknown_messages), (2, 1), "{stats:?}");
}
