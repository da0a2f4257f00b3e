//! A stand-in for `explobot sim --serve`: the scripted fake robot of the tests, served in real
//! time on two pseudo-terminals (`run/tty-motor`, `run/tty-sensor` by default), so the `carto`
//! binary can be tried end to end without the simulator.
//!
//! ```text
//! cargo run --release -p carto --example fake_twin -- [DIR] [DISTANCE_CM]
//! cargo run --release -p carto --bin carto -- --transport sim --motor-port DIR/tty-motor --sensor-port DIR/tty-sensor
//! ```
//! It prints the fake robot's pose every second.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[path = "../tests/fake/mod.rs"]
mod fake;

use std::time::Duration as StdDuration;

use carto::CartoConfig;
use robot_model::time::Instant;
use transport::{Clock, Link, PtyLink, WallClock};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dir = args.next().unwrap_or_else(|| "run".to_owned());
    let distance: f32 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(-1.0);
    std::fs::create_dir_all(&dir)?;
    let mut motor = PtyLink::open_with_symlink(format!("{dir}/tty-motor"))?;
    let mut sensor = PtyLink::open_with_symlink(format!("{dir}/tty-sensor"))?;
    eprintln!("fake twin: motor {} sensor {}", motor.slave_path().display(), sensor.slave_path().display());
    let mut robot = fake::FakeRobot::new(CartoConfig::default());
    robot.distance_cm = distance;
    robot.send_telemetry = true;
    let clock = WallClock::start();
    let mut last = Instant::ZERO;
    let mut next_print = 0u64;
    let mut buf = [0u8; 1024];
    loop {
        let now = clock.now();
        let dt = now.saturating_since(last).as_secs_f64();
        last = now;
        robot.step(now, dt);
        let (m, s) = robot.emit(now);
        motor.write(&m)?;
        sensor.write(&s)?;
        while let Ok(n @ 1..) = motor.read(&mut buf) {
            robot.motor_rx(now, &buf[..n]);
        }
        while let Ok(n @ 1..) = sensor.read(&mut buf) {
            robot.sensor_rx(now, &buf[..n]);
        }
        if now.total_millis() >= next_print {
            next_print += 1000;
            println!(
                "t={:.1}s x={:.4} y={:.4} yaw={:.2}° drives={} keep-states={}",
                now.as_secs_f64(),
                robot.x,
                robot.y,
                robot.yaw.to_degrees(),
                robot.drives.len(),
                robot.carto_keep_states.len()
            );
        }
        std::thread::sleep(StdDuration::from_millis(1));
    }
}
