//! Issue 13: runs as MCAP files and live over the Foxglove WebSocket protocol.
//!
//! 1. `explobot run --mcap` files read back with the `mcap` crate: every channel with its schema,
//!    message counts that agree with the report (frames per link and direction, one pose per
//!    20 steps), log times that never go back; the run itself unchanged (same `links.rec` bytes
//!    and link-log hash as without `--mcap`).
//! 2. `explobot replay links.rec --mcap` writes the same messages as the run did.
//! 3. A WebSocket client on `explobot sim --serve --foxglove` subscribes and receives poses; on
//!    `explobot run --window --foxglove` (under Xvfb) poses and Cute's map.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;
use std::time::Duration;

use crate::processes::{OutputWithin, TempDir, binary, workspace_root};
use serde_json::Value;

/// Poses are logged every this many steps (`twin_viz::POSE_EVERY`).
const POSE_EVERY: u64 = 20;

/// Every channel a lockstep run writes: topic, schema name.
const CHANNELS: &[(&str, &str)] = &[
    ("/tf", "foxglove.FrameTransforms"),
    ("/robot/pose", "foxglove.PoseInFrame"),
    ("/carto/pose", "foxglove.PoseInFrame"),
    ("/carto/belief", "foxglove.SceneUpdate"),
    ("/carto/grid", "foxglove.Grid"),
    ("/sonar/rays", "foxglove.SceneUpdate"),
    ("/sonar/range", "sonarrange.SonarRange"),
    ("/cute/map", "foxglove.Grid"),
    ("/cute/path", "foxglove.PosesInFrame"),
    ("/room", "foxglove.SceneUpdate"),
    ("/links/motor/bytes", "linkbytes.LinkBytes"),
    ("/links/sensor/bytes", "linkbytes.LinkBytes"),
    ("/links/gui/bytes", "linkbytes.LinkBytes"),
    ("/links/motor/out", "motorframe.MotorFrame"),
    ("/links/motor/in", "motorframe.MotorFrame"),
    ("/links/sensor/out", "sensorframe.SensorFrame"),
    ("/links/sensor/in", "sensorframe.SensorFrame"),
    ("/links/gui/out", "guiframe.GuiFrame"),
    ("/links/gui/in", "guiframe.GuiFrame"),
    ("/log", "foxglove.Log"),
    ("/report", "runreport.RunReport"),
];

/// What a file holds, per topic: schema name and encoding, messages, and every log time in
/// file order.
struct Mcap {
    channels: BTreeMap<String, (String, String, u64)>,
    times: Vec<(String, u64)>,
    last_report: Vec<u8>,
}

fn read_mcap(path: &Path) -> Mcap {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut channels: BTreeMap<String, (String, String, u64)> = BTreeMap::new();
    let mut times = Vec::new();
    let mut last_report = Vec::new();
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        let m = message.unwrap();
        let topic = m.channel.topic.clone();
        let schema = m.channel.schema.as_ref().expect("every channel has a schema");
        assert!(!schema.data.is_empty(), "{topic}: empty schema");
        let entry = channels
            .entry(topic.clone())
            .or_insert_with(|| (schema.name.clone(), schema.encoding.clone(), 0));
        entry.2 += 1;
        if topic == "/report" {
            last_report = m.data.to_vec();
        }
        times.push((topic, m.log_time));
    }
    // The file's own statistics (summary section) agree with what was read.
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary section");
    let stats = summary.stats.expect("statistics");
    assert_eq!(stats.message_count, times.len() as u64);
    for (id, count) in &stats.channel_message_counts {
        let topic = &summary.channels[id].topic;
        assert_eq!(channels[topic].2, *count, "{topic}: statistics");
    }
    Mcap { channels, times, last_report }
}

/// `explobot ARGS` from the workspace root: its exit code (0 or 1, else it panics) and stdout.
fn explobot_code(args: &[&str]) -> (i32, String) {
    let out = Command::new(binary("explobot"))
        .args(args)
        .current_dir(workspace_root())
        .output_within(Duration::from_secs(300));
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let code = out.status.code().unwrap_or(-1);
    assert!(
        code == 0 || code == 1,
        "explobot {args:?} exited {code}\n{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    (code, text)
}

fn count(m: &Mcap, topic: &str) -> u64 {
    m.channels.get(topic).map_or(0, |c| c.2)
}

/// The report's frames + errors for one link and direction (`outbound` / `inbound`).
fn frames(report: &Value, link: &str, direction: &str) -> u64 {
    let l = report["links"].as_array().unwrap().iter().find(|l| l["name"] == link).unwrap();
    l[direction]["frames"].as_u64().unwrap() + l[direction]["errors"].as_u64().unwrap()
}

/// Runs `scenario` with and without `--mcap`; checks the file against the report and the run
/// against the run without it. Returns the file's contents and the report.
fn check_run(scenario: &str, dir: &TempDir) -> (Mcap, Value) {
    let plain = dir.0.join("plain");
    let recorded = dir.0.join("recorded");
    let file = dir.0.join("run.mcap");
    let p = |p: &Path| p.to_str().unwrap().to_owned();
    // Exit code 1 (an expectation failed) is a finished run too.
    let code = explobot_code(&["run", scenario, "--quiet", "--out", &p(&plain)]).0;
    let (code_mcap, stdout) =
        explobot_code(&["run", scenario, "--quiet", "--out", &p(&recorded), "--mcap", &p(&file)]);
    assert_eq!(code, code_mcap);
    assert!(stdout.contains(&format!("wrote {}", file.display())), "{stdout}");

    // Nothing changes for the run: the same bytes on every link, the same hash.
    let read = |d: &Path, f: &str| std::fs::read(d.join(f)).unwrap();
    assert!(
        read(&plain, "links.rec") == read(&recorded, "links.rec"),
        "{scenario}: links.rec differs with --mcap"
    );
    let report: Value = serde_json::from_slice(&read(&recorded, "report.json")).unwrap();
    let plain_report: Value = serde_json::from_slice(&read(&plain, "report.json")).unwrap();
    assert_eq!(report["link_log_sha256"], plain_report["link_log_sha256"]);

    let m = read_mcap(&file);
    for (topic, schema) in CHANNELS {
        let (name, encoding, n) = m.channels.get(*topic).unwrap_or_else(|| panic!("{scenario}: no {topic}"));
        assert_eq!((name.as_str(), encoding.as_str()), (*schema, "protobuf"), "{topic}");
        assert!(*n > 0, "{topic}");
    }
    assert_eq!(m.channels.len(), CHANNELS.len(), "unexpected channels: {:?}", m.channels.keys());

    // One pose at the start, one every 20 steps, one at the last step.
    let steps = report["steps"].as_u64().unwrap();
    assert_eq!(
        count(&m, "/robot/pose"),
        1 + steps.div_ceil(POSE_EVERY),
        "{scenario}: poses for {steps} steps"
    );
    assert_eq!(count(&m, "/tf"), count(&m, "/robot/pose"));
    assert!(count(&m, "/carto/pose") <= count(&m, "/robot/pose"));
    assert!(count(&m, "/carto/belief") <= count(&m, "/carto/pose"));
    // Carto's grid at most every 2,000 steps (10 s) and at the last step.
    assert!(count(&m, "/carto/grid") <= 1 + steps / 2000, "{scenario}: {}", count(&m, "/carto/grid"));
    // Every frame the receivers decoded, and every error they saw, per link and direction.
    for link in ["motor", "sensor", "gui"] {
        assert_eq!(
            count(&m, &format!("/links/{link}/out")),
            frames(&report, link, "outbound"),
            "{scenario}: {link} out"
        );
        assert_eq!(
            count(&m, &format!("/links/{link}/in")),
            frames(&report, link, "inbound"),
            "{scenario}: {link} in"
        );
    }
    assert_eq!(count(&m, "/report"), 1);

    // Log times on the sim clock, never going back; the report last, at the end of the run.
    let sim_ns = (report["sim_time_s"].as_f64().unwrap() * 1e9).round() as u64;
    assert_eq!(m.times.first().map(|t| t.1), Some(0));
    for pair in m.times.windows(2) {
        assert!(pair[0].1 <= pair[1].1, "{scenario}: time goes back from {:?} to {:?}", pair[0], pair[1]);
    }
    assert_eq!(m.times.last(), Some(&("/report".to_string(), sim_ns)));
    // The report message carries report.json (the wall time in it aside).
    let text = String::from_utf8_lossy(&m.last_report);
    assert!(text.contains(report["link_log_sha256"].as_str().unwrap()));
    (m, report)
}

#[test]
fn issue_13_mcap_of_a_run_has_every_channel_and_the_report_counts() {
    let dir = TempDir::new("explobot-fox-default");
    let (m, report) = check_run("scenarios/default.ron", &dir);
    assert_eq!(report["passed"], true);
    // The map grew cell by cell, and Carto and Cute had things to say.
    assert!(count(&m, "/cute/map") > 20, "{}", count(&m, "/cute/map"));
    // Carto's grid grew as the robot went (a 360 s run: one every 10 s while it changed).
    assert!(count(&m, "/carto/grid") >= 20, "{}", count(&m, "/carto/grid"));
    assert!(count(&m, "/log") > 0);

    // `explobot replay links.rec --mcap` writes the same channels and counts (here compressed).
    let replayed = dir.0.join("replay.mcap");
    let rec = dir.0.join("recorded/links.rec");
    let (code, out) =
        explobot_code(&["replay", rec.to_str().unwrap(), "--mcap", replayed.to_str().unwrap(), "--mcap-lz4"]);
    assert!(code == 0 && out.contains("identical"), "{out}");
    let r = read_mcap(&replayed);
    let counts = |m: &Mcap| m.channels.iter().map(|(t, c)| (t.clone(), c.2)).collect::<Vec<_>>();
    assert_eq!(counts(&r), counts(&m));
    let size = |f: &str| std::fs::metadata(dir.0.join(f)).unwrap().len();
    assert!(size("replay.mcap") * 2 < size("run.mcap"), "lz4 should at least halve the file");
}

#[test]
fn issue_13_mcap_counts_hold_with_link_errors_and_a_reconnect() {
    // lossy-motor: corrupted motor bytes, so Carto rejects frames; reconnect: a second connection.
    for scenario in ["scenarios/lossy-motor.ron", "scenarios/reconnect.ron"] {
        let name = Path::new(scenario).file_stem().unwrap().to_str().unwrap();
        let dir = TempDir::new(&format!("explobot-fox-{name}"));
        let (_, report) = check_run(scenario, &dir);
        if scenario.contains("lossy") {
            let motor = report["links"].as_array().unwrap().iter().find(|l| l["name"] == "motor").unwrap();
            assert!(motor["inbound"]["errors"].as_u64().unwrap() > 0, "the scenario should corrupt frames");
        } else {
            assert!(report["reconnects"].as_u64().unwrap() >= 1);
        }
    }
}

#[test]
fn issue_13_sweep_writes_an_mcap_for_each_run_that_fails() {
    // furnished fails with seed 15 (a touch, docs/results/scenarios-240/summary.md) and passes
    // with seed 2: one file, for run 1 (seed 15).
    let dir = TempDir::new("explobot-fox-sweep");
    let out = dir.0.join("sweep");
    let scenario = "scenarios/furnished.ron";
    let args = ["sweep", scenario, "--seeds", "2,15", "--jobs", "2", "--quiet", "--mcap", "--out"];
    let (code, stdout) = explobot_code(&[&args[..], &[out.to_str().unwrap()]].concat());
    assert_eq!(code, 1, "{stdout}");
    assert!(stdout.contains("wrote 1 MCAP file"), "{stdout}");
    let files: Vec<_> =
        std::fs::read_dir(out.join("mcap")).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(files, ["0001-furnished-seed15.mcap"]);
    // The file is the failed run again: its report has the hash the sweep recorded.
    let results = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    let failed: Value = serde_json::from_str(results.lines().nth(1).unwrap()).unwrap();
    assert_eq!(failed["verdict"], "fail");
    let m = read_mcap(&out.join("mcap").join(&files[0]));
    assert_eq!(m.channels.len(), CHANNELS.len());
    let text = String::from_utf8_lossy(&m.last_report);
    assert!(text.contains(failed["link_log_sha256"].as_str().unwrap()));
    assert_eq!(count(&m, "/robot/pose"), 1 + failed["steps"].as_u64().unwrap().div_ceil(POSE_EVERY));
}

#[test]
fn issue_13_the_shipped_layout_names_only_channels_a_run_writes() {
    let text = std::fs::read_to_string(workspace_root().join("docs/foxglove-layout.json")).unwrap();
    let layout: Value = serde_json::from_str(&text).unwrap();
    let panels = layout["configById"].as_object().unwrap();
    // The 3D view, the sonar plot and the log, side by side.
    for kind in ["3D!", "Plot!", "RosOut!"] {
        assert!(panels.keys().any(|k| k.starts_with(kind)), "no {kind} panel");
    }
    let known = |topic: &str| CHANNELS.iter().any(|(t, _)| *t == topic);
    let mut named = Vec::new();
    for config in panels.values() {
        named.extend(config["topics"].as_object().into_iter().flat_map(|t| t.keys().cloned()));
        for path in config["paths"].as_array().into_iter().flatten() {
            named.push(path["value"].as_str().unwrap().split('.').next().unwrap().to_owned());
        }
        named.extend(config["topicToRender"].as_str().map(str::to_owned));
    }
    assert!(named.len() >= 8, "{named:?}");
    for topic in &named {
        assert!(known(topic), "the layout names {topic}, which no run writes");
    }
    // Every panel in the tree is configured, and every configured panel is in the tree.
    let tree = layout["layout"].to_string();
    for id in panels.keys() {
        assert!(tree.contains(&format!("\"{id}\"")), "{id} is not placed");
    }
}
