//! Cute's cartography on every scenario room in a pure grid simulation (no physics): the true
//! grid comes from the scenario's geometry, a grid-only robot executes Cute's commands. Every
//! reachable cell must end mapped free; the move count is printed next to the number of
//! reachable cells (`cargo test --test e2e grid_coverage -- --nocapture`) and bounded.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use cute::cartography::Cartographer;
use cute::gridsim::{FakeRobot, World};
use cute::map::Map;
use twin::setup::RunSetup;

#[test]
fn cartography_maps_every_reachable_cell_of_every_scenario_room() {
    let mut rooms = 0;
    for entry in std::fs::read_dir("../scenarios").unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "ron") {
            continue;
        }
        let loaded = RunSetup::load(&path).unwrap();
        let truth = loaded.truth();
        let (rows, cols) = (truth.rows, truth.cols);
        let blocked = (0..rows * cols).map(|i| !truth.is_free(i / cols, i % cols)).collect();
        let world = World::from_cells(rows, cols, blocked).unwrap();
        let s = loaded.scenario.start;
        let start = (s.row, s.col);
        let reachable = truth.reachable_from((usize::from(s.row), usize::from(s.col)));
        let n_reachable = reachable.iter().filter(|r| **r).count();

        let mut map = Map::new(rows, cols).unwrap();
        let mut carto = Cartographer::new(rows, cols, start, s.heading).unwrap();
        let mut robot = FakeRobot::new(world, start, s.heading);
        while let Some(cmd) = carto.next_command(&map) {
            let result = robot.execute(cmd);
            carto.on_result(&mut map, result);
            assert!(robot.moves() < 20 * (rows * cols) as u64, "{}: no end", path.display());
        }
        for row in 0..rows {
            for col in 0..cols {
                let known_free = map.get(row, col).is_some_and(|v| v.is_known_free());
                assert_eq!(
                    known_free,
                    reachable[row * cols + col],
                    "{}: cell ({row}, {col})",
                    path.display()
                );
            }
        }
        let ratio = robot.moves() as f64 / n_reachable as f64;
        println!(
            "{:<20} {rows:>2}x{cols:<2} reachable {n_reachable:>3}  moves {:>4}  ({ratio:.2} per reachable cell)",
            loaded.scenario.name,
            robot.moves()
        );
        // Measured: 1.19 (empty) to 3.09 (L-corridor, where every wall cell must be bumped
        // into). More than 4 moves per reachable cell would be a regression of the sweep.
        assert!(ratio <= 4.0, "{}: {ratio:.2} moves per reachable cell", path.display());
        rooms += 1;
    }
    assert!(rooms >= 10, "only {rooms} scenario rooms found");
}
