//! `explobot bench`: throughput figures, printed, never asserted.
//!
//! * **physics** — [`RobotBody`] alone in a scenario's room, driven in a fixed pattern (forward,
//!   spin, strafe), in three variants: no sonar; the sonar at its real 60 ms cycle; and a 5-ray
//!   cast on *every* step (the worst case the target is stated for).
//! * **full stack** — a whole scenario run (Cute ⇄ Carto ⇄ boards ⇄ physics, real bytes on every
//!   link) in the lockstep runner, headless, on one thread.

use std::time::Instant as WallInstant;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use robot_model::kinematics::{MecanumKinematics, rad_s_to_rpm};
use robot_model::pose::{Pose2, Twist};
use robot_model::time::{Duration, Instant};

use crate::body::RobotBody;
use crate::scenario::LoadedScenario;

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

/// One physics benchmark result.
#[derive(Debug, Clone, PartialEq)]
pub struct PhysicsFigure {
    /// Sonar variant.
    pub sonar: SonarLoad,
    /// Steps simulated.
    pub steps: u64,
    /// Wall-clock seconds.
    pub wall_s: f64,
}

impl PhysicsFigure {
    /// Physics steps per wall-clock second.
    pub fn steps_per_s(&self) -> f64 {
        self.steps as f64 / self.wall_s.max(1e-9)
    }

    /// Simulated seconds per wall-clock second at step `dt`.
    pub fn real_time_factor(&self, dt: Duration) -> f64 {
        self.steps_per_s() * dt.as_secs_f64()
    }
}

/// Runs `steps` physics steps of the scenario's robot in its room.
pub fn physics(loaded: &LoadedScenario, steps: u64, sonar: SonarLoad) -> PhysicsFigure {
    let scenario = &loaded.scenario;
    let profile = &loaded.profile;
    let dt = Duration::from_secs_f64(f64::from(scenario.physics.step_ms) / 1000.0);
    let frame = crate::grid::GridFrame::for_room(&scenario.room, scenario.cell_size(profile));
    let (x, y) = frame.cell_center(scenario.start.row as usize, scenario.start.col as usize);
    let mut body = RobotBody::new(scenario, profile, Pose2::new(x, y, scenario.start.heading.angle()), dt);
    let kin = MecanumKinematics::from_profile(profile);
    let pattern = [
        Twist { vx: 0.3, vy: 0.0, omega: 0.0 },
        Twist { vx: 0.0, vy: 0.0, omega: 1.5 },
        Twist { vx: 0.0, vy: 0.2, omega: 0.0 },
        Twist { vx: -0.3, vy: 0.0, omega: -1.5 },
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(scenario.seed);
    let start = WallInstant::now();
    let mut now = Instant::ZERO;
    for i in 0..steps {
        let twist = pattern[((i / 200) % 4) as usize];
        body.step(kin.inverse(twist).map(rad_s_to_rpm));
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
    PhysicsFigure { sonar, steps, wall_s: start.elapsed().as_secs_f64() }
}
