//! Tests of `grid`.

use super::*;

fn east(x: f64, y: f64) -> Pose2 {
    Pose2 { x, y, yaw_deg: 0.0 }
}

#[test]
fn evidence_is_clamped_so_that_no_reading_decides_for_ever() {
    let mut g = EvidenceGrid::new(GridParams::default());
    let c = (3, -4);
    assert_eq!(g.cell(c), Occupancy::Unknown);
    for _ in 0..100 {
        g.add(c, 1.0);
    }
    assert_eq!(g.cell(c), Occupancy::Occupied);
    assert!((g.log_odds(c) - 3.5).abs() < 1e-9, "{}", g.log_odds(c));
    // Five readings that see through it at 0.9 each make it free again.
    for _ in 0..5 {
        g.add(c, -0.9);
    }
    assert_eq!(g.cell(c), Occupancy::Free);
}

#[test]
fn pinned_cells_ignore_every_update() {
    let mut g = EvidenceGrid::new(GridParams::default());
    g.pin_segment((0.0, 0.0), (0.1, 0.0));
    let c = g.cell_of(0.05, 0.0);
    g.add(c, -10.0);
    g.set_certain(c, false);
    g.clear_rect(east(0.05, 0.0), -0.2, 0.2, 0.2);
    assert_eq!(g.cell(c), Occupancy::Occupied);
    assert_eq!(g.log_odds(c), f64::INFINITY);
}

#[test]
fn negative_coordinates_map_to_their_own_cells() {
    let g = EvidenceGrid::new(GridParams::default());
    assert_eq!(g.cell_of(-0.001, -0.001), (-1, -1));
    assert_eq!(g.cell_of(0.0, 0.019), (0, 0));
    let (x, y) = g.centre((-1, 2));
    assert!((x + 0.01).abs() < 1e-12 && (y - 0.05).abs() < 1e-12);
}

#[test]
fn rect_queries_follow_the_heading_and_answer_the_worst() {
    let mut g = EvidenceGrid::new(GridParams::default());
    let north = Pose2 { x: 0.0, y: 0.0, yaw_deg: 90.0 };
    g.clear_rect(north, 0.0, 0.5, 0.15);
    assert_eq!(g.classify_rect(north, 0.05, 0.45, 0.1), Occupancy::Free);
    // A leg 30 cm ahead and 5 cm to the left (west) of the track.
    g.mark_segment((-0.05, 0.30), (-0.05, 0.30));
    assert_eq!(g.classify_rect(north, 0.05, 0.45, 0.1), Occupancy::Occupied);
    let hit = g.first_occupied_in_rect(north, 0.05, 0.45, 0.1).unwrap();
    assert!((hit.0 + 0.05).abs() <= 0.015 && (hit.1 - 0.30).abs() <= 0.015, "{hit:?}");
    // 10 cm further out to the side it is not in a corridor 7 cm wide either side.
    assert!(g.first_occupied_in_rect(north, 0.05, 0.45, 0.03).is_none());
    // Facing east, the same leg is behind the corridor's side.
    assert!(g.first_occupied_in_rect(east(0.0, 0.0), 0.0, 0.45, 0.1).is_none());
}

#[test]
fn rect_queries_along_the_grid_take_exactly_the_cells_that_overlap() {
    let g = EvidenceGrid::new(GridParams::default());
    let cells = g.cells_in_rect(east(0.0, 0.0), 0.0, 0.2, 0.1);
    assert!(cells.contains(&g.cell_of(0.05, 0.11)), "the cell from 0.10 to 0.12 touches the edge");
    assert!(!cells.contains(&g.cell_of(0.05, 0.13)), "the cell from 0.12 to 0.14 does not");
    assert!(!cells.contains(&g.cell_of(0.23, 0.0)), "nor the cell from 0.22 to 0.24 beyond the end");
}

#[test]
fn clearing_a_rect_leaves_the_cells_half_under_its_edge() {
    let mut g = EvidenceGrid::new(GridParams::default());
    g.mark_segment((0.30, -0.2), (0.30, 0.2)); // a wall across, 30 cm ahead
    g.clear_rect(east(0.0, 0.0), -0.1, 0.30, 0.12); // the body's front face touches it
    assert_eq!(g.cell(g.cell_of(0.30, 0.0)), Occupancy::Occupied);
    assert_eq!(g.cell(g.cell_of(0.15, 0.0)), Occupancy::Free);
}

#[test]
fn circle_queries_cover_the_disc() {
    let mut g = EvidenceGrid::new(GridParams::default());
    for c in g.cells_in_circle((1.0, 1.0), 0.2) {
        g.set_certain(c, false);
    }
    assert_eq!(g.classify_circle((1.0, 1.0), 0.19), Occupancy::Free);
    assert_eq!(g.classify_circle((1.0, 1.0), 0.3), Occupancy::Unknown);
    g.mark_segment((1.14, 1.14), (1.14, 1.14)); // 19.8 cm from the centre
    assert_eq!(g.classify_circle((1.0, 1.0), 0.19), Occupancy::Occupied);
    assert_eq!(g.classify_circle((1.0, 1.0), 0.15), Occupancy::Free);
    let near = g.nearest_occupied_in_circle((1.0, 1.0), 0.19).unwrap();
    assert!((near.0 - 1.14).abs() <= 0.015 && (near.1 - 1.14).abs() <= 0.015, "{near:?}");
    assert_eq!(g.nearest_occupied_in_circle((1.0, 1.0), 0.15), None);
}

#[test]
fn memory_stays_within_its_bound_and_evicts_far_tiles_first() {
    let params = GridParams { max_tiles: 4, ..GridParams::default() };
    let side = TILE as f64 * params.resolution_m;
    let mut g = EvidenceGrid::new(params);
    g.set_robot(0.0, 0.0);
    for k in 0..10 {
        g.add(g.cell_of(k as f64 * side, 0.0), 1.0);
        assert!(g.memory_bytes() <= 4 * TILE * TILE);
    }
    // Near the origin, each new tile is the farthest, so the last one written went next.
    assert!(g.log_odds(g.cell_of(0.0, 0.0)) > 0.0);
    g.set_robot(9.0 * side, 0.0);
    g.add(g.cell_of(20.0 * side, 0.0), 1.0);
    assert_eq!(g.log_odds(g.cell_of(0.0, 0.0)), 0.0, "the far origin tile was evicted");
    assert!(g.log_odds(g.cell_of(20.0 * side, 0.0)) > 0.0);
}

#[test]
fn a_fifteen_metre_room_fits_in_about_a_megabyte() {
    let mut g = EvidenceGrid::new(GridParams::default());
    for i in 0..=150 {
        for j in 0..=150 {
            g.add(g.cell_of(f64::from(i) * 0.1, f64::from(j) * 0.1), -0.5);
        }
    }
    assert!(g.memory_bytes() <= 1 << 20, "{}", g.memory_bytes());
    assert!(g.memory_bytes() >= 15 * 15 * 2500, "every cell of the room is held");
}
