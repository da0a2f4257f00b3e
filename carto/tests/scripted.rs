//! Carto against scripted boards: bytes only, with the kinematic fake robot of `fake/`.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod fake;

use fake::{Harness, POSE};
use protocol::link::{Command, Direction, GuiMessage};
use robot_model::grid::Heading;
use robot_model::time::{Duration, Instant};

fn cartography(command: Command) -> GuiMessage {
    GuiMessage::SendMoveCartography { command }
}

fn traj(n_total: u8, command: Command) -> GuiMessage {
    GuiMessage::SendMovesTrajectory { n_total, command }
}

/// A harness with sensors flowing and the pose (5, 5) facing EAST acknowledged.
fn ready() -> Harness {
    Harness::ready()
}

fn yaw_deg(h: &Harness) -> f64 {
    h.robot.yaw.to_degrees()
}

fn forward_clear_moves_one_cell(telemetry: bool) {
    let mut h = ready();
    h.robot.send_telemetry = telemetry;
    h.run_ms(100);
    let (x0, y0) = (h.robot.x, h.robot.y);
    h.send(cartography(Command::Forward));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1), "no MOVE_DONE");
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetRobotPosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    let d = h.distance_from(x0, y0);
    assert!((d - 0.30).abs() <= 0.01, "travelled {d:.4} m");
    assert!(yaw_deg(&h).abs() <= 2.0, "drifted to {:.2}°", yaw_deg(&h));
    assert!(!h.robot.moving(), "wheels still turning at MOVE_DONE");
    assert_eq!(h.carto.status().pose.map(|p| (p.x, p.y)), Some((5, 6)));
    assert_eq!(h.carto.stats().pilot.moves_done, 1);
}

#[test]
fn cartography_forward_clear_drives_one_cell_on_encoders() {
    forward_clear_moves_one_cell(false);
}

#[test]
fn cartography_forward_clear_with_motor_telemetry() {
    forward_clear_moves_one_cell(true);
}

#[test]
fn cartography_forward_blocked_reports_obstacle_without_motion() {
    let mut h = ready();
    h.robot.distance_cm = 20.0;
    h.run_ms(150);
    let since = h.now;
    h.send(cartography(Command::Forward));
    assert!(h.run_until(3000, |h| h.move_done_count() == 1));
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetObstaclePosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    assert!(h.robot.drives_since(since).iter().all(|(_, d)| d.is_stop()), "a non-zero drive was sent");
    assert!(h.distance_from(0.0, 0.0) < 1e-6);
    assert_eq!(h.carto.status().pose.map(|p| (p.x, p.y)), Some((5, 5)));
}

#[test]
fn cartography_forward_threshold_is_one_cell_and_no_echo_is_clear() {
    let mut h = ready();
    h.robot.distance_cm = 31.0; // just beyond one cell: clear
    h.run_ms(150);
    h.send(cartography(Command::Forward));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1));
    assert_eq!(h.replies[0].1, GuiMessage::SetRobotPosition { x: 5, y: 6 });
    // (a second FORWARD here would be refused: the echo 31 cm ahead is remembered, 1 cm in
    // front of the body now)
    let mut h = ready();
    h.robot.distance_cm = -1.0; // no echo: clear
    h.run_ms(150);
    h.send(cartography(Command::Forward));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1));
    assert_eq!(h.replies[0].1, GuiMessage::SetRobotPosition { x: 5, y: 6 });
}

#[test]
fn cartography_right_turns_minus_90_ccw_and_updates_heading() {
    let mut h = ready();
    h.send(cartography(Command::Right));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1));
    assert_eq!(h.reply_msgs(), vec![GuiMessage::MoveDone]);
    let yaw = yaw_deg(&h);
    assert!((yaw + 90.0).abs() <= 2.0, "yaw {yaw:.2}°");
    assert!(h.distance_from(0.0, 0.0) < 0.01, "turned in place");
    let pose = h.carto.status().pose.unwrap();
    assert_eq!(pose.heading, Heading::South);
    // FORWARD now goes south: row + 1
    h.replies.clear();
    h.send(cartography(Command::Forward));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1));
    assert_eq!(h.replies[0].1, GuiMessage::SetRobotPosition { x: 6, y: 5 });
}

#[test]
fn cartography_left_turns_plus_90_ccw() {
    let mut h = ready();
    h.send(cartography(Command::Left));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1));
    let yaw = yaw_deg(&h);
    assert!((yaw - 90.0).abs() <= 2.0, "yaw {yaw:.2}°");
    assert_eq!(h.carto.status().pose.unwrap().heading, Heading::North);
}

#[test]
fn four_rights_come_back_to_the_start_heading_without_accumulating_error() {
    let mut h = ready();
    for i in 1..=4 {
        h.send(cartography(Command::Right));
        assert!(h.run_until(8000, |h| h.move_done_count() == i));
    }
    let yaw = yaw_deg(&h);
    assert!((yaw + 360.0).abs() <= 2.0, "yaw {yaw:.2}°");
}

#[test]
fn trajectory_batch_of_6_reports_each_forward_then_one_move_done() {
    let mut h = ready();
    let cmds = [
        Command::Forward,
        Command::Forward,
        Command::Right,
        Command::Forward,
        Command::Left,
        Command::Forward,
    ];
    for c in cmds {
        h.send(traj(6, c));
    }
    assert!(h.run_until(40_000, |h| h.move_done_count() == 1), "batch did not finish");
    assert_eq!(
        h.reply_msgs(),
        vec![
            GuiMessage::SetRobotPosition { x: 5, y: 6 },
            GuiMessage::SetRobotPosition { x: 5, y: 7 },
            GuiMessage::SetRobotPosition { x: 6, y: 7 },
            GuiMessage::SetRobotPosition { x: 6, y: 8 },
            GuiMessage::MoveDone,
        ]
    );
    // World: +x is EAST (y on the grid), −world y is SOUTH. Expected (0.9, −0.3).
    assert!(
        (h.robot.x - 0.90).abs() < 0.03 && (h.robot.y + 0.30).abs() < 0.03,
        "at ({:.3}, {:.3})",
        h.robot.x,
        h.robot.y
    );
    assert_eq!(h.carto.stats().pilot.moves_done, 6);
}

#[test]
fn trajectory_without_pose_runs_but_reports_no_positions() {
    let mut h = Harness::new();
    h.warm_up();
    h.send(traj(2, Command::Forward));
    h.send(traj(2, Command::Forward));
    assert!(h.run_until(20_000, |h| h.move_done_count() == 1));
    assert_eq!(h.reply_msgs(), vec![GuiMessage::MoveDone]);
    assert!((h.robot.x - 0.60).abs() < 0.02);
}

#[test]
fn trajectory_obstacle_before_a_forward_aborts_the_rest() {
    let mut h = ready();
    for c in [Command::Forward, Command::Forward, Command::Forward] {
        h.send(traj(3, c));
    }
    // Block the way once the first SET_ROBOT_POSITION is out.
    assert!(h.run_until(8000, |h| !h.replies.is_empty()));
    h.robot.distance_cm = 15.0;
    assert!(h.run_until(8000, |h| h.move_done_count() == 1));
    assert_eq!(
        h.reply_msgs(),
        vec![
            GuiMessage::SetRobotPosition { x: 5, y: 6 },
            GuiMessage::SetObstaclePosition { x: 5, y: 7 },
            GuiMessage::MoveDone
        ]
    );
    assert!((h.robot.x - 0.30).abs() < 0.015);
}

#[test]
fn trajectory_accumulation_rules() {
    let mut h = ready();
    // n_total 0 is ignored; a different n_total discards the partial batch.
    h.send(traj(0, Command::Forward));
    h.send(traj(3, Command::Forward));
    h.send(traj(3, Command::Forward));
    h.send(traj(1, Command::Right)); // discards the two FORWARDs, and completes at once
    assert!(h.run_until(8000, |h| h.move_done_count() == 1));
    assert_eq!(h.reply_msgs(), vec![GuiMessage::MoveDone]);
    assert!(h.distance_from(0.0, 0.0) < 0.01, "a discarded FORWARD ran");
    assert!((yaw_deg(&h) + 90.0).abs() <= 2.0);
    assert_eq!(h.carto.status().pending, 0);
}

#[test]
fn stop_mid_batch_zeroes_the_drive_at_once_and_drops_the_rest() {
    let mut h = ready();
    for _ in 0..6 {
        h.send(traj(6, Command::Forward));
    }
    assert!(h.run_until(8000, |h| h.replies.len() == 1), "first FORWARD did not finish");
    h.run_ms(200); // in the middle of the second FORWARD
    assert!(h.robot.moving());
    let stop_at = h.now;
    h.send(GuiMessage::StopRobot);
    let after = h.robot.drives_since(stop_at);
    assert!(
        after
            .first()
            .is_some_and(|(t, d)| d.is_stop() && t.saturating_since(stop_at) <= Duration::from_millis(100))
    );
    h.run_ms(3000);
    assert!(h.robot.drives_since(stop_at).iter().all(|(_, d)| d.is_stop()), "a drive after STOP");
    assert!(!h.robot.moving());
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetRobotPosition { x: 5, y: 6 }], "STOP gets no reply");
    let st = h.carto.status();
    assert!(!st.busy && st.pending == 0);
    // Still serving: a new command runs.
    h.send(cartography(Command::Right));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1));
}

#[test]
fn client_disconnect_stops_the_motors_and_drops_pending() {
    let mut h = ready();
    h.send(cartography(Command::Forward));
    h.send(cartography(Command::Forward));
    h.run_ms(400);
    assert!(h.robot.moving());
    let t = h.now;
    h.carto.on_client_disconnected(h.now);
    h.pump();
    assert!(h.robot.drives_since(t).first().is_some_and(|(_, d)| d.is_stop()));
    h.run_ms(2000);
    assert!(h.robot.drives_since(t).iter().all(|(_, d)| d.is_stop()));
    assert!(!h.carto.status().busy);
    assert!(h.reply_msgs().is_empty());
    // The next client is served.
    h.carto.on_client_connected(h.now, "test:2");
    h.send(cartography(Command::Left));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1));
}

#[test]
fn cartography_without_pose_or_with_bad_command_gets_move_done_only() {
    let mut h = Harness::new();
    h.warm_up();
    h.send(cartography(Command::Forward));
    assert!(h.run_until(100, |h| h.move_done_count() == 1));
    assert_eq!(h.reply_msgs(), vec![GuiMessage::MoveDone]);
    h.replies.clear();
    h.send(POSE);
    h.send(cartography(Command::Stop));
    h.send(cartography(Command::Unknown(9)));
    assert!(h.run_until(100, |h| h.move_done_count() == 2));
    assert_eq!(
        h.reply_msgs(),
        vec![GuiMessage::RobotPositionReceived, GuiMessage::MoveDone, GuiMessage::MoveDone]
    );
    assert!(h.distance_from(0.0, 0.0) < 1e-9);
    assert_eq!(h.carto.stats().pilot.moves_failed, 3);
}

#[test]
fn forward_off_the_byte_grid_is_refused() {
    let mut h = Harness::new();
    h.warm_up();
    h.send(GuiMessage::SendRobotPosition { x: 0, y: 0, direction: Direction::North });
    h.send(cartography(Command::Forward));
    assert!(h.run_until(100, |h| h.move_done_count() == 1));
    assert_eq!(h.reply_msgs(), vec![GuiMessage::RobotPositionReceived, GuiMessage::MoveDone]);
}

#[test]
fn drive_frames_keep_the_board_watchdog_fed() {
    let mut h = ready();
    h.send(traj(2, Command::Forward));
    h.send(traj(2, Command::Right));
    assert!(h.run_until(20_000, |h| h.move_done_count() == 1));
    h.run_ms(2000);
    assert_eq!(h.robot.watchdog_trips, 0);
    let gaps: Vec<u64> = h.robot.drives.windows(2).map(|w| (w[1].0 - w[0].0).total_millis()).collect();
    assert!(gaps.iter().all(|g| *g <= 500), "gap above 500 ms: {gaps:?}");
    // While moving, every 100 ms at least.
    let moving: Vec<_> = h
        .robot
        .drives
        .windows(2)
        .filter(|w| !w[0].1.is_stop())
        .map(|w| (w[1].0 - w[0].0).total_millis())
        .collect();
    assert!(!moving.is_empty() && moving.iter().all(|g| *g <= 100), "{moving:?}");
    assert!(h.robot.drives.last().unwrap().1.is_stop());
}

#[test]
fn keep_state_goes_out_at_2hz_with_sequence_from_1() {
    let mut h = Harness::new();
    h.run_ms(2100);
    let seqs: Vec<u16> = h.robot.carto_keep_states.iter().map(|(_, s)| *s).collect();
    assert_eq!(seqs, vec![1, 2, 3, 4, 5]);
    let times: Vec<u64> = h.robot.carto_keep_states.iter().map(|(t, _)| t.total_millis()).collect();
    assert!(times.windows(2).all(|w| w[1] - w[0] == 500), "{times:?}");
}

#[test]
fn peer_lost_stops_the_motors_and_fails_the_move() {
    let mut h = ready();
    h.send(cartography(Command::Forward));
    h.run_ms(300);
    assert!(h.robot.moving());
    h.robot.send_keep_state = false;
    let silent_from = h.now;
    assert!(h.run_until(3000, |h| h.move_done_count() == 1), "no MOVE_DONE after peer loss");
    let lost_at = h.replies[0].0;
    assert!(lost_at.saturating_since(silent_from) <= Duration::from_millis(1600));
    assert_eq!(h.reply_msgs(), vec![GuiMessage::MoveDone]);
    assert!(h.robot.drives.last().unwrap().1.is_stop());
    let st = h.carto.stats();
    assert_eq!((st.peer_lost_events, st.pilot.moves_failed), (1, 1));
    assert!(!h.carto.status().sensor_board_ok);
    // While lost, moves are refused.
    h.send(cartography(Command::Right));
    assert!(h.run_until(100, |h| h.move_done_count() == 2));
    // Back: moves run again.
    h.robot.send_keep_state = true;
    h.run_ms(600);
    assert!(h.carto.status().sensor_board_ok);
    h.send(cartography(Command::Right));
    assert!(h.run_until(8000, |h| h.move_done_count() == 3));
    assert_eq!(h.carto.stats().pilot.moves_done, 1);
}

#[test]
fn bumper_during_forward_stops_reports_obstacle_and_backs_off() {
    let mut h = ready();
    h.send(cartography(Command::Forward));
    h.run_ms(500);
    assert!(h.robot.moving());
    let t = h.now;
    h.robot.bumper = true;
    h.run_ms(10);
    assert!(h.robot.drives_since(t).first().is_some_and(|(_, d)| d.is_stop()), "no stop after the bumper");
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetObstaclePosition { x: 5, y: 6 }]);
    h.robot.bumper = false;
    assert!(h.run_until(8000, |h| h.move_done_count() == 1));
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetObstaclePosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    assert!(h.distance_from(0.0, 0.0) <= 0.015, "not back at the start: {:.3}", h.distance_from(0.0, 0.0));
    assert_eq!(h.carto.status().pose.map(|p| (p.x, p.y)), Some((5, 5)));
    assert_eq!(h.carto.stats().pilot.bumps, 1);
}

#[test]
fn jammed_wheels_time_out_and_stop() {
    let cfg = fake::test_config_with(|c| c.motion.move_timeout = Duration::from_secs(2));
    let mut h = Harness::with_config(cfg);
    h.warm_up();
    h.send(POSE);
    h.robot.jammed = true;
    h.send(cartography(Command::Forward));
    assert!(h.run_until(3000, |h| h.move_done_count() == 1));
    assert_eq!(h.reply_msgs(), vec![GuiMessage::RobotPositionReceived, GuiMessage::MoveDone]);
    assert!(h.replies[1].0 >= Instant::from_millis(2500), "failed too early");
    assert!(h.robot.drives.last().unwrap().1.is_stop());
    assert_eq!(h.carto.stats().pilot.moves_failed, 1);
    assert_eq!(h.carto.status().pose.map(|p| (p.x, p.y)), Some((5, 5)));
}

#[test]
fn a_turn_jammed_part_way_is_turned_back_before_its_move_done() {
    let mut h = ready();
    // a leg stops the body 20° into a RIGHT; the wheels keep turning
    h.robot.yaw_min_deg = Some(-20.0);
    let t = h.now;
    h.send(cartography(Command::Right));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1));
    // given up on the jam, well before the 8 s move timeout
    let done = h.replies[0].0;
    assert!(
        done.saturating_since(t) < Duration::from_millis(4000),
        "MOVE_DONE after {:?}",
        done.saturating_since(t)
    );
    assert_eq!(h.reply_msgs(), vec![GuiMessage::MoveDone]);
    // back at the heading it started from, which Carto still stores
    assert!(h.robot.yaw.to_degrees().abs() <= 3.0, "yaw {:.1}°", h.robot.yaw.to_degrees());
    assert_eq!(h.carto.status().pose.map(|p| p.heading), Some(Heading::East));
    assert_eq!((h.carto.stats().pilot.moves_failed, h.carto.stats().pilot.turns_undone), (1, 1));
    // the next FORWARD holds EAST, not the angle the body jammed at
    h.robot.yaw_min_deg = None;
    h.robot.distance_cm = 200.0;
    h.send(cartography(Command::Forward));
    assert!(h.run_until(10_000, |h| h.move_done_count() == 2));
    assert!(h.robot.y.abs() <= 0.02, "drove {:.3} m off the row", h.robot.y);
    assert_eq!(h.carto.status().pose.map(|p| (p.x, p.y)), Some((5, 6)));
}

#[test]
fn no_distance_reading_at_rest_refuses_the_forward() {
    let mut h = ready();
    h.robot.send_distance = false;
    h.run_ms(400); // the last reading is now older than distance_max_age (300 ms)
    let t = h.now;
    h.send(cartography(Command::Forward));
    assert!(h.run_until(3000, |h| h.move_done_count() == 1));
    assert_eq!(h.reply_msgs(), vec![GuiMessage::MoveDone]);
    assert!(h.robot.drives_since(t).iter().all(|(_, d)| d.is_stop()));
    // A reading from before the last move does not count either: after a turn, a fresh one is needed.
    h.robot.send_distance = true;
    h.send(cartography(Command::Right));
    assert!(h.run_until(8000, |h| h.move_done_count() == 2));
    h.robot.send_distance = false;
    h.send(cartography(Command::Forward));
    assert!(h.run_until(3000, |h| h.move_done_count() == 3));
    assert_eq!(h.carto.status().pose.map(|p| (p.x, p.y)), Some((5, 5)));
}

/// Runs `n` cartography FORWARDs from (5, 5) facing EAST; returns the robot's (x, y) after each.
fn forwards(h: &mut Harness, n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for i in 1..=n {
        h.send(cartography(Command::Forward));
        assert!(h.run_until(10_000, |h| h.move_done_count() == i), "FORWARD {i} did not finish");
        out.push((h.robot.x, h.robot.y));
    }
    out
}

#[test]
fn forward_targets_are_absolute_so_a_systematic_overshoot_does_not_accumulate() {
    let mut h = ready();
    // The motor board applies every frame 50 ms late: every stop lands ~5 mm too far, which the
    // ±1 cm settle accepts. With relative targets that would add up to ~10 cm over 20 cells.
    h.robot.send_telemetry = true;
    h.robot.drive_delay = Duration::from_millis(50);
    let ends = forwards(&mut h, 20);
    // The plant really overshoots (the first FORWARD, before anything is learnt).
    assert!(ends[0].0 - 0.30 > 0.002, "first FORWARD ended at {:.4}: no overshoot to correct", ends[0].0);
    for (i, (x, y)) in ends.iter().enumerate() {
        let along = x - 0.30 * (i + 1) as f64;
        assert!(along.abs() <= 0.01, "FORWARD {}: {along:+.4} m from the cell centre", i + 1);
        assert!(y.abs() <= 0.01, "FORWARD {}: {y:+.4} m off the track", i + 1);
    }
    // and the learnt stop point brings the last ones close to the centre
    let last = ends[19].0 - 6.0;
    assert!(last.abs() <= 0.003, "after learning the overshoot: {last:+.4} m");
    assert_eq!(h.carto.status().pose.map(|p| (p.x, p.y)), Some((5, 25)));
}

#[test]
fn lateral_drift_from_mismatched_wheels_is_strafed_back() {
    let mut h = ready();
    // FL and RR turn 10 % slow: the robot crabs to the left by ~5 % of the distance driven
    // (1.5 cm a cell; 15 cm over ten cells without correction).
    h.robot.wheel_gain = [0.9, 1.0, 1.0, 0.9];
    let ends = forwards(&mut h, 10);
    for (i, (x, y)) in ends.iter().enumerate() {
        assert!(y.abs() <= 0.01, "FORWARD {}: {y:+.4} m off the track", i + 1);
        assert!((x - 0.30 * (i + 1) as f64).abs() <= 0.015, "FORWARD {}: x {x:.4}", i + 1);
    }
    assert!(yaw_deg(&h).abs() <= 2.0, "heading {:.2}°", yaw_deg(&h));
}

#[test]
fn forward_after_a_stop_mid_move_completes_to_the_next_cell_centre() {
    let mut h = ready();
    h.send(cartography(Command::Forward));
    h.run_ms(700); // part of the way
    h.send(GuiMessage::StopRobot);
    h.run_ms(1000);
    let stopped = h.robot.x;
    assert!(stopped > 0.03 && stopped < 0.27, "stopped at {stopped:.3}");
    assert_eq!(
        h.carto.status().pose.map(|p| (p.x, p.y)),
        Some((5, 5)),
        "a stopped move does not move the pose"
    );
    h.send(cartography(Command::Forward));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1));
    assert!((h.robot.x - 0.30).abs() <= 0.01, "ended at {:.4}, not at the next cell's centre", h.robot.x);
    assert_eq!(h.carto.status().pose.map(|p| (p.x, p.y)), Some((5, 6)));
}

#[test]
fn a_turn_cut_by_a_stop_is_turned_back_before_the_next_forward() {
    let mut h = ready();
    h.send(cartography(Command::Right));
    assert!(h.run_until(8000, |h| (-60.0..=-30.0).contains(&yaw_deg(h))), "the turn did not get under way");
    h.send(GuiMessage::StopRobot);
    h.run_ms(1000);
    let cut = yaw_deg(&h);
    assert!(cut < -20.0, "stopped at {cut:.1}°");
    assert_eq!(h.carto.status().pose.map(|p| p.heading), Some(Heading::East), "a cut turn turned the pose");
    h.replies.clear();
    h.send(cartography(Command::Forward));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1), "no MOVE_DONE for the FORWARD");
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetRobotPosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    // it faced EAST again first, then drove one cell east (learning the heading from the IMU
    // instead would have driven it off at the angle the turn was cut)
    assert!(yaw_deg(&h).abs() <= 2.0, "heading {:.1}°", yaw_deg(&h));
    assert!((h.robot.x - 0.30).abs() <= 0.015, "ended at x {:.3}", h.robot.x);
    assert!(h.robot.y.abs() <= 0.02, "ended {:.3} m off the row", h.robot.y);
}

/// STOP part of the way through a FORWARD and ask for a RIGHT at once (with the encoders muted
/// from the STOP on unless `encoders`); returns how long after the zero drive the turn's first
/// drive came. The turn must have completed.
fn right_at_once_after_a_stop_mid_forward(encoders: bool) -> Duration {
    let mut h = ready();
    h.send(cartography(Command::Forward));
    h.run_ms(700); // part of the way, still driving
    h.robot.send_encoders = encoders;
    let stop_at = h.now;
    h.send(GuiMessage::StopRobot);
    h.send(cartography(Command::Right));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1));
    assert!((yaw_deg(&h) + 90.0).abs() <= 2.0, "heading {:.2}°", yaw_deg(&h));
    let drives = h.robot.drives_since(stop_at);
    let zero = drives.iter().find(|(_, d)| d.is_stop()).map(|(t, _)| *t).expect("a zero drive after STOP");
    let turn = drives.iter().find(|(_, d)| d.omega != 0).map(|(t, _)| *t).expect("the turn's drive");
    turn.saturating_since(zero)
}

#[test]
fn a_turn_right_after_a_stop_mid_move_waits_until_the_robot_is_at_rest() {
    let waited = right_at_once_after_a_stop_mid_forward(true);
    // settle_time (200 ms) plus at most one encoder period (200 ms) and the link's byte time.
    assert!(
        waited >= Duration::from_millis(200) && waited <= Duration::from_millis(450),
        "the turn started {} ms after the zero drive",
        waited.total_millis()
    );
}

#[test]
fn a_turn_after_a_stop_without_encoder_readings_waits_the_settle_time_and_turns() {
    let waited = right_at_once_after_a_stop_mid_forward(false);
    // Until the encoder readings are stale (600 ms after the last one), not until a timeout.
    assert!(
        waited >= Duration::from_millis(200) && waited <= Duration::from_millis(850),
        "the turn started {} ms after the zero drive",
        waited.total_millis()
    );
}

#[test]
fn a_turn_after_a_finished_forward_starts_at_once() {
    let mut h = ready();
    h.send(cartography(Command::Forward));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1));
    let asked_at = h.now;
    h.send(cartography(Command::Right));
    assert!(h.run_until(8000, |h| h.move_done_count() == 2));
    let drives = h.robot.drives_since(asked_at);
    let turn = drives.iter().find(|(_, d)| d.omega != 0).map(|(t, _)| *t).expect("the turn's drive");
    let waited = turn.saturating_since(asked_at);
    assert!(
        waited <= Duration::from_millis(20),
        "the turn started {} ms after it was asked",
        waited.total_millis()
    );
}

#[test]
fn resending_the_held_pose_keeps_the_cell_offset_and_a_new_pose_resets_it() {
    let mut h = ready();
    let origin = h.robot.x;
    h.send(cartography(Command::Forward));
    h.run_ms(700);
    h.send(GuiMessage::StopRobot);
    h.run_ms(1000);
    let stopped = h.robot.x;
    // Cute re-sends the pose Carto already holds (as after a reconnect): the FORWARD cut short
    // still counts, and the next FORWARD ends on the next cell's centre.
    h.send(POSE);
    h.replies.clear();
    h.send(cartography(Command::Forward));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1));
    let first_cell_end = h.robot.x;
    assert!(
        stopped - origin > 0.05,
        "the first FORWARD was cut short after moving: {:.4} m",
        stopped - origin
    );
    let error = first_cell_end - origin - 0.30;
    assert!(error.abs() <= 0.01, "ended {error:+.4} m from the next cell's centre");
    // A different pose names another cell: the robot is taken to be at its centre and the next
    // FORWARD drives a whole cell.
    let moved = match POSE {
        GuiMessage::SendRobotPosition { x, y, direction } => {
            GuiMessage::SendRobotPosition { x, y: y + 3, direction }
        }
        other => other,
    };
    h.send(moved);
    h.replies.clear();
    h.send(cartography(Command::Forward));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1));
    let d = h.robot.x - first_cell_end;
    assert!((d - 0.30).abs() <= 0.01, "drove {d:.4} m after a new pose");
}

#[test]
fn offset_along_the_old_heading_becomes_lateral_after_a_turn() {
    let mut h = ready();
    h.robot.send_telemetry = true;
    h.robot.drive_delay = Duration::from_millis(50); // the first FORWARD overshoots
    let first = forwards(&mut h, 1)[0].0;
    let over = first - 0.30;
    assert!(over > 0.003, "overshoot {over:.4}");
    // Turn left (to NORTH, +y): the overshoot along x is now to the robot's right, and the next
    // FORWARD strafes it away.
    h.robot.drive_delay = Duration::ZERO;
    h.send(cartography(Command::Left));
    assert!(h.run_until(8000, |h| h.move_done_count() == 2));
    h.send(cartography(Command::Forward));
    assert!(h.run_until(10_000, |h| h.move_done_count() == 3));
    assert!(
        (h.robot.x - 0.30).abs() < over.min(0.01) * 0.6,
        "x {:.4}: the offset was not strafed back",
        h.robot.x
    );
    assert!((h.robot.y - 0.30).abs() <= 0.01, "y {:.4}", h.robot.y);
}
