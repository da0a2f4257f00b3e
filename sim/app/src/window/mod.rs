//! The twin's window (feature `window`): the true world beside Cute's map, with time controls.
//!
//! Concept: [`SimRenderPlugin`] draws what the physics knows — the room, the obstacles, the
//! robot's body and its four wheels (tinted by their speed), the sonar rays of the last
//! measurement (bright when they echo), the trail, the planning grid — in the left half of the
//! window, with Carto's own evidence grid and belief over it as a layer that can be toggled
//! ([`carto_layer`]), and adds [`cute::gui::CutePlugin`] on [`Sim`] in the right half, so the operator sees
//! Cute's belief next to the truth and can drive Cute with its own buttons and clicks.
//!
//! Pacing: in window mode `Time<Fixed>` is not used. [`pace_lockstep`] runs in `Update` (in
//! [`SimSystems::Step`]) and steps the lockstep runner as many times as the wall time since the
//! last frame × the [`Speed`] asks for ([`crate::pacing`], shared with `explobot sim --serve`),
//! but never longer than [`FRAME_BUDGET`] per frame (a slower machine runs slower, it does not
//! pile up a backlog); `Max` fills the budget. The runner itself is the same deterministic
//! lockstep as headless: pacing only decides how many steps run per frame, so a window run
//! reaches the same states at the same sim times.
//!
//! The run never ends by itself here: the runner is [`Lockstep::interactive`], so the scenario's
//! script plays first and then the user drives until the window is closed; the expectations are
//! checked at the step where `explobot run` would stop, and Restart starts the scenario again
//! ([`session`]). The scenario's `max_sim_s` only decides when that verdict is taken if the script
//! has not ended by then.
//!
//! Layout of this folder: `layout` (window size, [`WorldLayout`]), `draw` (floor texture,
//! sprites, gizmos), `carto_layer` (Carto's grid and belief), `panels` (time controls, status bar), `session` (script → user handover,
//! verdict, restart), `status_file` (`--status-file`); this file holds the plugin, the pacing
//! system and screenshots.
//!
//! Invariants: one `Camera2d` at the origin, one world unit = one logical pixel (see
//! [`cute::gui`]); [`WorldLayout`] is the only place that maps metres to pixels; a screenshot
//! request ([`request_screenshot`]) stops the runner exactly at its time, so the picture shows the
//! state a headless run has after the same number of steps.
//!
//! ```no_run
//! use twin_app::app::{Mode, make_app};
//! let run = twin::runner::Lockstep::new(twin::setup::RunSetup::builtin_default()?, None)?;
//! let mut app = make_app(Mode::Window, run);
//! twin_app::window::request_screenshot(&mut app, "window.png".into(), 20.0);
//! app.run();
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::PathBuf;
use std::time::Duration as WallDuration;

use bevy::app::{App, Plugin, Startup, Update};
use bevy::ecs::schedule::IntoScheduleConfigs;
use bevy::ecs::schedule::common_conditions::resource_exists;
use bevy::ecs::system::{Res, ResMut};
use bevy::math::Rect;
use bevy::prelude::ClearColor;
use bevy::time::{Real, Time};
use cute::Cute;
use cute::gui::bevy_egui::{EguiPlugin, EguiPrimaryContextPass};
use cute::gui::{
    AutoScreenshot, BACKGROUND, ButtonRects, CuteAccess, CutePlugin, CuteUiState, CuteView,
    continuous_updates, setup_camera, window_plugins,
};
use robot_model::time::Instant;

use crate::pacing::{Pacing, Speed};
use crate::plugin::{Sim, SimSystems};
use twin::runner::Lockstep;

pub mod carto_layer;
mod draw;
mod layout;
mod panels;
pub mod session;
mod status_file;

pub use carto_layer::CartoLayer;
pub use draw::{FLOOR_RGB, OBSTACLE_RGB, OUTSIDE_RGB, PALETTE, ROBOT_RGB};
pub use layout::{STATUS_HEIGHT, WINDOW_SIZE, WorldLayout};
pub use session::{Handover, ScriptState};
pub use status_file::{STATUS_EVERY_S, StatusFile};

/// Longest time the runner may take per frame.
pub const FRAME_BUDGET: WallDuration = WallDuration::from_millis(12);

impl CuteAccess for Sim {
    fn cute(&self) -> &Cute {
        self.0.cute()
    }
    fn cute_mut(&mut self) -> &mut Cute {
        self.0.cute_mut()
    }
}

/// Adds everything the window needs to an app that holds [`Sim`]: Bevy's window plugins
/// (1280 × 720, titled after the scenario), the camera, [`SimRenderPlugin`] and Cute's GUI in the
/// right half. Called by `crate::app::make_app` for `Mode::Window`.
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

/// Runs the twin at full speed to `after_s` sim seconds (or the point where a headless run
/// ends, if sooner), stops there, saves a PNG of the window to `path` and exits.
pub fn request_screenshot(app: &mut App, path: PathBuf, after_s: f64) {
    let at = Instant::from_secs_f64(after_s.max(0.0));
    app.insert_resource(AutoScreenshot::new(path));
    app.insert_resource(Pacing::max_until(at));
    app.add_systems(Update, screenshot_when_due.after(SimSystems::Step));
}

fn screenshot_when_due(sim: Res<Sim>, mut pacing: ResMut<Pacing>, mut shot: ResMut<AutoScreenshot>) {
    let due = pacing.stop_at.is_some_and(|at| sim.0.now() >= at) || sim.0.headless_end().is_some();
    if due && !shot.ready {
        shot.ready = true;
        pacing.speed = Speed::Paused;
    }
}

/// Makes the window rewrite a JSON status file at `path` a few times a second (see
/// `status_file`).
pub fn request_status_file(app: &mut App, path: PathBuf) {
    app.insert_resource(StatusFile::new(path));
}

/// Draws the true world and the time controls; see the module docs. Registers resources and
/// systems only.
pub struct SimRenderPlugin;

impl Plugin for SimRenderPlugin {
    fn build(&self, app: &mut App) {
        if !app.is_plugin_added::<EguiPlugin>() {
            app.add_plugins(EguiPlugin::default());
        }
        if !app.world().contains_resource::<Pacing>() {
            app.init_resource::<Pacing>();
        }
        app.init_resource::<session::StatusCache>()
            .init_resource::<Handover>()
            .init_resource::<ButtonRects>()
            .init_resource::<CuteUiState>()
            .init_resource::<CartoLayer>()
            .add_systems(Startup, (draw::spawn_world, carto_layer::spawn_layer))
            .add_systems(Update, session::restart_when_asked.before(SimSystems::Step))
            .add_systems(Update, pace_lockstep.in_set(SimSystems::Step))
            .add_systems(
                Update,
                status_file::write_status.after(SimSystems::Step).run_if(resource_exists::<StatusFile>),
            )
            .add_systems(
                Update,
                (draw::place_world, draw::draw_world, carto_layer::draw_layer)
                    .chain()
                    .after(SimSystems::Step),
            )
            .add_systems(EguiPrimaryContextPass, (panels::time_controls, panels::status_bar));
    }
}

/// Steps the runner for this frame, and takes the verdict at the step where a headless run would
/// end; see the module docs.
pub fn pace_lockstep(
    mut sim: ResMut<Sim>,
    mut pacing: ResMut<Pacing>,
    mut handover: ResMut<Handover>,
    time: Res<Time<Real>>,
) {
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
        if handover.take_verdict(&sim.0, time.elapsed_secs_f64()) {
            // The report took a while: let this frame be drawn.
            break;
        }
        if done.is_multiple_of(8) && started.elapsed() >= FRAME_BUDGET {
            break;
        }
    }
    pacing.ran(done, dt_s, wall_s);
}
