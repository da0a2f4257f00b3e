//! Cute's operator GUI on Bevy + egui (feature `window`): the map, the robot, the buttons, the
//! pop-ups, and click-to-go.
//!
//! Concept: [`CutePlugin<R>`] draws and drives whatever [`Cute`] session the resource `R` holds
//! ([`CuteAccess`]), so the standalone `cute` binary (a TCP session) and the twin's window (the
//! lockstep runner's session) share one plugin. It owns a rectangle of the window, the
//! [`CuteView`]: an egui toolbar at its top (Cartography / Stop / Reset map and a status line),
//! and below it the map, one texel per cell, coloured as the original Cute did ([`cell_rgb`]:
//! 0 obstacle black, 1 free grey, 2 unknown white, 3 waypoint red, 4 destination orange,
//! 5 robot blue), with grid lines and the robot's heading drawn as gizmos. A left click on the
//! map calls [`Cute::go_to`] on that cell; session events become pop-ups ([`popup_for`]: no path,
//! connection lost, obstacle met, ...) and a log line.
//!
//! Coordinates: the plugin draws for one `Camera2d` at the origin with the default projection,
//! so one world unit is one logical pixel ([`setup_camera`] spawns it). [`MapLayout`] converts
//! between map cells and logical window pixels (origin top-left, y down); it is plain geometry,
//! used by the drawing, the clicks, and the screenshot tests alike.
//!
//! Invariants: the plugin never reads a clock or a socket; it only calls the session's user
//! actions and [`Cute::take_events`]. The map texture is rewritten only when a cell changed.
//!
//! ```
//! use bevy::math::{Rect, Vec2};
//! use cute::gui::{CuteView, MapLayout, cell_rgb};
//! use cute::CellValue;
//! // The right half of a 1280 x 720 window, 30 px kept free at the bottom.
//! let view = CuteView { region: Rect::new(0.5, 0.0, 1.0, 1.0), inset_bottom: 30.0 };
//! let layout = MapLayout::compute(Vec2::new(1280.0, 720.0), &view, 8, 10);
//! let centre = layout.cell_rect(3, 4).center();
//! assert_eq!(layout.cell_at(centre), Some((3, 4)));
//! assert!(layout.map_rect().min.x >= 640.0);
//! assert_eq!(cell_rgb(CellValue::Obstacle), [20, 20, 20]);
//! ```

use std::collections::VecDeque;
use std::marker::PhantomData;
use std::path::{Path, PathBuf};

use bevy::DefaultPlugins;
use bevy::app::{App, AppExit, Plugin, PluginGroup, PluginGroupBuilder, Startup, Update};
use bevy::asset::{Assets, Handle, RenderAssetUsages};
use bevy::color::Color;
use bevy::ecs::component::Mutable;
use bevy::ecs::message::MessageWriter;
use bevy::ecs::observer::On;
use bevy::ecs::schedule::IntoScheduleConfigs;
use bevy::ecs::schedule::common_conditions::{not, resource_exists};
use bevy::ecs::system::{Commands, Query, Res, ResMut, Single};
use bevy::gizmos::gizmos::Gizmos;
use bevy::image::{Image, ImageSampler};
use bevy::input::ButtonInput;
use bevy::input::mouse::MouseButton;
use bevy::math::{Rect, Vec2, Vec3};
use bevy::prelude::{Camera2d, Component, Resource, Transform, Visibility, With};
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat};
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};
use bevy::sprite::Sprite;
use bevy::window::{PrimaryWindow, Window, WindowPlugin, WindowResolution};
use bevy::winit::{UpdateMode, WinitPlugin, WinitSettings};
use bevy_egui::input::egui_wants_any_pointer_input;
use bevy_egui::{EguiContexts, EguiPlugin, EguiPrimaryContextPass, egui};

/// The egui integration this GUI is built on, for plugins that add their own panels beside it.
pub use bevy_egui;

pub use crate::notices::{Popup, describe, popup_for};

use crate::map::CellValue;
use crate::session::{Compat, Cute, CuteEvent, Status};
use crate::trajectory::PlanError;
use robot_model::grid::Heading;

mod layout;
mod screenshot;
pub use layout::{CuteView, MapLayout, cell_rgb, logical_to_world};

/// Height of the toolbar at the top of the [`CuteView`], logical pixels.
pub const TOOLBAR_HEIGHT: f32 = 64.0;
/// Space around the map inside its region, logical pixels.
pub const MAP_PADDING: f32 = 10.0;
/// Lines kept in the event log.
const LOG_LINES: usize = 6;
/// Window background.
pub const BACKGROUND: Color = Color::srgb(0.16, 0.17, 0.20);

/// A resource that gives access to a [`Cute`] session.
pub trait CuteAccess: Resource<Mutability = Mutable> {
    /// The session, to draw.
    fn cute(&self) -> &Cute;
    /// The session, for user actions and events.
    fn cute_mut(&mut self) -> &mut Cute;
}

impl CuteAccess for CuteSession {
    fn cute(&self) -> &Cute {
        &self.0
    }
    fn cute_mut(&mut self) -> &mut Cute {
        &mut self.0
    }
}

/// A bare session as a resource (tests, demos): nothing pumps its network.
#[derive(Resource, Debug)]
pub struct CuteSession(pub Cute);

/// What the GUI shows besides the session: pop-ups waiting, the log, the last notice.
#[derive(Resource, Debug, Default, Clone)]
pub struct CuteUiState {
    /// Pop-ups, oldest first; the first is shown.
    pub popups: VecDeque<Popup>,
    /// Recent events, oldest first.
    pub log: VecDeque<String>,
    /// The answer to the last user action (e.g. why a click did nothing).
    pub notice: Option<String>,
}

impl CuteUiState {
    /// Records an event: a log line, and a pop-up unless the same one is already waiting.
    pub fn record(&mut self, event: &CuteEvent) {
        if crate::notices::is_warning(event) {
            self.notice = Some(describe(event));
        }
        self.log.push_back(describe(event));
        while self.log.len() > LOG_LINES {
            self.log.pop_front();
        }
        if let Some(p) = popup_for(event)
            && !self.popups.contains(&p)
        {
            self.popups.push_back(p);
        }
    }
}

use screenshot::auto_screenshot;
pub use screenshot::{AutoScreenshot, capture_and_exit};

/// Where the GUI's buttons were drawn last (logical pixels, origin top-left), by label: what a
/// status file reports so that a test can click them with real input events.
#[derive(Resource, Debug, Default, Clone, PartialEq)]
pub struct ButtonRects(pub std::collections::BTreeMap<String, Rect>);

impl ButtonRects {
    /// Records where the button `label` was drawn.
    pub fn record(&mut self, label: &str, response: &egui::Response) {
        let r = response.rect;
        self.0.insert(label.to_string(), Rect::new(r.min.x, r.min.y, r.max.x, r.max.y));
    }
}

/// Bevy's default plugins as the `window` feature provides them, with one primary window of
/// `width × height` logical pixels titled `title`. Bevy's log plugin is left out (the binaries
/// install their own `tracing` subscriber). `any_thread` lets tests open the window off the
/// main thread.
pub fn window_plugins(title: &str, width: u32, height: u32, any_thread: bool) -> PluginGroupBuilder {
    DefaultPlugins
        .set(WindowPlugin {
            primary_window: Some(Window {
                title: title.to_string(),
                resolution: WindowResolution::new(width, height),
                ..Window::default()
            }),
            ..WindowPlugin::default()
        })
        .set(WinitPlugin { run_on_any_thread: any_thread })
        .disable::<bevy::log::LogPlugin>()
}

/// Keeps the app updating every frame whether or not the window has the focus (the session
/// and the twin must keep running).
pub fn continuous_updates() -> WinitSettings {
    WinitSettings { focused_mode: UpdateMode::Continuous, unfocused_mode: UpdateMode::Continuous }
}

/// Spawns the one `Camera2d` both plugins draw for.
pub fn setup_camera(mut commands: Commands) {
    commands.spawn(Camera2d);
}

/// The Cute GUI for the session in resource `R`; see the module docs.
pub struct CutePlugin<R> {
    view: CuteView,
    _session: PhantomData<fn() -> R>,
}

impl<R: CuteAccess> CutePlugin<R> {
    /// The plugin drawing in the whole window.
    pub fn new() -> Self {
        Self::with_view(CuteView::default())
    }

    /// The plugin drawing in `view`.
    pub fn with_view(view: CuteView) -> Self {
        CutePlugin { view, _session: PhantomData }
    }
}

impl<R: CuteAccess> Default for CutePlugin<R> {
    fn default() -> Self {
        Self::new()
    }
}

impl<R: CuteAccess> Plugin for CutePlugin<R> {
    fn build(&self, app: &mut App) {
        if !app.is_plugin_added::<EguiPlugin>() {
            app.add_plugins(EguiPlugin::default());
        }
        app.insert_resource(self.view)
            .init_resource::<CuteUiState>()
            .init_resource::<ButtonRects>()
            .add_systems(Startup, spawn_map_sprite)
            .add_systems(
                Update,
                (
                    collect_events::<R>,
                    click_to_go::<R>.run_if(not(egui_wants_any_pointer_input)),
                    update_map_sprite::<R>,
                    draw_map_overlay::<R>,
                    auto_screenshot.run_if(resource_exists::<AutoScreenshot>),
                )
                    .chain(),
            )
            .add_systems(EguiPrimaryContextPass, cute_toolbar::<R>);
    }
}

/// The sprite showing the map texture.
#[derive(Component)]
struct MapSprite;

/// The map texture and the cells it shows.
#[derive(Resource)]
struct MapTexture {
    handle: Handle<Image>,
    shown: Vec<CellValue>,
    size: (usize, usize),
}

fn map_image(rows: usize, cols: usize) -> Image {
    let mut image = Image::new_fill(
        Extent3d { width: cols.max(1) as u32, height: rows.max(1) as u32, depth_or_array_layers: 1 },
        TextureDimension::D2,
        &[255, 255, 255, 255],
        TextureFormat::Rgba8UnormSrgb,
        RenderAssetUsages::MAIN_WORLD | RenderAssetUsages::RENDER_WORLD,
    );
    image.sampler = ImageSampler::nearest();
    image
}

fn spawn_map_sprite(mut commands: Commands, mut images: ResMut<Assets<Image>>) {
    let handle = images.add(map_image(1, 1));
    commands.spawn((
        MapSprite,
        Sprite { image: handle.clone(), custom_size: Some(Vec2::ONE), ..Sprite::default() },
        Transform::default(),
        Visibility::Hidden,
    ));
    commands.insert_resource(MapTexture { handle, shown: Vec::new(), size: (0, 0) });
}

fn collect_events<R: CuteAccess>(mut session: ResMut<R>, mut ui: ResMut<CuteUiState>) {
    for event in session.cute_mut().take_events() {
        ui.record(&event);
    }
}

fn click_to_go<R: CuteAccess>(
    buttons: Res<ButtonInput<MouseButton>>,
    window: Single<&Window, With<PrimaryWindow>>,
    view: Res<CuteView>,
    mut session: ResMut<R>,
    mut ui: ResMut<CuteUiState>,
) {
    if !buttons.just_pressed(MouseButton::Left) {
        return;
    }
    let Some(cursor) = window.cursor_position() else {
        return;
    };
    let map = session.cute().map();
    let layout = MapLayout::compute(window_size(&window), &view, map.rows(), map.cols());
    let Some((x, y)) = layout.cell_at(cursor) else {
        return;
    };
    ui.notice = match session.cute_mut().go_to(x, y) {
        Ok(()) => Some(format!("going to ({x}, {y})")),
        // The session reports it as an event: a pop-up.
        Err(PlanError::NoPath { .. }) => None,
        Err(e) => Some(format!("cannot go to ({x}, {y}): {e}")),
    };
}

fn window_size(window: &Window) -> Vec2 {
    Vec2::new(window.width(), window.height())
}

fn update_map_sprite<R: CuteAccess>(
    session: Res<R>,
    window: Single<&Window, With<PrimaryWindow>>,
    view: Res<CuteView>,
    mut texture: ResMut<MapTexture>,
    mut images: ResMut<Assets<Image>>,
    mut sprite: Single<(&mut Sprite, &mut Transform, &mut Visibility), With<MapSprite>>,
) {
    let map = session.cute().map();
    let (rows, cols) = (map.rows(), map.cols());
    if texture.size != (rows, cols) {
        let handle = images.add(map_image(rows, cols));
        sprite.0.image = handle.clone();
        texture.handle = handle;
        texture.size = (rows, cols);
        texture.shown.clear();
    }
    if texture.shown != map.cells() {
        if let Some(mut image) = images.get_mut(&texture.handle) {
            let data: Vec<u8> = map
                .cells()
                .iter()
                .flat_map(|&v| {
                    let [r, g, b] = cell_rgb(v);
                    [r, g, b, 255]
                })
                .collect();
            image.data = Some(data);
        }
        texture.shown = map.cells().to_vec();
    }
    let size = window_size(&window);
    let layout = MapLayout::compute(size, &view, rows, cols);
    let rect = layout.map_rect();
    sprite.0.custom_size = Some(rect.size());
    let centre = logical_to_world(size, rect.center());
    *sprite.1 = Transform::from_translation(Vec3::new(centre.x, centre.y, 0.0));
    *sprite.2 = Visibility::Inherited;
}

fn heading_vector(h: Heading) -> Vec2 {
    // Logical pixels: x right, y down.
    match h {
        Heading::South => Vec2::new(0.0, 1.0),
        Heading::North => Vec2::new(0.0, -1.0),
        Heading::West => Vec2::new(-1.0, 0.0),
        Heading::East => Vec2::new(1.0, 0.0),
    }
}

fn draw_map_overlay<R: CuteAccess>(
    session: Res<R>,
    window: Single<&Window, With<PrimaryWindow>>,
    view: Res<CuteView>,
    mut gizmos: Gizmos,
) {
    let cute = session.cute();
    let map = cute.map();
    let size = window_size(&window);
    let layout = MapLayout::compute(size, &view, map.rows(), map.cols());
    let w = |p: Vec2| logical_to_world(size, p);
    let rect = layout.map_rect();
    if layout.cell >= 6.0 {
        let grid = Color::srgb(0.55, 0.57, 0.62);
        for row in 1..layout.rows {
            let y = rect.min.y + row as f32 * layout.cell;
            gizmos.line_2d(w(Vec2::new(rect.min.x, y)), w(Vec2::new(rect.max.x, y)), grid);
        }
        for col in 1..layout.cols {
            let x = rect.min.x + col as f32 * layout.cell;
            gizmos.line_2d(w(Vec2::new(x, rect.min.y)), w(Vec2::new(x, rect.max.y)), grid);
        }
    }
    let border = Color::srgb(0.85, 0.87, 0.92);
    gizmos.rect_2d(w(rect.center()), rect.size() + Vec2::splat(4.0), border);
    // Blocked moves: the side the two cells share, in red, three lines thick.
    let blocked = Color::srgb(0.9, 0.15, 0.1);
    for (a, b) in map.blocked_moves() {
        if let Some((p, q)) = layout.shared_side(a, b) {
            let across = if p.x == q.x { Vec2::X } else { Vec2::Y };
            for k in [-1.0, 0.0, 1.0] {
                gizmos.line_2d(w(p + across * k), w(q + across * k), blocked);
            }
        }
    }
    // The robot: a ring and an arrow towards its heading.
    let (x, y, heading) = cute.robot();
    let cell = layout.cell_rect(usize::from(x), usize::from(y));
    let c = cell.center();
    let r = layout.cell * 0.36;
    let white = Color::srgb(1.0, 1.0, 1.0);
    gizmos.circle_2d(w(c), r, white);
    let tip = c + heading_vector(heading) * layout.cell * 0.45;
    gizmos.arrow_2d(w(c), w(tip), white).with_tip_length(layout.cell * 0.25);
    // The destination: a ring, so it shows even under the robot.
    if let Some((dx, dy)) = map.destination() {
        let d = layout.cell_rect(usize::from(dx), usize::from(dy)).center();
        gizmos.circle_2d(w(d), layout.cell * 0.3, Color::srgb(0.45, 0.2, 0.0));
    }
}

fn status_text(cute: &Cute) -> String {
    let link = if cute.is_ready() {
        "connected"
    } else if cute.is_connected() {
        "connected, awaiting position ack"
    } else {
        "disconnected"
    };
    let status = match cute.status() {
        Status::Idle => "idle",
        Status::Mapping => "mapping",
        Status::Moving => "moving",
        Status::Done => "map complete",
    };
    let compat = match cute.config().compat {
        Compat::Default => "",
        Compat::Explobot2024 if cute.batch_drop_pending() => "compat 2024, next batch dropped | ",
        Compat::Explobot2024 => "compat 2024, unknown cells planned as free | ",
    };
    let (x, y, h) = cute.robot();
    let map = cute.map();
    format!(
        "{compat}{link} | {status} | robot ({x}, {y}) facing {h} | free {} obstacles {} unknown {}",
        map.cells().iter().filter(|v| v.is_known_free()).count(),
        map.count(CellValue::Obstacle),
        map.count(CellValue::Unknown),
    )
}

fn cute_toolbar<R: CuteAccess>(
    mut contexts: EguiContexts,
    mut session: ResMut<R>,
    mut ui_state: ResMut<CuteUiState>,
    mut rects: ResMut<ButtonRects>,
    view: Res<CuteView>,
    window: Query<&Window, With<PrimaryWindow>>,
) -> bevy::ecs::error::Result {
    let Ok(window) = window.single() else {
        return Ok(());
    };
    let ctx = contexts.ctx_mut()?;
    let region = view.region_px(window_size(window));
    let busy = matches!(session.cute().status(), Status::Mapping | Status::Moving);
    let compat = session.cute().config().compat == Compat::Explobot2024;
    egui::Area::new(egui::Id::new("cute-toolbar"))
        .fixed_pos(egui::pos2(region.min.x + MAP_PADDING, region.min.y + 6.0))
        .show(ctx, |ui| {
            ui.set_max_width(region.width() - 2.0 * MAP_PADDING);
            ui.horizontal(|ui| {
                ui.strong("Cute");
                let carto = ui
                    .add_enabled(!busy && !compat, egui::Button::new("Cartography"))
                    .on_hover_text("map the room (serpentine sweep)");
                rects.record("Cartography", &carto);
                if carto.clicked() {
                    ui_state.notice = session.cute_mut().start_cartography().err().map(|e| e.to_string());
                }
                let stop = ui.button("Stop");
                rects.record("Stop", &stop);
                if stop.clicked() {
                    session.cute_mut().stop();
                    ui_state.notice = None;
                }
                let reset = ui.button("Reset map");
                rects.record("Reset map", &reset);
                if reset.clicked() {
                    session.cute_mut().reset_map();
                    ui_state.notice = Some("map reset".to_string());
                }
                ui.label(if compat {
                    "click a cell to send the robot"
                } else {
                    "click a free cell to send the robot"
                });
            });
            ui.label(status_text(session.cute()));
            let last = ui_state.notice.clone().or_else(|| ui_state.log.back().cloned()).unwrap_or_default();
            ui.label(egui::RichText::new(last).color(egui::Color32::from_rgb(250, 210, 120)));
        });
    if let Some(popup) = ui_state.popups.front().cloned() {
        let offset = region.center() - window_size(window) * 0.5;
        let mut close = false;
        egui::Window::new(popup.title.as_str())
            .id(egui::Id::new("cute-popup"))
            .collapsible(false)
            .resizable(false)
            .anchor(egui::Align2::CENTER_CENTER, [offset.x, offset.y])
            .show(ctx, |ui| {
                ui.label(popup.text.as_str());
                let ok = ui.button("OK");
                rects.record("OK", &ok);
                if ok.clicked() {
                    close = true;
                }
            });
        if close {
            ui_state.popups.pop_front();
        }
    } else {
        rects.0.remove("OK");
    }
    Ok(())
}

#[cfg(test)]
mod tests;
