//! The transport swap, end to end in separate processes: `explobot sim --serve` exposes the
//! twin's boards on pseudo-terminals and the unchanged `carto` binary opens them as serial ports.
//! Then either a client speaking the link protocol over TCP moves the robot one cell and reads its
//! new position — as Cute would against the real robot — or (feature `window`, with a display)
//! the unchanged `cute` window connects and runs cartography by itself.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

#[path = "e2e/processes/mod.rs"]
mod processes;

use processes::{Guard, TempDir, binary, free_port, workspace_root};
use protocol::link::{Command as Cmd, Decoder, Direction, GuiMessage, MsgOrder};
use transport::{Link, TcpLink};

fn read_until(
    link: &mut TcpLink,
    decoder: &mut Decoder,
    want: impl Fn(&GuiMessage) -> bool,
    limit: Duration,
) -> Vec<GuiMessage> {
    let deadline = Instant::now() + limit;
    let mut seen = Vec::new();
    let mut buf = [0u8; 256];
    while Instant::now() < deadline {
        let n = link.read(&mut buf).expect("carto closed the connection");
        for m in decoder.feed(&buf[..n]) {
            let m = m.expect("well-formed frame from carto");
            let done = want(&m);
            seen.push(m);
            if done {
                return seen;
            }
        }
        if n == 0 {
            std::thread::sleep(Duration::from_millis(5));
        }
    }
    panic!("timed out; received so far: {seen:?}");
}

/// The twin serving `scenarios/empty.ron` in real time on ptys in `run_dir` (its pose printed
/// every half second, sent line by line to the receiver) and the unchanged `carto` binary on those
/// ptys, listening for Cute on the returned port.
fn start_twin_and_carto(root: &Path, run_dir: &Path) -> (Guard, Guard, mpsc::Receiver<String>, u16) {
    let mut twin = Command::new(binary("explobot"))
        .args(["sim", "scenarios/empty.ron", "--serve", "--status-every", "0.5", "--run-dir"])
        .arg(run_dir)
        .current_dir(root)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("start explobot sim --serve");
    let stdout = twin.stdout.take().unwrap();
    let twin = Guard(twin);
    let (tx, lines) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let deadline = Instant::now() + Duration::from_secs(20);
    while !run_dir.join("tty-sensor").exists() {
        assert!(Instant::now() < deadline, "the twin did not create its ptys");
        std::thread::sleep(Duration::from_millis(20));
    }
    let port = free_port();
    let carto = Command::new(binary("carto"))
        .args(["--transport", "sim", "--motor-port"])
        .arg(run_dir.join("tty-motor"))
        .arg("--sensor-port")
        .arg(run_dir.join("tty-sensor"))
        .args(["--listen", &format!("127.0.0.1:{port}"), "--profile", "scenarios/robots/mecanum-4wd.ron"])
        .args(["--cell", "0.30"]) // scenarios/empty.ron is drawn for 0.30 m cells
        .current_dir(root)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start carto");
    (twin, Guard(carto), lines, port)
}

#[test]
fn carto_binary_drives_the_served_twin_over_ptys_one_cell_forward() {
    let root = workspace_root();
    let run_dir = TempDir::new("explobot-e2e");
    // 1. The twin, in real time, and 2. the unchanged carto binary on its ptys.
    let (twin, _carto, lines, port) = start_twin_and_carto(&root, &run_dir.0);

    // 3. A client over TCP, as Cute.
    let deadline = Instant::now() + Duration::from_secs(20);
    let mut link = loop {
        match TcpLink::connect(("127.0.0.1", port)) {
            Ok(l) => break l,
            Err(_) if Instant::now() < deadline => std::thread::sleep(Duration::from_millis(50)),
            Err(e) => panic!("carto never listened on {port}: {e}"),
        }
    };
    let mut decoder = Decoder::default();
    let send = |link: &mut TcpLink, m: GuiMessage| {
        let bytes = m.to_bytes(MsgOrder::BigEndian);
        assert_eq!(link.write(&bytes).unwrap(), bytes.len());
    };
    send(&mut link, GuiMessage::SendRobotPosition { x: 0, y: 0, direction: Direction::East });
    read_until(&mut link, &mut decoder, |m| *m == GuiMessage::RobotPositionReceived, Duration::from_secs(10));
    send(&mut link, GuiMessage::SendMoveCartography { command: Cmd::Forward });
    let replies =
        read_until(&mut link, &mut decoder, |m| *m == GuiMessage::MoveDone, Duration::from_secs(30));
    assert!(replies.contains(&GuiMessage::SetRobotPosition { x: 0, y: 1 }), "{replies:?}");

    // 4. The twin's physics agrees: the robot now stands in cell (0, 1).
    let deadline = Instant::now() + Duration::from_secs(5);
    let mut last = String::new();
    while Instant::now() < deadline {
        if let Ok(line) = lines.recv_timeout(Duration::from_millis(200)) {
            if line.contains("cell (0, 1)") {
                drop(twin);
                return;
            }
            last = line;
        }
    }
    panic!("the twin never reported the robot in cell (0, 1); last status: {last}");
}

/// The standalone `cute` window, unchanged, against the served twin and the `carto` binary: it
/// connects, sends the start position, runs cartography on its own (`--cartography`) and saves a
/// screenshot after 20 s of its wall clock, then exits. By then the twin must have carried the
/// robot at least to cell (0, 2) along the serpentine's first row, and the screenshot must show
/// cells (0, 0) and (0, 1) mapped and the far corner still unknown.
#[cfg(feature = "window")]
#[test]
fn cute_binary_maps_the_served_twin_through_the_carto_binary() {
    use bevy::math::Vec2;
    use cute::CellValue;
    use cute::gui::{CuteView, MapLayout, cell_rgb};

    if std::env::var_os("DISPLAY").is_none() {
        println!(
            "SKIPPED cute_binary_maps_the_served_twin_through_the_carto_binary: no display; run under xvfb-run"
        );
        return;
    }
    let root = workspace_root();
    let run_dir = TempDir::new("explobot-e2e-cute");
    let (_twin, _carto, lines, port) = start_twin_and_carto(&root, &run_dir.0);
    // Carto listens before cute starts, so cute does not begin with its connect back-off. The
    // probe connection closes at once; Carto notices within a step or two.
    let deadline = Instant::now() + Duration::from_secs(20);
    while TcpLink::connect(("127.0.0.1", port)).is_err() {
        assert!(Instant::now() < deadline, "carto never listened on {port}");
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_millis(500));
    let shot = run_dir.0.join("cute.png");
    // cute's log goes to a file: a pipe nobody reads could fill up and block it.
    let log_path = run_dir.0.join("cute.log");
    let log = std::fs::File::create(&log_path).unwrap();

    let (rows, cols) = (6usize, 8usize); // scenarios/empty.ron
    let mut cute = Guard(
        Command::new(binary("cute"))
            .args(["--connect", &format!("127.0.0.1:{port}"), "--rows", "6", "--cols", "8"])
            .args(["--heading", "east", "--cartography", "--screenshot-after", "20", "--screenshot"])
            .arg(&shot)
            .current_dir(&root)
            .stdout(Stdio::null())
            .stderr(log)
            .spawn()
            .expect("start cute"),
    );
    let deadline = Instant::now() + Duration::from_secs(120);
    let status = loop {
        if let Some(status) = cute.0.try_wait().unwrap() {
            break status;
        }
        if Instant::now() >= deadline {
            let log = std::fs::read_to_string(&log_path).unwrap_or_default();
            panic!("cute did not take its screenshot and exit within 120 s: {log}");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    let log = std::fs::read_to_string(&log_path).unwrap_or_default();
    assert!(status.success(), "cute exited with {status}: {log}");

    // The twin's physics: the robot went east along row 0, at least two cells.
    let statuses: Vec<String> = lines.try_iter().collect();
    assert!(
        statuses.iter().any(|l| l.contains("cell (0, 2)")),
        "the twin never had the robot in cell (0, 2): {statuses:?}"
    );

    // Cute's window: the cells it crossed are mapped, the far corner is not.
    let img = image::open(&shot).unwrap().to_rgb8();
    let (w, h) = (img.width() as f32, img.height() as f32);
    let layout = MapLayout::compute(Vec2::new(w, h), &CuteView::default(), rows, cols);
    let colour = |row: usize, col: usize| {
        let p = layout.cell_rect(row, col).min + Vec2::splat(layout.cell * 0.2);
        img.get_pixel(p.x as u32, p.y as u32).0
    };
    let is =
        |got: [u8; 3], value: CellValue| got.iter().zip(cell_rgb(value)).all(|(&a, b)| a.abs_diff(b) <= 12);
    for col in 0..2 {
        let got = colour(0, col);
        assert!(
            is(got, CellValue::Free) || is(got, CellValue::Robot),
            "cell (0, {col}) should be mapped, its pixel is {got:?}"
        );
    }
    let corner = colour(rows - 1, cols - 1);
    assert!(is(corner, CellValue::Unknown), "the far corner should be unknown, its pixel is {corner:?}");
}
