//! The scenario and its start cell, and its RON text.

use super::*;
use super::{draft::*, geometry::*};

pub(super) fn finish(
    mut d: Draft,
    style: RoomStyle,
    seed: u64,
    sub_seed: u32,
    profile: &RobotProfile,
    rng: &mut ChaCha8Rng,
) -> Option<GeneratedRoom> {
    d.count_furniture();
    let pieces: Vec<Piece> = d
        .placed
        .iter()
        .filter(|p| p.item.kind != Kind::Clear)
        .map(|p| Piece {
            label: p.item.label.clone(),
            footprint: p.item.footprint.clone(),
            parts: p.item.parts.clone(),
        })
        .collect();
    let area = f64::from(polygon_area(&d.room).abs());
    let finish_s = ((SECONDS_PER_M2 * area / 60.0).ceil() * 60.0).max(MIN_FINISH_S);
    let (w, h) = grid::room_extent(&d.room);
    let f = &d.facts;
    let mut what = Vec::new();
    if f.rooms > 1 {
        what.push(format!("{} rooms", f.rooms));
    }
    for (n, one, many) in [
        (f.doors, "door", "doors"),
        (f.racks, "rack run", "rack runs"),
        (f.pillars, "pillar", "pillars"),
        (f.furniture, "piece of furniture", "pieces of furniture"),
        (f.pockets, "closed pocket", "closed pockets"),
    ] {
        match n {
            0 => {}
            1 => what.push(format!("1 {one}")),
            _ => what.push(format!("{n} {many}")),
        }
    }
    let description = format!(
        "Generated {} {w:.2} x {h:.2} m ({area:.1} m2): {}.",
        d.kind_name,
        if what.is_empty() { "empty".to_string() } else { what.join(", ") }
    );
    let mut scenario = Scenario {
        name: format!("gen-{}-{seed}", style.name()),
        description,
        robot: None,
        seed,
        cell: None,
        room: d.room.clone(),
        obstacles: pieces.iter().flat_map(|p| p.parts.iter().cloned()).collect(),
        start: Start { row: 0, col: 0, heading: Heading::East },
        physics: PhysicsSettings { max_sim_s: finish_s as f32, ..PhysicsSettings::default() },
        noise: Default::default(),
        links: Default::default(),
        faults: Vec::new(),
        mission: vec![Step::StartCartography, Step::WaitUntilMapped],
        expect: Expectations::from_criteria(&profile.scoring.pass, Some(finish_s)),
    };
    scenario.start = choose_start(&scenario, profile, rng)?;
    Some(GeneratedRoom { style, seed, sub_seed, pieces, scenario })
}

/// Every wall and obstacle of a scenario as parry shapes.
pub(super) fn scenario_shapes(s: &Scenario) -> Vec<Shaped> {
    let n = s.room.len();
    (0..n)
        .map(|i| Obstacle::Segment { from: s.room[i], to: s.room[(i + 1) % n] })
        .chain(s.obstacles.iter().cloned())
        .filter_map(|o| shaped(&o))
        .collect()
}

/// Whether the robot can turn on the spot at `(x, y)`: its turning disc touches nothing.
pub(super) fn can_turn(shapes: &[Shaped], profile: &RobotProfile, (x, y): Pt) -> bool {
    let g = &profile.geometry;
    let radius = 0.5 * g.body_length_m.hypot(g.body_width_m);
    let Some(disc) = shaped(&Obstacle::Circle { center: (x, y), radius }) else { return false };
    !shapes.iter().any(|s| near(s, &disc, 0.0))
}

/// Whether the body, facing the way it moves, can drive from `from` to `to` touching nothing.
pub(super) fn can_drive(shapes: &[Shaped], profile: &RobotProfile, from: Pt, to: Pt) -> bool {
    let g = &profile.geometry;
    let along = length(sub(to, from));
    let swept = Obstacle::Box {
        center: scale(add(from, to), 0.5),
        size: (along + g.body_length_m, g.body_width_m),
        angle_deg: dir_deg(sub(to, from)),
    };
    let Some(swept) = shaped(&swept) else { return false };
    !shapes.iter().any(|s| near(s, &swept, 0.0))
}

/// A start cell where the robot can turn on the spot and drive to a free neighbour, drawn from
/// the largest connected free area first.
pub(super) fn choose_start(s: &Scenario, profile: &RobotProfile, rng: &mut ChaCha8Rng) -> Option<Start> {
    let grid = s.truth(profile);
    let shapes = scenario_shapes(s);
    let (rows, cols) = (grid.rows, grid.cols);
    let mut label = vec![usize::MAX; rows * cols];
    let mut areas: Vec<Vec<(usize, usize)>> = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            if grid.is_free(r, c) && label[r * cols + c] == usize::MAX {
                let reach = grid.reachable_from((r, c));
                let cells: Vec<(usize, usize)> =
                    (0..rows * cols).filter(|&k| reach[k]).map(|k| (k / cols, k % cols)).collect();
                for &(rr, cc) in &cells {
                    label[rr * cols + cc] = areas.len();
                }
                areas.push(cells);
            }
        }
    }
    let mut order: Vec<usize> = (0..areas.len()).collect();
    order.sort_by(|&a, &b| areas[b].len().cmp(&areas[a].len()).then(a.cmp(&b)));
    for k in order {
        let mut cells = areas[k].clone();
        for i in (1..cells.len()).rev() {
            cells.swap(i, rng.random_range(0..=i));
        }
        for (r, c) in cells {
            let centre = grid.frame.cell_center(r, c);
            if !can_turn(&shapes, profile, centre) {
                continue;
            }
            let neighbours = [(r.wrapping_sub(1), c), (r + 1, c), (r, c.wrapping_sub(1)), (r, c + 1)];
            let moves = neighbours.iter().any(|&(nr, nc)| {
                grid.is_free(nr, nc) && can_drive(&shapes, profile, centre, grid.frame.cell_center(nr, nc))
            });
            if !moves {
                continue;
            }
            let heading = pick(rng, &[Heading::North, Heading::East, Heading::South, Heading::West])?;
            return Some(Start { row: u8::try_from(r).ok()?, col: u8::try_from(c).ok()?, heading });
        }
    }
    None
}

// ---------------------------------------------------------------------------------------------
// RON text.

pub(super) fn fmt_pt((x, y): Pt) -> String {
    format!("({x:.3}, {y:.3})")
}

pub(super) fn fmt_opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map_or("None".to_string(), |v| format!("Some({v})"))
}

pub(super) fn fmt_obstacle(o: &Obstacle) -> String {
    match o {
        Obstacle::Box { center, size, angle_deg } if *angle_deg == 0.0 => {
            format!("Box(center: {}, size: {})", fmt_pt(*center), fmt_pt(*size))
        }
        Obstacle::Box { center, size, angle_deg } => {
            format!("Box(center: {}, size: {}, angle_deg: {angle_deg:.1})", fmt_pt(*center), fmt_pt(*size))
        }
        Obstacle::Circle { center, radius } => {
            format!("Circle(center: {}, radius: {radius:.3})", fmt_pt(*center))
        }
        Obstacle::Segment { from, to } => format!("Segment(from: {}, to: {})", fmt_pt(*from), fmt_pt(*to)),
        Obstacle::Polygon { points } => {
            let pts: Vec<String> = points.iter().map(|p| fmt_pt(*p)).collect();
            format!("Polygon(points: [{}])", pts.join(", "))
        }
    }
}
