//! Issue 44: the twin's boards on serial devices (hardware in the loop) and `carto --record`.
//!
//! A USB-serial adapter appears as a device path such as `/dev/ttyUSB0`; `socat` makes the same
//! thing from two connected ptys, one end for the twin (`explobot sim --serve --motor-port …
//! --sensor-port …`, as the PC's adapters) and one for the unchanged `carto --transport serial`
//! binary (as the Pi's UARTs), at the profile's baud rates. Our Cute, without its window, drives a
//! mapping mission of the built-in default room over TCP.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::ffi::OsString;
use std::time::Duration;

use protocol::link::{Command as Cmd, Direction, GuiMessage};
// The twin's loader (`twin::record` re-exports the format from `transport::recording`).
use twin::record::{Recording, RecordingError};

use super::processes::{Carto, CuteClient, OutputWithin, SerialPair, TempDir, Twin, wait_for};

/// The default room's grid (`scenarios/default.ron`): 8 rows of 10 cells.
const ROWS: usize = 8;
const COLS: usize = 10;
/// Moves of the mapping mission compared: the first row, the turn at its end (the cabinet ahead)
/// and the start of the way back.
const MOVES: u64 = 14;

/// Cute's map and robot after [`MOVES`] moves of cartography against `carto`.
fn map_moves(carto: &Carto) -> (String, (u8, u8)) {
    let mut cute = CuteClient::connect(carto.port, ROWS, COLS);
    let cute = cute.map_for(MOVES, Duration::from_secs(150));
    let (x, y, _) = cute.robot();
    (cute.map().to_text(), (x, y))
}

fn os(args: &[&str]) -> Vec<OsString> {
    args.iter().map(Into::into).collect()
}

#[test]
fn issue_44_the_twin_on_serial_devices_maps_the_default_room_as_on_its_own_ptys() {
    let dir = TempDir::new("explobot-hil");
    // Over serial devices: the twin on the "PC" ends, carto on the "Pi" ends, at 115200 and 9600.
    let motor = SerialPair::new(&dir, "ttyUSB0", "ttyAMA0");
    let sensor = SerialPair::new(&dir, "ttyUSB1", "ttyAMA1");
    let mut args = os(&["--status-every", "0"]);
    args.extend([
        "--motor-port".into(),
        motor.a.clone().into(),
        "--sensor-port".into(),
        sensor.a.clone().into(),
    ]);
    let started = std::time::Instant::now();
    let twin_serial = Twin::serve(0, &args);
    for (port, baud) in [(&motor.a, 115_200), (&sensor.a, 9600)] {
        let line = format!("{} ({baud} baud)", port.display());
        twin_serial.wait_line_since(started, &line, Duration::from_secs(60), |l| l.contains(&line));
    }
    let carto_serial = Carto::start_on(&dir, "serial", (&motor.b, &sensor.b), &[]);
    // The same run over the twin's own ptys.
    let run = dir.0.join("run");
    let mut args = os(&["--status-every", "0", "--run-dir"]);
    args.push(run.clone().into());
    let _twin_pty = Twin::serve(0, &args);
    let carto_pty = Carto::start_on(&dir, "sim", (&run.join("tty-motor"), &run.join("tty-sensor")), &[]);

    let log = carto_serial.log();
    assert!(log.contains("baud=115200") && log.contains("baud=9600"), "{log}");
    // Both missions at once: each is real time, and the machine has cores to spare for two.
    let over_ptys = std::thread::spawn(move || map_moves(&carto_pty));
    let over_serial = map_moves(&carto_serial);
    let over_ptys = over_ptys.join().unwrap();
    assert_eq!(over_serial, over_ptys, "serial and pty runs mapped differently");
    let (map, _) = &over_serial;
    println!("the map after {MOVES} moves, over both:\n{map}");
    assert!(map.contains('0') && map.contains('1'), "no obstacle or no free cell mapped:\n{map}");
    drop(twin_serial);
}

#[test]
fn issue_44_a_missing_serial_device_is_a_clear_error() {
    let out = std::process::Command::new(super::processes::binary("explobot"))
        .args([
            "sim",
            "--serve",
            "--motor-port",
            "/dev/ttyUSB-explobot-missing",
            "--sensor-port",
            "/dev/null",
        ])
        .current_dir(super::processes::workspace_root())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("the motor board's port") && err.contains("/dev/ttyUSB-explobot-missing"), "{err}");
    assert!(err.contains("plugged in") && !err.contains("panicked"), "{err}");
}

#[test]
fn issue_44_an_adapter_unplugged_while_serving_ends_the_twin_with_a_clear_error() {
    let dir = TempDir::new("explobot-hil-unplug");
    let motor = SerialPair::new(&dir, "ttyUSB0", "ttyAMA0");
    let sensor = SerialPair::new(&dir, "ttyUSB1", "ttyAMA1");
    let mut twin = std::process::Command::new(super::processes::binary("explobot"));
    twin.args(["sim", "--serve", "--status-every", "0", "--motor-port"])
        .arg(&motor.a)
        .arg("--sensor-port")
        .arg(&sensor.a)
        .current_dir(super::processes::workspace_root());
    let motor_path = motor.a.display().to_string();
    // The motor adapter goes away two seconds in (socat ends, its ptys close).
    let unplug = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_secs(2));
        drop(motor);
    });
    let out = twin.output_within(Duration::from_secs(30));
    unplug.join().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains(&format!("the motor board's serial port {motor_path} stopped working")), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn issue_44_carto_record_writes_the_three_links_in_the_twin_s_format() {
    let dir = TempDir::new("explobot-carto-record");
    let file = dir.0.join("robot.rec");
    let twin = Twin::start(&dir, 0.5);
    let record = ["--record", file.to_str().unwrap(), "--record-flush", "0.2"];
    let mut carto = Carto::start(&dir, twin.base, twin.base + 1, &record);
    let mut client = carto.client();
    client.send(GuiMessage::SendRobotPosition { x: 0, y: 0, direction: Direction::East });
    client.read_until(|m| *m == GuiMessage::RobotPositionReceived, Duration::from_secs(10));
    client.send(GuiMessage::SendMoveCartography { command: Cmd::Forward });
    client.read_until(|m| *m == GuiMessage::MoveDone, Duration::from_secs(30));

    // While Carto runs, the file on disk is a complete recording with all three links.
    let has_links = |rec: &Recording| {
        ["motor", "sensor", "gui"].iter().all(|link| {
            rec.logs
                .iter()
                .any(|l| l.link == *link && l.endpoint.starts_with("carto") && !l.chunks.is_empty())
        })
    };
    wait_for("the three links on disk", Duration::from_secs(10), || {
        Recording::load(&file).ok().filter(has_links).map(|_| ())
    });
    carto.signal("TERM");
    assert_eq!(carto.wait_exit(Duration::from_secs(10)), Some(0));
    assert!(carto.log().contains("recording closed"), "{}", carto.log());

    // The twin's loader reads it: Carto's endpoints, the profile, no scenario to re-run.
    let rec = Recording::load(&file).unwrap();
    assert!(has_links(&rec), "{:?}", rec.logs.iter().map(|l| (&l.link, &l.endpoint)).collect::<Vec<_>>());
    assert!(rec.logs.iter().any(|l| l.link == "gui" && l.endpoint == "carto#1"));
    robot_model::profile::RobotProfile::from_ron_str(&rec.profile_ron, "recorded").unwrap();
    let err = twin::replay::rebuild(&rec).map(|_| ()).unwrap_err();
    assert!(err.to_string().contains("no scenario"), "{err}");
    // The last bytes Carto wrote to the motor board are the stop frame (drive v2, all zero).
    let motor = rec.logs.iter().find(|l| l.link == "motor").unwrap();
    let written: Vec<u8> = motor
        .chunks
        .iter()
        .filter(|c| c.direction == twin::record::Dir::Written)
        .flat_map(|c| c.bytes.clone())
        .collect();
    let stop = protocol::motor::MotorPacket::Drive(protocol::motor::MotorCommand::STOP_V2).to_bytes();
    assert!(
        written.ends_with(&stop),
        "last motor bytes {:02x?}",
        &written[written.len().saturating_sub(20)..]
    );
    // Times are Carto's wall clock since it started, in order.
    assert!(motor.chunks.windows(2).all(|w| w[0].at <= w[1].at));

    // A truncated recording (a copy cut in the middle) is a clear error.
    let bytes = std::fs::read(&file).unwrap();
    let cut = dir.0.join("cut.rec");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    match Recording::load(&cut) {
        Err(RecordingError::Decode { message, .. }) => assert!(message.contains("truncated"), "{message}"),
        other => panic!("{other:?}"),
    }
}
