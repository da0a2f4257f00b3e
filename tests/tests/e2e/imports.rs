//! No import cycle between the files of any crate (issue 41).
//!
//! Each `.rs` file under a crate's `src/` is a node; a file that names another file's module
//! (`use crate::a::b`, `super::x`, `self::y`, or `use child::…` for a submodule it declares)
//! has an arrow to it. An arrow from a submodule to a module it sits in (`use super::Parent`)
//! does not count: a submodule is part of its parent. Test modules (`tests.rs`, and the
//! `#[cfg(test)] mod tests` block at a file's end) are left out. The arrows left must form no
//! cycle.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Module = Vec<String>;

/// The crates checked: every workspace crate that has a `src/`.
fn crate_dirs(root: &Path) -> Vec<PathBuf> {
    let mut dirs: Vec<PathBuf> = ["protocol", "robot-model", "transport", "carto", "cute", "tests"]
        .iter()
        .map(|d| root.join(d))
        .collect();
    let mut sim: Vec<PathBuf> = std::fs::read_dir(root.join("sim"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("src").is_dir())
        .collect();
    sim.sort();
    dirs.extend(sim);
    dirs
}

fn rs_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rs_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// `a/b.rs` and `a/b/mod.rs` are `a::b`; `lib.rs` and `main.rs` are the root.
fn module_of(rel: &Path) -> Module {
    let mut parts: Module = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    if let Some(last) = parts.pop() {
        let stem = last.trim_end_matches(".rs").to_string();
        if !matches!(stem.as_str(), "lib" | "main" | "mod") {
            parts.push(stem);
        }
    }
    parts
}

/// The file's code: no comment lines, no trailing test module.
fn code(text: &str) -> String {
    let text = text.split("#[cfg(test)]\nmod tests").next().unwrap_or("");
    text.lines().filter(|l| !l.trim_start().starts_with("//")).collect::<Vec<_>>().join("\n")
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The paths written at `at` (just past `prefix::`): one path, or a `{…}` group of them.
fn paths_at(text: &[char], mut at: usize, prefix: Module, out: &mut Vec<Module>) -> usize {
    let mut path = prefix;
    loop {
        if text.get(at) == Some(&'{') {
            at += 1;
            loop {
                while text.get(at).is_some_and(|c| c.is_whitespace() || *c == ',') {
                    at += 1;
                }
                match text.get(at) {
                    None => return at,
                    Some('}') => return at + 1,
                    _ => at = paths_at(text, at, path.clone(), out),
                }
                // skip `as name` and anything else up to the next item
                while text.get(at).is_some_and(|c| *c != ',' && *c != '}') {
                    at += 1;
                }
            }
        }
        let start = at;
        while text.get(at).is_some_and(|c| is_ident(*c)) {
            at += 1;
        }
        if at > start {
            path.push(text[start..at].iter().collect());
        }
        if text.get(at) == Some(&':') && text.get(at + 1) == Some(&':') && at > start {
            at += 2;
        } else {
            out.push(path);
            return at;
        }
    }
}

/// Every module path `code` names from `here` (unresolved).
fn named(code: &str, here: &Module, children: &BTreeSet<String>) -> Vec<Module> {
    let text: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    for at in 0..text.len() {
        if at > 0 && (is_ident(text[at - 1]) || text[at - 1] == ':') {
            continue;
        }
        let rest: String = text[at..text.len().min(at + 8)].iter().collect();
        let base = if rest.starts_with("crate::") {
            Some((Vec::new(), 7))
        } else if rest.starts_with("super::") {
            Some((here[..here.len().saturating_sub(1)].to_vec(), 7))
        } else if rest.starts_with("self::") {
            Some((here.clone(), 6))
        } else {
            None
        };
        if let Some((mut base, skip)) = base {
            let mut found = Vec::new();
            paths_at(&text, at + skip, Vec::new(), &mut found);
            for p in found {
                let mut p = p.as_slice();
                while p.first().is_some_and(|s| s == "super") {
                    base.pop();
                    p = &p[1..];
                }
                out.push(base.iter().cloned().chain(p.iter().cloned()).collect());
            }
        } else if rest.starts_with("use ") {
            // `use child::…` for a submodule declared here
            let name: String = text[at + 4..].iter().take_while(|c| is_ident(**c)).collect();
            if children.contains(&name) {
                out.push(here.iter().cloned().chain([name]).collect());
            }
        }
    }
    out
}

/// The cycles among `edges` (each as its modules, in order), by depth-first search.
fn cycles(edges: &BTreeMap<Module, BTreeSet<Module>>) -> Vec<Vec<Module>> {
    fn visit(
        m: &Module,
        edges: &BTreeMap<Module, BTreeSet<Module>>,
        state: &mut BTreeMap<Module, u8>,
        stack: &mut Vec<Module>,
        found: &mut Vec<Vec<Module>>,
    ) {
        state.insert(m.clone(), 1);
        stack.push(m.clone());
        for n in edges.get(m).into_iter().flatten() {
            match state.get(n) {
                Some(1) => {
                    let from = stack.iter().position(|s| s == n).unwrap_or(0);
                    found.push(stack[from..].to_vec());
                }
                Some(_) => {}
                None => visit(n, edges, state, stack, found),
            }
        }
        stack.pop();
        state.insert(m.clone(), 2);
    }
    let (mut state, mut stack, mut found) = (BTreeMap::new(), Vec::new(), Vec::new());
    for m in edges.keys() {
        if !state.contains_key(m) {
            visit(m, edges, &mut state, &mut stack, &mut found);
        }
    }
    found
}

/// The arrows between the files of the crate in `dir`.
fn arrows(dir: &Path) -> BTreeMap<Module, BTreeSet<Module>> {
    let src = dir.join("src");
    let mut files = Vec::new();
    rs_files(&src, &mut files);
    let modules: BTreeMap<Module, PathBuf> =
        files.iter().map(|f| (module_of(f.strip_prefix(&src).unwrap()), f.clone())).collect();
    let mut edges = BTreeMap::new();
    for (m, file) in &modules {
        let mut to = BTreeSet::new();
        if file.file_name().is_some_and(|n| n != "tests.rs") {
            let children: BTreeSet<String> = modules
                .keys()
                .filter(|k| k.len() == m.len() + 1 && k.starts_with(m))
                .map(|k| k[m.len()].clone())
                .collect();
            for p in named(&code(&std::fs::read_to_string(file).unwrap()), m, &children) {
                // the longest prefix that is a file
                let target = (1..=p.len()).rev().map(|k| p[..k].to_vec()).find(|k| modules.contains_key(k));
                if let Some(t) = target
                    && &t != m
                    && !m.starts_with(&t)
                {
                    to.insert(t);
                }
            }
        }
        edges.insert(m.clone(), to);
    }
    edges
}

#[test]
fn issue_41_no_import_cycle_between_files() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
    let mut report = Vec::new();
    let mut files = 0;
    for dir in crate_dirs(root) {
        let edges = arrows(&dir);
        files += edges.len();
        for c in cycles(&edges) {
            let names: Vec<String> =
                c.iter().map(|m| if m.is_empty() { "lib".into() } else { m.join("::") }).collect();
            report.push(format!("{}: {} -> {}", dir.display(), names.join(" -> "), names[0]));
        }
    }
    assert!(files > 100, "only {files} files found");
    assert!(report.is_empty(), "import cycles between files:\n{}", report.join("\n"));
}

/// The check sees a cycle when there is one, and not the arrow from a submodule to its parent.
#[test]
fn issue_41_the_cycle_check_finds_a_cycle() {
    let here = vec!["a".to_string()];
    let none = BTreeSet::new();
    let found = named("use crate::b::{X, c::Y};\nuse super::z;\nfn f() { self::d::g() }", &here, &none);
    let want: Vec<Module> = vec![
        vec!["b".into(), "X".into()],
        vec!["b".into(), "c".into(), "Y".into()],
        vec!["z".into()],
        vec!["a".into(), "d".into(), "g".into()],
    ];
    assert_eq!(found, want);
    let m = |s: &str| -> Module { s.split("::").map(String::from).collect() };
    let edges: BTreeMap<Module, BTreeSet<Module>> = [
        (m("a"), [m("b")].into_iter().collect()),
        (m("b"), [m("c")].into_iter().collect()),
        (m("c"), [m("a")].into_iter().collect()),
    ]
    .into_iter()
    .collect();
    assert_eq!(cycles(&edges), vec![vec![m("a"), m("b"), m("c")]]);
}
