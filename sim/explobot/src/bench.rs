//! `explobot bench`: throughput figures, printed, never asserted.
//!
//! * **physics** — [`RobotBody`] alone in a scenario's room, driven in a fixed pattern (forward,
//!   spin, strafe), in three variants: no sonar; the sonar at its real 60 ms cycle; and a 5-ray
//!   cast on *every* step (the worst case, the one the throughput target is stated for).
//! * **full stack** — a whole scenario run (Cute ⇄ Carto ⇄ boards ⇄ physics, real bytes on every
//!   link) in the lockstep runner, headless, on one thread.
//!
//! The tables are built here ([`physics_header`], [`physics_rows`], [`full_stack_header`],
//! [`full_stack_row`]); `explobot bench` prints them.

use std::path::PathBuf;
use std::time::Instant as WallInstant;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use robot_model::kinematics::{MecanumKinematics, rad_s_to_rpm};
use robot_model::pose::Twist;
use robot_model::time::{Duration, Instant};

use twin::body::RobotBody;
use twin::report::Report;
use twin::scenario::ScenarioError;
use twin::setup::RunSetup;

/// `explobot bench`'s arguments.
#[derive(clap::Args, Clone, Debug)]
pub struct BenchArgs {
    /// Scenarios (default: the built-in default room).
    pub scenarios: Vec<PathBuf>,
    /// Physics steps per round of a physics measurement.
    #[arg(long, default_value_t = 100_000)]
    pub steps: u64,
    /// Rounds per physics measurement (the median and the best round are printed).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u16).range(1..))]
    pub rounds: u16,
    /// Only the physics figures.
    #[arg(long)]
    pub physics_only: bool,
}

impl BenchArgs {
    /// The scenarios asked for, loaded (the built-in default room when none is named).
    pub fn load(&self) -> Result<Vec<RunSetup>, ScenarioError> {
        if self.scenarios.is_empty() {
            return Ok(vec![RunSetup::builtin_default()?]);
        }
        self.scenarios.iter().map(|p| RunSetup::load(p)).collect()
    }
}

/// The physics table's title and column heads.
pub fn physics_header(steps: u64, rounds: u16) -> String {
    format!(
        "physics: {steps} steps of the robot in each room, {rounds} rounds per variant, one thread\n{:<20} {:<12} {:>16} {:>14} {:>12} {:>11}",
        "scenario", "sonar", "median steps/s", "best steps/s", "x real time", "collisions"
    )
}

/// One physics table line per figure of scenario `name`, each ending in a newline.
pub fn physics_rows(name: &str, figures: &[PhysicsFigure], dt: Duration) -> String {
    let mut out = String::new();
    for f in figures {
        let label = match f.sonar {
            SonarLoad::Off => "off",
            SonarLoad::PerCycle => "60 ms cycle",
            SonarLoad::EveryStep => "every step",
        };
        out += &format!(
            "{:<20} {:<12} {:>16.0} {:>14.0} {:>12.0} {:>11}\n",
            name,
            label,
            f.median_steps_per_s(),
            f.best_steps_per_s(),
            f.real_time_factor(dt),
            f.collisions
        );
    }
    out
}

/// The full-stack table's title and column heads.
pub fn full_stack_header() -> String {
    format!(
        "full stack: Cute + Carto + boards + physics, real bytes on every link, headless\n{:<20} {:>10} {:>10} {:>12} {:>10}",
        "scenario", "sim s", "wall s", "x real time", "result"
    )
}

/// One full-stack table line for a finished run's report.
pub fn full_stack_row(r: &Report) -> String {
    let verdict = if r.passed { "pass" } else { "FAIL" };
    format!(
        "{:<20} {:>10.1} {:>10.2} {:>12.0} {:>10}",
        r.scenario, r.sim_time_s, r.wall_time_s, r.real_time_factor, verdict
    )
}

/// How the sonar is exercised in a physics benchmark.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SonarLoad {
    /// No ray casts.
    Off,
    /// One measurement per HC-SR04 cycle (60 ms), as in a real run.
    PerCycle,
    /// A full measurement (all rays) on every physics step.
    EveryStep,
}

/// One physics benchmark result: the same run repeated `rounds` times.
#[derive(Debug, Clone, PartialEq)]
pub struct PhysicsFigure {
    /// Sonar variant.
    pub sonar: SonarLoad,
    /// Steps simulated per round.
    pub steps: u64,
    /// Wall-clock seconds of each round.
    pub wall_s: Vec<f64>,
    /// Collisions (contact starts) in one round. The pattern stays near the start cell, as the
    /// robot does under Carto; a large count means the figure includes the contact solver
    /// grinding along a wall (one-cell corridors).
    pub collisions: u32,
}

impl PhysicsFigure {
    /// Physics steps per wall-clock second of each round.
    fn rates(&self) -> impl Iterator<Item = f64> + '_ {
        self.wall_s.iter().map(|w| self.steps as f64 / w.max(1e-9))
    }

    /// Physics steps per wall-clock second in the median round (the upper middle one for an even
    /// number of rounds).
    pub fn median_steps_per_s(&self) -> f64 {
        let mut rates: Vec<f64> = self.rates().collect();
        rates.sort_by(f64::total_cmp);
        rates.get(rates.len() / 2).copied().unwrap_or(0.0)
    }

    /// Physics steps per wall-clock second in the fastest round (the least disturbed by other
    /// work on the machine).
    pub fn best_steps_per_s(&self) -> f64 {
        self.rates().fold(0.0, f64::max)
    }

    /// Simulated seconds per wall-clock second at step `dt`, median round.
    pub fn real_time_factor(&self, dt: Duration) -> f64 {
        self.median_steps_per_s() * dt.as_secs_f64()
    }
}

/// Every sonar variant, `rounds` times each, interleaved (off, per cycle, every step, off, …) so
/// that a burst of other work on the machine does not land on one variant only.
pub fn physics(loaded: &RunSetup, steps: u64, rounds: usize) -> Vec<PhysicsFigure> {
    let variants = [SonarLoad::Off, SonarLoad::PerCycle, SonarLoad::EveryStep];
    let mut figures: Vec<PhysicsFigure> = variants
        .iter()
        .map(|&sonar| PhysicsFigure { sonar, steps, wall_s: Vec::new(), collisions: 0 })
        .collect();
    for _ in 0..rounds.max(1) {
        for figure in &mut figures {
            let (wall_s, collisions) = physics_round(loaded, steps, figure.sonar);
            figure.wall_s.push(wall_s);
            figure.collisions = collisions;
        }
    }
    figures
}

/// Drives the scenario's robot for `steps` physics steps from its start cell; returns the
/// wall-clock seconds and the collisions. The pattern (forward and back, spin left and right,
/// strafe left and right, 1 s each) returns to its start but for wheel slip, so the robot stays
/// near its start cell.
fn physics_round(loaded: &RunSetup, steps: u64, sonar: SonarLoad) -> (f64, u32) {
    let scenario = &loaded.scenario;
    let profile = &loaded.profile;
    let dt = loaded.dt();
    let mut body = RobotBody::new(scenario, profile, loaded.start_pose(), dt);
    let kin = MecanumKinematics::from_profile(profile);
    let pattern = [
        Twist { vx: 0.3, vy: 0.0, omega: 0.0 },
        Twist { vx: -0.3, vy: 0.0, omega: 0.0 },
        Twist { vx: 0.0, vy: 0.0, omega: 1.5 },
        Twist { vx: 0.0, vy: 0.0, omega: -1.5 },
        Twist { vx: 0.0, vy: 0.2, omega: 0.0 },
        Twist { vx: 0.0, vy: -0.2, omega: 0.0 },
    ];
    let setpoints: Vec<[f32; 4]> = pattern.iter().map(|t| kin.inverse(*t).map(rad_s_to_rpm)).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(scenario.seed);
    let start = WallInstant::now();
    let mut now = Instant::ZERO;
    for i in 0..steps {
        body.step(setpoints[((i / 200) % 6) as usize]);
        now += dt;
        match sonar {
            SonarLoad::Off => {}
            SonarLoad::PerCycle => {
                body.sample_sonar(now, &mut rng);
            }
            SonarLoad::EveryStep => {
                body.force_sonar(now, &mut rng);
            }
        }
    }
    (start.elapsed().as_secs_f64(), body.world().collisions())
}
