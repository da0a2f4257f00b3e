#![allow(clippy::unwrap_used, clippy::panic)]
use super::*;
use crate::map::CellValue;
use crate::session::MAX_BATCH;

const T: Duration = Duration::from_secs(5);

/// A `1 × cols` corridor, robot at (0, 0) facing east; `free` cells known free.
fn corridor(cols: usize, free: bool) -> Belief {
    let mut map = Map::new(1, cols).unwrap();
    if free {
        for y in 0..cols {
            map.set_free(0, y).unwrap();
        }
    }
    map.set_robot(0, 0).unwrap();
    Belief { map, robot: (0, 0), heading: Heading::East }
}

fn mapping(b: &Belief) -> Mission {
    Mission::Mapping(Mapping::new(b.cartographer().unwrap()))
}

fn at(s: u64) -> Instant {
    Instant::from_secs(s)
}

#[test]
fn mapping_sends_one_move_and_waits_for_its_answer() {
    let (mut b, mut p) = (corridor(3, false), Planner::new());
    let mut m = mapping(&b);
    assert_eq!(m.next(&mut b, &mut p, at(1), T), Next::Cartography(Move::Forward));
    assert_eq!(m.deadline(), Some(at(6)));
    assert_eq!(m.next(&mut b, &mut p, at(2), T), Next::Wait, "one move in flight at a time");
    assert!(m.on_position(&mut b, 0, 1));
    assert_eq!(b.robot, (0, 0), "a position is only the move's result until MOVE_DONE");
    assert_eq!(m.on_move_done(&mut b), Answer::Applied);
    assert_eq!((b.robot, m.deadline()), ((0, 1), None));
    assert_eq!(m.next(&mut b, &mut p, at(3), T), Next::Cartography(Move::Forward));
    assert_eq!(m.on_obstacle(&mut b, 0, 2), Obstacle::Recorded);
    assert_eq!(m.on_move_done(&mut b), Answer::Applied);
    assert_eq!(b.map.get(0, 2), Some(CellValue::Obstacle));
    assert!(matches!(m.next(&mut b, &mut p, at(4), T), Next::Mapped(s) if s.commands == 2));
}

#[test]
fn a_forward_answered_by_a_bare_move_done_is_resent_then_given_up() {
    let (mut b, mut p) = (corridor(2, false), Planner::new());
    let mut m = mapping(&b);
    for _ in 1..MAX_REJECTED {
        assert_eq!(m.next(&mut b, &mut p, at(0), T), Next::Cartography(Move::Forward));
        assert_eq!(m.on_move_done(&mut b), Answer::Applied);
    }
    assert_eq!(m.next(&mut b, &mut p, at(0), T), Next::Cartography(Move::Forward));
    assert_eq!(m.on_move_done(&mut b), Answer::Rejected(Move::Forward));
    assert_eq!(b.robot, (0, 0));
}

#[test]
fn a_turn_answered_by_a_bare_move_done_was_made() {
    let (mut b, mut p) = (corridor(2, false), Planner::new());
    b.heading = Heading::North;
    let mut m = mapping(&b);
    let Next::Cartography(turn) = m.next(&mut b, &mut p, at(0), T) else { panic!("no move") };
    assert!(turn.is_turn());
    assert_eq!(m.on_move_done(&mut b), Answer::Applied);
    assert_eq!(b.heading, Heading::North.after(turn));
}

#[test]
fn a_disconnect_keeps_a_reported_result_and_resends_an_unanswered_move() {
    let (mut b, mut p) = (corridor(3, false), Planner::new());
    let mut m = mapping(&b);
    m.next(&mut b, &mut p, at(0), T);
    m.on_disconnected(&mut b);
    assert_eq!((b.robot, m.deadline()), ((0, 0), None));
    assert_eq!(m.next(&mut b, &mut p, at(1), T), Next::Cartography(Move::Forward), "re-sent");
    assert!(m.on_position(&mut b, 0, 1));
    m.on_disconnected(&mut b);
    assert_eq!(b.robot, (0, 1), "the reported move did happen");
    assert_eq!(m.on_move_done(&mut b), Answer::Unsolicited, "nothing in flight any more");
}

#[test]
fn a_map_reset_during_a_move_applies_it_then_starts_afresh() {
    let (mut b, mut p) = (corridor(3, false), Planner::new());
    let mut m = mapping(&b);
    m.next(&mut b, &mut p, at(0), T);
    b.map.reset();
    b.map.set_robot(0, 0).unwrap();
    if let Mission::Mapping(mm) = &mut m {
        mm.restart(&b);
    }
    assert!(m.on_position(&mut b, 0, 1));
    assert_eq!(m.on_move_done(&mut b), Answer::Applied);
    assert_eq!(b.robot, (0, 1));
    let Mission::Mapping(mm) = &m else { panic!("still mapping") };
    assert_eq!((mm.cartographer().pose(), mm.cartographer().pending()), ((0, 1), None));
}

#[test]
fn a_trajectory_follows_positions_and_ends_at_the_batch_end() {
    let (mut b, mut p) = (corridor(4, true), Planner::new());
    let mut m = Mission::Moving(Moving::new((0, 3), &[Move::Forward; 3], Compat::Default));
    assert_eq!(m.next(&mut b, &mut p, at(1), T), Next::Batch(vec![Move::Forward; 3]));
    assert_eq!(m.deadline(), Some(at(16)), "5 s per command");
    assert_eq!(m.next(&mut b, &mut p, at(1), T), Next::Wait);
    assert!(m.on_position(&mut b, 0, 1));
    assert_eq!(b.robot, (0, 1), "each position moves the robot at once");
    assert_eq!(m.on_move_done(&mut b), Answer::Applied);
    assert_eq!(b.robot, (0, 3), "MOVE_DONE: at the batch's last cell");
    assert_eq!(m.next(&mut b, &mut p, at(2), T), Next::Arrived);
}

#[test]
fn batches_follow_the_compat_limit() {
    let (mut b, mut p) = (corridor(2, true), Planner::new());
    let mut m = Mission::Moving(Moving::new((0, 1), &[Move::Right; 300], Compat::Default));
    assert!(matches!(m.next(&mut b, &mut p, at(0), T), Next::Batch(v) if v.len() == MAX_BATCH));
    m.on_move_done(&mut b);
    assert!(matches!(m.next(&mut b, &mut p, at(0), T), Next::Batch(v) if v.len() == 45));

    let mut m = Mission::Moving(Moving::new((0, 1), &[Move::Right; 120], Compat::Explobot2024));
    let Next::FireAndForget(all) = m.next(&mut b, &mut p, at(0), T) else { panic!("not fired") };
    assert_eq!(all.iter().map(Vec::len).collect::<Vec<_>>(), [50, 50, 20]);
    assert_eq!(m.deadline(), None, "nothing is awaited from the original Carto");
}

#[test]
fn a_fire_and_forget_trajectory_puts_the_robot_at_the_end() {
    let (mut b, mut p) = (corridor(3, true), Planner::new());
    let commands = [Move::Forward, Move::Forward, Move::Right];
    let mut m = Mission::Moving(Moving::new((0, 2), &commands, Compat::Explobot2024));
    assert_eq!(m.next(&mut b, &mut p, at(0), T), Next::FireAndForget(vec![commands.to_vec()]));
    assert_eq!(b.robot, (0, 0), "the session decides whether the batch runs");
    b.assume_driven(&commands);
    assert_eq!((b.robot, b.heading), ((0, 2), Heading::South));
}

#[test]
fn an_obstacle_aborts_a_trajectory_and_is_marked() {
    let (mut b, mut p) = (corridor(4, true), Planner::new());
    b.heading = Heading::North;
    let mut m = Mission::Moving(Moving::new((0, 3), &[Move::Right, Move::Forward], Compat::Default));
    m.next(&mut b, &mut p, at(0), T);
    assert_eq!(m.on_obstacle(&mut b, 0, 1), Obstacle::Aborted);
    assert_eq!(b.map.get(0, 1), Some(CellValue::Obstacle));
    assert_eq!(b.heading, Heading::East, "facing the obstacle");
}

#[test]
fn an_interrupted_trajectory_is_replanned_from_the_last_cell() {
    let (mut b, mut p) = (corridor(4, true), Planner::new());
    let mut m = Mission::Moving(Moving::new((0, 3), &[Move::Forward; 3], Compat::Default));
    m.next(&mut b, &mut p, at(0), T);
    m.on_position(&mut b, 0, 1);
    m.on_disconnected(&mut b);
    assert_eq!(m.deadline(), None);
    assert_eq!(m.next(&mut b, &mut p, at(1), T), Next::Batch(vec![Move::Forward; 2]));

    m.on_disconnected(&mut b);
    b.map.set_obstacle(0, 2).unwrap();
    assert_eq!(m.next(&mut b, &mut p, at(2), T), Next::NoPath((0, 3)));
}

#[test]
fn answers_without_a_mission_are_unsolicited() {
    let (mut b, mut p) = (corridor(2, true), Planner::new());
    let mut m = Mission::None;
    assert_eq!(m.next(&mut b, &mut p, at(0), T), Next::Wait);
    assert!(!m.on_position(&mut b, 0, 1));
    assert_eq!(m.on_obstacle(&mut b, 0, 1), Obstacle::Unsolicited);
    assert_eq!(m.on_move_done(&mut b), Answer::Unsolicited);
    assert_eq!(b.robot, (0, 0), "the session, not the mission, handles unsolicited answers");
}
