//! `explobot generate`: the example rooms in `scenarios/generated/` are exactly what the generator
//! writes today, and each passes the same loading and checks as `explobot check`.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};

use twin::setup::RunSetup;
use twin_roomgen::{RoomStyle, generate};

fn example(style: RoomStyle) -> PathBuf {
    Path::new("..").join(format!("scenarios/generated/{}-1.ron", style.name()))
}

#[test]
fn the_examples_are_the_generators_output_for_seed_1() {
    for style in RoomStyle::ALL {
        let path = example(style);
        let on_disk = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let now = generate(style, 1).unwrap().to_ron();
        assert!(
            on_disk == now,
            "{} differs from `explobot generate --style {} --seed 1`: regenerate it",
            path.display(),
            style.name()
        );
    }
}

#[test]
fn the_examples_pass_the_check_with_a_reachable_start() {
    for style in RoomStyle::ALL {
        let loaded = RunSetup::load(&example(style)).unwrap_or_else(|e| panic!("{e}"));
        let s = &loaded.scenario;
        let reachable = loaded
            .truth()
            .reachable_from((usize::from(s.start.row), usize::from(s.start.col)))
            .iter()
            .filter(|r| **r)
            .count();
        assert!(reachable >= 2, "{}: {reachable} reachable cells", style.name());
        assert_eq!(s.name, format!("gen-{}-1", style.name()));
    }
}

#[test]
fn the_command_line_writes_the_same_bytes_as_the_library() {
    let exe = std::env::current_exe().unwrap();
    let bin: PathBuf = exe.parent().and_then(Path::parent).unwrap().join("explobot");
    assert!(bin.exists(), "{} missing: `cargo test --workspace` builds it", bin.display());
    let out = std::process::Command::new(&bin)
        .args(["generate", "--style", "warehouse", "--seed", "42"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(String::from_utf8(out.stdout).unwrap(), generate(RoomStyle::Warehouse, 42).unwrap().to_ron());
    let file = std::env::temp_dir().join(format!("explobot-generate-{}.ron", std::process::id()));
    let status = std::process::Command::new(&bin)
        .args(["generate", "--style", "irregular", "--seed", "7", "--out"])
        .arg(&file)
        .status()
        .unwrap();
    assert!(status.success());
    assert_eq!(std::fs::read_to_string(&file).unwrap(), generate(RoomStyle::Irregular, 7).unwrap().to_ron());
    std::fs::remove_file(&file).unwrap();
    let out = std::process::Command::new(&bin)
        .args(["generate", "--style", "castle", "--seed", "1"])
        .output()
        .unwrap();
    assert!(!out.status.success());
}
