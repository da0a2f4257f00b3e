//! The twin library's dependency tree holds no Bevy, clap, image or foxglove crate (issue 41):
//! `cargo tree -p twin -e normal`, as a user would check it.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::process::Command;

#[test]
fn the_twin_library_links_no_window_command_line_or_picture_crate() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let out = Command::new(env!("CARGO"))
        .args(["tree", "-p", "twin", "-e", "normal", "--prefix", "none", "--locked", "--offline"])
        .current_dir(root)
        .output()
        .expect("cargo runs");
    assert!(out.status.success(), "cargo tree failed: {}", String::from_utf8_lossy(&out.stderr));
    let tree = String::from_utf8_lossy(&out.stdout);
    assert!(tree.lines().any(|l| l.starts_with("rapier2d ")), "not the twin's tree:\n{tree}");
    let banned: Vec<&str> = tree
        .lines()
        .filter(|l| ["bevy", "clap", "image", "foxglove"].iter().any(|b| l.starts_with(b)))
        .collect();
    assert!(banned.is_empty(), "the twin links {banned:?}");
}
