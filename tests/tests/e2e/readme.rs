//! The README says only what is true: its status box is what `docs/results/update.sh` writes from
//! the files in `docs/results/`, its cheap shell commands run and exit as documented, and every
//! path it (or a document under `docs/`, the journal aside) names exists.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The subcommands cheap enough to run here (well under a second each).
const CHEAP: [&str; 5] = ["check", "decode", "encode", "generate", "truth"];

/// Top-level folders a path in the documents may start with.
const ROOTS: [&str; 11] = [
    "protocol/",
    "robot-model/",
    "transport/",
    "carto/",
    "cute/",
    "sim/",
    "tests/",
    "scenarios/",
    "docs/",
    "deploy/",
    ".ci/",
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf()
}

fn readme() -> String {
    std::fs::read_to_string(root().join("README.md")).unwrap()
}

/// The folder holding the built `explobot` (next to this test's folder, as in `cli.rs`).
fn bin_dir() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let dir = exe.parent().and_then(Path::parent).unwrap().to_path_buf();
    assert!(
        dir.join("explobot").exists(),
        "{} missing: cargo test --workspace builds it",
        dir.join("explobot").display()
    );
    dir
}

#[test]
fn the_readme_is_short() {
    let lines = readme().lines().count();
    assert!(lines <= 250, "README.md has {lines} lines; at most 250");
}

#[test]
fn the_status_box_is_what_update_sh_writes_from_docs_results() {
    let out = Command::new("bash")
        .arg("docs/results/update.sh")
        .arg("--check")
        .current_dir(root())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    // With no summary in docs/results/ the box must say so, not stay silent.
    let any_summary = std::fs::read_dir(root().join("docs/results"))
        .unwrap()
        .any(|e| e.unwrap().path().join("summary.md").is_file());
    let text = readme();
    let block =
        text.split("<!-- status:begin -->").nth(1).unwrap().split("<!-- status:end -->").next().unwrap();
    if any_summary {
        assert!(block.contains("docs/results/"), "{block}");
    } else {
        assert!(block.contains("No generated figures on this checkout yet"), "{block}");
    }
}

/// One cheap command of a ```sh block: the line, the exit code its comment documents (`exit N`,
/// else 0) and the output it promises (`→ TEXT`, if any).
struct Documented {
    line: String,
    command: String,
    exit: i32,
    prints: Option<String>,
}

fn cheap_commands(text: &str) -> Vec<Documented> {
    let mut found = Vec::new();
    let mut in_sh = false;
    for line in text.lines() {
        let trimmed = line.trim();
        if trimmed.starts_with("```") {
            in_sh = !in_sh && trimmed == "```sh";
            continue;
        }
        if !in_sh {
            continue;
        }
        let (command, comment) = match trimmed.find(" # ") {
            Some(i) => (trimmed[..i].trim(), trimmed[i + 3..].trim()),
            None => (trimmed, ""),
        };
        let mut words = command.split_whitespace();
        if words.next() != Some("explobot") || !words.next().is_some_and(|w| CHEAP.contains(&w)) {
            continue;
        }
        assert!(!command.contains("&&") && !command.contains('|'), "one command per line: {line}");
        let exit = comment
            .split("exit ")
            .nth(1)
            .and_then(|rest| rest.split(|c: char| !c.is_ascii_digit()).next())
            .and_then(|n| n.parse().ok())
            .unwrap_or(0);
        let prints = comment.split("→ ").nth(1).map(|s| s.trim().to_string());
        found.push(Documented { line: line.to_string(), command: command.to_string(), exit, prints });
    }
    found
}

#[test]
fn the_readmes_cheap_commands_run_and_exit_as_documented() {
    let commands = cheap_commands(&readme());
    for sub in CHEAP {
        assert!(
            commands.iter().any(|c| c.command.split_whitespace().nth(1) == Some(sub)),
            "the README shows no `explobot {sub}` command"
        );
    }
    let path = format!("{}:{}", bin_dir().display(), std::env::var("PATH").unwrap_or_default());
    for c in &commands {
        // Through bash, as a reader would type it: globs such as scenarios/*.ron expand.
        let out = Command::new("bash")
            .arg("-c")
            .arg(&c.command)
            .env("PATH", &path)
            .current_dir(root())
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(c.exit), "{}\nstdout:\n{stdout}\nstderr:\n{stderr}", c.line);
        if let Some(text) = &c.prints {
            assert!(stdout.contains(text.as_str()), "{}\nprints:\n{stdout}", c.line);
        }
        eprintln!("ok: {}", c.command);
    }
}

/// Relative link targets (`](target)`, from the document's folder) and code spans that look like
/// repository paths (from the repository's root), each with whether it is from the root.
fn mentioned_paths(text: &str) -> Vec<(String, bool)> {
    let mut paths = Vec::new();
    for (i, _) in text.match_indices("](") {
        let rest = &text[i + 2..];
        let Some(end) = rest.find(')') else { continue };
        let target = rest[..end].split('#').next().unwrap_or("");
        if !target.is_empty() && !target.contains("://") && !target.starts_with("mailto:") {
            paths.push((target.to_string(), false));
        }
    }
    for (k, span) in text.split('`').enumerate() {
        if k % 2 == 1 && !span.contains(char::is_whitespace) && ROOTS.iter().any(|r| span.starts_with(r)) {
            paths.push((span.trim_end_matches([',', '.', ':', ';']).to_string(), true));
        }
    }
    paths
}

/// Whether `path` exists under `base`; a glob or a placeholder (`*`, `<name>`, `{a,b}`, an
/// upper-case NAME) is checked up to the folder before it.
fn exists(base: &Path, path: &str) -> bool {
    let mut kept = base.to_path_buf();
    for part in path.split('/') {
        let placeholder = part.contains(['*', '<', '{'])
            || (part.len() > 1 && part.chars().all(|c| c.is_ascii_uppercase() || c == '_'));
        if placeholder {
            break;
        }
        kept.push(part);
    }
    kept.exists()
}

#[test]
fn every_path_the_readme_and_the_docs_name_exists() {
    let root = root();
    let mut documents = vec![root.join("README.md")];
    let mut folders = vec![root.join("docs")];
    while let Some(dir) = folders.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() && !path.ends_with("journal") {
                folders.push(path);
            } else if path.extension().is_some_and(|e| e == "md") {
                documents.push(path);
            }
        }
    }
    documents.sort();
    let mut missing = Vec::new();
    for doc in &documents {
        let text = std::fs::read_to_string(doc).unwrap();
        for (path, from_root) in mentioned_paths(&text) {
            let base = if from_root { root.clone() } else { doc.parent().unwrap().to_path_buf() };
            if exists(&base, &path) {
                continue;
            }
            missing.push(format!("{}: {path}", doc.strip_prefix(&root).unwrap().display()));
        }
    }
    assert!(missing.is_empty(), "paths that do not exist:\n{}", missing.join("\n"));
}
