//! Carto as a robot daemon (issues 14 and 15), each test against the real `carto` binary and the
//! twin served in real time (`explobot sim --serve --tcp`): signals stop the motors, a twin that
//! dies and comes back is reconnected to, clients that reconnect at once or wait their turn are
//! served, a silent client is dropped, a flood of unknown ids stays out of the log, and a profile
//! that is not a regular file is refused at once.
//!
//! Every child process sits in a [`Guard`] that kills it when the test ends, passed or failed.
//! Waits are bounded and generous (a loaded 2-core CI machine); the timing assertions are the
//! issue's own (50 ms to the stop frame, 30 s to notice a silent client).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod processes;

use std::io::Read;
use std::net::{TcpListener, TcpStream};
use std::process::Command;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use processes::*;
use protocol::link::{Command as Cmd, Direction, GuiMessage};
use protocol::motor::{ChecksumPolicy, Decoder as MotorDecoder, MotorCommand, MotorPacket};

/// Bytes Carto wrote to the motor board, with the wall time the proxy read them.
type Tap = Arc<Mutex<Vec<(Instant, Vec<u8>)>>>;

/// A TCP proxy between Carto and the twin's motor port that records what Carto sends.
fn motor_tap(twin_motor: u16) -> (u16, Tap) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let tap: Tap = Arc::default();
    let record = Arc::clone(&tap);
    std::thread::spawn(move || {
        let Ok((mut from_carto, _)) = listener.accept() else { return };
        let Ok(mut to_twin) = TcpStream::connect(("127.0.0.1", twin_motor)) else { return };
        let (mut back_from_twin, mut back_to_carto) =
            (to_twin.try_clone().unwrap(), from_carto.try_clone().unwrap());
        std::thread::spawn(move || {
            let _ = std::io::copy(&mut back_from_twin, &mut back_to_carto);
        });
        let mut buf = [0u8; 4096];
        // Record every frame Carto sends until it closes the link, also once the twin is gone
        // and nothing can be forwarded (the stop frame after a lost link comes then).
        let mut forwarding = true;
        loop {
            match from_carto.read(&mut buf) {
                Ok(0) | Err(_) => break,
                Ok(n) => {
                    record.lock().unwrap().push((Instant::now(), buf[..n].to_vec()));
                    forwarding = forwarding && std::io::Write::write_all(&mut to_twin, &buf[..n]).is_ok();
                }
            }
        }
    });
    (port, tap)
}

/// The drive commands in the tap, each with the time its last byte was read.
fn drives(tap: &Tap) -> Vec<(Instant, (i8, i8, i8))> {
    let mut dec = MotorDecoder::new(ChecksumPolicy::Sum);
    let mut out = Vec::new();
    for (t, chunk) in tap.lock().unwrap().iter() {
        for p in dec.feed(chunk).into_iter().flatten() {
            if let MotorPacket::Drive(MotorCommand::V2 { vx, vy, omega, .. }) = p {
                out.push((*t, (vx, vy, omega)));
            }
        }
    }
    out
}

#[test]
fn issue_15_sigterm_mid_move_sends_the_stop_frame_within_50_ms_and_the_wheels_stop() {
    let dir = TempDir::new("explobot-daemon-sigterm");
    let twin = Twin::start(&dir, 0.05);
    let (tap_port, tap) = motor_tap(twin.base);
    let mut carto = Carto::start(&dir, tap_port, twin.base + 1, &[]);
    let mut c = carto.client();
    c.send(GuiMessage::SendRobotPosition { x: 0, y: 0, direction: Direction::East });
    c.read_until(|m| *m == GuiMessage::RobotPositionReceived, Duration::from_secs(20));
    c.send(GuiMessage::SendMovesTrajectory { n_total: 3, command: Cmd::Forward });
    c.send(GuiMessage::SendMovesTrajectory { n_total: 3, command: Cmd::Forward });
    c.send(GuiMessage::SendMovesTrajectory { n_total: 3, command: Cmd::Forward });
    // Mid-move: Carto drives forward, and the twin's wheels turn.
    wait_for("a forward drive frame", Duration::from_secs(20), || {
        drives(&tap).iter().any(|(_, d)| d.0 > 0).then_some(())
    });
    twin.wait_line("wheels turning", Duration::from_secs(10), |l| {
        wheels(l).is_some_and(|w| w.iter().any(|v| v.abs() > 5.0))
    });
    std::thread::sleep(Duration::from_millis(300));
    let before = drives(&tap).len();
    assert!(drives(&tap).last().is_some_and(|(_, d)| *d != (0, 0, 0)), "the move ended before SIGTERM");

    let t0 = Instant::now();
    carto.signal("TERM");
    let stop = wait_for("a stop frame after SIGTERM", Duration::from_secs(5), || {
        drives(&tap).into_iter().skip(before).find(|(t, d)| *t >= t0 && *d == (0, 0, 0)).map(|(t, _)| t)
    });
    let latency = stop.duration_since(t0);
    eprintln!("stop frame on the motor link {latency:?} after SIGTERM was sent");
    assert!(latency <= Duration::from_millis(50), "stop frame {latency:?} after SIGTERM");
    let code = carto.wait_exit(Duration::from_secs(10));
    assert_eq!(code, Some(0), "exit code after SIGTERM; log:\n{}", carto.log());
    assert!(carto.log().contains("SIGTERM"), "the log does not say why: {}", carto.log());
    // The twin's wheels are at 0 well before its 500 ms watchdog would have stopped them.
    twin.wait_line_since(t0, "wheels at 0", Duration::from_millis(400), |l| {
        wheels(l).is_some_and(|w| w.iter().all(|v| v.abs() < 0.5))
    });
}

#[test]
fn issue_15_sigint_and_sighup_stop_the_motors_and_exit_0() {
    for sig in ["INT", "HUP"] {
        let dir = TempDir::new(&format!("explobot-daemon-sig{sig}"));
        let twin = Twin::start(&dir, 0.5);
        let (tap_port, tap) = motor_tap(twin.base);
        let mut carto = Carto::start(&dir, tap_port, twin.base + 1, &[]);
        wait_for("carto drives the board", Duration::from_secs(20), || {
            (!drives(&tap).is_empty()).then_some(())
        });
        let before = drives(&tap).len();
        carto.signal(sig);
        assert_eq!(carto.wait_exit(Duration::from_secs(10)), Some(0), "SIG{sig}; log:\n{}", carto.log());
        assert!(drives(&tap).iter().skip(before).any(|(_, d)| *d == (0, 0, 0)), "SIG{sig}: no stop frame");
        assert!(carto.log().contains(&format!("SIG{sig}")), "{}", carto.log());
    }
}

#[test]
fn issue_15_twin_killed_and_restarted_mid_mission_carto_reconnects_and_a_new_trajectory_runs() {
    let dir = TempDir::new("explobot-daemon-restart");
    let twin = Twin::start(&dir, 0.5);
    let base = twin.base;
    let mut carto = Carto::start(&dir, base, base + 1, &[]);
    let mut c = carto.client();
    c.send(GuiMessage::SendRobotPosition { x: 0, y: 0, direction: Direction::East });
    c.read_until(|m| *m == GuiMessage::RobotPositionReceived, Duration::from_secs(20));
    for _ in 0..4 {
        c.send(GuiMessage::SendMovesTrajectory { n_total: 4, command: Cmd::Forward });
    }
    c.read_until(|m| *m == GuiMessage::SetRobotPosition { x: 0, y: 1 }, Duration::from_secs(30));
    // Mid-mission, the twin dies: the remaining moves did not happen, so no MOVE_DONE comes.
    drop(twin);
    let after_kill = c.collect_for(Duration::from_secs(3));
    assert!(
        !after_kill.contains(&GuiMessage::MoveDone),
        "MOVE_DONE for moves that did not happen: {after_kill:?}"
    );
    assert_eq!(carto.try_exit(), None, "carto exited on link loss; log:\n{}", carto.log());

    // The twin comes back on the same ports; Carto reopens both links on its own.
    let twin = Twin::start_on(&dir, base, 0.5);
    wait_for("carto reopens both board links", Duration::from_secs(30), || {
        (carto.log().matches("board link back").count() >= 2).then_some(())
    });
    // The same client session goes on: a new trajectory runs in the new twin.
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        c.send(GuiMessage::SendRobotPosition { x: 0, y: 0, direction: Direction::East });
        c.send(GuiMessage::SendMovesTrajectory { n_total: 1, command: Cmd::Forward });
        let got = c.read_until(|m| *m == GuiMessage::MoveDone, Duration::from_secs(30));
        if got.contains(&GuiMessage::SetRobotPosition { x: 0, y: 1 }) {
            break;
        }
        // MOVE_DONE alone: the sensor board had not sent keep-state yet. Try again.
        assert!(Instant::now() < deadline, "no trajectory ran after the twin came back: {got:?}");
        std::thread::sleep(Duration::from_millis(500));
    }
    twin.wait_line("the new twin's robot in cell (0, 1)", Duration::from_secs(10), |l| {
        l.contains("cell (0, 1)")
    });
    assert_eq!(carto.try_exit(), None);
}

#[test]
fn issue_15_exit_on_link_loss_stops_the_motors_and_exits_1() {
    let dir = TempDir::new("explobot-daemon-exit-on-loss");
    let twin = Twin::start(&dir, 0.5);
    let (tap_port, tap) = motor_tap(twin.base);
    // The sensor link goes through the twin directly: killing the twin drops it, while the
    // motor link (through the tap) is still open for the stop frame.
    let mut carto = Carto::start(&dir, tap_port, twin.base + 1, &["--exit-on-link-loss"]);
    wait_for("carto drives the board", Duration::from_secs(20), || (!drives(&tap).is_empty()).then_some(()));
    let before = drives(&tap).len();
    drop(twin);
    assert_eq!(carto.wait_exit(Duration::from_secs(20)), Some(1), "log:\n{}", carto.log());
    let log = carto.log();
    assert!(log.contains("--exit-on-link-loss"), "{log}");
    // the tap records what Carto wrote before it exited, on its own thread: give it a moment
    wait_for(&format!("a stop frame after the link loss; log:\n{log}"), Duration::from_secs(5), || {
        drives(&tap).iter().skip(before).any(|(_, d)| *d == (0, 0, 0)).then_some(())
    });
}

#[test]
fn issue_15_hundred_back_to_back_client_cycles_are_all_served() {
    let dir = TempDir::new("explobot-daemon-cycles");
    let twin = Twin::start(&dir, 0.5);
    let carto = Carto::start(&dir, twin.base, twin.base + 1, &[]);
    let mut resets = Vec::new();
    for i in 0..100 {
        let mut c = carto.client();
        let cycle = c
            .try_send(GuiMessage::SendRobotPosition { x: 0, y: 0, direction: Direction::East })
            .and_then(|()| {
                c.try_read_until(|m| *m == GuiMessage::RobotPositionReceived, Duration::from_secs(20))
            })
            .and_then(|_| c.try_send(GuiMessage::StopRobot));
        if let Err(e) = cycle {
            resets.push(format!("cycle {i}: {e}"));
        }
        drop(c); // closes at once; the next cycle connects immediately
    }
    assert!(resets.is_empty(), "{} of 100 cycles not served: {resets:?}", resets.len());
}

#[test]
fn issue_14_second_client_waits_and_is_served_when_the_first_leaves() {
    let dir = TempDir::new("explobot-daemon-second");
    let twin = Twin::start(&dir, 0.5);
    let carto = Carto::start(&dir, twin.base, twin.base + 1, &[]);
    let mut first = carto.client();
    first.send(GuiMessage::SendRobotPosition { x: 0, y: 0, direction: Direction::East });
    first.read_until(|m| *m == GuiMessage::RobotPositionReceived, Duration::from_secs(20));
    let mut second = carto.client();
    second.send(GuiMessage::SendRobotPosition { x: 0, y: 1, direction: Direction::East });
    // The second waits: not answered, not closed, while the first is still served.
    let waiting = second.collect_for(Duration::from_secs(1));
    assert!(waiting.is_empty(), "{waiting:?}");
    first.send(GuiMessage::SendRobotPosition { x: 0, y: 0, direction: Direction::East });
    first.read_until(|m| *m == GuiMessage::RobotPositionReceived, Duration::from_secs(20));
    drop(first);
    second.read_until(|m| *m == GuiMessage::RobotPositionReceived, Duration::from_secs(20));
    let log = carto.log();
    assert!(log.contains("waits in the backlog"), "{log}");
    assert!(log.contains("serving the client that waited"), "{log}");
}

#[test]
fn issue_14_silent_client_is_dropped_within_30_s_motors_stop_and_the_next_is_served() {
    let dir = TempDir::new("explobot-daemon-silent");
    let twin = Twin::start(&dir, 0.1);
    let (tap_port, tap) = motor_tap(twin.base);
    let carto = Carto::start(&dir, tap_port, twin.base + 1, &["--client-idle-limit", "3"]);
    let mut silent = carto.client();
    silent.send(GuiMessage::SendRobotPosition { x: 0, y: 0, direction: Direction::East });
    silent.read_until(|m| *m == GuiMessage::RobotPositionReceived, Duration::from_secs(20));
    // A long trajectory (7 cells east), then the client says nothing more and reads nothing.
    for _ in 0..7 {
        silent.send(GuiMessage::SendMovesTrajectory { n_total: 7, command: Cmd::Forward });
    }
    let t0 = Instant::now();
    wait_for("a forward drive frame", Duration::from_secs(20), || {
        drives(&tap).iter().any(|(_, d)| d.0 > 0).then_some(())
    });
    let dropped = wait_for("carto drops the silent client", Duration::from_secs(30), || {
        carto.log().contains("idle limit").then(Instant::now)
    });
    eprintln!("silent client dropped {:?} after its last byte", dropped.duration_since(t0));
    assert!(dropped.duration_since(t0) <= Duration::from_secs(30));
    // The motors stop at once, long before the 7 cells are driven.
    let n = drives(&tap).len();
    wait_for("a stop frame after the drop", Duration::from_secs(2), || {
        drives(&tap).into_iter().skip(n.saturating_sub(3)).any(|(_, d)| d == (0, 0, 0)).then_some(())
    });
    twin.wait_line_since(dropped, "wheels at 0", Duration::from_secs(2), |l| {
        wheels(l).is_some_and(|w| w.iter().all(|v| v.abs() < 0.5))
    });
    let last = twin.last_line();
    assert!(!last.contains("cell (0, 7)"), "the robot finished the trajectory anyway: {last}");
    assert!(silent.is_closed_within(Duration::from_secs(5)), "the silent client's socket was not closed");
    let mut next = carto.client();
    next.send(GuiMessage::SendRobotPosition { x: 0, y: 0, direction: Direction::East });
    next.read_until(|m| *m == GuiMessage::RobotPositionReceived, Duration::from_secs(20));
}

#[test]
fn issue_15_a_megabyte_of_unknown_ids_writes_fewer_than_100_log_lines() {
    let dir = TempDir::new("explobot-daemon-flood");
    let twin = Twin::start(&dir, 0.5);
    let carto = Carto::start(&dir, twin.base, twin.base + 1, &[]);
    let mut c = carto.client();
    c.send(GuiMessage::SendRobotPosition { x: 0, y: 0, direction: Direction::East });
    c.read_until(|m| *m == GuiMessage::RobotPositionReceived, Duration::from_secs(20));
    let lines_before = carto.log().lines().count();
    let frame = GuiMessage::Unknown { msg: 0x7777, data: vec![0x55; 12] }
        .to_bytes(protocol::link::MsgOrder::BigEndian);
    let mut flood = Vec::with_capacity(1 << 20);
    while flood.len() + frame.len() <= 1 << 20 {
        flood.extend_from_slice(&frame);
    }
    c.send_raw(&flood);
    // Carto has read it all when it answers the position sent after the flood.
    c.send(GuiMessage::SendRobotPosition { x: 0, y: 0, direction: Direction::East });
    c.read_until(|m| *m == GuiMessage::RobotPositionReceived, Duration::from_secs(60));
    std::thread::sleep(Duration::from_millis(1500)); // the last "N more like this" line
    let log = carto.log();
    let new_lines = log.lines().count() - lines_before;
    assert!(log.contains("unknown message ignored"), "the flood was not seen: {log}");
    assert!(log.contains("more like this"), "no summary of the suppressed warnings: {log}");
    eprintln!("{new_lines} log lines for {} unknown frames", flood.len() / frame.len());
    assert!(new_lines < 100, "{new_lines} log lines for {} frames", flood.len() / frame.len());
}

#[test]
fn issue_15_dev_zero_and_a_fifo_as_profile_are_clear_errors_within_1_s() {
    let dir = TempDir::new("explobot-daemon-profile");
    std::fs::create_dir_all(&dir.0).unwrap();
    let fifo = dir.0.join("profile.fifo");
    let made = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo");
    assert!(made.success());
    for profile in [std::path::PathBuf::from("/dev/zero"), fifo] {
        let t0 = Instant::now();
        let out = Command::new(binary("carto"))
            .args(["--transport", "tcp", "--motor-port", "127.0.0.1:9", "--sensor-port", "127.0.0.1:9"])
            .args(["--listen", "127.0.0.1:0", "--profile"])
            .arg(&profile)
            .output_within(Duration::from_secs(10));
        let took = t0.elapsed();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{}: {stderr}", profile.display());
        assert!(stderr.contains("not a regular file"), "{}: {stderr}", profile.display());
        assert!(took < Duration::from_secs(1), "{}: took {took:?}", profile.display());
    }
}
