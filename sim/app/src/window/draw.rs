//! Drawing the true world: the floor texture (rasterised once by [`twin::raster`]), sprites for
//! the robot's body and wheels, and gizmos for the grid, walls, obstacles, trail, sonar rays,
//! heading and bumper, redrawn every frame from the runner's state.
//!
//! Invariant: every position goes through [`WorldLayout`], so the sprites, the gizmos and the
//! floor agree whatever the window's size.

use bevy::asset::{Assets, RenderAssetUsages};
use bevy::color::Color;
use bevy::ecs::system::{Commands, Query, Res, ResMut, Single};
use bevy::gizmos::gizmos::Gizmos;
use bevy::image::{Image, ImageSampler};
use bevy::math::{Quat, Vec2};
use bevy::prelude::{Component, Transform, Visibility, With, Without};
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat};
use bevy::sprite::Sprite;
use bevy::window::{PrimaryWindow, Window};
use cute::gui::logical_to_world;

use super::layout::{WorldLayout, room_box};
use crate::plugin::Sim;
use twin::raster::{Palette, PixelGrid, RoomShapes};
use twin::scenario::{Obstacle, Scenario};

/// Trail points drawn at most.
const TRAIL_POINTS: usize = 2000;
/// Texels per metre of the floor texture, at most.
const FLOOR_TEXELS_PER_M: f32 = 200.0;
/// Largest floor texture side.
const FLOOR_MAX_SIDE: f32 = 1400.0;

/// Robot body colour (the same blue as Cute's robot cell).
pub const ROBOT_RGB: [u8; 3] = [40, 90, 230];
/// Floor colour.
pub const FLOOR_RGB: [u8; 3] = [236, 232, 220];
/// Obstacle colour.
pub const OBSTACLE_RGB: [u8; 3] = [120, 86, 60];
/// Outside the room.
pub const OUTSIDE_RGB: [u8; 3] = [70, 72, 78];
/// The floor texture's colours.
pub const PALETTE: Palette = Palette { outside: OUTSIDE_RGB, obstacle: OBSTACLE_RGB, floor: FLOOR_RGB };

fn rgb(c: [u8; 3]) -> Color {
    Color::srgb_u8(c[0], c[1], c[2])
}

#[derive(Component)]
pub(super) struct Floor;

#[derive(Component)]
pub(super) struct RobotBodySprite;

#[derive(Component)]
pub(super) struct WheelSprite(usize);

/// A floor texture of the room (outside, floor, obstacles) and the world box it covers.
fn floor_image(scenario: &Scenario) -> (Image, Vec2, Vec2) {
    let (min, max) = room_box(&scenario.room);
    let size = max - min;
    let texels = FLOOR_TEXELS_PER_M.min(FLOOR_MAX_SIDE / size.x.max(size.y).max(1e-3));
    let w = ((size.x * texels).ceil() as u32).max(1);
    let h = ((size.y * texels).ceil() as u32).max(1);
    let grid = PixelGrid { min_x: min.x, max_y: max.y, scale: texels, border: 0.0, width: w, height: h };
    let data: Vec<u8> = RoomShapes::new(scenario)
        .paint(&grid, &PALETTE, |_, _, c| c)
        .into_iter()
        .flat_map(|c| [c[0], c[1], c[2], 255])
        .collect();
    let mut image = Image::new(
        Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        TextureDimension::D2,
        data,
        TextureFormat::Rgba8UnormSrgb,
        RenderAssetUsages::RENDER_WORLD,
    );
    image.sampler = ImageSampler::linear();
    (image, min, max)
}

pub(super) fn spawn_world(mut commands: Commands, sim: Res<Sim>, mut images: ResMut<Assets<Image>>) {
    let (image, _, _) = floor_image(&sim.0.loaded().scenario);
    let handle = images.add(image);
    commands.spawn((
        Floor,
        Sprite { image: handle, custom_size: Some(Vec2::ONE), ..Sprite::default() },
        Transform::default(),
        Visibility::Hidden,
    ));
    commands.spawn((
        RobotBodySprite,
        Sprite::from_color(rgb(ROBOT_RGB), Vec2::ONE),
        Transform::default(),
        Visibility::Hidden,
    ));
    for i in 0..4 {
        commands.spawn((
            WheelSprite(i),
            Sprite::from_color(Color::srgb(0.1, 0.1, 0.1), Vec2::ONE),
            Transform::default(),
            Visibility::Hidden,
        ));
    }
}

/// Body-frame offsets of the wheels: FL, FR, RL, RR (x forward, y left).
fn wheel_offsets(wheelbase: f32, track: f32) -> [Vec2; 4] {
    let (a, b) = (wheelbase * 0.5, track * 0.5);
    [Vec2::new(a, b), Vec2::new(a, -b), Vec2::new(-a, b), Vec2::new(-a, -b)]
}

#[allow(clippy::type_complexity)]
pub(super) fn place_world(
    sim: Res<Sim>,
    window: Single<&Window, With<PrimaryWindow>>,
    mut floor: Single<(&mut Sprite, &mut Transform, &mut Visibility), With<Floor>>,
    mut body: Single<(&mut Sprite, &mut Transform, &mut Visibility), (With<RobotBodySprite>, Without<Floor>)>,
    mut wheels: Query<
        (&WheelSprite, &mut Sprite, &mut Transform, &mut Visibility),
        (Without<RobotBodySprite>, Without<Floor>),
    >,
) {
    let run = &sim.0;
    let size = window.size();
    let scenario = &run.loaded().scenario;
    let layout = WorldLayout::compute(size, &scenario.room);
    let (min, max) = room_box(&scenario.room);
    let to_world = |x: f32, y: f32| logical_to_world(size, layout.to_logical(x, y));
    let c = to_world((min.x + max.x) * 0.5, (min.y + max.y) * 0.5);
    floor.0.custom_size = Some((max - min) * layout.scale);
    *floor.1 = Transform::from_translation(c.extend(0.0));
    *floor.2 = Visibility::Inherited;

    let pose = run.body().pose();
    let g = &run.loaded().profile.geometry;
    let rot = Quat::from_rotation_z(pose.theta);
    let p = to_world(pose.x, pose.y);
    body.0.custom_size = Some(Vec2::new(g.body_length_m, g.body_width_m) * layout.scale);
    *body.1 = Transform::from_translation(p.extend(2.0)).with_rotation(rot);
    *body.2 = Visibility::Inherited;
    let offsets = wheel_offsets(g.wheelbase_m, g.track_m);
    let rpm = run.body().wheel_rpm();
    let max_rpm = run.loaded().profile.motor.max_wheel_rpm.max(1.0);
    let (s, co) = pose.theta.sin_cos();
    for (wheel, mut sprite, mut transform, mut vis) in &mut wheels {
        let Some(o) = offsets.get(wheel.0) else {
            continue;
        };
        let wx = pose.x + co * o.x - s * o.y;
        let wy = pose.y + s * o.x + co * o.y;
        let q = to_world(wx, wy);
        sprite.custom_size = Some(Vec2::new(2.0 * g.wheel_radius_m, 0.035) * layout.scale);
        // Forward green, backward red, idle near black.
        let k = (rpm.get(wheel.0).copied().unwrap_or(0.0) / max_rpm).clamp(-1.0, 1.0);
        sprite.color = if k >= 0.0 {
            Color::srgb(0.08, 0.08 + 0.7 * k, 0.08)
        } else {
            Color::srgb(0.08 - 0.7 * k, 0.08, 0.08)
        };
        *transform = Transform::from_translation(q.extend(3.0)).with_rotation(rot);
        *vis = Visibility::Inherited;
    }
}

/// Walls are drawn this many pixels thick.
const WALL_PX: u32 = 4;

/// A line `px` pixels thick: parallel one-pixel gizmo lines, centred on a→b.
fn thick_line(gizmos: &mut Gizmos, a: Vec2, b: Vec2, px: u32, color: Color) {
    let normal = (b - a).normalize_or_zero().perp();
    for k in 0..px {
        let offset = normal * (k as f32 - (px as f32 - 1.0) * 0.5);
        gizmos.line_2d(a + offset, b + offset, color);
    }
}

pub(super) fn draw_world(sim: Res<Sim>, window: Single<&Window, With<PrimaryWindow>>, mut gizmos: Gizmos) {
    let run = &sim.0;
    let size = window.size();
    let scenario = &run.loaded().scenario;
    let layout = WorldLayout::compute(size, &scenario.room);
    let w = |x: f32, y: f32| logical_to_world(size, layout.to_logical(x, y));

    // The planning grid, faint.
    let f = run.frame();
    let grid = Color::srgba(0.35, 0.45, 0.65, 0.35);
    for row in 0..=f.rows {
        let y = f.top - row as f32 * f.cell;
        gizmos.line_2d(w(f.left, y), w(f.left + f.cols as f32 * f.cell, y), grid);
    }
    for col in 0..=f.cols {
        let x = f.left + col as f32 * f.cell;
        gizmos.line_2d(w(x, f.top), w(x, f.top - f.rows as f32 * f.cell), grid);
    }

    // Walls, thick and in a colour that shows on the floor and on the dark background alike (a
    // wall on the panel's edge must not look like the edge), and obstacle outlines.
    let wall = Color::srgb(0.42, 0.45, 0.55);
    let room = &scenario.room;
    for (i, &(x0, y0)) in room.iter().enumerate() {
        let Some(&(x1, y1)) = room.get(i + 1).or(room.first()).filter(|_| room.len() >= 2) else {
            continue;
        };
        thick_line(&mut gizmos, w(x0, y0), w(x1, y1), WALL_PX, wall);
    }
    let edge = Color::srgb(0.3, 0.2, 0.12);
    for o in &scenario.obstacles {
        match o {
            Obstacle::Box { center, size, angle_deg } => {
                let (s, c) = angle_deg.to_radians().sin_cos();
                let (hx, hy) = (size.0 * 0.5, size.1 * 0.5);
                let corner = |a: f32, b: f32| w(center.0 + c * a - s * b, center.1 + s * a + c * b);
                let pts =
                    [corner(hx, hy), corner(-hx, hy), corner(-hx, -hy), corner(hx, -hy), corner(hx, hy)];
                gizmos.linestrip_2d(pts, edge);
            }
            Obstacle::Circle { center, radius } => {
                gizmos.circle_2d(w(center.0, center.1), radius * layout.scale, edge);
            }
            Obstacle::Segment { from, to } => {
                thick_line(&mut gizmos, w(from.0, from.1), w(to.0, to.1), WALL_PX, wall);
            }
            Obstacle::Polygon { points } => {
                gizmos.linestrip_2d(points.iter().chain(points.first()).map(|&(x, y)| w(x, y)), edge);
            }
        }
    }

    // Trail.
    let trail = run.trail();
    let stride = trail.len().div_ceil(TRAIL_POINTS).max(1);
    let pose = run.body().pose();
    gizmos.linestrip_2d(
        trail.iter().step_by(stride).chain(std::iter::once(&(pose.x, pose.y))).map(|&(x, y)| w(x, y)),
        Color::srgb(0.75, 0.3, 0.75),
    );

    // Sonar: the rays of the last measurement, each ending where it hit. A heard ray is drawn
    // to its echo point with a dot there; a ray lost to incidence faintly, with a cross at the
    // surface it glanced off; a ray that hit nothing within range, dotted to its range.
    for r in run.body().last_rays() {
        let (from, to) = (w(r.from.0, r.from.1), w(r.to.0, r.to.1));
        if r.echo {
            let heard = Color::srgb(0.0, 0.75, 0.55);
            gizmos.line_2d(from, to, heard);
            gizmos.circle_2d(to, 3.0, heard);
        } else if r.hit {
            let lost = Color::srgba(0.9, 0.3, 0.3, 0.7);
            gizmos.line_2d(from, to, Color::srgba(0.9, 0.3, 0.3, 0.35));
            gizmos.line_2d(to + Vec2::new(-4.0, -4.0), to + Vec2::new(4.0, 4.0), lost);
            gizmos.line_2d(to + Vec2::new(-4.0, 4.0), to + Vec2::new(4.0, -4.0), lost);
        } else {
            let miss = Color::srgba(0.6, 0.6, 0.6, 0.5);
            let n = 12;
            for i in (0..n).step_by(2) {
                let a = from.lerp(to, i as f32 / n as f32);
                let b = from.lerp(to, (i + 1) as f32 / n as f32);
                gizmos.line_2d(a, b, miss);
            }
        }
    }

    // Heading arrow and bumper.
    let g = &run.loaded().profile.geometry;
    let (s, c) = pose.theta.sin_cos();
    let half = g.body_length_m * 0.5;
    gizmos
        .arrow_2d(w(pose.x, pose.y), w(pose.x + c * half * 0.9, pose.y + s * half * 0.9), Color::WHITE)
        .with_tip_length(0.05 * layout.scale);
    let hw = g.body_width_m * 0.5;
    let front = |b: f32| w(pose.x + c * half - s * b, pose.y + s * half + c * b);
    let bumper = if run.body().bumper() { Color::srgb(1.0, 0.15, 0.1) } else { Color::srgb(0.9, 0.9, 0.95) };
    gizmos.line_2d(front(hw), front(-hw), bumper);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_texture_marks_obstacles_and_outside() {
        let loaded = twin::setup::RunSetup::builtin_default().unwrap();
        let (image, min, max) = floor_image(&loaded.scenario);
        let w = image.texture_descriptor.size.width as f32;
        let h = image.texture_descriptor.size.height as f32;
        let texel = |x: f32, y: f32| {
            let px = ((x - min.x) / (max.x - min.x) * w) as usize;
            let py = ((max.y - y) / (max.y - min.y) * h) as usize;
            let i = (py * w as usize + px) * 4;
            let d = image.data.as_ref().unwrap();
            [d[i], d[i + 1], d[i + 2]]
        };
        // The sofa's centre and an empty spot of the default room.
        assert_eq!(texel(1.55, 0.35), OBSTACLE_RGB);
        assert_eq!(texel(0.3, 2.2), FLOOR_RGB);
    }
}
