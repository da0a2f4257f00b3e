use super::*;

#[test]
fn default_profile_is_valid_and_round_trips_through_ron() {
    let p = RobotProfile::default();
    p.validate().unwrap();
    let text = p.to_ron_string().unwrap();
    assert_eq!(RobotProfile::from_ron_str(&text, "x.ron").unwrap(), p);
}

#[test]
fn derived_values_match_robot_md() {
    let p = RobotProfile::default();
    assert!((p.pulses_per_wheel_rev() - 206.8).abs() < 1e-3);
    // 300 rpm on a 39 mm radius: 2π·0.039·5 = 1.2252 m/s.
    assert!((p.max_rim_speed_mps() - 1.225_221).abs() < 1e-4);
}

#[test]
fn negative_wheel_radius_is_rejected_with_its_field() {
    let mut p = RobotProfile::default();
    p.geometry.wheel_radius_m = -0.039;
    let text = p.to_ron_string().unwrap();
    let err = RobotProfile::from_ron_str(&text, "robots/bad.ron").unwrap_err();
    assert_eq!(
        err,
        ProfileError::Invalid {
            path: "robots/bad.ron".into(),
            field: "geometry.wheel_radius_m",
            value: -0.039,
            rule: "must be a finite number greater than zero",
        }
    );
    assert_eq!(
        err.to_string(),
        "robots/bad.ron: invalid `geometry.wheel_radius_m` = -0.039: must be a finite number greater than zero"
    );
}

#[test]
fn range_rules_reject_out_of_range_values() {
    type Case = (fn(&mut RobotProfile), &'static str);
    let cases: Vec<Case> = vec![
        (|p| p.motor.dead_band_percent = 100.0, "motor.dead_band_percent"),
        (|p| p.sonar.rays = 0, "sonar.rays"),
        (|p| p.sonar.min_cm = 500.0, "sonar.min_cm"),
        (|p| p.sonar.incidence_limit_deg = 91.0, "sonar.incidence_limit_deg"),
        (|p| p.serial.sensor_baud = 0, "serial.sensor_baud"),
        (|p| p.motor_board.watchdog_ms = 0, "motor_board.watchdog_ms"),
        (|p| p.sensor_board.navx_hz = f32::NAN, "sensor_board.navx_hz"),
        (|p| p.wheels.roller_angle_deg = 90.0, "wheels.roller_angle_deg"),
        (|p| p.imu.drift_deg_per_min = f32::INFINITY, "imu.drift_deg_per_min"),
    ];
    for (mutate, want) in cases {
        let mut p = RobotProfile::default();
        mutate(&mut p);
        match p.validate() {
            Err(ProfileError::Invalid { field, .. }) => assert_eq!(field, want),
            other => panic!("{want}: expected Invalid, got {other:?}"),
        }
    }
    // A disabled watchdog may have a zero timeout.
    let mut p = RobotProfile::default();
    p.motor_board.watchdog_enabled = false;
    p.motor_board.watchdog_ms = 0;
    p.validate().unwrap();
}

#[test]
fn unknown_field_reports_line_and_column() {
    let text = RobotProfile::default().to_ron_string().unwrap();
    let text = text.replacen("wheel_radius_m", "wheel_radios_m", 1);
    let line = text.lines().position(|l| l.contains("wheel_radios_m")).unwrap() + 1;
    let err = RobotProfile::from_ron_str(&text, "p.ron").unwrap_err();
    match &err {
        ProfileError::Parse { path, line: l, column, message } => {
            assert_eq!(path, "p.ron");
            assert_eq!(*l, line);
            assert!(*column > 1);
            assert!(message.contains("wheel_radios_m"), "{message}");
        }
        other => panic!("expected Parse, got {other:?}"),
    }
}

#[test]
fn missing_file_is_an_io_error() {
    let err = RobotProfile::load("/nonexistent/robot.ron").unwrap_err();
    assert!(matches!(err, ProfileError::Io { kind: std::io::ErrorKind::NotFound, .. }), "{err:?}");
    assert!(err.to_string().starts_with("/nonexistent/robot.ron: cannot read"));
}
