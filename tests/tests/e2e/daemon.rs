//! Carto as a robot daemon (issues 14, 15 and 45), each test against the real `carto` binary and the
//! twin served in real time (`explobot sim --serve --tcp`): signals stop the motors, a twin that
//! dies and comes back is reconnected to, clients that reconnect at once or wait their turn are
//! served, a silent client is dropped, a flood of unknown ids stays out of the log, and a profile
//! that is not a regular file is refused at once.
//!
//! Every child process sits in a [`Guard`] that kills it when the test ends, passed or failed.
//! Waits are bounded and generous (a loaded 2-core CI machine); the timing assertions are the
//! issue's own (50 ms to the stop frame, 30 s to notice a silent client).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::io::Read;
use std::net::{TcpListener, TcpStream};
use std::process::Command;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::processes::*;
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
        // Carto has exited; the tap's thread may read its last bytes a moment later.
        wait_for(&format!("the stop frame after SIG{sig}"), Duration::from_secs(2), || {
            drives(&tap).iter().skip(before).any(|(_, d)| *d == (0, 0, 0)).then_some(())
        });
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

/// Signal numbers on Linux, by the names `kill` takes.
const SIGNALS_THAT_STOP: [(&str, i32); 16] = [
    ("QUIT", 3),
    ("USR1", 10),
    ("USR2", 12),
    ("ALRM", 14),
    ("TRAP", 5),
    ("ABRT", 6),
    ("STKFLT", 16),
    ("XCPU", 24),
    ("XFSZ", 25),
    ("VTALRM", 26),
    ("PROF", 27),
    ("IO", 29),
    ("PWR", 30),
    ("SYS", 31),
    ("34", 34), // SIGRTMIN
    ("64", 64), // SIGRTMAX
];

/// Starts Carto through a motor tap on `twin`, starts a turn on the spot (safe to repeat in the
/// one twin), sends `sig` mid-turn, and checks that the zero drive went out after the signal,
/// within 100 ms, and before exit, through the stop path. The exit code.
fn signal_stops_the_motors(dir: &TempDir, twin: &Twin, sig: &str) -> Result<Option<i32>, String> {
    let (tap_port, tap) = motor_tap(twin.base);
    let mut carto = Carto::start(dir, tap_port, twin.base + 1, &[]);
    let mut c = carto.client();
    c.send(GuiMessage::SendRobotPosition { x: 2, y: 2, direction: Direction::East });
    c.read_until(|m| *m == GuiMessage::RobotPositionReceived, Duration::from_secs(20));
    c.send(GuiMessage::SendMoveCartography { command: Cmd::Right });
    wait_for(&format!("SIG{sig}: a turning drive frame"), Duration::from_secs(20), || {
        drives(&tap).iter().any(|(_, d)| d.2 != 0).then_some(())
    });
    std::thread::sleep(Duration::from_millis(200));
    if drives(&tap).last().is_some_and(|(_, d)| *d == (0, 0, 0)) {
        return Err(format!("SIG{sig}: the turn ended before the signal; log:\n{}", carto.log()));
    }
    let t0 = Instant::now();
    carto.signal(sig);
    let code = carto.wait_exit(Duration::from_secs(10));
    // the tap records on its own thread: give it a moment to read the last bytes
    std::thread::sleep(Duration::from_millis(200));
    let stop = drives(&tap).into_iter().find(|(t, d)| *t >= t0 && *d == (0, 0, 0)).map(|(t, _)| t);
    let log = carto.log();
    let Some(stop) = stop else {
        return Err(format!("SIG{sig}: no stop frame after the signal; log:\n{log}"));
    };
    let latency = stop.duration_since(t0);
    if latency > Duration::from_millis(100) {
        return Err(format!("SIG{sig}: stop frame {latency:?} after the signal"));
    }
    if !log.contains("carto stopped") || !log.contains("stop_frame_sent=true") {
        return Err(format!("SIG{sig}: the stop path did not run; log:\n{log}"));
    }
    eprintln!("SIG{sig}: stop frame {latency:?} after the signal, exit {code:?}");
    Ok(code)
}

#[test]
fn issue_45_every_catchable_terminating_signal_sends_the_stop_frame_before_exit() {
    let dir = TempDir::new("explobot-daemon-signals");
    let twin = Twin::start(&dir, 0.5);
    let mut failures = Vec::new();
    for (sig, n) in SIGNALS_THAT_STOP {
        match signal_stops_the_motors(&dir, &twin, sig) {
            Ok(code) if code == Some(128 + n) => {}
            Ok(code) => failures.push(format!("SIG{sig}: exit {code:?}, expected {}", 128 + n)),
            Err(e) => failures.push(e),
        }
    }
    for sig in ["TERM", "INT", "HUP"] {
        match signal_stops_the_motors(&dir, &twin, sig) {
            Ok(Some(0)) => {}
            Ok(code) => failures.push(format!("SIG{sig}: exit {code:?}, expected 0")),
            Err(e) => failures.push(e),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn issue_45_sigpipe_is_ignored_and_carto_keeps_driving() {
    let dir = TempDir::new("explobot-daemon-sigpipe");
    let twin = Twin::start(&dir, 0.5);
    let (tap_port, tap) = motor_tap(twin.base);
    let mut carto = Carto::start(&dir, tap_port, twin.base + 1, &[]);
    wait_for("carto drives the board", Duration::from_secs(20), || (!drives(&tap).is_empty()).then_some(()));
    carto.signal("PIPE");
    let n = drives(&tap).len();
    // The idle zero drive is resent every 500 ms: two more arrive if Carto is alive.
    wait_for("carto still driving after SIGPIPE", Duration::from_secs(5), || {
        (drives(&tap).len() >= n + 2).then_some(())
    });
    assert_eq!(carto.try_exit(), None, "SIGPIPE ended carto; log:\n{}", carto.log());
    let mut c = carto.client();
    c.send(GuiMessage::SendRobotPosition { x: 0, y: 0, direction: Direction::East });
    c.read_until(|m| *m == GuiMessage::RobotPositionReceived, Duration::from_secs(20));
}

#[test]
fn issue_45_after_sigkill_the_motor_boards_watchdog_stops_the_wheels() {
    let dir = TempDir::new("explobot-daemon-sigkill");
    let twin = Twin::start(&dir, 0.02);
    let mut carto = Carto::start(&dir, twin.base, twin.base + 1, &[]);
    let mut c = carto.client();
    c.send(GuiMessage::SendRobotPosition { x: 0, y: 0, direction: Direction::East });
    c.read_until(|m| *m == GuiMessage::RobotPositionReceived, Duration::from_secs(20));
    for _ in 0..3 {
        c.send(GuiMessage::SendMovesTrajectory { n_total: 3, command: Cmd::Forward });
    }
    twin.wait_line("wheels turning", Duration::from_secs(20), |l| {
        wheels(l).is_some_and(|w| w.iter().any(|v| v.abs() > 5.0))
    });
    std::thread::sleep(Duration::from_millis(300));
    let t0 = Instant::now();
    carto.signal("KILL");
    assert_eq!(carto.wait_exit(Duration::from_secs(5)), None, "SIGKILL cannot be caught");
    // No stop frame can be sent: the board's 500 ms watchdog stops the wheels, which then spin
    // down with the motor model's lag.
    let stopped = twin.wait_line_since(t0, "wheels at 0 after SIGKILL", Duration::from_secs(3), |l| {
        wheels(l).is_some_and(|w| w.iter().all(|v| v.abs() < 0.5))
    });
    eprintln!("after SIGKILL: wheels at 0 {:?} later (status lines every 20 ms)", stopped.duration_since(t0));
    assert!(
        stopped.duration_since(t0) >= Duration::from_millis(400),
        "stopped before the watchdog could act"
    );
}

/// Logs since `from` bytes into the log, and the sum of every `more=N` summary in them.
fn log_since(carto: &Carto, from: usize) -> (String, u64) {
    let log = carto.log();
    let new = log.get(from..).unwrap_or_default().to_owned();
    let more = new
        .lines()
        .filter_map(|l| l.split("more=").nth(1))
        .filter_map(|r| r.split_whitespace().next()?.parse::<u64>().ok())
        .sum();
    (new, more)
}

#[test]
fn issue_45_a_megabyte_of_each_malformed_kind_writes_a_few_kilobytes_of_log() {
    let dir = TempDir::new("explobot-daemon-log-flood");
    let twin = Twin::start(&dir, 0.5);
    let carto = Carto::start(&dir, twin.base, twin.base + 1, &[]);
    let kinds: [(&str, &[u8], &str); 5] = [
        ("cartography moves with command 9", &[0x00, 0x03, 0x02, 0x00, 9], "is not a move"),
        ("trajectories with n_total 0", &[0x00, 0x04, 0x01, 0x00, 0, 0], "n_total 0"),
        ("positions with direction 9", &[0x00, 0x05, 0x07, 0x00, 1, 1, 9], "invalid direction"),
        ("STOP frames", &[0x00, 0x02, 0x06, 0x00], "stop: motors stopped"),
        ("MOVE_DONE sent by the client", &[0x00, 0x02, 0x03, 0x00], "message for Cute received"),
    ];
    let mut report = Vec::new();
    for (name, frame, line) in kinds {
        let from = carto.log().len();
        let frames = (1 << 20) / frame.len();
        let flood = frame.repeat(frames);
        let mut stream = TcpStream::connect(("127.0.0.1", carto.port)).unwrap();
        // Drain Carto's replies (MOVE_DONE, ROBOT_POSITION_RECEIVED) so it never sees a stuck client.
        let mut reader = stream.try_clone().unwrap();
        let drain = std::thread::spawn(move || {
            let mut buf = [0u8; 65536];
            while matches!(reader.read(&mut buf), Ok(n) if n > 0) {}
        });
        std::io::Write::write_all(&mut stream, &flood).unwrap();
        // Every frame is logged or counted in a summary: wait for the counts to add up.
        let (log, more) =
            wait_for(&format!("{name}: every frame logged or counted"), Duration::from_secs(60), || {
                let (log, more) = log_since(&carto, from);
                let logged =
                    log.lines().filter(|l| l.contains(line) && !l.contains("more like this")).count() as u64;
                (logged + more >= frames as u64).then_some((log, more))
            });
        // the reader holds a clone of the socket: shut it down so its read ends
        let _ = stream.shutdown(std::net::Shutdown::Both);
        let _ = drain.join();
        let logged = log.lines().filter(|l| l.contains(line) && !l.contains("more like this")).count() as u64;
        assert_eq!(logged + more, frames as u64, "{name}: lines and summaries do not add up:\n{log}");
        report.push(format!(
            "{name}: {frames} frames, {} bytes / {} lines of log",
            log.len(),
            log.lines().count()
        ));
        assert!(log.len() < 4096, "{name}: {} bytes of log for 1 MB:\n{log}", log.len());
    }
    eprintln!("{}", report.join("\n"));
}

#[test]
fn issue_45_five_hundred_empty_connections_write_a_few_lines() {
    let dir = TempDir::new("explobot-daemon-conn-flood");
    let twin = Twin::start(&dir, 0.5);
    let carto = Carto::start(&dir, twin.base, twin.base + 1, &[]);
    let from = carto.log().len();
    let t0 = Instant::now();
    for _ in 0..500 {
        drop(TcpStream::connect(("127.0.0.1", carto.port)).unwrap());
    }
    // Carto has served them all when the next client is answered.
    let mut c = carto.client();
    c.send(GuiMessage::SendRobotPosition { x: 0, y: 0, direction: Direction::East });
    c.read_until(|m| *m == GuiMessage::RobotPositionReceived, Duration::from_secs(30));
    std::thread::sleep(Duration::from_millis(1500)); // the last summaries
    let (log, _) = log_since(&carto, from);
    let secs = t0.elapsed().as_secs_f64().ceil();
    eprintln!("500 connections in {secs} s: {} bytes / {} lines of log", log.len(), log.lines().count());
    // At most one line of each of the three connection kinds, plus its summary, per second.
    assert!(log.lines().count() as f64 <= 6.0 * (secs + 1.0) + 4.0, "{log}");
    assert!(log.contains("more like this"), "{log}");
}

#[test]
fn issue_45_a_client_trickling_a_frame_is_closed_by_the_idle_limit() {
    let dir = TempDir::new("explobot-daemon-trickle");
    let twin = Twin::start(&dir, 0.5);
    let carto = Carto::start(&dir, twin.base, twin.base + 1, &["--client-idle-limit", "2"]);
    let mut c = carto.client();
    c.send(GuiMessage::SendRobotPosition { x: 0, y: 0, direction: Direction::East });
    c.read_until(|m| *m == GuiMessage::RobotPositionReceived, Duration::from_secs(20));
    let t0 = Instant::now();
    // A 1,000-byte frame, one byte every 300 ms: it would take 5 minutes to complete.
    let mut frame = vec![0x03, 0xE8, 0x07, 0x00];
    frame.resize(1002, 0x55);
    let mut closed = None;
    for b in frame.chunks(1) {
        if c.try_send_raw(b).is_err() || c.is_closed_within(Duration::from_millis(300)) {
            closed = Some(t0.elapsed());
            break;
        }
        assert!(t0.elapsed() < Duration::from_secs(15), "the trickling client still holds the session");
    }
    let closed = closed.expect("the trickling client was never closed");
    eprintln!("trickling client closed {closed:?} after its last complete frame");
    assert!(closed >= Duration::from_millis(1500) && closed <= Duration::from_secs(4), "{closed:?}");
    assert!(carto.log().contains("idle limit: no complete frame"), "{}", carto.log());
}

#[test]
fn issue_45_an_oversize_frame_gets_a_clean_close_not_a_reset() {
    let dir = TempDir::new("explobot-daemon-oversize");
    let twin = Twin::start(&dir, 0.5);
    let carto = Carto::start(&dir, twin.base, twin.base + 1, &[]);
    for _ in 0..20 {
        let mut s = TcpStream::connect(("127.0.0.1", carto.port)).unwrap();
        let mut bytes = vec![0xFF, 0xFF, 0x07, 0x00];
        bytes.resize(32 * 1024, 0x55);
        std::io::Write::write_all(&mut s, &bytes).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
        let mut buf = [0u8; 64];
        match s.read(&mut buf) {
            Ok(0) => {}
            other => panic!("expected a clean close (EOF), got {other:?}"),
        }
    }
    assert!(carto.log().contains("fatal framing error"), "{}", carto.log());
}
