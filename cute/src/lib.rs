#![doc = include_str!("../README.md")]

pub mod astar;
pub mod cartography;
pub mod gridsim;
#[cfg(feature = "window")]
pub mod gui;
pub mod map;
pub mod map_file;
pub mod notices;
pub mod runtime;
pub mod session;
pub mod trajectory;

pub use astar::{AStar, Grid, Path, TieBreak};
pub use cartography::{Cartographer, MoveResult};
pub use map::{CellValue, Map, MapError, TextProblem};
pub use map_file::{MapFileError, load_map};
pub use runtime::{CuteRuntime, Plain, Wrap};
pub use session::{Compat, Cute, CuteConfig, CuteError, CuteEvent, Status};
pub use trajectory::{PlanError, Planner, Trajectory};
