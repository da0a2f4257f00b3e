//! The `explobot` command line: exit codes and error messages a user sees.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::Command;

fn explobot() -> Command {
    let exe = std::env::current_exe().unwrap();
    let path: PathBuf = exe.parent().and_then(Path::parent).unwrap().join("explobot");
    assert!(path.exists(), "{} missing: cargo test --workspace builds it", path.display());
    let mut c = Command::new(path);
    c.current_dir(Path::new(".."));
    c
}

#[test]
fn a_broken_scenario_is_reported_with_file_line_and_column() {
    let dir = std::env::temp_dir().join(format!("explobot-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("broken.ron");
    std::fs::write(&file, "Scenario(\n  name: \"broken\",\n  room: [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0)],\n  start: (row: 0, col: 0, heading: Up),\n)\n").unwrap();
    let out = explobot().arg("check").arg(&file).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(2), "{text}");
    assert!(text.contains(&format!("{}:4:", file.display())), "{text}");
    let out = explobot().arg("run").arg(dir.join("missing.ron")).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.ron"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn decode_and_encode_round_trip_the_seed_frame() {
    let out =
        explobot().args(["encode", "--protocol", "motor", "drive-v1", "0x80", "0x80", "6"]).output().unwrap();
    assert!(out.status.success());
    assert_eq!(String::from_utf8_lossy(&out.stdout).trim(), "AA 03 01 80 80 06 0A");
    let out = explobot().args(["decode", "--protocol", "motor", "AA 03 01 80 80 06 0A"]).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("V1 { dir_x: 128, dir_y: 128, gear: 6 }") && text.contains("1 frame(s), 0 error(s)"),
        "{text}"
    );
    let out = explobot().args(["decode", "--protocol", "sensor", "zz"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn a_run_writes_its_files_and_replays_identically() {
    let out_dir = std::env::temp_dir().join(format!("explobot-cli-run-{}", std::process::id()));
    let out =
        explobot().args(["run", "scenarios/empty.ron", "--quiet", "--out"]).arg(&out_dir).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(text.contains("result          PASS"), "{text}");
    let report: String = std::fs::read_to_string(out_dir.join("report.json")).unwrap();
    assert!(report.contains("\"passed\": true"), "{report}");
    let png = std::fs::read(out_dir.join("map.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let out = explobot().arg("replay").arg(out_dir.join("links.rec")).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(text.contains("identical"), "{text}");
    // A damaged recording is an error with the file named, not a crash.
    std::fs::write(out_dir.join("bad.rec"), b"\x01\xff\xff\xff").unwrap();
    let out = explobot().arg("replay").arg(out_dir.join("bad.rec")).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("bad.rec"));
    std::fs::remove_dir_all(&out_dir).unwrap();
}

#[test]
fn bench_prints_every_sonar_variant_with_median_and_best() {
    let out = explobot()
        .args(["bench", "scenarios/empty.ron", "--physics-only", "--steps", "2000", "--rounds", "3"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    let rows: Vec<Vec<&str>> = text
        .lines()
        .filter(|l| l.starts_with("empty "))
        .map(|l| l.split("  ").map(str::trim).filter(|c| !c.is_empty()).collect())
        .collect();
    let labels: Vec<&str> = rows.iter().map(|r| r[1]).collect();
    assert_eq!(labels, ["off", "60 ms cycle", "every step"], "{text}");
    for row in &rows {
        let median: f64 = row[2].parse().unwrap();
        let best: f64 = row[3].parse().unwrap();
        assert!(median > 0.0 && best >= median, "{text}");
    }
    // The sonar does not move the robot: every variant drives the same trajectory.
    let collisions: Vec<&str> = rows.iter().map(|r| r[5]).collect();
    assert!(collisions.iter().all(|c| *c == collisions[0]), "{text}");
}

#[test]
fn a_known_room_run_says_so_in_its_report_and_is_refused_in_the_window() {
    let dir = std::env::temp_dir().join(format!("explobot-cli-known-{}", std::process::id()));
    let out =
        explobot().args(["run", "scenarios/empty.ron", "--known-room", "--out"]).arg(&dir).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(text.contains("known room      Carto was given every surface of the room"), "{text}");
    let report = std::fs::read_to_string(dir.join("report.json")).unwrap();
    assert!(report.contains("\"known_room\": true"), "{report}");
    // its recording replays with the room known again, byte for byte
    let replayed = explobot().arg("replay").arg(dir.join("links.rec")).output().unwrap();
    let text = String::from_utf8_lossy(&replayed.stdout);
    assert_eq!(replayed.status.code(), Some(0), "{text}");
    assert!(text.contains("identical"), "{text}");
    // a plain run's report has no such field
    let plain = explobot().args(["run", "scenarios/empty.ron", "--out"]).arg(&dir).output().unwrap();
    assert_eq!(plain.status.code(), Some(0));
    assert!(!std::fs::read_to_string(dir.join("report.json")).unwrap().contains("known_room"));
    for flag in ["--known-room", "--known-echoes"] {
        let out = explobot().args(["run", "--window", flag]).output().unwrap();
        assert_eq!(out.status.code(), Some(2));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--known-room and --known-echoes are for headless runs and sweeps"), "{err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--known-echoes` (README, "Perfect memory"): the report says so, the recording replays with the
/// echoes given again, byte for byte, and it cannot be combined with `--known-room`.
#[test]
fn a_known_echoes_run_says_so_replays_and_excludes_the_known_room() {
    let dir = std::env::temp_dir().join(format!("explobot-cli-echoes-{}", std::process::id()));
    let out = explobot()
        .args(["run", "scenarios/measured/default.ron", "--known-echoes", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("known echoes    Carto was given every point the sonar heard"), "{text}");
    let report = std::fs::read_to_string(dir.join("report.json")).unwrap();
    assert!(report.contains("\"known_echoes\": true") && !report.contains("known_room"), "{report}");
    let replayed = explobot().arg("replay").arg(dir.join("links.rec")).output().unwrap();
    let text = String::from_utf8_lossy(&replayed.stdout);
    assert_eq!(replayed.status.code(), Some(0), "{text}");
    assert!(text.contains("identical"), "{text}");
    let both = explobot().args(["run", "--known-room", "--known-echoes"]).output().unwrap();
    assert_eq!(both.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&both.stderr).contains("cannot be used with"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn truth_bounds_a_tour_for_each_clearance_and_stop_asked_for() {
    let dir = std::env::temp_dir().join(format!("explobot-cli-truth-{}", std::process::id()));
    let png = dir.join("truth.png");
    let out = explobot()
        .args(["truth", "sim/docs/truth-cases.ron", "--clearance", "0.02", "--stop-within", "0.03", "--out"])
        .arg(&png)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(text.contains("keeping 2.0 cm clear, stopping ≤ 3.0 cm off centres: one tour at most"), "{text}");
    assert!(!text.contains("stopping ≤ 0.0 cm"), "only the stops asked for: {text}");
    assert!(png.exists());
    let out =
        explobot().args(["truth", "sim/docs/truth-cases.ron", "--stop-within", "0.02"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2), "--stop-within needs --clearance");
    let out =
        explobot().args(["truth", "sim/docs/truth-cases.ron", "--clearance", "-0.01"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2), "a negative clearance is refused");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A reader that closes the pipe early (`explobot … | head`) gets what it read: no panic, the
/// exit code of the work, and the files written all the same.
#[test]
fn a_closed_standard_output_is_not_an_error() {
    let dir = std::env::temp_dir().join(format!("explobot-cli-pipe-{}", std::process::id()));
    let closed = || {
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader); // every write to `writer` now fails with EPIPE
        writer
    };
    let out =
        explobot().args(["generate", "--style", "flat", "--seed", "1"]).stdout(closed()).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    let png = dir.join("truth.png");
    let out = explobot()
        .args(["truth", "sim/docs/truth-cases.ron", "--out"])
        .arg(&png)
        .stdout(closed())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(png.exists(), "the picture is written after the text");
    let run = dir.join("run");
    let out = explobot().args(["run", "--quiet", "--out"]).arg(&run).stdout(closed()).output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "the default room passes: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(run.join("report.json").exists() && run.join("links.rec").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Carto's and Cute's log lines go to the run folder's log.txt, counted in the report, and to the
/// terminal only with `-v` (RUST_LOG left unset here).
#[test]
fn the_robot_programs_log_goes_to_log_txt_and_to_the_terminal_only_with_v() {
    let dir = std::env::temp_dir().join(format!("explobot-cli-log-{}", std::process::id()));
    let quiet =
        explobot().env_remove("RUST_LOG").args(["run", "--quiet", "--out"]).arg(&dir).output().unwrap();
    assert_eq!(quiet.status.code(), Some(0), "{}", String::from_utf8_lossy(&quiet.stderr));
    let (stdout, stderr) = (String::from_utf8_lossy(&quiet.stdout), String::from_utf8_lossy(&quiet.stderr));
    assert!(
        !stderr.contains("carto::") && !stderr.contains("cute::"),
        "robot lines on the terminal: {stderr}"
    );
    let log = std::fs::read_to_string(dir.join("log.txt")).unwrap();
    let lines = log.lines().count();
    assert!(log.contains(" INFO carto::") && lines > 10, "{log}");
    assert!(stdout.contains(&format!("log             {lines} lines from Carto and Cute")), "{stdout}");
    let loud =
        explobot().env_remove("RUST_LOG").args(["run", "-v", "--quiet", "--out"]).arg(&dir).output().unwrap();
    assert!(String::from_utf8_lossy(&loud.stderr).contains("carto::"), "-v shows them");
    std::fs::remove_dir_all(&dir).unwrap();
}
