//! A `results.jsonl` line read back: the fields the summary, junit.xml, merging and comparing use.

use serde::Deserialize;

use super::SweepError;
use super::exec::Verdict;
use super::plan::generated_room;
use twin::belief::BeliefReport;
use twin::report::FirstContact;
use twin::touches::TouchReport;
use twin::world::Unphysical;

/// The fields of a `results.jsonl` line that the summary and junit.xml use.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct RunRecord {
    /// Place in the run list.
    pub index: usize,
    /// Room id: path as given, or `gen:STYLE:SEED`.
    pub room: String,
    /// Scenario name.
    pub scenario: String,
    /// Run seed.
    pub seed: u64,
    /// Verdict.
    pub verdict: Verdict,
    /// Why a run did not pass.
    #[serde(default)]
    pub reason: Option<String>,
    /// Coverage of reachable cells (absent when the run produced no report).
    #[serde(default)]
    pub coverage: Option<f64>,
    /// Map accuracy.
    #[serde(default)]
    pub map_accuracy: Option<f64>,
    /// Collisions.
    #[serde(default)]
    pub collisions: Option<u32>,
    /// Each expectation's verdict.
    #[serde(default)]
    pub checks: Vec<CheckRecord>,
    /// The run's first contact, if any.
    #[serde(default)]
    pub first_contact: Option<FirstContact>,
    /// Whether and when the body moved faster than its wheels can drive it (absent in results
    /// of older binaries).
    #[serde(default)]
    pub unphysical: Option<Unphysical>,
    /// Moves Cute sent.
    #[serde(default)]
    pub moves: Option<u64>,
    /// The touches' figures (absent in results of older binaries).
    #[serde(default)]
    pub touches: Option<TouchReport>,
    /// Carto's belief against the truth (absent in results of older binaries).
    #[serde(default)]
    pub belief: Option<BeliefReport>,
    /// SHA-256 of every byte on every link: equal for runs with the same bytes.
    #[serde(default)]
    pub link_log_sha256: Option<String>,
}

/// One expectation of a run, as `report.json` has it.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct CheckRecord {
    /// Expectation name.
    pub name: String,
    /// What was asked for.
    pub expected: String,
    /// What the run achieved.
    pub actual: String,
    /// Whether it holds.
    pub pass: bool,
}

impl RunRecord {
    /// Parses one `results.jsonl` line; `origin` names it in errors.
    pub fn parse(line: &str, origin: &str) -> Result<RunRecord, SweepError> {
        serde_json::from_str(line)
            .map_err(|e| SweepError::Input(format!("{origin}: not a sweep result: {e}")))
    }

    pub(super) fn failed_checks(&self) -> usize {
        self.checks.iter().filter(|c| !c.pass).count()
    }

    pub(super) fn room_label(&self) -> String {
        match generated_room(&self.room) {
            Some((_, room_seed)) => format!("room {room_seed} seed {}", self.seed),
            None => format!("seed {}", self.seed),
        }
    }
}
