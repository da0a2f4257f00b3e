//! `explobot sweep`: the same runs give the same folder whatever `--jobs` or sharding, a
//! failing run gives exit code 1 and its re-run command, bad input gives exit code 2.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use explobot::sweep::output::compare_folders;

fn explobot() -> Command {
    let exe = std::env::current_exe().unwrap();
    let path: PathBuf = exe.parent().and_then(Path::parent).unwrap().join("explobot");
    assert!(path.exists(), "{} missing: cargo build --release -p explobot --bin explobot", path.display());
    let mut c = Command::new(path);
    c.current_dir(Path::new(".."));
    for var in ["EXPLOBOT_SHARD", "SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"] {
        c.env_remove(var);
    }
    c
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("explobot-sweep-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn sweep(args: &[&str], out: &Path) -> Output {
    explobot().arg("sweep").args(args).arg("--out").arg(out).output().unwrap()
}

const SMALL: [&str; 4] = ["scenarios/empty.ron", "scenarios/pocket.ron", "--seeds", "1..3"];

#[test]
fn jobs_and_shards_do_not_change_the_results() {
    let dir = temp("same");
    let one = sweep(&[&SMALL[..], &["--jobs", "1"]].concat(), &dir.join("j1"));
    assert_eq!(one.status.code(), Some(0), "{}", String::from_utf8_lossy(&one.stderr));
    let two = sweep(&[&SMALL[..], &["--jobs", "2"]].concat(), &dir.join("j2"));
    assert_eq!(two.status.code(), Some(0));
    compare_folders(&dir.join("j1"), &dir.join("j2")).unwrap();
    let results = std::fs::read_to_string(dir.join("j1/results.jsonl")).unwrap();
    assert_eq!(results.lines().count(), 6);
    assert!(
        results.lines().all(|l| l.contains("\"verdict\":\"pass\"") && l.contains("\"link_log_sha256\":\""))
    );

    // Three shards, each a different way: --shard K/N, a CI matrix, a Slurm array (ids 5..=7).
    let s1 = sweep(&[&SMALL[..], &["--shard", "1/3"]].concat(), &dir.join("s1"));
    let s2 = explobot()
        .env("EXPLOBOT_SHARD", "2/3")
        .args(["sweep", "--shard", "auto", "--out"])
        .arg(dir.join("s2"))
        .args(SMALL)
        .output()
        .unwrap();
    let s3 = explobot()
        .envs([("SLURM_ARRAY_TASK_ID", "7"), ("SLURM_ARRAY_TASK_MIN", "5"), ("SLURM_ARRAY_TASK_COUNT", "3")])
        .args(["sweep", "--shard", "auto", "--out"])
        .arg(dir.join("s3"))
        .args(SMALL)
        .output()
        .unwrap();
    for s in [&s1, &s2, &s3] {
        assert_eq!(s.status.code(), Some(0), "{}", String::from_utf8_lossy(&s.stderr));
    }
    assert_eq!(std::fs::read_to_string(dir.join("s3/results.jsonl")).unwrap().lines().count(), 2);
    let merged = explobot()
        .args(["sweep", "merge"])
        .args([dir.join("s3"), dir.join("s1"), dir.join("s2")])
        .arg("--out")
        .arg(dir.join("merged"))
        .output()
        .unwrap();
    assert_eq!(merged.status.code(), Some(0), "{}", String::from_utf8_lossy(&merged.stderr));
    compare_folders(&dir.join("j1"), &dir.join("merged")).unwrap();

    // A missing shard is bad input, not a smaller sweep.
    let partial = explobot()
        .args(["sweep", "merge"])
        .args([dir.join("s1"), dir.join("s2")])
        .arg("--out")
        .arg(dir.join("p"))
        .output()
        .unwrap();
    assert_eq!(partial.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&partial.stderr).contains("2 of 6 runs are missing"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `scenarios/empty.ron`'s text with its robot profile named by an absolute path, so a copy runs
/// from any folder.
fn empty_room_anywhere() -> String {
    let scenarios = std::fs::canonicalize("../scenarios").unwrap();
    let text = std::fs::read_to_string(scenarios.join("empty.ron")).unwrap();
    let robot = scenarios.join("robots/mecanum-4wd.ron").display().to_string();
    let text = text.replace("\"robots/mecanum-4wd.ron\"", &format!("{robot:?}"));
    assert!(text.contains(&robot));
    text
}

/// empty.ron's finish limit, and one no run can meet.
const HURRIED: (&str, &str) = ("finish_within_s: Some(600.0)", "finish_within_s: Some(5.0)");

#[test]
fn a_failing_run_exits_1_and_names_its_rerun_command() {
    let dir = temp("fail");
    // empty.ron with a finish limit no run can meet.
    let text = empty_room_anywhere();
    let text = text.replace(HURRIED.0, HURRIED.1);
    assert!(text.contains("Some(5.0)"));
    let file = dir.join("hurried.ron");
    std::fs::write(&file, text).unwrap();
    let out =
        sweep(&[file.to_str().unwrap(), "scenarios/empty.ron", "--seeds", "2", "--quiet"], &dir.join("out"));
    assert_eq!(out.status.code(), Some(1), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stdout).contains("1 of 2 runs pass"));
    let summary = std::fs::read_to_string(dir.join("out/summary.md")).unwrap();
    assert!(summary.contains(&format!("explobot run {} --seed 2", file.display())), "{summary}");
    assert!(summary.contains("finish_within_s expected <= 5.0 s"), "{summary}");
    let junit = std::fs::read_to_string(dir.join("out/junit.xml")).unwrap();
    assert!(junit.contains("tests=\"2\" failures=\"1\" errors=\"0\""), "{junit}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `sweep compare` on two small sweeps of the same room file, the second with a finish limit no
/// run can meet: every run flips pass → fail, the test of the flips is reported, the figures are
/// paired, and the link bytes are the same (an expectation changes no byte).
#[test]
fn sweep_compare_lists_a_known_flip_and_the_same_link_bytes() {
    let dir = temp("compare");
    let text = empty_room_anywhere();
    let file = dir.join("room.ron");
    let file_arg = file.to_str().unwrap();
    std::fs::write(&file, &text).unwrap();
    let old = sweep(&[file_arg, "--seeds", "1..2", "--quiet"], &dir.join("old"));
    assert_eq!(old.status.code(), Some(0), "{}", String::from_utf8_lossy(&old.stderr));
    std::fs::write(&file, text.replace(HURRIED.0, HURRIED.1)).unwrap();
    let new = sweep(&[file_arg, "--seeds", "1..2", "--quiet"], &dir.join("new"));
    assert_eq!(new.status.code(), Some(1));
    let summary = std::fs::read_to_string(dir.join("new/summary.md")).unwrap();
    assert!(summary.starts_with("# Sweep: 0 of 2 (0.0 %, Wilson 95 % 0.0–65.8 %) runs pass"), "{summary}");

    let out =
        explobot().args(["sweep", "compare"]).arg(dir.join("old")).arg(dir.join("new")).output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("paired by room and seed: 2 runs (0 only in old, 0 only in new)"), "{text}");
    assert!(text.contains("- old: 2 of 2 (100.0 %"), "{text}");
    assert!(
        text.contains("2 pass → fail, 0 fail → pass; McNemar's exact test p = 0.5000 (not significant"),
        "{text}"
    );
    assert!(
        text.contains(&format!("- {file_arg} seed 1: coverage 100.0% → 100.0%; finish_within_s")),
        "{text}"
    );
    assert!(text.contains("| hard collisions | 0 | 0 | +0 |"), "{text}");
    assert!(text.contains("2 of 2 paired runs with a link-log hash moved the same bytes"), "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_input_exits_2_with_a_clear_message() {
    let dir = temp("bad");
    let broken = dir.join("broken.ron");
    std::fs::write(&broken, "Scenario(\n  name: \"broken\",\n  room: [(0.0, 0.0), (1.0, 0.0)],\n)\n")
        .unwrap();
    let cases: Vec<(Vec<String>, String)> = vec![
        (vec!["scenarios/empty.ron".into(), "--seeds".into(), "5..1".into()], "A <= B".into()),
        (vec!["scenarios/empty.ron".into(), "--shard".into(), "3/2".into()], "1 <= K <= N".into()),
        (vec!["scenarios/empty.ron".into(), "--shard".into(), "auto".into()], "found no shard".into()),
        (vec!["--generate".into(), "castle:2".into()], "unknown style 'castle'".into()),
        (vec![], "nothing to run".into()),
        (vec![broken.display().to_string()], format!("{}:", broken.display())),
    ];
    for (args, expected) in cases {
        let out = explobot().arg("sweep").args(&args).arg("--out").arg(dir.join("out")).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(&expected), "{args:?}: {stderr}");
    }
    assert!(!dir.join("out").exists(), "bad input must not write a folder");
    std::fs::remove_dir_all(&dir).unwrap();
}
