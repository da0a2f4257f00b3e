use super::*;

/// A 4 × 3-cell room (1.2 × 0.9 m, no margin) with `obstacles`.
fn truth(obstacles: &str) -> RobotTruth {
    truth_in(1.2, 0.9, obstacles)
}

/// A `w` × `h` m room with `obstacles`, the robot starting in cell (0, 0).
fn room(w: f32, h: f32, obstacles: &str) -> Scenario {
    let text = format!(
        "Scenario(name: \"t\", room: [(0.0, 0.0), ({w:?}, 0.0), ({w:?}, {h:?}), (0.0, {h:?})], \
         start: (row: 0, col: 0, heading: East), obstacles: [{obstacles}])"
    );
    Scenario::from_ron_str(&text, "t.ron").unwrap()
}

/// The default robot on cells of `cell` metres.
fn robot(cell: f32) -> RobotProfile {
    RobotProfile { grid_cell_m: cell, ..RobotProfile::default() }
}

/// A `w` × `h` m room with `obstacles`, on cells of `cell` metres.
fn truth_with_cell(w: f32, h: f32, cell: f32, obstacles: &str) -> RobotTruth {
    room(w, h, obstacles).truth(&robot(cell))
}

/// The truth of that room and, per cell, whether the robot can turn after a slide.
fn truth_and_slide(w: f32, h: f32, cell: f32, obstacles: &str) -> (RobotTruth, Vec<bool>) {
    let (s, p) = (room(w, h, obstacles), robot(cell));
    let t = s.truth(&p);
    let slide = turnable_after_slide(t.frame, &s.room, &s.obstacle_shapes(), &p);
    (t, slide)
}

/// A `w` × `h` m room with `obstacles`, on the 0.30 m cells the documented cases are about.
fn truth_in(w: f32, h: f32, obstacles: &str) -> RobotTruth {
    truth_with_cell(w, h, 0.30, obstacles)
}

#[test]
fn an_empty_room_on_cell_lines_is_all_free_and_connected() {
    let t = truth("");
    assert_eq!((t.frame.rows, t.frame.cols), (3, 4));
    for r in 0..3 {
        for c in 0..4 {
            assert_eq!(t.stand(r, c), Stand { along_rows: true, along_cols: true }, "({r}, {c})");
            // Against a wall the body cannot turn on the spot: its corners sweep 17.7 cm and
            // the wall is 15 cm from the cell's centre.
            let inner = r == 1 && (1..3).contains(&c);
            assert_eq!(t.can_turn(r, c), inner, "({r}, {c})");
        }
    }
    assert!(t.reachable_from((0, 0)).iter().all(|&r| r));
    assert!(!t.can_move((0, 0), (1, 1)), "diagonals are not moves");
    assert!(!t.can_move((0, 3), (0, 4)), "off the grid");
}

#[test]
fn a_thin_wall_on_a_cell_line_blocks_the_move_not_the_cells() {
    // x = 0.6 is the line between columns 1 and 2.
    let t = truth("Segment(from: (0.6, 0.0), to: (0.6, 0.9))");
    assert!((0..3).all(|r| t.is_free(r, 1) && t.is_free(r, 2)));
    assert!((0..3).all(|r| !t.can_move((r, 1), (r, 2))));
    assert!(t.can_move((0, 1), (1, 1)));
    let reach = t.reachable_from((0, 0));
    assert!(reach[1] && !reach[2] && !reach[3]);
}

#[test]
fn a_thin_leg_on_a_cell_corner_blocks_nothing() {
    // A 5 × 4-cell room; a 4 cm leg on the corner of cells (1, 1), (1, 2), (2, 1), (2, 2),
    // at x 0.6, y 0.6.
    let t = truth_in(1.5, 1.2, "Circle(center: (0.6, 0.6), radius: 0.02)");
    for cell in [(1, 1), (1, 2), (2, 1), (2, 2)] {
        assert!(t.is_free(cell.0, cell.1) && t.can_turn(cell.0, cell.1), "{cell:?}");
    }
    assert!(t.can_move((1, 1), (1, 2)) && t.can_move((1, 1), (2, 1)));
    // A 9 cm pillar there leaves no room for the body in any of the four cells.
    let t = truth_in(1.5, 1.2, "Circle(center: (0.6, 0.6), radius: 0.045)");
    for cell in [(1, 1), (1, 2), (2, 1), (2, 2)] {
        assert!(!t.is_free(cell.0, cell.1), "{cell:?}");
    }
    assert!(t.is_free(0, 0) && t.can_move((0, 0), (1, 0)));
}

#[test]
fn a_wall_two_cm_into_a_cell_leaves_it_free_along_the_wall_only() {
    // Row 0 spans y 0.6..0.9; a wall 2 cm below its top edge, across the whole room.
    let t = truth("Box(center: (0.6, 0.88), size: (1.2, 0.001))");
    assert_eq!(t.stand(0, 1), Stand { along_rows: true, along_cols: false });
    assert!(!t.can_turn(0, 1));
    assert!(t.can_move((0, 1), (0, 2)), "along the wall");
    assert!(!t.can_move((0, 1), (1, 1)), "across it, the body touches the wall at row 0");
    assert!(!t.reachable_from((1, 1))[1], "so row 0 cannot be entered from below");
}

#[test]
fn turning_at_centres_only_leaves_the_corners_unvisited_sliding_first_opens_them() {
    // An empty 3 × 4-cell room of 0.30 m cells: the robot can turn only in the two inner
    // cells (1, 1) and (1, 2); against a wall its corners would touch it.
    let t = truth("");
    let cells =
        |v: &[bool]| -> Vec<(usize, usize)> { (0..12).filter(|&i| v[i]).map(|i| (i / 4, i % 4)).collect() };
    let v = t.visits_from((1, 1), Heading::East);
    // From an inner cell the robot faces any way and drives one cell on; there it faces a
    // wall and cannot turn. A corner needs a turn in a border cell: never visitable, though
    // coverage counts it (moves connect it to the start).
    assert_eq!(cells(&v.visitable), vec![(0, 1), (0, 2), (1, 0), (1, 1), (1, 2), (1, 3), (2, 1), (2, 2)]);
    assert!(t.reachable_from((1, 1)).iter().all(|&x| x));
    // Every border cell is a dead end: only the inner cells are round trips.
    assert_eq!(cells(&v.round_trip), vec![(1, 1), (1, 2)]);
    // Out of the inner cells, one drive into a border cell ends the tour: 3 of 12 cells.
    assert_eq!(v.tour_bound, 3);
    // Sliding helps: the room is 0.90 m wide, more than the 2 × 17.7 cm the turning circle
    // needs, so in every cell the robot can slide a few cm away from the walls, turn and
    // slide back, and every cell becomes a round trip.
    let (_, slide) = truth_and_slide(1.2, 0.9, 0.30, "");
    assert!(slide.iter().all(|&x| x));
    let v = t.visits_with((1, 1), Heading::East, |r, c| slide[r * 4 + c]);
    assert!(v.round_trip.iter().all(|&x| x) && v.tour_bound == 12);
    // Facing north in a corner the robot can go nowhere.
    let v = t.visits_from((0, 0), Heading::North);
    assert_eq!(cells(&v.visitable), vec![(0, 0)]);
}

#[test]
fn no_slide_helps_in_a_corridor_narrower_than_the_turning_circle() {
    // One row of 0.30 m cells in a 0.30 m corridor: the body fits either way (0.26 × 0.24 m),
    // the 2 × 17.7 cm circle nowhere.
    let (t, slide) = truth_and_slide(1.2, 0.3, 0.30, "");
    assert!((0..4).all(|c| t.is_free(0, c)));
    assert_eq!(slide, vec![false; 4]);
    // Facing east from (0, 0) the robot drives to the end and stays there.
    let v = t.visits_with((0, 0), Heading::East, |_, c| slide[c]);
    assert!(v.visitable.iter().all(|&x| x));
    assert_eq!((v.round_trip, v.tour_bound), (vec![true, false, false, false], 4));
}

#[test]
fn a_tour_takes_the_larger_of_two_one_way_branches() {
    // A 1 × 7 corridor of 0.45 m cells; the robot turns only in the middle cell (0, 3)
    // (the rule is given, not measured): west is a branch of 3 cells, east one of 3.
    let t = truth_with_cell(3.15, 0.45, 0.45, "Segment(from: (2.25, 0.0), to: (2.25, 0.15))");
    // the segment blocks the move (0, 4) -> (0, 5): the east branch keeps 1 cell.
    assert!(!t.can_move((0, 4), (0, 5)));
    let v = t.visits_with((0, 3), Heading::East, |_, c| c == 3);
    assert_eq!(v.round_trip.iter().filter(|&&x| x).count(), 1);
    assert_eq!(v.tour_bound, 1 + 3, "the middle cell plus the west branch, not both branches");
}

#[test]
fn sliding_away_from_a_wall_inside_the_turning_circle_allows_the_turn() {
    // 3 × 3 cells of 0.45 m; a thin wall 16 cm east of the centre of (1, 1): inside the
    // 17.7 cm turning circle, outside the body (13 cm half-length).
    let (t, slide) = truth_and_slide(1.35, 1.35, 0.45, "Segment(from: (0.835, 0.0), to: (0.835, 1.35))");
    assert!(t.is_free(1, 1) && !t.can_turn(1, 1));
    assert!(slide[4], "2 cm west of the centre the circle clears the wall");
    let v = t.visits_with((1, 0), Heading::East, |r, c| slide[r * 3 + c]);
    assert!(v.round_trip[4]);
}

/// The truth and the collision counter agree on what touching is: a turn at a cell's centre
/// that would pass within 1 mm of a wall is not allowed (found in a generated room where the
/// truth allowed a turn with 0.2 mm to spare and the run counted a collision).
#[test]
fn clearance_under_the_collision_gap_counts_as_touching() {
    // Cell (1, 1) is centred at (0.45, 0.45); the turning circle has a radius of
    // hypot(0.13, 0.12) = 0.1769 m. A thin wall at x = 0.45 + radius + gap.
    let radius = 0.13f32.hypot(0.12);
    let wall_at = |gap: f32| {
        let x = 0.45 + radius + gap;
        truth(&format!("Segment(from: ({x:?}, 0.0), to: ({x:?}, 0.9))"))
    };
    assert!(!wall_at(0.0005).can_turn(1, 1), "0.5 mm: the counter would count a contact");
    assert!(wall_at(0.002).can_turn(1, 1), "2 mm: clear");
}

#[test]
fn a_cell_the_body_cannot_fit_in_is_an_obstacle_cell() {
    // A box covering most of cell (1, 1) (x 0.3..0.6, y 0.3..0.6).
    let t = truth("Box(center: (0.45, 0.45), size: (0.1, 0.1), angle_deg: 30.0)");
    assert!(!t.is_free(1, 1));
    assert!(t.is_free(1, 0) && t.is_free(0, 1));
}

#[test]
fn a_closed_pocket_is_free_but_unreachable() {
    // Walls around the bottom-right cell (2, 3): x 0.9..1.2, y 0..0.3.
    let t = truth("Segment(from: (0.9, 0.0), to: (0.9, 0.3)), Segment(from: (0.9, 0.3), to: (1.2, 0.3))");
    assert!(t.is_free(2, 3));
    assert!(!t.reachable_from((0, 0))[2 * 4 + 3]);
    assert!(t.reachable_from((0, 0))[2 * 4 + 2]);
}
