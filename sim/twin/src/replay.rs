//! `explobot replay`: rebuild a recorded run from its recording alone and say where a new run
//! of it first differs.
//!
//! Concept: a recording (`links.rec`, [`crate::record`]) carries the scenario text, the robot
//! profile that ran (overrides applied) and the seed. [`rebuild`] turns them back into a
//! [`RunSetup`] without reading the scenario's `robot` file, which may have changed or be
//! gone; the caller runs it and compares the link logs with
//! [`crate::record::first_divergence`].
//!
//! Invariant: the rebuilt scenario has the recorded profile, so its grid, ground truth and `dt`
//! are the ones the recorded run had.

use robot_model::profile::{ProfileError, RobotProfile};

use crate::record::{EndpointLog, Recording, first_divergence};
use crate::scenario::{Scenario, ScenarioError};
use crate::setup::RunSetup;

/// A recording whose run cannot be rebuilt.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The recorded scenario no longer loads.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The recorded profile no longer loads.
    #[error("the recording's robot profile: {0}")]
    Profile(#[from] ProfileError),
    /// A recording made on the robot (`carto --record`): bytes without a scenario to re-run.
    #[error("{label}: recorded by carto on the robot, with no scenario: it cannot be re-run")]
    NoScenario {
        /// The recording's label.
        label: String,
    },
}

/// The recorded run's scenario with the recorded profile.
pub fn rebuild(rec: &Recording) -> Result<RunSetup, ReplayError> {
    if rec.scenario_ron.trim().is_empty() {
        return Err(ReplayError::NoScenario { label: rec.scenario_label.clone() });
    }
    let scenario = Scenario::from_ron_str(&rec.scenario_ron, &rec.scenario_label)?;
    let profile = RobotProfile::from_ron_str(&rec.profile_ron, "<recorded profile>")?;
    let loaded = RunSetup::with_profile(scenario, profile, &rec.scenario_ron, &rec.scenario_label)?;
    Ok(loaded.with_oracle(rec.oracle))
}

/// Whether `replayed` matches the recording, and the line that says so (the endpoint count and
/// hash, or where the first difference is).
pub fn verdict(rec: &Recording, replayed: &[EndpointLog]) -> (bool, String) {
    match first_divergence(&rec.logs, replayed) {
        None => (true, format!("identical: {} endpoint logs, sha256 {}", rec.logs.len(), rec.link_hash())),
        Some(d) => (false, format!("DIVERGED at {d}")),
    }
}
