//! Issue 10, "turns are safe": Carto checks turns and FORWARDs against the sonar echoes it
//! remembers (`carto::surroundings`, `pilot/safety.rs`), with the kinematic fake robot of `fake/`.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod fake;

use carto::CartoConfig;
use fake::{Harness, POSE};
use protocol::link::{Command, Direction, GuiMessage};

fn cartography(command: Command) -> GuiMessage {
    GuiMessage::SendMoveCartography { command }
}

fn ready_with(cfg: CartoConfig) -> Harness {
    let mut h = Harness::with_config(cfg);
    h.warm_up();
    h.send(POSE);
    assert_eq!(h.reply_msgs(), vec![GuiMessage::RobotPositionReceived]);
    h.replies.clear();
    h
}

/// A FORWARD against a wall `cm` ahead: refused, the echo remembered.
fn blocked_forward(h: &mut Harness, cm: f32) {
    h.robot.distance_cm = cm;
    h.run_ms(150);
    let done = h.move_done_count();
    h.send(cartography(Command::Forward));
    assert!(h.run_until(3000, |h| h.move_done_count() == done + 1));
    assert!(h.reply_msgs().contains(&GuiMessage::SetObstaclePosition { x: 5, y: 6 }) || done > 0);
}

/// Runs until the `n`th MOVE_DONE (at most 12 s), returning the largest `f(&h)` seen on the way.
fn run_to_move_done_tracking(h: &mut Harness, n: usize, f: impl Fn(&Harness) -> f64) -> f64 {
    let mut most = f64::MIN;
    for _ in 0..12_000 {
        most = most.max(f(h));
        h.run_ms(1);
        if h.move_done_count() == n {
            break;
        }
    }
    assert_eq!(h.move_done_count(), n, "no MOVE_DONE number {n}");
    most
}

#[test]
fn a_turn_beside_a_wall_ahead_backs_off_first_and_drives_back_to_the_centre_before_its_move_done() {
    let mut h = ready_with(fake::test_config());
    blocked_forward(&mut h, 3.0); // the wall 16 cm from the centre, inside the 19.7 cm circle
    let x0 = h.robot.x;
    h.send(cartography(Command::Right));
    let back = run_to_move_done_tracking(&mut h, 2, |h| x0 - h.robot.x);
    let stats = h.carto.stats();
    assert_eq!(
        (stats.pilot.turns_shifted, stats.pilot.turns_refused, stats.pilot.turns_recentred),
        (1, 0, 1)
    );
    // it backed off (west, -x) far enough that the circle clears the echo, turned there, and
    // was back at the centre when the MOVE_DONE went out
    assert!((0.03..=0.06).contains(&back), "backed off {back:.3} m");
    assert!((h.robot.x - x0).abs() <= 0.015, "ended {:.3} m from the centre", h.robot.x - x0);
    assert!((h.robot.yaw.to_degrees() + 90.0).abs() <= 2.0, "yaw {:.1}", h.robot.yaw.to_degrees());
    assert_eq!(h.carto.status().pose.map(|p| p.heading), Some(robot_model::grid::Heading::South));
}

#[test]
fn after_a_turn_on_the_spot_the_shift_before_the_next_turn_goes_back_the_way_the_body_came() {
    let mut h = ready_with(fake::test_config());
    // east into the next cell, then a turn to face south
    h.robot.distance_cm = 80.0;
    h.run_ms(150);
    h.send(cartography(Command::Forward));
    assert!(h.run_until(20000, |h| h.move_done_count() == 1), "no FORWARD");
    h.send(cartography(Command::Right));
    assert!(h.run_until(20000, |h| h.move_done_count() == 2), "no turn");
    // a wall 19 cm south of the centre, inside the 19.7 cm turning circle: the FORWARD is
    // refused, the RIGHT must shift first. Backing off (north) 2 cm would clear it, but north of
    // the body no reading ever looked; 6 cm west, back along the row it drove, clears it too
    blocked_forward(&mut h, 6.0);
    let (x0, y0) = (h.robot.x, h.robot.y);
    h.send(cartography(Command::Right));
    let (mut north, mut west) = (f64::MIN, f64::MIN);
    for _ in 0..12_000 {
        (north, west) = (north.max(h.robot.y - y0), west.max(x0 - h.robot.x));
        h.run_ms(1);
        if h.move_done_count() == 4 {
            break;
        }
    }
    assert_eq!(h.move_done_count(), 4, "no MOVE_DONE for the second RIGHT");
    assert_eq!(h.carto.stats().pilot.turns_shifted, 1, "{:?}", h.carto.stats());
    // north of the body, behind its new heading, no reading ever looked: it stays where it was;
    // west, along the row it drove, it shifts until the circle clears the wall
    assert!(north <= 0.005, "shifted {north:.3} m north, behind the heading it turned to");
    assert!(west >= 0.05, "shifted only {west:.3} m west, the way it came");
}

#[test]
fn a_turn_made_off_the_centre_drives_back_only_as_far_as_a_known_surface_allows() {
    // a 5 cm clearance, so that the surface bars a good part of the way back, and 0.45 m cells,
    // so that a shift may reach 11 cm
    let mut h = ready_with(fake::test_config_with(|c| {
        c.safety.clearance_m = 0.05;
        c.cell_size_m = 0.45;
    }));
    h.robot.distance_cm = -1.0;
    h.run_ms(150);
    // a floor plan with one point 13.5 cm east of cell (5, 5)'s centre, 5 mm ahead of the front
    // face: inside the 22.7 cm turning circle, so the RIGHT first backs off 10 cm west. Facing
    // SOUTH, the body and its clearance reach 17 cm east: the way back ends 3.5 cm short of
    // the centre
    h.carto.add_known_surfaces([(5.0 * 0.45 + 0.135, -5.0 * 0.45)]);
    let x0 = h.robot.x;
    h.send(cartography(Command::Right));
    let back = run_to_move_done_tracking(&mut h, 1, |h| x0 - h.robot.x);
    assert!((0.09..=0.11).contains(&back), "backed off {back:.3} m");
    let stats = h.carto.stats();
    assert_eq!((stats.pilot.turns_shifted, stats.pilot.turns_recentred), (1, 1));
    let west = x0 - h.robot.x;
    assert!((0.03..=0.05).contains(&west), "stands {west:.3} m west of the centre");
    assert!((h.robot.yaw.to_degrees() + 90.0).abs() <= 2.0, "yaw {:.1}", h.robot.yaw.to_degrees());
}

#[test]
fn a_turn_between_two_close_walls_is_refused() {
    let mut h = ready_with(fake::test_config());
    blocked_forward(&mut h, 3.0); // wall east, 16 cm from the centre
    h.send(cartography(Command::Right));
    h.send(cartography(Command::Right));
    assert!(h.run_until(20000, |h| h.move_done_count() == 3), "turns did not finish");
    // facing west, 3-4 cm west of the centre after the first shift: a wall 3 cm ahead again
    h.robot.distance_cm = 3.0;
    h.run_ms(150);
    h.send(cartography(Command::Forward));
    assert!(h.run_until(3000, |h| h.move_done_count() == 4));
    let yaw = h.robot.yaw;
    h.send(cartography(Command::Left));
    assert!(h.run_until(8000, |h| h.move_done_count() == 5));
    assert_eq!(h.carto.stats().pilot.turns_refused, 1, "{:?}", h.carto.stats());
    assert!((h.robot.yaw - yaw).abs() < 0.02, "the robot turned although it refused");
    assert_eq!(h.reply_msgs().last(), Some(&GuiMessage::MoveDone));
}

#[test]
fn the_scan_refuses_a_forward_with_an_echo_beside_the_path() {
    let mut h = ready_with(fake::test_config_with(|c| c.safety.scan_deg = Some(30.0)));
    h.robot.distance_cm = 80.0; // straight ahead: clear
    h.run_ms(150);
    h.send(cartography(Command::Forward));
    // once the robot has turned away from the grid heading, the sonar sees something close:
    // 12 cm at 30 degrees lies 12-13 cm left of the track, inside the 14 cm half corridor
    assert!(h.run_until(3000, |h| h.robot.yaw.to_degrees() > 10.0), "no look to the left");
    h.robot.distance_cm = 12.0;
    assert!(h.run_until(20000, |h| h.move_done_count() == 1), "no MOVE_DONE");
    // the way is not clear, but nothing was met in the cell ahead: the robot stays in (5, 5)
    let refused = vec![
        GuiMessage::SetObstaclePosition { x: 5, y: 6 },
        GuiMessage::SetRobotPosition { x: 5, y: 5 },
        GuiMessage::MoveDone,
    ];
    assert_eq!(h.reply_msgs(), refused);
    assert_eq!(h.carto.stats().pilot.corridor_blocked, 1);
    assert!(h.distance_from(0.0, 0.0) < 0.01, "the robot drove");
    assert!(h.robot.yaw.to_degrees().abs() <= 2.5, "left facing {:.1} deg", h.robot.yaw.to_degrees());
}

/// Cell (5, 5) facing east, 0.45 m cells, the sonar hearing nothing: a FORWARD sent with a
/// known leg 16 cm ahead and 11 cm left of the centre line, 3 cm inside the 14 cm half corridor
/// and 16 cm behind the body at the next centre; with a floor plan (`plan`) or the leg's point
/// alone.
fn forward_past_a_leg(plan: bool) -> Harness {
    let mut h = ready_in_45_cm_cells();
    let leg = [(5.0 * 0.45 + 0.16, -5.0 * 0.45 + 0.11)];
    if plan {
        h.carto.add_floor_plan(leg);
    } else {
        h.carto.add_known_surfaces(leg);
    }
    h.send(cartography(Command::Forward));
    h
}

/// Runs the FORWARD of [`forward_past_a_leg`] (or the one back) to its MOVE_DONE, at most 30 s:
/// how far right the body went, and the smallest gap between its left flank and the leg.
fn past_the_leg(h: &mut Harness) -> (f64, f64) {
    let (mut rightmost, mut closest) = (0.0f64, f64::INFINITY);
    for _ in 0..30_000 {
        h.tick();
        rightmost = rightmost.min(h.robot.y);
        if (h.robot.x - 0.16).abs() <= 0.13 {
            closest = closest.min(0.11 - (h.robot.y + 0.12));
        }
        if h.move_done_count() == 1 {
            break;
        }
    }
    (rightmost, closest)
}

#[test]
fn a_forward_with_a_leg_in_its_corridor_slides_round_it_and_ends_at_the_next_centre() {
    // (in 0.30 m cells, a leg deep in the body grown by the clearance at the next centre:
    // refused, as the way is not clear)
    let mut h = forward_past_a_leg(true);
    let (rightmost, closest) = past_the_leg(&mut h);
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetRobotPosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    let stats = h.carto.stats();
    assert_eq!((stats.pilot.forwards_slid, stats.pilot.corridor_blocked), (1, 0));
    // slid right, passed the leg keeping (nearly) the clearance, and ended near the line at the
    // next centre
    assert!(rightmost <= -0.025, "slid only {rightmost:.3} m right");
    assert!(closest >= 0.01, "the body's flank passed {closest:.3} m from the leg");
    assert!((h.robot.x - 0.45).abs() <= 0.015, "drove {:.3} m", h.robot.x);
    assert!(h.robot.y.abs() <= 0.02, "ended {:.4} m left of the line", h.robot.y);
    // control, 0.30 m cells, the leg 16.5 cm ahead: it lies 1.5 cm deep in the clearance of the
    // body at the next centre (not in the body), deeper than the 1 cm a FORWARD may stop off it
    let mut h = ready_with(fake::test_config());
    h.robot.distance_cm = -1.0;
    h.run_ms(150);
    h.carto.add_floor_plan([(5.0 * 0.30 + 0.165, -5.0 * 0.30 + 0.11)]);
    h.send(cartography(Command::Forward));
    assert!(h.run_until(20000, |h| h.move_done_count() == 1), "no MOVE_DONE");
    assert_eq!(h.reply_msgs(), WAY_EAST_NOT_CLEAR);
    assert_eq!(h.carto.stats().pilot.forwards_slid, 0);
    assert!(h.distance_from(0.0, 0.0) < 0.01, "the robot drove");
    // control, 0.45 m cells, the leg known but no floor plan and nothing heard beside the line:
    // the space the slide would cross is not known free
    let mut h = forward_past_a_leg(false);
    assert!(h.run_until(20000, |h| h.move_done_count() == 1), "no MOVE_DONE");
    assert_eq!(h.reply_msgs(), WAY_EAST_NOT_CLEAR);
    assert_eq!(h.carto.stats().pilot.forwards_slid, 0);
}

/// After the first FORWARD's MOVE_DONE: turns round on the spot (`turn` twice), then sends the
/// FORWARD back with the straight reading at rest hearing an echo 20 cm ahead, within the
/// one-cell threshold (a FORWARD from anywhere else is refused for it). Replies start afresh.
fn turn_round_and_forward_back(h: &mut Harness, turn: Command) {
    assert!(h.run_until(30_000, |h| h.move_done_count() == 1), "no MOVE_DONE for the way in");
    for k in 0..2 {
        h.send(cartography(turn));
        assert!(h.run_until(20_000, |h| h.move_done_count() == k + 2), "turn {k} not done");
    }
    h.replies.clear();
    h.robot.distance_cm = 20.0;
    h.run_ms(150);
    h.send(cartography(Command::Forward));
}

/// Cell (5, 5) facing east in 0.45 m cells (the threshold one cell), the sonar hearing nothing.
fn ready_in_45_cm_cells() -> Harness {
    let mut h = ready_with(fake::test_config_with(|c| {
        c.cell_size_m = 0.45;
        c.safety.obstacle_threshold_cm = 45.0;
    }));
    h.robot.distance_cm = -1.0;
    h.run_ms(150);
    h
}

/// [`ready_in_45_cm_cells`], a FORWARD east sent; with a complete floor plan (`plan`) holding
/// nothing near.
fn forward_in_45_cm_cells(plan: bool) -> Harness {
    let mut h = ready_in_45_cm_cells();
    if plan {
        h.carto.add_floor_plan([(-5.0, -5.0)]); // a complete plan, nothing near
    }
    h.send(cartography(Command::Forward));
    h
}

#[test]
fn after_sliding_round_a_leg_and_turning_round_the_forward_back_goes_the_way_the_body_came() {
    let mut h = forward_past_a_leg(true);
    turn_round_and_forward_back(&mut h, Command::Left);
    let (rightmost, closest) = past_the_leg(&mut h);
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetRobotPosition { x: 5, y: 5 }, GuiMessage::MoveDone]);
    assert_eq!(h.carto.stats().pilot.forwards_slid, 2);
    // back past the leg on the side the way in took, keeping the clearance, to the first centre
    assert!(rightmost <= -0.025, "slid only {rightmost:.3} m right");
    assert!(closest >= 0.01, "the body's flank passed {closest:.3} m from the leg");
    assert!(h.distance_from(0.0, 0.0) <= 0.02, "ended {:.3} m from the centre", h.distance_from(0.0, 0.0));
    // a second FORWARD the same way (west, out of the first cell) was not slid in: refused
    h.replies.clear();
    h.send(cartography(Command::Forward));
    assert!(h.run_until(5000, |h| h.move_done_count() == 1), "no MOVE_DONE");
    assert!(h.reply_msgs().iter().any(|m| matches!(m, GuiMessage::SetObstaclePosition { .. })));
}

#[test]
fn with_a_floor_plan_the_forward_back_after_turning_round_is_made_whatever_echo_lies_ahead() {
    // a straight FORWARD east into (5, 6), a turn round on the spot, then the FORWARD back west
    // with an echo 20 cm ahead (a leg beside the way, say)
    let mut h = forward_in_45_cm_cells(true);
    turn_round_and_forward_back(&mut h, Command::Right);
    assert!(h.run_until(20_000, |h| h.move_done_count() == 1), "no MOVE_DONE for the way back");
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetRobotPosition { x: 5, y: 5 }, GuiMessage::MoveDone]);
    assert!(h.distance_from(0.0, 0.0) <= 0.02, "ended {:.3} m from the centre", h.distance_from(0.0, 0.0));
    // without a plan the same echo refuses the FORWARD back, as it refuses any
    let mut h = forward_in_45_cm_cells(false);
    turn_round_and_forward_back(&mut h, Command::Right);
    assert!(h.run_until(5000, |h| h.move_done_count() == 1));
    assert!(h.reply_msgs().contains(&GuiMessage::SetObstaclePosition { x: 5, y: 5 }), "{:?}", h.reply_msgs());
}

#[test]
fn a_stop_while_sliding_round_a_leg_stops_the_robot_and_answers_nothing() {
    // the slide of the test above, cut by a STOP once the body has slid 1.5 cm right
    let mut h = forward_past_a_leg(true);
    assert!(h.run_until(20_000, |h| h.robot.y <= -0.015), "no slide");
    h.send(GuiMessage::StopRobot);
    h.run_ms(1000);
    let (x, y) = (h.robot.x, h.robot.y);
    h.run_ms(2000);
    assert!((h.robot.x - x).hypot(h.robot.y - y) < 0.002, "still moving after the STOP");
    assert!(h.reply_msgs().is_empty(), "{:?}", h.reply_msgs());
    // the next FORWARD is planned afresh from where the body stopped, and made
    h.send(cartography(Command::Forward));
    assert!(h.run_until(30_000, |h| h.move_done_count() == 1), "no MOVE_DONE");
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetRobotPosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    assert!(
        (h.robot.x - 0.45).abs() <= 0.02 && h.robot.y.abs() <= 0.02,
        "ended at ({:.3}, {:.3})",
        h.robot.x,
        h.robot.y
    );
}

#[test]
fn a_bump_after_sliding_round_a_leg_backs_off_the_way_the_body_came() {
    // the slide of the tests above; the bumper pressed once the body has passed the leg
    let mut h = forward_past_a_leg(true);
    assert!(h.run_until(30_000, |h| h.robot.x >= 0.33), "did not pass the leg");
    h.robot.bumper = true;
    h.run_ms(200);
    h.robot.bumper = false;
    let mut closest = f64::INFINITY;
    for _ in 0..30_000 {
        h.tick();
        // beside the leg, the gap between the body's left flank and it
        if (h.robot.x - 0.16).abs() <= 0.13 {
            closest = closest.min(0.11 - (h.robot.y + 0.12));
        }
        if h.move_done_count() == 1 {
            break;
        }
    }
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetObstaclePosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    assert!(closest >= 0.01, "backing off, the body's flank passed {closest:.3} m from the leg");
    assert!(h.robot.x.hypot(h.robot.y) <= 0.03, "ended at ({:.3}, {:.3})", h.robot.x, h.robot.y);
}

/// An echo 44 cm ahead of the sonar (one cell's threshold is 45 cm) from a leg on the line,
/// 57 cm from the centre: the body at the next centre would reach 58 cm. The FORWARD is refused
/// either way; without a floor plan the cell ahead is reported occupied, while a floor plan that
/// holds the leg has the body fit in that cell 2 cm short of its centre, so only the way is
/// reported blocked, and Cute keeps the cell to reach another way.
#[test]
fn with_a_floor_plan_a_refusal_reports_the_cell_ahead_occupied_only_when_the_body_cannot_fit_there() {
    let leg = (5.0 * 0.45 + 0.57, -5.0 * 0.45);
    for plan in [true, false] {
        let mut h = ready_with(fake::test_config_with(|c| {
            c.cell_size_m = 0.45;
            c.safety.obstacle_threshold_cm = 45.0;
        }));
        h.robot.distance_cm = 44.0;
        h.run_ms(150);
        if plan {
            h.carto.add_floor_plan([leg]);
        } else {
            h.carto.add_known_surfaces([leg]);
        }
        h.send(cartography(Command::Forward));
        assert!(h.run_until(20000, |h| h.move_done_count() == 1), "no MOVE_DONE (plan: {plan})");
        assert!(h.distance_from(0.0, 0.0) < 0.01, "the robot drove (plan: {plan})");
        if plan {
            assert_eq!(h.reply_msgs(), WAY_EAST_NOT_CLEAR);
        } else {
            assert_eq!(
                h.reply_msgs(),
                vec![GuiMessage::SetObstaclePosition { x: 5, y: 6 }, GuiMessage::MoveDone]
            );
        }
    }
}

const WAY_EAST_NOT_CLEAR: [GuiMessage; 3] = [
    GuiMessage::SetObstaclePosition { x: 5, y: 6 },
    GuiMessage::SetRobotPosition { x: 5, y: 5 },
    GuiMessage::MoveDone,
];

#[test]
fn a_forward_with_an_echo_just_inside_the_clearance_drives_on_a_track_aside() {
    // cell (5, 5) facing east, 0.30 m cells: a known point 25 cm ahead and 13.5 cm left of the
    // centre line, 5 mm inside the 14 cm half corridor (body 12 cm and 2 cm of clearance)
    let forward = |stop_within_m: f64| {
        let mut h = ready_with(fake::test_config_with(|c| c.safety.stop_within_m = stop_within_m));
        h.robot.distance_cm = -1.0;
        h.run_ms(150);
        h.carto.add_known_surfaces([(5.0 * 0.30 + 0.25, -5.0 * 0.30 + 0.135)]);
        h.send(cartography(Command::Forward));
        assert!(h.run_until(20000, |h| h.move_done_count() == 1), "no MOVE_DONE");
        h
    };
    // with 2 cm allowed off the centre (1 cm once the lateral tolerance is taken off), the
    // track 7.5 mm right of the line clears the point: the robot drives and ends on it
    let h = forward(0.02);
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetRobotPosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    let stats = h.carto.stats();
    assert_eq!((stats.pilot.forwards_aside, stats.pilot.corridor_blocked), (1, 0));
    assert!((h.robot.x - 0.30).abs() <= 0.015, "drove {:.3} m", h.robot.x);
    assert!((-0.0175..=0.0).contains(&h.robot.y), "ended {:.4} m left of the line", h.robot.y);
    // with no room off the centre it is refused, as before
    let h = forward(0.01);
    let refused = vec![
        GuiMessage::SetObstaclePosition { x: 5, y: 6 },
        GuiMessage::SetRobotPosition { x: 5, y: 5 },
        GuiMessage::MoveDone,
    ];
    assert_eq!(h.reply_msgs(), refused);
    assert_eq!(h.carto.stats().pilot.corridor_blocked, 1);
    assert!(h.distance_from(0.0, 0.0) < 0.01, "the robot drove");
}

#[test]
fn the_scan_drives_when_the_path_is_clear() {
    let mut h = ready_with(fake::test_config_with(|c| c.safety.scan_deg = Some(30.0)));
    h.robot.distance_cm = 80.0;
    h.run_ms(150);
    h.send(cartography(Command::Forward));
    assert!(h.run_until(20000, |h| h.move_done_count() == 1), "no MOVE_DONE");
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetRobotPosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    let looked_left = h.robot.drives_since(robot_model::time::Instant::ZERO).iter().any(|(_, d)| d.omega > 0);
    let looked_right =
        h.robot.drives_since(robot_model::time::Instant::ZERO).iter().any(|(_, d)| d.omega < 0);
    assert!(looked_left && looked_right, "no scan");
    assert!((h.distance_from(0.0, 0.0) - 0.30).abs() <= 0.015);
}

/// FORWARDs east with the range ahead before each read off a wall `wall_m` east of the start
/// (the sonar sits 13 cm ahead of the centre), plus `error_cm[i]` before FORWARD `i`; how far
/// each FORWARD drove, and how many readings corrected the belief.
fn forwards_towards_a_wall(wall_m: f64, error_cm: &[f32]) -> (Vec<f64>, u64) {
    let mut h = ready_with(fake::test_config());
    let mut driven = Vec::new();
    for (i, e) in error_cm.iter().enumerate() {
        h.robot.distance_cm = ((wall_m - h.robot.x - 0.13) * 100.0) as f32 + e;
        h.run_ms(150);
        let start = h.robot.x;
        h.send(cartography(Command::Forward));
        assert!(h.run_until(8000, |h| h.move_done_count() == i + 1), "FORWARD {i}");
        driven.push(h.robot.x - start);
    }
    (driven, h.carto.stats().pilot.pose_fixes)
}

#[test]
fn the_range_ahead_corrects_the_belief_against_the_wall_heard_before() {
    // the wall is heard from the first three cells; before the fourth FORWARD it reads 1 cm
    // short: the robot is further along than it believes, and that FORWARD drives less (the
    // filter weighs the wheels, 1 % of the distance, against two readings in whole centimetres)
    let (agree, fixes_agree) = forwards_towards_a_wall(1.60, &[0.0; 4]);
    let (short, fixes) = forwards_towards_a_wall(1.60, &[0.0, 0.0, 0.0, -1.0]);
    let less = agree[3] - short[3];
    assert!((0.001..=0.01).contains(&less), "the fourth FORWARD drove {less:.4} m less: {agree:?} {short:?}");
    assert_eq!((fixes_agree, fixes), (3, 3), "every reading after the first corrects");
    assert!((agree[0] - short[0]).abs() < 1e-9 && (agree[2] - short[2]).abs() < 1e-9);
}

#[test]
fn a_range_far_from_the_mapped_wall_is_another_object_and_is_ignored() {
    // 12 cm short: a chair, not the wall; the belief stays where the wheels put it
    let (agree, _) = forwards_towards_a_wall(1.60, &[0.0; 4]);
    let (chair, _) = forwards_towards_a_wall(1.60, &[0.0, 0.0, 0.0, -12.0]);
    assert!((agree[3] - chair[3]).abs() <= 0.003, "{agree:?} {chair:?}");
}

/// Sends the turn `turn` from EAST (`Right` to SOUTH, `Left` to NORTH) with the sonar reading
/// `cm` while the heading lies in `while_deg` (clockwise from east), no echo otherwise, and
/// waits for its `MOVE_DONE`; the sonar reads no echo after it.
fn turn_hearing(h: &mut Harness, turn: Command, cm: f32, while_deg: (f32, f32)) {
    let done = h.move_done_count();
    h.send(cartography(turn));
    for _ in 0..8000 {
        let cw = h.robot.heading_cw_deg();
        h.robot.distance_cm = if (while_deg.0..=while_deg.1).contains(&cw) { cm } else { -1.0 };
        h.run_ms(1);
        if h.move_done_count() == done + 1 {
            break;
        }
    }
    assert_eq!(h.move_done_count(), done + 1, "no MOVE_DONE for the turn");
    h.robot.distance_cm = -1.0;
}

/// A FORWARD with no echo ahead (a sofa closer than the sensor's 2 cm minimum reads so): its
/// replies.
fn forward_without_echo(h: &mut Harness) -> Vec<GuiMessage> {
    h.robot.distance_cm = -1.0;
    h.run_ms(150);
    h.replies.clear();
    h.send(cartography(Command::Forward));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1), "no MOVE_DONE for the FORWARD");
    h.reply_msgs()
}

/// [`turn_hearing`] from the start pose, then [`forward_without_echo`]: the replies to the
/// FORWARD, and how many readings Carto kept during the turn.
fn forward_after_a_turn(
    cfg: CartoConfig,
    turn: Command,
    cm: f32,
    while_deg: (f32, f32),
) -> (Vec<GuiMessage>, u64) {
    let mut h = ready_with(cfg);
    h.robot.distance_cm = -1.0;
    h.run_ms(150);
    turn_hearing(&mut h, turn, cm, while_deg);
    (forward_without_echo(&mut h), h.carto.stats().pilot.turn_readings)
}

const BLOCKED_SOUTH: [GuiMessage; 2] = [GuiMessage::SetObstaclePosition { x: 6, y: 5 }, GuiMessage::MoveDone];
const DROVE_SOUTH: [GuiMessage; 2] = [GuiMessage::SetRobotPosition { x: 6, y: 5 }, GuiMessage::MoveDone];
/// Refused with a point on the way south, not inside the body at the next centre: the robot stays
/// in (5, 5) and the cell ahead is not called occupied (`pilot/safety.rs`, "Corridor").
const WAY_SOUTH_NOT_CLEAR: [GuiMessage; 3] = [
    GuiMessage::SetObstaclePosition { x: 6, y: 5 },
    GuiMessage::SetRobotPosition { x: 5, y: 5 },
    GuiMessage::MoveDone,
];

#[test]
fn a_reading_late_in_a_turn_blocks_the_forward_after_it() {
    // 4 cm from the sonar while the robot is within 15 degrees of SOUTH: something in the path
    let (seen, kept) = forward_after_a_turn(fake::test_config(), Command::Right, 4.0, (75.0, 105.0));
    assert_eq!(seen, BLOCKED_SOUTH);
    assert!(kept >= 1);
    // control: when the turn hears nothing there, only the "no echo" at rest counts, and the
    // robot drives
    let (blind, kept) = forward_after_a_turn(fake::test_config(), Command::Right, -1.0, (75.0, 105.0));
    assert_eq!((blind, kept), (DROVE_SOUTH.to_vec(), 0));
    // the same to the left, towards NORTH (270 degrees clockwise from east)
    let (seen, _) = forward_after_a_turn(fake::test_config(), Command::Left, 4.0, (255.0, 285.0));
    assert_eq!(seen, vec![GuiMessage::SetObstaclePosition { x: 4, y: 5 }, GuiMessage::MoveDone]);
}

#[test]
fn a_reading_early_in_a_turn_is_not_kept() {
    // 10 cm while the robot faces 25-35 degrees short of SOUTH: outside the 20-degree window,
    // where a heading error of the moving robot would move the echo across the path
    let (seen, kept) = forward_after_a_turn(fake::test_config(), Command::Right, 10.0, (55.0, 65.0));
    assert_eq!((seen, kept), (DROVE_SOUTH.to_vec(), 0));
}

#[test]
fn a_reading_in_a_turn_is_kept_on_the_edge_of_the_cone_away_from_the_path() {
    // 30 cm while the robot faces 15-18 degrees short of SOUTH. On the cone's central ray the
    // echo would lie about 13 cm beside the path, inside the 14 cm half corridor; the cone's
    // edge farther from the path puts it about 17 cm out. The echo could come from anywhere
    // across the cone, so only an echo whose whole arc lies in the path blocks: the robot drives.
    let (seen, kept) = forward_after_a_turn(fake::test_config(), Command::Right, 30.0, (72.0, 75.0));
    assert!(kept >= 1, "no reading kept during the turn");
    assert_eq!(seen, DROVE_SOUTH);
    // with a cone of no width the edge is the central ray, and the same reading blocks (with no
    // room to drive on a track aside: 13 cm beside the path, it would clear the point)
    let narrow = fake::test_config_with(|c| {
        c.sonar.cone_deg = 0.0;
        c.safety.stop_within_m = 0.01;
    });
    let (seen, kept) = forward_after_a_turn(narrow, Command::Right, 30.0, (72.0, 75.0));
    assert!(kept >= 1, "no reading kept during the turn");
    assert_eq!(seen, WAY_SOUTH_NOT_CLEAR, "13 cm beside the path: within the clearance, not the body");
}

#[test]
fn echoes_heard_in_a_turn_are_kept_past_the_next_turns() {
    // heard late in the right turn, then a left turn back to EAST and a right turn to SOUTH
    // again with nothing heard
    let turns_after_hearing = || {
        let mut h = ready_with(fake::test_config());
        h.robot.distance_cm = -1.0;
        h.run_ms(150);
        turn_hearing(&mut h, Command::Right, 4.0, (75.0, 105.0));
        h.send(cartography(Command::Left));
        h.send(cartography(Command::Right));
        assert!(h.run_until(20000, |h| h.move_done_count() == 3), "turns did not finish");
        h
    };
    // "no echo" at rest clears nothing: the echo is still kept and blocks the FORWARD south
    // (until 2026-11-26 the next turn forgot it and the robot drove)
    assert_eq!(forward_without_echo(&mut turns_after_hearing()), BLOCKED_SOUTH);
    // a new pose from Cute forgets it (it was placed from the old one): the robot drives
    let mut h = turns_after_hearing();
    h.send(GuiMessage::SendRobotPosition { x: 5, y: 6, direction: Direction::South });
    assert!(h.run_until(1000, |h| h.reply_msgs().contains(&GuiMessage::RobotPositionReceived)));
    assert_eq!(
        forward_without_echo(&mut h),
        [GuiMessage::SetRobotPosition { x: 6, y: 6 }, GuiMessage::MoveDone]
    );
}

/// Asks for `forwards` FORWARDs: one cartography move, or a trajectory batch of them.
fn send_forwards(h: &mut Harness, forwards: u8) {
    if forwards == 1 {
        h.send(cartography(Command::Forward));
    } else {
        for _ in 0..forwards {
            h.send(GuiMessage::SendMovesTrajectory { n_total: forwards, command: Command::Forward });
        }
    }
}

/// The stall watch on or off, telemetry flowing (the odometry is carried between encoder frames
/// with it, as on the real board) and a wall 1 m ahead of the front face whose range follows the
/// body. `forwards` FORWARDs are asked for (one cartography move, or a trajectory batch); the
/// body is held once it is `pinned_after_m` along, its wheels spinning on, and let go once Carto
/// has seen the stall, so the back-off moves it. Runs until the task's MOVE_DONE.
fn forwards_with_stall_watch(forwards: u8, pinned_after_m: Option<f64>, watch: bool) -> Harness {
    let mut h = ready_with(fake::test_config_with(|c| c.safety.stall_watch = watch));
    h.robot.send_telemetry = true;
    let wall_cm = 100.0;
    h.robot.distance_cm = wall_cm;
    h.run_ms(150);
    send_forwards(&mut h, forwards);
    for _ in 0..20_000 {
        if h.move_done_count() == 1 {
            break;
        }
        h.robot.pinned = pinned_after_m.is_some_and(|m| h.robot.x >= m) && h.carto.stats().pilot.stalls == 0;
        h.robot.distance_cm = wall_cm - (h.robot.x * 100.0) as f32;
        h.tick();
    }
    assert_eq!(h.move_done_count(), 1, "no MOVE_DONE");
    h
}

#[test]
fn a_forward_towards_a_wall_is_not_taken_for_a_stall() {
    let h = forwards_with_stall_watch(1, None, true);
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetRobotPosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    assert_eq!(h.carto.stats().pilot.stalls, 0);
    assert!((h.robot.x - 0.30).abs() <= 0.015, "ended at {:.3} m", h.robot.x);
}

#[test]
fn a_forward_whose_range_holds_while_the_wheels_turn_is_stopped_and_reported() {
    // the body is held after 5 cm; its wheels spin on and count
    let h = forwards_with_stall_watch(1, Some(0.05), true);
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetObstaclePosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    assert_eq!(h.carto.stats().pilot.stalls, 1);
    assert_eq!(h.carto.status().pose.map(|p| (p.x, p.y)), Some((5, 5)), "the stored cell moved");
    // Carto took the sonar's word for where the body stood (5 cm along, not the wheels' 20 cm or
    // more), so the back-off brought the body, let go, back to the centre; a correction left out
    // or of the wrong sign sends it 15 cm or more behind
    assert!(h.robot.x.abs() <= 0.03, "the body ended {:.3} m from the centre", h.robot.x);
    // control: without the watch the wheels' count wins and Carto reports a cell it never reached
    let h = forwards_with_stall_watch(1, Some(0.05), false);
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetRobotPosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    assert!(h.robot.x < 0.06, "the fake body moved");
}

#[test]
fn a_stall_in_a_trajectory_ends_the_batch_as_the_bumper_does() {
    let h = forwards_with_stall_watch(3, Some(0.05), true);
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetObstaclePosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    assert_eq!(h.carto.stats().pilot.stalls, 1);
    // neither did the rest of the batch run, nor did the back-off miss the centre
    assert!(h.robot.x.abs() <= 0.03, "the body ended {:.3} m from the centre", h.robot.x);
}

/// `forwards` FORWARDs east from the start cell's centre (one cartography move, or a trajectory
/// batch) with the push watch on or off and telemetry flowing. Once the body has driven 5 cm,
/// something it touches turns it `nudge_deg` counter-clockwise at once: the IMU sees it, the
/// wheels do not. Runs until the first MOVE_DONE.
fn forwards_nudged(forwards: u8, nudge_deg: f64, watch: bool) -> Harness {
    let mut h = ready_with(fake::test_config_with(|c| {
        if let Some(drift) = c.imu.drift.as_mut() {
            drift.push_watch = watch;
        }
    }));
    h.robot.send_telemetry = true;
    h.run_ms(150);
    send_forwards(&mut h, forwards);
    let mut nudged = false;
    for _ in 0..12_000 {
        if h.move_done_count() == 1 {
            break;
        }
        if !nudged && h.robot.x >= 0.05 {
            h.robot.yaw += nudge_deg.to_radians();
            nudged = true;
        }
        h.tick();
    }
    assert!(nudged, "the body never drove 5 cm");
    assert_eq!(h.move_done_count(), 1, "no MOVE_DONE");
    h
}

/// The counters of the push watch: FORWARDs it stopped, jumps of the heading gap, and those of
/// them over the push threshold.
fn push_counts(h: &Harness) -> (u64, u64, u64) {
    let s = h.carto.stats();
    (s.pilot.pushes, s.heading_jumps, s.push_jumps)
}

#[test]
fn a_forward_whose_body_is_turned_under_its_wheels_is_stopped_and_reported() {
    let h = forwards_nudged(1, 6.0, true);
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetObstaclePosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    assert_eq!(push_counts(&h), (1, 1, 1));
    assert_eq!(h.carto.status().pose.map(|p| (p.x, p.y)), Some((5, 5)), "the stored cell moved");
    // stopped within a few centimetres of the push and driven back towards the centre
    assert!(h.robot.x < 0.05, "the body ended {:.3} m along", h.robot.x);
    // control: without the watch the same push is seen (a jump of the gap) and driven through
    let h = forwards_nudged(1, 6.0, false);
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetRobotPosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    assert_eq!(push_counts(&h), (0, 1, 1));
}

#[test]
fn a_jump_of_the_heading_gap_below_the_push_threshold_does_not_stop_a_forward() {
    // 2.5 degrees: more than the drift estimate's 2 degree jump, less than a push's 3. The nudge
    // comes 5 cm in, as in the test above, where 6 degrees stop the FORWARD: it does not land on
    // the sample the watch excuses.
    let h = forwards_nudged(1, 2.5, true);
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetRobotPosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    assert_eq!(push_counts(&h), (0, 1, 0));
}

#[test]
fn a_push_in_a_trajectory_ends_the_batch_as_the_bumper_does() {
    let h = forwards_nudged(3, 6.0, true);
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetObstaclePosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    assert_eq!(push_counts(&h), (1, 1, 1));
    // neither did the rest of the batch run, nor did the back-off leave the start cell
    assert!(h.robot.x < 0.05, "the body ended {:.3} m along", h.robot.x);
    assert_eq!(h.carto.status().pose.map(|p| (p.x, p.y)), Some((5, 5)));
}

#[test]
fn a_heading_gap_left_by_the_turn_before_is_not_taken_for_a_push() {
    let mut h = ready_with(fake::test_config());
    h.robot.send_telemetry = true;
    h.robot.distance_cm = -1.0;
    h.run_ms(150);
    // halfway through a LEFT, something turns the body 6 degrees on; the turn ends on the IMU's
    // heading, so the wheels have turned 6 degrees less: a gap the drift estimate, which takes
    // no samples in turns, sees only after it
    h.send(cartography(Command::Left));
    let mut nudged = false;
    assert!(
        h.run_until(8000, |h| {
            if !nudged && h.robot.yaw.to_degrees() >= 45.0 {
                nudged = true;
            }
            nudged
        }),
        "the turn never got halfway"
    );
    h.robot.yaw += 6f64.to_radians();
    assert!(h.run_until(8000, |h| h.move_done_count() == 1), "no MOVE_DONE for the turn");
    h.send(cartography(Command::Forward));
    let (x0, y0) = (h.robot.x, h.robot.y);
    assert!(h.run_until(8000, |h| h.distance_from(x0, y0) > 0.002), "the FORWARD never drove");
    // the jump had not been seen when the FORWARD started
    assert_eq!(push_counts(&h), (0, 0, 0));
    assert!(h.run_until(12_000, |h| h.move_done_count() == 2), "no MOVE_DONE for the FORWARD");
    assert_eq!(h.reply_msgs()[1..], [GuiMessage::SetRobotPosition { x: 4, y: 5 }, GuiMessage::MoveDone]);
    // seen during the FORWARD, at its first sample, as large as a push, and excused
    assert_eq!(push_counts(&h), (0, 1, 1));
}

/// Two FORWARDs east from the start cell's centre. With `heard`, while the first FORWARD has
/// driven 2–20 cm the sonar hears a post `post_m` ahead of the start cell's centre (at rest,
/// before and after, it reads no echo: a leg the cone holds only from farther back); without,
/// it never hears the post. The replies to the second FORWARD, and how many readings Carto kept while
/// driving.
fn second_forward_after_hearing(heard: bool, post_m: f64) -> (Vec<GuiMessage>, u64) {
    let (replies, kept, _, _) = forwards_after_hearing(heard, post_m, 2);
    (replies, kept)
}

/// [`second_forward_after_hearing`] with `forwards` FORWARDs in all (2 or 3): the replies to
/// the second, how many readings were kept, the replies to the third (empty for two), and the
/// harness after the last.
fn forwards_after_hearing(
    heard: bool,
    post_m: f64,
    forwards: u8,
) -> (Vec<GuiMessage>, u64, Vec<GuiMessage>, Harness) {
    let mut h = ready_with(fake::test_config());
    h.robot.send_telemetry = true;
    h.robot.distance_cm = -1.0;
    h.run_ms(150);
    h.send(cartography(Command::Forward));
    for _ in 0..8000 {
        let hearing = heard && (0.02..=0.20).contains(&h.robot.x);
        h.robot.distance_cm = if hearing { ((post_m - h.robot.x - 0.13) * 100.0) as f32 } else { -1.0 };
        h.tick();
        if h.move_done_count() == 1 {
            break;
        }
    }
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetRobotPosition { x: 5, y: 6 }, GuiMessage::MoveDone]);
    h.robot.distance_cm = -1.0;
    h.run_ms(150);
    h.replies.clear();
    h.send(cartography(Command::Forward));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1), "no MOVE_DONE for the second FORWARD");
    let second = h.reply_msgs();
    let mut third = Vec::new();
    if forwards == 3 {
        h.replies.clear();
        h.send(cartography(Command::Forward));
        assert!(h.run_until(8000, |h| h.move_done_count() == 1), "no MOVE_DONE for the third FORWARD");
        third = h.reply_msgs();
    }
    let kept = h.carto.stats().pilot.drive_readings;
    (second, kept, third, h)
}

#[test]
fn a_post_heard_while_driving_blocks_the_next_forward() {
    // 0.55 m from the start: 0.25 m past the next cell's centre, in the second FORWARD's path
    // (its front face reaches 0.43 m past that centre); heard 22–40 cm from the sonar, where the
    // cone is at most 10.5 cm wide, so the whole arc lies in the path
    let (seen, kept) = second_forward_after_hearing(true, 0.55);
    assert!(kept >= 1, "no reading kept while driving");
    assert_eq!(seen, vec![GuiMessage::SetObstaclePosition { x: 5, y: 7 }, GuiMessage::MoveDone]);
    // control: when the sonar does not hear the post while driving, only the "no echo" at rest
    // counts, and the robot drives
    let (blind, kept) = second_forward_after_hearing(false, 0.55);
    assert_eq!(kept, 0);
    assert_eq!(blind, vec![GuiMessage::SetRobotPosition { x: 5, y: 7 }, GuiMessage::MoveDone]);
}

#[test]
fn a_post_heard_while_driving_that_refused_a_forward_is_avoided_by_the_turn_after_it() {
    // The post stands 14 cm ahead of the second cell's centre (0.30 m cells): it refuses the
    // second FORWARD and lies inside the circle the body sweeps turning there (19.7 cm with the
    // clearance). The turn check does not ask the echoes heard moving, but the one that refused
    // a FORWARD is kept as if heard at rest (`pilot/safety.rs`, "Kept while they hold"), so the
    // turn backs off first.
    let (seen, _, _, mut h) = forwards_after_hearing(true, 0.44, 2);
    // on the cell line, short of the body at the next centre: the way is not clear
    let refused = vec![
        GuiMessage::SetObstaclePosition { x: 5, y: 7 },
        GuiMessage::SetRobotPosition { x: 5, y: 6 },
        GuiMessage::MoveDone,
    ];
    assert_eq!(seen, refused);
    // the copy lies exactly where the echo heard moving lay, 13-19 cm ahead of the centre of
    // the robot's cell (5, 6) (x = 6 x 0.30 m, facing east)
    let points: Vec<(f64, f64)> = h.carto.echo_points().collect();
    let copied = points
        .iter()
        .enumerate()
        .find(|(i, p)| points[i + 1..].iter().any(|q| (p.0 - q.0).hypot(p.1 - q.1) < 1e-9));
    let (_, at) = copied.expect("the refusing echo is held twice: heard moving, and kept as if at rest");
    assert!((0.13..=0.19).contains(&(at.0 - 1.8)), "{at:?}");
    h.replies.clear();
    let x0 = h.robot.x;
    h.send(cartography(Command::Right));
    let back = run_to_move_done_tracking(&mut h, 1, |h| x0 - h.robot.x);
    let stats = h.carto.stats();
    assert_eq!((stats.pilot.turns_shifted, stats.pilot.turns_refused), (1, 0));
    assert!(back >= 0.02, "backed off {back:.3} m");
}

#[test]
fn a_post_heard_while_driving_beyond_the_next_forward_blocks_the_one_after() {
    // 0.85 m from the start: 12 cm past where the second FORWARD's front face stops (0.73 m)
    let (seen, kept, third, _) = forwards_after_hearing(true, 0.85, 3);
    assert!(kept >= 1, "no reading kept while driving");
    assert_eq!(seen, vec![GuiMessage::SetRobotPosition { x: 5, y: 7 }, GuiMessage::MoveDone]);
    // it lies in the third FORWARD's path; the reading at rest before it hears nothing (the post
    // stands beside the cone, 12 cm ahead of the sonar), but the point heard while driving is
    // still kept ("Kept while they hold"): until 2026-11-26 the second FORWARD's start forgot it
    // and the third drove into the post
    assert_eq!(third, vec![GuiMessage::SetObstaclePosition { x: 5, y: 8 }, GuiMessage::MoveDone]);
}

#[test]
fn a_post_heard_while_driving_just_past_the_next_forward_does_not_block_it() {
    // 5 mm past where the second FORWARD's front face stops. The fake's readings are fresh while
    // Carto takes them for 30 ms old, which puts them 1.1 cm short: without the margin beyond
    // the range (3 sonar σ and the lag's travel) the post would block
    let (seen, kept) = second_forward_after_hearing(true, 0.735);
    assert!(kept >= 1, "no reading kept while driving");
    assert_eq!(seen, vec![GuiMessage::SetRobotPosition { x: 5, y: 7 }, GuiMessage::MoveDone]);
}

/// A right turn from EAST to SOUTH with no echo, then a FORWARD during which the sonar reads
/// `cm` while the heading lies in `while_deg` (clockwise from east) and no echo otherwise: the
/// replies to the FORWARD, how many readings were kept in turns and looks, and the furthest the
/// body turned past SOUTH during the turn's own command, degrees.
fn forward_hearing_past_a_right_turn(
    cfg: CartoConfig,
    cm: f32,
    while_deg: (f32, f32),
) -> (Vec<GuiMessage>, u64, f32) {
    let mut h = ready_with(cfg);
    h.robot.distance_cm = -1.0;
    h.run_ms(150);
    let mut past_in_turn = 0.0f32;
    h.send(cartography(Command::Right));
    for _ in 0..8000 {
        let cw = h.robot.heading_cw_deg();
        if (60.0..=180.0).contains(&cw) {
            past_in_turn = past_in_turn.max(cw - 90.0);
        }
        h.run_ms(1);
        if h.move_done_count() == 1 {
            break;
        }
    }
    assert_eq!(h.move_done_count(), 1, "no MOVE_DONE for the turn");
    h.replies.clear();
    h.send(cartography(Command::Forward));
    for _ in 0..12_000 {
        let cw = h.robot.heading_cw_deg();
        h.robot.distance_cm = if (while_deg.0..=while_deg.1).contains(&cw) { cm } else { -1.0 };
        h.run_ms(1);
        if h.move_done_count() == 1 {
            break;
        }
    }
    assert_eq!(h.move_done_count(), 1, "no MOVE_DONE for the FORWARD");
    (h.reply_msgs(), h.carto.stats().pilot.turn_readings, past_in_turn)
}

#[test]
fn a_forward_after_a_turn_looks_past_it_first_and_is_blocked_by_what_it_hears() {
    // 4 cm while the robot faces 6-25 degrees past SOUTH: the side of the path the right turn
    // from EAST did not sweep. The turn's MOVE_DONE came first: the look belongs to the FORWARD
    let look = fake::test_config();
    assert_eq!(look.safety.look_past_turn_deg, Some(20.0), "the default");
    let (seen, kept, past_in_turn) = forward_hearing_past_a_right_turn(look, 4.0, (96.0, 115.0));
    assert!(past_in_turn < 5.0, "the turn's own command went {past_in_turn:.1} degrees past SOUTH");
    assert!(kept >= 1, "no reading kept past the turn");
    assert_eq!(seen, WAY_SOUTH_NOT_CLEAR, "4 cm from the sonar: on the way, short of the next cell's body");
    // without the look nothing is heard there, and the robot drives
    let off = fake::test_config_with(|c| c.safety.look_past_turn_deg = None);
    let (blind, kept, _) = forward_hearing_past_a_right_turn(off, 4.0, (96.0, 115.0));
    assert_eq!((blind, kept), (DROVE_SOUTH.to_vec(), 0));
}

#[test]
fn the_look_past_a_turn_ends_facing_the_heading_and_the_forward_drives_straight() {
    let mut h = ready_with(fake::test_config());
    h.robot.distance_cm = -1.0;
    h.run_ms(150);
    h.send(cartography(Command::Left));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1), "no MOVE_DONE for the turn");
    h.replies.clear();
    let mut past = 0.0f32;
    h.send(cartography(Command::Forward));
    for _ in 0..12_000 {
        // clockwise from east: NORTH is 270, the look goes on past it towards 250
        let cw = h.robot.heading_cw_deg();
        if (200.0..=300.0).contains(&cw) {
            past = past.max(270.0 - cw);
        }
        h.run_ms(1);
        if h.move_done_count() == 1 {
            break;
        }
    }
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetRobotPosition { x: 4, y: 5 }, GuiMessage::MoveDone]);
    assert!(past >= 15.0, "turned only {past:.1} degrees past NORTH");
    assert!((h.robot.heading_cw_deg() - 270.0).abs() <= 2.0, "ended at {:.1}", h.robot.heading_cw_deg());
    assert!(
        h.robot.x.abs() <= 0.02 && (h.robot.y - 0.30).abs() <= 0.015,
        "ended at ({:.3}, {:.3})",
        h.robot.x,
        h.robot.y
    );
}

#[test]
fn a_stop_during_the_look_past_a_turn_makes_the_next_forward_face_the_heading_before_its_check() {
    let mut h = ready_with(fake::test_config());
    h.robot.distance_cm = -1.0;
    h.run_ms(150);
    h.send(cartography(Command::Left));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1), "no MOVE_DONE for the turn");
    assert_eq!(h.carto.status().pose.map(|p| p.heading), Some(robot_model::grid::Heading::North));
    h.send(cartography(Command::Forward));
    // cut the look 8-15 degrees past NORTH (clockwise from east: 255-262)
    assert!(h.run_until(8000, |h| (255.0..=262.0).contains(&h.robot.heading_cw_deg())), "no look");
    h.send(GuiMessage::StopRobot);
    h.run_ms(1000);
    assert!(h.robot.heading_cw_deg() < 265.0, "stopped at {:.1}", h.robot.heading_cw_deg());
    // the turn's MOVE_DONE had gone out: Carto and Cute both hold NORTH
    assert_eq!(h.carto.status().pose.map(|p| p.heading), Some(robot_model::grid::Heading::North));
    // a wall 10 cm ahead that the sonar hears only facing NORTH (within 3 degrees): the reading
    // at rest before the FORWARD must be taken facing the heading, not where the look was cut
    h.replies.clear();
    h.send(cartography(Command::Forward));
    for _ in 0..12_000 {
        let facing_north = (h.robot.heading_cw_deg() - 270.0).abs() <= 3.0;
        h.robot.distance_cm = if facing_north { 10.0 } else { -1.0 };
        h.run_ms(1);
        if h.move_done_count() == 1 {
            break;
        }
    }
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetObstaclePosition { x: 4, y: 5 }, GuiMessage::MoveDone]);
    assert!((h.robot.heading_cw_deg() - 270.0).abs() <= 2.0, "ended at {:.1}", h.robot.heading_cw_deg());
}

/// A LEFT turn to NORTH, then a FORWARD sent at once, and a STOP while the look past the turn
/// is `cut_cw` degrees clockwise from east (NORTH is 270); then the body cannot turn clockwise
/// from where it stopped (something beside it), so facing NORTH again jams.
fn look_cut_and_refacing_blocked(cut_cw: (f32, f32)) -> Harness {
    let mut h = ready_with(fake::test_config());
    h.robot.distance_cm = -1.0;
    h.run_ms(150);
    h.send(cartography(Command::Left));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1), "no MOVE_DONE for the turn");
    h.send(cartography(Command::Forward));
    assert!(h.run_until(8000, |h| (cut_cw.0..=cut_cw.1).contains(&h.robot.heading_cw_deg())), "no look");
    h.send(GuiMessage::StopRobot);
    h.run_ms(1000);
    h.robot.yaw_min_deg = Some(h.robot.yaw.to_degrees());
    h.replies.clear();
    h
}

#[test]
fn a_refacing_that_jams_close_to_the_heading_lets_the_forward_drive_and_keeps_the_heading() {
    // stopped 6-9 degrees past NORTH: within 10 degrees, the FORWARD runs from there
    let mut h = look_cut_and_refacing_blocked((261.0, 264.0));
    h.send(cartography(Command::Forward));
    assert!(h.run_until(12_000, |h| h.move_done_count() == 1), "no MOVE_DONE");
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetRobotPosition { x: 4, y: 5 }, GuiMessage::MoveDone]);
    // Carto still holds NORTH: once the body is free, the next FORWARD steers back onto it
    h.robot.yaw_min_deg = None;
    h.send(cartography(Command::Forward));
    assert!(h.run_until(12_000, |h| h.move_done_count() == 2), "no second MOVE_DONE");
    assert_eq!(h.carto.status().pose.map(|p| (p.x, p.y)), Some((3, 5)));
    assert!((h.robot.heading_cw_deg() - 270.0).abs() <= 2.0, "ended at {:.1}", h.robot.heading_cw_deg());
}

#[test]
fn a_refacing_that_jams_far_from_the_heading_fails_the_move_and_is_tried_again() {
    // stopped 14-18 degrees past NORTH: the FORWARD fails without moving, NORTH is kept
    let mut h = look_cut_and_refacing_blocked((252.0, 256.0));
    let (x0, y0) = (h.robot.x, h.robot.y);
    h.send(cartography(Command::Forward));
    assert!(h.run_until(12_000, |h| h.move_done_count() == 1), "no MOVE_DONE");
    assert_eq!(h.reply_msgs(), vec![GuiMessage::MoveDone]);
    assert!(h.distance_from(x0, y0) <= 0.01, "moved {:.3} m", h.distance_from(x0, y0));
    assert_eq!(h.carto.status().pose.map(|p| p.heading), Some(robot_model::grid::Heading::North));
    // free again: the next FORWARD faces NORTH first, then drives
    h.robot.yaw_min_deg = None;
    h.replies.clear();
    h.send(cartography(Command::Forward));
    assert!(h.run_until(12_000, |h| h.move_done_count() == 1), "no MOVE_DONE");
    assert_eq!(h.reply_msgs(), vec![GuiMessage::SetRobotPosition { x: 4, y: 5 }, GuiMessage::MoveDone]);
    assert!((h.robot.heading_cw_deg() - 270.0).abs() <= 2.0, "ended at {:.1}", h.robot.heading_cw_deg());
}

#[test]
fn after_three_refacings_that_jam_the_heading_is_learnt_again_and_the_robot_moves() {
    let mut h = look_cut_and_refacing_blocked((252.0, 256.0));
    for n in 1..=3 {
        h.send(cartography(Command::Forward));
        assert!(h.run_until(12_000, |h| h.move_done_count() == n), "no MOVE_DONE {n}");
    }
    assert_eq!(h.reply_msgs(), vec![GuiMessage::MoveDone; 3]);
    // the fourth is not refused: the robot is never stuck refusing every move
    h.send(cartography(Command::Forward));
    assert!(h.run_until(12_000, |h| h.move_done_count() == 4), "no fourth MOVE_DONE");
    assert_eq!(h.reply_msgs()[3..], [GuiMessage::SetRobotPosition { x: 4, y: 5 }, GuiMessage::MoveDone]);
}

/// A wall 3 cm ahead, then a RIGHT, which backs off before it turns and, made off the centre,
/// looks and drives back before its MOVE_DONE; the link drops when Carto does `cut_in`. Cute
/// never got that MOVE_DONE: on reconnect it re-sends its pose (EAST) and the RIGHT. Returns the
/// harness once the second RIGHT is done.
fn disconnect_before_an_off_centre_turns_move_done(cut_in: carto::pilot::Activity) -> Harness {
    let mut h = ready_with(fake::test_config());
    blocked_forward(&mut h, 3.0);
    h.robot.distance_cm = -1.0;
    h.send(cartography(Command::Right));
    assert!(h.run_until(12_000, |h| h.carto.activity() == cut_in), "never {cut_in:?}");
    h.run_ms(80);
    assert_eq!(h.move_done_count(), 1, "the RIGHT's MOVE_DONE went out before {cut_in:?}");
    h.carto.on_client_disconnected(h.now);
    h.run_ms(500);
    h.carto.on_client_connected(h.now, "cute again");
    h.replies.clear();
    h.send(POSE);
    h.run_ms(50);
    h.send(cartography(Command::Right));
    assert!(h.run_until(20_000, |h| h.move_done_count() == 1), "no MOVE_DONE for the RIGHT sent again");
    h.run_ms(3000);
    h
}

#[test]
fn a_disconnect_before_the_move_done_of_a_turn_made_off_the_centre_takes_the_turn_back() {
    use carto::pilot::Activity;
    for cut_in in [Activity::LookingPastTurn, Activity::Recentring] {
        let h = disconnect_before_an_off_centre_turns_move_done(cut_in);
        // Cute and Carto hold SOUTH after the one RIGHT Cute knows of, and so does the body
        assert_eq!(h.carto.status().pose.map(|p| p.heading), Some(robot_model::grid::Heading::South));
        let cw = h.robot.heading_cw_deg();
        assert!(
            (cw - 90.0).abs() <= 3.0,
            "cut in {cut_in:?}: the body faces {cw:.1}° clockwise, SOUTH is 90"
        );
    }
}

/// Drives `cells` FORWARDs east with nothing ahead, with or without a floor plan holding a
/// wall 40 cm left of the row; the looks aside taken and the most the body turned left and
/// right of east on the way, degrees.
fn forwards_along_a_wall(cells: usize, plan: bool) -> (u64, f64, f64) {
    let mut h = ready_with(fake::test_config());
    if plan {
        let row_y = -5.0 * 0.30;
        h.carto.add_known_surfaces((0..900).map(|k| (f64::from(k) * 0.01, row_y + 0.40)));
    }
    h.robot.distance_cm = -1.0;
    h.run_ms(150);
    let (mut left, mut right) = (0.0_f64, 0.0_f64);
    for i in 0..cells {
        h.send(cartography(Command::Forward));
        let least = std::cell::Cell::new(0.0_f64);
        let most = run_to_move_done_tracking(&mut h, i + 1, |h| {
            let yaw = h.robot.yaw.to_degrees();
            least.set(least.get().min(yaw));
            yaw
        });
        (left, right) = (left.max(most), right.max(-least.get()));
    }
    (h.carto.stats().pilot.looks_aside, left, right)
}

#[test]
fn with_a_floor_plan_the_uncertainty_across_the_row_sends_a_look_towards_the_wall() {
    // issue 42, item 2: with a plan, the belief is corrected in every direction it has surfaces
    // in; one forward sonar sees across the row only when the body turns, so Carto looks
    // aside (60° towards the plan's nearer surface) once its belief across the row has grown
    let (looks, left, right) = forwards_along_a_wall(20, true);
    assert!(looks >= 1, "no look aside in 20 cells");
    assert!(left > 45.0 && right < 5.0, "turned {left:.0}° left, {right:.0}° right");
    // without a plan nothing is known to look at: the FORWARDs drive straight
    let (looks, left, right) = forwards_along_a_wall(8, false);
    assert_eq!(looks, 0);
    assert!(left < 5.0 && right < 5.0, "turned {left:.0}° left, {right:.0}° right");
}

/// The largest heading, clockwise from east, in the 3 s after a mapping RIGHT from EAST has
/// answered `MOVE_DONE`; with a complete floor plan (a far point) or without one.
fn heading_after_a_right(plan: bool) -> f32 {
    let mut h = ready_with(CartoConfig::default());
    h.robot.distance_cm = -1.0;
    h.run_ms(150);
    if plan {
        h.carto.add_floor_plan([(5.0, 5.0)]);
    }
    h.send(cartography(Command::Right));
    assert!(h.run_until(8000, |h| h.move_done_count() == 1), "no MOVE_DONE for the turn");
    let mut most = f32::MIN;
    for _ in 0..3000 {
        most = most.max(h.robot.heading_cw_deg());
        h.run_ms(1);
    }
    most
}

#[test]
fn with_a_complete_floor_plan_the_robot_does_not_look_past_a_mapping_turn() {
    // the look past the turn goes on 20° past SOUTH (90° clockwise) and back; with the plan a
    // reading there would add no point, so the robot stays facing SOUTH
    let without = heading_after_a_right(false);
    assert!(without > 105.0, "no look past the turn without a plan: {without}°");
    let with = heading_after_a_right(true);
    assert!(with < 95.0, "a look past the turn with a complete plan: {with}°");
}
