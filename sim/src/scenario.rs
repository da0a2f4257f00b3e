//! Scenarios: a room, a robot, a mission script and what the run must achieve, as RON data.
//!
//! Geometry is in metres in the **world frame**: `x` to the right (east), `y` up (north), angles
//! counter-clockwise from `+x`. The planning grid covers the room's bounding box: `cell` metres a
//! side, row 0 at the top (largest `y`), column 0 at the left; whatever the bounding box leaves
//! over is split evenly as a margin on each side. A cell is free in the ground truth when its
//! square lies inside the room and touches no obstacle.
//!
//! Errors name the file, line and column:
//!
//! ```
//! let err = sim::scenario::Scenario::from_ron_str("Scenario(name: 1)", "bad.ron").unwrap_err();
//! assert!(err.to_string().starts_with("bad.ron:1:"));
//! ```

use std::fmt;
use std::path::{Path, PathBuf};

use robot_model::pose::Pose2;
use robot_model::profile::RobotProfile;
use serde::{Deserialize, Serialize};

/// The built-in default room (`explobot run` with no argument).
pub const DEFAULT_SCENARIO: &str = include_str!("../../scenarios/default.ron");

/// A compass heading on the grid, written by name in scenario files (`heading: East`).
pub use robot_model::grid::Heading;

/// A static obstacle in the room.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Obstacle {
    /// A rectangle: centre, full size (width along x, height along y), rotation in degrees.
    Box {
        /// Centre, metres.
        center: (f32, f32),
        /// Full width and height, metres.
        size: (f32, f32),
        /// Rotation counter-clockwise, degrees.
        #[serde(default)]
        angle_deg: f32,
    },
    /// A disc (a table leg, a bin).
    Circle {
        /// Centre, metres.
        center: (f32, f32),
        /// Radius, metres.
        radius: f32,
    },
    /// A thin wall from one point to another.
    Segment {
        /// One end, metres.
        from: (f32, f32),
        /// The other end, metres.
        to: (f32, f32),
    },
    /// A convex polygon (its convex hull is used).
    Polygon {
        /// Vertices, metres.
        points: Vec<(f32, f32)>,
    },
}

/// Where the robot starts: a grid cell and a heading.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Start {
    /// Row of the start cell.
    pub row: u8,
    /// Column of the start cell.
    pub col: u8,
    /// Initial heading.
    pub heading: Heading,
}

/// Physics settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PhysicsSettings {
    /// Fixed physics step, milliseconds.
    pub step_ms: f32,
    /// Hard limit on simulated time, seconds: the run stops there whatever the mission says.
    pub max_sim_s: f32,
}

impl Default for PhysicsSettings {
    fn default() -> Self {
        PhysicsSettings { step_ms: 5.0, max_sim_s: 1800.0 }
    }
}

/// Overrides of the robot profile's noise and friction, for "noisy" scenarios.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NoiseSettings {
    /// Sonar noise standard deviation, cm.
    pub sonar_sigma_cm: Option<f32>,
    /// IMU heading noise standard deviation, degrees.
    pub imu_sigma_deg: Option<f32>,
    /// IMU heading drift, degrees per minute.
    pub imu_drift_deg_per_min: Option<f32>,
    /// Wheel–floor friction coefficient (lower = more wheel slip).
    pub friction: Option<f32>,
}

/// Faults applied to one link for the whole run.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LinkFaults {
    /// Probability that a byte gets one bit flipped.
    pub corrupt_rate: f64,
    /// Probability that a byte is lost.
    pub drop_rate: f64,
    /// Extra one-way latency, milliseconds.
    pub latency_ms: f32,
}

/// Per-link fault settings.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LinkSettings {
    /// Carto ⇄ motor board.
    pub motor: LinkFaults,
    /// Carto ⇄ sensor board.
    pub sensor: LinkFaults,
    /// Cute ⇄ Carto.
    pub gui: LinkFaults,
}

/// Which link a timed fault hits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum LinkName {
    /// Carto ⇄ motor board.
    Motor,
    /// Carto ⇄ sensor board.
    Sensor,
    /// Cute ⇄ Carto (the TCP link).
    Gui,
}

/// A fault that happens at a given time, independent of the mission script.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Fault {
    /// The Cute ⇄ Carto connection drops at `at_s`; Cute is expected to reconnect by itself.
    GuiDisconnect {
        /// When, seconds of sim time.
        at_s: f32,
    },
}

/// One step of the mission script, executed in order by the scenario's operator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Step {
    /// Press "Cartography" in Cute.
    StartCartography,
    /// Wait until Cute says the map is complete (or the run's time limit).
    WaitUntilMapped,
    /// Click a cell: send the robot to (row, column).
    GoTo(u8, u8),
    /// Wait until the robot is idle (trajectory finished, stopped or failed).
    WaitUntilIdle,
    /// Press "Stop".
    Stop,
    /// Press "Reset map".
    ResetMap,
    /// Let this many seconds of sim time pass.
    Wait(f32),
}

/// What the run must achieve; each present field is checked and reported.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Expectations {
    /// Minimum fraction (0–1) of reachable cells that Cute's map shows as free.
    pub coverage_min: Option<f64>,
    /// Minimum fraction (0–1) of the cells Cute has classified that agree with the true room.
    pub map_accuracy_min: Option<f64>,
    /// Maximum number of collisions between the robot and anything.
    pub collisions_max: Option<u32>,
    /// The mission must end within this many seconds of sim time.
    pub finish_within_s: Option<f64>,
    /// The robot's final cell (row, column).
    pub reached: Option<(u8, u8)>,
    /// Largest distance, metres, between the true robot centre and the centre of the cell Cute
    /// believes it is in, at the end of each move ([`crate::localisation`]).
    #[serde(default)]
    pub position_error_max_m: Option<f64>,
    /// Largest angle, degrees, between the true heading and Cute's believed heading, at the end
    /// of each move.
    #[serde(default)]
    pub heading_error_max_deg: Option<f64>,
    /// `Some(true)`: at the end, the cell Cute believes the robot is in is the true one.
    #[serde(default)]
    pub believed_cell_true: Option<bool>,
}

/// A complete scenario file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Short name; also the output folder `runs/NAME`.
    pub name: String,
    /// One or two sentences on what the scenario tests.
    #[serde(default)]
    pub description: String,
    /// Robot profile: a path relative to the scenario file, or `None` for the built-in default.
    #[serde(default)]
    pub robot: Option<String>,
    /// Seed of every random process in the run (noise, faults).
    #[serde(default)]
    pub seed: u64,
    /// Grid cell size, metres (default: the profile's).
    #[serde(default)]
    pub cell: Option<f32>,
    /// The outer walls: a simple polygon, metres.
    pub room: Vec<(f32, f32)>,
    /// Obstacles inside the room.
    #[serde(default)]
    pub obstacles: Vec<Obstacle>,
    /// Start cell and heading.
    pub start: Start,
    /// Physics settings.
    #[serde(default)]
    pub physics: PhysicsSettings,
    /// Noise and friction overrides.
    #[serde(default)]
    pub noise: NoiseSettings,
    /// Faults on each link for the whole run.
    #[serde(default)]
    pub links: LinkSettings,
    /// Faults at given times.
    #[serde(default)]
    pub faults: Vec<Fault>,
    /// The operator's script.
    #[serde(default)]
    pub mission: Vec<Step>,
    /// What the run must achieve.
    #[serde(default)]
    pub expect: Expectations,
}

/// A scenario that could not be loaded: where and why.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioError {
    /// The file (or label) the text came from.
    pub file: String,
    /// 1-based line, when known.
    pub line: usize,
    /// 1-based column, when known.
    pub column: usize,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}: {}", self.file, self.line, self.column, self.message)
    }
}

impl std::error::Error for ScenarioError {}

impl ScenarioError {
    fn whole_file(file: &str, message: impl Into<String>) -> Self {
        ScenarioError { file: file.to_string(), line: 1, column: 1, message: message.into() }
    }
}

/// A scenario with its robot profile resolved, ready to run.
#[derive(Debug, Clone)]
pub struct LoadedScenario {
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
}

impl Scenario {
    /// Parses and validates a scenario; `file` is used in error messages.
    pub fn from_ron_str(text: &str, file: &str) -> Result<Scenario, ScenarioError> {
        let scenario: Scenario = ron::from_str(text).map_err(|e| ScenarioError {
            file: file.to_string(),
            line: e.span.start.line,
            column: e.span.start.col,
            message: e.code.to_string(),
        })?;
        scenario.validate().map_err(|message| {
            let (line, column) = locate(text, &message.anchor);
            ScenarioError { file: file.to_string(), line, column, message: message.text }
        })?;
        Ok(scenario)
    }

    /// The cell size to use with `profile`.
    pub fn cell_size(&self, profile: &RobotProfile) -> f32 {
        self.cell.unwrap_or(profile.grid_cell_m)
    }

    fn validate(&self) -> Result<(), Invalid> {
        if self.name.is_empty()
            || !self.name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
        {
            return Err(Invalid::at("name", "name must be non-empty ASCII letters, digits, '-' or '_'"));
        }
        if self.room.len() < 3 {
            return Err(Invalid::at("room", "room needs at least 3 corners"));
        }
        if self.room.iter().any(|&(x, y)| !x.is_finite() || !y.is_finite()) {
            return Err(Invalid::at("room", "room corners must be finite numbers"));
        }
        if polygon_area(&self.room).abs() < 1e-6 {
            return Err(Invalid::at("room", "room polygon has no area"));
        }
        if let Some(cell) = self.cell
            && !(cell.is_finite() && (0.05..=5.0).contains(&cell))
        {
            return Err(Invalid::at("cell", "cell must be between 0.05 and 5 metres"));
        }
        if !(self.physics.step_ms.is_finite() && (0.1..=50.0).contains(&self.physics.step_ms)) {
            return Err(Invalid::at("step_ms", "physics step_ms must be between 0.1 and 50"));
        }
        if !(self.physics.max_sim_s.is_finite() && self.physics.max_sim_s > 0.0) {
            return Err(Invalid::at("max_sim_s", "max_sim_s must be positive"));
        }
        for (i, o) in self.obstacles.iter().enumerate() {
            let positive = |v: f32| v.is_finite() && v > 0.0;
            let ok = match o {
                Obstacle::Box { center, size, angle_deg } => {
                    finite2(*center) && positive(size.0) && positive(size.1) && angle_deg.is_finite()
                }
                Obstacle::Circle { center, radius } => finite2(*center) && positive(*radius),
                Obstacle::Segment { from, to } => finite2(*from) && finite2(*to) && from != to,
                // A polygon whose points are all on a line has no convex hull.
                Obstacle::Polygon { points } => {
                    points.iter().all(|p| finite2(*p)) && crate::grid::obstacle_shape(o).is_some()
                }
            };
            if !ok {
                return Err(Invalid::at(
                    "obstacles",
                    &format!(
                        "obstacle {i} (counting from 0) has a non-finite, empty, negative or flat shape"
                    ),
                ));
            }
        }
        for fault in &self.faults {
            let Fault::GuiDisconnect { at_s } = fault;
            if !(at_s.is_finite() && *at_s >= 0.0) {
                return Err(Invalid::at("at_s", "fault times are zero or positive seconds"));
            }
        }
        if let Some(limit) = self.expect.finish_within_s
            && !(limit.is_finite() && limit > 0.0)
        {
            return Err(Invalid::at("finish_within_s", "finish_within_s must be positive"));
        }
        for links in [&self.links.motor, &self.links.sensor, &self.links.gui] {
            if !(0.0..=1.0).contains(&links.corrupt_rate) || !(0.0..=1.0).contains(&links.drop_rate) {
                return Err(Invalid::at("links", "link fault rates must be between 0 and 1"));
            }
            if !(links.latency_ms.is_finite() && links.latency_ms >= 0.0) {
                return Err(Invalid::at("latency_ms", "latency_ms must be zero or positive"));
            }
        }
        for step in &self.mission {
            if let Step::Wait(s) = step
                && !(s.is_finite() && *s >= 0.0)
            {
                return Err(Invalid::at("Wait(", "Wait takes a non-negative number of seconds"));
            }
        }
        for (name, v) in
            [("coverage_min", self.expect.coverage_min), ("map_accuracy_min", self.expect.map_accuracy_min)]
        {
            if let Some(v) = v
                && !(0.0..=1.0).contains(&v)
            {
                return Err(Invalid::at(name, "fractions are between 0 and 1"));
            }
        }
        Ok(())
    }
}

impl LoadedScenario {
    /// The robot's world pose at the start: the centre of its start cell, facing its start
    /// heading.
    pub fn start_pose(&self) -> Pose2 {
        let frame = crate::grid::room_frame(&self.scenario.room, self.scenario.cell_size(&self.profile));
        let start = self.scenario.start;
        let (x, y) = frame.cell_center(usize::from(start.row), usize::from(start.col));
        Pose2::new(x, y, start.heading.world_angle())
    }

    /// Loads a scenario file and the robot profile it names.
    pub fn load(path: &Path) -> Result<LoadedScenario, ScenarioError> {
        let label = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|e| ScenarioError::whole_file(&label, format!("cannot read scenario: {e}")))?;
        let scenario = Scenario::from_ron_str(&text, &label)?;
        let base = path.parent().unwrap_or(Path::new("."));
        Self::resolve(scenario, base, Some(path.to_path_buf()), &text, &label)
    }

    /// The built-in default room with the default robot.
    pub fn builtin_default() -> Result<LoadedScenario, ScenarioError> {
        let label = "<built-in default room>";
        let scenario = Scenario::from_ron_str(DEFAULT_SCENARIO, label)?;
        let mut scenario = scenario;
        scenario.robot = None;
        Self::resolve(scenario, Path::new("."), None, DEFAULT_SCENARIO, label)
    }

    /// Parses scenario text (robot paths resolved against `base`).
    pub fn from_ron_str(text: &str, label: &str, base: &Path) -> Result<LoadedScenario, ScenarioError> {
        let scenario = Scenario::from_ron_str(text, label)?;
        Self::resolve(scenario, base, None, text, label)
    }

    /// Resolves an already parsed scenario (robot paths relative to the working directory).
    pub fn from_scenario(scenario: Scenario) -> Result<LoadedScenario, ScenarioError> {
        let label = format!("<scenario {}>", scenario.name);
        let text =
            ron::ser::to_string_pretty(&scenario, ron::ser::PrettyConfig::default()).unwrap_or_default();
        Self::resolve(scenario, Path::new("."), None, &text, &label)
    }

    fn resolve(
        scenario: Scenario,
        base: &Path,
        path: Option<PathBuf>,
        text: &str,
        label: &str,
    ) -> Result<LoadedScenario, ScenarioError> {
        let mut profile = match &scenario.robot {
            None => RobotProfile::default(),
            Some(rel) => {
                let p = base.join(rel);
                RobotProfile::load(&p).map_err(|e| {
                    let (line, column) = locate(text, "robot");
                    ScenarioError {
                        file: label.to_string(),
                        line,
                        column,
                        message: format!("robot profile: {e}"),
                    }
                })?
            }
        };
        let at = |key: &str, message: String| {
            let (line, column) = locate(text, key);
            ScenarioError { file: label.to_string(), line, column, message }
        };
        apply_noise(&mut profile, &scenario.noise);
        // The overrides must leave a valid robot (a negative friction would break the physics).
        profile.validate().map_err(|e| at("noise", format!("noise overrides: {e}")))?;
        let cell = scenario.cell_size(&profile);
        let frame = crate::grid::room_frame(&scenario.room, cell);
        let (width, height) = crate::grid::room_extent(&scenario.room);
        let max = crate::grid::MAX_CELLS as f32 * cell;
        if width > max || height > max {
            return Err(at(
                "room",
                format!(
                    "room is {width:.2} m x {height:.2} m: at most {} cells of {cell} m a side fit the link protocol's one-byte coordinates",
                    crate::grid::MAX_CELLS
                ),
            ));
        }
        if frame.rows == 0 || frame.cols == 0 {
            return Err(at("room", format!("room is smaller than one {cell} m cell")));
        }
        let on_grid = |(row, col): (u8, u8)| usize::from(row) < frame.rows && usize::from(col) < frame.cols;
        for step in &scenario.mission {
            if let Step::GoTo(row, col) = *step
                && !on_grid((row, col))
            {
                return Err(at(
                    "GoTo(",
                    format!("GoTo({row}, {col}) is off the {}x{} grid", frame.rows, frame.cols),
                ));
            }
        }
        if let Some(reached) = scenario.expect.reached
            && !on_grid(reached)
        {
            return Err(at(
                "reached",
                format!("reached {reached:?} is off the {}x{} grid", frame.rows, frame.cols),
            ));
        }
        let loaded =
            LoadedScenario { scenario, profile, path, text: text.to_string(), label: label.to_string() };
        // The start cell must be on the grid and free, or nothing can run.
        let grid = crate::grid::TruthGrid::build(&loaded.scenario, &loaded.profile);
        let start = loaded.scenario.start;
        if !grid.is_free(start.row as usize, start.col as usize) {
            return Err(at(
                "start",
                format!(
                    "start cell ({}, {}) is not a free cell of the {}x{} grid",
                    start.row, start.col, grid.rows, grid.cols
                ),
            ));
        }
        Ok(loaded)
    }
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

struct Invalid {
    anchor: String,
    text: String,
}

impl Invalid {
    fn at(anchor: &str, text: &str) -> Self {
        Invalid { anchor: anchor.to_string(), text: text.to_string() }
    }
}

/// Line and column (1-based) of the first place `key` is used as a field (`key:`) or, for a
/// key ending in `(`, as a call — outside string literals and comments, at a word boundary. 1:1
/// when it is not there.
fn locate(text: &str, key: &str) -> (usize, usize) {
    for (i, line) in text.lines().enumerate() {
        let bytes = line.as_bytes();
        let mut in_string = false;
        let mut j = 0;
        while j < bytes.len() {
            match bytes[j] {
                b'\\' if in_string => j += 1,
                b'"' => in_string = !in_string,
                b'/' if !in_string && bytes.get(j + 1) == Some(&b'/') => break,
                _ if !in_string && line.get(j..).is_some_and(|rest| rest.starts_with(key)) => {
                    let before_ok = j == 0 || !(bytes[j - 1].is_ascii_alphanumeric() || bytes[j - 1] == b'_');
                    let rest = line.get(j + key.len()..).unwrap_or("").trim_start();
                    if before_ok && (key.ends_with('(') || rest.starts_with(':')) {
                        return (i + 1, j + 1);
                    }
                }
                _ => {}
            }
            j += 1;
        }
    }
    (1, 1)
}

fn finite2(p: (f32, f32)) -> bool {
    p.0.is_finite() && p.1.is_finite()
}

/// Signed area of a polygon (positive when counter-clockwise).
pub fn polygon_area(points: &[(f32, f32)]) -> f32 {
    let n = points.len();
    let mut twice = 0.0;
    for i in 0..n {
        let (x0, y0) = points[i];
        let (x1, y1) = points[(i + 1) % n];
        twice += x0 * y1 - x1 * y0;
    }
    twice * 0.5
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_room_loads() {
        let loaded = LoadedScenario::builtin_default().unwrap();
        assert_eq!(loaded.scenario.name, "default");
        assert!(!loaded.scenario.mission.is_empty());
    }

    #[test]
    fn syntax_error_reports_line_and_column() {
        let text = "Scenario(\n  name: \"x\",\n  room: [(0.0, 0.0), (1.0, 0.0)\n";
        let err = Scenario::from_ron_str(text, "rooms/x.ron").unwrap_err();
        assert_eq!(err.file, "rooms/x.ron");
        assert!(err.line >= 3, "{err}");
    }

    #[test]
    fn unknown_field_is_named_with_its_position() {
        let text = "Scenario(\n  name: \"x\",\n  rooom: [],\n)";
        let err = Scenario::from_ron_str(text, "x.ron").unwrap_err();
        assert_eq!((err.line, err.column), (3, 3), "{err}");
        assert!(err.message.contains("rooom"), "{err}");
    }

    #[test]
    fn semantic_error_points_at_the_field() {
        let text = "Scenario(\n  name: \"x\",\n  room: [(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)],\n  start: (row: 0, col: 0, heading: East),\n)";
        let err = Scenario::from_ron_str(text, "x.ron").unwrap_err();
        assert_eq!(err.line, 3, "{err}");
        assert!(err.message.contains("no area"), "{err}");
    }

    fn rejects(body: &str) -> ScenarioError {
        let text = format!(
            "Scenario(\n  name: \"x\",\n  description: \"a room: start here\",\n  room: [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)],\n  start: (row: 0, col: 0, heading: East),\n{body}\n)"
        );
        LoadedScenario::from_ron_str(&text, "x.ron", Path::new(".")).unwrap_err()
    }

    #[test]
    fn bad_values_are_rejected_where_they_are_written() {
        // Line 6 is the first line of `body`; the description mentioning "start" and "room" is
        // not mistaken for the fields.
        let e = rejects("  noise: (friction: Some(-0.1)),");
        assert_eq!((e.line, e.column), (6, 3), "{e}");
        assert!(e.message.contains("friction"), "{e}");
        let e = rejects("  obstacles: [Polygon(points: [(0.1, 0.1), (0.2, 0.2), (0.3, 0.3)])],");
        assert_eq!(e.line, 6, "{e}");
        assert!(e.message.contains("obstacle 0"), "{e}");
        let e = rejects("  obstacles: [Circle(center: (0.5, 0.5), radius: inf)],");
        assert_eq!(e.line, 6, "{e}");
        let e = rejects("  mission: [StartCartography,\n    GoTo(5, 0)],");
        assert_eq!((e.line, e.column), (7, 5), "{e}");
        let e = rejects("  faults: [GuiDisconnect(at_s: -1.0)],");
        assert_eq!(e.line, 6, "{e}");
        let e = rejects("  expect: (reached: Some((9, 9))),");
        assert_eq!(e.line, 6, "{e}");
        let e = rejects("  cell: Some(0.001),");
        assert_eq!(e.line, 6, "{e}");
    }

    #[test]
    fn a_room_too_big_for_one_byte_coordinates_is_rejected() {
        let text = "Scenario(name: \"big\", room: [(0.0, 0.0), (100.0, 0.0), (100.0, 1.0), (0.0, 1.0)], start: (row: 0, col: 0, heading: East))";
        let e = LoadedScenario::from_ron_str(text, "big.ron", Path::new(".")).unwrap_err();
        assert!(e.message.contains("256"), "{e}");
    }

    #[test]
    fn start_cell_outside_the_room_is_rejected() {
        let text = "Scenario(\n  name: \"x\",\n  room: [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)],\n  start: (row: 9, col: 0, heading: East),\n)";
        let err = LoadedScenario::from_ron_str(text, "x.ron", Path::new(".")).unwrap_err();
        assert_eq!(err.line, 4, "{err}");
        assert!(err.message.contains("start cell"), "{err}");
    }
}
