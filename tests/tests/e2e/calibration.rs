//! Issue 44, items 3–5: a "robot" (a twin whose profile hides values moved 10–30 % from the
//! default) records its calibration drive through the real `carto --calibration-drive --record`
//! in real time; `explobot calibrate` recovers the hidden values, and `explobot replay --compare`
//! shows the gap shrink from the base profile to the fitted one.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::ffi::OsString;
use std::process::Command;
use std::time::Duration;

use super::processes::{Carto, TempDir, Twin, binary, free_port_pair, workspace_root};

/// (profile key, factor): the hidden robot.
const HIDDEN: [(&str, f64); 6] = [
    ("mass_kg", 1.25),
    ("wheel_radius_m", 1.12),
    ("tau_ms", 1.3),
    ("dead_band_percent", 0.85),
    ("drift_deg_per_min", 1.2),
    ("noise_sigma_cm", 1.3),
];

/// The default profile's text with `key`'s number multiplied by `factor`.
fn scaled(text: &str, key: &str, factor: f64) -> (String, f64) {
    let at = text.find(&format!("{key}:")).unwrap() + key.len() + 1;
    let rest = &text[at..];
    let start = rest.find(|c: char| c.is_ascii_digit()).unwrap();
    let end = start + rest[start..].find(|c: char| !(c.is_ascii_digit() || c == '.')).unwrap();
    let value: f64 = rest[start..end].parse::<f64>().unwrap() * factor;
    (format!("{}{}{value:.5}{}", &text[..at], &rest[..start], &rest[end..]), value)
}

fn explobot(args: &[&str]) -> String {
    let out = Command::new(binary("explobot")).args(args).current_dir(workspace_root()).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "{args:?}: {}\n{text}", String::from_utf8_lossy(&out.stderr));
    text
}

/// The value column of `name`'s row in `explobot calibrate`'s table: (fitted, σ).
fn row(table: &str, name: &str) -> (f64, Option<f64>) {
    let line = table
        .lines()
        .find(|l| l.trim_start().starts_with(name))
        .unwrap_or_else(|| panic!("{name}:\n{table}"));
    let cols: Vec<&str> = line.split_whitespace().collect();
    (cols[2].parse().unwrap(), cols[3].parse().ok())
}

#[test]
fn issue_44_calibrate_recovers_a_hidden_robot_from_carto_s_own_recording() {
    let dir = TempDir::new("explobot-calibration");
    let mut profile =
        std::fs::read_to_string(workspace_root().join("scenarios/robots/mecanum-4wd.ron")).unwrap();
    let mut truth = Vec::new();
    for (key, factor) in HIDDEN {
        let (text, value) = scaled(&profile, key, factor);
        profile = text;
        truth.push((key, value));
    }
    std::fs::write(dir.0.join("hidden.ron"), &profile).unwrap();
    let room = std::fs::read_to_string(workspace_root().join("scenarios/calibration/room.ron")).unwrap();
    std::fs::write(dir.0.join("room.ron"), room.replace("robot: None,", "robot: Some(\"hidden.ron\"),"))
        .unwrap();

    let base = free_port_pair();
    let mut args: Vec<OsString> = vec![dir.0.join("room.ron").into()];
    for a in ["--tcp", &base.to_string(), "--status-every", "0", "--run-dir"] {
        args.push(a.into());
    }
    args.push(dir.0.join("run").into());
    let _twin = Twin::serve(base, &args);
    let rec = dir.0.join("robot.rec");
    let rec_arg = rec.to_str().unwrap();
    let mut carto = Carto::start(&dir, base, base + 1, &["--calibration-drive", "--record", rec_arg]);
    assert_eq!(carto.wait_exit(Duration::from_secs(150)), Some(0), "{}", carto.log());
    assert!(carto.log().contains("calibration drive done"), "{}", carto.log());

    let fitted = dir.0.join("fitted.ron");
    let table = explobot(&["calibrate", rec_arg, "--out", fitted.to_str().unwrap()]);
    println!("{table}");
    for (key, value) in &truth {
        let name = table
            .lines()
            .filter_map(|l| l.split_whitespace().next())
            .find(|n| n.ends_with(&format!(".{key}")))
            .unwrap_or_else(|| panic!("{key} missing:\n{table}"));
        let (fit, sigma) = row(&table, name);
        let err = (fit - value).abs();
        match sigma {
            // within 5 %, or within three of its reported standard deviations
            Some(s) => {
                assert!(err <= 0.05 * value || err <= 3.0 * s, "{key}: {fit} ± {s}, truth {value}\n{table}")
            }
            // the twin's wheels make the body's motion independent of its mass: reported as such
            None => assert_eq!(*key, "mass_kg", "{table}"),
        }
    }
    let text = std::fs::read_to_string(&fitted).unwrap();
    assert!(text.contains(&format!("fitted to {rec_arg}")), "{text}");
    robot_model::profile::RobotProfile::from_ron_str(&text, "fitted").unwrap();

    // the gap shrinks in every stream from the base profile to the fitted one
    let svg = dir.0.join("gap.svg");
    let gap = explobot(&[
        "replay",
        rec_arg,
        "--compare",
        "--profile",
        "scenarios/robots/mecanum-4wd.ron",
        "--profile",
        fitted.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
    ]);
    println!("{gap}");
    let rms = |stream: &str| -> Vec<f64> {
        gap.lines()
            .filter(|l| l.trim_start().starts_with(stream) && l.contains("RMS"))
            .map(|l| l.split("RMS").nth(1).unwrap().split_whitespace().next().unwrap().parse().unwrap())
            .collect()
    };
    for stream in ["wheel speed", "heading", "range at rest"] {
        let v = rms(stream);
        assert_eq!(v.len(), 2, "{gap}");
        assert!(v[1] < 0.5 * v[0], "{stream}: {v:?}\n{gap}");
    }
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<polyline"));
}
