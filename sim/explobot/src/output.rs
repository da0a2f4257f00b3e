//! What `explobot run` writes: `runs/NAME/{report.json, map.png, links.rec}`.
//!
//! Concept: a finished [`Lockstep`] holds everything the three files need — the report is the
//! caller's (it carries the wall time the caller measured), [`map_picture`] draws Cute's map over
//! the true room, and [`recording`] keeps the scenario text, the profile that ran, the seed and
//! every byte on every link, so `explobot replay` can rebuild the run ([`twin::replay`]).
//!
//! Invariant: the files depend only on the run and the report, so the same scenario and seed
//! write the same `links.rec` and `map.png` bytes.
//!
//! ```no_run
//! use twin::runner::Lockstep;
//! let mut run = Lockstep::new(twin::setup::RunSetup::builtin_default()?, None)?;
//! run.run_to_end(|_| {});
//! let report = run.report(1.0);
//! explobot::output::write_outputs(std::path::Path::new("runs/default"), &run, &report)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::{Path, PathBuf};

use indicatif::{ProgressBar, ProgressStyle};

use crate::args::ScreenshotArgs;
use twin::carto_map::{BeliefEllipse, CartoMap};
use twin::record::{FORMAT_VERSION, Recording, RecordingError};
use twin::report::Report;
use twin::runner::Lockstep;
use twin_pictures::mapimg::MapPicture;

pub use crate::sink::{default_out_dir, print_stdout};

/// `explobot run`'s arguments.
#[derive(clap::Args, Clone, Debug)]
pub struct RunArgs {
    /// Scenario file (RON); the built-in default room when omitted.
    pub scenario: Option<PathBuf>,
    /// Seed for every random process (default: the scenario's).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Output folder (default: runs/NAME).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Open the interactive window instead (world beside Cute's map; feature `window`).
    #[arg(long)]
    pub window: bool,
    /// Also write the whole run as an MCAP file (open it in Foxglove or Lichtblick).
    #[arg(long, value_name = "FILE")]
    pub mcap: Option<PathBuf>,
    /// Compress the MCAP file's chunks with lz4 (about a third of the size, a slower run).
    #[arg(long, requires = "mcap")]
    pub mcap_lz4: bool,
    /// Serve the run live over the Foxglove WebSocket protocol while the window shows it
    /// (implies --window; default address 127.0.0.1:8765).
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = twin_viz::DEFAULT_ADDR)]
    pub foxglove: Option<std::net::SocketAddr>,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub known: crate::args::KnownRoomArg,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub shot: ScreenshotArgs,
}

impl RunArgs {
    /// `explobot` with no subcommand: the default room, headless.
    pub fn default_room() -> RunArgs {
        RunArgs {
            scenario: None,
            seed: None,
            out: None,
            quiet: false,
            window: false,
            mcap: None,
            mcap_lz4: false,
            foxglove: None,
            known: crate::args::KnownRoomArg::default(),
            shot: ScreenshotArgs::none(),
        }
    }

    /// Whether the run is asked for in the window (`--window`, `--foxglove`, or a screenshot).
    pub fn wants_window(&self) -> bool {
        self.window
            || self.foxglove.is_some()
            || self.shot.screenshot.is_some()
            || self.shot.status_file.is_some()
    }
}

/// The progress bar of a headless run: sim seconds done of the time limit, and Cute's status.
pub struct Progress(ProgressBar);

impl Progress {
    /// A bar for `run` (hidden when `quiet`).
    pub fn new(run: &Lockstep, quiet: bool) -> Progress {
        let limit = run.time_limit().as_secs_f64().ceil() as u64;
        let bar = if quiet { ProgressBar::hidden() } else { ProgressBar::new(limit) };
        bar.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} s sim  {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        Progress(bar)
    }

    /// Shows where `run` is.
    pub fn show(&self, run: &Lockstep) {
        self.0.set_position(run.now().as_secs_f64() as u64);
        self.0.set_message(format!("{:?}", run.cute().status()));
    }

    /// Clears the bar.
    pub fn finish(self) {
        self.0.finish_and_clear();
    }
}

/// A run's files could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// A file or folder could not be written.
    #[error("writing {path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The report or the profile could not be serialized.
    #[error("serializing {what}: {message}")]
    Serialize {
        /// Which.
        what: &'static str,
        /// Why.
        message: String,
    },
    /// `map.png` could not be encoded or written.
    #[error("writing map.png: {0}")]
    Image(#[from] image::ImageError),
    /// `links.rec` could not be written.
    #[error(transparent)]
    Recording(#[from] RecordingError),
}

/// Cute's map over the true room, the true and the believed trail, the final pose and a legend.
pub fn map_picture(run: &Lockstep, known: &[Option<bool>]) -> image::RgbImage {
    let pose = run.body().pose();
    let geometry = &run.loaded().profile.geometry;
    MapPicture {
        scenario: &run.loaded().scenario,
        frame: run.frame(),
        known,
        blocked_moves: &run.blocked_moves(),
        trail: run.trail(),
        believed_trail: run.believed_trail(),
        carto_map: &CartoMap::of(run.carto(), &run.frame()),
        belief: BeliefEllipse::of(run.carto(), &run.frame(), run.now()),
        pose: (pose.x, pose.y, pose.theta),
        body: (geometry.body_length_m, geometry.body_width_m),
    }
    .render()
}

/// The run's recording: scenario text, the profile that ran, the seed, every link's bytes.
pub fn recording(run: &Lockstep) -> Result<Recording, OutputError> {
    let loaded = run.loaded();
    let profile_ron = loaded.profile.to_ron_string().map_err(|e| OutputError::Serialize {
        what: "the profile into the recording",
        message: e.to_string(),
    })?;
    Ok(Recording {
        version: FORMAT_VERSION,
        scenario_label: loaded.label.clone(),
        scenario_ron: loaded.text.clone(),
        profile_ron,
        seed: run.seed(),
        logs: run.link_logs().to_vec(),
        oracle: loaded.oracle(),
    })
}

/// Writes `report.json`, `map.png` and `links.rec` into `out` (created if missing).
pub fn write_outputs(out: &Path, run: &Lockstep, report: &Report) -> Result<(), OutputError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| OutputError::Io { path, source }
    };
    std::fs::create_dir_all(out).map_err(io(out))?;
    let json = serde_json::to_string_pretty(report)
        .map_err(|e| OutputError::Serialize { what: "report.json", message: e.to_string() })?;
    let report_path = out.join("report.json");
    std::fs::write(&report_path, json + "\n").map_err(io(&report_path))?;
    map_picture(run, &run.known_cells()).save(out.join("map.png"))?;
    recording(run)?.save(&out.join("links.rec"))?;
    Ok(())
}
