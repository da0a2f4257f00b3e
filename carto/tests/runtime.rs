//! CartoRuntime over transport's in-memory links: one client at a time, idle limit, closing, board loss, and a full
//! FORWARD through baud-timed serial links.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod fake;

use carto::{Carto, CartoRuntime};
use fake::FakeRobot;
use protocol::link::{Command, Direction, GuiMessage, MsgOrder};
use robot_model::time::{Duration, Instant};
use transport::{Connector, Link, MemLink, MemListener, MockClock, mem_listener};

struct World {
    clock: MockClock,
    rt: CartoRuntime<MemListener, MemLink, MemLink>,
    connector: transport::MemConnector,
    motor_board: MemLink,
    sensor_board: MemLink,
    robot: FakeRobot,
    now: Instant,
}

impl World {
    fn new(baud: bool) -> Self {
        let clock = MockClock::new();
        let (listener, connector) = mem_listener(None, clock.clone());
        let (m_carto, m_board) = MemLink::pair(baud.then_some(115_200), clock.clone());
        let (s_carto, s_board) = MemLink::pair(baud.then_some(9600), clock.clone());
        let mut cfg = fake::test_config();
        if !baud {
            cfg.boards.motor_baud = 0;
            cfg.boards.sensor_baud = 0;
        }
        World {
            clock,
            rt: CartoRuntime::new(Carto::new(cfg.clone()), listener, m_carto, s_carto),
            connector,
            motor_board: m_board,
            sensor_board: s_board,
            robot: FakeRobot::new(cfg),
            now: Instant::ZERO,
        }
    }

    fn tick(&mut self) -> carto::StepReport {
        self.now += Duration::from_millis(1);
        self.clock.set(Instant::from_micros(self.now.total_micros()));
        self.robot.step(self.now, 0.001);
        let (m, s) = self.robot.emit(self.now);
        // The boards' sides of the links: ignore a closed link (some tests drop Carto's end).
        let _ = self.motor_board.write(&m);
        let _ = self.sensor_board.write(&s);
        let report = self.rt.step(self.now);
        let mut buf = [0u8; 4096];
        while let Ok(n @ 1..) = self.motor_board.read(&mut buf) {
            self.robot.motor_rx(self.now, &buf[..n]);
        }
        while let Ok(n @ 1..) = self.sensor_board.read(&mut buf) {
            self.robot.sensor_rx(self.now, &buf[..n]);
        }
        report
    }

    fn run_ms(&mut self, ms: u64) {
        for _ in 0..ms {
            self.tick();
        }
    }
}

fn read_replies(link: &mut MemLink, dec: &mut protocol::link::Decoder) -> Vec<GuiMessage> {
    let mut buf = [0u8; 1024];
    let mut out = Vec::new();
    while let Ok(n @ 1..) = link.read(&mut buf) {
        out.extend(dec.feed(&buf[..n]).into_iter().map(|r| r.unwrap()));
    }
    out
}

fn pose_bytes() -> Vec<u8> {
    GuiMessage::SendRobotPosition { x: 1, y: 1, direction: Direction::South }.to_bytes(MsgOrder::BigEndian)
}

#[test]
fn issue_14_second_client_waits_in_the_backlog_and_is_served_when_the_first_leaves() {
    let mut w = World::new(false);
    let mut first = w.connector.connect().unwrap();
    let report = w.tick();
    assert_eq!(report.accepted.as_deref(), Some("mem:1"));
    let mut second = w.connector.connect().unwrap();
    let report = w.tick();
    assert!(report.waiting && report.accepted.is_none());
    // The second client is neither accepted nor closed: it can already send its request.
    second.write(&pose_bytes()).unwrap();
    let mut buf = [0u8; 8];
    assert_eq!(second.read(&mut buf).unwrap(), 0);
    // The first session is untouched.
    first.write(&pose_bytes()).unwrap();
    w.run_ms(2);
    let mut dec = protocol::link::Decoder::default();
    assert_eq!(read_replies(&mut first, &mut dec), vec![GuiMessage::RobotPositionReceived]);
    assert_eq!(w.rt.stats().waited, 1);
    // The first leaves: its close is read, then the waiting client is served.
    drop(first);
    let mut accepted = None;
    for _ in 0..5 {
        accepted = accepted.or(w.tick().accepted);
    }
    assert_eq!(accepted.as_deref(), Some("mem:2"));
    let mut dec = protocol::link::Decoder::default();
    assert_eq!(read_replies(&mut second, &mut dec), vec![GuiMessage::RobotPositionReceived]);
}

#[test]
fn issue_14_idle_client_is_closed_and_the_next_served() {
    let clock = MockClock::new();
    let (listener, mut connector) = mem_listener(None, clock.clone());
    let (m_carto, _m_board) = MemLink::pair(None, clock.clone());
    let (s_carto, _s_board) = MemLink::pair(None, clock.clone());
    let cfg = fake::test_config_with(|c| c.client.idle_limit = Some(Duration::from_secs(2)));
    let mut rt = CartoRuntime::new(Carto::new(cfg), listener, m_carto, s_carto);
    let mut silent = connector.connect().unwrap();
    let mut now = Instant::ZERO;
    let mut closed_at = None;
    let mut next = None;
    while now < Instant::from_millis(5000) {
        now += Duration::from_millis(10);
        let r = rt.step(now);
        if r.client_closed {
            closed_at = Some(now);
        }
        if closed_at.is_some() && next.is_none() {
            next = Some(connector.connect().unwrap());
        }
        if r.accepted.as_deref() == Some("mem:2") {
            break;
        }
    }
    assert_eq!(closed_at, Some(Instant::from_millis(2010)));
    assert!(rt.has_client(), "the next client was not served");
    let mut buf = [0u8; 8];
    assert!(silent.read(&mut buf).unwrap_err().is_disconnected());
}

#[test]
fn fatal_framing_error_closes_only_that_connection() {
    let mut w = World::new(false);
    let mut c = w.connector.connect().unwrap();
    w.tick();
    c.write(&[0x00, 0x01, 0x03]).unwrap(); // Size 1
    let report = w.tick();
    assert!(report.client_closed);
    let mut buf = [0u8; 8];
    assert!(c.read(&mut buf).unwrap_err().is_disconnected());
    let mut c2 = w.connector.connect().unwrap();
    w.tick();
    c2.write(&pose_bytes()).unwrap();
    w.run_ms(2);
    let mut dec = protocol::link::Decoder::default();
    assert_eq!(read_replies(&mut c2, &mut dec), vec![GuiMessage::RobotPositionReceived]);
    assert_eq!(w.rt.carto().stats().fatal_errors, 1);
}

#[test]
fn forward_through_baud_timed_links() {
    let mut w = World::new(true);
    let mut c = w.connector.connect().unwrap();
    w.run_ms(500);
    c.write(&pose_bytes()).unwrap();
    c.write(&GuiMessage::SendMoveCartography { command: Command::Forward }.to_bytes(MsgOrder::BigEndian))
        .unwrap();
    let mut dec = protocol::link::Decoder::default();
    let mut replies = Vec::new();
    for _ in 0..8000 {
        w.tick();
        replies.extend(read_replies(&mut c, &mut dec));
        if replies.contains(&GuiMessage::MoveDone) {
            break;
        }
    }
    assert_eq!(
        replies,
        vec![
            GuiMessage::RobotPositionReceived,
            GuiMessage::SetRobotPosition { x: 2, y: 1 },
            GuiMessage::MoveDone
        ]
    );
    let d = (w.robot.x.powi(2) + w.robot.y.powi(2)).sqrt();
    assert!((d - 0.30).abs() <= 0.01, "travelled {d:.4}");
    assert!(w.robot.carto_keep_states.len() >= 2);
}

#[test]
fn client_leaving_mid_move_stops_the_motors() {
    let mut w = World::new(false);
    let mut c = w.connector.connect().unwrap();
    w.run_ms(500);
    c.write(&pose_bytes()).unwrap();
    c.write(&GuiMessage::SendMoveCartography { command: Command::Forward }.to_bytes(MsgOrder::BigEndian))
        .unwrap();
    w.run_ms(400);
    assert!(w.robot.moving());
    drop(c);
    let t = w.now;
    w.run_ms(1500);
    let after = w.robot.drives_since(t);
    assert!(!after.is_empty() && after.iter().all(|(_, d)| d.is_stop()));
    assert!(!w.robot.moving());
}

#[test]
fn motor_board_link_loss_is_reported_and_moves_are_refused() {
    let mut w = World::new(false);
    let mut c = w.connector.connect().unwrap();
    w.run_ms(500);
    w.motor_board.close();
    let mut lost = false;
    for _ in 0..5 {
        lost |= w.tick().motor_lost;
    }
    assert!(lost);
    assert!(!w.rt.motor_up());
    c.write(&pose_bytes()).unwrap();
    c.write(&GuiMessage::SendMoveCartography { command: Command::Right }.to_bytes(MsgOrder::BigEndian))
        .unwrap();
    w.run_ms(5);
    let mut dec = protocol::link::Decoder::default();
    // The position is acknowledged; the move did not happen, so no MOVE_DONE says it ended.
    assert_eq!(read_replies(&mut c, &mut dec), vec![GuiMessage::RobotPositionReceived]);
    assert_eq!(w.rt.carto().stats().moves_refused, 1);
}

#[test]
fn stop_motors_sends_a_zero_drive() {
    let mut w = World::new(false);
    w.run_ms(50);
    let t = w.now;
    assert!(w.rt.stop_motors(w.now));
    let mut buf = [0u8; 64];
    let n = w.motor_board.read(&mut buf).unwrap();
    assert_eq!(
        &buf[..n],
        &[0xAA, 0x06, 0x10, 0, 0, 0, 0, 0, 0, 0x16],
        "stop frame (protocols-research §2.8)"
    );
    let _ = t;
}

/// A runtime with a 2 s idle limit and silent boards, and a connected client.
fn idle_limited() -> (CartoRuntime<MemListener, MemLink, MemLink>, MemLink, [MemLink; 2]) {
    let clock = MockClock::new();
    let (listener, mut connector) = mem_listener(None, clock.clone());
    let (m_carto, m_board) = MemLink::pair(None, clock.clone());
    let (s_carto, s_board) = MemLink::pair(None, clock);
    let cfg = fake::test_config_with(|c| c.client.idle_limit = Some(Duration::from_secs(2)));
    let rt = CartoRuntime::new(Carto::new(cfg), listener, m_carto, s_carto);
    let client = connector.connect().unwrap();
    (rt, client, [m_board, s_board])
}

#[test]
fn issue_45_a_client_trickling_a_frame_is_closed_by_the_idle_limit() {
    let (mut rt, mut trickler, _boards) = idle_limited();
    // A 1,000-byte frame (Size 1000 ≤ max_frame 1024), one byte every 300 ms: bytes keep coming,
    // but no frame completes, so the session ends 2 s after it opened.
    let mut frame = vec![0x03, 0xE8, 0x07, 0x00];
    frame.resize(1002, 0x55);
    let mut now = Instant::ZERO;
    let mut closed_at = None;
    let mut sent = 0;
    while now < Instant::from_millis(10_000) && closed_at.is_none() {
        now += Duration::from_millis(10);
        if now.total_millis().is_multiple_of(300) && sent < frame.len() {
            trickler.write(&frame[sent..=sent]).unwrap();
            sent += 1;
        }
        if rt.step(now).client_closed {
            closed_at = Some(now);
        }
    }
    assert_eq!(closed_at, Some(Instant::from_millis(2010)), "{sent} bytes trickled");
    let mut buf = [0u8; 8];
    assert!(trickler.read(&mut buf).unwrap_err().is_disconnected());
}

#[test]
fn issue_45_complete_frames_keep_the_session_and_a_partial_one_does_not_extend_it() {
    let (mut rt, mut client, _boards) = idle_limited();
    let pose = pose_bytes();
    let mut now = Instant::ZERO;
    let mut closed_at = None;
    while now < Instant::from_millis(20_000) && closed_at.is_none() {
        now += Duration::from_millis(10);
        let ms = now.total_millis();
        // A complete position every 1.5 s for 6 s: the session stays open.
        if ms <= 6000 && ms.is_multiple_of(1500) {
            client.write(&pose).unwrap();
        }
        // Then the first byte of a position at 7 s and one more at 7.5 s: no frame completes.
        if ms == 7000 || ms == 7500 {
            client.write(&pose[(ms as usize - 7000) / 500..=(ms as usize - 7000) / 500]).unwrap();
        }
        if rt.step(now).client_closed {
            closed_at = Some(now);
        }
    }
    // The last complete frame came at 6 s: closed at 8 s, the partial frame notwithstanding.
    assert_eq!(closed_at, Some(Instant::from_millis(8000)));
}

#[test]
fn issue_45_next_deadline_is_now_while_moving_and_later_when_idle() {
    let mut w = World::new(false);
    let mut c = w.connector.connect().unwrap();
    w.run_ms(500);
    let idle = w.rt.next_deadline(w.now);
    assert!(idle > w.now, "an idle runtime has nothing due now");
    assert!(idle <= w.now + Duration::from_millis(500), "keep-state and resend run at 2 Hz");
    c.write(&pose_bytes()).unwrap();
    c.write(&GuiMessage::SendMoveCartography { command: Command::Forward }.to_bytes(MsgOrder::BigEndian))
        .unwrap();
    w.run_ms(200);
    assert!(w.robot.moving());
    assert_eq!(w.rt.next_deadline(w.now), w.now, "the control loop wants every poll while moving");
}
