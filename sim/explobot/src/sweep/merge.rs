//! `explobot sweep merge DIR… --out DIR`: shard folders into one sweep folder.
//!
//! Every folder's `sweep.json` must describe the same sweep, and together their `results.jsonl`
//! must hold every run exactly once. Lines are copied as they are (sorted by index), and
//! `summary.md` and `junit.xml` are computed from them as a one-machine sweep computes its own:
//! the merged folder is byte-identical to that sweep's, apart from the `wall` fields.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::SweepError;
use super::output::write_folder;
use super::plan::Manifest;
use super::record::RunRecord;

/// Arguments of `explobot sweep merge`.
#[derive(clap::Args, Debug, Clone)]
pub struct MergeArgs {
    /// Shard folders (each written by `explobot sweep --shard`).
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
}

fn read(path: &Path) -> Result<String, SweepError> {
    std::fs::read_to_string(path)
        .map_err(|e| SweepError::Io { path: path.display().to_string(), message: e.to_string() })
}

impl MergeArgs {
    /// Merges and writes the folder; exit code 1 when any run failed.
    pub fn run(&self) -> Result<ExitCode, SweepError> {
        let (manifest, lines) = merge(&self.dirs)?;
        let totals = write_folder(&self.out, &manifest, &lines)?;
        Ok(super::verdict(&self.out, totals))
    }
}

/// Reads shard folders and returns the sweep's manifest and every line, sorted by index.
pub fn merge(dirs: &[PathBuf]) -> Result<(Manifest, Vec<String>), SweepError> {
    let mut manifest: Option<(Manifest, &Path)> = None;
    let mut lines: BTreeMap<usize, (String, &Path)> = BTreeMap::new();
    for dir in dirs {
        let path = dir.join("sweep.json");
        let m: Manifest = serde_json::from_str(&read(&path)?)
            .map_err(|e| SweepError::Input(format!("{}: not a sweep manifest: {e}", path.display())))?;
        match &manifest {
            None => manifest = Some((m, dir)),
            Some((first, first_dir)) if *first != m => {
                return Err(SweepError::Input(format!(
                    "{} and {} hold different sweeps (rooms, scenario texts or seeds differ)",
                    first_dir.display(),
                    dir.display()
                )));
            }
            Some(_) => {}
        }
        let results = dir.join("results.jsonl");
        for (n, line) in read(&results)?.lines().enumerate().filter(|(_, l)| !l.trim().is_empty()) {
            let record = RunRecord::parse(line, &format!("{}:{}", results.display(), n + 1))?;
            if let Some((_, other)) = lines.insert(record.index, (line.to_string(), dir)) {
                return Err(SweepError::Input(format!(
                    "run {} is in both {} and {}",
                    record.index,
                    other.display(),
                    dir.display()
                )));
            }
        }
    }
    let Some((manifest, _)) = manifest else {
        return Err(SweepError::Input("no shard folders given".into()));
    };
    let missing: Vec<String> =
        (0..manifest.runs).filter(|i| !lines.contains_key(i)).map(|i| i.to_string()).collect();
    if !missing.is_empty() {
        let shown = missing.iter().take(10).cloned().collect::<Vec<_>>().join(", ");
        return Err(SweepError::Input(format!(
            "{} of {} runs are missing (runs {shown}{}): a shard folder is missing or did not finish",
            missing.len(),
            manifest.runs,
            if missing.len() > 10 { ", …" } else { "" }
        )));
    }
    if let Some(extra) = lines.keys().find(|&&i| i >= manifest.runs) {
        return Err(SweepError::Input(format!("run {extra} is beyond the sweep's {} runs", manifest.runs)));
    }
    Ok((manifest, lines.into_values().map(|(l, _)| l).collect()))
}
