//! Reproduces the twin's known physics blow-up (README, "Known limits"): the robot, facing south
//! between a 0.183 m floor lamp and a box with `gap` metres either side of its 0.24 m width,
//! is told to spin on the spot. It cannot turn there (its diagonal is 0.35 m); rapier's soft
//! contacts with fixed bodies (60 Hz) let its corners sink into both, and after 4–5 s the solver
//! throws it across the room at about 20 m/s. Prints, per turn rate and gap, the largest speed
//! of the body between two steps and where it ends after 8 s.
//!
//! `cargo run --release -p sim --example wedge`
use robot_model::kinematics::{MecanumKinematics, rad_s_to_rpm};
use robot_model::pose::{Pose2, Twist};
use robot_model::profile::RobotProfile;
use robot_model::time::Duration;
use sim::body::RobotBody;
use sim::scenario::Scenario;

const DT: Duration = Duration::from_millis(5);

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let profile = RobotProfile::default();
    let half_width = profile.geometry.body_width_m / 2.0;
    for omega in [0.5f32, 1.0, 3.0] {
        for gap in [0.002f32, 0.01] {
            let text = format!(
                "Scenario(name: \"wedge\", room: [(-5.0, -5.0), (5.0, -5.0), (5.0, 5.0), (-5.0, 5.0)], \
                 start: (row: 0, col: 0, heading: East), obstacles: [\
                 Circle(center: ({lamp}, 0.0), radius: 0.183), Box(center: ({sofa}, 0.0), size: (1.0, 1.0))])",
                lamp = -(half_width + gap + 0.183),
                sofa = half_width + gap + 0.5,
            );
            let scenario = Scenario::from_ron_str(&text, "wedge.ron")?;
            let start = Pose2::new(0.0, 0.0, -std::f32::consts::FRAC_PI_2);
            let mut body = RobotBody::new(&scenario, &profile, start, DT);
            let setpoints = MecanumKinematics::from_profile(&profile)
                .inverse(Twist { vx: 0.0, vy: 0.0, omega })
                .map(rad_s_to_rpm);
            let (mut fastest, mut at_s, mut last) = (0.0f32, 0.0f32, body.pose());
            for step in 0..1600 {
                body.step(setpoints);
                let p = body.pose();
                let speed = (p.x - last.x).hypot(p.y - last.y) / DT.as_secs_f32();
                if speed > fastest {
                    (fastest, at_s) = (speed, step as f32 * DT.as_secs_f32());
                }
                last = p;
            }
            println!(
                "turn {omega} rad/s, gap {gap} m: fastest {fastest:.2} m/s at {at_s:.2} s, ends at ({:.2}, {:.2}), {} contacts",
                last.x,
                last.y,
                body.world().collisions()
            );
        }
    }
    Ok(())
}
