//! Cartography on grid-only rooms: a fake robot executes every command on a true grid.
//!
//! Each test prints `moves` (commands executed: FORWARDs and turns) against the number of cells
//! reachable from the start, and asserts the sweep covers exactly the reachable cells, never
//! marks a free cell as an obstacle, and stays within `MOVES_PER_CELL` commands per reachable
//! cell (see README, "Coverage figures").

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use cute::cartography::{Cartographer, MoveResult};
use cute::gridsim::{FakeRobot, World};
use cute::map::{CellValue, Map};
use proptest::prelude::*;
use robot_model::grid::{Heading, Move};

/// Upper bound on commands per cell to learn (reachable cells plus the obstacle cells next to
/// them, which can only be learnt by bumping). Measured over 3000 random rooms up to 11 x 11
/// with up to 45 % obstacles: worst 5.5, 99th percentile 3.7, mean 2.3; the named rooms below
/// stay under 2.5.
const MOVES_PER_CELL: f64 = 6.0;

#[derive(Debug)]
struct Report {
    moves: u64,
    reachable: usize,
    /// Truly blocked cells 4-adjacent to a reachable cell: each needs one bump.
    boundary: usize,
    bumps: u64,
    unreachable: usize,
}

fn run(name: &str, text: &str, start: (u8, u8), heading: Heading) -> Report {
    let world = World::parse(text).unwrap();
    run_world(name, world, start, heading)
}

fn run_world(name: &str, world: World, start: (u8, u8), heading: Heading) -> Report {
    let (rows, cols) = (world.rows(), world.cols());
    let reachable = world.reachable_from(start);
    let n_reachable = reachable.iter().filter(|r| **r).count();
    let boundary = (0..rows * cols)
        .filter(|&i| {
            let c = ((i / cols) as u8, (i % cols) as u8);
            world.is_blocked(i / cols, i % cols)
                && Heading::ALL.iter().any(|h| {
                    h.step(c, rows, cols)
                        .is_some_and(|n| reachable[usize::from(n.0) * cols + usize::from(n.1)])
                })
        })
        .count();
    let mut map = Map::new(rows, cols).unwrap();
    map.set_robot(usize::from(start.0), usize::from(start.1)).unwrap();
    let mut carto = Cartographer::new(rows, cols, start, heading).unwrap();

    let mut robot = FakeRobot::new(world.clone(), start, heading);
    // Hard stop far above any sane bound, so a livelock fails instead of hanging.
    let limit = 50 * (rows * cols) as u64 + 100;
    while let Some(cmd) = carto.next_command(&map) {
        if cmd == Move::Forward {
            let ahead = carto.heading().step(carto.pose(), rows, cols);
            let ahead = ahead.expect("never drives off the map");
            assert_ne!(map.at(ahead), Some(CellValue::Obstacle), "{name}: drove into a known obstacle");
        }
        let result = robot.execute(cmd);
        carto.on_result(&mut map, result);
        assert_eq!((carto.pose(), carto.heading()), robot.pose(), "{name}: pose drift");
        assert!(robot.moves() < limit, "{name}: no termination after {limit} moves");
    }
    assert!(carto.is_done());
    for ((x, y), v) in map.iter() {
        let i = usize::from(x) * cols + usize::from(y);
        let truly_blocked = world.is_blocked(usize::from(x), usize::from(y));
        if reachable[i] {
            assert!(v.is_known_free(), "{name}: reachable cell ({x}, {y}) left as {v:?}");
        } else {
            assert!(!v.is_known_free(), "{name}: unreachable cell ({x}, {y}) marked free");
            if v == CellValue::Obstacle {
                assert!(truly_blocked, "{name}: free cell ({x}, {y}) marked obstacle");
            } else {
                assert_eq!(v, CellValue::Unknown);
                assert!(carto.is_unreachable(x, y), "{name}: ({x}, {y}) unknown but not concluded");
            }
        }
    }
    let stats = carto.stats();
    let report = Report {
        moves: robot.moves(),
        reachable: n_reachable,
        boundary,
        bumps: stats.bumps,
        unreachable: stats.unreachable,
    };
    println!(
        "{name}: {rows}x{cols}, reachable {}, boundary {}, moves {} ({:.2}/reachable, {:.2}/learnt), forwards {}, turns {}, bumps {}, searches {}, unreachable {}",
        report.reachable,
        report.boundary,
        report.moves,
        report.moves as f64 / report.reachable.max(1) as f64,
        report.moves as f64 / (report.reachable + report.boundary).max(1) as f64,
        stats.forwards,
        stats.turns,
        stats.bumps,
        stats.searches,
        stats.unreachable
    );
    assert_eq!(stats.commands, report.moves);
    assert_eq!(stats.bumps as usize, report.boundary, "{name}: one bump per boundary cell");
    assert!(
        report.moves as f64 <= MOVES_PER_CELL * (report.reachable + report.boundary) as f64,
        "{name}: {} moves for {} reachable + {} boundary cells",
        report.moves,
        report.reachable,
        report.boundary
    );
    report
}

#[test]
fn empty_rectangle() {
    let room = "............\n".repeat(8);
    let r = run("empty_rectangle", &room, (0, 0), Heading::East);
    assert_eq!(r.reachable, 96);
    // A pure serpentine: one FORWARD per cell but the start, two turns per row change, and no
    // bump (the map's edge is known, so the sweep never drives into it).
    assert_eq!(r.moves, 95 + 2 * 7);
    assert_eq!(r.bumps, 0);
}

#[test]
fn furnished_room_with_boxes() {
    let room = "\
..............
..##......##..
..##..........
.......###....
.......###....
..#...........
..#.....##....
........##....
..............
";
    run("furnished_room", room, (0, 0), Heading::East);
}

#[test]
fn l_shaped_corridor() {
    let room = "\
..##########
..##########
..##########
..##########
............
............
";
    let r = run("l_corridor", room, (0, 0), Heading::South);
    assert_eq!(r.reachable, 8 + 24);
}

#[test]
fn narrow_doorway_between_two_rooms() {
    let room = "\
.....#.....
.....#.....
.....#.....
...........
.....#.....
.....#.....
";
    run("narrow_doorway", room, (0, 0), Heading::East);
}

#[test]
fn many_small_obstacles() {
    let room = "\
..............
.#..#..#..#...
...#....#...#.
.#...#.#...#..
....#.....#...
..#....#....#.
.#..#..#..#...
...#.....#....
..............
";
    run("many_small_obstacles", room, (0, 0), Heading::East);
}

#[test]
fn unreachable_pocket_is_concluded_and_the_sweep_ends() {
    let room = "\
..........
..#####...
..#...#...
..#...#...
..#####...
..........
";
    let r = run("unreachable_pocket", room, (0, 0), Heading::East);
    assert_eq!(r.reachable, 60 - 14 - 6);
    assert!(r.unreachable >= 6, "pocket cells concluded: {}", r.unreachable);
}

#[test]
fn outer_walls_unknown_room_smaller_than_the_map() {
    // The map is 10 x 12 but the room is an irregular area inside it: everything else is wall
    // the robot only learns about by bumping.
    let room = "\
############
#....#######
#..........#
#..........#
###.....####
###.....####
#.........##
#.........##
####....####
############
";
    run("walls_unknown", room, (4, 4), Heading::North);
}

#[test]
fn start_in_the_middle_facing_west() {
    let room = "..........\n".repeat(7);
    run("start_middle", &room, (3, 5), Heading::West);
}

#[test]
fn single_cell_and_single_row() {
    let r = run("single_cell", ".\n", (0, 0), Heading::East);
    assert_eq!((r.moves, r.reachable), (0, 1));
    let r = run("single_row", "......\n", (0, 5), Heading::East);
    assert_eq!(r.reachable, 6);
}

#[test]
fn cartography_results_match_the_map_values() {
    // Drive by hand and check the exact map encoding: 5 robot, 1 visited, 0 bumped, 2 unknown.
    let world = World::parse("..#\n...\n").unwrap();
    let mut robot = FakeRobot::new(world, (0, 0), Heading::East);
    let mut map = Map::new(2, 3).unwrap();
    map.set_robot(0, 0).unwrap();
    let mut carto = Cartographer::new(2, 3, (0, 0), Heading::East).unwrap();
    let mut trace = Vec::new();
    while let Some(cmd) = carto.next_command(&map) {
        let r = robot.execute(cmd);
        trace.push((cmd, r));
        carto.on_result(&mut map, r);
    }
    assert_eq!(trace[0], (Move::Forward, MoveResult::Moved { x: 0, y: 1 }));
    assert_eq!(trace[1], (Move::Forward, MoveResult::Blocked { x: 0, y: 2 }));
    assert_eq!(map.get(0, 2), Some(CellValue::Obstacle));
    assert_eq!(map.count(CellValue::Unknown), 0);
    assert_eq!(map.count(CellValue::Robot), 1);
}

proptest! {
    // A fixed seed: the moves bound is statistical, and the run must be reproducible.
    #![proptest_config(ProptestConfig {
        cases: 64,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0xC0FFEE),
        ..ProptestConfig::default()
    })]
    #[test]
    fn random_rooms_are_always_fully_covered(
        rows in 1usize..12,
        cols in 1usize..12,
        density in 0u8..45,
        bits in proptest::collection::vec(0u8..100, 144),
        start in (0usize..12, 0usize..12),
        heading in 0u8..4,
    ) {
        let start = ((start.0 % rows) as u8, (start.1 % cols) as u8);
        let mut blocked: Vec<bool> =
            (0..rows * cols).map(|i| bits[i] < density).collect();
        blocked[usize::from(start.0) * cols + usize::from(start.1)] = false;
        let world = World::from_cells(rows, cols, blocked).unwrap();
        run_world("random", world, start, Heading::from_u8(heading).unwrap());
    }
}
