//! Tests of `slide`.

use super::*;

/// The default robot: 0.45 m cells, a body 0.26 × 0.24 m, 2 cm clearance, 1 cm band.
fn geometry() -> SlideGeometry {
    SlideGeometry::from_config(&crate::CartoConfig::default())
}

fn all_free(_: (f64, f64), _: (f64, f64)) -> bool {
    true
}

/// The rectangle the grown body covers at `(a, l)` holds none of `points`.
fn keeps_clear(g: &SlideGeometry, (a, l): (f64, f64), points: &[(f64, f64)]) -> bool {
    points.iter().all(|&(pa, pl)| {
        (pa - a).abs() > g.half_length_m + g.clearance_m || (pl - l).abs() > g.half_width_m + g.clearance_m
    })
}

#[test]
fn an_open_floor_needs_no_slide() {
    let slide = plan(&geometry(), (0.0, 0.0), &[], &all_free).unwrap();
    assert_eq!(slide, Slide { legs: vec![], track_left_m: 0.0, stop_along_m: 0.0 });
}

/// A chair leg 20 cm ahead and 10 cm left lies in the straight way (14 cm either side of the
/// line), behind the body standing at B's centre: the way slides right around it and back to
/// the band.
#[test]
fn a_leg_in_the_way_is_passed_by_sliding_and_the_way_ends_in_the_band() {
    let g = geometry();
    let leg = [(0.20, 0.10)];
    let slide = plan(&g, (0.0, 0.0), &leg, &all_free).unwrap();
    assert!(slide.track_left_m.abs() <= g.band_m + 1e-9, "{slide:?}");
    assert!(!slide.legs.is_empty(), "{slide:?}");
    // every leg, sampled finely, keeps the clearance; then the last drive along its track
    let mut at = (0.0, 0.0);
    for &to in slide.legs.iter().chain([(g.cell_m, slide.track_left_m)].iter()) {
        for t in 0..=100 {
            let f = f64::from(t) / 100.0;
            let p = (at.0 + f * (to.0 - at.0), at.1 + f * (to.1 - at.1));
            assert!(keeps_clear(&g, p, &leg), "{p:?} on the way {slide:?}");
        }
        at = to;
    }
}

/// The same leg with room to spare: the way passes it with the comfort beyond the
/// clearance, not grazing the clearance as the shortest way would.
#[test]
fn where_the_space_allows_the_way_keeps_more_than_the_clearance() {
    let g = geometry();
    let leg = [(0.20, 0.10)];
    let slide = plan(&g, (0.0, 0.0), &leg, &all_free).unwrap();
    let gap = |(a, l): (f64, f64)| {
        let (da, dl) = (
            (0.20 - a).abs() - g.half_length_m - g.clearance_m,
            (0.10 - l).abs() - g.half_width_m - g.clearance_m,
        );
        da.max(0.0).hypot(dl.max(0.0))
    };
    let mut at = (0.0, 0.0);
    let mut least = f64::INFINITY;
    for &to in slide.legs.iter().chain([(g.cell_m, slide.track_left_m)].iter()) {
        for t in 0..=100 {
            let f = f64::from(t) / 100.0;
            least = least.min(gap((at.0 + f * (to.0 - at.0), at.1 + f * (to.1 - at.1))));
        }
        at = to;
    }
    assert!(least >= COMFORT_M - STEP_M, "passed {least:.3} m beyond the clearance: {slide:?}");
}

#[test]
fn no_way_when_the_space_beside_the_band_is_not_known_free() {
    let leg = [(0.20, 0.10)];
    assert_eq!(plan(&geometry(), (0.0, 0.0), &leg, &|_, _| false), None);
}

/// Points 1 cm apart on a wall across the way, from 30 cm right to 30 cm left, whose surface
/// lies `inside` metres inside the clearance of the body standing at B's centre.
fn wall_inside_the_clearance(g: &SlideGeometry, inside: f64) -> Vec<(f64, f64)> {
    let at_centre = g.cell_m + g.half_length_m + g.clearance_m;
    (-30..=30).map(|k| (at_centre - inside, f64::from(k) * 0.01)).collect()
}

/// A wall across the way whose surface lies 6 mm inside the clearance of the body at B's
/// centre: the FORWARD stops short within the band; 15 mm inside, beyond the band, no way.
#[test]
fn a_wall_just_inside_the_clearance_at_the_next_centre_stops_the_way_short() {
    let g = geometry();
    let wall = |inside: f64| wall_inside_the_clearance(&g, inside);
    let slide = plan(&g, (0.0, 0.0), &wall(0.006), &all_free).unwrap();
    assert!(slide.legs.is_empty(), "{slide:?}");
    assert!(slide.stop_along_m <= -0.006 && slide.stop_along_m >= -g.band_m - 1e-9, "{slide:?}");
    assert!(slide.track_left_m.hypot(slide.stop_along_m) <= g.band_m + 1e-9, "{slide:?}");
    // nothing in the way: the FORWARD ends on the centre
    assert_eq!(plan(&g, (0.0, 0.0), &wall(-0.01), &all_free).map(|s| s.stop_along_m), Some(0.0));
    assert_eq!(plan(&g, (0.0, 0.0), &wall(0.015), &all_free), None);
}

/// A wall 1.5 cm inside the clearance of the body at B's centre: the body keeps the
/// clearance 2 cm short of the centre (within `stop_within_m`); 3 cm inside, nowhere in B.
#[test]
fn the_body_fits_in_a_cell_within_its_stop_tolerance_of_the_centre() {
    let g = geometry();
    let wall = |inside: f64| wall_inside_the_clearance(&g, inside);
    let keep = g.clearance_m;
    assert!(fits_near(&g, (g.cell_m, 0.0), keep, &[]));
    assert!(fits_near(&g, (g.cell_m, 0.0), keep, &wall(0.015)));
    assert!(!fits_near(&g, (g.cell_m, 0.0), keep, &wall(0.03)));
    // the body itself, keeping nothing, fits 3 cm inside the clearance
    assert!(fits_near(&g, (g.cell_m, 0.0), 0.0, &wall(0.03)));
}

/// A wall across the way, 40 cm ahead, from 30 cm right to 30 cm left: no way round inside
/// the two cells.
#[test]
fn a_wall_across_both_cells_leaves_no_way() {
    let wall: Vec<_> = (-30..=30).map(|k| (0.40, f64::from(k) * 0.01)).collect();
    assert_eq!(plan(&geometry(), (0.0, 0.0), &wall, &all_free), None);
}

/// A body 9 cm left of the line (a turn that stayed off the centre) with a wall 16 cm beyond
/// the band on the right: the way slides back towards the line as it drives.
#[test]
fn a_body_off_the_line_slides_back_to_the_band() {
    let g = geometry();
    let slide = plan(&g, (0.0, 0.09), &[(0.10, -0.30)], &all_free).unwrap();
    assert!(slide.track_left_m.abs() <= g.band_m + 1e-9, "{slide:?}");
}

/// A table leg 17 cm ahead and 3 cm left of the centre lies in the turning circle (19.7 cm
/// with the clearance): the body backs off and aside to where the circle clears it, by as
/// little as the comfort allows, and stays in its cell; a leg on every side leaves no place.
#[test]
fn a_turn_slides_to_where_its_circle_clears_the_known_points() {
    let g = geometry();
    let leg = [(0.17, 0.03)];
    let legs = plan_turn(&g, (0.0, 0.0), &leg, &all_free).unwrap();
    let &(a, l) = legs.last().unwrap();
    let gap = (0.17 - a).hypot(0.03 - l) - g.turn_clear_m;
    assert!((COMFORT_M..COMFORT_M + 3.0 * STEP_M).contains(&gap), "{gap:.3} m beyond the circle: {legs:?}");
    assert!(a.abs() <= g.cell_m / 2.0 && l.abs() <= g.cell_m / 2.0, "left the cell: {legs:?}");
    assert_eq!(plan_turn(&g, (0.0, 0.0), &[(0.30, 0.0)], &all_free), Some(vec![]), "a clear circle");
    let ring: Vec<_> =
        (0..36).map(|k| f64::from(k * 10).to_radians()).map(|t| (0.18 * t.cos(), 0.18 * t.sin())).collect();
    assert_eq!(plan_turn(&g, (0.0, 0.0), &ring, &all_free), None);
}

/// The body stopped 1 cm from a wall on its right (inside the 2 cm clearance) with a leg in
/// its turning circle ahead: it may still slide, away from the wall, never nearer it.
#[test]
fn a_body_within_the_clearance_of_a_wall_may_move_but_no_nearer() {
    let g = geometry();
    let wall: Vec<_> = (-25..=25).map(|k| (f64::from(k) * 0.01, -0.13)).collect();
    let mut points = wall.clone();
    points.push((0.17, 0.03));
    let legs = plan_turn(&g, (0.0, 0.0), &points, &all_free).unwrap();
    assert!(!legs.is_empty());
    let mut at = (0.0, 0.0);
    for &to in &legs {
        assert!(to.1 >= at.1 - 1e-9, "slid towards the wall: {legs:?}");
        at = to;
    }
    // walls 1 cm from both flanks: no move leaves the one without nearing the other
    let both: Vec<_> = wall.iter().flat_map(|&(a, l)| [(a, l), (a, -l)]).chain([(0.17, 0.03)]).collect();
    assert_eq!(plan_turn(&g, (0.0, 0.0), &both, &all_free), None);
}

#[test]
fn bad_input_plans_nothing() {
    assert_eq!(plan(&geometry(), (f64::NAN, 0.0), &[], &all_free), None);
    let g = SlideGeometry { cell_m: 0.0, ..geometry() };
    assert_eq!(plan(&g, (0.0, 0.0), &[], &all_free), None);
}
