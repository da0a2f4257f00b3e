//! The shipped robot profile file against `RobotProfile::default()`, and file-level errors.

use robot_model::profile::{ProfileError, RobotProfile};

/// Relative to the package root, the working directory of `cargo test` (a path baked in at compile
/// time would go stale when two checkouts share one target directory).
const SHIPPED: &str = "../scenarios/robots/mecanum-4wd.ron";

#[test]
fn shipped_profile_loads_and_equals_default() {
    let p = RobotProfile::load(SHIPPED).unwrap();
    assert_eq!(p, RobotProfile::default());
}

#[test]
fn syntax_error_in_file_reports_file_line_and_column() {
    let text = std::fs::read_to_string(SHIPPED).unwrap();
    // Break the value on the `track_m` line: `0.18` → `0.18.5`.
    let line = text.lines().position(|l| l.contains("track_m")).unwrap() + 1;
    let broken = text.replacen("track_m: 0.18,", "track_m: 0.18.5,", 1);
    let dir = std::env::temp_dir().join(format!("robot-model-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("broken.ron");
    std::fs::write(&path, broken).unwrap();
    let err = RobotProfile::load(&path).unwrap_err();
    std::fs::remove_dir_all(&dir).unwrap();
    match &err {
        ProfileError::Parse { path: p, line: l, column, .. } => {
            assert_eq!(p, &path.display().to_string());
            assert_eq!(*l, line, "{err}");
            assert!(*column > 8, "{err}");
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
    let shown = err.to_string();
    assert!(shown.starts_with(&format!("{}:{line}:", path.display())), "{shown}");
}

#[test]
fn missing_field_is_a_parse_error_naming_it() {
    let text = std::fs::read_to_string(SHIPPED).unwrap();
    let without: String = text.lines().filter(|l| !l.contains("mass_kg")).map(|l| format!("{l}\n")).collect();
    let err = RobotProfile::from_ron_str(&without, "robots/no-mass.ron").unwrap_err();
    assert!(matches!(&err, ProfileError::Parse { message, .. } if message.contains("mass_kg")), "{err}");
}
