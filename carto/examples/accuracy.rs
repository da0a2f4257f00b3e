//! Measures Carto's move accuracy and duration against robot-model's board twins (see
//! `tests/twin/mod.rs`): for each seed, FORWARD, RIGHT, FORWARD, LEFT from rest; prints the error
//! of every move against the true pose, and the worst and mean over all seeds.
//!
//! ```text
//! cargo run --release -p carto --example accuracy -- [SEEDS]
//! ```

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[path = "../tests/twin/mod.rs"]
mod twin;

use protocol::link::{Command, Direction, GuiMessage};
use twin::Twin;

fn main() {
    let seeds: u64 = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(50);
    let (mut fwd, mut turn, mut fwd_t, mut turn_t, mut failed) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), 0);
    for seed in 1..=seeds {
        let mut t = Twin::new(seed);
        for _ in 0..600 {
            t.tick();
        }
        t.send(GuiMessage::SendRobotPosition { x: 5, y: 5, direction: Direction::East });
        let plan = [
            (Command::Forward, 0.0),
            (Command::Right, -90.0),
            (Command::Forward, -90.0),
            (Command::Left, 0.0),
        ];
        let (mut px, mut py) = (0.0, 0.0);
        for (i, (cmd, yaw)) in plan.iter().enumerate() {
            let start = t.now;
            t.send(GuiMessage::SendMoveCartography { command: *cmd });
            if !t.run_until_move_done(i + 1, 20_000) {
                failed += 1;
                continue;
            }
            let secs = (t.now - start).as_secs_f64();
            if *cmd == Command::Forward {
                let d = (t.x - px).hypot(t.y - py);
                fwd.push((d - 0.30) * 1000.0);
                fwd_t.push(secs);
            } else {
                turn.push(t.theta.to_degrees() - yaw);
                turn_t.push(secs);
            }
            (px, py) = (t.x, t.y);
        }
        failed += t.rt.carto().stats().pilot.moves_failed as usize;
    }
    let stats = |v: &[f64]| {
        let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
        let worst = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        (mean, worst)
    };
    let (fm, fw) = stats(&fwd);
    let (tm, tw) = stats(&turn);
    let (ftm, ftw) = stats(&fwd_t);
    let (ttm, ttw) = stats(&turn_t);
    println!("seeds: {seeds}, moves failed: {failed}");
    println!("FORWARD error (mm): mean {fm:+.2}, worst |{fw:.2}| over {} moves (tolerance 10)", fwd.len());
    println!("turn error (deg):   mean {tm:+.2}, worst |{tw:.2}| over {} moves (tolerance 2)", turn.len());
    println!("FORWARD time (s):   mean {ftm:.2}, worst {ftw:.2}");
    println!("turn time (s):      mean {ttm:.2}, worst {ttw:.2}");
}
