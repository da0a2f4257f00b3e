#![doc = include_str!("../README.md")]

//! A run the way robotics teams look at runs: MCAP files and a live Foxglove WebSocket server,
//! through the official `foxglove` crate and its well-known message types.
//!
//! Concept: a [`Recorder`] owns the sinks — an MCAP file, a WebSocket server, or both — on a
//! foxglove `Context` of its own (never the crate's global one, so the parallel runs of a sweep
//! never share a channel). Its [`Publisher`], set on a run as a
//! [`StepObserver`](twin::runner::StepObserver), logs what each step changed; the served twin
//! (`explobot sim --serve`) uses a [`TwinPublisher`] for the part it has.
//!
//! | topic | schema | when |
//! |---|---|---|
//! | `/tf` | `foxglove.FrameTransforms` | every [`POSE_EVERY`] steps: `world`→`robot` (true), `world`→`carto` (believed) |
//! | `/robot/pose` | `foxglove.PoseInFrame` | at 0, every [`POSE_EVERY`] steps and at the last step: the true pose |
//! | `/carto/pose` | `foxglove.PoseInFrame` | with `/robot/pose`, once Carto stores a cell: the cell's centre plus Carto's dead-reckoned offset, its heading |
//! | `/carto/belief` | `foxglove.SceneUpdate` | with `/robot/pose`, once Carto's filter has a reading: the 2σ ellipse of its position and its heading ([`twin::carto_map`]) |
//! | `/carto/grid` | `foxglove.Grid` | every [`CARTO_GRID_EVERY`] steps and at the last step, when it changed: Carto's evidence grid ([`scene::carto_grid`]) |
//! | `/sonar/rays` | `foxglove.SceneUpdate` | each HC-SR04 measurement: every ray, the echo kept in green |
//! | `/sonar/range` | `SonarRange` | each measurement: reported cm, the kept echo's and the central ray's true cm, each ray's length and echo |
//! | `/cute/map` | `foxglove.Grid` | when Cute's map changes (checked when Cute decodes a frame, and every [`POSE_EVERY`] steps) |
//! | `/cute/path` | `foxglove.PosesInFrame` | when Cute's planned path changes ([`scene::planned_path`]) |
//! | `/room` | `foxglove.SceneUpdate` | at 0: walls, obstacles, the robot's footprint |
//! | `/links/…` | see [`wire`] | link bytes and decoded frames |
//! | `/log` | `foxglove.Log` | each `tracing` event (INFO and above) Carto, Cute or the twin emit during a step |
//! | `/report` | `RunReport` | once, at the end: the verdict and the whole `report.json` |
//!
//! Invariants: every message is logged with an explicit log time, the sim clock in nanoseconds
//! (so a file is the same whatever the machine's speed, and times never go back); publishing
//! only reads the run, so a run with a recorder takes the same steps and moves the same bytes.
//!
//! ```no_run
//! use twin_viz::Recorder;
//! let mut run = twin::runner::Lockstep::new(twin::setup::RunSetup::builtin_default()?, None)?;
//! let recorder = Recorder::new().write_mcap("run.mcap".as_ref(), false)?;
//! run.set_observer(Box::new(recorder.publisher(&run)));
//! run.run_to_end(|_| {});
//! recorder.finish(Some((&run.report(1.0), run.now())))?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod logs;
mod outbox;
mod publisher;
pub mod scene;
pub mod wire;

use std::fs::File;
use std::io::{BufWriter, Write as _};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use foxglove::websocket::{ChannelView, Client, ServerListener};
use foxglove::{Context, Encode, McapWriteOptions, McapWriterHandle, WebSocketServer, WebSocketServerHandle};
use robot_model::time::Instant;

pub use outbox::{Outbox, Topic};
pub use publisher::{Publisher, SonarRange, TwinPublisher};

use twin::report::Report;

/// Poses and transforms are logged every this many steps (100 ms at 5 ms).
pub const POSE_EVERY: u64 = 20;

/// Carto's evidence grid is logged at most every this many steps (10 s at 5 ms): a whole room's
/// grid is a few hundred kilobytes.
pub const CARTO_GRID_EVERY: u64 = 2000;

/// Link bytes are logged in batches of this many steps (1 s at 5 ms); each chunk in a batch
/// keeps its own time.
pub const BYTES_EVERY: u64 = 200;

/// Where `--foxglove` serves when no address is given: loopback only, Foxglove's usual port.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8765";

/// Sim time in nanoseconds: a message's log time.
pub fn nanos(at: Instant) -> u64 {
    at.total_micros().saturating_mul(1000)
}

/// The run's report as the last message.
#[derive(Debug, Clone, PartialEq, Encode)]
pub struct RunReport {
    /// Scenario name.
    pub scenario: String,
    /// Seed.
    pub seed: u64,
    /// Whether every expectation holds.
    pub passed: bool,
    /// Whether the mission script completed.
    pub mission_complete: bool,
    /// Simulated seconds.
    pub sim_time_s: f64,
    /// Lockstep steps.
    pub steps: u64,
    /// Coverage of the scored set, 0–1.
    pub coverage: f64,
    /// Map accuracy, 0–1.
    pub map_accuracy: f64,
    /// Collisions: every touch.
    pub collisions: u32,
    /// Hard collisions among them (began at 0.10 m/s or more, or pushed the body 2 cm or more).
    pub hard_collisions: u32,
    /// Touches nothing in Carto noticed.
    pub unseen_touches: u32,
    /// Largest distance between the true body and Carto's belief, metres.
    pub belief_error_max_m: f64,
    /// 95th percentile of that distance, metres.
    pub belief_error_p95_m: f64,
    /// Largest angle between the true heading and Carto's believed heading, degrees.
    pub belief_heading_error_max_deg: f64,
    /// SHA-256 of every byte on every link.
    pub link_log_sha256: String,
    /// The whole `report.json`.
    pub json: String,
}

/// MCAP or server output that failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum VizError {
    /// The MCAP file could not be created or written.
    #[error("{path}: {message}")]
    Mcap {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// The WebSocket server could not start.
    #[error("foxglove server on {addr}: {message}")]
    Server {
        /// Where it was asked to listen.
        addr: SocketAddr,
        /// Why.
        message: String,
    },
}

/// Sets a flag whenever a WebSocket client subscribes, so the publisher sends the messages that
/// are only logged when they change (room, map, path) again.
struct Resend(Arc<AtomicBool>);

impl ServerListener for Resend {
    fn on_subscribe(&self, _client: Client, _channel: ChannelView) {
        self.0.store(true, Ordering::SeqCst);
    }
}

/// The sinks of one run (see the [module docs](self)).
pub struct Recorder {
    context: Arc<Context>,
    mcap: Option<(PathBuf, McapWriterHandle<BufWriter<File>>)>,
    server: Option<WebSocketServerHandle>,
    resend: Arc<AtomicBool>,
}

impl Default for Recorder {
    fn default() -> Self {
        Recorder::new()
    }
}

impl Recorder {
    /// No sink yet: messages go nowhere.
    pub fn new() -> Recorder {
        Recorder { context: Context::new(), mcap: None, server: None, resend: Arc::default() }
    }

    /// Also writes everything to the MCAP file `path` (replaced if it exists), its chunks
    /// compressed with lz4 when `lz4` (about a third of the size; measured costs in the README).
    pub fn write_mcap(mut self, path: &Path, lz4: bool) -> Result<Recorder, VizError> {
        let error = |message: String| VizError::Mcap { path: path.to_path_buf(), message };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| error(e.to_string()))?;
        }
        let file = File::create(path).map_err(|e| error(e.to_string()))?;
        // No CRCs (0 = "not computed" in MCAP): they cost about 2 % of a run; the file system
        // already checks what it stores.
        let options = McapWriteOptions::new()
            .compression(lz4.then_some(foxglove::McapCompression::Lz4))
            .calculate_chunk_crcs(false)
            .calculate_data_section_crc(false);
        let handle = self
            .context
            .mcap_writer_with_options(options)
            .create(BufWriter::new(file))
            .map_err(|e| error(e.to_string()))?;
        self.mcap = Some((path.to_path_buf(), handle));
        Ok(self)
    }

    /// Also serves everything live over the Foxglove WebSocket protocol on `addr` (port 0: any
    /// free port, see [`Recorder::port`]).
    pub fn serve(mut self, addr: SocketAddr) -> Result<Recorder, VizError> {
        let server = WebSocketServer::new()
            .name("explobot")
            .bind(addr.ip().to_string(), addr.port())
            .context(&self.context)
            .listener(Arc::new(Resend(Arc::clone(&self.resend))))
            .start_blocking()
            .map_err(|e| VizError::Server { addr, message: e.to_string() })?;
        self.server = Some(server);
        Ok(self)
    }

    /// The port the WebSocket server listens on, when serving.
    pub fn port(&self) -> Option<u16> {
        self.server.as_ref().map(WebSocketServerHandle::port)
    }

    /// The observer that publishes a lockstep run's channels.
    pub fn publisher(&self, run: &twin::runner::Lockstep) -> Publisher {
        Publisher::new(&self.context, self.outbox(), run, Arc::clone(&self.resend))
    }

    /// The publisher of the served twin's channels.
    pub fn twin_publisher(&self, loaded: &twin::setup::RunSetup) -> TwinPublisher {
        TwinPublisher::new(&self.context, self.outbox(), loaded, Arc::clone(&self.resend))
    }

    /// A new outbox (one per publisher).
    fn outbox(&self) -> Outbox {
        Outbox::default()
    }

    /// Logs the report (if any) at its sim time `at`, closes the MCAP file and stops the server.
    pub fn finish(self, report: Option<(&Report, Instant)>) -> Result<(), VizError> {
        let outbox = self.outbox();
        if let Some((r, at)) = report {
            let message = RunReport {
                scenario: r.scenario.clone(),
                seed: r.seed,
                passed: r.passed,
                mission_complete: r.mission_complete,
                sim_time_s: r.sim_time_s,
                steps: r.steps,
                coverage: r.coverage,
                map_accuracy: r.map_accuracy,
                collisions: r.collisions,
                hard_collisions: r.touches.hard,
                unseen_touches: r.touches.unseen,
                belief_error_max_m: r.belief.error_max_m,
                belief_error_p95_m: r.belief.error_p95_m,
                belief_heading_error_max_deg: r.belief.heading_error_max_deg,
                link_log_sha256: r.link_log_sha256.clone(),
                json: serde_json::to_string(r).unwrap_or_default(),
            };
            outbox.topic(&self.context, "/report").log(&message, nanos(at));
        }

        if let Some(server) = self.server {
            server.stop().wait_blocking();
        }
        if let Some((path, handle)) = self.mcap {
            let error = |message: String| VizError::Mcap { path: path.clone(), message };
            let mut writer = handle.close().map_err(|e| error(e.to_string()))?;
            writer.flush().map_err(|e| error(e.to_string()))?;
        }
        Ok(())
    }
}
