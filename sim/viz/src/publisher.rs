//! The publishers: after each step, what it changed as messages (the table in [`super`]).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use carto::CartoConfig;
use foxglove::messages::{FrameTransforms, Grid, Log, PoseInFrame, PosesInFrame, SceneUpdate};
use foxglove::{Context, Encode};
use protocol::motor::ChecksumPolicy;
use robot_model::time::Instant;
use transport::TraceRecord;

use super::logs::Capture;
use super::wire::{WireConfig, WireTap};
use super::{BYTES_EVERY, CARTO_GRID_EVERY, Outbox, POSE_EVERY, Topic, scene};
use twin::carto_map::{BeliefEllipse, CartoMap};
use twin::hardware::Twin;
use twin::localisation::carto_belief;
use twin::runner::{Endpoint, Lockstep, StepObserver};
use twin::scenario::Scenario;
use twin::setup::RunSetup;

/// One HC-SR04 measurement: what the sensor reported beside the geometry it measured.
#[derive(Debug, Clone, PartialEq, Encode)]
pub struct SonarRange {
    /// The range the sensor reports (noise and µs/58 quantisation applied), cm; −1 no echo.
    pub reported_cm: f32,
    /// The true distance of the echo kept (the nearest surviving one), cm; −1 none.
    pub kept_cm: f32,
    /// The true distance straight ahead (the central ray), cm; −1 nothing in range.
    pub center_cm: f32,
    /// Each ray's length as cast, left to right: to the surface it hit, or the sensor's range, cm.
    pub ray_cm: Vec<f32>,
    /// Each ray: whether its surface echoed back (hit within the incidence limit).
    pub ray_echo: Vec<bool>,
}

/// Log time that never goes back: a restarted run (the window's Restart) goes on after the
/// last time logged.
#[derive(Debug, Default)]
struct Clock {
    offset_us: u64,
    last_us: u64,
}

impl Clock {
    /// The log time of `now`, and whether the run started again.
    fn at(&mut self, now: Instant) -> (u64, bool) {
        let t = now.total_micros();
        let restarted = t <= self.last_us;
        if restarted {
            self.offset_us += self.last_us;
        }
        self.last_us = t;
        ((self.offset_us + t).saturating_mul(1000), restarted)
    }
}

/// What the served twin and the lockstep runner both have: the room, the true body, the sonar.
struct Body {
    scenario: Scenario,
    size: (f32, f32),
    tf: Topic<FrameTransforms>,
    pose: Topic<PoseInFrame>,
    rays: Topic<SceneUpdate>,
    range: Topic<SonarRange>,
    room: Topic<SceneUpdate>,
    measurements: u64,
}

impl Body {
    fn new(context: &Arc<Context>, outbox: &Outbox, loaded: &RunSetup) -> Body {
        let geometry = &loaded.profile.geometry;
        Body {
            scenario: loaded.scenario.clone(),
            size: (geometry.body_length_m, geometry.body_width_m),
            tf: outbox.topic(context, "/tf"),
            pose: outbox.topic(context, "/robot/pose"),
            rays: outbox.topic(context, "/sonar/rays"),
            range: outbox.topic(context, "/sonar/range"),
            room: outbox.topic(context, "/room"),
            measurements: 0,
        }
    }

    fn room(&self, ns: u64) {
        self.room.log(&scene::room_scene(&self.scenario, self.size, ns), ns);
    }

    /// The true pose (and Carto's belief, when there is one) as transforms, and the true pose.
    fn poses(&self, twin: &Twin, carto: Option<(f32, f32, f32)>, ns: u64) {
        let p = twin.body().pose();
        let truth = (p.x, p.y, p.theta);
        let mut transforms = vec![scene::transform(scene::ROBOT, truth, ns)];
        transforms.extend(carto.map(|c| scene::transform(scene::CARTO, c, ns)));
        self.tf.log(&FrameTransforms { transforms }, ns);
        self.pose.log(&scene::pose_in_world(truth, ns), ns);
    }

    /// The sonar's last measurement, if it is new.
    fn sonar(&mut self, twin: &Twin, ns: u64) {
        let body = twin.body();
        if body.sonar_measurements() == self.measurements {
            return;
        }
        self.measurements = body.sonar_measurements();
        let rays = body.last_rays();
        let cm = |r: &twin::body::CastRay| 100.0 * (r.to.0 - r.from.0).hypot(r.to.1 - r.from.1);
        let range = SonarRange {
            reported_cm: body.sonar_cm().unwrap_or(-1.0),
            kept_cm: scene::kept_ray(rays).and_then(|i| rays.get(i)).map_or(-1.0, cm),
            center_cm: rays.get(rays.len() / 2).filter(|r| r.hit).map_or(-1.0, cm),
            ray_cm: rays.iter().map(cm).collect(),
            ray_echo: rays.iter().map(|r| r.echo).collect(),
        };
        self.range.log(&range, ns);
        self.rays.log(&scene::sonar_scene(rays, ns), ns);
    }
}

fn wire_config(loaded: &RunSetup, decode_board_writes: bool) -> WireConfig {
    let carto = CartoConfig::from_profile(&loaded.profile);
    WireConfig {
        board_checksum: ChecksumPolicy::from(loaded.profile.motor_board.accept_checksum),
        carto_checksum: carto.boards.motor_checksum,
        max_frame: carto.client.max_frame,
        decode_board_writes,
    }
}

/// Publishes a lockstep run (set it with [`Lockstep::set_observer`]).
pub struct Publisher {
    body: Body,
    wire: WireTap,
    carto: Topic<PoseInFrame>,
    carto_grid: Topic<Grid>,
    carto_belief: Topic<SceneUpdate>,
    map: Topic<Grid>,
    path: Topic<PosesInFrame>,
    log: Topic<Log>,
    capture: Capture,
    clock: Clock,
    steps: u64,
    frames_in: u64,
    cells: Vec<cute::CellValue>,
    planned: Option<Vec<(u8, u8)>>,
    last_grid: Option<Grid>,
    last_path: Option<PosesInFrame>,
    /// Carto's grid as last published, and its message.
    carto_cells: CartoMap,
    last_carto_grid: Option<Grid>,
    resend: Arc<AtomicBool>,
}

impl Publisher {
    /// The channels of `run` on `context`; logs the room and the start pose at once.
    pub(super) fn new(
        context: &Arc<Context>,
        outbox: Outbox,
        run: &Lockstep,
        resend: Arc<AtomicBool>,
    ) -> Publisher {
        let mut publisher = Publisher {
            body: Body::new(context, &outbox, run.loaded()),
            wire: WireTap::new(context, &outbox, wire_config(run.loaded(), false)),
            carto: outbox.topic(context, "/carto/pose"),
            carto_grid: outbox.topic(context, "/carto/grid"),
            carto_belief: outbox.topic(context, "/carto/belief"),
            map: outbox.topic(context, "/cute/map"),
            path: outbox.topic(context, "/cute/path"),
            log: outbox.topic(context, "/log"),
            capture: Capture::default(),
            clock: Clock::default(),
            steps: 0,
            frames_in: 0,
            cells: Vec::new(),
            planned: None,
            last_grid: None,
            last_path: None,
            carto_cells: CartoMap::default(),
            last_carto_grid: None,
            resend,
        };
        let (ns, _) = publisher.clock.at(run.now());
        publisher.start(run, ns);
        publisher
    }

    /// What a run shows before its first step.
    fn start(&mut self, run: &Lockstep, ns: u64) {
        self.body.room(ns);
        self.body.poses(run.twin(), self.believed(run), ns);
        self.publish_map(run, ns);
    }

    /// Carto's believed pose in world metres and radians, once it stores a cell.
    fn believed(&self, run: &Lockstep) -> Option<(f32, f32, f32)> {
        let (pose, offset) = run.carto().believed_pose()?;
        let (x, y) = carto_belief(&run.frame(), pose, offset)?;
        Some((x, y, pose.heading.world_angle()))
    }

    /// Carto's evidence grid, when it changed.
    fn publish_carto_grid(&mut self, run: &Lockstep, ns: u64) {
        let cells = CartoMap::of(run.carto(), &run.frame());
        if cells != self.carto_cells {
            if let Some(grid) = scene::carto_grid(&cells, ns) {
                self.carto_grid.log(&grid, ns);
                self.last_carto_grid = Some(grid);
            }
            self.carto_cells = cells;
        }
    }

    /// Cute's map and planned path, each when it changed.
    fn publish_map(&mut self, run: &Lockstep, ns: u64) {
        let cute = run.cute();
        if self.cells.as_slice() != cute.map().cells() {
            self.cells = cute.map().cells().to_vec();
            let grid = scene::map_grid(cute.map(), &run.frame(), ns);
            self.map.log(&grid, ns);
            self.last_grid = Some(grid);
        }
        let planned = scene::planned_path(cute);
        if self.planned.as_ref() != Some(&planned) {
            let poses = scene::path_poses(&planned, &run.frame(), ns);
            self.path.log(&poses, ns);
            self.planned = Some(planned);
            self.last_path = Some(poses);
        }
    }
}

impl StepObserver for Publisher {
    fn before_step(&mut self) {
        self.capture.start();
    }

    fn after_step(&mut self, run: &Lockstep) {
        self.capture.stop();
        let (ns, restarted) = self.clock.at(run.now());
        if restarted {
            self.wire.reset();
            self.steps = 0;
            self.frames_in = 0;
            self.cells.clear();
            self.planned = None;
            self.carto_cells = CartoMap::default();
            self.start(run, ns);
        }
        self.steps += 1;
        let wire = &mut self.wire;
        run.step_records(|at: Endpoint<'_>, r: &TraceRecord| wire.record(at, r, ns));
        for event in self.capture.drain() {
            self.log.log(&event.to_log(ns), ns);
        }
        self.body.sonar(run.twin(), ns);
        let due = self.steps.is_multiple_of(POSE_EVERY) || run.is_finished();
        if due {
            let believed = self.believed(run);
            self.body.poses(run.twin(), believed, ns);
            if let Some(c) = believed {
                self.carto.log(&scene::pose_in_world(c, ns), ns);
            }
            if let Some(belief) = BeliefEllipse::of(run.carto(), &run.frame(), run.now()) {
                let reach = run.loaded().profile.geometry.body_length_m * 0.4;
                self.carto_belief.log(&scene::belief_scene(&belief, reach, ns), ns);
            }
        }
        if self.steps.is_multiple_of(CARTO_GRID_EVERY) || run.is_finished() {
            self.publish_carto_grid(run, ns);
        }
        let frames_in = run.cute().counters().frames_in;
        if due || frames_in != self.frames_in {
            self.frames_in = frames_in;
            self.publish_map(run, ns);
        }
        if self.steps.is_multiple_of(BYTES_EVERY) || run.is_finished() {
            self.wire.flush(ns);
        }
        if self.resend.swap(false, Ordering::SeqCst) {
            self.body.room(ns);
            if let Some(grid) = &self.last_grid {
                self.map.log(grid, ns);
            }
            if let Some(path) = &self.last_path {
                self.path.log(path, ns);
            }
            if let Some(grid) = &self.last_carto_grid {
                self.carto_grid.log(grid, ns);
            }
        }
    }
}

/// Publishes the served twin (`explobot sim --serve`): the room, the true pose, the sonar and
/// the boards' traffic. Carto and Cute run in other processes; their channels are not here.
pub struct TwinPublisher {
    body: Body,
    wire: WireTap,
    clock: Clock,
    steps: u64,
    resend: Arc<AtomicBool>,
}

impl TwinPublisher {
    pub(super) fn new(
        context: &Arc<Context>,
        outbox: Outbox,
        loaded: &RunSetup,
        resend: Arc<AtomicBool>,
    ) -> TwinPublisher {
        let body = Body::new(context, &outbox, loaded);
        body.room(0);
        TwinPublisher {
            body,
            wire: WireTap::new(context, &outbox, wire_config(loaded, true)),
            clock: Clock::default(),
            steps: 0,
            resend,
        }
    }

    /// After one step of the twin at `now`; `records` are what the board ports moved in it
    /// (endpoint `board` of links `motor` and `sensor`).
    pub fn after_step(&mut self, now: Instant, twin: &Twin, records: &[(Endpoint<'_>, TraceRecord)]) {
        let (ns, _) = self.clock.at(now);
        self.steps += 1;
        for (at, r) in records {
            self.wire.record(*at, r, ns);
        }
        self.body.sonar(twin, ns);
        if self.resend.swap(false, Ordering::SeqCst) {
            self.body.room(ns);
        }
        if self.steps.is_multiple_of(POSE_EVERY) {
            self.body.poses(twin, None, ns);
        }
        if self.steps.is_multiple_of(BYTES_EVERY) {
            self.wire.flush(ns);
        }
    }
}
