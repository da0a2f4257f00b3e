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
//! let err = twin::scenario::Scenario::from_ron_str(text, "bad.ron").unwrap_err();
//! assert!(err.to_string().starts_with("bad.ron:4:34: faults[1].at_s:"), "{err}");
//! ```
//!
//! This module is plain data and its checks; [`crate::setup::RunSetup`] adds the resolved robot
//! profile and computes once what every run reads: the grid frame, the ground truth and `dt`.

use rapier2d::parry::math::{Pose, Vector};
use rapier2d::parry::shape::{Ball, ConvexPolygon, Cuboid, Segment, Shape};
use robot_model::profile::RobotProfile;
use robot_model::time::Duration;
use serde::{Deserialize, Serialize};

use crate::grid::PlacedShape;

pub(crate) mod source;
mod values;

pub use source::ScenarioError;
use source::{Key, field};
pub use values::polygon_area;

/// The built-in default room (`explobot run` with no argument).
pub const DEFAULT_SCENARIO: &str = include_str!("../../../scenarios/default.ron");

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
