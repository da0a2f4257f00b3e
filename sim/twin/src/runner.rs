//! The lockstep runner: Cute ⇄ Carto ⇄ board twins ⇄ physics in one thread on a virtual clock.
//!
//! Every step of `dt` (5 ms by default), in this order:
//! 1. the clock moves to `now`; the in-memory links deliver the bytes whose serial time is due
//!    (baud-rate timing and the scenario's faults apply);
//! 2. the **motor board** and **sensor board** twins read their UARTs and answer (telemetry,
//!    keep-state, sensor frames built from the body's sensors);
//! 3. **Carto** ([`carto::CartoRuntime`]) reads its three links, runs its state machines, writes;
//! 4. **Cute** ([`cute::CuteRuntime`]) reads, the **operator** ([`crate::mission::Operator`])
//!    plays the mission script on it, and Cute polls and writes, over the in-memory "TCP" link
//!    (reconnecting by itself after a disconnect);
//! 5. the motor board's wheel setpoints drive the **physics** one step; the sonar measures when
//!    its cycle is due.
//!
//! Nothing reads a clock or an unseeded RNG, so the same scenario and seed give the same bytes on
//! every link — see [`Lockstep::link_logs`] and the determinism test.

use carto::{Carto, CartoConfig, CartoRuntime};
use cute::{CellValue, Cute, CuteConfig, CuteError, CuteRuntime, Wrap};
use robot_model::time::{Duration, Instant};
use transport::{
    ByteFaults, FaultConfig, FaultInjector, Link, MemConnector, MemLink, MemListener, MockClock, TraceHandle,
    Tracer, mem_listener,
};

use crate::belief::BeliefTracker;
use crate::body::RobotBody;
use crate::grid::GridFrame;
use crate::hardware::{Twin, WriteBudget};
use crate::localisation::{Localisation, carto_belief};
use crate::mission::Operator;
use crate::oracle::{Oracle, to_carto_frame};
use crate::record::EndpointLog;
use crate::report::FirstContact;
use crate::scenario::{Fault, LinkFaults};
use crate::scored::ScoredSet;
use crate::setup::RunSetup;
use crate::touches::TouchTracker;
use crate::truth::RobotTruth;

mod contact;
mod measure;
mod observe;
mod report;

pub use observe::{Endpoint, StepObserver};

/// Cute's end of the Cute ⇄ Carto link.
type CuteEnd = Tracer<FaultInjector<MemLink>>;
/// Carto's end of a board link.
type CartoEnd = Tracer<FaultInjector<MemLink>>;

/// Traces are moved into the link logs every this many steps (records carry their own times,
/// so the logs do not depend on it).
const TRACE_EVERY: u64 = 200;
/// Time the run goes on after the mission's last step, so final moves settle.
const SETTLE: Duration = Duration::from_millis(500);
/// A run that could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum SetupError {
    /// Cute refused its configuration (e.g. a grid larger than 256 × 256).
    #[error("cute: {0}")]
    Cute(#[from] CuteError),
}

/// How the twin wires each Cute connection: a fault injector seeded per connection, under a
/// tracer whose records become that connection's endpoint log.
struct GuiLinks {
    faults: FaultConfig,
    fault_seed: u64,
    clock: MockClock,
    /// One trace per connection, in order.
    traces: Vec<TraceHandle>,
    /// Faults injected on connections already closed.
    fault_counts: u64,
}

impl Wrap<MemLink> for GuiLinks {
    type Link = CuteEnd;

    fn wrap(&mut self, raw: MemLink, n: u64) -> CuteEnd {
        let seed = self.fault_seed.wrapping_add(n);
        let link = FaultInjector::new(raw, seed, self.clock.clone()).with_config(self.faults);
        let link = Tracer::new(link, self.clock.clone());
        self.traces.push(link.handle());
        link
    }

    fn retire(&mut self, mut link: CuteEnd) {
        self.fault_counts += fault_total(link.inner());
        if let Some(inner) = link.inner_mut().inner_mut() {
            inner.close();
        }
    }
}

/// Cute and its connection to Carto (Cute decides when to reconnect, with back-off).
type CuteSide = CuteRuntime<MemConnector, GuiLinks>;

fn fault_total<L: Link>(f: &FaultInjector<L>) -> u64 {
    let c = f.counters();
    c.rx.dropped + c.rx.flipped + c.rx.duplicated + c.tx.dropped + c.tx.flipped + c.tx.duplicated
}

fn fault_config(f: &LinkFaults) -> FaultConfig {
    let bytes = ByteFaults { drop_rate: f.drop_rate, flip_rate: f.corrupt_rate, duplicate_rate: 0.0 };
    FaultConfig {
        rx: bytes,
        tx: bytes,
        rx_delay: Duration::from_micros((f64::from(f.latency_ms) * 1000.0).round() as u64),
        disconnect_at: None,
    }
}

/// A whole scenario run in lockstep.
pub struct Lockstep {
    loaded: RunSetup,
    seed: u64,
    clock: MockClock,
    now: Instant,
    dt: Duration,
    steps: u64,
    end: Instant,
    twin: Twin,
    motor_board_end: Tracer<MemLink>,
    sensor_board_end: Tracer<MemLink>,
    carto: CartoRuntime<MemListener, CartoEnd, CartoEnd>,
    cute: CuteSide,
    operator: Operator,
    faults: Vec<Fault>,
    faults_fired: Vec<bool>,
    truth: RobotTruth,
    /// The run's first contact with a wall or an obstacle.
    first_contact: Option<FirstContact>,
    traces: Vec<(String, String, TraceHandle)>,
    logs: Vec<EndpointLog>,
    /// The link-log hash, computed once the run is over (the logs no longer change then).
    final_hash: std::sync::OnceLock<String>,
    localisation: Localisation,
    /// Carto's belief against the truth.
    belief: BeliefTracker,
    /// Every touch with its severity.
    touches: TouchTracker,
    /// Carto's refusals counted so far (cells reported blocked, turns refused).
    refusals_seen: u64,
    /// The cells the run is scored on, computed once when first asked for.
    scored: std::sync::OnceLock<ScoredSet>,
    /// Where Carto believed the robot was, sampled whenever the twin adds a trail point.
    believed_trail: Vec<(f32, f32)>,
    settled_at: Option<Instant>,
    /// The run goes on after the point where a headless run ends (see [`Lockstep::interactive`]).
    open_ended: bool,
    /// When the run reached the point where a headless run ends.
    headless_end: Option<Instant>,
    /// Who watches every step (the Foxglove/MCAP publisher), if anyone.
    observer: Option<Box<dyn StepObserver>>,
}

impl Lockstep {
    /// Builds the run: room, robot, board twins, Carto, Cute, links. `seed` overrides the
    /// scenario's seed when given.
    pub fn new(loaded: RunSetup, seed: Option<u64>) -> Result<Lockstep, SetupError> {
        let scenario = &loaded.scenario;
        let profile = &loaded.profile;
        let seed = seed.unwrap_or(scenario.seed);
        let dt = loaded.dt();
        let truth = loaded.truth().clone();
        let start = scenario.start;
        let mut twin = Twin::new(&loaded, seed, dt);
        let clock = MockClock::new();

        let mut traces = Vec::new();
        let mut board_link = |name: &str, baud: u32, faults: &LinkFaults, salt: u64| {
            let (carto_raw, board_raw) = MemLink::pair(Some(baud), clock.clone());
            let carto_end =
                FaultInjector::new(carto_raw, seed ^ salt, clock.clone()).with_config(fault_config(faults));
            let carto_end = Tracer::new(carto_end, clock.clone());
            let board_end = Tracer::new(board_raw, clock.clone());
            traces.push((name.to_string(), "carto".to_string(), carto_end.handle()));
            traces.push((name.to_string(), "board".to_string(), board_end.handle()));
            (carto_end, board_end)
        };
        let (motor_carto, motor_board_end) =
            board_link("motor", profile.serial.motor_baud, &scenario.links.motor, 0x006d_6f74_6f72);
        let (sensor_carto, sensor_board_end) =
            board_link("sensor", profile.serial.sensor_baud, &scenario.links.sensor, 0x0000_7365_6e73_6f72);
        let (listener, connector) = mem_listener(None, clock.clone());
        let mut carto = CartoRuntime::new(
            Carto::new(CartoConfig::from_profile(profile)),
            listener,
            motor_carto,
            sensor_carto,
        );
        match loaded.oracle() {
            Oracle::Room => {
                let points = crate::oracle::surface_points(scenario, &truth.frame, crate::oracle::SPACING_M);
                carto.carto_mut().add_floor_plan(points);
            }
            Oracle::Echoes => twin.body_mut().collect_new_heard(),
            Oracle::None => {}
        }
        let cute = Cute::new(CuteConfig {
            rows: truth.rows,
            cols: truth.cols,
            start: (start.row, start.col),
            heading: start.heading,
            ..CuteConfig::default()
        })?;
        let max = Instant::from_secs_f64(f64::from(scenario.physics.max_sim_s));
        let faults = scenario.faults.clone();
        let operator = Operator::new(scenario.mission.clone());
        Ok(Lockstep {
            seed,
            dt,
            steps: 0,
            now: Instant::ZERO,
            end: max,
            twin,
            motor_board_end,
            sensor_board_end,
            carto,
            cute: CuteRuntime::with_wrap(
                cute,
                connector,
                GuiLinks {
                    faults: fault_config(&scenario.links.gui),
                    fault_seed: seed ^ 0x0067_7569,
                    clock: clock.clone(),
                    traces: Vec::new(),
                    fault_counts: 0,
                },
            ),
            operator,
            faults_fired: vec![false; faults.len()],
            faults,
            truth,
            first_contact: None,
            clock,
            traces,
            logs: Vec::new(),
            final_hash: std::sync::OnceLock::new(),
            localisation: Localisation::default(),
            belief: BeliefTracker::default(),
            touches: TouchTracker::new(robot_model::kinematics::MecanumKinematics::from_profile(
                &loaded.profile,
            )),
            refusals_seen: 0,
            scored: std::sync::OnceLock::new(),
            believed_trail: Vec::new(),
            settled_at: None,
            open_ended: false,
            headless_end: None,
            observer: None,
            loaded,
        })
    }

    /// Advances the whole system by one step. Returns `false` once the run is over.
    pub fn step(&mut self) -> bool {
        if self.is_finished() {
            return false;
        }
        self.now += self.dt;
        let now = self.now;
        self.clock.set(now);
        self.steps += 1;
        let mut observer = self.observer.take();
        if let Some(o) = observer.as_mut() {
            o.before_step();
        }

        for (fault, fired) in self.faults.iter().zip(self.faults_fired.iter_mut()) {
            match fault {
                Fault::GuiDisconnect { at_s } => {
                    if !*fired && Instant::from_secs_f64(f64::from(*at_s)) <= now {
                        *fired = true;
                        self.cute.disconnect(now);
                    }
                }
            }
        }

        // 2. Board twins.
        self.twin.board_io(
            now,
            &mut self.motor_board_end,
            &mut self.sensor_board_end,
            WriteBudget::UNLIMITED,
        );

        // 3. Carto (given what the sonar heard, with `--known-echoes`).
        let heard = self.twin.body_mut().take_new_heard();
        if !heard.is_empty() {
            let frame = &self.truth.frame;
            let points = heard.into_iter().map(|(x, y)| to_carto_frame(frame, (f64::from(x), f64::from(y))));
            self.carto.carto_mut().add_known_surfaces(points);
        }
        let logging = tracing::enabled!(tracing::Level::DEBUG);
        let before = logging.then(|| self.carto.carto().stats());
        self.carto.step(now);
        if let Some(before) = before {
            let after = self.carto.carto().stats();
            if after.pilot.stalls != before.pilot.stalls {
                self.note_stop(now, "Carto stopped a stalled FORWARD");
            }
            if after.pilot.pushes != before.pilot.pushes {
                self.note_stop(now, "Carto stopped a FORWARD: the IMU saw the body turned under its wheels");
            }
            if after.pilot.obstacles != before.pilot.obstacles {
                self.note_obstacle_report(now);
            }
        }

        // 4. Cute and the operator.
        let operator = &mut self.operator;
        let moves_done = self.cute.cute().counters().moves_done;
        self.cute.step_with(now, |cute| operator.poll(now, cute));
        let move_ended = self.cute.cute().counters().moves_done != moves_done;
        if self.operator.finished_at.is_some() && self.settled_at.is_none() {
            self.settled_at = Some(now + SETTLE);
        }

        // 5. Physics.
        let trail_points = self.twin.trail().len();
        let collisions = self.twin.body().world().collisions();
        self.twin.physics_step(now);
        if self.twin.body().world().collisions() != collisions {
            self.note_contact(now);
            self.belief.contact();
        }
        if self.twin.trail().len() != trail_points
            && let Some(point) = self
                .carto
                .carto()
                .believed_pose()
                .and_then(|(pose, offset)| carto_belief(&self.truth.frame, pose, offset))
        {
            self.believed_trail.push(point);
        }
        // Headless, this is the run's last step; in an interactive run it happens once and the
        // run goes on.
        let at_end = self.headless_end.is_none() && self.headless_over();
        if at_end {
            self.headless_end = Some(now);
        }
        self.measure(now, move_ended, at_end);
        if move_ended || at_end {
            let (x, y, heading) = self.cute.cute().robot();
            self.localisation.sample(
                now.as_secs_f64(),
                &self.truth.frame,
                (x, y, heading),
                self.twin.body().pose(),
            );
        }
        // The observer sees this step's byte records before they move into the logs.
        if let Some(mut o) = observer {
            o.after_step(self);
            self.observer = Some(o);
        }
        if self.steps.is_multiple_of(TRACE_EVERY) || at_end {
            if self.headless_end.is_some() && !at_end {
                self.drop_traces();
            } else {
                self.collect_traces();
            }
        }
        !self.is_finished()
    }

    /// Runs until the mission is over (plus a short settle) or the time limit.
    pub fn run_to_end(&mut self, mut progress: impl FnMut(&Lockstep)) {
        while self.step() {
            if self.steps.is_multiple_of(2000) {
                progress(self);
            }
        }
        progress(self);
    }

    /// Whether the run is over: at the point where a headless run ends ([`Lockstep::headless_end`]),
    /// and never for an [`interactive`](Lockstep::interactive) run.
    pub fn is_finished(&self) -> bool {
        !self.open_ended && self.headless_over()
    }

    /// Whether the script is over (plus the settle time) or the time limit is reached.
    fn headless_over(&self) -> bool {
        self.now >= self.end || self.settled_at.is_some_and(|t| self.now >= t)
    }

    /// This run, made to go on after its script and past the scenario's time limit until the caller
    /// stops stepping it (the window: the user closes it). Up to the point where a headless run
    /// ends, it takes exactly the same steps; after that Cute is the user's alone, and the link
    /// logs are no longer kept (the link statistics still count).
    pub fn interactive(mut self) -> Lockstep {
        self.open_ended = true;
        self
    }

    /// Whether the run goes on after its script ([`Lockstep::interactive`]).
    pub fn is_interactive(&self) -> bool {
        self.open_ended
    }

    /// When the run reached the point where a headless run ends: the script done and settled, or
    /// the scenario's time limit (`max_sim_s`).
    pub fn headless_end(&self) -> Option<Instant> {
        self.headless_end
    }

    /// The same scenario again from its start pose, with the same seed (and interactive if this
    /// run is).
    pub fn restart(&self) -> Result<Lockstep, SetupError> {
        let run = Lockstep::new(self.loaded.clone(), Some(self.seed))?;
        Ok(if self.open_ended { run.interactive() } else { run })
    }

    /// The mission script's player.
    pub fn operator(&self) -> &Operator {
        &self.operator
    }

    /// Empties the tracers without keeping their records (an interactive run past its headless
    /// end: the byte logs would grow without bound).
    fn drop_traces(&mut self) {
        for (_, _, handle) in &self.traces {
            handle.take();
        }
        for handle in &self.cute.wrapper().traces {
            handle.take();
        }
    }

    fn collect_traces(&mut self) {
        // Each connection Cute makes is its own endpoint log: `cute#1`, `cute#2`, …
        let cute_traces = self
            .cute
            .wrapper()
            .traces
            .iter()
            .enumerate()
            .map(|(i, h)| ("gui".to_string(), format!("cute#{}", i + 1), h.clone()));
        let all: Vec<_> = self.traces.iter().cloned().chain(cute_traces).collect();
        for (link, endpoint, handle) in all {
            let records = handle.take();
            if records.is_empty() {
                continue;
            }
            let log = match self.logs.iter_mut().position(|l| l.link == link && l.endpoint == endpoint) {
                Some(i) => &mut self.logs[i],
                None => {
                    self.logs.push(EndpointLog {
                        link: link.clone(),
                        endpoint: endpoint.clone(),
                        chunks: Vec::new(),
                    });
                    let last = self.logs.len() - 1;
                    &mut self.logs[last]
                }
            };
            log.chunks.extend(records);
        }
    }

    /// Every byte moved on every link, per endpoint: complete once the run is finished, else as of
    /// the last collection (every `TRACE_EVERY` = 200 steps).
    pub fn link_logs(&self) -> &[EndpointLog] {
        &self.logs
    }

    /// The fixed physics step.
    pub fn dt(&self) -> Duration {
        self.dt
    }

    /// Simulated time now.
    pub fn now(&self) -> Instant {
        self.now
    }

    /// The time limit of the run.
    pub fn time_limit(&self) -> Instant {
        self.end
    }

    /// The robot's physical side.
    pub fn body(&self) -> &RobotBody {
        self.twin.body()
    }

    /// The board twins and the body.
    pub fn twin(&self) -> &Twin {
        &self.twin
    }

    /// Cute, as the operator sees it.
    pub fn cute(&self) -> &Cute {
        self.cute.cute()
    }

    /// Cute, for user actions from a window.
    pub fn cute_mut(&mut self) -> &mut Cute {
        self.cute.cute_mut()
    }

    /// Carto's state.
    pub fn carto(&self) -> &Carto {
        self.carto.carto()
    }

    /// The grid's placement in the world.
    pub fn frame(&self) -> GridFrame {
        self.truth.frame
    }

    /// The ground truth.
    pub fn truth(&self) -> &RobotTruth {
        &self.truth
    }

    /// The cells the run is scored on ([`crate::scored`]), computed on first use.
    pub fn scored_set(&self) -> &ScoredSet {
        self.scored.get_or_init(|| ScoredSet::of(&self.loaded))
    }

    /// The robot's trail (world metres).
    pub fn trail(&self) -> &[(f32, f32)] {
        self.twin.trail()
    }

    /// Where Carto believed the robot was, at the moments of [`Lockstep::trail`] once Carto
    /// knew its cell (world metres; see [`crate::localisation::carto_belief`]).
    pub fn believed_trail(&self) -> &[(f32, f32)] {
        &self.believed_trail
    }

    /// The scenario being run.
    pub fn loaded(&self) -> &RunSetup {
        &self.loaded
    }

    /// Seed in use.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// What Cute's map says of each cell, row-major: `Some(true)` free, `Some(false)` obstacle.
    pub fn known_cells(&self) -> Vec<Option<bool>> {
        let map = self.cute.cute().map();
        let mut out = Vec::with_capacity(self.truth.rows * self.truth.cols);
        for row in 0..self.truth.rows {
            for col in 0..self.truth.cols {
                out.push(match map.get(row, col) {
                    None | Some(CellValue::Unknown) => None,
                    Some(CellValue::Obstacle) => Some(false),
                    Some(_) => Some(true),
                });
            }
        }
        out
    }

    /// The moves Cute's map records as blocked (each once, the smaller cell first).
    pub fn blocked_moves(&self) -> Vec<((u8, u8), (u8, u8))> {
        self.cute.cute().map().blocked_moves().collect()
    }
}
