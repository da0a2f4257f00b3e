//! Scenario loading errors: each names the file, line and column of the value that is wrong,
//! as ron's parser finds it (issue 12: no hand-written text scanner).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::Path;

use robot_model::profile::RobotProfile;
use robot_model::time::Duration;
use twin::scenario::{Scenario, ScenarioError};
use twin::setup::RunSetup;

#[test]
fn default_room_loads() {
    let loaded = RunSetup::builtin_default().unwrap();
    assert_eq!(loaded.scenario.name, "default");
    assert!(!loaded.scenario.mission.is_empty());
}

#[test]
fn syntax_error_reports_line_and_column() {
    let text = "Scenario(\n  name: \"x\",\n  room: [(0.0, 0.0), (1.0, 0.0)\n";
    let err = Scenario::from_ron_str(text, "rooms/x.ron").unwrap_err();
    assert_eq!(err.file, "rooms/x.ron");
    assert!(err.line >= 3, "{err}");
}

#[test]
fn unknown_field_is_named_with_its_position() {
    let text = "Scenario(\n  name: \"x\",\n  rooom: [],\n)";
    let err = Scenario::from_ron_str(text, "x.ron").unwrap_err();
    assert_eq!((err.line, err.column), (3, 3), "{err}");
    assert!(err.message.contains("rooom"), "{err}");
}

#[test]
fn semantic_error_points_at_the_field() {
    let text = "Scenario(\n  name: \"x\",\n  room: [(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)],\n  start: (row: 0, col: 0, heading: East),\n)";
    let err = Scenario::from_ron_str(text, "x.ron").unwrap_err();
    assert_eq!(err.line, 3, "{err}");
    assert!(err.message.contains("no area"), "{err}");
}

fn rejects(body: &str) -> ScenarioError {
    let text = format!(
        "Scenario(\n  name: \"x\",\n  description: \"a room: start here\",\n  room: [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)],\n  start: (row: 0, col: 0, heading: East),\n{body}\n)"
    );
    RunSetup::from_ron_str(&text, "x.ron", Path::new(".")).unwrap_err()
}

#[test]
fn bad_values_are_rejected_where_they_are_written() {
    // Line 6 is the first line of `body`; the description mentioning "start" and "room" is
    // not mistaken for the fields. Each error points at the start of the bad value.
    let e = rejects("  noise: (friction: Some(-0.1)),");
    assert_eq!((e.line, e.column), (6, 21), "{e}");
    assert!(e.message.contains("friction"), "{e}");
    let e = rejects("  obstacles: [Polygon(points: [(0.1, 0.1), (0.2, 0.2), (0.3, 0.3)])],");
    assert_eq!((e.line, e.column), (6, 31), "{e}");
    assert!(e.message.starts_with("obstacles[0].points:"), "{e}");
    let e = rejects(
        "  obstacles: [Circle(center: (0.5, 0.5), radius: 0.1),\n    Circle(center: (0.5, 0.5), radius: inf)],",
    );
    assert_eq!((e.line, e.column), (7, 40), "{e}");
    assert!(e.message.starts_with("obstacles[1].radius:"), "{e}");
    let e = rejects("  obstacles: [Segment(from: (0.5, 0.5), to: (0.5, 0.5))],");
    assert_eq!((e.line, e.column), (6, 15), "{e}");
    let e = rejects("  mission: [StartCartography,\n    GoTo(5, 0)],");
    assert_eq!((e.line, e.column), (7, 5), "{e}");
    let e = rejects("  faults: [GuiDisconnect(at_s: -1.0)],");
    assert_eq!((e.line, e.column), (6, 32), "{e}");
    let e = rejects("  expect: (reached: Some((9, 9))),");
    assert_eq!((e.line, e.column), (6, 21), "{e}");
    let e = rejects("  cell: Some(0.001),");
    assert_eq!((e.line, e.column), (6, 9), "{e}");
    let e = rejects("  physics: (step_ms: 0.0),");
    assert_eq!((e.line, e.column), (6, 22), "{e}");
    assert!(e.message.starts_with("physics.step_ms:"), "{e}");
}

#[test]
fn issue_12_second_fault_error_points_at_the_second_fault() {
    let e = rejects("  faults: [GuiDisconnect(at_s: 1.0),\n    GuiDisconnect(at_s: -2.0)],");
    assert_eq!((e.line, e.column), (7, 25), "{e}");
    assert!(e.message.starts_with("faults[1].at_s:"), "{e}");
    // The same for a check that needs the grid: the third GoTo, not the first.
    let e = rejects("  mission: [GoTo(0, 0), GoTo(0, 0),\n    GoTo(0, 0), GoTo(9, 9)],");
    assert_eq!((e.line, e.column), (7, 17), "{e}");
    assert!(e.message.contains("GoTo(9, 9)"), "{e}");
}

#[test]
fn with_profile_reads_no_robot_file() {
    let text = "Scenario(name: \"x\", robot: Some(\"missing.ron\"), cell: Some(0.30), room: [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)], start: (row: 0, col: 0, heading: East))";
    let scenario = Scenario::from_ron_str(text, "x.ron").unwrap();
    let loaded = RunSetup::with_profile(scenario, RobotProfile::default(), text, "x.ron").unwrap();
    assert_eq!(loaded.dt(), Duration::from_millis(5));
    assert_eq!((loaded.truth().rows, loaded.truth().cols), (3, 3));
    assert_eq!(loaded.frame(), loaded.truth().frame);
}

#[test]
fn a_room_too_big_for_one_byte_coordinates_is_rejected() {
    let text = "Scenario(name: \"big\", room: [(0.0, 0.0), (200.0, 0.0), (200.0, 1.0), (0.0, 1.0)], start: (row: 0, col: 0, heading: East))";
    let e = RunSetup::from_ron_str(text, "big.ron", Path::new(".")).unwrap_err();
    assert!(e.message.contains("256"), "{e}");
}

#[test]
fn start_cell_outside_the_room_is_rejected() {
    let text = "Scenario(\n  name: \"x\",\n  room: [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)],\n  start: (row: 9, col: 0, heading: East),\n)";
    let err = RunSetup::from_ron_str(text, "x.ron", Path::new(".")).unwrap_err();
    assert_eq!(err.line, 4, "{err}");
    assert!(err.message.contains("start cell"), "{err}");
}

#[test]
fn issue_15_absurd_coordinates_and_obstacles_outside_the_room_are_errors_where_written() {
    // x = 2^32 m: a number, finite, and absurd.
    let e = rejects("  obstacles: [Circle(center: (4294967296.0, 0.5), radius: 0.1)],");
    assert_eq!((e.line, e.column), (6, 30), "{e}");
    assert!(e.message.starts_with("obstacles[0].center:") && e.message.contains("1000"), "{e}");
    let e = rejects("  obstacles: [Box(center: (0.5, 0.5), size: (1e9, 0.2))],");
    assert_eq!(e.line, 6, "{e}");
    assert!(e.message.starts_with("obstacles[0].size:"), "{e}");
    // In range, but wholly outside the 1 m room: the error points at the obstacle.
    let e = rejects(
        "  obstacles: [Circle(center: (0.5, 0.5), radius: 0.1),\n    Box(center: (40.0, 0.5), size: (0.2, 0.2))],",
    );
    assert_eq!((e.line, e.column), (7, 5), "{e}");
    assert!(e.message.contains("obstacles[1]: lies outside the room"), "{e}");
    // Touching the wall from outside still overlaps the room: allowed (half-pillars in walls).
    let text = "Scenario(\n  name: \"x\",\n  room: [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)],\n  obstacles: [Circle(center: (1.05, 0.5), radius: 0.1)],\n  start: (row: 0, col: 0, heading: East),\n)";
    assert!(Scenario::from_ron_str(text, "x.ron").is_ok());
}
