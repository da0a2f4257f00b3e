//! Scenarios: a room, a robot, a mission script and what the run must achieve, as RON data.
//!
//! Geometry is in metres in the **world frame**: `x` to the right (east), `y` up (north), angles
//! counter-clockwise from `+x`. The planning grid covers the room's bounding box: `cell` metres a
//! side, row 0 at the top (largest `y`), column 0 at the left; whatever the bounding box leaves
//! over is split evenly as a margin on each side. A cell is free in the ground truth when its
//! square lies inside the room and touches no obstacle.
//!
//! Errors name the file, line and column of the value that is wrong, as ron's parser finds it
//! (`source`): a value that fails its own check (`values`: a negative radius, a fault time
//! below zero) is refused while serde reads it; a check that needs the robot profile or the grid
//! (a `GoTo` off the grid, a start cell that is not free) finds its value again by path. Either
//! way a key written twice is told apart:
//!
//! ```
//! let text = "Scenario(name: \"x\", room: [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0)],
//!     start: (row: 0, col: 0, heading: East),
//!     faults: [GuiDisconnect(at_s: 1.0),
//!              GuiDisconnect(at_s: -1.0)])";
//! let err = sim::scenario::Scenario::from_ron_str(text, "bad.ron").unwrap_err();
//! assert!(err.to_string().starts_with("bad.ron:4:34: faults[1].at_s:"), "{err}");
//! ```
//!
//! [`LoadedScenario`] adds the resolved robot profile and computes once what every user reads:
//! the grid frame, the ground truth ([`RobotTruth`]) and the step `dt`.

use std::path::{Path, PathBuf};

use rapier2d::parry::math::{Pose, Vector};
use rapier2d::parry::shape::{Ball, ConvexPolygon, Cuboid, Segment, Shape};
use robot_model::pose::Pose2;
use robot_model::profile::RobotProfile;
use robot_model::time::Duration;
use serde::{Deserialize, Serialize};

use crate::grid::{GridFrame, MAX_CELLS, PlacedShape, room_extent, room_frame};
use crate::oracle::Oracle;
use crate::truth::RobotTruth;

mod source;
mod values;

pub use source::ScenarioError;
use source::{Key, field};
pub use values::polygon_area;

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
        #[serde(deserialize_with = "values::point")]
        center: (f32, f32),
        /// Full width and height, metres.
        #[serde(deserialize_with = "values::size")]
        size: (f32, f32),
        /// Rotation counter-clockwise, degrees.
        #[serde(default, deserialize_with = "values::finite")]
        angle_deg: f32,
    },
    /// A disc (a table leg, a bin).
    Circle {
        /// Centre, metres.
        #[serde(deserialize_with = "values::point")]
        center: (f32, f32),
        /// Radius, metres.
        #[serde(deserialize_with = "values::length")]
        radius: f32,
    },
    /// A thin wall from one point to another (two different points).
    Segment {
        /// One end, metres.
        #[serde(deserialize_with = "values::point")]
        from: (f32, f32),
        /// The other end, metres.
        #[serde(deserialize_with = "values::point")]
        to: (f32, f32),
    },
    /// A convex polygon (its convex hull is used).
    Polygon {
        /// Vertices, metres.
        #[serde(deserialize_with = "values::convex_points")]
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
    #[serde(deserialize_with = "values::step_ms")]
    pub step_ms: f32,
    /// Hard limit on simulated time, seconds: the run stops there whatever the mission says.
    #[serde(deserialize_with = "values::positive_s")]
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
    #[serde(deserialize_with = "values::rate")]
    pub corrupt_rate: f64,
    /// Probability that a byte is lost.
    #[serde(deserialize_with = "values::rate")]
    pub drop_rate: f64,
    /// Extra one-way latency, milliseconds.
    #[serde(deserialize_with = "values::latency_ms")]
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
        #[serde(deserialize_with = "values::non_negative_s")]
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
    Wait(#[serde(deserialize_with = "values::non_negative_s")] f32),
}

/// What the run must achieve; each present field is checked and reported.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Expectations {
    /// Minimum fraction (0–1) of reachable cells that Cute's map shows as free.
    #[serde(deserialize_with = "values::fraction")]
    pub coverage_min: Option<f64>,
    /// Minimum fraction (0–1) of the cells Cute has classified that agree with the true room.
    #[serde(deserialize_with = "values::fraction")]
    pub map_accuracy_min: Option<f64>,
    /// Maximum number of collisions between the robot and anything: every touch, light or hard.
    pub collisions_max: Option<u32>,
    /// Maximum number of touches ([`crate::touches`]); the same count as `collisions_max`, named
    /// as the profile's pass criteria name it.
    #[serde(default)]
    pub touches_max: Option<u32>,
    /// Maximum number of hard collisions (began at 0.10 m/s or more, or pushed the body 2 cm or
    /// more from where its wheels drove it).
    #[serde(default)]
    pub hard_collisions_max: Option<u32>,
    /// Maximum touches per 100 moves Cute sent.
    #[serde(default)]
    pub touches_per_100_moves_max: Option<f64>,
    /// Largest distance, metres, between the true body centre and Carto's belief
    /// ([`crate::belief`]).
    #[serde(default)]
    pub belief_error_max_m: Option<f64>,
    /// Largest 95th percentile of that distance, metres.
    #[serde(default)]
    pub belief_error_p95_max_m: Option<f64>,
    /// Largest angle, degrees, between the true heading and Carto's believed heading.
    #[serde(default)]
    pub belief_heading_error_max_deg: Option<f64>,
    /// The mission must end within this many seconds of sim time.
    #[serde(deserialize_with = "values::optional_positive_s")]
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

impl Expectations {
    /// The expectations a generated room gets: the robot's pass criteria (its profile's
    /// `scoring.pass`) and the room's time limit.
    pub fn from_criteria(
        c: &robot_model::profile::PassCriteria,
        finish_within_s: Option<f64>,
    ) -> Expectations {
        Expectations {
            coverage_min: c.coverage_min,
            map_accuracy_min: c.map_accuracy_min,
            finish_within_s,
            believed_cell_true: c.believed_cell_true,
            touches_max: c.touches_max,
            hard_collisions_max: c.hard_collisions_max,
            touches_per_100_moves_max: c.touches_per_100_moves_max,
            belief_error_max_m: c.belief_error_max_m,
            belief_error_p95_max_m: c.belief_error_p95_max_m,
            belief_heading_error_max_deg: c.belief_heading_error_max_deg,
            ..Expectations::default()
        }
    }
}

/// A complete scenario file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Short name; also the output folder `runs/NAME`.
    #[serde(deserialize_with = "values::name")]
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
    #[serde(default, deserialize_with = "values::cell")]
    pub cell: Option<f32>,
    /// The outer walls: a simple polygon, metres.
    #[serde(deserialize_with = "values::room")]
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

/// A scenario with its robot profile resolved, ready to run, and what its runs read from it
/// computed once.
///
/// *NOTE*: the cached grid and `dt` follow from `scenario` and `profile` as they were loaded;
/// build a new one (e.g. [`LoadedScenario::with_profile`]) rather than editing those fields.
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
    truth: RobotTruth,
    dt: Duration,
    oracle: Oracle,
}

impl Scenario {
    /// Parses and validates a scenario; `file` is used in error messages.
    pub fn from_ron_str(text: &str, file: &str) -> Result<Scenario, ScenarioError> {
        let scenario: Scenario = source::parse(text, file)?;
        // Checks that need two values: a segment's ends, an obstacle against the room.
        let room = values::bounds(&scenario.room);
        for (i, o) in scenario.obstacles.iter().enumerate() {
            let path = [field("obstacles"), Key::Index(i)];
            if let Obstacle::Segment { from, to } = o
                && from == to
            {
                let message = format!("obstacles[{i}]: a segment needs two different ends");
                return Err(ScenarioError::at(file, text, &path, message));
            }
            let b = o.bounds();
            if b.0 > room.2 || b.2 < room.0 || b.1 > room.3 || b.3 < room.1 {
                let message = format!(
                    "obstacles[{i}]: lies outside the room (x {:.2}..{:.2}, y {:.2}..{:.2} m; the room spans x {:.2}..{:.2}, y {:.2}..{:.2} m)",
                    b.0, b.2, b.1, b.3, room.0, room.2, room.1, room.3
                );
                return Err(ScenarioError::at(file, text, &path, message));
            }
        }
        Ok(scenario)
    }

    /// The cell size to use with `profile`.
    pub fn cell_size(&self, profile: &RobotProfile) -> f32 {
        self.cell.unwrap_or(profile.grid_cell_m)
    }

    /// What the robot of `profile` can really do in this room (see [`RobotTruth`]), on the grid
    /// [`room_frame`] lays over it. [`LoadedScenario`] builds it once, after checking the grid.
    pub fn truth(&self, profile: &RobotProfile) -> RobotTruth {
        RobotTruth::build(
            room_frame(&self.room, self.cell_size(profile)),
            &self.room,
            &self.obstacle_shapes(),
            profile,
        )
    }

    /// The fixed physics step.
    pub fn dt(&self) -> Duration {
        Duration::from_secs_f64(f64::from(self.physics.step_ms) / 1000.0)
    }

    /// Every obstacle's collision shape and placement.
    pub fn obstacle_shapes(&self) -> Vec<PlacedShape> {
        self.obstacles.iter().filter_map(Obstacle::shape).collect()
    }
}

impl Obstacle {
    /// The collision shape and placement (`None` for a polygon with no hull, which parsing
    /// refuses).
    pub fn shape(&self) -> Option<PlacedShape> {
        match self {
            Obstacle::Box { center, size, angle_deg } => Some((
                Pose::new(Vector::new(center.0, center.1), angle_deg.to_radians()),
                Box::new(Cuboid::new(Vector::new(size.0 * 0.5, size.1 * 0.5))),
            )),
            Obstacle::Circle { center, radius } => {
                Some((Pose::from_translation(Vector::new(center.0, center.1)), Box::new(Ball::new(*radius))))
            }
            Obstacle::Segment { from, to } => Some((
                Pose::IDENTITY,
                Box::new(Segment::new(Vector::new(from.0, from.1), Vector::new(to.0, to.1))),
            )),
            Obstacle::Polygon { points } => {
                let pts: Vec<Vector> = points.iter().map(|&(x, y)| Vector::new(x, y)).collect();
                ConvexPolygon::from_convex_hull(&pts).map(|p| (Pose::IDENTITY, Box::new(p) as Box<dyn Shape>))
            }
        }
    }
}

impl LoadedScenario {
    /// Runs give Carto what `oracle` says beyond its sensors ([`crate::oracle`]): the room's
    /// surfaces beforehand (`--known-room`), or every point the sonar heard (`--known-echoes`).
    pub fn with_oracle(mut self, oracle: Oracle) -> LoadedScenario {
        self.oracle = oracle;
        self
    }

    /// What runs give Carto beyond its sensors ([`LoadedScenario::with_oracle`]).
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
    pub fn load_or_default(path: Option<&Path>) -> Result<LoadedScenario, ScenarioError> {
        match path {
            Some(path) => Self::load(path),
            None => Self::builtin_default(),
        }
    }

    /// Loads a scenario file and the robot profile it names.
    pub fn load(path: &Path) -> Result<LoadedScenario, ScenarioError> {
        let label = path.display().to_string();
        let text = robot_model::files::read_text_bounded(path, robot_model::files::TEXT_FILE_LIMIT)
            .map_err(|e| ScenarioError::whole_file(&label, format!("cannot read scenario: {e}")))?;
        let scenario = Scenario::from_ron_str(&text, &label)?;
        let base = path.parent().unwrap_or(Path::new("."));
        Self::resolve(scenario, base, Some(path.to_path_buf()), &text, &label)
    }

    /// The built-in default room with the default robot.
    pub fn builtin_default() -> Result<LoadedScenario, ScenarioError> {
        let label = "<built-in default room>";
        let mut scenario = Scenario::from_ron_str(DEFAULT_SCENARIO, label)?;
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

    /// A scenario run with a given robot profile, its overrides already applied (a recording's):
    /// no robot file is read. `text` and `label` are the scenario's, for errors.
    pub fn with_profile(
        scenario: Scenario,
        profile: RobotProfile,
        text: &str,
        label: &str,
    ) -> Result<LoadedScenario, ScenarioError> {
        Self::checked(scenario, profile, None, text, label)
    }

    fn resolve(
        scenario: Scenario,
        base: &Path,
        path: Option<PathBuf>,
        text: &str,
        label: &str,
    ) -> Result<LoadedScenario, ScenarioError> {
        let at = |path: &[Key], message: String| ScenarioError::at(label, text, path, message);
        let mut profile = match &scenario.robot {
            None => RobotProfile::default(),
            Some(rel) => RobotProfile::load(&base.join(rel))
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
    ) -> Result<LoadedScenario, ScenarioError> {
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
        Ok(LoadedScenario {
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
