use super::*;

#[test]
fn a_refused_forward_blocks_the_move_into_a_free_cell_and_marks_any_other_cell() {
    let mut map = Map::parse("512\n").unwrap();
    assert_eq!(map.note_refused_forward((0, 0), (0, 1)), Refusal::MoveBlocked { new: true });
    assert_eq!(map.note_refused_forward((0, 1), (0, 0)), Refusal::MoveBlocked { new: false });
    assert!(map.is_move_blocked((0, 1), (0, 0)) && map.is_move_blocked((0, 0), (0, 1)));
    assert_eq!(map.to_text(), "512\n", "the cells keep their values");
    assert_eq!(map.note_refused_forward((0, 1), (0, 2)), Refusal::Obstacle);
    assert_eq!(map.to_text(), "510\n");
    assert_eq!(map.note_refused_forward((0, 2), (0, 3)), Refusal::Nothing, "off the map");
    assert_eq!(map.note_refused_forward((0, 0), (0, 0)), Refusal::Nothing, "the robot's cell");
    assert_eq!(map.blocked_moves().collect::<Vec<_>>(), vec![((0, 0), (0, 1))]);
    map.reset();
    assert_eq!(map.blocked_moves().count(), 0);
}

#[test]
fn block_move_needs_two_neighbours_on_the_map() {
    let mut map = Map::new(2, 2).unwrap();
    assert_eq!(map.block_move((0, 0), (1, 1)), Err(MapError::NotNeighbours { a: (0, 0), b: (1, 1) }));
    assert!(matches!(map.block_move((1, 1), (1, 2)), Err(MapError::OutOfBounds { .. })));
    assert_eq!(map.block_move((1, 1), (0, 1)), Ok(true));
    assert_eq!(map.blocked_moves().collect::<Vec<_>>(), vec![((0, 1), (1, 1))]);
}

#[test]
fn new_map_is_all_unknown_and_sized() {
    let map = Map::new(4, 7).unwrap();
    assert_eq!((map.rows(), map.cols()), (4, 7));
    assert_eq!(map.count(CellValue::Unknown), 28);
    assert_eq!(map.get(4, 0), None);
    assert_eq!(map.get(0, 7), None);
    assert!(Map::new(256, 256).is_ok());
    assert_eq!(Map::new(0, 3), Err(MapError::BadSize { rows: 0, cols: 3 }));
    assert_eq!(Map::new(3, 257), Err(MapError::BadSize { rows: 3, cols: 257 }));
}

#[test]
fn values_convert_to_and_from_numbers() {
    for n in 0..=5u8 {
        let v = CellValue::try_from(n).unwrap();
        assert_eq!(u8::from(v), n);
    }
    assert_eq!(CellValue::try_from(6), Err(MapError::BadValue { value: 6 }));
    assert!(CellValue::Robot.is_known_free());
    assert!(!CellValue::Unknown.is_known_free());
    assert!(!CellValue::Obstacle.is_known_free());
}

#[test]
fn iteration_is_row_major() {
    let mut map = Map::new(2, 3).unwrap();
    map.set(1, 0, CellValue::Obstacle).unwrap();
    let cells: Vec<_> = map.iter().map(|(c, _)| c).collect();
    assert_eq!(cells, vec![(0, 0), (0, 1), (0, 2), (1, 0), (1, 1), (1, 2)]);
    assert_eq!(map.iter().nth(3), Some(((1, 0), CellValue::Obstacle)));
    assert_eq!(map.row(1).unwrap()[0], CellValue::Obstacle);
}

#[test]
fn robot_and_destination_markers_stay_unique() {
    let mut map = Map::new(3, 3).unwrap();
    map.set_robot(0, 0).unwrap();
    map.set_robot(0, 1).unwrap();
    assert_eq!(map.get(0, 0), Some(CellValue::Free));
    assert_eq!(map.count(CellValue::Robot), 1);
    map.set(2, 2, CellValue::Destination).unwrap();
    map.set_destination(1, 1).unwrap();
    assert_eq!(map.get(2, 2), Some(CellValue::Free));
    assert_eq!(map.destination(), Some((1, 1)));
    map.set_waypoint(1, 0).unwrap();
    map.clear_trajectory();
    assert_eq!(map.count(CellValue::Waypoint) + map.count(CellValue::Destination), 0);
    assert_eq!(map.destination(), None);
    assert_eq!(map.robot(), Some((0, 1)));
    map.set_obstacle(0, 1).unwrap();
    assert_eq!(map.robot(), None);
}

#[test]
fn reset_sets_everything_unknown() {
    let mut map = Map::parse("5100\n0014\n").unwrap();
    map.reset();
    assert_eq!(map.count(CellValue::Unknown), 8);
    assert_eq!((map.robot(), map.destination()), (None, None));
}

#[test]
fn out_of_bounds_writes_are_errors() {
    let mut map = Map::new(2, 2).unwrap();
    assert_eq!(map.set(2, 0, CellValue::Free), Err(MapError::OutOfBounds { x: 2, y: 0, rows: 2, cols: 2 }));
    assert!(map.set_robot(0, 2).is_err());
}

#[test]
fn text_round_trip_and_errors() {
    let text = "# reference vector 1\n5111\n0201\n0001\n0004\n";
    let map = Map::parse(text).unwrap();
    assert_eq!(map.robot(), Some((0, 0)));
    assert_eq!(map.destination(), Some((3, 3)));
    assert_eq!(map.to_text(), "5111\n0201\n0001\n0004\n");
    assert_eq!(Map::parse("1,1,1\n0 0 0\n").unwrap().cols(), 3);
    let err = |line, column, problem| Err(MapError::text(line, column, problem));
    assert_eq!(Map::parse("11\n1x\n"), err(2, 2, TextProblem::BadChar { found: 'x' }));
    assert_eq!(Map::parse("# c\n1, 1\n 1,\t7\n"), err(3, 5, TextProblem::BadChar { found: '7' }));
    assert_eq!(Map::parse("11\n111\n"), err(2, 3, TextProblem::RaggedRow { got: 3, expected: 2 }));
    assert_eq!(Map::parse("1 1 1\n1 1\n"), err(2, 4, TextProblem::RaggedRow { got: 2, expected: 3 }));
    assert_eq!(Map::parse("15\n\n51\n"), err(3, 1, TextProblem::Duplicate { what: "robot" }));
    let text = Map::parse("12\n3x\n").unwrap_err().to_string();
    assert_eq!(text, "line 2, column 2: 'x' is not a cell value (0..=5)");
    assert!(matches!(Map::parse(""), Err(MapError::BadSize { .. })));
}

#[test]
fn a_way_not_clear_blocks_the_move_and_keeps_the_cell_unknown() {
    let mut map = Map::new(1, 3).unwrap();
    map.set_robot(0, 0).unwrap();
    assert_eq!(map.note_way_not_clear((0, 0), (0, 1)), Refusal::MoveBlocked { new: true });
    assert_eq!(map.note_way_not_clear((0, 1), (0, 0)), Refusal::MoveBlocked { new: false });
    assert_eq!(map.get(0, 1), Some(CellValue::Unknown));
    assert!(map.is_move_blocked((0, 0), (0, 1)) && !map.is_move_blocked((0, 1), (0, 2)));
    assert_eq!(map.note_way_not_clear((0, 0), (0, 2)), Refusal::Nothing, "not neighbours");
    assert_eq!(map.note_way_not_clear((0, 2), (0, 3)), Refusal::Nothing, "off the map");
    assert_eq!(map.note_way_not_clear((0, 0), (0, 0)), Refusal::Nothing, "the robot's cell");
}
