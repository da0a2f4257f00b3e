//! A sensor configuration that exceeds 9600 baud shows up as it would on the robot: the board
//! warns once, and over a baud-timed link the queue — and so the latency of every reading — grows.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use robot_model::boards::{SensorBoard, SensorInputs};
use robot_model::profile::RobotProfile;
use robot_model::time::{Duration, Instant};
use transport::{Link, MemLink, MemLinkConfig, MockClock};

/// Runs the sensor board for `seconds` into a 9600-baud link whose far end reads everything;
/// returns the link's backlog (µs of queued serial time) once per second.
fn backlog_per_second(profile: &RobotProfile, seconds: u64) -> (Vec<u64>, bool) {
    let clock = MockClock::new();
    let config = MemLinkConfig { capacity: 1 << 20, ..MemLinkConfig::with_baud(Some(9600)) };
    let (mut board_end, mut carto_end) = MemLink::pair_with(config, clock.clone());
    let mut board = SensorBoard::new(profile);
    let inputs = SensorInputs { distance_cm: Some(80.0), ..SensorInputs::default() };
    let mut pending: Vec<u8> = Vec::new();
    let mut buf = [0u8; 4096];
    let mut backlog = Vec::new();
    let step = Duration::from_millis(5);
    let mut now = Instant::ZERO;
    for i in 1..=(seconds * 200) {
        now += step;
        clock.set(Instant::from_micros(now.total_micros()));
        pending.extend(board.poll(now, &inputs));
        let n = board_end.write(&pending).unwrap();
        pending.drain(..n);
        while carto_end.read(&mut buf).unwrap() > 0 {}
        if i % 200 == 0 {
            backlog.push(board_end.stats().backlog.total_micros());
        }
    }
    (backlog, board.budget_warned())
}

#[test]
fn default_rates_fit_in_9600_baud_and_latency_stays_bounded() {
    let profile = RobotProfile::default();
    let (backlog, warned) = backlog_per_second(&profile, 10);
    assert!(!warned);
    // About 760 of 960 bytes/s: the queue drains between bursts.
    assert!(backlog.iter().all(|&b| b < 150_000), "{backlog:?}");
}

#[test]
fn rates_above_9600_baud_warn_and_latency_grows() {
    let mut profile = RobotProfile::default();
    profile.sensor_board.navx_hz = 25.0;
    profile.sensor_board.distance_hz = 50.0;
    let (backlog, warned) = backlog_per_second(&profile, 10);
    assert!(warned);
    // ~1790 bytes/s into a 960 bytes/s line: almost a second more latency every second.
    for pair in backlog.windows(2) {
        assert!(pair[1] > pair[0] + 500_000, "latency does not grow: {backlog:?}");
    }
}
