//! The twin's window (feature `window`): the true world beside Cute's map, with time controls.
//!
//! Concept: [`SimRenderPlugin`] draws what the physics knows — the room, the obstacles, the
//! robot's body and its four wheels (tinted by their speed), the sonar rays of the last
//! measurement (bright when they echo), the trail, the planning grid — in the left half of the
//! window, and adds [`cute::gui::CutePlugin`] on [`Sim`] in the right half, so the operator sees
//! Cute's belief next to the truth and can drive Cute with its own buttons and clicks.
//!
//! Pacing: in window mode `Time<Fixed>` is not used. [`pace_lockstep`] runs in `Update` (in
//! [`SimSystems::Step`]) and steps the lockstep runner as many times as the wall time since the
//! last frame × the [`Speed`] asks for, but never longer than [`FRAME_BUDGET`] per frame (a
//! slower machine runs slower, it does not pile up a backlog); `Max` fills the budget. The
//! runner itself is the same deterministic lockstep as headless: pacing only decides how many
//! steps run per frame, so a window run reaches the same states at the same sim times.
//!
//! Invariants: one `Camera2d` at the origin, one world unit = one logical pixel (see
//! [`cute::gui`]); [`WorldLayout`] is the only place that maps metres to pixels; a screenshot
//! request ([`request_screenshot`]) stops the runner exactly at its time, so the picture shows the
//! state a headless run has after the same number of steps.
//!
//! ```no_run
//! use sim::app::{Mode, make_app};
//! let run = sim::runner::Lockstep::new(sim::scenario::LoadedScenario::builtin_default()?, None)?;
//! let mut app = make_app(Mode::Window, run);
//! sim::window::request_screenshot(&mut app, "window.png".into(), 20.0);
//! app.run();
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::PathBuf;
use std::time::Duration as WallDuration;

use bevy::app::{App, Plugin, Startup, Update};
use bevy::asset::{Assets, RenderAssetUsages};
use bevy::color::Color;
use bevy::ecs::schedule::IntoScheduleConfigs;
use bevy::ecs::system::{Commands, Query, Res, ResMut, Single};
use bevy::gizmos::gizmos::Gizmos;
use bevy::image::{Image, ImageSampler};
use bevy::math::{Quat, Rect, Vec2};
use bevy::prelude::{ClearColor, Component, Resource, Transform, Visibility, With, Without};
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat};
use bevy::sprite::Sprite;
use bevy::time::{Real, Time};
use bevy::window::{PrimaryWindow, Window};
use cute::Cute;
use cute::gui::bevy_egui::{EguiContexts, EguiPlugin, EguiPrimaryContextPass, egui};
use cute::gui::{
    AutoScreenshot, BACKGROUND, CuteAccess, CutePlugin, CuteView, TOOLBAR_HEIGHT, continuous_updates,
    logical_to_world, setup_camera, window_plugins,
};
use rapier2d::parry::math::Vector;
use rapier2d::parry::query::PointQuery;
use rapier2d::parry::shape::Shape;
use robot_model::time::Instant;

use crate::app::{Sim, SimSystems};
use crate::grid::{obstacle_shape, point_in_poly2d, room_points};
use crate::report::Report;
use crate::runner::Lockstep;
use crate::scenario::{Obstacle, Scenario};

/// Window size, logical pixels.
pub const WINDOW_SIZE: (u32, u32) = (1280, 720);
/// Height of the status bar at the bottom, logical pixels.
pub const STATUS_HEIGHT: f32 = 46.0;
/// Longest time the runner may take per frame.
pub const FRAME_BUDGET: WallDuration = WallDuration::from_millis(12);
/// Most sim time a paced speed may owe after a slow frame, seconds.
const MAX_OWED_S: f64 = 0.25;
/// Trail points drawn at most.
const TRAIL_POINTS: usize = 2000;
/// Texels per metre of the floor texture, at most.
const FLOOR_TEXELS_PER_M: f32 = 200.0;
/// Largest floor texture side.
const FLOOR_MAX_SIDE: f32 = 1400.0;
/// How often the status bar's report is rebuilt, wall seconds.
const REPORT_EVERY_S: f64 = 0.5;

/// Robot body colour (the same blue as Cute's robot cell).
pub const ROBOT_RGB: [u8; 3] = [40, 90, 230];
/// Floor colour.
pub const FLOOR_RGB: [u8; 3] = [236, 232, 220];
/// Obstacle colour.
pub const OBSTACLE_RGB: [u8; 3] = [120, 86, 60];
/// Outside the room.
pub const OUTSIDE_RGB: [u8; 3] = [70, 72, 78];

fn rgb(c: [u8; 3]) -> Color {
    Color::srgb_u8(c[0], c[1], c[2])
}

/// How fast the twin runs in the window.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Speed {
    /// Stopped; the Step button runs single steps.
    Paused,
    /// Sim time follows wall time.
    RealTime,
    /// Ten sim seconds per wall second.
    Times10,
    /// As many steps as fit in [`FRAME_BUDGET`] per frame.
    Max,
}

impl Speed {
    /// Sim seconds per wall second; `None` for paused and max.
    pub fn factor(self) -> Option<f64> {
        match self {
            Speed::RealTime => Some(1.0),
            Speed::Times10 => Some(10.0),
            Speed::Paused | Speed::Max => None,
        }
    }

    /// Button label.
    pub fn label(self) -> &'static str {
        match self {
            Speed::Paused => "Pause",
            Speed::RealTime => "1x",
            Speed::Times10 => "10x",
            Speed::Max => "Max",
        }
    }
}

/// The window's clock: speed, single steps asked for, and what was achieved.
#[derive(Resource, Debug, Clone)]
pub struct Pacing {
    /// Current speed.
    pub speed: Speed,
    /// Single steps still to run (the Step button).
    pub single_steps: u32,
    /// The runner never goes past this time (screenshots).
    pub stop_at: Option<Instant>,
    /// Sim seconds per wall second over the last frames.
    pub achieved: f64,
    /// Steps run in the last frame.
    pub last_steps: u64,
    owed_s: f64,
}

impl Default for Pacing {
    fn default() -> Self {
        Pacing {
            speed: Speed::RealTime,
            single_steps: 0,
            stop_at: None,
            achieved: 0.0,
            last_steps: 0,
            owed_s: 0.0,
        }
    }
}

impl Pacing {
    /// How many steps to run this frame for `wall_s` seconds of wall time and a step of `dt_s`
    /// (before the frame budget); updates what is owed.
    pub fn steps_for(&mut self, wall_s: f64, dt_s: f64) -> u64 {
        match self.speed {
            Speed::Paused => {
                self.owed_s = 0.0;
                u64::from(std::mem::take(&mut self.single_steps))
            }
            Speed::Max => u64::MAX,
            Speed::RealTime | Speed::Times10 => {
                let factor = self.speed.factor().unwrap_or(1.0);
                self.owed_s = (self.owed_s + wall_s.max(0.0) * factor).min(MAX_OWED_S * factor.max(1.0));
                (self.owed_s / dt_s).floor() as u64
            }
        }
    }

    /// Records that `done` steps of `dt_s` ran in a frame of `wall_s`.
    pub fn ran(&mut self, done: u64, dt_s: f64, wall_s: f64) {
        if self.speed.factor().is_some() {
            self.owed_s = (self.owed_s - done as f64 * dt_s).max(0.0);
        }
        self.last_steps = done;
        if wall_s > 0.0 {
            let rate = done as f64 * dt_s / wall_s;
            self.achieved = 0.9 * self.achieved + 0.1 * rate;
        }
    }
}

impl CuteAccess for Sim {
    fn cute(&self) -> &Cute {
        self.0.cute()
    }
    fn cute_mut(&mut self) -> &mut Cute {
        self.0.cute_mut()
    }
}

/// Where the world view sits: its region and the metres-to-pixels map (logical pixels, origin
/// top-left, y down).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldLayout {
    /// The region the world is fitted into.
    pub region: Rect,
    /// Pixels per metre.
    pub scale: f32,
    /// World point (metres) drawn at the region's centre.
    pub centre: Vec2,
}

impl WorldLayout {
    /// Fits the room's bounding box into the left half of a window of `window` logical pixels,
    /// below the toolbar and above the status bar.
    pub fn compute(window: Vec2, room: &[(f32, f32)]) -> WorldLayout {
        let (min, max) = bounds(room);
        let pad = 14.0;
        let region =
            Rect::new(pad, TOOLBAR_HEIGHT + pad, window.x * 0.5 - pad, window.y - STATUS_HEIGHT - pad);
        let size = (max - min).max(Vec2::splat(1e-3));
        let scale = (region.width().max(1.0) / size.x).min(region.height().max(1.0) / size.y);
        WorldLayout { region, scale, centre: (min + max) * 0.5 }
    }

    /// World metres to logical pixels.
    pub fn to_logical(&self, x: f32, y: f32) -> Vec2 {
        let c = self.region.center();
        Vec2::new(c.x + (x - self.centre.x) * self.scale, c.y - (y - self.centre.y) * self.scale)
    }
}

fn bounds(room: &[(f32, f32)]) -> (Vec2, Vec2) {
    let mut min = Vec2::splat(f32::MAX);
    let mut max = Vec2::splat(f32::MIN);
    for &(x, y) in room {
        min = min.min(Vec2::new(x, y));
        max = max.max(Vec2::new(x, y));
    }
    if min.x > max.x { (Vec2::ZERO, Vec2::ONE) } else { (min, max) }
}

/// Adds everything the window needs to an app that holds [`Sim`]: Bevy's window plugins
/// (1280 × 720, titled after the scenario), the camera, [`SimRenderPlugin`] and Cute's GUI in the
/// right half. Called by [`crate::app::make_app`] for `Mode::Window`.
pub fn add_window_plugins(app: &mut App, run: &Lockstep) {
    let title = format!("ExploBot Twin — {}", run.loaded().scenario.name);
    app.add_plugins(window_plugins(&title, WINDOW_SIZE.0, WINDOW_SIZE.1, false))
        .insert_resource(continuous_updates())
        .insert_resource(ClearColor(BACKGROUND))
        .add_systems(Startup, setup_camera)
        .add_plugins(SimRenderPlugin)
        .add_plugins(CutePlugin::<Sim>::with_view(CuteView {
            region: Rect::new(0.5, 0.0, 1.0, 1.0),
            inset_bottom: STATUS_HEIGHT,
        }));
}

/// Runs the twin at full speed to `after_s` sim seconds (or the end of the run), stops there,
/// saves a PNG of the window to `path` and exits.
pub fn request_screenshot(app: &mut App, path: PathBuf, after_s: f64) {
    let at = Instant::from_secs_f64(after_s.max(0.0));
    app.insert_resource(AutoScreenshot::new(path));
    app.insert_resource(Pacing { speed: Speed::Max, stop_at: Some(at), ..Pacing::default() });
    app.add_systems(Update, screenshot_when_due.after(SimSystems::Step));
}

fn screenshot_when_due(sim: Res<Sim>, mut pacing: ResMut<Pacing>, mut shot: ResMut<AutoScreenshot>) {
    let due = pacing.stop_at.is_some_and(|at| sim.0.now() >= at) || sim.0.is_finished();
    if due && !shot.ready {
        shot.ready = true;
        pacing.speed = Speed::Paused;
    }
}

/// Draws the true world and the time controls; see the module docs.
pub struct SimRenderPlugin;

impl Plugin for SimRenderPlugin {
    fn build(&self, app: &mut App) {
        if !app.is_plugin_added::<EguiPlugin>() {
            app.add_plugins(EguiPlugin::default());
        }
        if !app.world().contains_resource::<Pacing>() {
            app.init_resource::<Pacing>();
        }
        app.init_resource::<StatusCache>()
            .add_systems(Startup, spawn_world)
            .add_systems(Update, pace_lockstep.in_set(SimSystems::Step))
            .add_systems(Update, (place_world, draw_world).chain().after(SimSystems::Step))
            .add_systems(EguiPrimaryContextPass, (time_controls, status_bar));
    }
}

/// Steps the runner for this frame; see the module docs.
pub fn pace_lockstep(mut sim: ResMut<Sim>, mut pacing: ResMut<Pacing>, time: Res<Time<Real>>) {
    let started = std::time::Instant::now();
    let wall_s = time.delta_secs_f64();
    let dt_s = sim.0.dt().as_secs_f64();
    let want = pacing.steps_for(wall_s, dt_s);
    let mut done = 0u64;
    while done < want {
        if pacing.stop_at.is_some_and(|at| sim.0.now() >= at) || !sim.0.step() {
            break;
        }
        done += 1;
        if done.is_multiple_of(8) && started.elapsed() >= FRAME_BUDGET {
            break;
        }
    }
    pacing.ran(done, dt_s, wall_s);
}

#[derive(Component)]
struct Floor;

#[derive(Component)]
struct RobotBodySprite;

#[derive(Component)]
struct WheelSprite(usize);

/// Colours a floor texture of the room: outside, floor, obstacles.
fn floor_image(scenario: &Scenario) -> (Image, Vec2, Vec2) {
    let (min, max) = bounds(&scenario.room);
    let size = max - min;
    let texels = FLOOR_TEXELS_PER_M.min(FLOOR_MAX_SIDE / size.x.max(size.y).max(1e-3));
    let w = ((size.x * texels).ceil() as u32).max(1);
    let h = ((size.y * texels).ceil() as u32).max(1);
    let shapes: Vec<_> = scenario.obstacles.iter().filter_map(obstacle_shape).collect();
    let room = room_points(&scenario.room);
    let mut data = Vec::with_capacity((w * h * 4) as usize);
    for py in 0..h {
        for px in 0..w {
            let x = min.x + (px as f32 + 0.5) / texels;
            let y = max.y - (py as f32 + 0.5) / texels;
            let c = if !point_in_poly2d(Vector::new(x, y), &room) {
                OUTSIDE_RGB
            } else if shapes.iter().any(|(pose, s)| contains(pose, s.as_ref(), x, y)) {
                OBSTACLE_RGB
            } else {
                FLOOR_RGB
            };
            data.extend_from_slice(&[c[0], c[1], c[2], 255]);
        }
    }
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

fn contains(pose: &rapier2d::parry::math::Pose, shape: &dyn Shape, x: f32, y: f32) -> bool {
    shape.contains_point(pose, Vector::new(x, y))
        || shape.as_segment().is_some_and(|seg| {
            let p = pose.inverse_transform_point(Vector::new(x, y));
            seg.distance_to_local_point(p, true) < 0.012
        })
}

fn spawn_world(mut commands: Commands, sim: Res<Sim>, mut images: ResMut<Assets<Image>>) {
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

fn window_size(window: &Window) -> Vec2 {
    Vec2::new(window.width(), window.height())
}

/// Body-frame offsets of the wheels: FL, FR, RL, RR (x forward, y left).
fn wheel_offsets(wheelbase: f32, track: f32) -> [Vec2; 4] {
    let (a, b) = (wheelbase * 0.5, track * 0.5);
    [Vec2::new(a, b), Vec2::new(a, -b), Vec2::new(-a, b), Vec2::new(-a, -b)]
}

#[allow(clippy::type_complexity)]
fn place_world(
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
    let size = window_size(&window);
    let scenario = &run.loaded().scenario;
    let layout = WorldLayout::compute(size, &scenario.room);
    let (min, max) = bounds(&scenario.room);
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

fn draw_world(sim: Res<Sim>, window: Single<&Window, With<PrimaryWindow>>, mut gizmos: Gizmos) {
    let run = &sim.0;
    let size = window_size(&window);
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

    // Walls and obstacle outlines.
    let wall = Color::srgb(0.1, 0.1, 0.12);
    let room = &scenario.room;
    if room.len() >= 2 {
        gizmos.linestrip_2d(room.iter().chain(room.first()).map(|&(x, y)| w(x, y)), wall);
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
                gizmos.line_2d(w(from.0, from.1), w(to.0, to.1), wall);
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

    // Sonar: the rays of the last measurement and the cone through their ends.
    let rays = run.body().last_rays();
    for r in rays {
        let color = if r.echo { Color::srgb(0.0, 0.75, 0.55) } else { Color::srgba(0.9, 0.3, 0.3, 0.6) };
        gizmos.line_2d(w(r.from.0, r.from.1), w(r.to.0, r.to.1), color);
    }
    if rays.len() >= 2 {
        let cone = Color::srgba(0.0, 0.6, 0.45, 0.5);
        gizmos.linestrip_2d(rays.iter().map(|r| w(r.to.0, r.to.1)), cone);
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

/// The last report (rebuilt every [`REPORT_EVERY_S`]) and when it was made.
#[derive(Resource, Default)]
struct StatusCache {
    report: Option<Report>,
    made_at_s: f64,
    sim_at: Option<Instant>,
}

fn time_controls(
    mut contexts: EguiContexts,
    mut pacing: ResMut<Pacing>,
    sim: Res<Sim>,
) -> bevy::ecs::error::Result {
    let ctx = contexts.ctx_mut()?;
    egui::Area::new(egui::Id::new("twin-time-controls")).fixed_pos(egui::pos2(14.0, 6.0)).show(ctx, |ui| {
        ui.horizontal(|ui| {
            ui.strong("Twin");
            for speed in [Speed::Paused, Speed::RealTime, Speed::Times10, Speed::Max] {
                if ui.selectable_label(pacing.speed == speed, speed.label()).clicked() {
                    pacing.speed = speed;
                    pacing.stop_at = None;
                }
            }
            let step = ui.button("Step").on_hover_text("pause and run one physics step");
            if step.clicked() {
                pacing.speed = Speed::Paused;
                pacing.stop_at = None;
                pacing.single_steps += 1;
            }
        });
        let run = &sim.0;
        let s = &run.loaded().scenario;
        ui.label(format!(
            "scenario '{}' (seed {}), {}x{} cells of {:.2} m, step {} ms",
            s.name,
            run.seed(),
            run.frame().rows,
            run.frame().cols,
            run.frame().cell,
            run.dt().as_secs_f64() * 1000.0
        ));
        ui.label(
            egui::RichText::new("true world: walls, obstacles, robot + wheels, sonar rays, trail")
                .color(egui::Color32::from_rgb(170, 180, 200)),
        );
    });
    Ok(())
}

fn kilo(bytes: u64) -> String {
    if bytes >= 10_000 { format!("{:.0} kB", bytes as f64 / 1000.0) } else { format!("{bytes} B") }
}

fn status_bar(
    mut contexts: EguiContexts,
    sim: Res<Sim>,
    pacing: Res<Pacing>,
    time: Res<Time<Real>>,
    mut cache: ResMut<StatusCache>,
    window: Query<&Window, With<PrimaryWindow>>,
) -> bevy::ecs::error::Result {
    let Ok(window) = window.single() else {
        return Ok(());
    };
    let run = &sim.0;
    let wall = time.elapsed_secs_f64();
    // Paused, the report catches up at once (a screenshot shows the figures of its instant).
    let stale = wall - cache.made_at_s >= REPORT_EVERY_S || pacing.speed == Speed::Paused;
    if cache.report.is_none() || (stale && cache.sim_at != Some(run.now())) {
        cache.report = Some(run.report(wall));
        cache.made_at_s = wall;
        cache.sim_at = Some(run.now());
    }
    let ctx = contexts.ctx_mut()?;
    let height = window_size(window).y;
    let speed = match pacing.speed {
        Speed::Paused => "paused".to_string(),
        s => format!("{} (achieved {:.1}x)", s.label(), pacing.achieved),
    };
    let finished = if run.is_finished() { " (run finished)" } else { "" };
    let mut line1 = format!(
        "t = {:.2} s / {:.0} s{finished} | {speed} | Cute: {:?}",
        run.now().as_secs_f64(),
        run.time_limit().as_secs_f64(),
        run.cute().status(),
    );
    let mut line2 = String::new();
    if let Some(r) = cache.report.as_ref() {
        line1 += &format!(
            " | coverage {:.0} % accuracy {:.0} % collisions {}",
            r.coverage * 100.0,
            r.map_accuracy * 100.0,
            r.collisions
        );
        let links: Vec<String> = r
            .links
            .iter()
            .map(|l| {
                format!(
                    "{} {} {} fr / {} {} fr",
                    l.name,
                    kilo(l.outbound.bytes),
                    l.outbound.frames,
                    kilo(l.inbound.bytes),
                    l.inbound.frames,
                )
            })
            .collect();
        let errors: u64 = r.links.iter().map(|l| l.outbound.errors + l.inbound.errors).sum();
        line2 = format!("links out / in: {} | frame errors {errors}", links.join(" | "));
    }
    egui::Area::new(egui::Id::new("twin-status"))
        .fixed_pos(egui::pos2(14.0, height - STATUS_HEIGHT + 4.0))
        .show(ctx, |ui| {
            ui.style_mut().wrap_mode = Some(egui::TextWrapMode::Truncate);
            ui.set_max_width(window_size(window).x - 28.0);
            ui.label(egui::RichText::new(line1).monospace());
            ui.label(egui::RichText::new(line2).monospace());
        });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paced_speeds_owe_wall_time_times_factor() {
        let mut p = Pacing { speed: Speed::Times10, ..Pacing::default() };
        // 16 ms at 10x = 160 ms = 32 steps of 5 ms.
        assert_eq!(p.steps_for(0.016, 0.005), 32);
        p.ran(32, 0.005, 0.016);
        assert_eq!(p.steps_for(0.0, 0.005), 0);
        p.speed = Speed::RealTime;
        assert_eq!(p.steps_for(0.016, 0.005), 3);
        p.ran(3, 0.005, 0.016);
        // The 1 ms left over carries to the next frame: 1 + 4 = 5 ms.
        assert_eq!(p.steps_for(0.004, 0.005), 1);
    }

    #[test]
    fn slow_frames_do_not_pile_up_a_backlog() {
        let mut p = Pacing { speed: Speed::RealTime, ..Pacing::default() };
        let n = p.steps_for(5.0, 0.005);
        assert_eq!(n, (MAX_OWED_S / 0.005) as u64);
    }

    #[test]
    fn paused_runs_only_requested_single_steps() {
        let mut p = Pacing { speed: Speed::Paused, single_steps: 2, ..Pacing::default() };
        assert_eq!(p.steps_for(1.0, 0.005), 2);
        assert_eq!(p.steps_for(1.0, 0.005), 0);
        p.speed = Speed::Max;
        assert_eq!(p.steps_for(0.0, 0.005), u64::MAX);
    }

    #[test]
    fn world_layout_keeps_the_room_in_the_left_half() {
        let room = [(0.0, 0.0), (3.1, 0.0), (3.1, 2.5), (0.0, 2.5)];
        let win = Vec2::new(1280.0, 720.0);
        let l = WorldLayout::compute(win, &room);
        let a = l.to_logical(0.0, 2.5);
        let b = l.to_logical(3.1, 0.0);
        assert!(a.x >= 0.0 && b.x <= 640.0, "{a} {b}");
        assert!(a.y >= TOOLBAR_HEIGHT && b.y <= 720.0 - STATUS_HEIGHT, "{a} {b}");
        // y grows up in the world, down on screen.
        assert!(a.y < b.y);
        // Square pixels: 1 m is the same length both ways.
        let d = l.to_logical(1.0, 1.0) - l.to_logical(0.0, 0.0);
        assert!((d.x + d.y).abs() < 1e-3, "{d}");
    }

    #[test]
    fn floor_texture_marks_obstacles_and_outside() {
        let loaded = crate::scenario::LoadedScenario::builtin_default().unwrap();
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
