//! A run's set-up: a [`Scenario`] with its robot profile resolved and checked against the grid,
//! and what every run reads from it computed once (the grid frame, the ground truth, `dt`), plus
//! what the run gives Carto beyond its sensors ([`Oracle`]).
//!
//! The scenario module is plain data; this one sits above it, the truth and the oracle, so the
//! arrows point one way: `setup` → `truth` → `world` → `scenario`.
//!
//! ```
//! let setup = twin::setup::RunSetup::builtin_default()?;
//! assert_eq!(setup.scenario.name, "default");
//! assert!(setup.truth().is_free(usize::from(setup.scenario.start.row), usize::from(setup.scenario.start.col)));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::{Path, PathBuf};

use robot_model::pose::Pose2;
use robot_model::profile::RobotProfile;
use robot_model::time::Duration;

use crate::grid::{GridFrame, MAX_CELLS, room_extent, room_frame};
use crate::oracle::Oracle;
use crate::scenario::source::{Key, field};
use crate::scenario::{DEFAULT_SCENARIO, NoiseSettings, Scenario, ScenarioError, Step};
use crate::truth::RobotTruth;

/// A scenario with its robot profile resolved, ready to run, and what its runs read from it
/// computed once.
///
/// *NOTE*: the cached grid and `dt` follow from `scenario` and `profile` as they were loaded;
/// build a new one (e.g. [`RunSetup::with_profile`]) rather than editing those fields.
#[derive(Debug, Clone)]
pub struct RunSetup {
    /// The scenario as written.
    pub scenario: Scenario,
    /// The robot profile with the scenario's overrides applied.
    pub profile: RobotProfile,
    /// Where the scenario came from (`None` for the built-in default).
    pub path: Option<PathBuf>,
    /// The scenario's text, as parsed (what a recording stores).
    pub text: String,
    /// How errors and recordings name the scenario (its path, or `<built-in default room>`).
    pub label: String,
    truth: RobotTruth,
    dt: Duration,
    oracle: Oracle,
}

impl RunSetup {
    /// Runs give Carto what `oracle` says beyond its sensors ([`crate::oracle`]): the room's
    /// surfaces beforehand (`--known-room`), or every point the sonar heard (`--known-echoes`).
    pub fn with_oracle(mut self, oracle: Oracle) -> RunSetup {
        self.oracle = oracle;
        self
    }

    /// What runs give Carto beyond its sensors ([`RunSetup::with_oracle`]).
    pub fn oracle(&self) -> Oracle {
        self.oracle
    }

    /// The grid's placement in the world.
    pub fn frame(&self) -> GridFrame {
        self.truth.frame
    }

    /// Which cells are free in the real room.
    pub fn truth(&self) -> &RobotTruth {
        &self.truth
    }

    /// The fixed physics step.
    pub fn dt(&self) -> Duration {
        self.dt
    }

    /// The robot's world pose at the start: the centre of its start cell, facing its start
    /// heading.
    pub fn start_pose(&self) -> Pose2 {
        let start = self.scenario.start;
        let (x, y) = self.frame().cell_center(usize::from(start.row), usize::from(start.col));
        Pose2::new(x, y, start.heading.world_angle())
    }

    /// `explobot check`'s line for the file at `path`: `ok` with the grid and how many cells moves
    /// connect to the start cell (the start cell included), or `FAIL` and the error.
    pub fn check_line(path: &Path) -> (bool, String) {
        match Self::load(path) {
            Ok(l) => {
                let start = (usize::from(l.scenario.start.row), usize::from(l.scenario.start.col));
                let reachable = l.truth.reachable_from(start).iter().filter(|r| **r).count();
                let (rows, cols) = (l.truth.rows, l.truth.cols);
                (true, format!("ok   {}: {rows}x{cols} grid, {reachable} reachable cells", path.display()))
            }
            Err(e) => (false, format!("FAIL {e}")),
        }
    }

    /// Loads `path`, or the built-in default room when there is none.
    pub fn load_or_default(path: Option<&Path>) -> Result<RunSetup, ScenarioError> {
        match path {
            Some(path) => Self::load(path),
            None => Self::builtin_default(),
        }
    }

    /// Loads a scenario file and the robot profile it names.
    pub fn load(path: &Path) -> Result<RunSetup, ScenarioError> {
        let label = path.display().to_string();
        let text = robot_model::files::read_text_bounded(path, robot_model::files::TEXT_FILE_LIMIT)
            .map_err(|e| ScenarioError::whole_file(&label, format!("cannot read scenario: {e}")))?;
        let scenario = Scenario::from_ron_str(&text, &label)?;
        let base = path.parent().unwrap_or(Path::new("."));
        Self::resolve(scenario, base, Some(path.to_path_buf()), &text, &label)
    }

    /// The built-in default room with the default robot.
    pub fn builtin_default() -> Result<RunSetup, ScenarioError> {
        let label = "<built-in default room>";
        let mut scenario = Scenario::from_ron_str(DEFAULT_SCENARIO, label)?;
        scenario.robot = None;
        Self::resolve(scenario, Path::new("."), None, DEFAULT_SCENARIO, label)
    }

    /// Parses scenario text (robot paths resolved against `base`).
    pub fn from_ron_str(text: &str, label: &str, base: &Path) -> Result<RunSetup, ScenarioError> {
        let scenario = Scenario::from_ron_str(text, label)?;
        Self::resolve(scenario, base, None, text, label)
    }

    /// Resolves an already parsed scenario (robot paths relative to the working directory).
    pub fn from_scenario(scenario: Scenario) -> Result<RunSetup, ScenarioError> {
        let label = format!("<scenario {}>", scenario.name);
        let text =
            ron::ser::to_string_pretty(&scenario, ron::ser::PrettyConfig::default()).unwrap_or_default();
        Self::resolve(scenario, Path::new("."), None, &text, &label)
    }

    /// A scenario run with a given robot profile, its overrides already applied (a recording's):
    /// no robot file is read. `text` and `label` are the scenario's, for errors.
    pub fn with_profile(
        scenario: Scenario,
        profile: RobotProfile,
        text: &str,
        label: &str,
    ) -> Result<RunSetup, ScenarioError> {
        Self::checked(scenario, profile, None, text, label)
    }

    fn resolve(
        scenario: Scenario,
        base: &Path,
        path: Option<PathBuf>,
        text: &str,
        label: &str,
    ) -> Result<RunSetup, ScenarioError> {
        let at = |path: &[Key], message: String| ScenarioError::at(label, text, path, message);
        let mut profile = match &scenario.robot {
            None => RobotProfile::default(),
            Some(rel) => RobotProfile::load(base.join(rel))
                .map_err(|e| at(&[field("robot")], format!("robot profile: {e}")))?,
        };
        // The overrides must leave a valid robot (a negative friction would break the physics):
        // each is tried alone first, so the error points at the one that breaks it.
        for (name, one) in noise_overrides(&scenario.noise) {
            let mut alone = profile.clone();
            apply_noise(&mut alone, &one);
            alone
                .validate()
                .map_err(|e| at(&[field("noise"), field(name)], format!("noise overrides: {e}")))?;
        }
        apply_noise(&mut profile, &scenario.noise);
        profile.validate().map_err(|e| at(&[field("noise")], format!("noise overrides: {e}")))?;
        Self::checked(scenario, profile, path, text, label)
    }

    /// Checks the scenario against the grid its profile gives and computes what is cached.
    fn checked(
        scenario: Scenario,
        profile: RobotProfile,
        path: Option<PathBuf>,
        text: &str,
        label: &str,
    ) -> Result<RunSetup, ScenarioError> {
        let at = |path: &[Key], message: String| ScenarioError::at(label, text, path, message);
        // A scenario's cell size is the run's: Carto drives one of these per FORWARD, Cute's grid
        // and the truth are cut in them (before, only the grid used it and Carto kept the profile's).
        let mut profile = profile;
        profile.grid_cell_m = scenario.cell_size(&profile);
        let cell = profile.grid_cell_m;
        let frame = room_frame(&scenario.room, cell);
        let (width, height) = room_extent(&scenario.room);
        let max = MAX_CELLS as f32 * cell;
        if width > max || height > max {
            return Err(at(
                &[field("room")],
                format!(
                    "room is {width:.2} m x {height:.2} m: at most {MAX_CELLS} cells of {cell} m a side fit the link protocol's one-byte coordinates"
                ),
            ));
        }
        if frame.rows == 0 || frame.cols == 0 {
            return Err(at(&[field("room")], format!("room is smaller than one {cell} m cell")));
        }
        let on_grid = |(row, col): (u8, u8)| usize::from(row) < frame.rows && usize::from(col) < frame.cols;
        for (i, step) in scenario.mission.iter().enumerate() {
            if let Step::GoTo(row, col) = *step
                && !on_grid((row, col))
            {
                return Err(at(
                    &[field("mission"), Key::Index(i)],
                    format!("GoTo({row}, {col}) is off the {}x{} grid", frame.rows, frame.cols),
                ));
            }
        }
        if let Some(reached) = scenario.expect.reached
            && !on_grid(reached)
        {
            return Err(at(
                &[field("expect"), field("reached")],
                format!("reached {reached:?} is off the {}x{} grid", frame.rows, frame.cols),
            ));
        }
        // The start cell must be on the grid and free, or nothing can run.
        let truth = RobotTruth::build(frame, &scenario.room, &scenario.obstacle_shapes(), &profile);
        let start = scenario.start;
        if !truth.is_free(start.row as usize, start.col as usize) {
            return Err(at(
                &[field("start")],
                format!(
                    "start cell ({}, {}) is not a free cell of the {}x{} grid",
                    start.row, start.col, truth.rows, truth.cols
                ),
            ));
        }
        let dt = scenario.dt();
        Ok(RunSetup {
            scenario,
            profile,
            path,
            text: text.to_string(),
            label: label.to_string(),
            truth,
            dt,
            oracle: Oracle::None,
        })
    }
}

/// Each override that is set, alone, with the name it has in the file.
fn noise_overrides(noise: &NoiseSettings) -> Vec<(&'static str, NoiseSettings)> {
    let none = NoiseSettings::default();
    let drift = noise.imu_drift_deg_per_min;
    [
        ("sonar_sigma_cm", NoiseSettings { sonar_sigma_cm: noise.sonar_sigma_cm, ..none.clone() }),
        ("imu_sigma_deg", NoiseSettings { imu_sigma_deg: noise.imu_sigma_deg, ..none.clone() }),
        ("imu_drift_deg_per_min", NoiseSettings { imu_drift_deg_per_min: drift, ..none.clone() }),
        ("friction", NoiseSettings { friction: noise.friction, ..none.clone() }),
    ]
    .into_iter()
    .filter(|(_, one)| *one != none)
    .collect()
}

fn apply_noise(profile: &mut RobotProfile, noise: &NoiseSettings) {
    if let Some(v) = noise.sonar_sigma_cm {
        profile.sonar.noise_sigma_cm = v;
    }
    if let Some(v) = noise.imu_sigma_deg {
        profile.imu.noise_sigma_deg = v;
    }
    if let Some(v) = noise.imu_drift_deg_per_min {
        profile.imu.drift_deg_per_min = v;
    }
    if let Some(v) = noise.friction {
        profile.wheels.friction_mu = v;
    }
}
