//! The sweep folder: `results.jsonl`, `summary.md`, `junit.xml` and `sweep.json`.
//!
//! `summary.md` and `junit.xml` are computed from the `results.jsonl` lines alone (parsed back,
//! [`super::summary`]), so a one-machine sweep and a merge of its shards, which hold the same
//! lines, write the same bytes. Neither file holds a wall-clock figure.

use std::path::{Path, PathBuf};

use super::SweepError;
use super::plan::Manifest;
use super::record::RunRecord;
use super::summary::{junit, summary};

/// What a sweep folder says: runs and passes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Totals {
    /// Runs in the folder.
    pub runs: usize,
    /// Runs that passed.
    pub passed: usize,
}

/// Writes the folder from `lines` (sorted by index, no newlines).
pub fn write_folder(out: &Path, manifest: &Manifest, lines: &[String]) -> Result<Totals, SweepError> {
    let records = lines
        .iter()
        .enumerate()
        .map(|(i, l)| RunRecord::parse(l, &format!("result {}", i + 1)))
        .collect::<Result<Vec<_>, _>>()?;
    let io = |path: &Path, e: std::io::Error| SweepError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    };
    std::fs::create_dir_all(out).map_err(|e| io(out, e))?;
    let mut jsonl = String::new();
    for l in lines {
        jsonl.push_str(l);
        jsonl.push('\n');
    }
    let manifest_text = serde_json::to_string_pretty(manifest).unwrap_or_default() + "\n";
    for (name, text) in [
        ("results.jsonl", jsonl),
        ("sweep.json", manifest_text),
        ("summary.md", summary(manifest, &records)),
        ("junit.xml", junit(&records)),
    ] {
        let path = out.join(name);
        std::fs::write(&path, text).map_err(|e| io(&path, e))?;
    }
    Ok(Totals { runs: records.len(), passed: records.iter().filter(|r| r.verdict.passed()).count() })
}

/// `1..10` for consecutive seeds, commas otherwise.
/// A `results.jsonl` line without its wall-clock figures (the `wall` object, always last).
pub fn without_wall(line: &str) -> &str {
    line.rfind(",\"wall\":").map_or(line, |at| &line[..at])
}

/// Why two sweep folders do not hold the same results ([`compare_folders`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FolderDiff {
    /// A file could not be read.
    #[error("{}: {message}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The system's reason.
        message: String,
    },
    /// `summary.md`, `junit.xml` or `sweep.json` differs.
    #[error("{name} differs between {} and {}", a.display(), b.display())]
    File {
        /// The file's name.
        name: &'static str,
        /// The first folder.
        a: PathBuf,
        /// The second folder.
        b: PathBuf,
    },
    /// `results.jsonl` has a different number of lines.
    #[error("results.jsonl: {a} lines against {b}")]
    LineCount {
        /// Lines in the first folder's file.
        a: usize,
        /// Lines in the second folder's file.
        b: usize,
    },
    /// A `results.jsonl` line differs outside its `wall` object.
    #[error("results.jsonl line {line} differs:\n{a}\n{b}")]
    Line {
        /// The line number, from 1.
        line: usize,
        /// The first folder's line.
        a: String,
        /// The second folder's line.
        b: String,
    },
}

/// Checks that two sweep folders hold the same results: `summary.md`, `junit.xml` and
/// `sweep.json` byte for byte, `results.jsonl` line for line apart from the `wall` objects.
/// The error names the first file and line that differ.
pub fn compare_folders(a: &Path, b: &Path) -> Result<(), FolderDiff> {
    let read = |dir: &Path, name: &str| {
        let path = dir.join(name);
        std::fs::read_to_string(&path).map_err(|e| FolderDiff::Read { path, message: e.to_string() })
    };
    for name in ["summary.md", "junit.xml", "sweep.json"] {
        if read(a, name)? != read(b, name)? {
            return Err(FolderDiff::File { name, a: a.to_path_buf(), b: b.to_path_buf() });
        }
    }
    let (la, lb) = (read(a, "results.jsonl")?, read(b, "results.jsonl")?);
    let (la, lb): (Vec<&str>, Vec<&str>) = (la.lines().collect(), lb.lines().collect());
    if la.len() != lb.len() {
        return Err(FolderDiff::LineCount { a: la.len(), b: lb.len() });
    }
    match la.iter().zip(&lb).position(|(x, y)| without_wall(x) != without_wall(y)) {
        Some(i) => Err(FolderDiff::Line { line: i + 1, a: la[i].to_string(), b: lb[i].to_string() }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_wall_object_is_cut_off() {
        assert_eq!(
            without_wall(r#"{"index":0,"reason":"x","wall":{"total_s":1.0}}"#),
            r#"{"index":0,"reason":"x""#
        );
    }
}
