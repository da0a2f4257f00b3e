use super::*;

fn grid_from(text: &str) -> Grid {
    let lines: Vec<&str> = text.lines().map(str::trim).filter(|l| !l.is_empty()).collect();
    Grid::from_fn(lines.len(), lines[0].len(), |r, c| u8::from(lines[r].as_bytes()[c] != b'#')).unwrap()
}

fn check_path(grid: &Grid, path: &Path, start: (usize, usize), goal: (usize, usize)) {
    assert_eq!(path.cells.first(), Some(&start));
    assert_eq!(path.cells.last(), Some(&goal));
    let mut total = 0u32;
    for w in path.cells.windows(2) {
        let d = w[0].0.abs_diff(w[1].0) + w[0].1.abs_diff(w[1].1);
        assert_eq!(d, 1, "non-adjacent step {:?}", w);
        assert!(grid.is_passable(w[1].0, w[1].1));
        assert!(grid.is_move_open(w[0], w[1]), "blocked move {:?}", w);
        total += u32::from(grid.cost(w[1].0, w[1].1));
    }
    assert_eq!(total, path.cost);
}

/// Plain Dijkstra (BFS for unit costs) as an oracle.
fn oracle(grid: &Grid, start: (usize, usize), goal: (usize, usize)) -> Option<u32> {
    let mut dist = vec![u32::MAX; grid.rows * grid.cols];
    let mut heap = BinaryHeap::new();
    dist[start.0 * grid.cols + start.1] = 0;
    heap.push(Reverse((0u32, start)));
    while let Some(Reverse((d, (r, c)))) = heap.pop() {
        if (r, c) == goal {
            return Some(d);
        }
        if d > dist[r * grid.cols + c] {
            continue;
        }
        for (dr, dc) in DELTAS {
            let (nr, nc) = (r.wrapping_add_signed(dr), c.wrapping_add_signed(dc));
            if grid.is_passable(nr, nc) && grid.is_move_open((r, c), (nr, nc)) {
                let nd = d + u32::from(grid.cost(nr, nc));
                if nd < dist[nr * grid.cols + nc] {
                    dist[nr * grid.cols + nc] = nd;
                    heap.push(Reverse((nd, (nr, nc))));
                }
            }
        }
    }
    None
}

/// A thin wall on the line between two free cells: the path goes round it, in every order.
#[test]
fn a_blocked_move_between_free_cells_is_walked_round() {
    let mut grid = Grid::open(2, 3).unwrap();
    assert!(grid.block_move((0, 1), (0, 2)));
    assert!(!grid.is_move_open((0, 2), (0, 1)), "blocked both ways");
    assert!(grid.is_move_open((0, 1), (1, 1)));
    assert!(grid.is_passable(0, 2), "the cells stay free");
    let mut a = AStar::new();
    for tb in [TieBreak::Fast, TieBreak::Reference, TieBreak::Original] {
        let p = a.search_with(&grid, (0, 0), (0, 2), tb).unwrap();
        assert_eq!(p.cost, 4, "{tb:?}");
        check_path(&grid, &p, (0, 0), (0, 2));
        assert_eq!(p.cells[p.cells.len() - 2], (1, 2), "{tb:?}: the goal is entered from below");
    }
    // closing the way below too leaves no path
    assert!(grid.block_move((1, 2), (1, 1)));
    for tb in [TieBreak::Fast, TieBreak::Reference, TieBreak::Original] {
        assert_eq!(a.search_with(&grid, (0, 0), (0, 2), tb), None, "{tb:?}");
    }
    grid.open_all_moves();
    assert_eq!(a.search(&grid, (0, 0), (0, 2)).map(|p| p.cost), Some(2));
}

#[test]
fn block_move_refuses_cells_that_are_not_neighbours() {
    let mut grid = Grid::open(3, 3).unwrap();
    assert!(!grid.block_move((0, 0), (1, 1)));
    assert!(!grid.block_move((0, 0), (0, 2)));
    assert!(!grid.block_move((2, 2), (2, 3)), "off the grid");
    assert!(!grid.block_move((1, 1), (1, 1)));
    assert!(!grid.is_move_open((2, 2), (2, 3)));
    assert_eq!(grid, Grid::open(3, 3).unwrap());
}

#[test]
fn straight_line_on_open_grid() {
    let grid = Grid::open(5, 8).unwrap();
    let mut a = AStar::new();
    for tb in [TieBreak::Fast, TieBreak::Reference, TieBreak::Original] {
        let p = a.search_with(&grid, (2, 0), (2, 7), tb).unwrap();
        assert_eq!(p.cost, 7);
        check_path(&grid, &p, (2, 0), (2, 7));
        assert!(p.cells.iter().all(|(r, _)| *r == 2));
    }
}

#[test]
fn around_a_wall() {
    let grid = grid_from(
        "
        .....
        .###.
        ..#..
        ..#..
        ",
    );
    let mut a = AStar::new();
    for tb in [TieBreak::Fast, TieBreak::Reference] {
        let p = a.search_with(&grid, (3, 0), (3, 4), tb).unwrap();
        assert_eq!(p.cost, 10);
        check_path(&grid, &p, (3, 0), (3, 4));
    }
}

#[test]
fn no_path_blocked_goal_and_out_of_bounds_are_none() {
    let grid = grid_from(
        "
        ..#..
        ..#..
        ",
    );
    let mut a = AStar::new();
    for tb in [TieBreak::Fast, TieBreak::Reference] {
        assert!(a.search_with(&grid, (0, 0), (0, 4), tb).is_none());
        assert!(a.search_with(&grid, (0, 0), (0, 2), tb).is_none());
        assert!(a.search_with(&grid, (0, 0), (2, 0), tb).is_none());
        assert!(a.search_with(&grid, (9, 0), (0, 1), tb).is_none());
    }
    // The planner is still usable after failures.
    assert_eq!(a.search(&grid, (0, 0), (1, 1)).unwrap().cost, 2);
}

#[test]
fn start_equals_goal_and_blocked_start() {
    let mut grid = Grid::open(3, 3).unwrap();
    let mut a = AStar::new();
    assert_eq!(a.search(&grid, (1, 1), (1, 1)).unwrap().cells, vec![(1, 1)]);
    grid.set_cost(0, 0, 0); // the robot's own cell may be marked blocked
    let p = a.search(&grid, (0, 0), (2, 2)).unwrap();
    assert_eq!(p.cost, 4);
}

#[test]
fn weighted_cells_are_avoided_when_cheaper() {
    // Unknown cells cost 3: the planner goes round through the known (cost 1) ring.
    let mut grid = Grid::open(3, 5).unwrap();
    for c in 1..4 {
        grid.set_cost(1, c, 3);
    }
    let mut a = AStar::new();
    for tb in [TieBreak::Fast, TieBreak::Reference] {
        let p = a.search_with(&grid, (1, 0), (1, 4), tb).unwrap();
        assert_eq!(p.cost, 6);
        assert_eq!(Some(6), oracle(&grid, (1, 0), (1, 4)));
        check_path(&grid, &p, (1, 0), (1, 4));
    }
}

#[test]
fn reference_order_prefers_smaller_row_then_column_on_ties() {
    // On an open grid every monotone path is optimal; (f, row, col) expands row 0 first,
    // so the original's path goes East along row 0 before turning South.
    let grid = Grid::open(3, 3).unwrap();
    let mut a = AStar::new();
    for tb in [TieBreak::Reference, TieBreak::Original] {
        let p = a.search_with(&grid, (0, 0), (2, 2), tb).unwrap();
        assert_eq!(p.cells, vec![(0, 0), (0, 1), (0, 2), (1, 2), (2, 2)]);
    }
}

#[test]
fn original_planner_can_be_suboptimal() {
    // Found by running the original `a_star_search` against BFS on random grids: it returns
    // 14 moves where 12 suffice, because an improved open node keeps its stale heap key.
    let grid = grid_from(
        "
        ...........
        #....#.....
        ....#......
        ...........
        ",
    );
    let mut a = AStar::new();
    let original = a.search_with(&grid, (3, 0), (1, 10), TieBreak::Original).unwrap();
    assert_eq!(original.cost, 14);
    check_path(&grid, &original, (3, 0), (1, 10));
    for tb in [TieBreak::Reference, TieBreak::Fast] {
        assert_eq!(a.search_with(&grid, (3, 0), (1, 10), tb).unwrap().cost, 12);
    }
}

#[test]
fn fast_expands_few_nodes_on_open_ground() {
    let grid = Grid::open(200, 200).unwrap();
    let mut a = AStar::new();
    let p = a.search(&grid, (10, 10), (150, 180)).unwrap();
    assert_eq!(p.cost, 310);
    assert!(a.last_expanded() <= 2 * 311, "expanded {}", a.last_expanded());
}

#[test]
fn generations_do_not_leak_between_queries() {
    let mut grid = Grid::open(6, 6).unwrap();
    let mut a = AStar::new();
    assert_eq!(a.search(&grid, (0, 0), (5, 5)).unwrap().cost, 10);
    for r in 0..5 {
        grid.set_cost(r, 3, 0);
    }
    assert_eq!(a.search(&grid, (0, 0), (0, 5)).unwrap().cost, 15);
    let small = Grid::open(2, 2).unwrap();
    assert_eq!(a.search(&small, (0, 0), (1, 1)).unwrap().cost, 2);
}

#[test]
fn generation_wrap_clears_stamps() {
    let grid = Grid::open(4, 4).unwrap();
    let mut a = AStar::new();
    a.search(&grid, (0, 0), (3, 3)).unwrap();
    a.generation = u32::MAX - 1;
    for _ in 0..3 {
        assert_eq!(a.search(&grid, (3, 3), (0, 0)).unwrap().cost, 6);
    }
}

#[test]
fn grid_size_limits() {
    assert!(Grid::open(0, 5).is_err());
    assert!(Grid::blocked(1 << 20, 1 << 20).is_err());
    assert!(Grid::open(1, 1).is_ok());
}

mod prop {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]
        #[test]
        fn both_orders_are_optimal(
            rows in 1usize..14, cols in 1usize..14,
            cells in proptest::collection::vec(0u8..6, 196),
            s in (0usize..14, 0usize..14), t in (0usize..14, 0usize..14),
            unit in proptest::bool::ANY,
            walls in proptest::collection::vec((0usize..14, 0usize..14, 0usize..4), 0..30),
        ) {
            // 0 → blocked, 1..=3 → cost 1, 4..=5 → cost 3 (or 1 with unit costs).
            let mut grid = Grid::from_fn(rows, cols, |r, c| match cells[r * 14 + c] {
                0 => 0, 1..=3 => 1, _ => if unit { 1 } else { 3 },
            }).unwrap();
            // thin walls between neighbours (those leaving the grid are refused and ignored)
            for (r, c, d) in walls {
                let (dr, dc) = DELTAS[d];
                if let (Some(nr), Some(nc)) = (r.checked_add_signed(dr), c.checked_add_signed(dc)) {
                    grid.block_move((r, c), (nr, nc));
                }
            }
            let start = (s.0 % rows, s.1 % cols);
            let goal = (t.0 % rows, t.1 % cols);
            let mut a = AStar::new();
            let want = if start == goal { Some(0) } else if grid.is_passable(goal.0, goal.1) {
                oracle(&grid, start, goal)
            } else { None };
            for tb in [TieBreak::Fast, TieBreak::Reference] {
                let got = a.search_with(&grid, start, goal, tb);
                prop_assert_eq!(got.as_ref().map(|p| p.cost), want, "{:?}", tb);
                if let Some(p) = got { check_path(&grid, &p, start, goal); }
            }
            // The original finds a path exactly when one exists, not always a shortest one.
            let got = a.search_with(&grid, start, goal, TieBreak::Original);
            prop_assert_eq!(got.is_some(), want.is_some());
            if let (Some(p), Some(w)) = (got, want) {
                prop_assert!(p.cost >= w);
                check_path(&grid, &p, start, goal);
            }
        }
    }
}
