//! The twin and Cute's picture of it as Foxglove's well-known messages: poses and transforms,
//! the room as a `SceneUpdate`, Cute's map as a `Grid`, the planned path, the sonar rays, and
//! Carto's own evidence grid (a `Grid`) and belief ellipse (a `SceneUpdate`).
//!
//! Frames: `world` is the scenario's metres (x right, y up, z up); `robot` is the true body,
//! `carto` the pose Carto believes. Every function here is pure: same input, same message.
//!
//! ```
//! use twin_viz::scene::{grid_bytes, map_grid};
//! let frame = robot_model::grid::GridFrame { left: 0.0, top: 0.6, cell: 0.3, rows: 2, cols: 3 };
//! let map = cute::Map::new(2, 3)?;
//! let grid = map_grid(&map, &frame, 0);
//! assert_eq!((grid.column_count, grid.data.len()), (3, 2 * 3 * grid_bytes::CELL));
//! # Ok::<(), cute::MapError>(())
//! ```

use foxglove::bytes::Bytes;
use foxglove::messages::{
    Color, CubePrimitive, CylinderPrimitive, FrameTransform, Grid, LinePrimitive, PackedElementField, Point3,
    Pose, PoseInFrame, PosesInFrame, Quaternion, SceneEntity, SceneUpdate, Timestamp, Vector2, Vector3,
    line_primitive, packed_element_field,
};
use robot_model::grid::GridFrame;

use twin::body::CastRay;
use twin::carto_map::{BeliefEllipse, CartoMap, Occupancy};
use twin::scenario::{Obstacle, Scenario};

/// The fixed frame: the scenario's metres.
pub const WORLD: &str = "world";
/// The true robot body.
pub const ROBOT: &str = "robot";
/// The pose Carto believes.
pub const CARTO: &str = "carto";
/// Drawn height of walls and obstacles, metres (the room is flat; this is for the 3D view).
const HEIGHT: f64 = 0.25;

/// A message timestamp from nanoseconds of sim time.
pub fn timestamp(ns: u64) -> Timestamp {
    Timestamp::new((ns / 1_000_000_000) as u32, (ns % 1_000_000_000) as u32)
}

fn vec3(x: f64, y: f64, z: f64) -> Option<Vector3> {
    Some(Vector3 { x, y, z })
}

fn point(x: f32, y: f32, z: f64) -> Point3 {
    Point3 { x: f64::from(x), y: f64::from(y), z }
}

fn color(r: f64, g: f64, b: f64, a: f64) -> Option<Color> {
    Some(Color { r, g, b, a })
}

/// A planar pose: position (x, y) and a turn of `theta` radians about z.
pub fn planar(x: f32, y: f32, theta: f32) -> Pose {
    let half = f64::from(theta) * 0.5;
    Pose {
        position: vec3(f64::from(x), f64::from(y), 0.0),
        orientation: Some(Quaternion { x: 0.0, y: 0.0, z: half.sin(), w: half.cos() }),
    }
}

/// `child` placed at (x, y, theta) in `world`.
pub fn transform(child: &str, (x, y, theta): (f32, f32, f32), ns: u64) -> FrameTransform {
    let pose = planar(x, y, theta);
    FrameTransform {
        timestamp: Some(timestamp(ns)),
        parent_frame_id: WORLD.to_string(),
        child_frame_id: child.to_string(),
        translation: pose.position,
        rotation: pose.orientation,
    }
}

/// A pose in `world`.
pub fn pose_in_world((x, y, theta): (f32, f32, f32), ns: u64) -> PoseInFrame {
    PoseInFrame {
        timestamp: Some(timestamp(ns)),
        frame_id: WORLD.to_string(),
        pose: Some(planar(x, y, theta)),
    }
}

fn entity(id: &str, frame_id: &str, ns: u64) -> SceneEntity {
    SceneEntity {
        timestamp: Some(timestamp(ns)),
        frame_id: frame_id.to_string(),
        id: id.to_string(),
        ..SceneEntity::default()
    }
}

fn line(kind: line_primitive::Type, points: Vec<Point3>, thickness: f64, c: Option<Color>) -> LinePrimitive {
    LinePrimitive {
        r#type: kind as i32,
        pose: Some(planar(0.0, 0.0, 0.0)),
        thickness,
        scale_invariant: false,
        points,
        color: c,
        ..LinePrimitive::default()
    }
}

/// The room: its walls as a closed line, each obstacle as a box, a cylinder or lines, and the
/// robot's footprint following the `robot` frame (`body` = length, width) and, dashed in
/// orange, the `carto` frame.
pub fn room_scene(scenario: &Scenario, body: (f32, f32), ns: u64) -> SceneUpdate {
    let wall = color(0.2, 0.25, 0.3, 1.0);
    let mut room = entity("room", WORLD, ns);
    let walls = scenario.room.iter().map(|&(x, y)| point(x, y, 0.0)).collect();
    room.lines.push(line(line_primitive::Type::LineLoop, walls, 0.03, wall));
    let obstacle = color(0.45, 0.3, 0.2, 1.0);
    for o in &scenario.obstacles {
        match o {
            Obstacle::Box { center, size, angle_deg } => room.cubes.push(CubePrimitive {
                pose: Some(Pose {
                    position: vec3(f64::from(center.0), f64::from(center.1), HEIGHT * 0.5),
                    orientation: planar(0.0, 0.0, angle_deg.to_radians()).orientation,
                }),
                size: vec3(f64::from(size.0), f64::from(size.1), HEIGHT),
                color: obstacle,
            }),
            Obstacle::Circle { center, radius } => room.cylinders.push(CylinderPrimitive {
                pose: Some(Pose {
                    position: vec3(f64::from(center.0), f64::from(center.1), HEIGHT * 0.5),
                    orientation: planar(0.0, 0.0, 0.0).orientation,
                }),
                size: vec3(f64::from(2.0 * radius), f64::from(2.0 * radius), HEIGHT),
                bottom_scale: 1.0,
                top_scale: 1.0,
                color: obstacle,
            }),
            Obstacle::Segment { from, to } => room.lines.push(line(
                line_primitive::Type::LineList,
                vec![point(from.0, from.1, 0.0), point(to.0, to.1, 0.0)],
                0.03,
                obstacle,
            )),
            Obstacle::Polygon { points } => room.lines.push(line(
                line_primitive::Type::LineLoop,
                points.iter().map(|&(x, y)| point(x, y, 0.0)).collect(),
                0.03,
                obstacle,
            )),
        }
    }
    let (length, width) = body;
    let mut robot = entity("robot-body", ROBOT, ns);
    robot.frame_locked = true;
    robot.cubes.push(CubePrimitive {
        pose: Some(planar(0.0, 0.0, 0.0)),
        size: vec3(f64::from(length), f64::from(width), 0.05),
        color: color(0.15, 0.45, 0.85, 0.8),
    });
    let mut believed = entity("carto-body", CARTO, ns);
    believed.frame_locked = true;
    let (hl, hw) = (length * 0.5, width * 0.5);
    let outline =
        vec![point(hl, hw, 0.06), point(-hl, hw, 0.06), point(-hl, -hw, 0.06), point(hl, -hw, 0.06)];
    believed.lines.push(line(line_primitive::Type::LineLoop, outline, 0.01, color(1.0, 0.55, 0.0, 1.0)));
    SceneUpdate { deletions: Vec::new(), entities: vec![room, robot, believed] }
}

/// Layout of a [`map_grid`] cell: red, green, blue, alpha, then Cute's number for the cell.
pub mod grid_bytes {
    /// Bytes per cell.
    pub const CELL: usize = 5;
    /// Offset of Cute's cell number (0 obstacle, 1 free, 2 unknown, 3 waypoint, 4 destination,
    /// 5 robot).
    pub const VALUE: usize = 4;
}

/// The colour a cell of Cute's map is drawn in (RGBA).
fn cell_rgba(value: cute::CellValue) -> [u8; 4] {
    use cute::CellValue::*;
    match value {
        Obstacle => [40, 40, 40, 255],
        Free => [240, 240, 240, 255],
        Unknown => [150, 150, 150, 90],
        Waypoint => [150, 200, 255, 255],
        Destination => [40, 110, 230, 255],
        Robot => [60, 180, 90, 255],
    }
}

/// Cute's map as a `Grid` in `world`, laid on the scenario's grid frame (row 0 at the top).
pub fn map_grid(map: &cute::Map, frame: &GridFrame, ns: u64) -> Grid {
    let (rows, cols) = (map.rows(), map.cols());
    let mut data = Vec::with_capacity(rows * cols * grid_bytes::CELL);
    // A Grid's rows grow along +y from its origin: our bottom row comes first.
    for row in (0..rows).rev() {
        for value in map.row(row).unwrap_or(&[]) {
            data.extend_from_slice(&cell_rgba(*value));
            data.push(value.as_u8());
        }
    }
    let bottom = frame.top - rows as f32 * frame.cell;
    rgba_grid((f64::from(frame.left), f64::from(bottom), -0.01), cols, f64::from(frame.cell), data, ns)
}

/// A `Grid` in `world` of `cols` columns of square `cell`s (metres) whose lower-left corner is
/// `origin`, from `data`: [`grid_bytes::CELL`] bytes per cell, RGBA then a `value`, bottom row
/// first.
fn rgba_grid(origin: (f64, f64, f64), cols: usize, cell: f64, data: Vec<u8>, ns: u64) -> Grid {
    let field = |name: &str, offset: usize| PackedElementField {
        name: name.to_string(),
        offset: offset as u32,
        r#type: packed_element_field::NumericType::Uint8 as i32,
    };
    Grid {
        timestamp: Some(timestamp(ns)),
        frame_id: WORLD.to_string(),
        pose: Some(Pose { position: vec3(origin.0, origin.1, origin.2), ..planar(0.0, 0.0, 0.0) }),
        column_count: cols as u32,
        cell_size: Some(Vector2 { x: cell, y: cell }),
        row_stride: (cols * grid_bytes::CELL) as u32,
        cell_stride: grid_bytes::CELL as u32,
        fields: vec![
            field("red", 0),
            field("green", 1),
            field("blue", 2),
            field("alpha", 3),
            field("value", grid_bytes::VALUE),
        ],
        data: Bytes::from(data),
    }
}

/// The path Cute plans, start cell first: the trajectory painted on its map (waypoints and
/// destination, followed from the robot's cell), or while mapping the cell the sweep heads for.
/// Empty when Cute plans nothing.
pub fn planned_path(cute: &cute::Cute) -> Vec<(u8, u8)> {
    let map = cute.map();
    let (x, y, _) = cute.robot();
    let painted =
        |c: (u8, u8)| matches!(map.at(c), Some(cute::CellValue::Waypoint | cute::CellValue::Destination));
    let mut path = vec![(x, y)];
    let mut at = (x, y);
    let limit = map.rows() * map.cols();
    while path.len() <= limit {
        let (r, c) = (i32::from(at.0), i32::from(at.1));
        let next = [(r + 1, c), (r - 1, c), (r, c + 1), (r, c - 1)]
            .into_iter()
            .filter_map(|(r, c)| Some((u8::try_from(r).ok()?, u8::try_from(c).ok()?)))
            .find(|&n| painted(n) && !path.contains(&n));
        match next {
            Some(n) => {
                path.push(n);
                at = n;
            }
            None => break,
        }
    }
    if path.len() > 1 {
        return path;
    }
    match cute.cartographer().and_then(|c| c.target()) {
        Some(target) if target != (x, y) => vec![(x, y), target],
        _ => Vec::new(),
    }
}

/// Cells as poses at their centres in `world`.
pub fn path_poses(path: &[(u8, u8)], frame: &GridFrame, ns: u64) -> PosesInFrame {
    let poses = path
        .iter()
        .map(|&(row, col)| {
            let (x, y) = frame.cell_center(usize::from(row), usize::from(col));
            planar(x, y, 0.0)
        })
        .collect();
    PosesInFrame { timestamp: Some(timestamp(ns)), frame_id: WORLD.to_string(), poses }
}

/// The ray whose echo the sensor keeps: the nearest surviving echo.
pub fn kept_ray(rays: &[CastRay]) -> Option<usize> {
    let length = |r: &CastRay| (r.to.0 - r.from.0).hypot(r.to.1 - r.from.1);
    rays.iter()
        .enumerate()
        .filter(|(_, r)| r.echo)
        .min_by(|a, b| length(a.1).total_cmp(&length(b.1)))
        .map(|(i, _)| i)
}

/// The last sonar measurement's rays in `world`: the echo kept green, other echoes yellow, hits
/// lost to specular reflection red, misses grey (one line list per colour, so a measurement
/// stays a few hundred bytes).
pub fn sonar_scene(rays: &[CastRay], ns: u64) -> SceneUpdate {
    let kept = kept_ray(rays);
    let class = |i: usize, r: &CastRay| match (kept == Some(i), r.echo, r.hit) {
        (true, _, _) => 0,
        (false, true, _) => 1,
        (false, false, true) => 2,
        (false, false, false) => 3,
    };
    let colors = [(0.1, 0.8, 0.2, 1.0), (0.95, 0.8, 0.1, 1.0), (0.9, 0.2, 0.2, 1.0), (0.6, 0.6, 0.6, 0.6)];
    let mut sonar = entity("sonar", WORLD, ns);
    for (c, &(r, g, b, a)) in colors.iter().enumerate() {
        let points: Vec<Point3> = rays
            .iter()
            .enumerate()
            .filter(|&(i, ray)| class(i, ray) == c)
            .flat_map(|(_, ray)| [point(ray.from.0, ray.from.1, 0.1), point(ray.to.0, ray.to.1, 0.1)])
            .collect();
        if !points.is_empty() {
            let mut l = line(line_primitive::Type::LineList, points, 0.01, color(r, g, b, a));
            l.pose = None;
            sonar.lines.push(l);
        }
    }
    SceneUpdate { deletions: Vec::new(), entities: vec![sonar] }
}

/// Carto's evidence grid as a `Grid` in `world`, over the box of the cells that hold evidence
/// (`None` while none does). Colours as in `map.png` (free cyan, occupied teal, undecided and
/// empty cells transparent); the field `value` is 0 for no evidence, 1 free, 2 undecided,
/// 3 occupied.
pub fn carto_grid(map: &CartoMap, ns: u64) -> Option<Grid> {
    let cell = f64::from(map.cell_m.max(1e-3));
    let (mut lo, mut hi) = ((f64::INFINITY, f64::INFINITY), (f64::NEG_INFINITY, f64::NEG_INFINITY));
    for &((x, y), _) in &map.cells {
        let (x, y) = (f64::from(x), f64::from(y));
        lo = (lo.0.min(x), lo.1.min(y));
        hi = (hi.0.max(x), hi.1.max(y));
    }
    if map.cells.is_empty() {
        return None;
    }
    let index = |v: f64, from: f64| ((v - from) / cell).round().max(0.0) as usize;
    let (cols, rows) = (index(hi.0, lo.0) + 1, index(hi.1, lo.1) + 1);
    let mut data = vec![0u8; rows * cols * grid_bytes::CELL];
    for &((x, y), occupancy) in &map.cells {
        let (rgba, value) = match occupancy {
            Occupancy::Free => ([0, 170, 210, 90], 1),
            Occupancy::Unknown => ([0, 0, 0, 0], 2),
            Occupancy::Occupied => ([0, 120, 130, 235], 3),
        };
        // a Grid's rows grow along +y from its origin
        let i = (index(f64::from(y), lo.1) * cols + index(f64::from(x), lo.0)) * grid_bytes::CELL;
        if let Some(texel) = data.get_mut(i..i + grid_bytes::CELL) {
            texel[..4].copy_from_slice(&rgba);
            texel[grid_bytes::VALUE] = value;
        }
    }
    Some(rgba_grid((lo.0 - cell / 2.0, lo.1 - cell / 2.0, -0.005), cols, cell, data, ns))
}

/// Carto's belief in `world`: the 2σ ellipse of its position and a line along its heading, in
/// the orange of its believed pose.
pub fn belief_scene(belief: &BeliefEllipse, length_m: f32, ns: u64) -> SceneUpdate {
    let orange = color(0.96, 0.55, 0.0, 1.0);
    let mut outline: Vec<Point3> = belief.outline(48).into_iter().map(|(x, y)| point(x, y, 0.12)).collect();
    if let Some(first) = outline.first().cloned() {
        outline.push(first);
    }
    let (x, y, heading) = belief.pose;
    let tip = (x + length_m * heading.cos(), y + length_m * heading.sin());
    let mut scene = entity("belief", WORLD, ns);
    for (kind, points) in [
        (line_primitive::Type::LineStrip, outline),
        (line_primitive::Type::LineList, vec![point(x, y, 0.12), point(tip.0, tip.1, 0.12)]),
    ] {
        let mut l = line(kind, points, 0.006, orange);
        l.pose = None;
        scene.lines.push(l);
    }
    SceneUpdate { deletions: Vec::new(), entities: vec![scene] }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn a_quarter_turn_is_a_quaternion_about_z() {
        let q = planar(1.0, 2.0, std::f32::consts::FRAC_PI_2).orientation.unwrap();
        assert!((q.z - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-6 && (q.w - q.z).abs() < 1e-6);
        assert_eq!(timestamp(3_000_000_123), Timestamp::new(3, 123));
    }

    #[test]
    fn the_grid_puts_the_top_row_last_and_keeps_cute_numbers() {
        let frame = GridFrame { left: 1.0, top: 2.0, cell: 0.5, rows: 2, cols: 2 };
        let mut map = cute::Map::new(2, 2).unwrap();
        map.set_obstacle(0, 1).unwrap();
        let grid = map_grid(&map, &frame, 0);
        let value = |i: usize| grid.data[i * grid_bytes::CELL + grid_bytes::VALUE];
        // Data order: (1,0) (1,1) (0,0) (0,1).
        assert_eq!([value(0), value(1), value(2), value(3)], [2, 2, 2, 0]);
        let origin = grid.pose.unwrap().position.unwrap();
        assert_eq!((origin.x, origin.y), (1.0, 1.0));
    }

    #[test]
    fn the_kept_ray_is_the_nearest_echo() {
        let ray = |to: f32, hit, echo| CastRay { from: (0.0, 0.0), to: (to, 0.0), hit, echo };
        let rays =
            [ray(2.0, true, true), ray(0.5, true, false), ray(1.0, true, true), ray(4.0, false, false)];
        assert_eq!(kept_ray(&rays), Some(2));
        assert_eq!(kept_ray(&rays[1..2]), None);
    }

    #[test]
    fn carto_grid_puts_each_cell_at_its_place_and_marks_what_it_is() {
        let map = CartoMap {
            cell_m: 0.02,
            cells: vec![((1.0, 2.0), Occupancy::Free), ((1.04, 2.02), Occupancy::Occupied)],
        };
        let grid = carto_grid(&map, 0).unwrap();
        assert_eq!(grid.column_count, 3);
        assert_eq!(grid.data.len(), 2 * 3 * grid_bytes::CELL, "3 columns by 2 rows");
        let value =
            |row: usize, col: usize| grid.data[(row * 3 + col) * grid_bytes::CELL + grid_bytes::VALUE];
        assert_eq!((value(0, 0), value(1, 2), value(0, 1)), (1, 3, 0));
        let origin = grid.pose.unwrap().position.unwrap();
        assert!((origin.x - 0.99).abs() < 1e-6 && (origin.y - 1.99).abs() < 1e-6, "{origin:?}");
        assert!(carto_grid(&CartoMap::default(), 0).is_none());
    }
}
