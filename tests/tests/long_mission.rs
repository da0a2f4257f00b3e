//! Issue 10, "a 30-minute mission keeps the position error within 5 cm": two full sweeps of an
//! empty 10 × 10 m hall back to back (`scenarios/long/open-hall-10x10.ron`, 37 simulated
//! minutes, 1,053 moves). Over seeds 0–30, 29 of 31 runs keep within 5 cm (README, "Long
//! missions"); this test runs the file's seed and seeds 1 and 2 and asserts every expectation of
//! the file: 100 % coverage, no collision, position error ≤ 5 cm, heading error ≤ 3°, and Cute's
//! final cell the true one. Before the IMU smoothing and the wall fix (`carto/README.md`) these
//! three seeds ended 10.3, 7.1 and 14.5 cm off.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::Path;

use sim::runner::Lockstep;
use sim::scenario::LoadedScenario;

#[test]
fn a_37_minute_sweep_of_an_empty_hall_stays_within_5_cm() {
    let path = Path::new("../scenarios/long/open-hall-10x10.ron");
    for seed in [None, Some(1), Some(2)] {
        let loaded = LoadedScenario::load(path).unwrap();
        let mut run = Lockstep::new(loaded, seed).unwrap();
        run.run_to_end(|_| {});
        let r = run.report(1.0);
        println!(
            "seed {seed:?}: position error max {:.1} cm, heading error max {:.1}°",
            100.0 * r.localisation.position_error_max_m,
            r.localisation.heading_error_max_deg
        );
        assert!(r.sim_time_s > 30.0 * 60.0, "seed {seed:?}: the mission is shorter than 30 minutes");
        assert!(r.passed, "seed {seed:?}:\n{}", r.to_text());
    }
}
