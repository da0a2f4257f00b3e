//! The arguments of the subcommands whose code lives in the library crates (`twin`,
//! `twin-roomgen`, `twin-pictures`, `twin-app`): every `clap::Args` of the command line is in
//! this crate, and turns into the plain values those crates take.

use std::path::{Path, PathBuf};

use twin::counts::{ClearanceBound, TruthCounts, lattice_tour_bounds};
use twin::oracle::Oracle;
use twin::scenario::ScenarioError;
use twin::scored::ScoredSet;
use twin::setup::RunSetup;
use twin_app::app::{WindowError, WindowOutputs};
use twin_pictures::truthimg::truth_picture_ringing;
use twin_roomgen::{GenerateError, RoomStyle, generate};

/// `--known-room` and `--known-echoes`, for `explobot run` and `explobot sweep`.
#[derive(clap::Args, Debug, Clone, Copy, Default)]
pub struct KnownRoomArg {
    /// Give Carto every surface of the room beforehand, as if its sonar saw everything: what
    /// the rest of Carto and Cute achieve with perfect perception (an analysis, never the
    /// robot's result).
    #[arg(long)]
    pub known_room: bool,
    /// Give Carto, as the run goes, every point the sonar has heard, where it really lies, never
    /// forgotten: what a perfect memory of the echoes would achieve (an analysis, never the
    /// robot's result).
    #[arg(long, conflicts_with = "known_room")]
    pub known_echoes: bool,
}

impl KnownRoomArg {
    /// The oracle the flags ask for.
    pub fn oracle(&self) -> Oracle {
        match (self.known_room, self.known_echoes) {
            (true, _) => Oracle::Room,
            (false, true) => Oracle::Echoes,
            (false, false) => Oracle::None,
        }
    }
}

/// `explobot replay`'s arguments.
#[derive(clap::Args, Clone, Debug)]
pub struct ReplayArgs {
    /// The recording.
    pub recording: PathBuf,
    /// Also write the replayed run as an MCAP file (see `explobot run --mcap`).
    #[arg(long, value_name = "FILE")]
    pub mcap: Option<PathBuf>,
    /// Compress the MCAP file's chunks with lz4.
    #[arg(long, requires = "mcap")]
    pub mcap_lz4: bool,
    /// Instead of re-running Carto: play the recorded drive commands into the twin and report
    /// how far each sensor stream of the twin is from the recorded one (a recording of
    /// `carto --calibration-drive`; `explobot calibrate` fits a profile to it).
    #[arg(long, conflicts_with = "mcap")]
    pub compare: bool,
    /// With --compare: a profile to compare (repeat for several; default the built-in robot).
    #[arg(long, value_name = "FILE", requires = "compare")]
    pub profile: Vec<PathBuf>,
    /// With --compare: the room the drive ran in (default: the built-in calibration room).
    #[arg(long, value_name = "SCENARIO", requires = "compare")]
    pub room: Option<PathBuf>,
    /// With --compare: also draw the heading and range errors over time as an SVG file.
    #[arg(long, value_name = "FILE", requires = "compare")]
    pub plot: Option<PathBuf>,
}

/// `--style`: a kind of room (the values of [`RoomStyle`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum StyleArg {
    /// A furnished flat: interior walls with doors, beds, sofas, wardrobes, tables, chairs.
    Flat,
    /// An office: desk banks on legs, turned chairs, a corridor, cellular offices.
    Office,
    /// Warehouse racks in long parallel runs with 1.0–3.0 m aisles.
    Warehouse,
    /// An open hall with pillars on a 5–8 m structural grid.
    Pillars,
    /// An irregular outline: L cuts, chamfers, slanted walls, bay windows.
    Irregular,
}

impl From<StyleArg> for RoomStyle {
    fn from(style: StyleArg) -> RoomStyle {
        match style {
            StyleArg::Flat => RoomStyle::Flat,
            StyleArg::Office => RoomStyle::Office,
            StyleArg::Warehouse => RoomStyle::Warehouse,
            StyleArg::Pillars => RoomStyle::Pillars,
            StyleArg::Irregular => RoomStyle::Irregular,
        }
    }
}

/// Arguments of `explobot generate`.
#[derive(clap::Args, Debug, Clone)]
pub struct GenerateArgs {
    /// Kind of room.
    #[arg(long, value_enum)]
    pub style: StyleArg,
    /// Seed: the same style and seed always give the same file.
    #[arg(long)]
    pub seed: u64,
    /// Output file (default: standard output).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

impl GenerateArgs {
    /// Generates the room, checks it as `explobot check` would, and writes it to `--out` or
    /// standard output.
    pub fn run(&self) -> Result<(), GenerateError> {
        let room = generate(self.style.into(), self.seed)?;
        let text = room.to_ron();
        let label = self.out.as_ref().map_or("<stdout>".to_string(), |p| p.display().to_string());
        RunSetup::from_ron_str(&text, &label, Path::new("."))
            .map_err(|e| GenerateError::Invalid(e.to_string()))?;
        let written = match &self.out {
            Some(path) => std::fs::write(path, &text),
            None => crate::sink::print_stdout(&text),
        };
        written.map_err(|e| GenerateError::Write { path: label, message: e.to_string() })
    }
}

/// Arguments of `explobot truth`.
#[derive(Debug, Clone, clap::Args)]
pub struct TruthArgs {
    /// Scenario file (default: the built-in default room).
    pub scenario: Option<PathBuf>,
    /// Where to write the picture (default: runs/NAME/truth.png).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Also bound one touch-free tour for a body that keeps this many metres from everything,
    /// anywhere in its cells (`sim/twin/src/freespace.rs`); repeat for several, e.g.
    /// `--clearance 0.01 --clearance 0.02`.
    #[arg(long, value_name = "METRES", value_parser = parse_metres)]
    pub clearance: Vec<f32>,
    /// With `--clearance`: how far from a cell's centre a command may leave the body, metres
    /// (repeat for several; default 0 and 0.02).
    #[arg(long, value_name = "METRES", value_parser = parse_metres, requires = "clearance")]
    pub stop_within: Vec<f32>,
}

/// A distance in metres: finite, 0 to 0.2.
fn parse_metres(text: &str) -> Result<f32, String> {
    let m: f32 = text.parse().map_err(|_| format!("`{text}` is not a number of metres"))?;
    if m.is_finite() && (0.0..=0.2).contains(&m) {
        Ok(m)
    } else {
        Err(format!("expected 0 to 0.2 m, not {text}"))
    }
}

/// Why `explobot truth` failed.
#[derive(Debug, thiserror::Error)]
pub enum TruthError {
    /// The scenario could not be loaded.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The picture could not be written.
    #[error("writing {path}: {message}")]
    Write {
        /// Where.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// The room is too large for the clearance bound's lattice.
    #[error(transparent)]
    TooLarge(#[from] twin::freespace::TooLarge),
}

impl TruthArgs {
    /// Prints the counts and writes the picture.
    pub fn run(&self) -> Result<(), TruthError> {
        let loaded = RunSetup::load_or_default(self.scenario.as_deref())?;
        let set = ScoredSet::of(&loaded);
        let c = TruthCounts::with_set(&loaded, &set);
        let stops = if self.stop_within.is_empty() { vec![0.0, 0.02] } else { self.stop_within.clone() };
        let mut bounds = Vec::new();
        for &clearance_m in &self.clearance {
            let tours = lattice_tour_bounds(&loaded, clearance_m, &stops)?;
            bounds.extend(stops.iter().zip(tours).map(|(&stop_within_m, tour_bound)| ClearanceBound {
                clearance_m,
                stop_within_m,
                tour_bound,
            }));
        }
        let mut text = c.text(&loaded.label, loaded.truth().frame.cell, &bounds);
        let path = self
            .out
            .clone()
            .unwrap_or_else(|| crate::sink::default_out_dir(&loaded.scenario.name).join("truth.png"));
        let write = |message: String| TruthError::Write { path: path.clone(), message };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| write(e.to_string()))?;
        }
        let s = &loaded.scenario;
        let keeps = self.clearance.first().map(|&c| {
            twin::freespace::centre_keeps(
                loaded.truth().frame,
                &s.room,
                &s.obstacle_shapes(),
                &loaded.profile,
                c,
            )
        });
        truth_picture_ringing(&loaded, &set, keeps.as_deref())
            .save(&path)
            .map_err(|e| write(e.to_string()))?;
        text.push_str(&format!("wrote {}\n", path.display()));
        crate::sink::print_stdout(&text)
            .map_err(|e| TruthError::Write { path: "<stdout>".into(), message: e.to_string() })
    }
}

/// What the window writes for tests and docs: a screenshot, a status file.
#[derive(clap::Args, Clone, Debug)]
pub struct ScreenshotArgs {
    /// Run at full speed to --screenshot-after sim seconds, save a PNG of the window, exit
    /// (implies --window).
    #[arg(long, value_name = "FILE")]
    pub screenshot: Option<PathBuf>,
    /// Sim seconds before the screenshot.
    #[arg(long, default_value_t = 10.0, value_name = "SECONDS")]
    pub screenshot_after: f64,
    /// Rewrite FILE a few times a second with what the window shows, as JSON: sim time, speed,
    /// script state and verdict, robot, Cute's map, where the buttons are (implies --window).
    #[arg(long, value_name = "FILE")]
    pub status_file: Option<PathBuf>,
}

impl ScreenshotArgs {
    /// No screenshot.
    pub fn none() -> ScreenshotArgs {
        ScreenshotArgs { screenshot: None, screenshot_after: 10.0, status_file: None }
    }

    /// What the window is to write: the screenshot's file and sim time, when one is asked for,
    /// and the status file.
    pub fn outputs(&self) -> Result<WindowOutputs, WindowError> {
        let screenshot = match &self.screenshot {
            None => None,
            Some(_) if !(self.screenshot_after.is_finite() && self.screenshot_after >= 0.0) => {
                return Err(WindowError::BadScreenshotTime);
            }
            Some(path) => Some((path.clone(), self.screenshot_after)),
        };
        Ok(WindowOutputs { screenshot, status_file: self.status_file.clone() })
    }
}

/// `explobot window`'s arguments.
#[derive(clap::Args, Clone, Debug)]
pub struct WindowArgs {
    /// Scenario file (RON); the built-in default room when omitted.
    pub scenario: Option<PathBuf>,
    /// Seed for every random process (default: the scenario's).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Serve the run live over the Foxglove WebSocket protocol (default address 127.0.0.1:8765).
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = twin_viz::DEFAULT_ADDR)]
    pub foxglove: Option<std::net::SocketAddr>,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub shot: ScreenshotArgs,
}
